"""Speed sweeps: a killed sweep resumes from its checkpoint with nothing lost; MPI ranks give the serial map;
interaction-map spectra and the steady-state test recover known signals."""
import dataclasses
import json
import os
import re
import subprocess
import sys
import types
from pathlib import Path

import numpy as np
import pytest

from conftest import Killed, killed_after
from rotor37_rom.studies import sweep as sweep_mod
from rotor37_rom.dynamics.casing import Casing
from rotor37_rom.dynamics.explicit import CentralDifference
from rotor37_rom.model.reduced import load_reduced_model, save_reduced_model
from rotor37_rom.post import signals
from rotor37_rom.post.signals import is_steady, response_period
from rotor37_rom.studies.sweep import SweepSpec, interaction_map, load_sweep, rerun_diverged, run_sweep, sweep_folder

ROOT = Path(__file__).resolve().parents[2]
SPEEDS = np.array([1300.0, 1600.0])
# spectral mass scaling at 60 kHz (12x the unscaled step): for the continuation's bookkeeping, which does not depend on
# the modes above the cap (bench_contact_convergence: the capped response within 3 % of the unscaled)
CAP = 2 * np.pi * 60e3


def test_killed_sweep_resumes(ci_rom, tmp_path, monkeypatch, capsys):
    scheme = CentralDifference(ci_rom, nonlinear=False, safety=0.9)
    spec = SweepSpec(revolutions=0.25, casing=Casing(), record_dt=2e-6)
    steps = np.ceil(0.25 * 2 * np.pi / SPEEDS / scheme.h).astype(int)     # 1600 rad/s finishes first
    kill_at = (steps.min() + steps.max()) // 2
    real = sweep_mod.simulate
    monkeypatch.setattr(sweep_mod, "simulate", killed_after(real, kill_at))
    with pytest.raises(Killed):
        run_sweep(scheme, SPEEDS, spec, tmp_path / "a", progress=False, checkpoint_seconds=0.0)
    folder = next((tmp_path / "a").iterdir())
    assert [float(r["omega"]) for r in load_sweep(folder)] == [1600.0]      # the finished speed was kept
    assert len(list(folder.glob("batch_*.ckpt.npz"))) == 1
    resumed_from = []

    def spy(*args, state=None, **kwargs):
        resumed_from.append(None if state is None else state.n)
        return real(*args, state=state, **kwargs)

    monkeypatch.setattr(sweep_mod, "simulate", spy)
    capsys.readouterr()
    run_sweep(scheme, SPEEDS, spec, tmp_path / "a", progress=True)
    assert resumed_from == [kill_at]                                          # one batch, resumed where it died
    # the progress bar starts where the batch stopped: the finished speed whole, the other at its step
    done = 100 * (steps.min() + kill_at) / steps.sum()
    first = re.search(r"sweep \(2 speeds, 2 resumed\):\s+(\d+)%", capsys.readouterr().err)
    assert first is not None and abs(int(first.group(1)) - done) <= 0.5, (first, done)    # tqdm rounds to 1 %
    assert not list(folder.glob("batch_*.ckpt.npz"))
    monkeypatch.setattr(sweep_mod, "simulate", real)
    ref_folder = run_sweep(scheme, SPEEDS, spec, tmp_path / "b", progress=False)
    for got, ref in zip(load_sweep(folder), load_sweep(ref_folder)):
        assert got["omega"] == ref["omega"]
        np.testing.assert_array_equal(got["u_r"], ref["u_r"])                # bit for bit: same operations
        np.testing.assert_array_equal(got["lam"], ref["lam"])
    # a corrupted result file is recomputed, not trusted
    bad = sorted(folder.glob("omega_*.npz"))[0]
    bad.write_bytes(b"garbage")
    run_sweep(scheme, SPEEDS, spec, tmp_path / "a", progress=False)
    assert len(load_sweep(folder)) == 2


def test_a_lost_speed_is_computed_again_in_its_batch(ci_rom, tmp_path):
    """A speed file lost and the map run again (#70): the speed is computed again with the batch it was first run in
    (the folder's batches.json), so the map is bit-identical to the uninterrupted one; alone, the same speed differs
    in its last bits (batched BLAS rounds a column by its batch: checked here too, so that the test would see a
    speed recomputed alone)."""
    scheme = CentralDifference(ci_rom, nonlinear=False, safety=0.9)
    spec = SweepSpec(revolutions=0.5, casing=Casing(mu=0.15), record_dt=1e-5, batch_size=2)
    speeds = [1300.0, 1400.0, 1500.0]
    folder = run_sweep(scheme, speeds, spec, tmp_path / "map", progress=False)
    layout = json.loads((folder / "batches.json").read_text())["batches"]
    assert layout == [[1300.0, 1400.0], [1500.0]]
    original = {float(r["omega"]): {k: np.array(r[k]) for k in ("u_r", "lam", "q_final")} for r in load_sweep(folder)}
    (folder / "omega_0001400.0000.npz").unlink()
    before = (folder / "omega_0001300.0000.npz").stat().st_mtime_ns
    assert run_sweep(scheme, speeds, spec, tmp_path / "map", progress=False) == folder
    assert (folder / "omega_0001300.0000.npz").stat().st_mtime_ns == before      # its batch-mate is not rewritten
    again = {float(r["omega"]): r for r in load_sweep(folder)}
    for w, arrays in original.items():
        for k, v in arrays.items():
            np.testing.assert_array_equal(again[w][k], v, err_msg=f"{w} {k}")
    assert json.loads((folder / "batches.json").read_text())["batches"] == layout
    alone = load_sweep(run_sweep(scheme, [1400.0], spec, tmp_path / "alone", progress=False))[0]
    assert not np.array_equal(alone["q_final"], original[1400.0]["q_final"])
    np.testing.assert_allclose(alone["u_r"], original[1400.0]["u_r"], rtol=0, atol=1e-8)   # the batch tolerance (m)


