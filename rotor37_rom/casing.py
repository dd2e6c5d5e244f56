"""Rigid casing with the two-lobe ovalization of the paper (§2.2.2, eqs. 37-38), contact directions at the tip nodes.

Pure NumPy. Angles in radians, lengths in metres, speeds in rad/s. The blade turns about e_z; ``rotation_sense`` = -1
(the default) means it turns towards -theta (NASA rotor 37, see the geometry notes), so a tip node's angle is
theta_b(t) = theta_0 + sense * Omega * t and it slides along sense * e_theta on the casing.
"""
from __future__ import annotations

import dataclasses

import numpy as np

__all__ = ["Casing", "casing_profile", "casing_clearance", "contact_frames", "contact_matrices", "ramp_rate"]


def casing_profile(theta: np.ndarray, c0: float, p0: float, width: float = 0.15) -> np.ndarray:
    """Final distortion f(theta) of eq. 37: two Gaussian bumps of height c0 + p0 at theta = pi/2 and 3 pi/2."""
    theta = np.asarray(theta, float)
    x = theta - np.floor(theta / np.pi) * np.pi - 0.5 * np.pi
    return (c0 + p0) * np.exp(-(x / width) ** 2)


def casing_clearance(theta, t: float, c0, p0, alpha, width: float = 0.15) -> np.ndarray:
    """c0 - (1 - exp(-alpha t)) f(theta): the gap of eq. 38 before the node's own displacement. Arrays broadcast
    (e.g. theta (nodes, P) with c0, p0, alpha (P,))."""
    return c0 - (1.0 - np.exp(-alpha * t)) * casing_profile(theta, c0, p0, width)


def ramp_rate(duration: np.ndarray, fraction: float = 0.2, level: float = 0.99) -> np.ndarray:
    """alpha of eq. 38 such that 1 - exp(-alpha t) reaches ``level`` at ``fraction`` of ``duration``."""
    return -np.log(1.0 - level) / (fraction * np.asarray(duration, float))


def contact_frames(nodes: np.ndarray, direction: str = "x", rotation_sense: int = -1):
    """Unit normal (outward 'radial') and sliding direction of each tip node at rest.

    direction 'x': e_x for every node, as the paper does (§2.3); 'radial': (x, y, 0)/|(x, y)|.
    Returns (normals (n, 3), slide (n, 3), theta0 (n,)): ``slide`` is the direction in which the node moves
    relative to the casing (rotation_sense * e_theta); friction on the blade acts along -slide.
    """
    nodes = np.asarray(nodes, float).reshape(-1, 3)
    theta0 = np.arctan2(nodes[:, 1], nodes[:, 0])
    if direction == "x":
        normals = np.tile([1.0, 0.0, 0.0], (len(nodes), 1))
        slide = np.tile([0.0, float(rotation_sense), 0.0], (len(nodes), 1))
    elif direction == "radial":
        normals = np.column_stack([np.cos(theta0), np.sin(theta0), np.zeros(len(nodes))])
        slide = rotation_sense * np.column_stack([-np.sin(theta0), np.cos(theta0), np.zeros(len(nodes))])
    else:
        raise ValueError(f"direction must be 'x' or 'radial', got {direction!r}")
    return normals, slide, theta0


def contact_matrices(boundary_nodes: np.ndarray, r: int, casing: "Casing | None"):
    """Normal and sliding directions of the contact nodes as rows over the reduced coordinates, whose first
    3 x n_b entries are the boundary nodes' displacements (Craig-Bampton): u_n = N q, u_s = S q.

    Returns (N (n_c, r), S (n_c, r), theta0 (n_c,), node indices (n_c,)). Without a casing every boundary node
    is listed with the e_x normal (what a run without contact records) and S = 0.
    """
    nodes = np.asarray(boundary_nodes, float).reshape(-1, 3)
    if casing is not None:
        idx = casing.node_indices(len(nodes))
        normals, slide, theta0 = contact_frames(nodes[idx], casing.direction, casing.rotation_sense)
    else:
        idx = np.arange(len(nodes))
        normals, slide = np.tile([1.0, 0.0, 0.0], (len(nodes), 1)), np.zeros((len(nodes), 3))
        theta0 = np.arctan2(nodes[:, 1], nodes[:, 0])
    rows = np.arange(len(idx))[:, None]
    dofs = 3 * idx[:, None] + np.arange(3)[None, :]
    N, S = np.zeros((len(idx), r)), np.zeros((len(idx), r))
    N[rows, dofs] = normals
    S[rows, dofs] = slide
    return N, S, theta0, idx


@dataclasses.dataclass(frozen=True)
class Casing:
    """Casing and contact law (§2.2.2). Defaults are the paper's.

    Attributes:
        c0: clearance at rest (m), > 0 (paper 0.5 mm).
        h_b: height of the two bumps, c0 + p0 (m), >= 0 (paper 0.625 mm).
        mu: Coulomb sliding-friction coefficient, >= 0 (paper 0.15).
        ramp_fraction, ramp_level: the ovalization reaches ``ramp_level`` at ``ramp_fraction`` of the run (eq. 38).
        direction: 'x' (paper: e_x at every tip node) or 'radial'.
        rotation_sense: -1 (rotor 37 turns towards -theta) or +1.
        contact_nodes: indices of the tip nodes (rows of the model's boundary nodes) that can touch; None = all.
        width: angular half-width parameter of the bumps (rad), eq. 37: 0.15.
    """

    c0: float = 0.5e-3
    h_b: float = 0.625e-3
    mu: float = 0.15
    ramp_fraction: float = 0.2
    ramp_level: float = 0.99
    direction: str = "x"
    rotation_sense: int = -1
    contact_nodes: tuple | None = None
    width: float = 0.15

    def __post_init__(self):
        if not (0.0 < self.c0 < 0.05):
            raise ValueError(f"casing clearance c0 must be in (0, 0.05) m, got {self.c0}")
        if not (0.0 <= self.h_b < 0.05):
            raise ValueError(f"bump height h_b must be in [0, 0.05) m, got {self.h_b}")
        if not (0.0 <= self.mu <= 2.0):
            raise ValueError(f"friction coefficient mu must be in [0, 2], got {self.mu}")
        if not (0.0 < self.ramp_fraction <= 1.0) or not (0.0 < self.ramp_level < 1.0):
            raise ValueError("ramp_fraction must be in (0, 1] and ramp_level in (0, 1)")
        if self.direction not in ("x", "radial"):
            raise ValueError(f"direction must be 'x' or 'radial', got {self.direction!r}")
        if self.rotation_sense not in (-1, 1):
            raise ValueError(f"rotation_sense must be -1 or +1, got {self.rotation_sense}")
        if not (0.0 < self.width < np.pi / 2):
            raise ValueError(f"bump width must be in (0, pi/2) rad, got {self.width}")

    @property
    def p0(self) -> float:
        return self.h_b - self.c0

    def node_indices(self, n_boundary_nodes: int) -> np.ndarray:
        if self.contact_nodes is None:
            return np.arange(n_boundary_nodes)
        idx = np.asarray(self.contact_nodes, dtype=np.int64).ravel()
        if idx.size == 0 or idx.min() < 0 or idx.max() >= n_boundary_nodes or len(set(idx.tolist())) != idx.size:
            raise ValueError(f"contact_nodes must be distinct boundary-node indices in [0, {n_boundary_nodes - 1}] "
                             f"(the nodes whose DOFs are kept in q), got {list(idx)}")
        return idx
