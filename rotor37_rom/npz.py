"""Array files that are complete or absent: the one way the project writes its caches, checkpoints and records
(``save_npz``: written under a hidden temporary name, then renamed, so a reader never opens half a file, ranks
writing the same file side by side do not clash, and a writer killed half-way leaves nothing a glob of the real
names picks up; ``save_json`` does the same for the JSON stores and summaries that later calls read back), and
reads a cache that may be damaged (``load_npz``: a damaged or
mismatched file is reported and treated as absent, so the caller computes it again). A damaged file a run would read
back (a summary, a sweep's spec, a result) is moved aside before the run works (``set_aside``, ``load_json``), with a
warning naming it, where it went and what the run does instead: it is never left to fail the run at its end."""
from __future__ import annotations

import glob
import json
import logging
import os
import zipfile
from pathlib import Path
from typing import Callable, Iterable

import numpy as np

__all__ = ["save_npz", "save_json", "load_npz", "load_json", "set_aside", "DAMAGED"]

LOG = logging.getLogger(__name__)

DAMAGED = (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile)     # what reading a damaged .npz raises


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:                        # another user's process
        return True
    return True


def _write_whole(path: Path, suffix: str, write: Callable[[Path], None]) -> Path:
    """``write(tmp)`` to ``.<name>.tmp<pid><suffix>`` beside ``path``, then rename it to ``path`` (its folder
    created). Temporary files a killed writer left (its pid no longer running; a checkpoint's can be GBs) are removed
    first."""
    path.parent.mkdir(parents=True, exist_ok=True)
    for stale in path.parent.glob(f".{glob.escape(path.name)}.tmp*{suffix}"):
        pid = stale.name[len(path.name) + 5:len(stale.name) - len(suffix)]
        if pid.isdigit() and int(pid) != os.getpid() and not _alive(int(pid)):
            LOG.info("removing %s (its writer, pid %s, was stopped)", stale, pid)
            stale.unlink(missing_ok=True)
    tmp = path.with_name(f".{path.name}.tmp{os.getpid()}{suffix}")
    try:
        write(tmp)
        tmp.replace(path)
    finally:
        tmp.unlink(missing_ok=True)
    return path


def save_npz(path: str | Path, **arrays) -> Path:
    """Write ``arrays`` to ``path`` (.npz, its folder created) complete or not at all; returns the path.

    The temporary file is ``.<name>.tmp<pid>.npz`` beside it (hidden: ``omega_*.npz`` does not match it)."""
    return _write_whole(Path(path), ".npz", lambda tmp: np.savez(tmp, **arrays))


def save_json(path: str | Path, obj, **dumps) -> Path:
    """Write ``json.dumps(obj, **dumps)`` to ``path`` complete or not at all (as ``save_npz``): a study's store or a
    run's summary read back by the next call is never half a file. Returns the path."""
    text = json.dumps(obj, **dumps)              # before any file is touched: an object JSON cannot hold raises here
    return _write_whole(Path(path), ".json", lambda tmp: tmp.write_text(text))


def load_npz(path: str | Path | None, names: Iterable[str] | None = None,
             check: Callable[[dict], None] | None = None, what: str = "cache") -> dict | None:
    """The arrays ``names`` (default all) of the .npz file ``path``, or None when there is no file or it is damaged
    (unreadable, a name missing, or ``check`` raising ValueError on the arrays read: a wrong shape, another key).
    A damaged file is logged as ignored (``what`` names it) and left for the caller to write again."""
    if path is None or not Path(path).is_file():
        return None
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {name: data[name] for name in (data.files if names is None else names)}
        if check is not None:
            check(arrays)
    except DAMAGED as exc:
        LOG.warning("ignoring %s %s (%s: %s): computed again", what, path, exc.__class__.__name__, exc)
        return None
    return arrays


def set_aside(path: str | Path, why: str, then: str) -> Path:
    """Move the damaged file ``path`` to ``<name>.damaged-<n>`` beside it (n: the first number free, so an earlier
    one is kept) and log a warning naming both paths, ``why`` (what is wrong with it) and ``then`` (what the run does
    instead); returns the new path. ValueError in one line where it cannot be moved (the user's to do)."""
    path = Path(path)
    n = 1
    while path.with_name(f"{path.name}.damaged-{n}").exists():
        n += 1
    aside = path.with_name(f"{path.name}.damaged-{n}")
    try:
        os.rename(path, aside)
    except OSError as exc:
        raise ValueError(f"{path} is damaged ({why}) and cannot be moved aside ({exc.strerror or exc}): move or "
                         f"remove it, then run again") from None
    LOG.warning("%s is damaged (%s): moved aside to %s; %s", path, why, aside, then)
    return aside


def _why(exc: BaseException) -> str:
    return " ".join(f"{exc.__class__.__name__}: {exc}".split())


def load_json(path: str | Path, check: Callable[[object], None] | None = None, then: str = "it is written again"
              ) -> object | None:
    """The content of the JSON file ``path``; None where there is none. A damaged file (it cannot be read, is not
    JSON, or ``check(content)`` raises ValueError, KeyError or TypeError: not what the caller wrote) is moved aside
    (``set_aside``: the warning names it, where it went and ``then``, what the caller does instead) and None
    returned, so that the caller's run does not end on it."""
    path = Path(path)
    if not path.is_file():
        return None
    try:
        content = json.loads(path.read_text())
        if check is not None:
            check(content)
    except (OSError, ValueError, KeyError, TypeError, AttributeError) as exc:
        set_aside(path, _why(exc), then)
        return None
    return content
