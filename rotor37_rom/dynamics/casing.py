"""Rigid casing with the two-lobe ovalization of the paper (§2.2.2, eqs. 37-38), contact directions at the tip nodes.

Pure NumPy. Angles in radians, lengths in metres, speeds in rad/s. The blade turns about e_z; ``rotation_sense`` = -1
(the default) means it turns towards -theta (NASA rotor 37, see the geometry notes), so a tip node's angle is
theta_b(t) = theta_0 + sense * Omega * t and it slides along sense * e_theta on the casing.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from rotor37_rom.checks import real_number

__all__ = ["Casing", "blade_hand", "check_hand", "casing_profile", "casing_clearance", "node_angles", "friction_power",
           "contact_frames", "contact_matrices", "check_node_hand", "ramp_rate", "ContactSolver", "ContactSetError",
           "CONE_SLOPE", "DIRECTIONS"]


def casing_profile(theta: np.ndarray, c0: float, p0: float, width: float = 0.15) -> np.ndarray:
    """Final distortion f(theta) of eq. 37: two Gaussian bumps of height c0 + p0 at theta = pi/2 and 3 pi/2."""
    theta = np.asarray(theta, float)
    x = theta - np.floor(theta / np.pi) * np.pi - 0.5 * np.pi
    return (c0 + p0) * np.exp(-(x / width) ** 2)


def casing_clearance(theta, t: float, c0, p0, alpha, width: float = 0.15) -> np.ndarray:
    """c0 - (1 - exp(-alpha t)) f(theta): the gap of eq. 38 before the node's own displacement. Arrays broadcast
    (e.g. theta (nodes, P) with c0, p0, alpha (P,))."""
    return c0 - (1.0 - np.exp(-alpha * t)) * casing_profile(theta, c0, p0, width)


def node_angles(theta0, omega, t: float, rotation_sense: int, phase=0.0) -> np.ndarray:
    """theta_b(t) = theta_0 + phase + sense * Omega * t: the tip nodes' angular positions on the casing. Arrays
    broadcast (e.g. theta0 (nodes, 1), omega and phase (1, P) for P runs)."""
    return theta0 + phase + rotation_sense * omega * t


def friction_power(mu_lambda, omega, radius, slide_velocity) -> np.ndarray:
    """The power -mu lambda (Omega r + v_s) of the friction force on a node that slides on the casing at
    Omega r (the rotation) plus its own velocity v_s along the sliding direction s: <= 0 when friction opposes
    the sliding. Arrays broadcast as in ``node_angles``."""
    return -mu_lambda * (omega * radius + slide_velocity)


def ramp_rate(duration: np.ndarray, fraction: float = 0.2, level: float = 0.99) -> np.ndarray:
    """alpha of eq. 38 such that 1 - exp(-alpha t) reaches ``level`` at ``fraction`` of ``duration``."""
    return -np.log(1.0 - level) / (fraction * np.asarray(duration, float))


CONE_SLOPE = 0.2737          # rotor 37's casing over the tip: r = 251.97 mm - 0.2737 (z - 6.32 mm) (NASA Table V)
DIRECTIONS = ("x", "radial", "cone")


def blade_hand(tip_nodes: np.ndarray) -> float:
    """The blade's stagger at its tip, as an angle about e_z: theta(TE) - theta(LE) (rad) of its contact nodes (LE
    first, TE last). A blade turns with its trailing edge behind its leading edge (the relative flow runs from LE to
    TE against the rotation): rotor 37's is +0.19 rad and it turns towards -theta."""
    tip = np.asarray(tip_nodes, float).reshape(-1, 3)
    return float(np.angle(np.exp(1j * (np.arctan2(tip[-1, 1], tip[-1, 0]) - np.arctan2(tip[0, 1], tip[0, 0])))))


def check_hand(tip_nodes: np.ndarray, rotation_sense: int, option: str = "--rotation-sense",
               below: float = np.radians(0.5)) -> float:
    """The blade's tip stagger (``blade_hand``), after checking that the rotation sense turns it with its trailing
    edge behind: ValueError naming ``option`` otherwise (a mirrored blade, or a blade given the other machine's
    sense), with the sense its hand asks for. A tip staggered less than ``below`` cannot tell: accepted."""
    stagger = blade_hand(tip_nodes)
    if abs(stagger) >= below and stagger * rotation_sense > 0:
        raise ValueError(f"{option} {rotation_sense:+d} turns this blade with its trailing edge ahead of its leading "
                         f"edge (theta(TE) - theta(LE) = {np.degrees(stagger):+.1f} deg at the tip); this blade's "
                         f"hand asks for {option} {-rotation_sense:+d}")
    return stagger


