"""Check a trajectory that was planned elsewhere (or by this tool) against a profile's limits.

The CSV needs a header with ``t`` and the joint positions ``q1 … qn`` (unit suffixes like ``q1[rad]`` are
ignored; ``,`` ``;`` or tab separated; ``#`` lines and blank lines are skipped). Positions go through forward
kinematics to the tool path; a quintic spline through the tool positions (interpolating by default,
smoothing with ``smoothing`` > 0) gives the continuous motion and its derivatives, which then run through
the same joint mapping, dynamics and limit check as ``plan``.

* **Several moves.** A file with a ``move`` column (this tool's ``plan --batch`` and ``--round-trip``
  output) is checked move by move: the rows of each move are consecutive, and its time may restart at 0
  (batch) or run on (round trip). Samples at the end of a move that repeat its last joint positions exactly
  are the tool at rest (a round trip's dwell): they are not part of the move (the duty cycle's dwell is the
  profile's, as for ``plan``). Without a ``move`` column a file is one move, and a time that goes back is an
  error that says so.
* **Positions as given.** The joint position rows use the file's values, not the model's inverse
  kinematics of the tool path (which wraps revolute joints into (−π, π]): q1 = 5 rad is checked as 5 rad.
  The file's joint positions must be the configuration the profile's model describes (the same branch, up
  to whole turns of a revolute joint), or the dynamics would be those of another pose; otherwise the
  check refuses the file (TaskError naming the line, joint and both values).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ..model.errors import TaskError
from ..limits.check import _range_row, capacity_rows, check_limits
from ..limits.grid import check_grid
from ..limits.motion import MotionModel
from ..limits.report import LimitReport
from ..model.headroom import limit_specs
from ..model.profile import Profile
from ..robots import build_robot
from ..model.trajectory import CartesianPath
from .check_read import (JOINT_UNITS, MIN_SAMPLES, TIME_UNITS, TOOL_COLUMNS, Samples, column_scales,  # noqa: F401
                         read_moves, read_trajectory)

#: a joint position in the file may differ from the model's inverse kinematics of its own forward
#: kinematics by this much (rad or m) before it counts as another branch. FK∘IK round trips to ~1e-12 and
#: the CSV carries 12 digits; 1e-3 still separates real branch changes (an elbow flipped, a Delta arm
#: folded in: tenths of a radian and more) and does not trip on a pose within 1e-3 of a singularity, where
#: the singularity row reports the problem instead.
BRANCH_TOL = 1e-3
#: the finest accuracy ``check`` claims for a peak estimated from samples, relative to the peak: the values of a file
#: carry 12 significant digits, a reconstruction's third derivative amplifies their round-off, and a plan's peak sits at
#: its limit to ~1e-7; a file run 1 % faster moves every timed peak by 1 % or more
CHECK_RESOLUTION = 1e-3
#: the change of a peak when every other sample is dropped, over this, is the septic Hermite's accuracy: (2⁵ − 1)/2,
#: its third derivative converging as h⁵, with a factor 2 of safety
HERMITE_DIVISOR = 15.5
#: the file's x, y, z may differ from FK of its joint positions by this much [m] (12 significant digits: ~1e-12)
TOOL_TOL = 1e-7
#: a file without a move column whose last joint positions are its first to this [rad or m] returns to its start:
#: it is one whole duty cycle (a round trip or belt cycle written as one table, a recording of a cycle), and the RMS
#: torque is taken over the file itself, no dwell and no move back added (a one-way move's ends lie far apart)
CLOSED_TOL = 1e-6
#: the note that says so (the verdict's cycle line then gives the file's duration as the duty cycle)
CLOSED_NOTE = "it ends where it starts: one whole duty cycle, the RMS torque taken over the file (no dwell added)"


class WholeCycleReport(LimitReport):
    """The limit report of a file that is one whole duty cycle (:data:`CLOSED_NOTE`): its duty cycle is the file's
    duration, not 2·(duration + dwell), and its picks per minute 60 over that."""

    @property
    def round_trip(self) -> float:
        return self.duration + self.dwell


def whole_cycle(report: LimitReport) -> LimitReport:
    """``report`` as a :class:`WholeCycleReport` when its notes say the file is a whole cycle, else unchanged."""
    if not any(CLOSED_NOTE in n for n in report.notes):
        return report
    return WholeCycleReport(report.rows, report.duration, report.dwell, report.notes)


def closed_cycle(q: np.ndarray) -> bool:
    """Whether joint positions ``q`` (N, n) [rad or m] end where they start (``CLOSED_TOL``)."""
    q = np.asarray(q, float)
    return len(q) > 2 and bool(np.max(np.abs(q[-1] - q[0])) <= CLOSED_TOL)


@dataclass(frozen=True)
class MoveCheck:
    """The limit report of one move of a checked file.

    Attributes
    ----------
    move : int or None
        The move's number (None for a file without a ``move`` column).
    first_line, last_line : int
        The move's lines in the file.
    report : LimitReport
        Its limit report (durations [s], peaks in each quantity's unit).
    """

    move: int | None
    first_line: int
    last_line: int
    report: LimitReport


def _check_branch(s: Samples, robot, pos: np.ndarray, source: str) -> None:
    """TaskError when the file's joint positions are not the model's configuration (module docstring)."""
    rotary = getattr(robot, "rotary", False)  # a fourth axis: the model's q4 for the file's own tool angle
    q_model = robot.inverse_kinematics(pos, robot.tool_angle(s.q)) if rotary else robot.inverse_kinematics(pos)
    diff = s.q - q_model
    revolute = np.array([u == "rad" for u in robot.joint_units])
    turns = np.where(revolute, 2 * np.pi * np.round(diff / (2 * np.pi)), 0.0)
    off = np.abs(diff - turns)
    if rotary and np.max(off[:, :-1]) > BRANCH_TOL:  # the arm's branch: name its joint (q4 follows from it)
        off[:, -1] = 0.0
    if np.max(off) > BRANCH_TOL:
        k = int(np.flatnonzero(np.max(off, axis=1) > BRANCH_TOL)[0])  # the first such row
        j = int(np.argmax(off[k]))
        name, unit = robot.joint_names[j], robot.joint_units[j]
        p = ", ".join(f"{c:.6g}" for c in pos[k])
        raise TaskError(
            f"{source}:{s.lines[k]}: {name} = {s.q[k, j]:.6g} {unit} is another configuration than the profile's "
            f"model: for the same tool position ({p}) m its inverse kinematics gives {name} = {q_model[k, j]:.6g} "
            f"{unit}; check the profile (e.g. the SCARA's robot.elbow), the joint order and the units"
        )


def _motion_report(t: np.ndarray, pos: np.ndarray, robot, profile: Profile, smoothing: float, source: str,
                   notes=None, tool: np.ndarray | None = None, rebuilt=None, not_held: str = "",
                   dwell: float | None = None):
    """The limit report of the tool positions ``pos`` (N, 3) m (and angle, rad, a 4th column with a rotary axis) at
    ``t`` (N,) s from 0, through a reconstruction of
    the continuous motion (an interpolating spline split at the jerk steps found in the data,
    :func:`~pickplace_cli.curves.sampled.reconstruct`, or a smoothing spline), and the words that say how the
    derivatives were found. ``notes``: a function of those words → the report's notes. ``tool`` (N, 12): the
    file's own tool positions, velocities, accelerations and jerks (consistent with ``pos``), through which the
    motion between samples is the septic Hermite interpolant (exact at every sample up to the jerk). ``rebuilt``:
    (evaluate(x, order), the times of its steps [s], the words) of a motion already rebuilt (a table). The tool's
    Cartesian capacity rows come from the same continuous motion (:func:`capacity_rows` on the check's grid);
    ``not_held``: why they are not held ("" when they are: they then decide the verdict with the others).
    ``dwell`` [s]: the duty cycle's dwell for the RMS torque (None: the profile's; 0 for a whole cycle)."""
    from scipy.interpolate import UnivariateSpline

    T = float(t[-1])
    rotary = pos.shape[1] == 4  # the tool angle θ (a rotary fourth axis) as one more column
    extra = " and angle" if rotary else ""
    if rebuilt is not None:
        ev, steps, how = rebuilt
    elif tool is not None and not smoothing:
        from ..curves.sampled import hermite, reconstruct

        ev3, steps = hermite(t, tool[:, 0:3], tool[:, 3:6], tool[:, 6:9], tool[:, 9:12])
        how = ("septic Hermite polynomials through the file's tool positions, velocities, accelerations and jerks "
               "(x … jz; x, y, z agree with FK(q))")
        ev = ev3
        if rotary:  # the angle has no derivative columns: its interpolating spline, split at its own steps
            ev_angle, angle_steps = reconstruct(t, pos[:, 3:4])
            steps = np.union1d(steps, angle_steps)
            how += ", and a quintic interpolating spline of the tool angle"

            def ev(x: np.ndarray, order: int) -> np.ndarray:
                return np.column_stack([ev3(x, order), ev_angle(x, order)])

        if steps.size:
            shown = ", ".join(f"{x:.5g}" for x in steps[:6]) + (" …" if steps.size > 6 else "")
            how += f", split at the jerk steps found between samples at t = {shown} s ({steps.size}; both sides checked)"
    elif smoothing > 0:
        splines = [UnivariateSpline(t, pos[:, k], k=5, s=smoothing * len(t)) for k in range(pos.shape[1])]

        def ev(x: np.ndarray, order: int) -> np.ndarray:
            return np.column_stack([sp.derivative(order)(x) if order else sp(x) for sp in splines])

        how = f"a quintic smoothing spline (s = {smoothing:g}·N) of the tool positions FK(q){extra}"
        steps = np.zeros(0)
    else:
        from ..curves.sampled import reconstruct

        ev, steps = reconstruct(t, pos)
        how = f"a quintic interpolating spline of the tool positions FK(q){extra}"
        if steps.size:
            shown = ", ".join(f"{x:.5g}" for x in steps[:6]) + (" …" if steps.size > 6 else "")
            how += (f", one per stretch between the jerk steps found in the data at t = {shown} s ({steps.size}; both "
                    "sides checked)")

    def evaluate(tau: np.ndarray, order: int) -> np.ndarray:
        return ev(np.clip(tau, 0.0, 1.0) * T, order)[:, :3] * T**order

    angle = None
    if rotary:
        from ..curves.rotation import SampledRotation

        angle = SampledRotation(lambda tau, order: ev(np.clip(tau, 0.0, 1.0) * T, order)[:, 3] * T**order)
    # the pieces join across the samples to the interpolation error: nothing jumps there, peaks are fitted across
    # them; at a jerk step found in the data the check takes both one-sided values (never across it)
    jumps = steps / T
    cpath = CartesianPath(evaluate, "checked", {"source": source}, (0.0, 0.0, 0.0),
                          np.sort(np.concatenate([t / T, jumps])), jumps=jumps, angle=angle)
    margin = getattr(profile.robot, "singularity_margin", None)
    model = MotionModel(cpath, robot, limit_specs(profile), margin, profile.workcell.box)
    grid = check_grid(t / T, cpath.breakpoints, jumps=jumps)
    report = check_limits(model, T, parts=model.parts(grid), dwell=profile.planning.dwell if dwell is None else dwell,
                          notes=() if notes is None else notes(how))
    return report.with_rows(capacity_rows(cpath, T, profile.capacity, not_held, grid=grid)), how


def _half(n: int) -> np.ndarray:
    """Every other sample of n, the last one always kept."""
    idx = np.arange(0, n, 2)
    return idx if idx[-1] == n - 1 else np.append(idx, n - 1)


def check_samples(s: Samples, profile: Profile, smoothing: float = 0.0, source: str = "<trajectory>",
                  strict: bool = False, warn=None, not_held: str = "") -> LimitReport:
    """Limit report of one move read by :func:`read_moves` (see the module docstring).

    Every duration-dependent peak is estimated from the samples twice, from all of them and from every other one
    (the same reconstruction): their difference, and at least 0.1 % of the peak (``CHECK_RESOLUTION``), is the
    peak's stated accuracy (the error of an estimate that converges with the sample rate is smaller than its change
    when the rate halves). A row is exceeded only
    when its peak less that accuracy is beyond the limit (the data shows it exceeded); a peak whose accuracy is
    worse than 1 % of the limit is reported as not resolved by the samples (``LimitReport.unresolved``).

    The file's tool derivative columns (vx … jz) are used only when they agree with its positions
    (:func:`~pickplace_cli.pipelines.check_read.derivative_problems`); otherwise the move is judged from its positions
    and ``warn`` (a callable) is told in one line, or with ``strict`` the file is refused (TaskError).
    ``not_held``: why the tool's Cartesian capacity is not held ("" when it is: an exceeded capacity then fails)."""
    robot = build_robot(profile.robot)
    t = s.t - s.t[0]
    pos = robot.forward_kinematics(s.q)
    _check_branch(s, robot, pos, source)
    T = float(t[-1])
    rest = f"; {s.rest} trailing samples at rest set aside as the dwell" if s.rest else ""
    dwell = 0.0 if s.move is None and closed_cycle(s.q) else None
    whole = f"; {CLOSED_NOTE}" if dwell is not None else ""

    def notes(how: str) -> tuple[str, ...]:
        return (f"{s.where(source)}: {len(t)} samples over {T:.6g} s{rest}; derivatives from {how}; joint positions "
                f"checked as given in the file{whole}",)

    if smoothing == "auto":
        from ..curves.sampled import noise_level

        smoothing = noise_level(t, pos) ** 2
    tool = s.tool
    if tool is not None and np.max(np.abs(tool[:, :3] - pos)) > TOOL_TOL:
        off = float(np.max(np.abs(tool[:, :3] - pos)))
        rest += f"; its x, y, z differ from FK of its joint positions by up to {off:.3g} m, so its tool columns are not used"
        tool = None
    if tool is not None:
        from .check_read import derivative_problems, describe_problems

        problems = derivative_problems(t, tool)
        if problems:
            said = f"{s.where(source)}: {describe_problems(problems)}"
            if strict:
                raise TaskError(f"{said}: refused (--strict); without --strict the move is judged from its positions")
            if warn is not None:
                warn(f"warning: {said}: judged from its positions alone")
            rest += f"; its derivative columns are not used ({describe_problems(problems)})"
            tool = None
    if getattr(robot, "rotary", False):  # the tool angle θ = FK of the fourth axis, one more column
        pos = np.column_stack([pos, robot.tool_angle(s.q)])
    report, _ = _motion_report(t, pos, robot, profile, smoothing, source, notes, tool, not_held=not_held, dwell=dwell)
    others = []
    half = _half(len(t))
    if len(half) >= 6:
        # the septic Hermite through positions to jerks converges as h⁵ in the third derivative: its estimate's error
        # is the change when the rate halves over 2⁵ − 1, taken twice (HERMITE_DIVISOR); the splines of positions
        # alone are taken at the whole change (a jerk step they do not find rings however fine the samples)
        share = 1.0 / HERMITE_DIVISOR if tool is not None and not smoothing else 1.0
        others.append((_motion_report(t[half], pos[half], robot, profile, smoothing, source, None,
                                      None if tool is None else tool[half], dwell=dwell)[0], share))
    if smoothing:  # what the smoothing takes away is as uncertain as the rest: the interpolated data's peaks
        others.append((_motion_report(t, pos, robot, profile, 0.0, source, dwell=dwell)[0], 1.0))
    report = _with_accuracy(report, others)
    # the position ranges on the file's own values (the model's inverse kinematics wraps revolute joints)
    specs = limit_specs(profile)
    given = {}
    for j, (name, unit, spec) in enumerate(zip(robot.joint_names, robot.joint_units, specs)):
        if spec.limits.position is not None:
            lo, hi = spec.limits.position
            kmax, kmin = int(np.argmax(s.q[:, j])), int(np.argmin(s.q[:, j]))
            given[name] = _range_row((name, "position", unit, "reach", float(lo), float(hi)),
                                     float(s.q[kmax, j]), float(s.q[kmin, j]), float(t[kmax]), float(t[kmin]))
    rows = tuple(given.get(r.joint, r) if r.quantity == "position" else r for r in report.rows)
    return replace(report, rows=rows)


