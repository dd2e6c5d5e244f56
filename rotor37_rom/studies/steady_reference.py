"""The steady-state GNL reference in contact as one study: the full order and reduced models of each case, run until
steady (or their revolution limit), kept in one results file and compared (#86; ``benchmarks/bench_gnl_steady.py``
is its command line).

Each case (``gnl_reference.SteadyCase``: speed, friction, normal, damping law, revolutions, the full order's law) runs
the full order at each of ``FullOrderSettings.steps`` (generalised alpha, checkpointed next to the results file, with
field snapshots on request, carried on for an energy balance on request), then POD-Galerkin models from those
snapshots, then the reduced models of ``ReducedSettings`` (exact cubic forces, or a point cubature trained on their
own exact runs). A run kept in the results file is not repeated; a kept reduced run of another model size is. Each
case ends with its runs against the full order at its finest step (``gnl_reference.compare_runs``).
"""
from __future__ import annotations

import dataclasses
import json
import os
from pathlib import Path

import numpy as np

from rotor37_rom.checks import real_number
from rotor37_rom.reporting import say
from rotor37_rom.studies.gnl_reference import SteadyCase, revolution_peaks

__all__ = ["FullOrderSettings", "ReducedSettings", "SteadyStudyConfig", "CaseResult", "run_steady_study",
           "run_steady_maps", "map_label", "full_order_stem"]


def _each(name: str, values, low: float, high: float) -> tuple:
    values = tuple(values)
    for v in values:
        real_number(name, v, low, high)
    return values


@dataclasses.dataclass(frozen=True)
class FullOrderSettings:
    """The full order's runs of each case.

    Attributes:
        steps: its time steps (s, each in [1e-8, 1e-4]; two give the step spread).
        rho_inf: generalised alpha's spectral radius at infinity, in [0, 1].
        snapshots: keep its fields, 100 a revolution (the POD bases' snapshots).
        energy: carry each finished run on for this many revolutions, in (0, 20], and close its energy balance
            (``gnl_reference.full_order_energy``); None: not.
        run: False: no full-order run (the reduced models alone); the settings still name the run whose snapshots
            the POD bases read.
    """

    steps: tuple = (2e-6,)
    rho_inf: float = 0.8
    snapshots: bool = False
    energy: float | None = None
    run: bool = True

    def __post_init__(self):
        object.__setattr__(self, "steps", tuple(sorted(_each("full.steps", self.steps, 1e-8, 1e-4), reverse=True)))
        if not self.steps:
            raise ValueError("full.steps: give one step at least")
        real_number("full.rho_inf", self.rho_inf, 0.0, 1.0)
        if self.energy is not None:
            real_number("full.energy", self.energy, 0.0, 20.0, open_low=True)

    def key(self, h: float) -> str:
        return f"full h {h:.3g} rho {self.rho_inf:g}"


