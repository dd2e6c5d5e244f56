"""Speed against accuracy: per scene, the cost and the error of every candidate model, one study (issue #22).

    python benchmarks/speed_accuracy.py                       # all scenes (52 min from scratch on the 2-core machine)
    python benchmarks/speed_accuracy.py --scene modes clearance map-linear
    python benchmarks/speed_accuracy.py --scene disk                # the bladed disk's scenes
    make speed-accuracy                                       # the same as the first line

Scenes (the report's settings):
- ``modes``: the clamped 1B/1T/2B frequencies against mesh presets ci / coarse / paper; reference: the paper preset
  (the presets are remeshed, not nested: no Richardson limit), whose own error is taken as its change from coarse;
  held out: modes 4-6.
- ``clearance``: the clearance consumption of 1B at zeta = 1 mm and 1T at 0.5 mm, delta in [-1, 1] (§2.3.2), reduced
  models against the full-order nonlinear statics; candidates: r_c x modal derivatives (none / 10 constraint-mode
  pairs by MI 2b or at random / the 6 of 1B-1T-2B / those + 10 by MI 2b), and the full-order linear model; held out: both modes at
  1.5 times the amplitude.
- ``map-linear`` / ``map-gnl``: the interaction map's NFRC at node LE, 11 speeds in 1,200-1,600 rad/s x 8
  revolutions from rest, mu = 0, normal e_x (what ``make demo`` runs), GNL off / on; error: the largest of the NFRC
  error on the speeds robust to a 1e-4 force perturbation (relative to the reference's peak), the resonance speed's
  and the peak amplitude's relative errors; candidates: r_c, frequency cap, step, force evaluation (exact tensors,
  point cubature, float32); held out: 10 other speeds (a cubature as trained on the study's speeds).
- ``history-linear`` / ``history-gnl``: the LE time history of the same runs at the robust speed of largest response:
  max |u - u_ref| / max |u_ref| over the run.
- the stability map: the stable step 2 / omega_max of the tangent against the LE amplitude, with and without a cap.
- ``paper-speedup``: the GNL map model chosen at 5 % (else 20 %) against the paper's r = 189 exact tensors at 1e-7 s.
- ``disk-modes`` (bladed disk, not in ``all``): the 1B, 1T and 2B families of the 36-sector disk at every nodal
  diameter against the sector's full-order cyclic modes; candidates: r_c x r_cyclic (8 tip nodes per sector, as the
  contact maps), with and without modal derivatives; cost: the linear contact run per simulated ms at the maps'
  60 kHz cap; held out: the 4th-6th modes of every nodal diameter.
- ``disk-map-linear`` (bladed disk, not in ``all``): the disk's short map without GNL, 8 speeds in 1,200-1,650 rad/s
  x 20 revolutions from rest on the disk maps' casing (cone normal, mu = 0.15); error on the robust speeds: the NFRC
  of node LE of sector 0 and of the largest blade, and the speed and amplitude of the largest response; reference:
  r_c 10, r_MD 10, r_cyclic 288 at a 240 kHz cap; candidates: r_c, r_MD, r_cyclic, frequency cap (the reference's
  model at 120 kHz measures its cap's own error); held out: 7 other speeds. With it, ``disk-stress-linear``: the von
  Mises stress in the disk at t_max of one revolution carried on from each of its maps at the reference's largest
  robust response, off the root corner, in sector 0 and over the sectors.
- ``disk-map-gnl`` (bladed disk, not in ``all``): the same map with GNL over 12 revolutions; reference: r_c 10,
  r_MD 10, r_cyclic 288 with the exact sector tensors at a 120 kHz cap (the GNL step's probe sets the step); the
  1e-4 perturbation is the map's own option (the internal force scaled, the same probe and step); candidates:
  the maps' model (r_cyclic 144) at 60 kHz with exact tensors and with point cubature at 1e-2 / 3e-3 / 1e-3 in
  float32 (the full-disk GNL map's model is 3e-3), no modal derivatives, the reference's basis at 60 kHz; held out:
  the 7 other speeds, a cubature as trained on the study's speeds. With it, ``disk-stress-gnl``: the stress at t_max
  with GNL, as ``disk-stress-linear`` (a cubature candidate carried on with its map's own cubature).
- ``disk-forced-linear`` / ``disk-forced-gnl`` (bladed disk, not in ``all``): the forced response without contact
  (§3.3, ``bench_disk_forced.py``'s runs): 400 N along e_z at node LE of every sector travelling with N_d diameters,
  ramped over one period, 10 periods from rest, implicit Newmark at T/100 for the full order (one repeat of sectors
  closed on themselves) and the reduced models alike; error: the largest of the performance indicator's four relative
  errors (loaded node, tip nodes, M- and K-norm of the sector fields) over the cases; cost: the reduced runs' wall
  time. GNL off: N_d 0 and 9 at 4,000 and 13,000 rad/s, candidates r_c x r_cyclic and 10 modal derivatives in the
  basis (node LE kept, r_b = 3), held out: 17,000 rad/s. GNL on: the 400 N over a 3 mm patch (the point load
  collapses the full order), N_d 0 at 4,000 rad/s, candidates r_MD by MI 2b with eq. 61's force or the faces' 6
  shapes in it, the patch's static correction in every basis; held out: 13,000 rad/s.
- ``cost-r``: the cost per simulation-step against r for each force method (no GNL, exact tensors, point cubature on
  all points and on 10 points per mode, float64 / float32), synthetic models of each size, and the trained cubatures.

Writes ``rotor37_rom/data/speed_accuracy.json`` (versioned: ``choose_model`` reads it) and the charts
``docs/img/speed_accuracy_<scene>.png``; work files under ``results/speed_accuracy/``. Scenes not run keep their
previous entries. Every figure of docs/choosing-a-model.md comes from that file. The disk scenes record a floor
(``floor_record``: what the reference's own cap is worth, and for a stress how far the reference's
1e-4 perturbation moves it), which ``choose_model`` takes as every candidate's least expected error.
"""
from __future__ import annotations

import argparse
import dataclasses
import functools
import hashlib
import json
import math
import sys
import time
import types
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import load_demo  # noqa: E402
from rotor37_rom.machine import machine_description  # noqa: E402
from rotor37_rom.npz import save_json  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
WORK = ROOT / "results" / "speed_accuracy"
IMG = ROOT / "docs" / "img"
SCENES = ("modes", "clearance", "map-linear", "map-gnl", "stability", "paper-speedup", "cost-r")
DISK_SCENES = ("disk-modes", "disk-map-linear", "disk-map-gnl",        # not in 'all' (the single-blade study's hour)
               "disk-forced-linear", "disk-forced-gnl")
PAPER_R, PAPER_H = 189, 1e-7            # the paper's single-blade GNL setting: r = 189, exact tensors, h = 1e-7 s
TOLERANCES = (0.01, 0.05, 0.2)
PERTURBATION = 1e-4
ROBUST = 0.01            # a speed is robust when the 1e-4 perturbation moves its NFRC by <= 1 % of the peak
MAP = dict(preset="ci", speeds=(1200.0, 1600.0, 11), revolutions=8.0, mu=0.0, direction="x", quiet=True, batch=16)
HELD_OUT_SPEEDS = (1220.0, 1580.0, 10)
PREFIX = "computed since, on their own: "
FRESH: list[str] = []    # what this invocation computed rather than read from results/speed_accuracy (runs' note)
FORCED_RUNS: list = []   # the forced-response runs computed (None: a full-order reference; else a reduced run's s)


def _finite(x):
    return None if x is None or not np.isfinite(x) else float(x)


# ## Clamped modes: mesh presets against the Richardson limit

def scene_modes() -> dict:
    from rotor37_rom import fem
    from rotor37_rom.post.modes import classify_blade_modes

    fem.create_blade_sector(preset="ci")                     # warm-up: imports and form compilation off the clock
    rows = {}
    for preset in ("ci", "coarse", "paper"):
        t0 = time.perf_counter()
        sector = fem.create_blade_sector(preset=preset)
        modal = fem.compute_clamped_modes(sector, 6)
        wall = time.perf_counter() - t0
        labels = classify_blade_modes(modal.tip_displacements, sector.tip_nodes)
        rows[preset] = dict(omega=np.asarray(modal.omega[:6], float), wall=wall, labels=labels, dofs=sector.n_dofs)
        print(f"modes {preset}: {sector.n_dofs} DOF, {wall:.1f} s, {np.round(modal.omega[:6])} {labels}")
    # the presets are not nested refinements (gmsh remeshes): the frequencies need not converge monotonically, so
    # no Richardson limit; the reference is the finest preset, whose own error is estimated by its last change
    ref = rows["paper"]["omega"]
    cands = []
    for preset, row in rows.items():
        err = np.abs((rows["coarse"]["omega"] if preset == "paper" else row["omega"]) - ref) / ref
        cands.append(dict(name=preset, options={"preset": preset}, cost=row["wall"], error=float(err[:3].max()),
                          held_out_error=float(err[3:6].max()), errors={"1-3": err[:3].tolist(),
                                                                         "4-6": err[3:6].tolist()},
                          wall_s=row["wall"], dofs=int(row["dofs"]), labels=row["labels"]))
    return dict(description="clamped frequencies of modes 1-3 (1B, 1T, 2B), largest relative error against the paper "
                            "preset (its own error: its change from the coarse preset); held out: modes 4-6",
                cost_unit="s (mesh + assembly + 6 modes)", reference={"paper_rad_s": ref.tolist()},
                candidates=cands, held_out_case="modes 4-6 (same runs)")


# ## Clearance consumption: reduced bases against the full-order statics

CLEARANCE_BASES = [  # (name, r_c, global_md_modes, r_md, criterion)
    ("r_c 5, no MD", 5, 0, 0, "MI2b"), ("r_c 15, no MD", 15, 0, 0, "MI2b"),
    ("r_c 15, 10 MD MI2b", 15, 0, 10, "MI2b"), ("r_c 15, 10 MD random", 15, 0, 10, "random"),
    ("r_c 5, 6 MD", 5, 3, 0, "MI2b"), ("r_c 15, 6 MD", 15, 3, 0, "MI2b"), ("r_c 25, 6 MD", 25, 3, 0, "MI2b"),
    ("r_c 15, 6 MD + 10 MI2b", 15, 3, 10, "MI2b"),
]


def scene_clearance() -> dict:
    from rotor37_rom import fem
    from rotor37_rom.reduction.builder import ReductionConfig, build_reduced_model, clearance_consumption_study
    from rotor37_rom.post.clearance import relative_error

    sector = fem.create_blade_sector(preset="ci")
    ops = fem.create_svk_operators(sector)
    roms, offline = {}, {}
    for name, r_c, n_global, r_md, criterion in CLEARANCE_BASES:
        t0 = time.perf_counter()
        roms[name], _ = build_reduced_model(sector, ReductionConfig(r_c=r_c, r_md=r_md, global_md_modes=n_global,
                                                                    criterion=criterion, forces="intrusive"), ops=ops)
        offline[name] = time.perf_counter() - t0
        print(f"clearance: {name}: r = {roms[name].r}, built in {offline[name]:.1f} s")
    cases = {"study": (("1B", 1e-3), ("1T", 0.5e-3)), "held_out": (("1B", 1.5e-3), ("1T", 0.75e-3))}
    studies = {key: [clearance_consumption_study(sector, mode, zeta, n_levels=10, ops=ops, roms=roms)
                     for mode, zeta in pairs] for key, pairs in cases.items()}
    cands = []
    for name in ["FOM linear"] + list(roms):
        errs = {}
        for key, curves in studies.items():
            errs[key] = [float(np.nanmax(relative_error(c.curves[name], c.curves["FOM nonlinear"])))
                         if np.isfinite(c.curves[name]).all() else math.inf for c in curves]
        if name == "FOM linear":
            options, cost, r = {"model": "full-order linear"}, 0.0, None
        else:
            _, r_c, n_global, r_md, criterion = next(b for b in CLEARANCE_BASES if b[0] == name)
            options = {"r_c": r_c, "global_md": n_global, "r_md": r_md, "criterion": criterion}
            r = roms[name].r
            cost = offline[name] + sum(c.costs[name] for c in studies["study"])
        cands.append(dict(name=name, options=options, cost=cost, error=max(errs["study"]),
                          held_out_error=max(errs["held_out"]), errors=errs, r=r,
                          online_s=sum(c.costs.get(name, 0.0) for c in studies["study"]),
                          offline_s=offline.get(name, 0.0)))
    return dict(description="clearance consumption at node LE of 1B at zeta = 1 mm and 1T at zeta = 0.5 mm (the "
                            "paper's cases), delta in [-1, 1]: largest relative error against the full-order "
                            "nonlinear curves (ci mesh)",
                cost_unit="s (offline build + the 2 x 20 static solves)",
                reference={"FOM nonlinear wall_s": sum(c.costs["FOM nonlinear"] for c in studies["study"])},
                candidates=cands, held_out_case="the same modes at 1.5 times the amplitude (1B 1.5 mm, 1T 0.75 mm)")


