"""The free travelling wave of a tuned disk with nonlinear forces (disk.travelling_wave_backbone, wave_history).

On a random tuned disk (N = 12 sectors, r_s = 4, 3 face DOFs, interface modes of every index):
- linear forces: the wave's frequency is the linear one at every amplitude, the state the scaled mode (round-off);
- a force that only stiffens the wave's own pair, g(q) = gamma (q^T P q) P q (P the M-orthogonal projector on the
  pair): every turn of the pair is an exact wave, omega^2 = omega_0^2 + gamma a^2 (round-off), the unfolding force 0;
- a cubic force on each sector's coordinates (the gradient of gamma / 4 |q^n|^4): omega^2 = omega_0^2 + c a^2 + d a^4
  + O(a^6), c and d from the ansatz's own expansion (d holds the inertia of index 3k, turning at 3 omega): the
  error of the a^4 coefficient falls 4x when a halves (Taylor), and the unbalanced force enters at a^5;
- a quadratic force on each sector's coordinates: omega^2 = omega_0^2 + c2 a^2 + O(a^4), c2 through the steady index
  0 and index 2k turning at 2 omega: the error of c2 falls 4x when a halves;
- continuing from returned points gives the points of one call (Newton's tolerance); a callback sees each point
  and ends the continuation where it returns True;
- wave_history gives sector 0's history of an analytic forward wave with a second harmonic (round-off);
- bad input.
"""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
import scipy.linalg

from rotor37_rom.disk.assembly import assemble_disk_matrices, interface_modes
from rotor37_rom.model.disk_basis import DiskBasis
from rotor37_rom.disk.harmonics import (harmonic_coordinates, harmonic_frequencies, travelling_wave_backbone,
    wave_harmonic_order, wave_history)
from conftest import random_sector  # noqa: E402

N, RS, NL, K_WAVE = 12, 4, 3, 2


def _disk(force=None, jacobian=None):
    """A random tuned disk model (the structure of harmonic_frequencies' test) with the given nonlinear force."""
    s = random_sector(np.random.default_rng(5), RS, NL)
    Pi, _, _ = interface_modes(s, N, N * NL, per_k=NL)
    Kd, Md = assemble_disk_matrices(s, Pi, N)
    basis = DiskBasis(np.zeros((1, RS)), np.zeros((1, NL)), np.zeros((1, NL)), Pi, np.arange(N * RS).reshape(N, RS), N)
    model = SimpleNamespace(sectors=basis, K=Kd, M=Md, r=Kd.shape[0], forces=None)
    if force is None:
        model.nonlinear_force = lambda q: np.zeros((model.r, 1))
    else:
        model.forces = SimpleNamespace(jacobian=lambda q: jacobian(model, q))
        model.nonlinear_force = lambda q: force(model, np.asarray(q, float).ravel())[:, None]
    return model


def test_linear_disk_backbone_is_the_linear_wave():
    model = _disk()
    pts = travelling_wave_backbone(model, K_WAVE, [0.1, 1.0, 10.0])
    omega_k = harmonic_frequencies(model, 1)[K_WAVE, 0]
    for p in pts:
        assert p["omega"] == pytest.approx(omega_k, rel=1e-12)
        np.testing.assert_allclose(p["q"], p["a"] * p["phi"], atol=1e-12 * p["a"] * np.abs(p["phi"]).max())
        assert p["defect"] < 1e-12


def _pair(model):
    """The linear pair of index K_WAVE, family 0 (M-orthonormal), as the backbone takes it."""
    T, k_of, Kt, Mt = harmonic_coordinates(model)
    idx = np.flatnonzero(k_of == K_WAVE)
    _, V = scipy.linalg.eigh(Kt[np.ix_(idx, idx)], Mt[np.ix_(idx, idx)])
    pair = np.zeros((model.r, 2))
    pair[idx] = V[:, :2]
    return np.asarray(T.T @ pair)


