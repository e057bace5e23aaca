"""Property tests of the robot models (hypothesis): IK∘FK identities, velocity and power identities,
over random points, joint values, states and (for the identities that hold for any geometry) random
robot dimensions. Every numeric assertion states its tolerance and why.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from pickplace_cli.model.errors import UnreachableError
from pickplace_cli.robots.delta import DeltaRobot
from pickplace_cli.robots.scara import ScaraRobot

DELTA = DeltaRobot(
    R=0.150, r=0.051, L=0.325, l=0.800,  # Su 2018 prototype
    upper_arm_inertia=0.030, upper_arm_mass=1.0, upper_arm_com=0.13,
    elbow_mass=0.10, forearm_mass=0.30, plate_mass=0.40, payload=0.1,
)  # fmt: skip
LUMPED = dataclasses.replace(DELTA, dynamics="lumped")
FITTED = dataclasses.replace(DELTA, forearm_end_elbow=0.05, forearm_end_plate=0.1, forearm_rod_inertia=0.004)
SCARA_MASSES = dict(m1=2.0, lc1=0.16, I1=0.020, m2=1.5, lc2=0.14, I2=0.012, m3=0.8, payload=0.1)
SCARAS = {e: ScaraRobot(l1=0.325, l2=0.275, elbow=e, z0=0.0, **SCARA_MASSES) for e in ("left", "right")}

SETTINGS = settings(max_examples=150, deadline=None)

#: identity tolerance of the brief: 1e-9 m / rad, ~1e6 × the round-off actually seen
IDENTITY_TOL = 1e-9


def fl(lo, hi):
    return st.floats(lo, hi, allow_nan=False, allow_infinity=False)


def rows(*ranges, max_size=16):
    """(N, len(ranges)) float arrays, N ∈ [1, max_size], column k uniform-ish in ranges[k]."""
    return st.lists(st.tuples(*(fl(lo, hi) for lo, hi in ranges)), min_size=1, max_size=max_size).map(
        lambda xs: np.array(xs, dtype=float)
    )


def wrap(angle):
    """Angle difference wrapped to (−π, π]."""
    return np.angle(np.exp(1j * angle))


# =========================================================================== Delta
@SETTINGS
@given(rows((-0.3, 0.3), (-0.3, 0.3), (-1.0, -0.6)))
def test_delta_fk_of_ik_is_identity(p):
    p = p[DELTA.reachable(p)]
    assume(len(p) > 0)
    q = DELTA.inverse_kinematics(p)
    assert np.max(np.abs(DELTA.forward_kinematics(q) - p)) < IDENTITY_TOL
    assert np.max(np.abs(DELTA.inverse_kinematics(DELTA.forward_kinematics(q)) - q)) < IDENTITY_TOL


delta_geometry = st.tuples(fl(0.05, 0.4), fl(0.02, 0.15), fl(0.1, 0.6), fl(0.3, 1.5))


@SETTINGS
@given(delta_geometry, rows((-0.8, 1.6), (-0.8, 1.6), (-0.8, 1.6)))
def test_delta_ik_of_fk_is_identity_on_knee_out_branch(geometry, q):
    """Any geometry: FK(q), then IK returns q wherever q is on the knee-out branch (B_ii = d_i·E_i′ > 0)."""
    robot = DeltaRobot(*geometry)
    try:
        p = robot.forward_kinematics(q)
    except UnreachableError:
        assume(False)
    _, B = robot.constraint_matrices(q, p)
    # stay a little away from the serial singularity B_ii = 0, where IK loses √eps of its accuracy
    keep = np.all(B > 1e-2 * robot.l * robot.L, axis=1)
    assume(keep.any())
    q, p = q[keep], p[keep]
    assert np.max(np.abs(robot.inverse_kinematics(p) - q)) < IDENTITY_TOL
    # every forearm closes its loop: ‖d_i‖ = l to round-off (1e-12 m)
    A, _ = robot.constraint_matrices(q, p)
    assert np.max(np.abs(np.linalg.norm(A, axis=2) - robot.l)) < 1e-12


@SETTINGS
@given(rows((-0.3, 0.3), (-0.3, 0.3), (-1.0, -0.6), (-3, 3), (-3, 3), (-3, 3), (-50, 50), (-50, 50), (-50, 50)))
def test_delta_velocity_and_virtual_work_identities(x):
    p, v, a = x[:, :3], x[:, 3:6], x[:, 6:9]
    keep = DELTA.reachable(p)
    assume(keep.any())
    p, v, a = p[keep], v[keep], a[keep]
    q, qd, qdd, _ = DELTA.joint_motion(p, v, a, np.zeros_like(a))
    J = DELTA.jacobian(q, p)
    # ṗ = J q̇: 1e-9 relative to ‖v‖·cond — round-off, loose because cond(J) grows near the workspace edge
    err = np.abs(np.einsum("nij,nj->ni", J, qd) - v).max(axis=1)
    assert np.all(err <= 1e-9 * (1 + np.abs(v).max(axis=1)) * np.linalg.cond(J))
    # power identity for any state, body by body: τ·q̇ = Σ (inertial + weight force)·velocity of every body
    # (written here from first principles, not from the model's lumped parameters)
    for robot in (DELTA, LUMPED, FITTED):
        torque = robot.inverse_dynamics(q, qd, qdd, p, a)
        expected, scale = _body_power(robot, q, qd, qdd, v, a)
        # 1e-9 relative to the sum of magnitudes: round-off of the reciprocal-basis solve amplified by cond(A)
        got = np.sum(torque * qd, axis=1)
        assert np.all(np.abs(got - expected) <= 1e-9 * (scale + np.abs(got)) * np.linalg.cond(J)), robot.dynamics


def _body_power(robot, q, qd, qdd, v, a):
    """(Σ f·v over the bodies, Σ |f·v|) (N,): upper arms, elbow and plate point masses, each pair's rods as a
    rigid body (centre at mid-rod, turning at ‖v − v_E‖/l), or the lumped ⅔/⅓ split."""
    g = np.array([0.0, 0.0, robot.g])
    phi = np.deg2rad([0.0, 120.0, 240.0])
    terms = [robot.upper_arm_inertia * qd * qdd - robot.g * robot.upper_arm_mass * robot.upper_arm_com * np.cos(q) * qd]
    lumped = robot.dynamics == "lumped"
    m_rod = robot.forearm_mass - robot.forearm_end_elbow - robot.forearm_end_plate
    i_rod = m_rod * robot.l**2 / 12 if robot.forearm_rod_inertia is None else robot.forearm_rod_inertia
    plate = robot.plate_mass + robot.payload + (robot.forearm_mass if lumped else 3 * robot.forearm_end_plate)
    terms.append((plate * np.sum((a + g) * v, axis=1))[:, None])
    for i in range(3):
        s, c = np.sin(q[:, i]), np.cos(q[:, i])
        u = np.column_stack((np.cos(phi[i]) * np.ones_like(s), np.sin(phi[i]) * np.ones_like(s)))
        dirs = lambda r, z: np.column_stack((r * u[:, 0], r * u[:, 1], z))  # noqa: E731 radial/vertical → base
        ve = robot.L * qd[:, i, None] * dirs(-s, -c)
        ae = robot.L * qdd[:, i, None] * dirs(-s, -c) + robot.L * qd[:, i, None] ** 2 * dirs(-c, s)
        if lumped:
            terms.append(((robot.elbow_mass + 2 * robot.forearm_mass / 3) * np.sum((ae + g) * ve, axis=1))[:, None])
            continue
        terms.append(((robot.elbow_mass + robot.forearm_end_elbow) * np.sum((ae + g) * ve, axis=1))[:, None])
        terms.append((m_rod * np.sum(((ae + a) / 2 + g) * (ve + v) / 2, axis=1))[:, None])
        terms.append((i_rod / robot.l**2 * np.sum((a - ae) * (v - ve), axis=1))[:, None])
    parts = np.concatenate(terms, axis=1)
    return parts.sum(axis=1), np.abs(parts).sum(axis=1)


@SETTINGS
@given(rows((-0.3, 0.3), (-0.3, 0.3), (-1.0, -0.6)))
def test_delta_singularity_measure_bounds_and_svd(p):
    p = p[DELTA.reachable(p)]
    assume(len(p) > 0)
    q = DELTA.inverse_kinematics(p)
    mu = DELTA.singularity_measure(q, p)
    assert np.all((mu >= 0) & (mu <= 1))
    A, B = DELTA.constraint_matrices(q, p)
    sv = np.linalg.svd(A / DELTA.l, compute_uv=False)
    ref = np.minimum(np.abs(B).min(axis=1) / (DELTA.l * DELTA.L), sv[:, -1] / sv[:, 0])
    # closed-form Gram eigenvalues vs SVD of Â: where two eigenvalues coincide the cubic's arccos loses
    # half the digits (√eps ≈ 1.5e-8 relative); 5e-8 absolute on a measure ≥ 0.02 still fails any wrong formula
    assert np.max(np.abs(mu - ref)) < 5e-8


# =========================================================================== SCARA
scara_geometry = st.tuples(fl(0.1, 0.6), fl(0.1, 0.6), fl(-0.5, 0.5))


@SETTINGS
@given(scara_geometry, st.sampled_from(["left", "right"]), rows((-np.pi, np.pi), (0.02, np.pi - 0.02), (-0.3, 0.3)))
def test_scara_ik_of_fk_is_identity(geometry, elbow, q):
    l1, l2, z0 = geometry
    robot = ScaraRobot(l1=l1, l2=l2, elbow=elbow, z0=z0)
    if elbow == "right":
        q = q * [1.0, -1.0, 1.0]
    back = robot.inverse_kinematics(robot.forward_kinematics(q))
    # angles compared modulo 2π; 1e-9 rad/m is the brief's identity tolerance
    assert np.max(np.abs(wrap(back[:, :2] - q[:, :2]))) < IDENTITY_TOL
    assert np.max(np.abs(back[:, 2] - q[:, 2])) < IDENTITY_TOL


@SETTINGS
@given(st.sampled_from(["left", "right"]), rows((0.05, 0.6), (-np.pi, np.pi), (-0.3, 0.3)))
def test_scara_fk_of_ik_is_identity_in_annulus(elbow, polar):
    robot = SCARAS[elbow]
    rho, ang, z = polar.T
    p = np.column_stack((rho * np.cos(ang), rho * np.sin(ang), z))
    q = robot.inverse_kinematics(p)
    assert np.max(np.abs(robot.forward_kinematics(q) - p)) < IDENTITY_TOL
    # the other elbow reaches the same point (1e-9 m)
    other = SCARAS["right" if elbow == "left" else "left"]
    assert np.max(np.abs(other.forward_kinematics(other.inverse_kinematics(p)) - p)) < IDENTITY_TOL


@SETTINGS
@given(st.sampled_from(["left", "right"]), rows((0.0, 0.049), (-np.pi, np.pi)), st.booleans())
def test_scara_outside_annulus_raises(elbow, polar, outer):
    robot = SCARAS[elbow]
    rho = polar[:, 0] + 0.601 if outer else polar[:, 0]  # ρ > l1 + l2 = 0.6 or ρ < l1 − l2 = 0.05
    p = np.column_stack((rho * np.cos(polar[:, 1]), rho * np.sin(polar[:, 1]), np.zeros(len(rho))))
    p = np.vstack(([0.3, 0.2, 0.0], p))  # sample 0 is reachable, sample 1 is the first bad one
    try:
        robot.inverse_kinematics(p)
    except UnreachableError as exc:
        assert "sample 1 " in str(exc)
    else:
        raise AssertionError("no UnreachableError outside the annulus")


@SETTINGS
@given(
    st.sampled_from(["left", "right"]),
    rows((-np.pi, np.pi), (0.05, 3.09), (-0.3, 0.3), (-5, 5), (-5, 5), (-2, 2), (-80, 80), (-80, 80), (-30, 30)),
)
def test_scara_power_identity(elbow, x):
    """τ·q̇ = d/dt(½ q̇ᵀMq̇) + m_t g q̇3 with Ṁ from ∂M/∂q2 in closed form (skew-symmetry of Ṁ − 2C)."""
    robot = SCARAS[elbow]
    q, qd, qdd = x[:, :3].copy(), x[:, 3:6], x[:, 6:9]
    if elbow == "right":
        q[:, 1] = -q[:, 1]
    torque = robot.inverse_dynamics(q, qd, qdd, robot.forward_kinematics(q), np.zeros_like(q))
    M = robot.mass_matrix(q)
    k = (robot.m2 * robot.lc2 + (robot.m3 + robot.payload) * robot.l2) * robot.l1 * np.sin(q[:, 1])
    Md = np.zeros_like(M)
    Md[:, 0, 0] = -2 * k * qd[:, 1]
    Md[:, 0, 1] = Md[:, 1, 0] = -k * qd[:, 1]
    expected = (
        np.einsum("ni,nij,nj->n", qd, M, qdd)
        + 0.5 * np.einsum("ni,nij,nj->n", qd, Md, qd)
        + (robot.m3 + robot.payload) * robot.g * qd[:, 2]
    )
    power = np.sum(torque * qd, axis=1)
    scale = np.sum(np.abs(torque * qd), axis=1) + 1e-12
    # 1e-12 relative to the sum of magnitudes: a handful of round-offs, no amplification (M is well conditioned)
    assert np.all(np.abs(power - expected) <= 1e-12 * scale + 1e-12)
