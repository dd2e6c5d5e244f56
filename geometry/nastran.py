"""The material of a NASTRAN bulk-data file (.bdf/.nas/.fem), which meshio does not read: its first ``MAT1`` card
(E, G, NU, RHO) in free-field (commas), small-field (8 characters) or large-field (``MAT1*``, 16 characters, with
its continuation) format, NASTRAN's reals included (``2.1+11`` for 2.1e11). ``bulk_material(path, units)`` gives it
in SI through the same unit systems as an Abaqus deck's (``geometry.abaqus.material_in_si``); a MAT1 with E and G
but no NU takes NU = E / 2G - 1, one with G and NU but no E takes E = 2 (1 + NU) G. Errors name the file and the
line. Pure Python.
"""
from __future__ import annotations

import re
from pathlib import Path

from .abaqus import material_in_si

__all__ = ["bulk_material", "nastran_real", "without_materials"]

_REAL = re.compile(r"^([+-]?(?:\d+\.?\d*|\.\d+))([+-]\d+)$")


def nastran_real(text: str, where: str) -> float | None:
    """A NASTRAN real field: 2.1E11, 2.1D11, 2.1+11 (the exponent's E left out), 7.85-9; None when blank."""
    text = text.strip().upper().replace("D", "E")
    if not text:
        return None
    m = _REAL.match(text)
    try:
        return float(f"{m.group(1)}E{m.group(2)}" if m else text)
    except ValueError:
        raise ValueError(f"{where}: {text!r} is not a number") from None


def _fields(lines: list[str], k: int) -> list[str]:
    """The fields of the card starting at line k (its name first), its continuation lines joined."""
    line = lines[k].rstrip("\n")
    if "," in line:                                                   # free field
        fields = [f.strip() for f in line.split(",")]
        nxt = lines[k + 1] if k + 1 < len(lines) else ""
        if nxt.startswith(("+", ",")) or (fields and fields[-1].startswith("+")):
            fields = fields[:9] + [f.strip() for f in nxt.split(",")[1:]]
        return fields
    large = line.split()[0].endswith("*") if line.strip() else False
    width = 16 if large else 8
    body = line[8:8 + 4 * width] if large else line[8:72]
    fields = [line[:8].strip()] + [body[i:i + width] for i in range(0, len(body), width)]
    if large and k + 1 < len(lines) and lines[k + 1].startswith("*"):
        nxt = lines[k + 1]
        fields += [nxt[8 + i:8 + i + width] for i in range(0, 4 * width, width)]
    return fields


def bulk_material(path: str | Path, units: str) -> tuple[float, float, float] | None:
    """(E (Pa), nu, rho (kg/m^3)) of the file's first MAT1 for a file in ``units``, or None without one."""
    path = Path(path)
    lines = path.read_text(errors="replace").splitlines()
    for k, line in enumerate(lines):
        if not re.match(r"^MAT1\*?(\s|,|$)", line.upper()):
            continue
        fields = _fields(lines, k) + [""] * 8
        where = f"{path}, line {k + 1} (MAT1)"
        E, G, nu, rho = (nastran_real(f, where) for f in fields[2:6])
        if E is None and G is not None and nu is not None:
            E = 2.0 * (1.0 + nu) * G
        if nu is None and E is not None and G is not None:
            nu = E / (2.0 * G) - 1.0
        if E is None or nu is None or rho is None:
            missing = ", ".join(n for n, v in (("E", E), ("NU", nu), ("RHO", rho)) if v is None)
            raise ValueError(f"{where}: no {missing} (give material=)")
        return material_in_si(E, nu, rho, units, str(path), f"MAT1 {fields[1].strip()}")
    return None


def without_materials(path: str | Path) -> str:
    """The file's text without its material cards (MAT*, with their continuation lines): meshio 5.3 reads the mesh
    of a NASTRAN file but fails on a large-field MAT1* with its continuation."""
    out, skipping = [], False
    for line in Path(path).read_text(errors="replace").splitlines():
        if re.match(r"^MAT\w*\*?(\s|,|$)", line.upper()):
            skipping = True
            continue
        if skipping and (line[:1] in ("+", "*", ",") or line[:8].strip() == ""):
            continue
        skipping = False
        out.append(line)
    return "\n".join(out) + "\n"
