"""Reduced contact integrator (§2.1.3, §2.2.2): constraints, discrete energy, stability limit, batches, full-order
agreement, bad input. Model: the ci blade, r = 45 (24 tip DOFs + 15 fixed-interface modes + 6 global MDs)."""
import dataclasses

import numpy as np
import pytest
import scipy.linalg

from rotor37_rom.dynamics.casing import Casing, casing_profile, contact_frames, ramp_rate
from rotor37_rom.dynamics.explicit import CentralDifference, SimulationDiverged, simulate, tangent_highest_frequency
from rotor37_rom.forces.tensors import PolynomialForces
from rotor37_rom.model.modes import normalise_signs
from rotor37_rom.model.reduced import load_reduced_model, save_reduced_model, with_force_precision


def _le_x(model):
    """Entry of q holding node LE's e_x displacement (from the model's node map)."""
    return int(model.nodes.q_index[model.nodes.row("LE"), 0])


def _boundary_rows(model):
    """Entries of q holding the contact nodes' displacements."""
    return model.nodes.boundary_rows


def _le(res, p=0):
    """Node LE's recorded normal displacement in simulation p."""
    return res.u_r[p][res.row("0:LE")]


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


@pytest.mark.kernels
@pytest.mark.parametrize("nonlinear", [False, pytest.param(True, marks=pytest.mark.slow)])
def test_contact_constraints(ci_rom, nonlinear):
    """After each correction no node penetrates, multipliers are >= 0 and friction opposes sliding; the recorded
    gaps, recomputed independently from eq. 38, are >= -1e-12 m."""
    scheme = CentralDifference(ci_rom, nonlinear=nonlinear, safety=0.5)
    speeds = np.array([1300.0, 1450.0, 1550.0])
    casing = Casing(mu=0.15)
    res = simulate(scheme, speeds, casing, n_steps=10_000, record_every=1)
    # the bumps (h_b > c0) sweep the tip: one pass over a bump's half-width (0.15 rad) lasts 0.15 / (Omega h) ~ 500
    # steps at these speeds; 100 contact steps ask for a fifth of one pass, whatever the trajectory's round-off (the
    # ovalisation's ramp is set for the run's length: 740-810 contact steps in 10,000 measured with GNL)
    assert (res.contact_steps > 100).all(), res.contact_steps
    assert res.max_penetration.max() <= 1e-12, res.max_penetration
    assert res.min_multiplier.min() >= 0.0
    assert res.friction_power.max() < 0.0                              # f_t . v_slide < 0 at every contact
    nodes = ci_rom.nodes.coordinates
    _, _, theta0 = contact_frames(nodes, "x", -1)
    alpha = ramp_rate(10_000 * scheme.h)
    for p, om in enumerate(speeds):
        t = res.t[p]
        gap = (casing.c0 - (1 - np.exp(-alpha * t))[None, :]
               * casing_profile(theta0[:, None] - om * t[None, :], casing.c0, casing.p0)) - res.u_r[p]
        assert gap.min() >= -1e-12, gap.min()
        assert (res.lam[p] >= 0).all() and res.lam[p].max() > 0
        assert ((res.lam[p] > 0) <= (np.abs(gap) < 1e-12)).all()        # force only where the gap is closed


