"""Blade-tip/casing contact on the bladed disk (paper §3.4) through the blade's integrator.

- a tuned disk's step operators applied per harmonic index equal the dense ones to round-off (and a mistuned disk,
  whose operators are not block-circulant, keeps the dense ones);
- tuned disk in contact with the ovalized casing, GNL off and on: every blade's tip history is blade 0's shifted in
  time by j (2 pi / 36) / Omega (the casing is fixed and the blades identical: the steady response is a travelling
  wave), no penetration is left, lambda >= 0 and friction opposes the sliding; GNL off, the discrete energy balance
  holds to round-off;
- mistuning factors: mean 1, the asked standard deviation, positive, seeded; bad input;
- point cubature of the sector force trained on the sectors of a GNL contact run (the blade's hyper-reduction with
  the sectors as columns): its force on another speed's run, float32, save/load, and the run it gives.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rotor37_rom.dynamics.casing import Casing
from rotor37_rom.disk.assembly import assemble_disk_matrices, mistuning_factors
from rotor37_rom.disk.harmonics import travelling_wave_departure
from rotor37_rom.dynamics.explicit import CentralDifference, simulate
from rotor37_rom.model.reduced import load_reduced_model, save_reduced_model, with_force_precision
from rotor37_rom.reduction.craig_bampton import modal_damping

pytestmark = pytest.mark.slow

OMEGA = 1400.0                       # rad/s: the 1B/EO4 region of the paper's maps
SHIFT = 2 * np.pi / 36 / OMEGA       # time for the rotor to turn one sector (s)
STEPS_PER_SHIFT = 13                 # h = SHIFT / 13 = 9.6e-6 s: a sector's turn is a whole number of steps
CAP = 1e5                            # rad/s: frequency cap, h_crit = 2e-5 s


def _le_rows(model):
    return [model.nodes.row("LE", s) for s in range(36)]


def test_harmonic_blocks_equal_the_dense_operators(disk_model):
    """X1 q + X2 q_prev + X0 (f - g(q)) per harmonic index (19 blocks for N = 36, one batched product) equals the
    dense products to round-off, GNL and forcing included: the blocks drop what the dense operators carry outside
    them, their own round-off amplified by the capped mass's conditioning (at most 1e-8 of each operator, the
    threshold of ``HarmonicBlocks``; 3e-10 here), so the products agree to 1e-8; a disk mistuned by 3 % gets the
    dense operators (its blocks couple the harmonics)."""
    model, report = disk_model
    scheme = CentralDifference(model, nonlinear=True, h=SHIFT / STEPS_PER_SHIFT, frequency_cap=CAP)
    assert scheme.harmonic is not None
    sizes = scheme.harmonic.sizes
    assert len(sizes) == 19 and sizes.sum() == model.r
    rng = np.random.default_rng(0)
    Q, Qp, F = (1e-4 * rng.standard_normal((model.r, 5)) for _ in range(3))
    dense = scheme.X1 @ Q + scheme.X2 @ Qp + scheme.X0 @ (F - model.forces.evaluate(Q))
    np.testing.assert_allclose(scheme.predict(Q, Qp, F), dense, rtol=0, atol=1e-8 * np.abs(dense).max())
    factors = mistuning_factors(36, 0.03, seed=1)
    K, _ = assemble_disk_matrices(report["sector_matrices"], model.sectors.Pi, 36, factors)
    mistuned = dataclasses.replace(model, K=K)
    assert CentralDifference(mistuned, nonlinear=False, h=scheme.h, frequency_cap=CAP).harmonic is None


@pytest.mark.parametrize("gnl", [False, True])
def test_tuned_disk_contact_is_a_travelling_wave(disk_model, gnl):
    """36 blades (node LE of each) against the two-lobe casing (c0 = 0.5 mm, bumps of 0.55 mm: light contact),
    mu = 0.15 along the casing cone's normal, 1400 rad/s, 0.15 s from rest; modal damping 2 % so that the start-up
    transient decays by exp(-0.02 omega_1 t) < 2e-5 after the casing's ramp (99 % at 0.03 s; omega_1 ~ 5,800 rad/s),
    where the forcing is a pure travelling wave. Blade j's LE history over the last two revolutions equals blade 0's
    delayed by j (2 pi / 36) / Omega (a whole number of steps, so the discrete schemes are exactly shifted too) to
    1e-3 of its amplitude (the transient's bound, with a margin of 50 for the contact's nonlinearity). With GNL the
    same ramp runs at half the step, 4.8e-6 s, for 0.3 s (``gnl_time_step`` on the runs' largest states: 9.2e-6 to
    1.0e-5 s): at the full step, on that limit, this ramp leaves a component not locked to the rotor that does not
    decay (5.4e-2 of the amplitude, flat from 0.2 to 0.45 s, on an AMD EPYC; 3e-5 on an Intel Xeon: round-off
    decides), a step artefact - at h/2 and h/4 the same ramp decays to the travelling wave, and a 3 times slower ramp
    does at every step from h to h/8 (docs/verification.md). The slowest decay measured over those runs, 26 /s,
    takes the 0.17 departure at the ramp's end (31 ms) to 1.5e-4 by 0.3 s: 1e-3 holds with a margin of 7.
    Contact checks of the blade, GNL off and on: no penetration after the correction (1e-12 m, round-off),
    lambda >= 0, friction power <= 0 (opposes the sliding); GNL off: the discrete energy changes by the contact and
    damping works to 1e-9 of the largest energy (round-off of 15,600 steps, as the blade's test)."""
    model, _ = disk_model
    C, _ = modal_damping(model.K, model.M, ratios=lambda w: np.full_like(w, 0.02))
    damped = dataclasses.replace(model, C=C)
    per_shift = 2 * STEPS_PER_SHIFT if gnl else STEPS_PER_SHIFT
    scheme = CentralDifference(damped, nonlinear=gnl, h=SHIFT / per_shift, frequency_cap=CAP)
    assert scheme.harmonic is not None and scheme.h < 0.5 * scheme.h_crit
    n_steps = int(round((0.3 if gnl else 0.15) / scheme.h))
    casing = Casing(h_b=0.55e-3, mu=0.15, direction="cone")
    res = simulate(scheme, OMEGA, casing, n_steps=n_steps, duration=0.15, monitor=_le_rows(model), energy=not gnl)
    assert res.diverged_step[0] == -1
    assert res.contact_steps[0] > 1000, res.contact_steps
    u = res.u_r[0]                                                       # (36, steps + 1), normal displacement
    window = np.arange(n_steps - int(2 * 2 * np.pi / OMEGA / scheme.h), n_steps + 1)
    worst, amplitude = travelling_wave_departure(u, window, per_shift)
    assert amplitude > 1e-5                                              # the blades do move (tens of microns)
    print(f"GNL {gnl}: LE amplitude {amplitude * 1e3:.4f} mm, largest departure from the travelling wave "
          f"{worst / amplitude:.2e}, contact steps {res.contact_steps[0]}")
    assert worst <= 1e-3 * amplitude
    # and not trivially: the blades are out of phase with one another
    assert np.abs(u[1, window] - u[0, window]).max() > 0.1 * amplitude
    assert res.max_penetration[0] <= 1e-12
    assert (res.lam[0] >= 0).all() and res.lam[0].max() > 0
    assert res.friction_power[0] <= 0.0
    if not gnl:
        E, W = res.energy[0], res.work_history[0]
        balance = (E - E[0]) - (W[0] + W[1] + W[2] - W[3])
        assert np.abs(balance).max() <= 1e-9 * np.abs(E).max()
        assert res.work[0][0] > 0 and res.work[0][3] > 0         # the bumps feed the blades, the damping takes


def test_mistuning_factors():
    """Log-normal stiffness factors: mean 1 and standard deviation sigma (checked on 2e5 draws to 5 standard errors
    of the estimators, the log-normal's kurtosis in that of the standard deviation), all > 0 even at sigma = 0.9,
    the same disk for the same seed; sigma outside [0, 1) refused naming the scatter."""
    for sigma in (0.01, 0.05, 0.9):
        x = mistuning_factors(200_000, sigma, seed=3)
        se = sigma / np.sqrt(x.size)
        assert abs(x.mean() - 1.0) <= 5 * se
        s2 = np.log1p(sigma**2)
        kurtosis = np.exp(4 * s2) + 2 * np.exp(3 * s2) + 3 * np.exp(2 * s2) - 3          # mu_4 / sigma^4
        assert abs(x.std() - sigma) <= 5 * sigma * np.sqrt(kurtosis - 1) / (2 * np.sqrt(x.size))
        assert x.min() > 0
    np.testing.assert_allclose(mistuning_factors(36, 0.02, seed=7), mistuning_factors(36, 0.02, seed=7), rtol=1e-15)
    assert not np.allclose(mistuning_factors(36, 0.02, seed=7), mistuning_factors(36, 0.02, seed=8))
    assert np.array_equal(mistuning_factors(36, 0.0), np.ones(36))
    for bad in (-0.01, 1.0, 1.5):
        with pytest.raises(ValueError, match=r"mistuning scatter must be in \[0, 1\)"):
            mistuning_factors(36, bad)


def test_contact_map_takes_a_disk_model(disk_model, tmp_path):
    """The map command runs a saved disk model as it runs a blade's (--model): the map and NFRC at node LE of the
    asked sector, node LE of every sector recorded and the largest over them in summary.json (so never below the
    asked sector's), the EO4 resonance from the 1B family's 4-diameter mode (above the family's lowest); its
    continuation (§2.3.3) on the disk follows the same node: each branch's first run is the map's run at its start
    speed (from rest, as long), so it gives the map's amplitude there."""
    from rotor37_rom.model.reduced import save_reduced_model
    from rotor37_rom.studies import contact_map
    from rotor37_rom.studies.sweep import load_sweep

    model, _ = disk_model
    config = contact_map.ContactMapConfig.from_options(
        model=save_reduced_model(model, tmp_path / "disk.npz"), sector=5, speeds=(1400, 1500, 2), revolutions=1.0,
        gnl="off", frequency_cap=16.0, direction="cone", hb=0.55e-3, quiet=True, out=tmp_path / "map",
        continuation=100.0, continuation_range=(1400.0, 1500.0))
    result = contact_map.run_contact_map(config)
    run, summary = result.runs["no GNL, cap 16 kHz"], result.summary
    up, down = run.branches["up"].points, run.branches["down"].points
    assert (up[0].omega, down[0].omega) == (1400.0, 1500.0) and up[-1].omega <= 1500.0 <= down[0].omega
    # the same run alone instead of in a batch of two: equal to the batch's round-off (as the MPI map's test)
    np.testing.assert_allclose([up[0].amplitude, down[0].amplitude], run.nfrc, rtol=1e-8)
    assert summary["node"] == "5:LE" and summary["disk"]
    entry = summary["runs"]["no GNL, cap 16 kHz"]
    assert np.all(np.asarray(entry["largest_over_sectors"]) >= run.nfrc) and np.all(run.nfrc > 0)
    records = load_sweep(run.folder)
    assert [str(x) for x in records[0]["labels"]] == [f"{s}:LE" for s in range(36)]
    assert entry["contact_checks"]["max_penetration"] <= 1e-12
    assert 4 * result.linear_resonance > result.eigenfrequencies[0]
    with pytest.raises(ValueError, match="--sector"):
        contact_map.ContactMapConfig.from_options(model=config.rom.path, sector=36)
    # a speed file lost and the map run again (#70): computed again with its batch, bit-identical
    lost = sorted(run.folder.glob("omega_*.npz"))[-1]
    with np.load(lost) as data:
        before = {k: data[k] for k in ("u_r", "lam", "q_final", "q_prev", "work")}
    lost.unlink()
    contact_map.run_contact_map(config)
    with np.load(lost) as again:
        for key, value in before.items():
            np.testing.assert_array_equal(again[key], value, err_msg=key)


def test_disk_gnl_map_probes_once(disk_model, tmp_path, monkeypatch):
    """A capped GNL disk map takes its step from a capped GNL probe run (the disk's unscaled step is ~5e-8 s); the
    probe is cached with the map, so the map started again (a resumed multi-hour map) runs no simulation at all - its
    speeds are done and the probe is read back - and takes the same step, below the capped linear one."""
    from rotor37_rom.model.reduced import save_reduced_model
    from rotor37_rom.studies import contact_map, contact_scheme

    model, _ = disk_model
    config = contact_map.ContactMapConfig.from_options(model=save_reduced_model(model, tmp_path / "disk.npz"),
                                          speeds=(1400, 1500, 2), revolutions=0.2, gnl="on", frequency_cap=16.0,
                                          direction="cone", hb=0.55e-3, quiet=True, out=tmp_path / "map")
    first = contact_map.run_contact_map(config).runs["GNL, cap 16 kHz"]
    assert len(list((tmp_path / "map" / "cache").glob("gnl_probe_*.npz"))) == 1

    def no_simulation(*args, **kwargs):
        raise AssertionError("the resumed map simulated again")

    for module in (contact_map, contact_scheme):                          # the study's own runs and the probe's
        monkeypatch.setattr(module, "simulate", no_simulation)
    again = contact_map.run_contact_map(config).runs["GNL, cap 16 kHz"]
    linear = CentralDifference(model, nonlinear=False, safety=0.5, frequency_cap=config.scheme.frequency_cap_rad_s)
    assert again.h == first.h <= linear.h
    np.testing.assert_array_equal(again.imap.nfrc, first.imap.nfrc)


def test_disk_point_cubature(ci_disk, disk_model, tmp_path):
    """The sector's force hyper-reduced by point cubature (``reduction.builder.hyper_reduce`` on a disk model), trained on the
    sector columns of a GNL contact run at 1,400 rad/s (light contact as above, 0.06 s: the casing's ramp and the first
    contacts). The exact quadrature on ``model.disk_basis.sector_force_basis`` equals the model's exact tensors to
    round-off (1e-10: the same polynomial, summed in another order); the training error is within its tolerance, 1e-3,
    on few of the sector's points with positive weights (the force stays the gradient of a sum of SVK point energies);
    on the states of a run at 1,500 rad/s (held out) the disk force's error has a median within 5 times the training
    tolerance (the blade's bound); K~ is the exact one and the key changes; float32 evaluation moves the force by far
    less than the cubature's own error; save/load keeps it. (Unlike the blade's test, no comparison of runs: this
    light-contact disk run amplifies any perturbation ~1e6-fold in 0.06 s - the batched and the single run at 1,500
    rad/s part at 2e-7 of the amplitude from round-off - so runs compare on the maps' statistics, in the benchmark.)"""
    from rotor37_rom.reduction.builder import hyper_reduce

    model, _ = disk_model
    scheme = CentralDifference(model, nonlinear=True, h=SHIFT / (2 * STEPS_PER_SHIFT), frequency_cap=CAP)
    casing = Casing(h_b=0.55e-3, mu=0.0, direction="cone")
    n_steps = int(round(0.06 / scheme.h))        # from rest: the casing's ramp, the first contact at 0.017 s
    exact = simulate(scheme, [1400.0, 1500.0], casing, n_steps=n_steps, duration=0.15, monitor=_le_rows(model),
                     record_q=True, record_every=50)
    assert (exact.diverged_step == -1).all() and (exact.contact_steps > 100).all(), exact.contact_steps
    Q_train, Q_held = exact.records_q[0], exact.records_q[1]
    hr, rep = hyper_reduce(ci_disk, model, Q_train, tol=1e-3, max_columns=128)
    n_all = rep["exact"].w.size
    X = rep["columns_trained"]
    assert X.shape == (model.forces.forces.r, 128)
    exact_quadrature = dataclasses.replace(model.forces, forces=rep["exact"])
    Q_held = Q_held[:, np.abs(Q_held[model.nodes.boundary_rows]).max(axis=0) > 1e-5]     # in motion
    g = model.forces.evaluate(Q_held)
    np.testing.assert_allclose(exact_quadrature.evaluate(Q_held), g, rtol=0, atol=1e-10 * np.abs(g).max())
    err = np.linalg.norm(hr.forces.evaluate(Q_held) - g, axis=0) / np.linalg.norm(g, axis=0)
    err_run = np.linalg.norm(hr.forces.evaluate(Q_held) - g, axis=0).max() / np.linalg.norm(g, axis=0).max()
    print(f"disk cubature: {rep['points']} of {n_all} points from {X.shape[1]} sector columns, training error "
          f"{rep['result'].training_error:.1e}; held-out force error median {np.median(err):.1e} max {err.max():.1e}, "
          f"largest relative to the run's largest force {err_run:.1e}")
    assert rep["result"].training_error <= 1e-3
    assert rep["points"] < 0.05 * n_all and np.all(hr.forces.forces.w > 0)
    assert hr.K is model.K and hr.key != model.key and hr.sectors is model.sectors
    assert np.median(err) <= 5e-3
    single = with_force_precision(hr, "single")
    assert single.key != hr.key and single.forces.forces.precision == "single"
    dev32 = np.linalg.norm(single.forces.evaluate(Q_held) - hr.forces.evaluate(Q_held), axis=0) / np.linalg.norm(
        g, axis=0)
    assert dev32.max() <= 1e-2 * np.median(err)
    back = load_reduced_model(save_reduced_model(single, tmp_path / "disk_cubature.npz"), expected_key=single.key)
    np.testing.assert_array_equal(back.forces.evaluate(Q_held), single.forces.evaluate(Q_held))

