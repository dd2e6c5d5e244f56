"""Friction-induced growth of the contact response: sliding stability (sprag-slip) and the energy balance per force.

With mu = 0.15 many speeds grow until the run is stopped (README, "where it breaks"). The integrator keeps the work
that each force does on the blade in the central-difference scheme's own energy balance (exact to round-off for the
linear scheme, ``test_energy_balance_with_contact_friction_forcing``): normal contact forces, friction, and the
energy the modal damping takes. This study runs one batch per rotation sense over speeds x friction coefficients
from rest (casing of the paper: c0 = 0.5 mm, h_b = 0.625 mm, normal e_x) and reports, per run, the LE amplitude over
the last revolution (or the time it was stopped), the three works, and the friction work per revolution against the
damping's over the last third of the run: the balance that decides whether a response grows. After each batch, the
number of speeds stopped per friction coefficient.

First, the stability of persistent sliding (``rotor37_rom.dynamics.friction``) at each tip node, the LE and TE halves
and all 8 nodes, in rotor 37's rotation sense (the other is refused: it turns this blade with its trailing edge
ahead): the divergence (sprag-slip) coefficient from the static compliance, and the first
instability of the constrained dynamics growing faster than --min-rate (1/s), divergence or flutter.

    python benchmarks/bench_friction_energy.py                  # linear, r = 55, 60 kHz cap: ~2 min
    python benchmarks/bench_friction_energy.py --gnl                # GNL, exact r = 55 tensors: ~45 min
    python benchmarks/bench_friction_energy.py --stability-only     # the sliding stability table: ~1 min

Results: results/bench_friction_energy[_gnl].json.
"""
from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from rotor37_rom.machine import write_results


def _tail_rates(t, work, energy, omega, fraction=1.0 / 3.0):
    """Friction work, normal work and damping per revolution over the last ``fraction`` of the recorded run."""
    ok = np.isfinite(energy)
    t, work = t[ok], work[:, ok]
    sel = t >= t[-1] * (1.0 - fraction)
    revs = (t[sel][-1] - t[sel][0]) * omega / (2 * np.pi)
    d = (work[:, sel][:, -1] - work[:, sel][:, 0]) / max(revs, 1e-12)
    return {"normal_per_rev": float(d[0]), "friction_per_rev": float(d[1]), "damping_per_rev": float(d[3])}


