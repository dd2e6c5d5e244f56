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
import numbers
import time
from pathlib import Path

import numpy as np

from rotor37_rom.checks import before_work, fits_in_memory
from rotor37_rom.geometry.blade import MESH_PRESETS
from rotor37_rom.model.campbell import engine_order_crossings, mac, track_modes
from rotor37_rom.npz import save_json

__all__ = ["CampbellConfig", "CampbellResult", "iterate_crossing", "run_campbell", "check_sweep",
           "MAX_TURNING_SPEED", "MAX_SPEED_COUNT", "BLADE_DOFS", "MAX_REFINE"]

#: rad/s: the fastest rotor 37 turns in this project's models (the Campbell diagrams, a turning map's model). Its
#: blade (maraging steel, sigma_Y = 1.38 GPa) at 3,000 rad/s (1.67 x its design speed 1,800 rad/s, ~760 m/s at the
#: tip) has its largest von Mises stress at 0.92 sigma_Y (the ci blade's centrifugal state: 1.27 GPa at its root;
#: 1.38 GPa is reached near 3,100 rad/s, 2.3 GPa at 4,000): beyond it the elastic St. Venant-Kirchhoff blade is
#: past its material's yield (and its burst), and Newton's centrifugal state ends in a RuntimeError further up.
MAX_TURNING_SPEED = 3000.0
#: speeds of a Campbell study at most: each is a full-order Newton and eigensolve (seconds for the blade, a minute
#: for the disk at ci); 1,000 speeds are 2 rad/s apart over 0-2,000 rad/s, finer than any diagram is read
MAX_SPEED_COUNT = 1000
#: rad/s: the coarsest refinement of a crossing (a tolerance above it refines nothing the grid does not give)
MAX_REFINE = 100.0
#: DOF of the rotor 37 blade per mesh preset, rounded up over the parametric and the Table IV blades
#: (docs/results-blade.md: 13,836-14,013, 33,474-33,489, 59,202-59,247): what a speed's mode shapes hold
BLADE_DOFS = {"ci": 14_100, "coarse": 33_500, "paper": 59_300}


@dataclasses.dataclass(frozen=True)
class CampbellConfig:
    """What to compute.

    Attributes:
        preset: mesh preset of the rotor 37 blade: ci, coarse or paper.
        speeds: (start, stop, n): n speeds (2..``MAX_SPEED_COUNT``, within this machine's memory) (rad/s) from
            start >= 0 to stop > start, at most ``MAX_TURNING_SPEED``.
        n_modes: modes followed (1..20).
        orders: engine orders drawn and crossed (integers 1..100).
        refine: each crossing iterated on the blade to this (rad/s, in (0, ``MAX_REFINE``]), or 0: interpolated on
            the grid only.
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
        if not (isinstance(self.n_modes, numbers.Integral) and 1 <= self.n_modes <= 20):
            raise ValueError(f"--modes must be in [1, 20], got {self.n_modes}")
        # what the study keeps per speed: the shapes of its modes (with Coriolis the 3 n_modes computed)
        columns = self.n_modes * (3 if self.coriolis else 1)
        check_speeds_memory(self.speeds[2], 8.0 * BLADE_DOFS[self.preset] * columns,
                            f"{BLADE_DOFS[self.preset]:,} DOF x {columns} mode shapes a speed, {self.preset} blade")

    @property
    def speed_grid(self) -> np.ndarray:
        return np.linspace(*self.speeds)


def _real(value) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool) and bool(np.isfinite(value))


def check_sweep(config, max_order: int) -> None:
    """The options a Campbell study shares, checked and normalised in place on a frozen ``config``: its preset, its
    speeds (start, stop, n: finite, 0 <= start < stop <= ``MAX_TURNING_SPEED``, n an integer in
    2..``MAX_SPEED_COUNT``), its engine orders (1..max_order), its refine tolerance (0..``MAX_REFINE``), its output
    folder (a path, not empty)."""
    if config.preset not in MESH_PRESETS:
        raise ValueError(f"--preset must be one of {', '.join(MESH_PRESETS)}, got {config.preset!r}")
    if not (isinstance(config.speeds, (tuple, list, np.ndarray)) and len(config.speeds) == 3):
        raise ValueError(f"--speeds START STOP N: give three numbers, got {config.speeds!r}")
    start, stop, n = config.speeds
    if not (_real(start) and _real(stop) and 0 <= start < stop <= MAX_TURNING_SPEED):
        raise ValueError(f"--speeds START STOP N: need finite 0 <= START < STOP <= {MAX_TURNING_SPEED:g} rad/s "
                         f"(rotor 37's range: its blade yields above), got {start:g} {stop:g}")
    if not (_real(n) and float(n).is_integer() and 2 <= n <= MAX_SPEED_COUNT):
        raise ValueError(f"--speeds START STOP N: N must be an integer in 2..{MAX_SPEED_COUNT}, got {n:g}")
    if not config.orders or any(not (_real(e) and float(e).is_integer() and 1 <= e <= max_order)
                                for e in config.orders):
        raise ValueError(f"--orders must be integers in [1, {max_order}], got {list(config.orders)}")
    if not (_real(config.refine) and 0 <= config.refine <= MAX_REFINE):
        raise ValueError(f"--refine must be in [0, {MAX_REFINE:g}] rad/s (0: no refinement), got {config.refine}")
    if not isinstance(config.out, (str, Path)) or not str(config.out).strip():
        raise ValueError(f"--out must be a folder's path, got {config.out!r}")
    object.__setattr__(config, "speeds", (float(start), float(stop), int(n)))
    object.__setattr__(config, "orders", tuple(sorted({int(e) for e in config.orders})))
    object.__setattr__(config, "out", Path(config.out))


def check_speeds_memory(n_speeds: int, per_speed: float, what: str) -> None:
    """Refused naming --speeds where ``n_speeds`` speeds of ``per_speed`` bytes each (``what``) would not fit in
    this machine's memory (``checks.fits_in_memory``): what a study keeps of every speed until its diagram."""
    fits_in_memory("--speeds", n_speeds * per_speed, f"{n_speeds} speeds x {per_speed / 2**20:.3g} MiB: {what}",
                   hint="fewer speeds or modes")


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
    before_work({"--out": config.out})                          # before any import of the FE adapter
    from rotor37_rom import fem
    from rotor37_rom.model.modes import classify_blade_modes

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
