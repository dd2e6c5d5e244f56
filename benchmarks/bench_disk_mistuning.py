"""Mistuning of the bladed disk in contact (issue #21, item 5; the paper's disk is tuned): how the largest response over
the blades and its localisation on one blade change with the blade-to-blade stiffness scatter.

The contact maps' disk model (ci preset, every sector's 8 tip nodes, r_c = 10, r_MD = 10 by MI 2b, r_cyclic = 144: r =
1,728) with each sector's stiffness and SVK force scaled by its own factor (``disk.assembly.mistuning_factors``:
log-normal, mean 1, standard deviation sigma, seeded), all 36 x 8 tip nodes against the casing (cone normal, mu = 0.15),
60 kHz cap, GNL off (a mistuned disk's operators are not block-circulant: the dense step) or on (--gnl: exact sector
tensors at --h). Each speed runs from rest for --revolutions through ``studies.sweep.run_sweep`` (resumable).

Per sigma, seed and speed: node LE's max over the last revolution on every blade; the largest over the blades and
which blade; its ratio to the tuned disk's largest at the same speed (the amplification); and the localisation, the
largest blade's amplitude over the RMS of the 36 (1 when every blade moves alike, as in a tuned disk's travelling
wave; 6 = sqrt(36) when one blade carries all).

    python benchmarks/bench_disk_mistuning.py [--sigma 0 0.01 0.03 0.05] [--seeds 0] [--speeds 1256 1453 1554]
                                              [--revolutions 200] [--gnl --h 1.15e-6]
    python benchmarks/bench_disk_mistuning.py --sigma 0.05 --seeds 1 2 3     # more disks of one scatter

Results: results/bench_disk_mistuning[_gnl].json (machine stated), which keeps the rows of earlier runs with the same
preset, speeds, revolutions, friction, cap and step (another seed adds to the disks of its sigma; runs of other seeds
may go on side by side: the file is read and written under a lock); per sigma over its seeds
(disks), the amplification's mean and largest and the localisation's, and where the largest blade sits in the
ranking of the stiffness factors. The sweeps in results/bench_disk_mistuning/.

Every option is checked, and the folders written in, before any work: a bad one is one line on stderr and exit
status 2. ``--check`` does only that (exit status 0); SIGTERM or SIGINT stop the run with one line
(``rotor37_rom.cli.run_main``).
"""
from __future__ import annotations

import fcntl
import sys
import time
from pathlib import Path
from typing import Sequence

import numpy as np

from rotor37_rom.checks import before_work, fits_in_memory, real_number, whole_number
from rotor37_rom.cli import ArgumentParser, run_main

MAX_SPEED = 1e5                  # rad/s: the map command's (studies.contact_config.MAX_SPEED)
MAX_SPEEDS = 100                 # speeds at most (one batch: all of them integrated together)
MAX_SEED = 2 ** 32 - 1
N_SECTORS = 36
ROWS = N_SECTORS + 8 * N_SECTORS     # what a record holds per run: node LE of every sector, the 288 contact forces
RECORD_DT = 1e-5                 # s: the sweep's sampling (studies.sweep.SweepSpec.record_dt)
H_GNL = 1.15e-6                  # s: the GNL step's default (the short GNL map's)
OUT = Path("results/bench_disk_mistuning")


