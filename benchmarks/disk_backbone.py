"""The backbone of the disk's travelling waves with GNL: how the frequency of the 1B family's wave of k nodal
diameters rises with its amplitude, and at which speed each engine-order line k Omega meets it (docs/results.md, the
full map with GNL: why its response rides EO6 from 1,200 to 1,520 rad/s).

For each k (``--diameters``), ``disk.harmonics.travelling_wave_backbone`` on the map's disk model (its exact sector
tensors, no casing, no damping) from the linear wave up to node LE of sector 0 at ``--le-max`` mm: per point the modal
amplitude, the frequency and its rise over the linear one, node LE's amplitude (max over a period of its normal
displacement along the casing's normal, ``--direction``), the speed Omega = omega / k where EO k meets the wave, and the
ansatz's defect (``travelling_wave_backbone``).

    python benchmarks/disk_backbone.py --model results/disk_map200/rom.npz [--diameters 4 6] [--le-max 0.8]
    python benchmarks/disk_backbone.py --replot --overlay results/bench_disk_map_reference.json

Results: results/disk_backbone.json and results/disk_backbone.png (node LE's amplitude against the speed where EO k
meets the wave, the points whose ansatz defect exceeds 1e-2 marked x; --overlay: the forced runs of
bench_disk_map.py). 3-6 min for the two default waves on this machine.

Every option is checked, and the model and the files read and the folder written in, before any work: a bad one is
one line on stderr and exit status 2. ``--check`` does only that (exit status 0); SIGTERM or SIGINT stop the run
with one line (``rotor37_rom.cli.run_main``).
"""
from __future__ import annotations

import json
import sys
import time
from pathlib import Path
from typing import Sequence

import numpy as np

from rotor37_rom.checks import before_work, readable_file, real_number, whole_number
from rotor37_rom.cli import ArgumentParser, run_main

DIRECTIONS = ("ex", "radial", "cone")
DEFECT = 1e-2          # points whose ansatz defect is larger are marked (x), not joined
MODEL = Path("results/disk_map200/rom.npz")      # the full-disk GNL map's model (benchmarks/bench_disk_map.py)
SAVED, CHART = Path("results/disk_backbone.json"), Path("results/disk_backbone.png")
DEFAULTS = {"diameters": [4, 6], "le_max": 0.8, "points": 16, "direction": "cone"}


def le_amplitude(Nm: np.ndarray, q: np.ndarray, k: int, omega: float) -> float:
    """Node LE of sector 0: max over a period of |its normal displacement| (m) for the wave whose snapshot is q."""
    from rotor37_rom.disk.harmonics import wave_history

    return float(np.abs(wave_history(Nm @ q, k, omega)).max())


def backbone(model, Nm: np.ndarray, k: int, le_max: float, points: int) -> tuple[list[dict], str]:
    """The wave of k nodal diameters from small amplitude to node LE at le_max (m), ``points`` steps at least (at
    most 4 x ``points``), and why it stopped."""
    from rotor37_rom.disk.harmonics import travelling_wave_backbone

    probe = travelling_wave_backbone(model, k, [1e-6])[0]
    per_a = le_amplitude(Nm, probe["q"], k, probe["omega"]) / probe["a"]      # linear: node LE per modal amplitude
    step = le_max / per_a / points
    rows = []

    def record(p: dict) -> bool:
        """One point found: its row, printed; True (stop) once node LE reaches le_max."""
        rows.append({"k": k, "a": p["a"], "omega": p["omega"], "omega_linear": p["omega_linear"],
                     "rise": p["omega"] / p["omega_linear"] - 1, "le0_m": le_amplitude(Nm, p["q"], k, p["omega"]),
                     "speed": p["omega"] / k, "defect": p["defect"], "steps": p["steps"]})
        print(f"k = {k}: a = {p['a']:.3g}, node LE {1e3 * rows[-1]['le0_m']:.3f} mm, omega {p['omega']:,.0f} rad/s "
              f"({rows[-1]['rise']:+.1%}), EO{k} at {p['omega'] / k:,.1f} rad/s, defect {p['defect']:.1e}",
              flush=True)
        return rows[-1]["le0_m"] >= le_max

    # one continuation from the probe (the secant predictor from its last two states), every step's amplitude a
    # target; it ends at le_max or after 4 x points
    try:
        travelling_wave_backbone(model, k, probe["a"] + step * np.arange(1, 4 * points + 1), start=[probe],
                                 callback=record)
    except ValueError as exc:                         # the continuation stopped (a fold, an internal resonance)
        print(f"k = {k}: {exc}")
        return rows, str(exc)
    if rows[-1]["le0_m"] < le_max:
        return rows, f"{4 * points} points"
    return rows, f"node LE reached {1e3 * le_max:g} mm"


