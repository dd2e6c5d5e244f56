"""A disk's reduced nonlinear force: one sector's force (exact tensors or a quadrature) evaluated for every
sector at once, the sectors as batch columns (eq. 61), optionally seeing the sector's faces."""
from __future__ import annotations

import dataclasses

import numpy as np

from rotor37_rom.forces.protocol import NonlinearForce


@dataclasses.dataclass(frozen=True)
class SectorForces:
    """The disk's reduced nonlinear force: one sector's reduced force ``forces`` applied to every sector, the sectors
    as batch columns (PolynomialForces or QuadratureForces).

    Without ``faces`` (eq. 61, the paper's linear coupling) sector n's force acts on its q^n only (r_s in, r_s out).
    With ``faces`` (n_f face coordinates per side) it acts on the sector's field including its faces:
    x^n = [q^n; a_L^n; a_R^n], [a_L^n; a_R^n] = faces[n] @ eta, eta = q[blocks.size:] the interface coordinates
    (a^n = L^T u_L^n on face shapes L, the right face's from the next sector), and its face rows are scattered back by
    faces[n]^T: the force is the gradient of the sum of the sectors' strain energies on those fields.

    Attributes:
        forces: the sector's reduced force (r_s + 2 n_f in and out); blocks: (N, r_s) entries of q of each sector's
            q^n; r: size of q; scales: (N,) factor of each sector's force (mistuning: a sector's E; 1 for a tuned
            disk); faces: None, or (N, 2 n_f, r_cyclic) each sector's face coordinates from eta.
    """

    forces: NonlinearForce
    blocks: np.ndarray
    r: int
    scales: np.ndarray
    faces: np.ndarray | None = None

    has_potential = False

    @property
    def precision(self) -> str:
        return self.forces.precision

    def with_precision(self, precision: str) -> "SectorForces":
        """The sector's force evaluated in ``precision`` (refused as the sector's force refuses it)."""
        return dataclasses.replace(self, forces=self.forces.with_precision(precision))

    def scaled(self, factor: float) -> "SectorForces":
        """The force times ``factor``: every sector's scale."""
        return dataclasses.replace(self, scales=np.asarray(self.scales, float) * factor)

    def premultiplied(self, X: np.ndarray) -> None:
        """None: the sectors' forces are evaluated, then mapped (on a tuned disk, per harmonic)."""
        return None

    def potential(self, Q: np.ndarray) -> np.ndarray:
        raise NotImplementedError("the potential of a disk's sector forces is not formed (has_potential is False)")

    def arrays(self) -> dict[str, np.ndarray]:
        """Its entries in a model's file: the sectors' blocks, scales and faces, then the sector's force's entries
        with its kind prefixed 'sector_' (``model.reduced``)."""
        out = {"sector_blocks": self.blocks, "sector_scales": self.scales}
        if self.faces is not None:
            out["sector_faces"] = self.faces
        inner = self.forces.arrays()
        return {**out, **inner, "forces": "sector_" + inner["forces"]}

    @classmethod
    def from_arrays(cls, arrays, forces: NonlinearForce, r: int) -> "SectorForces":
        return cls(forces, arrays["sector_blocks"], r, arrays["sector_scales"],
                   arrays["sector_faces"] if "sector_faces" in arrays else None)

    def _inputs(self, Q: np.ndarray) -> np.ndarray:
        """(N, r_s [+ 2 n_f], P): each sector's force coordinates."""
        N, rs = self.blocks.shape
        X = Q[self.blocks.ravel()].reshape(N, rs, Q.shape[1])
        if self.faces is None:
            return X
        return np.concatenate([X, np.einsum("nfc,cp->nfp", self.faces, Q[self.blocks.size:])], axis=1)

    def sector_states(self, Q: np.ndarray) -> np.ndarray:
        """(m, N P): the coordinates each sector's force acts on for the disk states Q (r, P), the sectors as
        columns (sector-major: column n P + p is sector n of state p), m = r_s (+ 2 n_f with faces)."""
        Q = np.asarray(Q, float).reshape(self.r, -1)
        X = self._inputs(Q)
        return X.transpose(1, 0, 2).reshape(X.shape[1], -1)

    def evaluate(self, Q: np.ndarray) -> np.ndarray:
        """g~(q) for Q (r,) or (r, P): (r, P); without ``faces`` the entries of the interface modes are 0."""
        Q = np.asarray(Q, float).reshape(self.r, -1)
        N, rs = self.blocks.shape
        P = Q.shape[1]
        X = self.sector_states(Q)
        m = X.shape[0]
        g = self.forces.evaluate(X).reshape(m, N, P) * self.scales[None, :, None]
        out = np.zeros((self.r, P))
        out[self.blocks.ravel()] = g[:rs].transpose(1, 0, 2).reshape(N * rs, P)
        if self.faces is not None:
            out[self.blocks.size:] = np.einsum("nfc,fnp->cp", self.faces, g[rs:])
        return out

    def jacobian(self, q: np.ndarray) -> np.ndarray:
        """dg~/dq (r, r) at one state: block-diagonal over the sectors (and their coupling through eta with faces)."""
        q = np.asarray(q, float).ravel()
        X = self._inputs(q[:, None])[:, :, 0]
        return self._assemble(self.forces.jacobians(X.T))

    def jacobians(self, Q: np.ndarray) -> np.ndarray:
        """``jacobian`` at each column of Q (r, P) -> (P, r, r): the N P sectors' Jacobians in one batch."""
        Q = np.asarray(Q, float).reshape(self.r, -1)
        N, P = self.blocks.shape[0], Q.shape[1]
        Jn = self.forces.jacobians(self.sector_states(Q))              # sector-major columns: (N P, m, m)
        m = Jn.shape[-1]
        Jn = Jn.reshape(N, P, m, m)
        return np.stack([self._assemble(Jn[:, p]) for p in range(P)]) if P else np.zeros((0, self.r, self.r))

    def _assemble(self, Js: np.ndarray) -> np.ndarray:
        """The disk's Jacobian (r, r) from the sectors' unscaled ones Js (N, m, m)."""
        rs = self.blocks.shape[1]
        eta = slice(self.blocks.size, self.r)
        J = np.zeros((self.r, self.r))
        for n, block in enumerate(self.blocks):                # N small Jacobians, one per sector
            Jn = self.scales[n] * Js[n]
            J[np.ix_(block, block)] = Jn[:rs, :rs]
            if self.faces is not None:
                E = self.faces[n]
                J[block, eta] += Jn[:rs, rs:] @ E
                J[eta, block] += E.T @ Jn[rs:, :rs]
                J[eta, eta] += E.T @ Jn[rs:, rs:] @ E
        return J
