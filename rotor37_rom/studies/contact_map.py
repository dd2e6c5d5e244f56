"""The contact-map study (demos/contact_map.py, paper §2.3.1, §2.3.3, §3.4): ``run_contact_map(ContactMapConfig)``.

The reduced model of the clamped blade or of the 36-sector bladed disk (loaded, or built on rank 0 and read by the
other ranks), its sprag-slip onsets, then one interaction map per GNL setting: every speed from rest, the speeds that
blew up run again with the step halved, a continuation up and down; the charts, and summary.json, which keeps the runs
of an earlier call on the same model, speeds and revolutions. Under MPI every rank runs its share of the speeds and
rank 0 writes the charts and the summary.

The configuration and its command line are ``rotor37_rom.studies.contact_config``, the time scheme and GNL forces
``rotor37_rom.studies.contact_scheme``; their names are imported here too, so that the study is one module to its
callers.
"""
from __future__ import annotations

import dataclasses
import importlib
import time
from pathlib import Path
from typing import TYPE_CHECKING, Sequence

import numpy as np
import scipy.linalg

from rotor37_rom.checks import before_work, flagged, output_lock
from rotor37_rom.disk.assembly import mistuning_factors
from rotor37_rom.disk.harmonics import sector_harmonics
from rotor37_rom.dynamics.casing import Casing, check_hand, contact_matrices
from rotor37_rom.dynamics.explicit import CentralDifference, simulate
from rotor37_rom.dynamics.friction import sprag_slip_friction
from rotor37_rom.model.reduced import ReducedModel, load_reduced_model, save_reduced_model, saved_model_key
from rotor37_rom.npz import load_json, save_json, set_aside
from rotor37_rom.studies.contact_config import (GNL_SETTINGS, N_SECTORS, PRECISIONS, ContactMapConfig, MapContinuation,
    MapModel, MapScheme, build_parser, continued_revolutions, map_model, parse_options)
from rotor37_rom.studies.contact_scheme import (capped_gnl_step, capped_probe, capped_probe_states, cubature_model,
    print_step_outliers, setting_names, time_scheme)
from rotor37_rom.studies.periodic_map import PeriodicBranch, describe_against, periodic_branch, save_orbits
from rotor37_rom.studies.sweep import (ContinuationPoint, InteractionMap, SavedRecord, compute_seconds,
    continuation, interaction_map, idle_barrier, load_speed, load_sweep, record_row, rerun_diverged, run_sweep,
    sector_maxima, sweep_folder)
from rotor37_rom.viz.charts import plot_interaction_map, plot_nfrc, plot_periodic_nfrc, plot_time_history
from rotor37_rom.reporting import say

if TYPE_CHECKING:
    from mpi4py import MPI

__all__ = ["run_contact_map", "ContactMapResult", "MapResult", "Branch", "reduced_model", "build_model",
           "eigenfrequencies", "eo4_frequency", "sprag_slip_onsets", "carry_on", "carry_on_record", "stress_mesh",
           "disk_stress_of", "disk_peak_stress", "merge_earlier_runs", "write_summary", "world_comm", "PAPER",
           "check_summary", "check_output",
           "ContactMapConfig", "MapModel", "MapScheme", "MapContinuation", "build_parser", "parse_options", "map_model",
           "continued_revolutions", "GNL_SETTINGS", "PRECISIONS", "N_SECTORS", "time_scheme", "setting_names",
           "cubature_model", "capped_probe", "capped_gnl_step", "capped_probe_states", "print_step_outliers",
           "PeriodicBranch"]

PAPER = {"linear 1B/EO4": 1317.0, "zero IC, no GNL": 1446.0, "zero IC, GNL": 1535.0,
         "continuation, no GNL": 1520.0, "continuation, GNL": 1551.0}


@dataclasses.dataclass(frozen=True)
class Branch:
    """One continuation branch (§2.3.3): its accepted points, the step it ran with (s) and its wall time (s)."""

    points: list[ContinuationPoint]
    h: float
    wall_s: float

    @property
    def peak(self) -> ContinuationPoint:
        """The point of largest (finite) amplitude."""
        return max(self.points, key=lambda p: p.amplitude if np.isfinite(p.amplitude) else -1)


@dataclasses.dataclass(frozen=True)
class MapResult:
    """The interaction map of one setting.

    Attributes:
        label: chart and summary label, e.g. 'no GNL' or 'GNL, cubature 0.0001, cap 120 kHz'.
        tag: the same in file names, e.g. 'linear' or 'gnl_cub0.0001_cap120k'.
        folder: folder of the sweep's per-speed records (speeds run again are in sweeps of their own).
        imap: spectra and NFRC of node LE (speeds in rad/s, amplitudes in m; NaN where a run diverged).
        h: time step of the sweep (s); h_crit: 2 / omega_max of its scheme (s).
        retried: {speed (rad/s): step of its last retry (s)} for the speeds run again after a blow-up.
        wall_s: wall time of the sweep and its retries (s).
        branches: {'up' | 'down': Branch}, empty without a continuation.
        periodic: the periodic orbits over the continuation's range (``studies.periodic_map``), None without
            --periodic.
    """

    label: str
    tag: str
    folder: Path
    imap: InteractionMap
    h: float
    h_crit: float
    retried: dict[float, float]
    wall_s: float
    branches: dict[str, Branch]
    periodic: PeriodicBranch | None = None

    @property
    def speeds(self) -> np.ndarray:
        """Angular speeds of the map (rad/s)."""
        return self.imap.speeds

    @property
    def nfrc(self) -> np.ndarray:
        """Max |u_LE,r| over the last revolution at each speed (m); NaN where the run diverged."""
        return self.imap.nfrc

    @property
    def diverged(self) -> np.ndarray:
        """Whether each speed's run blew up (after its retries)."""
        return self.imap.diverged

    @property
    def peak_speed(self) -> float:
        """The speed of largest response (rad/s); NaN when every run diverged."""
        ok = np.isfinite(self.nfrc)
        return float(self.speeds[ok][np.argmax(self.nfrc[ok])]) if ok.any() else float("nan")


