"""Explicit central differences in reduced coordinates with forward-increment Lagrange-multiplier contact (§2.1.3).

Pure NumPy/SciPy. P simulations advance together (eq. 34): the state is Q (r, P) and every step is a few GEMMs,
the cubic forces included (premultiplied tensors X3, X4 of eqs. 32-33 over unique monomials, eqs. 35-36). Each
simulation has its own angular speed, clearance, bump height and friction coefficient, so a sweep over any of them
is one batch.

Step n -> n+1 (t_n = n h):
    prediction  Q* = X0 F(t_n) + X1 Q_n + X2 Q_{n-1} + X3(Q_n, Q_n) + X4(Q_n, Q_n, Q_n)           (eqs. 26, 28)
    detection   g*_k = c0 - (1 - exp(-alpha t_{n+1})) f(theta_k(t_{n+1})) - n_k . u*_k                  (eq. 38)
    contact     D lambda = g* on the active set, D = N W (-N - mu S)^T, W = (M/h^2 + C/2h)^{-1} = X0
                (the reduced operator, not a lumped mass), active set iterated until lambda >= 0 and no gap < 0
    correction  Q_{n+1} = Q* + W f_c, f_c = sum_k lambda_k (-n_k - mu s_k) at node k's DOFs          (eq. 27)

n_k is the contact normal (e_x, radial or the casing cone's), s_k the direction in which node k slides on the casing
(the rotation direction); sliding friction mu lambda_k acts along -s_k. Contact forces, penetrations and the power of
friction are outputs, and so is the work each force does on the blade in the scheme's own energy balance: with the
discrete energy E_{n+1/2} = 1/2 v M v + 1/2 q_{n+1} K q_n (v = (q_{n+1} - q_n)/h, ``discrete_energy``) a force f_n of
step n does the work f_n . (q_{n+1} - q_{n-1})/2 and the damping takes (q_{n+1} - q_{n-1}) C (q_{n+1} - q_{n-1})/4h, so
for the linear scheme E_{n+1/2} - E_{-1/2} = W_normal + W_friction + W_forcing - D_damping to round-off (eq. 27's
correction is a force of step n). This tells which contact force feeds a growing response. The massless-boundary variant
(Monjaraz Tec, Gross & Krack 2022) drops the inertia of the boundary DOFs: they follow the interior quasi-statically,
which removes the stiff single-node constraint modes from the stability limit (linear models only). The frequency cap
(spectral mass scaling, ``capped_mass``) keeps all inertia and every mode below the cap exact and slows the stiff modes
above it, for linear and GNL models; with GNL the step then comes from the tangent limit on representative states
(``gnl_time_step``, ``probe_states``).
"""
from __future__ import annotations

import contextlib
import copy
import dataclasses
import json
import time
from pathlib import Path
from typing import Callable, Sequence

import numpy as np
import scipy.linalg

from rotor37_rom.checks import real_number
from rotor37_rom.dynamics.casing import Casing, contact_matrices
from rotor37_rom.dynamics.contact_step import ContactStep, per_simulation_casings, row_operator
from rotor37_rom.dynamics.recorder import LoopState, Recorder, loop_state, save_loop_state
from rotor37_rom.disk.harmonics import HarmonicBlocks
from rotor37_rom.interruption import checkpointing, requested, stop_if_requested

__all__ = ["CentralDifference", "SimulationResult", "SimulationDiverged", "capped_mass", "gnl_time_step",
           "gnl_step_report", "step_outliers", "tangent_frequencies",
           "highest_frequency", "largest_states", "probe_states", "simulate", "tangent_highest_frequency",
           "discrete_energy", "WORK_TERMS", "BLOWUP_LIMIT"]

#: the largest boundary displacement (m) a run may reach before it counts as blown up (the maps' limit: 40 times
#: the paper's 0.5 mm clearance)
BLOWUP_LIMIT = 0.02


class SimulationDiverged(RuntimeError):
    """A simulation blew up (NaN or displacement beyond the limit); the message names the step."""


def highest_frequency(M: np.ndarray, K: np.ndarray) -> float:
    """omega_max (rad/s): the largest generalized eigenvalue of (K, M), square-rooted."""
    r = K.shape[0]
    lam = scipy.linalg.eigh(K, M, eigvals_only=True, subset_by_index=[r - 1, r - 1])
    return float(np.sqrt(lam[-1]))


def tangent_frequencies(model, states: np.ndarray, mass: np.ndarray | None = None) -> np.ndarray:
    """omega_max (rad/s) of the tangent stiffness K~ + dg~/dq at each of the states (r,) or (r, n): the stability
    limit of the GNL scheme near each (stress stiffening raises it with the amplitude). ``mass``: the scheme's mass
    (e.g. ``scheme.M`` with a frequency cap); default the model's."""
    states = np.asarray(states, float).reshape(model.r, -1)
    M = model.M if mass is None else mass
    return np.array([highest_frequency(M, model.K + model.forces.jacobian(states[:, j]))
                     for j in range(states.shape[1])])


