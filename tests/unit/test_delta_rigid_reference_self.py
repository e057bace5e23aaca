"""Self-consistency of the independent rigid-body Delta reference (tests/reference/delta_rigid.py).

The complex-step Lagrangian and the MuJoCo closed chain are two derivations of one model: they must agree
to rounding (plus MuJoCo's 1e-12 floor masses); the Lagrangian must balance power (τ·q̇ = dE/dt); the
torque rate must be the time derivative of the torque. Relative errors are taken against the batch's
largest torque (resp. rate) so that a near-zero component does not inflate them."""

from __future__ import annotations

import numpy as np
import pytest

from tests.reference import delta_rigid as ref

pytest.importorskip("mujoco")

CASES = {
    "default": ref.params(),
    "half rod mass in end fittings": ref.params(forearm_end_elbow=0.075, forearm_end_plate=0.075),
    "uneven ends, explicit rod inertia": ref.params(forearm_end_elbow=0.05, forearm_end_plate=0.02,
                                                    forearm_rod_inertia=0.004),
    "heavy payload, light arm": ref.params(payload=2.0, upper_arm_mass=0.3, upper_arm_inertia=0.012,
                                           forearm_pair=0.6),
    "lumped (2/3 elbow, 1/3 plate)": ref.lumped_params(ref.params()),
    "other geometry": ref.params(R=0.2, r=0.04, L=0.35, l=0.75, upper_arm_com=0.1),
}


def random_motion(P: dict, n: int, seed: int):
    """Random reachable configurations (plate in a cylinder under the base, clear of singularities) with
    random joint velocities, accelerations and jerks of pick-and-place size."""
    rng = np.random.default_rng(seed)
    depth = P["l"] + 0.3 * P["L"]
    p = np.column_stack((rng.uniform(-0.2, 0.2, n), rng.uniform(-0.2, 0.2, n),
                         rng.uniform(-depth - 0.1, -depth + 0.1, n)))
    q = ref.inverse_kinematics(P, p)
    return (q, rng.normal(0.0, 3.0, (n, 3)), rng.normal(0.0, 60.0, (n, 3)), rng.normal(0.0, 2000.0, (n, 3)))


def rel(a: np.ndarray, b: np.ndarray) -> float:
    """max |a − b| relative to the batch's largest |b|."""
    return float(np.abs(a - b).max() / np.abs(b).max())


@pytest.mark.parametrize("name", list(CASES))
def test_lagrange_and_mujoco_agree(name):
    # measured ≤ 4e-12 (python -m tests.reference.measure_delta_rigid); tolerance 1e-9 leaves room for MuJoCo's 1e-12 floor masses
    # and the least-squares solve's conditioning, far inside the 1e-6 the library is held to
    P = CASES[name]
    q, qd, qdd, _ = random_motion(P, 40, seed=len(name))
    diagnostics: list = []
    lag = ref.reference_torques(P, q, qd, qdd)
    muj = ref.reference_torques(P, q, qd, qdd, method="mujoco", diagnostics=diagnostics)
    assert rel(muj, lag) < 1e-9
    gap, vel, force = np.max(diagnostics, axis=0)
    assert gap < 1e-12  # m: the prescribed configuration closes every loop (rounding only)
    assert vel < 1e-12  # m/s: and the prescribed velocities satisfy the constraints
    assert force < 1e-9 * np.abs(lag).max()  # N·m: Sᵀτ + J_cᵀλ = f is consistent (rounding only)


def test_static_torques_agree_and_gravity_pulls_arms_down():
    # at rest the torque holds gravity: q > 0 is downwards, so a motor must push every arm up (τ < 0) —
    # the sign is what a power balance alone would not see. Tolerance as above.
    P = CASES["default"]
    q, _, _, _ = random_motion(P, 20, seed=7)
    zero = np.zeros_like(q)
    lag = ref.reference_torques(P, q, zero, zero)
    assert rel(ref.reference_torques(P, q, zero, zero, method="mujoco"), lag) < 1e-9
    centre = ref.inverse_kinematics(P, np.array([[0.0, 0.0, -0.9]]))
    held = ref.reference_torques(P, centre, np.zeros((1, 3)), np.zeros((1, 3)))
    assert np.all(held < 0) and np.ptp(held) < 1e-12 * np.abs(held).max()  # symmetric pose: equal torques


