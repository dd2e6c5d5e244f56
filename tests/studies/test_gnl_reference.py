"""The steady-state GNL reference's pieces (issue #86): the full order's damping law on a reduced model by projection
(the ROM's 1B damped at the law's ratio to the Rayleigh-Ritz accuracy of its 1B), a reduced run ending "not steady"
at its revolution limit instead of a number, and the cases' and runs' misuse refused in one line."""
import dataclasses

import numpy as np
import pytest
import scipy.linalg

from rotor37_rom.studies.gnl_reference import SteadyCase, reduced_damping, reduced_run


def test_the_projected_law_damps_the_reduced_1b_at_the_full_orders_ratio(ci_blade, ci_ops, ci_rom):
    """phi_r^T C_r phi_r = 2 xi omega_1 up to the ROM's 1B error: the ROM's 1B is the full one's to Rayleigh-Ritz
    accuracy (frequency error eps, mode error ~sqrt(eps)), so the modal damping it sees is within a few sqrt(eps)."""
    from rotor37_rom.dynamics.damping import damping_law
    from rotor37_rom.fem.periodic import RepeatingSectors

    law = damping_law("heavy")
    C = reduced_damping(ci_rom, ci_blade, ci_ops, law)
    assert np.allclose(C, C.T, atol=1e-12 * np.abs(C).max())
    lam, V = scipy.linalg.eigh(ci_rom.K, ci_rom.M)
    omega_full = RepeatingSectors(ci_blade, 1, ci_ops).modes(law.n_modes)[0]
    eps = abs(np.sqrt(lam[0]) / omega_full[0] - 1)
    assert eps < 1e-3                                                  # the ROM's 1B (Rayleigh-Ritz: from above)
    zeta = V[:, 0] @ C @ V[:, 0] / (2 * np.sqrt(lam[0]))
    assert abs(zeta - 0.02) <= 0.02 * 10 * np.sqrt(eps) + 1e-6, (zeta, eps)


def test_a_run_that_does_not_settle_is_marked_not_steady(ci_rom):
    """Three revolutions of an undamped model from rest under the casing: the verdict is "not steady" (or steady
    with its reason), and a model without a basis cannot take the full order's law."""
    case = SteadyCase(2500.0, revolutions=3, ramp_revolutions=1.0, bump_mm=0.625)
    run = reduced_run(ci_rom, np.zeros_like(ci_rom.K), case, 4e-7, 2e3 * np.pi * 120, record=4e-6)
    assert run.verdict.maxima.size == 3 and np.all(np.isfinite(run.verdict.maxima))
    if not run.verdict.steady:
        assert run.verdict.reason.startswith("not steady by revolution 3")
    assert run.to_json()["steady"] == run.verdict.steady
    with pytest.raises(ValueError, match="carries no basis"):
        reduced_damping(dataclasses.replace(ci_rom, Phi=None), None, None, None)
    with pytest.raises(ValueError, match="C must be a finite"):
        reduced_run(ci_rom, np.zeros((3, 3)), case, 4e-7, 1e6)


@pytest.mark.parametrize("kwargs, word", [({"speed": 0.0}, "speed"), ({"speed": float("nan")}, "speed"),
                                          ({"mu": -0.1}, "mu"), ({"direction": "up"}, "direction"),
                                          ({"law": "rayleigh"}, "damping law"), ({"revolutions": 2}, "revolutions"),
                                          ({"revolutions": 8.5}, "revolutions"),
                                          ({"ramp_revolutions": 7.0}, "ramp_revolutions"),
                                          ({"tolerance": 0.0}, "tolerance"), ({"bump_mm": 5.0}, "bump_mm"),
                                          ({"hyperelastic": "mooney-rivlin"}, "hyperelastic")])
def test_bad_cases_are_refused(kwargs, word):
    with pytest.raises(ValueError, match=word):
        SteadyCase(**{"speed": 1280.0, **kwargs})


def test_the_case_ramps_over_its_own_revolutions():
    case = SteadyCase(1280.0, revolutions=10, ramp_revolutions=2.0)
    casing = case.casing()
    assert casing.ramp_fraction * case.duration == pytest.approx(2 * 2 * np.pi / 1280.0)
    assert case.damping.low == 0.02 and "heavy" in case.label()


def test_revolution_peaks_split_the_two_sides():
    from rotor37_rom.studies.gnl_reference import revolution_peaks

    w = 1000.0
    t = np.linspace(0.0, 3 * 2 * np.pi / w, 3 * 512 + 1)
    u = 0.2 + np.sin(w * t)                                 # towards the casing 1.2, towards the axis 0.8
    inward, outward = revolution_peaks(t, u, w)
    assert np.allclose(inward, 0.8, rtol=1e-4) and np.allclose(outward, 1.2, rtol=1e-4)