# ## Bladed disk: the disk model's frequencies at every nodal diameter against the cyclic full order

DISK_MODELS = [  # (name, r_c, r_md, r_cyclic): every sector's 8 tip nodes (the contact maps' boundary)
    ("r_c 2, r_cyclic 72", 2, 0, 72), ("r_c 2, r_cyclic 144", 2, 0, 144),
    ("r_c 5, r_cyclic 72", 5, 0, 72), ("r_c 5, r_cyclic 144", 5, 0, 144),
    ("r_c 10, r_cyclic 72", 10, 0, 72), ("r_c 10, r_cyclic 144", 10, 0, 144), ("r_c 10, r_cyclic 288", 10, 0, 288),
    ("r_c 10, 10 MD, r_cyclic 144 (the maps' model)", 10, 10, 144),
]
DISK_CAP_KHZ, DISK_TIMED_STEPS = 60.0, 2000


def scene_disk_modes() -> dict:
    """The 36-sector disk (ci sector): the 1B, 1T and 2B families at every nodal diameter k = 0 ... 18 of disk models
    (r_c, r_cyclic, modal derivatives) against the sector's full-order cyclic modes; held out: the 4th-6th modes of
    every k. Cost: the linear contact run's time per simulated millisecond at the disk maps' 60 kHz cap."""
    from rotor37_rom import fem
    from rotor37_rom.post.stress import cyclic_harmonic_frequencies
    from rotor37_rom.reduction.builder import mesh_signature
    from rotor37_rom.dynamics.casing import Casing
    from rotor37_rom.disk.harmonics import harmonic_frequencies
    from rotor37_rom.disk.builder import DiskReductionConfig, build_disk_model
    from rotor37_rom.dynamics.explicit import CentralDifference, simulate
    from rotor37_rom.npz import load_npz, save_npz

    sector = fem.create_disk_sector(preset="ci")
    ops = fem.create_svk_operators(sector)
    ref_file = WORK / f"disk_modes_reference_{mesh_signature(sector)[:16]}.npz"
    cached = load_npz(ref_file, ("omega", "wall"), what="cyclic reference")
    if cached is None:
        t0 = time.perf_counter()
        omega = cyclic_harmonic_frequencies(sector, 6, ops=ops)
        save_npz(ref_file, omega=omega, wall=time.perf_counter() - t0)
        FRESH.append(f"disk-modes reference {time.perf_counter() - t0:.0f} s")
        cached = load_npz(ref_file, ("omega", "wall"))
    ref, ref_wall = cached["omega"], float(cached["wall"])
    print(f"disk-modes: cyclic reference, 6 families x {ref.shape[0]} harmonics ({ref_wall:.0f} s)")
    cap = 2 * np.pi * DISK_CAP_KHZ * 1e3
    speeds = np.linspace(1200.0, 1650.0, 8)
    casing = Casing(mu=0.15, direction="cone")                 # the disk maps' casing (paper's c0, h_b)
    cands = []
    for name, r_c, r_md, r_cyclic in DISK_MODELS:
        t0 = time.perf_counter()
        model, built = build_disk_model(sector, DiskReductionConfig(tip_nodes="all", r_c=r_c, r_md=r_md,
                                                                    criterion="MI2b", r_cyclic=r_cyclic,
                                                                    forces="none"),
                                        ops=ops, cache_dir=WORK / "disk_models")
        build = None if built.get("cached") else time.perf_counter() - t0     # a cache read is not a build time
        rom = harmonic_frequencies(model, 6)
        err = np.abs(rom / ref - 1.0)
        below = float(np.nanmax((ref - rom) / ref))          # Rayleigh-Ritz: every value >= the full order's
        scheme = CentralDifference(model, nonlinear=False, frequency_cap=cap)
        simulate(scheme, speeds[:1], casing, n_steps=50, on_blowup="flag")                # warm-up
        t0 = time.perf_counter()
        simulate(scheme, speeds, casing, n_steps=DISK_TIMED_STEPS, record_every=50, on_blowup="flag")
        per_step = (time.perf_counter() - t0) / (DISK_TIMED_STEPS * speeds.size)
        cost = 1e6 * per_step / (scheme.h * 1e3)               # us per simulated ms of one speed
        study, held = float(np.nanmax(err[:, :3])), float(np.nanmax(err[:, 3:6]))
        cands.append(dict(name=name, options={"r_c": r_c, "r_md": r_md, "r_cyclic": r_cyclic, "tip_nodes": "all"},
                          cost=cost, error=study if np.isfinite(err[:, :3]).all() else math.inf,
                          held_out_error=held if np.isfinite(err[:, 3:6]).all() else math.inf, r=model.r,
                          build_s=build, us_per_sim_step=1e6 * per_step, h=scheme.h,
                          worst_k=int(np.nanargmax(err[:, :3].max(axis=1))), rayleigh_ritz_margin=below,
                          errors={"families 1-3 by k": err[:, :3].max(axis=1).tolist(),
                                  "families 4-6 by k": err[:, 3:6].max(axis=1).tolist()}))
        made = "read from the cache" if build is None else f"built in {build:.0f} s"
        print(f"disk-modes: {name}: r = {model.r}, {made}, 1B/1T/2B within {100 * study:.3f} %, "
              f"modes 4-6 within {100 * held:.3f} %, {1e6 * per_step:.1f} us/sim-step at h = {scheme.h:.3g} s")
    return dict(description="the bladed disk's (36 ci sectors, 8 tip nodes each) 1B, 1T and 2B families at every "
                            "nodal diameter k = 0 ... 18: largest relative frequency error against the sector's "
                            "full-order cyclic modes",
                cost_unit=f"us per simulated ms of one speed (linear contact run from rest, the maps' casing: cone "
                          f"normal, mu = 0.15; {DISK_CAP_KHZ:g} kHz cap, {speeds.size} speeds batched)",
                reference={"cyclic_rad_s": ref.tolist(), "wall_s": ref_wall,
                           "options": {"model": "full-order cyclic sector", "preset": "ci"}},
                candidates=cands, held_out_case="the 4th-6th modes of every nodal diameter (same models)",
                machine=machine_description())


# ## Interaction maps: schemes and force evaluations against a reference map

@dataclasses.dataclass
class MapRun:
    nfrc: np.ndarray
    speeds: np.ndarray
    diverged: np.ndarray
    records: list
    wall: float
    sweep_wall: float
    sim_steps: float
    h: float
    config: object = None         # the map's ContactMapConfig
    record_h: list = dataclasses.field(default_factory=list)     # the step each record ran at (retries: smaller)


@functools.lru_cache(maxsize=None)
def model_file(r_c: int) -> Path:
    """The ci blade's r_c model (24 tip DOFs + r_c modes + the 6 MDs of 1B/1T/2B), exact tensors, built once (checked
    once per process against the builder's cache)."""
    from rotor37_rom.model.reduced import load_reduced_model, save_reduced_model

    path = WORK / "models" / f"rom_rc{r_c}.npz"
    cm = load_demo("contact_map")
    # built through the builder's cache (keyed by the reduction's parameters): a file saved by an earlier builder is
    # replaced, and run_map then sees its maps ran another model
    model = cm.build_model(cm.ContactMapConfig(**{**MAP, "r_c": r_c, "out": WORK / "models"}))
    if not path.is_file() or load_reduced_model(path).key != model.key:
        save_reduced_model(model, path)
    return path


RETRIES = ", retries"


MODEL_OPTIONS = ("r_c", "r_md", "r_cyclic")     # a candidate's options that make its model, not its scheme


def run_map(name: str, gnl: bool, options: dict, speeds=MAP["speeds"], model_path: Path | None = None,
            setup: dict = MAP, prefix: str = "") -> MapRun:
    """One map of the scene (run_contact_map of demos/contact_map.py with ``setup``, MAP or DISK_MAP), cached in
    results/speed_accuracy/<prefix><name>. The model is ``model_path`` (default: the blade's of ``options['r_c']``).
    A candidate '<base>, retries' is its base candidate's map with the speeds that blew up run again at a smaller
    step: it runs in the base's folder (the base's sweep is reused, only the retries run), and its cost is the base
    map's plus the retries'."""
    from rotor37_rom.model.reduced import saved_model_key
    from rotor37_rom.studies.sweep import load_sweep

    cm = load_demo("contact_map")
    opts = {k: v for k, v in options.items() if k not in MODEL_OPTIONS}
    model_path = model_path or model_file(options.get("r_c", 15))
    base = None
    if opts.get("retry_diverged"):
        if not name.endswith(RETRIES):
            raise ValueError(f"a candidate with retry_diverged is named '<base>{RETRIES}', got {name!r}")
        base = run_map(name.removesuffix(RETRIES), gnl, {k: v for k, v in options.items() if k != "retry_diverged"},
                       speeds, model_path, setup, prefix)
        name = name.removesuffix(RETRIES)
    tag = f"{prefix}{'gnl' if gnl else 'linear'}_{name}_{int(speeds[0])}_{int(speeds[1])}_{int(speeds[2])}"
    tag = tag.replace(" ", "_")
    out = WORK / tag
    done = out / ("study_run.json" if base is None else f"study_run_retries{opts['retry_diverged']}.json")
    config = cm.ContactMapConfig(**{**setup, "speeds": speeds, "model": model_path, "gnl": "on" if gnl else "off",
                                    "out": out, **opts})
    setting = json.dumps([str(model_path), opts] + ([] if setup is MAP else [setup]), sort_keys=True, default=str)
    key = saved_model_key(model_path)
    info = json.loads(done.read_text()) if done.is_file() else {}
    # stale: another setting, or the model file rewritten since (another builder). The map records the key of the
    # file it was given: its sweep's spec holds the key of the model the map derived from it (a cubature, a
    # perturbation)
    if info.get("setting") != setting or info.get("model_file_key") != key:
        shared = WORK / "cubature_cache"          # one cubature training per model and casing, shared by candidates
        shared.mkdir(parents=True, exist_ok=True)
        out.mkdir(parents=True, exist_ok=True)
        if not (out / "cache").exists():
            (out / "cache").symlink_to(shared, target_is_directory=True)
        t0 = time.perf_counter()
        result = cm.run_contact_map(config)
        wall = time.perf_counter() - t0
        FRESH.append(f"{tag}{RETRIES if base else ''} {wall:.0f} s")
        run = next(iter(result.runs.values()))
        sweep_wall = run.wall_s if base is None else base.sweep_wall + run.wall_s
        wall = wall if base is None else base.wall + wall
        info = {"wall": wall, "sweep_wall": sweep_wall, "h": run.h, "folder": str(run.folder), "setting": setting,
                "model_file_key": key}
        save_json(done, info)
    grid = config.speed_grid
    # each speed's record: the map's, or the bounded one of its retries at a smaller step (their own sweep folders)
    records = {}
    specs = {p: json.loads((p / "spec.json").read_text()) for p in (out / "sweeps").iterdir()
             if (p / "spec.json").is_file()}
    main = specs[Path(info["folder"])]
    retries = [] if base is None else sorted(      # the base's retries: its model, a smaller step
        p for p, spec in specs.items() if spec["model"] == main["model"] and spec["h"] < main["h"])
    for folder in [Path(info["folder"])] + retries:
        h = specs[folder]["h"]
        for r in load_sweep(folder):
            w = float(r["omega"])
            if np.isclose(w, grid).any() and (w not in records or (int(records[w][0]["diverged_step"]) >= 0
                                                                    and int(r["diverged_step"]) < 0)):
                records[w] = (r, h)
    record_h = [records[w][1] for w in sorted(records)]
    records = [records[w][0] for w in sorted(records)]
    from rotor37_rom.studies.sweep import interaction_map

    imap = interaction_map(records, config.node)
    steps = sum(config.revolutions * 2 * np.pi / float(r["omega"]) / h for r, h in zip(records, record_h))
    print(f"map {tag}: h = {info['h']:.3g} s, sweep {info['sweep_wall']:.1f} s "
          f"({1e6 * info['sweep_wall'] / steps:.1f} us/sim-step), diverged {int(imap.diverged.sum())}")
    return MapRun(imap.nfrc, imap.speeds, imap.diverged, records, info["wall"], info["sweep_wall"], steps, info["h"],
                  config, record_h)


