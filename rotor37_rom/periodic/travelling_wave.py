"""The tuned disk's periodic response to a travelling load, on one sector: harmonic balance in the travelling-wave
subspace, and Hill stability against perturbations of every nodal diameter.

A tuned disk of N sectors loaded by a wave of k nodal diameters, f^s(t) = f^0(t - s Delta) on sector s (omega Delta
= theta = 2 pi k / N: the ``disk.loads`` waves), has a periodic response that is the same wave, q^s(tau) =
q^0(tau - s theta) on each sector block and the interface coordinates turned alike. Let R be the disk's turn by one
sector (sector s's field moved to sector s + 1; on the interface coordinates eta, Pi R_eta = S Pi with S the shift of
the sectors' interface blocks). In the complex Fourier form q(tau) = Re sum_h Q_h e^(i h tau), the wave is R Q_h =
e^(i h theta) Q_h: harmonic h lives in the nodal diameter h k (mod N), and its one-sector unknowns are the
coordinates of Q_h in that eigenspace of R (sector 0's r_s entries, the others follow by the phases e^(-i s h
theta), and the interface modes of that diameter).

The balance is the full disk's projected on that subspace (V^T R(V z)), but evaluated on one sector: the linear
operators per harmonic on the subspace, and the nonlinear force of sector 0 only, by alternating frequency-time on
sector 0's coordinates (its q^0 and, with faces, its face coordinates). Because R commutes with the disk's operators
and B_s = B_0 R^-s (B_s: sector s's force coordinates of q), the other sectors' forces are sector 0's delayed and
their projection is N times sector 0's: V^T G = N (B_0 V)^T g^0. So the cost is one sector's force, not N.

Stability (Hill's method on the full disk, block-diagonalised): a perturbation e^(lambda t) p(tau) of the wave splits
into classes j = 0 ... N/2: p's harmonic h in the eigenspaces e^(i (h theta +- 2 pi j / N)) of R (class j: nodal
diameter j in its constant part, the travelling wave's own subspace j = 0). The full disk's Hill matrices leave each
class invariant (the same argument), so the disk's exponents are the union of the classes', each from a problem of
one class's size. A class whose exponent crosses into the right half-plane names the diameters the wave loses
stability to.

``TravellingWaveBalance`` offers ``residual``, ``floquet_exponents``, ``size`` and ``split`` as ``HarmonicBalance``
does, so ``solve_periodic`` and ``continue_branch`` run on it; its solution's X is the one-sector unknowns (1, n),
``coefficients`` expands them to the disk's (2 H + 1, r). Pure NumPy/SciPy.
"""
from __future__ import annotations

import numpy as np
import scipy.linalg

from rotor37_rom.disk.harmonics import disk_blocks
from rotor37_rom.periodic.harmonic_balance import (Harmonics, harmonic_energy, hill_eigenvalues, hill_exponents,
                                                   square_matrices)

__all__ = ["TravellingWaveBalance", "travelling_excitation", "sector_turn"]


def sector_turn(model, tol: float = 1e-9) -> np.ndarray:
    """R_eta (r_c, r_c): the turn by one sector on a tuned disk model's interface coordinates, Pi R_eta = S Pi (S:
    sector s's interface block moved to s + 1). ValueError for a blade's model, sector blocks not first in q, or an
    interface basis the turn does not map into itself (relative residual above ``tol``)."""
    basis, N, _ = disk_blocks(model, "a travelling wave needs")
    Pi = np.asarray(basis.Pi, float)
    shifted = np.roll(Pi.reshape(N, -1, Pi.shape[1]), 1, axis=0).reshape(Pi.shape)
    R_eta = np.linalg.lstsq(Pi, shifted, rcond=None)[0]
    if np.linalg.norm(Pi @ R_eta - shifted) > tol * np.linalg.norm(Pi):
        raise ValueError("the model's interface modes are not mapped into themselves by a turn of one sector (not a "
                         "cyclic interface basis): no travelling wave on one sector")
    return R_eta


