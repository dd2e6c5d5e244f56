"""How much an impact law can matter at steady state (issue #88, item 5): the impact number of each contact node.

A plastic impact of node k (its normal velocity v_n erased) takes the kinetic energy 1/2 m_eff v_n^2 of the node's
impact mass m_eff = 1 / (n_k^T M^-1 n_k) (a unit normal impulse changes the node's normal velocity by n_k^T M^-1 n_k).
A mode phi vibrating with the node's normal velocity amplitude v_n holds 1/2 m_mode v_n^2, m_mode = phi^T M phi /
(n_k^T phi)^2 (its modal mass referred to the node's normal motion), and viscous damping zeta takes 4 pi zeta of that
a cycle. Their ratio

    Pi_k = (m_eff / m_mode) / (4 pi zeta)

is the energy one impact can take (at the mode's own normal velocity) over what damping takes a cycle. Pi << 1: the
impact law (restitution, plastic or elastic, the regularisation of a harmonic balance) hardly moves a steady state
that the damping sets; Pi >~ 1 (a 1-DOF oscillator whose whole mass impacts: m_eff = m_mode) it decides it.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import scipy.linalg
import scipy.sparse
import scipy.sparse.linalg

__all__ = ["ImpactNumbers", "impact_numbers"]


@dataclasses.dataclass(frozen=True)
class ImpactNumbers:
    """Per contact node: m_eff (n_c,) its impact mass (kg), m_mode (n_c,) the mode's mass referred to its normal
    motion (kg; inf where the mode does not move it), ratio m_eff / m_mode, pi the impact number at ``zeta``."""

    m_eff: np.ndarray
    m_mode: np.ndarray
    ratio: np.ndarray
    zeta: float
    pi: np.ndarray


def impact_numbers(M, N, phi, zeta: float) -> ImpactNumbers:
    """The impact numbers of the contact nodes whose normal displacements are N x (N (n_c, n), dense or sparse) for
    the mode phi (n,) of a structure of mass M (n, n; dense or sparse, symmetric positive definite) damped at
    ``zeta`` (in (0, 1)). One line naming the argument for bad input."""
    sparse = scipy.sparse.issparse(M)
    if getattr(M, "ndim", 2) != 2 or M.shape[0] != M.shape[1]:
        raise ValueError(f"M must be a square matrix, got shape {getattr(M, 'shape', None)}")
    n = M.shape[0]
    N = N.toarray() if scipy.sparse.issparse(N) else np.atleast_2d(np.asarray(N, float))
    if N.ndim != 2 or N.shape[1] != n or not np.isfinite(N).all() or not N.shape[0]:
        raise ValueError(f"N must be finite with shape (n_c >= 1, {n}), got {N.shape}")
    phi = np.asarray(phi, float)
    if phi.shape != (n,) or not np.isfinite(phi).all() or not phi.any():
        raise ValueError(f"phi must be a finite nonzero ({n},) mode, got shape {phi.shape}")
    if not (isinstance(zeta, (float, int, np.floating)) and 0.0 < zeta < 1.0):
        raise ValueError(f"zeta must be in (0, 1), got {zeta!r}")
    if sparse:
        Minv_N = scipy.sparse.linalg.splu(scipy.sparse.csc_matrix(M)).solve(N.T)
        modal = float(phi @ (M @ phi))
    else:
        M = np.asarray(M, float)
        try:
            Minv_N = scipy.linalg.cho_solve(scipy.linalg.cho_factor(M), N.T)
        except np.linalg.LinAlgError:
            raise ValueError("M must be symmetric positive definite") from None
        modal = float(phi @ M @ phi)
    flexibility = np.einsum("ij,ji->i", N, Minv_N)
    if not (flexibility > 0).all():
        raise ValueError("M must be symmetric positive definite (a node's n^T M^-1 n is not > 0)")
    m_eff = 1.0 / flexibility
    motion = N @ phi
    with np.errstate(divide="ignore"):
        m_mode = np.where(motion != 0, modal / np.where(motion != 0, motion, 1.0) ** 2, np.inf)
    ratio = m_eff / m_mode
    return ImpactNumbers(m_eff, m_mode, ratio, float(zeta), ratio / (4 * np.pi * zeta))
