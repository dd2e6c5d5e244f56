"""The structure turning about the machine axis (#73): the rotating cantilever against beam theory.

Reference: the uniform Euler-Bernoulli cantilever of length L turning at Omega about an axis through its root,
normal to it. Flapwise (bending along the axis) its deflection obeys EI w'''' - (N w')' = m omega^2 w with the
centrifugal tension N(x) = m Omega^2 (L^2 - x^2) / 2; lagwise (in the plane of rotation) the centrifugal force
also pushes the moving section outwards from its line, m Omega^2 w: omega_lag^2 = omega_flap^2 - Omega^2 for the
same section (the spin softening; Southwell's coefficients phi_lag = phi_flap - 1). The flapwise frequency is solved
here by Rayleigh-Ritz on 16 clamped-free modes (converged below the table's rounding) and checked against the table
of Hodges & Rutkowski, AIAA J. 19 (1981) 1459-1466 (first mode, no hub: 3.51602, 3.68165, 4.13732, 6.44954 at
Omega_bar = 0, 1, 2, 5; Omega_bar = Omega / sqrt(EI / (m L^4))).

The solid: SVK, P2 tetrahedra, L/h = 40 (square section), turning at Omega_bar = 2 (``solve_static(spin=...)``: the
nonlinear centrifugal equilibrium, then ``assemble_tangent``: K_T - Omega^2 M_P there). It departs from the beam by
shear and rotary inertia, ~(h/L)^2 pi^2 / 12 ~ 5e-4 of omega^2 for the first mode, by the prestress strain
rho Omega^2 L^2 / (2 E) = 1.3e-4 changing the geometry, and by its discretisation. Measured (outside the test) on
60x2x2 to 120x4x4: see the test's docstring.
"""

import dataclasses
import os

import numpy as np
import pytest
from dolfinx import mesh as dmesh
from mpi4py import MPI
from scipy import linalg

from rotor37_rom import fem
from rotor37_rom.forms import Material

def _clamped_free_roots(n: int) -> np.ndarray:
    """The first n roots of cos(b) cosh(b) = -1, by Newton on cos(b) + 1 / cosh(b) from (2k - 1) pi / 2."""
    roots = []
    for k in range(1, n + 1):
        b = (2 * k - 1) * np.pi / 2 + (0.304 if k == 1 else 0.0)
        for _ in range(50):
            step = (np.cos(b) + 1 / np.cosh(b)) / (-np.sin(b) - np.tanh(b) / np.cosh(b))
            b -= step
            if abs(step) < 1e-15 * b:
                break
        roots.append(b)
    return np.array(roots)


def beam_flap_frequency(spin_bar: float, hub: float = 0.0, n_modes: int = 16) -> float:
    """First flapwise frequency of the rotating uniform cantilever, in units of sqrt(EI / (m L^4)), hub radius
    ``hub`` L: Rayleigh-Ritz (an upper bound) on the first ``n_modes`` clamped-free modes, written without the
    cancellation of cosh - sinh at large b, integrals by 400-point Gauss-Legendre."""
    x, w = np.polynomial.legendre.leggauss(400)
    x, w = 0.5 * (x + 1), 0.5 * w
    d0, d1, d2 = [], [], []
    for b in _clamped_free_roots(n_modes):
        s = (np.sinh(b) - np.sin(b)) / (np.cosh(b) + np.cos(b))
        c = (np.exp(-b) + np.cos(b) + np.sin(b)) / (1 + np.exp(-2 * b) + 2 * np.exp(-b) * np.cos(b))
        grow, decay = c * np.exp(b * (x - 1)), (1 - c * np.exp(-b)) * np.exp(-b * x)   # cosh - s sinh, split
        d0.append(grow + decay - np.cos(b * x) + s * np.sin(b * x))
        d1.append(b * (grow - decay + np.sin(b * x) + s * np.cos(b * x)))
        d2.append(b * b * (grow + decay + np.cos(b * x) - s * np.sin(b * x)))
    d0, d1, d2 = map(np.array, (d0, d1, d2))
    tension = hub * (1 - x) + 0.5 * (1 - x**2)                    # N / (m Omega^2 L^2)
    K = (d2 * w) @ d2.T + spin_bar**2 * (d1 * tension * w) @ d1.T
    M = (d0 * w) @ d0.T
    return float(np.sqrt(linalg.eigh(K, M, eigvals_only=True)[0]))


def test_beam_reference_matches_hodges_and_rutkowski():
    """The beam reference reproduces the published table (5 decimals: rounding 5e-6, asserted 1e-5) and is converged
    in the number of modes: a Ritz value falls as modes are added, and 12 against 16 move it by less than the
    table's rounding."""
    for spin_bar, table in ((0.0, 3.51602), (1.0, 3.68165), (2.0, 4.13732), (5.0, 6.44954)):
        values = [beam_flap_frequency(spin_bar, n_modes=n) for n in (8, 12, 16)]
        assert abs(values[-1] - table) <= 1e-5, (spin_bar, values, table)
        assert values[0] >= values[1] >= values[2] >= values[1] - 5e-6, (spin_bar, values)


