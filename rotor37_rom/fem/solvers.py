"""Full-order solvers on a sector: SLEPc eigenproblems (shift-invert, MUMPS), Newton statics with the exact tangent,
and the factorisation and eigen-solver that the pure Craig-Bampton function (``reduction.craig_bampton``) and the
implicit Newmark of ``fem.periodic`` are given for SciPy matrices.

Part of the dolfinx adapter (``rotor37_rom.fem``). Everything but the SciPy-matrix helpers runs under MPI.
"""
from __future__ import annotations

import dataclasses
import logging
from typing import Callable, Sequence

import numpy as np
import ufl
from dolfinx import fem
from dolfinx.fem import petsc as fem_petsc
from mpi4py import MPI
from petsc4py import PETSc

from rotor37_rom import forms

from .operators import (JIT_PARAMS, SvkOperators, _require_serial, assemble_coriolis, assemble_mass,
                        assemble_spin_softening, assemble_stiffness, assemble_tangent, assemble_vector,
                        create_svk_operators, gather_dof_values, scipy_to_petsc)
from .sector import Sector

__all__ = ["ModalResult", "StaticResult", "solve_eigenproblem", "compute_clamped_modes",
           "solve_static", "solve_clamped_static", "mumps_solver", "slepc_eigenpairs",
           "shift_invert_solver", "static_compliance", "rotating_modes", "reduced_coriolis",
           "reduced_rotation_terms"]

LOG = logging.getLogger(__name__)


def _lu_solver(comm, A: PETSc.Mat, prefix: str) -> PETSc.KSP:
    ksp = PETSc.KSP().create(comm)
    ksp.setOptionsPrefix(prefix)
    ksp.setOperators(A)
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    ksp.getPC().setFactorSolverType("mumps")
    ksp.setFromOptions()
    return ksp


@dataclasses.dataclass(frozen=True)
class ModalResult:
    """Clamped modes: omega (rad/s), mass-normalised mode Functions, tip displacements (n_modes, n_tip, 3)."""

    omega: np.ndarray
    modes: list
    tip_displacements: np.ndarray


def shift_invert_solver(comm, sigma: float = 0.0, tol: float = 1e-12, prefix: str = "modes_"):
    """A SLEPc Krylov-Schur eigen-solver for the eigenvalues of K x = lambda M x nearest ``sigma`` (shift-invert,
    MUMPS LU), the one ``solve_eigenproblem`` uses. Kept by a caller for a sequence of problems whose K keeps its
    object and nonzero pattern while its values change (the harmonic indices of a cyclic sector), SLEPc keeps its
    factorisation object and MUMPS refactors numerically, without a new analysis. M is never singular here
    (clamped and eliminated DOFs carry a mass on the diagonal), so eigenvector purification (one more solve per
    vector, for a singular M) is off."""
    from slepc4py import SLEPc

    eps = SLEPc.EPS().create(comm)
    eps.setOptionsPrefix(prefix)
    eps.setProblemType(SLEPc.EPS.ProblemType.GHEP)
    eps.setType(SLEPc.EPS.Type.KRYLOVSCHUR)
    eps.setTolerances(tol, 500)
    eps.setWhichEigenpairs(SLEPc.EPS.Which.TARGET_MAGNITUDE)
    eps.setTarget(sigma)
    eps.setPurify(False)
    st = eps.getST()
    st.setType(SLEPc.ST.Type.SINVERT)
    st.setShift(sigma)
    ksp = st.getKSP()
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    ksp.getPC().setFactorSolverType("mumps")
    return eps