def build_parser() -> ArgumentParser:
    p = ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--preset", default="ci", choices=["ci", "coarse"], help="mesh preset of the disk sector "
                   "(default ci)")
    p.add_argument("--sigma", type=float, nargs="+", default=[0.0, 0.01, 0.03, 0.05],
                   help="standard deviations of the blades' stiffness factors, each in [0, 1) (0: tuned; the tuned "
                        "disk always runs; default 0 0.01 0.03 0.05)")
    p.add_argument("--seeds", type=int, nargs="+", default=None,
                   help=f"seeds of the mistuning factors, each in 0..{MAX_SEED} (default 0); needs a --sigma > 0")
    p.add_argument("--speeds", type=float, nargs="+", default=[1256.0, 1453.0, 1554.0],
                   help=f"angular speeds (rad/s), each in (0, {MAX_SPEED:g}], at most {MAX_SPEEDS} (default 1256 1453 "
                        f"1554: one in each band of large response of the tuned map: the k = 5 band's largest, the "
                        f"1B/EO4 branch above its jump, its upper part)")
    p.add_argument("--revolutions", type=float, default=200.0,
                   help="per speed, from rest, in (0, 1000] and within this machine's memory (default 200)")
    p.add_argument("--gnl", action="store_true", help="geometric nonlinearity (exact sector tensors at --h)")
    p.add_argument("--h", type=float, default=None,
                   help=f"with --gnl: the GNL step (s), in (0, 1e-4) (default {H_GNL:g})")
    p.add_argument("--cap", type=float, default=60.0, help="frequency cap (kHz), in [5, 500] (default 60)")
    p.add_argument("--mu", type=float, default=0.15, help="friction coefficient, in [0, 2] (default 0.15)")
    return p


def check_options(args) -> None:
    """Every option checked (ValueError naming it and its range); the defaults of --seeds and --h filled in."""
    for sigma in args.sigma:
        real_number("--sigma (standard deviations of the stiffness factors)", sigma, 0, 1, open_high=True)
    if args.seeds is not None and not any(s > 0 for s in args.sigma):
        raise ValueError("--seeds needs a --sigma > 0 (they seed the mistuning's random factors; the tuned disk has "
                         "none)")
    args.seeds = [0] if args.seeds is None else args.seeds
    for seed in args.seeds:
        whole_number("--seeds", seed, 0, MAX_SEED)
    for w in args.speeds:
        real_number("--speeds", w, 0, MAX_SPEED, open_low=True, unit=" rad/s")
    if len(args.speeds) > MAX_SPEEDS:
        raise ValueError(f"--speeds: at most {MAX_SPEEDS} speeds, got {len(args.speeds)}")
    real_number("--revolutions", args.revolutions, 0, 1000, open_low=True)
    if args.h is not None and not args.gnl:
        raise ValueError("--h is the GNL step: it needs --gnl (without it the step is the linear model's)")
    args.h = H_GNL if args.h is None else args.h
    real_number("--h (the GNL step)", args.h, 0, 1e-4, open_low=True, open_high=True, unit=" s")
    real_number("--cap", args.cap, 5, 500, unit=" kHz")
    real_number("--mu", args.mu, 0, 2)
    records = args.revolutions * 2 * np.pi / min(args.speeds) / RECORD_DT + 1
    batch = len(args.speeds)
    fits_in_memory("--revolutions", 8.0 * ROWS * records * batch,
                   f"{batch} runs x {records:.3g} records x {ROWS} values, at {min(args.speeds):g} rad/s",
                   hint="fewer revolutions or speeds")


