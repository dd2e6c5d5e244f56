"""The blade's Campbell diagram (#73, demos/campbell.py): ``run_campbell(CampbellConfig)``.

At each speed Omega the blade turns about the machine axis e_z: its centrifugal equilibrium (nonlinear SVK, Newton
on the exact tangent, ``fem.solve_static(spin=...)``) and the modes of the tangent there, K_T(u_c) - Omega^2 M_P
(geometric stiffening and spin softening), against the mass (``fem.rotating_modes``); with ``coriolis``, the
gyroscopic coupling of the turning frame too, on 3 n_modes of those modes (``fem.reduced_coriolis``). The modes are
followed across speeds by their shapes (``model.campbell.track_modes``) and named at rest from the tip's motion (1B,
1T, 2B, ...). Each crossing with an engine order e (omega_k = e Omega) is bracketed on the speed grid, interpolated
with omega^2 linear in Omega^2, then, with ``refine`` > 0, iterated on the blade itself:
Omega = omega_k,0 / sqrt(e^2 - S_k(Omega)) with Southwell's coefficient S_k(Omega) = (omega_k(Omega)^2 -
omega_k,0^2) / Omega^2 measured at the current estimate, until it moves by less than ``refine`` rad/s.
"""
from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import numpy as np

from rotor37_rom.checks import before_work
from rotor37_rom.geometry.blade import MESH_PRESETS
from rotor37_rom.model.campbell import engine_order_crossings, mac, track_modes
from rotor37_rom.npz import save_json

__all__ = ["CampbellConfig", "CampbellResult", "iterate_crossing", "run_campbell", "check_sweep"]


@dataclasses.dataclass(frozen=True)
class CampbellConfig:
    """What to compute.

    Attributes:
        preset: mesh preset of the rotor 37 blade: ci, coarse or paper.
        speeds: (start, stop, n): n >= 2 speeds (rad/s) from start >= 0 to stop > start.
        n_modes: modes followed (1..20).
        orders: engine orders drawn and crossed (integers 1..100).
        refine: each crossing iterated on the blade to this (rad/s, > 0), or 0: interpolated on the grid only.
        coriolis: include the Coriolis force (the turning frame's gyroscopic coupling), solved on 3 n_modes modes
            of the problem without it (``fem.reduced_coriolis``, ``model.campbell.gyroscopic_frequencies``).
        out: output folder (the chart and summary.json).
    """

    preset: str = "ci"
    speeds: tuple = (0.0, 2000.0, 11)
    n_modes: int = 4
    orders: tuple = (1, 2, 3, 4, 5, 6, 7, 8)
    refine: float = 0.01
    coriolis: bool = False
    out: Path = Path("results/campbell")

    def __post_init__(self):
        check_sweep(self, max_order=100)
        if not 1 <= self.n_modes <= 20:
            raise ValueError(f"--modes must be in [1, 20], got {self.n_modes}")

    @property
    def speed_grid(self) -> np.ndarray:
        return np.linspace(*self.speeds)


def check_sweep(config, max_order: int) -> None:
    """The options a Campbell study shares, checked and normalised in place on a frozen ``config``: its preset, its
    speeds (start, stop, n), its engine orders (1..max_order), its refine tolerance, its output folder."""
    if config.preset not in MESH_PRESETS:
        raise ValueError(f"--preset must be one of {', '.join(MESH_PRESETS)}, got {config.preset!r}")
    start, stop, n = config.speeds
    if not (np.isfinite(start) and np.isfinite(stop) and start >= 0 and stop > start):
        raise ValueError(f"--speeds START STOP N: need 0 <= START < STOP (rad/s), got {start:g} {stop:g}")
    if int(n) != n or n < 2:
        raise ValueError(f"--speeds START STOP N: N must be an integer >= 2, got {n}")
    if not config.orders or any(int(e) != e or not 1 <= e <= max_order for e in config.orders):
        raise ValueError(f"--orders must be integers in [1, {max_order}], got {list(config.orders)}")
    if not (np.isfinite(config.refine) and config.refine >= 0):
        raise ValueError(f"--refine must be >= 0 rad/s (0: no refinement), got {config.refine}")
    object.__setattr__(config, "speeds", (float(start), float(stop), int(n)))
    object.__setattr__(config, "orders", tuple(sorted({int(e) for e in config.orders})))
    object.__setattr__(config, "out", Path(config.out))


@dataclasses.dataclass(frozen=True)
class CampbellResult:
    """The diagram.

    Attributes:
        speeds: (n_speeds,) rad/s; omega: (n_speeds, n_modes) rad/s, column k the mode k-th at the first speed.
        labels: each column's name at the first speed (1B, 1T, 2B, ...).
        mac: the smallest MAC of a pairing between neighbouring speeds (1 at the first): a mode that left the
            computed set, or two that swapped shapes, shows as a low value.
        crossings: {'mode', 'label', 'order', 'speed', 'frequency' (rad/s), 'refined' (iterations, 0 if not),
            'bracket'} by speed.
        wall_s: wall time (s); files: what was written.
    """

    speeds: np.ndarray
    omega: np.ndarray
    labels: list
    mac: np.ndarray
    crossings: list
    wall_s: float
    files: list = dataclasses.field(default_factory=list)

    def summary(self) -> dict:
        return {"speeds_rad_s": self.speeds.tolist(), "omega_rad_s": self.omega.tolist(), "labels": self.labels,
                "mac_min": self.mac.tolist(), "crossings": self.crossings, "wall_s": self.wall_s}


