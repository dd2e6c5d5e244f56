"""A user's sector as a study's input: ``SectorFile`` (the file, its groups, units, material and, for a bladed-disk
sector, its cyclic faces and sector count), checked when it is made, and the command-line options every scene that
takes a user's mesh shares (``add_sector_options``, ``SectorFile.from_args``).

``SectorFile.create(comm)`` reads it through ``fem.create_sector_from_file``, the one entry for a user's blade or
disk sector; the scenes (``studies.disk_modes``, ``studies.contact_map``) then run on it as on the built-in rotor 37
sectors. Pure Python (no dolfinx): a bad option is refused before any meshing.
"""
from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

from rotor37_rom.checks import flagged, readable_file, whole_number
from rotor37_rom.forms import Material
from rotor37_rom.geometry.mesh_import import AXES, MESH_SUFFIXES, UNITS

__all__ = ["SectorFile", "add_sector_options", "SECTOR_OPTIONS"]

#: the command-line destinations of ``add_sector_options``
SECTOR_OPTIONS = ("mesh", "clamp", "tip", "left", "right", "n_sectors", "blade", "units", "contact", "material",
                  "mass_check", "axis")


@dataclasses.dataclass(frozen=True)
class SectorFile:
    """A user's blade or bladed-disk sector in a mesh file.

    Attributes:
        path: the mesh file (.inp, .msh, .bdf/.nas, .vtk/.vtu).
        clamp: the clamped group (node set, element set or physical group; any case).
        tip: the tip group, whose camber line carries the contact nodes (None: no contact nodes).
        left, right, n_sectors: a bladed-disk sector's cyclic faces (``left`` at the lower angle, ``right`` turned
            by 2 pi / N about +z) and the number of sectors N (2..360); all None for a blade.
        blade: of a disk sector, the element set of its blade (its volumes are then 'blade' and 'disk', as the
            built-in sector's: the SAFE diagram's labels); None: the modes are not labelled blade or disk.
        units: the file's length unit (m, mm, cm, in).
        contact: contact nodes along the tip camber line (2..40).
        material: (E Pa, nu, rho kg/m^3); 'paper': the paper's maraging steel, confirmed; None: the file's own
            material (an Abaqus deck's *MATERIAL, a NASTRAN MAT1); a file that states none is then refused, naming
            --material (a default steel would be a silent guess: a user's plate came out 6.3 % off).
        mass_check: refuse a sector whose mass is outside 1 g - 100 kg (a unit slip) with the likely units.
        axis: the rotation axis in the file's frame ('+z', the project's; '-z', '+x', '-x', '+y', '-y'): the mesh is
            turned so that it is +z, and the results are in that turned frame (said when it is read).
    """

    path: Path
    clamp: str = "CLAMP"
    tip: str | None = "TIP"
    left: str | None = None
    right: str | None = None
    n_sectors: int | None = None
    blade: str | None = None
    units: str = "mm"
    contact: int = 8
    material: tuple[float, float, float] | str | None = None
    mass_check: bool = True
    axis: str = "+z"

    def __post_init__(self):
        readable_file("--mesh", self.path)
        object.__setattr__(self, "path", Path(self.path))
        if self.path.suffix.lower() not in MESH_SUFFIXES:
            raise ValueError(f"--mesh must be one of {', '.join(MESH_SUFFIXES)}, got {self.path.name}")
        for option, name, needed in (("--clamp", self.clamp, True), ("--tip", self.tip, False),
                                     ("--left", self.left, False), ("--right", self.right, False),
                                     ("--blade", self.blade, False)):
            if (name is not None or needed) and not (isinstance(name, str) and name.strip()):
                raise ValueError(f"{option} must name a group of the mesh, got {name!r}")
        cyclic = (self.left, self.right, self.n_sectors)
        if any(v is not None for v in cyclic) and any(v is None for v in cyclic):
            given = ", ".join(f"{o} {v}" for o, v in zip(("--left", "--right", "--n-sectors"), cyclic))
            raise ValueError(f"--left, --right and --n-sectors go together (a bladed-disk sector's faces and count), "
                             f"got {given}")
        if self.n_sectors is not None:
            whole_number("--n-sectors", self.n_sectors, 2, 360)
            object.__setattr__(self, "n_sectors", int(self.n_sectors))
        if self.blade is not None and self.n_sectors is None:
            raise ValueError("--blade names a bladed-disk sector's blade: it needs --left, --right and --n-sectors")
        if self.units not in UNITS:
            raise ValueError(f"--units must be one of {', '.join(UNITS)}, got {self.units!r}")
        whole_number("--contact (nodes along the tip camber line)", self.contact, 2, 40)
        if self.material is not None and self.material != "paper":
            if not (isinstance(self.material, (tuple, list)) and len(self.material) == 3):
                raise ValueError(f"--material takes E (Pa), nu and rho (kg/m^3), or 'paper', got {self.material!r}")
            flagged("--material", lambda: Material(*self.material))
            object.__setattr__(self, "material", tuple(float(v) for v in self.material))
        if not isinstance(self.mass_check, bool):
            raise ValueError(f"--mass-check must be on or off, got {self.mass_check!r}")
        if self.axis not in AXES:
            raise ValueError(f"--axis must be one of {', '.join(AXES)} (the rotation axis in the file), got "
                             f"{self.axis!r}")

    @property
    def cyclic(self) -> tuple[str, str, int] | None:
        """(left, right, N) of a bladed-disk sector, else None."""
        return None if self.n_sectors is None else (self.left, self.right, self.n_sectors)

    def create(self, comm=None, verbose: bool = True):
        """The sector (``fem.create_sector_from_file``) on ``comm`` (default: MPI.COMM_WORLD); a file it refuses is
        one ValueError naming --mesh."""
        from mpi4py import MPI

        from rotor37_rom import fem

        material = None if self.material is None else Material() if self.material == "paper" else \
            Material(*self.material)
        try:
            return fem.create_sector_from_file(
                self.path, clamp=self.clamp, tip=self.tip, comm=comm or MPI.COMM_WORLD, preset="ci",
                units=self.units, contact=self.contact if self.tip is not None else None, verbose=verbose,
                mass_check=self.mass_check, cyclic=self.cyclic, blade=self.blade, axis=self.axis,
                material=material)
        except fem.MissingMaterial:
            raise ValueError(f"--material: {self.path.name} states no material: give --material E NU RHO (Pa, -, "
                             f"kg/m^3), or --material paper to run on the paper's maraging steel") from None
        except ValueError as exc:
            raise ValueError(f"--mesh: {exc}") from None

    def as_dict(self) -> dict:
        """What a summary records of the input."""
        return {k: (str(v) if isinstance(v, Path) else v) for k, v in dataclasses.asdict(self).items()}

    @staticmethod
    def material_option(words) -> tuple[float, float, float] | str | None:
        """--material's words: None, ['paper'] or three numbers E NU RHO; ValueError naming --material otherwise."""
        if words is None:
            return None
        if [str(w).lower() for w in words] == ["paper"]:
            return "paper"
        try:
            values = tuple(float(w) for w in words)
        except ValueError:
            values = ()
        if len(values) != 3:
            raise ValueError(f"--material takes E (Pa), nu and rho (kg/m^3), or 'paper' (the paper's maraging "
                             f"steel), got {' '.join(map(str, words))!r}")
        return values

    @classmethod
    def from_args(cls, args: argparse.Namespace, parser: argparse.ArgumentParser) -> "SectorFile | None":
        """The sector of the options ``add_sector_options`` added to ``parser`` (None without --mesh, where any of
        them given is refused: they describe the file)."""
        if getattr(args, "mesh", None) is None:
            given = [a.option_strings[0] for a in parser._actions
                     if a.dest in SECTOR_OPTIONS and getattr(args, a.dest, a.default) != a.default]
            if given:
                raise ValueError(f"{given[0]} describes your own sector's file: give it with --mesh")
            return None
        tip = None if str(args.tip).lower() == "none" else args.tip
        return cls(path=args.mesh, clamp=args.clamp, tip=tip, left=getattr(args, "left", None),
                   right=getattr(args, "right", None), n_sectors=getattr(args, "n_sectors", None),
                   blade=getattr(args, "blade", None), units=args.units, contact=args.contact,
                   material=cls.material_option(args.material),
                   mass_check=args.mass_check == "on", axis=args.axis)


