"""Misuses of the periodic-orbit API and of a turning model's speed (#85, items 5 and 6): each is refused before any
work with one line naming the argument and its range (never a traceback from inside NumPy, a hang or a silently
wrong orbit); a continuation that heads for omega <= 0 ends at the boundary omega > 0 saying so; the ``--periodic``
scene flags the orbits that move a node past the maps' own blow-up limit, as the maps flag their runs. On the
Duffing oscillator of ``test_harmonic_balance`` (fast: one degree of freedom)."""
import contextlib
import math
import signal
import types

import numpy as np
import pytest

from rotor37_rom.periodic import Harmonics, HarmonicBalance, Shooting, continue_branch, solve_periodic
from test_harmonic_balance import F0, duffing

NAN, INF = math.nan, math.inf


@contextlib.contextmanager
def within(seconds: float):
    """Fail (TimeoutError) instead of hanging where the body runs longer than ``seconds``."""
    def stop(signum, frame):
        raise TimeoutError(f"still running after {seconds:g} s (a hang)")

    previous = signal.signal(signal.SIGALRM, stop)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def refused(call, word: str, errors=(ValueError, TypeError), seconds: float = 10.0) -> str:
    """The one-line message of the ValueError/TypeError ``call()`` raises; it must name ``word``."""
    with within(seconds), pytest.raises(errors) as caught:
        call()
    message = str(caught.value)
    assert word in message, message
    assert "\n" not in message, message
    return message


@pytest.fixture(scope="module")
def orbit():
    """The Duffing oscillator's balance (H = 1) and its orbit at omega = 0.5 (below resonance, stable)."""
    hb = duffing(1)
    return hb, solve_periodic(hb, np.r_[0.0, F0 / 0.75, 0.0], 0.5)


@pytest.mark.parametrize("omega", [-0.5, 0.0, -0.0, INF, -INF, NAN, "0.5", True])
def test_solve_periodic_refuses_a_frequency_not_positive_and_finite(omega):
    """At -omega the balance's root is the mirrored orbit (called stable), at 0 the static state (called a stable
    periodic orbit): both refused, as are non-finite and non-numeric frequencies."""
    message = refused(lambda: solve_periodic(duffing(1), np.r_[0.0, F0 / 0.75, 0.0], omega), "omega")
    assert "> 0" in message


def test_solve_periodic_refuses_bad_newton_arguments(orbit):
    hb, sol = orbit
    refused(lambda: solve_periodic(hb, sol.unknowns, 0.5, tol=NAN), "tol")
    refused(lambda: solve_periodic(hb, sol.unknowns, 0.5, max_iter=2.5), "max_iter")
    refused(lambda: solve_periodic(hb, np.zeros(5), 0.5), "x0")
    refused(lambda: solve_periodic(hb, np.full(3, NAN), 0.5), "x0")


class _Fake:
    """The least of a blade's explicit scheme ``Shooting`` needs to be built without a model (a casing-free,
    forced map)."""

    r, h_crit = 1, 1.0


def test_shooting_refuses_omega_zero():
    """Shooting at omega = 0 raised ZeroDivisionError (the step 2 pi / omega / n): refused naming omega."""
    shooting = Shooting(_Fake(), casing=None, forcing=lambda t, omega: np.zeros(1), steps=8)
    refused(lambda: shooting.scheme_at(0.0), "omega")
    refused(lambda: shooting.residual(np.zeros(2), 0.0), "omega")
    refused(lambda: solve_periodic(shooting, np.zeros(2), 0.0), "omega")


def test_continuation_stops_at_the_boundary_omega_positive(orbit):
    """Continued down from 0.5 towards -1, the branch walked through omega = 0 into the mirrored orbits: it ends at
    the boundary omega > 0, its last point short of 0, with that reason."""
    hb, sol = orbit
    with within(30):
        branch = continue_branch(hb, sol, -1.0, step=0.1)
    assert np.all(branch.omega > 0), branch.omega.min()
    assert "boundary omega > 0" in branch.ended, branch.ended
    assert branch.omega.min() < 0.05                      # it did walk down to the boundary
    refused(lambda: continue_branch(hb, sol, INF, step=0.1), "omega_end")
    refused(lambda: continue_branch(hb, sol, NAN, step=0.1), "omega_end")


@pytest.mark.parametrize("options, word", [
    ({"step": INF}, "step"),                          # hung: the step halved from inf forever
    ({"step": 0.1, "step_min": 0.0}, "step_min"),     # a failing corrector halved the step to 0 and on
    ({"step": 0.1, "step_min": NAN}, "step_min"),
    ({"step": 0.1, "step_max": INF}, "step_max"),     # the step grew to inf, then halved from inf forever
    ({"step": 0.1, "step_max": 0.01}, "step_max"),
    ({"step": 0.1, "tol": NAN}, "tol"),
    ({"step": 0.1, "max_points": 2.5}, "max_points"),
    ({"step": 0.1, "max_iter": 0}, "max_iter"),
    ({"step": 0.1, "progress": "print"}, "progress"),
])
def test_continuation_refuses_bad_steps_and_numbers(orbit, options, word):
    hb, sol = orbit
    refused(lambda: continue_branch(hb, sol, 1.5, **options), word, seconds=5)


def test_continuation_refuses_a_start_at_omega_not_positive(orbit):
    hb, sol = orbit
    mirrored = type(sol)(-sol.omega, sol.X.copy(), sol.exponents, sol.stable)
    refused(lambda: continue_branch(hb, mirrored, 1.5, step=0.1), "start.omega", seconds=5)


