"""Proper orthogonal decomposition (POD) of full-order snapshots in the mass inner product, and the change of
coordinates that lets any basis run in the explicit contact scheme (pure NumPy/SciPy; issue #86 item 3a).

The POD basis of size r is the r-dimensional subspace that minimises the mean-square M-norm projection error of the
snapshots: no basis of that size represents them better, so a POD-Galerkin model of a full-order run is the bound on
what any reduced model of size r can reach on that run (if even it misses, the cause is not the basis). It is
computed by the method of snapshots (Sirovich 1987): the eigen-decomposition of the snapshots' correlation
S^T M S (n_snap, n_snap), which needs products with M only (no factorisation of the full mass).

The explicit scheme (``dynamics.explicit``) reads the contact nodes' displacements as entries of q
(``model.nodes.NodeMap``), so a basis must hold the boundary DOFs as its first coordinates, like a Craig-Bampton
basis [Psi Theta] (eq. 22). ``boundary_coordinates`` gives the change of coordinates within a basis's span that does
so: the span, hence the Galerkin model, is unchanged; only what the coordinates mean changes
(``reduction.builder.build_from_basis`` applies it and projects the operators and the exact forces).
"""

from typing import NamedTuple

import numpy as np
import scipy.linalg
import scipy.sparse as sp

from rotor37_rom.checks import whole_number

__all__ = ["PodBasis", "pod_basis", "boundary_coordinates"]

_EPS = np.finfo(float).eps


class PodBasis(NamedTuple):
    """What ``pod_basis`` returns (a tuple: ``basis, singular_values, bound, rank = pod_basis(...)``).

    Attributes:
        basis: (n_dofs, r) M-orthonormal POD modes (basis^T M basis = I), most energetic first.
        singular_values: (n_snap,) the snapshots' singular values in the M inner product, descending (those below
            the round-off of the method of snapshots are noise; ``rank`` counts the others).
        bound: sum of the discarded eigenvalues (sigma_i^2, i > r) over their total: the relative mean-square
            M-norm projection error of the snapshots onto the basis, sum_j |s_j - P s_j|_M^2 / sum_j |s_j|_M^2.
        rank: the snapshots' numerical rank (the largest r allowed).
    """

    basis: np.ndarray
    singular_values: np.ndarray
    bound: float
    rank: int


def _checked_snapshots(snapshots, M):
    """The snapshot matrix as a float array and M as a matrix with ``@``, or a one-line ValueError naming the
    argument at fault."""
    S = np.asarray(snapshots)
    if S.ndim != 2 or 0 in S.shape or not np.issubdtype(S.dtype, np.number) or np.iscomplexobj(S):
        raise ValueError(f"snapshots must be a real 2-D array (n_dofs, n_snap), got shape {S.shape} "
                         f"of {S.dtype}")
    S = S.astype(float, copy=False)
    if not np.isfinite(S).all():
        raise ValueError(f"snapshots must be finite: {np.count_nonzero(~np.isfinite(S))} entries are NaN or inf")
    if not (sp.issparse(M) or isinstance(M, np.ndarray)) or M.ndim != 2:
        raise ValueError(f"M must be the (n_dofs, n_dofs) mass matrix (NumPy or SciPy sparse), got "
                         f"{type(M).__name__}")
    if M.shape != (S.shape[0], S.shape[0]):
        raise ValueError(f"M has shape {M.shape}, the snapshots {S.shape}: M must be ({S.shape[0]}, {S.shape[0]})")
    values = M.data if sp.issparse(M) else M
    if not np.isfinite(values).all():
        raise ValueError("M must be finite: it holds NaN or inf entries")
    return S, M


