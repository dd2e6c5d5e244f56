"""The tuned disk's travelling wave on one sector (#72 (f)): what one sector costs against the full disk's harmonic
balance, and the forced k-diameter wave's NFRC with GNL through its 1B resonance, its stability against every nodal
diameter at each point: where the wave loses stability, and to which diameters.

The model is the contact maps' disk model (ci sector, every tip node, r_c = 10, r_MD = 10 by MI 2b, 144 interface
modes: r = 1,728; its exact sector tensors), built here (~70 s, cached) or read with --model. The load is a unit
axial force at node LE of every sector travelling with k nodal diameters (engine order k on a tuned disk), ``--force``
N; the rotor speed of a point is omega / k. Stability: Hill's method per perturbation class j = 0 .. N/2 (nodal
diameter j in its constant part), ``periodic.travelling_wave``.

    python benchmarks/bench_travelling_wave.py [--model results/disk_map200/rom.npz] [--k 6] [--force 20] [--H 3]
        [--check]

With ``--departure SPEED ...`` the stability along the branch is replaced by the full disk marched from the wave at
those rotor speeds (``periodic.departure``): each set of nodal diameters' growth a period against Hill's.

Results: results/bench_travelling_wave.json (the machine, both costs and their ratio, the branch: speed, node LE's
amplitude, and at every --every-th point its stability and the classes that are unstable). ~30 min on this
machine.

Every option is checked, and the model read and the folders written in, before any work: a bad one is one line on
stderr and exit status 2. ``--check`` does only that and says what would run (exit status 0); SIGTERM or SIGINT stop
the run with one line (``rotor37_rom.cli.run_main``).
"""
from __future__ import annotations

import re
import sys
import time
from pathlib import Path
from typing import Sequence

import numpy as np

from rotor37_rom.checks import before_work, flagged, real_number, whole_number, writable_folder
from rotor37_rom.cli import ArgumentParser, run_main
from rotor37_rom.machine import write_results

N_SECTORS = 36                   # the maps' disk (rotor 37)
MAX_FORCE = 1e3                  # N at one node: 50 times the default's 20 N
MAX_RANGE = 10.0                 # the branch's end, times the wave's linear 1B frequency
MAX_POINTS = 10_000              # points of the branch at most (each a Newton on the balance)
MAX_DEPARTURE = 3000.0           # rad/s: rotor 37's range (studies.campbell.MAX_TURNING_SPEED)
NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]{0,99}")


def map_model(path: Path | None, cache: Path):
    """The maps' disk model with GNL (read from ``path``, else built into ``cache``)."""
    from rotor37_rom.model.reduced import load_reduced_model

    if path is not None:
        return flagged("--model", lambda: load_reduced_model(path))
    from rotor37_rom import fem
    from rotor37_rom.reduction.disk_builder import DiskReductionConfig, build_disk_model

    sector = fem.create_disk_sector(preset="ci")
    config = DiskReductionConfig(tip_nodes="all", r_c=10, r_md=10, criterion="MI2b", r_cyclic=144,
                                 forces="intrusive")
    return build_disk_model(sector, config, cache_dir=cache)[0]


def departures(args, tw, branch, out) -> int:
    """The full disk marched from the wave at each --departure speed (``periodic.departure``): per set of nodal
    diameters, the measured growth a period against Hill's largest multiplier of its classes."""
    from rotor37_rom.periodic import solve_periodic
    from rotor37_rom.periodic.departure import wave_departure

    k = args.k
    speeds = [pt.omega / k for pt in branch.points]
    rows = []
    for speed in args.departure:
        i = int(np.argmin(np.abs(np.asarray(speeds) - speed)))
        if abs(speeds[i] - speed) > 0.01 * speed:
            raise ValueError(f"--departure {speed:g} rad/s is not on the branch (its speeds {min(speeds):,.1f}-"
                             f"{max(speeds):,.1f} rad/s)")
        sol = solve_periodic(tw, branch.points[i].X.ravel(), speed * k, stability=False, tol=1e-8)
        t = time.perf_counter()
        dep = wave_departure(tw, sol, periods=args.periods, size=1e-6)
        wall = time.perf_counter() - t
        print(f"{speed:,.1f} rad/s: {dep.periods} periods ({dep.ended}), {wall:.0f} s; the wave's own set "
              f"(Hill {dep.wave_predicted:.4f}) drifts {dep.drift[1]:.3f} -> {dep.drift.max():.3f}", flush=True)
        for st in dep.sets:
            measured = "-" if st.measured is None else f"{st.measured:.4f}"
            print(f"  diameters {st.diameters}: Hill {st.predicted:.4f}, marched {measured}; amplitude "
                  f"{st.amplitude[0]:.1e} -> max {st.amplitude.max():.1e}", flush=True)
        rows.append({"speed": speed, "periods": dep.periods, "ended": dep.ended, "wall_s": wall,
                     "wave_predicted": dep.wave_predicted, "drift": dep.drift.tolist(),
                     "sets": [{"diameters": list(st.diameters), "predicted": st.predicted, "measured": st.measured,
                               "amplitude": st.amplitude.tolist()} for st in dep.sets]})
    machine = write_results(args.name, rows, **out)
    print(f"results: results/{args.name}.json ({machine})")
    return 0


