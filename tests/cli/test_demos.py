"""Demos as library calls (#18, #69): demos/contact_map.py's work is run_contact_map(ContactMapConfig) ->
ContactMapResult of rotor37_rom.studies.contact_map, which a test calls in-process; its command line is that
configuration, and a bad input is one line on stderr naming the option, with exit status 2."""
import dataclasses
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from rotor37_rom.studies import blade_report, contact_map, sweep
from rotor37_rom.model.reduced import save_reduced_model

ROOT = Path(__file__).resolve().parents[2]




def test_contact_map_perturbation_keeps_the_step(ci_rom, tmp_path):
    """--perturbation EPS: the map's scheme runs the model with K q + g(q) scaled by 1 + EPS (perturbed_model) at the
    unperturbed scheme's step, with its damping and cap, GNL off and on and with a cap; the force to round-off
    (1e-12, as in test_perturbed_model_scales_the_internal_force); the highest frequency EPS / 2 higher without a
    cap, the cap's with it. At the stability limit (--safety 1) the stiffer model is refused."""
    path = save_reduced_model(ci_rom, tmp_path / "rom.npz")
    for gnl, cap in ((False, None), (True, None), (False, 60.0)):
        schemes = [contact_map.time_scheme(contact_map.ContactMapConfig.from_options(
                       model=path, perturbation=eps, quiet=True, frequency_cap=cap, out=tmp_path), ci_rom, gnl, None)
                   for eps in (0.0, 1e-4)]
        plain, pert = schemes
        assert pert.h == plain.h and pert.nonlinear == plain.nonlinear == gnl
        assert pert.frequency_cap == plain.frequency_cap
        assert np.array_equal(pert.C, plain.C)
        assert np.array_equal(pert.model.K, (1 + 1e-4) * ci_rom.K) and np.array_equal(pert.K, pert.model.K)
        # the highest frequency: sqrt(1 + 1e-4) higher without the cap, the cap's with it (its modes stay at the cap);
        # the largest eigenvalue's relative round-off is a few u
        ratio = np.sqrt(1 + 1e-4) if cap is None else 1.0
        assert pert.h_crit == pytest.approx(plain.h_crit / ratio, rel=1e-10)
        assert pert.model.metadata["perturbation"] == 1e-4 and "perturbation" not in plain.model.metadata
        if gnl:
            Q = np.full((ci_rom.r, 1), 1e-4)
            g, g_pert = plain.model.nonlinear_force(Q), pert.model.nonlinear_force(Q)
            assert np.abs(g_pert - (1 + 1e-4) * g).max() <= 1e-12 * np.abs(g).max()
    at_limit = contact_map.ContactMapConfig.from_options(model=path, perturbation=1e-4, safety=1.0, out=tmp_path)
    with pytest.raises(ValueError, match="stability limit"):         # at the limit, a stiffer model cannot run
        contact_map.time_scheme(at_limit, ci_rom, False, None)


def test_time_scheme_takes_a_record_step(ci_rom, tmp_path):
    """time_scheme(..., h=H) runs at H (a record's own step, as the stress carry-ons use) with the setting's forces,
    cap and perturbation, the setting itself unchanged (its step is part of a disk cubature's training key); H = 0
    is a step, refused as one, not "no step"."""
    path = save_reduced_model(ci_rom, tmp_path / "rom.npz")
    for cap in (None, 60.0):
        config = contact_map.ContactMapConfig.from_options(model=path, perturbation=1e-4, quiet=True, frequency_cap=cap,
                                              out=tmp_path)
        plain = contact_map.time_scheme(config, ci_rom, cap is None, None)
        half = contact_map.time_scheme(config, ci_rom, cap is None, None, h=plain.h / 2)
        assert half.h == plain.h / 2 and config.scheme.h is None
        assert half.frequency_cap == plain.frequency_cap and half.nonlinear == plain.nonlinear
        assert np.array_equal(half.model.K, plain.model.K) and half.model.metadata["perturbation"] == 1e-4
    with pytest.raises(ValueError, match="time step h must be > 0"):
        contact_map.time_scheme(config, ci_rom, False, None, h=0.0)


