"""Residual vibration (pickplace_cli.studies.vibration) against scipy.signal.lsim, and the profile section."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import lsim

from pickplace_cli.studies import vibration as vib
from pickplace_cli.model.errors import ProfileError
from pickplace_cli.paths import plan_path
from pickplace_cli.model.profile import load_profile, parse_profile, resolve_profile_path
from pickplace_cli.model.task import Task
from pickplace_cli.model.trajectory import CartesianTrajectory
from tests.conftest import ADEPT_FROM, ADEPT_TO

F = np.array([18.0, 18.0, 25.0])  # Hz (Delta-like estimates)
Z = np.array([0.03, 0.03, 0.03])


def _traj(duration: float = 0.18, p_to=ADEPT_TO) -> CartesianTrajectory:
    task = Task(ADEPT_FROM, p_to, 0.025)
    return CartesianTrajectory(plan_path(task, "bspline"), duration)


def _lsim_state(traj, axis: int, dt: float, after: float = 0.0):
    """lsim of ẍ + 2ζωẋ + ω²x = −a(t), state output (x, ẋ), a sampled every dt and zero after T."""
    T = traj.duration
    n = int(round((T + after) / dt))
    t = np.linspace(0.0, n * dt, n + 1)
    a = np.where(t <= T, traj(np.minimum(t, T), 2)[:, axis], 0.0)
    w = 2 * np.pi * F[axis]
    A = np.array([[0.0, 1.0], [-w * w, -2 * Z[axis] * w]])
    B = np.array([[0.0], [-1.0]])
    _, y, _ = lsim((A, B, np.eye(2), np.zeros((2, 1))), a, t)
    return t, y


def test_state_at_end_matches_lsim_and_lsim_converges_to_it():
    """lsim (first-order hold of the sampled acceleration) converges to the Duhamel value at second order.

    Tolerance: the hold's error is O(dt²); measured 1.0e-5 (x) and 2.0e-5 (z) relative at dt = 1e-4 s, so at
    dt = 2.5e-5 s it is ~1.3e-6 — we allow 3e-6. The error ratio between dt and dt/2 must be ≈ 4 (3.5–4.5),
    which shows lsim converges to *this* value (a constant offset would give a ratio near 1)."""
    traj = _traj()
    x, xd = vib.mode_state(traj, F, Z)
    for axis in (0, 2):  # the move is in the x-z plane; y is tested below
        errs = []
        for dt in (1e-4, 5e-5, 2.5e-5):
            t, y = _lsim_state(traj, axis, dt)
            assert t[-1] == pytest.approx(traj.duration, abs=1e-12)
            errs.append((abs(y[-1, 0] - x[axis]) / abs(x[axis]), abs(y[-1, 1] - xd[axis]) / abs(xd[axis])))
        assert errs[-1][0] < 3e-6 and errs[-1][1] < 3e-6, errs
        for k in (0, 1):
            assert 3.5 < errs[0][k] / errs[1][k] < 4.5, errs
            assert 3.5 < errs[1][k] / errs[2][k] < 4.5, errs


def test_free_decay_after_the_move_matches_the_closed_form_envelope():
    """After T the lsim response is a damped sinusoid under the envelope A·e^{−ζω(t−T)}; its peaks touch it.

    Tolerance 1e-4 relative: lsim at dt = 2e-5 s carries ~6e-7 relative error from the move (test above)
    plus the sampling of the peak: |x| near a peak varies as 1 − (ω_d δt)²/2 with δt ≤ dt/2 (~5e-6)."""
    traj = _traj()
    res = vib.residual_vibration(traj, type("V", (), {"frequency": F, "damping": Z})())
    for axis in (0, 2):
        t, y = _lsim_state(traj, axis, 2e-5, after=0.5)
        after = t >= traj.duration
        ta, xa, xda = t[after] - traj.duration, y[after, 0], y[after, 1]
        w = 2 * np.pi * F[axis]
        env = res.amplitude[axis] * np.exp(-Z[axis] * w * ta)
        assert np.all(np.abs(xa) <= env * (1 + 1e-4))
        # |x| touches the envelope once per half period: the local maxima of |x| / envelope → 1
        ratio = np.abs(xa) / env
        peaks = (ratio[1:-1] >= ratio[:-2]) & (ratio[1:-1] >= ratio[2:])
        # the first maxima after T: ratio = cos of the phase lag of the damped sinusoid's peak (≈ 1 − ζ²/2)
        assert np.max(ratio[1:-1][peaks]) == pytest.approx(1.0, abs=1e-3)
        # residual acceleration of the mode (what a plate accelerometer reads after the move): envelope ω²·A
        acc = -2 * Z[axis] * w * xda - w * w * xa
        assert np.all(np.abs(acc) <= w * w * env * (1 + 1e-4))
        assert np.max(np.abs(acc) / (w * w * env)) == pytest.approx(1.0, abs=1e-3)
        assert res.acceleration_amplitude[axis] == pytest.approx(w * w * res.amplitude[axis], rel=1e-14)


def test_quadrature_is_converged():
    """Halving the sub-interval size (and doubling the nodes' count) changes x(T) by < 1e-12 relative."""
    traj = _traj()
    x0, xd0 = vib.mode_state(traj, F, Z)
    old = (vib.MAX_PERIOD_FRACTION, vib.MIN_SUBINTERVALS)
    try:
        vib.MAX_PERIOD_FRACTION, vib.MIN_SUBINTERVALS = old[0] / 4, old[1] * 4
        x1, xd1 = vib.mode_state(traj, F, Z)
    finally:
        vib.MAX_PERIOD_FRACTION, vib.MIN_SUBINTERVALS = old
    np.testing.assert_allclose(x1, x0, rtol=1e-12, atol=1e-18)
    np.testing.assert_allclose(xd1, xd0, rtol=1e-12, atol=1e-16)


def test_axis_without_motion_does_not_ring_and_diagonal_moves_excite_both():
    x, _ = vib.mode_state(_traj(), F, Z)
    assert x[1] == 0.0  # the Adept move has no y motion: exactly zero
    diag = _traj(p_to=ADEPT_FROM + np.array([0.2, 0.2, 0.0]))
    x2, xd2 = vib.mode_state(diag, F, Z)
    # x and y see the same acceleration and the same mode: identical state
    assert x2[0] == pytest.approx(x2[1], rel=1e-12)
    assert xd2[0] == pytest.approx(xd2[1], rel=1e-12)


def test_undamped_amplitude_is_the_energy_amplitude():
    """ζ = 0: A = √(x² + (ẋ/ω)²) (energy conservation), exactly."""
    amp = vib.residual_amplitude([0.003, -0.001, 0.0], [0.2, 0.5, 0.0], [10.0, 20.0, 30.0], [0.0, 0.0, 0.0])
    w = 2 * np.pi * np.array([10.0, 20.0])
    np.testing.assert_allclose(amp[:2], np.hypot([0.003, -0.001], np.array([0.2, 0.5]) / w), rtol=1e-15)
    assert amp[2] == 0.0


def test_settling_time():
    r = vib.ResidualVibration(F, Z, np.zeros(3), np.zeros(3), np.array([1e-3, 0.0, 1e-4]), np.zeros(3))
    # envelope 1e-3·e^{−ζωt} reaches 1e-5 after ln(100)/(ζω)
    assert r.settling_time(1e-5) == pytest.approx(np.log(100) / (0.03 * 2 * np.pi * 18), rel=1e-12)
    assert r.settling_time(1e-2) == 0.0
    undamped = vib.ResidualVibration(F, np.zeros(3), np.zeros(3), np.zeros(3), np.array([1e-3, 0, 0]), np.zeros(3))
    assert undamped.settling_time(1e-5) == float("inf")
    with pytest.raises(ValueError, match="tolerance"):
        r.settling_time(0.0)


@pytest.mark.parametrize(
    "freq, damp, match",
    [([0.0, 1.0, 1.0], [0.1] * 3, "frequency"), ([1.0] * 3, [1.0, 0.1, 0.1], "damping"),
     ([np.nan, 1, 1], [0.1] * 3, "frequency"), ([1.0] * 3, [-0.1, 0.1, 0.1], "damping")],
)
def test_bad_modes_raise_profile_error(freq, damp, match):
    with pytest.raises(ProfileError, match=match):
        vib.mode_state(_traj(), freq, damp)


def test_shipped_profiles_have_vibration_and_the_section_is_validated():
    for name in ("delta-su2018", "scara-600", "gantry"):
        v = load_profile(name).vibration
        assert v is not None and len(v.frequency) == 3 and all(0 < z < 1 for z in v.damping)
    text = resolve_profile_path("gantry").read_text(encoding="utf-8")
    with pytest.raises(ProfileError, match=r"vibration\.frequency\.1 = -1: Input should be greater than 0"):
        parse_profile(text.replace("[10.0, 12.0, 20.0]", "[10.0, -1, 20.0]"), "g.yaml")
    with pytest.raises(ProfileError, match=r"vibration\.damping\.0 = 1.0: Input should be less than 1"):
        parse_profile(text.replace("[0.05, 0.05, 0.05]", "[1.0, 0.05, 0.05]"), "g.yaml")
    with pytest.raises(ProfileError, match="unknown key 'vibration.mode'"):
        parse_profile(text.replace("  damping: [0.05", "  mode: 1\n  damping: [0.05"), "g.yaml")
    no_vib = text.split("vibration:")[0]
    assert parse_profile(no_vib, "g.yaml").vibration is None
