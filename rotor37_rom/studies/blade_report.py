"""The paper's single-blade story in one report (demos/report.py, ``make demo``): ``run_report(ReportConfig)``.

The studies in turn, on one mesh preset: the clamped modes (``studies.blade_modes``), the reduced model and its
clearance consumption (``studies.clearance_consumption``), the interaction maps with GNL off and on on that model
(saved once as ``<out>/rom.npz``; ``studies.contact_map``), then the von Mises stress at t_max of each map's resonance
on the same mesh; ``<out>/report.html`` opens with the summary table and the list of runs that grew past the limit,
and every section below gives the numbers behind a row and the pictures.

The resonance of a map is its 1B/EO4 resonance, as in the paper: the largest bounded response among the speeds whose
response is dominated by the fourth engine order (``studies.sweep.engine_order_resonance``); a short map's largest
response can be a higher mode's crossing instead. The stress of one map is a ``PeakStress``: at that resonance the run
is carried on for one revolution from its final state (casing fully ovalized, the rotor angle carried over, as a
continuation does), recording every state; t_max is where node LE's radial displacement is largest in magnitude in that
revolution (the NFRC's max |u_LE|: as in the paper's Fig. 25 the blade swings away from the casing there, free of
contact forces). The map's scheme is rebuilt from its model, step and cap (the sweep folder it gives is checked to be
the map's); the stress recovery evaluates the von Mises field at every quadrature point from q(t_max) without
reassembly. A run that grows past the limit there, or a map without a 1B/EO4 resonance, gives no stress: the report says
so.
"""
from __future__ import annotations

import dataclasses
import json
import time
from pathlib import Path

import numpy as np

from rotor37_rom.checks import before_work
from rotor37_rom.post.clearance import delta_range_within
from rotor37_rom.model.modes import PAPER_CLAMPED_OMEGA
from rotor37_rom.studies.blade_modes import BladeModesConfig, BladeModesResult, run_blade_modes
from rotor37_rom.studies.clearance_consumption import (PAPER_LINEAR_RANGE, ReducedBladeConfig, ReducedBladeResult,
    run_reduced_blade)
from rotor37_rom.studies.contact_map import (PAPER, ContactMapConfig, ContactMapResult, MapResult, carry_on, map_model,
    run_contact_map, time_scheme)
from rotor37_rom.viz.html import Section, Table, write_report
from rotor37_rom.reporting import say

__all__ = ["ReportConfig", "ReportResult", "PeakStress", "run_report", "summary_table", "flags", "onset_text",
           "resonance", "amplitude_at", "peak_stress", "write_html", "NORMALS"]

SIGMA_Y_TEXT = "sigma_Y = 1.38 GPa"
NORMALS = {"x": "e_x (the paper's)", "radial": "radial at each node",
           "cone": "the conical casing's (15.3 deg from radial)"}
PAPER_STRESS = {False: "above sigma_Y (bladed disk at its 1B/EO4 resonance, Fig. 25)",
                True: "below sigma_Y: the blade stays elastic (Fig. 25)"}


