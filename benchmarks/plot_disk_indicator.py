"""Charts of the bladed disk's forced response without contact (paper Figs. 17, 18, 20-22 analogues) from the rows
``bench_disk_forced.py`` wrote: the performance indicator I against r_MD, and the error histories behind it.

Reads every results/disk_forced_<preset>*.json (a row measured twice keeps the newest file's), and draws
- <out>/disk_indicator_rmd.png: left, the linear response to the point load per load (N_d, omega) against r_MD
  (MI 2b); right, the GNL response to the 3 mm patch load (N_d = 0, 4,000 rad/s) against r_MD for MI 2b with eq. 61's
  force and with the faces in the force, the other criteria at their r_MD, the paper's I as levels;
- <out>/disk_error_histories.png: the four criteria over time for the GNL patch rows that kept their histories.

    python benchmarks/plot_disk_indicator.py [--preset ci] [--out docs/img] [--results results] [--name SUFFIX]

``--name SUFFIX`` reads only the files of ``bench_disk_forced.py --name SUFFIX...``
(results/disk_forced_<preset><SUFFIX>*.json); ``--results DIR`` reads them from DIR instead of results.

Every option is checked, and the folders read and written in, before any work: a bad one is one line on stderr and
exit status 2. ``--check`` does only that (exit status 0).
"""
from __future__ import annotations

import json
import re
import sys
from pathlib import Path
from typing import Sequence

from rotor37_rom.checks import before_work
from rotor37_rom.cli import ArgumentParser, run_main

RESULTS = Path("results")
PAPER = {"MMI": 0.93, "MI 2a": 0.96, "MI 2b": 0.97, "SMVW": 0.91}       # §3.3.1, N_d = 0, 4,000 rad/s


def rows_by_key(preset: str, results: Path = RESULTS, name: str = "") -> dict:
    """{row key: row} over the result files results/disk_forced_<preset><name>*.json, newer files winning."""
    files = sorted(results.glob(f"disk_forced_{preset}{name}*.json"), key=lambda p: p.stat().st_mtime)
    out = {}
    for f in files:
        try:
            rows = json.loads(f.read_text())["rows"]
        except (OSError, ValueError, KeyError, TypeError) as exc:
            raise ValueError(f"--results: {f} is not a results file of bench_disk_forced.py ({type(exc).__name__})"
                             ) from None
        for row in rows:
            if "I" not in row:                    # a failed run (the criterion's failure), no indicator
                continue
            key = (row["criterion"], row["r_md"], row["N_d"], row["omega"], row["gnl"], row.get("patch_mm", 0.0),
                   row.get("load_correction", False), row.get("face_shapes", 0), row.get("interface", "closest"),
                   row.get("ramp_periods", 1.0))
            out[key] = row
    return out


def build_parser() -> ArgumentParser:
    p = ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--preset", default="ci", choices=["ci", "coarse", "paper"],
                   help="the preset of bench_disk_forced.py's rows (default ci)")
    p.add_argument("--out", type=Path, default=Path("docs/img"), help="folder of the charts (default docs/img)")
    p.add_argument("--results", type=Path, default=None,
                   help=f"an existing folder the rows are read from (default {RESULTS}: where bench_disk_forced.py "
                        f"writes them)")
    p.add_argument("--name", default="",
                   help="only the files of bench_disk_forced.py --name SUFFIX (disk_forced_<preset><NAME>*.json): "
                        "letters, digits, '_', '-' or '.' (default: every file of the preset)")
    return p


def main(argv: Sequence[str] | None = None) -> int:
    """Check the options, then read the rows and draw the charts; raises ValueError for a bad input."""
    args = build_parser().parse_args(argv)
    if not re.fullmatch(r"[\w.-]*", args.name):
        raise ValueError(f"--name must be letters, digits, '_', '-' or '.' (a file name's suffix), got {args.name!r}")
    if args.results is not None and not args.results.is_dir():
        raise ValueError(f"--results {args.results} is not a folder (where bench_disk_forced.py's rows are)")
    results = RESULTS if args.results is None else args.results
    before_work({"--out": args.out})                  # before any work; a dry run stops here
    rows = rows_by_key(args.preset, results, args.name)
    if not rows:
        raise ValueError(f"no {results}/disk_forced_{args.preset}{args.name}*.json rows (run "
                         f"benchmarks/bench_disk_forced.py first)")
    from rotor37_rom.viz.charts import plot_disk_indicator, plot_error_histories

    linear, gnl, histories = {}, {}, {}
    for key, row in rows.items():
        criterion, r_md, nd, omega, is_gnl, patch, corr, faces, interface, ramp = key
        if interface != "closest" or ramp != 1.0:
            continue
        if not is_gnl and not patch and criterion == "MI2b":
            linear.setdefault(f"N_d = {nd}, {omega:g} rad/s", []).append((r_md, row["I"]))
        elif is_gnl and patch == 3.0 and corr and nd == 0 and omega == 4000.0:
            if r_md == 0:
                label = "no modal derivatives"
            elif criterion == "MI2b":
                label = f"MI 2b, faces in the force ({faces} shapes)" if faces else "MI 2b, eq. 61"
            else:
                label = criterion.replace("MI2", "MI 2") + (f", {faces} face shapes" if faces else ", eq. 61")
                if row["I"] == 0.0:
                    label += " (leaves the reference: I = 0)"
            gnl.setdefault(label, []).append((r_md, row["I"]))
            if "histories" in row and r_md:
                histories[f"{label}, r_MD = {r_md}"] = row["histories"]
    if "no modal derivatives" in gnl:                 # the r_MD = 0 point starts the MI 2b curves
        for label in [k for k in gnl if k.startswith("MI 2b")]:
            gnl[label] = gnl[label] + gnl["no modal derivatives"][:1]
    panels = {"linear, point load (MI 2b)": linear,
              "GNL, 3 mm patch, N_d = 0, 4,000 rad/s (with the load correction)": gnl}
    out = Path(args.out)
    written = [plot_disk_indicator(panels, out / "disk_indicator_rmd.png", paper=PAPER)]
    if histories:
        written.append(plot_error_histories(histories, out / "disk_error_histories.png",
                                            title="GNL, 3 mm patch, N_d = 0, 4,000 rad/s: the indicator's criteria"))
    print("wrote " + ", ".join(str(p) for p in written))
    return 0


if __name__ == "__main__":
    sys.exit(run_main(main))