def tangent_highest_frequency(model, states: np.ndarray, mass: np.ndarray | None = None) -> float:
    """Largest omega_max of the tangent stiffness over the given states (``tangent_frequencies``)."""
    return float(tangent_frequencies(model, states, mass).max())


def step_outliers(frequencies: np.ndarray, factor: float = 10.0) -> np.ndarray:
    """Indices of the states whose tangent frequency exceeds ``factor`` times the median of all: the few that set a
    GNL step far below the others' (on the ci blade at mu = 0.1, one state of 204 where the St. Venant-Kirchhoff
    model collapses under a point contact: 7.56 MHz, 55 times the median, against <= 401 kHz, a step about 19 times
    smaller). Without such a state the frequencies stay within about 3 times the median (mu = 0.05: 409 against a
    median of 137 kHz), hence the default 10."""
    w = np.asarray(frequencies, float).ravel()
    if w.size == 0:
        return np.zeros(0, int)
    return np.flatnonzero(w > factor * np.median(w))


def capped_mass(M: np.ndarray, K: np.ndarray, omega_cap: float) -> np.ndarray:
    """Spectral mass scaling in reduced coordinates: M_s = M V diag(s) V^T M with (K V = M V Lambda, V^T M V = I)
    and s_i = max(1, omega_i^2 / omega_cap^2).

    (K, M_s) has the eigenvectors V and the frequencies min(omega_i, omega_cap): every mode below the cap keeps its
    frequency and shape exactly (the linear response in that band is unchanged), the stiff modes above it (the
    single-tip-node constraint modes) are slowed to omega_cap, so the explicit scheme's limit becomes 2 / omega_cap.
    M~ is dense already, so the scaled mass costs nothing per step. What it changes is the inertia of the stiff
    modes, i.e. how hard the tip nodes hit the casing: the convergence study in omega_cap measures that."""
    if not (omega_cap is not None and np.isfinite(omega_cap) and omega_cap > 0):
        raise ValueError(f"frequency_cap must be a frequency > 0 rad/s, got {omega_cap}")
    lam, V = scipy.linalg.eigh(K, M)
    lowest = float(np.sqrt(max(lam[0], 0.0)))
    if omega_cap <= lowest:
        raise ValueError(f"frequency_cap = {omega_cap:.4g} rad/s must exceed the lowest frequency of the model "
                         f"({lowest:.4g} rad/s)")
    s = np.maximum(1.0, lam / omega_cap ** 2)
    MV = M @ V
    Ms = (MV * s) @ MV.T
    return 0.5 * (Ms + Ms.T)


def gnl_time_step(model, states: np.ndarray, frequency_cap: float | None = None, safety: float = 0.7,
                  cap_safety: float = 0.5) -> float:
    """Time step of a GNL run: min(cap_safety x 2/omega_max of the (capped) linear model, safety x 2/omega_t) where
    omega_t is the largest tangent frequency over ``states`` (r, n), e.g. the largest states of a short unscaled
    probe run (``probe_states``). With a frequency cap, stress stiffening raises the capped modes' tangent
    frequencies several times over the cap (measured 2x / 3.9x / 7.2x at 120 / 60 / 30 kHz on ~1 mm states of the
    ci blade), so 2/cap alone is not a stable step."""
    return gnl_step_report(model, states, frequency_cap, safety, cap_safety)["h"]


def gnl_step_report(model, states: np.ndarray, frequency_cap: float | None = None, safety: float = 0.7,
                    cap_safety: float = 0.5) -> dict:
    """``gnl_time_step`` with what decides it: {"h", "w_linear" (rad/s), "w_states" (each state's tangent
    frequency), "outliers" (``step_outliers``: the states far above the others), "h_without_outliers"}."""
    if not (0.0 < safety <= 1.0 and 0.0 < cap_safety <= 1.0):
        raise ValueError(f"safety factors must be in (0, 1], got {safety}, {cap_safety}")
    M = model.M if frequency_cap is None else capped_mass(model.M, model.K, frequency_cap)
    w_lin = highest_frequency(M, model.K)
    w_t = tangent_frequencies(model, states, mass=M)
    if w_t.size == 0 or not np.isfinite(w_t).all():
        raise ValueError(f"the GNL step needs states with finite tangent frequencies, got {w_t.size} states "
                         f"({np.count_nonzero(~np.isfinite(w_t))} not finite)")
    outliers = step_outliers(w_t)
    rest = np.delete(w_t, outliers)                      # never empty: the outliers lie above the median

    def step(w_max):
        return float(min(cap_safety * 2.0 / w_lin, safety * 2.0 / w_max))

    return {"h": step(w_t.max()), "w_linear": w_lin, "w_states": w_t, "outliers": outliers,
            "h_without_outliers": step(rest.max())}


