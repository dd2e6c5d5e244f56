# # Blade-tip/casing contact: interaction maps, NFRC and continuation (paper §2.3.1, §2.3.3, §3.4; Figs. 6, 7, 11, 12, 23, 24)
#
# Builds (or loads) a reduced model of the clamped blade, or with `--disk` of the whole 36-sector bladed disk (every
# blade's 8 tip nodes in contact, each blade at its own angle), then sweeps the angular speed with the casing ovalized
# into two lobes (eqs. 37-38; c0 = 0.5 mm, h_b = 0.625 mm, mu = 0.15), GNL off and on. Every speed's result is written as
# it finishes; a killed run started again resumes. The same command under `mpirun -n N` splits the speeds over the
# ranks (rank 0 builds the model, or give --model; with --cubature rank 0 trains; the others wait).
#
#     python demos/contact_map.py --preset ci --speeds 1200 1600 21 --revolutions 20          # minutes
#     python demos/contact_map.py --preset coarse --speeds 1200 1600 201 --revolutions 200      # paper scale (hours)
#     python demos/contact_map.py --disk --gnl off --direction cone --frequency-cap 60 --speeds 1200 1650 10 \
#         --out results/disk_map                                   # the bladed disk (minutes per speed batch)
#     mpirun -n 2 python demos/contact_map.py --model results/contact_map/rom.npz --speeds 1200 1600 21
#     OPENBLAS_NUM_THREADS=1 mpirun -n 2 python demos/contact_map.py --model results/contact_map/rom.npz --gnl on \
#         --cubature 1e-4 --precision single --frequency-cap 120 --mu 0 --speeds 1200 1600 100 --revolutions 200 \
#         --batch 50 --out results/headline     # the GNL headline map on 2 cores (docs/performance.md)
#
# The whole study is one function, `run_contact_map(ContactMapConfig(...))`, which returns a `ContactMapResult`; the
# command line only turns its options into that configuration. A bad option is one line on stderr and exit status 2.

# +
from __future__ import annotations

import argparse
import dataclasses
import functools
import hashlib
import importlib
import json
import logging
import numbers
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING, Sequence

import numpy as np
import scipy.linalg

from rotor37_rom.dynamics.casing import Casing, contact_matrices
from rotor37_rom.disk.assembly import mistuning_factors
from rotor37_rom.disk.harmonics import sector_harmonics
from rotor37_rom.cli import ArgumentParser, run_main
from rotor37_rom.viz.charts import plot_interaction_map, plot_nfrc, plot_time_history
from rotor37_rom.dynamics.friction import sprag_slip_friction
from rotor37_rom.geometry.blade import MESH_PRESETS
from rotor37_rom.dynamics.explicit import (CentralDifference, gnl_step_report, largest_states, probe_states, simulate,
    training_speeds)
from rotor37_rom.npz import load_npz, save_json, save_npz
from rotor37_rom.reduction.craig_bampton import GLOBAL_MD_MAX
from rotor37_rom.model.reduced import (ReducedModel, load_reduced_model, perturbed_model, save_reduced_model,
    with_force_precision)
from rotor37_rom.studies.sweep import (ContinuationPoint, InteractionMap, SweepSpec, continuation, interaction_map,
    idle_barrier, load_speed, load_sweep, record_row, rerun_diverged, run_sweep, sector_maxima, sweep_folder)

if TYPE_CHECKING:
    from mpi4py import MPI

PAPER = {"linear 1B/EO4": 1317.0, "zero IC, no GNL": 1446.0, "zero IC, GNL": 1535.0,
         "continuation, no GNL": 1520.0, "continuation, GNL": 1551.0}
GNL_SETTINGS = {"off": (False,), "on": (True,), "both": (False, True)}
PRECISIONS = ("double", "single")
N_SECTORS = 36                                     # rotor 37's blades (the disk sector of fem.create_disk_sector)
# -


# ## Configuration
#
# One field per command-line option (`--frequency-cap` is `frequency_cap`), with the same defaults. Every check
# names the option it concerns, so that the command line can report it as is. Numbers are stored as floats, as the
# command line gives them: the cache keys of sweeps and cubatures hash them, and a run from Python then reuses the
# files of the same run from the shell.

# +
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


def continued_revolutions(revolutions: float) -> float:
    """Length of each continued run: 15 % of the first (the paper: 200 then 30), at least 5 revolutions."""
    return max(5.0, revolutions * 0.15)


