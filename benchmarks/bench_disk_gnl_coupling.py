"""Where the disk models' GNL error comes from (issue #20): the basis, or the nonlinear force's coupling (eq. 61).

The disk model's nonlinear force of sector n acts on its q^n part only (Phi_s q^n, eq. 61: "linear coupling through
the disk"); the part of the sector's field carried by the cyclic faces' constraint modes (Psi_L u_L^n + Psi_R'
u_L^(n+1)) enters the linear matrices but not the nonlinear force. For a 0-diameter load every sector moves alike and
the disk model reduces exactly to one sector with its faces tied: q^n the same for all n, u_L = Pi_0 eta on the k = 0
interface modes only. On that tied sector (the disk model's own Phi_s, Psi_L, Psi_R' and k = 0 interface modes, r =
r_s + 6 on the ci sector) this script integrates the patch-load GNL case of ``bench_disk_forced.py`` three ways, with
the same Newmark at the same step as the full-order reference:

- "eq. 61": the nonlinear force of Phi_s q^n only, as the disk model (its I matches the 36-sector model's);
- "whole sector field": the nonlinear force of the whole sector field, faces included (exact tensors of [Phi_s,
  (Psi_L + Psi_R') Pi_0]);
- "linear": no nonlinear force;
- "faces on n_f shapes" (``--face-shapes``): the force of the disk model built with ``face_shapes = n_f``
  (``DiskReductionConfig``: each face on n_f shapes, ``disk.assembly.face_shapes``), restricted to the tied sector;

and reports each one's performance indicator (``disk.indicators.performance_indicator``) next to the smallest errors any
state of the basis can have (``disk.indicators.best_approximation``). The full-order GNL reference is
``bench_disk_forced.py``'s (cached under results/disk_forced/<preset>/; computed, about 20 min on the ci preset, when
missing) and the disk models are its cached ones (built when missing):

    python benchmarks/bench_disk_gnl_coupling.py [--preset ci] [--r-md 10 20 40] [--patch 3] [--face-shapes 6 12]
        [--faces-only] [--name SUFFIX]

Results: results/disk_gnl_coupling_<preset><SUFFIX>.json.

Every option is checked, and the folders written in, before any work: a bad one is one line on stderr and exit
status 2. ``--check`` does only that (exit status 0); SIGTERM or SIGINT stop the run with one line
(``rotor37_rom.cli.run_main``).
"""
from __future__ import annotations

import re
import sys
import time
from pathlib import Path
from typing import Sequence

import numpy as np

from rotor37_rom.checks import before_work, real_number, whole_number
from rotor37_rom.cli import ArgumentParser, run_main
from rotor37_rom.reduction.craig_bampton import CRITERIA

OMEGA, PERIODS, SPP, RAMP = 4000.0, 10, 100, 1.0
R_C, R_CYCLIC = 10, 144
#: modal derivatives per sector at most: the pairs (j <= k) of the sector's 14 linear columns (node LE's 3 constraint
#: modes, the R_C fixed-interface modes and the patch load's static correction): 14 x 15 / 2
MAX_R_MD = (3 + R_C + 1) * (3 + R_C + 2) // 2
MAX_FACE_SHAPES = R_CYCLIC       # shapes per face at most (and at most the face's DOFs, checked once it is built)


class _Mapped:
    """A force on coordinates x = G q (G: m x r), pulled back to q: G^T f(G q), Jacobian G^T J G."""

    def __init__(self, forces, G: np.ndarray):
        self.forces, self.G = forces, G

    def evaluate(self, Q):
        return self.G.T @ self.forces.evaluate(self.G @ np.asarray(Q, float).reshape(self.G.shape[1], -1))

    def jacobian(self, q):
        return self.G.T @ self.forces.jacobian(self.G @ np.asarray(q, float)) @ self.G


def tied_basis(model) -> tuple[np.ndarray, int, np.ndarray]:
    """Sector 0's fields of the disk model under a 0-diameter state: [Phi_s, (Psi_L + Psi_R') Pi_0] on the k = 0
    interface modes (those equal on every sector), r_s, and those modes' face displacements Pi_0 (n_L, 6)."""
    b = model.sectors
    N, nL = b.n_sectors, b.Psi_L.shape[1]
    blocks = b.Pi.reshape(N, nL, -1)
    k0 = np.abs(blocks - blocks[0]).max(axis=(0, 1)) <= 1e-9 * np.abs(b.Pi).max()
    return np.hstack([b.Phi_s, (b.Psi_L + b.Psi_Rr) @ blocks[0][:, k0]]), b.Phi_s.shape[1], blocks[0][:, k0]


