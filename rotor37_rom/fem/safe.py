"""SAFE diagram of a bladed-disk sector (frequency against nodal diameter, the paper's Fig. 15): the lowest modes of
every harmonic index, each told apart as blade-dominated (1B, 1T, 2B, ... from the tip motion) or disk-dominated
(from the share of strain energy in the blade).

Part of the dolfinx adapter (``rotor37_rom.fem``).
"""
from __future__ import annotations

import dataclasses
import time

import numpy as np
import ufl
from dolfinx import fem

from rotor37_rom import forms
from rotor37_rom.disk.symmetry import harmonic_indices
from rotor37_rom.model.modes import classify_blade_modes

from .cyclic import CyclicOperators
from .operators import (JIT_PARAMS, SvkOperators, _assemble_matrix, assemble_mass, assemble_stiffness,
                        create_svk_operators, gather_dof_values)
from .sector import Sector

__all__ = ["SafeDiagram", "compute_safe_diagram", "group_stiffness", "BLADE_SHARE_DOMINATED"]

BLADE_SHARE_DOMINATED = 0.5      # a mode with at least this share of its strain energy in the blade is blade-dominated


def group_stiffness(sector: Sector, group: str):
    """The linear stiffness of the cells of a named volume group only (no clamp rows: for energies)."""
    if group not in sector.groups:
        raise ValueError(f"group {group!r} not in this sector; it has {sorted(sector.groups)}")
    lmbda, mu = sector.material.lame
    dx = ufl.Measure("dx", domain=sector.mesh, subdomain_data=sector.cell_tags)(sector.groups[group])
    v, du = ufl.TestFunction(sector.V), ufl.TrialFunction(sector.V)
    return _assemble_matrix(fem.form(forms.linear_stiffness(v, du, lmbda, mu, dx), jit_params=JIT_PARAMS), [], 0.0)


@dataclasses.dataclass(frozen=True)
class SafeDiagram:
    """Modes of a cyclic sector over its harmonic indices (each double mode counted once).

    Attributes:
        n_sectors: N; k: (n_k,) harmonic indices (nodal diameters); omega: (n_k, n_modes) rad/s ascending per k;
        blade_share: (n_k, n_modes) share of each mode's strain energy in the blade cells; family: (n_k, n_modes)
        labels, '1B', '1T', '2B', ... (blade-dominated, from the tip LE/TE motion) or 'disk' ('mode j' for a sector
        without a blade volume: unlabelled); seconds: (n_k,) wall
        time per k (assembly of the projected operators and the eigen-solve).
    """

    n_sectors: int
    k: np.ndarray
    omega: np.ndarray
    blade_share: np.ndarray
    family: np.ndarray
    seconds: np.ndarray

    def family_curve(self, label: str) -> np.ndarray:
        """(n_k,) frequency of the mode labelled ``label`` at each k (NaN where no mode has that label)."""
        out = np.full(len(self.k), np.nan)
        for i in range(len(self.k)):
            hit = np.flatnonzero(self.family[i] == label)
            if hit.size:
                out[i] = self.omega[i, hit[0]]
        return out

    def as_dict(self) -> dict:
        return {"n_sectors": self.n_sectors, "k": self.k.tolist(), "omega": self.omega.tolist(),
                "blade_share": self.blade_share.tolist(), "family": self.family.tolist(),
                "seconds": self.seconds.tolist()}


def compute_safe_diagram(sector: Sector, n_modes: int = 6, ks=None, ops: SvkOperators | None = None,
                         blade_group: str = "blade") -> SafeDiagram:
    """The lowest ``n_modes`` distinct modes for each harmonic index ``ks`` (default 0 ... N/2), labelled.

    The blade share of a cos/sin pair is (a K_b a + b K_b b) / (a K a + b K b), K_b the stiffness of the blade cells;
    a blade-dominated mode (share >= 1/2) is named from the motion of the tip's LE and TE nodes (``modes.
    classify_blade_modes``, on whichever of a and b moves the tip more), counted within its k. A sector without a
    separate blade volume (a user's sector read without its blade's element set) or without contact nodes is not
    labelled: its shares are NaN, its modes 'mode 1', 'mode 2', ... in each k."""
    if sector.cyclic is None:
        raise ValueError(f"{sector.source} is not a cyclic sector (no paired left/right faces)")
    ks = harmonic_indices(sector.cyclic.n_sectors) if ks is None else np.asarray(ks, dtype=int)
    ops = ops or create_svk_operators(sector)
    K, M = assemble_stiffness(sector, ops), assemble_mass(sector, ops)
    cyclic = CyclicOperators(sector, K, M)
    labelled = blade_group in sector.groups and len(sector.groups.keys() & {"disk"}) == 1 \
        and len(sector.tip_nodes) >= 2
    K_all = assemble_stiffness(sector, ops, clamped=False) if labelled else None
    K_blade = group_stiffness(sector, blade_group) if labelled else None
    x, y = K.createVecRight(), K.createVecLeft()

    def energy(A, f):                     # f^T A f over all ranks (the owned part of f; PETSc's dot is global)
        x.array[:] = f.x.array[:x.getLocalSize()]
        A.mult(x, y)
        return float(x.dot(y))

    omega, share, family, seconds = [], [], [], []
    start = {}                                   # the last modes of each number of copies: the next k's start
    for k in ks:
        t0 = time.perf_counter()
        m = sector.cyclic.n_copies(int(k))
        modes = cyclic.modes(int(k), n_modes, initial=start.get(m))
        start[m] = modes.x
        seconds.append(time.perf_counter() - t0)
        w, idx = modes.distinct()
        if not labelled:
            omega.append(w[:n_modes])
            share.append(np.full(min(n_modes, len(idx)), np.nan))
            family.append(np.array([f"mode {j + 1}" for j in range(min(n_modes, len(idx)))]))
            continue
        shares, tips = [], []
        for i in idx:
            parts = [f for f in (modes.a[i], modes.b[i]) if f is not None]
            total = sum(energy(K_all, f) for f in parts)
            shares.append(sum(energy(K_blade, f) for f in parts) / total)
            moves = [gather_dof_values(sector, f.x.array, sector.tip_dofs) for f in parts]
            tips.append(max(moves, key=lambda u: np.abs(u).max()))
        blade = np.array(shares) >= BLADE_SHARE_DOMINATED
        labels = np.array(["disk"] * len(idx), dtype=object)
        if blade.any():
            labels[blade] = classify_blade_modes(np.array(tips)[blade], sector.tip_nodes)
        omega.append(w[:n_modes])
        share.append(np.array(shares)[:n_modes])
        family.append(labels[:n_modes].astype(str))
    cyclic.destroy()
    for A in (K, M, K_all, K_blade):
        if A is not None:
            A.destroy()
    return SafeDiagram(sector.cyclic.n_sectors, np.asarray(ks), np.array(omega), np.array(share),
                       np.array(family), np.array(seconds))
