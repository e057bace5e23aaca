"""Unit tests of pickplace_cli.robots.delta (Clavel Delta: rigid-body dynamics, and the lumped-mass model
[Codourey1998] by name).

Dimensions: the Su 2018 prototype (R = 0.150, r = 0.051, L = 0.325, l = 0.800 m) with the shared
masses of the project brief. Every numeric assertion states its tolerance and why.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from pickplace_cli.model.errors import UnreachableError
from pickplace_cli.robots.delta import DeltaRobot

DELTA = DeltaRobot(
    R=0.150,
    r=0.051,
    L=0.325,
    l=0.800,
    upper_arm_inertia=0.030,
    upper_arm_mass=1.0,
    upper_arm_com=0.13,
    elbow_mass=0.10,
    forearm_mass=0.30,
    plate_mass=0.40,
    payload=0.1,
)
#: the same robot under the papers' lumped-mass model
LUMPED = dataclasses.replace(DELTA, dynamics="lumped")
#: rigid rods with end fittings: 0.06 kg ball cups at each end of a pair, a rod inertia away from the uniform one
FITTED = dataclasses.replace(DELTA, forearm_end_elbow=0.06, forearm_end_plate=0.06, forearm_rod_inertia=0.0095)
MODELS = pytest.mark.parametrize("robot", [DELTA, LUMPED, FITTED], ids=["rigid", "lumped", "rigid-fitted"])

#: Adept cycle corners (25 mm × 305 mm × 25 mm) at the usual working height [m]
ADEPT = np.array(
    [
        [-0.1525, 0.0, -0.8],
        [0.1525, 0.0, -0.8],
        [-0.1525, 0.0, -0.775],
        [0.1525, 0.0, -0.775],
    ]
)


# --------------------------------------------------------------------------- smooth test paths
def sine_path(t: np.ndarray, p0=(0.03, -0.02, -0.82), amp=(0.12, 0.08, 0.05), w=(6.0, 7.5, 9.0), ph=(0.3, 1.1, -0.4)):
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


# --------------------------------------------------------------------------- parameters
def test_protocol_attributes():
    assert DELTA.joint_names == ("q1", "q2", "q3")
    assert DELTA.joint_units == ("rad", "rad", "rad")


@pytest.mark.parametrize(
    "field, value",
    [("R", 0.0), ("r", -0.05), ("L", math.nan), ("l", 0.0), ("plate_mass", -1.0), ("payload", -0.1),
     ("upper_arm_inertia", -1e-3), ("forearm_mass", math.inf)],
)
def test_non_physical_parameter_raises_value_error_naming_field(field, value):
    with pytest.raises(ValueError, match=rf"\b{field}\b"):
        dataclasses.replace(DELTA, **{field: value})


def test_frozen():
    with pytest.raises(dataclasses.FrozenInstanceError):
        DELTA.L = 0.3  # type: ignore[misc]


def test_lumped_masses():
    # exact arithmetic on the parameters; 1e-15 absorbs the float rounding of the sums
    assert LUMPED.platform_mass == pytest.approx(0.4 + 0.1 + 0.3, abs=1e-15)
    assert LUMPED.arm_inertia == pytest.approx(0.030 + (0.10 + 0.2) * 0.325**2, abs=1e-15)
    assert LUMPED.arm_gravity_moment == pytest.approx(1.0 * 0.13 + (0.10 + 0.2) * 0.325, abs=1e-15)


def test_rigid_masses():
    """Uniform rods: a third of a pair's mass moves with each end, a sixth couples them, half its weight on each end."""
    assert DELTA.platform_mass == pytest.approx(0.4 + 0.1 + 3 * 0.3 / 3, abs=1e-15)
    assert DELTA.platform_weight_mass == pytest.approx(0.4 + 0.1 + 3 * 0.3 / 2, abs=1e-15)
    assert DELTA.arm_inertia == pytest.approx(0.030 + (0.10 + 0.3 / 3) * 0.325**2, abs=1e-15)
    assert DELTA.arm_gravity_moment == pytest.approx(1.0 * 0.13 + (0.10 + 0.3 / 2) * 0.325, abs=1e-15)
    assert DELTA.rod_inertia == pytest.approx(0.3 * 0.8**2 / 12, abs=1e-15)


