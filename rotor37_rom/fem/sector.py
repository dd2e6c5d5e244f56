"""Sectors: a meshed structure with its named groups and DOF sets (a blade, a disk sector with cyclic faces).

Part of the dolfinx adapter (``rotor37_rom.fem``): gmsh models are turned into distributed dolfinx meshes here.
"""
from __future__ import annotations

import dataclasses
import logging
import time
from pathlib import Path

import numpy as np
import ufl
from scipy.spatial import cKDTree
from dolfinx import fem
from dolfinx.io import gmshio
from mpi4py import MPI
from petsc4py import PETSc

from rotor37_rom.disk.symmetry import CyclicPairs, rotation_z
from rotor37_rom.forms import Material
from rotor37_rom.geometry import blade as blade_geometry
from rotor37_rom.geometry.abaqus import deck_material, read_deck
from rotor37_rom.geometry.nastran import bulk_material
from rotor37_rom.geometry.mesh_import import UNITS, check_blade_mass
from rotor37_rom.geometry.tables import read_blade_table
from rotor37_rom.interruption import Interrupted
from rotor37_rom.reporting import say

from .operators import assemble_scalar

__all__ = ["Sector", "create_blade_sector", "create_sector_from_file", "MissingMaterial", "create_sector_from_gmsh",
           "create_sector_from_mesh", "tip_node_names", "clamp_cell_group", "build_on_rank0", "locate_cyclic_pairs",
           "write_sector_mesh"]

LOG = logging.getLogger(__name__)


def tip_node_names(n: int) -> tuple:
    """Names of n tip contact nodes ordered from LE to TE: 'LE', 'tip1', ..., 'TE'."""
    return tuple(["LE"] + [f"tip{k}" for k in range(1, n - 1)] + (["TE"] if n > 1 else []))


@dataclasses.dataclass(frozen=True)
class Sector:
    """A meshed structure with named groups and DOF sets: a blade, or a disk sector with cyclic faces.

    Attributes:
        mesh: dolfinx mesh (distributed over ``mesh.comm``). cell_tags, facet_tags: gmsh physical groups as dolfinx
        MeshTags. groups: group name -> tag (BladeGroup names, lower case). V: vector P``degree`` function space.
        material: the material. clamp_bc: homogeneous Dirichlet condition on the clamp facets. tip_nodes: (n_tip, 3)
        coordinates of the contact nodes, LE first (m), identical on all ranks. tip_dofs: (n_tip, 3) local (unblocked)
        DOF indices of the tip nodes on this rank, -1 where not owned here. tip_names: the contact nodes' names, 'LE',
        'tip1', ..., 'TE' in the order of tip_nodes. cyclic: the cyclic faces as global DOF indices paired node for node
        (``disk.symmetry.CyclicPairs``: right[i] is
            left[i] turned by 2 pi / N), None for a single blade.
        volume: CAD volume (m^3); for a mesh file, the mesh's own (assembled).
        source: where the geometry came from; preset: mesh preset name.
        summary: one line on what was read or meshed (files brought in from elsewhere), else ''.
    """

    mesh: object
    cell_tags: object
    facet_tags: object
    groups: dict
    V: object
    material: Material
    clamp_bc: object
    tip_nodes: np.ndarray
    tip_dofs: np.ndarray
    tip_names: tuple
    cyclic: object
    volume: float
    source: str
    preset: str
    summary: str = ""

    @property
    def comm(self) -> MPI.Comm:
        return self.mesh.comm

    @property
    def n_dofs(self) -> int:
        """Global number of DOFs (clamped ones included)."""
        im = self.V.dofmap.index_map
        return im.size_global * self.V.dofmap.index_map_bs

    def facets(self, name: str) -> np.ndarray:
        """Local facet indices of a named group."""
        if name not in self.groups:
            raise ValueError(f"group {name!r} not in this sector; it has {sorted(self.groups)}")
        return self.facet_tags.find(self.groups[name])

    def total_mass(self) -> float:
        return assemble_scalar(self.material.rho * ufl.dx(domain=self.mesh), self.comm)

    def blade_frame_angle(self) -> float:
        """The angle (rad) about e_z of the blade's frame: the plane through the rotation axis and the blade's centre
        of mass (of its 'blade' volume in a bladed-disk sector). A blade stacked on its sections' centroids along a
        radial line (rotor 37) has that line in this plane, so the frame comes from the blade, not from where it sits
        in its file: turned by any angle about e_z, its frame turns with it. Collective (every rank calls it)."""
        x = ufl.SpatialCoordinate(self.mesh)
        tags = self.cell_tags
        several = tags is not None and len(set(np.unique(tags.values).tolist())) > 1 and "blade" in self.groups
        dx = ufl.Measure("dx", domain=self.mesh, subdomain_data=tags)(self.groups["blade"]) if several else \
            ufl.dx(domain=self.mesh)
        cx, cy = (assemble_scalar(x[i] * dx, self.comm) for i in (0, 1))
        if np.hypot(cx, cy) <= 1e-9 * assemble_scalar(ufl.sqrt(x[0] ** 2 + x[1] ** 2) * dx, self.comm):
            raise ValueError(f"{self.source}: the blade's centre of mass lies on the rotation axis (e_z): it has no "
                             "radial direction to take its frame from (is the axis right?)")
        return float(np.arctan2(cy, cx))


