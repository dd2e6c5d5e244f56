"""Craig-Bampton bases with modal derivatives and the ReducedModel (pure NumPy/SciPy; FE work is passed in).

References: Craig & Bampton, AIAA J. 6 (1968) 1313 (eqs. 6-11 of the paper); Idelsohn & Cardona (1985) and
Wu & Tiso (2016) for static modal derivatives (eqs. 16-21); selection criteria of §3.1.2 (eqs. 54-58).
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import numbers
from pathlib import Path
from typing import Callable, Sequence

import numpy as np
import scipy.integrate
import scipy.linalg

from rotor37_rom.nonlinear_forces import PolynomialForces, QuadratureForces
from rotor37_rom.npz import save_npz

__all__ = [
    "NodeMap",
    "CraigBamptonBasis",
    "craig_bampton",
    "interface_transform",
    "modal_derivative_pairs",
    "fixed_interface_correction",
    "selection_weights",
    "select_pairs",
    "lift_states",
    "modal_damping",
    "simulate_linear_newmark",
    "simulate_newmark",
    "ReducedModel",
    "save_reduced_model",
    "load_reduced_model",
    "with_force_precision",
    "solve_reduced_static",
    "CRITERIA",
    "GLOBAL_MD_MAX",
]

CRITERIA = ("MMI", "MI2a", "MI2b", "SMVW", "random")
# the most clamped modes whose pairwise modal derivatives a basis takes (N (N + 1) / 2 vectors: 210 at 20)
GLOBAL_MD_MAX = 20


def _rotation_z(angle: np.ndarray) -> np.ndarray:
    """(..., 3, 3) rotations about e_z by ``angle`` (rad)."""
    c, s = np.cos(angle), np.sin(angle)
    R = np.zeros(np.shape(angle) + (3, 3))
    R[..., 0, 0], R[..., 0, 1], R[..., 1, 0], R[..., 1, 1], R[..., 2, 2] = c, -s, s, c, 1.0
    return R


@dataclasses.dataclass(frozen=True)
class NodeMap:
    """Which entries of the reduced state q are which physical node's displacement: the nodes a reduced model keeps
    (blade-tip contact nodes, one set per sector of a disk).

    Each node's displacement is q[q_index[k]] in its sector's frame; sector s's frame is the first sector's turned
    by s * sector_angle about e_z (a single blade: one sector, angle 0). Nothing else may assume where a node sits
    in q.

    Attributes:
        names: node names, unique within a sector; a blade's tip nodes are 'LE', 'tip1', ..., 'TE' from LE to TE.
        sector: (n,) sector of each node.
        coordinates: (n, 3) rest position in the node's sector frame (m).
        q_index: (n, 3) entries of q with the node's x, y, z displacement (sector frame).
        sector_angle: angle between consecutive sector frames (rad); 0 for a single blade.
    """

    names: tuple
    sector: np.ndarray
    coordinates: np.ndarray
    q_index: np.ndarray
    sector_angle: float = 0.0

    def __post_init__(self):
        n = len(self.names)
        sector = np.asarray(self.sector, dtype=np.int64).reshape(-1)
        coordinates = np.asarray(self.coordinates, float).reshape(-1, 3)
        q_index = np.asarray(self.q_index, dtype=np.int64).reshape(-1, 3)
        if not (sector.size == len(coordinates) == len(q_index) == n):
            raise ValueError(f"node map: {n} names, {sector.size} sectors, {len(coordinates)} coordinates and "
                             f"{len(q_index)} index rows must agree")
        if len(set(zip(self.names, sector.tolist()))) != n:
            raise ValueError("node map: node names must be unique within a sector")
        if q_index.size and (q_index.min() < 0 or len(np.unique(q_index)) != q_index.size):
            raise ValueError("node map: q indices must be distinct and >= 0")
        object.__setattr__(self, "names", tuple(str(x) for x in self.names))
        object.__setattr__(self, "sector", sector)
        object.__setattr__(self, "coordinates", coordinates)
        object.__setattr__(self, "q_index", q_index)

    @classmethod
    def for_nodes(cls, coordinates: np.ndarray, q_index: np.ndarray, names: Sequence[str] | None = None
                  ) -> "NodeMap":
        """One sector's nodes; default names 'LE', 'tip1', ..., 'TE' (the nodes must then be ordered LE -> TE)."""
        coordinates = np.asarray(coordinates, float).reshape(-1, 3)
        n = len(coordinates)
        if names is None:
            names = ["LE"] + [f"tip{k}" for k in range(1, n - 1)] + (["TE"] if n > 1 else [])
        return cls(tuple(names), np.zeros(n, np.int64), coordinates, q_index)

    def __len__(self) -> int:
        return len(self.names)

    @property
    def n_sectors(self) -> int:
        return int(self.sector.max()) + 1 if len(self) else 0

    @property
    def labels(self) -> tuple:
        """'<sector>:<name>' of every node, e.g. '0:LE'."""
        return tuple(f"{s}:{n}" for s, n in zip(self.sector.tolist(), self.names))

    @property
    def boundary_rows(self) -> np.ndarray:
        """All entries of q that hold node displacements (n * 3,), node by node."""
        return self.q_index.ravel()

    @property
    def angles(self) -> np.ndarray:
        """(n,) angle of each node's sector frame (rad)."""
        return self.sector * self.sector_angle

    def global_coordinates(self) -> np.ndarray:
        """(n, 3) rest positions in the frame of sector 0."""
        return np.einsum("nij,nj->ni", _rotation_z(self.angles), self.coordinates)

    def row(self, name: str = "LE", sector: int = 0) -> int:
        """Row of the node ``name`` of ``sector``; ValueError naming the nodes there if absent."""
        for k, (n, s) in enumerate(zip(self.names, self.sector.tolist())):
            if n == name and s == sector:
                return k
        if not 0 <= sector < max(self.n_sectors, 1):
            raise ValueError(f"sector must be in [0, {self.n_sectors - 1}], got {sector}")
        raise ValueError(f"no node {name!r} in sector {sector}; it has "
                         f"{[n for n, s in zip(self.names, self.sector.tolist()) if s == sector]}")

    def label_row(self, label: str) -> int:
        """Row of a node given as '<sector>:<name>' (see ``labels``)."""
        sector, _, name = str(label).partition(":")
        if not name or not sector.isdigit():
            raise ValueError(f"node label must read '<sector>:<name>', e.g. '0:LE', got {label!r}")
        return self.row(name, int(sector))

    def arrays(self, prefix: str = "nodes_") -> dict:
        """The map as named arrays (for .npz files); ``from_arrays`` reads them back."""
        return {prefix + "names": np.array(self.names, dtype=str), prefix + "sector": self.sector,
                prefix + "coordinates": self.coordinates, prefix + "q_index": self.q_index,
                prefix + "sector_angle": np.float64(self.sector_angle)}

    @classmethod
    def from_arrays(cls, arrays: dict, prefix: str = "nodes_") -> "NodeMap":
        return cls(tuple(str(x) for x in arrays[prefix + "names"]), arrays[prefix + "sector"],
                   arrays[prefix + "coordinates"], arrays[prefix + "q_index"], float(arrays[prefix + "sector_angle"]))


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
    from rotor37_rom.modes import normalise_signs

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


