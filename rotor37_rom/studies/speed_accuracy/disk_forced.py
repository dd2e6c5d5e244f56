"""The bladed disk's forced response without contact (scenes ``disk-forced-linear`` / ``disk-forced-gnl``, paper
§3.3): the full-order references of ``studies.forced_response``, the reduced models' runs at the same Newmark step,
scored by the performance indicator's four errors, every run cached under the study's work folder."""
from __future__ import annotations

import functools
import hashlib
import json
import math
import time
import types

import numpy as np

from rotor37_rom.machine import machine_description
from rotor37_rom.npz import save_json
from rotor37_rom.studies.speed_accuracy.context import StudyContext
from rotor37_rom.studies.speed_accuracy.disk_maps import disk_sector
from rotor37_rom.studies.speed_accuracy.study_file import finite_or_none
from rotor37_rom.reporting import say

__all__ = ["scene_disk_forced", "forced_reference", "forced_model", "forced_error", "DISK_FORCED",
           "DISK_FORCED_CASES", "DISK_FORCED_HELD_OUT", "DISK_FORCED_GNL_CASES", "DISK_FORCED_GNL_HELD_OUT",
           "DISK_FORCED_PATCH_MM", "DISK_FORCED_CANDIDATES", "DISK_FORCED_GNL_CANDIDATES"]

DISK_FORCED = dict(periods=10.0, steps_per_period=100, ramp=1.0)     # bench_disk_forced.py's defaults (Newmark, T/100)
DISK_FORCED_CASES = ((0, 4000.0), (0, 13000.0), (9, 4000.0), (9, 13000.0))       # (N_d, omega rad/s)
DISK_FORCED_HELD_OUT = ((0, 17000.0), (9, 17000.0))
DISK_FORCED_GNL_CASES = ((0, 4000.0),)
DISK_FORCED_GNL_HELD_OUT = ((0, 13000.0),)
DISK_FORCED_PATCH_MM = 3.0          # GNL: the 400 N over a 3 mm patch (a point load collapses the GNL reference)
_FORCED_MODEL = {"r_c": 10, "r_md": 0, "r_cyclic": 144}              # the §3.3 models' basis (r_b = 3, node LE)
DISK_FORCED_CANDIDATES = (  # node LE kept (r_b = 3) in every sector; GNL off; r_md by MI 2b (in the basis only)
    ("r_c 10, r_cyclic 144", _FORCED_MODEL),
    ("r_c 5, r_cyclic 144", {**_FORCED_MODEL, "r_c": 5}),
    ("r_c 2, r_cyclic 144", {**_FORCED_MODEL, "r_c": 2}),
    ("r_c 10, r_cyclic 72", {**_FORCED_MODEL, "r_cyclic": 72}),
    ("r_c 5, r_cyclic 72", {**_FORCED_MODEL, "r_c": 5, "r_cyclic": 72}),
    ("r_c 10, r_cyclic 288", {**_FORCED_MODEL, "r_cyclic": 288}),
    ("r_c 10, r_MD 10, r_cyclic 144", {**_FORCED_MODEL, "r_md": 10}),
)
DISK_FORCED_GNL_CANDIDATES = (  # the patch's static correction in every basis; exact sector tensors
    ("r_MD 0 (GNL neglected)", {**_FORCED_MODEL, "face_shapes": 0}),
    ("MI 2b r_MD 10, eq. 61", {**_FORCED_MODEL, "r_md": 10, "face_shapes": 0}),
    ("MI 2b r_MD 20, eq. 61", {**_FORCED_MODEL, "r_md": 20, "face_shapes": 0}),
    ("MI 2b r_MD 20, 6 face shapes", {**_FORCED_MODEL, "r_md": 20, "face_shapes": 6}),
)


@functools.lru_cache(maxsize=None)
def _forced_sector():
    """The ci disk sector, its operators and its free K and M (the indicator's norms)."""
    from rotor37_rom import fem

    sector, ops = disk_sector()
    K_s = fem.petsc_to_scipy(fem.assemble_stiffness(sector, ops, clamped=False))
    M_s = fem.petsc_to_scipy(fem.assemble_mass(sector, ops, clamped=False))
    return sector, ops, K_s, M_s


