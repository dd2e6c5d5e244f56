"""Point cubature of the bladed disk's sector force (paper §3.4's maps): cost per step against the exact sector
tensors and the error on the response at a few speeds, next to the problem's own sensitivity.

The disk model of the contact maps (ci preset, every sector's 8 tip nodes, r_c = 10, r_MD = 10 by MI 2b, r_cyclic = 144:
r = 1,728), casing cone normal, 60 kHz cap, GNL at a fixed step (default the short GNL map's 1.15e-6 s). The sector's
force is hyper-reduced by ``reduction.builder.hyper_reduce`` (the blade's point cubature with the sectors as columns)
trained on exact GNL contact runs from rest at --train speeds (``dynamics.explicit.contact_training_states``), at each
--tol, in float64 and float32. Then, in the same run:

1. cost per simulation-step of a batch of 8 speeds (1,000 steps), exact tensors against each cubature, and the issue's
   full-disk map (90 speeds x 200 revolutions, GNL) extrapolated at that step on one process;
2. the force error on held-out states (those of the evaluation runs, exact model), median and largest;
3. the evaluation speeds (none of them a training speed) over --revolutions from rest: node LE of sector 0 and the
   largest over the 36 blades, max over the last revolution, for the exact model, the exact model with its forces
   scaled by 1 + 1e-4 (the floor: how much any perturbation of that size moves the answer) and each cubature.

    python benchmarks/bench_disk_cubature.py [--tol 1e-3 3e-4] [--revolutions 20] [--mu 0.15]

Results: results/bench_disk_cubature.json (machine stated); the training runs are kept in
results/bench_disk_cubature/ (a rerun with other tolerances reuses them).
"""
from __future__ import annotations

import argparse
import dataclasses
import hashlib
import json
import resource
import sys
import time
from pathlib import Path

import numpy as np

from rotor37_rom.machine import write_results
from rotor37_rom.reduction.builder import hyper_reduce  # noqa: E402
from rotor37_rom.dynamics.casing import Casing  # noqa: E402
from rotor37_rom.dynamics.explicit import CentralDifference, contact_training_states, simulate  # noqa: E402
from rotor37_rom.npz import load_npz, save_npz  # noqa: E402
from rotor37_rom.model.reduced import with_force_precision  # noqa: E402
from rotor37_rom.studies.disk_contact import MAP_REVOLUTIONS, MAP_SPEEDS, contact_disk_model, cost_per_sim_step
from rotor37_rom.studies.sweep import last_revolution_max  # noqa: E402

OUT = Path("results/bench_disk_cubature")


