"""Planning with the rotary fourth axis (pickplace_cli.paths.turn, the planner, the time modes): the tool turns
as planned, three numbers keep the 3-axis motion, every time mode holds the fourth motor's limits, bad input is
refused.

References written here: the angle law from the hand-expanded polynomial s(x) = ∫630u⁴(1−u)⁴du; the fourth motor's
torque from its closed form (J_t·θ̈/(N·η) + J_rotor·N·θ̈); the lift-off window from the path's own heights; the
RMS over the round trip from the written samples of there, dwell, back, dwell.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from pickplace_cli.model.errors import TaskError
from pickplace_cli.model.profile import load_profile
from pickplace_cli.model.task import Task
from pickplace_cli.planner import PlanOptions, plan
from pickplace_cli.pipelines.timeline import round_trip

A, B = [-0.1525, 0.0, -0.8], [0.1525, 0.0, -0.8]
SA, SB = [0.35, -0.1525, -0.1], [0.35, 0.1525, -0.1]


def s_hand(x, k=0):
    """s(x) = ∫₀ˣ 630 u⁴(1 − u)⁴ du (hand expansion of the integrand) and its derivatives."""
    prim = np.concatenate([[0.0], [c / (n + 1) for n, c in enumerate([0, 0, 0, 0, 630, -2520, 3780, -2520, 630])]])
    poly = np.polynomial.Polynomial(prim)
    return (poly.deriv(k) if k else poly)(np.clip(np.asarray(x, float), 0, 1))


def without_axis(prof):
    return prof.model_copy(update={"robot": prof.robot.model_copy(update={"rotary": None})})


@pytest.fixture(scope="module")
def delta4():
    return load_profile("delta-4axis")


@pytest.fixture(scope="module")
def scara():
    return load_profile("scara-600")


@pytest.mark.parametrize("name, a, b", [("delta-4axis", A, B), ("scara-600", SA, SB)])
def test_three_numbers_keep_the_three_axis_motion(name, a, b):
    prof = load_profile(name)
    task = Task(a, b, 0.025)
    four = plan(task, prof, PlanOptions(time="auto", fit=False))
    three = plan(task, without_axis(prof), PlanOptions(time="auto", fit=False))
    jt4, jt3 = four.joint, three.joint
    assert jt4.names == ("q1", "q2", "q3", "q4") and jt3.names == ("q1", "q2", "q3")
    # the arm's joints, torques and motors: the 3-axis robot's, bitwise (the tool angle is held: no J_t term)
    for name_ in ("q", "qd", "qdd", "torque", "motor_torque"):
        assert np.array_equal(getattr(jt4, name_)[:, :3], getattr(jt3, name_)), name_
    if name == "delta-4axis":  # the plate does not turn: q4 stays at 0, its motor idle
        assert not np.any(jt4.q[:, 3]) and not np.any(jt4.motor_torque[:, 3])
    else:  # SCARA: the tool angle q1 + q2 + q4 is held at 0: J4 counter-rotates (1e-12 rad: round-off)
        assert np.max(np.abs(jt4.q[:, 0] + jt4.q[:, 1] + jt4.q[:, 3])) < 1e-12
        assert np.max(np.abs(jt4.qd[:, 3])) > 0.5  # it does move, and its motor shows in the report
        assert any(r.joint == "q4" and r.quantity == "motor speed" for r in four.report.rows)


def test_the_turn_follows_the_law_and_the_fourth_motor_its_closed_form(delta4):
    task = Task(A, B, 0.025, theta_from=0.2, theta_to=0.2 + math.pi / 2)
    res = plan(task, delta4, PlanOptions(time="auto", fit=False, rate=2000.0))
    T = res.duration.seconds
    turn = res.parameters["turn"]
    a, b = turn["window_tau"]
    path = res.cartesian.path
    z_lift = -0.8 + 0.5 * 0.025  # η of the rise to the apex, both ends at one height
    # the window's ends are where the tool passes the lift-off/set-down height (the path's own z: 1e-10 m)
    assert path(np.array([a, b]), 0)[:, 2] == pytest.approx([z_lift, z_lift], abs=1e-10)
    tau = res.t / T
    x = (tau - a) / (b - a)
    delta = math.pi / 2
    jt = res.joint
    # q4 = θ = 0.2 + Δ·s(x) (the Delta's q4 is the tool angle, σ = +1): 1e-12 rad is round-off
    assert np.max(np.abs(jt.q[:, 3] - (0.2 + delta * s_hand(x)))) < 1e-12
    # constant while the gripper engages: below the lift-off height at either end the tool has not turned
    low = res.p[:, 2] < z_lift - 1e-9
    assert np.all(np.abs(jt.q[low & (tau < 0.5), 3] - 0.2) < 1e-15)
    assert np.all(np.abs(jt.q[low & (tau > 0.5), 3] - (0.2 + delta)) < 1e-12)
    # the fourth motor's torque, closed form: θ̈ = Δ s″(x)/((b − a) T)², motor = J_t θ̈/(N η) + J_rotor N θ̈
    ax = delta4.robot.rotary
    d = ax.joint.drive
    thdd = delta * s_hand(x, 2) / ((b - a) * T) ** 2
    ref = ax.inertia * thdd / (d.gear_ratio * d.efficiency) + d.rotor_inertia * d.gear_ratio * thdd
    assert np.max(np.abs(jt.motor_torque[:, 3] - ref)) <= 1e-9 * np.max(np.abs(ref))  # round-off of two routes
    assert np.max(np.abs(jt.motor_speed[:, 3] - d.gear_ratio * delta * s_hand(x, 1) / ((b - a) * T))) <= 1e-9 * 600


def test_whole_move_turn_and_the_scara_tool_angle(scara):
    task = Task(SA, SB, 0.025, theta_from=-0.4, theta_to=0.9)
    res = plan(task, scara, PlanOptions(time="auto", fit=False, turn_during="whole"))
    assert res.parameters["turn"]["window_tau"] == [0.0, 1.0]
    tau = res.t / res.duration.seconds
    q = res.joint.q
    # the tool angle q1 + q2 + q4 (σ = +1 in scara-600) is the planned law over the whole move (1e-12 rad)
    assert np.max(np.abs(q[:, 0] + q[:, 1] + q[:, 3] - (-0.4 + 1.3 * s_hand(tau)))) < 1e-12


@pytest.mark.parametrize("rule, end", [("shortest", 0.5 - 2 * math.pi + 5.0), ("ccw", 5.5), ("cw", 5.5 - 2 * math.pi),
                                       ("as-given", 5.5)])
def test_turn_rules_reach_the_angle(delta4, rule, end):
    res = plan(Task(A, B, 0.025, theta_from=0.5, theta_to=5.5), delta4, PlanOptions(time="auto", fit=False, turn=rule))
    assert res.joint.q[0, 3] == pytest.approx(0.5, abs=1e-15)
    assert res.joint.q[-1, 3] == pytest.approx(end, abs=1e-12)  # hand-worked end angles; round-off
    assert res.task.theta_to == pytest.approx(end, abs=1e-12)
    assert res.summary()["to_theta_rad"] == pytest.approx(end, abs=1e-12)


def test_bad_angles_are_refused(delta4):
    # an angle on a profile without the axis: one line, exit 1
    with pytest.raises(TaskError, match=r"needs a robot with a rotary fourth axis; profile delta-su2018") as info:
        plan(Task(A, B, 0.025, theta_from=0.0, theta_to=1.0), load_profile("delta-su2018"), PlanOptions())
    assert info.value.exit_code == 1 and "\n" not in str(info.value)
    # a turn beyond the axis's whole range (±2π: 4π wide) whatever the start
    with pytest.raises(TaskError, match=r"moves q4 by 13 rad, beyond its whole range") as info:
        plan(Task(A, B, 0.025, theta_from=0.0, theta_to=13.0), delta4, PlanOptions(turn="as-given"))
    assert info.value.exit_code == 1
    # not finite, or one end only
    for bad in (math.nan, math.inf):
        with pytest.raises(TaskError, match="finite number of radians"):
            Task(A, B, 0.025, theta_from=0.0, theta_to=bad)
    with pytest.raises(TaskError, match="at both ends"):
        Task(A, B, 0.025, theta_from=0.0)


def test_a_start_outside_the_range_is_a_joint_range_result(delta4):
    # q4 from 6.0 to 6.6 rad: the turn fits the range's width but not its end: the report's position row, exit 4
    res = plan(Task(A, B, 0.025, theta_from=6.0, theta_to=6.6), delta4, PlanOptions(time="auto", fit=False,
                                                                                    turn="as-given"))
    bad = [r for r in res.report.violations if r.joint == "q4"]
    assert bad and bad[0].quantity == "position" and res.report.exit_code() == 4


def test_fit_holds_the_fourth_motor_and_it_binds(delta4):
    """Half a turn on the Adept cycle: the fourth motor's speed sets the fitted duration."""
    task = Task(A, B, 0.025, theta_from=0.0, theta_to=math.pi)
    fit = plan(task, delta4, PlanOptions(time="fit"))
    T = fit.duration.seconds
    assert fit.report.ok and fit.duration.binding.startswith("q4")
    # the binding limit is met at T_fit (its utilisation 1 within the fit's nudge, 1e-6) and broken just below
    q4 = {r.quantity: r for r in fit.report.rows if r.joint == "q4"}
    assert q4["motor speed"].utilisation == pytest.approx(1.0, abs=1e-6)
    short = plan(task, delta4, PlanOptions(time=0.999 * T, fit=False))
    assert not short.report.ok and any(r.joint == "q4" for r in short.report.violations)
    # without the turn the arms set a shorter duration
    assert plan(Task(A, B, 0.025), delta4, PlanOptions(time="fit")).duration.seconds < 0.95 * T


