"""The Campbell diagram's algebra (#73), pure NumPy: modes followed across speeds, and their crossings with the
engine-order lines omega = e Omega.

A mode is followed from one speed to the next by its shape (the modal assurance criterion, MAC, of the unweighted
displacement vectors: 1 for the same shape, whatever its sign or scale), not by its rank in frequency, so that two
modes that cross or veer keep their names. Between two neighbouring speeds the squared frequency of a mode is
linear in Omega^2 to first order (Southwell: omega^2 = omega_0^2 + S Omega^2, geometric stiffening and spin
softening both quadratic in Omega), so a crossing with engine order e in that bracket solves
a + b Omega^2 = e^2 Omega^2 through the bracket's two points.
"""
from __future__ import annotations

import numpy as np

__all__ = ["mac", "track_modes", "engine_order_crossings", "gyroscopic_frequencies", "gyroscopic_modes",
           "excited_index", "excited_direction", "travelling_direction", "pair_envelope"]


def mac(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """MAC[i, j] = (a_i . b_j)^2 / (|a_i|^2 |b_j|^2) of the columns of A (n, p) and B (n, q)."""
    A, B = np.asarray(A, float), np.asarray(B, float)
    num = (A.T @ B) ** 2
    return num / np.outer(np.sum(A * A, axis=0), np.sum(B * B, axis=0))


def track_modes(frequencies: list, vectors: list) -> tuple[np.ndarray, np.ndarray]:
    """Follow the modes from speed to speed. ``frequencies``: per speed, (m,) ascending; ``vectors``: per speed,
    (n, m) shapes. Returns (omega (n_speeds, m): column k the mode that is k-th at the first speed, mac (n_speeds,)
    the smallest MAC of a pairing at each step, 1 at the first): each speed's modes paired with the previous speed's
    by the largest MAC, greedily from the best pair (a mode leaving the computed set shows as a low MAC)."""
    m = len(frequencies[0])
    omega = np.empty((len(frequencies), m))
    omega[0] = frequencies[0]
    worst = np.ones(len(frequencies))
    previous = np.asarray(vectors[0], float)
    for s in range(1, len(frequencies)):
        V = np.asarray(vectors[s], float)
        C = mac(previous, V)
        order = np.empty(m, dtype=int)
        taken_rows, taken_cols = set(), set()
        for flat in np.argsort(-C, axis=None):
            i, j = divmod(int(flat), C.shape[1])
            if i in taken_rows or j in taken_cols:
                continue
            order[i] = j
            taken_rows.add(i)
            taken_cols.add(j)
            if len(taken_rows) == m:
                break
        omega[s] = np.asarray(frequencies[s])[order]
        worst[s] = C[np.arange(m), order].min()
        previous = V[:, order]
    return omega, worst


def engine_order_crossings(speeds: np.ndarray, omega: np.ndarray, orders) -> list[dict]:
    """Where each followed mode (column of ``omega`` (n_speeds, m), rad/s, at ``speeds`` rad/s ascending) meets each
    engine order e: the speeds Omega (rad/s) with omega_k(Omega) = e Omega, one per bracket where omega_k - e Omega
    changes sign, solved with omega_k^2 linear in Omega^2 across the bracket. Returns dicts {'mode', 'order',
    'speed', 'frequency', 'bracket' (its two speeds' indices)} by speed."""
    speeds = np.asarray(speeds, float)
    omega = np.asarray(omega, float)
    out = []
    for k in range(omega.shape[1]):
        for e in orders:
            g = omega[:, k] - e * speeds
            for s in np.flatnonzero((g[:-1] > 0) != (g[1:] > 0)):
                x0, x1 = speeds[s] ** 2, speeds[s + 1] ** 2
                y0, y1 = omega[s, k] ** 2, omega[s + 1, k] ** 2
                b = (y1 - y0) / (x1 - x0)
                a = y0 - b * x0
                if e * e <= b:
                    continue                         # parallel to the line: no single crossing in the bracket
                W = float(np.sqrt(max(a, 0.0) / (e * e - b)))
                W = min(max(W, speeds[s]), speeds[s + 1])
                out.append({"mode": int(k), "order": int(e), "speed": W, "frequency": e * W,
                            "bracket": (int(s), int(s + 1))})
    return sorted(out, key=lambda c: c["speed"])


def gyroscopic_frequencies(K: np.ndarray, M: np.ndarray, G: np.ndarray) -> np.ndarray:
    """The frequencies (rad/s, ascending, > 0) of M u'' + G u' + K u = 0 with K symmetric positive definite, M
    symmetric positive definite and G skew-symmetric (a turning structure's Coriolis matrix times its speed): the
    eigenvalues of the first-order form are i omega in +- pairs (the system is conservative); the positive omegas,
    each once. ValueError if an eigenvalue has a real part beyond round-off (K not positive, G not skew)."""
    K, M, G = (np.asarray(A, float) for A in (K, M, G))
    n = K.shape[0]
    Minv = np.linalg.inv(M)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ K, -Minv @ G]])
    lam = np.linalg.eigvals(A)
    scale = np.abs(lam).max()
    if np.abs(lam.real).max() > 1e-8 * scale:
        raise ValueError(f"gyroscopic_frequencies: an eigenvalue leaves the imaginary axis by "
                         f"{np.abs(lam.real).max() / scale:.1e} of the largest: K and M must be positive definite and "
                         f"G skew-symmetric")
    return np.sort(lam.imag[lam.imag > 0])


