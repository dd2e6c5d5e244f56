"""Blade-tip/casing contact on the whole bladed disk (paper §3.4): the cost of a full-disk map and a short one.

One disk model (ci preset: every sector's 8 tip nodes kept physical, r_b = 24, r_c = 10 fixed-interface modes,
r_MD = 10 modal derivatives by MI 2b, r_cyclic = 144 interface modes; exact sector tensors), all 36 x 8 tip nodes
in contact with the two-lobe casing (each blade at its own angle), through the blade's integrator and sweep.

1. Cost per simulation-step (a batch of 8 speeds in 1,200-1,650 rad/s, 2,000 steps with contact): the step
   operators dense against per harmonic index (``disk.harmonics.HarmonicBlocks``, automatic for a tuned disk), GNL off
   and on; the GNL step from the tangent limit on states of a capped GNL run; the wall time of the issue's full-disk map
   (90 speeds x 200 revolutions in 1,200-1,650 rad/s, GNL) extrapolated from them, on one process.
2. A short map through ``studies.sweep.run_sweep`` (GNL off, --speeds x --revolutions): node LE of sector 0 and the
   largest over the sectors, the contact checks (penetration, lambda >= 0, friction power <= 0).

    python benchmarks/bench_disk_contact.py [--speeds 1200 1650 10] [--revolutions 20] [--cap 60]
    python benchmarks/bench_disk_contact.py --gnl-throughput 10          # one process, 10 speeds x 1,500 GNL steps
    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_disk_contact.py --gnl-throughput 5 &
    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_disk_contact.py --gnl-throughput 5  # the two cores as two ranks

Results: results/bench_disk_contact.json (machine stated). A full map of the disk is this bench's extrapolation,
not a run: see docs/performance.md.

Every option is checked, and the folders written in, before any work: a bad one is one line on stderr and exit
status 2. ``--check`` does only that (exit status 0); SIGTERM or SIGINT stop the run with one line
(``rotor37_rom.cli.run_main``).
"""
from __future__ import annotations

import copy
import resource
import sys
import time
from pathlib import Path
from typing import Sequence

import numpy as np

from rotor37_rom.checks import before_work, fits_in_memory, real_number, whole_number
from rotor37_rom.cli import ArgumentParser, run_main

MAX_SPEED = 1e5                  # rad/s: the map command's (studies.contact_config.MAX_SPEED)
MAX_SPEEDS = 1000                # speeds of the short map at most (one batch: all of them integrated together)
MAX_THROUGHPUT = 100             # speeds of --gnl-throughput at most
DEFAULT_SPEEDS, DEFAULT_REVOLUTIONS = (1200.0, 1650.0, 10), 20.0
ROWS = 37 + 8 * 36               # what a record holds per run: node LE of the 36 sectors, TE, the 288 contact forces
RECORD_DT = 1e-5                 # s: the sweep's sampling (studies.sweep.SweepSpec.record_dt)


def build_parser() -> ArgumentParser:
    p = ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--preset", default="ci", choices=["ci", "coarse"], help="mesh preset of the disk sector "
                   "(default ci)")
    p.add_argument("--cap", type=float, default=60.0,
                   help="frequency cap of the explicit scheme (kHz), in [5, 500] (default 60)")
    p.add_argument("--speeds", type=float, nargs=3, default=None, metavar=("START", "STOP", "N"),
                   help=f"the short map's N speeds (rad/s) from START to STOP, 0 < START <= STOP <= {MAX_SPEED:g}, "
                        f"N in 1..{MAX_SPEEDS} (default 1200 1650 10); not with "
                        f"--gnl-throughput")
    p.add_argument("--revolutions", type=float, default=None,
                   help="revolutions of the short map per speed, in (0, 200] (default 20); not with --gnl-throughput")
    p.add_argument("--mu", type=float, default=0.15, help="friction coefficient, in [0, 2] (default 0.15)")
    p.add_argument("--gnl-throughput", type=int, metavar="P", default=0,
                   help=f"only time P speeds x 1,500 GNL steps at h = 1.15e-6 s, P in 0..{MAX_THROUGHPUT} (0, the "
                        f"default: the whole bench; run two side by side to measure what two ranks give)")
    return p