def contact_frames(nodes: np.ndarray, direction: str = "x", rotation_sense: int = -1, cone_slope: float = CONE_SLOPE,
                   frame_angle: float = 0.0):
    """Unit normal (outward) and sliding direction of each tip node at rest, in the frame of its blade.

    direction 'x': the blade frame's e_x for every node, as the paper does (§2.3): the radial direction of the plane
    at ``frame_angle`` about e_z (rad) in the nodes' frame, which holds the blade's centre of mass
    (``fem.Sector.blade_frame_angle``, kept as ``NodeMap.frame_angle``; 0: the file's own x);
    'radial': (x, y, 0)/|(x, y)|; 'cone': the normal of the conical casing r = r_0 - cone_slope z over the tip, e_r + cone_slope e_z normalised
    (rotor 37: tilted 15.3 deg from radial towards +z, downstream).
    Returns (normals (n, 3), slide (n, 3), theta0 (n,)): ``slide`` is the direction in which the node moves
    relative to the casing (rotation_sense * e_theta, in the casing's tangent plane for 'radial' and 'cone');
    friction on the blade acts along -slide; theta0 is the node's angle in the blade frame.
    """
    nodes = np.asarray(nodes, float).reshape(-1, 3)
    theta0 = np.arctan2(nodes[:, 1], nodes[:, 0])
    if direction == "x":
        c, s = np.cos(frame_angle), np.sin(frame_angle)
        normals = np.tile([c, s, 0.0], (len(nodes), 1))
        slide = np.tile([-rotation_sense * s, rotation_sense * c, 0.0], (len(nodes), 1))
    elif direction in ("radial", "cone"):
        normals = np.column_stack([np.cos(theta0), np.sin(theta0), np.full(len(nodes), 0.0)])
        if direction == "cone":
            normals[:, 2] = cone_slope
            normals /= np.linalg.norm(normals, axis=1)[:, None]
        slide = rotation_sense * np.column_stack([-np.sin(theta0), np.cos(theta0), np.zeros(len(nodes))])
    else:
        raise ValueError(f"direction must be one of {DIRECTIONS}, got {direction!r}")
    return normals, slide, theta0


def check_node_hand(nodes, rotation_sense: int, option: str = "rotation_sense") -> float | None:
    """``check_hand`` on a model's node map: the stagger of its nodes 'LE' and 'TE' of sector 0 (None where it has
    not both, e.g. a structure without a named tip), after refusing a sense that turns the blade with its trailing
    edge ahead (ValueError naming ``option``)."""
    names = [(n, s) for n, s in zip(nodes.names, nodes.sector.tolist())]
    if ("LE", 0) not in names or ("TE", 0) not in names:
        return None
    ends = nodes.coordinates[[nodes.row("LE"), nodes.row("TE")]]
    return check_hand(ends, rotation_sense, option)


def contact_matrices(nodes, r: int, casing: "Casing | None", rows=None):
    """Normal and sliding directions of contact nodes as rows over the reduced coordinates: u_n = N q, u_s = S q.

    The casing's rotation sense is checked against the blade's hand (``check_node_hand``: a sense that turns the
    blade with its trailing edge ahead, e.g. a mirrored blade given rotor 37's sense, is refused in one line), so
    every caller, not only the scenes, gets the check.

    Args:
        nodes: the model's ``model.nodes.NodeMap`` (which entries of q are which node, in which sector frame). r: size
        of q. casing: sets the normal direction and the rotation sense; None: e_x normals, S = 0 (what a run without
            contact records).
        rows: node-map rows to build (default: the casing's contact nodes, all nodes without a casing).
    Returns (N (n_c, r), S (n_c, r), theta0 (n_c,), rows (n_c,)): theta0 is each node's angle about e_z at rest,
    its sector's frame angle included (where the casing sits over it at t = 0).
    """
    if rows is None:
        rows = casing.node_indices(len(nodes)) if casing is not None else np.arange(len(nodes))
    rows = np.asarray(rows, dtype=np.int64).ravel()
    if rows.size and (rows.min() < 0 or rows.max() >= len(nodes)):
        raise ValueError(f"node rows must be in [0, {len(nodes) - 1}], got {rows.tolist()}")
    direction, sense = ("x", -1) if casing is None else (casing.direction, casing.rotation_sense)
    if casing is not None:
        check_node_hand(nodes, sense, "casing rotation_sense")
    slope = CONE_SLOPE if casing is None else casing.cone_slope
    normals, slide, theta_local = contact_frames(nodes.coordinates[rows], direction, sense, slope, nodes.frame_angle)
    if casing is None:
        slide = np.zeros_like(slide)
    theta0 = theta_local + nodes.angles[rows]
    N, S = np.zeros((len(rows), r)), np.zeros((len(rows), r))
    line = np.arange(len(rows))[:, None]
    N[line, nodes.q_index[rows]] = normals
    S[line, nodes.q_index[rows]] = slide
    return N, S, theta0, rows


