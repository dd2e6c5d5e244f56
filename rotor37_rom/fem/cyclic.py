"""Cyclic sectors on dolfinx: the disk sector and plate sector meshes (their faces are paired when they are built:
``sector.locate_cyclic_pairs``), the projected
operators per harmonic index k (nodal diameter) and their modes through the SLEPc shift-invert path, and the
expansion of a sector mode to the whole structure.

Part of the dolfinx adapter (``rotor37_rom.fem``); the algebra of the projection is ``rotor37_rom.disk.symmetry``. Runs
under MPI: the pairing is computed on every rank from gathered face nodes (a few thousand), the projection T_k is a
distributed PETSc matrix in the layout of [a; b] (each rank owns the a and b copies of its own DOFs), and K_k = T_k^T
diag(K, K) T_k is PETSc's PtAP. Eliminated slots (the right face, constrained axis directions) get 1 on K_k's diagonal
and MASS_DIAGONAL on M_k's, like the clamped DOFs: their eigenvalues sit at 1e14 (rad/s)^2.
"""
from __future__ import annotations

import dataclasses
import logging
from pathlib import Path

import numpy as np
from dolfinx import fem
from mpi4py import MPI
from petsc4py import PETSc

from rotor37_rom.disk.symmetry import cyclic_projection, cyclic_projection_parts
from rotor37_rom.forms import Material
from rotor37_rom.geometry import blade as blade_geometry
from rotor37_rom.geometry import disk as disk_geometry
from rotor37_rom.geometry.tables import read_blade_table

from .operators import MASS_DIAGONAL, SvkOperators, assemble_mass, assemble_stiffness, create_svk_operators
from .sector import Sector, build_on_rank0
from .solvers import shift_invert_solver, solve_eigenproblem

__all__ = ["create_disk_sector", "create_annular_sector", "create_ring_sector", "cyclic_projector",
           "centrifugal_state", "rotating_cyclic_operators", "CyclicOperators", "assemble_cyclic_operators",
           "CyclicModes", "solve_cyclic_modes", "sector_fields"]

LOG = logging.getLogger(__name__)


def create_disk_sector(comm: MPI.Comm = MPI.COMM_WORLD, table: str | Path | None = None, preset="coarse",
                       material: Material | None = None, degree: int = 2,
                       n_tip_nodes: int = blade_geometry.N_TIP_NODES, shorten: float = 4e-3,
                       profile: disk_geometry.DiskProfile | None = None, n_sectors: int = 36) -> Sector:
    """The rotor 37 bladed-disk sector (``geometry.disk.create_disk_sector_model``) as a Sector with its cyclic faces
    paired (``sector.locate_cyclic_pairs``), clamped at the bore. ``table``: NASA Table IV for the exact loft (None:
    the parametric blade)."""
    material = material or Material()
    preset_obj = blade_geometry.get_mesh_preset(preset)
    table_obj = read_blade_table(table) if table is not None else None
    profile = profile or disk_geometry.DiskProfile()
    return build_on_rank0(
        comm, lambda: disk_geometry.create_disk_sector_model(table_obj, preset_obj, n_tip_nodes=n_tip_nodes,
                                                             shorten=shorten, profile=profile, n_sectors=n_sectors),
        material, degree, preset_obj.name, "the disk sector")


def create_annular_sector(inner: float, outer: float, thickness: float, n_sectors: int, size: float,
                          layers: int = 2, comm: MPI.Comm = MPI.COMM_WORLD, material: Material | None = None,
                          degree: int = 2) -> Sector:
    """A sector of an annular plate clamped at its inner edge, ``size`` (m) in the plane and ``layers`` elements
    through the thickness (``geometry.disk.create_annular_sector_model``)."""
    return build_on_rank0(
        comm, lambda: disk_geometry.create_annular_sector_model(inner, outer, thickness, n_sectors, size, layers),
        material or Material(), degree, "plate", "the plate sector")


