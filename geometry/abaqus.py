"""What meshio does not read of an Abaqus/CalculiX deck: ``*INCLUDE`` files, ``*BOUNDARY`` node lists (a clamp given
without a named set) and the deck's material (``*MATERIAL`` / ``*ELASTIC`` / ``*DENSITY``).

``read_deck(path)`` returns the deck with every include inlined (the text meshio reads), the node labels and set
names its ``*BOUNDARY`` blocks fix, the labels of its nodes in the order they come (meshio numbers them so) and its
material's first ``*ELASTIC`` and ``*DENSITY`` data as written. ``deck_material(deck, units)`` turns that material
into SI for a deck in metres (N, Pa, kg/m^3) or in millimetres (N, MPa, t/mm^3, CalculiX's usual system). Errors
name the file and the line. Pure Python and NumPy.
"""
from __future__ import annotations

import dataclasses
import re
from pathlib import Path

__all__ = ["AbaqusDeck", "read_deck", "deck_material", "material_in_si", "MATERIAL_UNITS"]

#: the deck's length unit -> (stress, density) factors to SI of the consistent unit system it implies
MATERIAL_UNITS = {"m": (1.0, 1.0), "mm": (1e6, 1e12)}
_KEYWORD = re.compile(r"^\s*\*(?!\*)")


@dataclasses.dataclass
class AbaqusDeck:
    """A deck with its includes inlined.

    Attributes:
        lines: the deck's lines, includes inlined (comments kept).
        node_labels: the labels of its nodes in the order they come (meshio's point order).
        boundary_labels: node labels its ``*BOUNDARY`` blocks fix (any DOF); boundary_sets: the set names they fix.
        elastic, density: the first ``*ELASTIC`` data (E, nu) and ``*DENSITY`` data (rho) of its material, in the
            deck's units, or None; material_name: its name.
        source: the file.
    """

    lines: list
    node_labels: list
    boundary_labels: set
    boundary_sets: set
    elastic: tuple | None
    density: float | None
    material_name: str | None
    source: str

    @property
    def text(self) -> str:
        return "\n".join(self.lines) + "\n"


def _option(line: str, name: str) -> str | None:
    """The value of ``name=value`` on a keyword line (case-insensitive), or None."""
    m = re.search(rf",\s*{name}\s*=\s*([^,]+)", line, re.I)
    return m.group(1).strip().strip('"') if m else None


def _inline(path: Path, chain: tuple) -> list[str]:
    """The lines of ``path`` with its includes inlined; ValueError naming the file and line of a missing or circular
    include."""
    try:
        raw = path.read_text(errors="replace").splitlines()
    except OSError as exc:
        raise ValueError(f"deck {path} could not be read ({exc.strerror or type(exc).__name__})") from None
    out = []
    for number, line in enumerate(raw, start=1):
        if _KEYWORD.match(line) and line.strip().upper().startswith("*INCLUDE"):
            name = _option(line, "INPUT")
            if name is None:
                raise ValueError(f"{path}, line {number}: *INCLUDE without INPUT=")
            target = (path.parent / name).resolve()
            if target in chain:
                raise ValueError(f"{path}, line {number}: *INCLUDE of {name} includes itself")
            if not target.is_file():
                raise ValueError(f"{path}, line {number}: *INCLUDE, INPUT={name}: {target} does not exist")
            out += _inline(target, chain + (target,))
        else:
            out.append(line)
    return out


def _blocks(lines: list[str]):
    """(keyword line, its line number, its data lines) of every keyword block (comments '**' skipped)."""
    current, number, data = None, 0, []
    for k, line in enumerate(lines, start=1):
        if line.lstrip().startswith("**") or not line.strip():
            continue
        if _KEYWORD.match(line):
            if current is not None:
                yield current, number, data
            current, number, data = line.strip(), k, []
        elif current is not None:
            data.append((k, line))
    if current is not None:
        yield current, number, data


def _numbers(line: str, k: int, where: str, count: int | None = None) -> list[float]:
    try:
        values = [float(v) for v in line.replace(",", " ").split()]
    except ValueError:
        raise ValueError(f"{where}, line {k}: expected numbers, got {line.strip()!r}") from None
    if count is not None and len(values) < count:
        raise ValueError(f"{where}, line {k}: expected {count} numbers, got {line.strip()!r}")
    return values


def read_deck(path) -> AbaqusDeck:
    """The deck at ``path`` (see the module docstring)."""
    path = Path(path).resolve()
    lines = _inline(path, (path,))
    labels, fixed, fixed_sets = [], set(), set()
    elastic = density = name = None
    for keyword, number, data in _blocks(lines):
        word = keyword[1:].split(",")[0].strip().upper()
        if word == "NODE":
            for k, line in data:
                first = line.split(",")[0].strip()
                if not first.lstrip("-").isdigit():
                    raise ValueError(f"{path}, line {k}: a *NODE line starts with its label, got {line.strip()!r}")
                labels.append(int(first))
        elif word == "BOUNDARY":
            for k, line in data:
                first = line.split(",")[0].strip()
                if first.isdigit():
                    fixed.add(int(first))
                elif first:
                    fixed_sets.add(first)
        elif word == "MATERIAL" and name is None:
            name = _option(keyword, "NAME") or "(unnamed)"
        elif word == "ELASTIC" and elastic is None and data:
            values = _numbers(data[0][1], data[0][0], str(path), 2)
            elastic = (values[0], values[1])
        elif word == "DENSITY" and density is None and data:
            density = _numbers(data[0][1], data[0][0], str(path), 1)[0]
    return AbaqusDeck(lines, labels, fixed, fixed_sets, elastic, density, name, str(path))


def deck_material(deck: AbaqusDeck, units: str) -> tuple[float, float, float] | None:
    """(E (Pa), nu, rho (kg/m^3)) of the deck's material for a deck in ``units`` ('m': SI; 'mm': N-mm-t-s), or None
    without one; ValueError where it is incomplete, its units have no consistent system here, or its values in SI
    are no structural material's (a unit slip)."""
    if deck.elastic is None and deck.density is None:
        return None
    if deck.elastic is None or deck.density is None:
        missing = "*ELASTIC" if deck.elastic is None else "*DENSITY"
        raise ValueError(f"{deck.source}: material {deck.material_name} has no {missing}: give material=")
    return material_in_si(deck.elastic[0], deck.elastic[1], deck.density, units, deck.source,
                          f"material {deck.material_name}")


def material_in_si(E: float, nu: float, rho: float, units: str, source: str, what: str
                   ) -> tuple[float, float, float]:
    """A file's (E, nu, rho) as written, in SI for a file in ``units`` ('m': N, Pa, kg/m^3; 'mm': N, MPa, t/mm^3);
    ValueError where the units have no consistent system here or the values in SI are no structural material's."""
    if units not in MATERIAL_UNITS:
        raise ValueError(f"{source}: a material written in {units!r} has no consistent unit system here (m: N, "
                         f"Pa, kg/m^3; mm: N, MPa, t/mm^3): give material=")
    stress, mass = MATERIAL_UNITS[units]
    E, rho = E * stress, rho * mass
    if not (1e8 <= E <= 1e13 and 100.0 <= rho <= 3e4 and -1.0 < nu < 0.5):
        raise ValueError(f"{source}: {what} read in {units} units is E = {E:.3g} Pa, nu = {nu:g}, rho = {rho:.3g} "
                         "kg/m^3: no structural material; are the units right? (or give material=)")
    return E, nu, rho