@pytest.mark.parametrize("update, rule", [({"dynamics": "stiff"}, "'rigid' or 'lumped'"),
                                          ({"forearm_end_elbow": 0.2, "forearm_end_plate": 0.2}, "part of the pair"),
                                          ({"forearm_rod_inertia": -1.0}, "forearm_rod_inertia")])
def test_bad_rigid_parameters_name_the_rule(update, rule):
    with pytest.raises(ValueError, match=rule):
        dataclasses.replace(DELTA, **update)


def test_bad_shape_raises_value_error():
    with pytest.raises(ValueError, match=r"p must have shape \(N, 3\)"):
        DELTA.inverse_kinematics(np.array([0.0, 0.0, -0.8]))


# --------------------------------------------------------------------------- kinematics
def test_home_position_symmetric_knee_out():
    q = DELTA.inverse_kinematics(np.array([[0.0, 0.0, -0.8]]))
    # symmetric arms: equal angles to round-off (1e-14 rad ≫ eps · |q|)
    assert np.ptp(q) < 1e-14
    # knee-out branch: moderate positive angle (0.345 rad for these dimensions)
    assert 0.3 < q[0, 0] < 0.8
    # the elbow is outside the fixed platform: R + L cos q > R
    assert np.all(np.cos(q) > 0)


def test_convention_arm1_on_plus_x():
    # moving the platform towards +x lifts arm 1 (q1 decreases) and lowers arms 2 and 3 equally
    q = DELTA.inverse_kinematics(np.array([[0.0, 0.0, -0.8], [0.1, 0.0, -0.8]]))
    assert q[1, 0] < q[0, 0]
    assert q[1, 1] > q[0, 1]
    assert abs(q[1, 1] - q[1, 2]) < 1e-12  # mirror symmetry about the x axis, to round-off
    # q > 0 is downwards: the elbow of arm 1 is at z = −L sin q1 < 0
    elbow_z = -DELTA.L * np.sin(q[0, 0])
    assert elbow_z < 0


def test_adept_cycle_reachable_and_angles(capsys):
    q = DELTA.inverse_kinematics(ADEPT)
    deg = np.rad2deg(q)
    with capsys.disabled():
        print("\nDelta (Su 2018 dims) Adept-cycle joint angles [deg]:")
        for p, row in zip(ADEPT, deg):
            point = ", ".join(f"{x:+.4f}" for x in p)
            angles = ", ".join(f"{x:7.3f}" for x in row)
            print(f"  p = ({point}) m  ->  q = ({angles}) deg")
    # the usual motor range of a Delta; exact comparison, the angles are tens of degrees inside it
    assert np.all(deg > -40.0) and np.all(deg < 90.0)
    # FK closes the loop: 1e-12 m is ~1e4 × eps × 1 m, round-off of a dozen operations
    assert np.max(np.abs(DELTA.forward_kinematics(q) - ADEPT)) < 1e-12


def test_ik_fk_round_trip_grid():
    x, y, z = np.meshgrid(np.linspace(-0.3, 0.3, 13), np.linspace(-0.3, 0.3, 13), np.linspace(-1.0, -0.6, 9))
    p = np.stack((x.ravel(), y.ravel(), z.ravel()), axis=1)
    p = p[DELTA.reachable(p)]
    assert len(p) > 0.95 * 13 * 13 * 9  # the box is (almost) all inside the workspace
    q = DELTA.inverse_kinematics(p)
    # 1e-9 m / rad: the brief's identity tolerance; actual round-off is ~1e-15
    assert np.max(np.abs(DELTA.forward_kinematics(q) - p)) < 1e-9
    assert np.max(np.abs(DELTA.inverse_kinematics(DELTA.forward_kinematics(q)) - q)) < 1e-9
    # knee-out branch everywhere: B_ii = d_i·E_i' > 0
    _, B = DELTA.constraint_matrices(q, p)
    assert np.all(B > 0)


