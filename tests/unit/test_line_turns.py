"""A mixed line with a 4-axis Delta (delta-4axis: a rotary fourth axis) that turns every part from the angle it lies
at to its tray slot's angle, and a 3-axis Delta (delta-su2018) that cannot turn one, against independent
computations:

* every pick of the 4-axis Delta meets its part: the planner (plan(), bspline-vel with the leg's shape and
  duration, the tool angles at both ends, ``turn = as-given``) run to the part's position at the meeting time worked
  out by hand from the detection ends there within 1e-6 m and with the belt's velocity within 1e-6 m/s;
* every place move re-planned the same way ends with the joint q4 (= the tool angle on this Delta, sign +1) at
  the slot's angle turned into the base frame by hand (+π/2 for a belt along +y), modulo 2π, within 1e-9 rad, and
  the tool holds the part's angle (plus the same π/2) at the grip within 1e-9 rad; its limit report holds;
* the 3-axis Delta never takes a part whose turn to the place angle is above its tolerance, and says why;
* each robot's RMS motor torque over the run (the fourth axis' included) agrees within 0.5 % with the trapezoid
  integral of the motor torque written to the run's MCAP file at 1 kHz (the trapezoid's error at 1 kHz on moves
  of ~0.2 s is ~1e-5 relative; 0.5 % is the tolerance of the line's other RMS tests);
* the tray is exchanged after every 4th place: the next place move arrives at least 1.5 s after the release of
  the 4th part (1e-9 s), and the slots start again at the first;
* a SCARA (J4 on link 2: tool angle q1 + q2 + q4) in the manual's mixed line puts its parts down at its points'
  angles the same way (1e-9 rad);
* under ``time: fit`` a turn lengthens the place move, and the move is at its fit: a limit is used between 98 %
  and 100 % (the planner's exact check at the line's duration).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from pickplace_cli.line.engine import LineEngine
from pickplace_cli.line.parts import generate
from pickplace_cli.line.spec import parse_line
from pickplace_cli.model.profile import load_profile

FOUR = load_profile("delta-4axis")
THREE = load_profile("delta-su2018")
SLOTS = [0.0, 0.5, -1.2, 3.0]  # rad, line frame: one per tray slot, row by row
EXCHANGE = 1.5  # s: a full tray (4 places) is replaced in this time, during which d4 cannot place
LINE = f"""\
belt: {{speed: 0.3, width: 0.2, direction: +y}}
robots:
  - name: d4
    profile: delta-4axis
    base: [0.6, 0.0, 0.8]
    window: [0.4, 0.8]
    place: {{tray: {{origin: [0.55, 0.35, 0.0], rows: 2, columns: 2, pitch: [0.05, 0.05]}}, angle: {SLOTS},
            exchange: {{time: {EXCHANGE}}}}}
  - name: d3
    profile: delta-su2018
    base: [1.4, 0.0, 0.8]
    window: [1.2, 1.6]
    place: {{points: [[1.4, 0.35, 0.0]], angle: 0.5, angle_tolerance: 0.6}}
parts:
  generate: {{rate: 2.5, count: 50, seed: 3, angles: true}}
  latency: 0.05
  height: 0.01
