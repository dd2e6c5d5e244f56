"""The energy balance of implicit runs (``dynamics.energy``, issue #86 item 2a) on small dense systems, against what the
schemes' equations give: average acceleration conserves T + E of a linear model to round-off (the trapezoidal load,
damping and contact works exact), generalised alpha loses O(h^3) over a fixed time at its spectral radius, a cubic
force's trapezoidal work misses dE by O(h^3) a step, and a contact's work splits into what the wall does and what the
step that closes (opens) a gap takes (gives back), as the closed forms of a mass hitting a wall say.

Round-off: R is a sum of terms of size ``scale`` (each an n-term dot product) and carries the Newton residual that
an LU solve leaves (its backward error); the bound used is 100 n eps scale per step (measured: <= 50 eps scale)."""
import itertools
from math import factorial

import numpy as np
import pytest
import scipy.linalg

from rotor37_rom.dynamics.energy import (balance_of_run, energy_balance, record_run, reduced_strain_energy)
from rotor37_rom.dynamics.newmark import Newmark, StepContact, dense_newmark
from rotor37_rom.forces.tensors import PolynomialForces, cubic_monomial_indices, quadratic_monomial_indices

EPS = np.finfo(float).eps


def _roundoff(b, n):
    """The per-step round-off bound of the balance's sums (module docstring)."""
    return 100 * n * EPS * b.scale


def _lu(A):
    lu = scipy.linalg.lu_factor(np.asarray(A))
    return lambda B: scipy.linalg.lu_solve(lu, B)


def _spd(rng, n, scale=1.0):
    L = rng.standard_normal((n, n))
    return (L @ L.T + n * np.eye(n)) * scale


def _linear_run(C=None, load=True, n=8, steps=400, h=0.01, seed=0):
    """A random linear n-DOF model (omega 5 ... 18 rad/s) by average acceleration, from a random state, under a
    sinusoidal load: (stepper, run, balance)."""
    rng = np.random.default_rng(seed)
    M, K = _spd(rng, n), _spd(rng, n, 100.0)
    p = 50 * rng.standard_normal(n) if load else np.zeros(n)
    st = dense_newmark(M, None if C is None else C(M, K), K, lambda t: p * np.sin(3 * t))
    run = record_run(st, np.arange(steps + 1) * h, 0.1 * rng.standard_normal(n), rng.standard_normal(n))
    return st, run, balance_of_run(st, run, reduced_strain_energy(K))


# (a) linear, undamped, average acceleration

def test_average_acceleration_conserves_linear_energy():
    _, _, free = _linear_run(load=False)
    assert np.abs(free.residual).max() > 0                           # measured, not identically zero
    assert (np.abs(free.residual) <= _roundoff(free, 8)).all()
    assert abs(free.energy[-1] - free.energy[0]) <= 100 * 8 * EPS * free.energy[0] * len(free.residual) ** 0.5
    _, _, b = _linear_run()
    assert (np.abs(b.residual) <= _roundoff(b, 8)).all()
    assert np.ptp(b.energy) > 0.1 * b.energy[0]                      # the load works
    assert abs(b.energy[0] + b.external.sum() - b.energy[-1]) <= _roundoff(b, 8).sum()
    assert (b.damping == 0).all() and (b.contact == 0).all()
    assert (np.abs(b.quadrature_gap) <= _roundoff(b, 8)).all()        # a linear force: G = 0
    assert (np.abs(b.algorithmic) <= _roundoff(b, 8)).all()           # the scheme's identity


# (b) Rayleigh damping

def test_trapezoidal_damping_is_exact():
    st, run, b = _linear_run(C=lambda M, K: 0.05 * M + 1e-3 * K)
    assert (np.abs(b.residual) <= _roundoff(b, 8)).all()
    assert (b.damping > 0).all()                                      # h/4 (v_n + v_n+1).C(v_n + v_n+1)
    h = np.diff(run.t)
    vbar = run.v[:, :-1] + run.v[:, 1:]
    assert np.allclose(b.damping, h / 4 * np.einsum("ik,ik->k", vbar, st.C @ vbar), rtol=1e-12, atol=0)
    # the whole run: what the load put in less what the damping took is what the structure holds
    assert abs(b.energy[0] + b.external.sum() - b.damping.sum() - b.energy[-1]) <= _roundoff(b, 8).sum()