def _locate_point_dofs(V, points: np.ndarray, tol: float = 1e-9) -> np.ndarray:
    """(n, 3) owned local DOF indices of the vertices at ``points`` (-1 where not owned by this rank)."""
    bs = V.dofmap.index_map_bs
    n_owned = V.dofmap.index_map.size_local
    out = -np.ones((len(points), bs), dtype=np.int64)
    for k, p in enumerate(points):  # loop over a handful of contact nodes, not over DOFs
        blocks = fem.locate_dofs_geometrical(V, lambda x, p=p: np.linalg.norm(x.T - p, axis=1) < tol)
        blocks = blocks[blocks < n_owned]
        if blocks.size:
            out[k] = blocks[0] * bs + np.arange(bs)
    found = V.mesh.comm.allreduce((out[:, 0] >= 0).astype(int), op=MPI.SUM)
    if np.any(found != 1):
        missing = np.flatnonzero(found != 1)
        raise ValueError(f"tip nodes {missing.tolist()} are not vertices of the mesh (boundary nodes not on the mesh)")
    return out


def create_sector_from_gmsh(comm: MPI.Comm, model_info, material: Material, degree: int = 2,
                            preset: str = "") -> Sector:
    """Build a :class:`Sector` from the current gmsh model (alive on rank 0 only) and its builder report; a report
    with ``n_sectors`` (a cyclic sector) gets its left/right faces paired."""
    import gmsh

    names = {}
    if comm.rank == 0:
        names = {gmsh.model.getPhysicalName(d, t): t for d, t in gmsh.model.getPhysicalGroups()}
    names = comm.bcast(names, root=0)
    model_info = comm.bcast(model_info, root=0)
    mesh, cell_tags, facet_tags = gmshio.model_to_mesh(gmsh.model if comm.rank == 0 else None, comm, 0, gdim=3)
    sector = create_sector_from_mesh(mesh, cell_tags, facet_tags, names, material, degree,
                                     np.asarray(model_info.tip_nodes, dtype=float).reshape(-1, 3),
                                     float(model_info.volume), model_info.source, preset,
                                     free=bool(getattr(model_info, "free", False)))
    if getattr(model_info, "summary", ""):
        sector = dataclasses.replace(sector, summary=model_info.summary)
    n_sectors = getattr(model_info, "n_sectors", 0)
    if n_sectors:                            # a cyclic sector: pair its faces now
        sector = dataclasses.replace(sector, cyclic=locate_cyclic_pairs(sector, n_sectors))
    return sector