def face_shape_force(sector, model, r_s: int, Pi0: np.ndarray, n_f: int):
    """The force of the disk model with ``face_shapes = n_f`` (``disk.assembly.face_shapes``: the faces on n_f shapes L)
    restricted to the tied sector: x = [q; L^T Pi_0 eta; L^T Pi_0 eta] (both faces alike under k = 0)."""
    from rotor37_rom import fem
    from rotor37_rom.disk.assembly import face_shapes
    from rotor37_rom.forces.tensors import QuadratureForces, compute_polynomial_forces

    b = model.sectors
    eta = slice(b.blocks.size, model.r)
    omega = np.sqrt(np.diag(model.K)[eta] / np.diag(model.M)[eta])   # the interface modes are K- and M-orthogonal
    L, _ = face_shapes(b.Pi, omega, b.n_sectors, n_f)
    H, w, _ = fem.quadrature_gradients(sector, np.hstack([b.Phi_s, b.Psi_L @ L, b.Psi_Rr @ L]).T)
    forces = compute_polynomial_forces(QuadratureForces(H, w, *sector.material.lame))
    A = L.T @ Pi0
    G = np.zeros((r_s + 2 * n_f, r_s + Pi0.shape[1]))
    G[:r_s, :r_s] = np.eye(r_s)
    G[r_s:r_s + n_f, r_s:] = A
    G[r_s + n_f:, r_s:] = A
    return _Mapped(forces, G)


def build_parser() -> ArgumentParser:
    p = ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--preset", default="ci", choices=["ci", "coarse", "paper"],
                   help="mesh preset of the disk sector (default ci)")
    p.add_argument("--r-md", nargs="+", type=int, default=[10, 20, 40],
                   help=f"modal derivatives per sector of the disk models, each in 1..{MAX_R_MD} (the coupling acts "
                        f"through them; default 10 20 40)")
    p.add_argument("--criterion", default="MI2b", choices=CRITERIA,
                   help="the modal derivatives' selection criterion (default MI2b)")
    p.add_argument("--patch", type=float, default=3.0, help="load patch radius (mm), in (0, 20] (default 3)")
    p.add_argument("--out", default="results/disk_forced",
                   help="folder of bench_disk_forced.py's cached GNL reference and disk models, OUT/<preset> "
                        "(default results/disk_forced)")
    p.add_argument("--face-shapes", nargs="*", type=int, default=[],
                   help=f"also the disk model's force with the faces on these numbers of shapes "
                        f"(disk.face_shapes), each in 1..{MAX_FACE_SHAPES} (default none)")
    p.add_argument("--faces-only", action="store_true", help="only the --face-shapes variants (needs --face-shapes)")
    p.add_argument("--name", default="",
                   help="results file suffix, letters, digits, '_', '-' or '.': "
                        "results/disk_gnl_coupling_<preset><name>.json (default none)")
    return p


def check_options(args) -> None:
    """Every option checked: ValueError naming it and its range."""
    for r_md in args.r_md:
        whole_number("--r-md (the coupling acts through the modal derivatives)", r_md, 1, MAX_R_MD)
    real_number("--patch (load patch radius)", args.patch, 0, 20, open_low=True, unit=" mm")
    for n_f in args.face_shapes:
        whole_number("--face-shapes", n_f, 1, MAX_FACE_SHAPES)
    if args.faces_only and not args.face_shapes:
        raise ValueError("--faces-only needs --face-shapes (the only variants it runs): nothing would run")
    if not re.fullmatch(r"[\w.-]*", args.name):
        raise ValueError(f"--name must be letters, digits, '_', '-' or '.' (a file name's suffix), got {args.name!r}")


