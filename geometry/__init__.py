"""Geometry layer of rotor37_rom: NASA tables, the parametric rotor 37 blade and gmsh models (gmsh + NumPy only).

Installed as ``rotor37_rom.geometry`` (see README, "Packaging").
"""
