"""Cyclic sectors on the FE side: face pairing, the projected operators per nodal diameter against the whole
assembled structure and against the Kirchhoff annular plate, the rotor 37 bladed-disk sector, MPI, bad input."""

import numpy as np
import pytest
import scipy.linalg
import scipy.optimize
import scipy.sparse.linalg
from scipy import special

from rotor37_rom import fem
from rotor37_rom.disk.symmetry import assemble_full_structure, harmonic_indices

PLATE = dict(inner=0.1, outer=0.2, thickness=4e-3)


def kirchhoff_annular_plate(n: int, inner: float, outer: float, nu: float = 0.3, count: int = 1) -> np.ndarray:
    """Frequency parameters lambda a (lambda^4 = rho h omega^2 / D) of the first ``count`` modes with n nodal
    diameters of a Kirchhoff annular plate clamped at r = inner and free at r = outer: the roots of the 4 x 4
    frequency determinant of W = A J_n + B Y_n + C I_n + D K_n (Vogel & Skinner, J. Appl. Mech. 32 (1965) 926;
    Leissa, Vibration of Plates, NASA SP-160 (1969) §2.3): W = W' = 0 at the inner edge, M_r = 0 and the Kirchhoff
    shear V_r = 0 at the outer edge."""
    fns = [lambda z, d: special.jvp(n, z, d), lambda z, d: special.yvp(n, z, d),
           lambda z, d: special.ivp(n, z, d), lambda z, d: special.kvp(n, z, d)]

    def det(lam):
        rows = []
        b, a = lam * inner, lam * outer
        rows.append([f(b, 0) for f in fns])
        rows.append([lam * f(b, 1) for f in fns])
        W = np.array([[f(a, d) * lam ** d for f in fns] for d in range(4)])       # W, W', W'', W''' at r = a
        r = outer
        rows.append(W[2] + nu * (W[1] / r - n ** 2 * W[0] / r ** 2))
        lap_r = W[3] + W[2] / r - W[1] / r ** 2 - n ** 2 * (W[1] / r ** 2 - 2 * W[0] / r ** 3)
        rows.append(lap_r + (1 - nu) * n ** 2 / r ** 2 * (W[0] / r - W[1]))
        A = np.array(rows)
        return np.linalg.det(A / np.abs(A).max(axis=0))

    grid = np.linspace(0.5, 60.0, 4000) / outer
    values = np.array([det(x) for x in grid])
    roots = [scipy.optimize.brentq(det, grid[i], grid[i + 1], xtol=1e-14)
             for i in np.flatnonzero(np.sign(values[:-1]) != np.sign(values[1:]))]
    # sign changes across the poles of Y_n, K_n scaling are not roots: keep those where |det| is small around
    roots = [x for x in roots if abs(det(x)) < 1e-6]
    return np.array(roots[:count]) * outer


@pytest.fixture(scope="module")
def plate():
    return fem.create_annular_sector(PLATE["inner"], PLATE["outer"], PLATE["thickness"], n_sectors=8, size=0.012,
                                     layers=1)


def test_plate_cyclic_modes_equal_the_assembled_plate(plate):
    """N = 8 plate sectors: the cyclic eigenvalues of every k = 0 ... 4 (SLEPc shift-invert on T_k^T K T_k) are the
    eigenvalues of the whole plate assembled from 8 turned copies of the sector, to 1e-8 relative (both solvers
    converge to 1e-12; the two operators are assembled in different orders: round-off u kappa ~ 1e-10)."""
    ops = fem.create_svk_operators(plate)
    K, M = fem.assemble_stiffness(plate, ops), fem.assemble_mass(plate, ops)
    cyclic = []
    for k in harmonic_indices(8):
        omega = fem.solve_cyclic_modes(plate, k, 5, K, M).omega
        cyclic.append(omega)
    covered = min(w.max() for w in cyclic)             # every k's modes below this are all computed
    union = np.sort(np.concatenate(cyclic))
    union = union[union < covered * (1 - 1e-6)]
    Ks, Ms = fem.petsc_to_scipy(K), fem.petsc_to_scipy(M)
    dofs = np.arange(plate.n_dofs).reshape(-1, 3)
    K_full, M_full, _ = assemble_full_structure(Ks, Ms, plate.cyclic, dofs)
    lam = scipy.sparse.linalg.eigsh(K_full.tocsc(), union.size + 4, M_full.tocsc(), sigma=0.0, which="LM",
                                    return_eigenvectors=False, tol=1e-12)
    full = np.sqrt(np.sort(lam))[:union.size]
    print("cyclic", union[:12], "full", full[:12])
    np.testing.assert_allclose(union, full, rtol=1e-8)
    assert plate.cyclic.worst_distance <= 1e-12 * PLATE["outer"]         # the right face is the left one turned


