"""No silent wrong answer on a user's own blade (#85): the contact normal 'x' is the blade's frame, not the file's
(the same blade turned about the axis gives the same sprag-slip onsets); a box clamp that catches more than one face
and a tip that reaches down the flanks are refused; the casing's sense is checked by the library, not only by the
scenes; a file without a material is refused unless one is given or the paper's steel confirmed."""
import numpy as np
import pytest

from rotor37_rom import fem
from rotor37_rom.forms import Material

pytestmark = pytest.mark.fe


def _turned_deck(deck, path, angle):
    """The deck's blade turned by ``angle`` (rad) about e_z, its node sets and material kept (a rotation keeps the
    tetrahedra's orientation)."""
    import meshio

    from rotor37_rom.disk.symmetry import rotation_z
    from rotor37_rom.fem.sector import deck_material_lines

    mesh = meshio.read(deck)
    (block,) = mesh.cells
    meshio.write(path, meshio.Mesh(mesh.points @ rotation_z(angle).T, [(block.type, block.data)],
                                   point_sets=mesh.point_sets))
    with open(path, "a") as out:
        out.write(deck_material_lines(Material(), "mm", len(block.data)))
    return path


@pytest.fixture(scope="module")
def ci_deck(ci_blade, tmp_path_factory):
    return fem.write_sector_mesh(ci_blade, tmp_path_factory.mktemp("frame") / "blade_mm.inp", units="mm")


def test_a_turned_blade_has_the_same_sprag_slip_onsets(ci_deck, tmp_path):
    """The ci blade turned about the rotation axis by 1.22, -7 and 40 degrees in its file is the same blade: its
    frame turns with it (the plane through the axis and its centre of mass, to round-off), and the sprag-slip
    onset mu* of every contact node with the paper's normal 'x' is the same to the round-off of the solves (1e-8;
    with the file's e_x as the normal, 1.22 deg alone moved the third-party blade's onset from 0.2290 to 0.2419)."""
    from rotor37_rom.dynamics.casing import Casing, contact_matrices
    from rotor37_rom.dynamics.friction import sprag_slip_friction
    from rotor37_rom.reduction.builder import ReductionConfig, build_reduced_model

    config = ReductionConfig(r_c=8, r_md=0, forces="none", keep_basis=False)
    angles = np.radians([0.0, 1.22, -7.0, 40.0])
    onsets, frames = [], []
    for angle in angles:
        deck = ci_deck if angle == 0 else _turned_deck(ci_deck, tmp_path / f"turned_{angle:.3f}.inp", angle)
        blade = fem.create_sector_from_file(deck, clamp="CLAMP", tip="TIP", units="mm", contact=8, verbose=False)
        model = build_reduced_model(blade, config)[0]
        frames.append(model.nodes.frame_angle)
        N, S, _, _ = contact_matrices(model.nodes, model.r, Casing(direction="x"))
        onsets.append([sprag_slip_friction(model.K, N, S, [k]) for k in range(N.shape[0])])
    np.testing.assert_allclose(np.array(frames) - angles, frames[0], atol=1e-12)
    finite = np.isfinite(onsets[0])
    assert finite.sum() >= 2, onsets[0]
    for other in onsets[1:]:
        assert np.array_equal(np.isfinite(other), finite), (onsets[0], other)
        np.testing.assert_allclose(np.array(other)[finite], np.array(onsets[0])[finite], rtol=1e-8)


