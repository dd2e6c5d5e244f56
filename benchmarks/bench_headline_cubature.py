"""Cubature training for the GNL headline, checked where the map is most sensitive: at its resonance jump, after the
map's full length, against the exact cubic tensors of the same basis.

The headline's cubature is trained to tol = 1e-4 (relative to the nonlinear force) on states of 12-revolution exact
runs at 6 of the map's speeds. This compares training variants at the same capped step, casing and length:
- a tighter tolerance on the same states;
- refinement: the first cubature is run for the map's length at the 6 training speeds, the states of those runs
  (amplitudes the 12-revolution runs never reach) are added, and the points are selected again. Training stays
  exact: the cubature only proposes the states, the forces at them come from the full quadrature.

Each variant is judged by (1) its force error on held-out long-run states (the end states of the headline map's 100
runs and of the exact runs), relative to the nonlinear force and to the whole internal force K q + g (the part that
drives the motion; the two nearly cancel in the modal-derivative coordinates), and (2) the NFRC at the check speeds
against the exact runs of ``bench_headline_exact.py`` (their folders are read, nothing is rerun), with the exact
tensors scaled by 1 + 1e-4 as the problem's floor where ``--floor`` names that run.

    python benchmarks/bench_headline_cubature.py --tols 1e-4 3e-5 --refine 0 200
"""
from __future__ import annotations

import argparse
import glob
import json
import sys
import time
from pathlib import Path

import numpy as np

from rotor37_rom.machine import write_results


def _files(patterns) -> list:
    return sorted({f for p in ([patterns] if isinstance(patterns, str) else patterns) for f in glob.glob(p)})


def _finals(patterns) -> tuple[np.ndarray, np.ndarray]:
    """Speeds and end states (r, n) of the cached sweep results matching the patterns (finite ones only)."""
    speeds, states = [], []
    for f in _files(patterns):
        with np.load(f) as d:
            if np.isfinite(d["q_final"]).all() and int(d["diverged_step"]) < 0:
                speeds.append(float(d["omega"]))
                states.append(d["q_final"])
    return np.array(speeds), (np.array(states).T if states else np.zeros((0, 0)))


def _largest(Q: np.ndarray, boundary_rows: np.ndarray, n: int) -> np.ndarray:
    """The n states (columns) of largest boundary-DOF motion (as ``dynamics.explicit.largest_states``)."""
    return Q[:, np.argsort(-np.abs(Q[boundary_rows]).max(axis=0))[:n]]


