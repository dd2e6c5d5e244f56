"""Matplotlib charts for the studies (imported lazily; Agg backend, files only)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["plot_clearance_consumption", "plot_md_weights", "plot_interaction_map", "plot_nfrc", "plot_time_history",
           "plot_speed_accuracy", "plot_indicator_vs_rmd", "plot_safe_diagram", "plot_disk_indicator",
           "plot_error_histories"]


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_clearance_consumption(curves, path: str | Path, reference: str = "FOM nonlinear") -> Path:
    """Fig. 9/10 analogue: Delta (mm) vs delta for every curve, and the relative error to the reference."""
    from rotor37_rom.post.clearance import relative_error

    plt = _pyplot()
    fig, (ax, ax_err) = plt.subplots(1, 2, figsize=(11, 4.2))
    ref = curves.curves[reference]
    for k, (name, values) in enumerate(curves.curves.items()):
        color = f"C{k}"
        style = "-" if name == reference else ("--" if "linear" in name else "-.")
        cost = curves.costs.get(name)
        label = name + (f" ({cost:.1f} s)" if cost is not None else "")
        ax.plot(curves.deltas, values * 1e3, style, color=color, marker="o", ms=3, label=label)
        if name != reference:
            ax_err.semilogy(curves.deltas, relative_error(values, ref), style, color=color, marker="o", ms=3,
                            label=name)
    ax.set_xlabel("deformation level δ")
    ax.set_ylabel("clearance consumption Δ at node LE (mm)")
    ax.set_title(f"{curves.mode}, ζ = {curves.zeta * 1e3:g} mm")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax_err.axhline(0.1, color="k", lw=0.8, ls=":")
    ax_err.set_xlabel("deformation level δ")
    ax_err.set_ylabel(f"relative error vs {reference}")
    ax_err.grid(alpha=0.3, which="both")
    return _save(fig, path)


def _save(fig, path: str | Path) -> Path:
    import matplotlib.pyplot as plt

    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def plot_md_weights(W: np.ndarray, pairs: np.ndarray, r_b: int, path: str | Path, title: str = "") -> Path:
    """Fig. 5/19 analogue: the weight of every modal derivative (upper triangle) with the selected ones marked."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6, 5))
    Wu = np.where(np.triu(np.ones_like(W, dtype=bool)), W, np.nan)
    im = ax.imshow(np.log10(Wu / np.nanmax(Wu)), cmap="viridis", vmin=-6, vmax=0)
    ax.plot(pairs[:, 1], pairs[:, 0], "r*", ms=5, label=f"selected ({len(pairs)})")
    ax.axhline(r_b - 0.5, color="w", lw=0.8)
    ax.axvline(r_b - 0.5, color="w", lw=0.8)
    ax.set_xlabel("mode k (constraint modes | fixed-interface modes)")
    ax.set_ylabel("mode j")
    ax.set_title(title or "modal-derivative weights")
    fig.colorbar(im, ax=ax, label="log10 W_jk / max W")
    ax.legend(loc="lower left", fontsize=8)
    return _save(fig, path)


