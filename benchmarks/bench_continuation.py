"""Cost of the GNL continuation (issue #23, item 5): the rule for a speed that no halved step makes steady.

The paper's continuation (§2.3.3) halves the 2 rad/s step up to 3 times when a run is not steady. Read literally,
a speed where even the smallest step is not steady is accepted at step / 8, so every unsteady stretch of the
branch is crossed at 0.25 rad/s; the GNL contact response of this blade is mostly not periodic with the rotor
(docs/results.md, steadiness), so that reading multiplies the points. ``--unsteady-step full`` keeps the full step
there (the point is marked not steady). This benchmark runs both rules on the same stretch, from the same rest
state, with the same model and step, one rule per rank (serially without mpirun), and reports per rule the points,
the steady ones, the wall time and the wall per rad/s crossed:

    OPENBLAS_NUM_THREADS=1 mpirun -n 2 python benchmarks/bench_continuation.py [--range 1386 1390]
    python benchmarks/bench_continuation.py --per-step        # us per step of 1, 2, 4 runs in contact (serial; with
                                                              # the BLAS threads of the environment)

Model: the speed-accuracy study's cheapest GNL map candidate (r = 45 ci blade, point cubature trained to 1e-4 on
exact GNL contact runs at the study's 6 training speeds, float32, 120 kHz frequency cap), mu = 0, normal e_x; the first
run 200 revolutions from rest, then 30 per speed (the paper's). The r = 45 model file is the study's
(results/speed_accuracy/models/rom_rc15.npz, made by ``make speed-accuracy``; ``--model`` for another); the
cubature is trained once (about 4 min) into <out>/cache. Results: results/bench_continuation.json.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from rotor37_rom.machine import write_results

ROOT = Path(__file__).resolve().parent.parent
RULES = ("smallest", "full")
RESULTS = Path("results/bench_continuation.json")


def per_step(scheme, casing, omega: float, n: int = 3000) -> int:
    """Microseconds per step of P = 1, 2, 4 runs (a continuation's single run and batches of halvings) started from
    a state in contact (3 revolutions from rest at ``omega``), with the BLAS threads of the environment; added to
    results/bench_continuation.json under 'per_step_us' keyed by the thread count."""
    import os

    from rotor37_rom.dynamics.explicit import simulate

    res = simulate(scheme, [omega], casing, revolutions=3)
    q, qp = res.q_final[:, 0], res.q_prev[:, 0]
    threads = os.environ.get("OPENBLAS_NUM_THREADS", "default")
    record_every = max(1, int(round(1e-5 / scheme.h)))          # the continuation's recording cadence
    costs = {}
    for P in (1, 2, 4):
        speeds = omega + np.linspace(-2.0, 2.0, P) if P > 1 else [omega]
        t0 = time.perf_counter()
        run = simulate(scheme, speeds, casing, n_steps=n, initial=(np.tile(q[:, None], P), np.tile(qp[:, None], P)),
                       duration=1e-12, record_every=record_every)
        costs[str(P)] = (time.perf_counter() - t0) / n * 1e6
        print(f"P = {P}: {costs[str(P)]:.1f} us per step ({costs[str(P)] / P:.1f} per simulation-step), "
              f"{int(run.contact_steps.min())}-{int(run.contact_steps.max())} of {n} steps in contact; "
              f"OPENBLAS_NUM_THREADS={threads}")
    store = json.loads(RESULTS.read_text()) if RESULTS.is_file() else {}
    per_step = {**store.pop("per_step_us", {}), threads: {"omega": omega, "h": scheme.h, "us": costs}}
    write_results(RESULTS.stem, store.pop("rows", []), **{k: v for k, v in store.items() if k != "machine"},
                  per_step_us=per_step)
    return 0


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", type=Path, default=ROOT / "results" / "speed_accuracy" / "models" / "rom_rc15.npz")
    parser.add_argument("--range", type=float, nargs=2, default=[1386.0, 1390.0], metavar=("LOW", "HIGH"))
    parser.add_argument("--step", type=float, default=2.0)
    parser.add_argument("--out", type=Path, default=Path("results/bench_continuation"))
    parser.add_argument("--per-step", action="store_true",
                        help="only the cost per step of P = 1, 2, 4 runs in contact (a continuation's batches)")
    args = parser.parse_args(argv)
    low, high = args.range
    if not 0 < low < high:
        print(f"error: --range: need 0 < LOW < HIGH rad/s, got {args.range}", file=sys.stderr)
        return 2
    if not args.model.is_file():
        print(f"error: --model {args.model} not found (make speed-accuracy builds it)", file=sys.stderr)
        return 2
    from rotor37_rom.model.reduced import load_reduced_model
    from rotor37_rom.studies import contact_map as cm
    from rotor37_rom.studies.speed_accuracy.maps import study_training_speeds
    from rotor37_rom.studies.sweep import continuation

    comm = cm.world_comm()
    rank, size = (0, 1) if comm is None else (comm.rank, comm.size)
    if args.per_step and size > 1:
        print("error: --per-step runs serially (it times one process's batches); drop mpirun", file=sys.stderr)
        return 2
    config = cm.ContactMapConfig.from_options(model=args.model, gnl="on", frequency_cap=120.0, cubature=1e-4,
                                              precision="single", cubature_speeds=study_training_speeds(), mu=0.0,
                                              direction="x", speeds=(low, high, 2), revolutions=200.0, out=args.out,
                                              quiet=True)
    model = load_reduced_model(config.rom.path)
    scheme = cm.time_scheme(config, model, True, comm)
    if args.per_step:
        return per_step(scheme, config.sweep.casing, 0.5 * (low + high))
    rows = []
    for k, rule in enumerate(RULES):
        if k % size != rank:
            continue
        t0 = time.perf_counter()
        points = continuation(scheme, low, high, args.step, config.sweep.casing, first_revolutions=200.0,
                              revolutions=30.0, unsteady=rule, progress=True)
        wall = time.perf_counter() - t0
        rows.append({"rule": rule, "points": len(points), "steady": sum(p.steady for p in points),
                     "halvings": [p.halvings for p in points], "speeds": [p.omega for p in points],
                     "amplitude_mm": [p.amplitude * 1e3 for p in points], "wall_s": wall})
        print(f"rank {rank}: rule {rule}: {len(points)} points in {wall:.0f} s", flush=True)
    if comm is not None:
        gathered = comm.gather(rows, root=0)               # every rank takes part; rank 0 gets all the rows
        rows = [row for part in gathered for row in part] if rank == 0 else []
    if rank != 0:
        return 0
    rows.sort(key=lambda row: RULES.index(row["rule"]))
    earlier = json.loads(RESULTS.read_text()) if RESULTS.is_file() else {}
    machine = write_results(RESULTS.stem, rows, model=str(args.model), h=scheme.h, range=[low, high], step=args.step,
                            ranks=size, per_step_us=earlier.get("per_step_us", {}))
    print(f"GNL continuation up {low:g} -> {high:g} rad/s, step {args.step:g}, h = {scheme.h:.3g} s, {size} rank(s); "
          f"machine: {machine}")
    print("| rule | points | steady | wall (s) | wall per rad/s (s) | largest response |")
    print("|---|---|---|---|---|---|")
    for row in rows:
        amp = np.asarray(row["amplitude_mm"], float)
        largest = (f"{np.nanmax(amp):.2f} mm at {row['speeds'][int(np.nanargmax(amp))]:g} rad/s"
                   if np.isfinite(amp).any() else "diverged")
        print(f"| {row['rule']} | {row['points']} | {row['steady']} | {row['wall_s']:.0f} | "
              f"{row['wall_s'] / (high - low):.0f} | {largest} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
