# # The paper's single-blade story in one report: modes, clearance consumption, maps, NFRC and stress (`make demo`)
#
# Delhez et al. (2023) §2 at a size that runs in about six minutes on two cores (the GNL map four of them),
# written to one `report.html` that opens with our numbers next to the paper's:
#
# 1. the clamped modes of the blade against the paper's 5272 / 15760 / 19071 rad/s (`demos/blade_modes.py`);
# 2. the reduced model the contact studies use (r = 55: 24 tip DOFs, 25 fixed-interface modes, the 6 modal
#    derivatives of 1B/1T/2B) and the clearance consumption of 1B and 1T, linear against geometrically nonlinear,
#    full order against the reduced model (`demos/reduced_blade.py`);
# 3. interaction maps and NFRC with the geometric nonlinearity (GNL) off and on at a few speeds and revolutions
#    (`demos/contact_map.py`);
# 4. the von Mises stress at t_max, where node LE reaches its largest radial displacement, at the resonance of each
#    map (Fig. 25 analogue), from bounded runs only.
#
# Settings: each map (GNL off, on) runs with the frequency cap, step and force evaluation that the speed-accuracy
# study measured as the cheapest within 5 % on this scene (`--tolerance`, docs/choosing-a-model.md), on the reduced
# model of r = 55 that the basis-size studies support for contact (docs/results.md). Friction
# is off (mu = 0): with the paper's mu = 0.15 this blade's responses grow without bound at many speeds (the LE half
# of the tip wedges into the casing: sprag-slip), which the report would flag run by run (`--mu 0.15` shows it).
#
#     python demos/report.py                                            # make demo: about 6 min on 2 cores
#     python demos/report.py --speeds 1200 1600 21 --revolutions 20     # a finer map (the GNL map is most of it)
#
# The study is one library function, `run_report(ReportConfig(...))` of `rotor37_rom.studies.blade_report`, returning
# a `ReportResult`; a bad option is one line on stderr and exit status 2, before any meshing.

# +
from __future__ import annotations

import logging
import sys
from pathlib import Path
from typing import Sequence

from rotor37_rom.cli import TABLE_HELP, ArgumentParser, run_main
from rotor37_rom.geometry.blade import MESH_PRESETS
from rotor37_rom.studies.blade_report import NORMALS, ReportConfig, flags, run_report, summary_table
# -


# ## What to compute
#
# The report's own options (`ReportConfig`); every check is the one of the study it configures, so a bad value is
# refused, naming the option, when the configuration is made.
#
# ## Results
#
# The resonance of a map is its 1B/EO4 resonance, as in the paper: the largest bounded response among the speeds
# whose response is dominated by the fourth engine order (`sweep.engine_order_resonance`); a short map's largest
# response can be a higher mode's crossing instead. The stress of one map is a `PeakStress`: at that resonance, the
# run is carried on for one revolution from its final state (casing fully ovalized, the rotor angle carried over, as
# a continuation does), recording every state; t_max is where node LE's radial displacement is largest in magnitude
# in that revolution (the NFRC's max |u_LE|: as in the paper's Fig. 25 the blade swings away from the casing there,
# free of contact forces). A run that grows past the limit there, or a map without a 1B/EO4 resonance, gives no
# stress: the report says so.
#
# ## Stress at t_max
#
# The map's scheme is rebuilt from its model, step and cap (the sweep folder it gives is checked to be the map's);
# the stress recovery evaluates the von Mises field at every quadrature point from q(t_max) without reassembly.
#
# ## The study
#
# The studies in turn: modes, the reduced model and its clearance consumption, the two maps on that model (saved
# once as `<out>/rom.npz`), then the stresses on the same mesh.
#
# ## The report
#
# It opens with the summary table and the list of runs that grew past the limit; every section below gives the
# numbers behind a row and the pictures.


# ## Command line

# +
def build_parser() -> ArgumentParser:
    parser = ArgumentParser(description="the paper's single-blade story in one report (make demo)")
    parser.add_argument("--preset", default="ci", help=f"mesh preset: {', '.join(MESH_PRESETS)} (default ci)")
    parser.add_argument("--table", default="auto", help=TABLE_HELP + " (modes only; default auto)")
    parser.add_argument("--r-c", type=int, default=25, help="fixed-interface modes of the reduced model (default 25)")
    parser.add_argument("--speeds", type=float, nargs=3, default=[1200.0, 1600.0, 11.0],
                        metavar=("START", "STOP", "N"), help="N speeds (rad/s) from START to STOP (default 1200 "
                                                              "1600 11)")
    parser.add_argument("--revolutions", type=float, default=8.0, help="revolutions per speed (default 8)")
    parser.add_argument("--mu", type=float, default=0.0, help="friction coefficient (default 0; the paper 0.15)")
    parser.add_argument("--direction", choices=list(NORMALS), default="x",
                        help="contact normal: x (the paper's e_x, default), radial, cone (the casing cone's normal)")
    parser.add_argument("--tolerance", type=float, default=0.05, metavar="TOL",
                        help="the maps' cap, step and forces: the cheapest within this relative error in the "
                             "speed-accuracy study (docs/choosing-a-model.md; default 0.05; 0: by hand)")
    parser.add_argument("--linear-cap", type=float, default=None, metavar="KHZ",
                        help="with --tolerance 0: frequency cap of the linear map (kHz; default none)")
    parser.add_argument("--levels", type=int, default=10, help="clearance study: load levels per side (1..50)")
    parser.add_argument("--no-pictures", action="store_true", help="skip the pyvista pictures")
    parser.add_argument("--quiet", action="store_true", help="no progress bars")
    parser.add_argument("--out", type=Path, default=Path("results/report"), help="output folder")
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Parse the options, run every study, write the report; raises ValueError for a bad input."""
    args = build_parser().parse_args(argv)
    config = ReportConfig(preset=args.preset, table=args.table, r_c=args.r_c, speeds=tuple(args.speeds),
                          revolutions=args.revolutions, mu=args.mu, direction=args.direction,
                          tolerance=args.tolerance or None,
                          linear_cap=args.linear_cap or None,
                          levels=args.levels, pictures=not args.no_pictures, quiet=args.quiet, out=args.out)
    logging.basicConfig(level=logging.WARNING, force=True)
    logging.getLogger().handlers[0].setLevel(logging.WARNING)
    result = run_report(config)
    for row in summary_table(result).rows:
        print(f"{row[0]}: {row[1]} (paper: {row[2]})")
    for line in flags(result):
        print(f"flagged: {line}")
    print(f"report: {result.html}")
    return 0


if __name__ == "__main__":
    sys.exit(run_main(main))
# -