def test_box_clamps_and_tips_that_catch_other_faces_are_refused(ci_deck, tmp_path):
    """A box around one face clamps as the named set of that face does (a cantilever's root: the same frequencies);
    the bounding box of the ci blade's root, which on the hub cone also takes the flanks above it, is refused in
    one line (it over-clamps: +7.5 % on a third-party blade's f1), and so is the tip's bounding box, which on the
    conical tip reaches down the flanks (the 'camber line' nodes would sit on them)."""
    import meshio
    from test_mesh_import import H, _bar

    bar = _bar(tmp_path / "bar.msh", "tet", n=(6, 2))
    pad = 1e-6
    named = fem.create_sector_from_file(bar, clamp="ROOT", verbose=False, material=Material())
    boxed = fem.create_sector_from_file(bar, clamp=(-pad, -pad, -pad, pad, H + pad, H + pad), verbose=False,
                                        material=Material())
    np.testing.assert_allclose(fem.compute_clamped_modes(boxed, 2).omega, fem.compute_clamped_modes(named, 2).omega,
                               rtol=1e-10)
    deck = meshio.read(ci_deck)
    x = deck.points * 1e-3                                           # m
    r = np.hypot(x[:, 0], x[:, 1])
    root = deck.point_sets["CLAMP"]
    root_box = tuple(x[root].min(axis=0) - pad) + tuple(x[root].max(axis=0) + pad)
    with pytest.raises(ValueError, match=r"^clamp: the box .* facing more than 30 deg away") as info:
        fem.create_sector_from_file(ci_deck, clamp=root_box, units="mm", verbose=False)
    assert "\n" not in str(info.value)
    tip_nodes = deck.point_sets["TIP"]
    # the tip's bounding box: on a conical tip (r from 252 mm at the LE to 244 mm at the TE) it also takes the
    # flanks below the LE half of the tip
    low_tip = tuple(x[tip_nodes].min(axis=0) - pad) + tuple(x[tip_nodes].max(axis=0) + pad)
    assert r[tip_nodes].max() - r[tip_nodes].min() > 5e-3
    with pytest.raises(ValueError, match=r"^tip: contact nodes .* are not on the tip") as info:
        fem.create_sector_from_file(ci_deck, clamp="CLAMP", tip=low_tip, units="mm", contact=8, verbose=False)
    assert "\n" not in str(info.value)


def test_the_library_checks_the_sense_and_asks_for_a_material(ci_rom, ci_deck, tmp_path):
    """Called directly, contact_matrices refuses the sense that turns the ci blade with its trailing edge ahead (the
    check is the casing's, so every caller gets it); a mesh file without a material is refused, naming material=,
    and runs on the paper's steel only when that is said (material=Material()); the deck written by
    write_sector_mesh keeps its material."""
    import meshio

    from rotor37_rom.dynamics.casing import Casing, contact_matrices

    with pytest.raises(ValueError, match=r"^casing rotation_sense \+1 turns this blade with its trailing edge ahead"):
        contact_matrices(ci_rom.nodes, ci_rom.r, Casing(rotation_sense=+1))
    assert contact_matrices(ci_rom.nodes, ci_rom.r, Casing(rotation_sense=-1))[0].shape[1] == ci_rom.r
    bare = tmp_path / "bare_mm.inp"
    mesh = meshio.read(ci_deck)
    meshio.write(bare, meshio.Mesh(mesh.points, [(c.type, c.data) for c in mesh.cells], point_sets=mesh.point_sets))
    with pytest.raises(fem.MissingMaterial, match=r"states no material: give material="):
        fem.create_sector_from_file(bare, clamp="CLAMP", units="mm", verbose=False)
    steel = fem.create_sector_from_file(bare, clamp="CLAMP", units="mm", verbose=False, material=Material())
    kept = fem.create_sector_from_file(ci_deck, clamp="CLAMP", units="mm", verbose=False)
    assert steel.material == Material()
    # a material given stands whatever the deck's says in the units given (a mm deck's N-mm-t-s material read as
    # metres is no structural material: it used to refuse the file, "give material=", although it was given)
    given = fem.create_sector_from_file(ci_deck, clamp="CLAMP", units="m", verbose=False, material=Material(),
                                        mass_check=False)
    assert given.material == Material()
    np.testing.assert_allclose([kept.material.E, kept.material.nu, kept.material.rho],
                               [Material().E, Material().nu, Material().rho], rtol=1e-12)
