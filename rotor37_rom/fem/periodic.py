"""Full-order transient of a bladed disk under a load of N_d nodal diameters: the response repeats every
N / gcd(N, N_d) sectors, so that many sectors closed on themselves (``cyclic.repeating_sector_maps``) carry the whole
disk's nonlinear response. Implicit Newmark (average acceleration) with Newton on the exact SVK tangent, every
sector's forces and tangents from the one sector's compiled forms; the factorisation of the iteration matrix is kept
across iterations and steps while Newton converges fast (modified Newton), refreshed when it does not.

Part of the dolfinx adapter (``rotor37_rom.fem``); serial. The reference the disk's reduced models are checked
against (paper §3.3: full-order GNL responses, Fig. 16).
"""
from __future__ import annotations

import dataclasses
import logging
import time
from pathlib import Path
from typing import Callable

import numpy as np
import scipy.sparse as sp

from rotor37_rom.cyclic import repeating_sector_maps

from .operators import (SvkOperators, _require_serial, assemble_mass, assemble_stiffness, assemble_tangent_scipy,
                        create_svk_operators, evaluate_forces, free_dofs, petsc_to_scipy)
from .sector import Sector
from .solvers import mumps_solver

__all__ = ["RepeatingSectors", "RepeatingSectorResult", "solve_repeating_newmark", "sector_harmonic_load"]

LOG = logging.getLogger(__name__)


@dataclasses.dataclass(frozen=True)
class RepeatingSectorResult:
    """t (n + 1,) s; tip (n + 1, n_repeat, n_tip, 3) tip-node displacements of each sector in its frame (m);
    fields: (n_snap, n_repeat, n_dofs) sector fields every ``snapshot_every`` steps, at t[snapshots]; iterations
    (n,) Newton iterations per step; refreshes: factorisations; wall: s."""

    t: np.ndarray
    tip: np.ndarray
    fields: np.ndarray
    snapshots: np.ndarray
    iterations: np.ndarray
    refreshes: int
    wall: float


class RepeatingSectors:
    """n_repeat sectors closed on themselves (``cyclic.repeating_sector_maps``) with the clamped DOFs removed: the
    unknown x holds the free DOFs of all of them; ``fields(x)`` gives each sector's DOF vector in its own frame.

    Attributes: maps [(n_dofs, n_x)] per sector; keep: the slots of x among the map's; K, M: linear stiffness and
    mass (n_x, n_x) CSR; free: (n_dofs,) bool, the sector's unclamped DOFs."""

    def __init__(self, sector: Sector, n_repeat: int, ops: SvkOperators | None = None):
        _require_serial(sector, "RepeatingSectors")
        if sector.cyclic is None:
            raise ValueError(f"{sector.source} is not a cyclic sector")
        self.sector, self.ops = sector, ops or create_svk_operators(sector)
        n = sector.n_dofs
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

    def _sum(self, A_sector):
        return sum(P.T @ self._restrict @ A_sector @ self._restrict @ P for P in self.maps).tocsr()

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


def sector_harmonic_load(n_repeat: int, n_sectors: int, n_diameters: int, amplitude: float, omega: float,
                         ramp: float = 0.0) -> Callable[[float], np.ndarray]:
    """The amplitude (N) on each of the n_repeat sectors at time t: A e(t) sin(omega t - s N_d 2 pi / N) (a load of
    N_d nodal diameters travelling with the sector index), e(t) = (1 - cos(pi t / ramp)) / 2 for t < ramp, else 1
    (``ramp`` = 0: no envelope; a sector whose phase is not 0 then starts with a step)."""
    phase = np.arange(n_repeat) * n_diameters * 2 * np.pi / n_sectors
    return lambda t: amplitude * _envelope(t, ramp) * np.sin(omega * t - phase)


def _envelope(t: float, ramp: float) -> float:
    return 1.0 if t >= ramp else 0.5 * (1.0 - np.cos(np.pi * t / ramp))