@dataclasses.dataclass(frozen=True)
class ReducedSettings:
    """The reduced models of each case, all under the case's damping law projected on their bases.

    Attributes:
        r_c: their fixed-interface modes (each in [1, 200]); () for none.
        global_md: the modal derivatives of the first N clamped modes, each N in [0, 20] (3: the maps' r = 55; 10:
            r = 104); every pair (r_c, N) is a model.
        step, cap_khz: their explicit step (s, in [1e-9, 1e-5]) and frequency cap (kHz, in [1, 1e4]).
        pod: POD-Galerkin models of these ranks (each in [24, 400]) from the full order's snapshots at its largest
            step.
        cubature: run the models on a point cubature of this tolerance, in (0, 0.1], trained on their own exact runs
            at ``train_speeds`` (rad/s, 3 revolutions each); None: the exact cubic forces.
        batch_cost: also time each model in a map's batch of this many speeds, in [0, 1000] (0: not).
    """

    r_c: tuple = (25,)
    global_md: tuple = (3,)
    step: float = 4e-7
    cap_khz: float = 120.0
    pod: tuple = ()
    cubature: float | None = None
    train_speeds: tuple = (1200.0, 1600.0)
    batch_cost: int = 0

    def __post_init__(self):
        object.__setattr__(self, "r_c", _each("reduced.r_c", self.r_c, 1, 200))
        object.__setattr__(self, "global_md", _each("reduced.global_md", self.global_md, 0, 20))
        object.__setattr__(self, "pod", _each("reduced.pod", self.pod, 24, 400))
        object.__setattr__(self, "train_speeds", _each("reduced.train_speeds", self.train_speeds, 1.0, 5000.0))
        real_number("reduced.step", self.step, 1e-9, 1e-5)
        real_number("reduced.cap_khz", self.cap_khz, 1.0, 1e4)
        real_number("reduced.batch_cost", self.batch_cost, 0, 1000)
        if self.cubature is not None:
            real_number("reduced.cubature", self.cubature, 0.0, 0.1, open_low=True)

    @property
    def cap(self) -> float:
        """The frequency cap (rad/s)."""
        return 2e3 * np.pi * self.cap_khz

    def _training(self) -> str:
        return "" if self.cubature is None else (f" cubature {self.cubature:g} train "
                                                 + "/".join(f"{w:g}" for w in self.train_speeds))

    def key(self, r_c: int, g: int) -> str:
        """A reduced run's key in the results file."""
        return (f"rom r_c {r_c}" + ("" if g == 3 else f" global md {g}")
                + f"{self._training()} cap {self.cap_khz:g} h {self.step:.3g}")

    def pod_key(self, r: int) -> str:
        return f"pod r {r} cap {self.cap_khz:g} h {self.step:.3g}"

    def cubature_name(self, r_c: int, g: int, case: SteadyCase) -> str:
        """The stem of a trained cubature model kept beside the checkpoints (one for every speed of a case)."""
        return (f"cubature r_c {r_c} md {g}{self._training()} mu {case.mu:g} {case.direction} {case.law} "
                f"cap {self.cap_khz:g} h {self.step:.3g}").replace(" ", "_").replace("/", "-")


@dataclasses.dataclass(frozen=True)
class SteadyStudyConfig:
    """The cases and their runs; ``results``: the results file (.json), its checkpoints in the folder of the same stem
    (``.ckpt``); ``cache``: the reduced models' cache folder."""

    cases: tuple
    full: FullOrderSettings = FullOrderSettings()
    reduced: ReducedSettings = ReducedSettings()
    results: Path = Path("results/bench_gnl_steady.json")
    cache: Path = Path("results/cache")

    def __post_init__(self):
        object.__setattr__(self, "cases", tuple(self.cases))
        object.__setattr__(self, "results", Path(self.results))
        object.__setattr__(self, "cache", Path(self.cache))
        if not self.cases or not all(isinstance(c, SteadyCase) for c in self.cases):
            raise ValueError(f"cases must be one or more SteadyCase, got {self.cases!r}")
        if self.results.suffix != ".json":
            raise ValueError(f"results must name a .json file, got {str(self.results)!r}")
        laws = {c.hyperelastic for c in self.cases}
        if laws != {"svk"} and (self.reduced.r_c or self.reduced.pod):
            raise ValueError(f"cases' hyperelastic {', '.join(sorted(laws - {'svk'}))}: the reduced models are SVK's; "
                             f"run that full order alone (reduced.r_c and reduced.pod empty)")
        if len(laws) > 1:
            raise ValueError("cases: one hyperelastic law for all (the full order's operators are built once)")

    @property
    def checkpoints(self) -> Path:
        return self.results.with_suffix(".ckpt")


@dataclasses.dataclass(frozen=True)
class CaseResult:
    """A case's runs ({key: ``SteadyRun.to_json()``, with an energy balance where carried on}) and their comparison
    against ``reference``, the full order at its finest step (None: no full-order run, no rows)."""

    case: SteadyCase
    runs: dict
    reference: str | None
    rows: list