def probe_states(model, speeds, casing, revolutions: float = 4.0, n: int = 24, safety: float = 0.5,
                 duration: float | None = None, rotation=None) -> np.ndarray:
    """The n reduced states (r, n) of largest tip motion in a short unscaled GNL run at ``speeds`` with ``casing``
    (``duration`` in s instead of ``revolutions``: the same ramp as a capped run of that length; ``rotation``: the
    blade turning, ``dynamics.turning``). The probe has to reach the amplitudes of the run it stands for: states that
    are too small give a step that blows up (flagged)."""
    scheme = CentralDifference(model, nonlinear=True, safety=safety, rotation=rotation)
    length = {"revolutions": revolutions} if duration is None else {"n_steps": int(np.ceil(duration / scheme.h)),
                                                                   "duration": duration}
    res = simulate(scheme, speeds, casing, record_every=max(1, int(2e-5 / scheme.h)), record_q=True,
                   on_blowup="flag", **length)
    return largest_states(res, scheme.boundary_rows, n)


def training_speeds(speeds: Sequence[float], n: int = 6) -> np.ndarray:
    """n of a sweep's speeds spread over it (both ends included): where a map's hyper-reduction is trained."""
    speeds = np.asarray(speeds, float)
    return np.unique(speeds[np.linspace(0, len(speeds) - 1, min(n, len(speeds))).astype(int)])


def contact_training_states(scheme: "CentralDifference", speeds, casing, revolutions: float,
                            n_largest: int = 24, checkpoint: "str | Path | None" = None,
                            checkpoint_seconds: float = 60.0) -> tuple[np.ndarray, np.ndarray]:
    """States of exact GNL contact runs at ``speeds`` (records every 1e-5 s) for training a hyper-reduction
    (``forces.cubature.trajectory_states``), and the states a GNL step is taken over: the n_largest of largest tip
    motion and the training states (the stiffest tangent belongs to a deformation shape, not to the largest tip
    amplitude: on the r = 55 headline the 24 largest gave 7.62e-7 s, the 179 training states 6.21e-7 s). Returns (train,
    step). ``checkpoint``: a file the runs' loop state is saved to every ``checkpoint_seconds`` (``save_loop_state``)
    and resumed from when it holds the same runs (speeds, model, step, frequency cap, casing, length; exact runs of a
    large basis take an hour). It is left in place: the caller removes it once it has kept the result (a finished
    checkpoint resumed gives the result at once)."""
    from rotor37_rom.forces.cubature import trajectory_states
    from rotor37_rom.npz import load_npz

    speeds = np.atleast_1d(np.asarray(speeds, float))
    record_every = max(1, int(round(1e-5 / scheme.h)))
    state, save = None, None
    if checkpoint is not None:
        checkpoint = Path(checkpoint)
        setup = json.dumps([getattr(scheme.model, "key", None), scheme.r, scheme.h, scheme.nonlinear,
                            scheme.frequency_cap, revolutions, record_every, vars(casing)], sort_keys=True,
                           default=str)

        def same_runs(arrays):
            if not np.array_equal(np.asarray(arrays["speeds"], float), speeds) or str(arrays["setup"]) != setup:
                raise ValueError("the checkpoint holds other runs")

        data = load_npz(checkpoint, check=same_runs, what="training runs' checkpoint")
        if data is not None:
            state = loop_state(data, speeds.size)

        def save(st):
            save_loop_state(checkpoint, st, speeds, setup=np.array(setup))

    res = simulate(scheme, speeds, casing, revolutions=revolutions, record_q=True, on_blowup="flag",
                   record_every=record_every, state=state, checkpoint=save, checkpoint_seconds=checkpoint_seconds)
    Q_train, _ = trajectory_states(res.records_q, scheme.boundary_rows)
    return Q_train, np.hstack([largest_states(res, scheme.boundary_rows, n_largest), Q_train])


def largest_states(result: "SimulationResult", boundary_rows: np.ndarray, n: int) -> np.ndarray:
    """The n finite recorded states (r, n) of a run (``record_q=True``) with the largest motion of the entries
    ``boundary_rows`` of q (the node displacements: ``NodeMap.boundary_rows``)."""
    Q = np.hstack(result.records_q)
    Q = Q[:, np.isfinite(Q).all(axis=0)]
    return Q[:, np.argsort(-np.abs(Q[np.asarray(boundary_rows)]).max(axis=0))[:n]]


def discrete_energy(M, K, forces, q_next, q_now, h) -> np.ndarray:
    """Energy of the central-difference scheme between t_n and t_n+1, conserved exactly by the undamped linear
    scheme: 1/2 v M v + 1/2 q_n+1 K q_n (+ mean of V(q_n), V(q_n+1) for the cubic forces), v = (q_n+1 - q_n)/h."""
    q_next = np.asarray(q_next, float).reshape(K.shape[0], -1)
    q_now = np.asarray(q_now, float).reshape(K.shape[0], -1)
    v = (q_next - q_now) / h
    e = 0.5 * np.sum(v * (M @ v), axis=0) + 0.5 * np.sum(q_next * (K @ q_now), axis=0)
    if forces is not None:
        e = e + 0.5 * (forces.potential(q_next) + forces.potential(q_now))
    return e


