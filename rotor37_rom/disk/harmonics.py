"""The bladed disk in harmonic coordinates: the real DFT over the sectors, the integrator's harmonic blocks,
frequencies per harmonic, travelling-wave backbones and their histories."""
from __future__ import annotations

import numpy as np
import scipy.linalg
import scipy.sparse
import scipy.sparse.csgraph


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


def sector_harmonics(V: np.ndarray, blocks: np.ndarray) -> np.ndarray:
    """The harmonic index k (nodal diameters) carrying most of each column of V (r, m) across the sectors' q blocks
    (N, r_s): the DFT over the sector index of each block's entries, its energy summed over the entries."""
    return _dominant_harmonic(V[blocks.ravel()].reshape(blocks.shape[0], blocks.shape[1], -1))


def disk_blocks(model, what: str):
    """(model.sectors, N, r_s) of a disk model whose sector blocks come first in q, in order; ValueError starting with
    ``what`` (e.g. "harmonic coordinates need") for a blade's model or other blocks."""
    basis = getattr(model, "sectors", None)
    if basis is None:
        raise ValueError(f"{what} a disk model (model.sectors is None: a single blade's model)")
    N, rs = basis.blocks.shape
    if not np.array_equal(basis.blocks.ravel(), np.arange(N * rs)):
        raise ValueError(f"{what} the sector blocks first in q, in order")
    return basis, N, rs


def harmonic_coordinates(model, tol: float = 1e-8) -> tuple[scipy.sparse.csr_matrix, np.ndarray, np.ndarray,
                                                          np.ndarray]:
    """(T (r, r), k (r,), K~, M~): a tuned disk model's harmonic coordinates q~ = T q, the harmonic index 0 ... N/2 of
    each, and K~ = T K T^T, M~ = T M T^T, block-diagonal by k. T is orthogonal: the real DFT over the sector index
    (``real_dft``) of the sector blocks, the interface coordinates unchanged (each column of Pi is one harmonic
    exactly: its DFT over the sectors). ValueError for a blade's model, for sector blocks not first in q, and for a
    mistuned disk (its K or M couple the harmonics by more than ``tol`` of their norm)."""
    basis, N, rs = disk_blocks(model, "harmonic coordinates need")
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
