"""A steady-state full-order reference for the blade with GNL in casing contact, and reduced models run against it
(issue #86).

The full order is the blade's finite-element model itself (``fem.solve_repeating_newmark``: generalised alpha with
the exact SVK tangent, each iterate corrected by the multipliers that close its penetrations), the reduced models the
maps' explicit scheme (``dynamics.explicit``). Both carry one damping operator: a ``dynamics.damping.ModalLaw`` on the
full order (exact ratios on its lowest modes, stiffness proportional above), and its Galerkin projection V^T C V on
the reduced model's basis V, so the damping is the same on both sides by construction, not two modal laws on two
sets of modes. ``full_order_energy`` carries a finished full-order run on and closes its energy balance.
Each run goes on to its revolution limit; its map quantity (max |u_LE| over a revolution) is judged steady or "not
steady" by ``post.steady.steadiness`` (changing by less than 2 % a revolution over the last two), never reported as a
steady value otherwise.

The casing's ovalization ramp ends after ``SteadyCase.ramp_revolutions`` (eq. 38 reaching 99 % there), whatever the
run length, so that runs of different lengths see the same casing.
"""
from __future__ import annotations

import dataclasses
import time

import numpy as np

from rotor37_rom.checks import real_number
from rotor37_rom.dynamics.casing import DIRECTIONS, Casing
from rotor37_rom.dynamics.damping import ModalLaw, damping_law
from rotor37_rom.post.steady import Steadiness, revolution_maxima, steadiness

#: the full order's hyperelastic laws (``forms.HYPERELASTIC_LAWS``, named here without importing UFL)
HYPERELASTIC_LAWS = ("svk", "neo-hookean")

__all__ = ["SteadyCase", "SteadyRun", "full_order_run", "full_order_energy", "reduced_run", "reduced_damping",
           "cubature_model", "batch_cost", "steady_map", "pod_model", "revolution_peaks", "compare_runs"]


@dataclasses.dataclass(frozen=True)
class SteadyCase:
    """One steady-state question: the blade at ``speed`` (rad/s) under the paper's casing (clearance 0.5 mm, bumps
    ``bump_mm``), Coulomb ``mu``, contact normal ``direction``, damping law ``law`` (``dynamics.damping.DAMPING_LAWS``),
    run for ``revolutions`` at most, steady when the map quantity changes by less than ``tolerance`` a revolution.
    ``hyperelastic``: the full order's law (``forms.HYPERELASTIC_LAWS``: 'svk', the paper's and the reduced models',
    or 'neo-hookean', the second law against which SVK's softening in compression is judged)."""

    speed: float
    mu: float = 0.0
    direction: str = "x"
    law: str = "heavy"
    revolutions: int = 8
    ramp_revolutions: float = 1.0
    tolerance: float = 0.02
    bump_mm: float = 0.625
    hyperelastic: str = "svk"

    def __post_init__(self):
        real_number("speed", self.speed, 1.0, 5000.0, unit=" rad/s")
        real_number("mu", self.mu, 0.0, 2.0)
        if self.direction not in DIRECTIONS:
            raise ValueError(f"direction must be one of {', '.join(DIRECTIONS)}, got {self.direction!r}")
        damping_law(self.law)
        if not (isinstance(self.revolutions, (int, np.integer)) and 3 <= self.revolutions <= 200):
            raise ValueError(f"revolutions must be an integer in [3, 200], got {self.revolutions!r}")
        real_number("ramp_revolutions", self.ramp_revolutions, 0.0, self.revolutions - 2, open_low=True)
        real_number("tolerance", self.tolerance, 0.0, 0.5, open_low=True)
        real_number("bump_mm", self.bump_mm, 0.0, 4.9)
        if self.hyperelastic not in HYPERELASTIC_LAWS:
            raise ValueError(f"hyperelastic must be one of {', '.join(HYPERELASTIC_LAWS)}, got {self.hyperelastic!r}")

    @property
    def duration(self) -> float:
        return self.revolutions * 2.0 * np.pi / self.speed

    @property
    def damping(self) -> ModalLaw:
        return damping_law(self.law)

    def casing(self) -> Casing:
        return Casing(c0=0.5e-3, h_b=self.bump_mm * 1e-3, mu=self.mu, direction=self.direction,
                      ramp_fraction=self.ramp_revolutions / self.revolutions)

    def label(self) -> str:
        law = "" if self.hyperelastic == "svk" else f" {self.hyperelastic}"
        return f"{self.speed:g} rad/s mu {self.mu:g} {self.direction} {self.law} {self.revolutions} rev{law}"


