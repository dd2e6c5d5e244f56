"""Bladed disk without contact (paper §3.3, Figs. 16-22): the reduced models' forced response against the full-order
reference, cost and error side by side.

Load: 400 N along e_z at node LE of every sector, travelling with N_d nodal diameters, from rest, ``--periods``
periods. Reference: the full-order model of N / gcd(N, N_d) sectors closed on themselves (``fem.periodic``; implicit
Newmark, exact SVK tangent), linear for every case and GNL for the cases of ``--gnl-reference`` (the expensive part:
checkpointed under the output directory, resumed when run again). Reduced models: ``disk_builder.build_disk_model``
(r_b = 3, LE only, as the paper's §3.3 models) for each criterion and r_MD, integrated by the same Newmark at the
same step, so the error is the reduction's. Each pair is scored by the performance indicator I
(``disk.performance_indicator``: loaded node, tip nodes, field and strain-energy criteria), next to the smallest
field and strain-energy errors any state of the model could have (``disk.best_approximation``: the reference's
snapshots projected on the model's sector fields), which separates the basis's share of the error from that of the
reduced dynamics. Each row keeps the error histories behind its I (``disk.indicator_histories``), which
``benchmarks/plot_disk_indicator.py`` charts with I against r_MD.

A 400 N point force on the ci mesh's thin leading edge makes the GNL reference collapse locally (St. Venant-Kirchhoff
softens in compression; a point force on a continuum has no finite limit): ``--patch MM`` spreads the same 400 N as
an e_z traction over the boundary facets within MM mm of node LE (``fem.patch_load``), for the reference and the
reduced models alike; the models then carry the patch's static load correction (``--load-correction on``, one
vector per sector, ``DiskReductionConfig.load_patch``) or not (``off``). ``--face-shapes N_F`` builds the models
with the faces in the nonlinear force on N_F shapes (``DiskReductionConfig.face_shapes``; default 0: eq. 61).

    python benchmarks/bench_disk_forced.py [--preset ci] [--cases 0:4000 9:4000 ...] [--criteria MI2b MMI ...]
        [--r-md 0 5 10 20] [--periods 10] [--steps-per-period 100] [--gnl-reference 0:4000]
        [--patch 3 --load-correction on off] [--face-shapes N_F] [--tolerance 0.05]

``--tolerance T`` takes the model from the speed-accuracy study (scenes ``disk-forced-linear`` and, for a GNL reference
with ``--patch 3``, ``disk-forced-gnl``; docs/choosing-a-model.md) instead of the model options.

Results: results/disk_forced_<preset>.json; reference histories and models cached under results/disk_forced/<preset>/.
"""
from __future__ import annotations

import argparse
import resource
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import write_results  # noqa: E402

from rotor37_rom import fem  # noqa: E402
from rotor37_rom.disk.indicators import best_approximation, indicator_histories, performance_indicator
from rotor37_rom.disk.loads import harmonic_field_load, harmonic_node_load, repeat_count
from rotor37_rom.disk.builder import DiskReductionConfig, build_disk_model  # noqa: E402
from rotor37_rom.fem.periodic import RepeatingSectors, sector_harmonic_load, solve_repeating_newmark  # noqa: E402
from rotor37_rom.npz import save_npz  # noqa: E402
from rotor37_rom.reduction.craig_bampton import CRITERIA  # noqa: E402
from rotor37_rom.dynamics.newmark import simulate_newmark  # noqa: E402

AMPLITUDE = 400.0


def parse_case(text: str) -> tuple[int, float]:
    nd, _, omega = text.partition(":")
    try:
        return int(nd), float(omega)
    except ValueError:
        raise ValueError(f"a case reads '<N_d>:<omega rad/s>', e.g. 9:13000; got {text!r}") from None


def forced_model_choice(tolerance: float, gnl: bool):
    """The speed-accuracy study's cheapest disk model within ``tolerance`` for this command's runs (scene
    disk-forced-gnl or disk-forced-linear: node LE kept, MI 2b); ValueError naming --tolerance."""
    from rotor37_rom.studies.model_choice import choose_model

    try:
        return choose_model("disk-forced-gnl" if gnl else "disk-forced-linear", tolerance)
    except ValueError as exc:
        raise ValueError(f"--tolerance: {exc}") from None


