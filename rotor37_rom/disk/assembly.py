"""Component mode synthesis of N sectors (paper §3.1, eqs. 40-61), pure NumPy/SciPy: the disk's reduced model from
one sector's Craig-Bampton data.

Each sector n keeps q^n = [u_b^n; eta^n] (its tip DOFs, fixed-interface modes and modal derivatives: the columns Phi_s,
as a blade's reduced model) and its left cyclic DOFs u_L^n; its right face carries the next sector's left DOFs turned
into its frame, u_R^n = R u_L^{n+1} (eq. 43), so with B = [Phi_s, Psi_L, Psi_R R] the sector's matrices are k = B^T K B,
m = B^T M B (eqs. 45-49). The cyclic DOFs of all sectors are then reduced on r_cyclic interface modes Pi (eq. 50), the
eigenvectors of the cyclic block of the assembled matrices whose frequencies are closest to the sector's fixed-interface
modes (eq. 51). For a tuned disk that block is block-circulant, so its modes are computed per harmonic index k from an
n_L-size Hermitian problem instead of one of size N n_L: 19 problems of n_L instead of one of 36 n_L, each complex mode
giving the cos/sin pair of ``rotor37_rom.disk.symmetry``. The reduced model has r = N r_s + r_cyclic (eq. 53).

Nonlinear forces (eq. 61): the cyclic DOFs stay linear and each sector's reduced force depends on its own q^n only,
g~^n(q^n) = Phi_s^T g_s(Phi_s q^n): one sector's reduced force (exact tensors or quadrature) evaluated with the
sectors as batch columns (``SectorForces``). Optionally the force also sees the sector's faces on a few face shapes
L (``face_shapes``: the faces' constraint modes carry part of the blade's motion, which eq. 61 leaves linear). A
mistuned disk scales each sector's stiffness and force by its own factor (SVK forces are linear in E); the interface
modes stay those of the tuned disk, a basis for any scatter.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import scipy.linalg
import scipy.sparse
import scipy.sparse.csgraph

from rotor37_rom.disk.symmetry import harmonic_indices


@dataclasses.dataclass(frozen=True)
class SectorMatrices:
    """A sector's reduced matrices on [q (r_s); u_L (n_L); u_L of the next sector (n_L)] (eqs. 45-49), dense.

    Attributes:
        K, M: (r_s + 2 n_L) square; r_s: size of q^n; n_L: cyclic DOFs per face; omega_c: the sector's fixed-interface
        frequencies (rad/s), the targets of the interface-mode selection (eq. 51).
    """

    K: np.ndarray
    M: np.ndarray
    r_s: int
    n_L: int
    omega_c: np.ndarray

    def part(self, A: np.ndarray, a: str, b: str) -> np.ndarray:
        """Block of K or M: a, b in 'q', 'L' (this sector's left face), 'R' (the next sector's left face)."""
        sl = {"q": slice(0, self.r_s), "L": slice(self.r_s, self.r_s + self.n_L),
              "R": slice(self.r_s + self.n_L, self.r_s + 2 * self.n_L)}
        return A[sl[a], sl[b]]

    def faces(self, A: np.ndarray) -> np.ndarray:
        """The block of K or M on both faces' DOFs [u_L; u_L of the next sector] (2 n_L square)."""
        return np.block([[self.part(A, "L", "L"), self.part(A, "L", "R")],
                         [self.part(A, "R", "L"), self.part(A, "R", "R")]])


def _harmonic_blocks(s: SectorMatrices, A: np.ndarray, k: int, n_sectors: int) -> np.ndarray:
    """The cyclic block of the assembled matrix for harmonic index k (n_L, Hermitian; real for k = 0 and k = N/2):
    H_k = C0 + C1 e^{i k alpha} + C1^T e^{-i k alpha}, C0 = A_LL + A_RR, C1 = A_LR."""
    C0 = s.part(A, "L", "L") + s.part(A, "R", "R")
    C1 = s.part(A, "L", "R")
    phase = 2 * np.pi * k / n_sectors
    re = C0 + (C1 + C1.T) * np.cos(phase)
    if k == 0 or 2 * k == n_sectors:
        return re
    return re + 1j * ((C1 - C1.T) * np.sin(phase))  # the imaginary part antisymmetric


