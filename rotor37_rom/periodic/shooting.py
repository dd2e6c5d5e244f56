"""Periodic orbits of the project's explicit scheme itself, by shooting: Newton on z(T) = z(0) for the scheme's state
z = (q_0, q_-1) over one period of n steps, with the casing contact of the maps (Lagrange multipliers, Coulomb
friction; ``dynamics.contact_step``'s law, plastic at the node) and the reduced geometric nonlinearity.

The Jacobian of the period map is the monodromy of the scheme, marched beside the orbit: each step's tangent is the
scheme's linear operators, the GNL force's exact Jacobian premultiplied like the force, and, on a step that
touches, the contact correction's projection with the step's active set held (the multipliers are piecewise linear
in the predicted gaps). It is the exact derivative of the discrete map wherever the contact sets of the period do not
change under a small perturbation; its eigenvalues are the Floquet multipliers of the discrete orbit (the stability
of the orbit of the time-marching model, not of an approximation of it). A plastic impact erases the normal velocity
of a node: its multipliers are (near) zero.

``Shooting`` offers ``residual`` (R = z(T) - z(0), dR/dz = monodromy - I, dR/domega marched as one more column of
the tangent; by a difference under an external forcing),
``floquet_exponents``, ``size``, ``split``, so that ``solve_periodic`` and ``continue_branch`` (arc length through
folds) work on it as on the harmonic balance. The branch parameter is the fundamental frequency omega = 2 pi / T: the
casing's two lobes pass a blade every pi / Omega, so for the period m pi / Omega, Omega = m omega / 2.
"""
from __future__ import annotations

import numpy as np

from rotor37_rom.checks import real_number
from rotor37_rom.dynamics.casing import Casing, ContactSetError, contact_matrices
from rotor37_rom.dynamics.contact_step import ContactStep

__all__ = ["Shooting", "solve_periodic_krylov"]


