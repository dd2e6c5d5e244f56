# # The turning rotor 37 blade's Campbell diagram (#73)
#
# At each speed the blade's centrifugal equilibrium (nonlinear SVK) and the modes of its tangent there, geometric
# stiffening and spin softening included (Coriolis with `--coriolis`), followed across speeds by their shapes; the
# engine-order lines and every crossing, each iterated on the blade to 0.01 rad/s. The chart and summary.json go to
# `results/campbell/`.
#
#     python demos/campbell.py                       # ci preset, 0-2,000 rad/s, EO 1-8: about 1 min
#     python demos/campbell.py --preset coarse --speeds 0 2000 21
#
# The study is one library function, `run_campbell(CampbellConfig(...))` of `rotor37_rom.studies.campbell`; this
# script turns its options into that configuration and prints the crossings. A bad option is one line on stderr, exit
# status 2.

# +
from __future__ import annotations

import logging
import sys
from pathlib import Path
from typing import Sequence

from rotor37_rom.cli import ArgumentParser, run_main
from rotor37_rom.geometry.blade import MESH_PRESETS
from rotor37_rom.studies.campbell import (MAX_REFINE, MAX_SPEED_COUNT, MAX_TURNING_SPEED, CampbellConfig,
                                         CampbellResult, run_campbell)
# -


# ## Command line

# +
def print_report(result: CampbellResult) -> None:
    """The modes at the first and last speed, and the crossings."""
    print(f"{'mode':>5} " + " ".join(f"{w:>9.0f}" for w in (result.speeds[0], result.speeds[-1])) + "  (rad/s)")
    for k, label in enumerate(result.labels):
        print(f"{label:>5} {result.omega[0, k]:>9.1f} {result.omega[-1, k]:>9.1f}")
    if result.mac.min() < 0.8:
        print(f"warning: a mode's shape changes between neighbouring speeds (MAC {result.mac.min():.2f}): give more "
              f"speeds or modes")
    print("crossings (mode / engine order: speed, frequency):")
    for c in result.crossings:
        how = (f"iterated, {c['refined']} steps" if c["refined"] > 0 else
               "NOT settled in 20 iterations" if c["refined"] < 0 else "interpolated on the grid")
        print(f"  {c['label']:>3} / EO{c['order']}: {c['speed']:8.1f} rad/s, {c['frequency']:9.1f} rad/s ({how})")
    print(f"{result.wall_s:.0f} s; chart and summary.json: {', '.join(str(f) for f in result.files)}")


def build_parser() -> ArgumentParser:
    parser = ArgumentParser(description="Campbell diagram of the turning rotor 37 blade")
    parser.add_argument("--preset", default="ci", help=f"mesh preset: {', '.join(MESH_PRESETS)} (default ci)")
    parser.add_argument("--speeds", type=float, nargs=3, default=(0.0, 2000.0, 11), metavar=("START", "STOP", "N"),
                        help=f"N speeds (rad/s) from START >= 0 to STOP <= {MAX_TURNING_SPEED:g} (rotor 37's range: "
                             f"its blade yields above), N in 2..{MAX_SPEED_COUNT} (default 0 2000 11)")
    parser.add_argument("--modes", type=int, default=4, help="modes followed (1..20, default 4)")
    parser.add_argument("--orders", type=int, nargs="+", default=list(range(1, 9)),
                        help="engine orders (1..100, default 1 to 8)")
    parser.add_argument("--refine", type=float, default=0.01,
                        help=f"iterate each crossing on the blade to this (rad/s, 0..{MAX_REFINE:g}; 0: interpolated; "
                             f"default 0.01)")
    parser.add_argument("--coriolis", action="store_true",
                        help="include the Coriolis force (gyroscopic, on 3x the modes without it)")
    parser.add_argument("--out", type=Path, default=Path("results/campbell"), help="output folder")
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Parse the options, run the study, print the crossings; raises ValueError for a bad input."""
    args = build_parser().parse_args(argv)
    config = CampbellConfig(preset=args.preset, speeds=tuple(args.speeds), n_modes=args.modes,
                            orders=tuple(args.orders), refine=args.refine, coriolis=args.coriolis,
                            out=args.out)
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s", force=True)
    logging.getLogger().handlers[0].setLevel(logging.WARNING)
    print_report(run_campbell(config))
    return 0


if __name__ == "__main__":
    sys.exit(run_main(main))
# -