def travelling_excitation(P: np.ndarray, amplitude: float, n_diameters: int, basis: Harmonics) -> np.ndarray:
    """F (2 H + 1, r): the harmonic balance coefficients of the travelling load A sin(omega t - s k 2 pi / N) P[:, s]
    on every sector s (``disk.loads.travelling_load`` without its ramp), P (r, N) the reduced force of a unit load on
    each sector."""
    if basis.H < 1:
        raise ValueError("a travelling load needs H >= 1 (it is a first harmonic)")
    P = np.asarray(P, float)
    phase = np.arange(P.shape[1]) * n_diameters * 2 * np.pi / P.shape[1]
    F = np.zeros((basis.size, P.shape[0]))
    F[1] = -amplitude * (P @ np.sin(phase))            # sin(tau - phi) = cos(phi) sin(tau) - sin(phi) cos(tau)
    F[2] = amplitude * (P @ np.cos(phase))
    return F


class _Subspaces:
    """Real orthonormal bases of a tuned disk's harmonic coefficients whose complex form a - i b lies in given
    eigenspaces of the one-sector turn R: E(phi) = {w : R w = e^(i phi) w}, phi a multiple of 2 pi / N."""

    def __init__(self, N: int, rs: int, R_eta: np.ndarray, tol: float = 1e-8):
        self.N, self.rs, self.rc = N, rs, R_eta.shape[0]
        self.r = N * rs + self.rc
        lam = np.exp(2j * np.pi * np.arange(N) / N)
        self._eta = []
        for m in range(N):                            # the interface modes of each eigenvalue: a null space
            _, s, Vh = np.linalg.svd(R_eta - lam[m] * np.eye(self.rc))
            self._eta.append(Vh[s < tol * max(s.max(initial=0.0), 1.0)].conj().T if self.rc else
                             np.zeros((0, 0), complex))
        if sum(U.shape[1] for U in self._eta) != self.rc:
            raise ValueError("the turn of one sector is not diagonalisable on the interface modes (not a cyclic "
                             "interface basis)")

    def complex_basis(self, m: int) -> np.ndarray:
        """W (r, r_s + d): an orthonormal basis of E(2 pi m / N): sector s's block e^(-i s phi) I / sqrt(N), and
        the interface modes of that eigenvalue."""
        m %= self.N
        phi = 2 * np.pi * m / self.N
        U = self._eta[m]
        W = np.zeros((self.r, self.rs + U.shape[1]), complex)
        W[:self.N * self.rs, :self.rs] = np.kron(np.exp(-1j * phi * np.arange(self.N))[:, None] / np.sqrt(self.N),
                                                 np.eye(self.rs))
        W[self.N * self.rs:, self.rs:] = U
        return W

    def harmonic(self, h: int, indices) -> np.ndarray:
        """The real basis of harmonic h's coefficients with a - i b in the sum of E(2 pi m / N) over ``indices`` m:
        (r, d) for h = 0 (the constant's a, real: the indices must come in pairs m, -m), (2 r, d) of [a; b] else."""
        blocks = []
        for m in sorted({i % self.N for i in indices}):
            W = self.complex_basis(m)
            if h == 0:
                blocks += [W.real, W.imag]
            else:                                     # w -> (Re w, -Im w) and i w -> (-Im w, -Re w)
                blocks.append(np.block([[W.real, -W.imag], [-W.imag, -W.real]]))
        A = np.hstack(blocks)
        U, s, _ = np.linalg.svd(A, full_matrices=False)
        return U[:, s > 1e-8 * s.max()]


