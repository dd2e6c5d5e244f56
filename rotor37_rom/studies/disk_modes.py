"""The bladed disk's cyclic modes and SAFE diagram (demos/bladed_disk.py, §3.2, Fig. 15):
``run_bladed_disk(BladedDiskConfig)``.

A disk sector (the blade 4 mm shorter, a rim on the hub line, web and bore clamped at the bore; cyclic faces that
follow the root camber line) is meshed, its left and right faces paired, and the modes of every nodal diameter k = 0 ...
18 computed on the real cos/sin projection of the sector's K and M (``fem.safe.compute_safe_diagram``: K and M are
assembled once and projected for each k). The references: the blade clamped at its root on the same mesh (every disk
DOF fixed: by Rayleigh's theorem of constraint no cyclic frequency can exceed it) and the clamped single blade 4 mm
shorter on its own mesh (the paper's single-blade model). The 1B family is drawn on the whole disk at a few nodal
diameters; rank 0 writes the SAFE diagram and ``<out>/<preset>/summary.json``.

The configuration is checked when it is made (ValueError naming the option); dolfinx is imported by the study itself.
"""
from __future__ import annotations

import dataclasses
import json
import time
from pathlib import Path

import numpy as np

from rotor37_rom.checks import before_work
from rotor37_rom.cli import resolve_table
from rotor37_rom.geometry.blade import MESH_PRESETS
from rotor37_rom.model.modes import classify_blade_modes

__all__ = ["BladedDiskConfig", "BladedDiskResult", "run_bladed_disk"]


@dataclasses.dataclass(frozen=True)
class BladedDiskConfig:
    """preset: mesh preset; table: NASA Table IV (None: the built-in parametric blade); n_modes: distinct modes per
    nodal diameter (1..20); pictures: the 1B family on the whole disk at these nodal diameters (empty: none);
    out: output folder."""

    preset: str = "coarse"
    table: Path | None = None
    n_modes: int = 6
    pictures: tuple = (0, 3, 18)
    out: Path = Path("results/bladed_disk")

    def __post_init__(self):
        if self.preset not in MESH_PRESETS:
            raise ValueError(f"--preset must be one of {', '.join(MESH_PRESETS)}, got {self.preset!r}")
        if not 1 <= self.n_modes <= 20:
            raise ValueError(f"--modes must be in [1, 20], got {self.n_modes}")
        if any(not 0 <= int(k) <= 18 for k in self.pictures):
            raise ValueError(f"--pictures: nodal diameters must be in [0, 18], got {list(self.pictures)}")
        if self.table is not None:
            resolve_table(self.table)                   # reads the file: ValueError naming --table


@dataclasses.dataclass
class BladedDiskResult:
    """The SAFE diagram, the clamped-blade references (rad/s), sizes, timings (s) and the files written."""

    safe: object
    clamped_on_disk: np.ndarray
    clamped_blade: np.ndarray
    dofs: int
    seconds: dict
    files: list


def run_bladed_disk(config: BladedDiskConfig) -> BladedDiskResult:
    """The SAFE diagram of ``config``'s disk sector and its references, over MPI.COMM_WORLD (pictures serially)."""
    from mpi4py import MPI

    from rotor37_rom import fem
    from rotor37_rom.fem.safe import compute_safe_diagram

    comm = MPI.COMM_WORLD
    before_work({"--out": config.out})
    seconds, files = {}, []
    t0 = time.perf_counter()
    sector = fem.create_disk_sector(comm, table=config.table, preset=config.preset)
    seconds["mesh"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    safe = compute_safe_diagram(sector, config.n_modes)
    seconds["safe"] = time.perf_counter() - t0
    on_disk = fem.compute_clamped_modes(fem.clamp_cell_group(sector, "disk"), 3)
    blade = fem.create_blade_sector(comm, table=config.table, preset=config.preset, shorten=4e-3)
    single = fem.compute_clamped_modes(blade, 6)
    labels = classify_blade_modes(single.tip_displacements, blade.tip_nodes)
    clamped_blade = np.array([single.omega[labels.index(f)] for f in ("1B", "1T", "2B")])
    out = Path(config.out) / config.preset
    if comm.rank == 0:
        from rotor37_rom.viz.charts import plot_safe_diagram

        out.mkdir(parents=True, exist_ok=True)
        refs = {f"clamped blade (4 mm shorter) {f}": w for f, w in zip(("1B", "1T", "2B"), clamped_blade)}
        files.append(plot_safe_diagram(safe, out / "safe_diagram.png", refs,
                                       f"rotor 37 bladed disk, {config.preset} ({sector.n_dofs} DOF per sector)"))
    if config.pictures:
        from rotor37_rom.viz.plotting import render_cyclic_mode, write_cyclic_xdmf

        for k in config.pictures:
            modes = fem.solve_cyclic_modes(sector, int(k), config.n_modes)
            row = list(safe.k).index(int(k))
            hit = np.flatnonzero(safe.family[row] == "1B")
            if not hit.size:
                continue
            i = modes.distinct()[1][hit[0]]
            files.append(write_cyclic_xdmf(sector, modes.a[i], modes.b[i], int(k), out / f"mode_1B_k{k}.xdmf"))
            if comm.size == 1:
                files.append(render_cyclic_mode(sector, modes.a[i], modes.b[i], int(k), out / f"mode_1B_k{k}.png",
                                                f"1B family, {k} nodal diameters: {modes.omega[i]:.0f} rad/s"))
    result = BladedDiskResult(safe, on_disk.omega, clamped_blade, sector.n_dofs, seconds, files)
    if comm.rank == 0:
        summary = {"preset": config.preset, "dofs_per_sector": sector.n_dofs, "safe": safe.as_dict(),
                   "clamped_on_disk": on_disk.omega.tolist(), "clamped_blade_1B_1T_2B": clamped_blade.tolist(),
                   "seconds": seconds, "source": sector.source}
        (out / "summary.json").write_text(json.dumps(summary, indent=1))
        files.append(out / "summary.json")
    return result
