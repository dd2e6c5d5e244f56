"""Reduced contact integrator (§2.1.3, §2.2.2): constraints, discrete energy, stability limit, batches, full-order
agreement, bad input. Model: the ci blade, r = 45 (24 tip DOFs + 15 fixed-interface modes + 6 global MDs)."""
import dataclasses

import numpy as np
import pytest
import scipy.linalg

from rotor37_rom.casing import Casing, casing_profile, contact_frames, ramp_rate
from rotor37_rom.integrator import CentralDifference, SimulationDiverged, simulate, tangent_highest_frequency
from rotor37_rom.nonlinear_forces import PolynomialForces
from rotor37_rom.reduction import load_reduced_model, save_reduced_model, with_force_precision


def test_casing_profile_and_ramp():
    c0, p0 = 0.5e-3, 0.125e-3
    theta = np.array([np.pi / 2, 3 * np.pi / 2, 0.0, np.pi / 2 + 0.15])
    f = casing_profile(theta, c0, p0)
    np.testing.assert_allclose(f[:2], c0 + p0, rtol=1e-15)          # two bumps of height h_b
    assert f[2] < 1e-40                                              # none at theta = 0
    np.testing.assert_allclose(f[3], (c0 + p0) * np.exp(-1.0), rtol=1e-14)
    alpha = ramp_rate(2.0)
    np.testing.assert_allclose(1 - np.exp(-alpha * 0.4), 0.99, rtol=1e-14)   # 99 % at 20 % of the run
    n, s, _ = contact_frames(np.array([[0.25, 0.01, 0.02]]), "radial", -1)
    np.testing.assert_allclose(np.linalg.norm(n), 1.0)
    assert abs(n @ s.T) < 1e-15 and s[0, 1] < 0                       # sliding towards -theta


@pytest.mark.parametrize("nonlinear", [False, True])
def test_contact_constraints(ci_rom, nonlinear):
    """After each correction no node penetrates, multipliers are >= 0 and friction opposes sliding; the recorded
    gaps, recomputed independently from eq. 38, are >= -1e-12 m."""
    scheme = CentralDifference(ci_rom, nonlinear=nonlinear, safety=0.5)
    speeds = np.array([1300.0, 1450.0, 1550.0])
    casing = Casing(mu=0.15)
    res = simulate(scheme, speeds, casing, n_steps=30000, record_every=1)
    assert (res.contact_steps > 100).all(), res.contact_steps
    assert res.max_penetration.max() <= 1e-12, res.max_penetration
    assert res.min_multiplier.min() >= 0.0
    assert res.friction_power.max() < 0.0                              # f_t . v_slide < 0 at every contact
    nodes = ci_rom.boundary_nodes.reshape(-1, 3)
    _, _, theta0 = contact_frames(nodes, "x", -1)
    alpha = ramp_rate(30000 * scheme.h)
    for p, om in enumerate(speeds):
        t = res.t[p]
        gap = (casing.c0 - (1 - np.exp(-alpha * t))[None, :]
               * casing_profile(theta0[:, None] - om * t[None, :], casing.c0, casing.p0)) - res.u_r[p]
        assert gap.min() >= -1e-12, gap.min()
        assert (res.lam[p] >= 0).all() and res.lam[p].max() > 0
        assert ((res.lam[p] > 0) <= (np.abs(gap) < 1e-12)).all()        # force only where the gap is closed


def _free_vibration_start(model, amplitude=3e-4, seed=0, noise=1e-3):
    """1B-dominated initial displacement (node LE's e_x displacement = amplitude; the tip moves ~7x more along
    e_y, e_z) plus ``noise`` of every mode."""
    lam, V = scipy.linalg.eigh(model.K, model.M)
    rng = np.random.default_rng(seed)
    q = V[:, 0] + noise * V @ rng.standard_normal(model.r) * np.abs(V[:, 0]).max() / np.abs(V).max(axis=0)
    return q * amplitude / abs(q[0])