@dataclasses.dataclass(frozen=True)
class Casing:
    """Casing and contact law (§2.2.2). Defaults are the paper's.

    Attributes:
        c0: clearance at rest (m), > 0 (paper 0.5 mm).
        h_b: height of the two bumps, c0 + p0 (m), >= 0 (paper 0.625 mm).
        mu: Coulomb sliding-friction coefficient, >= 0 (paper 0.15).
        ramp_fraction, ramp_level: the ovalization reaches ``ramp_level`` at ``ramp_fraction`` of the run (eq. 38).
        direction: 'x' (paper: e_x at every tip node), 'radial' or 'cone' (the conical casing's normal).
        rotation_sense: -1 (rotor 37 turns towards -theta) or +1.
        contact_nodes: rows of the model's node map (``ReducedModel.nodes``) that can touch; None = all.
        width: angular half-width parameter of the bumps (rad), eq. 37: 0.15.
        cone_slope: -dr/dz of the casing over the tip, for direction 'cone' (rotor 37: 0.2737).
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
    cone_slope: float = CONE_SLOPE

    def __post_init__(self):
        real_number("casing clearance c0", self.c0, 0, 0.05, open_low=True, open_high=True, unit=" m")
        real_number("bump height h_b", self.h_b, 0, 0.05, open_high=True, unit=" m")
        real_number("friction coefficient mu", self.mu, 0, 2)
        real_number("ramp_fraction", self.ramp_fraction, 0, 1, open_low=True)
        real_number("ramp_level", self.ramp_level, 0, 1, open_low=True, open_high=True)
        if self.direction not in DIRECTIONS:
            raise ValueError(f"direction must be one of {DIRECTIONS}, got {self.direction!r}")
        real_number("cone_slope", self.cone_slope, 0, 1)     # a casing half-angle up to 45 deg
        if self.rotation_sense not in (-1, 1) or isinstance(self.rotation_sense, bool):
            raise ValueError(f"rotation_sense must be -1 or +1, got {self.rotation_sense!r}")
        real_number("bump width", self.width, 0, np.pi / 2, open_low=True, open_high=True, unit=" rad")

    @property
    def p0(self) -> float:
        return self.h_b - self.c0

    def node_indices(self, n_nodes: int) -> np.ndarray:
        """The node-map rows that can touch, checked against the map's size."""
        if self.contact_nodes is None:
            return np.arange(n_nodes)
        idx = np.asarray(self.contact_nodes, dtype=np.int64).ravel()
        if idx.size == 0 or idx.min() < 0 or idx.max() >= n_nodes or len(set(idx.tolist())) != idx.size:
            raise ValueError(f"contact_nodes must be distinct node-map rows in [0, {n_nodes - 1}] "
                             f"(the nodes whose DOFs are kept in q), got {list(idx)}")
        return idx


class ContactSetError(RuntimeError):
    """No contact set gives admissible multipliers (the active-set iteration cycled, or a D_AA is singular)."""


class ContactSolver:
    """Multipliers lambda >= 0 of the casing contact with D_AA lambda_A = g_A on the active set A and no remaining
    gap < 0 elsewhere, for D = DN + mu DT (n_c, n_c), which maps multipliers to the change of the normal displacements
    (u_r += D lambda, so gap -= D lambda; the explicit reduced scheme's and the implicit full-order one's compliance
    alike); g: predicted gaps. Active-set iteration from the penetrating nodes, with the inverse of each
    D_AA met kept (per mu and active set: a blade meets a few, a disk's blades passing the bumps more; at most
    ``max_kept``, then the store starts again), since a sweep solves the same small systems millions of times."""

    def __init__(self, DN: np.ndarray, DT: np.ndarray, max_iter: int = 64, max_kept: int = 4096):
        self.DN, self.DT, self.max_iter, self.max_kept = DN, DT, max_iter, max_kept
        self._inverses: dict = {}

    def inverse(self, mu: float, active: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(A, D_AA^-1) of the active set ``active`` (a mask over the nodes), kept for the next call."""
        key = (float(mu), active.tobytes())
        if key not in self._inverses:
            if len(self._inverses) >= self.max_kept:          # a disk meets many sets as blades pass the bumps
                self._inverses.clear()
            A = np.nonzero(active)[0]
            try:
                self._inverses[key] = (A, np.linalg.inv((self.DN + mu * self.DT)[np.ix_(A, A)]))
            except np.linalg.LinAlgError as exc:
                raise ContactSetError(f"singular contact compliance on the nodes {A.tolist()}") from exc
        return self._inverses[key]

    def solve(self, mu: float, g: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(lambda, gaps after the correction) for predicted gaps g (n_c,)."""
        active = g < 0.0
        lam = np.zeros_like(g)
        tol = 1e-14 * max(1e-3, float(np.abs(g).max()))
        for _ in range(self.max_iter):
            lam[:] = 0.0
            if active.any():
                A, inv = self.inverse(mu, active)
                lam_A = inv @ g[A]
                if (lam_A < 0).any():
                    active[A[np.argmin(lam_A)]] = False
                    continue
                lam[A] = lam_A
            gap = g - self.DN @ lam - mu * (self.DT @ lam) if mu else g - self.DN @ lam
            viol = (~active) & (gap < -tol)
            if not viol.any():
                return lam, gap
            active[np.argmin(np.where(viol, gap, np.inf))] = True
        raise ContactSetError("contact active-set iteration did not converge")
