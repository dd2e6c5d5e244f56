"""SVK operators of a sector: compiled UFL forms, assembly of K, M, forces and higher derivatives, and the data
the reduced models are built from (free-DOF matrices as SciPy, displacement gradients at quadrature points).

Part of the dolfinx adapter (``rotor37_rom.fem``). Clamped DOFs are kept in the PETSc matrices as decoupled rows: K
gets 1 on their diagonal and M gets MASS_DIAGONAL = 1e-14, so their spurious eigenvalues sit at 1e14 (rad/s)^2, far
above any physical mode, and M stays positive definite.
"""
from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

import numpy as np
import ufl
from dolfinx import fem
from dolfinx.fem import petsc as fem_petsc
from mpi4py import MPI
from petsc4py import PETSc

from rotor37_rom import forms

if TYPE_CHECKING:
    from .sector import Sector

__all__ = ["SvkOperators", "create_svk_operators", "assemble_stiffness", "assemble_mass", "assemble_vector",
           "assemble_scalar", "facet_centroid", "patch_load", "tip_patch_interface", "gather_dof_values", "free_dofs",
           "petsc_to_scipy", "scipy_to_petsc", "assemble_free_operators", "evaluate_forces",
           "evaluate_second_derivative", "strain_energy_form", "evaluate_strain_energy", "assemble_tangent_scipy", "assemble_tangent", "assemble_spin_softening",
           "assemble_coriolis", "quadrature_gradients", "MASS_DIAGONAL", "JIT_PARAMS"]

MASS_DIAGONAL = 1.0e-14
JIT_PARAMS = {"cffi_extra_compile_args": ["-O2", "-march=native"], "cffi_libraries": ["m"]}


@dataclasses.dataclass(frozen=True)
class SvkOperators:
    """Compiled SVK forms of a sector, evaluated at the state ``u`` (set ``u.x.array`` before assembling).

    Attributes:
        u: state Function; w1, w2, w3: direction Functions for the higher derivatives.
        f_int, g_nl: internal and nonlinear force 1-forms at u.
        tangent: exact tangent K_T(u) 2-form; stiffness: K; mass: M.
        d2: D^2 f_int(u)[w1, w2] 1-form; d3: D^3 f_int[w1, w2, w3] 1-form.
        law: the hyperelastic law of f_int, g_nl and tangent ('svk', the paper's: f_int exactly cubic, d3
            constant; or 'neo-hookean', ``forms.HYPERELASTIC_LAWS``, for the full order: d2 and d3 None, as the
            reduced models that need them take SVK's alone); stiffness and mass are the same for both.
    """

    u: object
    w1: object
    w2: object
    w3: object
    f_int: object
    g_nl: object
    tangent: object
    stiffness: object
    mass: object
    d2: object
    d3: object
    constants: dict
    law: str = "svk"
    quadrature_degree: int | None = None


def create_svk_operators(sector: Sector, quadrature_degree: int | None = None, law: str = "svk") -> SvkOperators:
    """Compile the forms of the hyperelastic ``law`` (:mod:`forms.svk` by default; 'neo-hookean':
    :mod:`forms.neo_hookean`, one ValueError for a law not known) for ``sector`` with material constants as
    fem.Constant."""
    forms_of = forms.hyperelastic_law(law)
    V, mesh = sector.V, sector.mesh
    lmbda_value, mu_value = sector.material.lame
    lmbda = fem.Constant(mesh, PETSc.ScalarType(lmbda_value))
    mu = fem.Constant(mesh, PETSc.ScalarType(mu_value))
    rho = fem.Constant(mesh, PETSc.ScalarType(sector.material.rho))
    u, w1, w2, w3 = (fem.Function(V, name=n) for n in ("u", "w1", "w2", "w3"))
    v, du = ufl.TestFunction(V), ufl.TrialFunction(V)
    metadata = {} if quadrature_degree is None else {"quadrature_degree": quadrature_degree}
    dx = ufl.dx(domain=mesh, metadata=metadata)

    def compile_(form):
        return fem.form(form, jit_params=JIT_PARAMS)

    d2 = d3 = None                 # another law's: the full order's alone, which needs no higher derivative
    if law == "svk":
        d2 = compile_(forms.second_derivative(u, v, w1, w2, lmbda, mu, dx))
        d3 = compile_(forms.third_derivative(u, v, w1, w2, w3, lmbda, mu, dx))
    return SvkOperators(
        u=u, w1=w1, w2=w2, w3=w3,
        f_int=compile_(forms_of.internal_force(u, v, lmbda, mu, dx)),
        g_nl=compile_(forms_of.nonlinear_force(u, v, lmbda, mu, dx)),
        tangent=compile_(forms_of.tangent_stiffness(u, v, du, lmbda, mu, dx)),
        stiffness=compile_(forms.linear_stiffness(v, du, lmbda, mu, dx)),
        mass=compile_(forms.mass(v, du, rho, dx)),
        d2=d2, d3=d3,
        constants={"lambda": lmbda, "mu": mu, "rho": rho}, law=law, quadrature_degree=quadrature_degree,
    )