@dataclasses.dataclass(frozen=True)
class ContactMapResult:
    """What ``run_contact_map`` produced.

    Attributes:
        out: the output folder.
        eigenfrequencies: the model's first three frequencies omega_1..3 (rad/s).
        linear_resonance: omega_1 / 4, where 1B crosses engine order 4 (rad/s).
        runs: {label: MapResult} of this call (rank 0; empty on the other ranks).
        summary: the content of summary.json (rank 0; with the runs of an earlier call on the same set-up).
        files: the files written: the model built (if any), the charts and summary.json.
    """

    out: Path
    eigenfrequencies: np.ndarray
    linear_resonance: float
    runs: dict[str, MapResult]
    summary: dict
    files: list[Path]


def reduced_model(config: ContactMapConfig, comm: MPI.Comm | None) -> tuple[ReducedModel, list[Path]]:
    """The model of ``config.rom.path``, or one built and saved; returns it and the files written."""
    if config.rom.path is not None:
        try:
            return load_reduced_model(config.rom.path), []
        except ValueError as exc:
            raise ValueError(f"--model: {exc}") from None
    if comm is None or comm.size == 1:
        model = build_model(config)
        return model, [save_reduced_model(model, config.out / "rom.npz")]
    # under MPI rank 0 builds (the reduction is serial: its own copy of the mesh) and saves; the others load
    importlib.import_module("rotor37_rom.fem")    # on every rank: importing dolfinx initializes PETSc (collective)
    error, path = None, None
    if comm.rank == 0:
        try:
            path = save_reduced_model(build_model(config), config.out / "rom.npz")
        except ValueError as exc:
            error = str(exc)
    idle_barrier(comm)
    error, path = comm.bcast((error, path), root=0)
    if error is not None:
        raise ValueError(error)
    return load_reduced_model(path), [path] if comm.rank == 0 else []


def build_model(config: ContactMapConfig) -> ReducedModel:
    """Build the reduced model of the ``config.rom.preset`` blade, of the bladed disk, or of the user's sector
    ``config.rom.mesh`` (cached in ``config.cache_dir``), in this process alone."""
    from mpi4py import MPI

    r_c, r_md = config.modes
    t0 = time.perf_counter()
    sector = config.rom.create_sector(MPI.COMM_SELF)
    if len(sector.tip_nodes) >= 2:                       # a sense the blade's hand refuses costs no model build
        check_hand(sector.tip_nodes, config.sweep.casing.rotation_sense)
    if config.rom.disk:
        from rotor37_rom.reduction.disk_builder import DiskReductionConfig, build_disk_model

        n = sector.cyclic.n_sectors
        factors = None if config.rom.mistuning == 0 else tuple(mistuning_factors(n, config.rom.mistuning,
                                                                              config.rom.seed).tolist())
        # without GNL no sector force is evaluated: the exact tensors (most of a build) are not built
        spin = config.spin_snapshots                     # a turning map's centrifugal snapshots, () at rest
        reduction = DiskReductionConfig(tip_nodes="all", r_c=r_c, r_md=r_md, criterion="MI2b",
                                        r_cyclic=min(config.interface_modes, n * sector.cyclic.left.size),
                                        mistuning=factors, forces="none" if config.gnl == "off" else "intrusive",
                                        spin_snapshots=spin, spin_modes=min(4, r_c) if spin else 0)
        model, _ = build_disk_model(sector, reduction, cache_dir=config.cache_dir)
    else:
        from rotor37_rom.reduction.builder import ReductionConfig, build_reduced_model

        spin = config.spin_snapshots                     # a turning map's centrifugal snapshots, () at rest
        reduction = ReductionConfig(r_c=r_c, r_md=r_md, global_md_modes=config.rom.global_md, forces="intrusive",
                                    contact_patch=config.rom.contact_patch, spin_snapshots=spin,
                                    spin_modes=min(4, r_c) if spin else 0)
        model, _ = build_reduced_model(sector, reduction, cache_dir=config.cache_dir)
    what = f"{config.rom.mesh.path.name}" if config.rom.mesh is not None else f"{config.rom.preset} preset"
    say(f"reduced model: {what} ({sector.n_dofs} DOF) -> r = {model.r} {model.sizes} "
          f"in {time.perf_counter() - t0:.1f} s")
    return model


