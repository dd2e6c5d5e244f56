"""A map's output folder (#85, items 7 and 8): a damaged file a run reads back (summary.json, a sweep's spec.json, a
speed file) is named, with what is done about it, before any work; two runs on one folder do not both work: the second
is refused at once, naming the folder and the first's pid.

The sweeps here run a stand-in integrator (``fake_simulate``) on a stand-in scheme: what is tested is the folder's
bookkeeping before and around the work, not the dynamics (tests/studies/test_sweep.py runs the real ones)."""
import json
import logging
import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from rotor37_rom.checks import output_lock
from rotor37_rom.dynamics.casing import Casing
from rotor37_rom.studies import contact_map
from rotor37_rom.studies import sweep as sweep_mod
from rotor37_rom.studies.sweep import SweepSpec, load_sweep, run_sweep, sweep_folder

ROOT = Path(__file__).resolve().parents[2]
SPEEDS = [1300.0, 1400.0]
SPEC = SweepSpec(revolutions=1.0, casing=Casing(), record_dt=1e-4)


class Work(Exception):
    """Raised where the run would start its work (the test has seen what it wanted before)."""


def fake_scheme(h: float = 2e-6):
    """What ``run_sweep`` reads of a scheme (its key, its spec.json), without a model."""
    return SimpleNamespace(h=h, nonlinear=False, massless=False, frequency_cap=None, rotation=None, r=3,
                           model=SimpleNamespace(key="a-fake-model"))


def fake_simulate(calls: list, before=None):
    """The integrator as the sweep calls it: each speed of the batch 'finishes' at once with a small record;
    ``calls`` gets each batch; ``before()`` runs first (what must hold before any work)."""
    def simulate(scheme, batch, casing, on_finish=None, **kwargs):
        if before is not None:
            before()
        calls.append(list(map(float, batch)))
        for p, w in enumerate(batch):
            t = np.linspace(0.0, 1e-3, 11)
            on_finish(p, {"t": t, "u_r": np.sin(w * t)[None, :], "lam": np.zeros((1, 11)), "q_final": np.ones(3) * w,
                          "q_prev": np.ones(3), "max_penetration": 0.0, "min_multiplier": 0.0, "friction_power": 0.0,
                          "diverged_step": -1, "work": np.zeros(4), "labels": np.array(["0:LE"]), "wall": 1.0})
    return simulate


def warnings_of(caplog) -> list[str]:
    return [r.getMessage() for r in caplog.records if r.levelno >= logging.WARNING]


