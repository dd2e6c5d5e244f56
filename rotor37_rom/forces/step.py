"""STEP: the stiffness evaluation procedure with enforced displacements (Muravyov & Rizzi, Comput. Struct. 81
(2003) 1513), identifying A~ and B~ of eq. (24) from nonlinear force evaluations of the full model (pure NumPy;
the force evaluation is passed in)."""
from __future__ import annotations

from typing import Callable

import numpy as np

from rotor37_rom.forces.tensors import PolynomialForces, _pair_index, cubic_monomial_indices

__all__ = ["step_displacement_sets", "identify_step"]


def step_displacement_sets(r: int) -> np.ndarray:
    """The unit-amplitude coordinate vectors STEP evaluates: +-e_i; e_i + e_j, -e_i - e_j, e_i - e_j (i < j);
    e_i + e_j + e_k (i < j < k). Shape (r, 2r + 3 r(r-1)/2 + r(r-1)(r-2)/6)."""
    cols = []
    eye = np.eye(r)
    for i in range(r):
        cols += [eye[i], -eye[i]]
    for i in range(r):
        for j in range(i + 1, r):
            cols += [eye[i] + eye[j], -eye[i] - eye[j], eye[i] - eye[j]]
    for i in range(r):
        for j in range(i + 1, r):
            for k in range(j + 1, r):
                cols.append(eye[i] + eye[j] + eye[k])
    return np.array(cols).T


def identify_step(g: Callable[[np.ndarray], np.ndarray], scales: np.ndarray, batch: int = 64) -> PolynomialForces:
    """Identify the reduced cubic forces from evaluations g(Q) -> (r, P) of the reduced nonlinear force.

    Args:
        g: reduced nonlinear force of a batch of reduced coordinates (r, P), e.g. Phi^T g_nl(Phi q) from the FE model.
        scales: (r,) amplitude of each coordinate in the enforced displacements (q_i = +-scales_i); STEP's accuracy
            depends on it (round-off grows as the amplitude shrinks; SVK being exactly cubic there is no truncation
            error at large amplitude).
    """
    scales = np.asarray(scales, float)
    r = scales.size
    S = step_displacement_sets(r)
    values = np.hstack([g(scales[:, None] * S[:, k:k + batch]) for k in range(0, S.shape[1], batch)])
    n_quad = r * (r + 1) // 2
    A = np.zeros((r, n_quad))
    ca, cb, cc = cubic_monomial_indices(r)
    B = np.zeros((r, ca.size))

    def cubic_index(a, b, c):
        a, b, c = sorted((a, b, c))
        # position of (a, b, c) in the lexicographic list of combinations with replacement
        before_a = sum((r - x) * (r - x + 1) // 2 for x in range(a))
        return before_a + _pair_index(r - a, np.array(b - a), np.array(c - a)).item()

    col = 0
    Aii, Biii = np.zeros((r, r)), np.zeros((r, r))
    for i in range(r):
        gp, gm = values[:, col], values[:, col + 1]
        Aii[:, i], Biii[:, i] = 0.5 * (gp + gm), 0.5 * (gp - gm)
        A[:, _pair_index(r, np.array(i), np.array(i))] = Aii[:, i]
        B[:, cubic_index(i, i, i)] = Biii[:, i]
        col += 2
    Aij = {}
    for i in range(r):
        for j in range(i + 1, r):
            gpp, gmm, gpm = values[:, col], values[:, col + 1], values[:, col + 2]
            col += 3
            a_ij = 0.5 * (gpp + gmm) - Aii[:, i] - Aii[:, j]
            s1 = 0.5 * (gpp - gmm) - Biii[:, i] - Biii[:, j]
            d1 = gpm - (Aii[:, i] + Aii[:, j] - a_ij) - Biii[:, i] + Biii[:, j]
            A[:, _pair_index(r, np.array(i), np.array(j))] = a_ij
            B[:, cubic_index(i, j, j)] = 0.5 * (s1 + d1)
            B[:, cubic_index(i, i, j)] = 0.5 * (s1 - d1)
            Aij[i, j] = a_ij
    for i in range(r):
        for j in range(i + 1, r):
            for k in range(j + 1, r):
                known = (Aii[:, i] + Aii[:, j] + Aii[:, k] + Aij[i, j] + Aij[i, k] + Aij[j, k]
                         + Biii[:, i] + Biii[:, j] + Biii[:, k])
                for a, b in ((i, j), (j, i), (i, k), (k, i), (j, k), (k, j)):
                    known = known + B[:, cubic_index(a, a, b)]
                B[:, cubic_index(i, j, k)] = values[:, col] - known
                col += 1
    # back to unscaled coordinates: coefficient / product of the scales of its indices
    qa, qb = np.triu_indices(r)
    A /= scales[qa] * scales[qb]
    B /= scales[ca] * scales[cb] * scales[cc]
    return PolynomialForces(A=A, B=B)