def full_order_stem(folder: Path, case: SteadyCase, key: str) -> Path:
    """The files' stem of a full-order run (its checkpoint <stem>.npz, its snapshots <stem>.snapshots.npy): the case
    and the run's key, the dots of its numbers kept (rho 0.8 and 0.9 are two runs)."""
    return folder / f"{case.label()} {key}".replace(" ", "_").replace("/", "")


class _Store:
    """The results file: {case label: {run key: run}, 'machine': ...}, merged with what other runs of the study wrote
    meanwhile (one per core) at every save, never half written."""

    def __init__(self, path: Path, machine: str):
        self.path = path
        self.data = json.loads(path.read_text()) if path.exists() else {}
        self.data["machine"] = machine

    def runs(self, case: SteadyCase) -> dict:
        return self.data.setdefault(case.label(), {})

    def runs_of_label(self, label: str) -> dict:
        return self.data.setdefault(label, {})

    def save(self) -> None:
        on_disk = json.loads(self.path.read_text()) if self.path.exists() else {}
        for label, runs in self.data.items():
            if isinstance(runs, dict) and label != "machine":
                runs.update({**on_disk.get(label, {}), **runs})     # in place: the study's `runs` is this dict
                on_disk[label] = runs
        on_disk["machine"] = self.data["machine"]
        tmp = self.path.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text(json.dumps(on_disk))
        tmp.replace(self.path)


def _said(case: SteadyCase, key: str, run: dict) -> None:
    inward, outward = revolution_peaks(run["t"], run["u_le"], case.speed)
    value = f"{1e3 * run['value']:.3f} mm" + ("" if run["steady"] else " (NOT STEADY)")
    say(f"{case.label()} | {key}: max |u_LE| {value}; per revolution, towards the axis / the casing (mm): "
        + "  ".join(f"{1e3 * a:.3f}/{1e3 * b:.3f}" for a, b in zip(inward, outward))
        + f"; {run['reason']}; {run['wall_s']:.0f} s", flush=True)


def _full_order(config: SteadyStudyConfig, case: SteadyCase, runs: dict, store: _Store, sector, ops) -> None:
    from rotor37_rom.studies import gnl_reference as gr

    full = config.full
    for h in full.steps:
        key, stem = full.key(h), full_order_stem(config.checkpoints, case, full.key(h))
        if key not in runs:
            run, snaps = gr.full_order_run(sector, ops, case, h, full.rho_inf, stem.with_name(stem.name + ".npz"),
                                           100 if full.snapshots else 0)
            if snaps is not None:
                np.save(stem.with_name(stem.name + ".snapshots.npy"), snaps)
            runs[key] = run.to_json()
            store.save()
        if full.energy is not None and runs[key].get("energy", {}).get("revolutions") != full.energy:
            runs[key]["energy"] = gr.full_order_energy(sector, ops, case, h, full.rho_inf,
                                                       stem.with_name(stem.name + ".npz"), full.energy)
            say(f"{case.label()} | {key}: energy per revolution (J) {json.dumps(runs[key]['energy'])}", flush=True)
            maxima = runs[key]["maxima"] + runs[key]["energy"]["maxima"]       # the run's, then carried on
            changes = np.abs(np.diff(maxima[-3:])) / np.asarray(maxima[-3:-1])
            say(f"{case.label()} | {key}: carried on {full.energy:g} revolutions, max |u_LE| per revolution (mm) "
                + " ".join(f"{1e3 * m:.3f}" for m in maxima) + "; last changes "
                + ", ".join(f"{100 * c:.1f} %" for c in changes)
                + (" (steady)" if (changes < case.tolerance).all() else " (not steady)"), flush=True)
            store.save()
        _said(case, key, runs[key])


