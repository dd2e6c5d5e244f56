"""The blade's GNL frequency response by periodic orbits against its interaction map, in one run (#72, the NFRC
benchmark): the orbits of the map's own scheme and casing (``studies.periodic_map.periodic_branch``: shooting,
arc length through the folds, Floquet multipliers at every point) over the map's speeds, and the map's cost on the
same model and step, measured in the same run.

The map's cost is measured on a batch of its speeds for a short run (the sweep's loop, ``simulate``, at the map's
batch size and step) and scaled to the whole map (its speeds x its revolutions, the steps counted speed by speed):
a map's cost is its simulation steps times the cost of one in a batch, which the sweep holds steady past its first
revolution (docs/performance.md). The speeds that blow up and run again at h / 2 (a quarter to a half of the
headline map's wall time) are left out of the estimate, and two ranks are counted at twice one's speed: both
favour the map.

The orbits run on the model's exact tensors, in double precision, at the map's step: the map's point cubature
approximates them (to 1e-4 on its training states), but its Jacobian, one state at a time, costs ~50 times theirs (10
ms against 0.22 ms at r = 55, one thread) and the tangent needs one at every step.
"""
from __future__ import annotations

import dataclasses
import time

import numpy as np

from rotor37_rom.checks import before_work
from rotor37_rom.dynamics.explicit import CentralDifference, simulate
from rotor37_rom.model.reduced import saved_model_key
from rotor37_rom.studies.contact_map import ContactMapConfig, reduced_model
from rotor37_rom.studies.contact_scheme import time_scheme
from rotor37_rom.studies.periodic_map import PeriodicBranch, periodic_branch

__all__ = ["PeriodicCost", "nfrc_against_map"]


@dataclasses.dataclass(frozen=True)
class PeriodicCost:
    """The NFRC by periodic orbits and the map's cost on the same model.

    Attributes:
        branch: the orbits (``PeriodicBranch``: speeds, amplitudes, stability, bifurcations, folds, its wall time).
        h: the map's step (s); the orbits' is at most it.
        map_batch: speeds in the measured batch; map_probe_s: its wall time; map_probe_steps: its simulation steps.
        map_steps: simulation steps of the whole map (every speed, every revolution).
        map_serial_s: the map's estimated wall time on one process; map_ranks: ranks it is counted on;
        map_s: map_serial_s / map_ranks.
    """

    branch: PeriodicBranch
    h: float
    map_batch: int
    map_probe_s: float
    map_probe_steps: int
    map_steps: int
    map_serial_s: float
    map_ranks: int

    @property
    def map_s(self) -> float:
        return self.map_serial_s / self.map_ranks

    @property
    def ratio(self) -> float | None:
        """The map's estimated wall time over the NFRC's; None where no orbit was found (nothing to compare)."""
        return self.map_s / self.branch.wall_s if len(self.branch.speeds) else None

    def summary(self) -> dict:
        return {"nfrc": self.branch.summary(), "h": self.h, "map_batch": self.map_batch,
                "map_probe_s": self.map_probe_s, "map_probe_steps": self.map_probe_steps,
                "map_us_per_step": 1e6 * self.map_probe_s / self.map_probe_steps, "map_steps": self.map_steps,
                "map_serial_s": self.map_serial_s, "map_ranks": self.map_ranks, "map_s": self.map_s,
                "nfrc_s": self.branch.wall_s, "ratio": self.ratio}


def _steps(speeds: np.ndarray, revolutions: float, h: float) -> np.ndarray:
    """Each speed's steps for ``revolutions`` revolutions at step h (the sweep's count)."""
    return np.ceil(revolutions * 2 * np.pi / (np.asarray(speeds, float) * h)).astype(np.int64)


def nfrc_against_map(config: ContactMapConfig, start_revolutions: float = 30.0, probe_revolutions: float = 1.0,
                     batch: int = 50, ranks: int = 2, max_points: int = 400, progress=None) -> PeriodicCost:
    """The GNL periodic orbits of ``config``'s map (``--periodic``'s branch over its continuation range; Newton's
    start the run from rest at the low end, ``start_revolutions`` long) and the cost of the map itself (GNL, its
    speeds x revolutions) from ``batch`` of its speeds run ``probe_revolutions`` in one batch; ValueError for a
    configuration the orbits do not take (a disk, a turning blade, no --periodic step, GNL off), or for its folders
    and model file, checked before any work (``checks.before_work``: a dry run stops there); ``progress(point)``
    after each orbit of the branch."""
    if config.continuation.periodic <= 0:
        raise ValueError("the NFRC needs --periodic STEP (> 0, the relative arc-length step)")
    if config.gnl != "on":
        raise ValueError("the NFRC benchmark is the GNL map's: --gnl on")
    for name, value, low in (("start_revolutions", start_revolutions, 1.0), ("probe_revolutions",
                                                                           probe_revolutions, 0.0)):
        if not value > low:
            raise ValueError(f"{name} must be > {low:g}, got {value}")
    if not (batch >= 1 and ranks >= 1):
        raise ValueError(f"batch and ranks must be >= 1, got {batch}, {ranks}")
    before_work({"--out": config.out, "--cache": config.cache_dir},              # before the hours of work
                {"--model": (config.rom.path, saved_model_key)})
    setting = config.setting(True)
    model, _ = reduced_model(config, None)
    scheme = time_scheme(setting, model, True, None)                  # the map's: its forces, precision and step
    # the orbits on the model's exact tensors, the cubature's reference (a cubature's Jacobian, one state at a time,
    # costs ~50x theirs: the tangent needs one at every step)
    orbits = scheme if setting.scheme.cubature is None else CentralDifference(
        model, nonlinear=True, h=scheme.h, frequency_cap=setting.scheme.frequency_cap_rad_s)
    speeds = config.speed_grid
    probe = speeds[np.unique(np.linspace(0, speeds.size - 1, min(batch, speeds.size)).round().astype(int))]
    n = _steps(probe, probe_revolutions, scheme.h)
    t0 = time.perf_counter()
    simulate(scheme, probe, casing=config.sweep.casing, n_steps=n, duration=config.sweep.revolutions * 2 * np.pi /
             probe, record_every=max(1, int(1e-5 / scheme.h)), on_blowup="flag")
    probe_s = time.perf_counter() - t0
    steps = int(_steps(speeds, config.sweep.revolutions, scheme.h).sum())
    branch = periodic_branch(setting.with_options(revolutions=start_revolutions), orbits, max_points=max_points,
                             progress=progress)
    return PeriodicCost(branch, scheme.h, probe.size, probe_s, int(n.sum()), steps,
                        probe_s / n.sum() * steps, ranks)
