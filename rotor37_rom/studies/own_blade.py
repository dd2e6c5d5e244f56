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

from rotor37_rom.checks import before_work, flagged
from rotor37_rom.dynamics.casing import Casing, check_hand
from rotor37_rom.studies.sector_file import SectorFile
from rotor37_rom.reporting import say

__all__ = ["OwnBladeConfig", "load_blade", "run_own_blade", "show_groups"]


@dataclasses.dataclass(frozen=True)
class OwnBladeConfig:
    """What to run. mesh: the user's blade (``SectorFile``: the file, its clamp and tip groups, units, contact nodes,
    material, mass check); None: the project's ci blade written as a millimetre Abaqus deck (the example input).

    The frame is the user's, stated and printed with the results: the blade turns about +z in ``rotation_sense`` (-1:
    towards -theta, rotor 37's) and touches the casing along ``direction`` ('x': the blade frame's e_x, the paper's;
    'radial'; 'cone'); a sense that turns the blade with its trailing edge ahead (a mirrored blade) is refused
    (``dynamics.casing.check_hand``). ``show_groups``: draw the groups on the mesh (``<out>/groups.png``) and
    stop."""

    mesh: SectorFile | None = None
    modes: int = 6
    r_c: int = 15
    speed: float = 1400.0
    revolutions: float = 2.0
    mu: float = 0.0
    direction: str = "x"
    rotation_sense: int = -1
    out: str = "results/own_blade"
    show_groups: bool = False

    def __post_init__(self):
        if self.mesh is not None and not isinstance(self.mesh, SectorFile):
            raise TypeError(f"mesh must be a SectorFile (the file and its groups) or None, got {self.mesh!r}")
        if self.mesh is not None and self.mesh.tip is None:
            raise ValueError("--tip none: this scene rubs the blade's tip on the casing; give --tip, the tip group "
                             "whose camber line carries the contact nodes")
        if self.mesh is not None and self.mesh.cyclic is not None:
            raise ValueError("--left/--right/--n-sectors make a bladed-disk sector: demos/bladed_disk.py --mesh takes "
                             "it")
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
        flagged("--direction", lambda: Casing(direction=self.direction))
        flagged("--rotation-sense", lambda: Casing(rotation_sense=self.rotation_sense))

    @property
    def casing(self) -> Casing:
        """The casing of the run in the user's frame: rotation about +z in ``rotation_sense``, the normal
        ``direction``, friction ``mu``."""
        return Casing(mu=self.mu, direction=self.direction, rotation_sense=self.rotation_sense)


def load_blade(config: OwnBladeConfig):
    """The user's blade (or the example deck, written first)."""
    from rotor37_rom import fem

    mesh = config.mesh
    if mesh is None:
        Path(config.out).mkdir(parents=True, exist_ok=True)
        path = fem.write_sector_mesh(fem.create_blade_sector(preset="ci"), Path(config.out) / "example_blade_mm.inp",
                                     units="mm")
        say(f"no --mesh: the ci blade written as {path} (C3D4, mm, node sets CLAMP and TIP)")
        mesh = SectorFile(path)
    return mesh.create()


def show_groups(sector, out) -> Path:
    """The groups of a user's sector drawn on its mesh (``viz.plotting.render_groups``) as ``<out>/groups.png``."""
    from rotor37_rom.viz.plotting import render_groups

    path = render_groups(sector, Path(out) / "groups.png", Path(sector.source.removeprefix("file:")).name)
    say(f"the groups drawn on the mesh (contact nodes in red): {path}; run again without --show-groups")
    return path


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
    if config.show_groups:
        return {"groups_png": str(show_groups(blade, config.out))}
    stagger = check_hand(blade.tip_nodes, config.rotation_sense)          # ValueError naming --rotation-sense
    towards = "-theta" if config.rotation_sense < 0 else "+theta"
    say(f"frame: rotation about +z, sense {config.rotation_sense:+d} (towards {towards}), contact normal "
          f"{config.direction}; the tip's trailing edge {abs(np.degrees(stagger)):.1f} deg behind its leading edge")
    modes = fem.compute_clamped_modes(blade, config.modes)
    say("clamped modes (Hz):", np.round(modes.omega / (2 * np.pi), 1).tolist())
    say("contact nodes (LE -> TE), mm:", np.round(1e3 * blade.tip_nodes, 2).tolist())
    model, _ = build_reduced_model(blade, ReductionConfig(r_c=config.r_c, r_md=0, global_md_modes=3,
                                                          forces="intrusive", keep_basis=True))
    say(f"reduced model: r = {model.r} {model.sizes}")
    frame_deg = float(np.degrees(model.nodes.frame_angle))
    if config.direction == "x":
        say(f"contact normal x: the blade frame's e_x, radial through the blade's centre of mass at "
              f"theta = {frame_deg:+.3f} deg in the file")
    casing = config.casing
    N, S, _, _ = contact_matrices(model.nodes, model.r, casing)
    per_node = [sprag_slip_friction(model.K, N, S, [k]) for k in range(N.shape[0])]
    le_half = sprag_slip_friction(model.K, N, S, list(range(max(1, N.shape[0] // 2))))
    say("sprag-slip onset mu* per node (LE -> TE):", [round(m, 3) if np.isfinite(m) else None for m in per_node],
          f"LE half {le_half:.3f}")
    scheme = CentralDifference(model, nonlinear=True, safety=0.5)
    run = simulate(scheme, [config.speed], casing, revolutions=config.revolutions, on_blowup="flag")
    diverged = bool(run.diverged_step[0] >= 0)
    le = run.row("0:LE")
    summary = {
        "mesh": blade.summary, "input": None if config.mesh is None else config.mesh.as_dict(),
        "mass_kg": blade.volume * blade.material.rho, "dofs": blade.n_dofs,
        "modes_hz": (modes.omega / (2 * np.pi)).tolist(), "contact_nodes_m": blade.tip_nodes.tolist(),
        "r": model.r, "sizes": list(model.sizes), "mu_star_per_node": [m if np.isfinite(m) else None for m in per_node],
        "mu_star_le_half": le_half if np.isfinite(le_half) else None, "speed": config.speed, "mu": config.mu,
        "revolutions": config.revolutions, "diverged": diverged,
        "frame": {"axis": "+z", "file_axis": "+z" if config.mesh is None else config.mesh.axis,
                  "rotation_sense": config.rotation_sense, "contact_normal": config.direction,
                  "tip_stagger_deg": float(np.degrees(stagger)),
                  "blade_frame": "the plane through the axis and the blade's centre of mass",
                  "blade_frame_theta_deg": frame_deg},
        "le_max_radial_mm": None if diverged else 1e3 * float(np.max(run.u_r[0][le])),
        "wall_s": time.perf_counter() - t0,
    }
    if diverged:
        say(f"contact run at {config.speed} rad/s grew past the limit: no result shown")
    else:
        say(f"contact run at {config.speed} rad/s, mu = {config.mu}: max radial displacement of node LE "
              f"{summary['le_max_radial_mm']:.3f} mm")
    out = Path(config.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "summary.json").write_text(json.dumps(summary, indent=1))
    say(f"wrote {out / 'summary.json'} ({summary['wall_s']:.0f} s)")
    return summary