def _pod(config: SteadyStudyConfig, case: SteadyCase, runs: dict, store: _Store, sector, ops) -> None:
    from rotor37_rom.studies import gnl_reference as gr

    red = config.reduced
    for r in red.pod:
        key = red.pod_key(r)
        if key not in runs:
            h = config.full.steps[0]
            stem = full_order_stem(config.checkpoints, case, config.full.key(h))
            snaps = stem.with_name(stem.name + ".snapshots.npy")
            if not snaps.exists():
                raise ValueError(f"reduced.pod: no full-order snapshots for {case.label()} at h {h:.3g} s ({snaps}): "
                                 f"run the full order with snapshots first")
            model, bound = gr.pod_model(sector, ops, np.load(snaps), r, cache_dir=config.cache)
            C = gr.reduced_damping(model, sector, ops, case.damping)
            runs[key] = gr.reduced_run(model, C, case, red.step, red.cap).to_json()
            runs[key]["details"]["pod_bound"] = bound
            store.save()
        _said(case, key, runs[key])


def _model(config: SteadyStudyConfig, case: SteadyCase, r_c: int, g: int, sector, ops):
    """(model, its damping matrix, its cubature's training record or None) of (r_c, g): built (or read from the
    cache), on a cubature trained once for every speed of the case's law and kept beside the checkpoints."""
    import dataclasses as dc

    from rotor37_rom.model.reduced import load_reduced_model, save_reduced_model
    from rotor37_rom.reduction.builder import ReductionConfig, build_reduced_model
    from rotor37_rom.studies import gnl_reference as gr

    red = config.reduced
    reduction = ReductionConfig(r_c=r_c, r_md=0, criterion="MI2b", global_md_modes=g, forces="intrusive")
    model, _ = build_reduced_model(sector, reduction, ops=ops, cache_dir=config.cache)
    C = gr.reduced_damping(model, sector, ops, case.damping)
    if red.cubature is None:
        return model, C, None
    stem = config.checkpoints / red.cubature_name(r_c, g, case)
    kept = stem.with_name(stem.name + ".npz")
    if kept.exists():
        model = load_reduced_model(kept)
    else:
        model, info = gr.cubature_model(model, C, sector, case, red.step, red.cap, red.cubature, red.train_speeds,
                                        checkpoint=stem.with_name(stem.name + ".training.npz"))
        model = dc.replace(model, metadata={**model.metadata, "steady_cubature": info})
        save_reduced_model(model, kept)
    return model, C, model.metadata["steady_cubature"]


def _reduced(config: SteadyStudyConfig, case: SteadyCase, runs: dict, store: _Store, models: dict, sector,
             ops) -> None:
    from rotor37_rom.studies import gnl_reference as gr

    red = config.reduced
    for r_c, g in ((r_c, g) for r_c in red.r_c for g in red.global_md):
        key = red.key(r_c, g)
        if (r_c, g) not in models:                    # the cases differ by their speed alone: built once
            models[r_c, g] = _model(config, case, r_c, g, sector, ops)
        model, C, info = models[r_c, g]
        made = runs.get(key, {}).get("details", {}).get("model")
        if made is not None and made != f"reduced r = {model.r}":       # kept from a model built otherwise
            say(f"{case.label()} | {key}: the run kept was of a {made}, this model has r = {model.r}: run again")
        if made != f"reduced r = {model.r}":
            runs[key] = gr.reduced_run(model, C, case, red.step, red.cap).to_json()
            if info is not None:
                runs[key]["details"]["cubature"] = info
            store.save()
        if red.batch_cost and runs[key]["details"].get("batch", {}).get("speeds") != red.batch_cost:
            runs[key]["details"]["batch"] = gr.batch_cost(model, C, case, red.step, red.cap, red.batch_cost)
            say(f"{case.label()} | {key}: in a batch of {red.batch_cost} speeds "
                f"{runs[key]['details']['batch']['us_per_speed_step']:.1f} us per speed-step", flush=True)
            store.save()
        _said(case, key, runs[key])