def simulate_linear_newmark(M: np.ndarray, C: np.ndarray, K: np.ndarray, f: Callable[[float], np.ndarray],
                            dt: float, n_steps: int) -> tuple[np.ndarray, np.ndarray]:
    """Average-acceleration Newmark for a small dense linear system from rest. Returns (t, q) with q (r, n+1)."""
    return simulate_newmark(M, C, K, f, dt, n_steps)


def simulate_newmark(M: np.ndarray, C: np.ndarray, K: np.ndarray, f: Callable[[float], np.ndarray], dt: float,
                     n_steps: int, forces=None, rtol: float = 1e-10, max_iterations: int = 40
                     ) -> tuple[np.ndarray, np.ndarray]:
    """Average-acceleration Newmark (beta = 1/4, gamma = 1/2) of M q'' + C q' + K q + g(q) = f(t) from rest, dense.

    ``forces``: the reduced nonlinear force g (``evaluate``/``jacobian``), None for the linear model. Each step
    iterates on the residual with the factorisation of K + 4 M / dt^2 + 2 C / dt (modified Newton); where that
    converges slowly (a ratio above 1/4) the tangent of g at the iterate is added and factorised (Newton, with a
    backtracking line search); a step whose Newton fails is split in two halves (up to 5 times).
    Stops at |residual| <= rtol x max(|f|, |K q|). Returns (t, q) with q (r, n_steps + 1)."""
    if not (dt > 0 and n_steps >= 1):
        raise ValueError(f"dt must be > 0 s and n_steps >= 1, got {dt}, {n_steps}")
    r = K.shape[0]
    linear = {}

    def factor(h):
        if h not in linear:
            A = K + 4.0 / h**2 * M + 2.0 / h * C
            linear[h] = (A, scipy.linalg.lu_factor(A))
        return linear[h]

    def g(q):
        return np.asarray(forces.evaluate(q)).reshape(r)

    def advance(q, v, a, t_new, h):
        A, lu = factor(h)
        rhs = f(t_new) + M @ (4.0 / h**2 * q + 4.0 / h * v + a) + C @ (2.0 / h * q + v)
        q_new = scipy.linalg.lu_solve(lu, rhs)
        if forces is not None:
            res = A @ q_new + g(q_new) - rhs
            norm = np.linalg.norm(res)
            for it in range(max_iterations + 1):
                if norm <= rtol * max(np.linalg.norm(rhs), np.linalg.norm(K @ q_new), 1e-300):
                    break
                if it == max_iterations or not np.isfinite(norm):
                    return None
                trial = q_new - scipy.linalg.lu_solve(lu, res)       # modified Newton: the kept factorisation
                res_trial = A @ trial + g(trial) - rhs
                if np.linalg.norm(res_trial) > 0.25 * norm:         # too slow: Newton with a line search
                    lu = scipy.linalg.lu_factor(A + forces.jacobian(q_new))
                    step = scipy.linalg.lu_solve(lu, res)
                    for _ in range(6):
                        trial = q_new - step
                        res_trial = A @ trial + g(trial) - rhs
                        if np.linalg.norm(res_trial) < norm:
                            break
                        step = 0.5 * step
                    else:
                        return None                    # no descent along Newton's direction: the step is too long
                q_new, res, norm = trial, res_trial, np.linalg.norm(res_trial)
        a_new = 4.0 / h**2 * (q_new - q) - 4.0 / h * v - a
        return q_new, v + 0.5 * h * (a + a_new), a_new

    def advance_adaptive(q, v, a, t_new, h, depth=0):
        out = advance(q, v, a, t_new, h)
        if out is not None:
            return out
        if depth == 5:
            raise RuntimeError(f"Newmark-Newton did not converge at t = {t_new:.6e} s even with dt / 32")
        q, v, a = advance_adaptive(q, v, a, t_new - h / 2, h / 2, depth + 1)
        return advance_adaptive(q, v, a, t_new, h / 2, depth + 1)

    q, v = np.zeros(r), np.zeros(r)
    a = np.linalg.solve(M, f(0.0))
    out = [q.copy()]
    for n in range(1, n_steps + 1):
        q, v, a = advance_adaptive(q, v, a, n * dt, dt)
        out.append(q.copy())
    return np.arange(n_steps + 1) * dt, np.array(out).T