def test_a_damaged_speed_file_is_named_and_computed_again(tmp_path, monkeypatch, caplog):
    """A speed file that does not open (garbage) and one cut short: each is named in a warning, moved aside to
    <name>.damaged-1, said to be computed again, before the sweep runs anything; then computed again (the map whole).
    A damaged file of a speed this sweep does not ask for is moved aside too (a reader of the folder would trip on it);
    the batch the lost speeds were run in runs again, so it is computed again too."""
    calls = []
    monkeypatch.setattr(sweep_mod, "simulate", fake_simulate(calls))
    folder = run_sweep(fake_scheme(), SPEEDS + [1500.0], SPEC, tmp_path, progress=False)
    assert calls == [SPEEDS + [1500.0]]
    files = {w: sweep_mod._speed_file(folder, w) for w in SPEEDS + [1500.0]}
    files[1300.0].write_bytes(b"garbage")
    whole = files[1400.0].read_bytes()
    files[1400.0].write_bytes(whole[:len(whole) // 2])                      # cut short: its zip directory lost
    files[1500.0].write_bytes(b"")
    caplog.set_level(logging.WARNING)

    def nothing_damaged_left():
        said = "\n".join(warnings_of(caplog))
        for w in SPEEDS:
            assert f"{files[w]} is damaged" in said and f"moved aside to {files[w]}.damaged-1" in said, said
        assert said.count("its speed is computed again") == 2, said
        assert f"{files[1500.0]} is damaged" in said and "not read (a sweep of its speed computes it" in said, said

    calls.clear()
    monkeypatch.setattr(sweep_mod, "simulate", fake_simulate(calls, before=nothing_damaged_left))
    assert run_sweep(fake_scheme(), SPEEDS, SPEC, tmp_path, progress=False) == folder
    assert calls == [SPEEDS + [1500.0]]                               # their batch, again (batches.json)
    assert [float(r["omega"]) for r in load_sweep(folder)] == SPEEDS + [1500.0]
    assert files[1300.0].with_name(files[1300.0].name + ".damaged-1").read_bytes() == b"garbage"
    assert files[1500.0].with_name(files[1500.0].name + ".damaged-1").read_bytes() == b""


def test_a_damaged_spec_is_named_and_written_again(tmp_path, monkeypatch, caplog):
    """A sweep's spec.json that is not JSON, and one that is JSON without a step: named in a warning, moved aside,
    written again before the sweep runs anything. A folder whose step rounded one unit apart is still the sweep's when
    its spec is damaged (found by its name), and a spec that names nothing is named where the folders are searched."""
    calls = []
    monkeypatch.setattr(sweep_mod, "simulate", fake_simulate(calls))
    folder = run_sweep(fake_scheme(), SPEEDS, SPEC, tmp_path, progress=False)
    spec_file = folder / "spec.json"
    good = json.loads(spec_file.read_text())
    caplog.set_level(logging.WARNING)
    for n, damage in enumerate(["{\"h\": 2e-06, \"mod", json.dumps({"model": "x"})], start=1):
        spec_file.write_text(damage)
        caplog.clear()

        def named_first():
            said = "\n".join(warnings_of(caplog))
            assert f"{spec_file} is damaged" in said and f"moved aside to {spec_file}.damaged-{n}" in said, said
            assert "a new one is written" in said
            assert json.loads(spec_file.read_text()) == good

        calls.clear()
        monkeypatch.setattr(sweep_mod, "simulate", fake_simulate(calls, before=named_first))
        run_sweep(fake_scheme(), SPEEDS + [1500.0 + n], SPEC, tmp_path, progress=False)
        assert calls == [[1500.0 + n]]
        assert (folder / f"spec.json.damaged-{n}").read_text() == damage
    # the same run's step one unit apart in its 12th digit: its folder, found by name though its spec is damaged
    twin = fake_scheme(h=2.00000000001e-6)
    assert sweep_folder(twin, SPEC, tmp_path) == folder
    spec_file.write_text("[")
    caplog.clear()
    assert sweep_folder(twin, SPEC, tmp_path) == folder
    calls.clear()
    run_sweep(twin, SPEEDS, SPEC, tmp_path, progress=False)
    assert calls == [] and json.loads(spec_file.read_text())["h"] == 2e-6     # its own step, its name's
    # another sweep's damaged spec, met where a new sweep looks for its folder: named, not taken
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "spec.json").write_text("not json")
    caplog.clear()
    assert sweep_folder(fake_scheme(h=3e-6), SPEC, tmp_path).name != "other"
    assert any(f"{tmp_path / 'other' / 'spec.json'} is damaged" in m for m in warnings_of(caplog))


def test_a_map_study_reads_no_damaged_spec(tmp_path, caplog):
    """The speed-accuracy study reads every sweep's spec.json after its map: a damaged one is moved aside, named in a
    warning, and not read (its sweep writes a new one when the map runs again)."""
    from rotor37_rom.studies.speed_accuracy.maps import _sweep_specs

    good, bad = tmp_path / "sweeps" / "a", tmp_path / "sweeps" / "b"
    good.mkdir(parents=True)
    bad.mkdir()
    (good / "spec.json").write_text(json.dumps({"h": 1e-6, "model": "k"}))
    (bad / "spec.json").write_text("{")
    caplog.set_level(logging.WARNING)
    assert _sweep_specs(tmp_path / "sweeps", "the map is run again") == {good: {"h": 1e-6, "model": "k"}}
    said = "\n".join(warnings_of(caplog))
    assert f"{bad / 'spec.json'} is damaged" in said and f"moved aside to {bad / 'spec.json'}.damaged-1" in said
    assert "the map is run again" in said


def test_a_damaged_summary_is_moved_aside_before_any_work(tmp_path, monkeypatch, caplog):
    """summary.json (read back at the map's end, to keep the runs of an earlier call) damaged: moved aside to
    summary.json.damaged-<n> with a warning naming both paths, before the map's first work (its model); a damaged
    continuation branch too. At the end, a summary damaged after all is moved aside, not a parser's error."""
    out = tmp_path / "map"
    out.mkdir()
    (out / "summary.json").write_text('{"runs": {"no GNL": {"speeds": [1300.0], "nfrc": [1e-4]}}')   # cut short
    (out / "summary.json.damaged-1").write_text("an earlier one, kept")
    branch = out / "continuation" / "linear" / "continuation_0123456789abcdef.npz"
    branch.parent.mkdir(parents=True)
    branch.write_bytes(b"PK\x03\x04 cut short")
    config = contact_map.ContactMapConfig.from_options(speeds=(1300, 1400, 2), revolutions=0.3, gnl="off", quiet=True,
                                                       out=out)
    caplog.set_level(logging.WARNING)
    summary, aside = out / "summary.json", out / "summary.json.damaged-2"

    def first_work(*args, **kwargs):
        said = "\n".join(warnings_of(caplog))
        assert f"{summary} is damaged" in said and f"moved aside to {aside}" in said, said
        assert "this run writes a new one" in said
        assert f"{branch} is damaged" in said and "its branch runs again" in said, said
        raise Work

    monkeypatch.setattr(contact_map, "reduced_model", first_work)
    with pytest.raises(Work):
        contact_map.run_contact_map(config)
    assert not summary.exists() and aside.read_text().startswith('{"runs"')
    assert (out / "summary.json.damaged-1").read_text() == "an earlier one, kept"
    assert not (out / ".lock").exists()                              # the lock let go with the run
    # damaged after the check (by hand, mid-run): the end moves it aside too, and writes its own summary
    summary.write_text("[1, 2")
    caplog.clear()
    new = {"r": 45, "speeds": [1300.0], "revolutions": 0.3, "runs": {"no GNL": {"speeds": [1300.0], "nfrc": [1.0]}}}
    contact_map.merge_earlier_runs(new, summary)
    assert new["runs"] == {"no GNL": {"speeds": [1300.0], "nfrc": [1.0]}}
    assert any(f"moved aside to {out / 'summary.json.damaged-3'}" in m for m in warnings_of(caplog))


HOLD = textwrap.dedent("""
    import fcntl, os, sys, time
    fd = os.open(sys.argv[1], os.O_RDWR | os.O_CREAT)
    fcntl.flock(fd, fcntl.LOCK_EX)
    os.write(fd, f"{os.getpid()} {os.uname().nodename}\\n".encode())
    print("held", flush=True)
    time.sleep(600)
""")


@pytest.fixture
def held(tmp_path):
    """hold(folder) -> the pid of a process holding <folder>/.lock as a run does (killed after the test)."""
    procs = []

    def hold(folder: Path) -> int:
        folder.mkdir(parents=True, exist_ok=True)
        proc = subprocess.Popen([sys.executable, "-c", HOLD, str(folder / ".lock")], stdout=subprocess.PIPE, text=True)
        procs.append(proc)
        assert proc.stdout.readline().strip() == "held"
        return proc.pid

    yield hold
    for proc in procs:
        proc.kill()
        proc.wait()


def test_a_second_run_on_a_locked_folder_is_refused_at_once(tmp_path, monkeypatch, held):
    """Another process holds the folder's lock: the sweep is refused before any work, in one line naming the folder
    and that process's pid; the map command too (exit status 2, one line, in seconds: no model built). Once the
    holder has ended (killed: the OS lets its lock go), the folder is free again."""
    calls = []
    monkeypatch.setattr(sweep_mod, "simulate", fake_simulate(calls))
    folder = sweep_folder(fake_scheme(), SPEC, tmp_path / "sweeps")
    pid = held(folder)
    with pytest.raises(ValueError) as refused:
        run_sweep(fake_scheme(), SPEEDS, SPEC, tmp_path / "sweeps", progress=False)
    message = str(refused.value)
    assert "\n" not in message and str(folder) in message and f"pid {pid}" in message, message
    assert "in use by another run" in message and calls == []
    assert not (folder / "spec.json").exists()                      # nothing written either

    out = tmp_path / "map"
    holder = held(out)
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, str(ROOT / "demos" / "contact_map.py"), "--speeds", "1300", "1400", "2",
                           "--revolutions", "0.3", "--gnl", "off", "--quiet", "--out", str(out)],
                          capture_output=True, text=True, timeout=300,
                          env=dict(os.environ, MPLBACKEND="Agg", OPENBLAS_NUM_THREADS="1"))
    wall = time.perf_counter() - t0
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and len(lines) == 1, proc.stderr[-2000:]
    assert lines[0].startswith(f"error: --out {out} is in use by another run (pid {holder}"), lines[0]
    assert sorted(p.name for p in out.iterdir()) == [".lock", "cache"]          # no model, no sweep
    assert wall < 60, wall

    os.kill(pid, 9)
    deadline = time.time() + 30
    while time.time() < deadline:
        try:
            run_sweep(fake_scheme(), SPEEDS, SPEC, tmp_path / "sweeps", progress=False)
            break
        except ValueError:
            time.sleep(0.1)
    assert calls == [SPEEDS] and not (folder / ".lock").exists()


