"""Mesh convergence of the bladed-disk sector's stress (issue #21, item 4): the sharp blade-rim corner against the
stress off it, on the disk's 1B mode; and the stress next to a contact load at node LE.

The disk sector of the maps has no root fillet: the blade meets the rim at a re-entrant corner, where the elastic
stress is singular (a 270-degree wedge: sigma ~ rho^(lambda - 1), lambda = 0.5445, Williams 1952), so its largest FE
value does not converge under refinement. This script meshes the ci sector at element sizes from the ci preset's
12 mm down to 1.5 mm (the LE/TE refinement kept at min(2 mm, size)), computes the full-order lowest 0-diameter mode
(the 1B family, every blade alike: the shape the contact maps' responses are built of) scaled to 1 mm of largest
displacement component at node LE, and reports its linear von Mises stress outside the tip band:
- at the corner: the largest at the cells' vertices anywhere (``fem.von_mises_at_vertices``);
- off the corner: the largest at the vertices of the cells farther than d from the blade-rim junction (every cell
  with a vertex within d left out; ``fem.root_junction``), d = 2, 4 (``post.stress.ROOT_BAND``, what the disk maps
  report) and 8 mm, and where it sits;
- the largest at the cells' midpoints (DG0, what the disk maps reported before: a midpoint misses the surface's
  bending stress on a coarse mesh).

The contact case: the static response of the same sector (0 diameters, every blade alike, the bore clamped) to the
force the casing puts on node LE when it touches, 1 kN along the cone's inward normal plus the Coulomb friction
against the sliding (mu = 0.15, the maps' casing), linear stress per kN. A reduced model carries a contact force
through its constraint modes, which are static responses to the tip nodes' displacements, so this is the field the
maps' stress next to the contact loads is made of. The point load's own stress is singular at the node (~ 1/rho^2);
reported are the disk summaries' largest off the corner (outside the tip band: the cells whose midpoint lies within
``post.stress.TIP_BAND`` = 10 % of the sector's radial extent, bore to tip, of a contact node - 10.6 mm on the ci
sector), the largest in the cells whose every vertex lies more than d = 8, 16, 24 mm from node LE (and off the
corner), and node LE's displacement. Both cases are also read at one point: the largest vertex value within 3 mm of
where the linear disk map's largest stress off the corner sits (MAP_POINT, at the LE 16 mm under the tip).

    python benchmarks/bench_disk_stress_convergence.py                 # 12, 6, 3, 2, 1.5 mm, both cases: ~6 min
    python benchmarks/bench_disk_stress_convergence.py --sizes 12 3     # a quick look
    python benchmarks/bench_disk_stress_convergence.py --case contact   # the contact load only (~3 min)

Results to results/bench_disk_stress_convergence.json (the mode), ..._contact.json and Markdown tables
(docs/results.md).
"""
from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from rotor37_rom.machine import write_results

BANDS_MM = (2.0, 4.0, 8.0)
LOAD_BALLS_MM = (8.0, 16.0, 24.0)
CASES = ("mode", "contact")
# where the linear disk map's largest stress off the corner sits (1,255.6 rad/s, node LE of sector 0 at t_max: the
# vertex of results/disk_map200/stress_11/summary.json, location_off_root; bench_disk_map.py --part stress): radius,
# axial position (mm), angle (deg) in the sector's frame. Each case reads the largest vertex value within
# POINT_RADIUS_MM of it on every mesh.
MAP_POINT = (230.911, 8.585, -3.898)
POINT_RADIUS_MM = 3.0


def point_xyz(point) -> np.ndarray:
    r, z, theta = point
    return 1e-3 * np.array([r * np.cos(np.radians(theta)), r * np.sin(np.radians(theta)), z])


def near_point(corners: np.ndarray, vertex: np.ndarray, point) -> dict:
    """The largest of ``vertex`` ((n_cells, 4) values at the vertices ``corners``, (n_cells, 4, 3) from
    ``fem.cell_vertices``) within POINT_RADIUS_MM of ``point``."""
    near = np.linalg.norm(corners - point_xyz(point), axis=2) < POINT_RADIUS_MM * 1e-3
    if not near.any():
        raise ValueError(f"no vertex within {POINT_RADIUS_MM} mm of the point {point} (r, z, theta)")
    return {"mpa": float(vertex[near].max() / 1e6), "n_vertices": int(near.sum())}


