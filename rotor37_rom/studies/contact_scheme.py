"""The contact-map study's time scheme and GNL forces (demos/contact_map.py): ``time_scheme`` of one setting.

Without GNL the step is ``safety`` x 2 / omega_max (or ``h``). With GNL and ``cubature``, the exact cubic forces are
replaced by point cubature trained on exact GNL runs at 6 of the speeds (``cubature_model``, cached under a key of
the model, the training runs and the tolerance); with a frequency cap the GNL step comes from the tangent frequencies
of the states a GNL run reaches (the cubature's training runs, or a short probe: ``capped_gnl_step``). Under MPI rank
0 trains and the other ranks wait.
"""
from __future__ import annotations

import hashlib
import importlib
import json
import time
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from rotor37_rom.dynamics.turning import Rotation
from rotor37_rom.dynamics.explicit import (CentralDifference, gnl_step_report, largest_states, probe_states, simulate,
    training_speeds)
from rotor37_rom.model.reduced import (ReducedModel, load_reduced_model, perturbed_model, save_reduced_model,
    with_force_precision)
from rotor37_rom.npz import load_npz, save_npz
from rotor37_rom.studies.contact_config import ContactMapConfig
from rotor37_rom.studies.sweep import idle_barrier
from rotor37_rom.reporting import say

if TYPE_CHECKING:
    from mpi4py import MPI

__all__ = ["time_scheme", "turning", "setting_names", "cubature_model", "capped_probe", "capped_gnl_step",
           "capped_probe_states", "print_step_outliers"]


def cubature_model(config: ContactMapConfig, model: ReducedModel, comm: MPI.Comm | None
                   ) -> tuple[ReducedModel, np.ndarray]:
    """The model with point-cubature GNL forces trained on exact GNL runs at 6 of the speeds (trajectory states), and
    the states the GNL step is taken over (those runs' 24 of largest tip motion and the training states). Cached in
    ``config.cache_dir``: a restarted map does not retrain, and another tolerance reuses the exact training runs.
    Under MPI rank 0 trains (serial FE quadrature on its own copy of the mesh) while the others wait."""
    importlib.import_module("rotor37_rom.fem")    # on every rank: importing dolfinx initializes PETSc (collective)
    train = training_speeds(config.speed_grid) if config.scheme.cubature_speeds is None else \
        np.asarray(config.scheme.cubature_speeds, float)
    revolutions = min(config.sweep.revolutions, 12.0)
    if capped_probe(config, model):
        # a disk's unscaled GNL step (~5e-8 s) would make the training runs hours long: they run capped, at the
        # tangent limit on the capped probe's states (exact forces); a blade's with --capped-training. The training
        # runs take the step from every probe state (--step-outliers is the map's): a step check at 'keep' then
        # finds the same cubature
        scheme = CentralDifference(model, nonlinear=True, safety=config.scheme.safety,
                                   frequency_cap=config.scheme.frequency_cap_rad_s,
                                   h=config.scheme.h or capped_gnl_step(config.with_options(step_outliers="keep"),
                                                                  model, model, None,
                                                                  verbose=comm is None or comm.rank == 0))
    else:
        scheme = CentralDifference(model, nonlinear=True, safety=config.scheme.safety)
    # h to 12 digits: its last bits follow the BLAS's summation order (1 or 2 threads), the caches' keys must not
    runs = [model.key, train.tolist(), revolutions, float(f"{scheme.h:.12g}"), vars(config.sweep.casing)]
    key = hashlib.sha256(json.dumps(runs + [config.scheme.cubature, "step states: largest and training"],
                                    sort_keys=True, default=str).encode()).hexdigest()[:16]
    cache = config.cache_dir / f"cubature_{key}.npz"
    runs_key = json.dumps(runs + ["states every 1e-5 s; step states: largest and training"], sort_keys=True,
                          default=str)
    runs_cache = config.cache_dir / f"training_runs_{hashlib.sha256(runs_key.encode()).hexdigest()[:16]}.npz"
    rank = 0 if comm is None else comm.rank
    if cache.is_file():
        if rank == 0:
            say(f"cubature: reusing {cache}")
    else:
        error = None
        if rank == 0:
            try:
                _train_cubature(config, model, scheme, train, revolutions, cache, runs_cache)
            except ValueError as exc:
                error = str(exc)
        if comm is not None:
            idle_barrier(comm)
            error = comm.bcast(error, root=0)
        if error is not None:
            raise ValueError(error)
    with np.load(cache.with_suffix(".states.npz")) as data:
        states = data["states"]
    return load_reduced_model(cache), states


