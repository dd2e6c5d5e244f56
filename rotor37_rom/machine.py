"""The machine a measurement ran on, stated with its numbers: the benchmarks' machine description, the environment of
their ``mpirun`` children, and the result files that carry both.

No dolfinx (``blas_check`` is read only when the BLAS is OpenBLAS): a benchmark calls it before any meshing.
"""
from __future__ import annotations

import os
import platform
from pathlib import Path

from rotor37_rom.npz import save_json


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