def test_a_force_on_the_pair_alone_gives_the_exact_wave():
    """g = grad gamma / 4 |z|^4, z = the pair's coordinates (phi, psi)^T M q: g(a phi) = gamma a^3 M phi, so
    K a phi + g = (omega_0^2 + gamma a^2) M a phi exactly: no other coordinate, no unfolding force."""
    gamma = 3.0
    base = _disk()
    pair = _pair(base)
    MP = base.M @ pair                                                  # (r, 2)

    def force(model, q):
        z = MP.T @ q
        return gamma * (z @ z) * (MP @ z)

    def jacobian(model, q):
        z = MP.T @ q
        v = MP @ z
        return gamma * (2 * np.outer(v, v) + (z @ z) * MP @ MP.T)

    model = _disk(force, jacobian)
    w2 = harmonic_frequencies(model, 1)[K_WAVE, 0] ** 2
    for p in travelling_wave_backbone(model, K_WAVE, [0.2, 0.5, 1.0, 2.0]):
        np.testing.assert_allclose(p["phi"], pair[:, 0], rtol=0, atol=0)
        assert p["omega"] ** 2 == pytest.approx(w2 + gamma * p["a"] ** 2, rel=1e-10)
        assert p["defect"] < 1e-10
        np.testing.assert_allclose(p["q"], p["a"] * p["phi"], atol=1e-9 * p["a"] * np.abs(p["phi"]).max())


def _sectorwise(g, dg):
    """(force, jacobian) of a force acting on each sector's coordinates alone: g(x) (RS,) and dg(x) (RS, RS) of one
    sector's x; the interface coordinates carry none."""
    def force(model, q):
        out = np.zeros(model.r)
        out[: N * RS] = np.concatenate([g(x) for x in q[: N * RS].reshape(N, RS)])
        return out

    def jacobian(model, q):
        J = np.zeros((model.r, model.r))
        for n, x in enumerate(q[: N * RS].reshape(N, RS)):
            J[n * RS:(n + 1) * RS, n * RS:(n + 1) * RS] = dg(x)
        return J
    return force, jacobian


def _sector_cubic(gamma):
    """The gradient of gamma / 4 |q^n|^4 summed over the sectors' coordinates, and its Jacobian."""
    return _sectorwise(lambda x: gamma * (x @ x) * x, lambda x: gamma * ((x @ x) * np.eye(RS) + 2 * np.outer(x, x)))


def _second_order_state(model, phi, psi, rhs):
    """w solving (K - omega_0^2 D M) w + s M psi + t M phi = rhs, phi^T M w = psi^T M w = 0: the ansatz's expansion
    term, with D M = T^T D T M built here from the harmonic coordinates and the wave's time harmonics."""
    T, k_of, _, _ = harmonic_coordinates(model)
    n2 = wave_harmonic_order(N, K_WAVE)[k_of].astype(float) ** 2
    DM = np.asarray(T.T @ (n2[:, None] * np.asarray(T @ model.M)))        # T^T D T M
    w02 = (phi @ model.K @ phi) / (phi @ model.M @ phi)
    r = model.r
    A = np.zeros((r + 2, r + 2))
    A[:r, :r], A[:r, r], A[:r, r + 1] = model.K - w02 * DM, model.M @ psi, model.M @ phi
    A[r, :r], A[r + 1, :r] = model.M @ phi, model.M @ psi
    return np.linalg.solve(A, np.concatenate([rhs, [0.0, 0.0]]))[:r]


