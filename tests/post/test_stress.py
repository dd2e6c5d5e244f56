"""Stress recovery: UFL von Mises against closed forms, the NumPy recovery from reduced states against direct UFL
evaluation, pictures (non-blank, drawn range = field range), bad input."""
import json

import numpy as np
import pytest
from dolfinx import fem as dfem
from dolfinx import mesh as dmesh
from mpi4py import MPI

from rotor37_rom import forms
from rotor37_rom.post.recovery import StressRecovery, svk_cauchy, von_mises

LMBDA, MU = forms.MARAGING_200.lame


def _vm(s):
    sxx, syy, szz, sxy = s
    return np.sqrt(0.5 * ((sxx - syy) ** 2 + (syy - szz) ** 2 + (szz - sxx) ** 2) + 3 * sxy**2)


def _closed_forms(case, a):
    """(sigma_xx, sigma_yy, sigma_zz, sigma_xy) of SVK under homogeneous deformations, by hand."""
    if case == "stretch":                                  # x -> (a x, y, z)
        e = 0.5 * (a * a - 1)
        Sxx, Syy = (LMBDA + 2 * MU) * e, LMBDA * e
        return a * Sxx, Syy / a, Syy / a, 0.0              # sigma = F S F^T / J, J = a
    g = a                                                  # simple shear x -> (x + g y, y, z)
    Sxx = Szz = LMBDA * g * g / 2
    Syy = LMBDA * g * g / 2 + MU * g * g
    Sxy = MU * g
    return Sxx + 2 * g * Sxy + g * g * Syy, Syy, Szz, Sxy + g * Syy


@pytest.mark.parametrize("case,a", [("stretch", 1.1), ("stretch", 0.95), ("shear", 0.3), ("shear", 1e-3)])
def test_von_mises_closed_forms(case, a):
    """The UFL expression (interpolated into DG0 on a cube) and the NumPy one equal the closed forms to 1e-10."""
    mesh = dmesh.create_unit_cube(MPI.COMM_WORLD, 2, 2, 2, dmesh.CellType.tetrahedron)
    V = dfem.VectorFunctionSpace(mesh, ("Lagrange", 1))
    u = dfem.Function(V)
    if case == "stretch":
        u.interpolate(lambda x: np.vstack([(a - 1) * x[0], 0 * x[1], 0 * x[2]]))
        G = np.array([[a - 1, 0, 0], [0, 0, 0], [0, 0, 0.0]])
    else:
        u.interpolate(lambda x: np.vstack([a * x[1], 0 * x[1], 0 * x[2]]))
        G = np.array([[0, a, 0], [0, 0, 0], [0, 0, 0.0]])
    W = dfem.FunctionSpace(mesh, ("DG", 0))
    vm = dfem.Function(W)
    vm.interpolate(dfem.Expression(forms.von_mises(forms.cauchy_stress(u, LMBDA, MU)),
                                   W.element.interpolation_points()))
    exact = _vm(_closed_forms(case, a))
    np.testing.assert_allclose(vm.x.array, exact, rtol=1e-10)
    np.testing.assert_allclose(von_mises(svk_cauchy(G, LMBDA, MU)), exact, rtol=1e-12)
    # linear stress: the same homogeneous strain with small-strain Hooke
    eps = 0.5 * (G + G.T)
    sig = LMBDA * np.trace(eps) * np.eye(3) + 2 * MU * eps
    vm.interpolate(dfem.Expression(forms.von_mises(forms.linear_stress(u, LMBDA, MU)),
                                   W.element.interpolation_points()))
    np.testing.assert_allclose(vm.x.array, _vm((sig[0, 0], sig[1, 1], sig[2, 2], sig[0, 1])), rtol=1e-10)


@pytest.fixture(scope="module")
def recovery(ci_blade, ci_rom):
    from rotor37_rom import fem

    H, w, cells = fem.quadrature_gradients(ci_blade, ci_rom.Phi.T)
    return StressRecovery(H, cells, *ci_blade.material.lame)


