"""Periodic orbits with nonsmooth forces (#72): Coulomb friction with sticking in harmonic balance (collocated, no
regularisation) against Den Hartog's piecewise closed form; shooting of the project's explicit scheme with the
casing contact (its monodromy, its orbit as the scheme's attractor, its multipliers as the rate at which
perturbations die) and against harmonic balance on the GNL blade."""
import warnings

import numpy as np
import pytest
import scipy.integrate
import scipy.linalg
import scipy.optimize

from rotor37_rom.periodic import (ContactBalance, CoulombFriction, Harmonics, HarmonicBalance, Shooting,
                                  solve_periodic)

# Den Hartog's oscillator x'' + 2 zeta x' + x = f cos(w t) - friction, |friction| <= mu N0, one stop per half cycle
ZETA, F0, MUN, W = 0.05, 1.0, 0.5, 0.5


def den_hartog():
    """The exact stick-slip orbit (Den Hartog, Trans. ASME 53 APM-53-9 (1931) 107-115: the motion is symmetric,
    x(t + T/2) = -x(t), and piecewise the linear oscillator's): the mass sticks at -X until the spring and the
    forcing reach mu N0 (t = 0, the forcing's phase phi: f cos(phi) + X = mu N0), slips with the friction -mu N0
    until its velocity vanishes at x = +X, and sticks there until T/2. (X, phi) solve the two conditions; the slip
    is integrated to 1e-13. Returns x(tau) on ``tau`` = W t of the forcing f cos(W t), and X."""
    T = 2 * np.pi / W

    def slip(X, phi):
        stop = lambda t, y: y[1]
        stop.terminal, stop.direction = True, -1
        return scipy.integrate.solve_ivp(lambda t, y: [y[1], F0 * np.cos(W * t + phi) - MUN - 2 * ZETA * y[1] - y[0]],
                                         (0, T), [-X, 0.0], events=stop, rtol=1e-13, atol=1e-14, dense_output=True)

    with warnings.catch_warnings():                      # fsolve's "not making good progress" at the 1e-14 floor
        warnings.simplefilter("ignore", RuntimeWarning)
        X, phi = scipy.optimize.fsolve(lambda p: [F0 * np.cos(p[1]) + p[0] - MUN, slip(*p).y[0, -1] - p[0]],
                                       [1.0, -0.5], xtol=1e-14)
    s = slip(X, phi)
    ts = s.t[-1]
    stick = np.linspace(ts, T / 2, 200)
    assert 0 < ts < T / 2 and np.abs(F0 * np.cos(W * stick + phi) - X).max() <= MUN + 1e-9   # it does stick

    def x(tau):
        t = np.mod((tau - phi) / W, T)
        sign = np.where(t < T / 2, 1.0, -1.0)
        t = np.where(t < T / 2, t, t - T / 2)
        return sign * np.where(t < ts, s.sol(np.minimum(t, ts))[0], X)

    return x, X


def friction_balance(H, eps=None, sign=1.0):
    basis = Harmonics(H, 4 * H + 4)
    F = np.zeros((basis.size, 1))
    F[1, 0] = F0
    hb = HarmonicBalance([[1.0]], [[2 * ZETA]], [[1.0]], None, F, basis)
    return ContactBalance(hb, [CoulombFriction([[sign]], MUN, eps=eps)]), hb