class CentralDifference:
    """The precomputed operators X0..X4 of eqs. 28-33 for one reduced model and time step.

    Args:
        model: ReducedModel (``model.nodes`` says which entries of q are the contact nodes' displacements).
        h: time step (s); None = ``safety`` * 2 / omega_max.
        nonlinear: include the reduced cubic forces (GNL); False = linear model.
        safety: fraction of the stability limit used when h is None, in (0, 1].
        force: accept h > 2 / omega_max (the run will blow up; for stability studies).
        damping: use the model's damping matrix C (False: undamped).
        massless_boundary: the boundary DOFs carry no inertia (linear models only).
        frequency_cap: spectral mass scaling (rad/s): the modes of (K~, M~) above this frequency get the mass that
            brings them down to it, the modes below keep their frequency and shape exactly (see ``capped_mass``);
            the stability limit becomes ~2 / frequency_cap. None: the model's own mass.
        rotation: the model turns at each run's speed (``dynamics.turning.Rotation``: the model's ``rotation``
            terms, the clearance's reference); omega_max is then the larger of the model's at rest and of its
            prestressed tangent at the top of its speed range (about the centrifugal state: GNL amplitudes stiffen
            it further, as at rest). None: the model at rest, the paper's.
    """

    def __init__(self, model, h: float | None = None, nonlinear: bool = True, safety: float = 0.9,
                 force: bool = False, damping: bool = True, massless_boundary: bool = False,
                 frequency_cap: float | None = None, rotation=None):
        missing = [name for name in ("r", "M", "K", "C", "nodes", "forces") if not hasattr(model, name)]
        if missing:
            raise TypeError(f"model must be a reduced model (model.reduced.ReducedModel), got {type(model).__name__}"
                            f" without {', '.join(missing)}")
        real_number("safety factor", safety, 0, 1, open_low=True)
        if h is not None:
            real_number("time step h", h, 0, open_low=True, unit=" s")
        if frequency_cap is not None:
            real_number("frequency_cap", frequency_cap, 0, open_low=True, unit=" rad/s")
        self.model = model
        self.r = model.r
        self.forced = bool(force)
        self.rotation = rotation
        if rotation is not None:
            from rotor37_rom.dynamics.turning import Rotation
            from rotor37_rom.model.rotating import check_spin

            if not isinstance(rotation, Rotation):
                raise TypeError(f"rotation must be a dynamics.turning.Rotation or None, got {rotation!r}")
            check_spin(model, 0.0)                                  # the model has rotation terms
            if model.forces is None:
                raise ValueError("rotation: this model has no nonlinear forces, and its prestress (the centrifugal "
                                 "stiffening) comes from them; build it with forces (ReductionConfig.forces)")
            if massless_boundary:
                raise ValueError("rotation: not with massless_boundary (its boundary carries no centrifugal force)")
        self.boundary_rows = np.asarray(model.nodes.boundary_rows, dtype=np.int64)   # node displacements in q
        self.nonlinear = bool(nonlinear and model.forces is not None)
        self.massless = bool(massless_boundary)
        if self.massless and self.nonlinear:
            raise ValueError("massless_boundary supports the linear model only (nonlinear=False)")
        M, K = np.asarray(model.M, float), np.asarray(model.K, float)
        C = np.asarray(model.C, float) if damping else np.zeros_like(M)
        self.frequency_cap = None
        if frequency_cap is not None:
            if self.massless:
                raise ValueError("frequency_cap and massless_boundary are alternatives; give one of them")
            M = capped_mass(M, K, frequency_cap)
            self.frequency_cap = float(frequency_cap)
        self.M, self.C, self.K = M, C, K
        if self.massless:
            b, i = self._boundary_interior()
            Kbb, Kbi = K[np.ix_(b, b)], K[np.ix_(b, i)]
            self.Kbb_inv = np.linalg.inv(Kbb)
            self.condense = -self.Kbb_inv @ Kbi                   # u_b = condense @ eta (+ Kbb^-1 f_b)
            Kc = K[np.ix_(i, i)] + Kbi.T @ self.condense
            self.omega_max = highest_frequency(M[np.ix_(i, i)], Kc)
        else:
            self.omega_max = highest_frequency(M, K)
            if rotation is not None:
                from rotor37_rom.dynamics.turning import prestressed_highest_frequency

                self.omega_max = max(self.omega_max, prestressed_highest_frequency(model, model.rotation.top_speed,
                                                                                   M))
        self.h_crit = 2.0 / self.omega_max
        if h is None:
            h = safety * self.h_crit
        if not (h > 0.0 and np.isfinite(h)):
            raise ValueError(f"time step h must be > 0, got {h}")
        if h > self.h_crit and not force:
            raise ValueError(f"time step h = {h:.4g} s exceeds the stability limit 2/omega_max = {self.h_crit:.4g} s "
                             f"(omega_max = {self.omega_max:.4g} rad/s); use h <= {self.h_crit:.4g} or force=True")
        self.h = float(h)
        self._build()

    def with_step(self, h: float) -> "CentralDifference":
        """The same scheme (model, mass, damping, cap or massless variant) at another step, forced like
        ``force=True``: operators rebuilt, omega_max and the scaled mass reused."""
        if not (h > 0.0 and np.isfinite(h)):
            raise ValueError(f"time step h must be > 0, got {h}")
        other = copy.copy(self)
        other.h = float(h)
        other.forced = True
        other._build()
        return other

    def _boundary_interior(self) -> tuple[np.ndarray, np.ndarray]:
        """The node-displacement entries of q and the others (the massless variant's boundary and interior)."""
        b = self.boundary_rows
        return b, np.setdiff1d(np.arange(self.r), b)

    def _build(self):
        h, M, C, K, r = self.h, self.M, self.C, self.K, self.r
        if not self.massless:
            # S^-1 (4M - 2h^2 K) = 2I - S^-1 (2hC + 2h^2 K) and S^-1 (hC - 2M) = -I + 2h S^-1 C: the identity parts
            # stay exact (undamped: X2 = -I), which keeps the discrete energy to ~1e-11 over 1e5 steps even though
            # cond(M~) ~ 1e7 (the direct form drifts ~1e-9)
            S = scipy.linalg.cho_factor(2.0 * M + h * C)
            self.X0 = 2.0 * h * h * scipy.linalg.cho_solve(S, np.eye(r))          # = (M/h^2 + C/2h)^-1 = W
            self.X1 = 2.0 * np.eye(r) - scipy.linalg.cho_solve(S, 2.0 * h * C + 2.0 * h * h * K)
            self.X2 = -np.eye(r) + (2.0 * h * scipy.linalg.cho_solve(S, C) if np.any(C) else 0.0)
            self.W = self.X0
            # the force's step: premultiplied by -X0 where that is cheaper (exact tensors: X3, X4 of eqs. 32-33),
            # else evaluated, then mapped (quadrature, cubature, a disk's sector forces)
            self.Xg = self.g = None
            if self.nonlinear:
                self.Xg = self.model.forces.premultiplied(-self.X0)
                self.g = self.model.forces if self.Xg is None else None
            # a tuned disk: X1, X2, X0 per harmonic index (block-circulant), None for a blade or a mistuned disk
            sectors = getattr(self.model, "sectors", None)
            self.harmonic = None
            if sectors is not None and self.Xg is None:
                self.harmonic = HarmonicBlocks.from_operators(sectors.blocks, [self.X1, self.X2, self.X0],
                                                              [self.model.K, self.model.M])
            return
        self.harmonic = None
        # massless boundary: eta from the explicit scheme, u_b from K_bb u_b + K_bi eta = f_b + f_c
        b, i = self._boundary_interior()
        Mi, Ci, Ki = M[np.ix_(i, i)], C[np.ix_(i, i)], K[np.ix_(i, i)]
        Kib = K[np.ix_(i, b)]
        S = scipy.linalg.cho_factor(2.0 * Mi + h * Ci)
        ni = i.size
        E1 = np.zeros((ni, r))
        E1[:, i] = scipy.linalg.cho_solve(S, 4.0 * Mi - 2.0 * h * h * Ki)
        E1[:, b] = scipy.linalg.cho_solve(S, -2.0 * h * h * Kib)
        E2 = np.zeros((ni, r))
        E2[:, i] = scipy.linalg.cho_solve(S, h * Ci - 2.0 * Mi)
        E0 = np.zeros((ni, r))
        E0[:, i] = 2.0 * h * h * scipy.linalg.cho_solve(S, np.eye(ni))
        lift = np.zeros((r, ni))                                        # q = lift eta (+ Kbb^-1 f_b at b)
        lift[b], lift[i] = self.condense, np.eye(ni)
        self.X1, self.X2 = lift @ E1, lift @ E2
        self.X0 = lift @ E0
        self.X0[np.ix_(b, b)] += self.Kbb_inv                           # f_b taken at t_n
        self.W = np.zeros((r, r))
        self.W[np.ix_(b, b)] = self.Kbb_inv                             # contact moves the massless boundary only
        self.Xg = self.g = None

    def predict(self, Q: np.ndarray, Qp: np.ndarray, F: np.ndarray | None, parts: bool = False):
        """The states at t_n+1 before the contact correction, of P runs at t_n (Q) and t_n-1 (Qp), (r, P), under
        the external forces F ((r,) or (r, P), None: none): X1 Q + X2 Qp + X0 (F - g(Q)) (eqs. 28-33). With
        ``parts`` (a blade's scheme): (those states, the GNL force's part -X0 g(Q) or None), for the tangent."""
        if self.harmonic is not None:
            if parts:
                raise ValueError("predict(parts=True): a blade's scheme only, not a tuned disk's")                     # tuned disk: one batched product over the harmonics
            G = None if F is None else (F if F.ndim == 2 else np.repeat(F[:, None], Q.shape[1], axis=1))
            if self.g is not None:
                g = self.g.evaluate(Q)
                G = -g if G is None else G - g
            return self.harmonic.apply(Q, Qp) if G is None else self.harmonic.apply(Q, Qp, G)
        out = self.X1 @ Q
        out += self.X2 @ Qp
        if F is not None:
            out += self.X0 @ F if F.ndim == 2 else (self.X0 @ F)[:, None]
        force = None
        if self.Xg is not None:
            force = self.Xg.evaluate(Q)
        elif self.g is not None:
            force = -(self.X0 @ self.g.evaluate(Q))
        if force is not None:
            out += force
        return (out, force) if parts else out


