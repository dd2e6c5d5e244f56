"""What each speed of a disk contact map is: its amplitudes, its dominant frequency and how much of its power the
casing forces (engine-order lines), next to the disk's critical speeds (paper §3.4; docs/results.md, the disk maps).

Reads a finished (or partly finished) sweep folder of ``demos/contact_map.py --disk`` (``<out>/sweeps/<key>``); per
speed: node LE of sector 0 and the largest over the blades (max over the last revolution), the dominant frequency of
node LE of sector 0 over the last ``--revolutions`` revolutions and the share of its power within 0.4 % of k Omega
(k = 1..29; ``post.signals.engine_order_content``), and where that frequency is an engine order n Omega, the nodal
diameters of the wave that carries it over the 36 blades (k, and its share of that order's power). With ``--model``
(the map's rom.npz) also the share of that window in contact (a positive normal multiplier on any tip node of
sector 0, and the mean over the sectors), the critical speeds omega_{f,k} / k of the model's lowest families inside
the map's range, where a wave of k nodal diameters stands still under the stationary casing, and the 1B/EO4 point
omega_{1,4} / 4.

    python benchmarks/disk_map_spectra.py results/disk_map200/sweeps/<key> --model results/disk_map200/rom.npz

Results: results/disk_map_spectra_<key>.json (or --name). No computation beyond the FFTs: a 90-speed map reads in a
few minutes (the records' time and displacement histories only).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from rotor37_rom.machine import write_results
from rotor37_rom.post.signals import engine_order_content
from rotor37_rom.studies.sweep import (engine_order_resonance, interaction_map, load_sweep, record_row, sector_maxima,
    sector_rows)


def critical_speeds(model, lo: float, hi: float, families: int = 3) -> tuple[float, list[dict]]:
    """The model's 1B/EO4 point omega_{1,4} / 4 and its critical speeds omega_{f,k} / k in [lo, hi] (rad/s)."""
    from rotor37_rom.disk.harmonics import harmonic_frequencies

    freqs = harmonic_frequencies(model, families)
    found = [{"family": f + 1, "k": k, "frequency": float(freqs[k, f]), "speed": float(freqs[k, f] / k)}
             for k in range(1, freqs.shape[0]) for f in range(families)
             if np.isfinite(freqs[k, f]) and lo <= freqs[k, f] / k <= hi]
    return float(freqs[4, 0] / 4), sorted(found, key=lambda c: c["speed"])


def engine_order_wave(record, order: int, revolutions: float) -> tuple[int, float]:
    """(nodal diameters k, its share) of engine order ``order`` over the blades: each blade's node LE coefficient of
    e^{i order Omega t} over the last ``revolutions``, transformed over the sector index (a tuned disk under a fixed
    casing answers EO n with the wave of k = n mod N nodal diameters); k in 0..N/2 (the direction folded), the share
    that wave's power, both directions, over all of them. Needs node LE of every sector 0..N-1 recorded."""
    omega = float(record["omega"])
    t = np.asarray(record["t"])
    sel = t >= t[-1] - revolutions * 2 * np.pi / omega
    rows = sector_rows(record, "LE", every=True)
    phasor = np.exp(-1j * order * omega * t[sel])
    coeff = np.array([np.mean(np.asarray(record["u_r"][i])[sel] * phasor) for i in rows])
    power = np.abs(np.fft.fft(coeff)) ** 2
    n = len(rows)
    index = int(np.argmax(power))
    k = min(index, n - index)
    wave = power[k] + (power[n - k] if 0 < k < n - k else 0.0)      # a standing wave is +k and -k
    return k, float(wave / power.sum())


