"""The single blade's static scenes: the clamped frequencies against the mesh presets (``modes``), the clearance
consumption of reduced bases against the full-order nonlinear statics (``clearance``) and the turning blade's
frequencies and centrifugal state against its full order (``rotating-modes``)."""
from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np

from rotor37_rom.reporting import say

__all__ = ["scene_modes", "scene_clearance", "scene_rotating_modes", "CLEARANCE_BASES", "ROTATING_BASES"]


# ## Clamped modes: mesh presets against the Richardson limit

def scene_modes() -> dict:
    """The clamped frequencies of modes 1-6 on the ci, coarse and paper presets (mesh, assembly and the modes
    timed); error: modes 1-3 against the paper preset, held out: modes 4-6."""
    from rotor37_rom import fem
    from rotor37_rom.model.modes import classify_blade_modes

    fem.create_blade_sector(preset="ci")                     # warm-up: imports and form compilation off the clock
    rows = {}
    for preset in ("ci", "coarse", "paper"):
        t0 = time.perf_counter()
        sector = fem.create_blade_sector(preset=preset)
        modal = fem.compute_clamped_modes(sector, 6)
        wall = time.perf_counter() - t0
        labels = classify_blade_modes(modal.tip_displacements, sector.tip_nodes)
        rows[preset] = dict(omega=np.asarray(modal.omega[:6], float), wall=wall, labels=labels, dofs=sector.n_dofs)
        say(f"modes {preset}: {sector.n_dofs} DOF, {wall:.1f} s, {np.round(modal.omega[:6])} {labels}")
    # the presets are not nested refinements (gmsh remeshes): the frequencies need not converge monotonically, so
    # no Richardson limit; the reference is the finest preset, whose own error is estimated by its last change
    ref = rows["paper"]["omega"]
    cands = []
    for preset, row in rows.items():
        err = np.abs((rows["coarse"]["omega"] if preset == "paper" else row["omega"]) - ref) / ref
        cands.append(dict(name=preset, options={"preset": preset}, cost=row["wall"], error=float(err[:3].max()),
                          held_out_error=float(err[3:6].max()), errors={"1-3": err[:3].tolist(),
                                                                         "4-6": err[3:6].tolist()},
                          wall_s=row["wall"], dofs=int(row["dofs"]), labels=row["labels"]))
    return dict(description="clamped frequencies of modes 1-3 (1B, 1T, 2B), largest relative error against the paper "
                            "preset (its own error: its change from the coarse preset); held out: modes 4-6",
                cost_unit="s (mesh + assembly + 6 modes)", reference={"paper_rad_s": ref.tolist()},
                candidates=cands, held_out_case="modes 4-6 (same runs)")


# ## Clearance consumption: reduced bases against the full-order statics

CLEARANCE_BASES = (  # (name, r_c, global_md_modes, r_md, criterion)
    ("r_c 5, no MD", 5, 0, 0, "MI2b"), ("r_c 15, no MD", 15, 0, 0, "MI2b"),
    ("r_c 15, 10 MD MI2b", 15, 0, 10, "MI2b"), ("r_c 15, 10 MD random", 15, 0, 10, "random"),
    ("r_c 5, 6 MD", 5, 3, 0, "MI2b"), ("r_c 15, 6 MD", 15, 3, 0, "MI2b"), ("r_c 25, 6 MD", 25, 3, 0, "MI2b"),
    ("r_c 15, 6 MD + 10 MI2b", 15, 3, 10, "MI2b"),
)