def test_discrete_energy_linear_conserved(ci_rom):
    scheme = CentralDifference(ci_rom, nonlinear=False, damping=False, safety=0.98)
    q0 = _free_vibration_start(ci_rom)
    res = simulate(scheme, 1.0, n_steps=100_000, initial=(q0, q0), record_every=100, energy=True)
    E = res.energy[0][1:]
    drift = np.abs(E - E[0]).max() / E[0]
    print("linear energy drift over 1e5 steps at 0.98 h_crit:", drift)
    assert drift <= 1e-10


def test_energy_balance_with_contact_friction_forcing(ci_rom):
    """The linear scheme's discrete energy changes by exactly the work of the contact forces (normal and friction),
    the forcing and the damping (module docstring of the integrator), over 3e4 steps with contact at 2 speeds with
    mu = 0.15 and one with mu = 0, modal damping and a tip force. Exact up to round-off: 3e4 accumulated steps, each
    with the cancellation of q K q terms; measured 0.6-4e-11 of the largest energy. (With GNL the cubic forces' work
    is not an exact difference of the scheme's energy: 3e-4 there, the O(h^2) defect of the bounded-energy test.)
    With mu = 0.15 friction does more work on the blade than the normal forces: it feeds the growth of the README."""
    scheme = CentralDifference(ci_rom, nonlinear=False, safety=0.5)
    f = np.zeros(ci_rom.r)
    f[0] = 20.0                                                         # 20 N at node LE along e_x
    res = simulate(scheme, [1400.0, 1500.0, 1400.0], [Casing(mu=0.15), Casing(mu=0.15), Casing(mu=0.0)],
                   n_steps=30000, record_every=100, energy=True, forcing=lambda t: f * np.sin(5000.0 * t))
    assert (res.contact_steps > 100).all(), res.contact_steps
    assert res.work[2][1] == 0.0                                        # mu = 0: no friction work
    for p in range(3):
        E, W = res.energy[p], res.work_history[p]
        np.testing.assert_allclose(W[:, -1], res.work[p], rtol=0, atol=0)
        balance = (E - E[0]) - (W[0] + W[1] + W[2] - W[3])
        err = np.abs(balance).max() / np.abs(E).max()
        print(f"{res.omega[p]:g} rad/s: works {res.work[p]}, E max {np.abs(E).max():.3e} J, "
              f"balance error {err:.2e}")
        assert err <= 1e-9
        assert min(abs(res.work[p][0]), res.work[p][3]) > 1e-3 * np.abs(E).max()
        assert p == 2 or res.work[p][1] > res.work[p][0] > 0.0
    # without energy=True or forcing, only the contact works are kept
    assert np.isnan(simulate(scheme, [1400.0], Casing(), n_steps=10).work[0][2:]).all()


def _static_start(model, amplitude):
    """Rest state of the GNL model under the force that gives the linear model a 1B deflection with node LE's e_x
    displacement = amplitude (the modal-derivative coordinates take their static values: a physical start)."""
    from rotor37_rom.reduction import solve_reduced_static

    lam, V = scipy.linalg.eigh(model.K, model.M)
    q_lin = V[:, 0] * amplitude / abs(V[0, 0])
    return solve_reduced_static(model, model.K @ q_lin, [0.5, 1.0])[-1]


