"""Forced response of the bladed disk without contact (paper §3.3, Figs. 16-22): the load, the full-order reference
and the reduced models' runs against it, and the options of the study (``benchmarks/bench_disk_forced.py``; the
speed-accuracy study's scenes disk-forced-linear and disk-forced-gnl run the same reference and reduced runs).

Load: 400 N (``AMPLITUDE``) along e_z at node LE of every sector, travelling with N_d nodal diameters, or the same
resultant spread over the boundary facets near node LE (``sector_load``). Reference: the full-order model of
N / gcd(N, N_d) sectors closed on themselves (``fem.periodic``; implicit Newmark, exact SVK tangent), cached as .npz
and checkpointed; reduced runs by the same Newmark at the same step, so the error is the reduction's.
"""
from __future__ import annotations

import re
import time
from pathlib import Path

import numpy as np

from rotor37_rom import fem
from rotor37_rom.checks import fits_in_memory, real_number, whole_number
from rotor37_rom.cli import ArgumentParser
from rotor37_rom.disk.loads import harmonic_field_load, harmonic_node_load, repeat_count
from rotor37_rom.dynamics.newmark import simulate_newmark
from rotor37_rom.fem.periodic import sector_harmonic_load, solve_repeating_newmark
from rotor37_rom.npz import save_npz
from rotor37_rom.reduction.craig_bampton import CRITERIA
from rotor37_rom.studies.sector_file import SectorFile, add_sector_options

AMPLITUDE = 400.0


def parse_case(text: str, option: str = "--cases") -> tuple[int, float]:
    """(N_d, omega) of a case written '<N_d>:<omega rad/s>'; ValueError naming ``option`` otherwise."""
    nd, _, omega = text.partition(":")
    try:
        return int(nd), float(omega)
    except ValueError:
        raise ValueError(f"{option}: a case reads '<N_d>:<omega rad/s>', e.g. 9:13000; got {text!r}") from None


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
    """One reduced model's history of ``case`` over the reference's window (``ref``: all periods, or a partial
    run's), by the same Newmark at the same step: the tip nodes of every sector of the repeat, its fields at the
    reference's snapshots, the wall time and the steps."""
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


def parse_args(argv=None, description: str | None = None):
    """The command's options (``benchmarks/bench_disk_forced.py``; ``description`` heads its --help), checked
    (ValueError naming the option) and completed: with ``--tolerance`` the model options are the speed-accuracy
    study's choice (``args.choice``) and a GNL reference runs only where asked, on the study's GNL load (``--patch
    3``); without it the defaults (MODEL_DEFAULTS, GNL reference of 0:4000)."""
    parser = ArgumentParser(description=description)
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
    add_sector_options(parser)
    args = parser.parse_args(argv)
    args.mesh = SectorFile.from_args(args, parser)
    n_sectors = 36 if args.mesh is None else args.mesh.n_sectors
    if args.mesh is not None and n_sectors is None:
        raise ValueError("--mesh: the forced response is a bladed disk's: give --left, --right and --n-sectors")
    args.choice = None
    if args.gnl_reference is None:
        args.gnl_reference = [] if args.tolerance is not None else ["0:4000"]
    cases = [parse_case(c) for c in args.cases]
    gnl_cases = {parse_case(c, "--gnl-reference") for c in args.gnl_reference}
    if not re.fullmatch(r"[\w.-]*", args.name):
        raise ValueError(f"--name must be letters, digits, '_', '-' or '.' (a file name's suffix), got {args.name!r}")
    if args.tolerance is not None:
        real_number("--tolerance", args.tolerance, 0, 1, open_low=True, open_high=True)
        given = [opt for opt, dest in MODEL_OPTIONS.items() if getattr(args, dest) is not None]
        if given:
            raise ValueError(f"--tolerance chooses {', '.join(given)}: give one or the other")
        if args.mesh is not None:
            raise ValueError("--tolerance with --mesh: the speed-accuracy study measured rotor 37's disk; give the "
                             "options for your sector")
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
        try:
            repeat_count(n_sectors, nd)
        except ValueError as exc:
            raise ValueError(f"--cases: {exc}") from None
        real_number("--cases: omega", omega, 100.0, 1e5, unit=" rad/s")
    bad = [c for c in args.criteria if c not in CRITERIA]
    if bad:
        raise ValueError(f"--criteria must be among {CRITERIA}, got {bad}")
    whole_number("--face-shapes", args.face_shapes, 0)
    for r_md in args.r_md:
        whole_number("--r-md", r_md, 0)
    whole_number("--r-c", args.r_c, 1)
    whole_number("--r-cyclic", args.r_cyclic, 1)
    real_number("--periods", args.periods, 0, 1000, open_low=True)        # 1,000 periods: 100,000 steps and more
    whole_number("--steps-per-period", args.steps_per_period, 20, 10000)
    real_number("--ramp", args.ramp, 0, args.periods, open_high=True, unit=" periods (below --periods)")
    real_number("--patch", args.patch, 0, 20, unit=" mm")
    # a reduced run keeps its state at every step: r = 36 (r_b + r_c + r_md) + r_cyclic, r_b = 3 (node LE)
    steps, r = args.periods * args.steps_per_period, 36 * (3 + args.r_c + max(args.r_md)) + args.r_cyclic
    fits_in_memory("--periods", 8.0 * (steps + 1) * r, f"{steps:.0f} steps x r = {r}",
                   hint="fewer --periods or --steps-per-period")
    return args