def test_killed_training_runs_resume(ci_rom, tmp_path, monkeypatch):
    """The cubature's exact GNL training runs (an hour on r = 104) checkpoint their loop state with the recorded full
    states: killed after one speed has ended, before the other has, they resume at the killed step and give the
    uninterrupted runs' training and step states bit for bit. A checkpoint of other speeds or of another step is not
    resumed; a run that records its states refuses a state saved without them."""
    from rotor37_rom.dynamics import explicit as integrator

    scheme = CentralDifference(ci_rom, nonlinear=True, safety=0.25, frequency_cap=CAP)     # capped: 20x the step
    casing = Casing(c0=2e-4)                                       # in contact within the quarter revolution
    steps = np.ceil(0.25 * 2 * np.pi / SPEEDS / scheme.h).astype(int)
    kill_at = (steps.min() + steps.max()) // 2
    ckpt = tmp_path / "runs.ckpt.npz"
    real = integrator.simulate

    def killed_simulate(*args, checkpoint=None, **kwargs):
        def save_then_die(st):
            if st.n >= kill_at:
                checkpoint(st)
                raise Killed

        return real(*args, checkpoint=save_then_die, **{**kwargs, "checkpoint_seconds": 0.0})

    resumed_from = []

    def spy(*args, state=None, **kwargs):
        resumed_from.append(None if state is None else state.n)
        return real(*args, state=state, **kwargs)

    def run(resumer, speeds):
        """Kill the runs at SPEEDS with ``scheme``, then run ``speeds`` with ``resumer`` on that checkpoint."""
        monkeypatch.setattr(integrator, "simulate", killed_simulate)
        ckpt.unlink(missing_ok=True)
        with pytest.raises(Killed):
            integrator.contact_training_states(scheme, SPEEDS, casing, 0.25, checkpoint=ckpt)
        monkeypatch.setattr(integrator, "simulate", spy)
        return integrator.contact_training_states(resumer, speeds, casing, 0.25, checkpoint=ckpt)

    train, step = run(scheme, SPEEDS)
    assert resumed_from == [kill_at]
    monkeypatch.setattr(integrator, "simulate", real)
    ref_train, ref_step = integrator.contact_training_states(scheme, SPEEDS, casing, 0.25)
    np.testing.assert_array_equal(train, ref_train)
    np.testing.assert_array_equal(step, ref_step)
    assert (real(scheme, SPEEDS, casing, revolutions=0.25).min_multiplier < np.inf).all()   # both touched
    with np.load(ckpt) as data:                                   # the killed step's state ...
        state = integrator.loop_state(data, SPEEDS.size)
    state.q_rec = None                                             # ... as a sweep saves it: no full states
    with pytest.raises(ValueError, match="record_q=True cannot resume"):
        real(scheme, SPEEDS, casing, revolutions=0.25, record_q=True, state=state)
    run(scheme, SPEEDS[:1])                                       # other speeds
    other_step = CentralDifference(ci_rom, nonlinear=True, safety=0.2, frequency_cap=CAP)
    run(other_step, SPEEDS)                                       # another step
    assert resumed_from[1:] == [None, None]


def test_sweep_folder_absorbs_the_steps_round_off(ci_rom, tmp_path):
    """The explicit step comes from the highest frequency, whose last digits depend on the BLAS threads: a restart
    with a step that differs by round-off finds the runs already done; a step that differs for real does not."""
    scheme = CentralDifference(ci_rom, nonlinear=False, safety=0.9)
    spec = SweepSpec(revolutions=0.02, casing=Casing(), record_dt=2e-6)
    folder = run_sweep(scheme, [1500.0], spec, tmp_path, progress=False)
    twin = scheme.with_step(scheme.h * (1 + 2e-11))        # above the 12-digit rounding step: another key
    assert sweep_mod._key(twin, spec) != sweep_mod._key(scheme, spec)
    assert sweep_folder(twin, spec, tmp_path) == folder
    assert run_sweep(twin, [1500.0], spec, tmp_path, progress=False) == folder
    assert len(load_sweep(folder)) == 1 and len(list(tmp_path.iterdir())) == 1
    assert sweep_folder(scheme.with_step(scheme.h * (1 - 1e-6)), spec, tmp_path) != folder
    other = SweepSpec(revolutions=0.03, casing=Casing(), record_dt=2e-6)
    assert sweep_folder(scheme, other, tmp_path) != folder


@pytest.mark.slow
@pytest.mark.mpi
def test_mpi_sweep_equals_serial(ci_rom, tmp_path):
    """The demo under mpirun -n 2 gives the serial map, and its continuation branches (up on rank 0, down on rank 1,
    gathered on rank 0) equal serial ones."""
    from rotor37_rom.studies.contact_map import ContactMapConfig
    from rotor37_rom.studies.sweep import continuation

    model_path = save_reduced_model(ci_rom, tmp_path / "rom.npz")
    speeds = np.linspace(1300.0, 1600.0, 4)
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1", MPLBACKEND="Agg")
    # capped at 60 kHz (12x the unscaled step): the split of the speeds and branches is what is checked
    cmd = ["mpirun", "-n", "2", sys.executable, str(ROOT / "demos" / "contact_map.py"), "--model", str(model_path),
           "--speeds", "1300", "1600", "4", "--revolutions", "0.3", "--gnl", "off", "--safety", "0.9",
           "--frequency-cap", "60", "--out", str(tmp_path / "mpi"), "--quiet", "--continuation", "150",
           "--continuation-range", "1300", "1450"]
    run = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-2000:]
    cap = ContactMapConfig.from_options(frequency_cap=60.0).scheme.frequency_cap_rad_s     # the command's, bit for bit
    scheme = CentralDifference(ci_rom, nonlinear=False, safety=0.9, frequency_cap=cap)
    serial = run_sweep(scheme, speeds, SweepSpec(revolutions=0.3, casing=Casing()), tmp_path / "serial",
                       progress=False)
    mpi_folder = tmp_path / "mpi" / "sweeps" / serial.name
    assert mpi_folder.is_dir(), "the MPI run used another key than the serial one"
    got, ref = load_sweep(mpi_folder), load_sweep(serial)
    assert len(got) == len(ref) == 4
    for a, b in zip(got, ref):
        assert float(a["omega"]) == float(b["omega"])
        scale = np.abs(b["u_r"]).max()
        assert np.abs(a["u_r"] - b["u_r"]).max() <= 1e-8 * scale
    ma, mb = interaction_map(got), interaction_map(ref)
    np.testing.assert_allclose(ma.nfrc, mb.nfrc, rtol=1e-8)
    run_mpi = json.loads((tmp_path / "mpi" / "summary.json").read_text())["runs"]["no GNL, cap 60 kHz"]
    down = continuation(scheme, 1450.0, 1300.0, 150.0, Casing(), first_revolutions=0.3, revolutions=5.0)
    got_down = np.array(run_mpi["continuation_down"], float)
    ups = [p[0] for p in run_mpi["continuation_up"]]
    assert ups[0] == 1300.0 and max(ups) <= 1450.0 and got_down.shape == (len(down), 5)
    np.testing.assert_allclose(got_down, np.array([dataclasses.astuple(p) for p in down], float), rtol=1e-8,
                               equal_nan=True)


@pytest.mark.slow
@pytest.mark.mpi
def test_mpi_map_without_a_model_builds_it_on_rank_0(tmp_path):
    """Under mpirun -n 2 without --model (the README's commands) rank 0 builds the reduced model on its own copy of
    the mesh and saves it, rank 1 waits and loads it, and the ranks split the speeds: every speed is in the summary
    and the saved model is the one the options ask for (r = 24 tip DOFs + r_c)."""
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1", MPLBACKEND="Agg", OPENBLAS_NUM_THREADS="1")
    cmd = ["mpirun", "-n", "2", sys.executable, str(ROOT / "demos" / "contact_map.py"), "--r-c", "4", "--global-md",
           "0", "--speeds", "1300", "1400", "2", "--revolutions", "0.2", "--gnl", "off", "--out", str(tmp_path),
           "--quiet"]
    run = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=900)
    assert run.returncode == 0, run.stderr[-2000:]
    model = load_reduced_model(tmp_path / "rom.npz")
    assert model.r == 28 and model.sizes["r_c"] == 4
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["runs"]["no GNL"]["speeds"] == [1300.0, 1400.0]
    assert len(list((tmp_path / "sweeps").glob("*/omega_*.npz"))) == 2


