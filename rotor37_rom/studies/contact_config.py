"""The contact-map study's configuration (demos/contact_map.py): ``ContactMapConfig``, composed of the library's
objects (the model to build or load, the time scheme, a ``SweepSpec`` with its ``Casing``, the continuation), and its
command line (``build_parser``), whose flat options map onto it (``OPTIONS``, ``ContactMapConfig.from_options``).

Every check names the option it concerns, so that the command line can report it as is. Numbers are stored as floats,
as the command line gives them: the cache keys of sweeps and cubatures hash them, and a run from Python then reuses the
files of the same run from the shell. With ``tolerance`` each setting's options are the speed-accuracy study's choice
(``map_model``).

Pure Python and NumPy (no dolfinx): a bad option is refused before any meshing.
"""
from __future__ import annotations

import argparse
import dataclasses
import functools
import numbers
from pathlib import Path
from typing import ClassVar

import numpy as np

from rotor37_rom.checks import fits_in_memory, flagged, real_number, whole_number
from rotor37_rom.cli import ArgumentParser
from rotor37_rom.dynamics.turning import CLEARANCES
from rotor37_rom.geometry.blade import MESH_PRESETS
from rotor37_rom.model.reduced import ReducedModel
from rotor37_rom.reduction.config import DiskReductionConfig, ReductionConfig, check_cubic_memory
from rotor37_rom.studies.campbell import MAX_TURNING_SPEED
from rotor37_rom.studies.sector_file import SECTOR_OPTIONS, SectorFile, add_sector_options
from rotor37_rom.studies.sweep import SweepSpec

__all__ = ["ContactMapConfig", "MapModel", "MapScheme", "MapContinuation", "OPTIONS", "build_parser", "parse_options",
           "map_model", "refuse_idle_options", "saved_model_info", "MAX_MAP_SPEEDS",
           "continued_revolutions", "GNL_SETTINGS", "PRECISIONS", "N_SECTORS"]

GNL_SETTINGS = {"off": (False,), "on": (True,), "both": (False, True)}
PRECISIONS = ("double", "single")
N_SECTORS = 36                                     # rotor 37's blades (the disk sector of fem.create_disk_sector)
MAX_SPEED = 1e5                                    # rad/s (about 1 million rpm): above any bladed rotor's
#: speeds of a map at most: each is a run of its revolutions from rest (seconds to minutes), its record file and, on
#: rank 0, its records read back for the map (``ContactMapConfig`` checks their memory too)
MAX_MAP_SPEEDS = 10_000
#: the options that build the model (``MapModel``): with --model (a saved model, read as it is) they do nothing;
#: --preset and --disk still name the mesh --stress recovers the disk's stress on
BUILD_OPTIONS = ("preset", "disk", "r_c", "r_md", "global_md", "contact_patch", "r_cyclic", "mistuning", "seed")
STRESS_MESH_OPTIONS = ("preset", "disk")


def map_model(tolerance: float, gnl: bool, fallback: bool = False, disk: bool = False):
    """The speed-accuracy study's model of a map (scene 'map-gnl' or 'map-linear'; a disk's: 'disk-map-gnl' or
    'disk-map-linear') within ``tolerance``; with ``fallback`` the study's reference where no measured model meets it.
    Errors name --tolerance."""
    from rotor37_rom.studies.model_choice import STUDY_FILE, choose_model

    scene = ("disk-map-gnl" if gnl else "disk-map-linear") if disk else "map-gnl" if gnl else "map-linear"
    try:
        stamp = STUDY_FILE.stat().st_mtime_ns if STUDY_FILE.is_file() else None
        return choose_model(scene, tolerance, _study(stamp), fallback=fallback)
    except ValueError as exc:
        raise ValueError(f"--tolerance: {exc}") from None


@functools.lru_cache(maxsize=2)
def _study(stamp: int | None) -> dict:
    """The shipped study file, read once per version (``stamp``: its modification time; a study rewritten in the same
    process is read again). Read-only: ``choose_model`` does not change it."""
    from rotor37_rom.studies.model_choice import load_study

    return load_study()


def saved_model_info(option: str, path) -> dict:
    """What a saved reduced model (.npz) is, read from its small entries alone (the matrices are not read): {'key',
    'metadata', 'sizes', 'disk' (a bladed disk's model), 'n_sectors' (1 for a blade), 'forces' (its force's kind,
    'none' for a linear model), 'nodes' (its contact nodes' names), 'top_speed' (rad/s: the top of a turning
    model's range, None for a model at rest)}. ValueError naming ``option`` for a file that is
    missing, unreadable or not a reduced model (``model.reduced.saved_model_key``)."""
    import json

    from rotor37_rom.model.reduced import saved_model_key

    key = flagged(option, lambda: saved_model_key(path))
    try:
        with np.load(path, allow_pickle=False) as data:
            info = json.loads(str(data["meta"]))
            forces = str(data["forces"]) if "forces" in data.files else "none"
            nodes = tuple(str(x) for x in data["nodes_names"]) if "nodes_names" in data.files else ()
            sectors = "sectors_Pi" in data.files
            top = float(np.max(data["rotation_speeds"])) if "rotation_speeds" in data.files else None
    except Exception as exc:
        raise ValueError(f"{option}: reduced model file {path} is corrupted or not a reduced model "
                         f"({exc.__class__.__name__})") from None
    metadata, sizes = info.get("metadata", {}), info.get("sizes") or {}
    disk = sectors or "n_sectors" in sizes or metadata.get("kind") == "disk"
    n = sizes.get("n_sectors", metadata.get("n_sectors", 1)) if disk else 1
    return {"key": key, "metadata": metadata, "sizes": sizes, "disk": bool(disk), "n_sectors": int(n),
            "forces": forces, "nodes": nodes, "top_speed": top}


def continued_revolutions(revolutions: float) -> float:
    """Length of each continued run: 15 % of the first (the paper: 200 then 30), at least 5 revolutions."""
    return max(5.0, revolutions * 0.15)


def _flag(option: str) -> str:
    """The command-line option of a flat option name: r_c -> --r-c."""
    return "--" + option.replace("_", "-")


def _real(option: str, value, *args, **kwargs) -> None:
    """``checks.real_number`` under the option's command-line name."""
    real_number(_flag(option), value, *args, **kwargs)


def _whole(option: str, value, *args) -> None:
    """``checks.whole_number`` under the option's command-line name."""
    whole_number(_flag(option), value, *args)


