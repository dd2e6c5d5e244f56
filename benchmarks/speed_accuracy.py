"""Speed against accuracy: per scene, the cost and the error of every candidate model, one study (issue #22).

    python benchmarks/speed_accuracy.py                       # all scenes (52 min from scratch on the 2-core machine)
    python benchmarks/speed_accuracy.py --scene modes clearance map-linear
    python benchmarks/speed_accuracy.py --scene disk                # the bladed disk's scenes
    python benchmarks/speed_accuracy.py --scene gnl-steady          # read from bench_gnl_steady's full-order runs
    make speed-accuracy                                       # the same as the first line

Scenes (the report's settings):
- ``modes``: the clamped 1B/1T/2B frequencies against mesh presets ci / coarse / paper; reference: the paper preset
  (the presets are remeshed, not nested: no Richardson limit), whose own error is taken as its change from coarse;
  held out: modes 4-6.
- ``clearance``: the clearance consumption of 1B at zeta = 1 mm and 1T at 0.5 mm, delta in [-1, 1] (§2.3.2), reduced
  models against the full-order nonlinear statics; candidates: r_c x modal derivatives (none / 10 constraint-mode
  pairs by MI 2b or at random / the 6 of 1B-1T-2B / those + 10 by MI 2b), and the full-order linear model; held
  out: both modes at 1.5 times the amplitude.
- ``rotating-modes``: the turning ci blade (#73): its reduced model's frequencies of modes 1-3 and its tip's
  centrifugal displacement against the full order at 1,200-1,600 rad/s by 100; candidates: r_c 15 with the 6 global
  modal derivatives and the full-order centrifugal states at 1,000 and/or 2,000 rad/s, with 0, 2 or 4 modes of the
  blade turning at 2,000 rad/s in the basis; held out: the other speeds of 0-2,000 rad/s by 100.
- ``map-linear`` / ``map-gnl``: the interaction map's NFRC at node LE, 11 speeds in 1,200-1,600 rad/s x 8
  revolutions from rest, mu = 0, normal e_x (what ``make demo`` runs), GNL off / on; error: the largest of the NFRC
  error on the speeds robust to a 1e-4 force perturbation (relative to the reference's peak), the resonance speed's
  and the peak amplitude's relative errors; candidates: r_c, frequency cap, step, force evaluation (exact tensors,
  point cubature, float32); held out: 10 other speeds (a cubature as trained on the study's speeds).
- ``history-linear`` / ``history-gnl``: the LE time history of the same runs at the robust speed of largest response:
  max |u - u_ref| / max |u_ref| over the run.
- the stability map: the stable step 2 / omega_max of the tangent against the LE amplitude, with and without a cap.
- ``paper-speedup``: the GNL map model chosen at 5 % (else 20 %) against the paper's r = 189 exact tensors at 1e-7 s.
- ``disk-modes`` (bladed disk, not in ``all``): the 1B, 1T and 2B families of the 36-sector disk at every nodal
  diameter against the sector's full-order cyclic modes; candidates: r_c x r_cyclic (8 tip nodes per sector, as the
  contact maps), with and without modal derivatives; cost: the linear contact run per simulated ms at the maps'
  60 kHz cap; held out: the 4th-6th modes of every nodal diameter.
- ``disk-map-linear`` (bladed disk, not in ``all``): the disk's short map without GNL, 8 speeds in 1,200-1,650 rad/s
  x 20 revolutions from rest on the disk maps' casing (cone normal, mu = 0.15); error on the robust speeds: the NFRC
  of node LE of sector 0 and of the largest blade, and the speed and amplitude of the largest response; reference:
  r_c 10, r_MD 10, r_cyclic 288 at a 240 kHz cap; candidates: r_c, r_MD, r_cyclic, frequency cap (the reference's
  model at 120 kHz measures its cap's own error); held out: 7 other speeds. With it, ``disk-stress-linear``: the von
  Mises stress in the disk at t_max of one revolution carried on from each of its maps at the reference's largest
  robust response, off the root corner, in sector 0 and over the sectors.
- ``disk-map-gnl`` (bladed disk, not in ``all``): the same map with GNL over 12 revolutions; reference: r_c 10,
  r_MD 10, r_cyclic 288 with the exact sector tensors at a 120 kHz cap (the GNL step's probe sets the step); the
  1e-4 perturbation is the map's own option (the internal force scaled, the same probe and step); candidates:
  the maps' model (r_cyclic 144) at 60 kHz with exact tensors and with point cubature at 1e-2 / 3e-3 / 1e-3 in
  float32 (the full-disk GNL map's model is 3e-3), no modal derivatives, the reference's basis at 60 kHz; held out:
  the 7 other speeds, a cubature as trained on the study's speeds. With it, ``disk-stress-gnl``: the stress at t_max
  with GNL, as ``disk-stress-linear`` (a cubature candidate carried on with its map's own cubature).
- ``disk-forced-linear`` / ``disk-forced-gnl`` (bladed disk, not in ``all``): the forced response without contact
  (§3.3, ``bench_disk_forced.py``'s runs): 400 N along e_z at node LE of every sector travelling with N_d diameters,
  ramped over one period, 10 periods from rest, implicit Newmark at T/100 for the full order (one repeat of sectors
  closed on themselves) and the reduced models alike; error: the largest of the performance indicator's four relative
  errors (loaded node, tip nodes, M- and K-norm of the sector fields) over the cases; cost: the reduced runs' wall
  time. GNL off: N_d 0 and 9 at 4,000 and 13,000 rad/s, candidates r_c x r_cyclic and 10 modal derivatives in the
  basis (node LE kept, r_b = 3), held out: 17,000 rad/s. GNL on: the 400 N over a 3 mm patch (the point load
  collapses the full order), N_d 0 at 4,000 rad/s, candidates r_MD by MI 2b with eq. 61's force or the faces' 6
  shapes in it, the patch's static correction in every basis; held out: 13,000 rad/s.
- ``cost-r``: the cost per simulation-step against r for each force method (no GNL, exact tensors, point cubature on
  all points and on 10 points per mode, float64 / float32), synthetic models of each size, and the trained cubatures.

Writes ``rotor37_rom/data/speed_accuracy.json`` (versioned: ``choose_model`` reads it) and the charts
``docs/img/speed_accuracy_<scene>.png``; work files under ``results/speed_accuracy/``. Scenes not run keep their
previous entries. Every figure of docs/choosing-a-model.md comes from that file. The disk scenes record a floor
(``floor_record``: what the reference's own cap is worth, and for a stress how far the reference's
1e-4 perturbation moves it), which ``choose_model`` takes as every candidate's least expected error.

``--json``, ``--cache`` and ``--out`` put the study file, the work files and the charts with their page elsewhere
(e.g. a trial run that leaves the repository's alone): ``--out DIR`` writes DIR/img/speed_accuracy_<scene>.png and
the generated block of DIR/choosing-a-model.md (a new page if there is none).

The scenes are library code, ``rotor37_rom.studies.speed_accuracy`` (one module per scene family, a registry of
scenes, the study file's schema in ``study_file``); this script turns its options into the scenes to run.

Every option is checked, and the study file read and the folders written in, before any work: a bad one is one line
on stderr and exit status 2. ``--check`` does only that (exit status 0); SIGTERM or SIGINT stop the run with one line
(``rotor37_rom.cli.run_main``).
"""
from __future__ import annotations

