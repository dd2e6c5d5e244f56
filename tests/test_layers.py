"""Layering: geometry (gmsh + NumPy), forms (UFL) and the pure NumPy/SciPy modules never import dolfinx."""
import subprocess
import sys

PURE = ["rotor37_rom", "rotor37_rom.geometry.tables", "rotor37_rom.geometry.parametric", "rotor37_rom.geometry.blade",
        "rotor37_rom.forms", "rotor37_rom.modes", "rotor37_rom.reduction", "rotor37_rom.nonlinear_forces",
        "rotor37_rom.step", "rotor37_rom.ecsw", "rotor37_rom.clearance", "rotor37_rom.charts", "rotor37_rom.casing",
        "rotor37_rom.integrator", "rotor37_rom.sweep", "rotor37_rom.stress", "rotor37_rom.report"]


def test_pure_modules_do_not_import_dolfinx():
    code = ("import sys\n" + "".join(f"import {m}\n" for m in PURE)
            + "bad = [m for m in ('dolfinx', 'petsc4py', 'slepc4py', 'pyvista') if m in sys.modules]\n"
            + "assert not bad, bad\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr[-1500:]