def plot_interaction_map(imap, path: str | Path, eigenfrequencies=(), engine_orders=range(1, 17), title: str = "",
                         linear_resonance: float | None = None) -> Path:
    """Fig. 6 analogue: spectrum amplitude of node LE's radial displacement (log colour) vs speed and frequency,
    with the clamped eigenfrequencies (dashed) and engine-order lines (dotted)."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7.5, 5.0))
    amp = np.where(np.isfinite(imap.amplitude), imap.amplitude, np.nan) * 1e3
    floor = np.nanmax(amp) * 1e-4 if np.isfinite(amp).any() else 1e-12
    mesh = ax.pcolormesh(imap.speeds, imap.frequencies, np.log10(np.maximum(amp, floor)).T, shading="nearest",
                         cmap="jet")
    fig.colorbar(mesh, ax=ax, label="log10 amplitude (mm)")
    for w in eigenfrequencies:
        ax.axhline(w, color="w", ls="--", lw=0.8)
    for k in engine_orders:
        ax.plot(imap.speeds, k * imap.speeds, "w:", lw=0.7)
    if linear_resonance is not None:
        ax.plot([linear_resonance], [4 * linear_resonance], "ko", ms=6, label="linear 1B/EO4")
    if np.isfinite(imap.nfrc).any():
        i = int(np.nanargmax(imap.nfrc))
        ax.plot([imap.speeds[i]], [4 * imap.speeds[i]], "k^", ms=7, label="largest response")
    ax.set_ylim(imap.frequencies[0], imap.frequencies[-1])
    ax.set_xlabel("angular speed Omega (rad/s)")
    ax.set_ylabel("frequency (rad/s)")
    ax.set_title(title)
    ax.legend(loc="upper left", fontsize=8)
    return _save(fig, path)


def plot_nfrc(curves: dict, path: str | Path, linear_resonance: float | None = None,
              paper: dict | None = None) -> Path:
    """Fig. 7/11/12 analogue: max |u_LE,r| over the last revolution vs speed, one line (or markers) per curve.
    curves: {label: (speeds, amplitudes (m), style)}."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    for k, (label, (speeds, amp, style)) in enumerate(curves.items()):
        speeds, amp = np.asarray(speeds, float), np.asarray(amp, float)
        ax.plot(speeds, amp * 1e3, style, label=label, ms=4, color=f"C{k}")
        lost = ~np.isfinite(amp)
        if lost.any():                             # diverged runs: a gap in the curve and a cross on the axis
            ax.plot(speeds[lost], np.zeros(lost.sum()), "x", color=f"C{k}", ms=7, label=f"{label}: diverged")
    if linear_resonance is not None:
        ax.axvline(linear_resonance, color="k", ls=":", lw=0.8, label=f"linear 1B/EO4 {linear_resonance:.0f} rad/s")
    for label, speed in (paper or {}).items():
        ax.axvline(speed, color="0.6", ls="--", lw=0.8)
        ax.text(speed, ax.get_ylim()[1] * 0.95, label, rotation=90, va="top", ha="right", fontsize=7, color="0.4")
    ax.set_xlabel("angular speed Omega (rad/s)")
    ax.set_ylabel("max |u_LE,r| over the last revolution (mm)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    return _save(fig, path)


def plot_periodic_nfrc(branch, path: str | Path, map_curve: tuple | None = None,
                       linear_resonance: float | None = None, title: str = "", continued: dict | None = None) -> Path:
    """The periodic orbits' NFRC over the map's (#72): node LE's amplitude against the speed, stable orbits solid,
    unstable dashed, the stability changes marked by kind (fold, period doubling, Neimark-Sacker); below, the
    largest Floquet multiplier's modulus. ``branch``: a ``studies.periodic_map.PeriodicBranch``; ``map_curve``:
    (speeds, amplitudes (m), label) of the map's runs from rest; ``continued``: {label: (speeds, amplitudes (m))}
    of the sequential continuation's branches."""
    plt = _pyplot()
    fig, (ax, bx) = plt.subplots(2, 1, figsize=(7.5, 6.0), sharex=True, gridspec_kw={"height_ratios": [3, 1.3]})
    if map_curve is not None:
        speeds, amp, label = map_curve
        ax.plot(speeds, np.asarray(amp, float) * 1e3, "o", ms=3.5, color="0.55", label=label)
    for (label, (speeds, amp)), marker in zip((continued or {}).items(), "+x"):
        ax.plot(speeds, np.asarray(amp, float) * 1e3, marker, ms=5, color="0.25", label=label)
    w, a, stable = branch.speeds, branch.amplitude * 1e3, np.asarray(branch.stable, bool)
    for k in range(len(w) - 1):                   # each segment as its end points say: both stable -> solid
        solid = stable[k] and stable[k + 1]
        ax.plot(w[k:k + 2], a[k:k + 2], "-" if solid else "--", color="C0", lw=1.6 if solid else 1.1)
    ax.plot([], [], "-", color="C0", label="periodic orbits, stable")
    ax.plot([], [], "--", color="C0", label="periodic orbits, unstable")
    markers = {"fold": ("^", "C3"), "period doubling": ("s", "C2"), "Neimark-Sacker": ("D", "C1")}
    for kind, (m, c) in markers.items():
        at = [b["index"] for b in branch.bifurcations if b["kind"] == kind]
        if at:
            ax.plot(w[at], a[at], m, color=c, ms=6, label=kind)
            bx.plot(w[at], np.asarray(branch.multiplier)[at], m, color=c, ms=5)
    if linear_resonance is not None:
        ax.axvline(linear_resonance, color="k", ls=":", lw=0.8, label=f"linear 1B/EO4 {linear_resonance:.0f} rad/s")
    ax.set_ylabel("max |u_LE,n| (mm)")
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    bx.plot(w, branch.multiplier, ".-", color="C0", ms=3, lw=0.8)
    bx.axhline(1.0, color="k", lw=0.8)
    bx.set_ylabel("largest |multiplier|")
    bx.set_xlabel("angular speed Omega (rad/s)")
    bx.grid(alpha=0.3)
    return _save(fig, path)


def _engine_order_lines(ax, W: np.ndarray, orders, top: float, ls: str) -> None:
    """The engine-order lines omega = e Omega over the speeds W, each labelled where it leaves the chart."""
    for e in orders:
        ax.plot(W, e * W, color="0.6", lw=0.8, ls=ls)
        end = min(W[-1], top / e)
        ax.text(end, e * end, f"EO{e}", fontsize=7, color="0.4", ha="right", va="bottom")


def _crossings_and_axes(ax, crossings, name, W: np.ndarray, top: float, ylabel: str, title: str) -> None:
    """A Campbell diagram's crossings marked and labelled (``name(crossing)``/EO, speed), its limits and labels."""
    for c in crossings:
        ax.plot(c["speed"], c["frequency"], "kx", ms=6)
        ax.annotate(f"{name(c)}/EO{c['order']} {c['speed']:.0f}", (c["speed"], c["frequency"]), fontsize=6,
                    xytext=(3, -9), textcoords="offset points")
    ax.set_ylim(0, top)
    ax.set_xlim(W[0], W[-1])
    ax.set_xlabel("angular speed Omega (rad/s)")
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=9)


