"""The dolfinx/PETSc/SLEPc adapter: the only package of rotor37_rom (plotting aside) that touches them.

It turns gmsh models into :class:`Sector` objects (mesh, tags by name, function space, named DOF sets,
communicator), assembles the SVK operators, solves eigenproblems with SLEPc shift-invert (also per nodal diameter of
a cyclic sector), and provides the full-order nonlinear static (Newton, exact tangent) and implicit transient
(Newmark) solvers that the reduced models are checked against. Everything runs under MPI unless a function says it
is serial; the communicator always comes from the mesh.

Modules: ``sector`` (building sectors), ``operators`` (forms and assembly), ``solvers`` (eigen, static, transient,
the factorisation and eigen-solver given to ``reduction.craig_bampton.craig_bampton``), ``fields`` (displacements
and stress on the mesh), ``cyclic`` (disk and plate sectors, face pairing, operators and modes per nodal diameter),
``periodic`` (the full-order transient of a disk under a nodal-diameter load on the sectors it repeats over),
``safe`` (SAFE diagram).
"""
# SLEPc initialises (and finalises at exit) collectively on PETSc's COMM_WORLD: importing it here makes every rank
# that imports this package do so, also when only rank 0 then solves eigenproblems on its own copy of a mesh (a rank
# 0 that alone initialised SLEPc waits for the others at exit forever)
from slepc4py import SLEPc  # noqa: F401

import logging as _logging


class _QuietCompiler(_logging.Filter):
    """dolfinx compiles its forms with cffi through distutils, which logs every compiler command at INFO on the root
    logger (a first run printed pages of gcc lines): its records are dropped; every other record passes."""

    def filter(self, record: _logging.LogRecord) -> bool:
        return "distutils" not in record.pathname.replace("\\", "/")


if not any(isinstance(f, _QuietCompiler) for f in _logging.getLogger().filters):
    _logging.getLogger().addFilter(_QuietCompiler())

from .cyclic import (CyclicModes, CyclicOperators, assemble_cyclic_operators, centrifugal_state, create_annular_sector,
                     create_disk_sector, create_ring_sector, cyclic_projector, rotating_cyclic_operators,
                     sector_fields, solve_cyclic_modes)
from .fields import (cell_midpoints, cell_vertices, cells_touching_points, displacement_function, root_junction,
                     von_mises_at_quadrature, von_mises_at_vertices, von_mises_function)
from .operators import (JIT_PARAMS, MASS_DIAGONAL, SvkOperators, assemble_coriolis, assemble_free_operators,
                        assemble_mass, assemble_scalar, assemble_spin_softening, assemble_stiffness, assemble_tangent,
                        assemble_tangent_scipy, assemble_vector,
                        create_svk_operators, evaluate_forces, evaluate_second_derivative, evaluate_strain_energy,
                        facet_centroid, strain_energy_form,
                        free_dofs, gather_dof_values, patch_load, petsc_to_scipy, quadrature_gradients,
                        scipy_to_petsc, tip_patch_interface)
from .periodic import (CasingContact, ContactOperators, NewmarkScheme, RepeatingNewmark, RepeatingSectorResult,
                       RepeatingSectors, SectorLoad, sector_harmonic_load, solve_repeating_newmark)
from .safe import BLADE_SHARE_DOMINATED, SafeDiagram, compute_safe_diagram, group_stiffness
from .sector import (MissingMaterial, Sector, build_on_rank0, clamp_cell_group, create_blade_sector,
                     create_sector_from_file,
                     create_sector_from_gmsh, create_sector_from_mesh, locate_cyclic_pairs, tip_node_names,
                     write_sector_mesh)
from .solvers import (ModalResult, StaticResult, compute_clamped_modes, mumps_solver, reduced_coriolis,
                     reduced_rotation_terms, rotating_modes, slepc_eigenpairs, solve_clamped_static,
                     shift_invert_solver, solve_eigenproblem, solve_static, static_compliance)

__all__ = [
    "Sector", "SvkOperators", "ModalResult", "StaticResult",
    "create_blade_sector", "create_sector_from_file", "MissingMaterial", "create_sector_from_gmsh",
    "create_sector_from_mesh",
    "tip_node_names", "create_svk_operators", "assemble_stiffness", "assemble_mass", "assemble_vector",
    "assemble_scalar", "gather_dof_values", "free_dofs", "petsc_to_scipy", "scipy_to_petsc",
    "assemble_free_operators", "evaluate_forces", "evaluate_second_derivative", "strain_energy_form",
    "evaluate_strain_energy", "assemble_tangent_scipy",
    "assemble_tangent", "assemble_spin_softening", "assemble_coriolis",
    "quadrature_gradients", "solve_eigenproblem", "compute_clamped_modes", "solve_static", "rotating_modes",
    "reduced_coriolis",
    "solve_clamped_static", "mumps_solver", "slepc_eigenpairs", "displacement_function", "von_mises_function",
    "von_mises_at_quadrature", "von_mises_at_vertices", "cell_midpoints", "cell_vertices", "cells_touching_points",
    "root_junction", "MASS_DIAGONAL", "JIT_PARAMS",
    "create_disk_sector", "create_annular_sector", "locate_cyclic_pairs", "assemble_cyclic_operators", "CyclicModes",
    "solve_cyclic_modes", "sector_fields", "clamp_cell_group", "build_on_rank0", "CyclicOperators",
    "RepeatingSectors", "RepeatingNewmark", "NewmarkScheme", "SectorLoad", "CasingContact", "solve_repeating_newmark",
    "sector_harmonic_load", "write_sector_mesh", "facet_centroid",
    "patch_load", "static_compliance", "tip_patch_interface", "create_ring_sector", "cyclic_projector",
    "centrifugal_state", "rotating_cyclic_operators", "reduced_rotation_terms", "RepeatingSectorResult",
    "ContactOperators", "SafeDiagram", "compute_safe_diagram", "group_stiffness", "BLADE_SHARE_DOMINATED",
    "shift_invert_solver",
]
