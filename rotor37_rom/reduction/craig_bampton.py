"""Craig-Bampton bases and modal derivatives with their selection (pure NumPy/SciPy; FE work is passed in).

References: Craig & Bampton, AIAA J. 6 (1968) 1313 (eqs. 6-11 of the paper); Idelsohn & Cardona (1985) and
Wu & Tiso (2016) for static modal derivatives (eqs. 16-21); selection criteria of §3.1.2 (eqs. 54-58)."""
from __future__ import annotations

import dataclasses
from typing import Callable

import numpy as np
import scipy.integrate
import scipy.linalg

from rotor37_rom.forces.tensors import QuadratureForces

CRITERIA = ("MMI", "MI2a", "MI2b", "SMVW", "random")


# the most clamped modes whose pairwise modal derivatives a basis takes (N (N + 1) / 2 vectors: 210 at 20)
GLOBAL_MD_MAX = 20


@dataclasses.dataclass(frozen=True)
class CraigBamptonBasis:
    """Phi = [Psi Theta Z] on the full DOF vector (eq. 22).

    Attributes:
        Psi: (n, r_b) constraint modes (identity on the boundary DOFs, eq. 8).
        Theta: (n, r_c) fixed-interface modes, M-normalised, zero on the boundary (eq. 10).
        omega_c: (r_c,) their frequencies (rad/s).
        boundary_dofs: (r_b,) full-vector indices of the boundary DOFs.
        Z: (n, r_MD) fixed-interface modal derivatives (eq. 20), M-normalised; md_pairs: (r_MD, 2) their (j, k).
        interface: None (the boundary coordinates are the DOFs ``boundary_dofs``), or (r_b, n) sparse C whose rows
            define them as functionals C u of the field (contact patches: each row a patch mean); then C Psi = I
            and C Theta = C Z = 0 take the place of "identity / zero on the boundary DOFs".
    """

    Psi: np.ndarray
    Theta: np.ndarray
    omega_c: np.ndarray
    boundary_dofs: np.ndarray
    Z: np.ndarray | None = None
    md_pairs: np.ndarray | None = None
    interface: object = None

    @property
    def linear(self) -> np.ndarray:
        """The linear Craig-Bampton modes [Psi Theta] (n, r_b + r_c)."""
        return np.hstack([self.Psi, self.Theta])

    @property
    def Phi(self) -> np.ndarray:
        return self.linear if self.Z is None else np.hstack([self.Psi, self.Theta, self.Z])

    @property
    def sizes(self) -> dict:
        return {"r_b": self.Psi.shape[1], "r_c": self.Theta.shape[1],
                "r_md": 0 if self.Z is None else self.Z.shape[1]}


def _scipy_factorization(A) -> Callable[[np.ndarray], np.ndarray]:
    import scipy.sparse.linalg

    lu = scipy.sparse.linalg.splu(scipy.sparse.csc_matrix(A))
    return lambda B: lu.solve(np.asarray(B, float))


def _scipy_eigenpairs(K, M, n_modes: int) -> tuple[np.ndarray, np.ndarray]:
    import scipy.sparse.linalg

    lam, V = scipy.sparse.linalg.eigsh(scipy.sparse.csc_matrix(K), n_modes, scipy.sparse.csc_matrix(M), sigma=0.0,
                                       which="LM")
    order = np.argsort(lam)
    return np.sqrt(lam[order]), V[:, order]


def interface_transform(C) -> tuple[object, np.ndarray]:
    """Coordinates x = (u with one DOF per row of C replaced by that row's value C_i u): u = T x. Each row's master
    is its entry of largest |C_ij| among the columns that no other row touches; x_master = C_i u, and
    u_master = (x_master - sum_(j != master) C_ij x_j) / C_(i, master). So C T x = x[masters] exactly and
    T = I outside the master rows. Returns (T (n, n) CSR, masters (n_b,)). ValueError for a row without such a
    column (rows that share all their columns: patches that overlap entirely) or a zero row."""
    import scipy.sparse

    C = scipy.sparse.csr_matrix(C)
    C.eliminate_zeros()
    n_b, n = C.shape
    touched = np.bincount(C.indices, minlength=n)
    masters = np.empty(n_b, dtype=np.int64)
    for i in range(n_b):
        cols, vals = C.indices[C.indptr[i]:C.indptr[i + 1]], C.data[C.indptr[i]:C.indptr[i + 1]]
        own = touched[cols] == 1
        if not own.any():
            raise ValueError(f"interface row {i} has no column of its own (its patch lies inside the others'): "
                             f"the boundary coordinates are not independent functionals of the field")
        masters[i] = cols[own][np.argmax(np.abs(vals[own]))]
    T = scipy.sparse.lil_matrix((n, n))
    T.setdiag(1.0)
    for i, m in enumerate(masters):
        cols, vals = C.indices[C.indptr[i]:C.indptr[i + 1]], C.data[C.indptr[i]:C.indptr[i + 1]]
        pivot = vals[cols == m][0]
        T[m, cols] = -vals / pivot
        T[m, m] = 1.0 / pivot
    return T.tocsr(), masters


