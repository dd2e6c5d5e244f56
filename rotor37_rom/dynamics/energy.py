"""Energy balance of an implicit run (``newmark.Newmark``: average acceleration or generalised alpha, viscous damping,
unilateral contact by Lagrange multipliers): what the structure stores, what the load, the damping and the contact
do to it, and what the scheme itself dissipates (issue #86, item 2a).

Per step n -> n+1, with dx = x_n+1 - x_n (sums over the steps give the run's balance):

    kinetic T = 1/2 v.M v and strain energy E(x) at the step points;
    external work   W_ext = dx . (f_n + f_n+1) / 2                       (trapezoidal)
    damping         D     = dx . C (v_n + v_n+1) / 2                     (trapezoidal)
    contact work    W_c   = -dx . B lam_bar, B = (N + mu S)^T            (the multipliers as the scheme writes them)
    residual        R     = W_ext + W_c - D - (T + E)_n+1 + (T + E)_n    (the numerical dissipation: R > 0 loses)

R is the energy the bookkeeping cannot place. The sign: R > 0 where the run holds less energy than was put in (the
brief of #86 wrote R = d(T + E) - W_ext + D - W_c and called it "the numerical dissipation, > 0 for generalised
alpha"; the two cannot both hold, and R here is that dissipation, i.e. minus that expression).

How exact each term is follows from the scheme's own equations (``Newmark``). Average acceleration (rho_inf None)
writes equilibrium at t_n+1 with the multipliers lam_n+1, and its kinematics give dx = h (v_n + v_n+1) / 2 exactly.
The mean of its equations at t_n and t_n+1, dotted with dx, is the identity

    R = G - P,   G = dx . (f_int(x_n) + f_int(x_n+1)) / 2 - (E_n+1 - E_n),   P = dx . (e_n + e_n+1) / 2,

with lam_bar = (lam_n + lam_n+1) / 2 and e_k the equilibrium residual at t_k (what Newton left, ``rtol``). So:

* a linear internal force has G = 0: without contact, load and damping T + E is conserved to round-off; with them
  the trapezoidal W_ext, D and W_c are exact; D = h/4 (v_n + v_n+1).C(v_n + v_n+1) >= 0;
* a nonlinear law has G = (1/12) D^2 f_int(x_n+1/2)[dx, dx] . dx + O(h^5) per step, the trapezoidal rule's error
  on the force's work along dx: O(h^3) per step, O(h^2) over a fixed time; for a force cubic in x (the reduced St.
  Venant-Kirchhoff force) exactly G = (phi(0) - 2 phi(1/2) + phi(1)) / 3, phi(s) = f_int(x_n + s dx) . dx;
* the generalised-alpha scheme writes the step's equation at its alpha points (inertia at 1 - alpha_m, the other
  forces at 1 - alpha_f) with one multiplier lam_n+1 for the whole step: lam_bar = lam_n+1, P its residual dotted
  with dx, and R = G - P + A, A its algorithmic dissipation (zero at rho_inf = 1, the mid-point form of average
  acceleration). For a mode the step resolves (Omega = omega h << 1) the spectral radius is 1 - O(Omega^4): the
  energy lost over a fixed time is O(h^3); per step T + E also oscillates at twice the frequency by O(h^3) (the
  scheme's energy is not T + E), so R per step is not one-signed, its sum over whole periods is > 0. Under loads and
  impacts its R is not one-signed over a run either (a loaded 3-DOF chain against a moving wall, rho_inf = 0.8:
  sum R = -7.9 J for 117 J of load work, the alpha weights moving load and contact work between steps).

``algorithmic`` = R - G + P is returned where the internal force is given: zero to round-off for average acceleration
(the balance identity itself, from the scheme's equations), A for generalised alpha. A step that ``Newmark.step``
split in halves is not one step of the scheme between its end points: its A is not zero.

Contact. With the gaps gap_k = gaps(t_k) - N x_k >= 0 and the complementarity lam_k . gap_k = 0 of the scheme, the
normal work splits exactly into W_n = wall - closing + opening: wall = -lam_bar . (gaps(t_n+1) - gaps(t_n)) the moving
casing's work (zero for a fixed wall), closing = 1/2 lam_n+1 . gap_n >= 0 the energy the step that closes a gap
removes (the impact's dissipation), opening = 1/2 lam_n . gap_n+1 >= 0 the energy average acceleration gives back at
the step that opens one (generalised alpha: closing = lam_n+1 . gap_n, opening = 0: its contact only dissipates).
In continuous time lam . d(gap)/dt = 0 and a fixed wall does no work: closing - opening is the scheme's own, and
average acceleration with contact is not energy-conserving either way: a free mass m at speed v0 that would reach a
fixed wall a fraction s < 1/2 of a step after t_n loses closing = 2 m v0^2 s (1 - s) at the impact step and gains
opening = 2 m v0^2 (1 - s) (2 - 3 s) at the next, leaving at |3 - 4 s| v0 > v0; the mid-point form (rho_inf = 1)
leaves at |1 - 2 s| v0 <= v0.

``record_run`` runs a ``Newmark`` and keeps what the balance needs; ``energy_balance`` takes arrays (any run can feed
it); ``balance_of_run`` joins the two; ``reduced_strain_energy`` is E(q) of a dense reduced model.
"""
from __future__ import annotations

