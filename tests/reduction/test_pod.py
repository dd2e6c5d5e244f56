"""POD-Galerkin reduced models (#86, item 3a): the POD basis in the mass inner product and its projection-error
bound (``reduction.pod.pod_basis``), the change of coordinates that lets any basis run in the explicit contact scheme
(``reduction.pod.boundary_coordinates``), and a POD-Galerkin model reproducing its own snapshots: a small dense linear
model (Newmark, then the explicit scheme with casing contact) and the ci blade through the real builder
(``reduction.builder.build_from_basis``). Bad input is refused in one line naming the argument."""
import math

import numpy as np
import pytest
import scipy.linalg
import scipy.sparse as sp

from rotor37_rom.dynamics.casing import Casing
from rotor37_rom.dynamics.explicit import CentralDifference, simulate
from rotor37_rom.dynamics.newmark import simulate_newmark
from rotor37_rom.model.nodes import NodeMap
from rotor37_rom.model.reduced import ReducedModel
from rotor37_rom.reduction.pod import boundary_coordinates, pod_basis
from test_periodic_misuse import refused

EPS = np.finfo(float).eps
NAN, INF = math.nan, math.inf


def spd(rng, n: int, low: float = 1.0) -> np.ndarray:
    """A random symmetric positive definite (n, n) matrix with eigenvalues >= ``low``."""
    A = rng.standard_normal((n, n))
    return A @ A.T / n + low * np.eye(n)


def m_norms2(X: np.ndarray, M) -> np.ndarray:
    """Squared M-norms of the columns of X."""
    return np.einsum("ij,ij->j", X, np.asarray(M @ X))


def projection_error(S: np.ndarray, V: np.ndarray, M) -> float:
    """The relative mean-square M-norm error of the M-orthogonal projection of the columns of S onto span(V) (V
    M-orthonormal), computed directly: sum_j |s_j - V V^T M s_j|_M^2 / sum_j |s_j|_M^2."""
    R = S - V @ (V.T @ np.asarray(M @ S))
    return float(m_norms2(R, M).sum() / m_norms2(S, M).sum())


@pytest.mark.parametrize("sparse", [False, True])
def test_pod_of_snapshots_in_a_subspace_spans_it(sparse):
    """Snapshots in a known 5-dimensional subspace (60 DOFs, 40 snapshots, a non-diagonal mass): the 5 POD modes
    are M-orthonormal, span the subspace (the snapshots' projection residual at round-off), the bound is round-off
    (each discarded eigenvalue lies below the rank tolerance n_snap eps lambda_max, so the bound is below
    n_snap^2 eps), the numerical rank is 5 and r = 6 is refused."""
    rng = np.random.default_rng(3)
    n, k, n_snap = 60, 5, 40
    M = spd(rng, n)
    M = sp.csr_matrix(M) if sparse else M
    S = rng.standard_normal((n, k)) @ rng.standard_normal((k, n_snap))
    V, sigma, bound, rank = pod_basis(S, M, k)
    assert V.shape == (n, k) and sigma.shape == (n_snap,) and rank == k
    np.testing.assert_allclose(V.T @ np.asarray(M @ V), np.eye(k), atol=1e-13)
    assert projection_error(S, V, M) < 1e-26                                   # |residual| / |S| ~ 1e-13
    assert 0.0 <= bound <= n_snap ** 2 * EPS, bound
    assert np.all(np.diff(sigma) <= 0) and sigma[k] < 1e-6 * sigma[0]
    refused(lambda: pod_basis(S, M, k + 1), "r")


