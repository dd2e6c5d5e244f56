"""The tuned disk's travelling-wave response on one sector (#72 (f)): the one-sector harmonic balance is the full
disk's, its orbit the full disk's to round-off at equal H, and Hill's problem of the full disk splits exactly into
the perturbation classes (nodal diameters) the one-sector balance solves one by one."""
import dataclasses

import numpy as np
import pytest
import scipy.linalg
import scipy.optimize

from rotor37_rom.disk.harmonics import harmonic_frequencies
from rotor37_rom.disk.loads import node_load_matrix
from rotor37_rom.periodic import Harmonics, HarmonicBalance, model_force, solve_periodic
from rotor37_rom.periodic.travelling_wave import TravellingWaveBalance, travelling_excitation

H, K_ND, LOAD = 2, 6, 20.0          # harmonics; the load's nodal diameters (EO6 on 36 blades); N at LE, axial


def le_loads(model):
    """P (r, N): a unit axial force at LE of each sector."""
    return node_load_matrix(model.nodes, model.r, "LE", 2)


def disk_coefficients(tw, x, j=0):
    """V_j: the disk's coefficients (columns, coefficient-major) of each of class j's unknowns."""
    V = tw.class_basis(j)
    return np.stack([tw.coefficients(e, V).ravel() for e in np.eye(sum(B.shape[1] for B in V))], axis=1)


@pytest.fixture(scope="module")
def wave(disk_model):
    """The one-sector wave at 0.95 of the first k = 6 frequency under 20 N at LE (cubic force balanced without
    aliasing: 4 H + 3 samples), the full disk's balance, and the disk's Jacobian at the orbit."""
    model, _ = disk_model
    basis = Harmonics(H, 4 * H + 3)
    F = travelling_excitation(le_loads(model), LOAD, K_ND, basis)
    tw = TravellingWaveBalance(model, F, basis, K_ND)
    full = HarmonicBalance(model.M, model.C, model.K, model_force(model.forces), F, basis)
    omega = 0.95 * harmonic_frequencies(model, 1)[K_ND, 0]
    sol = solve_periodic(tw, np.zeros(tw.size), omega, stability=False)
    X = tw.coefficients(sol.X)
    R, J, _ = full.residual(X.ravel(), omega, domega=False)
    return model, tw, full, sol, X, R, J


def test_one_sector_balance_is_the_full_disks(wave):
    """At a random travelling state the one-sector residual, Jacobian and d/domega are the full disk's projected
    on the wave's subspace, and the disk's residual lies in it (to round-off: the same sums, N sectors' forces
    against one sector's times N). The one-sector orbit is the full disk's at equal H: at the expanded orbit the
    full disk's Newton correction is round-off amplified by its conditioning (below cond(J) eps, with J's
    conditioning taken on the wave's class, where the correction lies). The orbit is nonlinear: the linear
    response at that speed is > 10 % away."""
    model, tw, full, sol, X, R, J = wave
    V = disk_coefficients(tw, sol.X)
    rng = np.random.default_rng(1)
    z = tw.restrict(rng.standard_normal(X.shape) * np.abs(X).max())
    r1, j1, d1 = tw.residual(z, sol.omega)
    rf, jf, df = full.residual(V @ z, sol.omega)
    eps = np.finfo(float).eps
    for one, disk in ((r1, V.T @ rf), (j1, V.T @ jf @ V), (d1, V.T @ df)):
        assert np.linalg.norm(one - disk) <= 1e3 * eps * np.linalg.norm(disk)
    assert np.linalg.norm(V @ (V.T @ rf) - rf) <= 1e3 * eps * np.linalg.norm(jf @ (V @ z))

    delta = np.linalg.solve(J, -R)
    kappa = np.linalg.cond(tw.residual(sol.X.ravel(), sol.omega)[1])
    print(f"one sector vs disk: Newton correction {np.linalg.norm(delta) / np.linalg.norm(X):.2e} of the orbit, "
          f"cond(J) eps = {kappa * eps:.2e}; one-sector unknowns {tw.size} of {full.size}")
    assert np.linalg.norm(delta) <= kappa * eps * np.linalg.norm(X)
    linear = tw.coefficients(np.linalg.solve(tw.linear_matrix(sol.omega), tw.F))
    assert np.linalg.norm(linear - X) > 0.1 * np.linalg.norm(X)