def solve_repeating_newmark(sector: Sector, n_repeat: int, load_dof: int, load: Callable[[float], np.ndarray],
                            dt: float, n_steps: int, nonlinear: bool = True, rtol: float = 1e-8,
                            snapshot_every: int = 20, max_iterations: int = 30, atol: float = 1e-6,
                            ops: SvkOperators | None = None, checkpoint: str | Path | None = None,
                            checkpoint_seconds: float = 60.0) -> RepeatingSectorResult:
    """Implicit Newmark (beta = 1/4, gamma = 1/2, undamped) of n_repeat sectors closed on themselves, from rest.

    Args:
        sector: a cyclic sector (serial); n_repeat: sectors carried (dividing N).
        load_dof: the sector DOF loaded in every sector (e.g. node LE's e_z), in the sector's frame.
        load: t -> (n_repeat,) force on each sector's load DOF (N), e.g. ``sector_harmonic_load``.
        dt, n_steps: time step (s) and steps; nonlinear: SVK (exact tangent) or linear K.
        rtol, atol: Newton stops at |r| <= max(rtol x max(|f_int|, |M a|, |f|), atol) (atol in N: the floor that the
            round-off of the internal forces sets while the load is still small).
        checkpoint: an .npz file the run saves its state to every ``checkpoint_seconds`` and resumes from (a file
            written for other arguments is refused).
    """
    if not (dt > 0 and n_steps >= 1):
        raise ValueError(f"dt must be > 0 s and n_steps >= 1, got {dt}, {n_steps}")
    t_wall = time.perf_counter()
    system = RepeatingSectors(sector, n_repeat, ops)
    M, maps, keep = system.M, system.maps, system.keep
    f_unit = [P.T @ np.eye(1, sector.n_dofs, load_dof).ravel() for P in maps]
    beta, gamma = 0.25, 0.5

    def force(t):
        return sum(a * f for a, f in zip(load(t), f_unit))

    internal = system.internal if nonlinear else (lambda x: system.K @ x)
    tangent = system.tangent if nonlinear else (lambda x: system.K)
    x, v = np.zeros(keep.size), np.zeros(keep.size)
    a = mumps_solver(M)(force(0.0))
    refreshes = 0
    tip = np.asarray(sector.tip_dofs)
    tips, fields, snaps, its = [np.zeros((n_repeat,) + tip.shape)], [], [], []
    signature = np.array([n_repeat, load_dof, dt, n_steps, float(nonlinear), snapshot_every, x.size, sector.n_dofs])
    start, saved = 1, time.perf_counter()
    if checkpoint is not None and Path(checkpoint).is_file():
        with np.load(checkpoint) as data:
            if not np.array_equal(data["signature"], signature):
                raise ValueError(f"checkpoint {checkpoint} belongs to another run: remove it or give another path")
            x, v, a = data["x"], data["v"], data["a"]
            tips, fields = list(data["tips"]), list(data["fields"])
            snaps, its, refreshes = list(data["snaps"]), list(data["its"]), int(data["refreshes"])
            start = int(data["step"]) + 1
            t_wall -= float(data["elapsed"]) if "elapsed" in data.files else 0.0   # wall of the earlier parts
        LOG.info("resuming from %s at step %d", checkpoint, start)
    cache = {"h": None, "solve": None, "refreshes": refreshes}

    def advance(x, v, a, t_new, h):
        """One Newmark step of length h to t_new: (x, v, a, iterations), or None where Newton fails."""
        c0 = 1.0 / (beta * h * h)
        f_ext = force(t_new)
        inertia = -M @ (c0 * x + v / (beta * h) + (0.5 / beta - 1.0) * a) - f_ext

        def residual(y):
            return c0 * (M @ y) + internal(y) + inertia

        x_new = x + h * v + 0.5 * h * h * a                  # predictor
        r = residual(x_new)
        norm = np.linalg.norm(r)
        for it in range(max_iterations + 1):
            acc = c0 * (x_new - x) - v / (beta * h) - (0.5 / beta - 1.0) * a
            scale = max(np.linalg.norm(M @ acc), np.linalg.norm(f_ext), np.linalg.norm(r + f_ext - M @ acc), 1e-300)
            LOG.debug("t %.6e it %d |r| = %.3e", t_new, it, norm)
            if norm <= max(rtol * scale, atol):
                return x_new, v + h * ((1 - gamma) * a + gamma * acc), acc, it
            if it == max_iterations or not np.isfinite(norm):
                return None
            trial = None
            if cache["solve"] is not None and cache["h"] == h:   # modified Newton: the kept factorisation
                trial = x_new - cache["solve"](r)
                r_trial = residual(trial)
                if np.linalg.norm(r_trial) > 0.25 * norm:        # too slow: refresh below
                    trial = None
            if trial is None:                                    # Newton with a backtracking line search
                cache["solve"] = mumps_solver((c0 * M + tangent(x_new)).tocsr())
                cache["h"] = h
                cache["refreshes"] += 1
                step = cache["solve"](r)
                for _ in range(6):
                    trial = x_new - step
                    r_trial = residual(trial)
                    if np.linalg.norm(r_trial) < norm:
                        break
                    step = 0.5 * step
                else:
                    return None                                  # no descent: the step is too long
            x_new, r, norm = trial, r_trial, np.linalg.norm(r_trial)
        return None

    def advance_adaptive(x, v, a, t_new, h, depth=0):
        """The step, split in halves (recursively, 5 levels) where Newton fails: the point load's local
        nonlinearity needs small load increments while the response does not."""
        out = advance(x, v, a, t_new, h)
        if out is not None:
            return out
        if depth == 5:
            raise RuntimeError(f"Newmark-Newton did not converge at t = {t_new:.6e} s even with dt / 32")
        LOG.info("t = %.6e s: Newton failed, two half steps", t_new)
        x, v, a, i1 = advance_adaptive(x, v, a, t_new - h / 2, h / 2, depth + 1)
        x, v, a, i2 = advance_adaptive(x, v, a, t_new, h / 2, depth + 1)
        return x, v, a, i1 + i2

    for k in range(start, n_steps + 1):
        x, v, a, it = advance_adaptive(x, v, a, k * dt, dt)
        its.append(it)
        per_sector = system.fields(x)
        tips.append(per_sector[:, tip])
        if k % snapshot_every == 0:
            fields.append(per_sector)
            snaps.append(k)
        if checkpoint is not None and (time.perf_counter() - saved > checkpoint_seconds or k == n_steps):
            tmp = Path(str(checkpoint) + ".tmp.npz")
            np.savez(tmp, signature=signature, x=x, v=v, a=a, tips=np.array(tips),
                     fields=np.array(fields).reshape((-1, n_repeat, sector.n_dofs)),
                     snaps=np.array(snaps, np.int64), its=np.array(its, np.int64), refreshes=cache["refreshes"],
                     step=k, elapsed=time.perf_counter() - t_wall)
            tmp.replace(checkpoint)
            saved = time.perf_counter()
    refreshes = cache["refreshes"]
    LOG.info("repeating-sector Newmark: %d steps, %d factorisations, %.1f s", n_steps, refreshes,
             time.perf_counter() - t_wall)
    return RepeatingSectorResult(t=np.arange(n_steps + 1) * dt, tip=np.array(tips), fields=np.array(fields),
                                 snapshots=np.array(snaps, dtype=np.int64), iterations=np.array(its),
                                 refreshes=refreshes, wall=time.perf_counter() - t_wall)
