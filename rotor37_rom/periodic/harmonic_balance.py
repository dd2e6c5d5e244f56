"""Harmonic balance on a second-order system M q'' + C q' + K q + g(q) = f(t): periodic orbits, their stability by
Hill's method, and their continuation in the excitation frequency along arc length through turning points.

The unknowns are the real Fourier coefficients of q over one period T = 2 pi / omega (``Harmonics``: q(tau) = a_0 +
sum_h a_h cos(h tau) + b_h sin(h tau), tau = omega t), one block of n per coefficient, the constant first. The linear
terms are exact per harmonic; the nonlinear force goes through alternating frequency-time (AFT: the coefficients to
``n_time`` samples of the period, g at every sample - a batch, as the reduced models' forces evaluate it - and back by
the discrete Fourier transform), with its exact Jacobian from the same samples. With ``n_time`` > (p + 1) H samples a
polynomial force of degree p is balanced without aliasing (the cubic SVK force of the reduced models: ``n_time`` > 4
H), so harmonic balance with H harmonics is exact for that truncation.

Stability (Hill's method, as NLvib and pyHarm do it): a perturbation e^(lambda t) p(t) of the orbit with p
T-periodic satisfies the quadratic eigenproblem (J + lambda Delta_1 + lambda^2 Delta_2) p = 0 in the same
coefficients, J the harmonic balance Jacobian, Delta_1 = C (x) I + 2 omega M (x) D and Delta_2 = M (x) I (D: d/dtau
on the coefficients); of its 2 n (2 H + 1) eigenvalues the 2 n whose imaginary parts are smallest in magnitude are
the Floquet exponents (the others are the same ones shifted by multiples of i omega, and the least accurate), the
multipliers exp(lambda T). An orbit is stable when every exponent has a negative real part (within ``tol``).

Continuation (``continue_branch``): pseudo-arc length in (X, omega) - a tangent predictor, a Newton corrector on
the residual bordered by the arc-length condition, the step halved where the corrector fails and grown where it
converges fast - which passes turning points (folds) where a continuation in omega stops. Folds are where the
tangent's omega component changes sign; every point carries its stability. Pure NumPy/SciPy.
"""
from __future__ import annotations

import dataclasses
import numbers
from typing import Callable, Protocol, runtime_checkable

import numpy as np
import scipy.linalg

from rotor37_rom.checks import real_number, whole_number

__all__ = ["Harmonics", "HarmonicBalance", "PeriodicProblem", "PeriodicSolution", "Branch", "continue_branch",
           "solve_periodic", "model_force", "time_state", "backbone", "bifurcation_kind", "hill_eigenvalues",
           "hill_exponents", "harmonic_energy", "square_matrices"]


@dataclasses.dataclass(frozen=True)
class Harmonics:
    """The real Fourier basis of H harmonics on ``n_time`` uniform samples of the period (tau_j = 2 pi j / n_time).

    Attributes:
        H: harmonics (>= 0); n_time: samples per period (> 2 H; > (p + 1) H balances a degree-p polynomial force
            without aliasing).
    """

    H: int
    n_time: int

    def __post_init__(self):
        if not (isinstance(self.H, (int, np.integer)) and not isinstance(self.H, bool) and self.H >= 0):
            raise ValueError(f"H (harmonics) must be an integer >= 0, got {self.H!r}")
        if not (isinstance(self.n_time, (int, np.integer)) and self.n_time > 2 * self.H):
            raise ValueError(f"n_time must be an integer > 2 H = {2 * self.H} (samples per period), got "
                             f"{self.n_time!r}")

    @property
    def size(self) -> int:
        """2 H + 1 coefficients per degree of freedom."""
        return 2 * self.H + 1

    @property
    def tau(self) -> np.ndarray:
        return 2 * np.pi * np.arange(self.n_time) / self.n_time

    @property
    def synthesis(self) -> np.ndarray:
        """E (n_time, 2 H + 1): samples = E @ coefficients; columns 1, cos tau, sin tau, cos 2 tau, ..."""
        tau, cols = self.tau, [np.ones(self.n_time)]
        for h in range(1, self.H + 1):
            cols += [np.cos(h * tau), np.sin(h * tau)]
        return np.column_stack(cols)

    @property
    def analysis(self) -> np.ndarray:
        """P (2 H + 1, n_time): coefficients = P @ samples (the discrete Fourier transform; P E = I)."""
        E = self.synthesis
        scale = np.full(self.size, 2.0 / self.n_time)
        scale[0] = 1.0 / self.n_time
        return scale[:, None] * E.T

    @property
    def derivative(self) -> np.ndarray:
        """D (2 H + 1, 2 H + 1): the coefficients of d/dtau: (a_h, b_h) -> (h b_h, -h a_h)."""
        D = np.zeros((self.size, self.size))
        for h in range(1, self.H + 1):
            c, s = 2 * h - 1, 2 * h
            D[c, s], D[s, c] = h, -h
        return D


