"""Build a reduced model of a Sector: Craig-Bampton modes, selected modal derivatives, reduced cubic forces.

The FE work goes through rotor37_rom.fem (the adapter); the algebra is in reduction, nonlinear_forces, step and
ecsw. Offline products are cached under a key (parameters + mesh signature + version) when a cache folder is given.
"""
from __future__ import annotations

import dataclasses
import hashlib
import logging
import time
from pathlib import Path

import numpy as np

from rotor37_rom import __version__, fem
from rotor37_rom.forces.cubature import train_ecsw
from rotor37_rom.model.modes import normalise_signs
from rotor37_rom.forces.tensors import QuadratureForces, compute_polynomial_forces
from rotor37_rom.reduction.config import ReductionConfig
from rotor37_rom.reduction.pod import boundary_coordinates
from rotor37_rom.reduction.craig_bampton import (CraigBamptonBasis, craig_bampton,
    fixed_interface_correction, lift_states, modal_damping, select_pairs, selection_weights)
from rotor37_rom.model.nodes import NodeMap
from rotor37_rom.model.reduced import ReducedModel, load_reduced_model, reduced_model_key, save_reduced_model
from rotor37_rom.model.rotating import RotationTerms
from rotor37_rom.dynamics.newmark import simulate_linear_newmark
from rotor37_rom.forces.step import identify_step

__all__ = ["ReductionConfig", "build_reduced_model", "build_from_basis", "galerkin_operators", "exact_quadrature",
           "hyper_reduce", "release_freed_memory", "mesh_signature",
           "compute_modal_derivatives", "boundary_node_map",
           "training_states", "clearance_consumption_study"]

LOG = logging.getLogger(__name__)


def mesh_signature(sector: fem.Sector) -> str:
    """sha256 of the DOF coordinates, the cell DOF map and the material: identifies the discrete problem."""
    h = hashlib.sha256()
    h.update(np.ascontiguousarray(sector.V.tabulate_dof_coordinates().round(12)).tobytes())
    h.update(np.ascontiguousarray(sector.V.dofmap.list.array).tobytes())
    h.update(repr(sector.material).encode())
    return h.hexdigest()[:24]


def _n_dofs(sector) -> int:
    """The number of DOFs of the sector's mesh (the full vectors' length, clamped DOFs included)."""
    return sector.V.dofmap.index_map.size_local * sector.V.dofmap.index_map_bs


def _boundary_positions(boundary_dofs: np.ndarray, free: np.ndarray, n_full: int) -> np.ndarray:
    """The positions of ``boundary_dofs`` among the free DOFs ``free``; ValueError unless they are indices in
    [0, n_full) of DOFs that are not clamped."""
    position = np.searchsorted(free, boundary_dofs)
    if boundary_dofs.size == 0 or boundary_dofs.min() < 0 or boundary_dofs.max() >= n_full \
            or not np.array_equal(free[np.minimum(position, free.size - 1)], boundary_dofs):
        raise ValueError(f"boundary DOFs must be indices in [0, {n_full}) of DOFs on the mesh that are not clamped")
    return position


def galerkin_operators(Phi: np.ndarray, K_f, M_f, free: np.ndarray):
    """(K~, M~, C~, omega): the reduced stiffness and mass Phi^T K Phi, Phi^T M Phi over the free DOFs
    (symmetrised, refused unless symmetric positive definite), the blade's modal damping on them (``modal_damping``:
    the maps' law) and the reduced model's frequencies (rad/s). The one projection of every blade basis,
    Craig-Bampton's (``build_reduced_model``) or another's (``build_from_basis``)."""
    K, M = Phi[free].T @ (K_f @ Phi[free]), Phi[free].T @ (M_f @ Phi[free])
    K, M = 0.5 * (K + K.T), 0.5 * (M + M.T)
    _check_operators(K, M)
    C, omega = modal_damping(K, M)
    return K, M, C, omega


def exact_quadrature(sector, Phi: np.ndarray) -> tuple[QuadratureForces, np.ndarray]:
    """The exact reduced St. Venant-Kirchhoff force of the basis Phi (n, r) as a quadrature over the sector's mesh
    (``forces.tensors.QuadratureForces``; ``compute_polynomial_forces`` turns it into the exact cubic tensors) and
    the cell of each quadrature point."""
    H, w, cells = fem.quadrature_gradients(sector, Phi.T)
    return QuadratureForces(H, w, *sector.material.lame), cells


def _check_operators(K: np.ndarray, M: np.ndarray) -> None:
    for name, A in (("stiffness", K), ("mass", M)):
        asym = np.abs(A - A.T).max() / np.abs(A).max()
        if asym > 1e-8:
            raise ValueError(f"reduced {name} is not symmetric (relative asymmetry {asym:.1e})")
        try:
            np.linalg.cholesky(0.5 * (A + A.T))
        except np.linalg.LinAlgError:
            raise ValueError(f"reduced {name} is not positive definite: the basis is rank-deficient or the "
                             f"operator indefinite; reduce r_md or check the clamp") from None


