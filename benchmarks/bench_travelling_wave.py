"""The tuned disk's travelling wave on one sector (#72 (f)): what one sector costs against the full disk's harmonic
balance, and the forced k-diameter wave's NFRC with GNL through its 1B resonance, its stability against every nodal
diameter at each point: where the wave loses stability, and to which diameters.

The model is the contact maps' disk model (ci sector, every tip node, r_c = 10, r_MD = 10 by MI 2b, 144 interface
modes: r = 1,728; its exact sector tensors), built here (~70 s, cached) or read with --model. The load is a unit
axial force at node LE of every sector travelling with k nodal diameters (engine order k on a tuned disk), ``--force``
N; the rotor speed of a point is omega / k. Stability: Hill's method per perturbation class j = 0 .. N/2 (nodal
diameter j in its constant part), ``periodic.travelling_wave``.

    python benchmarks/bench_travelling_wave.py [--model results/disk_map200/rom.npz] [--k 6] [--force 20] [--H 3]

With ``--departure SPEED ...`` the stability along the branch is replaced by the full disk marched from the wave at
those rotor speeds (``periodic.departure``): each set of nodal diameters' growth a period against Hill's.

Results: results/bench_travelling_wave.json (the machine, both costs and their ratio, the branch: speed, node LE's
amplitude, and at every --every-th point its stability and the classes that are unstable). ~30 min on this
machine.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from rotor37_rom.machine import write_results


def map_model(path: Path | None, cache: Path):
    """The maps' disk model with GNL (read from ``path``, else built into ``cache``)."""
    from rotor37_rom.model.reduced import load_reduced_model

    if path is not None:
        return load_reduced_model(path)
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
            print(f"bench_travelling_wave: --departure {speed:g} rad/s is not on the branch (its speeds "
                  f"{min(speeds):,.1f}-{max(speeds):,.1f} rad/s)", file=sys.stderr)
            return 2
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


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--model", type=Path, default=None, help="a saved disk model (default: build the maps' one)")
    p.add_argument("--k", type=int, default=6, help="the load's nodal diameters (engine order), 1..17")
    p.add_argument("--force", type=float, default=20.0, help="N at node LE of each sector (> 0)")
    p.add_argument("--H", type=int, default=3, help="harmonics (1..8)")
    p.add_argument("--range", type=float, nargs=2, default=(0.9, 1.6), metavar=("FROM", "TO"),
                   help="the branch from FROM to TO times the wave's linear 1B frequency")
    p.add_argument("--step", type=float, default=0.02, help="relative arc length of a step (> 0)")
    p.add_argument("--max-points", type=int, default=150, help="points of the branch at most")
    p.add_argument("--every", type=int, default=2, help="the stability at every this many points (>= 1)")
    p.add_argument("--no-full", action="store_true", help="skip the full disk's cost (its balance is dense)")
    p.add_argument("--departure", type=float, nargs="+", default=None, metavar="SPEED",
                   help="instead of the stability along the branch: the full disk marched from the wave at these rotor "
                        "speeds (rad/s, on the branch), each perturbation set's growth against Hill's")
    p.add_argument("--periods", type=int, default=60, help="--departure: wave periods marched at most (>= 8)")
    p.add_argument("--name", default="bench_travelling_wave", help="results/<name>.json")
    args = p.parse_args(argv)
    for ok, msg in ((1 <= args.k <= 17, f"--k must be in 1..17, got {args.k}"),
                    (args.force > 0, f"--force must be > 0 N, got {args.force}"),
                    (1 <= args.H <= 8, f"--H must be in 1..8, got {args.H}"),
                    (0 < args.range[0] < args.range[1], f"--range must be 0 < FROM < TO, got {args.range}"),
                    (args.step > 0, f"--step must be > 0, got {args.step}"),
                    (args.every >= 1, f"--every must be >= 1, got {args.every}"),
                    (args.departure is None or all(v > 0 for v in args.departure),
                     f"--departure speeds must be > 0 rad/s, got {args.departure}"),
                    (args.periods >= 8, f"--periods must be >= 8, got {args.periods}")):
        if not ok:
            print(f"bench_travelling_wave: {msg}", file=sys.stderr)
            return 2

    from rotor37_rom.disk.harmonics import harmonic_frequencies
    from rotor37_rom.disk.loads import node_load_matrix
    from rotor37_rom.periodic import (Harmonics, HarmonicBalance, TravellingWaveBalance, continue_branch,
                                      model_force, solve_periodic, travelling_excitation)

    t0 = time.perf_counter()
    model = map_model(args.model, Path("results/cache"))
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
    sys.exit(main())