def add_sector_options(parser: argparse.ArgumentParser, cyclic: bool = True) -> None:
    """The options of a user's sector (``SectorFile``) on a command line; with ``cyclic``, a bladed-disk sector's
    --left, --right, --n-sectors and --blade too."""
    group = parser.add_argument_group("your own sector (a mesh file)")
    group.add_argument("--mesh", default=None, help=f"the sector's mesh file ({', '.join(MESH_SUFFIXES)})")
    group.add_argument("--clamp", default="CLAMP", help="the clamped group (node set, element set or physical group; "
                                                        "any case)")
    group.add_argument("--tip", default="TIP", help="the tip group, whose camber line carries the contact nodes "
                                                    "('none': no contact nodes)")
    if cyclic:
        group.add_argument("--left", default=None, help="the cyclic face at the lower angle")
        group.add_argument("--right", default=None, help="the cyclic face turned by 2 pi / N about +z")
        group.add_argument("--n-sectors", type=int, default=None, help="the number of sectors N (2..360)")
        group.add_argument("--blade", default=None, help="the element set of the blade (labels the modes blade or "
                                                         "disk)")
    group.add_argument("--units", default="mm", help=f"the file's length unit: {', '.join(UNITS)} (default mm)")
    group.add_argument("--contact", type=int, default=8, help="contact nodes along the tip camber line (2..40)")
    group.add_argument("--material", nargs="+", metavar="E NU RHO | paper", default=None,
                       help="E (Pa), nu, rho (kg/m^3), or 'paper' for the paper's maraging steel; default: the "
                            "file's own (a file that states none is refused)")
    group.add_argument("--mass-check", choices=["on", "off"], default="on",
                       help="refuse a mass outside 1 g - 100 kg (a unit slip; default on)")
    group.add_argument("--axis", choices=list(AXES), default="+z",
                       help="the rotation axis in the file (default +z, the project's): the mesh is turned so that it "
                            "is +z, and the results are in that frame")
