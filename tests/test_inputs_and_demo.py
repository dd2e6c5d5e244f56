"""Bad input stops with one line naming the culprit; the demo runs at the ci preset and draws real pictures;
the implicit Newmark reference conserves energy (average acceleration, linear, undamped)."""
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from rotor37_rom import fem
from rotor37_rom.forms import Material
from rotor37_rom.geometry import blade as geo
from rotor37_rom.geometry.tables import read_blade_table

REPO = Path(__file__).resolve().parent.parent


def _one_line(exc_info, *words):
    msg = str(exc_info.value)
    assert "\n" not in msg
    for w in words:
        assert w in msg, msg


@pytest.mark.parametrize("kwargs, word", [({"E": 0.0}, "E"), ({"E": -1.0}, "E"), ({"rho": 0.0}, "rho"),
                                          ({"nu": 0.5}, "nu"), ({"nu": -1.0}, "nu"), ({"nu": 0.7}, "nu")])
def test_bad_material(kwargs, word):
    with pytest.raises(ValueError) as e:
        Material(**kwargs)
    _one_line(e, word)


def test_unknown_preset():
    with pytest.raises(ValueError) as e:
        fem.create_blade_sector(preset="huge")
    _one_line(e, "huge", "ci", "coarse", "paper")


def test_missing_and_garbled_tables(tmp_path):
    with pytest.raises(ValueError) as e:
        read_blade_table(tmp_path / "nope.dat")
    _one_line(e, "nope.dat", "does not exist")
    garbled = tmp_path / "garbled.dat"
    garbled.write_text(" SURFACE NUMBER 1\n    1   0.1  17.7  -0.11  -0.11\n    2   0.2  17.8  -0.1\n")
    with pytest.raises(ValueError) as e:
        read_blade_table(garbled)
    _one_line(e, "garbled.dat")
    garbled.write_bytes(b"\xff\xfe\x00binary")
    with pytest.raises(ValueError) as e:
        fem.create_blade_sector(table=garbled, preset="ci")
    _one_line(e, "garbled.dat")


def test_cad_without_clamp(tmp_path):
    """A BREP box whose clamp box selects nothing, and a .msh without a 'clamp' group."""
    brep, msh = tmp_path / "box.brep", tmp_path / "box.msh"
    with geo.gmsh_session() as gmsh:
        gmsh.model.add("box")
        gmsh.model.occ.addBox(0, 0, 0, 0.05, 0.01, 0.01)
        gmsh.model.occ.synchronize()
        gmsh.write(str(brep))
        gmsh.model.addPhysicalGroup(3, [1], 1)
        gmsh.model.setPhysicalName(3, 1, "blade")
        gmsh.model.addPhysicalGroup(2, [1], 2)
        gmsh.model.setPhysicalName(2, 2, "root")
        gmsh.model.mesh.generate(3)
        gmsh.write(str(msh))
    with pytest.raises(ValueError) as e:
        fem.create_sector_from_file(brep, clamp=(1, 1, 1, 2, 2, 2), preset="ci")
    _one_line(e, "clamp", "box.brep")
    with pytest.raises(ValueError) as e:
        fem.create_sector_from_file(msh, clamp="clamp")
    _one_line(e, "clamp", "box.msh", "root")
    # and a user's file that is right works: clamp the x = 0 face of the BREP box
    sector = fem.create_sector_from_file(brep, clamp=(-1e-6, -1e-6, -1e-6, 1e-6, 0.02, 0.02), preset="ci")
    omega = fem.compute_clamped_modes(sector, 1).omega[0]
    # Euler-Bernoulli cantilever 1st bending about the weak axis: 1.875^2 sqrt(EI/(rho A L^4)), h/L = 0.2 so
    # shear lowers the solid's value by a few %
    E, rho, L, h = 180e9, 8000.0, 0.05, 0.01
    beam = 1.8751**2 * np.sqrt(E * h**2 / 12.0 / rho / L**4)
    assert 0.85 * beam < omega < 1.01 * beam


def test_demo_runs_and_draws(tmp_path):
    env = dict(os.environ, MPLBACKEND="Agg")
    proc = subprocess.run([sys.executable, str(REPO / "demos" / "blade_modes.py"), "--preset", "ci", "--table", "none",
                           "--modes", "3", "--out", str(tmp_path)], capture_output=True, text=True, env=env)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "1B" in proc.stdout and "1T" in proc.stdout
    assert (tmp_path / "parametric_modes.xdmf").is_file()
    import matplotlib.image as mpimg

    for k in (1, 2, 3):
        img = mpimg.imread(tmp_path / "parametric_png" / f"mode_{k}.png")[..., :3]
        # non-blank: a sizeable share of pixels differ from the white background, and colours vary
        non_white = np.mean(np.any(img < 0.95, axis=-1))
        assert 0.02 < non_white < 0.9
        assert img.reshape(-1, 3).std(axis=0).max() > 0.05
    bad = subprocess.run([sys.executable, str(REPO / "demos" / "blade_modes.py"), "--preset", "huge"],
                         capture_output=True, text=True, env=env)
    assert bad.returncode == 2 and bad.stderr.strip().count("\n") == 0 and "huge" in bad.stderr


def test_newmark_linear_conserves_energy(ci_blade, ci_ops):
    """Average-acceleration Newmark is energy-conserving for linear undamped free vibration: after the load is
    released the discrete energy stays constant to round-off (1e-9 relative over 40 steps)."""
    import ufl
    from dolfinx import fem as dfem

    v = ufl.TestFunction(ci_blade.V)
    ds = ufl.Measure("ds", domain=ci_blade.mesh, subdomain_data=ci_blade.facet_tags)
    f = fem.assemble_vector(dfem.form(ufl.inner(ufl.as_vector([0.0, 1e5, 0.0]), v) * ds(ci_blade.groups["tip"])))
    dt = 2 * np.pi / 5400.0 / 40
    res = fem.solve_newmark(ci_blade, f, lambda t: 1.0 if t < 10 * dt else 0.0, dt, 50, ci_blade.tip_dofs,
                            nonlinear=False, ops=ci_ops)
    e = res.energy[11:]
    assert np.ptp(e) <= 1e-9 * e.mean()
    assert np.abs(res.monitored).max() > 0
