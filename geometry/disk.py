"""gmsh OpenCASCADE models of cyclic sectors: the rotor 37 bladed-disk sector of the paper's §3, a plain annular
plate sector and a free thin ring's sector (verification cases with closed-form references).

A sector is the part of a structure of N identical sectors between two cyclic faces, the right face being the left
one turned by 2 pi / N about e_z. The disk sector's faces are built as one surface and its turned copy, and meshed
with gmsh's ``setPeriodic`` (the right mesh is the left mesh turned), so every node of the right face has a partner on
the left face, to round-off; the plate sector is a structured grid whose right face is its left face turned.

The rotor 37 disk is not public; the disk sector here (``DiskProfile``) follows the notes in
``../shared/docs/rotor37-notes.md``: the rim's outer surface is the hub line of Table V (the cone on which the blade
root sits), the rim spans z = -5 ... 48 mm, a web and a bore ring carry it down to the bore, which is clamped
("the sectors are clamped at the disk lower surfaces", §3.2). The blade root spans 11.2 degrees of circumference,
more than the 10 degree pitch, so the cyclic faces follow the root camber line +-5 degrees (``root_camber_angle``),
at least 4 degrees from the blade. The blade is the project's blade 4 mm shorter (§3.2), its root continued 4 mm into
the rim and cut by it so that blade and disk share a conforming interface.

Only gmsh and NumPy are used. Lengths in m, angles in rad.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from .blade import (N_TIP_NODES, BladeGroup, MeshPreset, _apply_mesh_preset, _classify_blade_faces, _edge_curves,
                    _tip_camber_points, add_blade_from_sections, blade_sections, embed_tip_nodes, get_mesh_preset)
from .parametric import N_TABLE_SECTIONS, BladeLaw
from .tables import BladeTable

__all__ = ["DiskProfile", "SectorModel", "root_camber_angle", "create_disk_sector_model",
           "create_annular_sector_model", "create_ring_sector_model", "DISK_GROUP"]

DISK_GROUP = 11               # physical tag of the disk volume (the blade volume is BladeGroup.BLADE)
_MM = 1e-3


def root_camber_angle(z: np.ndarray) -> np.ndarray:
    """theta_c(z) (rad) of the blade root's camber line (rotor37-notes: -6.870 + 0.44798 z - 0.0043434 z^2 degrees,
    z in mm, on the root's chord 0.28 <= z <= 43.05 mm, max error 0.07 degree), continued with its end slopes."""
    z_mm = np.asarray(z, float) / _MM
    lo, hi = 0.28, 43.05

    def quad(x):
        return -6.870 + 0.44798 * x - 0.0043434 * x ** 2

    def slope(x):
        return 0.44798 - 2 * 0.0043434 * x

    deg = np.where(z_mm < lo, quad(lo) + slope(lo) * (z_mm - lo),
                   np.where(z_mm > hi, quad(hi) + slope(hi) * (z_mm - hi), quad(z_mm)))
    return np.radians(deg)


def hub_radius(z: np.ndarray) -> np.ndarray:
    """The hub cone of rotor 37 (Table V hub line to 0.02 mm): r = 177.90 + 0.2208 (z - 0.28) mm."""
    return (177.90 + 0.2208 * (np.asarray(z, float) / _MM - 0.28)) * _MM