def test_hill_splits_into_nodal_diameter_classes(wave):
    """The classes j = 0 .. N/2 (harmonic h of a perturbation in the turn's eigenspaces h k +- j) are orthonormal,
    mutually orthogonal and together the disk's coefficient space; the disk's balance Jacobian at the orbit leaves
    each invariant and equals there the class Jacobian the one-sector balance forms from sector 0's force alone
    (round-off). So the full disk's Hill spectrum is the union of the classes'."""
    model, tw, full, sol, X, R, J = wave
    eps = np.finfo(float).eps
    N = model.sectors.blocks.shape[0]
    for h in range(H + 1):                                  # each harmonic block: the classes' bases together
        B = np.hstack([tw.class_basis(j)[h] for j in tw.classes])
        assert B.shape[1] == B.shape[0]
        assert np.abs(B.T @ B - np.eye(B.shape[0])).max() <= 1e3 * eps
    worst = 0.0
    for j in tw.classes:
        Vj = disk_coefficients(tw, None, j)
        JV = J @ Vj
        Jj = Vj.T @ JV
        assert np.linalg.norm(JV - Vj @ Jj) <= 1e3 * eps * np.linalg.norm(JV)
        err = np.linalg.norm(tw.class_jacobian(sol.X, sol.omega, j) - Jj) / np.linalg.norm(Jj)
        worst = max(worst, err)
    print(f"class Jacobians against the disk's: {worst:.1e} over the {N // 2 + 1} classes")
    assert worst <= 1e3 * eps


def test_linear_wave_exponents_are_the_disks_eigenvalues(disk_model):
    """About the resting disk (the linear limit) Hill's exponents of all classes, one copy of each kept
    (``hill_exponents``), are the disk's own eigenvalues modulo i omega, each once: the closed form of its modal
    damping, lambda = omega_i (-zeta_i +- i sqrt(1 - zeta_i^2)) from eigh(K, M). Tolerance: the round-off of a
    symmetric-definite eigenproblem, eps (cond(M) + (omega_max / |lambda|)^2) relative (the model's stiffest
    coordinate is 1,900 times its first mode, its M's condition 4e8). The plain first-order form [p, lambda p] is
    1.6e-4 off at the first modes (a 10 % error in their damping), and a choice by the smallest imaginary part
    alone misses the stiff modes."""
    model, _ = disk_model
    basis = Harmonics(H, 4 * H + 3)
    tw = TravellingWaveBalance(model, np.zeros((basis.size, model.r)), basis, K_ND)
    omega = 0.9 * harmonic_frequencies(model, 1)[K_ND, 0]
    lam = tw.floquet_exponents(np.zeros(tw.size), omega)
    w2, Phi = scipy.linalg.eigh(model.K, model.M)
    w = np.sqrt(w2)
    zeta = np.einsum("ij,ik,kj->j", Phi, model.C, Phi) / (2 * w)
    root = np.sqrt(1 - zeta ** 2)
    exact = np.concatenate([w * (-zeta + 1j * root), w * (-zeta - 1j * root)])
    assert lam.size == exact.size == 2 * model.r
    d = exact[:, None] - lam[None, :]                            # exponents are defined modulo i omega
    d = d.real + 1j * (d.imag - omega * np.round(d.imag / omega))
    cost = np.abs(d) / np.abs(exact)[:, None]
    rows, cols = scipy.optimize.linear_sum_assignment(cost)     # one to one (the cyclic pairs are double)
    err = cost[rows, cols]
    eps = np.finfo(float).eps
    bound = eps * (np.linalg.cond(model.M) + (w.max() / np.abs(exact)) ** 2)
    print(f"linear wave: exponents against the disk's eigenvalues: {err.max():.1e} relative, "
          f"{(err / bound).max():.2g} of the round-off bound")
    assert np.all(err <= bound)


def test_travelling_wave_bad_input(disk_model):
    model, _ = disk_model
    basis = Harmonics(H, 4 * H + 3)
    P = le_loads(model)
    F = travelling_excitation(P, 1.0, K_ND, basis)
    with pytest.raises(ValueError, match="not a wave of 5 nodal diameters"):
        TravellingWaveBalance(model, F, basis, 5)
    with pytest.raises(ValueError, match="n_diameters must be an integer in -35..35"):
        TravellingWaveBalance(model, F, basis, 36)
    with pytest.raises(ValueError, match="needs a disk model"):
        TravellingWaveBalance(dataclasses.replace(model, sectors=None), F, basis, K_ND)
    mistuned = model.K.copy()
    block = model.sectors.blocks[3]
    mistuned[np.ix_(block, block)] *= 1.01
    with pytest.raises(ValueError, match="mistuned"):
        TravellingWaveBalance(dataclasses.replace(model, K=mistuned), F, basis, K_ND)
    with pytest.raises(ValueError, match="H >= 1"):
        travelling_excitation(P, 1.0, K_ND, Harmonics(0, 3))
    from rotor37_rom.periodic.departure import wave_departure

    tw = TravellingWaveBalance(model, F, basis, K_ND)
    rest = solve_periodic(tw, np.zeros(tw.size), 1000.0, stability=False)
    for kwargs, message in (({"periods": 4}, "periods must be an integer >= 8"),
                            ({"steps_per_period": 8}, "steps_per_period must be an integer >= 16"),
                            ({"size": 0.5}, r"size must be in \(0, linear_limit\)")):
        with pytest.raises(ValueError, match=message):
            wave_departure(tw, rest, **kwargs)


