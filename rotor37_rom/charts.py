"""Matplotlib charts for the studies (imported lazily; Agg backend, files only)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["plot_clearance_consumption", "plot_md_weights"]


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_clearance_consumption(curves, path: str | Path, reference: str = "FOM nonlinear") -> Path:
    """Fig. 9/10 analogue: Delta (mm) vs delta for every curve, and the relative error to the reference."""
    from rotor37_rom.clearance import relative_error

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
