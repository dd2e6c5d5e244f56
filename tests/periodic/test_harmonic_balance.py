"""Harmonic balance, Hill stability and arc-length continuation (``rotor37_rom.periodic``, #72) on the Duffing
oscillator x'' + 2 zeta x' + x + gamma x^3 = F cos(omega t), whose one-harmonic solution is closed-form:
A^2 [(1 - omega^2 + 3/4 gamma A^2)^2 + (2 zeta omega)^2] = F^2, backbone omega^2 = 1 + 3/4 gamma A^2 (and exactly, with
all harmonics, the elliptic-function solution); then on the ci blade's reduced model against the explicit scheme."""
import numpy as np
import pytest
import scipy.integrate
import scipy.optimize
import scipy.special

from rotor37_rom.periodic import (Harmonics, HarmonicBalance, backbone, bifurcation_kind, continue_branch,
                                  solve_periodic, time_state)

ZETA, GAMMA, F0 = 0.02, 0.1, 0.05       # hardening, peak amplitude ~1.25, bistable between ~1.046 and ~1.054 rad/s


def duffing(H: int, gamma: float = GAMMA) -> HarmonicBalance:
    """The Duffing oscillator's harmonic balance with H harmonics; 4 H + 4 samples: no aliasing of the cubic."""
    basis = Harmonics(H, 4 * H + 4)
    F = np.zeros((basis.size, 1))
    F[1, 0] = F0

    def force(Q):
        return gamma * Q ** 3, (3 * gamma * Q.T ** 2)[:, :, None]

    return HarmonicBalance([[1.0]], [[2 * ZETA]], [[1.0]], force, F, basis)


def one_harmonic(A, omega, gamma=GAMMA):
    """The closed form's residual A^2 [(1 - w^2 + 3/4 g A^2)^2 + (2 zeta w)^2] - F^2."""
    return A ** 2 * ((1 - omega ** 2 + 0.75 * gamma * A ** 2) ** 2 + (2 * ZETA * omega) ** 2) - F0 ** 2


def rhs(omega, gamma=GAMMA):
    return lambda t, y: [y[1], F0 * np.cos(omega * t) - 2 * ZETA * y[1] - y[0] - gamma * y[0] ** 3]


def padded(sol, H):
    """A solution's coefficients with zeros up to H harmonics (a start for a larger basis)."""
    X = np.zeros((2 * H + 1, sol.X.shape[1]))
    X[:min(len(sol.X), len(X))] = sol.X[:len(X)]
    return X.ravel()


@pytest.fixture(scope="module")
def branch():
    hb = duffing(1)
    start = solve_periodic(hb, np.r_[0.0, F0 / 0.75, 0.0], 0.5)
    return hb, continue_branch(hb, start, 1.5, step=0.02)


def test_fourier_basis():
    """The DFT inverts the synthesis (P E = I) and D is d/dtau, exactly (round-off)."""
    basis = Harmonics(5, 23)
    E, P, D = basis.synthesis, basis.analysis, basis.derivative
    np.testing.assert_allclose(P @ E, np.eye(11), atol=1e-14)
    X = np.random.default_rng(0).standard_normal((11, 3))
    tau = basis.tau
    dq = sum(h * (-X[2 * h - 1] * np.sin(h * tau)[:, None] + X[2 * h] * np.cos(h * tau)[:, None])
             for h in range(1, 6))
    np.testing.assert_allclose(E @ (D @ X), dq, atol=1e-13)
    for H, n in ((-1, 8), (2, 4), (1.5, 8)):
        with pytest.raises(ValueError):
            Harmonics(H, n)


def test_jacobian_taylor():
    """The residual's Jacobian in x and omega (AFT through the cubic force) passes the Taylor test: the remainder
    falls 4x when the step halves (second order)."""
    hb = duffing(3)
    rng = np.random.default_rng(1)
    x, d = rng.standard_normal(hb.size), rng.standard_normal(hb.size)
    R, J, dRw = hb.residual(x, 1.1)
    rem = [np.linalg.norm(hb.residual(x + e * d, 1.1 + e, jacobian=False) - R - e * (J @ d + dRw))
           for e in (1e-3, 5e-4, 2.5e-4)]
    for a, b in zip(rem, rem[1:]):
        assert 3.9 < a / b < 4.1


