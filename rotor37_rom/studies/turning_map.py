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
from typing import TYPE_CHECKING

import numpy as np
import scipy.linalg

from rotor37_rom.model.campbell import engine_order_crossings, track_modes
from rotor37_rom.model.reduced import ReducedModel, load_reduced_model
from rotor37_rom.model.rotating import centrifugal_equilibrium, rotating_stiffness
from rotor37_rom.npz import save_json
from rotor37_rom.studies.campbell import CampbellResult
from rotor37_rom.studies.contact_map import ContactMapConfig, ContactMapResult, eo4_frequency, run_contact_map
from rotor37_rom.viz.charts import plot_campbell

if TYPE_CHECKING:
    from mpi4py import MPI

__all__ = ["TurningComparison", "run_turning_comparison", "reduced_campbell", "engine_order_crossing", "ENGINE_ORDER"]

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
    (``model.rotating``). A blade's first ``n_modes``, followed by shape (``model.campbell.track_modes``), crossing
    every order; a tuned disk's lowest mode of each nodal diameter k = e of the orders (its 1B family; named by the
    harmonic index carrying it, ``disk.harmonics.sector_harmonics``), each crossing the order that excites it
    (e = k: the orders up to N/2 alias on nothing). Crossings interpolated on the grid
    (``model.campbell.engine_order_crossings``)."""
    from rotor37_rom.disk.harmonics import sector_harmonics

    orders = list(orders)
    speeds = np.linspace(0.0, model.rotation.top_speed, n_speeds)
    M = 0.5 * (model.M + model.M.T)
    disk = model.sectors is not None
    count = 3 * model.nodes.n_sectors if disk else n_modes
    frequencies, shapes = [], []
    for w in speeds:
        lam, V = scipy.linalg.eigh(rotating_stiffness(model, w, centrifugal_equilibrium(model, w)), M,
                                   subset_by_index=[0, count - 1])
        lam = np.sqrt(np.maximum(lam, 0.0))
        if disk:
            k = sector_harmonics(V, model.sectors.blocks)
            lam = np.array([lam[k == e].min() if (k == e).any() else np.nan for e in orders])
        frequencies.append(lam)
        shapes.append(V)
    if disk:
        omega, macs = np.array(frequencies), np.ones(n_speeds)
        labels = [f"k = {e}" for e in orders]
        crossings = [c for c in engine_order_crossings(speeds, omega, orders) if orders[c["mode"]] == c["order"]]
    else:
        omega, macs = track_modes(frequencies, shapes)
        labels = [f"mode {k + 1}" for k in range(n_modes)]
        crossings = engine_order_crossings(speeds, omega, orders)
    crossings = [dict(c, label=labels[c["mode"]]) for c in crossings]
    return CampbellResult(speeds=speeds, omega=omega, labels=labels, mac=macs, crossings=crossings, wall_s=0.0)


def engine_order_crossing(campbell: CampbellResult, order: int = ENGINE_ORDER) -> float | None:
    """The speed (rad/s) where the 1B line the order excites (a blade's first mode, a disk's k = ``order``) meets
    it on ``reduced_campbell``'s diagram; None if it does not."""
    wanted = {f"k = {order}", campbell.labels[0]} if campbell.labels[0] == "mode 1" else {f"k = {order}"}
    return next((c["speed"] for c in campbell.crossings if c["label"] in wanted and c["order"] == order), None)


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
    crossing = engine_order_crossing(campbell)
    chart = plot_campbell(campbell, range(1, 9), config.out / "campbell_maps.png",
                          title=f"turning reduced model (r = {model.r}): modes, engine orders and the maps' largest "
                                f"responses (EO4)", peaks=peaks)
    numbers = {"crossing_1B_EO4": crossing,
               "crossing_1B_EO4_at_rest": eo4_frequency(model) / ENGINE_ORDER,
               "peaks": {k: v[0] for k, v in peaks.items()}, "cost_per_speed": cost,
               "clearance": config.scheme.rotation, "campbell": campbell.summary()}
    files = [chart, save_json(config.out / "turning_comparison.json", numbers, indent=1, default=float)]
    return TurningComparison(turning, rest, campbell, peaks, cost, files)
