"""Readers for the NASA rotor 37 geometry tables (Table IV blade sections, Table V hub/shroud lines).

The files are the plain-text NASA/AGARD test-case tables (Reid & Moore 1978, NASA TP-1337; AGARD-AR-355): lengths
in centimetres, angles in radians. Everything returned here is in SI units (metres, radians).

Only NumPy is used: this is the bottom layer of the project.
"""
from __future__ import annotations

import dataclasses
import os
import re
from pathlib import Path

import numpy as np

from rotor37_rom.checks import readable_file

__all__ = [
    "BladeTable",
    "HubShroudTable",
    "read_blade_table",
    "read_hub_shroud_table",
    "default_data_dir",
]

_CM = 1.0e-2
_ROW = re.compile(r"^\s*(\d+)\s+(\S+)\s+(\S+)\s+(\S+)\s+(\S+)\s*$")


@dataclasses.dataclass(frozen=True)
class BladeTable:
    """NASA Table IV: blade sections on surfaces of revolution.

    Attributes:
        z: axial coordinate, shape (n_sections, n_points), m (downstream positive).
        r: radius, shape (n_sections, n_points), m.
        theta_suction: circumferential angle of the suction side (THETA1), rad.
        theta_pressure: circumferential angle of the pressure side (THETA2), rad.
        source: path of the file that was read.

    Section 0 is the hub/blade intersection (root), section 11 the tip and section 12 the casing line. Point 0 is the
    leading edge (LE), point -1 the trailing edge (TE); both sides share (z, r).
    """

    z: np.ndarray
    r: np.ndarray
    theta_suction: np.ndarray
    theta_pressure: np.ndarray
    source: str

    @property
    def n_sections(self) -> int:
        return self.z.shape[0]

    def side_points(self, section: int, side: str) -> np.ndarray:
        """Cartesian points (x, y, z) of one side of one section, shape (n_points, 3), m."""
        theta = {"suction": self.theta_suction, "pressure": self.theta_pressure}[side][section]
        r = self.r[section]
        return np.column_stack([r * np.cos(theta), r * np.sin(theta), self.z[section]])


@dataclasses.dataclass(frozen=True)
class HubShroudTable:
    """NASA Table V: meridional hub and shroud (casing) lines, all in m."""

    z_hub: np.ndarray
    r_hub: np.ndarray
    z_shroud: np.ndarray
    r_shroud: np.ndarray

    def casing_radius(self, z: np.ndarray) -> np.ndarray:
        """Casing radius at axial positions z (m), by linear interpolation of the shroud line."""
        return np.interp(z, self.z_shroud, self.r_shroud)


def default_data_dir() -> Path | None:
    """The shared NASA table folder if it exists: $ROTOR37_DATA, else ../shared/data/rotor37 beside the repo."""
    candidates = []
    if os.environ.get("ROTOR37_DATA"):
        candidates.append(Path(os.environ["ROTOR37_DATA"]))
    repo = Path(__file__).resolve().parent.parent
    candidates.append(repo.parent / "shared" / "data" / "rotor37")
    for folder in candidates:
        if (folder / "rotor37geometry.dat").is_file():
            return folder
    return None


def read_blade_table(path: str | os.PathLike) -> BladeTable:
    """Read NASA Table IV (``rotor37geometry.dat``).

    Raises:
        ValueError: one line naming the file and what is wrong with it (missing, garbled, inconsistent).
    """
    path = Path(path)
    readable_file("blade table file", path)
    sections: list[list[list[float]]] = []
    try:
        text = path.read_text(errors="strict")
    except (UnicodeDecodeError, OSError) as exc:
        raise ValueError(f"blade table file {path} is not a readable text file ({exc.__class__.__name__})") from None
    for line_no, line in enumerate(text.splitlines(), start=1):
        if "SURFACE" in line.upper():
            sections.append([])
            continue
        match = _ROW.match(line)
        if match is None:
            continue
        if not sections:
            raise ValueError(f"blade table file {path}: line {line_no} has data before any 'SURFACE' header")
        try:
            sections[-1].append([float(v) for v in match.groups()[1:]])
        except ValueError:
            raise ValueError(f"blade table file {path}: line {line_no} has a non-numeric value") from None
    if len(sections) < 2:
        raise ValueError(f"blade table file {path} holds {len(sections)} sections; expected Table IV (13 sections)")
    counts = {len(s) for s in sections}
    if len(counts) != 1 or counts.pop() < 10:
        raise ValueError(f"blade table file {path}: sections have unequal or too few points ({[len(s) for s in sections]})")
    data = np.asarray(sections, dtype=float)
    if not np.all(np.isfinite(data)):
        raise ValueError(f"blade table file {path} contains non-finite values")
    z, r, th1, th2 = (data[..., k] for k in range(4))
    if np.any(r <= 0.0):
        raise ValueError(f"blade table file {path} has non-positive radii")
    if np.any(th1 < th2 - 1e-9):
        raise ValueError(f"blade table file {path}: THETA1 < THETA2 somewhere; columns garbled")
    return BladeTable(z=z * _CM, r=r * _CM, theta_suction=th1, theta_pressure=th2, source=str(path))


def read_hub_shroud_table(path: str | os.PathLike) -> HubShroudTable:
    """Read NASA Table V (``rotor37hub-shroud.dat``): four labelled vectors, 8 values a line, in cm."""
    path = Path(path)
    readable_file("hub/shroud table file", path)
    vectors: dict[str, list[float]] = {}
    current = None
    for line in path.read_text(errors="replace").splitlines():
        word = line.strip()
        if word in ("Zhub", "Rhub", "Zshroud", "Rshroud"):
            current = word
            vectors[current] = []
        elif current and word and not word.endswith("points"):
            try:
                vectors[current].extend(float(v) for v in word.split())
            except ValueError:
                raise ValueError(f"hub/shroud table file {path}: garbled line {word!r}") from None
    missing = {"Zhub", "Rhub", "Zshroud", "Rshroud"} - set(vectors)
    if missing:
        raise ValueError(f"hub/shroud table file {path} lacks {sorted(missing)}")
    if len(vectors["Zhub"]) != len(vectors["Rhub"]) or len(vectors["Zshroud"]) != len(vectors["Rshroud"]):
        raise ValueError(f"hub/shroud table file {path}: Z and R vectors differ in length")
    arr = {k: np.asarray(v) * _CM for k, v in vectors.items()}
    return HubShroudTable(arr["Zhub"], arr["Rhub"], arr["Zshroud"], arr["Rshroud"])
