# # NASA rotor 37 bladed disk: the sector, its cyclic symmetry and the SAFE diagram (paper §3.2, Fig. 15)
#
# A disk sector (the blade 4 mm shorter, a rim on the hub line, web and bore clamped at the bore; cyclic faces that
# follow the root camber line) is meshed with gmsh, its left and right faces paired, and the modes of every nodal
# diameter k = 0 ... 18 computed with SLEPc on the real cos/sin projection of the sector's K and M. Each mode is
# labelled blade-dominated (1B, 1T, 2B from the tip motion) or disk-dominated (share of strain energy in the disk),
# drawn in a SAFE diagram next to the clamped blade's frequencies, and the 1B family is drawn on the whole disk.
#
# `python demos/bladed_disk.py --preset coarse` (about 4 min); results in `results/bladed_disk/<preset>/`.
# `mpirun -n 2 python demos/bladed_disk.py` runs the eigen-solves on two ranks (pictures are drawn serially).
#
# Your own bladed-disk sector (a mesh file whose left and right faces match under the rotation by 2 pi / N about +z):
#
#     python demos/bladed_disk.py --mesh sector.inp --clamp BORE --left LEFT --right RIGHT --n-sectors 24 \
#         --tip TIP --blade BLADE --units mm
#
# gives its SAFE diagram over k = 0 ... N/2 and mode pictures in `results/bladed_disk/own/` (modes labelled 1B, 1T,
# ... or disk where --blade names the blade's element set and --tip its tip).
#
# The study is one library function, `run_bladed_disk(BladedDiskConfig(...))` of `rotor37_rom.studies.disk_modes`;
# this script turns its options into that configuration and prints the table. A bad option is one line on stderr,
# exit status 2.

# +
from __future__ import annotations

import logging
import sys
from pathlib import Path

import numpy as np

from rotor37_rom.cli import TABLE_HELP, ArgumentParser, resolve_table, run_main
from rotor37_rom.geometry.blade import MESH_PRESETS
from rotor37_rom.studies.disk_modes import BladedDiskConfig, BladedDiskResult, run_bladed_disk
from rotor37_rom.studies.sector_file import SectorFile, add_sector_options
# -


# ## What to compute
#
# A frozen configuration (`BladedDiskConfig`), checked when it is made: a bad value is one error naming it and the
# allowed range.
#
# ## The study
#
# The sector is built once; K and M are assembled once and projected for each k. The references: the blade clamped
# at its root on the same mesh (every disk DOF fixed: by Rayleigh's theorem of constraint no cyclic frequency can
# exceed it) and the clamped single blade 4 mm shorter on its own mesh (the paper's single-blade model).


# ## Report

# +
def print_report(r: BladedDiskResult) -> None:
    s = r.safe
    print(f"\nbladed-disk sector: {r.dofs} DOF; mesh {r.seconds['mesh']:.1f} s, {len(s.k)} nodal diameters "
          f"{r.seconds['safe']:.1f} s")
    if r.clamped_blade.size:
        print(f"clamped blade 4 mm shorter (own mesh), 1B / 1T / 2B: {np.array2string(r.clamped_blade, precision=0)}")
    if r.clamped_on_disk.size:
        print(f"blade clamped on the disk (same mesh), first three: {np.array2string(r.clamped_on_disk, precision=0)}")
    print(f"{'k':>3} " + " ".join(f"{'mode ' + str(j + 1):>16}" for j in range(s.omega.shape[1])))
    for i, k in enumerate(s.k):
        cells = [f"{w:9.0f} {fam:>6}" for w, fam in zip(s.omega[i], s.family[i])]
        print(f"{k:>3} " + " ".join(cells))
    print("files: " + ", ".join(str(f) for f in r.files))


def main(argv=None) -> int:
    parser = ArgumentParser(description="Rotor 37 bladed-disk sector: cyclic modes and SAFE diagram")
    parser.add_argument("--preset", default="coarse", help=f"mesh preset: {', '.join(MESH_PRESETS)}")
    parser.add_argument("--table", default="none", help=TABLE_HELP + " (default none)")
    parser.add_argument("--modes", type=int, default=6, help="distinct modes per nodal diameter (1..20)")
    parser.add_argument("--pictures", type=int, nargs="*", default=None,
                        help="nodal diameters of the 1B pictures (0..N/2; none: no pictures; default 0 3 18, with "
                             "--mesh 0 1 N/2)")
    parser.add_argument("--nodal-diameters", type=int, nargs="+", default=None, metavar="K",
                        help="the nodal diameters of the SAFE diagram (0..N/2; default all)")
    parser.add_argument("--out", default="results/bladed_disk", help="output folder")
    add_sector_options(parser)
    parser.add_argument("--show-groups", action="store_true",
                        help="with --mesh: draw the groups and the contact nodes on the mesh (OUT/own/groups.png), "
                             "then stop")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s", force=True)
    mesh = SectorFile.from_args(args, parser)
    pictures = args.pictures
    if pictures is None:
        pictures = [0, 3, 18] if mesh is None else sorted({0, 1, (mesh.n_sectors or 2) // 2})
    config = BladedDiskConfig(preset=args.preset, table=resolve_table(args.table), n_modes=args.modes,
                              pictures=tuple(pictures), out=Path(args.out), mesh=mesh,
                              nodal_diameters=None if args.nodal_diameters is None else tuple(args.nodal_diameters),
                              show_groups=args.show_groups)
    result = run_bladed_disk(config)
    from mpi4py import MPI

    if MPI.COMM_WORLD.rank == 0 and result.safe is not None:
        print_report(result)
    return 0


if __name__ == "__main__":
    sys.exit(run_main(main))
# -
