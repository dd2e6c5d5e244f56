"""Two C kernels of the reduced SVK forces: the nonlinear part of the first Piola-Kirchhoff stress at many points
and states (the cubature force), and the exact polynomial force g(q) = A m2(q) + B m3(q) for a batch of states.

Why C in a NumPy layer: the cubature force of the integrator spent ~40 % of each step in ~125 element-wise NumPy
calls on (points x states) planes (memory- and call-bound, ~3 GFLOP/s); one pass that keeps each point's 3 x 3
tensors in registers is 8-17x faster (bench_integrator). The source is compiled on first use with the system C
compiler (the one FFCx already needs for dolfinx's forms) into a per-user cache, keyed by the source, the flags and
the CPU. Where no compiler works, or with ``ROTOR37_C_KERNEL=0``, callers get ``None`` and keep their NumPy path,
which stays the reference the kernel is tested against.

    out = mu A + lambda/2 tr(A) I + G S,  A = G^T G,  S = 2 mu (sym G + A/2) + lambda tr(sym G + A/2) I,

for G (9, m) displacement-gradient planes (row 3 i + j holds G_ij at the m points-and-states), out likewise.

The polynomial force of a map's batch (r = 55, 11 speeds: B is 55 x 29,260) is a product with a long inner dimension
and few columns, where OpenBLAS repacks all of B at every call (2.8 ms a step, 280 us a speed-step). B never changes,
so it is packed once into panels of 8 rows; the kernel forms each state's monomials in their lexicographic order and
streams B once a call, 8 rows by 6 states in registers (1.2 ms, one thread). The inner dimension is cut into four
fixed segments summed in a fixed order, which the threads share: the result does not depend on the thread count.
"""
from __future__ import annotations

import ctypes
import functools
from collections.abc import Callable
import hashlib
import logging
import os
import platform
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np

__all__ = ["pk_nonlinear_kernel", "polynomial_kernel", "kernel_threads"]

log = logging.getLogger(__name__)

_SOURCE = r"""
#include <stddef.h>
#define PK_NONLINEAR(NAME, T)                                                                                  \
void NAME(const T *restrict G, T *restrict out, ptrdiff_t m, T lmbda, T mu)                                 \
{                                                                                                            \
  const T *restrict g00 = G, *restrict g01 = G + m, *restrict g02 = G + 2 * m,                               \
          *restrict g10 = G + 3 * m, *restrict g11 = G + 4 * m, *restrict g12 = G + 5 * m,                   \
          *restrict g20 = G + 6 * m, *restrict g21 = G + 7 * m, *restrict g22 = G + 8 * m;                   \
  T *restrict o00 = out, *restrict o01 = out + m, *restrict o02 = out + 2 * m,                               \
    *restrict o10 = out + 3 * m, *restrict o11 = out + 4 * m, *restrict o12 = out + 5 * m,                   \
    *restrict o20 = out + 6 * m, *restrict o21 = out + 7 * m, *restrict o22 = out + 8 * m;                   \
  const T half = (T)0.5;                                                                                     \
  _Pragma("omp simd")                                                                                        \
  for (ptrdiff_t p = 0; p < m; ++p) {                                                                        \
    T a00 = g00[p] * g00[p] + g10[p] * g10[p] + g20[p] * g20[p];                                             \
    T a11 = g01[p] * g01[p] + g11[p] * g11[p] + g21[p] * g21[p];                                             \
    T a22 = g02[p] * g02[p] + g12[p] * g12[p] + g22[p] * g22[p];                                             \
    T a01 = g00[p] * g01[p] + g10[p] * g11[p] + g20[p] * g21[p];                                             \
    T a02 = g00[p] * g02[p] + g10[p] * g12[p] + g20[p] * g22[p];                                             \
    T a12 = g01[p] * g02[p] + g11[p] * g12[p] + g21[p] * g22[p];                                             \
    T tr_a = a00 + a11 + a22;                                                                                \
    T tr_e = lmbda * (g00[p] + g11[p] + g22[p] + half * tr_a);                                               \
    T s00 = mu * (2 * g00[p] + a00) + tr_e, s11 = mu * (2 * g11[p] + a11) + tr_e;                            \
    T s22 = mu * (2 * g22[p] + a22) + tr_e;                                                                  \
    T s01 = mu * (g01[p] + g10[p] + a01), s02 = mu * (g02[p] + g20[p] + a02);                                \
    T s12 = mu * (g12[p] + g21[p] + a12);                                                                    \
    T d = half * lmbda * tr_a;                                                                               \
    o00[p] = mu * a00 + d + g00[p] * s00 + g01[p] * s01 + g02[p] * s02;                                      \
    o01[p] = mu * a01 + g00[p] * s01 + g01[p] * s11 + g02[p] * s12;                                          \
    o02[p] = mu * a02 + g00[p] * s02 + g01[p] * s12 + g02[p] * s22;                                          \
    o10[p] = mu * a01 + g10[p] * s00 + g11[p] * s01 + g12[p] * s02;                                          \
    o11[p] = mu * a11 + d + g10[p] * s01 + g11[p] * s11 + g12[p] * s12;                                      \
    o12[p] = mu * a12 + g10[p] * s02 + g11[p] * s12 + g12[p] * s22;                                          \
    o20[p] = mu * a02 + g20[p] * s00 + g21[p] * s01 + g22[p] * s02;                                          \
    o21[p] = mu * a12 + g20[p] * s01 + g21[p] * s11 + g22[p] * s12;                                          \
    o22[p] = mu * a22 + d + g20[p] * s02 + g21[p] * s12 + g22[p] * s22;                                      \
  }                                                                                                          \
}
PK_NONLINEAR(pk_nonlinear_f32, float)
PK_NONLINEAR(pk_nonlinear_f64, double)
"""