def sliding_stability(model, min_rate: float) -> list:
    """Onsets of friction-induced instability of persistent sliding, per node set and rotation sense (printed)."""
    from rotor37_rom.dynamics.casing import Casing, contact_matrices
    from rotor37_rom.dynamics.friction import critical_friction, sprag_slip_friction

    sets = {**{f"node {k}": [k] for k in range(8)}, "LE half (0-3)": [0, 1, 2, 3], "TE half (4-7)": [4, 5, 6, 7],
            "all 8": None}
    rows = []
    print(f"sliding stability, r = {model.r}: divergence mu* (static compliance) | first instability growing "
          f"faster than {min_rate:g} 1/s (mu, rate 1/s, frequency rad/s)")
    for sense in (-1,):
        N, S, _, _ = contact_matrices(model.nodes, model.r, Casing(rotation_sense=sense))
        print(f"rotation sense {sense:+d}")
        for name, nodes in sets.items():
            mu_d = sprag_slip_friction(model.K, N, S, nodes)
            mu_c, ev = critical_friction(model.M, model.C, model.K, N, S, nodes, mu_max=1.0, n_grid=200,
                                         min_rate=min_rate)
            rows.append({"sense": sense, "nodes": name, "mu_divergence": mu_d, "mu_first": mu_c,
                         "rate": ev.real, "frequency": abs(ev.imag)})
            print(f"  {name:>14}: {mu_d:7.4f} | {mu_c:7.4f}  {ev.real:9.1f}  {abs(ev.imag):9.0f}")
    return rows


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--r-c", type=int, default=25)
    parser.add_argument("--gnl", action="store_true", help="GNL model with its exact cubic tensors")
    parser.add_argument("--speeds", type=float, nargs="+", default=[1300.0, 1400.0, 1450.0, 1500.0])
    parser.add_argument("--mu", type=float, nargs="+", default=[0.0, 0.05, 0.1, 0.15])
    parser.add_argument("--senses", type=int, nargs="+", default=[-1], choices=[-1],
                        help="rotation senses: rotor 37's -1 (+1 turns this blade with its trailing edge ahead)")
    parser.add_argument("--revolutions", type=float, default=15.0)
    parser.add_argument("--cap", type=float, default=60.0, help="frequency cap (kHz) of the linear runs; 0: none")
    parser.add_argument("--tangent-safety", type=float, default=0.5, help="GNL: h = safety x 2 / omega_tangent")
    parser.add_argument("--min-rate", type=float, default=10.0,
                        help="sliding instabilities growing slower than this (1/s) are not counted")
    parser.add_argument("--stability-only", action="store_true", help="the sliding stability table only")
    args = parser.parse_args(argv)
    from rotor37_rom import fem
    from rotor37_rom.reduction.builder import ReductionConfig, build_reduced_model
    from rotor37_rom.dynamics.casing import Casing
    from rotor37_rom.dynamics.explicit import CentralDifference, gnl_time_step, probe_states, simulate
    from rotor37_rom.post.signals import last_revolution_max

    sector = fem.create_blade_sector(preset="ci")
    ops = fem.create_svk_operators(sector)
    config = ReductionConfig(r_c=args.r_c, r_md=0, global_md_modes=3, forces="intrusive" if args.gnl else "none")
    model, _ = build_reduced_model(sector, config, ops=ops, cache_dir="results/cache")
    stability = sliding_stability(model, args.min_rate)
    if args.stability_only:
        write_results("bench_friction_stability", stability, settings=vars(args))
        return 0
    if args.gnl:
        probe = probe_states(model, args.speeds, Casing(mu=0.15))
        scheme = CentralDifference(model, nonlinear=True, h=gnl_time_step(model, probe, safety=args.tangent_safety))
    else:
        cap = 2 * np.pi * args.cap * 1e3 if args.cap > 0 else None
        scheme = CentralDifference(model, nonlinear=False, frequency_cap=cap, safety=0.5)
    kind = "GNL" if args.gnl else "linear"
    print(f"{kind}, r = {model.r}, h = {scheme.h:.4g} s, {args.revolutions:g} rev from rest, casing c0 = 0.5 mm, "
          f"h_b = 0.625 mm, normal e_x")
    grid = [(w, m) for w in args.speeds for m in args.mu]
    name = "bench_friction_energy" + ("_gnl" if args.gnl else "")
    rows = []
    for sense in args.senses:
        casings = [Casing(mu=m, rotation_sense=sense) for _, m in grid]
        speeds = np.array([w for w, _ in grid])
        t0 = time.perf_counter()
        res = simulate(scheme, speeds, casings, revolutions=args.revolutions, record_every=100, energy=True,
                       on_blowup="flag")
        wall = time.perf_counter() - t0
        print(f"\nrotation sense {sense:+d} ({len(grid)} runs, one batch, {wall:.0f} s)")
        print(f"{'rad/s':>6} {'mu':>5} {'LE mm':>7} {'stopped':>9} {'E end J':>9} {'W_n J':>9} {'W_f J':>9} "
              f"{'D J':>9} {'W_n/rev':>8} {'W_f/rev':>8} {'D/rev':>8}")
        for p, (w, m) in enumerate(grid):
            t, E, W = res.t[p], res.energy[p], res.work_history[p]
            stopped = int(res.diverged_step[p])
            valid = np.isfinite(res.u_r[p][res.row("0:LE")])              # a stopped run: its last revolution before the stop
            amp = last_revolution_max(t[valid], res.u_r[p][res.row("0:LE")][valid], w)
            rates = _tail_rates(t, W, E, w)
            end = np.flatnonzero(np.isfinite(E))[-1]        # last record: energy and works at the same instant
            e_end = float(E[end])
            row = {"omega": w, "mu": m, "sense": sense, "le_last_rev_m": amp,
                   "stopped_s": stopped * scheme.h if stopped >= 0 else None, "energy_end_J": e_end,
                   "work_normal_J": float(W[0, end]), "work_friction_J": float(W[1, end]),
                   "damping_J": float(W[3, end]), **rates, "wall_s": wall, "h": scheme.h, "r": model.r,
                   "gnl": args.gnl}
            rows.append(row)
            print(f"{w:>6.0f} {m:>5.2f} {amp * 1e3:>7.3f} "
                  f"{'-' if stopped < 0 else f'{stopped * scheme.h * 1e3:.1f} ms':>9} {e_end:>9.3g} "
                  f"{row['work_normal_J']:>9.3g} {row['work_friction_J']:>9.3g} {row['damping_J']:>9.3g} "
                  f"{rates['normal_per_rev']:>8.3g} {rates['friction_per_rev']:>8.3g} {rates['damping_per_rev']:>8.3g}")
        for m in args.mu:
            mine = [row for row in rows if row["sense"] == sense and row["mu"] == m]
            print(f"  mu = {m:.3f}: {sum(row['stopped_s'] is not None for row in mine)} of {len(mine)} speeds stopped")
        machine = write_results(name, rows, settings=vars(args), sliding_stability=stability)   # after each batch
    print(f"\nmachine: {machine}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