def test_optimal_law_carries_the_turn(delta4):
    task = Task(A, B, 0.025, theta_from=0.0, theta_to=math.pi)
    fit = plan(task, delta4, PlanOptions(time="fit")).duration.seconds
    opt = plan(task, delta4, PlanOptions(time="optimal"))
    assert opt.report.ok and opt.duration.seconds < fit  # the law is shorter and every limit holds
    # the composed angle law still ends exactly at the angle asked for (round-off of the time law's table)
    assert opt.joint.q[0, 3] == pytest.approx(0.0, abs=1e-12) and opt.joint.q[-1, 3] == pytest.approx(math.pi, abs=1e-9)
    assert opt.joint.qd[[0, -1], 3] == pytest.approx([0.0, 0.0], abs=1e-9)


def test_shape_and_the_conveyor_method_carry_the_turn(delta4):
    task = Task(A, B, 0.025, theta_from=0.0, theta_to=math.pi)
    shaped = plan(task, delta4, PlanOptions(time="fit", shape=True))
    assert shaped.report.ok and shaped.joint.q[-1, 3] == pytest.approx(math.pi, abs=1e-12)
    belt = Task(A, B, 0.025, v_from=[0, 0.3, 0], v_to=[0, 0.3, 0], theta_from=0.0, theta_to=1.0)
    vel = plan(belt, delta4, PlanOptions(method="bspline-vel", time="fit"))
    assert vel.report.ok and vel.joint.q[-1, 3] == pytest.approx(1.0, abs=1e-12)


