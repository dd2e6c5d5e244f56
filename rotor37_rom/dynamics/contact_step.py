"""The contact step of the explicit scheme (§2.1.3): detection against the casing, the Lagrange multipliers of the
active set with Coulomb friction, and the correction of the predicted states, for P runs at once."""
from __future__ import annotations

from typing import Sequence

import numpy as np
import scipy.sparse

from rotor37_rom.dynamics.casing import (Casing, ContactSolver, casing_clearance, contact_matrices, friction_power,
                                         node_angles, ramp_rate)

__all__ = ["ContactStep", "per_simulation_casings", "row_operator"]


def row_operator(A: np.ndarray, dense_limit: int = 1 << 16):
    """A node-row operator (n_c, r) for products with the states: dense for a blade's few nodes (a sparse product
    costs ~13 us of call overhead per step, a third of a single run's step), CSR for a disk's hundreds of nodes over
    thousands of entries of q."""
    return np.ascontiguousarray(A) if A.size <= dense_limit else scipy.sparse.csr_matrix(A)


def per_simulation_casings(casings: Casing | Sequence[Casing] | None, P: int) -> list[Casing] | None:
    """One Casing per run (a single one repeated); the runs of one batch may differ in c0, h_b and mu only."""
    if casings is None:
        return None
    if isinstance(casings, Casing):
        casings = [casings] * P
    if isinstance(casings, (str, bytes)) or not all(isinstance(c, Casing) for c in casings):
        raise TypeError(f"casing must be a Casing, one per simulation or None, got {casings!r}")
    casings = list(casings)
    if len(casings) != P:
        raise ValueError(f"casing: give one Casing or one per simulation ({P}), got {len(casings)}")
    first = casings[0]
    for c in casings:
        if (c.direction, c.rotation_sense, c.contact_nodes, c.ramp_fraction, c.ramp_level, c.width, c.cone_slope) != \
                (first.direction, first.rotation_sense, first.contact_nodes, first.ramp_fraction, first.ramp_level,
                 first.width, first.cone_slope):
            raise ValueError("casing: the simulations of one batch may differ in c0, h_b and mu only")
    return casings