def test_pod_bound_is_the_discarded_eigenvalue_sum():
    """Closed forms. Snapshots S = Q diag(sigma) W^T with Q M-orthonormal and W orthonormal have the singular values
    sigma in the M inner product, and the bound of r modes is sum_{i > r} sigma_i^2 / sum sigma_i^2. On Gaussian
    snapshots the bound is the relative mean-square M-norm projection error of the snapshots, computed directly."""
    rng = np.random.default_rng(5)
    n, n_snap = 50, 30
    M = spd(rng, n)
    X = rng.standard_normal((n, 8))
    Q = X @ np.linalg.inv(np.linalg.cholesky(X.T @ M @ X).T)                    # Q^T M Q = I
    W, _ = np.linalg.qr(rng.standard_normal((n_snap, 8)))
    sigma = 2.0 ** -np.arange(8)
    S = Q @ np.diag(sigma) @ W.T
    for r in (1, 3, 7, 8):
        V, s, bound, _ = pod_basis(S, M, r)
        np.testing.assert_allclose(s[:8], sigma, rtol=1e-12)
        np.testing.assert_allclose(bound, (sigma[r:] ** 2).sum() / (sigma ** 2).sum(), rtol=1e-10, atol=1e-15)
        np.testing.assert_allclose(projection_error(S, V, M), bound, rtol=1e-10, atol=1e-15)
    G = rng.standard_normal((n, n_snap))
    lam = np.sort(scipy.linalg.eigvalsh(G.T @ M @ G))[::-1]
    for r in (1, 10, 25, 30):
        V, s, bound, rank = pod_basis(G, M, r)
        assert rank == n_snap
        np.testing.assert_allclose(s ** 2, lam, rtol=1e-10)
        np.testing.assert_allclose(bound, lam[r:].sum() / lam.sum(), rtol=1e-9, atol=1e-15)
        np.testing.assert_allclose(projection_error(G, V, M), bound, rtol=1e-9, atol=1e-14)


def modal_load_model(rng, n: int = 40, excited=(0, 2, 5, 7)):
    """A dense linear model (M, C Rayleigh, K; n DOFs) and a harmonic load that excites only the modes ``excited``:
    every displacement of the run from rest lies in their span."""
    M, K = spd(rng, n), 1e4 * spd(rng, n)
    _, Phi = scipy.linalg.eigh(K, M)
    C = 1e-3 * M + 1e-5 * K
    b = M @ Phi[:, list(excited)] @ rng.standard_normal(len(excited))

    def load(t):
        return b * np.sin(37.0 * t)

    return M, C, K, load


def test_pod_galerkin_reproduces_its_newmark_snapshots():
    """A POD-Galerkin model of a dense linear model's Newmark run (4 modes excited among 40, r = the snapshots'
    rank), run with the same scheme and step, lifts onto the full trajectory to round-off; so does the same model in
    the coordinates the contact scheme reads (``boundary_coordinates``: two DOFs made physical).

    Why round-off: Newmark is linear in the states and the load, and the full trajectory's displacements,
    velocities and accelerations (combinations of the displacements and a_0 = M^-1 f(0) = 0) lie in the span, so the
    full step's solution solves the Galerkin step, whose solution is unique. What remains is each step's round-off,
    ~cond(M/(beta h^2) + K) eps, and the Newton tolerance (rtol = 1e-13 on both sides), accumulated without growth
    (average acceleration's amplification has spectral radius 1): 200 steps x (1e-13 + cond eps) ~ 1e-10 of the
    largest displacement at most."""
    rng = np.random.default_rng(11)
    M, C, K, load = modal_load_model(rng)
    dt, n_steps = 2e-3, 200
    _, U = simulate_newmark(M, C, K, load, dt, n_steps, rtol=1e-13)
    pod = pod_basis(U, M, 4)
    assert pod.rank == 4
    V = pod.basis
    T = boundary_coordinates(V[[3, 17]], V.T @ K @ V, V.T @ M @ V)
    for Phi in (V, V @ T):
        _, q = simulate_newmark(Phi.T @ M @ Phi, Phi.T @ C @ Phi, Phi.T @ K @ Phi, lambda t: Phi.T @ load(t), dt,
                                n_steps, rtol=1e-13)
        err = np.abs(Phi @ q - U).max() / np.abs(U).max()
        assert err < 1e-10, err
    np.testing.assert_allclose((V @ T)[[3, 17]], np.eye(2, 4), atol=1e-12)


