"""The damping law the full order and the reduced models share (``dynamics.damping``) and the steady-state verdict
(``post.steady``), issue #86: Woodbury against a direct solve (round-off), the law's modes decaying at their ratio
(Newmark's second order), the modes above it untouched (energy to round-off), its projection on the modes exact,
and the verdict on signals whose answer is known in closed form."""
import numpy as np
import pytest
import scipy.linalg
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from rotor37_rom.dynamics.damping import LowRankDamping, ModalLaw, damping_law, woodbury
from rotor37_rom.dynamics.newmark import Newmark
from rotor37_rom.post.steady import poincare_section, revolution_maxima, steadiness


def _chain(n=12):
    """A fixed-free spring-mass chain (dense M, K) and its M-orthonormal modes."""
    K = 2.0e6 * np.eye(n) - 1.0e6 * (np.eye(n, k=1) + np.eye(n, k=-1))
    K[-1, -1] = 1.0e6
    M = np.diag(np.linspace(1.0, 2.0, n))
    lam, phi = scipy.linalg.eigh(K, M)
    return M, K, np.sqrt(lam), phi


def test_woodbury_solves_the_sum_to_round_off():
    rng = np.random.default_rng(0)
    n, m = 300, 7
    A = sp.random(n, n, density=0.02, random_state=1)
    A = (A @ A.T + 10.0 * sp.identity(n)).tocsc()
    U, d = rng.standard_normal((n, m)), np.r_[rng.uniform(0.5, 2.0, m - 2), 0.0, 3.0]
    lu = spla.splu(A)
    solve = woodbury(lu.solve, U, d)
    B = rng.standard_normal((n, 3))
    exact = np.linalg.solve(A.toarray() + (U * d) @ U.T, B)
    cond = np.linalg.cond(A.toarray() + (U * d) @ U.T)
    tol = 100 * np.finfo(float).eps * cond                       # backward-stable solves: u cond(A)
    assert np.linalg.norm(solve(B) - exact) <= tol * np.linalg.norm(exact)
    assert np.linalg.norm(solve(B[:, 0]) - exact[:, 0]) <= tol * np.linalg.norm(exact[:, 0])


def test_low_rank_damping_is_its_dense_matrix_and_projects_onto_the_modes_exactly():
    M, K, omega, phi = _chain()
    law = ModalLaw(low=0.01, high=0.03, n_low=2, n_modes=5)
    C = law.operator(M, omega, phi)
    x = np.arange(12.0)
    assert np.allclose(C @ x, C.dense() @ x, rtol=1e-13, atol=0)
    # on the modes: diag(2 xi omega) for the first five, zero above (M-orthogonality)
    expected = np.diag(np.r_[2 * 0.01 * omega[:2], 2 * 0.03 * omega[2:5], np.zeros(7)])
    assert np.abs(C.project(phi) - expected).max() <= 1e-12 * np.abs(expected).max()
    # with K: the same ratios on the first five, xi = 0.03 omega / omega_5 above (stiffness proportional)
    CK = law.operator(M, omega, phi, K)
    assert np.allclose(CK @ x, CK.dense() @ x, rtol=1e-12, atol=0)
    xi = np.r_[0.01, 0.01, 0.03, 0.03, 0.03, 0.03 * omega[5:] / omega[4]]
    assert np.abs(CK.project(phi) - np.diag(2 * xi * omega)).max() <= 1e-12 * 2 * xi.max() * omega.max()


def _free_decay(M, K, C, x0, h, n_steps):
    """Newmark (average acceleration) free vibration from (x0, 0): the displacement history (n_steps + 1, n)."""
    solve = (lambda A: (lambda B, lu=scipy.linalg.lu_factor(A): scipy.linalg.lu_solve(lu, B)))
    nm = Newmark(M, lambda x: K @ x, lambda x: K, solve, lambda t: np.zeros(len(x0)), C=C, linear=True,
                 rtol=1e-13, history_scale=True)
    x, v = x0.copy(), np.zeros_like(x0)
    a = -np.linalg.solve(M, K @ x0)
    out = [x]
    for k in range(1, n_steps + 1):
        x, v, a, _, _ = nm.step(x, v, a, k * h, h)
        out.append(x)
    return np.array(out)