def _trapezoidal_multipliers(w, zeta, h, n):
    """|z_n / z_0| after n steps of average-acceleration Newmark (the trapezoidal rule on the first-order form) for
    damped modes w, zeta: |(1 + lambda h / 2) / (1 - lambda h / 2)|^n, lambda = w (-zeta + i sqrt(1 - zeta^2))."""
    lam = w * (-zeta + 1j * np.sqrt(1 - zeta ** 2))
    return np.abs((1 + lam * h / 2) / (1 - lam * h / 2)) ** n


def test_linear_wave_departure_decays_at_its_modes(disk_model):
    """The full disk marched from a linear travelling wave (H = 1: exact) plus a perturbation of the lowest modes of
    every other set of nodal diameters: the sets are orthonormal, M- and K-orthogonal and span the disk; each set's
    perturbation amplitude (the square root of its energy, a sum of its modes' energies) decays a period at a rate
    between the slowest and the fastest of the perturbed modes' own decay under the same scheme (closed form of the
    trapezoidal rule), within the fit's error (1e-4: the energy of a damped mode sampled once a period oscillates
    by ~zeta); Hill's largest multiplier of the set's classes is its slowest mode's exp(-zeta omega_i T) (round-off
    of the eigenvalues); and the wave's own set stays on the harmonic balance's wave within the scheme's frequency error
    (omega h)^2 / 12 times the forced response's sensitivity to it, 2 (omega / omega_1)^2 / (1 - (omega /
    omega_1)^2), plus the scheme's own relative error of a resolved motion, (omega h)^2 / 12, twice (the forced part
    and the start's transient, which beat)."""
    from rotor37_rom.periodic.departure import residue_sets, wave_departure

    model, _ = disk_model
    linear = dataclasses.replace(model, forces=None)
    basis = Harmonics(1, 4)
    tw = TravellingWaveBalance(linear, travelling_excitation(le_loads(model), LOAD, K_ND, basis), basis, K_ND)
    w1 = harmonic_frequencies(model, 1)[K_ND, 0]
    omega = 0.9 * w1
    sol = solve_periodic(tw, np.zeros(tw.size), omega, stability=False)
    sets = residue_sets(tw)
    U = np.hstack(list(sets.values()))
    eps = np.finfo(float).eps
    assert U.shape == (model.r, model.r) and np.abs(U.T @ U - np.eye(model.r)).max() <= 1e3 * eps
    for rho, A in sets.items():
        for sigma, B in sets.items():
            if rho != sigma:
                for Op in (model.M, model.K):
                    assert np.linalg.norm(A.T @ Op @ B) <= 1e-10 * np.linalg.norm(Op)

    spp, periods = 32, 12
    dep = wave_departure(tw, sol, periods=periods, steps_per_period=spp, size=1e-4, rho_inf=None)
    h = 2 * np.pi / omega / spp
    w2, Phi = scipy.linalg.eigh(model.K, model.M)
    w = np.sqrt(w2)
    zeta = np.einsum("ij,ik,kj->j", Phi, model.C, Phi) / (2 * w)
    g = 6                                                  # gcd(6, 36)
    assert [s.residue for s in dep.sets] == [1, 2, 3]
    for s in dep.sets:
        B = sets[s.residue]
        inside = (np.linalg.norm(B.T @ (model.M @ Phi), axis=0) > 0.5) & (w < 2.0 * omega)
        mu = _trapezoidal_multipliers(w[inside], zeta[inside], h, spp)
        print(f"diameters = +-{s.residue} mod {g}: marched {s.measured:.6f}, the modes' {mu.min():.6f}-"
              f"{mu.max():.6f}, Hill {s.predicted:.6f}")
        assert mu.min() - 1e-4 <= s.measured <= mu.max() + 1e-4
        every = np.linalg.norm(B.T @ (model.M @ Phi), axis=0) > 0.5            # Hill: the set's slowest mode
        assert s.predicted == pytest.approx(np.exp(-zeta[every] * w[every] * 2 * np.pi / omega).max(), rel=1e-8)
    ratio = (omega / w1) ** 2
    bound = 2 * (omega * h) ** 2 / 12 * (2 * ratio / (1 - ratio) + 1)
    print(f"the wave's own set: {dep.drift.max():.2e} from the balance's wave (bound {bound:.2e})")
    assert dep.drift.max() <= bound