def map_errors(run: MapRun, ref: MapRun, robust: np.ndarray) -> dict:
    """NFRC error on the robust speeds (relative to the reference's peak there), resonance speed and peak errors,
    and the LE history error at the robust speed of largest reference response."""
    from rotor37_rom.studies.sweep import record_row

    if run.diverged.any():
        return dict(nfrc=math.inf, speed=math.inf, peak=math.inf, map=math.inf, history=math.inf)
    peak_ref = np.nanmax(ref.nfrc[robust])
    nfrc = float(np.abs(run.nfrc[robust] - ref.nfrc[robust]).max() / peak_ref)
    i_ref, i = int(np.nanargmax(ref.nfrc)), int(np.nanargmax(run.nfrc))
    speed = abs(run.speeds[i] - ref.speeds[i_ref]) / ref.speeds[i_ref]
    peak = abs(run.nfrc[i] - ref.nfrc[i_ref]) / ref.nfrc[i_ref]
    k = int(np.flatnonzero(robust)[np.argmax(ref.nfrc[robust])])
    rec, rec_ref = run.records[k], ref.records[k]
    u_ref = np.asarray(rec_ref["u_r"])[record_row(rec_ref)]
    u = np.interp(rec_ref["t"], rec["t"], np.asarray(rec["u_r"])[record_row(rec)])
    history = float(np.abs(u - u_ref).max() / np.abs(u_ref).max())
    return dict(nfrc=nfrc, speed=float(speed), peak=float(peak), map=max(nfrc, speed, peak), history=history,
                history_speed=float(ref.speeds[k]))


LINEAR_CANDIDATES = [  # (name, options); the reference is r_c 40, no cap, h = 0.5 h_crit
    ("r_c 15", {"r_c": 15}), ("r_c 25", {"r_c": 25}),
    ("r_c 15, h 0.9 h_crit", {"r_c": 15, "safety": 0.9}),
    ("r_c 15, cap 120 kHz", {"r_c": 15, "frequency_cap": 120.0}),
    ("r_c 15, cap 60 kHz", {"r_c": 15, "frequency_cap": 60.0}),
    ("r_c 15, cap 30 kHz", {"r_c": 15, "frequency_cap": 30.0}),
    ("r_c 25, cap 60 kHz", {"r_c": 25, "frequency_cap": 60.0}),
    ("r_c 25, cap 30 kHz", {"r_c": 25, "frequency_cap": 30.0}),
    ("r_c 5, cap 60 kHz", {"r_c": 5, "frequency_cap": 60.0}),
    ("r_c 40, cap 120 kHz", {"r_c": 40, "frequency_cap": 120.0}),
    ("r_c 40, cap 60 kHz", {"r_c": 40, "frequency_cap": 60.0}),
]
GNL_CANDIDATES = [  # the reference is r_c 15 (r = 45) with exact tensors, no cap, h = 0.5 h_crit
    ("r_c 10", {"r_c": 10}),
    ("cap 120 kHz", {"r_c": 15, "frequency_cap": 120.0}),
    ("cap 60 kHz", {"r_c": 15, "frequency_cap": 60.0}),
    ("cubature 1e-4, cap 120 kHz", {"r_c": 15, "frequency_cap": 120.0, "cubature": 1e-4}),
    ("cubature 1e-4 float32, cap 120 kHz", {"r_c": 15, "frequency_cap": 120.0, "cubature": 1e-4,
                                            "precision": "single"}),
    ("cubature 1e-4, cap 120 kHz, retries", {"r_c": 15, "frequency_cap": 120.0, "cubature": 1e-4,
                                             "retry_diverged": 2}),
    ("r_c 10, retries", {"r_c": 10, "retry_diverged": 2}),
    ("cubature 1e-4", {"r_c": 15, "cubature": 1e-4}),
    ("cubature 1e-4 float32", {"r_c": 15, "cubature": 1e-4, "precision": "single"}),
    ("cubature 1e-5 float32", {"r_c": 15, "cubature": 1e-5, "precision": "single"}),
    ("cubature 1e-5", {"r_c": 15, "cubature": 1e-5}),
    ("cubature 1e-6 float32", {"r_c": 15, "cubature": 1e-6, "precision": "single"}),
]


def scene_map(gnl: bool) -> tuple[dict, dict]:
    ref_options = {"r_c": 15} if gnl else {"r_c": 40}
    ref = run_map("reference", gnl, ref_options)
    pert_path = WORK / "models" / f"rom_rc{ref_options['r_c']}_perturbed_{'gnl' if gnl else 'linear'}.npz"
    from rotor37_rom.model.reduced import load_reduced_model, perturbed_model, save_reduced_model

    perturbed = perturbed_model(load_reduced_model(model_file(ref_options["r_c"])), PERTURBATION)
    if not pert_path.is_file() or load_reduced_model(pert_path).key != perturbed.key:
        save_reduced_model(perturbed, pert_path)
    pert = run_map("reference_perturbed", gnl, ref_options, model_path=pert_path)
    peak = np.nanmax(ref.nfrc)
    robust = np.abs(pert.nfrc - ref.nfrc) <= ROBUST * peak
    print(f"robust speeds: {ref.speeds[robust].tolist()}")
    cands, hist = [], []
    for name, options in (GNL_CANDIDATES if gnl else LINEAR_CANDIDATES):
        run = run_map(name, gnl, options)
        err = map_errors(run, ref, robust)
        base = dict(name=name, options=options, us_per_step=1e6 * run.sweep_wall / run.sim_steps, h=run.h,
                    wall_s=run.wall, sweep_s=run.sweep_wall, diverged=int(run.diverged.sum()))
        cost = run.sweep_wall
        cands.append(dict(base, cost=cost, error=err["map"], errors={k: err[k] for k in ("nfrc", "speed", "peak")},
                          held_out_error=None))
        hist.append(dict(base, cost=cost, error=err["history"], held_out_error=None,
                         history_speed=err.get("history_speed")))
    ref_info = dict(options=ref_options, h=ref.h, sweep_s=ref.sweep_wall, wall_s=ref.wall,
                    us_per_step=1e6 * ref.sweep_wall / ref.sim_steps,
                    peak_speed=float(ref.speeds[np.nanargmax(ref.nfrc)]),
                    peak_m=float(peak), robust_speeds=ref.speeds[robust].tolist(), perturbation=PERTURBATION,
                    robust_threshold=ROBUST)
    kind = "GNL" if gnl else "GNL off"
    setting = "11 speeds in 1,200-1,600 rad/s x 8 revolutions, mu = 0, e_x, ci blade"
    maps = dict(description=f"interaction map, {kind}, {setting}: largest of the NFRC error on the robust speeds, the "
                            f"resonance speed's and the peak's relative errors",
                cost_unit="s (sweep wall time of the map)", reference=ref_info, candidates=cands,
                held_out_case=f"10 other speeds in {HELD_OUT_SPEEDS[0]:g}-{HELD_OUT_SPEEDS[1]:g} rad/s")
    history = dict(description=f"LE time history, {kind}, {setting}: max |u - u_ref| / max |u_ref| at the robust speed "
                               f"of largest reference response",
                   cost_unit="s (sweep wall time of the map)", reference=ref_info, candidates=hist,
                   held_out_case=None)
    return maps, history


def held_out_options(options: dict, setup: dict = MAP) -> dict:
    """A candidate's options on the held-out speeds: a cubature stays the one trained on the study's speeds of the
    scene's ``setup`` (the model chosen is run, not one retrained on runs at the held-out speeds)."""
    if options.get("cubature") is None:
        return options
    return {**options, "cubature_speeds": study_training_speeds(setup)}


def study_training_speeds(setup: dict = MAP) -> tuple[float, ...]:
    """The speeds a cubature of a map scene is trained at (those of the study's that contact_map picks)."""
    from rotor37_rom.dynamics.explicit import training_speeds

    return tuple(training_speeds(load_demo("contact_map").ContactMapConfig(**setup).speed_grid).tolist())


def held_out_map(scene: dict, gnl: bool, tolerances=TOLERANCES) -> None:
    """Run the models chosen at each tolerance on the held-out speeds; a miss is recorded on the candidate, and the
    chooser then passes it over for the next cheapest (the loop goes on until a choice holds on the held-out case)."""
    ref_options = scene["reference"]["options"]
    ref = run_map("reference", gnl, ref_options, speeds=HELD_OUT_SPEEDS)
    pert_path = WORK / "models" / f"rom_rc{ref_options['r_c']}_perturbed_{'gnl' if gnl else 'linear'}.npz"
    pert = run_map("reference_perturbed", gnl, ref_options, speeds=HELD_OUT_SPEEDS, model_path=pert_path)
    robust = np.abs(pert.nfrc - ref.nfrc) <= ROBUST * np.nanmax(ref.nfrc)
    held_out_choices(scene, tolerances, lambda name, options: map_errors(
        run_map(name, gnl, held_out_options(options), speeds=HELD_OUT_SPEEDS), ref, robust)["map"])
    scene["held_out_reference"] = dict(robust_speeds=ref.speeds[robust].tolist(), sweep_s=ref.sweep_wall)


def held_out_choices(scene: dict, tolerances, error_of) -> None:
    """For each tolerance, the chosen model's error on the held-out case (``error_of(name, options)``), recorded on
    its candidate; a miss passes the choice to the next cheapest, which is run in turn, until one holds."""
    from rotor37_rom.studies.model_choice import choose_model

    study = {"schema": 1, "scenes": {"s": scene}}
    by_name = {c["name"]: c for c in scene["candidates"]}
    for tol in tolerances:
        for _ in range(len(by_name)):
            try:
                choice = choose_model("s", tol, study)
            except ValueError:
                break
            cand = by_name[choice.name]
            if cand["held_out_error"] is not None:
                break
            cand["held_out_error"] = error_of(choice.name, cand["options"])
            print(f"held out at {tol:g}: {choice.name}: {cand['held_out_error']:.3g}")
            if cand["held_out_error"] <= tol:
                break


# ## The bladed disk's interaction map without GNL: basis, interface modes and frequency cap

DISK_MAP = dict(preset="ci", speeds=(1200.0, 1650.0, 8), revolutions=20.0, mu=0.15, direction="cone", quiet=True,
                batch=8)                     # the disk maps' casing (cone normal, the paper's mu) and short map