def test_fk_picks_platform_below_elbows():
    q = np.array([[0.2, 0.5, 0.9], [0.0, 0.0, 0.0], [-0.3, 0.1, 0.4]])
    p = DELTA.forward_kinematics(q)
    elbow_z = -DELTA.L * np.sin(q)
    assert np.all(p[:, 2] < elbow_z.min(axis=1))
    # every forearm has length l: 1e-12 m is round-off
    A, _ = DELTA.constraint_matrices(q, p)
    assert np.max(np.abs(np.linalg.norm(A, axis=2) - DELTA.l)) < 1e-12


def test_ik_unreachable_names_sample_index():
    p = np.array([[0.0, 0.0, -0.8], [0.1, 0.0, -0.9], [0.0, 0.0, -1.5], [0.0, 0.0, -2.0]])
    with pytest.raises(UnreachableError, match=r"sample 2 .*\(0, 0, -1\.5\) m") as info:
        DELTA.inverse_kinematics(p)
    assert "\n" not in str(info.value)
    assert info.value.exit_code == 4


def test_ik_nan_is_unreachable():
    with pytest.raises(UnreachableError, match="sample 1"):
        DELTA.inverse_kinematics(np.array([[0.0, 0.0, -0.8], [np.nan, 0.0, -0.8]]))


def test_fk_unassemblable_names_sample_index():
    short = DeltaRobot(R=0.15, r=0.05, L=0.3, l=0.2)  # sphere centres 0.4 m from the axis > l
    with pytest.raises(UnreachableError, match="sample 1"):
        short.forward_kinematics(np.array([[1.5, 1.5, 1.5], [0.0, 0.0, 0.0]]))


def test_reachable_mask():
    p = np.array([[0.0, 0.0, -0.8], [0.0, 0.0, -1.5], [np.nan, 0.0, -0.8]])
    assert DELTA.reachable(p).tolist() == [True, False, False]


def test_inverse_jacobian_matches_finite_differences_of_ik():
    rng = np.random.default_rng(7)
    p = np.column_stack((rng.uniform(-0.25, 0.25, (50, 2)), rng.uniform(-0.95, -0.65, 50)))
    q = DELTA.inverse_kinematics(p)
    Jinv = DELTA.inverse_jacobian(q, p)
    h = 1e-6  # m: central-difference truncation h²·q'''/6 ~ 1e-12, round-off eps/h ~ 1e-10 rad/m
    fd = np.stack(
        [(DELTA.inverse_kinematics(p + h * e) - DELTA.inverse_kinematics(p - h * e)) / (2 * h) for e in np.eye(3)],
        axis=2,
    )
    # 1e-6 relative (brief): ~1e3 × above the FD error budget, ≪ any sign or factor slip
    assert_rel(Jinv, fd, 1e-6, "inverse Jacobian vs FD of IK")
    # forward Jacobian is its inverse; 1e-12 is round-off of a 3×3 product with cond(J) ~ 10
    assert np.max(np.abs(DELTA.jacobian(q, p) @ Jinv - np.eye(3))) < 1e-12
    # forward Jacobian vs FD of FK (same FD budget)
    fdf = np.stack(
        [(DELTA.forward_kinematics(q + h * e) - DELTA.forward_kinematics(q - h * e)) / (2 * h) for e in np.eye(3)],
        axis=2,
    )
    assert_rel(DELTA.jacobian(q, p), fdf, 1e-6, "Jacobian vs FD of FK")