@dataclasses.dataclass(frozen=True)
class ReducedModel:
    """A reduced model M~ q'' + C~ q' + K~ q + g~(q) = f~ (eq. 3) with q = [u_b; eta_c; eta_MD] (eq. 22).

    Attributes:
        M, C, K: (r, r) reduced matrices.
        forces: PolynomialForces (exact tensors) or QuadratureForces (exact or ECSW), or None (linear).
        boundary_dofs: (r_b,) full-DOF indices (of one sector's mesh) kept physical in q.
        nodes: NodeMap: which entries of q are which node's displacement (the contact nodes).
        sizes: {'r_b', 'r_c', 'r_md'} per sector (a disk's also 'r_load', 'n_sectors', 'r_cyclic'); md_pairs:
            (r_md, 2).
        Phi: (n, r) basis to rebuild fields (optional).
        metadata: parameters, mesh signature, version; ``key`` hashes them.
        sectors: for a disk model, the per-sector basis that rebuilds each sector's field (``disk.DiskBasis``);
            None for a blade.
    """

    M: np.ndarray
    C: np.ndarray
    K: np.ndarray
    forces: object
    boundary_dofs: np.ndarray
    nodes: NodeMap
    sizes: dict
    md_pairs: np.ndarray
    Phi: np.ndarray | None
    metadata: dict
    sectors: object = None

    @property
    def r(self) -> int:
        return self.K.shape[0]

    @property
    def key(self) -> str:
        return reduced_model_key(self.metadata)

    def nonlinear_force(self, Q: np.ndarray) -> np.ndarray:
        if self.forces is None:
            return np.zeros_like(np.asarray(Q, float).reshape(self.r, -1))
        return self.forces.evaluate(Q)