def test_plate_layers_are_honoured():
    """create_annular_sector(layers=3) (#71): every vertex on one of the 3 + 1 planes through the thickness, every
    plane with the same vertices (a structured grid), the right face paired with the left."""
    sector = fem.create_annular_sector(PLATE["inner"], PLATE["outer"], PLATE["thickness"], n_sectors=8, size=0.05,
                                       layers=3)
    z = sector.mesh.geometry.x[:, 2] / PLATE["thickness"]
    planes, counts = np.unique(np.round(z, 12), return_counts=True)
    np.testing.assert_allclose(planes, [-0.5, -1 / 6, 1 / 6, 0.5], atol=1e-12)
    assert len(set(counts)) == 1 and sector.cyclic is not None
    with pytest.raises(ValueError, match="layers must be an integer in 1..50"):
        fem.create_annular_sector(PLATE["inner"], PLATE["outer"], PLATE["thickness"], 8, 0.05, layers=0)


@pytest.mark.slow                     # builds a plate twice as fine (16 s): in make test, not in test-fast
def test_plate_against_kirchhoff_theory(plate, tmp_path):
    """The lowest mode with n = k nodal diameters of the 3-D plate sector (P2) against the Kirchhoff plate (an
    analytical reference, independent of the code): within the thin-plate error, shear and rotary inertia
    (Mindlin) lower the frequency by ~ (1 + 2 / (kappa (1 - nu))) (lambda h)^2 / 24 (kappa = pi^2 / 12), plus the
    mesh's discretisation error, estimated from a mesh twice as fine: the error at least halves per halving of the
    size (measured ~3x: P2 tetrahedra in bending, before the asymptotic h^4), so the coarse-fine difference bounds
    the fine mesh's error. The fine plate is a user's sector (#71): written as a millimetre Abaqus deck (node sets
    CLAMP, LEFT, RIGHT) and read back with ``cyclic=("LEFT", "RIGHT", 8)``."""
    from rotor37_rom.forms import Material

    mat = Material()
    E, nu, rho, h = mat.E, mat.nu, mat.rho, PLATE["thickness"]
    D = E * h ** 3 / (12 * (1 - nu ** 2))
    built = fem.create_annular_sector(PLATE["inner"], PLATE["outer"], h, n_sectors=8, size=0.006, layers=1)
    deck = fem.write_sector_mesh(built, tmp_path / "plate_mm.inp", units="mm")
    fine = fem.create_sector_from_file(deck, clamp="CLAMP", units="mm", verbose=False, cyclic=("LEFT", "RIGHT", 8))
    kappa = np.pi ** 2 / 12
    for k in range(4):
        lam_a = kirchhoff_annular_plate(k, PLATE["inner"], PLATE["outer"], nu)[0]
        lam = lam_a / PLATE["outer"]
        w_kirchhoff = lam ** 2 * np.sqrt(D / (rho * h))
        w_coarse = fem.solve_cyclic_modes(plate, k, 1).omega[0]
        w_fine = fem.solve_cyclic_modes(fine, k, 1).omega[0]
        mindlin = (1 + 2 / (kappa * (1 - nu))) * (lam * h) ** 2 / 24
        mesh = abs(w_fine - w_coarse) / w_fine
        err = abs(w_fine - w_kirchhoff) / w_kirchhoff
        print(f"n = {k}: lambda a = {lam_a:.4f}, Kirchhoff {w_kirchhoff:.1f} rad/s, FE {w_coarse:.1f} / {w_fine:.1f}; "
              f"error {err:.2e}, Mindlin estimate {mindlin:.2e}, mesh estimate {mesh:.2e}")
        assert err <= 2 * mindlin + mesh + 1e-3


