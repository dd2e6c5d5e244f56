"""The model for a tolerance (issue #22): the chooser's rule on the shipped study file, the Pareto front, the docs
page generated from the same file, and the refusals."""
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from rotor37_rom.pareto import pareto_front
from rotor37_rom.studies.model_choice import STUDY_FILE, choose_model, load_study, scenes

ROOT = Path(__file__).resolve().parents[2]


def test_pareto_front_is_the_set_of_undominated_points():
    """Against the definition, point by point, on random clouds with ties and diverged (infinite) runs."""
    rng = np.random.default_rng(4)
    for _ in range(50):
        n = int(rng.integers(1, 30))
        cost = rng.integers(1, 8, n).astype(float)
        err = rng.integers(1, 8, n).astype(float)
        err[rng.random(n) < 0.1] = np.inf
        front = pareto_front(cost, err)
        for i in range(n):
            dominated = any(cost[j] <= cost[i] and err[j] <= err[i] and (cost[j] < cost[i] or err[j] < err[i])
                            for j in range(n) if np.isfinite(err[j]))
            assert front[i] == (np.isfinite(err[i]) and not dominated)


def _expected(candidate: dict, scene: dict) -> float:
    """The chooser's rule restated here, not imported: the largest of the study error, the held-out error (if run)
    and the scene's floor (if it states one)."""
    return max(candidate["error"], candidate.get("held_out_error") or 0.0, (scene.get("floor") or {}).get("error", 0.0))


def test_choices_of_the_shipped_study():
    """Every scene of the shipped file: at each tolerance the choice's expected error (the largest of the study's
    error, the held-out error and the scene's floor) meets it and no cheaper candidate's does; a candidate that missed
    on its held-out case is never chosen at a tolerance it missed; the chosen model at a looser tolerance never costs
    more."""
    study = load_study()
    assert study["schema"] == 1 and {"modes", "clearance", "map-linear"} <= set(scenes(study))
    for scene in scenes(study):
        cands = study["scenes"][scene]["candidates"]
        previous = np.inf
        for tol in (0.01, 0.05, 0.2):
            meeting = [c for c in cands if _expected(c, study["scenes"][scene]) <= tol]
            if not meeting:
                with pytest.raises(ValueError, match="tolerance"):
                    choose_model(scene, tol, study)
                continue
            choice = choose_model(scene, tol, study)
            assert choice.error <= tol
            assert choice.cost == min(c["cost"] for c in meeting)
            held = choice.held_out_error
            assert held is None or held <= tol
            assert choice.cost <= previous
            previous = choice.cost


def test_a_scene_floor_bounds_the_expected_error():
    """A scene's floor (the error below which its reference cannot tell models apart) is every candidate's least
    expected error: a model measured below it is chosen only at a tolerance at or above the floor. In the shipped
    file a floor is what its record says: the error of the candidate that is the reference's own model at the nearest
    lower cap, and for a stress scene the larger of that and how far the reference's perturbation moves the stress."""
    scene = dict(cost_unit="s", reference={}, candidates=[
        dict(name="cheap", options={}, cost=1.0, error=0.02, held_out_error=None),
        dict(name="dear", options={}, cost=5.0, error=0.10, held_out_error=None)])
    study = {"schema": 1, "scenes": {"s": scene}}
    assert choose_model("s", 0.05, study).name == "cheap"
    scene["floor"] = dict(error=0.08)
    with pytest.raises(ValueError, match="smallest expected error 0.08"):
        choose_model("s", 0.05, study)
    choice = choose_model("s", 0.09, study)
    assert (choice.name, choice.error, choice.study_error, choice.floor) == ("cheap", 0.08, 0.02, 0.08)

    study = load_study()
    floors = {name: data["floor"] for name, data in study["scenes"].items() if data.get("floor")}
    assert {"disk-map-linear", "disk-stress-linear", "disk-map-gnl", "disk-stress-gnl"} <= set(floors)
    for name, floor in floors.items():
        data = study["scenes"][name]
        ref = data["reference"]["options"]
        cap = floor.get("cap")
        if cap is not None:
            cand = next(c for c in data["candidates"] if c["name"] == cap["candidate"])
            assert cand["error"] == cap["error"] and cand["options"]["frequency_cap"] < ref["frequency_cap"]
            assert {k: v for k, v in cand["options"].items() if k != "frequency_cap"} == \
                {k: v for k, v in ref.items() if k != "frequency_cap"}
            between = [c for c in data["candidates"] if {k: v for k, v in c["options"].items() if k != "frequency_cap"}
                       == {k: v for k, v in ref.items() if k != "frequency_cap"}
                       and cap["cap_khz"] < c["options"]["frequency_cap"] < ref["frequency_cap"]]
            assert not between, "the floor is the nearest lower cap's"
        parts = [cap["error"] if cap else 0.0] + ([floor["perturbation"]] if "perturbation" in floor else [])
        assert floor["error"] == max(parts)


