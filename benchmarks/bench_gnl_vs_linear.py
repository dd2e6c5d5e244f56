"""GNL against linear in contact on equal footing (issue #23, item 2): zero-IC interaction maps and NFRC of one
reduced model with the geometric nonlinearity off and on, at friction coefficients where both stay bounded.

With the paper's contact normal e_x this blade's tip wedges into the casing by friction from mu ~ 0.17 (sprag-slip,
docs/results.md), and at mu = 0.15 about half of the map's speeds grow; the conical casing's own normal
(``--direction cone``) keeps every map bounded. Each friction value runs the project's map command, unchanged, on
the same reduced model with the same frequency cap for both settings (the linear model slowed above the cap exactly
as the GNL one):

    [mpirun -n RANKS] python demos/contact_map.py --model MODEL --gnl off|on|both --frequency-cap CAP --cubature 1e-4
        --precision single --mu MU --direction DIRECTION --speeds START STOP N --revolutions R
        --retry-diverged 2 --out results/gnl_vs_linear/<direction>_mu<MU>_<START>-<STOP>

(the GNL forces are the point cubature trained on exact GNL contact runs of that friction value, float32, as in
the GNL headline map). A killed run started again resumes. From each map's per-speed records this script takes,
GNL off and on: the speeds that grew past the limit after the retries, the largest response and its speed, the
1B/EO4 resonance (``studies.sweep.engine_order_resonance``) and its stiffening over omega_1/4 of the model, and at that
resonance the mechanism: the share of the last half of the run during which some tip node touches the casing, and
the work the normal and the friction forces did on the blade. Results to results/bench_gnl_vs_linear.json (rows of
earlier runs with other settings are kept), printed as Markdown (docs/results.md). Wall times are the maps' own
output (a rerun that finds every speed done takes seconds).

    python benchmarks/bench_gnl_vs_linear.py                  # mu = 0.15, 1200-2000 rad/s, 200 rev: 1-3 h on 2 cores
    python benchmarks/bench_gnl_vs_linear.py --mu 0 --gnl off    # the linear maps without friction: 4 min
    python benchmarks/bench_gnl_vs_linear.py --mu 0 0.05 0.1 0.15 # every friction value of issue #23 (4-12 h)
    python benchmarks/bench_gnl_vs_linear.py --global-md 10 --capped-training --speeds 1300 1600 4 --ranks 1
                                          # r = 104 (modal derivatives of 10 clamped modes) at 4 speeds
    python benchmarks/bench_gnl_vs_linear.py --mu 0.1 --gnl on --speeds 1620 2000 20 --step-outliers drop \
        --step-check 1820 1860 2          # the GNL step without a collapse state, two speeds checked at the full one

With ``--step-outliers drop`` the GNL step leaves out the few step states whose tangent frequency is far above the
others' (``dynamics.explicit.step_outliers``; St. Venant-Kirchhoff collapse states), and ``--step-check START STOP N``
runs those speeds of the map again at the step from every state, on the same cubature (OUT/step_check), and reports the
difference of the largest LE response. A speed of a drop map that still blows up after its retries (h/2, h/4: still
above the step from every state) is reported grown; run it with the step check before reading it so.

``--floor EPS`` runs the maps again with the internal forces scaled by 1 + EPS (``--perturbation``; the same cubature
and step, OUT/floor) and, with ``--step-check``, the checked speeds too (OUT/step_check_floor): a speed whose
response a 1e-4 perturbation moves by as much as the step does is one where any small change picks another
response, and the step's difference there says nothing of the step.

    python benchmarks/bench_gnl_vs_linear.py --mu 0.1 --gnl on --speeds 1620 2000 20 --step-outliers drop \
        --step-check 1960 1960 1 --floor 1e-4    # the floor of the map and of 1,960 rad/s at the full step

The r = 55 ci model is built (20 s) when --model is missing; another --global-md builds its own model and maps into
folders of their own, and each row says its model's r. Each cubature training takes 8-30 min (r = 55; about 1 h
with --global-md 10 --capped-training); the maps run on
--ranks ranks, the GNL step from each range's probe (1.2e-7 to 6.7e-7 s measured; 2.11e-8 s at mu = 0.1 over
1620-2000 rad/s, set by one collapse state: 3.96e-7 s with --step-outliers drop), which sets most of the time.

Every option is checked, and the model read (or its folder written in) and the folders written in, before any work:
a bad one is one line on stderr and exit status 2. ``--check`` does only that (exit status 0); SIGTERM or SIGINT stop
the run with one line (``rotor37_rom.cli.run_main``).
"""
from __future__ import annotations

