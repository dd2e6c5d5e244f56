"""The bladed disk's short interaction maps (scenes ``disk-map-linear`` / ``disk-map-gnl``): the disk models built
and saved for the map command, the speeds robust to the reference's 1e-4 perturbation, the errors over the blades,
the scene's floor (what the reference's own cap is worth) and the chosen models' held-out maps."""
from __future__ import annotations

import functools
import math
from pathlib import Path

import numpy as np

from rotor37_rom.machine import machine_description
from rotor37_rom.studies.speed_accuracy.context import PERTURBATION, ROBUST, TOLERANCES, StudyContext, percent
from rotor37_rom.studies.speed_accuracy.maps import MapRun, held_out_choices, held_out_options, run_map
from rotor37_rom.reporting import say

__all__ = ["scene_disk_map", "run_disk_map", "disk_model_file", "disk_sector", "disk_map_errors", "disk_robust",
           "largest_over_blades", "cap_floor", "floor_record", "DISK_MAP", "DISK_GNL_MAP", "DISK_HELD_OUT_SPEEDS",
           "DISK_MAP_REFERENCE", "DISK_GNL_REFERENCE", "DISK_MAP_CANDIDATES", "DISK_GNL_CANDIDATES"]

# ## The bladed disk's interaction map without GNL: basis, interface modes and frequency cap

DISK_MAP = dict(preset="ci", speeds=(1200.0, 1650.0, 8), revolutions=20.0, mu=0.15, direction="cone", quiet=True,
                batch=8)                     # the disk maps' casing (cone normal, the paper's mu) and short map
DISK_HELD_OUT_SPEEDS = (1230.0, 1620.0, 7)      # between the study's speeds (every 64.3 rad/s)
DISK_MAP_REFERENCE = {"r_c": 10, "r_md": 10, "r_cyclic": 288, "frequency_cap": 240.0}
DISK_GNL_MAP = {**DISK_MAP, "revolutions": 12.0}     # GNL: the sectors' forces batched, 12 revolutions
DISK_GNL_REFERENCE = {"r_c": 10, "r_md": 10, "r_cyclic": 288, "frequency_cap": 120.0}     # exact sector tensors
_MAPS_MODEL = {"r_c": 10, "r_md": 10, "r_cyclic": 144, "frequency_cap": 60.0}   # the disk contact maps' model
DISK_MAP_CANDIDATES = (  # every sector's 8 tip nodes; r_md by MI 2b
    ("the maps' model, cap 30 kHz", {**_MAPS_MODEL, "frequency_cap": 30.0}),
    ("the maps' model, cap 60 kHz", _MAPS_MODEL),
    ("the maps' model, cap 120 kHz", {**_MAPS_MODEL, "frequency_cap": 120.0}),
    ("r_c 10, r_cyclic 144, cap 60 kHz", {**_MAPS_MODEL, "r_md": 0}),
    ("r_c 10, r_cyclic 72, cap 60 kHz", {**_MAPS_MODEL, "r_md": 0, "r_cyclic": 72}),
    ("r_c 10, r_cyclic 72, cap 30 kHz", {**_MAPS_MODEL, "r_md": 0, "r_cyclic": 72, "frequency_cap": 30.0}),
    ("r_c 5, r_cyclic 72, cap 60 kHz", {**_MAPS_MODEL, "r_c": 5, "r_md": 0, "r_cyclic": 72}),
    ("r_c 2, r_cyclic 144, cap 60 kHz", {**_MAPS_MODEL, "r_c": 2, "r_md": 0}),
    ("the reference's model, cap 120 kHz", {**DISK_MAP_REFERENCE, "frequency_cap": 120.0}),   # its cap's own error
)
DISK_GNL_CANDIDATES = (  # with GNL: exact sector tensors unless a cubature (trained, capped, at the study's speeds)
    ("the maps' model, exact, cap 60 kHz", _MAPS_MODEL),
    ("the maps' model, cubature 1e-2 float32, cap 60 kHz", {**_MAPS_MODEL, "cubature": 1e-2, "precision": "single"}),
    ("the maps' model, cubature 3e-3 float32, cap 60 kHz", {**_MAPS_MODEL, "cubature": 3e-3, "precision": "single"}),
    ("the maps' model, cubature 1e-3 float32, cap 60 kHz", {**_MAPS_MODEL, "cubature": 1e-3, "precision": "single"}),
    ("r_c 10, r_cyclic 144, exact, cap 60 kHz", {**_MAPS_MODEL, "r_md": 0}),
    ("the reference's model, exact, cap 60 kHz", {**DISK_GNL_REFERENCE, "frequency_cap": 60.0}),
)