@dataclasses.dataclass(frozen=True)
class ReportConfig:
    """The single-blade story.

    Attributes:
        preset: mesh preset of every study: ci, coarse or paper.
        table: 'auto' (the modes of the shared NASA Table IV loft too), 'none' or a Table IV file (modes only; the
            contact studies use the parametric blade).
        r_c: fixed-interface modes of the reduced model (>= 1; 25 gives the r = 55 model of the contact studies).
        speeds: (START, STOP, N): the maps' angular speeds (rad/s).
        revolutions: revolutions per speed (> 0), from rest (zero initial conditions).
        mu: friction coefficient of the casing contact (>= 0; the paper 0.15, unbounded here at many speeds with
            the normal e_x).
        direction: contact normal: 'x' (the paper's e_x), 'radial' or 'cone' (the conical casing's own normal,
            with which friction cannot wedge this tip: docs/results.md).
        tolerance: the maps' frequency cap, step and force evaluation are the cheapest within this relative error
            in the speed-accuracy study (``studies.model_choice.choose_model``, scenes 'map-linear' and 'map-gnl'), in
            (0, 1); None: set by hand (``linear_cap``; the GNL map with exact tensors at half the stability limit).
        linear_cap: with ``tolerance`` None, the frequency cap of the linear map (kHz; None: none).
        levels: load levels on each side of delta = 0 in the clearance study (1..50).
        pictures: mode shapes and stress fields drawn with pyvista.
        quiet: no progress bars.
        out: the report's folder (report.html and one folder per study).
    """

    preset: str = "ci"
    table: str = "auto"
    r_c: int = 25
    speeds: tuple[float, float, int] = (1200.0, 1600.0, 11)
    revolutions: float = 8.0
    mu: float = 0.0
    direction: str = "x"
    tolerance: float | None = 0.05
    linear_cap: float | None = None
    levels: int = 10
    pictures: bool = True
    quiet: bool = False
    out: Path = Path("results/report")

    def __post_init__(self):
        object.__setattr__(self, "out", Path(self.out))
        if self.linear_cap is not None and not self.linear_cap > 0:
            raise ValueError(f"--linear-cap must be > 0 kHz (0: no cap), got {self.linear_cap}")
        if self.tolerance is not None and self.linear_cap is not None:
            raise ValueError("--linear-cap sets the linear map by hand: give --tolerance 0 with it")
        self.modes_config, self.clearance_config                          # noqa: B018 (each checks its options)
        maps = self.map_configs[0]                                        # the maps' checks, and their numbers
        object.__setattr__(self, "speeds", maps.speeds)
        object.__setattr__(self, "revolutions", maps.sweep.revolutions)
        object.__setattr__(self, "mu", maps.sweep.casing.mu)

    @property
    def modes_config(self) -> BladeModesConfig:
        return BladeModesConfig(preset=self.preset, n_modes=6, table=self.table, out=self.out / "modes",
                                pictures=self.pictures)

    @property
    def clearance_config(self) -> ReducedBladeConfig:
        """r_MD = 0 and the 6 global MDs, exact cubic tensors (the contact runs use the same model)."""
        return ReducedBladeConfig(preset=self.preset, table="none", r_c=self.r_c, r_md=(), forces="intrusive",
                                  levels=self.levels, global_md=3, out=self.out / "clearance")

    @property
    def model_file(self) -> Path:
        return self.out / "rom.npz"

    def choice(self, gnl: bool):
        """The speed-accuracy study's model for one map at ``tolerance`` (a ModelChoice; its reference where no
        measured model meets the tolerance), or None by hand."""
        return None if self.tolerance is None else map_model(self.tolerance, gnl, fallback=True)

    @property
    def map_configs(self) -> list[ContactMapConfig]:
        """The linear map and the GNL map: the study's choices at ``tolerance`` (their cap, step and forces; the
        model is the report's), or by hand: the linear map with ``linear_cap``, the GNL map with exact tensors at
        h = 0.5 x 2 / omega_max."""
        common = dict(model=self.model_file, speeds=self.speeds, revolutions=self.revolutions, mu=self.mu,
                      direction=self.direction, out=self.out / "contact_map", quiet=self.quiet)
        configs = []
        for gnl in (False, True):
            choice = self.choice(gnl)
            options = {} if choice is None else {k: v for k, v in choice.options.items() if k != "r_c"}
            if choice is None and not gnl:
                options["frequency_cap"] = self.linear_cap
            configs.append(ContactMapConfig.from_options(gnl="on" if gnl else "off", **options, **common))
        return configs


