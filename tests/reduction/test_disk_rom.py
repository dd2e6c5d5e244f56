"""The bladed disk's reduced model (paper §3.1, eqs. 40-61) and its full-order transient reference (§3.3).

- the repeating-sector reference (n sectors closed on themselves) equals the assembled whole structure for a
  linear transient under a nodal-diameter load (plate, N = 8, N_d = 2: 4 sectors carry it);
- the disk's CMS frequencies are Rayleigh-Ritz upper bounds of the full cyclic ones and within 1 % for the families
  up to 2B at k = 0, 1, 9, 18;
- the disk's reduced force equals Phi^T g(Phi q) of the full-order sector forms per sector (eq. 61) to round-off, and
  with the faces in the force (face_shapes) the chain rule through the face coordinates;
- save/load, the travelling load and the performance indicator; bad input;
- the best approximation of reference fields in the model's span (the basis's share of the indicator's error);
- a load spread over a patch (the GNL reference's load): its reduced force is the transpose of the field rebuild, and
  the static load correction gives the model the patch's local field.
"""
from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse.linalg as spla

from rotor37_rom import fem
from rotor37_rom.post.stress import cyclic_harmonic_frequencies
from rotor37_rom.disk.symmetry import assemble_full_structure, to_global_frame
from rotor37_rom.disk.assembly import assemble_disk_matrices, face_shapes, interface_modes
from rotor37_rom.model.disk_basis import DiskBasis, sector_force_basis
from rotor37_rom.disk.indicators import best_approximation, indicator_histories, performance_indicator
from rotor37_rom.disk.loads import harmonic_field_load, harmonic_node_load, repeat_count
from rotor37_rom.disk.harmonics import harmonic_frequencies, sector_harmonics
from rotor37_rom.reduction.disk_builder import DiskReductionConfig, build_disk_model
from rotor37_rom.model.reduced import load_reduced_model, save_reduced_model
from rotor37_rom.dynamics.newmark import simulate_newmark
from conftest import random_sector  # noqa: E402

pytestmark = pytest.mark.slow


def _newmark_sparse(M, K, f, dt, n):
    """Average-acceleration Newmark on a sparse linear system from rest (the reference's scheme)."""
    c0 = 4.0 / dt**2
    lu = spla.splu((K + c0 * M).tocsc())
    x, v = np.zeros(K.shape[0]), np.zeros(K.shape[0])
    a = spla.splu(M.tocsc()).solve(f(0.0))
    out = [x]
    for k in range(1, n + 1):
        x_new = lu.solve(f(k * dt) + M @ (c0 * x + 4.0 / dt * v + a))
        a_new = c0 * (x_new - x) - 4.0 / dt * v - a
        v, x, a = v + 0.5 * dt * (a + a_new), x_new, a_new
        out.append(x)
    return np.array(out)


