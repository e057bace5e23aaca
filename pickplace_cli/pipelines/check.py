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
from ..limits.check import _range_row
from ..limits.report import LimitReport
from ..model.headroom import limit_specs
from ..model.profile import Profile
from ..robots import build_robot
from .check_read import (JOINT_UNITS, MIN_SAMPLES, TIME_UNITS, TOOL_COLUMNS, Samples, column_scales,  # noqa: F401
                         read_moves, read_trajectory)
from ..limits.samples import (BRANCH_TOL, CHECK_RESOLUTION, CLOSED_NOTE, CLOSED_TOL, HERMITE_DIVISOR,  # noqa: F401
                              TOOL_TOL, _check_branch, _motion_report, _with_accuracy, check_samples, closed_cycle)


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
    cycle : float or None
        The controller cycle [s] a PVT or cam-table table's steps were held over (None for other files).
    """

    move: int | None
    first_line: int
    last_line: int
    report: LimitReport
    cycle: float | None = None



_HOW = {"pvt": "the drive's cubic Hermite through each point's position and velocity (PVT)",
        "cam": "the kernel's quintic through each point's position, velocity and acceleration (cam, XYVA)",
        "cam-table": "the straight lines between the points read every controller cycle of {cycle:g} s, each velocity "
                     "step blended over that cycle (a linear cam table)"}


def table_cycle(profile: Profile, cycle: float | None, table=None) -> float:
    """The controller cycle [s] a table is run at: ``cycle`` (``check --cycle``), else the profile's
    ``controller.cycle``, else what ``plan`` takes without ``--cycle``: the period of the profile's ``planning.rate``,
    for a cam-table (``table``) the nearest period that fits its span in whole periods (``plan`` reads an
    equidistant table of an unknown cycle at whole steps of its duration)."""
    if cycle is not None:
        return float(cycle)
    given = getattr(profile.controller, "cycle", None) if profile.controller is not None else None
    if given is not None:
        return float(given)
    step = 1.0 / float(profile.planning.rate)
    if table is not None and table.kind == "cam-table":
        span = float(table.t[-1] - table.t[0])
        return span / max(1, round(span / step)) if span > 0 else step
    return step


def check_table(table, profile: Profile, source: str, not_held: str = "", cycle: float | None = None,
                ends: str = "hold") -> LimitReport:
    """The limit report of a PVT, cam or equidistant cam table as the drive interpolates it (:func:`tool_motion`; a
    cam-table read every controller cycle, :func:`table_cycle`): the same dynamics and limit check as ``plan``, and
    its per-cycle step rows where the acceleration steps (PVT, cam-table: the motor torque step against the torque
    rate × the cycle, :func:`~pickplace_cli.limits.table.step_rows`); every duration-dependent peak to
    ``CHECK_RESOLUTION`` (the tool's motion is solved exactly from the rebuilt joint motion); the position rows on
    the interpolated joint positions themselves."""
    from .check_read import MAX_POINTS, SEGMENT_POINTS, table_motion, tool_motion

    cycle = table_cycle(profile, cycle, table)
    blend = cycle  # a cam-table's lines read every cycle; any table's moving end taken to or from rest in one cycle
    if len(table.t) > MAX_POINTS:
        raise TaskError(f"{source}: {len(table.t):,} points in a {table.kind} table: check reads at most {MAX_POINTS:,}")
    span = float(table.t[-1] - table.t[0])
    if cycle > span:
        raise TaskError(f"cycle = {cycle:g} s: longer than the {table.kind} table it runs ({span:.6g} s, {source}): the "
                        "controller cycle must be shorter than the move (is it in ms? give seconds: 1 ms = 0.001)")
    if table.kind == "cam-table" and span / blend > MAX_POINTS / 2:
        raise TaskError(f"{source}: a cam-table of {span:.6g} s read every {blend:g} s is "
                        f"{span / blend:,.0f} cycles, each a blend and a line: check reads at most "
                        f"{MAX_POINTS // 2:,} (give the controller's cycle: --cycle SECONDS)")
    robot = build_robot(profile.robot)
    rotary = getattr(robot, "rotary", False)

    def tool_of(q: np.ndarray) -> np.ndarray:
        p = robot.forward_kinematics(q)
        return np.column_stack([p, robot.tool_angle(q)]) if rotary else p

    t = table.t - table.t[0]
    rebased = replace(table, t=t)
    s = Samples(None, t, table.q, table.lines, 0, int(table.lines[-1]))
    _check_branch(s, robot, robot.forward_kinematics(table.q), source)
    motion = table_motion(rebased, blend, ends)  # the drive's joint motion, once
    ev, steps = tool_motion(rebased, robot, blend, motion)
    T = motion.duration
    how = _HOW[table.kind].format(cycle=cycle)
    note = (f"{s.where(source)}: a {table.kind} table of {len(t)} points over {float(t[-1]):.6g} s; the motion is {how}, "
            "as the drive runs it (each break a step of its derivatives: both sides checked); joint positions checked "
            "as interpolated")
    if motion.steps:
        note += (f"; each acceleration step (the ends from and to rest) taken within one controller cycle of "
                 f"{cycle:g} s: its motor torque step, with the torque's change at its rate over that cycle, held to the "
                 f"torque rate × the cycle (check --cycle; plan "
                 "--cycle, or the profile's controller.cycle, else its planning rate)")
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
    bt = np.asarray(motion.breaks, float)
    start = motion.start  # a cam-table's motion starts half a cycle before its first point (the first blend)
    if start == 0.0 and bt[-1] == t[-1]:  # (breaks = the points, from 0: no blend beyond them)
        report, _ = _motion_report(t, tool_of(table.q), robot, profile, 0.0, source, lambda how: (note,),
                                   rebuilt=(ev, steps, how), not_held=not_held, dwell=dwell)
    else:  # the report's times from the motion's start, shifted back to the table's below
        report, _ = _motion_report(bt - start, tool_of(motion(bt)), robot, profile, 0.0, source, lambda how: (note,),
                                   rebuilt=(lambda x, order: ev(np.asarray(x, float) + start, order), steps - start,
                                            how), not_held=not_held, dwell=dwell)
        # the duration (and the cycle, picks/min) is the table's, from its first point to its last, as plan's: the
        # blends' half cycles before and after are the drive taking the first and last steps
        report = replace(report, duration=float(t[-1]), rows=tuple(
            r if r.t_peak is None else replace(r, t_peak=r.t_peak + start) for r in report.rows))
    report = _with_accuracy(report, [(report, 1.0)])
    if motion.steps:
        from ..limits.motion import MotionModel
        from ..limits.table import step_rows, table_path

        model = MotionModel(table_path(motion, robot), robot, limit_specs(profile),
                            getattr(profile.robot, "singularity_margin", None), profile.workcell.box)
        report = report.with_rows(tuple(replace(r, t_peak=r.t_peak + start) for r in step_rows(model, motion, cycle)))
    u = 0.5 - 0.5 * np.cos(np.pi * np.arange(SEGMENT_POINTS) / (SEGMENT_POINTS - 1))
    x = np.append((bt[:-1, None] + np.diff(bt)[:, None] * u).ravel(), bt[-1])
    q = motion(x)
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
               hold_capacity: bool = True, cycle: float | None = None, table_end: str = "hold") -> list[MoveCheck]:
    """Check every move of a trajectory file against a profile's limits.

    Parameters
    ----------
    path : str or pathlib.Path
        A CSV file with a header holding ``t`` [s] and ``q1 … qn`` [rad or m] (units in the header are honoured);
        ``-`` reads standard input. A ``move`` column splits it into moves.
    profile : Profile or str
        The robot and its limits (a shipped profile's name or a YAML file: :func:`load_profile`).
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
        Told (one line each, starting "warning: ") when a file's derivative columns are not used because they
        disagree with its positions, when ``cycle`` is given for a file that is not a PVT or cam-table, and when a
        move starts or ends moving.
    hold_capacity : bool
        Whether the profile's Cartesian capacity (the tool's |v| [m/s], |a| [m/s²], |j| [m/s³]) is held: True, an
        exceeded capacity fails the check (as ``plan`` under its default rule); False, its rows are reported as
        not held (``--no-hold-capacity``, as ``plan --time fit`` or ``optimal``).
    cycle : float or None
        The controller cycle [s] a table is run at (``check --cycle``): a cam-table's lines are read once per cycle,
        and a PVT or cam-table's acceleration steps are taken within one (the motor torque step plus the torque's
        change at its rate over that cycle held to the torque rate × the cycle). None: the profile's ``controller.cycle``, else the period of its ``planning.rate`` (what
        ``plan`` takes without ``--cycle``).
    table_end : str
        Before a table that starts moving and after one that ends moving (``check --table-end``): "hold" (the drive
        holds its end point: the velocity step from or to rest within one cycle is judged) or "continue" (the
        controller goes on at the end's velocity: not judged past the end). Not used for a file of samples.

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

    if not isinstance(path, (str, Path)):
        raise TaskError(f"path = {path!r}: must be a file name (str or pathlib.Path), or '-' for standard input")
    if table_end not in ("hold", "continue"):
        raise TaskError(f"table_end = {table_end!r}: must be hold or continue (what the drive does past a table's end)")
    if cycle is not None:  # the CLI's rule and message for --cycle
        from ..timing.cycle import check_cycle

        cycle = check_cycle(cycle)
    if isinstance(profile, (str, Path)):  # a library caller's profile by name or file, as the CLI's --profile
        from ..model.profile import load_profile

        profile = load_profile(profile)
    elif not isinstance(profile, Profile):
        raise TaskError(f"profile = {profile!r}: must be a Profile (load_profile(name or path))")
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
    # (a cam that starts or ends moving, held there: a step from or to rest)
    steps = kind == "table" and (what.kind != "cam" or (table_end == "hold" and _table_moves(what)))
    if cycle is not None and warn is not None and not steps:
        warn(f"warning: --cycle {cycle:g} s: not used: {source} is not a pvt or cam-table table (its motion has no step a "
             "controller cycle bounds)")
    if warn is not None:
        for move, t, qd in _end_speeds(kind, what):
            _warn_moving_ends(warn, source, move, t, qd, robot.joint_names, table_end if kind == "table" else None)
    if kind == "table":
        on = table_cycle(profile, cycle, what) if steps else None
        return [MoveCheck(None, int(what.lines[0]), int(what.lines[-1]),
                          whole_cycle(check_table(what, profile, source, not_held, cycle, table_end)
                                      .rated(profile.limit_use)),
                          on)]
    out = []
    for s in (what if kind == "samples" else [what]):
        out.append(MoveCheck(s.move, int(s.lines[0]), s.last_line,
                             whole_cycle(check_samples(s, profile, smoothing, source, strict, warn,
                                                       not_held).rated(profile.limit_use))))
    return out


#: a move whose joint speed at its first or last sample is above this share of its peak [-] "ends moving": a file cut
#: short, or a conveyor move (which ends at the belt's speed); a move from and to rest stays far below (a sampled
#: file's end speed is extrapolated from its first or last two intervals: :func:`_end_speeds`)
MOVING_END = 0.1


def _table_moves(table) -> bool:
    """Whether a PVT or cam ``table`` starts or ends moving (a velocity step from or to rest at its end)."""
    from ..export.interpolate import moving_ends

    return any(np.any(v) for v in moving_ends(table.t, table.q, table.qd))


def _end_speeds(kind: str, what) -> list:
    """[(move, times (N,) [s], joint speeds (N, n) [per s])] of each move (a table: its points' velocities, a PVT's or
    cam's own, a cam-table's slopes; samples: the slope of each interval, at its end, and at the first and last
    sample the slope there of the parabola through the first or last three samples — a move from rest has a
    first interval's mean speed of 10-30 % of its peak at 50-80 Hz, which is no speed at its start: the parabola's
    slope there is ≤ 0 for any start from rest (q ∝ tⁿ, n ≥ 2), and the speed itself to O(h²) for a file that starts
    moving; a parabola that turns back there counts as at rest)."""
    if kind == "table":
        if what.qd is not None:
            return [(None, what.t, what.qd)]
        slope = np.diff(what.q, axis=0) / np.diff(what.t)[:, None]
        return [(None, what.t[1:], slope)] if len(slope) else []
    out = []
    for s in what:
        if len(s.t) < 2:
            continue
        h = np.diff(s.t)
        slope = np.diff(s.q, axis=0) / h[:, None]
        if len(slope) < 2:
            out.append((s.move, s.t[1:], slope))
            continue
        v0 = slope[0] - (slope[1] - slope[0]) * (h[0] / (h[0] + h[1]))
        v1 = slope[-1] + (slope[-1] - slope[-2]) * (h[-1] / (h[-1] + h[-2]))
        v0 = np.where(v0 * slope[0] > 0, v0, 0.0)
        v1 = np.where(v1 * slope[-1] > 0, v1, 0.0)
        out.append((s.move, np.concatenate([s.t[:1], s.t[1:], s.t[-1:]]), np.vstack([v0, slope, v1])))
    return out


def _warn_moving_ends(warn, source: str, move, t: np.ndarray, qd: np.ndarray, names, table: str | None = None) -> None:
    """One warning when the move starts or ends moving (:data:`MOVING_END`): check judges the file as it is, and the
    stop beyond its end (or the start before it) is not in it — but for a drive's table (``table``: "hold"), which
    the drive holds at its end position before and after: the step from or to rest is judged, within one controller
    cycle ("continue": the controller goes on at the end's velocity, not judged past it)."""
    peak = np.max(np.abs(qd), axis=0)
    for at, row, when in ((0, qd[0], "starts"), (-1, qd[-1], "ends")):
        share = np.where(peak > 0, np.abs(row) / np.where(peak > 0, peak, 1.0), 0.0)
        j = int(np.argmax(share))
        if share[j] > MOVING_END:
            which = f"move {move}: " if move is not None else ""
            said = (f"warning: {source}: {which}the motion {when} moving ({names[j]} at {100 * share[j]:.0f} % of its "
                    f"peak speed at t = {t[at]:.6g} s)")
            why = f"(a file cut short? a conveyor move {when} at the belt's speed)"
            if table == "hold":
                warn(f"{said}: the drive holds the table's {'first' if at == 0 else 'last'} point "
                     f"{'before' if at == 0 else 'after'} it, so the step {'from' if at == 0 else 'to'} rest is judged, "
                     f"taken within one controller cycle {why}; --table-end continue if the controller goes on at the "
                     "end's velocity")
            elif table == "continue":
                warn(f"{said}: judged as the controller going on at the end's velocity {'before' if at == 0 else 'after'} "
                     "it (--table-end continue): what it does there is not checked")
            else:
                warn(f"{said}: it is judged as the file holds it, and what the drive does "
                     f"{'before' if at == 0 else 'after'} is not checked {why}")
            return


def check_trajectory(path: str | Path, profile: Profile, smoothing: float = 0.0) -> LimitReport:
    """Limit report of the one move in CSV file ``path`` (a file of several moves: :func:`check_file`)."""
    checks = check_file(path, profile, smoothing)
    if len(checks) > 1:
        raise TaskError(f"{path}: {len(checks)} moves (a 'move' column); check_file checks each")
    return checks[0].report