@dataclasses.dataclass(frozen=True)
class SteadyRun:
    """One run's LE normal displacement (t, u_le in s, m), its verdict, its cost and the scheme's details."""

    t: np.ndarray
    u_le: np.ndarray
    verdict: Steadiness
    wall_s: float
    details: dict

    def to_json(self) -> dict:
        v = self.verdict
        return {"t": self.t.tolist(), "u_le": self.u_le.tolist(), "wall_s": self.wall_s, "details": self.details,
                "steady": v.steady, "value": v.value, "maxima": v.maxima.tolist(), "reason": v.reason,
                "revolution": v.revolution}


def full_order_run(sector, ops, case: SteadyCase, h: float, rho_inf: float = 0.8, checkpoint=None,
                   snapshots_per_revolution: int = 0) -> tuple[SteadyRun, np.ndarray | None]:
    """The full order at ``case`` with step h (s), generalised alpha ``rho_inf``: the run and, with
    ``snapshots_per_revolution``, its field snapshots (n_snap, n_dofs) for a POD basis (else None). ``checkpoint``:
    an .npz path the run saves to and resumes from. ``ops`` must be the case's law (``fem.create_svk_operators(
    sector, law=case.hyperelastic)``)."""
    from rotor37_rom.dynamics.casing import contact_frames

    problem, every = _full_order_problem(sector, ops, case, h, rho_inf, snapshots_per_revolution)
    t0 = time.perf_counter()
    res = problem.run(every, checkpoint, 600.0)
    casing, n_steps = problem.casing, problem.n_steps
    normal = contact_frames(sector.tip_nodes[:1], casing.direction, casing.rotation_sense, casing.cone_slope,
                            sector.blade_frame_angle())[0][0]
    u = res.tip[:, 0, 0, :] @ normal
    on = res.lam > 0
    details = {"model": "full order", "hyperelastic": case.hyperelastic, "h": h, "rho_inf": rho_inf, "steps": n_steps,
               "dofs": int(sector.n_dofs),
               "factorisations": int(res.refreshes), "newton_iterations": int(res.iterations.sum()),
               "contact_steps": int(on.any(axis=1).sum()), "max_penetration": res.max_penetration,
               "max_multiplier": float(res.lam.max()), "wall_run_s": res.wall}
    run = SteadyRun(res.t, u, steadiness(res.t, u, case.speed, case.tolerance), time.perf_counter() - t0, details)
    return run, (res.fields[:, 0] if snapshots_per_revolution else None)


def _full_order_problem(sector, ops, case: SteadyCase, h: float, rho_inf: float | None, snapshots_per_revolution: int):
    """The full order of ``case`` at step h (``fem.periodic.RepeatingNewmark``), ``ops`` of the case's law, and the
    steps between its snapshots (all of them: none but the last)."""
    from rotor37_rom.fem.periodic import CasingContact, NewmarkScheme, RepeatingNewmark

    real_number("h", h, 1e-8, 1e-4, unit=" s")
    if getattr(ops, "law", None) != case.hyperelastic:
        raise ValueError(f"ops: the case's full order is {case.hyperelastic!r}, the operators' law is "
                         f"{getattr(ops, 'law', None)!r}")
    n_steps = int(round(case.duration / h))
    every = n_steps if not snapshots_per_revolution else max(1, n_steps // (case.revolutions
                                                                            * snapshots_per_revolution))
    problem = RepeatingNewmark(sector, 1, h, n_steps, ops=ops, nonlinear=True,
                               contact=CasingContact(case.casing(), case.speed, case.duration),
                               damping=case.damping, scheme=NewmarkScheme(rho_inf, rtol=1e-6))
    return problem, every