def build_parser() -> ArgumentParser:
    p = ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--model", type=Path, default=None,
                   help=f"a disk map's reduced model (rom.npz, with its GNL tensors; default {MODEL}); not with "
                        f"--replot")
    p.add_argument("--diameters", type=int, nargs="+", default=None,
                   help="nodal diameters k of the waves, each in 1..(N - 1) // 2 for the model's N sectors (1..17 for "
                        "rotor 37; default 4 6); not with --replot")
    p.add_argument("--le-max", type=float, default=None,
                   help="node LE's largest amplitude (mm), in (0, 5] (default 0.8); not with --replot")
    p.add_argument("--points", type=int, default=None, help="points per backbone, 4..200 (default 16); not with "
                                                              "--replot")
    p.add_argument("--direction", choices=DIRECTIONS, default=None,
                   help="the contact normal node LE is along (default cone); not with --replot")
    p.add_argument("--overlay", type=Path,
                   help="results of bench_disk_map.py (bench_disk_map[_reference].json): its forced runs' node LE "
                        "drawn at their speeds")
    p.add_argument("--replot", action="store_true",
                   help=f"draw the chart again from {SAVED} (with --overlay) without computing")
    return p


def overlay_row(path: Path) -> dict:
    """The results row of bench_disk_map.py in ``path`` (ValueError naming --overlay for a file that is not one)."""
    readable_file("--overlay", path)
    try:
        row = json.loads(path.read_text())["rows"][0]
        if not (isinstance(row["responses"], dict) and isinstance(row["reference_speeds"], list)):
            raise TypeError(type(row).__name__)
    except (ValueError, KeyError, IndexError, TypeError, UnicodeDecodeError) as exc:
        raise ValueError(f"--overlay: {path} is not a results file of bench_disk_map.py (no rows with its reference "
                         f"speeds and responses: {type(exc).__name__})") from None
    return row


def saved_rows(path: Path) -> list[dict]:
    """The rows of an earlier run's results (``SAVED``), for --replot."""
    if not path.is_file():
        raise ValueError(f"--replot needs {path} (run without --replot first)")
    try:
        rows = json.loads(path.read_text())["rows"]
        if not all(isinstance(r, dict) and {"k", "speed", "le0_m", "defect"} <= r.keys() for r in rows):
            raise KeyError("k, speed, le0_m, defect")
    except (OSError, ValueError, KeyError, TypeError, UnicodeDecodeError) as exc:
        raise ValueError(f"--replot: {path} is not this command's results ({type(exc).__name__})") from None
    return rows


def check_options(args) -> dict | None:
    """Every option checked (ValueError naming it and its range), the defaults filled in; the saved model's kind
    (``studies.contact_config.saved_model_info``), None with --replot."""
    if args.replot:
        given = [name for name in ("model", *DEFAULTS) if getattr(args, name) is not None]
        if given:
            raise ValueError(f"--{given[0].replace('_', '-')} does nothing with --replot (the chart is drawn again "
                             f"from {SAVED})")
    for name, value in DEFAULTS.items():
        if getattr(args, name) is None:
            setattr(args, name, value)
    real_number("--le-max (node LE's largest amplitude)", args.le_max, 0, 5, open_low=True, unit=" mm")
    whole_number("--points", args.points, 4, 200)
    for k in args.diameters:
        whole_number("--diameters (nodal diameters of travelling waves)", k, 1)
    if args.overlay is not None:
        overlay_row(args.overlay)
    if args.replot:
        saved_rows(SAVED)
        return None
    from rotor37_rom.studies.contact_config import saved_model_info

    args.model = MODEL if args.model is None else args.model
    info = saved_model_info("--model", args.model)
    if not info["disk"] or info["forces"] == "none":
        raise ValueError(f"--model must be a disk model with its nonlinear forces (GNL): {args.model} is "
                         f"{'a single blade' if not info['disk'] else 'a linear disk'}'s (demos/contact_map.py --disk "
                         f"writes one in --out)")
    N = info["n_sectors"]
    bad = [k for k in args.diameters if not 0 < k < N / 2]
    if bad:
        raise ValueError(f"--diameters must be in 1..{(N - 1) // 2} (travelling waves of {N} sectors), got "
                         f"{' '.join(map(str, bad))}")
    if info["nodes"] and "LE" not in info["nodes"]:
        raise ValueError(f"--model: {args.model} has no node LE (the node the backbone follows): its nodes are "
                         f"{sorted(set(info['nodes']))}")
    return info