# (c) generalised alpha

def _alpha_part(st, run, b, rho_inf):
    """A of generalised alpha for a linear model (K = the tangent), from its equation written at the alpha points:
    (dx.M a_bar - dT) + (1/2 - alpha_f) dx.(K dx + C dv - df), Y_bar = alpha Y_n + (1 - alpha) Y_n+1; zero for
    average acceleration (rho_inf None: the mean of its equations at t_n and t_n+1)."""
    if rho_inf is None:
        return np.zeros_like(b.residual)
    am, af = (2 * rho_inf - 1) / (rho_inf + 1), rho_inf / (rho_inf + 1)
    M, K, C = st.M, st.tangent(None), st.C
    dX, dV, dF = np.diff(run.x, axis=1), np.diff(run.v, axis=1), np.diff(run.loads, axis=1)
    a_bar = am * run.a[:, :-1] + (1 - am) * run.a[:, 1:]
    inertia = np.einsum("ik,ik->k", dX, M @ a_bar) - np.diff(b.kinetic)
    forces = K @ dX - dF + (0 if C is None else C @ dV)
    return inertia + (0.5 - af) * np.einsum("ik,ik->k", dX, forces)


def _spectral_radius(omega_h, rho_inf):
    """Largest |eigenvalue| of the generalised-alpha amplification matrix of x'' + x = 0 at the step omega_h."""
    am, af = (2 * rho_inf - 1) / (rho_inf + 1), rho_inf / (rho_inf + 1)
    g, be, h = 0.5 - am + af, 0.25 * (1 - am + af) ** 2, omega_h
    lhs = np.array([[1, 0, -h * h * be], [0, 1, -h * g], [1 - af, 0, 1 - am]])
    rhs = np.array([[1, h, (0.5 - be) * h * h], [0, 1, (1 - g) * h], [-af, 0, -am]])
    return np.abs(np.linalg.eigvals(np.linalg.solve(lhs, rhs))).max()


def _oscillator(steps_per_period, periods, rho_inf):
    """A unit-period oscillator from x = 1 at rest: (stepper, run, balance)."""
    M, K = np.eye(1), np.eye(1) * (2 * np.pi) ** 2
    st = dense_newmark(M, None, K, lambda t: np.zeros(1), rho_inf=rho_inf)
    run = record_run(st, np.arange(periods * steps_per_period + 1) / steps_per_period, np.ones(1), np.zeros(1))
    return st, run, balance_of_run(st, run, reduced_strain_energy(K))


def test_generalised_alpha_dissipates_at_third_order():
    _, _, mid = _oscillator(20, 3, 1.0)                   # rho_inf = 1: average acceleration written at the mid-point
    assert (np.abs(mid.residual) <= _roundoff(mid, 1)).all()
    periods, losses = 6, []
    for n in (20, 40, 80):
        st, run, b = _oscillator(n, periods, 0.8)
        assert (np.abs(b.quadrature_gap) <= _roundoff(b, 1)).all()                           # G = 0: R = A - P
        assert (np.abs(b.algorithmic - _alpha_part(st, run, b, 0.8)) <= _roundoff(b, 1)).all()
        # T + E is not the scheme's energy: per step it swings both ways by O(h^3), its period means decay
        assert b.residual.min() < 0 < b.residual.max()
        first, last = b.energy[:n].mean(), b.energy[-n:].mean()
        loss = first - last
        assert loss > 0 and b.residual[:n * (periods - 1)].sum() > 0
        theory = first * (1 - _spectral_radius(2 * np.pi / n, 0.8) ** (2 * n * (periods - 1)))
        assert loss == pytest.approx(theory, rel=0.02)                # 1 %, 0.5 %, 0.25 %: O(h) of the leading term
        losses.append(loss)
    rate = np.polyfit(np.log([1 / 20, 1 / 40, 1 / 80]), np.log(losses), 1)[0]
    assert abs(rate - 3.0) < 0.3                                      # 1 - rho = O(Omega^4) a step: h^3 in a fixed time