def compute_modal_derivatives(sector, ops, basis: CraigBamptonBasis, pairs: np.ndarray, method: str = "exact",
                              fd_step: float = 1e-6, solve=None) -> np.ndarray:
    """Fixed-interface modal derivatives zeta_jk (eqs. 17, 19, 20) for the given (j, k) pairs, M-normalised later.

    exact: K xi = -D^2 f_int(0)[phi_j, phi_k] from the UFL second derivative (no step).
    fd:    K xi = -(K_T(eps phi_k) - K) phi_j / eps, eps = fd_step / max|phi_k| (eq. 19).
    solve: a factorisation of K on the free DOFs (``fem.mumps_solver``), reused between calls; built if None.
    """
    lin = basis.linear
    if len(pairs) == 0:
        return np.zeros((lin.shape[0], 0))
    rhs = np.empty((len(pairs), lin.shape[0]))
    if method == "exact":
        for n, (j, k) in enumerate(pairs):
            rhs[n] = -fem.evaluate_second_derivative(sector, ops, lin[:, j], lin[:, k])
    else:
        K0 = fem.assemble_tangent_scipy(sector, ops, np.zeros(lin.shape[0]))
        for k in np.unique(pairs[:, 1]):
            eps = fd_step / np.abs(lin[:, k]).max()
            dK = (fem.assemble_tangent_scipy(sector, ops, eps * lin[:, k]) - K0) / eps
            for n in np.flatnonzero(pairs[:, 1] == k):
                rhs[n] = -(dK @ lin[:, pairs[n, 0]])
    free = fem.free_dofs(sector)
    if solve is None:
        solve = fem.mumps_solver(fem.assemble_free_operators(sector, ops)[0])
    xi = np.zeros((lin.shape[0], len(pairs)))
    xi[free] = solve(rhs[:, free].T)
    return fixed_interface_correction(xi, basis.Psi, basis.boundary_dofs, basis.interface)


def boundary_node_map(sector, boundary_dofs: np.ndarray):
    """The NodeMap of a Craig-Bampton model whose q starts with ``boundary_dofs``: every node with its three DOFs
    among them, named as the sector's tip nodes where it is one ('LE', ..., 'TE') and 'node<k>' otherwise, its q
    entries the DOFs' positions in ``boundary_dofs`` (whatever their order), its frame the blade's
    (``Sector.blade_frame_angle``: collective)."""
    boundary_dofs = np.asarray(boundary_dofs, dtype=np.int64).ravel()
    bs = 3
    blocks, comps = boundary_dofs // bs, boundary_dofs % bs
    position = {int(d): k for k, d in enumerate(boundary_dofs)}
    complete = [b for b in dict.fromkeys(blocks.tolist()) if set(comps[blocks == b].tolist()) == {0, 1, 2}]
    coords = sector.V.tabulate_dof_coordinates()
    tip_blocks = {int(d) // bs: name for d, name in zip(np.asarray(sector.tip_dofs)[:, 0], sector.tip_names)
                  if d >= 0}
    names = [tip_blocks.get(b, f"node{b}") for b in complete]
    q_index = np.array([[position[b * bs + c] for c in range(bs)] for b in complete], dtype=np.int64).reshape(-1, 3)
    return NodeMap.for_nodes(coords[complete].reshape(-1, 3), q_index, names, sector.blade_frame_angle())


SPIN_SNAPSHOT_PAIR = -(10 ** 6)     # md_pairs' row of a centrifugal snapshot (not a pair of modes: never lifted)


