"""gmsh OpenCASCADE models of the rotor 37 blade: loft, named groups, tip contact nodes and mesh presets.

Only gmsh and NumPy are used. Functions build into the current gmsh model (``gmsh.model``); wrap calls in
:func:`gmsh_session` to get an initialised, quiet gmsh that is finalised afterwards.

Coordinates are SI (m): z axial (downstream), x = r cos(theta), y = r sin(theta).
"""
from __future__ import annotations

import contextlib
import dataclasses
import itertools
import enum
import os
from pathlib import Path
from typing import Iterator, Sequence

import numpy as np

from rotor37_rom.checks import readable_file
from .parametric import N_TABLE_SECTIONS, BladeLaw, default_blade_law
from .tables import BladeTable

__all__ = [
    "BladeGroup",
    "MeshPreset",
    "MESH_PRESETS",
    "get_mesh_preset",
    "BladeModel",
    "gmsh_session",
    "add_blade_from_sections",
    "table_sections",
    "law_sections",
    "blade_sections",
    "create_blade_model",
    "import_blade_model",
    "embed_tip_nodes",
    "N_TIP_NODES",
]

N_TIP_NODES = 8


class BladeGroup(enum.IntEnum):
    """Physical-group tags shared by every gmsh model of the project (names are the lower-case member names)."""

    BLADE = 1      # the volume
    CLAMP = 2      # root face (blade) or bore face (sector): u = 0
    TIP = 3        # blade tip face
    PRESSURE = 4   # pressure side (THETA2, lower theta)
    SUCTION = 5    # suction side (THETA1, higher theta)
    LEFT = 6       # cyclic face at lower theta (disk sector)
    RIGHT = 7      # cyclic face at higher theta (disk sector)
    TIP_NODES = 8  # the contact nodes on the tip, LE to TE (points)
    LEADING_EDGE = 9   # narrow blunt-edge strips at the LE
    TRAILING_EDGE = 10  # and at the TE


@dataclasses.dataclass(frozen=True)
class MeshPreset:
    """Mesh resolution.

    Attributes:
        name: preset name.
        size: target element size (m).
        curvature_points: elements per 2*pi of curvature (refines the rounded LE/TE); 0 switches it off.
        min_size: smallest element size (m).
    """

    name: str
    size: float
    curvature_points: int
    min_size: float


MESH_PRESETS = {
    "ci": MeshPreset("ci", size=12.0e-3, curvature_points=0, min_size=2.0e-3),
    "coarse": MeshPreset("coarse", size=6.0e-3, curvature_points=0, min_size=0.9e-3),
    "paper": MeshPreset("paper", size=3.0e-3, curvature_points=0, min_size=0.6e-3),
}


def get_mesh_preset(preset: str | MeshPreset) -> MeshPreset:
    """Return a preset by name (one of MESH_PRESETS) or validate a custom one."""
    if isinstance(preset, MeshPreset):
        if not (1e-5 < preset.size < 0.1) or not (0 < preset.min_size <= preset.size):
            raise ValueError(f"mesh preset {preset.name!r}: size must be in (1e-5, 0.1) m and 0 < min_size <= size")
        return preset
    if preset not in MESH_PRESETS:
        raise ValueError(f"unknown mesh preset {preset!r}; allowed: {', '.join(MESH_PRESETS)}")
    return MESH_PRESETS[preset]


@dataclasses.dataclass(frozen=True)
class BladeModel:
    """What the builder reports about the gmsh model it made (the mesh itself stays in gmsh).

    Attributes:
        source: 'parametric', 'table:<path>' or 'file:<path>'.
        volume: blade volume (m^3) from the CAD solid.
        tip_nodes: coordinates (n_tip, 3) of the tip contact nodes, LE first, TE last (m).
        preset: the mesh preset used.
        n_nodes: mesh nodes (order-1 mesh).
        summary: one line on what was read or meshed (imported files), with the bounding box.
        n_sectors: N for a cyclic sector read from a file (its 'left' and 'right' faces paired by ``fem``), else 0.
    """

    source: str
    volume: float
    tip_nodes: np.ndarray
    preset: MeshPreset
    n_nodes: int
    summary: str = ""
    n_sectors: int = 0


_SESSION_DEPTH = [0]


