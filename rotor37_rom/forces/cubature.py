"""Hyper-reduction of the reduced SVK forces (pure NumPy/SciPy): a sparse, non-negatively weighted subset of the
quadrature whose reduced nonlinear forces reproduce the full ones on training states.

Two granularities: whole cells (ECSW, Farhat, Avery, Chapman & Cortial, IJNME 98 (2014) 625) or single quadrature
points (empirical cubature, Hernandez, Caicedo & Ferrer, CMAME 313 (2017) 687). Either way the hyper-reduced force
is the gradient of a non-negatively weighted sum of SVK point energies, so it stays conservative, and the linear
part K~ is kept exact: only g~ is approximated.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import scipy.optimize

from rotor37_rom.forces.tensors import QuadratureForces

__all__ = ["EcswResult", "cell_contributions", "train_ecsw", "state_errors", "trajectory_states", "spread_columns"]


def cell_contributions(forces: QuadratureForces, cells: np.ndarray, Q: np.ndarray,
                       chunk_states: int = 16) -> np.ndarray:
    """Per-cell (or per-group) reduced nonlinear forces: (n_states * r, n_cells) for the states Q (r, n_states),
    rows ordered state by state."""
    Q = np.asarray(Q, float).reshape(forces.r, -1)
    cells = np.asarray(cells)
    n_cells, r, n_states = int(cells.max()) + 1, forces.r, Q.shape[1]
    out = np.zeros((n_states, r, n_cells))
    grouped = cells.size != n_cells or np.any(cells != np.arange(n_cells))
    for k in range(0, n_states, chunk_states):
        contrib = forces.point_contributions(Q[:, k:k + chunk_states])     # (n_points, r, S)
        block = out[k:k + chunk_states]                                    # (S, r, n_cells)
        if grouped:
            for s in range(contrib.shape[2]):
                np.add.at(block[s].T, cells, contrib[:, :, s])
        else:
            block[...] = contrib.transpose(2, 1, 0)
    return out.reshape(n_states * r, n_cells)


def state_errors(exact: QuadratureForces, hyper: QuadratureForces, Q: np.ndarray) -> np.ndarray:
    """Relative error ||g_hyper - g|| / ||g|| of the reduced nonlinear force at each state (column of Q)."""
    g = exact.evaluate(Q)
    return np.linalg.norm(hyper.evaluate(Q) - g, axis=0) / np.maximum(np.linalg.norm(g, axis=0), 1e-300)


def trajectory_states(runs, boundary_rows, n_per_run: int = 25, n_largest: int = 5, n_held: int = 0,
                      seed: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """Training states from recorded runs (each (r, n_rec), e.g. ``SimulationResult.records_q``): per run,
    n_per_run finite instants spread over it after its first tenth (the ramp) plus its n_largest states of largest
    motion of the entries ``boundary_rows`` of q (``NodeMap.boundary_rows``); and n_held random other instants of
    each run for checking. Returns (train, held)."""
    boundary_rows = np.asarray(boundary_rows, dtype=np.int64)
    rng = np.random.default_rng(seed)
    train, held = [], []
    for q in runs:
        q = np.asarray(q, float)
        q = q[:, np.isfinite(q).all(axis=0)]
        if q.shape[1] == 0:
            continue
        amp = np.abs(q[boundary_rows]).max(axis=0)
        spread = np.linspace(q.shape[1] // 10, q.shape[1] - 1, n_per_run).astype(int)
        picked = np.unique(np.r_[spread, np.argsort(amp)[::-1][:n_largest]])
        train.append(q[:, picked])
        others = np.setdiff1d(np.arange(q.shape[1]), picked)      # held-out instants are never training ones
        if n_held and others.size:
            held.append(q[:, rng.choice(others, min(n_held, others.size), replace=False)])
    if not train:
        raise ValueError("trajectory_states: no finite recorded state in the runs")
    r = train[0].shape[0]
    return np.hstack(train), (np.hstack(held) if held else np.zeros((r, 0)))


def spread_columns(X: np.ndarray, n: int) -> np.ndarray:
    """Indices of at most n nonzero columns of X to train on: the n // 2 of largest norm and the rest evenly spread
    over the others in their order (all nonzero columns if there are no more than n). For the columns of many
    similar states (a disk's sectors, each state's 36 of them), whose full set would make the training matrix
    n_columns x r rows by n_points."""
    if n < 1:
        raise ValueError(f"n must be >= 1, got {n}")
    norms = np.linalg.norm(X, axis=0)
    nonzero = np.flatnonzero(norms > 0)
    if nonzero.size <= n:
        return nonzero
    largest = nonzero[np.argsort(-norms[nonzero], kind="stable")[:n // 2]]
    rest = np.setdiff1d(nonzero, largest)
    spread = rest[np.linspace(0, rest.size - 1, n - largest.size).round().astype(int)]
    return np.union1d(largest, spread)


@dataclasses.dataclass(frozen=True)
class EcswResult:
    """Selected cells (or points), their weights, the hyper-reduced forces and the training residual (relative)."""

    cells: np.ndarray
    weights: np.ndarray
    forces: QuadratureForces
    training_error: float

    @property
    def n_points(self) -> int:
        """Quadrature points the hyper-reduced force evaluates (what its cost scales with)."""
        return int(self.forces.w.size)


def train_ecsw(forces: QuadratureForces, cells: np.ndarray, Q_train: np.ndarray, tol: float = 1e-3,
               max_cells: int | None = None, level: str = "cell", grow: float = 0.05) -> EcswResult:
    """Sparse NNLS (greedy active set, Lawson-Hanson on the active columns) until ||G xi - b|| <= tol ||b||, with
    G the per-cell (level='cell') or per-point (level='point') contributions on the training states and b their sum.
    Each training state's block is normalised by the norm of its total force, so small states count as much as
    large ones.

    Args:
        forces: exact quadrature forces on all points; cells: (n_points,) cell of each point.
        Q_train: (r, n_states) training states. tol: relative training tolerance, in (0, 1).
        max_cells: stop after this many selected columns. level: 'cell' or 'point'.
        grow: columns added per greedy pass, as a fraction of those already selected (at least one): fewer NNLS
            solves when hundreds of points are needed.
    """
    if not (0.0 < tol < 1.0):
        raise ValueError(f"tol must be in (0, 1), got {tol}")
    if level not in ("cell", "point"):
        raise ValueError(f"level must be 'cell' or 'point', got {level!r}")
    if not (0.0 <= grow <= 1.0):
        raise ValueError(f"grow must be in [0, 1], got {grow}")
    cells = np.asarray(cells)
    groups = cells if level == "cell" else np.arange(cells.size)
    G = cell_contributions(forces, groups, Q_train)
    r = forces.r
    blocks = G.reshape(-1, r, G.shape[1])
    norms = np.linalg.norm(blocks.sum(axis=2), axis=1)
    norms[norms == 0] = 1.0
    G = (blocks / norms[:, None, None]).reshape(G.shape)
    b = G.sum(axis=1)
    n_cols = G.shape[1]
    max_cells = max_cells or n_cols
    active: list[int] = []
    xi = np.zeros(0)
    residual = b.copy()
    b_norm = np.linalg.norm(b)
    while np.linalg.norm(residual) > tol * b_norm and len(active) < max_cells:
        grad = G.T @ residual
        grad[active] = -np.inf
        n_new = min(max(1, int(grow * len(active))), max_cells - len(active))
        new = np.argsort(grad)[::-1][:n_new]
        new = new[grad[new] > 0]
        if new.size == 0:
            break
        active.extend(int(j) for j in new)
        xi, _ = scipy.optimize.nnls(G[:, active], b, maxiter=50 * len(active))
        keep = xi > 0
        active = [a for a, k in zip(active, keep) if k]
        xi = xi[keep]
        residual = b - G[:, active] @ xi
    sel = np.array(active, dtype=np.int64)
    mask = np.isin(groups, sel)
    weight = np.zeros(n_cols)
    weight[sel] = xi
    hr = QuadratureForces(forces.H[mask], forces.w[mask] * weight[groups[mask]], forces.lmbda, forces.mu)
    return EcswResult(cells=sel, weights=xi, forces=hr, training_error=float(np.linalg.norm(residual) / b_norm))