def _train_cubature(config: ContactMapConfig, model: ReducedModel, scheme: CentralDifference, train: np.ndarray,
                    revolutions: float, cache: Path, runs_cache: Path) -> None:
    """Train the point cubature on exact GNL runs at ``train`` (their states kept in ``runs_cache``, for another
    tolerance) and save it with the step states to ``cache``."""
    from mpi4py import MPI

    from rotor37_rom.reduction.builder import hyper_reduce
    from rotor37_rom.dynamics.explicit import contact_training_states

    casing = config.sweep.casing
    t0 = time.perf_counter()
    runs = load_npz(runs_cache, ("train", "step"), what="training runs")
    if runs is not None:
        Q_train, step_states = runs["train"], runs["step"]
    else:
        checkpoint = runs_cache.with_suffix(".ckpt.npz")
        Q_train, step_states = contact_training_states(scheme, train, casing, revolutions, checkpoint=checkpoint)
        save_npz(runs_cache, train=Q_train, step=step_states)
        checkpoint.unlink(missing_ok=True)
    sector = config.rom.create_sector(MPI.COMM_SELF)
    reduced, rep = hyper_reduce(sector, model, Q_train, tol=config.scheme.cubature, level="point",
                                label=f"contact runs {train.tolist()} x {revolutions:g} rev, mu = {casing.mu:g}")
    say(f"cubature: {rep['points']} of {rep['exact'].w.size} quadrature points (training error "
          f"{rep['result'].training_error:.1e}) from {Q_train.shape[1]} states of exact GNL runs at "
          f"{len(train)} speeds x {revolutions:g} rev; {time.perf_counter() - t0:.0f} s")
    save_npz(cache.with_suffix(".states.npz"), states=step_states)
    save_reduced_model(reduced, cache)                  # written last: its presence means both are complete


def capped_probe(config: ContactMapConfig, model: ReducedModel) -> bool:
    """Whether the GNL training runs and step probe run with the frequency cap: a disk's always (its unscaled step
    is ~5e-8 s), a blade's with --capped-training."""
    return config.scheme.frequency_cap is not None and (model.sectors is not None or config.scheme.capped_training)