def test_discrete_energy_nonlinear_bounded(ci_rom):
    """GNL, undamped, released from a static 1B deflection (0.3 mm at node LE along e_x, ~2 mm tip motion): stress
    stiffening raises omega_max by ~2.6 %, so the step is 0.98 of the limit of the tangent at +-q0; the energy error
    stays bounded over 1e5 steps. At 0.5 mm the tangent limit is 5 % below the linear one, and 0.98 of the linear
    limit blows up: for GNL the linear limit is not enough."""
    q0 = _static_start(ci_rom, 3e-4)
    w_t = tangent_highest_frequency(ci_rom, np.column_stack([q0, -q0]))
    lin_limit = CentralDifference(ci_rom, nonlinear=False).h_crit
    assert 1.01 < w_t * lin_limit / 2 < 1.05
    scheme = CentralDifference(ci_rom, nonlinear=True, damping=False, h=0.98 * 2 / w_t)
    res = simulate(scheme, 1.0, n_steps=100_000, initial=(q0, q0), record_every=50, energy=True)
    E = res.energy[0][1:]
    err = np.abs(E - E[0]) / E[0]
    tenth = len(err) // 10
    first, last = err[:tenth].max(), err[-tenth:].max()
    print("GNL energy error, first and last tenth:", first, last)
    assert last <= 1.5 * first                                          # bounded, no secular growth
    assert last < 1e-4
    # the GNL run differs from the linear one (the cubic forces act)
    lin = simulate(CentralDifference(ci_rom, nonlinear=False, damping=False, h=scheme.h), 1.0, n_steps=2000,
                   initial=(q0, q0), record_every=50)
    assert np.abs(lin.u_r[0][0] - res.u_r[0][0][:41]).max() > 1e-2 * abs(q0[0])
    big = _static_start(ci_rom, 5e-4)
    assert tangent_highest_frequency(ci_rom, np.column_stack([big, -big])) * lin_limit / 2 > 1.03
    with pytest.raises(SimulationDiverged):
        simulate(CentralDifference(ci_rom, nonlinear=True, damping=False, safety=0.98), 1.0, n_steps=100_000,
                 initial=(big, big), check_every=50)


def test_time_step_limit(ci_rom):
    ref = CentralDifference(ci_rom, nonlinear=False, damping=False)
    lam = scipy.linalg.eigh(ci_rom.K, ci_rom.M, eigvals_only=True)
    np.testing.assert_allclose(ref.h_crit, 2 / np.sqrt(lam[-1]), rtol=1e-12)
    with pytest.raises(ValueError, match="exceeds the stability limit"):
        CentralDifference(ci_rom, h=1.02 * ref.h_crit)
    scheme = CentralDifference(ci_rom, nonlinear=False, damping=False, h=1.02 * ref.h_crit, force=True)
    q0 = _free_vibration_start(ci_rom)
    with pytest.raises(SimulationDiverged, match=r"diverged at step \d+"):
        simulate(scheme, 1.0, n_steps=100_000, initial=(q0, q0), check_every=50)
    res = simulate(scheme, 1.0, n_steps=100_000, initial=(q0, q0), check_every=50, on_blowup="flag")
    assert 0 < res.diverged_step[0] < 5000


def test_massless_boundary_variant(ci_rom):
    """Dropping the boundary inertia (Monjaraz Tec et al. 2022) removes the stiff single-node constraint modes:
    h_crit grows > 2x. The scheme solves the massless model exactly: it matches an independent Newmark solution of
    the condensed model (eta'' M_ii + K_c eta = f_i - K_ib K_bb^-1 f_b, u_b = K_bb^-1 (f_b - K_bi eta)) within 1 %.
    The price: the constraint modes of the 24 tip DOFs carry much of the blade's 1B inertia, so the massless model
    answers a point force at node LE differently from the full-inertia ROM (measured, printed; ~18 % on ci)."""
    from rotor37_rom.reduction import simulate_linear_newmark

    std = CentralDifference(ci_rom, nonlinear=False, damping=False)
    ml = CentralDifference(ci_rom, nonlinear=False, damping=False, massless_boundary=True)
    print("h_crit standard / massless:", std.h_crit, ml.h_crit)
    assert ml.h_crit > 2.0 * std.h_crit
    with pytest.raises(ValueError, match="linear model only"):
        CentralDifference(ci_rom, nonlinear=True, massless_boundary=True)
    w, T, rb = 3000.0, 2e-3, 24
    f = np.zeros(ci_rom.r)
    f[0] = 50.0
    law = lambda t: np.sin(w * t)  # noqa: E731
    b = simulate(ml, 1.0, n_steps=int(T / ml.h), forcing=lambda t: f * law(t), record_every=1)
    K, M = ci_rom.K, ci_rom.M
    Kbb_inv = np.linalg.inv(K[:rb, :rb])
    Kc = K[rb:, rb:] - K[rb:, :rb] @ Kbb_inv @ K[:rb, rb:]
    fc = f[rb:] - K[rb:, :rb] @ Kbb_inv @ f[:rb]
    dt = 2e-6
    t, eta = simulate_linear_newmark(M[rb:, rb:], np.zeros_like(Kc), Kc, lambda t: fc * law(t), dt, int(T / dt))
    ub = Kbb_inv @ (f[:rb, None] * law(t)[None, :] - K[:rb, rb:] @ eta)
    ref = ub[0]
    got = np.interp(t, b.t[0], b.u_r[0][0])
    err = np.abs(got - ref).max() / np.abs(ref).max()
    print("massless scheme vs condensed Newmark:", err)
    assert err < 0.01
    a = simulate(std, 1.0, n_steps=int(T / std.h), forcing=lambda t: f * law(t), record_every=1)
    full = np.interp(t, a.t[0], a.u_r[0][0])
    print("massless vs full-inertia ROM, forced LE response:", np.abs(full - ref).max() / np.abs(full).max())


