"""The reduced blade against a full-order reference in casing contact (issue #23, items 3 and 4).

The full-order reference is the ci blade's finite-element model (13,836 DOFs) integrated with implicit Newmark (average
acceleration, ``fem.solve_repeating_newmark`` with a casing): the same eight tip nodes, casing (eqs. 37-38), normal and
Coulomb law as the reduced models, each Newton iterate corrected by the multipliers that close every penetration at
t_n+1 (``dynamics.casing.ContactSolver`` on the iteration matrix's compliance). Both sides run undamped from rest over
the same ovalization ramp, so what differs is the reduction (and each side's time integration: the reference is run at
several steps, the finest being the reference). Reduced models: Craig-Bampton with r_b = 24 tip DOFs, r_c
fixed-interface modes, the global modal derivatives (of the first --global-md clamped modes: 6 for the default 3) and
r_MD MI 2b modal derivatives of the constraint modes, explicit central differences (``dynamics.explicit.simulate``) at
half the stability limit, unscaled. Among reduced models alone (--no-full-order: convergence in r, the largest the
reference) they keep their modal damping.

Error measures on the LE normal displacement u(t) (m), recorded every --record seconds: the relative RMS error
|u_rom - u_ref|_2 / |u_ref|_2 over the run, and the error of max |u| over the last revolution (the quantity a map is
made of) relative to the reference's. Completed runs are kept per model and speed in
results/bench_contact_reference[_gnl][_rom].json and not repeated when the script is started again with the same
case (revolutions, bump, mu), so a later command can add speeds, models or steps; the report compares the runs the
command names. Runs under way, full order and reduced, save their state every few minutes in the folder
results/bench_contact_reference[_gnl][_rom].ckpt, and the same command resumes them. With --rom-cap the reduced
models run at the given steps with the frequency cap (the maps' setting); several steps give the step's own error,
and the reference is the largest model at the smallest step.

    python benchmarks/bench_contact_reference.py --r-c 10 25 40 80        # linear: ~20 min
    python benchmarks/bench_contact_reference.py --gnl --no-full-order --speeds 1280 1520 --r-md 0 20 50 \
        --rom-cap 120 --rom-step 4e-7     # GNL convergence in r_MD at the maps' 120 kHz cap: 15 min
    python benchmarks/bench_contact_reference.py --gnl --no-full-order --speeds 1280 --r-md 0 20 50 100 \
        --rom-cap 120 --rom-step 4e-7     # r_MD = 100 (r = 155) too: + ~50 min (exact tensors, 9 min offline)
    python benchmarks/bench_contact_reference.py --gnl --speeds 1280 --h-full 2e-6 1e-6 --rho-inf 0.8 --r-md 0 20 50 \
        --rom-cap 120 --rom-step 4e-7     # GNL full order (generalised alpha) against the r_MD series: hours
    python benchmarks/bench_contact_reference.py --gnl --speeds 1280 --h-full 2e-6 --rho-inf 0.8 --r-md 0 20 50 100 \
        --rom-cap 120 --rom-step 4e-7 --contact-patch 3   # the same with 3 mm contact patches on both sides
    python benchmarks/bench_contact_reference.py --gnl --speeds 1280 --h-full 2e-6 --rho-inf 0.8 --r-md 0 \
        --global-md 3 6 10 --rom-cap 120 --rom-step 4e-7 --contact-patch 3   # more global modal derivatives
With GNL the full order needs --rho-inf: average acceleration leaves the tip nodes ringing after each impact at
frequencies the step does not resolve, and its Newton stalls in the first bump passage (docs/results.md).
Unscaled (no --rom-cap) the modal derivatives of the constraint modes shrink the explicit step 67 times from r_MD = 0
to 100 (docs/results.md).
"""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from rotor37_rom.machine import machine_description