def _trajectory(P: dict, t: np.ndarray):
    """q(t) = q0 + A sin(ωt + ψ) per joint, with its exact derivatives (N, 3) each."""
    q0 = ref.inverse_kinematics(P, np.array([[0.05, -0.08, -0.95]]))[0]
    A, w, psi = np.array([0.25, 0.2, 0.3]), np.array([7.0, 9.0, 11.0]), np.array([0.3, 1.1, 2.0])
    ph = w * t[:, None] + psi
    return (q0 + A * np.sin(ph), A * w * np.cos(ph), -A * w**2 * np.sin(ph), -A * w**3 * np.cos(ph))


@pytest.mark.parametrize("name", ["default", "half rod mass in end fittings", "uneven ends, explicit rod inertia"])
def test_power_balance(name):
    # Σ τ_i q̇_i = d/dt (T + V): dE/dt by an 8th-order central difference in time (h = 1e-3 s; truncation
    # ~(ωh)⁸ ≈ 1e-17, rounding ~1e-13 relative). Measured ≤ 1e-11; tolerance 1e-9.
    P = CASES[name]
    t = np.linspace(0.0, 0.6, 61)
    q, qd, qdd, _ = _trajectory(P, t)
    torque = ref.reference_torques(P, q, qd, qdd)
    power = (torque * qd).sum(axis=1)
    h, dE = 1e-3, np.zeros_like(t)
    for k, w in enumerate(ref._FD, start=1):
        for sgn in (1.0, -1.0):
            qk, qdk, _, _ = _trajectory(P, t + sgn * k * h)
            T, V = ref.reference_energy(P, qk, qdk)
            dE += sgn * w * (T + V)
    dE /= h
    assert rel(power, dE) < 1e-9


@pytest.mark.parametrize("method", ["lagrange", "mujoco"])
def test_torque_rate_is_the_time_derivative(method):
    # reference_torque_rate (directional 8th-order difference) against an independent time difference of
    # τ(q(t)) along an analytic trajectory (8th order, h = 1e-3 s) and against itself at half the step.
    # Measured ≈ 1e-13 (lagrange; measure_delta_rigid), mujoco adds its 1e-12 floors divided by the step; tolerance
    # 1e-8, far inside the 1e-4 the library's torque rate is held to.
    P = CASES["half rod mass in end fittings"]
    t = np.linspace(0.0, 0.6, 13 if method == "mujoco" else 61)
    q, qd, qdd, qddd = _trajectory(P, t)
    rate = ref.reference_torque_rate(P, q, qd, qdd, qddd, method=method)
    h, fd = 1e-3, np.zeros_like(q)
    for k, w in enumerate(ref._FD, start=1):
        for sgn in (1.0, -1.0):
            fd += sgn * w * ref.reference_torques(P, *_trajectory(P, t + sgn * k * h)[:3], method=method)
    fd /= h
    assert rel(rate, fd) < 1e-8
    half = ref.reference_torque_rate(P, q, qd, qdd, qddd, method=method, step=5e-3)
    assert rel(half, rate) < 1e-8


def test_random_rates_step_convergence():
    # on random (q, q̇, q̈, q⃛) the rate at step 1e-2 and 5e-3 agree (truncation and rounding both small):
    # measured ≤ 1e-13; tolerance 1e-9
    P = CASES["default"]
    q, qd, qdd, qddd = random_motion(P, 200, seed=3)
    a = ref.reference_torque_rate(P, q, qd, qdd, qddd)
    b = ref.reference_torque_rate(P, q, qd, qdd, qddd, step=5e-3)
    assert rel(a, b) < 1e-9


def test_uniform_rod_default_and_kinematics():
    # None = uniform rod m_rod·l²/12 (exact: the same arithmetic, tolerance rounding 1e-14); FK∘IK = identity
    # to 1e-12 m (two Newton steps after trilateration); the end fittings change the torques (the model
    # sees them: > 1 % on these motions)
    P = CASES["default"]
    q, qd, qdd, _ = random_motion(P, 50, seed=11)
    explicit = ref.params(forearm_rod_inertia=0.3 * 0.8**2 / 12.0)
    assert rel(ref.reference_torques(explicit, q, qd, qdd), ref.reference_torques(P, q, qd, qdd)) < 1e-14
    p = ref.forward_kinematics(P, q)
    assert np.abs(ref.inverse_kinematics(P, p) - q).max() < 1e-12
    ends = ref.reference_torques(CASES["half rod mass in end fittings"], q, qd, qdd)
    assert rel(ends, ref.reference_torques(P, q, qd, qdd)) > 1e-2


def test_end_fittings_must_fit_in_the_pair():
    with pytest.raises(ValueError, match="exceed"):
        ref.reference_torques(ref.params(forearm_end_elbow=0.2, forearm_end_plate=0.2), np.zeros((1, 3)),
                              np.zeros((1, 3)), np.zeros((1, 3)))
