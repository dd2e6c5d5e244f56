"""Mistuning of the bladed disk in contact (issue #21, item 5): the per-blade response of a map, and the statistic
over disks (seeds) of one blade-to-blade stiffness scatter (``benchmarks/bench_disk_mistuning.py``).

The amplification is a disk's largest response over the blades against the tuned disk's at the same speed; the
localisation its largest blade's amplitude over the RMS of the 36 (1 when every blade moves alike, 6 = sqrt(36) when
one blade carries all). An earlier run's rows count with a new run's when its settings are the same.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from rotor37_rom.studies import sweep


def blade_amplitudes(folder: Path, speeds) -> np.ndarray:
    """(speeds, sectors): node LE's max over the last revolution per blade (NaN where the run blew up)."""
    return np.array([sweep.sector_maxima(sweep.load_speed(folder, float(w))) for w in speeds])


def earlier_rows(path: Path, settings: dict, rows: list[dict]) -> list[dict]:
    """The rows of ``path`` (an earlier run's JSON) with the same ``settings`` (speeds, revolutions, friction, cap,
    GNL and its step) and another (sigma, seed) than ``rows``; none when the settings differ."""
    if not path.is_file():
        return []
    stored = {"preset": "ci"} | json.loads(path.read_text())     # files from before the preset was recorded: ci
    if any(stored.get(k) != v for k, v in settings.items()):
        return []
    new = {(r["sigma"], r["seed"]) for r in rows}
    return [r for r in stored["rows"] if (r["sigma"], r["seed"]) not in new]


def over_seeds(rows: list[dict]) -> list[dict]:
    """Per sigma > 0 over its disks (seeds): the amplification's and localisation's mean and largest per speed, and
    the largest blade's rank among the stiffness factors (0: the softest), per disk and speed."""
    out = []
    for sigma in sorted({r["sigma"] for r in rows if r["sigma"] > 0}):
        disks = sorted((r for r in rows if r["sigma"] == sigma), key=lambda r: r["seed"])
        amp = np.array([r["amplification"] for r in disks], float)      # NaN: a run that blew up
        loc = np.array([r["localisation"] for r in disks], float)
        ranks = [[int(np.argsort(np.argsort(r["factors"]))[b]) for b in r["largest_blade"]] for r in disks]
        out.append({"sigma": sigma, "seeds": [r["seed"] for r in disks],
                    "amplification_mean": np.nanmean(amp, axis=0).tolist(),
                    "amplification_max": np.nanmax(amp, axis=0).tolist(),
                    "localisation_mean": np.nanmean(loc, axis=0).tolist(),
                    "localisation_max": np.nanmax(loc, axis=0).tolist(),
                    "largest_blade_stiffness_rank": ranks})
    return out