def create_ring_sector(radius: float, radial: float, axial: float, n_sectors: int, size: float,
                       comm: MPI.Comm = MPI.COMM_WORLD, material: Material | None = None, degree: int = 2) -> Sector:
    """A sector of a free thin ring (``geometry.disk.create_ring_sector_model``): nothing clamped, so that its
    harmonic indices k = 0 and 1 hold rigid-body motions (their operators are singular: solve them with a shift
    sigma < 0)."""
    return build_on_rank0(
        comm, lambda: disk_geometry.create_ring_sector_model(radius, radial, axial, n_sectors, size),
        material or Material(), degree, "ring", "the ring sector")


def _layout(sector: Sector, m: int) -> tuple[np.ndarray, int, int]:
    """perm (m n,): canonical slot c n + g (g a global DOF) -> its row in the PETSc layout, where each rank owns the
    m copies of its own DOFs; and this rank's (first row, number of rows)."""
    im, bs = sector.V.dofmap.index_map, sector.V.dofmap.index_map_bs
    n = im.size_global * bs
    ranges = sector.comm.allgather((im.local_range[0] * bs, im.local_range[1] * bs))
    perm = np.empty(m * n, dtype=np.int64)
    for r0, r1 in ranges:
        for c in range(m):
            perm[c * n + np.arange(r0, r1)] = m * r0 + c * (r1 - r0) + np.arange(r1 - r0)
    r0, r1 = ranges[sector.comm.rank]
    return perm, m * r0, m * (r1 - r0)


def _petsc_from_rows(comm, rows_csr, perm_cols, local_rows: int, size: int) -> PETSc.Mat:
    """A distributed AIJ matrix from this rank's rows (scipy CSR with canonical column slots)."""
    A = rows_csr.tocsr()
    cols = perm_cols[A.indices]
    out = PETSc.Mat().createAIJ(size=((local_rows, size), (local_rows, size)),
                                csr=(A.indptr.astype(PETSc.IntType), cols.astype(PETSc.IntType),
                                     A.data.astype(PETSc.ScalarType)), comm=comm)
    out.assemble()
    return out


def _same_pattern(mats: list) -> list:
    """The matrices on the union of their nonzero patterns (new matrices; the inputs are destroyed), so that
    combinations of them are AXPYs of equal-length value arrays."""
    DIFFERENT, SUBSET = PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN, PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN
    union = mats[0].duplicate(copy=True)
    for A in mats[1:]:
        union.axpy(1.0, A, DIFFERENT)
    out = []
    for A in mats:
        B = union.duplicate(copy=False)                          # the union's pattern, zero values
        B.axpy(1.0, A, SUBSET)
        out.append(B)
        A.destroy()
    union.destroy()
    return out


def _block_diagonal(A: PETSc.Mat, sector: Sector, m: int, perm: np.ndarray, local_rows: int) -> PETSc.Mat:
    """diag(A, ..., A) (m copies) in the PETSc layout of ``_layout``."""
    import scipy.sparse as sp

    indptr, indices, data = A.getValuesCSR()
    n = A.getSize()[0]
    r0 = A.getOwnershipRange()[0]
    local = sp.csr_matrix((data, indices, indptr), shape=(indptr.size - 1, n))
    blocks = sp.vstack([sp.csr_matrix((local.data, local.indices + c * n, local.indptr), shape=(local.shape[0], m * n))
                        for c in range(m)]).tocsr()
    # this rank's rows are its slots c n + g in copy order: exactly its rows of the layout, in order
    del r0
    return _petsc_from_rows(sector.comm, blocks, perm, local_rows, m * n)


def _eliminated_diagonal(sector: Sector, rows: np.ndarray, m: int, value: float) -> PETSc.Mat:
    """``value`` on the diagonal of the eliminated slots (layout rows), for their empty rows in K_k and M_k."""
    _, _, local_rows = _layout(sector, m)
    size = m * sector.n_dofs
    D = PETSc.Mat().createAIJ(size=((local_rows, size), (local_rows, size)), nnz=1, comm=sector.comm)
    for r in rows:                                           # one face's slots, not the mesh
        D.setValue(int(r), int(r), value)
    D.assemble()
    return D


def _mine(sector: Sector, m: int) -> np.ndarray:
    """This rank's canonical slots c n + g (its own DOFs g, each copy c) in layout order."""
    im, bs, n = sector.V.dofmap.index_map, sector.V.dofmap.index_map_bs, sector.n_dofs
    g0, g1 = im.local_range[0] * bs, im.local_range[1] * bs
    return np.concatenate([c * n + np.arange(g0, g1) for c in range(m)])