import dataclasses
from typing import Callable

import numpy as np

__all__ = ["Run", "EnergyBalance", "record_run", "energy_balance", "balance_of_run", "reduced_strain_energy"]

#: Gauss-Legendre points and weights on [0, 1] (3 points: exact for a polynomial of degree 5; the reduced SVK force
#: along a ray, g(s x).x, is of degree 3 in s)
_GL_S, _GL_W = (np.polynomial.legendre.leggauss(3)[0] + 1.0) / 2.0, np.polynomial.legendre.leggauss(3)[1] / 2.0


@dataclasses.dataclass(frozen=True)
class Run:
    """The step points of a run: t (K+1,); x, v, a (n, K+1) one column per time point; loads (n, K+1) the load at
    each t_k; multipliers (n_c, K+1) or None (no contact): average acceleration's at t_k, generalised alpha's of the
    step that ends at t_k (column 0: zeros, a start out of contact)."""

    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    a: np.ndarray
    loads: np.ndarray
    multipliers: np.ndarray | None


@dataclasses.dataclass(frozen=True)
class EnergyBalance:
    """The balance's terms (J): kinetic, strain (K+1,) at the step points; per step (K,) external, damping, contact
    (= contact_normal + contact_friction), wall, closing, opening (contact_normal = wall - closing + opening), residual
    R (> 0: energy lost by the scheme) and scale, the sum of the magnitudes R is summed from (its round-off is
    ~ n eps scale); with the internal force also quadrature_gap G, defect P and algorithmic A (R = G - P + A), else
    None. See the module's docstring for which term is exact for which scheme."""

    kinetic: np.ndarray
    strain: np.ndarray
    external: np.ndarray
    damping: np.ndarray
    contact_normal: np.ndarray
    contact_friction: np.ndarray
    wall: np.ndarray
    closing: np.ndarray
    opening: np.ndarray
    residual: np.ndarray
    scale: np.ndarray
    quadrature_gap: np.ndarray | None
    defect: np.ndarray | None
    algorithmic: np.ndarray | None

    @property
    def contact(self) -> np.ndarray:
        """The multipliers' work per step, normal and friction."""
        return self.contact_normal + self.contact_friction

    @property
    def energy(self) -> np.ndarray:
        """T + E at the step points."""
        return self.kinetic + self.strain