@dataclasses.dataclass(frozen=True)
class DiskProfile:
    """Meridional profile of the disk sector (m). The defaults are estimates, not the paper's (unpublished) disk:

    rim: outer surface on the hub cone (where the blade root sits), z_front ... z_back (rotor37-notes: -5 ... 48 mm),
        inner radius ``rim_inner`` (165 mm: 12-23 mm of rim under the blade);
    web: web_front ... web_back (12 ... 28 mm: 16 mm thick, under the blade's stacking line z ~ 20 mm), from the rim
        down to ``bore_outer``;
    bore ring: bore_front ... bore_back (2 ... 38 mm), between ``bore_radius`` (145 mm, clamped; the notes give
        140-150) and ``bore_outer`` (155 mm).
    A thick, short web keeps the disk-dominated modes away from the blade's 1B (the notes warn that a thin free
    ring would put them below it); the SAFE diagram shows where they are.
    """

    z_front: float = -5e-3
    z_back: float = 48e-3
    rim_inner: float = 0.165
    web_front: float = 12e-3
    web_back: float = 28e-3
    bore_outer: float = 0.155
    bore_front: float = 2e-3
    bore_back: float = 38e-3
    bore_radius: float = 0.145

    def __post_init__(self):
        if not (self.z_front < self.bore_front < self.web_front < self.web_back < self.bore_back < self.z_back):
            raise ValueError("disk profile: need z_front < bore_front < web_front < web_back < bore_back < z_back")
        if not (0.0 < self.bore_radius < self.bore_outer < self.rim_inner < float(hub_radius(self.z_front))):
            raise ValueError("disk profile: need 0 < bore_radius < bore_outer < rim_inner < the hub radius")

    def outline(self) -> np.ndarray:
        """(z, r) vertices of the profile, counter-clockwise, the rim's outer edge (hub cone) first."""
        hub = hub_radius(np.array([self.z_front, self.z_back]))
        return np.array([
            [self.z_front, hub[0]], [self.z_front, self.rim_inner], [self.web_front, self.rim_inner],
            [self.web_front, self.bore_outer], [self.bore_front, self.bore_outer], [self.bore_front, self.bore_radius],
            [self.bore_back, self.bore_radius], [self.bore_back, self.bore_outer], [self.web_back, self.bore_outer],
            [self.web_back, self.rim_inner], [self.z_back, self.rim_inner], [self.z_back, hub[1]]])[::-1]


@dataclasses.dataclass(frozen=True)
class SectorModel:
    """What the sector builder reports about the gmsh model it made (the mesh stays in gmsh).

    Attributes:
        source: what was built; volume: CAD volume (m^3); tip_nodes: (n, 3) contact nodes LE -> TE (empty for a
        plate); preset; n_nodes: mesh nodes; n_sectors: N; blade_volume: CAD volume of the blade part (m^3); free: no
        clamp (the model has no 'clamp' group by design).
    """

    source: str
    volume: float
    tip_nodes: np.ndarray
    preset: MeshPreset
    n_nodes: int
    n_sectors: int
    blade_volume: float = 0.0
    free: bool = False


def _rotation_affine(angle: float) -> list[float]:
    c, s = np.cos(angle), np.sin(angle)
    return [c, -s, 0.0, 0.0, s, c, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]


def _point_on_face(tag: int) -> np.ndarray:
    """A point of a surface (its parametric middle), for classifying faces geometrically."""
    import gmsh

    lo, hi = gmsh.model.getParametrizationBounds(2, tag)
    return np.array(gmsh.model.getValue(2, tag, list(0.5 * (np.asarray(lo) + np.asarray(hi)))))


def _cyclic_faces(faces: list[int], theta_left, angle: float) -> tuple[list[int], list[int]]:
    """The left and right cyclic faces among ``faces``, paired in order (right[i] is left[i] turned by angle).

    Faces of revolution have normals in the meridional plane; the cyclic faces' normals point along e_theta. The
    left ones lie on theta_left(z), the right ones a sector angle further."""
    import gmsh

    lefts, rights, pts = [], [], {}
    for f in faces:
        lo, hi = gmsh.model.getParametrizationBounds(2, f)
        uv = list(0.5 * (np.asarray(lo) + np.asarray(hi)))
        p = np.array(gmsh.model.getValue(2, f, uv))
        n = np.array(gmsh.model.getNormal(f, uv))
        e_theta = np.array([-p[1], p[0], 0.0]) / np.hypot(p[0], p[1])
        if abs(n @ e_theta) < 0.5:
            continue
        pts[f] = p
        rel = np.arctan2(p[1], p[0]) - float(theta_left(p[2]))
        (lefts if abs(rel) < 0.25 * angle else rights if abs(rel - angle) < 0.25 * angle else []).append(f)
    rot = np.array(_rotation_affine(angle)).reshape(4, 4)[:3, :3]
    paired = [min(rights, key=lambda r: np.linalg.norm(pts[r] - rot @ pts[lf])) for lf in lefts] if rights else []
    if not lefts or len(lefts) != len(rights) or len(set(paired)) != len(lefts):
        raise ValueError(f"the cyclic faces of the sector could not be paired ({len(lefts)} left, {len(rights)} "
                         f"right faces found)")
    return lefts, paired


