"""Unit tests of pickplace_cli.robots.rotary: the rotary fourth axis on a SCARA (J4 at the end of link 2) and on
a Delta (a motor on the base driving the tool through a telescopic shaft).

References, all written here: the SCARA's torques against the Euler–Lagrange equations of an independently
written Lagrangian (link centre-of-mass velocities + ½·J_t·(q̇1 + q̇2 + σq̇4)², differentiated numerically, the
project's reference-free check of tests/unit/test_robot_scara.py) on random states; the Delta's fourth axis
against its closed form τ4 = σ·J_t·θ̈; joint rates against finite differences of the inverse kinematics;
torque rates against finite differences of the torques; the power balance Σ τ·q̇ = dE/dt.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from pickplace_cli.robots.delta import DeltaRobot
from pickplace_cli.robots.rotary import RotaryAxisRobot
from pickplace_cli.robots.scara import ScaraRobot

MASSES = dict(m1=2.0, lc1=0.16, I1=0.020, m2=1.5, lc2=0.14, I2=0.012, m3=0.8, payload=0.1)
J_T = 1.6e-3  # kg m²: shaft + tool + payload about the tool axis


def scara4(elbow="right", sign=1.0, inertia=J_T):
    base = ScaraRobot(l1=0.325, l2=0.275, elbow=elbow, z0=0.0, **MASSES)
    return RotaryAxisRobot(base, inertia=inertia, sign=sign, carrier=(1.0, 1.0, 0.0))


DELTA = DeltaRobot(R=0.150, r=0.051, L=0.325, l=0.800, upper_arm_inertia=0.030, upper_arm_mass=1.0,
                   upper_arm_com=0.13, elbow_mass=0.10, forearm_mass=0.30, plate_mass=0.50, payload=0.1)


def delta4(sign=1.0):
    return RotaryAxisRobot(DELTA, inertia=2.06e-4, sign=sign, carrier=(0.0, 0.0, 0.0))


def assert_rel(actual, expected, rtol, what):
    """max|actual − expected| ≤ rtol · max|expected| (scale-relative, robust to zero crossings)."""
    err = np.max(np.abs(np.asarray(actual) - np.asarray(expected)))
    scale = np.max(np.abs(expected))
    assert err <= rtol * scale, f"{what}: max error {err:.3g} > {rtol:g} × scale {scale:.3g}"


def d1(f, t, h):
    """4th-order central first derivative (truncation h⁴ f⁽⁵⁾/30)."""
    return (-f(t + 2 * h) + 8 * f(t + h) - 8 * f(t - h) + f(t - 2 * h)) / (12 * h)


def sine_pose(t, p0=(0.32, 0.18, -0.05), amp=(0.10, 0.12, 0.04), w=(6.0, 7.5, 9.0), ph=(0.3, 1.1, -0.4),
              th=(0.4, 1.3, 5.0, 0.2)):
    """p(t) and θ(t) = θ0 + A sin(ωt + φ) with exact derivatives: (p, v, a, j) each (N, 3), angle (4, N)."""
    t = np.asarray(t, float)[:, None]
    p0, amp, w, ph = (np.asarray(x, float) for x in (p0, amp, w, ph))
    s, c = np.sin(w * t + ph), np.cos(w * t + ph)
    t0, ta, tw, tp = th
    ss, cc = np.sin(tw * t[:, 0] + tp), np.cos(tw * t[:, 0] + tp)
    angle = np.stack([t0 + ta * ss, ta * tw * cc, -ta * tw**2 * ss, -ta * tw**3 * cc])
    return (p0 + amp * s, amp * w * c, -amp * w**2 * s, -amp * w**3 * c), angle


def kinetic_energy_independent(robot: RotaryAxisRobot, q, qd):
    """KE from the bodies' velocities: links by their centres of mass, the carried point mass at the end of link 2,
    and the turning tool ½·J_t·ω² with ω = q̇1 + q̇2 + σ·q̇4 its absolute angular velocity (not the code's M(q))."""
    b = robot.base
    q1, q12 = q[:, 0], q[:, 0] + q[:, 1]
    w1, w12 = qd[:, 0], qd[:, 0] + qd[:, 1]
    e1p = np.stack((-np.sin(q1), np.cos(q1)), axis=1)
    e12p = np.stack((-np.sin(q12), np.cos(q12)), axis=1)
    vc1 = b.lc1 * w1[:, None] * e1p
    vc2 = b.l1 * w1[:, None] * e1p + b.lc2 * w12[:, None] * e12p
    vt = b.l1 * w1[:, None] * e1p + b.l2 * w12[:, None] * e12p
    mt = b.m3 + b.payload
    omega_tool = qd[:, 0] + qd[:, 1] + robot.sign * qd[:, 3]
    return (0.5 * b.m1 * np.sum(vc1**2, axis=1) + 0.5 * b.I1 * w1**2 + 0.5 * b.m2 * np.sum(vc2**2, axis=1)
            + 0.5 * b.I2 * w12**2 + 0.5 * mt * (np.sum(vt**2, axis=1) + qd[:, 2] ** 2)
            + 0.5 * robot.inertia * omega_tool**2)


def lagrange_torque(robot: RotaryAxisRobot, q, qd, qdd):
    """τ = d/dt ∂T/∂q̇ − ∂T/∂q + ∂V/∂q at one state per row, with d/dt ∂T/∂q̇ = (∂²T/∂q̇²) q̈ + (∂²T/∂q̇∂q) q̇,
    all by central differences of the independent T and V = m_t g (z0 + q3)."""
    b = robot.base
    E = np.eye(4)
    hv, hq = 1e-3, 1e-5  # T is quadratic in q̇ (central differences exact up to round-off); hq: truncation ~1e-10

    def T(qq, qqd):
        return kinetic_energy_independent(robot, qq, qqd)

    def dT_dqd(qq, qqd):
        return np.stack([(T(qq, qqd + hv * e) - T(qq, qqd - hv * e)) / (2 * hv) for e in E], axis=1)

    H_vv = np.stack([(dT_dqd(q, qd + hv * e) - dT_dqd(q, qd - hv * e)) / (2 * hv) for e in E], axis=2)
    H_vq = np.stack([(dT_dqd(q + hq * e, qd) - dT_dqd(q - hq * e, qd)) / (2 * hq) for e in E], axis=2)
    dT_dq = np.stack([(T(q + hq * e, qd) - T(q - hq * e, qd)) / (2 * hq) for e in E], axis=1)
    dV_dq = np.zeros_like(q)
    dV_dq[:, 2] = (b.m3 + b.payload) * b.g
    return np.einsum("nij,nj->ni", H_vv, qdd) + np.einsum("nij,nj->ni", H_vq, qd) - dT_dq + dV_dq


def random_states(seed, n=60):
    rng = np.random.default_rng(seed)
    q = np.column_stack([rng.uniform(-2.3, 2.3, n), rng.uniform(-2.6, 2.6, n), rng.uniform(-0.2, 0.0, n),
                         rng.uniform(-6.0, 6.0, n)])
    return q, rng.normal(scale=3.0, size=(n, 4)), rng.normal(scale=30.0, size=(n, 4))


@pytest.mark.parametrize("elbow, sign", [("right", 1.0), ("left", 1.0), ("right", -1.0)])
def test_scara_j4_torque_matches_euler_lagrange_of_an_independent_lagrangian(elbow, sign):
    robot = scara4(elbow, sign)
    for seed in (1, 2, 3):
        q, qd, qdd = random_states(seed)
        p = robot.forward_kinematics(q)
        torque = robot.inverse_dynamics(q, qd, qdd, p, np.zeros_like(p))
        # the bound: 1e-6 relative to the torque scale; the differences above err by ≲ 1e-8 of it
        assert_rel(torque, lagrange_torque(robot, q, qd, qdd), 1e-6, f"τ (elbow {elbow}, σ = {sign:+g})")
        # J4 alone, on its own scale (it is ~100× smaller than J1's): the coupling J_t·(q̈1 + q̈2 + σq̈4)
        assert_rel(torque[:, 3], lagrange_torque(robot, q, qd, qdd)[:, 3], 1e-6, "τ4")


def test_scara_j4_coupling_by_hand():
    # a hand case: J4 held (q̈4 = 0) while the arm accelerates q̈1 = 10, q̈2 = -4 rad/s² from rest: the tool's
    # absolute angular acceleration is 6 rad/s², so J4 must give σ·J_t·6 and J1, J2 each carry J_t·6 more than
    # the 3-joint arm (exact but for one product: 1e-15 relative)
    robot = scara4(sign=-1.0)
    q = np.array([[0.3, -1.0, -0.1, 0.5]])
    qdd = np.array([[10.0, -4.0, 0.0, 0.0]])
    zero = np.zeros_like(q)
    p = robot.forward_kinematics(q)
    tau = robot.inverse_dynamics(q, zero, qdd, p, np.zeros((1, 3)))
    arm = robot.base.inverse_dynamics(q[:, :3], zero[:, :3], qdd[:, :3], p, np.zeros((1, 3)))
    assert tau[0, 3] == pytest.approx(-J_T * 6.0, rel=1e-14)
    assert tau[0, :2] - arm[0, :2] == pytest.approx([J_T * 6.0, J_T * 6.0], rel=1e-12)
    assert tau[0, 2] == pytest.approx(arm[0, 2], rel=1e-15)


def test_scara_tool_angle_and_joint_motion():
    robot = scara4(sign=-1.0)
    t = np.linspace(0.0, 1.0, 41)
    (p, v, a, j), angle = sine_pose(t)
    q, qd, qdd, qddd = robot.joint_motion(p, v, a, j, angle)
    # the tool angle of the joints is the planned angle: θ = q1 + q2 + σ q4 (1e-12 rad: round-off)
    assert np.max(np.abs(robot.tool_angle(q) - angle[0])) < 1e-12
    assert np.max(np.abs(q[:, :3] - robot.base.inverse_kinematics(p))) < 1e-12
    # q4's rates against 4th-order differences of the inverse kinematics (as test_robot_scara.py: 1e-9, 1e-8, 1e-6)
    q4 = lambda tt: robot.inverse_kinematics(sine_pose(tt)[0][0], sine_pose(tt)[1][0])[:, 3]  # noqa: E731
    assert_rel(qd[:, 3], d1(q4, t, 3e-4), 1e-9, "q̇4")
    q4d = lambda tt: robot.joint_motion(*sine_pose(tt)[0], sine_pose(tt)[1])[1][:, 3]  # noqa: E731
    assert_rel(qdd[:, 3], d1(q4d, t, 3e-4), 1e-8, "q̈4")
    q4dd = lambda tt: robot.joint_motion(*sine_pose(tt)[0], sine_pose(tt)[1])[2][:, 3]  # noqa: E731
    assert_rel(qddd[:, 3], d1(q4dd, t, 3e-4), 1e-7, "q⃛4")


@pytest.mark.parametrize("make", [lambda: scara4("left"), lambda: delta4(-1.0)], ids=["scara", "delta"])
def test_power_balance_and_torque_rate(make):
    robot = make()
    t = np.linspace(0.0, 1.0, 41)
    if robot.base.__class__ is DeltaRobot:
        sine = dict(p0=(0.02, -0.03, -0.8), amp=(0.1, 0.08, 0.04))
    else:
        sine = {}
    (p, v, a, j), angle = sine_pose(t, **sine)
    q, qd, qdd, qddd = robot.joint_motion(p, v, a, j, angle)
    torque = robot.inverse_dynamics(q, qd, qdd, p, a)
    power = np.sum(torque * qd, axis=1)

    def energy(tt):
        (pp, vv, aa, jj), an = sine_pose(tt, **sine)
        qq, qqd, _, _ = robot.joint_motion(pp, vv, aa, jj, an)
        return robot.kinetic_energy(qq, qqd, vv) + robot.potential_energy(qq, pp)

    # Σ τ q̇ = dE/dt: 4th-order difference, h = 1e-3 s (truncation ~1e-8 of the power scale): 1e-6 relative
    assert_rel(power, d1(energy, t, 1e-3), 1e-6, "Σ τ q̇ vs dE/dt")
    dA, dG = robot.torque_rate(q, qd, qdd, qddd, p, v, a, j)

    def tq(tt):
        (pp, vv, aa, jj), an = sine_pose(tt, **sine)
        qq, qqd, qqdd, _ = robot.joint_motion(pp, vv, aa, jj, an)
        return robot.inverse_dynamics(qq, qqd, qqdd, pp, aa)

    # the analytic torque rate against differences of the torque (h = 1e-4 s: truncation ~1e-9 relative)
    assert_rel(dA + dG, d1(tq, t, 1e-4), 1e-6, "dτ/dt")
    # the one-pass method gives the same numbers as the separate ones (round-off)
    out = robot.motion_and_dynamics(p, v, a, j, rates=True, angle=angle)
    assert_rel(out[4] + out[5], torque, 1e-10, "A + G")
    assert_rel(out[6] + out[7], dA + dG, 1e-10, "dA + dG")


def test_delta_fourth_axis_closed_form():
    """On the Delta the plate does not turn: q4 = σθ, τ4 = σ·J_t·θ̈, the arms' torques are the 3-axis robot's."""
    for sign in (1.0, -1.0):
        robot = delta4(sign)
        t = np.linspace(0.0, 1.0, 31)
        (p, v, a, j), angle = sine_pose(t, p0=(0.02, -0.03, -0.8), amp=(0.1, 0.08, 0.04))
        q, qd, qdd, qddd = robot.joint_motion(p, v, a, j, angle)
        for k, x in enumerate((q, qd, qdd, qddd)):
            assert np.max(np.abs(x[:, 3] - sign * angle[k])) <= 1e-12 * max(1.0, np.max(np.abs(angle[k])))
        torque = robot.inverse_dynamics(q, qd, qdd, p, a)
        # closed form: J_t θ̈ times σ (1e-14 relative: one product)
        assert np.max(np.abs(torque[:, 3] - sign * 2.06e-4 * angle[2])) <= 1e-14 * np.max(np.abs(2.06e-4 * angle[2]))
        # the arms see nothing of the turn (bitwise: the same base computation)
        assert np.array_equal(torque[:, :3], DELTA.inverse_dynamics(q[:, :3], qd[:, :3], qdd[:, :3], p, a))
        assert np.array_equal(robot.forward_kinematics(q), DELTA.forward_kinematics(q[:, :3]))


def test_without_an_angle_the_tool_angle_is_held_at_zero():
    robot = scara4()
    t = np.linspace(0.0, 1.0, 11)
    (p, v, a, j), _ = sine_pose(t)
    q, qd, qdd, _ = robot.joint_motion(p, v, a, j)
    # θ ≡ 0: J4 counter-rotates the arm exactly (1e-12: round-off)
    assert np.max(np.abs(robot.tool_angle(np.column_stack([q[:, :3], q[:, 3]])))) < 1e-12
    assert np.max(np.abs(qd[:, 3] + qd[:, 0] + qd[:, 1])) < 1e-12
    tau = robot.inverse_dynamics(q, qd, qdd, p, a)
    assert np.max(np.abs(tau[:, 3])) < 1e-15  # the tool does not turn: no torque on J4 (its rotor aside)


def test_parameter_checks():
    with pytest.raises(ValueError, match="inertia"):
        scara4(inertia=-1.0)
    with pytest.raises(ValueError, match="sign"):
        scara4(sign=2.0)
    with pytest.raises(ValueError, match="carrier"):
        RotaryAxisRobot(DELTA, carrier=(1.0, 1.0))
    robot = scara4()
    assert robot.joint_names == ("q1", "q2", "q3", "q4") and robot.joint_units == ("rad", "rad", "m", "rad")
    assert dataclasses.replace(robot, inertia=0.0).inertia == 0.0