def disk_sector(size_mm: float):
    """The ci disk sector meshed at ``size_mm`` (the LE/TE refinement kept at min(2 mm, size)) and its meshing time."""
    from mpi4py import MPI

    from rotor37_rom import fem
    from rotor37_rom.geometry.blade import MeshPreset

    t0 = time.perf_counter()
    preset = MeshPreset(f"h{size_mm:g}mm", size=size_mm * 1e-3, curvature_points=0,
                        min_size=min(2.0, size_mm) * 1e-3)
    return fem.create_disk_sector(MPI.COMM_SELF, preset=preset), time.perf_counter() - t0


def contact_stress(sector, point=MAP_POINT, mu: float = 0.15) -> dict:
    """The static response of the sector closed on itself (0 diameters, ``fem.RepeatingSectors``) to 1 kN of casing
    contact on node LE (inward cone normal, friction mu against the sliding): von Mises per kN (MPa) off the corner,
    outside the tip band and outside balls around node LE, and where the largest sit; near ``point`` (r, z, theta in
    mm, mm, deg); node LE's displacement per kN (its length and inward along the normal)."""
    from rotor37_rom import fem
    from rotor37_rom.post.stress import (ROOT_BAND, TIP_BAND, disk_stress_summary, root_distance, stress_location,
        tip_band)
    from rotor37_rom.dynamics.casing import Casing, contact_frames

    t0 = time.perf_counter()
    casing = Casing(direction="cone", mu=mu)
    le = sector.tip_names.index("LE")
    node = sector.tip_nodes[le]
    normal, slide, _ = contact_frames(node, casing.direction, casing.rotation_sense, casing.cone_slope)
    force = 1e3 * (-normal[0] - mu * slide[0])           # the casing pushes in; friction opposes the sliding
    f = np.zeros(sector.n_dofs)
    f[np.asarray(sector.tip_dofs[le])] = force
    closed = fem.RepeatingSectors(sector, 1)
    solve = fem.mumps_solver(closed.K)
    try:
        x = solve(closed.maps[0].T @ (closed.free * f))
    finally:
        solve.destroy()
    u = fem.displacement_function(sector, np.eye(sector.n_dofs, 1), np.zeros(1))
    u.x.array[:] = closed.fields(x)[0]
    vertex = fem.von_mises_at_vertices(sector, u, nonlinear=False)                  # (n_cells, 4)
    corners = fem.cell_vertices(sector)                                            # (n_cells, 4, 3)
    off_root = ~(root_distance(sector, corners) < ROOT_BAND).any(axis=1)
    band, _ = tip_band(sector, None)
    reach = np.linalg.norm(corners - node, axis=2)                                 # (n_cells, 4), m

    def largest(keep: np.ndarray) -> dict:
        cell, vert = np.unravel_index(int(np.argmax(np.where(keep[:, None], vertex, -np.inf))), vertex.shape)
        loc = stress_location(sector, None, int(cell), point=corners[cell, vert])
        return {"mpa_per_kn": float(vertex[cell, vert] / 1e6), "span": loc["span"], "z_mm": loc["z_mm"],
                "height_mm": loc["height_mm"], "from_le_mm": float(1e3 * reach[cell, vert])}

    clear = off_root & ~band
    u_le = u.x.array[np.asarray(sector.tip_dofs[le])]
    mid = fem.cell_midpoints(sector)
    row = {"force_n": force.tolist(), "le_displacement_mm_per_kn": float(1e3 * np.linalg.norm(u_le)),
           "le_inward_mm_per_kn": float(-1e3 * normal[0] @ u_le),
           "tip_band_radius_mm": float(1e3 * TIP_BAND * np.ptp(np.hypot(mid[:, 0], mid[:, 1]))),
           "map_point": {**near_point(corners, vertex, point), "point_r_z_theta": list(point)},
           "tip_band": largest(clear),
           "nearest_vertex_outside_band_mm": float(1e3 * reach[clear].min()),
           "balls": {f"{d:g}": largest(off_root & (reach.min(axis=1) > d * 1e-3)) for d in LOAD_BALLS_MM}}
    summary = disk_stress_summary(sector, None, vertex[None])       # the maps' number: the same cells
    if not np.isclose(summary["vm_max_off_root"] / 1e6, row["tip_band"]["mpa_per_kn"], rtol=1e-12):
        raise RuntimeError("the tip-band value differs from disk_stress_summary's")
    row["wall_s"] = time.perf_counter() - t0
    return row


