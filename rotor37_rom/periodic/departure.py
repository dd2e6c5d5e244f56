"""The tuned disk's travelling wave marched as the full disk: does a perturbation of other nodal diameters grow at the
rate Hill's method on one sector predicts? (#72, the disk's version of check (d).)

A wave of k diameters on N sectors lives, at every instant, in the nodal diameters that are multiples of g = gcd(k,
N) (harmonic h in h k mod N). A perturbation of Hill class j (harmonic h in h k +- j) lives in the diameters
congruent to +-j mod g. So the disk's coordinates split into g // 2 + 1 residue sets rho = 0 .. g // 2 (the diameters
d with d = +-rho mod g), each invariant under the disk's operators (they commute with the turn by one sector) and,
to first order in the perturbation, under its dynamics about the wave: the part of the state in a set rho != 0 is a
perturbation of the wave alone, whatever the harmonic truncation of the wave, and it grows per period at the
largest multiplier of the classes j = +-rho mod g. The set rho = 0 holds the wave itself and classes 0, g, 2g, ...:
there the run's departure from the wave mixes the balance's truncation with the perturbation, and is reported as a
drift, not a rate.

``wave_departure`` starts the full disk on the one-sector wave at phase 0 (``time_state`` of its coefficients, and
the series' acceleration), adds in every set rho != 0 a random combination of that set's lowest modes (below
``mode_cap`` times the wave's frequency: modes the step resolves), ``size`` of the wave's amplitude (energy norm),
with their accelerations, and marches the full disk by generalised alpha (``dynamics.newmark.dense_newmark``,
rho_inf = 0.8: it damps the stiff coordinates' ringing that the balance's truncated harmonics start, and a resolved
mode by O((omega h)^3) a step; ``rho_inf=None``: average acceleration), sampling each set's energy once a period.
The measured multiplier of a set is exp of the least-squares slope of the log of its amplitude (the square root of
its energy relative to the wave's) over the second half of the periods marched. The run stops when a perturbation
reaches ``linear_limit`` of the wave, or when the wave's own set drifts ``drift_limit`` from the balance's wave (an
instability of the classes 0, g, 2 g, ... seeded by the truncation: past it the perturbations no longer see the
wave). Pure NumPy/SciPy.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import scipy.linalg

from rotor37_rom.dynamics.newmark import dense_newmark
from rotor37_rom.periodic.harmonic_balance import time_state

__all__ = ["SetDeparture", "WaveDeparture", "residue_sets", "wave_departure"]


@dataclasses.dataclass
class SetDeparture:
    """One residue set's run: its diameters and Hill classes, the classes' largest multiplier |mu| (predicted), the
    square root of its energy at each sampled period (relative to the wave's), and the measured multiplier (None
    where the window had fewer than 4 periods)."""

    residue: int
    diameters: tuple
    classes: tuple
    predicted: float
    amplitude: np.ndarray
    measured: float | None


@dataclasses.dataclass
class WaveDeparture:
    """The run: the wave's frequency omega (rad/s), the steps a period, the periods marched, each perturbed set's
    ``SetDeparture``, the largest multiplier of the classes of the wave's own set rho = 0 (``wave_predicted``), why
    the run ended (``ended``: the periods asked, a perturbation out of the linear range, or the wave's own set
    departed) and the drift of the set rho = 0 from the wave at each sampled period (the square root of the energy
    of its difference from the wave at phase 0, relative to the wave's)."""

    omega: float
    steps_per_period: int
    periods: int
    sets: list
    drift: np.ndarray
    wave_predicted: float
    ended: str


def residue_sets(tw) -> dict:
    """{rho: U (r, d)}: an orthonormal basis of the disk's coordinates in the nodal diameters d = +-rho mod g, g =
    gcd(k, N), for rho = 0 .. g // 2 (they sum to the disk's coordinates)."""
    g = math.gcd(abs(tw.k), tw.N)
    out = {}
    for rho in range(g // 2 + 1):
        indices = [m for m in range(tw.N) if m % g in (rho, (-rho) % g)]
        out[rho] = tw.space.harmonic(0, indices)
    if sum(U.shape[1] for U in out.values()) != tw.r:
        raise ValueError("the residue sets of nodal diameters do not span the disk's coordinates")
    return out


def _energy(U, M, K, q, v) -> float:
    """The energy of the part of (q, v) in span(U) (M, K leave it invariant)."""
    qs, vs = U @ (U.T @ q), U @ (U.T @ v)
    return 0.5 * float(vs @ (M @ vs) + qs @ (K @ qs))


def _low_modes(U, M, K, cap: float) -> tuple[np.ndarray, np.ndarray]:
    """(Phi (r, p), omega^2 (p,)): the modes of span(U) with frequencies below ``cap`` rad/s, M-normalised."""
    w2, Phi = scipy.linalg.eigh(U.T @ K @ U, U.T @ M @ U)
    keep = w2 < cap ** 2
    return U @ Phi[:, keep], w2[keep]


def wave_departure(tw, solution, periods: int = 100, steps_per_period: int = 64, size: float = 1e-6,
                   mode_cap: float = 2.0, linear_limit: float = 1e-2, drift_limit: float = 0.2, seed: int = 0,
                   rho_inf: float | None = 0.8, progress=None) -> WaveDeparture:
    """March the full disk from the one-sector wave ``solution`` (of ``tw``, a ``TravellingWaveBalance``) plus a
    perturbation in every residue set rho != 0, and compare each set's growth per period with Hill's largest
    multiplier of its classes (module docstring). ValueError for a wave with g = gcd(k, N) < 2 (no
    set but the wave's own), a bad count or size. ``progress(period, amplitudes)`` is called each period."""
    for name, value, ok, allowed in (
            ("periods", periods, isinstance(periods, int) and periods >= 8, "an integer >= 8"),
            ("steps_per_period", steps_per_period, isinstance(steps_per_period, int) and steps_per_period >= 16,
             "an integer >= 16"),
            ("size", size, 0 < size < linear_limit < 1, "in (0, linear_limit), linear_limit < 1"),
            ("mode_cap", mode_cap, mode_cap > 0, "> 0"), ("drift_limit", drift_limit, drift_limit > 0, "> 0")):
        if not ok:
            raise ValueError(f"{name} must be {allowed}, got {value!r}")
    sets = residue_sets(tw)
    if len(sets) < 2:
        raise ValueError(f"a wave of {tw.k} diameters on {tw.N} sectors fills every nodal diameter (gcd 1): no "
                         f"perturbation set apart from the wave")
    omega = float(solution.omega)
    g = math.gcd(abs(tw.k), tw.N)
    X = tw.coefficients(solution.X)
    q_wave, v_wave = time_state(X, omega)
    h_ = np.arange(1, tw.basis.H + 1)[:, None]
    a0 = -omega ** 2 * (h_ ** 2 * X[1::2]).sum(axis=0)                # the wave's acceleration at phase 0
    F = tw.coefficients(tw.F)
    M, C, K = tw.M, tw.C, tw.K
    e_wave = 0.5 * float(v_wave @ (M @ v_wave) + q_wave @ (K @ q_wave))

    # the predicted multipliers: Hill's classes of each set
    exps = tw.class_exponents(solution.X, omega)
    rng = np.random.default_rng(seed)
    q0 = q_wave.copy()
    rows = []
    for rho, U in sets.items():
        classes = tuple(j for j in tw.classes if j % g in (rho, (-rho) % g))
        growth = max(float(exps[j].real.max()) for j in classes if exps[j].size)
        diameters = tuple(d for d in range(tw.N // 2 + 1) if d % g in (rho, (-rho) % g))
        rows.append([rho, diameters, classes, math.exp(growth * 2 * np.pi / omega)])
        if rho == 0:
            continue
        Phi, w2 = _low_modes(U, M, K, mode_cap * omega)
        if Phi.shape[1] == 0:
            raise ValueError(f"no mode of the diameters {diameters} below {mode_cap} x the wave's frequency")
        c = rng.standard_normal(Phi.shape[1])
        c *= size * math.sqrt(2 * e_wave / float(c @ (w2 * c)))      # its energy: size^2 of the wave's
        q0 += Phi @ c
        a0 -= Phi @ (w2 * c)                                          # its acceleration at rest: -omega_i^2

    def load(t):
        return time_state(F, omega, omega * t)[0]

    stepper = dense_newmark(M, C, K, load, tw.model.forces, rho_inf=rho_inf)
    T = 2 * np.pi / omega
    h = T / steps_per_period
    q, v, a = q0, v_wave.copy(), a0
    U0 = sets[0]
    amps = [[math.sqrt(_energy(sets[rho], M, K, q, v) / e_wave)] for rho, *_ in rows[1:]]
    drift = [0.0]
    n, ended = 0, f"{periods} periods"
    for n in range(1, periods + 1):
        for i in range(steps_per_period):
            q, v, a, _, _ = stepper.step(q, v, a, (n - 1) * T + (i + 1) * h, h)
        for row, amp in zip(rows[1:], amps):
            amp.append(math.sqrt(_energy(sets[row[0]], M, K, q, v) / e_wave))
        drift.append(math.sqrt(_energy(U0, M, K, q - q_wave, v - v_wave) / e_wave))
        if progress is not None:
            progress(n, [amp[-1] for amp in amps])
        if not np.all(np.isfinite(q)):
            ended = f"not finite at period {n}"
            break
        if max(amp[-1] for amp in amps) > linear_limit:
            ended = f"a perturbation past {linear_limit:g} of the wave at period {n}"
            break
        if drift[-1] > drift_limit:
            ended = f"the wave's own set {drift[-1]:.2g} from the wave at period {n}"
            break
    out = []
    for (rho, diameters, classes, predicted), amp in zip(rows[1:], amps):
        amp = np.asarray(amp)
        lo = len(amp) // 2
        measured = None
        if len(amp) - lo >= 4 and np.all(amp[lo:] > 0):
            slope = np.polyfit(np.arange(lo, len(amp)), np.log(amp[lo:]), 1)[0]
            measured = float(math.exp(slope))
        out.append(SetDeparture(rho, diameters, classes, predicted, amp, measured))
    return WaveDeparture(omega, steps_per_period, n, out, np.asarray(drift), rows[0][3], ended)
