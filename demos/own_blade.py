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
from rotor37_rom.studies.own_blade import OwnBladeConfig, run_own_blade
from rotor37_rom.studies.sector_file import SectorFile, add_sector_options
# -


def build_parser() -> ArgumentParser:
    p = ArgumentParser(description="Your own blade mesh through the pipeline: modes, reduced model, sprag-slip "
                                   "onset, a contact run")
    add_sector_options(p, cyclic=False)
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
    p.add_argument("--out", default="results/own_blade")
    p.add_argument("--show-groups", action="store_true",
                   help="draw the groups and the contact nodes on the mesh (OUT/groups.png), then stop")
    return p


def main(argv: Sequence[str] | None = None) -> int:
    p = build_parser()
    args = p.parse_args(argv)
    config = OwnBladeConfig(mesh=SectorFile.from_args(args, p), modes=args.modes, r_c=args.r_c, speed=args.speed,
                            revolutions=args.revolutions, mu=args.mu, direction=args.direction,
                            rotation_sense=args.rotation_sense, out=args.out, show_groups=args.show_groups)
    run_own_blade(config)
    return 0


if __name__ == "__main__":
    sys.exit(run_main(main))
