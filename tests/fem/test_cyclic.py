"""Cyclic symmetry operators on pure math: a ring of N identical 3-D truss sectors (with a node on the axis), whose
whole-ring spectrum is known by assembling all N sectors. No FE."""
import numpy as np
import pytest
import scipy.linalg

from rotor37_rom.disk.symmetry import (CyclicPairs, assemble_full_structure, cyclic_projection,
    cyclic_projection_parts, expand_sector_mode, harmonic_indices, project_cyclic, rotation_z, to_global_frame)


def _truss_sector(n_sectors: int, seed: int = 0, with_axis: bool = True):
    """One sector of a 3-D truss ring: 3 nodes on the left face (theta = 0), 4 inside, their images on the right
    face (theta = alpha), an axis node; bars between all nodes closer than a threshold (axial stiffness E A / L),
    ground springs on every node, lumped masses. Sector-frame coordinates; every sector is this one turned."""
    rng = np.random.default_rng(seed)
    alpha = 2 * np.pi / n_sectors
    face = np.array([[1.0, 0.0, 0.0], [1.3, 0.0, 0.2], [0.8, 0.0, 0.35]])
    inner = np.column_stack([rng.uniform(0.8, 1.3, 4), np.zeros(4), rng.uniform(0.0, 0.35, 4)])
    theta = rng.uniform(0.2, 0.8, 4) * alpha
    inner = np.column_stack([inner[:, 0] * np.cos(theta), inner[:, 0] * np.sin(theta), inner[:, 2]])
    right = face @ rotation_z(alpha).T
    nodes = np.vstack([face, inner, right] + ([np.array([[0.0, 0.0, 0.15]])] if with_axis else []))
    n_nodes = len(nodes)
    K = np.zeros((3 * n_nodes, 3 * n_nodes))
    M = np.zeros_like(K)
    for i in range(n_nodes):
        for j in range(i + 1, n_nodes):
            d = nodes[j] - nodes[i]
            L = np.linalg.norm(d)
            if L < 0.9 or (with_axis and j == n_nodes - 1 and i in (3, 4)):      # spokes to the axis node
                e = d / L
                k = 1e6 * (1 + rng.uniform()) / L * np.outer(e, e)
                idx = np.r_[3 * i:3 * i + 3, 3 * j:3 * j + 3]
                K[np.ix_(idx, idx)] += np.block([[k, -k], [-k, k]])
    K += 1e4 * np.diag(rng.uniform(0.5, 1.5, 3 * n_nodes))              # ground springs: no rigid motion
    M += np.diag(np.repeat(rng.uniform(0.5, 2.0, n_nodes), 3))
    dofs = np.arange(3 * n_nodes).reshape(-1, 3)
    pairs = CyclicPairs(n_sectors, left=dofs[:3], right=dofs[7:10], axis=dofs[10:] if with_axis else np.zeros((0, 3), int))
    return K, M, pairs, dofs


@pytest.mark.parametrize("n_sectors", [6, 7, 12])
def test_cyclic_spectrum_equals_the_assembled_ring(n_sectors):
    """The spectra of the projections for k = 0 ... N/2 are, together, the spectrum of the whole assembled ring
    (to 1e-8 relative: two dense eigen-solves of the same operator, round-off ~ u kappa ~ 1e-12). Every eigenvalue
    of the real 2n form for 0 < k < N/2 is double (the cos and sin modes); k = 0 and N/2 have single ones."""
    K, M, pairs, dofs = _truss_sector(n_sectors)
    K_full, M_full, _ = assemble_full_structure(K, M, pairs, dofs)
    full = scipy.linalg.eigh(K_full.toarray(), M_full.toarray(), eigvals_only=True)
    parts = []
    for k in harmonic_indices(n_sectors):
        Kk, Mk, _ = project_cyclic(K, M, pairs, k)
        lam = scipy.linalg.eigh(Kk.toarray(), Mk.toarray(), eigvals_only=True)
        if pairs.n_copies(k) == 2:
            np.testing.assert_allclose(lam[0::2], lam[1::2], rtol=1e-9)     # double modes
            assert np.all(np.diff(lam[0::2]) > 1e-6 * lam.max())              # ... and only double
        else:
            assert np.all(np.diff(lam) > 1e-9 * lam.max())                    # single modes (this truss)
        parts.append(lam)
    union = np.sort(np.concatenate(parts))
    assert union.size == full.size
    np.testing.assert_allclose(union, full, rtol=1e-8)


