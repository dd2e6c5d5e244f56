"""Craig-Bampton + modal derivatives + reduced cubic forces on the ci blade (identity and convergence checks)."""

import numpy as np
import pytest

from rotor37_rom import fem
from rotor37_rom.builder import ReductionConfig, build_reduced_model, compute_modal_derivatives, training_states
from rotor37_rom.ecsw import state_errors, train_ecsw
from rotor37_rom.nonlinear_forces import QuadratureForces, compute_polynomial_forces
from rotor37_rom.reduction import (CRITERIA, CraigBamptonBasis, load_reduced_model, save_reduced_model,
                                   select_pairs, selection_weights)
from rotor37_rom.step import identify_step


@pytest.fixture(scope="module")
def rom(ci_blade, ci_ops):
    """r_b = 24, r_c = 4, r_md = 6 (r = 34) with exact intrusive tensors."""
    return build_reduced_model(ci_blade, ReductionConfig(r_c=4, r_md=6, forces="intrusive"), ops=ci_ops)


@pytest.fixture(scope="module")
def cb_parts(ci_blade, ci_ops):
    return fem.solve_constraint_and_interface_modes(ci_blade, ci_blade.tip_dofs.ravel(), 15, ci_ops)


def test_rayleigh_ritz_bounds_and_convergence(ci_blade, ci_ops, cb_parts):
    """Craig-Bampton frequencies bound the full ones from above and converge as r_c grows."""
    Psi, Theta, _ = cb_parts
    K, M, free = fem.assemble_free_operators(ci_blade, ci_ops)
    exact = fem.compute_clamped_modes(ci_blade, 6, ci_ops).omega
    errors = []
    for r_c in (2, 5, 10, 15):
        Phi = np.hstack([Psi, Theta[:, :r_c]])[free]
        lam = np.sort(np.linalg.eigvalsh(np.linalg.solve(np.linalg.cholesky(Phi.T @ (M @ Phi)),
                                                          np.linalg.solve(np.linalg.cholesky(Phi.T @ (M @ Phi)),
                                                                          Phi.T @ (K @ Phi)).T)))
        omega = np.sqrt(lam[:6])
        assert np.all(omega >= exact * (1 - 1e-9))
        errors.append((omega - exact) / exact)
    errors = np.array(errors)
    assert np.all(np.diff(errors, axis=0) <= 1e-12), errors
    assert errors[-1, :3].max() < 1e-3


def test_constraint_modes_are_static_responses(ci_blade, ci_ops, cb_parts):
    Psi = cb_parts[0]
    dofs = ci_blade.tip_dofs.ravel()
    for j in (0, 13, 23):
        values = np.zeros(dofs.size)
        values[j] = 1.0
        u = fem.solve_static(ci_blade, prescribed=[(dofs, values)], n_steps=1, linear=True, ops=ci_ops).u.x.array
        assert np.linalg.norm(u - Psi[:, j]) <= 1e-10 * np.linalg.norm(u)


