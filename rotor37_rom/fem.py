"""The dolfinx/PETSc/SLEPc adapter: the only module of rotor37_rom that touches them.

It turns a gmsh model into a :class:`Sector` (mesh, tags by name, function space, named DOF sets, communicator),
assembles K and M with the clamp applied, solves the clamped eigenproblem with SLEPc shift-invert, and provides the
full-order nonlinear static (Newton, exact tangent, load stepping) and implicit transient (Newmark) solvers that later
reduced models are checked against. Everything runs under MPI; the communicator always comes from the mesh.

Clamped DOFs are kept in the matrices as decoupled rows: K gets 1 on their diagonal and M gets 1e-14, so their
spurious eigenvalues sit at 1e14 (rad/s)^2, far above any physical mode, and M stays positive definite.
"""
from __future__ import annotations

import dataclasses
import logging
from pathlib import Path
from typing import Callable, Sequence

import numpy as np
import ufl
from dolfinx import fem
from dolfinx.io import gmshio
from dolfinx.fem import petsc as fem_petsc
from mpi4py import MPI
from petsc4py import PETSc

from rotor37_rom import forms
from rotor37_rom.forms import Material
from rotor37_rom.geometry import blade as blade_geometry
from rotor37_rom.geometry.tables import read_blade_table

__all__ = [
    "Sector",
    "SvkOperators",
    "ModalResult",
    "StaticResult",
    "TransientResult",
    "create_blade_sector",
    "create_sector_from_file",
    "create_sector_from_gmsh",
    "create_sector_from_mesh",
    "create_svk_operators",
    "assemble_stiffness",
    "assemble_mass",
    "solve_eigenproblem",
    "compute_clamped_modes",
    "solve_static",
    "solve_newmark",
    "assemble_scalar",
    "assemble_vector",
    "gather_dof_values",
]

LOG = logging.getLogger(__name__)
MASS_DIAGONAL = 1.0e-14
JIT_PARAMS = {"cffi_extra_compile_args": ["-O2", "-march=native"], "cffi_libraries": ["m"]}


@dataclasses.dataclass(frozen=True)
class Sector:
    """A meshed structure with named groups and DOF sets (a blade now; a disk sector with cyclic faces later).

    Attributes:
        mesh: dolfinx mesh (distributed over ``mesh.comm``).
        cell_tags, facet_tags: gmsh physical groups as dolfinx MeshTags.
        groups: group name -> tag (BladeGroup names, lower case).
        V: vector P``degree`` function space.
        material: the material.
        clamp_bc: homogeneous Dirichlet condition on the clamp facets.
        tip_nodes: (n_tip, 3) coordinates of the contact nodes, LE first (m), identical on all ranks.
        tip_dofs: (n_tip, 3) local (unblocked) DOF indices of the tip nodes on this rank, -1 where not owned here.
        cyclic_dofs: {'left': ..., 'right': ...} local DOF indices of cyclic faces (empty for a single blade).
        volume: CAD volume (m^3).
        source: where the geometry came from; preset: mesh preset name.
    """

    mesh: object
    cell_tags: object
    facet_tags: object
    groups: dict
    V: object
    material: Material
    clamp_bc: object
    tip_nodes: np.ndarray
    tip_dofs: np.ndarray
    cyclic_dofs: dict
    volume: float
    source: str
    preset: str

    @property
    def comm(self) -> MPI.Comm:
        return self.mesh.comm

    @property
    def n_dofs(self) -> int:
        """Global number of DOFs (clamped ones included)."""
        im = self.V.dofmap.index_map
        return im.size_global * self.V.dofmap.index_map_bs

    def facets(self, name: str) -> np.ndarray:
        """Local facet indices of a named group."""
        if name not in self.groups:
            raise ValueError(f"group {name!r} not in this sector; it has {sorted(self.groups)}")
        return self.facet_tags.find(self.groups[name])

    def total_mass(self) -> float:
        return assemble_scalar(self.material.rho * ufl.dx(domain=self.mesh), self.comm)