def test_a_damped_mode_decays_at_its_ratio_to_second_order_in_the_step():
    """Mode 1 under the law: x(t) = phi_1 e^(-xi w t) (cos w_d t + xi w / w_d sin w_d t); Newmark's error after
    three periods falls 4 times when h halves (second order), through the Woodbury solve of A + c C."""
    M, K, omega, phi = _chain()
    law = ModalLaw(low=0.05, high=0.03, n_low=2, n_modes=5)
    C = law.operator(M, omega, phi)
    w, xi = omega[0], 0.05
    wd = w * np.sqrt(1 - xi ** 2)
    T = 2 * np.pi / w
    errors = []
    for n_per in (160, 320, 640):
        h = T / n_per
        hist = _free_decay(M, K, C, phi[:, 0], h, 3 * n_per)
        t = 3 * T
        exact = phi[:, 0] * np.exp(-xi * w * t) * (np.cos(wd * t) + xi * w / wd * np.sin(wd * t))
        errors.append(np.linalg.norm(hist[-1] - exact) / np.linalg.norm(phi[:, 0]))
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(rates - 2.0) < 0.05), (errors, rates)
    # the same run with the dense C: the Woodbury path changes nothing but round-off (with beta K too)
    C = law.operator(M, omega, phi, K)
    dense = _free_decay(M, K, C.dense(), phi[:, 0], T / 40, 120)
    assert np.abs(_free_decay(M, K, C, phi[:, 0], T / 40, 120) - dense).max() <= 1e-12


def test_modes_above_the_law_keep_their_energy():
    """Mode 8 is not among the law's 5: C phi_8 = 0, and average acceleration conserves its energy to round-off."""
    M, K, omega, phi = _chain()
    C = ModalLaw(low=0.05, high=0.05, n_low=2, n_modes=5).operator(M, omega, phi)
    h = 2 * np.pi / omega[7] / 30
    hist = _free_decay(M, K, C, phi[:, 7], h, 300)
    strain = 0.5 * np.einsum("ki,ij,kj->k", hist, K, hist)
    assert strain.max() <= 0.5 * omega[7] ** 2 * (1 + 1e-10)       # never above the initial energy
    assert strain.max() >= 0.5 * omega[7] ** 2 * (1 - 0.02)         # and it comes back to it (sampling)


def test_full_order_law_damps_1b_at_its_ratio(ci_blade, ci_ops):
    from rotor37_rom.fem.periodic import RepeatingSectors

    system = RepeatingSectors(ci_blade, 1, ci_ops)
    law = damping_law("heavy")
    C = system.damping(law)
    omega, phi = system.modes(law.n_modes)
    Cphi, Mphi = C @ phi[:, 0], system.M @ phi[:, 0]
    assert np.linalg.norm(Cphi - 2 * 0.02 * omega[0] * Mphi) <= 1e-9 * np.linalg.norm(Cphi)
    assert 800 < omega[0] / (2 * np.pi) < 900                      # the ci blade's 1B (862 Hz)
    # a basis in the blade's DOFs sees the same operator
    P = system.maps[0]
    assert np.allclose(system.project_damping(law, P @ phi[:, :3]), np.diag(2 * 0.02 * omega[:3]), rtol=1e-9,
                       atol=1e-9 * omega[2])
    with pytest.raises(ValueError, match="vanish on the clamped"):
        system.project_damping(law, np.ones((ci_blade.n_dofs, 1)))


@pytest.mark.parametrize("kwargs, word", [({"low": -0.1}, "low"), ({"high": 1.0}, "high"),
                                          ({"n_modes": 0}, "n_modes"), ({"n_low": 9, "n_modes": 5}, "n_low"),
                                          ({"low": float("nan")}, "low"), ({"n_modes": 2.5}, "n_modes")])
def test_bad_damping_laws_are_refused(kwargs, word):
    with pytest.raises(ValueError, match=word):
        ModalLaw(**kwargs)


def test_unknown_law_and_bad_operators_are_refused():
    with pytest.raises(ValueError, match="damping law must be one of maps, heavy"):
        damping_law("rayleigh")
    with pytest.raises(ValueError, match="U must be"):
        LowRankDamping(np.ones((4, 2)), np.ones(3))
    with pytest.raises(ValueError, match="U and d must be finite"):
        LowRankDamping(np.ones((4, 2)), np.array([1.0, np.nan]))
    with pytest.raises(ValueError, match="S must be"):
        LowRankDamping(np.ones((4, 2)), np.ones(2), np.eye(3))
    M, K, omega, phi = _chain()
    with pytest.raises(ValueError, match="n_modes = 20"):
        ModalLaw().operator(M, omega, phi)                            # 12 modes for a law of 20


def _revolutions(signal, omega=1000.0, n_rev=12, per=400):
    T = 2 * np.pi / omega
    t = np.arange(n_rev * per + 1) * T / per
    return t, signal(t, T)