def test_contact_map_runs_in_process(ci_rom, tmp_path):
    """run_contact_map on 2 speeds x 0.3 revolutions (GNL off): the result object holds what summary.json says, its
    NFRC is the map of the sweep folder it wrote, and it lists the files it wrote."""
    out = tmp_path / "map"
    config = contact_map.ContactMapConfig.from_options(model=save_reduced_model(ci_rom, tmp_path / "rom.npz"),
                                          speeds=(1400, 1450, 2), revolutions=0.3, gnl="off", quiet=True, out=out)
    result = contact_map.run_contact_map(config)
    summary = json.loads((out / "summary.json").read_text())
    assert json.loads(json.dumps(result.summary, default=float)) == summary
    assert list(result.runs) == list(summary["runs"]) == ["no GNL"]
    run, written = result.runs["no GNL"], summary["runs"]["no GNL"]
    assert run.speeds.tolist() == written["speeds"] == [1400.0, 1450.0]
    assert run.nfrc.tolist() == written["nfrc"] and np.all(run.nfrc > 0)
    assert not run.diverged.any() and written["diverged"] == [] and run.retried == {} and run.branches == {}
    assert run.h == written["h"] and run.peak_speed == written["peak_speed"]
    assert result.linear_resonance == summary["linear_resonance"] == result.eigenfrequencies[0] / 4
    assert run.folder.parent == out / "sweeps"
    np.testing.assert_array_equal(run.nfrc, sweep.interaction_map(sweep.load_sweep(run.folder)).nfrc)
    assert sorted(p.name for p in result.files) == ["interaction_map_linear.png", "nfrc.png", "summary.json",
                                                    "time_history_linear.png"]
    assert all(p.parent == out and p.is_file() for p in result.files)


def test_contact_map_rerun_keeps_the_wall_time(tmp_path):
    """A call that finds every speed of a setting done (wall < 1 s, no rate) keeps the wall time and rate of the call
    that ran them; a run at another step, or one that ran, reports its own."""
    previous = tmp_path / "summary.json"
    head = {"r": 55, "speeds": [1620.0, 2000.0, 20], "revolutions": 200.0}
    curve = {"speeds": [1620.0, 2000.0], "nfrc": [1e-4, 2e-4]}          # what write_summary reads of each run
    previous.write_text(json.dumps(head | {"runs": {"GNL": {"h": 4e-7, "wall_s": 686.0, "rev_per_s": 5.8, **curve},
                                                    "no GNL": {"h": 1e-6, "wall_s": 100.0, "rev_per_s": 40.0,
                                                               **curve}}}))
    summary = head | {"runs": {"GNL": {"h": 4e-7, "wall_s": 0.08, "rev_per_s": None, **curve},
                               "no GNL": {"h": 5e-7, "wall_s": 0.05, "rev_per_s": None, **curve}}}
    contact_map.merge_earlier_runs(summary, previous)
    assert summary["runs"]["GNL"] == {"h": 4e-7, "wall_s": 686.0, "rev_per_s": 5.8, **curve}
    assert summary["runs"]["no GNL"] == {"h": 5e-7, "wall_s": 0.05, "rev_per_s": None, **curve}     # another step
    summary = head | {"runs": {"GNL": {"h": 4e-7, "wall_s": 300.0, "rev_per_s": 13.3, **curve}}}
    contact_map.merge_earlier_runs(summary, previous)
    assert summary["runs"]["GNL"]["wall_s"] == 300.0 and summary["runs"]["no GNL"]["wall_s"] == 100.0


