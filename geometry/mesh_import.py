"""Meshes from other FE codes: read (meshio), convert to conforming tetrahedra, name groups, pick contact nodes.

A blade dynamicist receives meshes as gmsh ``.msh``, Abaqus/CalculiX ``.inp``, NASTRAN ``.bdf`` or VTK files, in
any units and with tetrahedra, hexahedra, wedges or pyramids of order 1 or 2. dolfinx 0.5 takes one cell type per
mesh, so every cell becomes tetrahedra of the same order:

* the quadrilateral faces get the diagonal through their smallest global node (the rule of Dompierre, Labbé,
  Vallet & Camarero, 1999): two cells sharing a face split it the same way, so the tetrahedra are conforming;
* the cell is then filled with the fewest tetrahedra that use exactly those face triangles (wedge: 3, pyramid: 2,
  hexahedron: 5 or 6), found once per diagonal pattern by a search on the reference cell (the rule never gives
  the twisted patterns that have no filling without an extra point);
* for quadratic cells, the new edges' mid-nodes (face and body diagonals) are placed by the cell's own
  serendipity map, so the curved geometry is kept; a face diagonal's node is shared with the neighbouring cell.

Named node sets, element sets and physical groups all become node sets; a facet group is the boundary facets whose
corners all lie in a set. The result is written into the current gmsh model (a discrete volume with the project's
physical groups), so that the rest of the pipeline reads it as it reads the project's own meshes.

Only NumPy, meshio and gmsh are used (geometry layer).
"""
from __future__ import annotations

import contextlib
import dataclasses
import functools
import io
import itertools
import os
import tempfile
from pathlib import Path
from typing import Sequence

import numpy as np

from .abaqus import AbaqusDeck, read_deck
from .nastran import without_materials

__all__ = ["MESH_SUFFIXES", "UNITS", "BLADE_MASS", "check_blade_mass", "group_report", "outward_normals",
           "check_box_face", "check_contact_on_tip", "ImportedMesh", "read_mesh",
           "split_to_tetrahedra", "boundary_facets", "order_le_to_te", "select_contact_nodes", "add_to_gmsh", "AXES",
           "turn_to_z"]

MESH_SUFFIXES = (".msh", ".inp", ".bdf", ".nas", ".fem", ".vtk", ".vtu")
UNITS = {"m": 1.0, "mm": 1e-3, "cm": 1e-2, "in": 0.0254}
BLADE_MASS = (1e-3, 100.0)                 # kg: a blade's mass lies between a gram and a hundred kilograms


#: the rotation axis of a file -> the proper rotation that turns it to +z (the project's axis): new = R @ old
AXES = {"+z": np.eye(3), "-z": np.diag([1.0, -1.0, -1.0]),
        "+x": np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]),
        "-x": np.array([[0.0, 1.0, 0.0], [0.0, 0.0, -1.0], [-1.0, 0.0, 0.0]]),
        "+y": np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]),
        "-y": np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])}


def turn_to_z(axis: str) -> np.ndarray:
    """R (3, 3): the proper rotation taking the file's rotation ``axis`` ('+x', '-y', ...) to +z; ValueError for
    another axis."""
    if axis not in AXES:
        raise ValueError(f"axis must be one of {', '.join(AXES)} (the rotation axis of the file), got {axis!r}")
    return AXES[axis]


def check_blade_mass(mass: float, scale: float, what: str) -> None:
    """ValueError naming ``what`` where a blade read with coordinates times ``scale`` (to metres) weighs outside
    ``BLADE_MASS``, with the units it would weigh a plausible mass in (a millimetre file read as metres weighs 1e9
    times too much): the message gives the mass, the likely unit and how to go on."""
    low, high = BLADE_MASS
    if low <= mass <= high:
        return
    masses = {u: mass * (f / scale) ** 3 for u, f in UNITS.items()}
    fits = [u for u, m in masses.items() if low <= m <= high]
    likely = min(fits, key=lambda u: abs(np.log(masses[u] / 0.3))) if fits else None
    hint = f"; the file is likely in {likely} ({masses[likely]:.3g} kg with units {likely!r})" if likely else ""
    raise ValueError(f"{what}: the blade's mass is {mass:.3g} kg, outside 1 g - 100 kg{hint}; give the file's units, "
                     "or confirm the mass (mass_check=False, --mass-check off)")

