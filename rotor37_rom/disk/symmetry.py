"""Cyclic symmetry of a structure made of N identical sectors (pure NumPy/SciPy): the real cos/sin projection per
harmonic index k, the expansion of a sector mode to the whole structure, and the assembly of the whole structure
from one sector (the reference the cyclic operators are checked against).

Sector s is sector 0 turned by s * alpha about e_z (alpha = 2 pi / N). A sector's DOFs are nodal 3-vectors in the
sector's own frame; its right cyclic face is its left face turned by alpha, node for node (``right[i]`` pairs with
``left[i]``), so sector s's right face is sector s + 1's left face. A mode of harmonic index k has, in complex
form, u_s = e^{i s k alpha} u_0 in each sector's frame, so the right face of sector 0 carries

    u_R = e^{i k alpha} R(alpha) u_L,      R(alpha) the rotation about e_z acting on each node's vector

(R appears because each sector's components are in its own frame: a vector v given in the frame of sector s + 1 is
R(alpha) v in the frame of sector s). Debian's PETSc is real, so the complex field u_0 = a + i b is carried as
two real fields, [a; b], with the real form of that constraint

    a_R = R (c a_L - s b_L),   b_R = R (s a_L + c b_L),   c = cos(k alpha), s = sin(k alpha),

which keeps the projected problem symmetric (it is the real form [[Re, -Im], [Im, Re]] of the Hermitian P^H K P;
using P^T instead of P^H is the classic mistake). For 0 < k < N/2 every eigenvalue appears twice (a, b) -> (-b, a):
the double modes of the whole structure (the cos and sin patterns). For k = 0 and k = N/2 (N even) s = 0 and the
two copies decouple into the same problem: one real field, single modes. Nodes on the axis belong to both faces
(u = e^{i k alpha} R u): their allowed motions are the local null space of that 6 x 6 real condition.

References: Thomas, Int. J. Numer. Meth. Eng. 14 (1979) 81 (cyclic symmetry); Wildheim (1981); the same real
formulation as Code_Aster's MODE_ITER_CYCL and NASTRAN's cyclic solution.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import scipy.linalg
import scipy.sparse as sp

__all__ = ["CyclicPairs", "rotation_z", "harmonic_indices", "cyclic_projection", "cyclic_projection_parts",
           "project_cyclic",
           "expand_sector_mode", "assemble_full_structure", "to_global_frame", "repeating_sector_maps"]


def rotation_z(angle: float) -> np.ndarray:
    """3 x 3 rotation about e_z by ``angle`` (rad)."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def harmonic_indices(n_sectors: int) -> np.ndarray:
    """k = 0 ... floor(N / 2): every distinct harmonic index (nodal diameter) of N sectors."""
    return np.arange(n_sectors // 2 + 1)


@dataclasses.dataclass(frozen=True)
class CyclicPairs:
    """The cyclic faces of a sector as DOF indices (one row per node, its x, y, z DOFs).

    Attributes:
        n_sectors: N (>= 2); the sector angle is 2 pi / N.
        left, right: (n_pairs, 3) DOF indices, right[i] at the left[i] node turned by 2 pi / N; pairs that are
            clamped on both faces are left out (u = 0 on both sides satisfies every constraint).
        axis: (n_axis, 3) DOFs of nodes on the rotation axis (on both faces).
        worst_distance: largest distance (m) between a right node and its turned left partner (face matching).
    """

    n_sectors: int
    left: np.ndarray
    right: np.ndarray
    axis: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((0, 3), np.int64))
    worst_distance: float = 0.0

    def __post_init__(self):
        if int(self.n_sectors) < 2:
            raise ValueError(f"number of sectors must be >= 2 (sector angle 2 pi / N), got {self.n_sectors}")
        left = np.asarray(self.left, dtype=np.int64).reshape(-1, 3)
        right = np.asarray(self.right, dtype=np.int64).reshape(-1, 3)
        axis = np.asarray(self.axis, dtype=np.int64).reshape(-1, 3)
        if left.shape != right.shape:
            raise ValueError(f"cyclic faces: {len(left)} left and {len(right)} right nodes must pair one to one")
        every = np.concatenate([left.ravel(), right.ravel(), axis.ravel()])
        if len(np.unique(every)) != every.size:
            raise ValueError("cyclic faces: a DOF is listed twice (left, right and axis DOFs must be distinct)")
        object.__setattr__(self, "left", left)
        object.__setattr__(self, "right", right)
        object.__setattr__(self, "axis", axis)
        object.__setattr__(self, "n_sectors", int(self.n_sectors))

    @property
    def angle(self) -> float:
        return 2.0 * np.pi / self.n_sectors

    def check_k(self, k: int) -> int:
        if not (0 <= int(k) <= self.n_sectors // 2) or int(k) != k:
            raise ValueError(f"harmonic index (nodal diameter) k must be an integer in [0, {self.n_sectors // 2}] "
                             f"for {self.n_sectors} sectors, got {k}")
        return int(k)

    def n_copies(self, k: int) -> int:
        """1 for k = 0 and k = N/2 (real, single modes), 2 otherwise (the cos and sin fields)."""
        k = self.check_k(k)
        return 1 if k == 0 or 2 * k == self.n_sectors else 2


def cyclic_projection(n_dofs: int, pairs: CyclicPairs, k: int) -> tuple[sp.csr_matrix, np.ndarray]:
    """The real projection T_k: u = T_k x, u the sector's fields [a; b] (2 n) or a (n, k = 0 or N/2), x the same
    slots with the right-face DOFs (and the axis DOFs' constrained directions) eliminated.

    Returns (T, kept): T (m n, m n) sparse, m = ``pairs.n_copies(k)``; kept (m n,) bool, the slots x really
    carries (the eliminated ones are empty columns of T). Column j of a kept slot is the unit field of that DOF
    plus, for a left DOF, its image on the right face: T^T diag(K, ..) T restricted to the kept slots is the
    Hermitian projection of K in real form.
    """
    k = pairs.check_k(k)
    m = pairs.n_copies(k)
    angle = pairs.angle
    c, s = np.cos(k * angle), np.sin(k * angle)
    R = rotation_z(angle)
    n = int(n_dofs)
    every = np.concatenate([pairs.left.ravel(), pairs.right.ravel(), pairs.axis.ravel()])
    if every.size and (every.min() < 0 or every.max() >= n):
        raise ValueError(f"cyclic DOF indices must be in [0, {n}), got [{every.min()}, {every.max()}]")
    rows, cols, vals = [], [], []
    kept = np.ones(m * n, bool)
    right = pairs.right.ravel()
    identity = np.setdiff1d(np.arange(n), np.concatenate([right, pairs.axis.ravel()]))
    for copy in range(m):
        rows.append(copy * n + identity)
        cols.append(copy * n + identity)
        vals.append(np.ones(identity.size))
        kept[copy * n + right] = False
    _right_face_entries(pairs, n, m, c, s, rows, cols, vals)
    # axis nodes: x on the axis belongs to both faces: (I - e^{i k alpha} R) u = 0, in real form on (a, b)
    if len(pairs.axis):
        if m == 1:
            A = np.eye(3) - c * R
        else:
            A = np.eye(6) - np.block([[c * R, -s * R], [s * R, c * R]])
        basis = scipy.linalg.null_space(A)                  # allowed local motions (3m, d)
        for node in pairs.axis:
            slots = np.concatenate([copy * n + node for copy in range(m)])
            kept[slots[basis.shape[1]:]] = False            # the node's first d slots carry the d free motions
            for j in range(basis.shape[1]):
                nz = np.abs(basis[:, j]) > 1e-14
                rows.append(slots[nz])
                cols.append(np.full(nz.sum(), slots[j]))
                vals.append(basis[nz, j])
    T = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(m * n, m * n))
    return T, kept


