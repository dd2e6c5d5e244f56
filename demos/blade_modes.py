# # Clamped NASA rotor 37 blade: mesh, first modes, comparison with the paper
#
# The main job (`make demo`). It meshes the blade with gmsh (the built-in parametric blade, and the exact loft of
# NASA Table IV when `../shared/data/rotor37` is present), computes the first clamped modes with SLEPc,
# identifies 1B/1T/2B from the tip LE/TE motion, prints them next to Delhez et al. (2023) §2.2.1, and writes XDMF
# files and pyvista pictures of the mode shapes to `results/blade_modes/`.
#
# Run `python demos/blade_modes.py --help` for options; `mpirun -n 2 python demos/blade_modes.py` also works.

# +
from __future__ import annotations

import argparse
import json
import logging
import sys
import time
from pathlib import Path

import numpy as np
from mpi4py import MPI

from rotor37_rom import fem
from rotor37_rom.geometry.blade import MESH_PRESETS
from rotor37_rom.geometry.tables import default_data_dir, read_hub_shroud_table
from rotor37_rom.modes import PAPER_CLAMPED_OMEGA, classify_blade_modes
from rotor37_rom.plotting import render_mode_shapes, write_xdmf

LOG = logging.getLogger("blade_modes")
# -


# ## One blade: modes, labels, mass and tip clearance

# +
def study_blade(table: Path | None, preset: str, n_modes: int, out: Path, pictures: bool) -> dict:
    comm = MPI.COMM_WORLD
    t0 = time.perf_counter()
    sector = fem.create_blade_sector(comm, table=table, preset=preset)
    modal = fem.compute_clamped_modes(sector, n_modes)
    wall = time.perf_counter() - t0
    labels = classify_blade_modes(modal.tip_displacements, sector.tip_nodes)
    name = "table_iv" if table else "parametric"
    report = {"name": name, "dofs": sector.n_dofs, "omega": modal.omega, "labels": labels,
              "mass": sector.total_mass(), "wall": wall, "clearance": None}
    data = default_data_dir()
    if data is not None:
        casing = read_hub_shroud_table(data / "rotor37hub-shroud.dat")
        tip = sector.tip_nodes
        report["clearance"] = casing.casing_radius(tip[:, 2]) - np.hypot(tip[:, 0], tip[:, 1])
    write_xdmf(sector, modal.modes, out / f"{name}_modes.xdmf")
    if pictures:
        titles = [f"{lab} mode {k + 1}: {w:.0f} rad/s ({name})" for k, (lab, w) in enumerate(zip(labels, modal.omega))]
        render_mode_shapes(sector, modal.modes, titles, out / f"{name}_png")
    return report


def print_report(r: dict) -> None:
    print(f"\n{r['name']} blade: {r['dofs']} DOF, mass {r['mass'] * 1e3:.2f} g, mesh+assembly+modes {r['wall']:.1f} s")
    if r["clearance"] is not None:
        c = r["clearance"] * 1e3
        print(f"tip clearance to the Table V casing, LE..TE: {np.array2string(c, precision=3)} mm")
    print(f"{'mode':>4} {'label':>5} {'omega (rad/s)':>14} {'paper':>8} {'error':>7}")
    for k, (lab, w) in enumerate(zip(r["labels"], r["omega"])):
        ref = PAPER_CLAMPED_OMEGA.get(lab)
        err = f"{100 * (w - ref) / ref:+6.2f}%" if ref else ""
        print(f"{k + 1:>4} {lab:>5} {w:>14.1f} {ref or '':>8} {err:>7}")
# -


# ## Command line

# +
def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--preset", default="coarse", help=f"mesh preset: {', '.join(MESH_PRESETS)}")
    parser.add_argument("--modes", type=int, default=6, help="number of clamped modes (1..50)")
    parser.add_argument("--table", default="auto", help="Table IV file, 'auto' (../shared if present) or 'none'")
    parser.add_argument("--out", default="results/blade_modes", help="output folder")
    parser.add_argument("--no-pictures", action="store_true", help="skip the pyvista PNGs")
    args = parser.parse_args(argv)
    # the FFCx JIT (through setuptools' distutils log) resets the root logger to INFO while compiling: filter at
    # the handler so compiler chatter stays out of the output
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s", force=True)
    logging.getLogger().handlers[0].setLevel(logging.WARNING)
    if not 1 <= args.modes <= 50:
        raise ValueError(f"--modes must be in [1, 50], got {args.modes}")
    tables = [None]
    if args.table == "auto":
        data = default_data_dir()
        if data is not None:
            tables.append(data / "rotor37geometry.dat")
    elif args.table != "none":
        tables.append(Path(args.table))
    out = Path(args.out)
    for table in tables:
        report = study_blade(table, args.preset, args.modes, out, not args.no_pictures)
        if MPI.COMM_WORLD.rank == 0:
            print_report(report)
            summary = {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in report.items()}
            summary.update(preset=args.preset, paper=PAPER_CLAMPED_OMEGA)
            out.mkdir(parents=True, exist_ok=True)
            (out / f"{report['name']}_summary.json").write_text(json.dumps(summary, indent=1, default=float))
    if MPI.COMM_WORLD.rank == 0:
        print(f"\nXDMF and PNG files in {out}/")
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except ValueError as exc:  # bad input: one line, no traceback
        print(f"error: {exc}", file=sys.stderr)
        sys.exit(2)
# -