def sector_load(sector, patch_mm: float):
    """The sector's load per unit amplitude: node LE's e_z DOF (``patch_mm`` = 0), else the e_z traction over the
    boundary facets within ``patch_mm`` of node LE (``fem.patch_load``, unit resultant)."""
    if patch_mm == 0:
        return int(sector.tip_dofs[sector.tip_names.index("LE"), 2])
    return fem.patch_load(sector, sector.tip_nodes[sector.tip_names.index("LE")], 1e-3 * patch_mm, component=2)


def reference(sector, system, case, nonlinear, periods, spp, ramp, out: Path, partial: bool = False,
              patch_mm: float = 0.0) -> dict:
    """The full-order history of one case (cached as .npz; GNL runs checkpoint). With ``partial``, an unfinished
    run's checkpoint is used as it stands (the window it covers, a whole number of snapshots) instead of running on."""
    nd, omega = case
    n_rep = repeat_count(sector.cyclic.n_sectors, nd)
    tag = (f"fom_nd{nd}_w{omega:g}_{'gnl' if nonlinear else 'lin'}_p{periods:g}_s{spp}_r{ramp:g}"
           + (f"_patch{patch_mm:g}" if patch_mm else ""))
    path = out / f"{tag}.npz"
    if path.is_file():
        with np.load(path) as d:
            return {k: d[k] for k in d.files}
    checkpoint = out / f"{tag}.checkpoint.npz"
    if partial and checkpoint.is_file():
        with np.load(checkpoint) as d:
            n = int(d["snaps"].max())                  # the window: up to the last snapshot
            return {"t": np.arange(n + 1) * 2 * np.pi / omega / spp, "tip": d["tips"][:n + 1],
                    "fields": d["fields"], "snapshots": d["snaps"],
                    "wall": np.float64(d["elapsed"]) if "elapsed" in d.files else np.float64(np.nan),
                    "partial": True}
    T = 2 * np.pi / omega
    steps = int(round(periods * spp))
    res = solve_repeating_newmark(sector, n_rep, sector_load(sector, patch_mm),
                                  sector_harmonic_load(n_rep, sector.cyclic.n_sectors, nd, AMPLITUDE, omega, ramp * T),
                                  T / spp, steps, nonlinear=nonlinear, rtol=1e-7, atol=1e-8 * AMPLITUDE,
                                  snapshot_every=max(spp // 10, 1),
                                  checkpoint=checkpoint, ops=system.ops)
    data = {"t": res.t, "tip": res.tip, "fields": res.fields, "snapshots": res.snapshots,
            "wall": np.float64(res.wall), "iterations": res.iterations}      # res.wall: a resumed run's parts too
    save_npz(path, **data)
    checkpoint.unlink(missing_ok=True)
    return data


def reduced(model, sector, case, nonlinear, periods, spp, ramp, ref, patch_mm: float = 0.0) -> dict:
    nd, omega = case
    T = 2 * np.pi / omega
    steps = ref["tip"].shape[0] - 1                  # the reference's window (all periods, or a partial run's)
    if patch_mm:
        load = harmonic_field_load(model.sectors, sector_load(sector, patch_mm), AMPLITUDE, omega, nd, ramp=ramp * T)
    else:
        load = harmonic_node_load(model.nodes, model.r, AMPLITUDE, omega, nd, ramp=ramp * T)
    t0 = time.perf_counter()
    _, Q = simulate_newmark(model.M, np.zeros_like(model.M), model.K, load, T / spp, steps,
                            forces=model.forces if nonlinear else None)
    wall = time.perf_counter() - t0
    n_rep = ref["tip"].shape[1]
    tip_dofs = np.asarray(sector.tip_dofs)
    basis = model.sectors
    tip = np.stack([basis.sector_field(Q, s, tip_dofs.ravel()).T.reshape(-1, *tip_dofs.shape)
                    for s in range(n_rep)], axis=1)
    fields = np.stack([np.stack([basis.sector_field(Q[:, k], s) for s in range(n_rep)])
                       for k in ref["snapshots"]])
    return {"tip": tip, "fields": fields, "wall": wall, "steps": steps}


MODEL_OPTIONS = {"--r-c": "r_c", "--r-md": "r_md", "--r-cyclic": "r_cyclic", "--criteria": "criteria",
                 "--face-shapes": "face_shapes"}
MODEL_DEFAULTS = {"r_c": 10, "r_md": [0, 5, 10, 20], "r_cyclic": 144, "criteria": ["MI2b"], "face_shapes": 0}


def parse_args(argv=None):
    """The command's options, checked (ValueError naming the option) and completed: with ``--tolerance`` the model
    options are the speed-accuracy study's choice (``args.choice``) and a GNL reference runs only where asked, on the
    study's GNL load (``--patch 3``); without it the defaults (MODEL_DEFAULTS, GNL reference of 0:4000)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--preset", default="ci", choices=["ci", "coarse", "paper"])
    parser.add_argument("--cases", nargs="+", default=["0:4000", "0:13000", "0:17000", "9:4000", "9:13000",
                                                       "9:17000"], help="N_d:omega pairs")
    parser.add_argument("--criteria", nargs="+", default=None, help=f"selection criteria {CRITERIA} (default MI2b)")
    parser.add_argument("--r-md", nargs="+", type=int, default=None, help="default: 0 5 10 20")
    parser.add_argument("--r-c", type=int, default=None, help="default: 10")
    parser.add_argument("--r-cyclic", type=int, default=None, help="default: 144")
    parser.add_argument("--interface", nargs="+", default=["closest"], choices=["closest", "per_k"],
                        help="interface-mode selection(s): eq. 51's closest frequencies or equal shares per harmonic")
    parser.add_argument("--periods", type=float, default=10.0)
    parser.add_argument("--steps-per-period", type=int, default=100)
    parser.add_argument("--gnl-reference", nargs="*", default=None,
                        help="cases that also get the (expensive) GNL full-order reference (default 0:4000; with "
                             "--tolerance, none unless given)")
    parser.add_argument("--ramp", type=float, default=1.0,
                        help="periods over which the load rises smoothly from 0 (0: a step where the phase is not 0)")
    parser.add_argument("--patch", type=float, default=0.0,
                        help="mm: spread the 400 N over the boundary facets within this radius of node LE (0: on the "
                             "node, the paper's point load)")
    parser.add_argument("--load-correction", nargs="+", default=["on"], choices=["on", "off"],
                        help="with --patch: the models get the patch load's static correction vector per sector "
                             "(DiskReductionConfig.load_patch), or not (the point-load models)")
    parser.add_argument("--partial", action="store_true",
                        help="score against an unfinished GNL reference (its checkpoint's window), not run it on")
    parser.add_argument("--face-shapes", type=int, default=None,
                        help="0: eq. 61's nonlinear force of q^n only; n_f >= 1: the faces in it on n_f shapes")
    parser.add_argument("--tolerance", type=float, default=None,
                        help="the speed-accuracy study's cheapest model within this relative error replaces --r-c, "
                             "--r-md, --r-cyclic, --criteria and --face-shapes (ci preset): scene disk-forced-gnl when "
                             "a GNL reference is asked (--gnl-reference, with --patch 3: the scene's load), else "
                             "disk-forced-linear")
    parser.add_argument("--out", default="results/disk_forced")
    parser.add_argument("--name", default="", help="results file suffix: results/disk_forced_<preset><name>.json")
    args = parser.parse_args(argv)
    args.choice = None
    if args.gnl_reference is None:
        args.gnl_reference = [] if args.tolerance is not None else ["0:4000"]
    cases = [parse_case(c) for c in args.cases]
    gnl_cases = {parse_case(c) for c in args.gnl_reference}
    if args.tolerance is not None:
        given = [opt for opt, dest in MODEL_OPTIONS.items() if getattr(args, dest) is not None]
        if given:
            raise ValueError(f"--tolerance chooses {', '.join(given)}: give one or the other")
        if args.preset != "ci":
            raise ValueError(f"--tolerance with --preset {args.preset}: the speed-accuracy study measured the ci "
                             "preset")
        gnl = bool(gnl_cases & set(cases))
        if gnl and args.patch != 3.0:
            raise ValueError(f"--tolerance with a GNL reference needs --patch 3 (the study's GNL load), got "
                             f"--patch {args.patch:g}")
        if gnl and "off" in args.load_correction:
            raise ValueError("--tolerance with --load-correction off: the study's GNL models carry the patch's "
                             "static correction")
        args.choice = forced_model_choice(args.tolerance, gnl)
        opts = args.choice.options
        args.r_c, args.r_md, args.r_cyclic = opts["r_c"], [opts["r_md"]], opts["r_cyclic"]
        args.criteria, args.face_shapes = ["MI2b"], opts.get("face_shapes", 0)
    for dest, value in MODEL_DEFAULTS.items():
        if getattr(args, dest) is None:
            setattr(args, dest, value)
    for nd, omega in cases:
        repeat_count(36, nd)
        if not 100.0 <= omega <= 1e5:
            raise ValueError(f"omega must be in [100, 1e5] rad/s, got {omega}")
    bad = [c for c in args.criteria if c not in CRITERIA]
    if bad:
        raise ValueError(f"criteria must be among {CRITERIA}, got {bad}")
    if args.face_shapes < 0:
        raise ValueError(f"face-shapes must be >= 0, got {args.face_shapes}")
    if min(args.r_md) < 0 or args.r_c < 1:
        raise ValueError(f"r-md must be >= 0 and r-c >= 1, got r-md {args.r_md}, r-c {args.r_c}")
    if not (args.periods > 0 and args.steps_per_period >= 20 and 0 <= args.ramp < args.periods):
        raise ValueError("periods must be > 0, steps-per-period >= 20 and ramp in [0, periods)")
    if not 0 <= args.patch <= 20:
        raise ValueError(f"patch must be in [0, 20] mm, got {args.patch:g}")
    return args


def main(argv=None) -> int:
    try:
        args = parse_args(argv)
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    cases = [parse_case(c) for c in args.cases]
    gnl_cases = {parse_case(c) for c in args.gnl_reference}
    if args.choice is not None:
        print(args.choice.describe())
    out = Path(args.out) / args.preset
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    sector = fem.create_disk_sector(preset=args.preset)
    system = RepeatingSectors(sector, 1)
    ops = system.ops
    K_s = fem.petsc_to_scipy(fem.assemble_stiffness(sector, ops, clamped=False))
    M_s = fem.petsc_to_scipy(fem.assemble_mass(sector, ops, clamped=False))
    setup = time.perf_counter() - t0
    refs = {}
    for case in cases:
        for nonlinear in (False, True):
            if nonlinear and case not in gnl_cases:
                continue
            refs[case, nonlinear] = reference(sector, system, case, nonlinear, args.periods,
                                              args.steps_per_period, args.ramp, out, partial=args.partial,
                                              patch_mm=args.patch)
            print(f"reference N_d = {case[0]}, omega = {case[1]:g}, {'GNL' if nonlinear else 'linear'}: "
                  f"{float(refs[case, nonlinear]['wall']):.1f} s", flush=True)
    rows = []
    name = f"disk_forced_{args.preset}{args.name}"

    def save() -> str:                                 # after every row: a stopped run keeps what it measured
        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        return write_results(name, rows, preset=args.preset, dofs_per_sector=sector.n_dofs, periods=args.periods,
                             steps_per_period=args.steps_per_period, setup_s=setup, peak_rss_mb=peak)
    corrections = [c == "on" for c in args.load_correction] if args.patch else [False]
    configs = [(c, r, i, lc) for lc in corrections for i in args.interface for c in args.criteria for r in args.r_md]
    for criterion, r_md, interface, correction in configs:
        config = DiskReductionConfig(tip_nodes="LE", r_c=args.r_c, r_md=r_md, criterion=criterion,
                                     r_cyclic=args.r_cyclic, interface=interface,
                                     forces="intrusive" if r_md else "none",
                                     load_patch=1e-3 * args.patch if correction else 0.0,
                                     face_shapes=args.face_shapes if r_md else 0)
        tb = time.perf_counter()
        model, report = build_disk_model(sector, config, ops=ops, cache_dir=out / "models")
        build = time.perf_counter() - tb
        for (case, nonlinear), ref in refs.items():
            if nonlinear and model.forces is None and r_md:
                continue
            try:
                rom = reduced(model, sector, case, nonlinear and model.forces is not None, args.periods,
                              args.steps_per_period, args.ramp, ref, patch_mm=args.patch)
            except RuntimeError as exc:                   # Newton failed even at dt / 32: a failure, reported
                rows.append({"patch_mm": args.patch, "load_correction": correction, "criterion": criterion,
                             "r_md": r_md, "interface": interface, "r": model.r,
                             "N_d": case[0], "omega": case[1], "gnl": nonlinear, "failed": str(exc)})
                print(f"{criterion} r_md {r_md} N_d {case[0]} omega {case[1]:g}: failed ({exc})", flush=True)
                save()
                continue
            score = performance_indicator(ref["tip"], rom["tip"], ref["fields"], rom["fields"], K_s, M_s,
                                          loaded=(sector.tip_names.index("LE"), 2))
            best = best_approximation(model.sectors, ref["fields"], K_s, M_s)   # the basis's share of the error
            hist = indicator_histories(ref["tip"], rom["tip"], ref["fields"], rom["fields"], K_s, M_s,
                                       loaded=(sector.tip_names.index("LE"), 2))
            row = {"ramp_periods": args.ramp, "patch_mm": args.patch, "load_correction": correction,
                   "face_shapes": model.forces.faces.shape[1] // 2 if model.forces is not None
                   and model.forces.faces is not None else 0,
                   "criterion": criterion, "r_md": r_md, "interface": interface,
                   "r": model.r, "N_d": case[0], "omega": case[1],
                   "gnl": nonlinear, "window_periods": (ref["tip"].shape[0] - 1) / args.steps_per_period,
                   "rom_gnl": bool(nonlinear and model.forces is not None),
                   "I": score["I"], "errors": score["errors"], "best_approximation": best, "rom_wall_s": rom["wall"],
                   "rom_us_per_step": 1e6 * rom["wall"] / rom["steps"], "build_s": build,
                   "build_cached": bool(report.get("cached")), "fom_wall_s": float(ref["wall"]),
                   "max_le_z_mm": 1e3 * float(np.abs(ref["tip"][:, :, sector.tip_names.index("LE"), 2]).max()),
                   "rom_max_le_z_mm": 1e3 * float(np.abs(rom["tip"][:, :, sector.tip_names.index("LE"), 2]).max()),
                   "histories": {"t_periods": (np.arange(ref["tip"].shape[0]) / args.steps_per_period).tolist(),
                                 "snapshot_periods": (np.asarray(ref["snapshots"]) / args.steps_per_period).tolist(),
                                 **{k: v.tolist() for k, v in hist.items()}}}
            rows.append(row)
            save()
            print(f"{interface:7s} {'S ' if correction else ''}{criterion:6s} r_md {r_md:3d} r {model.r:5d}  "
                  f"N_d {case[0]:2d} omega {case[1]:7g} "
                  f"{'GNL' if nonlinear else 'lin'}  I = {score['I']:.4f}  "
                  + " ".join(f"{k}: {v:.2e}" for k, v in score["errors"].items())
                  + f" (basis alone: {best['field']:.2e} / {best['strain energy']:.2e})"
                  + f"  ROM {rom['wall']:.2f} s, FOM {float(ref['wall']):.0f} s", flush=True)
    machine = save()
    print(f"{machine}; peak RSS {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MB; "
          f"results in results/{name}.json")
    return 0


if __name__ == "__main__":
    sys.exit(main())