import functools
import json
import subprocess
import sys
import time
from pathlib import Path
from typing import Sequence

import numpy as np

from rotor37_rom.checks import before_work, readable_file, real_number, whole_number
from rotor37_rom.cli import ArgumentParser, run_main
from rotor37_rom.machine import mpirun_env, write_results
from rotor37_rom.studies.gnl_vs_linear import check_speeds_error, grid_index, in_range, same_step

ROOT = Path(__file__).resolve().parent.parent
DEMO = ROOT / "demos" / "contact_map.py"
OUT = Path("results/gnl_vs_linear")
SETTINGS = {"off": (False,), "on": (True,), "both": (False, True)}
BUILD = {"preset": "ci", "r_c": 25, "global_md": 3}      # the model built when --model is missing
MAX_REVOLUTIONS = 1000.0
MAX_CAP = 1e4                    # kHz: the map command's (studies.contact_config.MapScheme)
MAX_BATCH = 1000
MAX_RANKS = 256


def map_command(args, mu: float, speeds: tuple, out: Path) -> list[str]:
    """The demo's command line of one friction value and speed range (under mpirun with more than one rank)."""
    extra = ["--step-outliers", args.step_outliers] if args.step_outliers != "keep" else []
    return demo_command(args, args.gnl, mu, speeds, out, extra)


def floor_command(args, mu: float, speeds: tuple, out: Path) -> list[str]:
    """The map of one speed range again with the internal forces scaled by 1 + args.floor, on its cubature and at
    its step, into OUT/floor."""
    extra = ["--step-outliers", args.step_outliers] if args.step_outliers != "keep" else []
    extra += ["--perturbation", f"{args.floor:g}", "--cache", str(out / "cache")]
    return demo_command(args, args.gnl, mu, speeds, out / "floor", extra)


def check_command(args, mu: float, speeds: tuple, check: tuple, out: Path, perturbation: float = 0.0
                  ) -> list[str]:
    """The demo's command line of the step check of one speed range: the GNL runs at the ``check`` speeds (START
    STOP N) again with the step from every state (--step-outliers keep), on the range's cubature (its cache and
    training speeds), into OUT/step_check (with a perturbation: OUT/step_check_floor)."""
    from rotor37_rom.dynamics.explicit import training_speeds

    train = training_speeds(np.linspace(speeds[0], speeds[1], int(speeds[2])))
    extra = ["--cubature-speeds", *[str(float(w)) for w in train], "--cache", str(out / "cache")]
    if perturbation:
        extra += ["--perturbation", f"{perturbation:g}"]
    return demo_command(args, "on", mu, check, out / ("step_check_floor" if perturbation else "step_check"), extra)


def run_name(cmd: list[str]) -> str:
    """'map', 'step check', 'floor' or 'step check, floor': which of a range's runs ``cmd`` is (its --out)."""
    out = Path(cmd[cmd.index("--out") + 1]).name
    return {"step_check": "step check", "floor": "floor", "step_check_floor": "step check, floor"}.get(out, "map")


def speed_arg(w: float) -> str:
    """A speed on the command line: '1620' for a whole number, else every digit (the demo's speeds, and the cubature's
    training speeds derived from them, are then the ones this script computes)."""
    return f"{w:g}" if float(w).is_integer() else repr(float(w))


def demo_command(args, gnl: str, mu: float, speeds: tuple, out: Path, extra: list[str]) -> list[str]:
    """demos/contact_map.py with the benchmark's settings, under mpirun with --ranks ranks (more than one)."""
    start, stop, n = speeds
    cmd = [sys.executable, str(DEMO), "--model", str(args.model), "--gnl", gnl,
           "--frequency-cap", f"{args.cap:g}", "--cubature", f"{args.cubature:g}", "--precision", "single",
           "--mu", f"{mu:g}", "--direction", args.direction, "--speeds", speed_arg(start), speed_arg(stop), f"{int(n)}",
           "--revolutions", f"{args.revolutions:g}", "--retry-diverged", "2", "--batch", f"{args.batch}",
           "--out", str(out), "--quiet"] + extra
    if args.capped_training:
        cmd.append("--capped-training")
    if args.ranks > 1:
        cmd = ["mpirun", "-n", str(args.ranks)] + cmd
    return cmd