def reduced_strain_energy(K, forces=None) -> Callable[[np.ndarray], float]:
    """E(q) = 1/2 q.K q + V(q) of a reduced model with the nonlinear force g (``forces.NonlinearForce``, None: linear):
    V from ``forces.potential`` where the force has one (``PolynomialForces``: the SVK force's quartic potential), else
    the line integral of g along the ray 0 -> q by 3-point Gauss-Legendre, exact for a force cubic in q (any
    conservative one: the SVK quadrature and cubature forces are gradients of their points' energies)."""
    K = np.asarray(K, float)
    if K.ndim != 2 or K.shape[0] != K.shape[1] or not np.isfinite(K).all():
        raise ValueError(f"K must be a finite square matrix, got shape {K.shape}")
    if forces is not None and forces.r != K.shape[0]:
        raise ValueError(f"forces: r = {forces.r} does not match K {K.shape}")

    def energy(q) -> float:
        q = _vector(q, "q", K.shape[0])
        e = 0.5 * q @ (K @ q)
        if forces is None:
            return float(e)
        if getattr(forces, "has_potential", False):
            return float(e + forces.potential(q)[0])
        g = np.asarray(forces.evaluate(np.outer(q, _GL_S)))            # (r, 3): g(s_i q)
        return float(e + _GL_W @ (q @ g))
    return energy


def record_run(stepper, t, x0, v0, a0=None) -> Run:
    """Run ``stepper`` (a ``Newmark``) through the times t (K+1,) from x0, v0 (a0: the acceleration there; None: the
    one equilibrium gives, M a0 = f(t0) - f_int(x0) - C v0, out of contact) and keep the step points, the loads and
    the multipliers. Each step is one call of ``stepper.step``; the start must be out of contact (zero
    multipliers)."""
    t = _times(t)
    n = _square(stepper.M, "stepper.M").shape[0]
    x, v = _vector(x0, "x0", n), _vector(v0, "v0", n)
    if a0 is None:
        rhs = np.asarray(stepper.force(t[0]), float) - np.asarray(stepper.internal(x), float)
        if stepper.C is not None:
            rhs = rhs - stepper.C @ v
        a = np.asarray(stepper.factorise(stepper.M)(rhs), float).reshape(n)
    else:
        a = _vector(a0, "a0", n)
    contact = stepper.contact
    cols = [(x, v, a, None if contact is None else np.zeros(stepper.B.shape[1]))]
    for k in range(1, t.size):
        lam = cols[-1][3]
        x, v, a, _, lam = stepper.step(x, v, a, t[k], t[k] - t[k - 1], lam is not None and bool(lam.any()))
        cols.append((x, v, a, lam))
    X, V, A = (np.column_stack([c[i] for c in cols]) for i in range(3))
    loads = np.column_stack([np.asarray(stepper.force(tk), float).reshape(n) for tk in t])
    lam = None if contact is None else np.column_stack([c[3] for c in cols])
    return Run(t, X, V, A, loads, lam)


def balance_of_run(stepper, run: Run, strain_energy: Callable) -> EnergyBalance:
    """``energy_balance`` of a ``record_run`` of ``stepper``: its M, C, internal force, contact and scheme."""
    rho_inf = None if stepper.alpha_f == 0.0 else stepper.alpha_f / (1.0 - stepper.alpha_f)
    return energy_balance(run.x, run.v, run.a, stepper.M, strain_energy, t=run.t, loads=run.loads, C=stepper.C,
                          contact=stepper.contact, multipliers=run.multipliers, internal=stepper.internal,
                          rho_inf=rho_inf)


