"""Full-order implicit transients: a bladed disk under a load of N_d nodal diameters, whose response repeats every
N / gcd(N, N_d) sectors, so that many sectors closed on themselves (``cyclic.repeating_sector_maps``) carry the whole
disk's nonlinear response; a single blade is the case of one sector without cyclic faces. Implicit Newmark (average
acceleration; or generalised alpha, whose numerical dissipation a contact run needs): the steps are
``dynamics.newmark.Newmark``'s, given the sectors' SVK forces and exact tangents (every sector's from the one
sector's compiled forms) and MUMPS; the factorisation of the iteration matrix is kept across iterations and steps
while Newton converges fast (modified Newton), refreshed when it does not. Optionally the tip nodes touch the casing
of eqs. 37-38 (Lagrange multipliers, Coulomb sliding friction, ``casing.ContactSolver``): each Newton iterate is
corrected by the multipliers that close every penetration at t_n+1 through the compliance of the iteration matrix,
the implicit counterpart of the reduced scheme's forward-increment correction (eq. 27).

Part of the dolfinx adapter (``rotor37_rom.fem``); serial. The references the reduced models are checked against
(paper §3.3: full-order GNL responses, Fig. 16; and, beyond the paper, the blade in contact with GNL).
"""
from __future__ import annotations

import contextlib
import dataclasses
import logging
import time
from pathlib import Path
from typing import Callable

import numpy as np
import scipy.sparse as sp

from rotor37_rom.dynamics.casing import (Casing, casing_clearance, check_hand, contact_frames, friction_power,
                                         node_angles, ramp_rate)
from rotor37_rom import forms
from rotor37_rom.disk.symmetry import repeating_sector_maps
from rotor37_rom.dynamics.damping import LowRankDamping, ModalLaw
from rotor37_rom.dynamics.newmark import Newmark, StepContact
from rotor37_rom.interruption import checkpointing, requested, stop_if_requested
from rotor37_rom.npz import save_npz

from .operators import (SvkOperators, _require_serial, assemble_mass, assemble_stiffness, assemble_tangent_scipy,
                        create_svk_operators, evaluate_forces, evaluate_strain_energy, free_dofs, petsc_to_scipy,
                        strain_energy_form)
from .sector import Sector
from .solvers import mumps_solver, slepc_eigenpairs

__all__ = ["RepeatingSectors", "RepeatingSectorResult", "ContactOperators", "RepeatingNewmark", "NewmarkScheme",
           "SectorLoad", "CasingContact", "solve_repeating_newmark", "sector_harmonic_load"]

LOG = logging.getLogger(__name__)


@dataclasses.dataclass(frozen=True)
class RepeatingSectorResult:
    """t (n + 1,) s; tip (n + 1, n_repeat, n_tip, 3) tip-node displacements of each sector in its frame (m; with a
    contact interface C, the patch means C u);
    fields: (n_snap, n_repeat, n_dofs) sector fields every ``snapshot_every`` steps, at t[snapshots]; iterations
    (n,) Newton iterations per step; refreshes: factorisations; wall: s. With a casing: lam (n + 1, n_c) normal
    multipliers (N) of the contact nodes (``ContactOperators.labels``), max_penetration (m) left after the steps'
    corrections, friction_power (W) the largest power of friction on a sliding node (<= 0: it opposes the sliding;
    NaN if no node touched), both taken at the ends of the steps; without a casing, None / NaN."""

    t: np.ndarray
    tip: np.ndarray
    fields: np.ndarray
    snapshots: np.ndarray
    iterations: np.ndarray
    refreshes: int
    wall: float
    lam: np.ndarray | None = None
    max_penetration: float = float("nan")
    friction_power: float = float("nan")


@dataclasses.dataclass(frozen=True)
class ContactOperators:
    """The casing's contact rows over the unknown x of ``RepeatingSectors``: normal displacements N x and sliding
    displacements S x (n_c, n_x) of the contact nodes of every sector carried (sector s turned by s 2 pi / N), their
    angles at rest theta0 (n_c,) and radii (m), labels '<sector>:<node name>'."""

    N: sp.csr_matrix
    S: sp.csr_matrix
    theta0: np.ndarray
    radius: np.ndarray
    labels: tuple


