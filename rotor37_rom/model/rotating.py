"""A reduced model that turns (#73), pure NumPy: the blade turning at Omega about the machine axis e_z, in the turning
frame, on the span of its basis V (q measured from the blade at rest):

    M q'' + (C + Omega G) q' + (K - Omega^2 M_P) q + g(q) = Omega^2 F_c + f(t),

with M_P = V^T M_P V (the mass of the motions normal to the axis: the centrifugal force rho Omega^2 P (X + u) is
linear in u, so it reduces exactly), F_c = V^T rho P X (its part at rest) and G = V^T G_1 V (Coriolis, skew). No term
is fitted or interpolated: the equations are exactly polynomial in Omega. The speed enters the accuracy only through
the basis: the full-order centrifugal states at a few speeds (``ReductionConfig.spin_snapshots``) are in it, so that
the prestressed state and, through g's Jacobian there, the prestressed tangent K_T(u_c) are reproduced. At a
snapshot's speed the centrifugal state is in the span and the reduced equilibrium is the full-order one (Galerkin: the
residual's projection vanishes at the exact state); between snapshots it is an approximation whose error
``studies.rotating_rom`` measures. The model's range is [0, the largest snapshot's speed]: beyond it a speed is
refused (``check_spin``).

The static prestressed state q_c(Omega) is Newton on K q + g(q) - Omega^2 (F_c + M_P q) = 0 with the exact
Jacobian K + dg/dq - Omega^2 M_P, load steps in Omega^2; its modes are those of that Jacobian against M, with
Coriolis the gyroscopic problem on all r coordinates (``model.campbell.gyroscopic_frequencies``).
"""
from __future__ import annotations

import dataclasses
import numbers

import numpy as np
import scipy.linalg

from rotor37_rom.checks import real_number

__all__ = ["RotationTerms", "check_spin", "centrifugal_equilibrium", "rotating_stiffness", "rotating_modes"]


@dataclasses.dataclass(frozen=True)
class RotationTerms:
    """The rotation terms of a reduced model (per unit speed: multiply by Omega^2, Omega^2 and Omega).

    Attributes:
        M_P: (r, r) V^T M_P V (kg): the spin softening per unit Omega^2.
        F_c: (r,) V^T rho P X (N s^2): the centrifugal load of the blade at rest per unit Omega^2.
        G: (r, r) V^T G_1 V (kg), skew-symmetric: the Coriolis matrix per unit Omega.
        speeds: (s,) rad/s: the speeds whose full-order centrifugal states are in the basis; the model's range is
            0 ... max(speeds).
    """

    M_P: np.ndarray
    F_c: np.ndarray
    G: np.ndarray
    speeds: np.ndarray

    @property
    def top_speed(self) -> float:
        return float(np.max(self.speeds))

    def arrays(self) -> dict:
        """The entries of a model's file (``model.reduced.save_reduced_model``)."""
        return {"rotation_M_P": self.M_P, "rotation_F_c": self.F_c, "rotation_G": self.G,
                "rotation_speeds": np.asarray(self.speeds, float)}

    @classmethod
    def from_arrays(cls, arrays) -> "RotationTerms | None":
        if "rotation_M_P" not in arrays:
            return None
        return cls(M_P=arrays["rotation_M_P"], F_c=arrays["rotation_F_c"], G=arrays["rotation_G"],
                   speeds=arrays["rotation_speeds"])


def check_spin(model, spin: float) -> float:
    """``spin`` (rad/s) if ``model`` turns there within its range, else one ValueError naming it and the range (a
    speed that is not a real number, e.g. a string or a list, included: refused before NumPy sees it)."""
    terms = getattr(model, "rotation", None)
    if terms is None:
        raise ValueError("spin: this reduced model was built at rest (no rotation terms); build it with "
                         "spin_snapshots (ReductionConfig) to turn it")
    try:
        real_number("spin", spin, 0.0, unit=" rad/s")
    except ValueError:
        shown = f"{spin:g}" if isinstance(spin, numbers.Real) else f"{spin!r:.60}"
        raise ValueError(f"spin must be a finite speed >= 0 rad/s, got {shown}") from None
    if spin > terms.top_speed * (1.0 + 1e-12):
        raise ValueError(f"spin {spin:g} rad/s is outside this reduced model's range 0 ... {terms.top_speed:g} "
                         f"rad/s (the speeds of its centrifugal snapshots); rebuild it with spin_snapshots reaching it")
    return float(spin)


def _jacobian(model, q: np.ndarray) -> np.ndarray:
    return np.zeros((model.r, model.r)) if model.forces is None else model.forces.jacobian(q)


def centrifugal_equilibrium(model, spin: float, rtol: float = 1e-10, n_steps: int = 4,
                            max_iterations: int = 30) -> np.ndarray:
    """q_c (r,): K q + g(q) = Omega^2 (F_c + M_P q), Newton with the exact Jacobian from q = 0, ``n_steps`` equal
    steps in Omega^2, each to ||r|| <= rtol max(||Omega^2 F_c||, ||K q||). RuntimeError if a step does not
    converge."""
    spin = check_spin(model, spin)
    terms = model.rotation
    q = np.zeros(model.r)
    if spin == 0.0:
        return q
    for lam in np.linspace(0.0, 1.0, n_steps + 1)[1:]:
        s2 = lam * spin ** 2
        for it in range(max_iterations + 1):
            r = model.K @ q + model.nonlinear_force(q[:, None]).ravel() - s2 * (terms.F_c + terms.M_P @ q)
            ref = max(np.linalg.norm(s2 * terms.F_c), np.linalg.norm(model.K @ q), 1e-300)
            if np.linalg.norm(r) <= rtol * ref:
                break
            if it == max_iterations:
                raise RuntimeError(f"centrifugal equilibrium: Newton did not converge at {np.sqrt(s2):.6g} rad/s "
                                   f"(|r|/ref = {np.linalg.norm(r) / ref:.1e})")
            q = q - np.linalg.solve(model.K + _jacobian(model, q) - s2 * terms.M_P, r)
    return q


def rotating_stiffness(model, spin: float, q_c: np.ndarray | None = None) -> np.ndarray:
    """K + dg/dq(q_c) - Omega^2 M_P (r, r): the prestressed, spin-softened tangent at the centrifugal state q_c
    (solved if None)."""
    spin = check_spin(model, spin)
    q_c = centrifugal_equilibrium(model, spin) if q_c is None else np.asarray(q_c, float)
    A = model.K + _jacobian(model, q_c) - spin ** 2 * model.rotation.M_P
    return 0.5 * (A + A.T)


def rotating_modes(model, spin: float, coriolis: bool = False, q_c: np.ndarray | None = None
                   ) -> tuple[np.ndarray, np.ndarray]:
    """(omega (r,) rad/s ascending, q_c (r,)): the turning model's frequencies about its centrifugal state; with
    ``coriolis`` the gyroscopic problem M q'' + Omega G q' + K_T q = 0 on all r coordinates."""
    from .campbell import gyroscopic_frequencies

    spin = check_spin(model, spin)
    q_c = centrifugal_equilibrium(model, spin) if q_c is None else np.asarray(q_c, float)
    K_T = rotating_stiffness(model, spin, q_c)
    M = 0.5 * (model.M + model.M.T)
    if coriolis and spin > 0.0:
        return gyroscopic_frequencies(K_T, M, spin * model.rotation.G), q_c
    return np.sqrt(np.maximum(scipy.linalg.eigh(K_T, M, eigvals_only=True), 0.0)), q_c
