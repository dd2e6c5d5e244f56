# # Your own blade: from another FE code's mesh to modes, a reduced model, the sprag-slip onset and a contact run
#
# A blade mesh from CalculiX/Abaqus (.inp), gmsh (.msh), NASTRAN (.bdf/.nas) or VTK (.vtk/.vtu), in any units, with
# tetrahedra, wedges, hexahedra or pyramids of order 1 or 2 (split into conforming tetrahedra on reading:
# rotor37_rom.geometry.mesh_import), goes through the project's pipeline:
#
#     python demos/own_blade.py --mesh my_blade.inp --clamp ROOT --tip TIP --units mm
#     python demos/own_blade.py --mesh my_blade.msh --clamp clamp --tip tip --contact 16
#     python demos/own_blade.py                      # no mesh: the ci blade written as a mm Abaqus deck, read back
#
# It prints what was read (cells converted, bounding box, mass: a unit slip shows there), the first clamped
# modes, builds the Craig-Bampton model on the contact nodes (ordered LE -> TE along the tip chord), gives the
# sprag-slip onset mu* of each contact node and of the LE half (rotor37_rom.dynamics.friction), and runs a short rub on
# the paper's ovalised casing at one speed. Results: results/own_blade/summary.json. A bad option is one line on
# stderr, exit status 2.
#
# The scene is one library function, `run_own_blade(OwnBladeConfig(...))` of `rotor37_rom.studies.own_blade`, which
# prints each step as it goes and returns the summary.

# +
from __future__ import annotations

import sys
from typing import Sequence

from rotor37_rom.cli import ArgumentParser, run_main
from rotor37_rom.geometry.mesh_import import MESH_SUFFIXES, UNITS
from rotor37_rom.studies.own_blade import OwnBladeConfig, run_own_blade
# -


def build_parser() -> ArgumentParser:
    p = ArgumentParser(description="Your own blade mesh through the pipeline: modes, reduced model, sprag-slip "
                                   "onset, a contact run")
    p.add_argument("--mesh", default=None, help=f"mesh file ({', '.join(MESH_SUFFIXES)}); default: an example deck")
    p.add_argument("--clamp", default="CLAMP", help="name of the clamp group (node set, element set, physical group)")
    p.add_argument("--tip", default="TIP", help="name of the tip group")
    p.add_argument("--units", default="mm", help=f"units of the file: {', '.join(UNITS)}")
    p.add_argument("--contact", type=int, default=8, help="contact nodes along the tip camber line")
    p.add_argument("--modes", type=int, default=6)
    p.add_argument("--r-c", type=int, default=15, help="fixed-interface modes of the reduced model")
    p.add_argument("--speed", type=float, default=1400.0, help="rotation speed of the contact run (rad/s)")
    p.add_argument("--revolutions", type=float, default=2.0)
    p.add_argument("--mu", type=float, default=0.0, help="friction coefficient")
    p.add_argument("--direction", default="x", choices=["x", "radial", "cone"],
                   help="contact normal: x (the blade frame's e_x, the paper's), radial, cone (default x)")
    p.add_argument("--rotation-sense", type=int, default=-1, choices=[-1, 1],
                   help="the rotor turns about +z towards -theta (-1, rotor 37's) or +theta (+1); a sense that turns "
                        "the blade with its trailing edge ahead (a mirrored blade) is refused (default -1)")
    p.add_argument("--material", type=float, nargs=3, metavar=("E", "NU", "RHO"),
                   help="the blade's material in SI (Pa, -, kg/m^3); default: the deck's own (*MATERIAL), else the "
                        "paper's maraging steel (180e9 0.3 8000); printed either way")
    p.add_argument("--mass-check", choices=["on", "off"], default="on",
                   help="refuse a blade outside 1 g - 100 kg, naming the units it is likely in (off: the mass is "
                        "right)")
    p.add_argument("--out", default="results/own_blade")
    return p


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    options = vars(args) | {"mass_check": args.mass_check == "on",
                            "material": None if args.material is None else tuple(args.material)}
    config = OwnBladeConfig(**options)
    run_own_blade(config)
    return 0


if __name__ == "__main__":
    sys.exit(run_main(main))
