"""FE checks of the SVK forms with exact answers: Taylor tests, objectivity, exact cubic dependence, symmetry.

Taylor tests follow pyadjoint's taylor_test: the first-order remainder of a smooth map decays as eps^2 (rate >= 1.95
asserted) and the second-order one as eps^3 (>= 2.9). Because SVK forces are exactly cubic in u, the third-order
remainder vanishes to round-off, which is asserted directly (no rate can be measured on a zero).

Round-off thresholds are set from u = 1.1e-16 times the cancellation between the terms compared times a growth
factor c ~ 1e2 for a quadrature kernel and the summation of ~30 cell contributions per entry (comments at each
assertion give the estimate and the measured value on the ci blade); every threshold is >= 30x its estimate. The
Taylor steps EPS/EPS2 keep the remainders far above round-off: the smallest first-order one, eps^2 |D^2 f[v, v]| / 2
~ 4e-10 |f| at eps = 6e-5, and the smallest second-order one, ~5e-8 |f| at eps = 0.025, are >= 1e4x the rounding of
f (~1e-14 |f|), so the rates are those of the expansion on any machine.
"""
import numpy as np
import pytest
from dolfinx import fem as dfem
from petsc4py import PETSc

from rotor37_rom import fem

EPS = 1e-3 * 0.5 ** np.arange(5)  # first-order remainders: eps^2 stays well above round-off
EPS2 = 0.4 * 0.5 ** np.arange(5)  # second-order remainder: eps^3 needs larger steps


def _vec(ops, form):
    return fem.assemble_vector(form).getArray(readonly=True).copy()


def _set(f, values):
    f.x.array[:] = values
    f.x.scatter_forward()


def _random_field(V, rng, amplitude):
    """Smooth-ish random field: random affine + quadratic in x (m), amplitude in m."""
    x = V.tabulate_dof_coordinates()
    x = (x - x.mean(0)) / np.ptp(x, axis=0).max()
    coeff = rng.standard_normal((3, 10))
    basis = np.column_stack([np.ones(len(x)), x, x**2, x[:, [0]] * x[:, [1]], x[:, [1]] * x[:, [2]],
                             x[:, [0]] * x[:, [2]]])
    return amplitude * (basis @ coeff.T).ravel()


def _rates(errors):
    errors = np.asarray(errors)
    return np.log(errors[:-1] / errors[1:]) / np.log(2.0)


@pytest.fixture(scope="module")
def fields(ci_blade):
    rng = np.random.default_rng(2023)
    V = ci_blade.V
    return [_random_field(V, rng, 2e-3) for _ in range(4)]


def _f_int(ops, u):
    _set(ops.u, u)
    return _vec(ops, ops.f_int)


def _tangent_action(ops, u, w):
    _set(ops.u, u)
    A = dfem.petsc.assemble_matrix(ops.tangent)
    A.assemble()
    x, y = A.createVecs()
    x.array[:] = w
    A.mult(x, y)
    return y.array.copy()


def _d2(ops, u, w1, w2):
    _set(ops.u, u), _set(ops.w1, w1), _set(ops.w2, w2)
    return _vec(ops, ops.d2)


def _d3(ops, w1, w2, w3):
    _set(ops.w1, w1), _set(ops.w2, w2), _set(ops.w3, w3)
    return _vec(ops, ops.d3)


def test_tangent_taylor(ci_ops, fields):
    u, v = fields[0], fields[1]
    f0, Kv = _f_int(ci_ops, u), _tangent_action(ci_ops, u, v)
    errors = [np.linalg.norm(_f_int(ci_ops, u + e * v) - f0 - e * Kv) for e in EPS]
    assert min(_rates(errors)) >= 1.95, _rates(errors)


def test_second_derivative_taylor(ci_ops, fields):
    u, v, w = fields[0], fields[1], fields[2]
    Kw = _tangent_action(ci_ops, u, w)
    d2 = _d2(ci_ops, u, w, v)
    errors = [np.linalg.norm(_tangent_action(ci_ops, u + e * v, w) - Kw - e * d2) for e in EPS]
    assert min(_rates(errors)) >= 1.95, _rates(errors)
    # second-order Taylor expansion of f_int itself: remainder O(eps^3)
    f0, Kv, d2vv = _f_int(ci_ops, u), _tangent_action(ci_ops, u, v), _d2(ci_ops, u, v, v)
    errors = [np.linalg.norm(_f_int(ci_ops, u + e * v) - f0 - e * Kv - 0.5 * e**2 * d2vv) for e in EPS2]
    assert min(_rates(errors)) >= 2.9, _rates(errors)