def test_den_hartog_stick_slip():
    """(c) of #72: the collocated friction law's orbit against Den Hartog's exact stick-slip orbit (one stop of
    ~1.2 rad per half period at W = 0.5, mu N0 = f / 2). The law holds exactly at the 2 H + 1 collocation instants,
    so a stick-slip switch is placed to within one interval 2 pi / (2 H + 1): the RMS error is bounded by X times
    that interval (|dx/dtau| <= X on this orbit) and falls as H grows (measured 5.6e-2 at H = 5, 2.5e-3 at H =
    65; the bound 0.69 and 0.058). The root does not depend on the augmentation eps: the H = 17 orbit solved with
    eps is a root, to round-off, of the equations with 30 eps (no iteration needed). Hill: stable."""
    x_exact, X = den_hartog()
    tau = 2 * np.pi * np.arange(4096) / 4096
    xe = x_exact(tau)
    errors, sol = {}, None
    for H in (5, 9, 17, 33, 65):
        cb, hb = friction_balance(H)
        x0 = np.r_[np.linalg.solve(hb.linear_matrix(W), hb.F.ravel()), np.zeros(hb.basis.size)]
        if sol is not None:                                        # the previous orbit, padded
            X0, L0 = np.zeros((hb.basis.size, 1)), np.zeros((hb.basis.size, 1))
            X0[:len(sol.X)], L0[:len(sol.X)] = sol.X, sol.L[0]
            x0 = np.r_[X0.ravel(), L0.ravel()]
        sol = solve_periodic(cb, x0, W, stability=H == 9, max_iter=60)
        if H == 9:
            assert sol.stable
        errors[H] = np.sqrt(np.mean((Harmonics(H, 4096).synthesis @ sol.X[:, 0] - xe) ** 2))
        assert errors[H] <= X * 2 * np.pi / (2 * H + 1), (H, errors[H])
        if H == 17:
            other, _ = friction_balance(H, eps=30 * cb.laws[0].eps)
            R = other.residual(sol.unknowns, W, jacobian=False)
            assert np.abs(R).max() < 1e-12
    print("RMS errors against Den Hartog:", {H: f"{e:.2e}" for H, e in errors.items()})
    assert errors[65] < errors[5] / 10


def test_friction_law_sign_matters():
    """The friction opposes the slip: with the sign of T flipped the law's force pushes along the velocity, and
    the orbit the balance returns is not Den Hartog's (a wrong friction direction fails)."""
    x_exact, X = den_hartog()
    tau = 2 * np.pi * np.arange(1024) / 1024
    cb, hb = friction_balance(9)
    wrong, _ = friction_balance(9)
    law = wrong.laws[0]
    law.project = lambda lam, V, law=law: _flipped(law, lam, V)
    x0 = np.r_[np.linalg.solve(hb.linear_matrix(W), hb.F.ravel()), np.zeros(hb.basis.size)]
    good = solve_periodic(cb, x0, W, stability=False, max_iter=60)
    err = np.sqrt(np.mean((Harmonics(9, 1024).synthesis @ good.X[:, 0] - x_exact(tau)) ** 2))
    assert err <= X * 2 * np.pi / 19
    try:
        bad = solve_periodic(wrong, x0, W, stability=False, max_iter=60)
    except ValueError:
        return                                               # no orbit at all: the mutation is caught
    err_bad = np.sqrt(np.mean((Harmonics(9, 1024).synthesis @ bad.X[:, 0] - x_exact(tau)) ** 2))
    assert err_bad > X * 2 * np.pi / 19


def _flipped(law, lam, V):
    """The law with the slip's sign reversed (a mutation)."""
    phi, d_lam, d_v = CoulombFriction.project(law, lam, -V)
    return phi, d_lam, -d_v


def test_friction_bad_input():
    with pytest.raises(ValueError, match="friction limit mu N0 must be > 0"):
        CoulombFriction([[1.0]], 0.0)
    with pytest.raises(ValueError, match="eps"):
        CoulombFriction([[1.0]], 1.0, eps=-1.0)
    with pytest.raises(ValueError, match="act on 2 coordinates, the model has 1"):
        ContactBalance(friction_balance(3)[1], [CoulombFriction([[1.0, 0.0]], 1.0)])


# -- shooting the explicit scheme ------------------------------------------------------------------------------------

CAP = 2 * np.pi * 30e3          # a 30 kHz mass scaling: the orbit's claims do not depend on the modes above