def test_one_harmonic_is_the_closed_form(branch):
    """With H = 1 (and no aliasing) harmonic balance is the closed form: every point of the continued branch
    satisfies it to round-off; the continuation passes both folds, which lie where the closed form's do (between
    the two points around each, whose omega differ by less than a step), and the stability from Hill's method
    changes exactly at them (a real Floquet exponent crosses 0 where the Jacobian is singular): the middle branch
    is unstable, the others stable."""
    hb, br = branch
    A = np.array([np.hypot(*p.X[1:3, 0]) for p in br.points])
    assert np.abs(one_harmonic(A, br.omega)).max() <= 1e-9 * F0 ** 2        # the corrector's 1e-10, conditioned
    assert br.ended.startswith("reached") and len(br.folds) == 2

    def fold(guess):                                 # dF/dA = 0 on F = 0: a vertical tangent of the curve
        def eqs(v):
            a, w = v
            return [one_harmonic(a, w), (one_harmonic(a * (1 + 1e-7), w) - one_harmonic(a * (1 - 1e-7), w))
                    / (2e-7 * a)]
        return scipy.optimize.fsolve(eqs, guess, xtol=1e-13)

    for i, turn in zip(br.folds, (max, min)):         # the upper fold turns back (omega's largest), the lower one
        a, w = fold([0.5 * (A[i - 1] + A[i]), 0.5 * (br.omega[i - 1] + br.omega[i])])
        near = turn(br.omega[i - 1], br.omega[i])
        print(f"fold: closed form {w:.6f} rad/s, continuation's points {br.omega[i - 1]:.6f}, {br.omega[i]:.6f}")
        assert abs(w - near) <= abs(br.omega[i] - br.omega[i - 1]) + 1e-9
        assert (w - near) * (1 if turn is max else -1) > -1e-12        # the fold is the extreme of the two
    stable = np.array([p.stable for p in br.points])
    changes = np.flatnonzero(stable[1:] != stable[:-1]) + 1
    assert changes.tolist() == br.folds
    assert stable[:br.folds[0]].all() and not stable[br.folds[0]:br.folds[1]].any() and stable[br.folds[1]:].all()
    # the bifurcations the branch reports: the same two, each a real multiplier through +1
    assert [b[0] for b in br.bifurcations] == br.folds
    assert all(kind == "fold" and abs(mu.imag) < 1e-9 and mu.real > 1 for _, kind, mu in br.bifurcations)
    assert [bifurcation_kind(m) for m in (1.02, -1.02, 1.02 * np.exp(1j))] == ["fold", "period doubling",
                                                                               "Neimark-Sacker"]


def test_harmonics_converge_to_the_time_integrations_orbit(branch):
    """On the upper branch at omega = 1.03: the odd harmonics (the cubic and the forcing are odd) converge
    geometrically, each pair of harmonics added dividing the error by > 10 (the third harmonic's share is ~ gamma
    A^2 / 36 ~ 4e-3 of the first's here); the H = 9 orbit is the orbit of the converged time integration (DOP853,
    rtol 1e-12): one period from its state returns to it within 1e-8 of the amplitude. At omega = 0.8 (one orbit
    only) a time integration from rest ends on it (300 periods: the transient is e^-47 of its start): its state at
t = 300 T within 1e-7 of the amplitude (the integration's tolerance 1e-11, summed over the run)."""
    _, br = branch
    upper = [p for p in br.points[:br.folds[0]] if p.omega <= 1.03][-1]
    orbits = {}
    sol = upper
    for H in (1, 3, 5, 7, 9, 11):
        hb = duffing(H)
        sol = solve_periodic(hb, padded(sol, H), 1.03, stability=False)
        orbits[H] = sol
    amp = {H: s.amplitude(0, Harmonics(H, 4 * H + 4)) for H, s in orbits.items()}
    errors = [abs(amp[H] - amp[11]) for H in (1, 3, 5, 7)]
    print("amplitude error against H = 11:", errors)
    for a, b in zip(errors, errors[1:]):
        assert b < a / 10
    (x0,), (v0,) = time_state(orbits[9].X, 1.03)
    T = 2 * np.pi / 1.03
    run = scipy.integrate.solve_ivp(rhs(1.03), (0, T), [x0, v0], method="DOP853", rtol=1e-12, atol=1e-14)
    assert np.abs(run.y[:, -1] - [x0, v0]).max() <= 1e-8 * amp[9]
    hb = duffing(9)
    low = solve_periodic(hb, np.r_[0.0, F0 / 0.36, np.zeros(hb.size - 2)], 0.8, stability=False)
    T = 2 * np.pi / 0.8
    run = scipy.integrate.solve_ivp(rhs(0.8), (0, 300 * T), [0.0, 0.0], method="DOP853", rtol=1e-11, atol=1e-13)
    state = np.ravel(time_state(low.X, 0.8))        # the orbit's state at t = 300 T (phase 0 of the forcing)
    np.testing.assert_allclose(run.y[:, -1], state, rtol=0, atol=1e-7 * low.amplitude(0, hb.basis))


