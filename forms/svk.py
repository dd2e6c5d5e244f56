"""St. Venant-Kirchhoff hyperelasticity in UFL (no dolfinx here: constants and functions come from the caller).

Every function is a small factory that returns a UFL expression or form; nothing is assembled here.

Notation: u displacement, F = I + grad u, E = (F^T F - I)/2 Green-Lagrange strain, S = lambda tr(E) I + 2 mu E second
Piola-Kirchhoff stress, W = lambda/2 tr(E)^2 + mu E:E strain energy density. The internal force is the first
variation f_int(u; v) = dW/du[v] = (F S) : grad v. Because E is quadratic in u, f_int is exactly cubic in u:
f_int(u) = K u + g_nl(u), with K the small-strain stiffness and g_nl = quadratic + cubic terms (paper eq. 1, 23).
"""
from __future__ import annotations

import ufl

__all__ = [
    "deformation_gradient",
    "green_lagrange_strain",
    "pk2_stress",
    "strain_energy_density",
    "strain_energy",
    "internal_force",
    "tangent_stiffness",
    "linear_stiffness",
    "mass",
    "centrifugal_force",
    "spin_softening",
    "coriolis",
    "nonlinear_force",
    "second_derivative",
    "third_derivative",
    "linear_stress",
    "cauchy_stress",
    "von_mises",
]


def deformation_gradient(u):
    """F = I + grad u."""
    return ufl.Identity(len(u)) + ufl.grad(u)


def green_lagrange_strain(u):
    """E = (F^T F - I)/2, written sym(grad u) + grad(u)^T grad(u)/2: the same polynomial without forming F^T F - I,
    whose cancellation keeps only about 16 + log10(eps) digits of a strain eps (a blade turning at 1 rad/s, strains
    ~1e-10: its static residual floored at 1.5e-6 of the load). Used where the value matters: the internal force,
    the energy, the stresses."""
    G = ufl.grad(u)
    return ufl.sym(G) + 0.5 * G.T * G


def _green_lagrange_strain_from_F(u):
    """The same E formed from F: its derivatives' kernels assemble 15-20 % faster (the ci blade's tangent: 91-100
    against 108-120 ms), and a tangent's round-off only slows Newton, it does not move its solution. Used for the
    tangent and the higher derivatives."""
    F = deformation_gradient(u)
    return 0.5 * (F.T * F - ufl.Identity(len(u)))


def pk2_stress(E, lmbda, mu):
    """S = lambda tr(E) I + 2 mu E (second Piola-Kirchhoff), from dW/dE."""
    E = ufl.variable(E)
    return ufl.diff(strain_energy_density(E, lmbda, mu), E)


def strain_energy_density(E, lmbda, mu):
    """W(E) = lambda/2 tr(E)^2 + mu E:E (J/m^3)."""
    return 0.5 * lmbda * ufl.tr(E) ** 2 + mu * ufl.inner(E, E)


def strain_energy(u, lmbda, mu, dx=ufl.dx):
    """Total strain energy Pi(u) = int W(E(u)) dx (a 0-form)."""
    return strain_energy_density(green_lagrange_strain(u), lmbda, mu) * dx


def internal_force(u, v, lmbda, mu, dx=ufl.dx):
    """f_int(u; v): first variation of the strain energy in direction v (a 1-form in v)."""
    return ufl.derivative(strain_energy(u, lmbda, mu, dx), u, v)


def _internal_force_from_F(u, v, lmbda, mu, dx=ufl.dx):
    """f_int with E formed from F (``_green_lagrange_strain_from_F``): what the derivatives differentiate."""
    energy = strain_energy_density(_green_lagrange_strain_from_F(u), lmbda, mu) * dx
    return ufl.derivative(energy, u, v)


def tangent_stiffness(u, v, du, lmbda, mu, dx=ufl.dx):
    """K_T(u): exact tangent, ufl.derivative of the internal force (a bilinear form in du, v); symmetric."""
    return ufl.derivative(_internal_force_from_F(u, v, lmbda, mu, dx), u, du)


