"""Your own blade through the pipeline (demos/own_blade.py): ``run_own_blade(OwnBladeConfig)``.

A blade mesh from CalculiX/Abaqus (.inp), gmsh (.msh), NASTRAN (.bdf/.nas) or VTK (.vtk/.vtu), in any units, with
tetrahedra, wedges, hexahedra or pyramids of order 1 or 2 (split into conforming tetrahedra on reading:
``rotor37_rom.geometry.mesh_import``): its first clamped modes, the Craig-Bampton model on the contact nodes (ordered
LE -> TE along the tip chord), the sprag-slip onset mu* of each contact node and of the LE half
(``rotor37_rom.dynamics.friction``) and a short rub on the paper's ovalised casing at one speed; the summary goes to
``<out>/summary.json``. Without a mesh, the project's ci blade written as a millimetre Abaqus deck is the input.
"""
from __future__ import annotations

import dataclasses
import json
import time
from pathlib import Path

import numpy as np

from rotor37_rom.checks import before_work, flagged, readable_file
from rotor37_rom.dynamics.casing import Casing, check_hand
from rotor37_rom.forms import Material
from rotor37_rom.geometry.mesh_import import MESH_SUFFIXES, UNITS

__all__ = ["OwnBladeConfig", "load_blade", "run_own_blade"]


@dataclasses.dataclass(frozen=True)
class OwnBladeConfig:
    """What to run. mesh None: the project's ci blade written as a millimetre Abaqus deck (the example input).

    The frame is the user's, stated and printed with the results: the blade turns about +z in ``rotation_sense`` (-1:
    towards -theta, rotor 37's) and touches the casing along ``direction`` ('x': the blade frame's e_x, the paper's;
    'radial'; 'cone'); a sense that turns the blade with its trailing edge ahead (a mirrored blade) is refused
    (``dynamics.casing.check_hand``). ``material`` (E, nu, rho in SI) overrides the deck's own (an Abaqus deck's
    *MATERIAL, read and printed), whose absence means the paper's maraging steel, said as well. A blade whose mass is
    outside 1 g - 100 kg is refused with the units it is likely in (``geometry.mesh_import.check_blade_mass``) unless
    ``mass_check`` is False."""

    mesh: str | None = None
    clamp: str = "CLAMP"
    tip: str = "TIP"
    units: str = "mm"
    contact: int = 8
    modes: int = 6
    r_c: int = 15
    speed: float = 1400.0
    revolutions: float = 2.0
    mu: float = 0.0
    direction: str = "x"
    rotation_sense: int = -1
    mass_check: bool = True
    material: tuple[float, float, float] | None = None
    out: str = "results/own_blade"

    def __post_init__(self):
        if self.mesh is not None:
            readable_file("--mesh", self.mesh)
        if self.mesh is not None and Path(self.mesh).suffix.lower() not in MESH_SUFFIXES:
            raise ValueError(f"--mesh must be one of {', '.join(MESH_SUFFIXES)}, got {Path(self.mesh).name}")
        for option, name in (("--clamp", self.clamp), ("--tip", self.tip)):
            if not (isinstance(name, str) and name.strip()):
                raise ValueError(f"{option} must name a group of the mesh, got {name!r}")
        if self.units not in UNITS:
            raise ValueError(f"--units must be one of {', '.join(UNITS)}, got {self.units!r}")
        if not 2 <= self.contact <= 40:
            raise ValueError(f"--contact must be in [2, 40] nodes along the tip camber line, got {self.contact}")
        if not 1 <= self.modes <= 50:
            raise ValueError(f"--modes must be in [1, 50], got {self.modes}")
        if not 1 <= self.r_c <= 100:
            raise ValueError(f"--r-c must be in [1, 100], got {self.r_c}")
        if not 100.0 <= self.speed <= 5000.0:
            raise ValueError(f"--speed must be in [100, 5000] rad/s, got {self.speed}")
        if not 0.0 < self.revolutions <= 50.0:
            raise ValueError(f"--revolutions must be in (0, 50], got {self.revolutions}")
        if not 0.0 <= self.mu < 1.0:
            raise ValueError(f"--mu must be in [0, 1), got {self.mu}")
        if self.material is not None:
            if not (isinstance(self.material, (tuple, list)) and len(self.material) == 3):
                raise ValueError(f"--material takes E (Pa), nu and rho (kg/m^3), got {self.material!r}")
            flagged("--material", lambda: Material(*self.material))
            object.__setattr__(self, "material", tuple(float(v) for v in self.material))
        flagged("--direction", lambda: Casing(direction=self.direction))
        flagged("--rotation-sense", lambda: Casing(rotation_sense=self.rotation_sense))

    @property
    def casing(self) -> Casing:
        """The casing of the run in the user's frame: rotation about +z in ``rotation_sense``, the normal
        ``direction``, friction ``mu``."""
        return Casing(mu=self.mu, direction=self.direction, rotation_sense=self.rotation_sense)