def with_force_precision(model: ReducedModel, precision: str) -> ReducedModel:
    """The model with its quadrature forces (exact or hyper-reduced) evaluated in ``precision``, 'double' or
    'single'; the key changes with it (single: metadata 'force_precision'), so cached sweeps are not mixed up."""
    sector = hasattr(model.forces, "blocks")                  # a disk's sector forces (disk.SectorForces)
    inner = model.forces.forces if sector else model.forces
    if not isinstance(inner, QuadratureForces):
        raise ValueError("force precision applies to quadrature forces (exact or hyper-reduced), not to "
                         f"{type(inner).__name__}")
    forces = inner.with_precision(precision)                 # checks the name
    if sector:
        forces = dataclasses.replace(model.forces, forces=forces)
    metadata = {k: v for k, v in model.metadata.items() if k != "force_precision"}
    if precision != "double":
        metadata["force_precision"] = precision
    return dataclasses.replace(model, forces=forces, metadata=metadata)


def perturbed_model(model: ReducedModel, eps: float) -> ReducedModel:
    """The model with its internal force K q + g(q) scaled by 1 + ``eps`` (|eps| < 0.01), whatever evaluates g:
    exact tensors, a quadrature or cubature (its weights), a disk's sector forces (their per-sector scales). A
    perturbation as small as any force approximation's error: the speeds whose response it moves are those no
    approximation can be judged on (the floor, docs/results.md). The key changes with it (metadata 'perturbation',
    the product of the factors applied), so cached sweeps are not mixed up."""
    if not (isinstance(eps, numbers.Real) and np.isfinite(eps) and abs(eps) < 0.01):
        raise ValueError(f"perturbation must be a number with |eps| < 0.01, got {eps!r}")
    eps = float(eps)
    if eps == 0:
        return model
    scale, forces = 1.0 + eps, model.forces
    if forces is None:
        pass
    elif hasattr(forces, "blocks"):                          # a disk's sector forces (disk.SectorForces)
        forces = dataclasses.replace(forces, scales=np.asarray(forces.scales, float) * scale)
    elif isinstance(forces, QuadratureForces):
        forces = dataclasses.replace(forces, w=forces.w * scale)
    elif isinstance(forces, PolynomialForces):
        forces = PolynomialForces(forces.A * scale, forces.B * scale)
    else:
        raise ValueError(f"perturbation: cannot scale forces of type {type(forces).__name__}")
    prior = model.metadata.get("perturbation")
    total = eps if prior is None else (1.0 + float(prior)) * scale - 1.0
    return dataclasses.replace(model, K=model.K * scale, forces=forces,
                               metadata={**model.metadata, "perturbation": total})


def reduced_model_key(metadata: dict) -> str:
    """sha256 of the metadata (parameters, mesh signature, version) as canonical JSON."""
    return hashlib.sha256(json.dumps(metadata, sort_keys=True, default=str).encode()).hexdigest()[:24]