def _locate_point_dofs(V, points: np.ndarray, tol: float = 1e-9) -> np.ndarray:
    """(n, 3) owned local DOF indices of the vertices at ``points`` (-1 where not owned by this rank)."""
    bs = V.dofmap.index_map_bs
    n_owned = V.dofmap.index_map.size_local
    out = -np.ones((len(points), bs), dtype=np.int64)
    for k, p in enumerate(points):  # loop over a handful of contact nodes, not over DOFs
        blocks = fem.locate_dofs_geometrical(V, lambda x, p=p: np.linalg.norm(x.T - p, axis=1) < tol)
        blocks = blocks[blocks < n_owned]
        if blocks.size:
            out[k] = blocks[0] * bs + np.arange(bs)
    found = V.mesh.comm.allreduce((out[:, 0] >= 0).astype(int), op=MPI.SUM)
    if np.any(found != 1):
        missing = np.flatnonzero(found != 1)
        raise ValueError(f"tip nodes {missing.tolist()} are not vertices of the mesh (boundary nodes not on the mesh)")
    return out


def create_sector_from_gmsh(comm: MPI.Comm, model_info, material: Material, degree: int = 2,
                            preset: str = "") -> Sector:
    """Build a :class:`Sector` from the current gmsh model (alive on rank 0 only) and its builder report."""
    import gmsh

    names = {}
    if comm.rank == 0:
        names = {gmsh.model.getPhysicalName(d, t): t for d, t in gmsh.model.getPhysicalGroups()}
    names = comm.bcast(names, root=0)
    model_info = comm.bcast(model_info, root=0)
    mesh, cell_tags, facet_tags = gmshio.model_to_mesh(gmsh.model if comm.rank == 0 else None, comm, 0, gdim=3)
    return create_sector_from_mesh(mesh, cell_tags, facet_tags, names, material, degree,
                                   np.asarray(model_info.tip_nodes, dtype=float).reshape(-1, 3),
                                   float(model_info.volume), model_info.source, preset)


def create_sector_from_mesh(mesh, cell_tags, facet_tags, groups: dict, material: Material, degree: int = 2,
                            tip_nodes: np.ndarray | None = None, volume: float = float("nan"), source: str = "mesh",
                            preset: str = "") -> Sector:
    """A :class:`Sector` from a distributed dolfinx mesh whose facet tags hold a group named 'clamp'."""
    if not (1 <= degree <= 3):
        raise ValueError(f"degree must be 1, 2 or 3, got {degree}")
    comm = mesh.comm
    V = fem.VectorFunctionSpace(mesh, ("Lagrange", degree))
    if "clamp" not in groups:
        raise ValueError(f"the model of {source} has no 'clamp' group; it has {sorted(groups)}")
    clamp_facets = facet_tags.find(groups["clamp"])
    if comm.allreduce(clamp_facets.size, op=MPI.SUM) == 0:
        raise ValueError(f"the clamp group of {source} holds no facets")
    mesh.topology.create_connectivity(mesh.topology.dim - 1, mesh.topology.dim)
    clamp_dofs = fem.locate_dofs_topological(V, mesh.topology.dim - 1, clamp_facets)
    clamp_bc = fem.dirichletbc(np.zeros(3, dtype=PETSc.ScalarType), clamp_dofs, V)
    tip_nodes = np.zeros((0, 3)) if tip_nodes is None else np.asarray(tip_nodes, float).reshape(-1, 3)
    tip_dofs = _locate_point_dofs(V, tip_nodes) if len(tip_nodes) else np.zeros((0, 3), dtype=np.int64)
    return Sector(mesh=mesh, cell_tags=cell_tags, facet_tags=facet_tags, groups=dict(groups), V=V,
                  material=material, clamp_bc=clamp_bc, tip_nodes=tip_nodes, tip_dofs=tip_dofs, cyclic_dofs={},
                  volume=volume, source=source, preset=preset)


def create_blade_sector(comm: MPI.Comm = MPI.COMM_WORLD, table: str | Path | None = None, preset="coarse",
                        material: Material | None = None, degree: int = 2,
                        n_tip_nodes: int = blade_geometry.N_TIP_NODES, shorten: float = 0.0) -> Sector:
    """Mesh the rotor 37 blade with gmsh (rank 0) and distribute it.

    Args:
        comm: communicator.
        table: path of NASA Table IV for the exact loft; None for the built-in parametric blade.
        preset: mesh preset name ('ci', 'coarse', 'paper') or a geometry.blade.MeshPreset.
        material: defaults to the paper's maraging steel.
        degree: Lagrange degree of the displacement (2 = the paper's quadratic elements).
        n_tip_nodes: contact nodes along the tip camber line, LE and TE included.
        shorten: radial length removed at the tip (m), parametric blade only.
    """
    material = material or Material()
    preset_obj = blade_geometry.get_mesh_preset(preset)
    table_obj = read_blade_table(table) if table is not None else None
    info, error = None, None
    if comm.rank == 0:
        with blade_geometry.gmsh_session():
            try:
                info = blade_geometry.create_blade_model(table_obj, preset_obj, n_tip_nodes=n_tip_nodes,
                                                         shorten=shorten)
            except ValueError as exc:
                error = str(exc)
            except Exception as exc:  # gmsh's own failures: one line, naming the step
                error = f"gmsh failed to mesh the blade ({str(exc).splitlines()[0]})"
            error = comm.bcast(error, root=0)
            if error is None:
                return create_sector_from_gmsh(comm, info, material, degree, preset_obj.name)
    else:
        error = comm.bcast(None, root=0)
        if error is None:
            return create_sector_from_gmsh(comm, None, material, degree, preset_obj.name)
    raise ValueError(error)


