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

Every option is checked, and the folders written in, before any work: a bad one is one line on stderr and exit
status 2. ``--check`` does only that (exit status 0); SIGTERM or SIGINT stop the run with one line
(``rotor37_rom.cli.run_main``).
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import resource
import sys
import time
from pathlib import Path
from typing import Sequence

import numpy as np

from rotor37_rom.checks import before_work, fits_in_memory, real_number
from rotor37_rom.cli import ArgumentParser, run_main

MAX_SPEED = 1e5                  # rad/s: the map command's (studies.contact_config.MAX_SPEED)
MAX_SPEEDS = 100                 # training or evaluation speeds at most (each a GNL run from rest)
R = 36 * (24 + 10 + 10) + 144    # the maps' disk model's size (8 tip nodes, r_c = 10, r_MD = 10, r_cyclic = 144)
RECORD_DT = 1e-5                 # s: the runs' states are recorded this often
OUT = Path("results/bench_disk_cubature")


def build_parser() -> ArgumentParser:
    p = ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--preset", default="ci", choices=["ci", "coarse"], help="mesh preset of the disk sector "
                   "(default ci)")
    p.add_argument("--tol", type=float, nargs="+", default=[1e-3, 3e-4],
                   help="cubature training tolerances, each in (0, 1) (default 1e-3 3e-4)")
    p.add_argument("--h", type=float, default=1.15e-6, help="GNL time step (s), in (0, 1e-4) (default 1.15e-6)")
    p.add_argument("--cap", type=float, default=60.0, help="frequency cap (kHz), in [5, 500] (default 60)")
    p.add_argument("--mu", type=float, default=0.15, help="friction coefficient, in [0, 2] (default 0.15)")
    p.add_argument("--train", type=float, nargs="+", default=[1200.0, 1290.0, 1380.0, 1470.0, 1560.0, 1650.0],
                   help=f"training speeds (rad/s), each in (0, {MAX_SPEED:g}], at most {MAX_SPEEDS} (default 1200 "
                        f"1290 1380 1470 1560 1650)")
    p.add_argument("--train-revolutions", type=float, default=12.0,
                   help="revolutions of each training run, in (0, 200] (default 12)")
    p.add_argument("--speeds", type=float, nargs="+", default=[1250.0, 1350.0, 1450.0, 1550.0],
                   help=f"evaluation speeds (rad/s), each in (0, {MAX_SPEED:g}], none a --train speed, at most "
                        f"{MAX_SPEEDS} (default 1250 1350 1450 1550)")
    p.add_argument("--revolutions", type=float, default=20.0,
                   help="revolutions of the evaluation runs, in (0, 200] (default 20)")
    return p


def check_options(args) -> None:
    """Every option checked: ValueError naming it and its range."""
    for tol in args.tol:
        real_number("--tol (cubature training tolerances)", tol, 0, 1, open_low=True, open_high=True)
    real_number("--h (the GNL step)", args.h, 0, 1e-4, open_low=True, open_high=True, unit=" s")
    real_number("--cap", args.cap, 5, 500, unit=" kHz")
    real_number("--mu", args.mu, 0, 2)
    for option, speeds in (("--train", args.train), ("--speeds", args.speeds)):
        for w in speeds:
            real_number(f"{option} (speeds)", w, 0, MAX_SPEED, open_low=True, unit=" rad/s")
        if len(speeds) > MAX_SPEEDS:
            raise ValueError(f"{option}: at most {MAX_SPEEDS} speeds, got {len(speeds)}")
    real_number("--train-revolutions", args.train_revolutions, 0, 200, open_low=True)
    real_number("--revolutions", args.revolutions, 0, 200, open_low=True)
    for option, speeds, revolutions, copies in (("--train-revolutions", args.train, args.train_revolutions, 1),
                                                ("--revolutions", args.speeds, args.revolutions, 2)):
        records = sum(revolutions * 2 * np.pi / w / RECORD_DT + 1 for w in speeds)
        fits_in_memory(option, 8.0 * R * records * copies, f"{records:.3g} recorded states of r = {R} over the "
                       f"speeds{', twice' if copies > 1 else ''}", hint="fewer revolutions or speeds")
    repeated = sorted(set(args.train) & set(args.speeds))
    if repeated:
        raise ValueError(f"--speeds must not repeat a --train speed (the evaluation is held out), got "
                         f"{', '.join(f'{w:g}' for w in repeated)}")


def responses(scheme, casing, speeds, revolutions, monitor) -> tuple[dict, np.ndarray]:
    """Node LE of sector 0 and the largest over the blades (max over the last revolution, m) per speed, and the
    run's states (records every 1e-5 s)."""
    from rotor37_rom.dynamics.explicit import simulate
    from rotor37_rom.post.signals import last_revolution_max

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


def main(argv: Sequence[str] | None = None) -> int:
    """Check the options, then the training runs, the cubatures, their costs and errors; raises ValueError for a bad
    input."""
    args = build_parser().parse_args(argv)
    check_options(args)
    before_work({"the training runs' folder": OUT, "the model cache": Path("results/cache"),
                 "the results folder": Path("results")})          # before any work; a dry run stops here

    from rotor37_rom.dynamics.casing import Casing
    from rotor37_rom.dynamics.explicit import CentralDifference, contact_training_states
    from rotor37_rom.machine import write_results
    from rotor37_rom.model.reduced import with_force_precision
    from rotor37_rom.npz import load_npz, save_npz
    from rotor37_rom.reduction.builder import hyper_reduce
    from rotor37_rom.studies.disk_contact import MAP_REVOLUTIONS, MAP_SPEEDS, contact_disk_model, cost_per_sim_step

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
    sys.exit(run_main(main))
