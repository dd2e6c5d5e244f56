"""Speed sweeps of the reduced contact model: interaction maps, NFRC, sequential continuation (§2.3.1, §2.3.3).

Pure NumPy (mpi4py optional, only to split a sweep over ranks). Each speed's result is written atomically as soon as
it finishes (``<out>/<key>/omega_<speed>.npz``); a batch in flight also checkpoints its whole loop state, so a killed
sweep resumes where it stopped and nothing already computed is recomputed. The key hashes the model, the scheme and
the scenario: files of another set-up are never mixed in. A sweep holds its folder's lock while it runs (a second run
on the same folder is refused at once), and checks the folder's files before it works: a damaged spec, result or
checkpoint is named in a warning and moved aside (or removed, a checkpoint), and what it held computed again.
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import logging
import time
from pathlib import Path
from collections.abc import Iterator, Mapping
from typing import Sequence

import numpy as np

from rotor37_rom.checks import output_lock, real_number, whole_number
from rotor37_rom.dynamics.casing import Casing
from rotor37_rom.dynamics.explicit import CentralDifference, simulate
from rotor37_rom.dynamics.recorder import LoopState, loop_state, save_loop_state
from rotor37_rom.npz import load_json, save_json, save_npz, set_aside
from rotor37_rom.post.signals import (engine_order_content, is_steady, last_revolution_max,  # noqa: F401 (kept
                                       response_period)                     # importable here for earlier users)

__all__ = ["SweepSpec", "run_sweep", "rerun_diverged", "load_sweep", "compute_seconds", "load_speed", "sweep_folder",
           "read_spec", "check_spec",
           "interaction_map", "InteractionMap", "engine_order_resonance", "record_row", "last_revolution_max",
           "sector_maxima", "sector_rows", "continuation", "ContinuationPoint", "is_steady", "response_period",
           "engine_order_content", "sweep_seconds"]

LOG = logging.getLogger(__name__)
LE = "0:LE"     # the node whose response makes the maps and NFRC: node LE of sector 0 (a NodeMap label)


@dataclasses.dataclass(frozen=True)
class SweepSpec:
    """A contact scenario at several speeds. revolutions: per speed (paper 200); record_dt: sampling (s);
    monitor: node-map rows whose normal displacement is recorded (None: all nodes of the model)."""

    revolutions: float = 200.0
    casing: Casing = Casing()
    record_dt: float = 1e-5
    batch_size: int = 16
    monitor: tuple | None = None

    def __post_init__(self):
        real_number("revolutions", self.revolutions, 0, open_low=True)
        real_number("record_dt", self.record_dt, 0, open_low=True, unit=" s")
        whole_number("batch_size", self.batch_size, 1)
        if not isinstance(self.casing, Casing):
            raise TypeError(f"casing must be a Casing, got {type(self.casing).__name__}")


def _key(scheme: CentralDifference, spec: SweepSpec, h: float | None = None) -> str:
    # h to 12 digits: the step from omega_max differs in its last bit with the BLAS thread count (mpirun ranks run
    # one thread each), and those are the same run (``sweep_folder`` also finds a folder whose step rounded apart)
    info = {"model": scheme.model.key, "h": float(f"{scheme.h if h is None else h:.12g}"),
            "nonlinear": scheme.nonlinear, "massless": scheme.massless,
            "spec": dataclasses.asdict(spec) | {"batch_size": None}}
    if scheme.frequency_cap is not None:                 # absent from older keys: their results stay valid
        info["frequency_cap"] = scheme.frequency_cap
    if scheme.rotation is not None:                      # a turning blade's runs (dynamics.turning)
        info["rotation"] = dataclasses.asdict(scheme.rotation)
    return hashlib.sha256(json.dumps(info, sort_keys=True, default=str).encode()).hexdigest()[:16]


def _speed_file(folder: Path, omega: float) -> Path:
    return folder / f"omega_{omega:012.4f}.npz"


RESULT_KEYS = ("omega", "t", "u_r", "diverged_step")     # what every speed's record holds (and a map reads)


def check_spec(spec) -> None:
    """ValueError unless ``spec`` (a sweep folder's spec.json, read) is what ``run_sweep`` writes: an object with the
    step 'h' (s, > 0) and the 'model' key."""
    if not isinstance(spec, dict):
        raise ValueError(f"a JSON object expected, got {type(spec).__name__}")
    h = spec.get("h")
    if isinstance(h, bool) or not isinstance(h, (int, float)) or not 0 < h < float("inf"):
        raise ValueError(f"its step 'h' must be a number > 0, got {h!r}")
    if not isinstance(spec.get("model"), str):
        raise ValueError(f"its 'model' must be a model's key, got {spec.get('model')!r}")


def read_spec(folder: str | Path, then: str = "its sweep writes a new one when it runs") -> dict | None:
    """The spec.json of a sweep folder (``check_spec``); None where it is absent or damaged: a damaged one is moved
    aside with a warning naming it and ``then``, what the caller does instead (``npz.load_json``)."""
    return load_json(Path(folder) / "spec.json", check_spec, then)


def _named_step(name: str, scheme: CentralDifference, spec: SweepSpec) -> float | None:
    """The step whose key (with ``scheme`` and ``spec``) names a folder ``name``: the scheme's, or a step one unit
    apart in its 12th digit (the same run's step from another BLAS: ``sweep_folder``); None if neither."""
    if name == _key(scheme, spec):
        return scheme.h
    h12 = float(f"{scheme.h:.12g}")
    unit = 10.0 ** (np.floor(np.log10(h12)) - 11)
    near = (float(f"{h12 + k * unit:.12g}") for k in (-1, 1))
    return next((h for h in near if name == _key(scheme, spec, h)), None)


def sweep_folder(scheme: CentralDifference, spec: SweepSpec, out: str | Path) -> Path:
    """The folder under ``out`` where ``run_sweep`` writes the speeds of ``scheme`` and ``spec``: the one its key
    names or, if that does not exist, an existing folder of the same run whose step differs by round-off only (its
    name is the key of everything else at its own step, within 1e-9 of ours). The step from the highest frequency
    differs in its last digits with the BLAS threads; the key rounds it to 12 digits, and two such steps can round
    apart (2.6525823848459e-06 and ...8440e-06: a restarted run would start over). A folder whose step rounded one
    unit apart is found by its name, even where its spec.json is damaged; another folder's damaged spec.json is named
    in a warning."""
    out = Path(out)
    folder = out / _key(scheme, spec)
    if folder.exists() or not out.is_dir():
        return folder
    for other in sorted(out.iterdir()):
        if not other.is_dir():
            continue
        if _named_step(other.name, scheme, spec) is not None:
            return other
        path = other / "spec.json"
        if not path.is_file():
            continue
        try:
            saved = json.loads(path.read_text())
            check_spec(saved)
            h = float(saved["h"])
        except (OSError, ValueError, KeyError, TypeError) as exc:
            LOG.warning("%s is damaged (%s): its folder is not taken for this sweep (a run of its own sweep moves "
                        "it aside and writes a new one)", path, " ".join(str(exc).split()))
            continue
        if abs(h - scheme.h) <= 1e-9 * scheme.h and other.name == _key(scheme, spec, h):
            return other
    return folder


def load_speed(folder: str | Path, omega: float) -> Mapping | None:
    """The record of one speed of a sweep folder (as ``load_sweep`` gives it); None if it is absent or unreadable."""
    path = _speed_file(Path(folder), float(omega))
    return _load_result(path) if path.exists() else None


class SavedRecord(Mapping):
    """A saved result (one speed's record, a checkpoint) read from its .npz file on demand: entries under 1 MB are
    read when it opens, each larger one when first asked for, then kept. A 200-revolution disk record holds ~230 MB of
    contact-force histories (288 nodes) that a map never reads: read eagerly, the 90 records of a disk map took 20 GB
    of the machine's 24."""

    SMALL = 1 << 20                                        # bytes

    def __init__(self, path: str | Path):
        self.path = Path(path)
        with np.load(self.path, allow_pickle=False) as data:
            sizes = {k: data.zip.getinfo(k + ".npy").file_size for k in data.files}
            self._keys = tuple(data.files)
            self._cache = {k: data[k] for k in self._keys if sizes[k] < self.SMALL}

    def read(self, key: str) -> np.ndarray:
        """record[key] read from the file without keeping it (a map's 90 multiplier histories would take 18 GB)."""
        if key in self._cache:
            return self._cache[key]
        if key not in self._keys:
            raise KeyError(key)
        with np.load(self.path, allow_pickle=False) as data:
            return data[key]

    def __getitem__(self, key: str) -> np.ndarray:
        if key not in self._cache:
            if key not in self._keys:
                raise KeyError(key)
            with np.load(self.path, allow_pickle=False) as data:
                self._cache[key] = data[key]
        return self._cache[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self._keys)

    def __len__(self) -> int:
        return len(self._keys)


def _load_result(path: Path) -> SavedRecord | None:
    """The saved result at ``path`` (``SavedRecord``), None if its file cannot be opened (truncated, corrupted: the
    caller computes it again; files are written whole by ``save_npz``, so a member that opens reads)."""
    try:
        return SavedRecord(path)
    except Exception as exc:
        LOG.warning("ignoring the damaged file %s (%s: %s)", path, exc.__class__.__name__, " ".join(str(exc).split()))
        return None


def _result_damage(path: Path) -> str | None:
    """Why the speed file ``path`` cannot be used (it does not open, a small entry does not read, an entry every
    record holds is missing, or it holds another speed than its name's); None when it can. Reads what ``SavedRecord``
    reads when it opens (the entries under 1 MB; the larger ones' zip entries are listed, not read)."""
    try:
        record = SavedRecord(path)
        missing = [k for k in RESULT_KEYS if k not in record]
        if missing:
            return f"no {', '.join(missing)}"
        if _speed_file(path.parent, float(record["omega"])) != path:
            return f"it holds the speed {float(record['omega'])!r} rad/s"
    except Exception as exc:
        return " ".join(f"{exc.__class__.__name__}: {exc}".split())
    return None


def _check_folder(folder: Path, scheme: CentralDifference, spec: SweepSpec, speeds: np.ndarray) -> None:
    """Before a sweep works in ``folder`` (rank 0, its lock held): every file the sweep and its reader read back is
    checked, and a damaged one named in a warning with what is done about it. The spec.json is moved aside and
    written again; a damaged speed file is moved aside (``<name>.damaged-<n>``) and, if it is one of ``speeds``,
    computed again (a speed not among them: by a sweep of its speed, or its batch run again for a lost batch-mate); a
    damaged batch checkpoint is removed (its batch starts over)."""
    step = _named_step(folder.name, scheme, spec)
    saved = read_spec(folder, "a new one is written")
    if saved is None:                                   # absent or just moved aside; a folder found by round-off
        save_json(folder / "spec.json", {                # keeps its own step (its name's)
            "h": scheme.h if step is None else step, "nonlinear": scheme.nonlinear, "model": scheme.model.key,
            "r": scheme.r, "spec": dataclasses.asdict(spec),
            "rotation": None if scheme.rotation is None else dataclasses.asdict(scheme.rotation)},
            default=str, indent=1)
    wanted = {_speed_file(folder, w).name for w in speeds}
    for path in sorted(p for p in folder.glob("omega_*.npz") if ".tmp" not in p.name):
        why = _result_damage(path)
        if why is not None:
            set_aside(path, why, "its speed is computed again" if path.name in wanted
                      else "not read (a sweep of its speed computes it again)")
    for ckpt in sorted(p for p in folder.glob("batch_*.ckpt.npz") if ".tmp" not in p.name):
        try:
            with np.load(ckpt, allow_pickle=False) as data:
                np.asarray(data["speeds"], float)
        except Exception as exc:
            LOG.warning("%s is damaged (%s: %s): removed; its batch starts over", ckpt, exc.__class__.__name__,
                        " ".join(str(exc).split()))
            ckpt.unlink(missing_ok=True)


def idle_barrier(comm, poll: float = 0.05) -> None:
    """A barrier the ranks wait at asleep, polling every ``poll`` s: OpenMPI's blocking calls spin a core, which a
    rank that finished its speeds would hold for hours while another integrates (or rank 0 does serial work)."""
    request = comm.Ibarrier()
    while not request.Test():
        time.sleep(poll)


def run_sweep(scheme: CentralDifference, speeds: Sequence[float], spec: SweepSpec, out: str | Path,
              comm=None, progress: bool = True, checkpoint_seconds: float = 60.0) -> Path:
    """Simulate every speed from rest (paper §2.3.1; a turning scheme's from its centrifugal state) in batches;
    return the folder of per-speed results.

    With ``comm`` (an mpi4py communicator) the speeds still to do are dealt round-robin to the ranks; every rank
    writes its own files, and all ranks return once the folder is complete."""
    speeds = np.unique(np.asarray(speeds, float))
    if speeds.size == 0 or speeds.min() <= 0:
        raise ValueError("speeds: give at least one angular speed Omega > 0 rad/s")
    folder = sweep_folder(scheme, spec, out)
    # the folder's lock (rank 0's), then its files checked, before any work: a second run on it is refused at once
    with output_lock(folder, "sweep folder", comm, check=lambda: _check_folder(folder, scheme, spec, speeds)):
        return _run_sweep(scheme, speeds, spec, folder, comm, progress, checkpoint_seconds)


def _run_sweep(scheme: CentralDifference, speeds: np.ndarray, spec: SweepSpec, folder: Path, comm, progress: bool,
               checkpoint_seconds: float) -> Path:
    """``run_sweep``'s work in ``folder`` (locked and checked)."""
    rank, size = (comm.rank, comm.size) if comm is not None else (0, 1)
    # batches interrupted earlier resume first (their speeds stay together); then the speeds not done yet
    pending = sorted(p for p in folder.glob("batch_*.ckpt.npz") if ".tmp" not in p.name)
    resumed = []
    for ckpt in pending:
        data = _load_result(ckpt)
        if data is None or "speeds" not in data:
            ckpt.unlink(missing_ok=True)
            continue
        resumed.append((ckpt, np.asarray(data["speeds"], float), int(data["n"]) if "n" in data else 0))
    in_ckpt = set(np.concatenate([b for _, b, _ in resumed]).tolist()) if resumed else set()
    todo = [w for w in speeds if w not in in_ckpt and not _readable(_speed_file(folder, w))]
    work, keep = _batch_layout(folder, todo, spec.batch_size, size, write=rank == 0)
    if comm is not None:
        idle_barrier(comm)                               # the layout written before anyone runs
    batches = [b for _, b, _ in resumed[rank::size]] + work[rank::size]
    record_every = max(1, int(round(spec.record_dt / scheme.h)))
    bar = None
    if progress and rank == 0 and batches:
        try:
            from tqdm import tqdm
            steps = lambda w: np.ceil(spec.revolutions * 2 * np.pi / w / scheme.h)          # noqa: E731
            total = int(sum(steps(w) for b in batches for w in b))
            done = int(sum(min(n, steps(w)) for _, b, n in resumed[rank::size] for w in b))   # resumed batches
            # rank 0's simulation-steps, scaled by the ranks (they run equal shares)
            bar = tqdm(total=total * size, initial=done * size, unit="sim-step", unit_scale=True,
                       desc=f"sweep ({len(todo) + len(in_ckpt)} speeds, {len(in_ckpt)} resumed)")
        except ImportError:
            bar = None
    for batch in batches:
        ckpt = folder / f"batch_{hashlib.sha256(batch.tobytes()).hexdigest()[:12]}.ckpt.npz"

        def on_finish(p, rec, batch=batch):
            if batch[p] not in keep and _readable(_speed_file(folder, batch[p])):
                return                                   # a batch run again for another of its speeds
            save_npz(_speed_file(folder, batch[p]), omega=batch[p], h=scheme.h, t=rec["t"], u_r=rec["u_r"],
                     lam=rec["lam"], q_final=rec["q_final"], q_prev=rec["q_prev"],
                     max_penetration=rec["max_penetration"], min_multiplier=rec["min_multiplier"],
                     friction_power=rec["friction_power"], diverged_step=rec["diverged_step"],
                     work=rec["work"], revolutions=spec.revolutions, labels=rec["labels"],
                     batch_wall_s=rec["wall"], batch_speeds=batch)       # the batch's wall so far, over sittings

        state = _load_state(ckpt, batch.size)

        def save_state(st, ckpt=ckpt, batch=batch):
            save_loop_state(ckpt, st, batch)

        simulate(scheme, batch, spec.casing, revolutions=spec.revolutions, record_every=record_every,
                 monitor=spec.monitor, on_blowup="flag", on_finish=on_finish, state=state, checkpoint=save_state,
                 checkpoint_seconds=checkpoint_seconds,
                 progress=(None if bar is None else lambda k: bar.update(k * size)))
        ckpt.unlink(missing_ok=True)
    if bar is not None:
        bar.close()
    if comm is not None:
        idle_barrier(comm)
    return folder


def rerun_diverged(scheme: CentralDifference, results: Sequence[dict], spec: SweepSpec, out: str | Path,
                   retries: int = 1, comm=None, progress: bool = True) -> tuple[list[dict], dict]:
    """Run the speeds of ``results`` (``load_sweep``) that blew up again with the step halved, up to ``retries``
    times; each retry is a sweep of its own under ``out`` (cached, resumable, distributed like ``run_sweep``).

    Returns the results with the retried speeds replaced, and {speed: step of its last retry}. A speed still blown up
    after the last retry stays marked (``diverged_step`` >= 0). Under MPI only rank 0 needs ``results`` (the records
    of a 100-speed map take ~1 GB): it tells the others which speeds to rerun, and only it loads the reruns; the
    other ranks get back their ``results`` unchanged (e.g. [])."""
    if not 0 <= retries <= 8:
        raise ValueError(f"retries must be in 0..8, got {retries}")
    results, retried = list(results), {}
    root = comm is None or comm.rank == 0
    for k in range(1, retries + 1):
        bad = np.array([float(r["omega"]) for r in results if int(r["diverged_step"]) >= 0]) if root else None
        if comm is not None:
            idle_barrier(comm)                           # rank 0 may still be reading the records
            bad = comm.bcast(bad, root=0)
        if bad.size == 0:
            break
        h = scheme.h / 2 ** k
        if progress and root:
            LOG.warning("%d speeds blew up: again with h = %.3g s", bad.size, h)
        folder = run_sweep(scheme.with_step(h), bad, spec, out, comm=comm, progress=progress)
        if root:
            again = {float(r["omega"]): r for r in load_sweep(folder)}
            results = [again.get(float(r["omega"]), r) if int(r["diverged_step"]) >= 0 else r for r in results]
        retried.update({w: h for w in bad.tolist()})
    return results, retried


def sweep_seconds(scheme: CentralDifference, speeds, spec: SweepSpec, probe_steps: int = 300) -> float:
    """The wall time a serial ``run_sweep`` of ``speeds`` should take on this machine: each batch runs until its
    slowest speed ends, so with its runs' step counts s_1 >= ... >= s_P it costs sum_k (s_k - s_(k+1)) c(k), c(k) the
    wall of one step with k runs, measured by probes of ``probe_steps`` steps from rest (1 and P runs, no contact
    yet, the fastest of three) and interpolated linearly between them (a step's forces and contact cost grow with
    k). The integration only: a map's charts and files, and the contact steps' own cost, come on top."""
    speeds = np.sort(np.asarray(speeds, float))
    whole_number("probe_steps", probe_steps, 10)
    steps = np.ceil(spec.revolutions * 2 * np.pi / speeds / scheme.h)
    batches = [steps[i:i + spec.batch_size] for i in range(0, speeds.size, spec.batch_size)]
    widest = max(b.size for b in batches)
    cost = {}
    for k in sorted({1, widest}):                       # the fastest of three: the first pays for warming up,
        cost[k] = min(simulate(scheme, speeds[:k], spec.casing, n_steps=probe_steps, record_every=probe_steps,
                               on_blowup="flag", duration=float(spec.revolutions * 2 * np.pi / speeds[0])).wall
                      for _ in range(3)) / probe_steps   # another job's bursts on a shared core inflate the others

    def c(k: int) -> float:
        return cost[1] if widest == 1 else cost[1] + (cost[widest] - cost[1]) * (k - 1) / (widest - 1)

    total = 0.0
    for b in batches:
        s = np.sort(b)[::-1]
        total += sum((s[k - 1] - (s[k] if k < s.size else 0.0)) * c(k) for k in range(1, s.size + 1))
    return float(total)


def _batch_layout(folder: Path, todo: list[float], batch_size: int, size: int, write: bool
                  ) -> tuple[list[np.ndarray], set[float]]:
    """The batches that compute the speeds ``todo`` (not done, not in a checkpoint), in the order the ranks deal
    them (batch k to rank k mod ``size``), and the speeds to write.

    A batch's BLAS calls round a column's arithmetic by the batch it sits in (8.5e-9 of u_r measured between 1,400
    rad/s run beside 1,300 and alone), so a speed is always computed in the batch it was first computed in: the
    folder's ``batches.json`` keeps every batch ever formed, a lost speed file is computed again with its whole
    batch (only the lost speeds written) and the map stays bit-identical. Speeds never run form new batches as a
    first run does: each rank's round-robin share of them in chunks of ``batch_size``, recorded before they run
    (rank 0 writes the layout: ``write``)."""
    path = folder / "batches.json"
    try:
        layout = [np.asarray(b, float) for b in json.loads(path.read_text())["batches"]] if path.is_file() else []
    except (ValueError, KeyError, TypeError):
        LOG.warning("ignoring the unreadable batch layout %s: its lost speeds form new batches", path)
        layout = []
    known = {float(w): k for k, b in enumerate(layout) for w in b}
    again = sorted({known[w] for w in todo if w in known})
    new = [w for w in todo if w not in known]
    shares = [new[r::size] for r in range(size)]
    chunks = max((len(s) + batch_size - 1) // batch_size for s in shares) if new else 0
    formed = [np.array(shares[r][i * batch_size:(i + 1) * batch_size]) for i in range(chunks) for r in range(size)]
    formed = [b for b in formed if b.size]
    if formed and write:
        save_json(path, {"batches": [b.tolist() for b in layout + formed]}, indent=1)
    return [layout[k] for k in again] + formed, set(todo)


def compute_seconds(records: Sequence[Mapping]) -> float | None:
    """The time spent integrating ``records`` (``load_sweep``), over every sitting: the sum of their batches' walls
    (each batch's at its last speed's end), in process-seconds (under mpirun the ranks' sum); None where a record
    predates the batch walls."""
    batches = {}
    for r in records:
        if "batch_wall_s" not in r:
            return None
        key = tuple(np.asarray(r["batch_speeds"], float).tolist())
        batches[key] = max(batches.get(key, 0.0), float(r["batch_wall_s"]))
    return float(sum(batches.values()))


def _load_state(path: Path, P: int) -> LoopState | None:
    data = _load_result(path) if path.exists() else None
    if data is None:
        return None
    st = loop_state(data, P)
    LOG.info("resuming batch from %s at step %d", path, st.n)
    return st


def _readable(path: Path) -> bool:
    """The file opens as an npz with its speed (a cheap check: the arrays are not read)."""
    try:
        with np.load(path, allow_pickle=False) as data:
            float(data["omega"])
        return True
    except Exception:
        return False


def load_sweep(folder: str | Path) -> list[Mapping]:
    """All per-speed results of a sweep folder, sorted by speed (``SavedRecord``: large arrays read on demand)."""
    files = sorted(p for p in Path(folder).glob("omega_*.npz") if ".tmp" not in p.name)   # (older temporaries)
    out = [r for r in (_load_result(f) for f in files) if r is not None]
    return sorted(out, key=lambda r: float(r["omega"]))


def sector_rows(record: dict, node: str = "LE", every: bool = False) -> list[int]:
    """Rows of ``record['u_r']`` holding ``node`` (monitored labels '<sector>:<node>'), in sector order; with
    ``every``, the node must be recorded on every sector 0..N-1."""
    found = sorted((int(label.partition(":")[0]), i) for i, label in enumerate(map(str, record["labels"]))
                   if label.partition(":")[2] == node)
    if every and [sector for sector, _ in found] != list(range(len(found))):
        raise ValueError(f"node {node} must be recorded on every sector 0..N-1; recorded on "
                         f"{[sector for sector, _ in found]}")
    return [i for _, i in found]


def sector_maxima(record: dict, node: str = "LE") -> np.ndarray:
    """Every sector's max |u| of ``node`` over the last revolution in a disk's sweep record (its monitored labels
    '<sector>:<node>'), in sector order; NaN where the run blew up."""
    rows = sector_rows(record, node)
    if int(record["diverged_step"]) >= 0:
        return np.full(len(rows), np.nan)
    return np.array([last_revolution_max(record["t"], record["u_r"][i], float(record["omega"])) for i in rows])


@dataclasses.dataclass
class InteractionMap:
    """speeds (n,), frequencies (m,) rad/s, amplitude (n, m) of the LE normal displacement spectrum (m),
    nfrc (n,) max over the last revolution (m), diverged (n,) bool."""

    speeds: np.ndarray
    frequencies: np.ndarray
    amplitude: np.ndarray
    nfrc: np.ndarray
    diverged: np.ndarray


def record_row(result: dict, node: str = LE) -> int:
    """Row of ``result['u_r']`` (a per-speed record of ``run_sweep`` / ``simulate``) holding node ``node``
    ('<sector>:<name>')."""
    labels = [str(x) for x in result.get("labels", ())]
    if node not in labels:
        raise ValueError(f"node {node!r} is not recorded in this result; recorded: {labels}")
    return labels.index(node)


def interaction_map(results: Sequence[dict], node: str = LE, f_max: float = 30000.0, n_freq: int = 600
                    ) -> InteractionMap:
    """Spectrum of the second half of node ``node``'s normal displacement at each speed (paper §2.3.1); ``node``
    is a node-map label, '<sector>:<name>' (default node LE of sector 0)."""
    freqs = np.linspace(0.0, f_max, n_freq)
    speeds, amp, nfrc, div = [], [], [], []
    for res in results:
        t, u = res["t"], res["u_r"][record_row(res, node)]
        om = float(res["omega"])
        speeds.append(om)
        diverged = int(res["diverged_step"]) >= 0 or not np.all(np.isfinite(u))
        div.append(diverged)
        if diverged:
            amp.append(np.full(n_freq, np.nan))
            nfrc.append(np.nan)
            continue
        half = u[len(u) // 2:]
        dt = t[1] - t[0]
        spec = np.abs(np.fft.rfft(half - half.mean())) * 2.0 / len(half)
        w = 2 * np.pi * np.fft.rfftfreq(len(half), dt)
        amp.append(np.interp(freqs, w, spec))
        nfrc.append(last_revolution_max(t, u, om))
    return InteractionMap(np.array(speeds), freqs, np.array(amp), np.array(nfrc), np.array(div))


def engine_order_resonance(imap: InteractionMap, order: int, revolutions: float) -> float:
    """The resonance of an engine-order interaction in a zero-IC map (paper §2.3.1: the 1B/EO4 resonance is
    ``order`` = 4): the speed of largest NFRC among the bounded speeds whose response is dominated by that engine
    order, i.e. whose largest spectral peak above Omega / 2 lies within the spectrum's resolution of order x Omega:
    one bin of the transform of the run's second half (2 Omega / ``revolutions``) or two steps of the map's frequency
    grid, whichever is larger. NaN when no bounded speed is dominated by that order.

    In 1200-1600 rad/s only 1B is near 4 Omega (omega_1 = 5414 rad/s on the ci blade); the largest response of a
    short map can be a higher mode's crossing instead (e.g. 1T near 10 Omega), which this leaves out."""
    if not order >= 1 or not revolutions > 0:
        raise ValueError(f"need order >= 1 and revolutions > 0, got {order}, {revolutions}")
    grid = imap.frequencies[1] - imap.frequencies[0]
    best, speed = -np.inf, np.nan
    for omega, spectrum, amplitude in zip(imap.speeds, imap.amplitude, imap.nfrc):
        if not np.isfinite(amplitude):
            continue
        above = imap.frequencies > omega / 2
        dominant = imap.frequencies[above][np.argmax(spectrum[above])]
        if abs(dominant - order * omega) <= max(2 * omega / revolutions, 2 * grid) and amplitude > best:
            best, speed = amplitude, float(omega)
    return speed


@dataclasses.dataclass
class ContinuationPoint:
    omega: float
    amplitude: float
    steady: bool
    halvings: int
    period: int = 0            # in half revolutions (``response_period``); 0: not periodic within 12 T; -1: unknown
                               # (record too short, or the run diverged)


def _shorter_branch(path: Path, info: dict) -> SavedRecord | None:
    """A saved branch that the branch of ``info`` (to be written at ``path``) extends: the same sweep key, start,
    step and settings, going the same way but stopping short of this one's stop (the farthest such). None if there is
    none. Branches written before their settings were saved with them (``branch_info``) are not considered."""
    start, stop, *rest = info["branch"]
    sign, best, best_stop = (1.0 if stop >= start else -1.0), None, None
    for other in sorted(path.parent.glob("continuation_*.npz")):
        if other == path:
            continue
        saved = _load_result(other)
        if saved is None or "branch_info" not in saved:
            continue
        theirs = json.loads(str(saved["branch_info"]))
        o_start, o_stop, *o_rest = theirs["branch"]
        if (theirs["sweep"] == info["sweep"] and o_start == start and o_rest == rest
                and 0 < sign * (o_stop - start) < sign * (stop - start)
                and (best_stop is None or sign * (o_stop - best_stop) > 0)):
            best, best_stop = saved, o_stop
    return best


def continuation(scheme: CentralDifference, start: float, stop: float, step: float, casing: Casing = Casing(),
                 first_revolutions: float = 200.0, revolutions: float = 30.0, max_halvings: int = 3,
                 record_dt: float = 1e-5, tol: float = 0.02, progress: bool = False,
                 out: str | Path | None = None, window: int = 1, batch_halvings: bool = True,
                 node: str = LE, unsteady: str = "smallest") -> list[ContinuationPoint]:
    """Sequential continuation (§2.3.3): each speed starts from the final state of the previous one; the first
    runs ``first_revolutions``, the next ``revolutions``; when a run is not steady (``is_steady`` with ``tol`` and
    ``window``) the speed step is halved (at most ``max_halvings`` times) and the run redone from the last accepted
    state. Sweeps up if stop > start. The amplitude is node ``node``'s ('<sector>:<name>', default LE of sector 0).

    The halved candidates all start from the same state, so with ``batch_halvings`` they run as one batch: after a
    point that needed a halving all candidates (step, step/2, ...) at once, otherwise the full step alone and, if it
    is not steady, the remaining ones at once. The first steady candidate in that order is accepted, the one the
    one-by-one procedure accepts (to the batch's round-off); a batch of a few costs little more than one run
    (``benchmarks/bench_integrator.py``: r = 55, 218 us per step alone).

    When no candidate is steady, ``unsteady`` says which one is accepted (marked not steady): 'smallest' (the
    paper's words read literally, the default: the step stays divided, so an unsteady stretch advances by
    step / 2**max_halvings per point) or 'full' (the divisions did not make it steady, so the full step is kept, or
    the largest one whose run did not blow up: the same resolution everywhere, up to 2**max_halvings times fewer
    points across an unsteady stretch).

    The casing is fully ovalized from the start of every continued run (the ramp only applies to the first). A run
    that diverges ends the branch (its point has amplitude NaN). With ``out`` the branch is written after every
    accepted point (``<out>/continuation_<key>.npz``: the points, the state, the rotor angle and the branch's
    settings), so a killed continuation resumes from its last accepted speed and a finished one is read back. A branch
    with a farther stop than a saved one (same start, step and settings, same direction) extends it from its last
    point instead of starting from rest again; it passes through the shorter branch's stop (a branch that ended where
    a run diverged is returned as it is)."""
    if step <= 0:
        raise ValueError(f"continuation step must be > 0 rad/s, got {step}")
    if max_halvings < 0:
        raise ValueError(f"max_halvings must be >= 0, got {max_halvings}")
    if window < 1:
        raise ValueError(f"steadiness window must be >= 1 revolution, got {window}")
    if unsteady not in ("smallest", "full"):
        raise ValueError(f"unsteady must be 'smallest' or 'full', got {unsteady!r}")
    sign = 1.0 if stop >= start else -1.0
    record_every = max(1, int(round(record_dt / scheme.h)))
    path = None
    if out is not None:
        branch = [start, stop, step, revolutions, max_halvings, tol] + ([window] if window != 1 else []) \
            + ([node] if node != LE else []) + ([unsteady] if unsteady != "smallest" else [])
        info = {"sweep": _key(scheme, SweepSpec(revolutions=first_revolutions, casing=casing, record_dt=record_dt)),
                "branch": branch}
        info_json = json.dumps(info, sort_keys=True)     # the key's digest, and saved with the branch
        path = Path(out) / f"continuation_{hashlib.sha256(info_json.encode()).hexdigest()[:16]}.npz"
    saved = _load_result(path) if path is not None and path.exists() else None
    extended = False
    if saved is None and path is not None:               # a farther stop than a saved branch: extend that one
        saved = _shorter_branch(path, info)
        extended = saved is not None

    def save(finished: bool) -> None:
        if path is not None:
            path.parent.mkdir(parents=True, exist_ok=True)
            save_npz(path, points=np.array([[p.omega, p.amplitude, p.steady, p.halvings, p.period]
                                            for p in points]),
                     q=state[0], q_prev=state[1], phase=phase, omega=omega, finished=finished,
                     branch_info=np.array(info_json))

    if saved is not None:
        points = [ContinuationPoint(float(w), float(a), bool(s), int(k), *(int(x) for x in rest))
                  for w, a, s, k, *rest in saved["points"]]             # branches saved before the period: 4 columns
        state, phase, omega = (saved["q"], saved["q_prev"]), float(saved["phase"]), float(saved["omega"])
        if bool(saved["finished"]) and (not extended or np.isnan(points[-1].amplitude)):
            return points                        # done, or ended where a run diverged: going farther ends there too
        LOG.info("continuation %s at %.1f rad/s from %s", "extends a shorter branch" if extended else "resumes",
                 omega, saved.path)
    else:
        res = simulate(scheme, start, casing, revolutions=first_revolutions, record_every=record_every,
                       on_blowup="flag")
        state, omega = (res.q_final[:, 0], res.q_prev[:, 0]), start
        phase = casing.rotation_sense * start * res.n_steps[0] * scheme.h    # the casing angle carries over
        if res.diverged_step[0] >= 0:
            points = [ContinuationPoint(start, np.nan, False, 0, -1)]
            save(True)
            return points
        row = res.row(node)
        points = [ContinuationPoint(start, last_revolution_max(res.t[0], res.u_r[0][row], start),
                                    is_steady(res.t[0], res.u_r[0][row], start, tol, window), 0,
                                    response_period(res.t[0], res.u_r[0][row], start, tol))]
        if progress:
            LOG.warning("continuation starts at %.1f rad/s: %.4g mm (%s)", start, points[0].amplitude * 1e3,
                        "steady" if points[0].steady else "not steady")
        save(False)
    while sign * (stop - omega) > 1e-9:
        targets = [omega + sign * min(step / 2 ** k, abs(stop - omega)) for k in range(max_halvings + 1)]
        if not batch_halvings:                    # the paper's order: one candidate at a time
            rounds = [[k] for k in range(max_halvings + 1)]
        elif points[-1].halvings > 0 or not points[-1].steady:
            rounds = [list(range(max_halvings + 1))]
        else:
            rounds = [[0], list(range(1, max_halvings + 1))]
        runs = _candidate_runs(scheme, targets, rounds, casing, revolutions, record_every, state, phase, node, tol,
                               window)
        k = next((k for k in range(max_halvings + 1) if targets[k] in runs and runs[targets[k]][2]), None)
        if k is None and unsteady == "full":       # the largest step whose run did not blow up
            k = next((k for k in range(max_halvings + 1) if targets[k] in runs
                      and runs[targets[k]][0].diverged_step[runs[targets[k]][1]] < 0), None)
        k = max_halvings if k is None else k
        target = targets[k]
        r, p, steady = runs[target]
        u = r.u_r[p][r.row(node)]
        bounded = r.diverged_step[p] < 0
        points.append(ContinuationPoint(target, last_revolution_max(r.t[p], u, target) if bounded else np.nan,
                                        steady, k, response_period(r.t[p], u, target, tol) if bounded else -1))
        amp = points[-1].amplitude
        if r.diverged_step[p] >= 0:            # nothing sensible to continue from: the branch ends here
            LOG.warning("continuation stopped at %.1f rad/s: the run diverged at step %d", target,
                        r.diverged_step[p])
            save(True)
            break
        if progress:
            LOG.warning("continuation %.1f rad/s: %.4g mm (%s, %d halvings, period %s)", target, amp * 1e3,
                        "steady" if steady else "not steady", k,
                        f"{points[-1].period}T/2" if points[-1].period > 0
                        else "none within 12T" if points[-1].period == 0 else "unknown: record too short")
        state = (r.q_final[:, p], r.q_prev[:, p])
        phase += casing.rotation_sense * target * r.n_steps[p] * scheme.h
        omega = target
        save(sign * (stop - omega) <= 1e-9)
    return points


def _candidate_runs(scheme: CentralDifference, targets: list[float], rounds: list[list[int]], casing: Casing,
                    revolutions: float, record_every: int, state: tuple, phase: float, node: str, tol: float,
                    window: int) -> dict[float, tuple]:
    """The continuation's candidate runs from ``state``: the speeds ``targets`` (the full step and its halvings), run
    in ``rounds`` (lists of indices of ``targets``, each round one batch) until a round has a steady run. Returns
    {target: (result, index in its batch, steady)}."""
    runs: dict[float, tuple] = {}
    for ks in rounds:
        todo = sorted({targets[k] for k in ks} - runs.keys())
        if todo:
            r = simulate(scheme, todo, casing, revolutions=revolutions, record_every=record_every,
                         initial=state, on_blowup="flag", duration=1e-12, phase=phase)
            runs.update({tg: (r, p, bool(r.diverged_step[p] < 0)
                              and is_steady(r.t[p], r.u_r[p][r.row(node)], tg, tol, window))
                         for p, tg in enumerate(todo)})
        if any(runs[targets[k]][2] for k in ks):
            break
    return runs
