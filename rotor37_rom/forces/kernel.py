"""A fused C kernel for the nonlinear part of the SVK first Piola-Kirchhoff stress at many points and states.

Why C in a NumPy layer: the cubature force of the integrator spent ~40 % of each step in ~125 element-wise NumPy
calls on (points x states) planes (memory- and call-bound, ~3 GFLOP/s); one pass that keeps each point's 3 x 3
tensors in registers is 8-17x faster (bench_integrator). The source is compiled on first use with the system C
compiler (the one FFCx already needs for dolfinx's forms) into a per-user cache, keyed by the source, the flags and
the CPU. Where no compiler works, or with ``ROTOR37_C_KERNEL=0``, callers get ``None`` and keep their NumPy path,
which stays the reference the kernel is tested against.

    out = mu A + lambda/2 tr(A) I + G S,  A = G^T G,  S = 2 mu (sym G + A/2) + lambda tr(sym G + A/2) I,

for G (9, m) displacement-gradient planes (row 3 i + j holds G_ij at the m points-and-states), out likewise.
"""
from __future__ import annotations

import ctypes
import functools
import hashlib
import logging
import os
import platform
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np

__all__ = ["pk_nonlinear_kernel"]

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


def _compile(target: Path) -> None:
    compiler = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")
    if compiler is None:
        raise RuntimeError("no C compiler (cc, gcc) on PATH")
    target.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=target.parent) as tmp:
        src, lib = Path(tmp) / "pk.c", Path(tmp) / target.name
        src.write_text(_SOURCE)
        for arch in (["-march=native"], []):         # -march=native is gcc/clang on x86/arm; plain -O3 elsewhere
            run = subprocess.run([compiler, *_FLAGS, *arch, str(src), "-o", str(lib)], capture_output=True,
                                 text=True)
            if run.returncode == 0:
                break
        else:
            raise RuntimeError(f"{compiler} failed: {run.stderr.strip()[:300]}")
        os.replace(lib, target)                       # atomic: MPI ranks compiling at once never see half a file


@functools.lru_cache(maxsize=None)
def _library() -> ctypes.CDLL | None:
    if os.environ.get("ROTOR37_C_KERNEL", "1") == "0":
        return None
    key = hashlib.sha256("\0".join((_SOURCE, *_FLAGS, _cpu_key(), platform.machine())).encode()).hexdigest()[:20]
    target = _cache_dir() / f"pk_nonlinear_{key}.so"
    try:
        if not target.is_file():
            _compile(target)
        return ctypes.CDLL(str(target))
    except (OSError, RuntimeError, subprocess.SubprocessError) as exc:
        log.warning("SVK C kernel unavailable, the NumPy path is used (~1.6x slower cubature steps): %s", exc)
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


def pk_nonlinear_kernel(dtype) -> "callable | None":
    """The compiled kernel for float32 or float64 as ``kernel(G, out, lmbda, mu)`` on C-contiguous arrays of 9 m
    values each (G read, out written), or None where it cannot be built (then use the NumPy path)."""
    return _kernel_for(np.dtype(dtype))