class Shooting:
    """The period map of the explicit scheme ``scheme`` (a blade's ``dynamics.explicit.CentralDifference``) with n
    steps per period.

    Args:
        scheme: the scheme (its model, GNL on or off, damping, mass); its step is replaced by T / n per omega.
        casing: the casing (steady: the ovalisation complete, eq. 38 at t -> infinity), or None (no contact).
        forcing: f(t, omega) -> (r,), the external force, or None.
        m: the period in bump passings, m pi / Omega (1: the orbit with the casing's own period; 2: period doubled).
        steps: n, the steps per period (the same along a branch, so that the map is smooth in omega); the step
            T / n must stay below the scheme's linear stability limit (ValueError otherwise; a GNL orbit needs the
            tangent's limit, ``dynamics.explicit.gnl_time_step``, which the caller takes into account).
        jacobian_every: see ``march``.
    """

    def __init__(self, scheme, casing: Casing | None = None, forcing=None, m: int = 1, steps: int = 2000,
                 jacobian_every: int = 1):
        if getattr(scheme, "harmonic", None) is not None or getattr(scheme, "massless", False):
            raise ValueError("shooting takes a blade's scheme (not a tuned disk's or the massless variant)")
        if getattr(scheme, "rotation", None) is not None:
            raise ValueError("shooting takes a blade at rest: the periodic orbits of a turning scheme are not "
                             "implemented (its maps and continuation are)")
        if not (isinstance(m, (int, np.integer)) and m >= 1):
            raise ValueError(f"m (the period in bump passings, m pi / Omega) must be an integer >= 1, got {m!r}")
        if not (isinstance(steps, (int, np.integer)) and steps >= 2):
            raise ValueError(f"steps (per period) must be an integer >= 2, got {steps!r}")
        if not (isinstance(jacobian_every, (int, np.integer)) and jacobian_every >= 1):
            raise ValueError(f"jacobian_every must be an integer >= 1, got {jacobian_every!r}")
        if casing is None and forcing is None:
            raise ValueError("shooting needs an excitation: a casing, a forcing or both")
        self.scheme, self.casing, self.forcing, self.m, self.steps = scheme, casing, forcing, int(m), int(steps)
        self.jacobian_every = int(jacobian_every)
        self.r = scheme.r
        self._h, self.contact = None, None
        if casing is not None:                    # the casing checked (its hand) before any work; its rows are the
            contact_matrices(scheme.model.nodes, self.r, casing)     # contact step's (``scheme_at``)

    @property
    def size(self) -> int:
        return 2 * self.r

    def split(self, x: np.ndarray):
        """(Z (2, r): q_0 and q_-1, ()): a shooting orbit's unknowns."""
        return np.asarray(x, float).reshape(2, self.r).copy(), ()

    def scheme_at(self, omega: float):
        """The scheme with the step T / n of the period 2 pi / omega; ValueError for an omega not finite and > 0,
        or past the scheme's stability limit."""
        real_number("omega", omega, 0.0, open_low=True, unit=" rad/s")
        h = 2 * np.pi / omega / self.steps
        if h > self.scheme.h_crit:
            raise ValueError(f"the step T / n = {h:.4g} s at omega = {omega:g} rad/s exceeds the scheme's stability "
                             f"limit {self.scheme.h_crit:.4g} s: give more steps per period")
        if self._h != h:
            self._scheme, self._h = self.scheme.with_step(h), h
            if self.casing is not None:
                self.contact = ContactStep(self._scheme, [self.casing], None)     # the casing's steady ovalisation
                self.WN, self.WT, self.solver = self.contact.WN, self.contact.WT, self.contact.solver
        return self._scheme

    def speed(self, omega: float) -> float:
        """Omega (rad/s) of the fundamental frequency omega: m omega / 2."""
        return self.m * omega / 2

    def march(self, z: np.ndarray, omega: float, tangent: bool = True, record: bool = False,
              domega: bool = False):
        """One period from z = (q_0, q_-1): (z(T), monodromy (2 r, 2 r) or None, records (n + 1, r) of q or None);
        with ``domega`` (and ``tangent``) a fourth item, dz(T)/domega, marched as one more column of the tangent
        (``_step_derivatives``; an external forcing's time dependence is not in it: None then).

        The orbit is marched first (its states and each touching step's active set kept), then the tangent along
        it. The GNL force's exact Jacobian is evaluated at every step (the exact derivative of the discrete map), or,
        on an orbit that does not touch, every ``jacobian_every`` steps and interpolated linearly between (a
        quadratic polynomial of the smooth q(t): an error O((k h)^2) in the tangent, which slows Newton a little
        and moves the multipliers by as much; a contact correction rings the highest modes, whose periods are a
        few steps, so an orbit that touches always gets the exact one)."""
        sc = self.scheme_at(omega)
        sensitivity = domega and tangent and self.forcing is None
        path = self._orbit(z, omega, keep_forces=sensitivity)
        zT, states = path["zT"], path["states"]
        if not tangent:
            return zT, None, (states if record else None)
        h, r = sc.h, self.r
        # the tangent: d q_n / d z and d q_n-1 / d z along the orbit (and d q_n / d h as a last column)
        T, Tp = np.eye(2 * r)[:r].copy(), np.eye(2 * r)[r:].copy()
        if sensitivity:
            T, Tp = np.hstack([T, np.zeros((r, 1))]), np.hstack([Tp, np.zeros((r, 1))])
        T, Tp = self._propagate(path, T, Tp, sensitivity)
        mono = np.vstack([T[:, :2 * r], Tp[:, :2 * r]])
        if domega and tangent:
            # h = 2 pi / (omega n); the casing's angle per step, Omega h = m pi / n, does not depend on omega
            dz = None if not sensitivity else np.r_[T[:, -1], Tp[:, -1]] * (-h / omega)
            return zT, mono, (states if record else None), dz
        return zT, mono, (states if record else None)

    def _orbit(self, z: np.ndarray, omega: float, keep_forces: bool = False) -> dict:
        """One period of the scheme from z: its states (n + 1, r), z(T), each touching step's active set, D_AA^-1
        and correction, and (``keep_forces``) each step's GNL part of the prediction."""
        sc = self.scheme_at(omega)
        h, r, n = sc.h, self.r, self.steps
        Q, Qp = np.array(z[:r], float), np.array(z[r:], float)
        Qp0 = Qp.copy()
        force = sc.model.forces if sc.nonlinear else None
        contact = self.contact
        if contact is not None:                   # the map's contact step (dynamics.contact_step), one run
            mu = self.casing.mu
            one, Om, phase = np.zeros(1, int), np.array([self.speed(omega)]), np.zeros(1)
        states = np.empty((n + 1, r))
        states[0] = Q
        touched = {}
        forces = np.zeros((n, r)) if keep_forces and force is not None else None
        for k in range(n):                        # the map's prediction (CentralDifference.predict), one run
            F = None if self.forcing is None else np.asarray(self.forcing(k * h, omega), float)
            Qn, fk = sc.predict(Q[:, None], Qp[:, None], F, parts=True)
            if forces is not None:
                forces[k] = fk[:, 0]
            if contact is not None:
                hits, lam, _ = contact.multipliers(Qn, one, Om, phase, (k + 1) * h)
                if hits.size and (lam[:, 0] > 0).any():
                    lam = lam[:, 0]
                    act, inv = self.solver.inverse(mu, lam > 0)            # D_AA^-1, kept by the solver
                    correction = contact.push(lam[:, None], np.array([mu]))[:, 0]
                    Qn[:, 0] += correction
                    touched[k] = act, inv, correction
            Qp, Q = Q, Qn[:, 0]
            states[k + 1] = Q
        return {"scheme": sc, "omega": omega, "zT": np.r_[Q, Qp], "states": states, "touched": touched,
                "forces": forces, "Qp0": Qp0}

    def _propagate(self, path: dict, T: np.ndarray, Tp: np.ndarray, sensitivity: bool = False):
        """The tangent of the period ``path`` (``_orbit``) applied to the columns (T; Tp) of d(q_0; q_-1): (d q_n,
        d q_n-1) at the period's end. With ``sensitivity`` the last column is d/dh, marched with the operators' own
        change with the step."""
        sc, states, touched, forces, Qp0 = (path[k] for k in ("scheme", "states", "touched", "forces", "Qp0"))
        n = self.steps
        force = sc.model.forces if sc.nonlinear else None
        if self.contact is not None:
            B = self.WN + self.casing.mu * self.WT
        if sensitivity:
            dX1, dX2, G0 = self._step_derivatives(sc)
        # an orbit that touches rings the highest modes (periods of a few steps): J at every step there
        every = 1 if touched else self.jacobian_every
        if force is not None:                     # J at k = 0, every, 2 every, ... and n - 1, linear between
            ks = sorted({*range(0, n, every), n - 1})
            Jk = dict(zip(ks, sc.X0 @ force.jacobians(states[ks].T)))
        for k in range(n):
            A = sc.X1
            if force is not None:
                k0 = k - k % every
                k1 = min(k0 + every, n - 1)
                s = (k - k0) / (k1 - k0) if k1 > k0 else 0.0
                A = A - (Jk[k0] if s == 0.0 else (1 - s) * Jk[k0] + s * Jk[k1])
            Tn = A @ T + sc.X2 @ Tp
            if sensitivity:
                # the operators' own change with h: X1, X2, and X0 in the force (f_k = -X0 g: dX0 X0^-1 f_k)
                dq = dX1 @ states[k] + dX2 @ (states[k - 1] if k else Qp0)
                if forces is not None:
                    dq += G0 @ forces[k]
                Tn[:, -1] += dq
            if k in touched:
                act, inv, correction = touched[k]
                if sensitivity:
                    # B = W E changes as dW W^-1 B = G0 B: d q = P (d q_pred + G0 B_A lambda_A)
                    Tn[:, -1] += G0 @ correction
                # lambda_A = D_AA^-1 (c - N_A q_pred): d q = (I - B_A D_AA^-1 N_A) d q_pred
                Tn = Tn - B[:, act] @ (inv @ (self.contact.N[act] @ Tn))
            Tp, T = T, Tn
        return T, Tp

    def monodromy_products(self, z: np.ndarray, omega: float):
        """The monodromy of the period from z as products (#88): returns (z(T), apply), apply(V) = M V for a block V
        (2 r, k) of perturbations of z, marched together along the one orbit (k columns, not 2 r: Newton-Krylov and
        Arnoldi need a few tens of products, not the whole monodromy)."""
        path = self._orbit(z, omega)
        r = self.r

        def apply(V: np.ndarray) -> np.ndarray:
            V = np.asarray(V, float)
            block = V.reshape(2 * r, -1)
            T, Tp = self._propagate(path, block[:r].copy(), block[r:].copy())
            return np.vstack([T, Tp]).reshape(V.shape)
        return path["zT"], apply

    def leading_multipliers(self, z: np.ndarray, omega: float, k: int = 6, tol: float = 1e-10) -> np.ndarray:
        """The k Floquet multipliers of largest modulus (those that decide stability and bifurcations), by Arnoldi
        on the monodromy's products (``monodromy_products``; scipy's ARPACK), by decreasing modulus."""
        import scipy.sparse.linalg as spla

        n = 2 * self.r
        if not (isinstance(k, (int, np.integer)) and 1 <= k <= n - 2):
            raise ValueError(f"k (the multipliers wanted) must be an integer in [1, {n - 2}], got {k!r}")
        if not (isinstance(tol, float) and 0.0 < tol < 1.0):
            raise ValueError(f"tol (Arnoldi's) must be in (0, 1), got {tol!r}")
        _, apply = self.monodromy_products(z, omega)
        op = spla.LinearOperator((n, n), matvec=apply, matmat=apply, dtype=float)
        values = spla.eigs(op, k=int(k), which="LM", tol=tol, return_eigenvectors=False)
        return values[np.argsort(-np.abs(values), kind="stable")]

    @staticmethod
    def _step_derivatives(sc):
        """(dX1/dh, dX2/dh, dX0/dh X0^-1) of the scheme ``sc`` (not massless): with S = 2 M + h C and S^-1 = X0 /
        (2 h^2), dX1/dh = -S^-1 (C X1 + 4 h K), dX2/dh = S^-1 C (I - X2), dX0/dh X0^-1 = 2 I / h - S^-1 C."""
        h, r = sc.h, sc.r
        Sinv = sc.X0 / (2 * h * h)
        SC = Sinv @ sc.C
        return -(SC @ sc.X1 + 4 * h * (Sinv @ sc.K)), SC @ (np.eye(r) - sc.X2), 2 * np.eye(r) / h - SC

    def from_rest(self, omega: float, periods: int) -> np.ndarray:
        """A start for Newton at ``omega``: the state after ``periods`` periods of the scheme (step T / n) from rest,
        the casing's ovalisation ramped in over the run as in the maps (eq. 38; complete at its end to 1e-10), so
        that the last state has the casing where the period map starts it. A GNL orbit from rest against the full
        casing at once, or Newton's first steps from there, can reach states past the tangent's stability limit;
        the transient brings the scheme onto its attractor first (ValueError if it blows up)."""
        from rotor37_rom.dynamics.explicit import simulate

        if not (isinstance(periods, (int, np.integer)) and periods >= 1):
            raise ValueError(f"periods (of the transient from rest) must be an integer >= 1, got {periods!r}")
        sc = self.scheme_at(omega)
        forcing = None if self.forcing is None else (lambda t: np.asarray(self.forcing(t, omega), float))
        run = simulate(sc, self.speed(omega), casing=self.casing, n_steps=int(periods) * self.steps,
                       forcing=forcing, record_every=self.steps, on_blowup="flag")
        if run.diverged_step[0] >= 0:
            raise ValueError(f"the transient from rest at Omega = {self.speed(omega):g} rad/s blew up at step "
                             f"{run.diverged_step[0]} (T / n = {sc.h:.3g} s): no start for the periodic orbit")
        return np.r_[run.q_final[:, 0], run.q_prev[:, 0]]

    def orbit(self, solution) -> np.ndarray:
        """q over the period of a shooting ``solution`` (a PeriodicSolution of this map): (n + 1, r), the states
        at t = 0, h, ..., T."""
        return self.march(solution.unknowns, solution.omega, tangent=False, record=True)[2]

    def residual(self, x: np.ndarray, omega: float, jacobian: bool = True, domega: bool = True):
        """R = z(T) - z(0) (with dR/dz and dR/domega); not finite (NaN) for an iterate whose period the scheme
        cannot march: past its stability limit, or a contact set that does not settle (``ContactSetError``: the
        state blown up by a wild Newton iterate), so that Newton steps back and the continuation halves its step."""
        try:
            return self._residual(x, omega, jacobian, domega)
        except ContactSetError:
            nan = np.full(self.size, np.nan)
            return nan if not jacobian else (nan, np.full((self.size, self.size), np.nan), nan if domega else None)

    def _residual(self, x: np.ndarray, omega: float, jacobian: bool, domega: bool):
        if not jacobian:
            return self.march(x, omega, tangent=False)[0] - x
        if not domega:
            zT, mono, _ = self.march(x, omega)
            return zT - x, mono - np.eye(self.size), None
        zT, mono, _, dz = self.march(x, omega, domega=True)
        R = zT - x
        if dz is not None:
            return R, mono - np.eye(self.size), dz
        d = 1e-7 * omega                   # an external forcing: dR/domega by central differences
        dR = (self.march(x, omega + d, tangent=False)[0] - self.march(x, omega - d, tangent=False)[0]) / (2 * d)
        return R, mono - np.eye(self.size), dR

    def floquet_exponents(self, x: np.ndarray, omega: float, J: np.ndarray | None = None) -> np.ndarray:
        """The 2 r exponents log(multiplier) / T of the discrete orbit (the monodromy's eigenvalues), by increasing
        real part; a multiplier 0 (a plastic impact) is an exponent of real part -inf."""
        if J is None:
            J = self.residual(x, omega, domega=False)[1]
        mult = np.linalg.eigvals(J + np.eye(self.size))
        with np.errstate(divide="ignore"):          # real and imaginary parts apart: -inf + i 0, not nan
            lam = np.log(np.abs(mult)) * (omega / (2 * np.pi)) + 1j * (np.angle(mult) * omega / (2 * np.pi))
        return lam[np.argsort(lam.real, kind="stable")]


