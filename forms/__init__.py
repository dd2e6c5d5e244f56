"""Forms layer of rotor37_rom: St. Venant-Kirchhoff hyperelasticity in UFL (UFL only). Installed as
``rotor37_rom.forms``."""
from .material import MARAGING_200, Material
from .svk import *  # noqa: F401,F403
from .svk import __all__ as _svk_all

__all__ = ["Material", "MARAGING_200", *_svk_all]
