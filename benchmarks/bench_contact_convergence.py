"""Cost vs error of the contact simulations: time step and spectral mass scaling (frequency cap), GNL off and on.

The explicit step of the reduced blade is set by omega_max = 4.6e6 rad/s (740 kHz), the constraint modes of single
tip nodes, while the response of interest lies below ~10 kHz (1B at 862 Hz, engine orders up to ~20 x 250 Hz).
``CentralDifference(frequency_cap=...)`` slows the modes above the cap to it (modes below keep frequency and shape
exactly), so h grows by omega_max / cap. This script measures what that costs in accuracy on the quantity the
interaction map is made of: the NFRC (max |u_LE| over the last revolution) at each speed, with casing contact.

With GNL, stress stiffening raises the tangent frequencies of the capped modes far more than those of the unscaled
ones (measured on the reference's largest states: 1.3x omega_max unscaled, 2x / 3.9x / 7.2x the cap at 120 / 60 /
30 kHz), so a GNL run with a cap takes h = min(safety x 2/cap, tangent_safety x 2/omega_tangent).

Reference: no cap, h = safety x 2/omega_max (the production setting). Its own sensitivity is measured too: the same
run at h/2 (near the zero-IC jump the response is sensitive to any perturbation, so that is the noise floor of the
comparison). Error = |NFRC - NFRC_ref| / max(NFRC_ref) per speed (median, 90th percentile, max), the peak speed, and
the wall time. A candidate is sufficient when its 90th-percentile error is below --tol and no larger than the
reference's own h/2 spread plus --tol; the cheapest sufficient one is reported. Completed runs are kept in
results/bench_contact_convergence.json and not repeated when the script is started again with the same settings.

    python benchmarks/bench_contact_convergence.py                       # 11 speeds x 12 rev, mu = 0: ~25 min
    python benchmarks/bench_contact_convergence.py --mu 0.15 --gnl on
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from rotor37_rom.machine import machine_description
from rotor37_rom.npz import save_json  # noqa: E402
from rotor37_rom.studies.convergence import compare, nfrc_run

RESULTS = Path("results/bench_contact_convergence.json")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", default="results/contact_map/rom.npz",
                        help="reduced model (.npz); built at the ci preset when missing")
    parser.add_argument("--speeds", type=float, nargs=3, default=[1200.0, 1600.0, 11])
    parser.add_argument("--revolutions", type=float, default=12.0)
    parser.add_argument("--mu", type=float, default=0.0)
    parser.add_argument("--caps", type=float, nargs="+", default=[120.0, 60.0, 30.0, 15.0], help="kHz")
    parser.add_argument("--safety", type=float, default=0.5)
    parser.add_argument("--gnl", choices=["off", "on", "both"], default="both")
    parser.add_argument("--tol", type=float, default=0.05, help="admissible NFRC error, fraction of the peak")
    parser.add_argument("--tangent-safety", type=float, default=0.7,
                        help="GNL with a cap: h <= this x 2 / tangent omega_max on the reference's largest states")
    args = parser.parse_args(argv)
    from rotor37_rom.dynamics.casing import Casing
    from rotor37_rom.viz.charts import plot_nfrc, plot_speed_accuracy
    from rotor37_rom.dynamics.explicit import gnl_time_step
    from rotor37_rom.model.reduced import load_reduced_model, save_reduced_model

    if Path(args.model).exists():
        model = load_reduced_model(args.model)
    else:
        from rotor37_rom import fem
        from rotor37_rom.reduction.builder import ReductionConfig, build_reduced_model

        sector = fem.create_blade_sector(preset="ci")
        model, _ = build_reduced_model(sector, ReductionConfig(r_c=15, r_md=0, global_md_modes=3, forces="intrusive"),
                                       cache_dir="results/cache")
        Path(args.model).parent.mkdir(parents=True, exist_ok=True)
        save_reduced_model(model, args.model)
    start, stop, n = args.speeds
    speeds = np.linspace(start, stop, int(n))
    casing = Casing(c0=0.5e-3, h_b=0.625e-3, mu=args.mu)
    settings = {"model": model.key, "r": model.r, "speeds": [start, stop, int(n)], "revolutions": args.revolutions,
                "mu": args.mu, "safety": args.safety}
    store = json.loads(RESULTS.read_text()) if RESULTS.exists() else {}
    if store.get("settings") != settings:
        store = {"settings": settings, "runs": {}}
    store["machine"] = machine_description()

    def cached(label, fn):
        if label not in store["runs"]:
            store["runs"][label] = fn()
            save_json(RESULTS, store, indent=1)
        return store["runs"][label]

    summary = {}
    for gnl in {"off": [False], "on": [True], "both": [False, True]}[args.gnl]:
        tag = "GNL" if gnl else "linear"
        ref = cached(f"{tag} reference", lambda: nfrc_run(model, gnl, speeds, casing, args.revolutions, args.safety,
                                                          None, states=24 if gnl else 0))
        half = cached(f"{tag} reference h/2", lambda: nfrc_run(model, gnl, speeds, casing, args.revolutions,
                                                               args.safety, None, h=ref["h"] / 2))
        floor = compare(half, ref)
        print(f"\n{tag}, mu = {args.mu}, {int(n)} speeds {start:g}-{stop:g} rad/s, {args.revolutions:g} rev "
              f"(r = {model.r}); errors relative to the reference's peak {np.nanmax(ref['nfrc']) * 1e3:.3f} mm")
        print(f"{'run':>26} {'h (s)':>9} {'wall (s)':>9} {'speed-up':>8} {'median':>7} {'p90':>7} {'max':>7} "
              f"{'peak rad/s':>10} {'peak mm':>8} {'diverged':>8}")
        rows, curves = [], {}

        def show(label, run, err):
            ok = np.isfinite(run["nfrc"])
            k = int(np.nanargmax(run["nfrc"])) if ok.any() else 0
            print(f"{label:>26} {run['h']:>9.3g} {run['wall_s']:>9.1f} {ref['wall_s'] / run['wall_s']:>8.1f} "
                  f"{err['median']:>7.3f} {err['p90']:>7.3f} {err['max']:>7.3f} {speeds[k]:>10.0f} "
                  f"{run['nfrc'][k] * 1e3:>8.3f} {run['diverged']:>8d}")

        show("reference", ref, compare(ref, ref))
        show("reference h/2", half, floor)
        curves["reference"] = (speeds, ref["nfrc"], "o-")
        curves["reference h/2"] = (speeds, half["nfrc"], "s--")
        best = None
        for cap_khz in [None] + list(args.caps):
            # None: no cap, the largest step the unscaled model takes (0.9 h_crit linear, the tangent limit GNL)
            cap = None if cap_khz is None else 2 * np.pi * cap_khz * 1e3
            name = "no cap, larger h" if cap is None else f"cap {cap_khz:g} kHz"
            safety = 0.9 if cap is None else args.safety
            h = None
            if gnl:         # stress stiffening: the tangent limit on the reference's largest states, not 2/cap
                h = gnl_time_step(model, np.asarray(ref["states"]).T, cap, safety=args.tangent_safety,
                                  cap_safety=safety)
                print(f"  {name}: h = {h:.3g} s (tangent limit on the reference's largest states)")
            run = cached(f"{tag} {name}", lambda: nfrc_run(model, gnl, speeds, casing, args.revolutions, safety,
                                                           cap, h=h))
            err = compare(run, ref)
            run["error"] = err
            show(name, run, err)
            rows.append((name, run["wall_s"], err["p90"]))
            curves[name] = (speeds, run["nfrc"], ".-")
            sufficient = err["p90"] <= args.tol and err["p90"] <= floor["p90"] + args.tol and run["diverged"] == 0
            if sufficient and (best is None or run["wall_s"] < best[1]["wall_s"]):
                best = (cap_khz, run)
        rows.append(("reference h/2", half["wall_s"], floor["p90"]))
        plot_speed_accuracy(rows, f"results/convergence_cost_error_{tag.lower()}.png",
                            title=f"{tag}: p90 NFRC error vs wall time ({int(n)} speeds x {args.revolutions:g} rev)")
        plot_nfrc(curves, f"results/convergence_nfrc_{tag.lower()}.png")
        summary[tag] = {"noise_floor_p90": floor["p90"], "cheapest_sufficient": best and (best[0] or "no cap"),
                        "cheapest_sufficient_cap_khz": best and best[0],
                        "h": best and best[1]["h"], "p90_error": best and best[1]["error"]["p90"],
                        "speed_up": best and ref["wall_s"] / best[1]["wall_s"], "reference_h": ref["h"]}
        if best:
            print(f"cheapest sufficient ({tag}): {'no cap' if best[0] is None else f'cap {best[0]:g} kHz'}, "
                  f"h = {best[1]['h']:.3g} s, "
                  f"{ref['wall_s'] / best[1]['wall_s']:.1f}x faster than the reference")
        else:
            print(f"no cap meets p90 <= {args.tol} ({tag})")
    store["summary"] = summary
    save_json(RESULTS, store, indent=1)
    print(f"machine: {store['machine']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