def _plate():
    """An annular plate sector (N = 8) and the e_z DOF of its outer node nearest the sector's middle."""
    plate = fem.create_annular_sector(0.05, 0.2, 0.01, n_sectors=8, size=0.02, layers=1)
    coords = plate.V.tabulate_dof_coordinates()[: plate.n_dofs // 3]
    theta = np.arctan2(coords[:, 1], coords[:, 0])
    node = int(np.argmax(np.hypot(coords[:, 0], coords[:, 1]) - 0.01 * np.abs(theta - np.pi / 8)))
    return plate, 3 * node + 2


def test_repeating_sectors_equal_the_assembled_structure():
    """Plate of N = 8 sectors, a load of N_d = 2 diameters (the response repeats every 8 / gcd(8, 2) = 4 sectors):
    the linear transient of the 4 sectors closed on themselves equals that of the whole plate assembled from 8
    turned copies, sector by sector, to 1e-9 relative (the same Newmark on the same equations reordered: round-off
    times the conditioning of K + 4 M / dt^2), and sectors s and s + 4 of the whole plate move alike."""
    plate, load_dof = _plate()
    N, nd, n_rep = 8, 2, repeat_count(8, 2)
    assert n_rep == 4
    dofs = np.arange(plate.n_dofs).reshape(-1, 3)
    omega, dt, steps = 3000.0, 2 * np.pi / 3000.0 / 40, 60
    rep = fem.solve_repeating_newmark(plate, n_rep, load_dof, fem.sector_harmonic_load(n_rep, N, nd, 100.0, omega),
                                      dt, steps, nonlinear=False, snapshot_every=1)
    ops = fem.create_svk_operators(plate)
    Ks = fem.petsc_to_scipy(fem.assemble_stiffness(plate, ops))
    Ms = fem.petsc_to_scipy(fem.assemble_mass(plate, ops))
    K_full, M_full, index = assemble_full_structure(Ks, Ms, plate.cyclic, dofs)
    phase = np.arange(N) * nd * 2 * np.pi / N
    unit = np.zeros((N, K_full.shape[0]))
    for s in range(N):                                    # e_z is the same in every sector frame
        unit[s, index[s, load_dof]] = 1.0

    def load(t):
        return (100.0 * np.sin(omega * t - phase)) @ unit

    full = _newmark_sparse(M_full, K_full, load, dt, steps)
    per_sector = np.stack([to_global_frame(full[:, index[s]], dofs, -s * plate.cyclic.angle) for s in range(N)], 1)
    scale = np.abs(per_sector).max()
    assert scale > 0
    for s in range(N):
        np.testing.assert_allclose(rep.fields[:, s % n_rep], per_sector[1:, s], atol=1e-9 * scale, rtol=0)


def test_generalised_alpha_is_second_order_and_newmark_at_rho_1():
    """The full-order reference's generalised-alpha option (rho_inf, for contact runs whose tip nodes ring at
    unresolved frequencies): at rho_inf = 1 it is average-acceleration Newmark (alpha_m = alpha_f = 1/2: the mean of
    equilibria at t_n and t_n+1, which holds at t_n), equal to round-off; at rho_inf = 0.8 and 0.5 it is second order
    (Chung & Hulbert): halving the step divides the change between successive halvings by 4 (3.5-4.5 asserted), on a
    load started smoothly (sin^2 over one period: an abrupt start excites the plate's mesh-scale modes, which no step of
    this size resolves, and the rate measured is then 1.5-2.6 for every scheme, Newmark included)."""
    plate, load_dof = _plate()
    N, nd, n_rep, omega = 8, 2, repeat_count(8, 2), 3000.0
    period = 2 * np.pi / omega
    harmonic = fem.sector_harmonic_load(n_rep, N, nd, 100.0, omega)

    def smooth(t):
        return harmonic(t) * np.sin(0.5 * np.pi * min(t / period, 1.0)) ** 2

    dt, steps = period / 40, 60
    newmark, alpha = (fem.solve_repeating_newmark(plate, n_rep, load_dof, harmonic, dt, steps, nonlinear=False,
                                                  snapshot_every=10, rho_inf=rho).fields for rho in (None, 1.0))
    scale = np.abs(newmark).max()
    assert scale > 0 and np.abs(alpha - newmark).max() <= 1e-9 * scale
    # with SVK forces too: generalised alpha averages f(x_n) (carried over from the previous step) and f(x_n+1), and
    # the equilibrium it adds at t_n is Newton's residual left there: at most rtol = 1e-8 of the forces per step,
    # twice that in displacement over 20 steps is 4e-7 (a stale f(x_n), one step old, would be ~1e-2 off)
    newmark, alpha = (fem.solve_repeating_newmark(plate, n_rep, load_dof, harmonic, dt, 20, nonlinear=True,
                                                  snapshot_every=10, rho_inf=rho).fields for rho in (None, 1.0))
    print("GNL, rho_inf 1 against Newmark:", np.abs(alpha - newmark).max() / np.abs(newmark).max())
    assert np.abs(alpha - newmark).max() <= 1e-6 * np.abs(newmark).max()
    for rho in (0.8, 0.5):
        fields = {k: fem.solve_repeating_newmark(plate, n_rep, load_dof, smooth, dt / k, steps * k, nonlinear=False,
                                                 rho_inf=rho, snapshot_every=10 * k).fields for k in (1, 2, 4, 8)}
        changes = [np.abs(fields[k] - fields[2 * k]).max() for k in (1, 2, 4)]     # e(h) - e(h/2) ~ (3/4) C h^2
        rates = [changes[0] / changes[1], changes[1] / changes[2]]
        print(f"rho_inf {rho}: changes {changes}, rates {rates}")
        assert all(3.5 <= r <= 4.5 for r in rates), rates
    with pytest.raises(ValueError, match="rho_inf"):
        fem.solve_repeating_newmark(plate, n_rep, load_dof, harmonic, dt, 2, nonlinear=False, rho_inf=1.5)


def test_generalised_alpha_damps_unresolved_modes_by_rho_inf():
    """What rho_inf is for: a mode with omega dt >> 1 loses the factor rho_inf per step, while average acceleration
    keeps it. At omega dt -> infinity generalised alpha's amplification matrix has the triple eigenvalue -rho_inf
    in one Jordan block (Chung & Hulbert 1993: the characteristic polynomial tends to (lambda + rho_inf)^3), so the
    free response is x_n = (-rho_inf)^n (c0 + c1 n + c2 n^2): x_n / (-rho_inf)^n is a quadratic in n. The plate
    kicked over one step of dt = 1e3 s, then free (omega_1 dt > 1e6 for its lowest mode: every mode unresolved; the
    triple root splits by O((omega dt)^(-2/3)) ~ 1e-4, which bends the quadratic by ~(n 1e-4 / rho)^3 < 1e-6 over
    100 steps; at dt = 1 s the split, 1e-2, bends it by 2.5e-3): from step 20 to where rho_inf^n reaches 1e-9 (above
    round-off) the quadratic fits every DOF to 1e-6 of its largest value (measured 3e-9), while the same fit with a
    rate 2 % off leaves 4e-4 to 6e-2. Average acceleration neither grows nor decays (1e-6 per step in log)."""
    plate, load_dof = _plate()
    dt, steps = 1e3, 100

    def kick(t):
        return np.full(1, 100.0) if t < 1.5 * dt else np.zeros(1)

    for rho in (None, 0.8, 0.5):
        fields = fem.solve_repeating_newmark(plate, 1, load_dof, kick, dt, steps, nonlinear=False, rho_inf=rho,
                                             snapshot_every=1).fields.reshape(steps, -1)   # snapshot k: step k + 1
        if rho is None:
            size = np.abs(fields).max(axis=1)
            slope = (np.log(size[99]) - np.log(size[19])) / 80
            print(f"Newmark: log change per step over steps 20-100 {slope:.2e}")
            assert abs(slope) <= 1e-6              # |eigenvalue| 1; its beat, (n / (omega dt))^2, and round-off
            continue
        n = np.arange(20, min(steps, int(np.log(1e-9) / np.log(rho))) + 1)
        V = np.vander(n.astype(float), 3)
        for rate, bound in ((rho, 1e-6), (1.02 * rho, None), (0.98 * rho, None)):
            Y = fields[n - 1] / (-rate) ** n[:, None]
            coef, *_ = np.linalg.lstsq(V, Y, rcond=None)
            misfit = np.abs(Y - V @ coef).max() / np.abs(Y).max()
            print(f"rho_inf {rho}, rate {rate:.3f}: quadratic misfit {misfit:.1e}")
            if bound is not None:
                assert misfit <= bound


def test_disk_frequencies_bound_the_cyclic_reference(ci_disk, ci_disk_ops, disk_model):
    """Per nodal diameter k = 0, 1, 9, 18, the disk model's three lowest frequencies (1B, 1T, 2B families) are upper
    bounds of the full-order cyclic ones (the model is a Galerkin projection of the whole disk: Rayleigh-Ritz; 1e-9
    for the eigensolvers' tolerance) and within 1 % of them."""
    model, report = disk_model
    harmonics = (0, 1, 9, 18)
    rom = harmonic_frequencies(model, 3)[list(harmonics)]
    ref = cyclic_harmonic_frequencies(ci_disk, 3, ops=ci_disk_ops, harmonics=harmonics)
    print(ref, rom)
    assert np.all(rom >= ref * (1 - 1e-9)), (rom, ref)
    np.testing.assert_array_less(rom, ref * 1.01)


def test_harmonic_frequencies_split_the_disk_by_nodal_diameter():
    """A random tuned disk (N = 6 sectors, r_s = 4, 3 face DOFs): the frequencies per harmonic index, each cos/sin
    pair of 0 < k < 3 counted twice, are all the disk model's eigenvalues (round-off: 1e-9 relative). With the
    interface modes of k = 2, 3 left out (their faces held), those k's families are the sector's fixed-interface
    frequencies exactly, the same values at two k, and still assigned to both (the degenerate case an eigenvector sort
    gets wrong). A disk mistuned by 1 % is refused."""
    from types import SimpleNamespace

    rng = np.random.default_rng(21)
    N, rs, nL = 6, 4, 3
    s = random_sector(rng, rs, nL)
    Pi, _, k_pi = interface_modes(s, N, N * nL, per_k=nL)
    blocks = np.arange(N * rs).reshape(N, rs)

    def model(Pi, scales=None):
        Kd, Md = assemble_disk_matrices(s, Pi, N, scales)
        basis = DiskBasis(np.zeros((1, rs)), np.zeros((1, nL)), np.zeros((1, nL)), Pi, blocks, N)
        return SimpleNamespace(sectors=basis, K=Kd, M=Md)

    for keep in (np.ones(Pi.shape[1], bool), k_pi < 2):
        m = model(Pi[:, keep])
        w = harmonic_frequencies(m, 50)
        counts = [1, 2, 2, 1]
        split = np.sort(np.concatenate([np.repeat(w[k][~np.isnan(w[k])], c) for k, c in enumerate(counts)]))
        full = np.sqrt(np.sort(np.linalg.eigvals(np.linalg.solve(m.M, m.K)).real))
        np.testing.assert_allclose(split, full, rtol=1e-9)
    for k in (2, 3):                                   # no interface modes of k: the faces held
        np.testing.assert_allclose(w[k][~np.isnan(w[k])], s.omega_c, rtol=1e-9)
    with pytest.raises(ValueError, match="mistuned"):
        harmonic_frequencies(model(Pi, 1 + 0.01 * rng.standard_normal(N)), 3)


def _tips_moving(basis, r: int, rng) -> np.ndarray:
    """A disk state with sectors 0 and 17 moved by random q^n, tip motions of ~2 mm (g ~ 1e-2 K u: no cancellation),
    the others and the interface modes at rest."""
    q = np.zeros(r)
    for n in (0, 17):
        block = rng.standard_normal(basis.blocks.shape[1])
        q[basis.blocks[n]] = 2e-3 * block / np.abs(basis.Phi_s @ block).max()
    return q


def test_disk_force_equals_the_sector_forms(ci_disk, ci_disk_ops, disk_model):
    """eq. 61: with the interface modes at rest, the disk model's force on sector n's block is
    Phi_s^T g(Phi_s q^n) of the full-order SVK form, to 1e-10 relative (exact cubic tensors against quadrature of the
    same polynomial: round-off); the interface rows get no nonlinear force (the paper's linear coupling)."""
    model, _ = disk_model
    basis, forces = model.sectors, model.forces
    K = fem.petsc_to_scipy(fem.assemble_stiffness(ci_disk, ci_disk_ops, clamped=False))
    rng = np.random.default_rng(3)
    q = _tips_moving(basis, model.r, rng)
    g = forces.evaluate(q)[:, 0]
    for n in (0, 17):
        u = basis.Phi_s @ q[basis.blocks[n]]
        ref = basis.Phi_s.T @ (fem.evaluate_forces(ci_disk, ci_disk_ops, u[None], "f_int")[0] - K @ u)
        np.testing.assert_allclose(g[basis.blocks[n]], ref, atol=1e-10 * np.abs(ref).max(), rtol=0)
    assert np.all(g[basis.blocks[5]] == 0.0)              # a sector at rest
    assert np.all(g[basis.blocks.size:] == 0.0)


def test_disk_force_with_the_faces(tmp_path, ci_disk, ci_disk_ops, disk_model, disk_cache):
    """face_shapes = n_f: each sector's force acts on its whole field with the faces on n_f shapes L, u^n =
    Phi_s q^n + Psi_L L a_L^n + Psi_R' L a_R^n (a = L^T u_L): the disk force equals, sector by sector, the
    full-order SVK form's force on that field projected back (q^n rows by Phi_s^T, the interface rows by the faces'
    chain rule), to 1e-10 relative (exact tensors against quadrature of the same polynomial: round-off); its
    Jacobian passes the Taylor test (remainder ratio 4 when the step halves: g is a cubic polynomial); the model
    saves and reloads with the same force."""
    config = DiskReductionConfig(tip_nodes="LE", r_c=8, r_md=4, criterion="MI2b", r_cyclic=96, face_shapes=4)
    model, report = build_disk_model(ci_disk, config, ops=ci_disk_ops, cache_dir=disk_cache)
    assert not report["cached"] and any(disk_cache.glob("disk_cb_*.npz"))   # disk_model's Craig-Bampton modes read
    basis, forces = model.sectors, model.forces
    N, nL = basis.n_sectors, basis.Psi_L.shape[1]
    L, faces = face_shapes(basis.Pi, report["interface_omega"], N, 4)
    np.testing.assert_allclose(faces, forces.faces, rtol=0, atol=1e-14)
    K = fem.petsc_to_scipy(fem.assemble_stiffness(ci_disk, ci_disk_ops, clamped=False))
    rng = np.random.default_rng(6)
    q = _tips_moving(basis, model.r, rng)
    eta = rng.standard_normal(basis.Pi.shape[1])
    q[basis.blocks.size:] = 5e-4 * eta / np.abs(basis.Pi @ eta).max()  # faces moving ~0.5 mm
    g = forces.evaluate(q)[:, 0]
    uL = (basis.Pi @ q[basis.blocks.size:]).reshape(N, nL)
    ref_eta = np.zeros(basis.Pi.shape[1])
    for n in range(N):
        a_L, a_R = L.T @ uL[n], L.T @ uL[(n + 1) % N]
        u = basis.Phi_s @ q[basis.blocks[n]] + basis.Psi_L @ (L @ a_L) + basis.Psi_Rr @ (L @ a_R)
        f_int, Ku = fem.evaluate_forces(ci_disk, ci_disk_ops, u[None], "f_int")[0], K @ u
        gn = f_int - Ku
        ref_eta += faces[n, :4].T @ ((basis.Psi_L @ L).T @ gn) + faces[n, 4:].T @ ((basis.Psi_Rr @ L).T @ gn)
        ref = basis.Phi_s.T @ gn
        # round-off of the reference: f_int - K u cancels where the faces' constraint modes move the sector (Phi_s^T
        # K Psi_L = 0 in exact arithmetic): a sum of n = 23,700 terms is within n eps = 2.6e-12 of sum |terms|
        # (measured 4e-13 on a sector moved by its faces only, where the force itself is 1e-5 of sum |terms|)
        noise = 1e-11 * (np.abs(basis.Phi_s).T @ (np.abs(f_int) + np.abs(Ku))).max()
        np.testing.assert_allclose(g[basis.blocks[n]], ref, atol=1e-10 * np.abs(ref).max() + noise, rtol=0)
    np.testing.assert_allclose(g[basis.blocks.size:], ref_eta, atol=1e-10 * np.abs(ref_eta).max(), rtol=0)
    d = rng.standard_normal(model.r) * np.abs(q).max()
    J = forces.jacobian(q)
    rem = [np.linalg.norm(forces.evaluate(q + e * d)[:, 0] - g - e * (J @ d)) for e in (1e-2, 5e-3, 2.5e-3)]
    for a, b in zip(rem, rem[1:]):
        assert 3.5 < a / b < 4.5
    Jb = forces.jacobians(np.column_stack([q, 0.5 * q]))                 # batched: the same two Jacobians
    np.testing.assert_allclose(Jb, np.stack([J, forces.jacobian(0.5 * q)]), rtol=0, atol=1e-10 * np.abs(J).max())
    back = load_reduced_model(save_reduced_model(model, tmp_path / "faces.npz"))
    np.testing.assert_array_equal(back.forces.evaluate(q), forces.evaluate(q))


def test_sector_force_basis_recovers_the_face_shapes():
    """The fields of the sector force (what a cubature is trained on) come back from a model's stored face
    coordinates alone: faces[n] = [L^T Pi_n; L^T Pi_(n+1)] determine L because L lies in the span of the faces'
    motions; [Phi_s, Psi_L L, Psi_R' L] to round-off (1e-12 relative; least squares on a matrix of condition ~10),
    and Phi_s alone without faces. Random interface modes (N = 6, 40 face DOFs, 30 modes)."""
    rng = np.random.default_rng(11)
    N, nL, r_c, n_dofs, r_s = 6, 40, 30, 200, 7
    Pi = rng.standard_normal((N * nL, r_c))
    L, faces = face_shapes(Pi, rng.uniform(1e3, 1e4, r_c), N, 5)
    basis = DiskBasis(rng.standard_normal((n_dofs, r_s)), rng.standard_normal((n_dofs, nL)),
                      rng.standard_normal((n_dofs, nL)), Pi, np.arange(N * r_s).reshape(N, r_s), N)
    want = np.hstack([basis.Phi_s, basis.Psi_L @ L, basis.Psi_Rr @ L])
    got = sector_force_basis(basis, faces)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12 * np.abs(want).max())
    assert sector_force_basis(basis, None) is basis.Phi_s
    with pytest.raises(ValueError, match="faces must be"):
        sector_force_basis(basis, faces[:, :, 1:])