def reference_run(sector, ops, casing, omega, duration, h, gnl, checkpoint, rho_inf=None, interface=None):
    """LE normal displacement of the full-order model every step, with the contact checks and the wall time;
    ``rho_inf``: generalised-alpha instead of average acceleration; ``interface``: the contact patches' C (the LE
    displacement is then its patch mean, as in the reduced models with the same patches)."""
    from rotor37_rom.dynamics.casing import contact_frames
    from rotor37_rom.fem.periodic import solve_repeating_newmark

    n_steps = int(round(duration / h))
    t0 = time.perf_counter()
    res = solve_repeating_newmark(sector, 1, None, None, h, n_steps, nonlinear=gnl, ops=ops, casing=casing,
                                  omega=omega, duration=duration, snapshot_every=n_steps, rtol=1e-6,
                                  checkpoint=checkpoint, rho_inf=rho_inf, contact_interface=interface)
    normal = contact_frames(sector.tip_nodes[:1], casing.direction, casing.rotation_sense, casing.cone_slope,
                            sector.blade_frame_angle())[0][0]
    le = res.tip[:, 0, 0, :] @ normal
    on = res.lam > 0
    return {"t": res.t.tolist(), "u_le": le.tolist(), "wall_s": time.perf_counter() - t0, "h": h,
            "steps": n_steps, "factorisations": int(res.refreshes), "newton_iterations": int(res.iterations.sum()),
            "rho_inf": rho_inf,
            "max_penetration": res.max_penetration, "friction_power": res.friction_power,
            "min_multiplier": float(res.lam[on].min()) if on.any() else None,
            "max_multiplier": float(res.lam.max()), "contact_steps": int(on.any(axis=1).sum())}


def rom_runs(model, casing, speeds, duration, gnl, record, cap=None, h=None, damping=False, checkpoint=None,
             checkpoint_seconds=300.0):
    """LE normal displacement of the reduced model at every speed (one batch): unscaled at 0.5 h_crit, or with the
    frequency cap ``cap`` (rad/s) at step h; undamped unless ``damping``. With ``checkpoint`` (a path) the loop state
    is saved there every ``checkpoint_seconds``, and a run of the same model, speeds, step, length and record interval
    resumes from it (the r = 169 GNL model at 2e-7 s runs for over an hour); its wall time counts the time run before
    the restart."""
    from rotor37_rom.dynamics.explicit import CentralDifference, simulate
    from rotor37_rom.dynamics.recorder import loop_state, save_loop_state

    scheme = CentralDifference(model, nonlinear=gnl, safety=0.5, damping=damping, frequency_cap=cap, h=h,
                               force=True)
    every = max(1, int(round(record / scheme.h)))
    n_steps = int(np.ceil(duration / scheme.h))
    speeds = np.asarray(speeds, float)
    ident = {"h": scheme.h, "n_steps": n_steps, "record_every": every}
    state, before = None, 0.0
    if checkpoint is not None and Path(checkpoint).exists():
        with np.load(checkpoint, allow_pickle=False) as data:
            if (str(data["model"]) == model.key and np.array_equal(data["speeds"], speeds)
                    and all(float(data[k]) == v for k, v in ident.items())):
                state, before = loop_state(data, speeds.size), float(data["elapsed"])
                print(f"  resuming at step {state.n} of {n_steps} ({before:.0f} s run before)", flush=True)
    t0 = time.perf_counter()
    save = None if checkpoint is None else (
        lambda st: save_loop_state(checkpoint, st, speeds, elapsed=before + time.perf_counter() - t0,
                                   model=np.array(model.key), **ident))
    bar = None
    try:
        from tqdm import tqdm
        bar = tqdm(total=n_steps * speeds.size, initial=0 if state is None else state.n * speeds.size,
                   unit="sim-step", unit_scale=True, mininterval=30, desc=f"r = {model.r}, h = {scheme.h:.3g} s")
    except ImportError:
        pass
    res = simulate(scheme, speeds, casing, n_steps=n_steps, duration=duration, record_every=every, on_blowup="flag",
                   state=state, checkpoint=save, checkpoint_seconds=checkpoint_seconds,
                   progress=None if bar is None else bar.update)
    if bar is not None:
        bar.close()
    row = res.row("0:LE")
    return [{"t": res.t[p].tolist(), "u_le": res.u_r[p][row].tolist(), "h": scheme.h, "wall_s": before + res.wall,
             "diverged": bool(res.diverged_step[p] >= 0), "max_penetration": float(res.max_penetration[p]),
             "diverged_t": float(res.diverged_step[p] * scheme.h) if res.diverged_step[p] >= 0 else None}
            for p in range(len(speeds))]