def test_the_unstable_orbit_departs_at_its_floquet_rate(branch):
    """The middle branch's orbit at omega = 1.05 (H = 9) has one real Floquet multiplier > 1: started on the orbit
    plus 1e-9, the time integration's stroboscopic distance to the orbit grows per period by that multiplier once
    the other one's share has died out (0.75^30 ~ 2e-4 of it after 30 periods), within 1 %."""
    _, br = branch
    middle = min(br.points[br.folds[0]:br.folds[1]], key=lambda p: abs(p.omega - 1.05))
    sol = middle
    for H in (3, 5, 7, 9):
        sol = solve_periodic(duffing(H), padded(sol, H), middle.omega)
    assert not sol.stable
    mu = sol.multipliers
    grow = mu[np.argmax(np.abs(mu))]
    assert abs(grow.imag) < 1e-9 and grow.real > 1.01
    w, T = sol.omega, 2 * np.pi / sol.omega
    y0 = np.ravel(time_state(sol.X, w))
    run = scipy.integrate.solve_ivp(rhs(w), (0, 40 * T), y0 + [1e-9, 0.0], method="DOP853", rtol=1e-13, atol=1e-15,
                                    t_eval=np.arange(41) * T)
    dist = np.linalg.norm(run.y.T - y0, axis=1)
    rates = dist[1:] / dist[:-1]
    print("per-period growth", rates[-10:], "multipliers", mu)
    np.testing.assert_allclose(rates[-10:], grow.real, rtol=1e-2)


def test_backbone_is_the_closed_form_and_the_elliptic_one():
    """The undamped Duffing oscillator's backbone (its nonlinear normal mode: cosine-only orbits, a_1 given, omega
    solved): with H = 1 it is omega^2 = 1 + 3/4 gamma A^2 to round-off; with more harmonics it converges to the exact
    backbone, x = X cn(omega_0 t, m) with omega_0^2 = 1 + gamma X^2, m = gamma X^2 / (2 omega_0^2) and omega = pi
    omega_0 / (2 K(m)) (X the largest displacement), geometrically: each step H = 3, 5, 9 divides the error by more
    than 10 (measured 1.2e-4, 2.1e-6, 6.3e-10 over A = 0.1 ... 3) and at H = 15 the truncation is below round-off
    (measured 3e-15; 1e-12 asserted)."""
    amplitudes = np.linspace(0.1, 3.0, 30)

    def free(H):
        hb = duffing(H)
        return HarmonicBalance(hb.M, 0 * hb.C, hb.K, hb.force, 0 * hb.F, hb.basis)

    errors = []
    for H in (1, 3, 5, 9, 15):
        hb = free(H)
        x0 = np.zeros(hb.size)
        x0[1] = amplitudes[0]
        orbits = backbone(hb, 0, amplitudes, x0, 1.0)
        omega = np.array([o.omega for o in orbits])
        if H == 1:
            np.testing.assert_allclose(omega ** 2, 1 + 0.75 * GAMMA * amplitudes ** 2, rtol=1e-13)
            continue
        X = np.array([time_state(o.X, o.omega)[0][0] for o in orbits])          # x(0): the largest displacement
        omega0 = np.sqrt(1 + GAMMA * X ** 2)
        exact = np.pi * omega0 / (2 * scipy.special.ellipk(GAMMA * X ** 2 / (2 * omega0 ** 2)))
        errors.append(np.abs(omega / exact - 1).max())
    print("backbone error against the elliptic solution, H = 3, 5, 9, 15:", errors)
    assert errors[1] < errors[0] / 10 and errors[2] < errors[1] / 10 and errors[3] < 1e-12
    with pytest.raises(ValueError, match="undamped and unforced"):
        backbone(duffing(1), 0, [0.1], np.zeros(3), 1.0)


def test_bad_input():
    """A step <= 0 is refused; a Newton that does not converge says so in one line."""
    hb = duffing(1)
    start = solve_periodic(hb, np.r_[0.0, F0 / 0.75, 0.0], 0.5)
    with pytest.raises(ValueError, match="step must be > 0"):
        continue_branch(hb, start, 1.5, step=0.0)
    with pytest.raises(ValueError, match="did not converge in 2 iterations at omega = 1.05"):
        solve_periodic(duffing(3), np.full(7, 3.0), 1.05, max_iter=2)
    from rotor37_rom.periodic import PeriodicProblem

    assert isinstance(hb, PeriodicProblem)

    class BlowsUp(type(hb)):                          # a residual past the floating-point range: stop at once
        def residual(self, x, omega, jacobian=True, domega=True):
            R, J, dR = super().residual(x, omega, jacobian, domega)
            return R * np.inf, J, dR

    blows = BlowsUp.__new__(BlowsUp)
    blows.__dict__.update(hb.__dict__)
    with pytest.raises(ValueError, match="residual is not finite at omega = 0.5 after 0 Newton iterations"):
        solve_periodic(blows, start.unknowns, 0.5)