@dataclasses.dataclass
class SimulationResult:
    """Output of ``simulate`` for P simulations.

    Attributes:
        omega: (P,) angular speeds (rad/s); h: time step (s); n_steps: (P,) steps run by each simulation.
        t: list of (n_rec_p,) record times; u_r: list of (n_m, n_rec_p) normal ('radial') displacements of the
            monitored nodes (rows ``monitor`` of the model's node map, labels ``labels``); lam: list of
            (n_c, n_rec_p) normal contact forces (N) of the contact nodes (rows ``contact_rows``) at the same instants.
        q_final, q_prev: (r, P) last two states (for continuation); energy: list of (n_rec_p,) or None.
        max_penetration: (P,) largest penetration left after a correction (m, >= 0 means none left beyond it).
        min_multiplier: (P,) smallest normal multiplier applied (N); friction_power: (P,) largest f_t . v_slide
            (W; <= 0 when friction opposes sliding); contact_steps: (P,) steps with at least one contact.
        diverged_step: (P,) step at which a simulation blew up, -1 if not; wall: seconds.
        records_q: list of (r, n_rec_p) full states when asked for, else None.
        work: (P, 4) work done on the blade over the run (J), in the order of ``WORK_TERMS``: normal contact,
            friction, external forcing (NaN without forcing or energy=True), and the energy the damping took (NaN
            unless energy=True); see the module docstring.
        work_history: with energy=True, list of (4, n_rec_p) running totals at the record instants (so that
            energy[i] - energy[0] = work[0] + work[1] + work[2] - work[3] for the linear scheme), else None.
    """

    omega: np.ndarray
    h: float
    n_steps: np.ndarray
    t: list
    u_r: list
    lam: list
    q_final: np.ndarray
    q_prev: np.ndarray
    energy: list | None
    max_penetration: np.ndarray
    min_multiplier: np.ndarray
    friction_power: np.ndarray
    contact_steps: np.ndarray
    diverged_step: np.ndarray
    wall: float
    records_q: list | None = None
    work: np.ndarray | None = None
    work_history: list | None = None
    monitor: np.ndarray | None = None
    labels: tuple = ()
    contact_rows: np.ndarray | None = None

    def row(self, label: str = "0:LE") -> int:
        """Row of ``u_r`` holding the node ``label`` ('<sector>:<name>', see ``NodeMap.labels``)."""
        if label not in self.labels:
            raise ValueError(f"node {label!r} is not monitored in this run; monitored: {list(self.labels)}")
        return self.labels.index(label)


