# # The blade turning and at rest: the interaction map side by side, and its resonances on the Campbell diagram (#73)
#
# The paper's maps (§2.3.1) hold the blade at rest. Here the same reduced model runs each map twice: turning at each
# speed (centrifugal prestress and spin softening, every run from its centrifugal state; without GNL the blade
# linearised about that state) and at rest. The model's basis holds the blade's full-order centrifugal states at
# STOP/2 and STOP and its first 4 modes turning at STOP, so both maps are the same model's. The casing's clearance is
# measured from the running blade (`--rotation running`, the default: the casing sits c0 beyond the turning tip) or
# from the blade at rest (`--rotation rest`: the tip's centrifugal growth eats it).
#
#     python demos/turning_map.py --speeds 1400 1900 11 --revolutions 20 --frequency-cap 60      # ~10 min
#     python demos/turning_map.py --rotation rest --c0 5e-4 --gnl off --speeds 1400 1900 11
#     mpirun -n 2 python demos/turning_map.py --model results/turning_map/rom.npz --speeds 1400 1900 21
#     python demos/turning_map.py --disk --gnl on --direction cone --frequency-cap 60 --speeds 1750 1850 3 \
#         --revolutions 2 --out results/turning_map_disk       # the bladed disk (its prestress from its GNL forces)
#
# The options are the contact map's (`python demos/contact_map.py --help`); the study is one library function,
# `run_turning_comparison(ContactMapConfig)` of `rotor37_rom.studies.turning_map`. Outputs in `--out` (default
# results/turning_map): both maps' charts, nfrc.png with every run, campbell_maps.png (the reduced model's Campbell
# diagram, the 1B/EO4 crossing and each map's largest response as its EO4 point) and turning_comparison.json (the
# crossing, the peaks, the cost per speed turning against at rest). A bad option is one line and exit status 2.

# +
from __future__ import annotations

import logging
import sys
from pathlib import Path
from typing import Sequence

from rotor37_rom.cli import run_main
from rotor37_rom.studies.contact_map import ContactMapConfig, parse_options, world_comm
from rotor37_rom.studies.turning_map import TurningComparison, engine_order_crossing, run_turning_comparison
# -


def print_report(result: TurningComparison) -> None:
    """The crossing, each map's peak and the cost ratio."""
    crossing = engine_order_crossing(result.campbell)
    print("1B meets EO4 at " + (f"{crossing:.0f} rad/s turning" if crossing else "no speed of the model's range"))
    for label, (speed, _) in result.peaks.items():
        print(f"  largest response {speed:.0f} rad/s: {label}")
    for setting, cost in result.cost.items():
        if cost["ratio"] is not None:
            print(f"  {setting}: {cost['turning_s']:.2f} s a speed turning, {cost['rest_s']:.2f} s at rest "
                  f"(x {cost['ratio']:.2f}; steps {cost['turning_h']:.3g} / {cost['rest_h']:.3g} s)")
    print(f"charts, summary.json and turning_comparison.json in {result.turning.out}/")


def main(argv: Sequence[str] | None = None) -> int:
    """Parse the options (--rotation running and --out results/turning_map unless given), run the comparison."""
    options = {"rotation": "running", "out": Path("results/turning_map")} | parse_options(argv)
    config = ContactMapConfig.from_options(**options)
    logging.basicConfig(level=logging.WARNING, force=True)
    comm = world_comm()
    result = run_turning_comparison(config, comm)
    if comm is None or comm.rank == 0:
        print_report(result)
    return 0


if __name__ == "__main__":
    sys.exit(run_main(main))