def eigenfrequencies(model: ReducedModel) -> np.ndarray:
    """The first three frequencies of the reduced model (rad/s)."""
    return np.sqrt(scipy.linalg.eigh(model.K, model.M, eigvals_only=True)[:3])


def eo4_frequency(model: ReducedModel) -> float:
    """The 1B frequency engine order 4 meets (rad/s): omega_1 of a blade; for a disk the lowest mode of 4 nodal
    diameters (the stationary two-lobe casing excites k = 4 through EO4 on a tuned disk)."""
    if model.sectors is None:
        return float(eigenfrequencies(model)[0])
    lam, V = scipy.linalg.eigh(model.K, model.M, subset_by_index=[0, 3 * model.nodes.n_sectors - 1])
    k = sector_harmonics(V, model.sectors.blocks)
    return float(np.sqrt(lam[k == 4].min())) if (k == 4).any() else float(np.sqrt(lam[0]))


def sprag_slip_onsets(model: ReducedModel, casing: Casing, sector: int = 0, spin: float | None = None) -> dict:
    """Friction coefficients at which sustained sliding on the casing diverges (rotor37_rom.dynamics.friction): per
    contact node of ``sector`` (a tuned disk's sectors are alike) and for all contact nodes together; ``spin``
    (rad/s): of the blade turning there (its prestressed tangent, ``model.rotating``), None: at rest."""
    from rotor37_rom.model.rotating import rotating_stiffness

    N, S, _, rows = contact_matrices(model.nodes, model.r, casing)
    mine = [k for k, row in enumerate(rows) if model.nodes.sector[row] == sector]
    K = model.K if spin is None else rotating_stiffness(model, spin)
    G = np.linalg.inv(K)                                # once, not per node (r = 1,728 on the disk)
    single = [sprag_slip_friction(K, N, S, [k], compliance=G) for k in mine]
    return {"weakest_node": min(single), "per_node": single,
            "all_nodes": sprag_slip_friction(K, N, S, compliance=G)}


def turning_resonance(model: ReducedModel, top: float, order: int = 4) -> float | None:
    """Where the turning blade's first mode (a tuned disk's: its lowest mode of ``order`` nodal diameters, which the
    two-lobe casing excites through that order) meets engine order ``order`` (rad/s): Southwell's iteration
    (``studies.campbell.iterate_crossing``) on the reduced model's prestressed, spin-softened modes
    (``model.rotating``, to 0.01 rad/s); None where it lies above ``top`` or the model's range."""
    from rotor37_rom.model.rotating import rotating_modes, rotating_stiffness
    from rotor37_rom.studies.campbell import iterate_crossing

    limit = min(top, model.rotation.top_speed)
    if model.sectors is None:
        def modes(w):
            return rotating_modes(model, min(w, limit))[0], None
        omega0 = float(eigenfrequencies(model)[0])
    else:                                   # a tuned disk: the lowest family of ``order`` nodal diameters
        def modes(w):
            w = min(w, limit)
            K_T = rotating_stiffness(model, w)
            lam, V = scipy.linalg.eigh(K_T, 0.5 * (model.M + model.M.T),
                                       subset_by_index=[0, 3 * model.nodes.n_sectors - 1])
            k = sector_harmonics(V, model.sectors.blocks)
            return np.sqrt(np.maximum(lam[k == order % model.nodes.n_sectors], 0.0)), None
        omega0 = eo4_frequency(model) if order == 4 else float(modes(0.0)[0][0])
    try:
        speed, iterations = iterate_crossing(modes, order, omega0 / order, omega0, lambda w, V: 0)
    except (ValueError, IndexError):
        return None
    return speed if iterations > 0 and speed <= limit else None


def _finite(x: float) -> float | None:
    """x, or None for inf (JSON has no inf: null = friction never wedges these nodes)."""
    return x if np.isfinite(x) else None


def model_summary(config: ContactMapConfig, model: ReducedModel, omega: np.ndarray, onset: dict) -> dict:
    """The summary.json entries of the model and the set-up (its 'runs' still empty)."""
    return {"r": model.r, "sizes": model.sizes, "omega_1_3": omega.tolist(),
            "linear_resonance": eo4_frequency(model) / 4, "node": config.node, "disk": model.sectors is not None,
            "input": None if config.rom.mesh is None else config.rom.mesh.as_dict(),
            "mistuning": model.metadata.get("config", {}).get("mistuning"),
            "speeds": list(config.speeds), "revolutions": config.sweep.revolutions, "casing": vars(config.sweep.casing),
            "runs": {}, "sprag_slip": {k: ([_finite(x) for x in v] if isinstance(v, list) else _finite(v))
                                       for k, v in onset.items()}}


def sweep_map(config: ContactMapConfig, scheme: CentralDifference, comm: MPI.Comm | None
              ) -> tuple[Path, list[dict], dict[float, float], float]:
    """Run the map's speeds and retry those that blew up. Returns the sweep folder, the per-speed records (rank 0;
    [] on the others), {retried speed: its last step} and the wall time (s)."""
    rank = 0 if comm is None else comm.rank
    spec, speeds, sweeps = config.sweep_spec(scheme.model), config.speed_grid, config.out / "sweeps"
    t0 = time.perf_counter()
    folder = run_sweep(scheme, speeds, spec, sweeps, comm=comm, progress=not config.quiet)
    # rank 0 reads the records (~1 GB for the 100-speed headline map); rerun_diverged tells the others
    records = [r for r in load_sweep(folder) if np.isclose(float(r["omega"]), speeds).any()] if rank == 0 else []
    records, retried = rerun_diverged(scheme, records, spec, sweeps, config.scheme.retry_diverged, comm=comm,
                                      progress=not config.quiet)
    return folder, records, retried, time.perf_counter() - t0