def _assemble_matrix(form, bcs, diagonal: float) -> PETSc.Mat:
    A = fem_petsc.assemble_matrix(form, bcs=bcs, diagonal=diagonal)
    A.assemble()
    return A


def assemble_stiffness(sector: Sector, ops: SvkOperators | None = None, clamped: bool = True) -> PETSc.Mat:
    """Linear stiffness K (N/m) with the clamp: clamped rows/columns zero, 1 on the diagonal."""
    ops = ops or create_svk_operators(sector)
    return _assemble_matrix(ops.stiffness, [sector.clamp_bc] if clamped else [], 1.0)


def assemble_mass(sector: Sector, ops: SvkOperators | None = None, clamped: bool = True) -> PETSc.Mat:
    """Consistent mass M (kg) with the clamp: clamped rows/columns zero, MASS_DIAGONAL on the diagonal."""
    ops = ops or create_svk_operators(sector)
    return _assemble_matrix(ops.mass, [sector.clamp_bc] if clamped else [], MASS_DIAGONAL)


def assemble_spin_softening(sector: Sector, ops: SvkOperators | None = None) -> PETSc.Mat:
    """M_P (kg): the mass of the motions normal to the machine axis e_z (``forms.spin_softening``), clamped rows and
    columns zero (0 on their diagonal, so that K - spin^2 M_P keeps the clamp's identity rows)."""
    ops = ops or create_svk_operators(sector)
    v, du = ufl.TestFunction(sector.V), ufl.TrialFunction(sector.V)
    form = fem.form(forms.spin_softening(v, du, ops.constants["rho"]), jit_params=JIT_PARAMS)
    return _assemble_matrix(form, [sector.clamp_bc], 0.0)


def assemble_coriolis(sector: Sector, ops: SvkOperators | None = None) -> PETSc.Mat:
    """G_1 (kg): the Coriolis matrix per unit spin about e_z (``forms.coriolis``; skew-symmetric), clamped rows and
    columns zero."""
    ops = ops or create_svk_operators(sector)
    v, du = ufl.TestFunction(sector.V), ufl.TrialFunction(sector.V)
    form = fem.form(forms.coriolis(v, du, ops.constants["rho"]), jit_params=JIT_PARAMS)
    return _assemble_matrix(form, [sector.clamp_bc], 0.0)


def assemble_tangent(sector: Sector, u: np.ndarray, ops: SvkOperators | None = None, spin: float = 0.0
                     ) -> PETSc.Mat:
    """K_T(u) - spin^2 M_P (N/m), clamped: the exact tangent at the state u (local DOF values with ghosts, as
    ``Function.x.array``) of the structure turning at ``spin`` rad/s about e_z, e.g. at its centrifugal equilibrium
    (``solve_static(spin=...)``): the prestressed stiffness, whose inverse is the rotating structure's static
    compliance (``static_compliance(K=...)``). Sets ``ops.u`` to u."""
    ops = ops or create_svk_operators(sector)
    ops.u.x.array[:] = u
    ops.u.x.scatter_forward()
    A = _assemble_matrix(ops.tangent, [sector.clamp_bc], 1.0)
    if spin:
        M_P = assemble_spin_softening(sector, ops)
        A.axpy(-spin**2, M_P, structure=PETSc.Mat.Structure.SAME_NONZERO_PATTERN)
        M_P.destroy()
    return A


def assemble_vector(form) -> PETSc.Vec:
    """Assemble a 1-form into a ghost-updated PETSc vector."""
    b = fem_petsc.assemble_vector(form)
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    return b


def assemble_scalar(form, comm: MPI.Comm | None = None) -> float:
    """Assemble a UFL 0-form and sum over ranks."""
    compiled = fem.form(form, jit_params=JIT_PARAMS)
    comm = comm or compiled.mesh.comm
    return comm.allreduce(fem.assemble_scalar(compiled), op=MPI.SUM)


