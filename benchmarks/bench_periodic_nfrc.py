"""The single blade's GNL NFRC by periodic orbits through 1B/EO4 against its 100-speed x 200-revolution map on the
same model, in one run (#72; ``studies.periodic_cost.nfrc_against_map``).

The headline map's model and recipe (docs/results-maps.md, "GNL headline map"): the ci blade, r = 55 (r_c = 25),
point cubature trained to 1e-4 (float32 in the map, float64 for the orbits), 120 kHz frequency cap, mu = 0, the
paper's casing, 1,200-1,600 rad/s. The orbits: shooting the map's scheme, arc length from 1,200 rad/s (relative step
--step), Floquet multipliers at every point. The map: a batch of 50 of its speeds run one revolution, scaled to its
100 speeds x 200 revolutions (retries left out, two ranks counted at twice one's speed).

    python benchmarks/bench_periodic_nfrc.py [--r-c 25] [--step 0.02] [--model ROM.npz] [--range LOW HIGH] [--out OUT]
        [--cache DIR]

The cubature's training (6 exact GNL runs x 12 revolutions, ~10 min) is cached in OUT/cache and not counted: the map
and the orbits share it. Results: results/bench_periodic_nfrc.json (machine stated), the chart in OUT.
"""
from __future__ import annotations

import argparse
from pathlib import Path

from rotor37_rom.machine import write_results
from rotor37_rom.studies.contact_map import ContactMapConfig
from rotor37_rom.studies.periodic_cost import nfrc_against_map
from rotor37_rom.viz.charts import plot_periodic_nfrc


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--r-c", type=int, default=25)
    parser.add_argument("--model", type=Path, default=None, help="a saved reduced model instead of building one")
    parser.add_argument("--step", type=float, default=0.02, help="relative arc-length step of the orbits")
    parser.add_argument("--speeds", type=float, nargs=3, default=(1200.0, 1600.0, 100), metavar=("START", "STOP", "N"))
    parser.add_argument("--revolutions", type=float, default=200.0)
    parser.add_argument("--max-points", type=int, default=400)
    parser.add_argument("--range", type=float, nargs=2, default=None, metavar=("LOW", "HIGH"),
                        help="the orbits' speeds (rad/s; default the map's): Newton's start at LOW")
    parser.add_argument("--out", type=Path, default=Path("results/bench_periodic_nfrc"))
    parser.add_argument("--cache", type=Path, default=None, help="the caches' folder (default OUT/cache)")
    args = parser.parse_args(argv)
    try:
        if not 0 < args.step <= 0.5:
            raise ValueError(f"--step (the relative arc-length step) must be in (0, 0.5], got {args.step:g}")
        config = ContactMapConfig.from_options(model=args.model, r_c=None if args.model else args.r_c,
                                               speeds=tuple(args.speeds), revolutions=args.revolutions, gnl="on",
                                               mu=0.0, frequency_cap=120.0, cubature=1e-4, precision="single",
                                               periodic=args.step, continuation_range=args.range, out=args.out, cache=args.cache,
                                               quiet=False)
        if args.max_points < 2:
            raise ValueError(f"--max-points must be >= 2, got {args.max_points}")
    except ValueError as exc:
        parser.exit(2, f"error: {exc}\n")
    count = []

    def progress(point):
        count.append(point.omega / 2)
        if len(count) % 10 == 0:
            print(f"  {len(count)} orbits, at {point.omega / 2:.1f} rad/s ({'stable' if point.stable else 'unstable'})",
                  flush=True)

    cost = nfrc_against_map(config, max_points=args.max_points, progress=progress)
    branch = cost.branch
    print(branch.describe())
    print(f"NFRC by periodic orbits: {branch.wall_s:.0f} s ({len(branch.speeds)} points, {branch.steps} steps a "
          f"period); the map ({config.speeds[2]:g} speeds x {args.revolutions:g} rev, h = {cost.h:.3g} s): "
          f"{cost.map_steps:.3g} simulation steps at {1e6 * cost.map_probe_s / cost.map_probe_steps:.1f} us "
          f"(batch of {cost.map_batch}) = {cost.map_serial_s / 60:.1f} min on one process, {cost.map_s / 60:.1f} "
          f"on {cost.map_ranks}; " + ("no orbit: no ratio" if cost.ratio is None else f"ratio {cost.ratio:.1f}"))
    if len(branch.speeds):
        args.out.mkdir(parents=True, exist_ok=True)
        plot_periodic_nfrc(branch, args.out / "nfrc_periodic_gnl.png", None, None,
                           "GNL, mu = 0, 120 kHz cap: periodic orbits of the map's scheme (shooting)")
    machine = write_results("bench_periodic_nfrc", [cost.summary()], speeds=list(config.speeds),
                            revolutions=args.revolutions, step=args.step)
    print(f"machine: {machine}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
