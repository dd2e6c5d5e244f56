"""Meshes from other FE codes (geometry.mesh_import, fem.create_sector_from_file): wedges, hexahedra and tetrahedra
of one cantilever agree with each other and with beam theory; units, an Abaqus .inp round trip, group names,
contact nodes ordered LE -> TE whatever the boundary DOFs' order, and one-line refusals."""
import itertools
import re

import numpy as np
import pytest
import scipy.linalg

from rotor37_rom import fem
from rotor37_rom.forms import Material
from rotor37_rom.geometry import blade as geo
from rotor37_rom.geometry import mesh_import as mi

pytestmark = pytest.mark.fe

STEEL = Material()                                  # the files made here state no material: the paper's steel, said
L, H = 0.05, 0.01                                   # the 50 x 10 x 10 mm steel cantilever of test_inputs_and_demo


def _one_line(exc_info, *words):
    msg = str(exc_info.value)
    assert "\n" not in msg, msg
    for w in words:
        assert w in msg, msg


def _bar(path, kind, n=(10, 2), unit=1.0, order=2, incomplete=True):
    """The cantilever as gmsh makes it from another code's point of view: the h x h section at x = 0 meshed with
    triangles or quadrangles and extruded along x in n[0] layers into tetrahedra, wedges or hexahedra (second order:
    the serendipity 15- and 20-node cells of Abaqus' C3D15 / C3D20). Groups ROOT (x = 0), END (x = L), bar."""
    with geo.gmsh_session() as gmsh:
        gmsh.model.add("bar")
        g = gmsh.model.geo
        p = [g.addPoint(0, y * unit, z * unit) for y, z in ((0, 0), (H, 0), (H, H), (0, H))]
        lines = [g.addLine(p[k], p[(k + 1) % 4]) for k in range(4)]
        s = g.addPlaneSurface([g.addCurveLoop(lines)])
        for c in lines:
            g.mesh.setTransfiniteCurve(c, n[1] + 1)
        g.mesh.setTransfiniteSurface(s)
        if kind == "hex":
            g.mesh.setRecombine(2, s)
        out = g.extrude([(2, s)], L * unit, 0, 0, numElements=[n[0]], recombine=(kind != "tet"))
        g.synchronize()
        for dim, tags, tag, name in ((2, [s], 1, "ROOT"), (2, [out[0][1]], 2, "END"), (3, [out[1][1]], 3, "bar")):
            gmsh.model.addPhysicalGroup(dim, tags, tag)
            gmsh.model.setPhysicalName(dim, tag, name)
        gmsh.option.setNumber("Mesh.SecondOrderIncomplete", int(incomplete))
        gmsh.model.mesh.generate(3)
        gmsh.model.mesh.setOrder(order)
        gmsh.write(str(path))
    return path


def _omega(path, n=2, **kwargs):
    sector = fem.create_sector_from_file(path, clamp="ROOT", preset="ci", verbose=False,
                                         **{"material": STEEL, **kwargs})
    return fem.compute_clamped_modes(sector, n).omega, sector


def test_the_smallest_node_rule_always_fills_wedges_and_hexahedra():
    """Every order of the global node numbers gives face diagonals that 3 (wedge) or 5-6 (hexahedron) tetrahedra
    fill exactly (volume checked inside _filling): all 6! and 8! orders."""
    for kind, n in (("wedge", 6), ("hexahedron", 8)):
        nodes = np.array(list(itertools.permutations(range(n))))
        patterns = np.column_stack([np.isin(np.argmin(nodes[:, list(q)], axis=1), (1, 3)).astype(int)
                                    for q in mi._REF[kind]["quads"]])          # mi._diagonal, all orders at once
        assert mi._diagonal(mi._REF[kind]["quads"][0], nodes[-1]) == patterns[-1, 0]
        counts = {len(mi._filling(kind, tuple(p))) for p in np.unique(patterns, axis=0).tolist()}
        assert counts == ({3} if kind == "wedge" else {5, 6}), (kind, counts)


def test_wedges_hexahedra_and_tetrahedra_give_the_cantilever(tmp_path):
    """One cantilever meshed three ways (10 x 2 x 2 layers; wedges -> 3 tetrahedra, hexahedra -> 5 or 6, quadratic
    cells with their own mid-nodes) and a 2x finer tetrahedral mesh. P2 eigenvalues converge as h^4, so the fine
    mesh carries ~1/16 of a coarse mesh's error: every coarse value must lie above the fine one (Rayleigh-Ritz, all
    conforming on the exact box) and within 1 % of it (the accuracy asked of a blade model's frequencies; each is
    an estimate of its own discretisation error times 15/16). The fine value against beam theory with the bound of
    test_inputs_and_demo.test_user_file_errors_and_a_cantilever: 0.99 omega_T <= omega <= 1.03 omega_T."""
    from test_inputs_and_demo import _timoshenko_first_bending

    fine, _ = _omega(_bar(tmp_path / "fine.msh", "tet", n=(20, 4)))
    values = {kind: _omega(_bar(tmp_path / f"{kind}.msh", kind))[0] for kind in ("tet", "wedge", "hex")}
    print({k: v[0] for k, v in values.items()}, fine[0])
    for kind, omega in values.items():
        assert fine[0] <= omega[0] <= 1.01 * fine[0], (kind, omega[0], fine[0])
    E, rho = 180e9, 8000.0
    beam = 1.8751**2 * np.sqrt(E * H**2 / 12.0 / rho / L**4)
    omega_t = _timoshenko_first_bending(E, 0.3, rho, L, H, 5.0 / 6.0, beam)
    assert 0.99 * omega_t <= fine[0] <= 1.03 * omega_t, (fine[0], omega_t)


def test_linear_and_quadratic_hexahedra_of_a_box_agree_to_round_off(tmp_path):
    """On a box every edge is straight, so the quadratic cells' mid-nodes (the file's and the new face/body
    diagonal ones placed by the serendipity map) sit at the chord midpoints: the 8- and the 20-node hexahedral
    meshes give the same P2 problem, the same frequencies to the eigen-solver's round-off (tolerance 1e-12)."""
    linear, _ = _omega(_bar(tmp_path / "h8.msh", "hex", order=1))
    quadratic, _ = _omega(_bar(tmp_path / "h20.msh", "hex", order=2))
    np.testing.assert_allclose(linear, quadratic, rtol=1e-9)