@contextlib.contextmanager
def gmsh_session(verbose: bool = False) -> Iterator[object]:
    """Initialise gmsh (quiet unless verbose), yield the module, finalise at exit (also on errors); nests."""
    import gmsh

    if _SESSION_DEPTH[0] == 0:
        gmsh.initialize([], readConfigFiles=False)
    _SESSION_DEPTH[0] += 1
    gmsh.option.setNumber("General.Terminal", 1 if verbose else 0)
    gmsh.option.setNumber("General.Verbosity", 5 if verbose else 1)
    try:
        yield gmsh
    finally:
        _SESSION_DEPTH[0] -= 1
        if _SESSION_DEPTH[0] == 0:
            gmsh.finalize()


def table_sections(table: BladeTable) -> list[tuple[np.ndarray, np.ndarray]]:
    """(suction, pressure) point arrays of Table IV sections 1-12 (the exact loft input)."""
    return [(table.side_points(k, "suction"), table.side_points(k, "pressure")) for k in range(N_TABLE_SECTIONS)]


def law_sections(law: BladeLaw, n_sections: int = N_TABLE_SECTIONS, n_points: int = 80,
                 ) -> list[tuple[np.ndarray, np.ndarray]]:
    """(suction, pressure) point arrays of the parametric blade at n_sections span fractions from root to tip."""
    etas = np.linspace(0.0, 1.0, n_sections)
    return [(law.side_points(eta, "suction", n_points), law.side_points(eta, "pressure", n_points)) for eta in etas]


EDGE_TRIM = 1.0e-4  # m of arc trimmed from each side at LE and TE (blunt edges; see add_blade_from_sections)


def _trim_side(points: np.ndarray, depth: float) -> np.ndarray:
    """Cut ``depth`` of arc length off both ends of a polyline (linear interpolation at the new ends)."""
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))])
    if arc[-1] <= 4 * depth:
        raise ValueError(f"section side of length {arc[-1]:.3g} m is too short for an edge trim of {depth:g} m")
    keep = (arc > depth) & (arc < arc[-1] - depth)
    ends = [np.array([np.interp(t, arc, points[:, k]) for k in range(3)]) for t in (depth, arc[-1] - depth)]
    return np.vstack([ends[0], points[keep], ends[1]])


def add_blade_from_sections(sections: Sequence[tuple[np.ndarray, np.ndarray]], edge_trim: float = EDGE_TRIM) -> int:
    """Loft the blade in gmsh OCC and return the volume tag.

    Each section (suction and pressure points, LE to TE, sharing the LE and TE points) becomes a closed wire: two
    side splines trimmed by ``edge_trim`` of arc at LE and TE, closed there by two straight segments that meet at
    the LE (TE) mid-point, a geometry vertex. The rounded noses of rotor 37 (radius ~0.1 mm) would otherwise force
    elements of that size; the trim moves the surface by less than ``edge_trim``. The side surfaces are lofted
    through the wires, the root and tip wires are closed by filling surfaces, and the shell is sewn into a volume
    (a solid loft of conical sections is fragile in OCC).
    """
    import gmsh

    occ = gmsh.model.occ
    if len(sections) < 2:
        raise ValueError(f"sections: need at least 2 blade sections, got {len(sections)}")
    if not (0.0 < edge_trim < 1e-3):
        raise ValueError(f"edge_trim must be in (0, 1e-3) m, got {edge_trim}")
    wires, end_loops = [], []
    for k, (suction, pressure) in enumerate(sections):
        if suction.shape != pressure.shape or suction.shape[0] < 4:
            raise ValueError(f"sections[{k}]: suction and pressure need the same shape with >= 4 points")
        le_mid, te_mid = occ.addPoint(*suction[0]), occ.addPoint(*suction[-1])
        suction, pressure = _trim_side(suction, edge_trim), _trim_side(pressure, edge_trim)
        s_tags = [occ.addPoint(*p) for p in suction]
        p_tags = [occ.addPoint(*p) for p in pressure[::-1]]
        curves = [occ.addSpline(s_tags), occ.addLine(s_tags[-1], te_mid), occ.addLine(te_mid, p_tags[0]),
                  occ.addSpline(p_tags), occ.addLine(p_tags[-1], le_mid), occ.addLine(le_mid, s_tags[0])]
        wires.append(occ.addWire(curves))
        if k in (0, len(sections) - 1):
            end_loops.append(occ.addCurveLoop(curves))
    sides = occ.addThruSections(wires, makeSolid=False, makeRuled=False)
    caps = [occ.addSurfaceFilling(loop) for loop in end_loops]
    originals = [tag for dim, tag in sides if dim == 2] + caps
    shell = occ.addSurfaceLoop(originals, sewing=True)
    volume = occ.addVolume([shell])
    occ.synchronize()
    # sewing builds new faces; drop the free originals and construction curves so only the volume is meshed
    kept = {tag for dim, tag in gmsh.model.getBoundary([(3, volume)], oriented=False)}
    occ.remove([(2, tag) for tag in originals if tag not in kept], recursive=True)
    occ.synchronize()
    used = {t for d, t in gmsh.model.getBoundary([(3, volume)], combined=False, oriented=False, recursive=True)}
    occ.remove([(d, t) for d, t in gmsh.model.getEntities(1) + gmsh.model.getEntities(0) if t not in used
                and not gmsh.model.getAdjacencies(d, t)[0].size], recursive=False)
    occ.synchronize()
    return volume