def mode_stress(sector, point=MAP_POINT) -> dict:
    """One mesh: the 1B 0-diameter mode's stresses (MPa) at 1 mm at node LE and where the off-corner largest sits."""
    from rotor37_rom import fem
    from rotor37_rom.post.stress import disk_stress_summary, tip_band

    t0 = time.perf_counter()
    cyc = fem.CyclicOperators(sector)
    try:
        modes = cyc.modes(0, 1)
    finally:
        cyc.destroy()
    u = modes.a[0]
    u.x.array[:] *= 1e-3 / np.abs(u.x.array[np.asarray(sector.tip_dofs[0])]).max()
    vertex = fem.von_mises_at_vertices(sector, u, nonlinear=False)[None]              # (1, n_cells, 4)
    midpoint = fem.von_mises_function(sector, u, False, degree=0).x.array
    band, _ = tip_band(sector, None)
    row = {"n_cells": int(band.size),
           "frequency_hz": float(modes.omega[0] / (2 * np.pi)),
           "midpoint_mpa": float(np.where(band, -np.inf, midpoint).max() / 1e6), "off_root": {}}
    for d in BANDS_MM:               # the disk maps' summary (its sector's own tip nodes), with a band of d mm
        numbers = disk_stress_summary(sector, None, vertex, root_band=d * 1e-3)
        where = numbers["location_off_root"]
        row["off_root"][f"{d:g}"] = {"mpa": numbers["vm_max_off_root"] / 1e6, "z_mm": where["z_mm"],
                                     "height_mm": where["height_mm"], "span": where["span"]}
    row["corner_mpa"] = numbers["vm_max"] / 1e6
    row["map_point"] = {**near_point(fem.cell_vertices(sector), vertex[0], point), "point_r_z_theta": list(point)}
    row["corner_location"] = numbers["location"]           # the cell's centroid
    row["wall_s"] = time.perf_counter() - t0
    return row


def markdown(rows: list[dict]) -> str:
    finest = rows[-1]
    head = ("| element size | DOFs | 1B (k = 0) | at the corner | " +
            " | ".join(f"off the corner, > {d:g} mm" for d in BANDS_MM)
            + " | at the midpoints (DG0) | at the map's point |")
    lines = [head, "|" + "---|" * (6 + len(BANDS_MM))]
    for r in rows:
        offs = []
        for d in BANDS_MM:
            o = r["off_root"][f"{d:g}"]
            change = 100 * (o["mpa"] / finest["off_root"][f"{d:g}"]["mpa"] - 1)
            offs.append(f"{o['mpa']:.1f} ({change:+.1f} %; {o['height_mm']:.1f} mm up, z = {o['z_mm']:.1f} mm)")
        lines.append(f"| {r['size_mm']:g} mm | {r['n_dofs']:,} | {r['frequency_hz']:.2f} Hz | {r['corner_mpa']:.1f} | "
                     + " | ".join(offs) + f" | {r['midpoint_mpa']:.1f} | {r['map_point']['mpa']:.1f} |")
    return "\n".join(lines)


