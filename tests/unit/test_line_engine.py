"""A random 3-robot line (a tray, fixed points, an outgoing belt) against independent computations:

* every pick meets its part: the project's planner (plan(), method bspline-vel with the pick's shape and duration)
  run to the part's position at the meeting time — worked out here from the detection, the belt and the robot's
  base by hand — ends there within 1e-6 m and with the belt's velocity within 1e-6 m/s, and its limit report
  holds (RMS aside: a property of the whole run);
* no robot starts a move before its previous one ends, and each leg starts where (and as fast as) the last one
  ended;
* each robot's RMS motor torque over the run agrees within 0.5 % with the trapezoid integral of the motor
  torque written to the run's MCAP file (1 kHz), decoded by mcap_ros2.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from pickplace_cli.line.engine import LineEngine
from pickplace_cli.line.parts import generate
from pickplace_cli.line.spec import parse_line
from pickplace_cli.model.profile import load_profile

PROFILE = load_profile()
LINE = """\
belt: {speed: 0.4, width: 0.3, direction: +y}
robots:
  - name: r1
    base: [0.6, 0.0, 0.8]
    window: [0.4, 0.8]
    place: {tray: {origin: [0.55, 0.3, 0.0], rows: 2, columns: 2, pitch: [0.05, 0.05]}}
  - name: r2
    base: [1.4, 0.0, 0.8]
    window: [1.2, 1.6]
    place: {points: [[1.4, 0.35, 0.02], [1.45, 0.35, 0.0]]}
  - name: r3
    base: [2.2, 0.02, 0.8]
    window: [2.0, 2.4]
    place: {belt: {point: [2.2, 0.35, 0.0], velocity: [-0.3, 0.0]}}
parts:
  generate: {rate: 4.0, count: 60, seed: 7, angles: true}
  latency: 0.05
  height: 0.01
