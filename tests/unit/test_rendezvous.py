"""Conveyor rendezvous (issue 17): the move meets a part on a belt with the belt's velocity."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pickplace_cli.model.errors import TaskError, UnreachableError, UsageError
from pickplace_cli.model.profile import load_profile
from pickplace_cli.pipelines.rendezvous import Part, find_rendezvous, plan_rendezvous

#: (profile, a working point the moves stay near [m], radius of the random starts [m])
SITES = {
    "delta-su2018": (np.array([0.0, 0.0, -0.8]), 0.2),
    "scara-600": (np.array([0.4, 0.0, -0.1]), 0.12),
    "gantry": (np.array([0.0, 0.0, -0.5]), 0.3),
}


def random_case(rng, name):
    """A start and a part that comes towards the working point (so a rendezvous exists): detected 0.1–0.2 m
    upstream of it, 0.1–0.5 m/s in a random horizontal direction, latency 0–0.1 s."""
    centre, radius = SITES[name]
    ang, dist = rng.uniform(0, 2 * np.pi), rng.uniform(0.5, 1.0) * radius
    start = centre + dist * np.array([np.cos(ang), np.sin(ang), 0.0])
    d = rng.uniform(0, 2 * np.pi)
    direction = np.array([np.cos(d), np.sin(d), 0.0])
    part = Part(centre - rng.uniform(0.1, 0.2) * direction, rng.uniform(0.1, 0.5) * direction, rng.uniform(0, 0.1))
    return start, part


def assert_meets(plan, part):
    """Position and velocity of the tool equal the part's at the meeting time T: 1e-6 m and 1e-6 m/s (the
    issue's tolerance; the construction gives round-off, ~1e-15)."""
    T = plan.duration.seconds
    assert plan.t[-1] == pytest.approx(T, abs=1e-12)
    for p, v in ((plan.p[-1], plan.v[-1]), (plan.cartesian(np.array([T]), 0)[0], plan.cartesian(np.array([T]), 1)[0])):
        assert np.abs(p - part.at(T)).max() <= 1e-6
        assert np.abs(v - part.velocity).max() <= 1e-6


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(SITES))
def test_exact_meeting_random_cases(name):
    prof = load_profile(name)
    rng = np.random.default_rng(17)
    rules = ["auto", 0.25] + (["fit"] if name != "gantry" else [])
    for k in range(3):
        start, part = random_case(rng, name)
        plan, rv = plan_rendezvous(start, part, prof, time=rules[k % len(rules)])
        assert_meets(plan, part)
        assert np.allclose(rv.meeting_point, part.at(rv.seconds), atol=1e-12, rtol=0)
        assert rv.meeting_time_since_detection == pytest.approx(part.latency + rv.seconds, abs=1e-15)
        assert plan.parameters["rendezvous"]["meeting_time_s"] == rv.seconds


def test_gantry_fit_has_no_timed_limit():
    """The gantry profile has no drives and no joint velocity limits: --time fit has nothing to fit (the same
    one-line error as for a fixed move)."""
    start, part = random_case(np.random.default_rng(1), "gantry")
    with pytest.raises(TaskError, match="no velocity, acceleration, jerk or motor limit"):
        find_rendezvous(start, part, load_profile("gantry"), time="fit")


def test_auto_is_the_fixed_point():
    """T* = T_auto(P(T*)): re-planning the move to the meeting point with the plain --time auto (the lead's
    search, continuation from its own start) gives T* back (relative 1e-6: the lead's brentq root refined to
    1e-8, the rendezvous's secant root to 1e-6, both nudged to the feasible side), and the capacity bound holds at T* to round-off."""
    from pickplace_cli.paths.bspline_vel import PathFactory
    from pickplace_cli.timing import auto_duration, choose_duration_for

    prof = load_profile("delta-su2018")
    part = Part(np.array([0.1525, -0.1, -0.8]), np.array([0.0, 0.5, 0.0]), 0.05)
    rv = find_rendezvous(np.array([-0.1525, 0.0, -0.8]), part, prof, "auto")
    tv, ta, tj, _ = auto_duration(rv.path, prof.capacity)
    assert max(tv, ta, tj or 0) <= rv.seconds * (1 + 1e-12)
    d, _ = choose_duration_for(PathFactory(rv.task), prof.capacity, "auto")
    assert d.seconds == pytest.approx(rv.seconds, rel=1e-6)