def _polar_theta(points: np.ndarray) -> np.ndarray:
    return np.arctan2(points[..., 1], points[..., 0])


def _classify_blade_faces(volume: int) -> dict[BladeGroup, list[int]]:
    """Find root, tip, pressure and suction faces geometrically (never by entity number)."""
    import gmsh

    faces = [tag for dim, tag in gmsh.model.getBoundary([(3, volume)], oriented=False) if dim == 2]
    centres = np.array([gmsh.model.occ.getCenterOfMass(2, f) for f in faces])
    radius = np.hypot(centres[:, 0], centres[:, 1])
    root = faces[int(np.argmin(radius))]
    tip = faces[int(np.argmax(radius))]
    areas = np.array([gmsh.model.occ.getMass(2, f) for f in faces])
    others = [k for k, f in enumerate(faces) if f not in (root, tip)]
    big = max(areas[others])
    sides = [faces[k] for k in others if areas[k] > 0.05 * big]
    strips = [k for k in others if areas[k] <= 0.05 * big]
    if len(sides) < 2:
        raise ValueError("blade model has fewer than two side faces")
    # project the centre of every side face onto all side faces; the face seen at the larger theta is suction
    groups: dict[BladeGroup, list[int]] = {BladeGroup.CLAMP: [root], BladeGroup.TIP: [tip],
                                           BladeGroup.PRESSURE: [], BladeGroup.SUCTION: [],
                                           BladeGroup.LEADING_EDGE: [], BladeGroup.TRAILING_EDGE: []}
    if strips:
        z_mid = np.median(centres[strips, 2])
        for k in strips:
            groups[BladeGroup.LEADING_EDGE if centres[k, 2] < z_mid else BladeGroup.TRAILING_EDGE].append(faces[k])
    for face, centre in zip(faces, centres):
        if face not in sides:
            continue
        own = np.array(gmsh.model.getClosestPoint(2, face, centre.tolist())[0])
        others = [np.array(gmsh.model.getClosestPoint(2, g, centre.tolist())[0]) for g in sides if g != face]
        opposite = min(others, key=lambda p: np.linalg.norm(p - own)) if others else own
        suction = _polar_theta(own) > _polar_theta(opposite)
        groups[BladeGroup.SUCTION if suction else BladeGroup.PRESSURE].append(face)
    return groups


def _tip_camber_points(tip_face: int, le: np.ndarray, te: np.ndarray, sections, n_nodes: int) -> np.ndarray:
    """n_nodes points on the tip face along the tip camber line, evenly spaced in arc length, LE and TE included."""
    import gmsh

    suction, pressure = sections[-1]
    # camber line of the tip section: mid-points between the two sides at matching chordwise stations
    mid = 0.5 * (suction + pressure)
    mid[0], mid[-1] = le, te
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(mid, axis=0), axis=1))])
    targets = np.linspace(0.0, arc[-1], n_nodes)
    points = np.column_stack([np.interp(targets, arc, mid[:, k]) for k in range(3)])
    projected = np.array(gmsh.model.getClosestPoint(2, tip_face, points[1:-1].ravel().tolist())[0]).reshape(-1, 3)
    return np.vstack([le, projected, te])