def is_free(sector: Sector) -> bool:
    """Whether nothing of ``sector`` is clamped (on any rank): its harmonic indices 0 and 1 hold rigid-body
    motions."""
    return sector.comm.allreduce(sector.clamp_bc.dof_indices()[0].size, op=MPI.SUM) == 0


def cyclic_projector(sector: Sector, k: int) -> tuple[PETSc.Mat, np.ndarray]:
    """(T_k, eliminated): the projection of harmonic index k (``disk.symmetry.cyclic_projection``) as a distributed
    PETSc matrix in the layout where each rank owns the copies of its own DOFs (for k = 0, one copy: its rows are
    the sector's own DOF numbering, u = T_0 x a sector field), and this rank's rows of the eliminated slots (the
    right face, constrained axis directions)."""
    pairs = sector.cyclic
    if pairs is None:
        raise ValueError(f"{sector.source} is not a cyclic sector (no paired left/right faces)")
    k = pairs.check_k(k)
    m = pairs.n_copies(k)
    perm, first, local_rows = _layout(sector, m)
    n = sector.n_dofs
    T, kept = cyclic_projection(n, pairs, k)
    mine = _mine(sector, m)
    T_p = _petsc_from_rows(sector.comm, T[mine], perm, local_rows, m * n)
    return T_p, first + np.flatnonzero(~kept[mine])