def solve_periodic_krylov(shooting: Shooting, x0: np.ndarray, omega: float, tol: float = 1e-10, max_iter: int = 30,
                          krylov_tol: float = 1e-3, multipliers: int = 6):
    """Newton-Krylov on the shooting residual R = z(T) - z (#88): each Newton step solves (M - I) dz = -R by GMRES on
    the monodromy's products (``Shooting.monodromy_products``: one orbit, then a few vectors marched along it,
    instead of the 2 r columns of the dense monodromy), to the relative residual ``krylov_tol``; stops when the
    update is below ``tol`` relative to z. Stability from the ``multipliers`` leading Floquet multipliers by
    Arnoldi (``Shooting.leading_multipliers``; 0: none). Returns a ``PeriodicSolution`` as ``solve_periodic`` does
    (its exponents those of the leading multipliers alone); ValueError where Newton does not converge."""
    import scipy.sparse.linalg as spla

    from rotor37_rom.checks import whole_number
    from rotor37_rom.periodic.harmonic_balance import PeriodicSolution, _stable

    real_number("omega", omega, 0.0, open_low=True, unit=" rad/s")
    real_number("tol", tol, 0.0)
    whole_number("max_iter", max_iter, 1)
    real_number("krylov_tol", krylov_tol, 0.0, 1.0, open_low=True, open_high=True)
    whole_number("multipliers", multipliers, 0)
    n = shooting.size
    if multipliers > n - 2:
        raise ValueError(f"multipliers must be in [0, {n - 2}], got {multipliers}")
    x = np.asarray(x0, float).copy()
    if x.shape != (n,) or not np.isfinite(x).all():
        raise ValueError(f"x0 must be {n} finite unknowns, got shape {x.shape}")
    for it in range(1, max_iter + 1):
        zT, apply = shooting.monodromy_products(x, omega)
        R = zT - x
        if not np.isfinite(R).all():
            raise ValueError(f"periodic orbit: the period from Newton-Krylov's iterate {it} is not finite at omega "
                             f"= {omega:g} (past the scheme's stability limit)")
        op = spla.LinearOperator((n, n), matvec=lambda v: apply(v) - v, dtype=float)
        dx, info = spla.gmres(op, -R, tol=krylov_tol, atol=0.0, restart=min(n, 60), maxiter=20)
        if info < 0 or not np.isfinite(dx).all():
            raise ValueError(f"periodic orbit: GMRES failed (info {info}) at omega = {omega:g}")
        x += dx
        if np.linalg.norm(dx) <= tol * max(np.linalg.norm(x), 1e-300):
            exps = None
            if multipliers:
                mult = shooting.leading_multipliers(x, omega, k=int(multipliers))
                with np.errstate(divide="ignore"):
                    exps = np.log(np.abs(mult)) * (omega / (2 * np.pi)) + 1j * (np.angle(mult) * omega / (2 * np.pi))
                exps = exps[np.argsort(exps.real, kind="stable")]
            X, L = shooting.split(x)
            residual = float(np.linalg.norm(shooting.march(x, omega, tangent=False)[0] - x))
            return PeriodicSolution(omega, X, exps, _stable(exps, omega), residual, it, L)
    raise ValueError(f"periodic orbit: Newton-Krylov did not converge in {max_iter} iterations at omega = {omega:g}")
