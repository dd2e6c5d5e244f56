"""Forms layer of rotor37_rom: hyperelasticity in UFL (UFL only): St. Venant-Kirchhoff (``svk``, the paper's) and a
compressible neo-Hookean law (``neo_hookean``, the second law of #86). Installed as ``rotor37_rom.forms``."""
from . import neo_hookean, svk
from .material import MARAGING_200, Material
from .svk import *  # noqa: F401,F403
from .svk import __all__ as _svk_all

#: the hyperelastic laws a run may name, and the module of each (its internal_force, tangent_stiffness, ...)
HYPERELASTIC_LAWS = {"svk": svk, "neo-hookean": neo_hookean}


def hyperelastic_law(name: str):
    """The module of the hyperelastic law ``name`` (``HYPERELASTIC_LAWS``); one ValueError naming the laws known
    otherwise."""
    if not isinstance(name, str) or name not in HYPERELASTIC_LAWS:
        raise ValueError(f"hyperelastic law must be one of {', '.join(HYPERELASTIC_LAWS)}, got {name!r}")
    return HYPERELASTIC_LAWS[name]


__all__ = ["Material", "MARAGING_200", "HYPERELASTIC_LAWS", "hyperelastic_law", "neo_hookean", "svk", *_svk_all]
