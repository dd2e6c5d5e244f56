"""The full order's problem object (``fem.periodic.RepeatingNewmark``) and its energy (#86 item 2a, #87): its strain
energy is the potential of its internal force (Taylor: the first-order remainder decays as eps^2, for St.
Venant-Kirchhoff and the neo-Hookean law, through the adapter's own quadrature and the sectors' maps), and one step of
the loaded blade's energy balance holds the identities of ``dynamics.energy``: average acceleration's algorithmic
term is zero to round-off, and SVK's internal force being exactly cubic in x, the trapezoidal gap G of a step is
(phi(0) - 2 phi(1/2) + phi(1)) / 3, phi(s) = f_int(x_n + s dx).dx, to round-off (a strain energy that is not the
force's potential breaks it)."""
import numpy as np
import pytest

from rotor37_rom import fem
from rotor37_rom.dynamics.energy import balance_of_run, record_run
from rotor37_rom.fem.periodic import NewmarkScheme, RepeatingNewmark, SectorLoad

pytestmark = pytest.mark.fe


def _field(problem, amplitude, seed):
    """A smooth field of ``amplitude`` (m) at the tip on the free DOFs: the first modes mixed at random."""
    omega, phi = problem.system.modes(4)
    x = phi @ np.random.default_rng(seed).standard_normal(4)
    return amplitude * x / np.abs(x).max()


@pytest.mark.parametrize("law", ["svk", "neo-hookean"])
def test_the_strain_energy_is_the_internal_forces_potential(ci_blade, ci_ops, law):
    ops = ci_ops if law == "svk" else fem.create_svk_operators(ci_blade, law=law)
    problem = RepeatingNewmark(ci_blade, 1, 1e-6, 1, ops=ops)
    x, d = _field(problem, 2e-3, 1), _field(problem, 2e-3, 2)
    e0, slope = problem.strain_energy(x), d @ problem.system.internal(x)
    eps = 0.1 * 0.5 ** np.arange(4)
    remainder = np.array([abs(problem.strain_energy(x + h * d) - e0 - h * slope) for h in eps])
    rates = np.log2(remainder[:-1] / remainder[1:])
    assert rates.min() > 1.9, (remainder, rates)
    assert remainder[-1] > 1e4 * np.finfo(float).eps * abs(e0)          # the remainders are above round-off


def test_one_loaded_step_closes_the_energy_balance_to_round_off(ci_blade, ci_ops):
    dof = 3 * int(np.asarray(ci_blade.tip_dofs)[0, 0] // 3) + 2          # node LE's e_z
    problem = RepeatingNewmark(ci_blade, 1, 2e-5, 3, ops=ci_ops,
                               load=SectorLoad(dof, lambda t: np.array([20.0 * np.sin(2e4 * t)])),   # one step each
                               scheme=NewmarkScheme(None, rtol=1e-10, atol=1e-9))
    x0, v0, a0 = problem.start()
    run = record_run(problem.stepper, np.arange(4) * 2e-5, x0, v0, a0)
    b = balance_of_run(problem.stepper, run, problem.strain_energy)
    round_off = 1e3 * np.finfo(float).eps * b.scale
    assert np.abs(b.algorithmic).max() <= round_off.max(), (b.algorithmic, round_off)
    internal = problem.system.internal
    for k in range(3):
        x, dx = run.x[:, k], run.x[:, k + 1] - run.x[:, k]
        phi = [internal(x + s * dx) @ dx for s in (0.0, 0.5, 1.0)]
        simpson_gap = (phi[0] - 2 * phi[1] + phi[2]) / 3
        assert abs(b.quadrature_gap[k] - simpson_gap) <= round_off[k], (k, b.quadrature_gap[k], simpson_gap)
    assert np.abs(b.quadrature_gap).min() > 1e3 * round_off.max()      # GNL is felt: the check is not 0 = 0


def test_bad_problems_and_energy_runs_are_refused_in_one_line(ci_blade, ci_ops, tmp_path):
    from rotor37_rom.dynamics.casing import Casing
    from rotor37_rom.fem.periodic import CasingContact
    from rotor37_rom.studies.gnl_reference import SteadyCase, full_order_energy

    for make, word in ((lambda: RepeatingNewmark(ci_blade, 1, 0.0, 1, ops=ci_ops), "dt must be"),
                       (lambda: RepeatingNewmark(ci_blade, 1, 1e-6, 0, ops=ci_ops), "n_steps"),
                       (lambda: NewmarkScheme(rho_inf=1.5), "rho_inf"),
                       (lambda: RepeatingNewmark(ci_blade, 1, 1e-6, 1, ops=ci_ops, damping="heavy"), "damping must"),
                       (lambda: RepeatingNewmark(ci_blade, 1, 1e-6, 1, ops=ci_ops,
                                                 contact=CasingContact(Casing(), -1.0)), "omega"),
                       (lambda: RepeatingNewmark(ci_blade, 1, 1e-6, 1, ops=ci_ops,
                                                 load=SectorLoad(np.ones(5), lambda t: [1.0])), "a load vector")):
        with pytest.raises(ValueError, match=word):
            make()
    other = tmp_path / "other.npz"
    np.savez(other, signature=np.zeros(3), step=0, x=np.zeros(1), v=np.zeros(1), a=np.zeros(1))
    case = SteadyCase(1280.0, revolutions=3)
    with pytest.raises(ValueError, match="belongs to another run"):
        full_order_energy(ci_blade, ci_ops, case, 2e-6, 0.8, other)
    with pytest.raises(ValueError, match="revolutions"):
        full_order_energy(ci_blade, ci_ops, case, 2e-6, 0.8, other, revolutions=0.0)
