"""The turning bladed disk's Campbell and interference (ZZENF) diagrams (#73, demos/disk_campbell.py):
``run_disk_campbell(DiskCampbellConfig)``.

At each speed Omega the whole disk's centrifugal equilibrium is solved once on one sector, as a harmonic-index-0
field (``fem.centrifugal_state``: the load is the same on every sector), and every nodal-diameter family k of the
tangent there, K_T(u_c) - Omega^2 M_P, comes from the cyclic operators of that one matrix
(``fem.rotating_cyclic_operators``). With ``coriolis`` the turning frame's gyroscopic coupling is solved on each
family's modes (``CyclicOperators.reduced_operator`` of the Coriolis matrix: the real cos/sin copies of an index carry
both its travelling waves, which Coriolis splits): each double mode becomes a forward and a backward wave (moving with
and against the rotation in the turning frame), told apart by the phase of their cos and sin parts
(``model.campbell.travelling_direction``).

An engine order e fixed to the ground excites, through the sampling of the N sectors, the index k =
min(e mod N, N - e mod N), backward for e ≡ k (mod N) and forward for e ≡ -k (``model.campbell.excited_index``,
``excited_direction``). The Campbell diagram lists each family's crossings with the orders that excite it (on the
speed grid, omega^2 linear in Omega^2 across a bracket); the interference diagram (ZZENF) draws, at one speed, the
families' frequencies against k with the engine orders' zig-zag, and tabulates each order's index, direction and the
margin of the nearest mode.

Modes are followed across speeds within a family by the shape of a^2 + b^2 (``model.campbell.pair_envelope``: a
double mode's shape whatever the mix of its members), by MAC.
"""
from __future__ import annotations

import dataclasses
import numbers
import time
from pathlib import Path

import numpy as np

from rotor37_rom.checks import before_work
from rotor37_rom.model.campbell import (engine_order_crossings, excited_direction, excited_index, gyroscopic_modes,
                                        pair_envelope, track_modes, travelling_direction)
from rotor37_rom.npz import save_json

from .campbell import MAX_TURNING_SPEED, check_speeds_memory, check_sweep, iterate_crossing

__all__ = ["DiskCampbellConfig", "DiskCampbellResult", "run_disk_campbell", "DISK_SECTORS", "DISK_DOFS"]

DISK_SECTORS = 36                 # the rotor 37 bladed disk
#: DOF of the rotor 37 disk sector per mesh preset, rounded up (ci measured: 23,700; coarse 52,440 and paper
#: 111,333: docs/results-disk.md): what a speed's families hold
DISK_DOFS = {"ci": 23_800, "coarse": 52_500, "paper": 111_400}


@dataclasses.dataclass(frozen=True)
class DiskCampbellConfig:
    """What to compute.

    Attributes:
        preset: mesh preset of the rotor 37 disk sector: ci, coarse or paper.
        speeds: (start, stop, n): n speeds (2..``studies.campbell.MAX_SPEED_COUNT``, within this machine's memory)
            (rad/s) from start >= 0 to stop > start, at most ``studies.campbell.MAX_TURNING_SPEED``.
        families: harmonic indices (nodal diameters) drawn, each in 0 ... 18; empty: all.
        n_modes: modes per family (1..10).
        orders: engine orders (integers 1..200); each crosses the family it excites.
        zzenf_speed: the interference diagram's speed (rad/s, one of the grid's or any in 0 ...
            ``MAX_TURNING_SPEED``); None: the last speed.
        refine: each crossing iterated on the disk to this (rad/s, in (0, 100]; its family solved again at each
            estimate), or 0: interpolated on the grid only.
        coriolis: the turning frame's Coriolis coupling (forward and backward waves), on each family's modes.
        prestress: the centrifugal equilibrium's stiffening (False: spin softening alone).
        out: output folder (the charts and summary.json).
    """

    preset: str = "ci"
    speeds: tuple = (0.0, 2000.0, 5)
    families: tuple = ()
    n_modes: int = 3
    orders: tuple = (1, 2, 3, 4, 5, 6, 7, 8)
    zzenf_speed: float | None = None
    refine: float = 0.0
    coriolis: bool = False
    prestress: bool = True
    out: Path = Path("results/disk_campbell")

    def __post_init__(self):
        check_sweep(self, max_order=200)
        half = DISK_SECTORS // 2
        if any(not (isinstance(k, numbers.Real) and np.isfinite(k) and int(k) == k and 0 <= k <= half)
               for k in self.families):
            raise ValueError(f"--families must be integers in [0, {half}], got {list(self.families)}")
        if not (isinstance(self.n_modes, numbers.Integral) and 1 <= self.n_modes <= 10):
            raise ValueError(f"--modes must be in [1, 10], got {self.n_modes}")
        if self.zzenf_speed is not None and not (isinstance(self.zzenf_speed, numbers.Real)
                                                 and np.isfinite(self.zzenf_speed)
                                                 and 0 <= self.zzenf_speed <= MAX_TURNING_SPEED):
            raise ValueError(f"--zzenf-speed must be a speed in [0, {MAX_TURNING_SPEED:g}] rad/s (rotor 37's range), "
                             f"got {self.zzenf_speed}")
        object.__setattr__(self, "families", tuple(sorted({int(k) for k in self.families})) or tuple(range(half + 1)))
        # what the study keeps per speed: each family's mode shapes (a^2 + b^2 over the sector)
        dofs, shapes = DISK_DOFS[self.preset], len(self.families) * self.n_modes
        check_speeds_memory(self.speeds[2], 8.0 * dofs * shapes,
                            f"{dofs:,} DOF x {len(self.families)} families x {self.n_modes} modes a speed, "
                            f"{self.preset} disk sector")

    @property
    def speed_grid(self) -> np.ndarray:
        return np.linspace(*self.speeds)