def facet_centroid(sector: Sector, group: str) -> np.ndarray:
    """(3,) area-weighted centroid (m) of a named facet group (e.g. 'clamp', 'tip')."""
    if group not in sector.groups:
        raise ValueError(f"group {group!r} not in this sector; it has {sorted(sector.groups)}")
    ds = ufl.Measure("ds", domain=sector.mesh, subdomain_data=sector.facet_tags)(sector.groups[group])
    x = ufl.SpatialCoordinate(sector.mesh)
    area = assemble_scalar(ufl.as_ufl(1.0) * ds, sector.comm)
    if not area > 0:
        raise ValueError(f"group {group!r} has no facets")
    return np.array([assemble_scalar(x[i] * ds, sector.comm) for i in range(3)]) / area


def patch_load(sector: Sector, center: np.ndarray, radius: float, component: int = 2) -> np.ndarray:
    """Consistent nodal forces (n_dofs,) of a uniform traction along e_component over the boundary facets whose
    midpoints lie within ``radius`` (m) of ``center``, scaled to a unit resultant: the point load's replacement where
    a point force on a 3-D continuum has no finite limit (a force of F N is F times this vector). Serial."""
    from dolfinx import mesh as dmesh

    _require_serial(sector, "patch_load")
    if component not in (0, 1, 2):
        raise ValueError(f"component must be 0, 1 or 2 (x, y, z), got {component}")
    if not (np.isfinite(radius) and radius > 0):
        raise ValueError(f"radius must be > 0 m, got {radius}")
    msh = sector.mesh
    fdim = msh.topology.dim - 1
    msh.topology.create_connectivity(fdim, msh.topology.dim)
    facets = dmesh.exterior_facet_indices(msh.topology)
    near = facets[np.linalg.norm(dmesh.compute_midpoints(msh, fdim, facets) - np.asarray(center), axis=1) < radius]
    if near.size == 0:
        raise ValueError(f"radius must reach a boundary facet: none has its midpoint within {radius} m of {center}")
    return _facet_traction(sector, near, component)


def _facet_traction(sector: Sector, facets: np.ndarray, component: int) -> np.ndarray:
    """Consistent nodal forces (n_dofs,) of a uniform traction along e_component of unit resultant over ``facets``."""
    from dolfinx import mesh as dmesh

    msh = sector.mesh
    fdim = msh.topology.dim - 1
    tags = dmesh.meshtags(msh, fdim, np.sort(facets).astype(np.int32), np.ones(facets.size, dtype=np.int32))
    ds = ufl.Measure("ds", domain=msh, subdomain_data=tags)(1)
    area = assemble_scalar(ufl.as_ufl(1.0) * ds, sector.comm)
    b = assemble_vector(fem.form(ufl.TestFunction(sector.V)[component] * ds, jit_params=JIT_PARAMS))
    n = sector.V.dofmap.index_map.size_local * sector.V.dofmap.index_map_bs
    return b.array[:n].copy() / area