DISK_HELD_OUT_SPEEDS = (1230.0, 1620.0, 7)      # between the study's speeds (every 64.3 rad/s)
DISK_MAP_REFERENCE = {"r_c": 10, "r_md": 10, "r_cyclic": 288, "frequency_cap": 240.0}
DISK_GNL_MAP = {**DISK_MAP, "revolutions": 12.0}     # GNL: the sectors' forces batched, 12 revolutions
DISK_GNL_REFERENCE = {"r_c": 10, "r_md": 10, "r_cyclic": 288, "frequency_cap": 120.0}     # exact sector tensors
_MAPS_MODEL = {"r_c": 10, "r_md": 10, "r_cyclic": 144, "frequency_cap": 60.0}   # the disk contact maps' model
DISK_MAP_CANDIDATES = [  # every sector's 8 tip nodes; r_md by MI 2b
    ("the maps' model, cap 30 kHz", {**_MAPS_MODEL, "frequency_cap": 30.0}),
    ("the maps' model, cap 60 kHz", _MAPS_MODEL),
    ("the maps' model, cap 120 kHz", {**_MAPS_MODEL, "frequency_cap": 120.0}),
    ("r_c 10, r_cyclic 144, cap 60 kHz", {**_MAPS_MODEL, "r_md": 0}),
    ("r_c 10, r_cyclic 72, cap 60 kHz", {**_MAPS_MODEL, "r_md": 0, "r_cyclic": 72}),
    ("r_c 10, r_cyclic 72, cap 30 kHz", {**_MAPS_MODEL, "r_md": 0, "r_cyclic": 72, "frequency_cap": 30.0}),
    ("r_c 5, r_cyclic 72, cap 60 kHz", {**_MAPS_MODEL, "r_c": 5, "r_md": 0, "r_cyclic": 72}),
    ("r_c 2, r_cyclic 144, cap 60 kHz", {**_MAPS_MODEL, "r_c": 2, "r_md": 0}),
    ("the reference's model, cap 120 kHz", {**DISK_MAP_REFERENCE, "frequency_cap": 120.0}),   # its cap's own error
]
DISK_GNL_CANDIDATES = [  # with GNL: exact sector tensors unless a cubature (trained, capped, at the study's speeds)
    ("the maps' model, exact, cap 60 kHz", _MAPS_MODEL),
    ("the maps' model, cubature 1e-2 float32, cap 60 kHz", {**_MAPS_MODEL, "cubature": 1e-2, "precision": "single"}),
    ("the maps' model, cubature 3e-3 float32, cap 60 kHz", {**_MAPS_MODEL, "cubature": 3e-3, "precision": "single"}),
    ("the maps' model, cubature 1e-3 float32, cap 60 kHz", {**_MAPS_MODEL, "cubature": 1e-3, "precision": "single"}),
    ("r_c 10, r_cyclic 144, exact, cap 60 kHz", {**_MAPS_MODEL, "r_md": 0}),
    ("the reference's model, exact, cap 60 kHz", {**DISK_GNL_REFERENCE, "frequency_cap": 60.0}),
]


@functools.lru_cache(maxsize=None)
def _disk_sector():
    from rotor37_rom import fem

    sector = fem.create_disk_sector(preset="ci")
    return sector, fem.create_svk_operators(sector)


def disk_model_file(options: dict, perturbation: float = 0.0, gnl: bool = False) -> Path:
    """The disk model of ``options`` (r_c, r_md by MI 2b, r_cyclic; every sector's 8 tip nodes; with ``gnl`` the
    sector's exact GNL tensors, else no GNL forces), built once (the Craig-Bampton parts cached with scene
    disk-modes') and saved for the map command's --model; with a ``perturbation`` (GNL off), that model's stiffness
    scaled by 1 + perturbation. Checked once per process."""
    if gnl and perturbation:
        raise ValueError("a GNL disk map is perturbed by the map's own option 'perturbation' (the same probe and "
                         "step), not by a perturbed model file")
    return _disk_model_file(options["r_c"], options["r_md"], options["r_cyclic"], float(perturbation), bool(gnl))


@functools.lru_cache(maxsize=None)
def _disk_model_file(r_c: int, r_md: int, r_cyclic: int, perturbation: float, gnl: bool) -> Path:
    from rotor37_rom.reduction.builder import mesh_signature
    from rotor37_rom.disk.builder import DiskReductionConfig, build_disk_model
    from rotor37_rom.model.reduced import load_reduced_model, perturbed_model, save_reduced_model

    sector, ops = _disk_sector()
    stem = f"disk_{mesh_signature(sector)[:12]}_rc{r_c}_md{r_md}_cyc{r_cyclic}" + ("_gnl" if gnl else "")
    # the builder's cache (keyed by every parameter of the reduction) decides: a file saved by an earlier builder is
    # replaced, and so is a perturbed copy of another model (run_map then sees the key change and runs its maps again)
    model, _ = build_disk_model(sector, DiskReductionConfig(tip_nodes="all", r_c=r_c, r_md=r_md, criterion="MI2b",
                                                            r_cyclic=r_cyclic,
                                                            forces="intrusive" if gnl else "none"),
                                ops=ops, cache_dir=WORK / "disk_models")
    if perturbation != 0.0:
        model = perturbed_model(model, perturbation)
        stem += f"_perturbed_{perturbation:g}"
    path = WORK / "models" / f"{stem}.npz"
    if not path.is_file() or load_reduced_model(path).key != model.key:
        save_reduced_model(model, path)
    return path


def run_disk_map(name: str, options: dict, speeds=None, perturbation: float = 0.0, gnl: bool = False) -> MapRun:
    """A map of the disk scenes: DISK_MAP (GNL off) or DISK_GNL_MAP at ``speeds`` (default: the scene's)."""
    setup = DISK_GNL_MAP if gnl else DISK_MAP
    return run_map(name, gnl, options, speeds or setup["speeds"], disk_model_file(options, perturbation, gnl),
                   setup, "disk_")


def largest_over_blades(run: MapRun) -> np.ndarray:
    """Per speed, the largest over the 36 blades of node LE's max |u| over the last revolution."""
    from rotor37_rom.studies.sweep import sector_maxima

    return np.array([np.nanmax(sector_maxima(r)) if int(r["diverged_step"]) < 0 else np.nan for r in run.records])


def disk_robust(ref: MapRun, pert: MapRun) -> np.ndarray:
    """The speeds where the reference's 1e-4 perturbation moves node LE of sector 0 and the largest blade by at most
    1 % of their peaks over all speeds (as the blade's scenes; the errors are then relative to the peaks over the
    robust speeds, so the threshold is a little looser than 1 % of those)."""
    big, big_p = largest_over_blades(ref), largest_over_blades(pert)
    return ((np.abs(pert.nfrc - ref.nfrc) <= ROBUST * np.nanmax(ref.nfrc))
            & (np.abs(big_p - big) <= ROBUST * np.nanmax(big)))


def disk_map_errors(run: MapRun, ref: MapRun, robust: np.ndarray) -> dict:
    """On the robust speeds only: the NFRC errors of node LE of sector 0 and of the largest blade (relative to the
    reference's peak there), and the resonance speed's and peak's relative errors at node LE of sector 0 (the largest
    response over the robust speeds: on the disk's short map the reference's largest response overall sits in a band
    where the contact selects the response, and the 1e-4 perturbation moves it by 11 %, docs/choosing-a-model.md);
    ``map`` is the largest of the four."""
    if not robust.any():
        raise RuntimeError("no speed of the disk map is robust to the reference's 1e-4 perturbation: the map cannot "
                           "judge a model (more revolutions or other speeds)")
    if run.diverged.any():
        return dict(nfrc=math.inf, largest=math.inf, speed=math.inf, peak=math.inf, map=math.inf)
    sub = np.flatnonzero(robust)
    big, big_ref = largest_over_blades(run), largest_over_blades(ref)
    i_ref, i = sub[np.nanargmax(ref.nfrc[sub])], sub[np.nanargmax(run.nfrc[sub])]
    err = dict(nfrc=float(np.abs(run.nfrc[sub] - ref.nfrc[sub]).max() / ref.nfrc[i_ref]),
               largest=float(np.abs(big[sub] - big_ref[sub]).max() / np.nanmax(big_ref[sub])),
               speed=float(abs(run.speeds[i] - ref.speeds[i_ref]) / ref.speeds[i_ref]),
               peak=float(abs(run.nfrc[i] - ref.nfrc[i_ref]) / ref.nfrc[i_ref]))
    err["map"] = max(err.values())
    return err


def disk_stress_at_tmax(run: MapRun, model_path: Path, speed: float, gnl: bool = False) -> dict:
    """The disk's von Mises stress at t_max (largest |u| of node LE of sector 0) of one revolution carried on from
    ``run``'s final state at ``speed`` (what ``contact_map.py --stress`` does at the map's largest response), every
    sector rebuilt from q: the largest off the root corner and outside the tip band in sector 0 and over the sectors
    (``analysis.disk_stress_summary``: the numbers that converge with the mesh), with the wall time."""
    from rotor37_rom.model.reduced import load_reduced_model

    cm = load_demo("contact_map")
    sector, _ = _disk_sector()
    model = load_reduced_model(model_path)
    k = int(np.argmin(np.abs(run.speeds - speed)))
    if not np.isclose(run.speeds[k], speed):
        raise ValueError(f"the map has no run at {speed} rad/s (its speeds: {run.speeds.tolist()})")
    gone = dict(vm=math.inf, vm_all=math.inf, sector_of_max=None, u_le=math.nan)
    if int(run.records[k]["diverged_step"]) >= 0:          # nothing to carry on
        return dict(gone, seconds=0.0)
    scheme = cm.time_scheme(run.config, model, gnl, None, h=run.record_h[k])      # the map's forces (its cubature)
    t0 = time.perf_counter()
    res, _ = cm.carry_on_record(run.config, scheme, run.records[k], float(run.records[k]["omega"]),
                                [model.nodes.label_row(run.config.node)])
    if res.diverged_step[0] >= 0:
        return dict(gone, seconds=time.perf_counter() - t0)
    *_, numbers, _ = cm.disk_stress_of(sector, model, res, gnl, 0)
    return dict(vm=numbers["vm_max_off_root"], vm_all=numbers["vm_max_off_root_all_sectors"],
                sector_of_max=numbers["sector_of_max_off_root"], u_le=numbers["u_le"],
                seconds=time.perf_counter() - t0)


def cap_floor(ref_opts: dict, cands: list[dict]) -> dict | None:
    """What the reference's own frequency cap is worth: the error of the candidate that is the reference's model at
    the nearest lower cap (None if no such candidate, or if it lost a speed). Models that differ from the reference
    by less cannot be told apart by the scene: its floor (``model_choice.scene_floor``)."""
    def model(options: dict) -> dict:
        return {k: v for k, v in options.items() if k != "frequency_cap"}

    lower = [c for c in cands if model(c["options"]) == model(ref_opts)
             and c["options"].get("frequency_cap", math.inf) < ref_opts.get("frequency_cap", math.inf)]
    if not lower:
        return None
    c = max(lower, key=lambda c: c["options"]["frequency_cap"])
    if not np.isfinite(c["error"]):
        return None
    return dict(error=c["error"], candidate=c["name"], cap_khz=c["options"]["frequency_cap"])