@dataclasses.dataclass(frozen=True)
class ContactMapConfig:
    """What to compute: the reduced model, the speeds, the scheme, the casing and the continuation.

    Attributes:
        preset: mesh preset of the blade the model is built on (and the cubature trained on): ci, coarse, paper.
        model: a saved reduced model (.npz) to load instead of building one (under MPI rank 0 builds it, the
            others load it).
        disk: build the model of the 36-sector bladed disk (``disk_builder``: every sector's 8 tip nodes, modal
            derivatives by MI 2b, ``r_cyclic`` interface modes) instead of the clamped blade's.
        r_c: fixed-interface modes (per sector) of the model built (>= 1). None: 15 for the blade, 10 for the disk.
        r_md: modal derivatives (per sector) selected by the criterion (>= 0). None: 0 for the blade, 10 for the disk.
        global_md: also the modal derivatives of the first N clamped modes (0..20; the blade's).
        contact_patch: 0 (point contact at the tip nodes, the paper's), or a radius (m, at most 0.01) of the tip
            patches over which each node's contact force spreads (``ReductionConfig.contact_patch``; the blade's
            model built here, not a --model or the disk's).
        r_cyclic: the disk's interface modes (eq. 51, >= 1; the paper's 144).
        mistuning: the disk's blade-to-blade stiffness scatter, a standard deviation in [0, 1) (0: tuned).
        seed: of the mistuning's random factors.
        sector: the sector whose node LE makes the map and the NFRC (0 .. 35; the blade: 0).
        stress: a disk's von Mises stress at t_max of each map's largest response, every sector rebuilt from q (the
            blade's: demos/report.py).
        speeds: (START, STOP, N): N angular speeds (rad/s) from START to STOP.
        revolutions: rotor revolutions simulated at each speed (> 0).
        gnl: geometric nonlinearity: 'off', 'on' or 'both' (one map each).
        safety: h = safety x 2 / omega_max of the linear model, in (0, 1].
        h: time step (s); overrides ``safety``. None: from ``safety``.
        frequency_cap: spectral mass scaling (kHz): the modes above it are slowed to it; a GNL step then comes from
            the tangent limit on a short unscaled probe run. None: no scaling.
        tangent_safety: with a cap, the GNL step is this x 2 / the largest tangent frequency, in (0, 1].
        step_outliers: with a cap, 'keep' (the GNL step from every step state) or 'drop' (from the states other than
            ``integrator.step_outliers``, those above 10 times the median tangent frequency: on the ci blade at
            mu = 0.1 over 1,620-2,000 rad/s one of 204, a St. Venant-Kirchhoff collapse that alone sets a step 19
            times smaller). With 'drop' a run that stays near such a state at the larger step blows up and is
            flagged; its retries (``retry_diverged``) halve that step, which may still be above the one from every
            state, and the demo then says so. A brief pass may not blow up, so benchmarks/bench_gnl_vs_linear.py
            --step-check measures the dropped step's error against runs at the kept one.
        perturbation: the internal force K q + g(q) of the runs scaled by 1 + this, |.| < 0.01 (0: none), after
            the cubature is trained and the step set (``reduction.perturbed_model``; the same cubature and step,
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
        tolerance: choose r_c, the frequency cap, the step and the force evaluation of each setting (GNL off, on) as
            the cheapest model of the speed-accuracy study within this relative error (``model_choice.choose_model``
            on the scenes 'map-linear' and 'map-gnl', read from rotor37_rom/data/speed_accuracy.json), in (0, 1);
            with ``disk`` (tuned) r_c, r_md, r_cyclic, the cap and the force evaluation from the scenes
            'disk-map-linear' and 'disk-map-gnl' (measured with the cone normal and mu = 0.15). The options it sets
            must not be given with it. None: the options as given.
        retry_diverged: runs that blew up run again with the step halved, up to this many times (0..4).
        mu: Coulomb friction coefficient of the casing contact (paper 0.15).
        c0: clearance at rest (m).
        hb: height h_b of the casing's two bumps (m).
        direction: contact normal: 'x' (the paper's e_x), 'radial' or 'cone' (the conical casing's normal, 15.3 deg
            from radial: no sprag-slip divergence at any mu on this blade, docs/results.md).
        batch: speeds integrated together in one batch (>= 1).
        continuation: speed step (rad/s) of a continuation up and down (0: none).
        continuation_range: (LOW, HIGH) speeds (rad/s) of the continuation; None: the map's range.
        steady_window: a continued run is steady when its max over the last N revolutions and the N before agree.
        unsteady_step: the continuation's point when no halving is steady: 'smallest' (the paper read literally:
            the step stays divided) or 'full' (the full step, marked not steady; ``sweep.continuation``).
        out: folder of the charts, summary.json, the sweeps' records and the caches.
        cache: folder of the model, cubature, training-run and probe caches; None: OUT/cache. Maps in other folders
            given the same cache share its cubature (e.g. a few speeds run again at another step).
        quiet: no progress bars and no sprag-slip note.
    """

    preset: str = "ci"
    model: Path | None = None
    disk: bool = False
    r_c: int | None = None
    r_md: int | None = None
    global_md: int = 3
    contact_patch: float = 0.0
    r_cyclic: int = 144
    mistuning: float = 0.0
    seed: int = 0
    sector: int = 0
    stress: bool = False
    speeds: tuple[float, float, int] = (1200.0, 1600.0, 21)
    revolutions: float = 20.0
    gnl: str = "both"
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
    tolerance: float | None = None
    retry_diverged: int = 0
    mu: float = 0.15
    c0: float = 0.5e-3
    hb: float = 0.625e-3
    direction: str = "x"
    batch: int = 16
    continuation: float = 0.0
    continuation_range: tuple[float, float] | None = None
    steady_window: int = 1
    unsteady_step: str = "smallest"
    out: Path = Path("results/contact_map")
    cache: Path | None = None
    quiet: bool = False

    def __post_init__(self):
        """Check every option (ValueError naming it) and store the numbers as the command line gives them."""
        self._check_model()
        self._check_sweep()
        self._check_casing()
        self._check_scheme()
        self._check_continuation()
        self._normalise()

    def _check_model(self) -> None:
        """The mesh preset and the sizes of a model to build."""
        if self.preset not in MESH_PRESETS:
            raise ValueError(f"--preset must be one of {', '.join(MESH_PRESETS)}, got {self.preset!r}")
        if self.r_c is not None and not self.r_c >= 1:
            raise ValueError(f"--r-c must be >= 1, got {self.r_c}")
        if self.r_md is not None and not self.r_md >= 0:
            raise ValueError(f"--r-md must be >= 0, got {self.r_md}")
        if not 0 <= self.global_md <= GLOBAL_MD_MAX:
            raise ValueError(f"--global-md must be in 0..{GLOBAL_MD_MAX}, got {self.global_md}")
        if not self.r_cyclic >= 1:
            raise ValueError(f"--r-cyclic must be >= 1, got {self.r_cyclic}")
        if not (np.isfinite(self.contact_patch) and 0 <= self.contact_patch <= 0.01):
            raise ValueError(f"--contact-patch must be in [0, 0.01] m, got {self.contact_patch}")
        if self.contact_patch and (self.disk or self.model is not None):
            raise ValueError("--contact-patch shapes the blade's model built here: not with --disk or --model")
        if not 0 <= self.mistuning < 1:
            raise ValueError(f"--mistuning must be in [0, 1) (standard deviation of the blades' stiffness factors), "
                             f"got {self.mistuning}")
        if self.mistuning > 0 and not self.disk:
            raise ValueError("--mistuning needs --disk (it scatters the disk's blades)")
        limit = N_SECTORS - 1 if self.disk or self.model is not None else 0
        if not 0 <= self.sector <= limit:
            raise ValueError(f"--sector must be in [0, {limit}] ({'the disk' if limit else 'a single blade'}'s "
                             f"sectors), got {self.sector}")
        if self.stress and not (self.disk or self.model is not None):
            raise ValueError("--stress is the disk's (--disk or a disk --model); the blade's stress at t_max is "
                             "demos/report.py's")

    @property
    def modes(self) -> tuple[int, int]:
        """(r_c, r_md) of the model built: the options, or 15, 0 for the blade and 10, 10 for the disk; with
        ``tolerance`` the largest r_c (and r_md, a disk's) the settings' choices need."""
        r_c, r_md = (self.r_c if self.r_c is not None else (10 if self.disk else 15),
                     self.r_md if self.r_md is not None else (10 if self.disk else 0))
        if self.tolerance is not None and self.r_c is None:
            chosen = [self.choice(gnl).options for gnl in GNL_SETTINGS[self.gnl]]
            return max(c.get("r_c", r_c) for c in chosen), max(c.get("r_md", r_md) for c in chosen)
        return r_c, r_md

    @property
    def interface_modes(self) -> int:
        """r_cyclic of the disk model built: the option, or with ``tolerance`` the largest the settings' choices
        need (one model serves GNL off and on)."""
        if self.tolerance is not None and self.disk:
            return max(self.choice(gnl).options.get("r_cyclic", self.r_cyclic) for gnl in GNL_SETTINGS[self.gnl])
        return self.r_cyclic

    def choice(self, gnl: bool):
        """The speed-accuracy study's cheapest model within ``tolerance`` for one setting (a ModelChoice)."""
        return map_model(self.tolerance, gnl, disk=self.disk)

    def model_beyond_choice(self, gnl: bool) -> dict:
        """The options of the model built (r_c, r_md, a disk's r_cyclic) where they exceed one setting's choice: one
        model serves GNL off and on, the larger of their choices. Empty without ``tolerance`` or where they agree."""
        if self.tolerance is None:
            return {}
        built = {"r_c": self.modes[0], "r_md": self.modes[1], **({"r_cyclic": self.interface_modes} if self.disk
                                                                  else {})}
        chosen = self.choice(gnl).options
        return {k: v for k, v in built.items() if k in chosen and chosen[k] != v}

    def setting(self, gnl: bool) -> "ContactMapConfig":
        """The configuration one setting (GNL off or on) runs with: with ``tolerance``, its chosen options."""
        if self.tolerance is None:
            return self
        options = {k: v for k, v in self.choice(gnl).options.items() if k != "r_c"}
        return dataclasses.replace(self, tolerance=None, **options)

    def _check_sweep(self) -> None:
        """Speeds, run length, batches and retries."""
        if len(self.speeds) != 3 or not 0 < self.speeds[0] <= self.speeds[1] or not self.speeds[2] >= 1 \
                or not float(self.speeds[2]).is_integer():
            raise ValueError(f"--speeds: need 0 < START <= STOP and an integer N >= 1, got {list(self.speeds)}")
        if not self.revolutions > 0:
            raise ValueError(f"--revolutions must be > 0, got {self.revolutions}")
        if self.gnl not in GNL_SETTINGS:
            raise ValueError(f"--gnl must be one of {', '.join(GNL_SETTINGS)}, got {self.gnl!r}")
        if not self.batch >= 1:
            raise ValueError(f"--batch must be >= 1, got {self.batch}")
        if not 0 <= self.retry_diverged <= 4:
            raise ValueError(f"--retry-diverged must be in 0..4, got {self.retry_diverged}")

    def _check_casing(self) -> None:
        """Each casing option alone through rotor37_rom.dynamics.casing.Casing (its checks are per field)."""
        for flag, name, value in (("--c0", "c0", self.c0), ("--hb", "h_b", self.hb), ("--mu", "mu", self.mu),
                                  ("--direction", "direction", self.direction)):
            try:
                Casing(**{name: value})
            except ValueError as exc:
                raise ValueError(f"{flag}: {exc}") from None

    def _check_scheme(self) -> None:
        """Time step, frequency cap and the GNL forces."""
        if not 0 < self.safety <= 1:
            raise ValueError(f"--safety must be in (0, 1], got {self.safety}")
        if self.h is not None and not self.h > 0:
            raise ValueError(f"--h must be > 0 s, got {self.h}")
        if self.frequency_cap is not None and not self.frequency_cap > 0:
            raise ValueError(f"--frequency-cap must be > 0 kHz, got {self.frequency_cap}")
        if not 0 < self.tangent_safety <= 1:
            raise ValueError(f"--tangent-safety must be in (0, 1], got {self.tangent_safety}")
        if self.step_outliers not in ("keep", "drop"):
            raise ValueError(f"--step-outliers must be 'keep' or 'drop', got {self.step_outliers!r}")
        if self.step_outliers == "drop" and (self.frequency_cap is None or self.h is not None):
            raise ValueError("--step-outliers drop needs --frequency-cap and no --h (it chooses the GNL step from "
                             "the tangent limit)")
        if not (isinstance(self.perturbation, numbers.Real) and abs(self.perturbation) < 0.01):
            raise ValueError(f"--perturbation must be a number with |eps| < 0.01, got {self.perturbation}")
        if self.cubature is not None and not 0 < self.cubature < 1:
            raise ValueError(f"--cubature must be in (0, 1), got {self.cubature}")
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
        if self.capped_training and self.tolerance is not None:
            raise ValueError("--capped-training: not with --tolerance (the study measured the chosen models trained "
                             "unscaled)")
        if self.capped_training and (self.cubature is None or self.frequency_cap is None):
            raise ValueError("--capped-training needs --cubature and --frequency-cap (it runs the cubature's training "
                             "runs with the cap)")
        if self.tolerance is not None:
            if not (isinstance(self.tolerance, (int, float)) and 0 < self.tolerance < 1):
                raise ValueError(f"--tolerance must be in (0, 1) (a relative error: 0.05 = 5 %), got {self.tolerance}")
            if self.disk and self.mistuning > 0:
                raise ValueError("--tolerance with --mistuning: the speed-accuracy study measured the tuned disk; "
                                 "give the options")
            chosen = set().union(*(self.choice(gnl).options for gnl in GNL_SETTINGS[self.gnl]))
            defaults = {f.name: f.default for f in dataclasses.fields(self)}
            given = [name for name in sorted(chosen - {"r_c"}) if getattr(self, name) != defaults[name]]
            if self.r_c is not None:
                given.append("r_c")
            if given or self.model is not None or self.h is not None:
                names = [f"--{n.replace('_', '-')}" for n in given] + (["--model"] if self.model else []) \
                    + (["--h"] if self.h is not None else [])
                raise ValueError(f"--tolerance chooses {', '.join(names)}: give either the tolerance or the options")

    def _check_continuation(self) -> None:
        """Continuation step, range and steadiness window."""
        if not self.continuation >= 0:
            raise ValueError(f"--continuation must be >= 0 rad/s (0: none), got {self.continuation}")
        if self.continuation_range is not None and (len(self.continuation_range) != 2
                                                    or not 0 < self.continuation_range[0] < self.continuation_range[1]):
            raise ValueError(f"--continuation-range: need 0 < LOW < HIGH rad/s, got {list(self.continuation_range)}")
        half = continued_revolutions(self.revolutions) / 2
        if not 1 <= self.steady_window <= half:
            raise ValueError(f"--steady-window must be in 1..{int(half)} revolutions (half of a continued run), got "
                             f"{self.steady_window}")
        if self.unsteady_step not in ("smallest", "full"):
            raise ValueError(f"--unsteady-step must be 'smallest' or 'full', got {self.unsteady_step!r}")

    def _normalise(self) -> None:
        """Floats, tuples and paths, as the command line gives them (same cache keys from Python and the shell)."""
        for name in ("revolutions", "safety", "h", "frequency_cap", "tangent_safety", "cubature", "mu", "c0", "hb",
                     "continuation", "mistuning", "perturbation"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, float(getattr(self, name)))
        start, stop, n = self.speeds
        object.__setattr__(self, "speeds", (float(start), float(stop), int(n)))
        if self.continuation_range is not None:
            object.__setattr__(self, "continuation_range", tuple(float(w) for w in self.continuation_range))
        if self.cubature_speeds is not None:
            object.__setattr__(self, "cubature_speeds", tuple(sorted({float(w) for w in self.cubature_speeds})))
        object.__setattr__(self, "out", Path(self.out))
        if self.cache is not None:
            object.__setattr__(self, "cache", Path(self.cache))
        if self.model is not None:
            object.__setattr__(self, "model", Path(self.model))

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
    def continuation_span(self) -> tuple[float, float]:
        """(LOW, HIGH) of the continuation (rad/s): ``continuation_range`` or the map's range."""
        return self.continuation_range or self.speeds[:2]

    @property
    def casing(self) -> Casing:
        """The casing and contact law."""
        return Casing(c0=self.c0, h_b=self.hb, mu=self.mu, direction=self.direction)

    @property
    def node(self) -> str:
        """The node whose response makes the map: LE of ``sector`` (a NodeMap label)."""
        return f"{self.sector}:LE"

    def sweep_spec(self, model: ReducedModel) -> SweepSpec:
        """The contact scenario each speed runs; a disk records node LE of every sector and TE of ``sector``."""
        monitor = None
        if model.nodes.n_sectors > 1:
            try:
                rows = [model.nodes.row("LE", s) for s in range(model.nodes.n_sectors)]
                rows += [model.nodes.row("TE", self.sector)] if "TE" in model.nodes.names else []
                monitor = tuple(rows)
            except ValueError as exc:
                raise ValueError(f"--sector: {exc}") from None
        elif self.sector != 0:
            raise ValueError(f"--sector must be 0 for a single blade's model, got {self.sector}")
        return SweepSpec(revolutions=self.revolutions, casing=self.casing, batch_size=self.batch, monitor=monitor)

    @property
    def frequency_cap_rad_s(self) -> float | None:
        """``frequency_cap`` in rad/s (None: no cap)."""
        return None if self.frequency_cap is None else 2 * np.pi * 1e3 * self.frequency_cap
