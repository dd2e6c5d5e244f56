"""Stress recovery from reduced states without reassembly (pure NumPy).

The displacement gradient is linear in q: grad u(x_p) = sum_i q_i H_i(x_p), with H the basis gradients at the
quadrature points (``fem.quadrature_gradients``, computed once). The Green-Lagrange strain is then quadratic in q,
E = sym(H q) + 1/2 (H q)^T (H q), so the exact SVK stresses at any instant cost one (n_points x 9 x r) product:

    F = I + H q,  S = lambda tr(E) I + 2 mu E,  sigma = F S F^T / det F     (GNL on)
    sigma = lambda tr(eps) I + 2 mu eps, eps = sym(H q)                     (GNL off)

and von Mises = sqrt(3/2 s:s). ``contributions`` exposes the linear and quadratic parts of E explicitly.
"""
from __future__ import annotations

import dataclasses

import numpy as np

__all__ = ["StressRecovery", "von_mises", "svk_cauchy", "YIELD_STRESS"]

YIELD_STRESS = 1.38e9          # Pa, the paper's sigma_Y (§3.4.2)


def von_mises(sigma: np.ndarray) -> np.ndarray:
    """sqrt(3/2 s:s), s the deviator of sigma (..., 3, 3)."""
    tr = np.trace(sigma, axis1=-2, axis2=-1)
    s = sigma - tr[..., None, None] / 3.0 * np.eye(3)
    return np.sqrt(1.5 * np.einsum("...ij,...ij->...", s, s))


def svk_cauchy(G: np.ndarray, lmbda: float, mu: float, nonlinear: bool = True) -> np.ndarray:
    """Cauchy stress from displacement gradients G (..., 3, 3): exact SVK, or the linear stress."""
    I = np.eye(3)
    if not nonlinear:
        eps = 0.5 * (G + np.swapaxes(G, -1, -2))
        return lmbda * np.trace(eps, axis1=-2, axis2=-1)[..., None, None] * I + 2.0 * mu * eps
    F = I + G
    E = 0.5 * (np.swapaxes(F, -1, -2) @ F - I)
    S = lmbda * np.trace(E, axis1=-2, axis2=-1)[..., None, None] * I + 2.0 * mu * E
    return F @ S @ np.swapaxes(F, -1, -2) / np.linalg.det(F)[..., None, None]


@dataclasses.dataclass
class StressRecovery:
    """Stresses at the quadrature points of the mesh for any reduced state.

    Attributes:
        H: (n_points, r, 3, 3) basis gradients; cells: (n_points,) cell of each point; lmbda, mu: Lame (Pa).
    """

    H: np.ndarray
    cells: np.ndarray
    lmbda: float
    mu: float

    def __post_init__(self):
        n, r = self.H.shape[:2]
        self._Hflat = np.ascontiguousarray(self.H.transpose(0, 2, 3, 1)).reshape(n * 9, r)

    @property
    def r(self) -> int:
        return self.H.shape[1]

    def _check(self, q) -> np.ndarray:
        q = np.asarray(q, float)
        if q.ndim != 1 or q.size != self.r:
            raise ValueError(f"reduced state q has shape {q.shape}; the model has r = {self.r} coordinates")
        if not np.all(np.isfinite(q)):
            raise ValueError("reduced state q contains NaN or inf (a diverged simulation?)")
        return q

    def gradient(self, q) -> np.ndarray:
        """grad u at the points, (n_points, 3, 3)."""
        return (self._Hflat @ self._check(q)).reshape(-1, 3, 3)

    def contributions(self, q) -> tuple[np.ndarray, np.ndarray]:
        """Linear and quadratic parts of the Green-Lagrange strain, E = E1 + E2 (each (n_points, 3, 3))."""
        G = self.gradient(q)
        return 0.5 * (G + np.swapaxes(G, -1, -2)), 0.5 * np.swapaxes(G, -1, -2) @ G

    def cauchy(self, q, nonlinear: bool = True) -> np.ndarray:
        return svk_cauchy(self.gradient(q), self.lmbda, self.mu, nonlinear)

    def von_mises(self, q, nonlinear: bool = True) -> np.ndarray:
        """von Mises stress (Pa) at every quadrature point."""
        return von_mises(self.cauchy(q, nonlinear))

    def cell_max(self, q, nonlinear: bool = True) -> np.ndarray:
        """Largest von Mises over the points of each cell (a DG0 field for pictures)."""
        vm = self.von_mises(q, nonlinear)
        out = np.full(int(self.cells.max()) + 1, -np.inf)
        np.maximum.at(out, self.cells, vm)
        return out