def _free_vibration_start(model, amplitude=3e-4, seed=0, noise=1e-3):
    """1B-dominated initial displacement (node LE's e_x displacement = +amplitude; the tip moves ~7x more along
    e_y, e_z) plus ``noise`` of every mode. The eigenvectors' signs are fixed first (modes.normalise_signs) and the
    scale is signed, so the start is the same on every machine."""
    lam, V = scipy.linalg.eigh(model.K, model.M)
    V = normalise_signs(V)
    rng = np.random.default_rng(seed)
    q = V[:, 0] + noise * V @ rng.standard_normal(model.r) * np.abs(V[:, 0]).max() / np.abs(V).max(axis=0)
    return q * amplitude / q[_le_x(model)]


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
    f[_le_x(ci_rom)] = 20.0                                             # 20 N at node LE along e_x
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
    displacement = +amplitude (towards the casing; the modal-derivative coordinates take their static values: a
    physical start). The scale is signed: eigh returns the 1B vector with either sign depending on the LAPACK
    kernels, and the GNL state under +F is not minus the state under -F (scaling by |V[LE_x, 0]| deflected the
    blade the other way on an AMD machine, where the 0.5 mm tangent ratio was 1.0287 instead of 1.0551)."""
    from rotor37_rom.model.reduced import solve_reduced_static

    lam, V = scipy.linalg.eigh(model.K, model.M)
    q_lin = V[:, 0] * amplitude / V[_le_x(model), 0]
    return solve_reduced_static(model, model.K @ q_lin, [0.5, 1.0])[-1]


@pytest.mark.slow
@pytest.mark.kernels
def test_discrete_energy_nonlinear_bounded(ci_rom):
    """GNL, undamped, released from a static 1B deflection (+0.3 mm at node LE along e_x, ~2 mm tip motion).

    Stress stiffening moves the highest tangent frequency: along +-q0 its first-order change is odd in q, so the
    larger of the two is above the linear omega_max, and the step is 0.98 of the tangent limit at +-q0. The scheme
    is symplectic, so its energy error stays bounded (no secular drift over 5e4 steps: a drift would make the error
    of the last tenth ~10x that of the first, bounded oscillation keeps the ratio ~1; 1.5 separates the two) and is
    an O(h^2) defect of the cubic forces (halving h divides it by 4; 3-5 allows the next-order term). At +0.5 mm
    the tangent frequency exceeds the linear one by more than 1/0.98, so 0.98 of the linear limit is beyond the
    tangent limit and that run must blow up: for GNL the linear limit is not enough."""
    q0 = _static_start(ci_rom, 3e-4)
    w_t = tangent_highest_frequency(ci_rom, np.column_stack([q0, -q0]))
    lin_limit = CentralDifference(ci_rom, nonlinear=False).h_crit
    assert w_t * lin_limit / 2 > 1.0
    scheme = CentralDifference(ci_rom, nonlinear=True, damping=False, h=0.98 * 2 / w_t)
    res = simulate(scheme, 1.0, n_steps=50_000, initial=(q0, q0), record_every=50, energy=True)
    E = res.energy[0][1:]
    err = np.abs(E - E[0]) / E[0]
    tenth = len(err) // 10
    first, last = err[:tenth].max(), err[-tenth:].max()
    print("GNL energy error, first and last tenth:", first, last)
    assert last <= 1.5 * first                                          # bounded, no secular growth
    # O(h^2): the same 2.2 ms at h and h/2 (the start (q0, q0) is the rest state, exact at any step)
    errors = []
    for h in (scheme.h, scheme.h / 2):
        run = simulate(CentralDifference(ci_rom, nonlinear=True, damping=False, h=h), 1.0,
                       n_steps=int(round(10_000 * scheme.h / h)), initial=(q0, q0), record_every=10, energy=True)
        errors.append(np.abs(run.energy[0][1:] / run.energy[0][1] - 1.0).max())
    print("GNL energy error at h and h/2:", errors, "ratio", errors[0] / errors[1])
    assert 3.0 <= errors[0] / errors[1] <= 5.0
    # the GNL run differs from the linear one: the cubic forces change the 1B frequency by an amount of the order of
    # the stiffening measured above, which over 2000 steps moves node LE by more than 1 % of its amplitude
    lin = simulate(CentralDifference(ci_rom, nonlinear=False, damping=False, h=scheme.h), 1.0, n_steps=2000,
                   initial=(q0, q0), record_every=50)
    assert np.abs(_le(lin) - _le(res)[:41]).max() > 1e-2 * abs(q0[_le_x(ci_rom)])
    big = _static_start(ci_rom, 5e-4)
    assert tangent_highest_frequency(ci_rom, np.column_stack([big, -big])) * lin_limit / 2 > 1 / 0.98
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
    # at h = 1.02 h_crit the top mode grows by |z| per step, z the larger root of z^2 - (2 - (h w)^2) z + 1 = 0;
    # from its share of q0 it reaches the 0.02 m blow-up limit within log(0.02 / a) / log|z| steps (+ the check)
    lam, V = scipy.linalg.eigh(ci_rom.K, ci_rom.M)
    hw2 = scheme.h ** 2 * lam[-1]
    z = abs((2 - hw2 - np.sqrt((2 - hw2) ** 2 - 4)) / 2)
    share = abs(V[:, -1] @ ci_rom.M @ q0) * np.abs(V[_boundary_rows(ci_rom), -1]).max()
    n_bound = np.log(0.02 / share) / np.log(z) + 2 * 50
    print(f"diverged at step {res.diverged_step[0]}; growth {z:.3f} per step, bound {n_bound:.0f}")
    assert 0 < res.diverged_step[0] <= n_bound


def test_massless_boundary_variant(ci_rom):
    """Dropping the boundary inertia (Monjaraz Tec et al. 2022) removes the stiff single-node constraint modes:
    h_crit grows > 2x. The scheme solves the massless model exactly: it matches an independent Newmark solution of
    the condensed model (eta'' M_ii + K_c eta = f_i - K_ib K_bb^-1 f_b, u_b = K_bb^-1 (f_b - K_bi eta)) within 1 %.
    The price: the constraint modes of the 24 tip DOFs carry much of the blade's 1B inertia, so the massless model
    answers a point force at node LE differently from the full-inertia ROM (measured, printed; ~18 % on ci)."""
    from rotor37_rom.dynamics.newmark import simulate_linear_newmark

    std = CentralDifference(ci_rom, nonlinear=False, damping=False)
    ml = CentralDifference(ci_rom, nonlinear=False, damping=False, massless_boundary=True)
    print("h_crit standard / massless:", std.h_crit, ml.h_crit)
    K, M = ci_rom.K, ci_rom.M
    b_ = _boundary_rows(ci_rom)
    i_ = np.setdiff1d(np.arange(ci_rom.r), b_)
    Kbb_inv = np.linalg.inv(K[np.ix_(b_, b_)])
    Kc = K[np.ix_(i_, i_)] - K[np.ix_(i_, b_)] @ Kbb_inv @ K[np.ix_(b_, i_)]
    w_c = np.sqrt(scipy.linalg.eigh(Kc, M[np.ix_(i_, i_)], eigvals_only=True)[-1])
    np.testing.assert_allclose(ml.h_crit, 2 / w_c, rtol=1e-9)      # the condensed spectrum, computed apart
    assert ml.h_crit > 2.0 * std.h_crit            # a property of the two spectra (eigh round-off ~1e-12)
    with pytest.raises(ValueError, match="linear model only"):
        CentralDifference(ci_rom, nonlinear=True, massless_boundary=True)
    w, T = 3000.0, 2e-3
    f = np.zeros(ci_rom.r)
    f[_le_x(ci_rom)] = 50.0
    law = lambda t: np.sin(w * t)  # noqa: E731
    b = simulate(ml, 1.0, n_steps=int(T / ml.h), forcing=lambda t: f * law(t), record_every=1)
    fc = f[i_] - K[np.ix_(i_, b_)] @ Kbb_inv @ f[b_]
    dt = 2e-6
    t, eta = simulate_linear_newmark(M[np.ix_(i_, i_)], np.zeros_like(Kc), Kc, lambda t: fc * law(t), dt,
                                     int(T / dt))
    ub = Kbb_inv @ (f[b_, None] * law(t)[None, :] - K[np.ix_(b_, i_)] @ eta)
    ref = ub[list(b_).index(_le_x(ci_rom))]
    got = np.interp(t, b.t[0], _le(b))
    err = np.abs(got - ref).max() / np.abs(ref).max()
    # two discretisations of one model: Newmark's phase error (w dt)^2 / 12 per radian and the central differences'
    # (w h)^2 / 24, over w T ~ 11 rad of the 1B response (w ~ 5.4e3 rad/s), are ~1e-4; 1 % bounds both with the
    # modes up to 20 kHz that carry the response
    print("massless scheme vs condensed Newmark:", err)
    assert err < 0.01
    a = simulate(std, 1.0, n_steps=int(T / std.h), forcing=lambda t: f * law(t), record_every=1)
    full = np.interp(t, a.t[0], _le(a))
    model_error = np.abs(full - ref).max() / np.abs(full).max()
    print("massless vs full-inertia ROM, forced LE response:", model_error)
    assert model_error > 0.01        # a modelling error, above what verifies either scheme: the method's price


@pytest.mark.slow
@pytest.mark.kernels
def test_frequency_cap_mass_scaling(ci_rom):
    """Spectral mass scaling (CentralDifference(frequency_cap=...)): the modes of (K~, M_s) below the cap keep their
    frequency and shape to round-off, the ones above sit at the cap, so h_crit = 2 / cap exactly. The linear scheme
    still conserves its discrete energy, contact stays exact, and, unlike the massless boundary, the point-forced
    LE response at 3000 rad/s stays close to the unscaled ROM: the cap changes only the frequencies of the modes above
    it, whose transients under a 3000 rad/s force are (w / w_i) of their static share at node LE (the bound below
    sums that over the modes, with each scheme's own discrete frequencies).

    Round-off of the eigenvalues of (K, M): relative u lambda_max / lambda_i ~ 1e-16 x 7e5 for the lowest mode, so
    1e-9 on the eigenvalues below the cap and 1e-8 on the residual of their shapes."""
    from rotor37_rom.dynamics.explicit import capped_mass, largest_states

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
    std = CentralDifference(ci_rom, nonlinear=False, damping=False)
    capped = CentralDifference(ci_rom, nonlinear=False, damping=False, frequency_cap=cap, safety=0.98)
    np.testing.assert_allclose(capped.h_crit, 2 / cap, rtol=1e-9)
    np.testing.assert_allclose(capped.h / std.h, (0.98 / 0.9) * std.omega_max / cap, rtol=1e-9)
    assert capped.h > 10 * std.h                   # the spectrum's property: omega_max / cap (eigh round-off)
    # discrete energy of the scaled scheme, free vibration
    q0 = _free_vibration_start(ci_rom)
    res = simulate(capped, 1.0, n_steps=20_000, initial=(q0, q0), record_every=20, energy=True)
    E = res.energy[0][1:]
    assert np.abs(E - E[0]).max() / E[0] <= 1e-10
    # forced LE response: 50 N sin(3000 t) at node LE along e_x, 1 ms from rest
    w, T = 3000.0, 1e-3
    f = np.zeros(ci_rom.r)
    f[_le_x(ci_rom)] = 50.0
    a = simulate(std, 1.0, n_steps=int(T / std.h), forcing=lambda t: f * np.sin(w * t), record_every=1)
    half = CentralDifference(ci_rom, nonlinear=False, damping=False, frequency_cap=cap, safety=0.5)
    assert half.h > 5 * std.h
    b = simulate(half, 1.0, n_steps=int(T / half.h), forcing=lambda t: f * np.sin(w * t), record_every=1)
    ref = _le(a)
    got = np.interp(a.t[0], b.t[0], _le(b))
    err = np.abs(got - ref).max() / np.abs(ref).max()
    # bound by modal superposition (both schemes share the modes' shapes): mode i under F sin(w t) from rest is
    # s_i (sin(w t) - (w / w_i) sin(w_i t)) / (1 - (w / w_i)^2), s_i its static share at LE, and each scheme runs it
    # at its own discrete frequency 2/h asin(h w_i / 2) (the capped one with min(w_i, cap)); two such responses
    # differ by at most the change of the steady part, of the transient's amplitude, and min(2, |dw| T) of it
    shares = np.abs(V[_le_x(ci_rom)] * (V.T @ f) / lam)
    w_i = np.sqrt(lam)
    w_std = 2 / std.h * np.arcsin(std.h * w_i / 2)
    w_cap = 2 / half.h * np.arcsin(half.h * np.minimum(w_i, cap) / 2)
    steady = np.abs(1 / (1 - (w / w_std) ** 2) - 1 / (1 - (w / w_cap) ** 2))
    transient = np.abs(w / w_std - w / w_cap) + np.minimum(2, np.abs(w_std - w_cap) * T) * w / np.minimum(w_std, w_cap)
    bound = (shares * (steady + transient)).sum() / np.abs(ref).max()
    print(f"cap 60 kHz: h {half.h:.3g} vs {std.h:.3g} s, forced LE response error {err:.2e} (bound {bound:.2e})")
    assert err <= bound
    # contact stays exact at the larger step
    gnl = CentralDifference(ci_rom, nonlinear=True, frequency_cap=cap, safety=0.25)
    res = simulate(gnl, [1300.0, 1450.0], Casing(mu=0.15), n_steps=3000, record_every=10)
    assert (res.contact_steps > 0).all() and res.max_penetration.max() <= 1e-12
    assert res.min_multiplier.min() >= 0.0 and res.friction_power.max() < 0.0
    # where it breaks: with GNL, stress stiffening raises the capped modes' tangent frequencies several times over the
    # cap on the states of these runs (from a short unscaled probe run), so 0.5 x 2/cap is beyond the tangent limit
    # there and blows up; the run is flagged at its step, no solver error
    from rotor37_rom.dynamics.explicit import gnl_time_step, probe_states

    T = 5e-3
    states = probe_states(ci_rom, [1300.0, 1450.0], Casing(mu=0.15), duration=T)
    bad_h = CentralDifference(ci_rom, nonlinear=True, frequency_cap=cap, safety=0.5)
    assert tangent_highest_frequency(ci_rom, states, mass=bad_h.M) * bad_h.h > 2.0
    res = simulate(bad_h, [1300.0, 1450.0], Casing(mu=0.15), n_steps=3000, record_every=10, on_blowup="flag")
    assert (res.diverged_step > 0).any()
    # the GNL step from the tangent limit on those states is stable, and the states the run reaches keep it within
    # the tangent limit (checked after the run: self-consistent on any machine)
    h = gnl_time_step(ci_rom, states, cap)
    assert std.h < h < bad_h.h
    scheme = CentralDifference(ci_rom, nonlinear=True, frequency_cap=cap, h=h)
    res = simulate(scheme, [1300.0, 1450.0], Casing(mu=0.15), n_steps=int(np.ceil(T / h)), duration=T,
                   record_every=10, on_blowup="flag", record_q=True)
    print("probe-based GNL step", h, "diverged", res.diverged_step, "pen", res.max_penetration)
    assert (res.diverged_step < 0).all() and res.max_penetration.max() <= 1e-12
    reached = largest_states(res, _boundary_rows(ci_rom), 24)
    assert tangent_highest_frequency(ci_rom, reached, mass=scheme.M) * h < 2.0
    # bad input
    for bad in (0.0, -1.0, float("nan"), 100.0):
        with pytest.raises(ValueError, match="frequency_cap"):
            CentralDifference(ci_rom, nonlinear=False, frequency_cap=bad)
    with pytest.raises(ValueError, match="frequency_cap"):
        CentralDifference(ci_rom, nonlinear=False, frequency_cap=cap, massless_boundary=True)


def test_gnl_step_report_names_the_states_that_set_the_step(ci_rom, capsys):
    """A few states far stiffer than the rest (a St. Venant-Kirchhoff collapse under a point contact: 55 times the
    median tangent frequency on the ci blade at mu = 0.1) set the GNL step alone: ``gnl_step_report`` names them and
    gives the step without them, each equal to ``gnl_time_step`` on the states concerned."""
    from rotor37_rom.dynamics.explicit import (capped_mass, gnl_step_report, gnl_time_step, highest_frequency,
        step_outliers, tangent_highest_frequency)

    assert step_outliers(np.array([1.0, 2.0, 3.0, 100.0])).tolist() == [3]
    assert step_outliers(np.array([1.0, 2.0, 19.0])).size == 0 and step_outliers(np.array([])).size == 0
    rng = np.random.default_rng(0)
    small = 1e-5 * rng.standard_normal((ci_rom.r, 6))
    states = np.hstack([small, 3e3 * small[:, :1]])            # one state with 3,000 times the amplitude
    cap = 2 * np.pi * 120e3
    rep = gnl_step_report(ci_rom, states, cap, safety=0.5)
    w = rep["w_states"]
    assert w[-1] > 10 * np.median(w) and (w[:-1] < 10 * np.median(w)).all()     # the construction holds
    assert rep["outliers"].tolist() == [6]
    M = capped_mass(ci_rom.M, ci_rom.K, cap)                   # the step's definition, written out
    assert rep["h"] == min(0.5 * 2.0 / highest_frequency(M, ci_rom.K),
                           0.5 * 2.0 / tangent_highest_frequency(ci_rom, states, mass=M))
    assert rep["h"] == gnl_time_step(ci_rom, states, cap, safety=0.5)
    assert rep["h_without_outliers"] == gnl_time_step(ci_rom, small, cap, safety=0.5) > rep["h"]
    with pytest.raises(ValueError, match="safety factors"):
        gnl_time_step(ci_rom, states, cap, safety=0.0)
    with pytest.raises(ValueError, match="finite tangent frequencies"):
        gnl_time_step(ci_rom, np.zeros((ci_rom.r, 0)), cap)
    from rotor37_rom.studies import contact_map                # the map's note names them, only when they bind

    contact_map.print_step_outliers(rep)
    note = capsys.readouterr().out
    assert note.startswith("note: 1 of 7 states would set the GNL step") and \
        f"{rep['h_without_outliers'] / rep['h']:.1f} times as many steps" in note
    contact_map.print_step_outliers(gnl_step_report(ci_rom, small, cap, safety=0.5))
    assert capsys.readouterr().out == ""
    # the map's step: from every state (keep, the default) or without the outliers (--step-outliers drop)
    for policy, h, says in (("keep", rep["h"], "times as many steps (--step-outliers drop)"),
                            ("drop", rep["h_without_outliers"], "--step-outliers drop takes the step without them")):
        config = contact_map.ContactMapConfig.from_options(frequency_cap=120.0, step_outliers=policy)
        # the same step up to round-off (the demo's cap in rad/s is 120 kHz converted in another order)
        assert contact_map.capped_gnl_step(config, ci_rom, ci_rom, states) == pytest.approx(h, rel=1e-12)
        out = capsys.readouterr().out
        assert f"h = {h:.3g} s" in out and says in out
    config = contact_map.ContactMapConfig.from_options(frequency_cap=120.0, step_outliers="drop")
    assert contact_map.capped_gnl_step(config, ci_rom, ci_rom, small) == pytest.approx(rep["h_without_outliers"],
                                                                                      rel=1e-12)  # none: as keep


@pytest.mark.parametrize("args, says", [
    (["--step-check", "1840", "1860", "2"], "needs --step-outliers drop"),
    (["--step-outliers", "drop", "--speeds", "1620", "2000", "20", "--step-check", "1850", "1850", "1"],
     "must be speeds of one of the ranges")])
def test_gnl_vs_linear_step_check_bad_input(tmp_path, args, says):
    """benchmarks/bench_gnl_vs_linear.py --step-check: without --step-outliers drop, or at speeds the map does not
    run, one line on stderr naming the option, exit status 2, nothing written; a check grid is valid when it is
    speeds of any one range, also of a later one overlapping an earlier; and the sweeps a map reads are those at its
    step or its retries' (halved), not those of the same map run earlier at another step."""
    import argparse
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    proc = subprocess.run([sys.executable, str(root / "benchmarks" / "bench_gnl_vs_linear.py")] + args, cwd=tmp_path,
                          capture_output=True, text=True, timeout=300)
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and len(lines) == 1 and lines[0].startswith("error: --step-check") and says in lines[0]
    assert not (tmp_path / "results").exists()
    from rotor37_rom.studies.gnl_vs_linear import check_speeds_error, same_step

    ranges = [(1300.0, 1600.0, 4), (1200.0, 1600.0, 21)]      # 1,320 rad/s: the second's, not the first's
    check = argparse.Namespace(step_outliers="drop", gnl="on", step_check=[1320.0, 1320.0, 1.0])
    assert check_speeds_error(check, ranges) is None
    check.step_check = [1330.0, 1330.0, 1.0]
    assert "must be speeds of one of the ranges" in check_speeds_error(check, ranges)
    h = 3.96e-7
    assert same_step(h, h) and same_step(h, h / 2) and same_step(h, h / 4 * (1 + 1e-12))
    assert not same_step(h, 2.11e-8) and not same_step(h, 2 * h) and not same_step(h, h / 3)


def test_linear_rom_matches_full_order_transient(ci_blade, ci_ops, ci_rom):
    """Point force F sin(3000 t) along e_x at node LE from rest, undamped, 2 ms: the linear ROM with central
    differences equals the full-order linear Newmark transient within 1 % (max over time of node LE's e_x)."""
    from rotor37_rom import fem

    F0, w, T = 50.0, 3000.0, 2e-3
    dof = int(ci_blade.tip_dofs[0, 0])
    dt = 5e-6
    fom = fem.solve_repeating_newmark(ci_blade, 1, dof, lambda t: [F0 * np.sin(w * t)], dt, int(T / dt),
                                      nonlinear=False, ops=ci_ops)
    scheme = CentralDifference(ci_rom, nonlinear=False, damping=False)
    fr = np.zeros(ci_rom.r)
    fr[_le_x(ci_rom)] = F0
    every = 1
    rom = simulate(scheme, 1.0, n_steps=int(T / scheme.h) + 1, forcing=lambda t: fr * np.sin(w * t),
                   record_every=every)
    u_rom = np.interp(fom.t, rom.t[0], _le(rom))
    u_fom = fom.tip[:, 0, 0, 0]                                  # node LE (the first tip node), e_x
    err = np.abs(u_rom - u_fom).max() / np.abs(u_fom).max()
    print("linear ROM vs full order (node LE, e_x):", err, "peak", np.abs(u_fom).max())
    assert err < 0.01


@pytest.mark.parametrize("P", [2, 8, 80])
def test_batches_equal_one_by_one(ci_rom, P):
    """P simulations at different speeds, clearances and friction coefficients in one batch equal the same
    simulations run one by one to 1e-8 (relative, node LE), over 1e4 steps with contact.

    A batch multiplies (r, r) by (r, P) (GEMM), a single run by (r, 1) (GEMV): the sums run in another order and
    differ by ~r u = 5e-15 per step; the linear scheme is neutrally stable, so only a contact that starts or ends a
    step earlier in one of the two amplifies that. Measured over the kernel variants of ``make test-kernels``
    (SkylakeX, Haswell and Zen kernels, 1 and 2 BLAS threads): 4e-12 to 5.5e-11; 1e-8 leaves two orders of
    magnitude."""
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
    the two summation orders differ by round-off (~1e-16 relative per step), which 8000 steps with contact grow to
    7.0e-9 to 7.4e-9 over the kernel variants of ``make test-kernels`` (SkylakeX, Haswell, Zen; 1 and 2 threads):
    the growth is the dynamics' (the same for any kernel), the seed is u times a kernel-dependent factor of order
    one, so 1e-6 leaves a factor of more than 100."""
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


@pytest.mark.slow
@pytest.mark.kernels
def test_point_cubature_trained_on_contact_states(ci_blade, ci_rom, tmp_path):
    """Empirical cubature (single quadrature points, non-negative weights) trained on the states of a GNL contact
    run: it reproduces the exact reduced force on the states of a run at another speed, keeps K~ exact, and a
    contact run with it follows the exact one. Weights >= 0 keep the force the gradient of a sum of SVK point
    energies (conservative)."""
    from rotor37_rom.reduction.builder import hyper_reduce
    from rotor37_rom.forces.cubature import state_errors

    scheme = CentralDifference(ci_rom, nonlinear=True, safety=0.5)
    speeds = [1340.0, 1460.0]
    exact = simulate(scheme, speeds, Casing(mu=0.0), n_steps=20_000, record_every=100, record_q=True)
    assert exact.contact_steps.min() > 0
    Q_train, Q_held = exact.records_q[0][:, ::3], exact.records_q[1]
    hr, rep = hyper_reduce(ci_blade, ci_rom, Q_train, tol=1e-3, level="point")
    n_all = rep["exact"].w.size
    Q_held = Q_held[:, np.abs(Q_held[_boundary_rows(ci_rom)]).max(axis=0) > 1e-5]   # in motion
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
    # forces scaled by 1 + the cubature's largest held-out error, a perturbation of the same size. Both deviations are
    # that size times the dynamics' amplification, which does not depend on the machine; 3 allows the cubature's
    # error, which varies with the state, to act up to three times more than a uniform scaling of the same norm
    def deviation(model):
        run = simulate(CentralDifference(model, nonlinear=True, h=scheme.h), speeds[1], Casing(mu=0.0),
                       n_steps=20_000, record_every=100)
        u = _le(exact, 1)
        return np.abs(_le(run) - u).max() / np.abs(u).max()

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
    with pytest.raises(ValueError, match="^Q_train: every training state is zero"):
        hyper_reduce(ci_blade, ci_rom, np.zeros_like(Q_train))