def test_interaction_map_spectrum_and_steady_state():
    """A sampled 2-tone signal: the map recovers both amplitudes (interpolated spectrum at the tones) of the node it
    is asked for (by label), from the second half of the run only (a transient in the first half changes nothing),
    and the steady-state test accepts a periodic signal but not a growing one; ``response_period`` gives each
    signal's period in half revolutions."""
    omega = 1400.0
    t = np.arange(0, 40 * 2 * np.pi / omega, 1e-5)
    w1, w2 = 4 * omega, 9.5 * omega
    u = 2e-4 * np.sin(w1 * t) + 5e-5 * np.cos(w2 * t)
    res = {"t": t, "u_r": np.vstack([0 * u, u]), "omega": omega, "diverged_step": -1,
           "labels": np.array(["0:TE", "0:LE"])}
    imap = interaction_map([res], f_max=20000.0, n_freq=20001)
    for w, a in ((w1, 2e-4), (w2, 5e-5)):
        k = np.argmin(np.abs(imap.frequencies - w))
        assert abs(imap.amplitude[0, k] - a) < 0.1 * a          # leakage of a non-bin tone < 10 % (rectangular)
    assert imap.nfrc[0] == pytest.approx(np.abs(u[t >= t[-1] - 2 * np.pi / omega]).max())
    first_half = t < t[len(t) - len(t) // 2]                    # the spectrum's window is the second half
    transient = dict(res, u_r=np.vstack([0 * u, u + np.where(first_half, 1e-3 * np.sin(3.3 * omega * t), 0.0)]))
    np.testing.assert_array_equal(interaction_map([transient], f_max=20000.0, n_freq=20001).amplitude, imap.amplitude)
    with pytest.raises(ValueError, match="not recorded"):
        interaction_map([res], node="3:LE")
    assert is_steady(t, u, omega)
    assert not is_steady(t, u * np.exp(0.05 * t * omega / (2 * np.pi)), omega)   # +5 % per revolution
    # period 11T/2 (the paper's quasi-periodic branch; |sub| has period 11T/4): wherever the run ends, the max of one
    # revolution wanders and the max over 3 or more does not (up to the sampling of the peak, (4 omega dt)^2 / 8 =
    # 4e-4 relative)
    sub = 2e-4 * np.sin(w1 * t) + 1e-4 * np.sin(2 * omega / 11 * t)
    ends = np.linspace(20, 40, 23) * 2 * np.pi / omega
    for window, expected in ((1, False), (3, True), (6, True)):
        assert all(is_steady(t[t <= e], sub[t <= e], omega, tol=2e-3, window=window) is expected for e in ends)
    assert not is_steady(t, sub * np.exp(0.05 * t * omega / (2 * np.pi)), omega, window=6)
    with pytest.raises(ValueError, match="window must be >= 1"):
        is_steady(t, u, omega, window=0)
    # the period in half revolutions: the smallest shift m T/2 that maps the record's end onto itself (linear
    # interpolation between samples: (9.5 omega dt)^2 / 8 = 2.2e-3 relative, inside the 2 % tolerance)
    assert response_period(t, 2e-4 * np.sin(w1 * t), omega) == 1                # 4 Omega: periodic with T/2
    assert response_period(t, 2e-4 * np.sin(w1 * t) + 5e-5 * np.sin(omega * t), omega) == 2   # with T, not T/2
    assert response_period(t, u, omega) == 4                                     # 9.5 Omega: with 2T
    assert response_period(t, sub, omega) == 11                                  # 11T/2
    assert response_period(t, u + 1e-4 * np.sin(np.sqrt(2) * omega * t), omega) == 0   # not locked to the rotor
    assert response_period(t, sub, omega, max_halves=10) == 0                    # above the longest period asked
    assert response_period(t[t > t[-1] - 3 * 2 * np.pi / omega], sub[t > t[-1] - 3 * 2 * np.pi / omega],
                           omega) == -1                                         # 3 revolutions cannot show 11T/2


def test_engine_order_resonance_picks_the_1b_eo4_speeds():
    """Synthetic maps of 8 revolutions: at 1300 and 1400 rad/s the response is a 4 Omega tone (1B/EO4), at 1560 a
    larger 10 Omega tone (a higher mode's crossing) over a smaller 4 Omega one, at 1500 the run diverged. The 1B/EO4
    resonance is the largest of the EO4-dominated speeds (1400), not the largest response (1560); with order 10 it is
    1560; a map without EO4-dominated bounded speed has none (NaN)."""
    revolutions, records = 8, []
    for omega, a4, a10, diverged in ((1300.0, 2e-4, 1e-5, -1), (1400.0, 5e-4, 1e-5, -1), (1500.0, 9e-4, 0.0, 100),
                                     (1560.0, 1e-4, 8e-4, -1)):
        t = np.arange(0, revolutions * 2 * np.pi / omega, 1e-5)
        u = a4 * np.sin(4 * omega * t) + a10 * np.sin(10 * omega * t)
        records.append({"t": t, "u_r": u[None, :], "omega": omega, "diverged_step": diverged,
                        "labels": np.array(["0:LE"])})
    imap = interaction_map(records)
    assert imap.speeds[np.nanargmax(imap.nfrc)] == 1560.0
    assert sweep_mod.engine_order_resonance(imap, 4, revolutions) == 1400.0
    assert sweep_mod.engine_order_resonance(imap, 10, revolutions) == 1560.0
    assert np.isnan(sweep_mod.engine_order_resonance(interaction_map(records[3:]), 4, revolutions))
    with pytest.raises(ValueError, match="revolutions > 0"):
        sweep_mod.engine_order_resonance(imap, 4, 0)


def test_engine_order_content_splits_forced_from_sustained_power():
    """On whole revolutions of uniform samples the DFT is exact: a 4 Omega tone of amplitude a over a tone at 5.3
    Omega (not an engine order) of amplitude b puts a^2 / (a^2 + b^2) of the power on the lines, to round-off; the
    dominant frequency is the larger tone's bin. A start-up transient before the window leaves it unchanged; a
    record off the revolution grid (dt not dividing T) still finds the forced tone's share within its leakage."""
    omega, per_rev, revolutions = 1400.0, 64, 40
    T = 2 * np.pi / omega
    t = np.arange(60 * per_rev + 1) * T / per_rev
    for a, b in ((3e-4, 1e-4), (1e-4, 3e-4)):
        u = a * np.sin(4 * omega * t + 0.3) + b * np.cos(5.3 * omega * t) + 2e-5
        u[: 10 * per_rev] += 1e-3 * np.exp(-t[: 10 * per_rev] / T)          # the transient, outside the window
        dominant, share = signals.engine_order_content(t, u, omega, revolutions)
        assert share == pytest.approx(a ** 2 / (a ** 2 + b ** 2), abs=1e-10)
        assert dominant == pytest.approx(4 * omega if a > b else 5.3 * omega, rel=1e-12)
    t2 = np.arange(0.0, 60 * T, T / 61.3)
    u2 = 3e-4 * np.sin(4 * omega * t2) + 1e-4 * np.cos(5.3 * omega * t2)
    _, share2 = signals.engine_order_content(t2, u2, omega, revolutions)
    assert share2 == pytest.approx(0.9, abs=0.02)
    assert np.isnan(signals.engine_order_content(t, np.zeros_like(t), omega)[1])
    with pytest.raises(ValueError, match="revolutions asked"):
        signals.engine_order_content(t, u, omega, 80)
    with pytest.raises(ValueError, match="omega > 0"):
        signals.engine_order_content(t, u, -1.0)


def test_band_rms_splits_the_variance_by_frequency():
    """On a whole revolution of uniform samples the DFT is exact: tones at 4 Omega, 30 Omega and the Nyquist
    frequency, of amplitudes a, b, c, give RMS a / sqrt 2, b / sqrt 2 and c (the Nyquist tone is +-c) in their
    bands, 0 in an empty one, and the squares add up to the variance (round-off); a start-up transient before the
    last revolution and a mean leave it unchanged."""
    omega, per_rev = 1280.0, 512
    T = 2 * np.pi / omega
    t = np.arange(3 * per_rev) * T / per_rev
    f0 = omega / (2 * np.pi)
    a, b, c = 3e-4, 1e-4, 2e-5
    u = a * np.sin(4 * omega * t + 0.3) + b * np.cos(30 * omega * t) + c * np.cos(np.pi * np.arange(t.size)) + 1e-3
    u[:per_rev] += 5e-4 * np.exp(-t[:per_rev] / T)
    edges = [0.0, 10 * f0, 20 * f0, 100 * f0, 1e9]
    rms = signals.band_rms(t, u, omega, edges)
    np.testing.assert_allclose(rms, [a / np.sqrt(2), 0.0, b / np.sqrt(2), c], atol=1e-12 * a)
    seg = u[-per_rev:]
    assert np.sum(rms ** 2) == pytest.approx(seg.var(), rel=1e-10)
    odd = np.random.default_rng(3).standard_normal(3 * 511)               # odd n: no Nyquist bin
    t_odd = np.arange(odd.size) * T / 511
    rms_odd = signals.band_rms(t_odd, odd, omega, [0.0, 50 * f0, np.inf])
    assert np.sum(rms_odd ** 2) == pytest.approx(odd[-511:].var(), rel=1e-10)
    for bad in ([0.0, 5e3, 2e3], [0.0, np.nan, 2e3]):
        with pytest.raises(ValueError, match="increasing edges_hz"):
            signals.band_rms(t, u, omega, bad)
    with pytest.raises(ValueError, match="as many samples"):
        signals.band_rms(t, u[:-1], omega, edges)
    with pytest.raises(ValueError, match="revolutions asked"):
        signals.band_rms(t, u, omega, edges, revolutions=4)


def test_diverged_runs_are_reported_as_results(ci_rom):
    """A run that blows up is a result: on_finish receives it with its step (run_sweep saves it, so a resumed sweep
    does not redo it), and the map draws it as NaN."""
    import scipy.linalg

    ref = CentralDifference(ci_rom, nonlinear=False)
    scheme = CentralDifference(ci_rom, nonlinear=False, h=1.02 * ref.h_crit, force=True)
    _, V = scipy.linalg.eigh(ci_rom.K, ci_rom.M)
    tip = ci_rom.nodes.boundary_rows
    q0 = 1e-4 * V[:, 0] / np.abs(V[tip, 0]).max() + 1e-9 * V[:, -1]          # either sign diverges above the limit
    done = {}
    simulate_ = sweep_mod.simulate
    simulate_(scheme, [1300.0, 1600.0], None, n_steps=20_000, initial=(q0, q0), on_blowup="flag",
              on_finish=lambda p, rec: done.setdefault(p, rec))
    assert sorted(done) == [0, 1] and all(rec["diverged_step"] > 0 for rec in done.values())
    imap = interaction_map([dict(rec, omega=1300.0 + 300 * p) for p, rec in done.items()])
    assert imap.diverged.all() and np.isnan(imap.nfrc).all()


def test_continuation_carries_state_and_casing_angle(ci_rom):
    """A run split in two (final states and rotor angle handed over) equals the run in one piece; without the angle
    the casing would jump under the blade. The two differ only in how the casing angle is rounded (-omega n1 h +
    omega m h instead of omega (n1 + m) h, ~1e-16 rad), which 4000 steps with friction contact grow to 4e-12 to
    1.2e-11 of the amplitude (measured over the kernel variants of make test-kernels): 1e-9. Without the angle the
    bump sits omega n1 h = 2.3 rad away."""
    from rotor37_rom.dynamics.explicit import simulate

    scheme = CentralDifference(ci_rom, nonlinear=False, safety=0.9)
    casing, om, n1, n2 = Casing(mu=0.15), 1450.0, 6000, 4000
    whole = simulate(scheme, om, casing, n_steps=n1 + n2, duration=1e-12)
    a = simulate(scheme, om, casing, n_steps=n1, duration=1e-12)
    b = simulate(scheme, om, casing, n_steps=n2, duration=1e-12, initial=(a.q_final, a.q_prev),
                 phase=-om * n1 * scheme.h)
    assert whole.contact_steps[0] > 0
    scale = np.abs(whole.u_r[0]).max()
    assert np.abs(b.u_r[0] - whole.u_r[0][:, n1:]).max() <= 1e-9 * scale
    jumped = simulate(scheme, om, casing, n_steps=n2, duration=1e-12, initial=(a.q_final, a.q_prev))
    assert np.abs(jumped.u_r[0] - whole.u_r[0][:, n1:]).max() > 1e-3 * scale


@pytest.mark.slow
@pytest.mark.kernels
def test_batched_halvings_accept_the_one_by_one_points(ci_rom, monkeypatch):
    """The halved candidates run as one batch accept the speeds, halvings and steadiness of the paper's one-by-one
    procedure, with amplitudes equal to the batch's round-off (1e-8 relative, the batch tolerance of the
    integrator), in fewer calls. Up to the 1B/EO4 resonance (mu = 0, linear, capped at 60 kHz) with 3-revolution runs
    some steps are halved and some are not; the branch stays bounded by the clearance scale."""
    scheme = CentralDifference(ci_rom, nonlinear=False, safety=0.9, frequency_cap=CAP)
    kwargs = dict(casing=Casing(mu=0.0), first_revolutions=3.0, revolutions=3.0, max_halvings=1)
    real, calls = sweep_mod.simulate, []

    def counted(*a, **k):
        calls.append(np.atleast_1d(a[1]).size)
        return real(*a, **k)

    monkeypatch.setattr(sweep_mod, "simulate", counted)
    one = sweep_mod.continuation(scheme, 1220.0, 1380.0, 40.0, batch_halvings=False, **kwargs)
    n_one, calls[:] = len(calls), []
    batched = sweep_mod.continuation(scheme, 1220.0, 1380.0, 40.0, **kwargs)
    assert [(p.omega, p.steady, p.halvings) for p in batched] == [(p.omega, p.steady, p.halvings) for p in one]
    speeds, halved = [p.omega for p in one], [p.halvings for p in one[1:]]
    assert speeds[0] == 1220.0 and speeds[-1] == 1380.0 and np.all(np.diff(speeds) > 0)
    # the case exercises both paths: the response builds up towards the resonance over 3-revolution runs, so its
    # steadiness test fails near the resonance and passes away from it, a margin far above round-off
    assert 0 < sum(halved) < len(halved)
    assert all(np.isfinite(p.amplitude) for p in one)                          # bounded: no run blew up
    a, b = np.array([p.amplitude for p in one]), np.array([p.amplitude for p in batched])
    assert np.abs(a - b).max() <= 1e-8 * np.abs(a).max()
    assert len(calls) < n_one and max(calls) > 1


@pytest.mark.slow
def test_unsteady_points_keep_the_full_step_when_asked(ci_rom):
    """unsteady='full': a speed where neither the full nor the halved step is steady is accepted at the full step,
    marked not steady; the steady points are those of the paper's literal reading ('smallest', where the step stays
    divided), which needs more points over the same range. Linear, mu = 0, capped at 60 kHz, runs of 2 revolutions
    building up towards the 1B/EO4 resonance."""
    scheme = CentralDifference(ci_rom, nonlinear=False, safety=0.9, frequency_cap=CAP)
    kwargs = dict(casing=Casing(mu=0.0), first_revolutions=2.0, revolutions=2.0, max_halvings=1)
    full = sweep_mod.continuation(scheme, 1300.0, 1380.0, 40.0, unsteady="full", **kwargs)
    smallest = sweep_mod.continuation(scheme, 1300.0, 1380.0, 40.0, **kwargs)
    assert full[0].omega == 1300.0 and full[-1].omega == 1380.0
    for prev, p in zip(full, full[1:]):
        if not p.steady:
            assert p.halvings == 0 and p.omega - prev.omega == min(40.0, 1380.0 - prev.omega)
    assert any(not p.steady for p in full[1:])                 # the case has a stretch no halving makes steady
    assert any(not p.steady and p.halvings == 1 for p in smallest[1:]) and len(smallest) > len(full)
    with pytest.raises(ValueError, match="unsteady must be 'smallest' or 'full'"):
        sweep_mod.continuation(scheme, 1300.0, 1380.0, 40.0, unsteady="half", **kwargs)


def test_saved_record_reads_large_arrays_on_demand(tmp_path):
    """A saved record gives back every array as written (bit for bit); the large ones (here 2 MB, like a disk
    record's contact-force histories) are read only when asked for, so a map that never reads them does not hold
    them; a file that does not open as an npz is refused (None: the sweep computes that speed again)."""
    rng = np.random.default_rng(0)
    arrays = {"omega": np.float64(1400.0), "u_r": rng.standard_normal((3, 50)),
              "lam": rng.standard_normal((8, 32768)), "labels": np.array(["0:LE", "0:TE", "1:LE"])}
    path = tmp_path / "omega_0001400.0000.npz"
    np.savez(path, **arrays)
    rec = sweep_mod.load_speed(tmp_path, 1400.0)
    assert set(rec) == set(arrays) and "lam" not in rec._cache and "u_r" in rec._cache
    np.testing.assert_array_equal(rec.read("lam"), arrays["lam"])
    assert "lam" not in rec._cache                             # read, not kept
    with pytest.raises(KeyError):
        rec.read("q_final")
    for key, value in arrays.items():
        np.testing.assert_array_equal(rec[key], value)
    assert "lam" in rec._cache
    with pytest.raises(KeyError):
        rec["q_final"]
    path.write_bytes(path.read_bytes()[:1000])                 # truncated
    assert sweep_mod.load_speed(tmp_path, 1400.0) is None


def test_sector_rows_and_maxima_follow_the_sector_index():
    """A disk record's rows of one node come back in sector order whatever the recording order; the maxima over the
    last revolution are each row's; a blown-up run gives NaN; ``every`` refuses a node missing on a sector."""
    omega = 1500.0
    t = np.linspace(0.0, 3 * 2 * np.pi / omega, 601)
    amps = {2: 3.0, 0: 1.0, 1: 2.0}
    labels = [f"{k}:LE" for k in amps] + ["0:TE"]
    u_r = np.array([a * np.sin(omega * t) for a in amps.values()] + [9.0 * np.sin(omega * t)])
    record = {"labels": np.array(labels), "t": t, "u_r": u_r, "omega": omega, "diverged_step": -1}
    assert sweep_mod.sector_rows(record, "LE", every=True) == [1, 2, 0]
    np.testing.assert_allclose(sweep_mod.sector_maxima(record), [1.0, 2.0, 3.0], rtol=1e-12)   # a peak is a sample
    assert np.isnan(sweep_mod.sector_maxima(dict(record, diverged_step=10))).all()
    assert sweep_mod.sector_rows(record, "TE") == [3]
    with pytest.raises(ValueError, match="node LE must be recorded on every sector"):
        sweep_mod.sector_rows(dict(record, labels=np.array(["0:LE", "2:LE", "3:LE", "0:TE"])), "LE", every=True)


class _Calls(list):
    """The first speed of each ``studies.sweep.simulate`` call; the call numbered ``kill_at`` (from 1) raises Killed."""
    kill_at = 0


def _counted_simulate(monkeypatch) -> _Calls:
    """Wrap ``studies.sweep.simulate`` (the continuation's runs) to count its calls; returns the list they go to."""
    real, calls = sweep_mod.simulate, _Calls()

    def counted(*a, **k):
        calls.append(float(np.atleast_1d(a[1])[0]))
        if len(calls) == calls.kill_at:
            raise Killed
        return real(*a, **k)

    monkeypatch.setattr(sweep_mod, "simulate", counted)
    return calls


def test_killed_continuation_resumes_where_it_stopped(ci_rom, tmp_path, monkeypatch):
    """A continuation killed at its third run resumes from the last accepted speed (the first run is not redone) and
    gives the points of an uninterrupted branch bit for bit; a finished branch is read back without running
    anything."""
    sweep = sweep_mod
    scheme = CentralDifference(ci_rom, nonlinear=False, safety=0.9)
    kwargs = dict(casing=Casing(mu=0.0), first_revolutions=1.0, revolutions=1.0, max_halvings=1)
    calls = _counted_simulate(monkeypatch)
    whole = sweep.continuation(scheme, 1200.0, 1275.0, 25.0, **kwargs)
    n_whole, calls[:] = len(calls), []
    calls.kill_at = 3
    with pytest.raises(Killed):
        sweep.continuation(scheme, 1200.0, 1275.0, 25.0, out=tmp_path, **kwargs)
    calls.kill_at, calls[:] = 0, []
    resumed = sweep.continuation(scheme, 1200.0, 1275.0, 25.0, out=tmp_path, **kwargs)
    # the first, long run is not redone; only the runs since the last accepted speed are (here at most 2)
    assert calls[0] != 1200.0 and n_whole - 2 <= len(calls) < n_whole
    assert [dataclasses.astuple(p) for p in resumed] == [dataclasses.astuple(p) for p in whole]
    calls[:] = []
    again = sweep.continuation(scheme, 1200.0, 1275.0, 25.0, out=tmp_path, **kwargs)
    assert not calls and [dataclasses.astuple(p) for p in again] == [dataclasses.astuple(p) for p in whole]


def test_continuation_extends_a_shorter_branch(ci_rom, tmp_path, monkeypatch):
    """A branch with a farther stop extends the saved one with the same start and settings from its last point (the
    first, long run is not redone): with the shorter stop on the step grid it gives the uninterrupted branch's points
    (amplitudes to round-off). A branch with another step or start, or going the other way, starts from rest; one
    that ended where a run blew up is given back as it is."""
    sweep = sweep_mod
    scheme = CentralDifference(ci_rom, nonlinear=False, safety=0.9, frequency_cap=CAP)
    kwargs = dict(casing=Casing(mu=0.0), first_revolutions=1.0, revolutions=1.0, max_halvings=1)
    calls = _counted_simulate(monkeypatch)
    whole = sweep.continuation(scheme, 1200.0, 1275.0, 25.0, **kwargs)
    short = sweep.continuation(scheme, 1200.0, 1225.0, 25.0, out=tmp_path, **kwargs)
    assert short[-1].omega == 1225.0
    calls[:] = []
    longer = sweep.continuation(scheme, 1200.0, 1275.0, 25.0, out=tmp_path, **kwargs)
    assert calls and 1200.0 not in calls and min(calls) > 1225.0           # only the runs past the shorter stop
    # the same speeds, steadiness and periods; amplitudes to round-off (the shorter branch ran its last halved
    # candidates as a smaller batch, the uninterrupted one as a larger: another BLAS summation order)
    assert [(p.omega, p.steady, p.halvings, p.period) for p in longer] == \
        [(p.omega, p.steady, p.halvings, p.period) for p in whole]
    np.testing.assert_allclose([p.amplitude for p in longer], [p.amplitude for p in whole], rtol=1e-9)
    assert len(list(tmp_path.glob("continuation_*.npz"))) == 2              # the shorter branch is left as it was
    for start, stop, step in [(1200.0, 1300.0, 50.0), (1210.0, 1300.0, 25.0), (1275.0, 1200.0, 25.0)]:
        calls[:] = []
        sweep.continuation(scheme, start, stop, step, out=tmp_path, **kwargs)
        assert calls[0] == start                                            # from rest: nothing to extend
    # a branch that ended where its run blew up (1.05 h_crit, as in test_blown_up_speeds_run_again_with_half_the_step)
    # ends there however far it is asked to go
    fast = CentralDifference(ci_rom, nonlinear=False, h=1.05 * scheme.h_crit, force=True)
    ended = sweep.continuation(fast, 1200.0, 1225.0, 25.0, out=tmp_path, **{**kwargs, "first_revolutions": 0.3})
    assert len(ended) == 1 and np.isnan(ended[0].amplitude)
    calls[:] = []
    farther = sweep.continuation(fast, 1200.0, 1275.0, 25.0, out=tmp_path, **{**kwargs, "first_revolutions": 0.3})
    assert not calls and repr(farther) == repr(ended)                      # (NaN != NaN: compared as text)


def test_contact_map_frequency_cap_flag(ci_rom, tmp_path):
    """demos/contact_map.py --frequency-cap: the sweep runs with h = safety x 2/cap (its own key: capped and unscaled
    results never mix) and the NFRC equals an in-process capped sweep; a cap <= 0 is a one-line error."""
    model_path = save_reduced_model(ci_rom, tmp_path / "rom.npz")
    env = dict(os.environ, MPLBACKEND="Agg")
    base = [sys.executable, str(ROOT / "demos" / "contact_map.py"), "--model", str(model_path), "--quiet",
            "--out", str(tmp_path / "cap")]
    run = subprocess.run(base + ["--speeds", "1400", "1450", "2", "--revolutions", "2", "--gnl", "off",
                                 "--frequency-cap", "60"], env=env, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-2000:]
    summary = json.loads((tmp_path / "cap" / "summary.json").read_text())
    got = summary["runs"]["no GNL, cap 60 kHz"]
    cap = 2 * np.pi * 60e3
    assert got["h"] == pytest.approx(0.5 * 2 / cap, rel=1e-9) and got["frequency_cap_khz"] == 60
    scheme = CentralDifference(ci_rom, nonlinear=False, safety=0.5, frequency_cap=cap)
    folder = run_sweep(scheme, [1400.0, 1450.0], SweepSpec(revolutions=2, casing=Casing()), tmp_path / "inproc",
                       progress=False)
    np.testing.assert_allclose(got["nfrc"], interaction_map(load_sweep(folder)).nfrc, rtol=1e-10)
    # the contact works of each speed and the sprag-slip onsets of the model's tip (rotor37_rom.dynamics.friction)
    works = [r["work"][:2] for r in load_sweep(folder)]
    np.testing.assert_allclose(np.column_stack([got["work_normal_J"], got["work_friction_J"]]), works, rtol=1e-10)
    assert 0.15 < summary["sprag_slip"]["weakest_node"] < 0.18 and summary["sprag_slip"]["per_node"][7] is None
    uncapped = run_sweep(CentralDifference(ci_rom, nonlinear=False, safety=0.5), [1400.0],
                         SweepSpec(revolutions=0.1, casing=Casing()), tmp_path / "inproc", progress=False)
    assert uncapped.name != folder.name
    bad = subprocess.run(base + ["--frequency-cap", "-1"], env=env, capture_output=True, text=True, timeout=600)
    assert bad.returncode == 2
    assert bad.stderr.strip().splitlines() == ["error: --frequency-cap must be in (0, 10000] kHz, got -1.0"]


@pytest.mark.slow
@pytest.mark.mpi
def test_contact_map_cubature_flag(ci_rom, tmp_path):
    """demos/contact_map.py --cubature: the GNL sweep runs on point cubature trained on exact GNL runs at the sweep's
    speeds (recorded in the summary); its NFRC follows the exact GNL sweep (over half a revolution the contact
    dynamics amplify the ~1e-3 force error about tenfold, test_contact); a tolerance outside (0, 1) is a one-line
    error."""
    model_path = save_reduced_model(ci_rom, tmp_path / "rom.npz")
    env = dict(os.environ, MPLBACKEND="Agg")
    base = [sys.executable, str(ROOT / "demos" / "contact_map.py"), "--model", str(model_path), "--quiet",
            "--out", str(tmp_path / "cub")]
    run = subprocess.run(base + ["--speeds", "1400", "1450", "2", "--revolutions", "0.5", "--gnl", "on", "--mu", "0",
                                 "--cubature", "1e-3"], env=env, capture_output=True, text=True, timeout=900)
    assert run.returncode == 0, run.stderr[-2000:]
    got = json.loads((tmp_path / "cub" / "summary.json").read_text())["runs"]["GNL, cubature 0.001"]
    assert got["cubature"]["level"] == "point" and 0 < got["cubature"]["points"] < 1000
    scheme = CentralDifference(ci_rom, nonlinear=True, safety=0.5)
    folder = run_sweep(scheme, [1400.0, 1450.0], SweepSpec(revolutions=0.5, casing=Casing(mu=0.0)),
                       tmp_path / "exact", progress=False)
    exact = interaction_map(load_sweep(folder)).nfrc
    dev = np.abs(np.asarray(got["nfrc"]) - exact) / exact.max()
    print(f"cubature {got['cubature']['points']} points: NFRC {got['nfrc']} vs exact {exact.tolist()}")
    assert dev.max() <= 0.05 and dev.max() > 1e-10       # close, and not the exact tensors
    # again in float32: the trained cubature is reused (no retraining), the sweep is new (its model key differs), and
    # float32 rounding (~1e-6 of the force, amplified ~10x by the contacts) stays far below the cubature's own error
    again = subprocess.run(base + ["--speeds", "1400", "1450", "2", "--revolutions", "0.5", "--gnl", "on", "--mu", "0",
                                   "--cubature", "1e-3", "--precision", "single"], env=env, capture_output=True,
                           text=True, timeout=900)
    assert again.returncode == 0 and "cubature: reusing" in again.stdout, again.stderr[-2000:]
    single = json.loads((tmp_path / "cub" / "summary.json").read_text())["runs"]["GNL, cubature 0.001, single"]
    assert single["force_precision"] == "single" and single["cubature"] == got["cubature"]
    dev_single = np.abs(np.asarray(single["nfrc"]) - got["nfrc"]) / exact.max()
    print(f"float32 cubature: NFRC {single['nfrc']}, {dev_single.max():.1e} of the peak from float64")
    assert dev_single.max() <= 1e-4 and dev_single.max() <= 0.1 * dev.max()
    # under MPI the two ranks split the speeds, on the serial run's cubature (its cache shared): the serial map to
    # the batching round-off (1e-8 over 1e4 steps, amplified ~10x by the contacts)
    mpi_env = dict(env, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
                   OMPI_MCA_rmaps_base_oversubscribe="1", OPENBLAS_NUM_THREADS="1")
    mpi = subprocess.run(["mpirun", "-n", "2"] + base[:-1] + [str(tmp_path / "cub_mpi"), "--speeds", "1400", "1450",
                                                              "2", "--revolutions", "0.5", "--gnl", "on", "--mu", "0",
                                                              "--cubature", "1e-3", "--cache",
                                                              str(tmp_path / "cub" / "cache")],
                         env=mpi_env, capture_output=True, text=True, timeout=900)
    assert mpi.returncode == 0, mpi.stderr[-2000:]
    got_mpi = json.loads((tmp_path / "cub_mpi" / "summary.json").read_text())["runs"]["GNL, cubature 0.001"]
    assert got_mpi["cubature"]["points"] == got["cubature"]["points"]
    np.testing.assert_allclose(got_mpi["nfrc"], got["nfrc"], rtol=1e-6)
    # refused before any work, in the words the command line prints (its one line: test_fuzz_entry_points)
    from rotor37_rom.studies.contact_map import ContactMapConfig

    for options, message in ((dict(cubature=0.0), "--cubature must be in (0, 1), got 0.0"),
                             (dict(continuation=5.0, continuation_range=[1450.0, 1400.0]),
                              "--continuation-range: need 0 < LOW < HIGH <= 100000 rad/s, got [1450.0, 1400.0]"),
                             (dict(continuation=5.0, steady_window=3),
                              "--steady-window must be in 1..2 revolutions (half of a continued run), got 3"),
                             (dict(precision="single"),
                              "--precision single needs --cubature (the exact cubic tensors are evaluated in double)")):
        with pytest.raises(ValueError) as e:
            ContactMapConfig.from_options(model=model_path, **options)
        assert str(e.value) == message


@pytest.mark.slow
def test_capped_training_trains_on_the_capped_probe_step(ci_rom, tmp_path):
    """--capped-training (for bases whose unscaled GNL step makes the exact training runs hours long): the blade's
    GNL step comes from a capped probe, as a disk's, and the cubature is trained on exact GNL runs at the cap and at
    the tangent limit on that probe's states - the training states equal those of that capped run redone here, to
    round-off (the same scheme, the same speeds, the same records) - and every step is within the capped linear one.
    Without the option the blade's training runs unscaled and no capped probe is made."""
    from rotor37_rom.dynamics.explicit import contact_training_states
    from rotor37_rom.studies import contact_map

    model_path = save_reduced_model(ci_rom, tmp_path / "rom.npz")
    config = contact_map.ContactMapConfig.from_options(model=model_path, speeds=(1400, 1450, 2), revolutions=0.5,
                                                       gnl="on", mu=0.0, frequency_cap=120.0, cubature=1e-3,
                                                       capped_training=True, quiet=True, out=tmp_path / "capped")
    run = contact_map.run_contact_map(config).runs["GNL, cubature 0.001, cap 120 kHz"]
    cache = tmp_path / "capped" / "cache"
    (probe,) = cache.glob("gnl_probe_*.npz")
    (runs,) = cache.glob("training_runs_*.npz")
    with np.load(probe) as data:
        h_probe = float(data["h"])
    with np.load(runs) as data:
        trained = data["train"]
    h_train = contact_map.capped_gnl_step(config, ci_rom, ci_rom, None, verbose=False)   # reads the cached probe
    linear = CentralDifference(ci_rom, nonlinear=False, safety=0.5, frequency_cap=config.scheme.frequency_cap_rad_s)
    assert max(h_probe, h_train, run.h) <= linear.h
    scheme = CentralDifference(ci_rom, nonlinear=True, safety=0.5, frequency_cap=config.scheme.frequency_cap_rad_s,
                               h=h_train)
    again, _ = contact_training_states(scheme, config.speed_grid, config.sweep.casing, 0.5)
    assert trained.shape == again.shape
    np.testing.assert_allclose(trained, again, rtol=0, atol=1e-9 * np.abs(again).max())
    assert not run.diverged.any() and (run.imap.nfrc > 1e-5).all()     # in contact (the clearance is 0.5 mm)
    points = json.loads((tmp_path / "capped" / "summary.json").read_text())["runs"][run.label]["cubature"]["points"]
    assert 0 < points < 1000
    # without the option the blade's GNL runs are not capped: no capped probe (a disk's always are)
    assert contact_map.capped_probe(config, ci_rom)
    assert not contact_map.capped_probe(config.with_options(capped_training=False), ci_rom)


@pytest.mark.mpi
def test_blown_up_speeds_run_again_with_half_the_step(ci_rom, tmp_path):
    """rerun_diverged: at 1.05 h_crit (forced) the unstable mode grows ~1.9x per step once the casing excites it, so
    both speeds blow up; halving the step (0.525 h_crit) makes them stable, and they then equal a plain sweep at that
    step. Speeds that did not blow up are left alone; the retries are sweeps of their own (a second call recomputes
    nothing)."""
    spec = SweepSpec(revolutions=0.3, casing=Casing(mu=0.0))
    ref = CentralDifference(ci_rom, nonlinear=False, safety=0.5)
    fast = CentralDifference(ci_rom, nonlinear=False, h=1.05 * ref.h_crit, force=True)
    results = load_sweep(run_sweep(fast, SPEEDS, spec, tmp_path / "sweeps", progress=False))
    assert all(int(r["diverged_step"]) >= 0 for r in results)
    fixed, retried = rerun_diverged(fast, results, spec, tmp_path / "sweeps", retries=2, progress=False)
    assert retried == {w: fast.h / 2 for w in SPEEDS.tolist()}                  # one retry was enough
    assert all(int(r["diverged_step"]) < 0 for r in fixed)
    plain = load_sweep(run_sweep(CentralDifference(ci_rom, nonlinear=False, h=fast.h / 2), SPEEDS, spec,
                                 tmp_path / "plain", progress=False))
    for a, b in zip(fixed, plain):
        assert float(a["omega"]) == float(b["omega"]) and np.array_equal(a["u_r"], b["u_r"])
    again, retried_again = rerun_diverged(fast, fixed, spec, tmp_path / "sweeps", retries=2, progress=False)
    assert retried_again == {} and all(a is b for a, b in zip(again, fixed))
    with pytest.raises(ValueError, match="retries"):
        rerun_diverged(fast, results, spec, tmp_path / "sweeps", retries=-1)
    # under mpirun -n 2 only rank 0 holds the records: it tells rank 1 which speeds to rerun, the ranks share the
    # rerun, rank 0 gets the serial result, rank 1 its own (empty) list back
    model_path = save_reduced_model(ci_rom, tmp_path / "rom.npz")
    script = (
        "import sys, json, numpy as np\n"
        "from mpi4py import MPI\n"
        "from rotor37_rom.dynamics.casing import Casing\n"
        "from rotor37_rom.dynamics.explicit import CentralDifference\n"
        "from rotor37_rom.model.reduced import load_reduced_model\n"
        "from rotor37_rom.studies.sweep import SweepSpec, load_sweep, rerun_diverged, run_sweep\n"
        "comm, out = MPI.COMM_WORLD, sys.argv[2]\n"
        "m = load_reduced_model(sys.argv[1])\n"
        "fast = CentralDifference(m, nonlinear=False, h=1.05 * 2 / CentralDifference(m).omega_max, force=True)\n"
        "spec = SweepSpec(revolutions=0.3, casing=Casing(mu=0.0))\n"
        f"folder = run_sweep(fast, {SPEEDS.tolist()}, spec, out, comm=comm, progress=False)\n"
        "results = load_sweep(folder) if comm.rank == 0 else []\n"
        "fixed, retried = rerun_diverged(fast, results, spec, out, retries=2, comm=comm, progress=False)\n"
        "info = {'rank': comm.rank, 'n': len(fixed), 'retried': sorted(retried), 'h': fast.h}\n"
        "if comm.rank == 0:\n"
        "    np.savez(out + '/fixed.npz', *[r['u_r'] for r in fixed])\n"
        "    info['diverged'] = [int(r['diverged_step']) for r in fixed]\n"
        "open(out + f'/info_{comm.rank}.json', 'w').write(json.dumps(info))\n")   # the ranks' stdout interleaves
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1")
    run = subprocess.run(["mpirun", "-n", "2", sys.executable, "-c", script, str(model_path), str(tmp_path / "mpi")],
                         env=env, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-2000:]
    infos = [json.loads((tmp_path / "mpi" / f"info_{k}.json").read_text()) for k in range(2)]
    assert [i["n"] for i in infos] == [2, 0] and all(i["retried"] == SPEEDS.tolist() for i in infos)
    assert infos[0]["diverged"] == [-1, -1]
    with np.load(tmp_path / "mpi" / "fixed.npz") as data:
        got = [data[f"arr_{k}"] for k in range(len(fixed))]
    for a, b in zip(got, fixed):
        assert np.abs(a - b["u_r"]).max() <= 1e-8 * np.abs(b["u_r"]).max()


@pytest.mark.slow
def test_zero_initial_condition_sweep_misses_the_high_branch(ci_rom):
    """Where the zero-IC map fails (docs/choosing-a-model.md, gallery; the paper's §2.3.3): on the r = 45 ci model
    (GNL off, 60 kHz cap, mu = 0), the runs from rest at 1,460 and 1,480 rad/s settle on the low branch (measured
    0.21-0.22 mm at node LE after 40 revolutions), while the sequential continuation from the 1,440 rad/s state
    (15 revolutions per point) stays on the high branch (1.2-1.3 mm), steady. Two coexisting steady states differ
    by a factor ~6; the test asks for 2 and for the continuation's points to be steady (the 2 % criterion), so it
    fails if a zero-IC run finds the high branch or the continuation loses it."""
    from rotor37_rom.dynamics.explicit import simulate
    from rotor37_rom.post.signals import last_revolution_max
    from rotor37_rom.studies.sweep import continuation

    scheme = CentralDifference(ci_rom, nonlinear=False, safety=0.5, frequency_cap=2 * np.pi * 60e3)
    casing, speeds = Casing(mu=0.0), np.array([1460.0, 1480.0])
    rest = simulate(scheme, speeds, casing, revolutions=40, record_every=4)
    zero_ic = np.array([last_revolution_max(rest.t[p], rest.u_r[p][rest.row("0:LE")], w)
                        for p, w in enumerate(speeds)])
    points = continuation(scheme, 1440.0, 1480.0, 20.0, casing, first_revolutions=40, revolutions=15,
                          max_halvings=1)
    continued = {p.omega: p for p in points}
    print("zero IC (mm):", zero_ic * 1e3, "continued:", [(p.omega, p.amplitude * 1e3, p.steady) for p in points])
    for w, low in zip(speeds, zero_ic):
        assert continued[w].steady and continued[w].amplitude > 2 * low


@pytest.mark.mpi
def test_idle_barrier_waits_asleep(tmp_path):
    """sweep.idle_barrier (run_sweep's barriers, the retries' and the continuation's hand-over): the rank that is done
    first waits without holding its core. Under mpirun -n 2 rank 1 arrives 2 s after rank 0; rank 0 waits the 2 s
    and spends < 0.5 s of CPU on it (polling every 50 ms: ~40 wake-ups), where OpenMPI's blocking barrier, the
    control, spins the core for most of the 2 s (> 1 s of CPU; checked when the machine is otherwise idle)."""
    script = tmp_path / "wait.py"
    script.write_text(
        "import sys, time\n"
        "from mpi4py import MPI\n"
        "from rotor37_rom.studies.sweep import idle_barrier\n"
        "comm = MPI.COMM_WORLD\n"
        "wait = idle_barrier if sys.argv[1] == 'idle' else (lambda c: c.Barrier())\n"
        "comm.Barrier()\n"
        "if comm.rank == 1:\n"
        "    time.sleep(2.0)\n"
        "cpu, wall = time.process_time(), time.perf_counter()\n"
        "wait(comm)\n"
        "if comm.rank == 0:\n"
        "    print(time.process_time() - cpu, time.perf_counter() - wall)\n")
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1", PYTHONPATH=str(ROOT))
    measured = {}
    for mode in ("idle", "blocking"):
        run = subprocess.run(["mpirun", "-n", "2", sys.executable, str(script), mode], env=env, capture_output=True,
                             text=True, timeout=120)
        assert run.returncode == 0, run.stderr[-2000:]
        measured[mode] = [float(x) for x in run.stdout.split()[-2:]]
    (cpu_idle, wall_idle), (cpu_blocking, wall_blocking) = measured["idle"], measured["blocking"]
    assert wall_idle >= 1.9 and wall_blocking >= 1.9
    assert cpu_idle < 0.5, measured
    if os.getloadavg()[0] < 1.0:          # the control needs the core to itself: on a busy machine a spin gets less
        assert cpu_blocking > 1.0, measured


def test_sweep_seconds_adds_each_batch_as_its_runs_end(monkeypatch):
    """``sweep_seconds``'s arithmetic against the closed form: with a step of k runs costing a + b k (what the probes
    measure, here given), a batch whose runs take s_1 >= ... >= s_P steps costs sum_k (s_k - s_(k+1)) (a + b k) =
    sum_p s_p b + s_1 a; two batches add. The probes are the only thing replaced (their wall is the given cost)."""
    a, b = 2e-4, 5e-5

    class Probe:
        def __init__(self, omega, n_steps):
            self.wall = n_steps * (a + b * len(omega))

    monkeypatch.setattr(sweep_mod, "simulate", lambda scheme, omega, casing, n_steps, **kw: Probe(omega, n_steps))
    scheme = types.SimpleNamespace(h=1e-6)
    speeds = np.array([1600.0, 1200.0, 1300.0, 1500.0, 1400.0])
    spec = SweepSpec(revolutions=2.0, batch_size=3)
    steps = np.ceil(2.0 * 2 * np.pi / np.sort(speeds) / 1e-6)
    expected = sum(s.sum() * b + s.max() * a for s in (steps[:3], steps[3:]))
    assert sweep_mod.sweep_seconds(scheme, speeds, spec) == pytest.approx(expected, rel=1e-12)
    with pytest.raises(ValueError, match="probe_steps"):
        sweep_mod.sweep_seconds(scheme, speeds, spec, probe_steps=5)