_POLY_SOURCE = r"""
#include <stddef.h>
#include <string.h>
typedef double v4d __attribute__((vector_size(32)));
#define TB 256          /* monomials a block: 8 rows x 256 of the packed panel (16 kB) stay in L1 over the states */
#define PT 6            /* states a register tile: 6 x 2 accumulators of 4 doubles */
#define NSEG 4          /* fixed segments of the monomials, summed in this order whatever the threads */

/* the monomials of each state q = Qt[p] (r values) in lexicographic order: m[p n + t] */
static void monomials(const double *restrict Qt, ptrdiff_t r, ptrdiff_t P, int deg, double *restrict m, ptrdiff_t n)
{
  for (ptrdiff_t p = 0; p < P; ++p) {
    const double *q = Qt + p * r;
    double *o = m + p * n;
    ptrdiff_t t = 0;
    for (ptrdiff_t a = 0; a < r; ++a)
      for (ptrdiff_t b = a; b < r; ++b) {
        if (deg == 2) { o[t++] = q[a] * q[b]; continue; }
        double qab = q[a] * q[b];
        for (ptrdiff_t c = b; c < r; ++c) o[t + c - b] = qab * q[c];
        t += r - b;
      }
  }
}

/* out[s] (P x rp) = sum over monomials t in [t_lo, t_hi) of m[:, t] C[:, t]^T, Cp the packed panels of C */
static void segment(const double *restrict Cp, ptrdiff_t rp, ptrdiff_t n, const double *restrict m, ptrdiff_t P,
                    ptrdiff_t t_lo, ptrdiff_t t_hi, double *restrict out)
{
  memset(out, 0, sizeof(double) * P * rp);
  for (ptrdiff_t t0 = t_lo; t0 < t_hi; t0 += TB) {
    ptrdiff_t nt = (t_hi - t0) < TB ? (t_hi - t0) : TB;
    for (ptrdiff_t ib = 0; ib < rp / 8; ++ib) {
      const double *c = Cp + (ib * n + t0) * 8;
      for (ptrdiff_t p0 = 0; p0 < P; p0 += PT) {
        v4d a[PT][2];
        memset(a, 0, sizeof a);
        const double *mm = m + p0 * n + t0;
        for (ptrdiff_t tt = 0; tt < nt; ++tt) {
          v4d lo, hi;
          memcpy(&lo, c + tt * 8, sizeof lo);
          memcpy(&hi, c + tt * 8 + 4, sizeof hi);
          for (int p = 0; p < PT; ++p) { a[p][0] += mm[p * n + tt] * lo; a[p][1] += mm[p * n + tt] * hi; }
        }
        for (int p = 0; p < PT; ++p) {
          double *o = out + (p0 + p) * rp + ib * 8;
          v4d lo, hi;
          memcpy(&lo, o, sizeof lo);
          memcpy(&hi, o + 4, sizeof hi);
          lo += a[p][0];
          hi += a[p][1];
          memcpy(o, &lo, sizeof lo);
          memcpy(o + 4, &hi, sizeof hi);
        }
      }
    }
  }
}

/* out (P x rp) += the force of degree deg (2: A m2, 3: B m3) at the states Qt (P x r, P a multiple of PT), with
   Cp (rp / 8 panels of n x 8) the packed coefficients, m (P x n) and seg (NSEG x P x rp) scratch */
void polynomial_f64(const double *restrict Cp, ptrdiff_t rp, ptrdiff_t n, int deg, const double *restrict Qt,
                    ptrdiff_t r, ptrdiff_t P, double *restrict m, double *restrict seg, double *restrict out,
                    int threads)
{
  monomials(Qt, r, P, deg, m, n);
  ptrdiff_t per = (n + NSEG - 1) / NSEG;
  #pragma omp parallel for num_threads(threads) schedule(static)
  for (int s = 0; s < NSEG; ++s) {
    ptrdiff_t lo = s * per, hi = (s + 1) * per < n ? (s + 1) * per : n;
    segment(Cp, rp, n, m, P, lo < n ? lo : n, hi, seg + s * P * rp);
  }
  for (int s = 0; s < NSEG; ++s)
    for (ptrdiff_t k = 0; k < P * rp; ++k) out[k] += seg[s * P * rp + k];
}
"""
#: states of one register tile of the polynomial kernel (the batch is padded with zero states to a multiple)
POLY_TILE = 6
# no -ffast-math: the kernel keeps IEEE arithmetic, so it differs from the NumPy path only by operation order
_FLAGS = ("-O3", "-fopenmp-simd", "-fPIC", "-shared")
_CTYPES = {np.dtype(np.float32): ctypes.c_float, np.dtype(np.float64): ctypes.c_double}


