"""The turning bladed disk's reduced model against the full order from rest to 2,000 rad/s (#73): the lowest frequency
of each nodal-diameter family in both, their relative difference, and the cost of a speed
(``studies.rotating_disk_rom.run_rotating_disk_rom``).

The model: the ci disk sector, node LE kept, r_c = 8, 4 modal derivatives, 96 interface modes, with the whole disk's
centrifugal states at 1,000 and 2,000 rad/s (index-0 interface modes and sector columns) and the first 4 modes of the
sector turning at 2,000 rad/s in its basis. The full order: the prestressed, spin-softened cyclic sector.

    python benchmarks/bench_rotating_disk_rom.py [--speeds 0 2000 5] [--no-spin-modes]

Results: results/bench_rotating_disk_rom.json (machine stated), results/rotating_disk_rom/ (chart, summary.json).
"""
from __future__ import annotations

import argparse

import numpy as np

from rotor37_rom.machine import write_results
from rotor37_rom.studies.rotating_disk_rom import RotatingDiskRomConfig, run_rotating_disk_rom


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--speeds", type=float, nargs=3, default=(0.0, 2000.0, 5), metavar=("START", "STOP", "N"))
    parser.add_argument("--no-spin-modes", action="store_true", help="the centrifugal states alone in the basis")
    args = parser.parse_args(argv)
    try:
        config = RotatingDiskRomConfig(speeds=tuple(args.speeds), spin_modes=0 if args.no_spin_modes else 4)
    except ValueError as exc:
        parser.exit(2, f"error: {exc}\n")
    result = run_rotating_disk_rom(config)
    rows = []
    for i, spin in enumerate(result.speeds):
        worst = np.nanmax(np.abs(result.error[i]))
        lowest = ", ".join(f"k{k} {w:.0f}" for k, w in zip(result.families, result.full[i]))
        print(f"{spin:6.0f} rad/s: lowest per family {lowest} rad/s; the model within {worst:.1e}")
        rows.append({"speed": float(spin), "full_rad_s": result.full[i].tolist(),
                     "reduced_rad_s": result.reduced[i].tolist(), "max_error": float(worst)})
    print(f"r = {result.r} (built in {result.build_s:.0f} s); a speed: {result.reduced_s:.2f} s reduced against "
          f"{result.full_s:.1f} s full order ({len(result.families)} families)")
    machine = write_results("bench_rotating_disk_rom", rows, families=result.families.tolist(), r=result.r,
                            reduced_per_speed_s=result.reduced_s, full_per_speed_s=result.full_s)
    print(f"machine: {machine}; {', '.join(str(f) for f in result.files)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
