"""A line robot's pick and place with the shapes re-optimised at every trial duration: the project's own
rendezvous search (:func:`~pickplace_cli.pipelines.rendezvous.find_rendezvous`, what ``plan --to-belt`` runs) and
planner (:func:`~pickplace_cli.planner.plan`, method ``bspline-vel`` with its exact solver) instead of the table's
shape held fixed (:mod:`~pickplace_cli.line.moves`). A robot with ``shape: optimal`` plans this way: about a
second a pick, for checking a line's fast results or when the last per cent of a move counts.

The robot's window becomes the profile's belt window (:func:`profile_with_window`), so the rendezvous meets a part
where the line would; the found shape and duration become the leg's :class:`~pickplace_cli.line.moves.Move`
(the same path, rebuilt from its shape), so the legs are checked, summed up and written as every other leg.
"""

from __future__ import annotations

import numpy as np

from ..model.errors import PickplaceError
from .moves import Move, Solved

#: the shape parameters of a bspline-vel path, in order
_NAMES = ("tau6", "tau7", "tau9", "tau10", "lambda1", "lambda2", "lambda3")


def profile_with_window(robot):
    """The robot's profile with its window as the belt window (``workcell.belt_window``, robot frame): from the
    window's start to the last meeting point plus the tracking, across the whole belt, at the grip height ± 1 mm."""
    from ..model.profile import Box

    corners = robot.frame.to_robot(np.array([[robot.window[0], -10.0, robot.grip - 1e-3],
                                             [robot.meet_end + robot.speed * robot.dwell, 10.0, robot.grip + 1e-3]]))
    box = Box(min=tuple(np.minimum(*corners)), max=tuple(np.maximum(*corners)))
    workcell = robot.profile.workcell.model_copy(update={"belt_window": box})
    return robot.profile.model_copy(update={"workcell": workcell})


def _solved(robot, mv: Move, params, T: float, path) -> Solved:
    """The planned move as a leg's Move of that shape (the same spline, the same turn)."""
    basis = robot.shapes.basis([float(params[n]) for n in _NAMES])
    again = Move(basis, mv.start, mv.v_from, mv.end_a, mv.end_b, mv.v_to, mv.height, mv.eta, mv.theta, mv.turn)
    return Solved(again, float(T), tuple(float(x) for x in path.peaks))


def _plan(robot, mv: Move, T_end):
    """The planner's bspline-vel move from ``mv``'s start to its end at ``T_end`` (fixed), by the robot's rule."""
    from ..planner import PlanOptions, plan

    rule = robot.rule
    return plan(mv.task(T_end), robot.profile,
                PlanOptions(method="bspline-vel", time=rule, fit=rule == "fit", rate=100.0, turn="as-given"))


def pick_and_place(robot, mv: Move, a: float, b: float, target, v_out, turn=(0.0, 0.0)):
    """(pick, place) Solved, None when the pick cannot meet the part in [a, b], or the reason (text) the place move
    cannot be planned: ``mv`` describes the pick (a moving end: the rendezvous; a fixed end: the move to the
    window's entry, which must take at most b); ``turn``: the place move's (start angle, turn) [rad] (the planner
    times it with the turn; the rendezvous of the pick is searched without its turn, which the leg's check then
    holds to every limit)."""
    from ..pipelines.rendezvous import Part, find_rendezvous

    try:
        if np.any(mv.end_b != 0):
            part = Part(mv.end_a, mv.end_b, 0.0, name="part")
            rv = find_rendezvous(mv.start, part, profile_with_window(robot), robot.rule, v_from=mv.v_from,
                                 dwell=robot.dwell)
            T = rv.seconds
            if not a - 1e-9 <= T <= b + 1e-9:
                return None
            pick = _solved(robot, mv, rv.path.parameters, T, rv.path)
        else:
            got = _plan(robot, mv, 0.0)
            T = float(got.duration.seconds)
            if T > b:
                return None
            pick = _solved(robot, mv, got.parameters, T, got.cartesian.path)
    except PickplaceError:
        return None
    leave = pick.end + robot.v_belt * robot.dwell
    pmv = Move(pick.move.basis, leave, robot.v_belt, target, np.zeros(3), v_out, robot.height, robot.eta, *turn)
    try:
        got = _plan(robot, pmv, 0.0)
    except PickplaceError as exc:
        return f"robot {robot.name}: no place move from {leave} m to {target} m: {exc}"
    return pick, _solved(robot, pmv, got.parameters, float(got.duration.seconds), got.cartesian.path)