def solve_eigenproblem(K: PETSc.Mat, M: PETSc.Mat, n_modes: int, sigma: float = 0.0, tol: float = 1e-12,
                       prefix: str = "modes_", initial: Sequence[PETSc.Vec] | None = None,
                       eps=None) -> tuple[np.ndarray, list]:
    """Lowest ``n_modes`` eigenpairs of K x = lambda M x by SLEPc Krylov-Schur with shift-invert (MUMPS LU).

    ``eps``: a ``shift_invert_solver`` kept by the caller (then ``sigma``, ``tol`` and ``prefix`` are its own);
    None: one made for this call.

    Returns:
        (omega, vectors): omega = sqrt(lambda) in rad/s ascending, vectors M-normalised (x^T M x = 1).
    """
    n_global = K.getSize()[0]
    if not (1 <= n_modes < n_global):
        raise ValueError(f"n_modes must be in [1, {n_global - 1}], got {n_modes}")
    own = eps is None
    if own:
        eps = shift_invert_solver(K.getComm(), sigma, tol, prefix)
    eps.setOperators(K, M)
    eps.setDimensions(n_modes, max(2 * n_modes, n_modes + 15))
    eps.setFromOptions()
    if initial:                       # e.g. the modes of a neighbouring problem: fewer Krylov-Schur restarts
        eps.setInitialSpace(list(initial))
    eps.solve()
    n_conv = eps.getConverged()
    if n_conv < n_modes:
        raise RuntimeError(f"SLEPc converged {n_conv} of {n_modes} eigenpairs")
    lams = np.array([eps.getEigenvalue(i).real for i in range(n_conv)])
    order = np.argsort(lams)[:n_modes]
    lam = lams[order]
    if np.any(lam <= 0):
        raise ValueError("K is not positive definite on the free DOFs (non-positive eigenvalue): check the clamp")
    vecs = []
    for i in order:
        x = K.createVecRight()
        eps.getEigenvector(int(i), x)
        vecs.append(x)
    comm = K.getComm().tompi4py()
    for x in vecs:  # M-normalise (SLEPc already does for GHEP; make it explicit), then fix the sign
        Mx = M.createVecLeft()
        M.mult(x, Mx)
        x.scale(1.0 / np.sqrt(x.dot(Mx)))
        # the sign SLEPc returns depends on the BLAS and the rank count: make the largest entry positive
        # (modes.normalise_signs, over all ranks)
        local = x.getArray(readonly=True)
        k = int(np.argmax(np.abs(local))) if local.size else -1
        candidates = comm.allgather((abs(local[k]), local[k]) if k >= 0 else (-1.0, 0.0))
        if max(candidates)[1] < 0:
            x.scale(-1.0)
    if own:
        eps.destroy()
    return np.sqrt(lam), vecs


def static_compliance(sector: Sector, dofs, K: PETSc.Mat | None = None, ops: SvkOperators | None = None
                      ) -> np.ndarray:
    """G = E^T K^-1 E (m/N): the static displacement of each DOF of ``dofs`` under a unit force on each, clamped
    (``solve_clamped_static`` with one unit load per DOF; serial).

    ``dofs``: DOF indices (``sector.tip_dofs``, any shape; G follows its flattened order). ``K``: the clamped
    stiffness (assembled if None), or any operator in the sector's layout (a cyclic K_k of k = 0 or N/2). Symmetric.
    Craig-Bampton keeps these DOFs with exact static constraint modes, so a reduced model's compliance at them is
    this one."""
    dofs = np.asarray(dofs).ravel()
    loads = np.zeros((dofs.size, sector.n_dofs))
    loads[np.arange(dofs.size), dofs] = 1.0
    G = solve_clamped_static(sector, loads, ops, K=K)[:, dofs]
    return 0.5 * (G + G.T)


def compute_clamped_modes(sector: Sector, n_modes: int = 6, ops: SvkOperators | None = None) -> ModalResult:
    """First ``n_modes`` clamped modes with tip-node displacements gathered on every rank."""
    ops = ops or create_svk_operators(sector)
    K, M = assemble_stiffness(sector, ops), assemble_mass(sector, ops)
    omega, vecs = solve_eigenproblem(K, M, n_modes)
    modes, tips = [], []
    for i, x in enumerate(vecs):
        f = fem.Function(sector.V, name=f"mode_{i + 1}")
        f.vector.array[:] = x.array
        f.x.scatter_forward()
        modes.append(f)
        tips.append(gather_dof_values(sector, f.x.array, sector.tip_dofs))
    K.destroy()
    M.destroy()
    return ModalResult(omega=omega, modes=modes, tip_displacements=np.array(tips))


@dataclasses.dataclass(frozen=True)
class StaticResult:
    """Load factors, tip displacements (n_steps, n_tip, 3) and Newton iterations per step; u: final Function;
    residuals: per load step, (iterations + 1, 2) of (|r|, ref) at each Newton iterate (convergence checks)."""

    load_factors: np.ndarray
    tip_displacements: np.ndarray
    iterations: np.ndarray
    u: object
    residuals: list = dataclasses.field(default_factory=list)


