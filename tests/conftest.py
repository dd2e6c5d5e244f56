"""Shared fixtures: the ci-preset blade and its compiled SVK operators (built once per session)."""
import os

import pytest

os.environ.setdefault("MPLBACKEND", "Agg")

class Killed(Exception):
    """A run stopped on purpose just after a checkpoint (``killed_after``)."""


def killed_after(simulate, kill_at: int, **overrides):
    """``simulate`` (the integrator, as a study module imports it) that saves each checkpoint, then raises Killed
    once the loop has reached step ``kill_at``: a run killed right after a save. ``overrides``: keyword arguments
    forced on every call (e.g. checkpoint_seconds=0.0)."""
    def killed(*args, checkpoint=None, **kwargs):
        def save_then_die(st):
            checkpoint(st)
            if st.n >= kill_at:
                raise Killed

        return simulate(*args, checkpoint=save_then_die, **{**kwargs, **overrides})

    return killed


FE_FIXTURES = {"ci_blade", "ci_ops", "ci_rom", "table_path", "ci_disk", "ci_disk_ops", "disk_model"}


def pytest_collection_modifyitems(config, items):
    """Every test that uses an FE fixture is marked 'fe' (so make test-fe and -m 'not fe' select by what a test
    needs, not by a hand-kept list)."""
    for item in items:
        if FE_FIXTURES & set(getattr(item, "fixturenames", ())):
            item.add_marker(pytest.mark.fe)


def pytest_report_header(config):
    """Which BLAS kernels and how many threads this run uses (make test-kernels runs the suite under several)."""
    from rotor37_rom.blas_check import openblas_core

    import numpy  # noqa: F401  (loads the BLAS with this environment)

    return (f"OpenBLAS kernels: {openblas_core() or 'not OpenBLAS'}, OPENBLAS_NUM_THREADS="
            f"{os.environ.get('OPENBLAS_NUM_THREADS', 'unset')}, OPENBLAS_CORETYPE="
            f"{os.environ.get('OPENBLAS_CORETYPE', 'unset')}")


@pytest.fixture
def serial_and_mpi(tmp_path):
    """run(code) -> (serial, mpi): the array a script body saves (``np.save(sys.argv[1], ...)`` on rank 0), from a
    serial run and from mpirun -n 2."""
    import subprocess
    import sys
    import textwrap

    import numpy as np

    def run(code: str):
        script = tmp_path / "script.py"
        script.write_text(textwrap.dedent(code))
        serial, parallel = tmp_path / "serial.npy", tmp_path / "mpi.npy"
        subprocess.run([sys.executable, str(script), str(serial)], check=True, capture_output=True)
        env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
                   OMPI_MCA_rmaps_base_oversubscribe="1")
        proc = subprocess.run(["mpirun", "-n", "2", sys.executable, str(script), str(parallel)],
                              capture_output=True, text=True, env=env)
        assert proc.returncode == 0, proc.stderr[-2000:]
        return np.load(serial), np.load(parallel)

    return run


@pytest.fixture(scope="session")
def ci_blade():
    from rotor37_rom import fem

    return fem.create_blade_sector(preset="ci")


@pytest.fixture(scope="session")
def ci_disk():
    """The rotor 37 bladed-disk sector at the ci preset (36 sectors, blade 4 mm shorter, parametric blade)."""
    from rotor37_rom import fem

    return fem.create_disk_sector(preset="ci")


@pytest.fixture(scope="session")
def ci_disk_ops(ci_disk):
    from rotor37_rom import fem

    return fem.create_svk_operators(ci_disk)


@pytest.fixture(scope="session")
def disk_cache(tmp_path_factory):
    """The session's cache of disk models: the tests' other models of the ci sector with LE and r_c = 8 read the
    sector's Craig-Bampton modes from it instead of computing them again (~30 s each)."""
    return tmp_path_factory.mktemp("disk_cache")


@pytest.fixture(scope="session")
def disk_model(ci_disk, ci_disk_ops, disk_cache):
    """A small disk model of the ci sector (LE only: r_b = 3, r_c = 8, 4 modal derivatives by MI 2b, 96 interface
    modes; r = 636), exact forces; (model, build report)."""
    from rotor37_rom.reduction.disk_builder import DiskReductionConfig, build_disk_model

    config = DiskReductionConfig(tip_nodes="LE", r_c=8, r_md=4, criterion="MI2b", r_cyclic=96)
    return build_disk_model(ci_disk, config, ops=ci_disk_ops, cache_dir=disk_cache)


@pytest.fixture(scope="session")
def ci_ops(ci_blade):
    from rotor37_rom import fem

    return fem.create_svk_operators(ci_blade)


@pytest.fixture(scope="session")
def table_path():
    from rotor37_rom.geometry.tables import default_data_dir

    data = default_data_dir()
    if data is None:
        pytest.skip("NASA Table IV not found: ../shared/data/rotor37 (or $ROTOR37_DATA) is absent on this machine")
    return data / "rotor37geometry.dat"


@pytest.fixture(scope="session")
def ci_rom(ci_blade, ci_ops, tmp_path_factory):
    """r = 45 reduced model of the ci blade (24 tip DOFs, 15 fixed-interface modes, the 6 global MDs of 1B/1T/2B)
    with exact cubic tensors: the model of the contact tests."""
    from rotor37_rom.reduction.builder import ReductionConfig, build_reduced_model

    config = ReductionConfig(r_c=15, r_md=0, global_md_modes=3, forces="intrusive")
    model, _ = build_reduced_model(ci_blade, config, ops=ci_ops, cache_dir=tmp_path_factory.mktemp("rom"))
    return model


def random_sector(rng, r_s: int, n_l: int):
    """A random sector's reduced matrices (``disk.assembly.SectorMatrices``: r_s interior coordinates, n_l DOFs per cyclic
    face, symmetric positive definite K and M) for the disk's algebra tests; tests import it with
    ``from conftest import random_sector``."""
    import numpy as np

    from rotor37_rom.disk.assembly import SectorMatrices

    n = r_s + 2 * n_l
    A, B = rng.standard_normal((n, n)), rng.standard_normal((n, n))
    K, M = A @ A.T + np.eye(n), B @ B.T + np.eye(n)
    omega_c = np.sqrt(np.linalg.eigvals(np.linalg.solve(M[:r_s, :r_s], K[:r_s, :r_s])).real)
    return SectorMatrices(K=K, M=M, r_s=r_s, n_L=n_l, omega_c=np.sort(omega_c))