@functools.lru_cache(maxsize=None)
def disk_sector():
    """The ci disk sector and its operators, made once per process."""
    from rotor37_rom import fem

    sector = fem.create_disk_sector(preset="ci")
    return sector, fem.create_svk_operators(sector)


def disk_model_file(ctx: StudyContext, options: dict, perturbation: float = 0.0, gnl: bool = False) -> Path:
    """The disk model of ``options`` (r_c, r_md by MI 2b, r_cyclic; every sector's 8 tip nodes; with ``gnl`` the
    sector's exact GNL tensors, else no GNL forces), built once (the Craig-Bampton parts cached with scene
    disk-modes') and saved for the map command's --model; with a ``perturbation`` (GNL off), that model's stiffness
    scaled by 1 + perturbation. Checked once per process."""
    if gnl and perturbation:
        raise ValueError("a GNL disk map is perturbed by the map's own option 'perturbation' (the same probe and "
                         "step), not by a perturbed model file")
    return _disk_model_file(ctx, options["r_c"], options["r_md"], options["r_cyclic"], float(perturbation), bool(gnl))


@functools.lru_cache(maxsize=None)
def _disk_model_file(ctx: StudyContext, r_c: int, r_md: int, r_cyclic: int, perturbation: float, gnl: bool) -> Path:
    from rotor37_rom.reduction.builder import mesh_signature
    from rotor37_rom.reduction.disk_builder import DiskReductionConfig, build_disk_model
    from rotor37_rom.model.reduced import load_reduced_model, perturbed_model, save_reduced_model

    sector, ops = disk_sector()
    stem = f"disk_{mesh_signature(sector)[:12]}_rc{r_c}_md{r_md}_cyc{r_cyclic}" + ("_gnl" if gnl else "")
    # the builder's cache (keyed by every parameter of the reduction) decides: a file saved by an earlier builder is
    # replaced, and so is a perturbed copy of another model (run_map then sees the key change and runs its maps again)
    model, _ = build_disk_model(sector, DiskReductionConfig(tip_nodes="all", r_c=r_c, r_md=r_md, criterion="MI2b",
                                                            r_cyclic=r_cyclic,
                                                            forces="intrusive" if gnl else "none"),
                                ops=ops, cache_dir=ctx.work / "disk_models")
    if perturbation != 0.0:
        model = perturbed_model(model, perturbation)
        stem += f"_perturbed_{perturbation:g}"
    path = ctx.work / "models" / f"{stem}.npz"
    if not path.is_file() or load_reduced_model(path).key != model.key:
        save_reduced_model(model, path)
    return path


def run_disk_map(ctx: StudyContext, name: str, options: dict, speeds=None, perturbation: float = 0.0,
                 gnl: bool = False) -> MapRun:
    """A map of the disk scenes: DISK_MAP (GNL off) or DISK_GNL_MAP at ``speeds`` (default: the scene's)."""
    setup = DISK_GNL_MAP if gnl else DISK_MAP
    return run_map(ctx, name, gnl, options, speeds or setup["speeds"], disk_model_file(ctx, options, perturbation, gnl),
                   setup, "disk_")


def largest_over_blades(run: MapRun) -> np.ndarray:
    """Per speed, the largest over the 36 blades of node LE's max |u| over the last revolution."""
    from rotor37_rom.studies.sweep import sector_maxima

    return np.array([np.nanmax(sector_maxima(r)) if int(r["diverged_step"]) < 0 else np.nan for r in run.records])


def disk_robust(ref: MapRun, pert: MapRun) -> np.ndarray:
    """The speeds where the reference's 1e-4 perturbation moves node LE of sector 0 and the largest blade by at most
    1 % of their peaks over all speeds (as the blade's scenes; the errors are then relative to the peaks over the
    robust speeds, so the threshold is a little looser than 1 % of those)."""
    big, big_p = largest_over_blades(ref), largest_over_blades(pert)
    return ((np.abs(pert.nfrc - ref.nfrc) <= ROBUST * np.nanmax(ref.nfrc))
            & (np.abs(big_p - big) <= ROBUST * np.nanmax(big)))