def create_sector_from_mesh(mesh, cell_tags, facet_tags, groups: dict, material: Material, degree: int = 2,
                            tip_nodes: np.ndarray | None = None, volume: float = float("nan"), source: str = "mesh",
                            preset: str = "", free: bool = False) -> Sector:
    """A :class:`Sector` from a distributed dolfinx mesh whose facet tags hold a group named 'clamp' (``free``: a
    structure held by nothing, e.g. a free ring's cyclic sector, whose clamp condition is empty; its operators are
    singular where rigid-body motions live: k = 0 and 1 of a cyclic sector)."""
    if not (1 <= degree <= 3):
        raise ValueError(f"degree must be 1, 2 or 3, got {degree}")
    comm = mesh.comm
    V = fem.VectorFunctionSpace(mesh, ("Lagrange", degree))
    mesh.topology.create_connectivity(mesh.topology.dim - 1, mesh.topology.dim)
    if free:
        clamp_dofs = np.zeros(0, dtype=np.int32)
    else:
        if "clamp" not in groups:
            raise ValueError(f"the model of {source} has no 'clamp' group; it has {sorted(groups)}")
        clamp_facets = facet_tags.find(groups["clamp"])
        if comm.allreduce(clamp_facets.size, op=MPI.SUM) == 0:
            raise ValueError(f"the clamp group of {source} holds no facets")
        clamp_dofs = fem.locate_dofs_topological(V, mesh.topology.dim - 1, clamp_facets)
    clamp_bc = fem.dirichletbc(np.zeros(3, dtype=PETSc.ScalarType), clamp_dofs, V)
    tip_nodes = np.zeros((0, 3)) if tip_nodes is None else np.asarray(tip_nodes, float).reshape(-1, 3)
    tip_dofs = _locate_point_dofs(V, tip_nodes) if len(tip_nodes) else np.zeros((0, 3), dtype=np.int64)
    return Sector(mesh=mesh, cell_tags=cell_tags, facet_tags=facet_tags, groups=dict(groups), V=V,
                  material=material, clamp_bc=clamp_bc, tip_nodes=tip_nodes, tip_dofs=tip_dofs,
                  tip_names=tip_node_names(len(tip_nodes)), cyclic=None, volume=volume, source=source,
                  preset=preset)


def build_on_rank0(comm: MPI.Comm, build, material: Material, degree: int, preset: str, what: str) -> Sector:
    """Run a gmsh builder (``build()``, returning its model report) on rank 0 and distribute its mesh as a Sector.
    A builder's ValueError, or gmsh's own failure, becomes one ValueError on every rank naming ``what``."""
    info, error = None, None
    if comm.rank == 0:
        with blade_geometry.gmsh_session():
            try:
                info = build()
            except ValueError as exc:
                error = str(exc)
            except Interrupted:                     # SIGTERM or SIGINT while meshing: a stop, not a gmsh failure
                raise
            except Exception as exc:  # gmsh's own failures: one line, naming the step
                error = f"gmsh failed on {what} ({str(exc).splitlines()[0]})"
            comm.Ibarrier().Wait()                  # matches the other ranks' polled barrier
            error = comm.bcast(error, root=0)
            if error is None:
                return create_sector_from_gmsh(comm, info, material, degree, preset)
    else:
        # OpenMPI's blocking calls spin: waiting in one would take a core from gmsh (a 2-core machine meshed
        # 1.4-1.8 times slower); poll a non-blocking barrier instead
        request = comm.Ibarrier()
        while not request.Test():
            time.sleep(0.005)
        error = comm.bcast(None, root=0)
        if error is None:
            return create_sector_from_gmsh(comm, None, material, degree, preset)
    raise ValueError(error)


def create_blade_sector(comm: MPI.Comm = MPI.COMM_WORLD, table: str | Path | None = None, preset="coarse",
                        material: Material | None = None, degree: int = 2,
                        n_tip_nodes: int = blade_geometry.N_TIP_NODES, shorten: float = 0.0) -> Sector:
    """Mesh the rotor 37 blade with gmsh (rank 0) and distribute it.

    Args:
        comm: communicator.
        table: path of NASA Table IV for the exact loft; None for the built-in parametric blade.
        preset: mesh preset name ('ci', 'coarse', 'paper') or a geometry.blade.MeshPreset.
        material: defaults to the paper's maraging steel.
        degree: Lagrange degree of the displacement (2 = the paper's quadratic elements).
        n_tip_nodes: contact nodes along the tip camber line, LE and TE included.
        shorten: radial length removed at the tip (m), parametric blade only.
    """
    preset_obj = blade_geometry.get_mesh_preset(preset)
    table_obj = read_blade_table(table) if table is not None else None
    return build_on_rank0(comm, lambda: blade_geometry.create_blade_model(table_obj, preset_obj,
                                                                         n_tip_nodes=n_tip_nodes, shorten=shorten),
                          material or Material(), degree, preset_obj.name, "the blade")


