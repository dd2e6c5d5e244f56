"""Geometry layer of rotor37_rom: NASA tables, the parametric rotor 37 blade, gmsh models and meshes from other FE codes
(gmsh + NumPy; meshio reads foreign mesh files).

Installed as ``rotor37_rom.geometry`` (see README, "Packaging").
"""