def disk_map_errors(run: MapRun, ref: MapRun, robust: np.ndarray) -> dict:
    """On the robust speeds only: the NFRC errors of node LE of sector 0 and of the largest blade (relative to the
    reference's peak there), and the resonance speed's and peak's relative errors at node LE of sector 0 (the largest
    response over the robust speeds: on the disk's short map the reference's largest response overall sits in a band
    where the contact selects the response, and the 1e-4 perturbation moves it by 11 %, docs/choosing-a-model.md);
    ``map`` is the largest of the four."""
    if not robust.any():
        raise RuntimeError("no speed of the disk map is robust to the reference's 1e-4 perturbation: the map cannot "
                           "judge a model (more revolutions or other speeds)")
    if run.diverged.any():
        return dict(nfrc=math.inf, largest=math.inf, speed=math.inf, peak=math.inf, map=math.inf)
    sub = np.flatnonzero(robust)
    big, big_ref = largest_over_blades(run), largest_over_blades(ref)
    i_ref, i = sub[np.nanargmax(ref.nfrc[sub])], sub[np.nanargmax(run.nfrc[sub])]
    err = dict(nfrc=float(np.abs(run.nfrc[sub] - ref.nfrc[sub]).max() / ref.nfrc[i_ref]),
               largest=float(np.abs(big[sub] - big_ref[sub]).max() / np.nanmax(big_ref[sub])),
               speed=float(abs(run.speeds[i] - ref.speeds[i_ref]) / ref.speeds[i_ref]),
               peak=float(abs(run.nfrc[i] - ref.nfrc[i_ref]) / ref.nfrc[i_ref]))
    err["map"] = max(err.values())
    return err


def cap_floor(ref_opts: dict, cands: list[dict]) -> dict | None:
    """What the reference's own frequency cap is worth: the error of the candidate that is the reference's model at
    the nearest lower cap (None if no such candidate, or if it lost a speed). Models that differ from the reference
    by less cannot be told apart by the scene: its floor (``studies.model_choice.scene_floor``)."""
    def model(options: dict) -> dict:
        return {k: v for k, v in options.items() if k != "frequency_cap"}

    lower = [c for c in cands if model(c["options"]) == model(ref_opts)
             and c["options"].get("frequency_cap", math.inf) < ref_opts.get("frequency_cap", math.inf)]
    if not lower:
        return None
    c = max(lower, key=lambda c: c["options"]["frequency_cap"])
    if not np.isfinite(c["error"]):
        return None
    return dict(error=c["error"], candidate=c["name"], cap_khz=c["options"]["frequency_cap"])


def floor_record(ref_opts: dict, cands: list[dict], moved: float | None = None) -> dict | None:
    """A scene's floor: the larger of what the reference's cap is worth (``cap_floor``) and, for a stress scene, how
    far the reference's 1e-4 perturbation moves the stress (``moved``; inf if the perturbed run diverged). None if
    neither is known."""
    cap = cap_floor(ref_opts, cands)
    why = [] if cap is None else [f"the reference's own model at {cap['cap_khz']:g} kHz is {percent(cap['error'])} "
                                  "off it"]
    if moved is not None:
        moved = moved if np.isfinite(moved) else math.inf
        why.append(f"the reference's {PERTURBATION:g} perturbation moves the stress by {percent(moved)}"
                   if np.isfinite(moved) else f"the reference's run perturbed by {PERTURBATION:g} diverged")
    if not why:
        return None
    record = dict(error=max(0.0 if cap is None else cap["error"], 0.0 if moved is None else moved), cap=cap,
                  why=" and ".join(why))
    return record if moved is None else dict(record, perturbation=moved)