def forced_reference(ctx: StudyContext, case: tuple, gnl: bool) -> dict:
    """The full-order history of one case (bench_disk_forced.reference: the sectors of one repeat closed on
    themselves, implicit Newmark at the scene's step; cached under results/speed_accuracy/disk_forced/ci, a GNL run
    checkpointed and resumed)."""
    from rotor37_rom.studies import forced_response as bdf

    sector, ops, *_ = _forced_sector()
    out = ctx.work / "disk_forced" / "ci"
    out.mkdir(parents=True, exist_ok=True)
    before = set(out.glob("fom_*.npz"))
    ref = bdf.reference(sector, types.SimpleNamespace(ops=ops), case, gnl,
                        DISK_FORCED["periods"], DISK_FORCED["steps_per_period"], DISK_FORCED["ramp"], out,
                        patch_mm=DISK_FORCED_PATCH_MM if gnl else 0.0)
    if set(out.glob("fom_*.npz")) - before:           # computed (or finished from a checkpoint), not read
        ctx.forced_runs.append(None)
    return ref


def forced_model(ctx: StudyContext, options: dict, gnl: bool):
    """The §3.3 disk model of ``options`` (node LE kept, r_b = 3; r_md by MI 2b; GNL: the patch's static correction
    and exact tensors with eq. 61's force or ``face_shapes``), built once (cached under results/speed_accuracy)."""
    from rotor37_rom.reduction.disk_builder import DiskReductionConfig, build_disk_model

    sector, ops, *_ = _forced_sector()
    config = DiskReductionConfig(tip_nodes="LE", r_c=options["r_c"], r_md=options["r_md"], criterion="MI2b",
                                 r_cyclic=options["r_cyclic"],
                                 forces="intrusive" if gnl and options["r_md"] else "none",
                                 load_patch=1e-3 * DISK_FORCED_PATCH_MM if gnl else 0.0,
                                 face_shapes=options.get("face_shapes", 0) if gnl and options["r_md"] else 0)
    t0 = time.perf_counter()
    model, built = build_disk_model(sector, config, ops=ops, cache_dir=ctx.work / "disk_forced" / "ci" / "models")
    return model, (None if built.get("cached") else time.perf_counter() - t0)


def forced_error(ctx: StudyContext, model, case: tuple, gnl: bool, ref: dict) -> dict:
    """One reduced run of ``case`` against its reference (bench_disk_forced.reduced, the same Newmark and step), scored
    by the performance indicator's four criteria (loaded node, tip nodes, field, strain energy); ``error`` is their
    largest. Cached by the model's key: a re-run of the study reads it."""
    from rotor37_rom.studies import forced_response as bdf
    from rotor37_rom.disk.indicators import performance_indicator

    sector, _, K_s, M_s = _forced_sector()
    spec = json.dumps([model.key, list(case), gnl, DISK_FORCED, DISK_FORCED_PATCH_MM if gnl else 0.0,
                       float(ref["wall"])], sort_keys=True)
    path = ctx.work / "disk_forced" / "ci" / f"rom_{hashlib.sha1(spec.encode()).hexdigest()[:16]}.json"
    if path.is_file():
        return json.loads(path.read_text())            # a failure's error is inf (JSON's Infinity)
    t0 = time.perf_counter()
    try:
        rom = bdf.reduced(model, sector, case, gnl and model.forces is not None, DISK_FORCED["periods"],
                          DISK_FORCED["steps_per_period"], DISK_FORCED["ramp"], ref,
                          patch_mm=DISK_FORCED_PATCH_MM if gnl else 0.0)
    except RuntimeError as exc:                        # Newton failed even at dt / 32: a failure, not a result
        wall = time.perf_counter() - t0
        out = dict(error=math.inf, I=0.0, errors={}, wall_s=wall, us_per_step=None, failed=str(exc))
    else:
        score = performance_indicator(ref["tip"], rom["tip"], ref["fields"], rom["fields"], K_s, M_s,
                                      loaded=(sector.tip_names.index("LE"), 2))
        out = dict(error=max(score["errors"].values()), I=score["I"], errors=score["errors"], wall_s=rom["wall"],
                   us_per_step=1e6 * rom["wall"] / rom["steps"])
    ctx.forced_runs.append(out["wall_s"])
    save_json(path, out, default=finite_or_none)
    return out


