"""Compact parametric description of the NASA rotor 37 blade (sections 1-12 of Table IV).

The blade is described on its own surfaces of revolution by four smooth laws of a chordwise parameter and a spanwise
parameter:

* ``s`` in [0, 1]: normalised meridional arc length from LE (s = 0) to TE (s = 1), with the cosine angle
  ``phi = arccos(1 - 2 s)`` in [0, pi] used for the thickness;
* ``eta`` in [0, 1]: span fraction, section k of Table IV (k = 1..12) sits at eta = (k - 1)/11.

Laws (``x = 2 s - 1``, ``y = 2 eta - 1``):

* meridional position ``z(s, eta) = sum_ij Z_ij x^i y^j`` and ``r(s, eta) = sum_ij R_ij x^i y^j`` (m);
* camber angle ``theta_c(s, eta) = sum_ij C_ij T_i(x) y^j`` (rad; T_i Chebyshev polynomials);
* half circumferential thickness ``tau(s, eta) = sum_ij H_ij sin((i + 1) phi) y^j`` (m), which vanishes at the
  rounded LE and TE.

The suction side is at ``theta_c + tau / r`` and the pressure side at ``theta_c - tau / r`` (the rotor turns towards
-theta; see ../shared/data/rotor37/README.md). 73 numbers, fitted by least squares to Table IV with
:func:`fit_blade_law`, reproduce the 2400 table points to 0.23 mm (largest distance; see tests/test_geometry.py).
"""
from __future__ import annotations

import dataclasses

import numpy as np
from numpy.polynomial import chebyshev

from .tables import BladeTable

__all__ = ["BladeLaw", "fit_blade_law", "default_blade_law", "section_parameters"]

N_TABLE_SECTIONS = 12  # sections 1..12 of Table IV are lofted; 13 is the casing line


def _power(x: np.ndarray, degree: int) -> np.ndarray:
    return np.stack([x**i for i in range(degree + 1)], axis=-1)


def _sines(phi: np.ndarray, count: int) -> np.ndarray:
    return np.stack([np.sin((i + 1) * phi) for i in range(count)], axis=-1)


def _tensor(chord_basis: np.ndarray, span_basis: np.ndarray, coefficients: np.ndarray) -> np.ndarray:
    return np.einsum("...i,...j,ij->...", chord_basis, span_basis, coefficients)


@dataclasses.dataclass(frozen=True)
class BladeLaw:
    """Coefficient arrays of the four laws (see the module docstring); shapes set the degrees."""

    z: np.ndarray
    r: np.ndarray
    camber: np.ndarray
    half_thickness: np.ndarray

    @property
    def n_coefficients(self) -> int:
        return sum(a.size for a in (self.z, self.r, self.camber, self.half_thickness))

    def evaluate(self, s: np.ndarray, eta: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """z, r, theta_c, tau at broadcastable (s, eta); s, eta in [0, 1]. Units m, m, rad, m."""
        s, eta = np.broadcast_arrays(np.asarray(s, float), np.asarray(eta, float))
        x, y = 2.0 * s - 1.0, 2.0 * eta - 1.0
        phi = np.arccos(np.clip(1.0 - 2.0 * s, -1.0, 1.0))
        z = _tensor(_power(x, self.z.shape[0] - 1), _power(y, self.z.shape[1] - 1), self.z)
        r = _tensor(_power(x, self.r.shape[0] - 1), _power(y, self.r.shape[1] - 1), self.r)
        theta_c = _tensor(chebyshev.chebvander(x, self.camber.shape[0] - 1), _power(y, self.camber.shape[1] - 1),
                          self.camber)
        tau = _tensor(_sines(phi, self.half_thickness.shape[0]), _power(y, self.half_thickness.shape[1] - 1),
                      self.half_thickness)
        return z, r, theta_c, tau

    def side_points(self, eta: float, side: str, n_points: int = 80) -> np.ndarray:
        """Cartesian points (n_points, 3) of one side of the section at span fraction eta, LE to TE, cosine spaced."""
        if side not in ("suction", "pressure"):
            raise ValueError(f"side must be 'suction' or 'pressure', got {side!r}")
        s = 0.5 * (1.0 - np.cos(np.linspace(0.0, np.pi, n_points)))
        z, r, theta_c, tau = self.evaluate(s, np.full_like(s, eta))
        theta = theta_c + (1.0 if side == "suction" else -1.0) * tau / r
        return np.column_stack([r * np.cos(theta), r * np.sin(theta), z])


def section_parameters(table: BladeTable, n_sections: int = N_TABLE_SECTIONS) -> tuple[np.ndarray, np.ndarray]:
    """Chordwise s (normalised meridional arc length) and span fraction eta of every Table IV point."""
    z, r = table.z[:n_sections], table.r[:n_sections]
    arc = np.concatenate([np.zeros((n_sections, 1)), np.cumsum(np.hypot(np.diff(z), np.diff(r)), axis=1)], axis=1)
    s = arc / arc[:, -1:]
    eta = np.broadcast_to(np.linspace(0.0, 1.0, n_sections)[:, None], s.shape)
    return s, eta


def fit_blade_law(table: BladeTable, z_degrees=(3, 2), camber_degrees=(4, 4), thickness_degrees=(6, 3)) -> BladeLaw:
    """Least-squares fit of the four laws to sections 1-12 of Table IV.

    Args:
        table: Table IV as read by :func:`geometry.tables.read_blade_table`.
        z_degrees: (chordwise, spanwise) polynomial degrees of z and r.
        camber_degrees: (Chebyshev chordwise, spanwise) degrees of the camber angle.
        thickness_degrees: (number of sine terms, spanwise degree) of the half thickness.
    """
    n = N_TABLE_SECTIONS
    s, eta = section_parameters(table, n)
    x, y = 2.0 * s - 1.0, 2.0 * eta - 1.0
    phi = np.arccos(np.clip(1.0 - 2.0 * s, -1.0, 1.0))
    r = table.r[:n]
    theta_c = 0.5 * (table.theta_suction[:n] + table.theta_pressure[:n])
    tau = 0.5 * (table.theta_suction[:n] - table.theta_pressure[:n]) * r

    def solve(chord_basis, span_basis, target):
        design = (chord_basis[..., :, None] * span_basis[..., None, :]).reshape(target.size, -1)
        coef, *_ = np.linalg.lstsq(design, target.ravel(), rcond=None)
        return coef.reshape(chord_basis.shape[-1], span_basis.shape[-1])

    kz, dz = z_degrees
    kc, dc = camber_degrees
    kt, dt = thickness_degrees
    return BladeLaw(
        z=solve(_power(x, kz), _power(y, dz), table.z[:n]),
        r=solve(_power(x, kz), _power(y, dz), r),
        camber=solve(chebyshev.chebvander(x, kc), _power(y, dc), theta_c),
        half_thickness=solve(_sines(phi, kt), _power(y, dt), tau),
    )


def default_blade_law() -> BladeLaw:
    """The built-in rotor 37 blade: the 73 coefficients of :mod:`geometry._blade_law_data` (fitted to Table IV)."""
    from . import _blade_law_data as data

    return BladeLaw(z=np.array(data.Z), r=np.array(data.R), camber=np.array(data.CAMBER),
                    half_thickness=np.array(data.HALF_THICKNESS))