def test_curved_quadratic_hexahedra_keep_their_geometry(tmp_path):
    """A 60-degree ring sector (radii 40-50 mm, 10 mm high, 4 cells along the arcs) in 20-node hexahedra, split into
    10-node tetrahedra. The ring is an extrusion, so its exact P2 geometry is the annulus whose arcs are replaced by
    their quadratic interpolants through the file's nodes: the mesh volume must equal that area (integrated here)
    times the height to round-off (1e-9) - which holds only if every new face-diagonal mid-node lies on the curved
    face's serendipity map. The 8-node mesh gives the chords' polygon the same way."""
    from scipy.integrate import quad

    def arc_area(R, n, quadratic):                  # area swept from the axis by the interpolated arc, 60 degrees
        e = np.pi / 3 / n
        if not quadratic:
            return 0.5 * n * R * R * np.sin(e)
        total = 0.0
        for k in range(n):
            P = np.array([[R * np.cos((k + s) * e), R * np.sin((k + s) * e)] for s in (0.0, 0.5, 1.0)])
            shape = lambda t: np.array([2 * (t - 0.5) * (t - 1), -4 * t * (t - 1), 2 * t * (t - 0.5)])   # noqa
            slope = lambda t: np.array([4 * t - 3, 4 - 8 * t, 4 * t - 1])                               # noqa
            total += quad(lambda t: 0.5 * np.cross(shape(t) @ P, slope(t) @ P), 0, 1, epsabs=1e-16)[0]
        return total

    def ring(path, order):
        with geo.gmsh_session() as gmsh:
            gmsh.model.add("ring")
            g = gmsh.model.geo
            c = g.addPoint(0, 0, 0)
            a = np.pi / 3
            pts = [g.addPoint(r * np.cos(t), r * np.sin(t), 0) for r, t in ((0.04, 0), (0.05, 0), (0.05, a),
                                                                           (0.04, a))]
            lines = [g.addLine(pts[0], pts[1]), g.addCircleArc(pts[1], c, pts[2]), g.addLine(pts[2], pts[3]),
                     g.addCircleArc(pts[3], c, pts[0])]
            s = g.addPlaneSurface([g.addCurveLoop(lines)])
            for k, cl in enumerate(lines):
                g.mesh.setTransfiniteCurve(cl, 3 if k % 2 == 0 else 5)
            g.mesh.setTransfiniteSurface(s)
            g.mesh.setRecombine(2, s)
            out = g.extrude([(2, s)], 0, 0, 0.01, numElements=[2], recombine=True)
            g.synchronize()
            gmsh.model.addPhysicalGroup(2, [s], 1)
            gmsh.model.setPhysicalName(2, 1, "ROOT")
            gmsh.model.addPhysicalGroup(3, [out[1][1]], 2)
            gmsh.model.setPhysicalName(3, 2, "ring")
            gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 1)
            gmsh.model.mesh.generate(3)
            gmsh.model.mesh.setOrder(order)
            gmsh.write(str(path))
        return fem.create_sector_from_file(path, clamp="ROOT", verbose=False, material=STEEL)

    for order in (2, 1):
        volume = ring(tmp_path / f"ring{order}.msh", order).volume
        expected = 0.01 * (arc_area(0.05, 4, order == 2) - arc_area(0.04, 4, order == 2))
        exact = np.pi / 6 * (0.05**2 - 0.04**2) * 0.01
        print(order, volume / exact - 1, expected / exact - 1)
        np.testing.assert_allclose(volume, expected, rtol=1e-9)


def test_millimetres_with_scale_equal_metres(tmp_path):
    """The same mesh written in mm and loaded with units='mm' (or scale=1e-3) is the metre mesh: coordinates
    equal to round-off, so the frequencies agree to the eigen-solver's tolerance; without the scale the mass is
    1e9 times too large: refused with the number and the likely unit, unless the mass is confirmed."""
    metres, _ = _omega(_bar(tmp_path / "m.msh", "wedge"))
    mm_path = _bar(tmp_path / "mm.msh", "wedge", unit=1000.0)
    mm, sector = _omega(mm_path, units="mm")
    np.testing.assert_allclose(mm, metres, rtol=1e-9)
    # what the clamp caught is said (#71): the root face, 10 x 10 mm (flat: its facets' area is exact)
    caught = re.search(r"clamp 'ROOT': \d+ facets, \d+ nodes, ([0-9.]+) mm\^2 in \[0, 0\] x \[0, 10\] x \[0, 10\] mm",
                       sector.summary)
    assert caught and abs(float(caught.group(1)) - 100.0) < 1e-9 * 100, sector.summary
    np.testing.assert_allclose(sector.volume, L * H * H, rtol=1e-12)
    scaled, _ = _omega(mm_path, scale=1e-3)
    np.testing.assert_allclose(scaled, metres, rtol=1e-9)
    with pytest.raises(ValueError, match=r"mass is 4e\+0?7 kg, outside 1 g - 100 kg; the file is likely in mm "
                                         r"\(0\.04 kg with units 'mm'\)"):
        fem.create_sector_from_file(mm_path, clamp="ROOT", verbose=False, material=STEEL)
    confirmed = fem.create_sector_from_file(mm_path, clamp="ROOT", verbose=False, mass_check=False,
                                            material=STEEL)
    np.testing.assert_allclose(confirmed.volume, L * H * H * 1e9, rtol=1e-12)      # the mass confirmed: read as is
    with pytest.raises(ValueError) as e:
        fem.create_sector_from_file(mm_path, clamp="ROOT", scale=2.0, units="mm", material=STEEL)
    _one_line(e, "scale", "units", "disagree")


