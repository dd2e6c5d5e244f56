"""Analyses that combine the FE adapter with the pure modules: stress at the worst instant of a simulation, and the
stress of every sector of a bladed disk from a disk model's state, and the full-order cyclic frequencies per nodal
diameter (a disk model's: ``disk.harmonics.harmonic_frequencies``)."""
from __future__ import annotations

import numpy as np

from rotor37_rom import fem

__all__ = ["stress_at_peak", "disk_stress", "disk_stress_summary", "stress_location", "describe_location",
           "tip_band", "TIP_BAND", "ROOT_BAND", "root_distance", "cyclic_harmonic_frequencies"]

TIP_BAND = 0.1     # cells closer to a contact node than this fraction of the span are reported apart
ROOT_BAND = 4e-3   # m: a disk sector's cells with a vertex closer than this to the blade-rim junction (a sharp
                   # corner) likewise


def stress_at_peak(sector, model, recovery, result, nonlinear: bool, sim: int = 0, magnitude: bool = False) -> dict:
    """t_max (largest radial displacement of node LE toward the casing; with ``magnitude``, largest in either sense,
    the NFRC's max |u_LE|: in the paper's Fig. 25 the blade swings away from the casing there, free of contact
    forces) and von Mises there: the maximum over the blade except the cells within 10 % of the span of a contact node,
    and apart, the maximum in that tip band and in the cells touching a contact node (point contact forces make the FE
    stress singular there: it grows under mesh refinement)."""
    if result is None or result.records_q is None:
        raise ValueError("no simulation with recorded states yet: run the contact simulation first (record_q=True)")
    if not 0 <= sim < len(result.t):
        raise ValueError(f"sim must be in [0, {len(result.t) - 1}], got {sim}")
    t, u_le = result.t[sim], result.u_r[sim][result.row("0:LE")]
    if not np.isfinite(u_le).any():
        raise ValueError("the simulation has no finite record of node LE (diverged?)")
    k = int(np.nanargmax(np.abs(u_le) if magnitude else u_le))
    q = result.records_q[sim][:, k]
    cell_max = recovery.cell_max(q, nonlinear)
    mid = fem.cell_midpoints(sector)
    band, singular = tip_band(sector, model, mid)
    regular = cell_max.copy()
    regular[band] = -np.inf
    cell = int(np.argmax(regular))
    centroid = mid[cell]
    return {"t_max": float(t[k]), "u_le": float(u_le[k]), "q": q, "vm_max": float(regular[cell]), "cell": cell,
            "location": centroid.tolist(), "ratio_yield": float(regular[cell] / sector.material.sigma_y),
            "vm_max_at_contact_nodes": float(cell_max[singular].max()), "cell_max": cell_max,
            "vm_max_tip_band": float(cell_max[band].max()),
            "clim": [0.0, float(np.percentile(cell_max[~band], 99.5))]}


def _contact_nodes(sector, model) -> np.ndarray:
    """The contact nodes on this sector's mesh: the model's of sector 0, or the sector's own tip nodes (model None)."""
    if model is None:
        return np.asarray(sector.tip_nodes, float)
    return model.nodes.coordinates[model.nodes.sector == 0]