def _nfrc_by_speed(patterns) -> dict:
    from rotor37_rom.studies.sweep import interaction_map, load_sweep

    out = {}
    for folder in sorted({str(Path(f).parent) for f in _files(patterns)}):
        m = interaction_map(load_sweep(folder))
        out.update({round(float(w), 1): (None if d else float(a)) for w, a, d in zip(m.speeds, m.nfrc, m.diverged)})
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--headline", default="results/headline_r55", help="the demo's --out of the headline map")
    parser.add_argument("--model", default="results/cache/rom_1099cedcb1070e3ef2577892.npz",
                        help="the reduced model with exact tensors (and its basis) the headline was built from")
    parser.add_argument("--preset", default="ci", help="the mesh preset of that model")
    parser.add_argument("--tols", type=float, nargs="+", default=[1e-4, 3e-5])
    parser.add_argument("--refine", type=float, nargs="+", default=[0.0, 200.0],
                        help="revolutions of the refinement runs (0: none)")
    parser.add_argument("--speeds", type=float, nargs="+", default=[1361.6, 1365.7, 1369.7, 1373.7, 1438.4],
                        help="check speeds (the nearest map speeds are used)")
    parser.add_argument("--exact", nargs="+", default=[f"results/bench_headline_exact{s}/sweeps/*/omega_*.npz"
                                                       for s in ("", "_fold", "_fold2")],
                        help="exact-tensor runs to compare with (bench_headline_exact.py), as glob patterns")
    parser.add_argument("--floor", default="results/bench_headline_exact_floor/sweeps/*/omega_*.npz",
                        help="runs of bench_headline_exact.py --perturbation 1e-4")
    parser.add_argument("--variants", nargs="*", help="run only these variants (e.g. 1e-04/0 3e-05/200)")
    parser.add_argument("--out", default="results/bench_headline_cubature")
    args = parser.parse_args(argv)
    if min(args.tols) <= 0 or max(args.tols) >= 1 or min(args.refine) < 0:
        print("error: --tols must lie in (0, 1) and --refine must be >= 0 revolutions", file=sys.stderr)
        return 2
    from mpi4py import MPI

    from rotor37_rom import fem
    from rotor37_rom.reduction.builder import hyper_reduce
    from rotor37_rom.dynamics.casing import Casing
    from rotor37_rom.forces.cubature import trajectory_states
    from rotor37_rom.dynamics.explicit import (CentralDifference, contact_training_states, gnl_time_step, simulate,
        training_speeds)
    from rotor37_rom.npz import load_npz, save_npz
    from rotor37_rom.model.reduced import load_reduced_model, save_reduced_model, with_force_precision
    from rotor37_rom.studies.sweep import SweepSpec, interaction_map, load_sweep, run_sweep

    summary_path = Path(args.headline) / "summary.json"
    if not summary_path.is_file():
        print(f"error: --headline: {summary_path} not found (run the headline map first)", file=sys.stderr)
        return 2
    summary = json.loads(summary_path.read_text())
    run = next(v for k, v in summary["runs"].items() if k.startswith("GNL"))
    map_speeds, map_nfrc = np.array(run["speeds"]), np.array(run["nfrc"])
    peak = float(np.nanmax(map_nfrc))
    casing = Casing(**{k: v for k, v in summary["casing"].items() if k in ("c0", "h_b", "mu", "direction")})
    cap = 2 * np.pi * 1e3 * run["frequency_cap_khz"]
    model = load_reduced_model(args.model)
    out = Path(args.out)
    (out / "cache").mkdir(parents=True, exist_ok=True)

    # the demo's training set: exact GNL runs at 6 of the map's speeds, 12 revolutions, unscaled at 0.5 h_crit
    train = training_speeds(map_speeds)
    train_file = out / "cache" / "train_states.npz"
    t0 = time.perf_counter()
    if load_npz(train_file, ("Q", "seconds"), what="training runs") is None:
        scheme = CentralDifference(model, nonlinear=True, safety=0.5)
        Q_train, _ = contact_training_states(scheme, train, casing, 12.0)
        save_npz(train_file, Q=Q_train, seconds=time.perf_counter() - t0)
    with np.load(train_file) as d:
        Q_train, t_train = d["Q"], float(d["seconds"])
    print(f"training states: {Q_train.shape[1]} from exact runs at {train.round(1).tolist()} x 12 rev "
          f"({t_train:.0f} s)")

    # held-out long-run states: end states of the headline map (but at the training speeds, which the refinement
    # runs visit) and of the exact runs (200 revolutions)
    w_map, Q_map = _finals(f"{args.headline}/sweeps/*/omega_*.npz")
    _, Q_ex = _finals(args.exact)
    Q_map = Q_map[:, ~np.isin(np.round(w_map, 6), np.round(train, 6))] if Q_map.size else Q_map
    Q_held = np.hstack([q for q in (Q_map, Q_ex) if q.size])
    g_ex = model.nonlinear_force(Q_held)
    net = np.linalg.norm(model.K @ Q_held + g_ex, axis=0)

    sector = fem.create_blade_sector(MPI.COMM_SELF, preset=args.preset)
    check = np.unique([map_speeds[np.argmin(np.abs(map_speeds - w))] for w in args.speeds])
    exact = _nfrc_by_speed(args.exact)
    floor = _nfrc_by_speed(args.floor)
    previous = Path("results") / f"{out.name}.json"          # variants run by earlier calls are kept
    rows = json.loads(previous.read_text())["rows"] if previous.is_file() else []
    for tol in args.tols:
        for refine in args.refine:
            name = f"{tol:.0e}/{refine:g}"
            if args.variants and name not in args.variants:
                continue
            path = out / "cache" / f"cubature_{tol:.0e}_{refine:g}.npz"
            t0 = time.perf_counter()
            if not path.is_file():
                base_path = out / "cache" / f"cubature_{tol:.0e}_0.npz"
                if base_path.is_file():
                    base = load_reduced_model(base_path)
                else:
                    base, _ = hyper_reduce(sector, model, Q_train, tol=tol, level="point",
                                           label=f"headline training, 6 speeds x 12 rev, tol {tol:g}")
                    save_reduced_model(base, base_path)
                reduced = base
                if refine > 0:     # the first cubature proposes long-run states, the full quadrature trains on them
                    scheme = CentralDifference(with_force_precision(base, "single"), nonlinear=True, h=run["h"],
                                               frequency_cap=cap)
                    res = simulate(scheme, train, casing, revolutions=refine, record_q=True, on_blowup="flag",
                                   record_every=max(1, int(round(1e-4 / scheme.h))))
                    # a run that blew up grows within a few hundred steps: drop its last 2 ms of records
                    runs = [q[:, t < (np.inf if k < 0 else k * scheme.h - 2e-3)]
                            for q, t, k in zip(res.records_q, res.t, res.diverged_step)]
                    Q_ref, _ = trajectory_states(runs, scheme.boundary_rows)
                    save_npz(path.with_suffix(".refine.npz"), Q_ref=Q_ref, diverged=res.diverged_step,
                             largest=_largest(np.hstack(runs), scheme.boundary_rows, 24))
                    reduced, _ = hyper_reduce(sector, model, np.hstack([Q_train, Q_ref]), tol=tol, level="point",
                                              label=f"headline training + {refine:g}-rev refinement, tol {tol:g}")
                save_reduced_model(reduced, path)
            reduced = load_reduced_model(path)
            t_build = time.perf_counter() - t0
            err = np.linalg.norm(reduced.nonlinear_force(Q_held) - g_ex, axis=0)
            # the GNL step at 0.5 of the tangent limit over the training states (the demo's rule) and, where
            # refined, over the long runs' states
            steps = {"train": gnl_time_step(reduced, Q_train, cap, 0.5)}
            if path.with_suffix(".refine.npz").is_file():
                with np.load(path.with_suffix(".refine.npz")) as d:
                    steps["refine"] = gnl_time_step(reduced, np.hstack([d["largest"], d["Q_ref"]]), cap, 0.5)
            scheme = CentralDifference(with_force_precision(reduced, "single"), nonlinear=True, h=run["h"],
                                       frequency_cap=cap)
            t0 = time.perf_counter()
            folder = run_sweep(scheme, check, SweepSpec(revolutions=summary["revolutions"], casing=casing,
                                                        batch_size=len(check)), out / "sweeps")
            t_check = time.perf_counter() - t0
            got = interaction_map([r for r in load_sweep(folder) if np.isclose(float(r["omega"]), check).any()])
            row = {"variant": name, "tol": tol, "refine_rev": refine,
                   "points": int(reduced.metadata["hyper_reduction"]["points"]),
                   "build_s": t_build, "check_s": t_check, "h_tangent_0.5": steps,
                   "force_err_g_median": float(np.median(err / np.linalg.norm(g_ex, axis=0))),
                   "force_err_g_max": float(np.max(err / np.linalg.norm(g_ex, axis=0))),
                   "force_err_net_median": float(np.median(err / net)), "force_err_net_max": float(np.max(err / net)),
                   "speeds": []}
            for w, a, d in zip(got.speeds, got.nfrc, got.diverged):
                key = round(float(w), 1)
                e, f = exact.get(key), floor.get(key)
                row["speeds"].append({"omega": float(w), "nfrc": None if d else float(a), "exact": e, "floor": f,
                                      "map": float(map_nfrc[np.argmin(np.abs(map_speeds - w))]),
                                      "diff_of_peak": None if d or e is None else abs(a - e) / peak})
            rows = [r for r in rows if r["variant"] != name] + [row]
            print(f"{name}: {row['points']} points, force error on {Q_held.shape[1]} long-run states "
                  f"{row['force_err_g_median']:.1e} / {row['force_err_g_max']:.1e} of g, "
                  f"{row['force_err_net_median']:.1e} / {row['force_err_net_max']:.1e} of K q + g "
                  f"(median / max); build {t_build:.0f} s, check {t_check:.0f} s; step at 0.5 of the tangent "
                  f"limit: " + ", ".join(f"{k} {v:.3g} s" for k, v in steps.items()))
            for s in row["speeds"]:
                fmt = (lambda v: "      -" if v is None else f"{v * 1e3:7.3f}")
                print(f"   {s['omega']:7.1f}: {fmt(s['nfrc'])} mm, exact {fmt(s['exact'])}, "
                      f"exact x (1 + 1e-4) {fmt(s['floor'])}, map {fmt(s['map'])}")
            write_results(out.name, rows, headline=args.headline, model=args.model, h=run["h"], map_peak=peak,
                          revolutions=summary["revolutions"], held_out_states=int(Q_held.shape[1]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