# reference cells in meshio's (VTK's) node order: corner coordinates, edges (mid-node order), faces
_REF = {
    "tetra": dict(x=[(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)],
                  edges=[(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)],
                  tris=[(0, 1, 2), (0, 1, 3), (1, 2, 3), (0, 2, 3)], quads=[]),
    "pyramid": dict(x=[(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0.5, 0.5, 1)],
                    edges=[(0, 1), (1, 2), (2, 3), (3, 0), (0, 4), (1, 4), (2, 4), (3, 4)],
                    tris=[(0, 1, 4), (1, 2, 4), (2, 3, 4), (3, 0, 4)], quads=[(0, 1, 2, 3)]),
    "wedge": dict(x=[(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (0, 1, 1)],
                  edges=[(0, 1), (1, 2), (2, 0), (3, 4), (4, 5), (5, 3), (0, 3), (1, 4), (2, 5)],
                  tris=[(0, 1, 2), (3, 4, 5)], quads=[(0, 1, 4, 3), (1, 2, 5, 4), (2, 0, 3, 5)]),
    "hexahedron": dict(x=[(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)],
                       edges=[(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4), (0, 4), (1, 5), (2, 6),
                              (3, 7)],
                       tris=[], quads=[(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6),
                                       (3, 0, 4, 7)]),
}
# meshio cell type -> (reference cell, corner count, nodes used, quadratic?); the 27-node hexahedron uses its
# serendipity subset (its first 20 nodes). Not wedge18: meshio 5.3 reads gmsh's Prism18 without reordering its
# nodes (simvia-tech/meshlane#27, nschloe/meshio#1517), so its geometry would be wrong.
CELL_TYPES = {
    "tetra": ("tetra", 4, 4, False), "tetra10": ("tetra", 4, 10, True),
    "pyramid": ("pyramid", 5, 5, False), "pyramid13": ("pyramid", 5, 13, True),
    "wedge": ("wedge", 6, 6, False), "wedge15": ("wedge", 6, 15, True),
    "hexahedron": ("hexahedron", 8, 8, False), "hexahedron20": ("hexahedron", 8, 20, True),
    "hexahedron27": ("hexahedron", 8, 20, True),
}
_SOLID_PREFIXES = ("tetra", "pyramid", "wedge", "hexahedron")
_TET_EDGES = _REF["tetra"]["edges"]
_TET_FACES = _REF["tetra"]["tris"]
_GMSH_TET10 = [0, 1, 2, 3, 4, 5, 6, 7, 9, 8]        # meshio (VTK) -> gmsh order of the 10-node tetrahedron


@dataclasses.dataclass
class ImportedMesh:
    """A mesh of tetrahedra (4 or 10 nodes, VTK order), its named node sets and what the conversion did.

    Attributes:
        points: (n, 3) coordinates in metres (after scaling).
        tets: (m, 4) or (m, 10) node indices.
        node_sets: group name -> sorted node indices (node sets, element sets and physical groups of the file).
        converted: input cell type -> (cells read, tetrahedra made).
        source: the file.
        cell_sets: element-set name -> sorted indices of the tetrahedra made of its solid cells (e.g. the blade of
            a bladed-disk sector).
    """

    points: np.ndarray
    tets: np.ndarray
    node_sets: dict
    converted: dict
    source: str
    cell_sets: dict = dataclasses.field(default_factory=dict)

    @property
    def quadratic(self) -> bool:
        return self.tets.shape[1] == 10

    def bounding_box(self) -> tuple[np.ndarray, np.ndarray]:
        used = np.unique(self.tets)
        return self.points[used].min(axis=0), self.points[used].max(axis=0)

    def summary(self) -> str:
        """One line: what was read and made, bounding box."""
        lo, hi = self.bounding_box()
        parts = [f"{n:,} {kind}" + (f" -> {t:,} tetrahedra" if kind not in ("tetra", "tetra10") else "")
                 for kind, (n, t) in self.converted.items()]
        return (f"{self.source}: {', '.join(parts)}; {len(np.unique(self.tets)):,} nodes; bounding box "
                f"[{lo[0]:.4g}, {hi[0]:.4g}] x [{lo[1]:.4g}, {hi[1]:.4g}] x [{lo[2]:.4g}, {hi[2]:.4g}] m")

    def nodes_of(self, spec, what: str) -> np.ndarray:
        """Node indices of a group name or of a box (xmin, ymin, zmin, xmax, ymax, zmax) in metres."""
        if isinstance(spec, str):
            return self.group(spec, what)
        box = np.asarray(spec, dtype=float).ravel() if np.ndim(spec) == 1 else np.zeros(0)
        if box.size != 6 or not np.all(box[:3] <= box[3:]):
            raise ValueError(f"{what} must be a group name or a box (xmin, ymin, zmin, xmax, ymax, zmax) in metres, "
                             f"got {spec!r}")
        inside = np.flatnonzero(np.all((self.points >= box[:3]) & (self.points <= box[3:]), axis=1))
        if inside.size == 0:
            raise ValueError(f"{what}: no node of {self.source} lies inside the box {tuple(box)} m")
        return inside

    def cell_set(self, name: str, what: str) -> np.ndarray:
        """Tetrahedra of a named element set of solid cells: the exact name, else the unique case-insensitive
        match."""
        matches = [name] if name in self.cell_sets else [k for k in self.cell_sets if k.lower() == str(name).lower()]
        if len(matches) != 1:
            raise ValueError(f"{what}: {self.source} has no element set of solid cells named {name!r}; its element "
                             f"sets: {', '.join(sorted(self.cell_sets)) or 'none'}")
        return self.cell_sets[matches[0]]

    def group(self, name: str, what: str) -> np.ndarray:
        """Node indices of a named group: the exact name, else the unique case-insensitive match."""
        if name in self.node_sets:
            return self.node_sets[name]
        matches = [k for k in self.node_sets if k.lower() == str(name).lower()]
        if len(matches) == 1:
            return self.node_sets[matches[0]]
        raise ValueError(f"{what}: {self.source} has no group named {name!r}; its groups: "
                         f"{', '.join(sorted(self.node_sets)) or 'none'}")


def read_mesh(path: str | os.PathLike, scale: float = 1.0) -> ImportedMesh:
    """Read a mesh file with meshio (gmsh .msh, Abaqus/CalculiX .inp, NASTRAN .bdf/.nas/.fem, VTK .vtk/.vtu),
    scale its coordinates to metres and convert its solid cells to tetrahedra (see the module docstring)."""
    import meshio

    # meshio 5.3 lacks the topological dimension of some quadratic cells and fails with KeyError: 'wedge15' on
    # reading them (nschloe/meshio#1247, #1505): give it the dimension of every cell type accepted here
    from meshio import _mesh

    for kind in CELL_TYPES:
        _mesh.topological_dimension.setdefault(kind, 3)
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in MESH_SUFFIXES:
        raise ValueError(f"mesh file {path}: unsupported type {suffix!r}; allowed: {', '.join(MESH_SUFFIXES)}")
    if not (np.isfinite(scale) and scale > 0):
        raise ValueError(f"scale must be > 0 (file units to metres, e.g. 1e-3 for mm), got {scale}")
    said = io.StringIO()
    deck = read_deck(path) if suffix == ".inp" else None     # its *INCLUDE files inlined, its *BOUNDARY nodes
    try:
        with contextlib.redirect_stdout(said), contextlib.redirect_stderr(said), tempfile.TemporaryDirectory() as tmp:
            source = path
            if deck is not None:
                source = Path(tmp) / path.name
                source.write_text(deck.text)
            elif suffix in (".bdf", ".nas", ".fem"):         # its material cards left out (geometry.nastran)
                source = Path(tmp) / path.name
                source.write_text(without_materials(path))
            mesh = meshio.read(str(source), file_format={".bdf": "nastran", ".nas": "nastran", ".fem": "nastran",
                                                         ".inp": "abaqus"}.get(suffix))
    except (Exception, SystemExit) as exc:  # meshio raises ReadError, KeyError, ... or exits on a malformed file
        # meshio's exit code says nothing: the reason is what it printed before exiting
        text = said.getvalue() if isinstance(exc, SystemExit) else str(exc) + "\n" + said.getvalue()
        first = ([ln for ln in text.splitlines() if ln.strip()][:1] or [type(exc).__name__])[0].strip()
        kind = "meshio stopped" if isinstance(exc, SystemExit) else type(exc).__name__
        raise ValueError(f"mesh file {path} could not be read ({kind}: {first})") from None
    points = np.asarray(mesh.points, dtype=float)
    if points.ndim != 2 or points.shape[0] == 0:
        raise ValueError(f"mesh file {path} holds no nodes: is it a {suffix} mesh?")
    points = points[:, :3] * scale
    if points.shape[1] != 3:
        raise ValueError(f"mesh file {path} is not three-dimensional")
    solids = [(k, b) for k, b in enumerate(mesh.cells) if b.type.startswith(_SOLID_PREFIXES)]
    unsupported = sorted({b.type for _, b in solids if b.type not in CELL_TYPES})
    if unsupported:
        raise ValueError(f"mesh file {path}: unsupported cell type(s) {', '.join(unsupported)}; accepted: "
                         f"{', '.join(CELL_TYPES)} (meshio names)")
    if not solids:
        found = sorted({b.type for b in mesh.cells})
        raise ValueError(f"mesh file {path} holds no solid cells (found: {', '.join(found) or 'none'}); accepted: "
                         f"{', '.join(CELL_TYPES)}")
    orders = {CELL_TYPES[b.type][3] for _, b in solids}
    if len(orders) > 1:
        raise ValueError(f"mesh file {path} mixes linear and quadratic solid cells; give one order")
    blocks = [(b.type, np.asarray(b.data, dtype=np.int64)[:, :CELL_TYPES[b.type][2]]) for _, b in solids]
    points, tets, converted, parent = split_to_tetrahedra(points, blocks)
    cell_sets = _solid_cell_sets(mesh, [k for k, _ in solids], parent)
    node_sets = _node_sets(mesh)
    if deck is not None and (deck.boundary_labels or deck.boundary_sets):
        node_sets["BOUNDARY"] = _boundary_nodes(deck, node_sets, len(mesh.points))
    used = np.unique(tets)                              # drop nodes no tetrahedron uses (surface-only, orphans)
    renumber = -np.ones(len(points), dtype=np.int64)
    renumber[used] = np.arange(used.size)
    node_sets = {k: np.unique(renumber[v[(v < len(renumber))]]) for k, v in node_sets.items()}
    node_sets = {k: v[v >= 0] for k, v in node_sets.items() if np.any(v >= 0)}
    return ImportedMesh(points=points[used], tets=renumber[tets], node_sets=node_sets, converted=converted,
                        source=str(path), cell_sets=cell_sets)


def group_report(points: np.ndarray, facets: np.ndarray, what: str, name) -> str:
    """What a group caught, to be seen (an over-wide box takes more than the face meant): its boundary facets,
    nodes, area (mm^2, of the facets' corner triangles) and bounding box (mm)."""
    corners = points[facets[:, :3]]
    area = 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1).sum()
    nodes = np.unique(facets[:, :3])
    low, high = 1e3 * points[nodes].min(axis=0), 1e3 * points[nodes].max(axis=0)
    box = " x ".join(f"[{a:.4g}, {b:.4g}]" for a, b in zip(low, high))
    label = name if isinstance(name, str) else "box"
    return f"{what} {label!r}: {len(facets)} facets, {nodes.size} nodes, {1e6 * area:.4g} mm^2 in {box} mm"


