# # Blade-tip/casing contact: interaction maps, NFRC and continuation (paper §2.3.1, §2.3.3; Figs. 6, 7, 11, 12)
#
# Builds (or loads) a reduced model of the clamped blade, then sweeps the angular speed with the casing ovalized into
# two lobes (eqs. 37-38; c0 = 0.5 mm, h_b = 0.625 mm, mu = 0.15), GNL off and on. Every speed's result is written as
# it finishes; a killed run started again resumes. The same command under `mpirun -n N` splits the speeds over the
# ranks (give --model, the file the serial run saved; with --cubature rank 0 trains, the others wait).
#
#     python demos/contact_map.py --preset ci --speeds 1200 1600 21 --revolutions 20          # minutes
#     python demos/contact_map.py --preset coarse --speeds 1200 1600 201 --revolutions 200      # paper scale (hours)
#     mpirun -n 2 python demos/contact_map.py --model results/contact_map/rom.npz --speeds 1200 1600 21
#     OPENBLAS_NUM_THREADS=1 mpirun -n 2 python demos/contact_map.py --model results/contact_map/rom.npz --gnl on \
#         --cubature 1e-4 --precision single --frequency-cap 120 --mu 0 --speeds 1200 1600 100 --revolutions 200 \
#         --batch 50 --out results/headline     # the GNL headline map on 2 cores (README: measured wall time)

# +
from __future__ import annotations

import argparse
import json
import logging
import sys
import time
from pathlib import Path

import numpy as np
import scipy.linalg

PAPER = {"linear 1B/EO4": 1317.0, "zero IC, no GNL": 1446.0, "zero IC, GNL": 1535.0,
         "continuation, no GNL": 1520.0, "continuation, GNL": 1551.0}
# -


# +
def build_or_load(args, comm):
    from rotor37_rom.reduction import load_reduced_model, save_reduced_model

    out = Path(args.out)
    if args.model:
        return load_reduced_model(args.model)
    if comm is not None and comm.size > 1:
        raise SystemExit("error: under MPI give --model (the rom.npz a serial run saved); the reduction is serial")
    from rotor37_rom import fem
    from rotor37_rom.builder import ReductionConfig, build_reduced_model

    sector = fem.create_blade_sector(preset=args.preset)
    config = ReductionConfig(r_c=args.r_c, r_md=args.r_md, global_md_modes=args.global_md, forces="intrusive")
    t0 = time.perf_counter()
    model, _ = build_reduced_model(sector, config, cache_dir=out / "cache")
    print(f"reduced model: {args.preset} preset ({sector.n_dofs} DOF) -> r = {model.r} {model.sizes} "
          f"in {time.perf_counter() - t0:.1f} s")
    save_reduced_model(model, out / "rom.npz")
    return model


def cubature_model(args, model, speeds, casing, comm):
    """The model with point-cubature GNL forces trained on exact GNL runs at 6 of the speeds (trajectory states), and
    the states the GNL step is taken over (those runs' 24 of largest tip motion and the training states). Cached in
    <out>/cache: a restarted map does not retrain.
    Under MPI rank 0 trains (serial FE quadrature on its own copy of the mesh) while the others wait."""
    import hashlib
    import importlib

    importlib.import_module("rotor37_rom.fem")    # on every rank: importing dolfinx initializes PETSc (collective)
    from rotor37_rom.integrator import CentralDifference, training_speeds
    from rotor37_rom.reduction import load_reduced_model

    train = training_speeds(speeds)
    revolutions = min(args.revolutions, 12.0)
    scheme = CentralDifference(model, nonlinear=True, safety=args.safety)
    key = hashlib.sha256(json.dumps([model.key, train.tolist(), revolutions, scheme.h, vars(casing), args.cubature,
                                     "step states: largest and training"],
                                    sort_keys=True, default=str).encode()).hexdigest()[:16]
    cache = Path(args.out) / "cache" / f"cubature_{key}.npz"
    rank = 0 if comm is None else comm.rank
    if cache.is_file():
        if rank == 0:
            print(f"cubature: reusing {cache}")
    else:
        error = None
        if rank == 0:
            try:
                _train_cubature(args, model, scheme, train, revolutions, casing, cache)
            except ValueError as exc:
                error = str(exc)
        if comm is not None:
            error = comm.bcast(error, root=0)
        if error is not None:
            raise ValueError(error)
    with np.load(cache.with_suffix(".states.npz")) as data:
        states = data["states"]
    return load_reduced_model(cache), states


def continued_revolutions(revolutions: float) -> float:
    """Length of each continued run: 15 % of the first (the paper: 200 then 30), at least 5 revolutions."""
    return max(5.0, revolutions * 0.15)


