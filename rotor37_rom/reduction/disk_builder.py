"""Build the reduced model of a bladed disk from one cyclic sector (paper §3.1): the sector's Craig-Bampton basis
with its tip and both cyclic faces as boundary, modal derivatives of the sector clamped on that boundary, the
sector's matrices on [q, u_L, u_L of the next sector], the interface reduction and the disk's matrices
(``rotor37_rom.disk.assembly``), and the sector's reduced nonlinear force evaluated with the sectors as batch columns.

The FE work goes through ``rotor37_rom.fem`` and the steps the blade's builder already has (Craig-Bampton, the
selection criteria, exact modal derivatives with the fixed-interface correction, quadrature forces and tensors).
"""
from __future__ import annotations

import dataclasses
import hashlib
import logging
from pathlib import Path

import numpy as np

from rotor37_rom import __version__, fem
from rotor37_rom.reduction.config import DiskReductionConfig
from rotor37_rom.reduction.builder import (SPIN_SNAPSHOT_PAIR, _m_normalise, _spin_snapshots, begin_build,
    boundary_node_map, compute_modal_derivatives, mesh_signature)
from rotor37_rom.disk.symmetry import rotation_z
from rotor37_rom.disk.assembly import (SectorMatrices, assemble_disk_matrices, assemble_disk_operator,
    assemble_disk_vector, disk_node_map, face_shapes, interface_modes)
from rotor37_rom.model.disk_basis import DiskBasis
from rotor37_rom.forces.sector import SectorForces
from rotor37_rom.forces.tensors import QuadratureForces, compute_polynomial_forces
from rotor37_rom.npz import load_npz, save_npz
from rotor37_rom.reduction.craig_bampton import (CraigBamptonBasis, craig_bampton, modal_damping,
    select_pairs, selection_weights)
from rotor37_rom.model.reduced import ReducedModel, reduced_model_key, save_reduced_model
from rotor37_rom.model.rotating import RotationTerms
from rotor37_rom.dynamics.newmark import simulate_linear_newmark

__all__ = ["DiskReductionConfig", "build_disk_model"]

LOG = logging.getLogger(__name__)


def _static_load_correction(M_f, boundary: np.ndarray, f: np.ndarray, Theta: np.ndarray, solve_ii) -> np.ndarray:
    """The static response to f with the boundary DOFs held (zero there), M-orthogonal to the fixed-interface modes
    Theta (M-orthonormal) and of unit M-norm: the part of the load's local field that they do not carry.
    ``solve_ii``: B -> K_ii^-1 B on the interior DOFs (ascending), Craig-Bampton's own factorisation."""
    interior = np.setdiff1d(np.arange(M_f.shape[0]), boundary)
    x = np.zeros(M_f.shape[0])
    x[interior] = solve_ii(f[interior])
    x -= Theta @ (Theta.T @ (M_f @ x))
    norm = float(np.sqrt(x @ (M_f @ x)))
    if not norm > 0:
        raise ValueError("load_patch: the load's static response lies in the fixed-interface modes' span")
    return x / norm


def _positions(free: np.ndarray, dofs: np.ndarray, what: str) -> np.ndarray:
    pos = np.searchsorted(free, dofs)
    if dofs.size == 0 or np.any(pos >= free.size) or not np.array_equal(free[np.minimum(pos, free.size - 1)], dofs):
        raise ValueError(f"{what}: DOFs must be on the mesh and not clamped")
    return pos


def _tied(A: np.ndarray, n_lin: int, n_L: int) -> np.ndarray:
    """A matrix on [lin, Psi_L, Psi_Rr] (n_lin + 2 n_L) on the tied basis [lin, Psi_L + Psi_Rr]: the right face's rows
    and columns added to the left face's (no new products with the sector's operators)."""
    m = n_lin + n_L
    T = A[:m, :m].copy()
    T[:, n_lin:] += A[:m, m:]
    T[n_lin:] += A[m:, :m]
    T[n_lin:, n_lin:] += A[m:, m:]
    return T


def _with_derivatives(A_B: np.ndarray, A_f, B: np.ndarray, n_lin: int, r_s: int) -> np.ndarray:
    """B^T A_f B for B = [lin, Z, Psi_L, Psi_Rr] (the modal derivatives Z: its columns n_lin ... r_s - 1) from A_B,
    the same matrix without Z's rows and columns (computed before Z existed): only Z's products with A_f are new."""
    rest = np.r_[:n_lin, r_s:B.shape[1]]
    out = np.empty((B.shape[1], B.shape[1]))
    out[np.ix_(rest, rest)] = A_B
    A_Z = A_f @ B[:, n_lin:r_s]
    out[:, n_lin:r_s] = B.T @ A_Z
    out[n_lin:r_s] = A_Z.T @ B
    return out


