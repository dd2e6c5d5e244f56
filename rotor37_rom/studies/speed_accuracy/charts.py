"""The study's charts (docs/img/speed_accuracy_<scene>.png): per scene the error against the cost with the Pareto
front, the stable step against the amplitude, and the cost per simulation-step against r."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from rotor37_rom.studies.speed_accuracy.context import TOLERANCES

__all__ = ["chart", "chart_stability", "chart_cost_r", "write_charts"]


def chart(img: Path, name: str, scene: dict) -> Path:
    """One scene's error against cost, the Pareto front joined, the tolerances and the scene's floor drawn."""
    from rotor37_rom.viz.charts import plot_speed_accuracy
    from rotor37_rom.studies.model_choice import scene_floor

    rows = [(c["name"], c["cost"], c["error"]) for c in scene["candidates"] if c["cost"] > 0]
    return plot_speed_accuracy(rows, img / f"speed_accuracy_{name}.png",
                               title=f"{name}: error against cost (Pareto front joined)",
                               cost_label=scene["cost_unit"], tolerances=TOLERANCES,
                               floor=scene_floor(scene),
                               reference=(f"the full order ({scene['reference']['cost']:.3g} s)",
                                          scene["reference"]["cost"]) if "cost" in scene["reference"] else None)


def chart_stability(img: Path, stab: dict) -> Path:
    """The stable step against the static LE displacement, GNL and linear, per cap."""
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
    return _save(fig, img / "speed_accuracy_stability.png")


def chart_cost_r(img: Path, cost_r: dict) -> Path:
    """The cost per simulation-step against r per force method, with the trained cubatures as stars."""
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
    return _save(fig, img / "speed_accuracy_cost_r.png")


def write_charts(img: Path, study: dict) -> list[Path]:
    """Every chart of the study file: one per scene, then the stability and cost-against-r tables' if present."""
    files = [chart(img, name, scene) for name, scene in study["scenes"].items()]
    if "stability" in study:
        files.append(chart_stability(img, study["stability"]))
    if "cost_r" in study:
        files.append(chart_cost_r(img, study["cost_r"]))
    return files