def _boundary_nodes(deck: AbaqusDeck, node_sets: dict, n_points: int) -> np.ndarray:
    """The point indices a deck's *BOUNDARY blocks fix: its node labels (meshio numbers the nodes in the order they
    come) and the nodes of the sets it names."""
    if len(deck.node_labels) != n_points:
        raise ValueError(f"{deck.source}: {len(deck.node_labels)} nodes in its *NODE blocks, {n_points} read: its "
                         "*BOUNDARY nodes cannot be placed")
    index = {label: k for k, label in enumerate(deck.node_labels)}
    unknown = sorted(label for label in deck.boundary_labels if label not in index)
    if unknown:
        raise ValueError(f"{deck.source}: *BOUNDARY names node(s) {unknown[:5]} that no *NODE block defines")
    nodes = [index[label] for label in deck.boundary_labels]
    lower = {k.lower(): v for k, v in node_sets.items()}
    for name in deck.boundary_sets:
        if name.lower() not in lower:
            raise ValueError(f"{deck.source}: *BOUNDARY names the set {name!r}, which the deck does not define")
        nodes += lower[name.lower()].tolist()
    return np.unique(np.asarray(nodes, dtype=np.int64))


def _solid_cell_sets(mesh, solid_blocks: list, parent: np.ndarray) -> dict:
    """Every element set of the solid cells as the tetrahedra made of them (``parent``: each tetrahedron's solid
    cell, numbered over ``solid_blocks`` in order); sets of surface cells only are left out."""
    offsets = dict(zip(solid_blocks, np.cumsum([0] + [len(mesh.cells[k].data) for k in solid_blocks])[:-1]))
    sets = {}
    for name, per_block in mesh.cell_sets.items():
        if str(name).startswith("gmsh:"):
            continue
        cells = [offsets[k] + np.asarray(idx, dtype=np.int64).ravel() for k, idx in enumerate(per_block)
                 if k in offsets and idx is not None and len(idx)]
        if cells:
            sets[str(name)] = np.flatnonzero(np.isin(parent, np.concatenate(cells)))
    return sets