def scene_disk_stress(maps: dict, runs: dict, gnl: bool = False) -> dict:
    """von Mises at t_max in the disk, GNL off or on, at the reference's largest robust response of the disk map
    scene, for its reference and candidates (``runs``: the map scene's MapRuns by name, the stress needs a map's final
    state); error: the larger of the relative errors in sector 0 and over the sectors, off the root corner."""
    scene = "disk-stress-gnl" if gnl else "disk-stress-linear"
    ref_opts, speed = maps["reference"]["options"], maps["reference"]["robust_peak_speed"]
    ref = disk_stress_at_tmax(runs["reference"], disk_model_file(ref_opts, gnl=gnl), speed, gnl)
    if not np.isfinite(ref["vm"]):
        raise RuntimeError(f"{scene}: the reference's run at {speed:g} rad/s diverged")
    # the perturbed reference's map carried on alike (GNL: the map's own perturbation option; off: its model file)
    pert = disk_stress_at_tmax(runs["reference_perturbed"], disk_model_file(ref_opts, 0.0 if gnl else PERTURBATION,
                                                                            gnl=gnl), speed, gnl)
    moved = max(abs(pert["vm"] - ref["vm"]) / ref["vm"], abs(pert["vm_all"] - ref["vm_all"]) / ref["vm_all"])
    print(f"{scene}: the reference {ref['vm'] / 1e6:.4g} / {ref['vm_all'] / 1e6:.4g} MPa, perturbed by "
          f"{PERTURBATION:g}: {pert['vm'] / 1e6:.4g} / {pert['vm_all'] / 1e6:.4g} MPa ({_pct(moved)})")
    cands = []
    for c in maps["candidates"]:
        if not np.isfinite(c["error"]):              # a map that lost a speed: no model for the scene
            out = dict(vm=math.inf, vm_all=math.inf, sector_of_max=None, u_le=math.nan, seconds=0.0)
        else:
            out = disk_stress_at_tmax(runs[c["name"]], disk_model_file(c["options"], gnl=gnl), speed, gnl)
        err = max(abs(out["vm"] - ref["vm"]) / ref["vm"], abs(out["vm_all"] - ref["vm_all"]) / ref["vm_all"])
        err = err if np.isfinite(err) else math.inf
        print(f"{scene}: {c['name']}: sector 0 {out['vm'] / 1e6:.4g} MPa, over the sectors "
              f"{out['vm_all'] / 1e6:.4g} MPa ({_pct(err)}), {out['seconds']:.1f} s")
        cands.append(dict(name=c["name"], options=c["options"], us_per_step=c["us_per_step"], h=c["h"],
                          cost=c["cost"] + out["seconds"], error=err, vm_max=out["vm"], vm_max_all=out["vm_all"],
                          sector_of_max=out["sector_of_max"], u_le=out["u_le"], carry_on_s=out["seconds"],
                          held_out_error=None))
    return dict(description=f"the bladed disk's largest von Mises stress off the root corner and outside the tip band "
                            f"at t_max of one revolution carried on from the disk map scene's final states at the "
                            f"reference's largest robust response ({speed:.0f} rad/s), GNL {'on' if gnl else 'off'}, "
                            f"ci sectors: the larger of the relative errors in sector 0 and over the 36 sectors "
                            f"against the reference's "
                            f"{ref['vm'] / 1e6:.4g} MPa in sector 0 and {ref['vm_all'] / 1e6:.4g} MPa over the "
                            f"sectors (in sector {ref['sector_of_max']})",
                cost_unit="s (the disk map scene's sweep wall time + the revolution carried on and the "
                          "recovery, timed in this run; µs/sim-step and h are the map's)",
                reference=dict(options=ref_opts, speed=speed, vm_max=ref["vm"], vm_max_all=ref["vm_all"],
                               sector_of_max=ref["sector_of_max"], u_le=ref["u_le"], seconds=ref["seconds"]),
                candidates=cands, machine=machine_description(), held_out_case=None,
                floor=floor_record(ref_opts, cands, moved))


def floor_record(ref_opts: dict, cands: list[dict], moved: float | None = None) -> dict | None:
    """A scene's floor: the larger of what the reference's cap is worth (``cap_floor``) and, for a stress scene, how
    far the reference's 1e-4 perturbation moves the stress (``moved``; inf if the perturbed run diverged). None if
    neither is known."""
    cap = cap_floor(ref_opts, cands)
    why = [] if cap is None else [f"the reference's own model at {cap['cap_khz']:g} kHz is {_pct(cap['error'])} off it"]
    if moved is not None:
        moved = moved if np.isfinite(moved) else math.inf
        why.append(f"the reference's {PERTURBATION:g} perturbation moves the stress by {_pct(moved)}"
                   if np.isfinite(moved) else f"the reference's run perturbed by {PERTURBATION:g} diverged")
    if not why:
        return None
    record = dict(error=max(0.0 if cap is None else cap["error"], 0.0 if moved is None else moved), cap=cap,
                  why=" and ".join(why))
    return record if moved is None else dict(record, perturbation=moved)


def scene_disk_map(gnl: bool = False) -> tuple[dict, dict]:
    """The disk's short interaction map (8 speeds in 1,200-1,650 rad/s from rest, the disk maps' casing: cone normal,
    mu = 0.15), GNL off (20 revolutions) or on (12), against the largest model at the highest cap; held out: 7 other
    speeds. With GNL the reference's 1e-4 perturbation is the map's own option (the same probe and step)."""
    scene_name = "disk-map-gnl" if gnl else "disk-map-linear"
    ref_opts = DISK_GNL_REFERENCE if gnl else DISK_MAP_REFERENCE
    setup = DISK_GNL_MAP if gnl else DISK_MAP

    def reference_maps(speeds=None) -> tuple[MapRun, MapRun]:
        ref = run_disk_map("reference", ref_opts, speeds, gnl=gnl)
        pert = (run_disk_map("reference_perturbed", {**ref_opts, "perturbation": PERTURBATION}, speeds, gnl=True)
                if gnl else run_disk_map("reference_perturbed", ref_opts, speeds, PERTURBATION))
        return ref, pert

    ref, pert = reference_maps()
    runs = {"reference": ref, "reference_perturbed": pert}     # for the stress scene: the maps' final states
    robust = disk_robust(ref, pert)
    print(f"{scene_name}: robust speeds {ref.speeds[robust].round(1).tolist()}")
    cands = []
    for name, options in (DISK_GNL_CANDIDATES if gnl else DISK_MAP_CANDIDATES):
        run = runs[name] = run_disk_map(name, options, gnl=gnl)
        err = disk_map_errors(run, ref, robust)
        cands.append(dict(name=name, options=options, us_per_step=1e6 * run.sweep_wall / run.sim_steps, h=run.h,
                          wall_s=run.wall, sweep_s=run.sweep_wall, diverged=int(run.diverged.sum()),
                          cost=run.sweep_wall, error=err["map"], held_out_error=None,
                          errors={k: err[k] for k in ("nfrc", "largest", "speed", "peak")}))
        print(f"{scene_name}: {name}: {run.sweep_wall:.0f} s, error {err['map']:.3g} "
              f"({', '.join(f'{k} {err[k]:.3g}' for k in ('nfrc', 'largest', 'speed', 'peak'))})")
    big, top = largest_over_blades(ref), int(np.nanargmax(ref.nfrc))
    i_rob = int(np.flatnonzero(robust)[np.nanargmax(ref.nfrc[robust])])
    forces = ("; GNL forces: the sectors' exact tensors, or a point cubature trained with the cap on the study's "
              "speeds" if gnl else "")
    scene = dict(description=f"the bladed disk's short interaction map, GNL {'on' if gnl else 'off'}, 8 speeds in "
                             f"1,200-1,650 rad/s x {setup['revolutions']:g} revolutions from rest, the disk maps' "
                             f"casing (cone normal, mu = 0.15), 36 ci sectors with 8 tip nodes each{forces}: on the "
                             "robust speeds, the largest of the NFRC errors (node LE of sector 0 and the largest over "
                             "the blades) and of the relative errors of the speed and the amplitude of the largest "
                             "response at node LE of sector 0",
                 cost_unit="s (sweep wall time of the map)",
                 reference=dict(options=ref_opts, h=ref.h, sweep_s=ref.sweep_wall, wall_s=ref.wall,
                                us_per_step=1e6 * ref.sweep_wall / ref.sim_steps,
                                peak_speed=float(ref.speeds[np.nanargmax(ref.nfrc)]), peak_m=float(np.nanmax(ref.nfrc)),
                                largest_peak_m=float(np.nanmax(big)), robust_speeds=ref.speeds[robust].tolist(),
                                peak_moved_by_perturbation=float(abs(pert.nfrc[top] - ref.nfrc[top]) / ref.nfrc[top]),
                                robust_peak_speed=float(ref.speeds[i_rob]), robust_peak_m=float(ref.nfrc[i_rob]),
                                perturbation=PERTURBATION, robust_threshold=ROBUST),
                 candidates=cands, machine=machine_description(),
                 held_out_case=f"{DISK_HELD_OUT_SPEEDS[2]} other speeds in {DISK_HELD_OUT_SPEEDS[0]:g}-"
                               f"{DISK_HELD_OUT_SPEEDS[1]:g} rad/s" + (
                                   "; a cubature as trained on the study's speeds (its capped training step from the "
                                   "held-out map's probe)" if gnl else ""))
    floor = floor_record(ref_opts, cands)
    if floor is not None:
        scene["floor"] = floor
    ref_h, pert_h = reference_maps(DISK_HELD_OUT_SPEEDS)
    robust_h = disk_robust(ref_h, pert_h)
    scene["held_out_reference"] = dict(robust_speeds=ref_h.speeds[robust_h].tolist(), sweep_s=ref_h.sweep_wall)
    if robust_h.any():
        held_out_choices(scene, TOLERANCES, lambda name, options: disk_map_errors(
            run_disk_map(name, held_out_options(options, setup), DISK_HELD_OUT_SPEEDS, gnl=gnl), ref_h,
            robust_h)["map"])
    else:        # a check on no speed would judge nothing: the choice rests on the study's speeds, and says so
        scene["held_out_case"] += (": none of them robust to the reference's 1e-4 perturbation, so no model could be "
                                   "judged there (the choices rest on the study's speeds alone)")
    return scene, runs


# ## The bladed disk's forced response without contact (§3.3): basis, interface modes, modal derivatives, force

DISK_FORCED = dict(periods=10.0, steps_per_period=100, ramp=1.0)     # bench_disk_forced.py's defaults (Newmark, T/100)
DISK_FORCED_CASES = ((0, 4000.0), (0, 13000.0), (9, 4000.0), (9, 13000.0))       # (N_d, omega rad/s)
DISK_FORCED_HELD_OUT = ((0, 17000.0), (9, 17000.0))
DISK_FORCED_GNL_CASES = ((0, 4000.0),)
DISK_FORCED_GNL_HELD_OUT = ((0, 13000.0),)
DISK_FORCED_PATCH_MM = 3.0          # GNL: the 400 N over a 3 mm patch (a point load collapses the GNL reference)
_FORCED_MODEL = {"r_c": 10, "r_md": 0, "r_cyclic": 144}              # the §3.3 models' basis (r_b = 3, node LE)
DISK_FORCED_CANDIDATES = [  # node LE kept (r_b = 3) in every sector; GNL off; r_md by MI 2b (in the basis only)
    ("r_c 10, r_cyclic 144", _FORCED_MODEL),
    ("r_c 5, r_cyclic 144", {**_FORCED_MODEL, "r_c": 5}),
    ("r_c 2, r_cyclic 144", {**_FORCED_MODEL, "r_c": 2}),
    ("r_c 10, r_cyclic 72", {**_FORCED_MODEL, "r_cyclic": 72}),
    ("r_c 5, r_cyclic 72", {**_FORCED_MODEL, "r_c": 5, "r_cyclic": 72}),
    ("r_c 10, r_cyclic 288", {**_FORCED_MODEL, "r_cyclic": 288}),
    ("r_c 10, r_MD 10, r_cyclic 144", {**_FORCED_MODEL, "r_md": 10}),
]
DISK_FORCED_GNL_CANDIDATES = [  # the patch's static correction in every basis; exact sector tensors
    ("r_MD 0 (GNL neglected)", {**_FORCED_MODEL, "face_shapes": 0}),
    ("MI 2b r_MD 10, eq. 61", {**_FORCED_MODEL, "r_md": 10, "face_shapes": 0}),
    ("MI 2b r_MD 20, eq. 61", {**_FORCED_MODEL, "r_md": 20, "face_shapes": 0}),
    ("MI 2b r_MD 20, 6 face shapes", {**_FORCED_MODEL, "r_md": 20, "face_shapes": 6}),
]


