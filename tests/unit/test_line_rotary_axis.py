"""The line's closed form of a decoupled rotary fourth axis (``pickplace_cli/line/rotary_axis.py``) and the fast turned
moves built on it, against independent computations:

* the axis' coefficients on delta-4axis equal the hand derivation from the profile (motor speed N·θ̇, motor torque
  (J_t/(N·η) + J_rotor·N)·θ̈ and its rate the same of θ⃛) within 1e-12 relative (round-off); a SCARA's J4 (on link 2)
  and a Delta without the axis have no closed form;
* T_axis of random turns and windows, checked by the project's exact limit check (``check_limits``, what
  ``plan --turn`` runs) on the move's real path: at T_axis every limit of q4 holds and the largest is used within
  1e-8 of 1 (T_axis is raised by 1e-9 for round-off; the check's refinement is exact to ~1e-12), at
  T_axis·(1 − 1e-6) q4 breaks one; the closed-form values equal the check's q4 rows at T_axis·1.01 within 1e-8 for a
  row within 5 % of its limit (refined exactly there), else within 1e-4 (the check's estimate of a peak away from
  its limit: ZOOM_TOL);
* place moves of a 4-axis Delta with large turns, timed by the line's rule ``limits``, against the single ``plan`` path
  (the planner's bspline-vel of the move's task, shape and tool angles: ``--time fit`` on every motor limit and
  ``--time auto`` on the capacity): the line's duration is never below the longer of both by more than 1e-6 relative
  (the planner's fit stops within ~1e-7 of its root) and above it by at most 3e-4 (the capacity's grid durations are
  raised by GRID_SAFETY = 2e-4 before their exact check); where q4 binds, within 1e-6 of the fit;
* one order of the angle law alone equals that row of all four bit for bit; the turn window's batched quintic roots
  equal numpy.roots' bit for bit;
* a 3-robot line of 4-axis Deltas turning every part (the benchmark's turned line, 20 s): each cycle's check (the
  evaluation kept from the motors' screen, the axis' torque in closed form) equals the model evaluated afresh with the
  tool angle's law (integrals 1e-12; uses 1e-12, the axis' 0.3 %: the grid's estimate); every pick and place move
  it accepts holds every limit (RMS aside: a property of the sequence) under ``check_limits`` on its real path, and
  its first 12 place moves' durations lie in the bracket above against the single ``plan`` path.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from pickplace_cli.line.engine import LineEngine
from pickplace_cli.line.moves import Move, Shapes
from pickplace_cli.line.parts import generate
from pickplace_cli.line.robot import LineRobot
from pickplace_cli.line.rotary_axis import DecoupledAxis
from pickplace_cli.line.spec import parse_line
from pickplace_cli.limits.check import check_limits
from pickplace_cli.model.profile import load_profile
from pickplace_cli.model.task import Task
from pickplace_cli.planner import PlanOptions, motion_model, plan

FOUR = load_profile("delta-4axis")
LINE = """\
belt: {speed: 0.5, width: 0.3, direction: +y}
robots:
  - name: d1
    profile: delta-4axis
    base: [0.6, 0.0, 0.8]
    window: [0.4, 0.8]
    gripper: {close: 0.03, open: 0.02}
    place: {tray: {origin: [0.55, 0.35, 0.0], rows: 3, columns: 2, pitch: [0.05, 0.05]}, angle: 0.0}
  - name: d2
    profile: delta-4axis
    base: [1.4, 0.0, 0.8]
    window: [1.2, 1.6]
    gripper: {close: 0.03, open: 0.02}
    place: {tray: {origin: [1.35, 0.35, 0.0], rows: 3, columns: 2, pitch: [0.05, 0.05]}, angle: 0.0}
  - name: d3
    profile: delta-4axis
    base: [2.2, 0.0, 0.8]
    window: [2.0, 2.4]
    gripper: {close: 0.03, open: 0.02}
    place: {tray: {origin: [2.15, 0.35, 0.0], rows: 3, columns: 2, pitch: [0.05, 0.05]}, angle: 0.0}
parts:
  generate: {rate: 5.0, duration: 20.0, arrival: poisson, seed: 4, angles: true}
  latency: 0.05
