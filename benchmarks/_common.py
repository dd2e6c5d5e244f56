"""Shared helpers of the benchmark scripts: machine description, result files, the demos as modules."""
from __future__ import annotations

import functools
import importlib.util
import os
import platform
import sys
from pathlib import Path

from rotor37_rom.npz import save_json

DEMOS = Path(__file__).resolve().parents[1] / "demos"


def machine_description() -> str:
    """CPU, core count, BLAS and Python version, for the tables."""
    blas = Path("/etc/alternatives/libblas.so.3-x86_64-linux-gnu")
    name = "OpenBLAS" if blas.exists() and "openblas" in str(blas.resolve()) else "reference BLAS"
    if name == "OpenBLAS":
        import importlib

        from rotor37_rom.blas_check import openblas_core

        importlib.import_module("numpy")                 # the BLAS as this interpreter loads it
        name += f" ({openblas_core()} kernels)"
    return f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, {name}, " \
           f"Python {platform.python_version()}"


def mpirun_env(**extra: str) -> dict:
    """The environment of an ``mpirun`` child: as root on the CI machine, oversubscribed, and unbound (a rank waiting
    for rank 0's gmsh must not hold its core; gmsh meshes with two threads), plus ``extra``."""
    return dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
                OMPI_MCA_rmaps_base_oversubscribe="1", OMPI_MCA_hwloc_base_binding_policy="none", **extra)


def write_results(name: str, rows: list, **extra) -> str:
    """results/<name>.json with the machine and rows; returns the machine description."""
    machine = machine_description()
    save_json(f"results/{name}.json", {"machine": machine, "rows": rows, **extra}, indent=1)   # never half a file
    return machine


@functools.lru_cache(maxsize=None)
def load_demo(name: str):
    """demos/<name>.py as a module (demos/ is not a package), loaded once per process; registered in sys.modules, as
    its dataclasses look their module up."""
    spec = importlib.util.spec_from_file_location(f"demo_{name}", DEMOS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module