def test_pod_model_refuses_fields_of_another_mesh(ci_blade):
    from rotor37_rom.studies.gnl_reference import pod_model

    with pytest.raises(ValueError, match="snapshots must be"):
        pod_model(ci_blade, None, np.ones((5, ci_blade.n_dofs + 3)), 30)


def test_runs_are_compared_only_where_both_are_steady():
    from rotor37_rom.post.steady import steadiness
    from rotor37_rom.studies.gnl_reference import SteadyRun, compare_runs

    case = SteadyCase(1000.0, revolutions=4)
    t = np.linspace(0.0, case.duration, 4 * 400 + 1)

    def run(amplitude, wall, growth=0.0):
        u = amplitude * (1 + growth * t / case.duration) * np.sin(4 * 1000.0 * t)
        return SteadyRun(t, u, steadiness(t, u, 1000.0), wall, {}).to_json()

    runs = {"full": run(2e-4, 400.0), "rom": run(1.8e-4, 4.0), "drifting": run(1.8e-4, 4.0, growth=0.5)}
    rows = {r["run"]: r for r in compare_runs(case, runs, "full")}
    assert rows["rom"]["error"] == pytest.approx(-0.1, abs=1e-4) and rows["rom"]["cost_ratio"] == pytest.approx(100)
    assert rows["rom"]["error_towards_casing"] == pytest.approx(-0.1, abs=1e-4)
    assert rows["drifting"]["steady"] is False and rows["drifting"]["error"] is None
    assert rows["full"]["error"] is None
    with pytest.raises(ValueError, match="reference must be one of"):
        compare_runs(case, runs, "fom")


def test_the_full_order_runs_the_cases_hyperelastic_law(ci_blade, ci_ops):
    """The case names its full order's law (the label too, where it is not SVK's), and operators of another law are
    refused before any step; the laws a case may name are the forms layer's."""
    from rotor37_rom import forms
    from rotor37_rom.studies.gnl_reference import HYPERELASTIC_LAWS, full_order_run

    assert sorted(HYPERELASTIC_LAWS) == sorted(forms.HYPERELASTIC_LAWS)
    neo = SteadyCase(1280.0, hyperelastic="neo-hookean")
    assert neo.label().endswith("neo-hookean") and "svk" not in SteadyCase(1280.0).label()
    with pytest.raises(ValueError, match="operators' law is 'svk'"):
        full_order_run(ci_blade, ci_ops, neo, 2e-6)


def test_the_cubature_model_is_trained_on_its_own_runs(ci_blade, ci_rom, tmp_path):
    """Trained on two revolutions of the model's own exact run (no full order), the point cubature keeps the
    training forces to its tolerance with fewer points than the exact quadrature, removes its training checkpoint and
    says what it was trained on; bad tolerances, speeds and lengths are refused in one line."""
    from rotor37_rom.studies.gnl_reference import cubature_model

    case = SteadyCase(2500.0, revolutions=3)
    C = np.zeros_like(ci_rom.K)
    ckpt = tmp_path / "train.npz"
    model, info = cubature_model(ci_rom, C, ci_blade, case, 4e-7, 2e3 * np.pi * 120, 1e-3, [2500.0],
                                 train_revolutions=2, checkpoint=ckpt)
    assert info["training_error"] <= 1e-3 and 0 < info["points"] < info["quadrature_points"]
    assert "2500" in model.metadata["hyper_reduction"]["label"] and not ckpt.exists()
    for kwargs, word in (({"tol": 0.0}, "tol"), ({"train_speeds": []}, "train_speeds"),
                         ({"train_speeds": [-1.0]}, "train_speeds"), ({"train_revolutions": 1}, "train_revolutions"),
                         ({"train_revolutions": 2.5}, "train_revolutions")):
        args = {"tol": 1e-3, "train_speeds": [2500.0], "train_revolutions": 2, **kwargs}
        with pytest.raises(ValueError, match=word):
            cubature_model(ci_rom, C, ci_blade, case, 4e-7, 1e6, **args)


def test_batch_cost_times_a_maps_batch_and_refuses_bad_sizes(ci_rom):
    from rotor37_rom.studies.gnl_reference import batch_cost

    case = SteadyCase(1280.0)
    C = np.zeros_like(ci_rom.K)
    out = batch_cost(ci_rom, C, case, 4e-7, 2e3 * np.pi * 120, speeds=3, steps=50)
    assert out["speeds"] == 3 and out["steps"] == 50 and 0 < out["us_per_speed_step"] < 1e6
    for kwargs, word in (({"speeds": 0}, "speeds"), ({"speeds": 2.5}, "speeds"), ({"steps": 5}, "steps")):
        with pytest.raises(ValueError, match=word):
            batch_cost(ci_rom, C, case, 4e-7, 1e6, **{"speeds": 3, "steps": 50, **kwargs})
