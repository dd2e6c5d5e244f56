"""Reduced blade models and their clearance consumption (demos/reduced_blade.py, §2.1, §2.3.2):
``run_reduced_blade(ReducedBladeConfig)``.

Reduced models of the clamped blade (r_b = 24 boundary DOFs at the 8 tip nodes, r_c fixed-interface modes, r_MD modal
derivatives selected by a criterion of §3.1.2, and optionally the modal derivatives of the first clamped modes) are
built through ``reduction.builder`` (cached under a key of their parameters and mesh: a second run loads them), their
modal-derivative weights drawn (Fig. 5 analogue), and the clearance consumption at node LE along 1B (zeta = 1 mm) and
1T (zeta = 0.5 mm) computed with the full-order model (linear and nonlinear statics) and with each reduced model
(Figs. 9-10 analogues): static analyses under delta f^X, delta in [-1, 1], with f^X = K phi^X and phi^X scaled to move
node LE by zeta along e_x. One ``ClearanceStudy`` per mode gives the two numbers the paper quotes: where the linear
model stays within 10 % of the nonlinear one, and each reduced model's largest error.
"""
from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import numpy as np

from rotor37_rom.checks import before_work, whole_number
from rotor37_rom.cli import resolve_table
from rotor37_rom.geometry.blade import MESH_PRESETS
from rotor37_rom.model.reduced import ReducedModel
from rotor37_rom.post.clearance import ClearanceCurves, delta_range_within, relative_error
from rotor37_rom.reduction.config import MODES_MAX, check_cubic_memory
from rotor37_rom.reduction.craig_bampton import CRITERIA, GLOBAL_MD_MAX
from rotor37_rom.studies.model_choice import ModelChoice

__all__ = ["ReducedBladeConfig", "ClearanceStudy", "ReducedBladeResult", "run_reduced_blade", "build_models",
           "study_clearance", "PAPER_LINEAR_RANGE", "AMPLITUDES", "FORCES"]

PAPER_LINEAR_RANGE = {"1B": (-0.25, 0.2), "1T": (-0.1, 0.1)}   # §2.3.2: linear within 10 % of GNL for delta in
AMPLITUDES = {"1B": 1e-3, "1T": 0.5e-3}                       # zeta (m): LE displacement of the scaled mode
FORCES = ("intrusive", "quadrature", "step", "ecsw")


