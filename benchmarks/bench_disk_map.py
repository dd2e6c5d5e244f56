"""The issue's full-disk GNL map (paper §3.4, Figs. 23-24): 90 speeds x 200 revolutions in 1,200-1,650 rad/s at the
recommended model, its wall time on this machine, and its error against the exact sector tensors at a few speeds.

The recommended model (benchmarks/bench_disk_cubature.py): the contact maps' disk model (ci preset, every sector's 8
tip nodes, r_c = 10, r_MD = 10 by MI 2b, r_cyclic = 144: r = 1,728), the casing cone's normal, mu = 0.15, a 60 kHz
frequency cap, the GNL forces by point cubature trained to 3e-3 and evaluated in float32, the step from the tangent
limit on the training states. The map is demos/contact_map.py's study itself (the command users run, with --stress):
its summary.json, NFRC, interaction map and stress pictures land in --out, next to the linear map of

    mpirun -n 2 python demos/contact_map.py --disk --direction cone --frequency-cap 60 --speeds 1200 1650 90 \
        --revolutions 200 --gnl off --stress --out results/disk_map200

Then the reference, at --reference map speeds (indices into the 90; none is a training speed): the same step with the
exact sector tensors, and the floor, the exact forces x (1 + 1e-4) (how far any perturbation of that size moves the
answer). Per speed: node LE of sector 0 and the largest over the 36 blades, max over the last revolution.

Every part resumes: the model, the probe and the cubature are cached, the sweeps checkpoint every 60 s; so the map
runs over several sittings. The wall time is accounted by a heartbeat (every 30 s, rank 0) per phase and sitting in
<out>/bench_disk_map_sittings.json (--part stress: <out>/bench_disk_map_stress_sittings.json): a sitting that is
killed loses at most 30 s of its account.

    OPENBLAS_NUM_THREADS=1 mpirun -n 2 python benchmarks/bench_disk_map.py [--reference 10 30 50 70] [--part all]
    OPENBLAS_NUM_THREADS=1 mpirun -n 2 python benchmarks/bench_disk_map.py --revolutions 0.5 --out results/smoke

The stress of the paper's Fig. 25 at the maps' largest responses (1,255.6 and 1,513.5 rad/s, indices 11 and 62),
each speed run from rest with GNL off and on, and carried on one revolution (``--stress`` of the map command), in
<out>/stress_<index>/summary.json (one process: one speed each):

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_disk_map.py --part stress [--stress-at 11 62]

Results: results/bench_disk_map.json (machine stated; written once the map and the reference are complete; with
fewer --revolutions results/bench_disk_map_<N>rev.json). The reference alone, without the whole map (the map's model
runs at the reference speeds only; each sitting's report shows the floor's runs already made at its speeds):

    OPENBLAS_NUM_THREADS=1 mpirun -n 2 python benchmarks/bench_disk_map.py --part reference --reference 30 70
    OPENBLAS_NUM_THREADS=1 mpirun -n 2 python benchmarks/bench_disk_map.py --part reference --no-floor

writes results/bench_disk_map_reference.json.

Every option is checked, and the folders written in, before any work: a bad one is one line on stderr and exit
status 2. ``--check`` does only that (exit status 0); SIGTERM or SIGINT stop the run with one line
(``rotor37_rom.cli.run_main``).
"""
from __future__ import annotations

import dataclasses
import json
import sys
import threading
import time
from pathlib import Path
from typing import TYPE_CHECKING, Sequence

import numpy as np

from rotor37_rom.checks import before_work, real_number, whole_number
from rotor37_rom.cli import ArgumentParser, run_main

if TYPE_CHECKING:
    from rotor37_rom.studies.contact_config import ContactMapConfig

SPEEDS, REVOLUTIONS = (1200.0, 1650.0, 90), 200.0
CUBATURE, PRECISION, CAP_KHZ = 3e-3, "single", 60.0
FLOOR = 1e-4