def create_sector_from_file(path: str | Path, clamp, tip=None, comm: MPI.Comm = MPI.COMM_WORLD,
                            preset="coarse", material: Material | None = None, degree: int = 2,
                            scale: float = 1.0, units: str | None = None, contact=None,
                            verbose: bool = True, mass_check: bool = True, cyclic=None,
                            blade: str | None = None, axis: str = "+z") -> Sector:
    """A user's blade from a CAD file (STEP/BREP) or a mesh from another FE code (.msh, .inp, .bdf/.nas, .vtk/.vtu);
    see geometry.blade.import_blade_model for clamp, tip, scale/units and contact (the contact nodes, ordered
    LE -> TE). With ``verbose``, rank 0 prints what was read, the bounding box and the mass. A mass outside 1 g -
    100 kg (a blade) is refused with the number and the units the file is likely in (a unit slip:
    ``geometry.mesh_import.check_blade_mass``), unless ``mass_check`` is False (the mass confirmed). ``cyclic=(left,
    right, N)``: a cyclic sector (a bladed disk's, or any structure of N identical sectors about e_z) whose faces
    ``left`` (at the lower angle) and ``right`` (turned by 2 pi / N) are groups of the file or boxes; they are paired
    node for node (``locate_cyclic_pairs``), and the sector takes every cyclic operator as the built-in disk's
    does. ``blade``: the element set of a cyclic sector's blade, which makes its volumes 'blade' and 'disk' as the
    built-in sector's (the SAFE diagram's blade share, ``clamp_cell_group``). ``axis``: the file's rotation axis
    ('+z', '-x', ...), turned to +z (the project's: the rotation, the casing, the cyclic faces are about it).

    Normalisation of the cyclic modes (``solve_cyclic_modes``, ``CyclicModes``): each cos/sin pair (a, b) is
    normalised on the sector, a^T M a + b^T M b = 1; expanded on the whole structure (``expand``) its modal mass is
    N/2 for 0 < k < N/2 and N for k = 0 and k = N/2 (one real shape), as in every cyclic-symmetry code."""
    material = file_material(path, material, units, scale, verbose and comm.rank == 0)
    sector = build_on_rank0(comm, lambda: blade_geometry.import_blade_model(path, clamp, tip, preset, scale, units,
                                                                           contact, cyclic, blade, axis),
                            material, degree, str(preset), str(path))
    if not np.isfinite(sector.volume):                 # a mesh file: its volume from the mesh (curved P2 cells too)
        sector = dataclasses.replace(sector, volume=assemble_scalar(1.0 * ufl.dx(domain=sector.mesh), sector.comm))
    mass = sector.volume * sector.material.rho
    if comm.rank == 0 and verbose:
        say(f"{sector.summary}; mass {mass:.4g} kg (rho = {sector.material.rho:g} kg/m^3); "
              f"{len(sector.tip_nodes)} contact nodes", flush=True)
    if mass_check:
        check_blade_mass(mass, UNITS[units] if units is not None else scale, str(path))
    return sector


class MissingMaterial(ValueError):
    """A user's file states no material and none was given: a default steel would be a silent guess."""