# -


# ## Results
#
# One `MapResult` per GNL setting ('no GNL', 'GNL', with the cubature and the cap in the label when used): its
# interaction map, the speeds run again with a smaller step and the continuation branches. `ContactMapResult` holds
# them with what the run wrote. Under MPI rank 0 gets them all; the other ranks get no maps and write nothing.

# +
@dataclasses.dataclass(frozen=True)
class Branch:
    """One continuation branch (§2.3.3): its accepted points, the step it ran with (s) and its wall time (s)."""

    points: list[ContinuationPoint]
    h: float
    wall_s: float

    @property
    def peak(self) -> ContinuationPoint:
        """The point of largest (finite) amplitude."""
        return max(self.points, key=lambda p: p.amplitude if np.isfinite(p.amplitude) else -1)


@dataclasses.dataclass(frozen=True)
class MapResult:
    """The interaction map of one setting.

    Attributes:
        label: chart and summary label, e.g. 'no GNL' or 'GNL, cubature 0.0001, cap 120 kHz'.
        tag: the same in file names, e.g. 'linear' or 'gnl_cub0.0001_cap120k'.
        folder: folder of the sweep's per-speed records (speeds run again are in sweeps of their own).
        imap: spectra and NFRC of node LE (speeds in rad/s, amplitudes in m; NaN where a run diverged).
        h: time step of the sweep (s); h_crit: 2 / omega_max of its scheme (s).
        retried: {speed (rad/s): step of its last retry (s)} for the speeds run again after a blow-up.
        wall_s: wall time of the sweep and its retries (s).
        branches: {'up' | 'down': Branch}, empty without a continuation.
    """

    label: str
    tag: str
    folder: Path
    imap: InteractionMap
    h: float
    h_crit: float
    retried: dict[float, float]
    wall_s: float
    branches: dict[str, Branch]

    @property
    def speeds(self) -> np.ndarray:
        """Angular speeds of the map (rad/s)."""
        return self.imap.speeds

    @property
    def nfrc(self) -> np.ndarray:
        """Max |u_LE,r| over the last revolution at each speed (m); NaN where the run diverged."""
        return self.imap.nfrc

    @property
    def diverged(self) -> np.ndarray:
        """Whether each speed's run blew up (after its retries)."""
        return self.imap.diverged

    @property
    def peak_speed(self) -> float:
        """The speed of largest response (rad/s); NaN when every run diverged."""
        ok = np.isfinite(self.nfrc)
        return float(self.speeds[ok][np.argmax(self.nfrc[ok])]) if ok.any() else float("nan")


@dataclasses.dataclass(frozen=True)
class ContactMapResult:
    """What ``run_contact_map`` produced.

    Attributes:
        out: the output folder.
        eigenfrequencies: the model's first three frequencies omega_1..3 (rad/s).
        linear_resonance: omega_1 / 4, where 1B crosses engine order 4 (rad/s).
        runs: {label: MapResult} of this call (rank 0; empty on the other ranks).
        summary: the content of summary.json (rank 0; with the runs of an earlier call on the same set-up).
        files: the files written: the model built (if any), the charts and summary.json.
    """

    out: Path
    eigenfrequencies: np.ndarray
    linear_resonance: float
    runs: dict[str, MapResult]
    summary: dict
    files: list[Path]
# -


# ## The reduced model
#
# Loaded from `--model`, or built serially from the blade mesh (Craig-Bampton with r_c fixed-interface modes and
# modal derivatives, exact cubic tensors) and saved as `<out>/rom.npz` for later runs and MPI runs.

