"""GNL against linear in contact on equal footing (issue #23, item 2; ``benchmarks/bench_gnl_vs_linear.py``): which
sweeps belong to a map, and which speeds the step check (a GNL map's speeds run again at the step from every state)
can run.

Pure NumPy.
"""
from __future__ import annotations

import numpy as np


def same_step(h_map: float, h: float) -> bool:
    """Whether a sweep at step ``h`` belongs to a map run at ``h_map``: the same step or one of its retries' (halved
    up to 8 times); a map run again at another step (e.g. --step-outliers) keeps its earlier sweeps beside it."""
    return any(abs(h * 2 ** k / h_map - 1.0) < 1e-9 for k in range(9))


def grid_index(grid, w: float) -> int | None:
    """The index of speed ``w`` in ``grid`` up to round-off (linspace of another range), or None."""
    hit = np.flatnonzero(np.isclose(np.asarray(grid, float), w, rtol=1e-12, atol=0))
    return int(hit[0]) if hit.size else None


def in_range(check, speeds: tuple) -> bool:
    """Whether the --step-check grid (START, STOP, N) is speeds of the range (START, STOP, N), up to round-off."""
    grid = np.linspace(speeds[0], speeds[1], int(speeds[2]))
    return speeds[0] <= check[0] and check[1] <= speeds[1] and all(
        grid_index(grid, w) is not None for w in np.linspace(check[0], check[1], int(check[2])))


def check_speeds_error(args, ranges: list[tuple]) -> str | None:
    """Why the --step-check grid cannot be run (None: it can): it needs --step-outliers drop and GNL maps, and
    each of its speeds must be one of a range's."""
    if args.step_outliers != "drop" or args.gnl == "off":
        return "needs --step-outliers drop and --gnl on or both (it checks the GNL maps' dropped step)"
    start, stop, n = args.step_check
    if not (0 < start <= stop and n >= 1 and float(n).is_integer()):
        return f"need 0 < START <= STOP and an integer N >= 1, got {args.step_check}"
    if not any(in_range(args.step_check, r) for r in ranges):
        grid = np.linspace(start, stop, int(n))
        return f"its speeds {grid.tolist()} must be speeds of one of the ranges {[list(r) for r in ranges]}"
    return None
