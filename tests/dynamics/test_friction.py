"""Friction-induced instability of sliding tip contact (rotor37_rom.dynamics.friction) against theory and the integrator.
Model: the ci blade, r = 45 (the contact tests' model), linear operators."""
import numpy as np
import pytest
import scipy.linalg

from rotor37_rom.dynamics.casing import Casing, contact_matrices
from rotor37_rom.dynamics.friction import critical_friction, sliding_contact_eigenvalues, sprag_slip_friction
from rotor37_rom.dynamics.explicit import CentralDifference, simulate


def _largest_real_root(ev):
    real = ev[np.abs(ev.imag) < 1e-9 * np.abs(ev).max()].real
    return real.max() if real.size else -np.inf


def test_sprag_slip_onset_is_where_a_real_eigenvalue_crosses_zero(ci_blade, ci_ops, ci_rom):
    """Divergence of persistent sliding: the static criterion det(N K^-1 (N + mu S)^T) = 0 is where a real eigenvalue
    of the constrained dynamics crosses zero (damping does not move a static instability), to 1e-4 in mu, for every
    node and node set that friction can wedge, in both rotation senses; a single node can be wedged exactly when its
    compliance G_ns < 0 (mu* = -G_nn / G_ns). Craig-Bampton keeps the tip DOFs, so the reduced static compliance at
    a tip node is the full-order one: mu* of the ROM equals mu* from two full-order static solves (forces along n
    and s at the node), to the solvers' round-off (kappa(K) u ~ 1e-10; asserted 1e-8). Without friction and damping
    the constrained eigenvalues are +-i omega of (T^T K T, T^T M T), the clamped-node modes."""
    from rotor37_rom import fem

    M, C, K = ci_rom.M, ci_rom.C, ci_rom.K
    G = np.linalg.inv(K)
    N, S_rotor37, _, _ = contact_matrices(ci_rom.nodes, ci_rom.r, Casing())
    for sense in (-1, 1):                # +1 (refused by contact_matrices for this blade's hand): S turned round
        S = -sense * S_rotor37
        wedged = [k for k in range(len(ci_rom.nodes)) if N[k] @ G @ S[k] < 0]
        assert wedged                                   # the crossing below is exercised in both senses
        for nodes in [[k] for k in range(len(ci_rom.nodes))] + [[0, 1, 2, 3], [4, 5, 6, 7], None]:
            mu = sprag_slip_friction(K, N, S, nodes)
            if len(nodes or []) == 1:
                assert np.isfinite(mu) == (nodes[0] in wedged), (sense, nodes, mu)
            if not np.isfinite(mu):
                continue
            below = sliding_contact_eigenvalues(M, C, K, N, S, mu * (1 - 1e-4), nodes)
            above = sliding_contact_eigenvalues(M, C, K, N, S, mu * (1 + 1e-4), nodes)
            assert _largest_real_root(below) < 0.0 < _largest_real_root(above), (sense, nodes, mu)
    N, S, _, _ = contact_matrices(ci_rom.nodes, ci_rom.r, Casing())
    k = ci_rom.nodes.row("tip2")
    n_dir, s_dir = N[k, ci_rom.nodes.q_index[k]], S[k, ci_rom.nodes.q_index[k]]
    dofs = ci_blade.tip_dofs[ci_blade.tip_names.index("tip2")]
    rhs = np.zeros((2, ci_blade.n_dofs))
    rhs[0, dofs], rhs[1, dofs] = n_dir, s_dir
    u = fem.solve_clamped_static(ci_blade, rhs, ci_ops)
    mu_full = -(u[0, dofs] @ n_dir) / (u[1, dofs] @ n_dir)          # -G_nn / G_ns
    assert sprag_slip_friction(K, N, S, [k]) == pytest.approx(mu_full, rel=1e-8)
    ev = sliding_contact_eigenvalues(M, 0 * C, K, N, S, 0.0, [0, 3])
    T = scipy.linalg.null_space(N[[0, 3]])
    w = np.sqrt(scipy.linalg.eigh(T.T @ K @ T, T.T @ M @ T, eigvals_only=True))
    np.testing.assert_allclose(np.sort(np.abs(ev.imag))[::2], w, rtol=1e-8)
    assert np.abs(ev.real).max() < 1e-8 * w.max()
    with pytest.raises(ValueError, match="mu must be >= 0"):
        sliding_contact_eigenvalues(M, C, K, N, S, -0.1)
    with pytest.raises(ValueError, match="nodes must be distinct"):
        sprag_slip_friction(K, N, S, [8])
    mu_c, lead = critical_friction(M, C, K, N, S, [2], mu_max=0.3)
    assert mu_c == pytest.approx(sprag_slip_friction(K, N, S, [2]), rel=1e-5) and lead.imag == 0.0