def interface_modes(s: SectorMatrices, n_sectors: int, r_cyclic: int, per_k: int = 12, selection: str = "closest"
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The r_cyclic interface modes Pi (eq. 50-51) of a tuned disk, per harmonic index.

    For every k the lowest ``per_k`` modes of the cyclic block are computed (a cos/sin pair counts as two); the
    r_cyclic of all of them whose frequencies are closest to the sector's fixed-interface frequencies are kept, a pair
    never split (``selection='closest'``, eq. 51), or the lowest modes of every harmonic in equal shares, r_cyclic / N
    per harmonic (``selection='per_k'``: a pair for each 0 < k < N/2; every travelling-wave pattern gets the same
    interface richness). Returns (Pi (N n_L, r_cyclic) with the rows of sector n's left face at n n_L ...,
    M^-orthonormal;
    omega (r_cyclic,) rad/s; k (r_cyclic,) harmonic index of each mode)."""
    N, nL = n_sectors, s.n_L
    candidates = []                                # (distance to the targets, omega, k, (a, b))
    for k in harmonic_indices(N):
        Kk, Mk = _harmonic_blocks(s, s.K, k, N), _harmonic_blocks(s, s.M, k, N)
        count = min(per_k, nL)
        lam, V = scipy.linalg.eigh(Kk, Mk, subset_by_index=[0, count - 1])
        w = np.sqrt(np.maximum(lam, 0.0))
        for j in range(count):                     # z = x + i y: the pair (x, y), (-y, x) of the real doubled form
            z = V[:, j]
            vecs = [(z, None)] if np.isrealobj(V) else [(z.real, z.imag), (-z.imag, z.real)]
            candidates.append((np.min(np.abs(s.omega_c - w[j])), w[j], k, vecs))
    if selection == "per_k":                       # rank within each harmonic first, then by frequency
        rank = {}
        for c in sorted(candidates, key=lambda c: c[1]):
            rank[id(c)] = sum(1 for d in candidates if d[2] == c[2] and d[1] < c[1])
        candidates.sort(key=lambda c: (rank[id(c)], c[1]))
    elif selection == "closest":
        candidates.sort(key=lambda c: (c[0], c[1]))
    else:
        raise ValueError(f"selection must be 'closest' or 'per_k', got {selection!r}")
    total = sum(len(c[3]) for c in candidates)
    if not (1 <= r_cyclic <= total):
        raise ValueError(f"r_cyclic must be in [1, {total}] (interface modes computed: {per_k} per nodal diameter), "
                         f"got {r_cyclic}")
    cols, omega, ks = [], [], []
    phase = 2 * np.pi * np.arange(N) / N
    for dist, w, k, vecs in candidates:
        if len(cols) + len(vecs) > r_cyclic:
            if len(cols) < r_cyclic:
                continue                           # a pair that does not fit: look for a single mode further on
            break
        for a, b in vecs:
            u = np.cos(k * phase)[:, None] * a[None, :]
            if b is not None:
                u = u - np.sin(k * phase)[:, None] * b[None, :]
            cols.append(u.ravel())
            omega.append(w)
            ks.append(k)
    Pi = np.column_stack(cols)
    return Pi, np.array(omega), np.array(ks)


def assemble_disk_operator(s: SectorMatrices, A: np.ndarray, Pi: np.ndarray, n_sectors: int,
                           scales: np.ndarray | None = None) -> np.ndarray:
    """The disk's reduced operator (r, r), r = N r_s + r_cyclic, of one sector's matrix A on [q; u_L; u_L of the
    next sector] (square, any symmetry: a stiffness, a mass, the Coriolis matrix's skew part): every sector's copy
    on its q^n and on its faces' interface coordinates, u_L = Pi eta (eqs. 48-52), times its factor ``scales`` (N,)
    (mistuning; 1 if None)."""
    N, rs, nL = n_sectors, s.r_s, s.n_L
    scales = np.ones(N) if scales is None else np.asarray(scales, float)
    r = N * rs + Pi.shape[1]
    X = np.zeros((r, r))
    Aqq = s.part(A, "q", "q")
    Aqc, Acq = np.hstack([s.part(A, "q", "L"), s.part(A, "q", "R")]), np.vstack([s.part(A, "L", "q"),
                                                                                 s.part(A, "R", "q")])
    Acc = s.faces(A)
    for n in range(N):                             # N sector blocks (dense products of the sector's size)
        q = slice(n * rs, (n + 1) * rs)
        Pn = np.vstack([Pi[n * nL:(n + 1) * nL], Pi[((n + 1) % N) * nL:((n + 1) % N + 1) * nL]])
        X[q, q] += scales[n] * Aqq
        X[q, N * rs:] += scales[n] * (Aqc @ Pn)
        X[N * rs:, q] += scales[n] * (Pn.T @ Acq)
        X[N * rs:, N * rs:] += scales[n] * (Pn.T @ Acc @ Pn)
    return X


def assemble_disk_vector(s: SectorMatrices, f: np.ndarray, Pi: np.ndarray, n_sectors: int) -> np.ndarray:
    """The disk's reduced load (r,) of the same load f on every sector, given on the sector's [q; u_L; u_L of the
    next sector] (e.g. the centrifugal load at rest, the same in each sector's frame): f_q on every q^n, the faces'
    parts on eta through Pi."""
    N, rs, nL = n_sectors, s.r_s, s.n_L
    faces = np.asarray(f[rs:], float)
    out = np.zeros(N * rs + Pi.shape[1])
    out[:N * rs] = np.tile(np.asarray(f[:rs], float), N)
    for n in range(N):
        out[N * rs:] += np.vstack([Pi[n * nL:(n + 1) * nL], Pi[((n + 1) % N) * nL:((n + 1) % N + 1) * nL]]).T @ faces
    return out


def assemble_disk_matrices(s: SectorMatrices, Pi: np.ndarray, n_sectors: int,
                           scales: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """K and M of the disk's reduced model (eqs. 48-52): q = [q^0 .. q^{N-1}, eta_cyclic], u_L = Pi eta_cyclic.
    ``scales`` (N,): each sector's stiffness factor (mistuning), 1 if None. Returns (K, M), dense (r, r),
    symmetric."""
    K = assemble_disk_operator(s, s.K, Pi, n_sectors, scales)
    M = assemble_disk_operator(s, s.M, Pi, n_sectors)
    return 0.5 * (K + K.T), 0.5 * (M + M.T)


def disk_node_map(sector_nodes, n_sectors: int, r_s: int):
    """The disk's NodeMap: sector n's copy of the sector map's nodes, at entries n r_s + (their q indices)."""
    from rotor37_rom.model.nodes import NodeMap

    n = len(sector_nodes)
    return NodeMap(tuple(sector_nodes.names) * n_sectors, np.repeat(np.arange(n_sectors), n),
                   np.tile(sector_nodes.coordinates, (n_sectors, 1)),
                   np.concatenate([sector_nodes.q_index + s * r_s for s in range(n_sectors)]),
                   2 * np.pi / n_sectors, sector_nodes.frame_angle)


def face_shapes(Pi: np.ndarray, omega: np.ndarray, n_sectors: int, count: int) -> tuple[np.ndarray, np.ndarray]:
    """Face shapes for the nonlinear force (``SectorForces.faces``) and every sector's face coordinates.

    L (n_L, count), orthonormal: the leading left singular vectors of the faces' motions in the interface modes, every
    sector's block of every mode, each mode weighted by its static flexibility 1 / omega^2 (a mode's share of a
    quasi-static response), each column's largest entry positive. faces (N, 2 count, r_cyclic): sector n's
    [L^T Pi_n; L^T Pi_(n+1)] (its left face and the next sector's, whose left face is its right one).

    Args: Pi (N n_L, r_cyclic) the interface modes; omega (r_cyclic,) their frequencies (rad/s); count >= 1."""
    N = int(n_sectors)
    nL = Pi.shape[0] // N
    omega = np.asarray(omega, float)
    if Pi.shape[0] != N * nL or omega.shape != (Pi.shape[1],) or not np.all(omega > 0):
        raise ValueError(f"interface modes (N n_L, r) with r positive frequencies expected, got {Pi.shape}, "
                         f"{omega.shape}")
    if not 1 <= count <= min(nL, N * Pi.shape[1]):
        raise ValueError(f"face_shapes must be in [1, {min(nL, N * Pi.shape[1])}], got {count}")
    blocks = Pi.reshape(N, nL, -1)
    U, _, _ = np.linalg.svd((blocks / omega**2).transpose(1, 0, 2).reshape(nL, -1), full_matrices=False)
    L = U[:, :count]
    L = L * np.where(L[np.abs(L).argmax(axis=0), np.arange(count)] < 0, -1.0, 1.0)
    P = np.einsum("lf,nlc->nfc", L, blocks)
    return L, np.concatenate([P, np.roll(P, -1, axis=0)], axis=1)


def mistuning_factors(n_sectors: int, scatter: float, seed: int = 0) -> np.ndarray:
    """Blade-to-blade stiffness factors (n_sectors,): log-normal with mean 1 and standard deviation ``scatter``
    (always > 0), seeded (the same seed gives the same disk on any machine: NumPy's PCG64)."""
    if not 0.0 <= scatter < 1.0:
        raise ValueError(f"mistuning scatter must be in [0, 1) (a standard deviation of the stiffness factor), got "
                         f"{scatter}")
    if n_sectors < 1:
        raise ValueError(f"n_sectors must be >= 1, got {n_sectors}")
    s2 = np.log1p(scatter ** 2)
    xi = np.random.Generator(np.random.PCG64(seed)).standard_normal(n_sectors)
    return np.exp(np.sqrt(s2) * xi - 0.5 * s2)