def tip_patch_interface(sector: Sector, radius: float, max_tilt_deg: float = 45.0):
    """The contact patches' interface C (3 n_tip, n_dofs), SciPy CSR, rows in the order of ``tip_dofs.ravel()``
    (node-major, x y z): row (k, c) is the consistent nodal load of a unit traction along e_c spread uniformly over
    the tip facets within ``radius`` (m) of contact node k, i.e. C u is each patch's area-mean displacement and
    C^T lambda the patch tractions of resultant lambda (RBE3-like: the reference point keeps the node's position).
    Tip facets: exterior facets whose midpoint lies within ``radius`` of the node and whose normal is within
    ``max_tilt_deg`` of the radial direction there (the tip face, not the pressure or suction side). Serial."""
    import scipy.sparse as sp
    from dolfinx import cpp as _cpp
    from dolfinx import mesh as dmesh

    _require_serial(sector, "tip_patch_interface")
    if not (np.isfinite(radius) and radius > 0):
        raise ValueError(f"radius must be > 0 m, got {radius}")
    if not 0 < max_tilt_deg < 90:
        raise ValueError(f"max_tilt_deg must be in (0, 90), got {max_tilt_deg}")
    if len(sector.tip_nodes) == 0:
        raise ValueError("the sector has no contact nodes (tip_nodes is empty)")
    msh = sector.mesh
    fdim = msh.topology.dim - 1
    msh.topology.create_connectivity(fdim, msh.topology.dim)
    facets = dmesh.exterior_facet_indices(msh.topology)
    mid = dmesh.compute_midpoints(msh, fdim, facets)
    normal = _cpp.mesh.cell_normals(getattr(msh, "_mesh", msh), fdim,   # the C++ mesh (a wrapper here)
                                     facets.astype(np.int32))
    bs = sector.V.dofmap.index_map_bs
    if bs != 3:
        raise ValueError(f"tip_patch_interface needs a 3-component displacement space, got block size {bs}")
    rows = []
    for k, node in enumerate(np.asarray(sector.tip_nodes)):
        radial = np.array([node[0], node[1], 0.0]) / np.hypot(node[0], node[1])
        near = facets[(np.linalg.norm(mid - node, axis=1) < radius)
                      & (np.abs(normal @ radial) >= np.cos(np.radians(max_tilt_deg)))]
        if near.size == 0:
            raise ValueError(f"radius must reach a tip facet of node {sector.tip_names[k]}: none within {radius} m")
        # the three components carry the same scalar weights: assemble e_x's once, copy it to the y and z slots
        weights = _facet_traction(sector, near, 0)[0::bs]
        for c in range(3):
            row = np.zeros(weights.size * bs)
            row[c::bs] = weights
            rows.append(row)
    C = sp.csr_matrix(np.array(rows))
    C.eliminate_zeros()
    return C


def gather_dof_values(sector: Sector, values: np.ndarray, dofs: np.ndarray) -> np.ndarray:
    """Values at per-rank local DOF indices (-1 = not here), summed over ranks: identical on every rank."""
    dofs = np.asarray(dofs)
    out = np.zeros(dofs.shape + values.shape[1:], dtype=float)
    mask = dofs >= 0
    out[mask] = values[dofs[mask]]
    return sector.comm.allreduce(out, op=MPI.SUM)


def _require_serial(sector: Sector, what: str) -> None:
    if sector.comm.size > 1:
        raise ValueError(f"{what} works on one process (the reduced model is built serially); got "
                         f"{sector.comm.size} ranks")


def free_dofs(sector: Sector) -> np.ndarray:
    """Sorted local (unblocked) indices of the DOFs not on the clamp (serial)."""
    _require_serial(sector, "free_dofs")
    bs = sector.V.dofmap.index_map_bs
    n = sector.V.dofmap.index_map.size_local * bs
    clamped = np.zeros(n, dtype=bool)
    clamped[sector.clamp_bc.dof_indices()[0]] = True
    return np.flatnonzero(~clamped)


def petsc_to_scipy(A: PETSc.Mat):
    """A serial PETSc AIJ matrix as scipy CSR (copy)."""
    import scipy.sparse as sp

    indptr, indices, data = A.getValuesCSR()
    return sp.csr_matrix((data.copy(), indices.copy(), indptr.copy()), shape=A.getSize())


def scipy_to_petsc(A, comm=MPI.COMM_SELF) -> PETSc.Mat:
    """A SciPy sparse matrix as a serial PETSc AIJ matrix (copy)."""
    A = A.tocsr()
    A.sort_indices()
    out = PETSc.Mat().createAIJ(size=A.shape, csr=(A.indptr.astype(PETSc.IntType), A.indices.astype(PETSc.IntType),
                                                   A.data.astype(PETSc.ScalarType)), comm=comm)
    out.assemble()
    return out


def assemble_free_operators(sector: Sector, ops: SvkOperators | None = None):
    """(K, M, free): linear stiffness and mass restricted to the free DOFs (scipy CSR, serial) and their indices."""
    ops = ops or create_svk_operators(sector)
    free = free_dofs(sector)
    K = petsc_to_scipy(assemble_stiffness(sector, ops, clamped=False))[free][:, free]
    M = petsc_to_scipy(assemble_mass(sector, ops, clamped=False))[free][:, free]
    return K.tocsr(), M.tocsr(), free


def evaluate_forces(sector: Sector, ops: SvkOperators, fields: np.ndarray, which: str = "g_nl") -> np.ndarray:
    """Internal ('f_int') or nonlinear ('g_nl') force vectors of full displacement fields (n_fields, n_dofs)."""
    _require_serial(sector, "evaluate_forces")
    form = {"g_nl": ops.g_nl, "f_int": ops.f_int}[which]
    fields = np.atleast_2d(fields)
    out = np.empty_like(fields)
    for k, u in enumerate(fields):  # one FE assembly per field (loop over fields, not DOFs)
        ops.u.x.array[:] = u
        out[k] = assemble_vector(form).getArray(readonly=True)
    ops.u.x.array[:] = 0.0
    return out