class _StaticProblem:
    """The pieces of ``solve_static``'s Newton iteration: the external load (a vector, the centrifugal force at the
    deformed position), the prescribed DOFs, the residual with its reference norm, and the tangent."""

    def __init__(self, sector: Sector, ops: SvkOperators, force, prescribed, spin: float):
        V = sector.V
        self.sector, self.ops, self.spin, self.bcs = sector, ops, spin, [sector.clamp_bc]
        self.f_ext = None
        if isinstance(force, PETSc.Vec):
            self.f_ext = force
        elif force is not None:
            self.f_ext = assemble_vector(fem.form(force(ufl.TestFunction(V)), jit_params=JIT_PARAMS))
        dofs = np.concatenate([np.asarray(d, dtype=np.int64).ravel() for d, _ in prescribed]) if prescribed else \
            np.zeros(0, np.int64)
        values = np.concatenate([np.asarray(v, float).ravel() for _, v in prescribed]) if prescribed else np.zeros(0)
        if dofs.shape != values.shape:
            raise ValueError(f"prescribed: {dofs.size} DOFs but {values.size} values")
        owned = dofs >= 0  # per-rank local indices, -1 where the DOF lives on another rank
        self.dofs, self.values = dofs[owned], values[owned]
        bs = V.dofmap.index_map_bs
        if np.any(self.dofs >= V.dofmap.index_map.size_local * bs):
            raise ValueError("prescribed: DOF indices must be owned local (unblocked) indices, as in Sector.tip_dofs")
        self.global_rows = (V.dofmap.index_map.local_range[0] * bs + self.dofs).astype(PETSc.IntType)
        if spin:
            spin_c = fem.Constant(sector.mesh, PETSc.ScalarType(spin))
            self.centrifugal = fem.form(forms.centrifugal_force(ops.u, ufl.TestFunction(V), ops.constants["rho"],
                                                                spin_c), jit_params=JIT_PARAMS)
            self.M_P = assemble_spin_softening(sector, ops)

    def residual(self, lam: float, r: PETSc.Vec) -> tuple[PETSc.Vec, float, float]:
        """(r - lam f on the free rows, |r|, the reference max(|lam f|, |reaction|)); ``r`` holds f_int(u) or K u."""
        reaction, load_norm = r.norm(), 0.0
        if self.f_ext is not None:
            r.axpy(-lam, self.f_ext)
            load_norm = abs(lam) * self.f_ext.norm()
        if self.spin:
            f_spin = assemble_vector(self.centrifugal)
            r.axpy(-lam, f_spin)
            load_norm = max(load_norm, abs(lam) * f_spin.norm())
            f_spin.destroy()
        fem_petsc.set_bc(r, self.bcs, scale=0.0)
        r.array[self.dofs] = 0.0
        return r, r.norm(), max(load_norm, reaction, 1e-300)

    def tangent(self, lam: float) -> PETSc.Mat:
        A = fem_petsc.assemble_matrix(self.ops.tangent, bcs=self.bcs, diagonal=1.0)
        A.assemble()
        if self.spin:
            A.axpy(-lam * self.spin**2, self.M_P, structure=PETSc.Mat.Structure.SAME_NONZERO_PATTERN)
        return A

    def correction(self, A: PETSc.Mat, r: PETSc.Vec, lift: PETSc.Vec, rhs: PETSc.Vec) -> PETSc.Vec:
        """rhs = -r - A lift on the free rows, = lift on the prescribed rows (a lifted predictor: no spike)."""
        A.mult(lift, rhs)
        rhs.axpy(1.0, r)
        rhs.scale(-1.0)
        fem_petsc.set_bc(rhs, self.bcs, scale=0.0)
        rhs.array[self.dofs] = lift.array[self.dofs]
        return rhs