def test_the_lock_is_reentrant_and_let_go(tmp_path):
    """Within one process a map's sweeps take their folders' locks inside the map's, and the same folder's again
    (nested); the lock file is removed when the outermost block ends, by an exception too."""
    with output_lock(tmp_path, "--out") as folder:
        assert folder == tmp_path and (tmp_path / ".lock").read_text().split()[0] == str(os.getpid())
        with output_lock(tmp_path / "sweeps" / "k", "sweep folder"), output_lock(tmp_path, "--out"):
            pass
        assert (tmp_path / ".lock").exists() and not (tmp_path / "sweeps" / "k" / ".lock").exists()
    assert not (tmp_path / ".lock").exists()
    with pytest.raises(Work), output_lock(tmp_path):
        raise Work
    assert not (tmp_path / ".lock").exists()


MPI_SWEEP = textwrap.dedent("""
    import sys
    from pathlib import Path
    from mpi4py import MPI
    from test_output_folder import SPEC, fake_scheme, fake_simulate
    from rotor37_rom.studies import sweep as sweep_mod
    calls = []
    sweep_mod.simulate = fake_simulate(calls)
    comm = MPI.COMM_WORLD
    try:
        folder = sweep_mod.run_sweep(fake_scheme(), [1300.0, 1400.0, 1500.0], SPEC, Path(sys.argv[1]), comm=comm,
                                     progress=False)
        said = f"rank {comm.rank} done {len(sweep_mod.load_sweep(folder))}"
    except ValueError as exc:
        said = f"rank {comm.rank} refused: {exc}"
    Path(sys.argv[1]).mkdir(parents=True, exist_ok=True)
    (Path(sys.argv[1]) / f"rank{comm.rank}.txt").write_text(said)
""")