def tip_band(sector, model, midpoints: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(cells within ``TIP_BAND`` of the span of a contact node, cells touching one) of the sector's mesh: the zone
    of the contact impulses, where point forces make the FE stress singular. ``model``: the reduced model (its
    contact nodes of sector 0), or None for the sector's own tip nodes (a full-order field; so also in
    ``disk_stress_summary`` and ``stress_location``). ``midpoints``: the cells' midpoints (``fem.cell_midpoints``)
    when the caller has them."""
    nodes = _contact_nodes(sector, model)
    singular = fem.cells_touching_points(sector, nodes)
    mid = fem.cell_midpoints(sector) if midpoints is None else midpoints
    span = np.ptp(np.hypot(mid[:, 0], mid[:, 1]))
    distance = np.min(np.linalg.norm(mid[:, None, :] - nodes[None, :, :], axis=2), axis=1)
    return distance < TIP_BAND * span, singular


def root_distance(sector, points: np.ndarray) -> np.ndarray:
    """Distance (m) of each of ``points`` (..., 3) to the line where a disk sector's blade meets the rim
    (``fem.root_junction``, sampled every 0.2 mm: exact to 0.1 mm)."""
    from scipy.spatial import cKDTree

    points = np.asarray(points, float)
    return cKDTree(fem.root_junction(sector)).query(points.reshape(-1, 3))[0].reshape(points.shape[:-1])


def disk_stress_summary(sector, model, values: np.ndarray, monitored: int = 0, root_band: float = ROOT_BAND) -> dict:
    """The numbers of a disk's von Mises field (``disk_stress`` values, (N, n_cells, 4) at the cells' vertices, all
    sectors): the largest in sector ``monitored`` and over all sectors outside the tip band (and which sector), in
    the tip band, the ratio of the sector's to the yield stress, and where the two largest sit (``stress_location``).

    The blade meets the rim at a sharp re-entrant corner (no fillet), where the FE stress is singular: its largest
    there does not converge under mesh refinement. The same numbers off the root corner (``*_off_root``: every cell
    with a vertex within ``root_band`` (m, default ``ROOT_BAND``) of the junction left out as well;
    ``location_off_root`` is the vertex's) converge with the mesh (benchmarks/bench_disk_stress_convergence.py: the
    disk's 1B mode on meshes of 12 to 1.5
    mm); they are the stress to compare with sigma_Y."""
    values = np.asarray(values, float)
    if values.ndim != 3 or values.shape[2] != 4:
        raise ValueError(f"values must be (N, n_cells, 4) von Mises at the cells' vertices (disk_stress), got "
                         f"{values.shape}")
    cells = values.max(axis=2)
    mid = fem.cell_midpoints(sector)
    band, _ = tip_band(sector, model, mid)
    regular = np.where(band[None, :], -np.inf, cells)
    per_sector = regular.max(axis=1)
    worst = int(np.argmax(per_sector))
    vertices = fem.cell_vertices(sector)                                           # (n_cells, 4, 3)
    # a cell with any vertex in the band is left out whole: its far vertices' values are the corner's, extrapolated
    near_root = (root_distance(sector, vertices) < root_band).any(axis=1)           # (n_cells,)
    off_vertices = np.where((band | near_root)[None, :, None], -np.inf, values)     # (N, n_cells, 4)
    off = off_vertices.max(axis=2)
    off_sector = off.max(axis=1)
    worst_off = int(np.argmax(off_sector))
    cell_off, vertex_off = np.unravel_index(int(np.argmax(off_vertices[monitored])), off_vertices.shape[1:])
    sigma_y = sector.material.sigma_y
    return {"vm_max": float(per_sector[monitored]), "ratio_yield": float(per_sector[monitored] / sigma_y),
            "vm_max_all_sectors": float(per_sector.max()), "sector_of_max": worst,
            "vm_max_tip_band": float(cells[monitored][band].max()),
            "location": stress_location(sector, model, int(np.argmax(regular[monitored])), mid),
            "location_all_sectors": stress_location(sector, model, int(np.argmax(regular[worst])), mid),
            "vm_max_off_root": float(off_sector[monitored]),
            "ratio_yield_off_root": float(off_sector[monitored] / sigma_y),
            "vm_max_off_root_all_sectors": float(off_sector.max()), "sector_of_max_off_root": worst_off,
            "location_off_root": stress_location(sector, model, int(cell_off), mid,
                                                 point=vertices[cell_off, vertex_off]),
            "root_band_m": root_band,
            "clim": [0.0, float(np.percentile(cells[:, ~band], 99.5))]}


def stress_location(sector, model, cell: int, midpoints: np.ndarray | None = None,
                    point: np.ndarray | None = None) -> dict:
    """Where a cell of a disk sector's mesh sits, in the sector's own frame (rotor axis z): its centroid's radius,
    axial position and angle, its height above the hub cone (Table V's hub line, where the blade root meets the rim:
    > 0 in the blade, < 0 in the disk), and in the blade the fraction of the span there (height over the tip's,
    the tip radius interpolated in z between the contact nodes). ``midpoints`` as in ``tip_band``; ``point``: the
    same numbers of that point of the cell instead of its centroid (the vertex where a largest was read)."""
    from rotor37_rom.geometry.disk import hub_radius

    x = np.asarray(point, float) if point is not None else \
        (fem.cell_midpoints(sector) if midpoints is None else midpoints)[cell]
    r, z = float(np.hypot(x[0], x[1])), float(x[2])
    height = r - float(hub_radius(z))
    tips = _contact_nodes(sector, model)
    order = np.argsort(tips[:, 2])
    r_tip = float(np.interp(z, tips[order, 2], np.hypot(tips[order, 0], tips[order, 1])))
    return {"r_mm": 1e3 * r, "z_mm": 1e3 * z, "theta_deg": float(np.degrees(np.arctan2(x[1], x[0]))),
            "height_mm": 1e3 * height, "region": "blade" if height > 0 else "disk",
            "span": height / (r_tip - float(hub_radius(z))) if height > 0 else None}


def describe_location(location: dict) -> str:
    """'blade, 4 % of the span, z = 12 mm' or 'disk, 3 mm under the hub cone, z = 40 mm'."""
    if location["region"] == "blade":
        return f"blade, {100 * location['span']:.0f} % of the span, z = {location['z_mm']:.0f} mm"
    return f"disk, {-location['height_mm']:.0f} mm under the hub cone, z = {location['z_mm']:.0f} mm"


def disk_stress(sector, model, q: np.ndarray, nonlinear: bool = True, sectors=None) -> tuple[np.ndarray, np.ndarray]:
    """von Mises (Pa) at the four vertices of every cell (``fem.von_mises_at_vertices``: the cell's own value
    there, where a bending stress is largest; a cell's midpoint value would miss much of it on a coarse mesh) of every
    sector of a disk model's state q, each sector's field rebuilt from q by the model's ``DiskBasis`` (no reassembly
    of the disk) and evaluated by the sector's UFL stress (SVK, second Piola-Kirchhoff pushed to Cauchy with
    ``nonlinear``, else linear). Returns (fields (n_s, n_dofs) in each sector's frame, values (n_s, n_cells, 4)) for
    ``sectors`` (default all); ``values.max(axis=2)`` is a per-cell field for pictures."""
    basis = getattr(model, "sectors", None)
    if basis is None:
        raise ValueError("disk_stress needs a disk model (model.sectors is None: a single blade's model)")
    q = np.asarray(q, float).ravel()
    if q.size != model.r:
        raise ValueError(f"q has {q.size} entries; the model has r = {model.r}")
    sectors = range(basis.n_sectors) if sectors is None else list(sectors)
    fields, values = [], []
    u = fem.displacement_function(sector, np.eye(sector.n_dofs, 1), np.zeros(1))
    for s in sectors:
        field = basis.sector_field(q, s)
        u.x.array[:] = field
        fields.append(field)
        values.append(fem.von_mises_at_vertices(sector, u, nonlinear))
    return np.array(fields), np.array(values)


def cyclic_harmonic_frequencies(sector, n_families: int, K=None, M=None, ops=None, harmonics=None) -> np.ndarray:
    """(len(harmonics), n_families) rad/s: the full-order frequencies of the cyclic ``sector`` at each harmonic index
    of ``harmonics`` (default k = 0 ... N/2; ``fem.CyclicOperators``, kept over k; each cos/sin pair counted once)."""
    if n_families < 1:
        raise ValueError(f"n_families must be >= 1, got {n_families}")
    half = sector.cyclic.n_sectors // 2
    harmonics = range(half + 1) if harmonics is None else [int(k) for k in harmonics]
    if any(not 0 <= k <= half for k in harmonics):
        raise ValueError(f"harmonics must be in 0 ... {half}, got {list(harmonics)}")
    cyc = fem.CyclicOperators(sector, K, M, ops)
    try:
        return np.array([cyc.modes(k, n_families).distinct()[0][:n_families] for k in harmonics])
    finally:
        cyc.destroy()