@dataclasses.dataclass(frozen=True)
class ReducedBladeConfig:
    """The blade, the reduced models and the clearance study.

    Attributes:
        preset: mesh preset: ci, coarse or paper.
        table: 'none' (the built-in parametric blade), 'auto' (the shared NASA Table IV) or a Table IV file.
        r_c: fixed-interface modes of every model (>= 1).
        r_md: one model per entry, with that many modal derivatives selected by ``criterion`` (each >= 0).
        criterion: modal-derivative selection: MMI, MI2a, MI2b, SMVW or random.
        forces: reduced nonlinear forces: intrusive (exact cubic tensors), quadrature (exact, tensor-free), step
            or ecsw.
        levels: load levels on each side of delta = 0 (1..50).
        global_md: also a model with r_MD = 0 and the modal derivatives of the first N clamped modes (0: none; 0..20).
        out: output folder (charts; the models are cached in <out>/cache).
        tolerance: build only the cheapest reduced model the speed-accuracy study measured within this relative
            error of the clearance consumption (scene 'clearance', its held-out amplitudes included; docs/choosing-
            a-model.md), in (0, 1); it sets r_c, r_md, criterion and global_md, which must not be given with it, and
            runs the study's setting (ci preset, built-in blade, exact cubic tensors).
        choice: the study's model chosen for ``tolerance`` (set from it; None without a tolerance).
    """

    preset: str = "ci"
    table: str = "none"
    r_c: int = 15
    r_md: tuple[int, ...] = (20, 80)
    criterion: str = "MI2b"
    forces: str = "quadrature"
    levels: int = 10
    global_md: int = 3
    out: Path = Path("results/reduced_blade")
    tolerance: float | None = None
    choice: ModelChoice | None = dataclasses.field(default=None, init=False, compare=False, repr=False)

    def __post_init__(self):
        if self.tolerance is not None:
            self._take_the_chosen_model()
        if self.preset not in MESH_PRESETS:
            raise ValueError(f"--preset must be one of {', '.join(MESH_PRESETS)}, got {self.preset!r}")
        whole_number("--r-c", self.r_c, 1, MODES_MAX)
        for r_md in self.r_md:
            whole_number("--r-md (each value)", r_md, 0, MODES_MAX)
        object.__setattr__(self, "r_md", tuple(int(r) for r in self.r_md))
        if self.criterion not in CRITERIA:
            raise ValueError(f"--criterion must be one of {', '.join(CRITERIA)}, got {self.criterion!r}")
        if self.forces not in FORCES:
            raise ValueError(f"--forces must be one of {', '.join(FORCES)}, got {self.forces!r}")
        if not 1 <= self.levels <= 50:
            raise ValueError(f"--levels must be in [1, 50], got {self.levels}")
        if not 0 <= self.global_md <= GLOBAL_MD_MAX:
            raise ValueError(f"--global-md must be in [0, {GLOBAL_MD_MAX}], got {self.global_md}")
        if not self.r_md and not self.global_md:
            raise ValueError("--r-md and --global-md: no model to build (give an --r-md value or --global-md >= 1)")
        if self.forces == "intrusive":
            check_cubic_memory("--r-c" if self.r_c > max(self.r_md, default=0) else "--r-md",
                               24 + self.r_c + max(self.r_md, default=0) + self.global_md * (self.global_md + 1) // 2)
        object.__setattr__(self, "table", str(self.table))
        object.__setattr__(self, "out", Path(self.out))
        resolve_table(self.table)

    def _take_the_chosen_model(self) -> None:
        """Set r_c, r_md, criterion, global_md and forces from the study's cheapest reduced model within
        ``tolerance`` (a field given another value than its default or the chosen one is refused)."""
        from rotor37_rom.studies.model_choice import choose_model

        if not (isinstance(self.tolerance, (int, float)) and 0 < self.tolerance < 1):
            raise ValueError(f"--tolerance must be in (0, 1) (a relative error: 0.05 = 5 %), got {self.tolerance}")
        try:                                           # the reduced models only (the full-order linear is always drawn)
            choice = choose_model("clearance", self.tolerance, where=lambda c: "r_c" in c["options"])
        except ValueError as exc:
            raise ValueError(f"--tolerance: {exc}") from None
        options = choice.options
        chosen = {"r_c": int(options["r_c"]), "r_md": (int(options["r_md"]),), "criterion": str(options["criterion"]),
                  "global_md": int(options["global_md"]), "forces": "intrusive"}   # the study's exact tensors
        defaults = {f.name: f.default for f in dataclasses.fields(self)}
        value = {n: tuple(self.r_md) if n == "r_md" else getattr(self, n) for n in [*chosen, "preset", "table"]}
        given = [n for n, v in value.items() if v != defaults[n] and v != chosen.get(n, defaults[n])]
        if given:
            raise ValueError(f"--tolerance chooses {', '.join('--' + n.replace('_', '-') for n in given)}: give "
                             f"either the tolerance or the options")
        for name, v in chosen.items():
            object.__setattr__(self, name, v)
        object.__setattr__(self, "choice", choice)

    def variants(self) -> list[tuple[str, int, int]]:
        """(name, r_MD, number of clamped modes whose MDs are added) of every model: with ``tolerance`` the chosen
        one (its r_MD selected MDs and the global MDs in one basis)."""
        if self.tolerance is not None:
            return [(f"ROM {self.choice.name}", self.r_md[0], self.global_md)]
        rows = [(f"ROM r_MD={r_md}", r_md, 0) for r_md in self.r_md]
        if self.global_md:
            n = self.global_md
            rows.append((f"ROM {n * (n + 1) // 2} global MDs", 0, n))
        return rows


@dataclasses.dataclass(frozen=True)
class ClearanceStudy:
    """Clearance consumption along one mode (curves in m, deltas in [-1, 1])."""

    curves: ClearanceCurves

    @property
    def reference(self) -> np.ndarray:
        """The full-order nonlinear curve."""
        return self.curves.curves["FOM nonlinear"]

    def error(self, name: str) -> np.ndarray:
        """Relative error of curve ``name`` against the full-order nonlinear one at every delta (NaN at 0)."""
        return relative_error(self.curves.curves[name], self.reference)

    def max_error(self, name: str) -> float:
        """Largest relative error of curve ``name`` over delta in [-1, 1] (NaN if its statics failed)."""
        err = self.error(name)
        return float(np.nanmax(err)) if np.isfinite(self.curves.curves[name]).any() else float("nan")

    @property
    def linear_range(self) -> tuple[float, float]:
        """The interval of delta around 0 where the linear model is within 10 % of the nonlinear one."""
        return delta_range_within(self.curves.deltas, self.error("FOM linear"))


@dataclasses.dataclass(frozen=True)
class ReducedBladeResult:
    """What ``run_reduced_blade`` produced.

    Attributes:
        sector: the blade (rotor37_rom.fem.Sector) the models were built on.
        omega: its first three clamped frequencies (rad/s).
        models: {name: ReducedModel}; seconds: {name: offline wall time (s)}.
        clearance: {'1B' | '1T': ClearanceStudy}.
        files: the charts written.
    """

    sector: object
    omega: np.ndarray
    models: dict[str, ReducedModel]
    seconds: dict[str, float]
    clearance: dict[str, ClearanceStudy]
    files: list[Path]

    def frequency_errors(self, name: str) -> np.ndarray:
        """Relative error of the model's first three frequencies against the full-order ones."""
        import scipy.linalg

        model = self.models[name]
        return np.sqrt(scipy.linalg.eigh(model.K, model.M, eigvals_only=True)[:3]) / self.omega - 1.0


def build_models(config: ReducedBladeConfig, sector, ops) -> tuple[dict, dict, list[Path]]:
    """Every model of ``config``: ({name: model}, {name: seconds}, the weight charts)."""
    from rotor37_rom.reduction.builder import ReductionConfig, build_reduced_model
    from rotor37_rom.viz.charts import plot_md_weights

    models, seconds, files = {}, {}, []
    for name, r_md, n_global in config.variants():
        reduction = ReductionConfig(r_c=config.r_c, r_md=r_md, criterion=config.criterion, forces=config.forces,
                                    global_md_modes=n_global)
        t0 = time.perf_counter()
        model, report = build_reduced_model(sector, reduction, ops=ops, cache_dir=config.out / "cache")
        models[name], seconds[name] = model, time.perf_counter() - t0
        if "weights" in report and r_md:
            files.append(plot_md_weights(report["weights"], report["pairs"], model.sizes["r_b"],
                                         config.out / f"md_weights_{config.criterion}_{r_md}.png",
                                         f"{config.criterion} weights, r_MD = {r_md} selected"))
    return models, seconds, files


def study_clearance(config: ReducedBladeConfig, sector, ops, models: dict) -> tuple[dict, list[Path]]:
    """The clearance studies of 1B and 1T and their charts."""
    from rotor37_rom.reduction.builder import clearance_consumption_study
    from rotor37_rom.viz.charts import plot_clearance_consumption, plot_indicator_vs_rmd, plot_speed_accuracy

    studies, files = {}, []
    for mode, zeta in AMPLITUDES.items():
        study = ClearanceStudy(clearance_consumption_study(sector, mode, zeta, config.levels, models, ops))
        studies[mode] = study
        files.append(plot_clearance_consumption(study.curves, config.out / f"clearance_{mode}.png"))
        accuracy = [(name, study.curves.costs[name], study.max_error(name)) for name in study.curves.curves
                    if name in study.curves.costs and name != "FOM nonlinear" and np.isfinite(study.max_error(name))]
        files.append(plot_speed_accuracy(accuracy, config.out / f"speed_accuracy_{mode}.png",
                                         f"clearance consumption {mode}: cost vs max relative error "
                                         "(FOM nonlinear = reference)"))
        md_rows = [(models[n].sizes["r_md"], e) for n, _, e in accuracy if n.startswith("ROM r_MD=")]
        if md_rows:
            files.append(plot_indicator_vs_rmd(md_rows, config.out / f"error_vs_rmd_{mode}.png",
                                               f"{mode}: max clearance error vs r_MD"))
    return studies, files


def run_reduced_blade(config: ReducedBladeConfig) -> ReducedBladeResult:
    """Mesh the blade, build the models, run both clearance studies (serial)."""
    from mpi4py import MPI

    from rotor37_rom import fem

    if MPI.COMM_WORLD.size > 1:
        raise ValueError("demos/reduced_blade.py runs serially")
    before_work({"--out": config.out})
    sector = fem.create_blade_sector(MPI.COMM_SELF, table=resolve_table(config.table), preset=config.preset)
    ops = fem.create_svk_operators(sector)
    omega = np.asarray(fem.compute_clamped_modes(sector, 3, ops).omega)
    models, seconds, files = build_models(config, sector, ops)
    studies, charts = study_clearance(config, sector, ops, models)
    return ReducedBladeResult(sector, omega, models, seconds, studies, files + charts)
