"""The blade's interaction map turning and at rest, side by side (#73; demos/turning_map.py):
``run_turning_comparison(ContactMapConfig)``.

The same reduced model (the turning one: its basis holds the centrifugal states and the turning modes,
``ReductionConfig.spin_snapshots``) runs the configuration's map twice, each speed from the blade's state there: turning
(``dynamics.turning``: centrifugal prestress and spin softening; GNL off, the blade linearised about its centrifugal
state) and at rest, the paper's. What the rotation changes is then the map's alone: the resonance peaks move with the
prestressed 1B, the clearance is measured from the running or the resting blade. The Campbell diagram of the reduced
model (its prestressed, spin-softened modes over 0 ... the model's top speed, the engine orders) carries the linear
1B/EO4 crossing and, over it, each map's largest response as the engine-order-4 point it is (speed, 4 x speed): the
contact-stiffened resonance against the linear one. The cost per speed of each map turning against at rest is the
ratio of their integration times in this one run (same speeds, revolutions and machine).
"""
from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import scipy.linalg

from rotor37_rom.model.campbell import engine_order_crossings, track_modes
from rotor37_rom.model.reduced import ReducedModel, load_reduced_model
from rotor37_rom.model.rotating import centrifugal_equilibrium, rotating_stiffness
from rotor37_rom.npz import save_json
from rotor37_rom.studies.campbell import CampbellResult
from rotor37_rom.studies.contact_map import ContactMapConfig, ContactMapResult, run_contact_map
from rotor37_rom.viz.charts import plot_campbell

if TYPE_CHECKING:
    from mpi4py import MPI

__all__ = ["TurningComparison", "run_turning_comparison", "reduced_campbell", "ENGINE_ORDER"]

ENGINE_ORDER = 4          # the two-lobe casing's bumps pass a blade twice a revolution: 1B meets EO4 in the maps


@dataclasses.dataclass(frozen=True)
class TurningComparison:
    """What ``run_turning_comparison`` produced (rank 0; the other ranks get the maps' own results only).

    Attributes:
        turning, rest: the two maps (``ContactMapResult``), in the same output folder (summary.json and nfrc.png
            hold both).
        campbell: the reduced model's Campbell diagram (``CampbellResult``, modes 1-3) with its crossings.
        peaks: {run label: (speed of largest response (rad/s), its EO4 frequency (rad/s))}.
        cost: {GNL setting ('no GNL' or 'GNL'): {'rest_s', 'turning_s' (integration seconds per speed), 'ratio',
            'rest_h', 'turning_h' (steps, s)}}.
        files: the Campbell chart and turning_comparison.json.
    """

    turning: ContactMapResult
    rest: ContactMapResult
    campbell: CampbellResult | None
    peaks: dict
    cost: dict
    files: list


def reduced_campbell(model: ReducedModel, n_speeds: int = 21, n_modes: int = 3, orders=range(1, 9)) -> CampbellResult:
    """The turning reduced model's Campbell diagram: at each of ``n_speeds`` speeds over 0 ... its top speed, the
    modes of the prestressed, spin-softened tangent K + dg/dq(q_c) - Omega^2 M_P about the centrifugal state
    (``model.rotating``), followed by shape (``model.campbell.track_modes``), their crossings with ``orders``
    interpolated on the grid (``engine_order_crossings``)."""
    speeds = np.linspace(0.0, model.rotation.top_speed, n_speeds)
    M = 0.5 * (model.M + model.M.T)
    frequencies, shapes = [], []
    for w in speeds:
        lam, V = scipy.linalg.eigh(rotating_stiffness(model, w, centrifugal_equilibrium(model, w)), M,
                                   subset_by_index=[0, n_modes - 1])
        frequencies.append(np.sqrt(np.maximum(lam, 0.0)))
        shapes.append(V)
    omega, macs = track_modes(frequencies, shapes)
    labels = [f"mode {k + 1}" for k in range(n_modes)]
    crossings = [dict(c, label=labels[c["mode"]]) for c in engine_order_crossings(speeds, omega, list(orders))]
    return CampbellResult(speeds=speeds, omega=omega, labels=labels, mac=macs, crossings=crossings, wall_s=0.0)


def _cost(rest: dict, turning: dict) -> dict:
    """Integration seconds per speed of a map at rest and turning, their ratio and steps (summary.json entries)."""
    per_speed = [run["compute_s"] / len(run["speeds"]) if run.get("compute_s") else None for run in (rest, turning)]
    ratio = per_speed[1] / per_speed[0] if None not in per_speed else None
    return {"rest_s": per_speed[0], "turning_s": per_speed[1], "ratio": ratio, "rest_h": rest["h"],
            "turning_h": turning["h"]}


def run_turning_comparison(config: ContactMapConfig, comm: MPI.Comm | None = None) -> TurningComparison:
    """Run ``config``'s map turning (its ``scheme.rotation``) and at rest on the same turning model (built by the
    turning map, or ``config.rom.path``), then the Campbell diagram with the maps' peaks and the cost ratios.
    ValueError without ``--rotation`` (what would turn)."""
    if config.scheme.rotation is None:
        raise ValueError("--rotation: the comparison needs the clearance's reference of the turning map (running or "
                         "rest)")
    turning = run_contact_map(config, comm)
    path = config.rom.path if config.rom.path is not None else config.out / "rom.npz"
    rest = run_contact_map(config.with_options(rotation=None, model=path, mesh=None, contact_patch=0.0), comm)
    if comm is not None and comm.rank != 0:
        return TurningComparison(turning, rest, None, {}, {}, [])
    model = load_reduced_model(path)
    campbell = reduced_campbell(model)
    runs = {**rest.summary["runs"], **turning.summary["runs"]}
    mine = [label for label in runs if label in turning.runs or label in rest.runs]
    peaks = {label: (runs[label]["peak_speed"], ENGINE_ORDER * runs[label]["peak_speed"]) for label in mine}
    cost = {}
    for label_t in turning.runs:
        label_r = next(label for label in rest.runs if label_t.startswith(label + ", turning"))
        cost[label_r.split(",")[0]] = _cost(runs[label_r], runs[label_t])
    crossing = next((c for c in campbell.crossings if c["mode"] == 0 and c["order"] == ENGINE_ORDER), None)
    chart = plot_campbell(campbell, range(1, 9), config.out / "campbell_maps.png",
                          title=f"turning reduced model (r = {model.r}): modes, engine orders and the maps' largest "
                                f"responses (EO4)", peaks=peaks)
    numbers = {"crossing_1B_EO4": None if crossing is None else crossing["speed"],
               "crossing_1B_EO4_at_rest": float(np.sqrt(scipy.linalg.eigh(model.K, model.M, eigvals_only=True,
                                                                           subset_by_index=[0, 0])[0]) / ENGINE_ORDER),
               "peaks": {k: v[0] for k, v in peaks.items()}, "cost_per_speed": cost,
               "clearance": config.scheme.rotation, "campbell": campbell.summary()}
    files = [chart, save_json(config.out / "turning_comparison.json", numbers, indent=1, default=float)]
    return TurningComparison(turning, rest, campbell, peaks, cost, files)