def test_joint_motion_matches_finite_differences_of_ik():
    t = T_SAMPLES
    p, v, a, j = sine_path(t)
    q, qd, qdd, qddd = DELTA.joint_motion(p, v, a, j)
    ik = lambda tt: DELTA.inverse_kinematics(sine_path(tt)[0])  # noqa: E731
    # 1e-12 rad: q is exactly IK(p)
    assert np.max(np.abs(q - ik(t))) < 1e-12
    # 4th-order stencils; h balances truncation (∝ h⁴ ω^(k+4), ω ≤ 9 rad/s) against round-off (∝ eps/h^k).
    # Measured errors: 3e-12, 2e-10, 3e-8 relative; the bounds leave ≥ 30× margin and still catch any
    # wrong term (which shows up at ≥ 1e-3).
    assert_rel(qd, d1(ik, t, 3e-4), 1e-9, "q̇ vs FD")
    assert_rel(qdd, d2(ik, t, 1e-3), 1e-8, "q̈ vs FD")
    assert_rel(qddd, d3(ik, t, 2e-3), 1e-6, "q⃛ vs FD")
    # and against FD (h = 1e-3 s, 4th order) of the analytic lower derivative: one order of differentiation
    # instead of two or three; measured 5e-10 and 1e-9 relative, bound 1e-8
    qd_of = lambda tt: DELTA.joint_motion(*sine_path(tt))[1]  # noqa: E731
    qdd_of = lambda tt: DELTA.joint_motion(*sine_path(tt))[2]  # noqa: E731
    assert_rel(qdd, d1(qd_of, t, 1e-3), 1e-8, "q̈ vs FD of q̇")
    assert_rel(qddd, d1(qdd_of, t, 1e-3), 1e-8, "q⃛ vs FD of q̈")


def test_joint_velocity_consistent_with_jacobian():
    p, v, a, j = sine_path(T_SAMPLES)
    q, qd, _, _ = DELTA.joint_motion(p, v, a, j)
    # ṗ = J q̇ exactly (same algebra, different route): 1e-12 relative is round-off
    assert_rel(np.einsum("nij,nj->ni", DELTA.jacobian(q, p), qd), v, 1e-12, "J q̇ vs v")


def test_singularity_measure_matches_svd_and_vanishes_at_boundary():
    rng = np.random.default_rng(3)
    p = np.column_stack((rng.uniform(-0.3, 0.3, (200, 2)), rng.uniform(-1.0, -0.6, 200)))
    p = p[DELTA.reachable(p)]
    q = DELTA.inverse_kinematics(p)
    mu = DELTA.singularity_measure(q, p)
    # independent route (SVD of Â instead of eigenvalues of ÂÂᵀ); 1e-10 ≫ the ~1e-15 round-off
    A, B = DELTA.constraint_matrices(q, p)
    sv = np.linalg.svd(A / DELTA.l, compute_uv=False)
    ref = np.minimum(np.abs(B).min(axis=1) / (DELTA.l * DELTA.L), sv[:, -1] / sv[:, 0])
    assert np.max(np.abs(mu - ref)) < 1e-10
    assert np.all((mu > 0) & (mu <= 1))
    # bisect the workspace boundary below the platform (discriminant → 0 is the serial singularity)
    lo, hi = -1.0, -1.5
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if DELTA.reachable(np.array([[0.05, 0.02, mid]]))[0] else (lo, mid)
    pb = np.array([[0.05, 0.02, lo]])
    # at 1e-16 m from the boundary the measure is ~√(1e-16) — 1e-6 is a loose bound far below the 0.03 minimum inside
    assert DELTA.singularity_measure(DELTA.inverse_kinematics(pb), pb)[0] < 1e-6


# --------------------------------------------------------------------------- dynamics
def test_static_holding_torque_sign_and_symmetry():
    p = np.array([[0.0, 0.0, -0.8]])
    q = DELTA.inverse_kinematics(p)
    torque = DELTA.inverse_dynamics(q, np.zeros_like(q), np.zeros_like(q), p, np.zeros_like(p))
    # q > 0 is downwards: holding the arms and the plate up takes a NEGATIVE torque on each motor
    assert np.all(torque < 0)
    assert np.ptp(torque) < 1e-12  # symmetric pose → equal torques, to round-off