def continuation_branches(config: ContactMapConfig, scheme: CentralDifference, retried: dict[float, float],
                          tag: str, comm: MPI.Comm | None) -> dict[str, Branch]:
    """Continuation up and down (§2.3.3) at the step the map's speeds all ran with (the smallest retry step, if any
    speed was run again), the first run as long as the map's, the next 15 % of it (the paper: 200 then 30).
    Under MPI the two branches run on ranks 0 and 1 at once; rank 0 gets both. Each branch is written after every
    accepted speed (``sweep.continuation(out=...)``), so a killed run resumes. Returns {'up' | 'down': Branch}."""
    if config.continuation.step <= 0:
        return {}
    run_scheme = scheme.with_step(min(retried.values())) if retried else scheme
    start, stop = config.continuation_span
    legs = {"up": (start, stop), "down": (stop, start)}
    rank, size = (0, 1) if comm is None else (comm.rank, comm.size)
    mine = {}
    for k, (name, (a, b)) in enumerate(legs.items()):
        if k % size == rank:
            t0 = time.perf_counter()
            points = continuation(run_scheme, a, b, config.continuation.step, config.sweep.casing,
                                  first_revolutions=config.sweep.revolutions,
                                  revolutions=continued_revolutions(config.sweep.revolutions),
                                  out=config.out / "continuation" / tag, window=config.continuation.steady_window,
                                  unsteady=config.continuation.unsteady_step, node=config.node,
                                  progress=not config.quiet)
            mine[name] = Branch(points, run_scheme.h, time.perf_counter() - t0)
    if comm is not None:
        idle_barrier(comm)                                # the branches take hours apart
        gathered = comm.gather(mine, root=0)
        mine = {k: v for part in gathered for k, v in part.items()} if rank == 0 else {}
    return mine


def chart_map(config: ContactMapConfig, result: MapResult, records: list[dict], omega: np.ndarray, r: int,
              lin_res: float) -> list[Path]:
    """Draw the interaction map, the time history of the largest response and the continuation NFRC (if any)."""
    out, imap = config.out, result.imap
    files = [plot_interaction_map(imap, out / f"interaction_map_{result.tag}.png", eigenfrequencies=omega,
                                  linear_resonance=lin_res,
                                  title=f"node {config.node}, {result.label}, r = {r}, "
                                        f"{config.sweep.revolutions:g} rev., h = {result.h:.3g} s")]
    ok = np.isfinite(imap.nfrc)
    worst = records[int(np.nanargmax(np.where(ok, imap.nfrc, -1)))] if ok.any() else records[0]
    curves = {name: worst["u_r"][record_row(worst, f"{config.sector}:{name}")] for name in ("LE", "TE")
              if f"{config.sector}:{name}" in map(str, worst["labels"])}
    files.append(plot_time_history(worst["t"], curves,
                                   out / f"time_history_{result.tag}.png",
                                   title=f"{result.label}, Omega = {float(worst['omega']):.0f} rad/s"))
    if result.branches:
        curves = {f"continuation {name}": ([p.omega for p in b.points], [p.amplitude for p in b.points],
                                           "+" if name == "up" else "o") for name, b in result.branches.items()}
        curves["zero IC"] = (imap.speeds, imap.nfrc, "--")
        files.append(plot_nfrc(curves, out / f"nfrc_continuation_{result.tag}.png", lin_res, PAPER))
    if result.periodic is not None and len(result.periodic.speeds):
        continued = {f"continuation {name}": ([p.omega for p in b.points], [p.amplitude for p in b.points])
                     for name, b in result.branches.items()}
        files.append(plot_periodic_nfrc(result.periodic, out / f"nfrc_periodic_{result.tag}.png",
                                        (imap.speeds, imap.nfrc, f"from rest, {config.sweep.revolutions:g} rev."),
                                        lin_res, f"{result.label}: periodic orbits (shooting) and the map",
                                        continued))
    return files


