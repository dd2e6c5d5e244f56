"""Loads on the bladed disk: a node's or a field's load travelling with N_d diameters, ramped."""
from __future__ import annotations

import numpy as np

from rotor37_rom.model.disk_basis import DiskBasis


def repeat_count(n_sectors: int, n_diameters: int) -> int:
    """Sectors over which a tuned disk's response to an N_d-diameter load repeats: N / gcd(N, N_d)."""
    if not (0 <= n_diameters <= n_sectors // 2):
        raise ValueError(f"N_d (nodal diameters) must be in [0, {n_sectors // 2}], got {n_diameters}")
    return n_sectors // int(np.gcd(n_sectors, n_diameters))


def harmonic_node_load(nodes, r: int, amplitude: float, omega: float, n_diameters: int, name: str = "LE",
                       component: int = 2, ramp: float = 0.0):
    """The reduced force of a travelling N_d-diameter load: A sin(omega t - s N_d 2 pi / N) on component
    ``component`` (sector frame: 0 x, 1 y, 2 z) of node ``name`` of every sector s. The node must be kept physical in
    q (a boundary node of the model's NodeMap): its row of the basis is the unit vector of its entry of q, so the
    reduced force is the nodal force itself. ``ramp`` (s): the envelope (1 - cos(pi t / ramp)) / 2 up to t = ramp
    (0: none; sectors whose phase is not 0 then start with a step). Returns t -> (r,)."""
    repeat_count(max(nodes.n_sectors, 1), n_diameters)
    return travelling_load(node_load_matrix(nodes, r, name, component), amplitude, omega, n_diameters, ramp)


def node_load_matrix(nodes, r: int, name: str = "LE", component: int = 2) -> np.ndarray:
    """P (r, N): the reduced force of a unit force on component ``component`` (sector frame) of node ``name`` of each
    sector s (column s); the node must be a boundary node of the model's NodeMap (its entry of q is the force)."""
    N = max(nodes.n_sectors, 1)
    if name not in nodes.names:
        raise ValueError(f"load node {name!r} is not in the model's boundary set {sorted(set(nodes.names))}")
    if component not in (0, 1, 2):
        raise ValueError(f"component must be 0, 1 or 2 (x, y, z), got {component}")
    P = np.zeros((r, N))
    P[[nodes.q_index[nodes.row(name, s), component] for s in range(N)], np.arange(N)] = 1.0
    return P


def harmonic_field_load(basis: DiskBasis, f: np.ndarray, amplitude: float, omega: float, n_diameters: int,
                        ramp: float = 0.0):
    """The reduced force of a travelling N_d-diameter load A sin(omega t - s N_d 2 pi / N) f on every sector s, f
    (n_dofs,) a sector load vector per unit amplitude in the sector's frame (e.g. ``fem.patch_load``), projected by
    ``DiskBasis.project``; the envelope as in ``harmonic_node_load``. Returns t -> (r,)."""
    N = basis.n_sectors
    repeat_count(N, n_diameters)
    if np.shape(f) != (basis.Phi_s.shape[0],):
        raise ValueError(f"the load vector must have the sector's {basis.Phi_s.shape[0]} DOFs, got {np.shape(f)}")
    P = np.stack([basis.project(np.asarray(f, dtype=float), s) for s in range(N)], axis=1)
    return travelling_load(P, amplitude, omega, n_diameters, ramp)


def travelling_load(P: np.ndarray, amplitude: float, omega: float, n_diameters: int, ramp: float):
    """t -> P (A e(t) sin(omega t - s N_d 2 pi / N))_s: P (r, N) the reduced force of a unit load on each sector."""
    if not ramp >= 0:
        raise ValueError(f"ramp must be >= 0 s, got {ramp}")
    phase = np.arange(P.shape[1]) * n_diameters * 2 * np.pi / P.shape[1]

    def load(t: float) -> np.ndarray:
        envelope = 1.0 if t >= ramp else 0.5 * (1.0 - np.cos(np.pi * t / ramp))
        return P @ (amplitude * envelope * np.sin(omega * t - phase))

    return load
