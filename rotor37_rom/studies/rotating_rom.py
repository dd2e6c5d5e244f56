"""The turning blade's reduced model against its full order over a speed range (#73):
``run_rotating_rom(RotatingRomConfig)``.

The reduced model that turns (``model.rotating``) carries Omega exactly (M_P, F_c, G: no fitted or interpolated term);
its speed dependence is its basis's: the full-order centrifugal states at a few speeds and, optionally, the first
modes of the blade turning at the top one (``ReductionConfig.spin_snapshots``, ``spin_modes``). Each candidate basis
is built once; at every speed of the grid the full order is solved (``fem.solve_static(spin=...)``,
``fem.rotating_modes``) beside the model (``model.rotating.centrifugal_equilibrium``, ``rotating_modes``), and the
study reports each mode's relative frequency error, the tip's centrifugal displacement error and the cost of a speed
in both. At a snapshot's speed the model's state is the full order's (Galerkin); between snapshots the error is the
basis's.
"""
from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import numpy as np

from rotor37_rom.checks import before_work
from rotor37_rom.geometry.blade import MESH_PRESETS
from rotor37_rom.npz import save_json

__all__ = ["RotatingRomConfig", "RotatingRomResult", "run_rotating_rom", "check_speed_grid"]


def check_speed_grid(preset: str, speeds: tuple) -> float:
    """A turning model's comparison grid checked: the mesh ``preset`` known, ``speeds`` = (start, stop, n) with
    0 <= start < stop (rad/s) and an integer n >= 2; returns stop. One ValueError naming the field otherwise."""
    if preset not in MESH_PRESETS:
        raise ValueError(f"preset must be one of {', '.join(MESH_PRESETS)}, got {preset!r}")
    start, stop, n = speeds
    if not (np.isfinite(start) and np.isfinite(stop) and 0 <= start < stop) or int(n) != n or n < 2:
        raise ValueError(f"speeds: need 0 <= start < stop (rad/s) and n >= 2, got {speeds}")
    return float(stop)


@dataclasses.dataclass(frozen=True)
class RotatingRomConfig:
    """What to compare.

    Attributes:
        preset: mesh preset of the rotor 37 blade.
        r_c, global_md_modes: the basis at rest (``ReductionConfig``).
        candidates: {label: (spin_snapshots, spin_modes)}: the bases compared.
        speeds: (start, stop, n) rad/s, n >= 2, within every candidate's range.
        n_modes: modes compared (1..10).
        out: output folder (the chart and summary.json).
    """

    preset: str = "ci"
    r_c: int = 15
    global_md_modes: int = 3
    candidates: tuple = (("snapshots 1,000 and 2,000 rad/s", (1000.0, 2000.0), 0),
                         ("the same + 4 modes at 2,000 rad/s", (1000.0, 2000.0), 4))
    speeds: tuple = (0.0, 2000.0, 11)
    n_modes: int = 4
    out: Path = Path("results/rotating_rom")

    def __post_init__(self):
        stop = check_speed_grid(self.preset, self.speeds)
        if not 1 <= self.n_modes <= 10:
            raise ValueError(f"n_modes must be in [1, 10], got {self.n_modes}")
        for label, snapshots, modes in self.candidates:
            if not snapshots or max(snapshots) < stop:
                raise ValueError(f"candidate {label!r}: its spin_snapshots must reach the top speed {stop:g} rad/s "
                                 f"(its range), got {snapshots}")
        object.__setattr__(self, "out", Path(self.out))


@dataclasses.dataclass(frozen=True)
class RotatingRomResult:
    """The comparison.

    Attributes:
        speeds: (S,) rad/s; full: (S, n_modes) the full order's frequencies (rad/s).
        rows: per candidate {'label', 'r', 'frequency_error' (S, n_modes) relative, signed, 'state_error' (S,) the
            tip's centrifugal displacement (max over its DOFs, relative to its largest), 'build_s', 'per_speed_s'}.
        full_per_speed_s: the full order's cost of a speed (state and modes).
    """

    speeds: np.ndarray
    full: np.ndarray
    rows: list
    full_per_speed_s: float
    files: list = dataclasses.field(default_factory=list)

    def summary(self) -> dict:
        return {"speeds_rad_s": self.speeds.tolist(), "full_rad_s": self.full.tolist(),
                "full_per_speed_s": self.full_per_speed_s,
                "candidates": [{k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in row.items()}
                               for row in self.rows]}


def run_rotating_rom(config: RotatingRomConfig, sector=None, ops=None) -> RotatingRomResult:
    """Build each candidate's model and compare it with the full order at every speed of ``config``."""
    from rotor37_rom import fem
    from rotor37_rom.model.rotating import centrifugal_equilibrium, rotating_modes
    from rotor37_rom.reduction.builder import ReductionConfig, build_reduced_model

    before_work({"--out": config.out})
    sector = sector if sector is not None else fem.create_blade_sector(preset=config.preset)
    ops = ops or fem.create_svk_operators(sector)
    speeds = np.linspace(*config.speeds)
    tip = sector.tip_dofs.ravel()
    full, states = [], []
    t0 = time.perf_counter()
    for spin in speeds:
        state = fem.solve_static(sector, spin=float(spin), n_steps=2, ops=ops).u.x.array if spin else None
        states.append(np.zeros(tip.size) if state is None else state[tip])
        full.append(fem.rotating_modes(sector, float(spin), config.n_modes, ops, state=state)[0])
    full_per_speed = (time.perf_counter() - t0) / len(speeds)
    full = np.array(full)
    rows = []
    for label, snapshots, modes in config.candidates:
        t0 = time.perf_counter()
        model, _ = build_reduced_model(sector, ReductionConfig(r_c=config.r_c, r_md=0,
                                                               global_md_modes=config.global_md_modes,
                                                               forces="intrusive", spin_snapshots=tuple(snapshots),
                                                               spin_modes=modes), ops=ops)
        build = time.perf_counter() - t0
        q_rows = model.nodes.q_index.ravel()
        freq_err, state_err = [], []
        t0 = time.perf_counter()
        for spin, w_full, u_full in zip(speeds, full, states):
            q_c = centrifugal_equilibrium(model, float(spin))
            w, _ = rotating_modes(model, float(spin), q_c=q_c)
            freq_err.append(w[:config.n_modes] / w_full - 1)
            state_err.append(np.abs(q_c[q_rows] - u_full).max() / np.abs(u_full).max() if spin else 0.0)
        rows.append({"label": label, "r": model.r, "spin_snapshots": list(snapshots), "spin_modes": int(modes),
                     "frequency_error": np.array(freq_err), "state_error": np.array(state_err), "build_s": build,
                     "per_speed_s": (time.perf_counter() - t0) / len(speeds)})
    result = RotatingRomResult(speeds, full, rows, full_per_speed)
    config.out.mkdir(parents=True, exist_ok=True)
    from rotor37_rom.viz.charts import plot_curves

    series = {}
    for row in rows:
        for j in range(config.n_modes):
            series[f"{row['label']} (r = {row['r']}), mode {j + 1}"] = np.maximum(np.abs(row["frequency_error"][:, j]),
                                                                                  1e-12)
    files = [plot_curves(speeds, series, config.out / "rotating_rom_errors.png",
                         f"the turning {config.preset} blade's reduced models against its full order",
                         "angular speed Omega (rad/s)", "relative frequency error", logy=True),
             save_json(config.out / "summary.json", result.summary(), indent=1)]
    return dataclasses.replace(result, files=files)
