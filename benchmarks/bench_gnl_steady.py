"""GNL in contact at steady state: the full-order reference against reduced models under one damping law (#86).

Each (speed, step) of the full order and each reduced model runs ``studies.gnl_reference`` for --revolutions at most
and is judged steady or not (max |u_LE| over a revolution changing by < 2 % a revolution over the last two); the
table gives the last revolution's max |u_LE|, marked "not steady" where it is not. Completed runs are kept in
results/bench_gnl_steady.json (per case) and not repeated; full-order runs under way checkpoint in
results/bench_gnl_steady.ckpt/ every 10 min, and the same command resumes them (SIGTERM: saved, then stops). With
--snapshots the full order's fields (100 a revolution) are kept in results/bench_gnl_steady.ckpt/ for a POD basis.

    python benchmarks/bench_gnl_steady.py --speeds 1280 --h-full 2e-6 --snapshots      # ~2-3 h a speed, 1 core
    python benchmarks/bench_gnl_steady.py --speeds 1280 --no-full-order --r-c 25       # the maps' r = 55: minutes
    python benchmarks/bench_gnl_steady.py --speeds 1280 1450 --r-c 25 --global-md 3 10 --pod 55   # against it
    python benchmarks/bench_gnl_steady.py --speeds 1280 1450 --no-full-order --global-md 10 --cubature 1e-4
    python benchmarks/bench_gnl_steady.py --speeds 1280 --hyperelastic neo-hookean --r-c   # the second law's full order
"""
from __future__ import annotations

import dataclasses
import json
import os
from pathlib import Path

import numpy as np

from rotor37_rom.checks import before_work, real_number
from rotor37_rom.cli import ArgumentParser, run_main
from rotor37_rom.machine import machine_description

RESULTS = Path("results/bench_gnl_steady.json")