def contact_share(record, sectors: np.ndarray, revolutions: float) -> tuple[float, float]:
    """(sector 0's, the mean over the sectors') share of the recorded samples (at the record's interval, not every
    step) in the last ``revolutions`` with a positive normal multiplier on any of the sector's contact nodes;
    ``sectors`` (n_nodes,) is the model's node map sector of each multiplier row."""
    t = np.asarray(record["t"])
    lam = record.read("lam") if hasattr(record, "read") else np.asarray(record["lam"])   # not kept: 196 MB each
    if lam.shape[0] != sectors.size:
        raise ValueError(f"the record has {lam.shape[0]} multiplier rows, the model {sectors.size} contact nodes")
    sel = t >= t[-1] - revolutions * 2 * np.pi / float(record["omega"])
    touching = lam[:, sel] > 0
    share = np.array([touching[sectors == s].any(axis=0).mean() for s in range(int(sectors.max()) + 1)])
    return float(share[0]), float(share.mean())


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", type=Path, help="a disk map's sweep folder (<out>/sweeps/<key>)")
    parser.add_argument("--model", type=Path, help="the map's reduced model (rom.npz): critical speeds")
    parser.add_argument("--revolutions", type=float, default=40.0, help="spectral window (default the last 40)")
    parser.add_argument("--name", help="results/disk_map_spectra_<name>.json (default: the folder's key)")
    args = parser.parse_args(argv)
    if not args.folder.is_dir():
        print(f"error: folder {args.folder} is not a sweep folder (a directory of omega_*.npz)", file=sys.stderr)
        return 2
    if not 1 <= args.revolutions <= 200:
        print(f"error: --revolutions must be in [1, 200], got {args.revolutions:g}", file=sys.stderr)
        return 2
    records = load_sweep(args.folder)
    if not records:
        print(f"error: folder {args.folder} holds no finished speed", file=sys.stderr)
        return 2
    model = None
    if args.model is not None:
        from rotor37_rom.model.reduced import load_reduced_model

        model = load_reduced_model(args.model)
    rows = []
    print(f"{'rad/s':>8} {'LE0 mm':>7} {'max mm':>7} {'blade':>5} {'dominant':>9} {'/Omega':>7} {'EO share':>8}"
          f" {'k':>4} {'share':>5}" + (f" {'contact 0':>9} {'contact':>7}" if model is not None else ""))
    for rec in records:
        omega = float(rec["omega"])
        per_blade = sector_maxima(rec)
        row = {"omega": omega, "diverged": int(rec["diverged_step"]) >= 0}
        if not row["diverged"]:
            u = rec["u_r"][record_row(rec, "0:LE")]
            try:
                dominant, share = engine_order_content(rec["t"], u, omega, args.revolutions)
            except ValueError as exc:                                   # a window longer than the record
                print(f"error: --revolutions at {omega:g} rad/s: {exc}", file=sys.stderr)
                return 2
            row.update(le0_m=float(per_blade[0]), largest_m=float(per_blade.max()),
                       largest_blade=int(np.argmax(per_blade)), dominant=dominant, eo_share=share)
            order = int(round(dominant / omega))
            line = (f"{omega:8.1f} {1e3 * per_blade[0]:7.3f} {1e3 * per_blade.max():7.3f} {np.argmax(per_blade):5d} "
                    f"{dominant:9.0f} {dominant / omega:7.2f} {share:8.2f}")
            # on an engine-order line (engine_order_content's band: 0.4 %, at least half a bin): which wave
            band = max(0.004 * order * omega, omega / (2 * args.revolutions))
            try:
                if order < 1 or abs(dominant - order * omega) > band:
                    raise ValueError("not on an engine-order line")
                row["wave_k"], row["wave_share"] = engine_order_wave(rec, order, args.revolutions)
                line += f" {row['wave_k']:4d} {row['wave_share']:5.2f}"
            except ValueError:                                          # off the lines, or not every blade recorded
                line += f" {'-':>4} {'-':>5}"
            if model is not None:
                try:
                    row["contact_share_0"], row["contact_share_mean"] = contact_share(rec, model.nodes.sector,
                                                                                      args.revolutions)
                except ValueError as exc:                               # the model is not the map's
                    print(f"error: --model {args.model}: {exc}", file=sys.stderr)
                    return 2
                line += f" {row['contact_share_0']:9.2f} {row['contact_share_mean']:7.2f}"
            print(line)
        else:
            print(f"{omega:8.1f} diverged at step {int(rec['diverged_step'])}")
        rows.append(row)
    extra = {"folder": str(args.folder), "window_revolutions": args.revolutions}
    # the 1B/EO4 resonance as the single blade's maps define it (the largest EO4-dominated response, sweep.py)
    imap = interaction_map(records)
    revolutions = float(records[0]["revolutions"])
    extra["eo_resonances"] = {k: engine_order_resonance(imap, k, revolutions) for k in (4, 5, 6)}
    print("largest response dominated by engine order 4 / 5 / 6 at "
          + " / ".join(f"{w:.1f}" for w in extra["eo_resonances"].values()) + " rad/s")
    if model is not None:
        speeds = [r["omega"] for r in rows]
        eo4, found = critical_speeds(model, min(speeds), max(speeds))
        extra.update(one_b_eo4_point=eo4, critical_speeds=found)
        print(f"1B/EO4 point omega_(1,4) / 4 = {eo4:.1f} rad/s; critical speeds in the range: "
              + "; ".join(f"family {c['family']} k = {c['k']}: {c['speed']:.1f}" for c in found))
    name = f"disk_map_spectra_{args.name or args.folder.name}"
    machine = write_results(name, rows, **extra)
    print(f"results/{name}.json ({machine})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