@dataclasses.dataclass(frozen=True)
class PeakStress:
    """The stress at t_max of one map's resonance.

    Attributes:
        label: the map's label ('no GNL, cap 60 kHz', 'GNL').
        nonlinear: GNL on (exact SVK Cauchy stress) or off (linear stress).
        speed: the map's 1B/EO4 resonance (rad/s; ``resonance``); NaN if no bounded speed is dominated by it.
        bounded: the revolution carried on stayed below the limit (and the map had a 1B/EO4 resonance).
        t_diverged: when an unbounded run passed the limit (s from rest); None otherwise.
        peak: ``post.stress.stress_at_peak``'s numbers (SI units, t_max from rest) when bounded, else None.
        files: pictures and XDMF files written.
    """

    label: str
    nonlinear: bool
    speed: float
    bounded: bool
    t_diverged: float | None = None
    peak: dict | None = None
    files: list = dataclasses.field(default_factory=list)

    def summary_text(self) -> str:
        """The summary table's cell: the stress of a bounded run, otherwise why there is none."""
        if not np.isfinite(self.speed):
            return "no stress: no bounded speed of the map is dominated by 1B/EO4"
        if not self.bounded:
            return (f"no stress: the run at {self.speed:.0f} rad/s is unbounded (grew past the limit at "
                    f"t = {self.t_diverged * 1e3:.2f} ms)")
        return (f"{self.peak['vm_max'] / 1e6:.0f} MPa = {100 * self.peak['ratio_yield']:.0f} % of sigma_Y at "
                f"{self.speed:.0f} rad/s")


@dataclasses.dataclass(frozen=True)
class ReportResult:
    """What ``run_report`` produced: each study's result, the maps, the stresses, the wall times (s), the report."""

    config: ReportConfig
    modes: BladeModesResult
    clearance: ReducedBladeResult
    maps: list[ContactMapResult]
    stress: dict[str, PeakStress]
    seconds: dict[str, float]
    html: Path

    @property
    def runs(self) -> list[tuple[ContactMapConfig, MapResult]]:
        """(configuration, map) of each map, linear first."""
        return [(c, run) for c, m in zip(self.config.map_configs, self.maps) for run in m.runs.values()]

    @property
    def linear_resonance(self) -> float:
        """omega_1 / 4 of the reduced model (rad/s)."""
        return self.maps[0].linear_resonance


def resonance(run: MapResult, revolutions: float) -> float:
    """The map's 1B/EO4 resonance (rad/s; NaN if no bounded speed is dominated by engine order 4)."""
    from rotor37_rom.studies.sweep import engine_order_resonance

    return engine_order_resonance(run.imap, 4, revolutions)


def amplitude_at(run: MapResult, speed: float) -> float:
    """The map's NFRC at ``speed`` (m)."""
    return float(run.nfrc[np.argmin(np.abs(run.speeds - speed))])


def peak_stress(config: ContactMapConfig, run: MapResult, sector, model, recovery, out: Path,
                pictures: bool) -> PeakStress:
    """The stress at t_max of ``run``'s resonance (one revolution carried on from the map's final state)."""
    from rotor37_rom.post.stress import stress_at_peak
    from rotor37_rom.studies.sweep import sweep_folder

    nonlinear = config.gnl == "on"
    speed = resonance(run, config.sweep.revolutions)
    if not np.isfinite(speed):
        return PeakStress(run.label, nonlinear, speed, False)
    scheme = time_scheme(config, model, nonlinear, None, h=run.h)                 # the map's forces (its cubature)
    if sweep_folder(scheme, config.sweep_spec(model), config.out / "sweeps") != run.folder:
        raise RuntimeError(f"the rebuilt scheme of '{run.label}' is not the map's (sweep folders differ)")
    res, scheme, t_start = carry_on(config, scheme, run, speed)
    if res.diverged_step[0] >= 0:
        return PeakStress(run.label, nonlinear, speed, False, t_diverged=t_start + res.diverged_step[0] * scheme.h)
    peak = stress_at_peak(sector, model, recovery, res, nonlinear, magnitude=True)
    files = draw_stress(sector, model, peak, run, speed, nonlinear, out, pictures)
    numbers = {k: v for k, v in peak.items() if k not in ("q", "cell_max")}
    numbers["t_max"] += t_start
    return PeakStress(run.label, nonlinear, speed, True, peak=numbers, files=files)