def parse(argv):
    """The options and the cases, each checked (one line naming the option, exit status 2)."""
    p = ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--speeds", type=float, nargs="+", default=[1280.0], help="rad/s, in [1, 5000]")
    p.add_argument("--mu", type=float, default=0.0, help="Coulomb coefficient, in [0, 2]")
    p.add_argument("--direction", default="x", help="contact normal: x, radial or cone")
    p.add_argument("--law", default="heavy", help="damping law: maps or heavy (dynamics.damping.DAMPING_LAWS)")
    p.add_argument("--revolutions", type=int, default=8, help="revolution limit, in [3, 200]")
    p.add_argument("--h-full", type=float, nargs="*", default=[2e-6], help="full-order steps (s), in [1e-8, 1e-4]")
    p.add_argument("--rho-inf", type=float, default=0.8, help="generalised alpha's rho_inf, in [0, 1]")
    p.add_argument("--no-full-order", action="store_true", help="the reduced models only")
    p.add_argument("--snapshots", action="store_true", help="keep the full order's fields, 100 a revolution")
    p.add_argument("--r-c", type=int, nargs="*", default=[25], help="reduced models' fixed-interface modes, [1, 200]")
    p.add_argument("--global-md", type=int, nargs="+", default=[3], help="the reduced models' modal derivatives of "
                   "the first N clamped modes, each N in [0, 20] (3: the maps' r = 55; 10: r = 104)")
    p.add_argument("--rom-step", type=float, default=4e-7, help="reduced models' step (s), in [1e-9, 1e-5]")
    p.add_argument("--rom-cap", type=float, default=120.0, help="reduced models' frequency cap (kHz), in [1, 1e4]")
    p.add_argument("--pod", type=int, nargs="*", default=[], help="POD-Galerkin models of these ranks from the full "
                   "order's snapshots at the largest --h-full (run with --snapshots first), each in [24, 400]")
    p.add_argument("--energy", type=float, default=None, help="carry each finished full-order run on for this many "
                   "revolutions, in (0, 20], and close its energy balance (studies.gnl_reference.full_order_energy)")
    p.add_argument("--batch-cost", type=int, default=0, help="also time each --r-c model in a map's batch of this "
                   "many speeds (0: not), in [0, 1000]")
    p.add_argument("--hyperelastic", default="svk", help="the full order's law: svk or neo-hookean (the full order "
                   "alone: the reduced models are SVK's)")
    p.add_argument("--cubature", type=float, default=None, help="run the --r-c models on a point cubature of this "
                   "tolerance, in (0, 0.1], trained on their own exact runs at --train-speeds (no full order)")
    p.add_argument("--train-speeds", type=float, nargs="+", default=[1200.0, 1600.0], help="the cubature's training "
                   "runs (rad/s, in [1, 5000]), 3 revolutions each")
    args = p.parse_args(argv)
    for name, values, lo, hi in (("--h-full", args.h_full, 1e-8, 1e-4), ("--rho-inf", [args.rho_inf], 0.0, 1.0),
                                 ("--r-c", args.r_c, 1, 200), ("--rom-step", [args.rom_step], 1e-9, 1e-5),
                                 ("--rom-cap", [args.rom_cap], 1.0, 1e4),
                                 ("--pod", args.pod, 24, 400), ("--global-md", args.global_md, 0, 20),
                                 ("--train-speeds", args.train_speeds, 1.0, 5000.0)):
        for v in values:
            real_number(name, v, lo, hi)
    real_number("--batch-cost", args.batch_cost, 0, 1000)
    if args.energy is not None:
        real_number("--energy", args.energy, 0.0, 20.0, open_low=True)
    if args.cubature is not None:
        real_number("--cubature", args.cubature, 0.0, 0.1, open_low=True)
    from rotor37_rom.studies.gnl_reference import SteadyCase

    options = {"speed": "--speeds", "mu": "--mu", "direction": "--direction", "damping law": "--law",
               "revolutions": "--revolutions", "hyperelastic": "--hyperelastic"}
    try:
        cases = [SteadyCase(w, mu=args.mu, direction=args.direction, law=args.law, revolutions=args.revolutions,
                            hyperelastic=args.hyperelastic) for w in args.speeds]
    except ValueError as err:                  # the config's field named as the option the user gave
        field = next((f for f in options if str(err).startswith(f)), None)
        raise ValueError(str(err).replace(field, options[field], 1) if field else str(err)) from None
    if args.hyperelastic != "svk" and (args.r_c or args.pod):
        raise ValueError(f"--hyperelastic {args.hyperelastic}: the reduced models are SVK's; run this full order "
                         f"alone (--r-c with no value, no --pod)")
    return args, cases