def _spin_snapshots(sector, ops, basis: CraigBamptonBasis, Z: np.ndarray, M_f, free: np.ndarray, speeds,
                    n_modes: int = 0, states: list | None = None) -> tuple[np.ndarray, list]:
    """The full-order centrifugal states at ``speeds`` (``fem.solve_static(spin=...)``, or ``states``: one full DOF
    vector per speed, e.g. a cyclic sector's index-0 states, ``fem.centrifugal_state``) and the first ``n_modes``
    modes of the blade turning at the last (the top) speed (``fem.rotating_modes``: K_T(u_c) - Omega^2 M_P, the tip
    free), each fixed-interface corrected (eq. 20: with the constraint modes they span the mode exactly), each
    M-orthogonalised against the interior columns already
    kept (Theta, Z, earlier ones: the span is the same, the reduced mass better conditioned). Returns ((n, s)
    columns, the remainder of each, |w| / |u| in M-norm after the orthogonalisation); a vector already in the span to
    1e-8 is dropped (its remainder reported)."""
    n_full = basis.Psi.shape[0]
    kept, remainders, out = [basis.Theta, Z], [], []

    def keep(w: np.ndarray) -> None:
        norm0 = np.sqrt(w[free] @ (M_f @ w[free]))
        for _ in range(2):                                 # twice: Gram-Schmidt's round-off
            for A in kept:
                if A.shape[1]:
                    MA = M_f @ A[free]
                    w = w - A @ np.linalg.solve(A[free].T @ MA, MA.T @ w[free])
        remainders.append(float(np.sqrt(w[free] @ (M_f @ w[free])) / norm0))
        if remainders[-1] > 1e-8:
            out.append(w)
            kept.append(w[:, None])

    for k, spin in enumerate(speeds):
        state = fem.solve_static(sector, spin=float(spin), ops=ops, n_steps=2).u.x.array.copy() if states is None \
            else np.asarray(states[k], float)
        keep(fixed_interface_correction(state[:n_full, None], basis.Psi, boundary_dofs=basis.boundary_dofs,
                                        interface=basis.interface)[:, 0])
    if n_modes:                          # the top speed's state, solved above
        _, V = fem.rotating_modes(sector, float(speeds[-1]), n_modes, ops, state=state)
        corrected = fixed_interface_correction(V[:n_full], basis.Psi, boundary_dofs=basis.boundary_dofs,
                                               interface=basis.interface)
        for j in range(n_modes):
            keep(corrected[:, j])
    return (np.column_stack(out) if out else np.zeros((n_full, 0))), remainders


def _sizes(basis: CraigBamptonBasis, pairs: np.ndarray) -> dict:
    """The basis's sizes, its centrifugal snapshots counted apart ('r_spin') from its modal derivatives."""
    sizes = dict(basis.sizes)
    n_spin = int(np.sum(pairs[:, 0] == SPIN_SNAPSHOT_PAIR)) if len(pairs) else 0
    if n_spin:
        sizes.update(r_md=sizes["r_md"] - n_spin, r_spin=n_spin)
    return sizes


