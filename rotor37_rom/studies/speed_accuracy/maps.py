"""The interaction-map runs the map scenes share: one map of a scene's setup (``run_map``, cached under the study's
work folder by its name, speeds and setting), the blade's models by r_c (``model_file``), the speeds a cubature is
trained at, and the held-out loop that runs the chosen models until a choice holds."""
from __future__ import annotations

import dataclasses
import functools
import json
import time
from pathlib import Path

import numpy as np

from rotor37_rom.npz import load_json, save_json
from rotor37_rom.studies.speed_accuracy.context import MAP, StudyContext
from rotor37_rom.reporting import say

__all__ = ["MapRun", "model_file", "run_map", "study_training_speeds", "held_out_options", "held_out_choices",
           "RETRIES", "MODEL_OPTIONS"]

@dataclasses.dataclass
class MapRun:
    """One map of a scene as the scenes judge it: node LE's NFRC over the speeds, the speeds that blew up, every
    speed's record, the map's and its sweep's wall times, the simulation-steps run and the step."""

    nfrc: np.ndarray
    speeds: np.ndarray
    diverged: np.ndarray
    records: list
    wall: float
    sweep_wall: float
    sim_steps: float
    h: float
    config: object = None         # the map's ContactMapConfig
    record_h: list = dataclasses.field(default_factory=list)     # the step each record ran at (retries: smaller)


@functools.lru_cache(maxsize=None)
def model_file(ctx: StudyContext, r_c: int) -> Path:
    """The ci blade's r_c model (24 tip DOFs + r_c modes + the 6 MDs of 1B/1T/2B), exact tensors, built once (checked
    once per process against the builder's cache)."""
    from rotor37_rom.model.reduced import load_reduced_model, save_reduced_model
    from rotor37_rom.studies import contact_map as cm

    path = ctx.work / "models" / f"rom_rc{r_c}.npz"
    # built through the builder's cache (keyed by the reduction's parameters): a file saved by an earlier builder is
    # replaced, and run_map then sees its maps ran another model
    model = cm.build_model(cm.ContactMapConfig.from_options(**{**MAP, "r_c": r_c, "out": ctx.work / "models"}))
    if not path.is_file() or load_reduced_model(path).key != model.key:
        save_reduced_model(model, path)
    return path


RETRIES = ", retries"


MODEL_OPTIONS = ("r_c", "r_md", "r_cyclic")     # a candidate's options that make its model, not its scheme


def run_map(ctx: StudyContext, name: str, gnl: bool, options: dict, speeds=MAP["speeds"],
            model_path: Path | None = None, setup: dict = MAP, prefix: str = "") -> MapRun:
    """One map of the scene (``run_contact_map`` of ``rotor37_rom.studies.contact_map`` with ``setup``, MAP or
    DISK_MAP), cached in <ctx.work>/<prefix><name> (results/speed_accuracy). The model is ``model_path`` (default:
    the blade's of ``options['r_c']``). A candidate '<base>, retries' is its base candidate's map with the speeds
    that blew up run again at a smaller step: it runs in the base's folder (the base's sweep is reused, only the
    retries run), and its cost is the base map's plus the retries'."""
    from rotor37_rom.model.reduced import saved_model_key
    from rotor37_rom.studies import contact_map as cm
    from rotor37_rom.studies.sweep import load_sweep

    opts = {k: v for k, v in options.items() if k not in MODEL_OPTIONS}
    model_path = model_path or model_file(ctx, options.get("r_c", 15))
    base = None
    if opts.get("retry_diverged"):
        if not name.endswith(RETRIES):
            raise ValueError(f"a candidate with retry_diverged is named '<base>{RETRIES}', got {name!r}")
        base = run_map(ctx, name.removesuffix(RETRIES), gnl,
                       {k: v for k, v in options.items() if k != "retry_diverged"}, speeds, model_path, setup, prefix)
        name = name.removesuffix(RETRIES)
    tag = f"{prefix}{'gnl' if gnl else 'linear'}_{name}_{int(speeds[0])}_{int(speeds[1])}_{int(speeds[2])}"
    tag = tag.replace(" ", "_")
    out = ctx.work / tag
    done = out / ("study_run.json" if base is None else f"study_run_retries{opts['retry_diverged']}.json")
    config = cm.ContactMapConfig.from_options(**{**setup, "speeds": speeds, "model": model_path,
                                                 "gnl": "on" if gnl else "off", "out": out, **opts})
    setting = json.dumps([str(model_path), opts] + ([] if setup == MAP else [setup]), sort_keys=True, default=str)
    key = saved_model_key(model_path)
    # the files read back, checked before any work: a damaged one is moved aside with a warning and the map run again
    # (its sweeps resume: only what the damaged files held is computed again)
    info = load_json(done, _check_run, "the map is run again") or {}
    specs = _sweep_specs(out / "sweeps", "the map is run again (its sweep writes a new one)")
    # the sweeps read below: the map's; with retries every sweep of the folder with results (told apart by their specs)
    sweeps = sorted((out / "sweeps").iterdir()) if (out / "sweeps").is_dir() else []
    read = [p for p in sweeps if any(p.glob("omega_*.npz"))] if base is not None else \
        [Path(info["folder"])] if "folder" in info else []
    # stale: another setting, or the model file rewritten since (another builder), or the spec of a sweep read below
    # lost. The map records the key of the file it was given: its sweep's spec holds the key of the model the map
    # derived from it (a cubature, a perturbation)
    if info.get("setting") != setting or info.get("model_file_key") != key or any(p not in specs for p in read):
        shared = ctx.work / "cubature_cache"          # one cubature training per model and casing, shared by candidates
        shared.mkdir(parents=True, exist_ok=True)
        out.mkdir(parents=True, exist_ok=True)
        if not (out / "cache").exists():
            (out / "cache").symlink_to(shared, target_is_directory=True)
        t0 = time.perf_counter()
        result = cm.run_contact_map(config)
        wall = time.perf_counter() - t0
        ctx.fresh.append(f"{tag}{RETRIES if base else ''} {wall:.0f} s")
        run = next(iter(result.runs.values()))
        sweep_wall = run.wall_s if base is None else base.sweep_wall + run.wall_s
        wall = wall if base is None else base.wall + wall
        info = {"wall": wall, "sweep_wall": sweep_wall, "h": run.h, "folder": str(run.folder), "setting": setting,
                "model_file_key": key}
        save_json(done, info)
    grid = config.speed_grid
    # each speed's record: the map's, or the bounded one of its retries at a smaller step (their own sweep folders)
    records = {}
    specs = _sweep_specs(out / "sweeps", "its sweep is not read")
    main = specs[Path(info["folder"])]
    retries = [] if base is None else sorted(      # the base's retries: its model, a smaller step
        p for p, spec in specs.items() if spec["model"] == main["model"] and spec["h"] < main["h"])
    for folder in [Path(info["folder"])] + retries:
        h = specs[folder]["h"]
        for r in load_sweep(folder):
            w = float(r["omega"])
            if np.isclose(w, grid).any() and (w not in records or (int(records[w][0]["diverged_step"]) >= 0
                                                                    and int(r["diverged_step"]) < 0)):
                records[w] = (r, h)
    record_h = [records[w][1] for w in sorted(records)]
    records = [records[w][0] for w in sorted(records)]
    from rotor37_rom.studies.sweep import interaction_map

    imap = interaction_map(records, config.node)
    steps = sum(config.sweep.revolutions * 2 * np.pi / float(r["omega"]) / h for r, h in zip(records, record_h))
    say(f"map {tag}: h = {info['h']:.3g} s, sweep {info['sweep_wall']:.1f} s "
          f"({1e6 * info['sweep_wall'] / steps:.1f} us/sim-step), diverged {int(imap.diverged.sum())}")
    return MapRun(imap.nfrc, imap.speeds, imap.diverged, records, info["wall"], info["sweep_wall"], steps, info["h"],
                  config, record_h)


