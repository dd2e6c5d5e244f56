"""The turning bladed disk's reduced model against the full order on the sector over a speed range (#73):
``run_rotating_disk_rom(RotatingDiskRomConfig)``.

The disk's turning model (``DiskReductionConfig(spin_snapshots=..., spin_modes=...)``: the whole disk's centrifugal
states as index-0 fields in its basis, the first modes of the sector turning at the top speed, the rotation terms
reduced exactly) is built once. At every speed of the grid the full order's nodal-diameter families come from the
cyclic operators of the prestressed, spin-softened sector (``fem.rotating_cyclic_operators``), the model's from its
tangent about its own centrifugal equilibrium (``model.rotating``), each of its modes named by the harmonic index
carrying it (``disk.harmonics.sector_harmonics``); the study reports the lowest frequency of each family in both and
their relative difference, and the cost of a speed in both. Without Coriolis (it splits each family's pair by a few
rad/s: docs/results-rotation.md).
"""
from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import numpy as np
import scipy.linalg

from rotor37_rom.checks import before_work, whole_number
from rotor37_rom.npz import save_json
from rotor37_rom.studies.rotating_rom import check_speed_grid

__all__ = ["RotatingDiskRomConfig", "RotatingDiskRomResult", "run_rotating_disk_rom"]


@dataclasses.dataclass(frozen=True)
class RotatingDiskRomConfig:
    """What to compare.

    Attributes:
        preset: mesh preset of the rotor 37 bladed-disk sector.
        r_c, r_md, r_cyclic: the disk's basis at rest (``DiskReductionConfig``; the tip's node LE kept).
        spin_snapshots: the speeds (rad/s) of the centrifugal states in the basis; spin_modes: modes of the sector
            turning at the top one.
        speeds: (start, stop, n) rad/s, n >= 2, within the snapshots' range.
        families: the nodal diameters compared (each in 0 .. N/2).
        out: output folder (the chart and summary.json).
    """

    preset: str = "ci"
    r_c: int = 8
    r_md: int = 4
    r_cyclic: int = 96
    spin_snapshots: tuple = (1000.0, 2000.0)
    spin_modes: int = 4
    speeds: tuple = (0.0, 2000.0, 5)
    families: tuple = (0, 1, 2, 4, 6, 9, 12, 18)
    out: Path = Path("results/rotating_disk_rom")

    def __post_init__(self):
        stop = check_speed_grid(self.preset, self.speeds)
        if not self.spin_snapshots or max(self.spin_snapshots) < stop:
            raise ValueError(f"spin_snapshots must reach the top speed {stop:g} rad/s, got {self.spin_snapshots}")
        for k in self.families:
            whole_number("families", k, 0, 18)
        for name in ("r_c", "r_md", "r_cyclic", "spin_modes"):
            whole_number(name, getattr(self, name), 0 if name in ("r_md", "spin_modes") else 1)


@dataclasses.dataclass(frozen=True)
class RotatingDiskRomResult:
    """The comparison.

    Attributes:
        speeds: (n,) rad/s; families: (f,) nodal diameters; full, reduced: (n, f) the lowest frequency of each family
        (rad/s); error: (n, f) reduced / full - 1; r: the model's size; build_s: its offline time; full_s, reduced_s:
        the cost of one speed (every family) in each (s); files: what was written.
    """

    speeds: np.ndarray
    families: np.ndarray
    full: np.ndarray
    reduced: np.ndarray
    error: np.ndarray
    r: int
    build_s: float
    full_s: float
    reduced_s: float
    files: list


def _reduced_families(model, spin: float, families) -> np.ndarray:
    """The model's lowest frequency of each family at ``spin`` (rad/s): its prestressed tangent's modes about its
    centrifugal equilibrium, each named by its dominant harmonic index; NaN for a family absent from the 3 N lowest."""
    from rotor37_rom.disk.harmonics import sector_harmonics
    from rotor37_rom.model.rotating import centrifugal_equilibrium, rotating_stiffness

    N = model.nodes.n_sectors
    K_T = rotating_stiffness(model, spin, centrifugal_equilibrium(model, spin))
    lam, V = scipy.linalg.eigh(K_T, 0.5 * (model.M + model.M.T), subset_by_index=[0, 3 * N - 1])
    k = sector_harmonics(V, model.sectors.blocks)
    return np.array([np.sqrt(lam[k == f].min()) if (k == f).any() else np.nan for f in families])


def run_rotating_disk_rom(config: RotatingDiskRomConfig) -> RotatingDiskRomResult:
    """Build the disk's turning model, compare its families with the full order's at every speed, chart and save."""
    from mpi4py import MPI

    from rotor37_rom import fem
    from rotor37_rom.reduction.disk_builder import DiskReductionConfig, build_disk_model
    from rotor37_rom.viz.charts import plot_curves

    before_work({"out": config.out})
    sector = fem.create_disk_sector(MPI.COMM_SELF, preset=config.preset)
    ops = fem.create_svk_operators(sector)
    t0 = time.perf_counter()
    model, _ = build_disk_model(sector, DiskReductionConfig(
        tip_nodes="LE", r_c=config.r_c, r_md=config.r_md, r_cyclic=config.r_cyclic,
        spin_snapshots=config.spin_snapshots, spin_modes=config.spin_modes), ops=ops, cache_dir=config.out / "cache")
    build_s = time.perf_counter() - t0
    speeds = np.linspace(*config.speeds)
    full, reduced, full_s, reduced_s = [], [], 0.0, 0.0
    for spin in speeds:
        t0 = time.perf_counter()
        cyclic, _ = fem.rotating_cyclic_operators(sector, float(spin), ops)
        try:
            full.append([cyclic.modes(k, 2).omega[0] for k in config.families])
        finally:
            cyclic.destroy()
        ops.u.x.array[:] = 0.0
        full_s += time.perf_counter() - t0
        t0 = time.perf_counter()
        reduced.append(_reduced_families(model, float(spin), config.families))
        reduced_s += time.perf_counter() - t0
    full, reduced = np.array(full), np.array(reduced)
    error = reduced / full - 1.0
    chart = plot_curves(speeds, {f"k = {k}": 100 * error[:, j] for j, k in enumerate(config.families)},
                        config.out / "rotating_disk_rom.png",
                        title=f"turning disk model (r = {model.r}) against the full order: lowest mode per nodal "
                              f"diameter", xlabel="angular speed Omega (rad/s)", ylabel="relative error (%)")
    result = RotatingDiskRomResult(speeds, np.asarray(config.families), full, reduced, error, model.r, build_s,
                                   full_s / len(speeds), reduced_s / len(speeds), [chart])
    summary = {"speeds": speeds.tolist(), "families": list(config.families), "full_rad_s": full.tolist(),
               "reduced_rad_s": reduced.tolist(), "error": error.tolist(), "r": model.r, "sizes": model.sizes,
               "build_s": build_s, "full_per_speed_s": result.full_s, "reduced_per_speed_s": result.reduced_s,
               "config": {k: (str(v) if isinstance(v, Path) else v) for k, v in dataclasses.asdict(config).items()}}
    result.files.append(save_json(config.out / "summary.json", summary, indent=1))
    return result