class ContactStep:
    """Contact of a scheme's contact nodes with the casings ``casings`` (one per run, or None: no contact).

    u_n = N q at the contact nodes (rows ``rows`` of the node map), S q along the sliding; a unit normal multiplier
    moves q by WN, a unit friction multiplier by WT (W = X0, the reduced operator); the multipliers of one run solve
    D lambda = g* on the active set (``ContactSolver``). ``run_length`` (P,) sets the ovalisation ramp (eq. 38); None:
    the casing's steady ovalisation from t = 0 (eq. 38 at t -> infinity: the periodic orbits').
    ``reference`` (r, P): the states the clearance is measured from (a turning blade's running state,
    ``dynamics.turning``); None: rest.
    """

    def __init__(self, scheme, casings: list[Casing] | None, run_length: np.ndarray | None,
                 reference: np.ndarray | None = None):
        nodes = scheme.model.nodes
        N, S, self.theta0, self.rows = contact_matrices(nodes, scheme.r, None if casings is None else casings[0])
        self.N, self.S = row_operator(N), row_operator(S)
        self.casings = casings
        if casings is None:
            return
        self.shift = None if reference is None else np.asarray(self.N @ reference)      # (nc, P)
        self.c0 = np.array([c.c0 for c in casings])
        self.mu = np.array([c.mu for c in casings])
        self.p0 = np.array([c.p0 for c in casings])
        self.alpha = (np.full(len(casings), np.inf) if run_length is None
                      else ramp_rate(run_length, casings[0].ramp_fraction, casings[0].ramp_level))
        self.sense, self.width = casings[0].rotation_sense, casings[0].width
        self.radius = np.hypot(nodes.coordinates[self.rows, 0], nodes.coordinates[self.rows, 1])
        # response to unit multipliers: normal force -n_k, friction force -s_k (times mu)
        self.WN = -np.asarray((self.N @ scheme.W.T).T)                    # (r, nc)
        self.WT = -np.asarray((self.S @ scheme.W.T).T)                    # (r, nc)
        DN, DT = np.asarray(self.N @ self.WN), np.asarray(self.N @ self.WT)   # (nc, nc)
        self.solver = ContactSolver(DN, DT)

    @property
    def n_contact(self) -> int:
        return len(self.rows)

    def correct(self, st, Qn: np.ndarray, Qa: np.ndarray, Qpa: np.ndarray, active: np.ndarray, omega: np.ndarray,
                phase: np.ndarray, t1: float, h: float, blowup_limit: float, lam_now: np.ndarray) -> None:
        """Correct the predicted states Qn (r, n_active) of the runs ``active`` in place at t1 (their states Qa at
        t_n, Qpa at t_n-1), with the multipliers into ``lam_now`` and the works and extremes into ``st``."""
        N, S, mu, work = self.N, self.S, self.mu, st.work
        om = omega[active]
        hits, lam, gap_after = self.multipliers(Qn, active, omega, phase, t1, blowup_limit)
        if not hits.size:
            return
        ps = active[hits]
        mus = mu[ps]
        mlam = lam * mus                       # friction multipliers mu lambda
        Qn[:, hits] += self.push(lam, mus)
        dq = Qn[:, hits] - Qpa[:, hits]        # q_n+1 - q_n-1: the force of step n works over dq / 2
        work[0, ps] -= 0.5 * np.sum(lam * (N @ dq), axis=0)
        work[1, ps] -= 0.5 * np.sum(mlam * (S @ dq), axis=0)
        st.max_pen[ps] = np.maximum(st.max_pen[ps], -gap_after.min(axis=0))
        on = lam > 0
        touched = on.any(axis=0)
        st.min_lam[ps] = np.minimum(st.min_lam[ps], np.where(on, lam, np.inf).min(axis=0))
        st.contact_steps[ps] += touched
        # sliding velocity of the node on the casing: rotation + its own tangential velocity along s_k
        v = (S @ (Qn[:, hits] - Qa[:, hits])) / h
        power = friction_power(mlam, om[hits][None, :], self.radius[:, None], v)
        power = np.where(on, power, -np.inf).max(axis=0)
        st.fric_pow[ps] = np.where(touched, np.maximum(st.fric_pow[ps], power), st.fric_pow[ps])
        lam_now[:, ps] = lam

    def multipliers(self, Qn: np.ndarray, active: np.ndarray, omega: np.ndarray, phase: np.ndarray, t1: float,
                    blowup_limit: float = np.inf) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The contact law at t1 on the predicted states Qn (r, n_active) of the runs ``active``: (hits, the columns
        of Qn that penetrate the casing; lam (n_c, n_hits), their normal multipliers; the gaps left after the
        correction). A run past the blow-up limit gets none (it is stopped at the next check)."""
        ur = self.N @ Qn
        if self.shift is not None:
            ur = ur - self.shift[:, active]
        theta = node_angles(self.theta0[:, None], omega[active][None, :], t1, self.sense, phase[active][None, :])
        g = casing_clearance(theta, t1, self.c0[active], self.p0[active], self.alpha[active], self.width) - ur
        sane = np.isfinite(g).all(axis=0) & (np.abs(ur).max(axis=0) <= blowup_limit)
        hits = np.nonzero((g < 0.0).any(axis=0) & sane)[0]
        lam, gap_after = np.empty((self.n_contact, hits.size)), np.empty((self.n_contact, hits.size))
        mus = self.mu[active[hits]]
        for k, j in enumerate(hits):
            lam[:, k], gap_after[:, k] = self.solver.solve(mus[k], g[:, j])
        return hits, lam, gap_after

    def push(self, lam: np.ndarray, mus: np.ndarray) -> np.ndarray:
        """The correction of the states (r, n) by normal multipliers lam (n_c, n) with Coulomb coefficients mus
        (n,): W N^T lam + W S^T mu lam, over the nodes pushed alone (a few of a disk's hundreds)."""
        act = np.nonzero((lam > 0).any(axis=1))[0]
        return self.WN[:, act] @ lam[act] + self.WT[:, act] @ (lam[act] * mus)