@pytest.fixture(scope="module")
def linear_contact(ci_rom):
    """The ci blade's linear scheme (30 kHz cap) rubbing the paper's casing at 0.9 of the 1B/EO4 speed, period
    pi / Omega, and its orbit."""
    from rotor37_rom.dynamics.casing import Casing
    from rotor37_rom.dynamics.explicit import CentralDifference

    w1 = np.sqrt(scipy.linalg.eigh(ci_rom.K, ci_rom.M, eigvals_only=True)[0])
    omega = 2 * 0.9 * w1 / 4
    scheme = CentralDifference(ci_rom, nonlinear=False, frequency_cap=CAP)
    steps = int(np.ceil(2 * np.pi / omega / (0.8 * scheme.h_crit)))
    shooting = Shooting(scheme, Casing(), steps=steps)
    sol = solve_periodic(shooting, np.zeros(shooting.size), omega, tol=1e-10)
    return shooting, sol


def test_shooting_monodromy_is_the_derivative(ci_rom, linear_contact):
    """The tangent marched beside the orbit is the derivative of the period map: central differences in a random
    direction converge to it (h^2, until the contact sets change under the step) on the linear rubbing orbit and on
    a GNL one that touches (exact Jacobian at every step)."""
    from rotor37_rom.dynamics.casing import Casing
    from rotor37_rom.dynamics.explicit import CentralDifference

    shooting, sol = linear_contact
    rng = np.random.default_rng(0)
    z = sol.unknowns
    d = rng.standard_normal(z.size)
    d *= np.abs(z).max() / np.linalg.norm(d)
    _, mono, _ = shooting.march(z, sol.omega)
    e = 1e-7
    fd = (shooting.march(z + e * d, sol.omega, False)[0] - shooting.march(z - e * d, sol.omega, False)[0]) / (2 * e)
    assert np.linalg.norm(fd - mono @ d) <= 1e-6 * np.linalg.norm(mono @ d)
    # d z(T) / d omega marched as the tangent's last column (the operators' change with the step h = T / n)
    dz = shooting.march(z, sol.omega, domega=True)[3]
    w = 1e-6 * sol.omega
    fd = (shooting.march(z, sol.omega + w, False)[0] - shooting.march(z, sol.omega - w, False)[0]) / (2 * w)
    print("d z(T) / d omega against central differences (linear, contact):",
          np.linalg.norm(fd - dz) / np.linalg.norm(dz))
    assert np.linalg.norm(fd - dz) <= 1e-6 * np.linalg.norm(dz)
    # GNL and contact: 1,000 steps of 60 ns (the tangent's stability limit on rubbing states) from a touching state
    h, n = 6e-8, 1000
    gnl = Shooting(CentralDifference(ci_rom, nonlinear=True, h=h), Casing(), steps=n, jacobian_every=16)
    omega = 2 * np.pi / (n * h)
    z = Shooting(CentralDifference(ci_rom, nonlinear=False, h=h), Casing(), steps=3 * n).march(
        np.zeros(z.size), omega / 3, tangent=False)[0]
    zT, mono, _ = gnl.march(z, omega)
    d *= np.abs(z).max() / np.abs(d).max()
    errs = []
    # a contact set that changes within the differences' span leaves an O(e) error (the map's kink), so the steps
    # go down until it shrinks tenfold per step: 0.35, 7.5e-5, 7.6e-7 at 1e-6, 1e-7, 1e-8 (round-off: 4e-7 at 1e-9)
    for e in (1e-7, 1e-8):
        fd = (gnl.march(z + e * d, omega, False)[0] - gnl.march(z - e * d, omega, False)[0]) / (2 * e)
        errs.append(np.linalg.norm(fd - mono @ d) / np.linalg.norm(mono @ d))
    print("GNL + contact monodromy against central differences (1e-7, 1e-8):", errs)
    assert errs[1] < 1e-5 and errs[1] < errs[0] / 30
    dz = gnl.march(z, omega, domega=True)[3]
    errs = []
    for e in (1e-6, 1e-7):                     # a contact set changing within the span: O(e), as above
        fd = (gnl.march(z, omega * (1 + e), False)[0] - gnl.march(z, omega * (1 - e), False)[0]) / (2 * e * omega)
        errs.append(np.linalg.norm(fd - dz) / np.linalg.norm(dz))
    print("GNL + contact d z(T) / d omega against central differences (1e-6, 1e-7):", errs)
    assert max(errs) < 1e-5                    # the monodromy's bound: the Jacobian interpolated on free stretches