def continuation_branches(args, scheme, retried, start, stop, casing, out: Path, tag: str, comm) -> dict:
    """Continuation up and down (§2.3.3) at the step the map's speeds all ran with (the smallest retry step, if any
    speed was run again), the first run as long as the map's, the next 15 % of it (the paper: 200 then 30).
    Under MPI the two branches run on ranks 0 and 1 at once; rank 0 gets both. Each branch is written after every
    accepted speed (``sweep.continuation(out=...)``), so a killed run resumes. Returns {name: (points, h, wall)}."""
    from rotor37_rom.sweep import continuation

    if args.continuation <= 0:
        return {}
    run_scheme = scheme.with_step(min(retried.values())) if retried else scheme
    legs = {"up": (start, stop), "down": (stop, start)}
    rank, size = (0, 1) if comm is None else (comm.rank, comm.size)
    mine = {}
    for k, (name, (a, b)) in enumerate(legs.items()):
        if k % size == rank:
            t0 = time.perf_counter()
            pts = continuation(run_scheme, a, b, args.continuation, casing, first_revolutions=args.revolutions,
                               revolutions=continued_revolutions(args.revolutions), out=out / "continuation" / tag,
                               window=args.steady_window, progress=not args.quiet)
            mine[name] = (pts, run_scheme.h, time.perf_counter() - t0)
    if comm is not None:
        gathered = comm.gather(mine, root=0)
        mine = {k: v for part in gathered for k, v in part.items()} if rank == 0 else {}
    return mine


def _train_cubature(args, model, scheme, train, revolutions, casing, cache: Path):
    from mpi4py import MPI

    from rotor37_rom import fem
    from rotor37_rom.builder import hyper_reduce
    from rotor37_rom.integrator import contact_training_states
    from rotor37_rom.reduction import save_reduced_model

    t0 = time.perf_counter()
    Q_train, step_states = contact_training_states(scheme, train, casing, revolutions)
    sector = fem.create_blade_sector(MPI.COMM_SELF, preset=args.preset)
    reduced, rep = hyper_reduce(sector, model, Q_train, tol=args.cubature, level="point",
                                label=f"contact runs {train.tolist()} x {revolutions:g} rev, mu = {casing.mu:g}")
    print(f"cubature: {rep['points']} of {rep['exact'].w.size} quadrature points (training error "
          f"{rep['result'].training_error:.1e}) from {Q_train.shape[1]} states of exact GNL runs at "
          f"{len(train)} speeds x {revolutions:g} rev; {time.perf_counter() - t0:.0f} s")
    cache.parent.mkdir(parents=True, exist_ok=True)
    np.savez(cache.with_suffix(".states.npz"), states=step_states)
    save_reduced_model(reduced, cache)                  # written last: its presence means both are complete


def sprag_slip_onsets(model, casing) -> dict:
    """Friction coefficients at which sustained sliding on the casing diverges (rotor37_rom.friction)."""
    from rotor37_rom.casing import contact_matrices
    from rotor37_rom.friction import sprag_slip_friction

    N, S, _, _ = contact_matrices(model.nodes, model.r, casing)
    single = [sprag_slip_friction(model.K, N, S, [k]) for k in range(N.shape[0])]
    return {"weakest_node": min(single), "per_node": single, "all_nodes": sprag_slip_friction(model.K, N, S)}