def _with_accuracy(fine: LimitReport, others: list[tuple[LimitReport, float]]) -> LimitReport:
    """``fine``'s duration-dependent rows with accuracy = the largest share × |its peak − the same row's peak| over
    ``others`` ((report, share): other estimates from the same data), at least ``CHECK_RESOLUTION`` of the peak, and
    the verdict that the data supports: exceeded only when the peak less its accuracy is beyond the allowed value."""
    from ..limits.report import LimitRow

    if not others:
        return fine
    other = [({(r.joint, r.quantity): r for r in o.rows}, share) for o, share in others]
    rows = []
    for r in fine.rows:
        cs = [(o[(r.joint, r.quantity)], share) for o, share in other if (r.joint, r.quantity) in o]
        if r.kind == "limit" and r.bound == "upper" and cs:
            acc = max(max(share * abs(r.peak - c.peak) for c, share in cs), CHECK_RESOLUTION * abs(r.peak))
            ok = r.peak - acc <= r.allowed
            r = LimitRow(r.joint, r.quantity, r.unit, r.peak, r.limit, r.utilisation, r.t_peak, ok, r.kind, r.bound,
                         r.target, acc, r.not_held)
        rows.append(r)
    return replace(fine, rows=tuple(rows))


_HOW = {"pvt": "the drive's cubic Hermite through each point's position and velocity (PVT)",
        "cam": "the kernel's quintic through each point's position, velocity and acceleration (cam, XYVA)"}