@functools.lru_cache(maxsize=None)
def _forced_sector():
    """The ci disk sector, its operators and its free K and M (the indicator's norms)."""
    from rotor37_rom import fem

    sector, ops = _disk_sector()
    K_s = fem.petsc_to_scipy(fem.assemble_stiffness(sector, ops, clamped=False))
    M_s = fem.petsc_to_scipy(fem.assemble_mass(sector, ops, clamped=False))
    return sector, ops, K_s, M_s


def forced_reference(case: tuple, gnl: bool) -> dict:
    """The full-order history of one case (bench_disk_forced.reference: the sectors of one repeat closed on
    themselves, implicit Newmark at the scene's step; cached under results/speed_accuracy/disk_forced/ci, a GNL run
    checkpointed and resumed)."""
    from rotor37_rom.studies import forced_response as bdf

    sector, ops, *_ = _forced_sector()
    out = WORK / "disk_forced" / "ci"
    out.mkdir(parents=True, exist_ok=True)
    before = set(out.glob("fom_*.npz"))
    ref = bdf.reference(sector, types.SimpleNamespace(ops=ops), case, gnl,
                        DISK_FORCED["periods"], DISK_FORCED["steps_per_period"], DISK_FORCED["ramp"], out,
                        patch_mm=DISK_FORCED_PATCH_MM if gnl else 0.0)
    if set(out.glob("fom_*.npz")) - before:           # computed (or finished from a checkpoint), not read
        FORCED_RUNS.append(None)
    return ref


def forced_model(options: dict, gnl: bool):
    """The §3.3 disk model of ``options`` (node LE kept, r_b = 3; r_md by MI 2b; GNL: the patch's static correction
    and exact tensors with eq. 61's force or ``face_shapes``), built once (cached under results/speed_accuracy)."""
    from rotor37_rom.disk.builder import DiskReductionConfig, build_disk_model

    sector, ops, *_ = _forced_sector()
    config = DiskReductionConfig(tip_nodes="LE", r_c=options["r_c"], r_md=options["r_md"], criterion="MI2b",
                                 r_cyclic=options["r_cyclic"],
                                 forces="intrusive" if gnl and options["r_md"] else "none",
                                 load_patch=1e-3 * DISK_FORCED_PATCH_MM if gnl else 0.0,
                                 face_shapes=options.get("face_shapes", 0) if gnl and options["r_md"] else 0)
    t0 = time.perf_counter()
    model, built = build_disk_model(sector, config, ops=ops, cache_dir=WORK / "disk_forced" / "ci" / "models")
    return model, (None if built.get("cached") else time.perf_counter() - t0)


def forced_error(model, case: tuple, gnl: bool, ref: dict) -> dict:
    """One reduced run of ``case`` against its reference (bench_disk_forced.reduced, the same Newmark and step), scored
    by the performance indicator's four criteria (loaded node, tip nodes, field, strain energy); ``error`` is their
    largest. Cached by the model's key: a re-run of the study reads it."""
    from rotor37_rom.studies import forced_response as bdf
    from rotor37_rom.disk.indicators import performance_indicator

    sector, _, K_s, M_s = _forced_sector()
    spec = json.dumps([model.key, list(case), gnl, DISK_FORCED, DISK_FORCED_PATCH_MM if gnl else 0.0,
                       float(ref["wall"])], sort_keys=True)
    path = WORK / "disk_forced" / "ci" / f"rom_{hashlib.sha1(spec.encode()).hexdigest()[:16]}.json"
    if path.is_file():
        return json.loads(path.read_text())            # a failure's error is inf (JSON's Infinity)
    t0 = time.perf_counter()
    try:
        rom = bdf.reduced(model, sector, case, gnl and model.forces is not None, DISK_FORCED["periods"],
                          DISK_FORCED["steps_per_period"], DISK_FORCED["ramp"], ref,
                          patch_mm=DISK_FORCED_PATCH_MM if gnl else 0.0)
    except RuntimeError as exc:                        # Newton failed even at dt / 32: a failure, not a result
        wall = time.perf_counter() - t0
        out = dict(error=math.inf, I=0.0, errors={}, wall_s=wall, us_per_step=None, failed=str(exc))
    else:
        score = performance_indicator(ref["tip"], rom["tip"], ref["fields"], rom["fields"], K_s, M_s,
                                      loaded=(sector.tip_names.index("LE"), 2))
        out = dict(error=max(score["errors"].values()), I=score["I"], errors=score["errors"], wall_s=rom["wall"],
                   us_per_step=1e6 * rom["wall"] / rom["steps"])
    FORCED_RUNS.append(out["wall_s"])
    save_json(path, out, default=_finite)
    return out


def scene_disk_forced(gnl: bool = False) -> dict:
    """The bladed disk's forced response without contact (paper §3.3): 400 N along e_z at node LE of every sector
    travelling with N_d diameters, ramped over one period, 10 periods, implicit Newmark at T/100 for the full order (one
    repeat of sectors closed on themselves) and the reduced models alike, so the error is the reduction's. GNL off:
    N_d 0 and 9 at 4,000 and 13,000 rad/s, held out 17,000 rad/s; GNL on: the load over a 3 mm patch, N_d 0 at 4,000
    rad/s, held out 13,000 rad/s (a GNL reference of N_d 9 would carry 4 sectors)."""
    name = "disk-forced-gnl" if gnl else "disk-forced-linear"
    cases, held_cases = ((DISK_FORCED_GNL_CASES, DISK_FORCED_GNL_HELD_OUT) if gnl
                         else (DISK_FORCED_CASES, DISK_FORCED_HELD_OUT))
    refs = {case: forced_reference(case, gnl) for case in cases}
    ref_wall = sum(float(r["wall"]) for r in refs.values())
    steps = sum(r["tip"].shape[0] - 1 for r in refs.values())
    print(f"{name}: full-order references {ref_wall:.0f} s")
    cands, models = [], {}
    for cname, options in (DISK_FORCED_GNL_CANDIDATES if gnl else DISK_FORCED_CANDIDATES):
        model, build = models[cname] = forced_model(options, gnl)
        runs = {case: forced_error(model, case, gnl, refs[case]) for case in cases}
        worst = max(runs, key=lambda c: runs[c]["error"])
        wall = sum(r["wall_s"] for r in runs.values())
        cands.append(dict(name=cname, options=options, r=model.r, build_s=build, cost=wall,
                          us_per_step=1e6 * wall / steps, h=None, error=runs[worst]["error"],
                          held_out_error=None, I=min(r["I"] for r in runs.values()),
                          worst_case={"N_d": worst[0], "omega": worst[1]}, errors=runs[worst]["errors"],
                          by_case=[{"N_d": c[0], "omega": c[1], **runs[c]} for c in cases]))
        print(f"{name}: {cname}: r = {model.r}, {wall:.1f} s, error {runs[worst]['error']:.3g} (I >= "
              f"{cands[-1]['I']:.3f}; worst N_d {worst[0]} at {worst[1]:g} rad/s)")
    load = (f"400 N along e_z over a {DISK_FORCED_PATCH_MM:g} mm patch around node LE of every sector" if gnl
            else "400 N along e_z at node LE of every sector")
    le = _forced_sector()[0].tip_names.index("LE")
    where = ", ".join(f"N_d {nd} at {w:,.0f} rad/s" for nd, w in cases)
    scene = dict(description=f"the bladed disk's forced response without contact (§3.3), GNL {'on' if gnl else 'off'}"
                             f": {load}, travelling with N_d diameters, ramped over one period, "
                             f"{DISK_FORCED['periods']:g} periods from rest ({where}), implicit Newmark at T/100 for "
                             "the full order and the models alike (the error is the reduction's); node LE kept in "
                             "every sector (r_b = 3)" + (", the patch's static correction in every basis, exact "
                                                         "sector tensors" if gnl else "") +
                             ": the largest of the performance indicator's four relative errors (loaded node, tip "
                             "nodes, M- and K-norm of the sector fields) over the cases",
                 cost_unit="s (the reduced runs' wall time over the cases; the build is not included)",
                 reference=dict(options={"model": "full order, one repeat of sectors closed on themselves",
                                         "preset": "ci"}, cost=ref_wall, wall_s=ref_wall,
                                us_per_step=1e6 * ref_wall / steps,
                                cases=[{"N_d": c[0], "omega": c[1], "wall_s": float(r["wall"]),
                                        "max_le_z_mm": 1e3 * float(np.abs(r["tip"][:, :, le, 2]).max()),
                                        "newton_per_step": float(np.mean(r["iterations"])) if gnl else None}
                                       for c, r in refs.items()]),
                 candidates=cands, machine=machine_description(),
                 held_out_case=", ".join(f"N_d {nd} at {w:,.0f} rad/s" for nd, w in held_cases)
                 + " (every candidate run there)")
    try:
        held = {case: forced_reference(case, gnl) for case in held_cases}
    except RuntimeError as exc:          # the full order's Newton failed: no yardstick there, and the page says so
        scene["held_out_case"] += f": its full-order reference failed ({exc}), so no model has a held-out check"
        return scene
    for cand in cands:                   # every candidate (a reduced run costs less than the references): the chooser
        runs = [forced_error(models[cand["name"]][0], case, gnl, held[case]) for case in held_cases]
        cand["held_out_error"] = max(run["error"] for run in runs)   # then judges each one by both, at any tolerance
        failed = [run["failed"] for run in runs if "failed" in run]
        if failed:
            cand["held_out_failed"] = failed[0]
        print(f"{name}: held out: {cand['name']}: {cand['held_out_error']:.3g}")
    return scene


# ## von Mises at t_max

@functools.lru_cache(maxsize=None)
def _recovery(r_c: int):
    """The ci blade's sector and the stress recovery of the r_c model's basis (made once per basis)."""
    from mpi4py import MPI

    from rotor37_rom import fem
    from rotor37_rom.model.reduced import load_reduced_model
    from rotor37_rom.post.recovery import StressRecovery

    model = load_reduced_model(model_file(r_c))
    sector = fem.create_blade_sector(MPI.COMM_SELF, preset=MAP["preset"])
    H, _, cells = fem.quadrature_gradients(sector, model.Phi.T)
    return sector, model, StressRecovery(H, cells, *sector.material.lame)


def stress_at_tmax(run: MapRun, options: dict, gnl: bool, speed: float) -> dict:
    """von Mises at t_max of one revolution carried on from ``run``'s final state at ``speed`` (the report's
    procedure: ``analysis.stress_at_peak``, the largest outside the contact nodes' tip band), with the wall time."""
    from rotor37_rom.post.stress import stress_at_peak

    cm = load_demo("contact_map")
    sector, model, recovery = _recovery(int(options.get("r_c", 15)))     # made once per basis, not timed
    k = int(np.argmin(np.abs(run.speeds - speed)))
    record, h = run.records[k], run.record_h[k]
    scheme = cm.time_scheme(run.config, model, gnl, None, h=h)                     # the map's forces (its cubature)
    t0 = time.perf_counter()
    res, _ = cm.carry_on_record(run.config, scheme, record, speed)
    if res.diverged_step[0] >= 0:
        return dict(vm_max=math.inf, seconds=time.perf_counter() - t0)
    peak = stress_at_peak(sector, model, recovery, res, gnl, magnitude=True)
    return dict(vm_max=peak["vm_max"], u_le=peak["u_le"], seconds=time.perf_counter() - t0)


