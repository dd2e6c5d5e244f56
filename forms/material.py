"""Material data (pure Python): validated, SI units."""
from __future__ import annotations

import dataclasses

__all__ = ["Material", "MARAGING_200"]


@dataclasses.dataclass(frozen=True)
class Material:
    """Isotropic St. Venant-Kirchhoff material.

    Attributes:
        E: Young's modulus (Pa), > 0.
        nu: Poisson's ratio, in (-1, 0.5).
        rho: density (kg/m^3), > 0.
        sigma_y: yield stress (Pa), > 0 (used to judge stresses, not in the constitutive law).

    Defaults are the paper's 200-grade maraging steel (§2.2.1): 180 GPa, 0.3, 8000 kg/m^3, 1.38 GPa.
    """

    E: float = 180.0e9
    nu: float = 0.3
    rho: float = 8000.0
    sigma_y: float = 1.38e9

    def __post_init__(self):
        if not (self.E > 0.0):
            raise ValueError(f"E (Young's modulus) must be > 0 Pa, got {self.E}")
        if not (-1.0 < self.nu < 0.5):
            raise ValueError(f"nu (Poisson's ratio) must be in (-1, 0.5), got {self.nu}")
        if not (self.rho > 0.0):
            raise ValueError(f"rho (density) must be > 0 kg/m^3, got {self.rho}")
        if not (self.sigma_y > 0.0):
            raise ValueError(f"sigma_y (yield stress) must be > 0 Pa, got {self.sigma_y}")

    @property
    def lame(self) -> tuple[float, float]:
        """Lamé constants (lambda, mu) in Pa."""
        mu = self.E / (2.0 * (1.0 + self.nu))
        lmbda = self.E * self.nu / ((1.0 + self.nu) * (1.0 - 2.0 * self.nu))
        return lmbda, mu


MARAGING_200 = Material()
