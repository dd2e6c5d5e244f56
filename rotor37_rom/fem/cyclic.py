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

__all__ = ["create_disk_sector", "create_annular_sector", "CyclicOperators", "assemble_cyclic_operators",
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

    def _mine(self, m: int) -> np.ndarray:
        """This rank's canonical slots c n + g (its own DOFs g, each copy c) in layout order."""
        im, bs, n = self.sector.V.dofmap.index_map, self.sector.V.dofmap.index_map_bs, self.sector.n_dofs
        g0, g1 = im.local_range[0] * bs, im.local_range[1] * bs
        return np.concatenate([c * n + np.arange(g0, g1) for c in range(m)])

    def _eliminated_diagonal(self, rows: np.ndarray, m: int, value: float) -> PETSc.Mat:
        """``value`` on the diagonal of the eliminated slots (layout rows), for their empty rows in K_k and M_k."""
        _, _, _, _, local_rows = self._copies(m)
        size = m * self.sector.n_dofs
        D = PETSc.Mat().createAIJ(size=((local_rows, size), (local_rows, size)), nnz=1, comm=self.sector.comm)
        for r in rows:                                           # one face's slots, not the mesh
            D.setValue(int(r), int(r), value)
        D.assemble()
        return D

    def _harmonic_parts(self) -> list:
        """For 0 < k < N/2 without axis nodes: [(K_0, K_c, K_s), (M_0, M_c, M_s), (T_0, T_c, T_s)], each three
        matrices of one nonzero pattern with A_k = A_0 + cos(k alpha) A_c + sin(k alpha) A_s
        (``disk.symmetry.cyclic_projection_parts``): three PtAP per operator once, then every k is two AXPY of
        values."""
        if self._parts is None:
            sector, pairs = self.sector, self.sector.cyclic
            K2, M2, perm, first, local_rows = self._copies(2)
            n, mine, SAME = sector.n_dofs, self._mine(2), PETSc.Mat.Structure.SAME_NONZERO_PATTERN

            def petsc(A):
                return _petsc_from_rows(sector.comm, A.tocsr()[mine], perm, local_rows, 2 * n)

            T0, Tc, Ts = cyclic_projection_parts(n, pairs)
            eliminated = first + np.flatnonzero(T0.diagonal()[mine] == 0.0)   # the right face, both copies
            parts = []
            for A2, diag in ((K2, 1.0), (M2, MASS_DIAGONAL)):
                plus, minus, sine = (A2.PtAP(P) for P in (petsc(T0 + Tc), petsc(T0 - Tc), petsc(T0 + Ts)))
                plus, minus, sine, D = _same_pattern([plus, minus, sine,
                                                      self._eliminated_diagonal(eliminated, 2, diag)])
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

    def project(self, k: int) -> tuple[PETSc.Mat, PETSc.Mat, PETSc.Mat]:
        """(K_k, M_k, T_k) for harmonic index k: K_k = T_k^T diag(K, K) T_k and likewise M_k (one copy for k = 0 and
        N/2), with 1 / MASS_DIAGONAL on the eliminated slots' diagonal."""
        sector, pairs = self.sector, self.sector.cyclic
        k = pairs.check_k(k)
        m = pairs.n_copies(k)
        if self._by_parts(k):
            out = tuple(A0.duplicate(copy=False) for A0, _, _ in self._harmonic_parts())
            self._combine(k, out)
            return out
        K2, M2, perm, first, local_rows = self._copies(m)
        n = sector.n_dofs
        T, kept = cyclic_projection(n, pairs, k)
        mine = self._mine(m)
        T_p = _petsc_from_rows(sector.comm, T[mine], perm, local_rows, m * n)
        eliminated = first + np.flatnonzero(~kept[mine])
        operators = []
        for A2, diag in ((K2, 1.0), (M2, MASS_DIAGONAL)):
            Ak = A2.PtAP(T_p)
            # the eliminated slots' empty rows get a diagonal: one merge of patterns (not one insertion per entry)
            D = self._eliminated_diagonal(eliminated, m, diag)
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