def draw_stress(sector, model, peak: dict, run: MapResult, speed: float, nonlinear: bool, out: Path,
                pictures: bool) -> list[Path]:
    """XDMF of u and von Mises at t_max; with ``pictures``, the field on the blade and on the 36-blade disk."""
    from rotor37_rom import fem
    from rotor37_rom.viz.plotting import render_stress, write_function_xdmf, write_xdmf

    tag = "gnl" if nonlinear else "linear"
    u = fem.displacement_function(sector, model.Phi, peak["q"])
    files = [write_xdmf(sector, [u], out / f"displacement_tmax_{tag}.xdmf"),
             write_function_xdmf(sector, fem.von_mises_function(sector, u, nonlinear=nonlinear, degree=0),
                                 out / f"von_mises_tmax_{tag}.xdmf")]
    if pictures:
        factor = 0.1 * 0.074 / max(np.abs(u.x.array).max(), 1e-12)      # largest motion drawn at 10 % of the span
        title = f"{run.label}: von Mises at t_max, Omega = {speed:.0f} rad/s (x{factor:.0f})"
        files.append(render_stress(sector, u, peak["cell_max"], out / f"stress_blade_{tag}.png", title,
                                   factor=factor, clim=peak["clim"]))
        files.append(render_stress(sector, u, peak["cell_max"], out / f"stress_disk_{tag}.png",
                                   title + ", 36 blades in phase", n_sectors=36, factor=factor, clim=peak["clim"]))
    return files


def map_seconds(config: ContactMapConfig, model) -> tuple[float, float] | None:
    """(the map, its stress at t_max) in seconds on this machine (``sweep.sweep_seconds``: probes of the map's own
    scheme; the stress carries one revolution on at one speed), or None for a cubature map (its training's length
    is known only once it has run)."""
    from rotor37_rom.studies.contact_scheme import time_scheme
    from rotor37_rom.studies.sweep import sweep_seconds

    if config.scheme.cubature is not None:
        return None
    scheme = time_scheme(config, model, config.gnl == "on", None)
    one = dataclasses.replace(config.sweep, revolutions=1.0, batch_size=1)
    speeds = config.speed_grid
    return sweep_seconds(scheme, speeds, config.sweep), sweep_seconds(scheme, [float(speeds.min())], one)


def _left(estimates: list, done: int) -> str:
    """What the report still has to do, from the estimates of its maps (and their stress) not yet run."""
    rest = estimates[done:]
    known = [e for e in rest if e is not None]
    stress = sum(e[1] for e in estimates if e is not None)
    text = (f"about {sum(e[0] for e in known) + stress:.0f} s of integration left (the maps' and the stress's, "
            f"from probes of each map's scheme on this machine)")
    return text + (f", plus {len(rest) - len(known)} cubature map(s) whose training is not timed"
                   if len(known) < len(rest) else "")


def run_report(config: ReportConfig) -> ReportResult:
    """Run every study of ``config`` and write ``<out>/report.html`` (serial)."""
    from mpi4py import MPI

    from rotor37_rom import fem
    from rotor37_rom.model.reduced import save_reduced_model
    from rotor37_rom.post.recovery import StressRecovery

    if MPI.COMM_WORLD.size > 1:
        raise ValueError("demos/report.py runs serially (demos/contact_map.py runs a map under mpirun)")
    before_work({"--out": config.out})
    seconds = {}

    def lap(name: str, t0: float) -> None:
        seconds[name] = time.perf_counter() - t0
        say(f"{name}: {seconds[name]:.0f} s", flush=True)

    t0 = time.perf_counter()
    modes = run_blade_modes(config.modes_config, comm=MPI.COMM_SELF)
    lap("clamped modes", t0)
    t0 = time.perf_counter()
    clearance = run_reduced_blade(config.clearance_config)
    model = next(iter(clearance.models.values()))
    save_reduced_model(model, config.model_file)
    lap("reduced model and clearance consumption", t0)
    estimates = [map_seconds(c, model) for c in config.map_configs]
    say(f"report: {_left(estimates, 0)}", flush=True)
    maps = []
    for k, map_config in enumerate(config.map_configs):
        t0 = time.perf_counter()
        maps.append(run_contact_map(map_config))
        lap(f"interaction map, GNL {map_config.gnl}", t0)
        say(f"report: {_left(estimates, k + 1)}", flush=True)
    t0 = time.perf_counter()
    sector = clearance.sector
    H, _, cells = fem.quadrature_gradients(sector, model.Phi.T)
    recovery = StressRecovery(H, cells, *sector.material.lame)
    stress = {run.label: peak_stress(c, run, sector, model, recovery, config.out / "stress", config.pictures)
              for c, m in zip(config.map_configs, maps) for run in m.runs.values()}
    lap("stress at t_max", t0)
    result = ReportResult(config, modes, clearance, maps, stress, seconds, config.out / "report.html")
    write_stress_summary(result)
    write_html(result)
    return result