strategy: {kind: upstream_first}
"""


def _robot(text: str = LINE) -> LineRobot:
    line = parse_line(text, "l.yaml")
    return LineRobot(line.robots[0], line, FOUR, Shapes.shared(), 0.05, 0.0)


def _q4_rows(rep) -> list:
    return [r for r in rep.rows if r.joint == "q4" and r.quantity not in ("position", "rms motor torque")]


def test_the_coefficients_are_the_profiles_by_hand():
    axis = _robot().axis
    rot = FOUR.robot.rotary
    drive = rot.joint.drive
    j_t = rot.shaft_inertia + rot.tool_inertia + rot.payload_inertia
    torque = j_t / (drive.gear_ratio * drive.efficiency) + drive.rotor_inertia * drive.gear_ratio
    want = {"motor speed": (1, drive.gear_ratio), "motor torque": (2, torque), "motor torque rate": (3, torque)}
    for quantity, (k, c) in want.items():
        got = axis._coef[quantity]
        assert got[0] == k and abs(got[1] - c) <= 1e-12 * c, (quantity, got, c)
    assert axis._coef["position max"][:2] == (0, 1.0) and axis._coef["position min"][:2] == (0, -1.0)


@pytest.mark.parametrize("name", ["scara-600", "delta-su2018"])
def test_no_closed_form_for_a_coupled_axis_or_none(name):
    from pickplace_cli.line.robot import _StandIn, _decoupled_axis
    from pickplace_cli.limits.motion import MotionModel
    from pickplace_cli.planner import motion_model_static

    robot, specs, margin, box, memo = motion_model_static(load_profile(name))
    model = MotionModel(_StandIn(), robot, specs, margin, box, memo)
    point = np.array([0.3, 0.2, 0.0]) if name.startswith("scara") else np.array([0.0, 0.0, -0.8])
    assert _decoupled_axis(model, point) is None


def test_the_shortest_duration_of_a_turn_against_the_exact_check():
    robot = _robot()
    shapes = Shapes.shared()
    rng = np.random.default_rng(7)
    from pickplace_cli.curves.vel_problem import PAPER_INITIAL

    for i in range(12):
        basis = shapes.basis(PAPER_INITIAL if i % 2 else [0.05, 0.2, 0.8, 0.95, 0.2, 0.5, 0.2])
        start = np.array([*rng.uniform(-0.15, 0.15, 2), -0.8])
        end = np.array([*rng.uniform(-0.2, 0.2, 2), -0.8])
        v0 = np.array([0.0, 0.5, 0.0]) if i % 3 else np.zeros(3)
        turn = rng.choice([-1, 1]) * rng.uniform(0.5, math.pi)
        mv = Move(basis, start, v0, end, np.zeros(3), np.zeros(3), 0.025, 0.5, rng.uniform(-1, 1), turn)
        T = robot.axis.shortest(mv)
        rep = check_limits(motion_model(mv.path(T), FOUR), T)
        rows = _q4_rows(rep)
        assert all(r.ok for r in rows), rows
        assert 1 - 1e-8 <= max(r.utilisation for r in rows) <= 1.0, rows
        short = T * (1 - 1e-6)
        assert not all(r.ok for r in _q4_rows(check_limits(motion_model(mv.path(short), FOUR), short)))
        T2 = 1.01 * T
        rep = check_limits(motion_model(mv.path(T2), FOUR), T2)
        meta = robot.model._column_plan(True, True)[0]
        values = robot.axis.values(meta, mv, (mv.theta, mv.theta_end), T2)[0]
        idx = robot.axis.plan(meta)[0]
        by_quantity = {meta[c][1]: v for c, v in zip(idx, values)}
        for r in _q4_rows(rep):  # a row near its limit is refined exactly; the others are the grid's (ZOOM_TOL 1e-4)
            tol = 1e-8 if r.utilisation >= 0.95 else 1e-4
            assert abs(by_quantity[r.quantity] - r.peak) <= tol * r.peak, (r, by_quantity[r.quantity])


def _single_plan(mv: Move, T: float, profile) -> tuple[float, float, object]:
    """(the planner's duration by --time auto, by --time fit, its report at the line's T) of the move's task."""
    task = Task(mv.start, mv.end(T), profile.planning.height, profile.planning.eta, mv.v_from, mv.v_to, mv.theta,
                mv.theta + mv.turn)
    common = {"method": "bspline-vel", "method_params": {"params": list(mv.basis.params)}, "turn": "as-given"}
    auto = plan(task, profile, PlanOptions(time="auto", fit=False, **common)).duration.seconds
    fit = plan(task, profile, PlanOptions(time="fit", **common)).duration.seconds
    at = plan(task, profile, PlanOptions(time=T, fit=False, **common))
    return auto, fit, at


def _bracket(T: float, auto: float, fit: float) -> None:
    ref = max(auto, fit)
    assert ref * (1 - 1e-6) <= T <= ref * (1 + 3e-4), (T, auto, fit)


def test_large_turns_are_timed_as_the_single_plan_path_times_them():
    robot = _robot()
    rng = np.random.default_rng(3)
    bound = 0
    for _ in range(10):
        # short moves (from the belt's tray side to the tray) with large turns: q4 binds about every other one
        leave = robot.part_at(rng.uniform(0.5, 0.65), rng.uniform(0.05, 0.15)) + robot.v_belt * robot.dwell
        target = robot.targets[int(rng.integers(len(robot.targets)))][0]
        turn = (rng.uniform(-1, 1), rng.choice([-1, 1]) * rng.uniform(2.5, math.pi))
        got = robot._solve(robot._place_moves(leave, target, np.zeros(3), turn), 1e-2, 20.0)
        auto, fit, at = _single_plan(got.move, got.T, robot.profile)
        _bracket(got.T, auto, fit)
        assert not [r for r in at.report.violations if r.quantity != "rms motor torque"]
        if robot.axis.use(got.move, got.T) > 1 - 1e-6:
            bound += 1
            assert abs(got.T / fit - 1) <= 1e-6, (got.T, fit)
    assert bound >= 5  # q4 binds (6 of the 10)


