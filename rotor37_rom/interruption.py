"""Stopping a long run cleanly on SIGTERM or SIGINT (#70).

A command runs inside ``stop_cleanly`` (``cli.run_main`` does it). A loop that checkpoints declares itself with
``checkpointing``; a signal then only asks it to stop: at its next step boundary it writes its checkpoint and raises
``Interrupted(saved=True)``, and the command says in one line how to resume. Outside such a loop (meshing, a build)
the signal raises ``Interrupted(saved=False)`` at once, and a second signal always does: the run then resumes from
the last checkpoint its loops wrote. Pure Python.
"""
from __future__ import annotations

import contextlib
import signal
import threading

__all__ = ["Interrupted", "stop_cleanly", "checkpointing", "requested", "stop_if_requested", "SIGNALS"]

SIGNALS = (signal.SIGTERM, signal.SIGINT)
_state = {"requested": None, "aware": 0}


class Interrupted(Exception):
    """A run stopped by a signal: ``name`` (SIGTERM, SIGINT), ``number``, and whether the loop it stopped wrote its
    checkpoint at the stop (``saved``)."""

    def __init__(self, name: str, number: int, saved: bool):
        super().__init__(f"stopped by {name}")
        self.name, self.number, self.saved = name, number, saved


def _handler(signum, frame):
    name = signal.Signals(signum).name
    if _state["requested"] is not None or not _state["aware"]:
        raise Interrupted(name, signum, saved=False)
    _state["requested"] = (name, signum)


@contextlib.contextmanager
def stop_cleanly():
    """SIGTERM and SIGINT stop the run within as described above (the main thread only; elsewhere nothing
    changes). The handlers before are restored after."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    before = {s: signal.signal(s, _handler) for s in SIGNALS}
    try:
        yield
    finally:
        for s, h in before.items():
            signal.signal(s, h)
        _state["requested"] = None


@contextlib.contextmanager
def checkpointing():
    """Within it, a signal asks the loop to stop at its next step boundary (``requested``) instead of stopping it."""
    _state["aware"] += 1
    try:
        yield
    finally:
        _state["aware"] -= 1


def requested() -> tuple[str, int] | None:
    """(name, number) of the signal that asked the run to stop, or None."""
    return _state["requested"]


def stop_if_requested(save) -> None:
    """Where a stop was asked: ``save()`` (the loop's checkpoint), then Interrupted(saved=True)."""
    asked = _state["requested"]
    if asked is not None:
        save()
        raise Interrupted(*asked, saved=True)