@pytest.mark.parametrize("spin_bar", [2.0])
def test_rotating_cantilever_southwell_flap_and_lag(spin_bar):
    """Southwell's coefficient phi = (omega^2 - omega_0^2) / Omega^2 of the solid's first flapwise mode against the
    beam's at the same Omega_bar, and the lagwise mode lower by exactly the spin softening (phi_flap - phi_lag = 1).

    Tolerances from the solid's departure from Euler-Bernoulli (module docstring) and its mesh convergence, measured
    outside the test at L/h = 40 (relative errors of omega_0 / phi_flap, and phi_flap - phi_lag - 1):
    60x2x2 (this test) 1.6e-3 / 1.2e-3, 3.0e-4; 120x2x2 1.1e-3 / 6.8e-4, 1.6e-5; 60x4x4 1.5e-3 / 8.2e-4, -2.4e-4;
    120x4x4 9.6e-4 / 3.0e-4, -6.3e-4 (and at L/h = 80, 120x2x2: 9.9e-4 / 4.0e-4, -5.0e-4). The error falls with the
    mesh toward the (h/L)^2 ~ 6e-4 of the three-dimensional solid; asserted: omega_0 2e-3, phi_flap 3e-3 (2.5x this
    mesh's), the split 2e-3 (3x the largest on any mesh)."""
    L, h = 1.0, 0.025
    material = Material(E=1.0e7, nu=0.3, rho=1.0, sigma_y=1.0)
    msh = dmesh.create_box(MPI.COMM_WORLD, [np.array([0.0, -h / 2, -h / 2]), np.array([L, h / 2, h / 2])],
                           [60, 2, 2], dmesh.CellType.tetrahedron)
    clamp = dmesh.locate_entities_boundary(msh, 2, lambda x: np.isclose(x[0], 0.0))
    tags = dmesh.meshtags(msh, 2, np.sort(clamp), np.full(clamp.size, 1, np.int32))
    sector = fem.create_sector_from_mesh(msh, None, tags, {"clamp": 1}, material, degree=2,
                                         source="rotating cantilever")
    unit = h * np.sqrt(material.E / (12 * material.rho)) / L**2          # sqrt(EI / (m L^4))
    spin = spin_bar * unit
    M = fem.assemble_mass(sector)
    K = fem.assemble_stiffness(sector)

    def flap_and_lag(K):
        """(flapwise, lagwise) first frequencies of K against M: the mode bending along the axis (z), the other in
        the plane of rotation (y)."""
        omega, vectors = fem.solve_eigenproblem(K, M, 2)
        flap = [k for k, v in enumerate(vectors) if np.abs(v.array[2::3]).max() > np.abs(v.array[1::3]).max()]
        assert len(flap) == 1
        return omega[flap[0]], omega[1 - flap[0]]

    rest = flap_and_lag(K)                       # equal in the beam; the tetrahedra's diagonals split them by 1e-4
    K.destroy()
    assert abs(rest[0] / unit / beam_flap_frequency(0.0) - 1) <= 2e-3
    res = fem.solve_static(sector, spin=spin, n_steps=1, rtol=1e-10)
    K_spin = fem.assemble_tangent(sector, res.u.x.array, None, spin)
    turning = flap_and_lag(K_spin)
    K_spin.destroy()
    M.destroy()
    phi_flap, phi_lag = ((turning[i] ** 2 - rest[i] ** 2) / spin**2 for i in (0, 1))
    beam = (beam_flap_frequency(spin_bar) ** 2 - beam_flap_frequency(0.0) ** 2) / spin_bar**2
    print(f"Omega_bar {spin_bar}: phi_flap {phi_flap:.5f} (beam {beam:.5f}), phi_lag {phi_lag:.5f}, "
          f"difference {phi_flap - phi_lag:.5f}")
    assert abs(phi_flap / beam - 1) <= 3e-3
    assert abs(phi_flap - phi_lag - 1) <= 2e-3


def test_crossings_and_tracking_closed_form():
    """``model.campbell`` on modes that follow Southwell's law exactly, omega_k^2 = a_k + b_k Omega^2: each crossing
    with omega = e Omega is sqrt(a / (e^2 - b)) to round-off from any bracket, and two modes whose frequencies cross
    keep their names (followed by their shapes, not their rank)."""
    from rotor37_rom.model.campbell import engine_order_crossings, track_modes

    a, b = np.array([5400.0**2, 5600.0**2]), np.array([5.7, 1.2])          # mode 1 overtakes mode 2
    speeds = np.linspace(0.0, 2000.0, 5)
    shapes = np.eye(6)[:, :2]
    freqs, vectors = [], []
    for W in speeds:
        w = np.sqrt(a + b * W**2)
        order = np.argsort(w)
        freqs.append(w[order])
        vectors.append(-3.0 * shapes[:, order])                              # sign and scale do not matter
    omega, worst = track_modes(freqs, vectors)
    np.testing.assert_allclose(omega, np.sqrt(a + b * speeds[:, None] ** 2), rtol=1e-15)
    assert np.all(worst == 1.0)
    crossings = engine_order_crossings(speeds, omega, (3, 4, 5))
    expected = sorted((float(np.sqrt(a[k] / (e * e - b[k]))), k, e) for k in range(2) for e in (3, 4, 5)
                      if np.sqrt(a[k] / (e * e - b[k])) <= 2000.0)
    assert [(c["mode"], c["order"]) for c in crossings] == [(k, e) for _, k, e in expected]
    for c, (W, _, _) in zip(crossings, expected):
        assert abs(c["speed"] - W) <= 1e-12 * W and c["frequency"] == c["order"] * c["speed"]


def test_campbell_of_the_ci_blade(ci_blade, tmp_path):
    """The turning ci blade (``run_campbell``): at rest its modes are the clamped ones (the same solve); each 1B
    crossing is where the prestressed blade's 1B, solved again at that speed, equals e Omega, to the iteration's
    0.01 rad/s (the Southwell iteration contracts by S'/(e^2 - S) ~ 0.05 a step: the distance to the fixed point is
    below the last step); 1B is stiffened by rotation; the second mode (1T) meets neither order below 2,000 rad/s."""
    from rotor37_rom import fem
    from rotor37_rom.studies.campbell import CampbellConfig, run_campbell

    sector = ci_blade
    config = CampbellConfig(preset="ci", speeds=(0.0, 2000.0, 3), n_modes=2, orders=(4, 5), out=tmp_path)
    result = run_campbell(config, sector)
    rest = fem.compute_clamped_modes(sector, 2).omega
    np.testing.assert_allclose(result.omega[0], rest, rtol=1e-9)
    k1b = result.labels.index("1B")
    assert result.omega[-1, k1b] > result.omega[0, k1b]
    found = result.crossings
    assert sorted((c["mode"], c["order"]) for c in found) == [(k1b, 4), (k1b, 5)]
    for c in found:
        assert c["refined"] > 0
        w = fem.rotating_modes(sector, c["speed"], 2)[0][k1b]
        print(f"1B/EO{c['order']}: {c['speed']:.2f} rad/s; 1B there {w:.2f} rad/s against e Omega {c['frequency']:.2f}")
        assert abs(w / c["order"] - c["speed"]) <= 0.01
    assert (tmp_path / "campbell.png").is_file() and (tmp_path / "summary.json").is_file()
    # with Coriolis: a gyroscopic coupling only lowers the fundamental frequency (it repels the modes), so 1B at
    # 2,000 rad/s and its EO4 crossing come down, by little on a blade (measured: 0.09 and 0.02 rad/s)
    gyro = run_campbell(dataclasses.replace(config, speeds=(0.0, 2000.0, 2), n_modes=1, orders=(4,), coriolis=True,
                                            out=tmp_path / "coriolis"), sector)
    assert gyro.omega[-1, 0] <= result.omega[-1, k1b]
    (eo4,) = gyro.crossings
    assert eo4["refined"] > 0 and eo4["speed"] <= next(c["speed"] for c in found if c["order"] == 4) + 0.01


