"""Modal damping laws a full-order model and its reduced models share exactly (issue #86).

A ``ModalLaw`` gives damping ratios to the lowest m modes of the linear model and a ratio growing with frequency
above them: C = beta K + (M Phi) diag(d) (M Phi)^T with Phi the first m modes (Phi^T M Phi = I), beta = 2 xi_m /
omega_m so that mode m has its ratio ``high`` and every mode above it omega has xi = high omega / omega_m (stiffness
proportional), and d_i = 2 xi_i omega_i - beta omega_i^2 so that the first m have their ratios exactly. In the
eigenbasis C is diagonal with 2 xi omega >= 0: positive semi-definite, although a d_i may be negative. No mode is
left undamped: an explicit reduced model in contact rings at its highest modes after every impact, and left
undamped they made the ci blade's r = 55 response wander by 20 % from revolution to revolution under 2 % on the
first 20 modes (1,200 and 1,280 rad/s, 40 revolutions), where the full order's generalised alpha damps them anyway.

A reduced model V (any Galerkin basis in the same DOFs) gets the same law by projection, V^T C V
(``LowRankDamping.project``): both sides carry one damping operator, not two modal laws on two sets of modes. The
implicit schemes factorise A + c C with A sparse: ``woodbury`` solves with it from the factorisation of A + c beta K
and an m x m capacitance matrix, so C never becomes a dense n x n matrix.
"""
from __future__ import annotations

import dataclasses
from typing import Callable

import numpy as np

__all__ = ["ModalLaw", "LowRankDamping", "woodbury", "MAPS_LAW", "DAMPING_LAWS", "damping_law"]


@dataclasses.dataclass(frozen=True)
class ModalLaw:
    """Damping ratios by mode order: ``low`` on the first ``n_low`` modes, ``high`` on the next ones up to
    ``n_modes`` (the modes kept), none above.

    The maps' law (``MAPS_LAW``, ``reduction.craig_bampton.modal_damping``): 5e-4 on 1B, 1T, 2B, 5e-3 above (paper
    §2.2.1)."""

    low: float = 5e-4
    high: float = 5e-3
    n_low: int = 3
    n_modes: int = 20

    def __post_init__(self):
        for name in ("low", "high"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and np.isfinite(value) and 0.0 <= value < 1.0):
                raise ValueError(f"damping law {name} must be a damping ratio in [0, 1), got {value!r}")
        if not (isinstance(self.n_modes, (int, np.integer)) and self.n_modes >= 1):
            raise ValueError(f"damping law n_modes must be an integer >= 1, got {self.n_modes!r}")
        if not (isinstance(self.n_low, (int, np.integer)) and 0 <= self.n_low <= self.n_modes):
            raise ValueError(f"damping law n_low must be an integer in [0, n_modes = {self.n_modes}], "
                             f"got {self.n_low!r}")

    def ratios(self, n: int) -> np.ndarray:
        """The damping ratios of the first n modes (n <= n_modes)."""
        return np.where(np.arange(n) < self.n_low, self.low, self.high)

    def operator(self, M, omega: np.ndarray, modes: np.ndarray, K=None) -> "LowRankDamping":
        """C on a model with mass M and stiffness K whose lowest eigenpairs are (omega, modes) (rad/s; M-orthonormal
        columns, at least ``n_modes`` of them: the first n_modes are used). K None: the modes above are undamped
        (the low-rank part alone)."""
        omega, modes = np.asarray(omega, float), np.asarray(modes, float)
        if omega.ndim != 1 or omega.size < self.n_modes or modes.shape != (modes.shape[0], omega.size):
            raise ValueError(f"modes must be (n, m) with m = len(omega) >= n_modes = {self.n_modes}, got "
                             f"{modes.shape} and {omega.shape}")
        if not (np.all(np.isfinite(omega)) and omega.min() > 0):
            raise ValueError("omega must be finite angular frequencies > 0 rad/s")
        m = self.n_modes
        beta = 0.0 if K is None else 2.0 * self.high / omega[m - 1]
        w = omega[:m]
        return LowRankDamping(np.asarray(M @ modes[:, :m]), 2.0 * self.ratios(m) * w - beta * w ** 2,
                              None if K is None else beta * K)


