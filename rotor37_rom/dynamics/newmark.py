"""Implicit Newmark (average acceleration) on dense reduced matrices, linear or with a nonlinear force."""
from __future__ import annotations

from typing import Callable

import numpy as np
import scipy.integrate
import scipy.linalg


def simulate_linear_newmark(M: np.ndarray, C: np.ndarray, K: np.ndarray, f: Callable[[float], np.ndarray],
                            dt: float, n_steps: int) -> tuple[np.ndarray, np.ndarray]:
    """Average-acceleration Newmark for a small dense linear system from rest. Returns (t, q) with q (r, n+1)."""
    return simulate_newmark(M, C, K, f, dt, n_steps)


def simulate_newmark(M: np.ndarray, C: np.ndarray, K: np.ndarray, f: Callable[[float], np.ndarray], dt: float,
                     n_steps: int, forces=None, rtol: float = 1e-10, max_iterations: int = 40
                     ) -> tuple[np.ndarray, np.ndarray]:
    """Average-acceleration Newmark (beta = 1/4, gamma = 1/2) of M q'' + C q' + K q + g(q) = f(t) from rest, dense.

    ``forces``: the reduced nonlinear force g (``evaluate``/``jacobian``), None for the linear model. Each step
    iterates on the residual with the factorisation of K + 4 M / dt^2 + 2 C / dt (modified Newton); where that
    converges slowly (a ratio above 1/4) the tangent of g at the iterate is added and factorised (Newton, with a
    backtracking line search); a step whose Newton fails is split in two halves (up to 5 times).
    Stops at |residual| <= rtol x max(|f|, |K q|). Returns (t, q) with q (r, n_steps + 1)."""
    if not (dt > 0 and n_steps >= 1):
        raise ValueError(f"dt must be > 0 s and n_steps >= 1, got {dt}, {n_steps}")
    r = K.shape[0]
    linear = {}

    def factor(h):
        if h not in linear:
            A = K + 4.0 / h**2 * M + 2.0 / h * C
            linear[h] = (A, scipy.linalg.lu_factor(A))
        return linear[h]

    def g(q):
        return np.asarray(forces.evaluate(q)).reshape(r)

    def advance(q, v, a, t_new, h):
        A, lu = factor(h)
        rhs = f(t_new) + M @ (4.0 / h**2 * q + 4.0 / h * v + a) + C @ (2.0 / h * q + v)
        q_new = scipy.linalg.lu_solve(lu, rhs)
        if forces is not None:
            res = A @ q_new + g(q_new) - rhs
            norm = np.linalg.norm(res)
            for it in range(max_iterations + 1):
                if norm <= rtol * max(np.linalg.norm(rhs), np.linalg.norm(K @ q_new), 1e-300):
                    break
                if it == max_iterations or not np.isfinite(norm):
                    return None
                trial = q_new - scipy.linalg.lu_solve(lu, res)       # modified Newton: the kept factorisation
                res_trial = A @ trial + g(trial) - rhs
                if np.linalg.norm(res_trial) > 0.25 * norm:         # too slow: Newton with a line search
                    lu = scipy.linalg.lu_factor(A + forces.jacobian(q_new))
                    step = scipy.linalg.lu_solve(lu, res)
                    for _ in range(6):
                        trial = q_new - step
                        res_trial = A @ trial + g(trial) - rhs
                        if np.linalg.norm(res_trial) < norm:
                            break
                        step = 0.5 * step
                    else:
                        return None                    # no descent along Newton's direction: the step is too long
                q_new, res, norm = trial, res_trial, np.linalg.norm(res_trial)
        a_new = 4.0 / h**2 * (q_new - q) - 4.0 / h * v - a
        return q_new, v + 0.5 * h * (a + a_new), a_new

    def advance_adaptive(q, v, a, t_new, h, depth=0):
        out = advance(q, v, a, t_new, h)
        if out is not None:
            return out
        if depth == 5:
            raise RuntimeError(f"Newmark-Newton did not converge at t = {t_new:.6e} s even with dt / 32")
        q, v, a = advance_adaptive(q, v, a, t_new - h / 2, h / 2, depth + 1)
        return advance_adaptive(q, v, a, t_new, h / 2, depth + 1)

    q, v = np.zeros(r), np.zeros(r)
    a = np.linalg.solve(M, f(0.0))
    out = [q.copy()]
    for n in range(1, n_steps + 1):
        q, v, a = advance_adaptive(q, v, a, n * dt, dt)
        out.append(q.copy())
    return np.arange(n_steps + 1) * dt, np.array(out).T