# +
def reduced_model(config: ContactMapConfig, comm: MPI.Comm | None) -> tuple[ReducedModel, list[Path]]:
    """The model of ``config.model``, or one built and saved; returns it and the files written."""
    if config.model is not None:
        try:
            return load_reduced_model(config.model), []
        except ValueError as exc:
            raise ValueError(f"--model: {exc}") from None
    if comm is None or comm.size == 1:
        model = build_model(config)
        return model, [save_reduced_model(model, config.out / "rom.npz")]
    # under MPI rank 0 builds (the reduction is serial: its own copy of the mesh) and saves; the others load
    importlib.import_module("rotor37_rom.fem")    # on every rank: importing dolfinx initializes PETSc (collective)
    error, path = None, None
    if comm.rank == 0:
        try:
            path = save_reduced_model(build_model(config), config.out / "rom.npz")
        except ValueError as exc:
            error = str(exc)
    idle_barrier(comm)
    error, path = comm.bcast((error, path), root=0)
    if error is not None:
        raise ValueError(error)
    return load_reduced_model(path), [path] if comm.rank == 0 else []


def build_model(config: ContactMapConfig) -> ReducedModel:
    """Build the reduced model of the ``config.preset`` blade, or of the bladed disk (cached in ``config.cache_dir``),
    in this process alone."""
    from mpi4py import MPI

    from rotor37_rom import fem

    r_c, r_md = config.modes
    t0 = time.perf_counter()
    if config.disk:
        from rotor37_rom.disk.builder import DiskReductionConfig, build_disk_model

        sector = fem.create_disk_sector(MPI.COMM_SELF, preset=config.preset)
        factors = None if config.mistuning == 0 else tuple(mistuning_factors(N_SECTORS, config.mistuning,
                                                                              config.seed).tolist())
        # without GNL no sector force is evaluated: the exact tensors (most of a build) are not built
        reduction = DiskReductionConfig(tip_nodes="all", r_c=r_c, r_md=r_md, criterion="MI2b",
                                        r_cyclic=config.interface_modes, mistuning=factors,
                                        forces="none" if config.gnl == "off" else "intrusive")
        model, _ = build_disk_model(sector, reduction, cache_dir=config.cache_dir)
    else:
        from rotor37_rom.reduction.builder import ReductionConfig, build_reduced_model

        sector = fem.create_blade_sector(MPI.COMM_SELF, preset=config.preset)
        reduction = ReductionConfig(r_c=r_c, r_md=r_md, global_md_modes=config.global_md, forces="intrusive",
                                    contact_patch=config.contact_patch)
        model, _ = build_reduced_model(sector, reduction, cache_dir=config.cache_dir)
    print(f"reduced model: {config.preset} preset ({sector.n_dofs} DOF) -> r = {model.r} {model.sizes} "
          f"in {time.perf_counter() - t0:.1f} s")
    return model


def eigenfrequencies(model: ReducedModel) -> np.ndarray:
    """The first three frequencies of the reduced model (rad/s)."""
    return np.sqrt(scipy.linalg.eigh(model.K, model.M, eigvals_only=True)[:3])


def eo4_frequency(model: ReducedModel) -> float:
    """The 1B frequency engine order 4 meets (rad/s): omega_1 of a blade; for a disk the lowest mode of 4 nodal
    diameters (the stationary two-lobe casing excites k = 4 through EO4 on a tuned disk)."""
    if model.sectors is None:
        return float(eigenfrequencies(model)[0])
    lam, V = scipy.linalg.eigh(model.K, model.M, subset_by_index=[0, 3 * model.nodes.n_sectors - 1])
    k = sector_harmonics(V, model.sectors.blocks)
    return float(np.sqrt(lam[k == 4].min())) if (k == 4).any() else float(np.sqrt(lam[0]))


def sprag_slip_onsets(model: ReducedModel, casing: Casing, sector: int = 0) -> dict:
    """Friction coefficients at which sustained sliding on the casing diverges (rotor37_rom.dynamics.friction): per contact
    node of ``sector`` (a tuned disk's sectors are alike) and for all contact nodes together."""
    N, S, _, rows = contact_matrices(model.nodes, model.r, casing)
    mine = [k for k, row in enumerate(rows) if model.nodes.sector[row] == sector]
    G = np.linalg.inv(model.K)                          # once, not per node (r = 1,728 on the disk)
    single = [sprag_slip_friction(model.K, N, S, [k], compliance=G) for k in mine]
    return {"weakest_node": min(single), "per_node": single,
            "all_nodes": sprag_slip_friction(model.K, N, S, compliance=G)}


def _finite(x: float) -> float | None:
    """x, or None for inf (JSON has no inf: null = friction never wedges these nodes)."""
    return x if np.isfinite(x) else None


def model_summary(config: ContactMapConfig, model: ReducedModel, omega: np.ndarray, onset: dict) -> dict:
    """The summary.json entries of the model and the set-up (its 'runs' still empty)."""
    return {"r": model.r, "sizes": model.sizes, "omega_1_3": omega.tolist(), "linear_resonance": eo4_frequency(model) / 4,
            "node": config.node, "disk": model.sectors is not None,
            "mistuning": model.metadata.get("config", {}).get("mistuning"),
            "speeds": list(config.speeds), "revolutions": config.revolutions, "casing": vars(config.casing),
            "runs": {}, "sprag_slip": {k: ([_finite(x) for x in v] if isinstance(v, list) else _finite(v))
                                       for k, v in onset.items()}}
# -


# ## Time step and GNL forces
#
# Without GNL the step is `safety` x 2 / omega_max (or `--h`). With GNL and `--cubature`, the exact cubic forces are
# replaced by point cubature trained on exact GNL runs at 6 of the speeds; with a frequency cap the GNL step comes
# from the tangent frequencies of the states a GNL run reaches (the cubature's training runs, or a short probe).

# +
def cubature_model(config: ContactMapConfig, model: ReducedModel, comm: MPI.Comm | None
                   ) -> tuple[ReducedModel, np.ndarray]:
    """The model with point-cubature GNL forces trained on exact GNL runs at 6 of the speeds (trajectory states), and
    the states the GNL step is taken over (those runs' 24 of largest tip motion and the training states). Cached in
    ``config.cache_dir``: a restarted map does not retrain, and another tolerance reuses the exact training runs.
    Under MPI rank 0 trains (serial FE quadrature on its own copy of the mesh) while the others wait."""
    importlib.import_module("rotor37_rom.fem")    # on every rank: importing dolfinx initializes PETSc (collective)
    train = training_speeds(config.speed_grid) if config.cubature_speeds is None else \
        np.asarray(config.cubature_speeds, float)
    revolutions = min(config.revolutions, 12.0)
    if capped_probe(config, model):
        # a disk's unscaled GNL step (~5e-8 s) would make the training runs hours long: they run capped, at the
        # tangent limit on the capped probe's states (exact forces); a blade's with --capped-training. The training
        # runs take the step from every probe state (--step-outliers is the map's): a step check at 'keep' then
        # finds the same cubature
        scheme = CentralDifference(model, nonlinear=True, safety=config.safety,
                                   frequency_cap=config.frequency_cap_rad_s,
                                   h=config.h or capped_gnl_step(dataclasses.replace(config, step_outliers="keep"),
                                                                  model, model, None,
                                                                  verbose=comm is None or comm.rank == 0))
    else:
        scheme = CentralDifference(model, nonlinear=True, safety=config.safety)
    runs = [model.key, train.tolist(), revolutions, scheme.h, vars(config.casing)]
    key = hashlib.sha256(json.dumps(runs + [config.cubature, "step states: largest and training"],
                                    sort_keys=True, default=str).encode()).hexdigest()[:16]
    cache = config.cache_dir / f"cubature_{key}.npz"
    runs_key = json.dumps(runs + ["states every 1e-5 s; step states: largest and training"], sort_keys=True,
                          default=str)
    runs_cache = config.cache_dir / f"training_runs_{hashlib.sha256(runs_key.encode()).hexdigest()[:16]}.npz"
    rank = 0 if comm is None else comm.rank
    if cache.is_file():
        if rank == 0:
            print(f"cubature: reusing {cache}")
    else:
        error = None
        if rank == 0:
            try:
                _train_cubature(config, model, scheme, train, revolutions, cache, runs_cache)
            except ValueError as exc:
                error = str(exc)
        if comm is not None:
            idle_barrier(comm)
            error = comm.bcast(error, root=0)
        if error is not None:
            raise ValueError(error)
    with np.load(cache.with_suffix(".states.npz")) as data:
        states = data["states"]
    return load_reduced_model(cache), states


