"""The second hyperelastic law (#86, ``forms.neo_hookean``) against its definition: Taylor tests of the internal force
against the energy and of the tangent against the force, a symmetric tangent, and the SVK limit at small strain (the
same small-strain stiffness; the two forces part at second order in the strain). An unknown law is refused in one
line.

Taylor tests as in test_forms.py (pyadjoint's taylor_test): a first-order remainder of a smooth map decays as eps^2
(rate >= 1.9 asserted). The mesh is a 50 x 10 x 10 mm bar of P2 tetrahedra (6 x 2 x 2 boxes), the state a smooth
random field of 0.5 mm (strains ~2 %), the directions random fields of the same size; the steps eps keep the
remainders >= 1e4 x the rounding of the terms compared (eps^2 |D^2 Pi| ~ 1e-7 |Pi| at the smallest eps)."""
import numpy as np
import pytest
import ufl
from dolfinx import fem as dfem
from dolfinx import mesh as dmesh
from mpi4py import MPI

from rotor37_rom.forms import Material, hyperelastic_law, linear_stiffness, neo_hookean, svk

pytestmark = pytest.mark.fe

EPS = 1e-2 * 0.5 ** np.arange(5)
LMBDA, MU = Material().lame


@pytest.fixture(scope="module")
def bar():
    domain = dmesh.create_box(MPI.COMM_SELF, [np.zeros(3), np.array([0.05, 0.01, 0.01])], [6, 2, 2],
                              dmesh.CellType.tetrahedron)
    V = dfem.VectorFunctionSpace(domain, ("CG", 2))
    rng = np.random.default_rng(86)
    x = V.tabulate_dof_coordinates() / 0.05

    def field(amplitude):
        basis = np.column_stack([x, x ** 2, x[:, [0]] * x[:, [1]], np.sin(3 * x[:, [0]])])
        return amplitude * (basis @ rng.standard_normal((basis.shape[1], 3))).ravel()

    return V, field


def _assemble(form, kind):
    compiled = dfem.form(form)
    if kind == "scalar":
        return dfem.assemble_scalar(compiled)
    if kind == "vector":
        return dfem.petsc.assemble_vector(compiled).getArray().copy()
    A = dfem.petsc.assemble_matrix(compiled)
    A.assemble()
    return A.convert("dense").getDenseArray().copy()


def _rates(errors):
    errors = np.asarray(errors)
    return np.log(errors[:-1] / errors[1:]) / np.log(2.0)


def test_force_and_tangent_are_the_energy_s_derivatives(bar):
    """Pi(u + eps v) - Pi(u) - eps f(u) . v = O(eps^2) and f(u + eps w) - f(u) - eps K_T(u) w = O(eps^2): the force is
    the energy's gradient and the tangent the force's (rates >= 1.9); K_T symmetric to round-off (the second
    variation of an energy: 1e-12 of its largest entry)."""
    V, field = bar
    u, v_dir, w_dir = dfem.Function(V), field(5e-4), field(5e-4)
    v, du = ufl.TestFunction(V), ufl.TrialFunction(V)
    u0 = field(5e-4)

    def at(values):
        u.x.array[:] = values
        return u

    energy = neo_hookean.strain_energy(u, LMBDA, MU)
    force = neo_hookean.internal_force(u, v, LMBDA, MU)
    tangent = neo_hookean.tangent_stiffness(u, v, du, LMBDA, MU)
    at(u0)
    Pi0, f0, K0 = _assemble(energy, "scalar"), _assemble(force, "vector"), _assemble(tangent, "matrix")
    first, second = [], []
    for eps in EPS:
        at(u0 + eps * v_dir)
        first.append(abs(_assemble(energy, "scalar") - Pi0 - eps * f0 @ v_dir))
        at(u0 + eps * w_dir)
        second.append(np.linalg.norm(_assemble(force, "vector") - f0 - eps * K0 @ w_dir))
    print("energy -> force remainders", first, "rates", _rates(first))
    print("force -> tangent remainders", second, "rates", _rates(second))
    assert np.all(_rates(first) >= 1.9) and np.all(_rates(second) >= 1.9)
    assert np.abs(K0 - K0.T).max() <= 1e-12 * np.abs(K0).max()


def test_small_strain_limit_is_svk_s(bar):
    """At u = 0 the neo-Hookean tangent is the small-strain stiffness K (both laws linearise to Hooke's law with the
    same Lame constants: 1e-12 of K, round-off); at amplitudes a, a/2, a/4 the two laws' forces differ by O(a^2)
    against K u = O(a): the ratio halves with a (rate within 0.1 of 1), while each law's own nonlinear force
    ``nonlinear_force`` is O(a^2) against K u as well (same rate)."""
    V, field = bar
    u, v, du = dfem.Function(V), ufl.TestFunction(V), ufl.TrialFunction(V)
    K = _assemble(linear_stiffness(v, du, LMBDA, MU), "matrix")
    u.x.array[:] = 0.0
    K_T0 = _assemble(neo_hookean.tangent_stiffness(u, v, du, LMBDA, MU), "matrix")
    assert np.abs(K_T0 - K).max() <= 1e-12 * np.abs(K).max()
    shape = field(1.0)
    gap, own = [], []
    for a in 4e-4 * 0.5 ** np.arange(3):
        u.x.array[:] = a * shape
        f_nh = _assemble(neo_hookean.internal_force(u, v, LMBDA, MU), "vector")
        f_svk = _assemble(svk.internal_force(u, v, LMBDA, MU), "vector")
        g_nh = _assemble(neo_hookean.nonlinear_force(u, v, LMBDA, MU), "vector")
        Ku = np.linalg.norm(K @ u.x.array)
        gap.append(np.linalg.norm(f_nh - f_svk) / Ku)
        own.append(np.linalg.norm(g_nh) / Ku)
    print("|f_NH - f_SVK| / |K u|", gap, "rates", _rates(gap), "; |g_NH| / |K u|", own, "rates", _rates(own))
    assert np.all(np.abs(_rates(gap) - 1.0) <= 0.1) and np.all(np.abs(_rates(own) - 1.0) <= 0.1)
    assert gap[0] > 1e3 * 1e-14                          # the laws do differ: not two names for one


@pytest.mark.parametrize("name", ["SVK", "neo_hookean", "mooney-rivlin", "", None, 3])
def test_an_unknown_law_is_refused_in_one_line(name):
    with pytest.raises(ValueError, match=r"^hyperelastic law must be one of svk, neo-hookean, got ") as info:
        hyperelastic_law(name)
    assert "\n" not in str(info.value)
    assert hyperelastic_law("svk") is svk and hyperelastic_law("neo-hookean") is neo_hookean