def _disk_metadata(sector, config: DiskReductionConfig) -> dict:
    """What a disk model's key hashes: its configuration, mesh, version, damping and training load."""
    config_meta = dataclasses.asdict(config)
    if not config.face_shapes:                     # eq. 61's models keep the keys they were cached under
        config_meta.pop("face_shapes")
    if not config.spin_snapshots:                  # likewise the models at rest
        config_meta.pop("spin_snapshots")
        config_meta.pop("spin_modes")
    metadata = {"config": config_meta, "mesh": mesh_signature(sector), "source": sector.source,
                "version": __version__, "kind": "disk", "n_sectors": sector.cyclic.n_sectors,
                "damping": "5e-4 on the 3 N lowest modes", "blade_frame": "centre of mass"}
    if config.load_patch:
        metadata["load_correction"] = "one static vector per sector, its modal derivatives among the candidates"
    else:                                    # models cached before the point load was put on node LE are not read
        metadata["training_load"] = "node LE, e_z"
    return metadata


def _sector_craig_bampton(sector, config: DiskReductionConfig, K_f, M_f, free: np.ndarray, boundary: np.ndarray,
                          pos: np.ndarray, mesh: str, cache_dir, factorised: list):
    """(Psi_f, Theta_f, omega_c): the sector's constraint and fixed-interface modes on its free DOFs, computed or read
    from their cache; K_ii's factorisation appended to ``factorised`` when a load patch needs it.

    The sector's Craig-Bampton modes depend on the mesh, the boundary and r_c only: models that differ in r_MD, face
    shapes, the load patch or mistuning share them (a cache beside the models': n_free x (r_b + 2 n_L + r_c))."""
    def solve(A):
        factorised.append(fem.mumps_solver(A))
        return factorised[-1]

    cb_meta = {"mesh": mesh, "source": sector.source, "r_c": config.r_c, "version": __version__,
               "kind": "disk Craig-Bampton", "boundary": boundary.tolist(),
               "free": hashlib.sha256(np.ascontiguousarray(free, np.int64).tobytes()).hexdigest()}
    cb_file = Path(cache_dir) / f"disk_cb_{reduced_model_key(cb_meta)}.npz" if cache_dir else None

    def shapes(arrays: dict) -> None:
        if arrays["Psi"].shape != (free.size, boundary.size) or arrays["Theta"].shape != (free.size, config.r_c):
            raise ValueError(f"shapes {arrays['Psi'].shape}, {arrays['Theta'].shape}")

    cb = load_npz(cb_file, ("Psi", "Theta", "omega_c"), shapes, what="Craig-Bampton cache")
    if cb is not None:
        LOG.info("Craig-Bampton modes read from %s", cb_file)
        if config.load_patch:               # the correction's solve on the interior DOFs
            interior = np.setdiff1d(np.arange(free.size), pos)
            factorised.append(fem.mumps_solver(K_f[interior][:, interior]))
        return cb["Psi"], cb["Theta"], cb["omega_c"]
    Psi_f, Theta_f, omega_c = craig_bampton(K_f, M_f, pos, config.r_c, solve=solve, eigensolve=fem.slepc_eigenpairs)
    if cb_file is not None:
        save_npz(cb_file, Psi=Psi_f, Theta=Theta_f, omega_c=omega_c)
    return Psi_f, Theta_f, omega_c


def _force_faces(Pi: np.ndarray, omega_pi: np.ndarray, N: int, count: int, centrifugal: list
                 ) -> tuple[np.ndarray, np.ndarray] | None:
    """The face shapes L the force sees and every sector's face coordinates (``face_shapes``'s pair): the
    centrifugal states' faces (so that the force is exact on those states) and ``count`` shapes of the interface
    modes, orthonormalised together; None for neither (eq. 61)."""
    if not count and not centrifugal:
        return None
    nL = Pi.shape[0] // N
    L = np.zeros((nL, 0)) if not count else face_shapes(Pi, omega_pi, N, count)[0]
    if centrifugal:
        Q, R = np.linalg.qr(np.column_stack([np.column_stack(centrifugal), L]))
        L = Q[:, np.abs(np.diag(R)) > 1e-10 * np.abs(np.diag(R)).max()]
    P = np.einsum("lf,nlc->nfc", L, Pi.reshape(N, nL, -1))
    return L, np.concatenate([P, np.roll(P, -1, axis=0)], axis=1)


