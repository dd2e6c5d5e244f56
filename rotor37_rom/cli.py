"""What every demo's command line shares: one kind of error and the blade-table option.

A demo's ``main(argv)`` parses its options into a frozen configuration whose checks raise ValueError naming the
option and its allowed range ("--modes must be in [1, 50], got 0"); the library raises ValueError for inputs it
refuses. ``run_main`` turns either into one line on stderr and exit status 2, and ``ArgumentParser`` does the same for
what argparse itself refuses (an option that is not a number), so a user never sees a traceback for a bad input.

Pure Python (the table check reads a text file with NumPy): no dolfinx, so a demo can refuse a bad input before any
meshing.
"""
from __future__ import annotations

import argparse
import contextlib
import os
import re
import sys
from pathlib import Path
from typing import Callable, Sequence

from rotor37_rom.checks import DryRun, dry_run
from rotor37_rom.geometry.tables import default_data_dir, read_blade_table
from rotor37_rom.interruption import Interrupted, stop_cleanly

__all__ = ["ArgumentParser", "run_main", "resolve_table", "TABLE_HELP"]

TABLE_HELP = "NASA Table IV file (the blade's CAD), 'auto' (../shared/data/rotor37 when present) or 'none'"


def _rank() -> int:
    """This process's MPI rank from the launcher's environment (0 when not under mpirun), without importing MPI."""
    for name in ("OMPI_COMM_WORLD_RANK", "PMI_RANK"):
        if os.environ.get(name, "").isdigit():
            return int(os.environ[name])
    return 0


def _one_line(message: str) -> str:
    return " ".join(str(message).split())


class ArgumentParser(argparse.ArgumentParser):
    """argparse with its errors on one line ("error: argument --speed: invalid float value: 'x'"), exit status 2, and
    the dry run's ``--check`` (handled by ``run_main``) listed in its help."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        # "-inf", "-nan" and "-1e300" are values (of a number option), not options: their checks then name the option
        self._negative_number_matcher = re.compile(r"^-(\d+\.?\d*|\.\d+|inf|infinity|nan)([eE][-+]?\d+)?$", re.I)
        self.add_argument("--check", action="store_true", default=argparse.SUPPRESS,
                          help="check the options, files and folders, then stop before any work (exit status 0)")

    def error(self, message: str):
        if _rank() == 0:
            sys.stderr.write(f"error: {_one_line(message)} (see --help)\n")
        sys.exit(2)


def run_main(main: Callable[[Sequence[str] | None], int], argv: Sequence[str] | None = None) -> int:
    """Call ``main(argv)``; a ValueError (a bad option or an input the library refuses) is one line on stderr
    ("error: <message>", printed by rank 0 only under mpirun) and exit status 2. With ``--check`` among the options
    the run is a dry run (``checks.dry_run``): its options, files and folders are checked, it stops before any work
    (meshing, computing, writing) and says so, exit status 0. SIGTERM or SIGINT stop it cleanly
    (``interruption.stop_cleanly``: the running loop's checkpoint written), with one line on how to resume and exit
    status 128 + the signal's number."""
    argv = list(sys.argv[1:] if argv is None else argv)
    check = "--check" in argv and "--help" not in argv and "-h" not in argv
    if check:
        argv = [a for a in argv if a != "--check"]
    try:
        with dry_run() if check else contextlib.nullcontext(), stop_cleanly():
            return main(argv)
    except Interrupted as exc:
        if _rank() == 0:
            print(f"stopped by {exc.name}: " + ("the checkpoints are written; " if exc.saved else "")
                  + "run the same command again to resume" + ("" if exc.saved else " from the last checkpoint"),
                  file=sys.stderr)
        return 128 + exc.number
    except DryRun:
        if _rank() == 0:
            print("checked: the options, files and folders are valid; nothing was run (--check)")
        return 0
    except ValueError as exc:
        if _rank() == 0:
            print(f"error: {_one_line(exc)}", file=sys.stderr)
        return 2


def resolve_table(value: str | Path | None, option: str = "--table") -> Path | None:
    """The blade table of a ``--table`` option: 'auto' (the shared NASA Table IV if present, else None), 'none' or
    None (the built-in parametric blade), or a file, read here so that a file that is not a NASA Table IV is refused
    (ValueError naming ``option``) before any meshing."""
    if value is None or str(value) == "none":
        return None
    if str(value) == "auto":
        data = default_data_dir()
        return None if data is None else data / "rotor37geometry.dat"
    try:
        read_blade_table(value)
    except ValueError as exc:
        raise ValueError(f"{option}: {exc}") from None
    return Path(value)