def summary_entry(config: ContactMapConfig, scheme: CentralDifference, result: MapResult, records: list[dict]
                  ) -> dict:
    """The summary.json entry of one map: step, forces, NFRC, contact works and checks, continuation branches."""
    imap, wall, compute = result.imap, result.wall_s, compute_seconds(records)
    works = np.array([np.asarray(r.get("work", np.full(4, np.nan)), float)[:2] for r in records])
    entry = {"h": scheme.h, "h_crit": scheme.h_crit, "frequency_cap_khz": config.scheme.frequency_cap,
             "step_outliers": config.scheme.step_outliers if scheme.nonlinear else None,
             "perturbation": config.scheme.perturbation, "model_key": scheme.model.key,
             "cubature": scheme.model.metadata.get("hyper_reduction"),
             # from the metadata: a disk's sector forces wrap the quadrature forces that carry the precision
             "force_precision": scheme.model.metadata.get("force_precision", "double"), "peak_speed": result.peak_speed,
             "peak_amplitude": float(np.nanmax(imap.nfrc)),
             "diverged": imap.speeds[imap.diverged].tolist(), "wall_s": wall, "compute_s": compute,
             "retried": {f"{w:g}": hk for w, hk in result.retried.items()},
             # per process-second over every sitting (a resumed map's too); older folders: this sitting's wall
             "rev_per_s": config.sweep.revolutions * len(records) / compute if compute else
             config.sweep.revolutions * len(records) / wall if wall > 1 else None,
             "nfrc": imap.nfrc.tolist(),
             "work_normal_J": works[:, 0].tolist(), "work_friction_J": works[:, 1].tolist(),
             "speeds": imap.speeds.tolist(), "contact_checks": {
                 "max_penetration": max(float(r["max_penetration"]) for r in records),
                 "min_multiplier": min(float(r["min_multiplier"]) for r in records),
                 "max_friction_power": max(float(r["friction_power"]) for r in records)}}
    if len({label.partition(":")[0] for label in map(str, records[0]["labels"])}) > 1:     # a disk: every LE
        per_sector = [sector_maxima(r) for r in records]
        entry["largest_over_sectors"] = [float(np.nanmax(a)) if np.isfinite(a).any() else None for a in per_sector]
        entry["largest_sector"] = [int(np.nanargmax(a)) if np.isfinite(a).any() else None for a in per_sector]
    if result.periodic is not None:
        entry["periodic"] = result.periodic.summary()
    for name, branch in result.branches.items():
        entry[f"continuation_{name}_peak"] = branch.peak.omega
        entry[f"continuation_{name}"] = [(p.omega, p.amplitude, p.steady, p.halvings, p.period)
                                         for p in branch.points]
        entry[f"continuation_{name}_h"], entry[f"continuation_{name}_wall_s"] = branch.h, branch.wall_s
        entry["continuation_steady_window"] = config.continuation.steady_window
        entry["continuation_unsteady_step"] = config.continuation.unsteady_step
    return entry


def carry_on(config: ContactMapConfig, scheme: CentralDifference, result: MapResult, speed: float,
             monitor: Sequence[int] | None = None):
    """The map's run at ``speed`` carried on one revolution from its final state (its sweep record, at the step it
    ran with), the casing where it was, states recorded every ~1e-6 s. Returns (SimulationResult, its scheme, the
    time (s) the map's run ended at)."""
    run_scheme = scheme.with_step(result.retried[speed]) if speed in result.retried else scheme
    record = load_speed(sweep_folder(run_scheme, config.sweep_spec(scheme.model), config.out / "sweeps"), speed)
    res, t_end = carry_on_record(config, run_scheme, record, speed, monitor)
    return res, run_scheme, t_end


def carry_on_record(config: ContactMapConfig, run_scheme: CentralDifference, record: dict, speed: float,
                    monitor: Sequence[int] | None = None):
    """One revolution from a sweep ``record``'s final state, run with the scheme (and step) it ran with, the casing
    where it was. Returns (SimulationResult, the time (s) the record's run ended at)."""
    steps = int(np.ceil(config.sweep.revolutions * 2 * np.pi / speed / run_scheme.h))
    casing = config.sweep.casing
    res = simulate(run_scheme, [speed], casing, revolutions=1, initial=(record["q_final"], record["q_prev"]),
                   duration=1e-12, phase=casing.rotation_sense * speed * steps * run_scheme.h,
                   record_every=max(1, int(round(1e-6 / run_scheme.h))), record_q=True, on_blowup="flag",
                   monitor=monitor)
    return res, steps * run_scheme.h


def stress_mesh(config: ContactMapConfig, model: ReducedModel):
    """The disk sector's mesh the model was built on (for ``--stress``; made once per call of the study)."""
    from mpi4py import MPI

    from rotor37_rom.reduction.builder import mesh_signature

    if model.sectors is None:
        raise ValueError("--stress needs a disk model (this one is a single blade's: demos/report.py draws its stress)")
    sector = config.rom.create_sector(MPI.COMM_SELF)                       # rank 0's own copy under mpirun
    if mesh_signature(sector) != model.metadata.get("mesh"):
        where = "--mesh" if config.rom.mesh is not None else "--preset"
        raise ValueError(f"{where}: the model was not built on {sector.source}'s mesh")
    return sector


def disk_stress_of(sector, model: ReducedModel, res, nonlinear: bool, monitor: int
                   ) -> tuple[np.ndarray, np.ndarray, dict, int]:
    """The disk's von Mises stress at t_max of a carried-on run ``res`` (one speed; its first recorded row is the
    monitored node): every sector's field rebuilt from q at the record of largest |u| (no reassembly) on the disk
    ``sector`` (``stress_mesh``), summarised for sector ``monitor`` and over the sectors
    (``post.stress.disk_stress_summary``). Returns (the sectors' displacement fields, each sector's largest von Mises
    per cell, the numbers with ``u_le``, the record's index)."""
    from rotor37_rom.post.stress import disk_stress, disk_stress_summary

    u = res.u_r[0][0]
    k = int(np.nanargmax(np.abs(u)))
    fields, values = disk_stress(sector, model, res.records_q[0][:, k], nonlinear=nonlinear)
    numbers = disk_stress_summary(sector, model, values, monitor)
    numbers["u_le"] = float(u[k])
    return fields, values.max(axis=2), numbers, k


