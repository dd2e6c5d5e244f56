"""The turning blade in the explicit scheme (#73): the rotation's force of each step, the state each run starts from,
and the clearance's reference. Pure NumPy.

A scheme that turns (``CentralDifference(..., rotation=Rotation())``) integrates, for each run p at its speed
Omega_p about e_z, in the turning frame (``model.rotating``),

    M q'' + C q' + K q + g(q) = Omega_p^2 (F_c + M_P q) + f(t)                          (GNL scheme)
    M q'' + C q' + K q + g(q_c) + J_c (q - q_c) = Omega_p^2 (F_c + M_P q) + f(t)         (linear scheme)

with q_c = q_c(Omega_p) the centrifugal state (K q_c + g(q_c) = Omega_p^2 (F_c + M_P q_c)) and J_c = dg/dq(q_c): the
linear scheme is the turning blade linearised about its prestressed state (tangent K + J_c - Omega^2 M_P: centrifugal
stiffening and spin softening, the linear rotating analysis's operator), the GNL scheme keeps the whole polynomial.
Each term joins the step's force explicitly, as g does; Coriolis (Omega G q') is left out: on the ci blade it moves
the frequencies by <= 0.70 rad/s and the 1B/EO4 crossing by <= 0.09 rad/s (docs/results-rotation.md), below what
the central difference's own frequency error does at the map's steps.

Clearance (``Rotation.clearance``): 'running' (the default) measures the casing's clearance c0 and the recorded
normal displacements from the running blade, its centrifugal state (the casing sits c0 beyond the tip's running
position: the clearance an engine is designed to); 'rest' measures both from the blade at rest, so the centrifugal
growth of the tip eats the clearance. Each run starts at its centrifugal state unless given another start.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import scipy.linalg

from rotor37_rom.disk.harmonics import HarmonicBlocks

__all__ = ["Rotation", "TurningRuns", "CLEARANCES", "prestressed_highest_frequency"]

CLEARANCES = ("running", "rest")


@dataclasses.dataclass(frozen=True)
class Rotation:
    """How a scheme turns its model (the model's ``rotation`` terms, each run at its own speed).

    Attributes:
        clearance: 'running' (the casing's c0 and the recorded displacements from the centrifugal state) or 'rest'
            (from the blade at rest).
    """

    clearance: str = "running"

    def __post_init__(self):
        if self.clearance not in CLEARANCES:
            raise ValueError(f"clearance must be one of {', '.join(CLEARANCES)}, got {self.clearance!r}")


def prestressed_highest_frequency(model, spin: float, M: np.ndarray, q_c: np.ndarray | None = None) -> float:
    """omega_max (rad/s) of the turning model's tangent K + dg/dq(q_c) - Omega^2 M_P against the mass ``M`` (a
    scheme's, capped or not): the explicit scheme's limit 2 / omega_max about the centrifugal state."""
    from rotor37_rom.model.rotating import rotating_stiffness

    r = M.shape[0]
    lam = scipy.linalg.eigh(rotating_stiffness(model, spin, q_c), M, eigvals_only=True, subset_by_index=[r - 1, r - 1])
    return float(np.sqrt(lam[-1]))


class TurningRuns:
    """The rotation of P runs at the speeds ``omega`` (P,) of a turning ``scheme``: their centrifugal states q_c
    (r, P), the force each step adds (``force``), the states the clearance and the records are measured from
    (``reference``). A linear scheme's runs are checked against the stability limit of their prestressed tangent
    (exact for the linearised model): ValueError naming the step it needs."""

    def __init__(self, scheme, omega: np.ndarray):
        from rotor37_rom.model.rotating import centrifugal_equilibrium, check_spin

        model = scheme.model
        spins = np.array([check_spin(model, w) for w in np.asarray(omega, float).ravel()])
        self.terms = model.rotation
        self.spin2 = spins ** 2
        self.q_c = np.column_stack([centrifugal_equilibrium(model, w) for w in spins])
        self.linearised = not scheme.nonlinear and model.forces is not None
        if self.linearised:
            # F = A_p q + b_p per run: A_p = Omega^2 M_P - J_c, b_p = Omega^2 F_c - g(q_c) + J_c q_c
            J_c = model.forces.jacobians(self.q_c)                            # (P, r, r)
            self.A = self.spin2[:, None, None] * self.terms.M_P[None] - J_c
            self.b = (self.terms.F_c[:, None] * self.spin2 - model.nonlinear_force(self.q_c)
                      + np.einsum("pij,jp->ip", J_c, self.q_c))
            for p, w in enumerate(spins):
                w_max = prestressed_highest_frequency(model, w, scheme.M, self.q_c[:, p])
                if scheme.h > 2.0 / w_max and not scheme.forced:
                    raise ValueError(f"time step h = {scheme.h:.4g} s exceeds the stability limit of the blade "
                                     f"prestressed at {w:g} rad/s, 2/omega_max = {2.0 / w_max:.4g} s; use h <= "
                                     f"{2.0 / w_max:.4g} s")
        # a tuned disk's M_P is block-circulant: applied per harmonic index (``HarmonicBlocks``), not densely
        sectors = getattr(model, "sectors", None)
        self.spin_softening = None if sectors is None or self.linearised else \
            HarmonicBlocks.from_operators(sectors.blocks, [self.terms.M_P], [model.K, model.M])
        running = scheme.rotation.clearance == "running"
        self.reference = self.q_c if running else np.zeros_like(self.q_c)

    def force(self, Q: np.ndarray, active: np.ndarray) -> np.ndarray:
        """The rotation's force (r, n_active) on the states Q of the runs ``active``."""
        if self.linearised:
            return np.matmul(self.A[active], Q.T[:, :, None])[:, :, 0].T + self.b[:, active]
        M_P_Q = self.terms.M_P @ Q if self.spin_softening is None else self.spin_softening.apply(Q)
        return (self.terms.F_c[:, None] + M_P_Q) * self.spin2[active]