def test_frequency_cap_mass_scaling(ci_rom):
    """Spectral mass scaling (CentralDifference(frequency_cap=...)): the modes of (K~, M_s) below the cap keep their
    frequency and shape to round-off, the ones above sit at the cap, so h_crit = 2 / cap exactly. The linear scheme
    still conserves its discrete energy, contact stays exact, and, unlike the massless boundary (~18 % off), the
    point-forced LE response at 3000 rad/s stays within 1 % of the unscaled ROM (measured 0.5-0.9 % at the 8 tip
    nodes with h = 0.5 x 2/cap, 6.8x the unscaled step; at 0.98 x 2/cap the capped modes ring at the edge of the
    scheme's range and the error doubles)."""
    from rotor37_rom.integrator import capped_mass

    K, M = ci_rom.K, ci_rom.M
    cap = 2 * np.pi * 60e3
    Ms = capped_mass(M, K, cap)
    lam, V = scipy.linalg.eigh(K, M)
    lam_s = scipy.linalg.eigh(K, Ms, eigvals_only=True)
    low = lam < cap**2
    assert 10 < low.sum() < ci_rom.r                                     # the cap cuts inside the spectrum
    np.testing.assert_allclose(lam_s[: low.sum()], lam[low], rtol=1e-9)
    np.testing.assert_allclose(lam_s[low.sum():], cap**2, rtol=1e-9)
    resid = K @ V[:, low] - Ms @ V[:, low] * lam[low]                    # same shapes below the cap
    assert np.abs(resid).max() <= 1e-8 * np.abs(K @ V[:, low]).max()
    np.testing.assert_allclose(Ms, Ms.T, rtol=0, atol=1e-14 * np.abs(Ms).max())
    std = CentralDifference(ci_rom, nonlinear=False, damping=False)
    capped = CentralDifference(ci_rom, nonlinear=False, damping=False, frequency_cap=cap, safety=0.98)
    np.testing.assert_allclose(capped.h_crit, 2 / cap, rtol=1e-9)
    assert capped.h > 10 * std.h
    # discrete energy of the scaled scheme, free vibration
    q0 = _free_vibration_start(ci_rom)
    res = simulate(capped, 1.0, n_steps=20_000, initial=(q0, q0), record_every=20, energy=True)
    E = res.energy[0][1:]
    assert np.abs(E - E[0]).max() / E[0] <= 1e-10
    # forced LE response: 50 N sin(3000 t) at node LE along e_x, 2 ms from rest
    w, T = 3000.0, 2e-3
    f = np.zeros(ci_rom.r)
    f[0] = 50.0
    a = simulate(std, 1.0, n_steps=int(T / std.h), forcing=lambda t: f * np.sin(w * t), record_every=1)
    half = CentralDifference(ci_rom, nonlinear=False, damping=False, frequency_cap=cap, safety=0.5)
    assert half.h > 5 * std.h
    b = simulate(half, 1.0, n_steps=int(T / half.h), forcing=lambda t: f * np.sin(w * t), record_every=1)
    ref = a.u_r[0][0]
    got = np.interp(a.t[0], b.t[0], b.u_r[0][0])
    err = np.abs(got - ref).max() / np.abs(ref).max()
    print(f"cap 60 kHz: h {half.h:.3g} vs {std.h:.3g} s, forced LE response error {err:.2e}")
    assert err < 1e-2
    # contact stays exact at the larger step
    gnl = CentralDifference(ci_rom, nonlinear=True, frequency_cap=cap, safety=0.25)
    res = simulate(gnl, [1300.0, 1450.0], Casing(mu=0.15), n_steps=3000, record_every=10)
    assert (res.contact_steps > 20).all() and res.max_penetration.max() <= 1e-12
    assert res.min_multiplier.min() >= 0.0 and res.friction_power.max() < 0.0
    # where it breaks: with GNL, stress stiffening raises the capped modes' tangent frequencies (measured 3.9x the
    # cap at 60 kHz on ~1 mm states), so 0.5 x 2/cap blows up; the run is flagged at its step, no solver error
    bad_h = CentralDifference(ci_rom, nonlinear=True, frequency_cap=cap, safety=0.5)
    res = simulate(bad_h, [1300.0, 1450.0], Casing(mu=0.15), n_steps=3000, record_every=10, on_blowup="flag")
    assert (res.diverged_step > 0).any()
    # the GNL step from the tangent limit on the largest states of a short unscaled probe run is stable
    from rotor37_rom.integrator import gnl_time_step, probe_states

    T = 5e-3
    states = probe_states(ci_rom, [1300.0, 1450.0], Casing(mu=0.15), duration=T)
    h = gnl_time_step(ci_rom, states, cap)
    assert std.h < h < bad_h.h
    res = simulate(CentralDifference(ci_rom, nonlinear=True, frequency_cap=cap, h=h), [1300.0, 1450.0],
                   Casing(mu=0.15), n_steps=int(np.ceil(T / h)), duration=T, record_every=10, on_blowup="flag")
    print("probe-based GNL step", h, "diverged", res.diverged_step, "pen", res.max_penetration)
    assert (res.diverged_step < 0).all() and res.max_penetration.max() <= 1e-12
    # bad input
    for bad in (0.0, -1.0, float("nan"), 100.0):
        with pytest.raises(ValueError, match="frequency_cap"):
            CentralDifference(ci_rom, nonlinear=False, frequency_cap=bad)
    with pytest.raises(ValueError, match="frequency_cap"):
        CentralDifference(ci_rom, nonlinear=False, frequency_cap=cap, massless_boundary=True)


