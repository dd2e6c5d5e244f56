"""Implicit Newmark (average acceleration) and generalised alpha, written once, with the operators given (pyMOR /
dolfinx-demo style): the full order's steps (sparse matrices, MUMPS) of a sector repeat or a blade, and the dense
reduced models' (``simulate_newmark``: the disk's forced response, the builders' training runs).

``Newmark`` takes M (any matrix with ``@``), optionally a viscous damping matrix C, the internal force ``internal(x)``,
its tangent ``tangent(x)``, a ``factorise(A) -> solve`` function, the load ``force(t)`` and optionally a unilateral
contact (``StepContact``: gaps, normal and sliding rows, friction coefficient). Each step writes equilibrium at the
alpha point (at t_n+1 for Newmark), starts from a predictor, iterates with a kept factorisation of the iteration matrix
while that converges fast (modified Newton), else refactorises at the iterate (Newton with a backtracking line search),
corrects every iterate by the contact multipliers that close its penetrations, and splits a step whose Newton fails in
two halves, recursively. ``fem.solve_repeating_newmark`` runs it on the full order (a sector repeat or a blade),
``simulate_newmark`` on a dense reduced model.

Its stopping test is the residual against the largest force term (``rtol``), floored at the residual's own round-off
(``ROUNDOFF`` times the terms it is summed from, the step's history c0 M x_n among them): a stiff reduced GNL model
at a fine step cannot meet an rtol below that (the disk's r_MD = 10 GNL forced response at 4,000 rad/s, whose
iterates stalled at |r| ~ 1e-13 of the inertia terms until the floor was added).
"""
from __future__ import annotations

import dataclasses
import logging
from typing import Callable

import numpy as np
import scipy.linalg
import scipy.sparse as sp

from rotor37_rom.dynamics.casing import ContactSetError, ContactSolver
from rotor37_rom.dynamics.damping import LowRankDamping, woodbury

__all__ = ["Newmark", "StepContact", "dense_newmark", "simulate_newmark", "simulate_linear_newmark", "ROUNDOFF"]

LOG = logging.getLogger(__name__)
#: The residual's round-off, relative to the terms it is summed from: u sqrt(n) for sums of n ~ 65,000 terms (a
#: dense reduced model's rows, a sparse row's and the vector norm), with u = 2.2e-16
ROUNDOFF = 256 * np.finfo(float).eps


@dataclasses.dataclass(frozen=True)
class StepContact:
    """A unilateral contact for ``Newmark``: N x (n_c,) the normal displacements of the contact nodes, S x their
    sliding displacements (N, S: (n_c, n_x), SciPy sparse or dense), mu the Coulomb friction coefficient and
    gaps(t) (n_c,) the gaps at x = 0 at time t; the constraint is N x <= gaps(t), the contact force -(N + mu S)^T
    lambda with lambda >= 0 (``casing.ContactSolver``)."""

    N: object
    S: object
    mu: float
    gaps: Callable[[float], np.ndarray]