@dataclasses.dataclass(frozen=True)
class DiskCampbellResult:
    """The diagrams.

    Attributes:
        speeds: (S,) rad/s; families: (F,) harmonic indices; n_sectors: N.
        omega: (S, F, m) rad/s without Coriolis, mode j of family f the j-th at the first speed.
        forward, backward: (S, F, m) rad/s with Coriolis (the waves moving with and against the rotation in the
            turning frame; equal to omega for k = 0 and N/2), None without.
        mac: (S,) the smallest MAC of a pairing between neighbouring speeds over the families (1 at the first).
        crossings: {'family', 'mode', 'order', 'direction', 'speed', 'frequency' (rad/s), 'bracket', 'refined'
            (iterations on the disk, 0 if interpolated)} by speed.
        zzenf: {'speed', 'omega' (F, m) (backward and forward too with Coriolis), 'orders': [{'order', 'index',
            'direction', 'frequency', 'nearest_mode', 'margin' (omega_nearest / (e Omega) - 1)}]}.
        wall_s: wall time (s); files: what was written.
    """

    speeds: np.ndarray
    families: tuple
    n_sectors: int
    omega: np.ndarray
    forward: np.ndarray | None
    backward: np.ndarray | None
    mac: np.ndarray
    crossings: list
    zzenf: dict
    wall_s: float
    files: list = dataclasses.field(default_factory=list)

    def branch(self, direction: str) -> np.ndarray:
        """The frequencies an excitation of this direction meets: backward, forward, or omega (standing, or no
        Coriolis)."""
        if self.forward is None or direction == "standing":
            return self.omega
        return self.forward if direction == "forward" else self.backward

    def summary(self) -> dict:
        out = {"speeds_rad_s": self.speeds.tolist(), "families": list(self.families), "n_sectors": self.n_sectors,
               "omega_rad_s": self.omega.tolist(), "mac_min": self.mac.tolist(), "crossings": self.crossings,
               "zzenf": self.zzenf, "wall_s": self.wall_s}
        if self.forward is not None:
            out.update(forward_rad_s=self.forward.tolist(), backward_rad_s=self.backward.tolist())
        return out