def check_table(table, profile: Profile, source: str, not_held: str = "") -> LimitReport:
    """The limit report of a PVT or cam table as the drive interpolates it (:func:`tool_motion`): the same dynamics and
    limit check as ``plan``; every duration-dependent peak to ``CHECK_RESOLUTION`` (the rebuild is exact up to the fit
    of the tool's motion, far finer); the position rows on the interpolated joint positions themselves."""
    from .check_read import MAX_POINTS, SEGMENT_POINTS, joint_polynomial, tool_motion

    if len(table.t) > MAX_POINTS:
        raise TaskError(f"{source}: {len(table.t):,} points in a {table.kind} table: check reads at most {MAX_POINTS:,}")
    robot = build_robot(profile.robot)
    rotary = getattr(robot, "rotary", False)

    def tool_of(q: np.ndarray) -> np.ndarray:
        p = robot.forward_kinematics(q)
        return np.column_stack([p, robot.tool_angle(q)]) if rotary else p

    t = table.t - table.t[0]
    rebased = replace(table, t=t)
    s = Samples(None, t, table.q, table.lines, 0, int(table.lines[-1]))
    _check_branch(s, robot, robot.forward_kinematics(table.q), source)
    ev, steps = tool_motion(rebased, tool_of)
    T = float(t[-1])
    note = (f"{s.where(source)}: a {table.kind} table of {len(t)} points over {T:.6g} s; the motion is {_HOW[table.kind]}, "
            "as the drive runs it (each point a step of its derivatives: both sides checked); joint positions checked "
            "as interpolated")
    if table.kind == "pvt":  # the drive's cubic Hermite is C¹: its acceleration steps at the points
        from .check_read import pvt_acceleration_steps

        jumps = ", ".join(f"{n} {v:.4g} {u}/s²" for n, v, u in zip(robot.joint_names, pvt_acceleration_steps(table),
                                                                     robot.joint_units))
        note += (f"; its acceleration steps at the points by up to {jumps} (the torque there is checked on both "
                 "sides; the torque rate is that inside the segments)")
    dwell = None
    if closed_cycle(table.q):  # a round trip or belt cycle as one table: the duty cycle is the table itself
        dwell = 0.0
        note += f"; {CLOSED_NOTE}"
    report, _ = _motion_report(t, tool_of(table.q), robot, profile, 0.0, source, lambda how: (note,),
                               rebuilt=(ev, steps, _HOW[table.kind]), not_held=not_held, dwell=dwell)
    report = _with_accuracy(report, [(report, 1.0)])
    u = 0.5 - 0.5 * np.cos(np.pi * np.arange(SEGMENT_POINTS) / (SEGMENT_POINTS - 1))
    x = np.append((t[:-1, None] + np.diff(t)[:, None] * u).ravel(), T)
    q = joint_polynomial(rebased)(x)
    given = {}
    for j, (name, unit, spec) in enumerate(zip(robot.joint_names, robot.joint_units, limit_specs(profile))):
        if spec.limits.position is not None:
            lo, hi = spec.limits.position
            kmax, kmin = int(np.argmax(q[:, j])), int(np.argmin(q[:, j]))
            given[name] = _range_row((name, "position", unit, "reach", float(lo), float(hi)),
                                     float(q[kmax, j]), float(q[kmin, j]), float(x[kmax]), float(x[kmin]))
    rows = tuple(given.get(r.joint, r) if r.quantity == "position" else r for r in report.rows)
    return replace(report, rows=rows)