# (d) a cubic (reduced St. Venant-Kirchhoff-like) force

def _sym(T):
    perms = list(itertools.permutations(range(T.ndim)))
    return sum(np.transpose(T, p) for p in perms) / len(perms)


def _multiplicity(idx):
    m = factorial(len(idx))
    for c in np.unique(idx, return_counts=True)[1]:
        m //= factorial(c)
    return m


def _gradient_forces(r, seed=1):
    """A ``PolynomialForces`` that is the gradient of V = a.q^3 / 3 + b.q^4 / 4 (a, b symmetric; b positive), as the
    reduced SVK force is: (forces, V)."""
    rng = np.random.default_rng(seed)
    a3 = _sym(rng.standard_normal((r,) * 3))
    b4 = _sym(rng.standard_normal((r,) * 4)) + 3 * _sym(np.einsum("ij,kl->ijkl", np.eye(r), np.eye(r)))
    pa, pb = quadratic_monomial_indices(r)
    ca, cb, cc = cubic_monomial_indices(r)
    A = np.array([[a3[m, i, j] * _multiplicity((i, j)) for i, j in zip(pa, pb)] for m in range(r)])
    B = np.array([[b4[m, i, j, k] * _multiplicity((i, j, k)) for i, j, k in zip(ca, cb, cc)] for m in range(r)])

    def V(q):
        return np.einsum("ijk,i,j,k", a3, q, q, q) / 3 + np.einsum("ijkl,i,j,k,l", b4, q, q, q, q) / 4
    return PolynomialForces(A, B), V


class _WithoutPotential:
    """A force that does not expose its potential (as ``QuadratureForces``)."""
    has_potential = False

    def __init__(self, forces):
        self.forces, self.r = forces, forces.r

    def evaluate(self, Q):
        return self.forces.evaluate(Q)


def test_reduced_strain_energy_potential_and_line_integral():
    forces, V = _gradient_forces(3)
    K = np.diag([1.0, 3.0, 5.0])
    q = np.array([0.4, -0.7, 0.3])
    exact = 0.5 * q @ K @ q + V(q)
    assert reduced_strain_energy(K, forces)(q) == pytest.approx(exact, rel=1e-13)
    assert reduced_strain_energy(K, _WithoutPotential(forces))(q) == pytest.approx(exact, rel=1e-13)
    E, d = reduced_strain_energy(K, forces), 1e-5 * np.eye(3)          # its gradient is the internal force
    grad = np.array([(E(q + e) - E(q - e)) / 2e-5 for e in d])
    assert np.allclose(grad, K @ q + forces.evaluate(q).ravel(), rtol=1e-8)


def _cubic_run(steps_per_period, forces):
    M, K = np.diag([1.0, 2.0, 1.5]), np.diag([1.0, 3.0, 5.0]) * (2 * np.pi) ** 2
    st = dense_newmark(M, None, K, lambda t: np.zeros(3), forces=forces, rtol=1e-13)
    t = np.arange(2 * steps_per_period + 1) / steps_per_period
    run = record_run(st, t, np.array([0.5, 0.3, -0.4]), np.zeros(3))
    return st, run, balance_of_run(st, run, reduced_strain_energy(K, forces))