def test_linear_rom_matches_full_order_transient(ci_blade, ci_ops, ci_rom):
    """Point force F sin(3000 t) along e_x at node LE from rest, undamped, 2 ms: the linear ROM with central
    differences equals the full-order linear Newmark transient within 1 % (max over time of node LE's e_x)."""
    from rotor37_rom import fem

    F0, w, T = 50.0, 3000.0, 2e-3
    dof = int(ci_blade.tip_dofs[0, 0])
    f = ci_ops.u.vector.copy()
    f.set(0.0)
    f.array[dof] = F0
    dt = 5e-6
    fom = fem.solve_newmark(ci_blade, f, lambda t: np.sin(w * t), dt, int(T / dt), ci_blade.tip_dofs,
                            nonlinear=False, ops=ci_ops)
    scheme = CentralDifference(ci_rom, nonlinear=False, damping=False)
    fr = np.zeros(ci_rom.r)
    fr[0] = F0
    every = 1
    rom = simulate(scheme, 1.0, n_steps=int(T / scheme.h) + 1, forcing=lambda t: fr * np.sin(w * t),
                   record_every=every)
    u_rom = np.interp(fom.t, rom.t[0], rom.u_r[0][0])
    u_fom = fom.monitored.reshape(len(fom.t), -1)[:, 0]
    err = np.abs(u_rom - u_fom).max() / np.abs(u_fom).max()
    print("linear ROM vs full order (node LE, e_x):", err, "peak", np.abs(u_fom).max())
    assert err < 0.01