def solve_static(sector: Sector, force: Callable[[object], object] | PETSc.Vec | None = None,
                 prescribed: Sequence[tuple[np.ndarray, np.ndarray]] = (), n_steps: int = 10,
                 rtol: float = 1e-10, max_iterations: int = 25, ops: SvkOperators | None = None,
                 linear: bool = False, spin: float = 0.0) -> StaticResult:
    """Nonlinear static equilibrium f_int(u) = lambda f_ext by Newton with the exact tangent and load stepping, each
    step started from the secant predictor (u_k plus the previous step's increment).

    Args:
        sector: the structure (clamp applied).
        force: external load for lambda = 1: a PETSc vector (N) or a function v -> UFL 1-form (e.g. a traction).
        prescribed: displacement control: (local DOF indices, values at lambda = 1) pairs, imposed as lambda*values.
        n_steps: equal load increments (1..10000).
        rtol: Newton stops when ||r|| <= rtol * max(||lambda f_ext||, ||reaction||) (relative residual), or at its
            round-off floor (below 1e-7 of that and no longer halving: ``_at_round_off``).
        linear: solve K u = lambda f (one factorisation) instead.
        spin: the structure turns at this speed (rad/s) about the machine axis e_z: the centrifugal force
            rho spin^2 P (X + u) (``forms.centrifugal_force``, following the deformed position) joins the load, scaled
            by lambda with it (load steps in spin^2), and -lambda spin^2 M_P joins the exact tangent. Nonlinear only.
    """
    if not (1 <= n_steps <= 10000):
        raise ValueError(f"n_steps must be in [1, 10000], got {n_steps}")
    if not (np.isfinite(spin) and spin >= 0.0):
        raise ValueError(f"spin must be a finite speed >= 0 rad/s, got {spin}")
    if linear and spin:
        raise ValueError("spin needs the nonlinear solve (linear=False): the spin softening follows the load factor")
    ops = ops or create_svk_operators(sector)
    u = ops.u
    u.x.array[:] = 0.0
    problem = _StaticProblem(sector, ops, force, prescribed, spin)
    dofs, values = problem.dofs, problem.values
    lambdas = np.linspace(0.0, 1.0, n_steps + 1)[1:]
    tips, its, history = [], [], []
    du = u.vector.duplicate()
    K_full = assemble_stiffness(sector, ops) if linear else None
    if linear:  # one factorisation of K with the prescribed rows and columns eliminated
        K_lin = K_full.copy()
        K_lin.zeroRowsColumns(problem.global_rows, diag=1.0)
        ksp = _lu_solver(sector.comm, K_lin, "static_")
    lift, rhs, r = u.vector.duplicate(), u.vector.duplicate(), u.vector.duplicate()
    increment = None                       # the previous load step's converged increment: the secant predictor
    for lam in lambdas:
        step_history = []
        start = u.x.array.copy()
        if increment is not None and not linear:          # equal load steps: u_k+1 ~ u_k + (u_k - u_k-1)
            u.x.array[:] += increment
            u.x.scatter_forward()
        for it in range(max_iterations + 1):
            # the prescribed increment still to apply (only non-zero on the first iteration of a step)
            lift.set(0.0)
            with u.vector.localForm() as local:
                lift.array[dofs] = lam * values - local.array[dofs]
            if linear:
                K_full.mult(u.vector, r)
            else:
                r = assemble_vector(ops.f_int)
            r, res, ref = problem.residual(lam, r)
            LOG.debug("lambda=%.4f it=%d |r|=%.3e ref=%.3e", lam, it, res, ref)
            step_history.append((res, ref))
            if (res <= rtol * ref or (linear and it == 1) or _at_round_off(step_history)) and lift.norm() == 0.0:
                break
            if it == max_iterations:
                raise RuntimeError(f"Newton did not converge at load factor {lam:.4g} "
                                   f"(|r|/ref = {res / ref:.2e} after {it} iterations); use more n_steps")
            A = K_full if linear else problem.tangent(lam)
            problem.correction(A, r, lift, rhs)
            if not linear:
                A.zeroRowsColumns(problem.global_rows, diag=1.0)
                ksp = _lu_solver(sector.comm, A, "newton_")
            ksp.solve(rhs, du)
            u.vector.axpy(1.0, du)
            u.x.scatter_forward()
            if not linear:
                A.destroy()
                ksp.destroy()
        increment = u.x.array - start
        tips.append(gather_dof_values(sector, u.x.array, sector.tip_dofs))
        its.append(it)
        history.append(np.array(step_history))
    if spin:
        problem.M_P.destroy()
    out = fem.Function(sector.V, name="u")
    out.x.array[:] = u.x.array
    return StaticResult(load_factors=lambdas, tip_displacements=np.array(tips), iterations=np.array(its), u=out,
                        residuals=history)


ROUND_OFF_FLOOR = 1e-7


