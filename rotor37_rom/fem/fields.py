"""Fields on a sector from reduced states: displacement Functions, von Mises stress (linear or SVK Cauchy),
cell geometry for locating maxima.

Part of the dolfinx adapter (``rotor37_rom.fem``).
"""
from __future__ import annotations

import numpy as np
from dolfinx import fem

from rotor37_rom import forms

from .operators import JIT_PARAMS, _require_serial
from .sector import Sector

__all__ = ["displacement_function", "von_mises_function", "von_mises_at_vertices", "von_mises_at_quadrature",
           "cell_midpoints", "cell_vertices", "cells_touching_points", "root_junction"]


def displacement_function(sector: Sector, Phi: np.ndarray, q: np.ndarray, name: str = "displacement"):
    """u = Phi q as a dolfinx Function on the sector (serial: Phi holds all DOFs)."""
    _require_serial(sector, "displacement_function")
    Phi = np.asarray(Phi)
    q = np.asarray(q, float)
    if Phi.ndim != 2 or Phi.shape[0] != sector.V.dofmap.index_map.size_local * 3:
        raise ValueError(f"basis Phi has shape {Phi.shape}; the sector has "
                         f"{sector.V.dofmap.index_map.size_local * 3} DOFs (was it built on another mesh?)")
    if q.ndim != 1 or q.size != Phi.shape[1]:
        raise ValueError(f"reduced state q has shape {q.shape}; the basis has r = {Phi.shape[1]} columns")
    u = fem.Function(sector.V, name=name)
    u.x.array[:] = Phi @ q
    return u


def _stress_expression(sector: Sector, u, nonlinear: bool):
    lmbda, mu = sector.material.lame
    sigma = forms.cauchy_stress(u, lmbda, mu) if nonlinear else forms.linear_stress(u, lmbda, mu)
    return forms.von_mises(sigma)


def von_mises_function(sector: Sector, u, nonlinear: bool = True, degree: int = 1):
    """von Mises stress (Pa) of the displacement u interpolated into a DG space of the given degree (0 or 1)."""
    if degree not in (0, 1):
        raise ValueError(f"degree must be 0 or 1, got {degree}")
    W = fem.FunctionSpace(sector.mesh, ("DG", degree))
    expr = fem.Expression(_stress_expression(sector, u, nonlinear), W.element.interpolation_points(),
                          jit_params=JIT_PARAMS)
    out = fem.Function(W, name="von_mises")
    out.interpolate(expr)
    return out


def von_mises_at_vertices(sector: Sector, u, nonlinear: bool = True) -> np.ndarray:
    """von Mises stress (Pa) at the four vertices of every local cell, (n_cells, 4), in the order of
    ``cell_vertices``: the cell's own value at each vertex (the stress of a P2 displacement is discontinuous across
    cells; a surface stress is read at the vertices, where bending puts its largest, not at the midpoint)."""
    f = von_mises_function(sector, u, nonlinear, degree=1)
    n_cells = sector.mesh.topology.index_map(3).size_local
    dofs = f.function_space.dofmap.list.array.reshape(-1, 4)[:n_cells]
    return f.x.array[dofs]


def cell_vertices(sector: Sector) -> np.ndarray:
    """Coordinates (n_cells, 4, 3) of the vertices of every local cell, in the order of ``von_mises_at_vertices``."""
    W = fem.FunctionSpace(sector.mesh, ("DG", 1))
    n_cells = sector.mesh.topology.index_map(3).size_local
    dofs = W.dofmap.list.array.reshape(-1, 4)[:n_cells]
    return W.tabulate_dof_coordinates()[dofs]