def linear_stiffness(v, du, lmbda, mu, dx=ufl.dx):
    """K: small-strain stiffness, sigma(eps(du)) : eps(v) (= K_T(0))."""
    eps_u, eps_v = ufl.sym(ufl.grad(du)), ufl.sym(ufl.grad(v))
    return (lmbda * ufl.tr(eps_u) * ufl.tr(eps_v) + 2.0 * mu * ufl.inner(eps_u, eps_v)) * dx


def mass(v, du, rho, dx=ufl.dx):
    """M: consistent mass, rho du . v."""
    return rho * ufl.inner(du, v) * dx


def _radial(w):
    """P w: the part of a vector normal to the machine axis e_z (the rotation axis; x = r cos theta,
    y = r sin theta)."""
    return ufl.as_vector((w[0], w[1], 0.0))


def centrifugal_force(u, v, rho, spin, dx=ufl.dx):
    """rho spin^2 P (X + u) . v: the centrifugal body force on the structure turning at ``spin`` (rad/s) about e_z
    through the origin, at the deformed position X + u (a 1-form in v; its dead part is the u = 0 value)."""
    X = ufl.SpatialCoordinate(u.ufl_domain())
    return rho * spin**2 * ufl.inner(_radial(X + u), v) * dx


def spin_softening(v, du, rho, dx=ufl.dx):
    """M_P: rho P du . v, so that -spin^2 M_P is the derivative of ``centrifugal_force`` in u, negated (the spin
    softening of the rotating structure's tangent: K_T(u) - spin^2 M_P)."""
    return rho * ufl.inner(_radial(du), v) * dx


def coriolis(v, du, rho, dx=ufl.dx):
    """G_1: 2 rho (e_z x du) . v, so that spin G_1 u' is the Coriolis force of the structure turning at ``spin``
    (rad/s) about e_z, seen in the turning frame (M u'' + spin G_1 u' + (K_T - spin^2 M_P) u = f); skew-symmetric:
    it does no work."""
    return 2.0 * rho * ufl.inner(ufl.cross(ufl.as_vector((0.0, 0.0, 1.0)), du), v) * dx


def nonlinear_force(u, v, lmbda, mu, dx=ufl.dx):
    """g_nl(u; v) = f_int(u; v) - K(u, v): the quadratic and cubic part of the internal force (eq. 1)."""
    return internal_force(u, v, lmbda, mu, dx) - linear_stiffness(v, u, lmbda, mu, dx)


def second_derivative(u, v, w1, w2, lmbda, mu, dx=ufl.dx):
    """D^2 f_int(u)[w1, w2; v]: the directional derivative of K_T(u) w1 along w2 (a 1-form in v).

    At u = 0 this is the right-hand side of the modal-derivative equation (eq. 17): dK_T/d eta_k phi_j. For SVK it
    is affine in u.
    """
    return ufl.derivative(ufl.derivative(_internal_force_from_F(u, v, lmbda, mu, dx), u, w1), u, w2)


def third_derivative(u, v, w1, w2, w3, lmbda, mu, dx=ufl.dx):
    """D^3 f_int[w1, w2, w3; v]: constant for SVK; six times the cubic reduced-force coefficient (eq. 23)."""
    return ufl.derivative(second_derivative(u, v, w1, w2, lmbda, mu, dx), u, w3)


def linear_stress(u, lmbda, mu):
    """Small-strain Cauchy stress sigma = lambda tr(eps) I + 2 mu eps (GNL off)."""
    eps = ufl.sym(ufl.grad(u))
    return lmbda * ufl.tr(eps) * ufl.Identity(len(u)) + 2.0 * mu * eps


def cauchy_stress(u, lmbda, mu):
    """sigma = J^-1 F S F^T (exact SVK Cauchy stress)."""
    F = deformation_gradient(u)
    S = pk2_stress(green_lagrange_strain(u), lmbda, mu)
    return F * S * F.T / ufl.det(F)


def von_mises(sigma):
    """sqrt(3/2 s:s) with s the deviator of sigma (3D)."""
    s = sigma - ufl.tr(sigma) / 3.0 * ufl.Identity(3)
    return ufl.sqrt(1.5 * ufl.inner(s, s))