def run_campbell(config: CampbellConfig, sector=None) -> CampbellResult:
    """The Campbell diagram of ``config`` (``sector``: a blade sector already built, else the preset's)."""
    from rotor37_rom import fem
    from rotor37_rom.model.modes import classify_blade_modes

    before_work({"--out": config.out})
    t0 = time.perf_counter()
    sector = sector if sector is not None else fem.create_blade_sector(preset=config.preset)
    ops = fem.create_svk_operators(sector)
    M = fem.assemble_mass(sector, ops)
    G = fem.assemble_coriolis(sector, ops) if config.coriolis else None      # one for every speed
    speeds = config.speed_grid
    freqs, shapes = [], []
    for spin in speeds:
        w, V = _modes(sector, ops, M, G, config, float(spin))
        freqs.append(w)
        shapes.append(V)
    omega, worst = track_modes(freqs, shapes)
    tips = np.stack([shapes[0][sector.tip_dofs.ravel(), k].reshape(-1, 3) for k in range(config.n_modes)])
    labels = classify_blade_modes(tips, sector.tip_nodes)
    crossings = engine_order_crossings(speeds, omega, config.orders)
    rest = omega[0] if speeds[0] == 0.0 else _modes(sector, ops, M, G, config, 0.0)[0]
    for c in crossings:
        c["label"] = labels[c["mode"]]
        c["refined"] = 0
        if config.refine > 0:
            _refine(sector, ops, M, G, config, c, rest[c["mode"]], shapes, freqs, omega)
    M.destroy()
    if G is not None:
        G.destroy()
    result = CampbellResult(speeds, omega, labels, worst, crossings, time.perf_counter() - t0)
    config.out.mkdir(parents=True, exist_ok=True)
    from rotor37_rom.viz.charts import plot_campbell

    effects = "prestressed, spin softened, " + ("Coriolis" if config.coriolis else "no Coriolis")
    files = [plot_campbell(result, config.orders, config.out / "campbell.png",
                           f"rotor 37 blade ({config.preset}): {effects}")]
    save_json(config.out / "summary.json", result.summary(), indent=1)
    files.append(config.out / "summary.json")
    return dataclasses.replace(result, files=files)


def _modes(sector, ops, M, G, config: CampbellConfig, spin: float) -> tuple[np.ndarray, np.ndarray]:
    """(frequencies (n_modes,) rad/s, shapes (n_dofs, n_modes)) at ``spin``: the prestressed, spin-softened modes;
    with Coriolis, the gyroscopic frequencies on 3 n_modes of them, the lowest n_modes, beside the shapes without
    it (the Coriolis force of a blade moves its frequencies by little and keeps their order: the shapes follow
    the modes across speeds)."""
    from rotor37_rom import fem
    from rotor37_rom.model.campbell import gyroscopic_frequencies

    n = config.n_modes
    if not config.coriolis or spin == 0.0:
        return fem.rotating_modes(sector, spin, n, ops, M)
    w, V = fem.rotating_modes(sector, spin, 3 * n, ops, M)
    Gr = fem.reduced_coriolis(sector, V, ops, G)
    return gyroscopic_frequencies(np.diag(w**2), np.eye(len(w)), spin * Gr)[:n], V[:, :n]


def _refine(sector, ops, M, G, config: CampbellConfig, crossing: dict, omega0: float, shapes, freqs, omega) -> None:
    """Iterate one crossing on the blade (``iterate_crossing``), the mode found at each estimate by its shape (largest
    MAC against the bracket's nearer speed's shape); updates ``crossing`` in place."""
    k = crossing["mode"]
    s0, s1 = crossing["bracket"]
    grid = config.speed_grid
    near = s0 if abs(crossing["speed"] - grid[s0]) <= abs(crossing["speed"] - grid[s1]) else s1
    column = int(np.flatnonzero(np.isclose(freqs[near], omega[near, k]))[0])
    reference = shapes[near][:, [column]]
    W, steps = iterate_crossing(lambda spin: _modes(sector, ops, M, G, config, spin), crossing["order"],
                                crossing["speed"], omega0, lambda w, V: int(np.argmax(mac(reference, V)[0])),
                                config.refine)
    crossing.update(speed=W, frequency=crossing["order"] * W, refined=steps)


def iterate_crossing(modes, order: int, start: float, omega0: float, pick, tol: float = 0.01,
                     max_iter: int = 20) -> tuple[float, int]:
    """The speed where a mode meets engine order ``order``, iterated from ``start`` (rad/s): Omega = omega0 /
    sqrt(e^2 - S(Omega)) with Southwell's S(Omega) = (omega(Omega)^2 - omega0^2) / Omega^2 measured at the current
    estimate (omega0: the mode at rest), until it moves by less than ``tol``. ``modes(spin)`` -> (frequencies,
    shapes) of the turning structure; ``pick(frequencies, shapes)`` -> the index of the mode followed. Returns (speed,
    iterations), iterations -max_iter if it did not settle. The update contracts by about S' / (e^2 - S) a step (a
    few per cent on a blade), so the last step bounds the distance to the crossing."""
    W, e = float(start), int(order)
    for it in range(1, max_iter + 1):
        w, V = modes(W)
        S = (w[pick(w, V)] ** 2 - omega0**2) / W**2 if W > 0 else 0.0
        new = float(omega0 / np.sqrt(e * e - S)) if e * e > S else W
        done = abs(new - W) < tol
        W = new
        if done:
            return W, it
    return W, -max_iter