def test_integrator_follows_the_sliding_stability(ci_rom):
    """Node 2 alone, pressed on a round casing (c0 = 0.5 mm) by a constant outward force (1.1 c0 of free static
    deflection). Below the sprag-slip coefficient (0.95 mu*) the static pressed state is a fixed point of the scheme
    with contact: the multiplier stays at its static value to round-off over 4e4 steps (a stable fixed point does not
    accumulate round-off: each step reproduces it to ~kappa(K~) u = 8e-11; asserted 1e-7). Above it (1.2 mu*) no
    pressed equilibrium exists: the multiplier grows as exp(s t) with s the real eigenvalue of the sliding dynamics,
    fast enough (s T > log of the growth to the 1 m blow-up limit) to stop the run within it. The rate fitted over
    the last quarter is s up to the other eigenvalues' share: log(lambda) = s t + log(1 + c exp(-(s - Re_2) t)),
    Re_2 < 0 the next real part, so the fitted slope is off by at most that share at the window's start (times the
    start's ratio c of the other modes to the growing one, <= 2 from a pressed state): rel 2 x share."""
    scheme = CentralDifference(ci_rom, nonlinear=False, safety=0.5)
    c0, k = 0.5e-3, 2
    N, S, _, _ = contact_matrices(ci_rom.nodes, ci_rom.r, Casing(contact_nodes=(k,)))
    mu_star = sprag_slip_friction(ci_rom.K, N, S)
    G = np.linalg.inv(ci_rom.K)
    F = N[0] * (1.1 * c0 / (N @ G @ N.T)[0, 0])
    mu = 0.95 * mu_star
    B = (N + mu * S).T
    lam_s = ((N @ G @ F)[0] - c0) / (N @ G @ B)[0, 0]
    q_s = G @ (F - B[:, 0] * lam_s)
    res = simulate(scheme, [1400.0], Casing(c0=c0, h_b=0.0, mu=mu, contact_nodes=(k,)), n_steps=40000,
                   forcing=lambda t: F, initial=(q_s, q_s), record_every=10, on_blowup="flag", blowup_limit=1.0)
    assert res.diverged_step[0] < 0 and res.contact_steps[0] == 40000
    assert np.abs(res.lam[0][0][1:] / lam_s - 1.0).max() < 1e-7
    mu = 1.2 * mu_star
    ev = sliding_contact_eigenvalues(ci_rom.M, ci_rom.C, ci_rom.K, N, S, mu)
    s = _largest_real_root(ev)
    assert s * 40000 * scheme.h > np.log(1.0 / c0)
    res = simulate(scheme, [1400.0], Casing(c0=c0, h_b=0.0, mu=mu, contact_nodes=(k,)), n_steps=40000,
                   forcing=lambda t: F, initial=(q_s, q_s), record_every=10, on_blowup="flag", blowup_limit=1.0)
    assert 0 < res.diverged_step[0] < 40000
    lam, t = res.lam[0][0], res.t[0]
    grew = lam > 0
    t, lam = t[grew], lam[grew]
    tail = slice(3 * len(t) // 4, len(t))
    rate = np.polyfit(t[tail], np.log(lam[tail]), 1)[0]
    re_2 = ev.real[1:].max()
    share = np.exp(-(s - re_2) * (t[tail][0] - t[0]))
    print(f"mu* = {mu_star:.4f}; at 1.2 mu*: fitted rate {rate:.1f} 1/s, eigenvalue {s:.1f} 1/s, others' share "
          f"{share:.1e}")
    assert rate == pytest.approx(s, rel=2 * share)
    assert res.work[0][1] > 0.0                  # friction feeds the blade


def test_static_compliance_and_the_casing_cone_normal(ci_blade, ci_ops, ci_rom):
    """``fem.static_compliance`` at the 8 tip nodes (24 unit loads on one MUMPS factorisation) equals the r = 45
    model's tip block of K_r^-1: the constraint modes are exact static responses to tip loads, so the Galerkin
    solution on the basis is exact and the two differ by round-off (kappa(K) u ~ 1e-10 relative; asserted 1e-8 of
    max |G|); the sprag-slip onsets from G therefore equal the model's for every contact normal (1e-7). The casing
    cone's normal is a unit vector at atan(0.2737) = 15.3 deg from e_r towards +e_z, orthogonal to the sliding
    direction; with slope 0 it is the radial frame (to round-off)."""
    from rotor37_rom import fem

    G = fem.static_compliance(ci_blade, ci_blade.tip_dofs, ops=ci_ops)
    rows = [ci_rom.nodes.row(name) for name in ci_blade.tip_names]
    idx = ci_rom.nodes.q_index[rows].ravel()
    G_rom = np.linalg.inv(ci_rom.K)[np.ix_(idx, idx)]
    np.testing.assert_allclose(G, G_rom, rtol=0, atol=1e-8 * np.abs(G).max())
    for direction in ("x", "radial", "cone"):
        N, S, _, _ = contact_matrices(ci_rom.nodes, ci_rom.r, Casing(direction=direction), rows=rows)
        n_tip = len(rows)
        Nt, St = N[:, idx], S[:, idx]
        for nodes in ([0], [1], [2], [3], [0, 1, 2, 3], None):
            mu_rom = sprag_slip_friction(ci_rom.K, N, S, nodes)
            mu_fom = sprag_slip_friction(np.linalg.inv(G), Nt, St, nodes)
            assert (np.isinf(mu_rom) and np.isinf(mu_fom)) or mu_fom == pytest.approx(mu_rom, rel=1e-7), \
                (direction, nodes, mu_rom, mu_fom)
        assert Nt.shape == (n_tip, 3 * n_tip)
    from rotor37_rom.dynamics.casing import CONE_SLOPE, contact_frames

    normals, slide, theta = contact_frames(ci_blade.tip_nodes, "cone", -1)
    e_r = np.column_stack([np.cos(theta), np.sin(theta), 0 * theta])
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, rtol=1e-15)
    np.testing.assert_allclose(np.einsum("ij,ij->i", normals, e_r), np.cos(np.arctan(CONE_SLOPE)), rtol=1e-15)
    assert np.all(normals[:, 2] > 0) and np.abs(np.einsum("ij,ij->i", normals, slide)).max() < 1e-15
    flat = contact_frames(ci_blade.tip_nodes, "cone", -1, cone_slope=0.0)
    radial = contact_frames(ci_blade.tip_nodes, "radial", -1)
    for a, b in zip(flat, radial):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-15)      # the normalisation: round-off
    with pytest.raises(ValueError, match="cone_slope must be in"):
        Casing(direction="cone", cone_slope=-0.1)
    with pytest.raises(ValueError, match="direction must be one of"):
        Casing(direction="axial")
