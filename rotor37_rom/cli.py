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
import signal
import sys
import threading
from pathlib import Path
from typing import Callable, Sequence

from rotor37_rom.checks import DryRun, dry_run
from rotor37_rom.geometry.tables import default_data_dir, read_blade_table
from rotor37_rom.interruption import SIGNALS, Interrupted, stop_cleanly

__all__ = ["ArgumentParser", "run_main", "resolve_table", "TABLE_HELP", "PATH_OPTIONS"]

TABLE_HELP = "NASA Table IV file (the blade's CAD), 'auto' (../shared/data/rotor37 when present) or 'none'"

#: options that name a file or a folder whatever their type: an empty value is refused (Path('') is the current
#: folder: ``--out ''`` would write there)
PATH_OPTIONS = ("out", "cache", "model", "mesh", "table")


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

    def _get_value(self, action, arg_string):
        """An option's value converted by its type; an empty path (a value of an option of ``PATH_OPTIONS`` or of
        type Path that is empty or blank) is refused naming the option, before ``Path('')`` makes it the current
        folder."""
        path_like = action.dest in PATH_OPTIONS or (isinstance(action.type, type) and issubclass(action.type, Path))
        if path_like and action.option_strings and isinstance(arg_string, str) and not arg_string.strip():
            raise argparse.ArgumentError(action, f"must be a path, got {arg_string!r} (empty; '.' is the current "
                                                 f"folder)")
        return super()._get_value(action, arg_string)


def run_main(main: Callable[[Sequence[str] | None], int], argv: Sequence[str] | None = None) -> int:
    """Call ``main(argv)``; a ValueError (a bad option or an input the library refuses) is one line on stderr
    ("error: <message>", printed by rank 0 only under mpirun) and exit status 2. With ``--check`` among the options
    the run is a dry run (``checks.dry_run``): its options, files and folders are checked, it stops before any work
    (meshing, computing, writing) and says so, exit status 0. SIGTERM or SIGINT stop it cleanly
    (``interruption.stop_cleanly``: the running loop's checkpoint written), with one line on how to resume and exit
    status 128 + the signal's number, also where a library caught the stop and raised another error instead."""
    argv = list(sys.argv[1:] if argv is None else argv)
    check = "--check" in argv and "--help" not in argv and "-h" not in argv
    if check:
        argv = [a for a in argv if a != "--check"]
    noted: list[int] = []
    try:
        with dry_run() if check else contextlib.nullcontext(), stop_cleanly(), _noting_signals(noted):
            return main(argv)
    except Interrupted as exc:
        return _stopped(exc.name, exc.number, exc.saved)
    except DryRun:
        if _rank() == 0:
            print("checked: the options, files and folders are valid; nothing was run (--check)")
        return 0
    except Exception as exc:
        if noted:             # the stop, caught on its way by a library's broad except and turned into another error
            return _stopped(signal.Signals(noted[0]).name, noted[0], False)
        if not isinstance(exc, ValueError):
            raise
        if _rank() == 0:
            print(f"error: {_one_line(exc)}", file=sys.stderr)
        return 2


def _stopped(name: str, number: int, saved: bool) -> int:
    """The one line of a run stopped by a signal (rank 0), and its exit status, 128 + the signal's number."""
    if _rank() == 0:
        print(f"stopped by {name}: " + ("the checkpoints are written; " if saved else "")
              + "run the same command again to resume" + ("" if saved else " from the last checkpoint"),
              file=sys.stderr)
    return 128 + number


@contextlib.contextmanager
def _noting_signals(noted: list):
    """Within ``stop_cleanly``: each SIGTERM or SIGINT appended to ``noted`` before its handler runs, so that a stop
    a library's ``except Exception`` turned into another error (gmsh's failures, ``fem.sector.build_on_rank0``) is
    still said as the stop it is. The handlers before are restored after."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    before = {s: signal.getsignal(s) for s in SIGNALS}

    def note(signum, frame):
        noted.append(signum)
        handler = before[signum]
        if callable(handler):
            handler(signum, frame)

    for s in SIGNALS:
        signal.signal(s, note)
    try:
        yield
    finally:
        for s, h in before.items():
            signal.signal(s, h)


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
