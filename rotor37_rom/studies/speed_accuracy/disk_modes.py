"""The bladed disk's frequencies (scene ``disk-modes``): the disk models' 1B, 1T and 2B families at every nodal
diameter against the sector's full-order cyclic modes, and each model's cost in the linear contact run."""
from __future__ import annotations

import math
import time

import numpy as np

from rotor37_rom.machine import machine_description
from rotor37_rom.studies.speed_accuracy.context import StudyContext
from rotor37_rom.reporting import say

__all__ = ["scene_disk_modes", "DISK_MODELS", "DISK_CAP_KHZ", "DISK_TIMED_STEPS"]

DISK_MODELS = (  # (name, r_c, r_md, r_cyclic): every sector's 8 tip nodes (the contact maps' boundary)
    ("r_c 2, r_cyclic 72", 2, 0, 72), ("r_c 2, r_cyclic 144", 2, 0, 144),
    ("r_c 5, r_cyclic 72", 5, 0, 72), ("r_c 5, r_cyclic 144", 5, 0, 144),
    ("r_c 10, r_cyclic 72", 10, 0, 72), ("r_c 10, r_cyclic 144", 10, 0, 144), ("r_c 10, r_cyclic 288", 10, 0, 288),
    ("r_c 10, 10 MD, r_cyclic 144 (the maps' model)", 10, 10, 144),
)
DISK_CAP_KHZ, DISK_TIMED_STEPS = 60.0, 2000


def scene_disk_modes(ctx: StudyContext) -> dict:
    """The 36-sector disk (ci sector): the 1B, 1T and 2B families at every nodal diameter k = 0 ... 18 of disk models
    (r_c, r_cyclic, modal derivatives) against the sector's full-order cyclic modes; held out: the 4th-6th modes of
    every k. Cost: the linear contact run's time per simulated millisecond at the disk maps' 60 kHz cap."""
    from rotor37_rom import fem
    from rotor37_rom.post.stress import cyclic_harmonic_frequencies
    from rotor37_rom.reduction.builder import mesh_signature
    from rotor37_rom.dynamics.casing import Casing
    from rotor37_rom.disk.harmonics import harmonic_frequencies
    from rotor37_rom.reduction.disk_builder import DiskReductionConfig, build_disk_model
    from rotor37_rom.dynamics.explicit import CentralDifference, simulate
    from rotor37_rom.npz import load_npz, save_npz

    sector = fem.create_disk_sector(preset="ci")
    ops = fem.create_svk_operators(sector)
    ref_file = ctx.work / f"disk_modes_reference_{mesh_signature(sector)[:16]}.npz"
    cached = load_npz(ref_file, ("omega", "wall"), what="cyclic reference")
    if cached is None:
        t0 = time.perf_counter()
        omega = cyclic_harmonic_frequencies(sector, 6, ops=ops)
        save_npz(ref_file, omega=omega, wall=time.perf_counter() - t0)
        ctx.fresh.append(f"disk-modes reference {time.perf_counter() - t0:.0f} s")
        cached = load_npz(ref_file, ("omega", "wall"))
    ref, ref_wall = cached["omega"], float(cached["wall"])
    say(f"disk-modes: cyclic reference, 6 families x {ref.shape[0]} harmonics ({ref_wall:.0f} s)")
    cap = 2 * np.pi * DISK_CAP_KHZ * 1e3
    speeds = np.linspace(1200.0, 1650.0, 8)
    casing = Casing(mu=0.15, direction="cone")                 # the disk maps' casing (paper's c0, h_b)
    cands = []
    for name, r_c, r_md, r_cyclic in DISK_MODELS:
        t0 = time.perf_counter()
        model, built = build_disk_model(sector, DiskReductionConfig(tip_nodes="all", r_c=r_c, r_md=r_md,
                                                                    criterion="MI2b", r_cyclic=r_cyclic,
                                                                    forces="none"),
                                        ops=ops, cache_dir=ctx.work / "disk_models")
        build = None if built.get("cached") else time.perf_counter() - t0     # a cache read is not a build time
        rom = harmonic_frequencies(model, 6)
        err = np.abs(rom / ref - 1.0)
        below = float(np.nanmax((ref - rom) / ref))          # Rayleigh-Ritz: every value >= the full order's
        scheme = CentralDifference(model, nonlinear=False, frequency_cap=cap)
        simulate(scheme, speeds[:1], casing, n_steps=50, on_blowup="flag")                # warm-up
        t0 = time.perf_counter()
        simulate(scheme, speeds, casing, n_steps=DISK_TIMED_STEPS, record_every=50, on_blowup="flag")
        per_step = (time.perf_counter() - t0) / (DISK_TIMED_STEPS * speeds.size)
        cost = 1e6 * per_step / (scheme.h * 1e3)               # us per simulated ms of one speed
        study, held = float(np.nanmax(err[:, :3])), float(np.nanmax(err[:, 3:6]))
        cands.append(dict(name=name, options={"r_c": r_c, "r_md": r_md, "r_cyclic": r_cyclic, "tip_nodes": "all"},
                          cost=cost, error=study if np.isfinite(err[:, :3]).all() else math.inf,
                          held_out_error=held if np.isfinite(err[:, 3:6]).all() else math.inf, r=model.r,
                          build_s=build, us_per_sim_step=1e6 * per_step, h=scheme.h,
                          worst_k=int(np.nanargmax(err[:, :3].max(axis=1))), rayleigh_ritz_margin=below,
                          errors={"families 1-3 by k": err[:, :3].max(axis=1).tolist(),
                                  "families 4-6 by k": err[:, 3:6].max(axis=1).tolist()}))
        made = "read from the cache" if build is None else f"built in {build:.0f} s"
        say(f"disk-modes: {name}: r = {model.r}, {made}, 1B/1T/2B within {100 * study:.3f} %, "
              f"modes 4-6 within {100 * held:.3f} %, {1e6 * per_step:.1f} us/sim-step at h = {scheme.h:.3g} s")
    return dict(description="the bladed disk's (36 ci sectors, 8 tip nodes each) 1B, 1T and 2B families at every "
                            "nodal diameter k = 0 ... 18: largest relative frequency error against the sector's "
                            "full-order cyclic modes",
                cost_unit=f"us per simulated ms of one speed (linear contact run from rest, the maps' casing: cone "
                          f"normal, mu = 0.15; {DISK_CAP_KHZ:g} kHz cap, {speeds.size} speeds batched)",
                reference={"cyclic_rad_s": ref.tolist(), "wall_s": ref_wall,
                           "options": {"model": "full-order cyclic sector", "preset": "ci"}},
                candidates=cands, held_out_case="the 4th-6th modes of every nodal diameter (same models)",
                machine=machine_description())