def _m_normalise(Z: np.ndarray, M, free: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    norms = np.sqrt(np.einsum("ij,ij->j", Z[free], M @ Z[free]))
    return Z / norms, norms


def training_states(K_lin: np.ndarray, M_lin: np.ndarray, pairs: np.ndarray, md_scale: np.ndarray,
                    boundary_rows: np.ndarray, n_states: int, amplitudes=(1e-3, 3e-3), n_modes: int = 12,
                    seed: int = 7) -> np.ndarray:
    """Smooth reduced states for training and checking hyper-reduction: the first n_modes eigenvectors of the linear
    Craig-Bampton model and random combinations of them (seeded), each scaled so that its largest boundary
    displacement (entries ``boundary_rows`` of the linear coordinates) is one of ``amplitudes`` (m), lifted with the
    modal derivatives (reduction.lift_states).
    A different seed gives held-out states."""
    import scipy.linalg

    _, V = scipy.linalg.eigh(K_lin, M_lin)
    V = normalise_signs(V[:, :n_modes])           # the same states on every machine (eigh's signs are arbitrary)
    rng = np.random.default_rng(seed)
    n_random = max(0, n_states // len(amplitudes) - n_modes)
    base = np.hstack([V, V @ rng.standard_normal((n_modes, n_random))]) if seed == 7 else \
        V @ rng.standard_normal((n_modes, max(1, n_states // len(amplitudes))))
    base = base / np.abs(base[np.asarray(boundary_rows)]).max(axis=0)
    return np.hstack([lift_states(a * base, pairs, md_scale) for a in amplitudes])



def cached_model(metadata: dict, cache_dir: str | Path | None, prefix: str):
    """(path, model): the cache file of a reduced model with this metadata (None without cache_dir) and the model
    read from it when it exists (else None: also when the file is damaged or another model's, to be built again)."""
    key = reduced_model_key(metadata)
    cache = Path(cache_dir) / f"{prefix}_{key}.npz" if cache_dir else None
    if cache is not None and cache.is_file():
        LOG.info("loading cached reduced model %s", cache)
        try:
            return cache, load_reduced_model(cache, expected_key=key)
        except ValueError as exc:
            LOG.warning("ignoring the cached model (%s): built again", exc)
    return cache, None


def begin_build(sector, ops, metadata: dict, cache_dir: str | Path | None, prefix: str):
    """The start of a build: (cache path, the cached model or None, the report, its ``Laps``, the free operators
    (K_f, M_f, free) or None when the model is cached). ValueError for operators of another law than SVK: a reduced
    model's forces are SVK's exact cubic ones (tensors, or a cubature of them); the other laws are the full order's."""
    if getattr(ops, "law", "svk") != "svk":
        raise ValueError(f"ops: a reduced model holds St. Venant-Kirchhoff's cubic forces; operators of the law "
                         f"{ops.law!r} are for the full order (fem.solve_static, fem.solve_repeating_newmark)")
    cache, cached = cached_model(metadata, cache_dir, prefix)
    if cached is not None:
        return cache, cached, {"cached": True}, None, None
    report: dict = {"cached": False}
    return cache, None, report, Laps(report), fem.assemble_free_operators(sector, ops)


class Laps:
    """Wall time between calls, stored under report['timings'][name]."""

    def __init__(self, report: dict):
        self.report = report
        report.setdefault("timings", {})
        self.clock = time.perf_counter()

    def __call__(self, name: str) -> None:
        now = time.perf_counter()
        self.report["timings"][name] = now - self.clock
        self.clock = now


def build_reduced_model(sector, config: ReductionConfig = ReductionConfig(), boundary_dofs: np.ndarray | None = None,
                        ops=None, cache_dir: str | Path | None = None) -> tuple[ReducedModel, dict]:
    """Craig-Bampton + modal derivatives + reduced forces. Returns (model, report with timings and weights)."""
    ops = ops or fem.create_svk_operators(sector)
    if config.contact_patch and boundary_dofs is not None \
            and not np.array_equal(np.asarray(boundary_dofs).ravel(), sector.tip_dofs.ravel()):
        raise ValueError("contact_patch: the patches replace the tip nodes' DOFs; other boundary DOFs are not "
                         "supported with it (boundary_dofs must be None)")
    boundary_dofs = sector.tip_dofs.ravel() if boundary_dofs is None else np.asarray(boundary_dofs).ravel()
    meta_config = dataclasses.asdict(config)
    if not config.contact_patch:          # absent from the point-contact models' keys: their caches stay valid
        del meta_config["contact_patch"]
    if not config.spin_snapshots:         # likewise for the models at rest
        del meta_config["spin_snapshots"], meta_config["spin_modes"]
    metadata = {"config": meta_config, "boundary_dofs": boundary_dofs.tolist(),
                "mesh": mesh_signature(sector), "source": sector.source, "version": __version__,
                "blade_frame": "centre of mass"}        # NodeMap.frame_angle: models without it are rebuilt
    cache, cached, report, lap, operators = begin_build(sector, ops, metadata, cache_dir, "rom")
    if cached is not None:
        return cached, report
    K_f, M_f, free = operators
    n_full = _n_dofs(sector)
    position = _boundary_positions(boundary_dofs, free, n_full)
    interface = None
    if config.contact_patch:
        interface = fem.tip_patch_interface(sector, config.contact_patch)
        if abs(interface).sum(axis=0).A.ravel()[np.setdiff1d(np.arange(n_full), free)].max(initial=0.0) > 0:
            raise ValueError("contact_patch: a patch reaches the clamp; take a smaller radius")
    Psi_f, Theta_f, omega_c = craig_bampton(K_f, M_f, position if interface is None else interface[:, free],
                                            config.r_c, solve=fem.mumps_solver, eigensolve=fem.slepc_eigenpairs)
    Psi, Theta = np.zeros((n_full, Psi_f.shape[1])), np.zeros((n_full, Theta_f.shape[1]))
    Psi[free], Theta[free] = Psi_f, Theta_f
    basis = CraigBamptonBasis(Psi=Psi, Theta=Theta, omega_c=omega_c, boundary_dofs=boundary_dofs,
                              interface=interface)
    nodes = boundary_node_map(sector, boundary_dofs)
    if "LE" not in nodes.names:
        raise ValueError("the boundary DOFs must hold the three DOFs of node LE (the training force acts there)")
    lin = basis.linear
    n_lin = lin.shape[1]
    max_md = n_lin * (n_lin + 1) // 2
    if config.r_md > max_md:
        raise ValueError(f"r_md must be in [0, {max_md}] for r_b + r_c = {n_lin}, got {config.r_md}")
    lap("craig_bampton")
    # linear training response in the Craig-Bampton space (harmonic force at node LE along e_z, one period)
    K_lin, M_lin = lin[free].T @ (K_f @ lin[free]), lin[free].T @ (M_f @ lin[free])
    C_lin, _ = modal_damping(K_lin, M_lin)
    le_z = nodes.q_index[nodes.row("LE"), 2]
    # the force on node LE's z coordinate: a point force, or with patches the traction of that resultant
    f_shape = config.training_force * (lin[boundary_dofs[le_z]] if interface is None
                                         else np.asarray(interface[le_z] @ lin).ravel())
    period = 2 * np.pi / config.training_omega
    t, q_train = simulate_linear_newmark(M_lin, C_lin, K_lin,
                                         lambda tt: f_shape * np.sin(config.training_omega * tt), period / 400, 400)
    lin_forces = None
    if config.criterion == "SMVW":
        H, w, _ = fem.quadrature_gradients(sector, lin.T)
        lin_forces = QuadratureForces(H, w, *sector.material.lame)
    W = selection_weights(config.criterion, q_train, t, lin, lin_forces)
    pairs = select_pairs(W, config.r_md)
    report["weights"], report["pairs"] = W, pairs
    lap("selection")
    solve_free = fem.mumps_solver(K_f)
    Z = compute_modal_derivatives(sector, ops, basis, pairs, config.md_method, config.fd_step, solve_free)
    if config.global_md_modes:
        n_g = config.global_md_modes
        normal = np.column_stack([m.x.array for m in fem.compute_clamped_modes(sector, n_g, ops).modes])
        gpairs = np.column_stack(np.triu_indices(n_g))
        global_basis = dataclasses.replace(basis, Psi=np.zeros((normal.shape[0], 0)), Theta=normal,
                                           boundary_dofs=np.zeros(0, dtype=np.int64), interface=None)
        xi = compute_modal_derivatives(sector, ops, global_basis, gpairs, config.md_method, config.fd_step,
                                       solve_free)
        # the derivatives are of the free blade; remove their boundary part with the constraint modes (eq. 20)
        Z = np.hstack([Z, fixed_interface_correction(xi, basis.Psi, boundary_dofs, basis.interface)])
        pairs = np.vstack([pairs, -1 - gpairs])  # negative: pairs of clamped normal modes
    if config.spin_snapshots:
        snapshots, report["spin_snapshot_remainder"] = _spin_snapshots(sector, ops, basis, Z, M_f, free,
                                                                       config.spin_snapshots, config.spin_modes)
        Z = np.hstack([Z, snapshots])
        pairs = np.vstack([pairs, np.full((snapshots.shape[1], 2), SPIN_SNAPSHOT_PAIR)]).astype(pairs.dtype)
    Z, md_scale = _m_normalise(Z, M_f, free) if Z.shape[1] else (Z, np.zeros(0))
    basis = dataclasses.replace(basis, Z=Z, md_pairs=pairs)
    lap("modal_derivatives")
    Phi = basis.Phi
    K, M, C, omega = galerkin_operators(Phi, K_f, M_f, free)
    report["omega"] = omega
    report["q_train"], report["md_scale"], report["linear_operators"] = q_train, md_scale, (K_lin, M_lin)
    lap("projection")
    forces = None
    if config.forces != "none":
        exact, cells = exact_quadrature(sector, Phi)
        lap("quadrature_data")
        if config.forces == "intrusive":
            forces = compute_polynomial_forces(exact)
        elif config.forces == "quadrature":
            forces = exact
        elif config.forces == "step":
            scales = config.step_amplitude / np.abs(Phi).max(axis=0)
            forces = identify_step(lambda Q: Phi.T @ fem.evaluate_forces(sector, ops, (Phi @ Q).T).T, scales)
        elif config.forces == "ecsw":
            Q_train = training_states(K_lin, M_lin, pairs, md_scale, nodes.boundary_rows, config.ecsw_states)
            result = train_ecsw(exact, cells, Q_train, tol=config.ecsw_tol)
            report["ecsw_exact"] = exact
            forces = result.forces
            report["ecsw_cells"], report["ecsw_training_error"] = result.cells.size, result.training_error
        lap("forces")
    rotation = None
    if config.spin_snapshots:
        M_P, F_c, G = fem.reduced_rotation_terms(sector, Phi, ops)
        rotation = RotationTerms(M_P=M_P, F_c=F_c, G=G, speeds=np.array(config.spin_snapshots))
        lap("rotation_terms")
    model = ReducedModel(M=M, C=C, K=K, forces=forces, boundary_dofs=boundary_dofs,
                         nodes=nodes, sizes=_sizes(basis, pairs), md_pairs=pairs,
                         Phi=Phi if config.keep_basis else None, metadata=metadata, rotation=rotation)
    if cache is not None:
        save_reduced_model(model, cache)
    return model, report


BASIS_FORCES = ("intrusive", "quadrature", "none")


def _given_basis(sector, basis, boundary_dofs, forces: str) -> tuple[np.ndarray, np.ndarray]:
    """``build_from_basis``'s basis (n_full, r) as floats and its boundary DOFs, checked before any FE work: a
    one-line ValueError naming the argument otherwise."""
    if forces not in BASIS_FORCES:
        raise ValueError(f"forces must be one of {BASIS_FORCES}, got {forces!r}")
    n_full = _n_dofs(sector)
    try:
        basis = np.asarray(basis, float)
    except (TypeError, ValueError):
        raise ValueError(f"basis must be a real (n_dofs = {n_full}, r) array, got {type(basis).__name__}") from None
    if basis.ndim != 2 or basis.shape[0] != n_full or not np.isfinite(basis).all():
        raise ValueError(f"basis must be a finite (n_dofs = {n_full}, r) array over the sector's DOFs, got shape "
                         f"{basis.shape}{'' if np.isfinite(basis).all() else ' with NaN or inf entries'}")
    boundary_dofs = sector.tip_dofs.ravel() if boundary_dofs is None else np.asarray(boundary_dofs).ravel()
    if not np.issubdtype(boundary_dofs.dtype, np.integer):
        raise ValueError(f"boundary_dofs must be integer DOF indices, got {boundary_dofs.dtype}")
    if basis.shape[1] < boundary_dofs.size:
        raise ValueError(f"basis has r = {basis.shape[1]} columns, fewer than the {boundary_dofs.size} boundary DOFs "
                         f"its coordinates must hold")
    return basis, boundary_dofs.astype(np.int64)


def _boundary_basis(basis: np.ndarray, boundary_dofs: np.ndarray, K_f, M_f, free: np.ndarray):
    """(Phi, T): the basis in the coordinates the explicit contact scheme reads, Phi = basis T with
    Phi[boundary_dofs] = [I 0] (``reduction.pod.boundary_coordinates``: the same span), exactly zero on the clamp;
    ValueError where the basis does not vanish on the clamp or cannot hold the boundary DOFs."""
    clamped = np.setdiff1d(np.arange(basis.shape[0]), free)
    scale = np.abs(basis).max()
    if scale == 0 or np.abs(basis[clamped]).max(initial=0.0) > 1e-12 * scale:
        raise ValueError("basis must be nonzero and vanish on the clamped DOFs (the clamp applied: zero rows outside "
                         "fem.free_dofs)")
    V = basis[free]
    K_r, M_r = V.T @ (K_f @ V), V.T @ (M_f @ V)
    try:
        T = boundary_coordinates(basis[boundary_dofs], 0.5 * (K_r + K_r.T), 0.5 * (M_r + M_r.T))
    except ValueError as exc:
        raise ValueError(f"basis cannot hold the boundary_dofs as coordinates ({exc})") from None
    Phi = basis @ T
    Phi[clamped] = 0.0
    Phi[boundary_dofs] = np.eye(boundary_dofs.size, Phi.shape[1])      # what it is to round-off
    return Phi, T


def build_from_basis(sector, basis, boundary_dofs: np.ndarray | None = None, ops=None, forces: str = "intrusive",
                     label: str = "", cache_dir: str | Path | None = None) -> tuple[ReducedModel, dict]:
    """A reduced model of the blade on any basis (e.g. POD modes of full-order snapshots, ``reduction.pod``), run by
    the explicit contact scheme like a Craig-Bampton model: the Galerkin projection of the same operators, the same
    damping law and the same exact forces as ``build_reduced_model`` (``galerkin_operators``, ``exact_quadrature``).

    The basis's coordinates are changed within its span so that the first r_b are the boundary DOFs' displacements
    (``reduction.pod.boundary_coordinates``: the span's constraint modes, then its fixed-interface modes), as
    ``model.nodes.NodeMap`` and the contact scheme require; the span, hence the Galerkin model, is the basis's.

    Args:
        basis: (n_dofs, r) fields over the sector's DOFs (the builders' numbering: ``fem.free_dofs`` rows, zero on
            the clamp), spanning the space wanted, r >= r_b; the boundary DOFs must move independently in the span.
            POD of full-order states U (n_dofs, n_snap): ``K_f, M_f, free = fem.assemble_free_operators(sector)``,
            ``basis = np.zeros((n_dofs, r)); basis[free] = pod_basis(U[free], M_f, r).basis``.
        boundary_dofs: the contact nodes' DOFs (point contact), default the tip nodes' (``Sector.tip_dofs``).
        forces: 'intrusive' (exact cubic tensors), 'quadrature' (exact, tensor-free) or 'none' (linear).
        label: recorded in the metadata (where the basis comes from); cache_dir: as ``build_reduced_model``'s.
    Returns (model, report): report holds 'omega' (rad/s), 'transform' T (r, r: model.Phi = basis T) and timings
    ({'cached': True} alone for a model read from ``cache_dir``).
    """
    basis, boundary_dofs = _given_basis(sector, basis, boundary_dofs, forces)
    ops = ops or fem.create_svk_operators(sector)
    metadata = {"basis": hashlib.sha256(np.ascontiguousarray(basis).tobytes()).hexdigest()[:24], "label": str(label),
                "forces": forces, "boundary_dofs": boundary_dofs.tolist(), "mesh": mesh_signature(sector),
                "source": sector.source, "version": __version__, "blade_frame": "centre of mass"}
    cache, cached, report, lap, operators = begin_build(sector, ops, metadata, cache_dir, "basis_rom")
    if cached is not None:
        return cached, report
    K_f, M_f, free = operators
    _boundary_positions(boundary_dofs, free, basis.shape[0])
    Phi, report["transform"] = _boundary_basis(basis, boundary_dofs, K_f, M_f, free)
    K, M, C, report["omega"] = galerkin_operators(Phi, K_f, M_f, free)
    lap("projection")
    force = None
    if forces != "none":
        exact, _ = exact_quadrature(sector, Phi)
        force = compute_polynomial_forces(exact) if forces == "intrusive" else exact
        lap("forces")
    r_b = boundary_dofs.size
    model = ReducedModel(M=M, C=C, K=K, forces=force, boundary_dofs=boundary_dofs,
                         nodes=boundary_node_map(sector, boundary_dofs),
                         sizes={"r_b": r_b, "r_c": Phi.shape[1] - r_b, "r_md": 0},
                         md_pairs=np.zeros((0, 2), dtype=np.int64), Phi=Phi, metadata=metadata)
    if cache is not None:
        save_reduced_model(model, cache)
    return model, report


def release_freed_memory() -> None:
    """Return the heap's freed pages to the system (glibc ``malloc_trim``; nothing elsewhere). A disk cubature's
    training matrix is built from ~30 MB blocks, under glibc's mmap threshold once it has grown, so freeing it leaves
    the pages with the process: 11.5 GB stayed resident after training a cubature on the disk map's training states,
    1.2 GB with the trim (docs/performance.md)."""
    import ctypes
    import ctypes.util

    name = ctypes.util.find_library("c")
    try:
        ctypes.CDLL(name).malloc_trim(0)
    except (OSError, AttributeError, TypeError):      # not glibc
        pass


def hyper_reduce(sector, model: ReducedModel, Q_train: np.ndarray, tol: float = 1e-3, level: str = "point",
                 label: str = "", max_columns: int = 256) -> tuple[ReducedModel, dict]:
    """The model with its nonlinear forces replaced by a hyper-reduced quadrature trained on the states Q_train
    (r, n): cells (ECSW) or single points (empirical cubature), see ``forces.cubature.train_ecsw``. Train on the states
    the model will visit (e.g. those of contact runs): smooth lifted modes miss the local tip deformations of contact.

    A disk model (``model.sectors``, forces ``forces.sector.SectorForces``): the sector's force is hyper-reduced,
    trained on the sectors' coordinates of the states as columns (``SectorForces.sector_states``; at most
    ``max_columns`` of them, ``forces.cubature.spread_columns``), on the sector's fields
    (``model.disk_basis.sector_force_basis``, the faces included when the model's force has them); every sector then
    evaluates the same points. ``sector`` is the disk sector.

    Returns (model, report): report has the exact quadrature forces ('exact'), the EcswResult ('result'), the
    training columns ('columns_trained') and the training time (s). The model's metadata records the
    hyper-reduction (level, tol, points, a hash of Q_train and ``label``), so sweeps cached under its key are not
    mixed up with the exact model's.
    """
    disk = model.sectors is not None
    if disk and model.forces is None:
        raise ValueError("hyper_reduce: this disk model has no nonlinear forces (built with forces='none')")
    if not disk and model.Phi is None:
        raise ValueError("hyper_reduce needs the model's basis: build it with keep_basis=True")
    if model.metadata.get("mesh") not in (None, mesh_signature(sector)):
        raise ValueError("hyper_reduce: the sector is not the mesh the model was built on (mesh signatures differ)")
    Q_train = np.asarray(Q_train, float)
    if Q_train.ndim != 2 or Q_train.shape[0] != model.r or not np.all(np.isfinite(Q_train)):
        raise ValueError(f"Q_train must be finite with shape (r = {model.r}, n), got {Q_train.shape}")
    if not Q_train.any():
        raise ValueError("Q_train: every training state is zero (a run that never left rest, e.g. too short to "
                         "reach the casing); the cubature would have no points")
    t0 = time.perf_counter()
    if disk:
        from rotor37_rom.model.disk_basis import sector_force_basis
        from rotor37_rom.forces.cubature import spread_columns

        fields = sector_force_basis(model.sectors, model.forces.faces)
        X = model.forces.sector_states(Q_train)
        X = X[:, spread_columns(X, max_columns)]
    else:
        fields, X = model.Phi, Q_train
    H, w, cells = fem.quadrature_gradients(sector, fields.T)
    exact = QuadratureForces(H, w, *sector.material.lame)
    result = train_ecsw(exact, cells, X, tol=tol, level=level)
    release_freed_memory()            # the training matrix (GBs for a disk) was freed: give it back to the system
    info = {"level": level, "tol": tol, "columns": int(result.cells.size), "points": result.n_points,
            "training": hashlib.sha256(np.ascontiguousarray(Q_train).tobytes()).hexdigest()[:16], "label": label}
    forces = dataclasses.replace(model.forces, forces=result.forces) if disk else result.forces
    reduced = dataclasses.replace(model, forces=forces, metadata={**model.metadata, "hyper_reduction": info})
    return reduced, {"exact": exact, "result": result, "columns_trained": X, "seconds": time.perf_counter() - t0,
                     **info}


def clearance_consumption_study(sector, mode: str = "1B", zeta: float = 1e-3, n_levels: int = 10,
                                roms: dict | None = None, ops=None, direction: str = "x"):
    """Full-order linear/nonlinear and reduced clearance consumption at node LE along a clamped mode (§2.3.2).

    Args:
        mode: '1B' or '1T' (identified from the tip motion); zeta: LE displacement of the scaled mode (m) along
            ``direction``: 'x' (e_x, the paper's "radial" direction for this blade, §2.3) or 'radial' (true radial;
            1B and 1T move the tip LE mostly tangentially, so this gives much larger amplitudes).
        n_levels: load levels on each side of 0 (delta = +-k/n_levels).
        roms: {name: ReducedModel} to compare (node LE located through each model's node map).
    Returns:
        ClearanceCurves with 'FOM linear', 'FOM nonlinear' and one curve per ROM (nonlinear), and their costs.
    """
    import time

    from rotor37_rom.post.clearance import ClearanceCurves, clearance_change
    from rotor37_rom.model.modes import classify_blade_modes
    from rotor37_rom.model.reduced import solve_reduced_static

    if mode not in ("1B", "1T"):
        raise ValueError(f"mode must be '1B' or '1T', got {mode!r}")
    if not (0 < zeta < 0.02):
        raise ValueError(f"zeta must be in (0, 0.02) m, got {zeta}")
    ops = ops or fem.create_svk_operators(sector)
    modal = fem.compute_clamped_modes(sector, 6, ops)
    labels = classify_blade_modes(modal.tip_displacements, sector.tip_nodes)
    phi = modal.modes[labels.index(mode)].x.array.copy()
    i_le, i_te = sector.tip_names.index("LE"), sector.tip_names.index("TE")
    le, le_dofs = sector.tip_nodes[i_le], sector.tip_dofs[i_le]
    if direction not in ("x", "radial"):
        raise ValueError(f"direction must be 'x' or 'radial', got {direction!r}")
    e_n = np.array([1.0, 0.0, 0.0]) if direction == "x" else np.array([le[0], le[1], 0.0]) / np.hypot(*le[:2])
    phi *= zeta / (phi[le_dofs] @ e_n)
    K = fem.assemble_stiffness(sector, ops)
    x, f = K.createVecs()
    x.array[:] = phi
    K.mult(x, f)
    te = sector.tip_nodes[i_te]
    slope = (np.hypot(*te[:2]) - np.hypot(*le[:2])) / (te[2] - le[2])
    deltas = np.concatenate([-np.arange(n_levels, 0, -1), [0], np.arange(1, n_levels + 1)]) / n_levels
    curves, costs = {}, {}
    curves["FOM linear"] = clearance_change(le, deltas[:, None] * phi[le_dofs][None, :], slope)
    t0 = time.perf_counter()
    tips = {}
    for sign in (1.0, -1.0):
        f_signed = f.copy()
        f_signed.scale(sign)
        res = fem.solve_static(sector, force=f_signed, n_steps=n_levels, ops=ops)
        tips[sign] = res.tip_displacements[:, i_le, :]
    u_le = np.vstack([tips[-1.0][::-1], np.zeros((1, 3)), tips[1.0]])
    curves["FOM nonlinear"] = clearance_change(le, u_le, slope)
    costs["FOM nonlinear"] = time.perf_counter() - t0
    f_full = f.array.copy()
    for name, model in (roms or {}).items():
        t0 = time.perf_counter()
        f_red = model.Phi.T @ f_full
        try:
            q_pos = solve_reduced_static(model, f_red, deltas[deltas > 0])
            q_neg = solve_reduced_static(model, f_red, -deltas[deltas > 0])
        except RuntimeError as exc:    # a poor basis can lose equilibrium (a spurious limit point): show it, go on
            LOG.warning("%s: %s; its clearance curve is left out (NaN)", name, exc)
            curves[name] = np.full(len(deltas), np.nan)
            costs[name] = time.perf_counter() - t0
            continue
        q = np.vstack([q_neg[::-1], np.zeros((1, model.r)), q_pos])
        curves[name] = clearance_change(le, q[:, model.nodes.q_index[model.nodes.row("LE")]], slope)
        costs[name] = time.perf_counter() - t0
    return ClearanceCurves(mode=mode, zeta=zeta, deltas=deltas, curves=curves, costs=costs)
