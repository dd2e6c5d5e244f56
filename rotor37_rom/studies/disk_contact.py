"""Blade-tip/casing contact on the whole bladed disk (paper §3.4): the disk model of the contact maps, the issue's
full-disk map (its speeds and revolutions, for extrapolating its cost) and the cost per simulation-step of a batch
run with contact (``benchmarks/bench_disk_contact.py``, ``bench_disk_cubature.py``).
"""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from rotor37_rom import fem
from rotor37_rom.reduction.disk_builder import DiskReductionConfig, build_disk_model
from rotor37_rom.dynamics.explicit import simulate
from rotor37_rom.reporting import say

MAP_SPEEDS, MAP_REVOLUTIONS = np.linspace(1200.0, 1650.0, 90), 200.0     # the full-disk map


def contact_disk_model(preset: str):
    """(sector, model, seconds): the disk model of the contact maps (every sector's 8 tip nodes, r_c = 10, r_MD = 10
    by MI 2b, r_cyclic = 144), cached in results/cache."""
    t0 = time.perf_counter()
    sector = fem.create_disk_sector(preset=preset)
    model, _ = build_disk_model(sector, DiskReductionConfig(tip_nodes="all", r_c=10, r_md=10, criterion="MI2b",
                                                            r_cyclic=144), cache_dir=Path("results/cache"))
    offline = time.perf_counter() - t0
    say(f"disk model r = {model.r} {model.sizes}, {len(model.nodes)} tip nodes; {offline:.0f} s", flush=True)
    return sector, model, offline


def cost_per_sim_step(scheme, casing, speeds, steps=2000) -> tuple[float, object]:
    """Seconds per simulation-step of a batch run with contact (and the run, for its states)."""
    t0 = time.perf_counter()
    res = simulate(scheme, speeds, casing, n_steps=steps, duration=steps * scheme.h * 5, record_every=20,
                   record_q=True, on_blowup="flag")
    return (time.perf_counter() - t0) / (steps * len(speeds)), res
