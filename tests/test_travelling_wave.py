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
