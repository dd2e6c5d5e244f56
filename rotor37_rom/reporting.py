"""The library's voice (#87): what a study tells as it goes (a model built, a map's largest response, a step
chosen) goes through ``say``, never ``print``; the reporter in force decides where it goes: standard output by
default, as the command line wants, or any callable given to ``reporting`` (a list's append to keep the messages, a
GUI's log, ``lambda message: None`` for silence).

    with reporting(notes.append):
        run_contact_map(config)
"""
from __future__ import annotations

import contextlib
import sys
from typing import Callable, Iterator

__all__ = ["say", "reporting"]

_reporter: Callable[[str], None] | None = None


def _to_stdout(message: str) -> None:
    sys.stdout.write(message + "\n")                  # the stream in force now (a test's or a driver's capture too)
    sys.stdout.flush()


def say(*values, sep: str = " ", flush: bool = True) -> None:
    """Tell ``values`` (joined by ``sep``, as print joins them) to the reporter in force (``flush`` is print's
    and always so)."""
    (_reporter or _to_stdout)(sep.join(str(v) for v in values))


@contextlib.contextmanager
def reporting(reporter: Callable[[str], None]) -> Iterator[None]:
    """Send what the library says to ``reporter`` (a callable taking one string) within the block."""
    global _reporter
    if not callable(reporter):
        raise ValueError(f"reporter must be a callable taking one message, got {reporter!r}")
    previous, _reporter = _reporter, reporter
    try:
        yield
    finally:
        _reporter = previous
