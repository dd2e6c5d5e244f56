"""Mesh convergence of the bladed-disk sector's stress (issue #21, item 4): the sharp blade-rim corner against the
stress off it, on the disk's 1B mode.

The disk sector of the maps has no root fillet: the blade meets the rim at a re-entrant corner, where the elastic
stress is singular (a 270-degree wedge: sigma ~ rho^(lambda - 1), lambda = 0.5445, Williams 1952), so its largest FE
value does not converge under refinement. This script meshes the ci sector at element sizes from the ci preset's
12 mm down to 1.5 mm (the LE/TE refinement kept at min(2 mm, size)), computes the full-order lowest 0-diameter mode
(the 1B family, every blade alike: the shape the contact maps' responses are built of) scaled to 1 mm of largest
displacement component at node LE, and reports its linear von Mises stress outside the tip band:
- at the corner: the largest at the cells' vertices anywhere (``fem.von_mises_at_vertices``);
- off the corner: the largest at the vertices of the cells farther than d from the blade-rim junction (every cell
  with a vertex within d left out; ``fem.root_junction``), d = 2, 4 (``analysis.ROOT_BAND``, what the disk maps
  report) and 8 mm, and where it sits;
- the largest at the cells' midpoints (DG0, what the disk maps reported before: a midpoint misses the surface's
  bending stress on a coarse mesh).

    python benchmarks/bench_disk_stress_convergence.py                 # 12, 6, 3, 2, 1.5 mm: ~4 min on 2 cores
    python benchmarks/bench_disk_stress_convergence.py --sizes 12 3     # a quick look

Results to results/bench_disk_stress_convergence.json and a Markdown table (docs/results.md).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import write_results  # noqa: E402

BANDS_MM = (2.0, 4.0, 8.0)


def mode_stress(size_mm: float) -> dict:
    """One mesh: the 1B 0-diameter mode's stresses (MPa) at 1 mm at node LE and where the off-corner largest sits."""
    from mpi4py import MPI

    from rotor37_rom import fem
    from rotor37_rom.analysis import disk_stress_summary, tip_band
    from rotor37_rom.geometry.blade import MeshPreset

    t0 = time.perf_counter()
    preset = MeshPreset(f"h{size_mm:g}mm", size=size_mm * 1e-3, curvature_points=0,
                        min_size=min(2.0, size_mm) * 1e-3)
    sector = fem.create_disk_sector(MPI.COMM_SELF, preset=preset)
    t_mesh = time.perf_counter() - t0
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
    row = {"size_mm": size_mm, "n_dofs": sector.n_dofs, "n_cells": int(band.size),
           "frequency_hz": float(modes.omega[0] / (2 * np.pi)),
           "midpoint_mpa": float(np.where(band, -np.inf, midpoint).max() / 1e6), "off_root": {}}
    for d in BANDS_MM:               # the disk maps' summary (its sector's own tip nodes), with a band of d mm
        numbers = disk_stress_summary(sector, None, vertex, root_band=d * 1e-3)
        where = numbers["location_off_root"]
        row["off_root"][f"{d:g}"] = {"mpa": numbers["vm_max_off_root"] / 1e6, "z_mm": where["z_mm"],
                                     "height_mm": where["height_mm"], "span": where["span"]}
    row["corner_mpa"] = numbers["vm_max"] / 1e6
    row["corner_location"] = numbers["location"]           # the cell's centroid
    row["wall_s"] = time.perf_counter() - t0
    row["mesh_s"] = t_mesh
    return row


def markdown(rows: list[dict]) -> str:
    finest = rows[-1]
    head = ("| element size | DOFs | 1B (k = 0) | at the corner | " +
            " | ".join(f"off the corner, > {d:g} mm" for d in BANDS_MM) + " | at the midpoints (DG0) |")
    lines = [head, "|" + "---|" * (5 + len(BANDS_MM))]
    for r in rows:
        offs = []
        for d in BANDS_MM:
            o = r["off_root"][f"{d:g}"]
            change = 100 * (o["mpa"] / finest["off_root"][f"{d:g}"]["mpa"] - 1)
            offs.append(f"{o['mpa']:.1f} ({change:+.1f} %; {o['height_mm']:.1f} mm up, z = {o['z_mm']:.1f} mm)")
        lines.append(f"| {r['size_mm']:g} mm | {r['n_dofs']:,} | {r['frequency_hz']:.2f} Hz | {r['corner_mpa']:.1f} | "
                     + " | ".join(offs) + f" | {r['midpoint_mpa']:.1f} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=float, nargs="+", default=[12.0, 6.0, 3.0, 2.0, 1.5],
                        help="element sizes (mm), coarse to fine, each in [1, 20] (default 12 6 3 2 1.5)")
    args = parser.parse_args(argv)
    if any(not 1.0 <= s <= 20.0 for s in args.sizes):
        print(f"error: --sizes must each be in [1, 20] mm, got {args.sizes}", file=sys.stderr)
        return 2
    rows = []
    for size in args.sizes:
        rows.append(mode_stress(size))
        r = rows[-1]
        print(f"{size:g} mm: {r['n_dofs']} DOFs, {r['frequency_hz']:.2f} Hz, corner {r['corner_mpa']:.1f} MPa, off "
              f"the corner (> 4 mm) {r['off_root']['4']['mpa']:.1f} MPa, midpoints {r['midpoint_mpa']:.1f} MPa; "
              f"{r['wall_s']:.0f} s", flush=True)
    machine = write_results("bench_disk_stress_convergence", rows,
                            mode="the disk's lowest 0-diameter mode, 1 mm largest component at node LE, linear "
                                 "stress, outside the tip band (10 % of the span around the contact nodes)")
    print(f"{machine}\n\n{markdown(rows)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
