"""The turning blade's reduced model against its full order from rest to 2,000 rad/s (#73): the frequency and
centrifugal-state errors of each candidate basis at every speed, and the cost of a speed in both
(``studies.rotating_rom.run_rotating_rom``).

The model carries the speed exactly (spin softening, centrifugal load, Coriolis: no fitted term); the candidates
differ by their bases: the full-order centrifugal states at 1,000 and 2,000 rad/s, and the same with the first 4 modes
of the blade turning at 2,000 rad/s.

    python benchmarks/bench_rotating_rom.py [--preset ci] [--speeds 0 2000 21]

Results: results/bench_rotating_rom.json (machine stated), results/rotating_rom/ (chart, summary.json).
"""
from __future__ import annotations

import argparse

import numpy as np

from rotor37_rom.machine import write_results
from rotor37_rom.studies.rotating_rom import RotatingRomConfig, run_rotating_rom


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--preset", default="ci", choices=["ci", "coarse"])
    parser.add_argument("--speeds", type=float, nargs=3, default=(0.0, 2000.0, 21), metavar=("START", "STOP", "N"))
    args = parser.parse_args(argv)
    try:
        config = RotatingRomConfig(preset=args.preset, speeds=tuple(args.speeds))
    except ValueError as exc:
        parser.exit(2, f"error: {exc}\n")
    result = run_rotating_rom(config)
    print(f"full order: {result.full_per_speed_s:.2f} s a speed (centrifugal state and {config.n_modes} modes)")
    rows = []
    for row in result.rows:
        worst = np.abs(row["frequency_error"]).max(axis=0)
        print(f"{row['label']} (r = {row['r']}, built in {row['build_s']:.0f} s): largest frequency error per mode "
              f"{', '.join(f'{x:.1e}' for x in worst)}; tip state {row['state_error'].max():.1e}; "
              f"{row['per_speed_s'] * 1e3:.1f} ms a speed ({result.full_per_speed_s / row['per_speed_s']:.0f}x)")
        rows.append({"label": row["label"], "r": row["r"], "max_frequency_error": worst.tolist(),
                     "max_state_error": float(row["state_error"].max()), "build_s": row["build_s"],
                     "per_speed_s": row["per_speed_s"], "full_per_speed_s": result.full_per_speed_s})
    machine = write_results("bench_rotating_rom", rows, speeds=result.speeds.tolist())
    print(f"machine: {machine}; chart and summary: {', '.join(str(f) for f in result.files)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