def test_cubic_force_trapezoidal_gap_is_third_order():
    forces, _ = _gradient_forces(3)
    worst = []
    for n in (40, 80, 160):
        st, run, b = _cubic_run(n, forces)
        assert (np.abs(b.algorithmic) <= _roundoff(b, 3)).all()
        assert np.abs(b.residual - b.quadrature_gap).max() <= 1e-4 * np.abs(b.residual).max()   # P: Newton's rtol
        # a cubic force: G = (phi(0) - 2 phi(1/2) + phi(1)) / 3 exactly, phi(s) = f(x_n + s dx).dx
        X, dX = run.x, np.diff(run.x, axis=1)
        phi = [np.einsum("ik,ik->k", dX, np.column_stack([st.internal(x) for x in (X[:, :-1] + s * dX).T]))
               for s in (0.0, 0.5, 1.0)]
        assert np.allclose(b.quadrature_gap, (phi[0] - 2 * phi[1] + phi[2]) / 3, rtol=0,
                           atol=1e-9 * np.abs(b.quadrature_gap).max())
        worst.append(np.abs(b.residual).max())
    rate = np.polyfit(np.log([1 / 40, 1 / 80, 1 / 160]), np.log(worst), 1)[0]
    assert abs(rate - 3.0) < 0.3


# (e) unilateral contact

def _wall_run(rho_inf, s=0.3, v0=1.0, h=0.1, m=1.0):
    """A free mass m at speed v0 towards a fixed wall at x = 1 that it would reach a fraction s of a step after t_2."""
    contact = StepContact(N=np.eye(1), S=np.zeros((1, 1)), mu=0.0, gaps=lambda t: np.array([1.0]))
    st = Newmark(m * np.eye(1), lambda x: 0.0 * x, lambda x: np.zeros((1, 1)), _lu, lambda t: np.zeros(1),
                 contact=contact, linear=True, rho_inf=rho_inf, rtol=1e-12)
    run = record_run(st, np.arange(8) * h, np.array([1.0 - (2 + s) * h * v0]), np.array([v0]))
    return run, balance_of_run(st, run, lambda x: 0.0)


def test_impact_closed_forms():
    s, v0, m = 0.3, 1.0, 1.0
    run, b = _wall_run(None, s, v0, m=m)                              # average acceleration
    assert (np.abs(b.residual) <= _roundoff(b, 1)).all() and (np.abs(b.algorithmic) <= _roundoff(b, 1)).all()
    assert b.closing[2] == pytest.approx(2 * m * v0 ** 2 * s * (1 - s), rel=1e-12)            # the impact step takes
    assert b.opening[3] == pytest.approx(2 * m * v0 ** 2 * (1 - s) * (2 - 3 * s), rel=1e-12)  # the release gives back
    assert b.kinetic[-1] == pytest.approx(0.5 * m * v0 ** 2 * (3 - 4 * s) ** 2, rel=1e-12)    # more than it had
    assert np.allclose(b.contact_normal, b.wall - b.closing + b.opening, rtol=0, atol=1e-14)
    run, b = _wall_run(1.0, s, v0, m=m)                               # the mid-point form: contact only takes
    assert (np.abs(b.residual) <= _roundoff(b, 1)).all()
    assert (b.opening == 0).all() and b.closing[2] == pytest.approx(2 * m * v0 ** 2 * s * (1 - s), rel=1e-12)
    assert b.kinetic[-1] == pytest.approx(0.5 * m * v0 ** 2 * (1 - 2 * s) ** 2, rel=1e-12)


def _contact_run(rho_inf, damped):
    """A 3-DOF chain, loaded, its first DOF against a moving wall with friction along the second."""
    M = np.diag([1.0, 1.0, 0.5])
    K = np.array([[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0]]) * 40
    contact = StepContact(N=np.array([[1.0, 0, 0]]), S=np.array([[0, 1.0, 0]]), mu=0.3,
                          gaps=lambda t: np.array([0.05 + 0.01 * np.sin(7 * t)]))
    st = Newmark(M, lambda x: K @ x, lambda x: K, _lu, lambda t: np.array([2.5, 1.0, 5.0]) * np.sin(4 * t),
                 contact=contact, linear=True, rho_inf=rho_inf, rtol=1e-12, C=0.02 * K + 0.1 * M if damped else None)
    run = record_run(st, np.arange(601) * 0.01, np.zeros(3), np.zeros(3))
    return st, run, balance_of_run(st, run, reduced_strain_energy(K))