@pytest.mark.parametrize("M, C, K, word", [
    (np.eye(2), np.zeros((2, 2)), np.eye(3), "K"),             # M 2 x 2 with K 3 x 3 was accepted
    (np.eye(2), np.zeros((3, 3)), np.eye(3), "C"),
    (np.eye(3), np.zeros((2, 2)), np.eye(3), "C"),
    (np.eye(3), np.zeros((3, 3)), np.eye(2), "K"),
    (np.ones((2, 3)), np.zeros((2, 2)), np.eye(2), "M"),       # not square
    (np.eye(2), np.zeros((2, 2)), np.ones(2), "K"),            # not a matrix
    (np.eye(2), np.zeros((2, 2)), np.diag([1.0, NAN]), "K"),   # not finite
    (np.eye(2), np.diag([INF, 0.0]), np.eye(2), "C"),
    (np.eye(2), np.zeros((2, 2)), [["a", "b"], ["c", "d"]], "K"),
])
def test_harmonic_balance_refuses_bad_matrices(M, C, K, word):
    basis = Harmonics(1, 8)
    F = np.zeros((basis.size, len(K)))                   # the excitation of K's size: the matrices are at fault
    message = refused(lambda: HarmonicBalance(M, C, K, None, F, basis), word)
    assert message.startswith(word), message           # the matrix at fault first (and the one it differs from)


def test_harmonic_balance_refuses_a_bad_excitation_basis_or_force():
    basis = Harmonics(1, 8)
    refused(lambda: HarmonicBalance(np.eye(2), np.zeros((2, 2)), np.eye(2), None, np.zeros((3, 3)), basis),
            "excitation")
    refused(lambda: HarmonicBalance(np.eye(2), np.zeros((2, 2)), np.eye(2), None, np.full((3, 2), NAN), basis),
            "excitation")
    refused(lambda: HarmonicBalance(np.eye(2), np.zeros((2, 2)), np.eye(2), None, np.zeros((3, 2)), (1, 8)),
            "basis")
    refused(lambda: HarmonicBalance(np.eye(2), np.zeros((2, 2)), np.eye(2), "cubic", np.zeros((3, 2)), basis),
            "force")


@pytest.mark.parametrize("spin", ["1000", "fast", [500.0], None, np.array([100.0, 200.0])])
def test_a_turning_model_refuses_a_speed_that_is_not_a_number(spin):
    """A string speed failed inside NumPy (isfinite on a str), a list passed: one line naming spin."""
    from rotor37_rom.model.rotating import RotationTerms, centrifugal_equilibrium, check_spin

    terms = RotationTerms(M_P=np.eye(2), F_c=np.ones(2), G=np.zeros((2, 2)), speeds=np.array([1000.0, 2000.0]))
    model = types.SimpleNamespace(rotation=terms, r=2, K=np.eye(2), forces=None)
    message = refused(lambda: check_spin(model, spin), "spin")
    assert "finite speed >= 0 rad/s" in message
    refused(lambda: centrifugal_equilibrium(model, spin), "spin")


def test_orbits_past_the_maps_blowup_limit_are_flagged():
    """The maps' test (a node displacement past ``dynamics.explicit.simulate``'s blow-up limit, 20 mm, or not finite)
    on a synthetic orbit just under, just over, and not finite; a branch's summary and description carry the
    flag, and a flagged orbit's amplitude is not given as a result."""
    import inspect

    from rotor37_rom.dynamics.explicit import simulate
    from rotor37_rom.studies.periodic_map import BLOWUP_LIMIT, PeriodicBranch, orbit_blowup

    assert BLOWUP_LIMIT == inspect.signature(simulate).parameters["blowup_limit"].default
    rows = [0, 1, 2]                                   # the entries of q that hold node displacements
    tau = np.linspace(0, 2 * np.pi, 65)
    states = np.zeros((65, 5))
    states[:, 3] = 10.0                                # a modal coordinate: not a node displacement
    for peak, blown in ((0.99 * BLOWUP_LIMIT, False), (1.01 * BLOWUP_LIMIT, True)):
        states[:, 1] = peak * np.sin(tau)
        largest, flag = orbit_blowup(states, rows)
        assert flag is blown and largest == pytest.approx(peak, rel=1e-3)
    states[7, 2] = NAN
    assert orbit_blowup(states, rows)[1] is True

    branch = PeriodicBranch(speeds=np.array([1200.0, 1210.0]), amplitude=np.array([1e-3, np.nan]),
                            stable=np.array([True, True]), multiplier=np.array([0.9, 0.95]), bifurcations=[],
                            folds=[], ended="reached 1210 rad/s", steps=100, wall_s=1.0,
                            blown_up=np.array([False, True]), largest_displacement=np.array([2e-3, 0.03]))
    summary = branch.summary()
    assert summary["blown_up"] == [False, True] and summary["blown_up_speeds"] == [1210.0]
    assert summary["blowup_limit"] == BLOWUP_LIMIT
    assert "BLOWN UP" in branch.describe() and "1210.0" in branch.describe()
    assert "BLOWN UP" not in PeriodicBranch(speeds=np.array([1200.0]), amplitude=np.array([1e-3]),
                                            stable=np.array([True]), multiplier=np.array([0.9]), bifurcations=[],
                                            folds=[], ended="", steps=100, wall_s=1.0).describe()
