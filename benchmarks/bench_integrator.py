"""Online cost of the reduced contact integrator (eq. 34): microseconds per simulation-step vs r and P.

For each r, a synthetic reduced model (SPD M~, K~, random cubic tensors of the right sizes: timing only) is stepped
with the batched prediction of eq. 34 (X1 Q + X2 Q_prev + cubic forces over unique monomials), against a naive
loop that evaluates each simulation with numpy.einsum over the full r^3 and r^4 tensors, measured in the same run.
The machine's GEMM rate (dgemm 2000 x 2000) gives the fraction of peak. Then, on the ci blade model (r = 45), the
full step with casing contact, and the interaction-map throughput in simulated revolutions per wall second, GNL on,
with the projection to the headline map (100 speeds x 200 revolutions).

The exact polynomial force of a batch on its C kernel against the NumPy path (GEMMs over monomials), same arrays,
same run, at the kernel's thread count (``forces.kernel.kernel_threads``: OPENBLAS_NUM_THREADS's).

    python benchmarks/bench_integrator.py [--r 30 45 60 90] [--P 1 8 80]
    python benchmarks/bench_integrator.py --polynomial-only --r 55 104 --P 2 6 11 16 32   # the kernel alone
"""
from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np

from rotor37_rom.checks import before_work, real_number
from rotor37_rom.cli import ArgumentParser, run_main
from rotor37_rom.machine import write_results
from rotor37_rom.studies.speed_accuracy.cost import synthetic_model, time_per_step


def gemm_rate(n: int = 2000) -> float:
    a, b = np.random.rand(n, n), np.random.rand(n, n)
    a @ b
    t0 = time.perf_counter()
    for _ in range(3):
        a @ b
    return 3 * 2 * n**3 / (time.perf_counter() - t0) / 1e9


def full_tensors(forces):
    """Dense A (r, r, r) and B (r, r, r, r) holding the same polynomial (coefficient on the sorted index)."""
    from rotor37_rom.forces.tensors import cubic_monomial_indices, quadratic_monomial_indices

    r = forces.r
    A3 = np.zeros((r, r, r))
    a, b = quadratic_monomial_indices(r)
    A3[:, a, b] = forces.A
    B4 = np.zeros((r, r, r, r))
    ca, cb, cc = cubic_monomial_indices(r)
    B4[:, ca, cb, cc] = forces.B
    return A3, B4


def _headline_cubature(headline: str) -> tuple[str | None, float | None]:
    """The cubature model a headline map trained (``<headline>/cache/cubature_*.npz``) and the step it ran at."""
    summary = Path(headline) / "summary.json"
    models = sorted(p for p in (Path(headline) / "cache").glob("cubature_*.npz") if not p.name.endswith(".states.npz"))
    if not summary.is_file() or len(models) != 1:
        return None, None
    run = next((v for k, v in json.loads(summary.read_text())["runs"].items() if k.startswith("GNL")), None)
    return (str(models[0]), run["h"]) if run else (None, None)