def _revolved_block(profile_zr: np.ndarray, theta_from: float, theta_to: float) -> int:
    """The profile (z, r) revolved about e_z from theta_from to theta_to: one volume tag."""
    import gmsh

    occ = gmsh.model.occ
    pts = [occ.addPoint(r, 0.0, z) for z, r in profile_zr]
    lines = [occ.addLine(pts[i], pts[(i + 1) % len(pts)]) for i in range(len(pts))]
    face = occ.addPlaneSurface([occ.addCurveLoop(lines)])
    occ.rotate([(2, face)], 0, 0, 0, 0, 0, 1, theta_from)
    out = occ.revolve([(2, face)], 0, 0, 0, 0, 0, 1, theta_to - theta_from)
    return [t for d, t in out if d == 3][0]


def _cyclic_surface(theta_of_z, z_range, r_range, n_stations: int = 16) -> int:
    """The left cyclic face: radial lines at theta_of_z(z) for z in z_range, through-sectioned into one surface."""
    import gmsh

    occ = gmsh.model.occ
    wires = []
    for z in np.linspace(*z_range, n_stations):
        th = float(theta_of_z(z))
        a = occ.addPoint(r_range[0] * np.cos(th), r_range[0] * np.sin(th), z)
        b = occ.addPoint(r_range[1] * np.cos(th), r_range[1] * np.sin(th), z)
        wires.append(occ.addWire([occ.addLine(a, b)]))
    surf = occ.addThruSections(wires, makeSolid=False, makeRuled=False)
    return [t for d, t in surf if d == 2][0]


def _cut_sector(block: int, theta_left, z_range, r_range, n_sectors: int) -> tuple[int, list[int], list[int]]:
    """Cut the sector out of the block between the left face and its copy turned by 2 pi / N; returns the volume
    and its left and right faces, paired in order (right[i] is left[i] turned)."""
    import gmsh

    occ = gmsh.model.occ
    angle = 2 * np.pi / n_sectors
    left = _cyclic_surface(theta_left, z_range, r_range)
    right = occ.copy([(2, left)])
    occ.rotate(right, 0, 0, 0, 0, 0, 1, angle)
    pieces, _ = occ.fragment([(3, block)], [(2, left)] + right)
    occ.synchronize()
    volumes = [t for d, t in pieces if d == 3]
    # the middle piece: its centre lies between the faces
    def offset(v):
        c = np.array(occ.getCenterOfMass(3, v))
        return np.arctan2(c[1], c[0]) - float(theta_left(c[2]))

    keep = [v for v in volumes if 0.0 < offset(v) < angle]
    if len(keep) != 1:
        raise ValueError(f"cutting the sector produced {len(keep)} middle volumes (expected 1): check the profile")
    occ.remove([(3, v) for v in volumes if v != keep[0]], recursive=True)
    occ.synchronize()
    bounding = {t for d, t in gmsh.model.getBoundary([(3, keep[0])], oriented=False) if d == 2}
    occ.remove([(2, t) for d, t in gmsh.model.getEntities(2) if t not in bounding], recursive=True)
    occ.synchronize()
    lefts, rights = _cyclic_faces(sorted(bounding), theta_left, angle)
    return keep[0], lefts, rights


def _add_group(dim: int, tags: list[int], tag: int, name: str) -> None:
    import gmsh

    gmsh.model.addPhysicalGroup(dim, tags, tag)
    gmsh.model.setPhysicalName(dim, tag, name)