def test_shooting_orbit_is_the_schemes_attractor(linear_contact):
    """(d) of #72 on the ci blade rubbing the casing: the shooting orbit is a fixed point of the period map to
    round-off; the project's own ``simulate`` (the maps' loop, not the shooting's) started on it stays on it for
    200 revolutions (400 periods; 1e-9 of the orbit); it is stable (every multiplier inside the unit circle); and a
    perturbation along the least damped Floquet mode dies in ``simulate`` at the rate its multiplier gives, |mu| per
    period (to 2 % over 40 periods: the decay is the orbit's, measured by the integrator that made no use of the
    tangent)."""
    from rotor37_rom.dynamics.explicit import simulate

    shooting, sol = linear_contact
    assert sol.residual < 1e-12 * np.linalg.norm(sol.unknowns) and sol.stable
    scheme = shooting.scheme_at(sol.omega)
    n, casing, speed = shooting.steps, shooting.casing, shooting.speed(sol.omega)
    q0, qm = sol.X
    run = simulate(scheme, speed, casing=casing, revolutions=200, initial=(q0, qm), duration=1e-12,
                   record_every=n, record_q=True)
    assert run.n_steps[0] >= 400 * n                       # the casing's period is half a revolution
    drift = np.abs(run.records_q[0] - q0[:, None]).max() / np.abs(q0).max()
    print(f"200 revolutions of simulate from the shooting orbit: drift {drift:.1e}")
    assert drift < 1e-9
    mu, V = np.linalg.eig(shooting.march(sol.unknowns, sol.omega)[1])
    k = np.argmax(np.abs(mu))
    v = np.real(V[:, k] * np.exp(-1j * np.angle(V[np.argmax(np.abs(V[:, k])), k])))
    dz = 1e-9 * np.abs(sol.unknowns).max() * v / np.abs(v).max()
    periods = 40
    run = simulate(scheme, speed, casing=casing, n_steps=periods * n, initial=(q0 + dz[:q0.size], qm + dz[q0.size:]),
                   duration=1e-12, record_every=n, record_q=True)
    dev = np.linalg.norm(run.records_q[0] - q0[:, None], axis=0)
    rate = np.exp(np.polyfit(np.arange(dev.size)[5:], np.log(dev[5:]), 1)[0])
    print(f"largest multiplier |mu| = {abs(mu[k]):.5f}; the perturbation decays by {rate:.5f} per period")
    assert abs(rate / abs(mu[k]) - 1) < 0.02