def _right_face_entries(pairs: CyclicPairs, n: int, m: int, c: float, s: float, rows, cols, vals) -> None:
    """Append T's right-face entries: a_R = R (c a_L - s b_L), b_R = R (s a_L + c b_L) (m = 1: a_R = c R a_L)."""
    R = rotation_z(pairs.angle)
    blocks = {(0, 0): c * R} if m == 1 else {(0, 0): c * R, (0, 1): -s * R, (1, 0): s * R, (1, 1): c * R}
    for (out_copy, in_copy), B in blocks.items():
        for i in range(3):
            for j in range(3):
                if B[i, j] != 0.0:
                    rows.append(out_copy * n + pairs.right[:, i])
                    cols.append(in_copy * n + pairs.left[:, j])
                    vals.append(np.full(len(pairs.right), B[i, j]))


def cyclic_projection_parts(n_dofs: int, pairs: CyclicPairs) -> tuple[sp.csr_matrix, sp.csr_matrix, sp.csr_matrix]:
    """(T_0, T_c, T_s) with T_k = T_0 + cos(k alpha) T_c + sin(k alpha) T_s (``cyclic_projection``) for every
    0 < k < N/2, on a sector without axis nodes (their null space is not linear in cos and sin).

    With K2 = diag(K, K), T_s^T K2 T_s = T_c^T K2 T_c and the cos-sin cross terms cancel, so
    K_k = T_k^T K2 T_k = B_0 + cos(k alpha) B_c + sin(k alpha) B_s with three k-free matrices: the projection of
    every harmonic index is a linear combination of matrices computed once."""
    if len(pairs.axis):
        raise ValueError("cyclic_projection_parts: a sector with axis nodes has no k-free parts")
    n = int(n_dofs)
    unit = np.ones(n)
    unit[pairs.right.ravel()] = 0.0                     # T_0: the unit columns of every slot but the right face
    out = [sp.diags(np.concatenate([unit, unit]), format="csr")]
    out[0].eliminate_zeros()
    for c, s in ((1.0, 0.0), (0.0, 1.0)):
        rows, cols, vals = [], [], []
        _right_face_entries(pairs, n, 2, c, s, rows, cols, vals)
        out.append(sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                                 shape=(2 * n, 2 * n)))
    return tuple(out)