def file_material(path, material: Material | None, units: str | None, scale: float, verbose: bool) -> Material:
    """The material of a user's file: ``material`` where given, else the material of an Abaqus/CalculiX deck
    (``*MATERIAL``/``*ELASTIC``/``*DENSITY``, in SI for a deck in metres, N-mm-t-s for one in millimetres:
    ``geometry.abaqus.deck_material``) or of a NASTRAN file's first MAT1 (``geometry.nastran.bulk_material``);
    a file that states none and no ``material`` given is refused (``MissingMaterial``: ``material=Material()``
    confirms the paper's maraging steel). Printed with ``verbose``, and where the deck states another material than
    the one given."""
    deck = None
    suffix = Path(path).suffix.lower()
    if suffix in (".inp", ".bdf", ".nas", ".fem"):
        unit = units if units is not None else {1.0: "m", 1e-3: "mm"}.get(float(scale), f"scale {scale:g}")
        try:
            found = deck_material(read_deck(path), unit) if suffix == ".inp" else bulk_material(path, unit)
        except ValueError:
            if material is None:
                raise
            found = None                # the given material stands; the file's, unreadable in these units, aside
        if found is not None:
            deck = Material(E=found[0], nu=found[1], rho=found[2])

    def stated(m: Material) -> str:
        return f"E = {m.E / 1e9:.4g} GPa, nu = {m.nu:g}, rho = {m.rho:.5g} kg/m^3"

    if material is None and deck is None:
        raise MissingMaterial(f"{Path(path).name} states no material: give material=Material(E, nu, rho), or "
                              "material=Material() to confirm the paper's maraging steel")
    chosen = material or deck
    if verbose:
        where = "given" if material is not None else "the deck's"
        other = f"; the deck states {stated(deck)}" if material is not None and deck is not None and deck != material \
            else ""
        say(f"material: {stated(chosen)} ({where}){other}", flush=True)
    return chosen