def main(argv: Sequence[str] | None = None) -> int:
    """Check the options, then the reference (cached), the disk models and the tied sector's variants; raises
    ValueError for a bad input."""
    args = build_parser().parse_args(argv)
    check_options(args)
    out = Path(args.out) / args.preset
    before_work({"--out": out, "the results folder": Path("results")})    # before any work; a dry run stops here

    from rotor37_rom import fem
    from rotor37_rom.disk.indicators import best_approximation, performance_indicator
    from rotor37_rom.disk.loads import travelling_load
    from rotor37_rom.dynamics.newmark import simulate_newmark
    from rotor37_rom.fem.periodic import RepeatingSectors
    from rotor37_rom.forces.tensors import QuadratureForces, compute_polynomial_forces
    from rotor37_rom.machine import write_results
    from rotor37_rom.reduction.disk_builder import DiskReductionConfig, build_disk_model
    from rotor37_rom.studies.forced_response import AMPLITUDE, reference, sector_load

    sector = fem.create_disk_sector(preset=args.preset)
    system = RepeatingSectors(sector, 1)
    ops = system.ops
    K_s = fem.petsc_to_scipy(fem.assemble_stiffness(sector, ops, clamped=False))
    M_s = fem.petsc_to_scipy(fem.assemble_mass(sector, ops, clamped=False))
    ref = reference(sector, system, (0, OMEGA), True, PERIODS, SPP, RAMP, out, patch_mm=args.patch)
    le = sector.tip_names.index("LE")
    tip_dofs = np.asarray(sector.tip_dofs)
    f = sector_load(sector, args.patch)
    T = 2 * np.pi / OMEGA
    rows = []
    for r_md in args.r_md:
        config = DiskReductionConfig(tip_nodes="LE", r_c=R_C, r_md=r_md, criterion=args.criterion, r_cyclic=R_CYCLIC,
                                     forces="intrusive", load_patch=1e-3 * args.patch)
        model, _ = build_disk_model(sector, config, ops=ops, cache_dir=out / "models")
        B, r_s, Pi0 = tied_basis(model)
        K0, M0 = B.T @ (K_s @ B), B.T @ (M_s @ B)
        load = travelling_load((B.T @ f)[:, None], AMPLITUDE, OMEGA, 0, RAMP * T)   # as the disk's, one sector
        t0 = time.perf_counter()
        variants = []
        if not args.faces_only:
            H, w, _ = fem.quadrature_gradients(sector, B.T)
            lame = sector.material.lame
            whole = compute_polynomial_forces(QuadratureForces(H, w, *lame))
            leading = _Mapped(compute_polynomial_forces(QuadratureForces(np.ascontiguousarray(H[:, :r_s]), w, *lame)),
                              np.eye(B.shape[1])[:r_s])          # q^n's coordinates only
            del H
            variants = [("whole sector field", whole), ("eq. 61", leading), ("linear", None)]
        variants += [(f"faces on {n_f} shapes", face_shape_force(sector, model, r_s, Pi0, n_f))
                     for n_f in args.face_shapes]
        tensors = time.perf_counter() - t0
        best = best_approximation(model.sectors, ref["fields"], K_s, M_s)
        for name, forces in variants:
            t0 = time.perf_counter()
            _, Q = simulate_newmark(M0, np.zeros_like(M0), K0, load, T / SPP, PERIODS * SPP, forces=forces)
            wall = time.perf_counter() - t0
            tip = (B[tip_dofs.ravel()] @ Q).T.reshape(-1, 1, *tip_dofs.shape)
            fields = (B @ Q[:, ref["snapshots"]]).T[:, None, :]
            score = performance_indicator(ref["tip"], tip, ref["fields"], fields, K_s, M_s, loaded=(le, 2))
            rows.append({"criterion": args.criterion, "r_md": r_md, "r_disk": model.r, "r_tied": B.shape[1],
                         "forces": name, "I": score["I"], "errors": score["errors"], "best_approximation": best,
                         "rom_wall_s": wall, "tensors_s": tensors, "fom_wall_s": float(ref["wall"]),
                         "rom_max_le_z_mm": 1e3 * float(np.abs(tip[:, 0, le, 2]).max()),
                         "max_le_z_mm": 1e3 * float(np.abs(ref["tip"][:, 0, le, 2]).max())})
            machine = write_results(f"disk_gnl_coupling_{args.preset}{args.name}", rows, patch_mm=args.patch,
                                    omega=OMEGA, periods=PERIODS, steps_per_period=SPP)
            print(f"r_md {r_md:3d} (disk r {model.r}, tied r {B.shape[1]}) {name:18s} I = {score['I']:.4f}  "
                  + " ".join(f"{k}: {v:.3f}" for k, v in score["errors"].items())
                  + f"  (basis alone: {best['field']:.3f} / {best['strain energy']:.3f})  {wall:.0f} s", flush=True)
    print(f"{machine}; results in results/disk_gnl_coupling_{args.preset}{args.name}.json")
    return 0


if __name__ == "__main__":
    sys.exit(run_main(main))