def write_stress_summary(result: ReportResult) -> Path:
    """``<out>/stress/summary.json``: each map's stress numbers, or why there are none."""
    path = result.config.out / "stress" / "summary.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps({label: {"speed": p.speed, "bounded": p.bounded, "t_diverged": p.t_diverged,
                                        **(p.peak or {})} for label, p in result.stress.items()},
                               indent=1, default=float))
    return path


def percent(x: float) -> str:
    return f"{100 * x:+.1f} %"


def summary_table(result: ReportResult) -> Table:
    """Our numbers next to the paper's, one row per result of §2 (and Fig. 25)."""
    cfg, rows = result.config, []
    for blade in result.modes.blades:
        found = [lab for lab in PAPER_CLAMPED_OMEGA if lab in blade.labels]
        ours = " / ".join(f"{blade.frequency(lab):.0f}" for lab in found)
        errors = " / ".join(percent(blade.paper_errors[lab]) for lab in found)
        name = "parametric blade" if blade.name == "parametric" else "NASA Table IV loft"
        rows.append([f"clamped {' / '.join(found)} (rad/s)", f"{ours} ({errors})",
                     " / ".join(f"{PAPER_CLAMPED_OMEGA[lab]:.0f}" for lab in found),
                     f"{name}, {cfg.preset} mesh, {blade.dofs} DOF"])
    for mode, study in result.clearance.clearance.items():
        lo, hi = study.linear_range
        p_lo, p_hi = PAPER_LINEAR_RANGE[mode]
        rows.append([f"clearance consumption {mode}: linear within 10 % of GNL for delta in",
                     f"[{lo:+.2f}, {hi:+.2f}]", f"[{p_lo:+.2f}, {p_hi:+.2f}]",
                     f"full-order statics, zeta = {study.curves.zeta * 1e3:g} mm at node LE"])
    name, model = next(iter(result.clearance.models.items()))
    errors = " / ".join(f"{100 * result.clearance.clearance[m].max_error(name):.1f} %" for m in ("1B", "1T"))
    rows.append(["largest clearance error of the reduced model, 1B / 1T", errors, "< 10 % (r = 189)",
                 f"r = {model.r}, delta in [-1, 1], against full-order GNL"])
    lin = result.linear_resonance
    rows.append(["linear 1B/EO4 crossing omega_1 / 4 (rad/s)", f"{lin:.0f}", f"{PAPER['linear 1B/EO4']:.0f}",
                 f"omega_1 of the r = {model.r} model"])
    start, stop, n = cfg.speeds
    for c, run in result.runs:
        paper = PAPER["zero IC, GNL" if c.gnl == "on" else "zero IC, no GNL"]
        w = resonance(run, c.sweep.revolutions)
        ours = (f"{w:.0f} ({amplitude_at(run, w) * 1e3:.2f} mm; {percent(w / lin - 1)} over omega_1 / 4)"
                if np.isfinite(w) else "no bounded speed dominated by 1B/EO4")
        rows.append([f"zero-IC 1B/EO4 resonance, {run.label} (rad/s)", ours,
                     f"{paper:.0f} ({percent(paper / PAPER['linear 1B/EO4'] - 1)})",
                     f"mu = {c.sweep.casing.mu:g}, normal {c.sweep.casing.direction}, {n:d} speed{'s' * (n > 1)} in "
                     f"{start:g}-{stop:g} x {c.sweep.revolutions:g} rev (paper: mu = 0.15, "
                     "every 2 rad/s x 200 rev)"])
    past = [f"{run.label}: {', '.join(f'{w:.0f}' for w in run.speeds[run.diverged])} rad/s"
            for _, run in result.runs if run.diverged.any()]
    rows.append(["map runs past the limit (a tip DOF beyond 20 mm)", "; ".join(past) or "none", "none reported",
                 f"{sum(len(run.speeds) for _, run in result.runs)} runs"])
    for label, p in result.stress.items():
        rows.append([f"max von Mises at t_max, {label}", p.summary_text(), PAPER_STRESS[p.nonlinear],
                     f"{SIGMA_Y_TEXT}; outside the tip band; single blade"])
    return Table("Summary: this work next to Delhez et al. (2023)", ["quantity", "this work", "paper", "conditions"],
                 rows, html_id="summary")


