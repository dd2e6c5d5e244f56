"""What every reduced nonlinear force g~(q) of a model offers (``NonlinearForce``), and its file entries.

A reduced model's nonlinear force is evaluated by the integrators (explicit and implicit), the static solver, the
hyper-reduction and the stress recovery through this one interface, whatever computes it: the exact cubic tensors
(``tensors.PolynomialForces``), a quadrature over the mesh's points or a cubature's subset
(``tensors.QuadratureForces``), or a bladed disk's sector forces (``sector.SectorForces``, one sector's force applied
to every sector). A new evaluation (another material law, a neural surrogate) is a class with these members; the
model's file then needs its kind in ``model.reduced.FORCE_KINDS``.
"""
from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

__all__ = ["NonlinearForce"]


@runtime_checkable
class NonlinearForce(Protocol):
    """g~(q) of a reduced model M~ q'' + C~ q' + K~ q + g~(q) = f~ (the nonlinear part: K~ q is the model's).

    Members:
        r: size of q.
        precision: arithmetic of ``evaluate``, 'double' or 'single'.
        has_potential: whether ``potential`` is available (the energy of the explicit scheme needs it).
        evaluate(Q): g~ for states Q (r,) or (r, P) -> (r, P).
        jacobian(q): d g~ / d q at one state (r, r), exact.
        jacobians(Q): the same at each column of Q (r, P) -> (P, r, r), batched where the force can do better than
            one call per state (the shooting's tangent along an orbit, the harmonic balance's time samples).
        with_precision(precision): the same force evaluated in 'double' or 'single'; refused (ValueError) by a force
            that has one arithmetic only.
        scaled(factor): the force times ``factor`` (a perturbation of the model, a mistuned sector's E).
        premultiplied(X): a force that gives X @ g~(Q) more cheaply than the product after the evaluation (the
            explicit scheme's X3, X4 of eqs. 32-33), or None where there is no cheaper way.
        potential(Q): V(q) with grad V = g~, per column (only where ``has_potential``).
        arrays(): the entries that save it in a model's file, 'forces' naming its kind (``model.reduced`` reads them
            back through the kind's ``from_arrays``).
    """

    @property
    def r(self) -> int: ...

    @property
    def precision(self) -> str: ...

    has_potential: bool

    def evaluate(self, Q: np.ndarray) -> np.ndarray: ...

    def jacobian(self, q: np.ndarray) -> np.ndarray: ...

    def jacobians(self, Q: np.ndarray) -> np.ndarray: ...

    def with_precision(self, precision: str) -> "NonlinearForce": ...

    def scaled(self, factor: float) -> "NonlinearForce": ...

    def premultiplied(self, X: np.ndarray) -> "NonlinearForce | None": ...

    def potential(self, Q: np.ndarray) -> np.ndarray: ...

    def arrays(self) -> dict[str, np.ndarray]: ...