def pod_basis(snapshots, M, r: int) -> PodBasis:
    """The M-orthonormal POD basis of size r of ``snapshots`` (n_dofs, n_snap), with the projection-error bound.

    Method of snapshots: C = S^T M S = W diag(lambda) W^T, sigma_i = sqrt(lambda_i), mode i = S w_i / sigma_i;
    the kept modes are M-orthonormalised once more (symmetrically, the modes barely move) against the round-off of
    the small singular values. The numerical rank counts the eigenvalues above n_snap eps lambda_max (the eigenvalues'
    round-off, ``numpy.linalg.matrix_rank``'s rule applied to C): r beyond it would take noise for modes.

    Args:
        snapshots: (n_dofs, n_snap) fields with the boundary conditions applied (e.g. the free DOFs of full-order
            states); M: (n_dofs, n_dofs) symmetric positive (semi-)definite mass on the same DOFs, dense or sparse;
        r: basis size, 1 <= r <= the snapshots' numerical rank.
    Returns ``PodBasis(basis, singular_values, bound, rank)``; ValueError naming the argument for bad input.
    """
    S, M = _checked_snapshots(snapshots, M)
    whole_number("r", r, 1)
    C = S.T @ np.asarray(M @ S)
    lam, W = scipy.linalg.eigh(0.5 * (C + C.T))
    lam, W = lam[::-1], W[:, ::-1]
    top = max(lam[0], 0.0)
    tol = max(S.shape[1], 1) * _EPS * top
    if lam[-1] < -1e3 * tol:
        raise ValueError(f"M is not positive semi-definite on the snapshots' span (correlation eigenvalue "
                         f"{lam[-1]:.3g} against the largest {lam[0]:.3g})")
    rank = int(np.count_nonzero(lam > tol))
    if r > rank:
        raise ValueError(f"r = {r} exceeds the snapshots' numerical rank {rank} (n_snap = {S.shape[1]}): "
                         f"take r <= {rank}")
    lam = np.maximum(lam, 0.0)
    sigma = np.sqrt(lam)
    V = S @ (W[:, :r] / sigma[:r])
    G = V.T @ np.asarray(M @ V)
    g, E = scipy.linalg.eigh(0.5 * (G + G.T))
    V = V @ (E / np.sqrt(g)) @ E.T                      # G^-1/2: M-orthonormal to round-off
    bound = float(lam[r:].sum() / lam.sum())
    return PodBasis(basis=V, singular_values=sigma, bound=bound, rank=rank)


def _real_matrix(name: str, A, shape: str) -> np.ndarray:
    """A as a finite 2-D float array, or a one-line ValueError naming ``name`` and the ``shape`` it must have."""
    try:
        out = np.asarray(A, float)
    except (TypeError, ValueError):
        out = None
    if out is None or out.ndim != 2 or not np.isfinite(out).all():
        raise ValueError(f"{name} must be a finite real array {shape}, got {type(A).__name__} of shape "
                         f"{np.shape(A) if out is not None else '?'}")
    return out


def boundary_coordinates(V_b, K, M) -> np.ndarray:
    """T (r, r) such that the basis V T holds the boundary DOFs as its first coordinates: (V T)[boundary] =
    [I 0], the Craig-Bampton form (eq. 22) within the span of V. The span is unchanged, so the Galerkin model is the
    same, only in coordinates the explicit contact scheme reads (``model.nodes.NodeMap``: q[:r_b] are the boundary
    DOFs' displacements).

    The last r - r_b columns are the span's fixed-interface modes (zero on the boundary; eigenvectors of K, M there,
    M-normalised, by frequency); the first r_b its constraint modes (a unit displacement of one boundary DOF, zero on
    the others, K-orthogonal to the fixed-interface modes: the least strain energy the span allows).

    Args:
        V_b: (r_b, r) the basis's rows at the boundary DOFs (of full rank r_b <= r: each boundary DOF must move
            independently within the span); K, M: (r, r) the reduced stiffness and mass V^T K V, V^T M V (symmetric,
            positive definite).
    ValueError naming the argument for bad input.
    """
    V_b = _real_matrix("V_b", V_b, "(r_b, r) with 1 <= r_b <= r")
    if V_b.shape[0] < 1 or V_b.shape[0] > V_b.shape[1]:
        raise ValueError(f"V_b must be (r_b, r) with 1 <= r_b <= r, got shape {V_b.shape}")
    r_b, r = V_b.shape
    K, M = (_real_matrix(name, A, f"({r}, {r}): the reduced matrix") for name, A in (("K", K), ("M", M)))
    for name, A in (("K", K), ("M", M)):
        if A.shape != (r, r):
            raise ValueError(f"{name} must be ({r}, {r}): the reduced matrix, got shape {A.shape}")
    U, s, Wt = scipy.linalg.svd(V_b)
    if s[-1] <= 1e-10 * s[0]:
        rank = np.count_nonzero(s > 1e-10 * s[0])
        raise ValueError(f"V_b: the basis's rows at the {r_b} boundary DOFs have rank {rank} < {r_b}: the "
                         f"boundary DOFs cannot move independently within its span")
    P = (Wt[:r_b].T / s) @ U.T                          # V_b P = I
    if r == r_b:
        return P
    N = Wt[r_b:].T                                       # V_b N = 0
    try:
        lam, E = scipy.linalg.eigh(N.T @ K @ N, N.T @ M @ N)
    except np.linalg.LinAlgError:
        raise ValueError("M is not positive definite on the span (the basis is rank-deficient)") from None
    if lam[0] <= 0:
        raise ValueError("K is not positive definite on the span's interior (is the basis clamped?)")
    Theta = N @ E
    return np.hstack([P - Theta @ ((Theta.T @ K @ P) / lam[:, None]), Theta])