def _at_round_off(history: list) -> bool:
    """Newton has reached its round-off floor: the residual is below ROUND_OFF_FLOOR of its reference (where Newton
    converges quadratically, so the next iterate would be far below the tolerance) and the last iteration did not
    halve it. A small load (a slowly turning structure) has a floor of ~1e-10 of itself: the internal force is a sum
    of element contributions far larger than their net."""
    if len(history) < 2:
        return False
    (previous, _), (res, ref) = history[-2], history[-1]
    return res <= ROUND_OFF_FLOOR * ref and res > 0.5 * previous


def solve_clamped_static(sector: Sector, rhs: np.ndarray, ops: SvkOperators | None = None,
                         K: PETSc.Mat | None = None) -> np.ndarray:
    """Solve K x = b for many right-hand sides b (n_rhs, n_dofs) with the clamp (one MUMPS factorisation). ``K``:
    the clamped stiffness (assembled if None), or any operator in the sector's layout (a cyclic K_k of k = 0 or
    N/2)."""
    _require_serial(sector, "solve_clamped_static")
    own = K is None
    if own:
        K = assemble_stiffness(sector, ops or create_svk_operators(sector))
    ksp = _lu_solver(sector.comm, K, "md_")
    clamped = sector.clamp_bc.dof_indices()[0]
    b, x = K.createVecLeft(), K.createVecRight()
    rhs = np.atleast_2d(rhs)
    out = np.empty_like(rhs)
    for k, r in enumerate(rhs):
        b.array[:] = r
        b.array[clamped] = 0.0
        ksp.solve(b, x)
        out[k] = x.array
    ksp.destroy()
    if own:
        K.destroy()
    return out


class _MumpsSolve:
    """solve(B) with one MUMPS factorisation; its PETSc objects are destroyed with it (petsc4py does not free a
    factorised KSP on garbage collection: about 120 MB per factorisation of the ci disk sector otherwise)."""

    def __init__(self, A):
        self._A = scipy_to_petsc(A)
        self._ksp = _lu_solver(MPI.COMM_SELF, self._A, "cb_")
        self._b, self._x = self._A.createVecLeft(), self._A.createVecRight()

    def __call__(self, B: np.ndarray) -> np.ndarray:
        B = np.asarray(B, float)
        cols = B.reshape(B.shape[0], -1)
        out = np.empty_like(cols)
        for j in range(cols.shape[1]):                 # one factorisation, many right-hand sides
            self._b.array[:] = cols[:, j]
            self._ksp.solve(self._b, self._x)
            out[:, j] = self._x.array
        return out.reshape(B.shape)

    def destroy(self) -> None:
        for obj in (self._ksp, self._A, self._b, self._x):
            if obj is not None:
                obj.destroy()
        self._ksp = self._A = self._b = self._x = None

    def __del__(self):
        try:
            self.destroy()
        except Exception:                              # interpreter shutdown: PETSc may be finalised already
            pass


