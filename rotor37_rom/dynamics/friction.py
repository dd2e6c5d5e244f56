"""Friction-induced instability of the blade sliding on the casing (sprag-slip, mode coupling). Pure NumPy/SciPy.

At a tip node k in contact the casing pushes with -lambda_k (n_k + mu s_k): the normal force and the sliding
friction (``casing``). A twisted, swept blade tip that is pulled backwards along s_k can move outwards along n_k:
friction then presses the node harder into the casing, which raises the friction (Spurr's sprag-slip). For a
persistent sliding contact on the node set A (N q = g, casing locally fixed) the reduced equations

    M q'' + C q' + K q = -B lambda,   N q = g,   B = (N + mu S)^T

are linear, with a constraint force that is not along the constraint's normal. On q = T z (N T = 0) and projected
with L (L B = 0) they become L M T z'' + L C T z' + L K T z = 0, whose eigenvalues (the complex eigenvalue
analysis of brake squeal) say whether sliding is stable:

- divergence: a real eigenvalue crosses zero where the static problem is singular, det(N K^-1 B) = 0; for one node
  mu* = -G_nn / G_ns with G = K^-1 the static compliance (``sprag_slip_friction``). Craig-Bampton keeps the tip
  DOFs, so this compliance is the full-order one (constraint modes are exact static responses);
- flutter: two eigenvalues merge and leave the imaginary axis (mode coupling), found by ``critical_friction``.

Contact in a rub is intermittent, so these onsets are those of sustained sliding; the energy balance of a run
(``dynamics.explicit.simulate``: ``work``) shows how much energy friction gives the blade between them.
"""
from __future__ import annotations

import numpy as np
import scipy.linalg

__all__ = ["sliding_contact_eigenvalues", "sprag_slip_friction", "critical_friction"]


def _rows(N, S, nodes):
    sel = np.arange(N.shape[0]) if nodes is None else np.atleast_1d(np.asarray(nodes, dtype=np.int64))
    if sel.size == 0 or sel.min() < 0 or sel.max() >= N.shape[0] or len(set(sel.tolist())) != sel.size:
        raise ValueError(f"nodes must be distinct contact-node rows in [0, {N.shape[0] - 1}], got {sel.tolist()}")
    return N[sel], S[sel]


def sliding_contact_eigenvalues(M, C, K, N, S, mu: float, nodes=None) -> np.ndarray:
    """Eigenvalues (1/s) of the reduced model in persistent sliding contact at the rows ``nodes`` of N, S (all by
    default; N, S from ``dynamics.casing.contact_matrices``) with friction coefficient mu: 2 (r - n_A) of them, sorted
    by
    decreasing real part. Re > 0: the sliding state is unstable (rate Re, frequency |Im|)."""
    if not mu >= 0.0:
        raise ValueError(f"friction coefficient mu must be >= 0, got {mu}")
    Na, Sa = _rows(np.asarray(N, float), np.asarray(S, float), nodes)
    B = (Na + mu * Sa).T
    T = scipy.linalg.null_space(Na)                      # motions that keep the contact (r, r - n_A)
    L = scipy.linalg.null_space(B.T).T                   # equations free of the multipliers (r - n_A, r)
    m, c, k = L @ M @ T, L @ C @ T, L @ K @ T
    n = T.shape[1]
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(m, k), -np.linalg.solve(m, c)]])
    ev = np.linalg.eigvals(A)
    return ev[np.argsort(-ev.real)]


def sprag_slip_friction(K, N, S, nodes=None, compliance: np.ndarray | None = None) -> float:
    """Smallest mu > 0 at which persistent sliding on the rows ``nodes`` diverges: det(N G (N + mu S)^T) = 0 with
    G = K^-1; -G_nn / G_ns for one node. inf when friction never wedges these nodes (G_ns >= 0 for one node).
    ``compliance``: K^-1 if the caller has it (many node sets of one model)."""
    Na, Sa = _rows(np.asarray(N, float), np.asarray(S, float), nodes)
    G = np.linalg.inv(np.asarray(K, float)) if compliance is None else np.asarray(compliance, float)
    A, Bm = Na @ G @ Na.T, Na @ G @ Sa.T
    nu = np.linalg.eigvals(np.linalg.solve(A, Bm))      # (A + mu Bm) x = 0  <=>  A^-1 Bm x = -x / mu
    real = nu[(np.abs(nu.imag) <= 1e-12 * np.abs(nu).max()) & (nu.real < 0)].real
    return float(-1.0 / real.min()) if real.size else float("inf")


def critical_friction(M, C, K, N, S, nodes=None, mu_max: float = 1.0, n_grid: int = 100, rtol: float = 1e-6,
                      min_rate: float = 0.0) -> tuple[float, complex]:
    """Smallest mu in (0, mu_max] where sliding on ``nodes`` loses stability (an eigenvalue with Re > min_rate, in
    1/s: growth slower than that does not matter over the runs at hand), by a scan over n_grid coefficients and
    bisection of the first crossing to rtol; (inf, nan) if stable up to mu_max. Returns (mu, the leading eigenvalue
    just above it): real for divergence, complex for flutter."""
    if not (mu_max > 0 and n_grid >= 2 and min_rate >= 0):
        raise ValueError(f"mu_max must be > 0, n_grid >= 2 and min_rate >= 0, got {mu_max}, {n_grid}, {min_rate}")

    def lead(mu):
        return sliding_contact_eigenvalues(M, C, K, N, S, mu, nodes)[0]

    if lead(0.0).real > min_rate:
        raise ValueError("the model is unstable without friction (an eigenvalue with Re > min_rate at mu = 0)")
    lo = 0.0
    for hi in np.linspace(0.0, mu_max, n_grid + 1)[1:]:
        if lead(hi).real > min_rate:
            break
        lo = hi
    else:
        return float("inf"), complex("nan")
    while hi - lo > rtol * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if lead(mid).real > min_rate else (mid, hi)
    return float(hi), complex(lead(hi))