def scene_clearance() -> dict:
    """The clearance consumption of 1B and 1T on the ci mesh, every basis of ``CLEARANCE_BASES`` and the full-order
    linear model against the full-order nonlinear curves; held out: the same modes at 1.5 times the amplitude."""
    from rotor37_rom import fem
    from rotor37_rom.reduction.builder import ReductionConfig, build_reduced_model, clearance_consumption_study
    from rotor37_rom.post.clearance import relative_error

    sector = fem.create_blade_sector(preset="ci")
    ops = fem.create_svk_operators(sector)
    roms, offline = {}, {}
    for name, r_c, n_global, r_md, criterion in CLEARANCE_BASES:
        t0 = time.perf_counter()
        roms[name], _ = build_reduced_model(sector, ReductionConfig(r_c=r_c, r_md=r_md, global_md_modes=n_global,
                                                                    criterion=criterion, forces="intrusive"), ops=ops)
        offline[name] = time.perf_counter() - t0
        say(f"clearance: {name}: r = {roms[name].r}, built in {offline[name]:.1f} s")
    cases = {"study": (("1B", 1e-3), ("1T", 0.5e-3)), "held_out": (("1B", 1.5e-3), ("1T", 0.75e-3))}
    studies = {key: [clearance_consumption_study(sector, mode, zeta, n_levels=10, ops=ops, roms=roms)
                     for mode, zeta in pairs] for key, pairs in cases.items()}
    cands = []
    for name in ["FOM linear"] + list(roms):
        errs = {}
        for key, curves in studies.items():
            errs[key] = [float(np.nanmax(relative_error(c.curves[name], c.curves["FOM nonlinear"])))
                         if np.isfinite(c.curves[name]).all() else math.inf for c in curves]
        if name == "FOM linear":
            options, cost, r = {"model": "full-order linear"}, 0.0, None
        else:
            _, r_c, n_global, r_md, criterion = next(b for b in CLEARANCE_BASES if b[0] == name)
            options = {"r_c": r_c, "global_md": n_global, "r_md": r_md, "criterion": criterion}
            r = roms[name].r
            cost = offline[name] + sum(c.costs[name] for c in studies["study"])
        cands.append(dict(name=name, options=options, cost=cost, error=max(errs["study"]),
                          held_out_error=max(errs["held_out"]), errors=errs, r=r,
                          online_s=sum(c.costs.get(name, 0.0) for c in studies["study"]),
                          offline_s=offline.get(name, 0.0)))
    return dict(description="clearance consumption at node LE of 1B at zeta = 1 mm and 1T at zeta = 0.5 mm (the "
                            "paper's cases), delta in [-1, 1]: largest relative error against the full-order "
                            "nonlinear curves (ci mesh)",
                cost_unit="s (offline build + the 2 x 20 static solves)",
                reference={"FOM nonlinear wall_s": sum(c.costs["FOM nonlinear"] for c in studies["study"])},
                candidates=cands, held_out_case="the same modes at 1.5 times the amplitude (1B 1.5 mm, 1T 0.75 mm)")


# ## The turning blade: reduced bases against the full order over speed

ROTATING_BASES = (  # (name, spin_snapshots, spin_modes); r_c 15 with the 6 global modal derivatives of 1B-1T-2B
    ("snapshots 1,000 + 2,000", (1000.0, 2000.0), 0), ("snapshots 2,000 + 2 modes", (2000.0,), 2),
    ("snapshots 1,000 + 2,000 + 2 modes", (1000.0, 2000.0), 2),
    ("snapshots 1,000 + 2,000 + 4 modes", (1000.0, 2000.0), 4),
)
ROTATING_STUDY = (1200.0, 1600.0)       # the maps' range (rad/s); the other speeds of 0-2,000 are held out


def scene_rotating_modes() -> dict:
    """The turning ci blade (``studies.rotating_rom``): every basis of ``ROTATING_BASES`` against the full order at
    0-2,000 rad/s by 100; error: the largest relative error of modes 1-3 and of the tip's centrifugal displacement at
    1,200-1,600 rad/s; held out: the other speeds."""
    import tempfile

    from rotor37_rom.studies.rotating_rom import RotatingRomConfig, run_rotating_rom

    with tempfile.TemporaryDirectory() as out:
        result = run_rotating_rom(RotatingRomConfig(candidates=ROTATING_BASES, speeds=(0.0, 2000.0, 21), n_modes=3,
                                                    out=Path(out)))
    study = (result.speeds >= ROTATING_STUDY[0]) & (result.speeds <= ROTATING_STUDY[1])
    cands = []
    for row in result.rows:
        err = np.maximum(np.abs(row["frequency_error"]).max(axis=1), row["state_error"])
        cands.append(dict(name=row["label"], options={"r_c": 15, "global_md_modes": 3,
                                                      "spin_snapshots": row["spin_snapshots"],
                                                      "spin_modes": row["spin_modes"]},
                          cost=row["build_s"] + row["per_speed_s"] * int(study.sum()),
                          error=float(err[study].max()), held_out_error=float(err[~study].max()), r=row["r"],
                          offline_s=row["build_s"], online_s=row["per_speed_s"] * int(study.sum()),
                          errors={"speeds_rad_s": result.speeds.tolist(), "largest": err.tolist()}))
        say(f"rotating-modes: {row['label']}: r = {row['r']}, error {cands[-1]['error']:.1e}, held out "
              f"{cands[-1]['held_out_error']:.1e}, cost {cands[-1]['cost']:.1f} s")
    return dict(description="the turning ci blade's frequencies of modes 1-3 and its tip's centrifugal displacement "
                            "at 1,200-1,600 rad/s by 100 (the maps' range): largest relative error against the full "
                            "order (prestressed, spin softened)",
                cost_unit="s (build + the 5 study speeds' centrifugal state and modes)",
                reference={"full_order_s": result.full_per_speed_s * int(study.sum())},
                candidates=cands, held_out_case="the other speeds of 0-2,000 rad/s by 100")