def errors(run, ref, omega):
    """(relative RMS error over the run, relative error of the last revolution's max |u|) of run against ref."""
    t, u = np.asarray(run["t"]), np.asarray(run["u_le"])
    u_ref = np.interp(t, np.asarray(ref["t"]), np.asarray(ref["u_le"]))
    last = t >= t[-1] - 2 * np.pi / omega
    peak_ref = np.abs(u_ref[last]).max()
    return (float(np.linalg.norm(u - u_ref) / np.linalg.norm(u_ref)),
            float((np.abs(u[last]).max() - peak_ref) / peak_ref))


def per_revolution(run, omega):
    """Per revolution of a run: (largest inward, mean, largest outward) LE normal displacement (m)."""
    t, u = np.asarray(run["t"]), np.asarray(run["u_le"])
    n = max(1, int(round(t[-1] * omega / (2 * np.pi))))
    rev = np.floor(t * omega / (2 * np.pi)).clip(0, n - 1).astype(int)        # the last sample ends revolution n
    return [(float(u[rev == k].min()), float(u[rev == k].mean()), float(u[rev == k].max())) for k in range(n)]


BANDS_HZ = (0.0, 2e3, 5e3, 10e3, 20e3, 50e3, np.inf)


def completed_revolutions(run, omega):
    """(a diverged run cut after the last whole revolution before it blew up, or None if it completed none; the time
    it blew up): the integrator's flagged step where the run has it, else its first non-finite sample or |u| above
    2 cm (the integrator's limit on the boundary coordinates)."""
    t, u = np.asarray(run["t"]), np.asarray(run["u_le"])
    if run.get("diverged_t") is not None:
        t_end = run["diverged_t"]
    else:
        bad = ~np.isfinite(u) | (np.abs(np.nan_to_num(u, nan=np.inf)) > 0.02)
        t_end = float(t[np.argmax(bad)] if bad.any() else t[-1])
    n = int(np.floor(t_end * omega / (2 * np.pi) + 1e-9))
    keep = t <= n * 2 * np.pi / omega + 1e-12
    return (None if n < 1 else {**run, "t": t[keep], "u_le": u[keep]}), t_end


