"""Clearance consumption (§2.3.2, Figs. 9-10): how the blade-tip/casing clearance at node LE changes as the blade
deforms statically along a clamped mode, full-order (linear, nonlinear) and reduced.

Procedure (paper): mode phi^X normalised so that the radial displacement of node LE is zeta; f^X = K phi^X; static
analyses under delta f^X for delta in [-1, 1]. The clearance is measured normal to the casing in the meridional
(z, r) plane, the casing being a cone parallel to the tip: Delta = c0 - c(delta) = (r' - r0) cos(beta) -
(z' - z0) sin(beta) with tan(beta) the cone slope dr/dz and r' the radius of the displaced node (so that even a
linear displacement field changes the radius nonlinearly). Delta > 0: the clearance is consumed.
"""
from __future__ import annotations

import dataclasses

import numpy as np

__all__ = ["clearance_change", "ClearanceCurves", "relative_error", "delta_range_within"]


def clearance_change(x0: np.ndarray, u: np.ndarray, slope: float) -> np.ndarray:
    """Delta for a node at x0 (3,) displaced by u (..., 3) (m); slope = dr/dz of the casing cone."""
    x = x0 + np.asarray(u)
    r0, r1 = np.hypot(x0[0], x0[1]), np.hypot(x[..., 0], x[..., 1])
    beta = np.arctan(slope)
    return (r1 - r0) * np.cos(beta) - (x[..., 2] - x0[2]) * np.sin(beta)


@dataclasses.dataclass(frozen=True)
class ClearanceCurves:
    """Delta(delta) curves: deltas (n,), curves {name: (n,) m}, costs {name: seconds}."""

    mode: str
    zeta: float
    deltas: np.ndarray
    curves: dict
    costs: dict


def relative_error(curve: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """Pointwise |curve - reference| / |reference| (both vanish at delta = 0, where the value is undefined: nan)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(reference != 0, np.abs(curve - reference) / np.abs(reference), np.nan)


def delta_range_within(deltas: np.ndarray, error: np.ndarray, tol: float = 0.1) -> tuple[float, float]:
    """The interval around 0 of deltas where ``error`` stays <= tol (the paper's 'linear model valid in [a, b]')."""
    order = np.argsort(deltas)
    d, e = deltas[order], error[order]
    zero = np.argmin(np.abs(d))
    lo = zero
    while lo - 1 >= 0 and not (e[lo - 1] > tol):
        lo -= 1
    hi = zero
    while hi + 1 < len(d) and not (e[hi + 1] > tol):
        hi += 1
    return float(d[lo]), float(d[hi])
