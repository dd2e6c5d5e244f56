"""Craig-Bampton + modal derivatives + reduced cubic forces on the ci blade (identity and convergence checks).

Round-off tolerances are derived from u = 1.1e-16 (unit round-off), the cancellation among the terms compared and,
for linear solves, backward errors and the smallest eigenvalue of K; each assertion says which.
"""

import json

import os

import numpy as np
import pytest
import scipy.linalg
import scipy.sparse.linalg

from rotor37_rom import fem
from rotor37_rom.reduction.builder import (ReductionConfig, build_reduced_model, cached_model,
    compute_modal_derivatives, training_states)
from rotor37_rom.forces.cubature import state_errors, train_ecsw
from rotor37_rom.forces.tensors import QuadratureForces, compute_polynomial_forces
from rotor37_rom.npz import load_npz, save_json, save_npz
from rotor37_rom.reduction.craig_bampton import (CRITERIA, CraigBamptonBasis, craig_bampton,
    fixed_interface_correction, interface_transform, select_pairs, selection_weights)
from rotor37_rom.model.reduced import load_reduced_model, save_reduced_model, saved_model_key
from rotor37_rom.forces.step import identify_step

U = np.finfo(float).eps / 2  # unit round-off of float64


@pytest.fixture(scope="module")
def rom(ci_blade, ci_ops):
    """r_b = 24, r_c = 4, r_md = 6 (r = 34) with exact intrusive tensors."""
    return build_reduced_model(ci_blade, ReductionConfig(r_c=4, r_md=6, forces="intrusive"), ops=ci_ops)


@pytest.fixture(scope="module")
def free_operators(ci_blade, ci_ops):
    """(K, M, free) on the DOFs that are not clamped, and the smallest eigenvalue of K there (Euclidean, N/m)."""
    K, M, free = fem.assemble_free_operators(ci_blade, ci_ops)
    lam_min = scipy.sparse.linalg.eigsh(K.tocsc(), 1, sigma=0, which="LM", return_eigenvectors=False)[0]
    return K, M, free, lam_min


@pytest.fixture(scope="module")
def cb_parts(ci_blade, free_operators):
    """Constraint modes of the 24 tip DOFs and 15 fixed-interface modes on the full DOF vector (as the builder)."""
    K, M, free, _ = free_operators
    dofs = ci_blade.tip_dofs.ravel()
    Psi_f, Theta_f, omega = craig_bampton(K, M, np.searchsorted(free, dofs), 15, solve=fem.mumps_solver,
                                          eigensolve=fem.slepc_eigenpairs)
    n = ci_blade.V.dofmap.index_map.size_local * ci_blade.V.dofmap.index_map_bs
    Psi, Theta = np.zeros((n, Psi_f.shape[1])), np.zeros((n, Theta_f.shape[1]))
    Psi[free], Theta[free] = Psi_f, Theta_f
    return Psi, Theta, omega