def test_fit_is_the_fixed_point():
    """T* = T_fit(P(T*)) on the Delta (relative 1e-5: the lead's fit stops at rtol 1e-7 and both are nudged
    by the exact check), and every limit holds at T*."""
    from pickplace_cli.paths.bspline_vel import PathFactory
    from pickplace_cli.planner import motion_model
    from pickplace_cli.timing import choose_duration_for

    prof = load_profile("delta-su2018")
    part = Part(np.array([0.1525, -0.1, -0.8]), np.array([0.0, 0.5, 0.0]), 0.0)
    plan, rv = plan_rendezvous(np.array([-0.1525, 0.0, -0.8]), part, prof, "fit")
    assert plan.report.ok
    d, _ = choose_duration_for(PathFactory(rv.task), prof.capacity, "fit",
                               model_of=lambda p: motion_model(p, prof), dwell=prof.planning.dwell)
    assert d.seconds == pytest.approx(rv.seconds, rel=1e-5)


@pytest.mark.parametrize("power, k", [(1.0, 1), (3.0, 3), (3.0, 2), (3.0, 1)])
def test_root_near_finds_the_crossing(power, k):
    """The secant search lands on the feasible side within 1e-6 of the root of (c/T)^k − 1 from 40 % above or
    below it, whatever the power it assumes; with noise of 1e-7 on e it still settles; e(a) ≤ 0 gives a, an
    infeasible window end gives None (the caller's scan then reports the miss)."""
    from pickplace_cli.pipelines.rendezvous import _root_near

    c = 0.123
    for start in (0.6 * c, 1.4 * c):
        calls = []

        def e(T):
            calls.append(T)
            return (c / T) ** k - 1.0

        T = _root_near(e, 0.01, 10.0, start, power=power)
        assert T is not None and e(T) <= 0 and T == pytest.approx(c, rel=1e-6)
        assert len(calls) <= 12
    rng = np.random.default_rng(3)
    T = _root_near(lambda T: (c / T) ** k - 1.0 + 1e-7 * rng.standard_normal(), 0.01, 10.0, 1.3 * c, power=power)
    assert T is None or T == pytest.approx(c, rel=1e-5)
    assert _root_near(lambda T: (c / T) ** k - 1.0, 0.2, 10.0, 0.5, power=power) == 0.2
    assert _root_near(lambda T: (c / T) ** k - 1.0, 0.01, 0.1, 0.05, power=power) is None


@pytest.mark.parametrize("rule", ["auto", "fit"])
def test_secant_root_is_the_scanned_root(rule, monkeypatch):
    """The rendezvous's secant search (a few continued solves) finds the T of the scan it replaced (steps of
    2 % down from the screened root, then brentq to 1e-8) on random Delta cases, to 2e-5 relative (the secant
    search stops at ROOT_RTOL = 1e-5)."""
    import pickplace_cli.pipelines.rendezvous as R

    prof = load_profile("delta-su2018")
    rng = np.random.default_rng(21)
    for _ in range(3):
        start, part = random_case(rng, "delta-su2018")
        fast = find_rendezvous(start, part, prof, rule)
        with monkeypatch.context() as m:
            m.setattr(R, "_root_near", lambda *a, **k: None)
            scanned = find_rendezvous(start, part, prof, rule)
        assert fast.seconds == pytest.approx(scanned.seconds, rel=2e-5)
        assert fast.evaluations["exact"] < scanned.evaluations["exact"]


def test_given_seconds_is_one_solve():
    prof = load_profile("delta-su2018")
    part = Part(np.array([0.1, -0.1, -0.8]), np.array([0.0, 0.3, 0.0]), 0.02)
    rv = find_rendezvous(np.array([-0.15, 0.0, -0.8]), part, prof, 0.2)
    assert rv.seconds == 0.2 and rv.duration.mode == "given"
    assert np.allclose(rv.meeting_point, [0.1, -0.1 + 0.3 * 0.22, -0.8], atol=1e-15)
    assert rv.evaluations == {"exact": 1}


def test_optimal_and_explicit_shape_are_refused():
    prof = load_profile("delta-su2018")
    part = Part(np.array([0.1, 0.0, -0.8]), np.array([0.0, 0.3, 0.0]))
    with pytest.raises(UsageError, match="--time optimal"):
        find_rendezvous(np.array([-0.15, 0.0, -0.8]), part, prof, "optimal")
    with pytest.raises(UsageError, match="shape parameters"):
        find_rendezvous(np.array([-0.15, 0.0, -0.8]), part, prof, "auto", method_params={"params": [0.01] * 7})


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"velocity": [0.0, math.nan, 0.0]}, "to-belt = .*finite"),
        ({"velocity": [0.0, math.inf, 0.0]}, "to-belt = .*finite"),
        ({"velocity": [0.0, 1.0]}, "to-belt = .*three"),
        ({"latency": -0.01}, "latency = -0.01: must be a finite number of seconds >= 0"),
        ({"latency": math.inf}, "latency = inf"),
    ],
)
def test_bad_part(kwargs, match):
    args = {"position": [0.1, 0.0, -0.8], "velocity": [0.0, 0.3, 0.0], "latency": 0.0, **kwargs}
    with pytest.raises(TaskError, match=match):
        Part(**args)