class RepeatingSectors:
    """n_repeat sectors closed on themselves (``cyclic.repeating_sector_maps``) with the clamped DOFs removed: the
    unknown x holds the free DOFs of all of them; ``fields(x)`` gives each sector's DOF vector in its own frame. A
    sector without cyclic faces (a blade) is carried alone (n_repeat = 1).

    Attributes: maps [(n_dofs, n_x)] per sector; keep: the slots of x among the map's; K, M: linear stiffness and
    mass (n_x, n_x) CSR; free: (n_dofs,) bool, the sector's unclamped DOFs."""

    def __init__(self, sector: Sector, n_repeat: int, ops: SvkOperators | None = None):
        _require_serial(sector, "RepeatingSectors")
        if sector.cyclic is None and n_repeat != 1:
            raise ValueError(f"n_repeat must be 1 for {sector.source} (no cyclic faces), got {n_repeat}")
        self.sector, self.ops = sector, ops or create_svk_operators(sector)
        n = sector.n_dofs
        if sector.cyclic is None:
            maps, n_x = [sp.identity(n, format="csr")], n
        else:
            maps, n_x = repeating_sector_maps(n, sector.cyclic, n_repeat)
        self.free = np.zeros(n, bool)
        self.free[free_dofs(sector)] = True
        used = np.zeros(n_x, bool)
        for P in maps:
            used[P[self.free].indices] = True                  # slots carried by some free DOF
        self.keep = np.flatnonzero(used)
        self.maps = [P[:, self.keep].tocsr() for P in maps]
        self._restrict = sp.diags(self.free.astype(float))    # clamped rows carry reactions, not equations
        K_s = petsc_to_scipy(assemble_stiffness(sector, self.ops, clamped=False))
        M_s = petsc_to_scipy(assemble_mass(sector, self.ops, clamped=False))
        self.K, self.M = self._sum(K_s), self._sum(M_s)
        self._modes = {}

    def _sum(self, A_sector):
        return sum(P.T @ self._restrict @ A_sector @ self._restrict @ P for P in self.maps).tocsr()

    def contact_operators(self, casing: Casing, interface=None) -> ContactOperators:
        """The rows of the casing's contact nodes (``casing.contact_nodes`` among the sector's tip nodes, all by
        default) in every sector carried, with the casing's normal and sliding directions (``casing.contact_frames``).
        ``interface``: None, each node's own displacement; or a (3 n_tip, n_dofs) matrix C whose rows 3k..3k+2 give
        node k's contact displacement as C u (``fem.tip_patch_interface``: the mean over a patch of the tip, whose
        force is then C^T lambda, the reduced models' ``ReductionConfig.contact_patch``)."""
        sector = self.sector
        tip, rows = np.asarray(sector.tip_dofs), casing.node_indices(len(sector.tip_names))
        if (tip < 0).any():
            raise ValueError("the tip nodes' DOFs must all be on this rank (a serial sector)")
        C = _contact_interface(sector, interface)
        check_hand(sector.tip_nodes, casing.rotation_sense, "casing rotation_sense")
        normals, slide, theta_local = contact_frames(sector.tip_nodes[rows], casing.direction, casing.rotation_sense,
                                                     casing.cone_slope, sector.blade_frame_angle())
        pitch = 0.0 if sector.cyclic is None else 2.0 * np.pi / sector.cyclic.n_sectors
        N, S, theta0, labels = [], [], [], []
        for s, P in enumerate(self.maps):
            for k, node in enumerate(rows):
                # (3, n_x): the node's three DOFs (or its patch means) in sector s's frame
                block = P[tip[node]] if C is None else C[3 * node:3 * node + 3] @ P
                N.append(sp.csr_matrix(block.T @ normals[k]))
                S.append(sp.csr_matrix(block.T @ slide[k]))
                theta0.append(theta_local[k] + s * pitch)
                labels.append(f"{s}:{sector.tip_names[node]}")
        radius = np.tile(np.hypot(sector.tip_nodes[rows, 0], sector.tip_nodes[rows, 1]), len(self.maps))
        return ContactOperators(N=sp.vstack(N).tocsr(), S=sp.vstack(S).tocsr(), theta0=np.array(theta0),
                                radius=radius, labels=tuple(labels))

    def modes(self, n_modes: int) -> tuple[np.ndarray, np.ndarray]:
        """The lowest n_modes eigenpairs of the carried linear model (omega (n,) rad/s, Phi (n_x, n), Phi^T M Phi
        = I), computed once per count."""
        if n_modes not in self._modes:
            self._modes[n_modes] = slepc_eigenpairs(self.K, self.M, n_modes)
        return self._modes[n_modes]

    def damping(self, law: ModalLaw) -> LowRankDamping:
        """The damping law's matrix on x (``dynamics.damping``: rank law.n_modes)."""
        omega, phi = self.modes(law.n_modes)
        return law.operator(self.M, omega, phi, self.K)

    def project_damping(self, law: ModalLaw, basis: np.ndarray) -> np.ndarray:
        """The law's matrix on a reduced model of one blade whose basis is ``basis`` (n_dofs, r) in the sector's
        DOFs (zero on the clamp): V^T C V with V = P^T basis, P the blade's map (n_repeat = 1 only)."""
        if len(self.maps) != 1:
            raise ValueError("project_damping: a blade's model only (n_repeat = 1)")
        basis = np.asarray(basis, float)
        if basis.ndim != 2 or basis.shape[0] != self.sector.n_dofs:
            raise ValueError(f"basis must be ({self.sector.n_dofs}, r), got {basis.shape}")
        if np.abs(basis[~self.free]).max(initial=0.0) > 0:
            raise ValueError("basis must vanish on the clamped DOFs")
        return self.damping(law).project(np.asarray(self.maps[0].T @ basis))

    def fields(self, x: np.ndarray) -> np.ndarray:
        """(n_repeat, n_dofs): each sector's displacement in its own frame."""
        return np.array([P @ x for P in self.maps])

    def internal(self, x: np.ndarray) -> np.ndarray:
        """The SVK internal force of all sectors at x (n_x,)."""
        f = evaluate_forces(self.sector, self.ops, self.fields(x), "f_int")
        return sum(P.T @ (self.free * fi) for P, fi in zip(self.maps, f))

    def tangent(self, x: np.ndarray) -> sp.csr_matrix:
        """The exact SVK tangent d internal / dx at x."""
        return sum(P.T @ self._restrict @ assemble_tangent_scipy(self.sector, self.ops, u) @ self._restrict @ P
                   for P, u in zip(self.maps, self.fields(x))).tocsr()