@pytest.mark.parametrize("P", [1, 8, 80])
def test_batches_equal_one_by_one(ci_rom, P):
    """P simulations at different speeds, clearances and friction coefficients in one batch equal the same
    simulations run one by one to 1e-8 (relative, node LE), over 1e4 steps with contact."""
    scheme = CentralDifference(ci_rom, nonlinear=False, safety=0.9)
    rng = np.random.default_rng(P)
    speeds = np.linspace(1300.0, 1600.0, P)
    casings = [Casing(c0=c0, mu=mu, h_b=c0 + 0.125e-3) for c0, mu in
               zip(rng.uniform(0.45e-3, 0.55e-3, P), rng.uniform(0.0, 0.2, P))]
    done = []                                   # progress reports simulation-steps (the sweep's progress bar)
    batch = simulate(scheme, speeds, casings, n_steps=10_000, record_every=10, progress=done.append)
    assert batch.contact_steps.min() > 0 and sum(done) == batch.n_steps.sum() == 10_000 * P
    picks = range(P) if P <= 8 else rng.choice(P, 10, replace=False)
    for p in picks:
        one = simulate(scheme, speeds[p], casings[p], n_steps=10_000, record_every=10)
        scale = np.abs(one.u_r[0]).max()
        assert np.abs(batch.u_r[p] - one.u_r[0]).max() <= 1e-8 * scale


def test_nonlinear_batch_equals_one_by_one(ci_rom):
    """GNL batches: a single state uses one GEMV over all cubic monomials, a batch the per-index GEMMs of eqs. 35-36;
    the two summation orders differ by round-off (1e-16), which 8000 steps with contact grow to ~5e-8: 1e-6 here."""
    scheme = CentralDifference(ci_rom, nonlinear=True, safety=0.5)
    speeds = np.array([1300.0, 1400.0, 1500.0, 1600.0])
    batch = simulate(scheme, speeds, Casing(), n_steps=8000, record_every=10)
    assert batch.contact_steps.min() > 0
    for p in (0, 3):
        one = simulate(scheme, speeds[p], Casing(), n_steps=8000, record_every=10)
        assert np.abs(batch.u_r[p] - one.u_r[0]).max() <= 1e-6 * np.abs(one.u_r[0]).max()


def test_bad_input(ci_rom):
    with pytest.raises(ValueError, match="c0"):
        Casing(c0=-1e-4)
    with pytest.raises(ValueError, match="mu"):
        Casing(mu=-0.1)
    scheme = CentralDifference(ci_rom, nonlinear=False)
    with pytest.raises(ValueError, match="Omega must be > 0"):
        simulate(scheme, [1300.0, 0.0], Casing(), n_steps=10)
    with pytest.raises(ValueError, match="contact_nodes"):
        simulate(scheme, 1300.0, Casing(contact_nodes=(0, 9)), n_steps=10)
    with pytest.raises(ValueError, match="time step h"):
        CentralDifference(ci_rom, h=-1.0)
    with pytest.raises(ValueError, match="give revolutions or n_steps"):
        simulate(scheme, 1300.0, Casing())