def last_peak(run, omega):
    """The last revolution's max |u| of a run (m): the NFRC's quantity (``post.signals.last_revolution_max``)."""
    from rotor37_rom.post.signals import last_revolution_max

    return last_revolution_max(np.asarray(run["t"]), np.asarray(run["u_le"]), omega)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--speeds", type=float, nargs="+", default=[1280.0, 1520.0], help="rad/s")
    parser.add_argument("--revolutions", type=float, default=4.0)
    parser.add_argument("--gnl", action="store_true", help="SVK on both sides (default: linear)")
    parser.add_argument("--r-c", type=int, nargs="+", default=[25], help="fixed-interface modes of the ROMs")
    parser.add_argument("--r-md", type=int, nargs="+", default=[0], help="MI 2b modal derivatives of the ROMs")
    parser.add_argument("--global-md", type=int, nargs="+", default=[3],
                        help="the ROMs' modal derivatives of every pair of the first N clamped modes, N in 0..20 "
                             "(default 3: 1B, 1T, 2B, the 6 of the maps' model)")
    parser.add_argument("--h-full", type=float, nargs="+", default=[2e-6, 1e-6, 5e-7],
                        help="steps of the full-order runs (s); the finest is the reference")
    parser.add_argument("--rho-inf", type=float, default=None,
                        help="the full order by generalised alpha with this spectral radius at infinity, in [0, 1] "
                             "(default: average-acceleration Newmark); damps the tip nodes' unresolved ringing")
    parser.add_argument("--bump", type=float, default=0.625, help="bump height h_b (mm; the paper's 0.625)")
    parser.add_argument("--mu", type=float, default=0.0)
    parser.add_argument("--record", type=float, default=2e-6, help="record interval of the ROMs (s)")
    parser.add_argument("--no-full-order", action="store_true",
                        help="no full-order runs: the ROM with the largest r is the reference (convergence in r); "
                             "the ROMs then keep their modal damping (undamped, the GNL explicit scheme blows up at "
                             "0.5 h_crit within 4 revolutions)")
    parser.add_argument("--rom-cap", type=float, default=None, help="frequency cap of the ROMs (kHz; default none)")
    parser.add_argument("--rom-step", type=float, nargs="+", default=None,
                        help="steps of the ROMs with --rom-cap (s; several: each model at each step, the smallest "
                             "one's run of the largest model the reference; without a cap: 0.5 x the stability "
                             "limit)")
    parser.add_argument("--contact-patch", type=float, default=0.0, metavar="MM",
                        help="the contact force spread over the tip facets within MM of each node, in the ROMs "
                             "and the full order alike (issue #23; default 0: point contact)")
    parser.add_argument("--plot", default=None, metavar="PNG",
                        help="draw the LE histories of the reference and the compared models, one file per speed "
                             "(the speed appended to the name)")
    args = parser.parse_args(argv)
    from rotor37_rom.reduction.craig_bampton import GLOBAL_MD_MAX

    checks = (("--revolutions", [args.revolutions], 0.5, 50), ("--h-full", args.h_full, 1e-8, 1e-4),
              ("--bump", [args.bump], 0.0, 4.9), ("--mu", [args.mu], 0.0, 2.0), ("--speeds", args.speeds, 1.0, 5000),
              ("--record", [args.record], 1e-8, 1e-3), ("--r-c", args.r_c, 1, 500), ("--r-md", args.r_md, 0, 300),
              ("--global-md", args.global_md, 0, GLOBAL_MD_MAX),
              ("--rom-cap", [] if args.rom_cap is None else [args.rom_cap], 1.0, 1e4),
              ("--rom-step", args.rom_step or [], 1e-9, 1e-5),
              ("--rho-inf", [] if args.rho_inf is None else [args.rho_inf], 0.0, 1.0),
              ("--contact-patch", [args.contact_patch], 0.0, 10.0))
    for name, values, lo, hi in checks:
        if not all(np.isfinite(v) and lo <= v <= hi for v in values):
            parser.exit(2, f"bench_contact_reference.py: {name} must be in [{lo:g}, {hi:g}], got {values}\n")
    if (args.rom_cap is None) != (args.rom_step is None):
        parser.exit(2, "bench_contact_reference.py: give --rom-cap and --rom-step together\n")
    from rotor37_rom import fem
    from rotor37_rom.reduction.builder import ReductionConfig, build_reduced_model
    from rotor37_rom.dynamics.casing import Casing
    from rotor37_rom.post.signals import band_rms

    sector = fem.create_blade_sector(preset="ci")
    ops = fem.create_svk_operators(sector)
    casing = Casing(c0=0.5e-3, h_b=args.bump * 1e-3, mu=args.mu)
    speeds = np.asarray(args.speeds, float)
    results = Path("results/bench_contact_reference" + ("_gnl" if args.gnl else "")
                   + ("_rom" if args.no_full_order else "") + ".json")
    # the case (a change starts the file again, its checkpoints removed) and the ROMs' settings (a change redoes them);
    # runs are kept per speed, so a later command can add speeds or models without repeating the others
    settings = {"revolutions": args.revolutions, "bump_mm": args.bump, "mu": args.mu}
    rom_settings = {"record": args.record}
    store = json.loads(results.read_text()) if results.exists() else {}
    checkpoints = results.with_suffix(".ckpt")     # the runs under way: full_<key>.npz, rom_<label>_<speed>.npz
    if store.get("settings") != settings:
        for stale in checkpoints.glob("*.npz"):
            stale.unlink()
        store = {"settings": settings, "reference": {}, "roms": {}}
    if store.get("rom_settings") != rom_settings:
        for stale in checkpoints.glob("rom_*.npz"):
            stale.unlink()
        store["rom_settings"], store["roms"] = rom_settings, {}
    checkpoints.mkdir(parents=True, exist_ok=True)
    store["machine"] = machine_description()
    results.parent.mkdir(exist_ok=True)
    durations = {float(w): args.revolutions * 2 * np.pi / w for w in speeds}

    def save():
        tmp = results.with_suffix(".tmp")
        tmp.write_text(json.dumps(store))
        tmp.replace(results)

    save()              # the case on disk before any run: a restart must find it, or it would drop the checkpoints

    def ref_key(w, h):                             # average-acceleration runs keep their keys of before
        return f"{w:g} h {h:.3g}" + ("" if args.rho_inf is None else f" rho {args.rho_inf:g}") \
            + (f" patch {args.contact_patch:g} mm" if args.contact_patch else "")

    interface = fem.tip_patch_interface(sector, 1e-3 * args.contact_patch) if args.contact_patch else None

    for w in [] if args.no_full_order else speeds:
        for h in sorted(args.h_full, reverse=True):
            key = ref_key(w, h)
            if key not in store["reference"]:
                ckpt = checkpoints / f"full_{key.replace(' ', '_')}.npz"
                store["reference"][key] = reference_run(sector, ops, casing, w, durations[float(w)], h, args.gnl,
                                                        ckpt, args.rho_inf, interface)
                save()
                ckpt.unlink(missing_ok=True)
            ref = store["reference"][key]
            print(f"full order {key}: {ref['wall_s']:.0f} s, {ref['factorisations']} "
                  f"factorisations, {ref['contact_steps']} steps in contact, largest multiplier "
                  f"{ref['max_multiplier']:.0f} N, penetration left {ref['max_penetration']:.1e} m", flush=True)
    steps = [None] if args.rom_step is None else sorted(args.rom_step, reverse=True)

    def rom_label(r_c, r_md, g, h):
        return f"r_c {r_c} r_md {r_md}" + ("" if g == 3 else f" global {g}") \
            + ("" if h is None else f" cap {args.rom_cap:g} h {h:.3g}") \
            + (f" patch {args.contact_patch:g} mm" if args.contact_patch else "")

    combos = [(r_c, r_md, g, h) for r_c in args.r_c for r_md in args.r_md for g in args.global_md for h in steps]
    for r_c, r_md, g, h in combos:
        label = rom_label(r_c, r_md, g, h)
        todo = [w for w in speeds if f"{w:g}" not in store["roms"].get(label, {}).get("runs", {})]
        if todo:
            config = ReductionConfig(r_c=r_c, r_md=r_md, criterion="MI2b", global_md_modes=g,
                                     forces="intrusive" if args.gnl else "none",
                                     contact_patch=1e-3 * args.contact_patch)
            model, _ = build_reduced_model(sector, config, ops=ops, cache_dir="results/cache")
            store["roms"].setdefault(label, {"r": model.r, "runs": {}})
            for w in todo:                         # one speed at a time: each has its own run length
                ckpt = checkpoints / f"rom_{label.replace(' ', '_')}_{w:g}.npz"
                run, = rom_runs(model, casing, [w], durations[float(w)], args.gnl, args.record,
                                None if args.rom_cap is None else 2e3 * np.pi * args.rom_cap, h,
                                damping=args.no_full_order, checkpoint=ckpt)
                store["roms"][label]["runs"][f"{w:g}"] = run
                save()
                ckpt.unlink(missing_ok=True)
    kind = "GNL" if args.gnl else "linear"
    labels = [rom_label(*combo) for combo in combos]
    print(f"\n{kind}, mu = {args.mu:g}, h_b = {args.bump:g} mm, {args.revolutions:g} revolutions from rest; errors "
          f"of the LE normal displacement against "
          + ("the largest reduced model bounded at that speed" if args.no_full_order
             else f"the full order at h = {min(args.h_full):.3g} s"))
    print(f"{'model':>34} {'r':>4} {'speed':>6} {'RMS err':>8} {'peak err':>9} {'LE peak':>9} {'wall (s)':>9}")
    for w in speeds:
        runs = {k: (store["roms"][k]["r"], store["roms"][k]["runs"][f"{w:g}"]) for k in labels}
        if args.no_full_order:
            bounded = [k for k, (_, run) in runs.items() if not run["diverged"]]
            if not bounded:
                print(f"every reduced model diverged at {w:g} rad/s: no reference")
                continue
            ref = runs[max(bounded, key=lambda k: (runs[k][0], -runs[k][1]["h"]))][1]
        else:
            ref = store["reference"][ref_key(w, min(args.h_full))]
            for h in sorted(args.h_full, reverse=True):
                run = store["reference"][ref_key(w, h)]
                e = errors(run, ref, w)
                print(f"{f'full order h {h:.3g}':>34} {'':>4} {w:>6g} {e[0]:>8.3f} {e[1]:>+9.3f} "
                      f"{last_peak(run, w) * 1e3:>6.3f} mm {run['wall_s']:>9.0f}")
        for label, (r, run) in runs.items():
            if run["diverged"]:
                print(f"{label:>34} {r:>4} {w:>6g} diverged")
                continue
            e = errors(run, ref, w)
            print(f"{label:>34} {r:>4} {w:>6g} {e[0]:>8.3f} {e[1]:>+9.3f} {last_peak(run, w) * 1e3:>6.3f} mm "
                  f"{run['wall_s']:>9.1f}")
        print(f"per revolution, LE inward peak / mean / outward peak (mm); RMS error over the first revolution:")
        t_ref = np.asarray(ref["t"])
        one = t_ref <= 2 * np.pi / w
        coarser = [] if args.no_full_order else [(f"full order h {h:.3g}", store["reference"][ref_key(w, h)])
                                                 for h in sorted(args.h_full, reverse=True) if h != min(args.h_full)]
        shown = [("reference", ref)] + coarser + [(f"{k} (r = {r})", run) for k, (r, run) in runs.items()]
        for label, run in shown:
            if run.get("diverged"):                    # the revolutions it completed before the blow-up
                run, t_end = completed_revolutions(run, w)
                if run is None:
                    print(f"  {label}: diverged at {1e3 * t_end:.1f} ms, no whole revolution")
                    continue
                label += f" (diverged at {1e3 * t_end:.1f} ms; the revolutions before)"
            rows = "  ".join(f"{-1e3 * a:.3f}/{1e3 * m:+.3f}/{1e3 * b:.3f}" for a, m, b in per_revolution(run, w))
            u = np.interp(t_ref[one], np.asarray(run["t"]), np.asarray(run["u_le"]))
            e1 = np.linalg.norm(u - np.asarray(ref["u_le"])[one]) / np.linalg.norm(np.asarray(ref["u_le"])[one])
            print(f"  {label}: {rows}  ({e1:.0%})")
        print("last revolution, RMS of the LE normal displacement (its mean removed) by band " +
              " / ".join(f"{lo / 1e3:g}-{hi / 1e3:g}" for lo, hi in zip(BANDS_HZ[:-2], BANDS_HZ[1:-1]))
              + f" / > {BANDS_HZ[-2] / 1e3:g} kHz (mm): the first modes, or ringing at the tip's local frequencies")
        for label, run in ((label, run) for label, run in shown if not run.get("diverged")):
            rms = band_rms(np.asarray(run["t"]), np.asarray(run["u_le"]), w, BANDS_HZ,
                           revolutions=min(1.0, args.revolutions))
            print(f"  {label}: " + " / ".join(f"{1e3 * x:.3f}" for x in rms))
        if args.plot:
            from rotor37_rom.viz.charts import plot_time_history
            t = np.asarray(ref["t"])
            series = {("reference" if args.no_full_order else
                       f"full order, h = {ref['h']:.3g} s" + (f", rho_inf {ref['rho_inf']:g}"
                                                             if ref.get("rho_inf") is not None else "")): ref["u_le"]}
            series.update({f"{label} (r = {r})" + (" (diverged)" if run["diverged"] else ""):
                           np.interp(t, np.asarray(run["t"]), np.asarray(run["u_le"]))
                           for label, (r, run) in runs.items() if run is not ref})
            path = Path(args.plot)
            path = plot_time_history(t, series, path.with_name(f"{path.stem}_{w:g}{path.suffix or '.png'}"),
                                     title=f"{kind}, node LE, {w:g} rad/s, mu = {args.mu:g}",
                                     ylabel="normal displacement (mm)")
            print(f"chart: {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
