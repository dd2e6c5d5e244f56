"""rotor37_rom: reduced-order models of the NASA rotor 37 blade and bladed disk with FEniCSx.

Layers (imports flow one way): ``rotor37_rom.geometry`` (gmsh + NumPy) -> ``rotor37_rom.forms`` (UFL) ->
``rotor37_rom.fem`` (the only dolfinx/PETSc/SLEPc adapter) -> pure NumPy/SciPy subpackages (``model``, ``forces``,
``reduction``, ``disk``, ``dynamics``) -> ``studies`` and ``post`` -> ``viz`` (pictures).
Importing this package pulls in nothing heavy.
"""
__version__ = "0.1.0"
PAPER = "Delhez, Nyssen, Golinval & Batailly, J. Sound Vib. 544 (2023) 117382"
