"""Compressible neo-Hookean hyperelasticity in UFL: the second law against which St. Venant-Kirchhoff's geometric
nonlinearity is checked (#86). UFL only; nothing is assembled here.

W(F) = mu/2 (I_C - 3) - mu ln J + lambda/2 (ln J)^2, with C = F^T F, I_C = tr C, J = det F (e.g. Bonet & Wood,
Nonlinear continuum mechanics for finite element analysis, 2nd ed., eq. 6.28). Linearised at u = 0 it is Hooke's
law with the same Lame constants (lambda, mu), so it and SVK agree to first order in the strain and part at second
order. They part most in compression: SVK's W = lambda/2 tr(E)^2 + mu E:E stays bounded as J -> 0 (its stress in
uniaxial compression turns back towards zero past a stretch of 1/sqrt(3): the material softens), neo-Hookean's
grows without bound (-mu ln J). A response that depends on that softening differs between the two; one that does not
is geometric, and then both agree.

Unlike SVK's (exactly cubic in u), these forces are not polynomial: no reduced cubic tensor represents them; they
are evaluated on the full order (``fem``) and by quadrature-based reduced forces.
"""
from __future__ import annotations

import ufl

from .svk import deformation_gradient

__all__ = ["strain_energy_density", "strain_energy", "internal_force", "tangent_stiffness", "nonlinear_force",
           "pk1_stress"]


def strain_energy_density(F, lmbda, mu):
    """W(F) = mu/2 (tr(F^T F) - 3) - mu ln J + lambda/2 (ln J)^2 (J/m^3), J = det F."""
    ln_J = ufl.ln(ufl.det(F))
    return 0.5 * mu * (ufl.tr(F.T * F) - 3.0) - mu * ln_J + 0.5 * lmbda * ln_J ** 2


def pk1_stress(u, lmbda, mu):
    """P = dW/dF = mu (F - F^-T) + lambda ln J F^-T (first Piola-Kirchhoff), from the energy."""
    F = ufl.variable(deformation_gradient(u))
    return ufl.diff(strain_energy_density(F, lmbda, mu), F)


def strain_energy(u, lmbda, mu, dx=ufl.dx):
    """Total strain energy Pi(u) = int W(F(u)) dx (a 0-form)."""
    return strain_energy_density(deformation_gradient(u), lmbda, mu) * dx


def internal_force(u, v, lmbda, mu, dx=ufl.dx):
    """f_int(u; v) = P(u) : grad v: the first variation of the strain energy (a 1-form in v)."""
    return ufl.derivative(strain_energy(u, lmbda, mu, dx), u, v)


def tangent_stiffness(u, v, du, lmbda, mu, dx=ufl.dx):
    """K_T(u): the exact tangent, ufl.derivative of the internal force (a bilinear form in du, v); symmetric (the
    second variation of an energy)."""
    return ufl.derivative(internal_force(u, v, lmbda, mu, dx), u, du)


def nonlinear_force(u, v, lmbda, mu, dx=ufl.dx):
    """g_nl(u; v) = f_int(u; v) - K(u, v): everything beyond the small-strain stiffness (K: ``svk.linear_stiffness``,
    the same for both laws)."""
    from .svk import linear_stiffness

    return internal_force(u, v, lmbda, mu, dx) - linear_stiffness(v, u, lmbda, mu, dx)