def _cache_dir() -> Path:
    root = os.environ.get("ROTOR37_KERNEL_CACHE") or os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(root) / "rotor37_rom"


def _cpu_key() -> str:
    """What -march=native depends on: the CPU's model and flags (a cache shared between machines stays valid)."""
    try:
        lines = Path("/proc/cpuinfo").read_text().splitlines()
        info = [ln for ln in lines if ln.startswith(("model name", "flags"))][:2]
    except OSError:
        info = []
    return "\n".join(info) or platform.processor() or platform.machine()


def _compile(target: Path, source: str = _SOURCE, flags: tuple = _FLAGS) -> None:
    compiler = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")
    if compiler is None:
        raise RuntimeError("no C compiler (cc, gcc) on PATH")
    target.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=target.parent) as tmp:
        src, lib = Path(tmp) / "pk.c", Path(tmp) / target.name
        src.write_text(source)
        for arch in (["-march=native"], []):         # -march=native is gcc/clang on x86/arm; plain -O3 elsewhere
            run = subprocess.run([compiler, *flags, *arch, str(src), "-o", str(lib)], capture_output=True,
                                 text=True)
            if run.returncode == 0:
                break
        else:
            raise RuntimeError(f"{compiler} failed: {run.stderr.strip()[:300]}")
        os.replace(lib, target)                       # atomic: MPI ranks compiling at once never see half a file


@functools.lru_cache(maxsize=None)
def _library(name: str = "pk_nonlinear") -> ctypes.CDLL | None:
    if os.environ.get("ROTOR37_C_KERNEL", "1") == "0":
        return None
    source, flags, cost = ((_SOURCE, _FLAGS, "~1.6x slower cubature steps") if name == "pk_nonlinear" else
                           (_POLY_SOURCE, (*_FLAGS, "-fopenmp"), "~2.4x slower exact GNL steps in a batch"))
    key = hashlib.sha256("\0".join((source, *flags, _cpu_key(), platform.machine())).encode()).hexdigest()[:20]
    target = _cache_dir() / f"{name}_{key}.so"
    try:
        if not target.is_file():
            _compile(target, source, flags)
        return ctypes.CDLL(str(target))
    except (OSError, RuntimeError, subprocess.SubprocessError) as exc:
        log.warning("SVK C kernel %s unavailable, the NumPy path is used (%s): %s", name, cost, exc)
        return None