def test_small_amplitude_frequency_follows_the_cubic_term():
    """omega^2 = omega_0^2 + c a^2 + d a^4 + O(a^6) with c = phi^T g(phi) and d = phi^T J(phi) w3, w3 the third-order
    state (K - omega_0^2 D M) w3 + s M psi = c M phi - g(phi) in the complement of the pair, where D turns each
    harmonic index at its time harmonic (here index 3k at 3 omega: d fails if that inertia is wrong).
    (omega^2 - omega_0^2 - c a^2) / a^4 - d = O(a^2): its ratio over a halving is 4 (the Taylor test's observed rate,
    to 10 %). The unbalanced force sigma enters at a^5, so the defect |sigma| / (omega^2 a) falls 16x (to 10 %)."""
    model = _disk(*_sector_cubic(50.0))
    pts = travelling_wave_backbone(model, K_WAVE, [0.16, 0.08, 0.04], tol=1e-14)   # below 0.04 round-off / a^4
    phi, psi = _pair(model).T
    np.testing.assert_array_equal(pts[0]["phi"], phi)
    g = model.nonlinear_force(phi)[:, 0]
    c = phi @ g
    w02 = pts[0]["omega_linear"] ** 2
    w3 = _second_order_state(model, phi, psi, c * model.M @ phi - g)
    d = phi @ model.forces.jacobian(phi) @ w3
    assert c > 0 and abs(d) > 1e-3 * c ** 2 / w02                         # both terms there to measure
    err = {p["a"]: abs((p["omega"] ** 2 - w02 - c * p["a"] ** 2) / p["a"] ** 4 - d) for p in pts}
    defect = {p["a"]: p["defect"] for p in pts}
    for big, small in ((0.16, 0.08), (0.08, 0.04)):
        assert err[big] / err[small] == pytest.approx(4.0, rel=0.1)
        assert defect[big] / defect[small] == pytest.approx(16.0, rel=0.1)


def test_small_amplitude_frequency_follows_the_quadratic_term():
    """g the gradient of beta (e . q^n) |q^n|^2 on each sector (quadratic): phi^T g(phi) = 0 (a k-wave's cubes sum to
    0 over the sectors unless 3k = 0 mod N), so omega^2 = omega_0^2 + c2 a^2 + O(a^4), c2 = phi^T J(phi) w2, w2 the
    second-order state (K - omega_0^2 D M) w2 = -g(phi) on the steady index 0 and index 2k turning at 2 omega: c2
    fails if either inertia is wrong. The error of c2 falls 4x when a halves (to 10 %)."""
    beta = 30.0
    e = np.array([1.0, -0.5, 0.25, 2.0]) / np.sqrt(5.3125)

    force, jacobian = _sectorwise(lambda x: beta * ((x @ x) * e + 2 * (x @ e) * x),
                                  lambda x: beta * (2 * np.outer(e, x) + 2 * np.outer(x, e) + 2 * (x @ e) * np.eye(RS)))

    model = _disk(force, jacobian)
    pts = travelling_wave_backbone(model, K_WAVE, [0.04, 0.02, 0.01], tol=1e-14)
    phi, psi = _pair(model).T
    g = model.nonlinear_force(phi)[:, 0]
    assert abs(phi @ g) < 1e-12 * np.linalg.norm(g) * np.linalg.norm(phi)
    w2 = _second_order_state(model, phi, psi, -g)
    c2 = phi @ model.forces.jacobian(phi) @ w2
    w02 = pts[0]["omega_linear"] ** 2
    assert abs(c2) > 1e-3 * w02                                            # a term there to measure
    err = {p["a"]: abs((p["omega"] ** 2 - w02) / p["a"] ** 2 - c2) for p in pts}
    for big, small in ((0.04, 0.02), (0.02, 0.01)):
        assert err[big] / err[small] == pytest.approx(4.0, rel=0.1)


def test_backbone_continues_from_returned_points():
    """One call through 0.1, 0.2, 0.3 and a call from its first two points to 0.3 reach the same state (Newton's
    tolerance, 1e-12 of |K q|: omega to 1e-10); a start above the amplitudes is refused."""
    model = _disk(*_sector_cubic(50.0))
    pts = travelling_wave_backbone(model, K_WAVE, [0.1, 0.2, 0.3], tol=1e-12)
    more = travelling_wave_backbone(model, K_WAVE, [0.3], tol=1e-12, start=pts[:2])
    assert more[0]["omega"] == pytest.approx(pts[2]["omega"], rel=1e-10)
    np.testing.assert_allclose(more[0]["q"], pts[2]["q"], atol=1e-9 * np.abs(pts[2]["q"]).max())
    assert more[0]["steps"] == 1
    with pytest.raises(ValueError, match="start: points of this wave"):
        travelling_wave_backbone(model, K_WAVE, [0.15], start=pts[1])