def plot_campbell(result, orders, path: str | Path, title: str = "", peaks: dict | None = None) -> Path:
    """The Campbell diagram (#73): each followed mode's frequency against the speed (rad/s both), the engine-order
    lines omega = e Omega, and the crossings marked and labelled (mode/EO, speed). ``result``: a
    ``studies.campbell.CampbellResult``; ``peaks``: {label: (speed, frequency)} drawn over it (a map's largest
    response, the engine-order point of a contact-stiffened resonance)."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7.5, 5.5))
    W = np.asarray(result.speeds, float)
    top = float(np.max(result.omega)) * 1.08
    _engine_order_lines(ax, W, orders, top, "--")
    for k, label in enumerate(result.labels):
        ax.plot(W, result.omega[:, k], "-o", ms=3, lw=1.4, label=label)
    for (label, (speed, frequency)), marker in zip((peaks or {}).items(), "sD^vP*"):
        if np.isfinite(speed):
            ax.plot(speed, frequency, marker, ms=7, mfc="none", mew=1.4, label=f"largest response: {label}")
    _crossings_and_axes(ax, result.crossings, lambda c: c["label"], W, top, "frequency omega (rad/s)", title)
    ax.legend(fontsize=7, loc="upper left")
    ax.grid(alpha=0.3)
    return _save(fig, path)


def plot_disk_campbell(result, orders, path: str | Path, title: str = "") -> Path:
    """The bladed disk's Campbell diagram (#73): each nodal-diameter family's modes against the speed (coloured by
    the index k; with Coriolis the forward waves solid and the backward dashed), the engine-order lines, and each
    crossing of an order with the family it excites marked (k/EO, speed). ``result``: a
    ``studies.disk_campbell.DiskCampbellResult``."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7.5, 5.5))
    W = np.asarray(result.speeds, float)
    top = float(np.max(result.omega)) * 1.08
    cmap = plt.get_cmap("viridis")
    half = max(result.n_sectors // 2, 1)
    _engine_order_lines(ax, W, orders, top, ":")
    for f, k in enumerate(result.families):
        colour = cmap(k / half)
        if result.forward is None:
            ax.plot(W, result.omega[:, f], "-", color=colour, lw=1.0)
        else:
            ax.plot(W, result.forward[:, f], "-", color=colour, lw=1.0)
            ax.plot(W, result.backward[:, f], "--", color=colour, lw=1.0)
    if result.forward is not None:
        ax.plot([], [], "k-", lw=1.0, label="forward wave")
        ax.plot([], [], "k--", lw=1.0, label="backward wave")
        ax.legend(fontsize=7, loc="upper left")
    bar = fig.colorbar(plt.cm.ScalarMappable(cmap=cmap, norm=plt.Normalize(0, half)), ax=ax, pad=0.02)
    bar.set_label("nodal diameter k", fontsize=8)
    _crossings_and_axes(ax, result.crossings, lambda c: f"k{c['family']}", W, top,
                        "frequency omega (rad/s), turning frame", title)
    ax.grid(alpha=0.3)
    return _save(fig, path)


def plot_interference(result, path: str | Path, title: str = "") -> Path:
    """The interference (ZZENF) diagram (#73): at one speed, each mode's frequency against the nodal diameter k
    (one line per mode number; with Coriolis the forward and backward waves), and the engine orders' zig-zag: order
    e at its excited index (e aliased by the N sectors) and frequency e Omega, consecutive orders joined; each order
    labelled with its direction. ``result``: a ``studies.disk_campbell.DiskCampbellResult``."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7.5, 5.0))
    zz = result.zzenf
    k = np.asarray(result.families)
    omega = np.asarray(zz["omega"])
    for j in range(omega.shape[1]):
        if "forward" in zz:
            ax.plot(k, np.asarray(zz["forward"])[:, j], "-o", ms=3, lw=1.0, color=f"C{j}",
                    label=f"mode {j + 1} forward")
            ax.plot(k, np.asarray(zz["backward"])[:, j], "--s", ms=3, lw=1.0, color=f"C{j}",
                    label=f"mode {j + 1} backward")
        else:
            ax.plot(k, omega[:, j], "-o", ms=3, lw=1.2, color=f"C{j}", label=f"mode {j + 1}")
    rows = sorted(zz["orders"], key=lambda r: r["order"])
    ax.plot([r["index"] for r in rows], [r["frequency"] for r in rows], "k-", lw=0.8)
    for r in rows:
        ax.plot(r["index"], r["frequency"], "kD", ms=4)
        ax.annotate(f"EO{r['order']}" + {"backward": " b", "forward": " f"}.get(r["direction"], ""),
                    (r["index"], r["frequency"]), fontsize=6, xytext=(3, 3), textcoords="offset points")
    top = max(float(np.nanmax(omega)), max(r["frequency"] for r in rows)) * 1.08
    ax.set_ylim(0, top)
    ax.set_xlim(-0.5, result.n_sectors // 2 + 0.5)
    ax.xaxis.get_major_locator().set_params(integer=True)
    ax.set_xlabel("nodal diameter k")
    ax.set_ylabel("frequency omega (rad/s), turning frame")
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=7, loc="lower right")
    ax.grid(alpha=0.3)
    return _save(fig, path)


def plot_curves(x: np.ndarray, series: dict, path: str | Path, title: str = "", xlabel: str = "",
                ylabel: str = "", logy: bool = False) -> Path:
    """Curves y(x), one per entry of ``series`` ({label: (len(x),) values}); a candidate's curves share a line style
    when labels share their text before ', mode' (the colour is the mode)."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7.5, 4.8))
    styles, groups = ["-", "--", ":", "-."], []
    for label, y in series.items():
        group = label.split(", mode")[0]
        if group not in groups:
            groups.append(group)
        mode = label.split(", mode")[-1].strip() if ", mode" in label else ""
        colour = f"C{int(mode) - 1}" if mode.isdigit() else None
        ax.plot(x, y, styles[groups.index(group) % len(styles)], color=colour, marker="o", ms=3, lw=1.0,
                label=label)
    if logy:
        ax.set_yscale("log")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=6, loc="best")
    ax.grid(alpha=0.3, which="both")
    return _save(fig, path)