def _train_cubature(config: ContactMapConfig, model: ReducedModel, scheme: CentralDifference, train: np.ndarray,
                    revolutions: float, cache: Path, runs_cache: Path) -> None:
    """Train the point cubature on exact GNL runs at ``train`` (their states kept in ``runs_cache``, for another
    tolerance) and save it with the step states to ``cache``."""
    from mpi4py import MPI

    from rotor37_rom import fem
    from rotor37_rom.reduction.builder import hyper_reduce
    from rotor37_rom.dynamics.explicit import contact_training_states

    casing = config.casing
    t0 = time.perf_counter()
    runs = load_npz(runs_cache, ("train", "step"), what="training runs")
    if runs is not None:
        Q_train, step_states = runs["train"], runs["step"]
    else:
        checkpoint = runs_cache.with_suffix(".ckpt.npz")
        Q_train, step_states = contact_training_states(scheme, train, casing, revolutions, checkpoint=checkpoint)
        save_npz(runs_cache, train=Q_train, step=step_states)
        checkpoint.unlink(missing_ok=True)
    create = fem.create_disk_sector if model.sectors is not None else fem.create_blade_sector
    sector = create(MPI.COMM_SELF, preset=config.preset)
    reduced, rep = hyper_reduce(sector, model, Q_train, tol=config.cubature, level="point",
                                label=f"contact runs {train.tolist()} x {revolutions:g} rev, mu = {casing.mu:g}")
    print(f"cubature: {rep['points']} of {rep['exact'].w.size} quadrature points (training error "
          f"{rep['result'].training_error:.1e}) from {Q_train.shape[1]} states of exact GNL runs at "
          f"{len(train)} speeds x {revolutions:g} rev; {time.perf_counter() - t0:.0f} s")
    save_npz(cache.with_suffix(".states.npz"), states=step_states)
    save_reduced_model(reduced, cache)                  # written last: its presence means both are complete


def capped_probe(config: ContactMapConfig, model: ReducedModel) -> bool:
    """Whether the GNL training runs and step probe run with the frequency cap: a disk's always (its unscaled step
    is ~5e-8 s), a blade's with --capped-training."""
    return config.frequency_cap is not None and (model.sectors is not None or config.capped_training)


