# # Reduced blade: Craig-Bampton + modal derivatives, and clearance consumption (paper §2.1, §2.3.2)
#
# Builds reduced models of the clamped blade (r_b = 24 boundary DOFs at the 8 tip nodes, r_c fixed-interface modes,
# r_MD modal derivatives selected by a criterion of §3.1.2, and optionally the modal derivatives of the first clamped
# modes), draws the modal-derivative weights (Fig. 5 analogue), and computes the clearance consumption at node LE along
# 1B (zeta = 1 mm) and 1T (zeta = 0.5 mm) with the full-order model (linear and nonlinear statics) and with each
# reduced model (Figs. 9-10 analogues), cost next to error.
#
#     python demos/reduced_blade.py --preset ci                     # r_MD = 20, 80 and the 6 global MDs (minutes)
#     python demos/reduced_blade.py --preset ci --r-md --r-c 25      # the contact studies' r = 55 model only
#     python demos/reduced_blade.py --preset coarse --r-md 40 150    # closer to the paper's selection
#     python demos/reduced_blade.py --tolerance 0.2                  # the cheapest model the speed-accuracy study
#                                                                    # measured within 20 % (scene 'clearance')
#
# The study is one library function, `run_reduced_blade(ReducedBladeConfig(...))` of
# `rotor37_rom.studies.clearance_consumption`, returning a `ReducedBladeResult`; a bad option is one line on stderr and
# exit status 2.

# +
from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path
from typing import Sequence

import numpy as np

from rotor37_rom.cli import TABLE_HELP, ArgumentParser, run_main
from rotor37_rom.geometry.blade import MESH_PRESETS
from rotor37_rom.post.clearance import delta_range_within
from rotor37_rom.reduction.craig_bampton import CRITERIA
from rotor37_rom.studies.clearance_consumption import (FORCES, PAPER_LINEAR_RANGE, ReducedBladeConfig,
    ReducedBladeResult, run_reduced_blade)
# -


# ## What to compute
#
# `ReducedBladeConfig`: the blade, the reduced models (r_c, one model per r_MD, the criterion, the global MDs) and the
# clearance study's load levels; with `--tolerance`, the one model the speed-accuracy study chose.
#
# ## Results
#
# One `ClearanceStudy` per mode: the curves Delta(delta) of the full-order model (linear and nonlinear) and of each
# reduced model, with the two numbers the paper quotes: where the linear model stays within 10 % of the nonlinear one,
# and each reduced model's largest error.
#
# ## The models
#
# Built through `rotor37_rom.reduction.builder` (Craig-Bampton, modal derivatives, reduced forces) and cached under a
# key of their parameters and mesh: a second run loads them.
#
# ## Clearance consumption
#
# Static analyses under delta f^X, delta in [-1, 1], with f^X = K phi^X and phi^X scaled to move node LE by zeta
# along e_x: full order linear and nonlinear, and each reduced model (nonlinear).


# ## Command line

# +
def print_report(config: ReducedBladeConfig, result: ReducedBladeResult) -> None:
    """Each model's size, cost and frequency error; each curve's end values, error and cost."""
    print(f"blade: {config.preset} preset, {result.sector.n_dofs} DOF; clamped 1B/1T/2B {np.round(result.omega, 1)} "
          "rad/s")
    print(f"\n{'ROM':>20} {'r':>4} {'offline (s)':>11} {'omega_1..3 error':>22}")
    for name, model in result.models.items():
        err = np.array2string(result.frequency_errors(name), precision=1, floatmode="fixed")
        print(f"{name:>20} {model.r:>4} {result.seconds[name]:>11.1f} {err}")
    for mode, study in result.clearance.items():
        curves = study.curves
        print(f"\nclearance consumption at node LE along {mode} (zeta = {curves.zeta * 1e3:g} mm along e_x)")
        print(f"{'model':>20} {'Delta(-1) mm':>12} {'Delta(+1) mm':>12} {'max rel. err':>12} "
              f"{'<=10 % for delta in':>20} {'cost (s)':>9}")
        for name, values in curves.curves.items():
            cost = curves.costs.get(name, float("nan"))
            if not np.isfinite(values).any():
                print(f"{name:>20} {'no equilibrium: the reduced Newton lost it (poor basis)':>57} {cost:>9.1f}")
                continue
            lo, hi = delta_range_within(curves.deltas, study.error(name))
            print(f"{name:>20} {values[0] * 1e3:>12.4f} {values[-1] * 1e3:>12.4f} {study.max_error(name):>12.3f} "
                  f"{f'[{lo:+.2f}, {hi:+.2f}]':>20} {cost:>9.1f}")
        print(f"paper: the linear model's error exceeds 10 % outside {list(PAPER_LINEAR_RANGE[mode])}")
    print(f"\ncharts in {config.out}/")


def build_parser() -> ArgumentParser:
    parser = ArgumentParser(description="reduced models of the blade and their clearance consumption",
                            argument_default=argparse.SUPPRESS)        # an option not given keeps the config's default
    parser.add_argument("--preset", help=f"mesh preset: {', '.join(MESH_PRESETS)} (default ci)")
    parser.add_argument("--table", help=TABLE_HELP + " (default none)")
    parser.add_argument("--r-c", type=int, help="fixed-interface modes (>= 1, default 15)")
    parser.add_argument("--r-md", type=int, nargs="*",
                        help="one model per value, with that many selected modal derivatives (default 20 80)")
    parser.add_argument("--criterion", help=f"MD selection: {', '.join(CRITERIA)} (default MI2b)")
    parser.add_argument("--forces", help=f"reduced forces: {', '.join(FORCES)}")
    parser.add_argument("--levels", type=int, help="load levels on each side of delta = 0 (1..50)")
    parser.add_argument("--global-md", type=int,
                        help="also build r_MD = 0 + the MDs of the first N clamped normal modes (0: skip; 0..20)")
    parser.add_argument("--out", type=Path, help="output folder (default results/reduced_blade)")
    parser.add_argument("--tolerance", type=float, metavar="TOL",
                        help="build only the cheapest reduced model within this relative error of the clearance "
                             "consumption in the speed-accuracy study (docs/choosing-a-model.md), in (0, 1); it sets "
                             "--r-c, --r-md, --criterion, --global-md and runs the study's setting (ci, built-in "
                             "blade, exact tensors)")
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Parse the options, run the study, print the tables; raises ValueError for a bad input."""
    args = vars(build_parser().parse_args(argv))
    if "r_md" in args:
        args["r_md"] = tuple(args["r_md"])
    given = [f"--{k.replace('_', '-')}" for k, v in args.items() if k in ("r_c", "r_md", "criterion", "global_md",
                                                                              "preset", "table", "forces")]
    if "tolerance" in args and given:
        raise ValueError(f"--tolerance chooses {', '.join(given)}: give either the tolerance or the options")
    config = ReducedBladeConfig(**args)
    if config.tolerance is not None:
        print(f"--tolerance {config.tolerance:g}: {config.choice.describe()}")
    logging.basicConfig(level=logging.WARNING, force=True)
    logging.getLogger().handlers[0].setLevel(logging.WARNING)
    print_report(config, run_reduced_blade(config))
    return 0


if __name__ == "__main__":
    sys.exit(run_main(main))
# -