def contact_share(record: dict) -> float:
    """Share of the last half of a run's records during which some contact node carries a multiplier."""
    lam = np.asarray(record["lam"])
    half = lam[:, lam.shape[1] // 2:]
    return float(np.mean(np.any(half > 0.0, axis=0)))


@functools.lru_cache(maxsize=None)
def setting_records(folder: Path, gnl: bool, revolutions: float, every: bool = False) -> tuple[dict, dict | None]:
    """({speed: per-speed record}, summary.json entry) of one setting (GNL off or on) of the map in ``folder``: the
    speeds of its last run, or with ``every`` all those its sweeps at that step hold (step checks run one after
    another); ({}, None) when the folder has no map of that setting. Only sweeps of the entry's model (a map run
    again with another --perturbation writes beside it at the same step). Read once per process (``map_row`` and
    ``step_check`` both ask), after the maps have run; callers do not modify what it returns."""
    from rotor37_rom.studies.sweep import load_sweep

    summary = json.loads((folder / "summary.json").read_text())
    entry = next((v for k, v in summary["runs"].items() if k.startswith("GNL") == gnl), None)
    if entry is None:
        return {}, None
    records = {}
    for sweep in sorted((folder / "sweeps").iterdir()):
        spec = json.loads((sweep / "spec.json").read_text())
        if bool(spec["nonlinear"]) != gnl or float(spec["spec"]["revolutions"]) != revolutions \
                or not same_step(entry["h"], float(spec["h"])) \
                or ("model_key" in entry and spec.get("model") != entry["model_key"]):
            continue
        for rec in load_sweep(sweep):                  # the retries' records replace the first run's
            if int(rec["diverged_step"]) < 0 or float(rec["omega"]) not in records:
                records[float(rec["omega"])] = rec
    return (dict(sorted(records.items())) if every else {w: records[w] for w in entry["speeds"]}), entry


def step_check(folder: Path, revolutions: float) -> list[dict]:
    """The GNL map in ``folder`` (run with --step-outliers drop) against its speeds run again in folder/step_check
    at the step from every state: per speed, the largest LE response of both (mm), their relative difference and
    both steps; with the floor runs (folder/floor, folder/step_check_floor), both responses perturbed too."""
    from rotor37_rom.studies.sweep import interaction_map

    runs = [setting_records(folder, True, revolutions), setting_records(folder / "step_check", True, revolutions,
                                                                         every=True)]
    (dropped, entry), (kept, entry_kept) = runs
    if entry is None or entry_kept is None:
        return []
    grid = list(dropped)
    pairs = [(w, grid[i]) for w in kept if (i := grid_index(grid, w)) is not None]   # (check speed, map speed)
    if not pairs:
        return []
    amp = [interaction_map([recs[w] for w in ws]).nfrc * 1e3 for recs, ws in ((dropped, [p[1] for p in pairs]),
                                                                            (kept, [p[0] for p in pairs]))]
    checks = [{"speed": w, "mm_dropped": float(a), "mm_kept": float(b), "rel": float(a / b - 1.0),
               "h_dropped": entry["h"], "h_kept": entry_kept["h"]} for (_, w), a, b in zip(pairs, *amp)]
    for name, key, ws in (("floor", "mm_dropped_perturbed", [p[1] for p in pairs]),
                          ("step_check_floor", "mm_kept_perturbed", [p[0] for p in pairs])):
        if (folder / name / "summary.json").is_file():
            records = setting_records(folder / name, True, revolutions, every=True)[0]
            speeds = list(records)
            for check, w in zip(checks, ws):
                hit = grid_index(speeds, w)
                check[key] = None if hit is None else float(interaction_map([records[speeds[hit]]]).nfrc[0] * 1e3)
    return checks


def floor_row(folders: list[Path], gnl: bool, revolutions: float) -> dict | None:
    """The maps of ``folders`` run again perturbed (folder/floor): their perturbation, speeds and NFRC (mm), and the
    1B/EO4 resonance of the perturbed map (rad/s), or None when none was run."""
    from rotor37_rom.studies.sweep import engine_order_resonance, interaction_map

    records, eps = {}, set()
    for folder in folders:
        if not (folder / "floor" / "summary.json").is_file():
            continue
        recs, entry = setting_records(folder / "floor", gnl, revolutions)
        if entry is not None:
            eps.add(entry.get("perturbation"))
            records.update(recs)
    if not records:
        return None
    imap = interaction_map([records[w] for w in sorted(records)])
    return {"perturbation": sorted(eps, key=str), "speeds": sorted(records), "nfrc_mm": (imap.nfrc * 1e3).tolist(),
            "resonance": engine_order_resonance(imap, 4, revolutions)}


def map_row(folders: list[Path], mu: float, gnl: bool, revolutions: float, quarter_omega1: float) -> dict:
    """One setting (GNL off or on) over the speed ranges of ``folders``: speeds grown past the limit, the largest
    response, the 1B/EO4 resonance and the contact mechanism there."""
    from rotor37_rom.studies.sweep import engine_order_resonance, interaction_map

    records, entries = {}, []
    for folder in folders:
        recs, entry = setting_records(folder, gnl, revolutions)
        records.update(recs)
        entries.append(entry)
    speeds = np.array(sorted(records))
    recs = [records[w] for w in speeds]
    imap = interaction_map(recs)
    resonance = engine_order_resonance(imap, 4, revolutions)
    at = recs[int(np.argmin(np.abs(speeds - resonance)))] if np.isfinite(resonance) else None
    work = np.asarray(at["work"], float) if at is not None else np.full(4, np.nan)
    bounded = ~imap.diverged
    checks = [e["contact_checks"] for e in entries]
    return {
        "mu": mu, "gnl": gnl, "h": [e["h"] for e in entries],
        "speeds_grown": speeds[imap.diverged].tolist(), "n_speeds": len(speeds),
        "peak_speed": float(speeds[bounded][np.nanargmax(imap.nfrc[bounded])]) if bounded.any() else None,
        "peak_mm": float(np.nanmax(imap.nfrc) * 1e3) if bounded.any() else None,
        "resonance": resonance, "stiffening_pct": 100.0 * (resonance / quarter_omega1 - 1.0),
        "resonance_mm": float(imap.nfrc[speeds == resonance][0] * 1e3) if at is not None else None,
        "contact_share": contact_share(at) if at is not None else None,
        "work_normal_J_per_rev": float(work[0] / revolutions),
        "work_friction_J_per_rev": float(work[1] / revolutions),
        "max_penetration": max(c["max_penetration"] for c in checks),
        "min_multiplier": min(c["min_multiplier"] for c in checks),
        "max_friction_power": max(c["max_friction_power"] for c in checks),
        "nfrc_mm": (imap.nfrc * 1e3).tolist(), "speeds": speeds.tolist()}


def earlier_rows(rows: list[dict]) -> list[dict]:
    """The rows of results/bench_gnl_vs_linear.json that ``rows`` do not replace (another model size, friction value,
    setting, normal or training, e.g. from a run with --gnl off only), so that the file collects every run. A row
    written before rows carried their model's r is the file's model's; one written before --capped-training was
    trained unscaled; a GNL row written before --step-outliers took its step from every state."""
    path = Path("results/bench_gnl_vs_linear.json")
    if not path.is_file():
        return []
    key = ("r", "mu", "gnl", "direction", "speeds", "capped_training", "step_outliers")
    new = {tuple(json.dumps(r[k]) for k in key) for r in rows}
    stored = json.loads(path.read_text())
    old = [{"r": stored["model"]["r"], "capped_training": False, "step_outliers": "keep" if r["gnl"] else None} | r
           for r in stored["rows"]]
    return [r for r in old if tuple(json.dumps(r.get(k)) for k in key) not in new]


def gnl_label(row: dict) -> str:
    """'off', 'on', 'on, capped training' (the cubature trained on capped runs), '…, step outliers dropped'."""
    if not row["gnl"]:
        return "off"
    return "on" + (", capped training" if row.get("capped_training") else "") \
        + (", step outliers dropped" if row.get("step_outliers") == "drop" else "")


def markdown(rows: list[dict], quarter_omega1: float) -> str:
    def f(x, fmt):
        return "–" if x is None or not np.isfinite(x) else format(x, fmt)

    lines = [f"| r | μ | GNL | grown (of N) | largest response | 1B/EO4 resonance (stiffening over ω₁/4 = "
             f"{quarter_omega1:.0f}) | LE there | time in contact there | normal / friction work there (J/rev) |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(
            f"| {r['r']} | {r['mu']:g} | {gnl_label(r)} | {len(r['speeds_grown'])} of {r['n_speeds']} | "
            f"{f(r['peak_mm'], '.2f')} mm at {f(r['peak_speed'], '.0f')} | {f(r['resonance'], '.0f')} rad/s "
            f"({f(r['stiffening_pct'], '+.1f')} %) | {f(r['resonance_mm'], '.2f')} mm | "
            f"{f(None if r['contact_share'] is None else 100 * r['contact_share'], '.1f')} % | "
            f"{f(r['work_normal_J_per_rev'], '.3f')} / {f(r['work_friction_J_per_rev'], '.3f')} |")
    checks = [(r, c) for r in rows for c in r.get("step_check", [])]
    if checks:
        lines += ["", "| r | μ | Ω (rad/s) | LE, step without the outliers | LE, step from every state | "
                      "difference |", "|---|---|---|---|---|---|"]
        lines += [f"| {r['r']} | {r['mu']:g} | {c['speed']:.0f} | {c['mm_dropped']:.3f} mm (h = {c['h_dropped']:.3g} "
                  f"s) | {c['mm_kept']:.3f} mm (h = {c['h_kept']:.3g} s) | {100 * c['rel']:+.1f} % |"
                  for r, c in checks]
    perturbed = [(r, c) for r, c in checks if c.get("mm_dropped_perturbed") is not None
                 or c.get("mm_kept_perturbed") is not None]
    if perturbed:
        lines += ["", "| r | μ | Ω (rad/s) | step without the outliers: LE, perturbed | step from every state: LE, "
                      "perturbed |", "|---|---|---|---|---|"]
        lines += [f"| {r['r']} | {r['mu']:g} | {c['speed']:.0f} | {c['mm_dropped']:.3f}, "
                  f"{f(c.get('mm_dropped_perturbed'), '.3f')} mm | {c['mm_kept']:.3f}, "
                  f"{f(c.get('mm_kept_perturbed'), '.3f')} mm |" for r, c in perturbed]
    floors = [r for r in rows if r.get("floor")]
    for r in floors:
        fl = r["floor"]
        peak = np.nanmax(r["nfrc_mm"])
        moved = [f"{w:.0f}: {100 * abs(b - r['nfrc_mm'][i]) / peak:.1f} %"
                 for w, b in zip(fl["speeds"], fl["nfrc_mm"]) if (i := grid_index(r["speeds"], w)) is not None]
        eps = ", ".join(f"{e:g}" for e in fl["perturbation"] if e is not None)
        lines += ["", f"r = {r['r']}, μ = {r['mu']:g}, GNL {gnl_label(r)}: x (1 + {eps}) moves the "
                      f"NFRC by (of its peak {peak:.3f} mm) " + ", ".join(moved)
                  + f"; 1B/EO4 resonance {f(fl.get('resonance'), '.0f')} rad/s perturbed, "
                    f"{f(r['resonance'], '.0f')} not"]
    return "\n".join(lines)


def build_model(path: Path, preset: str, r_c: int, global_md: int) -> None:
    """The reduced model the maps share, built as the map command builds it (24 tip DOFs, r_c fixed-interface modes,
    the modal derivatives of the first ``global_md`` clamped modes (3: 1B, 1T, 2B), exact cubic tensors), saved to
    ``path``."""
    from rotor37_rom.model.reduced import save_reduced_model
    from rotor37_rom.studies import contact_map

    model = contact_map.build_model(contact_map.ContactMapConfig.from_options(preset=preset, r_c=r_c,
                                                                              global_md=global_md, out=OUT))
    path.parent.mkdir(parents=True, exist_ok=True)
    save_reduced_model(model, path)


def nfrc_chart(rows: list[dict], direction: str, quarter_omega1: float) -> Path:
    """The NFRC of every row with this normal, one curve per friction value and setting, with the paper's zero-IC
    resonances; results/gnl_vs_linear/nfrc_<direction>.png."""
    from rotor37_rom.viz.charts import plot_nfrc

    curves = {f"r = {r['r']}, mu = {r['mu']:g}, GNL {gnl_label(r)}, {r['speeds'][0]:g}-{r['speeds'][-1]:g} rad/s":
              (r["speeds"], np.asarray(r["nfrc_mm"], float) * 1e-3, "o-" if r["gnl"] else "s--")
              for r in sorted(rows, key=lambda r: (r["r"], r["mu"], r["gnl"])) if r["direction"] == direction}
    return plot_nfrc(curves, OUT / f"nfrc_{direction}.png", linear_resonance=quarter_omega1,
                     paper={"paper zero IC, no GNL": 1446.0, "paper zero IC, GNL": 1535.0})


def build_parser() -> ArgumentParser:
    from rotor37_rom.reduction.craig_bampton import GLOBAL_MD_MAX
    from rotor37_rom.studies.contact_config import MAX_MAP_SPEEDS, MAX_SPEED

    p = ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--model", type=Path,
                   help="reduced model (.npz, a blade's); built when missing (default results/gnl_vs_linear/rom.npz, "
                        "rom_g<N>.npz with --global-md N other than 3)")
    p.add_argument("--preset", choices=["ci", "coarse", "paper"], default=None,
                   help="mesh preset of the model built (default ci); only when the model is built")
    p.add_argument("--r-c", type=int, default=None,
                   help="fixed-interface modes of the model built, >= 1 (default 25); only when the model is built")
    p.add_argument("--global-md", type=int, default=None,
                   help=f"modal derivatives of the first N clamped modes in the model built, 0..{GLOBAL_MD_MAX} "
                        f"(default 3: the maps' r = 55; 10: r = 104, the basis nearest the full order in contact); "
                        f"only when the model is built")
    p.add_argument("--capped-training", action="store_true",
                   help="the cubature's training runs at the frequency cap (demos/contact_map.py --capped-training; "
                        "for --global-md 10, whose unscaled exact runs take hours); needs GNL maps (--gnl on or both)")
    p.add_argument("--mu", type=float, nargs="+", default=[0.15],
                   help="friction coefficients, each in [0, 2] (default 0.15)")
    p.add_argument("--direction", choices=["x", "radial", "cone"], default="cone",
                   help="the casing's contact normal (default cone)")
    p.add_argument("--gnl", choices=list(SETTINGS), default="both", help="maps with GNL off, on or both (default both)")
    p.add_argument("--speeds", type=float, nargs="+", default=[1200.0, 1600.0, 21, 1620.0, 2000.0, 20],
                   metavar="START STOP N",
                   help=f"one or more speed ranges, each a map of its own (its own cubature, trained at its speeds): "
                        f"0 < START <= STOP <= {MAX_SPEED:g} rad/s, N in 1..{MAX_MAP_SPEEDS}; default 1200-1600 x 21 "
                        f"and 1620-2000 x 20")
    p.add_argument("--revolutions", type=float, default=200.0,
                   help=f"revolutions per speed, in (0, {MAX_REVOLUTIONS:g}] and within this machine's memory "
                        f"(default 200)")
    p.add_argument("--cap", type=float, default=120.0,
                   help=f"frequency cap of both settings (kHz), in (0, {MAX_CAP:g}] (default 120)")
    p.add_argument("--cubature", type=float, default=None,
                   help="tolerance of the GNL point cubature, in (0, 1) (default 1e-4); needs GNL maps")
    p.add_argument("--batch", type=int, default=11,
                   help=f"speeds integrated together per rank, 1..{MAX_BATCH} (default 11)")
    p.add_argument("--ranks", type=int, default=2, help=f"MPI ranks of the maps, 1..{MAX_RANKS} (1: serial; default 2)")
    p.add_argument("--step-outliers", choices=["keep", "drop"], default=None,
                   help="the GNL maps' step from every state (keep, the default) or without the few collapse states "
                        "far above the others (drop; demos/contact_map.py --step-outliers); needs GNL maps")
    p.add_argument("--floor", type=float, metavar="EPS",
                   help="run the maps (and the --step-check speeds) again with the internal forces scaled by "
                        "1 + EPS, 0 < |EPS| < 0.01, on the same cubature and step: the speeds a perturbation that "
                        "small moves (OUT/floor, OUT/step_check_floor)")
    p.add_argument("--step-check", type=float, nargs=3, metavar=("START", "STOP", "N"),
                   help="with --step-outliers drop: run these speeds of the GNL map again at the step from "
                        "every state and compare (each speed one of a range's)")
    return p