def test_intrusive_forces_equal_projection(ci_blade, ci_ops, rom):
    model, _ = rom
    rng = np.random.default_rng(3)
    Phi = model.Phi
    scale = 1e-3 / np.abs(Phi).max(axis=0)
    Q = rng.standard_normal((model.r, 4)) * scale[:, None]
    direct = Phi.T @ fem.evaluate_forces(ci_blade, ci_ops, (Phi @ Q).T).T
    reduced = model.forces.evaluate(Q)
    assert np.linalg.norm(reduced - direct) <= 1e-10 * np.linalg.norm(direct)
    # and its Jacobian is the exact derivative (central difference of a cubic: error O(h^2) -> tiny)
    q = Q[:, 0]
    J = model.forces.jacobian(q)
    h = 1e-3 * scale
    Jfd = np.column_stack([(model.forces.evaluate(q + h[k] * np.eye(model.r)[k])
                            - model.forces.evaluate(q - h[k] * np.eye(model.r)[k]))[:, 0] / (2 * h[k])
                           for k in range(model.r)])
    assert np.abs(J - Jfd).max() <= 1e-6 * np.abs(J).max()
    # the tensor-free quadrature forces (batched, component planes) and their Jacobian are the same
    H, w, _ = fem.quadrature_gradients(ci_blade, Phi.T)
    qp = QuadratureForces(H, w, *ci_blade.material.lame)
    assert np.linalg.norm(qp.evaluate(Q) - direct) <= 1e-10 * np.linalg.norm(direct)
    assert np.linalg.norm(qp.evaluate(Q, linear=True) - model.K @ Q) <= 1e-10 * np.linalg.norm(model.K @ Q)
    assert np.linalg.norm(qp.evaluate(Q, chunk=2 * H.shape[0]) - direct) <= 1e-10 * np.linalg.norm(direct)
    J_qp = qp.jacobian(q)
    assert np.abs(J_qp - J).max() <= 1e-9 * np.abs(J).max()


def test_step_matches_intrusive_and_its_amplitude_dependence(ci_blade, ci_ops, rom):
    """STEP on a 6-vector sub-basis: SVK is exactly cubic, so STEP has no truncation error; its error is round-off
    amplified as the enforced amplitude shrinks (~ eps |K q| / |g|, growing like amplitude^-2 and ^-3)."""
    model, _ = rom
    Phi = model.Phi[:, [0, 12, 23, 24, 27, 30]]
    H, w, _ = fem.quadrature_gradients(ci_blade, Phi.T)
    exact = compute_polynomial_forces(QuadratureForces(H, w, *ci_blade.material.lame))

    def g(Q):
        return Phi.T @ fem.evaluate_forces(ci_blade, ci_ops, (Phi @ Q).T).T

    errors = {}
    for amp in (1e-7, 1e-5, 1e-3):
        est = identify_step(g, amp / np.abs(Phi).max(axis=0))
        errors[amp] = max(np.abs(est.A - exact.A).max() / np.abs(exact.A).max(),
                          np.abs(est.B - exact.B).max() / np.abs(exact.B).max())
    print("STEP relative error vs amplitude", errors)
    assert errors[1e-3] <= 1e-6
    assert errors[1e-7] > errors[1e-5] > errors[1e-3]


def test_finite_difference_md_converge_linearly(ci_blade, ci_ops, cb_parts):
    """Eq. (19) vs the exact eq. (17): K_T is quadratic in u for SVK, so the one-sided difference has an error
    exactly proportional to the step (rate 1) until round-off."""
    Psi, Theta, omega = cb_parts
    basis = CraigBamptonBasis(Psi, Theta[:, :3], omega[:3], ci_blade.tip_dofs.ravel())
    pairs = np.array([[0, 0], [5, 24], [24, 25]])
    exact = compute_modal_derivatives(ci_blade, ci_ops, basis, pairs, "exact")
    errs = []
    for step in (1e-4, 1e-5, 1e-6):
        fd = compute_modal_derivatives(ci_blade, ci_ops, basis, pairs, "fd", fd_step=step)
        errs.append(np.linalg.norm(fd - exact) / np.linalg.norm(exact))
    rates = np.log10(np.array(errs[:-1]) / np.array(errs[1:]))
    print("FD modal derivative errors", errs, "rates", rates)
    assert np.all(np.abs(rates - 1.0) < 0.05)


