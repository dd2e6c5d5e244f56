"""Reduced St. Venant-Kirchhoff forces (pure NumPy): exact quadrature-level evaluation, exact cubic tensors over
unique monomials (eqs. 23-24), and their batched evaluation (eqs. 34-36).

With H_p,i the displacement gradient of basis vector i at quadrature point p (weight w_p), eps_i = sym(H_i) and
P_ij = sym(H_i^T H_j), the reduced internal force of u = Phi q is exactly (C the isotropic elasticity tensor)

    f^m(q) = sum_i q_i <C eps_i, eps_m>                                  (K~ q)
           + sum_ij q_i q_j [<C eps_i, P_jm> + 1/2 <C P_ij, eps_m>]       (A~(q, q))
           + 1/2 sum_ijk q_i q_j q_k <C P_ij, P_km>                       (B~(q, q, q))

with <X, Y> = sum_p w_p X_p : Y_p. The quadratic and cubic parts are stored over unique monomials q_a q_b (a <= b,
r(r+1)/2 of them) and q_a q_b q_c (a <= b <= c, r(r+1)(r+2)/6), in lexicographic order.
"""
from __future__ import annotations

import dataclasses
import functools
import itertools

import numpy as np

from rotor37_rom.forces.kernel import pack_panels, pk_nonlinear_kernel, polynomial_kernel

__all__ = [
    "quadratic_monomial_indices",
    "cubic_monomial_indices",
    "QuadratureForces",
    "PolynomialForces",
    "compute_polynomial_forces",
]

_VOIGT_I = np.array([0, 1, 2, 1, 0, 0])
_VOIGT_J = np.array([0, 1, 2, 2, 2, 1])
_VOIGT_SCALE = np.sqrt(np.array([1.0, 1.0, 1.0, 2.0, 2.0, 2.0]))  # so that dot products are X : Y


@functools.lru_cache(maxsize=16)
def quadratic_monomial_indices(r: int) -> tuple[np.ndarray, np.ndarray]:
    """(a, b) with a <= b, lexicographic: r(r+1)/2 pairs (cached, read-only)."""
    a, b = np.triu_indices(r)
    a.flags.writeable = b.flags.writeable = False
    return a, b


