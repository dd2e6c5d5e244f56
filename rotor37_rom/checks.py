"""The checks every configuration makes of its numbers when it is made, before any work: one ValueError naming the
field and the range allowed. A command line prefixes the option's name (``flagged``); a run takes its output
folder's lock before it works (``output_lock``: a second run on the same folder is refused at once). Pure Python."""
from __future__ import annotations

import contextlib
import contextvars
import errno
import fcntl
import logging
import math
import numbers
import os
import socket
import tempfile
import time
from pathlib import Path
from typing import Callable, TypeVar

__all__ = ["whole_number", "real_number", "flagged", "writable_folder", "fits_in_memory", "physical_memory",
           "readable_file", "before_work", "dry_run", "DryRun", "output_lock", "LOCK_FILE"]

T = TypeVar("T")
LOG = logging.getLogger(__name__)


def whole_number(name: str, value, low: int, high: int | None = None) -> None:
    """ValueError naming ``name`` unless ``value`` is an integer (Python's or NumPy's; not a bool) in low..high."""
    ok = isinstance(value, numbers.Integral) and not isinstance(value, bool) and value >= low \
        and (high is None or value <= high)
    if not ok:
        span = f"in {low}..{high}" if high is not None else f">= {low}"
        raise ValueError(f"{name} must be an integer {span}, got {value!r}")


def real_number(name: str, value, low: float | None = None, high: float | None = None, open_low: bool = False,
                open_high: bool = False, unit: str = "") -> None:
    """ValueError naming ``name`` unless ``value`` is a finite real number (not a bool) within the bounds given
    (closed unless ``open_low``/``open_high``); ``unit`` follows the range in the message."""
    ok = isinstance(value, numbers.Real) and not isinstance(value, bool) and math.isfinite(value)
    if ok and low is not None:
        ok = value > low if open_low else value >= low
    if ok and high is not None:
        ok = value < high if open_high else value <= high
    if not ok:
        if low is not None and high is not None:
            span = f"in {'(' if open_low else '['}{low:g}, {high:g}{')' if open_high else ']'}{unit}"
        elif low is not None:
            span = f"{'>' if open_low else '>='} {low:g}{unit}"
        elif high is not None:
            span = f"{'<' if open_high else '<='} {high:g}{unit}"
        else:
            span = "a finite number"
        infinite = isinstance(value, numbers.Real) and not math.isfinite(value) and span != "a finite number"
        raise ValueError(f"{name} must be {'finite and ' if infinite else ''}{span}, got {value!r}")


def flagged(flag: str, make: Callable[[], T]) -> T:
    """``make()``, its ValueError prefixed with ``flag`` (the command-line option it came from)."""
    try:
        return make()
    except ValueError as exc:
        raise ValueError(f"{flag}: {exc}") from None


#: file systems no run can write in (kernel interfaces)
PSEUDO_FILE_SYSTEMS = ("proc", "sysfs", "devpts", "cgroup", "cgroup2", "securityfs", "debugfs", "tracefs", "bpf",
                       "configfs", "pstore", "mqueue", "hugetlbfs", "fusectl")


def _mount_of(path: Path) -> tuple[str, set[str]]:
    """(file system type, mount options) of the mount that holds ``path`` (an existing path), from /proc/self/mounts;
    ('', set()) where that cannot be read."""
    try:
        mounts = [line.split() for line in Path("/proc/self/mounts").read_text().splitlines()]
    except OSError:
        return "", set()
    best, kind, options = "", "", set()
    for fields in mounts:
        if len(fields) >= 4:
            point = fields[1].replace("\\040", " ")
            inside = str(path) == point or str(path).startswith(point.rstrip("/") + "/")
            if inside and len(point) >= len(best):
                best, kind, options = point, fields[2], set(fields[3].split(","))
    return kind, options


