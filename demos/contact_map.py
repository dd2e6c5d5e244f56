# # Blade-tip/casing contact: interaction maps, NFRC and continuation (paper §2.3.1, §2.3.3, §3.4; Figs. 6, 7, 11, 12,
# 23, 24)
#
# Builds (or loads) a reduced model of the clamped blade, or with `--disk` of the whole 36-sector bladed disk (every
# blade's 8 tip nodes in contact, each blade at its own angle), then sweeps the angular speed with the casing ovalized
# into two lobes (eqs. 37-38; c0 = 0.5 mm, h_b = 0.625 mm, mu = 0.15), GNL off and on. Every speed's result is written
# as
# it finishes; a killed run started again resumes. The same command under `mpirun -n N` splits the speeds over the
# ranks (rank 0 builds the model, or give --model; with --cubature rank 0 trains; the others wait).
#
#     python demos/contact_map.py --preset ci --speeds 1200 1600 21 --revolutions 20          # minutes
#     python demos/contact_map.py --preset coarse --speeds 1200 1600 201 --revolutions 200      # paper scale (hours)
#     python demos/contact_map.py --disk --gnl off --direction cone --frequency-cap 60 --speeds 1200 1650 10 \
#         --out results/disk_map                                   # the bladed disk (minutes per speed batch)
#     mpirun -n 2 python demos/contact_map.py --model results/contact_map/rom.npz --speeds 1200 1600 21
#     OPENBLAS_NUM_THREADS=1 mpirun -n 2 python demos/contact_map.py --model results/contact_map/rom.npz --gnl on \
#         --cubature 1e-4 --precision single --frequency-cap 120 --mu 0 --speeds 1200 1600 100 --revolutions 200 \
#         --batch 50 --out results/headline     # the GNL headline map on 2 cores (docs/performance.md)
#
# The whole study is one library function, `run_contact_map(ContactMapConfig.from_options(...))` of
# `rotor37_rom.studies.contact_map`, which returns a `ContactMapResult`; this script only turns its options into that
# configuration and prints the comparison with the paper. A bad option is one line on stderr and exit status 2.

# +
from __future__ import annotations

import logging
import sys
from typing import Sequence

from rotor37_rom.cli import run_main
from rotor37_rom.studies.contact_map import (PAPER, ContactMapConfig, ContactMapResult, parse_options,
    run_contact_map, world_comm)
# -


# ## Configuration
#
# `ContactMapConfig` (`rotor37_rom.studies.contact_config`) composes the library's objects: the model to build or load
# (`rom`), the time scheme (`scheme`), a `SweepSpec` with its `Casing` (`sweep`) and the continuation. Each command-
# line option is one of its flat options (`--frequency-cap` is `frequency_cap`, held at `config.scheme.frequency_cap`;
# `ContactMapConfig.OPTIONS` lists where each lives), with the same defaults. Every check names the option it
# concerns, so that the command line can report it as is. Numbers are stored as floats, as the command line gives
# them: the cache keys of sweeps and cubatures hash them, and a run from Python then reuses the files of the same run
# from the shell.
#
# ## Results
#
# One `MapResult` per GNL setting ('no GNL', 'GNL', with the cubature and the cap in the label when used): its
# interaction map, the speeds run again with a smaller step and the continuation branches. `ContactMapResult` holds
# them with what the run wrote. Under MPI rank 0 gets them all; the other ranks get no maps and write nothing.
#
# ## The reduced model
#
# Loaded from `--model`, or built serially from the blade mesh (Craig-Bampton with r_c fixed-interface modes and
# modal derivatives, exact cubic tensors) and saved as `<out>/rom.npz` for later runs and MPI runs. `--mesh` builds
# it on your own blade, or with `--left`, `--right` and `--n-sectors` on your own bladed-disk sector (its tip nodes
# in contact, every sector's), through the same builders.
#
# ## Time step and GNL forces
#
# Without GNL the step is `safety` x 2 / omega_max (or `--h`). With GNL and `--cubature`, the exact cubic forces are
# replaced by point cubature trained on exact GNL runs at 6 of the speeds; with a frequency cap the GNL step comes
# from the tangent frequencies of the states a GNL run reaches (the cubature's training runs, or a short probe):
# `time_scheme` of `rotor37_rom.studies.contact_scheme`.
#
# ## One map: sweep, retries, continuation
#
# Every speed starts from rest (§2.3.1); speeds that blew up run again with the step halved (`--retry-diverged`).
# The continuation (§2.3.3) then runs up and down at the step all the map's speeds ran with.
#
# ## Charts, summary and report
#
# Each map gives an interaction map, the LE/TE time history of its largest bounded response and, with a continuation,
# the NFRC of both branches next to the zero-IC map. summary.json keeps the runs of an earlier call on the same
# model, speeds and revolutions, and nfrc.png draws them all.
#
# ## The study
#
# The model, its sprag-slip onsets (the friction coefficient from which sustained sliding grows), then one map per
# GNL setting. Under MPI every rank runs its share of the speeds and rank 0 writes the charts and the summary.


# ## Command line
#
# The options are the flat options of `ContactMapConfig` (their defaults too: an option not given is left to the
# configuration; `build_parser` lists them). `main` runs the study and prints the comparison with the paper; a
# ValueError (a bad option, a file that is not a reduced model, a step the library refuses) is one line on stderr and
# exit status 2.

# +
def print_report(result: ContactMapResult) -> None:
    """The paper's speeds to compare with, and where the outputs are."""
    print(f"paper: linear {PAPER['linear 1B/EO4']:.0f}, zero IC {PAPER['zero IC, no GNL']:.0f} / "
          f"{PAPER['zero IC, GNL']:.0f} (no GNL / GNL), continuation {PAPER['continuation, no GNL']:.0f} / "
          f"{PAPER['continuation, GNL']:.0f} rad/s")
    print(f"charts and summary.json in {result.out}/")


def main(argv: Sequence[str] | None = None) -> int:
    """Parse the options, run the study, print the report; raises ValueError for a bad input."""
    config = ContactMapConfig.from_options(**parse_options(argv))
    logging.basicConfig(level=logging.WARNING, force=True)
    logging.getLogger().handlers[0].setLevel(logging.WARNING)
    comm = world_comm()
    result = run_contact_map(config, comm)
    if comm is None or comm.rank == 0:
        print_report(result)
    return 0


if __name__ == "__main__":
    sys.exit(run_main(main))
# -