def full_order_energy(sector, ops, case: SteadyCase, h: float, rho_inf: float | None, checkpoint,
                      revolutions: float = 1.0) -> dict:
    """The energy balance (``dynamics.energy``) of the full order carried on for ``revolutions`` from the end of its
    finished run (``checkpoint``, the .npz ``full_order_run`` wrote with these arguments, with or without snapshots):
    per revolution (J), the
    casing's work (wall), what the impacts take (closing) and give back (opening), friction, the damping law's
    dissipation, the change of kinetic + strain energy, the residual R (> 0: lost by the scheme) split as R = G - P + A
    (the trapezoidal quadrature gap of the internal force, Newton's defect, generalised alpha's algorithmic
    dissipation); and node LE's map quantity over the window: per whole revolution carried on, max |u_LE|
    ('maxima', the run's own revolutions' continued) and its peaks towards the axis and the casing."""
    from rotor37_rom.dynamics.energy import balance_of_run, record_run

    problem, _ = _full_order_problem(sector, ops, case, h, rho_inf, 0)
    real_number("revolutions", revolutions, 0.0, 20.0, open_low=True)
    with np.load(checkpoint) as data:
        if not problem.same_steps(data["signature"]):
            raise ValueError(f"checkpoint {checkpoint} belongs to another run")
        if int(data["step"]) != problem.n_steps:
            raise ValueError(f"checkpoint {checkpoint}: the run is at step {int(data['step'])} of "
                             f"{problem.n_steps}; finish it first")
        x, v, a = data["x"], data["v"], data["a"]
    k = int(round(revolutions * 2 * np.pi / case.speed / h))
    t = (problem.n_steps + np.arange(k + 1)) * h
    t0 = time.perf_counter()
    run = record_run(problem.stepper, t, x, v, a)
    balance = balance_of_run(problem.stepper, run, problem.strain_energy)
    wall_s = time.perf_counter() - t0
    per = 1.0 / revolutions

    def total(y):
        return float(per * np.sum(y))

    terms = {"wall": total(balance.wall), "closing": total(balance.closing), "opening": total(balance.opening),
             "friction": total(balance.contact_friction), "damping": total(balance.damping),
             "external": total(balance.external), "stored": float(per * (balance.energy[-1] - balance.energy[0])),
             "residual": total(balance.residual), "quadrature_gap": total(balance.quadrature_gap),
             "defect": total(balance.defect), "algorithmic": total(balance.algorithmic),
             "scale": total(balance.scale)}
    labels = list(problem.contact.labels)
    u = np.asarray(problem.contact.N[labels.index("0:LE") if "0:LE" in labels else 0] @ run.x).ravel()
    inward, outward = revolution_peaks(run.t, u, case.speed)
    return {"per_revolution_J": terms, "revolutions": revolutions, "steps": k, "wall_s": wall_s,
            "mean_energy_J": float(np.mean(balance.energy)), "le_normal_max_m": float(np.abs(u).max()),
            "maxima": revolution_maxima(run.t, u, case.speed).tolist(), "towards_axis": inward.tolist(),
            "towards_casing": outward.tolist()}


def reduced_damping(model, sector, ops, law: ModalLaw) -> np.ndarray:
    """The full order's damping law projected on the reduced model's basis (model.Phi, the blade's DOFs): V^T C V
    (r, r). The model must carry its basis."""
    from rotor37_rom.fem.periodic import RepeatingSectors

    if model.Phi is None:
        raise ValueError("the reduced model carries no basis (Phi): the full order's damping cannot be projected on it")
    return RepeatingSectors(sector, 1, ops).project_damping(law, model.Phi)


