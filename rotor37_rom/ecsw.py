"""ECSW hyper-reduction (Farhat, Avery, Chapman & Cortial, IJNME 98 (2014) 625): a sparse, non-negatively weighted
subset of cells whose reduced nonlinear forces reproduce the full ones on training states (pure NumPy/SciPy)."""
from __future__ import annotations

import dataclasses

import numpy as np
import scipy.optimize

from rotor37_rom.nonlinear_forces import QuadratureForces

__all__ = ["EcswResult", "cell_contributions", "train_ecsw"]


def cell_contributions(forces: QuadratureForces, cells: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """Per-cell reduced nonlinear forces: (r * n_states, n_cells) for the states Q (r, n_states)."""
    n_cells = int(cells.max()) + 1
    per_point = []
    for k in range(Q.shape[1]):
        single = QuadratureForces(forces.H, np.ones_like(forces.w), forces.lmbda, forces.mu)
        # contribution of each point: w_p * (first PK - linear) : H_p,m, summed per cell
        G = single._gradients(Q[:, [k]])[..., 0]
        F = np.eye(3) + G
        eps = 0.5 * (G + np.swapaxes(G, 1, 2))
        E = eps + 0.5 * np.einsum("nki,nkj->nij", G, G)
        S, S_lin = single._stress(E[..., None])[..., 0], single._stress(eps[..., None])[..., 0]
        P1 = np.einsum("nik,nkj->nij", F, S) - S_lin
        contrib = forces.w[:, None] * np.einsum("nij,nmij->nm", P1, forces.H)    # (n_points, r)
        per_cell = np.zeros((n_cells, forces.r))
        np.add.at(per_cell, cells, contrib)
        per_point.append(per_cell.T)
    return np.vstack(per_point)


@dataclasses.dataclass(frozen=True)
class EcswResult:
    """Selected cells, their weights, the hyper-reduced forces and the training residual (relative)."""

    cells: np.ndarray
    weights: np.ndarray
    forces: QuadratureForces
    training_error: float


def train_ecsw(forces: QuadratureForces, cells: np.ndarray, Q_train: np.ndarray, tol: float = 1e-3,
               max_cells: int | None = None) -> EcswResult:
    """Sparse NNLS (greedy active set, Lawson-Hanson on the active columns) until
    ||G xi - b|| <= tol ||b||, with G the per-cell contributions on the training states and b their sum.

    Args:
        forces: exact quadrature forces on all points; cells: (n_points,) cell of each point.
        Q_train: (r, n_states) training states. tol: relative training tolerance, in (0, 1).
    """
    if not (0.0 < tol < 1.0):
        raise ValueError(f"tol must be in (0, 1), got {tol}")
    G = cell_contributions(forces, cells, Q_train)
    # every training state counts equally: normalise its block of r rows by the norm of its total force
    r = forces.r
    blocks = G.reshape(-1, r, G.shape[1])
    norms = np.linalg.norm(blocks.sum(axis=2), axis=1)
    norms[norms == 0] = 1.0
    G = (blocks / norms[:, None, None]).reshape(G.shape)
    b = G.sum(axis=1)
    n_cells = G.shape[1]
    max_cells = max_cells or n_cells
    active: list[int] = []
    xi = np.zeros(0)
    residual = b.copy()
    b_norm = np.linalg.norm(b)
    while np.linalg.norm(residual) > tol * b_norm and len(active) < max_cells:
        grad = G.T @ residual
        grad[active] = -np.inf
        j = int(np.argmax(grad))
        if grad[j] <= 0:
            break
        active.append(j)
        xi, _ = scipy.optimize.nnls(G[:, active], b)
        keep = xi > 0
        active = [a for a, k in zip(active, keep) if k]
        xi = xi[keep]
        residual = b - G[:, active] @ xi
    sel = np.array(active, dtype=np.int64)
    mask = np.isin(cells, sel)
    cell_weight = np.zeros(n_cells)
    cell_weight[sel] = xi
    hr = QuadratureForces(forces.H[mask], forces.w[mask] * cell_weight[cells[mask]], forces.lmbda, forces.mu)
    return EcswResult(cells=sel, weights=xi, forces=hr, training_error=float(np.linalg.norm(residual) / b_norm))