@pytest.fixture(scope="module")
def turned():
    line = parse_line(LINE, "l.yaml")
    eng = LineEngine(line, {r.name: FOUR for r in line.robots})
    for d in generate(line.parts.generate, line.belt.width):
        eng.offer(d)
    eng.finish()
    return eng


def test_the_kept_evaluation_and_the_axis_torque_are_the_models(turned):
    """Every accepted cycle's legs as checked (the evaluation kept from the motors' screen, the axis left out of the
    model and its torque added in closed form) against the model evaluated afresh on the same legs with the tool
    angle's law (the axis taken as any coupled one): the ∫ torque² dt of every joint within 1e-12 relative (the
    Gauss–Legendre sums of the same samples: round-off), the end torques within 1e-12 N·m, the use of every limit but
    the axis' within 1e-12 and the axis' within 0.3 % (its closed form against the grid's parabola through samples of
    its peak: the grid's estimates are within 0.2 % of the exact peaks; 2e-4 at most here)."""
    cycles = 0
    for res in turned.results:
        if res.cycle is None:
            continue
        robot = next(r for r in turned.robots if r.name == res.robot)
        legs = res.cycle.legs
        axis, robot.axis, robot._kept = robot.axis, None, None
        try:
            meta, peaks, sums = robot._evaluate(legs)
        finally:
            robot.axis = axis
        uses = robot._use_plan(meta)(peaks)
        for leg, (integral, end), use in zip(legs, sums, uses):
            assert np.allclose(leg.integral, integral, rtol=1e-12, atol=0.0), (leg.kind, leg.integral, integral)
            assert np.abs(leg.end_torque - end).max() <= 1e-12
            if not leg.exact:
                mine = np.array([k[0] == "q4" for k in robot.use_keys])
                assert np.abs(leg.use - use)[~mine].max() <= 1e-12, (leg.kind, leg.use - use)
                assert np.all(np.abs(leg.use - use)[mine] <= 3e-3 * np.maximum(use[mine], 1e-3)), (leg.use - use)
        cycles += 1
    assert cycles >= 50


def test_every_move_of_a_turned_line_holds_every_limit_and_places_are_timed_as_plan_times_them(turned):
    eng = turned
    robots = {r.name: r for r in eng.robots}
    moves = places = bound = 0
    for res in eng.results:
        if res.cycle is None:
            continue
        robot = robots[res.robot]
        for leg in res.cycle.legs:
            if leg.solved is None:
                continue
            mv, T = leg.solved.move, leg.duration
            rep = check_limits(motion_model(mv.path(T), robot.profile), T)
            bad = [r for r in rep.violations if r.quantity != "rms motor torque"]
            assert not bad, (res.robot, leg.kind, bad)
            moves += 1
            bound += robot.axis.use(mv, T) > 1 - 1e-6
            if leg.kind == "place" and places < 12:
                auto, fit, _ = _single_plan(mv, T, robot.profile)
                _bracket(T, auto, fit)
                places += 1
    assert moves >= 100 and places == 12 and bound >= 5, (moves, places, bound)


def test_one_order_of_a_rotation_law_is_that_row_of_all_orders_bitwise():
    """``RotationLaw(tau, k)`` computes the k-th order alone (the line's torque of the axis needs θ″ only): the same
    numbers, bit for bit, as row k of ``all_orders`` (the same operations), inside, outside and at the window's ends."""
    from pickplace_cli.curves.rotation import RotationLaw

    law = RotationLaw(0.3, -2.7, 0.18, 0.83)
    tau = np.concatenate([np.linspace(0.0, 1.0, 257), [0.18, 0.83]])
    rows = law.all_orders(tau)
    for k in range(4):
        assert np.array_equal(law(tau, k), rows[k])


def test_the_batched_quintic_roots_are_numpys():
    """The transfer window's roots, all spans and both heights in one batched eigenvalue call, against
    :func:`numpy.roots` one polynomial at a time (the same companion matrices): equal bit for bit on 200 random
    quintics, those with a zero highest or lowest coefficient (numpy.roots drops them) included."""
    from pickplace_cli.line.moves import _quintic_roots

    rng = np.random.default_rng(2)
    coef = rng.normal(size=(200, 6))
    coef[::7, 0] = 0.0
    coef[3::11, -1] = 0.0
    got = _quintic_roots(coef)
    for c, row in zip(coef, got):
        want = np.roots(c)
        assert np.array_equal(row[: len(want)], want) and np.all(np.isnan(row[len(want):]))