def responses(scheme, casing, speeds, revolutions, monitor) -> tuple[dict, np.ndarray]:
    """Node LE of sector 0 and the largest over the blades (max over the last revolution, m) per speed, and the
    run's states (records every 1e-5 s)."""
    res = simulate(scheme, speeds, casing, revolutions=revolutions, monitor=monitor, on_blowup="flag",
                   record_q=True, record_every=max(1, int(round(1e-5 / scheme.h))))
    le0, largest = [], []
    for p, om in enumerate(speeds):
        amp = [last_revolution_max(res.t[p], u, om) for u in res.u_r[p]]
        le0.append(amp[0] if res.diverged_step[p] < 0 else float("nan"))
        largest.append(max(amp) if res.diverged_step[p] < 0 else float("nan"))
    return {"le0_m": le0, "largest_m": largest, "diverged": res.diverged_step.tolist(),
            "max_penetration": float(res.max_penetration.max()), "min_multiplier": float(res.min_multiplier.min()),
            "max_friction_power": float(res.friction_power.max())}, np.hstack(res.records_q)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--preset", default="ci", choices=["ci", "coarse"])
    parser.add_argument("--tol", type=float, nargs="+", default=[1e-3, 3e-4], help="cubature training tolerances")
    parser.add_argument("--h", type=float, default=1.15e-6, help="GNL time step (s)")
    parser.add_argument("--cap", type=float, default=60.0, help="frequency cap (kHz)")
    parser.add_argument("--mu", type=float, default=0.15, help="friction coefficient")
    parser.add_argument("--train", type=float, nargs="+", default=[1200.0, 1290.0, 1380.0, 1470.0, 1560.0, 1650.0],
                        help="training speeds (rad/s)")
    parser.add_argument("--train-revolutions", type=float, default=12.0)
    parser.add_argument("--speeds", type=float, nargs="+", default=[1250.0, 1350.0, 1450.0, 1550.0],
                        help="evaluation speeds (rad/s)")
    parser.add_argument("--revolutions", type=float, default=20.0, help="revolutions of the evaluation runs")
    args = parser.parse_args(argv)
    if not all(0 < t < 1 for t in args.tol) or not 0 < args.h < 1e-4 or not 5 <= args.cap <= 500 \
            or not 0 <= args.mu <= 2 or not 0 < args.revolutions <= 200 or not 0 < args.train_revolutions <= 200 \
            or min(args.train + args.speeds) <= 0:
        print("error: --tol must be in (0, 1), --h in (0, 1e-4) s, --cap in [5, 500] kHz, --mu in [0, 2], "
              "--revolutions and --train-revolutions in (0, 200], speeds > 0", file=sys.stderr)
        return 2
    if set(args.train) & set(args.speeds):
        print("error: --speeds must not repeat a --train speed (the evaluation is held out)", file=sys.stderr)
        return 2
    cap = 2 * np.pi * 1e3 * args.cap
    casing = Casing(mu=args.mu, direction="cone")
    sector, model, _ = contact_disk_model(args.preset)
    exact = CentralDifference(model, nonlinear=True, h=args.h, frequency_cap=cap)
    summary = {"preset": args.preset, "r": model.r, "h": args.h, "cap_khz": args.cap, "mu": args.mu,
               "train": args.train, "train_revolutions": args.train_revolutions, "speeds": args.speeds,
               "revolutions": args.revolutions}
    key = hashlib.sha256(json.dumps([model.key, args.train, args.train_revolutions, args.h, args.cap,
                                     vars(casing)], sort_keys=True, default=str).encode()).hexdigest()[:16]
    runs = OUT / f"training_{key}.npz"
    t0 = time.perf_counter()
    Q_train = (load_npz(runs, ("train",), what="training runs") or {}).get("train")
    if Q_train is None:
        Q_train, _ = contact_training_states(exact, args.train, casing, args.train_revolutions)
        save_npz(runs, train=Q_train)
    summary["training_runs_s"] = time.perf_counter() - t0
    print(f"training states {Q_train.shape[1]} ({summary['training_runs_s']:.0f} s)", flush=True)
    variants = {"exact": exact}
    rows = []
    for tol in args.tol:
        hr, rep = hyper_reduce(sector, model, Q_train, tol=tol, label=f"disk contact runs {args.train}")
        rows.append({"tol": tol, "points": rep["points"], "of_points": int(rep["exact"].w.size),
                     "columns": int(rep["columns_trained"].shape[1]),
                     "training_error": rep["result"].training_error, "training_s": rep["seconds"]})
        print(f"tol {tol:g}: {rep['points']} of {rep['exact'].w.size} points ({rep['seconds']:.0f} s)", flush=True)
        for precision in ("double", "single"):
            m = with_force_precision(hr, precision)
            variants[f"cubature {tol:g} {precision}"] = CentralDifference(m, nonlinear=True, h=args.h,
                                                                          frequency_cap=cap)
    scaled = dataclasses.replace(model, forces=dataclasses.replace(model.forces, scales=model.forces.scales * 1.0001))
    batch = np.linspace(1200.0, 1650.0, 8)
    sim_steps = float(np.sum(np.ceil(MAP_REVOLUTIONS * 2 * np.pi / MAP_SPEEDS / args.h)))
    costs = {name: cost_per_sim_step(s, casing, batch, steps=1000)[0] for name, s in variants.items()}
    for name, c in costs.items():
        print(f"{name:24s} {1e6 * c:7.0f} us per simulation-step ({costs['exact'] / c:.2f}x); full map "
              f"{sim_steps * c / 3600:.1f} h on one process", flush=True)
    summary["us_per_sim_step"] = {n: 1e6 * c for n, c in costs.items()}
    summary["full_map_hours_one_process"] = {n: sim_steps * c / 3600 for n, c in costs.items()}
    summary["full_map_sim_steps"] = sim_steps
    monitor = tuple(model.nodes.row("LE", s) for s in range(36))
    evaluation = {}
    t0 = time.perf_counter()
    evaluation["exact"], Q_held = responses(exact, casing, args.speeds, args.revolutions, monitor)
    evaluation["exact"]["wall_s"] = time.perf_counter() - t0
    held = Q_held[:, np.abs(Q_held[model.nodes.boundary_rows]).max(axis=0) > 1e-5]
    g = model.forces.evaluate(held)
    for row, tol in zip(rows, args.tol):
        name = f"cubature {tol:g} double"
        err = np.linalg.norm(variants[name].model.forces.evaluate(held) - g, axis=0) / np.linalg.norm(g, axis=0)
        row.update(held_out_median=float(np.median(err)), held_out_max=float(err.max()), held_out_states=held.shape[1])
    t0 = time.perf_counter()
    evaluation["exact x (1 + 1e-4)"], _ = responses(CentralDifference(scaled, nonlinear=True, h=args.h,
                                                                      frequency_cap=cap), casing, args.speeds,
                                                    args.revolutions, monitor)
    evaluation["exact x (1 + 1e-4)"]["wall_s"] = time.perf_counter() - t0
    for name, s in variants.items():
        if name != "exact":
            t0 = time.perf_counter()
            evaluation[name], _ = responses(s, casing, args.speeds, args.revolutions, monitor)
            evaluation[name]["wall_s"] = time.perf_counter() - t0
    ref = evaluation["exact"]
    for name, e in evaluation.items():
        e["le0_error"] = [abs(a - b) / b for a, b in zip(e["le0_m"], ref["le0_m"])]
        e["largest_error"] = [abs(a - b) / b for a, b in zip(e["largest_m"], ref["largest_m"])]
        print(f"{name:24s} LE sector 0: " + " ".join(f"{1e3 * a:.3f}" for a in e["le0_m"]) + " mm  errors "
              + " ".join(f"{x:.1%}" for x in e["le0_error"]) + f"; largest errors "
              + " ".join(f"{x:.1%}" for x in e["largest_error"]) + f"  ({e['wall_s']:.0f} s)", flush=True)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    machine = write_results("bench_disk_cubature", [dict(summary, cubatures=rows, evaluation=evaluation)],
                            peak_rss_mb=peak)
    print(f"results/bench_disk_cubature.json ({machine}; peak RSS {peak:.0f} MB)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
