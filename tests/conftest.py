"""Shared fixtures: the ci-preset blade and its compiled SVK operators (built once per session)."""
import os

import pytest

os.environ.setdefault("MPLBACKEND", "Agg")


@pytest.fixture(scope="session")
def ci_blade():
    from rotor37_rom import fem

    return fem.create_blade_sector(preset="ci")


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