def stress_kernel(headline: str, point_counts, P: int = 50, r: int = 45) -> dict:
    """The cubature force's point stress: the fused C kernel (svk_kernel) against the NumPy path, same arrays, same
    run (synthetic gradients: timing only), float32 and float64; then the whole integrator step on a trained
    cubature model with the kernel and with the NumPy path (1 revolution, casing contact, mu = 0)."""
    from rotor37_rom.forces import tensors as nonlinear_forces
    from rotor37_rom.forces.tensors import QuadratureForces

    out = {"P": P, "r": r, "stress": [], "step": None}
    rng = np.random.default_rng(2)
    for n in point_counts:
        forces = QuadratureForces(rng.standard_normal((n, r, 3, 3)) * 1e-2, rng.random(n), 1.0e11, 7.0e10)
        Q = rng.standard_normal((r, P)) * 0.1
        for precision, dtype in (("single", np.float32), ("double", np.float64)):
            f = forces.with_precision(precision)
            G = (f._planes[0] @ Q.astype(dtype)).reshape(3, 3, n, P)
            work = f._buffers(n, P, dtype)
            if nonlinear_forces.pk_nonlinear_kernel(dtype) is None:
                print("stress kernel: no C kernel on this machine (no compiler or ROTOR37_C_KERNEL=0)")
                return out
            t_np = time_per_step(lambda: f._first_pk_nonlinear_numpy(G, work), 0.3)
            t_c = time_per_step(lambda: f._first_pk_nonlinear(G, work), 0.3)
            row = {"points": n, "precision": precision, "numpy_us": t_np * 1e6, "c_us": t_c * 1e6,
                   "speedup": t_np / t_c, "c_ns_per_point_state": t_c / (n * P) * 1e9}
            out["stress"].append(row)
            print(f"stress, {n} points x P = {P}, {precision}: numpy {t_np * 1e6:.0f} us, C kernel {t_c * 1e6:.0f} us "
                  f"({t_np / t_c:.1f}x, {row['c_ns_per_point_state']:.2f} ns per point and state)")
    cubature_model, h = _headline_cubature(headline)
    if cubature_model is None:
        print(f"step with/without the kernel: skipped (no headline map with one trained cubature in {headline})")
        return out
    from rotor37_rom.dynamics.casing import Casing
    from rotor37_rom.dynamics.explicit import CentralDifference, simulate
    from rotor37_rom.model.reduced import load_reduced_model, with_force_precision

    model = with_force_precision(load_reduced_model(cubature_model), "single")
    scheme = CentralDifference(model, nonlinear=True, h=h, frequency_cap=2 * np.pi * 120e3)
    speeds = np.linspace(1200.0, 1600.0, P)
    step = {}
    original = nonlinear_forces.pk_nonlinear_kernel
    for key in ("numpy", "C kernel"):
        nonlinear_forces.pk_nonlinear_kernel = original if key == "C kernel" else (lambda dtype: None)
        try:
            res = simulate(scheme, speeds, Casing(mu=0.0), revolutions=1.0, on_blowup="flag")
        finally:
            nonlinear_forces.pk_nonlinear_kernel = original
        step[key] = res.wall / int(res.n_steps.sum()) * 1e6
    out["step"] = {"model": cubature_model, "points": int(model.forces.w.size), "h": scheme.h,
                   "us_per_sim_step": step, "speedup": step["numpy"] / step["C kernel"]}
    print(f"step, {model.forces.w.size} float32 points, P = {P}, contact: numpy {step['numpy']:.1f}, C kernel "
          f"{step['C kernel']:.1f} us per simulation-step ({step['numpy'] / step['C kernel']:.2f}x)")
    return out


