"""The single blade's map scenes: the interaction map without and with GNL (``map-linear`` / ``map-gnl``, with the LE
time history of the same runs, ``history-*``) against a reference map, the speeds robust to a 1e-4 perturbation, and
the chosen models' held-out maps."""
from __future__ import annotations

import math

import numpy as np

from rotor37_rom.studies.speed_accuracy.context import HELD_OUT_SPEEDS, PERTURBATION, ROBUST, TOLERANCES, StudyContext
from rotor37_rom.studies.speed_accuracy.maps import MapRun, held_out_choices, held_out_options, model_file, run_map
from rotor37_rom.reporting import say

__all__ = ["scene_map", "held_out_map", "map_errors", "LINEAR_CANDIDATES", "GNL_CANDIDATES"]


def map_errors(run: MapRun, ref: MapRun, robust: np.ndarray) -> dict:
    """NFRC error on the robust speeds (relative to the reference's peak there), resonance speed and peak errors,
    and the LE history error at the robust speed of largest reference response."""
    from rotor37_rom.studies.sweep import record_row

    if run.diverged.any():
        return dict(nfrc=math.inf, speed=math.inf, peak=math.inf, map=math.inf, history=math.inf)
    peak_ref = np.nanmax(ref.nfrc[robust])
    nfrc = float(np.abs(run.nfrc[robust] - ref.nfrc[robust]).max() / peak_ref)
    i_ref, i = int(np.nanargmax(ref.nfrc)), int(np.nanargmax(run.nfrc))
    speed = abs(run.speeds[i] - ref.speeds[i_ref]) / ref.speeds[i_ref]
    peak = abs(run.nfrc[i] - ref.nfrc[i_ref]) / ref.nfrc[i_ref]
    k = int(np.flatnonzero(robust)[np.argmax(ref.nfrc[robust])])
    rec, rec_ref = run.records[k], ref.records[k]
    u_ref = np.asarray(rec_ref["u_r"])[record_row(rec_ref)]
    u = np.interp(rec_ref["t"], rec["t"], np.asarray(rec["u_r"])[record_row(rec)])
    history = float(np.abs(u - u_ref).max() / np.abs(u_ref).max())
    return dict(nfrc=nfrc, speed=float(speed), peak=float(peak), map=max(nfrc, speed, peak), history=history,
                history_speed=float(ref.speeds[k]))


LINEAR_CANDIDATES = (  # (name, options); the reference is r_c 40, no cap, h = 0.5 h_crit
    ("r_c 15", {"r_c": 15}), ("r_c 25", {"r_c": 25}),
    ("r_c 15, h 0.9 h_crit", {"r_c": 15, "safety": 0.9}),
    ("r_c 15, cap 120 kHz", {"r_c": 15, "frequency_cap": 120.0}),
    ("r_c 15, cap 60 kHz", {"r_c": 15, "frequency_cap": 60.0}),
    ("r_c 15, cap 30 kHz", {"r_c": 15, "frequency_cap": 30.0}),
    ("r_c 25, cap 60 kHz", {"r_c": 25, "frequency_cap": 60.0}),
    ("r_c 25, cap 30 kHz", {"r_c": 25, "frequency_cap": 30.0}),
    ("r_c 5, cap 60 kHz", {"r_c": 5, "frequency_cap": 60.0}),
    ("r_c 40, cap 120 kHz", {"r_c": 40, "frequency_cap": 120.0}),
    ("r_c 40, cap 60 kHz", {"r_c": 40, "frequency_cap": 60.0}),
)
GNL_CANDIDATES = (  # the reference is r_c 15 (r = 45) with exact tensors, no cap, h = 0.5 h_crit
    ("r_c 10", {"r_c": 10}),
    ("cap 120 kHz", {"r_c": 15, "frequency_cap": 120.0}),
    ("cap 60 kHz", {"r_c": 15, "frequency_cap": 60.0}),
    ("cubature 1e-4, cap 120 kHz", {"r_c": 15, "frequency_cap": 120.0, "cubature": 1e-4}),
    ("cubature 1e-4 float32, cap 120 kHz", {"r_c": 15, "frequency_cap": 120.0, "cubature": 1e-4,
                                            "precision": "single"}),
    ("cubature 1e-4, cap 120 kHz, retries", {"r_c": 15, "frequency_cap": 120.0, "cubature": 1e-4,
                                             "retry_diverged": 2}),
    ("r_c 10, retries", {"r_c": 10, "retry_diverged": 2}),
    ("cubature 1e-4", {"r_c": 15, "cubature": 1e-4}),
    ("cubature 1e-4 float32", {"r_c": 15, "cubature": 1e-4, "precision": "single"}),
    ("cubature 1e-5 float32", {"r_c": 15, "cubature": 1e-5, "precision": "single"}),
    ("cubature 1e-5", {"r_c": 15, "cubature": 1e-5}),
    ("cubature 1e-6 float32", {"r_c": 15, "cubature": 1e-6, "precision": "single"}),
)