@pytest.mark.mpi
def test_mpi_ranks_take_the_lock_on_rank_0(tmp_path, held):
    """Under mpirun -n 2 rank 0 alone takes the lock: a free folder is swept by both ranks (no deadlock); a held one
    is refused on every rank at once, naming the holder (no rank left waiting)."""
    script = tmp_path / "mpi_sweep.py"
    script.write_text(MPI_SWEEP)
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1", OPENBLAS_NUM_THREADS="1",
               PYTHONPATH=os.pathsep.join([str(ROOT), str(ROOT / "tests"), str(Path(__file__).resolve().parent)]),
               MPLBACKEND="Agg")

    def mpirun(out):
        proc = subprocess.run(["mpirun", "-n", "2", sys.executable, str(script), str(out)],
                              capture_output=True, text=True, env=env, timeout=120)
        assert proc.returncode == 0, proc.stderr[-2000:]
        return [(out / f"rank{r}.txt").read_text() for r in range(2)]

    assert mpirun(tmp_path / "free") == ["rank 0 done 3", "rank 1 done 3"]
    pid = held(sweep_folder(fake_scheme(), SPEC, tmp_path / "locked"))
    said = mpirun(tmp_path / "locked")
    assert [line.split(":")[0] for line in said] == ["rank 0 refused", "rank 1 refused"], said
    assert all(f"pid {pid}" in line for line in said), said
