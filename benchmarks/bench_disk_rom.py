"""The paper's r = 972 bladed-disk model (r_b = 3, r_c = 10, r_MD = 10 by MI 2b, r_cyclic = 144; §3.3): offline wall
time and peak memory, and 50 ms of simulated time at h = 1e-5 s with the project's explicit integrator (central
differences, GNL, 400 N at node LE of every sector, 4,000 rad/s, N_d = 0), next to the implicit Newmark of the same
model (the error the explicit step's frequency cap costs).

The model's highest frequency is ~2e7 rad/s (the LE's constraint mode on the thin leading edge), so h = 1e-5 s needs
the spectral frequency cap (``CentralDifference(frequency_cap=...)``: the modes above the cap get the mass that
brings them down to it; those below keep their frequency and shape). The paper's figures: ~10 h offline, ~60 s for
50 ms on one core; its full-order GNL reference: 18 h.

    python benchmarks/bench_disk_rom.py [--preset ci] [--cap 1.5e5]

Results: results/bench_disk_rom.json and the von Mises stress of the whole bladed disk at sector 0's t_max
(each sector's field rebuilt from q, no reassembly; results/bench_disk_rom/stress_{linear,gnl}.png). Each part runs in
this process, one after the other (2-core machine).
"""
from __future__ import annotations

import argparse
import resource
import sys
import time
from pathlib import Path

import numpy as np

from rotor37_rom.machine import write_results
from rotor37_rom import fem  # noqa: E402
from rotor37_rom.post.stress import disk_stress  # noqa: E402
from rotor37_rom.disk.loads import harmonic_node_load  # noqa: E402
from rotor37_rom.reduction.disk_builder import DiskReductionConfig, build_disk_model  # noqa: E402
from rotor37_rom.dynamics.explicit import CentralDifference, SimulationDiverged, simulate  # noqa: E402
from rotor37_rom.dynamics.newmark import simulate_newmark  # noqa: E402


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--preset", default="ci", choices=["ci", "coarse", "paper"])
    parser.add_argument("--cap", type=float, default=1.5e5, help="frequency cap of the explicit scheme (rad/s)")
    parser.add_argument("--duration", type=float, default=0.05, help="simulated time (s)")
    args = parser.parse_args(argv)
    if not (2e4 < args.cap < 2e7) or not (0 < args.duration <= 1.0):
        print("error: cap must be in (2e4, 2e7) rad/s and duration in (0, 1] s", file=sys.stderr)
        return 2
    t0 = time.perf_counter()
    sector = fem.create_disk_sector(preset=args.preset)
    t_mesh = time.perf_counter() - t0
    t0 = time.perf_counter()
    model, report = build_disk_model(sector, DiskReductionConfig(tip_nodes="LE", r_c=10, r_md=10, criterion="MI2b",
                                                                 r_cyclic=144))
    t_build = time.perf_counter() - t0
    print(f"offline: {t_build:.1f} s for r = {model.r} ({sector.n_dofs} DOF per sector)", flush=True)
    omega, h = 4000.0, 1e-5
    steps = int(round(args.duration / h))
    load = harmonic_node_load(model.nodes, model.r, 400.0, omega, 0, ramp=2 * np.pi / omega)
    rows = [model.nodes.q_index[model.nodes.row("LE", s), 2] for s in range(36)]
    out = {}
    for gnl in (False, True):
        t0 = time.perf_counter()
        scheme = CentralDifference(model, h=h, nonlinear=gnl, damping=False, frequency_cap=args.cap)
        t_ops = time.perf_counter() - t0
        t0 = time.perf_counter()
        try:
            res = simulate(scheme, omega, n_steps=steps, forcing=load, record_q=True, record_every=10)
        except SimulationDiverged as exc:              # recorded as a failure of this cap, never as a result
            out["gnl" if gnl else "linear"] = {"diverged": str(exc), "omega_max": scheme.omega_max}
            print(f"{'gnl' if gnl else 'linear'}: explicit run diverged ({exc})", flush=True)
            continue
        t_run = time.perf_counter() - t0
        t0 = time.perf_counter()
        _, Q = simulate_newmark(model.M, np.zeros_like(model.M), model.K, load, h, steps,
                                forces=model.forces if gnl else None)
        t_newmark = time.perf_counter() - t0
        explicit = np.asarray(res.records_q[0])[rows]
        implicit = Q[rows][:, ::10][:, :explicit.shape[1]]
        n = min(explicit.shape[1], implicit.shape[1])
        err = np.abs(explicit[:, :n] - implicit[:, :n]).max() / np.abs(implicit[:, :n]).max()
        key = "gnl" if gnl else "linear"
        k_max = int(np.argmax(np.abs(explicit[0])))                  # t_max of sector 0's LE
        fields, vm = disk_stress(sector, model, np.asarray(res.records_q[0])[:, k_max], nonlinear=gnl)
        from rotor37_rom.viz.plotting import render_stress

        picture = render_stress(sector, fields[0], vm.max(axis=2), Path("results") / "bench_disk_rom" / f"stress_{key}.png",
                                f"bladed disk, ROM r = {model.r}, {key}, t = {1e3 * res.t[0][k_max]:.2f} ms",
                                n_sectors=36, factor=5.0, sector_displacements=fields)
        out[key] = {"vm_max_mpa": float(vm.max() / 1e6), "picture": str(picture), "explicit_s": t_run, "operators_s": t_ops, "us_per_step": 1e6 * t_run / steps,
                    "implicit_newmark_s": t_newmark, "explicit_vs_implicit_le": float(err),
                    "omega_max": scheme.omega_max, "h_crit": scheme.h_crit,
                    "le_max_mm": 1e3 * float(np.abs(implicit).max())}
        print(f"{key}: 50 ms explicit {t_run:.2f} s ({1e6 * t_run / steps:.0f} us/step), implicit Newmark "
              f"{t_newmark:.2f} s, LE difference {err:.2e}", flush=True)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    row = {"preset": args.preset, "dofs_per_sector": sector.n_dofs, "r": model.r, "mesh_s": t_mesh,
           "offline_s": t_build, "offline_parts_s": report.get("timings", {}), "cap": args.cap, "h": h,
           "steps": steps, "peak_rss_mb": peak, **out}
    machine = write_results("bench_disk_rom", [row])
    print(f"{machine}: offline {t_build:.1f} s (r = {model.r}), peak RSS {peak:.0f} MB")
    return 0


if __name__ == "__main__":
    sys.exit(main())
