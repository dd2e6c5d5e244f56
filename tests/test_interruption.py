"""SIGTERM and SIGINT end a long run cleanly (#70): the running loop writes its checkpoint at the step the signal
arrives, the command says in one line how to resume (exit status 128 + the signal), and the resumed run equals the
uninterrupted one bit for bit."""
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from rotor37_rom.dynamics.casing import Casing
from rotor37_rom.dynamics.explicit import CentralDifference, simulate
from rotor37_rom.interruption import Interrupted, stop_cleanly

ROOT = Path(__file__).resolve().parents[1]


def test_a_signal_stops_the_loop_at_a_saved_step(ci_rom):
    """In-process: SIGTERM arrives during the steps (sent from the progress callback); the loop saves its state at
    the next step boundary and raises Interrupted(saved=True); resumed from that state, the run is bit-identical to
    one never stopped. Outside a checkpointed loop the signal stops at once (saved=False)."""
    scheme = CentralDifference(ci_rom, nonlinear=True, safety=0.9)
    speeds, casing = [1400.0, 1500.0], Casing(mu=0.15)
    whole = simulate(scheme, speeds, casing, revolutions=0.3)
    saved, calls = [], []

    def progress(k):
        calls.append(k)
        if len(calls) == 3:
            os.kill(os.getpid(), signal.SIGTERM)

    with stop_cleanly(), pytest.raises(Interrupted) as stop:
        simulate(scheme, speeds, casing, revolutions=0.3, progress=progress, checkpoint=saved.append,
                 checkpoint_seconds=1e9)
    assert stop.value.saved and stop.value.name == "SIGTERM" and len(saved) == 1
    state = saved[0]
    assert 0 < state.n < whole.n_steps.max()
    resumed = simulate(scheme, speeds, casing, revolutions=0.3, state=state)
    for p in range(2):
        np.testing.assert_array_equal(resumed.u_r[p], whole.u_r[p])
        np.testing.assert_array_equal(resumed.lam[p], whole.lam[p])
    np.testing.assert_array_equal(resumed.q_final, whole.q_final)
    with stop_cleanly(), pytest.raises(Interrupted) as stop:       # no checkpointed loop: at once, nothing saved
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(1)
    assert not stop.value.saved and stop.value.name == "SIGINT"
    assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL or callable(signal.getsignal(signal.SIGTERM))


@pytest.mark.slow
def test_sigterm_mid_map_resumes_bit_for_bit(ci_rom, tmp_path):
    """The map command, stopped by SIGTERM while its batch integrates: exit status 143, one line saying the
    checkpoints are written and how to resume, a batch checkpoint on disk; the same command again finishes the map,
    equal bit for bit to the map never stopped."""
    from rotor37_rom.model.reduced import save_reduced_model
    from rotor37_rom.studies.sweep import load_sweep

    model = save_reduced_model(ci_rom, tmp_path / "rom.npz")
    env = dict(os.environ, MPLBACKEND="Agg", OPENBLAS_NUM_THREADS="1")

    def command(out):
        return [sys.executable, str(ROOT / "demos" / "contact_map.py"), "--model", str(model), "--speeds", "1400",
                "1450", "2", "--revolutions", "10", "--gnl", "off", "--mu", "0.15", "--quiet", "--out", str(out)]

    stopped = subprocess.Popen(command(tmp_path / "a"), env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True)
    deadline = time.time() + 300
    while not list((tmp_path / "a" / "sweeps").glob("*/spec.json")) and time.time() < deadline:
        time.sleep(0.2)
    time.sleep(1)                                              # inside the batch's steps
    stopped.send_signal(signal.SIGTERM)
    _, err = stopped.communicate(timeout=300)
    assert stopped.returncode == 128 + signal.SIGTERM, err
    assert err.strip().splitlines()[-1] == ("stopped by SIGTERM: the checkpoints are written; run the same command "
                                            "again to resume")
    folder = next((tmp_path / "a" / "sweeps").iterdir())
    (ckpt,) = folder.glob("batch_*.ckpt.npz")
    assert not list(folder.glob("omega_*.npz"))
    with np.load(ckpt) as data:
        first_sitting = float(data["elapsed"])                 # the batch's wall up to the stop
    assert first_sitting > 0
    again = subprocess.run(command(tmp_path / "a"), env=env, capture_output=True, text=True, timeout=600)
    assert again.returncode == 0, again.stderr[-2000:]
    # the resumed map reports the time over both sittings: its batch's wall carries the first sitting's on
    summary = json.loads((tmp_path / "a" / "summary.json").read_text())["runs"]["no GNL"]
    walls = [float(r["batch_wall_s"]) for r in load_sweep(folder)]
    assert min(walls) > first_sitting and summary["compute_s"] == max(walls)
    assert summary["rev_per_s"] == 10 * 2 / summary["compute_s"]
    whole = subprocess.run(command(tmp_path / "b"), env=env, capture_output=True, text=True, timeout=600)
    assert whole.returncode == 0, whole.stderr[-2000:]
    ref = load_sweep(next((tmp_path / "b" / "sweeps").iterdir()))
    got = load_sweep(folder)
    assert [float(r["omega"]) for r in got] == [1400.0, 1450.0]
    for a, b in zip(got, ref):
        for key in ("u_r", "lam", "q_final", "q_prev", "work"):
            np.testing.assert_array_equal(a[key], b[key], err_msg=key)