def _write_inp(path, mesh, extra_sets=None):
    """An Abaqus/CalculiX input deck as a user receives it: 1-based node labels, C3D15 wedges (same node order as
    meshio's wedge15), node sets."""
    with open(path, "w") as f:
        f.write("*HEADING\ncantilever\n*NODE\n")
        for k, x in enumerate(mesh.points, start=1):
            f.write(f"{k}, {x[0]!r}, {x[1]!r}, {x[2]!r}\n")
        wedges = mesh.get_cells_type("wedge15")
        f.write("*ELEMENT, TYPE=C3D15, ELSET=BAR\n")
        for k, c in enumerate(wedges, start=1):
            f.write(f"{k}, " + ", ".join(str(i + 1) for i in c[:10]) + ",\n" + ", ".join(str(i + 1) for i in c[10:])
                    + "\n")
        for name in ("ROOT", "END"):
            nodes = np.unique(np.concatenate([mesh.cells[b].data[idx].ravel()
                                              for b, idx in enumerate(mesh.cell_sets[name]) if len(idx)]))
            f.write(f"*NSET, NSET={name}\n")
            for chunk in range(0, nodes.size, 16):
                f.write(", ".join(str(i + 1) for i in nodes[chunk:chunk + 16]) + "\n")
        for name, nodes in (extra_sets or {}).items():
            f.write(f"*NSET, NSET={name}\n" + ", ".join(str(i + 1) for i in nodes) + "\n")


def test_abaqus_inp_round_trip(tmp_path):
    """A .inp deck written from the .msh (same nodes, same C3D15 cells, the groups as node sets) gives the same
    frequencies to round-off; the clamp named in lower case finds the NSET ROOT (a unique case-insensitive match)."""
    import meshio

    msh = _bar(tmp_path / "bar.msh", "wedge")
    from_msh, _ = _omega(msh)
    inp = tmp_path / "bar.inp"
    _write_inp(inp, meshio.read(msh))
    sector = fem.create_sector_from_file(inp, clamp="root", tip="END", contact=3, verbose=False, material=STEEL)
    from_inp = fem.compute_clamped_modes(sector, 2).omega
    np.testing.assert_allclose(from_inp, from_msh, rtol=1e-9)
    assert "80 wedge15 -> 240 tetrahedra" in sector.summary, sector.summary
    assert sector.tip_names == ("LE", "tip1", "TE") and np.allclose(sector.tip_nodes[:, 0], L)


def test_contact_nodes_along_the_camber_line_and_ordered_le_to_te():
    """An airfoil-like tip (chord along +z from LE at z = 0 to TE at z = 0.05, thickness along y, camber
    y = 0.1 z (1 - z / c)) sampled on its two sides: 5 nodes 'along the camber line' are the chord's two ends and the
    nodes nearest to mid-thickness at 3 stations; coordinates given in any order come back LE -> TE."""
    c = 0.05
    z = np.linspace(0, c, 21)
    camber = 0.1 * z * (1 - z / c)
    half = 0.004 * np.sin(np.pi * z / c)
    sides = np.vstack([np.column_stack([np.full(21, 0.2), camber + half, z]),
                       np.column_stack([np.full(21, 0.2), camber - half, z])[1:-1],
                       np.column_stack([np.full(19, 0.2), camber[1:-1], z[1:-1]])])     # nodes on the camber line
    tip = np.arange(len(sides))
    nodes, how = mi.select_contact_nodes(sides, tip, 5)
    assert "camber" in how
    np.testing.assert_allclose(sides[nodes[[0, -1]], 2], [0.0, c])
    on_camber = np.abs(sides[nodes, 1] - 0.1 * sides[nodes, 2] * (1 - sides[nodes, 2] / c))
    assert on_camber.max() < 1e-12                                 # the camber-line nodes are chosen
    np.testing.assert_allclose(sides[nodes, 2], np.linspace(0, c, 5), atol=c / 20 / 2 + 1e-12)
    shuffled = sides[nodes][[3, 0, 4, 2, 1]] + 1e-7
    again, _ = mi.select_contact_nodes(sides, tip, shuffled)
    np.testing.assert_array_equal(again, nodes)
    with pytest.raises(ValueError) as e:
        mi.select_contact_nodes(sides, tip, sides[nodes] * 1000.0)
    _one_line(e, "contact point", "units")
    with pytest.raises(ValueError) as e:
        mi.select_contact_nodes(sides, tip, 1)
    _one_line(e, "contact must be in [2,")


def test_boundary_map_follows_the_boundary_dofs_in_any_order(tmp_path):
    """The reduced model's node map and contact rows follow the boundary DOFs whatever their order and number
    (issue 24: 24 boundary DOFs used to meet 134 tip nodes): with the TE's DOFs first and only 3 of 4 contact nodes,
    q[q_index of LE] is node LE's displacement (Phi's rows at LE's DOFs are the identity there) and the contact
    matrices pick those entries."""
    from rotor37_rom.dynamics import casing
    from rotor37_rom.reduction.builder import ReductionConfig, build_reduced_model

    sector = fem.create_sector_from_file(_bar(tmp_path / "bar.msh", "hex"), clamp="ROOT", tip="END", contact=4,
                                         verbose=False, material=STEEL)
    dofs = sector.tip_dofs
    boundary = np.concatenate([dofs[3], dofs[0], dofs[1]])           # TE, LE, tip1 (tip2 left out)
    model, _ = build_reduced_model(sector, ReductionConfig(r_c=4, r_md=2, forces="none", keep_basis=True),
                                   boundary_dofs=boundary)
    assert sorted(model.nodes.names) == ["LE", "TE", "tip1"]
    for name, row in (("LE", 0), ("TE", 3), ("tip1", 1)):
        k = model.nodes.row(name)
        np.testing.assert_allclose(model.nodes.coordinates[k], sector.tip_nodes[row], atol=1e-12)
        np.testing.assert_allclose(model.Phi[np.ix_(dofs[row], model.nodes.q_index[k])], np.eye(3), atol=1e-12)
    N, _, _, rows = casing.contact_matrices(model.nodes, model.r, None)
    # the 'x' normal is the bar's frame (its centre of mass at atan(5 / 25) = 11.3 deg): x and y at each node
    frame = np.arctan2(0.5 * H, 0.5 * L)
    assert model.nodes.frame_angle == pytest.approx(frame, abs=1e-12)
    assert N.shape == (3, model.r) and np.count_nonzero(N) == 6
    np.testing.assert_allclose(N[np.arange(3)[:, None], model.nodes.q_index[rows]],
                               np.tile([np.cos(frame), np.sin(frame), 0.0], (3, 1)), atol=1e-15)