def test_held_out_checks_ran_for_three_scenes():
    """The acceptance's held-out check: in at least three scenes the models chosen at 1 %, 5 % and 20 % were run on
    cases not used to choose them (a held-out error is recorded on each chosen candidate)."""
    study = load_study()
    checked = 0
    for scene in scenes(study):
        data = study["scenes"][scene]
        by_name = {c["name"]: c for c in data["candidates"]}
        chosen = [c["name"] for c in data["choices"].values() if c["name"] is not None]
        if chosen and all(by_name[n].get("held_out_error") is not None for n in chosen):
            checked += 1
    assert checked >= 3


def test_held_out_maps_run_the_cubature_as_trained():
    """A cubature candidate's held-out map reuses the cubature trained on the study's speeds (none of them a held-out
    speed): retrained on runs at the held-out speeds it would be judged on its own training cases."""
    from rotor37_rom.studies.speed_accuracy.context import HELD_OUT_SPEEDS, MAP
    from rotor37_rom.studies.speed_accuracy.maps import held_out_options

    options = held_out_options({"r_c": 15, "cubature": 1e-4, "precision": "single"})
    start, stop, n = MAP["speeds"]
    study_speeds = np.linspace(start, stop, int(n))
    held_out = np.linspace(*HELD_OUT_SPEEDS[:2], int(HELD_OUT_SPEEDS[2]))
    train = np.asarray(options["cubature_speeds"])
    assert train.size == 6 and np.isin(train, study_speeds).all() and not np.isin(train, held_out).any()
    assert held_out_options({"r_c": 25, "frequency_cap": 60.0}) == {"r_c": 25, "frequency_cap": 60.0}


def test_docs_page_is_the_study_file():
    """docs/choosing-a-model.md's generated block is what the study (benchmarks/speed_accuracy.py, through
    ``speed_accuracy.docs``) renders from the shipped file."""
    from rotor37_rom.studies.speed_accuracy.docs import BEGIN, END, render_markdown

    text = (ROOT / "docs" / "choosing-a-model.md").read_text()
    block = text.split(BEGIN, 1)[1].split(END, 1)[0].strip()
    assert block == render_markdown(load_study(), ROOT / "docs" / "img").strip()


def test_study_options_are_the_library_configurations_fields():
    """The study file is keyed on the library's own configuration names: every option of every candidate and
    reference is a field of the configuration its scene measured (``study_file.SCENE_CONFIG``), and a choice's options
    map onto another configuration in one place (``ModelChoice.config_options``: ``global_md`` is
    ``ReductionConfig.global_md_modes``)."""
    import importlib

    from rotor37_rom.reduction.builder import ReductionConfig
    from rotor37_rom.studies.speed_accuracy.study_file import SCENE_CONFIG, config_options, option_names

    study = load_study()
    assert set(scenes(study)) <= set(SCENE_CONFIG)
    for scene in scenes(study):
        module, name = SCENE_CONFIG[scene]
        config = getattr(importlib.import_module(module), name)
        data = study["scenes"][scene]
        for options in [c["options"] for c in data["candidates"]] + [data["reference"].get("options", {})]:
            if "model" in options:               # a full-order model: no reduced configuration
                continue
            assert set(config_options(options, config)) <= option_names(config), scene
            if name == "ContactMapConfig":                   # the options make a configuration, on its parts
                made = config.from_options(**config_options(options, config)).options()
                assert all(made[k] == v for k, v in options.items()), scene
    choice = choose_model("clearance", 0.2, study, where=lambda c: "r_c" in c["options"])
    assert ReductionConfig(**choice.config_options(ReductionConfig)).global_md_modes == choice.options["global_md"]
    with pytest.raises(ValueError, match="model are not fields of ReductionConfig"):
        config_options({"model": "full-order linear"}, ReductionConfig)


