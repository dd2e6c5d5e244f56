"""Coulomb friction with sticking in harmonic balance, without regularisation: the friction forces' Fourier
coefficients are unknowns beside the displacements', and Coulomb's law holds exactly at the 2 H + 1 collocation
instants of the period (trigonometric collocation of the law; the mixed, frequency-time form of the dynamic Lagrangian
method of Nacivet, Pierre, Thouverez & Jezequel, JSV 265 (2003) 201-219, with the law collocated instead of
Fourier-projected).

A law acts through its rows T (n_c, n): the force on q is -T^T lambda. At each collocation instant

    phi = (lambda - proj(lambda + eps v)) / eps = 0,    v = T q',  proj onto [-mu N0, mu N0],

which holds exactly when v = 0 with |lambda| <= mu N0 (stick) or lambda = mu N0 sign(v) (slip): Coulomb's law, for
every eps > 0. eps (an augmentation, N s/m) only chooses which of the two conditions Newton imposes at an instant:
a root does not depend on it (verified to round-off in the tests), unlike a regularised law's. The price of
collocating a nonsmooth law is that a stick-slip transition is located to within one collocation interval, 2 pi /
(2 H + 1): the error falls as 1 / H, not as the orbit's own truncation (measured on Den Hartog's oscillator).

Unilateral contact is not here. A rigid impact has no periodic solution that a truncated Fourier series can carry:
the multiplier holds a Dirac at the impact, and its truncation's oscillations break lambda >= 0 at every sample near
it. On the one-degree-of-freedom impact oscillator both the Fourier-projected and the collocated complementarity
converge (residual 1e-16) to orbits 0.4-1.0 (RMS, amplitude ~1.2) away from the plastic (e = 0, the explicit
scheme's law) and the elastic (e = 1) orbits at every H from 4 to 128, however they are started; the restitution is
not a consequence of the constraint. Contact orbits are found by shooting the explicit scheme itself
(``periodic.shooting``). ``ContactBalance`` offers ``residual``, ``floquet_exponents``, ``size``, ``split`` and
``scales`` with ``HarmonicBalance``'s signatures, so ``solve_periodic`` and ``continue_branch`` solve and continue it.
Pure NumPy/SciPy.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import scipy.linalg

from .harmonic_balance import Harmonics, HarmonicBalance

__all__ = ["CoulombFriction", "ContactBalance"]


@dataclasses.dataclass
class CoulombFriction:
    """Coulomb friction on tangential velocities v = T q' at n_c points under constant normal loads N0: the force
    on q is -T^T lambda with |lambda| <= mu N0, v = 0 while |lambda| < mu N0 (stick), lambda = mu N0 sign(v) in slip.

    Attributes:
        T: (n_c, n) tangential rows. limit: mu N0 (N), (n_c,) or scalar, > 0. eps: the augmentation (N s/m), > 0;
        None: sqrt(diag(T K T^T) diag(T M T^T)) averaged (critical damping's scale).
    """

    T: np.ndarray
    limit: np.ndarray | float
    eps: float | None = None

    def __post_init__(self):
        self.T = np.atleast_2d(np.asarray(self.T, float))
        self.limit = np.broadcast_to(np.asarray(self.limit, float), (self.T.shape[0],)).copy()
        if not np.all(self.limit > 0):
            raise ValueError(f"friction limit mu N0 must be > 0 at every point, got {self.limit.tolist()}")
        if self.eps is not None and not self.eps > 0:
            raise ValueError(f"eps (the augmentation) must be > 0, got {self.eps}")

    def default_eps(self, M, K) -> float:
        k = np.einsum("ij,jk,ik->i", self.T, K, self.T)
        m = np.einsum("ij,jk,ik->i", self.T, M, self.T)
        return float(np.mean(np.sqrt(np.abs(k * m))))

    def project(self, lam: np.ndarray, V: np.ndarray):
        """phi (n_c, m) at m instants with multipliers lam (n_c, m) and velocities V (n, m), d phi / d lambda
        (n_c, m) and d phi / d v (m, n_c, n)."""
        v = self.T @ V
        lim = self.limit[:, None]
        pred = lam + self.eps * v
        stick = np.abs(pred) <= lim
        phi = np.where(stick, -v, (lam - np.sign(pred) * lim) / self.eps)
        d_lam = np.where(stick, 0.0, 1.0 / self.eps)
        d_v = -(stick.T[:, :, None] * self.T[None])
        return phi, d_lam, d_v


class ContactBalance:
    """The harmonic balance of ``hb`` (M q'' + C q' + K q + g(q) = f) with the friction ``laws``: the unknowns
    x = [X.ravel(), L_1.ravel(), ...], each law's multipliers' coefficients (2 H + 1, n_c) after X; the laws hold at
    the 2 H + 1 collocation instants (``colloc``)."""

    def __init__(self, hb: HarmonicBalance, laws):
        self.hb, self.basis, self.n = hb, hb.basis, hb.n
        self.laws = list(laws)
        for law in self.laws:
            if law.T.shape[1] != hb.n:
                raise ValueError(f"a friction law's rows act on {law.T.shape[1]} coordinates, the model has {hb.n}")
            if law.eps is None:
                law.eps = law.default_eps(hb.M, hb.K)
        self.colloc = Harmonics(hb.basis.H, hb.basis.size)
        self._Ec, self._Pc = self.colloc.synthesis, self.colloc.analysis
        self.sizes = [law.T.shape[0] for law in self.laws]
        self.offsets = np.cumsum([hb.size] + [hb.basis.size * s for s in self.sizes])

    @property
    def size(self) -> int:
        return int(self.offsets[-1])

    def split(self, x: np.ndarray):
        """(X (2 H + 1, n), [L (2 H + 1, n_c) per law])."""
        k = self.basis.size
        X = x[:self.hb.size].reshape(k, self.n)
        return X, [x[a:b].reshape(k, s) for a, b, s in zip(self.offsets[:-1], self.offsets[1:], self.sizes)]

    def scales(self, x: np.ndarray) -> np.ndarray:
        """Each unknown's scale: its block's norm (a multiplier block at zero: its law's limit)."""
        X, Ls = self.split(x)
        out = [np.full(X.size, max(np.linalg.norm(X), 1e-300))]
        for law, L in zip(self.laws, Ls):
            out.append(np.full(L.size, max(np.linalg.norm(L), float(law.limit.max()))))
        return np.concatenate(out)

    def _laws(self, x: np.ndarray, omega: float):
        """Per law: (its block's bounds, phi, d phi / d lambda, d phi / d v) at the collocation instants."""
        X, Ls = self.split(x)
        V = omega * (self._Ec @ self.hb._D @ X).T
        for law, L, a, b in zip(self.laws, Ls, self.offsets[:-1], self.offsets[1:]):
            yield (a, b, law, L) + law.project((self._Ec @ L).T, V)

    def residual(self, x: np.ndarray, omega: float, jacobian: bool = True, domega: bool = True):
        hb, k = self.hb, self.basis.size
        Ec, Pc, D = self._Ec, self._Pc, hb._D
        X, _ = self.split(x)
        out = hb.residual(x[:hb.size], omega, jacobian, domega)
        R = [out[0] if jacobian else out]
        if jacobian:
            J = np.zeros((self.size, self.size))
            J[:hb.size, :hb.size] = out[1]
            dRw = np.zeros(self.size) if domega else None
            if domega:
                dRw[:hb.size] = out[2]
        Ik, EcD = np.eye(k), Ec @ D
        for a, b, law, L, phi, d_lam, d_v in self._laws(x, omega):
            R[0] = R[0] + (L @ law.T).ravel()                     # the force -T^T lambda moved to the left
            R.append((Pc @ phi.T).ravel())
            if not jacobian:
                continue
            J[:hb.size, a:b] = np.kron(Ik, law.T.T)
            J[a:b, a:b] = _diagonal_block(Pc, d_lam, Ec)
            J[a:b, :hb.size] = omega * np.einsum("at,tij,tb->aibj", Pc, d_v, EcD).reshape(b - a, hb.size)
            if domega:
                dRw[a:b] = (Pc @ np.einsum("tij,jt->ti", d_v, (EcD @ X).T)).ravel()
        R = np.concatenate(R)
        return (R, J, dRw) if jacobian else R

    def floquet_exponents(self, x: np.ndarray, omega: float, J: np.ndarray | None = None) -> np.ndarray:
        """The 2 n Floquet exponents nearest the real axis (Hill's method on the mixed system: y = [p, lambda p,
        l], the multipliers' perturbations l without inertia; the law's rows act on the perturbation's velocity
        (omega D + lambda) p), by increasing real part."""
        hb, k, N = self.hb, self.basis.size, self.hb.size
        if J is None:
            J = self.residual(x, omega, domega=False)[1]
        Nl = self.size - N
        I = np.eye(k)
        D1 = np.kron(I, hb.C) + 2 * omega * np.kron(hb._D, hb.M)
        D2 = np.kron(I, hb.M)
        D1c = np.zeros((Nl, N))
        for a, b, law, L, phi, d_lam, d_v in self._laws(x, omega):
            D1c[a - N:b - N] = np.einsum("at,tij,tb->aibj", self._Pc, d_v, self._Ec).reshape(b - a, N)
        Z = np.zeros
        A = np.block([[Z((N, N)), np.eye(N), Z((N, Nl))],
                      [-J[:N, :N], -D1, -J[:N, N:]],
                      [-J[N:, :N], -D1c, -J[N:, N:]]])
        B = np.block([[np.eye(N), Z((N, N)), Z((N, Nl))],
                      [Z((N, N)), D2, Z((N, Nl))],
                      [Z((Nl, N)), Z((Nl, N)), Z((Nl, Nl))]])
        lam = scipy.linalg.eigvals(A, B)
        lam = lam[np.isfinite(lam) & (np.abs(lam) < 1e12 * max(omega, 1.0))]
        central = lam[np.argsort(np.abs(lam.imag), kind="stable")[:2 * self.n]]
        return central[np.argsort(central.real, kind="stable")]


def _diagonal_block(P, d, E):
    """sum_t P[:, t] (x) diag(d[:, t]) (x) E[t, :] on coefficient-major unknowns: ((2 H + 1) n_c)^2."""
    k, nc = P.shape[0], d.shape[0]
    out = np.einsum("at,it,tb->aib", P, d, E)                    # (k, n_c, k)
    J = np.zeros((k, nc, k, nc))
    idx = np.arange(nc)
    J[:, idx, :, idx] = out.transpose(1, 0, 2)
    return J.reshape(k * nc, k * nc)