def hidden_subspace_model(rng):
    """A 14-DOF dense linear model whose first 3 DOFs are a contact node's (x, y, z) and which hides an invariant
    8-dimensional subspace: block-diagonal in coordinates p = Z^-1 q (the node and 5 interior coordinates, then 6
    others), with Z = [[I, 0], [Z21, Z22]] keeping the node's DOFs physical and mixing all the others. A load on the
    first block keeps every state of a contact run in that subspace (the contact force acts on the node's DOFs, p's
    first three). Returns (M, C Rayleigh, K, the first block's load shape on q)."""
    n_a, n = 8, 14
    blocks = [(spd(rng, n_a), 1e6 * spd(rng, n_a)), (spd(rng, n - n_a), 1e6 * spd(rng, n - n_a))]
    M_p, K_p = (scipy.linalg.block_diag(*(b[i] for b in blocks)) for i in (0, 1))
    Z = np.eye(n)
    Z[3:, :] += 0.3 * rng.standard_normal((n - 3, n))          # [[I, 0], [Z21, I + Z22]]
    Zi = np.linalg.inv(Z)
    M, K = Zi.T @ M_p @ Zi, Zi.T @ K_p @ Zi
    f_p = np.zeros(n)
    f_p[[0, 4]] = [400.0, 200.0]
    return M, 1e-4 * K + 2.0 * M, K, Zi.T @ f_p


def dense_model(M, C, K) -> ReducedModel:
    """A dense linear model whose first three DOFs are the tip node 'LE' at (0.25, 0, 0.1) m."""
    nodes = NodeMap.for_nodes(np.array([[0.25, 0.0, 0.1]]), np.arange(3)[None, :], ["LE"])
    return ReducedModel(M=M, C=C, K=K, forces=None, boundary_dofs=np.arange(3), nodes=nodes,
                        sizes={"r_b": 3, "r_c": K.shape[0] - 3, "r_md": 0}, md_pairs=np.zeros((0, 2), int),
                        Phi=None, metadata={})


def test_pod_galerkin_reproduces_its_contact_run():
    """The explicit contact scheme (casing bumps, friction 0.15, a harmonic load): a 14-DOF model's run stays in an
    8-dimensional subspace that no coordinate shows (``hidden_subspace_model``); POD finds its rank, 8, and the
    POD-Galerkin model in the coordinates ``boundary_coordinates`` gives (the node's DOFs first) reproduces the run
    with the same step: states, tip displacements and contact forces. Why round-off: the scheme's prediction is
    linear in the states and the load, and where the full step's corrected state lies in the span it solves the
    Galerkin step's contact problem with the same multiplier (unique: one node), so only round-off separates the
    runs, ~cond(2M + hC) eps a step over 3,000 steps of a stable, barely damped scheme."""
    rng = np.random.default_rng(2)
    M, C, K, f = hidden_subspace_model(rng)
    full = dense_model(M, C, K)
    scheme = CentralDifference(full, safety=0.5)
    casing = Casing(c0=0.5e-3, h_b=0.625e-3, mu=0.15)

    def run(model, load, h):
        return simulate(CentralDifference(model, h=h), [1500.0], casing, n_steps=3000, record_q=True,
                        record_every=4, forcing=lambda t: load * np.sin(2000.0 * t))

    ref = run(full, f, scheme.h)
    U = ref.records_q[0]
    assert ref.contact_steps[0] > 50, ref.contact_steps
    pod = pod_basis(U, M, 8)
    assert pod.rank == 8 and pod.bound < U.shape[1] * EPS             # the discarded eigenvalues: round-off
    V = pod.basis
    Phi = V @ boundary_coordinates(V[:3], V.T @ K @ V, V.T @ M @ V)
    galerkin = dense_model(Phi.T @ M @ Phi, Phi.T @ C @ Phi, Phi.T @ K @ Phi)
    res = run(galerkin, Phi.T @ f, scheme.h)
    err = np.abs(Phi @ res.records_q[0] - U).max() / np.abs(U).max()
    assert err < 1e-9, err
    np.testing.assert_allclose(res.u_r[0], ref.u_r[0], rtol=0, atol=1e-9 * np.abs(ref.u_r[0]).max())
    np.testing.assert_allclose(res.lam[0], ref.lam[0], rtol=0, atol=1e-8 * np.abs(ref.lam[0]).max())


# --- bad input: one line naming the argument ---------------------------------------------------------------------

S6, M6 = np.arange(12.0).reshape(6, 2) ** 2, np.eye(6)