def root_junction(sector: Sector, faces=("pressure", "suction", "leading_edge", "trailing_edge"),
                  region: str = "disk", spacing: float | None = 2e-4) -> np.ndarray:
    """Points (n, 3) along the line where the blade's surface meets the disk (a disk sector's blade root, a sharp
    re-entrant corner without a fillet): the mesh edges of the ``faces`` groups whose two vertices belong to cells of
    the ``region`` volume group, each sampled every ``spacing`` m or closer (distances to the line are then exact
    to spacing / 2); ``spacing`` None: the edges themselves, (n, 2, 3) end points. Serial (the sector of one
    rank)."""
    _require_serial(sector, "root_junction")
    missing = [g for g in (*faces, region) if g not in sector.groups]
    if missing:
        raise ValueError(f"root_junction: the sector has no group {missing} (a disk sector has 'disk' and the blade's "
                         f"faces; it has {sorted(sector.groups)})")
    topo = sector.mesh.topology
    topo.create_connectivity(2, 0)
    topo.create_connectivity(3, 0)
    cell_v = topo.connectivity(3, 0).array.reshape(-1, 4)          # tetrahedra: 4 vertices per cell
    facet_v = topo.connectivity(2, 0).array.reshape(-1, 3)
    in_region = np.zeros(topo.index_map(0).size_local + topo.index_map(0).num_ghosts, bool)
    in_region[cell_v[sector.cell_tags.find(sector.groups[region])].ravel()] = True
    # vertex coordinates through a P1 space, whose cell dofs follow the cell's vertices in the same local order
    P1 = fem.FunctionSpace(sector.mesh, ("Lagrange", 1))
    vertex_x = np.empty((in_region.size, 3))
    vertex_x[cell_v.ravel()] = P1.tabulate_dof_coordinates()[P1.dofmap.list.array]
    segments = set()
    for name in faces:
        tri = facet_v[sector.facets(name)]
        on = in_region[tri]
        for i, j in ((0, 1), (0, 2), (1, 2)):                      # the facet's edges with both ends on the region
            both = on[:, i] & on[:, j]
            segments.update(zip(np.minimum(tri[both, i], tri[both, j]).tolist(),
                                np.maximum(tri[both, i], tri[both, j]).tolist()))
    if not segments:
        raise ValueError(f"root_junction: no edge of {list(faces)} lies on the {region!r} cells (not a bladed sector?)")
    if spacing is None:
        return np.array([[vertex_x[a], vertex_x[b]] for a, b in sorted(segments)])
    points = []
    for a, b in sorted(segments):
        pa, pb = vertex_x[a], vertex_x[b]
        n = max(2, int(np.ceil(np.linalg.norm(pb - pa) / spacing)) + 1)
        points.append(pa + np.linspace(0.0, 1.0, n)[:, None] * (pb - pa))
    return np.unique(np.vstack(points), axis=0)


def von_mises_at_quadrature(sector: Sector, u, nonlinear: bool = True, degree: int = 4) -> np.ndarray:
    """Direct UFL evaluation of von Mises at the quadrature points of every local cell, ordered as
    ``quadrature_gradients`` (points grouped by cell), for checks of the NumPy recovery."""
    import basix

    points, _ = basix.make_quadrature(basix.CellType.tetrahedron, degree)
    n_cells = sector.mesh.topology.index_map(3).size_local
    expr = fem.Expression(_stress_expression(sector, u, nonlinear), points, jit_params=JIT_PARAMS)
    return expr.eval(np.arange(n_cells, dtype=np.int32)).ravel()


def cell_midpoints(sector: Sector) -> np.ndarray:
    """Centroids (n_local_cells, 3) of the local cells (for locating stress maxima)."""
    from dolfinx import mesh as dmesh

    n_cells = sector.mesh.topology.index_map(3).size_local
    return dmesh.compute_midpoints(sector.mesh, 3, np.arange(n_cells, dtype=np.int32))


def cells_touching_points(sector: Sector, points: np.ndarray, tol: float = 1e-9) -> np.ndarray:
    """Local cells having one of ``points`` (n, 3) among their geometry nodes (e.g. the contact nodes, where point
    contact forces make the FE stress singular)."""
    x = sector.mesh.geometry.x
    n_cells = sector.mesh.topology.index_map(3).size_local
    dofmap = sector.mesh.geometry.dofmap.array
    geom = dofmap.reshape(-1, dofmap.size // sector.mesh.geometry.dofmap.num_nodes)[:n_cells]
    hit = np.zeros(len(x), bool)
    for p in np.asarray(points, float).reshape(-1, 3):
        hit |= np.linalg.norm(x - p, axis=1) < tol
    return np.nonzero(hit[geom].any(axis=1))[0]
