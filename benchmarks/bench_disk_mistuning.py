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
"""
from __future__ import annotations

import argparse
import fcntl
import sys
import time
from pathlib import Path

import numpy as np

from rotor37_rom.machine import write_results
from rotor37_rom import fem  # noqa: E402
from rotor37_rom.dynamics.casing import Casing  # noqa: E402
from rotor37_rom.disk.assembly import mistuning_factors  # noqa: E402
from rotor37_rom.reduction.disk_builder import DiskReductionConfig, build_disk_model  # noqa: E402
from rotor37_rom.dynamics.explicit import CentralDifference  # noqa: E402
from rotor37_rom.studies.mistuning import blade_amplitudes, earlier_rows, over_seeds
from rotor37_rom.studies.sweep import SweepSpec, run_sweep  # noqa: E402

OUT = Path("results/bench_disk_mistuning")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--preset", default="ci", choices=["ci", "coarse"])
    parser.add_argument("--sigma", type=float, nargs="+", default=[0.0, 0.01, 0.03, 0.05],
                        help="standard deviations of the blades' stiffness factors, in [0, 1) (0: tuned)")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0], help="seeds of the mistuning factors (>= 0)")
    parser.add_argument("--speeds", type=float, nargs="+", default=[1256.0, 1453.0, 1554.0],
                        help="angular speeds (rad/s; default: one in each band of large response of the tuned map: "
                             "the k = 5 band's largest, the 1B/EO4 branch above its jump, its upper part)")
    parser.add_argument("--revolutions", type=float, default=200.0, help="per speed, from rest")
    parser.add_argument("--gnl", action="store_true", help="geometric nonlinearity (exact sector tensors at --h)")
    parser.add_argument("--h", type=float, default=1.15e-6, help="the GNL step (s)")
    parser.add_argument("--cap", type=float, default=60.0, help="frequency cap (kHz)")
    parser.add_argument("--mu", type=float, default=0.15, help="friction coefficient")
    args = parser.parse_args(argv)
    if not all(0 <= s < 1 for s in args.sigma) or min(args.seeds) < 0 or min(args.speeds) <= 0 \
            or not 0 < args.revolutions <= 1000 or not 0 < args.h < 1e-4 or not 5 <= args.cap <= 500 \
            or not 0 <= args.mu <= 2:
        print("error: --sigma must be in [0, 1), --seeds >= 0, --speeds > 0 rad/s, --revolutions in (0, 1000], --h in "
              "(0, 1e-4) s, --cap in [5, 500] kHz, --mu in [0, 2]", file=sys.stderr)
        return 2
    cap = 2 * np.pi * 1e3 * args.cap
    casing = Casing(mu=args.mu, direction="cone")
    sector = fem.create_disk_sector(preset=args.preset)
    base = dict(tip_nodes="all", r_c=10, r_md=10, criterion="MI2b", r_cyclic=144)
    rows, tuned = [], None
    disks = [(0.0, 0)] + [(s, seed) for s in args.sigma if s > 0 for seed in args.seeds]
    N = 36
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
    sys.exit(main())