def energy_balance(x, v, a, M, strain_energy: Callable, *, t=None, loads=None, C=None, contact=None,
                   multipliers=None, internal: Callable | None = None, rho_inf: float | None = None
                   ) -> EnergyBalance:
    """The energy balance of a run's step points x, v, a (n, K+1), one column per time point.

    Args:
        M, C: mass and viscous damping (n, n), any matrices with ``@`` (C None: undamped).
        strain_energy: x (n,) -> E(x), the potential of the internal force (``reduced_strain_energy``).
        t: (K+1,) the times (needed with contact: the gaps move with t). loads: (n, K+1) f(t_k), None: unloaded.
        contact: a ``newmark.StepContact`` (N, S, mu, gaps) with multipliers (n_c, K+1) as ``Run`` keeps them.
        internal: x -> f_int(x) (n,): adds the quadrature gap, the defect and the algorithmic dissipation.
        rho_inf: the scheme, as ``Newmark`` takes it (None: average acceleration, else generalised alpha).
    """
    X, V, A, n = _states(x, v, a)
    M = _square(M, "M", n)
    C = None if C is None else _square(C, "C", n)
    F = np.zeros_like(X) if loads is None else _columns(loads, "loads", X.shape)
    am, af = _alphas(rho_inf)
    T = _time_column(t, X.shape[1], required=contact is not None)
    dX = np.diff(X, axis=1)
    kinetic = 0.5 * np.einsum("ik,ik->k", V, M @ V)
    strain = np.array([_scalar(strain_energy(X[:, k]), "strain_energy") for k in range(X.shape[1])])
    external = 0.5 * np.einsum("ik,ik->k", dX, F[:, :-1] + F[:, 1:])
    damping = np.zeros(dX.shape[1]) if C is None else 0.5 * np.einsum("ik,ik->k", dX, C @ (V[:, :-1] + V[:, 1:]))
    c = _contact_terms(contact, multipliers, X, dX, T, newmark=rho_inf is None)
    stored = np.diff(kinetic + strain)
    residual = external + c["normal"] + c["friction"] - damping - stored
    scale = (kinetic[:-1] + kinetic[1:] + np.abs(strain[:-1]) + np.abs(strain[1:]) + np.abs(external)
             + np.abs(damping) + np.abs(c["normal"]) + np.abs(c["friction"]))
    gap = defect = algorithmic = None
    if internal is not None:
        f_int = np.column_stack([_vector(internal(X[:, k]), "internal(x)", n) for k in range(X.shape[1])])
        gap = 0.5 * np.einsum("ik,ik->k", dX, f_int[:, :-1] + f_int[:, 1:]) - np.diff(strain)
        weights = (0.5, 0.5) if rho_inf is None else (am, af)
        defect = _defect(M, C, dX, A, V, f_int, F, c["force"], weights)
        algorithmic = residual - gap + defect
    return EnergyBalance(kinetic, strain, external, damping, c["normal"], c["friction"], c["wall"], c["closing"],
                         c["opening"], residual, scale, gap, defect, algorithmic)


def _defect(M, C, dX, A, V, f_int, F, contact_force, weights) -> np.ndarray:
    """P per step: dx dotted with the residual of the step's equation as the scheme writes it, inertia at the weights
    (w_m of t_n, 1 - w_m of t_n+1), the other forces at (w_f, 1 - w_f), the contact force B lam_bar of the step."""
    wm, wf = weights

    def mix(Y, w):
        return w * Y[:, :-1] + (1.0 - w) * Y[:, 1:]
    e = M @ mix(A, wm) + mix(f_int, wf) - mix(F, wf) + contact_force
    if C is not None:
        e = e + C @ mix(V, wf)
    return np.einsum("ik,ik->k", dX, e)


def _contact_terms(contact, multipliers, X, dX, t, newmark: bool) -> dict:
    """The multipliers' works per step: normal and friction, the normal one split into wall - closing + opening, and
    the force B lam_bar (n, K) of each step (module docstring)."""
    K = dX.shape[1]
    zero = np.zeros(K)
    if contact is None:
        if multipliers is not None:
            raise ValueError("multipliers given without a contact")
        return dict(normal=zero, friction=zero, wall=zero, closing=zero, opening=zero, force=0.0)
    N, S, mu = contact.N, contact.S, float(contact.mu)
    n_c = N.shape[0]
    if N.shape != (n_c, X.shape[0]) or S.shape != N.shape:
        raise ValueError(f"contact: N {N.shape} and S {S.shape} must both be (n_c, {X.shape[0]})")
    if not (np.isfinite(mu) and mu >= 0):
        raise ValueError(f"contact: mu must be finite and >= 0, got {mu}")
    if multipliers is None:
        raise ValueError("multipliers: required with a contact, (n_c, K+1)")
    lam = _columns(multipliers, "multipliers", (n_c, X.shape[1]))
    lam_bar = 0.5 * (lam[:, :-1] + lam[:, 1:]) if newmark else lam[:, 1:]
    free = np.column_stack([_vector(contact.gaps(tk), "contact.gaps(t)", n_c) for tk in t])
    gap = free - np.asarray(N @ X)
    normal = -np.einsum("ik,ik->k", lam_bar, np.asarray(N @ dX))
    friction = -mu * np.einsum("ik,ik->k", lam_bar, np.asarray(S @ dX))
    wall = -np.einsum("ik,ik->k", lam_bar, np.diff(free, axis=1))
    if newmark:
        closing = 0.5 * np.einsum("ik,ik->k", lam[:, 1:], gap[:, :-1])
        opening = 0.5 * np.einsum("ik,ik->k", lam[:, :-1], gap[:, 1:])
    else:
        closing, opening = np.einsum("ik,ik->k", lam[:, 1:], gap[:, :-1]), zero
    force = np.asarray(N.T @ lam_bar) + mu * np.asarray(S.T @ lam_bar)
    return dict(normal=normal, friction=friction, wall=wall, closing=closing, opening=opening, force=force)