class Newmark:
    """Implicit Newmark (beta = 1/4, gamma = 1/2) of M x'' + C x' + internal(x) = force(t), or with ``rho_inf`` the
    generalised-alpha scheme (Chung & Hulbert 1993: alpha_m = (2 rho - 1) / (rho + 1), alpha_f = rho / (rho + 1);
    rho_inf = 1 is average acceleration written at the mid-point, rho_inf < 1 damps the modes the step does not
    resolve), optionally with unilateral contact.

    Args:
        M: mass (n, n), any matrix with ``@`` that ``factorise`` and ``tangent(x)`` add to. C: viscous damping
            (n, n), or a ``damping.LowRankDamping`` (solved by Woodbury on the factorisation without it), or None
            (undamped). internal: x -> internal force (n,); tangent: x -> its derivative (n, n).
            factorise: A -> solve, solve(B) = A^-1 B for B (n,) or (n, m) (e.g. ``fem.mumps_solver``). force: t ->
            load (n,).
        rtol, atol: a step has converged when |residual| <= max(rtol x scale, atol), scale the largest of the
            inertia, the load, the other forces and the contact force. The residual's round-off is ~u c0 |M x|,
            c0 = 1 / (beta h^2) (the inertia at x_n+1 and at x_n are computed apart), i.e. u / (omega h)^2 of the
            forces: an rtol below ~1e-12 is not met at fine steps, nor any rtol with atol = 0 where the forces vanish;
            the test is therefore floored at ``ROUNDOFF`` times those inertia terms. history_scale: the scale
            includes them (the effective load c0 M x_n + ...): rtol is then the relative accuracy of the step's
            displacement, as a dense reduced model's runs take it (``simulate_newmark``).
        max_iterations: iterations per step before the step is split. contact: a ``StepContact`` or None. linear:
        ``internal`` is linear (its tangent constant): in contact the kept factorisation stays exact. max_halvings:
        levels of step splitting before a step is given up (RuntimeError).

    ``refreshes`` counts the factorisations of the iteration matrix. One instance per run: it keeps the last
    factorisation and (generalised alpha) the internal forces of the last converged state.
    """

    def __init__(self, M, internal: Callable, tangent: Callable, factorise: Callable, force: Callable, *,
                 rho_inf: float | None = None, rtol: float = 1e-8, atol: float = 0.0, max_iterations: int = 30,
                 contact: StepContact | None = None, linear: bool = False, max_halvings: int = 5, C=None,
                 history_scale: bool = False):
        if rho_inf is not None and not 0.0 <= rho_inf <= 1.0:
            raise ValueError(f"rho_inf must be in [0, 1] (or None: Newmark), got {rho_inf}")
        self.M, self.C, self.internal, self.tangent = M, C, internal, tangent
        self.factorise, self.force = factorise, force
        if rho_inf is None:
            self.alpha_m = self.alpha_f = 0.0
        else:
            self.alpha_m, self.alpha_f = (2 * rho_inf - 1) / (rho_inf + 1), rho_inf / (rho_inf + 1)
        self.gamma, self.beta = 0.5 - self.alpha_m + self.alpha_f, 0.25 * (1 - self.alpha_m + self.alpha_f) ** 2
        self.rtol, self.atol, self.max_iterations = rtol, atol, max_iterations
        self.contact, self.linear, self.max_halvings = contact, linear, max_halvings
        self.history_scale = history_scale
        if contact is not None:
            self.B = sp.csr_matrix((contact.N + contact.mu * contact.S).T)    # contact force: -B lambda
        self.solve, self.h, self.refreshes = None, None, 0
        self._carried = {"x": None, "f": None}   # the internal forces of the last converged state

    def acceleration_at_rest(self) -> np.ndarray:
        """a_0 = M^-1 force(0), the acceleration from rest (x = 0, v = 0, internal(0) = 0)."""
        return self.factorise(self.M)(self.force(0.0))

    def step(self, x, v, a, t_new: float, h: float, touching: bool = False, depth: int = 0):
        """One step of length h to t_new: (x, v, a, iterations, multipliers (None without contact)). Where Newton
        fails the step is split in two halves, recursively (``max_halvings`` levels): a local nonlinearity (a point
        load, a contact) may need small increments while the response does not. ``touching``: the step starts in
        contact, and the predictor keeps the velocity instead of the acceleration."""
        try:
            out = self._advance(x, v, a, t_new, h, touching)
        except ContactSetError:                                  # no admissible contact set from this iterate
            out = None
        if out is not None:
            return out
        if depth == self.max_halvings:
            raise RuntimeError(f"Newmark-Newton did not converge at t = {t_new:.6e} s even with dt / "
                               f"{2 ** self.max_halvings}")
        LOG.info("t = %.6e s: Newton failed, two half steps", t_new)
        x, v, a, i1, lam = self.step(x, v, a, t_new - h / 2, h / 2, touching, depth + 1)
        x, v, a, i2, lam = self.step(x, v, a, t_new, h / 2, lam is not None and lam.any(), depth + 1)
        return x, v, a, i1 + i2, lam

    def _refactorise(self, y, h):
        """The iteration matrix at y, factorised; with contact also its response to unit multipliers."""
        A = (1 - self.alpha_m) / (self.beta * h * h) * self.M + (1 - self.alpha_f) * self.tangent(y)
        c_damp = (1 - self.alpha_f) * self.gamma / (self.beta * h)
        if isinstance(self.C, LowRankDamping):      # C = S + U D U^T: (A + c S)'s factorisation + Woodbury
            A = A if self.C.S is None else A + c_damp * self.C.S
            self.solve = woodbury(self.factorise(A), self.C.U, c_damp * self.C.d)
        else:
            self.solve = self.factorise(A if self.C is None else A + c_damp * self.C)
        self.h = h
        self.refreshes += 1
        if self.contact is not None:
            N, S = self.contact.N, self.contact.S
            WN, WT = -self.solve(_dense(N.T)), -self.solve(_dense(S.T))
            self._WB = WN + self.contact.mu * WT                 # the iterate's change per multiplier
            self._contact_solver = ContactSolver(np.asarray(N @ WN), np.asarray(N @ WT))

    def _advance(self, x, v, a, t_new, h, touching):
        """The Newton iteration of one step: (x, v, a, iterations, multipliers), or None where it fails."""
        eq = _StepEquations(self, x, v, a, t_new, h)
        beta, gamma, c0 = self.beta, self.gamma, eq.c0
        # predictor: in contact a_n is mostly the contact nodes' ringing at frequencies the step does not resolve,
        # and extrapolating it costs Newton 8-11 iterations per step instead of 3-4 (ci blade, GNL, generalised
        # alpha, the second bump passage at 1,280 rad/s); out of contact it is the better guess
        x_new = x + h * v + (0.0 if touching else 0.5 * h * h * a)
        lam = None if self.contact is None else np.zeros(self.B.shape[1])
        r = eq.residual(x_new)
        norm = np.linalg.norm(r)
        for it in range(self.max_iterations + 1):
            acc = c0 * (x_new - x) - v / (beta * h) - (0.5 / beta - 1.0) * a
            f_c = 0.0 if lam is None else np.linalg.norm(self.B @ lam)
            scale = max(np.linalg.norm(self.M @ acc), np.linalg.norm(eq.f_ext),
                        np.linalg.norm(r + eq.f_ext - self.M @ acc), f_c, 1e-300)
            LOG.debug("t %.6e it %d |r| = %.3e", t_new, it, norm)
            history = eq.history(x_new)
            if self.history_scale:
                scale = max(scale, history)
            if norm <= max(self.rtol * scale, self.atol, ROUNDOFF * history) and eq.admissible(x_new):
                if eq.last_y is x_new:
                    self._carried["x"], self._carried["f"] = x_new, eq.last_f
                return x_new, v + h * ((1 - gamma) * a + gamma * acc), acc, it, lam
            if it == self.max_iterations or not np.isfinite(norm):
                return None
            trial = self._iterate(eq, x_new, lam, r, norm, h)
            if trial is None:
                return None                                      # no descent: the step is too long
            x_new, lam, r, norm = trial
        return None

    def _iterate(self, eq, y, lam, r, norm, h):
        """The next iterate from y (residual r, |r + B lam| = norm): (y, lam, r, norm), or None without descent.
        Modified Newton with the kept factorisation where it converges fast (ratio <= 1/4); else Newton on the
        tangent at y with a backtracking line search. In contact with a nonlinear force, Newton on the exact tangent
        always (a kept factorisation's stale compliance at the contact nodes makes the multipliers oscillate between
        iterates: measured on the ci blade)."""
        in_contact = not self.linear and lam is not None and (lam.any() or not eq.admissible(y))
        if self.solve is not None and self.h == h and not in_contact:   # the kept factorisation
            try:
                trial, lam_t = eq.correct(y - self.solve(r))
                r_trial = eq.residual(trial)
                norm_t = np.linalg.norm(eq.total(r_trial, lam_t))
            except ContactSetError:                              # the stale compliance: refresh below
                trial = None
            # too slow: refresh below (from a penetrating iterate any admissible one is progress)
            if trial is not None and not (norm_t > 0.25 * norm and eq.admissible(y)):
                return trial, lam_t, r_trial, norm_t
        self._refactorise(y, h)                                  # Newton with a backtracking line search
        step = self.solve(r)
        for _ in range(6):
            trial, lam_t = eq.correct(y - step)
            r_trial = eq.residual(trial)
            norm_t = np.linalg.norm(eq.total(r_trial, lam_t))
            # a change of the contact set is a finite step of the semi-smooth Newton (exact tangent)
            if norm_t < norm or not (eq.admissible(y) and _same_set(lam, lam_t)):
                return trial, lam_t, r_trial, norm_t
            step = 0.5 * step
        return None


