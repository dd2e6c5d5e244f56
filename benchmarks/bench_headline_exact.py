"""Accuracy of the GNL headline map over its full length: a few of its speeds again with the exact cubic tensors of
the same basis, at the same capped step, the same casing and the same number of revolutions.

The headline replaces the exact tensors by a point cubature trained on 12-revolution runs, evaluated in float32;
this checks that choice where it matters most, at the peak of the map and on either side, after 200 revolutions
(amplitudes the training runs never reached). The exact sweep is an ordinary cached sweep: a killed run resumes.

    python benchmarks/bench_headline_exact.py --headline results/headline_r55 \
        --model results/cache/rom_1099cedcb1070e3ef2577892.npz
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
from pathlib import Path

import numpy as np

from rotor37_rom.machine import write_results


def main(argv=None) -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--headline", default="results/headline_r55", help="the demo's --out of the headline map")
    parser.add_argument("--model", default="results/cache/rom_1099cedcb1070e3ef2577892.npz",
                        help="the reduced model with exact tensors the headline's cubature was trained on")
    parser.add_argument("--speeds", type=float, nargs="*",
                        help="map speeds to check (the nearest map speeds are used); default: 1200, the peak, "
                             "1440, 1520 rad/s")
    parser.add_argument("--perturbation", type=float, default=0.0,
                        help="scale the exact nonlinear forces by 1 + this (the problem's own sensitivity: any "
                             "approximate force model perturbs at least ~1e-4); its sweeps are cached apart")
    parser.add_argument("--out", default="results/bench_headline_exact",
                        help="sweeps under it, the table in results/<its name>.json")
    args = parser.parse_args(argv)
    from rotor37_rom.dynamics.casing import Casing
    from rotor37_rom.dynamics.explicit import CentralDifference
    from rotor37_rom.forces.tensors import PolynomialForces
    from rotor37_rom.model.reduced import load_reduced_model
    from rotor37_rom.studies.sweep import SweepSpec, interaction_map, load_sweep, run_sweep

    summary_path = Path(args.headline) / "summary.json"
    if not summary_path.is_file():
        print(f"error: --headline: {summary_path} not found (run the headline map first)", file=sys.stderr)
        return 2
    summary = json.loads(summary_path.read_text())
    label, run = next((k, v) for k, v in summary["runs"].items() if k.startswith("GNL"))
    map_speeds, map_nfrc = np.array(run["speeds"]), np.array(run["nfrc"])
    retried = {float(w) for w in run.get("retried", {})}
    wanted = args.speeds or [1200.0, run["peak_speed"], 1440.0, 1520.0]
    speeds = np.unique([map_speeds[np.argmin(np.abs(map_speeds - w))] for w in wanted])
    if any(float(f"{w:g}") in retried for w in speeds):
        print("note: some checked speeds were retried at a smaller step in the map; the exact run uses the map's "
              "first step for all")
    model = load_reduced_model(args.model)
    if args.perturbation:
        if not isinstance(model.forces, PolynomialForces) or not -0.1 < args.perturbation < 0.1:
            print("error: --perturbation applies to a model with exact tensors and must lie in (-0.1, 0.1)",
                  file=sys.stderr)
            return 2
        s = 1.0 + args.perturbation
        model = dataclasses.replace(model, forces=PolynomialForces(model.forces.A * s, model.forces.B * s),
                                    metadata={**model.metadata, "force_scale": s})   # own key: own cached sweeps
    casing = Casing(**{k: v for k, v in summary["casing"].items() if k in ("c0", "h_b", "mu", "direction")})
    cap = 2 * np.pi * 1e3 * run["frequency_cap_khz"]
    scheme = CentralDifference(model, nonlinear=True, h=run["h"], frequency_cap=cap)
    spec = SweepSpec(revolutions=summary["revolutions"], casing=casing, batch_size=len(speeds))
    t0 = time.perf_counter()
    folder = run_sweep(scheme, speeds, spec, Path(args.out) / "sweeps")
    wall = time.perf_counter() - t0
    results = [r for r in load_sweep(folder) if np.isclose(float(r["omega"]), speeds).any()]
    exact = interaction_map(results)
    peak = float(np.nanmax(map_nfrc))
    rows = []
    print(f"{label}, r = {model.r}, h = {scheme.h:.3g} s, {summary['revolutions']:g} rev; exact tensors: {wall:.0f} s")
    print(f"{'Omega':>8} {'map (mm)':>9} {'exact (mm)':>11} {'diff / peak':>12}")
    for w, e, div in zip(exact.speeds, exact.nfrc, exact.diverged):
        m = float(map_nfrc[np.argmin(np.abs(map_speeds - w))])
        rows.append({"omega": float(w), "map_nfrc": m, "exact_nfrc": None if div else float(e),
                     "diff_of_peak": None if div else abs(m - e) / peak})
        print(f"{w:8.1f} {m * 1e3:9.3f} " + ("   blew up" if div else f"{e * 1e3:11.3f} {abs(m - e) / peak:11.1%}"))
    machine = write_results(Path(args.out).name, rows, headline=str(args.headline), model=args.model,
                            h=scheme.h, revolutions=summary["revolutions"], wall_s=wall, map_peak=peak,
                            perturbation=args.perturbation)
    print(f"machine: {machine}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