def check_options(args) -> list[tuple]:
    """Every option checked (ValueError naming it and its range), the defaults of those that need another filled
    in; the speed ranges (START, STOP, N). The model is checked by ``check_model``."""
    from rotor37_rom.reduction.craig_bampton import GLOBAL_MD_MAX
    from rotor37_rom.studies.contact_config import MAX_MAP_SPEEDS, MAX_SPEED

    for mu in args.mu:
        real_number("--mu (friction coefficients)", mu, 0, 2)
    if len(args.speeds) % 3:
        raise ValueError(f"--speeds takes START STOP N per range, got {len(args.speeds)} numbers")
    ranges = [tuple(args.speeds[i:i + 3]) for i in range(0, len(args.speeds), 3)]
    for start, stop, n in ranges:
        for value in (start, stop, n):
            real_number("--speeds (START, STOP, N)", value, 0, MAX_SPEED, open_low=True)
        if not (start <= stop and float(n).is_integer() and 1 <= n <= MAX_MAP_SPEEDS):
            raise ValueError(f"--speeds: each range needs 0 < START <= STOP <= {MAX_SPEED:g} rad/s and an integer N "
                             f"in 1..{MAX_MAP_SPEEDS}, got {start:g} {stop:g} {n:g}")
    real_number("--revolutions", args.revolutions, 0, MAX_REVOLUTIONS, open_low=True)
    real_number("--cap (the frequency cap)", args.cap, 0, MAX_CAP, open_low=True, unit=" kHz")
    whole_number("--batch", args.batch, 1, MAX_BATCH)
    whole_number("--ranks", args.ranks, 1, MAX_RANKS)
    if args.global_md is not None:
        whole_number("--global-md", args.global_md, 0, GLOBAL_MD_MAX)
    if args.r_c is not None:
        whole_number("--r-c", args.r_c, 1)
    gnl = args.gnl != "off"
    for option, given in (("--cubature", args.cubature is not None), ("--step-outliers", args.step_outliers),
                          ("--capped-training", args.capped_training)):
        if given and not gnl:
            raise ValueError(f"{option} shapes the GNL maps: it does nothing with --gnl off")
    args.cubature = 1e-4 if args.cubature is None else args.cubature
    args.step_outliers = "keep" if args.step_outliers is None else args.step_outliers
    real_number("--cubature (its tolerance)", args.cubature, 0, 1, open_low=True, open_high=True)
    if args.floor is not None:
        real_number("--floor (the perturbation EPS)", args.floor, -0.01, 0.01, open_low=True, open_high=True)
        if args.floor == 0:
            raise ValueError("--floor must be a perturbation with 0 < |EPS| < 0.01, got 0")
    if args.step_check is not None:
        for value in args.step_check:
            real_number("--step-check (START, STOP, N)", value, 0, MAX_SPEED, open_low=True)
        error = check_speeds_error(args, ranges)
        if error:
            raise ValueError(f"--step-check: {error}")
    return ranges


