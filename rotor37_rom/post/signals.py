"""Signal analysis of a run's record (pure NumPy): the map's NFRC value (max |u| over the last revolutions), the
engine-order content of a response and its band RMS, steadiness and the response's period in half revolutions. What
``studies.sweep`` and the maps read from each speed's record of u(t)."""
from __future__ import annotations

from typing import Sequence

import numpy as np

__all__ = ["last_revolution_max", "engine_order_content", "band_rms", "is_steady", "response_period"]


def last_revolution_max(t: np.ndarray, u: np.ndarray, omega: float, revolutions: int = 1) -> float:
    """max |u| over the last ``revolutions`` revolutions (NFRC, Fig. 7)."""
    T = 2 * np.pi / omega
    sel = t >= t[-1] - revolutions * T + 1e-15
    return float(np.nanmax(np.abs(u[sel])))


def _last_revolutions(t: np.ndarray, u: np.ndarray, omega: float, revolutions: float) -> tuple[np.ndarray, float]:
    """(the samples of u's last ``revolutions`` revolutions, the sample interval) of a uniform record."""
    t, u = np.asarray(t, float).ravel(), np.asarray(u, float).ravel()
    if t.size < 2 or t.size != u.size or not t[-1] > t[0]:
        raise ValueError(f"need a record of increasing times t and as many samples u, got {t.size} times and "
                         f"{u.size} samples")
    dt = (t[-1] - t[0]) / (t.size - 1)
    n = int(round(revolutions * 2 * np.pi / omega / dt))
    if n < 4 or n > u.size:
        raise ValueError(f"the record spans {(t[-1] - t[0]) * omega / (2 * np.pi):.3g} revolutions at "
                         f"{t.size} samples; {revolutions:g} revolutions asked")
    return u[-n:], dt


def engine_order_content(t: np.ndarray, u: np.ndarray, omega: float, revolutions: float = 40.0,
                         max_order: int = 29, band: float = 0.004) -> tuple[float, float]:
    """(dominant frequency in rad/s, share of the power on engine-order lines) of u over its last ``revolutions``
    revolutions (uniform samples; the mean removed, no window, so a response locked to the rotor puts all its power
    on the lines k omega when the span is whole revolutions). The share is the power within ``band`` x k omega of
    k omega, k = 1 ... ``max_order`` (at least the nearest bin: half the bin spacing omega / ``revolutions`` either
    side), over the power of every bin but the mean. 1: a forced (engine-order) response; well below 1: a response
    the contact sustains at the structure's own frequencies (a critical-speed band of the disk). NaN, NaN for a
    non-finite or constant record."""
    if not omega > 0 or not revolutions > 0 or max_order < 1 or not band >= 0:
        raise ValueError(f"need omega > 0, revolutions > 0, max_order >= 1 and band >= 0; got {omega}, "
                         f"{revolutions}, {max_order}, {band}")
    seg, dt = _last_revolutions(t, u, omega, revolutions)
    n = seg.size
    if not np.all(np.isfinite(seg)):
        return float("nan"), float("nan")
    power = np.abs(np.fft.rfft(seg - seg.mean())) ** 2
    w = 2 * np.pi * np.fft.rfftfreq(n, dt)
    power, w = power[1:], w[1:]
    total = power.sum()
    if total == 0.0:
        return float("nan"), float("nan")
    lines = omega * np.arange(1, max_order + 1)
    width = np.maximum(band * lines, 0.5 * (w[1] - w[0]) if w.size > 1 else 0.0)
    on_line = (np.abs(w[:, None] - lines[None, :]) <= width[None, :] * (1 + 1e-12)).any(axis=1)
    return float(w[np.argmax(power)]), float(power[on_line].sum() / total)


def band_rms(t: np.ndarray, u: np.ndarray, omega: float, edges_hz: Sequence[float], revolutions: float = 1.0
             ) -> np.ndarray:
    """RMS of u (mean removed) over its last ``revolutions`` revolutions within each frequency band
    [edges_hz[i], edges_hz[i + 1]) (Hz; uniform samples), by Parseval on the one-sided spectrum: the squares of the
    bands add up to the variance when the edges span 0 to above the Nyquist frequency. Where a response's motion
    lies: the first modes, or ringing at a contact's local frequencies."""
    edges = np.asarray(edges_hz, float)
    if not omega > 0 or not revolutions > 0 or edges.size < 2 or np.isnan(edges).any() or \
            not np.all(np.diff(edges) > 0) or edges[0] < 0:
        raise ValueError(f"need omega > 0, revolutions > 0 and increasing edges_hz >= 0 (two at least); got {omega}, "
                         f"{revolutions}, {edges.tolist()}")
    seg, dt = _last_revolutions(t, u, omega, revolutions)
    n = seg.size
    seg = seg - seg.mean()
    power = np.abs(np.fft.rfft(seg)) ** 2 / n ** 2
    power[1:(n + 1) // 2] *= 2                        # the negative frequencies (not the Nyquist bin of an even n)
    f = np.fft.rfftfreq(n, dt)
    return np.array([np.sqrt(power[(f >= lo) & (f < hi)].sum()) for lo, hi in zip(edges[:-1], edges[1:])])


def is_steady(t: np.ndarray, u: np.ndarray, omega: float, tol: float = 0.02, window: int = 1) -> bool:
    """Steady when the max |u| over the last ``window`` revolutions and over the ``window`` before differ by less
    than ``tol``. One revolution (the default) recognises responses periodic with the rotor period T; a response of
    period up to ``window`` T counts as steady with that window (the paper's 11T/2 branch, §2.3.3: 6)."""
    if window < 1:
        raise ValueError(f"steadiness window must be >= 1 revolution, got {window}")
    span = window * 2 * np.pi / omega
    last = np.abs(u[t >= t[-1] - span])
    before = np.abs(u[(t >= t[-1] - 2 * span) & (t < t[-1] - span)])
    if last.size == 0 or before.size == 0:
        return False
    a, b = last.max(), before.max()
    return bool(abs(a - b) <= tol * max(a, b, 1e-12))


def response_period(t: np.ndarray, u: np.ndarray, omega: float, tol: float = 0.02, max_halves: int = 24) -> int:
    """The response's period in half revolutions: the smallest m <= ``max_halves`` such that u(t) and u(t - m T/2)
    differ by at most ``tol`` times max |u| over the last max(m T/2, T) of the record (T = 2 pi / omega; u
    interpolated linearly between samples). 0 when none does (not periodic with any period up to ``max_halves``
    T/2); -1 when the record is too short to test them all and none of those it can test fits (unknown: a longer
    record may find a longer period). A response locked to the rotor gives 2 (T) or 1 (T/2: the two-lobe casing's
    EO2 family); the paper's 11T/2 branch (§2.3.3) gives 11."""
    if max_halves < 1 or not tol > 0:
        raise ValueError(f"max_halves must be >= 1 and tol > 0, got {max_halves}, {tol}")
    half = np.pi / omega
    for m in range(1, max_halves + 1):
        shift = m * half
        window = t >= t[-1] - max(shift, 2 * half)
        if t[window][0] - shift < t[0]:
            return -1                                     # the record is too short for this period and above
        ref = np.abs(u[window]).max()
        if ref == 0.0:
            return 1
        lagged = np.interp(t[window] - shift, t, u)
        if np.abs(u[window] - lagged).max() <= tol * ref:
            return m
    return 0