def polynomial_kernel_rows(rs, Ps) -> list[dict]:
    """Microseconds of one evaluation of the exact polynomial force of r modes at P states: the C kernel (packed
    tensors) against the NumPy path, random tensors of the right sizes (timing only)."""
    from rotor37_rom.forces.kernel import kernel_threads, polynomial_kernel
    from rotor37_rom.forces.tensors import PolynomialForces

    if polynomial_kernel() is None:
        print("polynomial kernel: none on this machine (no compiler or ROTOR37_C_KERNEL=0)")
        return []
    rows, rng = [], np.random.default_rng(0)
    for r in rs:
        forces = PolynomialForces(rng.standard_normal((r, r * (r + 1) // 2)),
                                  rng.standard_normal((r, r * (r + 1) * (r + 2) // 6)))
        for P in Ps:
            if P < 2:
                continue                               # one state: the NumPy GEMV (memory-bound) is used
            Q = rng.standard_normal((r, P)) * 1e-3
            t_np = time_per_step(lambda: forces._evaluate_numpy(Q), 0.3)
            t_c = time_per_step(lambda: forces.evaluate(Q), 0.3)
            rows.append({"r": r, "P": P, "numpy_us": t_np * 1e6, "kernel_us": t_c * 1e6, "speedup": t_np / t_c,
                         "threads": kernel_threads()})
            print(f"polynomial force r = {r}, P = {P}: numpy {t_np * 1e6:.0f} us, C kernel {t_c * 1e6:.0f} us "
                  f"({t_np / t_c:.2f}x, {kernel_threads()} thread(s), {t_c / P * 1e6:.0f} us a state)")
    return rows


def main(argv=None) -> int:
    parser = ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--r", type=int, nargs="+", default=[30, 45, 60, 90], help="reduced sizes, each in [1, 150]")
    parser.add_argument("--P", type=int, nargs="+", default=[1, 8, 80], help="batch sizes, each in [1, 1000]")
    parser.add_argument("--preset", default="ci", help="mesh preset of the real model: ci, coarse or paper")
    parser.add_argument("--throughput-speeds", type=int, default=16, help="speeds of a throughput batch, [1, 1000]")
    parser.add_argument("--throughput-revolutions", type=float, default=1.0,
                        help="revolutions of a throughput run, in (0, 100]")
    parser.add_argument("--headline-speeds", type=int, default=100, help="speeds of the headline batch, [1, 1000]")
    parser.add_argument("--headline", default=None,
                        help="a GNL headline map's folder (the demo's --out with --cubature): its trained cubature "
                             "and step for the step with and without the C stress kernel (default results/headline, "
                             "skipped when missing)")
    parser.add_argument("--kernel-points", type=int, nargs="+", default=[376, 3000])
    parser.add_argument("--polynomial-only", action="store_true",
                        help="time the exact polynomial force's C kernel against NumPy at --r x --P, nothing else")
    args = parser.parse_args(argv)
    from rotor37_rom.geometry.blade import MESH_PRESETS

    for name, values, high in (("--r", args.r, 150), ("--P", args.P, 1000)):
        for v in values:
            real_number(name, v, 1, high)
    for name, v in (("--throughput-speeds", args.throughput_speeds), ("--headline-speeds", args.headline_speeds)):
        real_number(name, v, 1, 1000)
    real_number("--throughput-revolutions", args.throughput_revolutions, 0, 100, open_low=True)
    real_number("--kernel-points", min(args.kernel_points), 1, None)
    if args.preset not in MESH_PRESETS:
        raise ValueError(f"--preset must be one of {', '.join(MESH_PRESETS)}, got {args.preset!r}")
    if args.headline is not None and (not args.headline or not Path(args.headline).is_dir()):
        raise ValueError(f"--headline must be a map's output folder, got {args.headline!r} (no such folder)")
    args.headline = args.headline or "results/headline"
    before_work({"results": Path("results")})
    if args.polynomial_only:
        rows = polynomial_kernel_rows(args.r, args.P)
        print(f"machine: {write_results('bench_polynomial_kernel', rows)}")
        return 0
    from rotor37_rom.dynamics.explicit import CentralDifference

    gflops = gemm_rate()
    print(f"dgemm 2000^3: {gflops:.1f} GFLOP/s")
    rows = []
    print(f"{'r':>4} {'P':>4} {'batched us/sim-step':>20} {'naive einsum':>13} {'speed-up':>9} {'GFLOP/s':>8} "
          f"{'% of dgemm':>10}")
    for r in args.r:
        model = synthetic_model(r)
        scheme = CentralDifference(model, nonlinear=True, safety=0.9)
        A3, B4 = full_tensors(scheme.Xg)
        n3 = scheme.Xg.B.shape[1]
        flops = 2 * r * (2 * r + r * (r + 1) // 2 + n3)            # GEMMs of eq. 34 per simulation
        for P in args.P:
            Q = np.random.default_rng(1).standard_normal((r, P)) * 1e-4
            Qp = Q.copy()
            t_batch = time_per_step(lambda: scheme.predict(Q, Qp, None)) / P

            def naive():
                for p in range(P):
                    q = Q[:, p]
                    scheme.X1 @ q + scheme.X2 @ Qp[:, p] + np.einsum("mij,i,j->m", A3, q, q) + \
                        np.einsum("mijk,i,j,k->m", B4, q, q, q)

            t_naive = time_per_step(naive, min_time=0.3) / P
            rate = flops / t_batch / 1e9
            rows.append({"r": r, "P": P, "us_per_sim_step": t_batch * 1e6, "naive_us": t_naive * 1e6,
                         "speedup": t_naive / t_batch, "gflops": rate, "fraction_of_dgemm": rate / gflops})
            print(f"{r:>4} {P:>4} {t_batch * 1e6:>20.1f} {t_naive * 1e6:>13.1f} {t_naive / t_batch:>9.1f} "
                  f"{rate:>8.1f} {100 * rate / gflops:>9.0f}%")
        A3 = B4 = None          # free the dense tensors before the next r
    # real model: full step with contact, and interaction-map throughput
    from rotor37_rom import fem
    from rotor37_rom.reduction.builder import ReductionConfig, build_reduced_model
    from rotor37_rom.dynamics.casing import Casing
    from rotor37_rom.dynamics.explicit import simulate

    sector = fem.create_blade_sector(preset=args.preset)
    model, _ = build_reduced_model(sector, ReductionConfig(r_c=15, r_md=0, global_md_modes=3, forces="intrusive"),
                                   cache_dir="results/cache")
    throughput = {}

    def measure(key, scheme, n_speeds, **extra):
        """Interaction-map throughput of one batch of n_speeds in 1200-1600 rad/s; the ovalization reaches 99 % at
        20 % of the run, so contacts happen in these short runs too."""
        speeds = np.linspace(1200.0, 1600.0, n_speeds)
        res = simulate(scheme, speeds, Casing(), revolutions=args.throughput_revolutions, record_every=50,
                       on_blowup="flag")
        revs = args.throughput_revolutions * n_speeds
        t = throughput[key] = {
            "h": scheme.h, "P": n_speeds, "rev_per_s": revs / res.wall,
            "us_per_sim_step": res.wall / int(res.n_steps.sum()) * 1e6, "contact_steps": int(res.contact_steps.sum()),
            "diverged": int((res.diverged_step >= 0).sum()), "headline_hours": 100 * 200 / (revs / res.wall) / 3600,
            **extra}
        print(f"{args.preset} r = {model.r}, {key}, P = {n_speeds}, h = {scheme.h:.3g} s: {t['rev_per_s']:.3f} rev/s, "
              f"{t['us_per_sim_step']:.1f} us/sim-step with contact; 100 speeds x 200 rev would take "
              f"{t['headline_hours']:.2f} h")

    # unscaled, P = throughput speeds; GNL also with all headline speeds in one batch (the batch lever)
    for key, gnl, n_speeds in (("linear", False, args.throughput_speeds), ("GNL", True, args.throughput_speeds),
                               ("GNL, all speeds in one batch", True, args.headline_speeds)):
        measure(key, CentralDifference(model, nonlinear=gnl, safety=0.5), n_speeds)
    # the setting the convergence study found sufficient (bench_contact_convergence.py): frequency cap and step,
    # all headline speeds in one batch
    conv = Path("results/bench_contact_convergence.json")
    found = json.loads(conv.read_text()).get("summary", {}) if conv.exists() else {}
    for tag, gnl in (("linear", False), ("GNL", True)):
        best = found.get(tag)
        if not (best and best.get("h")):
            print(f"{tag}: no cheaper setting met the accuracy in results/bench_contact_convergence.json "
                  f"({'not run' if not conv.exists() else 'none sufficient'}): the unscaled figure above stands")
            continue
        cap_khz = best["cheapest_sufficient_cap_khz"]
        scheme = CentralDifference(model, nonlinear=gnl, h=best["h"],
                                   frequency_cap=None if cap_khz is None else 2 * np.pi * cap_khz * 1e3)
        measure(f"{tag}, " + ("no cap" if cap_khz is None else f"cap {cap_khz:g} kHz"), scheme, args.headline_speeds,
                cap_khz=cap_khz, p90_nfrc_error=best.get("p90_error"))
    kernel = stress_kernel(args.headline, args.kernel_points)
    polynomial = polynomial_kernel_rows(args.r, args.P)
    machine = write_results("bench_integrator", rows, dgemm_gflops=gflops, throughput=throughput,
                            model={"preset": args.preset, "r": model.r}, stress_kernel=kernel,
                            polynomial_kernel=polynomial)
    print(f"machine: {machine}")
    return 0


if __name__ == "__main__":
    sys.exit(run_main(main))