class Sittings:
    """Wall time per phase and sitting, kept by a heartbeat thread (rank 0) in a JSON file."""

    def __init__(self, path: Path, active: bool):
        self.path, self.active, self.phase = path, active, "start"
        self.log = json.loads(path.read_text()) if active and path.is_file() else []
        self.entry = {"started": time.time(), "phases": {}}
        self.log.append(self.entry)
        self._last, self._stop = time.time(), threading.Event()
        if active:
            self._thread = threading.Thread(target=self._beat, daemon=True)
            self._thread.start()

    def _tick(self) -> None:
        now = time.time()
        phases = self.entry["phases"]
        phases[self.phase] = phases.get(self.phase, 0.0) + now - self._last
        self._last = now
        self.path.parent.mkdir(parents=True, exist_ok=True)
        tmp = self.path.with_suffix(".partial")
        tmp.write_text(json.dumps(self.log, indent=1))
        tmp.replace(self.path)

    def _beat(self) -> None:
        while not self._stop.wait(30.0):
            self._tick()

    def enter(self, phase: str) -> None:
        if self.active:
            self._tick()
        self.phase = phase

    def close(self) -> None:
        if self.active:
            self._stop.set()
            self._tick()

    def totals(self) -> dict:
        out: dict = {}
        for entry in self.log:
            for phase, seconds in entry["phases"].items():
                out[phase] = out.get(phase, 0.0) + seconds
        return out


def responses(folder: Path, speeds, missing_ok: bool = False) -> dict:
    """Node LE of sector 0 and the largest over the blades (max over the last revolution, m) of a sweep's speeds;
    with ``missing_ok`` NaN where the sweep has not run a speed."""
    from rotor37_rom.studies.sweep import load_speed, sector_maxima

    le0, largest, blade = [], [], []
    for w in speeds:
        rec = load_speed(folder, float(w))
        if rec is None and missing_ok:
            le0.append(float("nan"))
            largest.append(float("nan"))
            blade.append(None)
            continue
        if rec is None:
            raise FileNotFoundError(f"{folder}: no run at {w:g} rad/s")
        per_blade = sector_maxima(rec)
        le0.append(float(per_blade[0]))
        largest.append(float(np.max(per_blade)))
        blade.append(int(np.argmax(per_blade)) if np.isfinite(per_blade).all() else None)
    return {"le0_m": le0, "largest_m": largest, "largest_blade": blade}


def build_parser() -> ArgumentParser:
    p = ArgumentParser(description=__doc__.splitlines()[0])
    n = int(SPEEDS[2])
    p.add_argument("--out", type=Path, default=Path("results/disk_map200"),
                   help="the map's folder (default results/disk_map200)")
    p.add_argument("--reference", type=int, nargs="+", default=None,
                   help=f"with --part all or reference: indices (0..{n - 1}) of the map's speeds run with the exact "
                        f"sector tensors, none of the cubature's training speeds (default 10 30 50 70)")
    p.add_argument("--part", choices=["all", "map", "reference", "stress"], default="all",
                   help="reference: the map's model at the --reference speeds only (what the map has not run "
                        "yet), the exact tensors and the floor there; stress: the disk's stress at t_max at the "
                        "--stress-at speeds, GNL off and on (the map's model and step); map: the map alone "
                        "(default all: the map, then the reference)")
    p.add_argument("--stress-at", type=int, nargs="+", default=None,
                   help=f"with --part stress: indices (0..{n - 1}) of the map's speeds, each run from rest GNL off "
                        f"and on and carried on one revolution for the stress at t_max, in <out>/stress_<index> "
                        f"(default 11 62: the largest responses of the maps without and with GNL)")
    p.add_argument("--no-floor", action="store_true",
                   help="with --part all or reference: skip the floor run (exact forces x (1 + 1e-4)); the report "
                        "still shows the floor's runs an earlier sitting made at these speeds")
    p.add_argument("--revolutions", type=float, default=REVOLUTIONS,
                   help=f"per speed, in (0, 1000] and within this machine's memory (default {REVOLUTIONS:g}; fewer: "
                        f"a smoke run of the whole chain)")
    return p