@dataclasses.dataclass(frozen=True)
class MapModel:
    """The reduced model a map runs on: built here (the clamped blade of ``preset``, the 36-sector bladed disk, or a
    user's blade or bladed-disk sector ``mesh``), or a saved one (``path``). What the builders share with it they
    check themselves (``ReductionConfig``, ``DiskReductionConfig``); the errors name the command line's options.

    Attributes:
        preset: mesh preset of the blade the model is built on (and the cubature trained on): ci, coarse, paper.
        path: a saved reduced model (.npz, option ``model``) to load instead of building one (under MPI rank 0
            builds it, the others load it).
        disk: build the model of the 36-sector bladed disk (``reduction.disk_builder``: every sector's 8 tip nodes,
            modal derivatives by MI 2b, ``r_cyclic`` interface modes) instead of the clamped blade's.
        r_c: fixed-interface modes (per sector) of the model built (>= 1). None: 15 for the blade, 10 for the disk.
        r_md: modal derivatives (per sector) selected by the criterion (>= 0). None: 0 for the blade, 10 for the disk.
        global_md: also the modal derivatives of the first N clamped modes (0..20; the blade's; ReductionConfig's
            ``global_md_modes``).
        contact_patch: 0 (point contact at the tip nodes, the paper's), or a radius (m, at most 0.01) of the tip
            patches over which each node's contact force spreads (``ReductionConfig.contact_patch``; the blade's
            model built here, not a saved one or the disk's).
        r_cyclic: the disk's interface modes (eq. 51, >= 1; the paper's 144).
        mistuning: the disk's blade-to-blade stiffness scatter, a standard deviation in [0, 1) (0: tuned).
        seed: of the mistuning's random factors (a seed other than 0 needs ``mistuning`` > 0).
        mesh: a user's sector (``studies.sector_file.SectorFile``) to build the model on instead of rotor 37's: a
            blade, or with its cyclic faces and count a bladed disk (``disk`` is then set); None: rotor 37.
    """

    preset: str = "ci"
    path: Path | None = None
    disk: bool = False
    r_c: int | None = None
    r_md: int | None = None
    global_md: int = 3
    contact_patch: float = 0.0
    r_cyclic: int = 144
    mistuning: float = 0.0
    seed: int = 0
    mesh: SectorFile | None = None

    def _check_tensor_memory(self) -> None:
        """The blade's model built here, r = 3 x contact nodes + r_c + r_md + the global modal derivatives'
        g (g + 1) / 2, must hold its exact cubic forces (``reduction.config.check_cubic_memory``)."""
        g = self.global_md
        r = (3 * (self.mesh.contact if self.mesh is not None else 8) + (self.r_c or 15) + (self.r_md or 0)
             + g * (g + 1) // 2)
        check_cubic_memory("--r-c" if self.r_c else "--r-md", r)

    def __post_init__(self):
        if self.mesh is not None:
            if not isinstance(self.mesh, SectorFile):
                raise TypeError(f"mesh must be a SectorFile (the file and its groups) or None, got {self.mesh!r}")
            if self.path is not None:
                raise ValueError("--mesh builds a model on your sector: not with --model (a saved one)")
            if self.disk and self.mesh.cyclic is None:
                raise ValueError("--disk is rotor 37's bladed disk; your own disk: give --mesh with --left, --right "
                                 "and --n-sectors")
            object.__setattr__(self, "disk", self.mesh.cyclic is not None)
        if self.preset not in MESH_PRESETS:
            raise ValueError(f"--preset must be one of {', '.join(MESH_PRESETS)}, got {self.preset!r}")
        for option, field, value, config in (("r_c", "r_c", self.r_c, ReductionConfig),
                                             ("r_md", "r_md", self.r_md, ReductionConfig),
                                             ("global_md", "global_md_modes", self.global_md, ReductionConfig),
                                             ("contact_patch", "contact_patch", self.contact_patch, ReductionConfig),
                                             ("r_cyclic", "r_cyclic", self.r_cyclic, DiskReductionConfig),
                                             ("seed", "seed", self.seed, DiskReductionConfig)):
            if value is not None:
                flagged(_flag(option), lambda: config(**{field: value}))
        if not self.disk and self.path is None:
            self._check_tensor_memory()
        if self.contact_patch and (self.disk or self.path is not None):
            raise ValueError("--contact-patch shapes the blade's model built here: not with --disk or --model")
        real_number("--mistuning (standard deviation of the blades' stiffness factors)", self.mistuning, 0, 1,
                    open_high=True)
        if self.mistuning > 0 and not self.disk:
            raise ValueError("--mistuning needs --disk (it scatters the disk's blades)")
        if self.seed != 0 and self.mistuning == 0:
            raise ValueError(f"--seed needs --mistuning > 0 (it seeds the mistuning's random factors; a tuned disk "
                             f"has none), got --seed {self.seed}")
        for name in ("contact_patch", "mistuning"):
            object.__setattr__(self, name, float(getattr(self, name)))
        if self.path is not None:
            object.__setattr__(self, "path", Path(self.path))

    @property
    def n_sectors(self) -> int:
        """The sectors of the disk built (a user's N, rotor 37's 36), or of a saved model that may be a disk (36 at
        most checked before it is read, its own N after: ``sweep_spec``); 1 for a blade."""
        if self.mesh is not None and self.mesh.cyclic is not None:
            return self.mesh.n_sectors
        return N_SECTORS if self.disk or self.path is not None else 1

    def create_sector(self, comm):
        """The sector the model is built on (serially on ``comm``): the user's, or rotor 37's blade or disk sector
        of ``preset``."""
        from rotor37_rom import fem

        if self.mesh is not None:
            return self.mesh.create(comm)
        return (fem.create_disk_sector if self.disk else fem.create_blade_sector)(comm, preset=self.preset)


@dataclasses.dataclass(frozen=True)
class MapScheme:
    """How each speed is integrated: the explicit scheme's step, the frequency cap, the GNL forces' evaluation.

    Attributes:
        safety: h = safety x 2 / omega_max of the linear model, in (0, 1].
        h: time step (s); overrides ``safety``. None: from ``safety``.
        frequency_cap: spectral mass scaling (kHz): the modes above it are slowed to it; a GNL step then comes from
            the tangent limit on a short unscaled probe run. None: no scaling.
        tangent_safety: with a cap, the GNL step is this x 2 / the largest tangent frequency, in (0, 1].
        step_outliers: with a cap, 'keep' (the GNL step from every step state) or 'drop' (from the states other than
            ``dynamics.explicit.step_outliers``, those above 10 times the median tangent frequency: on the ci blade at
            mu = 0.1 over 1,620-2,000 rad/s one of 204, a St. Venant-Kirchhoff collapse that alone sets a step 19
            times smaller). With 'drop' a run that stays near such a state at the larger step blows up and is
            flagged; its retries (``retry_diverged``) halve that step, which may still be above the one from every
            state, and the demo then says so. A brief pass may not blow up, so benchmarks/bench_gnl_vs_linear.py
            --step-check measures the dropped step's error against runs at the kept one.
        perturbation: the internal force K q + g(q) of the runs scaled by 1 + this, |.| < 0.01 (0: none), after
            the cubature is trained and the step set (``model.reduced.perturbed_model``; the same cubature and step,
            the cap applied to the perturbed model): a map again with 1e-4 shows the speeds whose response any
            force approximation's error moves (the floor; docs/results.md). A step at the unperturbed limit is
            refused, the perturbed model's being eps / 2 lower.
        cubature: GNL forces by point cubature trained to this relative tolerance, in (0, 1). None: exact tensors.
        precision: arithmetic of the cubature forces: 'double' or 'single' (float32; needs ``cubature``).
        cubature_speeds: the speeds (rad/s) of the exact GNL runs the cubature is trained on (needs ``cubature``).
            None: 6 of the map's speeds, both ends included. A map on other speeds with the same training speeds
            reuses the same cubature (a held-out check runs the model as trained, not one retrained on its speeds).
        capped_training: the blade's cubature training runs (and the GNL step's probe) run with the frequency cap,
            at the tangent limit on a capped probe's states (exact forces), as a disk's always do (needs
            ``cubature`` and ``frequency_cap``). For bases whose unscaled GNL step makes the exact runs hours long
            (the modal derivatives of 10 clamped modes, r = 104); the cubature is then trained on the capped
            dynamics the map runs. False: unscaled training runs (the headline maps').
        retry_diverged: runs that blew up run again with the step halved, up to this many times (0..4).
        rotation: the blade turns at each speed (``dynamics.turning``: centrifugal prestress and spin softening, each
            run from its centrifugal state; GNL off, the blade linearised about that state): 'running' (the casing's
            c0 and the map's displacements measured from the running blade) or 'rest' (from the blade at rest: the
            tip's centrifugal growth eats the clearance). None: the blade at rest, the paper's. The model built
            then holds the centrifugal states at STOP / 2 and STOP and the first 4 modes turning at STOP (STOP: the
            top of the map's and the continuation's speeds; ``ReductionConfig.spin_snapshots``; a disk's:
            ``DiskReductionConfig.spin_snapshots``, GNL on only, tuned).
    """

    safety: float = 0.5
    h: float | None = None
    frequency_cap: float | None = None
    tangent_safety: float = 0.5
    step_outliers: str = "keep"
    perturbation: float = 0.0
    cubature: float | None = None
    precision: str = "double"
    cubature_speeds: tuple[float, ...] | None = None
    capped_training: bool = False
    retry_diverged: int = 0
    rotation: str | None = None

    def __post_init__(self):
        _real("safety", self.safety, 0, 1, open_low=True)
        if self.rotation is not None:
            if self.rotation not in CLEARANCES:
                raise ValueError(f"--rotation must be one of {', '.join(CLEARANCES)} (where the clearance is "
                                 f"measured from), got {self.rotation!r}")
            if self.cubature is not None:
                raise ValueError("--rotation: not with --cubature (the cubature is trained on runs at rest; give the "
                                 "exact GNL forces)")
        if self.h is not None:
            _real("h", self.h, 0, 1, open_low=True, unit=" s")
        if self.frequency_cap is not None:
            _real("frequency_cap", self.frequency_cap, 0, 1e4, open_low=True, unit=" kHz")
        _real("tangent_safety", self.tangent_safety, 0, 1, open_low=True)
        if self.step_outliers not in ("keep", "drop"):
            raise ValueError(f"--step-outliers must be 'keep' or 'drop', got {self.step_outliers!r}")
        if self.step_outliers == "drop" and (self.frequency_cap is None or self.h is not None):
            raise ValueError("--step-outliers drop needs --frequency-cap and no --h (it chooses the GNL step from "
                             "the tangent limit)")
        _real("perturbation", self.perturbation, -0.01, 0.01, open_low=True, open_high=True)
        if self.cubature is not None:
            _real("cubature", self.cubature, 0, 1, open_low=True, open_high=True)
        if self.precision not in PRECISIONS:
            raise ValueError(f"--precision must be one of {', '.join(PRECISIONS)}, got {self.precision!r}")
        if self.precision != "double" and self.cubature is None:
            raise ValueError("--precision single needs --cubature (the exact cubic tensors are evaluated in double)")
        if self.cubature_speeds is not None:
            if self.cubature is None:
                raise ValueError("--cubature-speeds needs --cubature (they are the cubature's training runs)")
            speeds = self.cubature_speeds
            if not (isinstance(speeds, (tuple, list, np.ndarray)) and len(speeds) >= 1
                    and all(isinstance(w, numbers.Real) and np.isfinite(w) and w > 0 for w in speeds)):
                raise ValueError(f"--cubature-speeds must be one or more finite speeds > 0 rad/s, got "
                                 f"{self.cubature_speeds!r}")
        if self.capped_training and (self.cubature is None or self.frequency_cap is None):
            raise ValueError("--capped-training needs --cubature and --frequency-cap (it runs the cubature's training "
                             "runs with the cap)")
        _whole("retry_diverged", self.retry_diverged, 0, 4)
        for name in ("safety", "h", "frequency_cap", "tangent_safety", "cubature", "perturbation"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, float(getattr(self, name)))
        if self.cubature_speeds is not None:
            object.__setattr__(self, "cubature_speeds", tuple(sorted({float(w) for w in self.cubature_speeds})))

    @property
    def frequency_cap_rad_s(self) -> float | None:
        """``frequency_cap`` in rad/s (None: no cap)."""
        return None if self.frequency_cap is None else 2 * np.pi * 1e3 * self.frequency_cap


@dataclasses.dataclass(frozen=True)
class MapContinuation:
    """A sequential continuation in speed up and down beside the map (``studies.sweep.continuation``).

    Attributes:
        step: speed step (rad/s; option ``continuation``); 0: none.
        range: (LOW, HIGH) speeds (rad/s; option ``continuation_range``); None: the map's range. Needs ``step`` or
            ``periodic`` > 0 (it is their range).
        steady_window: a continued run is steady when its max over the last N revolutions and the N before agree.
        unsteady_step: the continuation's point when no halving is steady: 'smallest' (the paper read literally:
            the step stays divided) or 'full' (the full step, marked not steady). Either, other than its default
            (1, 'smallest'), needs ``step`` > 0.
        periodic: relative arc-length step of the periodic orbits' continuation over the same range (option
            ``periodic``; ``studies.periodic_map``: the map's scheme and casing by shooting, with their stability);
            0: none. A blade's model only.
    """

    step: float = 0.0
    range: tuple[float, float] | None = None
    steady_window: int = 1
    unsteady_step: str = "smallest"
    periodic: float = 0.0

    def __post_init__(self):
        real_number("--continuation (the speed step, rad/s; 0: none)", self.step, 0, MAX_SPEED)
        if self.range is not None and not (
                isinstance(self.range, (tuple, list)) and len(self.range) == 2
                and all(isinstance(w, numbers.Real) and np.isfinite(w) for w in self.range)
                and 0 < self.range[0] < self.range[1] <= MAX_SPEED):
            raise ValueError(f"--continuation-range: need 0 < LOW < HIGH <= {MAX_SPEED:g} rad/s, got {self.range!r}")
        _whole("steady_window", self.steady_window, 1)
        if self.unsteady_step not in ("smallest", "full"):
            raise ValueError(f"--unsteady-step must be 'smallest' or 'full', got {self.unsteady_step!r}")
        real_number("--periodic (the relative arc-length step of the periodic orbits; 0: none)", self.periodic, 0,
                    0.5)
        if self.range is not None and self.step == 0 and self.periodic == 0:
            raise ValueError("--continuation-range needs --continuation STEP > 0 or --periodic STEP > 0 (it is the "
                             "speed range of their branches)")
        for name, value, default in (("steady_window", self.steady_window, 1),
                                     ("unsteady_step", self.unsteady_step, "smallest")):
            if self.step == 0 and value != default:
                raise ValueError(f"{_flag(name)} needs --continuation STEP > 0 (it shapes the continuation's runs), "
                                 f"got {_flag(name)} {value}")
        object.__setattr__(self, "step", float(self.step))
        object.__setattr__(self, "periodic", float(self.periodic))
        if self.range is not None:
            object.__setattr__(self, "range", tuple(float(w) for w in self.range))


#: The command line's options (and the speed-accuracy study's, which are among them) -> (the part of a
#: ContactMapConfig that holds it, its field there); '' is the configuration itself
OPTIONS = {
    **{name: ("rom", name) for name in ("preset", "disk", "r_c", "r_md", "global_md", "contact_patch", "r_cyclic",
                                        "mistuning", "seed")},
    "model": ("rom", "path"), "mesh": ("rom", "mesh"),
    **{f.name: ("scheme", f.name) for f in dataclasses.fields(MapScheme)},
    "revolutions": ("sweep", "revolutions"), "batch": ("sweep", "batch_size"),
    "mu": ("sweep.casing", "mu"), "c0": ("sweep.casing", "c0"), "hb": ("sweep.casing", "h_b"),
    "direction": ("sweep.casing", "direction"), "rotation_sense": ("sweep.casing", "rotation_sense"),
    "continuation": ("continuation", "step"), "continuation_range": ("continuation", "range"),
    "steady_window": ("continuation", "steady_window"), "unsteady_step": ("continuation", "unsteady_step"),
    "periodic": ("continuation", "periodic"),
    **{name: ("", name) for name in ("speeds", "gnl", "sector", "stress", "tolerance", "out", "cache", "quiet")},
}


def _part(obj, where: str):
    """The part of ``obj`` at a dotted path ('' : obj itself)."""
    for name in filter(None, where.split(".")):
        obj = getattr(obj, name)
    return obj


@dataclasses.dataclass(frozen=True)
class ContactMapConfig:
    """What to compute: the reduced model, the time scheme, the speeds and the casing, the continuation. It composes
    the library's objects: ``rom`` (MapModel), ``scheme`` (MapScheme), ``sweep`` (a ``studies.sweep.SweepSpec``:
    revolutions per speed, batch size and the ``dynamics.casing.Casing``) and ``continuation`` (MapContinuation).
    The command line and the speed-accuracy study name flat options (``OPTIONS``): ``from_options`` makes a
    configuration of them, ``options`` gives them back and ``with_options`` changes some.

    Attributes:
        speeds: (START, STOP, N): N angular speeds (rad/s) from START to STOP: 0 < START <= STOP <= ``MAX_SPEED``
            (with ``scheme.rotation``, a model built on rotor 37: <= ``studies.campbell.MAX_TURNING_SPEED``, its
            continuation's range too), N in 1..``MAX_MAP_SPEEDS``, the records of all N read back within this
            machine's memory.
        gnl: geometric nonlinearity: 'off', 'on' or 'both' (one map each).
        sector: the sector whose node LE makes the map and the NFRC (0 .. 35; the blade: 0).
        stress: a disk's von Mises stress at t_max of each map's largest response, every sector rebuilt from q (the
            blade's: demos/report.py).
        tolerance: choose r_c, the frequency cap, the step and the force evaluation of each setting (GNL off, on) as
            the cheapest model of the speed-accuracy study within this relative error
            (``studies.model_choice.choose_model`` on the scenes 'map-linear' and 'map-gnl', read from
            rotor37_rom/data/speed_accuracy.json), in (0, 1); with a disk (tuned) r_c, r_md, r_cyclic, the cap and the
            force evaluation from the scenes 'disk-map-linear' and 'disk-map-gnl' (measured with the cone normal and mu
            = 0.15). The options it sets must not be given with it. None: the options as given.
        out: folder of the charts, summary.json, the sweeps' records and the caches.
        cache: folder of the model, cubature, training-run and probe caches; None: OUT/cache. Maps in other folders
            given the same cache share its cubature (e.g. a few speeds run again at another step).
        quiet: no progress bars and no sprag-slip note.
    """

    OPTIONS: ClassVar[dict] = OPTIONS

    rom: MapModel = MapModel()
    scheme: MapScheme = MapScheme()
    sweep: SweepSpec = SweepSpec(revolutions=20.0)
    continuation: MapContinuation = MapContinuation()
    speeds: tuple[float, float, int] = (1200.0, 1600.0, 21)
    gnl: str = "both"
    sector: int = 0
    stress: bool = False
    tolerance: float | None = None
    out: Path = Path("results/contact_map")
    cache: Path | None = None
    quiet: bool = False

    @classmethod
    def from_options(cls, **options) -> "ContactMapConfig":
        """The configuration of flat options (``OPTIONS``: the command line's names), the others at their defaults;
        a bad value is refused naming its option (--name)."""
        unknown = sorted(set(options) - set(OPTIONS))
        if unknown:
            raise TypeError(f"ContactMapConfig has no option {', '.join(unknown)}")
        parts = {}
        for option, value in options.items():
            where, field = OPTIONS[option]
            parts.setdefault(where, {})[field] = value
        default = cls.__dataclass_fields__
        casing = default["sweep"].default.casing
        for field, value in parts.get("sweep.casing", {}).items():           # each alone: the error names it
            option = next(o for o, (w, f) in OPTIONS.items() if w == "sweep.casing" and f == field)
            casing = flagged(_flag(option), lambda: dataclasses.replace(casing, **{field: value}))
        sweep = dataclasses.replace(default["sweep"].default, casing=casing)
        for field, value in parts.get("sweep", {}).items():
            option = next(o for o, (w, f) in OPTIONS.items() if w == "sweep" and f == field)
            sweep = flagged(_flag(option), lambda: dataclasses.replace(sweep, **{field: value}))
        return cls(rom=MapModel(**parts.get("rom", {})), scheme=MapScheme(**parts.get("scheme", {})), sweep=sweep,
                   continuation=MapContinuation(**parts.get("continuation", {})), **parts.get("", {}))

    def options(self) -> dict:
        """The flat options of this configuration (``OPTIONS``)."""
        return {option: getattr(_part(self, where), field) for option, (where, field) in OPTIONS.items()}

    def with_options(self, **options) -> "ContactMapConfig":
        """This configuration with some flat options changed (checked again)."""
        return type(self).from_options(**{**self.options(), **options})

    def __post_init__(self):
        """Check the options that tie the parts together (each part checks its own) and store the numbers as the
        command line gives them."""
        for name, kind in (("rom", MapModel), ("scheme", MapScheme), ("sweep", SweepSpec),
                           ("continuation", MapContinuation)):
            if not isinstance(getattr(self, name), kind):
                raise TypeError(f"ContactMapConfig.{name} must be a {kind.__name__}, got "
                                f"{type(getattr(self, name)).__name__}")
        self._check_sweep()
        self._check_tolerance()
        self._normalise()

    def _check_sweep(self) -> None:
        """Speeds, the map's node, stress, the continuation's steadiness window."""
        speeds = self.speeds
        if not (isinstance(speeds, (tuple, list)) and len(speeds) == 3
                and all(isinstance(w, numbers.Real) and np.isfinite(w) for w in speeds)
                and 0 < speeds[0] <= speeds[1] <= MAX_SPEED and 1 <= speeds[2] <= MAX_MAP_SPEEDS
                and float(speeds[2]).is_integer()):
            raise ValueError(f"--speeds: need 0 < START <= STOP <= {MAX_SPEED:g} rad/s and an integer N in "
                             f"1..{MAX_MAP_SPEEDS}, got {list(speeds)}")
        if self.gnl not in GNL_SETTINGS:
            raise ValueError(f"--gnl must be one of {', '.join(GNL_SETTINGS)}, got {self.gnl!r}")
        # what a batch holds: every record_dt, per run the monitored nodes' normal displacements and the contact
        # forces (a blade: 8 + 8; a disk, or a model file that may be one: 37 + 288), at the slowest speed
        rows = 8 + 8 if not (self.rom.disk or self.rom.path is not None) else 37 + 8 * self.rom.n_sectors
        records = self.sweep.revolutions * 2 * np.pi / speeds[0] / self.sweep.record_dt + 1
        batch = min(self.sweep.batch_size, int(speeds[2]))
        fits_in_memory("--revolutions", 8.0 * rows * records * batch,
                       f"{batch} runs x {records:.3g} records x {rows} values, at {speeds[0]:g} rad/s",
                       hint="fewer revolutions or a smaller --batch")
        # what the whole map holds on rank 0 once its speeds are run: every speed's record read back (its time and
        # the monitored nodes' displacements: a blade's 8, a disk's LE of every sector and TE) and its spectrum
        kept = 1 + (8 if not (self.rom.disk or self.rom.path is not None) else self.rom.n_sectors + 1)
        n = int(speeds[2])
        fits_in_memory("--speeds", n * (8.0 * kept * records + 8.0 * 600 + 1024),
                       f"{n} speeds x {records:.3g} records x {kept} values read back for the map, at most (at "
                       f"{speeds[0]:g} rad/s)", hint="fewer speeds or revolutions, or the speed range split over "
                                                     "several maps")
        limit = self.rom.n_sectors - 1
        if not (isinstance(self.sector, numbers.Integral) and 0 <= self.sector <= limit):
            raise ValueError(f"--sector must be in [0, {limit}] ({'the disk' if limit else 'a single blade'}'s "
                             f"sectors), got {self.sector}")
        if self.stress and not (self.rom.disk or self.rom.path is not None):
            raise ValueError("--stress is the disk's (--disk or a disk --model); the blade's stress at t_max is "
                             "demos/report.py's")
        if self.continuation.periodic > 0 and self.rom.disk:
            raise ValueError("--periodic: periodic orbits by shooting take a blade (not --disk; a tuned disk's "
                             "travelling wave is periodic.TravellingWaveBalance)")
        if self.scheme.rotation is not None and self.rom.disk and self.gnl != "on":
            raise ValueError("--rotation with --disk takes --gnl on (the disk's prestress comes from its GNL forces; "
                             "its linearised turning scheme is not implemented)")
        if self.scheme.rotation is not None and self.rom.disk and self.rom.mistuning > 0:
            raise ValueError("--rotation: not with --mistuning (the turning disk's centrifugal state is the tuned "
                             "disk's)")
        if self.scheme.rotation is not None and self.continuation.periodic > 0:
            raise ValueError("--rotation: not with --periodic (the periodic orbits of a turning blade are not "
                             "implemented; its map and continuation are)")
        if (self.scheme.rotation is not None and self.rom.path is None and self.rom.mesh is None
                and self.top_speed > MAX_TURNING_SPEED):
            option, top = (("--speeds", "STOP") if speeds[1] >= self.continuation_span[1] else
                           ("--continuation-range", "HIGH"))
            raise ValueError(f"{option}: the turning model is built up to {self.top_speed:g} rad/s, above rotor 37's "
                             f"{MAX_TURNING_SPEED:g} rad/s (its blade yields above: studies.campbell."
                             f"MAX_TURNING_SPEED); need {top} <= {MAX_TURNING_SPEED:g} rad/s with --rotation")
        half = continued_revolutions(self.sweep.revolutions) / 2
        if not self.continuation.steady_window <= half:
            raise ValueError(f"--steady-window must be in 1..{int(half)} revolutions (half of a continued run), got "
                             f"{self.continuation.steady_window}")

    def _check_tolerance(self) -> None:
        """With ``tolerance``: in (0, 1), and none of the options it chooses given."""
        if self.tolerance is None:
            return
        if self.scheme.rotation is not None:
            raise ValueError("--rotation: not with --tolerance (the speed-accuracy study measured maps of the blade at "
                             "rest; give the options)")
        if self.scheme.capped_training:
            raise ValueError("--capped-training: not with --tolerance (the study measured the chosen models trained "
                             "unscaled)")
        if not (isinstance(self.tolerance, numbers.Real) and 0 < self.tolerance < 1):
            raise ValueError(f"--tolerance must be in (0, 1) (a relative error: 0.05 = 5 %), got {self.tolerance}")
        if self.rom.mesh is not None:
            raise ValueError("--tolerance with --mesh: the speed-accuracy study measured rotor 37's models; give the "
                             "options for your sector")
        if self.rom.disk and self.rom.mistuning > 0:
            raise ValueError("--tolerance with --mistuning: the speed-accuracy study measured the tuned disk; "
                             "give the options")
        chosen = set().union(*(self.choice(gnl).options for gnl in GNL_SETTINGS[self.gnl]))
        mine, defaults = self.options(), _default_options()
        given = [name for name in sorted(chosen - {"r_c"}) if mine[name] != defaults[name]]
        if self.rom.r_c is not None:
            given.append("r_c")
        if given or self.rom.path is not None or self.scheme.h is not None:
            names = [_flag(n) for n in given] + (["--model"] if self.rom.path else []) \
                + (["--h"] if self.scheme.h is not None else [])
            raise ValueError(f"--tolerance chooses {', '.join(names)}: give either the tolerance or the options")

    def _normalise(self) -> None:
        """Floats, tuples and paths, as the command line gives them (same cache keys from Python and the shell)."""
        casing = self.sweep.casing
        casing = dataclasses.replace(casing, c0=float(casing.c0), h_b=float(casing.h_b), mu=float(casing.mu))
        object.__setattr__(self, "sweep", dataclasses.replace(self.sweep, revolutions=float(self.sweep.revolutions),
                                                              casing=casing))
        start, stop, n = self.speeds
        object.__setattr__(self, "speeds", (float(start), float(stop), int(n)))
        if self.tolerance is not None:
            object.__setattr__(self, "tolerance", float(self.tolerance))
        for name in ("out", "cache"):                    # Path('') is the current folder: refused, not written in
            value = getattr(self, name)
            if value is None and name == "cache":
                continue
            if not isinstance(value, (str, Path)) or not str(value).strip():
                raise ValueError(f"{_flag(name)} must be a folder's path, got {value!r}")
            object.__setattr__(self, name, Path(value))

    @property
    def modes(self) -> tuple[int, int]:
        """(r_c, r_md) of the model built: the options, or 15, 0 for the blade and 10, 10 for the disk; with
        ``tolerance`` the largest r_c (and r_md, a disk's) the settings' choices need."""
        rom = self.rom
        r_c, r_md = (rom.r_c if rom.r_c is not None else (10 if rom.disk else 15),
                     rom.r_md if rom.r_md is not None else (10 if rom.disk else 0))
        if self.tolerance is not None and rom.r_c is None:
            chosen = [self.choice(gnl).options for gnl in GNL_SETTINGS[self.gnl]]
            return max(c.get("r_c", r_c) for c in chosen), max(c.get("r_md", r_md) for c in chosen)
        return r_c, r_md

    @property
    def interface_modes(self) -> int:
        """r_cyclic of the disk model built: the option, or with ``tolerance`` the largest the settings' choices
        need (one model serves GNL off and on)."""
        if self.tolerance is not None and self.rom.disk:
            return max(self.choice(gnl).options.get("r_cyclic", self.rom.r_cyclic) for gnl in GNL_SETTINGS[self.gnl])
        return self.rom.r_cyclic

    def choice(self, gnl: bool):
        """The speed-accuracy study's cheapest model within ``tolerance`` for one setting (a ModelChoice)."""
        return map_model(self.tolerance, gnl, disk=self.rom.disk)

    def model_beyond_choice(self, gnl: bool) -> dict:
        """The options of the model built (r_c, r_md, a disk's r_cyclic) where they exceed one setting's choice: one
        model serves GNL off and on, the larger of their choices. Empty without ``tolerance`` or where they agree."""
        if self.tolerance is None:
            return {}
        built = {"r_c": self.modes[0], "r_md": self.modes[1], **({"r_cyclic": self.interface_modes} if self.rom.disk
                                                                  else {})}
        chosen = self.choice(gnl).options
        return {k: v for k, v in built.items() if k in chosen and chosen[k] != v}

    def setting(self, gnl: bool) -> "ContactMapConfig":
        """The configuration one setting (GNL off or on) runs with: with ``tolerance``, its chosen options."""
        if self.tolerance is None:
            return self
        options = {k: v for k, v in self.choice(gnl).options.items() if k != "r_c"}
        return self.with_options(tolerance=None, **options)

    @property
    def cache_dir(self) -> Path:
        """The caches' folder: ``cache``, or OUT/cache."""
        return self.cache if self.cache is not None else self.out / "cache"

    @property
    def speed_grid(self) -> np.ndarray:
        """The map's angular speeds (rad/s)."""
        start, stop, n = self.speeds
        return np.linspace(start, stop, n)

    @property
    def top_speed(self) -> float:
        """The highest speed a run of this configuration turns at (rad/s): the map's or the continuation's."""
        return float(max(self.speeds[1], self.continuation_span[1]))

    @property
    def spin_snapshots(self) -> tuple[float, ...]:
        """The centrifugal snapshots of a turning model built here (``MapScheme.rotation``): STOP / 2 and STOP (the
        ``top_speed``); () for a blade at rest."""
        return () if self.scheme.rotation is None else (self.top_speed / 2, self.top_speed)

    @property
    def continuation_span(self) -> tuple[float, float]:
        """(LOW, HIGH) of the continuation (rad/s): its range or the map's."""
        return self.continuation.range or self.speeds[:2]

    @property
    def node(self) -> str:
        """The node whose response makes the map: LE of ``sector`` (a NodeMap label)."""
        return f"{self.sector}:LE"

    def sweep_spec(self, model: ReducedModel) -> SweepSpec:
        """The contact scenario each speed runs (``sweep``); a disk records node LE of every sector and TE of
        ``sector``."""
        monitor = None
        n = model.nodes.n_sectors
        if n > 1 and not 0 <= self.sector < n:           # a saved model's N is known once it is read
            raise ValueError(f"--sector must be in [0, {n - 1}] (the sectors of the model read), got {self.sector}")
        if n > 1:
            try:
                rows = [model.nodes.row("LE", s) for s in range(model.nodes.n_sectors)]
                rows += [model.nodes.row("TE", self.sector)] if "TE" in model.nodes.names else []
                monitor = tuple(rows)
            except ValueError as exc:
                raise ValueError(f"--sector: {exc}") from None
        elif self.sector != 0:
            raise ValueError(f"--sector must be 0 for a single blade's model, got {self.sector}")
        return dataclasses.replace(self.sweep, monitor=monitor)


@functools.lru_cache(maxsize=1)
def _default_options() -> dict:
    """The flat options of ContactMapConfig's defaults."""
    return ContactMapConfig().options()


def build_parser() -> ArgumentParser:
    """The command line: one option per entry of ``OPTIONS`` (defaults: the configuration's)."""
    parser = ArgumentParser(description="interaction maps of the reduced blade with casing contact",
                            argument_default=argparse.SUPPRESS)
    parser.add_argument("--preset", help=f"mesh preset: {', '.join(MESH_PRESETS)} (default ci)")
    parser.add_argument("--model", type=Path, help="load this reduced model (.npz) instead of building one (not with "
                                                   "the options that build one: --preset and --disk only with "
                                                   "--stress)")
    parser.add_argument("--disk", action="store_true",
                        help="the 36-sector bladed disk (every blade's 8 tip nodes in contact) instead of the blade")
    parser.add_argument("--r-c", type=int, help="fixed-interface modes (per sector) of the model built (default 15; "
                                                "disk 10)")
    parser.add_argument("--r-md", type=int, help="modal derivatives (per sector) of the model built (default 0; disk "
                                                 "10, by MI 2b)")
    parser.add_argument("--global-md", type=int, help="modal derivatives of the first N clamped modes (default 3; the "
                                                       "blade's)")
    parser.add_argument("--contact-patch", type=float, metavar="RADIUS",
                        help="spread each tip node's contact force over the tip facets within RADIUS (m, <= 0.01; "
                             "default 0: point contact)")
    parser.add_argument("--r-cyclic", type=int, help="the disk's interface modes (default 144, the paper's; needs "
                                                      "--disk)")
    parser.add_argument("--mistuning", type=float, metavar="SIGMA",
                        help="the disk's blade stiffness scatter: standard deviation in [0, 1) of log-normal factors "
                             "(default 0: tuned)")
    parser.add_argument("--seed", type=int, help="seed of the mistuning factors (default 0; needs --mistuning)")
    parser.add_argument("--sector", type=int, help="sector whose node LE makes the map (0..35; default 0)")
    parser.add_argument("--stress", action="store_true",
                        help="the disk's von Mises stress at t_max of each map's largest response (all sectors)")
    parser.add_argument("--speeds", type=float, nargs=3, metavar=("START", "STOP", "N"),
                        help=f"N angular speeds (rad/s) from START to STOP, 0 < START <= STOP <= {MAX_SPEED:g} (with "
                             f"--rotation and the model built here <= {MAX_TURNING_SPEED:g}: rotor 37's range), N in "
                             f"1..{MAX_MAP_SPEEDS} and within this machine's memory (default 1200 1600 21)")
    parser.add_argument("--revolutions", type=float, help="revolutions per speed (default 20)")
    parser.add_argument("--gnl", choices=list(GNL_SETTINGS), help="geometric nonlinearity (default both)")
    parser.add_argument("--safety", type=float, help="h = safety * 2 / omega_max (linear model; default 0.5)")
    parser.add_argument("--h", type=float, help="time step (s); overrides --safety")
    parser.add_argument("--frequency-cap", type=float, metavar="KHZ",
                        help="spectral mass scaling: slow the modes above this frequency (kHz) to it; the GNL step "
                             "then comes from the tangent limit on a short unscaled probe run "
                             "(benchmarks/bench_contact_convergence.py measures the error: 60 kHz is within 3 %%)")
    parser.add_argument("--tangent-safety", type=float,
                        help="GNL with a cap: h = this x 2 / tangent omega_max on the probe's largest states "
                             "(default 0.5; 0.7 lost speeds at 120 kHz in bench_contact_convergence, 0.5 none in "
                             "bench_contact_ecsw)")
    parser.add_argument("--step-outliers", choices=["keep", "drop"],
                        help="with a cap: the GNL step from every probe/training state (keep, the default) or "
                             "without the few whose tangent frequency is above 10x the median (drop: St. Venant-"
                             "Kirchhoff collapse states; a run that stays near one blows up and is flagged)")
    parser.add_argument("--perturbation", type=float, metavar="EPS",
                        help="scale the runs' internal force K q + g(q) by 1 + EPS, |EPS| < 0.01, after the cubature "
                             "and the step are set: the map again with 1e-4 shows the speeds whose response a "
                             "force error that small moves (the floor; default 0)")
    parser.add_argument("--cubature", type=float, metavar="TOL",
                        help="GNL: replace the exact cubic forces by point cubature trained to this relative "
                             "tolerance on exact GNL runs at 6 of the speeds (min(revolutions, 12) each; "
                             "bench_contact_ecsw: 1e-4 with a 120 kHz cap is the cheapest setting within the "
                             "problem's own sensitivity)")
    parser.add_argument("--precision", choices=PRECISIONS,
                        help="with --cubature: arithmetic of the cubature forces (single: float32, 1.6-2.1x faster "
                             "in bench_contact_ecsw, within 4e-7 of the double force; default double)")
    parser.add_argument("--cubature-speeds", type=float, nargs="+", metavar="OMEGA",
                        help="with --cubature: train it on exact GNL runs at these speeds (rad/s) instead of 6 of the "
                             "map's own")
    parser.add_argument("--capped-training", action="store_true",
                        help="with --cubature and --frequency-cap: the training runs and the GNL step's probe run "
                             "capped (a disk's always do), for bases whose unscaled GNL step makes the exact runs "
                             "hours long (--global-md 10)")
    parser.add_argument("--tolerance", type=float, metavar="TOL",
                        help="choose r_c, the frequency cap, the step and the GNL forces (with --disk: r_c, r_md, "
                             "r_cyclic, the cap and the GNL forces; GNL once the study has measured the disk's GNL "
                             "map) as the cheapest model within this relative error in "
                             "the speed-accuracy study (docs/choosing-a-model.md), in (0, 1)")
    parser.add_argument("--retry-diverged", type=int, metavar="N",
                        help="run the speeds that blew up again with the step halved, up to N times (0..4, default 0)")
    parser.add_argument("--mu", type=float, help="friction coefficient (default 0.15)")
    parser.add_argument("--c0", type=float, help="clearance at rest (m, default 0.5e-3)")
    parser.add_argument("--hb", type=float, help="height of the casing's bumps (m, default 0.625e-3)")
    parser.add_argument("--direction", choices=["x", "radial", "cone"],
                        help="contact normal: x (the paper's e_x, default), radial, cone (the casing cone's normal)")
    parser.add_argument("--rotation-sense", type=int, choices=[-1, 1],
                        help="the rotor turns about +z towards -theta (-1, rotor 37's, the default) or +theta (+1); a "
                             "sense that turns the blade with its trailing edge ahead (a mirrored blade) is refused")
    parser.add_argument("--rotation", choices=list(CLEARANCES),
                        help="the blade turns at each speed: centrifugal prestress and spin softening, each run from "
                             "its centrifugal state (GNL off: linearised about it), the clearance --c0 measured from "
                             "the running blade (running) or from the blade at rest (rest: the tip's centrifugal "
                             "growth eats it); the model built holds the centrifugal states at STOP/2 and STOP. "
                             "Default: at rest, the paper's")
    parser.add_argument("--batch", type=int, help="speeds integrated together (default 16)")
    parser.add_argument("--continuation", type=float,
                        help="speed step (rad/s) of a continuation up and down over the map's range (0: none, the "
                             "default); under mpirun the two branches run on ranks 0 and 1; resumable")
    parser.add_argument("--continuation-range", type=float, nargs=2, metavar=("LOW", "HIGH"),
                        help="run the continuation over this speed range (rad/s) instead of the map's: up from LOW, "
                             "down from HIGH (each first run as long as the map's, 15 %% of it after); a higher "
                             "HIGH with the same LOW extends the saved up branch from its last point (a lower LOW "
                             "with the same HIGH, the down branch); the --periodic orbits' range too; needs "
                             "--continuation or --periodic")
    parser.add_argument("--steady-window", type=int, metavar="N",
                        help="a continued run is steady when its max over the last N revolutions and the N before "
                             "agree to 2 %% (1, the paper's and the default: periodic with the rotor; N: periods up to "
                             "N T); needs --continuation")
    parser.add_argument("--unsteady-step", choices=["smallest", "full"],
                        help="the continuation's point where no halved step is steady: smallest (the paper read "
                             "literally, the default: the step stays divided) or full (the full step, marked not "
                             "steady: 8 times fewer points across an unsteady stretch); needs --continuation")
    parser.add_argument("--periodic", type=float, metavar="STEP",
                        help="also the periodic orbits of the map's scheme and casing over the continuation's range "
                             "(its --continuation-range, else the map's speeds), continued by arc length with this "
                             "relative step (e.g. 0.05; 0: none, the default), with their Floquet multipliers: "
                             "stable and unstable branches, folds, Neimark-Sacker points; a blade only")
    parser.add_argument("--out", type=Path, help="output folder (default results/contact_map)")
    parser.add_argument("--cache", type=Path, help="folder of the model, cubature and probe caches (default "
                                                   "OUT/cache; another map's to share its cubature)")
    parser.add_argument("--quiet", action="store_true", help="no progress bars")
    add_sector_options(parser)
    return parser


def parse_options(argv=None) -> dict:
    """The flat options (``OPTIONS``) of a command line (``build_parser``): those given, a user's sector's options
    gathered into ``mesh`` (a ``SectorFile``). An option given that does nothing with the others given is refused
    (ValueError naming it and what it needs: ``refuse_idle_options``)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    mesh = SectorFile.from_args(args, parser)
    options = {k: v for k, v in vars(args).items() if k not in SECTOR_OPTIONS}
    options |= {"mesh": mesh} if mesh is not None else {}
    refuse_idle_options(options)
    return options


def refuse_idle_options(given: dict) -> None:
    """ValueError naming the first option of ``given`` (the flat options a command line gave, defaults left out)
    that would do nothing: a model-building option with --model (the saved model is read as it is; --preset and
    --disk only with --stress, whose mesh they name), --seed without --mistuning, --continuation-range without
    --continuation or --periodic, --steady-window or --unsteady-step without --continuation, --r-cyclic (the disk's)
    without --disk, --global-md (the blade's) with --disk."""
    if given.get("model") is not None:
        for name in BUILD_OPTIONS:
            if name in given and not (name in STRESS_MESH_OPTIONS and given.get("stress")):
                why = ("names the mesh of --stress only" if name in STRESS_MESH_OPTIONS else "builds the model")
                raise ValueError(f"{_flag(name)} {why}: not with --model (the saved model is read as it is)")
    if "seed" in given and given.get("mistuning", 0) == 0:
        raise ValueError("--seed needs --mistuning > 0 (it seeds the mistuning's random factors; a tuned disk has "
                         "none)")
    if "continuation_range" in given and not (given.get("continuation", 0) or given.get("periodic", 0)):
        raise ValueError("--continuation-range needs --continuation STEP > 0 or --periodic STEP > 0 (it is the speed "
                         "range of their branches)")
    for name in ("steady_window", "unsteady_step"):
        if name in given and not given.get("continuation", 0):
            raise ValueError(f"{_flag(name)} needs --continuation STEP > 0 (it shapes the continuation's runs)")
    mesh = given.get("mesh")
    if "r_cyclic" in given and not given.get("disk") and (mesh is None or getattr(mesh, "cyclic", None) is None):
        raise ValueError("--r-cyclic (the disk's interface modes) needs --disk (or --mesh with a disk's sector)")
    if "global_md" in given and (given.get("disk") or getattr(mesh, "cyclic", None) is not None):
        raise ValueError("--global-md (the blade's modal derivatives of its clamped modes) does nothing with --disk "
                         "(its modal derivatives are --r-md's)")