def test_coriolis_splits_a_spinning_shaft_by_twice_the_speed():
    """Coriolis (``forms.coriolis``, ``fem.reduced_coriolis``, ``model.campbell.gyroscopic_frequencies``): a slender
    square rod on the machine axis (clamped at z = 0, L/h = 40) turning at Omega. Seen from the ground its bending
    frequency omega_0 does not change (a Euler-Bernoulli shaft has no gyroscopic effect); seen from the turning frame
    the whirls are omega_0 - Omega and omega_0 + Omega, forward and backward, exactly: the turning frame's
    M u'' + Omega G_1 u' + (K - Omega^2 M_P) u = 0 has them as roots for an isotropic section. Without Coriolis both
    are sqrt(omega_0^2 - Omega^2) (no split). The rod's rotary inertia (Rayleigh) splits a spinning shaft by
    ~(h/L)^2 omega_0 ~ 6e-4 omega_0, the tetrahedra's anisotropy its two bending planes by ~1e-4: each whirl is
    asserted to 2e-3 omega_0 at Omega = 0.3 omega_0, so the split to 4e-3 omega_0 = 1.3e-2 of its 2 Omega (measured:
    whirls 6e-5 and 8e-5 of omega_0 off, split / Omega = 1.99952). A Coriolis force without its factor 2 splits by
    Omega."""
    from rotor37_rom.model.campbell import gyroscopic_frequencies

    L, h = 1.0, 0.025
    material = Material(E=1.0e7, nu=0.3, rho=1.0, sigma_y=1.0)
    msh = dmesh.create_box(MPI.COMM_WORLD, [np.array([-h / 2, -h / 2, 0.0]), np.array([h / 2, h / 2, L])],
                           [2, 2, 60], dmesh.CellType.tetrahedron)
    clamp = dmesh.locate_entities_boundary(msh, 2, lambda x: np.isclose(x[2], 0.0))
    tags = dmesh.meshtags(msh, 2, np.sort(clamp), np.full(clamp.size, 1, np.int32))
    sector = fem.create_sector_from_mesh(msh, None, tags, {"clamp": 1}, material, degree=2, source="shaft")
    omega0 = fem.rotating_modes(sector, 0.0, 2)[0]
    spin = 0.3 * omega0.mean()
    omega, V = fem.rotating_modes(sector, spin, 6, prestress=False)      # on the axis: no centrifugal load
    np.testing.assert_allclose(omega[:2], np.sqrt(omega0**2 - spin**2), rtol=2e-3)   # no Coriolis: no split
    Gr = fem.reduced_coriolis(sector, V)
    np.testing.assert_allclose(Gr, -Gr.T, atol=1e-12 * np.abs(Gr).max())
    whirls = gyroscopic_frequencies(np.diag(omega**2), np.eye(6), spin * Gr)[:2]
    print(f"omega_0 {omega0.mean():.4f}, Omega {spin:.4f}: whirls {whirls} against {omega0.mean() - spin:.4f}, "
          f"{omega0.mean() + spin:.4f}; split / Omega {(whirls[1] - whirls[0]) / spin:.5f}")
    np.testing.assert_allclose(whirls, omega0.mean() + np.array([-spin, spin]), rtol=0, atol=2e-3 * omega0.mean())
    assert abs((whirls[1] - whirls[0]) / spin - 2.0) <= 4e-3 / 0.3


def test_bryans_factor_of_a_free_ring():
    """Coriolis on one cyclic sector (``CyclicOperators.reduced_operator``): a free thin steel ring (mean radius R =
    0.1 m, section 2 x 4 mm radial x axial, h/R = 0.02; 36 sectors, nothing clamped) turning at Omega. Its
    in-plane inextensional n-wave (harmonic index k = n) seen in the turning frame splits into two travelling waves
    by exactly 4 n Omega / (n^2 + 1) when only Coriolis acts (thin-ring theory: m A'' - 2 c B' + k A = 0 and
    m B'' + 2 c A' + k B = 0 with c / m = 2 n Omega / (n^2 + 1); roots omega = sqrt(omega_n^2 + (c/m)^2) +- c/m):
    its standing pattern precesses against the ring at kappa Omega, Bryan's factor kappa = 2 / (n^2 + 1) (G. H.
    Bryan, On the beats in the vibrations of a revolving cylinder or bell, Proc. Camb. Phil. Soc. 7 (1890) 101-111).
    The real cos/sin copies of one index carry both waves: T_k^T diag(G_1, G_1) T_k couples them. The solid departs
    from the inextensional thin ring by the ratio of the n-wave's bending to membrane stiffness, eps = (h/R)^2 n^2 /
    12; asserted to 3 eps (measured -1.0e-4, -3.2e-4, -6.2e-4 for n = 2, 3, 4: 4x smaller at h/R = 0.01, 4x larger
    at 0.04, the same to 4 digits on a mesh twice as fine). The frequency omega_n = sqrt(EI / (rho A R^4))
    n (n^2 - 1) / sqrt(n^2 + 1) to the same bound (measured -1.6e-4 ... -8.8e-4). Without Coriolis the pair stays
    one double frequency, to the eigen-solver's tolerance. Broken on purpose: a Coriolis force without its factor 2
    halves the split (fails by 0.5)."""
    from rotor37_rom.model.campbell import gyroscopic_frequencies

    R, radial, axial = 0.1, 2e-3, 4e-3
    ring = fem.create_ring_sector(R, radial, axial, n_sectors=36, size=1e-3)
    ops = fem.create_svk_operators(ring)
    cyclic = fem.CyclicOperators(ring, fem.assemble_stiffness(ring, ops), fem.assemble_mass(ring, ops))
    G = fem.assemble_coriolis(ring, ops)
    E, rho = ring.material.E, ring.material.rho
    with pytest.raises(ValueError, match="free .* rigid-body"):
        cyclic.modes(1, 2)
    with pytest.raises(ValueError, match="free .* not unique"):
        fem.centrifugal_state(ring, 100.0, ops)
    for n in (2, 3, 4):
        eps = (radial / R) ** 2 * n ** 2 / 12
        modes = cyclic.modes(n, 4)
        axial_share = [np.sum(a.x.array.reshape(-1, 3)[:, 2] ** 2) / np.sum(a.x.array ** 2) for a in modes.a]
        i = 2 * int(np.argmin(axial_share[::2]))               # the in-plane pair (the others bend out of plane)
        assert axial_share[i] < 1e-2 and axial_share[i + 1] < 1e-2
        w = modes.omega
        assert abs(w[i + 1] - w[i]) <= 1e-7 * w[i]                # no Coriolis, no split
        thin = np.sqrt(E * axial * radial ** 3 / 12 / (rho * radial * axial * R ** 4)) * n * (n ** 2 - 1) / np.sqrt(
            n ** 2 + 1)
        Gr = cyclic.reduced_operator(G, modes)
        np.testing.assert_allclose(Gr, -Gr.T, atol=1e-12 * np.abs(Gr).max())
        spin = 1e-3 * w[i]
        f = gyroscopic_frequencies(np.diag(w ** 2), np.eye(w.size), spin * Gr)
        pair = np.sort(f[np.argsort(np.abs(f - w[i]))[:2]])
        kappa = (pair[1] - pair[0]) / spin / (2 * n)
        print(f"n = {n}: omega {w[i]:.3f} rad/s ({w[i] / thin - 1:+.2e} from the thin ring), Bryan's factor "
              f"{kappa:.6f} against {2 / (n ** 2 + 1):.6f} ({kappa * (n ** 2 + 1) / 2 - 1:+.2e}; "
              f"3 eps = {3 * eps:.1e})")
        assert abs(w[i] / thin - 1) <= 3 * eps
        assert abs(kappa * (n ** 2 + 1) / 2 - 1) <= 3 * eps
    cyclic.destroy()