def test_contact_map_command_line_is_the_config(tmp_path):
    """The options parse into the config a Python caller writes (numbers as floats: the same cache keys)."""
    argv = ["--model", str(tmp_path / "rom.npz"), "--speeds", "1400", "1450", "2", "--revolutions", "0.3", "--gnl",
            "off", "--mu", "0", "--quiet", "--out", str(tmp_path)]
    parsed = contact_map.ContactMapConfig.from_options(**contact_map.parse_options(argv))
    assert parsed == contact_map.ContactMapConfig.from_options(model=tmp_path / "rom.npz", speeds=(1400, 1450, 2),
                                                               revolutions=0.3, gnl="off", mu=0, quiet=True,
                                                               out=tmp_path)
    assert contact_map.ContactMapConfig.from_options(**contact_map.parse_options([])) \
        == contact_map.ContactMapConfig()
    argv = ["--cubature", "1e-4", "--cubature-speeds", "1500", "1300"]
    assert contact_map.ContactMapConfig.from_options(**contact_map.parse_options(argv)) \
        == contact_map.ContactMapConfig.from_options(cubature=1e-4, cubature_speeds=(1300, 1500, 1300))


def test_contact_map_config_composes_the_library_objects(tmp_path):
    """ContactMapConfig is made of the library's own objects (#69): its flat options land on a Casing and a SweepSpec
    (the ones a sweep runs: the same cache keys), the model to build and the scheme; the options come back out, and a
    configuration written with the objects equals one written with the options."""
    from rotor37_rom.dynamics.casing import Casing
    from rotor37_rom.studies.sweep import SweepSpec

    options = dict(model=tmp_path / "rom.npz", mu=0.1, hb=0.7e-3, direction="cone", revolutions=3, batch=4,
                   frequency_cap=120, continuation=5, steady_window=1, speeds=(1400, 1450, 2))
    config = contact_map.ContactMapConfig.from_options(**options)
    casing = Casing(mu=0.1, h_b=0.7e-3, direction="cone")
    assert config.sweep == SweepSpec(revolutions=3.0, casing=casing, batch_size=4)
    assert config == contact_map.ContactMapConfig(
        rom=contact_map.MapModel(path=tmp_path / "rom.npz"), scheme=contact_map.MapScheme(frequency_cap=120.0),
        sweep=SweepSpec(revolutions=3, casing=casing, batch_size=4),
        continuation=contact_map.MapContinuation(step=5), speeds=(1400, 1450, 2))
    assert all(config.options()[k] == v for k, v in options.items())
    assert type(config.sweep.revolutions) is float and type(config.sweep.casing.mu) is float    # the cache keys'
    changed = config.with_options(mu=0.2)
    assert changed.sweep.casing == dataclasses.replace(casing, mu=0.2) and changed.rom == config.rom
    with pytest.raises(TypeError, match="no option frobnicate"):
        contact_map.ContactMapConfig.from_options(frobnicate=1)
    with pytest.raises(TypeError, match="sweep must be a SweepSpec"):
        contact_map.ContactMapConfig(sweep=casing)


@pytest.mark.parametrize("fields, flag", [
    ({"preset": "huge"}, "--preset"), ({"speeds": (1400, 1450, 2.5)}, "--speeds"),
    ({"revolutions": 0}, "--revolutions"),
    ({"gnl": "maybe"}, "--gnl"), ({"c0": 0}, "--c0"), ({"hb": -1e-3}, "--hb"), ({"direction": "z"}, "--direction"),
    ({"safety": 1.5}, "--safety"), ({"h": -1e-7}, "--h"), ({"batch": 0}, "--batch"), ({"r_c": 0}, "--r-c"),
    ({"continuation": -5}, "--continuation"), ({"precision": "half"}, "--precision"),
    ({"disk": True, "mistuning": -0.01}, "--mistuning"), ({"disk": True, "mistuning": 1.0}, "--mistuning"),
    ({"mistuning": 0.02}, "--mistuning"), ({"disk": True, "sector": 36}, "--sector"), ({"sector": 1}, "--sector"),
    ({"disk": True, "sector": -1}, "--sector"), ({"disk": True, "r_cyclic": 0}, "--r-cyclic"),
    ({"disk": True, "cubature": 1.0}, "--cubature"), ({"stress": True}, "--stress"),
    ({"cubature_speeds": (1300.0,)}, "--cubature-speeds"),
    ({"cubature": 1e-4, "cubature_speeds": ()}, "--cubature-speeds"),
    ({"cubature": 1e-4, "cubature_speeds": (1300.0, -1.0)}, "--cubature-speeds"),
    ({"cubature": 1e-4, "cubature_speeds": 1300.0}, "--cubature-speeds"),
    ({"cubature": 1e-4, "cubature_speeds": (1300.0, float("inf"))}, "--cubature-speeds"),
    ({"capped_training": True, "frequency_cap": 120.0}, "--capped-training"),
    ({"capped_training": True, "cubature": 1e-4}, "--capped-training"),
    ({"capped_training": True, "tolerance": 0.05}, "--capped-training"),
    ({"periodic": -0.1}, "--periodic"), ({"periodic": 0.05, "disk": True}, "--periodic")])