def _alphas(rho_inf) -> tuple[float, float]:
    """(alpha_m, alpha_f) of ``Newmark``'s generalised alpha; (0, 0) for average acceleration (rho_inf None)."""
    if rho_inf is None:
        return 0.0, 0.0
    if not (isinstance(rho_inf, (int, float, np.floating)) and 0.0 <= rho_inf <= 1.0):
        raise ValueError(f"rho_inf must be in [0, 1] (or None: average acceleration), got {rho_inf!r}")
    return (2 * rho_inf - 1) / (rho_inf + 1), rho_inf / (rho_inf + 1)


def _states(x, v, a) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """x, v, a as finite (n, K+1) arrays of one shape, K >= 1."""
    X = np.asarray(x, float)
    if X.ndim != 2 or X.shape[1] < 2 or X.shape[0] < 1:
        raise ValueError(f"x must be (n, K+1) with K >= 1 steps, got shape {X.shape}")
    if not np.isfinite(X).all():
        raise ValueError("x must be finite")
    return X, _columns(v, "v", X.shape), _columns(a, "a", X.shape), X.shape[0]


def _columns(y, name: str, shape) -> np.ndarray:
    """y as a finite float array of ``shape``."""
    Y = np.asarray(y, float)
    if Y.shape != tuple(shape):
        raise ValueError(f"{name} must be {tuple(shape)}, got shape {Y.shape}")
    if not np.isfinite(Y).all():
        raise ValueError(f"{name} must be finite")
    return Y


def _vector(y, name: str, n: int) -> np.ndarray:
    """y as a finite float vector of n entries ((n,) or (n, 1))."""
    Y = np.asarray(y, float)
    if Y.size != n or Y.ndim > 2 or (Y.ndim == 2 and 1 not in Y.shape):
        raise ValueError(f"{name} must be ({n},), got shape {Y.shape}")
    if not np.isfinite(Y).all():
        raise ValueError(f"{name} must be finite")
    return Y.reshape(n)


def _scalar(e, name: str) -> float:
    """e as a finite float (one entry)."""
    e = np.asarray(e, float)
    if e.size != 1 or not np.isfinite(e).all():
        raise ValueError(f"{name} must return one finite number, got {e!r}")
    return float(e.reshape(()))


def _square(A, name: str, n: int | None = None):
    """A (unchanged: dense or sparse) after checking it is (n, n)."""
    shape = getattr(A, "shape", None)
    if shape is None or len(shape) != 2 or shape[0] != shape[1] or (n is not None and shape[0] != n):
        raise ValueError(f"{name} must be ({n or 'n'}, {n or 'n'}), got shape {shape}")
    return A


def _times(t) -> np.ndarray:
    """t as a finite, strictly increasing (K+1,) array, K >= 1."""
    t = np.asarray(t, float)
    if t.ndim != 1 or t.size < 2 or not np.isfinite(t).all() or not (np.diff(t) > 0).all():
        raise ValueError(f"t must be finite, strictly increasing, with >= 2 entries, got shape {t.shape}")
    return t


def _time_column(t, n_points: int, required: bool) -> np.ndarray | None:
    """The times for n_points step points (None where not given and not needed)."""
    if t is None:
        if required:
            raise ValueError("t: required with a contact (the gaps move with t)")
        return None
    t = _times(t)
    if t.size != n_points:
        raise ValueError(f"t must have {n_points} entries (one per column of x), got {t.size}")
    return t