def build_parser() -> ArgumentParser:
    p = ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--model", type=Path, default=None,
                   help="a saved tuned bladed disk's model with GNL forces (.npz, e.g. results/disk_map200/rom.npz; "
                        "default: build the maps' one into --cache)")
    p.add_argument("--cache", type=Path, default=None,
                   help="folder the maps' disk model is built into and read from (default results/cache); not with "
                        "--model")
    p.add_argument("--k", type=int, default=6,
                   help=f"the load's nodal diameters (engine order), 1..{N_SECTORS // 2 - 1} (below half the model's "
                        f"sectors; default 6)")
    p.add_argument("--force", type=float, default=20.0,
                   help=f"N at node LE of each sector, in (0, {MAX_FORCE:g}] (default 20)")
    p.add_argument("--H", type=int, default=3, help="harmonics of the balance, 1..8 (default 3)")
    p.add_argument("--range", type=float, nargs=2, default=(0.9, 1.6), metavar=("FROM", "TO"),
                   help=f"the branch from FROM to TO times the wave's linear 1B frequency, 0 < FROM < TO <= "
                        f"{MAX_RANGE:g} (default 0.9 1.6)")
    p.add_argument("--step", type=float, default=0.02,
                   help="relative arc length of a step, in (0, 0.5] (default 0.02)")
    p.add_argument("--max-points", type=int, default=150,
                   help=f"points of the branch at most, 2..{MAX_POINTS} (default 150)")
    p.add_argument("--every", type=int, default=None,
                   help=f"the stability at every this many points, 1..{MAX_POINTS} (default 2); not with --departure")
    p.add_argument("--no-full", action="store_true", help="skip the full disk's cost (its balance is dense)")
    p.add_argument("--departure", type=float, nargs="+", default=None, metavar="SPEED",
                   help=f"instead of the stability along the branch: the full disk marched from the wave at these "
                        f"rotor speeds (rad/s, in (0, {MAX_DEPARTURE:g}], on the branch), each perturbation set's "
                        f"growth against Hill's")
    p.add_argument("--periods", type=int, default=None,
                   help="with --departure: wave periods marched at most, 8..10000 (default 60)")
    p.add_argument("--name", default="bench_travelling_wave",
                   help="the results file results/NAME.json: a file name (letters, digits, _ . -; default "
                        "bench_travelling_wave)")
    return p