def test_refusals(tmp_path):
    study = load_study()
    with pytest.raises(ValueError, match="scene must be one of"):
        choose_model("no-such-scene", 0.05, study)
    for bad in (0, 1.0, -0.1, float("nan"), "0.05"):
        with pytest.raises(ValueError, match=r"tolerance must be in \(0, 1\)"):
            choose_model(scenes(study)[0], bad, study)
    with pytest.raises(ValueError, match="not found"):
        load_study(tmp_path / "missing.json")
    (tmp_path / "old.json").write_text('{"schema": 0, "scenes": {}}')
    with pytest.raises(ValueError, match="schema"):
        load_study(tmp_path / "old.json")
    assert STUDY_FILE.is_file()


@pytest.mark.parametrize("demo, argv, message", [
    ("contact_map", ["--tolerance", "2"], "--tolerance must be in (0, 1)"),
    ("contact_map", ["--tolerance", "0.2", "--gnl", "off", "--frequency-cap", "60"],
     "--tolerance chooses --frequency-cap"),
    ("contact_map", ["--tolerance", "1e-9"], "--tolerance: tolerance 1e-09 is below every measured model"),
    ("contact_map", ["--tolerance", "1e-9", "--disk"], "--tolerance: tolerance 1e-09 is below every measured model "
                                                       "of scene 'disk-map-"),
    ("contact_map", ["--tolerance", "0.2", "--disk", "--gnl", "off", "--r-cyclic", "72"],
     "--tolerance chooses --r-cyclic"),
    ("contact_map", ["--tolerance", "0.2", "--disk", "--gnl", "off", "--mistuning", "0.05"],
     "--tolerance with --mistuning: the speed-accuracy study measured the tuned disk"),
    ("reduced_blade", ["--tolerance", "0"], "--tolerance must be in (0, 1)"),
    ("reduced_blade", ["--tolerance", "0.5", "--r-c", "25"], "--tolerance chooses --r-c"),
    ("reduced_blade", ["--tolerance", "0.5", "--r-md", "10", "--global-md", "0"],
     "--tolerance chooses --r-md, --global-md"),
    ("reduced_blade", ["--tolerance", "1e-9"], "--tolerance: tolerance 1e-09 is below every measured model"),
    ("reduced_blade", ["--tolerance", "0.5", "--preset", "coarse", "--r-c", "15"],
     "--tolerance chooses --preset, --r-c"),
])
def test_tolerance_errors(demo, argv, message):
    """contact_map.py and reduced_blade.py refuse a bad --tolerance in one line, exit status 2."""
    proc = subprocess.run([sys.executable, str(ROOT / "demos" / f"{demo}.py"), *argv], capture_output=True, text=True)
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr.count("\n") == 1 and message in proc.stderr, proc.stderr


def test_contact_map_takes_the_chosen_options():
    """--tolerance sets each setting's options from the study (the command's own configuration, no run)."""
    from rotor37_rom.studies import contact_map as cm

    study = load_study()
    settings = {"map-linear": False, "map-gnl": True}
    for tol in (0.01, 0.05, 0.2):
        chosen = {s: study["scenes"][s]["choices"][f"{tol:g}"]["name"] for s in settings}
        both = all(chosen.values())
        gnl = "both" if both else "off" if chosen["map-linear"] else "on" if chosen["map-gnl"] else None
        if gnl is None:
            with pytest.raises(ValueError, match="--tolerance: tolerance"):
                cm.ContactMapConfig.from_options(tolerance=tol, gnl="both")
            continue
        config = cm.ContactMapConfig.from_options(tolerance=tol, gnl=gnl)
        used = [s for s in settings if chosen[s]]
        for scene in used:
            choice = choose_model(scene, tol)
            assert choice.name == chosen[scene]
            setting = config.setting(settings[scene])
            assert all(setting.options()[k] == v for k, v in choice.options.items() if k != "r_c")
        assert config.modes[0] == max(choose_model(s, tol).options.get("r_c", 15) for s in used)