def test_prestressed_cyclic_families_equal_the_whole_disk():
    """The turning disk on one sector (``fem.rotating_cyclic_operators``): an annular steel plate (0.1-0.2 m, 4 mm,
    clamped at the bore, 8 sectors) at 1,000 rad/s. The centrifugal equilibrium is solved once on the sector as a
    harmonic-index-0 field (``centrifugal_state``: Newton on T_0^T r(T_0 x)); the whole plate assembled from 8 turned
    copies of the sector (``disk.symmetry.assemble_full_structure``'s numbering, not T_0) is in equilibrium there,
    to the Newton tolerance (the sector alone, faces free, is 1.6 of the load off: the faces carry the hoop stress).
    Then every family k = 0 ... 4 of K_T(u_c) - Omega^2 M_P is the whole plate's spectrum of the same operator
    assembled, to 1e-8 (both solvers to 1e-12; round-off of two assembly orders); the prestress raises the lowest
    frequency of each family (geometric stiffening beats spin softening for a disk's bending). Broken on purpose:
    the state taken as the projected vector itself (u = x, the right face left at zero, not T_0 x): Newton stalls
    at 0.46 of the load (a RuntimeError, no state is returned)."""
    import ufl
    from dolfinx import fem as dfem
    from scipy.sparse import linalg as splinalg

    from rotor37_rom import forms
    from rotor37_rom.disk.symmetry import assemble_full_structure, harmonic_indices, to_global_frame

    spin, N = 1000.0, 8
    plate = fem.create_annular_sector(0.1, 0.2, 4e-3, n_sectors=N, size=0.012, layers=1)
    ops = fem.create_svk_operators(plate)
    cyclic, u = fem.rotating_cyclic_operators(plate, spin, ops)
    ops.u.x.array[:] = u.x.array
    f_int = fem.assemble_vector(ops.f_int).array.copy()
    f_c = fem.assemble_vector(dfem.form(forms.centrifugal_force(ops.u, ufl.TestFunction(plate.V),
                                                                ops.constants["rho"],
                                                                dfem.Constant(plate.mesh, spin)))).array.copy()
    clamped = plate.clamp_bc.dof_indices()[0]
    f_int[clamped] = f_c[clamped] = 0.0
    dofs = np.arange(plate.n_dofs).reshape(-1, 3)
    K_full, M_full, index = assemble_full_structure(fem.petsc_to_scipy(cyclic.K), fem.petsc_to_scipy(cyclic.M),
                                                    plate.cyclic, dofs)
    residual, load = np.zeros(K_full.shape[0]), np.zeros(K_full.shape[0])
    for s in range(N):
        np.add.at(residual, index[s], to_global_frame(f_int - f_c, dofs, s * plate.cyclic.angle))
        np.add.at(load, index[s], to_global_frame(f_c, dofs, s * plate.cyclic.angle))
    print(f"whole plate: |r| / |f_c| = {np.linalg.norm(residual) / np.linalg.norm(load):.1e}; the sector alone "
          f"{np.linalg.norm(f_int - f_c) / np.linalg.norm(f_c):.2f}")
    assert np.linalg.norm(residual) <= 1e-9 * np.linalg.norm(load)
    families = [cyclic.modes(k, 5).omega for k in harmonic_indices(N)]
    covered = min(w.max() for w in families)
    union = np.sort(np.concatenate(families))
    union = union[union < covered * (1 - 1e-6)]
    lam = splinalg.eigsh(K_full.tocsc(), union.size + 4, M_full.tocsc(), sigma=0.0, which="LM",
                         return_eigenvectors=False, tol=1e-12)
    full = np.sqrt(np.sort(lam))[:union.size]
    print("cyclic", union[:8], "whole", full[:8])
    np.testing.assert_allclose(union, full, rtol=1e-8)
    at_rest, _ = fem.rotating_cyclic_operators(plate, 0.0, ops)
    for k, w in zip(harmonic_indices(N), families):
        assert w[0] > at_rest.modes(k, 1).omega[0]
    for c in (cyclic, at_rest):
        c.destroy()


def test_engine_order_aliasing_closed_form():
    """``model.campbell.excited_index`` / ``excited_direction`` on 36 sectors: e = 2 excites k = 2 backward (the
    ground-fixed pattern moves against the rotation in the turning frame), e = 34 = 36 - 2 the same index forward,
    e = 36 and 18 standing waves of k = 0 and 18, e = 40 k = 4 backward, e = 71 k = 1 forward."""
    from rotor37_rom.model.campbell import excited_direction, excited_index

    cases = {2: (2, "backward"), 34: (2, "forward"), 36: (0, "standing"), 18: (18, "standing"), 40: (4, "backward"),
             71: (1, "forward"), 0: (0, "standing")}
    for e, (k, direction) in cases.items():
        assert (excited_index(e, 36), excited_direction(e, 36)) == (k, direction)
    with pytest.raises(ValueError, match="engine order"):
        excited_index(-1, 36)


