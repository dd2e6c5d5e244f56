# # Clamped NASA rotor 37 blade: mesh, first modes, comparison with the paper (§2.2.1)
#
# The blade is meshed with gmsh (the built-in parametric blade, and the exact loft of NASA Table IV when
# `../shared/data/rotor37` is present or `--table` names the file), its first clamped modes are computed with SLEPc,
# 1B/1T/2B are identified from the motion of the tip's leading and trailing edges, and the frequencies are compared
# with Delhez et al. (2023): 5272 / 15760 / 19071 rad/s. XDMF files and pyvista pictures of the mode shapes go to
# `results/blade_modes/`.
#
#     python demos/blade_modes.py --preset coarse        # about a minute
#     mpirun -n 2 python demos/blade_modes.py             # the eigen-solves on two ranks (no pictures)
#
# The study is one function, `run_blade_modes(BladeModesConfig(...))`, which returns a `BladeModesResult`; the
# command line only turns its options into that configuration. A bad option is one line on stderr, exit status 2.

# +
from __future__ import annotations

import dataclasses
import json
import logging
import sys
import time
from pathlib import Path
from typing import Sequence

import numpy as np

from rotor37_rom.cli import TABLE_HELP, ArgumentParser, resolve_table, run_main
from rotor37_rom.geometry.blade import MESH_PRESETS
from rotor37_rom.post.modes import PAPER_CLAMPED_OMEGA

LOG = logging.getLogger("blade_modes")
# -


# ## What to compute
#
# A frozen configuration, checked when it is made: a bad value is a ValueError naming the option and its range, and
# a `--table` that is not a NASA Table IV is refused here, before any meshing.

# +
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
# -


# ## One blade: mesh, modes, labels, mass and tip clearance
#
# The labels come from the tip: bending moves the leading and trailing edges together, torsion in opposite senses
# (`rotor37_rom.post.modes.classify_blade_modes`).

# +
def study_blade(config: BladeModesConfig, table: Path | None, comm) -> tuple[BladeModes, list[Path]]:
    """Mesh one blade, compute its clamped modes, write the XDMF (and PNGs); returns its modes and the files."""
    from rotor37_rom import fem
    from rotor37_rom.geometry.tables import default_data_dir, read_hub_shroud_table
    from rotor37_rom.post.modes import classify_blade_modes
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
# -


# ## The study
#
# Every blade in turn; under `mpirun` the meshes are distributed and rank 0 writes the summaries.

# +
def run_blade_modes(config: BladeModesConfig, comm=None) -> BladeModesResult:
    """Modes of every blade of ``config``; ``comm``: the communicator of the meshes (None: MPI.COMM_WORLD)."""
    from mpi4py import MPI

    comm = comm or MPI.COMM_WORLD
    blades, files = [], []
    for table in config.blades:
        blade, written = study_blade(config, table, comm)
        blades.append(blade)
        files += written
        if comm.rank == 0:
            files.append(write_summary(config, blade))
    return BladeModesResult(blades, files)
# -


# ## Command line

# +
def print_report(result: BladeModesResult, out: Path) -> None:
    """The frequencies of each blade next to the paper's."""
    for r in result.blades:
        print(f"\n{r.name} blade: {r.dofs} DOF, mass {r.mass * 1e3:.2f} g, mesh+assembly+modes {r.wall:.1f} s")
        if r.clearance is not None:
            print(f"tip clearance to the Table V casing, LE..TE: {np.array2string(r.clearance * 1e3, precision=3)} mm")
        print(f"{'mode':>4} {'label':>5} {'omega (rad/s)':>14} {'paper':>8} {'error':>7}")
        for k, (lab, w) in enumerate(zip(r.labels, r.omega)):
            ref = PAPER_CLAMPED_OMEGA.get(lab)
            err = f"{100 * (w - ref) / ref:+6.2f}%" if ref else ""
            print(f"{k + 1:>4} {lab:>5} {w:>14.1f} {ref or '':>8} {err:>7}")
    print(f"\nXDMF and PNG files in {out}/")


def build_parser() -> ArgumentParser:
    parser = ArgumentParser(description="clamped modes of the rotor 37 blade against the paper")
    parser.add_argument("--preset", default="coarse", help=f"mesh preset: {', '.join(MESH_PRESETS)} (default coarse)")
    parser.add_argument("--modes", type=int, default=6, help="number of clamped modes (1..50, default 6)")
    parser.add_argument("--table", default="auto", help=TABLE_HELP + " (default auto)")
    parser.add_argument("--out", type=Path, default=Path("results/blade_modes"), help="output folder")
    parser.add_argument("--no-pictures", action="store_true", help="skip the pyvista PNGs")
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Parse the options, run the study, print the table; raises ValueError for a bad input."""
    args = build_parser().parse_args(argv)
    config = BladeModesConfig(preset=args.preset, n_modes=args.modes, table=args.table, out=args.out,
                              pictures=not args.no_pictures)
    # the FFCx JIT (through setuptools' distutils log) resets the root logger to INFO while compiling: filter at
    # the handler so compiler chatter stays out of the output
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s", force=True)
    logging.getLogger().handlers[0].setLevel(logging.WARNING)
    result = run_blade_modes(config)
    from mpi4py import MPI

    if MPI.COMM_WORLD.rank == 0:
        print_report(result, config.out)
    return 0


if __name__ == "__main__":
    sys.exit(run_main(main))
# -