def main(argv: Sequence[str] | None = None) -> int:
    """Check the options, then the backbones and their chart (or the chart again); raises ValueError for a bad
    input."""
    args = build_parser().parse_args(argv)
    check_options(args)
    before_work({"the results folder": SAVED.parent})            # before any work; a dry run stops here
    overlay = overlay_row(args.overlay) if args.overlay is not None else None
    if args.replot:
        chart(saved_rows(SAVED), CHART, overlay)
        print(str(CHART))
        return 0
    from rotor37_rom.dynamics.casing import Casing, contact_matrices
    from rotor37_rom.machine import write_results
    from rotor37_rom.model.reduced import load_reduced_model

    model = load_reduced_model(args.model)
    N = model.nodes.n_sectors
    if model.sectors is None or model.forces is None:
        raise ValueError(f"--model must be a disk model with its nonlinear forces (GNL): {args.model}")
    Nm = contact_matrices(model.nodes, model.r, Casing(direction=args.direction),
                          rows=[model.nodes.row("LE", s) for s in range(N)])[0]
    Nm = Nm.toarray() if hasattr(Nm, "toarray") else np.asarray(Nm)
    rows, stops, t0 = [], {}, time.perf_counter()
    for k in args.diameters:
        found, stops[k] = backbone(model, Nm, k, 1e-3 * args.le_max, args.points)
        rows += found
    wall = time.perf_counter() - t0
    machine = write_results("disk_backbone", rows, model=str(args.model), model_key=model.key, r=model.r,
                            direction=args.direction, wall_s=wall, stopped=stops)
    chart(rows, CHART, overlay)
    print(f"{SAVED}, {CHART} ({wall:.0f} s; {machine})")
    return 0


def chart(rows: list[dict], path: Path, overlay: dict | None = None) -> None:
    """Node LE's amplitude against the speed Omega = omega / k where EO k meets each wave (the backbone drawn
    where a forced response's NFRC would run), the map's speed range shaded; ``overlay``: a bench_disk_map results
    row, its runs' node LE of sector 0 at its reference speeds."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.8, 4.2))
    ax.axvspan(1200, 1650, color="0.92", label="the map's speeds")
    for k in sorted({r["k"] for r in rows}):
        sel = [r for r in rows if r["k"] == k]
        good = [r for r in sel if r["defect"] <= DEFECT]
        line, = ax.plot([r["speed"] for r in good], [1e3 * r["le0_m"] for r in good], "o-", ms=3,
                        label=f"k = {k}: EO{k} meets the free wave")
        bad = [r for r in sel if r["defect"] > DEFECT]
        if bad:
            ax.plot([r["speed"] for r in bad], [1e3 * r["le0_m"] for r in bad], "x", color=line.get_color(),
                    label=f"k = {k}, ansatz defect > {DEFECT:g}")
    for (name, resp), marker in zip((overlay or {}).get("responses", {}).items(), "sD^v"):
        ax.plot(overlay["reference_speeds"], [1e3 * x for x in resp["le0_m"]], marker, mfc="none", ms=7,
                label=f"forced, {name}")
    ax.set_xlim(900, 2000)                           # the map's neighbourhood (the JSON holds the whole backbones)
    ax.set_ylim(0, None)
    ax.set_xlabel("Omega = omega / k (rad/s)")
    ax.set_ylabel("node LE of sector 0, amplitude (mm)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title("Backbones of the 1B family's travelling waves with GNL", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(run_main(main))