def save_reduced_model(model: ReducedModel, path: str | Path) -> Path:
    """Write an .npz atomically (temporary file, then rename)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    arrays = {"M": model.M, "C": model.C, "K": model.K, "boundary_dofs": model.boundary_dofs,
              **model.nodes.arrays(), "md_pairs": model.md_pairs,
              "meta": np.array(json.dumps({"metadata": model.metadata, "sizes": model.sizes, "key": model.key},
                                          sort_keys=True, default=str))}
    if model.Phi is not None:
        arrays["Phi"] = model.Phi
    forces, kind = model.forces, "none"
    if forces is not None and hasattr(forces, "blocks"):          # a disk's sector forces (disk.SectorForces)
        arrays.update(sector_blocks=forces.blocks, sector_scales=forces.scales)
        if forces.faces is not None:
            arrays["sector_faces"] = forces.faces
        forces, kind = forces.forces, "sector_"
    if isinstance(forces, PolynomialForces):
        arrays.update(forces=kind.replace("none", "") + "polynomial", A=forces.A, B=forces.B)
    elif isinstance(forces, QuadratureForces):
        arrays.update(forces=kind.replace("none", "") + "quadrature", H=forces.H, w=forces.w,
                      lame=np.array([forces.lmbda, forces.mu]), precision=forces.precision)
    else:
        arrays["forces"] = "none"
    if model.sectors is not None:
        arrays.update({f"sectors_{name}": value for name, value in dataclasses.asdict(model.sectors).items()})
    return save_npz(path, **arrays)


def saved_model_key(path: str | Path) -> str:
    """The key of the reduced model saved at ``path`` (``save_reduced_model``), read from its 'meta' entry alone
    (np.load reads an .npz's arrays lazily: the matrices are not read); refuses a missing or corrupted file, or one
    whose stored key does not match its metadata, as ``load_reduced_model`` does."""
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"reduced model file {path} does not exist")
    try:
        with np.load(path, allow_pickle=False) as data:
            info = json.loads(str(data["meta"]))
        if not {"metadata", "key"} <= info.keys():          # a 'meta' without them: not a reduced model
            raise KeyError("metadata, key")
    except Exception as exc:
        raise ValueError(f"reduced model file {path} is corrupted or not a reduced model ({exc.__class__.__name__})"
                         ) from None
    return _checked_key(info, path)


def _checked_key(info: dict, path: Path) -> str:
    """The key stored in a saved model's 'meta' entry ``info``, refused if it does not match its metadata."""
    key = reduced_model_key(info["metadata"])
    if key != info["key"]:
        raise ValueError(f"reduced model file {path}: stored key does not match its metadata (corrupted)")
    return key


def load_reduced_model(path: str | Path, expected_key: str | None = None) -> ReducedModel:
    """Read a reduced model; refuse a corrupted file or one whose key differs from ``expected_key``."""
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"reduced model file {path} does not exist")
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {k: data[k] for k in data.files}
        info = json.loads(str(arrays["meta"]))
        nodes = NodeMap.from_arrays(arrays)
    except Exception as exc:
        raise ValueError(f"reduced model file {path} is corrupted or not a reduced model ({exc.__class__.__name__})"
                         ) from None
    key = _checked_key(info, path)
    if expected_key is not None and key != expected_key:
        raise ValueError(f"reduced model file {path} was built for other parameters or another mesh "
                         f"(key {key}, expected {expected_key}); it is stale: rebuild it")
    kind = str(arrays["forces"])
    forces = None
    if kind.endswith("polynomial"):
        forces = PolynomialForces(arrays["A"], arrays["B"])
    elif kind.endswith("quadrature"):
        forces = QuadratureForces(arrays["H"], arrays["w"], *arrays["lame"],
                                  precision=str(arrays.get("precision", "double")))
    if kind.startswith("sector_"):
        from rotor37_rom.disk import SectorForces

        forces = SectorForces(forces, arrays["sector_blocks"], arrays["K"].shape[0], arrays["sector_scales"],
                              arrays["sector_faces"] if "sector_faces" in arrays else None)
    sectors = None
    if "sectors_Pi" in arrays:
        from rotor37_rom.disk import DiskBasis

        sectors = DiskBasis(**{f.name: arrays[f"sectors_{f.name}"] for f in dataclasses.fields(DiskBasis)})
    return ReducedModel(M=arrays["M"], C=arrays["C"], K=arrays["K"], forces=forces,
                        boundary_dofs=arrays["boundary_dofs"], nodes=nodes,
                        sizes=info["sizes"], md_pairs=arrays["md_pairs"], Phi=arrays.get("Phi"),
                        metadata=info["metadata"], sectors=sectors)


def solve_reduced_static(model: ReducedModel, f: np.ndarray, load_factors: Sequence[float],
                         nonlinear: bool = True, rtol: float = 1e-10, max_iterations: int = 30,
                         max_bisections: int = 8) -> np.ndarray:
    """K~ q + g~(q) = lambda f for each lambda in order (continuation from q = 0).

    Newton with the exact reduced Jacobian, refreshed only when the residual stops dropping fast (ratio > 0.3);
    a load increment that does not converge is bisected (up to ``max_bisections`` times).
    Returns q (len(load_factors), r).
    """
    f = np.asarray(f, float)
    use_nl = nonlinear and model.forces is not None

    def residual(q, lam):
        res = model.K @ q - lam * f
        if use_nl:
            res += model.forces.evaluate(q)[:, 0]
        return res

    def newton(q, lam):
        scale = max(np.linalg.norm(lam * f), 1e-300)
        J, previous = None, np.inf
        for _ in range(max_iterations):
            res = residual(q, lam)
            norm = np.linalg.norm(res)
            if norm <= rtol * max(scale, np.linalg.norm(model.K @ q)):
                return q
            if J is None or norm > 0.3 * previous:
                J = model.K + (model.forces.jacobian(q) if use_nl else 0.0)
            previous = norm
            q = q - np.linalg.solve(J, res)
        return None

    q, lam_done, out = np.zeros(model.r), 0.0, []
    for target in load_factors:
        step, bisections = target - lam_done, 0
        while lam_done != target:
            lam = target if abs(target - lam_done) <= abs(step) else lam_done + step
            q_new = newton(q.copy(), lam)
            if q_new is None:
                bisections += 1
                if bisections > max_bisections:
                    raise RuntimeError(f"reduced Newton did not converge at load factor {lam:.4g} after "
                                       f"{max_bisections} bisections of the increment")
                step *= 0.5
                continue
            q, lam_done = q_new, lam
        out.append(q.copy())
    return np.array(out)
