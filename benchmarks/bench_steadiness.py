"""How often a map's responses pass the continuation's steady-state test, by window length.

The sequential continuation (§2.3.3, ``studies.sweep.continuation``) halves its speed step when a run is not steady. The
paper's test compares the largest response of the last two revolutions; contact responses that repeat over several
revolutions (the paper's 11T/2 branch) or never exactly (quasi-periodic) fail it at every step. This reads the
LE records of a finished map (each speed from rest, the map's full length) and counts, for each window of N
revolutions, the speeds whose max |u| over the last N revolutions and the N before agree to ``--tol``. Nothing is
rerun; the table says which window a continuation of that model needs.

    python benchmarks/bench_steadiness.py results/headline_r55_h6/sweeps/*
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from rotor37_rom.machine import write_results


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("folders", nargs="+", help="sweep folders of one map (<out>/sweeps/<key>)")
    parser.add_argument("--windows", type=int, nargs="+", default=[1, 2, 3, 6, 10, 20])
    parser.add_argument("--tol", type=float, default=0.02)
    parser.add_argument("--band", type=float, nargs=2, default=None, metavar=("LOW", "HIGH"),
                        help="also list the verdicts of the speeds in this band (rad/s)")
    parser.add_argument("--name", default="bench_steadiness")
    args = parser.parse_args(argv)
    from rotor37_rom.post.signals import is_steady
    from rotor37_rom.studies.sweep import LE, load_sweep, record_row

    bad = [f for f in args.folders if not Path(f).is_dir()]
    if bad or min(args.windows) < 1 or not 0 < args.tol < 1:
        print(f"error: need sweep folders (missing: {bad}), windows >= 1 and 0 < tol < 1", file=sys.stderr)
        return 2
    runs = {}
    for folder in args.folders:                         # later folders (retries) replace earlier verdicts
        for rec in load_sweep(folder):
            if int(np.asarray(rec["diverged_step"]).ravel()[0]) < 0:
                runs[float(rec["omega"])] = rec
    speeds = sorted(runs)
    verdict = {w: [is_steady(runs[om]["t"], runs[om]["u_r"][record_row(runs[om], LE)], om, args.tol, w) for om in speeds]
               for w in args.windows}
    rows = [{"window": w, "steady": int(sum(v)), "of": len(v)} for w, v in verdict.items()]
    print(f"{len(speeds)} finished speeds, tol {args.tol:g}")
    for row in rows:
        print(f"  window {row['window']:3d} rev: steady at {row['steady']:3d} of {row['of']}")
    band = {}
    if args.band:
        for k, om in enumerate(speeds):
            if args.band[0] <= om <= args.band[1]:
                band[f"{om:.1f}"] = "".join("s" if verdict[w][k] else "." for w in args.windows)
        print("  by speed (s = steady, one character per window):", " ".join(f"{k}:{v}" for k, v in band.items()))
    write_results(args.name, rows, folders=args.folders, tol=args.tol, band=band)
    return 0


if __name__ == "__main__":
    sys.exit(main())