def capped_gnl_step(config: ContactMapConfig, model: ReducedModel, run_model: ReducedModel,
                    states: np.ndarray | None, verbose: bool = True) -> float:
    """The GNL step with a frequency cap, from the tangent limit on ``states`` (None: on a short unscaled probe;
    for a disk, whose unscaled step is ~5e-8 s, or with --capped-training, a capped GNL probe at 4 of the speeds,
    its 8 largest states)."""
    if states is None:
        revolutions = min(4.0, config.revolutions)
        if capped_probe(config, model):
            probe = training_speeds(config.speed_grid, 4)
            states, h_probe = capped_probe_states(config, model, probe, revolutions)
            kind = f"capped (h = {h_probe:.3g} s)"
        else:
            probe = config.speed_grid[:: max(1, config.speeds[2] // 16)]
            states = probe_states(model, probe, config.casing, revolutions=revolutions)
            kind = "unscaled"
        if verbose:
            print(f"GNL step from the tangent limit on a {revolutions:g}-revolution {kind} probe at {len(probe)} "
                  f"speeds")
    step = gnl_step_report(run_model, states, config.frequency_cap_rad_s, safety=config.tangent_safety,
                           cap_safety=config.safety)
    drop = config.step_outliers == "drop" and step["h_without_outliers"] > step["h"]
    h = step["h_without_outliers"] if drop else step["h"]
    if verbose:
        print(f"GNL with a {config.frequency_cap:g} kHz cap: h = {h:.3g} s")
        print_step_outliers(step, dropped=drop)
    return h


def print_step_outliers(step: dict, dropped: bool = False) -> None:
    """A line when a few states set the GNL step far below the others' (``integrator.step_outliers``), and whether
    the step was taken without them (--step-outliers drop)."""
    out = step["outliers"]
    if out.size and step["h_without_outliers"] > step["h"]:
        w = step["w_states"]
        ratio = step["h_without_outliers"] / step["h"]
        head = (f"note: {out.size} of {w.size} states would set the GNL step: their tangent's highest frequency "
                f"reaches {w[out].max() / 2e3 / np.pi:.4g} kHz, the others' at most "
                f"{np.delete(w, out).max() / 2e3 / np.pi:.4g} kHz; ")
        if dropped:
            tail = (f"--step-outliers drop takes the step without them, {ratio:.1f} times the {step['h']:.3g} s they "
                    f"set; a run that stays near such a state blows up and is flagged, a brief pass may not "
                    f"(benchmarks/bench_gnl_vs_linear.py --step-check measures the error).")
        else:
            tail = (f"without them the step would be {step['h_without_outliers']:.3g} s, so the GNL runs at this "
                    f"step take {ratio:.1f} times as many steps (--step-outliers drop). Such states may be where the "
                    f"St. Venant-Kirchhoff model collapses under a point contact (docs/results.md, 'GNL against "
                    f"linear with the paper's friction').")
        print(head + tail)


def capped_probe_states(config: ContactMapConfig, model: ReducedModel, probe: np.ndarray, revolutions: float
                        ) -> tuple[np.ndarray, float]:
    """The 8 largest states of a capped GNL run of the disk or blade (exact forces) at the ``probe`` speeds, its step
    halved until no speed blows up (the capped modes stiffen with the amplitude), and that step. Cached in
    ``config.cache_dir`` (a resumed map does not probe again; every rank computes or reads the same)."""
    scheme = CentralDifference(model, nonlinear=True, safety=config.safety, frequency_cap=config.frequency_cap_rad_s)
    key = json.dumps([model.key, probe.tolist(), revolutions, scheme.h, scheme.frequency_cap, vars(config.casing),
                      "8 largest states"], sort_keys=True, default=str)
    cache = config.cache_dir / f"gnl_probe_{hashlib.sha256(key.encode()).hexdigest()[:16]}.npz"
    cached = load_npz(cache, ("states", "h"), what="probe")
    if cached is not None:
        return cached["states"], float(cached["h"])
    for _ in range(5):
        res = simulate(scheme, probe, config.casing, revolutions=revolutions, on_blowup="flag", record_q=True,
                       record_every=max(1, int(round(2e-5 / scheme.h))))
        if (res.diverged_step < 0).all():
            break
        scheme = scheme.with_step(scheme.h / 2)
    else:
        raise ValueError(f"--h: the capped GNL probe diverged down to h = {scheme.h:.3g} s; give a smaller "
                         f"step or a higher --frequency-cap")
    states = largest_states(res, scheme.boundary_rows, 8)
    save_npz(cache, states=states, h=scheme.h)           # ranks may write it side by side
    return states, scheme.h


def time_scheme(config: ContactMapConfig, model: ReducedModel, gnl: bool, comm: MPI.Comm | None,
                h: float | None = None) -> CentralDifference:
    """The central-difference scheme of one setting: its forces (exact or cubature), step and frequency cap; with a
    perturbation, the perturbed model's scheme with the same cap at the unperturbed model's step (the cap applies to
    the perturbed model: its modes above the cap stay at the cap, their capped mass scaled with their stiffness).
    ``h``: the step to run at instead of the setting's (a record's own, e.g. a retried speed's); the forces stay the
    setting's (a disk's cubature is trained at the setting's step, so replacing ``config.h`` would train another)."""
    run_model, states, h = model, None, config.h if h is None else h
    if gnl and config.cubature is not None:
        run_model, states = cubature_model(config, model, comm)
        run_model = with_force_precision(run_model, config.precision)
    if gnl and config.frequency_cap is not None and h is None:
        h = capped_gnl_step(config, model, run_model, states, verbose=comm is None or comm.rank == 0)
    scheme = CentralDifference(run_model, nonlinear=gnl, h=h, safety=config.safety,
                               frequency_cap=config.frequency_cap_rad_s)
    if not config.perturbation:
        return scheme
    return CentralDifference(perturbed_model(run_model, config.perturbation), nonlinear=gnl, h=scheme.h,
                             frequency_cap=config.frequency_cap_rad_s)


def setting_names(config: ContactMapConfig, gnl: bool) -> tuple[str, str]:
    """(chart label, file tag) of one setting, e.g. ('GNL, cubature 0.0001, single', 'gnl_cub0.0001_f32')."""
    parts = [("GNL", "gnl") if gnl else ("no GNL", "linear")]
    if gnl and config.cubature is not None:
        parts.append((f"cubature {config.cubature:g}", f"cub{config.cubature:g}"))
        if config.precision == "single":
            parts.append(("single", "f32"))
    if config.frequency_cap is not None:
        parts.append((f"cap {config.frequency_cap:g} kHz", f"cap{config.frequency_cap:g}k"))
    if config.perturbation:
        parts.append((f"x (1 + {config.perturbation:g})", f"pert{config.perturbation:g}"))
    return ", ".join(p[0] for p in parts), "_".join(p[1] for p in parts)
# -


# ## One map: sweep, retries, continuation
#
# Every speed starts from rest (§2.3.1); speeds that blew up run again with the step halved (`--retry-diverged`).
# The continuation (§2.3.3) then runs up and down at the step all the map's speeds ran with.

# +
def sweep_map(config: ContactMapConfig, scheme: CentralDifference, comm: MPI.Comm | None
              ) -> tuple[Path, list[dict], dict[float, float], float]:
    """Run the map's speeds and retry those that blew up. Returns the sweep folder, the per-speed records (rank 0;
    [] on the others), {retried speed: its last step} and the wall time (s)."""
    rank = 0 if comm is None else comm.rank
    spec, speeds, sweeps = config.sweep_spec(scheme.model), config.speed_grid, config.out / "sweeps"
    t0 = time.perf_counter()
    folder = run_sweep(scheme, speeds, spec, sweeps, comm=comm, progress=not config.quiet)
    # rank 0 reads the records (~1 GB for the 100-speed headline map); rerun_diverged tells the others
    records = [r for r in load_sweep(folder) if np.isclose(float(r["omega"]), speeds).any()] if rank == 0 else []
    records, retried = rerun_diverged(scheme, records, spec, sweeps, config.retry_diverged, comm=comm,
                                      progress=not config.quiet)
    return folder, records, retried, time.perf_counter() - t0


def continuation_branches(config: ContactMapConfig, scheme: CentralDifference, retried: dict[float, float],
                          tag: str, comm: MPI.Comm | None) -> dict[str, Branch]:
    """Continuation up and down (§2.3.3) at the step the map's speeds all ran with (the smallest retry step, if any
    speed was run again), the first run as long as the map's, the next 15 % of it (the paper: 200 then 30).
    Under MPI the two branches run on ranks 0 and 1 at once; rank 0 gets both. Each branch is written after every
    accepted speed (``sweep.continuation(out=...)``), so a killed run resumes. Returns {'up' | 'down': Branch}."""
    if config.continuation <= 0:
        return {}
    run_scheme = scheme.with_step(min(retried.values())) if retried else scheme
    start, stop = config.continuation_span
    legs = {"up": (start, stop), "down": (stop, start)}
    rank, size = (0, 1) if comm is None else (comm.rank, comm.size)
    mine = {}
    for k, (name, (a, b)) in enumerate(legs.items()):
        if k % size == rank:
            t0 = time.perf_counter()
            points = continuation(run_scheme, a, b, config.continuation, config.casing,
                                  first_revolutions=config.revolutions,
                                  revolutions=continued_revolutions(config.revolutions),
                                  out=config.out / "continuation" / tag, window=config.steady_window,
                                  unsteady=config.unsteady_step, node=config.node,
                                  progress=not config.quiet)
            mine[name] = Branch(points, run_scheme.h, time.perf_counter() - t0)
    if comm is not None:
        idle_barrier(comm)                                # the branches take hours apart
        gathered = comm.gather(mine, root=0)
        mine = {k: v for part in gathered for k, v in part.items()} if rank == 0 else {}
    return mine
# -


# ## Charts, summary and report
#
# Each map gives an interaction map, the LE/TE time history of its largest bounded response and, with a continuation,
# the NFRC of both branches next to the zero-IC map. summary.json keeps the runs of an earlier call on the same
# model, speeds and revolutions, and nfrc.png draws them all.

# +
def chart_map(config: ContactMapConfig, result: MapResult, records: list[dict], omega: np.ndarray, r: int,
              lin_res: float) -> list[Path]:
    """Draw the interaction map, the time history of the largest response and the continuation NFRC (if any)."""
    out, imap = config.out, result.imap
    files = [plot_interaction_map(imap, out / f"interaction_map_{result.tag}.png", eigenfrequencies=omega,
                                  linear_resonance=lin_res,
                                  title=f"node {config.node}, {result.label}, r = {r}, {config.revolutions:g} rev., "
                                        f"h = {result.h:.3g} s")]
    ok = np.isfinite(imap.nfrc)
    worst = records[int(np.nanargmax(np.where(ok, imap.nfrc, -1)))] if ok.any() else records[0]
    curves = {name: worst["u_r"][record_row(worst, f"{config.sector}:{name}")] for name in ("LE", "TE")
              if f"{config.sector}:{name}" in map(str, worst["labels"])}
    files.append(plot_time_history(worst["t"], curves,
                                   out / f"time_history_{result.tag}.png",
                                   title=f"{result.label}, Omega = {float(worst['omega']):.0f} rad/s"))
    if result.branches:
        curves = {f"continuation {name}": ([p.omega for p in b.points], [p.amplitude for p in b.points],
                                           "+" if name == "up" else "o") for name, b in result.branches.items()}
        curves["zero IC"] = (imap.speeds, imap.nfrc, "--")
        files.append(plot_nfrc(curves, out / f"nfrc_continuation_{result.tag}.png", lin_res, PAPER))
    return files


def summary_entry(config: ContactMapConfig, scheme: CentralDifference, result: MapResult, records: list[dict]
                  ) -> dict:
    """The summary.json entry of one map: step, forces, NFRC, contact works and checks, continuation branches."""
    imap, wall = result.imap, result.wall_s
    works = np.array([np.asarray(r.get("work", np.full(4, np.nan)), float)[:2] for r in records])
    entry = {"h": scheme.h, "h_crit": scheme.h_crit, "frequency_cap_khz": config.frequency_cap,
             "step_outliers": config.step_outliers if scheme.nonlinear else None,
             "perturbation": config.perturbation, "model_key": scheme.model.key,
             "cubature": scheme.model.metadata.get("hyper_reduction"),
             # from the metadata: a disk's sector forces wrap the quadrature forces that carry the precision
             "force_precision": scheme.model.metadata.get("force_precision", "double"), "peak_speed": result.peak_speed,
             "peak_amplitude": float(np.nanmax(imap.nfrc)),
             "diverged": imap.speeds[imap.diverged].tolist(), "wall_s": wall,
             "retried": {f"{w:g}": hk for w, hk in result.retried.items()},
             "rev_per_s": config.revolutions * len(records) / wall if wall > 1 else None, "nfrc": imap.nfrc.tolist(),
             "work_normal_J": works[:, 0].tolist(), "work_friction_J": works[:, 1].tolist(),
             "speeds": imap.speeds.tolist(), "contact_checks": {
                 "max_penetration": max(float(r["max_penetration"]) for r in records),
                 "min_multiplier": min(float(r["min_multiplier"]) for r in records),
                 "max_friction_power": max(float(r["friction_power"]) for r in records)}}
    if len({label.partition(":")[0] for label in map(str, records[0]["labels"])}) > 1:     # a disk: every LE
        per_sector = [sector_maxima(r) for r in records]
        entry["largest_over_sectors"] = [float(np.nanmax(a)) if np.isfinite(a).any() else None for a in per_sector]
        entry["largest_sector"] = [int(np.nanargmax(a)) if np.isfinite(a).any() else None for a in per_sector]
    for name, branch in result.branches.items():
        entry[f"continuation_{name}_peak"] = branch.peak.omega
        entry[f"continuation_{name}"] = [(p.omega, p.amplitude, p.steady, p.halvings, p.period)
                                         for p in branch.points]
        entry[f"continuation_{name}_h"], entry[f"continuation_{name}_wall_s"] = branch.h, branch.wall_s
        entry["continuation_steady_window"] = config.steady_window
        entry["continuation_unsteady_step"] = config.unsteady_step
    return entry


def carry_on(config: ContactMapConfig, scheme: CentralDifference, result: MapResult, speed: float,
             monitor: Sequence[int] | None = None):
    """The map's run at ``speed`` carried on one revolution from its final state (its sweep record, at the step it
    ran with), the casing where it was, states recorded every ~1e-6 s. Returns (SimulationResult, its scheme, the
    time (s) the map's run ended at)."""
    run_scheme = scheme.with_step(result.retried[speed]) if speed in result.retried else scheme
    record = load_speed(sweep_folder(run_scheme, config.sweep_spec(scheme.model), config.out / "sweeps"), speed)
    res, t_end = carry_on_record(config, run_scheme, record, speed, monitor)
    return res, run_scheme, t_end


def carry_on_record(config: ContactMapConfig, run_scheme: CentralDifference, record: dict, speed: float,
                    monitor: Sequence[int] | None = None):
    """One revolution from a sweep ``record``'s final state, run with the scheme (and step) it ran with, the casing
    where it was. Returns (SimulationResult, the time (s) the record's run ended at)."""
    steps = int(np.ceil(config.revolutions * 2 * np.pi / speed / run_scheme.h))
    casing = config.casing
    res = simulate(run_scheme, [speed], casing, revolutions=1, initial=(record["q_final"], record["q_prev"]),
                   duration=1e-12, phase=casing.rotation_sense * speed * steps * run_scheme.h,
                   record_every=max(1, int(round(1e-6 / run_scheme.h))), record_q=True, on_blowup="flag",
                   monitor=monitor)
    return res, steps * run_scheme.h


def stress_mesh(config: ContactMapConfig, model: ReducedModel):
    """The disk sector's mesh the model was built on (for ``--stress``; made once per call of the study)."""
    from mpi4py import MPI

    from rotor37_rom import fem
    from rotor37_rom.reduction.builder import mesh_signature

    if model.sectors is None:
        raise ValueError("--stress needs a disk model (this one is a single blade's: demos/report.py draws its stress)")
    sector = fem.create_disk_sector(MPI.COMM_SELF, preset=config.preset)     # rank 0's own copy under mpirun
    if mesh_signature(sector) != model.metadata.get("mesh"):
        raise ValueError(f"--preset: the model was not built on the {config.preset} disk sector's mesh")
    return sector


def disk_stress_of(sector, model: ReducedModel, res, nonlinear: bool, monitor: int
                   ) -> tuple[np.ndarray, np.ndarray, dict, int]:
    """The disk's von Mises stress at t_max of a carried-on run ``res`` (one speed; its first recorded row is the
    monitored node): every sector's field rebuilt from q at the record of largest |u| (no reassembly) on the disk
    ``sector`` (``stress_mesh``), summarised for sector ``monitor`` and over the sectors
    (``analysis.disk_stress_summary``). Returns (the sectors' displacement fields, each sector's largest von Mises
    per cell, the numbers with ``u_le``, the record's index)."""
    from rotor37_rom.post.stress import disk_stress, disk_stress_summary

    u = res.u_r[0][0]
    k = int(np.nanargmax(np.abs(u)))
    fields, values = disk_stress(sector, model, res.records_q[0][:, k], nonlinear=nonlinear)
    numbers = disk_stress_summary(sector, model, values, monitor)
    numbers["u_le"] = float(u[k])
    return fields, values.max(axis=2), numbers, k


def disk_peak_stress(config: ContactMapConfig, scheme: CentralDifference, result: MapResult, tag: str, sector
                     ) -> tuple[dict, list[Path]]:
    """The whole bladed disk's von Mises stress at t_max (largest |u| of node LE of ``config.sector``) of the map's
    largest bounded response: that run carried on one revolution from its final state (as the report does for the
    blade), every sector's field rebuilt from q (no reassembly) on the disk ``sector`` (``stress_mesh``). Returns
    (numbers, [picture])."""
    from rotor37_rom.post.stress import describe_location
    from rotor37_rom.viz.plotting import render_stress

    model, speed = scheme.model, result.peak_speed
    if not np.isfinite(speed):
        return {"speed": None}, []
    res, run_scheme, t_start = carry_on(config, scheme, result, speed, [model.nodes.label_row(config.node)])
    if res.diverged_step[0] >= 0:
        return {"speed": speed, "diverged": True}, []
    fields, vm_sectors, numbers, k = disk_stress_of(sector, model, res, run_scheme.nonlinear, config.sector)
    numbers.update(speed=speed, t_max=t_start + float(res.t[0][k]))
    factor = 0.1 * 0.074 / max(np.abs(fields).max(), 1e-12)     # largest motion drawn at 10 % of the blade's span
    title = (f"{result.label}: von Mises at t_max, Omega = {speed:.0f} rad/s, node {config.node} (x{factor:.0f})")
    picture = render_stress(sector, fields[config.sector], vm_sectors, config.out / f"stress_disk_{tag}.png",
                            title, n_sectors=model.nodes.n_sectors, factor=factor, clim=numbers["clim"],
                            sector_displacements=fields)
    print(f"         stress at t_max ({speed:.0f} rad/s): sector {config.sector} {numbers['vm_max'] / 1e6:.0f} MPa "
          f"({numbers['ratio_yield']:.2f} sigma_Y) outside the tip band ({describe_location(numbers['location'])}), "
          f"largest over the sectors {numbers['vm_max_all_sectors'] / 1e6:.0f} MPa (sector {numbers['sector_of_max']}: "
          f"{describe_location(numbers['location_all_sectors'])}); off the root corner (> "
          f"{1e3 * numbers['root_band_m']:.0f} mm from the blade-rim junction): sector {config.sector} "
          f"{numbers['vm_max_off_root'] / 1e6:.0f} MPa ({numbers['ratio_yield_off_root']:.2f} sigma_Y, "
          f"{describe_location(numbers['location_off_root'])}), over the sectors "
          f"{numbers['vm_max_off_root_all_sectors'] / 1e6:.0f} MPa (sector {numbers['sector_of_max_off_root']})")
    return numbers, [picture]


def print_map(result: MapResult, linear_resonance: float) -> None:
    """One line per map (step, largest response, divergences) and one per continuation branch."""
    print(f"{result.label:>7}: h = {result.h:.3g} s (2/omega_max = {result.h_crit:.3g}), largest response at "
          f"{result.peak_speed:.0f} rad/s ({np.nanmax(result.nfrc) * 1e3:.3f} mm), linear 1B/EO4 "
          f"{linear_resonance:.0f} rad/s; {int(result.diverged.sum())} diverged ({len(result.retried)} run again "
          f"with a smaller step); {result.wall_s:.0f} s")
    for name, branch in result.branches.items():
        best = branch.peak
        unsteady = [f"{p.omega:.0f}" for p in branch.points if not p.steady]
        print(f"         continuation {name} (h = {branch.h:.3g} s, {branch.wall_s:.0f} s): largest response at "
              f"{best.omega:.0f} rad/s ({best.amplitude * 1e3:.3f} mm); {len(branch.points)} speeds, not steady at "
              f"{', '.join(unsteady) or 'none'}")


def merge_earlier_runs(summary: dict, previous: Path) -> None:
    """Add to ``summary['runs']`` the runs of an earlier summary.json of the same model, speeds and revolutions
    (this call's entries win, key by key)."""
    if not previous.is_file():
        return
    old = json.loads(previous.read_text())
    if (old.get("r"), old.get("speeds"), old.get("revolutions")) != (summary["r"], summary["speeds"],
                                                                      summary["revolutions"]):
        return
    for label, run in old.get("runs", {}).items():
        new = summary["runs"].get(label, {})
        merged = {**run, **new}
        if new and new.get("rev_per_s") is None and run.get("rev_per_s") and run.get("h") == new.get("h"):
            # a call that found every speed done keeps the wall time of the call that ran them
            merged["wall_s"], merged["rev_per_s"] = run["wall_s"], run["rev_per_s"]
        summary["runs"][label] = merged


def write_summary(out: Path, summary: dict) -> list[Path]:
    """Write nfrc.png (every run of the summary) and summary.json; returns their paths."""
    merge_earlier_runs(summary, out / "summary.json")
    curves = {}
    for label, run in summary["runs"].items():
        style = "-" if label.startswith("GNL") else "--"
        curves[label] = (np.array(run["speeds"]), np.array(run["nfrc"]), style)
        if "largest_over_sectors" in run:                  # a disk: also the largest over the blades
            largest = np.array([np.nan if a is None else a for a in run["largest_over_sectors"]], float)
            curves[f"{label}: largest over the blades"] = (np.array(run["speeds"]), largest,
                                                           "-." if label.startswith("GNL") else ":")
    chart = plot_nfrc(curves, out / "nfrc.png", summary["linear_resonance"], PAPER)
    return [chart, save_json(out / "summary.json", summary, indent=1, default=float)]
# -


# ## The study
#
# The model, its sprag-slip onsets (the friction coefficient from which sustained sliding grows), then one map per
# GNL setting. Under MPI every rank runs its share of the speeds and rank 0 writes the charts and the summary.

# +
def run_contact_map(config: ContactMapConfig, comm: MPI.Comm | None = None,
                    schemes: dict[bool, CentralDifference] | None = None) -> ContactMapResult:
    """Run the interaction maps (and continuations) of ``config``; ``comm``: split the speeds over its ranks
    (None: serial); ``schemes``: the schemes of the GNL settings (True/False) when the caller has them already
    (``time_scheme``). Raises ValueError for an input the library refuses (a corrupted model, a step above the
    stability limit, ...)."""
    rank = 0 if comm is None else comm.rank
    if comm is not None:
        # rank 0 alone imports dolfinx for its serial work (the build, the cubature, the stress) and PETSc's
        # initialisation is collective: every rank initialises it first (a disk map read from --model with --stress
        # imported none before the stress, and rank 0 waited there forever)
        importlib.import_module("rotor37_rom.fem")
    model, files = reduced_model(config, comm)
    omega = eigenfrequencies(model)
    onset = sprag_slip_onsets(model, config.casing, config.sector)
    summary = model_summary(config, model, omega, onset)
    if rank == 0 and not config.quiet:
        print(f"sustained sliding diverges (sprag-slip) from mu = {onset['weakest_node']:.3f} on one contact node, "
              f"{onset['all_nodes']:.3f} on all of them; this run: mu = {config.mu:g} (growth can start below: "
              f"docs/results.md, 'Friction')")
    runs, mesh = {}, None
    for gnl in GNL_SETTINGS[config.gnl]:
        setting = config.setting(gnl)
        if config.tolerance is not None and rank == 0:
            larger = config.model_beyond_choice(gnl)
            print(f"--tolerance {config.tolerance:g}: {config.choice(gnl).describe()}" + (
                f"; run on the larger model the settings share ({', '.join(f'{k} {v}' for k, v in larger.items())}): "
                f"the expected error and cost are the choice's, measured on its own model" if larger else ""))
        scheme = (schemes or {}).get(gnl) or time_scheme(setting, model, gnl, comm)
        label, tag = setting_names(setting, gnl)
        folder, records, retried, wall = sweep_map(setting, scheme, comm)
        branches = continuation_branches(setting, scheme, retried, tag, comm)
        if rank != 0:
            continue
        runs[label] = result = MapResult(label, tag, folder, interaction_map(records, config.node), scheme.h,
                                         scheme.h_crit, retried, wall, branches)
        files += chart_map(setting, result, records, omega, model.r, summary["linear_resonance"])
        summary["runs"][label] = summary_entry(setting, scheme, result, records)
        if config.tolerance is not None:
            choice = config.choice(gnl)
            summary["runs"][label]["chosen"] = dict(tolerance=config.tolerance, model=choice.name,
                                                    options=choice.options, expected_error=choice.error,
                                                    run_on_larger_model=config.model_beyond_choice(gnl))
        print_map(result, summary["linear_resonance"])
        if gnl and setting.step_outliers == "drop" and result.imap.diverged.any():
            print(f"         {int(result.imap.diverged.sum())} speeds still blew up with --step-outliers drop (their "
                  f"retries halve a step above the one from every state): run them with --step-outliers keep before "
                  f"reading them as grown")
        if config.stress:
            mesh = mesh or stress_mesh(config, model)
            summary["runs"][label]["stress"], pictures = disk_peak_stress(config, scheme, result, tag, mesh)
            files += pictures
    if rank == 0:
        files += write_summary(config.out, summary)
    return ContactMapResult(config.out, omega, float(summary["linear_resonance"]), runs, summary, files)
# -


# ## Command line
#
# The options are the fields of `ContactMapConfig` (their defaults too: an option not given is left to the
# dataclass). `main` runs the study and prints the comparison with the paper; a ValueError (a bad option, a file
# that is not a reduced model, a step the library refuses) is one line on stderr and exit status 2.

# +
def build_parser() -> ArgumentParser:
    """The command line: one option per ContactMapConfig field (defaults: the dataclass's)."""
    parser = ArgumentParser(description="interaction maps of the reduced blade with casing contact",
                            argument_default=argparse.SUPPRESS)
    parser.add_argument("--preset", help=f"mesh preset: {', '.join(MESH_PRESETS)} (default ci)")
    parser.add_argument("--model", type=Path, help="load this reduced model (.npz) instead of building one")
    parser.add_argument("--disk", action="store_true",
                        help="the 36-sector bladed disk (every blade's 8 tip nodes in contact) instead of the blade")
    parser.add_argument("--r-c", type=int, help="fixed-interface modes (per sector) of the model built (default 15; "
                                                "disk 10)")
    parser.add_argument("--r-md", type=int, help="modal derivatives (per sector) of the model built (default 0; disk "
                                                 "10, by MI 2b)")
    parser.add_argument("--global-md", type=int, help="modal derivatives of the first N clamped modes (default 3)")
    parser.add_argument("--contact-patch", type=float, metavar="RADIUS",
                        help="spread each tip node's contact force over the tip facets within RADIUS (m, <= 0.01; "
                             "default 0: point contact)")
    parser.add_argument("--r-cyclic", type=int, help="the disk's interface modes (default 144, the paper's)")
    parser.add_argument("--mistuning", type=float, metavar="SIGMA",
                        help="the disk's blade stiffness scatter: standard deviation in [0, 1) of log-normal factors "
                             "(default 0: tuned)")
    parser.add_argument("--seed", type=int, help="seed of the mistuning factors (default 0)")
    parser.add_argument("--sector", type=int, help="sector whose node LE makes the map (0..35; default 0)")
    parser.add_argument("--stress", action="store_true",
                        help="the disk's von Mises stress at t_max of each map's largest response (all sectors)")
    parser.add_argument("--speeds", type=float, nargs=3, metavar=("START", "STOP", "N"),
                        help="N angular speeds (rad/s) from START to STOP (default 1200 1600 21)")
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
    parser.add_argument("--batch", type=int, help="speeds integrated together (default 16)")
    parser.add_argument("--continuation", type=float,
                        help="speed step (rad/s) of a continuation up and down over the map's range (0: none, the "
                             "default); under mpirun the two branches run on ranks 0 and 1; resumable")
    parser.add_argument("--continuation-range", type=float, nargs=2, metavar=("LOW", "HIGH"),
                        help="run the continuation over this speed range (rad/s) instead of the map's: up from LOW, "
                             "down from HIGH (each first run as long as the map's, 15 %% of it after); a higher "
                             "HIGH with the same LOW extends the saved up branch from its last point (a lower LOW "
                             "with the same HIGH, the down branch)")
    parser.add_argument("--steady-window", type=int, metavar="N",
                        help="a continued run is steady when its max over the last N revolutions and the N before "
                             "agree to 2 %% (1, the paper's and the default: periodic with the rotor; N: periods up to "
                             "N T)")
    parser.add_argument("--unsteady-step", choices=["smallest", "full"],
                        help="the continuation's point where no halved step is steady: smallest (the paper read "
                             "literally, the default: the step stays divided) or full (the full step, marked not "
                             "steady: 8 times fewer points across an unsteady stretch)")
    parser.add_argument("--out", type=Path, help="output folder (default results/contact_map)")
    parser.add_argument("--cache", type=Path, help="folder of the model, cubature and probe caches (default "
                                                   "OUT/cache; another map's to share its cubature)")
    parser.add_argument("--quiet", action="store_true", help="no progress bars")
    return parser


def world_comm() -> MPI.Comm | None:
    """MPI.COMM_WORLD under mpirun with more than one rank; None when serial (or without mpi4py)."""
    try:
        from mpi4py import MPI
    except ImportError:
        return None
    return MPI.COMM_WORLD if MPI.COMM_WORLD.size > 1 else None


def print_report(result: ContactMapResult) -> None:
    """The paper's speeds to compare with, and where the outputs are."""
    print(f"paper: linear {PAPER['linear 1B/EO4']:.0f}, zero IC {PAPER['zero IC, no GNL']:.0f} / "
          f"{PAPER['zero IC, GNL']:.0f} (no GNL / GNL), continuation {PAPER['continuation, no GNL']:.0f} / "
          f"{PAPER['continuation, GNL']:.0f} rad/s")
    print(f"charts and summary.json in {result.out}/")


def main(argv: Sequence[str] | None = None) -> int:
    """Parse the options, run the study, print the report; raises ValueError for a bad input."""
    config = ContactMapConfig(**vars(build_parser().parse_args(argv)))
    logging.basicConfig(level=logging.WARNING, force=True)
    logging.getLogger().handlers[0].setLevel(logging.WARNING)
    comm = world_comm()
    result = run_contact_map(config, comm)
    if comm is None or comm.rank == 0:
        print_report(result)
    return 0


if __name__ == "__main__":
    sys.exit(run_main(main))
# -