def markdown_contact(rows: list[dict]) -> str:
    """The contact case's table as in docs/results.md: per kN, the change against the finest mesh in brackets."""
    finest = rows[-1]["contact"]

    def change(value, ref):
        return f"{value:,.0f} ({100 * (value / ref - 1):+.1f} %)"

    head = ("| element size | node LE inward (mm per kN) | outside the tip band (MPa per kN) | "
            "where: from node LE, span | "
            + " | ".join(f"> {d:g} mm from node LE" for d in LOAD_BALLS_MM)
            + " | at the map's point: per kN | per mm of node LE inward |")
    lines = [head, "|" + "---|" * (6 + len(LOAD_BALLS_MM))]
    ref_mm = finest["map_point"]["mpa"] / finest["le_inward_mm_per_kn"]
    for r in rows:
        c = r["contact"]
        band = c["tip_band"]
        per_mm = c["map_point"]["mpa"] / c["le_inward_mm_per_kn"]
        lines.append(f"| {r['size_mm']:g} mm | {c['le_inward_mm_per_kn']:.2f} | "
                     f"{change(band['mpa_per_kn'], finest['tip_band']['mpa_per_kn'])} | "
                     f"{band['from_le_mm']:.1f} mm, {100 * band['span']:.0f} % | "
                     + " | ".join(change(c["balls"][f"{d:g}"]["mpa_per_kn"], finest["balls"][f"{d:g}"]["mpa_per_kn"])
                                  for d in LOAD_BALLS_MM)
                     + f" | {change(c['map_point']['mpa'], finest['map_point']['mpa'])} | {change(per_mm, ref_mm)} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=float, nargs="+", default=[12.0, 6.0, 3.0, 2.0, 1.5],
                        help="element sizes (mm), coarse to fine, each in [1, 20] (default 12 6 3 2 1.5)")
    parser.add_argument("--case", choices=CASES + ("both",), default="both",
                        help="the 1B mode (results/bench_disk_stress_convergence.json), the contact load at node LE "
                             "(..._contact.json) or both (default)")
    parser.add_argument("--point", type=float, nargs=3, default=list(MAP_POINT), metavar=("R", "Z", "THETA"),
                        help="where each case is also read (mm, mm, deg in the sector's frame; default the linear "
                             "disk map's largest off the corner)")
    args = parser.parse_args(argv)
    if any(not 1.0 <= s <= 20.0 for s in args.sizes):
        print(f"error: --sizes must each be in [1, 20] mm, got {args.sizes}", file=sys.stderr)
        return 2
    cases = CASES if args.case == "both" else (args.case,)
    rows = {case: [] for case in cases}
    for size in args.sizes:
        sector, t_mesh = disk_sector(size)
        common = {"size_mm": size, "n_dofs": sector.n_dofs, "mesh_s": t_mesh}
        if "mode" in cases:
            r = {**common, **mode_stress(sector, args.point)}
            rows["mode"].append(r)
            print(f"{size:g} mm: {r['n_dofs']} DOFs, {r['frequency_hz']:.2f} Hz, corner {r['corner_mpa']:.1f} MPa, "
                  f"off the corner (> 4 mm) {r['off_root']['4']['mpa']:.1f} MPa, midpoints {r['midpoint_mpa']:.1f} "
                  f"MPa; {r['wall_s']:.0f} s", flush=True)
        if "contact" in cases:
            r = {**common, "contact": contact_stress(sector, args.point)}
            rows["contact"].append(r)
            c = r["contact"]
            print(f"{size:g} mm: contact at LE, per kN: {c['le_displacement_mm_per_kn']:.3f} mm at LE; outside the "
                  f"tip band {c['tip_band']['mpa_per_kn']:.1f} MPa ({c['tip_band']['from_le_mm']:.1f} mm from LE), "
                  + ", ".join(f"> {d} mm {c['balls'][d]['mpa_per_kn']:.1f}" for d in c["balls"])
                  + f" MPa, at the map's point {c['map_point']['mpa']:.1f} MPa; {c['wall_s']:.0f} s", flush=True)
    if "mode" in cases:
        machine = write_results("bench_disk_stress_convergence", rows["mode"],
                                mode="the disk's lowest 0-diameter mode, 1 mm largest component at node LE, linear "
                                     "stress, outside the tip band (10 % of the span around the contact nodes)")
        print(f"{machine}\n\n{markdown(rows['mode'])}")
    if "contact" in cases:
        machine = write_results("bench_disk_stress_convergence_contact", rows["contact"],
                                load="1 kN of casing contact at node LE: the cone's inward normal and friction 0.15 "
                                     "against the sliding; static, 0 diameters, linear stress per kN, off the root "
                                     "corner (ROOT_BAND)")
        print(f"{machine}\n\n{markdown_contact(rows['contact'])}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