def capped_gnl_step(config: ContactMapConfig, model: ReducedModel, run_model: ReducedModel,
                    states: np.ndarray | None, verbose: bool = True) -> float:
    """The GNL step with a frequency cap, from the tangent limit on ``states`` (None: on a short unscaled probe;
    for a disk, whose unscaled step is ~5e-8 s, or with --capped-training, a capped GNL probe at 4 of the speeds,
    its 8 largest states)."""
    if states is None:
        revolutions = min(4.0, config.sweep.revolutions)
        if capped_probe(config, model):
            probe = training_speeds(config.speed_grid, 4)
            states, h_probe = capped_probe_states(config, model, probe, revolutions)
            kind = f"capped (h = {h_probe:.3g} s)"
        else:
            probe = config.speed_grid[:: max(1, config.speeds[2] // 16)]
            states = probe_states(model, probe, config.sweep.casing, revolutions=revolutions,
                                  rotation=turning(config))
            kind = "unscaled"
        if verbose:
            say(f"GNL step from the tangent limit on a {revolutions:g}-revolution {kind} probe at {len(probe)} "
                  f"speeds")
    step = gnl_step_report(run_model, states, config.scheme.frequency_cap_rad_s, safety=config.scheme.tangent_safety,
                           cap_safety=config.scheme.safety)
    drop = config.scheme.step_outliers == "drop" and step["h_without_outliers"] > step["h"]
    h = step["h_without_outliers"] if drop else step["h"]
    if verbose:
        say(f"GNL with a {config.scheme.frequency_cap:g} kHz cap: h = {h:.3g} s")
        print_step_outliers(step, dropped=drop)
    return h


def print_step_outliers(step: dict, dropped: bool = False) -> None:
    """A line when a few states set the GNL step far below the others' (``dynamics.explicit.step_outliers``), and
    whether the step was taken without them (--step-outliers drop)."""
    out = step["outliers"]
    if out.size and step["h_without_outliers"] > step["h"]:
        w = step["w_states"]
        ratio = step["h_without_outliers"] / step["h"]
        head = (f"note: {out.size} of {w.size} states would set the GNL step: their tangent's highest frequency "
                f"reaches {w[out].max() / 2e3 / np.pi:.4g} kHz, the others' at most "
                f"{np.delete(w, out).max() / 2e3 / np.pi:.4g} kHz; ")
        if dropped:
            tail = (f"--step-outliers drop takes the step without them, {ratio:.1f} times the {step['h']:.3g} s they "
                    f"set; a run that stays near such a state blows up and is flagged, a brief pass may not "
                    f"(benchmarks/bench_gnl_vs_linear.py --step-check measures the error).")
        else:
            tail = (f"without them the step would be {step['h_without_outliers']:.3g} s, so the GNL runs at this "
                    f"step take {ratio:.1f} times as many steps (--step-outliers drop). Such states may be where the "
                    f"St. Venant-Kirchhoff model collapses under a point contact (docs/results.md, 'GNL against "
                    f"linear with the paper's friction').")
        say(head + tail)


def capped_probe_states(config: ContactMapConfig, model: ReducedModel, probe: np.ndarray, revolutions: float
                        ) -> tuple[np.ndarray, float]:
    """The 8 largest states of a capped GNL run of the disk or blade (exact forces) at the ``probe`` speeds, its step
    halved until no speed blows up (the capped modes stiffen with the amplitude), and that step. Cached in
    ``config.cache_dir`` (a resumed map does not probe again; every rank computes or reads the same)."""
    scheme = CentralDifference(model, nonlinear=True, safety=config.scheme.safety,
                               frequency_cap=config.scheme.frequency_cap_rad_s, rotation=turning(config))
    # the step to 12 digits: its last bits follow the BLAS's summation order (the thread count), the key must not
    key = json.dumps([model.key, probe.tolist(), revolutions, float(f"{scheme.h:.12g}"), scheme.frequency_cap,
                      vars(config.sweep.casing), "8 largest states"]
                     + ([] if scheme.rotation is None else [vars(scheme.rotation)]),
                     sort_keys=True, default=str)
    cache = config.cache_dir / f"gnl_probe_{hashlib.sha256(key.encode()).hexdigest()[:16]}.npz"
    cached = load_npz(cache, ("states", "h"), what="probe")
    if cached is not None:
        return cached["states"], float(cached["h"])
    for _ in range(5):
        res = simulate(scheme, probe, config.sweep.casing, revolutions=revolutions, on_blowup="flag", record_q=True,
                       record_every=max(1, int(round(2e-5 / scheme.h))))
        if (res.diverged_step < 0).all():
            break
        scheme = scheme.with_step(scheme.h / 2)
    else:
        raise ValueError(f"--h: the capped GNL probe diverged down to h = {scheme.h:.3g} s; give a smaller "
                         f"step or a higher --frequency-cap")
    states = largest_states(res, scheme.boundary_rows, 8)
    save_npz(cache, states=states, h=scheme.h)           # ranks may write it side by side
    return states, scheme.h


def time_scheme(config: ContactMapConfig, model: ReducedModel, gnl: bool, comm: MPI.Comm | None,
                h: float | None = None) -> CentralDifference:
    """The central-difference scheme of one setting: its forces (exact or cubature), step and frequency cap; with a
    perturbation, the perturbed model's scheme with the same cap at the unperturbed model's step (the cap applies to
    the perturbed model: its modes above the cap stay at the cap, their capped mass scaled with their stiffness).
    ``h``: the step to run at instead of the setting's (a record's own, e.g. a retried speed's); the forces stay the
    setting's (a disk's cubature is trained at the setting's step, so replacing ``config.scheme.h`` would train
    another)."""
    run_model, states, h = model, None, config.scheme.h if h is None else h
    if gnl and config.scheme.cubature is not None:
        run_model, states = cubature_model(config, model, comm)
        run_model = with_force_precision(run_model, config.scheme.precision)
    if gnl and config.scheme.frequency_cap is not None and h is None:
        h = capped_gnl_step(config, model, run_model, states, verbose=comm is None or comm.rank == 0)
    scheme = CentralDifference(run_model, nonlinear=gnl, h=h, safety=config.scheme.safety,
                               frequency_cap=config.scheme.frequency_cap_rad_s, rotation=turning(config))
    if not config.scheme.perturbation:
        return scheme
    return CentralDifference(perturbed_model(run_model, config.scheme.perturbation), nonlinear=gnl, h=scheme.h,
                             frequency_cap=config.scheme.frequency_cap_rad_s, rotation=turning(config))


def turning(config: ContactMapConfig) -> Rotation | None:
    """The rotation of the map's scheme (``dynamics.turning.Rotation``; None: the blade at rest)."""
    return None if config.scheme.rotation is None else Rotation(clearance=config.scheme.rotation)


def setting_names(config: ContactMapConfig, gnl: bool) -> tuple[str, str]:
    """(chart label, file tag) of one setting, e.g. ('GNL, cubature 0.0001, single', 'gnl_cub0.0001_f32')."""
    parts = [("GNL", "gnl") if gnl else ("no GNL", "linear")]
    if gnl and config.scheme.cubature is not None:
        parts.append((f"cubature {config.scheme.cubature:g}", f"cub{config.scheme.cubature:g}"))
        if config.scheme.precision == "single":
            parts.append(("single", "f32"))
    if config.scheme.frequency_cap is not None:
        parts.append((f"cap {config.scheme.frequency_cap:g} kHz", f"cap{config.scheme.frequency_cap:g}k"))
    if config.scheme.perturbation:
        parts.append((f"x (1 + {config.scheme.perturbation:g})", f"pert{config.scheme.perturbation:g}"))
    if config.scheme.rotation is not None:
        parts.append((f"turning, {config.scheme.rotation} clearance", f"turning_{config.scheme.rotation}"))
    return ", ".join(p[0] for p in parts), "_".join(p[1] for p in parts)