def strain_energy_form(sector: Sector, ops: SvkOperators):
    """The compiled strain energy (J) of ``ops``' law at ``ops.u``, at the quadrature of its forces: the potential of
    its internal force, f_int = dE/du."""
    metadata = {} if ops.quadrature_degree is None else {"quadrature_degree": ops.quadrature_degree}
    dx = ufl.dx(domain=sector.mesh, metadata=metadata)
    energy = forms.hyperelastic_law(ops.law).strain_energy(ops.u, ops.constants["lambda"], ops.constants["mu"], dx)
    return fem.form(energy, jit_params=JIT_PARAMS)


def evaluate_strain_energy(sector: Sector, ops: SvkOperators, form, u: np.ndarray) -> float:
    """The strain energy (J) of the sector's displacement field u (n_dofs,), ``form`` from ``strain_energy_form``."""
    _require_serial(sector, "evaluate_strain_energy")
    ops.u.x.array[:] = u
    value = float(fem.assemble_scalar(form))
    ops.u.x.array[:] = 0.0
    return value


def evaluate_second_derivative(sector: Sector, ops: SvkOperators, w1: np.ndarray, w2: np.ndarray,
                               u: np.ndarray | None = None) -> np.ndarray:
    """D^2 f_int(u)[w1, w2] (full vector); at u = 0 the exact modal-derivative right-hand side of eq. (17)."""
    _require_serial(sector, "evaluate_second_derivative")
    ops.u.x.array[:] = 0.0 if u is None else u
    ops.w1.x.array[:] = w1
    ops.w2.x.array[:] = w2
    out = assemble_vector(ops.d2).getArray(readonly=True).copy()
    ops.u.x.array[:] = 0.0
    return out


def assemble_tangent_scipy(sector: Sector, ops: SvkOperators, u: np.ndarray):
    """Exact tangent K_T(u) on all DOFs (scipy CSR, no clamp) for the finite-difference MD variant (eq. 19)."""
    ops.u.x.array[:] = u
    A = fem_petsc.assemble_matrix(ops.tangent)
    A.assemble()
    ops.u.x.array[:] = 0.0
    out = petsc_to_scipy(A)
    A.destroy()                  # petsc4py keeps an unreferenced Mat (~11 MB on the ci blade): one per Newton refresh
    return out


def quadrature_gradients(sector: Sector, fields: np.ndarray, degree: int = 4):
    """Displacement gradients of fields at the quadrature points of every cell.

    Args:
        fields: (r, n_dofs) displacement fields (e.g. the reduction basis, transposed).
        degree: quadrature degree (4 integrates every SVK force term exactly for P2 on affine tetrahedra,
            and is what UFL estimates for the forms of create_svk_operators).
    Returns:
        (H, w, cells): H (n_points, r, 3, 3) with H[p, i] = grad(phi_i) at point p, w (n_points,) the physical
        quadrature weights (m^3), cells (n_points,) the cell of each point (points are grouped by cell).
    """
    import basix

    _require_serial(sector, "quadrature_gradients")
    mesh = sector.mesh
    points, ref_weights = basix.make_quadrature(basix.CellType.tetrahedron, degree)
    n_cells = mesh.topology.index_map(3).size_local
    cells = np.arange(n_cells, dtype=np.int32)
    u = fem.Function(sector.V)
    grad_expr = fem.Expression(ufl.grad(u), points, jit_params=JIT_PARAMS)
    det_expr = fem.Expression(abs(ufl.JacobianDeterminant(mesh)), points, jit_params=JIT_PARAMS)
    fields = np.atleast_2d(fields)
    n_pts = n_cells * len(ref_weights)
    H = np.empty((n_pts, len(fields), 3, 3))
    for i, field in enumerate(fields):  # one compiled evaluation per basis vector
        u.x.array[:] = field
        H[:, i] = grad_expr.eval(cells).reshape(n_pts, 3, 3)
    w = (det_expr.eval(cells).reshape(n_cells, -1) * ref_weights).ravel()
    return H, w, np.repeat(cells, len(ref_weights))
