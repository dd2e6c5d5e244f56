"""One explicit step for the map and the shooting (#87 item 1): ``CentralDifference.predict`` gives its GNL part
apart (``parts=True``) without changing the prediction, and the map's contact step with the casing's steady
ovalisation (``ContactStep(..., run_length=None)``, what the shooting uses) sees the clearance c0 - f(theta) of eq. 37
from the first step on; the tuned disk's prediction refuses ``parts``. Equalities to round-off (the same operations)."""
import numpy as np
import pytest

from rotor37_rom.dynamics.casing import Casing, casing_profile
from rotor37_rom.dynamics.contact_step import ContactStep
from rotor37_rom.dynamics.explicit import CentralDifference


def test_predict_gives_its_gnl_part_apart(ci_rom):
    scheme = CentralDifference(ci_rom, nonlinear=True)
    rng = np.random.default_rng(87)
    Q, Qp = 1e-4 * rng.standard_normal((ci_rom.r, 3)), 1e-4 * rng.standard_normal((ci_rom.r, 3))
    F = rng.standard_normal(ci_rom.r)
    whole = scheme.predict(Q, Qp, F)
    out, force = scheme.predict(Q, Qp, F, parts=True)
    assert np.array_equal(out, whole)
    assert np.allclose(force, -(scheme.X0 @ ci_rom.forces.evaluate(Q)), rtol=1e-12, atol=1e-30)
    linear = CentralDifference(ci_rom, nonlinear=False)
    assert linear.predict(Q, Qp, None, parts=True)[1] is None


def test_the_steady_casing_is_there_from_the_first_step(ci_rom):
    scheme = CentralDifference(ci_rom, nonlinear=False)
    casing = Casing(mu=0.15)
    steady = ContactStep(scheme, [casing], None)
    assert np.isinf(steady.alpha).all()
    Q = np.zeros((ci_rom.r, 1))
    speed, sense = 1300.0, casing.rotation_sense
    t1 = ((np.pi / 2 - steady.theta0[0]) / (sense * speed)) % (np.pi / speed)    # node 0 under a bump's top
    hits, lam, after = steady.multipliers(Q, np.zeros(1, int), np.array([speed]), np.zeros(1), t1)
    theta = steady.theta0 + sense * speed * t1
    gap = casing.c0 - casing_profile(theta, casing.c0, casing.p0, casing.width)
    assert gap[0] == pytest.approx(-casing.p0) and hits.tolist() == [0] and lam[0, 0] > 0
    assert after.min() >= -1e-12 * casing.p0                        # the multipliers close the penetration
    ramped = ContactStep(scheme, [casing], np.array([1.0]))          # the maps' ramp over 1 s: ~2 % of it there
    assert ramped.multipliers(Q, np.zeros(1, int), np.array([speed]), np.zeros(1), t1)[0].size == 0
    push = steady.push(np.ones((steady.n_contact, 1)), np.array([0.15]))
    assert np.allclose(push[:, 0], (steady.WN + 0.15 * steady.WT).sum(axis=1), rtol=1e-12)
