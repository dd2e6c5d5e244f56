"""Pareto-optimal points of a cost-error cloud: what the speed-accuracy study chooses models from
(``studies.model_choice``) and what its charts join (``viz.charts.plot_speed_accuracy``). Pure NumPy."""
from __future__ import annotations

from typing import Sequence

import numpy as np

__all__ = ["pareto_front"]


def pareto_front(costs: Sequence[float], errors: Sequence[float]) -> np.ndarray:
    """Mask of the Pareto-optimal points: no other point is at most as costly and at most as wrong, and strictly
    better in one of the two. NaN or infinite errors (a run that diverged) are never optimal."""
    c, e = np.asarray(costs, float), np.asarray(errors, float)
    ok = np.isfinite(c) & np.isfinite(e)
    front = np.zeros(c.size, bool)
    for i in np.flatnonzero(ok):
        dominated = ok & (c <= c[i]) & (e <= e[i]) & ((c < c[i]) | (e < e[i]))
        front[i] = not dominated.any()
    return front