def test_newton_stops_at_the_round_off_floor():
    """A tolerance no update can meet (0) ends a smooth balance's Newton at its round-off floor (the residual no
    longer falls, the update below 1e-6) on the orbit a met tolerance gives, to round-off; a balance that does not
    declare itself smooth (friction: a stagnating semismooth Newton may be a contact set that cycles) still says it
    did not converge."""
    hb = duffing(5)
    met = solve_periodic(hb, np.zeros(hb.size), 1.02, tol=1e-12)
    floor = solve_periodic(hb, np.zeros(hb.size), 1.02, tol=0.0)
    assert floor.iterations > met.iterations
    assert np.abs(floor.X - met.X).max() <= 1e3 * np.finfo(float).eps * np.abs(met.X).max()

    class NotSmooth:                                  # the same balance, not declared smooth
        def __init__(self, inner):
            self.inner, self.basis, self.n, self.size = inner, inner.basis, inner.n, inner.size

        def residual(self, *args, **kwargs):
            return self.inner.residual(*args, **kwargs)

    with pytest.raises(ValueError, match="did not converge in 30 iterations"):
        solve_periodic(NotSmooth(hb), np.zeros(hb.size), 1.02, tol=0.0, stability=False)


def test_the_reduced_blades_orbit_is_the_explicit_schemes(ci_rom):
    """Harmonic balance on the ci blade's r = 45 model with its exact cubic tensors (AFT; no contact), forced by
    20 N along e_x at node LE at 0.98 of its 1B frequency: started on the H-harmonic orbit, the project's own
    explicit scheme (central differences, nonlinear, with the model's damping; the step from 0.5 of its stability
    limit rounded to a whole number per period, ~5,500 steps) returns after one period to within the truncation
    error of the orbit: at most 10 x the share of its last harmonic (the coefficients decay geometrically, so the
    first neglected ones are below the last kept), falling from 6e-3 (H = 1) to 4e-6 (H = 5) relative; the orbit is
    stable (Hill)."""
    import scipy.linalg

    from rotor37_rom.dynamics.explicit import CentralDifference, simulate
    from rotor37_rom.periodic import model_force, time_state

    model = ci_rom
    r = model.r
    le = int(model.nodes.q_index[model.nodes.row("LE"), 0])
    omega = 0.98 * np.sqrt(scipy.linalg.eigh(model.K, model.M, eigvals_only=True)[0])
    T = 2 * np.pi / omega
    f = np.zeros(r)
    f[le] = 20.0
    n = int(round(T / CentralDifference(model, nonlinear=True, safety=0.5).h))
    scheme = CentralDifference(model, nonlinear=True, h=T / n)
    sol, errors = None, {}
    for H in (1, 2, 3, 4, 5):
        basis = Harmonics(H, 4 * H + 4)
        F = np.zeros((basis.size, r))
        F[1] = f
        hb = HarmonicBalance(model.M, model.C, model.K, model_force(model.forces), F, basis)
        x0 = padded(sol, H) if sol is not None else np.r_[np.zeros(r), f / np.diag(model.K), np.zeros(r)]
        sol = solve_periodic(hb, x0, omega, stability=H == 5)
        if H in (1, 3, 5):
            q0, _ = time_state(sol.X, omega)
            q_prev, _ = time_state(sol.X, omega, -omega * scheme.h)
            run = simulate(scheme, 1.0, n_steps=n, initial=(q0, q_prev), forcing=lambda t: f * np.cos(omega * t),
                           record_every=n, record_q=True)
            errors[H] = np.abs(run.records_q[0][:, -1] - q0).max() / np.abs(q0).max()
            norms = np.linalg.norm(sol.X, axis=1)
            last = np.hypot(norms[-2], norms[-1]) / np.linalg.norm(sol.X)
            print(f"H = {H}: one period of the explicit scheme from the orbit returns within {errors[H]:.2e}; "
                  f"last harmonic's share {last:.2e}")
            if H > 1:
                assert errors[H] <= 10 * last
    assert errors[5] < errors[3] < errors[1] and errors[5] < 1e-4 and sol.stable