@pytest.mark.parametrize("speed, match", [
    (3.0, "the robot cannot reach it before it leaves the workspace .*--time auto needs longer"),
    (8.0, "it is never inside the workspace of profile delta-su2018 for the pick and 0.1 s of tracking"),
])
def test_belt_faster_than_the_robot_has_no_rendezvous(speed, match):
    """A part running away at 3 m/s is never caught under the capacity; at 8 m/s the tracking segment alone
    (0.8 m) does not fit in the workspace: one line each, exit 4."""
    prof = load_profile("delta-su2018")
    part = Part(np.array([0.0, 0.0, -0.8]), np.array([speed, 0.0, 0.0]))
    with pytest.raises(UnreachableError, match=rf"part \(detected at 0,0,-0.8 m, belt {speed:g},0,0 m/s\): {match}") as exc:
        find_rendezvous(np.array([-0.15, 0.0, -0.8]), part, prof, "auto")
    assert "\n" not in str(exc.value) and exc.value.exit_code == 4


@pytest.mark.parametrize("name", ["delta-su2018", "scara-600", "gantry"])
def test_tracking_segment_follows_the_part(name):
    """t from T to T + dwell: the tool is where the part is (1e-9 m: round-off of P + v·t) with its velocity,
    zero acceleration and jerk; the joint columns come from the robot's IK (FK of q gives p back, 1e-9 m) and
    the segment is limit-checked; the joined trajectory has strictly increasing t and no duplicate meeting."""
    from pickplace_cli.planner import motion_model_static
    from pickplace_cli.pipelines.tracking import plan_tracking, with_tracking

    prof = load_profile(name)
    start, part = random_case(np.random.default_rng(5), name)
    move, rv = plan_rendezvous(start, part, prof, "auto")
    track = plan_tracking(move, part, prof)
    T, D = rv.seconds, prof.planning.dwell
    assert track.t[-1] == pytest.approx(D, abs=1e-12)
    assert np.abs(track.p - part.at(T + track.t)).max() <= 1e-9
    assert np.abs(track.v - part.velocity).max() <= 1e-12 and not track.a.any() and not track.j.any()
    robot = motion_model_static(prof)[0]
    assert np.abs(robot.forward_kinematics(track.joint.q) - track.p).max() <= 1e-9
    assert track.report.rows and track.report.duration == D
    # the limit table's t_peak is trajectory time (T … T + dwell), not the segment's own clock (1e-12: round-off)
    peaks = [r.t_peak for r in track.report.rows if r.t_peak is not None]
    assert peaks and all(T - 1e-12 <= t <= T + D + 1e-12 for t in peaks)
    tl = with_tracking(move, track)
    assert np.all(np.diff(tl.t) > 0) and tl.t[-1] == pytest.approx(T + D, abs=1e-12)
    assert len(tl.t) == len(move.t) + len(track.t) - 1
    assert [s.label for s in tl.segments] == ["move", "track"]
    after = tl.t >= T
    assert np.abs(tl.p[after] - part.at(tl.t[after])).max() <= 1e-9


# ------------------------------------------------------------------------------------------ belt window

START = np.array([-0.1525, 0.0, -0.8])


def with_window(lo_y, hi_y, name="delta-su2018"):
    """The profile with a belt window x ∈ [0, 0.3], y ∈ [lo_y, hi_y], z ∈ [-0.9, -0.7] m (a belt along +y)."""
    from pickplace_cli.model.profile import Box

    prof = load_profile(name)
    wc = prof.workcell.model_copy(update={"belt_window": Box(min=(0.0, lo_y, -0.9), max=(0.3, hi_y, -0.7))})
    return prof.model_copy(update={"workcell": wc})


def test_window_inside_changes_nothing():
    part = Part(np.array([0.1525, -0.1, -0.8]), np.array([0.0, 0.5, 0.0]))
    free = find_rendezvous(START, part, load_profile("delta-su2018"), "auto")
    win = find_rendezvous(START, part, with_window(-0.3, 0.1), "auto")
    assert win.seconds == pytest.approx(free.seconds, rel=1e-9)
    assert win.window_s[1] == pytest.approx((0.1 + 0.1) / 0.5 - 0.1, abs=1e-12)  # exit at y = 0.1, minus the dwell


