"""What a reduced model is built from: ``ReductionConfig`` (the blade, or any clamped sector) and
``DiskReductionConfig`` (the bladed disk). Pure Python and NumPy: a configuration checks itself when made, before
any meshing, and names the field it refuses (``rotor37_rom.checks``)."""
from __future__ import annotations

import dataclasses
import numbers

import numpy as np

from rotor37_rom.checks import fits_in_memory, real_number, whole_number
from rotor37_rom.reduction.craig_bampton import CRITERIA, GLOBAL_MD_MAX

#: fixed-interface modes or modal derivatives (per sector) at most: far above any contact study's (15-200), below
#: what SLEPc and the cubic tensors (r^4 / 6 entries) could hold on one machine
MODES_MAX = 2000


def check_cubic_memory(option: str, r: int, copies: int = 3) -> None:
    """ValueError naming ``option`` where a blade's reduced model of size ``r`` could not hold its exact cubic forces
    (r (r + 1) (r + 2) / 6 x r doubles) ``copies`` times: the tensor, its packed copy for the C kernel and the
    explicit scheme's premultiplied one."""
    fits_in_memory(option, copies * 8.0 * r * r * (r + 1) * (r + 2) / 6,
                   f"a reduced model of r = {r}: its exact cubic forces {copies} times",
                   hint="fewer modes (--r-c, --r-md, --global-md)")

__all__ = ["ReductionConfig", "DiskReductionConfig", "FORCE_METHODS"]

FORCE_METHODS = ("intrusive", "quadrature", "step", "ecsw", "none")


@dataclasses.dataclass(frozen=True)
class ReductionConfig:
    """Reduction parameters (SI units).

    Attributes:
        r_c: fixed-interface modes (>= 1).
        r_md: modal derivatives kept (0 .. (r_b + r_c)(r_b + r_c + 1)/2).
        criterion: MD selection: 'MMI', 'MI2a', 'MI2b', 'SMVW', 'random'.
        md_method: 'exact' (UFL second derivative, eq. 17) or 'fd' (finite-difference tangent, eq. 19).
        fd_step: displacement amplitude (m) of the finite-difference step (largest nodal displacement of eps phi_k).
        forces: 'intrusive' (exact tensors), 'quadrature' (exact, tensor-free), 'step', 'ecsw', 'none'.
        step_amplitude: largest displacement (m) of each enforced STEP displacement.
        ecsw_tol: relative training tolerance of ECSW; ecsw_states: number of training states.
        training_force: amplitude (N) of the harmonic training force at node LE along e_z (§3.3.1: 400 N).
        training_omega: its pulsation (rad/s) (§3.3.1: 4000); one period, 400 Newmark steps.
        keep_basis: store Phi in the model (to rebuild fields).
        global_md_modes: n > 0 adds the modal derivatives of all pairs of the first n clamped normal modes (1B, 1T,
            2B, ...), fixed-interface corrected: n(n+1)/2 vectors that carry the global quadratic kinematics
            (foreshortening) which otherwise needs hundreds of constraint-mode pairs. 0 = the paper's basis.
        contact_patch: 0 (the paper's point contact: the boundary DOFs are the tip nodes' own), or a radius (m):
            each contact node's boundary coordinates are the area-mean displacement of the tip facets within it
            (``fem.tip_patch_interface``), so its contact force acts as a uniform traction on that patch and no
            constraint mode or modal derivative carries a point load's singular field (issue #23).
        spin_snapshots: () (a model at rest), or speeds (rad/s, > 0): the blade's full-order centrifugal states at
            them (``fem.solve_static(spin=...)``, fixed-interface corrected) join the basis after the modal
            derivatives, and the model carries its rotation terms (``model.rotating``: spin softening, centrifugal
            load, Coriolis), valid from 0 to the largest of them (#73).
        spin_modes: with spin_snapshots, the first n modes of the blade turning at the top snapshot speed
            (prestressed, spin softened), fixed-interface corrected, join the basis too (a multi-model basis: the
            modes at rest and at speed; at the top speed these n are then exact), 0 .. r_c.
    """

    r_c: int = 15
    r_md: int = 30
    criterion: str = "MI2b"
    md_method: str = "exact"
    fd_step: float = 1e-6
    forces: str = "intrusive"
    step_amplitude: float = 1e-3
    ecsw_tol: float = 1e-3
    ecsw_states: int = 80
    training_force: float = 400.0
    training_omega: float = 4000.0
    keep_basis: bool = True
    global_md_modes: int = 0
    contact_patch: float = 0.0
    spin_snapshots: tuple = ()
    spin_modes: int = 0

    def __post_init__(self):
        whole_number("r_c", self.r_c, 1, MODES_MAX)
        whole_number("r_md", self.r_md, 0, MODES_MAX)
        whole_number("global_md_modes", self.global_md_modes, 0, GLOBAL_MD_MAX)
        whole_number("ecsw_states", self.ecsw_states, 1)
        real_number("contact_patch", self.contact_patch, 0, 0.01, unit=" m")
        if self.criterion not in CRITERIA:
            raise ValueError(f"criterion must be one of {CRITERIA}, got {self.criterion!r}")
        if self.md_method not in ("exact", "fd"):
            raise ValueError(f"md_method must be 'exact' or 'fd', got {self.md_method!r}")
        if self.forces not in FORCE_METHODS:
            raise ValueError(f"forces must be one of {FORCE_METHODS}, got {self.forces!r}")
        real_number("fd_step", self.fd_step, 0, 1e-2, open_low=True, open_high=True, unit=" m")
        real_number("step_amplitude", self.step_amplitude, 0, 0.1, open_low=True, open_high=True, unit=" m")
        real_number("ecsw_tol", self.ecsw_tol, 0, 1, open_low=True, open_high=True)
        real_number("training_force", self.training_force, 0, open_low=True, unit=" N")
        real_number("training_omega", self.training_omega, 0, open_low=True, unit=" rad/s")
        object.__setattr__(self, "spin_snapshots", _spin_snapshots(self.spin_snapshots))
        whole_number("spin_modes", self.spin_modes, 0, self.r_c)
        if self.spin_modes and not self.spin_snapshots:
            raise ValueError("spin_modes needs spin_snapshots (the modes are the blade's turning at the top "
                             "snapshot speed)")