def test_disk_model_save_load_and_response(tmp_path, disk_model):
    """The saved model reloads with the same matrices, forces and sector basis; a travelling 0-diameter load gives
    every sector the same LE history (the tuned disk's symmetry; GNL on) to round-off, and a 9-diameter load repeats
    every 4 sectors. (40 N: the paper's 400 N on the single LE node of the ci mesh indents its thin LE locally,
    which needs the reference's load increments; the symmetry does not depend on the amplitude.)"""
    model, _ = disk_model
    back = load_reduced_model(save_reduced_model(model, tmp_path / "disk.npz"))
    np.testing.assert_array_equal(back.K, model.K)
    q = np.random.default_rng(0).standard_normal(model.r) * 1e-6
    np.testing.assert_array_equal(back.forces.evaluate(q), model.forces.evaluate(q))
    np.testing.assert_array_equal(back.sectors.Pi, model.sectors.Pi)
    rows = np.array([model.nodes.q_index[model.nodes.row("LE", s), 2] for s in range(36)])
    for nd, period in ((0, 1), (9, 4)):
        load = harmonic_node_load(model.nodes, model.r, 40.0, 4000.0, nd)
        _, Q = simulate_newmark(model.M, np.zeros_like(model.M), model.K, load, 2 * np.pi / 4000 / 100, 60,
                                forces=model.forces)
        le = Q[rows]
        scale = np.abs(le).max()
        for s in range(period, 36):
            np.testing.assert_allclose(le[s], le[s - period], atol=1e-7 * scale, rtol=0)
    # the indicator of a history against itself is 1, and against zero 0.5 minus nothing (all errors 1)
    tip = np.random.default_rng(1).standard_normal((5, 2, 3, 3))
    fields = np.random.default_rng(2).standard_normal((2, 2, 6))
    import scipy.sparse as sp

    eye = sp.identity(6)
    assert performance_indicator(tip, tip, fields, fields, eye, eye)["I"] == 1.0
    assert performance_indicator(tip, 0 * tip, fields, 0 * fields, eye, eye)["I"] == 0.0