def check_options(args) -> np.ndarray:
    """Every option checked (ValueError naming it and its range), the defaults of those that need a --part filled
    in; the map's speeds."""
    from rotor37_rom.dynamics.explicit import training_speeds

    real_number("--revolutions", args.revolutions, 0, 1000, open_low=True)
    grid = np.linspace(*SPEEDS[:2], int(SPEEDS[2]))
    train = training_speeds(grid)
    reference = args.part in ("all", "reference")
    for option, value, wanted in (("--reference", args.reference, reference),
                                  ("--stress-at", args.stress_at, args.part == "stress"),
                                  ("--no-floor", args.no_floor or None, reference)):
        if value is not None and not wanted:
            needs = "--part stress" if option == "--stress-at" else "--part all or reference"
            raise ValueError(f"{option} does nothing with --part {args.part}: it needs {needs}")
    for option, value, default in (("--reference", args.reference, [10, 30, 50, 70]),
                                   ("--stress-at", args.stress_at, [11, 62])):
        value = default if value is None else value
        for i in value:
            whole_number(f"{option} (indices of the map's speeds)", i, 0, grid.size - 1)
        setattr(args, option[2:].replace("-", "_"), value)
    trained = sorted(int(np.argmin(abs(grid - w))) for w in train)
    if reference and set(grid[args.reference]) & set(train):
        raise ValueError(f"--reference must be indices in 0..{grid.size - 1} of the map's speeds, none of the "
                         f"training ones ({', '.join(map(str, trained))}), got {' '.join(map(str, args.reference))}")
    return grid


def main(argv: Sequence[str] | None = None) -> int:
    """Check the options, then the model, probe and cubature (cached), the map, the reference or the stress runs;
    raises ValueError for a bad input."""
    args = build_parser().parse_args(argv)
    grid = check_options(args)
    from rotor37_rom.studies.contact_config import ContactMapConfig, saved_model_info

    try:
        config = ContactMapConfig.from_options(disk=True, direction="cone", mu=0.15, frequency_cap=CAP_KHZ,
                                               speeds=SPEEDS, revolutions=args.revolutions, gnl="on",
                                               cubature=CUBATURE, precision=PRECISION, stress=True, out=args.out,
                                               quiet=False)
    except ValueError as exc:                       # the map's own checks: --revolutions is this command's input
        raise ValueError(f"--revolutions {args.revolutions:g}: {exc}") from None
    rom = args.out / "rom.npz"
    if rom.is_file() and not saved_model_info("--out", rom)["disk"]:     # the map's model, read as it is
        raise ValueError(f"--out: {rom} is a single blade's model; the map's is the bladed disk's (use another "
                         f"--out)")
    before_work({"--out": args.out, "the results folder": Path("results")})    # before any work; a dry run stops here

    from rotor37_rom.studies.contact_map import world_comm

    comm = world_comm()
    rank = 0 if comm is None else comm.rank
    # the stress runs keep their own account (the map's wall time is the sittings of the map and its reference)
    sittings = Sittings(args.out / ("bench_disk_map_stress_sittings.json" if args.part == "stress"
                                    else "bench_disk_map_sittings.json"), rank == 0)
    try:
        return run(args, config, grid, comm, sittings)
    finally:
        sittings.close()