def test_refusals_are_one_line(tmp_path):
    """Unsupported cells, unknown groups, a group that covers no boundary facet, bad units, an unknown file type,
    an unreadable deck, contact nodes along a tip that was not given: one line each, naming the culprit and what is
    allowed."""
    import meshio

    bad = _bar(tmp_path / "wedge18.msh", "wedge", incomplete=False)   # gmsh's complete Prism18: not accepted
    with pytest.raises(ValueError) as e:
        fem.create_sector_from_file(bad, clamp="ROOT", material=STEEL)
    _one_line(e, "wedge18", "accepted", "hexahedron20", "wedge15")
    msh = _bar(tmp_path / "bar.msh", "wedge")
    with pytest.raises(ValueError) as e:
        fem.create_sector_from_file(msh, clamp="clamp", material=STEEL)
    _one_line(e, "clamp", "no group named 'clamp'", "ROOT", "END")
    inp = tmp_path / "bar.inp"
    _write_inp(inp, meshio.read(msh), {"ONE": [0, 1]})                # two nodes: no facet has 3 corners in it
    with pytest.raises(ValueError) as e:
        fem.create_sector_from_file(inp, clamp="ONE", material=STEEL)
    _one_line(e, "clamp", "ONE", "covers no boundary facet")
    with pytest.raises(ValueError) as e:
        fem.create_sector_from_file(msh, clamp="ROOT", units="furlong", material=STEEL)
    _one_line(e, "units", "mm")
    with pytest.raises(ValueError) as e:
        fem.create_sector_from_file(tmp_path / "bar.stl", clamp="ROOT", material=STEEL)
    _one_line(e, "bar.stl")
    (tmp_path / "garbage.inp").write_text("*NODE\n1, 0, 0\n*ELEMENT, TYPE=C3D99\n1, 1, 2\n")
    with pytest.raises(ValueError) as e:
        fem.create_sector_from_file(tmp_path / "garbage.inp", clamp="ROOT", material=STEEL)
    _one_line(e, "garbage.inp", "C3D99")                                # meshio's reason, not its exit code
    with pytest.raises(ValueError) as e:
        fem.create_sector_from_file(msh, clamp="ROOT", contact=3, material=STEEL)
    _one_line(e, "contact", "tip")


def test_the_project_blade_round_trips_through_an_abaqus_deck(ci_blade, tmp_path):
    """fem.write_sector_mesh -> create_sector_from_file: the ci blade as a millimetre deck comes back with the same
    frequencies (same nodes and cells: round-off, 1e-9) and, with 8 nodes chosen along the tip camber line, exactly
    the project's 8 contact nodes in the same LE -> TE order (they are mesh vertices on the camber line)."""
    omega = fem.compute_clamped_modes(ci_blade, 4).omega
    deck = fem.write_sector_mesh(ci_blade, tmp_path / "blade_mm.inp", units="mm")
    for contact in (8, "CONTACT"):
        back = fem.create_sector_from_file(deck, clamp="CLAMP", tip="TIP", units="mm", contact=contact,
                                           verbose=False, material=STEEL)
        np.testing.assert_allclose(fem.compute_clamped_modes(back, 4).omega, omega, rtol=1e-9)
        np.testing.assert_allclose(back.tip_nodes, ci_blade.tip_nodes, atol=1e-12)
        assert back.tip_names == ci_blade.tip_names
    with pytest.raises(ValueError) as e:
        fem.write_sector_mesh(ci_blade, tmp_path / "blade.msh")
    _one_line(e, "blade.msh", ".inp")


@pytest.mark.slow
def test_own_blade_demo(tmp_path):
    """demos/own_blade.py without --mesh (rotor37_rom.studies.own_blade): the ci blade as a mm deck through modes,
    the r = 38 model, the sprag-slip onsets and a 1-revolution rub; its summary holds the round-tripped blade (the ci
    mesh's mass to 1e-9, 8 contact nodes) and the onsets of the LE half and per node; a bad --units is one line, exit
    2 (the script). The script on the deck it wrote, with a material, a normal and a sense given."""
    import json
    import os
    import subprocess
    import sys
    from pathlib import Path

    from rotor37_rom.studies.own_blade import OwnBladeConfig, run_own_blade
    from rotor37_rom.studies.sector_file import SectorFile

    root = Path(__file__).resolve().parents[2]
    env = dict(os.environ, MPLBACKEND="Agg")
    run = subprocess.run([sys.executable, "demos/own_blade.py", "--units", "furlong", "--out", str(tmp_path / "bad")],
                         cwd=root, env=env, capture_output=True, text=True, timeout=120)
    assert run.returncode == 2 and "--units describes your own sector's file: give it with --mesh" in run.stderr
    summary = run_own_blade(OwnBladeConfig(r_c=8, revolutions=1.0, out=str(tmp_path)))
    # the script on that deck with a material, a normal and a sense of the user's: the material given is used and
    # said, the frame is in the summary, the modes scale as sqrt(E / rho) (the same mesh: 1e-8)
    own = subprocess.run([sys.executable, "demos/own_blade.py", "--mesh", str(tmp_path / "example_blade_mm.inp"),
                          "--material", "210e9", "0.3", "9000", "--direction", "radial", "--rotation-sense", "-1",
                          "--r-c", "4", "--revolutions", "0.3", "--out", str(tmp_path / "own")],
                         cwd=root, env=env, capture_output=True, text=True, timeout=600)
    assert own.returncode == 0, own.stderr[-2000:]
    assert "material: E = 210 GPa, nu = 0.3, rho = 9000 kg/m^3 (given)" in own.stdout
    mine = json.loads((tmp_path / "own" / "summary.json").read_text())
    assert mine["frame"]["contact_normal"] == "radial" and mine["frame"]["rotation_sense"] == -1
    assert mine["input"]["material"] == [210e9, 0.3, 9000.0]
    np.testing.assert_allclose(mine["modes_hz"], np.asarray(summary["modes_hz"]) * np.sqrt(210 / 180 * 8000 / 9000),
                               rtol=1e-8)
    blade = fem.create_blade_sector(preset="ci")
    np.testing.assert_allclose(summary["mass_kg"], blade.total_mass(), rtol=1e-9)
    np.testing.assert_allclose(summary["contact_nodes_m"], blade.tip_nodes, atol=1e-12)
    assert summary["r"] == 24 + 8 + 6 and len(summary["mu_star_per_node"]) == 8
    assert summary["mu_star_le_half"] is not None and 0 < summary["mu_star_le_half"] < 1
    assert not summary["diverged"] and summary["le_max_radial_mm"] > 0
    assert summary["frame"] == {"axis": "+z", "file_axis": "+z", "rotation_sense": -1, "contact_normal": "x",
                                "tip_stagger_deg": pytest.approx(np.degrees(0.1943543), abs=1e-3),
                                "blade_frame": "the plane through the axis and the blade's centre of mass",
                                "blade_frame_theta_deg": pytest.approx(np.degrees(blade.blade_frame_angle()),
                                                                       abs=1e-9)}
    with pytest.raises(ValueError, match=r"^--rotation-sense \+1 turns this blade with its trailing edge ahead"):
        run_own_blade(OwnBladeConfig(rotation_sense=1, out=str(tmp_path / "other_sense")))
    with pytest.raises(ValueError, match=r"^--rotation-sense"):
        OwnBladeConfig(rotation_sense=0)
    # the millimetre deck read as metres: refused with its mass and the likely unit (#71), unless confirmed
    deck = str(tmp_path / "example_blade_mm.inp")
    # (a material given: the deck's own, in N-mm-t-s, is refused first as no structural material in SI)
    with pytest.raises(ValueError, match=r"^--mesh: .* the blade's mass is 6\.27e\+0?7 kg, outside 1 g - 100 kg; "
                                         r"the file is likely in mm"):
        run_own_blade(OwnBladeConfig(mesh=SectorFile(deck, units="m", material="paper"), out=str(tmp_path / "m")))
    with pytest.raises(ValueError, match=r"^--mesh: .* read in m units is E = 1\.8e\+05 Pa, .* are the units right"):
        run_own_blade(OwnBladeConfig(mesh=SectorFile(deck, units="m"), out=str(tmp_path / "metres")))


