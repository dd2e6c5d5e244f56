"""The bladed disk's cyclic modes and SAFE diagram (demos/bladed_disk.py, §3.2, Fig. 15):
``run_bladed_disk(BladedDiskConfig)``.

A disk sector (the blade 4 mm shorter, a rim on the hub line, web and bore clamped at the bore; cyclic faces that
follow the root camber line) is meshed, its left and right faces paired, and the modes of every nodal diameter k = 0 ...
18 computed on the real cos/sin projection of the sector's K and M (``fem.safe.compute_safe_diagram``: K and M are
assembled once and projected for each k). The references: the blade clamped at its root on the same mesh (every disk
DOF fixed: by Rayleigh's theorem of constraint no cyclic frequency can exceed it) and the clamped single blade 4 mm
shorter on its own mesh (the paper's single-blade model). The 1B family is drawn on the whole disk at a few nodal
diameters; rank 0 writes the SAFE diagram and ``<out>/<preset>/summary.json``.

A user's bladed-disk sector (``config.mesh``, a ``studies.sector_file.SectorFile`` with its cyclic faces and sector
count) goes through the same steps: its SAFE diagram over k = 0 ... N/2 (labelled blade or disk where the file gives
the blade's element set), the blade clamped on its disk where it has one, its mode pictures; the rotor 37 single
blade's references are left out.

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
from rotor37_rom.studies.sector_file import SectorFile

__all__ = ["BladedDiskConfig", "BladedDiskResult", "run_bladed_disk"]


@dataclasses.dataclass(frozen=True)
class BladedDiskConfig:
    """preset: mesh preset; table: NASA Table IV (None: the built-in parametric blade); n_modes: distinct modes per
    nodal diameter (1..20); pictures: the 1B family (a user's sector: its lowest mode) on the whole disk at these
    nodal diameters (empty: none); out: output folder; mesh: a user's bladed-disk sector instead of rotor 37's (its
    cyclic faces and sector count given); nodal_diameters: the harmonic indices of the SAFE diagram (None: all, 0 ...
    N/2); show_groups: draw the user's sector's groups on its mesh (``<out>/own/groups.png``) and stop."""

    preset: str = "coarse"
    table: Path | None = None
    n_modes: int = 6
    pictures: tuple = (0, 3, 18)
    out: Path = Path("results/bladed_disk")
    mesh: SectorFile | None = None
    nodal_diameters: tuple | None = None
    show_groups: bool = False

    def __post_init__(self):
        if self.preset not in MESH_PRESETS:
            raise ValueError(f"--preset must be one of {', '.join(MESH_PRESETS)}, got {self.preset!r}")
        if not 1 <= self.n_modes <= 20:
            raise ValueError(f"--modes must be in [1, 20], got {self.n_modes}")
        if self.mesh is not None:
            if not isinstance(self.mesh, SectorFile):
                raise TypeError(f"mesh must be a SectorFile or None, got {self.mesh!r}")
            if self.mesh.cyclic is None:
                raise ValueError("--mesh: a bladed-disk sector needs its cyclic faces and count: give --left, --right "
                                 "and --n-sectors")
            if self.table is not None:
                raise ValueError("--table shapes rotor 37's blade: not with --mesh (your own sector)")
        half = self.n_sectors // 2
        if self.nodal_diameters is not None:
            if not self.nodal_diameters or any(not 0 <= int(k) <= half for k in self.nodal_diameters):
                raise ValueError(f"--nodal-diameters must be in [0, {half}], got {list(self.nodal_diameters)}")
            object.__setattr__(self, "nodal_diameters", tuple(sorted({int(k) for k in self.nodal_diameters})))
        if any(not 0 <= int(k) <= half for k in self.pictures):
            raise ValueError(f"--pictures: nodal diameters must be in [0, {half}], got {list(self.pictures)}")
        if self.nodal_diameters is not None and not set(map(int, self.pictures)) <= set(self.nodal_diameters):
            raise ValueError(f"--pictures {list(self.pictures)}: draw nodal diameters the SAFE diagram computes "
                             f"(--nodal-diameters {list(self.nodal_diameters)})")
        if self.table is not None:
            resolve_table(self.table)                   # reads the file: ValueError naming --table
        if self.show_groups and self.mesh is None:
            raise ValueError("--show-groups draws your own sector's groups: give --mesh")

    @property
    def n_sectors(self) -> int:
        """N: the user's sector count, else rotor 37's 36."""
        return 36 if self.mesh is None else self.mesh.n_sectors


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
    own = config.mesh is not None
    sector = config.mesh.create(comm) if own else fem.create_disk_sector(comm, table=config.table,
                                                                         preset=config.preset)
    seconds["mesh"] = time.perf_counter() - t0
    out = Path(config.out) / ("own" if own else config.preset)
    if config.show_groups:
        from rotor37_rom.studies.own_blade import show_groups

        files = [show_groups(sector, out)] if comm.rank == 0 else []
        return BladedDiskResult(None, np.zeros(0), np.zeros(0), sector.n_dofs, seconds, files)
    t0 = time.perf_counter()
    safe = compute_safe_diagram(sector, config.n_modes, ks=config.nodal_diameters)
    seconds["safe"] = time.perf_counter() - t0
    on_disk = fem.compute_clamped_modes(fem.clamp_cell_group(sector, "disk"), 3).omega if "disk" in sector.groups \
        else np.zeros(0)
    clamped_blade, refs = np.zeros(0), {}
    if not own:
        blade = fem.create_blade_sector(comm, table=config.table, preset=config.preset, shorten=4e-3)
        single = fem.compute_clamped_modes(blade, 6)
        labels = classify_blade_modes(single.tip_displacements, blade.tip_nodes)
        clamped_blade = np.array([single.omega[labels.index(f)] for f in ("1B", "1T", "2B")])
        refs = {f"clamped blade (4 mm shorter) {f}": w for f, w in zip(("1B", "1T", "2B"), clamped_blade)}
    refs.update({f"blade clamped on the disk {j + 1}": w for j, w in enumerate(on_disk[:1])} if own else {})
    name = f"{config.mesh.path.name}, N = {config.n_sectors}" if own else f"rotor 37 bladed disk, {config.preset}"
    if comm.rank == 0:
        from rotor37_rom.viz.charts import plot_safe_diagram

        out.mkdir(parents=True, exist_ok=True)
        files.append(plot_safe_diagram(safe, out / "safe_diagram.png", refs,
                                       f"{name} ({sector.n_dofs} DOF per sector)"))
    if config.pictures:
        from rotor37_rom.viz.plotting import render_cyclic_mode, write_cyclic_xdmf

        for k in config.pictures:
            modes = fem.solve_cyclic_modes(sector, int(k), config.n_modes)
            row = list(safe.k).index(int(k))
            label = "1B" if (safe.family[row] == "1B").any() else safe.family[row][0]
            hit = np.flatnonzero(safe.family[row] == label)
            if not hit.size:
                continue
            i = modes.distinct()[1][hit[0]]
            stem = f"mode_{label.replace(' ', '')}_k{k}"
            files.append(write_cyclic_xdmf(sector, modes.a[i], modes.b[i], int(k), out / f"{stem}.xdmf"))
            if comm.size == 1:
                files.append(render_cyclic_mode(sector, modes.a[i], modes.b[i], int(k), out / f"{stem}.png",
                                                f"{label}, {k} nodal diameters: {modes.omega[i]:.0f} rad/s"))
    result = BladedDiskResult(safe, on_disk, clamped_blade, sector.n_dofs, seconds, files)
    if comm.rank == 0:
        summary = {"preset": None if own else config.preset, "input": config.mesh.as_dict() if own else None,
                   "n_sectors": config.n_sectors, "dofs_per_sector": sector.n_dofs, "safe": safe.as_dict(),
                   "clamped_on_disk": on_disk.tolist(), "clamped_blade_1B_1T_2B": clamped_blade.tolist(),
                   "seconds": seconds, "source": sector.source}
        (out / "summary.json").write_text(json.dumps(summary, indent=1))
        files.append(out / "summary.json")
    return result