@pytest.mark.parametrize("method", ["bspline", "ph", "superposition", "lame", "piecewise-poly"])
def test_every_method_turns(delta4, method):
    res = plan(Task(A, B, 0.025, theta_from=0.0, theta_to=1.0), delta4, PlanOptions(method=method, fit=False))
    assert res.joint.q[-1, 3] == pytest.approx(1.0, abs=1e-12) and res.joint.qd[-1, 3] == pytest.approx(0.0, abs=1e-12)


def test_rms_over_the_round_trip_with_the_turn_back(delta4):
    """The report's RMS (the move back retraces the move) against the written round trip: there (turning by +Δ),
    dwell, back (turning by −Δ), dwell, integrated from its samples (trapezoid at 20 kHz: < 1e-5 relative)."""
    task = Task(A, B, 0.025, theta_from=0.0, theta_to=2.5)
    opts = PlanOptions(time="fit", rate=20000.0)
    there = plan(task, delta4, opts)
    back = plan(Task(B, A, 0.025, theta_from=there.task.theta_to, theta_to=0.0), delta4,
                PlanOptions(time=there.duration.seconds, rate=20000.0, fit=False, turn="as-given"))
    trip = round_trip(there, back, delta4.planning.dwell, 20000.0)
    mt = trip.joint.motor_torque
    total = trip.t[-1] - trip.t[0]
    for k, joint in enumerate(("q1", "q2", "q3", "q4")):
        written = math.sqrt(np.trapezoid(mt[:, k] ** 2, trip.t) / total)
        row = next(r for r in there.report.rows if r.joint == joint and r.quantity == "rms motor torque")
        assert row.peak == pytest.approx(written, rel=0.005), joint  # the 0.5 %
