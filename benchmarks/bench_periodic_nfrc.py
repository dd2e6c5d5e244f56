"""The single blade's GNL NFRC by periodic orbits through 1B/EO4 against its 100-speed x 200-revolution map on the
same model, in one run (#72; ``studies.periodic_cost.nfrc_against_map``).

The headline map's model and recipe (docs/results-maps.md, "GNL headline map"): the ci blade, r = 55 (r_c = 25),
point cubature trained to 1e-4 (float32 in the map, float64 for the orbits), 120 kHz frequency cap, mu = 0, the
paper's casing, 1,200-1,600 rad/s. The orbits: shooting the map's scheme, arc length from 1,200 rad/s (relative step
--step), Floquet multipliers at every point. The map: a batch of 50 of its speeds run one revolution, scaled to its
100 speeds x 200 revolutions (retries left out, two ranks counted at twice one's speed).

    python benchmarks/bench_periodic_nfrc.py [--r-c 25 | --model ROM.npz] [--step 0.02] [--range LOW HIGH]
        [--out OUT] [--cache DIR] [--check]

The cubature's training (6 exact GNL runs x 12 revolutions, ~10 min) is cached in OUT/cache and not counted: the map
and the orbits share it. Results: results/bench_periodic_nfrc.json (machine stated), the chart in OUT.

Every option is checked, and the folders written in and the model read, before any work: a bad one is one line on
stderr and exit status 2. ``--check`` does only that and says what would run (exit status 0); SIGTERM or SIGINT stop
the run with one line (``rotor37_rom.cli.run_main``): run the same command again to resume from the caches.
"""
from __future__ import annotations

import sys
from pathlib import Path
from typing import Sequence

from rotor37_rom.checks import before_work, real_number, whole_number, writable_folder
from rotor37_rom.cli import ArgumentParser, run_main

R_C = 25                         # the headline map's model: r = 55
MAX_POINTS = 10_000              # orbits of the branch at most (each a shooting Newton: seconds to minutes)
RESULTS = "results/bench_periodic_nfrc.json"


def build_parser() -> ArgumentParser:
    parser = ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--r-c", type=int, default=None,
                        help=f"fixed-interface modes of the ci blade's model built here (>= 1; default {R_C}: r = 55, "
                             f"the headline map's); not with --model")
    parser.add_argument("--model", type=Path, default=None,
                        help="a saved reduced model of a blade with GNL forces (.npz, e.g. a map's rom.npz) instead "
                             "of building one")
    parser.add_argument("--step", type=float, default=0.02,
                        help="relative arc-length step of the orbits' continuation, in (0, 0.5] (default 0.02)")
    parser.add_argument("--speeds", type=float, nargs=3, default=(1200.0, 1600.0, 100), metavar=("START", "STOP", "N"),
                        help="the map whose cost is estimated: N speeds (rad/s) from START to STOP (0 < START <= STOP "
                             "<= 1e5, N in 1..10000; default 1200 1600 100)")
    parser.add_argument("--revolutions", type=float, default=200.0,
                        help="the map's revolutions per speed (> 0; default 200)")
    parser.add_argument("--max-points", type=int, default=400,
                        help=f"orbits of the branch at most, 2..{MAX_POINTS} (default 400)")
    parser.add_argument("--range", type=float, nargs=2, default=None, metavar=("LOW", "HIGH"),
                        help="the orbits' speeds (rad/s, 0 < LOW < HIGH <= 1e5; default the map's): Newton's start "
                             "at LOW")
    parser.add_argument("--out", type=Path, default=Path("results/bench_periodic_nfrc"),
                        help="folder of the chart (and of the caches without --cache; default "
                             "results/bench_periodic_nfrc)")
    parser.add_argument("--cache", type=Path, default=None,
                        help="the caches' folder: the model, the cubature, the probe (default OUT/cache)")
    return parser