def _mirrored_deck(deck, path):
    """The deck's blade mirrored through the plane y = 0 (theta -> -theta: its hand reversed), its tetrahedra
    reordered to keep a positive volume, its node sets kept."""
    import meshio

    from rotor37_rom.fem.sector import deck_material_lines

    mesh = meshio.read(deck)
    points = mesh.points * np.array([1.0, -1.0, 1.0])
    (block,) = mesh.cells
    cells = block.data[:, [0, 2, 1, 3]] if block.type == "tetra" else block.data[:, [0, 2, 1, 3, 6, 5, 4, 7, 9, 8]]
    meshio.write(path, meshio.Mesh(points, [(block.type, cells)], point_sets=mesh.point_sets))
    with open(path, "a") as out:
        out.write(deck_material_lines(Material(), "mm", len(cells)))
    return path


@pytest.mark.slow
def test_a_mirrored_blade_turning_the_other_way_is_the_same_blade(ci_blade, tmp_path):
    """The frame and the hand are the user's (#71): the ci blade mirrored through y = 0 and turning the other way
    (sense +1) is the same physical blade: the same clamped frequencies, the same contact nodes mirrored, the same
    sprag-slip onset mu* at every contact node with either normal (x, radial) and the same 1-revolution map at two
    speeds from the map command (``--mesh``, ``--rotation-sense``), to the round-off of the two solves (1e-8); the
    mirrored blade with rotor 37's sense (-1) is refused (its trailing edge would lead), by the map command too. A
    sign error in the sliding direction or the normal gives other onsets."""
    from rotor37_rom.dynamics.casing import Casing, check_hand, contact_matrices
    from rotor37_rom.dynamics.friction import sprag_slip_friction
    from rotor37_rom.reduction.builder import ReductionConfig, build_reduced_model
    from rotor37_rom.studies.contact_map import ContactMapConfig, run_contact_map
    from rotor37_rom.studies.sector_file import SectorFile

    deck = fem.write_sector_mesh(ci_blade, tmp_path / "blade_mm.inp", units="mm")
    mirror = _mirrored_deck(deck, tmp_path / "mirror_mm.inp")
    blades = [fem.create_sector_from_file(f, clamp="CLAMP", tip="TIP", units="mm", contact=8, verbose=False)
              for f in (deck, mirror)]
    np.testing.assert_allclose(blades[1].tip_nodes, blades[0].tip_nodes * [1.0, -1.0, 1.0], atol=1e-12)
    assert check_hand(blades[0].tip_nodes, -1) > 0 and check_hand(blades[1].tip_nodes, +1) < 0
    with pytest.raises(ValueError, match=r"--rotation-sense -1 turns this blade with its trailing edge ahead"):
        check_hand(blades[1].tip_nodes, -1)
    config = ReductionConfig(r_c=8, r_md=0, forces="none", keep_basis=False)
    models = [build_reduced_model(b, config)[0] for b in blades]
    omega = [np.sqrt(scipy.linalg.eigh(m.K, m.M, eigvals_only=True)[:4]) for m in models]
    assert np.all(omega[0] > 2 * np.pi * 100)                     # the ci blade's 1B is ~840 Hz
    np.testing.assert_allclose(omega[1], omega[0], rtol=1e-8)
    for direction in ("x", "radial"):
        onsets = []
        for model, sense in zip(models, (-1, +1)):
            N, S, _, _ = contact_matrices(model.nodes, model.r, Casing(direction=direction, rotation_sense=sense))
            onsets.append([sprag_slip_friction(model.K, N, S, [k]) for k in range(N.shape[0])])
        finite = np.isfinite(onsets[0])
        assert finite.any() and np.array_equal(finite, np.isfinite(onsets[1])), onsets
        np.testing.assert_allclose(np.array(onsets[1])[finite], np.array(onsets[0])[finite], rtol=1e-8)
    # the map command on each deck (--mesh, --rotation-sense): the same map, the frame in its summary
    maps = []
    for f, sense in ((deck, -1), (mirror, +1)):
        config = ContactMapConfig.from_options(mesh=SectorFile(f), rotation_sense=sense, r_c=8, global_md=0,
                                               speeds=(1350.0, 1450.0, 2), revolutions=1.0, gnl="off", mu=0.15,
                                               quiet=True, out=tmp_path / f"map_{f.stem}")
        maps.append(run_contact_map(config))
    scale = np.abs(maps[0].runs["no GNL"].imap.nfrc).max()
    assert scale > 1e-5                                           # in contact: the casing pushes the tip 0.1 mm
    np.testing.assert_allclose(maps[1].runs["no GNL"].imap.nfrc, maps[0].runs["no GNL"].imap.nfrc, rtol=0,
                               atol=1e-8 * scale)
    assert maps[1].summary["frame"]["rotation_sense"] == 1 and maps[1].summary["input"]["path"] == str(mirror)
    with pytest.raises(ValueError, match=r"^--rotation-sense -1 turns this blade with its trailing edge ahead"):
        run_contact_map(config.with_options(rotation_sense=-1))