def run_disk_campbell(config: DiskCampbellConfig, sector=None) -> DiskCampbellResult:
    """The Campbell and interference diagrams of ``config`` (``sector``: a cyclic sector already built, else the
    preset's rotor 37 disk sector)."""
    before_work({"--out": config.out})                          # before any import of the FE adapter
    from rotor37_rom import fem

    t0 = time.perf_counter()
    name = f"rotor 37 bladed disk ({config.preset}" if sector is None else f"{sector.source} ("
    sector = sector if sector is not None else fem.create_disk_sector(preset=config.preset)
    N = sector.cyclic.n_sectors
    if max(config.families) > N // 2:
        raise ValueError(f"--families must be in [0, {N // 2}] for {N} sectors, got {list(config.families)}")
    ops = fem.create_svk_operators(sector)
    M = fem.assemble_mass(sector, ops)
    G = fem.assemble_coriolis(sector, ops) if config.coriolis else None      # one for every speed
    speeds = config.speed_grid
    solves = [_families(sector, ops, M, G, config, float(spin)) for spin in speeds]
    F, m = len(config.families), config.n_modes
    omega = np.empty((len(speeds), F, m))
    forward = np.empty_like(omega) if G is not None else None
    backward = np.empty_like(omega) if G is not None else None
    worst = np.ones(len(speeds))
    for f in range(F):
        w, order_mac = track_modes([s[f]["omega"] for s in solves], [s[f]["envelope"] for s in solves])
        omega[:, f] = w
        worst = np.minimum(worst, order_mac)
        if G is not None:                # the same pairing for the waves, by the modes' frequencies without Coriolis
            for i, s in enumerate(solves):
                order = [int(np.argmin(np.abs(s[f]["omega"] - x))) for x in w[i]]
                forward[i, f] = s[f]["forward"][order]
                backward[i, f] = s[f]["backward"][order]
    result = DiskCampbellResult(speeds, config.families, N, omega, forward, backward, worst, [], {}, 0.0)
    crossings = []
    for f, k in enumerate(config.families):
        for e in config.orders:
            if excited_index(e, N) != k:
                continue
            direction = excited_direction(e, N)
            for c in engine_order_crossings(speeds, result.branch(direction)[:, f], [e]):
                crossings.append({"family": int(k), **c, "mode": c["mode"] + 1, "direction": direction})
    if config.refine > 0:
        rest = omega[0] if speeds[0] == 0.0 else np.array(
            [s["omega"] for s in _families(sector, ops, M, None, config, 0.0)])
        for c in crossings:
            _refine(sector, ops, M, G, config, c, rest, solves, omega)
    else:
        for c in crossings:
            c["refined"] = 0
    crossings.sort(key=lambda c: c["speed"])
    zz_speed = float(speeds[-1] if config.zzenf_speed is None else config.zzenf_speed)
    if zz_speed in speeds:
        at = int(np.flatnonzero(speeds == zz_speed)[0])
        zz = {"omega": omega[at], "forward": None if G is None else forward[at],
              "backward": None if G is None else backward[at]}
    else:                                # a speed off the grid: solved there, modes in frequency order
        zz_solve = _families(sector, ops, M, G, config, zz_speed)
        zz = {name: (None if G is None and name != "omega" else np.array([s[name] for s in zz_solve]))
              for name in ("omega", "forward", "backward")}
    M.destroy()
    if G is not None:
        G.destroy()
    zzenf = _interference(zz, zz_speed, config, N)
    result = dataclasses.replace(result, crossings=crossings, zzenf=zzenf, wall_s=time.perf_counter() - t0)
    config.out.mkdir(parents=True, exist_ok=True)
    from rotor37_rom.viz.charts import plot_disk_campbell, plot_interference

    effects = ("prestressed, spin softened" if config.prestress else "spin softened, no prestress") + \
        (", Coriolis" if config.coriolis else ", no Coriolis")
    files = [plot_disk_campbell(result, config.orders, config.out / "campbell_disk.png",
                                f"{name}, {N} sectors): {effects}"),
             plot_interference(result, config.out / "zzenf.png",
                               f"interference diagram at {zz_speed:.0f} rad/s, {name}): {effects}")]
    save_json(config.out / "summary.json", result.summary(), indent=1)
    files.append(config.out / "summary.json")
    return dataclasses.replace(result, files=files)


def _refine(sector, ops, M, G, config: DiskCampbellConfig, crossing: dict, rest: np.ndarray, solves: list,
            omega: np.ndarray) -> None:
    """Iterate one crossing on the disk (``studies.campbell.iterate_crossing``: Southwell's coefficient measured at
    each estimate), solving its family alone; the mode found at each estimate by its shape (largest MAC of a^2 + b^2
    against the bracket's nearer speed's); updates ``crossing`` in place ('refined': iterations, < 0 if it did not
    settle)."""
    from rotor37_rom.model.campbell import mac

    f = config.families.index(crossing["family"])
    j = crossing["mode"] - 1
    s0, s1 = crossing["bracket"]
    grid = config.speed_grid
    near = s0 if abs(crossing["speed"] - grid[s0]) <= abs(crossing["speed"] - grid[s1]) else s1
    column = int(np.argmin(np.abs(solves[near][f]["omega"] - omega[near, f, j])))
    reference = solves[near][f]["envelope"][:, [column]]
    branch = {"forward": "forward", "backward": "backward"}.get(crossing["direction"], "omega")

    def modes(spin):
        entry = _families(sector, ops, M, G, config, spin, [crossing["family"]])[0]
        return entry.get(branch, entry["omega"]), entry["envelope"]

    W, steps = iterate_crossing(modes, crossing["order"], crossing["speed"], rest[f, j],
                                lambda w, V: int(np.argmax(mac(reference, V)[0])), config.refine)
    crossing.update(speed=W, frequency=crossing["order"] * W, refined=steps)