def _finite(x):
    return x if np.isfinite(x) else None            # JSON has no inf: null = friction never wedges these nodes


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description="interaction maps of the reduced blade with casing contact")
    parser.add_argument("--preset", default="ci")
    parser.add_argument("--model", help="load this reduced model (.npz) instead of building one")
    parser.add_argument("--r-c", type=int, default=15)
    parser.add_argument("--r-md", type=int, default=0)
    parser.add_argument("--global-md", type=int, default=3)
    parser.add_argument("--speeds", type=float, nargs=3, default=[1200.0, 1600.0, 21], metavar=("START", "STOP", "N"))
    parser.add_argument("--revolutions", type=float, default=20.0)
    parser.add_argument("--gnl", choices=["off", "on", "both"], default="both")
    parser.add_argument("--safety", type=float, default=0.5, help="h = safety * 2 / omega_max (linear model)")
    parser.add_argument("--h", type=float, help="time step (s); overrides --safety")
    parser.add_argument("--frequency-cap", type=float, metavar="KHZ",
                        help="spectral mass scaling: slow the modes above this frequency (kHz) to it; the GNL step "
                             "then comes from the tangent limit on a short unscaled probe run "
                             "(benchmarks/bench_contact_convergence.py measures the error: 60 kHz is within 3 %%)")
    parser.add_argument("--tangent-safety", type=float, default=0.5,
                        help="GNL with a cap: h = this x 2 / tangent omega_max on the probe's largest states "
                             "(0.7 lost speeds at 120 kHz in bench_contact_convergence, 0.5 none in "
                             "bench_contact_ecsw)")
    parser.add_argument("--cubature", type=float, metavar="TOL",
                        help="GNL: replace the exact cubic forces by point cubature trained to this relative "
                             "tolerance on exact GNL runs at 6 of the speeds (min(revolutions, 12) each; "
                             "bench_contact_ecsw: 1e-4 with a 120 kHz cap is the cheapest setting within the "
                             "problem's own sensitivity)")
    parser.add_argument("--precision", choices=["double", "single"], default="double",
                        help="with --cubature: arithmetic of the cubature forces (single: float32, 1.6-2.1x faster "
                             "in bench_contact_ecsw, within 4e-7 of the double force)")
    parser.add_argument("--retry-diverged", type=int, default=0, metavar="N",
                        help="run the speeds that blew up again with the step halved, up to N times")
    parser.add_argument("--mu", type=float, default=0.15)
    parser.add_argument("--c0", type=float, default=0.5e-3)
    parser.add_argument("--hb", type=float, default=0.625e-3)
    parser.add_argument("--direction", choices=["x", "radial"], default="x")
    parser.add_argument("--batch", type=int, default=16)
    parser.add_argument("--continuation", type=float, default=0.0,
                        help="speed step (rad/s) of a continuation up and down over the map's range (0: none); "
                             "under mpirun the two branches run on ranks 0 and 1; resumable")
    parser.add_argument("--continuation-range", type=float, nargs=2, metavar=("LOW", "HIGH"),
                        help="run the continuation over this speed range (rad/s) instead of the map's: up from LOW, "
                             "down from HIGH (each first run as long as the map's, 15 %% of it after)")
    parser.add_argument("--steady-window", type=int, default=1, metavar="N",
                        help="a continued run is steady when its max over the last N revolutions and the N before "
                             "agree to 2 %% (1, the paper's: periodic with the rotor; N: periods up to N T)")
    parser.add_argument("--out", default="results/contact_map")
    parser.add_argument("--quiet", action="store_true")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.WARNING, force=True)
    logging.getLogger().handlers[0].setLevel(logging.WARNING)

    from rotor37_rom.casing import Casing
    from rotor37_rom.integrator import CentralDifference
    from rotor37_rom.sweep import SweepSpec, interaction_map, load_sweep, record_row, rerun_diverged, run_sweep

    try:
        casing = Casing(c0=args.c0, h_b=args.hb, mu=args.mu, direction=args.direction)
        start, stop, n = args.speeds
        if not (0 < start <= stop) or n < 1:
            raise ValueError(f"--speeds: need 0 < START <= STOP and N >= 1, got {args.speeds}")
        speeds = np.linspace(start, stop, int(n))
        if args.frequency_cap is not None and not args.frequency_cap > 0:
            raise ValueError(f"--frequency-cap must be > 0 kHz, got {args.frequency_cap}")
        if args.cubature is not None and not 0 < args.cubature < 1:
            raise ValueError(f"--cubature must be in (0, 1), got {args.cubature}")
        if args.precision != "double" and args.cubature is None:
            raise ValueError("--precision single needs --cubature (the exact cubic tensors are evaluated in double)")
        if not 0 <= args.retry_diverged <= 4:
            raise ValueError(f"--retry-diverged must be in 0..4, got {args.retry_diverged}")
        if not args.continuation >= 0:
            raise ValueError(f"--continuation must be >= 0 rad/s (0: none), got {args.continuation}")
        c_start, c_stop = args.continuation_range or (start, stop)
        if args.continuation_range is not None and not 0 < c_start < c_stop:
            raise ValueError(f"--continuation-range: need 0 < LOW < HIGH rad/s, got {args.continuation_range}")
        cont_revolutions = continued_revolutions(args.revolutions)
        if not 1 <= args.steady_window <= cont_revolutions / 2:
            raise ValueError(f"--steady-window must be in 1..{int(cont_revolutions // 2)} revolutions (half of a "
                             f"continued run), got {args.steady_window}")
        if not 0 < args.tangent_safety <= 1:
            raise ValueError(f"--tangent-safety must be in (0, 1], got {args.tangent_safety}")
        spec = SweepSpec(revolutions=args.revolutions, casing=casing, batch_size=args.batch)
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    comm = None
    try:
        from mpi4py import MPI

        comm = MPI.COMM_WORLD if MPI.COMM_WORLD.size > 1 else None
    except ImportError:
        pass
    rank = comm.rank if comm is not None else 0
    out = Path(args.out)
    model = build_or_load(args, comm)
    lam = scipy.linalg.eigh(model.K, model.M, eigvals_only=True)
    omega = np.sqrt(lam[:3])
    lin_res = omega[0] / 4
    onset = sprag_slip_onsets(model, casing)
    summary = {"r": model.r, "sizes": model.sizes, "omega_1_3": omega.tolist(), "linear_resonance": lin_res,
               "speeds": [start, stop, int(n)], "revolutions": args.revolutions, "casing": vars(casing), "runs": {},
               "sprag_slip": {k: ([_finite(x) for x in v] if isinstance(v, list) else _finite(v))
                              for k, v in onset.items()}}
    if rank == 0 and not args.quiet:
        print(f"sustained sliding diverges (sprag-slip) from mu = {onset['weakest_node']:.3f} on one contact node, "
              f"{onset['all_nodes']:.3f} on all of them; this run: mu = {casing.mu:g} (growth can start below: "
              f"README, 'Why mu = 0.15 grows')")
    modes = {"off": [False], "on": [True], "both": [False, True]}[args.gnl]
    for gnl in modes:
        try:
            cap = None if args.frequency_cap is None else 2 * np.pi * 1e3 * args.frequency_cap
            h = args.h
            run_model, states = model, None
            if gnl and args.cubature is not None:
                from rotor37_rom.reduction import with_force_precision

                run_model, states = cubature_model(args, model, speeds, casing, comm)
                run_model = with_force_precision(run_model, args.precision)
            if cap is not None and gnl and h is None:
                from rotor37_rom.integrator import gnl_time_step, probe_states

                if states is None:
                    probe = speeds[:: max(1, len(speeds) // 16)]
                    states = probe_states(model, probe, casing, revolutions=min(4.0, args.revolutions))
                    print(f"GNL step from the tangent limit on a {min(4.0, args.revolutions):g}-revolution unscaled "
                          f"probe at {len(probe)} speeds")
                h = gnl_time_step(run_model, states, cap, safety=args.tangent_safety, cap_safety=args.safety)
                print(f"GNL with a {args.frequency_cap:g} kHz cap: h = {h:.3g} s")
            scheme = CentralDifference(run_model, nonlinear=gnl, h=h, safety=args.safety, frequency_cap=cap)
        except ValueError as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 2
        cub = gnl and args.cubature
        parts = [("GNL", "gnl") if gnl else ("no GNL", "linear")]      # (chart label, file tag) of each setting
        if cub:
            parts.append((f"cubature {args.cubature:g}", f"cub{args.cubature:g}"))
            if args.precision == "single":
                parts.append(("single", "f32"))
        if cap is not None:
            parts.append((f"cap {args.frequency_cap:g} kHz", f"cap{args.frequency_cap:g}k"))
        label, tag = ", ".join(p[0] for p in parts), "_".join(p[1] for p in parts)
        t0 = time.perf_counter()
        folder = run_sweep(scheme, speeds, spec, out / "sweeps", comm=comm, progress=not args.quiet)
        # rank 0 reads the records (~1 GB for the 100-speed headline map); rerun_diverged tells the others
        results = [r for r in load_sweep(folder) if np.isclose(float(r["omega"]), speeds).any()] if rank == 0 else []
        results, retried = rerun_diverged(scheme, results, spec, out / "sweeps", args.retry_diverged, comm=comm,
                                          progress=not args.quiet)
        wall = time.perf_counter() - t0
        branches = continuation_branches(args, scheme, retried, c_start, c_stop, casing, out, tag, comm)
        if rank != 0:
            continue
        imap = interaction_map(results)
        from rotor37_rom.charts import plot_interaction_map, plot_nfrc, plot_time_history

        plot_interaction_map(imap, out / f"interaction_map_{tag}.png", eigenfrequencies=omega, linear_resonance=lin_res,
                             title=f"node LE, {label}, r = {model.r}, {args.revolutions:g} rev., h = {scheme.h:.3g} s")
        ok = np.isfinite(imap.nfrc)
        peak = float(imap.speeds[ok][np.argmax(imap.nfrc[ok])]) if ok.any() else float("nan")
        worst = results[int(np.nanargmax(np.where(ok, imap.nfrc, -1)))] if ok.any() else results[0]
        plot_time_history(worst["t"], {"LE": worst["u_r"][record_row(worst, "0:LE")],
                                         "TE": worst["u_r"][record_row(worst, "0:TE")]},
                          out / f"time_history_{tag}.png", title=f"{label}, Omega = {float(worst['omega']):.0f} rad/s")
        revs = args.revolutions * len(results)
        works = np.array([np.asarray(r.get("work", np.full(4, np.nan)), float)[:2] for r in results])
        run = {"h": scheme.h, "h_crit": scheme.h_crit, "frequency_cap_khz": args.frequency_cap,
               "cubature": run_model.metadata.get("hyper_reduction"),
               "force_precision": getattr(run_model.forces, "precision", "double"), "peak_speed": peak,
               "peak_amplitude": float(np.nanmax(imap.nfrc)),
               "diverged": imap.speeds[imap.diverged].tolist(), "wall_s": wall,
               "retried": {f"{w:g}": hk for w, hk in retried.items()},
               "rev_per_s": revs / wall if wall > 1 else None, "nfrc": imap.nfrc.tolist(),
               "work_normal_J": works[:, 0].tolist(), "work_friction_J": works[:, 1].tolist(),
               "speeds": imap.speeds.tolist(), "contact_checks": {
                   "max_penetration": max(float(r["max_penetration"]) for r in results),
                   "min_multiplier": min(float(r["min_multiplier"]) for r in results),
                   "max_friction_power": max(float(r["friction_power"]) for r in results)}}
        summary["runs"][label] = run
        print(f"{label:>7}: h = {scheme.h:.3g} s (2/omega_max = {scheme.h_crit:.3g}), largest response at "
              f"{peak:.0f} rad/s ({run['peak_amplitude'] * 1e3:.3f} mm), linear 1B/EO4 {lin_res:.0f} rad/s; "
              f"{len(imap.diverged.nonzero()[0])} diverged ({len(retried)} run again with a smaller step); "
              f"{wall:.0f} s")
        if branches:
            curves = {}
            for name, (pts, h_cont, wall_cont) in branches.items():
                curves[f"continuation {name}"] = ([p.omega for p in pts], [p.amplitude for p in pts],
                                                  "+" if name == "up" else "o")
                best = max(pts, key=lambda p: p.amplitude if np.isfinite(p.amplitude) else -1)
                run[f"continuation_{name}_peak"] = best.omega
                run[f"continuation_{name}"] = [(p.omega, p.amplitude, p.steady, p.halvings) for p in pts]
                run[f"continuation_{name}_h"], run[f"continuation_{name}_wall_s"] = h_cont, wall_cont
                run["continuation_steady_window"] = args.steady_window
                unsteady = [f"{p.omega:.0f}" for p in pts if not p.steady]
                print(f"         continuation {name} (h = {h_cont:.3g} s, {wall_cont:.0f} s): largest response at "
                      f"{best.omega:.0f} rad/s ({best.amplitude * 1e3:.3f} mm); {len(pts)} speeds, not steady at "
                      f"{', '.join(unsteady) or 'none'}")
            curves["zero IC"] = (imap.speeds, imap.nfrc, "--")
            plot_nfrc(curves, out / f"nfrc_continuation_{tag}.png", lin_res, PAPER)
    if rank == 0:
        from rotor37_rom.charts import plot_nfrc

        previous = out / "summary.json"
        if previous.is_file():                     # keep the runs of an earlier call on the same set-up
            old = json.loads(previous.read_text())
            if (old.get("r"), old.get("speeds"), old.get("revolutions")) == (model.r, summary["speeds"],
                                                                              args.revolutions):
                for label, run in old.get("runs", {}).items():
                    if label not in summary["runs"]:
                        summary["runs"][label] = run
                    else:
                        summary["runs"][label] = {**run, **summary["runs"][label]}
        curves = {label: (np.array(run["speeds"]), np.array(run["nfrc"]), "-" if label.startswith("GNL") else "--")
                  for label, run in summary["runs"].items()}
        plot_nfrc(curves, out / "nfrc.png", lin_res, PAPER)
        out.mkdir(parents=True, exist_ok=True)
        (out / "summary.json").write_text(json.dumps(summary, indent=1, default=float))
        print(f"paper: linear {PAPER['linear 1B/EO4']:.0f}, zero IC {PAPER['zero IC, no GNL']:.0f} / "
              f"{PAPER['zero IC, GNL']:.0f} (no GNL / GNL), continuation {PAPER['continuation, no GNL']:.0f} / "
              f"{PAPER['continuation, GNL']:.0f} rad/s")
        print(f"charts and summary.json in {out}/")
    return 0


if __name__ == "__main__":
    sys.exit(main())
# -