def scene_stress(gnl: bool, maps: dict) -> dict:
    """von Mises at t_max at the reference map's 1B/EO4 resonance (the report's speed: ``engine_order_resonance``),
    for the map scene's reference and candidates (the same runs: the stress needs a map's final state); error
    relative to the reference's maximum. On the ci mesh, whose clamped root corner is singular: a comparison of
    models on one mesh, not a converged stress."""
    from rotor37_rom.studies.sweep import engine_order_resonance, interaction_map

    ref_run = run_map("reference", gnl, maps["reference"]["options"])
    speed = engine_order_resonance(interaction_map(ref_run.records, ref_run.config.node), 4, MAP["revolutions"])
    if not np.isfinite(speed):                        # no speed dominated by EO4: the largest response
        speed = maps["reference"]["peak_speed"]
    ref = stress_at_tmax(ref_run, maps["reference"]["options"], gnl, speed)
    cands = []
    for c in maps["candidates"]:
        if not np.isfinite(c["error"]):              # a map that lost a speed: no model for the scene
            vm, seconds = math.inf, 0.0
        else:
            out = stress_at_tmax(run_map(c["name"], gnl, c["options"]), c["options"], gnl, speed)
            vm, seconds = out["vm_max"], out["seconds"]
        err = abs(vm - ref["vm_max"]) / ref["vm_max"] if np.isfinite(vm) else math.inf
        print(f"stress {'gnl' if gnl else 'linear'} {c['name']}: {vm / 1e6:.4g} MPa ({_pct(err)})")
        cands.append(dict(name=c["name"], options=c["options"], us_per_step=c["us_per_step"], h=c["h"],
                          cost=c["cost"] + seconds, error=err, vm_max=vm, held_out_error=None))
    kind = "GNL" if gnl else "GNL off"
    return dict(description=f"largest von Mises stress (outside the contact nodes' tip band) at t_max of one "
                            f"revolution carried on from the map's final state at the reference's 1B/EO4 resonance "
                            f"({speed:g} rad/s), {kind}, the map scene's runs, ci mesh: relative error against the "
                            f"reference's {ref['vm_max'] / 1e6:.4g} MPa (LE at {1e3 * abs(ref['u_le']):.3g} mm)",
                cost_unit="s (sweep wall time of the map + the revolution carried on and the recovery)",
                reference=dict(options=maps["reference"]["options"], speed=speed, vm_max=ref["vm_max"],
                               u_le=ref["u_le"]),
                candidates=cands, held_out_case=None)


# ## Stability map: the stable step against the amplitude

def scene_stability() -> dict:
    from rotor37_rom.dynamics.explicit import CentralDifference, highest_frequency, tangent_highest_frequency
    from rotor37_rom.model.reduced import load_reduced_model, solve_reduced_static

    model = load_reduced_model(model_file(15))
    le = model.nodes.q_index[model.nodes.row("LE")][0]      # x DOF of node LE
    f = np.zeros(model.r)
    f[le] = 1.0
    q1 = np.linalg.solve(model.K, f)
    amplitudes = np.geomspace(1e-5, 5e-3, 12)
    loads = amplitudes / q1[le]
    rows = []
    states = solve_reduced_static(model, f, loads)
    for cap in (None, 120.0, 60.0):
        scheme = CentralDifference(model, nonlinear=False, frequency_cap=None if cap is None else 2e3 * np.pi * cap)
        lin = 2 / highest_frequency(scheme.M, model.K)
        gnl = [2 / tangent_highest_frequency(model, q, mass=scheme.M) for q in states]
        reached = [float(abs(q[le])) for q in states]
        rows.append(dict(cap_khz=cap, h_linear=float(lin), h_gnl=[float(h) for h in gnl], le_amplitude=reached))
        print(f"stability, cap {cap}: linear {lin:.3g} s, GNL {gnl[0]:.3g} .. {gnl[-1]:.3g} s")
    return dict(description="the stable step 2 / omega_max of the tangent (K + dg/dq, mass M or the capped mass) on "
                            "static states of a load at node LE along e_x, against the LE displacement; r = 45 ci",
                rows=rows)


# ## The chosen 5 % GNL model against the paper's setting

def scene_paper_speedup(study: dict, tolerance: float = 0.05) -> dict:
    """Per simulated second of the GNL map: the model chosen at ``tolerance`` against the paper's r = 189 with exact
    tensors at h = 1e-7 s, as a ratio of per-step costs measured here in the same run (the integrator's prediction
    with the forces, batch of the map's 11 speeds; r = 189 on a synthetic model with tensors of its size: the cost of
    a step does not depend on their values, and building the real ones takes hours)."""
    from bench_integrator import synthetic_model, time_per_step

    from rotor37_rom.dynamics.explicit import CentralDifference
    from rotor37_rom.studies.model_choice import choose_model
    from rotor37_rom.model.reduced import load_reduced_model

    cm = load_demo("contact_map")
    for tolerance in (tolerance, 0.2):          # no 5 % model: the 20 % one (the docs say which)
        try:
            choice = choose_model("map-gnl", tolerance, study)
            break
        except ValueError:
            continue
    cand = next(c for c in study["scenes"]["map-gnl"]["candidates"] if c["name"] == choice.name)
    options = dict(cand["options"])
    r_c = options.pop("r_c", 15)
    tag = f"gnl_{choice.name}_{int(MAP['speeds'][0])}_{int(MAP['speeds'][1])}_{int(MAP['speeds'][2])}"
    config = cm.ContactMapConfig(**{**MAP, "model": model_file(r_c), "gnl": "on", "out": WORK / tag.replace(" ", "_"),
                                    **options, "h": cand["h"]})
    scheme = cm.time_scheme(config, load_reduced_model(model_file(r_c)), True, None)
    P = int(MAP["speeds"][2])
    rng = np.random.default_rng(1)
    rows = {}
    for name, sch in (("chosen", scheme), ("paper", CentralDifference(synthetic_model(PAPER_R), nonlinear=True,
                                                                       h=PAPER_H, force=True))):
        Q = rng.standard_normal((sch.model.r, P)) * 1e-6
        t = time_per_step(lambda: sch.predict(Q, Q.copy(), None), min_time=2.0) / P
        rows[name] = dict(r=sch.model.r, h=sch.h, us_per_sim_step=1e6 * t, us_per_simulated_ms=1e6 * t / sch.h * 1e-3)
        print(f"{name}: r = {sch.model.r}, {1e6 * t:.1f} us per simulation-step, h = {sch.h:.3g} s")
    per_step = rows["paper"]["us_per_sim_step"] / rows["chosen"]["us_per_sim_step"]
    step = rows["chosen"]["h"] / PAPER_H
    return dict(tolerance=tolerance, model=choice.name, expected_error=choice.error, rows=rows,
                per_step_ratio=per_step, step_ratio=step, speedup=per_step * step)


# ## Cost against r per force method

COST_R = (30, 45, 55, 85, 125, 189)
CI_POINTS = 30_548           # the ci blade's quadrature points (degree 4: 14 on each of 2,182 cells)
POINTS_PER_MODE = 10         # trained here: 8.5-13.5 points per mode at tolerance 1e-4, 19-20 at 1e-5 (`trained`)


def _synthetic_cubature(r: int, n: int, precision: str, rng) -> "QuadratureForces":
    from rotor37_rom.forces.tensors import QuadratureForces

    return QuadratureForces(rng.standard_normal((n, r, 3, 3)) * 1e-3, rng.random(n) * 1e-9, 1.0e11, 7.0e10,
                            precision=precision)


def scene_cost_r(r_values=COST_R, P: int = 11, min_time: float = 0.4) -> dict:
    """The integrator's cost per simulation-step against r for each force method, same run: no GNL forces (linear),
    exact unique-monomial tensors, point cubature on all 30,548 quadrature points of the ci blade (exact, no
    training) and on 10 points per mode (a trained cubature's size), float64 and float32; batch of the map's P
    speeds. Synthetic models of each size: the cost of a step depends on the sizes, not on the values. The trained
    cubatures of the map-gnl scene are timed as they are (their r and point count) to place them on the chart."""
    from bench_integrator import synthetic_model, time_per_step

    from rotor37_rom.dynamics.explicit import CentralDifference
    from rotor37_rom.model.reduced import load_reduced_model

    rng = np.random.default_rng(3)
    methods = {"linear (no GNL forces)": [], "exact tensors": [], "cubature, all points": [],
               f"cubature, {POINTS_PER_MODE} r points": [], f"cubature, {POINTS_PER_MODE} r points, float32": []}

    def cost(model, nonlinear=True) -> float:
        sch = CentralDifference(model, nonlinear=nonlinear, h=PAPER_H, force=True)
        Q = rng.standard_normal((model.r, P)) * 1e-6
        return 1e6 * time_per_step(lambda: sch.predict(Q, Q.copy(), None), min_time=min_time) / P

    for r in r_values:
        model = synthetic_model(r)
        methods["linear (no GNL forces)"].append(cost(model, nonlinear=False))
        methods["exact tensors"].append(cost(model))
        for name, n, precision in (("cubature, all points", CI_POINTS, "double"),
                                   (f"cubature, {POINTS_PER_MODE} r points", POINTS_PER_MODE * r, "double"),
                                   (f"cubature, {POINTS_PER_MODE} r points, float32", POINTS_PER_MODE * r, "single")):
            methods[name].append(cost(dataclasses.replace(model, forces=_synthetic_cubature(r, n, precision, rng))))
            print(f"r = {r}: {name}: {methods[name][-1]:.3g} us per simulation-step")
        del model
    study_training = f"contact runs {list(study_training_speeds())}"
    trained = []
    for path in sorted((WORK / "cubature_cache").glob("cubature_*.npz")):
        if path.name.endswith(".states.npz"):
            continue
        model = load_reduced_model(path)
        info = model.metadata.get("hyper_reduction", {})
        if not info.get("label", "").startswith(study_training):      # trained for another map: not the study's
            continue
        for precision in ("double", "single"):
            m = dataclasses.replace(model, forces=model.forces.with_precision(precision))
            trained.append(dict(r=model.r, points=int(model.forces.w.size), tol=info.get("tol"), precision=precision,
                                us_per_sim_step=cost(m)))
    return dict(description=f"the integrator's prediction (linear step + forces) per simulation-step against r, "
                            f"batch of {P} speeds; synthetic models of each size (the cost depends on the sizes only); "
                            f"all points = the ci blade's {CI_POINTS:,} quadrature points",
                r=list(r_values), P=P, methods=methods, trained=trained, points_per_mode=POINTS_PER_MODE,
                all_points=CI_POINTS)


def chart_cost_r(cost_r: dict) -> Path:
    from rotor37_rom.viz.charts import _pyplot, _save

    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6.8, 4.6))
    for k, (name, values) in enumerate(cost_r["methods"].items()):
        ax.loglog(cost_r["r"], values, "o-", color=f"C{k}", label=name)
    for t in cost_r["trained"]:
        k = 4 if t["precision"] == "single" else 3
        ax.loglog([t["r"]], [t["us_per_sim_step"]], "*", color=f"C{k}", ms=11, mec="k", mew=0.5)
        single = t["precision"] == "single"
        ax.annotate(f"trained {t['tol']:g}: {t['points']} pts{', f32' if single else ''}",
                    (t["r"], t["us_per_sim_step"]), fontsize=6.5, xytext=(6, -3) if single else (-6, 0),
                    textcoords="offset points", ha="left" if single else "right")
    ax.set_xlabel("r (reduced coordinates)")
    ax.set_ylabel("µs per simulation-step")
    ax.set_title(f"cost against r per force method (batch of {cost_r['P']} speeds)", fontsize=9)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    return _save(fig, IMG / "speed_accuracy_cost_r.png")


# ## Charts and the file

def chart(name: str, scene: dict) -> Path:
    from rotor37_rom.viz.charts import plot_speed_accuracy
    from rotor37_rom.studies.model_choice import scene_floor

    rows = [(c["name"], c["cost"], c["error"]) for c in scene["candidates"] if c["cost"] > 0]
    return plot_speed_accuracy(rows, IMG / f"speed_accuracy_{name}.png",
                               title=f"{name}: error against cost (Pareto front joined)",
                               cost_label=scene["cost_unit"], tolerances=TOLERANCES,
                               floor=scene_floor(scene),
                               reference=(f"the full order ({scene['reference']['cost']:.3g} s)",
                                          scene["reference"]["cost"]) if "cost" in scene["reference"] else None)


