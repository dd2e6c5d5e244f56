"""Periodic orbits beside a contact map (#72, option ``--periodic`` of the map command): the blade's periodic
responses to the casing, orbits of the map's own explicit scheme with its contact law (``periodic.Shooting``),
continued by arc length over the continuation's speeds, each with its Floquet multipliers. They say which of the
map's steady responses are stable periodic orbits, where the branch loses stability and how (a fold: a jump; a
Neimark-Sacker point: a response modulated, steady but not periodic with the rotor; a period doubling), and the
unstable branches a run from rest never shows.

The orbit has the casing's own period, pi / Omega (two lobes), and a fixed number of steps n per period over the
whole branch (so that the period map is smooth in Omega): n = ceil(pi / (Omega_low h)), h the map's step, so every
point's step T / n is at most the map's. Its amplitude is the map's: max |u_n| of the map's node over the period.
"""
from __future__ import annotations

import dataclasses
import time

import numpy as np

from rotor37_rom.dynamics.casing import contact_matrices
from rotor37_rom.periodic import Shooting, continue_branch, solve_periodic

__all__ = ["PeriodicBranch", "periodic_branch"]


@dataclasses.dataclass(frozen=True)
class PeriodicBranch:
    """A continued branch of periodic orbits of the map's scheme.

    Attributes:
        speeds: Omega of each point (rad/s), in arc-length order (a fold turns back).
        amplitude: max |u_n| of the map's node over each orbit (m).
        stable: whether each orbit is stable (every Floquet multiplier inside the unit circle).
        multiplier: the largest |multiplier| of each orbit.
        bifurcations: where the stability changes: {'index', 'speed' (rad/s), 'kind' (fold, period doubling,
            Neimark-Sacker), 'modulus', 'argument' (rad) of the multiplier that crossed}.
        folds: the speeds (rad/s) of the points just past each turning point.
        ended: why the branch ended (reached its speed, or a corrector that failed with the step at its minimum).
        steps: explicit steps per period; wall_s: wall time (s).
    """

    speeds: np.ndarray
    amplitude: np.ndarray
    stable: np.ndarray
    multiplier: np.ndarray
    bifurcations: list
    folds: list
    ended: str
    steps: int
    wall_s: float

    def summary(self) -> dict:
        """Its entry in summary.json."""
        return {"speeds": self.speeds.tolist(), "amplitude": self.amplitude.tolist(),
                "stable": self.stable.tolist(), "largest_multiplier": self.multiplier.tolist(),
                "bifurcations": self.bifurcations, "folds": self.folds, "ended": self.ended,
                "steps_per_period": self.steps, "wall_s": self.wall_s}

    def describe(self) -> str:
        """One line: points, stable share, the stability changes by kind and the first of them (all of them are in
        ``bifurcations``)."""
        kinds = [b["kind"] for b in self.bifurcations]
        counts = ", ".join(f"{kinds.count(k)} {k}" for k in dict.fromkeys(kinds)) or "none"
        first = self.bifurcations[0] if self.bifurcations else None
        lost = (f"; stable up to {self.speeds[first['index'] - 1]:.1f} rad/s, then {first['kind']} at "
                f"{first['speed']:.1f} rad/s (|mu| {first['modulus']:.4f})" if first and self.stable[0] else "")
        return (f"periodic orbits ({self.steps} steps a period, {self.wall_s:.0f} s): {len(self.speeds)} points, "
                f"{int(self.stable.sum())} stable, {len(self.folds)} folds; stability changes: {counts}{lost}; "
                f"{self.ended}")


def periodic_branch(config, scheme, max_points: int = 400) -> PeriodicBranch:
    """The periodic orbits of ``scheme`` (the map's scheme of one GNL setting) against the map's casing, from rest
    at the low end of ``config.continuation_span`` continued by arc length (relative step
    ``config.continuation.periodic``) to its high end. ValueError for a disk's model (shooting marches a blade's
    2 r states; a tuned disk's travelling wave is ``periodic.TravellingWaveBalance``)."""
    model = scheme.model
    if model.sectors is not None:
        raise ValueError("--periodic: periodic orbits by shooting take a blade's model, not a disk's")
    low, high = config.continuation_span
    casing = config.sweep.casing
    steps = int(np.ceil(np.pi / (low * scheme.h)))
    t0 = time.perf_counter()
    shooting = Shooting(scheme, casing, steps=steps)
    start = solve_periodic(shooting, np.zeros(shooting.size), 2 * low, tol=1e-9)
    branch = continue_branch(shooting, start, 2 * high, config.continuation.periodic, tol=1e-9,
                             max_points=max_points)
    Nn = contact_matrices(model.nodes, model.r, casing, rows=[model.nodes.row("LE", config.sector)])[0]
    amplitude = np.array([np.abs(shooting.orbit(p) @ Nn[0]).max() for p in branch.points])
    bifurcations = [{"index": int(i), "speed": branch.points[i].omega / 2, "kind": kind, "modulus": float(abs(mu)),
                     "argument": float(np.angle(mu))} for i, kind, mu in branch.bifurcations]
    last = branch.points[-1].omega / 2                  # the branch's parameter is omega = 2 Omega: said in Omega
    ended = (f"reached {high:g} rad/s" if branch.ended.startswith("reached") else
             f"the corrector failed at {last:.1f} rad/s with the step at its minimum"
             if branch.ended.startswith("the corrector") else f"{branch.ended}, at {last:.1f} rad/s")
    return PeriodicBranch(speeds=branch.omega / 2, amplitude=amplitude,
                          stable=np.array([bool(p.stable) for p in branch.points]),
                          multiplier=np.array([float(np.abs(p.multipliers).max()) for p in branch.points]),
                          bifurcations=bifurcations, folds=[float(branch.points[i].omega / 2) for i in branch.folds],
                          ended=ended, steps=steps, wall_s=time.perf_counter() - t0)
