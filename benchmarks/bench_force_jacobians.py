"""The reduced cubic force's Jacobian at many states: one ``jacobian`` call per state against ``jacobians`` (two
GEMMs over gathered tensors, ``forces.tensors.PolynomialForces.jacobians``), in the same run. Shooting needs it at
every step of a period (n ~ 500-8,000), the harmonic balance at its 2H + 1 samples per Newton iteration.

For each r a synthetic reduced model (random tensors of the right sizes: timing only; ``speed_accuracy.cost``) and
P states; the two results are checked equal to 1e-10 of their largest entry before their times are reported.

    python benchmarks/bench_force_jacobians.py [--r 30 45 55 90] [--P 1200]
"""
from __future__ import annotations

import argparse
import time

import numpy as np

from rotor37_rom.machine import write_results
from rotor37_rom.studies.speed_accuracy.cost import synthetic_model


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--r", type=int, nargs="+", default=[30, 45, 55, 90], help="model sizes (default 30 45 55 90)")
    parser.add_argument("--P", type=int, default=1200, help="states per batch (default 1200, >= 1)")
    args = parser.parse_args(argv)
    if args.P < 1 or min(args.r) < 1:
        parser.exit(2, f"error: --P and --r must be >= 1, got P = {args.P}, r = {args.r}\n")
    rows = []
    for r in args.r:
        forces = synthetic_model(r).forces
        Q = np.random.default_rng(1).standard_normal((r, args.P)) * 1e-3
        t0 = time.perf_counter()
        single = np.stack([forces.jacobian(q) for q in Q.T])
        t_single = time.perf_counter() - t0
        t0 = time.perf_counter()
        forces._jacobian_tensors                      # gathered once per force (kept with it)
        t_setup = time.perf_counter() - t0
        t0 = time.perf_counter()
        batch = forces.jacobians(Q)
        t_batch = time.perf_counter() - t0
        err = float(np.abs(batch - single).max() / np.abs(single).max())
        if err > 1e-10:
            raise SystemExit(f"r = {r}: the batched Jacobians differ from the single ones by {err:.1e}")
        rows.append({"r": r, "P": args.P, "per_state_ms": 1e3 * t_single / args.P,
                     "batched_per_state_ms": 1e3 * t_batch / args.P, "setup_s": t_setup,
                     "speedup": t_single / t_batch, "difference": err})
        print(f"r = {r:3d}, P = {args.P}: one call a state {rows[-1]['per_state_ms']:.3f} ms, batched "
              f"{rows[-1]['batched_per_state_ms']:.4f} ms ({rows[-1]['speedup']:.0f}x; tensors gathered once in "
              f"{t_setup:.2f} s); largest difference {err:.1e}")
    machine = write_results("bench_force_jacobians", rows)
    print(f"machine: {machine}")


if __name__ == "__main__":
    main()