WORK_TERMS = ("normal", "friction", "forcing", "damping")


def simulate(scheme: CentralDifference, omega: Sequence[float] | float, casing: Casing | Sequence[Casing] | None = None,
             revolutions: float | None = None, n_steps: int | Sequence[int] | None = None,
             forcing: Callable[[float], np.ndarray] | None = None, initial: tuple | None = None,
             record_every: int = 1, record_q: bool = False, energy: bool = False, on_blowup: str = "raise",
             blowup_limit: float = BLOWUP_LIMIT, check_every: int = 200, duration: float | Sequence[float] | None = None,
             progress: Callable[[int], None] | None = None, on_finish: Callable[[int, dict], None] | None = None,
             state: LoopState | None = None, checkpoint: Callable[[LoopState], None] | None = None,
             checkpoint_seconds: float = 60.0, phase: float | Sequence[float] = 0.0,
             monitor: Sequence[int] | None = None) -> SimulationResult:
    """Run P simulations of the reduced model together with central differences and casing contact.

    Args:
        scheme: CentralDifference (model, h, GNL on/off).
        omega: angular speed(s) (rad/s), > 0, one per simulation.
        casing: Casing, or one per simulation (c0, h_b, mu may differ); None = no contact.
        revolutions: run each simulation for this many revolutions (2 pi / omega each); or
        n_steps: number of steps (one for all or one per simulation).
        duration: the run length (s) that sets the ovalization ramp (eq. 38); default: each simulation's own.
        forcing: f(t) -> (r,) or (r, P) reduced external force (N).
        initial: (Q_0, Q_-1), each (r,) or (r, P); default: rest, or with a turning scheme each run's centrifugal
            state (``dynamics.turning``: the scheme's ``rotation`` adds each run's rotation force to every step and
            sets where the clearance and the recorded displacements are measured from).
        record_every: record every this many steps; record_q: also keep full states; energy: discrete energy
            (record 0 holds that of (Q_0, Q_-1)), the damping's share of the balance and the running works.
        phase: angle (rad) the rotor has turned through before t = 0 (continuation: the casing must not jump).
        monitor: rows of the model's node map whose normal displacement is recorded in ``u_r`` (default: all).
        on_blowup: 'raise' (SimulationDiverged naming the step) or 'flag' (stop that simulation, mark it).
        blowup_limit: largest admissible boundary displacement (m) before a run counts as blown up.
        progress: called with the simulation-steps done since the last call (steps x running simulations: the
            batch's share of ``n_steps``.sum()); on_finish(p, record dict) when a
            simulation ends; state/checkpoint: resume from / save the loop state every ``checkpoint_seconds``, or
            every 50 times the last save's duration where that is longer (a 100-speed map's records are ~0.6 GB per
            batch: at most 2 % of the wall goes to checkpoints); 0: after every step.
    """
    omega = np.atleast_1d(np.asarray(omega, float)).ravel()
    P = omega.size
    if P == 0 or not np.all(np.isfinite(omega)) or omega.min() <= 0:
        raise ValueError(f"angular speed Omega must be > 0 rad/s, got {omega.tolist()}")
    if on_blowup not in ("raise", "flag"):
        raise ValueError(f"on_blowup must be 'raise' or 'flag', got {on_blowup!r}")
    if record_every < 1:
        raise ValueError(f"record_every must be >= 1, got {record_every}")
    if not isinstance(scheme, CentralDifference):
        raise TypeError(f"scheme must be a CentralDifference, got {type(scheme).__name__}")
    h, r = scheme.h, scheme.r
    steps = _run_steps(omega, h, revolutions, n_steps)
    run_length = steps * h if duration is None else np.broadcast_to(np.asarray(duration, float), (P,))
    casings = per_simulation_casings(casing, P)
    phase = np.broadcast_to(np.asarray(phase, float), (P,)).copy()
    turning = None
    if scheme.rotation is not None:
        from rotor37_rom.dynamics.turning import TurningRuns

        turning = TurningRuns(scheme, omega)
        if initial is None:
            initial = (turning.q_c, turning.q_c)
    reference = None if turning is None else turning.reference
    contact = ContactStep(scheme, casings, run_length, reference)
    nodes = scheme.model.nodes
    monitor = np.arange(len(nodes)) if monitor is None else np.asarray(monitor, dtype=np.int64).ravel()
    Nm = row_operator(contact_matrices(nodes, r, None if casings is None else casings[0], rows=monitor)[0])
    rec = Recorder(Nm, tuple(nodes.labels[k] for k in monitor), steps, h, record_every, omega, contact.n_contact,
                   record_q, energy, None if reference is None else np.asarray(Nm @ reference))
    st = rec.fresh(r, initial) if state is None else rec.check_resumable(state)
    energy_forces = scheme.model.forces if (energy and scheme.nonlinear) else None
    if energy and scheme.nonlinear and not energy_forces.has_potential:
        raise ValueError("energy=True with nonlinear forces needs the polynomial (intrusive) tensors")
    if st.work is None:                        # also a checkpoint written before the works were kept: from its step on
        _start_works(st, scheme, energy_forces, energy, forcing is not None or turning is not None, steps,
                     record_every)
    Q, Qp, work = st.Q, st.Qp, st.work

    with np.errstate(over="ignore", invalid="ignore"), \
            (checkpointing() if checkpoint is not None else contextlib.nullcontext()):   # SIGTERM: saved, then stop
        t_wall, elapsed = time.perf_counter(), st.elapsed        # the wall of earlier sittings carried on
        last_ckpt, ckpt_interval = t_wall, checkpoint_seconds
        active = np.nonzero(~st.done)[0]
        n_max = int(steps.max())
        ends = set(steps.tolist())
        lam_now = np.zeros((contact.n_contact, P))
        stepped = 0                                     # simulation-steps since the last progress call
        while st.n < n_max and active.size:
            n = st.n
            Qa, Qpa = Q[:, active], Qp[:, active]
            F = None
            if forcing is not None:
                F = np.asarray(forcing(n * h), float)
                F = F if F.ndim == 1 else F.reshape(r, -1)[:, active]
            if turning is not None:
                F_rot = turning.force(Qa, active)
                F = F_rot if F is None else F_rot + (F[:, None] if F.ndim == 1 else F)
            Qn = scheme.predict(Qa, Qpa, F)
            lam_now[:, active] = 0.0
            if casings is not None:
                contact.correct(st, Qn, Qa, Qpa, active, omega, phase, (n + 1) * h, h, blowup_limit, lam_now)
            if F is not None or energy:
                dq = Qn - Qpa
                if F is not None:
                    work[2, active] += 0.5 * np.sum((F if F.ndim == 2 else F[:, None]) * dq, axis=0)
                if energy:
                    work[3, active] += np.sum(dq * (scheme.C @ dq), axis=0) / (4.0 * h)
            Qp[:, active] = Qa
            Q[:, active] = Qn
            st.n = n = n + 1
            stepped += active.size
            if n % record_every == 0:
                rec.record(st, active, Qn, lam_now,
                           discrete_energy(scheme.M, scheme.K, energy_forces, Qn, Qa, h) if energy else None)
            if n % check_every == 0 or n in ends:
                st.elapsed = elapsed + (time.perf_counter() - t_wall)       # what a finished run's record says
                active = _end_runs(st, active, Qn, scheme, steps, blowup_limit, on_blowup, on_finish, rec)
            if progress is not None and (n % check_every == 0 or not active.size):
                progress(stepped)
                stepped = 0
            if checkpoint is not None and time.perf_counter() - last_ckpt > ckpt_interval:
                t_save = time.perf_counter()
                st.elapsed = elapsed + (t_save - t_wall)
                checkpoint(st)
                last_ckpt = time.perf_counter()
                if checkpoint_seconds > 0:                 # 0: every step (as asked); else <= 2 % of the wall
                    ckpt_interval = max(checkpoint_seconds, 50.0 * (last_ckpt - t_save))
            if checkpoint is not None and requested() is not None:
                st.elapsed = elapsed + (time.perf_counter() - t_wall)
                stop_if_requested(lambda: checkpoint(st))
    wall = time.perf_counter() - t_wall
    recs = [rec.record_of(st, p) for p in range(P)]
    return SimulationResult(
        omega=omega, h=h, n_steps=np.minimum(steps, st.n), t=[x["t"] for x in recs], u_r=[x["u_r"] for x in recs],
        lam=[x["lam"] for x in recs], q_final=Q.copy(), q_prev=Qp.copy(),
        energy=[x["energy"] for x in recs] if energy else None,
        max_penetration=np.maximum(st.max_pen, 0.0), min_multiplier=st.min_lam, friction_power=st.fric_pow,
        contact_steps=st.contact_steps, diverged_step=st.diverged, wall=wall,
        records_q=[st.q_rec[p] for p in range(P)] if record_q else None, work=work.T.copy(),
        work_history=[st.work_rec[p] for p in range(P)] if energy else None, monitor=monitor, labels=rec.labels,
        contact_rows=contact.rows)