def model_force(forces) -> Callable:
    """The harmonic balance's ``force`` of a reduced model's nonlinear force (``forces.protocol.NonlinearForce``:
    ``evaluate`` and ``jacobians`` on a batch of states): Q (r, m) -> (G (r, m), J (m, r, r))."""
    def force(Q):
        return forces.evaluate(Q), forces.jacobians(Q)

    return force


def time_state(X: np.ndarray, omega: float, tau: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """(q, q') at phase ``tau`` = omega t of the orbit with coefficients X (2 H + 1, n)."""
    H = (len(X) - 1) // 2
    h = np.arange(1, H + 1)[:, None]
    a, b = X[1::2], X[2::2]
    q = X[0] + (a * np.cos(h * tau) + b * np.sin(h * tau)).sum(axis=0)
    v = omega * (h * (b * np.cos(h * tau) - a * np.sin(h * tau))).sum(axis=0)
    return q, v


@dataclasses.dataclass
class PeriodicSolution:
    """A periodic orbit: its frequency omega (rad/s), coefficients X (2 H + 1, n), Floquet exponents (2 n,) and
    multipliers, stability, the residual norm reached, Newton iterations; with contact (``contact.ContactBalance``)
    the coefficients L (2 H + 1, n_c) of each law's multipliers."""

    omega: float
    X: np.ndarray
    exponents: np.ndarray | None = None
    stable: bool | None = None
    residual: float = np.nan
    iterations: int = 0
    L: tuple = ()

    @property
    def unknowns(self) -> np.ndarray:
        """x: the balance's unknowns, [X.ravel(), L_1.ravel(), ...]."""
        return np.concatenate([self.X.ravel()] + [L.ravel() for L in self.L])

    @property
    def multipliers(self) -> np.ndarray | None:
        return None if self.exponents is None else np.exp(self.exponents * 2 * np.pi / self.omega)

    def amplitude(self, dof: int, basis: Harmonics, n_samples: int = 512) -> float:
        """max |q_dof(t)| over the period, sampled on ``n_samples`` points."""
        return float(np.abs(Harmonics(basis.H, n_samples).synthesis @ self.X[:, dof]).max())


def square_matrices(**matrices) -> list:
    """The matrices given by name (``M=..., K=...``) as float arrays, each a finite real square matrix of the first
    one's size; else one TypeError (not numbers) or ValueError (not square, sizes that differ, not finite) naming
    the matrix and what it must be.

    Returns:
        The float arrays, in the order given.
    """
    out, first = [], None
    for name, value in matrices.items():
        try:
            A = np.asarray(value, float)
        except (TypeError, ValueError):
            raise TypeError(f"{name} must be a real square matrix, got {type(value).__name__} {value!r:.60}") \
                from None
        if A.ndim != 2 or A.shape[0] != A.shape[1] or A.shape[0] == 0:
            raise ValueError(f"{name} must be a square (n, n) matrix with n >= 1, got shape {A.shape}")
        if first is not None and A.shape != first[1]:
            raise ValueError(f"{name} must be {first[1]} like {first[0]}, got shape {A.shape}")
        if not np.isfinite(A).all():
            raise ValueError(f"{name} must be finite, has nan or inf in {int((~np.isfinite(A)).sum())} of its "
                             f"{A.size} entries")
        first = first or (name, A.shape)
        out.append(A)
    return out


class HarmonicBalance:
    """The harmonic balance equations of M q'' + C q' + K q + g(q) = f(tau) for one ``Harmonics`` basis.

    Args:
        M, C, K: (n, n) matrices, finite, of one size (ValueError naming the one that is not).
        force: g and its Jacobian at a batch of states: ``force(Q)`` with Q (n, m) returns (G (n, m), J (m, n, n)),
            or None (linear).
        excitation: F (2 H + 1, n): the coefficients of f per unit amplitude (its cos tau row: a force f0 cos(omega
            t) is F[1] = f0).
        basis: the Harmonics.
    """

    smooth = True              # a smooth residual: Newton may stop at its round-off floor (``_at_floor``)

    def __init__(self, M, C, K, force: Callable | None, excitation: np.ndarray, basis: Harmonics):
        if not isinstance(basis, Harmonics):
            raise TypeError(f"basis must be a Harmonics, got {type(basis).__name__}")
        if force is not None and not callable(force):
            raise TypeError(f"force must be a callable force(Q) -> (G, J) or None (linear), got "
                            f"{type(force).__name__}")
        self.M, self.C, self.K = square_matrices(M=M, C=C, K=K)
        self.n = self.K.shape[0]
        self.force, self.basis = force, basis
        try:
            F = np.asarray(excitation, float)
        except (TypeError, ValueError):
            raise TypeError(f"excitation must be real coefficients (2 H + 1, n), got {type(excitation).__name__}") \
                from None
        if F.size != basis.size * self.n or not np.isfinite(F).all():
            raise ValueError(f"excitation must be finite coefficients (2 H + 1, n) = ({basis.size}, {self.n}), got "
                             f"shape {F.shape}" + ("" if F.size != basis.size * self.n else " not finite"))
        self.F = F.reshape(basis.size, self.n)
        self._E, self._P, self._D = basis.synthesis, basis.analysis, basis.derivative
        I = np.eye(basis.size)
        self._lin = [np.kron(I, self.K), np.kron(self._D, self.C), np.kron(self._D @ self._D, self.M)]

    @property
    def size(self) -> int:
        return self.basis.size * self.n

    def linear_matrix(self, omega: float) -> np.ndarray:
        """The linear part's matrix on x = X.ravel() (coefficient-major: kron(A, B) x = (A X B^T).ravel()):
        kron(I, K) + omega kron(D, C) + omega^2 kron(D^2, M)."""
        return self._lin[0] + omega * self._lin[1] + omega ** 2 * self._lin[2]

    def residual(self, x: np.ndarray, omega: float, jacobian: bool = True, domega: bool = True):
        """R(x, omega), and with ``jacobian`` dR/dx and dR/domega (None without ``domega``)."""
        X = x.reshape(self.basis.size, self.n)
        R = self.linear_matrix(omega) @ x - self.F.ravel()
        J = self.linear_matrix(omega) if jacobian else None
        if self.force is not None:
            Q = (self._E @ X).T                                     # (n, n_time): the states over the period
            G, dG = self.force(Q)
            R = R + (self._P @ G.T).ravel()
            if jacobian:
                # d(P g(E X))/dX: sum over samples t of P[:, t] (x) J_t (x) E[t, :]
                J = J + np.einsum("at,tij,tb->aibj", self._P, dG, self._E).reshape(self.size, self.size)
        if not jacobian:
            return R
        dR_domega = (self._lin[1] + 2 * omega * self._lin[2]) @ x if domega else None
        return R, J, dR_domega

    def floquet_exponents(self, x: np.ndarray, omega: float, J: np.ndarray | None = None) -> np.ndarray:
        """The 2 n Floquet exponents of the orbit (Hill's method; see the module docstring), by increasing real
        part."""
        if J is None:
            J = self.residual(x, omega)[1]
        I = np.eye(self.basis.size)
        D1 = np.kron(I, self.C) + 2 * omega * np.kron(self._D, self.M)
        D2 = np.kron(I, self.M)
        lam, centre = hill_eigenvalues(J, D1, D2, lambda P: harmonic_energy(P, self.basis.size, self.n),
                                       stiffness=self._lin[0])
        central = lam[hill_exponents(lam, centre, omega, self.basis.H)]
        return central[np.argsort(central.real, kind="stable")]


def harmonic_energy(P: np.ndarray, k: int, n: int) -> np.ndarray:
    """(2 H + 1, m): the energy of each complex harmonic -H .. H of perturbations whose real coefficients (k n, m)
    are coefficient-major blocks [p_0, p_a1, p_b1, ...] (p_a cos + p_b sin = ((p_a - i p_b) e^(i h tau) + (p_a +
    i p_b) e^(-i h tau)) / 2)."""
    P = P.reshape(k, n, -1)
    H = (k - 1) // 2
    out = np.empty((k, P.shape[2]))
    out[H] = (np.abs(P[0]) ** 2).sum(axis=0)
    for h in range(1, H + 1):
        a, b = P[2 * h - 1], P[2 * h]
        out[H + h] = (np.abs(a - 1j * b) ** 2).sum(axis=0) / 4
        out[H - h] = (np.abs(a + 1j * b) ** 2).sum(axis=0) / 4
    return out


def hill_eigenvalues(J: np.ndarray, D1: np.ndarray, D2: np.ndarray, energy: Callable,
                     stiffness: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(lambda, centre): the eigenvalues of Hill's quadratic problem (J + lambda D1 + lambda^2 D2) p = 0, and the
    barycentre over the harmonics -H .. H of each eigenvector's energy (``energy(P)`` -> (2 H + 1, m) for the
    eigenvectors' columns P). Each exponent appears 2 H + 1 times, shifted by i m omega with its eigenvector's
    harmonics shifted by -m; ``hill_exponents`` keeps one copy of each. Picking by the smallest imaginary part
    alone fails on a stiff model: a mode far above H omega is never the nearest the real axis, while shifted copies
    of low modes are; there the copy to keep is the one whose eigenvector is centred on the constant harmonic
    (Lazarus & Thomas, C. R. Mecanique 338 (2010) 510-517, choose by the eigenvectors likewise).

    The problem is solved in the coordinates of ``stiffness`` and D2 (symmetric, D2 positive definite: p = Phi u,
    Phi^T D2 Phi = I, Phi^T stiffness Phi = diag(w^2)) on the state [w u, lambda u]: its matrix's norm is then the
    highest frequency w, not w^2 as in the plain first-order form [p, lambda p], whose round-off (eps w_max^2 on a
    reduced model whose stiffest coordinate sits 1,000 times above its first mode) swamps the real parts of the low
    exponents, the damping that decides stability. Without ``stiffness`` D2 alone is made the identity."""
    n = J.shape[0]
    if stiffness is None:
        Phi, w = np.linalg.inv(np.linalg.cholesky(D2)).T, np.ones(n)
    else:
        w2, Phi = scipy.linalg.eigh(stiffness, D2)
        w = np.sqrt(np.abs(w2))
        w = np.maximum(w, 1e-8 * max(w.max(), 1e-300))
    Jt, D1t = Phi.T @ J @ Phi, Phi.T @ D1 @ Phi
    A = np.block([[np.zeros((n, n)), np.diag(w)], [-Jt / w[None, :], -D1t]])
    lam, Y = scipy.linalg.eig(A)
    keep = np.isfinite(lam)
    lam, P = lam[keep], Phi @ (Y[:n, keep] / w[:, None])
    e = energy(P)
    H = (e.shape[0] - 1) // 2
    centre = (np.arange(-H, H + 1)[:, None] * e).sum(axis=0) / np.maximum(e.sum(axis=0), 1e-300)
    return lam, centre


def hill_exponents(lam: np.ndarray, centre: np.ndarray, omega: float, H: int) -> np.ndarray:
    """The indices of Hill's eigenvalues ``lam`` that are the Floquet exponents, one copy of each: those with
    |Im| <= omega / 2 (each exponent whose copies reach that band has one copy there, as in the usual choice by the
    smallest imaginary part, robust where an eigenvector spreads over the harmonics near a resonance), and, above
    the band the balance resolves (|Im| > (H + 1/2) omega: a mode too stiff for any copy to reach omega / 2), those
    whose eigenvector is centred on the constant harmonic (``hill_eigenvalues``'s centre within 1/2). On a linear
    system this is every eigenvalue exactly once, modulo i omega."""
    band = np.abs(lam.imag) <= 0.5 * omega * (1 + 1e-9)
    stiff = (np.abs(lam.imag) > (H + 0.5) * omega) & (np.abs(centre) < 0.5)
    return np.flatnonzero(band | stiff)


@runtime_checkable
class PeriodicProblem(Protocol):
    """What ``solve_periodic`` and ``continue_branch`` need of a periodic problem (``HarmonicBalance``,
    ``ContactBalance``, ``Shooting``, ``TravellingWaveBalance`` implement it).

    Members:
        size: the number of unknowns x.
        residual(x, omega, jacobian=True, domega=True): R, or (R, dR/dx, dR/domega or None).
        floquet_exponents(x, omega, J=None): the orbit's Floquet exponents (J: dR/dx at x, if at hand).
    Optional members (read where present): split(x) -> (X, (L, ...)), the orbit and its contact laws' unknowns
    (default: x as the (2H + 1, n) coefficients); scales(x), the unknowns' scales of a nonsmooth balance (Newton's
    step is then halved while it raises the residual, and measured in these scales); smooth, true where Newton may
    stop at its round-off floor (``_at_floor``).
    """

    @property
    def size(self) -> int: ...

    def residual(self, x: np.ndarray, omega: float, jacobian: bool = True, domega: bool = True): ...

    def floquet_exponents(self, x: np.ndarray, omega: float, J: np.ndarray | None = None) -> np.ndarray: ...


def _unknowns(name: str, x, hb) -> np.ndarray:
    """``x`` as a new flat float array of ``hb``'s finite unknowns, else one TypeError/ValueError naming ``name``."""
    try:
        x = np.array(x, float).ravel()
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be an array of real unknowns, got {type(x).__name__}") from None
    size = getattr(hb, "size", None)
    if isinstance(size, numbers.Integral) and x.size != size:
        raise ValueError(f"{name} must hold the problem's {size} unknowns, got {x.size}")
    if not np.isfinite(x).all():
        raise ValueError(f"{name} must be finite, has nan or inf in {int((~np.isfinite(x)).sum())} of its {x.size} "
                         f"unknowns")
    return x


def _stable(exponents: np.ndarray | None, omega: float) -> bool | None:
    """Every Floquet exponent with a negative real part (round-off: 1e-9 omega); None without exponents."""
    return None if exponents is None else bool(np.all(exponents.real < 1e-9 * omega))


def _newton_step(J: np.ndarray, R: np.ndarray) -> np.ndarray:
    """-J^-1 R; where J is singular (a contact law's iterate that sticks at every sample leaves the mean position
    free), the least-squares step."""
    try:
        return np.linalg.solve(J, -R)
    except np.linalg.LinAlgError:
        return np.linalg.lstsq(J, -R, rcond=None)[0]


def _split(hb, x):
    """(X, (L, ...)) of the unknowns x of a balance (with contact laws or without)."""
    if hasattr(hb, "split"):
        X, Ls = hb.split(x)
        return X.copy(), tuple(L.copy() for L in Ls)
    return x.reshape(hb.basis.size, hb.n).copy(), ()


def _at_floor(hb, norms: list, step: float, size: float) -> bool:
    """Whether Newton on a smooth balance (``hb.smooth``) has reached the round-off floor: after 3 iterations an
    update below 1e-6 of the unknowns while the residual no longer falls (not below half the least of the three
    before). A stiff model's floor can sit above a relative tolerance of 1e-10 (the maps' disk model, r = 1,728:
    ~1e-9); quadratic convergence ends there, where a wrong Jacobian would still be converging linearly."""
    return bool(getattr(hb, "smooth", False) and len(norms) >= 4 and step <= 1e-6 * size
                and norms[-1] >= 0.5 * min(norms[-4:-1]))


def solve_periodic(hb: PeriodicProblem, x0: np.ndarray, omega: float, tol: float = 1e-10, max_iter: int = 30,
                   stability: bool = True) -> PeriodicSolution:
    """Newton on R(x, omega) = 0 at fixed omega from x0 (relative tolerance ``tol`` on the update, or a smooth
    balance's round-off floor, ``_at_floor``); an iterate whose residual is not finite (a shooting step that took
    the scheme past its stability limit) is replaced by the previous one plus half its step, up to 6 times;
    ValueError where it does not converge.

    Args:
        hb: the periodic problem (``PeriodicProblem``).
        x0: Newton's start, ``hb.size`` finite unknowns.
        omega: the orbit's frequency (rad/s), finite and > 0 (at omega <= 0 the balance's root is the mirrored
            orbit or the static state, not a periodic orbit of frequency omega; ValueError before any work).
        tol: the relative tolerance on Newton's update, finite and >= 0.
        max_iter: Newton's iterations, an integer >= 1.
        stability: whether the orbit's Floquet exponents are computed.
    """
    real_number("omega", omega, 0.0, open_low=True, unit=" rad/s")
    real_number("tol", tol, 0.0)
    whole_number("max_iter", max_iter, 1)
    x = _unknowns("x0", x0, hb)
    norms, last, halved = [], None, 0
    for it in range(1, max_iter + 1):
        with np.errstate(over="ignore", invalid="ignore"):
            R, J, _ = hb.residual(x, omega, domega=False)
        if not (np.isfinite(R).all() and np.isfinite(J).all()):
            if last is None or halved >= 6:
                raise ValueError(f"periodic orbit: the residual is not finite at omega = {omega:g} after {it - 1} "
                                 "Newton iterations (a shooting iterate past the scheme's stability limit)")
            # the step took the iterate where the scheme blows up: back, half the step (up to 6 times)
            base, dx = last[0], last[1] / 2
            last, halved = (base, dx), halved + 1
            x = base + dx
            continue
        norms.append(float(np.linalg.norm(R)))
        dx = _newton_step(J, R)
        if hasattr(hb, "scales"):
            # contact: a semismooth Newton, the step halved while it raises the residual (a contact set that
            # cycles), the update measured in the unknowns' own scales
            r0, a = np.linalg.norm(R), 1.0
            while a > 1 / 64 and np.linalg.norm(hb.residual(x + a * dx, omega, jacobian=False)) > r0:
                a /= 2
            dx *= a
            s = hb.scales(x)
            small = np.linalg.norm(dx / s) <= tol * max(np.linalg.norm(x / s), 1e-300)
        else:
            small = np.linalg.norm(dx) <= tol * max(np.linalg.norm(x), 1e-300) or \
                _at_floor(hb, norms, np.linalg.norm(dx), np.linalg.norm(x))
        last = (x.copy(), dx)
        x += dx
        if small:
            if stability:
                R, J, _ = hb.residual(x, omega, domega=False)
                exps = hb.floquet_exponents(x, omega, J)
            else:
                R, exps = hb.residual(x, omega, jacobian=False), None
            X, L = _split(hb, x)
            return PeriodicSolution(omega, X, exps, _stable(exps, omega), float(np.linalg.norm(R)), it, L)
    raise ValueError(f"periodic orbit: Newton did not converge in {max_iter} iterations at omega = {omega:g}")


@dataclasses.dataclass
class Branch:
    """A continued branch: its solutions in arc-length order, the indices where a fold lies between two points
    (the tangent's omega component changes sign), why it ended, and its bifurcations: (i, kind, multiplier) where
    the stability changes between points i - 1 and i, the kind told by the multiplier that crossed the unit circle
    (``bifurcation_kind``)."""

    points: list
    folds: list
    ended: str
    bifurcations: list = dataclasses.field(default_factory=list)

    @property
    def omega(self) -> np.ndarray:
        return np.array([p.omega for p in self.points])


def bifurcation_kind(multiplier: complex, angle_tol: float = 0.1) -> str:
    """What a Floquet multiplier crossing the unit circle makes: 'fold' at +1 (a turning point, or a branch point
    where the branch's symmetry breaks), 'period doubling' at -1 (an orbit of twice the period is born),
    'Neimark-Sacker' for a complex pair (a torus: the response modulated at the pair's frequency)."""
    a = abs(np.angle(multiplier))
    return "fold" if a < angle_tol else "period doubling" if a > np.pi - angle_tol else "Neimark-Sacker"


def _crossing(before: PeriodicSolution, after: PeriodicSolution):
    """(kind, multiplier) of the stability change between two neighbouring points: the largest multiplier of the
    unstable one (the one that left the unit circle), or None."""
    if before.stable is None or after.stable is None or before.stable == after.stable:
        return None
    mult = (after if before.stable else before).multipliers
    mu = complex(mult[np.argmax(np.abs(mult))])
    return bifurcation_kind(mu), mu


def _tangent(J: np.ndarray, dR_domega: np.ndarray, previous: np.ndarray | None) -> np.ndarray:
    """The unit tangent of R(x, omega) = 0: the null vector of [J, dR/domega], oriented along ``previous``."""
    N = J.shape[0]
    A = np.hstack([J, dR_domega[:, None]])
    # the null vector: solve the bordered system with the previous tangent (or e_omega) as the last row
    border = previous if previous is not None else np.r_[np.zeros(N), 1.0]
    t = np.linalg.solve(np.vstack([A, border[None]]), np.r_[np.zeros(N), 1.0])
    t /= np.linalg.norm(t)
    if previous is not None and t @ previous < 0:
        t = -t
    return t


def _branch_arguments(hb, start, omega_end, step, step_min, step_max, max_points, tol, max_iter, progress):
    """``continue_branch``'s arguments checked (ValueError or TypeError naming the one outside its range); returns
    (step_min, step_max) with their defaults."""
    if not isinstance(start, PeriodicSolution):
        raise TypeError(f"start must be a PeriodicSolution (solve_periodic's), got {type(start).__name__}")
    real_number("start.omega", start.omega, 0.0, open_low=True, unit=" rad/s")
    _unknowns("start's unknowns", start.unknowns, hb)
    real_number("omega_end", omega_end, unit=" rad/s")
    real_number("step", step, 0.0, open_low=True)
    step_min = step / 64 if step_min is None else step_min
    real_number("step_min", step_min, 0.0, step, open_low=True)
    step_max = 8 * step if step_max is None else step_max
    real_number("step_max", step_max, step)
    whole_number("max_points", max_points, 1)
    real_number("tol", tol, 0.0)
    whole_number("max_iter", max_iter, 1)
    if progress is not None and not callable(progress):
        raise TypeError(f"progress must be a callable or None, got {type(progress).__name__}")
    return step_min, step_max


def continue_branch(hb: PeriodicProblem, start: PeriodicSolution, omega_end: float, step: float,
                    step_min: float | None = None, step_max: float | None = None, max_points: int = 2000,
                    tol: float = 1e-10, max_iter: int = 12, stability: bool = True,
                    progress: Callable[[PeriodicSolution], None] | None = None) -> Branch:
    """Pseudo-arc-length continuation from ``start`` towards ``omega_end`` (the branch ends past it, where the
    step falls below ``step_min``, or at the boundary omega > 0: the end is said in ``Branch.ended``). Arc length is
    measured in (x / s_x, omega / s_omega) with s_x the start's norm and s_omega its frequency, so that ``step`` is
    relative. ``progress`` is called with each new point.

    A branch lives at frequencies omega > 0 (at omega <= 0 the balance's roots are the mirrored orbits and the
    static state): a corrector that lands at omega <= 0 (``omega_end`` <= 0, or a branch that turns back down) is
    a failed step; the step is halved, and once it falls below ``step_min`` the branch ends there, its last point
    the nearest omega = 0 it reached, with that reason.

    Args:
        hb: the periodic problem (``PeriodicProblem``).
        start: the first point (a ``PeriodicSolution`` of ``hb``, omega finite and > 0).
        omega_end: the frequency (rad/s) to reach, finite.
        step: the relative arc length of a step, finite and > 0.
        step_min: the least step, in (0, step] (default step / 64).
        step_max: the largest step, finite and >= step (default 8 step).
        max_points: the most points, an integer >= 1.
        tol: the corrector's relative tolerance, finite and >= 0.
        max_iter: the corrector's iterations, an integer >= 1.
        stability: whether each point's Floquet exponents are computed.
        progress: None or a callable, called with each new point.

    Returns:
        The Branch. ValueError or TypeError naming the argument before any work where one is outside its range.
    """
    step_min, step_max = _branch_arguments(hb, start, omega_end, step, step_min, step_max, max_points, tol, max_iter,
                                           progress)
    sx = hb.scales(start.unknowns) if hasattr(hb, "scales") else np.full(hb.size, max(np.linalg.norm(start.X),
                                                                                           1e-300))
    sw = start.omega
    scale = np.r_[sx, sw]
    y = np.r_[start.unknowns, start.omega] / scale
    direction = np.sign(omega_end - start.omega) or 1.0
    _, J, dRw = hb.residual(y[:-1] * sx, y[-1] * sw)
    t = _tangent(J * sx[None, :], dRw * sw, np.r_[np.zeros(hb.size), direction])
    points, folds, bifurcations, h = [start], [], [], step
    boundary = False              # a failed step since the last point landed at omega <= 0
    while len(points) < max_points:
        pred = y + h * t
        z, ok, norms = pred.copy(), False, []
        for _ in range(max_iter):
            if not z[-1] > 0:         # past the boundary omega > 0 (and 2 pi / omega undefined at 0): a failed step
                boundary = True
                break
            try:                      # a shooting map refuses an omega past its step's limit: a failed corrector
                R, J, dRw = hb.residual(z[:-1] * sx, z[-1] * sw)
            except ValueError:
                break
            norms.append(float(np.linalg.norm(R)))
            A = np.vstack([np.hstack([J * sx[None, :], dRw[:, None] * sw]), t[None]])
            rhs = -np.r_[R, t @ (z - y) - h]
            dz = np.linalg.solve(A, rhs)
            z += dz
            if not np.all(np.isfinite(z)) or np.linalg.norm(z - pred) > 4 * h:
                break                 # the corrector left the predictor's neighbourhood: a smaller step
            if np.linalg.norm(dz) <= tol * max(np.linalg.norm(z), 1.0) or \
                    _at_floor(hb, norms, np.linalg.norm(dz), max(np.linalg.norm(z), 1.0)):
                ok = bool(z[-1] > 0)
                boundary = boundary or not ok
                break
        if not ok:
            h /= 2
            if h < step_min:
                if boundary:
                    return Branch(points, folds, f"stopped at the boundary omega > 0: the next point had omega <= 0 "
                                                 f"past omega = {y[-1] * sw:g}, with the step at its minimum "
                                                 f"{step_min:g}", bifurcations)
                return Branch(points, folds, f"the corrector failed at omega = {y[-1] * sw:g} with the step at its "
                                             f"minimum {step_min:g}", bifurcations)
            continue
        boundary = False
        R, J, dRw = hb.residual(z[:-1] * sx, z[-1] * sw)
        t_new = _tangent(J * sx[None, :], dRw * sw, t)
        if t_new[-1] * t[-1] < 0:
            folds.append(len(points))                          # a turning point between the last point and this one
        exps = hb.floquet_exponents(z[:-1] * sx, z[-1] * sw, J) if stability else None
        X, L = _split(hb, z[:-1] * sx)
        points.append(PeriodicSolution(z[-1] * sw, X, exps, _stable(exps, z[-1] * sw), float(np.linalg.norm(R)),
                                       L=L))
        if progress is not None:
            progress(points[-1])
        change = _crossing(points[-2], points[-1])
        if change is not None:
            bifurcations.append((len(points) - 1,) + change)
        y, t = z, t_new
        if (y[-1] * sw - omega_end) * direction >= 0:
            return Branch(points, folds, f"reached omega = {omega_end:g}", bifurcations)
        h = min(step_max, 1.5 * h)
    return Branch(points, folds, f"stopped after {max_points} points", bifurcations)


def backbone(hb: HarmonicBalance, dof: int, amplitudes, x0: np.ndarray, omega0: float, tol: float = 1e-12,
             max_iter: int = 30) -> list:
    """The backbone (the nonlinear normal mode's frequency against amplitude) of the undamped, unforced system of
    ``hb`` (its C and F must be zero): its synchronous periodic orbits, even in time (cosine terms only: an orbit
    released from rest at its largest displacement), each with the first-harmonic amplitude a_1 of ``dof`` given by
    ``amplitudes`` (in order; each solved by Newton on (a, omega) from the previous one, the first from (x0,
    omega0)). The cosine rows of the balance are solved for the cosine coefficients and omega; the phase of the
    autonomous orbit is fixed by leaving the sine terms out. Returns PeriodicSolutions (no stability: a
    conservative orbit's exponents sit on the imaginary axis)."""
    if np.any(hb.C) or np.any(hb.F):
        raise ValueError("backbone: the system must be undamped and unforced (C = 0, F = 0)")
    real_number("omega0", omega0, 0.0, open_low=True, unit=" rad/s")
    H, n = hb.basis.H, hb.n
    cos = np.r_[0, 2 * np.arange(1, H + 1) - 1]                    # the coefficient rows 1, cos tau, cos 2 tau, ...
    keep = (cos[:, None] * n + np.arange(n)[None, :]).ravel()
    pin = 1 * n + dof                                               # a_1 of dof: the amplitude, given
    free = keep[keep != pin]
    x = np.asarray(x0, float).ravel().copy()
    x[np.setdiff1d(np.arange(hb.size), keep)] = 0.0
    omega, out = float(omega0), []
    for A in amplitudes:
        x[pin] = A
        for it in range(1, max_iter + 1):
            R, J, dRw = hb.residual(x, omega)
            A_ = np.column_stack([J[np.ix_(keep, free)], dRw[keep]])
            dz = np.linalg.solve(A_, -R[keep])
            x[free] += dz[:-1]
            omega += dz[-1]
            if np.linalg.norm(dz) <= tol * max(np.linalg.norm(x) + abs(omega), 1e-300):
                break
        else:
            raise ValueError(f"backbone: Newton did not converge in {max_iter} iterations at amplitude {A:g}")
        R = hb.residual(x, omega, jacobian=False)
        out.append(PeriodicSolution(omega, x.reshape(hb.basis.size, n).copy(), residual=float(np.linalg.norm(R)),
                                    iterations=it))
    return out