def configuration(args):
    """The map's configuration of the options (``ContactMapConfig``), every option checked (ValueError naming it),
    and the saved model's kind: a blade's, with GNL forces."""
    from rotor37_rom.studies.contact_config import MAX_SPEED, saved_model_info
    from rotor37_rom.studies.contact_map import ContactMapConfig

    if args.model is not None and args.r_c is not None:
        raise ValueError("--r-c builds the model: not with --model (the saved model is read as it is)")
    real_number("--step (the relative arc-length step of the orbits)", args.step, 0, 0.5, open_low=True)
    whole_number("--max-points", args.max_points, 2, MAX_POINTS)
    if args.range is not None:                 # the configuration's --continuation-range, named as given here
        for value in args.range:
            real_number("--range (LOW, HIGH)", value, 0, MAX_SPEED, open_low=True, unit=" rad/s")
        if not args.range[0] < args.range[1]:
            raise ValueError(f"--range must be 0 < LOW < HIGH <= {MAX_SPEED:g} rad/s, got {args.range[0]:g} "
                             f"{args.range[1]:g}")
    r_c = None if args.model is not None else R_C if args.r_c is None else args.r_c
    config = ContactMapConfig.from_options(model=args.model, r_c=r_c, speeds=tuple(args.speeds),
                                           revolutions=args.revolutions, gnl="on", mu=0.0, frequency_cap=120.0,
                                           cubature=1e-4, precision="single", periodic=args.step,
                                           continuation_range=args.range, out=args.out, cache=args.cache, quiet=False)
    if args.model is not None:
        info = saved_model_info("--model", args.model)
        if info["disk"]:
            raise ValueError(f"--model: {args.model} is a bladed disk's model ({info['n_sectors']} sectors); the "
                             f"periodic orbits by shooting take a blade's")
        if info["forces"] == "none":
            raise ValueError(f"--model: {args.model} is a linear model (no GNL forces); the NFRC is the GNL map's")
    return config


def main(argv: Sequence[str] | None = None) -> int:
    """Check the options, say what runs, then the orbits and the map's cost; raises ValueError for a bad input."""
    args = build_parser().parse_args(argv)
    config = configuration(args)
    folders = {"--out": config.out, "--cache": config.cache_dir, f"{RESULTS}'s folder": Path(RESULTS).parent}
    for option, folder in folders.items():                    # refused before the plan is said; created below
        writable_folder(option, folder, create=False)
    low, high = config.continuation_span
    start, stop, n = config.speeds
    model = (f"the saved model {args.model}" if args.model is not None else
             f"the ci blade's model built with r_c = {config.rom.r_c} (cached in {config.cache_dir})")
    print(f"bench_periodic_nfrc: the GNL NFRC by periodic orbits over {low:g}-{high:g} rad/s (relative step "
          f"{args.step:g}, at most {args.max_points} orbits) against the cost of the map of {n} speeds x "
          f"{config.sweep.revolutions:g} revolutions over {start:g}-{stop:g} rad/s, on {model}; writes {RESULTS} and "
          f"{config.out}/nfrc_periodic_gnl.png", flush=True)
    before_work(folders, {"--model": args.model})             # before any work; a dry run stops here

    from rotor37_rom.machine import write_results
    from rotor37_rom.studies.periodic_cost import nfrc_against_map
    from rotor37_rom.viz.charts import plot_periodic_nfrc

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
          f"period); the map ({n:g} speeds x {config.sweep.revolutions:g} rev, h = {cost.h:.3g} s): "
          f"{cost.map_steps:.3g} simulation steps at {1e6 * cost.map_probe_s / cost.map_probe_steps:.1f} us "
          f"(batch of {cost.map_batch}) = {cost.map_serial_s / 60:.1f} min on one process, {cost.map_s / 60:.1f} "
          f"on {cost.map_ranks}; " + ("no orbit: no ratio" if cost.ratio is None else f"ratio {cost.ratio:.1f}"))
    if len(branch.speeds):
        config.out.mkdir(parents=True, exist_ok=True)
        plot_periodic_nfrc(branch, config.out / "nfrc_periodic_gnl.png", None, None,
                           "GNL, mu = 0, 120 kHz cap: periodic orbits of the map's scheme (shooting)")
    machine = write_results("bench_periodic_nfrc", [cost.summary()], speeds=list(config.speeds),
                            revolutions=config.sweep.revolutions, step=args.step)
    print(f"machine: {machine}")
    return 0


if __name__ == "__main__":
    sys.exit(run_main(main))
