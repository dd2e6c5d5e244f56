# # Reduced blade: Craig-Bampton + modal derivatives, and clearance consumption (paper §2.1, §2.3.2)
#
# Builds reduced models of the clamped blade (r_b = 24 boundary DOFs at the 8 tip nodes, r_c fixed-interface modes,
# r_MD modal derivatives selected by a criterion of §3.1.2), draws the modal-derivative weights (Fig. 5 analogue),
# and computes the clearance consumption at node LE along 1B (zeta = 1 mm) and 1T (zeta = 0.5 mm) with the full-order
# model (linear and nonlinear statics) and with each reduced model (Figs. 9-10 analogues), cost next to error.
#
#     python demos/reduced_blade.py --preset ci --r-md 20 80      # quick
#     python demos/reduced_blade.py --preset coarse --r-md 40 150  # closer to the paper (minutes)

# +
from __future__ import annotations

import argparse
import logging
import sys
import time
from pathlib import Path

import numpy as np
import scipy.linalg

from rotor37_rom import fem
from rotor37_rom.builder import ReductionConfig, build_reduced_model, clearance_consumption_study
from rotor37_rom.charts import (plot_clearance_consumption, plot_indicator_vs_rmd, plot_md_weights,
                                plot_speed_accuracy)
from rotor37_rom.clearance import delta_range_within, relative_error

PAPER_LINEAR_RANGE = {"1B": (-0.25, 0.2), "1T": (-0.1, 0.1)}
# -


# +
def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--preset", default="ci")
    parser.add_argument("--r-c", type=int, default=15)
    parser.add_argument("--r-md", type=int, nargs="+", default=[20, 80])
    parser.add_argument("--criterion", default="MI2b")
    parser.add_argument("--forces", default="quadrature", help="intrusive, quadrature, ecsw, step")
    parser.add_argument("--levels", type=int, default=10, help="load levels on each side of delta = 0")
    parser.add_argument("--global-md", type=int, default=3,
                        help="also build r_MD = 0 + the MDs of the first N clamped normal modes (0: skip)")
    parser.add_argument("--out", default="results/reduced_blade")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.WARNING, force=True)
    logging.getLogger().handlers[0].setLevel(logging.WARNING)
    out = Path(args.out)
    sector = fem.create_blade_sector(preset=args.preset)
    ops = fem.create_svk_operators(sector)
    exact = fem.compute_clamped_modes(sector, 3, ops).omega
    print(f"blade: {args.preset} preset, {sector.n_dofs} DOF; clamped 1B/1T/2B {np.round(exact, 1)} rad/s")
    roms = {}
    print(f"\n{'ROM':>20} {'r':>4} {'offline (s)':>11} {'omega_1..3 error':>22}")
    variants = [(r_md, 0) for r_md in args.r_md] + ([(0, args.global_md)] if args.global_md else [])
    for r_md, n_global in variants:
        config = ReductionConfig(r_c=args.r_c, r_md=r_md, criterion=args.criterion, forces=args.forces,
                                 global_md_modes=n_global)
        t0 = time.perf_counter()
        model, report = build_reduced_model(sector, config, ops=ops, cache_dir=out / "cache")
        wall = time.perf_counter() - t0
        name = f"ROM r_MD={r_md}" if not n_global else f"ROM {n_global * (n_global + 1) // 2} global MDs"
        roms[name] = model
        lam = scipy.linalg.eigh(model.K, model.M, eigvals_only=True)
        err = np.sqrt(lam[:3]) / exact - 1.0
        print(f"{name:>20} {model.r:>4} {wall:>11.1f} {np.array2string(err, precision=1, floatmode='fixed')}")
        if "weights" in report and r_md:
            plot_md_weights(report["weights"], report["pairs"], model.sizes["r_b"],
                            out / f"md_weights_{args.criterion}_{r_md}.png",
                            f"{args.criterion} weights, r_MD = {r_md} selected")
    for mode, zeta in (("1B", 1e-3), ("1T", 0.5e-3)):
        curves = clearance_consumption_study(sector, mode, zeta, args.levels, roms, ops)
        plot_clearance_consumption(curves, out / f"clearance_{mode}.png")
        ref = curves.curves["FOM nonlinear"]
        accuracy = []
        print(f"\nclearance consumption at node LE along {mode} (zeta = {zeta * 1e3:g} mm along e_x)")
        print(f"{'model':>20} {'Delta(-1) mm':>12} {'Delta(+1) mm':>12} {'max rel. err':>12} "
              f"{'<=10 % for delta in':>20} {'cost (s)':>9}")
        for name, values in curves.curves.items():
            cost = curves.costs.get(name, float("nan"))
            if not np.isfinite(values).any():
                print(f"{name:>20} {'no equilibrium: the reduced Newton lost it (poor basis)':>57} {cost:>9.1f}")
                continue
            err = relative_error(values, ref)
            lo, hi = delta_range_within(curves.deltas, err)
            print(f"{name:>20} {values[0] * 1e3:>12.4f} {values[-1] * 1e3:>12.4f} {np.nanmax(err):>12.3f} "
                  f"{f'[{lo:+.2f}, {hi:+.2f}]':>20} {cost:>9.1f}")
            if name != "FOM nonlinear" and np.isfinite(cost):
                accuracy.append((name, cost, float(np.nanmax(err))))
        print(f"paper: the linear model's error exceeds 10 % outside {list(PAPER_LINEAR_RANGE[mode])}")
        plot_speed_accuracy(accuracy, out / f"speed_accuracy_{mode}.png",
                            f"clearance consumption {mode}: cost vs max relative error (FOM nonlinear = reference)")
        md_rows = [(roms[n].sizes["r_md"], e) for n, _, e in accuracy if n.startswith("ROM r_MD=")]
        if md_rows:
            plot_indicator_vs_rmd(md_rows, out / f"error_vs_rmd_{mode}.png", f"{mode}: max clearance error vs r_MD")
    print(f"\ncharts in {out}/")
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        sys.exit(2)
# -