def check_options(args) -> dict | None:
    """Every option checked (ValueError naming it and its range), the defaults of those that need another filled
    in; the saved model's kind (``studies.contact_config.saved_model_info``) when --model is given, else None."""
    from rotor37_rom.studies.contact_config import saved_model_info

    whole_number("--k", args.k, 1, N_SECTORS // 2 - 1)
    real_number("--force", args.force, 0, MAX_FORCE, open_low=True, unit=" N")
    whole_number("--H", args.H, 1, 8)
    low, high = args.range
    for value in args.range:
        real_number("--range (FROM, TO)", value, 0, MAX_RANGE, open_low=True)
    if not low < high:
        raise ValueError(f"--range must be 0 < FROM < TO <= {MAX_RANGE:g}, got {low:g} {high:g}")
    real_number("--step (the relative arc length of a step)", args.step, 0, 0.5, open_low=True)
    whole_number("--max-points", args.max_points, 2, MAX_POINTS)
    if args.departure is not None:
        if args.every is not None:
            raise ValueError("--every (the stability along the branch) does nothing with --departure (which replaces "
                             "it)")
        for speed in args.departure:
            real_number("--departure (rotor speeds on the branch)", speed, 0, MAX_DEPARTURE, open_low=True,
                        unit=" rad/s")
        args.periods = 60 if args.periods is None else args.periods
        whole_number("--periods", args.periods, 8, 10000)
    elif args.periods is not None:
        raise ValueError("--periods needs --departure (the periods the full disk is marched)")
    else:
        args.every = 2 if args.every is None else args.every
        whole_number("--every", args.every, 1, MAX_POINTS)
    if not (isinstance(args.name, str) and NAME.fullmatch(args.name)):
        raise ValueError(f"--name must be a file name (letters, digits, _ . -, not starting with '.' or '-'; "
                         f"results/NAME.json), got {args.name!r}")
    if args.model is None:
        args.cache = Path("results/cache") if args.cache is None else args.cache
        return None
    if args.cache is not None:
        raise ValueError("--cache is where the model is built: not with --model (the saved model is read as it is)")
    info = saved_model_info("--model", args.model)
    mistuning = (info["metadata"].get("config") or {}).get("mistuning")
    if not info["disk"]:
        raise ValueError(f"--model: {args.model} is a single blade's model; the travelling wave takes a bladed disk's "
                         f"(demos/contact_map.py --disk writes one)")
    if not info["forces"].startswith("sector_"):
        raise ValueError(f"--model: {args.model} has no GNL sector forces ({info['forces']}); the wave's NFRC is the "
                         f"disk's with GNL (build it with --gnl on)")
    if mistuning and len(set(np.ravel(mistuning).tolist())) > 1:
        raise ValueError(f"--model: {args.model} is a mistuned disk's model: no travelling wave on one sector")
    if "LE" not in info["nodes"]:
        raise ValueError(f"--model: {args.model} has no node LE (the load's node): its nodes are "
                         f"{sorted(set(info['nodes']))}")
    if not args.k < info["n_sectors"] / 2:
        raise ValueError(f"--k must be in 1..{(info['n_sectors'] - 1) // 2} for the model's {info['n_sectors']} "
                         f"sectors, got {args.k}")
    return info


def main(argv: Sequence[str] | None = None) -> int:
    """Check the options, say what runs, then the costs, the branch and its stability (or the departures); raises
    ValueError for a bad input."""
    args = build_parser().parse_args(argv)
    check_options(args)
    folders = {"--name": Path("results")} | ({"--cache": args.cache} if args.model is None else {})
    for option, folder in folders.items():                    # refused before the plan is said; created below
        writable_folder(option, folder, create=False)
    model = (f"the saved model {args.model}" if args.model is not None else
             f"the maps' disk model (ci, r_c = 10, r_MD = 10, 144 interface modes) built into {args.cache}")
    after = (f"the full disk marched from the wave at {', '.join(f'{w:g}' for w in args.departure)} rad/s "
             f"({args.periods} periods at most)" if args.departure else f"its stability every {args.every} points")
    against = "" if args.no_full else " against the full disk's"
    print(f"bench_travelling_wave: the {args.k}-diameter wave's GNL branch ({args.force:g} N at node LE, H = {args.H}) "
          f"from {args.range[0]:g} to {args.range[1]:g} times its linear 1B frequency (step {args.step:g}, at most "
          f"{args.max_points} points), then {after}; the cost of one sector's balance"
          f"{against}; on {model}; writes results/{args.name}.json",
          flush=True)
    before_work(folders, {"--model": args.model})             # before any work; a dry run stops here

    from rotor37_rom.disk.harmonics import harmonic_frequencies
    from rotor37_rom.disk.loads import node_load_matrix
    from rotor37_rom.periodic import (Harmonics, HarmonicBalance, TravellingWaveBalance, continue_branch,
                                      model_force, solve_periodic, travelling_excitation)

    t0 = time.perf_counter()
    model = map_model(args.model, args.cache)
    t_model = time.perf_counter() - t0
    P = node_load_matrix(model.nodes, model.r, "LE", 2)
    le = model.nodes.q_index[model.nodes.row("LE", 0), 2]
    w0 = float(harmonic_frequencies(model, 1)[args.k, 0])
    basis = Harmonics(args.H, 4 * args.H + 3)
    F = travelling_excitation(P, args.force, args.k, basis)
    tw = TravellingWaveBalance(model, F, basis, args.k)
    print(f"model r = {model.r} ({t_model:.0f} s); k = {args.k}: linear 1B {w0:,.1f} rad/s (EO{args.k} at "
          f"{w0 / args.k:,.1f} rad/s); one sector: {tw.size} unknowns of {basis.size * model.r}", flush=True)

    out = {"model_r": model.r, "k": args.k, "force_N": args.force, "H": args.H,
           "omega_linear": w0, "unknowns_one_sector": tw.size, "unknowns_disk": basis.size * model.r}

    # cost: the balance's residual and Jacobian, one sector against the full disk, at the same state
    start = solve_periodic(tw, np.zeros(tw.size), args.range[0] * w0, stability=False, tol=1e-8)
    reps = 3
    t = time.perf_counter()
    for _ in range(reps):
        tw.residual(start.X.ravel(), start.omega)
    out["one_sector_residual_jacobian_s"] = (time.perf_counter() - t) / reps
    if not args.no_full:
        full = HarmonicBalance(model.M, model.C, model.K, model_force(model.forces), F, basis)
        X = tw.coefficients(start.X).ravel()
        t = time.perf_counter()
        full.residual(X, start.omega)
        out["disk_residual_jacobian_s"] = time.perf_counter() - t
        out["ratio"] = out["disk_residual_jacobian_s"] / out["one_sector_residual_jacobian_s"]
        del full
        print(f"residual + Jacobian: one sector {out['one_sector_residual_jacobian_s']:.3f} s, the disk "
              f"{out['disk_residual_jacobian_s']:.2f} s ({out['ratio']:.0f}x)", flush=True)

    # the branch (Newton to 1e-8: the round-off floor of this model's update is ~1e-9), then the stability per class
    # at every --every-th point (the classes' Hill problems cost ~30 s a point at H = 3: the branch's cost x 10)
    t = time.perf_counter()
    branch = continue_branch(tw, start, args.range[1] * w0, args.step, max_points=args.max_points, tol=1e-8,
                             stability=False)
    out["branch_s"] = time.perf_counter() - t
    if args.departure:
        return departures(args, tw, branch, out)
    t = time.perf_counter()
    rows, previous = [], None
    for i, pt in enumerate(branch.points):
        Xd = tw.coefficients(pt.X)
        row = {"omega": pt.omega, "speed": pt.omega / args.k,
               "le0_m": float(np.abs(basis.synthesis @ Xd[:, le]).max())}
        if i % args.every == 0 or i == len(branch.points) - 1:
            ce = tw.class_exponents(pt.X, pt.omega)
            growth = {j: float(e.real.max()) for j, e in ce.items() if e.size}
            row["unstable_classes"] = [j for j, g in growth.items() if g > 1e-9 * pt.omega]
            row["largest_multiplier"] = float(np.exp(max(growth.values()) * 2 * np.pi / pt.omega))
            row["stable"] = not row["unstable_classes"]
            if previous is not None and previous["stable"] != row["stable"]:
                print(f"  stability {'lost' if previous['stable'] else 'regained'} between {previous['speed']:,.1f} "
                      f"and {row['speed']:,.1f} rad/s (node LE {1e3 * row['le0_m']:.3f} mm); unstable classes "
                      f"(nodal diameters) {row['unstable_classes'] or previous['unstable_classes']}", flush=True)
            previous = row
        rows.append(row)
    out["stability_s"] = time.perf_counter() - t
    out.update({"folds": branch.folds, "ended": branch.ended, "every": args.every})
    peak = max(rows, key=lambda r: r["le0_m"])
    print(f"branch: {len(rows)} points in {out['branch_s']:.0f} s ({branch.ended}); stability at every "
          f"{args.every}-th in {out['stability_s']:.0f} s; peak node LE {1e3 * peak['le0_m']:.3f} mm at "
          f"{peak['speed']:,.1f} rad/s; {len(branch.folds)} folds")
    machine = write_results(args.name, rows, **out)
    print(f"results: results/{args.name}.json ({machine})")
    return 0


if __name__ == "__main__":
    sys.exit(run_main(main))
