"""Full-order static (displacement control) and transient (GNL Newmark) solvers on the ci blade.

Small amplitudes: the SVK response differs from the linear one by a relative amount proportional to the amplitude
(quadratic terms), so halving the amplitude must halve the difference (ratio 2 +- 10 %) — the Taylor argument applied
to the solvers' outputs.
"""
import numpy as np
import ufl
from dolfinx import fem as dfem

from rotor37_rom import fem


def _tip_traction(sector, amplitude):
    v = ufl.TestFunction(sector.V)
    ds = ufl.Measure("ds", domain=sector.mesh, subdomain_data=sector.facet_tags)
    return fem.assemble_vector(dfem.form(ufl.inner(ufl.as_vector([0.0, amplitude, 0.0]), v)
                                         * ds(sector.groups["tip"])))


def test_force_control_tends_to_linear(ci_blade, ci_ops):
    diffs = []
    for amplitude in (4e6, 2e6):  # Pa on the tip face: tip deflection ~ 1 mm and 0.5 mm
        f = _tip_traction(ci_blade, amplitude)
        lin = fem.solve_static(ci_blade, force=f, n_steps=1, linear=True, ops=ci_ops)
        nl = fem.solve_static(ci_blade, force=f, n_steps=2, ops=ci_ops)
        assert nl.iterations.max() <= 6
        diffs.append(np.linalg.norm(nl.u.x.array - lin.u.x.array) / np.linalg.norm(lin.u.x.array))
    print("relative GNL - linear difference", diffs)
    assert 1e-4 < diffs[1] < 0.1
    assert 1.8 < diffs[0] / diffs[1] < 2.2, diffs


def test_displacement_control_reproduces_force_control(ci_blade, ci_ops):
    """Prescribing the tip-node displacements of a force-controlled equilibrium (same load) returns that
    equilibrium: the lifted Newton of displacement control converges to the same state."""
    f = _tip_traction(ci_blade, 4e6)
    u_f = fem.solve_static(ci_blade, force=f, n_steps=2, ops=ci_ops).u.x.array.copy()
    dofs = ci_blade.tip_dofs.ravel()
    nl = fem.solve_static(ci_blade, force=f, prescribed=[(dofs, u_f[dofs])], n_steps=2, ops=ci_ops)
    np.testing.assert_allclose(nl.u.x.array[dofs], u_f[dofs], atol=1e-15)
    assert np.linalg.norm(nl.u.x.array - u_f) <= 1e-8 * np.linalg.norm(u_f)
    lin = fem.solve_static(ci_blade, prescribed=[(dofs, u_f[dofs])], n_steps=1, linear=True, ops=ci_ops)
    np.testing.assert_allclose(lin.u.x.array[dofs], u_f[dofs], atol=1e-15)


def test_nonlinear_newmark_tends_to_linear(ci_blade, ci_ops):
    v = ufl.TestFunction(ci_blade.V)
    ds = ufl.Measure("ds", domain=ci_blade.mesh, subdomain_data=ci_blade.facet_tags)
    tip = ci_blade.groups["tip"]
    dt = 2 * np.pi / 5400.0 / 20
    diffs = []
    for amplitude in (2e5, 1e5):
        f = fem.assemble_vector(dfem.form(ufl.inner(ufl.as_vector([0.0, amplitude, 0.0]), v) * ds(tip)))
        args = (ci_blade, f, lambda t: 1.0, dt, 8, ci_blade.tip_dofs)
        lin = fem.solve_newmark(*args, nonlinear=False, ops=ci_ops)
        nl = fem.solve_newmark(*args, nonlinear=True, ops=ci_ops)
        diffs.append(np.abs(nl.monitored - lin.monitored).max() / np.abs(lin.monitored).max())
    assert 1e-6 < diffs[1] < 1e-2
    assert 1.8 < diffs[0] / diffs[1] < 2.2, diffs
