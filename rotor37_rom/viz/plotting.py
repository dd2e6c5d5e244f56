"""Pictures: pyvista off-screen renderings and XDMF output (pyvista and matplotlib are imported lazily)."""
from __future__ import annotations

import logging
from pathlib import Path
from typing import Sequence

import numpy as np

__all__ = ["write_xdmf", "write_function_xdmf", "render_mode_shapes", "render_stress", "vtk_grid", "render_cyclic_mode",
           "write_cyclic_xdmf"]

LOG = logging.getLogger(__name__)


def write_xdmf(sector, functions: Sequence, path: str | Path) -> Path:
    """Write functions (interpolated to P1, the mesh degree) to an XDMF/HDF5 pair for ParaView; one 'time' each."""
    from dolfinx import fem, io

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    V1 = fem.VectorFunctionSpace(sector.mesh, ("Lagrange", 1))
    out = fem.Function(V1, name="displacement")
    with io.XDMFFile(sector.comm, str(path), "w") as xdmf:
        xdmf.write_mesh(sector.mesh)
        for k, f in enumerate(functions):
            out.interpolate(f)
            xdmf.write_function(out, float(k))
    return path


def write_function_xdmf(sector, function, path: str | Path) -> Path:
    """Write one function in its own space (e.g. a cell-wise von Mises field) to an XDMF/HDF5 pair for ParaView."""
    from dolfinx import io

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with io.XDMFFile(sector.comm, str(path), "w") as xdmf:
        xdmf.write_mesh(sector.mesh)
        xdmf.write_function(function)
    return path


def render_mode_shapes(sector, modes: Sequence, titles: Sequence[str], folder: str | Path, amplitude: float = 0.1
                       ) -> list[Path]:
    """One PNG per mode: the blade deformed so that the largest displacement is ``amplitude`` x blade span,
    coloured by the normalised displacement magnitude. Serial only (returns [] under MPI).

    Rendering runs in a child process without dolfinx (see rotor37_rom.viz._render for why).
    """
    if sector.comm.size > 1:
        LOG.warning("render_mode_shapes: pyvista rendering runs serially; skipped under MPI")
        return []
    from dolfinx import plot

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    topology, cell_types, x = plot.create_vtk_mesh(sector.V)
    span = np.ptp(np.hypot(x[:, 0], x[:, 1]))
    scene = {"topology": topology, "cell_types": cell_types, "points": x, "n_frames": len(modes),
             "scalar_name": "|u| (normalised)", "clim": np.array([0.0, 1.0])}     # a colour bar from 0
    paths = []
    for k, (f, title) in enumerate(zip(modes, titles)):
        values = f.x.array.reshape(-1, 3)
        magnitude = np.linalg.norm(values, axis=1)
        path = folder / f"mode_{k + 1}.png"
        scene.update({f"u_{k}": values, f"s_{k}": magnitude / magnitude.max(), f"title_{k}": title,
                      f"path_{k}": str(path), f"factor_{k}": amplitude * span / magnitude.max()})
        paths.append(path)
    run_render(scene, folder / "scene.npz")
    return paths


def run_render(scene: dict, scene_path: Path) -> None:
    """Save the scene and render it in a child process; raises RuntimeError with its last error line."""
    import subprocess
    import sys

    np.savez(scene_path, **scene)
    proc = subprocess.run([sys.executable, "-m", "rotor37_rom.viz._render", str(scene_path)], capture_output=True,
                          text=True)
    scene_path.unlink(missing_ok=True)
    if proc.returncode != 0:
        last = (proc.stderr.strip().splitlines() or ["no output"])[-1]
        raise RuntimeError(f"pyvista rendering failed: {last}")


def vtk_grid(sector):
    """(topology, cell_types, points) of the sector's function space for pyvista (serial)."""
    from dolfinx import plot

    return plot.create_vtk_mesh(sector.V)