def _node_sets(mesh) -> dict:
    """Every named group of a meshio mesh as node indices: point sets as they are; cell sets (element sets, gmsh
    physical groups) as the nodes of their cells; gmsh physical tags without cell sets through field_data."""
    sets = {str(k): np.asarray(v, dtype=np.int64).ravel() for k, v in mesh.point_sets.items()}
    for name, per_block in mesh.cell_sets.items():
        if str(name).startswith("gmsh:"):               # meshio's bookkeeping, not a group
            continue
        nodes = [np.asarray(mesh.cells[k].data)[np.asarray(idx, dtype=np.int64)].ravel()
                 for k, idx in enumerate(per_block) if idx is not None and len(idx)]
        if nodes:
            sets[str(name)] = np.unique(np.concatenate([sets.get(str(name), np.zeros(0, np.int64))] + nodes))
    physical = mesh.cell_data.get("gmsh:physical")
    if physical is not None and not mesh.cell_sets:
        for name, (tag, dim) in mesh.field_data.items():
            nodes = [np.asarray(b.data)[np.asarray(p) == tag].ravel() for b, p in zip(mesh.cells, physical)]
            nodes = [n for n in nodes if n.size]
            if nodes:
                sets[str(name)] = np.unique(np.concatenate(nodes))
    return sets


