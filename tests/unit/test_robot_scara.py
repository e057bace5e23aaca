"""Unit tests of pickplace_cli.robots.scara (serial SCARA, 2-link planar dynamics [Spong2006, Ch. 7]).

Every numeric assertion states its tolerance and why.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from pickplace_cli.model.errors import UnreachableError
from pickplace_cli.robots.scara import Elbow, ScaraRobot

MASSES = dict(m1=2.0, lc1=0.16, I1=0.020, m2=1.5, lc2=0.14, I2=0.012, m3=0.8, payload=0.1)
RIGHT = ScaraRobot(l1=0.325, l2=0.275, elbow="right", z0=0.0, **MASSES)
LEFT = ScaraRobot(l1=0.325, l2=0.275, elbow="left", z0=0.0, **MASSES)


# --------------------------------------------------------------------------- helpers
def sine_path(t, p0=(0.32, 0.18, -0.05), amp=(0.10, 0.12, 0.04), w=(6.0, 7.5, 9.0), ph=(0.3, 1.1, -0.4)):
    """p(t) = p0 + A sin(ωt + φ) per axis and its exact derivatives v, a, j (each (N, 3), SI)."""
    t = np.asarray(t, dtype=float)[:, None]
    p0, amp, w, ph = (np.asarray(x, dtype=float) for x in (p0, amp, w, ph))
    s, c = np.sin(w * t + ph), np.cos(w * t + ph)
    return p0 + amp * s, amp * w * c, -amp * w**2 * s, -amp * w**3 * c


T_SAMPLES = np.linspace(0.0, 1.0, 41)


def d1(f, t, h):
    """4th-order central first derivative (truncation h⁴ f⁽⁵⁾/30)."""
    return (-f(t + 2 * h) + 8 * f(t + h) - 8 * f(t - h) + f(t - 2 * h)) / (12 * h)


def d2(f, t, h):
    """4th-order central second derivative (truncation h⁴ f⁽⁶⁾/90)."""
    return (-f(t + 2 * h) + 16 * f(t + h) - 30 * f(t) + 16 * f(t - h) - f(t - 2 * h)) / (12 * h * h)


def d3(f, t, h):
    """4th-order central third derivative (truncation 7 h⁴ f⁽⁷⁾/120)."""
    return (
        -f(t + 3 * h) + 8 * f(t + 2 * h) - 13 * f(t + h) + 13 * f(t - h) - 8 * f(t - 2 * h) + f(t - 3 * h)
    ) / (8 * h**3)


def assert_rel(actual, expected, rtol, what):
    """max|actual − expected| ≤ rtol · max|expected| (scale-relative, robust to zero crossings)."""
    err = np.max(np.abs(actual - expected))
    scale = np.max(np.abs(expected))
    assert err <= rtol * scale, f"{what}: max error {err:.3g} > {rtol:g} × scale {scale:.3g}"


def kinetic_energy_from_link_velocities(robot: ScaraRobot, q, qd):
    """Independent KE: ½ m v_c² + ½ I ω² per link from the centre-of-mass velocities, plus the carried point mass."""
    q1, q12 = q[:, 0], q[:, 0] + q[:, 1]
    w1, w12 = qd[:, 0], qd[:, 0] + qd[:, 1]
    e1p = np.stack((-np.sin(q1), np.cos(q1)), axis=1)  # d/dq1 of (cos q1, sin q1)
    e12p = np.stack((-np.sin(q12), np.cos(q12)), axis=1)
    vc1 = robot.lc1 * w1[:, None] * e1p
    vc2 = robot.l1 * w1[:, None] * e1p + robot.lc2 * w12[:, None] * e12p
    vt = robot.l1 * w1[:, None] * e1p + robot.l2 * w12[:, None] * e12p
    mt = robot.m3 + robot.payload
    return (
        0.5 * robot.m1 * np.sum(vc1**2, axis=1)
        + 0.5 * robot.I1 * w1**2
        + 0.5 * robot.m2 * np.sum(vc2**2, axis=1)
        + 0.5 * robot.I2 * w12**2
        + 0.5 * mt * (np.sum(vt**2, axis=1) + qd[:, 2] ** 2)
    )


# --------------------------------------------------------------------------- parameters
def test_protocol_attributes():
    assert RIGHT.joint_names == ("q1", "q2", "q3")
    assert RIGHT.joint_units == ("rad", "rad", "m")
    assert RIGHT.elbow is Elbow.RIGHT and LEFT.elbow == "left"


@pytest.mark.parametrize(
    "field, value",
    [("l1", 0.0), ("l2", -0.2), ("m1", -1.0), ("payload", -0.1), ("I2", math.nan), ("lc2", -0.01), ("z0", math.inf)],
)
def test_non_physical_parameter_raises_value_error_naming_field(field, value):
    with pytest.raises(ValueError, match=rf"\b{field}\b"):
        dataclasses.replace(RIGHT, **{field: value})


def test_unknown_elbow_raises():
    with pytest.raises(ValueError, match="elbow"):
        ScaraRobot(l1=0.3, l2=0.2, elbow="up")


def test_bad_shape_raises_value_error():
    with pytest.raises(ValueError, match=r"q must have shape \(N, 3\)"):
        RIGHT.forward_kinematics(np.zeros((4, 2)))


# --------------------------------------------------------------------------- kinematics
def test_forward_kinematics_known_poses():
    q = np.array([[0.0, 0.0, 0.0], [np.pi / 2, 0.0, 0.1], [0.0, np.pi / 2, -0.2]])
    expected = np.array([[0.6, 0.0, 0.0], [0.0, 0.6, 0.1], [0.325, 0.275, -0.2]])
    # 1e-15 m: round-off of cos/sin at exact angles
    assert np.max(np.abs(RIGHT.forward_kinematics(q) - expected)) < 1e-15


def test_z0_offsets_the_prismatic_axis():
    robot = dataclasses.replace(RIGHT, z0=0.25)
    q = robot.inverse_kinematics(np.array([[0.4, 0.1, 0.05]]))
    assert q[0, 2] == pytest.approx(-0.2, abs=1e-15)  # q3 = z − z0, exact up to one subtraction


def test_elbow_branches_same_position_mirrored_angles():
    rng = np.random.default_rng(5)
    rho = rng.uniform(0.06, 0.59, 200)
    ang = rng.uniform(-np.pi, np.pi, 200)
    p = np.column_stack((rho * np.cos(ang), rho * np.sin(ang), rng.uniform(-0.2, 0.0, 200)))
    qr = RIGHT.inverse_kinematics(p)
    ql = LEFT.inverse_kinematics(p)
    assert np.all(qr[:, 1] < 0) and np.all(ql[:, 1] > 0)  # the documented convention
    # both branches reach the same point: 1e-12 m is round-off
    assert np.max(np.abs(RIGHT.forward_kinematics(qr) - p)) < 1e-12
    assert np.max(np.abs(LEFT.forward_kinematics(ql) - p)) < 1e-12
    # mirror images about the line base → tool: q2 flips sign (1e-12 rad, round-off)
    assert np.max(np.abs(qr[:, 1] + ql[:, 1])) < 1e-12


def test_outside_annulus_raises_naming_sample():
    p = np.array([[0.4, 0.0, 0.0], [0.0, 0.3, 0.0], [0.7, 0.0, 0.0], [0.01, 0.0, 0.0]])
    with pytest.raises(UnreachableError, match=r"sample 2 .*\(0\.7, 0, 0\) m") as info:
        RIGHT.inverse_kinematics(p)
    assert "\n" not in str(info.value) and info.value.exit_code == 4
    with pytest.raises(UnreachableError, match="sample 0"):
        LEFT.inverse_kinematics(p[3:])  # inside the inner hole ρ < l1 − l2 = 0.05 m


def test_annulus_boundaries_are_reachable():
    p = np.array([[0.6, 0.0, 0.0], [0.0, 0.05, 0.0]])
    q = RIGHT.inverse_kinematics(p)
    # fully stretched: q2 = 0; folded: |q2| = π (1e-7 rad: √eps round-off of the root at the boundary)
    assert abs(q[0, 1]) < 1e-7 and abs(abs(q[1, 1]) - np.pi) < 1e-7
    assert RIGHT.reachable(np.array([[0.6, 0, 0], [0.61, 0, 0], [0.049, 0, 0]])).tolist() == [True, False, False]


def test_jacobian_matches_finite_differences_of_fk_and_ik():
    rng = np.random.default_rng(8)
    q = np.column_stack((rng.uniform(-3, 3, 50), rng.uniform(0.2, 2.9, 50), rng.uniform(-0.2, 0.0, 50)))
    J = LEFT.jacobian(q)
    h = 1e-6  # truncation h²/6·|FK'''| ~ 1e-13, round-off eps/h ~ 1e-10
    fk, ik = LEFT.forward_kinematics, LEFT.inverse_kinematics
    fd = np.stack([(fk(q + h * e) - fk(q - h * e)) / (2 * h) for e in np.eye(3)], axis=2)
    assert_rel(J, fd, 1e-6, "J vs FD of FK")  # brief: 1e-6 relative, ~1e4 × the FD error
    p = LEFT.forward_kinematics(q)
    fdi = np.stack([(ik(p + h * e) - ik(p - h * e)) / (2 * h) for e in np.eye(3)], axis=2)
    assert_rel(np.linalg.inv(J), fdi, 1e-6, "J⁻¹ vs FD of IK")


def test_jacobian_derivatives_match_finite_differences():
    t = T_SAMPLES
    p, v, a, j = sine_path(t)
    q, qd, qdd, _ = RIGHT.joint_motion(p, v, a, j)
    J_of = lambda tt: RIGHT.jacobian(RIGHT.joint_motion(*sine_path(tt))[0])  # noqa: E731
    Jd_of = lambda tt: RIGHT.jacobian_dot(*RIGHT.joint_motion(*sine_path(tt))[:2])  # noqa: E731
    # 4th-order stencil, h = 1e-3 s: truncation ~h⁴ω⁵ (measured 2e-9 and 7e-9 relative); 1e-7 bound
    assert_rel(RIGHT.jacobian_dot(q, qd), d1(J_of, t, 1e-3), 1e-7, "J̇ vs FD")
    assert_rel(RIGHT.jacobian_ddot(q, qd, qdd), d1(Jd_of, t, 1e-3), 1e-7, "J̈ vs FD")


def test_joint_motion_matches_finite_differences_of_ik():
    for robot in (RIGHT, LEFT):
        t = T_SAMPLES
        p, v, a, j = sine_path(t)
        q, qd, qdd, qddd = robot.joint_motion(p, v, a, j)
        ik = lambda tt: robot.inverse_kinematics(sine_path(tt)[0])  # noqa: E731
        assert np.max(np.abs(q - ik(t))) < 1e-12  # q is exactly IK(p)
        # 4th-order stencils; h balances truncation ∝ h⁴ω^(k+4) against round-off ∝ eps/h^k. Measured
        # errors: 1e-11, 2e-10, 2e-8 relative; the bounds leave ≥ 50× margin and any wrong term shows at ≥ 1e-3
        assert_rel(qd, d1(ik, t, 3e-4), 1e-9, "q̇ vs FD")
        assert_rel(qdd, d2(ik, t, 5e-4), 1e-8, "q̈ vs FD")
        assert_rel(qddd, d3(ik, t, 1e-3), 1e-6, "q⃛ vs FD")
        # velocity relation, same algebra by another route: 1e-12 relative round-off
        assert_rel(np.einsum("nij,nj->ni", robot.jacobian(q), qd), v, 1e-12, "J q̇ vs v")


def test_singularity_measure():
    q = np.array([[0.3, 0.0, 0.0], [0.3, np.pi / 2, 0.0], [0.3, -np.pi / 2, 0.0], [0.1, np.pi, 0.0]])
    mu = RIGHT.singularity_measure(q, RIGHT.forward_kinematics(q))
    # |sin q2|; 1e-15 is the round-off of sin(π)
    assert np.allclose(mu, [0.0, 1.0, 1.0, 0.0], atol=1e-15, rtol=0)


# --------------------------------------------------------------------------- dynamics
def test_kinetic_energy_matches_link_velocities():
    rng = np.random.default_rng(2)
    q = rng.uniform(-3, 3, (100, 3))
    qd = rng.normal(size=(100, 3))
    # independent formulation (centre-of-mass velocities); 1e-12 relative is round-off
    assert_rel(RIGHT.kinetic_energy(q, qd), kinetic_energy_from_link_velocities(RIGHT, q, qd), 1e-12, "KE")
    M = RIGHT.mass_matrix(q)
    assert_rel(0.5 * np.einsum("ni,nij,nj->n", qd, M, qd), RIGHT.kinetic_energy(q, qd), 1e-12, "½ q̇ᵀMq̇")


def test_static_force_holds_carried_mass():
    q = np.array([[0.2, 1.0, -0.1]])
    zeros = np.zeros_like(q)
    torque = RIGHT.inverse_dynamics(q, zeros, zeros, RIGHT.forward_kinematics(q), zeros)
    # horizontal arm: no torque at rest; z axis lifts m3 + payload = 0.9 kg (exact up to one product)
    assert np.all(torque[0, :2] == 0.0)
    assert torque[0, 2] == pytest.approx(0.9 * 9.80665, rel=1e-15)


def test_power_balance_against_finite_difference_of_energy():
    for robot in (RIGHT, LEFT):
        t = T_SAMPLES
        p, v, a, j = sine_path(t)
        q, qd, qdd, _ = robot.joint_motion(p, v, a, j)
        power = np.sum(robot.inverse_dynamics(q, qd, qdd, p, a) * qd, axis=1)

        def energy(tt):
            qq, qqd, _, _ = robot.joint_motion(*sine_path(tt))
            return robot.kinetic_energy(qq, qqd) + robot.potential_energy(qq)

        # 4th-order central difference, h = 1e-3 s: truncation ~h⁴E⁽⁵⁾/30 dominates (measured 1.5e-8 of the
        # power scale), round-off eps·|E|/h ~ 1e-13 → the brief's 1e-6 relative holds with margin
        assert_rel(power, d1(energy, t, 1e-3), 1e-6, "Σ τ q̇ vs dE/dt")


def test_torque_matches_lagrange_equations_of_independent_energy():
    """τ = d/dt ∂T/∂q̇ − ∂T/∂q + ∂V/∂q with T from the link velocities (not the M(q) formula), all by FD."""
    t = T_SAMPLES
    p, v, a, j = sine_path(t)
    q, qd, qdd, _ = LEFT.joint_motion(p, v, a, j)
    torque = LEFT.inverse_dynamics(q, qd, qdd, p, a)
    T = lambda qq, qqd: kinetic_energy_from_link_velocities(LEFT, qq, qqd)  # noqa: E731
    V = lambda qq: (LEFT.m3 + LEFT.payload) * LEFT.g * (LEFT.z0 + qq[:, 2])  # noqa: E731
    E = np.eye(3)
    hv, hq = 1e-3, 1e-6  # T is quadratic in q̇ (exact central difference); hq: truncation ~1e-12

    def dT_dqd(tt):
        qq, qqd, _, _ = LEFT.joint_motion(*sine_path(tt))
        return np.stack([(T(qq, qqd + hv * e) - T(qq, qqd - hv * e)) / (2 * hv) for e in E], axis=1)

    dT_dq = np.stack([(T(q + hq * e, qd) - T(q - hq * e, qd)) / (2 * hq) for e in E], axis=1)
    dV_dq = np.stack([(V(q + hq * e) - V(q - hq * e)) / (2 * hq) for e in E], axis=1)
    lagrange = d1(dT_dqd, t, 1e-3) - dT_dq + dV_dq
    # 1e-6 relative: the FD errors above sum to ≲ 1e-8 of the torque scale
    assert_rel(torque, lagrange, 1e-6, "τ vs Lagrange equations")


def test_vectorised_shapes():
    p, v, a, j = sine_path(np.linspace(0, 1, 1000))
    out = RIGHT.joint_motion(p, v, a, j)
    assert all(x.shape == (1000, 3) for x in out)
    assert RIGHT.inverse_dynamics(out[0], out[1], out[2], p, a).shape == (1000, 3)
    assert RIGHT.singularity_measure(out[0], p).shape == (1000,)
