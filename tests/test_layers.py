"""Layering: geometry (gmsh + NumPy), forms (UFL) and the pure NumPy/SciPy modules never import dolfinx; the BLAS
under them runs kernels that fit the CPU."""
import subprocess
import sys

import pytest

PURE = ["rotor37_rom", "rotor37_rom.geometry.tables", "rotor37_rom.geometry.parametric", "rotor37_rom.geometry.blade",
        "rotor37_rom.forms", "rotor37_rom.modes", "rotor37_rom.reduction", "rotor37_rom.nonlinear_forces",
        "rotor37_rom.step", "rotor37_rom.ecsw", "rotor37_rom.clearance", "rotor37_rom.charts", "rotor37_rom.casing",
        "rotor37_rom.friction", "rotor37_rom.integrator", "rotor37_rom.sweep", "rotor37_rom.stress",
        "rotor37_rom.report", "rotor37_rom.blas_check", "rotor37_rom.svk_kernel"]


def test_pure_modules_do_not_import_dolfinx():
    code = ("import sys\n" + "".join(f"import {m}\n" for m in PURE)
            + "bad = [m for m in ('dolfinx', 'petsc4py', 'slepc4py', 'pyvista') if m in sys.modules]\n"
            + "assert not bad, bad\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr[-1500:]


def test_openblas_runs_kernels_that_fit_the_cpu():
    """make setup (rotor37_rom/blas_check.py): OpenBLAS 0.3.21 falls back to its SSE3 'Prescott' kernels on CPUs it
    does not know (dgemm 6x slower on the project's AVX-512 machines); the environment must run fitting ones."""
    import importlib

    importlib.import_module("numpy")                     # loads the BLAS with the interpreter's environment
    from rotor37_rom.blas_check import AVX512, cpu_flags, openblas_core, suggested_coretype

    assert suggested_coretype("Prescott", AVX512 | {"avx2", "fma"}) == "SkylakeX"
    assert suggested_coretype("Prescott", {"avx2", "fma", "sse3"}) == "Haswell"
    assert suggested_coretype("Prescott", {"sse3"}) is None                     # nothing better to run
    assert suggested_coretype("SkylakeX", AVX512) is None and suggested_coretype(None, AVX512) is None
    core = openblas_core()
    if core is None:
        pytest.skip("the BLAS is not OpenBLAS")
    assert suggested_coretype(core, cpu_flags()) is None, \
        f"OpenBLAS runs its generic '{core}' kernels on this CPU: run make setup (it sets OPENBLAS_CORETYPE)"