def check_options(args) -> None:
    """Every option checked (ValueError naming it and its range); the short map's defaults filled in."""
    real_number("--cap", args.cap, 5, 500, unit=" kHz")
    real_number("--mu", args.mu, 0, 2)
    whole_number("--gnl-throughput", args.gnl_throughput, 0, MAX_THROUGHPUT)
    if args.gnl_throughput:
        for option, value in (("--speeds", args.speeds), ("--revolutions", args.revolutions)):
            if value is not None:
                raise ValueError(f"{option} (the short map's) does nothing with --gnl-throughput (which only times "
                                 f"GNL steps at 1,200-1,650 rad/s)")
        return
    args.speeds = list(DEFAULT_SPEEDS) if args.speeds is None else args.speeds
    args.revolutions = DEFAULT_REVOLUTIONS if args.revolutions is None else args.revolutions
    start, stop, n = args.speeds
    for value in args.speeds:
        real_number("--speeds (START, STOP, N)", value, 0, MAX_SPEED, open_low=True)
    if not (start <= stop and float(n).is_integer() and 1 <= n <= MAX_SPEEDS):
        raise ValueError(f"--speeds: need 0 < START <= STOP <= {MAX_SPEED:g} rad/s and an integer N in "
                         f"1..{MAX_SPEEDS}, got {' '.join(f'{v:g}' for v in args.speeds)}")
    args.speeds = [float(start), float(stop), int(n)]
    real_number("--revolutions", args.revolutions, 0, 200, open_low=True)
    records = args.revolutions * 2 * np.pi / start / RECORD_DT + 1
    fits_in_memory("--revolutions", 8.0 * ROWS * records * int(n),
                   f"{int(n)} runs x {records:.3g} records x {ROWS} values, at {start:g} rad/s",
                   hint="fewer revolutions or speeds")


