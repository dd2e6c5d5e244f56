"""Convergence of the contact response against a reference run: the NFRC of a sweep (max |u_LE| over the last
revolution at each speed) and its error per speed, for the studies of time step, frequency cap, model size and
cubature (``benchmarks/bench_contact_convergence.py``, ``bench_contact_rom_size.py``, ``bench_contact_ecsw.py``).

Pure NumPy (the integrator and the sweep are imported where a run is made).
"""
from __future__ import annotations

import numpy as np


def nfrc_run(model, gnl, speeds, casing, revolutions, safety, cap, h=None, states=0):
    """NFRC at each speed; with ``states`` > 0 also the that many largest-amplitude reduced states of the run (the
    GNL tangent stability limit is evaluated on them)."""
    from rotor37_rom.dynamics.explicit import CentralDifference, largest_states, simulate
    from rotor37_rom.post.signals import last_revolution_max

    scheme = CentralDifference(model, nonlinear=gnl, safety=safety, frequency_cap=cap, h=h)
    rec = max(1, int(round(1e-5 / scheme.h)))
    res = simulate(scheme, speeds, casing, revolutions=revolutions, on_blowup="flag", record_every=rec,
                   record_q=states > 0)
    amp = [last_revolution_max(res.t[p], res.u_r[p][res.row("0:LE")], speeds[p]) if res.diverged_step[p] < 0
           else float("nan") for p in range(len(speeds))]
    out = {"cap_hz": None if cap is None else cap / 2 / np.pi, "h": scheme.h, "h_crit": scheme.h_crit,
           "wall_s": res.wall, "rev_per_s": revolutions * len(speeds) / res.wall, "nfrc": amp,
           "max_penetration": float(res.max_penetration.max()), "diverged": int((res.diverged_step >= 0).sum())}
    if states:
        out["states"] = largest_states(res, scheme.boundary_rows, states).T.tolist()
    return out


def speed_errors(run, ref) -> np.ndarray:
    """|NFRC - NFRC_ref| / max(NFRC_ref) at each speed; a diverged run (NaN) counts as infinitely wrong."""
    a, b = np.asarray(run["nfrc"], float), np.asarray(ref["nfrc"], float)
    err = np.abs(a - b) / np.nanmax(b)
    return np.where(np.isfinite(err), err, np.inf)


def compare(run, ref):
    """The speed errors of ``run`` against ``ref`` (``speed_errors``): median, 90th percentile and largest."""
    err = speed_errors(run, ref)
    return {"median": float(np.median(err)), "p90": float(np.quantile(err, 0.9, method="higher")),
            "max": float(err.max())}