def _contact_interface(sector: Sector, interface):
    """``interface`` as CSR (3 n_tip, n_dofs), checked; None stays None."""
    if interface is None:
        return None
    C = sp.csr_matrix(interface)
    if C.shape != (3 * len(sector.tip_names), sector.n_dofs):
        raise ValueError(f"the contact interface must be (3 x {len(sector.tip_names)} tip nodes, {sector.n_dofs} "
                         f"DOFs), got {C.shape}")
    return C


def sector_harmonic_load(n_repeat: int, n_sectors: int, n_diameters: int, amplitude: float, omega: float,
                         ramp: float = 0.0) -> Callable[[float], np.ndarray]:
    """The amplitude (N) on each of the n_repeat sectors at time t: A e(t) sin(omega t - s N_d 2 pi / N) (a load of
    N_d nodal diameters travelling with the sector index), e(t) = (1 - cos(pi t / ramp)) / 2 for t < ramp, else 1
    (``ramp`` = 0: no envelope; a sector whose phase is not 0 then starts with a step)."""
    phase = np.arange(n_repeat) * n_diameters * 2 * np.pi / n_sectors
    return lambda t: amplitude * _envelope(t, ramp) * np.sin(omega * t - phase)


def _envelope(t: float, ramp: float) -> float:
    return 1.0 if t >= ramp else 0.5 * (1.0 - np.cos(np.pi * t / ramp))