def test_backbone_callback_sees_each_point_and_stops_the_path():
    """The callback sees the points one call returns, in order, and a True return ends the path there: the points
    so far are those of the full call (the same arithmetic), the rest not computed."""
    model = _disk(*_sector_cubic(50.0))
    full = travelling_wave_backbone(model, K_WAVE, [0.1, 0.2, 0.3, 0.4])
    seen = []
    part = travelling_wave_backbone(model, K_WAVE, [0.1, 0.2, 0.3, 0.4],
                                    callback=lambda p: seen.append(p["a"]) or p["a"] >= 0.2)
    assert seen == [0.1, 0.2] and [p["a"] for p in part] == seen
    for p, f in zip(part, full):
        assert p["omega"] == f["omega"] and np.array_equal(p["q"], f["q"])


def test_wave_history_of_an_analytic_forward_wave():
    """u_j(t) = A cos(omega t - k theta_j) + B cos(2 omega t - 2 k theta_j + beta): sector 0's history is A cos(omega
    t) + B cos(2 omega t + beta), rebuilt from the snapshot at t = 0 (round-off)."""
    n, k, omega, A, B, beta = 36, 6, 8000.0, 1.3, 0.4, 0.7
    theta = 2 * np.pi * np.arange(n) / n
    snapshot = A * np.cos(-k * theta) + B * np.cos(-2 * k * theta + beta)
    t = np.arange(720) / 720 * 2 * np.pi / omega
    np.testing.assert_allclose(wave_history(snapshot, k, omega), A * np.cos(omega * t) + B * np.cos(2 * omega * t
                                                                                                 + beta), atol=1e-12)
    np.testing.assert_array_equal(wave_harmonic_order(36, 6), [0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 2, 0, 0, 0, 0, 0, 3])
    np.testing.assert_array_equal(wave_harmonic_order(36, 4)[[0, 4, 8, 12, 16]], [0, 1, 2, 3, 4])


def test_backbone_bad_input():
    model = _disk()
    with pytest.raises(ValueError, match="n_diameters must be in 1..5"):
        travelling_wave_backbone(model, 6, [1.0])
    for bad in ([0.0, 1.0], [np.nan], [np.inf]):
        with pytest.raises(ValueError, match="amplitudes must be finite modal amplitudes > 0"):
            travelling_wave_backbone(model, K_WAVE, bad)
    with pytest.raises(ValueError, match="family must be in"):
        travelling_wave_backbone(model, K_WAVE, [1.0], family=-1)
    with pytest.raises(ValueError, match="family must be in"):
        travelling_wave_backbone(model, K_WAVE, [1.0], family=50)
    with pytest.raises(ValueError, match="need a disk model"):
        travelling_wave_backbone(SimpleNamespace(sectors=None, K=model.K, M=model.M), K_WAVE, [1.0])


@pytest.mark.parametrize("args, option", [(["--le-max", "0"], "--le-max"), (["--points", "2"], "--points"),
                                          (["--model", "{text}"], "--model")])
def test_backbone_script_bad_input(tmp_path, args, option):
    """benchmarks/disk_backbone.py: one line on stderr naming the option, exit status 2, nothing written."""
    import subprocess
    import sys
    from pathlib import Path

    text = tmp_path / "notes.txt"
    text.write_text("not a reduced model\n")
    script = Path(__file__).resolve().parents[2] / "benchmarks" / "disk_backbone.py"
    proc = subprocess.run([sys.executable, str(script)] + [a.replace("{text}", str(text)) for a in args],
                          cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: " + option), proc.stderr
    assert not (tmp_path / "results").exists()