def test_unstable_rubbing_orbit_departs_at_its_multiplier(linear_contact):
    """(d) of #72, unstable side: continued by arc length from 0.9 of the 1B/EO4 speed, the rubbing branch of the
    ci blade loses stability through a complex pair of multipliers (Neimark-Sacker: the response becomes
    modulated, not periodic with the rotor); on the first orbit with |mu| > 1.02, a 1e-9 perturbation along that
    Floquet mode grows in ``simulate`` by |mu| per period, its amplitude measured in the pair's invariant plane (to
    1e-3 over 30 periods, before it is large enough to change a contact set)."""
    from rotor37_rom.dynamics.explicit import simulate
    from rotor37_rom.periodic import continue_branch

    shooting, sol = linear_contact
    branch = continue_branch(shooting, sol, 1.15 / 0.9 * sol.omega, step=0.05, tol=1e-9, max_points=30)
    unstable = [p for p in branch.points if np.abs(p.multipliers).max() > 1.02]
    assert unstable and any(kind == "Neimark-Sacker" for _, kind, _ in branch.bifurcations)
    orbit = unstable[0]
    mu, V = np.linalg.eig(shooting.march(orbit.unknowns, orbit.omega)[1])
    k = np.argmax(np.abs(mu))
    plane = np.column_stack([V[:, k].real, V[:, k].imag])            # the pair's invariant plane
    z = orbit.unknowns
    dz = 1e-9 * np.abs(z).max() * plane[:, 0] / np.abs(plane[:, 0]).max()
    q0, qm = orbit.X
    n, periods = shooting.steps, 30
    run = simulate(shooting.scheme_at(orbit.omega), shooting.speed(orbit.omega), casing=shooting.casing,
                   n_steps=periods * n, initial=(q0 + dz[:q0.size], qm + dz[q0.size:]), duration=1e-12,
                   record_q=True)
    Q = run.records_q[0]                                              # every step: q at k n and k n - 1
    dev = np.vstack([Q[:, n::n] - q0[:, None], Q[:, n - 1::n][:, :periods] - qm[:, None]])
    # the perturbation's coordinates (a, b) in the plane: dz_k = Re(c mu^k v), |c mu^k| = |(a, -b)| grows by |mu|
    amp = np.linalg.norm(np.linalg.lstsq(plane, dev, rcond=None)[0], axis=0)
    rate = np.exp(np.polyfit(np.arange(1, periods + 1), np.log(amp), 1)[0])
    print(f"unstable rubbing orbit at Omega = {shooting.speed(orbit.omega):.1f} rad/s: |mu| = {abs(mu[k]):.5f} "
          f"(arg {np.angle(mu[k]):+.3f}); the perturbation grows by {rate:.5f} per period")
    assert abs(rate / abs(mu[k]) - 1) < 1e-3


def test_shooting_equals_harmonic_balance(ci_rom):
    """(e) of #72: on the ci blade's GNL model (exact tensors) forced by 20 N at LE at 0.98 of its 1B frequency, the
    periodic orbit of the explicit scheme (0.9 of its stability limit, ~3,100 steps a period) found by shooting
    (Newton on the period map, from the H = 5 harmonic balance orbit) equals the harmonic balance orbit over the
    whole period to within the truncation error: at most 10 x the share of the last harmonic kept (as in
    test_harmonic_balance; the scheme's own frequency error, (omega h)^2 / 24 ~ 1.8e-7 amplified ~25 x this near
    resonance, is of the same order: measured 1.2e-5 in all). At H = 1 the two differ by far more than H = 5's
    share: the test sees truncation."""
    from rotor37_rom.dynamics.explicit import CentralDifference
    from rotor37_rom.periodic import model_force, time_state

    r = ci_rom.r
    le = int(ci_rom.nodes.q_index[ci_rom.nodes.row("LE"), 0])
    omega = 0.98 * np.sqrt(scipy.linalg.eigh(ci_rom.K, ci_rom.M, eigvals_only=True)[0])
    f = np.zeros(r)
    f[le] = 20.0
    scheme = CentralDifference(ci_rom, nonlinear=True)
    steps = int(np.ceil(2 * np.pi / omega / (0.9 * scheme.h_crit)))
    shooting = Shooting(scheme, forcing=lambda t, w: f * np.cos(w * t), steps=steps, jacobian_every=32)
    h = shooting.scheme_at(omega).h
    orbits = {}
    for H in (1, 5):
        basis = Harmonics(H, 4 * H + 4)
        F = np.zeros((basis.size, r))
        F[1] = f
        hb = HarmonicBalance(scheme.M, ci_rom.C, ci_rom.K, model_force(ci_rom.forces), F, basis)
        x0 = np.zeros(hb.size)
        x0[r:2 * r] = np.linalg.solve(ci_rom.K - omega ** 2 * scheme.M, f)
        orbits[H] = solve_periodic(hb, x0, omega, stability=False)
    X = orbits[5].X
    z0 = np.r_[time_state(X, omega)[0], time_state(X, omega, -omega * h)[0]]
    sol = solve_periodic(shooting, z0, omega, tol=1e-8, stability=False)
    q = shooting.orbit(sol)[:-1]                          # (steps, r) at tau = 2 pi k / steps
    scale = np.abs(q).max()
    norms = np.linalg.norm(X, axis=1)
    last = np.hypot(norms[-2], norms[-1]) / np.linalg.norm(X)
    diff = {H: np.abs(Harmonics(H, steps).synthesis @ orbits[H].X - q).max() / scale for H in (1, 5)}
    print(f"shooting against harmonic balance: H = 1 {diff[1]:.2e}, H = 5 {diff[5]:.2e} (last harmonic's share "
          f"{last:.2e}); Newton {sol.iterations} iterations")
    assert diff[5] <= 10 * last and diff[1] > 100 * last