def _rotate_z(x: np.ndarray, angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    R = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return x @ R.T


def render_stress(sector, u, cell_values: np.ndarray, path: str | Path, title: str, n_sectors: int = 1,
                  factor: float = 1.0, clim=None, sector_displacements: Sequence | None = None) -> Path:
    """PNG of a cell field (von Mises, Pa; drawn in MPa) on the deformed blade; with n_sectors > 1, the whole disk
    made of rotated copies (sector k turned by 2 pi k / n_sectors about e_z; its displacement from
    ``sector_displacements[k]`` (n_dofs,) or, if None, the same u rotated: a tuned, in-phase response; its cell
    values from ``cell_values[k]`` when cell_values is (n_sectors, n_cells), else the same for all).
    Writes ``path`` and ``path.json`` (the scalar range drawn). Serial only."""
    _check_serial(sector)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    topology, cell_types, x = vtk_grid(sector)
    # the vtk mesh of V has one point per DOF node: the displacement reshapes directly
    u_nodes = np.asarray(u.x.array if hasattr(u, "x") else u).reshape(-1, 3)
    values = np.asarray(cell_values, float)
    if values.shape[-1] != len(cell_types) or values.ndim > 2 or (values.ndim == 2 and len(values) != n_sectors):
        raise ValueError(f"cell_values has shape {values.shape}; the mesh has {len(cell_types)} cells "
                         f"(give (n_cells,) or (n_sectors, n_cells))")
    if n_sectors < 1 or n_sectors > 360:
        raise ValueError(f"n_sectors must be in [1, 360], got {n_sectors}")
    tops, pts, us, vals = [], [], [], []
    n_pts = len(x)
    for k in range(n_sectors):
        angle = 2 * np.pi * k / n_sectors
        uk = u_nodes if sector_displacements is None else np.asarray(sector_displacements[k]).reshape(-1, 3)
        top = topology.reshape(-1, topology[0] + 1).copy()
        top[:, 1:] += k * n_pts
        tops.append(top.ravel())
        pts.append(_rotate_z(x, angle))
        us.append(_rotate_z(uk, angle))
        vals.append(values if values.ndim == 1 else values[k])
    scene = {"topology": np.concatenate(tops), "cell_types": np.tile(cell_types, n_sectors),
             "points": np.vstack(pts), "n_frames": 1, "scalar_name": "von Mises (MPa)", "cell_scalars": True,
             "cmap": "jet", "u_0": np.vstack(us), "s_0": np.concatenate(vals) / 1e6, "title_0": title,
             "path_0": str(path), "factor_0": factor, "no_ghost": n_sectors > 1}
    # von Mises is >= 0: its colour bar starts at 0 (not at the field's smallest value, ~1e-18 Pa at a free edge)
    scene["clim"] = np.asarray((0.0, float(values.max())) if clim is None else clim, float) / 1e6
    if n_sectors > 1:
        scene.update(view=(0.0, 0.0, 1.0), viewup=(0.0, 1.0, 0.0))
    run_render(scene, path.with_suffix(".scene.npz"))
    return path


def _check_serial(sector) -> None:
    if sector.comm.size > 1:
        raise RuntimeError("pyvista rendering runs serially; call it from a serial run")


def _sector_fields(sector, a, b, k: int) -> np.ndarray:
    """(N, n_nodes, 3) displacement of every sector, each turned to the common frame, of the mode (a, b) of index k
    (``disk.symmetry.expand_sector_mode``)."""
    from rotor37_rom.disk.symmetry import expand_sector_mode

    n = sector.cyclic.n_sectors
    local = expand_sector_mode(a.x.array, None if b is None else b.x.array, k, n).reshape(n, -1, 3)
    return np.stack([_rotate_z(local[s], 2 * np.pi * s / n) for s in range(n)])


def render_cyclic_mode(sector, a, b, k: int, path: str | Path, title: str, amplitude: float = 0.08) -> Path:
    """PNG of a mode of harmonic index k of a cyclic sector on the whole structure (all N sectors, the disk
    included), deformed so that the largest displacement is ``amplitude`` x the radius, coloured by the normalised
    displacement magnitude. Writes ``path`` and ``path.json`` (what was drawn). Serial only."""
    _check_serial(sector)
    if sector.cyclic is None:
        raise ValueError(f"{sector.source} is not a cyclic sector")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    topology, cell_types, x = vtk_grid(sector)
    n = sector.cyclic.n_sectors
    u = _sector_fields(sector, a, b, k)
    magnitude = np.linalg.norm(u, axis=2)
    top = topology.reshape(-1, topology[0] + 1)
    tops = [np.column_stack([top[:, :1], top[:, 1:] + s * len(x)]).ravel() for s in range(n)]
    radius = np.hypot(x[:, 0], x[:, 1]).max()
    scene = {"topology": np.concatenate(tops), "cell_types": np.tile(cell_types, n),
             "points": np.vstack([_rotate_z(x, 2 * np.pi * s / n) for s in range(n)]), "n_frames": 1,
             "scalar_name": "|u| (normalised)", "clim": np.array([0.0, 1.0]), "u_0": u.reshape(-1, 3),
             "s_0": (magnitude / magnitude.max()).ravel(),
             "title_0": title, "path_0": str(path), "factor_0": amplitude * radius / magnitude.max(),
             "no_ghost": True, "view": (0.55, -0.45, 0.7), "viewup": (0.0, 0.0, 1.0)}
    run_render(scene, path.with_suffix(".scene.npz"))
    return path


def write_cyclic_xdmf(sector, a, b, k: int, path: str | Path) -> Path:
    """The mode (a, b) of index k on every sector, as one XDMF series over the sector's mesh: step s is sector s's
    displacement in the common frame (ParaView: turn the mesh of step s by 360 s / N degrees about z to place it)."""
    from dolfinx import fem, io

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    u = _sector_fields(sector, a, b, k)
    f = fem.Function(sector.V, name="displacement")
    V1 = fem.VectorFunctionSpace(sector.mesh, ("Lagrange", 1))
    out = fem.Function(V1, name="displacement")
    with io.XDMFFile(sector.comm, str(path), "w") as xdmf:
        xdmf.write_mesh(sector.mesh)
        for s in range(sector.cyclic.n_sectors):
            f.x.array[:] = u[s].ravel()
            out.interpolate(f)
            xdmf.write_function(out, float(s))
    return path



def render_groups(sector, path: str | Path, title: str = "") -> Path:
    """PNG of the sector's boundary coloured by its named facet groups (clamp, tip, left, right, ...; 0: no group)
    with the contact nodes as red dots, so that what a group caught is seen (an over-wide box takes more than the
    face it was meant for). Writes ``path`` and ``path.json`` (what was drawn). Serial only."""
    from dolfinx.cpp.mesh import entities_to_geometry
    from dolfinx.mesh import exterior_facet_indices

    _check_serial(sector)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    mesh = sector.mesh
    fdim = mesh.topology.dim - 1
    mesh.topology.create_connectivity(fdim, mesh.topology.dim)
    facets = exterior_facet_indices(mesh.topology)
    corners = entities_to_geometry(getattr(mesh, "_mesh", mesh), fdim, facets, False)[:, :3]
    value = np.zeros(facets.size)
    names = sorted((tag, name) for name, tag in sector.groups.items() if sector.facet_tags.find(tag).size)
    for k, (tag, _) in enumerate(names, start=1):
        value[np.isin(facets, sector.facet_tags.find(tag))] = k
    topology = np.column_stack([np.full(len(corners), 3), corners]).ravel()
    legend = ", ".join(f"{k} {name}" for k, (_, name) in enumerate(names, start=1))
    scene = {"topology": topology, "cell_types": np.full(len(corners), 5, dtype=np.uint8),
             "points": mesh.geometry.x, "n_frames": 1, "scalar_name": "group", "cell_scalars": True,
             "u_0": np.zeros_like(mesh.geometry.x), "s_0": value, "factor_0": 0.0, "cmap": "tab10",
             "clim": np.array([-0.5, 9.5]), "title_0": (title + "\n" if title else "") + f"groups: 0 none, {legend}",
             "path_0": str(path), "no_ghost": True, "markers": np.asarray(sector.tip_nodes, float).reshape(-1, 3)}
    run_render(scene, path.with_suffix(".scene.npz"))
    return path