def main(argv=None) -> int:
    args, cases = parse(argv)
    before_work({"results": RESULTS.parent})
    from rotor37_rom import fem
    from rotor37_rom.model.reduced import load_reduced_model, save_reduced_model
    from rotor37_rom.reduction.builder import ReductionConfig, build_reduced_model
    from rotor37_rom.studies import gnl_reference as gr

    store = json.loads(RESULTS.read_text()) if RESULTS.exists() else {}
    store["machine"] = machine_description()
    ckpts = RESULTS.with_suffix(".ckpt")           # full-order runs under way
    ckpts.mkdir(parents=True, exist_ok=True)

    def save():                  # merged with what other runs of this command saved meanwhile (one per core)
        on_disk = json.loads(RESULTS.read_text()) if RESULTS.exists() else {}
        for label, runs in store.items():
            if isinstance(runs, dict) and label != "machine":
                runs.update({**on_disk.get(label, {}), **runs})     # in place: the loop's `runs` is this dict
                on_disk[label] = runs
        on_disk["machine"] = store["machine"]
        tmp = RESULTS.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text(json.dumps(on_disk))
        tmp.replace(RESULTS)

    sector = fem.create_blade_sector(preset="ci")
    ops = fem.create_svk_operators(sector, law=args.hyperelastic)
    models, cap = {}, 2e3 * np.pi * args.rom_cap      # the reduced models, their damping and cubature, by (r_c, g)
    for case in cases:
        runs = store.setdefault(case.label(), {})
        for h in [] if args.no_full_order else sorted(args.h_full, reverse=True):
            key = f"full h {h:.3g} rho {args.rho_inf:g}"
            if key not in runs:
                stem = full_order_stem(ckpts, case, key)
                run, snaps = gr.full_order_run(sector, ops, case, h, args.rho_inf, stem.with_name(stem.name + ".npz"),
                                               100 if args.snapshots else 0)
                if snaps is not None:
                    np.save(stem.with_name(stem.name + ".snapshots.npy"), snaps)
                runs[key] = run.to_json()
                save()
            if args.energy is not None and runs[key].get("energy", {}).get("revolutions") != args.energy:
                stem = full_order_stem(ckpts, case, key)
                runs[key]["energy"] = gr.full_order_energy(sector, ops, case, h, args.rho_inf,
                                                           stem.with_name(stem.name + ".npz"), args.energy)
                print(f"{case.label()} | {key}: energy per revolution (J) {json.dumps(runs[key]['energy'])}",
                      flush=True)
                maxima = runs[key]["maxima"] + runs[key]["energy"]["maxima"]       # the run's, then carried on
                changes = np.abs(np.diff(maxima[-3:])) / np.asarray(maxima[-3:-1])
                print(f"{case.label()} | {key}: carried on {args.energy:g} revolutions, max |u_LE| per revolution "
                      f"(mm) " + " ".join(f"{1e3 * m:.3f}" for m in maxima) + "; last changes "
                      + ", ".join(f"{100 * c:.1f} %" for c in changes)
                      + (" (steady)" if (changes < case.tolerance).all() else " (not steady)"), flush=True)
                save()
            report(case, key, runs[key])
        for r in args.pod:
            key = f"pod r {r} cap {args.rom_cap:g} h {args.rom_step:.3g}"
            if key not in runs:
                h = max(args.h_full) if args.h_full else 2e-6
                stem = full_order_stem(ckpts, case, f"full h {h:.3g} rho {args.rho_inf:g}")
                snaps = stem.with_name(stem.name + ".snapshots.npy")
                if not snaps.exists():
                    raise ValueError(f"--pod: no full-order snapshots for {case.label()} at h {h:.3g} s ({snaps}): "
                                     f"run the full order with --snapshots first")
                model, bound = gr.pod_model(sector, ops, np.load(snaps), r, cache_dir="results/cache")
                C = gr.reduced_damping(model, sector, ops, case.damping)
                runs[key] = gr.reduced_run(model, C, case, args.rom_step, cap).to_json()
                runs[key]["details"]["pod_bound"] = bound
                save()
            report(case, key, runs[key])
        for r_c, g in ((r_c, g) for r_c in args.r_c for g in args.global_md):
            hr = "" if args.cubature is None else (f" cubature {args.cubature:g} train "
                                                    + "/".join(f"{w:g}" for w in args.train_speeds))
            key = (f"rom r_c {r_c}" + ("" if g == 3 else f" global md {g}")
                   + f"{hr} cap {args.rom_cap:g} h {args.rom_step:.3g}")
            if (r_c, g) not in models:                    # the cases differ by their speed alone: built once
                config = ReductionConfig(r_c=r_c, r_md=0, criterion="MI2b", global_md_modes=g, forces="intrusive")
                model, _ = build_reduced_model(sector, config, ops=ops, cache_dir="results/cache")
                C, info = gr.reduced_damping(model, sector, ops, case.damping), None
                if args.cubature is not None:              # trained once for every speed, kept for the next run
                    name = (f"cubature r_c {r_c} md {g}{hr} mu {case.mu:g} {case.direction} {case.law} "
                            f"cap {args.rom_cap:g} h {args.rom_step:.3g}")
                    stem = ckpts / name.replace(" ", "_").replace("/", "-")
                    kept = stem.with_name(stem.name + ".npz")
                    if kept.exists():
                        model = load_reduced_model(kept)
                    else:
                        model, info = gr.cubature_model(model, C, sector, case, args.rom_step, cap, args.cubature,
                                                        args.train_speeds,
                                                        checkpoint=stem.with_name(stem.name + ".training.npz"))
                        model = dataclasses.replace(model, metadata={**model.metadata, "steady_cubature": info})
                        save_reduced_model(model, kept)
                    info = model.metadata["steady_cubature"]
                models[r_c, g] = model, C, info
            model, C, info = models[r_c, g]
            made = runs.get(key, {}).get("details", {}).get("model")
            if made is not None and made != f"reduced r = {model.r}":       # kept from a model built otherwise
                print(f"{case.label()} | {key}: the run kept was of a {made}, this model has r = {model.r}: run again")
            if made != f"reduced r = {model.r}":
                runs[key] = gr.reduced_run(model, C, case, args.rom_step, cap).to_json()
                if info is not None:
                    runs[key]["details"]["cubature"] = info
                save()
            if args.batch_cost and runs[key]["details"].get("batch", {}).get("speeds") != args.batch_cost:
                runs[key]["details"]["batch"] = gr.batch_cost(model, C, case, args.rom_step, cap, args.batch_cost)
                print(f"{case.label()} | {key}: in a batch of {args.batch_cost} speeds "
                      f"{runs[key]['details']['batch']['us_per_speed_step']:.1f} us per speed-step", flush=True)
                save()
            report(case, key, runs[key])
        save()                                    # merged with the other runs of this case on disk
        runs = store[case.label()]
        full = sorted((k for k in runs if k.startswith("full")), key=lambda k: float(k.split()[2]))
        if full:
            table(gr.compare_runs(case, runs, full[0]), case, full[0])
    return 0