def create_disk_sector_model(table: BladeTable | None = None, preset: str | MeshPreset = "coarse",
                             law: BladeLaw | None = None, n_tip_nodes: int = N_TIP_NODES, shorten: float = 4e-3,
                             profile: DiskProfile = DiskProfile(), n_sectors: int = 36) -> SectorModel:
    """Build and mesh the rotor 37 bladed-disk sector in the current gmsh model.

    Args:
        table: NASA Table IV for the exact loft; None for the built-in parametric blade.
        preset: mesh preset ('ci', 'coarse', 'paper') or a MeshPreset (the blade edges are refined as for the blade).
        n_tip_nodes: contact nodes on the tip camber line, LE to TE (2..40).
        shorten: blade length removed at the tip (m), 0 <= shorten < 20 mm (the paper: 4 mm).
        profile: the disk's meridional profile.
        n_sectors: N, the number of blades (rotor 37: 36); the sector angle 2 pi / N must exceed the blade root's
            11.2 degrees minus the 8 degrees the camber-following faces keep from it, so N <= 100.
    Physical groups: volumes 'blade' and 'disk'; faces 'clamp' (the bore), 'left', 'right' (cyclic), 'tip',
    'pressure', 'suction', 'leading_edge', 'trailing_edge'; points 'tip_nodes' (LE -> TE).
    """
    import gmsh

    preset = get_mesh_preset(preset)
    if not (2 <= int(n_tip_nodes) <= 40):
        raise ValueError(f"n_tip_nodes must be in [2, 40], got {n_tip_nodes}")
    if not (0.0 <= shorten < 0.02):
        raise ValueError(f"shorten must be in [0, 0.02) m, got {shorten}")
    if not (4 <= int(n_sectors) <= 100) or int(n_sectors) != n_sectors:
        raise ValueError(f"n_sectors must be an integer in [4, 100] (360 / N degrees per sector), got {n_sectors}")
    if table is not None and table.n_sections < N_TABLE_SECTIONS:
        raise ValueError(f"blade table {table.source} has {table.n_sections} sections, needs >= {N_TABLE_SECTIONS}")
    n_sectors = int(n_sectors)
    angle = 2 * np.pi / n_sectors
    occ = gmsh.model.occ
    gmsh.model.add("disk_sector")
    outline = profile.outline()
    margin = 1e-3
    theta_left = lambda z: root_camber_angle(z) - 0.5 * angle      # noqa: E731
    z_range = (profile.z_front - margin, profile.z_back + margin)
    thetas = theta_left(np.linspace(*z_range, 50))
    block = _revolved_block(outline, thetas.min() - 0.2, thetas.max() + angle + 0.2)
    disk, lefts, rights = _cut_sector(block, theta_left, z_range,
                                      (profile.bore_radius - margin, outline[:, 1].max() + margin), n_sectors)
    sections, source = blade_sections(table, law, shorten, root_depth=4e-3)
    blade = add_blade_from_sections(sections)
    # one boolean: the blade (its root 4 mm into the rim) and the disk fragment into the blade above the rim, the
    # root inside the rim (counted as disk) and the rest of the disk, with conforming interfaces
    gmsh.option.setNumber("Geometry.OCCParallel", 1)
    pieces, _ = occ.fragment([(3, disk)], [(3, blade)])
    occ.synchronize()
    volumes = [t for d, t in pieces if d == 3]
    if len(volumes) != 3:
        raise ValueError(f"blade and disk fragmented into {len(volumes)} volumes (expected 3)")
    radius = {v: np.hypot(*occ.getCenterOfMass(3, v)[:2]) for v in volumes}
    blade_vol = max(volumes, key=radius.get)
    disk_vols = [v for v in volumes if v != blade_vol]
    groups = _classify_blade_faces(blade_vol)               # root (the interface), tip, sides, edge strips
    tip_face = groups[BladeGroup.TIP][0]
    del groups[BladeGroup.CLAMP]                           # the blade is held by the disk, not clamped
    disk_faces = [t for d, t in gmsh.model.getBoundary([(3, v) for v in disk_vols], combined=True, oriented=False)
                  if d == 2]
    bore = [f for f in disk_faces if abs(np.hypot(*_point_on_face(f)[:2]) - profile.bore_radius) < 1e-7]
    if not bore:
        raise ValueError("no bore face found on the disk sector")
    lefts, rights = _cyclic_faces(disk_faces, theta_left, angle)      # the fragment may renumber faces
    le, te = sections[-1][0][0], sections[-1][0][-1]
    tip_points = _tip_camber_points(tip_face, le, te, sections, int(n_tip_nodes))
    _add_group(3, [blade_vol], BladeGroup.BLADE, "blade")
    _add_group(3, disk_vols, DISK_GROUP, "disk")
    for group, faces in groups.items():
        if faces:
            _add_group(2, faces, group, group.name.lower())
    _add_group(2, bore, BladeGroup.CLAMP, "clamp")
    _add_group(2, lefts, BladeGroup.LEFT, "left")
    _add_group(2, rights, BladeGroup.RIGHT, "right")
    node_tags = embed_tip_nodes(tip_face, tip_points)
    _add_group(0, node_tags, BladeGroup.TIP_NODES, "tip_nodes")
    gmsh.model.mesh.setPeriodic(2, rights, lefts, _rotation_affine(angle))
    _apply_mesh_preset(preset, _edge_curves(groups))
    gmsh.model.mesh.generate(3)
    tip_mesh = np.array([gmsh.model.mesh.getNodes(0, t)[1] for t in node_tags]).reshape(-1, 3)
    return SectorModel(source=f"disk:{source}(shorten={shorten:g}, N={n_sectors})",
                       volume=sum(occ.getMass(3, v) for v in volumes), tip_nodes=tip_mesh,
                       preset=preset, n_nodes=len(gmsh.model.mesh.getNodes()[0]), n_sectors=n_sectors,
                       blade_volume=occ.getMass(3, blade_vol))