def disk_peak_stress(config: ContactMapConfig, scheme: CentralDifference, result: MapResult, tag: str, sector
                     ) -> tuple[dict, list[Path]]:
    """The whole bladed disk's von Mises stress at t_max (largest |u| of node LE of ``config.sector``) of the map's
    largest bounded response: that run carried on one revolution from its final state (as the report does for the
    blade), every sector's field rebuilt from q (no reassembly) on the disk ``sector`` (``stress_mesh``). Returns
    (numbers, [picture])."""
    from rotor37_rom.post.stress import describe_location
    from rotor37_rom.viz.plotting import render_stress

    model, speed = scheme.model, result.peak_speed
    if not np.isfinite(speed):
        return {"speed": None}, []
    res, run_scheme, t_start = carry_on(config, scheme, result, speed, [model.nodes.label_row(config.node)])
    if res.diverged_step[0] >= 0:
        return {"speed": speed, "diverged": True}, []
    fields, vm_sectors, numbers, k = disk_stress_of(sector, model, res, run_scheme.nonlinear, config.sector)
    numbers.update(speed=speed, t_max=t_start + float(res.t[0][k]))
    factor = 0.1 * 0.074 / max(np.abs(fields).max(), 1e-12)     # largest motion drawn at 10 % of the blade's span
    title = (f"{result.label}: von Mises at t_max, Omega = {speed:.0f} rad/s, node {config.node} (x{factor:.0f})")
    picture = render_stress(sector, fields[config.sector], vm_sectors, config.out / f"stress_disk_{tag}.png",
                            title, n_sectors=model.nodes.n_sectors, factor=factor, clim=numbers["clim"],
                            sector_displacements=fields)
    say(f"         stress at t_max ({speed:.0f} rad/s): sector {config.sector} {numbers['vm_max'] / 1e6:.0f} MPa "
          f"({numbers['ratio_yield']:.2f} sigma_Y) outside the tip band ({describe_location(numbers['location'])}), "
          f"largest over the sectors {numbers['vm_max_all_sectors'] / 1e6:.0f} MPa (sector {numbers['sector_of_max']}: "
          f"{describe_location(numbers['location_all_sectors'])}); off the root corner (> "
          f"{1e3 * numbers['root_band_m']:.0f} mm from the blade-rim junction): sector {config.sector} "
          f"{numbers['vm_max_off_root'] / 1e6:.0f} MPa ({numbers['ratio_yield_off_root']:.2f} sigma_Y, "
          f"{describe_location(numbers['location_off_root'])}), over the sectors "
          f"{numbers['vm_max_off_root_all_sectors'] / 1e6:.0f} MPa (sector {numbers['sector_of_max_off_root']})")
    return numbers, [picture]


def print_map(result: MapResult, linear_resonance: float) -> None:
    """One line per map (step, largest response, divergences) and one per continuation branch."""
    say(f"{result.label:>7}: h = {result.h:.3g} s (2/omega_max = {result.h_crit:.3g}), largest response at "
          f"{result.peak_speed:.0f} rad/s ({np.nanmax(result.nfrc) * 1e3:.3f} mm), linear 1B/EO4 "
          f"{linear_resonance:.0f} rad/s; {int(result.diverged.sum())} diverged ({len(result.retried)} run again "
          f"with a smaller step); {result.wall_s:.0f} s")
    for name, branch in result.branches.items():
        best = branch.peak
        unsteady = [f"{p.omega:.0f}" for p in branch.points if not p.steady]
        largest = (f"largest response at {best.omega:.0f} rad/s ({best.amplitude * 1e3:.3f} mm)"
                   if np.isfinite(best.amplitude) else f"every run blew up (from {best.omega:.0f} rad/s)")
        say(f"         continuation {name} (h = {branch.h:.3g} s, {branch.wall_s:.0f} s): {largest}; "
              f"{len(branch.points)} speeds, not steady at {', '.join(unsteady) or 'none'}")
    if result.periodic is not None:
        say(f"         {result.periodic.describe()}")
        for name, comparison in result.periodic.continuation.items():
            say(f"         {describe_against(name, comparison)}")


def check_summary(summary) -> None:
    """ValueError (KeyError, TypeError) unless ``summary`` (a summary.json, read) is what ``write_summary`` writes as
    far as a later call reads it back: an object whose 'runs', if any, are objects with as many 'nfrc' values as
    'speeds'."""
    if not isinstance(summary, dict):
        raise ValueError(f"a JSON object expected, got {type(summary).__name__}")
    runs = summary.get("runs", {})
    if not isinstance(runs, dict):
        raise ValueError(f"its 'runs' must be an object, got {type(runs).__name__}")
    for label, run in runs.items():
        if not isinstance(run, dict) or not isinstance(run.get("speeds"), list) or \
                not isinstance(run.get("nfrc"), list) or len(run["speeds"]) != len(run["nfrc"]):
            raise ValueError(f"its run {label!r} has no list of speeds with as many nfrc values")