@dataclasses.dataclass(frozen=True)
class NewmarkScheme:
    """The implicit scheme and its Newton: ``rho_inf`` None, Newmark's average acceleration (beta = 1/4, gamma =
    1/2, no numerical dissipation), or generalised alpha's spectral radius at infinite frequency in [0, 1] (Chung &
    Hulbert 1993); Newton stops at |r| <= max(rtol x max(|f_int|, |M a|, |f|, |f_contact|), atol) (atol in N: the
    floor the internal forces' round-off sets while the load is small), after max_iterations at most."""

    rho_inf: float | None = None
    rtol: float = 1e-8
    atol: float = 1e-6
    max_iterations: int = 30

    def __post_init__(self):
        if self.rho_inf is not None and not 0.0 <= self.rho_inf <= 1.0:
            raise ValueError(f"rho_inf must be in [0, 1] (or None: Newmark), got {self.rho_inf}")


@dataclasses.dataclass(frozen=True)
class SectorLoad:
    """A load on every sector carried: ``dof`` the sector DOF loaded (e.g. node LE's e_z, in the sector's frame) or a
    sector load vector (n_dofs,) per unit amplitude (e.g. ``patch_load``); ``amplitude`` t -> (n_repeat,) the force
    on each sector (N), e.g. ``sector_harmonic_load``."""

    dof: int | np.ndarray
    amplitude: Callable[[float], np.ndarray]


@dataclasses.dataclass(frozen=True)
class CasingContact:
    """The tip nodes touch ``casing``, the rotor turning at ``omega`` (rad/s); the ovalization ramp (eq. 38) is set
    for a run of ``duration`` s (None: the run's n_steps dt), as ``dynamics.explicit.simulate`` sets it;
    ``interface`` None, the nodes' own displacements, or a (3 n_tip, n_dofs) matrix C: the casing touches the patch
    means C u (``fem.tip_patch_interface``) and pushes with C^T lambda."""

    casing: Casing
    omega: float
    duration: float | None = None
    interface: object = None