@functools.lru_cache(maxsize=16)
def cubic_monomial_indices(r: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(a, b, c) with a <= b <= c, lexicographic: r(r+1)(r+2)/6 triples (cached, read-only)."""
    triples = np.array(list(itertools.combinations_with_replacement(range(r), 3)), dtype=np.int64).reshape(-1, 3)
    out = tuple(np.ascontiguousarray(triples[:, i]) for i in range(3))
    for x in out:
        x.flags.writeable = False
    return out


@functools.lru_cache(maxsize=16)
def _cubic_from_pairs(r: int) -> tuple[np.ndarray, np.ndarray]:
    """For each cubic monomial (a, b, c): the index of pair (a, b) and c, so m3 = m2[first] * q[c]."""
    ca, cb, cc = cubic_monomial_indices(r)
    first = _pair_index(r, ca, cb)
    first.flags.writeable = False
    return first, cc


def _pair_index(r: int, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """Position of the sorted pair (min, max) in the lexicographic list of quadratic monomials."""
    a, b = np.minimum(i, j), np.maximum(i, j)
    return a * r - a * (a - 1) // 2 + (b - a)


def _sym_voigt(X: np.ndarray) -> np.ndarray:
    """Symmetric part of (..., 3, 3) as (..., 6) scaled Voigt vectors (dot product = double contraction)."""
    S = 0.5 * (X + np.swapaxes(X, -1, -2))
    return S[..., _VOIGT_I, _VOIGT_J] * _VOIGT_SCALE


def _apply_C(V: np.ndarray, lmbda: float, mu: float) -> np.ndarray:
    """C : X in scaled Voigt form: lambda tr(X) I + 2 mu X."""
    out = 2.0 * mu * V
    out[..., :3] += lmbda * V[..., :3].sum(axis=-1, keepdims=True)
    return out


_PRECISIONS = {"double": np.float64, "single": np.float32}
_KEEP_BUFFERS = 64 << 20        # bytes of work arrays a QuadratureForces keeps between evaluations (few points)


def _batched_product(X: np.ndarray, Y: np.ndarray) -> np.ndarray:
    """X @ Y over the last two axes (3 x 3), broadcasting the leading ones, as three multiply-adds (numpy's
    matmul loops over tiny matrices one by one)."""
    return X[..., :, 0, None] * Y[..., 0, None, :] + X[..., :, 1, None] * Y[..., 1, None, :] \
        + X[..., :, 2, None] * Y[..., 2, None, :]


@dataclasses.dataclass(frozen=True)
class QuadratureForces:
    """Tensor-free exact SVK forces on a set of quadrature points (all points: exact; a weighted subset: ECSW).

    Attributes:
        H: (n_points, r, 3, 3) basis gradients; w: (n_points,) weights (m^3, or ECSW-modified); lmbda, mu (Pa).
        precision: arithmetic of ``evaluate`` (the time integrator's force): 'double', or 'single' (float32
            gradients, stresses and projection, about 3x faster on few points; the nonlinear stress is formed from
            products of gradients, not as a difference from the linear one, so it keeps float32's relative accuracy,
            ~1e-7, before the sum over points). ``jacobian``, ``stiffness`` and ``point_contributions`` stay double.
    """

    H: np.ndarray
    w: np.ndarray
    lmbda: float
    mu: float
    precision: str = "double"

    def __post_init__(self):
        if self.precision not in _PRECISIONS:
            raise ValueError(f"precision must be one of {sorted(_PRECISIONS)}, got {self.precision!r}")

    @property
    def r(self) -> int:
        return self.H.shape[1]

    has_potential = False                              # the strain energy of a quadrature is not formed here

    def with_precision(self, precision: str) -> "QuadratureForces":
        """The same quadrature evaluated in ``precision`` ('double' or 'single')."""
        return dataclasses.replace(self, precision=precision)

    def scaled(self, factor: float) -> "QuadratureForces":
        """The force times ``factor``: its weights scaled."""
        return dataclasses.replace(self, w=self.w * factor)

    def premultiplied(self, X: np.ndarray) -> None:
        """None: a quadrature's force is evaluated, then mapped (no premultiplied form is cheaper)."""
        return None

    def potential(self, Q: np.ndarray) -> np.ndarray:
        raise NotImplementedError("the potential of quadrature forces is not formed (has_potential is False)")

    def arrays(self) -> dict[str, np.ndarray]:
        """Its entries in a model's file (``model.reduced``)."""
        return {"forces": "quadrature", "H": self.H, "w": self.w, "lame": np.array([self.lmbda, self.mu]),
                "precision": self.precision}

    @classmethod
    def from_arrays(cls, arrays) -> "QuadratureForces":
        return cls(arrays["H"], arrays["w"], *arrays["lame"], precision=str(arrays.get("precision", "double")))

    @functools.cached_property
    def _planes(self) -> tuple[np.ndarray, np.ndarray]:
        """The basis gradients as (9 n, r) with rows ordered (i, j, point), so that each component of a batch of
        displacement gradients is a contiguous (n, P) plane, and the weighted transpose (r, 9 n) that projects,
        both in the evaluation precision."""
        dtype = _PRECISIONS[self.precision]
        weighted = self._gradient_planes(self.H * self.w[:, None, None, None], dtype)
        return self._gradient_planes(self.H, dtype), np.ascontiguousarray(weighted.T)

    @staticmethod
    def _gradient_planes(H: np.ndarray, dtype=np.float64) -> np.ndarray:
        """(n, r, 3, 3) -> (9 n, r), rows ordered (i, j, point)."""
        n, r = H.shape[:2]
        return np.ascontiguousarray(H.transpose(2, 3, 0, 1), dtype=dtype).reshape(9 * n, r)

    def _buffers(self, n: int, P: int, dtype) -> dict:
        """Work arrays for a batch of P states, kept between calls with the same shape: fresh arrays of this size
        cost a page-mapping and first-touch faults each, which doubled the force's time inside the integrator."""
        cache = self.__dict__.setdefault("_work", {})
        key = (n, P, np.dtype(dtype).str)
        if key not in cache:
            cache.clear()                                # one batch shape at a time (the integrator's)
            cache[key] = {"G": np.empty((9 * n, P), dtype), "A": np.empty((3, 3, n, P), dtype),
                          "S": np.empty((3, 3, n, P), dtype), "tmp": np.empty((n, P), dtype),
                          "tr_A": np.empty((n, P), dtype), "tr_E": np.empty((n, P), dtype)}
        return cache[key]

    def _first_pk_nonlinear(self, G: np.ndarray, work: dict | None = None) -> np.ndarray:
        """For displacement gradients G (3, 3, n, P): F S - C eps, the nonlinear part of the first Piola-Kirchhoff
        stress, into work['A'] (``_buffers``) or a fresh array: the fused C kernel of ``svk_kernel`` where it
        builds (8-17x faster than the NumPy path in bench_integrator), else ``_first_pk_nonlinear_numpy``."""
        kernel = pk_nonlinear_kernel(G.dtype)
        if kernel is None or not G.flags.c_contiguous:
            return self._first_pk_nonlinear_numpy(G, work)
        return kernel(G, work["A"] if work is not None else np.empty_like(G), self.lmbda, self.mu)

    def _first_pk_nonlinear_numpy(self, G: np.ndarray, work: dict | None = None) -> np.ndarray:
        """The NumPy reference of ``_first_pk_nonlinear``: component by component on contiguous (n, P) planes into
        preallocated buffers (numpy's matmul loops over tiny 3 x 3 products), ``work`` or fresh ones; the result is
        work['A'] then:

            F S - C eps = mu A + lambda/2 tr(A) I + G S,  A = G^T G,  S = 2 mu (sym G + A/2) + lambda tr(...) I.
        """
        lmbda, mu = self.lmbda, self.mu
        if work is None:
            work = {k: np.empty_like(G) for k in ("A", "S")}
            work.update({k: np.empty_like(G[0, 0]) for k in ("tmp", "tr_A", "tr_E")})
        A, S, tmp, tr_A, tr_E = work["A"], work["S"], work["tmp"], work["tr_A"], work["tr_E"]
        for i in range(3):
            for j in range(i, 3):
                a = A[i, j]
                np.multiply(G[0, i], G[0, j], out=a)
                for k in (1, 2):
                    np.multiply(G[k, i], G[k, j], out=tmp)
                    a += tmp
                if i != j:
                    A[j, i] = a                                  # A is symmetric
        np.add(A[0, 0], A[1, 1], out=tr_A)
        tr_A += A[2, 2]
        np.add(G[0, 0], G[1, 1], out=tr_E)
        tr_E += G[2, 2]
        np.multiply(tr_A, 0.5, out=tmp)
        tr_E += tmp
        tr_E *= lmbda
        tr_A *= 0.5 * lmbda
        for i in range(3):
            for j in range(i, 3):
                s = S[i, j]
                np.add(G[i, j], G[j, i], out=s)
                s += A[i, j]
                s *= mu
                if i == j:
                    s += tr_E
                else:
                    S[j, i] = s
        out = A
        out *= mu
        for k in range(3):
            out[k, k] += tr_A
        for i in range(3):
            for j in range(3):
                o = out[i, j]
                for k in range(3):
                    np.multiply(G[i, k], S[k, j], out=tmp)
                    o += tmp
        return out

    def evaluate(self, Q: np.ndarray, linear: bool = False, chunk: int = 1 << 22) -> np.ndarray:
        """Nonlinear reduced force g~(q) (eq. 23) for a batch Q (r, P) -> (r, P); with linear=True, K~ q instead.

        Two GEMMs with the cached gradient planes (gradients, projection) around ~60 flops per point and state, in
        ``precision``; the result is float64. States are taken in chunks of about ``chunk`` / n_points to bound the
        temporaries; with few points (the integrator's cubature) the work arrays are kept for the next call."""
        Q = np.asarray(Q, float).reshape(self.r, -1)
        n, P = self.H.shape[0], Q.shape[1]
        planes, weighted = self._planes
        step = max(1, chunk // max(n, 1))
        if P > step:
            return np.hstack([self.evaluate(Q[:, k:k + step], linear, chunk) for k in range(0, P, step)])
        Q = Q.astype(planes.dtype, copy=False)
        if linear:
            G = (planes @ Q).reshape(3, 3, n, P)
            S = self.mu * (G + G.transpose(1, 0, 2, 3))
            tr = self.lmbda * (G[0, 0] + G[1, 1] + G[2, 2])
            for k in range(3):
                S[k, k] += tr
            return (weighted @ S.reshape(9 * n, P)).astype(float, copy=False)
        # work arrays kept between calls for few points (the integrator's cubature); temporaries for all of a mesh's
        work = self._buffers(n, P, planes.dtype) if 27 * n * P * planes.itemsize <= _KEEP_BUFFERS else None
        G = (planes @ Q if work is None else np.matmul(planes, Q, out=work["G"])).reshape(3, 3, n, P)
        return (weighted @ self._first_pk_nonlinear(G, work).reshape(9 * n, P)).astype(float, copy=False)

    def point_contributions(self, Q: np.ndarray) -> np.ndarray:
        """Each point's share of g~ (the summand of eq. 23 before the sum over points): (n, r, P) for Q (r, P)."""
        Q = np.asarray(Q, float).reshape(self.r, -1)
        n, P = self.H.shape[0], Q.shape[1]
        planes = self._planes[0] if self.precision == "double" else self._gradient_planes(self.H)
        P1 = self._first_pk_nonlinear((planes @ Q).reshape(3, 3, n, P))          # (3, 3, n, P)
        Hw = (self.H * self.w[:, None, None, None]).reshape(n, self.r, 9)
        return Hw @ np.ascontiguousarray(P1.reshape(9, n, P).transpose(1, 0, 2))

    def _stress(self, E: np.ndarray) -> np.ndarray:
        tr = E[:, 0, 0] + E[:, 1, 1] + E[:, 2, 2]
        S = 2.0 * self.mu * E
        for k in range(3):
            S[:, k, k] += self.lmbda * tr
        return S

    def jacobian(self, q: np.ndarray, chunk_points: int = 4096) -> np.ndarray:
        """d g~ / d q at one state q (r,) -> (r, r), exact, as two GEMMs per chunk of points:

        J_f[m, l] = sum_p w [ (H_l S) : H_m + sym(F^T H_l) : C : sym(F^T H_m) ],  J = J_f - K~.
        """
        q = np.asarray(q, float).reshape(self.r, 1)
        r = self.r
        J = np.zeros((r, r))
        for start in range(0, self.H.shape[0], chunk_points):
            H = self.H[start:start + chunk_points]
            w = self.w[start:start + chunk_points]
            n = H.shape[0]
            G = np.einsum("nlij,l->nij", H, q[:, 0])
            F = G + np.eye(3)
            E = 0.5 * (_batched_product(np.swapaxes(F, 1, 2), F) - np.eye(3))
            S = self._stress(E[..., None])[..., 0]
            HS = _batched_product(H, S[:, None])                              # (n, r, 3, 3)
            J += (H * w[:, None, None, None]).transpose(1, 0, 2, 3).reshape(r, n * 9) @ \
                HS.transpose(1, 0, 2, 3).reshape(r, n * 9).T
            e = _sym_voigt(_batched_product(np.swapaxes(F, 1, 2)[:, None], H))  # (n, r, 6)
            Ce = _apply_C(e, self.lmbda, self.mu) * w[:, None, None]
            J += e.transpose(1, 0, 2).reshape(r, n * 6) @ Ce.transpose(1, 0, 2).reshape(r, n * 6).T
        return J - self._stiffness

    def jacobians(self, Q: np.ndarray) -> np.ndarray:
        """``jacobian`` at each column of Q (r, P) -> (P, r, r) (each state's GEMMs are already the cost)."""
        Q = np.asarray(Q, float).reshape(self.r, -1)
        return np.stack([self.jacobian(q) for q in Q.T]) if Q.shape[1] else np.zeros((0, self.r, self.r))

    @functools.cached_property
    def _stiffness(self) -> np.ndarray:
        return self.stiffness()

    def stiffness(self) -> np.ndarray:
        """K~ = <C eps_i, eps_m> (r, r)."""
        eps = _sym_voigt(self.H)                       # (n, r, 6)
        Ceps = _apply_C(eps, self.lmbda, self.mu) * self.w[:, None, None]
        return np.einsum("nia,nja->ij", Ceps, eps)


@dataclasses.dataclass(frozen=True)
class PolynomialForces:
    """g~(q) = A~ m2(q) + B~ m3(q) over unique monomials (eq. 24).

    Attributes:
        A: (r, r(r+1)/2) quadratic coefficients; B: (r, r(r+1)(r+2)/6) cubic coefficients.
    """

    A: np.ndarray
    B: np.ndarray

    precision = "double"
    has_potential = True

    @property
    def r(self) -> int:
        return self.A.shape[0]

    def with_precision(self, precision: str) -> "PolynomialForces":
        raise ValueError("force precision applies to quadrature forces (exact or hyper-reduced), not to "
                         f"{type(self).__name__}")

    def scaled(self, factor: float) -> "PolynomialForces":
        """The force times ``factor``: both tensors scaled."""
        return PolynomialForces(self.A * factor, self.B * factor)

    def premultiplied(self, X: np.ndarray) -> "PolynomialForces":
        """X @ g~ as tensors X A~, X B~ (the explicit scheme's X3, X4 of eqs. 32-33: one GEMM per step less)."""
        return PolynomialForces(A=X @ self.A, B=X @ self.B)

    def potential(self, Q: np.ndarray) -> np.ndarray:
        """V(q) with grad V = g~ (SVK forces derive from a potential): V = q.A m2 / 3 + q.B m3 / 4, per column."""
        Q = np.asarray(Q, float).reshape(self.r, -1)
        a, b = quadratic_monomial_indices(self.r)
        ca, cb, cc = cubic_monomial_indices(self.r)
        return (np.sum(Q * (self.A @ (Q[a] * Q[b])), axis=0) / 3.0
                + np.sum(Q * (self.B @ (Q[ca] * Q[cb] * Q[cc])), axis=0) / 4.0)

    def arrays(self) -> dict[str, np.ndarray]:
        """Its entries in a model's file (``model.reduced``)."""
        return {"forces": "polynomial", "A": self.A, "B": self.B}

    @classmethod
    def from_arrays(cls, arrays) -> "PolynomialForces":
        return cls(arrays["A"], arrays["B"])

    def __post_init__(self):
        r = self.A.shape[0]
        if self.A.shape != (r, r * (r + 1) // 2) or self.B.shape != (r, r * (r + 1) * (r + 2) // 6):
            raise ValueError(f"PolynomialForces: A {self.A.shape} and B {self.B.shape} do not match r = {r}")

    def evaluate(self, Q: np.ndarray) -> np.ndarray:
        """g~ for a batch Q (r, P) -> (r, P): from two states on, the C kernel on A~ and B~ packed once
        (``forces.kernel.polynomial_kernel``); without it (or for one state) GEMMs over monomials, the cubic one
        without forming m3: for each j, Q_j * (B[:, triples starting at j] @ m2[pairs starting at >= j])."""
        Q = np.asarray(Q, float).reshape(self.r, -1)
        if Q.shape[1] >= 2 and self._panels is not None:
            return polynomial_kernel()(self._panels, Q)
        return self._evaluate_numpy(Q)

    @functools.cached_property
    def _panels(self) -> "tuple | None":
        """A~ and B~ packed for the C kernel (a copy of both), or None without a kernel or past 1 GB."""
        if polynomial_kernel() is None or self.A.nbytes + self.B.nbytes > 2 ** 30:
            return None
        return ((2, pack_panels(self.A)), (3, pack_panels(self.B)))

    def _evaluate_numpy(self, Q: np.ndarray) -> np.ndarray:
        r = self.r
        a, b = quadratic_monomial_indices(r)
        m2 = Q[a] * Q[b]
        out = self.A @ m2
        if Q.shape[1] <= 2:                                # one or two states: a single GEMV over m3 is faster
            first, cc = _cubic_from_pairs(r)
            return out + self.B @ (m2[first] * Q[cc])
        start = 0
        pair_start = 0
        for j in range(r):
            n_tail = (r - j) * (r - j + 1) // 2            # pairs (b, c) with j <= b <= c
            out += Q[j] * (self.B[:, start:start + n_tail] @ m2[pair_start:])
            start += n_tail
            pair_start += r - j
        return out

    def jacobian(self, q: np.ndarray) -> np.ndarray:
        """d g~ / d q at one state q (r,) -> (r, r), exact: A~ D2 + B~ D3 with D2, D3 the sparse derivatives of
        the monomials (2 and 3 entries a row)."""
        import scipy.sparse as sp

        q = np.asarray(q, float).ravel()
        r = self.r
        a, b = quadratic_monomial_indices(r)
        rows2 = np.arange(a.size)
        D2 = sp.csr_matrix((np.concatenate([q[b], q[a]]), (np.concatenate([rows2, rows2]), np.concatenate([a, b]))),
                           shape=(a.size, r))
        ca, cb, cc = cubic_monomial_indices(r)
        rows3 = np.arange(ca.size)
        D3 = sp.csr_matrix((np.concatenate([q[cb] * q[cc], q[ca] * q[cc], q[ca] * q[cb]]),
                            (np.tile(rows3, 3), np.concatenate([ca, cb, cc]))), shape=(ca.size, r))
        return np.asarray((D2.T @ self.A.T).T + (D3.T @ self.B.T).T)

    def jacobians(self, Q: np.ndarray, chunk: int = 256) -> np.ndarray:
        """``jacobian`` at each column of Q (r, P) -> (P, r, r), as two GEMMs over the states: dg~/dq is linear in q
        through A~ and quadratic through B~, so vec(J(q)) = T2 q + T3 m2(q) with T2 (r^2, r) and T3 (r^2, r(r+1)/2)
        gathered once from A~ and B~ (T3 has r^4 / 2 entries: 37 MB at r = 55). Where T3 would exceed 512 MB it falls
        back to one ``jacobian`` per state."""
        Q = np.asarray(Q, float).reshape(self.r, -1)
        r, P = self.r, Q.shape[1]
        if r * r * r * (r + 1) // 2 * 8 > 512 * 2 ** 20:
            return np.stack([self.jacobian(q) for q in Q.T]) if P else np.zeros((0, r, r))
        T2, T3 = self._jacobian_tensors
        a, b = quadratic_monomial_indices(r)
        out = np.empty((P, r, r))
        for s in range(0, P, chunk):
            X = Q[:, s:s + chunk]
            out[s:s + chunk] = (T2 @ X + T3 @ (X[a] * X[b])).T.reshape(-1, r, r)
        return out

    @functools.cached_property
    def _jacobian_tensors(self) -> tuple[np.ndarray, np.ndarray]:
        """(T2, T3): J(q)[i, j] = T2[i r + j] . q + T3[i r + j] . m2(q). A pair (a, b) gives d(q_a q_b)/dq_j = q_b
        [j = a] + q_a [j = b]; a triple (a, b, c) gives q_b q_c [j = a] + q_a q_c [j = b] + q_a q_b [j = c]."""
        r = self.r
        a, b = quadratic_monomial_indices(r)
        T2 = np.zeros((r, r, r))
        np.add.at(T2, (slice(None), a, b), self.A)            # j = a: coefficient of q_b
        np.add.at(T2, (slice(None), b, a), self.A)            # j = b: coefficient of q_a
        ca, cb, cc = cubic_monomial_indices(r)
        n2 = a.size
        T3 = np.zeros((r, r, n2))
        for j, (p, q) in ((ca, (cb, cc)), (cb, (ca, cc)), (cc, (ca, cb))):
            np.add.at(T3, (slice(None), j, _pair_index(r, p, q)), self.B)
        return T2.reshape(r * r, r), T3.reshape(r * r, n2)


def _unique_pair_strains(H: np.ndarray, pa: np.ndarray, pb: np.ndarray) -> np.ndarray:
    """P_ab = sym(H_a^T H_b) for the unique pairs (a <= b) as scaled Voigt vectors (n, n_pairs, 6)."""
    Ht = np.ascontiguousarray(H.transpose(2, 3, 0, 1))     # (k, l, n, r): contiguous planes per component
    Ha, Hb = Ht[..., pa], Ht[..., pb]                     # one gather each: (3, 3, n, n_pairs)
    out = np.empty((H.shape[0], pa.size, 6))
    for v, (l, m) in enumerate(zip(_VOIGT_I, _VOIGT_J)):
        acc = Ha[0, l] * Hb[0, m]
        for k in range(3):
            if k:
                acc += Ha[k, l] * Hb[k, m]
            if l != m:
                acc += Ha[k, m] * Hb[k, l]
        out[:, :, v] = acc * (_VOIGT_SCALE[v] * (0.5 if l != m else 1.0))
    return out


def compute_polynomial_forces(forces: QuadratureForces, chunk_points: int = 512,
                              chunk_elements: int = 1 << 24) -> PolynomialForces:
    """Exact intrusive A~ and B~ from the quadrature data (chunked GEMMs over points).

    Cost ~ 2 r^3 * 3 n_points (quadratic) + (r^2/2)^2 * 12 n_points (cubic Gram matrix) flops; memory: the Gram
    matrix's (r^2/2)^2 doubles, read on its upper triangle (never symmetrised in a copy), and B~'s r^4/6, filled in
    column chunks of ``chunk_elements`` entries (r = 155: 1.2 + 0.8 GB; r = 205: 3.6 + 2.4 GB).
    """
    H, w, lmbda, mu = forces.H, forces.w, forces.lmbda, forces.mu
    r = forces.r
    pa, pb = quadratic_monomial_indices(r)
    n_pairs = pa.size
    from scipy.linalg.blas import dsyrk

    T = np.zeros((r, n_pairs))        # T[i, (jm)] = <eps_i, C P_jm>
    G = np.zeros((n_pairs, n_pairs), order="F")  # G[(ij), (km)] = <P_ij, C P_km>, upper triangle accumulated
    # C is symmetric positive definite in scaled Voigt form: G = Y^T Y with Y = C^(1/2) P sqrt(w) (a SYRK)
    C6 = _apply_C(np.eye(6), lmbda, mu)
    lam6, vec6 = np.linalg.eigh(C6)
    if lam6.min() <= 0:
        raise ValueError("elasticity tensor is not positive definite (check E and nu)")
    C_half = vec6 @ np.diag(np.sqrt(lam6)) @ vec6.T
    for start in range(0, H.shape[0], chunk_points):
        Hc, wc = H[start:start + chunk_points], w[start:start + chunk_points]
        n = Hc.shape[0]
        eps = _sym_voigt(Hc)                                          # (n, r, 6)
        Pu = _unique_pair_strains(Hc, pa, pb)                         # (n, n_pairs, 6)
        CPu = _apply_C(Pu, lmbda, mu)
        eps_w = (eps * wc[:, None, None]).transpose(1, 0, 2).reshape(r, n * 6)
        CP_flat = CPu.transpose(0, 2, 1).reshape(n * 6, n_pairs)
        T += eps_w @ CP_flat
        Y = ((Pu @ C_half) * np.sqrt(wc)[:, None, None]).transpose(0, 2, 1).reshape(n * 6, n_pairs)
        G = dsyrk(1.0, Y, beta=1.0, c=G, trans=1, lower=0, overwrite_c=1)
    # quadratic: a^m_ij = T[i, (jm)] + 1/2 T[m, (ij)]; unique monomials a <= b
    idx = np.arange(r)
    T_full = T[:, _pair_index(r, idx[:, None], idx[None, :])]         # (i, j, m)
    a_full = np.einsum("ijm->mij", T_full) + 0.5 * T_full             # (m, i, j)
    A = a_full[:, pa, pb] + np.where(pa != pb, a_full[:, pb, pa], 0.0)
    # cubic: b^m_ijk = 1/2 G[(ij), (km)]; coefficient of q_a q_b q_c = sum over its distinct orderings
    ca, cb, cc = cubic_monomial_indices(r)
    stab = np.where((ca == cb) & (cb == cc), 6.0, np.where((ca == cb) | (cb == cc), 2.0, 1.0))
    B = np.empty((r, ca.size))
    step = max(1, chunk_elements // r)
    for s in range(0, ca.size, step):                  # column chunks: the gathers' index arrays stay small
        cols = slice(s, s + step)
        acc = np.zeros((r, ca[cols].size))
        for i, j, k in itertools.permutations((ca[cols], cb[cols], cc[cols])):
            p = _pair_index(r, i, j)[None, :]
            q = _pair_index(r, k[None, :], idx[:, None])
            acc += G[np.minimum(p, q), np.maximum(p, q)]   # G is symmetric: its upper triangle holds it
        B[:, cols] = 0.5 * acc / stab[cols]
    return PolynomialForces(A=A, B=B)
