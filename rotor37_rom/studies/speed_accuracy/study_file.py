"""The study file's schema, and the one module that reads and writes it (``rotor37_rom/data/speed_accuracy.json``).

The file is JSON: per scene a ``SceneRecord`` whose candidates (``CandidateRecord``) carry their ``options``, keyed on
the option names of the library's configuration the scene measured (``SCENE_CONFIG``): ``ContactMapConfig`` for the
maps and stresses (``r_c``, ``frequency_cap``, ``safety``, ``cubature``, ``precision``, ``retry_diverged``, a disk's
``r_md``, ``r_cyclic``), ``ReducedBladeConfig`` for the clearance (``r_c``, ``r_md``, ``criterion``, ``global_md``),
``DiskReductionConfig`` for the disk's frequencies and forced response (``r_c``, ``r_md``, ``r_cyclic``,
``tip_nodes``, ``face_shapes``). ``config_options`` turns a candidate's options into another configuration's fields
(the one renaming: ``global_md`` is ``ReductionConfig.global_md_modes``). Records are TypedDicts: the file is read
and written as it is, with the keys each scene adds (its errors by case, its timings).

Pure Python (no dolfinx, no numpy beyond the writer's default): ``model_choice`` reads the file through here.
"""
from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Any, TypedDict

from rotor37_rom.npz import save_json

__all__ = ["SCHEMA", "CandidateRecord", "FloorRecord", "ChoiceRecord", "SceneRecord", "RunRecord", "StudyRecord",
           "SCENE_CONFIG", "RENAMED", "new_study", "read_study", "load_or_new", "write_study", "config_options",
           "option_names",
           "finite_or_none"]

SCHEMA = 1


class CandidateRecord(TypedDict, total=False):
    """One candidate model of a scene: its name, its options (its configuration's field names), its cost (in the
    scene's ``cost_unit``), its error on the study's cases and on held-out cases (None: not run there)."""

    name: str
    options: dict[str, Any]
    cost: float
    error: float
    held_out_error: float | None


class FloorRecord(TypedDict, total=False):
    """The error below which a scene cannot tell models apart: what the reference's own cap is worth (``cap``) and,
    for a stress, how far the reference's perturbation moves it (``perturbation``); ``why`` says it in words."""

    error: float
    cap: dict | None
    why: str
    perturbation: float


class ChoiceRecord(TypedDict, total=False):
    """The model chosen at one tolerance (``name`` None: none, and ``reason`` says why)."""

    name: str | None
    error: float
    cost: float
    reason: str


class SceneRecord(TypedDict, total=False):
    """A scene: what it measures, its cost unit, its reference (``options``, and its cost where measured), its
    candidates, its held-out case (None: none), its floor, and the choices at the study's tolerances (keyed '0.05')."""

    description: str
    cost_unit: str
    reference: dict[str, Any]
    candidates: list[CandidateRecord]
    held_out_case: str | None
    held_out_reference: dict[str, Any]
    floor: FloorRecord | None
    choices: dict[str, ChoiceRecord]
    machine: str


class RunRecord(TypedDict, total=False):
    """One invocation of the study: its scenes, its wall time, whether it ran from scratch, and what it computed."""

    scenes: list[str]
    wall_s: float
    from_scratch: bool
    note: str


class StudyRecord(TypedDict, total=False):
    """The study file: the schema, the scenes, the machine and command, the tolerances, the tables that are not
    scenes (stability, paper_speedup, cost_r) and the runs."""

    schema: int
    scenes: dict[str, SceneRecord]
    machine: str
    command: str
    tolerances: list[float]
    stability: dict[str, Any]
    paper_speedup: dict[str, Any]
    cost_r: dict[str, Any]
    runs: list[RunRecord]


# the configuration whose field names a scene's options are (module, class): checked by tests/studies/test_model_choice.py
_MAP_CONFIG = ("rotor37_rom.studies.contact_config", "ContactMapConfig")
_DISK_CONFIG = ("rotor37_rom.reduction.disk_builder", "DiskReductionConfig")
SCENE_CONFIG = {
    "modes": _MAP_CONFIG, "clearance": ("rotor37_rom.studies.clearance_consumption", "ReducedBladeConfig"),
    **{f"{kind}-{gnl}": _MAP_CONFIG for kind in ("map", "history", "stress", "disk-map", "disk-stress")
       for gnl in ("linear", "gnl")},
    "disk-modes": _DISK_CONFIG, "disk-forced-linear": _DISK_CONFIG, "disk-forced-gnl": _DISK_CONFIG,
    "rotating-modes": ("rotor37_rom.reduction.config", "ReductionConfig"), "gnl-steady": _MAP_CONFIG,
}
# a study option that another configuration names otherwise: {(configuration class name, option): its field}
RENAMED = {("ReductionConfig", "global_md"): "global_md_modes"}


def new_study() -> StudyRecord:
    return {"schema": SCHEMA, "scenes": {}}


def read_study(path: str | Path) -> StudyRecord:
    """The study file at ``path``; ValueError if absent or of another schema."""
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"speed-accuracy study file {path} not found: run python benchmarks/speed_accuracy.py")
    study = json.loads(path.read_text())
    if study.get("schema") != SCHEMA:
        raise ValueError(f"speed-accuracy study file {path}: schema {study.get('schema')!r}, expected {SCHEMA}")
    return study


def load_or_new(path: str | Path) -> StudyRecord:
    """The study file at ``path`` as it is (a run adds its scenes to it), or a new study if there is none."""
    path = Path(path)
    return json.loads(path.read_text()) if path.is_file() else new_study()


def finite_or_none(x):
    """JSON's default for a value it cannot hold: None for a missing or non-finite number."""
    import numpy as np

    return None if x is None or not np.isfinite(x) else float(x)


def write_study(path: str | Path, study: StudyRecord) -> Path:
    """Write the study file whole (one space of indent; a number JSON cannot hold, a numpy scalar, as a float or,
    not finite, as null)."""
    return save_json(path, study, indent=1, default=finite_or_none)


def option_names(config_type: type) -> set[str]:
    """The options a configuration takes: its ``OPTIONS`` where it maps flat options onto the objects it composes
    (``ContactMapConfig.from_options``), else its dataclass fields."""
    flat = getattr(config_type, "OPTIONS", None)
    return set(flat) if flat is not None else {f.name for f in dataclasses.fields(config_type)}


def config_options(options: dict[str, Any], config_type: type) -> dict[str, Any]:
    """A candidate's ``options`` as keyword arguments of the dataclass ``config_type`` (of its ``from_options`` where
    it composes others; ``RENAMED`` where it names an option otherwise); ValueError naming the options that are none
    of its options (e.g. the full-order linear candidate's ``model``)."""
    fields = option_names(config_type)
    out = {RENAMED.get((config_type.__name__, k), k): v for k, v in options.items()}
    unknown = sorted(k for k in out if k not in fields)
    if unknown:
        raise ValueError(f"options {', '.join(unknown)} are not fields of {config_type.__name__}")
    return out
