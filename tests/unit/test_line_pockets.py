"""Placing into pockets on an outgoing belt (``place.belt.pitch``): each part is met with a pocket like the pick meets a
part — against independent computations:

* pocket k passes the place point at first + k·pitch/speed (written out here); the engine's place point is that
  pocket's position at the end of the place move (line frame → base frame by hand) within 1e-9 m, within ``reach``
  of the point along the outgoing belt;
* the planner (plan(), bspline-vel with the leg's shape and duration) run from the leg's start to that point ends
  there within 1e-6 m with the outgoing belt's velocity within 1e-6 m/s, and its limit report holds;
* every pocket is used at most once, in order; the release moves on with the pocket.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from pickplace_cli.line.engine import LineEngine
from pickplace_cli.line.parts import generate
from pickplace_cli.line.spec import parse_line
from pickplace_cli.model.errors import ProfileError
from pickplace_cli.model.profile import load_profile

PROFILE = load_profile()
POCKETS = {"r1": ((0.6, 0.35, 0.0), (-0.2, 0.0), 0.12, 0.3, 0.1), "r2": ((1.45, 0.35, 0.0), (0.1, 0.2), 0.15, 1.0, None)}
LINE = """\
belt: {speed: 0.3, width: 0.2, direction: +y}
robots:
  - name: r1
    base: [0.6, 0.0, 0.8]
    window: [0.4, 0.8]
    place: {belt: {point: [0.6, 0.35, 0.0], velocity: [-0.2, 0.0], pitch: 0.12, first: 0.3, reach: 0.1}}
  - name: r2
    base: [1.4, 0.0, 0.8]
    window: [1.2, 1.6]
    place: {belt: {point: [1.45, 0.35, 0.0], velocity: [0.1, 0.2], pitch: 0.15, first: 1.0}}
parts:
  generate: {rate: 3.0, count: 40, seed: 4}
  latency: 0.05
  height: 0.01
"""


def _robot_point(base, p):
    """Line frame → the base frame of a robot whose y axis is the belt's direction (+y), written out."""
    return np.array([-(p[1] - base[1]), p[0] - base[0], p[2] - base[2]])


@pytest.fixture(scope="module")
def run():
    line = parse_line(LINE, "l.yaml")
    eng = LineEngine(line, {r.name: PROFILE for r in line.robots})
    for d in generate(line.parts.generate, line.belt.width):
        eng.offer(d)
    return line, eng, eng.finish()


def test_every_place_meets_its_pocket(run):
    from pickplace_cli.model.task import Task
    from pickplace_cli.planner import PlanOptions, plan

    line, eng, _ = run
    bases = {r.name: r.base for r in line.robots}
    for name, (point, vel, pitch, first, reach) in POCKETS.items():
        reach = pitch / 2 if reach is None else reach
        speed = math.hypot(*vel)
        v_robot = np.array([-vel[1], vel[0], 0.0])
        mine = sorted((res.cycle for res in eng.results if res.robot == name), key=lambda c: c.t_start)
        assert len(mine) >= 8, name
        pockets = [c.target for c in mine]
        assert pockets == sorted(set(pockets))  # each pocket once, in order
        for c in mine:
            place = next(leg for leg in c.legs if leg.kind == "place")
            t_k = first + c.target * pitch / speed
            offset = speed * (place.t1 - t_k)  # how far the pocket is past the point when the tool meets it
            assert abs(offset) <= reach + 1e-9
            at = np.array(point) + np.array([vel[0], vel[1], 0.0]) * (place.t1 - t_k)
            target = _robot_point(bases[name], at)
            assert np.abs(c.place_point - target).max() < 1e-9
            mv = place.solved.move
            got = plan(Task(mv.start, target, PROFILE.planning.height, PROFILE.planning.eta, mv.v_from, v_robot),
                       PROFILE, PlanOptions(method="bspline-vel", method_params={"params": list(mv.basis.params)},
                                            time=place.duration, fit=False))
            assert np.abs(got.p[-1] - target).max() < 1e-6
            assert np.abs(got.v[-1] - v_robot).max() < 1e-6
            assert not [r for r in got.report.violations if r.quantity != "rms motor torque"]
            release = next(leg for leg in c.legs if leg.kind == "release")
            assert np.abs(release.velocity - v_robot).max() < 1e-12  # the tool moves on with the pocket


@pytest.mark.parametrize("old,new,text", [
    ("velocity: [-0.2, 0.0], pitch: 0.12", "velocity: [0.0, 0.0], pitch: 0.12",
     "pockets on a belt that stands still are fixed points"),
    ("pitch: 0.12, first: 0.3, reach: 0.1", "first: 0.3, reach: 0.1", "first and reach are for pockets: give pitch"),
    ("pitch: 0.12", "pitch: 0", "pitch = 0: Input should be greater than 0"),
    ("    window: [0.4, 0.8]\n", "    window: [0.4, 0.8]\n    shape: optimal\n",
     "shape: optimal does not place into pockets"),
])
def test_bad_pockets_are_one_line(old, new, text):
    assert old in LINE
    with pytest.raises(ProfileError, match=text):
        line = parse_line(LINE.replace(old, new), "l.yaml")
        LineEngine(line, {r.name: PROFILE for r in line.robots})
