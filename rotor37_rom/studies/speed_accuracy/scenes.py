"""The registry of the study's scenes and one run of the study: each scene's runner stores its records in the study
file's dict and notes what it computed rather than read from the work folder; ``run_study`` runs the scenes asked,
writes the study file after each, then the charts and the generated block of docs/choosing-a-model.md."""
from __future__ import annotations

import dataclasses
import functools
import time
from typing import Callable, Iterable

from rotor37_rom.machine import machine_description
from rotor37_rom.studies.speed_accuracy.blade_maps import held_out_map, scene_map
from rotor37_rom.studies.speed_accuracy.blade_statics import scene_clearance, scene_modes, scene_rotating_modes
from rotor37_rom.studies.speed_accuracy.blade_stress import scene_stability, scene_stress
from rotor37_rom.studies.speed_accuracy.charts import write_charts
from rotor37_rom.studies.speed_accuracy.context import COMMAND, PREFIX, TOLERANCES, StudyContext
from rotor37_rom.studies.speed_accuracy.cost import scene_cost_r, scene_paper_speedup
from rotor37_rom.studies.speed_accuracy.disk_forced import scene_disk_forced
from rotor37_rom.studies.speed_accuracy.disk_maps import scene_disk_map
from rotor37_rom.studies.speed_accuracy.disk_modes import scene_disk_modes
from rotor37_rom.studies.speed_accuracy.disk_stress import scene_disk_stress
from rotor37_rom.studies.speed_accuracy.docs import write_docs
from rotor37_rom.studies.speed_accuracy.gnl_steady import scene_gnl_steady
from rotor37_rom.studies.speed_accuracy.study_file import SCHEMA, StudyRecord, load_or_new, write_study
from rotor37_rom.reporting import say

__all__ = ["Scene", "REGISTRY", "SCENES", "DISK_SCENES", "REFERENCE_SCENES", "GROUPS", "expand_scenes", "record_choices", "run_study"]


@dataclasses.dataclass(frozen=True)
class Scene:
    """A scene of the command line: ``family`` 'blade' (in 'all'), 'disk' (in 'disk', the bladed disk's: not in
    'all', the single-blade study's hour) or 'reference' (by name: read from a benchmark's full-order runs); ``run(ctx, study, t0)`` stores its records in ``study`` (``t0``: when the
    scene started, for its note)."""

    family: str
    run: Callable[[StudyContext, StudyRecord, float], None]


def _modes(ctx: StudyContext, study: StudyRecord, t0: float) -> None:
    study["scenes"]["modes"] = scene_modes()


def _clearance(ctx: StudyContext, study: StudyRecord, t0: float) -> None:
    study["scenes"]["clearance"] = scene_clearance()


def _rotating_modes(ctx: StudyContext, study: StudyRecord, t0: float) -> None:
    study["scenes"]["rotating-modes"] = scene_rotating_modes()
    ctx.fresh.append(f"scene rotating-modes {time.perf_counter() - t0:.0f} s")


def _map(gnl: bool, ctx: StudyContext, study: StudyRecord, t0: float) -> None:
    """A map scene, its held-out maps, and the history and stress scenes of the same runs."""
    name = "map-gnl" if gnl else "map-linear"
    maps, history = scene_map(ctx, gnl)
    held_out_map(ctx, maps, gnl)
    study["scenes"][name], study["scenes"][name.replace("map", "history")] = maps, history
    study["scenes"][name.replace("map", "stress")] = scene_stress(ctx, gnl, maps)


def _gnl_steady(ctx: StudyContext, study: StudyRecord, t0: float) -> None:
    """Read from the steady-state benchmark's results (results/bench_gnl_steady.json): nothing computed here."""
    study["scenes"]["gnl-steady"] = scene_gnl_steady(ctx.work.parent / "bench_gnl_steady.json")


def _stability(ctx: StudyContext, study: StudyRecord, t0: float) -> None:
    study["stability"] = scene_stability(ctx)


def _paper_speedup(ctx: StudyContext, study: StudyRecord, t0: float) -> None:
    study["paper_speedup"] = scene_paper_speedup(ctx, study)


def _cost_r(ctx: StudyContext, study: StudyRecord, t0: float) -> None:
    study["cost_r"] = scene_cost_r(ctx)
    ctx.fresh.append(f"scene cost-r {time.perf_counter() - t0:.0f} s")


def _disk_modes(ctx: StudyContext, study: StudyRecord, t0: float) -> None:
    study["scenes"]["disk-modes"] = scene_disk_modes(ctx)
    ctx.fresh.append(f"scene disk-modes {time.perf_counter() - t0:.0f} s")


def _disk_map(gnl: bool, ctx: StudyContext, study: StudyRecord, t0: float) -> None:
    """A disk map scene and its stress scene (the maps' final states carried on); the note counts the maps
    computed (``run_map`` notes each one it did not read from the work folder)."""
    name = "disk-map-gnl" if gnl else "disk-map-linear"
    before, stress = len(ctx.fresh), name.replace("map", "stress")
    study["scenes"][name], runs = scene_disk_map(ctx, gnl)
    study["scenes"][stress] = scene_disk_stress(ctx, study["scenes"][name], runs, gnl)
    maps = len(ctx.fresh) - before
    ctx.fresh.append(f"scenes {name} and {stress} {time.perf_counter() - t0:.0f} s ("
                     + (f"{maps} maps computed, the others" if maps else "every map") +
                     " read from results/speed_accuracy)")