def _structured_annulus(inner: float, outer: float, height: float, n_sectors: int, nr: int, nt: int, nz: int):
    """A structured grid of the sector inner <= r <= outer, 0 <= theta <= 2 pi / N, |z| <= height / 2 with nr x nt x
    nz cells, each split into the 6 tetrahedra of its main diagonal (Kuhn's subdivision: the same in every cell, so
    the mesh is conforming and the right face's triangles are the left face's turned, to round-off). Returns (points,
    tets (positively oriented), index (nr+1, nt+1, nz+1) of the nodes, volume)."""
    import itertools

    angle = 2 * np.pi / int(n_sectors)
    r = inner + (outer - inner) * np.arange(nr + 1) / nr
    theta = angle * np.arange(nt + 1) / nt
    theta[-1] = angle                                  # the right face: the left one's nodes turned, exactly
    z = height * (np.arange(nz + 1) / nz - 0.5)
    R, TH, Z = np.meshgrid(r, theta, z, indexing="ij")
    points = np.column_stack([(R * np.cos(TH)).ravel(), (R * np.sin(TH)).ravel(), Z.ravel()])
    index = np.arange(len(points)).reshape(nr + 1, nt + 1, nz + 1)

    def corner(d):                                     # the node at offset d of every cell
        return index[d[0]:nr + d[0], d[1]:nt + d[1], d[2]:nz + d[2]].ravel()

    tets = []
    for order in itertools.permutations(range(3)):     # 000 -> ... -> 111 along the axes in this order
        path = [np.zeros(3, dtype=int)]
        for axis in order:
            path.append(path[-1] + np.eye(3, dtype=int)[axis])
        tets.append(np.column_stack([corner(p) for p in path]))
    tets = np.vstack(tets)
    a, b, c, d = (points[tets[:, k]] for k in range(4))
    signed = np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a)
    tets[signed < 0] = tets[signed < 0][:, [0, 2, 1, 3]]
    return points, tets, index, float(np.abs(signed).sum() / 6)


def _annulus_to_gmsh(points, tets, index, clamped: bool, source: str) -> None:
    """The structured annulus into a new gmsh model: volume 'disk', faces 'left', 'right' and (if ``clamped``)
    'clamp' (the inner edge)."""
    import gmsh

    from .mesh_import import ImportedMesh, add_to_gmsh, boundary_facets

    facets = boundary_facets(tets)
    faces = ([(BladeGroup.CLAMP, "clamp", index[0])] if clamped else []) + \
        [(BladeGroup.LEFT, "left", index[:, 0]), (BladeGroup.RIGHT, "right", index[:, -1])]
    groups = {(int(tag), name): facets[np.isin(facets, nodes.ravel()).all(axis=1)] for tag, name, nodes in faces}
    mesh = ImportedMesh(points=points, tets=tets, node_sets={}, converted={"tetra": (len(tets), len(tets))},
                        source=source)
    gmsh.model.add("annular_sector")
    add_to_gmsh(mesh, groups, DISK_GROUP, "disk")