def gyroscopic_modes(K: np.ndarray, M: np.ndarray, G: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(omega (n,) rad/s ascending, Z (n, n) complex): the modes of M u'' + G u' + K u = 0 (as
    ``gyroscopic_frequencies``), u = Re(Z[:, j] e^{i omega_j t}) with omega_j > 0, each column of unit norm."""
    K, M, G = (np.asarray(A, float) for A in (K, M, G))
    n = K.shape[0]
    Minv = np.linalg.inv(M)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ K, -Minv @ G]])
    lam, X = np.linalg.eig(A)
    scale = np.abs(lam).max()
    if np.abs(lam.real).max() > 1e-8 * scale:
        raise ValueError(f"gyroscopic_modes: an eigenvalue leaves the imaginary axis by "
                         f"{np.abs(lam.real).max() / scale:.1e} of the largest: K and M must be positive definite and "
                         f"G skew-symmetric")
    keep = np.flatnonzero(lam.imag > 0)
    keep = keep[np.argsort(lam.imag[keep])]
    Z = X[:n, keep]
    return lam.imag[keep], Z / np.linalg.norm(Z, axis=0)


def excited_index(order: int, n_sectors: int) -> int:
    """The harmonic index (nodal diameter) an engine order e excites on N identical sectors: e aliased by the
    sampling of the N sectors, k = min(e mod N, N - e mod N) (the zig-zag of the interference diagram)."""
    if int(order) != order or order < 0 or int(n_sectors) != n_sectors or n_sectors < 1:
        raise ValueError(f"engine order must be an integer >= 0 and N >= 1, got {order}, {n_sectors}")
    r = int(order) % int(n_sectors)
    return min(r, int(n_sectors) - r)


def excited_direction(order: int, n_sectors: int) -> str:
    """Which travelling wave of its index k an engine order excites, seen from the turning structure: a pattern
    with e lobes fixed to the ground moves against the rotation in the turning frame (e ≡ k mod N: 'backward'); its
    alias e ≡ -k mod N moves with it ('forward'); 'standing' for k = 0 and N/2 (one copy: no direction)."""
    k = excited_index(order, n_sectors)
    if k == 0 or 2 * k == int(n_sectors):
        return "standing"
    return "backward" if int(order) % int(n_sectors) == k else "forward"


def travelling_direction(z: np.ndarray, aa: np.ndarray, ab: np.ndarray, bb: np.ndarray) -> float:
    """The direction of the travelling wave u_s(t) = Re[(cos(s k alpha) A - sin(s k alpha) B) e^{i omega t}] (s the
    sector, omega > 0) with A = sum_j z_j a_j and B = sum_j z_j b_j over cos/sin fields (a_j, b_j): Im(A^H B) /
    (|A|^2 + |B|^2), from the Gram matrices aa = [a_i . a_j], ab = [a_i . b_j], bb = [b_i . b_j]: +1/2 for a wave
    moving towards increasing theta (the sense of rotation, 'forward': B = i A), -1/2 backward, 0 standing."""
    z = np.asarray(z, complex)
    cross = np.conj(z) @ (np.asarray(ab, float) @ z)
    energy = np.conj(z) @ ((np.asarray(aa, float) + np.asarray(bb, float)) @ z)
    return float(cross.imag / energy.real)


def pair_envelope(a: np.ndarray, b: np.ndarray | None) -> np.ndarray:
    """a^2 + b^2, entry by entry: a double mode's shape whatever the mix of its cos and sin members (any rotation
    (a, b) -> (a cos p - b sin p, a sin p + b cos p) leaves it unchanged), for following it across speeds."""
    a = np.asarray(a, float)
    return a * a if b is None else a * a + np.asarray(b, float) ** 2