def main(argv: Sequence[str] | None = None) -> int:
    """Check the options, then the tuned and mistuned disks' sweeps and their statistics; raises ValueError for a bad
    input."""
    args = build_parser().parse_args(argv)
    check_options(args)
    before_work({"the sweeps' folder": OUT, "the model cache": Path("results/cache"),
                 "the results folder": Path("results")})          # before any work; a dry run stops here

    from rotor37_rom import fem
    from rotor37_rom.disk.assembly import mistuning_factors
    from rotor37_rom.dynamics.casing import Casing
    from rotor37_rom.dynamics.explicit import CentralDifference
    from rotor37_rom.machine import write_results
    from rotor37_rom.reduction.disk_builder import DiskReductionConfig, build_disk_model
    from rotor37_rom.studies.mistuning import blade_amplitudes, earlier_rows, over_seeds
    from rotor37_rom.studies.sweep import SweepSpec, run_sweep

    cap = 2 * np.pi * 1e3 * args.cap
    casing = Casing(mu=args.mu, direction="cone")
    sector = fem.create_disk_sector(preset=args.preset)
    base = dict(tip_nodes="all", r_c=10, r_md=10, criterion="MI2b", r_cyclic=144)
    rows, tuned = [], None
    disks = [(0.0, 0)] + [(s, seed) for s in args.sigma if s > 0 for seed in args.seeds]
    N = N_SECTORS
    for sigma, seed in disks:
        factors = None if sigma == 0 else tuple(mistuning_factors(N, sigma, seed).tolist())
        t0 = time.perf_counter()
        model, _ = build_disk_model(sector, DiskReductionConfig(**base, mistuning=factors),
                                    cache_dir=Path("results/cache"))
        offline = time.perf_counter() - t0
        monitor = tuple(model.nodes.row("LE", s) for s in range(N))
        spec = SweepSpec(revolutions=args.revolutions, casing=casing, monitor=monitor, batch_size=len(args.speeds))
        scheme = (CentralDifference(model, nonlinear=True, h=args.h, frequency_cap=cap) if args.gnl else
                  CentralDifference(model, nonlinear=False, safety=0.5, frequency_cap=cap))
        t0 = time.perf_counter()
        folder = run_sweep(scheme, args.speeds, spec, OUT)
        wall = time.perf_counter() - t0
        amp = blade_amplitudes(folder, args.speeds)
        largest = np.nanmax(amp, axis=1)
        if tuned is None:
            tuned = largest
        rms = np.sqrt(np.nanmean(amp ** 2, axis=1))
        row = {"sigma": sigma, "seed": seed, "factors": None if factors is None else list(factors), "h": scheme.h,
               "offline_s": offline, "wall_s": wall, "speeds": args.speeds,
               "largest_m": largest.tolist(), "largest_blade": np.nanargmax(amp, axis=1).tolist(),
               "le0_m": amp[:, 0].tolist(), "amplification": (largest / tuned).tolist(),
               "localisation": (largest / rms).tolist(), "blades_m": amp.tolist()}
        rows.append(row)
        print(f"sigma {sigma:.3f} seed {seed}: largest " + " ".join(f"{1e3 * a:.3f}" for a in largest)
              + " mm (blades " + " ".join(map(str, row["largest_blade"])) + "), amplification "
              + " ".join(f"{x:.2f}" for x in row["amplification"]) + ", localisation "
              + " ".join(f"{x:.2f}" for x in row["localisation"]) + f"  ({wall:.0f} s)", flush=True)
    name = "bench_disk_mistuning" + ("_gnl" if args.gnl else "")
    settings = dict(preset=args.preset, speeds=args.speeds, revolutions=args.revolutions, mu=args.mu, cap_khz=args.cap,
                    gnl=args.gnl, h=args.h if args.gnl else None)
    Path("results").mkdir(exist_ok=True)
    with open(f"results/{name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)               # another seed's run may be writing the file
        rows = sorted(earlier_rows(Path(f"results/{name}.json"), settings, rows) + rows,
                      key=lambda r: (r["sigma"], r["seed"]))
        stats = over_seeds(rows)
        machine = write_results(name, rows, over_seeds=stats, **settings)
    for st in stats:
        print(f"sigma {st['sigma']:.3f} over {len(st['seeds'])} disks (seeds {st['seeds']}): amplification mean "
              + " ".join(f"{x:.2f}" for x in st["amplification_mean"]) + ", largest "
              + " ".join(f"{x:.2f}" for x in st["amplification_max"]) + "; localisation mean "
              + " ".join(f"{x:.2f}" for x in st["localisation_mean"]) + ", largest "
              + " ".join(f"{x:.2f}" for x in st["localisation_max"]) + "; the largest blade's stiffness rank (0: "
              "softest of 36) " + "; ".join(" ".join(map(str, r)) for r in st["largest_blade_stiffness_rank"]))
    print(f"results/{name}.json ({machine}); speeds {args.speeds} rad/s")
    return 0


if __name__ == "__main__":
    sys.exit(run_main(main))