class _Arctan:
    """R(x) = arctan(x): Newton from |x0| > 1.39 diverges; the residual is not finite past |x| = 3 (as a shooting
    iterate past the scheme's stability limit)."""

    size = 1

    def split(self, x):
        return np.asarray(x, float).reshape(1, 1), ()

    def residual(self, x, omega, jacobian=True, domega=True):
        R = np.arctan(x) if abs(x[0]) <= 3 else np.full(1, np.nan)
        return R if not jacobian else (R, np.array([[1 / (1 + x[0] ** 2)]]), None)

    def floquet_exponents(self, x, omega, J=None):
        return np.zeros(1)


def test_newton_steps_back_from_a_blown_up_iterate():
    """From x0 = 2 Newton's first step lands at -3.54, where the residual is not finite: the step is halved (to
    -0.77, inside Newton's basin |x| < 1.39) and Newton converges to the root; a start whose residual is not finite
    is refused in one line."""
    sol = solve_periodic(_Arctan(), np.array([2.0]), 1.0, tol=1e-12, stability=False)
    assert abs(sol.X[0, 0]) < 1e-12
    with pytest.raises(ValueError, match="not finite"):
        solve_periodic(_Arctan(), np.array([4.0]), 1.0, stability=False)


def test_shooting_residual_of_an_unmarchable_iterate_is_not_finite(linear_contact, monkeypatch):
    """A period whose contact set does not settle (the contact solver's ContactSetError, as a blown-up Newton iterate
    makes it) is a residual that is not finite, not an exception: Newton then steps back, and a start there is
    refused in one line."""
    from rotor37_rom.dynamics.casing import ContactSetError

    shooting, sol = linear_contact
    shooting.scheme_at(sol.omega)

    def cycling(mu, g):
        raise ContactSetError("contact active-set iteration did not converge")

    monkeypatch.setattr(shooting.solver, "solve", cycling)
    R, J, dR = shooting.residual(sol.unknowns, sol.omega)
    assert np.isnan(R).all() and np.isnan(J).all() and np.isnan(dR).all()
    with pytest.raises(ValueError, match="not finite"):
        solve_periodic(shooting, sol.unknowns, sol.omega)


