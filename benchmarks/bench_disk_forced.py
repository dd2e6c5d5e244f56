"""Bladed disk without contact (paper §3.3, Figs. 16-22): the reduced models' forced response against the full-order
reference, cost and error side by side.

Load: 400 N along e_z at node LE of every sector, travelling with N_d nodal diameters, from rest, ``--periods`` periods.
Reference: the full-order model of N / gcd(N, N_d) sectors closed on themselves (``fem.periodic``; implicit Newmark,
exact SVK tangent), linear for every case and GNL for the cases of ``--gnl-reference`` (the expensive part: checkpointed
under the output directory, resumed when run again). Reduced models: ``reduction.disk_builder.build_disk_model`` (r_b =
3, LE only, as the paper's §3.3 models) for each criterion and r_MD, integrated by the same Newmark at the same step, so
the error is the reduction's. Each pair is scored by the performance indicator I
(``disk.indicators.performance_indicator``: loaded node, tip nodes, field and strain-energy criteria), next to the
smallest field and strain-energy errors any state of the model could have (``disk.indicators.best_approximation``: the
reference's snapshots projected on the model's sector fields), which separates the basis's share of the error from that
of the reduced dynamics. Each row keeps the error histories behind its I (``disk.indicators.indicator_histories``),
which ``benchmarks/plot_disk_indicator.py`` charts with I against r_MD.

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

Your own bladed-disk sector instead of rotor 37's: ``--mesh sector.inp --clamp G --left G --right G --n-sectors N --tip
G --units mm`` (its node LE, the first contact node, carries the load); results under the tag ``own``.

Results: results/disk_forced_<preset>.json; reference histories and models cached under results/disk_forced/<preset>/.
"""
from __future__ import annotations

import resource
import sys
import time
from pathlib import Path

import numpy as np

from rotor37_rom import fem
from rotor37_rom.reduction.disk_builder import DiskReductionConfig, build_disk_model
from rotor37_rom.disk.indicators import best_approximation, indicator_histories, performance_indicator
from rotor37_rom.fem.periodic import RepeatingSectors
from rotor37_rom.checks import before_work
from rotor37_rom.cli import run_main
from rotor37_rom.machine import write_results
from rotor37_rom.studies.forced_response import parse_args, parse_case, reduced, reference


def main(argv=None) -> int:
    """The study; a bad option raises ValueError naming it (one line and exit status 2 through ``run_main``)."""
    args = parse_args(argv, description=__doc__.splitlines()[0])
    tag = "own" if args.mesh is not None else args.preset          # a user's sector (--mesh): results under own/
    out = Path(args.out) / tag
    before_work({"--out": out})
    cases = [parse_case(c) for c in args.cases]
    gnl_cases = {parse_case(c, "--gnl-reference") for c in args.gnl_reference}
    if args.choice is not None:
        print(args.choice.describe())
    t0 = time.perf_counter()
    sector = args.mesh.create() if args.mesh is not None else fem.create_disk_sector(preset=args.preset)
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
    name = f"disk_forced_{tag}{args.name}"

    def save() -> str:                                 # after every row: a stopped run keeps what it measured
        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        return write_results(name, rows, preset=tag, dofs_per_sector=sector.n_dofs, periods=args.periods,
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
    sys.exit(run_main(main))