def clamp_cell_group(sector: Sector, group: str) -> Sector:
    """The sector with every DOF of the cells of a named volume group clamped as well (e.g. 'disk': the blade of a
    disk sector clamped at its root, on the same mesh; by Rayleigh's theorem of constraint its frequencies bound the
    unclamped structure's from above)."""
    if group not in sector.groups:
        raise ValueError(f"group {group!r} not in this sector; it has {sorted(sector.groups)}")
    cells = sector.cell_tags.find(sector.groups[group])
    dofs = fem.locate_dofs_topological(sector.V, sector.mesh.topology.dim, cells)
    all_dofs = np.union1d(dofs, sector.clamp_bc.dof_indices()[0] // sector.V.dofmap.index_map_bs)
    bc = fem.dirichletbc(np.zeros(3, dtype=PETSc.ScalarType), all_dofs.astype(np.int32), sector.V)
    return dataclasses.replace(sector, clamp_bc=bc, cyclic=None, source=f"{sector.source} with {group} clamped")


def _face_nodes(sector: Sector, name: str) -> tuple[np.ndarray, np.ndarray]:
    """(global blocks, coordinates) of the DOF nodes on a named face group, gathered on every rank."""
    V, mesh = sector.V, sector.mesh
    mesh.topology.create_connectivity(mesh.topology.dim - 1, mesh.topology.dim)
    blocks = fem.locate_dofs_topological(V, mesh.topology.dim - 1, sector.facets(name))
    blocks = blocks[blocks < V.dofmap.index_map.size_local]
    coords = V.tabulate_dof_coordinates()[blocks]
    glob = V.dofmap.index_map.local_range[0] + blocks
    parts = sector.comm.allgather((glob, coords))
    g = np.concatenate([p[0] for p in parts]).astype(np.int64)
    x = np.vstack([p[1] for p in parts]) if g.size else np.zeros((0, 3))
    order = np.argsort(g)
    return g[order], x[order]


def _face_hint(x_left: np.ndarray, x_right: np.ndarray, angle: float, tol: float) -> str:
    """Why two cyclic faces do not match, where it can be told: given the other way round (left is the face at the
    higher angle), or turned by another angle (another N)."""
    back, _ = cKDTree(x_left).query(x_right @ rotation_z(angle).T)
    if back.max() <= tol:
        return ": the faces are swapped (the left face is the one at the higher angle): exchange left and right"
    # the mean of e^{i theta} over a face turns with the face: the angle between the two faces' means is the turn
    turn = np.angle(np.mean(x_right[:, 0] + 1j * x_right[:, 1]) / np.mean(x_left[:, 0] + 1j * x_left[:, 1]))
    if abs(turn) > 1e-6 and abs(2 * np.pi / abs(turn) - round(2 * np.pi / abs(turn))) < 1e-3:
        n = int(round(2 * np.pi / abs(turn)))
        if 2 <= n <= 360 and abs(abs(turn) - angle) > 1e-9:
            again, _ = cKDTree(x_left).query(x_right @ rotation_z(-turn).T)
            if again.max() <= tol:
                return (f": they match under a rotation by 360/{n} degrees" +
                        (" (with left and right exchanged)" if turn < 0 else "") + f": N = {n}?")
    return ""


def locate_cyclic_pairs(sector: Sector, n_sectors: int, rel_tol: float = 1e-6) -> CyclicPairs:
    """Pair the DOF nodes of the sector's 'left' and 'right' faces under the rotation by 2 pi / N about e_z.

    Every right node must sit within rel_tol x (the sector's size) of a turned left node, one to one (gmsh's
    ``setPeriodic`` builds such meshes; the worst distance is reported). Nodes on both faces are axis nodes. Pairs
    clamped on both faces are dropped (u = 0 meets every constraint); a pair clamped on one face only is an error.
    Returns global (unblocked) DOF indices, identical on every rank."""
    for name in ("left", "right"):
        if name not in sector.groups:
            raise ValueError(f"the mesh of {sector.source} has no '{name}' face group: it is not a cyclic sector "
                             f"(groups: {sorted(sector.groups)})")
    if int(n_sectors) != n_sectors or not 2 <= n_sectors <= 360:
        raise ValueError(f"n_sectors must be an integer in [2, 360] (the sector angle 360/N degrees divides the "
                         f"circle), got {n_sectors}")
    left, x_left = _face_nodes(sector, "left")
    right, x_right = _face_nodes(sector, "right")
    if left.size == 0 or left.size != right.size:
        raise ValueError(f"cyclic faces: {left.size} left and {right.size} right nodes (the meshes do not match)")
    axis = np.intersect1d(left, right)
    keep_l, keep_r = ~np.isin(left, axis), ~np.isin(right, axis)
    left, x_left, right, x_right = left[keep_l], x_left[keep_l], right[keep_r], x_right[keep_r]
    angle = 2 * np.pi / n_sectors
    turned_back = x_right @ rotation_z(-angle).T
    dist, match = cKDTree(x_left).query(turned_back)
    scale = float(np.abs(np.vstack([x_left, x_right])).max())
    worst = int(np.argmax(dist)) if dist.size else 0
    if dist.size and dist[worst] > rel_tol * scale:
        p = x_right[worst]
        raise ValueError(f"cyclic faces do not match under a rotation by 360/{n_sectors} degrees: the right node at "
                         f"({p[0]:.6g}, {p[1]:.6g}, {p[2]:.6g}) m is {dist[worst]:.3g} m from the nearest turned left "
                         f"node (tolerance {rel_tol * scale:.3g} m)" + _face_hint(x_left, x_right, angle,
                                                                                   rel_tol * scale))
    if len(np.unique(match)) != match.size:
        raise ValueError("cyclic faces: two right nodes match the same left node (duplicate nodes on a face?)")
    left = left[match]
    clamped_local = sector.clamp_bc.dof_indices()[0]
    bs = sector.V.dofmap.index_map_bs
    owned = clamped_local[clamped_local < sector.V.dofmap.index_map.size_local * bs]
    start = sector.V.dofmap.index_map.local_range[0]
    clamped_blocks = np.unique(np.concatenate(sector.comm.allgather(start + owned // bs)))
    cl, cr = np.isin(left, clamped_blocks), np.isin(right, clamped_blocks)
    if np.any(cl != cr):
        raise ValueError("cyclic faces: a node is clamped on one face and free on the other (the clamp must be "
                         "cyclic too)")
    left, right = left[~cl], right[~cr]
    axis = axis[~np.isin(axis, clamped_blocks)]
    triples = lambda b: (bs * b[:, None] + np.arange(bs)[None, :]).astype(np.int64)      # noqa: E731
    LOG.info("cyclic faces: %d node pairs, %d axis nodes, worst distance %.3g m", left.size, axis.size,
             dist.max() if dist.size else 0.0)
    return CyclicPairs(int(n_sectors), triples(left), triples(right), triples(axis),
                       float(dist.max()) if dist.size else 0.0)


def write_sector_mesh(sector: Sector, path: str | Path, units: str = "m") -> Path:
    """Write a sector's mesh as an Abaqus/CalculiX input deck (serial; meshio): coordinates in ``units``, its
    tetrahedra (C3D4 / C3D10), each named facet group as a node set of its facets' corners (upper-case name: CLAMP,
    TIP, ...), the contact nodes as the node set CONTACT and, where the sector has several volumes (a bladed-disk
    sector's blade and disk), each as an element set (BLADE, DISK).
    ``create_sector_from_file(path, clamp='CLAMP', tip='TIP', units=units, contact='CONTACT')`` reads it back."""
    import meshio
    from dolfinx.cpp.io import perm_vtk
    from dolfinx.cpp.mesh import entities_to_geometry

    from rotor37_rom.geometry.mesh_import import UNITS

    if sector.comm.size != 1:
        raise ValueError("write_sector_mesh runs on one process (the mesh is distributed here)")
    if units not in UNITS:
        raise ValueError(f"units must be one of {', '.join(UNITS)}, got {units!r}")
    deck_material_lines(sector.material, units, 1)              # units the material can be written in
    path = Path(path)
    if path.suffix.lower() != ".inp":
        raise ValueError(f"write_sector_mesh writes an Abaqus/CalculiX .inp deck (the exchange format that keeps named "
                         f"node sets), got {path.name}")
    mesh = sector.mesh
    x = mesh.geometry.x / UNITS[units]
    nodes_per_cell = mesh.geometry.dofmap.offsets[1]
    cells = mesh.geometry.dofmap.array.reshape(-1, nodes_per_cell)
    to_vtk = np.argsort(perm_vtk(mesh.topology.cell_type, nodes_per_cell))
    cells = cells[:, to_vtk]
    mesh.topology.create_connectivity(mesh.topology.dim - 1, mesh.topology.dim)
    point_sets = {}
    for name in sorted(sector.groups):
        facets = sector.facet_tags.find(sector.groups[name])
        if facets.size:
            geometry_nodes = entities_to_geometry(getattr(mesh, "_mesh", mesh),
                                                  mesh.topology.dim - 1, facets, False)   # corners: enough
            point_sets[name.upper()] = np.unique(geometry_nodes).astype(np.int64)
    if len(sector.tip_nodes):
        point_sets["CONTACT"] = cKDTree(mesh.geometry.x).query(sector.tip_nodes)[1].astype(np.int64)
    kind = "tetra10" if nodes_per_cell == 10 else "tetra"
    cell_sets = {}
    if sector.cell_tags is not None and len(sector.cell_tags.values) and len(set(sector.cell_tags.values)) > 1:
        names = {tag: name for name, tag in sector.groups.items()}
        for tag in np.unique(sector.cell_tags.values):
            if int(tag) in names:
                cell_sets[names[int(tag)].upper()] = [sector.cell_tags.find(tag).astype(np.int64)]
    meshio.write(path, meshio.Mesh(x, [(kind, cells)], point_sets=point_sets, cell_sets=cell_sets))
    with open(path, "a") as deck:                       # the material, so that the deck reads back as it was
        deck.write(deck_material_lines(sector.material, units, len(cells)))
    return path


def deck_material_lines(material: Material, units: str, n_cells: int) -> str:
    """``*MATERIAL`` / ``*ELASTIC`` / ``*DENSITY`` and a ``*SOLID SECTION`` over the ``n_cells`` elements of a deck in
    ``units`` ('m': N, Pa, kg/m^3; 'mm': N, MPa, t/mm^3, ``geometry.abaqus.MATERIAL_UNITS``); ValueError for units
    with no consistent system."""
    from rotor37_rom.geometry.abaqus import MATERIAL_UNITS

    if units not in MATERIAL_UNITS:
        raise ValueError(f"units must be one of {', '.join(MATERIAL_UNITS)} for a deck that keeps its material (a "
                         f"material in {units!r} has no consistent unit system), got {units!r}")
    stress, mass = MATERIAL_UNITS[units]
    return (f"*ELSET, ELSET=EALL, GENERATE\n1, {n_cells}, 1\n*MATERIAL, NAME=SECTOR_MATERIAL\n*ELASTIC\n"
            f"{material.E / stress!r}, {material.nu!r}\n*DENSITY\n{material.rho / mass!r}\n"
            "*SOLID SECTION, ELSET=EALL, MATERIAL=SECTOR_MATERIAL\n")