def check_output(out: Path) -> None:
    """The files of an earlier run in the map's folder ``out`` that this one reads back, checked before it works: a
    damaged summary.json is moved aside (``summary.json.damaged-<n>``; this run writes a new one, without the
    earlier runs it held), a damaged continuation branch too (that branch runs again). A warning names each."""
    load_json(out / "summary.json", check_summary,
              "this run writes a new one (the earlier runs it held are not carried over)")
    for path in sorted((out / "continuation").glob("*/continuation_*.npz")):
        try:
            missing = [k for k in ("points", "q", "q_prev", "phase", "omega", "finished") if k not in SavedRecord(path)]
            if missing:
                raise ValueError(f"no {', '.join(missing)}")
        except Exception as exc:
            set_aside(path, " ".join(f"{exc.__class__.__name__}: {exc}".split()), "its branch runs again")


def merge_earlier_runs(summary: dict, previous: Path) -> None:
    """Add to ``summary['runs']`` the runs of an earlier summary.json of the same model, speeds and revolutions
    (this call's entries win, key by key). A damaged one is moved aside with a warning and nothing merged
    (``run_contact_map`` checks it before it works: ``check_output``)."""
    old = load_json(previous, check_summary, "the new summary holds this call's runs only")
    if old is None:
        return
    if (old.get("r"), old.get("speeds"), old.get("revolutions")) != (summary["r"], summary["speeds"],
                                                                      summary["revolutions"]):
        return
    for label, run in old.get("runs", {}).items():
        new = summary["runs"].get(label, {})
        merged = {**run, **new}
        if new and new.get("rev_per_s") is None and run.get("rev_per_s") and run.get("h") == new.get("h"):
            # a call that found every speed done keeps the wall time of the call that ran them
            merged["wall_s"], merged["rev_per_s"] = run["wall_s"], run["rev_per_s"]
        summary["runs"][label] = merged


def write_summary(out: Path, summary: dict) -> list[Path]:
    """Write nfrc.png (every run of the summary) and summary.json; returns their paths."""
    merge_earlier_runs(summary, out / "summary.json")
    curves = {}
    for label, run in summary["runs"].items():
        style = "-" if label.startswith("GNL") else "--"
        curves[label] = (np.array(run["speeds"]), np.array(run["nfrc"]), style)
        if "largest_over_sectors" in run:                  # a disk: also the largest over the blades
            largest = np.array([np.nan if a is None else a for a in run["largest_over_sectors"]], float)
            curves[f"{label}: largest over the blades"] = (np.array(run["speeds"]), largest,
                                                           "-." if label.startswith("GNL") else ":")
    chart = plot_nfrc(curves, out / "nfrc.png", summary["linear_resonance"], PAPER)
    return [chart, save_json(out / "summary.json", summary, indent=1, default=float)]


def run_contact_map(config: ContactMapConfig, comm: MPI.Comm | None = None,
                    schemes: dict[bool, CentralDifference] | None = None) -> ContactMapResult:
    """Run the interaction maps (and continuations) of ``config``; ``comm``: split the speeds over its ranks
    (None: serial); ``schemes``: the schemes of the GNL settings (True/False) when the caller has them already
    (``time_scheme``). Raises ValueError for an input the library refuses (a corrupted model, a step above the
    stability limit, ...)."""
    before_work({"--out": config.out, "--cache": config.cache_dir},                         # before any work
                {"--model": (config.rom.path, saved_model_key)})
    # the folder's lock (rank 0's: a second run on it is refused at once), then the files of an earlier run that this
    # one reads back checked (a damaged summary.json moved aside), before any work
    with output_lock(config.out, "--out", comm, check=lambda: check_output(config.out)):
        return _run_contact_map(config, comm, schemes)


