"""The tool's turn on a robot with a rotary fourth axis: the task's end angles checked and resolved, and the
angle law (:mod:`pickplace_cli.curves.rotation`) attached to a method's path.

* :func:`resolve_task` — the end angle by the turn rule (the shorter way round unless told otherwise), a TaskError
  (exit 1) for an angle given to a profile without the axis, or for a turn the axis can never make: q4 would
  have to travel further than its whole position range (q4 at the ends from the inverse kinematics; a start
  outside the range is a result of the limit check instead, exit 4).
* :func:`turned` — the path carrying the law: over the whole move, or between lift-off and set-down (the
  heights of the via points P2, P4 of [Li2018, Eq. (11)] with the path's own η).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Callable

import numpy as np

from ..curves.rotation import TurnRule, TurnWindow, resolve_turn, transfer_window, with_rotation
from ..model.errors import TaskError, UnreachableError
from ..model.task import Task


def resolve_task(task: Task, rule: TurnRule | str, robot, specs, profile_name: str) -> Task:
    """``task`` with ``theta_to`` the end angle reached by ``rule`` (unchanged without angles); TaskError for a
    tool angle on a profile without a rotary axis or a turn longer than the axis' range (module docstring)."""
    if task.theta_from is None:
        return task
    _, end = resolve_angles(task.p_from, task.p_to, task.theta_from, task.theta_to, rule, robot, specs, profile_name)
    return replace(task, theta_to=end)


def resolve_angles(p_from, p_to, theta_from: float | None, theta_to: float | None, rule: TurnRule | str, robot, specs,
                   profile_name: str) -> tuple[float | None, float | None]:
    """(start, end) tool angles [rad] of a move from ``p_from`` to ``p_to`` [m] with the end reached by ``rule``
    ((None, None) without angles); TaskError as :func:`resolve_task` (also for only one angle given)."""
    if theta_from is None and theta_to is None:
        return None, None
    if theta_from is None or theta_to is None:
        given = "to_theta" if theta_from is None else "from_theta"
        raise TaskError(f"{given} = {theta_to if theta_from is None else theta_from!r} rad alone: give the tool "
                        "angle at both ends of the move (or at neither)")
    if not getattr(robot, "rotary", False):
        pose = ",".join(f"{c:g}" for c in p_from)
        raise TaskError(f"from = {pose},{theta_from:g}: a tool angle (the fourth number, rad) needs a robot with "
                        f"a rotary fourth axis; profile {profile_name} has {len(robot.joint_names)} joints and no "
                        "robot.rotary (give X,Y,Z, or a 4-axis profile)")
    end = resolve_turn(theta_from, theta_to, rule)
    rng = specs[-1].limits.position
    if rng is not None:
        try:
            q = robot.inverse_kinematics(np.stack([np.asarray(p_from, float), np.asarray(p_to, float)]),
                                         np.array([theta_from, end]))
        except UnreachableError:  # an end out of reach: the planner's own check names it (exit 4)
            return float(theta_from), end
        travel, width = abs(q[1, -1] - q[0, -1]), rng[1] - rng[0]
        if travel > width:
            name = robot.joint_names[-1]
            raise TaskError(
                f"to_theta = {theta_to:g} rad: turning from {theta_from:g} to {end:g} rad ({rule_name(rule)}) "
                f"moves {name} by {travel:.4g} rad, beyond its whole range [{rng[0]:g}, {rng[1]:g}] rad "
                f"({width:.4g} rad): no start angle makes this turn (give another end angle or --turn)")
    return float(theta_from), end


def rule_name(rule: TurnRule | str) -> str:
    return {TurnRule.shortest: "the shorter way", TurnRule.ccw: "counter-clockwise", TurnRule.cw: "clockwise",
            TurnRule.as_given: "as given"}[TurnRule(rule)]


def turned(path, task: Task, during: TurnWindow | str = TurnWindow.transfer):
    """``path`` carrying the angle law of ``task``'s turn (``task`` resolved by :func:`resolve_task`) over
    ``during``; the path itself when the task gives no angles. The transfer window uses the lift-off and
    set-down heights of the task's via points with the path's own η (``parameters["eta"]``, else the task's)."""
    if task.theta_from is None:
        return path
    window = (0.0, 1.0)
    turn = task.theta_to - task.theta_from
    if TurnWindow(during) is TurnWindow.transfer and turn != 0.0:
        eta = float(path.parameters.get("eta", task.eta)) if isinstance(path.parameters, dict) else task.eta
        p1, p5, top = task.p_from[2], task.p_to[2], task.z_top
        window = transfer_window(path, p1 + eta * (top - p1), p5 + eta * (top - p5))
    info = {"from_rad": task.theta_from, "to_rad": task.theta_to, "turn_rad": turn, "during": TurnWindow(during).value,
            "window_tau": [window[0], window[1]]}
    path = with_rotation(path, task.theta_from, turn, window)
    return replace(path, parameters={**path.parameters, "turn": info})


def turned_factory(factory: Callable, task: Task, during: TurnWindow | str) -> Callable:
    """A path factory T → path (a method whose path depends on the duration) whose paths carry the turn."""
    if task.theta_from is None:
        return factory

    def call(T: float):
        return turned(factory(T), task, during)

    final = getattr(factory, "final", None)
    if final is not None:  # the factory's confirmation of a continued solve (bspline-vel) passes through

        def confirm(T: float):
            path, *rest = final(T)
            return (turned(path, task, during), *rest)

        call.final = confirm  # type: ignore[attr-defined]
    return call


def turned_at(factory, during: TurnWindow | str) -> Callable:
    """T → ``factory(T)`` carrying the turn of ``factory.task_at(T)`` (a factory whose task changes with T, as a
    conveyor rendezvous' end point does)."""

    def call(T: float):
        return turned(factory(T), factory.task_at(T), during)

    return call