def embed_tip_nodes(tip_face: int, tip_points: np.ndarray) -> list[int]:
    """Point entities at the contact nodes, embedded in the tip face so that they become mesh vertices; LE and TE,
    vertices of the tip face already, are reused. Returns their tags in the order of ``tip_points``."""
    import gmsh

    vertices = [t for d, t in gmsh.model.getBoundary([(2, tip_face)], recursive=True) if d == 0]
    vcoords = np.array([gmsh.model.getValue(0, v, []) for v in vertices])
    tags = []
    for k, p in enumerate(tip_points):            # a handful of contact nodes
        dist = np.linalg.norm(vcoords - p, axis=1)
        if k in (0, len(tip_points) - 1) and dist.min() < 1e-9:
            tags.append(vertices[int(np.argmin(dist))])
        else:
            tags.append(gmsh.model.occ.addPoint(*p))
    gmsh.model.occ.synchronize()
    gmsh.model.mesh.embed(0, [t for t in tags if t not in vertices], 2, tip_face)
    return tags


def _apply_mesh_preset(preset: MeshPreset, edge_curves: Sequence[int] = ()) -> None:
    """Global size options; with edge_curves (the thin LE/TE), a distance field grades the size from min_size there
    to size at a distance of 4*size, so that the two sides of a thin edge never see overlapping triangles."""
    import gmsh

    if edge_curves:
        field = gmsh.model.mesh.field
        dist = field.add("Distance")
        field.setNumbers(dist, "CurvesList",
                         list(edge_curves))
        field.setNumber(dist, "NumPointsPerCurve", 200)
        ramp = field.add("Threshold")
        field.setNumber(ramp, "InField", dist)
        field.setNumber(ramp, "SizeMin", preset.min_size)
        field.setNumber(ramp, "SizeMax", preset.size)
        field.setNumber(ramp, "DistMin", 0.0)
        field.setNumber(ramp, "DistMax", 4.0 * preset.size)
        field.setAsBackgroundMesh(ramp)
        gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)

    gmsh.option.setNumber("Mesh.MeshSizeMax", preset.size)
    gmsh.option.setNumber("Mesh.MeshSizeMin", preset.min_size)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", preset.curvature_points)
    gmsh.option.setNumber("Mesh.Algorithm", 6)
    gmsh.option.setNumber("Mesh.Algorithm3D", 1)
    gmsh.option.setNumber("Mesh.Optimize", 1)
    gmsh.option.setNumber("Mesh.ElementOrder", 1)


def _edge_curves(groups: dict[BladeGroup, list[int]]) -> list[int]:
    """Spanwise curves of the blunt LE and TE strips."""
    import gmsh

    faces = groups.get(BladeGroup.LEADING_EDGE, []) + groups.get(BladeGroup.TRAILING_EDGE, [])
    return sorted({t for f in faces for d, t in gmsh.model.getBoundary([(2, f)], oriented=False) if d == 1})


def _tag_and_mesh(volume: int, groups: dict[BladeGroup, list[int]], tip_points: np.ndarray | None,
                  tip_face: int | None, preset: MeshPreset) -> np.ndarray:
    """Add physical groups, embed the tip nodes, mesh; returns the mesh coordinates of the tip nodes."""
    import gmsh

    gmsh.model.addPhysicalGroup(3, [volume], BladeGroup.BLADE)
    gmsh.model.setPhysicalName(3, BladeGroup.BLADE, BladeGroup.BLADE.name.lower())
    for group, faces in groups.items():
        if faces:
            gmsh.model.addPhysicalGroup(2, faces, group)
            gmsh.model.setPhysicalName(2, group, group.name.lower())
    point_tags = []
    if tip_points is not None:
        point_tags = embed_tip_nodes(tip_face, tip_points)
        gmsh.model.addPhysicalGroup(0, point_tags, BladeGroup.TIP_NODES)
        gmsh.model.setPhysicalName(0, BladeGroup.TIP_NODES, BladeGroup.TIP_NODES.name.lower())
    _apply_mesh_preset(preset, _edge_curves(groups))
    gmsh.model.mesh.generate(3)
    if tip_points is None:
        return np.zeros((0, 3))
    return np.array([gmsh.model.mesh.getNodes(0, t)[1] for t in point_tags]).reshape(-1, 3)