def _sector_forces(sector, config: DiskReductionConfig, Phi_s, Psi_L, Psi_Rr, Pi, omega_pi, free, blocks, r: int,
                   scales, centrifugal: list) -> SectorForces:
    """The disk's nonlinear force: the sector's exact quadrature (or its tensors) on Phi_s, with ``face_shapes`` (or
    the centrifugal states' faces) also on the faces' shapes [Phi_s, Psi_L L, Psi_R' L], applied to every sector
    (eq. 61)."""
    N, r_s, n_full = blocks.shape[0], Phi_s.shape[1], Phi_s.shape[0]
    Phi_nl, faces = Phi_s, None
    shapes = _force_faces(Pi, omega_pi, N, config.face_shapes, centrifugal)
    if shapes is not None:               # the faces in the force, on a few shapes: [Phi_s, Psi_L L, Psi_R' L]
        L, faces = shapes
        Phi_nl = np.zeros((n_full, r_s + 2 * L.shape[1]))
        Phi_nl[:, :r_s] = Phi_s
        Phi_nl[free, r_s:] = np.hstack([Psi_L @ L, Psi_Rr @ L])
    H, w, _ = fem.quadrature_gradients(sector, Phi_nl.T)
    exact = QuadratureForces(H, w, *sector.material.lame)
    sector_forces = compute_polynomial_forces(exact) if config.forces == "intrusive" else exact
    return SectorForces(sector_forces, blocks, r, scales, faces)