def scene_disk_map(ctx: StudyContext, gnl: bool = False) -> tuple[dict, dict]:
    """The disk's short interaction map (8 speeds in 1,200-1,650 rad/s from rest, the disk maps' casing: cone normal,
    mu = 0.15), GNL off (20 revolutions) or on (12), against the largest model at the highest cap; held out: 7 other
    speeds. With GNL the reference's 1e-4 perturbation is the map's own option (the same probe and step)."""
    scene_name = "disk-map-gnl" if gnl else "disk-map-linear"
    ref_opts = DISK_GNL_REFERENCE if gnl else DISK_MAP_REFERENCE
    setup = DISK_GNL_MAP if gnl else DISK_MAP

    def reference_maps(speeds=None) -> tuple[MapRun, MapRun]:
        ref = run_disk_map(ctx, "reference", ref_opts, speeds, gnl=gnl)
        if gnl:
            pert = run_disk_map(ctx, "reference_perturbed", {**ref_opts, "perturbation": PERTURBATION}, speeds,
                                gnl=True)
        else:
            pert = run_disk_map(ctx, "reference_perturbed", ref_opts, speeds, PERTURBATION)
        return ref, pert

    ref, pert = reference_maps()
    runs = {"reference": ref, "reference_perturbed": pert}     # for the stress scene: the maps' final states
    robust = disk_robust(ref, pert)
    say(f"{scene_name}: robust speeds {ref.speeds[robust].round(1).tolist()}")
    cands = []
    for name, options in (DISK_GNL_CANDIDATES if gnl else DISK_MAP_CANDIDATES):
        run = runs[name] = run_disk_map(ctx, name, options, gnl=gnl)
        err = disk_map_errors(run, ref, robust)
        cands.append(dict(name=name, options=options, us_per_step=1e6 * run.sweep_wall / run.sim_steps, h=run.h,
                          wall_s=run.wall, sweep_s=run.sweep_wall, diverged=int(run.diverged.sum()),
                          cost=run.sweep_wall, error=err["map"], held_out_error=None,
                          errors={k: err[k] for k in ("nfrc", "largest", "speed", "peak")}))
        say(f"{scene_name}: {name}: {run.sweep_wall:.0f} s, error {err['map']:.3g} "
              f"({', '.join(f'{k} {err[k]:.3g}' for k in ('nfrc', 'largest', 'speed', 'peak'))})")
    big, top = largest_over_blades(ref), int(np.nanargmax(ref.nfrc))
    i_rob = int(np.flatnonzero(robust)[np.nanargmax(ref.nfrc[robust])])
    forces = ("; GNL forces: the sectors' exact tensors, or a point cubature trained with the cap on the study's "
              "speeds" if gnl else "")
    scene = dict(description=f"the bladed disk's short interaction map, GNL {'on' if gnl else 'off'}, 8 speeds in "
                             f"1,200-1,650 rad/s x {setup['revolutions']:g} revolutions from rest, the disk maps' "
                             f"casing (cone normal, mu = 0.15), 36 ci sectors with 8 tip nodes each{forces}: on the "
                             "robust speeds, the largest of the NFRC errors (node LE of sector 0 and the largest over "
                             "the blades) and of the relative errors of the speed and the amplitude of the largest "
                             "response at node LE of sector 0",
                 cost_unit="s (sweep wall time of the map)",
                 reference=dict(options=ref_opts, h=ref.h, sweep_s=ref.sweep_wall, wall_s=ref.wall,
                                us_per_step=1e6 * ref.sweep_wall / ref.sim_steps,
                                peak_speed=float(ref.speeds[np.nanargmax(ref.nfrc)]), peak_m=float(np.nanmax(ref.nfrc)),
                                largest_peak_m=float(np.nanmax(big)), robust_speeds=ref.speeds[robust].tolist(),
                                peak_moved_by_perturbation=float(abs(pert.nfrc[top] - ref.nfrc[top]) / ref.nfrc[top]),
                                robust_peak_speed=float(ref.speeds[i_rob]), robust_peak_m=float(ref.nfrc[i_rob]),
                                perturbation=PERTURBATION, robust_threshold=ROBUST),
                 candidates=cands, machine=machine_description(),
                 held_out_case=f"{DISK_HELD_OUT_SPEEDS[2]} other speeds in {DISK_HELD_OUT_SPEEDS[0]:g}-"
                               f"{DISK_HELD_OUT_SPEEDS[1]:g} rad/s" + (
                                   "; a cubature as trained on the study's speeds (its capped training step from the "
                                   "held-out map's probe)" if gnl else ""))
    floor = floor_record(ref_opts, cands)
    if floor is not None:
        scene["floor"] = floor
    ref_h, pert_h = reference_maps(DISK_HELD_OUT_SPEEDS)
    robust_h = disk_robust(ref_h, pert_h)
    scene["held_out_reference"] = dict(robust_speeds=ref_h.speeds[robust_h].tolist(), sweep_s=ref_h.sweep_wall)
    if robust_h.any():
        held_out_choices(scene, TOLERANCES, lambda name, options: disk_map_errors(
            run_disk_map(ctx, name, held_out_options(options, setup), DISK_HELD_OUT_SPEEDS, gnl=gnl), ref_h,
            robust_h)["map"])
    else:        # a check on no speed would judge nothing: the choice rests on the study's speeds, and says so
        scene["held_out_case"] += (": none of them robust to the reference's 1e-4 perturbation, so no model could be "
                                   "judged there (the choices rest on the study's speeds alone)")
    return scene, runs
