"""The blade's interaction map turning against at rest through 1B/EO4 (#73): each map's largest response beside the
turning blade's 1B/EO4 crossing, and the cost of a speed turning against at rest in the same run
(``studies.turning_map.run_turning_comparison``).

One turning reduced model of the ci blade (r_c = 15, 3 global modal derivatives, the centrifugal states at 950 and
1,900 rad/s and the first 4 modes turning at 1,900 rad/s: r = 51) runs the map GNL off and on, turning (the clearance
from the running blade) and at rest, 60 kHz frequency cap, the paper's casing (c0 = 0.5 mm, h_b = 0.625 mm, mu = 0.15).

    python benchmarks/bench_rotating_map.py [--speeds 1300 1900 25] [--revolutions 20] [--out OUT]
    python benchmarks/bench_rotating_map.py --disk --r-c 4 --r-md 2 --r-cyclic 36 --speeds 1750 1850 3 --revolutions 2

With --disk: the 36-sector bladed disk (GNL on, the casing cone's normal; its centrifugal states and 4 turning
modes in the basis; ``DiskReductionConfig(spin_snapshots=...)``).

Results: results/bench_rotating_map[_disk].json (machine stated), and the comparison's charts, summary.json and
turning_comparison.json in --out.
"""
from __future__ import annotations

import argparse
from pathlib import Path

from rotor37_rom.machine import write_results
from rotor37_rom.studies.contact_map import ContactMapConfig
from rotor37_rom.studies.turning_map import engine_order_crossing, run_turning_comparison


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--speeds", type=float, nargs=3, default=(1300.0, 1900.0, 25), metavar=("START", "STOP", "N"))
    parser.add_argument("--revolutions", type=float, default=20.0)
    parser.add_argument("--gnl", choices=["off", "on", "both"], default="both")
    parser.add_argument("--out", type=Path, default=None, help="default results/bench_rotating_map[_disk]")
    parser.add_argument("--disk", action="store_true", help="the bladed disk (GNL on, cone normal)")
    parser.add_argument("--r-c", type=int, default=None)
    parser.add_argument("--r-md", type=int, default=None)
    parser.add_argument("--r-cyclic", type=int, default=144)
    args = parser.parse_args(argv)
    disk = {"disk": True, "gnl": "on", "direction": "cone", "r_cyclic": args.r_cyclic} if args.disk else {}
    out = args.out or Path("results/bench_rotating_map" + ("_disk" if args.disk else ""))
    try:
        config = ContactMapConfig.from_options(**{"rotation": "running", "speeds": tuple(args.speeds),
                                                  "revolutions": args.revolutions, "gnl": args.gnl,
                                                  "frequency_cap": 60.0, "out": out, "quiet": True,
                                                  "r_c": args.r_c, "r_md": args.r_md, **disk})
    except ValueError as exc:
        parser.exit(2, f"error: {exc}\n")
    result = run_turning_comparison(config)
    crossing = engine_order_crossing(result.campbell)
    rows = []
    for label, (speed, _) in result.peaks.items():
        run = {**result.rest.summary["runs"], **result.turning.summary["runs"]}[label]
        print(f"{label}: largest response {speed:.0f} rad/s ({run['peak_amplitude'] * 1e3:.3f} mm), "
              f"{len(run['diverged'])} speeds diverged, h = {run['h']:.3g} s")
        rows.append({"label": label, "peak_speed": speed, "peak_amplitude": run["peak_amplitude"],
                     "diverged": run["diverged"], "h": run["h"], "compute_s": run["compute_s"]})
    for setting, cost in result.cost.items():
        print(f"{setting}: {cost['turning_s']:.2f} s a speed turning against {cost['rest_s']:.2f} s at rest "
              f"(ratio {cost['ratio']:.2f})")
    machine = write_results("bench_rotating_map" + ("_disk" if args.disk else ""), rows, crossing_1B_EO4=crossing,
                            cost_per_speed=result.cost,
                            speeds=list(config.speeds), revolutions=config.sweep.revolutions)
    print(f"1B/EO4 turning: {crossing:.1f} rad/s; machine: {machine}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