def test_disk_campbell_on_a_ring(tmp_path):
    """The disk Campbell study (``run_disk_campbell``) on the free ring of ``test_bryans_factor_of_a_free_ring``,
    spin softening alone (a free ring has no centrifugal equilibrium to solve on k = 0: its rigid-body motions).
    Without Coriolis an in-plane mode of the ring is (but for 2e-6 of its mass: the tetrahedra are not
    mirror-symmetric through the mid-plane) all motion normal to the axis, so K - Omega^2 M_P shifts it by
    -p Omega^2 with p = phi^T M_P phi, the same shape to O(Omega^4): omega^2 = omega_0^2 - p Omega^2, and the
    crossings, on the grid (omega^2 linear in Omega^2) and then iterated on the ring (``refine``), are
    omega_0 / sqrt(e^2 + p), both to 1e-7 (the eigen-solver's accuracy on this free thin ring, stiff in extension
    and soft in bending: the two members of a double mode differ by 2e-9 of omega^2, two solves of the same
    operator by 1e-8), each on the index the order excites (EO38 backward and EO34 forward on k = 2). With Coriolis
    the waves split by 4 n Omega / (n^2 + 1) (inextensional ring with spin softening: omega = sqrt(omega_0^2 -
    Omega^2 + (c/m)^2) +- c/m), to the 3 eps of the Bryan test, and the
    backward wave is the higher in the turning frame (the root with z = A + iB ~ e^{-i omega t}: ring theory), which
    checks the direction each wave is named by. Broken on purpose: ``travelling_direction`` with the sign of its
    cross term flipped names them the other way (fails at the direction assertion)."""
    from rotor37_rom.studies.disk_campbell import DiskCampbellConfig, run_disk_campbell

    R, radial = 0.1, 2e-3
    ring = fem.create_ring_sector(R, radial, 4e-3, n_sectors=36, size=1e-3)
    plain = run_disk_campbell(DiskCampbellConfig(speeds=(0.0, 80.0, 2), families=(2, 3), n_modes=2,
                                                 orders=(3, 33, 34, 38), prestress=False, refine=1e-6,
                                                 out=tmp_path / "a"),
                              sector=ring)
    w0 = plain.omega[0, :, 0]
    cyclic = fem.CyclicOperators(ring)
    M_P = fem.assemble_spin_softening(ring)
    share = []                       # phi^T M_P phi: 1 - 2e-6 (the Kuhn tetrahedra are not mirror-symmetric in z)
    for k in (2, 3):
        modes = cyclic.modes(k, 2)
        share.append(cyclic.reduced_operator(M_P, modes)[0, 0])
    share = np.array(share)
    assert np.all(np.abs(share - 1) < 1e-4)
    np.testing.assert_allclose(plain.omega[:, :, 0] ** 2, w0 ** 2 - share * plain.speeds[:, None] ** 2, rtol=1e-7)
    expected = {(2, 38, "backward"): w0[0] / np.sqrt(38 ** 2 + share[0]),
                (2, 34, "forward"): w0[0] / np.sqrt(34 ** 2 + share[0]),
                (3, 33, "forward"): w0[1] / np.sqrt(33 ** 2 + share[1])}
    found = {(c["family"], c["order"], c["direction"]): c["speed"] for c in plain.crossings if c["mode"] == 1}
    assert set(expected) <= set(found)
    for key, speed in expected.items():
        assert abs(found[key] / speed - 1) <= 1e-7, (key, found[key], speed)
    assert all(c["refined"] > 0 for c in plain.crossings)      # iterated on the ring (Southwell), settled
    assert all(c["order"] != 3 for c in plain.crossings)        # EO3 never reaches k = 3 (2,077 rad/s) by 80 rad/s
    spin = 40.0
    turning = run_disk_campbell(DiskCampbellConfig(speeds=(0.0, spin, 2), families=(2, 3, 4), n_modes=2,
                                                   orders=(2,), coriolis=True, prestress=False, out=tmp_path / "b"),
                                sector=ring)
    for f, n in enumerate((2, 3, 4)):
        eps = (radial / R) ** 2 * n ** 2 / 12
        split = turning.backward[-1, f, 0] - turning.forward[-1, f, 0]
        print(f"n = {n}: forward {turning.forward[-1, f, 0]:.3f}, backward {turning.backward[-1, f, 0]:.3f} rad/s; "
              f"split / (4 n Omega / (n^2 + 1)) = {split / (4 * n * spin / (n * n + 1)):.6f}")
        assert split > 0                                          # the backward wave is the higher
        assert abs(split / (4 * n * spin / (n * n + 1)) - 1) <= 3 * eps
    assert (tmp_path / "b" / "zzenf.png").exists() and (tmp_path / "b" / "campbell_disk.png").exists()
    row = turning.zzenf["orders"][0]
    assert (row["index"], row["direction"], row["nearest_mode"]) == (2, "backward", 1)
    np.testing.assert_allclose(row["margin"], turning.backward[-1, 0, 0] / (2 * spin) - 1, rtol=1e-12)


@pytest.fixture(scope="module")
def turning_rom(ci_blade, ci_ops, tmp_path_factory):
    """The ci blade's reduced model that turns: r_c = 8, the centrifugal states at 1,000 and 2,000 rad/s and the
    first 2 modes of the blade turning at 2,000 rad/s in its basis (r = 36)."""
    from rotor37_rom.reduction.builder import ReductionConfig, build_reduced_model

    config = ReductionConfig(r_c=8, r_md=0, global_md_modes=0, forces="intrusive", spin_snapshots=(1000.0, 2000.0),
                             spin_modes=2)
    model, report = build_reduced_model(ci_blade, config, ops=ci_ops, cache_dir=tmp_path_factory.mktemp("spin"))
    return model