def test_indicator_histories_give_the_criteria():
    """The error histories charted next to I are the indicator's own criteria over time: their largest values are the
    loaded-node, field and strain-energy errors and the RMS of the tip history is the tip error, to round-off
    (random histories of 3 sectors, 8 tip nodes, 40 instants, 10 snapshots, SPD K and M)."""
    rng = np.random.default_rng(4)
    tip_ref, tip_rom = rng.standard_normal((2, 40, 3, 8, 3))
    field_ref, field_rom = rng.standard_normal((2, 10, 3, 12))
    A, B = rng.standard_normal((2, 12, 12))
    K, M = A @ A.T + np.eye(12), B @ B.T + np.eye(12)
    errors = performance_indicator(tip_ref, tip_rom, field_ref, field_rom, K, M, loaded=(2, 1))["errors"]
    hist = indicator_histories(tip_ref, tip_rom, field_ref, field_rom, K, M, loaded=(2, 1))
    assert hist["loaded node"].shape == hist["tip nodes"].shape == (40,) and hist["field"].shape == (10,)
    for name in ("loaded node", "field", "strain energy"):
        assert hist[name].max() == pytest.approx(errors[name], rel=1e-12)
    assert np.sqrt(np.mean(hist["tip nodes"] ** 2)) == pytest.approx(errors["tip nodes"], rel=1e-12)