@functools.lru_cache(maxsize=None)
def _kernel_for(dtype: np.dtype):
    lib = _library()
    if lib is None or dtype not in _CTYPES:
        return None
    fn = getattr(lib, "pk_nonlinear_f32" if dtype == np.float32 else "pk_nonlinear_f64")
    scalar = _CTYPES[dtype]
    fn.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_ssize_t, scalar, scalar]
    fn.restype = None

    def kernel(G: np.ndarray, out: np.ndarray, lmbda: float, mu: float) -> np.ndarray:
        if not (G.dtype == out.dtype == dtype and G.flags.c_contiguous and out.flags.c_contiguous
                and G.size == out.size and G.size % 9 == 0):
            raise ValueError("pk_nonlinear kernel: G and out must be C-contiguous arrays of 9 m values of "
                             f"{dtype}, got {G.dtype} {G.shape} and {out.dtype} {out.shape}")
        fn(G.ctypes.data, out.ctypes.data, G.size // 9, lmbda, mu)
        return out

    return kernel


def pk_nonlinear_kernel(dtype) -> "Callable[..., np.ndarray] | None":
    """The compiled kernel for float32 or float64 as ``kernel(G, out, lmbda, mu)`` on C-contiguous arrays of 9 m
    values each (G read, out written), or None where it cannot be built (then use the NumPy path)."""
    return _kernel_for(np.dtype(dtype))


def kernel_threads() -> int:
    """Threads of the polynomial kernel: OpenBLAS's own setting (OPENBLAS_NUM_THREADS, else OMP_NUM_THREADS), else
    the cores shared among the MPI ranks of this machine's run (``make test`` runs one thread a half, like its BLAS)."""
    for name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"):
        value = os.environ.get(name, "").strip()
        if value.isdigit() and int(value) > 0:
            return int(value)
    ranks = next((int(v) for v in (os.environ.get(k, "") for k in ("OMPI_COMM_WORLD_LOCAL_SIZE",
                                                                    "OMPI_COMM_WORLD_SIZE", "PMI_SIZE"))
                  if v.isdigit() and int(v) > 0), 1)
    return max(1, (os.cpu_count() or 1) // ranks)


@functools.lru_cache(maxsize=None)
def _polynomial_function():
    lib = _library("polynomial")
    if lib is None:
        return None
    fn = lib.polynomial_f64
    ptr, size = ctypes.c_void_p, ctypes.c_ssize_t
    fn.argtypes = [ptr, size, size, ctypes.c_int, ptr, size, size, ptr, ptr, ptr, ctypes.c_int]
    fn.restype = None
    return fn


def pack_panels(C: np.ndarray) -> np.ndarray:
    """C (r, n) as the kernel reads it: panels of 8 rows (zero rows past r), each n x 8 row-major."""
    C = np.asarray(C)
    if C.ndim != 2 or C.dtype.kind != "f" or not np.isfinite(C).all():
        raise ValueError(f"pack_panels: C must be a finite 2-D float array (r, n), got {C.dtype} {C.shape}")
    r, n = C.shape
    rp = -(-r // 8) * 8
    padded = np.zeros((rp, n))
    padded[:r] = C
    return np.ascontiguousarray(padded.reshape(rp // 8, 8, n).transpose(0, 2, 1))


def polynomial_kernel() -> "Callable[..., np.ndarray] | None":
    """``kernel(panels, Q) -> (r, P)``: sum over degrees d of C_d m_d(Q) for ``panels`` = [(d, pack_panels(C_d)), ...]
    (d = 2: r(r+1)/2 pairs, d = 3: r(r+1)(r+2)/6 triples, lexicographic) and states Q (r, P); or None where the
    kernel cannot be built (then use the NumPy path)."""
    fn = _polynomial_function()
    if fn is None:
        return None

    def kernel(panels, Q: np.ndarray) -> np.ndarray:
        Q = np.asarray(Q, float)
        if Q.ndim != 2 or Q.shape[1] == 0:
            raise ValueError(f"polynomial kernel: Q must be (r, P) with P >= 1 states, got {Q.shape}")
        r, P = Q.shape
        rp, Pp = -(-r // 8) * 8, -(-P // POLY_TILE) * POLY_TILE
        Qt = np.zeros((Pp, r))
        Qt[:P] = Q.T
        out = np.zeros((Pp, rp))
        threads = kernel_threads()
        seg = np.empty((4, Pp, rp))
        for degree, Cp in panels:
            n = Cp.shape[1]
            if Cp.dtype != np.float64 or not Cp.flags.c_contiguous or Cp.shape != (rp // 8, n, 8):
                raise ValueError(f"polynomial kernel: panels of shape ({rp // 8}, n, 8) float64 expected for r = {r}, "
                                 f"got {Cp.dtype} {Cp.shape}")
            if n != (r * (r + 1) // 2 if degree == 2 else r * (r + 1) * (r + 2) // 6):
                raise ValueError(f"polynomial kernel: {n} monomials do not match degree {degree} at r = {r}")
            m = np.empty((Pp, n))
            fn(Cp.ctypes.data, rp, n, degree, Qt.ctypes.data, r, Pp, m.ctypes.data, seg.ctypes.data, out.ctypes.data,
               threads)
        return out[:P, :r].T

    return kernel