def chart_stability(stab: dict) -> Path:
    from rotor37_rom.viz.charts import _pyplot, _save

    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for k, row in enumerate(stab["rows"]):
        label = "no cap" if row["cap_khz"] is None else f"cap {row['cap_khz']:g} kHz"
        ax.loglog(np.asarray(row["le_amplitude"]) * 1e3, row["h_gnl"], "o-", color=f"C{k}", label=f"GNL, {label}")
        ax.axhline(row["h_linear"], color=f"C{k}", ls="--", lw=0.8, label=f"linear, {label}")
    ax.set_xlabel("static LE displacement (mm)")
    ax.set_ylabel("stable step 2 / ω_max (s)")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    return _save(fig, IMG / "speed_accuracy_stability.png")


def _pct(x) -> str:
    if x is None:
        return "–"
    if not np.isfinite(x):
        return "diverged"
    return f"{100 * x:.2g} %" if x < 1 else f"{100 * x:.0f} %"


def _options(options: dict) -> str:
    return ", ".join(f"{k} {v}" for k, v in options.items()) or "–"


def render_markdown(study: dict) -> str:
    """The generated part of docs/choosing-a-model.md: per scene, the candidates (cost, error, held-out error,
    Pareto-optimal or not) and the models chosen at each tolerance, every number from the study file."""
    from rotor37_rom.studies.model_choice import pareto_front

    runs = study.get("runs", [])
    full = [i for i, r in enumerate(runs) if r["from_scratch"]]
    text = f"Generated by `{study['command']}` on {study['machine']}"
    if full:
        r = runs[full[-1]]
        text += (f"; the study from scratch (no cached runs: scenes {', '.join(r['scenes'])}) took "
                 f"{r['wall_s'] / 60:.0f} min")
        added = [x["note"].removeprefix(PREFIX) for x in runs[full[-1] + 1:] if x.get("note")]
        text += f"; {PREFIX}{'; '.join(added)}" if added else ""
    lines = [text + ".", ""]
    for name, scene in study["scenes"].items():
        cands = scene["candidates"]
        front = pareto_front([c["cost"] for c in cands], [c["error"] for c in cands])
        lines += [f"### Scene `{name}`", "", scene["description"][0].upper() + scene["description"][1:] + ".", ""]
        if scene.get("machine", study["machine"]) != study["machine"]:
            lines += [f"Measured on {scene['machine']}.", ""]
        if f"speed_accuracy_{name}.png" in {p.name for p in IMG.glob("speed_accuracy_*.png")}:
            lines += [f"![{name}: error against cost](img/speed_accuracy_{name}.png)", ""]
        extra = "us_per_step" in cands[0]
        head = "| model | options | cost | " + ("µs/sim-step | h (s) | " if extra else "") + \
               "error | held-out error | Pareto |"
        lines += [head, "|" + "---|" * (head.count("|") - 1)]
        for c, opt in sorted(zip(cands, front), key=lambda x: x[0]["cost"]):
            row = f"| {c['name']} | {_options(c['options'])} | {c['cost']:.3g} | "
            if extra:
                row += f"{c['us_per_step']:.3g} | {'–' if c['h'] is None else format(c['h'], '.3g')} | "
            row += f"{_pct(c['error'])} | {_pct(c.get('held_out_error'))} | {'yes' if opt else ''} |"
            lines.append(row)
        lines += ["", f"Cost: {scene['cost_unit']}. Held-out case: {scene.get('held_out_case') or 'none'}.", ""]
        if scene.get("floor"):
            lines += [f"Floor: {_pct(scene['floor']['error'])} ({scene['floor']['why']}): the scene cannot tell "
                      "models apart below it, and the chooser expects no model to do better.", ""]
        chosen = []
        for tol, c in scene["choices"].items():
            if c["name"] is None:
                chosen.append(f"{100 * float(tol):g} %: none ({c['reason']})")
            else:
                chosen.append(f"{100 * float(tol):g} %: **{c['name']}** (expected {_pct(c['error'])}, cost "
                              f"{c['cost']:.3g})")
        lines += ["Chosen: " + "; ".join(chosen) + ".", ""]
    ps = study.get("paper_speedup")
    if ps:
        rows = ps["rows"]
        lines += ["### The chosen GNL model against the paper's setting", "",
                  f"The `map-gnl` model chosen at {100 * ps['tolerance']:g} % ({ps['model']}, expected error "
                  f"{_pct(ps['expected_error'])}) against the paper's r = {rows['paper']['r']} with exact tensors at "
                  f"h = {rows['paper']['h']:.3g} s, per simulation-step of the integrator with its forces (batch of "
                  f"the map's speeds; r = {rows['paper']['r']} on a synthetic model of its size), same run: "
                  f"{rows['chosen']['us_per_sim_step']:.3g} against {rows['paper']['us_per_sim_step']:.4g} µs per "
                  f"simulation-step ({ps['per_step_ratio']:.3g}×), with a step {ps['step_ratio']:.3g}× larger "
                  f"(h = {rows['chosen']['h']:.3g} s): **{ps['speedup']:.3g}× less wall time per simulated second**.",
                  ""]
    cr = study.get("cost_r")
    if cr:
        names = list(cr["methods"])
        lines += ["### Cost against r per force method", "", cr["description"][0].upper() + cr["description"][1:]
                  + " (µs per simulation-step).", "", "![cost against r](img/speed_accuracy_cost_r.png)", "",
                  "| r | " + " | ".join(names) + " |", "|" + "---|" * (len(names) + 1)]
        for i, r in enumerate(cr["r"]):
            lines.append(f"| {r} | " + " | ".join(f"{cr['methods'][n][i]:.3g}" for n in names) + " |")
        trained = "; ".join(f"r = {t['r']}, {t['points']} points (tolerance {t['tol']:g}), "
                            f"{'float32' if t['precision'] == 'single' else 'float64'}: {t['us_per_sim_step']:.3g} µs"
                            for t in cr["trained"])
        lines += ["", f"The trained cubatures of the `map-gnl` scene, same run: {trained}.", ""]
    stab = study.get("stability")
    if stab:
        lines += ["### Scene `stability`", "", stab["description"][0].upper() + stab["description"][1:] + ".", ""]
        amps = stab["rows"][0]["le_amplitude"]
        pick = sorted({0, len(amps) // 2, len(amps) - 3, len(amps) - 1})
        head = "| model | linear | " + " | ".join(f"GNL at {1e3 * amps[i]:.3g} mm" for i in pick) + " |"
        lines += [head, "|" + "---|" * (head.count("|") - 1)]
        for row in stab["rows"]:
            name = "no cap" if row["cap_khz"] is None else f"cap {row['cap_khz']:g} kHz"
            lines.append(f"| {name} | {row['h_linear']:.3g} s | "
                         + " | ".join(f"{row['h_gnl'][i]:.3g} s" for i in pick) + " |")
        lines.append("")
    return "\n".join(lines)


DOC = ROOT / "docs" / "choosing-a-model.md"
BEGIN, END = "<!-- study: begin -->", "<!-- study: end -->"


def write_docs(study: dict) -> None:
    text = DOC.read_text() if DOC.is_file() else f"# Choosing a model\n\n{BEGIN}\n{END}\n"
    head, rest = text.split(BEGIN, 1)
    tail = rest.split(END, 1)[1]
    DOC.write_text(f"{head}{BEGIN}\n{render_markdown(study)}\n{END}{tail}")


def record_choices(study: dict) -> None:
    from rotor37_rom.studies.model_choice import choose_model

    for name, scene in study["scenes"].items():
        scene["choices"] = {}
        for tol in TOLERANCES:
            try:
                c = choose_model(name, tol, study)
                scene["choices"][f"{tol:g}"] = dict(name=c.name, error=c.error, cost=c.cost)
            except ValueError as exc:
                scene["choices"][f"{tol:g}"] = dict(name=None, reason=str(exc))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", nargs="+", choices=SCENES + DISK_SCENES + ("all", "disk"),
                        default=["all"],
                        help="scenes to run: all (the single blade's), disk (the bladed disk's) or names")
    parser.add_argument("--json", type=Path, default=ROOT / "rotor37_rom" / "data" / "speed_accuracy.json")
    args = parser.parse_args(argv)
    todo = tuple(dict.fromkeys(name for scene in args.scene
                               for name in {"all": SCENES, "disk": DISK_SCENES}.get(scene, (scene,))))
    # from scratch: the whole single-blade study with no cached runs (a disk scene alone is a note on the study)
    fresh = (not WORK.is_dir() or not any(WORK.iterdir())) and set(SCENES) <= set(todo)
    t_start = time.perf_counter()
    WORK.mkdir(parents=True, exist_ok=True)
    study = json.loads(args.json.read_text()) if args.json.is_file() else {"schema": 1, "scenes": {}}
    for name in todo:
        t0 = time.perf_counter()
        if name == "modes":
            study["scenes"]["modes"] = scene_modes()
        elif name == "clearance":
            study["scenes"]["clearance"] = scene_clearance()
        elif name == "disk-modes":
            study["scenes"]["disk-modes"] = scene_disk_modes()
            FRESH.append(f"scene disk-modes {time.perf_counter() - t0:.0f} s")
        elif name in ("disk-map-linear", "disk-map-gnl"):
            before, gnl, stress = len(FRESH), name.endswith("gnl"), name.replace("map", "stress")
            study["scenes"][name], runs = scene_disk_map(gnl)
            study["scenes"][stress] = scene_disk_stress(study["scenes"][name], runs, gnl)
            maps = len(FRESH) - before          # run_map notes each map it computed (not read from WORK)
            FRESH.append(f"scenes {name} and {stress} {time.perf_counter() - t0:.0f} s ("
                         + (f"{maps} maps computed, the others" if maps else "every map") +
                         " read from results/speed_accuracy)")
        elif name in ("disk-forced-linear", "disk-forced-gnl"):
            FORCED_RUNS.clear()
            study["scenes"][name] = scene_disk_forced(name.endswith("gnl"))
            refs = sum(run is None for run in FORCED_RUNS)
            roms = len(FORCED_RUNS) - refs
            FRESH.append(f"scene {name} {time.perf_counter() - t0:.0f} s"
                         + (f" ({refs} full-order and {roms} reduced runs computed, the others read from "
                            "results/speed_accuracy)" if FORCED_RUNS else
                            " (every run read from results/speed_accuracy)"))
        elif name in ("map-linear", "map-gnl"):
            gnl = name == "map-gnl"
            maps, history = scene_map(gnl)
            held_out_map(maps, gnl)
            study["scenes"][name], study["scenes"][name.replace("map", "history")] = maps, history
            study["scenes"][name.replace("map", "stress")] = scene_stress(gnl, maps)
        elif name == "stability":
            study["stability"] = scene_stability()
        elif name == "paper-speedup":
            study["paper_speedup"] = scene_paper_speedup(study)
        elif name == "cost-r":
            study["cost_r"] = scene_cost_r()
            FRESH.append(f"scene cost-r {time.perf_counter() - t0:.0f} s")
        print(f"scene {name}: {time.perf_counter() - t0:.0f} s")
        record_choices(study)
        # the study's machine is the from-scratch run's; a scene measured elsewhere since says its own
        study.update(schema=1, machine=study.get("machine") if not fresh and "machine" in study
                     else machine_description(), command="python benchmarks/speed_accuracy.py",
                     tolerances=list(TOLERANCES))
        save_json(args.json, study, indent=1, default=_finite)
    for name, scene in study["scenes"].items():
        chart(name, scene)
    if "stability" in study:
        chart_stability(study["stability"])
    if "cost_r" in study:
        chart_cost_r(study["cost_r"])
    run = dict(scenes=list(todo), wall_s=time.perf_counter() - t_start, from_scratch=fresh)
    if FRESH and not fresh:
        run["note"] = PREFIX + ", ".join(FRESH)
    study.setdefault("runs", []).append(run)
    save_json(args.json, study, indent=1, default=_finite)
    write_docs(study)
    for name, scene in study["scenes"].items():
        print(name, {k: v.get("name") for k, v in scene["choices"].items()})
    return 0


if __name__ == "__main__":
    sys.exit(main())