def test_best_approximation_bounds_every_state(ci_disk, ci_disk_ops, disk_model):
    """disk.best_approximation, the basis's share of a reduced model's error: fields that sectors 0 and 1 of the
    model can take (one state q) are approximated to round-off in both norms; a field off the model's span is
    approximated no worse than by the state it was made from or by any other state (the projection in a norm is
    the best approximation in that norm), and not exactly."""
    model, _ = disk_model
    basis = model.sectors
    K = fem.petsc_to_scipy(fem.assemble_stiffness(ci_disk, ci_disk_ops, clamped=False))
    M = fem.petsc_to_scipy(fem.assemble_mass(ci_disk, ci_disk_ops, clamped=False))
    rng = np.random.default_rng(5)
    q = rng.standard_normal(model.r)
    inside = np.stack([basis.sector_field(q, n) for n in (0, 1)])[None]           # (1 snapshot, 2 sectors, n)
    for e in best_approximation(basis, inside, K, M).values():
        assert e < 1e-6         # the span's directions below 1e-14 of the Gram's largest eigenvalue are dropped as
        #                         round-off: a field's part along them is <= sqrt(1e-14) = 1e-7 of its norm
    fields = inside[0, :1]
    noise = rng.standard_normal(fields.shape) * (fields[0] != 0)                 # free DOFs only
    target = (fields + 0.05 * np.abs(fields).max() * noise)[None]
    best = best_approximation(basis, target, K, M)

    def error(candidate, A):
        d = target[0, 0] - candidate
        return np.sqrt(d @ (A @ d)) / np.sqrt(target[0, 0] @ (A @ target[0, 0]))
    for name, A in (("field", M), ("strain energy", K)):
        assert 0 < best[name] <= error(fields[0], A) * (1 + 1e-10)
        for _ in range(3):
            other = basis.sector_field(q + 1e-3 * np.abs(q).max() * rng.standard_normal(model.r), 0)
            assert best[name] <= error(other, A) * (1 + 1e-10)