def reduced_run(model, C: np.ndarray, case: SteadyCase, h: float, cap: float, record: float = 2e-6,
                checkpoint=None) -> SteadyRun:
    """The reduced model (its C replaced by ``C``, e.g. ``reduced_damping``) in the maps' explicit scheme at step h
    (s) with the frequency cap ``cap`` (rad/s) at ``case``: node LE's normal displacement every ``record`` s."""
    from rotor37_rom.dynamics.explicit import CentralDifference, simulate

    C = np.asarray(C, float)
    if C.shape != model.K.shape or not np.all(np.isfinite(C)):
        raise ValueError(f"C must be a finite ({model.r}, {model.r}) matrix, got {C.shape}")
    damped = dataclasses.replace(model, C=C)
    scheme = CentralDifference(damped, nonlinear=True, damping=True, frequency_cap=cap, h=h, force=True)
    every = max(1, int(round(record / scheme.h)))
    n_steps = every * int(np.ceil(case.duration / (scheme.h * every)))   # the last revolution recorded whole
    t0 = time.perf_counter()
    res = simulate(scheme, [case.speed], case.casing(), n_steps=n_steps, duration=case.duration,
                   record_every=every, on_blowup="flag")
    u = np.asarray(res.u_r[0][res.row("0:LE")], float)
    t = np.asarray(res.t[0], float)
    if res.diverged_step[0] >= 0:
        u = np.where(t <= res.diverged_step[0] * scheme.h, u, np.nan)
    details = {"model": f"reduced r = {model.r}", "h": scheme.h, "cap_hz": cap / (2 * np.pi), "steps": n_steps,
               "diverged": bool(res.diverged_step[0] >= 0), "max_penetration": float(res.max_penetration[0])}
    return SteadyRun(t, u, steadiness(t, u, case.speed, case.tolerance), time.perf_counter() - t0, details)


def cubature_model(model, C: np.ndarray, sector, case: SteadyCase, h: float, cap: float, tol: float,
                   train_speeds, train_revolutions: int = 3, checkpoint=None):
    """The reduced model with its exact GNL forces replaced by a point cubature (``reduction.builder.hyper_reduce``)
    trained on its own exact runs (damping ``C``, the explicit scheme at step h and cap ``cap`` rad/s) at
    ``train_speeds`` for ``train_revolutions`` each under ``case``'s casing (its ramp over its first revolutions):
    no full-order run enters it. ``checkpoint``: the training runs' checkpoint (.npz), removed once trained.
    Returns (model, report: cubature points, quadrature points, training error, states, seconds)."""
    from pathlib import Path

    from rotor37_rom.dynamics.explicit import CentralDifference, contact_training_states
    from rotor37_rom.reduction.builder import hyper_reduce

    real_number("tol", tol, 1e-10, 0.1, open_low=True)
    speeds = np.atleast_1d(np.asarray(train_speeds, float))
    if speeds.size == 0:
        raise ValueError("train_speeds: give at least one training speed")
    for w in speeds:
        real_number("train_speeds", w, 1.0, 5000.0, unit=" rad/s")
    if not (isinstance(train_revolutions, (int, np.integer)) and case.ramp_revolutions < train_revolutions <= 50):
        raise ValueError(f"train_revolutions must be an integer in ({case.ramp_revolutions:g}, 50] (past the "
                         f"casing's ramp), got {train_revolutions!r}")
    t0 = time.perf_counter()
    train_case = dataclasses.replace(case, revolutions=max(3, int(train_revolutions)))
    casing = dataclasses.replace(train_case.casing(), ramp_fraction=case.ramp_revolutions / train_revolutions)
    scheme = CentralDifference(dataclasses.replace(model, C=np.asarray(C, float)), nonlinear=True, damping=True,
                               frequency_cap=cap, h=h, force=True)
    Q_train, _ = contact_training_states(scheme, speeds, casing, float(train_revolutions), checkpoint=checkpoint,
                                         checkpoint_seconds=300.0)
    reduced, rep = hyper_reduce(sector, model, Q_train, tol=tol, level="point",
                                label=f"steady GNL runs {speeds.tolist()} x {train_revolutions} rev, {case.law} "
                                      f"damping, mu = {case.mu:g}, {case.direction}")
    if checkpoint is not None:
        Path(checkpoint).unlink(missing_ok=True)
    return reduced, {"points": int(rep["points"]), "quadrature_points": int(rep["exact"].w.size),
                     "training_error": float(rep["result"].training_error), "states": int(Q_train.shape[1]),
                     "seconds": time.perf_counter() - t0}