def test_contact_map_takes_the_disk_choice():
    """With --disk, --tolerance builds the disk model (r_c, r_md, r_cyclic) and sets the cap (and with GNL the force
    evaluation) of the choice of the scene 'disk-map-linear' (GNL off) or 'disk-map-gnl' (on), read from the study
    file."""
    from rotor37_rom.studies import contact_map as cm

    study = load_study()
    for gnl, name in ((False, "disk-map-linear"), (True, "disk-map-gnl")):
        setting = "on" if gnl else "off"
        scene = study["scenes"][name]
        for tol in (0.01, 0.05, 0.2):
            within = [c for c in scene["candidates"] if _expected(c, scene) <= tol]
            if not within:
                with pytest.raises(ValueError, match="--tolerance: tolerance"):
                    cm.ContactMapConfig.from_options(disk=True, gnl=setting, tolerance=tol)
                continue
            best = min(within, key=lambda c: c["cost"])
            config = cm.ContactMapConfig.from_options(disk=True, gnl=setting, tolerance=tol)
            assert config.choice(gnl).name == best["name"]
            opts = best["options"]
            assert config.modes == (opts["r_c"], opts["r_md"]) and config.interface_modes == opts["r_cyclic"]
            chosen = config.setting(gnl)
            assert all(chosen.options()[k] == v for k, v in opts.items() if k != "r_c")
            assert config.model_beyond_choice(gnl) == {}
    # GNL off and on in one run: one disk model serves both, the larger of the two choices in each option, and each
    # setting says where the model it runs on exceeds its choice
    both = cm.ContactMapConfig.from_options(disk=True, gnl="both", tolerance=0.2)
    chosen = {gnl: both.choice(gnl).options for gnl in (False, True)}
    built = {k: max(c[k] for c in chosen.values()) for k in ("r_c", "r_md", "r_cyclic")}
    assert both.modes == (built["r_c"], built["r_md"]) and both.interface_modes == built["r_cyclic"]
    for gnl, c in chosen.items():
        assert both.model_beyond_choice(gnl) == {k: v for k, v in built.items() if c[k] != v}


def test_reduced_blade_builds_the_chosen_model():
    """--tolerance builds only the study's cheapest reduced model of the clearance scene within it (one basis with
    its selected and global MDs), read from the study file; never the full-order linear candidate."""
    from rotor37_rom.studies import clearance_consumption as rb

    study = load_study()
    scene = study["scenes"]["clearance"]
    roms = [c for c in scene["candidates"] if "r_c" in c["options"]]
    for tol in (0.01, 0.05, 0.2, 0.5):
        within = [c for c in roms if _expected(c, scene) <= tol]
        if not within:
            with pytest.raises(ValueError, match="--tolerance: tolerance"):
                rb.ReducedBladeConfig(tolerance=tol)
            continue
        best = min(within, key=lambda c: c["cost"])
        config = rb.ReducedBladeConfig(tolerance=tol)
        assert config.choice.name == best["name"]
        (name, r_md, n_global), = config.variants()
        assert (config.r_c, r_md, n_global, config.criterion) == tuple(
            best["options"][k] for k in ("r_c", "r_md", "global_md", "criterion"))
        assert best["name"] in name and config.forces == "intrusive"             # the study's force evaluation