def run_steady_study(config: SteadyStudyConfig, sector=None, ops=None) -> list[CaseResult]:
    """Run (or read back) every run of every case of ``config``; one ``CaseResult`` per case. ``sector``, ``ops``: the
    ci blade and its operators of the cases' law, where the caller has them (None: built here)."""
    from rotor37_rom import fem
    from rotor37_rom.machine import machine_description
    from rotor37_rom.studies.gnl_reference import compare_runs

    store = _Store(config.results, machine_description())
    config.checkpoints.mkdir(parents=True, exist_ok=True)
    sector = fem.create_blade_sector(preset="ci") if sector is None else sector
    ops = fem.create_svk_operators(sector, law=config.cases[0].hyperelastic) if ops is None else ops
    models, results = {}, []
    for case in config.cases:
        runs = store.runs(case)
        if config.full.run:
            _full_order(config, case, runs, store, sector, ops)
        _pod(config, case, runs, store, sector, ops)
        _reduced(config, case, runs, store, models, sector, ops)
        store.save()                                    # merged with the other runs of this case on disk
        runs = store.runs(case)
        full = sorted((k for k in runs if k.startswith("full")), key=lambda k: float(k.split()[2]))
        results.append(CaseResult(case, runs, full[0] if full else None,
                                  compare_runs(case, runs, full[0]) if full else []))
    return results


def map_label(case: SteadyCase, speeds: tuple) -> str:
    """The results file's label of the steady maps of ``case``'s casing and law over ``speeds`` (start, stop, n)."""
    start, stop, n = speeds
    law = "" if case.hyperelastic == "svk" else f" {case.hyperelastic}"
    return (f"map {start:g}-{stop:g} rad/s x {int(n)} mu {case.mu:g} {case.direction} {case.law} "
            f"{case.revolutions} rev{law}")


def run_steady_maps(config: SteadyStudyConfig, speeds: tuple, sector=None, ops=None) -> dict:
    """Each reduced model of ``config`` (r_c x global_md, on its cubature where asked) over ``speeds`` (start, stop,
    n: rad/s) at steady state under the first case's casing, damping and revolutions, GNL off and on
    (``gnl_reference.steady_map``): {run key + ' GNL' / ' linear': map}, kept in the results file under
    ``map_label`` and not run again."""
    from rotor37_rom import fem
    from rotor37_rom.machine import machine_description
    from rotor37_rom.studies import gnl_reference as gr

    start, stop, n = speeds
    real_number("map speeds' start", start, 1.0, 5000.0)
    real_number("map speeds' stop", stop, start, 5000.0, open_low=True)
    if not (isinstance(n, (int, np.integer)) and 2 <= n <= 1000):
        raise ValueError(f"map speeds' count must be an integer in [2, 1000], got {n!r}")
    case, red = config.cases[0], config.reduced
    store = _Store(config.results, machine_description())
    maps = store.data.setdefault(map_label(case, speeds), {})
    sector = fem.create_blade_sector(preset="ci") if sector is None else sector
    ops = fem.create_svk_operators(sector, law=case.hyperelastic) if ops is None else ops
    grid = np.linspace(start, stop, int(n))
    for r_c, g in ((r_c, g) for r_c in red.r_c for g in red.global_md):
        model, C, _ = _model(config, case, r_c, g, sector, ops)
        for nonlinear in (False, True):
            key = red.key(r_c, g) + (" GNL" if nonlinear else " linear")
            if key not in maps:
                maps[key] = gr.steady_map(model, C, case, grid, red.step, red.cap, nonlinear)
                store.save()
            m = maps[key]
            best = int(np.nanargmax(m["value"]))
            say(f"{map_label(case, speeds)} | {key}: largest max |u_LE| {1e3 * m['value'][best]:.3f} mm at "
                f"{m['speeds'][best]:g} rad/s; {sum(m['steady'])} of {len(m['steady'])} speeds steady; "
                f"{m['wall_s']:.0f} s", flush=True)
    store.save()
    return dict(store.runs_of_label(map_label(case, speeds)))
