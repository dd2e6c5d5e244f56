"""Periodic orbits beside a contact map (#72, option ``--periodic`` of the map command): the blade's periodic
responses to the casing, orbits of the map's own explicit scheme with its contact law (``periodic.Shooting``),
continued by arc length over the continuation's speeds, each with its Floquet multipliers. They say which of the
map's steady responses are stable periodic orbits, where the branch loses stability and how (a fold: a jump; a
Neimark-Sacker point: a response modulated, steady but not periodic with the rotor; a period doubling), and the
unstable branches a run from rest never shows.

The orbit has the casing's own period, pi / Omega (two lobes), and a fixed number of steps n per period over the
whole branch (so that the period map is smooth in Omega): n = ceil(pi / (Omega_low h)), h the map's step, so every
point's step T / n is at most the map's. Its amplitude is the map's: max |u_n| of the map's node over the period.

An orbit that moves a node further than the maps' blow-up limit (``BLOWUP_LIMIT``: a run whose node displacement
passes it is stopped and flagged as diverged, its NFRC point left out) is flagged alike (``PeriodicBranch.blown_up``,
in the summary and the one-line description) and its amplitude left out (NaN, as the map's NFRC of a diverged run):
the reduced model is not meant for such motions, and the orbit is not a result.
"""
from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import numpy as np

from rotor37_rom.dynamics.casing import contact_matrices
from rotor37_rom.dynamics.explicit import BLOWUP_LIMIT
from rotor37_rom.periodic import Shooting, continue_branch, solve_periodic

__all__ = ["BLOWUP_LIMIT", "PeriodicBranch", "against_continuation", "describe_against", "orbit_blowup",
           "periodic_branch", "save_orbits", "load_orbits", "ORBITS_LAYOUT"]

#: what an orbits file holds (``save_orbits``): written into it, so that the file says how to read it
ORBITS_LAYOUT = ("states (n, 2, r): each orbit's start [q_0, q_-1], the central-difference scheme's two-step state in "
                 "the model's reduced coordinates (node_labels / node_q_index: which entries are which node, m); "
                 "speeds (n,): the rotor speed Omega (rad/s), the period pi / Omega (two bumps a revolution; "
                 "periodic.Shooting(scheme, casing, steps).march(states[k].ravel(), 2 Omega) marches it); steps: "
                 "explicit steps a period (h = pi / (Omega steps)); stable, largest_multiplier, blown_up (n,)")