def test_patch_load_and_its_static_correction(ci_disk, ci_disk_ops, disk_model, disk_cache):
    """The 400 N of the forced-response study spread over the boundary facets within 3 mm of node LE: the nodal
    forces have a unit resultant along e_z and none across (consistent forces of a uniform traction, round-off).
    Their reduced force is the transpose of the field rebuild (f . u_n(q) = P_n(f) . q for any q, round-off), and
    node LE's unit vector projects to the point load of ``harmonic_node_load`` (LE is a boundary node: the interface
    constraint modes vanish there). Static 0-diameter load on every sector: the reduced compliance f . u is a
    Rayleigh-Ritz lower bound of the full-order one (one sector closed on itself), and with the patch's static
    correction its error is the interface reduction's alone, of the order of the point load's (which sits on the
    boundary, where the constraint modes are exact), while without it the local field under the patch is missing
    (an error at least ten times the corrected one)."""
    model, _ = disk_model
    basis = model.sectors
    le = ci_disk.tip_names.index("LE")
    f = fem.patch_load(ci_disk, ci_disk.tip_nodes[le], 3e-3, component=2)
    resultant = f.reshape(-1, 3).sum(axis=0)
    np.testing.assert_allclose(resultant, [0.0, 0.0, 1.0], atol=1e-12, rtol=0)
    assert np.count_nonzero(f) > 3                      # spread over more than one node
    q = np.random.default_rng(4).standard_normal(model.r)
    for n in (0, 35):
        assert np.isclose(f @ basis.sector_field(q, n), basis.project(f, n) @ q, rtol=1e-12,
                          atol=1e-12 * np.abs(f) @ np.abs(basis.sector_field(q, n)))
    point = np.zeros(ci_disk.n_dofs)
    point[ci_disk.tip_dofs[le, 2]] = 1.0
    t = 0.3e-3
    np.testing.assert_allclose(harmonic_field_load(basis, point, 400.0, 4000.0, 9)(t),
                               harmonic_node_load(model.nodes, model.r, 400.0, 4000.0, 9)(t), atol=1e-12, rtol=0)
    system = fem.RepeatingSectors(ci_disk, 1, ci_disk_ops)
    P, solve = system.maps[0], fem.mumps_solver(system.K)

    def compliance_error(rom, g):
        full = g @ (P @ solve(P.T @ g))
        reduced = g @ rom.sectors.sector_field(np.linalg.solve(rom.K, harmonic_field_load(
            rom.sectors, g, 1.0, 1.0, 0)(np.pi / 2)), 0)
        assert reduced <= full * (1 + 1e-9)               # Rayleigh-Ritz
        return 1 - reduced / full

    corrected, _ = build_disk_model(ci_disk, DiskReductionConfig(tip_nodes="LE", r_c=8, r_md=0, r_cyclic=96,
                                                                 forces="none", load_patch=3e-3), ops=ci_disk_ops,
                                    cache_dir=disk_cache)
    assert corrected.sizes["r_load"] == 1 and corrected.r == model.r - 36 * 3
    e_point, e_patch = compliance_error(model, point), compliance_error(corrected, f)
    e_uncorrected = compliance_error(model, f)
    print(f"static compliance errors: point {e_point:.2e}, patch corrected {e_patch:.2e}, uncorrected "
          f"{e_uncorrected:.2e}")
    assert e_patch <= 5 * e_point                       # measured 1.6e-4 against 1.0e-4
    assert e_uncorrected >= 10 * e_patch                 # measured 3.9e-2


def test_disk_bad_input(ci_disk, disk_model):
    model, _ = disk_model
    with pytest.raises(ValueError, match="N_d"):
        harmonic_node_load(model.nodes, model.r, 400.0, 4000.0, 19)
    with pytest.raises(ValueError, match="boundary set"):
        harmonic_node_load(model.nodes, model.r, 400.0, 4000.0, 0, name="TE")
    with pytest.raises(ValueError, match="mistuning"):
        build_disk_model(ci_disk, DiskReductionConfig(tip_nodes="LE", r_c=2, r_md=0, mistuning=(1.0,) * 35))
    with pytest.raises(ValueError, match="r_cyclic"):
        build_disk_model(ci_disk, DiskReductionConfig(tip_nodes="LE", r_c=2, r_md=0, r_cyclic=100000,
                                                      forces="none"))
    with pytest.raises(ValueError, match="tip_nodes"):
        DiskReductionConfig(tip_nodes="mid")
    with pytest.raises(ValueError, match="face_shapes"):
        DiskReductionConfig(face_shapes=-1)
    with pytest.raises(ValueError, match="face_shapes must be in"):
        face_shapes(model.sectors.Pi, np.ones(model.sectors.Pi.shape[1]), 36, 10**6)


def test_disk_stress_of_a_tuned_state(ci_disk, disk_model):
    """A 0-diameter state (every sector's block alike, interface modes of k = 0 only) gives every sector the same
    field and the same von Mises stress, sector by sector through the DiskBasis (the interface rows of sector n and
    n + 1, the last wrapping to the first), to round-off; a sector at rest in a state that moves only sector 3 has
    no stress, and GNL changes the stress (Green-Lagrange's quadratic term at ~2 mm)."""
    from rotor37_rom.post.stress import disk_stress, disk_stress_summary, tip_band

    model, report = disk_model
    basis = model.sectors
    rng = np.random.default_rng(5)
    block = rng.standard_normal(basis.blocks.shape[1])
    block *= 2e-3 / np.abs(basis.Phi_s @ block).max()
    q = np.zeros(model.r)
    q[basis.blocks] = block
    k0 = np.flatnonzero(report["interface_k"] == 0)
    assert k0.size > 0
    q[basis.blocks.size + k0] = 1e-4 * rng.standard_normal(k0.size)
    fields, vm = disk_stress(ci_disk, model, q, nonlinear=True, sectors=(0, 17, 35))
    assert np.abs(fields).max() > 1e-3
    np.testing.assert_allclose(fields[1:], fields[[0, 0]], atol=1e-12 * np.abs(fields).max(), rtol=0)
    np.testing.assert_allclose(vm[1:], vm[[0, 0]], atol=1e-9 * vm.max(), rtol=0)
    _, vm_lin = disk_stress(ci_disk, model, q, nonlinear=False, sectors=(0,))
    assert np.abs(vm_lin[0] - vm[0]).max() > 1e-3 * vm.max()
    q_one = np.zeros(model.r)
    q_one[basis.blocks[3]] = block
    _, vm_one = disk_stress(ci_disk, model, q_one, sectors=(3, 10))
    assert vm_one[0].max() > 0 and vm_one[1].max() == 0.0
    # the summary of a field that loads sector 3 only: its largest is sector 3's, the others' is 0
    values = np.zeros((36,) + vm_one.shape[1:])
    values[3] = vm_one[0]
    numbers = disk_stress_summary(ci_disk, model, values, monitored=10)
    band, _ = tip_band(ci_disk, model)
    assert numbers["sector_of_max"] == 3 and numbers["vm_max"] == 0.0
    assert numbers["vm_max_all_sectors"] == vm_one[0][~band].max()
    assert numbers["ratio_yield"] == 0.0 and 0 < band.sum() < band.size
    assert numbers["sector_of_max_off_root"] == 3 and numbers["vm_max_off_root"] == 0.0
    assert 0 < numbers["vm_max_off_root_all_sectors"] <= numbers["vm_max_all_sectors"]
    with pytest.raises(ValueError, match="entries"):
        disk_stress(ci_disk, model, q[:-1])
    with pytest.raises(ValueError, match="vertices"):
        disk_stress_summary(ci_disk, model, values.max(axis=2))
    # a cell touching the junction is left out whole: a large value at its vertex farthest from the junction counts
    # for the corner, not off it
    from rotor37_rom.post.stress import ROOT_BAND, root_distance
    dist = root_distance(ci_disk, fem.cell_vertices(ci_disk))
    corner = np.flatnonzero((dist.min(axis=1) < 1e-9) & ~band)[0]
    far = int(np.argmax(dist[corner]))
    assert dist[corner, far] >= ROOT_BAND / 4                 # a ci cell reaches well away from the corner
    spike = np.zeros((36,) + vm_one.shape[1:])
    spike[0, corner, far] = 1e9
    numbers = disk_stress_summary(ci_disk, model, spike, monitored=0)
    assert numbers["vm_max"] == 1e9 and numbers["vm_max_off_root"] == 0.0