class RepeatingNewmark:
    """The full order's transient problem: n_repeat sectors closed on themselves (or one blade, n_repeat = 1),
    ``RepeatingSectors``, from rest under a ``SectorLoad`` and/or a ``CasingContact``, with a
    ``dynamics.damping.ModalLaw`` (None: undamped), SVK's or ``ops``' law (exact tangent; ``nonlinear`` False: linear
    K), stepped by ``dynamics.newmark.Newmark`` under a ``NewmarkScheme`` at dt for n_steps.

    ``start()`` is the state at rest, ``step(k, x, v, a, touching)`` the step to t_k = k dt, ``run()`` the whole run
    (checkpointed), ``stepper`` the ``Newmark`` itself (``dynamics.energy.record_run`` runs it), ``strain_energy(x)``
    the potential of its internal force. Generalised alpha writes equilibrium at its alpha point, the internal forces
    as (1 - alpha_f) f(x_n+1) + alpha_f f(x_n), the contact multipliers as one force there (the result's ``lam`` and
    friction power are alpha-point quantities); the constraint stays on x_n+1."""

    def __init__(self, sector: Sector, n_repeat: int, dt: float, n_steps: int, *, ops: SvkOperators | None = None,
                 nonlinear: bool = True, load: SectorLoad | None = None, contact: CasingContact | None = None,
                 damping: ModalLaw | None = None, scheme: NewmarkScheme = NewmarkScheme()):
        if not (dt > 0 and n_steps >= 1):
            raise ValueError(f"dt must be > 0 s and n_steps >= 1, got {dt}, {n_steps}")
        if contact is not None and not (contact.omega is not None and np.isfinite(contact.omega)
                                        and contact.omega > 0):
            raise ValueError(f"omega must be an angular speed > 0 rad/s with a casing, got {contact.omega}")
        if damping is not None and not isinstance(damping, ModalLaw):
            raise ValueError(f"damping must be a dynamics.damping.ModalLaw or None, got {type(damping).__name__}")
        self.sector, self.n_repeat, self.dt, self.n_steps = sector, n_repeat, dt, n_steps
        self.nonlinear, self.load, self.damping, self.scheme = nonlinear, load, damping, scheme
        self.load_key = -1.0
        if load is not None:
            if np.ndim(load.dof) == 0:
                unit, self.load_key = np.eye(1, sector.n_dofs, int(load.dof)).ravel(), float(load.dof)
            else:
                unit = np.asarray(load.dof, dtype=float)
                if unit.shape != (sector.n_dofs,):
                    raise ValueError(f"a load vector must have the sector's {sector.n_dofs} DOFs, got {unit.shape}")
                self.load_key = -2.0 - float(unit @ np.linspace(1.0, 2.0, unit.size))  # a vector's fingerprint
        self.system = system = RepeatingSectors(sector, n_repeat, ops)
        keep = system.keep
        if load is None:
            def force(t):
                return np.zeros(keep.size)
        else:
            f_unit = [P.T @ unit for P in system.maps]

            def force(t):
                return sum(a * f for a, f in zip(load.amplitude(t), f_unit))

        self.casing = None if contact is None else contact.casing
        self.omega = None if contact is None else contact.omega
        self.interface = _contact_interface(sector, None if contact is None else contact.interface)
        self.contact = None if contact is None else system.contact_operators(contact.casing, self.interface)
        step_contact = None
        if contact is not None:
            casing, co = contact.casing, self.contact
            self.duration = n_steps * dt if contact.duration is None else float(contact.duration)
            if not self.duration > 0:
                raise ValueError(f"duration must be > 0 s, got {self.duration}")
            alpha = float(ramp_rate(self.duration, casing.ramp_fraction, casing.ramp_level))

            def clearance(t):
                theta = node_angles(co.theta0, contact.omega, t, casing.rotation_sense)
                return casing_clearance(theta, t, casing.c0, casing.p0, alpha, casing.width)

            self.clearance = clearance
            step_contact = StepContact(co.N, co.S, casing.mu, clearance)
        self.stepper = Newmark(system.M, system.internal if nonlinear else (lambda x: system.K @ x),
                               system.tangent if nonlinear else (lambda x: system.K),
                               lambda A: mumps_solver(A.tocsr()), force, rho_inf=scheme.rho_inf, rtol=scheme.rtol,
                               atol=scheme.atol, max_iterations=scheme.max_iterations, linear=not nonlinear,
                               C=None if damping is None else system.damping(damping), contact=step_contact)
        self._energy = None

    def start(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """x, v, a at rest (the acceleration equilibrium gives there)."""
        n = self.system.keep.size
        return np.zeros(n), np.zeros(n), self.stepper.acceleration_at_rest()

    def step(self, k: int, x, v, a, touching: bool):
        """The step from t_k-1 to t_k: (x, v, a, Newton iterations, multipliers)."""
        return self.stepper.step(x, v, a, k * self.dt, self.dt, touching)

    def strain_energy(self, x: np.ndarray) -> float:
        """The strain energy of all sectors at x (J), the potential of the internal force (``ops``' law; the linear
        problem's 1/2 x.K x)."""
        if not self.nonlinear:
            return float(0.5 * x @ (self.system.K @ x))
        if self._energy is None:
            self._energy = strain_energy_form(self.sector, self.system.ops)
        return sum(evaluate_strain_energy(self.sector, self.system.ops, self._energy, u)
                   for u in self.system.fields(x))

    def tip_values(self, per_sector: np.ndarray) -> np.ndarray:
        """(n_repeat, n_tip, 3): the tip nodes' displacements (with an interface, the patch means C u)."""
        tip = np.asarray(self.sector.tip_dofs)
        if self.interface is None:
            return per_sector[:, tip]
        return (self.interface @ per_sector.T).T.reshape((self.n_repeat,) + tip.shape)

    def signature_fields(self, snapshot_every: int) -> list[tuple[str, float]]:
        """What a checkpoint of this run must match, named: every argument that changes its steps (the optional
        groups only where they apply, behind a negative tag where they could be mistaken for another group)."""
        casing, contact, damping, sector = self.casing, self.contact, self.damping, self.sector
        interface = self.interface
        fields = [("n_repeat", self.n_repeat), ("load", self.load_key), ("dt", self.dt), ("n_steps", self.n_steps),
                  ("nonlinear", float(self.nonlinear)), ("snapshot_every", snapshot_every),
                  ("kept_dofs", self.system.keep.size), ("sector_dofs", sector.n_dofs)]
        if self.scheme.rho_inf is not None:
            fields.append(("rho_inf", self.scheme.rho_inf))
        if casing is not None:
            fields += [("omega", self.omega), ("duration", self.duration), ("c0", casing.c0), ("h_b", casing.h_b),
                       ("mu", casing.mu), ("direction", "xrc".index(casing.direction[0])),
                       ("rotation_sense", casing.rotation_sense), ("ramp_fraction", casing.ramp_fraction),
                       ("ramp_level", casing.ramp_level), ("width", casing.width), ("cone_slope", casing.cone_slope),
                       ("contact_rows", contact.N.shape[0]), ("theta0_sum", float(contact.theta0.sum()))]
        if interface is not None:
            fields.append(("interface", float(np.linspace(1.0, 2.0, interface.shape[0])
                                              @ (interface @ np.linspace(1.0, 2.0, sector.n_dofs)))))
        if damping is not None:
            fields += [("damping_tag", -4.0), ("damping_low", damping.low), ("damping_high", damping.high),
                       ("damping_n_low", damping.n_low), ("damping_n_modes", damping.n_modes)]
        law = self.system.ops.law
        if law != "svk":
            fields += [("law_tag", -5.0), ("law", 1.0 + sorted(forms.HYPERELASTIC_LAWS).index(law))]
        return fields

    def signature(self, snapshot_every: int) -> np.ndarray:
        """``signature_fields``' values, as a checkpoint stores them."""
        return np.array([value for _, value in self.signature_fields(snapshot_every)])

    def same_steps(self, signature: np.ndarray) -> bool:
        """Whether a checkpoint's ``signature`` is of this run's steps, whatever its snapshot spacing."""
        names = [name for name, _ in self.signature_fields(0)]
        ours, theirs, slot = self.signature(0), np.asarray(signature), names.index("snapshot_every")
        return theirs.shape == ours.shape and np.array_equal(np.delete(theirs, slot), np.delete(ours, slot))

    def run(self, snapshot_every: int = 20, checkpoint: str | Path | None = None,
            checkpoint_seconds: float = 60.0) -> RepeatingSectorResult:
        """All n_steps from rest: tip displacements every step, sector fields every ``snapshot_every`` steps.
        ``checkpoint``: an .npz file the run saves its state to every ``checkpoint_seconds`` and resumes from (a
        file written for another run is refused); SIGTERM or SIGINT: saved at the step, then the run stops."""
        t_wall = time.perf_counter()
        system, contact, stepper, n_repeat = self.system, self.contact, self.stepper, self.n_repeat
        x, v, a = self.start()
        tip = np.asarray(self.sector.tip_dofs)
        tips, fields, snaps, its = [np.zeros((n_repeat,) + tip.shape)], [], [], []
        lams = [] if contact is None else [np.zeros(contact.N.shape[0])]
        checks = np.array([0.0, -np.inf])                                  # max penetration, friction power
        signature = self.signature(snapshot_every)
        start, saved, refreshes = 1, time.perf_counter(), 0
        if checkpoint is not None and Path(checkpoint).is_file():
            with np.load(checkpoint) as data:
                if not np.array_equal(data["signature"], signature):
                    raise ValueError(f"checkpoint {checkpoint} belongs to another run: remove it or give another path")
                x, v, a = data["x"], data["v"], data["a"]
                tips, fields = list(data["tips"]), list(data["fields"])
                snaps, its, refreshes = list(data["snaps"]), list(data["its"]), int(data["refreshes"])
                lams = list(data["lams"]) if contact is not None else lams
                checks = data["checks"] if "checks" in data.files else checks
                start = int(data["step"]) + 1
                t_wall -= float(data["elapsed"]) if "elapsed" in data.files else 0.0   # wall of the earlier parts
            LOG.info("resuming from %s at step %d", checkpoint, start)
        stepper.refreshes = refreshes
        dt, casing = self.dt, self.casing
        with checkpointing() if checkpoint is not None else contextlib.nullcontext():
            for k in range(start, self.n_steps + 1):
                x_old = x
                x, v, a, it, lam = self.step(k, x, v, a, contact is not None and lams[-1].any())
                its.append(it)
                per_sector = system.fields(x)
                tips.append(self.tip_values(per_sector))
                if contact is not None:
                    lams.append(lam)
                    checks[0] = max(checks[0], -(self.clearance(k * dt) - contact.N @ x).min())
                    on = lam > 0
                    if on.any():                                         # sliding: rotation + the node's own motion
                        power = friction_power(casing.mu * lam, self.omega, contact.radius,
                                               contact.S @ (x - x_old) / dt)
                        checks[1] = max(checks[1], float(power[on].max()))
                if k % snapshot_every == 0:
                    fields.append(per_sector)
                    snaps.append(k)
                if checkpoint is not None and (time.perf_counter() - saved > checkpoint_seconds or k == self.n_steps
                                               or requested() is not None):
                    save_npz(checkpoint, signature=signature, x=x, v=v, a=a, tips=np.array(tips),
                             fields=np.array(fields).reshape((-1, n_repeat, self.sector.n_dofs)),
                             snaps=np.array(snaps, np.int64), its=np.array(its, np.int64),
                             refreshes=stepper.refreshes, step=k, elapsed=time.perf_counter() - t_wall,
                             lams=np.array(lams), checks=checks)
                    saved = time.perf_counter()
                    stop_if_requested(lambda: None)                        # saved just above
        LOG.info("repeating-sector Newmark: %d steps, %d factorisations, %.1f s", self.n_steps, stepper.refreshes,
                 time.perf_counter() - t_wall)
        touched = contact is not None
        return RepeatingSectorResult(t=np.arange(self.n_steps + 1) * dt, tip=np.array(tips), fields=np.array(fields),
                                     snapshots=np.array(snaps, dtype=np.int64), iterations=np.array(its),
                                     refreshes=stepper.refreshes, wall=time.perf_counter() - t_wall,
                                     lam=np.array(lams) if touched else None,
                                     max_penetration=float(max(checks[0], 0.0)) if touched else float("nan"),
                                     friction_power=float(checks[1]) if touched and np.isfinite(checks[1])
                                     else float("nan"))


def solve_repeating_newmark(sector: Sector, n_repeat: int, load_dof: int | np.ndarray | None,
                            load: Callable[[float], np.ndarray] | None, dt: float, n_steps: int,
                            nonlinear: bool = True, rtol: float = 1e-8, snapshot_every: int = 20,
                            max_iterations: int = 30, atol: float = 1e-6, ops: SvkOperators | None = None,
                            checkpoint: str | Path | None = None, checkpoint_seconds: float = 60.0,
                            casing: Casing | None = None, omega: float | None = None,
                            duration: float | None = None, rho_inf: float | None = None,
                            contact_interface=None, damping: ModalLaw | None = None) -> RepeatingSectorResult:
    """``RepeatingNewmark(...).run(...)`` with its parts as flat arguments (the callers' form before the problem
    object): load_dof and load make a ``SectorLoad``; casing, omega, duration and contact_interface a
    ``CasingContact``; rho_inf, rtol, atol and max_iterations a ``NewmarkScheme``."""
    if casing is not None and omega is None:
        raise ValueError(f"omega must be an angular speed > 0 rad/s with a casing, got {omega}")
    if (load is None) != (load_dof is None):
        raise ValueError("give load_dof and load together (or neither)")
    problem = RepeatingNewmark(
        sector, n_repeat, dt, n_steps, ops=ops, nonlinear=nonlinear,
        load=None if load is None else SectorLoad(load_dof, load),
        contact=None if casing is None else CasingContact(casing, omega, duration, contact_interface),
        damping=damping, scheme=NewmarkScheme(rho_inf, rtol, atol, max_iterations))
    return problem.run(snapshot_every, checkpoint, checkpoint_seconds)