def _deck_with_include_and_boundary(deck, folder, material=None):
    """The deck as another code writes it: its nodes and elements in an *INCLUDEd file, its clamp given by a
    *BOUNDARY list of node labels (no named set), the TIP set after the include, a material in N-mm-t-s."""
    lines = deck.read_text().splitlines()
    starts = [k for k, line in enumerate(lines) if line.startswith("*NSET")]
    mesh_part, sets = lines[:starts[0]], lines[starts[0]:]
    (folder / "mesh.inp").write_text("\n".join(line for line in mesh_part if not line.startswith("*HEADING")) + "\n")
    blocks, current = {}, None
    for line in sets:                                # the node sets (the deck's material after them left out)
        if line.startswith("*"):
            current = line.split("=")[-1].strip() if line.upper().startswith("*NSET") else None
            blocks.setdefault(current, [])
        elif current is not None:
            blocks[current] += [int(v) for v in line.replace(",", " ").split()]
    main = ["*HEADING", "a blade from another code", "*INCLUDE, INPUT=mesh.inp", "*NSET, NSET=TIP"]
    main += [", ".join(str(v) for v in blocks["TIP"][k:k + 16]) for k in range(0, len(blocks["TIP"]), 16)]
    main += ["*BOUNDARY"] + [f"{label}, 1, 3" for label in blocks["CLAMP"]]
    if material is not None:
        main += ["*MATERIAL, NAME=BLADE_STEEL", "*ELASTIC", f"{material[0]!r}, {material[1]!r}", "*DENSITY",
                 f"{material[2]!r}"]
    path = folder / "blade.inp"
    path.write_text("\n".join(main) + "\n")
    return path


def test_a_deck_with_an_include_a_boundary_clamp_and_its_material(ci_blade, tmp_path, capsys):
    """A deck as another code writes it (#71): the mesh in an *INCLUDEd file, the clamp a *BOUNDARY node list
    (group 'BOUNDARY'), the material in N-mm-t-s (210 GPa, 9,000 kg/m^3): the same nodes and cells as the project's
    deck with named sets, so the same frequencies with the same material to 1e-9 (round-off), and with the deck's
    own material the project's scaled exactly by sqrt(E rho_0 / (E_0 rho)) (linear modes; same nu), the material
    printed. Refused in one line naming the file and line: a missing include, a material in units with no
    consistent system, a material whose SI values are no structural material's (a unit slip)."""
    from rotor37_rom.forms import Material

    deck = fem.write_sector_mesh(ci_blade, tmp_path / "named_mm.inp", units="mm")
    named = fem.create_sector_from_file(deck, clamp="CLAMP", tip="TIP", units="mm", contact=8, verbose=False,
                                        material=Material(E=210e9, rho=9000.0))
    other = tmp_path / "other"
    other.mkdir()
    raw = _deck_with_include_and_boundary(deck, other, material=(210000.0, 0.3, 9e-9))
    capsys.readouterr()
    theirs = fem.create_sector_from_file(raw, clamp="boundary", tip="tip", units="mm", contact=8)
    printed = capsys.readouterr().out
    assert "material: E = 210 GPa, nu = 0.3, rho = 9000 kg/m^3 (the deck's)" in printed, printed
    assert theirs.material == Material(E=210e9, nu=0.3, rho=9000.0)
    w_named, w_theirs = (fem.compute_clamped_modes(s, 4).omega for s in (named, theirs))
    np.testing.assert_allclose(w_theirs, w_named, rtol=1e-9)
    w_project = fem.compute_clamped_modes(ci_blade, 4).omega
    np.testing.assert_allclose(w_theirs, w_project * np.sqrt((210.0 / 180.0) * (8000.0 / 9000.0)), rtol=1e-9)
    np.testing.assert_allclose(theirs.tip_nodes, ci_blade.tip_nodes, atol=1e-12)
    given = fem.create_sector_from_file(raw, clamp="BOUNDARY", tip="TIP", units="mm", contact=8,
                                        material=Material())                  # the argument wins, and says so
    assert given.material == Material() and "the deck states E = 210 GPa" in capsys.readouterr().out
    (other / "mesh.inp").rename(other / "moved.inp")
    with pytest.raises(ValueError) as e:
        fem.create_sector_from_file(raw, clamp="BOUNDARY", units="mm")
    _one_line(e, "blade.inp, line 3", "*INCLUDE, INPUT=mesh.inp", "does not exist")
    (other / "moved.inp").rename(other / "mesh.inp")
    with pytest.raises(ValueError) as e:
        fem.create_sector_from_file(raw, clamp="BOUNDARY", units="cm")
    _one_line(e, "no consistent unit system", "give material=")
    pascal = _deck_with_include_and_boundary(deck, other, material=(210e9, 0.3, 9000.0))   # SI values in a mm deck
    with pytest.raises(ValueError) as e:
        fem.create_sector_from_file(pascal, clamp="BOUNDARY", units="mm")
    _one_line(e, "E = 2.1e+17 Pa", "are the units right")


