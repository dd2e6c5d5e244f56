"""Reduced nonlinear (St. Venant-Kirchhoff) forces: exact tensors, quadrature and cubature, STEP, a disk's
sector forces."""