def test_disk_stress_of_the_1b_mode_peaks_at_the_blade_root(ci_disk, disk_model):
    """Where the summary says the largest stress is: the disk's lowest 0-diameter mode (the 1B family: every blade
    bending alike as a cantilever on the rim) has its largest curvature, hence its largest bending stress, at the
    root of the blade, as the first bending mode of any clamped beam, and the root corner (no fillet) concentrates
    it: the largest stress outside the tip band is in the lowest quarter of the span or within 5 mm under the hub
    cone (either side of the junction). (A point load at node LE would not do: it bends the thin LE locally, and the
    largest stress then sits just outside the tip band.) The location's numbers are the cell's centroid's, its height
    the radius less the hub cone's. Off the root corner (every cell with a vertex within ROOT_BAND of the junction left
    out) the
    largest is still the root's bending stress: in the blade, in the lowest third of the span, and below the
    corner's."""
    from rotor37_rom.post.stress import (ROOT_BAND, describe_location, disk_stress, disk_stress_summary, root_distance,
        tip_band)
    from rotor37_rom.geometry.disk import hub_radius
    import scipy.linalg

    model, _ = disk_model
    lam, V = scipy.linalg.eigh(model.K, model.M)
    first = np.flatnonzero(sector_harmonics(V, model.forces.blocks) == 0)[0]
    print(f"lowest 0-diameter mode: {np.sqrt(lam[first]) / (2 * np.pi):.0f} Hz")
    q = V[:, first] * 1e-3 / np.abs(V[model.nodes.q_index[model.nodes.row("LE", 0)], first]).max()
    _, vm = disk_stress(ci_disk, model, q, nonlinear=False, sectors=(0,))
    numbers = disk_stress_summary(ci_disk, model, vm, monitored=0)
    where = numbers["location"]
    print(f"1B, 0 diameters, 1 mm at LE: {numbers['vm_max'] / 1e6:.0f} MPa at {describe_location(where)} ({where})")
    assert where == numbers["location_all_sectors"]
    assert (where["region"] == "blade" and where["span"] <= 0.25) or -5.0 <= where["height_mm"] <= 0.0
    off = numbers["location_off_root"]
    print(f"off the root corner: {numbers['vm_max_off_root'] / 1e6:.0f} MPa at {describe_location(off)}")
    # the value is one cell's own at the vertex the location names (each cell sharing the vertex has its own), and
    # that cell is clear of the band
    vertices = fem.cell_vertices(ci_disk)
    at = np.argwhere(np.all(np.isclose(vertices, [1e-3 * off["r_mm"] * np.cos(np.radians(off["theta_deg"])),
                                                  1e-3 * off["r_mm"] * np.sin(np.radians(off["theta_deg"])),
                                                  1e-3 * off["z_mm"]], rtol=0, atol=1e-12), axis=2))
    clear = [(c, v) for c, v in at if root_distance(ci_disk, vertices[c]).min() >= ROOT_BAND]
    assert clear and max(vm[0][c, v] for c, v in clear) == numbers["vm_max_off_root"]
    assert off["region"] == "blade" and off["span"] <= 1 / 3 and off["height_mm"] > 1e3 * ROOT_BAND / 2
    assert numbers["vm_max_off_root"] < numbers["vm_max"]
    band, _ = tip_band(ci_disk, model)
    cell = int(np.argmax(np.where(band, -np.inf, vm[0].max(axis=1))))
    x = fem.cell_midpoints(ci_disk)[cell]
    assert np.isclose(where["r_mm"], 1e3 * np.hypot(x[0], x[1]), rtol=1e-12)
    assert np.isclose(where["height_mm"], 1e3 * (np.hypot(x[0], x[1]) - hub_radius(x[2])), rtol=1e-12)