def test_ecsw_held_out_accuracy(ci_blade, ci_ops):
    model, report = build_reduced_model(ci_blade, ReductionConfig(r_c=4, r_md=6, forces="ecsw", ecsw_tol=1e-3),
                                        ops=ci_ops)
    Q = training_states(*report["linear_operators"], report["pairs"], report["md_scale"], 24, 20,
                        amplitudes=(2e-3,), seed=11)
    exact, hyper = report["ecsw_exact"].evaluate(Q), model.forces.evaluate(Q)
    err = np.linalg.norm(hyper - exact, axis=0) / np.linalg.norm(exact, axis=0)
    n_cells = ci_blade.mesh.topology.index_map(3).size_local
    print(f"ECSW: {report['ecsw_cells']} of {n_cells} cells, held-out max error {err.max():.1e}")
    assert err.max() <= 1e-2
    assert report["ecsw_cells"] < 0.1 * n_cells
    # single quadrature points instead of whole cells: same states and tolerance, fewer points to evaluate
    exact = report["ecsw_exact"]
    Q_train = training_states(*report["linear_operators"], report["pairs"], report["md_scale"], 24, 80)
    points = train_ecsw(exact, np.arange(exact.w.size), Q_train, tol=1e-3, level="point")
    err_p = state_errors(exact, points.forces, Q)
    print(f"points: {points.n_points} (cells: {model.forces.w.size} points), held-out max error {err_p.max():.1e}")
    assert points.training_error <= 1e-3 and err_p.max() <= 1e-2
    assert points.n_points < model.forces.w.size and np.all(points.forces.w > 0)


def test_selection_weights():
    rng = np.random.default_rng(0)
    t = np.linspace(0.0, 1e-3, 201)
    q = rng.standard_normal((5, 1)) * np.sin(2e4 * t)[None, :]
    Phi = rng.standard_normal((30, 5))
    for criterion in CRITERIA:
        if criterion == "SMVW":
            continue
        W = selection_weights(criterion, q, t, Phi)
        assert np.allclose(W, W.T) and np.all(W >= 0)
    W = selection_weights("MI2a", q, t)
    np.testing.assert_allclose(np.diag(W), np.trapz(q**2, t), rtol=1e-12)
    pairs = select_pairs(W, 4)
    vals = W[pairs[:, 0], pairs[:, 1]]
    assert np.all(np.diff(vals) <= 0) and vals[0] == W[np.triu_indices(5)].max()


def test_c_kernel_equals_numpy_stress_and_forces():
    """The fused C kernel of the nonlinear first Piola-Kirchhoff stress (svk_kernel) against the NumPy path: the same
    IEEE operations in another order, so they agree to a few ulps of the largest term (float64: 1e-13 relative,
    float32: 2e-6, i.e. ~16 ulps of 2**-23 ~ 1.2e-7, the sums having up to 9 terms of like size); the force through
    evaluate likewise. Where a C compiler exists the kernel must build: a silent fallback would cost 1.6x per step."""
    import os
    import shutil

    from rotor37_rom.svk_kernel import pk_nonlinear_kernel

    if os.environ.get("ROTOR37_C_KERNEL") == "0":
        pytest.skip("ROTOR37_C_KERNEL=0: the C kernel is switched off")
    if shutil.which("cc") is None and shutil.which("gcc") is None:
        pytest.skip("no C compiler: the NumPy path is used")
    rng = np.random.default_rng(5)
    n, r, P = 37, 7, 5
    H = rng.standard_normal((n, r, 3, 3))
    forces = QuadratureForces(H, rng.random(n), 1.1e11, 4.4e10)
    Q = rng.standard_normal((r, P)) * 2e-3                     # displacement gradients ~1e-2, as in a tip rub
    for precision, dtype, rtol in (("double", np.float64, 1e-13), ("single", np.float32, 2e-6)):
        assert pk_nonlinear_kernel(dtype) is not None
        f = forces.with_precision(precision)
        G = (f._planes[0] @ Q.astype(dtype)).reshape(3, 3, n, P)
        fast, ref = f._first_pk_nonlinear(G), f._first_pk_nonlinear_numpy(G)
        assert fast.dtype == ref.dtype == dtype
        assert np.abs(fast - ref).max() <= rtol * np.abs(ref).max()
        g = f.evaluate(Q)
        g_ref = f._planes[1].astype(float) @ ref.reshape(9 * n, P).astype(float)
        assert np.abs(g - g_ref).max() <= 10 * rtol * np.abs(g_ref).max()
    with pytest.raises(ValueError, match="C-contiguous"):
        pk_nonlinear_kernel(np.float64)(G.transpose(1, 0, 2, 3).astype(float), np.empty((3, 3, n, P)), 1.0, 1.0)