def create_annular_sector_model(inner: float, outer: float, thickness: float, n_sectors: int,
                                size: float, layers: int = 2) -> SectorModel:
    """A sector of a flat annular plate (inner radius clamped, outer edge free; mid-plane z = 0) with radial cyclic
    faces at theta = 0 and 2 pi / N, meshed as a structured grid of about ``size`` (m) in r and along the mid-radius
    arc and exactly ``layers`` elements through the thickness (``_structured_annulus``). Groups: volume 'disk', faces
    'clamp' (inner edge), 'left', 'right'. For verification against the Kirchhoff plate (``tests/disk/test_disk.py``)."""
    if not (0.0 < inner < outer) or not (0.0 < thickness < outer - inner):
        raise ValueError("annular sector: need 0 < inner < outer and 0 < thickness < outer - inner")
    if not (2 <= int(n_sectors) <= 360):
        raise ValueError(f"n_sectors must be in [2, 360], got {n_sectors}")
    if not (isinstance(layers, (int, np.integer)) and not isinstance(layers, bool) and 1 <= layers <= 50):
        raise ValueError(f"layers must be an integer in 1..50 (elements through the thickness), got {layers!r}")
    if not 0.0 < size <= outer - inner:
        raise ValueError(f"size must be in (0, outer - inner], got {size}")
    angle = 2 * np.pi / int(n_sectors)
    nr = max(1, int(np.ceil((outer - inner) / size - 1e-9)))
    nt = max(1, int(np.ceil(angle * 0.5 * (inner + outer) / size - 1e-9)))     # about size at the mid radius
    points, tets, index, volume = _structured_annulus(inner, outer, thickness, n_sectors, nr, nt, layers)
    _annulus_to_gmsh(points, tets, index, True, "annular plate sector")
    return SectorModel(source=f"annular(a={outer:g}, b={inner:g}, h={thickness:g}, N={int(n_sectors)}, "
                              f"{nr} x {nt} x {layers} cells)",
                       volume=volume, tip_nodes=np.zeros((0, 3)),
                       preset=MeshPreset("plate", size, 0, min(size, thickness / layers)),
                       n_nodes=len(points), n_sectors=int(n_sectors))


def create_ring_sector_model(radius: float, radial: float, axial: float, n_sectors: int, size: float
                             ) -> SectorModel:
    """A sector of a free thin ring: mean radius ``radius``, rectangular cross-section ``radial`` x ``axial`` (m),
    a structured grid (``_structured_annulus``) of about ``size`` (m) in every direction (at least 2 cells across
    the section's sides). Nothing is clamped (a free structure: its rigid-body motions live in the harmonic indices
    k = 0 and 1). Groups: volume 'disk', faces 'left', 'right'. For Bryan's factor (``tests/dynamics/test_rotation.py``)."""
    if not (0.0 < radial < radius) or not (0.0 < axial < radius):
        raise ValueError("ring sector: need 0 < radial < radius and 0 < axial < radius")
    if not (4 <= int(n_sectors) <= 360):
        raise ValueError(f"n_sectors must be in [4, 360], got {n_sectors}")
    if not 0.0 < size <= radius:
        raise ValueError(f"size must be in (0, radius], got {size}")
    nr = max(2, int(np.ceil(radial / size - 1e-9)))
    nz = max(2, int(np.ceil(axial / size - 1e-9)))
    nt = max(1, int(np.ceil(2 * np.pi * radius / int(n_sectors) / size - 1e-9)))
    points, tets, index, volume = _structured_annulus(radius - radial / 2, radius + radial / 2, axial, n_sectors,
                                                      nr, nt, nz)
    _annulus_to_gmsh(points, tets, index, False, "ring sector")
    return SectorModel(source=f"ring(R={radius:g}, {radial:g} x {axial:g}, N={int(n_sectors)}, "
                              f"{nr} x {nt} x {nz} cells)",
                       volume=volume, tip_nodes=np.zeros((0, 3)),
                       preset=MeshPreset("ring", size, 0, size), n_nodes=len(points), n_sectors=int(n_sectors),
                       free=True)
