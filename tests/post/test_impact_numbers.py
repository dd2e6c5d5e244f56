"""The impact number (#88 item 5, ``post.impact``) against closed forms: a 1-DOF oscillator whose whole mass impacts
has m_eff = m_mode, Pi = 1 / (4 pi zeta); a 2-DOF chain touching at its first mass has m_eff = m1 (diagonal mass)
and m_mode = (m1 a^2 + m2 b^2) / a^2; a full mass matrix has m_eff = 1 / (M^-1)_kk, sparse or dense alike, and a
mode's scale does not change it. Bad input is refused in one line."""
import numpy as np
import pytest
import scipy.sparse

from rotor37_rom.post.impact import impact_numbers


def test_a_whole_mass_impact_has_pi_one_over_4_pi_zeta():
    out = impact_numbers(np.array([[3.0]]), np.array([[1.0]]), np.array([2.0]), 0.01)
    assert out.m_eff[0] == pytest.approx(3.0) and out.m_mode[0] == pytest.approx(3.0)
    assert out.pi[0] == pytest.approx(1 / (4 * np.pi * 0.01))


def test_two_masses_and_a_full_mass_matrix():
    m1, m2, a, b = 0.01, 5.0, 0.3, 1.0
    out = impact_numbers(np.diag([m1, m2]), np.array([[1.0, 0.0]]), np.array([a, b]), 0.02)
    assert out.m_eff[0] == pytest.approx(m1) and out.m_mode[0] == pytest.approx((m1 * a * a + m2 * b * b) / a ** 2)
    rng = np.random.default_rng(88)
    A = rng.standard_normal((6, 6))
    M = A @ A.T + 6 * np.eye(6)
    N = rng.standard_normal((3, 6))
    phi = rng.standard_normal(6)
    dense, sparse = impact_numbers(M, N, phi, 0.05), impact_numbers(scipy.sparse.csr_matrix(M), N, 7 * phi, 0.05)
    expected = 1 / np.einsum("ij,ji->i", N, np.linalg.solve(M, N.T))
    assert np.allclose(dense.m_eff, expected, rtol=1e-12) and np.allclose(sparse.m_eff, expected, rtol=1e-12)
    assert np.allclose(dense.pi, sparse.pi, rtol=1e-12)                 # the mode's scale cancels
    still = impact_numbers(np.eye(2), np.array([[0.0, 1.0]]), np.array([1.0, 0.0]), 0.1)
    assert still.m_mode[0] == np.inf and still.pi[0] == 0.0             # a mode that does not move the node


@pytest.mark.parametrize("args, word", [((np.ones((2, 3)), [[1, 0]], [1, 0], 0.1), "M must be a square"),
                                        ((np.eye(2), [[1, 0, 0]], [1, 0], 0.1), "N must be"),
                                        ((np.eye(2), [[1, np.nan]], [1, 0], 0.1), "N must be"),
                                        ((np.eye(2), [[1, 0]], [0, 0], 0.1), "phi must be"),
                                        ((np.eye(2), [[1, 0]], [1, 0], 0.0), "zeta must be"),
                                        ((np.eye(2), [[1, 0]], [1, 0], "0.1"), "zeta must be"),
                                        ((-np.eye(2), [[1, 0]], [1, 0], 0.1), "positive definite")])
def test_bad_input_is_refused(args, word):
    with pytest.raises(ValueError, match=word):
        impact_numbers(*args)
