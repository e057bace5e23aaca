"""plan(task, profile, options) → Plan: the one entry point the CLI and the tests use.

Pipeline [DESIGN §1]: Task + method → CartesianPath → MotionModel (robot + joint specs) →
choose_duration (auto / seconds / fit) → samples → JointTrajectory → check_limits → LimitReport.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any, Callable

import numpy as np

from .model.errors import TableError, UnreachableError
from .limits.check import capacity_rows, check_limits, reach_error
from .limits.grid import check_grid_order
from .limits.motion import MotionModel
from .limits.report import LimitReport
from .paths import Method, depends_on_duration, path_factory, plan_path
from .model.headroom import apply_limit_use, limit_specs
from .paths.turn import resolve_task, turned, turned_factory
from .model.profile import Profile
from .robots import build_robot
from .model.task import Task
from .timing import Duration, choose_duration, choose_duration_for
from .model.trajectory import CartesianTrajectory, JointTrajectory


@dataclass(frozen=True)
class PlanOptions:
    """What to plan beyond the task (immutable; every field has a default).

    Attributes
    ----------
    method : Method or str
        The planning method (``bspline``, ``ph``, ``superposition``, ``lame``, ``piecewise-poly``, ``bspline-vel``).
    method_params : dict
        The method's parameters by name (``ph``: ``m``, ``r`` [m]; ``lame``: ``m`` [-]; …).
    time : str or float
        The duration [s], or a rule: ``limits`` (every limit of the profile), ``auto`` (the Cartesian capacity),
        ``fit`` (the joint and motor limits) or ``optimal`` (a time-optimal law).
    rate : float or None
        Output samples per second [Hz]; None: the profile's ``planning.rate``.
    fit : bool
        Also compute the fitted duration [s] next to the chosen one.
    shape : bool
        ``bspline``: choose k1, k2 [-] (and η unless ``hold_eta``) for the smallest duration on this robot.
    hold_eta : bool
        With ``shape``: keep the task's η [-].
    hold_capacity : bool
        ``fit``/``optimal`` also hold the Cartesian capacity [m/s, m/s², m/s³].
    shape_law_evals : int
        With ``shape`` and ``optimal``: COBYQA over the shape family with the optimal law's duration [s] as the
        objective, at most this many law solves [-] (0: the screened search alone).
    law_coefficients : int or None
        ``optimal``: coefficients [-] of the time law's B-spline; None: automatic (the SQP solver's quintic law of 60;
        the SLSQP solver's cubic law of 20, refined to 40).
    cycle : float or None
        The controller's cycle [s]: duration and dwell rounded up to whole cycles, one sample per cycle.
    limit_use : float or None
        Headroom: the fraction (0, 1] [-] of every timed limit's rating to plan to; None: the profile's.
    capacity_rows : bool or None
        Whether the capacity's rows are held (decide the verdict; else they are reported as not held); None: by the
        duration rule. False with a duration in seconds: the caller timed the move by the fit rule (a conveyor
        rendezvous under ``--time fit``).
    turn : str
        A rotary fourth axis: the way round to the end angle (``shortest``, ``ccw``, ``cw``, ``as-given``).
    turn_during : str
        When the tool turns: ``transfer`` (lift-off to set-down) or ``whole`` (the whole move).
    read_written : str
        ``fit`` and ``optimal`` (every rule when the move has fewer than ``WRITTEN_FEW`` samples or the file holds the
        joint positions alone: :func:`~pickplace_cli.timing.written.reads_written`): read the samples as a CSV holds them through ``check``'s
        reconstruction, and slow the law until ``check`` reads them within every limit (a given duration: judged)
        (:mod:`pickplace_cli.timing.written`): ``"tool"`` (the file has the
        tool's x … jz, as this tool writes it by default), ``"positions"`` (the joint positions alone, e.g. ``plan
        --columns t,q1,q2,q3`` or a drive's positions), ``""`` (not read: a drive's table, judged as the drive
        interpolates it instead).
    law_smoothing : float or None
        ``optimal``: the SQP law's smoothing weight [-] (``timing.law_sqp``); None: the shipped rule, and with ``shape``
        the law without the term too, the shorter as written kept (``timing.shape_plan``).
    strict : bool
        Read the written samples (``read_written``) as ``check --strict`` does, under the rules ``limits`` and ``auto``
        too: the law is slowed until every peak is resolved by them (within its limit at the reading's stated accuracy,
        or known to 1 %); a peak still not resolved fails the plan (exit 3).
    """

    method: Method | str = Method.bspline
    method_params: dict[str, Any] = field(default_factory=dict)
    time: str | float = "limits"  # limits | auto | fit | optimal | seconds (pickplace_cli.timing.parse_time)
    rate: float | None = None  # Hz; None → profile.planning.rate
    fit: bool = True  # also compute the fitted duration (reported next to auto); for a method whose path
    # depends on the duration (bspline-vel) only with time="fit": each trial duration re-plans the path
    shape: bool = False  # bspline: choose k1, k2 (and η unless hold_eta) for the smallest duration on the robot
    hold_eta: bool = False  # with shape: keep the task's η (the user gave it), search k1, k2 only
    hold_capacity: bool = False  # fit/optimal also hold the profile's Cartesian capacity (|v|, |a|, |j|)
    shape_law_evals: int = 0  # with shape and optimal: this many more shapes judged by the optimal law itself
    law_coefficients: int | None = None  # optimal: coefficients of the time law's B-spline (None: auto, the SQP's
    # quintic law of 60, or SLSQP's cubic law of 20 refined to 40 when far from uniform; more: finer, slower)
    cycle: float | None = None  # s: the controller's cycle (duration and dwell rounded up to whole cycles, one
    # sample per cycle: :mod:`pickplace_cli.timing.cycle`); None: sampled at ``rate``
    limit_use: float | None = None  # fraction (0, 1] of every timed limit's rating to plan to; None: the profile's
    # planning.limit_use
    capacity_rows: bool | None = None  # the Cartesian capacity's rows held (else reported as not held): None by the rule
    # (:func:`holds_capacity`); a caller that chose the duration itself (a conveyor rendezvous) says
    turn: str = "shortest"  # a rotary fourth axis: the way round to the task's end angle (curves.rotation.TurnRule)
    turn_during: str = "transfer"  # … and when the tool turns: between lift-off and set-down, or the whole move
    read_written: str = "tool"  # fit, optimal: the written samples read as check reads them (timing/written.py)
    law_smoothing: float | None = None  # optimal: the SQP law's smoothing weight (None: the shipped rule)
    strict: bool = False  # … as check --strict reads them: every peak resolved (also under limits and auto)


def holds_capacity(options: PlanOptions) -> bool:
    """Whether the duration rule holds the profile's Cartesian capacity (its rows then decide the verdict with the
    others): every rule but fit and optimal without ``hold_capacity`` (those hold the joint and motor limits alone;
    the capacity's rows are still reported, as not held)."""
    if options.capacity_rows is not None:
        return options.capacity_rows
    return options.hold_capacity or options.time not in ("fit", "optimal")


def capacity_not_held(options: PlanOptions) -> str:
    """Why the duration rule does not hold the Cartesian capacity (``--time fit``), "" when it does
    (:attr:`~pickplace_cli.limits.report.LimitRow.not_held`)."""
    if holds_capacity(options):
        return ""
    # (capacity_rows False with a duration in seconds: a conveyor rendezvous timed by the fit rule)
    return f"--time {options.time}" if options.time in ("fit", "optimal") else "--time fit"


@dataclass(frozen=True)
class Plan:
    """Everything one planned move produced (immutable).

    Attributes
    ----------
    task : Task
        The move as planned (its shape may be the optimised one).
    method : str
        The planning method.
    parameters : dict
        The path's parameters (k1, k2 [-], their source, λ [-], η [-], …).
    duration : Duration
        The duration T [s] and how it was chosen.
    cartesian : CartesianTrajectory
        The tool's continuous motion over T [m, m/s, m/s², m/s³].
    t : numpy.ndarray
        Sample times, shape (N,) [s].
    p, v, a, j : numpy.ndarray
        The tool's position [m], velocity [m/s], acceleration [m/s²] and jerk [m/s³] at the samples, (N, 3).
    joint : JointTrajectory
        The joints' motion, torques [N·m or N] and motors' speed [rad/s] and torque [N·m] at the samples.
    report : LimitReport
        Every checked limit, found on the continuous motion, and the verdict.
    profile_name : str
        The profile's name.
    cycle : object or None
        The controller-cycle rounding when planned on a cycle [s], else None.
    """

    task: Task
    method: str
    parameters: dict[str, Any]
    duration: Duration
    cartesian: CartesianTrajectory
    t: np.ndarray  # (N,) s
    p: np.ndarray  # (N, 3) m
    v: np.ndarray  # (N, 3) m/s
    a: np.ndarray  # (N, 3) m/s²
    j: np.ndarray  # (N, 3) m/s³
    joint: JointTrajectory
    report: LimitReport
    profile_name: str
    cycle: Any = None  # timing.cycle.CycleRounding when planned on a controller's cycle, else None

    def summary(self) -> dict[str, Any]:
        """Scalars for reports and --format json (SI units, keys name the unit)."""
        vpk, apk, jpk = self.cartesian.peaks()
        return {
            "profile": self.profile_name,
            "method": self.method,
            "parameters": dict(self.parameters),
            "from_m": self.task.p_from.tolist(),
            "to_m": self.task.p_to.tolist(),
            **({} if self.task.theta_from is None else
               {"from_theta_rad": self.task.theta_from, "to_theta_rad": self.task.theta_to}),
            "height_m": self.task.height,
            "eta": self.task.eta,
            "b_m": self.task.b,
            "lambda": self.task.lam,
            **self.duration.as_dict(),
            "samples": int(len(self.t)),
            "peak_speed_m_s": vpk,
            "peak_acceleration_m_s2": apk,
            "peak_jerk_m_s3": jpk,
            "cycle_time_one_way_s": self.report.duration,
            "cycle_time_round_trip_s": self.report.round_trip,
            "picks_per_minute": self.report.picks_per_minute,
            "limits_ok": self.report.ok,
            "all_limits_ok": self.report.all_ok,
            "capacity_held": not any(r.not_held for r in self.report.rows),
            "exceeded_not_held": [r.as_dict() for r in self.report.exceeded_not_held],
            **({"cycle": self.cycle.as_dict()} if getattr(self, "cycle", None) is not None else {}),
        }


def motion_model(path, profile: Profile) -> MotionModel:
    """The path on the profile's robot, with its joint specs, singularity margin and workcell box (built
    once per profile: a profile is immutable)."""
    return MotionModel(path, *motion_model_static(profile))


def motion_model_static(profile: Profile) -> tuple:
    """(robot, joint specs, singularity margin, workcell box, memo) of ``profile``, built once per profile."""
    hit = _STATIC.get(id(profile))
    if hit is None or hit[0] is not profile:
        robot = build_robot(profile.robot)
        margin = getattr(profile.robot, "singularity_margin", None)
        hit = (profile, robot, limit_specs(profile), margin, profile.workcell.box, {})
        if len(_STATIC) > 32:
            _STATIC.clear()
        _STATIC[id(profile)] = hit
    return hit[1:]


_STATIC: dict[int, tuple] = {}
_OUTPUT_PARTS = ("p", "v1", "a1", "j1", "q", "qd1", "qdd1", "qddd1", "A", "G", "Am", "Gm")  # id(profile) → (profile, robot, specs, margin, box, memo); holds the profile


def _first_unreachable(exc: UnreachableError, model: MotionModel, grid, order, T: float) -> UnreachableError:
    """:func:`reach_error` for the earliest unreachable sample: the grid has the output samples first, so
    the one the robot named need not be the first in time; the sorted grid finds that one."""
    sorted_grid = grid[order]
    try:
        model.parts(sorted_grid)
    except UnreachableError as first:
        return reach_error(first, sorted_grid, T)
    return reach_error(exc, grid, T)  # pragma: no cover - the same points, sorted, fail the same way


def check_ends_reachable(task: Task, profile: Profile, T: float | None = None) -> None:
    """UnreachableError (exit 4) naming the end point outside the robot's workspace, if one is (with ``T`` [s], the
    duration, also when: t = 0 or t = T)."""
    robot = motion_model_static(profile)[0]
    for name, p, t in (("from", task.p_from, 0.0), ("to", task.p_to, T)):
        try:
            robot.inverse_kinematics(p[None])
        except UnreachableError as exc:
            xyz = ",".join(f"{c:g}" for c in p)
            why = str(exc).replace("sample 0 at ", "").replace(" (sample 0)", "")  # the robot's message names its sample; here it is the point
            when = "" if T is None else f" at t = {t:.6g} s"
            raise UnreachableError(f"{name} = {xyz} m: outside the workspace of profile {profile.name} ({why}){when}") from None


def _library_inputs(task, profile, options) -> tuple:
    """A library caller's arguments as the CLI gives them, or one TaskError naming the field, value and rule (never
    a bare ValueError or AttributeError): a profile by name or file (:func:`load_profile`), a known method, a finite
    rate in (0, 1e6] Hz."""
    import math
    from pathlib import Path

    from .model.errors import TaskError

    if not isinstance(task, Task):
        raise TaskError(f"task = {task!r}: must be a Task (Task(p_from, p_to, height) in m)")
    if isinstance(profile, (str, Path)):
        from .model.profile import load_profile

        profile = load_profile(profile)
    elif not isinstance(profile, Profile):
        raise TaskError(f"profile = {profile!r}: must be a Profile (load_profile(name or path))")
    if not isinstance(options, PlanOptions):
        raise TaskError(f"options = {options!r}: must be a PlanOptions")
    try:
        Method(options.method)
    except ValueError:
        raise TaskError(f"method = {options.method!r}: must be one of {', '.join(m.value for m in Method)}") from None
    if options.rate is not None:
        try:
            rate = float(options.rate)
        except (TypeError, ValueError):
            rate = math.nan
        if not (math.isfinite(rate) and 0 < rate <= 1e6):
            raise TaskError(f"rate = {options.rate!r} Hz: the output rate must be a finite number in (0, 1e6] Hz")
    if options.law_smoothing is not None:
        w = options.law_smoothing
        if isinstance(w, bool) or not isinstance(w, (int, float)) or not (math.isfinite(w) and w >= 0):
            raise TaskError(f"law_smoothing = {w!r}: the time law's smoothing weight must be a finite number >= 0 "
                            "(or None: the shipped one)")
    return task, profile, options


class PlanInterrupted(Exception):
    """Raised by :func:`plan` when its ``interrupt`` returned True (not an error: the caller asked to stop)."""


def plan(task: Task, profile: Profile, options: PlanOptions = PlanOptions(), *,
         interrupt: Callable[[], bool] | None = None) -> Plan:
    """Plan one move: its path, duration, samples, joint motion and limit report.

    Parameters
    ----------
    task : Task
        The move: end points [m], clearance height [m], lift-off ratio η [-], end velocities [m/s] and tool
        angles [rad].
    profile : Profile
        The robot and its workcell (:func:`load_profile`); its timed limits at the profile's limit use.
    options : PlanOptions
        Method, duration rule [s or a rule name], sample rate [Hz], headroom [-] and the rest.
    interrupt : callable, optional
        Called between the stages; once it returns True, ``plan`` raises :class:`PlanInterrupted`.

    Returns
    -------
    Plan
        The samples (times [s], tool motion [m, m/s, m/s², m/s³], joint motion, torques [N·m or N]) and the
        limit report. A limit that is exceeded is a result (``plan.report.ok`` is False), not an exception.

    Raises
    ------
    TaskError, ProfileError, TableError
        Invalid input (exit code 1).
    UnreachableError
        A point of the move outside the workspace (exit code 4).
    NoFeasibleDuration
        ``time="fit"``: no duration holds every limit (exit code 3).

    Examples
    --------
    >>> from pickplace_cli import PlanOptions, Task, load_profile, plan
    >>> p = plan(Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], height=0.025), load_profile("delta-su2018"))
    >>> round(p.duration.seconds, 4), p.report.ok
    (0.18, True)

    Notes
    -----
    The pipeline, each stage once, in order: the task (and, with ``--optimize shape``, its shape) → the path
    (:func:`_path_stage`) → the motion model (:func:`motion_model`) → the duration or time law
    (:func:`_duration_stage`; the fit/optimal searches test feasibility through ``model_of``, passed in) →
    the samples (:func:`_sample`) → the limit check (:func:`check_limits`) → the Plan (:func:`_assemble`).
    ``interrupt`` (``--keep-warm``'s warm-ups) is called between the stages; once it returns True, plan raises
    :class:`PlanInterrupted`.
    """
    def stop() -> None:
        if interrupt is not None and interrupt():
            raise PlanInterrupted

    task, profile, options = _library_inputs(task, profile, options)
    if isinstance(options.time, str):  # a rule's name in any case and spacing (TaskError for a bad one)
        from .timing import parse_time

        options = replace(options, time=parse_time(options.time))
    profile = apply_limit_use(profile, options.limit_use)  # every timed limit at use × its rating (itself at 1)

    _refuse_moving_ends(task, options)
    task = resolve_task(task, options.turn, *motion_model_static(profile)[:2], profile.name)
    rate = options.rate if options.rate is not None else profile.planning.rate
    if options.cycle is not None:
        rate = 1.0 / options.cycle  # one sample per cycle
    shape = None
    if options.shape:
        from .timing.shape_plan import optimised_shape

        task, options, shape = optimised_shape(task, profile, options, motion_model)
        if options.time == "optimal" and options.law_smoothing is None and options.read_written:
            from .timing.shape_plan import shortest_as_written

            return shortest_as_written(lambda o: _planned(task, profile, o, shape, rate, stop), options)
    return _planned(task, profile, options, shape, rate, stop)


def _planned(task: Task, profile: Profile, options: PlanOptions, shape, rate: float, stop) -> Plan:
    """:func:`plan` from the path on (the task resolved, its shape chosen, the rate known)."""
    path, factory, first = _path_stage(task, profile, options, shape)
    stop()
    model = motion_model(path, profile)
    # reachability first, on the output samples of the auto (or given) duration, so an error names a time
    try:
        samples = _sample(model, path, first.seconds, rate)
    except UnreachableError:  # an end point itself out of reach is the clearer message (only on this error path)
        check_ends_reachable(task, profile, first.seconds)
        raise
    stop()
    final = _FinalCheck(rate, profile.planning.dwell)
    uniform = (model, path)  # the path the uniform law scales (the time-optimal law composes a new one)
    duration, path, model, notes = _duration_stage(task, profile, options, path, factory, model, first, final,
                                                   samples.parts)
    done = final.at(path, duration.seconds)
    if done is not None:  # the search's last exact check was this one: same path, duration, grid and dwell
        samples, report = done
        report = replace(report, notes=notes)
    else:
        if duration.seconds != first.seconds or model.path is not samples.path:
            samples = _sample(model, path, duration.seconds, rate)
        stop()
        report = check_limits(model, duration.seconds, parts=samples.parts, dwell=profile.planning.dwell, notes=notes)
    rounding = None
    if options.cycle is not None:
        stop()
        duration, model, path, samples, report, rounding = _cycle_stage(options.cycle, profile, model, path, factory,
                                                                        duration, report)
    from .timing.written import as_read, reads_written

    read_past: tuple = ()
    if reads_written(options, len(samples.t)) and report.ok:
        stop()  # a law at its limits (or a file too sparse to show its motion), as check reads its samples
        duration, model, path, samples, report, rounding, read_past = _written_stage(
            model, path, duration, samples, report, rounding, rate, options, profile, uniform, factory)
    # the Cartesian capacity's rows always: judged when the rule holds it, else reported as not held
    report = report.with_rows(capacity_rows(path, duration.seconds, profile.capacity, capacity_not_held(options)))
    if read_past:  # still past a limit as read (or, strict, not resolved): the plan says so, with the reading's peak
        report = as_read(report, read_past)
    if options.strict:
        report = replace(report, strict=True)
    planned = _assemble(task, profile, path, duration, model, samples, report.rated(profile.limit_use))
    return planned if rounding is None else replace(planned, cycle=rounding)


def _cycle_stage(cycle: float, profile: Profile, model: MotionModel, path, factory, duration: Duration,
                 report: LimitReport):
    """The controller's cycle (:func:`pickplace_cli.timing.cycle.align_to_cycle`): the duration and the dwell rounded
    up to whole cycles, the samples one per cycle (t = k·cycle), the limit check run again on them (a path planned
    for its duration is planned again for the rounded one). → (duration, model, path, samples, report, rounding)."""
    from .timing.cycle import align_to_cycle

    def check(T: float, dwell: float):
        m, p = model, path
        if factory is not None and T != duration.seconds:
            p = factory(T)
            m = motion_model(p, profile)
        s = _sample(m, p, T, 1.0 / cycle, cycle)
        return (m, p, s), check_limits(m, T, parts=s.parts, dwell=dwell, notes=report.notes)

    rounding, (model, path, samples), report = align_to_cycle(duration.seconds, profile.planning.dwell, cycle, check,
                                                              report.ok)
    if rounding.note:
        report = replace(report, notes=report.notes + (rounding.note,))
    return replace(duration, seconds=rounding.seconds), model, path, samples, report, rounding


def _written_stage(model: MotionModel, path, duration: Duration, samples, report: LimitReport, rounding, rate: float,
                   options: PlanOptions, profile: Profile, uniform: tuple, factory=None):
    """A law at its limits (``fit``, ``optimal``) slowed until ``check`` reads its written samples within every limit
    (:func:`pickplace_cli.timing.written.hold_as_written`); a time-optimal law slowed past the uniform law's fit is
    replaced by the uniform law (``uniform``: its model and path) when that is shorter as written. The exact check runs
    again at the new duration, and a reading that still exceeds a limit marks that row exceeded. ``factory``: a path
    planned for its duration (``bspline-vel``) is planned again for each longer one.
    → (duration, model, path, samples, report, rounding, the reading's rows still past their limit: :func:`~pickplace_cli.timing.written.as_read`)."""
    from .timing.written import hold_as_written

    cycle = options.cycle
    dwell = rounding.dwell_s if rounding is not None else profile.planning.dwell

    def outputs(s: _Samples, T: float) -> tuple:
        n, P = len(s.t), s.parts
        return s.t, np.column_stack([P.p[:n], P.v1[:n] / T, P.a1[:n] / T**2, P.j1[:n] / T**3]), P.q[:n]

    def held(m, p, T0: float, s0):
        def sample(T: float):
            mm, pp = m, p
            if factory is not None and T != T0:  # the path planned for this duration (its model with it)
                pp = factory(T)
                mm = motion_model(pp, profile)
            s = _sample(mm, pp, T, rate, cycle)
            return s, outputs(s, T), mm, pp

        return hold_as_written(T0, (s0, outputs(s0, T0), m, p) if s0 is not None else sample(T0), sample, profile,
                               capacity_not_held(options), cycle, rate,
                               positions_only=options.read_written == "positions", strict=options.strict,
                               stretch=isinstance(options.time, str))

    T0 = duration.seconds
    w = held(model, path, T0, samples)
    t_fit, switched = duration.t_fit, False
    if options.time == "optimal" and w.k > 1.0 and t_fit is not None and w.T > t_fit and uniform[1] is not path:
        t_uni = float(np.ceil(t_fit / cycle - 1e-9) * cycle) if cycle is not None else t_fit
        u = held(*uniform, t_uni, None)
        if u.T < w.T and not u.past and not u.refused:  # the uniform law of --time fit, as written, is the shorter
            model, path = uniform
            switched = True
            w = replace(u, note=f"{w.note}; longer than the uniform law of --time fit as written: that law is "
                                f"written instead, T {u.T:.6g} s" + (f" ({u.note})" if u.note else ""))
            duration = replace(duration, law="uniform (its written samples hold sooner than the optimal law's)")
    if w.refused:  # (strict) check --strict refuses the file whatever its peaks
        from .model.errors import TaskError

        raise TaskError(f"--strict: {w.refused} at T = {w.T:.6g} s (the law slowed × {w.k:.4g}): check --strict "
                        "refuses such a file; write at a higher --rate, or leave the tool's columns out (--columns)")
    if w.k == 1.0 and not switched and not w.past:  # read within every limit as planned (or not read: too few samples)
        return replace(duration, written=w.note), model, path, samples, report, rounding, ()
    samples, _, model, path = w.state  # (a path planned for its duration: the one planned for w.T)
    report = check_limits(model, w.T, parts=samples.parts, dwell=dwell, notes=report.notes + ((w.note,) if w.note else ()))
    if rounding is not None:
        cycles = int(round(w.T / cycle))
        added = cycles - rounding.cycles
        said = f"{added:+d} cycle(s) so that check reads the written samples within every limit"
        rounding = replace(rounding, cycles=cycles, extra_cycles=rounding.extra_cycles + added,
                           note="; ".join(n for n in (rounding.note, said) if n))
    binding = duration.binding if w.k == 1.0 else f"the written samples as {'check --strict' if options.strict else 'check'} reads them"
    return (replace(duration, seconds=w.T, written_stretch=w.T / T0, written=w.note, binding=binding), model, path,
            samples, report, rounding, tuple(w.past))


class _FinalCheck:
    """The plan's final limit check (on the output samples' grid: :func:`_sample`) as the fit's exact check:
    a fit ends with a check at the T it returns, so when that T is the plan's the check is not run twice.
    Keeps the last (path, T, samples, report)."""

    def __init__(self, rate: float, dwell: float) -> None:
        self.rate, self.dwell, self.last = rate, dwell, None

    def __call__(self, model: MotionModel, T: float) -> LimitReport:
        samples = _sample(model, model.path, T, self.rate)
        report = check_limits(model, T, parts=samples.parts, dwell=self.dwell)
        self.last = (model.path, T, samples, report)
        return report

    def at(self, path, T: float):
        """(samples, report) of the last check when it was of ``path`` at ``T`` [s], else None."""
        if self.last is not None and self.last[0] is path and self.last[1] == T:
            return self.last[2], self.last[3]
        return None


def _refuse_moving_ends(task: Task, options: PlanOptions) -> None:
    """TaskError: end velocities with a method that plans from rest to rest."""
    if (task.v_from.any() or task.v_to.any()) and not depends_on_duration(options.method):
        from .model.errors import TaskError

        raise TaskError(
            f"v_from/v_to = ({', '.join(f'{x:g}' for x in task.v_from)}), ({', '.join(f'{x:g}' for x in task.v_to)}) m/s: "
            f"method {Method(options.method).value} plans moves from rest to rest; use bspline-vel for moving ends"
        )


def _path_stage(task: Task, profile: Profile, options: PlanOptions, shape: dict | None):
    """The path, its factory T → path when the path is planned for a duration (else None), and the first
    duration (auto or given; ``fit``/``optimal`` start from auto). A move the table does not cover is often one
    the robot cannot make at all: that is said first (exit 4)."""
    first_spec = "auto" if options.time in ("fit", "optimal", "limits") else options.time
    try:
        if depends_on_duration(options.method):  # the path is planned for a duration (e.g. conveyor tracking)
            _refuse_retiming(options)
            if first_spec == "auto":
                _refuse_ends_past_capacity(task, profile)
            factory = turned_factory(path_factory(task, options.method, **options.method_params), task,
                                     options.turn_during)
            first, path = choose_duration_for(factory, profile.capacity, first_spec)
            return path, factory, first
        path = turned(plan_path(task, options.method, **options.method_params), task, options.turn_during)
    except TableError:
        check_ends_reachable(task, profile)
        raise
    if shape is not None:
        path = replace(path, parameters={**path.parameters, "k_source": "--optimize shape", "shape": shape})
    return path, None, choose_duration(path, profile.capacity, first_spec)


def _refuse_ends_past_capacity(task: Task, profile: Profile) -> None:
    """TaskError: an end velocity faster than the capacity's [v] (the duration is searched from the capacity's
    Eq. 26 bound, which no duration meets when the move must end at that speed)."""
    from .model.errors import TaskError

    for name, v in (("v_from", task.v_from), ("v_to", task.v_to)):
        speed = float(np.linalg.norm(v))
        if speed > profile.capacity.velocity:
            raise TaskError(f"{name} = ({', '.join(f'{x:g}' for x in v)}) m/s: its speed {speed:g} m/s is above the "
                            f"profile's capacity.velocity {profile.capacity.velocity:g} m/s; no duration can meet it "
                            "(a belt that fast needs a faster capacity, or the move cannot track it)")


def _refuse_retiming(options: PlanOptions) -> None:
    """UsageError: options that retime a path which is planned for its duration."""
    from .model.errors import UsageError

    name = Method(options.method).value
    if options.hold_capacity:
        raise UsageError(f"--hold-capacity: not available for method {name} (its "
                         "fit re-plans the path for every trial duration); use --time auto for the capacity")
    if options.time == "optimal":
        raise UsageError(
            f"--time optimal: method {name} plans its path for a duration (the end "
            "velocities enter as v·T), so a time law would change the path; use --time fit"
        )


def _duration_stage(task: Task, profile: Profile, options: PlanOptions, path, factory, model: MotionModel,
                    first: Duration, check=None, parts=None) -> tuple[Duration, Any, MotionModel, tuple[str, ...]]:
    """(duration, path, model, notes) for ``options.time``: the first duration as it is, the fit (the smallest
    T at which every limit holds), or the time-optimal law (which composes a new path). The searches reach the
    limit stage only through ``model_of`` (path → MotionModel) and ``check`` (the plan's final check, for the
    fits of a fixed path), passed in."""
    dwell = profile.planning.dwell

    def model_of(p):
        return motion_model(p, profile)

    if factory is not None and options.time in ("fit", "limits"):
        duration, path = choose_duration_for(factory, profile.capacity, options.time, model_of=model_of, dwell=dwell,
                                             start=first.seconds)
        return duration, path, model_of(path), ()
    if options.time == "optimal":
        from .timing import choose_optimal

        duration, law_path, law_note = choose_optimal(path, profile, model, dwell, model_of,
                                                      hold_capacity=options.hold_capacity,
                                                      coefficients=options.law_coefficients, check=check,
                                                      smooth=options.law_smoothing)
        if law_path is not model.path:  # the composed path: evaluated anew
            model = model_of(law_path)
        return duration, law_path, model, (law_note,)
    if factory is None and options.time == "limits":  # the fit screens the first samples' model (same path)
        return choose_duration(path, profile.capacity, "limits", model=model, dwell=dwell, check=check,
                               parts=parts if parts is not None and model.path is path else None), path, model, ()
    if factory is None and (options.fit or options.time == "fit"):
        same = parts is not None and model.path is path and options.time == "auto"  # auto screens as limits does
        return choose_duration(path, profile.capacity, options.time, model=model, dwell=dwell,
                               hold_capacity=options.hold_capacity, check=check,
                               parts=parts if same else None), path, model, ()
    return first, path, model, ()


@dataclass(frozen=True)
class _Samples:
    """The output sample times ``t`` [s] and the model on the check grid (outputs first, then the check's
    extra points: the outputs are the first len(t) rows of ``parts``), for ``path`` at one duration."""

    path: Any
    t: np.ndarray
    parts: Any


def _sample(model: MotionModel, path, T: float, rate: float, cycle: float | None = None) -> _Samples:
    """One evaluation of the model on the check grid (output samples ∪ a dense uniform grid ∪ knots) at
    duration T [s]; an unreachable point names its earliest time. ``cycle`` [s]: T is a whole number of cycles and
    the output samples are t = k·cycle exactly."""
    t = CartesianTrajectory(path, T).sample_times(rate)
    if cycle is not None:
        from .timing.cycle import cycle_times

        t = cycle_times(len(t) - 1, cycle)
    grid, order = check_grid_order(t / T, path.breakpoints, path.jumps)
    try:
        return _Samples(path, t, model.parts(grid, order=order))
    except UnreachableError as exc:  # a path planned for another duration can take another route
        raise _first_unreachable(exc, model, grid, order, T) from None


def _assemble(task: Task, profile: Profile, path, duration: Duration, model: MotionModel, samples: _Samples,
              report: LimitReport) -> Plan:
    """The Plan: the output samples of the quantities written out (the first len(t) rows of the grid)."""
    T = duration.seconds
    t = samples.t
    n = len(t)
    out = {name: getattr(samples.parts, name)[:n] for name in _OUTPUT_PARTS}
    robot = model.robot
    joint = JointTrajectory(
        t,
        out["q"],
        out["qd1"] / T,
        out["qdd1"] / T**2,
        out["qddd1"] / T**3,
        robot.joint_names,
        robot.joint_units,
        torque=out["A"] / T**2 + out["G"],
        motor_speed=model.gear * out["qd1"] / T if model.has_drives else None,
        motor_torque=out["Am"] / T**2 + out["Gm"] if model.has_drives else None,
        angle_weights=getattr(robot, "angle_weights", None),
    )
    p, v, a, j = out["p"], out["v1"] / T, out["a1"] / T**2, out["j1"] / T**3
    traj = CartesianTrajectory(path, T)
    return Plan(task, path.method, dict(path.parameters), duration, traj, t, p, v, a, j, joint, report, profile.name)