def test_expanded_modes_are_modes_of_the_whole_ring():
    """A sector mode of index k expanded to the N sectors (each turned to the common frame) satisfies the whole
    ring's eigenproblem (residual 1e-10 relative), matches across every left/right face, and has the same amplitude
    pattern on every sector up to the phase (for the real cos/sin pair: a^2 + b^2 per DOF is shared)."""
    N = 9
    K, M, pairs, dofs = _truss_sector(N)
    K_full, M_full, index = assemble_full_structure(K, M, pairs, dofs)
    for k in (0, 2, 4):
        Kk, Mk, T = project_cyclic(K, M, pairs, k)
        lam, X = scipy.linalg.eigh(Kk.toarray(), Mk.toarray())
        fields = T @ X[:, 0]
        n = K.shape[0]
        a, b = fields[:n], (fields[n:] if pairs.n_copies(k) == 2 else None)
        local = expand_sector_mode(a, b, k, N)
        u = np.zeros(K_full.shape[0])
        for s in range(N):
            glob = to_global_frame(local[s], dofs, s * 2 * np.pi / N)
            seen = u[index[s]] != 0
            np.testing.assert_allclose(u[index[s]][seen], glob[seen], rtol=1e-10, atol=1e-12 * np.abs(glob).max())
            u[index[s]] = glob
        res = K_full @ u - lam[0] * (M_full @ u)
        assert np.linalg.norm(res) <= 1e-10 * np.linalg.norm(K_full @ u)
        if b is not None:
            amp = local ** 2 + expand_sector_mode(b, -a, k, N) ** 2
            np.testing.assert_allclose(amp, np.broadcast_to(a ** 2 + b ** 2, amp.shape), rtol=1e-10, atol=1e-14)


def test_projection_is_linear_in_cos_and_sin():
    """T_k = T_0 + c T_c + s T_s exactly (c, s = cos, sin k alpha) for every 0 < k < N/2, and the projected stiffness
    is B_0 + c B_c + s B_s with three k-free matrices (T_s^T K2 T_s = T_c^T K2 T_c, the c s cross terms cancel):
    equal to T_k^T K2 T_k to round-off (1e-13 of |K|). The same real form commutes with J: (a, b) -> (-b, a)."""
    N = 12
    K, M, pairs, _ = _truss_sector(N, with_axis=False)
    n = K.shape[0]
    T0, Tc, Ts = cyclic_projection_parts(n, pairs)
    K2 = scipy.linalg.block_diag(K, K)
    P = [(T0 + Tc).toarray(), (T0 - Tc).toarray(), (T0 + Ts).toarray()]
    plus, minus, sine = (A.T @ K2 @ A for A in P)
    B0, Bc = 0.5 * (plus + minus), 0.5 * (plus - minus)
    Bs = sine - B0
    J = np.block([[np.zeros((n, n)), -np.eye(n)], [np.eye(n), np.zeros((n, n))]])
    for k in range(1, N // 2):
        c, s = np.cos(2 * np.pi * k / N), np.sin(2 * np.pi * k / N)
        T, _ = cyclic_projection(n, pairs, k)
        assert abs(T - (T0 + c * Tc + s * Ts)).max() <= 1e-15
        Kk = T.toarray().T @ K2 @ T.toarray()
        np.testing.assert_allclose(B0 + c * Bc + s * Bs, Kk, rtol=0, atol=1e-13 * np.abs(K).max())
        np.testing.assert_allclose(Kk @ J, J @ Kk, rtol=0, atol=1e-13 * np.abs(K).max())
    _, _, with_axis, _ = _truss_sector(N)
    with pytest.raises(ValueError, match="axis nodes"):
        cyclic_projection_parts(n + 3, with_axis)


def test_projection_identities_and_bad_input():
    """T_k is the identity on interior slots, maps each left DOF to its rotated, phase-shifted right image, and its
    eliminated columns are exactly the right face's (plus the axis node's constrained directions)."""
    N = 8
    K, M, pairs, dofs = _truss_sector(N)
    n = K.shape[0]
    T, kept = cyclic_projection(n, pairs, 3)
    c, s, R = np.cos(3 * np.pi / 4), np.sin(3 * np.pi / 4), rotation_z(np.pi / 4)
    x = np.zeros(2 * n)
    x[pairs.left[0]] = [1.0, 2.0, 3.0]                      # a on the first left node
    u = T @ x
    np.testing.assert_allclose(u[pairs.right[0]], c * R @ [1.0, 2.0, 3.0], rtol=1e-14)
    np.testing.assert_allclose(u[n + pairs.right[0]], s * R @ [1.0, 2.0, 3.0], rtol=1e-14)
    assert not kept[pairs.right.ravel()].any() and not kept[n + pairs.right.ravel()].any()
    # an axis node may only move along e_z for k = 0 (u = R u), in the plane for k = 1 (one complex circular
    # motion: 2 real ones in the cos/sin form), not at all for 1 < k < N/2
    for k, free in ((0, 1), (1, 2), (2, 0)):
        _, kept_k = cyclic_projection(n, pairs, k)
        slots = np.concatenate([copy * n + pairs.axis.ravel() for copy in range(pairs.n_copies(k))])
        assert kept_k[slots].sum() == free, (k, kept_k[slots].sum())
    with pytest.raises(ValueError, match="k must be an integer in \\[0, 4\\]"):
        cyclic_projection(n, pairs, 5)
    with pytest.raises(ValueError, match="number of sectors must be >= 2"):
        CyclicPairs(1, pairs.left, pairs.right)
    with pytest.raises(ValueError, match="pair one to one"):
        CyclicPairs(N, pairs.left, pairs.right[:2])
