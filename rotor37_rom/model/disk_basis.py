"""What rebuilds each sector's field from a bladed disk's reduced state: the disk model's per-sector basis
(``ReducedModel.sectors``), and the fields a sector's nonlinear force acts on."""
from __future__ import annotations

import dataclasses

import numpy as np


@dataclasses.dataclass(frozen=True)
class DiskBasis:
    """What rebuilds sector n's field from the disk's q (no reassembly): u^n = Phi_s q^n + Psi_L u_L^n +
    Psi_R' u_L^{n+1}, u_L = Pi eta (each sector's frame, free DOFs lifted to the full vector).

    Attributes: Phi_s (n, r_s), Psi_L (n, n_L), Psi_Rr (n, n_L): the right-face constraint modes times the rotation
    R, Pi (N n_L, r_cyclic), blocks (N, r_s) sector blocks of q, n_sectors."""

    Phi_s: np.ndarray
    Psi_L: np.ndarray
    Psi_Rr: np.ndarray
    Pi: np.ndarray
    blocks: np.ndarray
    n_sectors: int

    def __post_init__(self):
        object.__setattr__(self, "n_sectors", int(self.n_sectors))

    def sector_field(self, q: np.ndarray, n: int, dofs: np.ndarray | None = None) -> np.ndarray:
        """Sector n's displacement in its own frame for the disk state q (r,) or states (r, T): the full DOF vector,
        or only the DOFs ``dofs`` (cheap: only those rows of the basis are used)."""
        N, nL = self.n_sectors, self.Psi_L.shape[1]
        rows = slice(None) if dofs is None else np.asarray(dofs)
        uL = self.Pi @ q[self.blocks.size:]
        return (self.Phi_s[rows] @ q[self.blocks[n]] + self.Psi_L[rows] @ uL[n * nL:(n + 1) * nL]
                + self.Psi_Rr[rows] @ uL[((n + 1) % N) * nL:((n + 1) % N + 1) * nL])

    def project(self, f: np.ndarray, n: int) -> np.ndarray:
        """The reduced force (r,) of a force f (n_dofs,) on sector n in its own frame: the transpose of
        ``sector_field`` (the work of f on sector n's field equals that of the result on q)."""
        N, nL = self.n_sectors, self.Psi_L.shape[1]
        if not 0 <= n < N:
            raise ValueError(f"sector must be in 0 ... {N - 1}, got {n}")
        out = np.zeros(self.blocks.size + self.Pi.shape[1])
        out[self.blocks[n]] = self.Phi_s.T @ f
        right = (n + 1) % N
        out[self.blocks.size:] = (self.Pi[n * nL:(n + 1) * nL].T @ (self.Psi_L.T @ f)
                                  + self.Pi[right * nL:(right + 1) * nL].T @ (self.Psi_Rr.T @ f))
        return out


def sector_force_basis(basis: DiskBasis, faces: np.ndarray | None = None) -> np.ndarray:
    """The fields a sector's nonlinear force acts on (n_dofs, m), in the order of ``SectorForces.sector_states``:
    Phi_s, and with ``faces`` (``SectorForces.faces``) also Psi_L L and Psi_R' L. The face shapes L come back from
    faces[n, :n_f] = L^T Pi_n (every sector n) by least squares: L lies in the span of the faces' motions in the
    interface modes (``face_shapes`` takes it from their singular vectors), where that solution is exact."""
    if faces is None:
        return basis.Phi_s
    N, nL = basis.n_sectors, basis.Psi_L.shape[1]
    n_f = faces.shape[1] // 2
    if faces.shape != (N, 2 * n_f, basis.Pi.shape[1]):
        raise ValueError(f"faces must be (N = {N}, 2 n_f, r_cyclic = {basis.Pi.shape[1]}), got {faces.shape}")
    motions = basis.Pi.reshape(N, nL, -1).transpose(1, 0, 2).reshape(nL, -1)     # [Pi_0 ... Pi_(N-1)]
    L = np.linalg.lstsq(motions.T, faces[:, :n_f].transpose(0, 2, 1).reshape(-1, n_f), rcond=None)[0]
    return np.hstack([basis.Phi_s, basis.Psi_L @ L, basis.Psi_Rr @ L])