def test_turning_rom_is_the_full_order_at_its_snapshots(turning_rom, ci_blade, ci_ops, tmp_path):
    """A reduced model that turns (``model.rotating``; #73): M q'' + (K - Omega^2 M_P) q + g(q) = Omega^2 F_c with M_P =
    V^T M_P V, F_c = V^T rho P X (the centrifugal force is linear in u: reduced exactly) on a basis holding the
    full-order centrifugal states at 1,000 and 2,000 rad/s. Galerkin: where the full-order state is in the span, the
    projected residual vanishes there, so the reduced equilibrium is the full-order one: its tip displacement equals
    ``fem.solve_static(spin=...)``'s to 1e-8 (both Newtons to 1e-10; measured 2e-10) at both speeds (not between
    them: 2e-5 at 1,500 rad/s, ``bench_rotating_rom``). There the reduced tangent K + dg/dq - Omega^2 M_P is V^T
    (K_T(u_c) - Omega^2 M_P) V exactly, so its frequencies bound the full order's from above (Rayleigh-Ritz; to 1e-9
    for the eigen-solvers), and the 2 turning modes in the basis are exact at 2,000 rad/s (1e-8). The rotation
    terms: M_P symmetric positive semi-definite, G skew; the file keeps them; a speed past the snapshots, a negative
    one and a model at rest are refused. Broken on purpose: the model without its spin softening (M_P = 0) misses
    the full-order state at 1,000 rad/s by 1.4e-3 (fails)."""
    from rotor37_rom.model.reduced import load_reduced_model, save_reduced_model
    from rotor37_rom.model.rotating import centrifugal_equilibrium, check_spin, rotating_modes

    model = turning_rom
    terms = model.rotation
    assert model.sizes["r_spin"] == 4 and model.r == 24 + 8 + 4
    np.testing.assert_allclose(terms.G, -terms.G.T, atol=1e-14 * np.abs(terms.G).max())
    np.testing.assert_allclose(terms.M_P, terms.M_P.T, atol=1e-14 * np.abs(terms.M_P).max())
    assert np.linalg.eigvalsh(terms.M_P).min() >= -1e-12 * np.abs(terms.M_P).max()
    tip, rows = ci_blade.tip_dofs.ravel(), model.nodes.q_index.ravel()
    for spin in terms.speeds:
        state = fem.solve_static(ci_blade, spin=spin, n_steps=2, ops=ci_ops).u.x.array
        q_c = centrifugal_equilibrium(model, spin)
        error = np.abs(q_c[rows] - state[tip]).max() / np.abs(state[tip]).max()
        w_full, _ = fem.rotating_modes(ci_blade, spin, 4, ci_ops, state=state)
        w_rom, _ = rotating_modes(model, spin, q_c=q_c)
        print(f"{spin:.0f} rad/s: tip state {error:.1e} from the full order; frequencies "
              f"{np.array2string(w_rom[:4] / w_full - 1, precision=2)} from it")
        assert error <= 1e-8
        assert np.all(w_rom[:4] >= w_full * (1 - 1e-9))
    np.testing.assert_allclose(w_rom[:2], w_full[:2], rtol=1e-8)
    saved = load_reduced_model(save_reduced_model(model, tmp_path / "turning.npz"))
    np.testing.assert_array_equal(saved.rotation.G, terms.G)
    assert saved.rotation.top_speed == 2000.0
    for spin, message in ((2000.5, "outside this reduced model's range 0 ... 2000"), (-1.0, "finite speed >= 0")):
        with pytest.raises(ValueError, match=message):
            check_spin(model, spin)
    with pytest.raises(ValueError, match="built at rest"):
        check_spin(dataclasses.replace(model, rotation=None), 100.0)


def test_the_integrator_turns_the_reduced_model(turning_rom):
    """A turning scheme (``CentralDifference(rotation=Rotation())``): Omega^2 (F_c + M_P q) joins each step's force
    (explicitly, as g). Started by default at the model's centrifugal state at 2,000 rad/s (no casing, no damping)
    the run stays there: to 1e-8 of the state over 4,000 steps (the state's Newton residual is 1e-10 of the load;
    measured 2e-10). Started there plus a small displacement eps along the first mode of the turning tangent
    K + dg/dq(q_c) - Omega^2 M_P, its modal coordinate follows the central-difference oscillator of that mode
    exactly, cos(omega_h t) with omega_h = (2/h) asin(omega_1 h/2), but for the O(eps) nonlinear remainder: below
    1e-4 at eps = 1 micron at the tip (measured 3e-6) and doubling with eps (ratio in [1.5, 2.5]). Broken on
    purpose: the force without its spin softening (F_c alone) leaves the state by 1.5e-2 (fails at the first
    assertion)."""
    from rotor37_rom.dynamics.explicit import CentralDifference, simulate
    from rotor37_rom.dynamics.turning import Rotation
    from rotor37_rom.model.rotating import centrifugal_equilibrium, rotating_stiffness

    model, spin, n = turning_rom, 2000.0, 4000
    q_c = centrifugal_equilibrium(model, spin)
    scheme = CentralDifference(model, nonlinear=True, safety=0.5, damping=False, rotation=Rotation())
    h = scheme.h
    rest = simulate(scheme, [spin], None, n_steps=n, record_q=True)           # from its centrifugal state
    drift = np.abs(rest.records_q[0] - q_c[:, None]).max() / np.abs(q_c).max()
    M = 0.5 * (model.M + model.M.T)
    w2, V = linalg.eigh(rotating_stiffness(model, spin, q_c), M)
    phi = V[:, 0]
    omega_h = 2.0 / h * np.arcsin(np.sqrt(w2[0]) * h / 2.0)
    errors = []
    for scale in (1.0, 2.0):
        eps = scale * 1e-6 / np.abs(phi[model.nodes.q_index.ravel()]).max()
        start = (q_c + eps * phi, q_c + eps * phi * np.cos(omega_h * h))    # the discrete oscillator's two steps
        Q = simulate(scheme, [spin], None, n_steps=n, initial=start, record_q=True).records_q[0]
        y = phi @ M @ (Q - q_c[:, None]) / eps
        errors.append(np.abs(y - np.cos(omega_h * h * np.arange(Q.shape[1]))).max())
    print(f"drift {drift:.1e}; first mode {np.sqrt(w2[0]):.2f} rad/s, modal coordinate off the oscillator by "
          f"{errors[0]:.1e} (eps) and {errors[1]:.1e} (2 eps)")
    assert drift <= 1e-8
    assert errors[0] <= 1e-4 and 1.5 <= errors[1] / errors[0] <= 2.5
    with pytest.raises(ValueError, match="outside this reduced model's range"):
        simulate(scheme, [2500.0], None, n_steps=2)