def rotating_modes(sector: Sector, spin: float, n_modes: int, ops: SvkOperators | None = None,
                   M: PETSc.Mat | None = None, rtol: float = 1e-10, prestress: bool = True,
                   state: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The first ``n_modes`` modes of the structure turning at ``spin`` (rad/s) about the machine axis e_z, without
    Coriolis: K_T(u_c) - spin^2 M_P at the centrifugal equilibrium u_c (``solve_static(spin=...)``, nonlinear SVK,
    Newton to ``rtol``) against the mass; at spin 0 the clamped stiffness K; with ``prestress`` False, K - spin^2 M_P
    (spin softening only: a structure on the axis, whose centrifugal load is nil). Returns (omega (n,) rad/s
    ascending, V (n_dofs, n) with V^T M V = I, this rank's owned entries). ``M``: the mass, if the caller keeps it;
    ``state``: the centrifugal equilibrium at ``spin`` if the caller has solved it (local values with ghosts, as
    ``solve_static(spin=...).u.x.array``)."""
    if not (np.isfinite(spin) and spin >= 0.0):
        raise ValueError(f"spin must be a finite speed >= 0 rad/s, got {spin}")
    ops = ops or create_svk_operators(sector)
    own_mass = M is None
    M = assemble_mass(sector, ops) if own_mass else M
    if spin > 0.0:
        if state is not None:
            u = np.asarray(state, float)
        else:
            u = (solve_static(sector, spin=spin, n_steps=2, ops=ops, rtol=rtol).u.x.array if prestress else
                 np.zeros(ops.u.x.array.size))
        K = assemble_tangent(sector, u, ops, spin)
    else:
        K = assemble_stiffness(sector, ops)
    omega, vecs = solve_eigenproblem(K, M, n_modes)
    V = np.column_stack([v.array.copy() for v in vecs])
    K.destroy()
    if own_mass:
        M.destroy()
    return np.asarray(omega), V


def reduced_coriolis(sector: Sector, V: np.ndarray, ops: SvkOperators | None = None,
                     G: PETSc.Mat | None = None) -> np.ndarray:
    """V^T G_1 V (n, n): the Coriolis matrix per unit spin about e_z (``assemble_coriolis``; ``G``: that matrix, if
    the caller keeps it: it does not depend on the speed) on the columns of V (this rank's owned entries, e.g.
    ``rotating_modes``' vectors), summed over ranks and made exactly skew-symmetric. With M-orthonormal modes V of
    K_T - spin^2 M_P, the turning structure with Coriolis is I u'' + spin (V^T G_1 V) u' + diag(omega^2) u = 0 on
    their span (``model.campbell.gyroscopic_frequencies``)."""
    own = G is None
    G = assemble_coriolis(sector, ops or create_svk_operators(sector)) if own else G
    Gr = _project(sector, G, V)
    if own:
        G.destroy()
    return 0.5 * (Gr - Gr.T)


def _project(sector: Sector, A: PETSc.Mat, V: np.ndarray) -> np.ndarray:
    """V^T A V (n, n) for the columns of V (this rank's owned entries), summed over ranks."""
    x, y = A.createVecs()
    AV = np.empty_like(V)
    for k in range(V.shape[1]):
        x.array[:] = V[:, k]
        A.mult(x, y)
        AV[:, k] = y.array
    return sector.comm.allreduce(V.T @ AV, op=MPI.SUM)


def reduced_rotation_terms(sector: Sector, V: np.ndarray, ops: SvkOperators | None = None
                           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(V^T M_P V, V^T f_c0, V^T G_1 V) on the columns of V (this rank's owned entries, zero on the clamp), summed
    over ranks: the spin softening per unit spin^2 (``assemble_spin_softening``), the centrifugal load at rest per unit
    spin^2 (f_c0 = rho P X: ``forms.centrifugal_force`` at u = 0 and spin 1; the force at u is spin^2 (f_c0 + M_P u),
    linear in u) and the Coriolis matrix per unit spin (skew). A reduced model on V turning at spin about e_z
    (``model.rotating``) is exactly these three and its model at rest."""
    ops = ops or create_svk_operators(sector)
    M_P, G = assemble_spin_softening(sector, ops), assemble_coriolis(sector, ops)
    Mr, Gr = _project(sector, M_P, V), _project(sector, G, V)
    for A in (M_P, G):
        A.destroy()
    zero = fem.Function(sector.V)
    one = fem.Constant(sector.mesh, PETSc.ScalarType(1.0))
    f = assemble_vector(fem.form(forms.centrifugal_force(zero, ufl.TestFunction(sector.V), ops.constants["rho"],
                                                         one), jit_params=JIT_PARAMS))
    fem_petsc.set_bc(f, [sector.clamp_bc], scale=0.0)
    Fr = sector.comm.allreduce(V.T @ f.array, op=MPI.SUM)
    f.destroy()
    return 0.5 * (Mr + Mr.T), Fr, 0.5 * (Gr - Gr.T)


def mumps_solver(A) -> Callable[[np.ndarray], np.ndarray]:
    """Factorise a SciPy sparse matrix once with MUMPS (serial); returns solve(B) for B (n,) or (n, m). The
    factorisation is freed when solve is (or by solve.destroy())."""
    return _MumpsSolve(A)


def slepc_eigenpairs(K, M, n_modes: int, sigma: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Lowest ``n_modes`` eigenpairs of SciPy sparse (K, M) (serial) through ``solve_eigenproblem``: (omega (n,),
    V (n_dofs, n_modes)) with V^T M V = I and each vector's largest entry positive."""
    Kp, Mp = scipy_to_petsc(K), scipy_to_petsc(M)
    omega, vecs = solve_eigenproblem(Kp, Mp, n_modes, sigma=sigma, prefix="cb_interface_")
    V = np.column_stack([v.array.copy() for v in vecs])
    Kp.destroy()
    Mp.destroy()
    return omega, V
