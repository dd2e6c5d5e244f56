"""Is a run's response steady? The map's quantity revolution by revolution (issue #86).

A map reads max |u| over a run's last revolution once the transients have died. A run asked for a steady state is
steady when that quantity changes by less than ``tolerance`` (2 %) from one revolution to the next over the last
``window`` revolutions; otherwise it ends at its revolution limit marked "not steady", with the per-revolution maxima
and a Poincaré section (the response sampled once a revolution at the same casing phase) that tell a transient still
decaying (the section creeps to a point) from a response that never settles: a period-2 response alternates between
two values, a quasi-periodic one fills a closed curve, a chaotic one a cloud.
"""
from __future__ import annotations

import dataclasses

import numpy as np

__all__ = ["Steadiness", "steadiness", "revolution_maxima", "poincare_section", "harmonic_fractions"]


def _check_history(t, u, omega):
    t, u = np.asarray(t, float), np.asarray(u, float)
    if t.ndim != 1 or u.shape != t.shape or t.size < 2:
        raise ValueError(f"t and u must be 1-D of one length >= 2, got {t.shape} and {u.shape}")
    if not (np.all(np.isfinite(t)) and np.all(np.diff(t) > 0)):
        raise ValueError("t must be finite and increasing")
    if not (isinstance(omega, (int, float, np.floating)) and np.isfinite(omega) and omega > 0):
        raise ValueError(f"omega must be an angular speed > 0 rad/s, got {omega!r}")
    return t, u


def revolution_maxima(t, u, omega: float) -> np.ndarray:
    """max |u| over each whole revolution of the run (revolution k: k T <= t <= (k + 1) T, T = 2 pi / omega; a
    partial last revolution is left out). A run that ends at most one sample spacing before a revolution's end (its
    step count rounded down) lacks only that revolution's last sample, which is the next one's first: it counts. A non-finite sample
    makes its revolution's maximum NaN."""
    t, u = _check_history(t, u, omega)
    T = 2.0 * np.pi / omega
    span = t[-1] - t[0]
    n = int(np.floor(span / T + 1e-9))
    if t.size > 1 and (n + 1) * T - span <= (t[-1] - t[-2]) * (1 + 1e-9):
        n += 1
    out = np.full(n, np.nan)
    for k in range(n):
        sel = (t >= t[0] + k * T - 1e-12 * T) & (t <= t[0] + (k + 1) * T + 1e-12 * T)
        out[k] = np.abs(u[sel]).max() if np.all(np.isfinite(u[sel])) else np.nan
    return out


def poincare_section(t, u, omega: float, phase: float = 0.0) -> np.ndarray:
    """u sampled once a revolution at t = t_0 + (k + phase) T (linear interpolation between samples), k = 0, 1, ...
    while inside the run; ``phase`` in [0, 1)."""
    t, u = _check_history(t, u, omega)
    if not (np.isfinite(phase) and 0.0 <= phase < 1.0):
        raise ValueError(f"phase must be in [0, 1), got {phase!r}")
    T = 2.0 * np.pi / omega
    times = t[0] + (np.arange(int(np.floor((t[-1] - t[0]) / T - phase + 1e-9)) + 1) + phase) * T
    times = times[times <= t[-1]]
    return np.interp(times, t, u)


@dataclasses.dataclass(frozen=True)
class Steadiness:
    """The verdict on a run's map quantity.

    Attributes: maxima (per whole revolution, m); changes: |m_k - m_k-1| / m_k-1 (one fewer); steady: the last
    ``window`` changes are all below the tolerance; revolution: the first whole revolution from which that held to
    the end (1-based), or None; value: the last revolution's max |u| (NaN where the run has none or diverged);
    reason: one line, what the verdict rests on."""

    maxima: np.ndarray
    changes: np.ndarray
    steady: bool
    revolution: int | None
    value: float
    tolerance: float
    reason: str