def run(args, config: ContactMapConfig, grid: np.ndarray, comm, sittings: Sittings) -> int:
    """The model, probe and cubature (cached), the map, the reference and floor runs, the report."""
    from rotor37_rom.dynamics.explicit import CentralDifference
    from rotor37_rom.machine import write_results
    from rotor37_rom.studies.contact_map import reduced_model, run_contact_map, time_scheme
    from rotor37_rom.studies.sweep import run_sweep, sweep_folder

    rank = 0 if comm is None else comm.rank
    sittings.enter("model, probe and cubature")
    rom = args.out / "rom.npz"
    config = config.with_options(model=rom) if rom.is_file() else config
    model, _ = reduced_model(config, comm)             # rank 0 builds it (or every rank reads rom.npz)
    config = config.with_options(model=rom)
    scheme = time_scheme(config.setting(True), model, True, comm)      # the map's own scheme (probe, cubature)
    spec = config.sweep_spec(model)
    if args.part == "stress":
        for i in args.stress_at:
            w = float(grid[i])
            sittings.enter(f"stress at {w:.1f} rad/s")
            run_contact_map(config.with_options(speeds=(w, w, 1), gnl="both", out=args.out / f"stress_{i}"),
                            comm, schemes={True: scheme})
        return 0
    if args.part in ("all", "map"):
        sittings.enter("map")
        run_contact_map(config, comm, schemes={True: scheme})
    if args.part == "map":
        return 0
    speeds = grid[args.reference]
    exact = CentralDifference(model, nonlinear=True, h=scheme.h, frequency_cap=scheme.frequency_cap)
    scaled = dataclasses.replace(model, forces=dataclasses.replace(model.forces,
                                                                   scales=model.forces.scales * (1 + FLOOR)),
                                 metadata=dict(model.metadata, force_scale=1 + FLOOR))
    floor = CentralDifference(scaled, nonlinear=True, h=scheme.h, frequency_cap=scheme.frequency_cap)
    sittings.enter("map's model at the reference speeds")
    map_folder = run_sweep(scheme, speeds, spec, args.out / "sweeps", comm=comm)    # nothing to do after the map
    sittings.enter("reference (exact tensors)")
    ref_folder = run_sweep(exact, speeds, spec, args.out / "reference", comm=comm)
    if not args.no_floor:
        sittings.enter("floor (exact x (1 + 1e-4))")
        run_sweep(floor, speeds, spec, args.out / "reference", comm=comm)
    sittings.enter("report")
    if rank != 0:
        return 0
    runs = {"map (cubature 3e-3 float32)": responses(map_folder, speeds), "exact": responses(ref_folder, speeds)}
    floor_folder = sweep_folder(floor, spec, args.out / "reference")
    if floor_folder.is_dir():                        # where the floor has run (--no-floor: an earlier sitting's)
        runs["exact x (1 + 1e-4) (floor)"] = responses(floor_folder, speeds, missing_ok=True)
    ref = runs["exact"]
    for name, resp in runs.items():
        resp["le0_error"] = [abs(a - b) / b for a, b in zip(resp["le0_m"], ref["le0_m"])]
        resp["largest_error"] = [abs(a - b) / b for a, b in zip(resp["largest_m"], ref["largest_m"])]
        print(f"{name:28s} LE sector 0: " + " ".join(f"{1e3 * a:.3f}" for a in resp["le0_m"]) + " mm, errors "
              + " ".join(f"{x:.1%}" for x in resp["le0_error"]) + "; largest over the blades: "
              + " ".join(f"{1e3 * a:.3f}" for a in resp["largest_m"]) + " mm, errors "
              + " ".join(f"{x:.1%}" for x in resp["largest_error"]))
    summary_file = args.out / "summary.json"         # the whole map's (absent after --part reference alone)
    summary = json.loads(summary_file.read_text()) if summary_file.is_file() else {"runs": {}}
    gnl = next((entry for label, entry in summary["runs"].items() if label.startswith("GNL")), {})
    sittings.close()
    totals = sittings.totals()
    row = {"speeds": SPEEDS, "revolutions": config.sweep.revolutions, "r": model.r, "h": scheme.h, "cap_khz": CAP_KHZ,
           "cubature": CUBATURE, "precision": PRECISION, "mu": config.sweep.casing.mu,
           "direction": config.sweep.casing.direction,
           "ranks": 1 if comm is None else comm.size, "reference_speeds": speeds.tolist(), "responses": runs,
           "wall_s_by_phase": totals, "sittings": len(sittings.log), "map_wall_s": totals.get("map"),
           "map": {k: gnl.get(k) for k in ("peak_speed", "peak_amplitude", "diverged", "contact_checks",
                                           "stress", "cubature")}}
    map_time = f"{totals['map'] / 3600:.2f} h" if "map" in totals else "not run in this folder's sittings"
    print(f"map: {map_time} over {len(sittings.log)} sittings (model, probe and cubature "
          f"{totals.get('model, probe and cubature', 0) / 60:.0f} min; reference "
          f"{totals.get('reference (exact tensors)', 0) / 60:.0f} min, floor "
          f"{totals.get('floor (exact x (1 + 1e-4))', 0) / 60:.0f} min)")
    name = "bench_disk_map" + ("" if args.part == "all" else "_reference")
    name += "" if config.sweep.revolutions == REVOLUTIONS else f"_{config.sweep.revolutions:g}rev"
    machine = write_results(name, [row])
    print(f"results/{name}.json ({machine})")
    return 0


if __name__ == "__main__":
    sys.exit(run_main(main))