def test_craig_bampton_on_patch_means_is_the_constrained_reduction():
    """Boundary coordinates that are patch means (rows of C) instead of DOFs, on a spring chain clamped at one end
    (80 DOFs, random stiffnesses and masses, two tent-weighted patches of 5 and 7 DOFs), against dense algebra:
    C Psi = I and C Theta = 0; Psi = K^-1 C^T (C K^-1 C^T)^-1 (the field of least strain energy with C u = e_j);
    omega_c^2 are the eigenvalues of K, M on the null space of C, and interlace the unconstrained ones
    (lambda_i <= lambda_i^C <= lambda_(i + 2): Courant-Fischer for a rank-2 constraint); the fixed-interface
    correction leaves C zeta = 0. With unit rows C = the DOF selection it is the index path. Tolerances: a backward
    stable solve gives a relative error <= c n u cond(K) (cond(K) ~ 7e3 here), c = 10."""
    import scipy.sparse as sp

    rng = np.random.default_rng(0)
    n = 80
    k, m = 1 + rng.random(n + 1), 1 + rng.random(n)
    K = sp.diags([k[:-1] + k[1:], -k[1:-1], -k[1:-1]], [0, 1, -1]).tocsr()
    M = sp.diags(m).tocsr()
    rows = []
    for center, width in ((20, 5), (60, 7)):
        idx = np.arange(center - width // 2, center + width // 2 + 1)
        weights = 1 - np.abs(idx - center) / (width / 2 + 1)
        row = np.zeros(n)
        row[idx] = weights / weights.sum()
        rows.append(row)
    Cd = np.array(rows)
    C = sp.csr_matrix(Cd)
    Kd, Md = K.toarray(), M.toarray()
    tol = 10 * n * U * np.linalg.cond(Kd)
    Psi, Theta, omega = craig_bampton(K, M, C, 6)
    assert np.abs(Cd @ Psi - np.eye(2)).max() <= tol and np.abs(Cd @ Theta).max() <= tol
    KinvCt = np.linalg.solve(Kd, Cd.T)
    reference = KinvCt @ np.linalg.inv(Cd @ KinvCt)
    assert np.abs(Psi - reference).max() <= tol * np.abs(reference).max()
    Z = scipy.linalg.null_space(Cd)
    lam_c = scipy.linalg.eigh(Z.T @ Kd @ Z, Z.T @ Md @ Z, eigvals_only=True)[:6]
    lam = scipy.linalg.eigh(Kd, Md, eigvals_only=True)
    assert omega ** 2 == pytest.approx(lam_c, rel=tol)
    assert np.all(lam[:6] <= lam_c * (1 + tol)) and np.all(lam_c <= lam[2:8] * (1 + tol))
    assert np.abs(Theta.T @ Md @ Theta - np.eye(6)).max() <= tol
    zeta = fixed_interface_correction(rng.standard_normal((n, 3)), Psi, np.zeros(0, dtype=int), C)
    assert np.abs(Cd @ zeta).max() <= tol * np.abs(zeta).max()
    T, masters = interface_transform(C)
    assert np.abs(Cd @ T.toarray() - np.eye(n)[masters]).max() <= 4 * U * np.abs(T.toarray()).max()
    selection = sp.csr_matrix(np.eye(n)[[20, 60]])
    for a, b in zip(craig_bampton(K, M, selection, 6), craig_bampton(K, M, np.array([20, 60]), 6)):
        assert np.abs(a - b).max() <= tol * np.abs(b).max()
    with pytest.raises(ValueError, match="no column of its own"):
        interface_transform(sp.csr_matrix(np.vstack([Cd[0], 2 * Cd[0]])))


def test_rayleigh_ritz_bounds_and_convergence(ci_blade, ci_ops, cb_parts, free_operators):
    """Craig-Bampton frequencies bound the full ones from above and converge as r_c grows.

    The subspaces are nested, so in exact arithmetic omega_i(r_c) >= omega_i and decreases with r_c. Computed:
    the dense symmetric-definite solve (LAPACK sygvd, after a diagonal scaling that leaves the eigenvalues alone)
    has |d lambda_i| <= u |K^| |M^-1| (the LAPACK error bound, ^: scaled matrices), i.e. a relative slack
    u |K^| |M^-1| / lambda_i on lambda, half of it on omega (computed: 5e-10 for 1B at r_c = 15, 1e-11 for the
    sixth mode); SLEPc's reference adds <= 1e-12 (its residual tolerance; for a symmetric pencil the eigenvalue error
    is <= the relative residual). Nothing else rounds: the reduced operators are symmetrised.
    The r_c = 15 model's 1B/1T/2B are within 0.1 %: the accuracy the contact models (r_c = 15) rely on; measured
    0.004 / 0.03 / 0.04 %, reproducible to ~1e-10, so the bound is about the basis, not the machine."""
    Psi, Theta, _ = cb_parts
    K, M, free, _ = free_operators
    exact = fem.compute_clamped_modes(ci_blade, 6, ci_ops).omega
    errors, slacks = [], []
    for r_c in (2, 5, 10, 15):
        Phi = np.hstack([Psi, Theta[:, :r_c]])[free]
        Kr, Mr = Phi.T @ (K @ Phi), Phi.T @ (M @ Phi)
        d = 1.0 / np.sqrt(np.diag(Mr))
        Kr, Mr = [0.5 * (A + A.T) * d[:, None] * d[None, :] for A in (Kr, Mr)]
        lam = scipy.linalg.eigh(Kr, Mr, eigvals_only=True)[:6]
        bound = U * np.linalg.norm(Kr, 2) / np.linalg.eigvalsh(Mr)[0]
        slack = 0.5 * bound / lam + 1e-12
        omega = np.sqrt(lam)
        assert np.all(omega >= exact * (1 - slack)), (omega / exact - 1, slack)
        errors.append((omega - exact) / exact)
        slacks.append(slack)
    errors, slacks = np.array(errors), np.array(slacks)
    print("relative errors (rows r_c = 2, 5, 10, 15)\n", errors, "\nslacks\n", slacks)
    assert np.all(np.diff(errors, axis=0) <= slacks[1:] + slacks[:-1]), errors
    assert errors[-1, :3].max() < 1e-3


def test_constraint_modes_are_static_responses(ci_blade, ci_ops, cb_parts, free_operators):
    """Psi_j is the static response to a unit displacement of boundary DOF j (the others held): the same linear
    system as fem.solve_static's displacement control, solved another way (SciPy-side MUMPS on the free operator vs
    PETSc with eliminated rows). Both must be backward stable (residual <= 100 u |K| |x|, in the infinity norm), and
    they then differ by K_ii^-1 (r_1 - r_2): |du| <= (|r_1| + |r_2|) / lambda_min(K), lambda_min(K_ii) >=
    lambda_min(K) by interlacing (computed, 200 N/m). Measured: backward errors ~3e-17, |du| / |u| ~1e-11 against a
    bound ~6e-9 (the residuals do not line up with the softest mode)."""
    Psi = cb_parts[0]
    K, _, free, lam_min = free_operators
    dofs = ci_blade.tip_dofs.ravel()
    interior = np.setdiff1d(np.arange(free.size), np.searchsorted(free, dofs))
    norm_K = scipy.sparse.linalg.norm(K, np.inf)
    for j in (0, 13, 23):
        values = np.zeros(dofs.size)
        values[j] = 1.0
        u = fem.solve_static(ci_blade, prescribed=[(dofs, values)], n_steps=1, linear=True, ops=ci_ops).u.x.array
        residuals = []
        for x in (u[free], Psi[free, j]):
            r = (K @ x)[interior]
            eta = np.abs(r).max() / (norm_K * np.abs(x).max())
            assert eta <= 100 * U, eta
            residuals.append(np.linalg.norm(r))
        diff = np.linalg.norm(u - Psi[:, j])
        print(f"constraint mode {j}: |du| / |u| = {diff / np.linalg.norm(u):.1e}, bound "
              f"{sum(residuals) / lam_min / np.linalg.norm(u):.1e}")
        assert diff <= sum(residuals) / lam_min


def test_contact_patches_make_the_boundary_coordinates_patch_means(ci_blade, ci_ops, free_operators, rom):
    """ReductionConfig.contact_patch (issue #23: the contact force spread over the tip, RBE3-like), ci blade, 3 mm
    patches, r_c = 4, r_MD = 6:
    - q's boundary entries are the patches' mean displacements: C Phi = [I 0] (C = fem.tip_patch_interface). C Psi
      and C Theta only carry the transform's round-off (C T = the master rows exactly but for a few u |C| |T| per
      entry); the modal derivatives zeta = xi - Psi C xi also that of the cancellation, bounded by |Psi| |C xi|,
      i.e. the boundary part a point-contact derivative would have (< 1e3 |zeta| on this mesh).
    - A static load spread as patch tractions, f = C^T g, is reproduced exactly (K^-1 C^T lies in span Psi): the
      two solves differ by round-off, <= 10 u |K| / lambda_min(K) relatively.
    - The frequencies are Rayleigh-Ritz upper bounds of the clamped blade's.
    - The point-contact model's cache key is unchanged (contact_patch absent from its metadata)."""
    K, M, free, lam_min = free_operators
    model, _ = build_reduced_model(ci_blade, ReductionConfig(r_c=4, r_md=6, forces="none", contact_patch=3e-3),
                                   ops=ci_ops)
    C = fem.tip_patch_interface(ci_blade, 3e-3)
    Phi = model.Phi
    CPhi = np.asarray(C @ Phi)
    scale = np.abs(C).sum(axis=1).max() * np.abs(Phi).max(axis=0)       # |C| |Phi_j| per column
    assert np.abs(CPhi[:, :24] - np.eye(24)).max() <= 100 * U * scale[:24].max()
    assert np.all(np.abs(CPhi[:, 24:28]).max(axis=0) <= 100 * U * scale[24:28])
    assert np.all(np.abs(CPhi[:, 28:]).max(axis=0) <= 1e3 * 100 * U * scale[28:])
    assert model.nodes.names == ci_blade.tip_names and model.sizes == {"r_b": 24, "r_c": 4, "r_md": 6}
    g = np.zeros(24)
    g[2], g[10], g[21] = 400.0, -150.0, 80.0                         # N on LE (z), tip3 (x), TE (x)
    f = np.asarray(C.T @ g).ravel()
    u = np.zeros(Phi.shape[0])
    u[free] = scipy.sparse.linalg.spsolve(K.tocsc(), f[free])
    u_rom = Phi @ np.linalg.solve(model.K, Phi.T @ f)
    bound = 10 * U * scipy.sparse.linalg.norm(K, 1) / lam_min
    print(f"patch load: |u_rom - u| / |u| = {np.linalg.norm(u_rom - u) / np.linalg.norm(u):.1e}, bound {bound:.1e}")
    assert np.linalg.norm(u_rom - u) <= bound * np.linalg.norm(u)
    exact = fem.compute_clamped_modes(ci_blade, 3, ci_ops).omega
    d = 1.0 / np.sqrt(np.diag(model.M))                  # the slack of the Rayleigh-Ritz test above
    Kr, Mr = [A * d[:, None] * d[None, :] for A in (model.K, model.M)]
    lam = scipy.linalg.eigh(Kr, Mr, eigvals_only=True)[:3]
    slack = 0.5 * U * np.linalg.norm(Kr, 2) / np.linalg.eigvalsh(Mr)[0] / lam + 1e-12
    assert np.all(np.sqrt(lam) >= exact * (1 - slack)), (np.sqrt(lam) / exact - 1, slack)
    assert "contact_patch" in model.metadata["config"] and "contact_patch" not in rom[0].metadata["config"]


def test_intrusive_forces_equal_projection(ci_blade, ci_ops, rom):
    """The reduced cubic forces (exact tensors, and tensor-free quadrature) are the projected FE forces.

    Same polynomial, other operation order: u times the cancellation among the summed terms times the summation
    depth. The tensors sum r^2 + r^3 ~ 4e4 products per entry, with |A||q|^2 + |B||q|^3 ~ 17 |g| on these states:
    worst case u x 17 x 4e4 = 8e-11, random-sign rounding u x 17 x sqrt(4e4) ~ 4e-13; the FE and quadrature forces
    are cell sums of ~1e5 point values without cancellation (|f_int| ~ |g|). Measured <= 1e-15; 1e-10 asserted.
    Linear part: K Q is ~1e3x smaller than the point contributions it sums (the rigid-body-like cancellation of
    stiffness rows), ~1e-13 (measured 2e-13)."""
    model, _ = rom
    rng = np.random.default_rng(3)
    Phi = model.Phi
    scale = 1e-3 / np.abs(Phi).max(axis=0)
    Q = rng.standard_normal((model.r, 4)) * scale[:, None]
    direct = Phi.T @ fem.evaluate_forces(ci_blade, ci_ops, (Phi @ Q).T).T
    reduced = model.forces.evaluate(Q)
    assert np.linalg.norm(reduced - direct) <= 1e-10 * np.linalg.norm(direct)
    # its Jacobian against central differences with h_k = 1e-3 scale_k: exact on the quadratic part, the cubic
    # part leaves h^2 B ~ (h / q)^2 / 3 ~ 3e-7 of |J| (measured 1e-7), round-off u |q| / h ~ 1e-13
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
    assert np.abs(J_qp - J).max() <= 1e-9 * np.abs(J).max()                 # measured 2e-15
    # batched over states (the shooting's tangent, the balance's samples): the same Jacobians, the tensors' as two
    # GEMMs over gathered tensors (other summation order: the 1e-10 bound above)
    for force in (model.forces, qp):
        batch = force.jacobians(Q)
        single = np.stack([force.jacobian(x) for x in Q.T])
        assert batch.shape == (Q.shape[1], model.r, model.r)
        assert np.abs(batch - single).max() <= 1e-10 * np.abs(single).max()
    # B~ filled in column chunks (the memory bound of large bases): chunks of 1 and 1000 entries per row give the
    # same numbers as one chunk (each entry is the same six gathered terms summed in the same order)
    one = compute_polynomial_forces(qp)
    for chunk in (model.r, 1000 * model.r):
        chunked = compute_polynomial_forces(qp, chunk_elements=chunk)
        assert np.array_equal(chunked.A, one.A) and np.array_equal(chunked.B, one.B)
    assert np.linalg.norm(one.evaluate(Q) - direct) <= 1e-10 * np.linalg.norm(direct)


def test_step_matches_intrusive_and_its_amplitude_dependence(ci_blade, ci_ops, rom, free_operators):
    """STEP on a 6-vector sub-basis: SVK is exactly cubic, so STEP has no truncation error; its error is round-off
    amplified as the enforced amplitude shrinks.

    Estimate, computed here: the FE force rounds the Green strain (F^T F - I) / 2 to an absolute u whatever the
    displacement, so each evaluation carries dg_i ~ u |K phi_i| / |grad phi_i| (the force of a unit strain in the
    shape of vector i); STEP divides it by s_i^2 (quadratic A) and s_i^3 (cubic B), s_i the enforced amplitude:
    e_A ~ max_i dg_i / (s_i^2 max|A|) and e_B ~ max_i dg_i / (s_i^3 max|B|), growing like amplitude^-2 and ^-3.
    Asserted: error <= 100 (e_A + e_B) + 100 u (quadrature sums and the contractions; measured 6-12x the estimate
    where it dominates, ~40 u at 1e-3 where the rest of the arithmetic does), so at 1 mm STEP equals the exact
    tensors to <= 1e-6 on any machine."""
    model, _ = rom
    K, _, free, _ = free_operators
    sub = [0, 12, 23, 24, 27, 30]
    Phi = model.Phi[:, sub]
    H, w, _ = fem.quadrature_gradients(ci_blade, Phi.T)
    exact = compute_polynomial_forces(QuadratureForces(H, w, *ci_blade.material.lame))
    K_sub = Phi[free].T @ (K @ Phi[free])
    dg = U * np.abs(K_sub).max(axis=0) / np.abs(H).reshape(H.shape[0], H.shape[1], -1).max(axis=(0, 2))

    def g(Q):
        return Phi.T @ fem.evaluate_forces(ci_blade, ci_ops, (Phi @ Q).T).T

    errors, estimates = {}, {}
    for amp in (1e-7, 1e-5, 1e-3):
        s = amp / np.abs(Phi).max(axis=0)
        est = identify_step(g, s)
        errors[amp] = max(np.abs(est.A - exact.A).max() / np.abs(exact.A).max(),
                          np.abs(est.B - exact.B).max() / np.abs(exact.B).max())
        estimates[amp] = np.max(dg / s**2) / np.abs(exact.A).max() + np.max(dg / s**3) / np.abs(exact.B).max()
    print("STEP relative error vs amplitude", errors, "estimate", estimates)
    for amp in errors:
        assert errors[amp] <= 100 * estimates[amp] + 100 * U
    assert errors[1e-3] <= 1e-6
    assert errors[1e-7] > errors[1e-5] > errors[1e-3]
    # too large an amplitude (docs/choosing-a-model.md, gallery): no truncation error for an exactly cubic force, but
    # the quadratic tensor is then the small part of g(s) ~ B s^3, so its round-off grows like u |B| s / |A|, linearly
    # with the amplitude (measured 2.8e-15 at 1 cm, 2.7e-12 at 10 m; 10 asked for a growth of 1000)
    large = {}
    for amp in (1e-2, 10.0):
        est = identify_step(g, amp / np.abs(Phi).max(axis=0))
        large[amp] = np.abs(est.A - exact.A).max() / np.abs(exact.A).max()
    print("STEP quadratic tensor error at 1 cm and 10 m:", large)
    assert large[10.0] > 10 * large[1e-2]


def test_finite_difference_md_converge_linearly(ci_blade, ci_ops, cb_parts):
    """Eq. (19) vs the exact eq. (17): K_T is quadratic in u for SVK, so the one-sided difference has an error
    exactly proportional to the step (rate 1) until round-off.

    Round-off: the difference of two assembled tangents keeps ~u |K| / |K_T - K| ~ 1e-10 of itself (strain 1e-6),
    and its product with phi_j cancels ~1e3x: ~1e-7 of the smallest FD error (0.03 at the 1e-6 step), which moves
    the rate by ~1e-7 (measured 6e-7); 0.05 leaves > 1e4."""
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
    """ECSW (cells) and empirical cubature (points) trained to ecsw_tol = 1e-3 on 80 states, checked on 20 others.

    The training stops at |G xi - b| <= tol |b| with each state's block normalised to a unit total force, so
    |b| = sqrt(80) and every training state is reproduced within tol sqrt(80) = 0.9e-2 (derived, any machine). The
    held-out states are of the same family (another seed of random combinations of the same 12 linear modes, lifted
    with the same modal derivatives, at 2 mm, inside the training amplitudes 1-3 mm), so they are held to the same
    1e-2 (measured 1.2e-3 and 1.1e-3: the training residual spreads over all states). The selection must be sparse
    to be worth it: < 10 % of the cells (measured 36 of 2182), and single points fewer than the selected cells'
    points (measured 43 vs 504): 6x and 12x inside the limits, which a round-off change in the greedy order (a
    cell or two) cannot cross."""
    model, report = build_reduced_model(ci_blade, ReductionConfig(r_c=4, r_md=6, forces="ecsw", ecsw_tol=1e-3),
                                        ops=ci_ops)
    rows = model.nodes.boundary_rows
    Q = training_states(*report["linear_operators"], report["pairs"], report["md_scale"], rows, 20,
                        amplitudes=(2e-3,), seed=11)
    exact, hyper = report["ecsw_exact"].evaluate(Q), model.forces.evaluate(Q)
    err = np.linalg.norm(hyper - exact, axis=0) / np.linalg.norm(exact, axis=0)
    n_cells = ci_blade.mesh.topology.index_map(3).size_local
    print(f"ECSW: {report['ecsw_cells']} of {n_cells} cells, held-out max error {err.max():.1e}")
    assert err.max() <= 1e-2
    assert report["ecsw_cells"] < 0.1 * n_cells
    # single quadrature points instead of whole cells: same states and tolerance, fewer points to evaluate
    exact = report["ecsw_exact"]
    Q_train = training_states(*report["linear_operators"], report["pairs"], report["md_scale"], rows, 80)
    points = train_ecsw(exact, np.arange(exact.w.size), Q_train, tol=1e-3, level="point")
    err_p = state_errors(exact, points.forces, Q)
    print(f"points: {points.n_points} (cells: {model.forces.w.size} points), held-out max error {err_p.max():.1e}")
    assert points.training_error <= 1e-3 and err_p.max() <= 1e-2
    assert points.n_points < model.forces.w.size and np.all(points.forces.w > 0)
    # where it fails (docs/choosing-a-model.md, gallery): the same points on the states of a rub, the linear static
    # response to a load along e_x at one contact node (2 mm there), a local tip deformation that the smooth training
    # states do not contain. The error is far beyond the 1e-2 the training guarantees on states of its family
    # (measured 30-94 %); the project trains its cubatures on contact runs for this reason
    rub = []
    for node in range(len(model.nodes)):
        f = np.zeros(model.r)
        f[model.nodes.q_index[node][0]] = 1.0
        q = np.linalg.solve(model.K, f)
        rub.append(q * 2e-3 / abs(q[model.nodes.q_index[node][0]]))
    err_rub = state_errors(exact, points.forces, np.array(rub).T)
    print(f"points trained on smooth states, on rub states: median error {np.median(err_rub):.2f}")
    assert np.median(err_rub) > 10 * 1e-2


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
    # the same trapezoid sum of the same products in another code path: a few ulps of a positive sum
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

    from rotor37_rom.forces.kernel import pk_nonlinear_kernel

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
    from rotor37_rom.forces.cubature import trajectory_states

    rng = np.random.default_rng(3)
    runs = [rng.standard_normal((6, 120)) * np.linspace(0.1, 1.0, 120), rng.standard_normal((6, 40))]
    runs[1][:, 30:] = np.nan
    train, held = trajectory_states(runs, boundary_rows=[0, 1], n_per_run=10, n_largest=3, n_held=25)
    cols = lambda Q: {tuple(c) for c in Q.T}                              # noqa: E731
    assert not cols(train) & cols(held)
    n1 = trajectory_states([runs[1]], boundary_rows=[0, 1], n_per_run=10, n_largest=3)[0].shape[1]
    assert held.shape[1] == 25 + (30 - n1)                                # run 1 has only 30 - n1 other instants
    first = runs[0][:, :12]                                               # first tenth: only if among the largest
    amp = np.abs(runs[0][:2]).max(axis=0)
    largest = set(np.argsort(amp)[::-1][:3].tolist())
    assert all((k in largest) == (tuple(first[:, k]) in cols(train)) for k in range(12))
    assert np.isfinite(train).all() and np.isfinite(held).all()
    with pytest.raises(ValueError, match="no finite"):
        trajectory_states([np.full((6, 5), np.nan)], boundary_rows=[0, 1])


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
    # the key alone (a cached sweep's check that it ran this model), with the same refusals
    assert saved_model_key(path) == model.key
    with pytest.raises(ValueError, match="corrupted"):
        saved_model_key(bad)
    with np.load(path) as data:
        arrays = {k: data[k] for k in data.files}
    info = json.loads(str(arrays["meta"]))
    info["metadata"]["version"] = "another"                  # metadata edited, the key left as it was
    arrays["meta"] = np.array(json.dumps(info))
    np.savez(tmp_path / "edited.npz", **arrays)
    for read in (saved_model_key, load_reduced_model):
        with pytest.raises(ValueError, match="does not match its metadata"):
            read(tmp_path / "edited.npz")
    # as a cache, a damaged file or another model's is built again, never trusted
    metadata = json.loads(str(np.load(path)["meta"]))["metadata"]
    cache, cached = cached_model(metadata, tmp_path, "rom")
    assert cached is None and not cache.exists()
    save_reduced_model(model, cache)
    assert cached_model(metadata, tmp_path, "rom")[1].key == model.key
    for damage in (cache.read_bytes()[:1000], path.read_bytes()[:-10], b"garbage"):
        cache.write_bytes(damage)
        assert cached_model(metadata, tmp_path, "rom")[1] is None


def test_cache_files_are_whole_or_ignored(tmp_path):
    """``save_npz`` leaves the file complete (no temporary beside it); ``load_npz`` gives None for a file that is
    absent, truncated, garbage, short of a name or failing the caller's check, and the arrays otherwise."""
    a, b = np.arange(12.0).reshape(3, 4), np.array(2.5)
    path = save_npz(tmp_path / "sub" / "c.npz", a=a, b=b)
    assert sorted(p.name for p in path.parent.iterdir()) == ["c.npz"]
    got = load_npz(path, ("a", "b"))
    np.testing.assert_array_equal(got["a"], a)
    assert float(got["b"]) == 2.5

    def shape(arrays):
        if arrays["a"].shape != (3, 4):
            raise ValueError(f"shape {arrays['a'].shape}")

    assert load_npz(path, ("a",), shape)["a"].shape == (3, 4)
    assert load_npz(None) is None and load_npz(tmp_path / "none.npz") is None
    assert load_npz(path, ("a", "c")) is None                          # a name missing
    save_npz(path, a=a.T, b=b)
    assert load_npz(path, ("a",), shape) is None                       # the caller's check
    whole = path.read_bytes()
    for damage in (whole[: len(whole) // 2], whole[:-30], b"garbage", b""):
        path.write_bytes(damage)
        assert load_npz(path) is None, damage[:20]
    # a writer killed half-way leaves a hidden temporary (no glob of the real names sees it); the next write of the
    # same file removes it when its writer is gone, and keeps a running writer's
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    dead, running = int(done.stdout), os.getppid()
    for pid in (dead, running):
        (path.parent / f".c.npz.tmp{pid}.npz").write_bytes(whole[:100])
    assert [p.name for p in path.parent.glob("c*.npz")] == ["c.npz"]
    save_npz(path, a=a, b=b)
    assert sorted(p.name for p in path.parent.iterdir()) == [f".c.npz.tmp{running}.npz", "c.npz"]



def test_json_stores_are_whole(tmp_path):
    """``save_json`` writes the whole text or leaves the earlier file: an object JSON cannot hold raises before any
    file is touched, and a dead writer's temporary is removed by the next write (as ``save_npz``'s)."""
    import json
    import subprocess
    import sys

    path = save_json(tmp_path / "sub" / "store.json", {"a": [1, 2.5], "b": "x"}, indent=1)
    assert json.loads(path.read_text()) == {"a": [1, 2.5], "b": "x"}
    assert sorted(p.name for p in path.parent.iterdir()) == ["store.json"]
    with pytest.raises(TypeError):
        save_json(path, {"a": object()})
    assert json.loads(path.read_text()) == {"a": [1, 2.5], "b": "x"}       # the earlier store, untouched
    done = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    (path.parent / f".store.json.tmp{int(done.stdout)}.json").write_text('{"a": [1,')
    save_json(path, {"a": 3}, default=float)
    assert sorted(p.name for p in path.parent.iterdir()) == ["store.json"]
    assert json.loads(path.read_text()) == {"a": 3}

def test_bad_reduction_input(ci_blade, ci_ops, free_operators):
    from rotor37_rom.fem.sector import _locate_point_dofs

    with pytest.raises(ValueError, match="not vertices of the mesh"):
        _locate_point_dofs(ci_blade.V, np.array([[0.0, 0.0, 0.0]]))
    K, M, free, _ = free_operators
    with pytest.raises(ValueError, match="boundary DOFs"):
        craig_bampton(K, M, np.array([free.size + 5]), 3)
    with pytest.raises(ValueError, match="boundary DOFs"):
        build_reduced_model(ci_blade, ReductionConfig(r_c=2, r_md=0, forces="none"), ops=ci_ops,
                            boundary_dofs=np.array([ci_blade.V.dofmap.index_map.size_local * 3 + 5]))
    with pytest.raises(ValueError, match="r_c"):
        craig_bampton(K, M, np.searchsorted(free, ci_blade.tip_dofs.ravel()), 10**7)
    with pytest.raises(ValueError, match="r_md"):
        build_reduced_model(ci_blade, ReductionConfig(r_c=2, r_md=10**4, forces="none"), ops=ci_ops)
    with pytest.raises(ValueError, match="criterion"):
        ReductionConfig(criterion="best")
    with pytest.raises(ValueError, match="contact_patch must be in"):
        ReductionConfig(contact_patch=-1e-3)
    with pytest.raises(ValueError, match="radius must reach a tip facet"):
        fem.tip_patch_interface(ci_blade, 1e-6)
    with pytest.raises(ValueError, match="contact_patch: the patches replace"):
        build_reduced_model(ci_blade, ReductionConfig(r_c=2, r_md=0, forces="none", contact_patch=3e-3), ops=ci_ops,
                            boundary_dofs=ci_blade.tip_dofs.ravel()[:6])
    from rotor37_rom.reduction.builder import _check_operators

    with pytest.raises(ValueError, match="not symmetric"):
        _check_operators(np.array([[2.0, 1.0], [0.0, 2.0]]), np.eye(2))
    with pytest.raises(ValueError, match="positive definite"):
        _check_operators(np.diag([1.0, -1.0]), np.eye(2))


class _CubicSprings:
    """g(q) = k3 (q_i^3) per coordinate (a Duffing chain's hardening): exact evaluate and jacobian."""

    def __init__(self, k3: float):
        self.k3 = k3

    def evaluate(self, q):
        return (self.k3 * np.asarray(q, float) ** 3).reshape(-1, 1)

    def jacobian(self, q):
        return np.diag(3.0 * self.k3 * np.asarray(q, float) ** 2)


def test_nonlinear_newmark_is_second_order():
    """simulate_newmark on a 2-DOF hardening (Duffing) chain, strongly nonlinear (g ~ K q at the peak), against an
    ODE reference to 1e-12: halving dt divides the error by 4 +- 15 % (the average-acceleration rule is second
    order; the band covers the next term of the expansion at these step sizes), with viscous damping as well, and the
    linear case equals simulate_linear_newmark exactly."""
    import scipy.integrate

    from rotor37_rom.dynamics.newmark import simulate_linear_newmark, simulate_newmark

    M = np.diag([1.0, 2.0])
    K = np.array([[2.0, -1.0], [-1.0, 1.0]]) * 100.0
    g = _CubicSprings(4e4)

    def f(t):
        return np.array([50.0 * np.sin(7.0 * t), 0.0])

    def rhs(t, y):
        q, v = y[:2], y[2:]
        return np.concatenate([v, np.linalg.solve(M, f(t) - K @ q - g.evaluate(q)[:, 0])])

    T_end = 1.0
    ref = scipy.integrate.solve_ivp(rhs, (0, T_end), np.zeros(4), rtol=1e-12, atol=1e-14).y[:2, -1]
    assert np.abs(ref).max() ** 2 * 4e4 > 0.3 * 100.0           # strongly nonlinear: k3 q^2 comparable to K
    errors = []
    for n in (400, 800, 1600):
        _, Q = simulate_newmark(M, np.zeros((2, 2)), K, f, T_end / n, n, forces=g)
        errors.append(np.linalg.norm(Q[:, -1] - ref))
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    assert np.all(np.abs(ratios - 4.0) < 0.6), ratios
    # viscous damping (the builders' training runs): second order too, against the damped ODE's reference
    C = 0.1 * K / 100

    def damped(t, y):
        q, v = y[:2], y[2:]
        return np.concatenate([v, np.linalg.solve(M, f(t) - K @ q - C @ v - g.evaluate(q)[:, 0])])

    ref = scipy.integrate.solve_ivp(damped, (0, T_end), np.zeros(4), rtol=1e-12, atol=1e-14).y[:2, -1]
    errors = [np.linalg.norm(simulate_newmark(M, C, K, f, T_end / n, n, forces=g)[1][:, -1] - ref)
              for n in (400, 800, 1600)]
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    assert np.all(np.abs(ratios - 4.0) < 0.6), ratios
    _, Q1 = simulate_newmark(M, C, K, f, 1e-3, 200)
    _, Q2 = simulate_linear_newmark(M, C, K, f, 1e-3, 200)
    np.testing.assert_array_equal(Q1, Q2)


def test_perturbed_model_scales_the_internal_force(ci_rom):
    """perturbed_model(model, eps) is the model whose internal force K q + g(q) is (1 + eps) times the model's,
    whichever evaluates g: exact tensors, a quadrature (its weights), a disk's sector forces (per-sector scales). To
    round-off: sums of at most r(r+1)(r+2)/6 = 16,215 products, sqrt(n) u ~ 1.4e-14 of their size, so 1e-12 of the
    largest component leaves two orders for cancellation. Its key differs (cached sweeps are not mixed up), eps = 0
    is the model itself, a second perturbation composes, and |eps| >= 0.01 is refused (a model change, not a
    perturbation)."""
    import dataclasses

    from rotor37_rom.forces.sector import SectorForces
    from rotor37_rom.model.reduced import perturbed_model

    eps, rng, r = 1e-4, np.random.default_rng(11), ci_rom.r
    quad = QuadratureForces(rng.standard_normal((20, r, 3, 3)), rng.random(20), 1.1e11, 4.4e10)
    sectors = SectorForces(quad, np.arange(2 * r).reshape(2, r), 2 * r, np.array([1.0, 1.03]))
    for forces in (ci_rom.forces, quad, sectors):
        model = dataclasses.replace(ci_rom, forces=forces)
        pert = perturbed_model(model, eps)
        Q = rng.standard_normal((forces.r, 3)) * 1e-3
        g, g_pert = model.nonlinear_force(Q), pert.nonlinear_force(Q)
        assert np.abs(g_pert - (1 + eps) * g).max() <= 1e-12 * np.abs(g).max() > 0
        assert np.array_equal(pert.K, (1 + eps) * ci_rom.K) and np.array_equal(pert.M, ci_rom.M)
        assert pert.key != model.key and pert.metadata["perturbation"] == eps
    twice = perturbed_model(perturbed_model(ci_rom, eps), -eps)
    # (1 + eps)(1 - eps) - 1 in floating point: -eps^2 to a few units of round-off of 1
    assert twice.metadata["perturbation"] == pytest.approx(-eps * eps, abs=4e-16) and twice.key != ci_rom.key
    assert perturbed_model(ci_rom, 0.0) is ci_rom
    for bad in (0.01, -0.5, float("nan")):
        with pytest.raises(ValueError, match="perturbation"):
            perturbed_model(ci_rom, bad)