import json
import os
import sys
from pathlib import Path
from typing import Sequence

from rotor37_rom.checks import before_work, readable_file
from rotor37_rom.cli import ArgumentParser, run_main
from rotor37_rom.studies.speed_accuracy.scenes import DISK_SCENES, GROUPS, REFERENCE_SCENES, SCENES

ROOT = Path(__file__).resolve().parents[1]
PAGE = "choosing-a-model.md"          # the page whose generated block the study rewrites, in --out


def build_parser() -> ArgumentParser:
    p = ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scene", nargs="+", choices=SCENES + DISK_SCENES + REFERENCE_SCENES + tuple(GROUPS),
                   default=["all"], help="scenes to run: all (the single blade's, the default), disk (the bladed "
                   "disk's) or names (gnl-steady: read from bench_gnl_steady's full-order runs)")
    p.add_argument("--json", type=Path, default=ROOT / "rotor37_rom" / "data" / "speed_accuracy.json",
                   help="the study file (.json; read if it exists, the scenes not run keep their entries; default "
                        "rotor37_rom/data/speed_accuracy.json, the one choose_model reads)")
    p.add_argument("--cache", type=Path, default=ROOT / "results" / "speed_accuracy",
                   help="folder of the work files: the cached maps, models and runs (default results/speed_accuracy)")
    p.add_argument("--out", type=Path, default=ROOT / "docs",
                   help=f"folder of the charts (OUT/img) and of the page whose generated block is rewritten "
                        f"(OUT/{PAGE}; default docs)")
    return p


def study_file(path: Path) -> None:
    """ValueError naming --json unless ``path`` is a .json file's path and, where it exists, a study file."""
    if path.suffix != ".json" or not path.name[:-len(".json")].strip():
        raise ValueError(f"--json must be a .json file's path (the study file), got {str(path)!r}")
    if path.exists():
        readable_file("--json", path)
        try:
            study = json.loads(path.read_text())
        except (ValueError, UnicodeDecodeError) as exc:
            raise ValueError(f"--json: {path} is not a study file ({type(exc).__name__})") from None
        if not isinstance(study, dict):
            raise ValueError(f"--json: {path} is not a study file (a JSON object)")
        if not os.access(path, os.W_OK):
            raise ValueError(f"--json: cannot write {path} (permission denied)")


def main(argv: Sequence[str] | None = None) -> int:
    """Check the options, then run the scenes into the study file, its charts and page; raises ValueError for a bad
    input."""
    args = build_parser().parse_args(argv)
    study_file(args.json)
    page = args.out / PAGE
    if page.exists() and not (page.is_file() and os.access(page, os.R_OK | os.W_OK)):
        raise ValueError(f"--out: cannot rewrite {page} (not a file that can be read and written)")
    before_work({"--json": args.json.parent, "--cache": args.cache,
                 "--out": args.out / "img"})             # before any work; a dry run stops here

    from rotor37_rom.studies.speed_accuracy.context import StudyContext
    from rotor37_rom.studies.speed_accuracy.scenes import expand_scenes, run_study

    ctx = StudyContext(work=args.cache, img=args.out / "img", doc=page, study_file=args.json)
    study = run_study(ctx, expand_scenes(args.scene))
    for name, scene in study["scenes"].items():
        print(name, {k: v.get("name") for k, v in scene["choices"].items()})
    return 0


if __name__ == "__main__":
    sys.exit(run_main(main))