@MODELS
def test_static_torque_is_gradient_of_potential_energy(robot):
    DELTA = robot  # noqa: N806
    rng = np.random.default_rng(11)
    p = np.column_stack((rng.uniform(-0.25, 0.25, (30, 2)), rng.uniform(-0.95, -0.65, 30)))
    q = DELTA.inverse_kinematics(p)
    zeros = np.zeros_like(q)
    torque = DELTA.inverse_dynamics(q, zeros, zeros, p, zeros)
    V = lambda qq: DELTA.potential_energy(qq, DELTA.forward_kinematics(qq))  # noqa: E731
    h = 1e-6  # rad: truncation h²V'''/6 ~ 1e-12, round-off eps·|V|/h ~ 1e-9 N·m
    grad = np.stack([(V(q + h * e) - V(q - h * e)) / (2 * h) for e in np.eye(3)], axis=1)
    # 1e-7 relative: ~100× the FD round-off on ~3 N·m torques
    assert_rel(torque, grad, 1e-7, "static torque vs ∂V/∂q")


@MODELS
def test_power_balance_against_finite_difference_of_energy(robot):
    DELTA = robot  # noqa: N806
    t = T_SAMPLES
    p, v, a, j = sine_path(t)
    q, qd, qdd, _ = DELTA.joint_motion(p, v, a, j)
    torque = DELTA.inverse_dynamics(q, qd, qdd, p, a)
    power = np.sum(torque * qd, axis=1)

    def energy(tt):
        pp, vv, aa, jj = sine_path(tt)
        qq, qqd, _, _ = DELTA.joint_motion(pp, vv, aa, jj)
        return DELTA.kinetic_energy(qq, qqd, vv) + DELTA.potential_energy(qq, pp)

    # 4th-order central difference, h = 1e-3 s: truncation h⁴E⁽⁵⁾/30 ~ 1e-8 W, round-off eps·|E|/h ~ 1e-11 W,
    # on powers up to ~11 W (measured 8e-10 relative) → the brief's 1e-6 relative holds with a wide margin
    assert_rel(power, d1(energy, t, 1e-3), 1e-6, "Σ τ q̇ vs dE/dt")


def _body_kinetic_energy(robot: DeltaRobot, qq, qqd):
    """T(q, q̇) [J] of every body, written here from first principles (not from the model's α, β, I_b, m_p):
    upper arms about their axes, point masses at the elbows (elbow mass + the elbow fittings), each pair's
    rod body (centre of mass at mid-rod moving with (v_E + v_C)/2, turning at ‖v_C − v_E‖/l), the plate
    fittings, plate and payload at the plate; or, lumped, ⅔ of each pair at its elbow and ⅓ at the plate."""
    pp = robot.forward_kinematics(qq)
    vc = np.einsum("nij,nj->ni", robot.jacobian(qq, pp), qqd)  # plate velocity from J = ∂p/∂q
    phi = np.deg2rad([0.0, 120.0, 240.0])
    ke = 0.5 * robot.upper_arm_inertia * np.sum(qqd**2, axis=1)
    ke = ke + 0.5 * (robot.plate_mass + robot.payload) * np.sum(vc**2, axis=1)
    for i in range(3):
        s, c = np.sin(qq[:, i]), np.cos(qq[:, i])
        # dE/dt of E = Rz(φ)(R + L cos q, 0, −L sin q)
        ve = robot.L * qqd[:, i, None] * np.column_stack((-s * np.cos(phi[i]), -s * np.sin(phi[i]), -c))
        if robot.dynamics == "lumped":
            ke = ke + 0.5 * (robot.elbow_mass + 2 * robot.forearm_mass / 3) * np.sum(ve**2, axis=1)
            ke = ke + 0.5 * robot.forearm_mass / 3 * np.sum(vc**2, axis=1)
            continue
        m_rod = robot.forearm_mass - robot.forearm_end_elbow - robot.forearm_end_plate
        i_rod = m_rod * robot.l**2 / 12 if robot.forearm_rod_inertia is None else robot.forearm_rod_inertia
        ke = ke + 0.5 * (robot.elbow_mass + robot.forearm_end_elbow) * np.sum(ve**2, axis=1)
        ke = ke + 0.5 * robot.forearm_end_plate * np.sum(vc**2, axis=1)
        ke = ke + 0.5 * m_rod * np.sum(((ve + vc) / 2) ** 2, axis=1)
        ke = ke + 0.5 * i_rod * np.sum((vc - ve) ** 2, axis=1) / robot.l**2
    return ke