def project_cyclic(K, M, pairs: CyclicPairs, k: int) -> tuple[sp.csr_matrix, sp.csr_matrix, sp.csr_matrix]:
    """(K_k, M_k, T): the sector's (K, M) projected on harmonic index k, restricted to the kept slots, and the
    projection T (columns of the kept slots) that maps their eigenvectors back to the sector fields [a; b]."""
    n = K.shape[0]
    T, kept = cyclic_projection(n, pairs, k)
    T = T[:, np.flatnonzero(kept)].tocsr()
    m = pairs.n_copies(k)
    K2, M2 = sp.block_diag([sp.csr_matrix(K)] * m, format="csr"), sp.block_diag([sp.csr_matrix(M)] * m, format="csr")
    Kk, Mk = (T.T @ K2 @ T).tocsr(), (T.T @ M2 @ T).tocsr()
    return 0.5 * (Kk + Kk.T), 0.5 * (Mk + Mk.T), T


def to_global_frame(fields: np.ndarray, node_dofs: np.ndarray, angle: float) -> np.ndarray:
    """Fields (..., n) of nodal vectors in a frame turned by ``angle`` about e_z, given in the first frame."""
    out = np.array(fields, float, copy=True)
    R = rotation_z(angle)
    vec = out[..., node_dofs]                                   # (..., n_nodes, 3)
    out[..., node_dofs] = np.einsum("ij,...nj->...ni", R, vec)
    return out