@pytest.mark.parametrize("call, word", [
    (lambda: pod_basis(S6, M6, 0), "r must"),
    (lambda: pod_basis(S6, M6, 2.5), "r must"),
    (lambda: pod_basis(S6, M6, True), "r must"),
    (lambda: pod_basis(S6, M6, NAN), "r must"),
    (lambda: pod_basis(S6, M6, 3), "rank"),
    (lambda: pod_basis(np.zeros((6, 2)), M6, 1), "rank"),
    (lambda: pod_basis(np.where(S6 > 50, NAN, S6), M6, 1), "snapshots"),
    (lambda: pod_basis(np.where(S6 > 50, INF, S6), M6, 1), "snapshots"),
    (lambda: pod_basis(S6[:, 0], M6, 1), "snapshots"),
    (lambda: pod_basis(np.zeros((6, 0)), M6, 1), "snapshots"),
    (lambda: pod_basis("snapshots", M6, 1), "snapshots"),
    (lambda: pod_basis(S6 + 1j, M6, 1), "snapshots"),
    (lambda: pod_basis(S6, np.eye(5), 1), "M"),
    (lambda: pod_basis(S6, np.eye(6)[:, :5], 1), "M"),
    (lambda: pod_basis(S6, sp.eye(7, format="csr"), 1), "M"),
    (lambda: pod_basis(S6, np.full((6, 6), NAN), 1), "M"),
    (lambda: pod_basis(S6, -np.eye(6), 1), "M"),
    (lambda: pod_basis(S6, [[1.0]], 1), "M"),
    (lambda: boundary_coordinates(np.eye(2, 4), np.eye(4), np.eye(3)), "M"),
    (lambda: boundary_coordinates(np.eye(2, 4), np.eye(4)[:, :3], np.eye(4)), "K"),
    (lambda: boundary_coordinates(np.eye(2, 4), np.full((4, 4), INF), np.eye(4)), "K"),
    (lambda: boundary_coordinates(np.eye(2, 4), "K", np.eye(4)), "K"),
    (lambda: boundary_coordinates(np.eye(2, 4), np.eye(4), np.diag([1.0, 1.0, 1.0, -1.0])), "M"),
    (lambda: boundary_coordinates(np.eye(2, 4), np.diag([1.0, 1.0, 1.0, -1.0]), np.eye(4)), "K"),
    (lambda: boundary_coordinates(np.eye(5, 4), np.eye(4), np.eye(4)), "V_b"),
    (lambda: boundary_coordinates(np.zeros((0, 4)), np.eye(4), np.eye(4)), "V_b"),
    (lambda: boundary_coordinates(np.ones((2, 4)), np.eye(4), np.eye(4)), "V_b"),
    (lambda: boundary_coordinates(np.full((2, 4), NAN), np.eye(4), np.eye(4)), "V_b"),
    (lambda: boundary_coordinates([1.0, 0.0], np.eye(2), np.eye(2)), "V_b"),
])
def test_pod_refuses_bad_input_naming_the_argument(call, word):
    refused(call, word, errors=ValueError)