def _with_index0_faces(s: SectorMatrices, Pi: np.ndarray, omega: np.ndarray, k: np.ndarray, faces: list,
                       n_sectors: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The interface modes with the centrifugal states' face shapes added: each a harmonic-index-0 column (the same
    left face a in every sector: tiled), less its part in the columns already there (a tiled column stays tiled: the
    other indices' columns are orthogonal to it), scaled to a unit interface mass; dropped where that part leaves
    less than 1e-8 of it. Its frequency is its Rayleigh quotient on the faces' blocks."""
    cols, omegas = [Pi], [omega]
    K_faces, M_faces = s.faces(s.K), s.faces(s.M)
    for a in faces:
        t = np.tile(np.asarray(a, float), n_sectors)
        size = np.linalg.norm(t)
        for _ in range(2):                                    # twice: Gram-Schmidt's round-off
            basis = np.hstack(cols)
            t = t - basis @ np.linalg.lstsq(basis, t, rcond=None)[0]
        if not np.linalg.norm(t) > 1e-8 * size:
            continue
        face = np.concatenate([t[:s.n_L], t[:s.n_L]])          # [u_L; u_L of the next sector]: the same a
        stiffness, mass = face @ K_faces @ face, face @ M_faces @ face
        cols.append((t / np.sqrt(n_sectors * mass))[:, None])
        omegas.append(np.array([np.sqrt(max(stiffness, 0.0) / mass)]))
    added = len(cols) - 1
    return np.hstack(cols), np.concatenate(omegas), np.concatenate([k, np.zeros(added, dtype=k.dtype)])


def build_disk_model(sector, config: DiskReductionConfig = DiskReductionConfig(), ops=None,
                     cache_dir: str | Path | None = None) -> tuple[ReducedModel, dict]:
    """The disk's reduced model (r = N (r_b + r_c + r_load + r_MD) + r_cyclic, eq. 53) from a cyclic sector (serial).

    Returns (model, report): the model is a ReducedModel like a blade's (its ``nodes`` cover all sectors' tip
    nodes, its forces are ``forces.sector.SectorForces``, ``model.sectors`` the DiskBasis); the report has the timings,
    the
    selection weights and pairs, the interface modes' frequencies and nodal diameters, the sector frequencies."""
    if sector.cyclic is None:
        raise ValueError(f"{sector.source} is not a cyclic sector: build a disk model from fem.create_disk_sector")
    pairs = sector.cyclic
    N = pairs.n_sectors
    if config.mistuning is not None and len(config.mistuning) != N:
        raise ValueError(f"mistuning: give one factor per sector ({N}), got {len(config.mistuning)}")
    if config.r_cyclic > N * pairs.left.size:
        raise ValueError(f"r_cyclic must be in [1, {N * pairs.left.size}] (the disk's cyclic DOFs), got "
                         f"{config.r_cyclic}")
    ops = ops or fem.create_svk_operators(sector)
    tip_rows = [sector.tip_names.index("LE")] if config.tip_nodes == "LE" else list(range(len(sector.tip_names)))
    tip_dofs = np.asarray(sector.tip_dofs)[tip_rows].ravel()
    metadata = _disk_metadata(sector, config)
    cache, cached, report, lap, operators = begin_build(sector, ops, metadata, cache_dir, "disk")
    if cached is not None:
        return cached, report
    K_f, M_f, free = operators
    n_full = sector.n_dofs
    left, right = pairs.left.ravel(), pairs.right.ravel()
    boundary = np.concatenate([tip_dofs, left, right])
    pos = _positions(free, boundary, "tip and cyclic DOFs")
    factorised = []                          # K_ii's factorisation, kept for the load correction below
    Psi_f, Theta_f, omega_c = _sector_craig_bampton(sector, config, K_f, M_f, free, boundary, pos, metadata["mesh"],
                                                    cache_dir, factorised)
    nb, nL = tip_dofs.size, left.size
    R_blk = np.kron(np.eye(nL // 3), rotation_z(pairs.angle))          # u_R = R u_L of the next sector, per node
    Psi_tip, Psi_L, Psi_Rr = Psi_f[:, :nb], Psi_f[:, nb:nb + nL], Psi_f[:, nb + nL:] @ R_blk
    lap("craig_bampton")
    le = sector.tip_names.index("LE")
    S_f = np.zeros((free.size, 0))
    if config.load_patch:                    # the patch's static correction, a fixed-interface vector like Theta's
        f_free = fem.patch_load(sector, sector.tip_nodes[le], config.load_patch, component=2)[free]
        S_f = _static_load_correction(M_f, pos, f_free, Theta_f, factorised[-1])[:, None]
    else:                                    # the unit force on node LE's e_z (a free DOF: the rows of tied below)
        f_free = np.zeros(free.size)
        f_free[pos[np.flatnonzero(boundary == sector.tip_dofs[le, 2])[0]]] = 1.0
    factorised.clear()                       # MUMPS frees K_ii's factors
    # training (§3.3.1): the 0-diameter load at node LE along e_z, on the sector with its faces tied for k = 0
    lin = np.hstack([Psi_tip, Theta_f, S_f])
    n_lin = lin.shape[1]
    tied = np.hstack([lin, Psi_L + Psi_Rr])
    # the sector's matrices on [lin, Psi_L, Psi_Rr], B below without its modal derivatives, computed once (seconds of
    # sparse and dense products): tied's are sums of their rows and columns, B's get the modal derivatives' ones
    B = np.hstack([lin, Psi_L, Psi_Rr])
    K_B, M_B = B.T @ (K_f @ B), B.T @ (M_f @ B)
    del B                                    # n_free x (n_lin + 2 n_L), not kept through the modal derivatives
    K0, M0 = _tied(K_B, n_lin, nL), _tied(M_B, n_lin, nL)
    C0, _ = modal_damping(K0, M0)
    f_shape = config.training_force * (tied.T @ f_free)
    period = 2 * np.pi / config.training_omega
    t, q_train = simulate_linear_newmark(M0, C0, K0, lambda tt: f_shape * np.sin(config.training_omega * tt),
                                         period / 400, 400)
    q_train = q_train[:lin.shape[1]]
    lin_full = np.zeros((n_full, lin.shape[1]))
    lin_full[free] = lin
    lin_forces = None
    if config.criterion == "SMVW":
        H, w, _ = fem.quadrature_gradients(sector, lin_full.T)
        lin_forces = QuadratureForces(H, w, *sector.material.lame)
    W = selection_weights(config.criterion, q_train, t, lin_full, lin_forces, seed=config.seed)
    chosen = select_pairs(W, config.r_md)
    report["weights"], report["pairs"] = W, chosen
    lap("selection")
    # modal derivatives of [Psi_tip, Theta, S], made zero on the tip and both faces by all constraint modes (eq. 20)
    Psi_full, Theta_full = np.zeros((n_full, Psi_f.shape[1])), np.zeros((n_full, Theta_f.shape[1] + S_f.shape[1]))
    Psi_full[free], Theta_full[free] = Psi_f, np.hstack([Theta_f, S_f])
    basis = CraigBamptonBasis(Psi=Psi_full, Theta=Theta_full, omega_c=omega_c, boundary_dofs=boundary)
    index = np.r_[np.arange(nb), Psi_f.shape[1] + np.arange(Theta_full.shape[1])]   # lin's columns in basis.linear
    Z = compute_modal_derivatives(sector, ops, basis, index[chosen] if len(chosen) else chosen, "exact",
                                  solve=fem.mumps_solver(K_f))
    chosen = np.asarray(chosen, dtype=np.int64).reshape(-1, 2)
    faces_c = []                             # the centrifugal states' left faces (each an index-0 interface shape)
    if config.spin_snapshots:
        states = [fem.centrifugal_state(sector, w, ops).x.array.copy() for w in config.spin_snapshots]
        snapshots, report["spin_snapshot_remainder"] = _spin_snapshots(sector, ops, basis, Z, M_f, free,
                                                                       config.spin_snapshots, config.spin_modes,
                                                                       states=states)
        Z = np.hstack([Z, snapshots])
        chosen = np.vstack([chosen, np.full((snapshots.shape[1], 2), SPIN_SNAPSHOT_PAIR, dtype=np.int64)])
        faces_c = [u[left] for u in states]
        ops.u.x.array[:] = 0.0                # centrifugal_state leaves its last state in the operators' u
        lap("centrifugal_states")
    Z, md_scale = _m_normalise(Z, M_f, free) if Z.shape[1] else (Z, np.zeros(0))
    Phi_s = np.hstack([Psi_full[:, :nb], Theta_full, Z])                 # Theta_full ends with S
    r_s = Phi_s.shape[1]
    lap("modal_derivatives")
    B = np.hstack([Phi_s[free], Psi_L, Psi_Rr])                      # Phi_s[free] = [lin, Z[free]]
    s = SectorMatrices(K=_with_derivatives(K_B, K_f, B, n_lin, r_s), M=_with_derivatives(M_B, M_f, B, n_lin, r_s),
                       r_s=r_s, n_L=nL, omega_c=omega_c)
    Pi, omega_pi, k_pi = interface_modes(s, N, config.r_cyclic, selection=config.interface)
    if faces_c:
        Pi, omega_pi, k_pi = _with_index0_faces(s, Pi, omega_pi, k_pi, faces_c, N)
    scales = np.ones(N) if config.mistuning is None else np.asarray(config.mistuning, float)
    K, M = assemble_disk_matrices(s, Pi, N, scales)
    C, omega = modal_damping(K, M, n_low=3 * N)             # the blade's 1B, 1T, 2B ratio for those families
    report.update(omega=omega, omega_c=omega_c, interface_omega=omega_pi, interface_k=k_pi, q_train=q_train,
                  md_scale=md_scale, sector_matrices=s)
    lap("assembly")
    blocks = np.arange(N * r_s).reshape(N, r_s)
    forces = None
    if config.forces != "none":
        forces = _sector_forces(sector, config, Phi_s, Psi_L, Psi_Rr, Pi, omega_pi, free, blocks, K.shape[0], scales,
                                faces_c)
        lap("forces")
    sector_nodes = boundary_node_map(sector, tip_dofs)
    Psi_L_full, Psi_Rr_full = np.zeros((n_full, nL)), np.zeros((n_full, nL))
    Psi_L_full[free], Psi_Rr_full[free] = Psi_L, Psi_Rr
    rotation = None
    if config.spin_snapshots:                # exact on the basis: M_P, F_c and G are linear in u
        MP_B, F_B, G_B = fem.reduced_rotation_terms(sector, np.hstack([Phi_s, Psi_L_full, Psi_Rr_full]), ops)
        M_P, G = assemble_disk_operator(s, MP_B, Pi, N), assemble_disk_operator(s, G_B, Pi, N)
        rotation = RotationTerms(M_P=0.5 * (M_P + M_P.T), F_c=assemble_disk_vector(s, F_B, Pi, N),
                                 G=0.5 * (G - G.T), speeds=np.array(config.spin_snapshots))
        lap("rotation_terms")
    n_spin = int(np.sum(chosen[:, 0] == SPIN_SNAPSHOT_PAIR))
    model = ReducedModel(M=M, C=C, K=K, forces=forces, boundary_dofs=tip_dofs,
                         nodes=disk_node_map(sector_nodes, N, r_s),
                         sizes={"r_b": nb, "r_c": config.r_c, "r_load": S_f.shape[1], "r_md": Z.shape[1] - n_spin,
                                "n_sectors": N, "r_cyclic": Pi.shape[1], **({"r_spin": n_spin} if n_spin else {})},
                         md_pairs=chosen, Phi=None, metadata=metadata,
                         sectors=DiskBasis(Phi_s, Psi_L_full, Psi_Rr_full, Pi, blocks, N), rotation=rotation)
    if cache is not None:
        save_reduced_model(model, cache)
    LOG.info("disk model r = %d (N = %d x r_s = %d + r_cyclic = %d)", model.r, N, r_s, Pi.shape[1])
    return model, report