def full_order_stem(folder: Path, case, key: str) -> Path:
    """The files' stem of a full-order run (its checkpoint <stem>.npz, its snapshots <stem>.snapshots.npy): the case
    and the run's key, the dots of its numbers kept (rho 0.8 and 0.9 are two runs)."""
    return folder / f"{case.label()} {key}".replace(" ", "_").replace("/", "")


def table(rows, case, reference):
    """The case's runs against the full order at its finest step, as Markdown."""
    print(f"\n{case.label()}, against {reference}:\n\n| run | max \\|u_LE\\| (mm) | towards the casing (mm) | "
          f"error | error towards the casing | wall per revolution (s) | cost ratio |\n|---|---|---|---|---|---|---|")
    for r in rows:
        def pct(e):
            return "—" if e is None else f"{100 * e:+.1f} %"
        flag = "" if r["steady"] else " (not steady)"
        print(f"| {r['run']} | {1e3 * r['value']:.3f}{flag} | {1e3 * r['towards_casing']:.3f} | {pct(r['error'])} | "
              f"{pct(r['error_towards_casing'])} | {r['wall_per_revolution_s']:.1f} | {r['cost_ratio']:.0f} |")


def report(case, key, run):
    from rotor37_rom.studies.gnl_reference import revolution_peaks

    inward, outward = revolution_peaks(run["t"], run["u_le"], case.speed)
    value = f"{1e3 * run['value']:.3f} mm" + ("" if run["steady"] else " (NOT STEADY)")
    print(f"{case.label()} | {key}: max |u_LE| {value}; per revolution, towards the axis / the casing (mm): "
          + "  ".join(f"{1e3 * a:.3f}/{1e3 * b:.3f}" for a, b in zip(inward, outward))
          + f"; {run['reason']}; {run['wall_s']:.0f} s", flush=True)


if __name__ == "__main__":
    raise SystemExit(run_main(main))