def writable_folder(option: str, path, create: bool = True) -> Path:
    """``path`` as a folder a run can write in, created (with its parents) if need be, before any work: ValueError
    naming ``option`` where it is a file, lies under one, or cannot be written (a read-only or pseudo file system
    such as /proc, no permission). A file is written in it and removed to be sure. ``create=False`` (a dry run):
    nothing is created or written; the nearest existing folder above is checked instead."""
    if not isinstance(path, (str, os.PathLike)) or str(path).strip() == "":
        raise ValueError(f"{option} must be a folder's path, got {path!r}")
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise ValueError(f"{option}: {path} exists and is not a folder")
    above = next((p for p in [path, *path.absolute().parents] if p.exists()), None)
    if above is not None and not above.is_dir():
        raise ValueError(f"{option}: cannot write in {path} ({above} is not a folder)")
    kind, options = _mount_of(above.resolve()) if above is not None else ("", set())
    if kind in PSEUDO_FILE_SYSTEMS or "ro" in options:
        raise ValueError(f"{option}: cannot write in {path} ({above} is on a "
                         f"{'pseudo' if kind in PSEUDO_FILE_SYSTEMS else 'read-only'} file system, {kind})")
    if not create:
        if above is None or not os.access(above, os.W_OK | os.X_OK):
            raise ValueError(f"{option}: cannot write in {path} (permission denied)")
        return path
    try:
        path.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=path, prefix=".write_check_"):
            pass
    except OSError as exc:
        raise ValueError(f"{option}: cannot write in {path} ({(exc.strerror or type(exc).__name__).lower()})") \
            from None
    return path


class DryRun(Exception):
    """Raised by ``before_work`` in a dry run (``dry_run``): the inputs are valid and nothing was done."""


_DRY_RUN = contextvars.ContextVar("dry_run", default=False)


@contextlib.contextmanager
def dry_run():
    """Within it, a run stops at ``before_work`` with DryRun once its inputs are checked (``--check``)."""
    token = _DRY_RUN.set(True)
    try:
        yield
    finally:
        _DRY_RUN.reset(token)


def before_work(folders: dict, files: dict | None = None) -> None:
    """The point of a run after which it works (meshes, computes, writes): its input files checked ({option: path},
    None where not given; or {option: (path, check)}, check(path) raising ValueError for a file that is not what
    the option wants), its output folders ({option: path}) checked and created; in a dry run checked only, and
    DryRun raised."""
    dry = _DRY_RUN.get()
    for option, given in (files or {}).items():
        path, check = given if isinstance(given, tuple) else (given, None)
        if path is not None:
            readable_file(option, path)
            if check is not None:
                flagged(option, lambda: check(path))
    for option, path in folders.items():
        writable_folder(option, path, create=not dry)
    if dry:
        raise DryRun()


def physical_memory() -> int:
    """This machine's physical memory (bytes)."""
    return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")


def fits_in_memory(option: str, nbytes: float, what: str, share: float = 0.8, hint: str = "") -> None:
    """ValueError naming ``option`` where a run would hold ``nbytes`` (``what``: how that is counted) beyond
    ``share`` of this machine's physical memory: refused before any work, with the estimate (and ``hint``: what to
    change)."""
    limit = share * physical_memory()
    if not nbytes <= limit:                                     # nan and inf are refused too
        raise ValueError(f"{option}: the run would hold {nbytes / 2**30:.3g} GiB ({what}), more than "
                         f"{limit / 2**30:.3g} GiB ({100 * share:.0f} % of this machine's memory)"
                         + (f": {hint}" if hint else ""))


def readable_file(what: str, path) -> Path:
    """``path`` as a file that can be read, else ValueError naming ``what`` (e.g. "--mesh", "blade table file") and
    why: it does not exist, it is a folder, it cannot be read."""
    if not isinstance(path, (str, os.PathLike)) or str(path).strip() == "":
        raise ValueError(f"{what} must be a file's path, got {path!r}")
    path = Path(path)
    if path.is_dir():
        raise ValueError(f"{what} {path} is a folder, not a file")
    if not path.is_file():
        raise ValueError(f"{what} {path} does not exist")
    if not os.access(path, os.R_OK):
        raise ValueError(f"{what} {path} cannot be read (permission denied)")
    return path