def blade_sections(table: BladeTable | None, law: BladeLaw | None = None, shorten: float = 0.0,
                   root_depth: float = 0.0) -> tuple[list, str]:
    """The sections to loft, from ``root_depth`` (m) below the root (into a disk's rim) to the tip shortened by
    ``shorten`` (m, at the LE; the tip section sits at span fraction 1 - shorten / LE span), and the source name.

    Parametric blade: N_TABLE_SECTIONS + (1 if root_depth) sections of the law, evenly spaced in span fraction (the
    law is smooth, so it is evaluated slightly outside [0, 1] below the root). Table IV: its sections 1-12 as read,
    the part above the shortened tip replaced by a section interpolated point by point between its neighbours, and
    below the root a section extrapolated from sections 1 and 2."""
    if table is None:
        law = law or default_blade_law()
        span_le = float(np.diff(law.evaluate(0.0, np.array([0.0, 1.0]))[1])[0])
        count = N_TABLE_SECTIONS + (1 if root_depth else 0)
        etas = np.linspace(-root_depth / span_le, 1.0 - shorten / span_le, count)
        source = "parametric" if not shorten else f"parametric(shorten={shorten:g})"
        return [(law.side_points(e, "suction"), law.side_points(e, "pressure")) for e in etas], source
    sections = table_sections(table)
    radius = lambda side: np.hypot(side[0, 0], side[0, 1])          # noqa: E731  (LE radius of a side)
    span = np.array([radius(s) - radius(sections[0][0]) for s, _ in sections])
    top = span[-1] - shorten
    k = min(int(np.searchsorted(span, top)) - 1, len(span) - 2)       # the tip lies between sections k and k + 1
    t = (top - span[k]) / (span[k + 1] - span[k])
    tip = tuple((1 - t) * a + t * b for a, b in zip(sections[k], sections[k + 1]))
    kept = list(sections[:k + 1]) + [tip]
    if root_depth:
        below = root_depth / (span[1] - span[0])
        kept = [tuple(a[0] + below * (a[0] - a[1]) for a in zip(sections[0], sections[1]))] + kept
    source = f"table:{table.source}" + (f"(shorten={shorten:g})" if shorten else "")
    return kept, source


def create_blade_model(table: BladeTable | None = None, preset: str | MeshPreset = "coarse",
                       law: BladeLaw | None = None, n_tip_nodes: int = N_TIP_NODES,
                       shorten: float = 0.0) -> BladeModel:
    """Build and mesh the rotor 37 blade in the current gmsh model.

    Args:
        table: NASA Table IV; if given, the exact loft of sections 1-12 is used, else the parametric blade.
        preset: mesh preset name ('ci', 'coarse', 'paper') or a MeshPreset.
        law: parametric law (default: the built-in one); ignored when a table is given.
        n_tip_nodes: contact nodes on the tip camber line, LE to TE inclusive (2..40).
        shorten: radial length (m) removed at the tip, 0 <= shorten < 20 mm (the paper shortens the disk's
            blades by 4 mm): ``blade_sections``.
    """
    import gmsh

    preset = get_mesh_preset(preset)
    if not (2 <= int(n_tip_nodes) <= 40):
        raise ValueError(f"n_tip_nodes must be in [2, 40], got {n_tip_nodes}")
    if not (0.0 <= shorten < 0.02):
        raise ValueError(f"shorten must be in [0, 0.02) m, got {shorten}")
    if table is not None and table.n_sections < N_TABLE_SECTIONS:
        raise ValueError(f"blade table {table.source} has {table.n_sections} sections, needs >= {N_TABLE_SECTIONS}")
    sections, source = blade_sections(table, law, shorten)
    gmsh.model.add("blade")
    volume = add_blade_from_sections(sections)
    groups = _classify_blade_faces(volume)
    tip_face = groups[BladeGroup.TIP][0]
    le, te = sections[-1][0][0], sections[-1][0][-1]
    tip_points = _tip_camber_points(tip_face, le, te, sections, int(n_tip_nodes))
    tip_mesh = _tag_and_mesh(volume, groups, tip_points, tip_face, preset)
    return BladeModel(source=source, volume=gmsh.model.occ.getMass(3, volume), tip_nodes=tip_mesh,
                      preset=preset, n_nodes=len(gmsh.model.mesh.getNodes()[0]))


