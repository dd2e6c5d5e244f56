"""The steady-state GNL study as a library function (``studies.steady_reference``, #87): its configs refuse what
cannot run, naming the field; a reduced run is made once, kept in the results file and read back, not run again."""
from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from rotor37_rom.studies.gnl_reference import SteadyCase
from rotor37_rom.studies.steady_reference import (FullOrderSettings, ReducedSettings, SteadyStudyConfig,
                                                  run_steady_study)


@pytest.mark.parametrize("make, field", [
    (lambda: FullOrderSettings(steps=(0.0,)), "full.steps"),
    (lambda: FullOrderSettings(steps=()), "full.steps"),
    (lambda: FullOrderSettings(rho_inf=1.5), "full.rho_inf"),
    (lambda: FullOrderSettings(energy=0.0), "full.energy"),
    (lambda: ReducedSettings(r_c=(0,)), "reduced.r_c"),
    (lambda: ReducedSettings(global_md=(21,)), "reduced.global_md"),
    (lambda: ReducedSettings(step=1.0), "reduced.step"),
    (lambda: ReducedSettings(cap_khz=float("nan")), "reduced.cap_khz"),
    (lambda: ReducedSettings(pod=(10,)), "reduced.pod"),
    (lambda: ReducedSettings(cubature=0.5), "reduced.cubature"),
    (lambda: ReducedSettings(train_speeds=(-1.0,)), "reduced.train_speeds"),
    (lambda: ReducedSettings(batch_cost=-1), "reduced.batch_cost"),
    (lambda: SteadyStudyConfig(()), "cases"),
    (lambda: SteadyStudyConfig((1280.0,)), "cases"),
    (lambda: SteadyStudyConfig((SteadyCase(1280.0),), results="out.txt"), "results"),
    (lambda: SteadyStudyConfig((SteadyCase(1280.0, hyperelastic="neo-hookean"),)), "hyperelastic"),
    (lambda: SteadyStudyConfig((SteadyCase(1280.0), SteadyCase(1300.0, hyperelastic="neo-hookean")),
                               reduced=ReducedSettings(r_c=())), "one hyperelastic law"),
])
def test_configs_refuse_naming_the_field(make, field):
    with pytest.raises(ValueError, match=field):
        make()


def test_reduced_run_is_kept_and_read_back(ci_blade, ci_ops, tmp_path):
    """r = 27 (r_c 3, no modal derivative), 3 revolutions at 1,280 rad/s: run, saved, then read back unchanged by a
    second call (its wall time is the first run's), and compared with nothing (no full-order run here)."""
    case = SteadyCase(1280.0, revolutions=3)
    config = SteadyStudyConfig((case,), FullOrderSettings(run=False), ReducedSettings(r_c=(3,), global_md=(0,)),
                               results=tmp_path / "steady.json", cache=tmp_path / "cache")
    (first,) = run_steady_study(config, ci_blade, ci_ops)
    key = config.reduced.key(3, 0)
    assert set(first.runs) == {key} and first.reference is None and first.rows == []
    run = first.runs[key]
    assert run["details"]["model"] == "reduced r = 27" and np.isfinite(run["value"]) and 0 < run["value"] < 5e-3
    saved = json.loads(config.results.read_text())
    assert saved[case.label()][key]["wall_s"] == run["wall_s"] and "machine" in saved
    (again,) = run_steady_study(dataclasses.replace(config), ci_blade, ci_ops)
    assert again.runs[key]["wall_s"] == run["wall_s"] and again.runs[key]["u_le"] == run["u_le"]


def test_steady_map_is_the_single_runs_batched(ci_blade, ci_ops, tmp_path):
    """A steady map's speed is the reduced run of that speed alone (the same scheme, casing and damping; only the
    batch's BLAS rounding differs, ~1e-9 of u after 3 revolutions: 1e-6 leaves three orders), GNL on; with GNL off
    the same model's linear runs; a map is kept and read back."""
    from rotor37_rom.studies import gnl_reference as gr
    from rotor37_rom.studies.steady_reference import map_label, run_steady_maps

    case = SteadyCase(1300.0, revolutions=3)
    config = SteadyStudyConfig((case,), FullOrderSettings(run=False), ReducedSettings(r_c=(3,), global_md=(0,)),
                               results=tmp_path / "steady.json", cache=tmp_path / "cache")
    maps = run_steady_maps(config, (1300.0, 1400.0, 2), ci_blade, ci_ops)
    key = config.reduced.key(3, 0)
    assert set(maps) == {key + " linear", key + " GNL"}
    (single,) = run_steady_study(config, ci_blade, ci_ops)
    alone = single.runs[key]["value"]
    assert maps[key + " GNL"]["speeds"] == [1300.0, 1400.0]
    assert maps[key + " GNL"]["value"][0] == pytest.approx(alone, rel=1e-6)
    assert maps[key + " linear"]["value"][0] != pytest.approx(alone, rel=1e-6)      # GNL off is another run
    saved = json.loads(config.results.read_text())[map_label(case, (1300.0, 1400.0, 2))]
    assert saved[key + " GNL"]["wall_s"] == maps[key + " GNL"]["wall_s"]
    with pytest.raises(ValueError, match="count"):
        run_steady_maps(config, (1300.0, 1400.0, 1), ci_blade, ci_ops)