def _body_potential_energy(robot: DeltaRobot, qq):
    """V(q) [J] of every body at its own height (rod bodies at mid-rod), written here independently."""
    pp = robot.forward_kinematics(qq)
    ze = -robot.L * np.sin(qq)  # elbow heights (N, 3)
    zc = pp[:, 2]
    g = robot.g
    v = g * (robot.upper_arm_mass * -robot.upper_arm_com * np.sin(qq)).sum(axis=1)
    v = v + g * (robot.plate_mass + robot.payload) * zc
    if robot.dynamics == "lumped":
        return v + g * ((robot.elbow_mass + 2 * robot.forearm_mass / 3) * ze).sum(axis=1) + g * robot.forearm_mass * zc
    m_rod = robot.forearm_mass - robot.forearm_end_elbow - robot.forearm_end_plate
    v = v + g * ((robot.elbow_mass + robot.forearm_end_elbow) * ze).sum(axis=1) + 3 * g * robot.forearm_end_plate * zc
    return v + g * (m_rod * (ze + zc[:, None]) / 2).sum(axis=1)


@MODELS
def test_torque_matches_lagrange_equations(robot):
    """Independent check of every torque component: τ = d/dt ∂T/∂q̇ − ∂T/∂q + ∂V/∂q with T and V written
    body by body in this test (:func:`_body_kinetic_energy`), all partials by finite differences."""
    t = T_SAMPLES
    p, v, a, j = sine_path(t)
    q, qd, qdd, _ = robot.joint_motion(p, v, a, j)
    torque = robot.inverse_dynamics(q, qd, qdd, p, a)
    T = lambda qq, qqd: _body_kinetic_energy(robot, qq, qqd)  # noqa: E731
    V = lambda qq: _body_potential_energy(robot, qq)  # noqa: E731
    E = np.eye(3)
    hv = 1e-3  # T is quadratic in q̇: the central difference is exact up to round-off
    hq = 1e-6  # rad: truncation ~1e-12, round-off eps·|T|/h ~ 1e-10

    def dT_dqd(tt):
        pp, vv, aa, jj = sine_path(tt)
        qq, qqd, _, _ = robot.joint_motion(pp, vv, aa, jj)
        return np.stack([(T(qq, qqd + hv * e) - T(qq, qqd - hv * e)) / (2 * hv) for e in E], axis=1)

    dT_dq = np.stack([(T(q + hq * e, qd) - T(q - hq * e, qd)) / (2 * hq) for e in E], axis=1)
    dV_dq = np.stack([(V(q + hq * e) - V(q - hq * e)) / (2 * hq) for e in E], axis=1)
    lagrange = d1(dT_dqd, t, 1e-3) - dT_dq + dV_dq
    # 1e-6 relative: the sum of the FD errors above is ≲ 1e-8 of the ~10 N·m torques
    assert_rel(torque, lagrange, 1e-6, "τ vs Lagrange equations")
    # and the energies the model states are the bodies' own
    assert_rel(robot.kinetic_energy(q, qd, v), T(q, qd), 1e-12, "KE")
    np.testing.assert_allclose(robot.potential_energy(q, p), V(q), rtol=0, atol=1e-12 * np.abs(V(q)).max())