def main(argv: Sequence[str] | None = None) -> int:
    """Check the options, then the costs and the short map (or the GNL throughput); raises ValueError for a bad
    input."""
    args = build_parser().parse_args(argv)
    check_options(args)
    folders = {"the model cache": Path("results/cache")}
    if not args.gnl_throughput:
        folders["the results folder"] = Path("results")
    before_work(folders)                                    # before any work; a dry run stops here

    from rotor37_rom.dynamics.casing import Casing
    from rotor37_rom.dynamics.explicit import CentralDifference, gnl_time_step, largest_states, simulate
    from rotor37_rom.machine import write_results
    from rotor37_rom.studies.disk_contact import MAP_REVOLUTIONS, MAP_SPEEDS, contact_disk_model, cost_per_sim_step
    from rotor37_rom.post.signals import last_revolution_max
    from rotor37_rom.studies.sweep import SweepSpec, load_sweep, run_sweep

    start, stop, n = args.speeds if args.speeds is not None else (None, None, None)
    cap = 2 * np.pi * 1e3 * args.cap
    casing = Casing(mu=args.mu, direction="cone")
    _, model, offline = contact_disk_model(args.preset)
    if args.gnl_throughput:
        scheme = CentralDifference(model, nonlinear=True, h=1.15e-6, frequency_cap=cap)
        speeds = np.linspace(1200.0, 1650.0, args.gnl_throughput)
        t0 = time.perf_counter()
        simulate(scheme, speeds, casing, n_steps=1500, duration=1500 * scheme.h * 5, on_blowup="flag")
        wall = time.perf_counter() - t0
        print(f"{len(speeds)} speeds x 1500 GNL steps: {wall:.1f} s ({1e6 * wall / 1500 / len(speeds):.0f} us per "
              f"simulation-step)")
        return 0
    batch = np.linspace(1200.0, 1650.0, 8)
    row = {"preset": args.preset, "r": model.r, "sizes": model.sizes, "contact_nodes": len(model.nodes),
           "offline_s": offline, "cap_khz": args.cap, "mu": args.mu, "direction": "cone", "batch": len(batch)}
    linear = CentralDifference(model, nonlinear=False, safety=0.5, frequency_cap=cap)
    row["h_linear"] = linear.h
    row["harmonic_blocks"] = linear.harmonic.sizes.tolist()
    dense = copy.copy(linear)
    dense.harmonic = None                                  # the same operators applied densely: the baseline
    row["us_linear_dense"] = 1e6 * cost_per_sim_step(dense, casing, batch)[0]
    row["us_linear_harmonic"] = 1e6 * cost_per_sim_step(linear, casing, batch)[0]
    gnl = CentralDifference(model, nonlinear=True, h=linear.h, frequency_cap=cap)
    us_gnl, probe = cost_per_sim_step(gnl, casing, batch)
    row["us_gnl_harmonic"] = 1e6 * us_gnl
    states = largest_states(probe, gnl.boundary_rows, 6)
    row["h_gnl"] = gnl_time_step(model, states, cap, safety=0.5, cap_safety=0.5)
    print(f"per simulation-step (batch of {len(batch)}): linear dense {row['us_linear_dense']:.0f} us, per harmonic "
          f"{row['us_linear_harmonic']:.0f} us; GNL per harmonic {row['us_gnl_harmonic']:.0f} us; h linear "
          f"{linear.h:.3g} s, GNL {row['h_gnl']:.3g} s", flush=True)
    sim_steps = float(np.sum(np.ceil(MAP_REVOLUTIONS * 2 * np.pi / MAP_SPEEDS / row["h_gnl"])))
    row["full_map_gnl_sim_steps"] = sim_steps
    row["full_map_gnl_hours_one_process"] = sim_steps * us_gnl / 3600
    lin_steps = float(np.sum(np.ceil(MAP_REVOLUTIONS * 2 * np.pi / MAP_SPEEDS / linear.h)))
    row["full_map_linear_hours_one_process"] = lin_steps * row["us_linear_harmonic"] * 1e-6 / 3600
    print(f"full-disk map, 90 speeds x 200 rev: GNL {row['full_map_gnl_hours_one_process']:.1f} h, linear "
          f"{row['full_map_linear_hours_one_process']:.1f} h on one process (extrapolated)", flush=True)
    # the short map through the sweep: LE of every sector monitored
    monitor = tuple(model.nodes.row("LE", s) for s in range(36))
    spec = SweepSpec(revolutions=args.revolutions, casing=casing, batch_size=int(n), monitor=monitor)
    t0 = time.perf_counter()
    folder = run_sweep(linear, np.linspace(start, stop, int(n)), spec, Path("results/bench_disk_contact"),
                       progress=False)
    records = load_sweep(folder)
    row["short_map_s"] = time.perf_counter() - t0
    speeds, le0, largest, where, checks = [], [], [], [], []
    for rec in records:
        om = float(rec["omega"])
        amp = [last_revolution_max(rec["t"], u, om) for u in rec["u_r"]]
        speeds.append(om)
        le0.append(amp[0])
        largest.append(max(amp))
        where.append(int(np.argmax(amp)))
        checks.append((float(rec["max_penetration"]), float(rec["min_multiplier"]), float(rec["friction_power"]),
                       int(rec["diverged_step"])))
    row["short_map"] = {"speeds": speeds, "revolutions": args.revolutions, "le_sector0_m": le0,
                        "largest_le_m": largest, "largest_sector": where, "h": linear.h,
                        "max_penetration": max(c[0] for c in checks), "min_multiplier": min(c[1] for c in checks),
                        "max_friction_power": max(c[2] for c in checks),
                        "diverged": [s for s, c in zip(speeds, checks) if c[3] >= 0]}
    for om, a, b, w in zip(speeds, le0, largest, where):
        print(f"  {om:7.1f} rad/s: LE of sector 0 {a * 1e3:.4f} mm, largest {b * 1e3:.4f} mm (sector {w})")
    print(f"short map {row['short_map_s']:.0f} s; penetration <= {row['short_map']['max_penetration']:.1e} m, "
          f"lambda >= {row['short_map']['min_multiplier']:.1e} N, friction power <= "
          f"{row['short_map']['max_friction_power']:.2g} W, diverged {row['short_map']['diverged']}")
    row["peak_rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    machine = write_results("bench_disk_contact", [row])
    print(f"{machine}; peak RSS {row['peak_rss_mb']:.0f} MB")
    return 0


if __name__ == "__main__":
    sys.exit(run_main(main))