def test_shooting_bad_input(ci_rom):
    from rotor37_rom.dynamics.casing import Casing
    from rotor37_rom.dynamics.explicit import CentralDifference

    scheme = CentralDifference(ci_rom, nonlinear=False, frequency_cap=CAP)
    with pytest.raises(ValueError, match="m \\(the period in bump passings"):
        Shooting(scheme, Casing(), m=0)
    with pytest.raises(ValueError, match="steps \\(per period\\) must be an integer >= 2"):
        Shooting(scheme, Casing(), steps=1)
    with pytest.raises(ValueError, match="needs an excitation"):
        Shooting(scheme)
    from rotor37_rom.periodic import PeriodicProblem

    assert isinstance(Shooting(scheme, Casing()), PeriodicProblem)
    with pytest.raises(ValueError, match="periods \\(of the transient from rest\\) must be an integer >= 1"):
        Shooting(scheme, Casing(), steps=4000).from_rest(2 * 1220.0, 0)
    with pytest.raises(ValueError, match="exceeds the scheme's stability limit"):
        Shooting(scheme, Casing(), steps=10).scheme_at(100.0)


def test_monodromy_products_and_arnoldi_multipliers_are_the_dense_ones(linear_contact):
    """#88 item 1: the monodromy applied to a block by ``monodromy_products`` is the dense monodromy's product to
    round-off (the same recurrence on k columns instead of 2 r), and Arnoldi on those products
    (``leading_multipliers``) finds the multipliers of largest modulus of the dense monodromy (the ci blade's rubbing
    orbit), each within 1e-8 of one of them (ARPACK's 1e-10 relative residual)."""
    shooting, sol = linear_contact
    z = sol.unknowns
    zT, mono, _ = shooting.march(z, sol.omega)
    zT2, apply = shooting.monodromy_products(z, sol.omega)
    V = np.random.default_rng(88).standard_normal((z.size, 3))
    assert np.array_equal(zT, zT2)
    assert np.abs(apply(V) - mono @ V).max() <= 1e-12 * np.abs(mono).max() * np.abs(V).max() * z.size
    dense = np.linalg.eigvals(mono)
    dense = dense[np.argsort(-np.abs(dense))]
    found = shooting.leading_multipliers(z, sol.omega, k=6)
    assert np.allclose(np.abs(found), np.abs(dense[:6]), rtol=0, atol=1e-8)
    assert all(np.abs(dense - mu).min() <= 1e-8 for mu in found)
    with pytest.raises(ValueError, match="k \\(the multipliers wanted\\)"):
        shooting.leading_multipliers(z, sol.omega, k=0)
    with pytest.raises(ValueError, match="tol"):
        shooting.leading_multipliers(z, sol.omega, tol=0.0)


def test_newton_krylov_finds_the_dense_newtons_orbit(linear_contact):
    """#88 item 1: Newton-Krylov (GMRES on the monodromy's products, ``solve_periodic_krylov``) from rest converges to
    the orbit dense Newton found (both to 1e-10 on the update; the orbits agree to 1e-8 of their size, the Newton
    tolerance times the conditioning of M - I of a damped orbit), with the same stability and the same leading
    multipliers (1e-8); bad input is refused in one line."""
    from rotor37_rom.periodic import solve_periodic_krylov

    shooting, sol = linear_contact
    nk = solve_periodic_krylov(shooting, np.zeros(shooting.size), sol.omega, tol=1e-10, krylov_tol=1e-8)
    assert np.abs(nk.unknowns - sol.unknowns).max() <= 1e-8 * np.abs(sol.unknowns).max()
    assert nk.stable == sol.stable and nk.residual <= 1e-8 * np.abs(sol.unknowns).max()
    dense = np.sort(np.abs(sol.multipliers))[::-1][:6]
    assert np.allclose(np.sort(np.abs(nk.multipliers))[::-1], dense, rtol=0, atol=1e-8)
    for kwargs, word in (({"krylov_tol": 0.0}, "krylov_tol"), ({"multipliers": shooting.size}, "multipliers"),
                         ({"x0": np.zeros(3)}, "x0"), ({"omega": -1.0}, "omega")):
        args = {"x0": np.zeros(shooting.size), "omega": sol.omega, **kwargs}
        with pytest.raises(ValueError, match=word):
            solve_periodic_krylov(shooting, **args)