def _run_steps(omega: np.ndarray, h: float, revolutions: float | None, n_steps) -> np.ndarray:
    """(P,) steps of each run: ``revolutions`` at its speed, or ``n_steps`` (one for all or one per run)."""
    if revolutions is not None:
        if not revolutions > 0:
            raise ValueError(f"revolutions must be > 0, got {revolutions}")
        steps = np.ceil(revolutions * 2.0 * np.pi / omega / h).astype(np.int64)
    elif n_steps is not None:
        steps = np.broadcast_to(np.asarray(n_steps, dtype=np.int64), (omega.size,)).copy()
    else:
        raise ValueError("give revolutions or n_steps")
    if steps.min() < 1:
        raise ValueError(f"n_steps must be >= 1, got {steps.min()}")
    return steps


def _start_works(st: LoopState, scheme: CentralDifference, energy_forces, energy: bool, forced: bool,
                 steps: np.ndarray, record_every: int) -> None:
    """The running works of ``st`` from its step on (``WORK_TERMS``: damping with energy, forcing when forced or with
    energy, else NaN), and with energy their records and the energy at step 0."""
    P = st.Q.shape[1]
    st.work = np.zeros((4, P))
    st.work[3] = 0.0 if energy else np.nan
    st.work[2] = 0.0 if (energy or forced) else np.nan
    if energy:
        st.work_rec = [np.full((4, n), np.nan) for n in steps // record_every + 1]
        i0 = st.n // record_every
        E0 = discrete_energy(scheme.M, scheme.K, energy_forces, st.Q, st.Qp, scheme.h)
        for p in range(P):
            st.work_rec[p][:, i0] = st.work[:, p]
            if st.n == 0:
                st.energy[p][0] = E0[p]


def _end_runs(st: LoopState, active: np.ndarray, Qn: np.ndarray, scheme: CentralDifference, steps: np.ndarray,
              blowup_limit: float, on_blowup: str, on_finish, rec: Recorder) -> np.ndarray:
    """Stop the runs ``active`` (states Qn at step st.n) that blew up (raise, or mark them: ``on_blowup``) or reached
    their length, handing each one's record to ``on_finish``; returns the runs still active."""
    n, h, brows = st.n, scheme.h, scheme.boundary_rows
    bad = ~np.isfinite(Qn[brows]).all(axis=0) | (np.abs(Qn[brows]).max(axis=0) > blowup_limit)
    for j in np.nonzero(bad)[0]:
        p = active[j]
        st.diverged[p] = n
        if on_blowup == "raise":
            raise SimulationDiverged(
                f"simulation {p} (Omega = {rec.omega[p]:g} rad/s) diverged at step {n} (t = {n * h:.6g} s): "
                f"boundary displacement NaN or above {blowup_limit:g} m; h = {h:.4g} s, "
                f"stability limit 2/omega_max = {scheme.h_crit:.4g} s")
        st.done[p] = True
        if on_finish is not None:          # a diverged run is a result too (marked, kept)
            on_finish(p, rec.record_of(st, p))
    finished = [p for p in active if n >= steps[p] and not st.done[p]]
    for p in finished:
        st.done[p] = True
        if on_finish is not None:
            on_finish(p, rec.record_of(st, p))
    if finished or bad.any():
        return np.nonzero(~st.done)[0]
    return active