def test_repeating_sectors_contact_rows_through_an_interface(ci_disk, ci_disk_ops):
    """``RepeatingSectors.contact_operators`` with a contact interface C (the full order's contact patches, issue
    #23), two sectors carried (the second turned by 2 pi / 36) and two of the 8 contact nodes (rows 1 and 6, so a
    node's row in C differs from its place among the contact rows):
    - unit rows of C at the tip DOFs give the node rows to the last bit (each entry of C P is one product by 1.0);
    - with 3 mm patches, row (s, k) of N applied to x is n_k . (C_k u_s), u_s = sector s's field, to round-off."""
    import scipy.sparse as sp

    from rotor37_rom.dynamics.casing import Casing, contact_frames

    system = fem.RepeatingSectors(ci_disk, 2, ci_disk_ops)
    casing = Casing(direction="cone", contact_nodes=(1, 6))
    tip = np.asarray(ci_disk.tip_dofs).ravel()
    unit = sp.csr_matrix((np.ones(tip.size), (np.arange(tip.size), tip)), shape=(tip.size, ci_disk.n_dofs))
    node, via = system.contact_operators(casing), system.contact_operators(casing, unit)
    assert node.labels == via.labels == ("0:tip1", "0:tip6", "1:tip1", "1:tip6")
    assert abs(node.N - via.N).max() == 0.0 and abs(node.S - via.S).max() == 0.0
    C = fem.tip_patch_interface(ci_disk, 3e-3)
    patch = system.contact_operators(casing, C)
    x = np.random.default_rng(7).standard_normal(system.keep.size)
    fields = system.fields(x)
    normals = contact_frames(ci_disk.tip_nodes[[1, 6]], casing.direction, casing.rotation_sense, casing.cone_slope)[0]
    expected = np.array([normals[j] @ (C[3 * k:3 * k + 3] @ fields[s]) for s in range(2) for j, k in enumerate((1, 6))])
    scale = np.abs(C).sum(axis=1).max() * np.abs(x).max()      # |C_k u| <= max row sum x max |u|
    assert np.abs(patch.N @ x - expected).max() <= 1e-13 * scale
    assert np.abs(patch.N @ x - node.N @ x).max() > 1e-3 * scale    # the patch is not the node
    with pytest.raises(ValueError, match="contact interface must be"):
        system.contact_operators(casing, C[:6])


def test_von_mises_at_vertices_of_a_uniform_strain(ci_disk):
    """Patch test of the vertex stress: an affine displacement u = A x is in the P2 space exactly, its strain is
    uniform, so at every vertex of every cell von Mises equals the closed form (linear: of eps = sym A; SVK Cauchy of
    F = I + A) to round-off; and the cells' vertices average to their midpoints."""
    from dolfinx import fem as dfem

    from rotor37_rom.post.recovery import svk_cauchy, von_mises

    A = 1e-3 * np.array([[0.3, -1.2, 0.5], [0.8, 0.1, -0.4], [0.2, 0.9, -0.6]])
    u = dfem.Function(ci_disk.V)
    u.interpolate(lambda x: A @ x)
    lmbda, mu = ci_disk.material.lame
    for nonlinear in (False, True):
        vm = fem.von_mises_at_vertices(ci_disk, u, nonlinear)
        exact = float(von_mises(svk_cauchy(A, lmbda, mu, nonlinear)))
        n_cells = ci_disk.mesh.topology.index_map(3).size_local
        assert vm.shape == (n_cells, 4)
        np.testing.assert_allclose(vm, exact, rtol=1e-9)
    np.testing.assert_allclose(fem.cell_vertices(ci_disk).mean(axis=1), fem.cell_midpoints(ci_disk), rtol=0,
                               atol=1e-15)


def test_root_junction_is_the_blade_root_on_the_hub_cone(ci_disk, ci_blade):
    """The line where the blade meets the rim (``fem.root_junction``): every point lies on the hub cone (the rim's
    outer surface) to the chord sagitta of the mesh's straight edges on that curved surface, L^2 / (8 r) for the
    longest junction edge L and the smallest radius r; it runs along the whole root chord (rotor37-notes: z = 0.28 ...
    43.05 mm), on the pressure and on the suction side, which are apart by the root's thickness at mid-chord; any
    point of an edge is within spacing / 2 of a sample, so ``root_distance`` is exact to 0.1 mm. A blade without a
    disk has no junction: an error."""
    from rotor37_rom.post.stress import root_distance
    from rotor37_rom.geometry.disk import hub_radius

    edges = fem.root_junction(ci_disk, spacing=None)                       # (n, 2, 3)
    J = fem.root_junction(ci_disk)
    r = np.hypot(J[:, 0], J[:, 1])
    ends = edges.reshape(-1, 3)                 # mesh vertices: on the CAD cone to OCC's tolerance (1e-7 m)
    assert np.abs(np.hypot(ends[:, 0], ends[:, 1]) - hub_radius(ends[:, 2])).max() <= 1e-7
    longest = np.linalg.norm(edges[:, 1] - edges[:, 0], axis=1).max()
    assert np.abs(r - hub_radius(J[:, 2])).max() <= longest ** 2 / (8 * r.min())
    assert J[:, 2].min() < 0.28e-3 + 0.5e-3 and J[:, 2].max() > 43.05e-3 - 0.5e-3
    sides = {name: fem.root_junction(ci_disk, faces=(name,)) for name in ("pressure", "suction")}
    for name, points in sides.items():          # each side spans the chord but for the 0.1 mm LE and TE strips
        assert points[:, 2].min() < 0.28e-3 + 0.5e-3 and points[:, 2].max() > 43.05e-3 - 0.5e-3, name
    # at mid-chord the two sides are apart: the root is several mm thick there (> 1 mm)
    mid = {name: p[np.argmin(np.abs(p[:, 2] - 20e-3))] for name, p in sides.items()}
    assert np.linalg.norm(mid["pressure"] - mid["suction"]) > 1e-3
    # any point of the line is within spacing / 2 of a sample: what root_distance's accuracy rests on
    between = edges[:, 0] + 0.37 * (edges[:, 1] - edges[:, 0])
    assert root_distance(ci_disk, between).max() <= 1e-4 * (1 + 1e-9)
    with pytest.raises(ValueError, match="no group"):
        fem.root_junction(ci_blade)