def test_third_derivative_is_exact(ci_ops, fields):
    """D^2 f is affine in u for SVK: its first-order remainder against D^3 vanishes to round-off, and the
    third-order Taylor expansion of f_int is exact."""
    u, v, w1, w2 = fields
    d3 = _d3(ci_ops, w1, w2, v)
    for e in (1.0, 0.1):
        rem = _d2(ci_ops, u + e * v, w1, w2) - _d2(ci_ops, u, w1, w2) - e * d3
        # cancellation |D2 f(u + e v)| / |e d3| = 24 (e = 1), 246 (e = 0.1): u x 246 x c ~ 3e-12 (measured 3e-13)
        assert np.linalg.norm(rem) <= 1e-10 * np.linalg.norm(e * d3)
    f0, Kv, d2vv, d3vvv = (_f_int(ci_ops, u), _tangent_action(ci_ops, u, v), _d2(ci_ops, u, v, v),
                           _d3(ci_ops, v, v, v))
    e = 0.5
    rem = _f_int(ci_ops, u + e * v) - f0 - e * Kv - e**2 / 2 * d2vv - e**3 / 6 * d3vvv
    # the terms are <= 1.13 |f_int(u + e v)|: u x 1.13 x c ~ 1e-14 (measured 5e-14)
    assert np.linalg.norm(rem) <= 1e-10 * np.linalg.norm(_f_int(ci_ops, u + e * v))


def test_rigid_rotation_gives_no_force(ci_ops, ci_blade):
    """u = (R - I) X is exactly representable (P2 contains affine fields) and strain-free: f_int = 0."""
    x = ci_blade.V.tabulate_dof_coordinates()
    angle = 0.6
    R = np.array([[np.cos(angle), -np.sin(angle), 0.0], [np.sin(angle), np.cos(angle), 0.0], [0.0, 0.0, 1.0]])
    axis = np.array([0.0, 0.3, 0.2])
    R = R @ np.array([[1, 0, 0], [0, np.cos(0.4), -np.sin(0.4)], [0, np.sin(0.4), np.cos(0.4)]])
    u = ((x - axis) @ R.T - (x - axis)).ravel()
    f = _f_int(ci_ops, u)
    K = fem.assemble_stiffness(ci_blade, ci_ops, clamped=False)
    a, b = K.createVecs()
    a.array[:] = u
    K.mult(a, b)
    # the strain-free field is exact only up to the rounding of u itself, u |x - axis| ~ 4e-17 m, which its
    # gradient over the smallest elements (h ~ 2 mm) turns into a strain error ~ u |x - axis| / h ~ 2e-14 against
    # the linear strain ~0.2 that K u sees: ~1e-13, times the summation over the cells of a node (~30): ~3e-12
    # (measured 2.8e-12; a norm of ~1e4 independent roundings, stable to tens of %)
    assert np.linalg.norm(f) <= 1e-11 * np.linalg.norm(b.array)


def test_internal_force_is_exactly_cubic(ci_ops, ci_blade, fields):
    u = fields[0]
    alphas = np.array([-1.5, -1.0, -0.5, 0.25, 0.5, 1.0, 1.5, 2.0])
    F = np.array([_f_int(ci_ops, a * u) for a in alphas])
    V = np.column_stack([alphas, alphas**2, alphas**3])
    coef, *_ = np.linalg.lstsq(V, F, rcond=None)
    residual = np.linalg.norm(V @ coef - F) / np.linalg.norm(F)
    # exact cubic: the fit residual is the rounding of F and of the 8 x 3 least squares, u x cond(V) = 8.5 x c
    # ~ 1e-13 (measured 7e-15)
    assert residual <= 1e-10
    # the linear coefficient is K u and g_nl is the rest
    K = fem.assemble_stiffness(ci_blade, ci_ops, clamped=False)
    a, b = K.createVecs()
    a.array[:] = u
    K.mult(a, b)
    # coefficients from the fit: u x cond(V) x |F(2 u)| / |K u| (= 2.4) x c ~ 2e-13 (measured 2e-13); the g_nl
    # check below likewise with |F| / |g| = 24: ~2e-12 (measured 2e-14)
    assert np.linalg.norm(coef[0] - b.array) <= 1e-9 * np.linalg.norm(b.array)
    _set(ci_ops.u, u)
    g = _vec(ci_ops, ci_ops.g_nl)
    assert np.linalg.norm(g - (coef[1] + coef[2])) <= 1e-9 * np.linalg.norm(g)


def test_tangent_symmetric_and_equal_to_K_at_zero(ci_ops, ci_blade, fields):
    _set(ci_ops.u, fields[0])
    A = dfem.petsc.assemble_matrix(ci_ops.tangent)
    A.assemble()
    At = A.copy()
    At.transpose()
    At.axpy(-1.0, A)
    # A_ij and A_ji come from one symmetric kernel in another operation order: ~u |A| entrywise (measured 1e-16)
    assert At.norm(PETSc.NormType.FROBENIUS) <= 1e-12 * A.norm(PETSc.NormType.FROBENIUS)
    _set(ci_ops.u, np.zeros_like(fields[0]))
    T0 = dfem.petsc.assemble_matrix(ci_ops.tangent)
    T0.assemble()
    K = fem.assemble_stiffness(ci_blade, ci_ops, clamped=False)
    T0.axpy(-1.0, K)
    # two forms of the same bilinear form, different operation order: ~u x c relative (measured 3e-15)
    assert T0.norm(PETSc.NormType.FROBENIUS) <= 1e-12 * K.norm(PETSc.NormType.FROBENIUS)