"""
PROFILES = {"d4": FOUR, "d3": THREE}


def _wrap(x: float) -> float:
    """x into (−π, π] (written out: not the code's turn rule)."""
    y = math.fmod(x + math.pi, 2 * math.pi)
    y = y + 2 * math.pi if y <= 0 else y
    return y - math.pi


@pytest.fixture(scope="module")
def run():
    line = parse_line(LINE, "l.yaml")
    eng = LineEngine(line, PROFILES)
    for d in generate(line.parts.generate, line.belt.width):
        eng.offer(d)
    return line, eng, eng.finish()


def _robot_point(spec, along, across, height):
    """Line frame → the base frame of a robot whose y axis is the belt's direction (+y), written out."""
    b = spec.base
    return np.array([-(across - b[1]), along - b[0], height - b[2]])


def _replan(mv, T, target, v_to):
    from pickplace_cli.model.task import Task
    from pickplace_cli.planner import PlanOptions, plan

    task = Task(mv.start, target, FOUR.planning.height, FOUR.planning.eta, mv.v_from, v_to, mv.theta,
                mv.theta + mv.turn)
    return plan(task, FOUR, PlanOptions(method="bspline-vel", method_params={"params": list(mv.basis.params)},
                                        time=T, fit=False, turn="as-given"))


def test_every_pick_meets_and_every_place_ends_at_the_slot_angle(run):
    line, eng, _ = run
    spec = line.robots[0]
    v_belt = np.array([0.0, line.belt.speed, 0.0])
    turned = 0
    mine = [res for res in eng.results if res.robot == "d4"]
    assert len(mine) >= 20
    for res in mine:
        d, c = res.detection, res.cycle
        pick = c.pick
        along = d.along + line.belt.speed * (c.t_meet - d.t)
        target = _robot_point(spec, along, d.across, line.parts.height)
        got = _replan(pick.solved.move, pick.duration, target, v_belt)
        assert np.abs(got.p[-1] - target).max() < 1e-6
        assert np.abs(got.v[-1] - v_belt).max() < 1e-6
        # the gripper takes the part as it lies: q4 at the meeting = the part's angle + π/2 (mod 2π)
        assert abs(_wrap(got.joint.q[-1, 3] - (d.angle + math.pi / 2))) < 1e-9
        place = next(leg for leg in c.legs if leg.kind == "place")
        slot = SLOTS[c.target]
        got = _replan(place.solved.move, place.duration, c.place_point, np.zeros(3))
        assert abs(_wrap(got.joint.q[-1, 3] - (slot + math.pi / 2))) < 1e-9, (got.joint.q[-1, 3], slot)
        assert abs(got.joint.q[-1, 3]) <= math.pi + 1e-12  # the tool puts parts down within half a turn of 0
        assert abs(_wrap(place.solved.move.turn - (slot - d.angle))) < 1e-9
        assert abs(place.solved.move.turn) <= math.pi + 1e-12
        bad = [r for r in got.report.violations if r.quantity != "rms motor torque"]
        assert not bad, bad
        turned += abs(place.solved.move.turn) > 0.1
    assert turned >= 15


def test_a_robot_without_the_axis_leaves_the_parts_it_would_have_to_turn(run):
    _, eng, _ = run
    taken = [res for res in eng.results if res.robot == "d3"]
    assert taken  # it takes what lies within its tolerance
    for res in taken:
        assert abs(_wrap(0.5 - res.detection.angle)) <= 0.6
        assert res.cycle.pick.solved.move.turn == 0.0
    refused = [res for res in eng.results if res.robot != "d3" and "d3" in res.declines
               and abs(_wrap(0.5 - res.detection.angle)) > 0.6]
    assert refused
    for res in refused:
        why = res.declines["d3"]
        assert "no rotary fourth axis" in why and "angle_tolerance = 0.6 rad" in why, why
    missed = [res for res in eng.results if not res.picked]
    assert any("no rotary fourth axis" in res.reason for res in missed)


def test_rms_over_the_run_against_the_written_motor_torque(run):
    from tests.reference.line_rms import trapezoid_rms, written_run

    _, eng, s = run
    written = written_run(eng, s)
    for r in s.robots:
        tt, tau, _ = written[r.name]
        assert tt[-1] - tt[0] == pytest.approx(s.span, abs=2e-9)
        assert len(r.rms) == (4 if r.name == "d4" else 3)
        assert np.allclose(r.rms, trapezoid_rms(tt, tau), rtol=5e-3), (r.name, r.rms, trapezoid_rms(tt, tau))
    q4 = written["d4"][2][:, 3]
    assert np.ptp(q4) > 1.0  # the written fourth axis turns
    assert np.abs(q4).max() <= 2 * math.pi  # and stays in its range


def test_a_turn_lengthens_the_move_at_fit_and_the_move_is_at_its_fit():
    from pickplace_cli.line.moves import Shapes
    from pickplace_cli.line.robot import LineRobot, TIMED

    text = LINE.replace("    window: [0.4, 0.8]\n", "    window: [0.4, 0.8]\n    time: fit\n")
    line = parse_line(text, "l.yaml")
    robot = LineRobot(line.robots[0], line, FOUR, Shapes.shared(), 0.0, 0.01)
    leave = robot.part_at(0.6, 0.0) + robot.v_belt * robot.dwell
    target = robot.targets[0][0]
    plain = robot._solve(robot._place_moves(leave, target, np.zeros(3)), 1e-2, 20.0)
    turning = robot._solve(robot._place_moves(leave, target, np.zeros(3), (0.0, math.pi)), 1e-2, 20.0)
    assert turning.T > plain.T * 1.01
    got = _replan(turning.move, turning.T, target, np.zeros(3))
    timed = [r.utilisation for r in got.report.rows if r.quantity in TIMED]
    assert 0.98 <= max(timed) <= 1.0 + 1e-9
    worst = max((r for r in got.report.rows if r.quantity in TIMED), key=lambda r: r.utilisation)
    assert worst.joint == "q4"  # the turn binds
    assert abs(got.joint.q[-1, 3] - math.pi) < 1e-9


def test_the_tray_is_exchanged_after_every_full_tray(run):
    _, eng, _ = run
    mine = sorted((res.cycle for res in eng.results if res.robot == "d4"), key=lambda c: c.t_start)
    assert len(mine) >= 12
    assert [c.target for c in mine] == [k % 4 for k in range(len(mine))]
    waits = []
    for k in range(4, len(mine), 4):
        full = mine[k - 1].t_free  # the 4th part released: the tray is replaced from then on
        assert mine[k].t_placed >= full + EXCHANGE - 1e-9
        waits.append(mine[k].t_placed - full)
    assert min(waits) < EXCHANGE + 0.5  # the next cycle is started so as to place soon after, not held back further
    robot = eng.robots[0]
    assert len(robot.exchanges) == len(mine) // 4
    assert any("its place is exchanged until" in why for res in eng.results for why in res.declines.values()
               if isinstance(why, str))


def test_the_turn_window_is_turneds():
    """The window of a move's turn from its height's piece polynomials equals turned()'s (sampled, then bisected to
    1e-12) within 1e-9 in τ on 40 random moves of two shapes (rest or belt velocity at the start, unequal heights)."""
    from pickplace_cli.curves.vel_problem import PAPER_INITIAL
    from pickplace_cli.line.moves import Move, Shapes, transfer_window
    from pickplace_cli.paths.turn import turned

    shapes = Shapes.shared()
    rng = np.random.default_rng(11)
    for i in range(40):
        basis = shapes.basis(PAPER_INITIAL if i % 2 else [0.05, 0.2, 0.8, 0.95, 0.2, 0.5, 0.2])
        start = np.array([*rng.uniform(-0.2, 0.2, 2), -0.79])
        end = np.array([*rng.uniform(-0.3, 0.3, 2), -0.8 + rng.uniform(0.0, 0.05)])
        v0 = np.array([0.0, rng.uniform(0.0, 1.0), 0.0]) if i % 3 else np.zeros(3)
        mv = Move(basis, start, v0, end, np.zeros(3), np.zeros(3), 0.025, 0.5, 0.3, rng.uniform(-3.0, 3.0))
        law = turned(mv.path(0.3, angle=False), mv.task(0.3), "transfer").angle
        got = transfer_window(mv)
        assert abs(got[0] - law.tau0) < 1e-9 and abs(got[1] - law.tau1) < 1e-9, (got, law.tau0, law.tau1)
        assert mv.path(0.3).angle.tau0 == got[0]  # the leg's path carries that window


def test_a_scara_turns_the_part_with_its_arm_counted():
    """docs/line/mixed.yaml with parts at random angles and the SCARA's two place points at 0 and 1.5 rad: each of
    its place moves, re-planned by the planner, ends with the tool angle q1 + q2 + q4 (the SCARA's J4 sits on link 2:
    written out here from the profile's sign +1) at its point's angle + π/2 (mod 2π) within 1e-9 rad, and holds
    every limit; the 4-axis Delta and the gantry beside it place as the parts lie (their places give no angle)."""
    from pathlib import Path

    from pickplace_cli.model.task import Task
    from pickplace_cli.planner import PlanOptions, plan

    text = Path(__file__).parents[2].joinpath("docs", "line", "mixed.yaml").read_text()
    text = text.replace("    place: {points: [[0.3, 0.2, 0.0], [-0.3, 0.2, 0.0]]}",
                        "    place: {points: [[0.3, 0.2, 0.0], [-0.3, 0.2, 0.0]], angle: [0.0, 1.5]}")
    text = text.replace("detect_at: -0.6}", "detect_at: -0.6, angles: true}")
    assert "angle: [0.0, 1.5]" in text and "angles: true" in text
    line = parse_line(text, "mixed.yaml")
    profiles = {r.name: load_profile(r.profile) for r in line.robots}
    eng = LineEngine(line, profiles)
    for d in generate(line.parts.generate, line.belt.width):
        eng.offer(d)
    scara = profiles["s1"]
    mine = [res for res in eng.results if res.robot == "s1"]
    assert len(mine) >= 5
    for res in mine:
        place = next(leg for leg in res.cycle.legs if leg.kind == "place")
        mv = place.solved.move
        task = Task(mv.start, mv.end(place.duration), scara.planning.height, scara.planning.eta, mv.v_from, mv.v_to,
                    mv.theta, mv.theta + mv.turn)
        got = plan(task, scara, PlanOptions(method="bspline-vel", method_params={"params": list(mv.basis.params)},
                                            time=place.duration, fit=False, turn="as-given"))
        q = got.joint.q[-1]
        slot = [0.0, 1.5][res.cycle.target]
        assert abs(_wrap(q[0] + q[1] + q[3] - (slot + math.pi / 2))) < 1e-9
        assert abs(_wrap(mv.turn - (slot - res.detection.angle))) < 1e-9
        bad = [r for r in got.report.violations if r.quantity != "rms motor torque"]
        assert not bad, bad
    others = [res for res in eng.results if res.robot in ("d4", "g1")]
    assert others and all(res.cycle.pick.solved.move.turn == 0.0 for res in others)