def flags(result: ReportResult) -> list[str]:
    """Every run that grew past the limit, in words (a map speed, or the revolution of a stress run)."""
    out = []
    for _, run in result.runs:
        for w in run.speeds[run.diverged]:
            out.append(f"{run.label}: the run at {w:.0f} rad/s grew past the limit (a tip DOF beyond 20 mm); it "
                       "is drawn as missing in the map and the NFRC")
    for p in result.stress.values():
        if np.isfinite(p.speed) and not p.bounded:
            out.append(f"{p.label}: the revolution carried on at {p.speed:.0f} rad/s grew past the limit at "
                       f"t = {p.t_diverged * 1e3:.2f} ms: no stress is shown for it")
    return out


def modes_section(result: ReportResult) -> Section:
    tables, figures = [], []
    for blade in result.modes.blades:
        rows = [[k + 1, lab, w, PAPER_CLAMPED_OMEGA.get(lab, float("nan")),
                 percent(w / PAPER_CLAMPED_OMEGA[lab] - 1) if lab in PAPER_CLAMPED_OMEGA else ""]
                for k, (lab, w) in enumerate(zip(blade.labels, blade.omega))]
        tables.append(Table(f"{blade.name} blade: {blade.dofs} DOF, mass {blade.mass * 1e3:.2f} g",
                            ["mode", "label", "omega (rad/s)", "paper", "error"], rows))
        if blade.name == "parametric":
            figures += [(p, f"{blade.name} blade: {lab}") for p, lab in zip(
                [p for p in result.modes.files if p.suffix == ".png" and p.parent.name == "parametric_png"],
                blade.labels[:3])]
    return Section("Clamped modes (§2.2.1)",
                   ["P2 tetrahedra, E = 180 GPa, nu = 0.3, rho = 8000 kg/m3 (the paper's values), clamped at the "
                    "root; 1B/1T/2B identified from the motion of the tip's leading and trailing edges. The remaining "
                    "~3 % is the model (blade CAD and root), not the mesh (docs/results.md)."], tables, figures)


def clearance_section(result: ReportResult) -> Section:
    name, model = next(iter(result.clearance.models.items()))
    tables, figures = [], []
    for mode, study in result.clearance.clearance.items():
        rows = []
        for curve, values in study.curves.curves.items():
            lo, hi = (np.nan, np.nan) if curve == "FOM nonlinear" else \
                delta_range_within(study.curves.deltas, study.error(curve))
            rows.append([curve if curve != name else f"ROM r = {model.r}", values[0] * 1e3, values[-1] * 1e3,
                         "reference" if curve == "FOM nonlinear" else f"{100 * study.max_error(curve):.1f} %",
                         "" if curve == "FOM nonlinear" else f"[{lo:+.2f}, {hi:+.2f}]",
                         study.curves.costs.get(curve, float("nan"))])
        tables.append(Table(f"{mode}, zeta = {study.curves.zeta * 1e3:g} mm (paper: linear within 10 % for delta "
                            f"in {list(PAPER_LINEAR_RANGE[mode])})",
                            ["curve", "Delta(-1) (mm)", "Delta(+1) (mm)", "max error vs FOM GNL",
                             "within 10 % for delta in", "cost (s)"], rows))
        figures.append((result.config.out / "clearance" / f"clearance_{mode}.png", f"clearance consumption, {mode}"))
    errors = result.clearance.frequency_errors(name)
    return Section("Reduced model and clearance consumption (§2.1, §2.3.2, Figs. 9-10)",
                   [f"Reduced model r = {model.r} (r_b = {model.sizes['r_b']}, r_c = {model.sizes['r_c']}, r_MD = "
                    f"{model.sizes['r_md']}): Craig-Bampton on the 24 DOFs of the 8 tip nodes, "
                    f"{result.config.r_c} fixed-interface modes and the modal derivatives of 1B, 1T, 2B; exact cubic "
                    f"force tensors; built in {result.clearance.seconds[name]:.0f} s. Its first three frequencies are "
                    f"within {100 * np.abs(errors).max():.2g} % of the full-order ones.",
                    "Static analyses under delta f^X, delta in [-1, 1], f^X = K phi^X with phi^X scaled to move node "
                    "LE by zeta along e_x; Delta is the clearance consumption at node LE normal to the conical "
                    "casing."],
                   tables, figures)