LOCK_FILE = ".lock"
_HELD: dict[str, list] = {}        # the locks this process holds: real path of the folder -> [fd, lock file, depth]


def _holder(fd: int) -> str:
    """Who holds the lock of the open lock file ``fd``: 'pid <n>' (and ' on <host>' when not this machine's)."""
    try:
        words = os.pread(fd, 200, 0).decode(errors="replace").split()
    except OSError:
        words = []
    if not words or not words[0].isdigit():
        return "pid unknown"
    host = f" on {words[1]}" if len(words) > 1 and words[1] != socket.gethostname() else ""
    return f"pid {words[0]}{host}"


def _acquire(folder: Path, what: str) -> str | None:
    """Take ``folder``'s lock (see ``output_lock``); its key in ``_HELD``, None where the file system has no locks."""
    key = os.path.realpath(folder)
    if key in _HELD:                                    # this process holds it already (a sweep within its map)
        _HELD[key][2] += 1
        return key
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / LOCK_FILE
    for _ in range(20):
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            holder = _holder(fd)
            os.close(fd)
            if exc.errno in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                raise ValueError(f"{what} {folder} is in use by another run ({holder}, holding {path}): wait for "
                                 f"it to end, or write elsewhere") from None
            LOG.warning("cannot lock %s (%s): two runs on %s would not see each other", path,
                        exc.strerror or exc, folder)
            return None
        try:
            same = os.path.samestat(os.fstat(fd), os.stat(path))
        except FileNotFoundError:
            same = False
        if same:
            os.ftruncate(fd, 0)
            os.pwrite(fd, f"{os.getpid()} {socket.gethostname()}\n".encode(), 0)
            _HELD[key] = [fd, path, 1]
            return key
        os.close(fd)                                    # its holder removed it as it let go: the new one
    raise ValueError(f"{what} {folder}: could not take its lock {path} (other runs keep taking it)")


def _release(key: str | None) -> None:
    if key is None or key not in _HELD:
        return
    held = _HELD[key]
    held[2] -= 1
    if held[2] == 0:
        del _HELD[key]
        fd, path = held[0], held[1]
        with contextlib.suppress(OSError):
            path.unlink()                               # while held: a run that opened it retries on the new one
        os.close(fd)


@contextlib.contextmanager
def output_lock(folder, what: str = "output folder", comm=None, check: Callable[[], None] | None = None):
    """Hold ``folder``'s lock for the block (created if need be): an advisory ``fcntl.flock`` on ``<folder>/.lock``,
    which holds the holder's pid and host. A second run on the same folder (another process) is refused at once: a
    ValueError in one line naming ``what`` (e.g. '--out'), the folder and the holder's pid. The OS lets the lock go
    when its process ends, crashed or killed; the file is removed when the block ends. Re-entrant within a process (a
    map's sweeps take their own folders' locks inside the map's). ``check()``, if given, runs once the lock is held,
    before the block (the checks of the folder's files before any work; its ValueError refuses the run too).

    With ``comm`` (an mpi4py communicator) rank 0 alone takes the lock and runs ``check``; every rank waits for it
    (asleep) and raises the same refusal, so no rank is left waiting for another that stopped."""
    rank = 0 if comm is None else comm.rank
    key, error = None, None
    if rank == 0:
        try:
            key = _acquire(Path(folder), what)
            if check is not None:
                check()
        except Exception as exc:                          # any failure: told to every rank before it is raised
            _release(key)
            key, error = None, exc
    if comm is not None and comm.size > 1:
        request = comm.Ibarrier()                         # the others wait asleep (rank 0 may read many files)
        while not request.Test():
            time.sleep(0.05)
        message = comm.bcast(None if error is None else " ".join(str(error).split()), root=0)
        if message is not None and error is None:
            error = ValueError(message)
    if error is not None:
        raise error
    try:
        yield Path(folder)
    finally:
        _release(key)