def test_disk_forced_scenes_score_the_indicator():
    """The disk's forced-response scenes (§3.3) judge a model by the largest of the four relative errors behind the
    performance indicator I, over the cases: the recorded error of every candidate is that maximum, and each case's I
    is the mean of max(0, 1 - e) over the same four errors (the indicator's definition,
    ``disk.indicators.performance_indicator``).
    The costs are the reduced runs' wall times summed over the cases, below the full order's."""
    study = load_study()
    for name in ("disk-forced-linear", "disk-forced-gnl"):
        data = study["scenes"][name]
        for c in data["candidates"]:
            finite = [case for case in c["by_case"] if case["errors"]]
            if len(finite) < len(c["by_case"]):                  # a run that failed: the candidate is refused
                assert c["error"] == float("inf")
                continue
            assert c["error"] == max(max(case["errors"].values()) for case in finite)
            assert c["cost"] == pytest.approx(sum(case["wall_s"] for case in finite), rel=1e-12)
            for case in finite:
                assert set(case["errors"]) == {"loaded node", "tip nodes", "field", "strain energy"}
                assert case["I"] == pytest.approx(np.mean([max(0.0, 1.0 - e) for e in case["errors"].values()]),
                                                  abs=1e-12)
        assert data["reference"]["cost"] == sum(case["wall_s"] for case in data["reference"]["cases"])


@pytest.mark.parametrize("argv, message", [
    (["--tolerance", "2"], "error: --tolerance must be in (0, 1)"),
    (["--tolerance", "1e-9"], "error: --tolerance: tolerance 1e-09 is below every measured model of scene "
                              "'disk-forced-linear'"),
    (["--tolerance", "1e-9", "--gnl-reference", "0:4000", "--patch", "3"],
     "below every measured model of scene 'disk-forced-gnl'"),
    (["--tolerance", "0.2", "--r-c", "5", "--r-md", "0"], "error: --tolerance chooses --r-c, --r-md"),
    (["--tolerance", "0.2", "--gnl-reference", "0:4000", "--patch", "3", "--load-correction", "off"],
     "error: --tolerance with --load-correction"),
    (["--tolerance", "0.2", "--gnl-reference", "0:4000"], "error: --tolerance with a GNL reference needs --patch 3"),
])
def test_forced_response_bench_tolerance_errors(tmp_path, argv, message):
    """bench_disk_forced.py --tolerance (scenes disk-forced-linear / disk-forced-gnl): a bad value or an option it
    chooses is one line on stderr, exit status 2, nothing written."""
    proc = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "bench_disk_forced.py"), *argv,
                           "--out", str(tmp_path / "out")], capture_output=True, text=True, cwd=tmp_path)
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr.count("\n") == 1 and message in proc.stderr, proc.stderr
    assert not (tmp_path / "out").exists()


def test_forced_response_bench_takes_the_chosen_model():
    """bench_disk_forced.py --tolerance runs the study's choice: the linear scene's model with no GNL reference unless
    one is asked, the GNL scene's where it is (on the scene's 3 mm patch); without --tolerance, its own defaults."""
    from rotor37_rom.studies import forced_response as bdf

    models = ("r_c", "r_md", "r_cyclic", "criteria", "face_shapes")

    def expected(scene, tol):
        opts = choose_model(scene, tol).options
        return opts["r_c"], [opts["r_md"]], opts["r_cyclic"], ["MI2b"], opts.get("face_shapes", 0)

    args = bdf.parse_args(["--tolerance", "0.05"])
    assert tuple(getattr(args, k) for k in models) == expected("disk-forced-linear", 0.05)
    assert args.gnl_reference == [] and args.choice.scene == "disk-forced-linear"
    args = bdf.parse_args([])
    assert tuple(getattr(args, k) for k in models) == (10, [0, 5, 10, 20], 144, ["MI2b"], 0)
    assert args.gnl_reference == ["0:4000"] and args.choice is None
    gnl = ["--cases", "0:4000", "--gnl-reference", "0:4000", "--patch", "3", "--tolerance"]
    for tol in (0.2, 0.5, 0.99):
        try:
            want = expected("disk-forced-gnl", tol)
        except ValueError:
            with pytest.raises(ValueError, match="--tolerance: tolerance .* scene 'disk-forced-gnl'"):
                bdf.parse_args(gnl + [str(tol)])
        else:
            assert tuple(getattr(bdf.parse_args(gnl + [str(tol)]), k) for k in models) == want
    with pytest.raises(ValueError, match="needs --patch 3"):
        bdf.parse_args(["--tolerance", "0.2", "--gnl-reference", "0:4000"])
    with pytest.raises(ValueError, match="measured the ci preset"):
        bdf.parse_args(["--tolerance", "0.2", "--preset", "coarse"])


