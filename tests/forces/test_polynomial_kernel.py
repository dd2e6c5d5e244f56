"""The C kernel of the exact polynomial force (``forces.kernel.polynomial_kernel``) against the NumPy path.

Both compute g = A m2(q) + B m3(q) as sums of n products (n = r(r+1)(r+2)/6 at most) in different orders; any order
of an n-term sum has the forward error gamma_n sum |terms| (Higham, Accuracy and Stability, 3.1), and forming a
monomial adds two roundings. So the two paths differ by at most 2 gamma_(n+3) (|A| |m2| + |B| |m3|), entry by entry:
the bound is a theorem, not a measured band. Broken on purpose (the kernel's cubic monomials started at c = b + 1,
i.e. the wrong lexicographic order), the first test fails by 1e0 relative.
"""
from __future__ import annotations

import os
import shutil

import numpy as np
import pytest

from rotor37_rom.forces import kernel as K
from rotor37_rom.forces.tensors import PolynomialForces, cubic_monomial_indices, quadratic_monomial_indices

pytestmark = pytest.mark.skipif(os.environ.get("ROTOR37_C_KERNEL") == "0" or
                                (shutil.which("cc") is None and shutil.which("gcc") is None),
                                reason="no C kernel here (ROTOR37_C_KERNEL=0 or no compiler): the NumPy path is used")


def random_forces(r: int, seed: int) -> PolynomialForces:
    rng = np.random.default_rng(seed)
    return PolynomialForces(rng.standard_normal((r, r * (r + 1) // 2)),
                            rng.standard_normal((r, r * (r + 1) * (r + 2) // 6)))


def roundoff_bound(forces: PolynomialForces, Q: np.ndarray) -> np.ndarray:
    r = forces.r
    a, b = quadratic_monomial_indices(r)
    ca, cb, cc = cubic_monomial_indices(r)
    n = forces.B.shape[1] + forces.A.shape[1] + 3
    u = np.finfo(float).eps / 2
    gamma = n * u / (1 - n * u)
    return 2 * gamma * (np.abs(forces.A) @ np.abs(Q[a] * Q[b]) + np.abs(forces.B) @ np.abs(Q[ca] * Q[cb] * Q[cc]))


@pytest.mark.parametrize("r", [5, 8, 13, 17])
@pytest.mark.parametrize("P", [2, 5, 6, 7, 13])
def test_kernel_equals_numpy_within_roundoff(r, P):
    """Every r (multiple of the 8-row panel or not) and every batch (multiple of the 6-state tile or not)."""
    assert K.polynomial_kernel() is not None                  # a compiler is here: a silent fallback is a failure
    forces = random_forces(r, seed=r * 100 + P)
    Q = np.random.default_rng(P).standard_normal((r, P)) * 1e-2
    fast, ref = forces.evaluate(Q), forces._evaluate_numpy(Q)
    assert forces._panels is not None
    assert np.all(np.abs(fast - ref) <= roundoff_bound(forces, Q))
    single = np.column_stack([forces.evaluate(q) for q in Q.T])          # one state: the NumPy path
    assert np.all(np.abs(fast - single.reshape(r, P)) <= roundoff_bound(forces, Q))


def test_kernel_result_does_not_depend_on_the_threads(monkeypatch):
    """Four fixed segments of the monomials summed in a fixed order: bit-identical with 1, 2 or 3 threads (a run
    resumed with other threads is the same run)."""
    forces = random_forces(11, seed=3)
    Q = np.random.default_rng(4).standard_normal((11, 9)) * 1e-2
    outs = []
    for threads in ("1", "2", "3"):
        monkeypatch.setenv("OPENBLAS_NUM_THREADS", threads)
        assert K.kernel_threads() == int(threads)
        outs.append(forces.evaluate(Q))
    assert all(np.array_equal(outs[0], o) for o in outs[1:])


def test_threads_follow_blas_settings(monkeypatch):
    for name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "OMPI_COMM_WORLD_LOCAL_SIZE", "OMPI_COMM_WORLD_SIZE",
                 "PMI_SIZE"):
        monkeypatch.delenv(name, raising=False)
    cores = os.cpu_count() or 1
    assert K.kernel_threads() == cores
    monkeypatch.setenv("OMP_NUM_THREADS", "1")
    assert K.kernel_threads() == 1
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "0")          # not a thread count: the next setting decides
    assert K.kernel_threads() == 1
    monkeypatch.delenv("OMP_NUM_THREADS")
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "two")
    monkeypatch.setenv("OMPI_COMM_WORLD_LOCAL_SIZE", str(2 * cores))   # more ranks than cores: one thread each
    assert K.kernel_threads() == 1


def test_kernel_refuses_what_it_cannot_read():
    kernel = K.polynomial_kernel()
    forces = random_forces(9, seed=1)
    panels = forces._panels
    with pytest.raises(ValueError, match="panels of shape"):
        kernel(panels, np.zeros((8, 3)))                       # states of another r
    with pytest.raises(ValueError, match="do not match degree"):
        kernel(((3, panels[0][1]),), np.zeros((9, 3)))         # quadratic panels called cubic
    with pytest.raises(ValueError, match=r"Q must be \(r, P\)"):
        kernel(panels, np.zeros((9, 0)))
    for bad in (np.zeros(5), np.zeros((2, 3), dtype=int), np.full((2, 3), np.nan)):
        with pytest.raises(ValueError, match="pack_panels: C must be"):
            K.pack_panels(bad)