def create_sector_from_file(path: str | Path, clamp, tip=None, comm: MPI.Comm = MPI.COMM_WORLD,
                            preset="coarse", material: Material | None = None, degree: int = 2,
                            scale: float = 1.0) -> Sector:
    """A user's blade from a STEP/BREP/MSH file (see geometry.blade.import_blade_model for clamp/tip)."""
    material = material or Material()
    error = None
    if comm.rank == 0:
        with blade_geometry.gmsh_session():
            try:
                info = blade_geometry.import_blade_model(path, clamp, tip, preset, scale)
            except ValueError as exc:
                error = str(exc)
            except Exception as exc:
                error = f"gmsh failed on {path} ({str(exc).splitlines()[0]})"
            error = comm.bcast(error, root=0)
            if error is None:
                return create_sector_from_gmsh(comm, info, material, degree, str(preset))
    else:
        error = comm.bcast(None, root=0)
        if error is None:
            return create_sector_from_gmsh(comm, None, material, degree, str(preset))
    raise ValueError(error)


@dataclasses.dataclass(frozen=True)
class SvkOperators:
    """Compiled SVK forms of a sector, evaluated at the state ``u`` (set ``u.x.array`` before assembling).

    Attributes:
        u: state Function; w1, w2, w3: direction Functions for the higher derivatives.
        f_int, g_nl: internal and nonlinear force 1-forms at u.
        tangent: exact tangent K_T(u) 2-form; stiffness: K; mass: M.
        d2: D^2 f_int(u)[w1, w2] 1-form; d3: D^3 f_int[w1, w2, w3] 1-form.
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


def create_svk_operators(sector: Sector, quadrature_degree: int | None = None) -> SvkOperators:
    """Compile the forms of :mod:`forms.svk` for ``sector`` with material constants as fem.Constant."""
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

    return SvkOperators(
        u=u, w1=w1, w2=w2, w3=w3,
        f_int=compile_(forms.internal_force(u, v, lmbda, mu, dx)),
        g_nl=compile_(forms.nonlinear_force(u, v, lmbda, mu, dx)),
        tangent=compile_(forms.tangent_stiffness(u, v, du, lmbda, mu, dx)),
        stiffness=compile_(forms.linear_stiffness(v, du, lmbda, mu, dx)),
        mass=compile_(forms.mass(v, du, rho, dx)),
        d2=compile_(forms.second_derivative(u, v, w1, w2, lmbda, mu, dx)),
        d3=compile_(forms.third_derivative(u, v, w1, w2, w3, lmbda, mu, dx)),
        constants={"lambda": lmbda, "mu": mu, "rho": rho},
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


def gather_dof_values(sector: Sector, values: np.ndarray, dofs: np.ndarray) -> np.ndarray:
    """Values at per-rank local DOF indices (-1 = not here), summed over ranks: identical on every rank."""
    dofs = np.asarray(dofs)
    out = np.zeros(dofs.shape + values.shape[1:], dtype=float)
    mask = dofs >= 0
    out[mask] = values[dofs[mask]]
    return sector.comm.allreduce(out, op=MPI.SUM)


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


def solve_eigenproblem(K: PETSc.Mat, M: PETSc.Mat, n_modes: int, sigma: float = 0.0, tol: float = 1e-12,
                       prefix: str = "modes_") -> tuple[np.ndarray, list]:
    """Lowest ``n_modes`` eigenpairs of K x = lambda M x by SLEPc Krylov-Schur with shift-invert (MUMPS LU).

    Returns:
        (omega, vectors): omega = sqrt(lambda) in rad/s ascending, vectors M-normalised (x^T M x = 1).
    """
    from slepc4py import SLEPc

    n_global = K.getSize()[0]
    if not (1 <= n_modes < n_global):
        raise ValueError(f"n_modes must be in [1, {n_global - 1}], got {n_modes}")
    eps = SLEPc.EPS().create(K.getComm())
    eps.setOptionsPrefix(prefix)
    eps.setOperators(K, M)
    eps.setProblemType(SLEPc.EPS.ProblemType.GHEP)
    eps.setType(SLEPc.EPS.Type.KRYLOVSCHUR)
    eps.setDimensions(n_modes, max(2 * n_modes, n_modes + 15))
    eps.setTolerances(tol, 500)
    eps.setWhichEigenpairs(SLEPc.EPS.Which.TARGET_MAGNITUDE)
    eps.setTarget(sigma)
    st = eps.getST()
    st.setType(SLEPc.ST.Type.SINVERT)
    st.setShift(sigma)
    ksp = st.getKSP()
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    ksp.getPC().setFactorSolverType("mumps")
    eps.setFromOptions()
    eps.solve()
    n_conv = eps.getConverged()
    if n_conv < n_modes:
        raise RuntimeError(f"SLEPc converged {n_conv} of {n_modes} eigenpairs")
    lams, vecs = [], []
    for i in range(n_conv):
        x = K.createVecRight()
        lam = eps.getEigenpair(i, x).real
        lams.append(lam)
        vecs.append(x)
    order = np.argsort(lams)[:n_modes]
    lam = np.array(lams)[order]
    if np.any(lam <= 0):
        raise ValueError("K is not positive definite on the free DOFs (non-positive eigenvalue): check the clamp")
    vecs = [vecs[i] for i in order]
    for x in vecs:  # M-normalise (SLEPc already does for GHEP; make it explicit)
        Mx = M.createVecLeft()
        M.mult(x, Mx)
        x.scale(1.0 / np.sqrt(x.dot(Mx)))
    eps.destroy()
    return np.sqrt(lam), vecs


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
    """Load factors, tip displacements (n_steps, n_tip, 3) and Newton iterations per step; u: final Function."""

    load_factors: np.ndarray
    tip_displacements: np.ndarray
    iterations: np.ndarray
    u: object


def solve_static(sector: Sector, force: Callable[[object], object] | PETSc.Vec | None = None,
                 prescribed: Sequence[tuple[np.ndarray, np.ndarray]] = (), n_steps: int = 10,
                 rtol: float = 1e-10, max_iterations: int = 25, ops: SvkOperators | None = None,
                 linear: bool = False) -> StaticResult:
    """Nonlinear static equilibrium f_int(u) = lambda f_ext by Newton with the exact tangent and load stepping.

    Args:
        sector: the structure (clamp applied).
        force: external load for lambda = 1: a PETSc vector (N) or a function v -> UFL 1-form (e.g. a traction).
        prescribed: displacement control: (local DOF indices, values at lambda = 1) pairs, imposed as lambda*values.
        n_steps: equal load increments (1..10000).
        rtol: Newton stops when ||r|| <= rtol * max(||lambda f_ext||, ||reaction||) (relative residual).
        linear: solve K u = lambda f (one factorisation) instead.
    """
    if not (1 <= n_steps <= 10000):
        raise ValueError(f"n_steps must be in [1, 10000], got {n_steps}")
    ops = ops or create_svk_operators(sector)
    V = sector.V
    u = ops.u
    u.x.array[:] = 0.0
    f_ext = None
    if isinstance(force, PETSc.Vec):
        f_ext = force
    elif force is not None:
        f_ext = assemble_vector(fem.form(force(ufl.TestFunction(V)), jit_params=JIT_PARAMS))
    dofs = np.concatenate([np.asarray(d, dtype=np.int64).ravel() for d, _ in prescribed]) if prescribed else \
        np.zeros(0, np.int64)
    values = np.concatenate([np.asarray(v, float).ravel() for _, v in prescribed]) if prescribed else np.zeros(0)
    if dofs.shape != values.shape:
        raise ValueError(f"prescribed: {dofs.size} DOFs but {values.size} values")
    owned = dofs >= 0  # per-rank local indices, -1 where the DOF lives on another rank
    dofs, values = dofs[owned], values[owned]
    bs = V.dofmap.index_map_bs
    n_owned = V.dofmap.index_map.size_local * bs
    if np.any(dofs >= n_owned):
        raise ValueError("prescribed: DOF indices must be owned local (unblocked) indices, as in Sector.tip_dofs")
    global_rows = (V.dofmap.index_map.local_range[0] * bs + dofs).astype(PETSc.IntType)
    bcs = [sector.clamp_bc]
    lambdas = np.linspace(0.0, 1.0, n_steps + 1)[1:]
    tips, its = [], []
    du = u.vector.duplicate()
    K_full = assemble_stiffness(sector, ops) if linear else None
    if linear:  # one factorisation of K with the prescribed rows and columns eliminated
        K_lin = K_full.copy()
        K_lin.zeroRowsColumns(global_rows, diag=1.0)
        ksp = _lu_solver(sector.comm, K_lin, "static_")
    lift, rhs, r = u.vector.duplicate(), u.vector.duplicate(), u.vector.duplicate()
    for lam in lambdas:
        for it in range(max_iterations + 1):
            # the prescribed increment still to apply (only non-zero on the first iteration of a step)
            lift.set(0.0)
            with u.vector.localForm() as local:
                lift.array[dofs] = lam * values - local.array[dofs]
            if linear:
                K_full.mult(u.vector, r)
            else:
                r = assemble_vector(ops.f_int)
            reaction = r.norm()
            load_norm = 0.0
            if f_ext is not None:
                r.axpy(-lam, f_ext)
                load_norm = abs(lam) * f_ext.norm()
            fem_petsc.set_bc(r, bcs, scale=0.0)
            r.array[dofs] = 0.0
            res, ref = r.norm(), max(load_norm, reaction, 1e-300)
            LOG.debug("lambda=%.4f it=%d |r|=%.3e ref=%.3e", lam, it, res, ref)
            if (res <= rtol * ref or (linear and it == 1)) and lift.norm() == 0.0:
                break
            if it == max_iterations:
                raise RuntimeError(f"Newton did not converge at load factor {lam:.4g} "
                                   f"(|r|/ref = {res / ref:.2e} after {it} iterations); use more n_steps")
            A = K_full
            if not linear:
                A = fem_petsc.assemble_matrix(ops.tangent, bcs=bcs, diagonal=1.0)
                A.assemble()
            # rhs = -r - A lift on the free rows, = lift on the prescribed rows (a lifted predictor: no spike)
            A.mult(lift, rhs)
            rhs.axpy(1.0, r)
            rhs.scale(-1.0)
            fem_petsc.set_bc(rhs, bcs, scale=0.0)
            rhs.array[dofs] = lift.array[dofs]
            if not linear:
                A.zeroRowsColumns(global_rows, diag=1.0)
                ksp = _lu_solver(sector.comm, A, "newton_")
            ksp.solve(rhs, du)
            u.vector.axpy(1.0, du)
            u.x.scatter_forward()
            if not linear:
                A.destroy()
                ksp.destroy()
        tips.append(gather_dof_values(sector, u.x.array, sector.tip_dofs))
        its.append(it)
    out = fem.Function(V, name="u")
    out.x.array[:] = u.x.array
    return StaticResult(load_factors=lambdas, tip_displacements=np.array(tips), iterations=np.array(its), u=out)


@dataclasses.dataclass(frozen=True)
class TransientResult:
    """Times (n+1,), monitored DOF values (n+1, n_monitor) and final displacement/velocity Functions."""

    t: np.ndarray
    monitored: np.ndarray
    u: object
    v: object
    energy: np.ndarray


def solve_newmark(sector: Sector, force_shape: PETSc.Vec, load: Callable[[float], float], dt: float,
                  n_steps: int, monitor_dofs: np.ndarray, nonlinear: bool = True, rayleigh=(0.0, 0.0),
                  beta: float = 0.25, gamma: float = 0.5, rtol: float = 1e-9, max_iterations: int = 20,
                  ops: SvkOperators | None = None) -> TransientResult:
    """Implicit Newmark integration of M a + C v + f_int(u) = load(t) f from rest (full-order reference).

    Args:
        force_shape: spatial load vector f (N).
        load: time law load(t) (dimensionless).
        dt: time step (s), > 0; n_steps: number of steps.
        monitor_dofs: per-rank local DOF indices (-1 = not here) recorded each step, e.g. ``sector.tip_dofs``.
        nonlinear: SVK internal force with Newton on the exact tangent; False: linear K u (one factorisation).
        rayleigh: (alpha, beta_K): C = alpha M + beta_K K.
        beta, gamma: Newmark parameters (default: average acceleration, unconditionally stable, no dissipation).
    Returns:
        TransientResult with energy (n+1,): kinetic + strain energy (linear: u^T K u / 2), for checks.
    """
    if not dt > 0:
        raise ValueError(f"dt must be > 0 s, got {dt}")
    if not (1 <= n_steps <= 10_000_000):
        raise ValueError(f"n_steps must be in [1, 1e7], got {n_steps}")
    if not (0.0 < beta <= 0.5 and 0.5 <= gamma <= 1.0):
        raise ValueError(f"Newmark needs 0 < beta <= 0.5 and 0.5 <= gamma <= 1, got beta={beta}, gamma={gamma}")
    ops = ops or create_svk_operators(sector)
    comm, bcs = sector.comm, [sector.clamp_bc]
    K, M = assemble_stiffness(sector, ops), assemble_mass(sector, ops)
    C = M.copy()
    C.scale(rayleigh[0])
    C.axpy(rayleigh[1], K)
    c_mass, c_damp = 1.0 / (beta * dt**2), gamma / (beta * dt)
    u = ops.u
    u.x.array[:] = 0.0
    un, vn, an = u.vector.copy(), u.vector.duplicate(), u.vector.duplicate()
    for w in (vn, an):
        w.set(0.0)
    # initial acceleration from rest: M a0 = f(0)
    rhs = force_shape.copy()
    rhs.scale(load(0.0))
    fem_petsc.set_bc(rhs, bcs, scale=0.0)
    ksp_m = _lu_solver(comm, M, "newmark_mass_")
    ksp_m.solve(rhs, an)
    ksp_m.destroy()
    if not nonlinear:
        A_lin = K.copy()
        A_lin.axpy(c_mass, M)
        A_lin.axpy(c_damp, C)
        ksp_lin = _lu_solver(comm, A_lin, "newmark_")
    t = np.arange(n_steps + 1) * dt
    monitored = [gather_dof_values(sector, u.x.array, monitor_dofs)]
    energies = [0.0]
    pred_a, pred_v, tmp, r, du = (u.vector.duplicate() for _ in range(5))
    for n in range(1, n_steps + 1):
        # predictors: a_{n+1} = c_mass (u - un) - pred_a, v_{n+1} = pred_v + gamma dt a_{n+1}
        pred_a.set(0.0)
        pred_a.axpy(c_mass * dt, vn)
        pred_a.axpy(1.0 / (2.0 * beta) - 1.0, an)
        pred_v.set(0.0)
        pred_v.axpy(1.0, vn)
        pred_v.axpy((1.0 - gamma) * dt, an)
        f_n = force_shape.copy()
        f_n.scale(load(t[n]))
        for it in range(max_iterations + 1):
            # a = c_mass (u - un) - pred_a ; v = pred_v + gamma dt a
            a_vec = u.vector.copy()
            a_vec.axpy(-1.0, un)
            a_vec.scale(c_mass)
            a_vec.axpy(-1.0, pred_a)
            v_vec = pred_v.copy()
            v_vec.axpy(gamma * dt, a_vec)
            if nonlinear:
                r = assemble_vector(ops.f_int)
            else:
                K.mult(u.vector, r)
            M.mult(a_vec, tmp)
            # residual scale: the largest of the force terms, so round-off in any of them cannot stall Newton
            ref = max(f_n.norm(), r.norm(), tmp.norm(), 1e-30)
            r.axpy(1.0, tmp)
            C.multAdd(v_vec, r, r)
            r.axpy(-1.0, f_n)
            fem_petsc.set_bc(r, bcs, scale=0.0)
            res = r.norm()
            if not nonlinear and it == 1:
                break
            if nonlinear and (res <= rtol * ref or (it > 0 and res < 1e-14)):
                break
            if it == max_iterations:
                raise RuntimeError(f"Newmark-Newton did not converge at step {n} (|r|/|f| = {res / ref:.2e})")
            if nonlinear:
                A = fem_petsc.assemble_matrix(ops.tangent, bcs=bcs, diagonal=1.0)
                A.assemble()
                A.axpy(c_mass, M)
                A.axpy(c_damp, C)
                ksp = _lu_solver(comm, A, "newmark_")
            else:
                ksp = ksp_lin
            r.scale(-1.0)
            ksp.solve(r, du)
            u.vector.axpy(1.0, du)
            u.x.scatter_forward()
            if nonlinear:
                ksp.destroy()
                A.destroy()
        un.array[:] = u.vector.array
        vn.array[:] = v_vec.array
        an.array[:] = a_vec.array
        monitored.append(gather_dof_values(sector, u.x.array, monitor_dofs))
        M.mult(vn, tmp)
        kinetic = 0.5 * vn.dot(tmp)
        K.mult(un, tmp)
        energies.append(kinetic + 0.5 * un.dot(tmp))
    v_out = fem.Function(sector.V, name="velocity")
    v_out.vector.array[:] = vn.array
    u_out = fem.Function(sector.V, name="u")
    u_out.x.array[:] = u.x.array
    return TransientResult(t=t, monitored=np.array(monitored), u=u_out, v=v_out, energy=np.array(energies))


# ---------------------------------------------------------------------------------------------------------------
# Reduction support: free-DOF operators, constraint and fixed-interface modes, exact modal-derivative right-hand
# sides, nonlinear forces of given fields and displacement gradients at quadrature points (all serial NumPy out).
# ---------------------------------------------------------------------------------------------------------------

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
    return petsc_to_scipy(A)


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


def solve_constraint_and_interface_modes(sector: Sector, boundary_dofs: np.ndarray, n_interface: int,
                                         ops: SvkOperators | None = None):
    """Craig-Bampton ingredients on the full DOF vector (eqs. 8-11), serial NumPy output.

    Constraint modes Psi: K u = 0 on the interior with u = e_j on boundary DOF j (one MUMPS factorisation of K_ii,
    reused for all boundary DOFs). Fixed-interface modes Theta: the r_c lowest modes of (K_ii, M_ii) from SLEPc
    shift-invert, M-normalised, zero on the boundary.

    Returns:
        (Psi, Theta, omega_c): (n_dofs, n_b), (n_dofs, r_c), (r_c,) rad/s; clamped DOFs are zero.
    """
    _require_serial(sector, "solve_constraint_and_interface_modes")
    ops = ops or create_svk_operators(sector)
    boundary_dofs = np.asarray(boundary_dofs, dtype=np.int64).ravel()
    n = sector.V.dofmap.index_map.size_local * sector.V.dofmap.index_map_bs
    clamped = sector.clamp_bc.dof_indices()[0]
    if boundary_dofs.size == 0 or boundary_dofs.min() < 0 or boundary_dofs.max() >= n:
        raise ValueError(f"boundary DOFs must be indices in [0, {n}) of DOFs on the mesh")
    if np.intersect1d(boundary_dofs, clamped).size:
        raise ValueError("boundary DOFs must not be clamped")
    if len(np.unique(boundary_dofs)) != boundary_dofs.size:
        raise ValueError("boundary DOFs contain duplicates")
    rows = boundary_dofs.astype(PETSc.IntType)
    K = assemble_stiffness(sector, ops)
    M = assemble_mass(sector, ops)
    K_fixed = K.copy()
    K_fixed.zeroRowsColumns(rows, diag=1.0)
    M_fixed = M.copy()
    M_fixed.zeroRowsColumns(rows, diag=MASS_DIAGONAL)
    n_free_interior = n - clamped.size - boundary_dofs.size
    if not (1 <= n_interface < n_free_interior):
        raise ValueError(f"r_c (fixed-interface modes) must be in [1, {n_free_interior - 1}], got {n_interface}")
    ksp = _lu_solver(sector.comm, K_fixed, "constraint_")
    Psi = np.zeros((n, boundary_dofs.size))
    e, rhs, x = K.createVecRight(), K.createVecLeft(), K.createVecRight()
    for j, dof in enumerate(boundary_dofs):  # a handful of right-hand sides, one factorisation
        e.set(0.0)
        e.array[dof] = 1.0
        K.mult(e, rhs)
        rhs.scale(-1.0)
        rhs.array[boundary_dofs] = 0.0
        rhs.array[dof] = 1.0
        rhs.array[clamped] = 0.0
        ksp.solve(rhs, x)
        Psi[:, j] = x.array
    ksp.destroy()
    omega, vecs = solve_eigenproblem(K_fixed, M_fixed, n_interface, prefix="interface_")
    Theta = np.column_stack([v.array for v in vecs])
    Theta[boundary_dofs] = 0.0
    for A in (K, M, K_fixed, M_fixed):
        A.destroy()
    return Psi, Theta, omega


def solve_clamped_static(sector: Sector, rhs: np.ndarray, ops: SvkOperators | None = None) -> np.ndarray:
    """Solve K x = b for many right-hand sides b (n_rhs, n_dofs) with the clamp (one MUMPS factorisation)."""
    _require_serial(sector, "solve_clamped_static")
    ops = ops or create_svk_operators(sector)
    K = assemble_stiffness(sector, ops)
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
    K.destroy()
    return out


# ---------------------------------------------------------------------------------------------------------------
# Stress recovery (issue: stress and visual results)
# ---------------------------------------------------------------------------------------------------------------
def displacement_function(sector: Sector, Phi: np.ndarray, q: np.ndarray, name: str = "displacement"):
    """u = Phi q as a dolfinx Function on the sector (serial: Phi holds all DOFs)."""
    _require_serial(sector, "displacement_function")
    Phi = np.asarray(Phi)
    q = np.asarray(q, float)
    if Phi.ndim != 2 or Phi.shape[0] != sector.V.dofmap.index_map.size_local * 3:
        raise ValueError(f"basis Phi has shape {Phi.shape}; the sector has "
                         f"{sector.V.dofmap.index_map.size_local * 3} DOFs (was it built on another mesh?)")
    if q.ndim != 1 or q.size != Phi.shape[1]:
        raise ValueError(f"reduced state q has shape {q.shape}; the basis has r = {Phi.shape[1]} columns")
    u = fem.Function(sector.V, name=name)
    u.x.array[:] = Phi @ q
    return u


def _stress_expression(sector: Sector, u, nonlinear: bool):
    lmbda, mu = sector.material.lame
    sigma = forms.cauchy_stress(u, lmbda, mu) if nonlinear else forms.linear_stress(u, lmbda, mu)
    return forms.von_mises(sigma)


def von_mises_function(sector: Sector, u, nonlinear: bool = True, degree: int = 1):
    """von Mises stress (Pa) of the displacement u interpolated into a DG space of the given degree (0 or 1)."""
    if degree not in (0, 1):
        raise ValueError(f"degree must be 0 or 1, got {degree}")
    W = fem.FunctionSpace(sector.mesh, ("DG", degree))
    expr = fem.Expression(_stress_expression(sector, u, nonlinear), W.element.interpolation_points(),
                          jit_params=JIT_PARAMS)
    out = fem.Function(W, name="von_mises")
    out.interpolate(expr)
    return out


def von_mises_at_quadrature(sector: Sector, u, nonlinear: bool = True, degree: int = 4) -> np.ndarray:
    """Direct UFL evaluation of von Mises at the quadrature points of every local cell, ordered as
    ``quadrature_gradients`` (points grouped by cell), for checks of the NumPy recovery."""
    import basix

    points, _ = basix.make_quadrature(basix.CellType.tetrahedron, degree)
    n_cells = sector.mesh.topology.index_map(3).size_local
    expr = fem.Expression(_stress_expression(sector, u, nonlinear), points, jit_params=JIT_PARAMS)
    return expr.eval(np.arange(n_cells, dtype=np.int32)).ravel()


def cell_midpoints(sector: Sector) -> np.ndarray:
    """Centroids (n_local_cells, 3) of the local cells (for locating stress maxima)."""
    from dolfinx import mesh as dmesh

    n_cells = sector.mesh.topology.index_map(3).size_local
    return dmesh.compute_midpoints(sector.mesh, 3, np.arange(n_cells, dtype=np.int32))


def cells_touching_points(sector: Sector, points: np.ndarray, tol: float = 1e-9) -> np.ndarray:
    """Local cells having one of ``points`` (n, 3) among their geometry nodes (e.g. the contact nodes, where point
    contact forces make the FE stress singular)."""
    x = sector.mesh.geometry.x
    n_cells = sector.mesh.topology.index_map(3).size_local
    dofmap = sector.mesh.geometry.dofmap.array
    geom = dofmap.reshape(-1, dofmap.size // sector.mesh.geometry.dofmap.num_nodes)[:n_cells]
    hit = np.zeros(len(x), bool)
    for p in np.asarray(points, float).reshape(-1, 3):
        hit |= np.linalg.norm(x - p, axis=1) < tol
    return np.nonzero(hit[geom].any(axis=1))[0]