class _StepEquations:
    """One step's equations: the residual at the alpha point as a function of x_n+1 = y, with the inertia of
    a(y) = c0 (y - x) - v / (beta h) - (1 / (2 beta) - 1) a and the load; the contact correction and admissibility at
    t_n+1."""

    def __init__(self, nm: Newmark, x, v, a, t_new, h):
        self.nm, M, alpha_m, alpha_f, beta = nm, nm.M, nm.alpha_m, nm.alpha_f, nm.beta
        self.c0 = c0 = 1.0 / (beta * h * h)
        self.f_ext = (1 - alpha_f) * nm.force(t_new) + (alpha_f * nm.force(t_new - h) if alpha_f else 0.0)
        # the inertia at the alpha point without y
        self.inertia = -M @ ((1 - alpha_m) * (c0 * x + v / (beta * h) + (0.5 / beta - 1.0) * a) - alpha_m * a) \
            - self.f_ext
        if alpha_f:             # f(x_n): carried over from the step that converged to x_n (the same evaluation)
            carried = nm._carried
            self.inertia = self.inertia + alpha_f * (carried["f"] if carried["x"] is x else nm.internal(x))
        if nm.C is not None:    # damping at the alpha point: v(y) = cv y + the part without y
            gamma = nm.gamma
            self.cv = (1 - alpha_f) * gamma / (beta * h)
            v_rest = -gamma / (beta * h) * x + (1 - gamma / beta) * v + h * (1 - 0.5 * gamma / beta) * a
            self.inertia = self.inertia + nm.C @ ((1 - alpha_f) * v_rest + alpha_f * v)
        self.inertia_norm = np.linalg.norm(self.inertia)
        self.gap_free = None if nm.contact is None else nm.contact.gaps(t_new)
        self.last_y = self.last_f = None

    def residual(self, y):
        nm = self.nm
        f = nm.internal(y)
        self.last_y, self.last_f = y, f
        self.last_my = (1 - nm.alpha_m) * self.c0 * (nm.M @ y)
        r = self.last_my + (1 - nm.alpha_f) * f + self.inertia
        return r if nm.C is None else r + self.cv * (nm.C @ y)

    def history(self, y) -> float:
        """The size of the terms the residual at y is summed from: its inertia at y and the step's history (c0 M x_n,
        the load, the damping): what bounds its round-off."""
        my = self.last_my if self.last_y is y else (1 - self.nm.alpha_m) * self.c0 * (self.nm.M @ y)
        return float(np.linalg.norm(my)) + self.inertia_norm

    def correct(self, y):
        """y with the multipliers that close its penetrations through the kept compliance, and them."""
        nm = self.nm
        if nm.contact is None:
            return y, None
        g = self.gap_free - nm.contact.N @ y
        if g.min() >= 0.0:
            return y, np.zeros(g.size)
        lam, _ = nm._contact_solver.solve(nm.contact.mu, g)    # ContactSetError: refreshed, then the step split
        return y + nm._WB @ lam, lam

    def total(self, r, lam):
        return r if lam is None else r + self.nm.B @ lam

    def admissible(self, y):                                   # round-off of the correction: ~1e-20 m
        return self.nm.contact is None or (self.gap_free - self.nm.contact.N @ y).min() >= -1e-15