@pytest.mark.slow
def test_a_users_bladed_disk_from_a_deck(ci_disk, tmp_path):
    """One entry for a user's bladed-disk sector (#71): the built-in ci sector written as a millimetre Abaqus deck
    (node sets CLAMP, TIP, LEFT, RIGHT; element sets BLADE, DISK) goes through ``demos/bladed_disk.py --mesh ...``
    (group names in any case) as rotor 37's does: its cyclic frequencies at k = 0, 1 and N/2 are the built-in
    sector's to 1e-8 (the same nodes and cells: the eigen-solver's round-off, measured 2e-11), its modes labelled the
    same (the blade's share from the element set), the blade clamped on its disk the same, a 1B picture drawn;
    ``--show-groups`` draws the four groups on the mesh and stops.
    Refused in one line: N outside 2..360, a face group the deck does not have, faces given the other way round
    (named as swapped), the wrong N (the right one suggested), an unknown blade element set."""
    import json
    import os
    import subprocess
    import sys
    from pathlib import Path

    from rotor37_rom.fem.safe import compute_safe_diagram

    deck = fem.write_sector_mesh(ci_disk, tmp_path / "disk_mm.inp", units="mm")
    run = subprocess.run([sys.executable, "demos/bladed_disk.py", "--mesh", str(deck), "--clamp", "clamp", "--tip",
                          "TIP", "--left", "left", "--right", "RIGHT", "--n-sectors", "36", "--blade", "Blade",
                          "--units", "mm", "--modes", "4", "--nodal-diameters", "0", "1", "18", "--pictures", "1",
                          "--out", str(tmp_path / "out")],
                         cwd=Path(__file__).resolve().parents[2], env=dict(os.environ, MPLBACKEND="Agg"),
                         capture_output=True, text=True, timeout=900)
    assert run.returncode == 0, run.stderr[-3000:]
    assert re.search(r"left 'left': \d+ facets, \d+ nodes", run.stdout) and "blade 'Blade': " in run.stdout
    summary = json.loads((tmp_path / "out" / "own" / "summary.json").read_text())
    safe = summary["safe"]
    assert summary["n_sectors"] == 36 and safe["k"] == [0, 1, 18]
    ref = compute_safe_diagram(ci_disk, 4, ks=[0, 1, 18])
    np.testing.assert_allclose(safe["omega"], ref.omega, rtol=1e-8)
    assert safe["family"] == ref.family.tolist()
    np.testing.assert_allclose(summary["clamped_on_disk"],
                               fem.compute_clamped_modes(fem.clamp_cell_group(ci_disk, "disk"), 3).omega, rtol=1e-8)
    assert (tmp_path / "out" / "own" / "mode_1B_k1.png").is_file()
    # --show-groups: the groups drawn on the mesh, and nothing else run
    shown = subprocess.run([sys.executable, "demos/bladed_disk.py", "--mesh", str(deck), "--left", "LEFT", "--right",
                            "RIGHT", "--n-sectors", "36", "--show-groups", "--out", str(tmp_path / "shown")],
                           cwd=Path(__file__).resolve().parents[2], env=dict(os.environ, MPLBACKEND="Agg"),
                           capture_output=True, text=True, timeout=300)
    assert shown.returncode == 0, shown.stderr[-3000:]
    drawn = json.loads((tmp_path / "shown" / "own" / "groups.png.json").read_text())
    assert drawn["scalar_range"] == [0.0, 4.0] and drawn["n_cells"] > 0          # clamp, left, right, tip
    assert sorted(p.name for p in (tmp_path / "shown" / "own").iterdir()) == ["groups.png", "groups.png.json"]
    for cyclic, words in (((("LEFT", "RIGHT", 1)), ("cyclic", "2..360")), (("LEFT", "SIDE", 36), ("right", "SIDE")),
                          (("RIGHT", "LEFT", 36), ("faces are swapped", "exchange left and right")),
                          (("LEFT", "RIGHT", 18), ("do not match", "360/36 degrees: N = 36?"))):
        with pytest.raises(ValueError) as e:
            fem.create_sector_from_file(deck, clamp="CLAMP", units="mm", verbose=False, cyclic=cyclic)
        _one_line(e, *words)
    with pytest.raises(ValueError) as e:
        fem.create_sector_from_file(deck, clamp="CLAMP", units="mm", verbose=False, cyclic=("LEFT", "RIGHT", 36),
                                    blade="ROTOR", material=STEEL)
    _one_line(e, "blade", "no element set", "'ROTOR'", "BLADE", "DISK")


