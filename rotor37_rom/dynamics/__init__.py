"""Time integration: the explicit central-difference scheme with Lagrange-multiplier contact and friction,
the casing, implicit Newmark."""