def _dense(A) -> np.ndarray:
    return A.toarray() if sp.issparse(A) else np.asarray(A)


def _same_set(lam, other) -> bool:
    """Whether two multiplier vectors (None without contact) have the same nodes in contact."""
    return lam is None or other is None or np.array_equal(lam > 0, other > 0)


def simulate_linear_newmark(M: np.ndarray, C: np.ndarray, K: np.ndarray, f: Callable[[float], np.ndarray],
                            dt: float, n_steps: int) -> tuple[np.ndarray, np.ndarray]:
    """Average-acceleration Newmark for a small dense linear system from rest. Returns (t, q) with q (r, n+1)."""
    return simulate_newmark(M, C, K, f, dt, n_steps)


def _dense_solver(A) -> Callable:
    """A's LU factorisation (dense), as a solve function."""
    lu = scipy.linalg.lu_factor(_dense(A))
    return lambda B: scipy.linalg.lu_solve(lu, B)


def dense_newmark(M: np.ndarray, C: np.ndarray | None, K: np.ndarray, f: Callable[[float], np.ndarray], forces=None,
                  rtol: float = 1e-10, max_iterations: int = 40, rho_inf: float | None = None) -> Newmark:
    """The average-acceleration ``Newmark`` (or with ``rho_inf`` generalised alpha) of a dense reduced model M q'' +
    C q' + K q + g(q) = f(t): K q + g(q) as the internal force, K + dg/dq as its tangent, dense LU factorisations.
    ``forces``: the reduced nonlinear force g (``evaluate``/``jacobian``), None for the linear model (one
    factorisation for the run). Its stopping test is ``rtol`` of the largest term, the effective load c0 M q_n + ...
    among them (a relative accuracy of the displacement)."""
    r = K.shape[0]
    if forces is None:
        def internal(q):
            return K @ q

        def tangent(q):
            return K
    else:
        def internal(q):
            return K @ q + np.asarray(forces.evaluate(q)).reshape(r)

        def tangent(q):
            return K + forces.jacobian(q)
    damped = C is not None and np.any(C)
    return Newmark(M, internal, tangent, _dense_solver, f, rtol=rtol, max_iterations=max_iterations,
                   linear=forces is None, C=C if damped else None, history_scale=True, rho_inf=rho_inf)


def simulate_newmark(M: np.ndarray, C: np.ndarray, K: np.ndarray, f: Callable[[float], np.ndarray], dt: float,
                     n_steps: int, forces=None, rtol: float = 1e-10, max_iterations: int = 40
                     ) -> tuple[np.ndarray, np.ndarray]:
    """Average-acceleration Newmark (beta = 1/4, gamma = 1/2) of M q'' + C q' + K q + g(q) = f(t) from rest, dense
    (``dense_newmark``). Returns (t, q) with q (r, n_steps + 1)."""
    if not (dt > 0 and np.isfinite(dt) and isinstance(n_steps, (int, np.integer)) and n_steps >= 1):
        raise ValueError(f"dt must be finite and > 0 s and n_steps an integer >= 1, got {dt}, {n_steps}")
    r = K.shape[0]
    stepper = dense_newmark(M, C, K, f, forces, rtol, max_iterations)
    q, v = np.zeros(r), np.zeros(r)
    a = stepper.acceleration_at_rest()
    out = [q.copy()]
    for n in range(1, n_steps + 1):
        q, v, a, _, _ = stepper.step(q, v, a, n * dt, dt)
        out.append(q.copy())
    return np.arange(n_steps + 1) * dt, np.array(out).T
