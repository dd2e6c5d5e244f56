"""Bladed-disk sector: wall time and peak memory of mesh + assembly + all 19 nodal diameters (6 modes each) per mesh
preset, and the mesh convergence of the first three families (1B, 1T, 2B) at k = 0, 1, 18.

Each preset runs in a fresh child process (its own peak RSS, ru_maxrss), optionally under ``mpirun -n 2``.
Results go to results/bench_safe.json and are printed as Markdown (copied into docs/performance.md and
docs/results.md with this command).

    python benchmarks/bench_safe.py [--presets ci coarse paper] [--ranks 1 2]
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys

from rotor37_rom.machine import mpirun_env, write_results

CHILD = r"""
import json, resource, sys, time
import numpy as np
from mpi4py import MPI
t0 = time.perf_counter()
from rotor37_rom import fem
from rotor37_rom.fem.safe import compute_safe_diagram
preset = sys.argv[1]
t0 = time.perf_counter()
sector = fem.create_disk_sector(preset=preset)
t_mesh = time.perf_counter() - t0
t0 = time.perf_counter()
ops = fem.create_svk_operators(sector)
K, M = fem.assemble_stiffness(sector, ops), fem.assemble_mass(sector, ops)
t_assemble = time.perf_counter() - t0
t0 = time.perf_counter()
safe = compute_safe_diagram(sector, 6, ops=ops)
t_safe = time.perf_counter() - t0
rss = MPI.COMM_WORLD.allreduce(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, op=MPI.SUM)
if MPI.COMM_WORLD.rank == 0:
    print(json.dumps({"preset": preset, "dofs": sector.n_dofs, "ranks": MPI.COMM_WORLD.size, "mesh_s": t_mesh,
                      "assembly_s": t_assemble, "safe_s": t_safe, "per_k_s": safe.seconds.tolist(),
                      "peak_rss_mb": rss, "safe": safe.as_dict()}))
"""


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--presets", nargs="+", default=["ci", "coarse"], help="mesh presets (ci, coarse, paper)")
    parser.add_argument("--ranks", nargs="+", type=int, default=[1], help="MPI ranks per run (1 or 2)")
    args = parser.parse_args(argv)
    rows = []
    # no core binding: rank 0 meshes with gmsh's two threads while rank 1 waits (bound to one core: 1.6x slower)
    env = mpirun_env()
    for preset in args.presets:
        for ranks in args.ranks:
            cmd = [sys.executable, "-c", CHILD, preset]
            if ranks > 1:
                cmd = ["mpirun", "-n", str(ranks)] + cmd
            proc = subprocess.run(cmd, capture_output=True, text=True, env=env)
            if proc.returncode != 0:
                print(f"{preset} x {ranks}: failed: {proc.stderr.strip().splitlines()[-1:]}", file=sys.stderr)
                continue
            rows.append(json.loads(proc.stdout.strip().splitlines()[-1]))
            r = rows[-1]
            print(f"{preset} x {ranks} ranks: {r['dofs']} DOF, mesh {r['mesh_s']:.1f} s, assembly "
                  f"{r['assembly_s']:.1f} s, 19 nodal diameters {r['safe_s']:.1f} s, peak RSS {r['peak_rss_mb']:.0f} MB",
                  flush=True)
    machine = write_results("bench_safe", rows)
    print(f"\nMachine: {machine}. Command: python benchmarks/bench_safe.py --presets {' '.join(args.presets)} "
          f"--ranks {' '.join(map(str, args.ranks))}\n")
    print("| preset | ranks | DOF per sector | mesh (s) | assembly (s) | 19 NDs x 6 modes (s) | total (s) | peak RSS (MB) |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        total = r["mesh_s"] + r["assembly_s"] + r["safe_s"]
        print(f"| {r['preset']} | {r['ranks']} | {r['dofs']:,} | {r['mesh_s']:.1f} | {r['assembly_s']:.1f} | "
              f"{r['safe_s']:.1f} | {total:.1f} | {r['peak_rss_mb']:.0f} |")
    print("\nMesh convergence (rad/s), first mode of each family:\n")
    print("| preset | family | k = 0 | k = 1 | k = 18 |")
    print("|---|---|---|---|---|")
    for r in rows:
        if r["ranks"] != args.ranks[0]:
            continue
        s = r["safe"]
        for fam in ("1B", "1T", "2B"):
            cells = []
            for k in (0, 1, 18):
                i = s["k"].index(k)
                hits = [w for w, f in zip(s["omega"][i], s["family"][i]) if f == fam]
                cells.append(f"{hits[0]:.1f}" if hits else "-")
            print(f"| {r['preset']} | {fam} | " + " | ".join(cells) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