def batch_cost(model, C: np.ndarray, case: SteadyCase, h: float, cap: float, speeds: int = 20,
               steps: int = 4000) -> dict:
    """What the reduced model costs in a map: ``speeds`` runs around ``case``'s speed (+-10 %) marched together in
    the maps' explicit scheme (``dynamics.explicit.simulate``, one batch) for ``steps`` steps from rest under the
    casing. Returns the wall time per speed-step (us), the steps and speeds, and the step h (s)."""
    from rotor37_rom.dynamics.explicit import CentralDifference, simulate

    if not (isinstance(speeds, (int, np.integer)) and 1 <= speeds <= 1000):
        raise ValueError(f"speeds must be an integer in [1, 1000], got {speeds!r}")
    if not (isinstance(steps, (int, np.integer)) and 10 <= steps <= 10 ** 6):
        raise ValueError(f"steps must be an integer in [10, 1e6], got {steps!r}")
    damped = dataclasses.replace(model, C=np.asarray(C, float))
    scheme = CentralDifference(damped, nonlinear=True, damping=True, frequency_cap=cap, h=h, force=True)
    omega = case.speed * np.linspace(0.9, 1.1, speeds)
    t0 = time.perf_counter()
    simulate(scheme, omega, case.casing(), n_steps=steps, duration=case.duration, record_every=steps,
             on_blowup="flag")
    wall = time.perf_counter() - t0
    return {"us_per_speed_step": 1e6 * wall / (speeds * steps), "speeds": speeds, "steps": steps, "h": scheme.h}


def steady_map(model, C: np.ndarray, case: SteadyCase, speeds, h: float, cap: float, nonlinear: bool = True,
               record: float = 2e-6) -> dict:
    """An interaction map at steady state: ``case`` (its casing, damping, revolutions) at every speed of ``speeds``
    (rad/s), the reduced model (damping ``C``) marched in one batch of the maps' explicit scheme, GNL on or off, each
    run's max |u_LE| over its last revolution judged steady or not (``post.steady.steadiness``). Returns {'speeds',
    'value' (m), 'steady', 'maxima' (per revolution), 'diverged', 'reason', 'nonlinear', 'h', 'wall_s'}."""
    from rotor37_rom.dynamics.explicit import CentralDifference, simulate

    speeds = np.atleast_1d(np.asarray(speeds, float))
    if speeds.size == 0 or speeds.size > 1000:
        raise ValueError(f"speeds: give 1 to 1000 speeds, got {speeds.size}")
    cases = [dataclasses.replace(case, speed=float(w)) for w in speeds]        # each speed checked by its case
    C = np.asarray(C, float)
    if C.shape != model.K.shape or not np.all(np.isfinite(C)):
        raise ValueError(f"C must be a finite ({model.r}, {model.r}) matrix, got {C.shape}")
    scheme = CentralDifference(dataclasses.replace(model, C=C), nonlinear=nonlinear, damping=True,
                               frequency_cap=cap, h=h, force=True)
    every = max(1, int(round(record / scheme.h)))
    n_steps = [every * int(np.ceil(c.duration / (scheme.h * every))) for c in cases]   # last revolutions whole
    t0 = time.perf_counter()
    res = simulate(scheme, speeds, case.casing(), n_steps=n_steps, duration=[c.duration for c in cases],
                   record_every=every, on_blowup="flag")
    out = {"speeds": speeds.tolist(), "value": [], "steady": [], "maxima": [], "reason": [],
           "diverged": (res.diverged_step >= 0).tolist(), "nonlinear": bool(nonlinear), "h": scheme.h}
    for p, c in enumerate(cases):
        t, u = np.asarray(res.t[p], float), np.asarray(res.u_r[p][res.row("0:LE")], float)
        if res.diverged_step[p] >= 0:
            u = np.where(t <= res.diverged_step[p] * scheme.h, u, np.nan)
        v = steadiness(t, u, c.speed, c.tolerance)
        out["value"].append(v.value)
        out["steady"].append(bool(v.steady))
        out["maxima"].append(v.maxima.tolist())
        out["reason"].append(v.reason)
    out["wall_s"] = time.perf_counter() - t0
    return out


