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


@pytest.fixture(scope="session")
def ci_rom(ci_blade, ci_ops, tmp_path_factory):
    """r = 45 reduced model of the ci blade (24 tip DOFs, 15 fixed-interface modes, the 6 global MDs of 1B/1T/2B)
    with exact cubic tensors: the model of the contact tests."""
    from rotor37_rom.builder import ReductionConfig, build_reduced_model

    config = ReductionConfig(r_c=15, r_md=0, global_md_modes=3, forces="intrusive")
    model, _ = build_reduced_model(ci_blade, config, ops=ci_ops, cache_dir=tmp_path_factory.mktemp("rom"))
    return model
