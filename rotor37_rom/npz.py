"""Array files that are complete or absent: the one way the project writes its caches, checkpoints and records
(``save_npz``: written under a hidden temporary name, then renamed, so a reader never opens half a file, ranks
writing the same file side by side do not clash, and a writer killed half-way leaves nothing a glob of the real
names picks up; ``save_json`` does the same for the JSON stores and summaries that later calls read back), and
reads a cache that may be damaged (``load_npz``: a damaged or
mismatched file is reported and treated as absent, so the caller computes it again)."""
from __future__ import annotations

import glob
import json
import logging
import os
import zipfile
from pathlib import Path
from typing import Callable, Iterable

import numpy as np

__all__ = ["save_npz", "save_json", "load_npz", "DAMAGED"]

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