def _diagonal(quad: Sequence[int], nodes: np.ndarray) -> int:
    """0 where the diagonal (q0, q2) goes through the quad's smallest global node, 1 for (q1, q3)."""
    return 0 if int(np.argmin(nodes[list(quad)])) in (0, 2) else 1


def _quad_triangles(quad: Sequence[int], diagonal: int) -> list[tuple]:
    a, b, c, d = quad
    return [(a, b, c), (a, c, d)] if diagonal == 0 else [(a, b, d), (b, c, d)]


@functools.lru_cache(maxsize=None)
def _filling(kind: str, pattern: tuple) -> tuple:
    """The fewest tetrahedra (local corner indices) filling the reference cell whose quadrilateral faces are split
    by ``pattern``: a depth-first search over tetrahedra of the corners that closes every face from the right
    side, deepened one tetrahedron at a time, checked by the volume."""
    ref = _REF[kind]
    x = np.array(ref["x"], dtype=float)
    boundary = [tuple(t) for t in ref["tris"]]
    for quad, diag in zip(ref["quads"], pattern):
        boundary += _quad_triangles(quad, diag)
    centre = x.mean(axis=0)
    faces_on_hull = [set(f) for f in ref["tris"]] + [set(q) for q in ref["quads"]]

    def side(face, apex, pts):
        a, b, c = (pts[i] for i in face)
        return np.sign(np.dot(np.cross(b - a, c - a), pts[apex] - a))

    def inward(face):
        a, b, c = (x[i] for i in face)
        return np.sign(np.dot(np.cross(b - a, c - a), centre - a))

    n = len(x)
    boundary_keys = {tuple(sorted(f)) for f in boundary}

    def search(max_tets):
        open_faces = {tuple(sorted(f)): (tuple(sorted(f)), inward(tuple(sorted(f)))) for f in boundary}
        closed: set = set()
        chosen: list = []

        def dfs():
            if not open_faces:
                return True
            if len(chosen) == max_tets:
                return False
            key, (face, need) = next(iter(open_faces.items()))
            for apex in range(n):
                if apex in face or side(face, apex, x) != need:
                    continue
                tet = tuple(sorted(face + (apex,)))
                if tet in chosen:
                    continue
                changes, ok = [], True
                for sub in itertools.combinations(tet, 3):
                    other = next(i for i in tet if i not in sub)
                    s = side(sub, other, x)
                    if sub in open_faces:
                        if open_faces[sub][1] != s:
                            ok = False
                            break
                        changes.append(("close", sub, open_faces[sub]))
                    elif sub in closed or sub in boundary_keys or any(set(sub) <= h for h in faces_on_hull):
                        ok = False                       # a closed face, or a triangle on the hull not chosen
                        break
                    else:
                        changes.append(("open", sub, (sub, -s)))
                if not ok:
                    continue
                for op, sub, val in changes:
                    if op == "close":
                        del open_faces[sub]
                        closed.add(sub)
                    else:
                        open_faces[sub] = val
                chosen.append(tet)
                if dfs():
                    return True
                chosen.pop()
                for op, sub, val in changes:
                    if op == "close":
                        closed.discard(sub)
                        open_faces[sub] = val
                    else:
                        del open_faces[sub]
            return False

        return list(chosen) if dfs() else None

    limit = {"tetra": 1, "pyramid": 2, "wedge": 3, "hexahedron": 6}[kind]
    cell = {"tetra": 1 / 6, "pyramid": 1 / 3, "wedge": 0.5, "hexahedron": 1.0}[kind]
    for k in range(1, limit + 1):
        tets = search(k)
        if tets is not None:
            vol = sum(abs(np.linalg.det(np.c_[np.ones(4), x[list(t)]])) for t in tets) / 6
            if abs(vol - cell) < 1e-12:
                return tuple(tets)
    # the smallest-node rule never gives the twisted patterns that have no filling (checked over every node order
    # in tests/fem/test_mesh_import.py); anything else reaching here is a bug
    raise AssertionError(f"no tetrahedral filling of a {kind} with face diagonals {pattern}")