def expand_sector_mode(a: np.ndarray, b: np.ndarray | None, k: int, n_sectors: int) -> np.ndarray:
    """The fields of all sectors, each in its own frame, of a mode of harmonic index k given by the sector's cos
    and sin fields (a, b) (n,): sector s carries cos(s k alpha) a - sin(s k alpha) b (the real part of
    e^{i s k alpha} (a + i b)). Returns (N, n). For k = 0 and N/2, b may be None (zero)."""
    if not (0 <= int(k) <= n_sectors // 2):
        raise ValueError(f"harmonic index k must be in [0, {n_sectors // 2}], got {k}")
    a = np.asarray(a, float)
    b = np.zeros_like(a) if b is None else np.asarray(b, float)
    phase = np.arange(n_sectors) * k * 2.0 * np.pi / n_sectors
    return np.cos(phase)[:, None] * a[None, :] - np.sin(phase)[:, None] * b[None, :]


def assemble_full_structure(K, M, pairs: CyclicPairs, node_dofs: np.ndarray
                            ) -> tuple[sp.csr_matrix, sp.csr_matrix, np.ndarray]:
    """K and M of the whole structure of N sectors assembled from one sector's, in the frame of sector 0.

    Every sector's matrices are turned to the common frame (block rotation of each node's vector) and added, sector
    s's right face merged with sector s + 1's left face. Axis DOFs are shared by all sectors. Returns (K_full,
    M_full, index) with index (N, n) the global row of each sector DOF, so that a field of sector s is
    ``u_full[index[s]]`` after ``to_global_frame``. For checking the cyclic operators (dense-size problems only).
    """
    N = pairs.n_sectors
    n = K.shape[0]
    node_dofs = np.asarray(node_dofs, dtype=np.int64).reshape(-1, 3)
    right, left, axis = pairs.right.ravel(), pairs.left.ravel(), pairs.axis.ravel()
    own = np.setdiff1d(np.arange(n), np.concatenate([right, axis]))
    n_own = own.size
    index = np.empty((N, n), dtype=np.int64)
    slot = np.full(n, -1, dtype=np.int64)
    slot[own] = np.arange(n_own)
    for s in range(N):
        index[s, own] = s * n_own + slot[own]
    for s in range(N):
        index[s, right] = index[(s + 1) % N, left]
    index[:, axis] = N * n_own + np.arange(axis.size)
    size = N * n_own + axis.size
    K, M = sp.csr_matrix(K), sp.csr_matrix(M)
    parts_K, parts_M = [], []
    for s in range(N):
        Q = _block_rotation(n, node_dofs, s * pairs.angle)        # sector frame -> common frame
        P = sp.csr_matrix((np.ones(n), (index[s], np.arange(n))), shape=(size, n))
        parts_K.append(P @ Q @ K @ Q.T @ P.T)
        parts_M.append(P @ Q @ M @ Q.T @ P.T)
    K_full, M_full = sum(parts_K).tocsr(), sum(parts_M).tocsr()
    return K_full, M_full, index


def _block_rotation(n: int, node_dofs: np.ndarray, angle: float) -> sp.csr_matrix:
    """The rotation of every node's vector by ``angle`` as an (n, n) sparse matrix (identity on other DOFs)."""
    R = rotation_z(angle)
    rows, cols, vals = [], [], []
    rest = np.setdiff1d(np.arange(n), node_dofs.ravel())
    rows.append(rest)
    cols.append(rest)
    vals.append(np.ones(rest.size))
    for i in range(3):
        for j in range(3):
            if R[i, j] != 0.0:
                rows.append(node_dofs[:, i])
                cols.append(node_dofs[:, j])
                vals.append(np.full(len(node_dofs), R[i, j]))
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n))


def repeating_sector_maps(n_dofs: int, pairs: CyclicPairs, n_repeat: int) -> tuple[list, int]:
    """The DOF maps of ``n_repeat`` consecutive sectors closed on themselves, in their own frames: x holds each
    sector's DOFs except its right face, and sector s's right face is sector s + 1's left face (mod n_repeat) turned
    by R (eq. 43). A load of N_d nodal diameters gives a response that repeats every N / gcd(N, N_d) sectors, so that
    many sectors carry the whole disk's (nonlinear) response. Returns ([P_s] (n_dofs, n_x) sparse per sector, n_x);
    sector s's field is P_s x. Axis DOFs are not supported here (each sector keeps its own)."""
    if not (1 <= n_repeat <= pairs.n_sectors) or pairs.n_sectors % n_repeat:
        raise ValueError(f"n_repeat must divide the number of sectors {pairs.n_sectors}, got {n_repeat}")
    n = int(n_dofs)
    right = pairs.right.ravel()
    own = np.setdiff1d(np.arange(n), right)
    slot = np.full(n, -1, dtype=np.int64)
    slot[own] = np.arange(own.size)
    R = rotation_z(pairs.angle)
    maps = []
    for s in range(n_repeat):
        nxt = (s + 1) % n_repeat
        rows, cols, vals = [own], [s * own.size + slot[own]], [np.ones(own.size)]
        for i in range(3):
            for j in range(3):
                if R[i, j] != 0.0:
                    rows.append(pairs.right[:, i])
                    cols.append(nxt * own.size + slot[pairs.left[:, j]])
                    vals.append(np.full(len(pairs.right), R[i, j]))
        maps.append(sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                                  shape=(n, n_repeat * own.size)))
    return maps, n_repeat * own.size