def test_trajectory_states_hold_out_other_instants():
    """Training instants: n_per_run spread after the first tenth plus the n_largest of largest boundary motion;
    held-out instants are other ones (never a training column); NaN instants (a blow-up) are dropped."""
    from rotor37_rom.ecsw import trajectory_states

    rng = np.random.default_rng(3)
    runs = [rng.standard_normal((6, 120)) * np.linspace(0.1, 1.0, 120), rng.standard_normal((6, 40))]
    runs[1][:, 30:] = np.nan
    train, held = trajectory_states(runs, r_b=2, n_per_run=10, n_largest=3, n_held=25)
    cols = lambda Q: {tuple(c) for c in Q.T}                              # noqa: E731
    assert not cols(train) & cols(held)
    n1 = trajectory_states([runs[1]], r_b=2, n_per_run=10, n_largest=3)[0].shape[1]
    assert held.shape[1] == 25 + (30 - n1)                                # run 1 has only 30 - n1 other instants
    first = runs[0][:, :12]                                               # first tenth: only if among the largest
    amp = np.abs(runs[0][:2]).max(axis=0)
    largest = set(np.argsort(amp)[::-1][:3].tolist())
    assert all((k in largest) == (tuple(first[:, k]) in cols(train)) for k in range(12))
    assert np.isfinite(train).all() and np.isfinite(held).all()
    with pytest.raises(ValueError, match="no finite"):
        trajectory_states([np.full((6, 5), np.nan)], r_b=2)


def test_save_load_and_refusals(rom, tmp_path):
    model, _ = rom
    path = save_reduced_model(model, tmp_path / "rom.npz")
    back = load_reduced_model(path, expected_key=model.key)
    np.testing.assert_array_equal(back.K, model.K)
    np.testing.assert_array_equal(back.forces.B, model.forces.B)
    with pytest.raises(ValueError, match="stale"):
        load_reduced_model(path, expected_key="0" * 24)
    bad = tmp_path / "bad.npz"
    bad.write_bytes(path.read_bytes()[:1000])
    with pytest.raises(ValueError, match="corrupted"):
        load_reduced_model(bad)


def test_bad_reduction_input(ci_blade, ci_ops):
    with pytest.raises(ValueError, match="not vertices of the mesh"):
        fem._locate_point_dofs(ci_blade.V, np.array([[0.0, 0.0, 0.0]]))
    n = ci_blade.V.dofmap.index_map.size_local * 3
    with pytest.raises(ValueError, match="boundary DOFs"):
        fem.solve_constraint_and_interface_modes(ci_blade, np.array([n + 5]), 3, ci_ops)
    with pytest.raises(ValueError, match="r_c"):
        fem.solve_constraint_and_interface_modes(ci_blade, ci_blade.tip_dofs.ravel(), 10**7, ci_ops)
    with pytest.raises(ValueError, match="r_md"):
        build_reduced_model(ci_blade, ReductionConfig(r_c=2, r_md=10**4, forces="none"), ops=ci_ops)
    with pytest.raises(ValueError, match="criterion"):
        ReductionConfig(criterion="best")
    from rotor37_rom.builder import _check_operators

    with pytest.raises(ValueError, match="not symmetric"):
        _check_operators(np.array([[2.0, 1.0], [0.0, 2.0]]), np.eye(2))
    with pytest.raises(ValueError, match="positive definite"):
        _check_operators(np.diag([1.0, -1.0]), np.eye(2))