#: the largest trajectory file ``check`` reads [bytes] (~600,000 rows of a 3-joint trajectory at 1 kHz; its
#: parse holds a few times this in memory): larger is one line, exit 1, never a swap storm
CHECK_MAX_BYTES = 64 << 20


def _read_bounded(fh, limit: int) -> bytes:
    """At most ``limit`` bytes of ``fh``, read in 1 MiB pieces (one ``read(limit)`` would allocate all of ``limit``
    however small the file)."""
    parts, total = [], 0
    while total < limit:
        piece = fh.read(min(1 << 20, limit - total))
        if not piece:
            break
        parts.append(piece)
        total += len(piece)
    return b"".join(parts)


def check_file(path: str | Path, profile: Profile, smoothing: float | str = 0.0,
               limit_use: float | None = None, notify=None, strict: bool = False, warn=None,
               hold_capacity: bool = True) -> list[MoveCheck]:
    """Check every move of a trajectory file against a profile's limits.

    Parameters
    ----------
    path : str or pathlib.Path
        A CSV file with a header holding ``t`` [s] and ``q1 … qn`` [rad or m] (units in the header are honoured);
        ``-`` reads standard input. A ``move`` column splits it into moves.
    profile : Profile
        The robot and its limits.
    smoothing : float or str
        Smoothing factor per sample [m²] of the tool position (0: interpolate exactly), or ``"auto"``: the square
        of the noise level estimated from the samples.
    limit_use : float or None
        The fraction (0, 1] [-] of every timed limit's rating allowed; None: the profile's ``planning.limit_use``.
    notify : callable, optional
        Told (one text argument) what a named pipe without a writer is waiting for.
    strict : bool
        Refuse (TaskError) a file whose derivative columns disagree with its positions, instead of judging it from
        its positions.
    warn : callable, optional
        Told (one line) when a file's derivative columns are not used because they disagree with its positions.
    hold_capacity : bool
        Whether the profile's Cartesian capacity (the tool's |v| [m/s], |a| [m/s²], |j| [m/s³]) is held: True, an
        exceeded capacity fails the check (as ``plan`` under its default rule); False, its rows are reported as
        not held (``--no-hold-capacity``, as ``plan --time fit`` or ``optimal``).

    Returns
    -------
    list of MoveCheck
        One limit report per move, each peak with its accuracy from the samples.

    Raises
    ------
    TaskError
        An unreadable, binary, oversized or malformed file, or positions the profile's model cannot have.
    """
    from ..model.headroom import apply_limit_use

    profile = apply_limit_use(profile, limit_use)
    import sys

    p = Path(path)
    source = "<stdin>" if str(path) == "-" else str(p)
    try:
        if str(path) == "-":
            raw = _read_bounded(sys.stdin.buffer, CHECK_MAX_BYTES + 1)
        else:  # (a named pipe: its writer awaited for a bounded time, saying so through ``notify``)
            from ..model.files import open_for_reading

            with open(open_for_reading(str(p), "trajectory", TaskError, notify=notify), "rb") as fh:
                raw = _read_bounded(fh, CHECK_MAX_BYTES + 1)
    except OSError as exc:
        raise TaskError(f"{p}: cannot read: {exc.strerror}") from None
    if len(raw) > CHECK_MAX_BYTES:
        raise TaskError(f"{source}: larger than {CHECK_MAX_BYTES} bytes ({CHECK_MAX_BYTES >> 20} MiB), the most check "
                        "reads at once; split the file by move (e.g. one file per move column value)")
    from ..model.text import decode_text

    text = decode_text(raw, source, "a CSV trajectory", TaskError)
    robot = build_robot(profile.robot)
    from .check_read import read_checked

    not_held = "" if hold_capacity else "--no-hold-capacity"
    kind, what, source = read_checked(text, source, profile, robot)  # joints, drive units, a table (check_read)
    if kind == "table":
        return [MoveCheck(None, int(what.lines[0]), int(what.lines[-1]),
                          whole_cycle(check_table(what, profile, source, not_held).rated(profile.limit_use)))]
    out = []
    for s in (what if kind == "samples" else [what]):
        out.append(MoveCheck(s.move, int(s.lines[0]), s.last_line,
                             whole_cycle(check_samples(s, profile, smoothing, source, strict, warn,
                                                       not_held).rated(profile.limit_use))))
    return out


def check_trajectory(path: str | Path, profile: Profile, smoothing: float = 0.0) -> LimitReport:
    """Limit report of the one move in CSV file ``path`` (a file of several moves: :func:`check_file`)."""
    checks = check_file(path, profile, smoothing)
    if len(checks) > 1:
        raise TaskError(f"{path}: {len(checks)} moves (a 'move' column); check_file checks each")
    return checks[0].report
