"""Offline cost of the reduced model vs r (r_b = 24, r_c = 15, r_MD = 10, 30, 60, 150) for the force methods:
intrusive exact tensors, exact tensor-free quadrature data, ECSW and STEP.

Each configuration runs in a fresh child process (its peak RSS is its own). Methods whose cost explodes are
measured where affordable and extrapolated with their operation counts elsewhere; such rows say 'model' in the
'how' column. Results: results/bench_reduction.json and a Markdown table (copied into the README).

    python benchmarks/bench_reduction.py [--preset coarse] [--r-md 10 30 60 150] [--intrusive-max-r 69]
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time

from rotor37_rom.machine import write_results

CHILD = r"""
import json, resource, sys, time
import numpy as np
from rotor37_rom import fem
from rotor37_rom.reduction.builder import ReductionConfig, build_reduced_model
preset, r_md, forces = sys.argv[1], int(sys.argv[2]), sys.argv[3]
sector = fem.create_blade_sector(preset=preset)
ops = fem.create_svk_operators(sector)
if forces == "step-cost":  # one FE nonlinear-force assembly, the unit of STEP's cost
    u = np.zeros((20, sector.n_dofs))
    t1 = time.perf_counter(); fem.evaluate_forces(sector, ops, u)
    print(json.dumps({"assembly_s": (time.perf_counter() - t1) / 20})); sys.exit(0)
t0 = time.perf_counter()
model, report = build_reduced_model(sector, ReductionConfig(r_c=15, r_md=r_md, forces=forces), ops=ops)
total = time.perf_counter() - t0
n_points = sector.mesh.topology.index_map(3).size_local * 14
out = {"preset": preset, "dofs": sector.n_dofs, "r": model.r, "r_md": r_md, "forces": forces, "total_s": total,
       "timings": report["timings"], "n_points": n_points, "ecsw_cells": report.get("ecsw_cells"),
       "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}
print(json.dumps(out))
"""


def step_evaluations(r: int) -> int:
    return 2 * r + 3 * r * (r - 1) // 2 + r * (r - 1) * (r - 2) // 6


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--preset", default="coarse")
    parser.add_argument("--r-md", type=int, nargs="+", default=[10, 30, 60, 150])
    parser.add_argument("--intrusive-max-r", type=int, default=69, help="largest r computed intrusively")
    args = parser.parse_args()
    rows = []

    def run(r_md, forces):
        t0 = time.perf_counter()
        proc = subprocess.run([sys.executable, "-c", CHILD, args.preset, str(r_md), forces], capture_output=True,
                              text=True)
        if proc.returncode != 0:
            raise RuntimeError(proc.stderr[-2000:])
        row = json.loads(proc.stdout.strip().splitlines()[-1])
        row["wall_s"] = time.perf_counter() - t0
        row["how"] = "measured"
        print(f"{forces:>10} r_MD={r_md}: {row['total_s']:.1f} s", file=sys.stderr)
        return row

    measured_intrusive = []
    for r_md in args.r_md:
        r = 39 + r_md
        rows.append(run(r_md, "quadrature"))
        rows.append(run(r_md, "ecsw"))
        if r <= args.intrusive_max_r:
            row = run(r_md, "intrusive")
            measured_intrusive.append(row)
            rows.append(row)
        elif measured_intrusive:
            ref = measured_intrusive[-1]
            scale = ((r * (r + 1) / 2) / (ref["r"] * (ref["r"] + 1) / 2)) ** 2
            est = dict(ref, r=r, r_md=r_md, how=f"model (pairs^2 from r={ref['r']})",
                       total_s=ref["timings"]["forces"] * scale + rows[-2]["total_s"],
                       peak_rss_mb=8 * (r * (r + 1) / 2) ** 2 / 2**20 + ref["peak_rss_mb"])
            rows.append(est)
    # STEP cost model: one FE assembly per enforced displacement (STEP itself is verified in tests/reduction/test_reduction.py)
    child = subprocess.run([sys.executable, "-c", CHILD, args.preset, "0", "step-cost"], capture_output=True,
                           text=True, check=True)
    assembly_s = json.loads(child.stdout.strip().splitlines()[-1])["assembly_s"]
    for r_md in args.r_md:
        r = 39 + r_md
        rows.append({"preset": args.preset, "r": r, "r_md": r_md, "forces": "step",
                     "total_s": step_evaluations(r) * assembly_s, "peak_rss_mb": None,
                     "how": f"model ({step_evaluations(r):,} assemblies x {assembly_s * 1e3:.1f} ms)"})
    machine = write_results("bench_reduction", rows)
    print(f"Machine: {machine}; preset {args.preset}\n")
    print("| forces | r_MD | r | offline time (s) | peak RSS (MB) | ECSW cells | how |")
    print("|---|---|---|---|---|---|---|")
    for r in sorted(rows, key=lambda x: (x["forces"], x["r"])):
        rss = f"{r['peak_rss_mb']:.0f}" if r.get("peak_rss_mb") else ""
        print(f"| {r['forces']} | {r['r_md']} | {r['r']} | {r['total_s']:.1f} | {rss} | {r.get('ecsw_cells') or ''} | "
              f"{r['how']} |")


if __name__ == "__main__":
    main()