def load_blade(config: OwnBladeConfig):
    """The user's sector (or the example deck, written first)."""
    from rotor37_rom import fem

    path = config.mesh
    if path is None:
        Path(config.out).mkdir(parents=True, exist_ok=True)
        path = fem.write_sector_mesh(fem.create_blade_sector(preset="ci"), Path(config.out) / "example_blade_mm.inp",
                                     units="mm")
        print(f"no --mesh: the ci blade written as {path} (C3D4, mm, node sets CLAMP and TIP)")
    try:
        return fem.create_sector_from_file(path, clamp=config.clamp, tip=config.tip, units=config.units,
                                           contact=config.contact, preset="ci", mass_check=config.mass_check,
                                           material=None if config.material is None else Material(*config.material))
    except ValueError as exc:
        raise ValueError(f"--mesh: {exc}") from None


def run_own_blade(config: OwnBladeConfig) -> dict:
    """The whole scene; returns the summary written to results/own_blade/summary.json."""
    from rotor37_rom import fem
    from rotor37_rom.reduction.builder import ReductionConfig, build_reduced_model
    from rotor37_rom.dynamics.casing import contact_matrices
    from rotor37_rom.dynamics.friction import sprag_slip_friction
    from rotor37_rom.dynamics.explicit import CentralDifference, simulate

    before_work({"--out": config.out})
    t0 = time.perf_counter()
    blade = load_blade(config)
    stagger = check_hand(blade.tip_nodes, config.rotation_sense)          # ValueError naming --rotation-sense
    towards = "-theta" if config.rotation_sense < 0 else "+theta"
    print(f"frame: rotation about +z, sense {config.rotation_sense:+d} (towards {towards}), contact normal "
          f"{config.direction}; the tip's trailing edge {abs(np.degrees(stagger)):.1f} deg behind its leading edge")
    modes = fem.compute_clamped_modes(blade, config.modes)
    print("clamped modes (Hz):", np.round(modes.omega / (2 * np.pi), 1).tolist())
    print("contact nodes (LE -> TE), mm:", np.round(1e3 * blade.tip_nodes, 2).tolist())
    model, _ = build_reduced_model(blade, ReductionConfig(r_c=config.r_c, r_md=0, global_md_modes=3,
                                                          forces="intrusive", keep_basis=True))
    print(f"reduced model: r = {model.r} {model.sizes}")
    casing = config.casing
    N, S, _, _ = contact_matrices(model.nodes, model.r, casing)
    per_node = [sprag_slip_friction(model.K, N, S, [k]) for k in range(N.shape[0])]
    le_half = sprag_slip_friction(model.K, N, S, list(range(max(1, N.shape[0] // 2))))
    print("sprag-slip onset mu* per node (LE -> TE):", [round(m, 3) if np.isfinite(m) else None for m in per_node],
          f"LE half {le_half:.3f}")
    scheme = CentralDifference(model, nonlinear=True, safety=0.5)
    run = simulate(scheme, [config.speed], casing, revolutions=config.revolutions, on_blowup="flag")
    diverged = bool(run.diverged_step[0] >= 0)
    le = run.row("0:LE")
    summary = {
        "mesh": blade.summary, "mass_kg": blade.volume * blade.material.rho, "dofs": blade.n_dofs,
        "modes_hz": (modes.omega / (2 * np.pi)).tolist(), "contact_nodes_m": blade.tip_nodes.tolist(),
        "r": model.r, "sizes": list(model.sizes), "mu_star_per_node": [m if np.isfinite(m) else None for m in per_node],
        "mu_star_le_half": le_half if np.isfinite(le_half) else None, "speed": config.speed, "mu": config.mu,
        "revolutions": config.revolutions, "diverged": diverged,
        "frame": {"axis": "+z", "rotation_sense": config.rotation_sense, "contact_normal": config.direction,
                  "tip_stagger_deg": float(np.degrees(stagger))},
        "le_max_radial_mm": None if diverged else 1e3 * float(np.max(run.u_r[0][le])),
        "wall_s": time.perf_counter() - t0,
    }
    if diverged:
        print(f"contact run at {config.speed} rad/s grew past the limit: no result shown")
    else:
        print(f"contact run at {config.speed} rad/s, mu = {config.mu}: max radial displacement of node LE "
              f"{summary['le_max_radial_mm']:.3f} mm")
    out = Path(config.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "summary.json").write_text(json.dumps(summary, indent=1))
    print(f"wrote {out / 'summary.json'} ({summary['wall_s']:.0f} s)")
    return summary

