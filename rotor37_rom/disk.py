"""Component mode synthesis of N sectors (paper §3.1, eqs. 40-61), pure NumPy/SciPy: the disk's reduced model from
one sector's Craig-Bampton data.

Each sector n keeps q^n = [u_b^n; eta^n] (its tip DOFs, fixed-interface modes and modal derivatives: the columns
Phi_s, as a blade's reduced model) and its left cyclic DOFs u_L^n; its right face carries the next sector's left DOFs
turned into its frame, u_R^n = R u_L^{n+1} (eq. 43), so with B = [Phi_s, Psi_L, Psi_R R] the sector's matrices are
k = B^T K B, m = B^T M B (eqs. 45-49). The cyclic DOFs of all sectors are then reduced on r_cyclic interface modes
Pi (eq. 50), the eigenvectors of the cyclic block of the assembled matrices whose frequencies are closest to the
sector's fixed-interface modes (eq. 51). For a tuned disk that block is block-circulant, so its modes are computed per
harmonic index k from an n_L-size Hermitian problem (in the real cos/sin form of ``rotor37_rom.cyclic``) instead of
one of size N n_L: 19 problems of 2 n_L instead of one of 36 n_L. The reduced model has r = N r_s + r_cyclic (eq. 53).

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

from rotor37_rom.cyclic import harmonic_indices

__all__ = ["SectorForces", "SectorMatrices", "DiskBasis", "HarmonicBlocks", "interface_modes", "assemble_disk_matrices",
           "disk_node_map", "sector_harmonics", "harmonic_node_load", "harmonic_field_load", "repeat_count",
           "performance_indicator", "travelling_wave_departure", "INDICATOR_CRITERIA", "mistuning_factors",
           "best_approximation", "face_shapes", "travelling_load", "sector_force_basis",
           "indicator_histories", "harmonic_frequencies", "harmonic_coordinates", "wave_harmonic_order",
           "travelling_wave_backbone", "wave_history"]


@dataclasses.dataclass(frozen=True)
class SectorForces:
    """The disk's reduced nonlinear force: one sector's reduced force ``forces`` applied to every sector, the sectors
    as batch columns (PolynomialForces or QuadratureForces).

    Without ``faces`` (eq. 61, the paper's linear coupling) sector n's force acts on its q^n only (r_s in, r_s out).
    With ``faces`` (n_f face coordinates per side) it acts on the sector's field including its faces:
    x^n = [q^n; a_L^n; a_R^n], [a_L^n; a_R^n] = faces[n] @ eta, eta = q[blocks.size:] the interface coordinates
    (a^n = L^T u_L^n on face shapes L, the right face's from the next sector), and its face rows are scattered back by
    faces[n]^T: the force is the gradient of the sum of the sectors' strain energies on those fields.

    Attributes:
        forces: the sector's reduced force (r_s + 2 n_f in and out); blocks: (N, r_s) entries of q of each sector's
            q^n; r: size of q; scales: (N,) factor of each sector's force (mistuning: a sector's E; 1 for a tuned
            disk); faces: None, or (N, 2 n_f, r_cyclic) each sector's face coordinates from eta.
    """

    forces: object
    blocks: np.ndarray
    r: int
    scales: np.ndarray
    faces: np.ndarray | None = None

    def _inputs(self, Q: np.ndarray) -> np.ndarray:
        """(N, r_s [+ 2 n_f], P): each sector's force coordinates."""
        N, rs = self.blocks.shape
        X = Q[self.blocks.ravel()].reshape(N, rs, Q.shape[1])
        if self.faces is None:
            return X
        return np.concatenate([X, np.einsum("nfc,cp->nfp", self.faces, Q[self.blocks.size:])], axis=1)

    def sector_states(self, Q: np.ndarray) -> np.ndarray:
        """(m, N P): the coordinates each sector's force acts on for the disk states Q (r, P), the sectors as
        columns (sector-major: column n P + p is sector n of state p), m = r_s (+ 2 n_f with faces)."""
        Q = np.asarray(Q, float).reshape(self.r, -1)
        X = self._inputs(Q)
        return X.transpose(1, 0, 2).reshape(X.shape[1], -1)

    def evaluate(self, Q: np.ndarray) -> np.ndarray:
        """g~(q) for Q (r,) or (r, P): (r, P); without ``faces`` the entries of the interface modes are 0."""
        Q = np.asarray(Q, float).reshape(self.r, -1)
        N, rs = self.blocks.shape
        P = Q.shape[1]
        X = self.sector_states(Q)
        m = X.shape[0]
        g = self.forces.evaluate(X).reshape(m, N, P) * self.scales[None, :, None]
        out = np.zeros((self.r, P))
        out[self.blocks.ravel()] = g[:rs].transpose(1, 0, 2).reshape(N * rs, P)
        if self.faces is not None:
            out[self.blocks.size:] = np.einsum("nfc,fnp->cp", self.faces, g[rs:])
        return out

    def jacobian(self, q: np.ndarray) -> np.ndarray:
        """dg~/dq (r, r) at one state: block-diagonal over the sectors (and their coupling through eta with faces)."""
        q = np.asarray(q, float).ravel()
        X = self._inputs(q[:, None])[:, :, 0]
        rs = self.blocks.shape[1]
        eta = slice(self.blocks.size, self.r)
        J = np.zeros((self.r, self.r))
        for n, block in enumerate(self.blocks):                # N small Jacobians, one per sector
            Jn = self.scales[n] * self.forces.jacobian(X[n])
            J[np.ix_(block, block)] = Jn[:rs, :rs]
            if self.faces is not None:
                E = self.faces[n]
                J[block, eta] += Jn[:rs, rs:] @ E
                J[eta, block] += E.T @ Jn[rs:, :rs]
                J[eta, eta] += E.T @ Jn[rs:, rs:] @ E
        return J


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


@dataclasses.dataclass(frozen=True)
class DiskBasis:
    """What rebuilds sector n's field from the disk's q (no reassembly): u^n = Phi_s q^n + Psi_L u_L^n +
    Psi_R' u_L^{n+1}, u_L = Pi eta (each sector's frame, free DOFs lifted to the full vector).

    Attributes: Phi_s (n, r_s), Psi_L (n, n_L), Psi_Rr (n, n_L): the right-face constraint modes times the rotation
    R, Pi (N n_L, r_cyclic), blocks (N, r_s) sector blocks of q, n_sectors."""

    Phi_s: np.ndarray
    Psi_L: np.ndarray
    Psi_Rr: np.ndarray
    Pi: np.ndarray
    blocks: np.ndarray
    n_sectors: int

    def __post_init__(self):
        object.__setattr__(self, "n_sectors", int(self.n_sectors))

    def sector_field(self, q: np.ndarray, n: int, dofs: np.ndarray | None = None) -> np.ndarray:
        """Sector n's displacement in its own frame for the disk state q (r,) or states (r, T): the full DOF vector,
        or only the DOFs ``dofs`` (cheap: only those rows of the basis are used)."""
        N, nL = self.n_sectors, self.Psi_L.shape[1]
        rows = slice(None) if dofs is None else np.asarray(dofs)
        uL = self.Pi @ q[self.blocks.size:]
        return (self.Phi_s[rows] @ q[self.blocks[n]] + self.Psi_L[rows] @ uL[n * nL:(n + 1) * nL]
                + self.Psi_Rr[rows] @ uL[((n + 1) % N) * nL:((n + 1) % N + 1) * nL])

    def project(self, f: np.ndarray, n: int) -> np.ndarray:
        """The reduced force (r,) of a force f (n_dofs,) on sector n in its own frame: the transpose of
        ``sector_field`` (the work of f on sector n's field equals that of the result on q)."""
        N, nL = self.n_sectors, self.Psi_L.shape[1]
        if not 0 <= n < N:
            raise ValueError(f"sector must be in 0 ... {N - 1}, got {n}")
        out = np.zeros(self.blocks.size + self.Pi.shape[1])
        out[self.blocks[n]] = self.Phi_s.T @ f
        right = (n + 1) % N
        out[self.blocks.size:] = (self.Pi[n * nL:(n + 1) * nL].T @ (self.Psi_L.T @ f)
                                  + self.Pi[right * nL:(right + 1) * nL].T @ (self.Psi_Rr.T @ f))
        return out


def _harmonic_blocks(s: SectorMatrices, A: np.ndarray, k: int, n_sectors: int) -> np.ndarray:
    """The cyclic block of the assembled matrix for harmonic index k, in real form (n_L, or 2 n_L for 0 < k < N/2):
    H_k = C0 + C1 e^{i k alpha} + C1^T e^{-i k alpha}, C0 = A_LL + A_RR, C1 = A_LR."""
    C0 = s.part(A, "L", "L") + s.part(A, "R", "R")
    C1 = s.part(A, "L", "R")
    phase = 2 * np.pi * k / n_sectors
    re = C0 + (C1 + C1.T) * np.cos(phase)
    if k == 0 or 2 * k == n_sectors:
        return re
    im = (C1 - C1.T) * np.sin(phase)               # H = re + i im, im antisymmetric
    return np.block([[re, -im], [im, re]])


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
        m = Kk.shape[0] // nL
        count = min(per_k * m, Kk.shape[0])
        lam, V = scipy.linalg.eigh(Kk, Mk, subset_by_index=[0, count - 1])
        w = np.sqrt(np.maximum(lam, 0.0))
        for j in range(0, count, m):               # pairs (m = 2) enter together
            dist = np.min(np.abs(s.omega_c - w[j]))
            vecs = [(V[:nL, i], V[nL:, i] if m == 2 else None) for i in range(j, min(j + m, count))]
            candidates.append((dist, w[j], k, vecs))
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


def assemble_disk_matrices(s: SectorMatrices, Pi: np.ndarray, n_sectors: int,
                           scales: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """K and M of the disk's reduced model (eqs. 48-52): q = [q^0 .. q^{N-1}, eta_cyclic], u_L = Pi eta_cyclic.
    ``scales`` (N,): each sector's stiffness factor (mistuning), 1 if None. Returns (K, M), dense (r, r)."""
    N, rs, nL = n_sectors, s.r_s, s.n_L
    scales = np.ones(N) if scales is None else np.asarray(scales, float)
    rc = Pi.shape[1]
    r = N * rs + rc
    out = []
    for A, factor in ((s.K, scales), (s.M, np.ones(N))):
        X = np.zeros((r, r))
        Aqq, Aqc = s.part(A, "q", "q"), np.hstack([s.part(A, "q", "L"), s.part(A, "q", "R")])
        Acc = np.block([[s.part(A, "L", "L"), s.part(A, "L", "R")], [s.part(A, "R", "L"), s.part(A, "R", "R")]])
        for n in range(N):                         # N sector blocks (dense products of the sector's size)
            q = slice(n * rs, (n + 1) * rs)
            Pn = np.vstack([Pi[n * nL:(n + 1) * nL], Pi[((n + 1) % N) * nL:((n + 1) % N + 1) * nL]])
            X[q, q] += factor[n] * Aqq
            coupling = factor[n] * (Aqc @ Pn)
            X[q, N * rs:] += coupling
            X[N * rs:, q] += coupling.T
            X[N * rs:, N * rs:] += factor[n] * (Pn.T @ Acc @ Pn)
        out.append(0.5 * (X + X.T))
    return out[0], out[1]


def disk_node_map(sector_nodes, n_sectors: int, r_s: int):
    """The disk's NodeMap: sector n's copy of the sector map's nodes, at entries n r_s + (their q indices)."""
    from rotor37_rom.reduction import NodeMap

    n = len(sector_nodes)
    return NodeMap(tuple(sector_nodes.names) * n_sectors, np.repeat(np.arange(n_sectors), n),
                   np.tile(sector_nodes.coordinates, (n_sectors, 1)),
                   np.concatenate([sector_nodes.q_index + s * r_s for s in range(n_sectors)]),
                   2 * np.pi / n_sectors)


def _harmonic_matrix(n_sectors: int, r_s: int, r: int) -> scipy.sparse.csr_matrix:
    """T = (F (x) I_{r_s}) (+) I on q = [q^0 .. q^{N-1} (r_s each), the r - N r_s interface coordinates], F the real
    DFT over the sector index (``real_dft``): orthogonal."""
    return scipy.sparse.block_diag([scipy.sparse.kron(real_dft(n_sectors), np.eye(r_s)),
                                    scipy.sparse.identity(r - n_sectors * r_s)]).tocsr()


def _transformed(T: scipy.sparse.csr_matrix, A: np.ndarray) -> np.ndarray:
    """T A T^T."""
    return np.asarray(T @ np.asarray(T @ np.asarray(A, float)).T).T


def _harmonic_transform(n_sectors: int, r_s: int, r: int):
    """(F, transform): the real DFT F over the sector index (``real_dft``) and A -> T A T^T (``_harmonic_matrix``): a
    tuned disk's operator in harmonic coordinates, where it is block-diagonal by harmonic index."""
    T = _harmonic_matrix(n_sectors, r_s, r)
    return real_dft(n_sectors), lambda A: _transformed(T, A)


def _dominant_harmonic(X: np.ndarray) -> np.ndarray:
    """The harmonic index k = 0 .. N/2 carrying most of each column of X (N, n, m) over its first axis, the sector
    index: the DFT's energy summed over the n entries, k and N - k folded together (the same travelling pattern)."""
    N = X.shape[0]
    power = (np.abs(np.fft.fft(X, axis=0)) ** 2).sum(axis=1)        # (N, m)
    folded = power[: N // 2 + 1].copy()
    folded[1:(N + 1) // 2] += power[N - 1:N // 2:-1]
    return np.argmax(folded, axis=0)


def real_dft(n: int) -> np.ndarray:
    """The orthogonal real DFT over n sectors (n, n): rows cos 0, (cos k, sin k) for 0 < k < n/2, cos n/2 (n even)."""
    phase = 2 * np.pi * np.arange(n) / n
    rows = [np.full(n, 1 / np.sqrt(n))]
    for k in range(1, (n + 1) // 2):
        rows += [np.sqrt(2 / n) * np.cos(k * phase), np.sqrt(2 / n) * np.sin(k * phase)]
    if n % 2 == 0:
        rows.append(np.cos(n // 2 * phase) / np.sqrt(n))
    return np.array(rows)


class HarmonicBlocks:
    """Square operators of a tuned disk's reduced model applied per harmonic index (block-circulant structure).

    q = [q^0 .. q^{N-1} (r_s each), eta (r_cyclic)]. The real DFT over the sector index, F (x) I_{r_s} on the sector
    blocks and the identity on the interface modes (each of one harmonic already), makes the operators of a tuned
    disk block-diagonal: harmonic k couples only the cos/sin k components of every sector entry and the interface
    modes of index k, 19 blocks of ~2 r_s + r_cyclic / 19 for N = 36 instead of one of N r_s + r_cyclic. The blocks
    are found from the model's K and M (the connected components of their transformed pattern), and each operator
    is checked to lie in them, so a mistuned disk, whose operators are not block-circulant, is recognised and
    refused (``from_operators`` returns None). What the blocks leave out of the dense operators (their round-off,
    ~1e-10) is dropped.

    ``apply(X)`` computes sum_i A_i X_i for the operators A_i given, for X_i (r, P): the blocks padded to one size and
    applied in one batched product (dense cost / ~N/2 FLOPs, one call).
    """

    def __init__(self, F: np.ndarray, r_sec: int, index: np.ndarray, stacked: np.ndarray, r: int):
        self.F, self.r_sec, self.index, self.stacked, self.r = F, r_sec, index, stacked, r
        self.valid = index < r

    @classmethod
    def from_operators(cls, blocks: np.ndarray, operators: list, structure: list, tol: float = 1e-8
                       ) -> "HarmonicBlocks | None":
        """The operators (each (r, r)) per harmonic, or None when they are not block-diagonal in the harmonic basis
        or when that would not pay (fewer than 3 blocks).

        The blocks are the connected components of the transformed ``structure`` matrices (the model's K and M,
        block-circulant to round-off, 1e-15, for a tuned disk: entries above 1e-12 of the largest couple). Each
        operator may leave out of them at most ``tol`` of its Frobenius norm: the step operators come from dense
        Cholesky solves and eigendecompositions whose round-off, amplified by the conditioning of the capped mass,
        puts ~1e-10 outside; a mistuning of 1e-3 puts 1e-3."""
        blocks = np.asarray(blocks)
        N, rs = blocks.shape
        r = operators[0].shape[0]
        if not np.array_equal(blocks.ravel(), np.arange(N * rs)):
            return None
        F, harmonic = _harmonic_transform(N, rs, r)
        pattern = sum(np.abs(A) > 1e-12 * np.abs(A).max() for A in map(harmonic, structure))
        n_comp, labels = scipy.sparse.csgraph.connected_components(scipy.sparse.csr_matrix(pattern), directed=False)
        if n_comp < 3:
            return None
        outside = labels[:, None] != labels[None, :]
        transformed = [harmonic(A) for A in operators]
        for A in transformed:
            if np.linalg.norm(A[outside]) > tol * np.linalg.norm(A):
                return None
        members = [np.flatnonzero(labels == c) for c in range(n_comp)]
        m = max(len(x) for x in members)
        index = np.full((n_comp, m), r, dtype=np.int64)              # padding points at a zero row
        stacked = np.zeros((n_comp, m, len(operators) * m))
        for c, idx in enumerate(members):
            index[c, :len(idx)] = idx
            for i, A in enumerate(transformed):
                stacked[c, :len(idx), i * m:i * m + len(idx)] = A[np.ix_(idx, idx)]
        return cls(F, N * rs, index, stacked, r)

    @property
    def sizes(self) -> np.ndarray:
        """Size of each harmonic block."""
        return self.valid.sum(axis=1)

    def forward(self, X: np.ndarray) -> np.ndarray:
        """Harmonic coordinates of X (r, P), with one zero row appended (the padding's)."""
        N = self.F.shape[0]
        out = np.zeros((self.r + 1, X.shape[1]))
        out[:self.r_sec] = (self.F @ X[:self.r_sec].reshape(N, -1)).reshape(self.r_sec, -1)
        out[self.r_sec:self.r] = X[self.r_sec:]
        return out

    def backward(self, Xh: np.ndarray) -> np.ndarray:
        """Physical coordinates (r, P) of harmonic coordinates (r, P)."""
        N = self.F.shape[0]
        out = np.empty_like(Xh)
        out[:self.r_sec] = (self.F.T @ Xh[:self.r_sec].reshape(N, -1)).reshape(self.r_sec, -1)
        out[self.r_sec:] = Xh[self.r_sec:]
        return out

    def apply(self, *X: np.ndarray) -> np.ndarray:
        """sum_i A_i X_i (r, P) for the first len(X) operators given to ``from_operators``, in their order."""
        m = self.index.shape[1]
        n_ops = self.stacked.shape[2] // m
        if not 1 <= len(X) <= n_ops:
            raise ValueError(f"give one state per operator (1..{n_ops}), got {len(X)}")
        gathered = np.concatenate([self.forward(x)[self.index] for x in X], axis=1)   # (blocks, k m, P)
        out_blocks = np.matmul(self.stacked[:, :, :len(X) * m], gathered)             # (blocks, m, P)
        out = np.zeros((self.r, out_blocks.shape[2]))
        out[self.index[self.valid]] = out_blocks[self.valid]
        return self.backward(out)


def sector_force_basis(basis: DiskBasis, faces: np.ndarray | None = None) -> np.ndarray:
    """The fields a sector's nonlinear force acts on (n_dofs, m), in the order of ``SectorForces.sector_states``:
    Phi_s, and with ``faces`` (``SectorForces.faces``) also Psi_L L and Psi_R' L. The face shapes L come back from
    faces[n, :n_f] = L^T Pi_n (every sector n) by least squares: L lies in the span of the faces' motions in the
    interface modes (``face_shapes`` takes it from their singular vectors), where that solution is exact."""
    if faces is None:
        return basis.Phi_s
    N, nL = basis.n_sectors, basis.Psi_L.shape[1]
    n_f = faces.shape[1] // 2
    if faces.shape != (N, 2 * n_f, basis.Pi.shape[1]):
        raise ValueError(f"faces must be (N = {N}, 2 n_f, r_cyclic = {basis.Pi.shape[1]}), got {faces.shape}")
    motions = basis.Pi.reshape(N, nL, -1).transpose(1, 0, 2).reshape(nL, -1)     # [Pi_0 ... Pi_(N-1)]
    L = np.linalg.lstsq(motions.T, faces[:, :n_f].transpose(0, 2, 1).reshape(-1, n_f), rcond=None)[0]
    return np.hstack([basis.Phi_s, basis.Psi_L @ L, basis.Psi_Rr @ L])


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


def sector_harmonics(V: np.ndarray, blocks: np.ndarray) -> np.ndarray:
    """The harmonic index k (nodal diameters) carrying most of each column of V (r, m) across the sectors' q blocks
    (N, r_s): the DFT over the sector index of each block's entries, its energy summed over the entries."""
    return _dominant_harmonic(V[blocks.ravel()].reshape(blocks.shape[0], blocks.shape[1], -1))


def harmonic_coordinates(model, tol: float = 1e-8) -> tuple[scipy.sparse.csr_matrix, np.ndarray, np.ndarray,
                                                          np.ndarray]:
    """(T (r, r), k (r,), K~, M~): a tuned disk model's harmonic coordinates q~ = T q, the harmonic index 0 ... N/2 of
    each, and K~ = T K T^T, M~ = T M T^T, block-diagonal by k. T is orthogonal: the real DFT over the sector index
    (``real_dft``) of the sector blocks, the interface coordinates unchanged (each column of Pi is one harmonic
    exactly: its DFT over the sectors). ValueError for a blade's model, for sector blocks not first in q, and for a
    mistuned disk (its K or M couple the harmonics by more than ``tol`` of their norm)."""
    basis = getattr(model, "sectors", None)
    if basis is None:
        raise ValueError("harmonic coordinates need a disk model (model.sectors is None: a single blade's model)")
    N, rs = basis.blocks.shape
    if not np.array_equal(basis.blocks.ravel(), np.arange(N * rs)):
        raise ValueError("harmonic coordinates need the sector blocks first in q, in order")
    nL = basis.Psi_L.shape[1]
    k_pi = _dominant_harmonic(basis.Pi.reshape(N, nL, -1))
    dft_k = np.array([0] + [k for k in range(1, (N + 1) // 2) for _ in (0, 1)] + ([N // 2] if N % 2 == 0 else []))
    T = _harmonic_matrix(N, rs, model.K.shape[0])
    k_of = np.concatenate([np.repeat(dft_k, rs), k_pi])
    outside = k_of[:, None] != k_of[None, :]
    Kt, Mt = _transformed(T, model.K), _transformed(T, model.M)
    for name, At in (("K", Kt), ("M", Mt)):
        if np.linalg.norm(At[outside]) > tol * np.linalg.norm(At):
            raise ValueError(f"the model's {name} couples the harmonic indices (a mistuned disk): no frequencies "
                             f"per nodal diameter")
    return T, k_of, Kt, Mt


def harmonic_frequencies(model, n_families: int, tol: float = 1e-8) -> np.ndarray:
    """(N // 2 + 1, n_families) rad/s: a tuned disk model's lowest ``n_families`` frequencies at each harmonic index
    k = 0 ... N/2 (each cos/sin pair of 0 < k < N/2 counted once); NaN where the model has fewer modes of that k.

    Each k is solved on its own subspace of ``harmonic_coordinates``. So a model whose families of different k
    coincide (e.g. nodal diameters left without interface modes, all with the faces held) still gives each k its own
    values; sorting the disk's eigenvectors by their dominant harmonic (``sector_harmonics``) would mix such
    degenerate modes as the eigensolver's round-off falls. ValueError for a mistuned disk."""
    if n_families < 1:
        raise ValueError(f"n_families must be >= 1, got {n_families}")
    _, k_of, Kt, Mt = harmonic_coordinates(model, tol)
    N = model.sectors.blocks.shape[0]
    out = np.full((N // 2 + 1, n_families), np.nan)
    for k in range(N // 2 + 1):
        idx = np.flatnonzero(k_of == k)
        lam = scipy.linalg.eigh(Kt[np.ix_(idx, idx)], Mt[np.ix_(idx, idx)], eigvals_only=True)
        m = 1 if k == 0 or 2 * k == N else 2                                            # cos/sin: each value twice
        values = np.sqrt(np.maximum(lam, 0.0))[::m][:n_families]
        out[k, :values.size] = values
    return out


def wave_harmonic_order(n_sectors: int, n_diameters: int) -> np.ndarray:
    """(N // 2 + 1,): for each harmonic index h, the time harmonic n >= 0 of a travelling wave of k = ``n_diameters``
    that lands on it: the smallest n with n k = +-h (mod N) (its n-th harmonic turns the pattern n times as fast, so
    it shows h nodal diameters, folded); 0 where no n does (the wave puts nothing there)."""
    N, k = n_sectors, n_diameters
    if not 0 < k < N / 2:
        raise ValueError(f"n_diameters must be in 1..{(N - 1) // 2} (a travelling wave of {N} sectors), got {k}")
    order = np.zeros(N // 2 + 1, dtype=np.int64)
    for n in range(N, 0, -1):                    # the smallest n wins
        h = (n * k) % N
        order[min(h, N - h)] = n
    order[0] = 0
    return order


def travelling_wave_backbone(model, n_diameters: int, amplitudes, family: int = 0, tol: float = 1e-10,
                             max_iter: int = 25, start=None, callback=None) -> list[dict]:
    """The free travelling wave of ``n_diameters`` = k nodal diameters of a tuned disk with its nonlinear forces:
    for each modal amplitude a (increasing from small), its frequency omega(a) and its state q at t = 0 (the
    backbone curve of the ``family``-th family's wave: 0 the 1B family).

    A travelling wave is a turning pattern: its component of harmonic index h turns at n omega, n the time harmonic
    of ``wave_harmonic_order`` (0: steady; 2, 3: the second and third harmonics the quadratic and cubic forces make).
    So M q'' = -omega^2 D M q, D the n^2 on each harmonic block (M is block-diagonal by h), and the state solves

        K q + g(q) = omega^2 D M q,   q = a phi + w,   phi^T M w = 0,   psi^T M w = 0

    with phi, psi the linear pair of index k and that family (mass-normalised): the first condition sets the
    amplitude, the second the phase. Each index keeps one time harmonic, its smallest n: the others that fold onto it
    (on a 36-sector disk's k = 6 wave the 5th harmonic lands on index 6 and the 4th on 12) are left out, so the state
    is balanced by a small force sigma M psi along the pair's other member, an unfolding parameter that would be 0
    for an exact wave: |sigma| / (omega^2 a) is the part of the ansatz's defect that w cannot absorb (necessary, not
    sufficient, for the wave to be exact). Newton on (w, omega^2, sigma), continued in a from the linear mode, or
    from ``start`` (points this function returned for the same wave, below every amplitude: the last two seed the
    secant predictor), the step halved where Newton fails. Where several states share an amplitude, the step decides
    which one the path follows: take steps small enough that halving them does not change it.

    Returns per amplitude {'a', 'omega' (rad/s), 'q' (r,), 'phi' (r,), 'iterations', 'residual' (|R| / |K q|),
    'omega_linear', 'sigma', 'defect' (|sigma| / (omega^2 a)), 'steps' (Newton solves since the linear mode or
    ``start``)}; ValueError for bad input and where the continuation cannot go on (a fold in a, or an internal
    resonance: some n omega meets a frequency of index h). ``callback(point)``, if given, sees each point as it is
    found (so a caller keeps the points found before such an error); a true return ends the continuation there,
    that point the last returned (a path run until some response of the state reaches a level)."""
    T, k_of, Kt, Mt = harmonic_coordinates(model)
    N = model.sectors.blocks.shape[0]
    k = int(n_diameters)
    order = wave_harmonic_order(N, k)
    amplitudes = np.asarray(amplitudes, float).ravel()
    if amplitudes.size == 0 or not np.all(np.isfinite(amplitudes)) or amplitudes.min() <= 0:
        raise ValueError(f"amplitudes must be finite modal amplitudes > 0, got {amplitudes.tolist()[:5]}")
    idx = np.flatnonzero(k_of == k)
    lam, V = scipy.linalg.eigh(Kt[np.ix_(idx, idx)], Mt[np.ix_(idx, idx)])
    if not 0 <= family < lam.size // 2:
        raise ValueError(f"family must be in 0..{lam.size // 2 - 1} for k = {k}, got {family}")
    if abs(lam[2 * family + 1] - lam[2 * family]) > 1e-8 * abs(lam[2 * family]):
        raise ValueError(f"family {family} of k = {k} is not a degenerate pair (a mistuned disk, or families that "
                         f"cross): no travelling wave")
    pair = np.zeros((model.r, 2))
    pair[idx] = V[:, 2 * family:2 * family + 2]
    pair = np.asarray(T.T @ pair)                                   # q-space, M-orthonormal
    phi, psi = pair[:, 0], pair[:, 1]
    omega0 = float(np.sqrt(lam[2 * family]))
    n2 = order[k_of].astype(float) ** 2
    DM = np.asarray(T.T @ np.asarray(T.T @ (n2[:, None] * Mt)).T).T    # T^T D M~ T, symmetric
    Mphi, Mpsi = model.M @ phi, model.M @ psi
    r = model.r

    def newton(a, w, omega2, sigma):
        """(w, omega^2, sigma, iterations, residual) at amplitude a from the guess; None if Newton fails."""
        for it in range(max_iter + 1):
            q = a * phi + w
            Kq = model.K @ q
            R = Kq + model.nonlinear_force(q)[:, 0] - omega2 * (DM @ q) + sigma * Mpsi
            res = float(np.linalg.norm(R) / np.linalg.norm(Kq))
            if res <= tol:
                return w, omega2, sigma, it, res
            if it == max_iter or not np.isfinite(res) or res > 1e3:
                return None
            J = model.K - omega2 * DM
            if model.forces is not None:
                J = J + model.forces.jacobian(q)
            A = np.zeros((r + 2, r + 2))           # unknowns w, omega^2 / omega0^2, sigma / omega0^2; the two
            A[:r, :r], A[:r, r], A[:r, r + 1] = J, -omega0 ** 2 * (DM @ q), omega0 ** 2 * Mpsi    # constraint
            A[r, :r], A[r + 1, :r] = omega0 ** 2 * Mphi, omega0 ** 2 * Mpsi       # rows x omega0^2: one scale
            rhs = -np.concatenate([R, omega0 ** 2 * np.array([Mphi @ w, Mpsi @ w])])
            dx = scipy.linalg.solve(A, rhs, check_finite=False)
            w, omega2, sigma = w + dx[:r], omega2 + omega0 ** 2 * dx[r], sigma + omega0 ** 2 * dx[r + 1]

    # continuation in a: secant predictor from the last two points, the step halved where Newton fails
    path = [(0.0, np.zeros(r), omega0 ** 2, 0.0)]
    if start is not None:
        start = [start] if isinstance(start, dict) else list(start)[-2:]
        if not start or any(not np.array_equal(p["phi"], phi) for p in start) or \
                amplitudes.min() <= start[-1]["a"] or (len(start) == 2 and start[0]["a"] >= start[1]["a"]):
            raise ValueError("start: points of this wave (same model, k and family), increasing, below every "
                             "amplitude")
        path = [(p["a"], p["q"] - p["a"] * phi, p["omega"] ** 2, p["sigma"]) for p in start]
    n_start = len(path)
    out = []
    for target in np.sort(amplitudes):
        step = target - path[-1][0]
        while path[-1][0] < target:
            a = min(path[-1][0] + step, target)
            w, omega2, sigma = path[-1][1:]
            if len(path) > 1:                                   # secant predictor
                (a0, w0, o0, s0), (a1, w1, o1, s1) = path[-2], path[-1]
                f = (a - a1) / (a1 - a0)
                w, omega2, sigma = w1 + f * (w1 - w0), o1 + f * (o1 - o0), s1 + f * (s1 - s0)
            found = newton(a, w, omega2, sigma)
            if found is None:
                step /= 2
                if step < target * 2.0 ** -12:
                    raise ValueError(f"travelling_wave_backbone: no converged state beyond amplitude "
                                     f"{path[-1][0]:.4g} (k = {k}, omega = {np.sqrt(path[-1][2]):.1f} rad/s)")
                continue
            path.append((a,) + found[:3])
            iterations, res = found[3:]
            step *= 1.5
        a, w, omega2, sigma = path[-1]
        out.append({"a": float(a), "omega": float(np.sqrt(omega2)), "q": a * phi + w, "phi": phi,
                    "iterations": iterations, "residual": res, "omega_linear": omega0, "sigma": float(sigma),
                    "defect": float(abs(sigma) / (omega2 * a)), "steps": len(path) - n_start})
        if callback is not None and callback(out[-1]):
            break
    return out


def wave_history(values: np.ndarray, n_diameters: int, omega: float, samples: int = 720) -> np.ndarray:
    """(samples,) one period (2 pi / omega) of sector 0's history of a travelling wave of ``n_diameters`` whose
    snapshot over the N sectors at t = 0 is ``values`` (N,) (e.g. node LE's normal displacement in each sector): each
    harmonic of the snapshot turns at its time harmonic (``wave_harmonic_order``; the sign of n is the side of the
    fold its index lies on). The wave travels towards increasing sector index (u_j(t) = f(omega t - k theta_j)); the
    other way round the history is the same reversed in time (so are its extremes). The standing indices 0 and N/2
    have no sine partner in a snapshot: they are taken at their extreme at t = 0 (cos n omega t), as the backbone's
    ansatz takes them."""
    if not omega > 0 or samples < 1:
        raise ValueError(f"omega must be > 0 and samples >= 1, got {omega} and {samples}")
    values = np.asarray(values, float).ravel()
    N = values.size
    order = wave_harmonic_order(N, n_diameters)
    U = np.fft.fft(values) / N
    m = np.arange(N)
    h = np.minimum(m, N - m)
    sign = np.where(((order[h] * n_diameters) % N) == m, 1.0, -1.0)        # +n k = m or -n k = m (mod N)
    t = np.arange(samples) / samples * 2 * np.pi / omega
    return np.real(np.exp(-1j * np.outer(omega * t, sign * order[h])) @ U)


def travelling_wave_departure(u: np.ndarray, window: np.ndarray, shift: int) -> tuple[float, float]:
    """How far the N blades' histories u (N, n), sampled evenly, are from a travelling wave: the largest
    |u_j(t_i) - u_0(t_i - j shift)| over the sample indices i of ``window`` and j = 1 .. N - 1 (``shift``: samples per
    sector turn of the rotor), and blade 0's amplitude max |u_0| over the window. Returns (departure, amplitude)."""
    window = np.asarray(window)
    if window.min() < (u.shape[0] - 1) * shift:
        raise ValueError(f"window must start at sample >= (N - 1) shift = {(u.shape[0] - 1) * shift}, "
                         f"got {window.min()}")
    worst = max(np.abs(u[j, window] - u[0, window - j * shift]).max() for j in range(1, u.shape[0]))
    return float(worst), float(np.abs(u[0, window]).max())


def repeat_count(n_sectors: int, n_diameters: int) -> int:
    """Sectors over which a tuned disk's response to an N_d-diameter load repeats: N / gcd(N, N_d)."""
    if not (0 <= n_diameters <= n_sectors // 2):
        raise ValueError(f"N_d (nodal diameters) must be in [0, {n_sectors // 2}], got {n_diameters}")
    return n_sectors // int(np.gcd(n_sectors, n_diameters))


def harmonic_node_load(nodes, r: int, amplitude: float, omega: float, n_diameters: int, name: str = "LE",
                       component: int = 2, ramp: float = 0.0):
    """The reduced force of a travelling N_d-diameter load: A sin(omega t - s N_d 2 pi / N) on component
    ``component`` (sector frame: 0 x, 1 y, 2 z) of node ``name`` of every sector s. The node must be kept physical in
    q (a boundary node of the model's NodeMap): its row of the basis is the unit vector of its entry of q, so the
    reduced force is the nodal force itself. ``ramp`` (s): the envelope (1 - cos(pi t / ramp)) / 2 up to t = ramp
    (0: none; sectors whose phase is not 0 then start with a step). Returns t -> (r,)."""
    N = max(nodes.n_sectors, 1)
    repeat_count(N, n_diameters)
    if name not in nodes.names:
        raise ValueError(f"load node {name!r} is not in the model's boundary set {sorted(set(nodes.names))}")
    if component not in (0, 1, 2):
        raise ValueError(f"component must be 0, 1 or 2 (x, y, z), got {component}")
    P = np.zeros((r, N))
    P[[nodes.q_index[nodes.row(name, s), component] for s in range(N)], np.arange(N)] = 1.0
    return travelling_load(P, amplitude, omega, n_diameters, ramp)


def harmonic_field_load(basis: DiskBasis, f: np.ndarray, amplitude: float, omega: float, n_diameters: int,
                        ramp: float = 0.0):
    """The reduced force of a travelling N_d-diameter load A sin(omega t - s N_d 2 pi / N) f on every sector s, f
    (n_dofs,) a sector load vector per unit amplitude in the sector's frame (e.g. ``fem.patch_load``), projected by
    ``DiskBasis.project``; the envelope as in ``harmonic_node_load``. Returns t -> (r,)."""
    N = basis.n_sectors
    repeat_count(N, n_diameters)
    if np.shape(f) != (basis.Phi_s.shape[0],):
        raise ValueError(f"the load vector must have the sector's {basis.Phi_s.shape[0]} DOFs, got {np.shape(f)}")
    P = np.stack([basis.project(np.asarray(f, dtype=float), s) for s in range(N)], axis=1)
    return travelling_load(P, amplitude, omega, n_diameters, ramp)


def travelling_load(P: np.ndarray, amplitude: float, omega: float, n_diameters: int, ramp: float):
    """t -> P (A e(t) sin(omega t - s N_d 2 pi / N))_s: P (r, N) the reduced force of a unit load on each sector."""
    if not ramp >= 0:
        raise ValueError(f"ramp must be >= 0 s, got {ramp}")
    phase = np.arange(P.shape[1]) * n_diameters * 2 * np.pi / P.shape[1]

    def load(t: float) -> np.ndarray:
        envelope = 1.0 if t >= ramp else 0.5 * (1.0 - np.cos(np.pi * t / ramp))
        return P @ (amplitude * envelope * np.sin(omega * t - phase))

    return load


INDICATOR_CRITERIA = ("loaded node", "tip nodes", "field", "strain energy")


def _norms(A, X: np.ndarray) -> np.ndarray:
    """The A-norms of the fields X (..., n_dofs), one per leading index, flattened."""
    X2 = X.reshape(-1, X.shape[-1])
    return np.sqrt(np.maximum(np.einsum("ij,ij->i", X2, (A @ X2.T).T), 0.0))


def best_approximation(basis: DiskBasis, field_ref: np.ndarray, K, M) -> dict:
    """The smallest errors that any state of a disk model can have against reference fields: the lower bounds of
    ``performance_indicator``'s global criteria, which tell the basis's share of a reduced model's error from the
    share of its reduced dynamics (Galerkin projection, force approximation, time integration).

    Each snapshot of sector n is projected, in the M norm ('field') and in the K norm ('strain energy'), on the
    fields that sector n can take: span[Phi_s, Psi_L Pi_n + Psi_R' Pi_(n+1)] (``DiskBasis.sector_field``'s image;
    the snapshots are treated independently, so the bound holds for every q history). Normalised as the indicator
    (max over snapshots and sectors of the error norm / max of the reference's).

    Args: field_ref (n_snap, n_s, n_dofs) snapshots of sectors 0 ... n_s - 1; K, M the sector's stiffness and mass
    (as for the indicator). Returns {'field': e_M, 'strain energy': e_K}."""
    field_ref = np.asarray(field_ref, float)
    N, nL = basis.n_sectors, basis.Psi_L.shape[1]
    if field_ref.ndim != 3 or field_ref.shape[2] != basis.Phi_s.shape[0] or not 1 <= field_ref.shape[1] <= N:
        raise ValueError(f"reference fields must be (snapshots, 1 ... {N} sectors, {basis.Phi_s.shape[0]} DOFs), got "
                         f"{field_ref.shape}")
    out = {}
    for name, A in (("field", M), ("strain energy", K)):
        worst, ref_max = 0.0, 0.0
        for n in range(field_ref.shape[1]):
            m = (n + 1) % N
            B = np.hstack([basis.Phi_s, basis.Psi_L @ basis.Pi[n * nL:(n + 1) * nL]
                           + basis.Psi_Rr @ basis.Pi[m * nL:(m + 1) * nL]])
            AB = np.asarray(A @ B)
            d = np.sqrt(np.maximum(np.einsum("ij,ij->j", B, AB), 1e-300))   # columns scaled to unit A-norm
            w, V = np.linalg.eigh(0.5 * (B.T @ AB + AB.T @ B) / np.outer(d, d))
            keep = w > 1e-14 * w.max()      # an A-orthonormal basis of the span; directions at round-off (eigh's
            #                                 1e-16 w_max) out, a field's part along them <= 1e-7 of its norm
            T = V[:, keep] / np.sqrt(w[keep]) / d[:, None]
            U = field_ref[:, n, :].T
            E = U - B @ (T @ (T.T @ (AB.T @ U)))
            E -= B @ (T @ (T.T @ (AB.T @ E)))           # once more: the projection's round-off projected out
            worst, ref_max = max(worst, _norms(A, E.T).max()), max(ref_max, _norms(A, U.T).max())
        out[name] = float(worst / max(ref_max, 1e-300))
    return out


def performance_indicator(tip_ref: np.ndarray, tip_rom: np.ndarray, field_ref: np.ndarray, field_rom: np.ndarray,
                          K, M, loaded: tuple = (0, 2)) -> dict:
    """The performance indicator I in [0, 1] of a reduced model's transient against a full-order reference, in the
    spirit of the paper's (its ref. [28]): two tip-local and two global criteria, each e_i >= 0 a relative error,
    I = mean_i max(0, 1 - e_i) (1: exact).

    - loaded node: max_t |u - u_ref| / max_t |u_ref| of the loaded DOF (``loaded`` = (tip node, component)) of
      every sector carried, the largest over sectors;
    - tip nodes: || u - u_ref || / || u_ref || over all tip nodes, components, sectors and instants (RMS);
    - field: max over snapshots of || u - u_ref ||_M / max over snapshots of || u_ref ||_M (whole sectors);
    - strain energy: the same in the K norm (the linear strain energy of the error).

    Args: tip_*: (n_t, n_s, n_tip, 3) tip histories (same instants, sectors in their frames); field_*: (n_snap, n_s,
    n_dofs) snapshots; K, M: the sector's stiffness and mass (n_dofs square, clamped rows and columns zero or
    identity-free). Returns {'I': ..., 'errors': {criterion: e}}."""
    tip_ref, tip_rom = np.asarray(tip_ref, float), np.asarray(tip_rom, float)
    field_ref, field_rom = np.asarray(field_ref, float), np.asarray(field_rom, float)
    if tip_ref.shape != tip_rom.shape or field_ref.shape != field_rom.shape:
        raise ValueError(f"reference and reduced histories must have the same shape: tips {tip_ref.shape} vs "
                         f"{tip_rom.shape}, fields {field_ref.shape} vs {field_rom.shape}")
    hist = indicator_histories(tip_ref, tip_rom, field_ref, field_rom, K, M, loaded)
    rms_tip = np.linalg.norm(tip_rom - tip_ref) / max(np.linalg.norm(tip_ref), 1e-300)   # the tip history's RMS
    errors = {name: float(rms_tip if name == "tip nodes" else hist[name].max()) for name in INDICATOR_CRITERIA}
    return {"I": float(np.mean([max(0.0, 1.0 - e) for e in errors.values()])), "errors": errors}


def indicator_histories(tip_ref: np.ndarray, tip_rom: np.ndarray, field_ref: np.ndarray, field_rom: np.ndarray,
                        K, M, loaded: tuple = (0, 2)) -> dict:
    """The error time histories behind ``performance_indicator`` (same arguments), each relative to the same
    reference scale as its criterion, so that the criterion is the history's largest value (loaded node, field,
    strain energy) or its RMS (tip nodes):

    - 'loaded node' (n_t,): |u - u_ref| of the loaded DOF, the largest over sectors of that sector's error over the
      sector's max_t |u_ref|;
    - 'tip nodes' (n_t,): || u - u_ref || over tip nodes, components and sectors at each instant over the RMS over
      instants of || u_ref ||;
    - 'field', 'strain energy' (n_snap,): the M- and K-norm of the error per snapshot (largest over sectors) over the
      largest of the reference's."""
    tip_ref, tip_rom = np.asarray(tip_ref, float), np.asarray(tip_rom, float)
    field_ref, field_rom = np.asarray(field_ref, float), np.asarray(field_rom, float)
    node, comp = loaded
    d_ref, d_rom = tip_ref[:, :, node, comp], tip_rom[:, :, node, comp]
    loaded_err = (np.abs(d_rom - d_ref) / np.maximum(np.abs(d_ref).max(axis=0), 1e-300)).max(axis=1)
    n_t = tip_ref.shape[0]
    per_instant = np.linalg.norm((tip_rom - tip_ref).reshape(n_t, -1), axis=1)
    tip_err = per_instant / max(np.linalg.norm(tip_ref) / np.sqrt(n_t), 1e-300)
    out = {"loaded node": loaded_err, "tip nodes": tip_err}
    n_snap, n_s = field_ref.shape[:2]
    for name, A in (("field", M), ("strain energy", K)):
        e = _norms(A, field_rom - field_ref).reshape(n_snap, n_s).max(axis=1)
        out[name] = e / max(_norms(A, field_ref).max(), 1e-300)
    return out