def _spin_snapshots(speeds) -> tuple:
    """The centrifugal snapshots' speeds, checked (at most 10 in (0, 1e5] rad/s), sorted and distinct."""
    if not isinstance(speeds, (tuple, list)) or len(speeds) > 10 or any(
            not isinstance(w, numbers.Real) or not np.isfinite(w) or not 0 < w <= 1e5 for w in speeds):
        raise ValueError(f"spin_snapshots: at most 10 speeds in (0, 1e5] rad/s, got {speeds!r}")
    return tuple(sorted({float(w) for w in speeds}))


@dataclasses.dataclass(frozen=True)
class DiskReductionConfig:
    """Parameters of the disk's reduced model (SI units).

    Attributes:
        tip_nodes: the sector's tip nodes kept physical in q ('all': the 8 contact nodes, r_b = 24; 'LE': node LE
            only, r_b = 3, the paper's §3.3 models).
        r_c: fixed-interface modes per sector (>= 1).
        r_md: modal derivatives per sector, selected by ``criterion`` on the training response.
        criterion: 'MMI', 'MI2a', 'MI2b', 'SMVW' or 'random' (§3.1.2).
        r_cyclic: interface modes of the whole disk (eq. 51; the paper: 144).
        interface: 'closest' (eq. 51: the interface modes closest in frequency to the sector's fixed-interface
            modes) or 'per_k' (the lowest modes of every harmonic in equal shares).
        forces: 'intrusive' (exact tensors), 'quadrature' (exact, tensor-free) or 'none' (linear).
        training_force, training_omega: the training load (§3.3.1: 400 N along e_z at node LE of every sector,
            4000 rad/s, one period, a 0-diameter load: the training runs on the sector with its faces tied for k = 0).
        mistuning: None (tuned) or one stiffness factor per sector (e.g. 1 + scatter), each > 0.
        seed: of the 'random' criterion.
        load_patch: 0 (the paper's point load at node LE), or a radius (m): the training force spread as a traction
            over the boundary facets within it of node LE (``fem.patch_load``), and that load's static response with
            the boundary fixed added to every sector's basis after the fixed-interface modes (the static load
            correction of component mode synthesis: a load off the boundary set has a local field that neither the
            constraint modes nor the lowest fixed-interface modes carry), its modal derivatives among the candidates.
        face_shapes: 0 (eq. 61: each sector's nonlinear force acts on its q^n only, the paper's linear coupling), or
            n_f >= 1: the force acts on the sector's whole field with each face on n_f shapes
            (``disk.assembly.face_shapes``), r_s + 2 n_f force coordinates per sector. The faces' constraint modes carry
            part of the blade's motion: eq. 61 caps the GNL forced response's accuracy (docs/results.md).
        spin_snapshots: () (a disk at rest), or speeds (rad/s): the whole disk's centrifugal states there, each a
            harmonic-index-0 field solved on the sector (``fem.centrifugal_state``), put in the basis: its faces'
            shape as an index-0 interface mode, its part with the tip and faces held as a column of every sector's
            basis; the model then turns (``model.rotating``: the rotation terms reduced exactly), over 0 ... the top
            snapshot's speed.
    """

    tip_nodes: str = "all"
    r_c: int = 10
    r_md: int = 10
    criterion: str = "MI2b"
    r_cyclic: int = 144
    interface: str = "closest"
    forces: str = "intrusive"
    training_force: float = 400.0
    training_omega: float = 4000.0
    mistuning: tuple | None = None
    seed: int = 0
    load_patch: float = 0.0
    face_shapes: int = 0
    spin_snapshots: tuple = ()
    spin_modes: int = 0

    def __post_init__(self):
        object.__setattr__(self, "spin_snapshots", _spin_snapshots(self.spin_snapshots))
        whole_number("spin_modes", self.spin_modes, 0, self.r_c)
        if self.spin_modes and not self.spin_snapshots:
            raise ValueError("spin_modes needs spin_snapshots (the modes are the sector's turning at the top "
                             "snapshot speed)")
        if self.tip_nodes not in ("all", "LE"):
            raise ValueError(f"tip_nodes must be 'all' or 'LE', got {self.tip_nodes!r}")
        whole_number("r_c", self.r_c, 1, MODES_MAX)
        whole_number("r_md", self.r_md, 0, MODES_MAX)
        whole_number("r_cyclic", self.r_cyclic, 1)
        whole_number("face_shapes", self.face_shapes, 0)
        whole_number("seed", self.seed, 0)
        if self.criterion not in CRITERIA:
            raise ValueError(f"criterion must be one of {CRITERIA}, got {self.criterion!r}")
        if self.interface not in ("closest", "per_k"):
            raise ValueError(f"interface must be 'closest' or 'per_k', got {self.interface!r}")
        if self.forces not in ("intrusive", "quadrature", "none"):
            raise ValueError(f"forces must be 'intrusive', 'quadrature' or 'none', got {self.forces!r}")
        if self.mistuning is not None and not (
                isinstance(self.mistuning, (tuple, list)) and len(self.mistuning) > 0
                and all(isinstance(f, numbers.Real) and np.isfinite(f) and f > 0 for f in self.mistuning)):
            raise ValueError(f"mistuning: one finite stiffness factor > 0 per sector, got {self.mistuning!r}")
        real_number("load_patch", self.load_patch, 0, 0.02, unit=" m")
        real_number("training_force", self.training_force, 0, open_low=True, unit=" N")
        real_number("training_omega", self.training_omega, 0, open_low=True, unit=" rad/s")