def test_reference_model_is_the_yardstick():
    """The scene's reference (what a caller runs when no candidate meets its tolerance): its options as recorded,
    its error not measured."""
    from rotor37_rom.studies.model_choice import reference_model

    study = load_study()
    for scene in ("map-linear", "map-gnl"):
        ref = reference_model(scene, study)
        assert ref.options == study["scenes"][scene]["reference"]["options"] and np.isnan(ref.error)
        assert "reference" in ref.describe()
        assert choose_model(scene, 1e-9, study, fallback=True) == ref           # what the report runs then
    forced = reference_model("disk-forced-linear", study)          # the full order: its cost is its own runs'
    assert forced.cost == study["scenes"]["disk-forced-linear"]["reference"]["cost"] > 0
    with pytest.raises(ValueError, match="scene must be one of"):
        reference_model("no-such-scene", study)


def test_run_study_on_a_toy_scene(tmp_path, monkeypatch):
    """One run of the study through the registry on a toy scene (no model built): the scene's record and its
    choices in the study file, the other scenes kept, the run's note of what it computed, its chart, and the docs
    block rewritten between its markers with the text around them kept."""
    from rotor37_rom.studies.speed_accuracy import scenes as registry
    from rotor37_rom.studies.speed_accuracy.context import PREFIX, StudyContext
    from rotor37_rom.studies.speed_accuracy.docs import BEGIN, END, render_markdown
    from rotor37_rom.studies.speed_accuracy.study_file import read_study, write_study

    def toy(ctx, study, t0):
        study["scenes"]["toy"] = dict(description="a toy scene", cost_unit="s", reference={"options": {"r_c": 40}},
                                      held_out_case=None, candidates=[
                                          dict(name="cheap", options={"r_c": 5}, cost=1.0, error=0.1,
                                               held_out_error=None),
                                          dict(name="dear", options={"r_c": 15}, cost=3.0, error=0.02,
                                               held_out_error=0.03)])
        ctx.fresh.append("toy 0 s")

    monkeypatch.setitem(registry.REGISTRY, "toy", registry.Scene("blade", toy))
    ctx = StudyContext(work=tmp_path / "work", img=tmp_path / "img", doc=tmp_path / "page.md",
                       study_file=tmp_path / "study.json")
    ctx.img.mkdir()
    ctx.doc.write_text(f"# Page\n\nbefore\n{BEGIN}\nold\n{END}\nafter\n")
    shipped = load_study()
    write_study(ctx.study_file, {**shipped, "scenes": {"modes": shipped["scenes"]["modes"]}})
    study = registry.run_study(ctx, ["toy"])
    assert read_study(ctx.study_file) == study and set(study["scenes"]) == {"modes", "toy"}
    choices = study["scenes"]["toy"]["choices"]
    assert choices["0.01"]["name"] is None and choices["0.05"]["name"] == "dear" and choices["0.2"]["name"] == "cheap"
    assert study["runs"][-1]["scenes"] == ["toy"] and study["runs"][-1]["note"] == PREFIX + "toy 0 s"
    assert (ctx.img / "speed_accuracy_toy.png").is_file() and ctx.work.is_dir()
    text = ctx.doc.read_text()
    assert text.startswith("# Page\n\nbefore\n") and text.endswith(f"{END}\nafter\n")
    assert text.split(BEGIN, 1)[1].split(END, 1)[0].strip() == render_markdown(study, ctx.img).strip()
    assert registry.expand_scenes(["modes", "disk", "modes"]) == ("modes",) + registry.DISK_SCENES


def test_a_choice_says_what_its_error_is_measured_against():
    """#86: a GNL scene's choice names its reference, and says when that is a reduced model, not the full order."""
    study = load_study()
    gnl = choose_model("map-gnl", 0.5, study)
    assert "error against the reduced model" in gnl.describe() and "not the full order" in gnl.describe()
    linear = choose_model("map-linear", 0.5, study)
    assert "error against the reduced model" in linear.describe() and "not the full order" not in linear.describe()
    forced = choose_model("disk-forced-gnl", 0.99, study)
    assert forced.reference.startswith("full order")