def maps_section(result: ReportResult) -> Section:
    cfg, out = result.config, result.config.out / "contact_map"
    summary = result.maps[-1].summary
    rows, figures = [], []
    for c, run in result.runs:
        paper = PAPER["zero IC, GNL" if c.gnl == "on" else "zero IC, no GNL"]
        w = resonance(run, c.sweep.revolutions)
        largest = (f"{run.peak_speed:.0f} ({np.nanmax(run.nfrc) * 1e3:.3g} mm)" if np.isfinite(run.peak_speed)
                   else "none")
        rows.append([run.label, run.h, w, amplitude_at(run, w) * 1e3 if np.isfinite(w) else float("nan"), largest,
                     paper, ", ".join(f"{v:.0f}" for v in run.speeds[run.diverged]) or "none", run.wall_s])
        figures += [(out / f"interaction_map_{run.tag}.png", f"interaction map, {run.label}"),
                    (out / f"time_history_{run.tag}.png", f"LE/TE normal displacement at the largest response, "
                                                          f"{run.label}")]
    figures.insert(0, (out / "nfrc.png", "NFRC: max |u_LE| over the last revolution, GNL off and on"))
    onset = summary["sprag_slip"]
    start, stop, n = cfg.speeds
    return Section(
        "Interaction maps and NFRC (§2.3.1, Figs. 6-7)",
        [f"{n:d} speed{'s' * (n > 1)} in {start:g}-{stop:g} rad/s, {cfg.revolutions:g} revolutions each from rest "
         "(the paper: every "
         f"2 rad/s, 200 revolutions), casing ovalized into two lobes (c0 = 0.5 mm, h_b = 0.625 mm), mu = {cfg.mu:g}, "
         f"contact normal {NORMALS[cfg.direction]}. "
         "The map is the spectrum of the second half of node LE's normal displacement; the NFRC its largest value "
         "over the last revolution. Speeds that grew past the limit (a tip DOF beyond 20 mm) are left out. The 1B/EO4 "
         "resonance is the largest response among the speeds whose spectrum peaks at 4 Omega (1B); the largest "
         "response of the map can be a higher mode's crossing.",
         f"Why mu = {cfg.mu:g} with this normal: sustained sliding on the casing diverges (sprag-slip) from mu = "
         f"{onset_text(onset['weakest_node'])} on the weakest contact node and {onset_text(onset['all_nodes'])} on "
         "all eight. With the normal e_x, intermittent contact on the moving bumps makes the paper's mu = 0.15 grow "
         "without bound at many speeds, while the frictionless maps are bounded; with the conical casing's own "
         "normal friction does not wedge the tip and mu = 0.15 stays bounded (docs/results.md, 'Friction').",
         settings_text(cfg)],
        tables=[Table("Response from rest", ["map", "h (s)", "1B/EO4 resonance (rad/s)", "amplitude (mm)",
                                             "largest response", "paper (rad/s, mu = 0.15)",
                                             "past the limit (rad/s)", "wall (s)"], rows)],
        figures=figures, flags=[f for f in flags(result) if "drawn as missing" in f])


def settings_text(cfg: ReportConfig) -> str:
    """How the maps' cap, step and forces were set: the speed-accuracy study's choices, or by hand."""
    if cfg.tolerance is None:
        cap = "no frequency cap" if cfg.linear_cap is None else f"the {cfg.linear_cap:g} kHz frequency cap"
        return (f"Set by hand (--tolerance 0): the linear map runs with {cap}, the GNL map with the exact cubic "
                "tensors at half the stability limit.")
    parts = []
    for gnl in (False, True):
        c = cfg.choice(gnl)
        parts.append(f"{'GNL' if gnl else 'linear'} map: " + (
            "no measured model within the tolerance, so the study's reference setting (exact forces, no cap, half "
            "the stability limit)" if c.name == "reference" else f"{c.name} (expected error {100 * c.error:.2g} %)"))
    return (f"Each map runs with the cheapest model of the speed-accuracy study within {100 * cfg.tolerance:g} % "
            f"(--tolerance; docs/choosing-a-model.md, measured on this scene at r = 45-70): " + "; ".join(parts)
            + ". The reduced model is the report's own (its r_c), not the study's.")