def test_contact_map_config_names_the_option(fields, flag):
    with pytest.raises(ValueError, match=f"^{flag}[ :]"):
        contact_map.ContactMapConfig.from_options(**fields)


def test_a_saved_disks_sector_range_is_its_own():
    """A saved model's N is known once it is read: --sector 20 passes the check made before (36 at most) and is
    refused, in one line naming the range, by a 12-sector disk's model."""
    import types

    from rotor37_rom.model.nodes import NodeMap

    n = 12
    nodes = NodeMap(names=("LE", "TE") * n, sector=np.repeat(np.arange(n), 2), coordinates=np.zeros((2 * n, 3)),
                    q_index=np.arange(6 * n).reshape(-1, 3), sector_angle=2 * np.pi / n)
    config = contact_map.ContactMapConfig.from_options(disk=True, sector=20)
    with pytest.raises(ValueError, match=r"^--sector must be in \[0, 11\] \(the sectors of the model read\), got 20$"):
        config.sweep_spec(types.SimpleNamespace(nodes=nodes))
    assert contact_map.ContactMapConfig.from_options(disk=True, sector=11).sweep_spec(
        types.SimpleNamespace(nodes=nodes)).monitor[-1] == nodes.row("TE", 11)


@pytest.mark.parametrize("args, flag", [
    (["--preset", "huge"], "--preset"), (["--model", "{text}"], "--model"), (["--revolutions", "-1"], "--revolutions"),
    (["--speeds", "1600", "1200", "5"], "--speeds"), (["--mu", "-0.1"], "--mu")])
def test_contact_map_bad_input_is_one_line(tmp_path, args, flag):
    """A bad option or a file that is not a reduced model: one line naming the option, exit status 2, nothing
    written."""
    text = tmp_path / "notes.txt"
    text.write_text("not a reduced model\n")
    out = tmp_path / "out"
    cmd = [sys.executable, str(ROOT / "demos" / "contact_map.py"), *[a.format(text=text) for a in args], "--quiet",
           "--out", str(out)]
    run = subprocess.run(cmd, env=dict(os.environ, MPLBACKEND="Agg"), capture_output=True, text=True, timeout=120)
    assert run.returncode == 2
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: {flag}") and "Traceback" not in run.stderr, run.stderr
    assert not out.exists()


def test_report_passes_the_contact_normal_to_both_maps():
    """The report's --direction reaches both maps' casing (the cone normal keeps the paper's mu = 0.15 bounded), and a
    normal it does not know is refused naming the option, before any work."""
    report = blade_report
    config = report.ReportConfig(direction="cone", mu=0.15)
    assert [c.sweep.casing.direction for c in config.map_configs] == ["cone", "cone"]
    assert [c.sweep.casing.mu for c in config.map_configs] == [0.15, 0.15]
    assert report.onset_text(None) == report.onset_text(float("inf")) == "never"
    with pytest.raises(ValueError, match="^--direction: "):
        report.ReportConfig(direction="z")