def test_point_cubature_trained_on_contact_states(ci_blade, ci_rom, tmp_path):
    """Empirical cubature (single quadrature points, non-negative weights) trained on the states of a GNL contact
    run: it reproduces the exact reduced force on the states of a run at another speed, keeps K~ exact, and a
    contact run with it follows the exact one. Weights >= 0 keep the force the gradient of a sum of SVK point
    energies (conservative)."""
    from rotor37_rom.builder import hyper_reduce
    from rotor37_rom.ecsw import state_errors

    scheme = CentralDifference(ci_rom, nonlinear=True, safety=0.5)
    speeds = [1340.0, 1460.0]
    exact = simulate(scheme, speeds, Casing(mu=0.0), n_steps=20_000, record_every=100, record_q=True)
    assert exact.contact_steps.min() > 0
    Q_train, Q_held = exact.records_q[0][:, ::3], exact.records_q[1]
    hr, rep = hyper_reduce(ci_blade, ci_rom, Q_train, tol=1e-3, level="point")
    n_all = rep["exact"].w.size
    Q_held = Q_held[:, np.abs(Q_held[:ci_rom.sizes["r_b"]]).max(axis=0) > 1e-5]   # in motion
    err = state_errors(rep["exact"], hr.forces, Q_held)
    g = rep["exact"].evaluate(Q_held)
    err_run = np.linalg.norm(hr.forces.evaluate(Q_held) - g, axis=0).max() / np.linalg.norm(g, axis=0).max()
    print(f"cubature: {rep['points']} of {n_all} points, training error {rep['result'].training_error:.1e}, "
          f"held-out force error median {np.median(err):.1e} max {err.max():.1e}, largest relative to the run's "
          f"largest force {err_run:.1e}")
    assert rep["result"].training_error <= 1e-3
    assert rep["points"] < 0.02 * n_all and np.all(hr.forces.w > 0)
    assert hr.K is ci_rom.K and hr.key != ci_rom.key
    assert np.median(err) <= 5e-3 and err_run <= 1e-2
    # contact dynamics amplify any force perturbation (~30x over this revolution): compare with the exact model's
    # forces scaled by 1 + the cubature's largest held-out error, a perturbation of the same size
    def deviation(model):
        run = simulate(CentralDifference(model, nonlinear=True, h=scheme.h), speeds[1], Casing(mu=0.0),
                       n_steps=20_000, record_every=100)
        u = exact.u_r[1][0]
        return np.abs(run.u_r[0][0] - u).max() / np.abs(u).max()

    scaled = dataclasses.replace(ci_rom, forces=PolynomialForces(ci_rom.forces.A * (1 + err_run),
                                                                 ci_rom.forces.B * (1 + err_run)))
    dev, dev_scaled = deviation(hr), deviation(scaled)
    print(f"LE normal displacement, 20,000 steps at {speeds[1]:g} rad/s: largest deviation {dev:.1e} of its peak "
          f"(exact forces x (1 + {err_run:.1e}): {dev_scaled:.1e})")
    assert dev <= 3.0 * dev_scaled
    # float32 evaluation of the same cubature: the nonlinear stress is formed from products of gradients (no
    # cancellation against the linear part), so each point's term carries ~10 u (u = 2^-24 = 6e-8); the sums over
    # r and over the 9 n terms add ~sqrt(K) u (probabilistic rounding, Higham & Mary 2019) of the absolute sum,
    # which the cancellation |sum of |terms|| / |sum| scales (measured ~1 here: the points push the same way).
    # Bound per state: 10 u sqrt(9 n) times that ratio (~2e-5; measured ~4e-7).
    single = with_force_precision(hr, "single")
    assert single.key != hr.key and single.forces.precision == "single"
    g_double = hr.forces.evaluate(Q_held)
    g_single = single.forces.evaluate(Q_held)
    assert g_single.dtype == np.float64
    some = Q_held[:, :3]
    assert np.array_equal(single.forces.point_contributions(some), hr.forces.point_contributions(some))  # training
    terms = np.abs(hr.forces.point_contributions(Q_held)).sum(axis=0)               # (r, n_states)
    cancel = np.linalg.norm(terms, axis=0) / np.linalg.norm(g_double, axis=0)
    u = float(np.finfo(np.float32).eps) / 2
    dev32 = np.linalg.norm(g_single - g_double, axis=0) / np.linalg.norm(g_double, axis=0)
    bound = 10 * u * np.sqrt(9 * rep["points"]) * cancel
    print(f"float32 cubature: force deviation from float64 median {np.median(dev32):.1e} max {dev32.max():.1e} "
          f"(cancellation up to {cancel.max():.0f}, bound {bound.min():.1e}-{bound.max():.1e})")
    assert np.all(dev32 <= bound) and np.all(dev32 > 0)
    assert dev32.max() <= 1e-2 * np.median(err)                   # far below the cubature's own error
    loaded = load_reduced_model(save_reduced_model(single, tmp_path / "single.npz"), expected_key=single.key)
    assert loaded.forces.precision == "single" and np.array_equal(loaded.forces.evaluate(Q_held), g_single)
    with pytest.raises(ValueError, match="precision"):
        with_force_precision(hr, "half")
    with pytest.raises(ValueError, match="quadrature forces"):
        with_force_precision(ci_rom, "single")
    with pytest.raises(ValueError, match="Q_train"):
        hyper_reduce(ci_blade, ci_rom, Q_train[:-1])
