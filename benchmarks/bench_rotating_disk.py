"""The turning bladed disk on one sector against the whole disk (#73): the centrifugal equilibrium and the
prestressed, spin-softened families k = 0, 1 and 18 of the rotor 37 disk sector (``fem.rotating_cyclic_operators``)
checked on the 36-sector annulus assembled from the sector (``disk.symmetry.assemble_full_structure``: its own
numbering and rotations, not the cyclic projection T_k).

- The state: the whole annulus's residual at the sector's state turned onto every sector, against the load.
- Each family's modes: the sector's mode expanded to the 36 sectors (``expand_sector_mode``, turned to the common
  frame) is an eigenvector of the assembled annulus: its Rayleigh quotient against omega^2 (relative) and its
  residual |K phi - omega^2 M phi| / |K phi|. The annulus has ~830,000 DOFs (ci): matrix-vector products only, no
  eigen-solve of it.
- Costs: the state, the operators, each family's modes; and the frequencies at rest beside them.

    python benchmarks/bench_rotating_disk.py [--preset ci] [--speed 1800] [--modes 4]

Results: results/bench_rotating_disk.json (machine stated).
"""
from __future__ import annotations

import argparse
import time

import numpy as np

from rotor37_rom import fem
from rotor37_rom.disk.symmetry import assemble_full_structure, expand_sector_mode, to_global_frame
from rotor37_rom.machine import write_results

FAMILIES = (0, 1, 18)


def _on_annulus(fields: np.ndarray, index: np.ndarray, dofs: np.ndarray, angle: float, size: int) -> np.ndarray:
    """Per-sector fields (N, n) in their own frames as one vector of the assembled annulus."""
    out = np.zeros(size)
    for s, f in enumerate(fields):
        out[index[s]] = to_global_frame(f, dofs, s * angle)
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--preset", default="ci", choices=["ci", "coarse"])
    parser.add_argument("--speed", type=float, default=1800.0, help="rad/s (default 1,800: rotor 37's design speed)")
    parser.add_argument("--modes", type=int, default=4, help="modes per family (default 4)")
    args = parser.parse_args(argv)
    if not (np.isfinite(args.speed) and args.speed > 0) or args.modes < 1:
        parser.exit(2, f"error: --speed must be > 0 rad/s and --modes >= 1, got {args.speed}, {args.modes}\n")
    t0 = time.perf_counter()
    sector = fem.create_disk_sector(preset=args.preset)
    ops = fem.create_svk_operators(sector)
    M = fem.assemble_mass(sector, ops)
    t_mesh = time.perf_counter() - t0
    t0 = time.perf_counter()
    u = fem.centrifugal_state(sector, args.speed, ops)
    t_state = time.perf_counter() - t0
    t0 = time.perf_counter()
    cyclic, _ = fem.rotating_cyclic_operators(sector, args.speed, ops, M)   # solves the state again: timed whole
    t_ops = time.perf_counter() - t0
    at_rest = fem.CyclicOperators(sector, fem.assemble_stiffness(sector, ops), M)
    N, angle = sector.cyclic.n_sectors, sector.cyclic.angle
    dofs = np.arange(sector.n_dofs).reshape(-1, 3)
    t0 = time.perf_counter()
    K_full, M_full, index = assemble_full_structure(fem.petsc_to_scipy(cyclic.K), fem.petsc_to_scipy(M),
                                                    sector.cyclic, dofs)
    t_full = time.perf_counter() - t0
    size = K_full.shape[0]
    print(f"{sector.source}: {sector.n_dofs} DOFs a sector, the annulus {size}; {args.speed:g} rad/s; mesh "
          f"{t_mesh:.1f} s, state {t_state:.1f} s (max |u| {np.abs(u.x.array).max() * 1e3:.3f} mm), operators "
          f"{t_ops:.1f} s, annulus assembled in {t_full:.1f} s")

    import ufl
    from dolfinx import fem as dfem

    from rotor37_rom import forms

    ops.u.x.array[:] = u.x.array
    f_int = fem.assemble_vector(ops.f_int).array.copy()
    f_c = fem.assemble_vector(dfem.form(forms.centrifugal_force(
        ops.u, ufl.TestFunction(sector.V), ops.constants["rho"], dfem.Constant(sector.mesh, args.speed)))).array.copy()
    clamped = sector.clamp_bc.dof_indices()[0]
    f_int[clamped] = f_c[clamped] = 0.0
    residual, load = np.zeros(size), np.zeros(size)
    for s in range(N):
        np.add.at(residual, index[s], to_global_frame(f_int - f_c, dofs, s * angle))
        np.add.at(load, index[s], to_global_frame(f_c, dofs, s * angle))
    state_residual = float(np.linalg.norm(residual) / np.linalg.norm(load))
    print(f"the annulus at the sector's state: |r| / |f_c| = {state_residual:.1e}")
    rows = []
    for k in FAMILIES:
        t0 = time.perf_counter()
        modes = cyclic.modes(k, args.modes)
        t_modes = time.perf_counter() - t0
        rest = at_rest.modes(k, args.modes).omega
        for i in modes.distinct()[1]:
            a = modes.a[i].x.array
            b = None if modes.b[i] is None else modes.b[i].x.array
            phi = _on_annulus(expand_sector_mode(a, b, k, N), index, dofs, angle, size)
            Kphi, Mphi = K_full @ phi, M_full @ phi
            w2 = modes.omega[i] ** 2
            rq = float(phi @ Kphi / (phi @ Mphi))
            row = {"k": k, "mode": len([r for r in rows if r["k"] == k]) + 1, "omega_rad_s": float(modes.omega[i]),
                   "at_rest_rad_s": float(rest[i]), "rayleigh_quotient_error": abs(rq / w2 - 1),
                   "residual": float(np.linalg.norm(Kphi - w2 * Mphi) / np.linalg.norm(Kphi)),
                   "modes_s": t_modes, "state_residual": state_residual, "speed_rad_s": args.speed}
            rows.append(row)
            print(f"k = {k:2d} mode {row['mode']}: {row['omega_rad_s']:9.2f} rad/s (at rest "
                  f"{row['at_rest_rad_s']:9.2f}); on the annulus: Rayleigh quotient "
                  f"{row['rayleigh_quotient_error']:.1e}, residual {row['residual']:.1e}; family solved in "
                  f"{t_modes:.1f} s")
    machine = write_results("bench_rotating_disk", rows, state_residual=state_residual, dofs_sector=sector.n_dofs,
                            dofs_annulus=size, state_s=t_state, operators_s=t_ops)
    print(f"machine: {machine}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
