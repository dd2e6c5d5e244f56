"""The speed-accuracy scene 'gnl-steady' (#86): read from the steady-state benchmark's runs, its candidates are the
predictive reduced models run at every speed, their error the largest relative error on the steady max |u_LE|
against the full order over the speeds (a run not steady at some speed has none: infinite), their cost the mean wall
time per revolution; POD models (built from the full order's own fields) and other questions' cases are not
candidates; a missing or damaged results file is named with the command that makes it. Synthetic runs: a sine of
known amplitude at the rotation's 4th harmonic, so the errors are the amplitudes' ratios exactly."""
import json

import numpy as np
import pytest

from rotor37_rom.post.steady import steadiness
from rotor37_rom.studies.gnl_reference import SteadyCase, SteadyRun
from rotor37_rom.studies.speed_accuracy.gnl_steady import candidate_options, scene_gnl_steady

ROM = "rom r_c 25 global md 10 cap 120 h 4e-07"
CUB = "rom r_c 25 global md 10 cubature 0.0001 train 1200/1600 cap 120 h 4e-07"


def _run(speed, amplitude, wall, growth=0.0, r=104):
    case = SteadyCase(speed)
    t = np.linspace(0.0, case.duration, case.revolutions * 400 + 1)
    u = amplitude * (1 + growth * t / case.duration) * np.sin(4 * speed * t)
    return SteadyRun(t, u, steadiness(t, u, speed), wall, {"model": f"reduced r = {r}"}).to_json()


def _results(tmp_path, cubature_growth=0.0):
    store = {"machine": "test"}
    for w, amp in ((1280.0, 2e-4), (1450.0, 1e-4)):
        store[f"{w:g} rad/s mu 0 x heavy 8 rev"] = {
            "full h 2e-06 rho 0.8": _run(w, amp, 4000.0), "full h 1e-06 rho 0.8": _run(w, amp, 8000.0),
            ROM: _run(w, amp * (1.05 if w == 1280 else 0.97), 800.0),
            CUB: _run(w, amp * 1.02, 40.0, growth=cubature_growth if w == 1450 else 0.0),
            "pod r 55 cap 120 h 4e-07": _run(w, amp, 40.0, r=55)}
    store["1400 rad/s mu 0 x heavy 8 rev"] = {"full h 2e-06 rho 0.8": _run(1400.0, 5e-4, 4000.0, growth=0.5)}
    store["1280 rad/s mu 0.15 cone heavy 8 rev"] = {"full h 2e-06 rho 0.8": _run(1280.0, 3e-4, 4000.0),
                                                    ROM: _run(1280.0, 1e-4, 1.0)}
    path = tmp_path / "bench_gnl_steady.json"
    path.write_text(json.dumps(store))
    return path


def test_the_scene_compares_predictive_models_with_the_full_order(tmp_path):
    scene = scene_gnl_steady(_results(tmp_path))
    rows = {c["run"]: c for c in scene["candidates"]}
    assert set(rows) == {ROM, CUB}                                        # no POD, no other question's case
    assert rows[ROM]["error"] == pytest.approx(0.05, abs=1e-4)            # the largest over the speeds
    assert rows[ROM]["errors"]["1450"] == pytest.approx(-0.03, abs=1e-4)
    assert rows[CUB]["error"] == pytest.approx(0.02, abs=1e-4) and rows[CUB]["options"]["cubature"] == 1e-4
    assert rows[ROM]["cost"] == pytest.approx(100.0) and rows[CUB]["cost_ratio"] == pytest.approx(200.0)
    assert "(full h 1e-06 rho 0.8 s)" in scene["reference"]["options"]["model"]     # against the finest step
    assert "r = 104" in rows[ROM]["name"]
    assert "left out (a full order without reduced runs): 1400 rad/s" in scene["description"]
    assert set(rows[ROM]["errors"]) == {"1280", "1450"}


def test_a_model_not_steady_at_one_speed_has_no_error(tmp_path):
    rows = {c["run"]: c for c in scene_gnl_steady(_results(tmp_path, cubature_growth=0.5))["candidates"]}
    assert rows[CUB]["error"] == np.inf and rows[CUB]["errors"]["1450"] is None


def test_keys_name_their_options():
    assert candidate_options(CUB) == {"r_c": 25, "global_md": 10, "cubature": 1e-4}
    assert candidate_options("rom r_c 40 cap 120 h 4e-07") == {"r_c": 40, "global_md": 3}
    assert candidate_options("pod r 55 cap 120 h 4e-07") is None and candidate_options("full h 2e-06 rho 0.8") is None


def test_missing_damaged_or_empty_results_are_named(tmp_path):
    with pytest.raises(ValueError, match="bench_gnl_steady.py first"):
        scene_gnl_steady(tmp_path / "none.json")
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(ValueError, match="bad.json could not be read"):
        scene_gnl_steady(bad)
    with pytest.raises(ValueError, match="no full-order run of 'mu 0 x maps 8 rev'"):
        scene_gnl_steady(_results(tmp_path), question="mu 0 x maps 8 rev")