def scene_map(ctx: StudyContext, gnl: bool) -> tuple[dict, dict]:
    """The map scene and the history scene of one setting (GNL off: the reference r_c 40; on: r_c 15, exact
    tensors; both uncapped at h = 0.5 h_crit): every candidate of ``LINEAR_CANDIDATES`` / ``GNL_CANDIDATES`` judged
    on the speeds the reference's 1e-4 perturbation moves by at most 1 % of its peak."""
    ref_options = {"r_c": 15} if gnl else {"r_c": 40}
    ref = run_map(ctx, "reference", gnl, ref_options)
    pert_path = ctx.work / "models" / f"rom_rc{ref_options['r_c']}_perturbed_{'gnl' if gnl else 'linear'}.npz"
    from rotor37_rom.model.reduced import load_reduced_model, perturbed_model, save_reduced_model

    perturbed = perturbed_model(load_reduced_model(model_file(ctx, ref_options["r_c"])), PERTURBATION)
    if not pert_path.is_file() or load_reduced_model(pert_path).key != perturbed.key:
        save_reduced_model(perturbed, pert_path)
    pert = run_map(ctx, "reference_perturbed", gnl, ref_options, model_path=pert_path)
    peak = np.nanmax(ref.nfrc)
    robust = np.abs(pert.nfrc - ref.nfrc) <= ROBUST * peak
    say(f"robust speeds: {ref.speeds[robust].tolist()}")
    cands, hist = [], []
    for name, options in (GNL_CANDIDATES if gnl else LINEAR_CANDIDATES):
        run = run_map(ctx, name, gnl, options)
        err = map_errors(run, ref, robust)
        base = dict(name=name, options=options, us_per_step=1e6 * run.sweep_wall / run.sim_steps, h=run.h,
                    wall_s=run.wall, sweep_s=run.sweep_wall, diverged=int(run.diverged.sum()))
        cost = run.sweep_wall
        cands.append(dict(base, cost=cost, error=err["map"], errors={k: err[k] for k in ("nfrc", "speed", "peak")},
                          held_out_error=None))
        hist.append(dict(base, cost=cost, error=err["history"], held_out_error=None,
                         history_speed=err.get("history_speed")))
    ref_info = dict(options=ref_options, h=ref.h, sweep_s=ref.sweep_wall, wall_s=ref.wall,
                    us_per_step=1e6 * ref.sweep_wall / ref.sim_steps,
                    peak_speed=float(ref.speeds[np.nanargmax(ref.nfrc)]),
                    peak_m=float(peak), robust_speeds=ref.speeds[robust].tolist(), perturbation=PERTURBATION,
                    robust_threshold=ROBUST)
    kind = "GNL" if gnl else "GNL off"
    setting = "11 speeds in 1,200-1,600 rad/s x 8 revolutions, mu = 0, e_x, ci blade"
    maps = dict(description=f"interaction map, {kind}, {setting}: largest of the NFRC error on the robust speeds, the "
                            f"resonance speed's and the peak's relative errors",
                cost_unit="s (sweep wall time of the map)", reference=ref_info, candidates=cands,
                held_out_case=f"10 other speeds in {HELD_OUT_SPEEDS[0]:g}-{HELD_OUT_SPEEDS[1]:g} rad/s")
    history = dict(description=f"LE time history, {kind}, {setting}: max |u - u_ref| / max |u_ref| at the robust speed "
                               f"of largest reference response",
                   cost_unit="s (sweep wall time of the map)", reference=ref_info, candidates=hist,
                   held_out_case=None)
    return maps, history


def held_out_map(ctx: StudyContext, scene: dict, gnl: bool, tolerances=TOLERANCES) -> None:
    """Run the models chosen at each tolerance on the held-out speeds; a miss is recorded on the candidate, and the
    chooser then passes it over for the next cheapest (the loop goes on until a choice holds on the held-out case)."""
    ref_options = scene["reference"]["options"]
    ref = run_map(ctx, "reference", gnl, ref_options, speeds=HELD_OUT_SPEEDS)
    pert_path = ctx.work / "models" / f"rom_rc{ref_options['r_c']}_perturbed_{'gnl' if gnl else 'linear'}.npz"
    pert = run_map(ctx, "reference_perturbed", gnl, ref_options, speeds=HELD_OUT_SPEEDS, model_path=pert_path)
    robust = np.abs(pert.nfrc - ref.nfrc) <= ROBUST * np.nanmax(ref.nfrc)
    held_out_choices(scene, tolerances, lambda name, options: map_errors(
        run_map(ctx, name, gnl, held_out_options(options), speeds=HELD_OUT_SPEEDS), ref, robust)["map"])
    scene["held_out_reference"] = dict(robust_speeds=ref.speeds[robust].tolist(), sweep_s=ref.sweep_wall)
