"""The impact numbers of the blade's contact nodes on 1B: full order and reduced models, each damping law (#88).

Pi = (m_eff / m_mode) / (4 pi zeta): the energy one impact can take over what damping takes a cycle
(``rotor37_rom.post.impact``). Results: results/bench_impact_numbers.json (--out).

    python benchmarks/bench_impact_numbers.py                  # the maps' r = 55 and r = 104 against the full order
    python benchmarks/bench_impact_numbers.py --global-md 3     # the maps' r = 55 alone
"""
from __future__ import annotations

import json
from pathlib import Path

from rotor37_rom.checks import before_work, real_number
from rotor37_rom.cli import ArgumentParser, run_main

RESULTS = Path("results/bench_impact_numbers.json")


def parse(argv):
    p = ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--r-c", type=int, default=25, help="the reduced models' fixed-interface modes, in [1, 200]")
    p.add_argument("--global-md", type=int, nargs="*", default=[3, 10], help="their modal derivatives of the first N "
                   "clamped modes, each N in [0, 20] (3: the maps' r = 55; 10: r = 104)")
    p.add_argument("--direction", default="x", help="contact normal: x, radial or cone")
    p.add_argument("--out", type=Path, default=RESULTS, help="the results file (.json)")
    args = p.parse_args(argv)
    if args.out.suffix != ".json":
        raise ValueError(f"--out must name a .json file, got {str(args.out)!r}")
    real_number("--r-c", args.r_c, 1, 200)
    for g in args.global_md:
        real_number("--global-md", g, 0, 20)
    from rotor37_rom.dynamics.casing import DIRECTIONS

    if args.direction not in DIRECTIONS:
        raise ValueError(f"--direction must be one of {', '.join(DIRECTIONS)}, got {args.direction!r}")
    return args


def main(argv=None) -> int:
    args = parse(argv)
    before_work({"--out": args.out.parent})
    from rotor37_rom import fem
    from rotor37_rom.dynamics.casing import Casing
    from rotor37_rom.dynamics.damping import DAMPING_LAWS
    from rotor37_rom.machine import machine_description
    from rotor37_rom.reduction.builder import ReductionConfig, build_reduced_model
    from rotor37_rom.studies.impact_numbers import blade_impact_numbers, table

    sector = fem.create_blade_sector(preset="ci")
    ops = fem.create_svk_operators(sector)
    models = {}
    for g in args.global_md:
        config = ReductionConfig(r_c=args.r_c, r_md=0, criterion="MI2b", global_md_modes=g, forces="intrusive")
        model, _ = build_reduced_model(sector, config, ops=ops, cache_dir="results/cache")
        models[f"r = {model.r} (r_c {args.r_c}, MDs of {g} modes)"] = model
    zetas = {name: law.low for name, law in DAMPING_LAWS.items()}
    rows = table(blade_impact_numbers(sector, ops, models, Casing(direction=args.direction), zetas))
    args.out.write_text(json.dumps({"rows": rows, "machine": machine_description()}, indent=1))
    print("| model | law (1B's zeta) | m_eff / m_mode over the contact nodes | Pi |\n|---|---|---|---|")
    for r in rows:
        print(f"| {r['model']} | {r['law']} ({r['zeta']:g}) | {r['ratio_min']:.2e} … {r['ratio_max']:.2e} | "
              f"{r['pi_min']:.2e} … {r['pi_max']:.2e} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(run_main(main))