def _faces_in_box(box: Sequence[float], what: str, path: Path) -> list[int]:
    import gmsh

    if len(box) != 6:
        raise ValueError(f"{what} box must be (xmin, ymin, zmin, xmax, ymax, zmax), got {box!r}")
    faces = [t for d, t in gmsh.model.getEntitiesInBoundingBox(*box, dim=2)]
    if not faces:
        raise ValueError(f"{what}: no surface of {path} lies inside the box {tuple(box)}")
    return faces


def _scale_for(scale: float, units: str | None) -> float:
    from .mesh_import import UNITS

    if units is not None:
        if units not in UNITS:
            raise ValueError(f"units must be one of {', '.join(UNITS)}, got {units!r}")
        if scale != 1.0 and scale != UNITS[units]:
            raise ValueError(f"scale = {scale} and units = {units!r} disagree: give one of them")
        scale = UNITS[units]
    if not (np.isfinite(scale) and scale > 0):
        raise ValueError(f"scale must be > 0 (file units to metres, e.g. 1e-3 for mm), got {scale}")
    return float(scale)


def import_blade_model(path: str | os.PathLike, clamp: str | Sequence[float], tip: str | Sequence[float] | None = None,
                       preset: str | MeshPreset = "coarse", scale: float = 1.0, units: str | None = None,
                       contact=None, cyclic=None, blade: str | None = None, axis: str = "+z") -> BladeModel:
    """Load a user's blade into the current gmsh model: a CAD file (STEP, BREP: meshed with the preset) or a mesh
    from another FE code (gmsh .msh, Abaqus/CalculiX .inp, NASTRAN .bdf/.nas, VTK .vtk/.vtu; wedges, hexahedra and
    pyramids are split into conforming tetrahedra, see geometry.mesh_import).

    Args:
        path: the file.
        clamp: the name of any group of a mesh file (node set, element set, physical group), or a box
            (xmin, ymin, zmin, xmax, ymax, zmax) in metres (after scaling) enclosing the clamped faces (CAD: only a
            box; formats without groups, such as .bdf or .vtu as meshio reads them: a box).
        tip: the tip, given the same way (optional).
        cyclic: (left, right, N) of a cyclic sector in a mesh file: its two cyclic faces given the same way (groups
            'left' and 'right' of the model) and the number of sectors; None: not cyclic.
        blade: of a cyclic sector, the element set of its blade's solid cells: the model's volumes are then 'blade'
            and 'disk' (the rest), as the built-in bladed-disk sector's (which the SAFE diagram's labels and the
            blade clamped on the disk use); None: one volume 'blade'.
        preset: mesh preset for CAD files.
        scale: factor from file units to metres (e.g. 1e-3 for mm), applied to every kind of input.
        units: 'm', 'mm', 'cm' or 'in' instead of scale.
        contact: the contact nodes, always ordered LE -> TE along the tip chord: a number N (N nodes along the tip
            camber line; default 8 when a tip is given), a group name, an (n, 3) array of coordinates (m, after
            scaling; the nearest nodes) or a 1-D sequence of node indices (0-based, the mesh file's node order).
    """
    import gmsh

    from . import mesh_import

    path = Path(path)
    readable_file("blade file", path)
    suffix = path.suffix.lower()
    cad = (".step", ".stp", ".brep")
    if suffix not in cad + mesh_import.MESH_SUFFIXES:
        raise ValueError(f"blade file {path}: unsupported type {suffix!r}; allowed: "
                         f"{', '.join(cad + mesh_import.MESH_SUFFIXES)}")
    scale = _scale_for(scale, units)
    preset = get_mesh_preset(preset)
    if contact is None and tip is not None:
        contact = N_TIP_NODES
    if contact is not None and tip is None and isinstance(contact, (int, np.integer)):
        raise ValueError("contact: a number of nodes along the tip camber line needs the tip (tip=...)")
    if cyclic is not None:
        if not (isinstance(cyclic, (tuple, list)) and len(cyclic) == 3 and isinstance(cyclic[2], (int, np.integer))
                and not isinstance(cyclic[2], bool) and 2 <= cyclic[2] <= 360):
            raise ValueError(f"cyclic: give (left face, right face, N sectors in 2..360), got {cyclic!r}")
        if suffix not in mesh_import.MESH_SUFFIXES:
            raise ValueError("cyclic: a CAD file is meshed here without matching faces; give a mesh file whose left "
                             "and right faces match under the rotation by 2 pi / N")
    if blade is not None and (cyclic is None or not (isinstance(blade, str) and blade.strip())):
        raise ValueError(f"blade: the name of the element set of a cyclic sector's blade (with cyclic=...), got "
                         f"{blade!r}" + ("" if cyclic is not None else " without cyclic"))
    gmsh.model.add("user_blade")
    R = mesh_import.turn_to_z(axis)
    if axis != "+z" and suffix not in mesh_import.MESH_SUFFIXES:
        raise ValueError(f"axis {axis}: a CAD file is meshed as it is; turn it so that its axis is +z, or give a mesh "
                         "file")

    def turned(spec):                                   # a box or coordinates of the file's frame, in the turned one
        if spec is None or isinstance(spec, (str, int, np.integer)) or axis == "+z":
            return spec
        arr = np.asarray(spec, dtype=float)
        if arr.ndim == 1 and arr.size == 6 and np.all(arr[:3] <= arr[3:]):
            corners = np.array(list(itertools.product(*zip(arr[:3], arr[3:])))) @ R.T
            return tuple(corners.min(axis=0)) + tuple(corners.max(axis=0))
        if arr.ndim == 2 and arr.shape[1] == 3:
            return arr @ R.T
        return spec

    if suffix in mesh_import.MESH_SUFFIXES:
        mesh = mesh_import.read_mesh(path, scale)
        if axis != "+z":
            mesh = dataclasses.replace(mesh, points=mesh.points @ R.T)
            clamp, tip = turned(clamp), turned(tip)
            cyclic = cyclic if cyclic is None else (turned(cyclic[0]), turned(cyclic[1]), cyclic[2])
            contact = contact if contact is None or isinstance(contact, str) or np.ndim(contact) != 2 \
                else turned(contact)
        facets = mesh_import.boundary_facets(mesh.tets)
        _, normals, areas = mesh_import.outward_normals(mesh.points, mesh.tets)        # row for row with facets
        groups, named = {}, {}
        faces = ((BladeGroup.CLAMP, "clamp", clamp), (BladeGroup.TIP, "tip", tip))
        if cyclic is not None:
            faces += ((BladeGroup.LEFT, "left", cyclic[0]), (BladeGroup.RIGHT, "right", cyclic[1]))
        for tag, what, name in faces:
            if name is None:
                continue
            named[what] = name
            nodes = mesh.nodes_of(name, what)
            inside = np.isin(facets[:, :3], nodes).all(axis=1)
            if not inside.any():
                raise ValueError(f"{what}: {name!r} of {path} covers no boundary facet (all three corners of a "
                                 f"facet must be in it)")
            if what == "clamp" and not isinstance(name, str):
                mesh_import.check_box_face(normals[inside], areas[inside], what, name)
            groups[(int(tag), what)] = facets[inside]
        keys = {what: {tuple(sorted(f)) for f in facets[:, :3].tolist()} for (_, what), facets in groups.items()}
        for a, b in itertools.combinations(keys, 2):
            shared = len(keys[a] & keys[b])
            if shared:
                raise ValueError(f"{b}: {named[b]!r} shares {shared} boundary facets with the {a} {named[a]!r} of "
                                 f"{path}: each facet belongs to one group (a clamped face cannot be a cyclic face)")
        tip_group = np.unique(groups[(int(BladeGroup.TIP), "tip")]) if tip is not None else np.zeros(0, np.int64)
        tip_nodes = np.zeros((0, 3))
        if contact is not None:
            if isinstance(contact, str):
                contact = mesh.group(contact, "contact")
            nodes, _ = mesh_import.select_contact_nodes(mesh.points, tip_group, contact)
            mesh_import.check_contact_on_tip(mesh.points, facets, normals, nodes, "tip" if tip is not None else
                                             "contact")
            tip_nodes = mesh.points[nodes]
        parts = None
        if blade is not None:
            from .disk import DISK_GROUP

            blade_tets = mesh.cell_set(blade, "blade")
            if blade_tets.size == len(mesh.tets):
                raise ValueError(f"blade: the element set {blade!r} of {path} holds every cell: no disk is left")
            parts = {(int(BladeGroup.BLADE), "blade"): blade_tets,
                     (DISK_GROUP, "disk"): np.setdiff1d(np.arange(len(mesh.tets)), blade_tets)}
        mesh_import.add_to_gmsh(mesh, groups, int(BladeGroup.BLADE), parts=parts)
        caught = "; ".join(mesh_import.group_report(mesh.points, f, what, named[what])
                           for (_, what), f in groups.items())
        if parts is not None:
            caught += f"; blade {blade!r}: {blade_tets.size} of {len(mesh.tets)} tetrahedra"
        if axis != "+z":
            names = ["x", "y", "z"]
            image = ", ".join(("-" if R[i][np.flatnonzero(R[i])[0]] < 0 else "") + names[np.flatnonzero(R[i])[0]]
                              for i in range(3))
            caught += f"; its axis {axis} turned to +z: (x, y, z) -> ({image}), the results in that frame"
        return BladeModel(source=f"file:{path}", volume=float("nan"),        # assembled on the mesh (fem)
                          tip_nodes=tip_nodes, preset=preset, n_nodes=len(mesh.points),
                          summary=f"{mesh.summary()}; {caught}", n_sectors=0 if cyclic is None else int(cyclic[2]))
    try:
        entities = gmsh.model.occ.importShapes(str(path))
    except Exception as exc:
        raise ValueError(f"blade file {path} could not be read by gmsh ({str(exc).splitlines()[0]})") from None
    if scale != 1.0:
        gmsh.model.occ.dilate(entities, 0, 0, 0, scale, scale, scale)
    gmsh.model.occ.synchronize()
    volumes = [t for d, t in gmsh.model.getEntities(3)]
    if not volumes:
        raise ValueError(f"blade file {path} holds no solid")
    groups = {BladeGroup.CLAMP: _faces_in_box(clamp, "clamp", path)}
    if tip is not None:
        groups[BladeGroup.TIP] = _faces_in_box(tip, "tip", path)
    gmsh.model.addPhysicalGroup(3, volumes, BladeGroup.BLADE)
    gmsh.model.setPhysicalName(3, BladeGroup.BLADE, "blade")
    for group, faces in groups.items():
        gmsh.model.addPhysicalGroup(2, faces, group)
        gmsh.model.setPhysicalName(2, group, group.name.lower())
    _apply_mesh_preset(preset)
    gmsh.model.mesh.generate(3)
    tip_nodes = np.zeros((0, 3))
    if contact is not None:
        if isinstance(contact, str):
            raise ValueError("contact: a CAD file has no named node groups; give a number of nodes along the tip "
                             "camber line, coordinates or node indices")
        tags, x, _ = gmsh.model.mesh.getNodes()
        x = x.reshape(-1, 3)
        tip_tags = gmsh.model.mesh.getNodesForPhysicalGroup(2, BladeGroup.TIP)[0] if tip is not None else []
        index = {int(t): k for k, t in enumerate(tags)}
        nodes, _ = mesh_import.select_contact_nodes(x, np.array([index[int(t)] for t in tip_tags], np.int64),
                                                    contact)
        tip_nodes = x[nodes]
    lo, hi = np.array(gmsh.model.getBoundingBox(-1, -1)).reshape(2, 3)
    summary = (f"{path}: meshed with preset {preset.name}, {len(gmsh.model.mesh.getNodes()[0]):,} nodes; bounding box "
               f"[{lo[0]:.4g}, {hi[0]:.4g}] x [{lo[1]:.4g}, {hi[1]:.4g}] x [{lo[2]:.4g}, {hi[2]:.4g}] m")
    return BladeModel(source=f"file:{path}", volume=sum(gmsh.model.occ.getMass(3, v) for v in volumes),
                      tip_nodes=tip_nodes, preset=preset, n_nodes=len(gmsh.model.mesh.getNodes()[0]), summary=summary)
