"""Clearance consumption (§2.3.2): the geometric measure, and the full-order linear vs nonlinear statics."""
import numpy as np

from rotor37_rom.clearance import clearance_change, delta_range_within, relative_error


def test_clearance_change_geometry():
    x0 = np.array([0.25, 0.0, 0.01])
    # radial displacement on a cylindrical casing: Delta = u_r exactly
    assert np.isclose(clearance_change(x0, np.array([1e-3, 0.0, 0.0]), 0.0), 1e-3, rtol=1e-12)
    # tangential displacement v raises the radius by sqrt(r^2 + v^2) - r (second order)
    v = 5e-3
    assert np.isclose(clearance_change(x0, np.array([0.0, v, 0.0]), 0.0), np.hypot(0.25, v) - 0.25, rtol=1e-12)
    # on a cone of slope s, moving along the cone leaves the clearance unchanged
    s = -0.2737
    along = 1e-3 * np.array([s, 0.0, 1.0]) / np.hypot(1.0, s)
    assert abs(clearance_change(x0, along, s)) < 1e-12
    d = np.linspace(-1, 1, 9)
    err = np.abs(d) ** 2
    assert delta_range_within(d, err, 0.1) == (-0.25, 0.25)
    assert np.isnan(relative_error(np.array([0.0]), np.array([0.0]))[0])


def test_clearance_consumption_full_and_reduced(ci_blade, ci_ops):
    """ci preset, 1B (zeta = 1 mm) and 1T (0.5 mm) along e_x.

    Full order: the linear model's clearance consumption is within 10 % of the nonlinear one for |delta| <= 0.1 and
    not beyond |delta| = 0.4 (paper: within [-0.25, 0.2] and [-0.1, 0.1]).
    Reduced: r_b = 24, r_c = 15 and the 6 modal derivatives of the first three clamped normal modes (r = 45) stay
    within 10 % of the full-order nonlinear curve over delta in [-1, 1] (measured: 1.4 % and 6.7 %)."""
    from rotor37_rom.builder import ReductionConfig, build_reduced_model, clearance_consumption_study

    rom, _ = build_reduced_model(ci_blade, ReductionConfig(r_c=15, r_md=0, forces="quadrature", global_md_modes=3),
                                 ops=ci_ops)
    for mode, zeta in (("1B", 1e-3), ("1T", 0.5e-3)):
        c = clearance_consumption_study(ci_blade, mode, zeta, n_levels=10, ops=ci_ops, roms={"rom": rom})
        rom_error = relative_error(c.curves["rom"], c.curves["FOM nonlinear"])
        print(mode, "ROM r = 45 max error", np.nanmax(rom_error))
        assert np.nanmax(rom_error) <= 0.1
        err = relative_error(c.curves["FOM linear"], c.curves["FOM nonlinear"])
        lo, hi = delta_range_within(c.deltas, err)
        print(mode, "linear within 10 % for delta in", (lo, hi), "max error", np.nanmax(err))
        assert lo <= -0.1 + 1e-12 and hi >= 0.1 - 1e-12
        assert -0.4 <= lo and hi <= 0.4
        assert np.nanmax(err) > 0.3