def onset_text(mu: float | None) -> str:
    """A sprag-slip onset for the text: 'never' where friction does not wedge the nodes at any mu (None in the
    summary)."""
    return "never" if mu is None or not np.isfinite(mu) else f"{mu:.3f}"


def stress_section(result: ReportResult) -> Section:
    rows, figures = [], []
    for label, p in result.stress.items():
        tag = "gnl" if p.nonlinear else "linear"
        if p.bounded:
            k = p.peak
            rows.append([label, p.speed, k["t_max"] * 1e3, k["u_le"] * 1e3, k["vm_max"] / 1e6,
                         f"{100 * k['ratio_yield']:.0f} %", str(np.round(np.array(k["location"]) * 1e3, 1)),
                         k["vm_max_tip_band"] / 1e6, k["vm_max_at_contact_nodes"] / 1e6])
            figures += [(result.config.out / "stress" / f"stress_{part}_{tag}.png", f"{label}: von Mises at t_max, "
                         f"{what}") for part, what in (("blade", "blade"), ("disk", "36 blades in phase"))
                        if result.config.pictures]
        else:
            rows.append([label, p.speed, p.summary_text(), "", "", "", "", "", ""])
    return Section(
        "Stress at t_max (Fig. 25 analogue)",
        ["At the 1B/EO4 resonance of each map the run is carried on for one revolution from its final state; t_max is "
         "where node LE's radial displacement is largest in magnitude in that revolution (time from rest; as in the "
         "paper, the blade swings away from the casing there, free of contact forces). Von Mises from the exact SVK "
         "Cauchy stress (GNL on) or the linear stress (GNL off) at every "
         f"quadrature point, from q(t_max); {SIGMA_Y_TEXT}. The maximum excludes the cells within 10 % of the span "
         "of a contact node: that tip band, where the contact impulses excite the local response, and the cells "
         "touching a contact node, where point contact forces make the FE stress singular, are listed apart. Only "
         "bounded runs give a stress. The paper's Fig. 25 is the bladed disk at its resonance; this is the single "
         "blade."],
        tables=[Table("Peak instant and stress", ["map", "speed (rad/s)", "t_max (ms)", "u_LE (mm)",
                                                  "max von Mises (MPa)", "of sigma_Y", "location (mm)",
                                                  "tip band (MPa)", "at contact nodes (MPa, singular)"], rows)],
        figures=figures, flags=[f for f in flags(result) if "no stress" in f])


def write_html(result: ReportResult) -> Path:
    """report.html: the summary, the flags, one section per study, the parameters."""
    cfg = result.config
    intro = [f"The single-blade studies of Delhez et al., J. Sound Vib. 544 (2023) 117382, §2, on the {cfg.preset} "
             f"mesh of the NASA rotor 37 blade, at a reduced number of speeds and revolutions. Wall times of this run "
             f"(results of an earlier run with the same settings are reused): "
             f"{', '.join(f'{k} {v:.0f} s' for k, v in result.seconds.items())}. The measured record at the paper's "
             "scale is in docs/results.md."]
    params = {"config": cfg, "model": result.maps[-1].summary.get("sizes"),
              "casing": vars(cfg.map_configs[0].sweep.casing),
              "maps": {run.label: {"h (s)": run.h, "h_crit (s)": run.h_crit} for _, run in result.runs},
              "wall times (s)": {k: round(v, 1) for k, v in result.seconds.items()}}
    sections = [modes_section(result), clearance_section(result), maps_section(result), stress_section(result)]
    return write_report(result.html, "rotor37_rom: the single blade against the paper", sections, params,
                        summary=summary_table(result), flags=flags(result), intro=intro)