def _run_contact_map(config: ContactMapConfig, comm: MPI.Comm | None,
                     schemes: dict[bool, CentralDifference] | None) -> ContactMapResult:
    """``run_contact_map``'s work (its folder locked and checked)."""
    rank = 0 if comm is None else comm.rank
    if comm is not None:
        # rank 0 alone imports dolfinx for its serial work (the build, the cubature, the stress) and PETSc's
        # initialisation is collective: every rank initialises it first (a disk map read from --model with --stress
        # imported none before the stress, and rank 0 waited there forever)
        importlib.import_module("rotor37_rom.fem")
    model, files = reduced_model(config, comm)
    casing = config.sweep.casing
    first = model.nodes.coordinates[model.nodes.sector == 0]
    stagger = check_hand(first, casing.rotation_sense)              # a mirrored blade: refused, naming the option
    omega = eigenfrequencies(model)
    turning = config.scheme.rotation is not None
    if turning:
        from rotor37_rom.model.rotating import check_spin

        flagged("--rotation", lambda: check_spin(model, config.top_speed))      # the model turns up to the top speed
        if model.sectors is not None and config.gnl != "on":
            raise ValueError("--rotation with a disk model takes --gnl on (the disk's prestress comes from its GNL "
                             "forces; its linearised turning scheme is not implemented)")
    onset = sprag_slip_onsets(model, config.sweep.casing, config.sector, config.top_speed if turning else None)
    summary = model_summary(config, model, omega, onset)
    rotation = None if not turning else {
        "clearance": config.scheme.rotation, "sprag_slip_at": config.top_speed,
        "resonance_1B_EO4": turning_resonance(model, config.top_speed),
        "model_speeds": np.asarray(model.rotation.speeds, float).tolist()}
    resonance = rotation["resonance_1B_EO4"] if turning else None
    resonance = summary["linear_resonance"] if resonance is None else resonance
    summary["frame"] = {"axis": "+z", "file_axis": "+z" if config.rom.mesh is None else config.rom.mesh.axis,
                        "rotation_sense": casing.rotation_sense, "contact_normal": casing.direction,
                        "tip_stagger_deg": float(np.degrees(stagger)),
                        "blade_frame": "the plane through the axis and the blade's centre of mass",
                        "blade_frame_theta_deg": float(np.degrees(model.nodes.frame_angle))}
    if rank == 0 and not config.quiet:
        say(f"frame: rotation about +z, sense {casing.rotation_sense:+d} (towards "
              f"{'-' if casing.rotation_sense < 0 else '+'}theta), contact normal {casing.direction}"
              + (f" (the blade frame's e_x: radial through its centre of mass, "
                 f"{np.degrees(model.nodes.frame_angle):+.3f} deg)" if casing.direction == "x" else "") + "; the tip's "
              f"trailing edge {abs(np.degrees(stagger)):.1f} deg behind its leading edge")
    if rank == 0 and not config.quiet:
        where = f" turning at {config.top_speed:g} rad/s" if turning else ""
        say(f"sustained sliding{where} diverges (sprag-slip) from mu = {onset['weakest_node']:.3f} on one contact "
              f"node, {onset['all_nodes']:.3f} on all of them; this run: mu = {config.sweep.casing.mu:g} (growth can "
              f"start below: docs/results.md, 'Friction')")
        if turning:
            crossing = rotation["resonance_1B_EO4"]
            what = "disk: its k = 4 1B family" if model.sectors is not None else "blade: 1B"
            say(f"turning {what} ({config.scheme.rotation} clearance) meets EO4 at "
                  + (f"{crossing:.1f} rad/s" if crossing is not None else f"no speed up to {config.top_speed:g} "
                     f"rad/s") + f" (at rest: {summary['linear_resonance']:.1f} rad/s)")
    runs, mesh = {}, None
    for gnl in GNL_SETTINGS[config.gnl]:
        setting = config.setting(gnl)
        if config.tolerance is not None and rank == 0:
            larger = config.model_beyond_choice(gnl)
            say(f"--tolerance {config.tolerance:g}: {config.choice(gnl).describe()}" + (
                f"; run on the larger model the settings share ({', '.join(f'{k} {v}' for k, v in larger.items())}): "
                f"the expected error and cost are the choice's, measured on its own model" if larger else ""))
        scheme = (schemes or {}).get(gnl) or time_scheme(setting, model, gnl, comm)
        label, tag = setting_names(setting, gnl)
        folder, records, retried, wall = sweep_map(setting, scheme, comm)
        branches = continuation_branches(setting, scheme, retried, tag, comm)
        if rank != 0:
            continue
        periodic = (periodic_branch(setting, scheme, {name: b.points for name, b in branches.items()})
                    if setting.continuation.periodic > 0 else None)
        runs[label] = result = MapResult(label, tag, folder, interaction_map(records, config.node), scheme.h,
                                         scheme.h_crit, retried, wall, branches, periodic)
        files += chart_map(setting, result, records, omega, model.r, resonance)
        summary["runs"][label] = summary_entry(setting, scheme, result, records)
        if periodic is not None and len(periodic.speeds):             # the orbits, to be read back (load_orbits)
            files.append(save_orbits(periodic, model, config.out / f"orbits_{tag}.npz"))
            summary["runs"][label]["periodic"]["file"] = files[-1].name
        if turning:                                       # the turning blade's crossing and clearance, per run
            summary["runs"][label]["rotation"] = rotation
        if config.tolerance is not None:
            choice = config.choice(gnl)
            summary["runs"][label]["chosen"] = dict(tolerance=config.tolerance, model=choice.name,
                                                    options=choice.options, expected_error=choice.error,
                                                    run_on_larger_model=config.model_beyond_choice(gnl))
        print_map(result, resonance)
        if gnl and setting.scheme.step_outliers == "drop" and result.imap.diverged.any():
            say(f"         {int(result.imap.diverged.sum())} speeds still blew up with --step-outliers drop (their "
                  f"retries halve a step above the one from every state): run them with --step-outliers keep before "
                  f"reading them as grown")
        if config.stress:
            mesh = mesh or stress_mesh(config, model)
            summary["runs"][label]["stress"], pictures = disk_peak_stress(config, scheme, result, tag, mesh)
            files += pictures
    if rank == 0:
        files += write_summary(config.out, summary)
    return ContactMapResult(config.out, omega, float(summary["linear_resonance"]), runs, summary, files)


def world_comm() -> MPI.Comm | None:
    """MPI.COMM_WORLD under mpirun with more than one rank; None when serial (or without mpi4py)."""
    try:
        from mpi4py import MPI
    except ImportError:
        return None
    return MPI.COMM_WORLD if MPI.COMM_WORLD.size > 1 else None