@MODELS
def test_torque_rate_is_the_time_derivative_of_torque(robot):
    """split_dynamics' dA + dG against a 4th-order central difference in time of inverse_dynamics along the
    sine path (h = 1e-4 s: truncation h⁴τ⁽⁵⁾/30 ~ 1e-9, round-off eps·|τ|/h ~ 1e-11 of torque rates ~1e3 N·m/s)."""
    t = T_SAMPLES

    def torque(tt):
        pp, vv, aa, jj = sine_path(tt)
        qq, qqd, qqdd, _ = robot.joint_motion(pp, vv, aa, jj)
        return robot.inverse_dynamics(qq, qqd, qqdd, pp, aa)

    p, v, a, j = sine_path(t)
    q, qd, qdd, qddd = robot.joint_motion(p, v, a, j)
    A, G, dA, dG = robot.split_dynamics(q, qd, qdd, qddd, p, v, a, j)
    assert_rel(A + G, torque(t), 1e-13, "split_dynamics A + G vs inverse_dynamics")
    assert_rel(dA + dG, d1(torque, t, 1e-4), 1e-7, "torque rate vs dτ/dt")


def test_massless_robot_needs_no_torque():
    light = DeltaRobot(R=0.150, r=0.051, L=0.325, l=0.800)
    p, v, a, j = sine_path(T_SAMPLES)
    q, qd, qdd, _ = light.joint_motion(p, v, a, j)
    assert np.all(light.inverse_dynamics(q, qd, qdd, p, a) == 0.0)


def test_vectorised_shapes():
    p, v, a, j = sine_path(np.linspace(0, 1, 1000))
    out = DELTA.joint_motion(p, v, a, j)
    assert all(x.shape == (1000, 3) for x in out)
    assert DELTA.inverse_dynamics(out[0], out[1], out[2], p, a).shape == (1000, 3)
    assert DELTA.singularity_measure(out[0], p).shape == (1000,)


def test_motion_and_dynamics_is_the_separate_methods_in_one_pass():
    """The one-pass evaluation (the limit check's) equals joint_motion + split_dynamics +
    singularity_measure. Not bitwise: it takes cos q, sin q from the inverse kinematics' own C/ρ², S/ρ²
    instead of np.cos/np.sin of the angle; 1e-12 relative to each quantity's scale (measured ~1e-15)."""
    rng = np.random.default_rng(4)
    p = np.column_stack([rng.uniform(-0.2, 0.2, 200), rng.uniform(-0.2, 0.2, 200), rng.uniform(-0.9, -0.7, 200)])
    v, a, j = (rng.normal(scale=s, size=(200, 3)) for s in (2.0, 50.0, 3000.0))
    one = DELTA.motion_and_dynamics(p, v, a, j)
    q, qd, qdd, qddd = DELTA.joint_motion(p, v, a, j)
    ref = (q, qd, qdd, qddd, *DELTA.split_dynamics(q, qd, qdd, qddd, p, v, a, j), DELTA.singularity_measure(q, p))
    for got, want in zip(one, ref):
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-12 * np.abs(want).max())
    no_rates = DELTA.motion_and_dynamics(p, v, a, j, rates=False)
    assert no_rates[6] is None and no_rates[7] is None
    np.testing.assert_array_equal(no_rates[4], one[4])


def test_singularity_measure_of_any_q_p_matches_svd():
    """singularity_measure(q, p) is public: for a (q, p) pair that does not belong together the forearm
    vectors are not of length l. The measure must still be min(|B_ii|/(lL), σ_min/σ_max of A), as for a
    matching pair; the planner's inverse-kinematics path may use ‖d_i‖ = l, this one must not."""
    rng = np.random.default_rng(11)
    p = np.column_stack([rng.uniform(-0.15, 0.15, 300), rng.uniform(-0.15, 0.15, 300), rng.uniform(-0.9, -0.7, 300)])
    q = DELTA.inverse_kinematics(p) + rng.normal(0.0, 0.2, (300, 3))
    A, B = DELTA.constraint_matrices(q, p)
    assert np.abs(np.linalg.norm(A, axis=2) - DELTA.l).max() > 0.05  # really not of length l
    sv = np.linalg.svd(A, compute_uv=False)
    ref = np.minimum(np.abs(B).min(axis=1) / (DELTA.l * DELTA.L), sv[:, -1] / sv[:, 0])
    np.testing.assert_allclose(DELTA.singularity_measure(q, p), ref, rtol=1e-9, atol=1e-12)