def test_a_decaying_transient_is_steady_where_the_closed_form_says():
    """u = (1 + e^(-t/tau)) sin(8 pi t / T) (never zero at the crests): max over revolution k is 1 + e^(-k T/tau)
    (the first crest of the revolution, to the sampling's O((2 pi / per)^2)), its change e^(-k T/tau)(1 - e^(-T /
    tau)) / (1 + e^(-kT/tau)) falls below 2 % from a revolution known in closed form."""
    tau_rev = 2.0
    t, u = _revolutions(lambda t, T: (1 + np.exp(-t / (tau_rev * T))) * np.sin(8 * np.pi * t / T + 0.3))
    v = steadiness(t, u, 1000.0, tolerance=0.02, window=2)
    k = np.arange(12)
    m = 1 + np.exp(-(k + 1 / 16 - 0.3 / (8 * np.pi)) / tau_rev)    # at each revolution's first crest
    assert np.allclose(v.maxima, m, rtol=1e-3)
    change = np.abs(np.diff(m)) / m[:-1]
    assert v.steady and v.revolution == int(np.argmax(change < 0.02)) + 1
    assert v.value == pytest.approx(m[-1], rel=1e-3)


def test_period_doubling_divergence_and_short_runs_are_not_steady():
    t, u = _revolutions(lambda t, T: 0.5 + np.sin(2 * np.pi * t / T) * (1 + 0.2 * np.cos(np.pi * t / T)))  # period 2T
    v = steadiness(t, u, 1000.0)
    assert not v.steady and v.revolution is None and "not steady by revolution 12" in v.reason
    section = poincare_section(t, u, 1000.0, phase=0.25)
    assert np.allclose(section[0::2], section[0], rtol=1e-9) and np.allclose(section[1::2], section[1], rtol=1e-9)
    assert abs(section[0] - section[1]) == pytest.approx(0.4 * np.cos(np.pi / 4), rel=1e-9)   # two points
    u_bad = u.copy()
    u_bad[-50] = np.nan
    assert "diverged" in steadiness(t, u_bad, 1000.0).reason and np.isnan(steadiness(t, u_bad, 1000.0).value)
    short = t <= 2.5 * 2 * np.pi / 1000.0
    assert "3 needed" in steadiness(t[short], u[short], 1000.0).reason
    assert revolution_maxima(t[short], u[short], 1000.0).size == 2
    T, dt = 2 * np.pi / 1000.0, t[1] - t[0]
    for end, whole in ((3 * T - 0.5 * dt, 3), (3 * T - 1.5 * dt, 2)):    # within one sample of the end, or not
        keep = t <= end
        assert revolution_maxima(t[keep], u[keep], 1000.0).size == whole


@pytest.mark.parametrize("args, word", [((np.arange(3.0), np.ones(4), 1.0), "t and u"),
                                        ((np.array([0.0, 2.0, 1.0]), np.ones(3), 1.0), "increasing"),
                                        ((np.arange(3.0), np.ones(3), -1.0), "omega"),
                                        ((np.arange(3.0), np.ones(3), "fast"), "omega")])
def test_bad_histories_are_refused(args, word):
    with pytest.raises(ValueError, match=word):
        steadiness(*args)
    with pytest.raises(ValueError, match="tolerance"):
        steadiness(np.arange(3.0), np.ones(3), 1.0, tolerance=0.0)


def test_harmonic_fractions_tell_periodic_period_two_and_quasi_periodic():
    from rotor37_rom.post.steady import harmonic_fractions

    w = 1000.0
    periodic = _revolutions(lambda t, T: np.sin(4 * 2 * np.pi * t / T) + 0.3 * np.cos(6 * 2 * np.pi * t / T),
                            n_rev=12)
    doubled = _revolutions(lambda t, T: np.sin(2 * np.pi * t / T) + 0.5 * np.sin(np.pi * t / T + 0.2), n_rev=12)
    quasi = _revolutions(lambda t, T: np.sin(4 * 2 * np.pi * t / T) + 0.5 * np.sin(2 * np.pi * 4.23 * t / T),
                         n_rev=12)
    f = harmonic_fractions(*periodic, w)
    assert f[1] > 1 - 1e-6
    f = harmonic_fractions(*doubled, w)
    assert f[2] > 1 - 1e-6 and abs(f[1] - 1 / 1.25) < 0.02        # power 1 : 0.25, the subharmonic's share 0.2
    f = harmonic_fractions(*quasi, w, revolutions=10)
    assert f[1] < 0.85 and f[2] < 0.85                              # the 4.23 f_rev line: 0.2 of the power
    with pytest.raises(ValueError, match="revolutions"):
        harmonic_fractions(*periodic, w, revolutions=40)