def test_a_turning_linear_scheme_is_the_prestressed_central_difference(turning_rom):
    """Without GNL a turning scheme is the blade linearised about its centrifugal state (``dynamics.turning``): the
    step's force Omega^2 (F_c + M_P q) - g(q_c) - J_c (q - q_c) makes the explicit scheme the central difference of
    M y'' + (K + J_c - Omega^2 M_P) y = 0, y = q - q_c, exactly. So (no damping, 2,000 rad/s) the run started by
    default at q_c stays there, and a displacement eps along the first prestressed mode follows the discrete
    oscillator cos(omega_h t), omega_h = (2/h) asin(omega_1 h / 2), to round-off: the only error is q_c's Newton
    residual (1e-10 of the load, i.e. ~1e-10 |q_c| / eps of the mode: 2e-9 at eps = 10 microns) and the 4,000 steps'
    rounding; 1e-7 allows both. The scheme's step limit is the prestressed tangent's at the model's top speed (its
    1B is a third stiffer than at rest). Broken on purpose: the force without - J_c (q - q_c) (the spin softening
    alone: no stiffening) follows the mode at rest and fails by O(1)."""
    from rotor37_rom.dynamics.explicit import CentralDifference, highest_frequency, simulate
    from rotor37_rom.dynamics.turning import Rotation
    from rotor37_rom.model.rotating import centrifugal_equilibrium, rotating_stiffness

    model, spin, n = turning_rom, 2000.0, 4000
    scheme = CentralDifference(model, nonlinear=False, safety=0.5, damping=False, rotation=Rotation())
    K_T = rotating_stiffness(model, spin)
    assert scheme.omega_max == pytest.approx(max(highest_frequency(model.M, model.K),
                                                 highest_frequency(model.M, K_T)), rel=1e-12)
    q_c = centrifugal_equilibrium(model, spin)
    still = simulate(scheme, [spin], None, n_steps=n, record_q=True).records_q[0]
    drift = np.abs(still - q_c[:, None]).max() / np.abs(q_c).max()
    M = 0.5 * (model.M + model.M.T)
    w2, V = linalg.eigh(K_T, M)
    phi, h = V[:, 0], scheme.h
    omega_h = 2.0 / h * np.arcsin(np.sqrt(w2[0]) * h / 2.0)
    eps = 1e-5 / np.abs(phi[model.nodes.q_index.ravel()]).max()
    start = (q_c + eps * phi, q_c + eps * phi * np.cos(omega_h * h))
    Q = simulate(scheme, [spin], None, n_steps=n, initial=start, record_q=True).records_q[0]
    error = np.abs(phi @ M @ (Q - q_c[:, None]) / eps - np.cos(omega_h * h * np.arange(Q.shape[1]))).max()
    w_rest = np.sqrt(linalg.eigh(model.K, M, eigvals_only=True)[0])
    print(f"drift {drift:.1e}; first prestressed mode {np.sqrt(w2[0]):.1f} rad/s (at rest {w_rest:.1f}), off the "
          f"discrete oscillator by {error:.1e}")
    assert drift <= 1e-8
    assert error <= 1e-7


def test_the_running_clearance_is_measured_from_the_centrifugal_state(turning_rom):
    """The clearance's reference (``Rotation.clearance``), on a round casing (no bumps, no friction, radial normals)
    at 2,000 rad/s, the blade linearised about its centrifugal state q_c: 'running' measures c0 and the records from
    the running blade, so a run started at q_c never touches a casing c0 away and records 0 (to the round-off of q_c's
    equilibrium); 'rest' measures both from the blade at rest, so a casing at half the tip's smallest radial growth
    (N q_c) is met at the first step: the records start at N q_c exactly, the pushed nodes are on the casing after
    it, u_r = c0, and no record passes it (the active set's gaps closed to 1e-14 m) while the blade rebounds. Broken
    on purpose: without the records' offset the running run records N q_c (fails at the first assertion)."""
    from rotor37_rom.dynamics.casing import Casing, contact_matrices
    from rotor37_rom.dynamics.explicit import CentralDifference, simulate
    from rotor37_rom.dynamics.turning import Rotation
    from rotor37_rom.model.rotating import centrifugal_equilibrium

    model, spin, n = turning_rom, 2000.0, 400
    q_c = centrifugal_equilibrium(model, spin)
    N = contact_matrices(model.nodes, model.r, Casing(direction="radial"))[0]
    growth = N @ q_c
    assert growth.min() > 0                                   # the tip grows outwards
    c0 = 0.5 * growth.min()
    casing = Casing(c0=c0, h_b=0.0, mu=0.0, direction="radial")
    runs = {}
    for clearance in ("running", "rest"):
        scheme = CentralDifference(model, nonlinear=False, safety=0.5, damping=False,
                                   rotation=Rotation(clearance=clearance))
        runs[clearance] = simulate(scheme, [spin], casing, n_steps=n)
    running, rest = runs["running"], runs["rest"]
    print(f"tip growth {1e6 * growth.min():.1f} - {1e6 * growth.max():.1f} um; running: {running.contact_steps[0]} "
          f"contact steps, |u_r| <= {np.abs(running.u_r[0]).max():.1e} m; rest: {rest.contact_steps[0]} of {n} steps "
          f"in contact, u_r after the first {rest.u_r[0][:, 1].max():.6e} (c0 {c0:.6e})")
    assert np.abs(running.u_r[0]).max() <= 1e-9 * growth.max() and running.contact_steps[0] == 0
    np.testing.assert_allclose(rest.u_r[0][:, 0], growth, rtol=1e-14, atol=0)
    assert (rest.lam[0][:, 1] > 0).any() and rest.u_r[0][:, 1].max() == pytest.approx(c0, rel=1e-9)
    assert rest.u_r[0][:, 1:].max() <= c0 + 1e-14 and rest.max_penetration[0] <= 1e-14