def _state(ci_rom, amplitude=1e-3):
    """1B + 0.3 x 1T of the reduced model, scaled so that the tip moves by ``amplitude`` (m)."""
    import scipy.linalg

    from rotor37_rom.model.modes import normalise_signs

    _, V = scipy.linalg.eigh(ci_rom.K, ci_rom.M)
    V = normalise_signs(V[:, :2])                         # the same state on every machine
    tip = ci_rom.nodes.boundary_rows
    q = V[:, 0] + 0.3 * V[:, 1] * np.abs(V[tip, 0]).max() / np.abs(V[tip, 1]).max()
    return q * amplitude / np.abs(q[tip]).max()


@pytest.mark.parametrize("nonlinear", [True, False])
def test_recovery_equals_direct_evaluation(ci_blade, ci_rom, recovery, nonlinear):
    from rotor37_rom import fem

    q = _state(ci_rom)
    u = fem.displacement_function(ci_blade, ci_rom.Phi, q)
    direct = fem.von_mises_at_quadrature(ci_blade, u, nonlinear)
    fast = recovery.von_mises(q, nonlinear)
    err = np.abs(fast - direct).max() / np.abs(direct).max()
    print("recovery vs direct UFL:", err, "max von Mises (MPa)", direct.max() / 1e6)
    assert err <= 1e-10
    E1, E2 = recovery.contributions(q)
    G = recovery.gradient(q)
    np.testing.assert_allclose(E1 + E2, 0.5 * (np.swapaxes(G + np.eye(3), 1, 2) @ (G + np.eye(3)) - np.eye(3)),
                               atol=1e-14)
    # the quadratic part scales with the square of the state: Taylor-style check of the decomposition
    E1h, E2h = recovery.contributions(0.5 * q)
    np.testing.assert_allclose(E1h, 0.5 * E1, atol=1e-15)
    np.testing.assert_allclose(E2h, 0.25 * E2, atol=1e-15)


def test_dg_field_matches_recovery_maximum(ci_blade, ci_rom, recovery):
    """DG0 interpolation (value at each cell's centroid) stays within the range of the quadrature values."""
    from rotor37_rom import fem

    q = _state(ci_rom)
    u = fem.displacement_function(ci_blade, ci_rom.Phi, q)
    vm0 = fem.von_mises_function(ci_blade, u, degree=0).x.array
    cmax = recovery.cell_max(q)
    assert vm0.shape == cmax.shape
    assert (vm0 <= cmax * (1 + 1e-9) + 1.0).mean() > 0.99


def test_stress_picture(ci_blade, ci_rom, recovery, tmp_path):
    import matplotlib.image as mpimg

    from rotor37_rom import fem
    from rotor37_rom.viz.plotting import render_stress

    q = _state(ci_rom)
    u = fem.displacement_function(ci_blade, ci_rom.Phi, q)
    cells = recovery.cell_max(q)
    for n_sectors in (1, 36):
        path = render_stress(ci_blade, u, cells, tmp_path / f"vm_{n_sectors}.png", "test", n_sectors=n_sectors,
                             factor=5.0)
        img = mpimg.imread(path)[..., :3]
        non_white = (img < 0.95).any(axis=2).mean()
        colours = len(np.unique((img * 255).astype(np.uint8).reshape(-1, 3), axis=0))
        info = json.loads(path.with_name(path.name + ".json").read_text())
        print(n_sectors, "non-white fraction", non_white, "colours", colours, info["scalar_range"])
        assert non_white > 0.05 and colours > 100
        np.testing.assert_allclose(info["scalar_range"], [cells.min() / 1e6, cells.max() / 1e6], rtol=1e-6)
        assert info["n_cells"] == n_sectors * len(cells)


def test_bad_input(ci_blade, ci_rom, recovery):
    from rotor37_rom import fem

    with pytest.raises(ValueError, match="r = 45"):
        recovery.von_mises(np.zeros(44))
    with pytest.raises(ValueError, match="r = 45"):
        fem.displacement_function(ci_blade, ci_rom.Phi, np.zeros(46))
    with pytest.raises(ValueError, match="NaN"):
        recovery.von_mises(np.full(45, np.nan))