def split_to_tetrahedra(points: np.ndarray, blocks: list) -> tuple[np.ndarray, np.ndarray, dict, np.ndarray]:
    """(points, tets, converted, parent): the cells of ``blocks`` [(meshio type, (m, k) nodes)] as conforming
    tetrahedra (4 or 10 nodes, VTK order), new mid-nodes appended to points; ``parent``: each tetrahedron's cell,
    numbered over the blocks in order."""
    points = [np.asarray(points, float)]
    n_points = len(points[0])
    new_nodes: dict = {}                                # key -> index of a node made here

    def new_node(key, coords):
        nonlocal n_points
        if key not in new_nodes:
            new_nodes[key] = n_points
            points.append(np.asarray(coords, float)[None])
            n_points += 1
        return new_nodes[key]

    tets, converted, parent, first = [], {}, [], 0
    x0 = points[0]
    for kind_name, cells in blocks:
        kind, n_corner, _, quadratic = CELL_TYPES[kind_name]
        ref = _REF[kind]
        edge_slot = {frozenset(e): n_corner + k for k, e in enumerate(ref["edges"])}
        corners = cells[:, :n_corner]
        if np.any(np.sort(corners, axis=1)[:, 1:] == np.sort(corners, axis=1)[:, :-1]):
            bad = int(np.flatnonzero(np.any(np.diff(np.sort(corners, axis=1), axis=1) == 0, axis=1))[0])
            raise ValueError(f"{kind_name} cell {bad} repeats a corner node (collapsed cells are not accepted)")
        patterns = np.array([[_diagonal(q, c) for q in ref["quads"]] for c in corners], dtype=np.int64) \
            if ref["quads"] else np.zeros((len(cells), 0), dtype=np.int64)
        made = 0
        for cell_index, (cell, pattern) in enumerate(zip(cells, patterns)):
            filling = _filling(kind, tuple(pattern.tolist()))
            glob = list(cell[:n_corner])
            for tet in filling:
                row = [glob[i] for i in tet]
                if quadratic:
                    for a, b in _TET_EDGES:
                        la, lb = tet[a], tet[b]
                        slot = edge_slot.get(frozenset((la, lb)))
                        if slot is not None:
                            row.append(int(cell[slot]))
                        else:
                            row.append(_mid_node(kind, cell_index, cell, la, lb, edge_slot, x0, new_node))
                tets.append(row)
                parent.append(first + cell_index)
            made += len(filling)
        first += len(cells)
        converted[kind_name] = (converted.get(kind_name, (0, 0))[0] + len(cells),
                                converted.get(kind_name, (0, 0))[1] + made)
    tets = np.array(tets, dtype=np.int64)
    return np.vstack(points), tets, converted, np.asarray(parent, dtype=np.int64)


def _mid_node(kind, cell_index, cell, la, lb, edge_slot, x0, new_node) -> int:
    """The mid-node of a new edge (la, lb) of a quadratic cell: a face diagonal's (the serendipity face centre,
    shared with the neighbour through the diagonal's global corners) or a hexahedron's body diagonal's (its centre,
    the serendipity map at the reference centre: -1/4 of the corners plus 1/4 of the mid-edge nodes)."""
    for quad in _REF[kind]["quads"]:
        if la in quad and lb in quad:                  # a diagonal of this quadrilateral face
            mids = [edge_slot[frozenset((quad[k], quad[(k + 1) % 4]))] for k in range(4)]
            centre = -0.25 * x0[cell[list(quad)]].sum(axis=0) + 0.5 * x0[cell[mids]].sum(axis=0)
            return new_node(("face", frozenset((int(cell[la]), int(cell[lb])))), centre)
    if kind != "hexahedron":
        raise AssertionError(f"edge ({la}, {lb}) of a {kind} is neither an edge nor a face diagonal")
    centre = -0.25 * x0[cell[:8]].sum(axis=0) + 0.25 * x0[cell[8:20]].sum(axis=0)
    return new_node(("body", cell_index), centre)