def check_model(args) -> dict:
    """The model the maps share: a saved blade's model read as it is (the options that build one refused), or the
    one to build (its options checked, its folder written in before any work). {option: folder} of before_work."""
    from rotor37_rom.studies.contact_config import ContactMapConfig, saved_model_info

    given = {name: getattr(args, name) for name in BUILD if getattr(args, name) is not None}
    explicit = args.model is not None
    if args.model is None:
        global_md = given.get("global_md", BUILD["global_md"])
        args.model = OUT / ("rom.npz" if global_md == 3 else f"rom_g{global_md}.npz")
    if args.model.exists():
        readable_file("--model", args.model)
        info = saved_model_info("--model", args.model)
        if info["disk"]:
            raise ValueError(f"--model: {args.model} is a bladed disk's model; the maps are the blade's")
        idle = [n for n in given if explicit or n != "global_md"]      # --global-md names the default model
        if idle:
            raise ValueError(f"--{idle[0].replace('_', '-')} builds the model: {args.model} exists and is read as it "
                             f"is (give another --model to build one)")
        folders = {}
    else:
        if str(args.model).strip() == "" or args.model.suffix != ".npz":
            raise ValueError(f"--model must be a reduced model's file (.npz), got {str(args.model)!r}")
        folders = {"--model (the folder of the model built)": args.model.parent}
    for name, value in BUILD.items():
        setattr(args, name, given.get(name, value))
    if not args.model.exists():                     # the model built: its options, as the map command checks them
        ContactMapConfig.from_options(preset=args.preset, r_c=args.r_c, global_md=args.global_md, out=OUT)
    return folders


