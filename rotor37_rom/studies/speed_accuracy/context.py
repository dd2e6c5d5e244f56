"""The speed-accuracy study's settings and its run context: the blade maps' setup, the tolerances, the robustness
probe, and the ``StudyContext`` every scene is given (its folders and what the run computed rather than read)."""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

__all__ = ["StudyContext", "MAP", "HELD_OUT_SPEEDS", "TOLERANCES", "PERTURBATION", "ROBUST", "PAPER_R", "PAPER_H",
           "PREFIX", "COMMAND", "percent"]

PAPER_R, PAPER_H = 189, 1e-7            # the paper's single-blade GNL setting: r = 189, exact tensors, h = 1e-7 s
TOLERANCES = (0.01, 0.05, 0.2)
PERTURBATION = 1e-4
ROBUST = 0.01            # a speed is robust when the 1e-4 perturbation moves its NFRC by <= 1 % of the peak
MAP = dict(preset="ci", speeds=(1200.0, 1600.0, 11), revolutions=8.0, mu=0.0, direction="x", quiet=True, batch=16)
HELD_OUT_SPEEDS = (1220.0, 1580.0, 10)
PREFIX = "computed since, on their own: "
COMMAND = "python benchmarks/speed_accuracy.py"          # the study file's 'command' and the docs' first line


@dataclasses.dataclass(eq=False)
class StudyContext:
    """Where one run of the study reads and writes, and what it computed: ``work`` the cached maps, models and runs
    (results/speed_accuracy), ``img`` the charts (docs/img), ``doc`` the page whose generated block it rewrites,
    ``study_file`` the study file; ``fresh`` what this run computed rather than read from ``work`` (the run's note),
    ``forced_runs`` the forced-response runs it computed (None: a full-order reference; else a reduced run's wall
    time). Compared by identity: the per-process caches of models are keyed on it."""

    work: Path
    img: Path
    doc: Path
    study_file: Path
    fresh: list[str] = dataclasses.field(default_factory=list)
    forced_runs: list = dataclasses.field(default_factory=list)

    @classmethod
    def in_repository(cls, root: Path, study_file: Path | None = None) -> "StudyContext":
        """The repository's folders: results/speed_accuracy, docs/img, docs/choosing-a-model.md and the package's
        study file (rotor37_rom/data/speed_accuracy.json) unless ``study_file``."""
        root = Path(root)
        return cls(work=root / "results" / "speed_accuracy", img=root / "docs" / "img",
                   doc=root / "docs" / "choosing-a-model.md",
                   study_file=study_file or root / "rotor37_rom" / "data" / "speed_accuracy.json")


def percent(x) -> str:
    """A relative error as the docs write it: '–' (none), 'diverged' (not finite), two digits below 100 %."""
    if x is None:
        return "–"
    if not np.isfinite(x):
        return "diverged"
    return f"{100 * x:.2g} %" if x < 1 else f"{100 * x:.0f} %"