#: The maps' law (the reduced models' modal damping: 5e-4 on 1B, 1T, 2B, 5e-3 above) on the lowest 20 modes of the
#: full order (the ci blade's up to 21.7 kHz), stiffness proportional above
MAPS_LAW = ModalLaw()
#: The laws a run can name: the maps', and a heavier one under which the ci blade's 1B response settles within a
#: few revolutions (2 % on the first 20 modes: the free decay falls by exp(-2 pi 0.02 f_1B / f_rev) ~ 0.59 a
#: revolution at 1,280 rad/s, against 0.987 under the maps' 5e-4, i.e. ~300 revolutions to settle)
DAMPING_LAWS = {"maps": MAPS_LAW, "heavy": ModalLaw(low=0.02, high=0.02)}


def damping_law(name: str) -> ModalLaw:
    """The damping law of that name (``DAMPING_LAWS``): ValueError naming the known ones otherwise."""
    if name not in DAMPING_LAWS:
        raise ValueError(f"damping law must be one of {', '.join(DAMPING_LAWS)}, got {name!r}")
    return DAMPING_LAWS[name]


@dataclasses.dataclass(frozen=True)
class LowRankDamping:
    """C = S + U diag(d) U^T, U (n, m), d (m,), S (n, n) a sparse or dense symmetric matrix or None: a viscous
    damping matrix for models of n DOFs (``ModalLaw.operator``: S = beta K, the sum positive semi-definite)."""

    U: np.ndarray
    d: np.ndarray
    S: object = None

    def __post_init__(self):
        U, d = np.asarray(self.U, float), np.asarray(self.d, float)
        if U.ndim != 2 or d.shape != (U.shape[1],):
            raise ValueError(f"U must be (n, m) and d (m,), got {U.shape} and {d.shape}")
        if not (np.all(np.isfinite(U)) and np.all(np.isfinite(d))):
            raise ValueError("U and d must be finite")
        if self.S is not None and getattr(self.S, "shape", None) != (U.shape[0], U.shape[0]):
            raise ValueError(f"S must be ({U.shape[0]}, {U.shape[0]}) like U's rows, got "
                             f"{getattr(self.S, 'shape', None)}")
        object.__setattr__(self, "U", U)
        object.__setattr__(self, "d", d)

    @property
    def shape(self) -> tuple[int, int]:
        return (self.U.shape[0], self.U.shape[0])

    def __matmul__(self, x):
        low = self.U @ (self.d[:, None] * (self.U.T @ x)) if np.ndim(x) == 2 else self.U @ (self.d * (self.U.T @ x))
        return low if self.S is None else low + self.S @ x

    def dense(self) -> np.ndarray:
        low = (self.U * self.d) @ self.U.T
        if self.S is None:
            return low
        return low + (self.S.toarray() if hasattr(self.S, "toarray") else np.asarray(self.S))

    def project(self, V: np.ndarray) -> np.ndarray:
        """V^T C V (r, r): the same law on a Galerkin basis V (n, r)."""
        V = np.asarray(V)
        W = V.T @ self.U
        out = (W * self.d) @ W.T
        return out if self.S is None else out + V.T @ np.asarray(self.S @ V)


def woodbury(solve: Callable, U: np.ndarray, d: np.ndarray) -> Callable:
    """solve for A + U diag(d) U^T from solve(B) = A^-1 B (A symmetric): Y - Z (D^-1 + U^T Z)^-1 U^T Y with
    Y = A^-1 B, Z = A^-1 U, D = diag(d), written as (I + D U^T Z)^-1 D so that d = 0 entries drop out."""
    if not np.any(d):
        return solve
    Z = np.asarray(solve(U))
    Z = Z.reshape(U.shape)
    cap = np.eye(d.size) + d[:, None] * (U.T @ Z)
    lu = np.linalg.inv(cap)                    # m x m, m ~ 20: its inverse is as accurate as its LU here

    def solve_sum(B):
        Y = solve(B)
        corr = lu @ (d[:, None] * (U.T @ Y)) if np.ndim(B) == 2 else lu @ (d * (U.T @ Y))
        return Y - Z @ corr

    return solve_sum