def check_maps(args, ranges: list[tuple]) -> None:
    """Each map command's options as demos/contact_map.py checks them (its memory too): ValueError naming this
    command's option."""
    from rotor37_rom.studies.contact_config import ContactMapConfig

    for mu in args.mu:
        for speeds in ranges:
            try:
                ContactMapConfig.from_options(
                    model=args.model, gnl=args.gnl, frequency_cap=args.cap, cubature=args.cubature,
                    precision="single", mu=mu, direction=args.direction, speeds=speeds, revolutions=args.revolutions,
                    retry_diverged=2, batch=args.batch, out=OUT, quiet=True, step_outliers=args.step_outliers,
                    capped_training=args.capped_training, perturbation=args.floor or 0.0)
            except ValueError as exc:
                raise ValueError(str(exc).replace("--frequency-cap", "--cap").replace("--perturbation", "--floor")
                                 ) from None


def main(argv: Sequence[str] | None = None) -> int:
    """Check the options and the model, then the maps (demos/contact_map.py), their rows and the charts; raises
    ValueError for a bad input."""
    args = build_parser().parse_args(argv)
    ranges = check_options(args)
    folders = check_model(args)
    check_maps(args, ranges)
    before_work(folders | {"the maps' folder": OUT, "the results folder": Path("results")})   # a dry run stops here

    from rotor37_rom.model.reduced import load_reduced_model
    from rotor37_rom.studies import contact_map

    if not args.model.is_file():
        build_model(args.model, args.preset, args.r_c, args.global_md)
    model = load_reduced_model(args.model)
    quarter_omega1 = float(contact_map.eigenfrequencies(model)[0]) / 4
    env = mpirun_env(OPENBLAS_NUM_THREADS="1") if args.ranks > 1 else None    # one BLAS thread per rank
    rows, commands = [], []
    # the maps' r = 55 trained unscaled keeps its folders; another model or training its own
    tag = ("" if args.model == OUT / "rom.npz" else f"{args.model.stem}_") + ("capped_" if args.capped_training else "")
    for mu in args.mu:
        folders = []
        for speeds in ranges:
            out = OUT / f"{tag}{args.direction}_mu{mu:g}_{speeds[0]:g}-{speeds[1]:g}"
            cmds = [map_command(args, mu, speeds, out)]
            checked = args.step_check is not None and in_range(args.step_check, speeds)
            if checked:
                cmds.append(check_command(args, mu, speeds, tuple(args.step_check), out))
            if args.floor is not None:
                cmds.append(floor_command(args, mu, speeds, out))
                if checked:
                    cmds.append(check_command(args, mu, speeds, tuple(args.step_check), out, args.floor))
            for cmd in cmds:
                commands.append(" ".join(str(c) for c in cmd))
                t0 = time.perf_counter()
                done = subprocess.run(cmd, env=env, cwd=Path.cwd())
                if done.returncode != 0:
                    print(f"the map at mu = {mu:g} failed (exit {done.returncode}): {commands[-1]}", file=sys.stderr)
                    return 1
                print(f"mu = {mu:g}, {speeds[0]:g}-{speeds[1]:g} rad/s ({run_name(cmd)}): "
                      f"{time.perf_counter() - t0:.0f} s")
            folders.append(out)
        for gnl in SETTINGS[args.gnl]:
            row = map_row(folders, mu, gnl, args.revolutions, quarter_omega1)
            row |= {"direction": args.direction, "r": model.r, "capped_training": args.capped_training and gnl,
                    "step_outliers": args.step_outliers if gnl else None}
            row["floor"] = floor_row(folders, gnl, args.revolutions)   # by this or earlier calls
            if gnl and args.step_outliers == "drop":                 # the checks run so far, by this or earlier calls
                row["step_check"] = [c for f in folders if (f / "step_check" / "summary.json").is_file()
                                     for c in step_check(f, args.revolutions)]
            rows.append(row)
    rows = earlier_rows(rows) + rows
    machine = write_results("bench_gnl_vs_linear", rows, model={"file": str(args.model), "r": model.r,
                            "sizes": model.sizes, "quarter_omega1": quarter_omega1},
                            settings={k: (str(v) if isinstance(v, Path) else v) for k, v in vars(args).items()},
                            commands=commands)
    chart = nfrc_chart(rows, args.direction, quarter_omega1)
    print(f"{machine}; model r = {model.r} {model.sizes}, {args.direction} normal, {args.revolutions:g} revolutions; "
          f"NFRC chart {chart}")
    print(markdown(sorted(rows, key=lambda r: (r["direction"], r["r"], r["mu"], r["gnl"])), quarter_omega1))
    return 0


if __name__ == "__main__":
    sys.exit(run_main(main))