def _disk_forced(gnl: bool, ctx: StudyContext, study: StudyRecord, t0: float) -> None:
    """A forced-response scene; the note counts the full-order and reduced runs computed."""
    name = "disk-forced-gnl" if gnl else "disk-forced-linear"
    ctx.forced_runs.clear()
    study["scenes"][name] = scene_disk_forced(ctx, gnl)
    refs = sum(run is None for run in ctx.forced_runs)
    roms = len(ctx.forced_runs) - refs
    ctx.fresh.append(f"scene {name} {time.perf_counter() - t0:.0f} s"
                     + (f" ({refs} full-order and {roms} reduced runs computed, the others read from "
                        "results/speed_accuracy)" if ctx.forced_runs else
                        " (every run read from results/speed_accuracy)"))


REGISTRY: dict[str, Scene] = {
    "modes": Scene("blade", _modes), "clearance": Scene("blade", _clearance),
    "rotating-modes": Scene("blade", _rotating_modes),
    "map-linear": Scene("blade", functools.partial(_map, False)),
    "map-gnl": Scene("blade", functools.partial(_map, True)),
    "stability": Scene("blade", _stability), "paper-speedup": Scene("blade", _paper_speedup),
    "cost-r": Scene("blade", _cost_r),
    "disk-modes": Scene("disk", _disk_modes),
    "disk-map-linear": Scene("disk", functools.partial(_disk_map, False)),
    "disk-map-gnl": Scene("disk", functools.partial(_disk_map, True)),
    "disk-forced-linear": Scene("disk", functools.partial(_disk_forced, False)),
    "disk-forced-gnl": Scene("disk", functools.partial(_disk_forced, True)),
    "gnl-steady": Scene("reference", _gnl_steady),
}
SCENES = tuple(name for name, scene in REGISTRY.items() if scene.family == "blade")
DISK_SCENES = tuple(name for name, scene in REGISTRY.items() if scene.family == "disk")
#: scenes read from a benchmark's full-order runs (hours each), run by name only
REFERENCE_SCENES = tuple(name for name, scene in REGISTRY.items() if scene.family == "reference")
GROUPS = {"all": SCENES, "disk": DISK_SCENES}


def expand_scenes(names: Iterable[str]) -> tuple[str, ...]:
    """The scenes of the command line's names ('all', 'disk' or scenes), in order, each once."""
    return tuple(dict.fromkeys(name for scene in names for name in GROUPS.get(scene, (scene,))))


def record_choices(study: StudyRecord) -> None:
    """Every scene's choices at the study's tolerances (``studies.model_choice.choose_model``), or why there is none."""
    from rotor37_rom.studies.model_choice import choose_model

    for name, scene in study["scenes"].items():
        scene["choices"] = {}
        for tol in TOLERANCES:
            try:
                c = choose_model(name, tol, study)
                scene["choices"][f"{tol:g}"] = dict(name=c.name, error=c.error, cost=c.cost)
            except ValueError as exc:
                scene["choices"][f"{tol:g}"] = dict(name=None, reason=str(exc))


def run_study(ctx: StudyContext, todo: Iterable[str]) -> StudyRecord:
    """Run the scenes ``todo`` (names of ``REGISTRY``) into the study file ``ctx.study_file`` (the scenes not run keep
    their entries), written after each scene; then the charts, the run's record and the docs block. From scratch
    means the whole single-blade study with an empty work folder (a disk scene alone is a note on the study)."""
    todo = tuple(todo)
    fresh = (not ctx.work.is_dir() or not any(ctx.work.iterdir())) and set(SCENES) <= set(todo)
    t_start = time.perf_counter()
    ctx.work.mkdir(parents=True, exist_ok=True)
    study = load_or_new(ctx.study_file)
    for name in todo:
        t0 = time.perf_counter()
        REGISTRY[name].run(ctx, study, t0)
        say(f"scene {name}: {time.perf_counter() - t0:.0f} s")
        record_choices(study)
        # the study's machine is the from-scratch run's; a scene measured elsewhere since says its own
        study.update(schema=SCHEMA, machine=study.get("machine") if not fresh and "machine" in study
                     else machine_description(), command=COMMAND, tolerances=list(TOLERANCES))
        write_study(ctx.study_file, study)
    write_charts(ctx.img, study)
    run = dict(scenes=list(todo), wall_s=time.perf_counter() - t_start, from_scratch=fresh)
    if ctx.fresh and not fresh:
        run["note"] = PREFIX + ", ".join(ctx.fresh)
    study.setdefault("runs", []).append(run)
    write_study(ctx.study_file, study)
    write_docs(ctx.doc, ctx.img, study)
    return study
