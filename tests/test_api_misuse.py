"""Misuses of the Python API (#70): each raises ValueError or TypeError with a message naming the argument, before
any work; never an AttributeError from deep inside, never a silent nonsense run."""
import math

import numpy as np
import pytest

from rotor37_rom.dynamics.casing import Casing
from rotor37_rom.dynamics.explicit import CentralDifference, simulate
from rotor37_rom.dynamics.newmark import Newmark, simulate_newmark
from rotor37_rom.model.reduced import load_reduced_model
from rotor37_rom.reduction.config import DiskReductionConfig, ReductionConfig
from rotor37_rom.studies.contact_config import ContactMapConfig, MapScheme
from rotor37_rom.studies.model_choice import choose_model
from rotor37_rom.studies.sweep import SweepSpec

NAN, INF = math.nan, math.inf
M2, K2 = np.eye(2), np.diag([1.0, 4.0])

# (what is called, the exception, a word the message must hold)
PURE = [
    (lambda: ReductionConfig(r_c=NAN), ValueError, "r_c"),
    (lambda: ReductionConfig(r_c=2.5), ValueError, "r_c"),
    (lambda: ReductionConfig(r_c=True), ValueError, "r_c"),
    (lambda: ReductionConfig(r_md=-1), ValueError, "r_md"),
    (lambda: ReductionConfig(global_md_modes=21), ValueError, "global_md_modes"),
    (lambda: ReductionConfig(contact_patch=INF), ValueError, "contact_patch"),
    (lambda: ReductionConfig(criterion="best"), ValueError, "criterion"),
    (lambda: ReductionConfig(forces="magic"), ValueError, "forces"),
    (lambda: ReductionConfig(fd_step=0.0), ValueError, "fd_step"),
    (lambda: ReductionConfig(training_omega=-1.0), ValueError, "training_omega"),
    (lambda: DiskReductionConfig(r_cyclic=0), ValueError, "r_cyclic"),
    (lambda: DiskReductionConfig(mistuning=(1.0, -1.0)), ValueError, "mistuning"),
    (lambda: DiskReductionConfig(mistuning=(1.0, NAN)), ValueError, "mistuning"),
    (lambda: DiskReductionConfig(load_patch=NAN), ValueError, "load_patch"),
    (lambda: DiskReductionConfig(face_shapes=-1), ValueError, "face_shapes"),
    (lambda: DiskReductionConfig(tip_nodes="mid"), ValueError, "tip_nodes"),
    (lambda: Casing(c0="abc"), ValueError, "c0"),
    (lambda: Casing(mu=NAN), ValueError, "mu"),
    (lambda: Casing(h_b=-1e-3), ValueError, "h_b"),
    (lambda: Casing(direction="z"), ValueError, "direction"),
    (lambda: Casing(rotation_sense=0), ValueError, "rotation_sense"),
    (lambda: Casing(width=INF), ValueError, "width"),
    (lambda: SweepSpec(revolutions=INF), ValueError, "revolutions"),
    (lambda: SweepSpec(batch_size=0), ValueError, "batch_size"),
    (lambda: SweepSpec(record_dt=0.0), ValueError, "record_dt"),
    (lambda: SweepSpec(casing="x"), TypeError, "casing"),
    (lambda: choose_model("nope", 0.1), ValueError, "scene"),
    (lambda: choose_model("map-gnl", 2.0), ValueError, "tolerance"),
    (lambda: choose_model("map-gnl", True), ValueError, "tolerance"),
    (lambda: ContactMapConfig.from_options(frobnicate=1), TypeError, "frobnicate"),
    (lambda: ContactMapConfig(sweep=Casing()), TypeError, "sweep"),
    (lambda: ContactMapConfig.from_options(speeds=(1200.0, 1600.0)), ValueError, "--speeds"),
    (lambda: ContactMapConfig.from_options(revolutions=1e9), ValueError, "--revolutions"),
    (lambda: MapScheme(cubature=1.5), ValueError, "--cubature"),
    (lambda: simulate_newmark(M2, 0 * M2, K2, lambda t: np.zeros(2), 0.0, 10), ValueError, "dt"),
    (lambda: simulate_newmark(M2, 0 * M2, K2, lambda t: np.zeros(2), 0.1, 1.5), ValueError, "n_steps"),
    (lambda: Newmark(M2, lambda x: K2 @ x, lambda x: K2, None, None, rho_inf=2.0), ValueError, "rho_inf"),
    (lambda: load_reduced_model("no/such/model.npz"), ValueError, "reduced model file"),
    (lambda: CentralDifference(None), TypeError, "model"),
    (lambda: simulate("x", [1400.0], revolutions=0.01), TypeError, "scheme"),
]


@pytest.mark.parametrize("call, error, word", PURE, ids=[f"{k}" for k in range(len(PURE))])
def test_a_misuse_is_refused_naming_its_argument(call, error, word):
    with pytest.raises(error) as refused:
        call()
    assert word in str(refused.value), str(refused.value)
    assert "\n" not in str(refused.value)


def test_misuses_with_a_model(ci_rom, tmp_path):
    """The integrator's arguments, on a real reduced model."""
    scheme = CentralDifference(ci_rom, nonlinear=False, safety=0.5)
    cases = [
        (lambda: CentralDifference(ci_rom, safety=NAN), ValueError, "safety"),
        (lambda: CentralDifference(ci_rom, h=-1e-7), ValueError, "time step h"),
        (lambda: CentralDifference(ci_rom, frequency_cap=INF), ValueError, "frequency_cap"),
        (lambda: simulate(scheme, [NAN], revolutions=0.01), ValueError, "Omega"),
        (lambda: simulate(scheme, [1400.0], "x", revolutions=0.01), TypeError, "casing"),
        (lambda: simulate(scheme, [1400.0], [Casing(), Casing()], revolutions=0.01), ValueError, "casing"),
        (lambda: simulate(scheme, [1400.0], on_blowup="maybe", revolutions=0.01), ValueError, "on_blowup"),
        (lambda: simulate(scheme, [1400.0]), ValueError, "revolutions"),
        (lambda: load_reduced_model(tmp_path), ValueError, "is a folder"),
    ]
    for call, error, word in cases:
        with pytest.raises(error) as refused:
            call()
        assert word in str(refused.value), str(refused.value)
