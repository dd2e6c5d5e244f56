"""The bladed disk's stress scenes (``disk-stress-linear`` / ``disk-stress-gnl``): von Mises at t_max of one
revolution carried on from each disk map's final state at the reference's largest robust response, every sector
rebuilt from q."""
from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np

from rotor37_rom.machine import machine_description
from rotor37_rom.studies.speed_accuracy.context import PERTURBATION, StudyContext, percent
from rotor37_rom.studies.speed_accuracy.disk_maps import disk_model_file, disk_sector, floor_record
from rotor37_rom.studies.speed_accuracy.maps import MapRun
from rotor37_rom.reporting import say

__all__ = ["scene_disk_stress", "disk_stress_at_tmax"]


def disk_stress_at_tmax(run: MapRun, model_path: Path, speed: float, gnl: bool = False) -> dict:
    """The disk's von Mises stress at t_max (largest |u| of node LE of sector 0) of one revolution carried on from
    ``run``'s final state at ``speed`` (what ``contact_map.py --stress`` does at the map's largest response), every
    sector rebuilt from q: the largest off the root corner and outside the tip band in sector 0 and over the sectors
    (``post.stress.disk_stress_summary``: the numbers that converge with the mesh), with the wall time."""
    from rotor37_rom.model.reduced import load_reduced_model
    from rotor37_rom.studies import contact_map as cm

    sector, _ = disk_sector()
    model = load_reduced_model(model_path)
    k = int(np.argmin(np.abs(run.speeds - speed)))
    if not np.isclose(run.speeds[k], speed):
        raise ValueError(f"the map has no run at {speed} rad/s (its speeds: {run.speeds.tolist()})")
    gone = dict(vm=math.inf, vm_all=math.inf, sector_of_max=None, u_le=math.nan)
    if int(run.records[k]["diverged_step"]) >= 0:          # nothing to carry on
        return dict(gone, seconds=0.0)
    scheme = cm.time_scheme(run.config, model, gnl, None, h=run.record_h[k])      # the map's forces (its cubature)
    t0 = time.perf_counter()
    res, _ = cm.carry_on_record(run.config, scheme, run.records[k], float(run.records[k]["omega"]),
                                [model.nodes.label_row(run.config.node)])
    if res.diverged_step[0] >= 0:
        return dict(gone, seconds=time.perf_counter() - t0)
    *_, numbers, _ = cm.disk_stress_of(sector, model, res, gnl, 0)
    return dict(vm=numbers["vm_max_off_root"], vm_all=numbers["vm_max_off_root_all_sectors"],
                sector_of_max=numbers["sector_of_max_off_root"], u_le=numbers["u_le"],
                seconds=time.perf_counter() - t0)


def scene_disk_stress(ctx: StudyContext, maps: dict, runs: dict, gnl: bool = False) -> dict:
    """von Mises at t_max in the disk, GNL off or on, at the reference's largest robust response of the disk map
    scene, for its reference and candidates (``runs``: the map scene's MapRuns by name, the stress needs a map's final
    state); error: the larger of the relative errors in sector 0 and over the sectors, off the root corner."""
    scene = "disk-stress-gnl" if gnl else "disk-stress-linear"
    ref_opts, speed = maps["reference"]["options"], maps["reference"]["robust_peak_speed"]
    ref = disk_stress_at_tmax(runs["reference"], disk_model_file(ctx, ref_opts, gnl=gnl), speed, gnl)
    if not np.isfinite(ref["vm"]):
        raise RuntimeError(f"{scene}: the reference's run at {speed:g} rad/s diverged")
    # the perturbed reference's map carried on alike (GNL: the map's own perturbation option; off: its model file)
    pert_file = disk_model_file(ctx, ref_opts, 0.0 if gnl else PERTURBATION, gnl=gnl)
    pert = disk_stress_at_tmax(runs["reference_perturbed"], pert_file, speed, gnl)
    moved = max(abs(pert["vm"] - ref["vm"]) / ref["vm"], abs(pert["vm_all"] - ref["vm_all"]) / ref["vm_all"])
    say(f"{scene}: the reference {ref['vm'] / 1e6:.4g} / {ref['vm_all'] / 1e6:.4g} MPa, perturbed by "
          f"{PERTURBATION:g}: {pert['vm'] / 1e6:.4g} / {pert['vm_all'] / 1e6:.4g} MPa ({percent(moved)})")
    cands = []
    for c in maps["candidates"]:
        if not np.isfinite(c["error"]):              # a map that lost a speed: no model for the scene
            out = dict(vm=math.inf, vm_all=math.inf, sector_of_max=None, u_le=math.nan, seconds=0.0)
        else:
            out = disk_stress_at_tmax(runs[c["name"]], disk_model_file(ctx, c["options"], gnl=gnl), speed, gnl)
        err = max(abs(out["vm"] - ref["vm"]) / ref["vm"], abs(out["vm_all"] - ref["vm_all"]) / ref["vm_all"])
        err = err if np.isfinite(err) else math.inf
        say(f"{scene}: {c['name']}: sector 0 {out['vm'] / 1e6:.4g} MPa, over the sectors "
              f"{out['vm_all'] / 1e6:.4g} MPa ({percent(err)}), {out['seconds']:.1f} s")
        cands.append(dict(name=c["name"], options=c["options"], us_per_step=c["us_per_step"], h=c["h"],
                          cost=c["cost"] + out["seconds"], error=err, vm_max=out["vm"], vm_max_all=out["vm_all"],
                          sector_of_max=out["sector_of_max"], u_le=out["u_le"], carry_on_s=out["seconds"],
                          held_out_error=None))
    return dict(description=f"the bladed disk's largest von Mises stress off the root corner and outside the tip band "
                            f"at t_max of one revolution carried on from the disk map scene's final states at the "
                            f"reference's largest robust response ({speed:.0f} rad/s), GNL {'on' if gnl else 'off'}, "
                            f"ci sectors: the larger of the relative errors in sector 0 and over the 36 sectors "
                            f"against the reference's "
                            f"{ref['vm'] / 1e6:.4g} MPa in sector 0 and {ref['vm_all'] / 1e6:.4g} MPa over the "
                            f"sectors (in sector {ref['sector_of_max']})",
                cost_unit="s (the disk map scene's sweep wall time + the revolution carried on and the "
                          "recovery, timed in this run; µs/sim-step and h are the map's)",
                reference=dict(options=ref_opts, speed=speed, vm_max=ref["vm"], vm_max_all=ref["vm_all"],
                               sector_of_max=ref["sector_of_max"], u_le=ref["u_le"], seconds=ref["seconds"]),
                candidates=cands, machine=machine_description(), held_out_case=None,
                floor=floor_record(ref_opts, cands, moved))