class CyclicOperators:
    """A cyclic sector's K and M, their block-diagonal copies (one per number of copies m) and the layout, reused
    over the harmonic indices; nothing is assembled again (pitfall 6 of the cyclic notes: re-assembling per k is
    what makes tools slow). For 0 < k < N/2 (no axis nodes) the projected operators are A_0 + cos A_c + sin A_s of
    three matrices computed once (three PtAP each), written into one pair of matrices whose solver is kept: each k
    costs two AXPY, a numeric MUMPS refactorisation and the Krylov-Schur iterations. k = 0 and N/2 (one copy, and
    any k of a sector with axis nodes) are projected by PtAP each.

    Args:
        sector: a cyclic Sector; K, M: its clamped operators (assembled from ``ops`` if None).
    """

    def __init__(self, sector: Sector, K: PETSc.Mat | None = None, M: PETSc.Mat | None = None,
                 ops: SvkOperators | None = None):
        if sector.cyclic is None:
            raise ValueError(f"{sector.source} is not a cyclic sector (no paired left/right faces)")
        if K is None or M is None:
            ops = ops or create_svk_operators(sector)
            K, M = assemble_stiffness(sector, ops), assemble_mass(sector, ops)
        self.sector, self.K, self.M = sector, K, M
        self.free = is_free(sector)
        self._blocks: dict = {}
        self._parts = None
        self._work = None

    def _copies(self, m: int):
        """(diag(K..), diag(M..), perm, first row, local rows) for m copies, built once."""
        if m not in self._blocks:
            perm, first, local_rows = _layout(self.sector, m)
            self._blocks[m] = (_block_diagonal(self.K, self.sector, m, perm, local_rows),
                               _block_diagonal(self.M, self.sector, m, perm, local_rows), perm, first, local_rows)
        return self._blocks[m]


    def _harmonic_parts(self) -> list:
        """For 0 < k < N/2 without axis nodes: [(K_0, K_c, K_s), (M_0, M_c, M_s), (T_0, T_c, T_s)], each three
        matrices of one nonzero pattern with A_k = A_0 + cos(k alpha) A_c + sin(k alpha) A_s
        (``disk.symmetry.cyclic_projection_parts``): three PtAP per operator once, then every k is two AXPY of
        values."""
        if self._parts is None:
            sector, pairs = self.sector, self.sector.cyclic
            K2, M2, perm, first, local_rows = self._copies(2)
            n, mine, SAME = sector.n_dofs, _mine(sector, 2), PETSc.Mat.Structure.SAME_NONZERO_PATTERN

            def petsc(A):
                return _petsc_from_rows(sector.comm, A.tocsr()[mine], perm, local_rows, 2 * n)

            T0, Tc, Ts = cyclic_projection_parts(n, pairs)
            eliminated = first + np.flatnonzero(T0.diagonal()[mine] == 0.0)   # the right face, both copies
            parts = []
            for A2, diag in ((K2, 1.0), (M2, MASS_DIAGONAL)):
                plus, minus, sine = (A2.PtAP(P) for P in (petsc(T0 + Tc), petsc(T0 - Tc), petsc(T0 + Ts)))
                plus, minus, sine, D = _same_pattern([plus, minus, sine,
                                                      _eliminated_diagonal(sector, eliminated, 2, diag)])
                A0 = plus.duplicate(copy=True)                   # (T0 + Tc)^T A2 (T0 + Tc) = B0 + Bc, minus: B0 - Bc
                A0.axpy(1.0, minus, SAME)
                A0.scale(0.5)
                Ac = plus
                Ac.axpy(-1.0, A0, SAME)
                As = sine
                As.axpy(-1.0, A0, SAME)
                A0.axpy(1.0, D, SAME)
                for A in (minus, D):
                    A.destroy()
                parts.append((A0, Ac, As))
            parts.append(tuple(_same_pattern([petsc(T0), petsc(Tc), petsc(Ts)])))
            self._parts = parts
        return self._parts

    def _combine(self, k: int, out) -> None:
        """(K_k, M_k, T_k) = A_0 + cos(k alpha) A_c + sin(k alpha) A_s written into ``out`` (matrices of the parts'
        pattern: their objects and patterns stay, only values change)."""
        SAME = PETSc.Mat.Structure.SAME_NONZERO_PATTERN
        c, s = np.cos(k * self.sector.cyclic.angle), np.sin(k * self.sector.cyclic.angle)
        for (A0, Ac, As), A in zip(self._harmonic_parts(), out):
            A0.copy(A, SAME)
            A.axpy(c, Ac, SAME)
            A.axpy(s, As, SAME)

    def _by_parts(self, k: int) -> bool:
        """Whether index k is a combination of the k-free parts (0 < k < N/2, no axis nodes)."""
        return self.sector.cyclic.n_copies(k) == 2 and not len(self.sector.cyclic.axis)

    def projector(self, k: int) -> tuple[PETSc.Mat, np.ndarray]:
        """``cyclic_projector(sector, k)``."""
        return cyclic_projector(self.sector, k)

    def project_operator(self, A: PETSc.Mat, k: int) -> PETSc.Mat:
        """T_k^T diag(A, ..., A) T_k: any other operator of the sector (e.g. the Coriolis matrix
        ``assemble_coriolis``, skew-symmetric) on harmonic index k, in the layout of ``project``'s (K_k, M_k) and
        ``CyclicModes.x``; the eliminated slots' rows are empty. The real cos/sin copies carry both travelling
        directions of index k: a skew A couples them (the forward and backward waves)."""
        m = self.sector.cyclic.n_copies(self.sector.cyclic.check_k(k))
        _, _, perm, _, local_rows = self._copies(m)
        T_p, _ = self.projector(k)
        A2 = _block_diagonal(A, self.sector, m, perm, local_rows)
        out = A2.PtAP(T_p)
        A2.destroy()
        T_p.destroy()
        return out

    def reduced_operator(self, A: PETSc.Mat, modes: "CyclicModes") -> np.ndarray:
        """X^T A_k X (n, n) on the projected eigenvectors X of ``modes`` (``CyclicModes.x``, M_k-orthonormal), with
        A_k = ``project_operator(A, modes.k)``: e.g. the Coriolis matrix per unit spin of the index's modes
        (``model.campbell.gyroscopic_frequencies`` solves the turning structure on their span)."""
        if not modes.x:
            raise ValueError("modes: no projected eigenvectors (CyclicModes.x is empty)")
        Ak = self.project_operator(A, modes.k)
        y = Ak.createVecLeft()
        out = np.empty((len(modes.x), len(modes.x)))
        for j, xj in enumerate(modes.x):
            Ak.mult(xj, y)
            for i, xi in enumerate(modes.x):
                out[i, j] = xi.dot(y)                    # a global dot product: the same on every rank
        y.destroy()
        Ak.destroy()
        return out

    def project(self, k: int) -> tuple[PETSc.Mat, PETSc.Mat, PETSc.Mat]:
        """(K_k, M_k, T_k) for harmonic index k: K_k = T_k^T diag(K, K) T_k and likewise M_k (one copy for k = 0 and
        N/2), with 1 / MASS_DIAGONAL on the eliminated slots' diagonal."""
        pairs = self.sector.cyclic
        k = pairs.check_k(k)
        m = pairs.n_copies(k)
        if self._by_parts(k):
            out = tuple(A0.duplicate(copy=False) for A0, _, _ in self._harmonic_parts())
            self._combine(k, out)
            return out
        K2, M2, *_ = self._copies(m)
        T_p, eliminated = self.projector(k)
        operators = []
        for A2, diag in ((K2, 1.0), (M2, MASS_DIAGONAL)):
            Ak = A2.PtAP(T_p)
            # the eliminated slots' empty rows get a diagonal: one merge of patterns (not one insertion per entry)
            D = _eliminated_diagonal(self.sector, eliminated, m, diag)
            Ak.axpy(1.0, D, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
            D.destroy()
            operators.append(Ak)
        return operators[0], operators[1], T_p

    def modes(self, k: int, n_modes: int = 6, sigma: float = 0.0, initial=None) -> "CyclicModes":
        """The lowest ``n_modes`` distinct modes of harmonic index k (2 n_modes eigenpairs for 0 < k < N/2), with the
        sector's SLEPc shift-invert solver (``solve_eigenproblem``). ``initial``: the projected eigenvectors of a
        neighbouring k with as many copies (``CyclicModes.x``), a good start for Krylov-Schur."""
        if n_modes < 1:
            raise ValueError(f"n_modes must be >= 1, got {n_modes}")
        m = self.sector.cyclic.n_copies(k)
        if k in (0, 1) and sigma >= 0.0 and self.free:
            raise ValueError(f"{self.sector.source} is free (nothing clamped): harmonic index {k} holds rigid-body "
                             f"motions, its stiffness is singular; pass a shift sigma < 0")
        reuse = self._by_parts(k)
        if reuse:            # one K_k object and one solver for all 0 < k < N/2: MUMPS refactors, no new analysis
            if self._work is None:
                self._work = (*(A0.duplicate(copy=False) for A0, _, _ in self._harmonic_parts()),
                              shift_invert_solver(self.sector.comm, sigma, prefix="cyclic_"))
            Kk, Mk, T, eps = self._work
            if eps.getTarget() != sigma:
                raise ValueError(f"sigma must stay {eps.getTarget()} over one CyclicOperators' harmonic indices, "
                                 f"got {sigma}")
            self._combine(k, (Kk, Mk, T))
        else:
            (Kk, Mk, T), eps = self.project(k), None
        omega, vecs = solve_eigenproblem(Kk, Mk, m * n_modes, sigma=sigma, prefix="cyclic_", initial=initial,
                                         eps=eps)
        a, b = [], []
        for x in vecs:
            fa, fb = sector_fields(self.sector, T, x, m)
            a.append(fa)
            b.append(fb)
        if not reuse:
            for A in (Kk, Mk, T):
                A.destroy()
        return CyclicModes(int(k), omega, a, b, vecs)

    def destroy(self) -> None:
        for K2, M2, *_ in self._blocks.values():
            K2.destroy()
            M2.destroy()
        self._blocks.clear()
        for part in self._parts or []:
            for A in part:
                A.destroy()
        for A in self._work or ():
            A.destroy()
        self._parts = self._work = None


def centrifugal_state(sector: Sector, spin: float, ops: SvkOperators | None = None, n_steps: int = 2,
                      rtol: float = 1e-10, max_iterations: int = 25) -> fem.Function:
    """The whole structure's centrifugal equilibrium at ``spin`` (rad/s) about e_z, on one cyclic sector: the
    load is the same on every sector, so the state is a harmonic-index-0 field, u = T_0 x (the right face the left
    one turned). Newton on T_0^T r(T_0 x) = 0 with r = f_int(u) - f_c(u) (SVK, the centrifugal force following the
    deformed position, ``forms.centrifugal_force``) and its exact tangent T_0^T (K_T(u) - spin^2 M_P) T_0, load steps
    in spin^2 (as ``solve_static(spin=...)``), to ||T_0^T r|| <= rtol max(||f_c||, ||f_int||) or its round-off floor
    (``solvers._at_round_off``). Runs under MPI."""
    import ufl

    from rotor37_rom import forms

    from .operators import JIT_PARAMS

    if not (np.isfinite(spin) and spin >= 0.0):
        raise ValueError(f"spin must be a finite speed >= 0 rad/s, got {spin}")
    if not (1 <= n_steps <= 10000):
        raise ValueError(f"n_steps must be in [1, 10000], got {n_steps}")
    if spin == 0.0:
        return fem.Function(sector.V, name="u")
    if is_free(sector):
        raise ValueError(f"{sector.source} is free (nothing clamped): its harmonic index 0 holds rigid-body motions, "
                         f"so its centrifugal state is not unique; clamp it, or take spin softening alone "
                         f"(prestress=False)")
    ops = ops or create_svk_operators(sector)
    T0, eliminated = cyclic_projector(sector, 0)
    u = ops.u
    u.x.array[:] = 0.0
    spin_c = fem.Constant(sector.mesh, PETSc.ScalarType(spin))
    centrifugal = fem.form(forms.centrifugal_force(u, ufl.TestFunction(sector.V), ops.constants["rho"], spin_c),
                           jit_params=JIT_PARAMS)
    D = _eliminated_diagonal(sector, eliminated, 1, 1.0)
    x, dx = T0.createVecRight(), T0.createVecRight()
    rhs, du = T0.createVecRight(), T0.createVecLeft()
    try:
        _newton_on_index_0(sector, ops, centrifugal, spin_c, spin, T0, D, (x, dx, rhs, du), n_steps, rtol,
                           max_iterations)
    finally:
        for obj in (T0, D, x, dx, rhs, du):
            obj.destroy()
    out = fem.Function(sector.V, name="u")
    out.x.array[:] = u.x.array
    return out


def _newton_on_index_0(sector: Sector, ops: SvkOperators, centrifugal, spin_c, spin: float, T0, D, work,
                       n_steps: int, rtol: float, max_iterations: int) -> None:
    """``centrifugal_state``'s load steps and Newton iterations on x (u = T_0 x, left in ``ops.u``)."""
    from dolfinx.fem import petsc as fem_petsc

    from .operators import assemble_tangent, assemble_vector
    from .solvers import _at_round_off, _lu_solver

    x, dx, rhs, du = work
    u = ops.u
    for lam in np.linspace(0.0, 1.0, n_steps + 1)[1:]:
        spin_c.value = spin * np.sqrt(lam)
        history: list = []
        for it in range(max_iterations + 1):
            r = assemble_vector(ops.f_int)
            reference = r.norm()
            f_c = assemble_vector(centrifugal)
            reference = max(reference, f_c.norm(), 1e-300)
            r.axpy(-1.0, f_c)
            fem_petsc.set_bc(r, [sector.clamp_bc], scale=0.0)
            T0.multTranspose(r, rhs)
            res = rhs.norm()
            for vec in (r, f_c):
                vec.destroy()
            LOG.debug("centrifugal state: spin^2 factor %.3f it %d |T0^T r| %.3e ref %.3e", lam, it, res, reference)
            history.append((res, reference))
            if res <= rtol * reference or _at_round_off(history):
                break
            if it == max_iterations:
                raise RuntimeError(f"centrifugal state: Newton did not converge at {spin * np.sqrt(lam):.6g} rad/s "
                                   f"(|r|/ref = {res / reference:.2e} after {it} iterations); use more n_steps")
            A = assemble_tangent(sector, u.x.array.copy(), ops, spin * np.sqrt(lam))
            A0 = A.PtAP(T0)
            A0.axpy(1.0, D, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
            ksp = _lu_solver(sector.comm, A0, "cyclic_static_")
            rhs.scale(-1.0)
            ksp.solve(rhs, dx)
            x.axpy(1.0, dx)
            T0.mult(x, du)
            with u.vector.localForm() as local:
                local.array[:du.getLocalSize()] = du.array
            u.x.scatter_forward()
            for obj in (ksp, A0, A):
                obj.destroy()


def rotating_cyclic_operators(sector: Sector, spin: float, ops: SvkOperators | None = None,
                              M: PETSc.Mat | None = None, prestress: bool = True, rtol: float = 1e-10
                              ) -> tuple["CyclicOperators", fem.Function]:
    """The cyclic operators of the structure turning at ``spin`` (rad/s) about e_z, without Coriolis: K_T(u_c) -
    spin^2 M_P at the whole structure's centrifugal equilibrium u_c (``centrifugal_state``: one state for every
    harmonic index, the load being the same on every sector) and M; with ``prestress`` False, K - spin^2 M_P (spin
    softening alone). Returns (CyclicOperators, u_c). Its modes per index k are the nodal-diameter families of the
    turning structure (add Coriolis with ``CyclicOperators.reduced_operator(assemble_coriolis(...), modes)``)."""
    from .operators import assemble_tangent

    if not (np.isfinite(spin) and spin >= 0.0):
        raise ValueError(f"spin must be a finite speed >= 0 rad/s, got {spin}")
    ops = ops or create_svk_operators(sector)
    M = assemble_mass(sector, ops) if M is None else M
    if spin > 0.0 and prestress:
        u = centrifugal_state(sector, spin, ops, rtol=rtol)
    else:
        u = fem.Function(sector.V, name="u")
    K = assemble_tangent(sector, u.x.array, ops, spin) if spin > 0.0 else assemble_stiffness(sector, ops)
    return CyclicOperators(sector, K, M), u


def assemble_cyclic_operators(sector: Sector, k: int, K: PETSc.Mat | None = None, M: PETSc.Mat | None = None,
                              ops: SvkOperators | None = None) -> tuple[PETSc.Mat, PETSc.Mat, PETSc.Mat]:
    """(K_k, M_k, T_k) of the sector for harmonic index k (``CyclicOperators.project``)."""
    return CyclicOperators(sector, K, M, ops).project(k)


@dataclasses.dataclass(frozen=True)
class CyclicModes:
    """Modes of a cyclic sector for one harmonic index.

    Attributes:
        k: harmonic index (nodal diameter); omega (n,): rad/s ascending, each value twice for 0 < k < N/2 (the cos
        and sin modes); a, b: lists of the sector's cos and sin fields (dolfinx Functions; b is None for k = 0 and
        N/2), normalised so that a^T M a + b^T M b = 1; x: the projected eigenvectors (PETSc), a start for a
        neighbouring k.

    Expanded on the whole structure (``disk.symmetry.expand_sector_mode``: sector s carries cos(s k alpha) a -
    sin(s k alpha) b), a mode's modal mass is N/2 for 0 < k < N/2 and N for k = 0 and N/2.
    """

    k: int
    omega: np.ndarray
    a: list
    b: list
    x: list = dataclasses.field(default_factory=list)

    def distinct(self) -> tuple[np.ndarray, list]:
        """(omega, indices) with each double mode counted once (every second of a pair)."""
        step = 1 if self.b[0] is None else 2
        idx = list(range(0, len(self.omega), step))
        return self.omega[idx], idx


def sector_fields(sector: Sector, T: PETSc.Mat, x: PETSc.Vec, m: int) -> tuple[fem.Function, fem.Function | None]:
    """The sector's cos and sin fields (a, b) of the projected vector x (u = T x), as Functions."""
    u = T.createVecLeft()
    T.mult(x, u)
    arr = u.getArray(readonly=True)
    n_local = arr.size // m
    out = []
    for c in range(m):
        f = fem.Function(sector.V)
        f.vector.array[:] = arr[c * n_local:(c + 1) * n_local]
        f.x.scatter_forward()
        out.append(f)
    return out[0], (out[1] if m == 2 else None)


def solve_cyclic_modes(sector: Sector, k: int, n_modes: int = 6, K: PETSc.Mat | None = None,
                       M: PETSc.Mat | None = None, ops: SvkOperators | None = None, sigma: float = 0.0) -> CyclicModes:
    """The lowest ``n_modes`` distinct modes of harmonic index k (``CyclicOperators.modes``; to sweep over k, keep one
    CyclicOperators)."""
    ops_k = CyclicOperators(sector, K, M, ops)
    try:
        return ops_k.modes(k, n_modes, sigma)
    finally:
        ops_k.destroy()
