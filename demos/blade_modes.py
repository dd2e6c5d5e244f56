# # Clamped NASA rotor 37 blade: mesh, first modes, comparison with the paper (§2.2.1)
#
# The blade is meshed with gmsh (the built-in parametric blade, and the exact loft of NASA Table IV when
# `../shared/data/rotor37` is present or `--table` names the file), its first clamped modes are computed with SLEPc,
# 1B/1T/2B are identified from the motion of the tip's leading and trailing edges, and the frequencies are compared
# with Delhez et al. (2023): 5272 / 15760 / 19071 rad/s. XDMF files and pyvista pictures of the mode shapes go to
# `results/blade_modes/`.
#
#     python demos/blade_modes.py --preset coarse        # about a minute
#     mpirun -n 2 python demos/blade_modes.py             # the eigen-solves on two ranks (no pictures)
#
# The study is one library function, `run_blade_modes(BladeModesConfig(...))` of `rotor37_rom.studies.blade_modes`,
# which returns a `BladeModesResult`; this script only turns its options into that configuration and prints the table.
# A bad option is one line on stderr, exit status 2.

# +
from __future__ import annotations

import logging
import sys
from pathlib import Path
from typing import Sequence

import numpy as np

from rotor37_rom.cli import TABLE_HELP, ArgumentParser, run_main
from rotor37_rom.geometry.blade import MESH_PRESETS
from rotor37_rom.model.modes import PAPER_CLAMPED_OMEGA
from rotor37_rom.studies.blade_modes import BladeModesConfig, BladeModesResult, run_blade_modes
# -


# ## What to compute
#
# A frozen configuration (`BladeModesConfig`), checked when it is made: a bad value is a ValueError naming the option
# and its range, and a `--table` that is not a NASA Table IV is refused there, before any meshing.
#
# ## One blade: mesh, modes, labels, mass and tip clearance
#
# The labels come from the tip: bending moves the leading and trailing edges together, torsion in opposite senses
# (`rotor37_rom.model.modes.classify_blade_modes`).
#
# ## The study
#
# Every blade in turn; under `mpirun` the meshes are distributed and rank 0 writes the summaries.


# ## Command line

# +
def print_report(result: BladeModesResult, out: Path) -> None:
    """The frequencies of each blade next to the paper's."""
    for r in result.blades:
        print(f"\n{r.name} blade: {r.dofs} DOF, mass {r.mass * 1e3:.2f} g, mesh+assembly+modes {r.wall:.1f} s")
        if r.clearance is not None:
            print(f"tip clearance to the Table V casing, LE..TE: {np.array2string(r.clearance * 1e3, precision=3)} mm")
        print(f"{'mode':>4} {'label':>5} {'omega (rad/s)':>14} {'paper':>8} {'error':>7}")
        for k, (lab, w) in enumerate(zip(r.labels, r.omega)):
            ref = PAPER_CLAMPED_OMEGA.get(lab)
            err = f"{100 * (w - ref) / ref:+6.2f}%" if ref else ""
            print(f"{k + 1:>4} {lab:>5} {w:>14.1f} {ref or '':>8} {err:>7}")
    print(f"\nXDMF and PNG files in {out}/")


def build_parser() -> ArgumentParser:
    parser = ArgumentParser(description="clamped modes of the rotor 37 blade against the paper")
    parser.add_argument("--preset", default="coarse", help=f"mesh preset: {', '.join(MESH_PRESETS)} (default coarse)")
    parser.add_argument("--modes", type=int, default=6, help="number of clamped modes (1..50, default 6)")
    parser.add_argument("--table", default="auto", help=TABLE_HELP + " (default auto)")
    parser.add_argument("--out", type=Path, default=Path("results/blade_modes"), help="output folder")
    parser.add_argument("--no-pictures", action="store_true", help="skip the pyvista PNGs")
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Parse the options, run the study, print the table; raises ValueError for a bad input."""
    args = build_parser().parse_args(argv)
    config = BladeModesConfig(preset=args.preset, n_modes=args.modes, table=args.table, out=args.out,
                              pictures=not args.no_pictures)
    # the FFCx JIT (through setuptools' distutils log) resets the root logger to INFO while compiling: filter at
    # the handler so compiler chatter stays out of the output
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s", force=True)
    logging.getLogger().handlers[0].setLevel(logging.WARNING)
    result = run_blade_modes(config)
    from mpi4py import MPI

    if MPI.COMM_WORLD.rank == 0:
        print_report(result, config.out)
    return 0


if __name__ == "__main__":
    sys.exit(run_main(main))
# -