def pod_model(sector, ops, snapshots: np.ndarray, r: int, cache_dir=None):
    """The POD-Galerkin model of rank r of full-order fields ``snapshots`` (n_snap, n_dofs), mass-weighted
    (``reduction.pod.pod_basis``), built on the maps' exact tensors (``reduction.builder.build_from_basis``): the
    bound on what any basis of r vectors can do for these runs. Returns (model, the POD's relative projection error
    of the snapshots)."""
    from rotor37_rom import fem
    from rotor37_rom.reduction.builder import build_from_basis
    from rotor37_rom.reduction.pod import pod_basis

    snapshots = np.asarray(snapshots, float)
    if snapshots.ndim != 2 or snapshots.shape[1] != sector.n_dofs:
        raise ValueError(f"snapshots must be (n_snap, {sector.n_dofs}), got {snapshots.shape}")
    _, M_f, free = fem.assemble_free_operators(sector, ops)
    pod = pod_basis(snapshots[:, free].T, M_f, r)
    basis = np.zeros((sector.n_dofs, r))
    basis[free] = pod.basis
    model, _ = build_from_basis(sector, basis, ops=ops, label=f"POD r = {r} of {snapshots.shape[0]} full-order fields",
                                cache_dir=cache_dir)
    return model, float(pod.bound)


def revolution_peaks(t, u, omega: float) -> tuple[np.ndarray, np.ndarray]:
    """Per whole revolution, the largest displacement on each side: (max of -u, max of u) (m); for the LE normal
    displacement, towards the axis (where the casing pushes it) and towards the casing (the free side)."""
    from rotor37_rom.post.steady import revolution_maxima

    t, u = np.asarray(t, float), np.asarray(u, float)
    return revolution_maxima(t, np.maximum(-u, 0.0), omega), revolution_maxima(t, np.maximum(u, 0.0), omega)


def compare_runs(case: SteadyCase, runs: dict, reference: str) -> list[dict]:
    """One row per run of ``runs`` ({key: ``SteadyRun.to_json()``}) against ``runs[reference]`` (the full order):
    the last revolution's max |u_LE| and its peak towards the casing (m), whether steady, their relative errors
    against the reference's (None where either is not steady: a number that is not steady is not compared), the
    wall time per simulated revolution and the reference's over it (the cost ratio)."""
    if reference not in runs:
        raise ValueError(f"reference must be one of the runs ({', '.join(runs)}), got {reference!r}")

    def summary(run):
        _, outward = revolution_peaks(run["t"], run["u_le"], case.speed)
        return run["value"], (float(outward[-1]) if outward.size else float("nan")), bool(run["steady"])

    ref_value, ref_out, ref_steady = summary(runs[reference])
    ref_cost = runs[reference]["wall_s"] / case.revolutions
    rows = []
    for key, run in runs.items():
        value, out, steady = summary(run)
        compared = steady and ref_steady and key != reference
        cost = run["wall_s"] / case.revolutions
        rows.append({"run": key, "value": value, "towards_casing": out, "steady": steady,
                     "error": (value - ref_value) / ref_value if compared else None,
                     "error_towards_casing": (out - ref_out) / ref_out if compared else None,
                     "wall_per_revolution_s": cost, "cost_ratio": ref_cost / cost if cost > 0 else None,
                     "pod_bound": run.get("details", {}).get("pod_bound"), "reason": run["reason"]})
    return rows
