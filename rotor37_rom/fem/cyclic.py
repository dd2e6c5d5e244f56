"""Cyclic sectors on dolfinx: the disk sector and plate sector meshes (their faces are paired when they are built:
``sector.locate_cyclic_pairs``), the projected
operators per harmonic index k (nodal diameter) and their modes through the SLEPc shift-invert path, and the
expansion of a sector mode to the whole structure.

Part of the dolfinx adapter (``rotor37_rom.fem``); the algebra of the projection is ``rotor37_rom.cyclic``. Runs under
MPI: the pairing is computed on every rank from gathered face nodes (a few thousand), the projection T_k is a
distributed PETSc matrix in the layout of [a; b] (each rank owns the a and b copies of its own DOFs), and
K_k = T_k^T diag(K, K) T_k is PETSc's PtAP. Eliminated slots (the right face, constrained axis directions) get 1 on
K_k's diagonal and MASS_DIAGONAL on M_k's, like the clamped DOFs: their eigenvalues sit at 1e14 (rad/s)^2.
"""
from __future__ import annotations

import dataclasses
import logging
from pathlib import Path

import numpy as np
from dolfinx import fem
from mpi4py import MPI
from petsc4py import PETSc

from rotor37_rom.cyclic import cyclic_projection
from rotor37_rom.forms import Material
from rotor37_rom.geometry import blade as blade_geometry
from rotor37_rom.geometry import disk as disk_geometry
from rotor37_rom.geometry.tables import read_blade_table

from .operators import MASS_DIAGONAL, SvkOperators, assemble_mass, assemble_stiffness, create_svk_operators
from .sector import Sector, build_on_rank0
from .solvers import solve_eigenproblem

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
    """A sector of an annular plate clamped at its inner edge (``geometry.disk.create_annular_sector_model``)."""
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
    over the harmonic indices: each k costs one projection T_k, two PtAP and one eigen-solve, nothing is assembled
    again (pitfall 6 of the cyclic notes: re-assembling per k is what makes tools slow).

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

    def _copies(self, m: int):
        """(diag(K..), diag(M..), perm, first row, local rows) for m copies, built once."""
        if m not in self._blocks:
            perm, first, local_rows = _layout(self.sector, m)
            self._blocks[m] = (_block_diagonal(self.K, self.sector, m, perm, local_rows),
                               _block_diagonal(self.M, self.sector, m, perm, local_rows), perm, first, local_rows)
        return self._blocks[m]

    def project(self, k: int) -> tuple[PETSc.Mat, PETSc.Mat, PETSc.Mat]:
        """(K_k, M_k, T_k) for harmonic index k: K_k = T_k^T diag(K, K) T_k and likewise M_k (one copy for k = 0 and
        N/2), with 1 / MASS_DIAGONAL on the eliminated slots' diagonal."""
        sector, pairs = self.sector, self.sector.cyclic
        k = pairs.check_k(k)
        m = pairs.n_copies(k)
        K2, M2, perm, first, local_rows = self._copies(m)
        n = sector.n_dofs
        T, kept = cyclic_projection(n, pairs, k)
        im, bs = sector.V.dofmap.index_map, sector.V.dofmap.index_map_bs
        g0, g1 = im.local_range[0] * bs, im.local_range[1] * bs
        mine = np.concatenate([c * n + np.arange(g0, g1) for c in range(m)])      # in layout order
        T_p = _petsc_from_rows(sector.comm, T[mine], perm, local_rows, m * n)
        eliminated = first + np.flatnonzero(~kept[mine])
        operators = []
        for A2, diag in ((K2, 1.0), (M2, MASS_DIAGONAL)):
            Ak = A2.PtAP(T_p)
            # the eliminated slots' empty rows get a diagonal: one merge of patterns (not one insertion per entry)
            D = PETSc.Mat().createAIJ(size=((local_rows, m * n), (local_rows, m * n)), nnz=1, comm=sector.comm)
            for r in eliminated:                                 # one face's slots, not the mesh
                D.setValue(int(r), int(r), diag)
            D.assemble()
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
        Kk, Mk, T = self.project(k)
        m = self.sector.cyclic.n_copies(k)
        omega, vecs = solve_eigenproblem(Kk, Mk, m * n_modes, sigma=sigma, prefix="cyclic_", initial=initial)
        a, b = [], []
        for x in vecs:
            fa, fb = sector_fields(self.sector, T, x, m)
            a.append(fa)
            b.append(fb)
        for A in (Kk, Mk, T):
            A.destroy()
        return CyclicModes(int(k), omega, a, b, vecs)

    def destroy(self) -> None:
        for K2, M2, *_ in self._blocks.values():
            K2.destroy()
            M2.destroy()
        self._blocks.clear()


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
