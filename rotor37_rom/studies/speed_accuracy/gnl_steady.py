"""The scene 'gnl-steady': GNL in contact at steady state, the reduced models against the full order itself (#86).

It computes nothing: the full-order runs take an hour and more a speed, so they are the benchmark's
(``python benchmarks/bench_gnl_steady.py``, results/bench_gnl_steady.json); the scene reads its runs, keeps the
cases of one question (the same friction, normal, damping law and length, St. Venant-Kirchhoff's full order at its
finest step) and turns the predictive reduced models run at every one of its speeds into candidates: error the
largest relative error on the steady max |u_LE| over the speeds (a run that is not steady at some speed is not a
candidate: it has no error), cost the mean wall time per simulated revolution. The POD models are not candidates:
they are built from the full order's own fields (the bound of ``docs/results-gnl-contact.md``, not a model a user can
build first).
"""
from __future__ import annotations

import json
import math
import re
from pathlib import Path

from rotor37_rom.studies.speed_accuracy.study_file import CandidateRecord, SceneRecord

__all__ = ["SCENE", "BENCH_COMMAND", "scene_gnl_steady", "candidate_options"]

SCENE = "gnl-steady"
BENCH_COMMAND = "python benchmarks/bench_gnl_steady.py"
_CASE = re.compile(r"^(?P<speed>[\d.e+]+) rad/s (?P<rest>mu \S+ \S+ \S+ \d+ rev)$")     # SVK cases only
_FULL = re.compile(r"^full h (?P<h>\S+) rho (?P<rho>\S+)$")
_ROM = re.compile(r"^rom r_c (?P<r_c>\d+)(?: global md (?P<g>\d+))?(?: cubature (?P<tol>\S+) train \S+)?"
                  r" cap \S+ h \S+$")


def candidate_options(key: str) -> dict | None:
    """The options (``ContactMapConfig``'s names) of a reduced run of the benchmark from its key, None for a run
    that is not a predictive reduced model (the full order, a POD model)."""
    m = _ROM.match(key)
    if m is None:
        return None
    options = {"r_c": int(m["r_c"]), "global_md": int(m["g"] or 3)}
    if m["tol"] is not None:
        options["cubature"] = float(m["tol"])
    return options


def scene_gnl_steady(results: str | Path, question: str = "mu 0 x heavy 8 rev") -> SceneRecord:
    """The scene from the benchmark's results file: the cases of ``question`` (the case label without its speed)
    that have a full-order run; ValueError naming the file and the command where there is none."""
    from rotor37_rom.studies.gnl_reference import SteadyCase, compare_runs

    results = Path(results)
    if not results.is_file():
        raise ValueError(f"{results}: no steady-state runs; run {BENCH_COMMAND} first (hours: "
                         f"docs/results-gnl-contact.md)")
    try:
        store = json.loads(results.read_text())
    except (OSError, ValueError) as exc:
        raise ValueError(f"{results} could not be read ({exc}); remove it and run {BENCH_COMMAND} again") from None
    per_speed, full_costs, refs, reference = {}, [], [], {}
    for label, runs in sorted(store.items()):
        m = _CASE.match(label) if isinstance(runs, dict) else None
        if m is None or m["rest"] != question:
            continue
        fulls = sorted((k for k in runs if _FULL.match(k)), key=lambda k: float(_FULL.match(k)["h"]))
        if not fulls:
            continue
        case = SteadyCase(float(m["speed"]), revolutions=int(question.split()[-2]))
        rows = compare_runs(case, runs, fulls[0])
        per_speed[case.speed] = {r["run"]: r for r in rows}
        reference[case.speed] = fulls[0]
        full = per_speed[case.speed][fulls[0]]
        full_costs.append((case.speed, full["wall_per_revolution_s"]))
        refs.append(f"{case.speed:g} rad/s: {1e3 * full['value']:.3f} mm" + ("" if full["steady"] else " (not steady)"))
    if not per_speed:
        raise ValueError(f"{results}: no full-order run of '{question}'; run {BENCH_COMMAND} first")
    # a speed with a full-order run and no predictive reduced run is left out, and said
    skipped = sorted(w for w, rows in per_speed.items() if not any(candidate_options(k) for k in rows))
    speeds = sorted(w for w in per_speed if w not in skipped)
    if not speeds:
        raise ValueError(f"{results}: no reduced model was run beside the full order of '{question}'")
    keys = set.intersection(*(set(per_speed[w]) for w in speeds))
    full_cost = sum(c for w, c in full_costs if w in speeds) / len(speeds)      # over the speeds compared
    candidates: list[CandidateRecord] = []
    for key in sorted(keys):
        options = candidate_options(key)
        if options is None:
            continue
        rows = [per_speed[w][key] for w in speeds]
        errors = [r["error"] for r in rows]
        error = math.inf if any(e is None for e in errors) else max(abs(e) for e in errors)
        cost = sum(r["wall_per_revolution_s"] for r in rows) / len(rows)
        model = _runs(store, speeds[0], question)[key].get("details", {}).get("model", "reduced")
        candidates.append(CandidateRecord(name=_name(options, model), options=options, cost=cost, error=error,
                                          held_out_error=None, errors={f"{w:g}": e for w, e in zip(speeds, errors)},
                                          cost_ratio=full_cost / cost, run=key))
    if not candidates:
        raise ValueError(f"{results}: no reduced model was run at every speed of '{question}' ({speeds})")
    return SceneRecord(
        description=(f"GNL in contact at steady state ({question}: mu, normal, damping law, revolutions), ci blade, "
                     f"{len(speeds)} speeds ({', '.join(f'{w:g}' for w in speeds)} rad/s): the largest relative "
                     f"error on the steady max |u_LE| against the full order; not steady anywhere = no error"
                     + (f"; left out (a full order without reduced runs): {', '.join(f'{w:g}' for w in skipped)} "
                        f"rad/s" if skipped else "")),
        cost_unit="s per simulated revolution (one run, one BLAS thread; the cubature's training not included)",
        reference={"options": {"model": f"the full order at steady state ({' / '.join(sorted({reference[w] for w in speeds}))} s), "
                                        f"{BENCH_COMMAND}"},
                   "cost": full_cost, "values": refs},
        candidates=candidates, held_out_case=None)


def _runs(store: dict, speed: float, question: str) -> dict:
    """The runs of the case at ``speed`` of ``question`` in the benchmark's results."""
    return store[f"{speed:g} rad/s {question}"]


def _name(options: dict, model: str) -> str:
    """The candidate's name: its basis, its forces and its size (``model``: the run's 'reduced r = ...')."""
    forces = f"cubature {options['cubature']:g}" if "cubature" in options else "exact tensors"
    return f"r_c {options['r_c']}, MDs of {options['global_md']} modes, {forces} ({model.replace('reduced ', '')})"