def _boundary(tets: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(corner facets (f, 3), their tetrahedra (f,), the face of each in its tetrahedron (f,)) of the boundary."""
    faces = np.array([[t[i] for i in f] for t in tets[:, :4] for f in _TET_FACES]).reshape(len(tets), 4, 3)
    keys = np.sort(faces.reshape(-1, 3), axis=1)
    _, first, counts = np.unique(keys, axis=0, return_index=True, return_counts=True)
    once = first[counts == 1]
    return faces.reshape(-1, 3)[once], once // 4, once % 4


def outward_normals(points: np.ndarray, tets: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(corner facets (f, 3), outward unit normals (f, 3), areas (f,)) of the boundary facets of ``tets``: each
    normal points away from the fourth node of the facet's tetrahedron."""
    corners, tet_of, face_of = _boundary(tets)
    a, b, c = (points[corners[:, k]] for k in range(3))
    n = np.cross(b - a, c - a)
    apex = points[tets[tet_of, 6 - np.array(_TET_FACES).sum(axis=1)[face_of]]]
    n *= np.where(np.einsum("ij,ij->i", n, apex - a) > 0, -1.0, 1.0)[:, None]
    area = 0.5 * np.linalg.norm(n, axis=1)
    return corners, n / np.maximum(2 * area, np.finfo(float).tiny)[:, None], area


#: the widest angle between a box clamp's facets and their mean normal that still makes one face (a root on a
#: hub cone turns by the blade's angular extent, ~11 deg on rotor 37); past it the box has caught another face
ONE_FACE_DEG = 30.0
#: the widest angle between a contact node's tip facet and the outward radial direction (rotor 37's tip cone
#: is tilted 15.3 deg from radial)
TIP_FACING_DEG = 45.0


def check_box_face(normals: np.ndarray, areas: np.ndarray, what: str, box, share: float = 0.02) -> None:
    """Refuse a group given as a box whose boundary facets are not one face: more than ``share`` of their area
    faces more than ``ONE_FACE_DEG`` away from their area-weighted mean normal (a root box that also caught the
    blade's flanks over-clamps it: +7.5 % on f1 of a third-party blade)."""
    mean = (areas[:, None] * normals).sum(axis=0)
    mean /= max(np.linalg.norm(mean), np.finfo(float).tiny)
    off = areas[normals @ mean < np.cos(np.radians(ONE_FACE_DEG))].sum() / areas.sum()
    if off > share:
        raise ValueError(f"{what}: the box {tuple(float(v) for v in box)} m catches {1e6 * areas.sum():.4g} mm^2 of "
                         f"boundary facets, {100 * off:.0f} % of them facing more than {ONE_FACE_DEG:g} deg away "
                         f"from the rest (the blade's flanks or another face): a box selects one face; draw it "
                         f"around that face only, or name a node set of the file")


def check_contact_on_tip(points: np.ndarray, facets: np.ndarray, normals: np.ndarray, nodes: np.ndarray,
                         what: str) -> None:
    """Refuse contact nodes that are not on the blade's tip: each must be a node of a boundary facet facing outwards
    within ``TIP_FACING_DEG`` of the radial direction (the largest radius, where the casing is), not on the flanks
    (a tip box reaching down the flanks moves the nodes chosen along the 'camber line' there)."""
    centre = points[facets[:, :3]].mean(axis=1)
    radial = centre[:, :2] / np.maximum(np.linalg.norm(centre[:, :2], axis=1), np.finfo(float).tiny)[:, None]
    facing = np.einsum("ij,ij->i", normals[:, :2], radial) >= np.cos(np.radians(TIP_FACING_DEG))
    off = np.flatnonzero(~np.isin(nodes, facets[facing]))
    if off.size:
        radius = np.hypot(points[nodes[off], 0], points[nodes[off], 1])
        raise ValueError(f"{what}: contact nodes {off.tolist()} (of {nodes.size}, LE -> TE; r = "
                         f"{', '.join(f'{1e3 * r:.2f}' for r in radius)} mm) lie on no boundary facet facing "
                         f"outwards within {TIP_FACING_DEG:g} deg of radial about +z: they are not on the tip (a tip "
                         f"group or box that reaches down the flanks? or a rotation axis other than the file's +z: "
                         f"axis=); give the tip face only")


def boundary_facets(tets: np.ndarray) -> np.ndarray:
    """(f, 3) or (f, 6) boundary facets (faces of one tetrahedron only), VTK triangle order."""
    corners, tet_of, face_of = _boundary(tets)
    if tets.shape[1] == 4:
        return corners
    edge_slot = {frozenset(e): 4 + k for k, e in enumerate(_TET_EDGES)}
    out = []
    for t, f in zip(tet_of, face_of):
        a, b, c = _TET_FACES[f]
        out.append([tets[t, a], tets[t, b], tets[t, c], tets[t, edge_slot[frozenset((a, b))]],
                    tets[t, edge_slot[frozenset((b, c))]], tets[t, edge_slot[frozenset((c, a))]]])
    return np.array(out, dtype=np.int64).reshape(-1, 6)


def order_le_to_te(points: np.ndarray, reference: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(order, chord coordinate): points sorted from the leading to the trailing edge along the chord, the principal
    direction of ``reference`` (the tip nodes; default the points), oriented downstream (+z: the flow's direction in
    the project's frame, so the LE is the upstream end)."""
    reference = points if reference is None else reference
    centre = reference.mean(axis=0)
    _, _, vt = np.linalg.svd(reference - centre, full_matrices=False)
    chord = vt[0] if vt[0][2] >= 0 else -vt[0]
    s = (points - centre) @ chord
    return np.argsort(s, kind="stable"), s


def select_contact_nodes(points: np.ndarray, tip: np.ndarray, contact) -> tuple[np.ndarray, str]:
    """Contact nodes as the user chooses, ordered LE -> TE: (node indices, one-line description).

    Args:
        points: (n, 3) node coordinates.
        tip: node indices of the tip group (for ``contact`` as a count).
        contact: an int N (N nodes along the tip's camber line: LE and TE the chord's ends, the others the tip nodes
            nearest to mid-thickness at evenly spaced chord stations), an (n, 3) array of coordinates (the nearest
            nodes), or a 1-D sequence of node indices (0-based, in the file's node order).
    """
    tip = np.asarray(tip, dtype=np.int64)
    if isinstance(contact, (int, np.integer)):
        n = int(contact)
        if tip.size == 0:
            raise ValueError("contact: a number of nodes along the tip camber line needs the tip group (tip=...)")
        if not 2 <= n <= min(40, tip.size):
            raise ValueError(f"contact must be in [2, {min(40, tip.size)}] nodes along the tip camber line "
                             f"(the tip group has {tip.size} nodes), got {n}")
        x = points[tip]
        _, s = order_le_to_te(x)
        centre = x.mean(axis=0)
        _, _, vt = np.linalg.svd(x - centre, full_matrices=False)
        t = (x - centre) @ vt[1]                       # across the chord, in the tip's plane: thickness
        stations = np.linspace(s.min(), s.max(), n)
        half = 0.5 * (stations[1] - stations[0])
        chosen = [int(np.argmin(s)), int(np.argmax(s))]
        for st in stations[1:-1]:
            near = np.flatnonzero(np.abs(s - st) <= half)
            mid = 0.5 * (t[near].min() + t[near].max())
            dist = np.hypot(s[near] - st, t[near] - mid)
            free = [k for k in near[np.argsort(dist)] if k not in chosen]
            if not free:
                raise ValueError(f"contact: the tip has too few nodes for {n} nodes along its camber line")
            chosen.insert(-1, int(free[0]))
        nodes = tip[chosen]
        how = f"{n} nodes along the tip camber line"
    else:
        arr = np.asarray(contact)
        if arr.ndim == 2 and arr.shape[1] == 3 and arr.dtype.kind == "f":
            from scipy.spatial import cKDTree

            dist, nodes = cKDTree(points).query(arr.astype(float))
            size = float(np.ptp(points, axis=0).max())
            if dist.max() > 0.02 * size:
                k = int(np.argmax(dist))
                raise ValueError(f"contact point {k} is {dist[k]:.3g} m from the nearest node (more than 2 % of the "
                                 f"model's size {size:.3g} m): check the units of the points")
            how = f"{len(nodes)} nodes nearest to the given points (up to {dist.max():.2g} m away)"
        elif arr.ndim == 1 and arr.dtype.kind in "iu":
            nodes = arr.astype(np.int64)
            if nodes.size and (nodes.min() < 0 or nodes.max() >= len(points)):
                raise ValueError(f"contact node indices must be in [0, {len(points)}) (0-based, file order), "
                                 f"got {nodes.min()} ... {nodes.max()}")
            how = f"{nodes.size} given nodes"
        else:
            raise ValueError("contact must be a number of nodes along the tip camber line, an (n, 3) array of "
                             "coordinates, a 1-D sequence of node indices or a group name")
    nodes = np.asarray(nodes, dtype=np.int64)
    if nodes.size < 1 or len(np.unique(nodes)) != nodes.size:
        raise ValueError(f"contact nodes must be distinct and at least one; got {nodes.size} nodes with "
                         f"{len(np.unique(nodes))} distinct")
    reference = points[tip] if tip.size >= 3 else points[nodes]
    order, _ = order_le_to_te(points[nodes], reference if len(reference) >= 2 else None)
    return nodes[order], how


def add_to_gmsh(mesh: ImportedMesh, facet_groups: dict, volume_tag: int, volume_name: str = "blade",
                parts: dict | None = None) -> None:
    """Write the tetrahedra into the current gmsh model as discrete volumes, and each facet group {(tag, name):
    facets} as a discrete surface with its physical group. ``parts`` {(tag, name): tetrahedron indices} splits the
    volume into physical groups (e.g. a bladed-disk sector's 'blade' and 'disk'; every tetrahedron in exactly one);
    None: one physical volume ``volume_tag`` named ``volume_name``."""
    import gmsh

    quadratic = mesh.quadratic
    if parts is None:
        parts = {(volume_tag, volume_name): np.arange(len(mesh.tets))}
    tags = np.arange(1, len(mesh.points) + 1)
    cells = mesh.tets[:, _GMSH_TET10] if quadratic else mesh.tets
    next_tag = 1
    for k, ((tag, name), tets) in enumerate(parts.items()):
        vol = gmsh.model.addDiscreteEntity(3)
        if k == 0:                                       # the nodes live on the first volume; the others share them
            gmsh.model.mesh.addNodes(3, vol, tags.tolist(), mesh.points.ravel().tolist())
        tets = np.asarray(tets, dtype=np.int64)
        gmsh.model.mesh.addElementsByType(vol, 11 if quadratic else 4,
                                          np.arange(next_tag, next_tag + tets.size).tolist(),
                                          (cells[tets] + 1).ravel().tolist())
        next_tag += tets.size
        gmsh.model.addPhysicalGroup(3, [vol], tag)
        gmsh.model.setPhysicalName(3, tag, name)
    for (tag, name), facets in facet_groups.items():
        surf = gmsh.model.addDiscreteEntity(2)
        gmsh.model.mesh.addElementsByType(surf, 9 if quadratic else 2,
                                          np.arange(next_tag, next_tag + len(facets)).tolist(),
                                          (np.asarray(facets) + 1).ravel().tolist())
        next_tag += len(facets)
        gmsh.model.addPhysicalGroup(2, [surf], tag)
        gmsh.model.setPhysicalName(2, tag, name)