def plot_time_history(t: np.ndarray, series: dict, path: str | Path, title: str = "",
                      ylabel: str = "radial displacement (mm)") -> Path:
    """Displacement histories (mm) vs time (ms). series: {label: values (m)}."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(8, 3.6))
    for label, values in series.items():
        ax.plot(t * 1e3, np.asarray(values) * 1e3, lw=0.7, label=label)
    ax.set_xlabel("time (ms)")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    return _save(fig, path)


def plot_speed_accuracy(rows: list, path: str | Path, title: str = "", cost_label: str = "cost (s)",
                        tolerances: tuple = (), floor: float | None = None,
                        reference: tuple | None = None) -> Path:
    """Error against cost on log-log axes: rows of (label, cost, error (relative)); the Pareto-optimal models
    (``pareto.pareto_front``) are joined and labelled, the others drawn grey; ``tolerances`` as dotted
    lines; the scene's ``floor`` (the error below which it cannot tell models apart) shaded below a dashed line;
    ``reference`` = (label, cost): the reference's cost as a vertical line (a full-order reference, whose error is 0 by
    construction). A run that diverged (error inf) is drawn on the top edge with a cross."""
    from rotor37_rom.pareto import pareto_front

    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7.2, 4.8))
    labels = [r[0] for r in rows]
    cost = np.array([r[1] for r in rows], float)
    err = np.array([r[2] for r in rows], float)
    front = pareto_front(cost, err)
    finite = np.isfinite(err)
    top = 2 * np.nanmax(np.where(finite, err, np.nan)) if finite.any() else 1.0
    ax.loglog(cost[finite & ~front], np.maximum(err[finite & ~front], 1e-16), "o", color="0.6", label="dominated")
    if (~finite).any():
        ax.loglog(cost[~finite], np.full((~finite).sum(), top), "x", color="C3", ms=9, label="diverged")
    order = np.flatnonzero(front)[np.argsort(cost[front])]
    ax.loglog(cost[order], np.maximum(err[order], 1e-16), "o-", color="C0", label="Pareto-optimal")
    # labels that would overlap (e.g. models at a scene's floor) are stacked, not drawn over each other: a label
    # spans about 0.01 of the axes' width per character from its point, 0.05 of the height
    y_at = np.maximum(np.where(finite, err, top), 1e-16)
    lx, ly = np.log10(np.maximum(cost, 1e-300)), np.log10(y_at)
    fx = (lx - lx.min()) / max(np.ptp(lx), 1e-12) * 0.9          # about where the points sit in the axes
    fy = (ly - ly.min()) / max(np.ptp(ly), 1e-12) * 0.9
    placed = []                                                    # (x0, x1, y, level)
    for i in np.argsort(cost, kind="stable"):
        x0, x1 = fx[i], fx[i] + 0.0098 * len(labels[i])
        taken = {lv for a, b, y, lv in placed if a < x1 and x0 < b and abs(y - fy[i]) < 0.05}
        level = min(set(range(len(rows) + 1)) - taken)
        placed.append((x0, x1, fy[i], level))
        ax.annotate(labels[i], (cost[i], y_at[i]), fontsize=7, xytext=(4, 3 + 9 * level), textcoords="offset points",
                    color="k" if front[i] or not finite[i] else "0.45")
    for tol in tolerances:
        ax.axhline(tol, color="k", ls=":", lw=0.7)
        ax.annotate(f"{100 * tol:g} %", (ax.get_xlim()[0], tol), fontsize=7, xytext=(2, 2), textcoords="offset points")
    if floor and np.isfinite(floor):
        ax.axhline(floor, color="C1", ls="--", lw=0.9, label="the scene's floor")
        ax.axhspan(ax.get_ylim()[0], floor, color="C1", alpha=0.08)
    if reference is not None:
        ax.axvline(reference[1], color="C2", ls="--", lw=0.9, label=reference[0])
    ax.set_xlabel(cost_label)
    ax.set_ylabel("relative error")
    ax.set_title(title, fontsize=9)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7, loc="lower left")
    return _save(fig, path)


def plot_indicator_vs_rmd(rows: list, path: str | Path, title: str = "") -> Path:
    """Accuracy indicator (max relative error) vs the number of modal derivatives. rows: (r_md, error)."""
    plt = _pyplot()
    rows = sorted(rows)
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.semilogy([r for r, _ in rows], [max(e, 1e-16) for _, e in rows], "o-")
    ax.axhline(0.1, color="k", ls=":", lw=0.8, label="10 %")
    ax.set_xlabel("r_MD")
    ax.set_ylabel("max relative error")
    ax.set_title(title)
    ax.grid(alpha=0.3, which="both")
    ax.legend()
    return _save(fig, path)


def plot_disk_indicator(panels: dict, path: str | Path, paper: dict | None = None) -> Path:
    """The disk's performance indicator I against r_MD (Figs. 17, 18, 20-22 analogues), one panel per title in
    ``panels``: {title: {series label: [(r_md, I), ...]}} (a one-point series is a marker); ``paper``: {criterion:
    I} drawn as dotted levels on the last panel."""
    plt = _pyplot()
    fig, axes = plt.subplots(1, len(panels), figsize=(6.2 * len(panels), 4.4), squeeze=False)
    for ax, (title, series) in zip(axes[0], panels.items()):
        for k, (label, pts) in enumerate(series.items()):
            pts = sorted(pts)
            style = "o-" if len(pts) > 1 else "s"
            ax.plot([p[0] for p in pts], [p[1] for p in pts], style, color=f"C{k % 10}", ms=5, label=label)
        ax.set_xlabel("modal derivatives per sector r_MD")
        ax.set_ylabel("performance indicator I")
        ax.set_title(title, fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="lower right")
    for value in (paper or {}).values():
        axes[0][-1].axhline(value, color="0.5", ls=":", lw=0.8)
    if paper:
        axes[0][-1].text(0.02, 0.5, "dotted: the paper's " + ", ".join(f"{k} {v:g}" for k, v in paper.items()),
                         transform=axes[0][-1].transAxes, fontsize=7, color="0.3")
    return _save(fig, path)


def plot_error_histories(histories: dict, path: str | Path, title: str = "") -> Path:
    """The indicator's four criteria over time for several models: {label: row['histories'] of
    bench_disk_forced} (loaded node and tip nodes at every step, field and strain energy at the snapshots)."""
    plt = _pyplot()
    names = ("loaded node", "tip nodes", "field", "strain energy")
    fig, axes = plt.subplots(2, 2, figsize=(11, 6.4), sharex=True)
    for k, (label, h) in enumerate(histories.items()):
        for ax, name in zip(axes.ravel(), names):
            t = h["t_periods"] if len(h[name]) == len(h["t_periods"]) else h["snapshot_periods"]
            ax.plot(t, h[name], lw=0.8, color=f"C{k % 10}", label=label)
    for ax, name in zip(axes.ravel(), names):
        ax.set_title(name, fontsize=9)
        ax.set_ylabel("relative error")
        ax.grid(alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel("time (periods of the load)")
    axes[0][0].legend(fontsize=7)
    fig.suptitle(title, fontsize=10)
    return _save(fig, path)


def plot_safe_diagram(safe, path: str | Path, references: dict | None = None, title: str = "") -> Path:
    """Fig. 15 analogue: frequency (rad/s) against nodal diameter, one colour per family (1B, 1T, 2B, other
    blade-dominated modes, disk-dominated modes), with ``references`` {label: omega} drawn as horizontal lines (e.g.
    the clamped single blade's 1B/1T/2B). ``safe``: a ``fem.safe.SafeDiagram`` or its ``as_dict()``."""
    plt = _pyplot()
    d = safe.as_dict() if hasattr(safe, "as_dict") else safe
    k, omega, family = np.asarray(d["k"]), np.asarray(d["omega"]), np.asarray(d["family"])
    colors = {"1B": "C0", "1T": "C1", "2B": "C2"}
    fig, ax = plt.subplots(figsize=(8, 5))
    drawn = set()
    for label in [f for f in ("1B", "1T", "2B") if (family == f).any()]:
        curve = np.array([omega[i][np.flatnonzero(family[i] == label)[0]] if (family[i] == label).any() else np.nan
                          for i in range(len(k))])
        ax.plot(k, curve, "-o", color=colors[label], ms=4, label=f"{label} family")
        drawn.add(label)
    for i, kk in enumerate(k):
        for w, fam in zip(omega[i], family[i]):
            if fam in drawn:
                continue
            color, name, marker = (("C3", "disk-dominated", "s") if fam == "disk" else
                                   ("C4", "modes (not labelled: no blade volume)", "o")
                                   if str(fam).startswith("mode") else ("C7", "other blade modes", "^"))
            ax.plot(kk, w, marker, color=color, ms=5,
                    label=name if name not in ax.get_legend_handles_labels()[1] else None)
    for label, w in (references or {}).items():
        ax.axhline(w, color=colors.get(label.split()[-1], "k"), ls="--", lw=0.8, label=label)
    ax.set_xlabel("nodal diameter k")
    ax.set_ylabel("ω (rad/s)")
    ax.set_xticks(k[:: max(1, len(k) // 19)])
    ax.set_title(title or "SAFE diagram")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    return _save(fig, path)

