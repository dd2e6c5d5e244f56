"""Full-order blade: wall time and peak memory of mesh + assembly + 10 clamped modes for each mesh preset, and the
mesh-convergence table (presets vs frequencies) for the built-in parametric blade and the exact Table IV loft.

Each preset runs in a fresh child process so that its peak RSS (ru_maxrss) is its own. Results go to
results/bench_full_order.json and are printed as Markdown (copied into the README).

    python benchmarks/bench_full_order.py [--presets ci coarse paper]
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
t0 = time.perf_counter()
from rotor37_rom import fem
from rotor37_rom.model.modes import classify_blade_modes
t_import = time.perf_counter() - t0
preset, table = sys.argv[1], (sys.argv[2] if sys.argv[2] != "none" else None)
t0 = time.perf_counter()
sector = fem.create_blade_sector(table=table, preset=preset)
t_mesh = time.perf_counter() - t0
t0 = time.perf_counter()
ops = fem.create_svk_operators(sector)
K, M = fem.assemble_stiffness(sector, ops), fem.assemble_mass(sector, ops)
t_assemble = time.perf_counter() - t0
t0 = time.perf_counter()
omega, vecs = fem.solve_eigenproblem(K, M, 10)
t_modes = time.perf_counter() - t0
modal = fem.compute_clamped_modes(sector, 10, ops)
labels = classify_blade_modes(modal.tip_displacements, sector.tip_nodes)
print(json.dumps({"preset": preset, "source": "table" if table else "parametric", "dofs": sector.n_dofs,
                  "mesh_s": t_mesh, "assembly_s": t_assemble, "modes_s": t_modes, "import_s": t_import,
                  "omega": omega.tolist(), "labels": labels, "mass_g": sector.total_mass() * 1e3,
                  "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))
"""

PAPER = {"1B": 5272.0, "1T": 15760.0, "2B": 19071.0}


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--presets", nargs="+", default=["ci", "coarse", "paper"])
    args = parser.parse_args()
    from rotor37_rom.geometry.tables import default_data_dir

    data = default_data_dir()
    sources = ["none"] + ([str(data / "rotor37geometry.dat")] if data else [])
    rows = []
    for source in sources:
        for preset in args.presets:
            t0 = time.perf_counter()
            out = subprocess.run([sys.executable, "-c", CHILD, preset, source], capture_output=True, text=True,
                                 check=True)
            row = json.loads(out.stdout.strip().splitlines()[-1])
            row["total_s"] = time.perf_counter() - t0
            rows.append(row)
            print(f"{row['source']:>10} {preset:>6}: {row['dofs']} DOF, {row['total_s']:.1f} s", file=sys.stderr)
    machine = write_results("bench_full_order", rows)
    print(f"Machine: {machine}\n")
    print("| blade | preset | DOF | mesh (s) | assembly K,M (s) | 10 modes (s) | total incl. start-up (s) "
          "| peak RSS (MB) |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['source']} | {r['preset']} | {r['dofs']:,} | {r['mesh_s']:.1f} | {r['assembly_s']:.2f} | "
              f"{r['modes_s']:.1f} | {r['total_s']:.1f} | {r['peak_rss_mb']:.0f} |")
    print("\n| blade | preset | DOF | mass (g) | 1B (rad/s) | 1T | 2B | error vs paper 1B / 1T / 2B |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        w = {lab: om for lab, om in zip(r["labels"], r["omega"])}
        errs = " / ".join(f"{100 * (w[k] - PAPER[k]) / PAPER[k]:+.2f} %" for k in PAPER)
        print(f"| {r['source']} | {r['preset']} | {r['dofs']:,} | {r['mass_g']:.2f} | {w['1B']:.0f} | {w['1T']:.0f} | "
              f"{w['2B']:.0f} | {errs} |")
    print("| paper (Delhez et al. 2023) | quadratic pentahedra | 61,971 | | 5272 | 15760 | 19071 | |")


if __name__ == "__main__":
    main()
