"""The tracking segment after a conveyor rendezvous: the tool follows the part at the belt's velocity while it grips
it (:func:`plan_tracking`), the move and the segment as one trajectory (:func:`with_tracking`), and a plain batch's
belt row (:func:`plan_belt_move`)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..model.errors import UnreachableError
from .rendezvous import Part, plan_rendezvous


def tracking_path(point, velocity, duration: float):
    """CartesianPath of the tracking segment: from ``point`` [m] at constant ``velocity`` [m/s] for ``duration``
    [s] (the tool moves with the belt while it grips the part: acceleration and jerk zero)."""
    from ..model.trajectory import CartesianPath

    p0, d = np.asarray(point, float), np.asarray(velocity, float) * float(duration)  # d = dp/dτ

    def evaluate(tau: np.ndarray, order: int) -> np.ndarray:
        if order == 0:
            return p0 + np.multiply.outer(tau, d)
        return np.broadcast_to(d if order == 1 else np.zeros(3), (len(tau), 3)).copy()

    params = {"velocity_m_s": np.asarray(velocity, float).tolist(), "duration_s": float(duration), "continuity": 3}
    return CartesianPath(evaluate, "track", params, (float(np.linalg.norm(d)), 0.0, 0.0), jumps=())


def plan_tracking(move, part: Part, profile, duration: float | None = None, rate: float | None = None,
                  cycle: float | None = None):
    """Plan of the tracking segment after the rendezvous ``move`` (a Plan ending at the part): the tool follows
    the part for ``duration`` [s] (default: the profile's dwell), joint motion by the robot's IK and dynamics,
    checked against every limit like a move (its RMS row covers the segment alone). Its ``t`` runs from 0; its
    report's ``t_peak`` is trajectory time (T … T + duration), like the joined samples of :func:`with_tracking`."""
    from ..limits.check import check_limits
    from ..limits.grid import check_grid_order
    from ..planner import Plan, motion_model
    from ..timing import Duration
    from ..model.trajectory import CartesianTrajectory, JointTrajectory

    D = float(profile.planning.dwell if duration is None else duration)
    rate = float(profile.planning.rate if rate is None else rate)
    if cycle is not None:  # whole cycles, one sample per cycle
        from ..timing.cycle import whole_cycles

        D, rate = whole_cycles(D, cycle) * cycle, 1.0 / cycle
    T = float(move.duration.seconds)
    path = tracking_path(part.at(T), part.velocity, D)
    if move.task.theta_to is not None:  # the tool holds the part's angle while it tracks it
        from ..curves.rotation import with_rotation

        path = with_rotation(path, move.task.theta_to, 0.0)
    traj = CartesianTrajectory(path, D)
    t = traj.sample_times(rate)
    if cycle is not None:
        t = np.arange(len(t)) * cycle
    model = motion_model(path, profile)
    grid, order = check_grid_order(t / D, path.breakpoints, path.jumps)
    try:
        parts = model.parts(grid, order=order)
    except UnreachableError as exc:
        raise UnreachableError(f"{part.label()}: the tracking segment (t = {T:.4f} … {T + D:.4f} s) leaves the "
                               f"workspace: {exc}") from None
    report = check_limits(model, D, parts=parts, dwell=0.0).rated(profile.limit_use)
    # t_peak in the trajectory's time (the segment runs from T to T + D), as the written samples and the
    # segment's heading say; the segment's own clock would read 0 … D
    shifted = tuple(replace(r, t_peak=None if r.t_peak is None else r.t_peak + T) for r in report.rows)
    report = replace(report, rows=shifted)
    n = len(t)
    out = {k: getattr(parts, k)[:n] for k in ("p", "v1", "a1", "j1", "q", "qd1", "qdd1", "qddd1", "A", "G", "Am", "Gm")}
    robot = model.robot
    joint = JointTrajectory(
        t, out["q"], out["qd1"] / D, out["qdd1"] / D**2, out["qddd1"] / D**3, robot.joint_names, robot.joint_units,
        torque=out["A"] / D**2 + out["G"],
        motor_speed=model.gear * out["qd1"] / D if model.has_drives else None,
        motor_torque=out["Am"] / D**2 + out["Gm"] if model.has_drives else None,
        angle_weights=getattr(robot, "angle_weights", None),
    )
    duration_info = Duration(D, "tracking", 0.0, 0.0, None, "belt")
    return Plan(move.task, "track", dict(path.parameters), duration_info, traj, t, out["p"], out["v1"] / D,
                out["a1"] / D**2, out["j1"] / D**3, joint, report, profile.name)


def with_tracking(move, track):
    """One trajectory: the rendezvous ``move`` (t from 0 to T) then the ``track`` segment (t from T to T + dwell,
    its first sample — the meeting, already the move's last — left out); a Timeline with ``move`` 1 for every
    sample and the segments "move" and "track"."""
    from .timeline import Segment, _join, _pieces_of

    T = float(move.t[-1])
    first = _pieces_of(move, 0.0)
    rest = _pieces_of(track, T)
    rest = {k: ({n: None if a is None else a[1:] for n, a in v.items()} if k == "joint" else v[1:]) for k, v in rest.items()}
    segments = [Segment(1, "move", 0.0, T), Segment(1, "track", T, T + float(track.t[-1]))]
    return _join([first, rest], [1, 1], move.joint, segments, [move.summary()])


def plan_belt_move(start, part: Part, profile, time: str | float = "limits", height: float | None = None,
                   eta: float | None = None, v_from=None, rate: float | None = None, start_angle: float | None = None,
                   turn: str = "shortest", turn_during: str = "transfer", cycle: float | None = None):
    """One Plan of the rendezvous move and its tracking segment (the profile's dwell), as a plain batch's belt
    row writes it: the samples run from 0 to T + dwell (the tracking samples after the meeting), the limit
    report holds the move's rows and the segment's (its quantities marked "(tracking)", its times
    trajectory time), the summary describes the move (its duration, peaks and method) and its parameters
    carry ``rendezvous`` and ``tracking``. Without a dwell it is the move alone."""
    move, rv = plan_rendezvous(start, part, profile, time, height, eta, v_from, None, rate, None, start_angle, turn,
                               turn_during, cycle=cycle)
    if profile.planning.dwell <= 0:
        return move
    track = plan_tracking(move, part, profile, rate=rate, cycle=cycle)
    from .timeline import on_cycle

    joined = on_cycle(with_tracking(move, track), cycle)
    rows = move.report.rows + tuple(replace(r, quantity=f"{r.quantity} (tracking)") for r in track.report.rows)
    parameters = {**move.parameters, "tracking": {"t_start_s": rv.seconds, "duration_s": track.duration.seconds,
                                                 "velocity_m_s": part.velocity.tolist(),
                                                 "limits_ok": track.report.ok}}
    return replace(move, t=joined.t, p=joined.p, v=joined.v, a=joined.a, j=joined.j, joint=joined.joint,
                   report=replace(move.report, rows=rows), parameters=parameters)