def scene_disk_forced(ctx: StudyContext, gnl: bool = False) -> dict:
    """The bladed disk's forced response without contact (paper §3.3): 400 N along e_z at node LE of every sector
    travelling with N_d diameters, ramped over one period, 10 periods, implicit Newmark at T/100 for the full order (one
    repeat of sectors closed on themselves) and the reduced models alike, so the error is the reduction's. GNL off:
    N_d 0 and 9 at 4,000 and 13,000 rad/s, held out 17,000 rad/s; GNL on: the load over a 3 mm patch, N_d 0 at 4,000
    rad/s, held out 13,000 rad/s (a GNL reference of N_d 9 would carry 4 sectors)."""
    name = "disk-forced-gnl" if gnl else "disk-forced-linear"
    cases, held_cases = ((DISK_FORCED_GNL_CASES, DISK_FORCED_GNL_HELD_OUT) if gnl
                         else (DISK_FORCED_CASES, DISK_FORCED_HELD_OUT))
    refs = {case: forced_reference(ctx, case, gnl) for case in cases}
    ref_wall = sum(float(r["wall"]) for r in refs.values())
    steps = sum(r["tip"].shape[0] - 1 for r in refs.values())
    say(f"{name}: full-order references {ref_wall:.0f} s")
    cands, models = [], {}
    for cname, options in (DISK_FORCED_GNL_CANDIDATES if gnl else DISK_FORCED_CANDIDATES):
        model, build = models[cname] = forced_model(ctx, options, gnl)
        runs = {case: forced_error(ctx, model, case, gnl, refs[case]) for case in cases}
        worst = max(runs, key=lambda c: runs[c]["error"])
        wall = sum(r["wall_s"] for r in runs.values())
        cands.append(dict(name=cname, options=options, r=model.r, build_s=build, cost=wall,
                          us_per_step=1e6 * wall / steps, h=None, error=runs[worst]["error"],
                          held_out_error=None, I=min(r["I"] for r in runs.values()),
                          worst_case={"N_d": worst[0], "omega": worst[1]}, errors=runs[worst]["errors"],
                          by_case=[{"N_d": c[0], "omega": c[1], **runs[c]} for c in cases]))
        say(f"{name}: {cname}: r = {model.r}, {wall:.1f} s, error {runs[worst]['error']:.3g} (I >= "
              f"{cands[-1]['I']:.3f}; worst N_d {worst[0]} at {worst[1]:g} rad/s)")
    load = (f"400 N along e_z over a {DISK_FORCED_PATCH_MM:g} mm patch around node LE of every sector" if gnl
            else "400 N along e_z at node LE of every sector")
    le = _forced_sector()[0].tip_names.index("LE")
    where = ", ".join(f"N_d {nd} at {w:,.0f} rad/s" for nd, w in cases)
    scene = dict(description=f"the bladed disk's forced response without contact (§3.3), GNL {'on' if gnl else 'off'}"
                             f": {load}, travelling with N_d diameters, ramped over one period, "
                             f"{DISK_FORCED['periods']:g} periods from rest ({where}), implicit Newmark at T/100 for "
                             "the full order and the models alike (the error is the reduction's); node LE kept in "
                             "every sector (r_b = 3)" + (", the patch's static correction in every basis, exact "
                                                         "sector tensors" if gnl else "") +
                             ": the largest of the performance indicator's four relative errors (loaded node, tip "
                             "nodes, M- and K-norm of the sector fields) over the cases",
                 cost_unit="s (the reduced runs' wall time over the cases; the build is not included)",
                 reference=dict(options={"model": "full order, one repeat of sectors closed on themselves",
                                         "preset": "ci"}, cost=ref_wall, wall_s=ref_wall,
                                us_per_step=1e6 * ref_wall / steps,
                                cases=[{"N_d": c[0], "omega": c[1], "wall_s": float(r["wall"]),
                                        "max_le_z_mm": 1e3 * float(np.abs(r["tip"][:, :, le, 2]).max()),
                                        "newton_per_step": float(np.mean(r["iterations"])) if gnl else None}
                                       for c, r in refs.items()]),
                 candidates=cands, machine=machine_description(),
                 held_out_case=", ".join(f"N_d {nd} at {w:,.0f} rad/s" for nd, w in held_cases)
                 + " (every candidate run there)")
    try:
        held = {case: forced_reference(ctx, case, gnl) for case in held_cases}
    except RuntimeError as exc:          # the full order's Newton failed: no yardstick there, and the page says so
        scene["held_out_case"] += f": its full-order reference failed ({exc}), so no model has a held-out check"
        return scene
    for cand in cands:                   # every candidate (a reduced run costs less than the references): the chooser
        runs = [forced_error(ctx, models[cand["name"]][0], case, gnl, held[case]) for case in held_cases]
        cand["held_out_error"] = max(run["error"] for run in runs)   # then judges each one by both, at any tolerance
        failed = [run["failed"] for run in runs if "failed" in run]
        if failed:
            cand["held_out_failed"] = failed[0]
        say(f"{name}: held out: {cand['name']}: {cand['held_out_error']:.3g}")
    return scene