@pytest.mark.slow
def test_disk_sector_groups_and_faces(ci_disk):
    """The rotor 37 bladed-disk sector: blade and disk volumes, bore clamp, paired cyclic faces (setPeriodic: the
    worst pair within round-off of the sector's size), 8 tip nodes LE -> TE on the shortened blade's tip."""
    for name in ("blade", "disk", "clamp", "left", "right", "tip", "pressure", "suction"):
        assert name in ci_disk.groups
    pairs = ci_disk.cyclic
    assert pairs.n_sectors == 36 and len(pairs.left) > 50 and len(pairs.axis) == 0
    assert pairs.worst_distance < 1e-12 * 1e3 * 0.25
    tip = ci_disk.tip_nodes
    assert tip.shape == (8, 3) and tip[0, 2] < tip[-1, 2] and np.all(ci_disk.tip_dofs >= 0)
    # LE and TE are the tip section's ends, at span fraction 1 - 4 mm / LE span of the blade law (§3.2: 4 mm shorter)
    from rotor37_rom.geometry.parametric import default_blade_law

    law = default_blade_law()
    span_le = float(np.diff(law.evaluate(0.0, np.array([0.0, 1.0]))[1])[0])
    eta_tip = 1.0 - 4e-3 / span_le
    for node, s in ((tip[0], 0.0), (tip[-1], 1.0)):
        z, r, theta, _ = (float(np.ravel(x)[0]) for x in law.evaluate(s, eta_tip))
        np.testing.assert_allclose(node, [r * np.cos(theta), r * np.sin(theta), z], atol=1e-9)
    # r is a polynomial in eta, not linear: the cut at eta_tip is 4 mm at the LE up to its curvature (~10 um)
    assert abs(float(law.evaluate(0.0, 1.0)[1]) - np.hypot(*tip[0, :2]) - 4e-3) < 1e-4


@pytest.mark.slow
def test_disk_modes_below_the_blade_clamped_on_the_disk(ci_disk):
    """Rayleigh's theorem of constraint on one mesh: clamping every DOF of the disk cells leaves the blade clamped at
    its root, a constrained version of every nodal-diameter problem, so each cyclic frequency is at most the
    corresponding clamped-blade one (SLEPc tolerance 1e-12: asserted with 1e-9 slack). The 1B family rises
    towards it with the nodal diameter (a stiffer disk pattern)."""
    ops = fem.create_svk_operators(ci_disk)
    K, M = fem.assemble_stiffness(ci_disk, ops), fem.assemble_mass(ci_disk, ops)
    blade_only = fem.clamp_cell_group(ci_disk, "disk")
    clamped = fem.compute_clamped_modes(blade_only, 3).omega
    first = []
    for k in (0, 1, 9, 18):
        w = fem.solve_cyclic_modes(ci_disk, k, 3, K, M).distinct()[0]
        assert np.all(w <= clamped * (1 + 1e-9)), (k, w, clamped)
        first.append(w[0])
    print("1B family at k = 0, 1, 9, 18:", first, "blade clamped on the disk:", clamped)
    assert first[1] < first[2] < first[3] < clamped[0]


@pytest.mark.mpi
@pytest.mark.slow
def test_cyclic_frequencies_serial_and_mpi_agree(serial_and_mpi):
    """The plate sector's nodal-diameter frequencies under mpirun -n 2 equal the serial ones to 1e-8 (the
    distributed projection, PtAP and MUMPS differ from serial only by round-off; SLEPc converges to 1e-12), at rest
    and turning at 1,000 rad/s (#73: the centrifugal state's Newton on the distributed T_0, then the families of the
    prestressed tangent)."""
    serial, parallel = serial_and_mpi(f"""
        import sys, numpy as np
        from mpi4py import MPI
        from rotor37_rom import fem
        s = fem.create_annular_sector({PLATE['inner']}, {PLATE['outer']}, {PLATE['thickness']}, 8, 0.012, 1)
        w = np.concatenate([fem.solve_cyclic_modes(s, k, 3).omega for k in range(5)])
        turning, _ = fem.rotating_cyclic_operators(s, 1000.0)
        w = np.concatenate([w] + [turning.modes(k, 3).omega for k in range(5)])
        if MPI.COMM_WORLD.rank == 0:
            np.save(sys.argv[1], w)
    """)
    np.testing.assert_allclose(parallel, serial, rtol=1e-8)


