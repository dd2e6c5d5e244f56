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

from pathlib import Path

from rotor37_rom.checks import before_work, real_number
from rotor37_rom.cli import ArgumentParser, run_main

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
    p.add_argument("--map", type=float, nargs=3, default=None, metavar=("START", "STOP", "N"),
                   help="also each --r-c model's steady map over N speeds in [START, STOP] rad/s, GNL off and on, "
                        "under the first speed's case (studies.steady_reference.run_steady_maps); N in [2, 1000]")
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
    if args.map is not None:
        real_number("--map START", args.map[0], 1.0, 5000.0)
        real_number("--map STOP", args.map[1], args.map[0], 5000.0, open_low=True)
        real_number("--map N", args.map[2], 2, 1000)
        if args.map[2] != int(args.map[2]) or not args.r_c:
            raise ValueError(f"--map N must be a whole number of speeds and --map needs --r-c models, got "
                             f"{args.map[2]:g} with --r-c {args.r_c}")
        args.map = (args.map[0], args.map[1], int(args.map[2]))
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


def config_of(args, cases):
    """The study's config from the checked options."""
    from rotor37_rom.studies.steady_reference import FullOrderSettings, ReducedSettings, SteadyStudyConfig

    full = FullOrderSettings(steps=tuple(args.h_full) or (2e-6,), rho_inf=args.rho_inf, snapshots=args.snapshots,
                             energy=args.energy, run=not args.no_full_order and bool(args.h_full))
    reduced = ReducedSettings(r_c=tuple(args.r_c), global_md=tuple(args.global_md), step=args.rom_step,
                              cap_khz=args.rom_cap, pod=tuple(args.pod), cubature=args.cubature,
                              train_speeds=tuple(args.train_speeds), batch_cost=args.batch_cost)
    return SteadyStudyConfig(tuple(cases), full, reduced, RESULTS)


def main(argv=None) -> int:
    args, cases = parse(argv)
    config = config_of(args, cases)
    before_work({"results": RESULTS.parent})
    from rotor37_rom.studies.steady_reference import run_steady_maps, run_steady_study

    for result in run_steady_study(config):
        if result.reference is not None:
            table(result.rows, result.case, result.reference)
    if args.map is not None:
        run_steady_maps(config, args.map)
    return 0


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


if __name__ == "__main__":
    raise SystemExit(run_main(main))