def orbit_blowup(states: np.ndarray, rows) -> tuple[float, bool]:
    """Whether an orbit goes past the maps' blow-up limit, by the maps' own test (``dynamics.explicit``: a node
    displacement above ``BLOWUP_LIMIT`` or not finite).

    Args:
        states: (m, r) the orbit's states q over its period.
        rows: the entries of q that hold node displacements (``NodeMap.boundary_rows``).

    Returns:
        (the largest |node displacement| over the orbit (m; NaN where one is not finite), whether it is blown up).
    """
    u = np.abs(np.asarray(states, float)[:, np.asarray(rows, dtype=np.int64)])
    if not np.isfinite(u).all():
        return float("nan"), True
    largest = float(u.max(initial=0.0))
    return largest, largest > BLOWUP_LIMIT


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
        continuation: {name: ``against_continuation``'s comparison} of the map's sequential continuation branches.
        blown_up: whether each orbit moves a node past the maps' blow-up limit (``BLOWUP_LIMIT``; its amplitude is
            then NaN, as a diverged run's NFRC point).
        largest_displacement: the largest |node displacement| of each orbit (m), any entry of q holding one (the
            maps' blow-up test's).
        states: (n, 2, r) each orbit's start as the explicit scheme's two-step state [q_0, q_-1] (reduced
            coordinates; ``model.nodes`` says which entries are which node): ``Shooting(scheme, casing, steps)
            .march(states[k].ravel(), 2 * speeds[k])`` marches it one period (``save_orbits``, ``load_orbits``).
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
    continuation: dict = dataclasses.field(default_factory=dict)
    blown_up: np.ndarray | None = None
    largest_displacement: np.ndarray | None = None
    states: np.ndarray | None = None

    def __post_init__(self):
        n = len(self.speeds)
        if self.blown_up is None:
            object.__setattr__(self, "blown_up", np.zeros(n, bool))
        if self.largest_displacement is None:
            object.__setattr__(self, "largest_displacement", np.full(n, np.nan))
        object.__setattr__(self, "blown_up", np.asarray(self.blown_up, bool))
        if len(self.blown_up) != n or len(self.largest_displacement) != n:
            raise ValueError(f"blown_up and largest_displacement must have one entry per orbit ({n}), got "
                             f"{len(self.blown_up)} and {len(self.largest_displacement)}")

    def summary(self) -> dict:
        """Its entry in summary.json (an orbit past the blow-up limit: ``blown_up`` true, its amplitude NaN, its
        speed in ``blown_up_speeds``)."""
        return {"speeds": self.speeds.tolist(), "amplitude": self.amplitude.tolist(),
                "stable": self.stable.tolist(), "largest_multiplier": self.multiplier.tolist(),
                "blown_up": self.blown_up.tolist(), "blown_up_speeds": self.speeds[self.blown_up].tolist(),
                "blowup_limit": BLOWUP_LIMIT, "largest_displacement": np.asarray(self.largest_displacement,
                                                                                  float).tolist(),
                "bifurcations": self.bifurcations, "folds": self.folds, "ended": self.ended,
                "steps_per_period": self.steps, "wall_s": self.wall_s,
                **{f"continuation_{name}": c for name, c in self.continuation.items()}}

    def describe(self) -> str:
        """One line: points, stable share, the stability changes by kind and the first of them (all of them are in
        ``bifurcations``)."""
        if not len(self.speeds):
            return f"periodic orbits ({self.steps} steps a period, {self.wall_s:.0f} s): none; {self.ended}"
        kinds = [b["kind"] for b in self.bifurcations]
        counts = ", ".join(f"{kinds.count(k)} {k}" for k in dict.fromkeys(kinds)) or "none"
        first = self.bifurcations[0] if self.bifurcations else None
        lost = (f"; stable up to {self.speeds[first['index'] - 1]:.1f} rad/s, then {first['kind']} at "
                f"{first['speed']:.1f} rad/s (|mu| {first['modulus']:.4f})" if first and self.stable[0] else "")
        past = self.speeds[self.blown_up]
        blown = (f"; {len(past)} BLOWN UP (a node past the maps' blow-up limit {BLOWUP_LIMIT * 1e3:g} mm; not "
                 f"results, amplitude left out) at "
                 + (f"{past[0]:.1f}" if len(past) == 1 else f"{past.min():.1f}-{past.max():.1f}") + " rad/s"
                 if len(past) else "")
        return (f"periodic orbits ({self.steps} steps a period, {self.wall_s:.0f} s): {len(self.speeds)} points, "
                f"{int(self.stable.sum())} stable, {len(self.folds)} folds; stability changes: {counts}{lost}"
                f"{blown}; {self.ended}")


def against_continuation(shooting: Shooting, points: list, row: np.ndarray, continued) -> dict:
    """(g) of #72: the sequential continuation's points (``sweep.ContinuationPoint``: each speed's run started from
    the previous one's end, the paper's §2.3.3) against the stable periodic orbits at their own speeds. Each steady
    point within the branch is compared with the stable orbit(s) of the branch's stable stretches that cross its speed,
    each solved there by Newton from the stretch's nearer end (a stretch with one stable end counts: the stability
    changes somewhere between): its relative distance to the nearest stable one, with that
    orbit's largest |multiplier| (a continued run of n periods is left |mu|^n of the distance it started at). A steady
    point where no stable orbit is (a torus past a Neimark-Sacker point, another period, a branch the orbits did not
    reach) is listed apart. ``points``: the branch's PeriodicSolutions; ``row``: the map node's normal row. A
    compared orbit past the maps' blow-up limit is flagged (``blown_up`` in its row)."""
    w = np.array([p.omega / 2 for p in points])
    stable = [bool(p.stable) for p in points]
    rows, elsewhere = [], []
    for c in continued:
        if not (c.steady and np.isfinite(c.amplitude) and w.min() <= c.omega <= w.max()):
            continue
        found = []
        for k in range(len(points) - 1):
            if (stable[k] or stable[k + 1]) and min(w[k], w[k + 1]) <= c.omega <= max(w[k], w[k + 1]):
                near = points[k] if abs(w[k] - c.omega) <= abs(w[k + 1] - c.omega) else points[k + 1]
                try:
                    orbit = solve_periodic(shooting, near.unknowns, 2 * c.omega, tol=1e-9)
                except ValueError:
                    continue
                if orbit.stable:
                    states = shooting.orbit(orbit)
                    amp = float(np.abs(states @ row).max())
                    found.append((amp, float(np.abs(orbit.multipliers).max()),
                                  orbit_blowup(states, shooting.scheme.boundary_rows)[1]))
        if not found:
            elsewhere.append(float(c.omega))
            continue
        amp, mu, blown = min(found, key=lambda f: abs(f[0] - c.amplitude))
        rows.append({"speed": float(c.omega), "continuation": float(c.amplitude), "orbit": amp, "multiplier": mu,
                     "period": int(c.period), "difference": abs(c.amplitude - amp) / amp, "blown_up": blown})
    worst = max((r["difference"] for r in rows), default=None)
    return {"compared": rows, "no_stable_orbit": elsewhere, "largest_difference": worst}


def describe_against(name: str, comparison: dict) -> str:
    """One line: how the continuation ``name`` sits on the stable orbits (``against_continuation``)."""
    rows, other = comparison["compared"], comparison["no_stable_orbit"]
    if not rows and not other:
        return f"continuation {name} against the periodic orbits: no steady point within the branch's speeds"
    line = f"continuation {name} against the periodic orbits: {len(rows)} steady points on a stable orbit"
    if rows:
        line += f" (largest difference {100 * comparison['largest_difference']:.3g} %)"
    blown = [r["speed"] for r in rows if r.get("blown_up")]
    if blown:
        line += (f"; {len(blown)} on orbits BLOWN UP (past the blow-up limit {BLOWUP_LIMIT * 1e3:g} mm): "
                 + ", ".join(f"{w:.0f}" for w in blown) + " rad/s")
    if other:
        line += f"; {len(other)} where no stable orbit is: " + ", ".join(f"{w:.0f}" for w in other) + " rad/s"
    return line


def periodic_branch(config, scheme, continued: dict | None = None, max_points: int = 400,
                    progress=None) -> PeriodicBranch:
    """The periodic orbits of ``scheme`` (the map's scheme of one GNL setting) against the map's casing, from rest
    at the low end of ``config.continuation_span`` continued by arc length (relative step
    ``config.continuation.periodic``) to its high end; with ``continued`` ({name: list of
    ``sweep.ContinuationPoint``}, the map's sequential continuation) each branch compared with the stable orbits
    (``against_continuation``); ``progress(point)`` after each new point of the branch. An orbit that moves a node
    past the maps' blow-up limit is flagged (``orbit_blowup``; ``PeriodicBranch.blown_up``) and its amplitude left
    out (NaN). ValueError for a disk's model (shooting marches a blade's 2 r states; a tuned disk's travelling wave
    is ``periodic.TravellingWaveBalance``)."""
    model = scheme.model
    if model.sectors is not None:
        raise ValueError("--periodic: periodic orbits by shooting take a blade's model, not a disk's")
    low, high = config.continuation_span
    casing = config.sweep.casing
    steps = int(np.ceil(np.pi / (low * scheme.h)))
    t0 = time.perf_counter()
    shooting = Shooting(scheme, casing, steps=steps)
    # the map's own run from rest at the low speed (its revolutions, two periods each) is Newton's start
    try:
        start = solve_periodic(shooting, shooting.from_rest(2 * low, max(1, round(2 * config.sweep.revolutions))),
                               2 * low, tol=1e-9)
    except ValueError as error:                      # no orbit to continue: an empty branch that says why
        return PeriodicBranch(speeds=np.zeros(0), amplitude=np.zeros(0), stable=np.zeros(0, bool),
                              multiplier=np.zeros(0), bifurcations=[], folds=[],
                              ended=f"no periodic orbit found at {low:g} rad/s: {error}", steps=steps,
                              wall_s=time.perf_counter() - t0)
    branch = continue_branch(shooting, start, 2 * high, config.continuation.periodic, tol=1e-9,
                             max_points=max_points, progress=progress)
    Nn = contact_matrices(model.nodes, model.r, casing, rows=[model.nodes.row("LE", config.sector)])[0]
    amplitude, largest, blown_up = [], [], []
    for p in branch.points:
        states = shooting.orbit(p)
        tip, blown = orbit_blowup(states, scheme.boundary_rows)
        # past the maps' blow-up limit: flagged, its amplitude left out as a diverged run's NFRC point
        amplitude.append(np.nan if blown else float(np.abs(states @ Nn[0]).max()))
        largest.append(tip)
        blown_up.append(blown)
    against = {name: against_continuation(shooting, branch.points, Nn[0], points)
               for name, points in (continued or {}).items()}
    bifurcations = [{"index": int(i), "speed": branch.points[i].omega / 2, "kind": kind, "modulus": float(abs(mu)),
                     "argument": float(np.angle(mu))} for i, kind, mu in branch.bifurcations]
    last = branch.points[-1].omega / 2                  # the branch's parameter is omega = 2 Omega: said in Omega
    ended = (f"reached {high:g} rad/s" if branch.ended.startswith("reached") else
             f"the corrector failed at {last:.1f} rad/s with the step at its minimum"
             if branch.ended.startswith("the corrector") else f"{branch.ended}, at {last:.1f} rad/s")
    return PeriodicBranch(speeds=branch.omega / 2, amplitude=np.array(amplitude),
                          stable=np.array([bool(p.stable) for p in branch.points]),
                          multiplier=np.array([float(np.abs(p.multipliers).max()) for p in branch.points]),
                          bifurcations=bifurcations, folds=[float(branch.points[i].omega / 2) for i in branch.folds],
                          ended=ended, steps=steps, wall_s=time.perf_counter() - t0, continuation=against,
                          blown_up=np.array(blown_up, bool), largest_displacement=np.array(largest),
                          states=np.array([p.X for p in branch.points]))


def save_orbits(branch: PeriodicBranch, model, path) -> Path:
    """Write the branch's orbits (``PeriodicBranch.states`` and what each is) as an .npz file at ``path`` that
    ``load_orbits`` reads back, its layout written into it (``ORBITS_LAYOUT``); atomic (``npz.save_npz``)."""
    from rotor37_rom.npz import save_npz

    if branch.states is None or len(branch.states) != len(branch.speeds):
        raise ValueError("the branch holds no orbit states to save (a branch made before they were kept)")
    return save_npz(path, states=branch.states, speeds=branch.speeds, steps=np.int64(branch.steps),
                    stable=branch.stable, largest_multiplier=branch.multiplier, blown_up=branch.blown_up,
                    node_labels=np.array(model.nodes.labels, dtype=str), node_q_index=model.nodes.q_index,
                    r=np.int64(model.r), layout=np.array(ORBITS_LAYOUT))


def load_orbits(path) -> dict:
    """The orbits of a file ``save_orbits`` wrote: {name: array} with the names of ``ORBITS_LAYOUT``; ValueError
    naming the file where it is no such file."""
    names = ("states", "speeds", "steps", "stable", "largest_multiplier", "blown_up", "node_labels", "node_q_index",
             "r", "layout")
    try:
        with np.load(path, allow_pickle=False) as data:
            saved = {name: data[name] for name in names}
    except Exception as exc:                          # missing, not an .npz, truncated, a name missing
        raise ValueError(f"{path} is no orbits file of the map's --periodic ({type(exc).__name__}: "
                         f"{' '.join(str(exc).split())})") from None
    n, r = len(saved["speeds"]), int(saved["r"])
    if saved["states"].shape != (n, 2, r):
        raise ValueError(f"{path}: states of shape {saved['states'].shape}, expected ({n}, 2, {r})")
    return saved
