"""The single blade's stress and stability scenes: von Mises at t_max of one revolution carried on from each map's
final state at the reference's 1B/EO4 resonance (``stress-linear`` / ``stress-gnl``), and the stable step against
the LE amplitude with and without a frequency cap (``stability``)."""
from __future__ import annotations

import functools
import math
import time

import numpy as np

from rotor37_rom.studies.speed_accuracy.context import MAP, StudyContext, percent
from rotor37_rom.studies.speed_accuracy.maps import MapRun, model_file, run_map
from rotor37_rom.reporting import say

__all__ = ["scene_stress", "stress_at_tmax", "scene_stability"]

# ## von Mises at t_max

@functools.lru_cache(maxsize=None)
def _recovery(ctx: StudyContext, r_c: int):
    """The ci blade's sector and the stress recovery of the r_c model's basis (made once per basis)."""
    from mpi4py import MPI

    from rotor37_rom import fem
    from rotor37_rom.model.reduced import load_reduced_model
    from rotor37_rom.post.recovery import StressRecovery

    model = load_reduced_model(model_file(ctx, r_c))
    sector = fem.create_blade_sector(MPI.COMM_SELF, preset=MAP["preset"])
    H, _, cells = fem.quadrature_gradients(sector, model.Phi.T)
    return sector, model, StressRecovery(H, cells, *sector.material.lame)


def stress_at_tmax(ctx: StudyContext, run: MapRun, options: dict, gnl: bool, speed: float) -> dict:
    """von Mises at t_max of one revolution carried on from ``run``'s final state at ``speed`` (the report's
    procedure: ``post.stress.stress_at_peak``, the largest outside the contact nodes' tip band), with the wall time."""
    from rotor37_rom.post.stress import stress_at_peak
    from rotor37_rom.studies import contact_map as cm

    sector, model, recovery = _recovery(ctx, int(options.get("r_c", 15)))     # made once per basis, not timed
    k = int(np.argmin(np.abs(run.speeds - speed)))
    record, h = run.records[k], run.record_h[k]
    scheme = cm.time_scheme(run.config, model, gnl, None, h=h)                     # the map's forces (its cubature)
    t0 = time.perf_counter()
    res, _ = cm.carry_on_record(run.config, scheme, record, speed)
    if res.diverged_step[0] >= 0:
        return dict(vm_max=math.inf, seconds=time.perf_counter() - t0)
    peak = stress_at_peak(sector, model, recovery, res, gnl, magnitude=True)
    return dict(vm_max=peak["vm_max"], u_le=peak["u_le"], seconds=time.perf_counter() - t0)


def scene_stress(ctx: StudyContext, gnl: bool, maps: dict) -> dict:
    """von Mises at t_max at the reference map's 1B/EO4 resonance (the report's speed: ``engine_order_resonance``),
    for the map scene's reference and candidates (the same runs: the stress needs a map's final state); error
    relative to the reference's maximum. On the ci mesh, whose clamped root corner is singular: a comparison of
    models on one mesh, not a converged stress."""
    from rotor37_rom.studies.sweep import engine_order_resonance, interaction_map

    ref_run = run_map(ctx, "reference", gnl, maps["reference"]["options"])
    speed = engine_order_resonance(interaction_map(ref_run.records, ref_run.config.node), 4, MAP["revolutions"])
    if not np.isfinite(speed):                        # no speed dominated by EO4: the largest response
        speed = maps["reference"]["peak_speed"]
    ref = stress_at_tmax(ctx, ref_run, maps["reference"]["options"], gnl, speed)
    cands = []
    for c in maps["candidates"]:
        if not np.isfinite(c["error"]):              # a map that lost a speed: no model for the scene
            vm, seconds = math.inf, 0.0
        else:
            out = stress_at_tmax(ctx, run_map(ctx, c["name"], gnl, c["options"]), c["options"], gnl, speed)
            vm, seconds = out["vm_max"], out["seconds"]
        err = abs(vm - ref["vm_max"]) / ref["vm_max"] if np.isfinite(vm) else math.inf
        say(f"stress {'gnl' if gnl else 'linear'} {c['name']}: {vm / 1e6:.4g} MPa ({percent(err)})")
        cands.append(dict(name=c["name"], options=c["options"], us_per_step=c["us_per_step"], h=c["h"],
                          cost=c["cost"] + seconds, error=err, vm_max=vm, held_out_error=None))
    kind = "GNL" if gnl else "GNL off"
    return dict(description=f"largest von Mises stress (outside the contact nodes' tip band) at t_max of one "
                            f"revolution carried on from the map's final state at the reference's 1B/EO4 resonance "
                            f"({speed:g} rad/s), {kind}, the map scene's runs, ci mesh: relative error against the "
                            f"reference's {ref['vm_max'] / 1e6:.4g} MPa (LE at {1e3 * abs(ref['u_le']):.3g} mm)",
                cost_unit="s (sweep wall time of the map + the revolution carried on and the recovery)",
                reference=dict(options=maps["reference"]["options"], speed=speed, vm_max=ref["vm_max"],
                               u_le=ref["u_le"]),
                candidates=cands, held_out_case=None)


# ## Stability map: the stable step against the amplitude

def scene_stability(ctx: StudyContext) -> dict:
    """The stable step 2 / omega_max of the r_c 15 model's tangent on static states of a load at node LE along e_x,
    against the LE displacement, uncapped and at 120 and 60 kHz."""
    from rotor37_rom.dynamics.explicit import CentralDifference, highest_frequency, tangent_highest_frequency
    from rotor37_rom.model.reduced import load_reduced_model, solve_reduced_static

    model = load_reduced_model(model_file(ctx, 15))
    le = model.nodes.q_index[model.nodes.row("LE")][0]      # x DOF of node LE
    f = np.zeros(model.r)
    f[le] = 1.0
    q1 = np.linalg.solve(model.K, f)
    amplitudes = np.geomspace(1e-5, 5e-3, 12)
    loads = amplitudes / q1[le]
    rows = []
    states = solve_reduced_static(model, f, loads)
    for cap in (None, 120.0, 60.0):
        scheme = CentralDifference(model, nonlinear=False, frequency_cap=None if cap is None else 2e3 * np.pi * cap)
        lin = 2 / highest_frequency(scheme.M, model.K)
        gnl = [2 / tangent_highest_frequency(model, q, mass=scheme.M) for q in states]
        reached = [float(abs(q[le])) for q in states]
        rows.append(dict(cap_khz=cap, h_linear=float(lin), h_gnl=[float(h) for h in gnl], le_amplitude=reached))
        say(f"stability, cap {cap}: linear {lin:.3g} s, GNL {gnl[0]:.3g} .. {gnl[-1]:.3g} s")
    return dict(description="the stable step 2 / omega_max of the tangent (K + dg/dq, mass M or the capped mass) on "
                            "static states of a load at node LE along e_x, against the LE displacement; r = 45 ci",
                rows=rows)
