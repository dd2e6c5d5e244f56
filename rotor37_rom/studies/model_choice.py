"""The model for a tolerance: the cheapest measured configuration of a scene whose error meets it.

The speed-accuracy study (``python benchmarks/speed_accuracy.py``, ``make speed-accuracy``) measures, per scene, the
cost and the error against a reference of every candidate model and writes them to ``rotor37_rom/data/
speed_accuracy.json`` (versioned with the code). ``choose_model(scene, tolerance)`` reads that file — never numbers
typed here — and returns the cheapest candidate whose *expected* error is within the tolerance: the largest of the
error measured on the study's cases, when the study ran the candidate on held-out cases (other speeds, another mode
or amplitude) the error there, and the scene's floor where it states one (the error below which its reference cannot
tell models apart). A candidate that missed on held-out cases is thereby passed over for the next cheapest. The
file's schema, its reader and the options' mapping onto a configuration's fields: ``speed_accuracy.study_file``.

Pure Python and NumPy (no dolfinx): the demos call it before any meshing.
"""
from __future__ import annotations

import dataclasses
import math
import numbers
from pathlib import Path
from typing import Callable


from rotor37_rom.studies.speed_accuracy.study_file import SCHEMA, config_options, read_study

__all__ = ["STUDY_FILE", "SCHEMA", "ModelChoice", "load_study", "scene_floor", "expected_error",
           "choose_model", "reference_model", "reference_label", "scenes"]

STUDY_FILE = Path(__file__).resolve().parents[1] / "data" / "speed_accuracy.json"


@dataclasses.dataclass(frozen=True)
class ModelChoice:
    """One candidate of a scene: its options (the option names of the configuration the scene measured,
    ``study_file.SCENE_CONFIG``: e.g. ``frequency_cap``, held at ``ContactMapConfig.scheme.frequency_cap``), its
    expected error (relative), the error on the study's cases and on held-out cases (None: not run there), its cost,
    and the scene's floor (0: the scene states none)."""

    scene: str
    name: str
    options: dict
    error: float
    study_error: float
    held_out_error: float | None
    cost: float
    cost_unit: str
    floor: float = 0.0
    reference: str = ""

    def config_options(self, config_type: type) -> dict:
        """The options as keyword arguments of the dataclass ``config_type`` (``study_file.config_options``: e.g.
        ``global_md`` is ``ReductionConfig.global_md_modes``); ValueError naming an option it has no field for."""
        return config_options(self.options, config_type)

    def describe(self) -> str:
        if self.name == "reference":
            return (f"{self.scene}: the study's reference ({', '.join(f'{k} {v}' for k, v in self.options.items())};"
                    f" the yardstick of the others, its own error not measured), cost {self.cost:.3g} {self.cost_unit}")
        held = "not run" if self.held_out_error is None else f"{100 * self.held_out_error:.2g} %"
        floor = f", the scene's floor {100 * self.floor:.2g} %" if self.floor else ""
        against = f"; error against {self.reference}" if self.reference else ""
        return (f"{self.scene}: {self.name} — expected error {100 * self.error:.2g} % (study "
                f"{100 * self.study_error:.2g} %, held-out {held}{floor}), cost {self.cost:.3g} {self.cost_unit}"
                f"{against}")


def reference_label(scene: str, data: dict) -> str:
    """What a scene's errors are measured against, in words: the full order where the study's reference is one
    (its options name a 'model'), else the reduced model of its options — for a GNL scene flagged as not validated
    against the full order (``docs/results-gnl-contact.md``, issue #86)."""
    options = dict(data.get("reference", {}).get("options", {}))
    if "model" in options:
        return str(options["model"])
    label = "the reduced model " + ", ".join(f"{k} {v}" for k, v in options.items())
    if "gnl" in scene:
        label += " (a reduced GNL reference, not the full order: see docs/results-gnl-contact.md)"
    return label


def load_study(path: str | Path | None = None) -> dict:
    """The study file (default: the one shipped with the package); ValueError if absent or of another schema."""
    return read_study(path if path is not None else STUDY_FILE)


def scenes(study: dict | None = None) -> list[str]:
    """The scenes the study measured."""
    return sorted((study or load_study())["scenes"])


def scene_floor(scene: dict) -> float:
    """The error below which ``scene`` (a scene of the study file) cannot tell models apart, 0 if it states none:
    its ``floor`` record, e.g. what the reference's own frequency cap is worth (its model at a lower cap, measured
    against it) or how far the reference's 1e-4 perturbation moves the scene's quantity."""
    return float((scene.get("floor") or {}).get("error", 0.0))


def expected_error(candidate: dict, scene: dict) -> float:
    """The error a candidate of ``scene`` is chosen by: the largest of its study error, its held-out error (if
    measured) and the scene's floor (``scene_floor``: a model cannot be shown closer to the truth than that)."""
    err = candidate.get("error")
    err = math.inf if err is None else float(err)
    held = candidate.get("held_out_error")
    return max(err, scene_floor(scene), -math.inf if held is None else float(held))


def choose_model(scene: str, tolerance: float, study: dict | None = None, fallback: bool = False,
                 where: Callable[[dict], bool] | None = None) -> ModelChoice:
    """The cheapest measured candidate of ``scene`` whose expected error is <= ``tolerance`` (relative, in (0, 1)),
    among the candidates (dicts of the study file) for which ``where`` holds (default: all).

    Raises ValueError naming the scene (unknown scene) or the tolerance (out of range, or below every candidate's
    expected error: then the message gives the smallest one measured, unless ``fallback``, which returns the scene's
    reference model instead, ``reference_model``)."""
    study = study if study is not None else load_study()
    if scene not in study["scenes"]:
        raise ValueError(f"scene must be one of {', '.join(scenes(study))}, got {scene!r}")
    if not (isinstance(tolerance, numbers.Real) and not isinstance(tolerance, bool) and 0 < tolerance < 1):
        raise ValueError(f"tolerance must be in (0, 1) (a relative error, 0.05 = 5 %), got {tolerance!r}")
    data = study["scenes"][scene]
    candidates = [c for c in data["candidates"] if where is None or where(c)]
    best = None
    for cand in candidates:
        err = expected_error(cand, data)
        if err <= tolerance and (best is None or cand["cost"] < best["cost"]):
            best = cand
    if best is None and fallback:
        return reference_model(scene, study)
    if best is None:
        smallest = min((expected_error(c, data) for c in candidates), default=math.inf)
        raise ValueError(f"tolerance {tolerance:g} is below every measured model of scene {scene!r} "
                         f"(smallest expected error {smallest:.4g}); allowed: tolerance >= {smallest:.4g}")
    return ModelChoice(scene, best["name"], dict(best["options"]), expected_error(best, data), float(best["error"]),
                       best.get("held_out_error"), float(best["cost"]), data["cost_unit"], scene_floor(data),
                       reference_label(scene, data))


def reference_model(scene: str, study: dict | None = None) -> ModelChoice:
    """The reference model of ``scene`` (what every candidate was measured against), for a caller that must run
    something when no candidate meets its tolerance; its error is NaN (not measured)."""
    study = study if study is not None else load_study()
    if scene not in study["scenes"]:
        raise ValueError(f"scene must be one of {', '.join(scenes(study))}, got {scene!r}")
    data = study["scenes"][scene]
    ref = data["reference"]
    return ModelChoice(scene, "reference", dict(ref.get("options", {})), math.nan, math.nan, None,
                       float(ref.get("cost", ref.get("sweep_s", math.nan))), data["cost_unit"])
