"""Tuned bladed disk in contact with GNL: does the response settle on the travelling wave, and at which step?

The case of ``tests/disk/test_disk_contact.py`` (ci disk sector, node LE of each of the 36 blades kept physical, r_c = 8,
4 modal derivatives by MI 2b, 96 interface modes: r = 636, exact sector tensors; 2 % modal damping; the two-lobe
casing with bumps of 0.55 mm, mu = 0.15 along the casing cone's normal; 1,400 rad/s from rest, 100 kHz cap), run
with GNL for --duration seconds at h = (2 pi / 36) / Omega / m for each m of --per-shift (a sector's turn is a whole
number of steps, so blade j's history is blade 0's shifted by j m steps on a travelling wave), and for each casing
ramp of --ramps (the run length that sets the ovalization's ramp, eq. 38: 99 % at a fifth of it). Per revolution:
the largest departure of any blade's LE history from blade 0's shifted one, relative to blade 0's amplitude; per
run: ``gnl_time_step`` on its 24 largest states (the step the project's GNL rule gives), the decay rate of the
departure (a least-squares fit of its logarithm where it lies between 1e-2 and 1e-7) and its final value.

    python benchmarks/bench_disk_travelling_wave.py                       # m = 13, 26, 52; ramps 0.15 and 0.45 s
    python benchmarks/bench_disk_travelling_wave.py --per-shift 13 104 --ramps 0.45

~15 min on 2 cores for the default (6 runs of 0.45 s; h/4 costs 3 min). Results to
results/bench_disk_travelling_wave.json (machine stated); the table is in docs/verification.md.
"""
from __future__ import annotations

import argparse
import dataclasses
import sys
import time

import numpy as np

from rotor37_rom.machine import write_results
from rotor37_rom import fem  # noqa: E402
from rotor37_rom.dynamics.casing import Casing  # noqa: E402
from rotor37_rom.disk.harmonics import travelling_wave_departure  # noqa: E402
from rotor37_rom.reduction.disk_builder import DiskReductionConfig, build_disk_model  # noqa: E402
from rotor37_rom.dynamics.explicit import CentralDifference, gnl_time_step, largest_states, simulate  # noqa: E402
from rotor37_rom.reduction.craig_bampton import modal_damping  # noqa: E402

OMEGA = 1400.0
SHIFT = 2 * np.pi / 36 / OMEGA            # time for the rotor to turn one sector (s)
CAP = 1e5                                 # rad/s
BASE = 13                                 # records per sector turn: one record every m / 13 steps


def departures(u: np.ndarray) -> np.ndarray:
    """(revolution end time, amplitude, departure / amplitude) per whole revolution of the records u (36, n) taken
    every SHIFT / BASE s; the first revolution is left out."""
    rev = 36 * BASE
    out = []
    for k in range(1, u.shape[1] // rev):
        worst, amp = travelling_wave_departure(u, np.arange(k * rev, (k + 1) * rev), BASE)
        out.append(((k + 1) * rev * SHIFT / BASE, amp, worst / amp if amp > 0 else np.nan))
    return np.array(out)


def decay_rate(table: np.ndarray) -> float:
    """-d ln(departure)/dt fitted where the departure lies in [1e-7, 1e-2] (nan with fewer than 3 points)."""
    t, d = table[:, 0], table[:, 2]
    sel = np.isfinite(d) & (d <= 1e-2) & (d >= 1e-7)
    return float(-np.polyfit(t[sel], np.log(d[sel]), 1)[0]) if sel.sum() >= 3 else float("nan")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--per-shift", type=int, nargs="+", default=[13, 26, 52],
                        help="steps per sector turn, multiples of 13 (13: h = 9.6e-6 s, the test's GNL-off step)")
    parser.add_argument("--ramps", type=float, nargs="+", default=[0.15, 0.45],
                        help="run lengths (s) that set the casing's ramp (0.15: the test's, 99 %% at 30 ms)")
    parser.add_argument("--duration", type=float, default=0.45, help="simulated time of each run (s)")
    args = parser.parse_args(argv)
    bad = [m for m in args.per_shift if m < BASE or m % BASE]
    if bad:
        parser.error(f"--per-shift must be multiples of {BASE} (13, 26, 52, ...), got {bad}")
    if not all(0.0 < r <= 10.0 for r in args.ramps):
        parser.error(f"--ramps must be in (0, 10] s, got {args.ramps}")
    if not 2 * 2 * np.pi / OMEGA < args.duration <= 10.0:
        parser.error(f"--duration must be in ({2 * 2 * np.pi / OMEGA:.4f}, 10] s (two revolutions at least), "
                     f"got {args.duration}")

    t0 = time.perf_counter()
    disk = fem.create_disk_sector(preset="ci")
    config = DiskReductionConfig(tip_nodes="LE", r_c=8, r_md=4, criterion="MI2b", r_cyclic=96)
    model, _ = build_disk_model(disk, config, ops=fem.create_svk_operators(disk))
    C, _ = modal_damping(model.K, model.M, ratios=lambda w: np.full_like(w, 0.02))
    model = dataclasses.replace(model, C=C)
    print(f"disk model r = {model.r} in {time.perf_counter() - t0:.0f} s", flush=True)
    rows_le = [model.nodes.row("LE", s) for s in range(36)]
    casing = Casing(h_b=0.55e-3, mu=0.15, direction="cone")
    rows = []
    print("| ramp (s) | m | h (s) | gnl_time_step (s) | departure at the end | decay rate (1/s) | wall (s) |")
    print("|---|---|---|---|---|---|---|")
    for ramp in args.ramps:
        for m in args.per_shift:
            scheme = CentralDifference(model, nonlinear=True, h=SHIFT / m, frequency_cap=CAP)
            n_steps = int(round(args.duration / scheme.h))
            t1 = time.perf_counter()
            res = simulate(scheme, OMEGA, casing, n_steps=n_steps, duration=ramp, monitor=rows_le, record_q=True,
                           record_every=m // BASE, on_blowup="flag")
            wall = time.perf_counter() - t1
            if res.diverged_step[0] >= 0:
                print(f"| {ramp:g} | {m} | {scheme.h:.3e} | - | diverged at step {res.diverged_step[0]} | - | "
                      f"{wall:.0f} |", flush=True)
                rows.append({"ramp": ramp, "per_shift": m, "h": scheme.h, "diverged_step": int(res.diverged_step[0])})
                continue
            table = departures(res.u_r[0])
            h_gnl = gnl_time_step(model, largest_states(res, scheme.boundary_rows, 24), frequency_cap=CAP)
            rate = decay_rate(table)
            print(f"| {ramp:g} | {m} | {scheme.h:.3e} | {h_gnl:.2e} | {table[-1, 2]:.1e} at {table[-1, 0]:.3f} s | "
                  f"{rate:.0f} | {wall:.0f} |", flush=True)
            rows.append({"ramp": ramp, "per_shift": m, "h": scheme.h, "gnl_time_step": h_gnl, "decay_rate": rate,
                         "final_departure": float(table[-1, 2]), "wall_s": wall,
                         "per_revolution": table.tolist()})
    machine = write_results("bench_disk_travelling_wave", rows, duration=args.duration, omega=OMEGA, cap=CAP)
    print(f"results/bench_disk_travelling_wave.json ({machine})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