"""


@pytest.fixture(scope="module")
def run():
    line = parse_line(LINE, "l.yaml")
    eng = LineEngine(line, {r.name: PROFILE for r in line.robots})
    for d in generate(line.parts.generate, line.belt.width):
        eng.offer(d)
    return line, eng, eng.finish()


def _robot_point(spec, along, across, height):
    """Line frame → the base frame of a robot whose y axis is the belt's direction (+y): x = −(across − base),
    y = along − base, z = height − base height (written out, not the code's Frame)."""
    b = spec.base
    return np.array([-(across - b[1]), along - b[0], height - b[2]])


def test_the_run_picks_and_uses_every_robot(run):
    _, eng, s = run
    assert s.picked >= 45 and all(r.picks > 0 for r in s.robots)
    assert any(leg.kind == "stop" for leg in eng.runs[2].legs)  # the outgoing-belt robot came to rest at least once


def test_every_pick_meets_its_part_exactly(run):
    from pickplace_cli.model.task import Task
    from pickplace_cli.planner import PlanOptions, plan

    line, eng, _ = run
    specs = {r.name: r for r in line.robots}
    v_belt = np.array([0.0, line.belt.speed, 0.0])
    checked = 0
    for res in eng.results:
        if res.cycle is None:
            continue
        d, c = res.detection, res.cycle
        pick = c.pick
        along = d.along + line.belt.speed * (c.t_meet - d.t)
        target = _robot_point(specs[res.robot], along, d.across, line.parts.height)
        mv = pick.solved.move
        task = Task(mv.start, target, PROFILE.planning.height, PROFILE.planning.eta, mv.v_from, v_belt)
        got = plan(task, PROFILE, PlanOptions(method="bspline-vel", method_params={"params": list(mv.basis.params)},
                                              time=pick.duration, fit=False))
        assert np.abs(got.p[-1] - target).max() < 1e-6
        assert np.abs(got.v[-1] - v_belt).max() < 1e-6
        assert np.abs(pick.solved.end - target).max() < 1e-6  # the engine's meeting point is that point
        bad = [r for r in got.report.violations if r.quantity != "rms motor torque"]
        assert not bad, bad
        checked += 1
    assert checked >= 45


def test_no_robot_starts_a_move_before_the_last_one_ends(run):
    """From the per-part results (t_start, t_free) and the legs: in time order, each starts at or after the end of
    the one before (1e-9 s), where it ended (1e-9 m) and with its velocity (1e-9 m/s)."""
    _, eng, _ = run
    for robot_run in eng.runs:
        picks = sorted((res.cycle.t_start, res.cycle.t_free) for res in eng.results if res.robot == robot_run.robot.name)
        for (s0, f0), (s1, _) in zip(picks, picks[1:]):
            assert s1 >= f0 - 1e-9
        legs = sorted(robot_run.legs, key=lambda g: g.t0)
        for a, b in zip(legs, legs[1:]):
            assert b.t0 >= a.t1 - 1e-9
            start = b.solved.move.start if b.solved is not None else b.point
            v_start = b.solved.move.v_from if b.solved is not None else b.velocity
            v_end = a.solved.move.v_to if a.solved is not None else a.velocity
            assert np.abs(start - a.end).max() < 1e-9
            if b.t0 == a.t1 or np.any(v_end != 0):  # a leg that starts at once goes on with the motion
                assert np.abs(v_start - v_end).max() < 1e-9


def test_rms_over_the_run_against_the_written_motor_torque(run):
    from tests.reference.line_rms import trapezoid_rms, written_run

    _, eng, s = run
    written = written_run(eng, s)
    for r in s.robots:
        tt, tau, _ = written[r.name]
        assert tt[-1] - tt[0] == pytest.approx(s.span, abs=2e-9)
        assert np.allclose(r.rms, trapezoid_rms(tt, tau), rtol=5e-3), (r.name, r.rms, trapezoid_rms(tt, tau))


def test_a_robot_that_waits_meets_the_part_at_its_window(run):
    line, eng, _ = run
    waited = [res for res in eng.results if res.cycle is not None and res.cycle.waited]
    assert waited
    for res in waited:
        window = next(r.window for r in line.robots if r.name == res.robot)
        assert float(res.cycle.meet_line[0]) == pytest.approx(window[0], abs=1e-9)


@pytest.mark.slow
def test_optimal_shapes_meet_exactly_too():
    """``shape: optimal`` (the project's rendezvous search and planner per move): every pick meets its part as
    above (1e-6 m, 1e-6 m/s, the planner re-run to the part's position worked out by hand)."""
    from pickplace_cli.model.task import Task
    from pickplace_cli.planner import PlanOptions, plan

    text = LINE.replace("    window: [0.4, 0.8]\n", "    window: [0.4, 0.8]\n    shape: optimal\n").replace(
        "count: 60", "count: 4")
    line = parse_line(text, "l.yaml")
    eng = LineEngine(line, {r.name: PROFILE for r in line.robots})
    for d in generate(line.parts.generate, line.belt.width):
        eng.offer(d)
    v_belt = np.array([0.0, line.belt.speed, 0.0])
    spec = line.robots[0]
    mine = [res for res in eng.results if res.robot == "r1"]
    assert mine
    for res in mine:
        d, c = res.detection, res.cycle
        target = _robot_point(spec, d.along + line.belt.speed * (c.t_meet - d.t), d.across, line.parts.height)
        mv = c.pick.solved.move
        got = plan(Task(mv.start, target, PROFILE.planning.height, PROFILE.planning.eta, mv.v_from, v_belt), PROFILE,
                   PlanOptions(method="bspline-vel", method_params={"params": list(mv.basis.params)},
                               time=c.pick.duration, fit=False))
        assert np.abs(got.p[-1] - target).max() < 1e-6 and np.abs(got.v[-1] - v_belt).max() < 1e-6


def test_default_rule_holds_every_limit_and_headroom_caps_the_use():
    """The default duration rule of a line robot is plan's (limits: the motors and the Cartesian capacity); a robot
    with limit_use 0.9 plans every timed limit to at most 90 % of its rating (its reported peak use, against the
    ratings, stays ≤ 0.9 + the screening's 0.5 %), and its moves are never shorter than without headroom."""
    from pickplace_cli.line.summary import summarise

    text = LINE.replace("    window: [0.4, 0.8]\n", "    window: [0.4, 0.8]\n    limit_use: 0.9\n")
    results = {}
    for name, source in (("plain", LINE), ("headroom", text)):
        line = parse_line(source, "l.yaml")
        assert line.robots[0].time is None
        eng = LineEngine(line, {r.name: PROFILE for r in line.robots})
        for d in generate(line.parts.generate, line.belt.width):
            eng.offer(d)
        eng.finish()
        run_r1 = next(r for r in eng.runs if r.robot.name == "r1")
        assert run_r1.robot.rule == "limits"
        picks = [leg for leg in run_r1.legs if leg.kind == "pick"]
        results[name] = (run_r1, picks)
    run_r1, picks = results["headroom"]
    assert run_r1.robot.limit_use == 0.9 and picks
    timed = [i for i, k in enumerate(run_r1.robot.use_keys)
             if not k[1].startswith(("position", "workcell", "singularity"))]
    for leg in picks:
        # the use of the scaled limits (≤ 1 + 0.5 % screening), i.e. ≤ 0.9 of the ratings
        assert max(leg.use[i] for i in timed) <= 1.005


def test_default_rule_screen_gives_the_full_search_s_durations(monkeypatch):
    """Under the rule limits a robot takes the capacity's durations where the motors hold there with room to spare
    (LIMITS_SCREEN); the full search of the rule (every limit on the grid at every trial duration, then the exact
    check) finds the same pick and place durations for the same parts: the capacity search raises its durations by
    the grid's safety (2e-4), and from there on each robot starts its next move from a slightly different state, so
    the two runs drift apart (measured: at most 2.4e-3, median 2e-4)."""
    import pickplace_cli.line.robot as R

    def durations():
        line = parse_line(LINE, "l.yaml")
        eng = LineEngine(line, {r.name: PROFILE for r in line.robots})
        for d in generate(line.parts.generate, line.belt.width):
            eng.offer(d)
        eng.finish()
        return [(r.robot, r.cycle.pick.duration, next(g.duration for g in r.cycle.legs if g.kind == "place"))
                if r.cycle is not None else None for r in eng.results]

    fast = durations()
    monkeypatch.setattr(R, "LIMITS_SCREEN", 0.0)  # nothing clears the screen: every move by the full search
    full = durations()
    gaps: list[float] = []
    for a, b in zip(fast, full):
        if a is None and b is None:
            continue  # missed by both
        if a is None or b is None or a[0] != b[0]:
            break  # (the runs part ways where one robot takes a part the other leaves: compare up to there)
        assert a[1] == pytest.approx(b[1], rel=5e-3) and a[2] == pytest.approx(b[2], rel=5e-3), (a, b)
        gaps += [abs(a[1] / b[1] - 1), abs(a[2] / b[2] - 1)]
    assert len(gaps) >= 40 and float(np.median(gaps)) < 5e-4