@pytest.mark.parametrize("rho_inf", [None, 1.0, 0.8])
@pytest.mark.parametrize("damped", [False, True])
def test_contact_balance_closes(rho_inf, damped):
    st, run, b = _contact_run(rho_inf, damped)
    bound = _roundoff(b, 3)
    assert (run.multipliers > 0).sum() >= 10                          # it touches, more than once
    # R = G - P + A from the scheme's own equations: A = 0 (average acceleration, either form), else the alpha
    # weights' part alone, the contact's multiplier of the step cancelling exactly
    assert (np.abs(b.algorithmic - _alpha_part(st, run, b, rho_inf)) <= bound).all()
    if rho_inf in (None, 1.0):
        assert (np.abs(b.residual) <= bound).all()
    # complementarity: the normal work is the wall's, less what closing steps take, plus what opening ones give
    assert (np.abs(b.contact_normal - (b.wall - b.closing + b.opening)) <= bound).all()
    tol = 1e-13 * b.scale                                             # gaps >= -1e-15 m (Newmark.admissible)
    assert (b.closing >= -tol).all() and (b.opening >= -tol).all() and b.closing.sum() > 0
    assert np.abs(b.wall).max() > 0 and np.abs(b.contact_friction).max() > 0
    if rho_inf is not None:
        assert (b.opening == 0).all()


# bad input

def test_bad_input_is_refused():
    _, run, _ = _linear_run(steps=3)
    M, x, v, a = np.eye(8), run.x, run.v, run.a

    def E(y):
        return 0.0
    cases = [
        (dict(x=x[:, :1]), "^x must be"),
        (dict(v=v[:-1]), "^v must be"),
        (dict(a=np.where(a == a[0, 0], np.nan, a)), "^a must be finite"),
        (dict(M=np.eye(7)), "^M must be"),
        (dict(C=np.ones((8, 3))), "^C must be"),
        (dict(loads=np.zeros((8, 3))), "^loads must be"),
        (dict(strain_energy=lambda y: np.inf), "^strain_energy must"),
        (dict(strain_energy=lambda y: y), "^strain_energy must"),
        (dict(rho_inf=1.5), "^rho_inf must"),
        (dict(t=[0.0, 1.0, 1.0, 2.0]), "^t must be"),
        (dict(t=[0.0, 1.0]), "^t must have"),
        (dict(multipliers=np.zeros((1, 4))), "^multipliers given without a contact"),
        (dict(internal=lambda y: y[:3]), r"^internal\(x\) must be"),
    ]
    for change, message in cases:
        args = dict(x=x, v=v, a=a, M=M, strain_energy=E)
        args.update(change)
        with pytest.raises(ValueError, match=message):
            energy_balance(args.pop("x"), args.pop("v"), args.pop("a"), args.pop("M"), args.pop("strain_energy"),
                           **args)
    contact = StepContact(N=np.eye(8)[:1], S=np.zeros((1, 8)), mu=0.0, gaps=lambda t: np.ones(1))
    with pytest.raises(ValueError, match="^multipliers: required"):
        energy_balance(x, v, a, M, E, t=run.t, contact=contact)
    with pytest.raises(ValueError, match="^t: required"):
        energy_balance(x, v, a, M, E, contact=contact, multipliers=np.zeros((1, 4)))
    with pytest.raises(ValueError, match="^K must be"):
        reduced_strain_energy(np.ones((2, 3)))
    with pytest.raises(ValueError, match="^forces: r"):
        reduced_strain_energy(np.eye(2), _gradient_forces(3)[0])
    with pytest.raises(ValueError, match="^q must be"):
        reduced_strain_energy(np.eye(2))(np.ones(3))
    st = dense_newmark(np.eye(2), None, np.eye(2), lambda t: np.zeros(2))
    with pytest.raises(ValueError, match="^x0 must be"):
        record_run(st, [0.0, 0.1], np.ones(3), np.zeros(2))
    with pytest.raises(ValueError, match="^t must be"):
        record_run(st, [0.0, np.nan], np.ones(2), np.zeros(2))