def test_a_turning_sweep_resumes_bit_identically_in_its_own_folder(turning_rom, tmp_path, monkeypatch):
    """A turning map's sweep (``run_sweep`` with a turning scheme, the casing's bumps and friction, each speed from
    its centrifugal state) killed halfway resumes from its checkpoint and gives the uninterrupted sweep bit for bit
    (the centrifugal states are solved again, the same operations); its folder is not the same blade at rest's, nor
    the other clearance's (the key holds the rotation), and each speed starts at its centrifugal state (records from
    0 with the running clearance)."""
    from conftest import Killed, killed_after
    from rotor37_rom.dynamics.casing import Casing
    from rotor37_rom.dynamics.explicit import CentralDifference
    from rotor37_rom.dynamics.turning import Rotation
    from rotor37_rom.studies import sweep as sweep_mod
    from rotor37_rom.studies.sweep import SweepSpec, load_sweep, run_sweep

    cap = 2 * np.pi * 60e3
    schemes = {c: CentralDifference(turning_rom, nonlinear=False, safety=0.9, frequency_cap=cap,
                                    rotation=Rotation(clearance=c)) for c in ("running", "rest")}
    still = CentralDifference(turning_rom, nonlinear=False, safety=0.9, frequency_cap=cap)
    spec = SweepSpec(revolutions=0.5, casing=Casing(), record_dt=2e-6)
    speeds = np.array([1500.0, 1800.0])
    scheme = schemes["running"]
    kill_at = int(0.25 * 2 * np.pi / speeds.max() / scheme.h)
    real = sweep_mod.simulate
    monkeypatch.setattr(sweep_mod, "simulate", killed_after(real, kill_at))
    with pytest.raises(Killed):
        run_sweep(scheme, speeds, spec, tmp_path / "a", progress=False, checkpoint_seconds=0.0)
    monkeypatch.setattr(sweep_mod, "simulate", real)
    resumed = load_sweep(run_sweep(scheme, speeds, spec, tmp_path / "a", progress=False))
    whole = load_sweep(run_sweep(scheme, speeds, spec, tmp_path / "b", progress=False))
    for got, ref in zip(resumed, whole):
        np.testing.assert_array_equal(got["u_r"], ref["u_r"])
        np.testing.assert_array_equal(got["lam"], ref["lam"])
        assert np.abs(got["u_r"][:, 0]).max() <= 1e-15                  # from the running blade
    assert (resumed[0]["lam"] > 0).any()                                  # the bumps were met
    names = {run_sweep(s, speeds[:1], spec, tmp_path / "c", progress=False).name
             for s in (schemes["running"], schemes["rest"], still)}
    assert len(names) == 3


@pytest.mark.slow
@pytest.mark.mpi
def test_turning_map_under_mpi_equals_the_serial_sweep(turning_rom, tmp_path):
    """``demos/contact_map.py --rotation running`` under mpirun -n 2 (the speeds split over the ranks, each rank
    solving its speeds' centrifugal states) writes the serial turning sweep's folder with the same records, to the
    1e-8 that a batch's BLAS rounding allows (the at-rest map's MPI test)."""
    import json
    import os
    import subprocess
    import sys
    from pathlib import Path

    from rotor37_rom.dynamics.casing import Casing
    from rotor37_rom.dynamics.explicit import CentralDifference
    from rotor37_rom.dynamics.turning import Rotation
    from rotor37_rom.model.reduced import save_reduced_model
    from rotor37_rom.studies.contact_config import ContactMapConfig
    from rotor37_rom.studies.sweep import SweepSpec, load_sweep, run_sweep

    path = save_reduced_model(turning_rom, tmp_path / "turning.npz")
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1", MPLBACKEND="Agg", OPENBLAS_NUM_THREADS="1")
    demo = Path(__file__).resolve().parents[2] / "demos" / "contact_map.py"
    cmd = ["mpirun", "-n", "2", sys.executable, str(demo), "--model", str(path), "--rotation", "running",
           "--speeds", "1500", "1800", "4", "--revolutions", "0.5", "--gnl", "off", "--safety", "0.9",
           "--frequency-cap", "60", "--out", str(tmp_path / "mpi"), "--quiet"]
    run = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-2000:]
    cap = ContactMapConfig.from_options(frequency_cap=60.0).scheme.frequency_cap_rad_s
    scheme = CentralDifference(turning_rom, nonlinear=False, safety=0.9, frequency_cap=cap, rotation=Rotation())
    serial = run_sweep(scheme, np.linspace(1500.0, 1800.0, 4), SweepSpec(revolutions=0.5, casing=Casing()),
                       tmp_path / "serial", progress=False)
    got, ref = load_sweep(tmp_path / "mpi" / "sweeps" / serial.name), load_sweep(serial)
    assert len(got) == len(ref) == 4
    for a, b in zip(got, ref):
        assert float(a["omega"]) == float(b["omega"])
        assert np.abs(a["u_r"] - b["u_r"]).max() <= 1e-8 * np.abs(b["u_r"]).max()
    summary = json.loads((tmp_path / "mpi" / "summary.json").read_text())
    assert summary["runs"]["no GNL, cap 60 kHz, turning, running clearance"]["rotation"]["clearance"] == "running"


def test_a_turning_map_refuses_a_model_that_cannot_turn_there(turning_rom, tmp_path):
    """``--rotation`` on a saved model: a model built at rest, and a map reaching past the model's centrifugal
    snapshots (2,000 rad/s here), are each one line naming --rotation and the range, exit status 2, once the model is
    read and before any run."""
    import subprocess
    import sys
    from pathlib import Path

    from rotor37_rom.model.reduced import save_reduced_model

    turning = save_reduced_model(turning_rom, tmp_path / "turning.npz")
    still = save_reduced_model(dataclasses.replace(turning_rom, rotation=None), tmp_path / "still.npz")
    demo = Path(__file__).resolve().parents[2] / "demos" / "contact_map.py"
    for model, speeds, words in ((still, ["1500", "1800", "2"], "built at rest"),
                                 (turning, ["1500", "2500", "2"], "outside this reduced model's range 0 ... 2000")):
        run = subprocess.run([sys.executable, str(demo), "--model", str(model), "--rotation", "running", "--speeds",
                              *speeds, "--gnl", "off", "--out", str(tmp_path / "out"), "--quiet"],
                             capture_output=True, text=True, timeout=120, env=dict(os.environ, MPLBACKEND="Agg"))
        lines = run.stderr.strip().splitlines()
        assert run.returncode == 2 and len(lines) == 1 and lines[0].startswith("error: --rotation"), run.stderr
        assert words in lines[0] and not list((tmp_path / "out").glob("sweeps/*/omega_*"))


@pytest.mark.parametrize("options, words", [
    ({"rotation": "spinning"}, "--rotation must be one of running, rest"),
    ({"rotation": "running", "disk": True}, "takes --gnl on"),
    ({"rotation": "running", "disk": True, "gnl": "on", "mistuning": 0.05}, "not with --mistuning"),
    ({"rotation": "running", "gnl": "on", "cubature": 1e-4}, "not with --cubature"),
    ({"rotation": "rest", "periodic": 0.05}, "not with --periodic"),
    ({"rotation": "running", "tolerance": 0.05}, "not with --tolerance")])
def test_a_turning_map_configuration_refuses_what_it_cannot_turn(options, words):
    """What a turning map does not take is refused by its configuration, one ValueError naming --rotation, before
    any work (the command line prints it as one line: tests/cli/test_demo_errors.py)."""
    from rotor37_rom.studies.contact_config import ContactMapConfig

    with pytest.raises(ValueError, match="^--rotation") as error:
        ContactMapConfig.from_options(**options)
    assert words in str(error.value)
