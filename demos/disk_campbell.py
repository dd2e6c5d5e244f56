# # The turning rotor 37 bladed disk: Campbell and interference (ZZENF) diagrams (#73)
#
# At each speed the whole disk's centrifugal equilibrium is solved on one sector (the load is the same on every
# sector), and every nodal-diameter family of the tangent there (geometric stiffening and spin softening) comes from
# the cyclic operators of that one matrix; with `--coriolis` each double mode splits into its forward and backward
# waves. Each engine order crosses the family it excites (e aliased by the 36 sectors: k = min(e mod 36, 36 - e mod
# 36), backward for e = k, forward for e = 36 - k), and the interference diagram shows, at one speed, the families
# against k with the orders' zig-zag. Charts and summary.json go to `results/disk_campbell/`.
#
#     python demos/disk_campbell.py                          # ci preset, 0-2,000 rad/s, 5 speeds, k = 0..18: ~5 min
#     python demos/disk_campbell.py --families 0 1 2 3 4 --coriolis --zzenf-speed 1800
#
# The study is one library function, `run_disk_campbell(DiskCampbellConfig(...))` of
# `rotor37_rom.studies.disk_campbell`; this script turns its options into that configuration and prints the
# crossings and the interference table. A bad option is one line on stderr, exit status 2.

# +
from __future__ import annotations

import logging
import sys
from pathlib import Path
from typing import Sequence

from rotor37_rom.cli import ArgumentParser, run_main
from rotor37_rom.geometry.blade import MESH_PRESETS
from rotor37_rom.studies.campbell import MAX_REFINE, MAX_SPEED_COUNT, MAX_TURNING_SPEED
from rotor37_rom.studies.disk_campbell import DiskCampbellConfig, DiskCampbellResult, run_disk_campbell
# -


# ## Command line

# +
def print_report(result: DiskCampbellResult) -> None:
    """Each family's lowest modes at the first and last speed, the crossings and the interference table."""
    print(f"{'k':>3} " + " ".join(f"{w:>9.0f}" for w in (result.speeds[0], result.speeds[-1])) + "  (rad/s, mode 1)")
    for f, k in enumerate(result.families):
        print(f"{k:>3} {result.omega[0, f, 0]:>9.1f} {result.omega[-1, f, 0]:>9.1f}")
    if result.mac.min() < 0.8:
        print(f"warning: a mode's shape changes between neighbouring speeds (MAC {result.mac.min():.2f}): give more "
              f"speeds or modes")
    print("crossings (family k, mode / engine order, wave: speed, frequency):")
    for c in result.crossings:
        how = (f"iterated, {c['refined']} steps" if c["refined"] > 0 else
               "NOT settled in 20 iterations" if c["refined"] < 0 else "interpolated on the grid")
        print(f"  k = {c['family']:2d}, mode {c['mode']} / EO{c['order']} ({c['direction']}): {c['speed']:8.1f} rad/s, "
              f"{c['frequency']:9.1f} rad/s ({how})")
    zz = result.zzenf
    print(f"interference at {zz['speed']:.0f} rad/s (order: index, wave, e Omega, nearest mode and margin):")
    for r in zz["orders"]:
        near = f"mode {r['nearest_mode']} {100 * r['margin']:+.1f} %" if "margin" in r else "family not computed"
        print(f"  EO{r['order']:<3d}: k = {r['index']:2d} {r['direction']:>8}, {r['frequency']:9.1f} rad/s; {near}")
    print(f"{result.wall_s:.0f} s; charts and summary.json: {', '.join(str(f) for f in result.files)}")


def build_parser() -> ArgumentParser:
    parser = ArgumentParser(description="Campbell and interference diagrams of the turning rotor 37 bladed disk")
    parser.add_argument("--preset", default="ci", help=f"mesh preset: {', '.join(MESH_PRESETS)} (default ci)")
    parser.add_argument("--speeds", type=float, nargs=3, default=(0.0, 2000.0, 5), metavar=("START", "STOP", "N"),
                        help=f"N speeds (rad/s) from START >= 0 to STOP <= {MAX_TURNING_SPEED:g} (rotor 37's range: "
                             f"its blade yields above), N in 2..{MAX_SPEED_COUNT} (default 0 2000 5)")
    parser.add_argument("--families", type=int, nargs="+", default=[],
                        help="nodal diameters 0..18 (default all)")
    parser.add_argument("--modes", type=int, default=3, help="modes per family (1..10, default 3)")
    parser.add_argument("--orders", type=int, nargs="+", default=list(range(1, 9)),
                        help="engine orders (1..200, default 1 to 8)")
    parser.add_argument("--zzenf-speed", type=float, default=None,
                        help=f"the interference diagram's speed (rad/s, 0..{MAX_TURNING_SPEED:g}; default the last "
                             f"speed)")
    parser.add_argument("--refine", type=float, default=0.0,
                        help=f"iterate each crossing on the disk to this (rad/s, 0..{MAX_REFINE:g}; default 0: "
                             f"interpolated on the grid)")
    parser.add_argument("--coriolis", action="store_true",
                        help="include the Coriolis force (forward and backward waves)")
    parser.add_argument("--no-prestress", action="store_true",
                        help="spin softening alone (no centrifugal stiffening)")
    parser.add_argument("--out", type=Path, default=Path("results/disk_campbell"), help="output folder")
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Parse the options, run the study, print the crossings; raises ValueError for a bad input."""
    args = build_parser().parse_args(argv)
    config = DiskCampbellConfig(preset=args.preset, speeds=tuple(args.speeds), families=tuple(args.families),
                                n_modes=args.modes, orders=tuple(args.orders), zzenf_speed=args.zzenf_speed,
                                refine=args.refine,
                                coriolis=args.coriolis, prestress=not args.no_prestress, out=args.out)
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s", force=True)
    logging.getLogger().handlers[0].setLevel(logging.WARNING)
    print_report(run_disk_campbell(config))
    return 0


if __name__ == "__main__":
    sys.exit(run_main(main))
# -