def test_a_users_plate_about_another_axis(plate, tmp_path):
    """A user's sector whose rotation axis is another (#71): the plate deck written with its axis along +x, -y or -z
    (coordinates turned) and read with ``axis=`` is turned back to +z: paired faces, and its cyclic frequencies at
    k = 0 and 1 equal the plate's to 1e-9 (the same nodes and cells, turned twice: round-off). Read without the axis
    its faces do not match under a rotation about z, and that is said."""
    import meshio

    from rotor37_rom.geometry.mesh_import import AXES

    deck = fem.write_sector_mesh(plate, tmp_path / "plate_mm.inp", units="mm")
    mesh = meshio.read(deck)
    ref = [fem.solve_cyclic_modes(plate, k, 3).omega for k in (0, 1)]
    for axis in ("+x", "-y", "-z"):
        turned = tmp_path / f"plate_{axis[1]}{'p' if axis[0] == '+' else 'm'}.inp"
        meshio.write(turned, meshio.Mesh(mesh.points @ AXES[axis], mesh.cells, point_sets=mesh.point_sets))
        sector = fem.create_sector_from_file(turned, clamp="CLAMP", units="mm", verbose=False,
                                             cyclic=("LEFT", "RIGHT", 8), axis=axis, material=plate.material)
        assert f"its axis {axis} turned to +z" in sector.summary
        for k, omega in zip((0, 1), ref):
            np.testing.assert_allclose(fem.solve_cyclic_modes(sector, k, 3).omega, omega, rtol=1e-9)
    with pytest.raises(ValueError, match="cyclic faces do not match under a rotation by 360/8 degrees"):
        fem.create_sector_from_file(turned, clamp="CLAMP", units="mm", verbose=False, cyclic=("LEFT", "RIGHT", 8),
                                    material=plate.material)
    with pytest.raises(ValueError, match="axis must be one of"):
        fem.create_sector_from_file(turned, clamp="CLAMP", units="mm", verbose=False, axis="z",
                                    material=plate.material)


def test_cyclic_bad_input(plate, ci_blade):
    with pytest.raises(ValueError, match="no 'left' face group"):
        fem.locate_cyclic_pairs(ci_blade, 36)
    with pytest.raises(ValueError, match="do not match under a rotation by 360/9 degrees.*m from the nearest"):
        fem.locate_cyclic_pairs(plate, 9)                   # the plate was built for 8 sectors
    with pytest.raises(ValueError, match="integer in \\[2, 360\\]"):
        fem.locate_cyclic_pairs(plate, 7.5)
    with pytest.raises(ValueError, match="k must be an integer in \\[0, 4\\]"):
        fem.solve_cyclic_modes(plate, 5)
    with pytest.raises(ValueError, match="not a cyclic sector"):
        fem.solve_cyclic_modes(ci_blade, 0)


@pytest.mark.slow
def test_safe_families_and_full_disk_pictures(ci_disk, tmp_path):
    """SAFE labels at k = 0 and 18: the three lowest modes are the blade's 1B, 1T, 2B (blade-dominated: most of their
    strain energy in the blade), and at k = 0 a disk-dominated mode follows (low nodal diameters bend the disk most).
    The 1B family drawn on the whole disk (36 sectors, disk included) at k = 0, 3, 18: non-blank pictures whose drawn
    range is the normalised magnitude [0, 1] on 36 x the sector's cells."""
    import json

    from PIL import Image

    from rotor37_rom.fem.safe import compute_safe_diagram
    from rotor37_rom.viz.plotting import render_cyclic_mode

    safe = compute_safe_diagram(ci_disk, 4, ks=(0, 18))
    print(safe.family, safe.omega, safe.blade_share)
    for i in range(2):
        assert list(safe.family[i][:3]) == ["1B", "1T", "2B"]
        assert np.all(safe.blade_share[i][:3] > 0.5)
    assert "disk" in safe.family[0]
    n_cells = ci_disk.mesh.topology.index_map(3).size_local
    for k in (0, 3, 18):
        modes = fem.solve_cyclic_modes(ci_disk, k, 1)
        path = render_cyclic_mode(ci_disk, modes.a[0], modes.b[0], k, tmp_path / f"k{k}.png", f"1B, k = {k}")
        info = json.loads(path.with_name(path.name + ".json").read_text())
        assert info["n_cells"] == 36 * n_cells
        assert info["scalar_range"][1] == pytest.approx(1.0, abs=1e-12) and info["scalar_range"][0] >= 0.0
        pixels = np.asarray(Image.open(path).convert("L"))
        assert (pixels < 250).mean() > 0.02                      # not blank