def steadiness(t, u, omega: float, tolerance: float = 0.02, window: int = 2) -> Steadiness:
    """The map quantity of a run (max |u| over a revolution) and whether it is steady: changing by less than
    ``tolerance`` a revolution over the last ``window`` revolutions (so at least window + 1 whole revolutions)."""
    if not (np.isfinite(tolerance) and 0.0 < tolerance < 1.0):
        raise ValueError(f"tolerance must be in (0, 1), got {tolerance!r}")
    if not (isinstance(window, (int, np.integer)) and window >= 1):
        raise ValueError(f"window must be an integer >= 1, got {window!r}")
    maxima = revolution_maxima(t, u, omega)
    changes = np.abs(np.diff(maxima)) / maxima[:-1] if maxima.size > 1 else np.zeros(0)
    value = float(maxima[-1]) if maxima.size else float("nan")
    if maxima.size < window + 1:
        return Steadiness(maxima, changes, False, None, value, tolerance,
                          f"not steady: {maxima.size} whole revolutions, {window + 1} needed to tell")
    if not np.all(np.isfinite(maxima)):
        return Steadiness(maxima, changes, False, None, float("nan"), tolerance, "not steady: the run diverged")
    below = changes < tolerance
    if not below[-window:].all():
        return Steadiness(maxima, changes, False, None, value, tolerance,
                          f"not steady by revolution {maxima.size}: the last changes "
                          + ", ".join(f"{c:.1%}" for c in changes[-window:]) + f" (tolerance {tolerance:.0%})")
    first = below.size - int(np.argmin(below[::-1])) if not below.all() else 0   # start of the final run of Trues
    revolution = first + 1                    # change k compares revolutions k and k + 1 (0-based)
    return Steadiness(maxima, changes, True, revolution, value, tolerance,
                      f"steady from revolution {revolution}: the last {window} changes "
                      + ", ".join(f"{c:.2%}" for c in changes[-window:]) + f" < {tolerance:.0%}")


def harmonic_fractions(t, u, omega: float, revolutions: int = 10, per_revolution: int = 512,
                       subharmonics: tuple = (1, 2)) -> dict:
    """How much of the motion over the last ``revolutions`` (its mean removed) repeats every 1, 2, ... revolutions:
    {s: the fraction of the power at multiples of f_rev / s}, f_rev = omega / 2 pi, from the Hann-windowed spectrum
    of u resampled at ``per_revolution`` points a revolution (whole revolutions, so a periodic response's harmonics
    fall on bins; the window spreads each over +-1 bin, which are counted). A periodic response has fraction 1
    at s = 1 (to the resampling's error); a period-2 one 1 at s = 2 and less at s = 1; a quasi-periodic or chaotic one
    less than 1 at every s (its frequencies not locked to the rotation: the sidebands of the spectrum)."""
    t, u = _check_history(t, u, omega)
    T = 2.0 * np.pi / omega
    if not (isinstance(revolutions, (int, np.integer)) and 1 <= revolutions <= (t[-1] - t[0]) / T + 1e-9):
        raise ValueError(f"revolutions must be an integer in [1, the run's {int((t[-1] - t[0]) / T + 1e-9)}], "
                         f"got {revolutions!r}")
    if not np.all(np.isfinite(u)):
        raise ValueError("u must be finite over the run (a diverged run has no spectrum)")
    grid = t[-1] - revolutions * T + np.arange(revolutions * per_revolution) * T / per_revolution
    y = np.interp(grid, t, u)
    y = (y - y.mean()) * np.hanning(y.size)
    power = np.abs(np.fft.rfft(y)) ** 2
    bins = np.arange(power.size)
    total = power[1:].sum()
    out = {}
    for sub in subharmonics:
        step = revolutions / sub                       # bins between multiples of f_rev / sub
        near = np.abs(bins - step * np.round(bins / step)) <= 1.0
        out[int(sub)] = float(power[1:][near[1:]].sum() / total) if total > 0 else 1.0
    return out