def _gather(sector, values: np.ndarray) -> np.ndarray:
    """A field's owned entries from every rank, in rank order (the whole sector's vector on every rank)."""
    n = sector.V.dofmap.index_map.size_local * sector.V.dofmap.index_map_bs
    return np.concatenate(sector.comm.allgather(np.asarray(values[:n])))


def _families(sector, ops, M, G, config: DiskCampbellConfig, spin: float, families=None) -> list[dict]:
    """At ``spin``, per family (``families``, default the config's): {'omega' (m,), 'envelope' (n, m)} and with
    Coriolis {'forward', 'backward'} (m,)."""
    from rotor37_rom import fem

    cyclic, _ = fem.rotating_cyclic_operators(sector, spin, ops, M, prestress=config.prestress)
    m, out = config.n_modes, []
    try:
        for k in (config.families if families is None else families):
            modes = cyclic.modes(k, m)
            w, idx = modes.distinct()
            a = [_gather(sector, modes.a[i].x.array) for i in range(len(modes.a))]
            b = None if modes.b[0] is None else [_gather(sector, modes.b[i].x.array) for i in range(len(modes.b))]
            entry = {"omega": w[:m], "envelope": np.column_stack(
                [pair_envelope(a[i], None if b is None else b[i]) for i in idx[:m]])}
            if G is not None:
                entry.update(_waves(cyclic, G, modes, a, b, idx[:m], spin))
            out.append(entry)
    finally:
        cyclic.K.destroy()
        cyclic.destroy()
    return out


def _waves(cyclic, G, modes, a: list, b: list | None, idx: list, spin: float) -> dict:
    """Forward and backward frequencies (m,) of the family's double modes under Coriolis: the gyroscopic problem on
    all of its computed modes; each wave assigned to the double mode whose pair carries most of it, the pair's two
    waves named by their directions (``travelling_direction``: the larger forward). At rest, and for k = 0 and N/2
    (one copy), both are the frequencies without a split."""
    W = modes.omega
    if spin == 0.0:
        return {"forward": W[idx], "backward": W[idx]}
    Gr = cyclic.reduced_operator(G, modes) * spin
    freqs, Z = gyroscopic_modes(np.diag(W ** 2), np.eye(W.size), Gr)
    if b is None:
        return {"forward": freqs[:len(idx)], "backward": freqs[:len(idx)]}
    A, B = np.column_stack(a), np.column_stack(b)
    aa, ab, bb = A.T @ A, A.T @ B, B.T @ B
    waves: dict = {p: [] for p in range(len(idx))}
    for j in range(Z.shape[1]):
        weight = np.abs(Z[:, j]) ** 2
        pair = int(np.argmax([weight[i] + weight[i + 1] for i in idx]))
        if weight[idx[pair]] + weight[idx[pair] + 1] > 0.5:          # mostly this pair's (not another computed one)
            waves[pair].append((travelling_direction(Z[:, j], aa, ab, bb), freqs[j]))
    forward, backward = np.full(len(idx), np.nan), np.full(len(idx), np.nan)
    for p, found in waves.items():
        if found:
            found.sort()
            backward[p], forward[p] = found[0][1], found[-1][1]
    return {"forward": forward, "backward": backward}


def _interference(zz: dict, speed: float, config: DiskCampbellConfig, N: int) -> dict:
    """The interference diagram's table: for each order, its index, direction, e Omega and the nearest mode of that
    family and direction (margin omega / (e Omega) - 1), where the family is computed."""
    rows = []
    for e in config.orders:
        k = excited_index(e, N)
        direction = excited_direction(e, N)
        row = {"order": int(e), "index": int(k), "direction": direction, "frequency": e * speed}
        if k in config.families and speed > 0:
            f = config.families.index(k)
            branch = zz["omega"] if zz["forward"] is None or direction == "standing" else zz[direction]
            j = int(np.nanargmin(np.abs(branch[f] - e * speed)))
            row.update(nearest_mode=j + 1, margin=float(branch[f][j] / (e * speed) - 1))
        rows.append(row)
    out = {"speed": speed, "omega": np.asarray(zz["omega"]).tolist(), "orders": rows}
    if zz["forward"] is not None:
        out.update(forward=np.asarray(zz["forward"]).tolist(), backward=np.asarray(zz["backward"]).tolist())
    return out