class TravellingWaveBalance:
    """Harmonic balance of a tuned disk's travelling-wave response, on one sector (module docstring).

    Args:
        model: a tuned disk's reduced model (``model.sectors`` set; its nonlinear force ``forces.sector.
            SectorForces`` with equal scales, or None: linear).
        excitation: F (2 H + 1, r): the disk's load coefficients (``travelling_excitation``), a wave of
            ``n_diameters``; it must lie in the wave's subspace (ValueError otherwise, naming its departure).
        basis: the Harmonics (n_time > 4 H balances the cubic force exactly).
        n_diameters: k, the load's nodal diameters (its wave travels towards increasing sector index; a negative k
            the other way).
        M, C, K: the operators (default the model's; e.g. the explicit scheme's capped mass): finite (r, r)
            matrices (ValueError naming the one that is not).
    """

    smooth = True              # polynomial forces: Newton may stop at its round-off floor

    def __init__(self, model, excitation: np.ndarray, basis: Harmonics, n_diameters: int, M=None, C=None, K=None):
        R_eta = sector_turn(model)
        N, rs = model.sectors.blocks.shape
        if not (isinstance(n_diameters, (int, np.integer)) and -N < n_diameters < N):
            raise ValueError(f"n_diameters must be an integer in {-(N - 1)}..{N - 1}, got {n_diameters!r}")
        self.model, self.basis, self.k, self.N, self.rs = model, basis, int(n_diameters), N, rs
        self.r = model.K.shape[0]
        self.M, self.C, self.K = square_matrices(**{name: model_A if A is None else A for name, A, model_A in
                                                    (("M", M, model.M), ("C", C, model.C), ("K", K, model.K))})
        if self.K.shape[0] != self.r:
            raise ValueError(f"M, C, K must be ({self.r}, {self.r}) like the model's, got {self.K.shape}")
        turn = self._turn_matrix(R_eta)
        for name, A in (("M", self.M), ("C", self.C), ("K", self.K)):
            if np.linalg.norm(turn.T @ A @ turn - A) > 1e-8 * max(np.linalg.norm(A), 1e-300):
                raise ValueError(f"the disk's {name} does not commute with a turn of one sector (a mistuned disk): "
                                 f"no travelling wave on one sector")
        forces = model.forces
        self.sector_force, self.faces = None, None
        if forces is not None:
            scales = np.asarray(forces.scales, float)
            if not np.all(scales == scales[0]):
                raise ValueError("the sectors' forces differ (a mistuned disk): no travelling wave on one sector")
            self.sector_force, self.scale, self.faces = forces.forces, float(scales[0]), forces.faces
            if self.faces is not None:                 # sector s + 1 sees the turned state as sector s saw it
                for s in range(N):
                    if np.linalg.norm(self.faces[(s + 1) % N] @ R_eta - self.faces[s]) > \
                            1e-8 * np.linalg.norm(self.faces[s]):
                        raise ValueError("the sectors' face coordinates do not turn with the disk: no travelling "
                                         "wave on one sector")
        self.space = _Subspaces(N, rs, R_eta)
        self.V = self._bases(0)
        self.sizes = [V.shape[1] for V in self.V]
        self.offsets = np.r_[0, np.cumsum(self.sizes)]
        F = np.asarray(excitation, float).reshape(basis.size, self.r)
        self.F = self.restrict(F)
        departure = np.linalg.norm(self.coefficients(self.F) - F)
        if departure > 1e-9 * max(np.linalg.norm(F), 1e-300):
            raise ValueError(f"the excitation is not a wave of {self.k} nodal diameters travelling towards increasing "
                             f"sector index (departure {departure / np.linalg.norm(F):.2g} of its norm)")
        self._E, self._P = basis.synthesis, basis.analysis
        self._A = self._sector_map(self.V)              # the wave's own class: sector 0's map, times N
        self._classes = {0: (self.V, self._projected(self.V), None)}     # j -> (bases, operators, sectors' maps)

    # --- the subspaces --------------------------------------------------------------------------------------------
    def _turn_matrix(self, R_eta: np.ndarray) -> np.ndarray:
        """R (r, r): the turn by one sector on q (sector s's block to s + 1, R_eta on eta)."""
        N, rs = self.N, self.rs
        R = np.zeros((self.r, self.r))
        R[:N * rs, :N * rs] = np.kron(np.roll(np.eye(N), 1, axis=0), np.eye(rs))
        R[N * rs:, N * rs:] = R_eta
        return R

    def _bases(self, j: int) -> list:
        """Per coefficient block (the constant, then each harmonic's pair) the real basis of class j: harmonic h in
        E(h theta + 2 pi j / N) + E(h theta - 2 pi j / N)."""
        return [self.space.harmonic(h, (h * self.k + j, h * self.k - j)) for h in range(self.basis.H + 1)]

    @property
    def classes(self) -> list:
        """The perturbation classes j = 0 ... N // 2 (nodal diameter j in a perturbation's constant part)."""
        return list(range(self.N // 2 + 1))

    @property
    def size(self) -> int:
        return int(self.offsets[-1])

    def coefficients(self, x: np.ndarray, V: list | None = None) -> np.ndarray:
        """The disk's coefficients X (2 H + 1, r) of the one-sector unknowns x."""
        x = np.asarray(x, float).ravel()
        return self._coefficient_columns(x[:, None], self.V if V is None else V).reshape(self.basis.size, self.r)

    def restrict(self, X: np.ndarray, V: list | None = None) -> np.ndarray:
        """x = V^T X: the one-sector unknowns of the disk's coefficients X (2 H + 1, r) (their projection)."""
        V = self.V if V is None else V
        X = np.asarray(X, float).reshape(self.basis.size, self.r)
        return np.concatenate([V[0].T @ X[0]] + [V[h].T @ X[2 * h - 1:2 * h + 1].ravel()
                                                 for h in range(1, self.basis.H + 1)])

    def split(self, x: np.ndarray):
        """(X, ()): a solution's X is the one-sector unknowns as one row (``coefficients`` expands them)."""
        return np.asarray(x, float).reshape(1, -1), ()

    # --- the operators on a subspace ------------------------------------------------------------------------------
    def _projected(self, V: list) -> dict:
        """Block-diagonal (by harmonic) projections on V of the linear parts: K, the omega and omega^2 terms of the
        balance, and Hill's C, 2 omega M D and M."""
        def pair(A, B):                                # [[A, B], [-B, A]] on [a; b]
            return np.block([[A, B], [-B, A]])

        Z = np.zeros_like(self.K)
        out = {name: [] for name in ("K", "C1", "M2", "HC", "HM1", "HM2")}
        out["K"].append(V[0].T @ self.K @ V[0])
        out["C1"].append(np.zeros((V[0].shape[1],) * 2))
        out["M2"].append(np.zeros((V[0].shape[1],) * 2))
        out["HC"].append(V[0].T @ self.C @ V[0])
        out["HM1"].append(np.zeros((V[0].shape[1],) * 2))
        out["HM2"].append(V[0].T @ self.M @ V[0])
        for h in range(1, self.basis.H + 1):
            B = V[h]
            out["K"].append(B.T @ pair(self.K, Z) @ B)
            out["C1"].append(B.T @ pair(Z, h * self.C) @ B)          # omega kron(D, C): (a, b) -> (h C b, -h C a)
            out["M2"].append(B.T @ pair(-h * h * self.M, Z) @ B)     # omega^2 kron(D^2, M)
            out["HC"].append(B.T @ pair(self.C, Z) @ B)
            out["HM1"].append(B.T @ pair(Z, h * self.M) @ B)         # kron(D, M)
            out["HM2"].append(B.T @ pair(self.M, Z) @ B)
        return {name: scipy.linalg.block_diag(*blocks) for name, blocks in out.items()}

    def _sector_map(self, V: list, n: int = 0) -> np.ndarray | None:
        """A ((2 H + 1) m, d): sector n's force coordinates' coefficients (coefficient-major) of the unknowns on V,
        advanced by n theta (sector n's orbit is sector 0's delayed by n theta: this puts it on sector 0's clock)."""
        if self.sector_force is None:
            return None
        rs, N = self.rs, self.N

        def bn(Q):                                     # (r, p) -> (m, p): [q^n; faces[n] eta]
            out = Q[n * rs:(n + 1) * rs]
            if self.faces is not None:
                out = np.vstack([out, self.faces[n] @ Q[N * rs:]])
            return out

        m = bn(V[0][:, :1]).shape[0]
        d = [B.shape[1] for B in V]
        A = np.zeros((self.basis.size, m, sum(d)))
        cols = np.r_[0, np.cumsum(d)]
        A[0, :, cols[0]:cols[1]] = bn(V[0])
        alpha = 2 * np.pi * self.k * n / N
        for h in range(1, self.basis.H + 1):
            a, b = bn(V[h][:self.r]), bn(V[h][self.r:])
            c, s = np.cos(h * alpha), np.sin(h * alpha)    # f(tau + alpha): (a, b) -> (a c + b s, -a s + b c)
            A[2 * h - 1, :, cols[h]:cols[h + 1]] = c * a + s * b
            A[2 * h, :, cols[h]:cols[h + 1]] = -s * a + c * b
        return A.reshape(self.basis.size * m, -1)

    def _class(self, j: int) -> tuple:
        """(bases, projected operators, every sector's map on sector 0's clock (N, (2 H + 1) m, d_j) or None) of
        class j, built once."""
        if j not in self._classes:
            V = self._bases(j)
            maps = None if self.sector_force is None else np.stack([self._sector_map(V, n) for n in range(self.N)])
            self._classes[j] = (V, self._projected(V), maps)
        return self._classes[j]

    def _sector_force(self, x: np.ndarray, A: np.ndarray, jacobian: bool):
        """Sector 0's force coefficients (2 H + 1) m and, with ``jacobian``, their Jacobian on sector 0's
        coefficients, at the orbit x (class 0's unknowns)."""
        m = A.shape[0] // self.basis.size
        Xs = (A @ x).reshape(self.basis.size, m)
        Q = (self._E @ Xs).T                                           # (m, n_time)
        g = self.scale * self.sector_force.evaluate(Q)
        G = (self._P @ g.T).ravel()
        if not jacobian:
            return G, None
        dG = self.scale * self.sector_force.jacobians(Q)
        n = self.basis.size * m
        Jg = np.einsum("at,tij,tb->aibj", self._P, dG, self._E).reshape(n, n)
        return G, Jg

    # --- the balance ----------------------------------------------------------------------------------------------
    def linear_matrix(self, omega: float, j: int = 0) -> np.ndarray:
        ops = self._class(j)[1]
        return ops["K"] + omega * ops["C1"] + omega ** 2 * ops["M2"]

    def residual(self, x: np.ndarray, omega: float, jacobian: bool = True, domega: bool = True):
        """R(x, omega) = V^T R_disk(V x, omega), and with ``jacobian`` dR/dx and dR/domega."""
        x = np.asarray(x, float).ravel()
        L = self.linear_matrix(omega)
        R = L @ x - self.F
        J = L if jacobian else None
        if self.sector_force is not None:
            G, Jg = self._sector_force(x, self._A, jacobian)
            R = R + self.N * (self._A.T @ G)
            if jacobian:
                J = J + self._class_force_jacobian(Jg, 0)
        if not jacobian:
            return R
        ops = self._class(0)[1]
        dR = (ops["C1"] + 2 * omega * ops["M2"]) @ x if domega else None
        return R, J, dR

    def _class_force_jacobian(self, Jg: np.ndarray, j: int) -> np.ndarray:
        """The disk's nonlinear force's balance Jacobian on class j: sum over the sectors of their maps' transposes
        times sector 0's Jacobian Jg times their maps (each sector's Jacobian is sector 0's delayed; on class 0 the
        sum is N times sector 0's term; on a class of a pair +-j the terms between +j and -j cancel over the sectors,
        so the sum is not N times one sector's)."""
        if j == 0:
            return self.N * (self._A.T @ Jg @ self._A)
        U = self._class(j)[2]
        return np.einsum("nai,ab,nbk->ik", U, Jg, U, optimize=True)

    def _orbit_jacobian(self, x: np.ndarray) -> np.ndarray | None:
        """Sector 0's force's balance Jacobian at the wave x (None for a linear model)."""
        return None if self.sector_force is None else self._sector_force(x, self._A, True)[1]

    def _hill_matrices(self, Jg, omega: float, j: int) -> tuple:
        """(J, D1, D2, stiffness) of Hill's problem on class j (``harmonic_balance.hill_eigenvalues``)."""
        ops = self._class(j)[1]
        J = self.linear_matrix(omega, j)
        if Jg is not None:
            J = J + self._class_force_jacobian(Jg, j)
        return J, ops["HC"] + 2 * omega * ops["HM1"], ops["HM2"], ops["K"]

    def class_basis(self, j: int) -> list:
        """Class j's real bases per coefficient block (the constant, then each harmonic's [a; b])."""
        return self._class(j)[0]

    def class_jacobian(self, x: np.ndarray, omega: float, j: int) -> np.ndarray:
        """Hill's J on class j: the disk's balance Jacobian at the wave x, projected on class j's subspace."""
        return self._hill_matrices(self._orbit_jacobian(np.asarray(x, float).ravel()), omega, j)[0]

    def class_exponents(self, x: np.ndarray, omega: float) -> dict:
        """{j: class j's Floquet exponents}: Hill's eigenvalues of every class (their union is the full disk's Hill
        spectrum), one copy of each exponent kept (``harmonic_balance.hill_exponents``) with the class it came from, by
        increasing real part."""
        Jg = self._orbit_jacobian(np.asarray(x, float).ravel())
        values, centres, labels = [], [], []
        for j in self.classes:
            J, D1, D2, K = self._hill_matrices(Jg, omega, j)
            lam, centre = hill_eigenvalues(J, D1, D2, lambda P, j=j: self._energy(P, j), stiffness=K)
            values.append(lam)
            centres.append(centre)
            labels.append(np.full(lam.size, j))
        values, centres, labels = np.concatenate(values), np.concatenate(centres), np.concatenate(labels)
        central = hill_exponents(values, centres, omega, self.basis.H)
        out = {}
        for j in self.classes:
            lam = values[central[labels[central] == j]]
            out[j] = lam[np.argsort(lam.real, kind="stable")]
        return out

    def _energy(self, P: np.ndarray, j: int) -> np.ndarray:
        """(2 H + 1, m): the energy of each complex harmonic -H .. H of class j's perturbations P (n_j, m), on the
        disk's coefficients."""
        V = self._class(j)[0]
        return harmonic_energy(self._coefficient_columns(P, V), self.basis.size, self.r)

    def _coefficient_columns(self, P: np.ndarray, V: list) -> np.ndarray:
        """The disk's coefficients (coefficient-major, (2 H + 1) r rows) of the columns P of unknowns on V."""
        offsets = np.r_[0, np.cumsum([B.shape[1] for B in V])]
        out = np.empty((self.basis.size, self.r, P.shape[1]), dtype=P.dtype)
        out[0] = V[0] @ P[offsets[0]:offsets[1]]
        for h in range(1, self.basis.H + 1):
            out[2 * h - 1:2 * h + 1] = (V[h] @ P[offsets[h]:offsets[h + 1]]).reshape(2, self.r, -1)
        return out.reshape(-1, P.shape[1])

    def floquet_exponents(self, x: np.ndarray, omega: float, J: np.ndarray | None = None) -> np.ndarray:
        """Every class's exponents together (the disk's 2 r), by increasing real part."""
        exps = np.concatenate(list(self.class_exponents(x, omega).values()))
        return exps[np.argsort(exps.real, kind="stable")]