def test_part_leaves_the_window_before_the_robot_reaches_it():
    """Window exit at y = 0 (t = 0.2 s): with 0.1 s of tracking the last meeting is t = 0.1 s; the earliest
    feasible meeting is T ≈ 0.18 s, so the part is missed by 0.5 m/s × (0.18 − 0.1) s ≈ 40 mm."""
    part = Part(np.array([0.1525, -0.1, -0.8]), np.array([0.0, 0.5, 0.0]))
    T = find_rendezvous(START, part, load_profile("delta-su2018"), "auto").seconds
    with pytest.raises(UnreachableError) as exc:
        find_rendezvous(START, part, with_window(-0.3, 0.0), "auto")
    msg = str(exc.value)
    assert f"the part leaves the belt window {0.5 * (T - 0.1) * 1e3:.0f} mm before the robot can reach it" in msg, msg
    assert msg.startswith("part (detected at 0.1525,-0.1,-0.8 m, belt 0,0.5,0 m/s)") and "\n" not in msg


def test_part_already_past_the_window():
    part = Part(np.array([0.1525, 0.2, -0.8]), np.array([0.0, 0.5, 0.0]), latency=0.05)
    with pytest.raises(UnreachableError, match=r"already past the belt window when the move starts \(latency 0.05 s\): "
                       r"it leaves the window \d+ mm before"):
        find_rendezvous(START, part, with_window(-0.3, 0.1), "auto")


def test_window_missed_by_the_path():
    part = Part(np.array([0.5, -0.1, -0.8]), np.array([0.0, 0.5, 0.0]))  # x = 0.5: beside the window
    with pytest.raises(UnreachableError, match="its path never crosses the belt window"):
        find_rendezvous(START, part, with_window(-0.3, 0.1), "auto")


def test_robot_waits_for_a_part_upstream_of_the_window():
    """The part enters the window (y = −0.1) at t = 0.8 s, long after the robot could be there: the robot meets
    it exactly at the window's edge, on time, with its velocity (a longer move that still meets the rule)."""
    part = Part(np.array([0.1525, -0.5, -0.8]), np.array([0.0, 0.5, 0.0]))
    plan, rv = plan_rendezvous(START, part, with_window(-0.1, 0.3), "auto")
    assert rv.waited and rv.seconds == pytest.approx(0.8, abs=1e-9)
    assert rv.meeting_point[1] == pytest.approx(-0.1, abs=1e-9)
    assert_meets(plan, part)


def test_given_time_outside_the_window():
    part = Part(np.array([0.1525, -0.1, -0.8]), np.array([0.0, 0.5, 0.0]))
    with pytest.raises(UnreachableError, match=r"--time 0.15 s meets it at t = 0.1500 s, 25 mm after the last point"):
        find_rendezvous(START, part, with_window(-0.3, 0.0), 0.15)


def test_window_must_intersect_the_box():
    from pydantic import ValidationError

    from pickplace_cli.model.profile import Box, Workcell

    box = load_profile("delta-su2018").workcell.box
    with pytest.raises(ValidationError, match="does not intersect the workcell box"):
        Workcell(box=box, belt_window=Box(min=(0.0, 0.7, -0.9), max=(0.3, 0.9, -0.7)))


def test_belt_move_is_the_move_and_its_tracking():
    """plan_belt_move (a plain batch's belt row): the samples run to T + dwell, the limit report holds the move's
    rows and the tracking segment's (marked, times after T), as plan_rendezvous and plan_tracking give them."""
    from pickplace_cli.pipelines.tracking import plan_belt_move, plan_tracking

    prof = load_profile("delta-su2018")
    part = Part(np.array([0.1525, -0.1, -0.8]), np.array([0.0, 0.5, 0.0]), 0.05)
    start = np.array([-0.1525, 0.0, -0.8])
    both = plan_belt_move(start, part, prof)
    move, rv = plan_rendezvous(start, part, prof)
    track = plan_tracking(move, part, prof)
    T = rv.seconds
    assert both.t[-1] == pytest.approx(T + prof.planning.dwell) and len(both.t) == len(move.t) + len(track.t) - 1
    assert len(both.report.rows) == len(move.report.rows) + len(track.report.rows)
    marked = [r for r in both.report.rows if r.quantity.endswith("(tracking)")]
    assert len(marked) == len(track.report.rows)
    assert all(r.t_peak is None or r.t_peak >= T - 1e-12 for r in marked)
    assert both.parameters["tracking"]["duration_s"] == prof.planning.dwell and "rendezvous" in both.parameters
    np.testing.assert_allclose(both.p[len(move.t) - 1], part.at(T), atol=1e-9)
