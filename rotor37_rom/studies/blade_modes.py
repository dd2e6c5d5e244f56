"""The clamped blade's modes against the paper (demos/blade_modes.py, §2.2.1): ``run_blade_modes(BladeModesConfig)``.

The blade is meshed with gmsh (the built-in parametric blade, and the exact loft of NASA Table IV when
``../shared/data/rotor37`` is present or ``table`` names the file), its first clamped modes computed with SLEPc,
1B/1T/2B identified from the motion of the tip's leading and trailing edges (``model.modes.classify_blade_modes``:
bending moves them together, torsion in opposite senses), and the frequencies compared with Delhez et al. (2023). XDMF
files, pyvista pictures of the mode shapes and one summary JSON per blade go to ``out``.

The configuration is checked when it is made (ValueError naming the option; a ``table`` that is not a NASA Table IV is
refused before any meshing); dolfinx is imported only by the study itself.
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
from rotor37_rom.model.modes import PAPER_CLAMPED_OMEGA

__all__ = ["BladeModesConfig", "BladeModes", "BladeModesResult", "run_blade_modes", "study_blade", "write_summary"]


@dataclasses.dataclass(frozen=True)
class BladeModesConfig:
    """The blades and modes to compute.

    Attributes:
        preset: mesh preset: ci, coarse or paper.
        n_modes: clamped modes per blade (1..50).
        table: 'auto' (also the exact loft of the shared NASA Table IV, when present), 'none' (the parametric blade
            only) or a Table IV file (the parametric blade and the loft of that file).
        out: output folder (XDMF, pictures, one summary JSON per blade).
        pictures: draw the mode shapes (pyvista PNGs; serial runs only).
    """

    preset: str = "coarse"
    n_modes: int = 6
    table: str = "auto"
    out: Path = Path("results/blade_modes")
    pictures: bool = True

    def __post_init__(self):
        if self.preset not in MESH_PRESETS:
            raise ValueError(f"--preset must be one of {', '.join(MESH_PRESETS)}, got {self.preset!r}")
        if not 1 <= self.n_modes <= 50:
            raise ValueError(f"--modes must be in [1, 50], got {self.n_modes}")
        object.__setattr__(self, "table", str(self.table))
        object.__setattr__(self, "out", Path(self.out))
        resolve_table(self.table)                     # reads a given file: ValueError naming --table

    @property
    def blades(self) -> list[Path | None]:
        """The blades to study: None (the parametric blade), then the Table IV loft if any."""
        table = resolve_table(self.table)
        return [None] if table is None else [None, table]


@dataclasses.dataclass(frozen=True)
class BladeModes:
    """One blade's modes.

    Attributes:
        name: 'parametric' or 'table_iv'.
        dofs: number of DOFs; mass: blade mass (kg).
        omega: clamped angular eigenfrequencies (rad/s), ascending; labels: '1B', '1T', '2B', ... per mode.
        clearance: tip clearance of the tip nodes (LE..TE) to the NASA Table V casing line (m), None without the
            shared data.
        wall: mesh + assembly + eigen-solve (s).
    """

    name: str
    dofs: int
    mass: float
    omega: np.ndarray
    labels: list[str]
    clearance: np.ndarray | None
    wall: float

    @property
    def paper_errors(self) -> dict[str, float]:
        """Relative error against the paper of each identified 1B / 1T / 2B mode (first of each label)."""
        return {lab: self.frequency(lab) / ref - 1.0 for lab, ref in PAPER_CLAMPED_OMEGA.items()
                if lab in self.labels}

    def frequency(self, label: str) -> float:
        """The first mode of ``label`` (rad/s); NaN if none was identified."""
        return float(next((w for lab, w in zip(self.labels, self.omega) if lab == label), np.nan))


@dataclasses.dataclass(frozen=True)
class BladeModesResult:
    """The blades studied (parametric first) and the files written."""

    blades: list[BladeModes]
    files: list[Path]


def study_blade(config: BladeModesConfig, table: Path | None, comm) -> tuple[BladeModes, list[Path]]:
    """Mesh one blade, compute its clamped modes, write the XDMF (and PNGs); returns its modes and the files."""
    from rotor37_rom import fem
    from rotor37_rom.geometry.tables import default_data_dir, read_hub_shroud_table
    from rotor37_rom.model.modes import classify_blade_modes
    from rotor37_rom.viz.plotting import render_mode_shapes, write_xdmf

    t0 = time.perf_counter()
    sector = fem.create_blade_sector(comm, table=table, preset=config.preset)
    modal = fem.compute_clamped_modes(sector, config.n_modes)
    wall = time.perf_counter() - t0
    labels = classify_blade_modes(modal.tip_displacements, sector.tip_nodes)
    name = "table_iv" if table else "parametric"
    clearance = None
    data = default_data_dir()
    if data is not None:
        casing = read_hub_shroud_table(data / "rotor37hub-shroud.dat")
        tip = sector.tip_nodes
        clearance = casing.casing_radius(tip[:, 2]) - np.hypot(tip[:, 0], tip[:, 1])
    files = [write_xdmf(sector, modal.modes, config.out / f"{name}_modes.xdmf")]
    if config.pictures and comm.size == 1:
        titles = [f"{lab} mode {k + 1}: {w:.0f} rad/s ({name})" for k, (lab, w) in enumerate(zip(labels, modal.omega))]
        files += render_mode_shapes(sector, modal.modes, titles, config.out / f"{name}_png")
    blade = BladeModes(name, sector.n_dofs, sector.total_mass(), np.asarray(modal.omega), list(labels), clearance,
                       wall)
    return blade, files


def write_summary(config: BladeModesConfig, blade: BladeModes) -> Path:
    """``<out>/<name>_summary.json``: the blade's numbers next to the paper's."""
    summary = {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in dataclasses.asdict(blade).items()}
    summary.update(preset=config.preset, paper=PAPER_CLAMPED_OMEGA)
    config.out.mkdir(parents=True, exist_ok=True)
    path = config.out / f"{blade.name}_summary.json"
    path.write_text(json.dumps(summary, indent=1, default=float))
    return path


def run_blade_modes(config: BladeModesConfig, comm=None) -> BladeModesResult:
    """Modes of every blade of ``config``; ``comm``: the communicator of the meshes (None: MPI.COMM_WORLD)."""
    from mpi4py import MPI

    comm = comm or MPI.COMM_WORLD
    before_work({"--out": config.out})
    blades, files = [], []
    for table in config.blades:
        blade, written = study_blade(config, table, comm)
        blades.append(blade)
        files += written
        if comm.rank == 0:
            files.append(write_summary(config, blade))
    return BladeModesResult(blades, files)