def _check_run(info) -> None:
    """ValueError unless ``info`` (a map's study_run.json, read) is the object ``run_map`` writes."""
    if not isinstance(info, dict) or not {"wall", "sweep_wall", "h", "folder", "setting"} <= info.keys():
        raise ValueError("not the object of a map's run (wall, sweep_wall, h, folder, setting)")


def _sweep_specs(sweeps: Path, then: str) -> dict[Path, dict]:
    """{sweep folder: its spec} of the map's sweeps under ``sweeps`` whose spec.json reads (``sweep.read_spec``: a
    damaged one is moved aside with a warning ending in ``then``, what is done instead)."""
    from rotor37_rom.studies.sweep import read_spec

    specs = {}
    for folder in sorted(sweeps.iterdir()) if sweeps.is_dir() else []:
        spec = read_spec(folder, then) if folder.is_dir() else None
        if spec is not None:
            specs[folder] = spec
    return specs


def study_training_speeds(setup: dict = MAP) -> tuple[float, ...]:
    """The speeds a cubature of a map scene is trained at (those of the study's that contact_map picks)."""
    from rotor37_rom.dynamics.explicit import training_speeds
    from rotor37_rom.studies.contact_config import ContactMapConfig

    return tuple(training_speeds(ContactMapConfig.from_options(**setup).speed_grid).tolist())


def held_out_options(options: dict, setup: dict = MAP) -> dict:
    """A candidate's options on the held-out speeds: a cubature stays the one trained on the study's speeds of the
    scene's ``setup`` (the model chosen is run, not one retrained on runs at the held-out speeds)."""
    if options.get("cubature") is None:
        return options
    return {**options, "cubature_speeds": study_training_speeds(setup)}


def held_out_choices(scene: dict, tolerances, error_of) -> None:
    """For each tolerance, the chosen model's error on the held-out case (``error_of(name, options)``), recorded on
    its candidate; a miss passes the choice to the next cheapest, which is run in turn, until one holds."""
    from rotor37_rom.studies.model_choice import choose_model

    study = {"schema": 1, "scenes": {"s": scene}}
    by_name = {c["name"]: c for c in scene["candidates"]}
    for tol in tolerances:
        for _ in range(len(by_name)):
            try:
                choice = choose_model("s", tol, study)
            except ValueError:
                break
            cand = by_name[choice.name]
            if cand["held_out_error"] is not None:
                break
            cand["held_out_error"] = error_of(choice.name, cand["options"])
            say(f"held out at {tol:g}: {choice.name}: {cand['held_out_error']:.3g}")
            if cand["held_out_error"] <= tol:
                break