def craig_bampton(K, M, boundary, n_interface: int,
                  solve: Callable | None = None, eigensolve: Callable | None = None
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Craig-Bampton modes (eqs. 8-11) of a structure: the one reduction that blade, disk sector and disk share.

    Args:
        K, M: (n, n) stiffness and mass (SciPy sparse or dense) on the DOFs that are not clamped.
        boundary: (n_b,) indices in [0, n) of the boundary DOFs kept physical (tip nodes, cyclic faces); or an
            (n_b, n) SciPy sparse C whose rows define the boundary coordinates C u (contact patches, RBE3-like
            means): the same modes in the coordinates of ``interface_transform``, so that C Psi = I (Psi: the
            field of least strain energy with C u = e_j), C Theta = 0 (Theta: the modes with C u held at 0).
        n_interface: r_c, the number of fixed-interface modes, 1 <= r_c < n - n_b.
        solve: factorize(A) -> (B -> A^-1 B), e.g. ``fem.mumps_solver``; default SciPy's SuperLU.
        eigensolve: (K, M, m) -> (omega (m,), V (., m)) lowest modes, e.g. ``fem.slepc_eigenpairs``; default SciPy's
            ARPACK in shift-invert.
    Returns:
        (Psi, Theta, omega_c): Psi (n, n_b) the constraint modes, the static responses to a unit displacement of one
        boundary DOF with the others held (identity on the boundary, K Psi = 0 on the interior, eq. 9); Theta
        (n, r_c) the lowest modes of the structure with its boundary fixed, zero there, Theta^T M Theta = I, each
        column's largest entry positive (eq. 11; the sign is thus machine-independent); omega_c (r_c,) rad/s.
    """
    import scipy.sparse

    K, M = scipy.sparse.csr_matrix(K), scipy.sparse.csr_matrix(M)
    n = K.shape[0]
    if scipy.sparse.issparse(boundary):
        if boundary.shape[1] != n:
            raise ValueError(f"the interface matrix must have n = {n} columns, got {boundary.shape}")
        T, masters = interface_transform(boundary)
        K_t, M_t = T.T @ (K @ T), T.T @ (M @ T)
        Psi, Theta, omega = craig_bampton(0.5 * (K_t + K_t.T), 0.5 * (M_t + M_t.T), masters, n_interface, solve,
                                          eigensolve)
        return T @ Psi, T @ Theta, omega
    boundary = np.asarray(boundary, dtype=np.int64).ravel()
    if boundary.size == 0 or boundary.min() < 0 or boundary.max() >= n:
        raise ValueError(f"boundary DOFs must be indices in [0, {n}) of DOFs that are not clamped")
    if len(np.unique(boundary)) != boundary.size:
        raise ValueError("boundary DOFs contain duplicates")
    interior = np.setdiff1d(np.arange(n), boundary)
    if not (1 <= n_interface < interior.size):
        raise ValueError(f"r_c (fixed-interface modes) must be in [1, {interior.size - 1}], got {n_interface}")
    solve = solve or _scipy_factorization
    eigensolve = eigensolve or _scipy_eigenpairs
    K_ii = K[interior][:, interior]
    M_ii = M[interior][:, interior]
    Psi = np.zeros((n, boundary.size))
    Psi[boundary, np.arange(boundary.size)] = 1.0
    Psi[interior] = -solve(K_ii)(K[interior][:, boundary].toarray())
    omega, V = eigensolve(K_ii, M_ii, n_interface)
    V = np.asarray(V, float)
    V = V / np.sqrt(np.einsum("ij,ij->j", V, M_ii @ V))
    from rotor37_rom.model.modes import normalise_signs

    Theta = np.zeros((n, n_interface))
    Theta[interior] = normalise_signs(V)
    return Psi, Theta, np.asarray(omega, float)


def modal_derivative_pairs(n_linear: int) -> np.ndarray:
    """All (j, k) with j <= k among the linear modes: n(n+1)/2 pairs (zeta_jk = zeta_kj, eq. 21)."""
    j, k = np.triu_indices(n_linear)
    return np.column_stack([j, k])


def fixed_interface_correction(xi: np.ndarray, Psi: np.ndarray, boundary_dofs: np.ndarray, interface=None
                               ) -> np.ndarray:
    """Eq. (20): zeta = xi - Psi xi_b, which vanishes on the boundary. xi: (n, m) -> (n, m). With an ``interface``
    C (``CraigBamptonBasis.interface``) the boundary values are C xi: zeta = xi - Psi C xi, C zeta = 0."""
    if interface is not None:
        return xi - Psi @ np.asarray(interface @ xi)
    zeta = xi - Psi @ xi[boundary_dofs]
    zeta[boundary_dofs] = 0.0
    return zeta


def selection_weights(criterion: str, q: np.ndarray, t: np.ndarray, Phi_lin: np.ndarray | None = None,
                      forces: QuadratureForces | None = None, seed: int = 0) -> np.ndarray:
    """Weights W_jk (n_lin, n_lin, symmetric) of the modal derivatives from a linear training response.

    Args:
        criterion: 'MMI' (eq. 54), 'MI2a' (55), 'MI2b' (56), 'SMVW' (57-58) or 'random'.
        q: (n_lin, n_t) linear Craig-Bampton coordinates of the training response; t: (n_t,) times (s).
        Phi_lin: (n, n_lin) the linear modes (MMI and MI2b use their norms and inner products).
        forces: exact quadrature forces of the linear modes (SMVW's virtual works).
    """
    if criterion not in CRITERIA:
        raise ValueError(f"criterion must be one of {CRITERIA}, got {criterion!r}")
    n = q.shape[0]
    if criterion == "random":
        W = np.random.default_rng(seed).random((n, n))
        return 0.5 * (W + W.T)
    if criterion == "MMI":
        a = np.linalg.norm(Phi_lin, axis=0) * np.abs(q).max(axis=1)
        return np.outer(a, a)
    if criterion in ("MI2a", "MI2b"):
        absq = np.abs(q)
        W = scipy.integrate.trapezoid(absq[:, None, :] * absq[None, :, :], t, axis=-1)
        if criterion == "MI2b":
            W *= np.abs(Phi_lin.T @ Phi_lin)
        return W
    # SMVW: t_jk = argmax (q_j q_k)^2; W = sqrt((phi_k^T g(phi_j q_j(t)))^2 + (phi_j^T g(phi_k q_k(t)))^2)
    prod = (q[:, None, :] * q[None, :, :]) ** 2
    t_max = prod.argmax(axis=-1)
    W = np.zeros((n, n))
    eye = np.eye(n)
    for j in range(n):  # n_lin single-mode force evaluations per distinct amplitude, batched over k
        amps = q[j, t_max[j]]                          # q_j at t_jk for every k
        g = forces.evaluate(eye[:, [j]] * amps[None, :])  # (n, n_lin): column k = g~(e_j q_j(t_jk))
        W[j] = np.diag(g)  # entry k: phi_k^T g(phi_j q_j(t_jk))
    return np.sqrt(W**2 + W.T**2)


def lift_states(q_lin: np.ndarray, pairs: np.ndarray, md_scale: np.ndarray) -> np.ndarray:
    """Full reduced states from linear Craig-Bampton coordinates q_lin (n_lin, n): the modal-derivative
    coordinates follow the second-order term of eq. (14), u ~ Phi q + 1/2 sum_jk xi_jk q_j q_k, i.e.
    eta_jk = c_jk q_j q_k md_scale_jk with c = 1/2 on the diagonal, 1 off it (each pair stored once).

    md_scale: (r_md,) norm of each modal derivative before normalisation (Z = zeta / md_scale)."""
    j, k = pairs[:, 0], pairs[:, 1]
    c = np.where(j == k, 0.5, 1.0) * (j >= 0)  # pairs of clamped normal modes (negative) are not lifted
    return np.vstack([q_lin, (c * md_scale)[:, None] * q_lin[np.maximum(j, 0)] * q_lin[np.maximum(k, 0)]])


def select_pairs(W: np.ndarray, r_md: int) -> np.ndarray:
    """The r_md pairs (j <= k) with the largest weights, best first."""
    pairs = modal_derivative_pairs(W.shape[0])
    if not (0 <= r_md <= len(pairs)):
        raise ValueError(f"r_md must be in [0, {len(pairs)}], got {r_md}")
    order = np.argsort(-W[pairs[:, 0], pairs[:, 1]], kind="stable")
    return pairs[order[:r_md]]


def modal_damping(K: np.ndarray, M: np.ndarray, ratios: Callable[[np.ndarray], np.ndarray] | None = None,
                  n_low: int = 3):
    """C~ = M~ V diag(2 xi_k omega_k) V^T M~ on the modes of the reduced model (V^T M~ V = I).

    Default ratios: xi = 5e-4 for the first ``n_low`` modes, 5e-3 above (paper §2.2.1: the blade's 1B, 1T, 2B; a
    disk of N sectors passes 3 N, those three families). A mode whose frequency equals that of the last low mode to
    1e-8 gets its ratio too: C is then a function of (K, M) alone and keeps their symmetries (a tuned disk's
    degenerate pairs are never split). Returns (C, omega): damping matrix and the eigenfrequencies (rad/s).
    """
    lam, V = scipy.linalg.eigh(K, M)
    if lam.min() <= 0:
        raise ValueError("reduced stiffness is not positive definite on the reduced space")
    omega = np.sqrt(lam)
    if not 0 <= n_low <= len(omega):
        raise ValueError(f"n_low must be in [0, {len(omega)}], got {n_low}")
    cut = omega[n_low - 1] * (1 + 1e-8) if n_low else -1.0
    xi = ratios(omega) if ratios else np.where(omega <= cut, 5e-4, 5e-3)
    MV = M @ V
    return MV @ np.diag(2.0 * xi * omega) @ MV.T, omega