def test_ci_blade_pod_model_reproduces_its_snapshots(ci_blade, ci_ops, ci_rom):
    """The real builder on the ci blade: the r = 45 model's GNL contact run (exact tensors, casing bumps, friction
    0.15, 5,000 steps, ~600 in contact) lifted to fields is POD's snapshot set (rank 45, bound at round-off);
    ``build_from_basis`` makes the 45 POD modes a model (boundary DOFs first, exact tensors projected anew from the
    mesh), and its run with the same step lifts onto the snapshots.

    The tolerance, 1e-6 of the largest value, is that of this run's round-off, not of the algebra: the run amplifies
    perturbations (contact and GNL), and multiplying the reference's internal force by 1 + 1e-15
    (``model.reduced.perturbed_model``) moves its states by 7e-9 of their largest; the POD model (the same Galerkin
    model in other coordinates, built with round-off cond(M~) eps ~ 3e-9) measured 1.4e-8 (u_r 1.5e-8, contact forces
    1e-12). With 44 modes instead of 45 the lifted states miss by 2e-3, the tip's by 7e-3, the forces by 2.5e-2."""
    from rotor37_rom import fem
    from rotor37_rom.reduction.builder import build_from_basis

    h = CentralDifference(ci_rom, nonlinear=True, safety=0.5).h
    casing = Casing(mu=0.15)
    options = dict(n_steps=5000, record_q=True, record_every=10, phase=np.pi / 2 + 0.2)   # a bump at once
    ref = simulate(CentralDifference(ci_rom, nonlinear=True, h=h), [1400.0], casing, **options)
    assert ref.contact_steps[0] > 300, ref.contact_steps
    U = ci_rom.Phi @ ref.records_q[0]
    _, M_f, free = fem.assemble_free_operators(ci_blade, ci_ops)
    pod = pod_basis(U[free], M_f, ci_rom.r)
    assert pod.rank == ci_rom.r and pod.bound < U.shape[1] * EPS
    basis = np.zeros((U.shape[0], ci_rom.r))
    basis[free] = pod.basis
    model, report = build_from_basis(ci_blade, basis, ops=ci_ops, label="test: ci_rom's run")
    assert model.nodes.names == ci_rom.nodes.names and np.array_equal(model.nodes.q_index, ci_rom.nodes.q_index)
    np.testing.assert_array_equal(model.Phi[ci_rom.boundary_dofs], np.eye(24, ci_rom.r))
    assert np.allclose(model.Phi, basis @ report["transform"], rtol=0, atol=1e-12 * np.abs(model.Phi).max())
    assert model.sizes == {"r_b": 24, "r_c": ci_rom.r - 24, "r_md": 0} and model.forces.B.shape == ci_rom.forces.B.shape
    res = simulate(CentralDifference(model, nonlinear=True, h=h), [1400.0], casing, **options)
    assert np.abs(model.Phi @ res.records_q[0] - U).max() < 1e-6 * np.abs(U).max()
    np.testing.assert_allclose(res.u_r[0], ref.u_r[0], rtol=0, atol=1e-6 * np.abs(ref.u_r[0]).max())
    np.testing.assert_allclose(res.lam[0], ref.lam[0], rtol=0, atol=1e-6 * np.abs(ref.lam[0]).max())


def test_build_from_basis_refuses_bad_input_naming_the_argument(ci_blade, ci_ops, ci_rom):
    """Before any FE work where it can (the basis's shape, values, the force kind, the boundary DOFs' type), else
    once the free DOFs are known (a basis that does not vanish on the clamp or cannot hold the boundary DOFs)."""
    from rotor37_rom import fem
    from rotor37_rom.reduction.builder import build_from_basis

    Phi = ci_rom.Phi
    twin = Phi.copy()
    twin[:, 1] = twin[:, 0]                                   # two boundary DOFs that move together
    loose = Phi.copy()
    loose[np.setdiff1d(np.arange(Phi.shape[0]), fem.free_dofs(ci_blade))[0]] = 1.0     # not clamped
    for call, word in [
        (lambda: build_from_basis(ci_blade, Phi[:-1], ops=ci_ops), "basis"),
        (lambda: build_from_basis(ci_blade, Phi[:, 0], ops=ci_ops), "basis"),
        (lambda: build_from_basis(ci_blade, np.where(Phi > 0.5, NAN, Phi), ops=ci_ops), "basis"),
        (lambda: build_from_basis(ci_blade, "basis", ops=ci_ops), "basis"),
        (lambda: build_from_basis(ci_blade, Phi[:, :20], ops=ci_ops), "basis"),
        (lambda: build_from_basis(ci_blade, Phi, ops=ci_ops, forces="magic"), "forces"),
        (lambda: build_from_basis(ci_blade, Phi, boundary_dofs=[0.5, 1.5], ops=ci_ops), "boundary_dofs"),
        (lambda: build_from_basis(ci_blade, Phi, boundary_dofs=[-1, 2], ops=ci_ops, forces="none"), "boundary DOFs"),
        (lambda: build_from_basis(ci_blade, np.zeros_like(Phi), ops=ci_ops, forces="none"), "basis"),
        (lambda: build_from_basis(ci_blade, loose, ops=ci_ops, forces="none"), "clamped"),
        (lambda: build_from_basis(ci_blade, twin, ops=ci_ops, forces="none"), "boundary_dofs"),
    ]:
        refused(call, word, errors=ValueError, seconds=60.0)