def test_bad_inputs_to_a_users_mesh_are_one_line_each(tmp_path, capsys):
    """Bad inputs to the user-mesh path (#71), from the options' checks (no meshing) to what only reading the file
    shows: each is refused with one line naming the culprit (the option, the group, the face, the units)."""
    from rotor37_rom.studies.contact_map import ContactMapConfig, MapModel
    from rotor37_rom.studies.disk_modes import BladedDiskConfig
    from rotor37_rom.studies.own_blade import OwnBladeConfig
    from rotor37_rom.studies.sector_file import SectorFile

    bar = _bar(tmp_path / "bar.msh", "tet", n=(4, 1))                  # 50 x 10 x 10 mm, groups ROOT, END, bar
    (tmp_path / "notes.stl").write_text("solid\n")
    (tmp_path / "empty.inp").write_text("*HEADING\nnothing\n")
    ring = dict(left="ROOT", right="END", n_sectors=12)

    def read(**kwargs):
        return fem.create_sector_from_file(bar, **{"clamp": "ROOT", "verbose": False, "material": STEEL, **kwargs})

    cases = [
        ("a missing file", lambda: SectorFile(tmp_path / "missing.inp"), ("--mesh", "does not exist")),
        ("a folder", lambda: SectorFile(tmp_path), ("--mesh", "is a folder")),
        ("a file of another kind", lambda: SectorFile(tmp_path / "notes.stl"), ("--mesh must be one of", "notes.stl")),
        ("an empty clamp name", lambda: SectorFile(bar, clamp=" "), ("--clamp",)),
        ("a left face alone", lambda: SectorFile(bar, left="ROOT"), ("--left, --right and --n-sectors go together",)),
        ("one sector", lambda: SectorFile(bar, **{**ring, "n_sectors": 1}), ("--n-sectors", "2..360")),
        ("a blade set without faces", lambda: SectorFile(bar, blade="bar"), ("--blade", "--n-sectors")),
        ("unknown units", lambda: SectorFile(bar, units="furlong"), ("--units", "furlong")),
        ("one contact node", lambda: SectorFile(bar, contact=1), ("--contact", "2..40")),
        ("a negative modulus", lambda: SectorFile(bar, material=(-1.0, 0.3, 8000.0)), ("--material",)),
        ("nu = 0.5", lambda: SectorFile(bar, material=(2e11, 0.5, 8000.0)), ("--material",)),
        ("a blade to the disk scene", lambda: BladedDiskConfig(mesh=SectorFile(bar)), ("--mesh", "--n-sectors")),
        ("a disk to the blade scene", lambda: OwnBladeConfig(mesh=SectorFile(bar, **ring)), ("bladed_disk.py",)),
        ("a picture past N/2", lambda: BladedDiskConfig(mesh=SectorFile(bar, **ring), pictures=(7,)),
         ("--pictures", "[0, 6]")),
        ("--disk with a blade", lambda: MapModel(mesh=SectorFile(bar), disk=True), ("--disk", "--n-sectors")),
        ("--mesh with --model", lambda: MapModel(mesh=SectorFile(bar), path=tmp_path / "rom.npz"), ("--model",)),
        ("--tolerance with --mesh", lambda: ContactMapConfig.from_options(mesh=SectorFile(bar), tolerance=0.1),
         ("--tolerance", "--mesh")),
        ("a clamp group the file lacks", lambda: read(clamp="HUB"), ("clamp", "'HUB'", "ROOT", "END")),
        ("a clamp box with no node", lambda: read(clamp=(1, 1, 1, 2, 2, 2)), ("clamp", "no node")),
        ("a reversed box", lambda: read(clamp=(1, 1, 1, 0, 0, 0)), ("clamp", "box")),
        ("a contact group the file lacks", lambda: read(tip="END", contact="LE_NODES"), ("contact", "'LE_NODES'")),
        ("metres read as millimetres", lambda: fem.create_sector_from_file(bar, clamp="ROOT", units="mm",
                                                                          verbose=False, material=STEEL),
         ("mass", "outside 1 g - 100 kg", "likely in m")),
        ("a negative scale", lambda: read(scale=-1.0), ("scale", "> 0")),
        ("a clamped face as a cyclic face", lambda: read(cyclic=("END", "ROOT", 12)),
         ("right: 'ROOT' shares", "with the clamp 'ROOT'")),
        ("faces that are no cyclic pair", lambda: read(clamp=(0, 0, 0, 0.05, 0.01, 1e-4), cyclic=("END", "ROOT", 12)),
         ("cyclic faces do not match under a rotation by 360/12 degrees",)),
        ("a deck without nodes", lambda: fem.create_sector_from_file(tmp_path / "empty.inp", clamp="ROOT",
                                                                     verbose=False, material=STEEL),
         ("empty.inp", "no nodes")),
    ]
    outcomes = []
    for what, call, words in cases:
        with pytest.raises((ValueError, TypeError)) as e:
            call()
        _one_line(e, *words)
        outcomes.append(f"{what}: {e.value}")
    assert len(cases) >= 20
    with capsys.disabled():
        print("\n" + "\n".join(outcomes))


def test_a_nastran_files_mat1_is_its_material(tmp_path, capsys):
    """A NASTRAN bulk-data file's material (#71): the cantilever written as a .bdf (meshio: GRID/CTETRA, no named
    sets: a box clamp) with a MAT1 card in free, small and large field (NASTRAN reals such as 2.1+5 included), in
    N-mm-t-s: the material is read, printed and used - the frequencies are the default material's scaled by sqrt(E
    rho_0 / (E_0 rho)) to 1e-9 (linear modes of the same mesh, same nu). A MAT1 without RHO is refused naming the
    file and line."""
    import meshio

    from rotor37_rom.forms import Material

    msh = _bar(tmp_path / "bar.msh", "tet", n=(4, 1), unit=1000.0)             # in mm
    mesh = meshio.read(msh)
    tets = [(b.type, b.data) for b in mesh.cells if b.type.startswith("tetra")]
    bdf = tmp_path / "bar.bdf"
    meshio.write(bdf, meshio.Mesh(mesh.points, tets), file_format="nastran")
    root = (-1.0, -1.0, -1.0, 1e-3, 11.0, 11.0)                                   # x = 0, in mm
    reference = fem.create_sector_from_file(bdf, clamp=root, units="mm", verbose=False, mass_check=False,
                                            material=STEEL)
    w0 = fem.compute_clamped_modes(reference, 2).omega
    text = bdf.read_text().replace("ENDDATA", "{card}\nENDDATA")
    cards = {"free": "MAT1,1,210000.,,0.3,9.-9",
             "small": "MAT1    1       2.1+5           .3      9.-9",
             "large": "MAT1*   1               2.1+5                                   .3              *\n"
                      "*       9.-9"}
    for form, card in cards.items():
        bdf.write_text(text.format(card=card))
        capsys.readouterr()
        bar = fem.create_sector_from_file(bdf, clamp=root, units="mm", mass_check=False)
        assert "material: E = 210 GPa, nu = 0.3, rho = 9000 kg/m^3 (the deck's)" in capsys.readouterr().out, form
        assert bar.material == Material(E=210e9, nu=0.3, rho=9000.0), form
        np.testing.assert_allclose(fem.compute_clamped_modes(bar, 2).omega,
                                   w0 * np.sqrt((210.0 / 180.0) * (8000.0 / 9000.0)), rtol=1e-9)
    bdf.write_text(text.format(card="MAT1,1,210000.,,0.3"))
    with pytest.raises(ValueError) as e:
        fem.create_sector_from_file(bdf, clamp=root, units="mm", mass_check=False)
    _one_line(e, "bar.bdf, line", "(MAT1): no RHO")
