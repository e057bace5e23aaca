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

import csv
import math
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
#: fewest samples a move needs: a quintic spline has 6 coefficients
MIN_SAMPLES = 6
#: the tool's motion this tool's CSV writes beside the joints (m, m/s, m/s², m/s³): with all of them, and the
#: positions FK(q) within ``TOOL_TOL``, the motion between samples is the septic Hermite through them
TOOL_COLUMNS = ("x", "y", "z", "vx", "vy", "vz", "ax", "ay", "az", "jx", "jy", "jz")
#: the file's x, y, z may differ from FK of its joint positions by this much [m] (12 significant digits: ~1e-12)
TOOL_TOL = 1e-7


@dataclass(frozen=True)
class Samples:
    """One move of a trajectory file: ``move`` its number in the file's move column (None: no such column),
    ``t`` (N,) s and ``q`` (N, n) as in the file, ``lines`` (N,) the 1-based file line of every sample,
    ``rest`` how many trailing samples at rest were set aside (see the module docstring) and ``last_line``
    the file line of the move's last row (with them)."""

    move: int | None
    t: np.ndarray
    q: np.ndarray
    lines: np.ndarray
    rest: int
    last_line: int
    #: (N, 12) the tool's x, y, z [m], vx … [m/s], ax … [m/s²], jx … [m/s³] when the file has all of them (this
    #: tool's CSV does), else None
    tool: np.ndarray | None = None

    def where(self, source: str) -> str:
        name = f"move {self.move}" if self.move is not None else "the trajectory"
        return f"{source}: {name} (lines {int(self.lines[0])}–{self.last_line})"


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


def _number(cell: str, name: str, source: str, line: int, column: str) -> float:
    """The number in one cell; TaskError naming file:line, the column and the cell's text."""
    from ..model.text import plain_float

    try:
        x = plain_float(cell.strip())
    except ValueError:
        shown = cell.strip() if len(cell.strip()) <= 40 else cell.strip()[:40] + "…"
        raise TaskError(f"{source}:{line}: {name} = {shown!r}: not a number (column {column})") from None
    if not np.isfinite(x):
        raise TaskError(f"{source}:{line}: {name} = {cell.strip()}: must be a finite number (column {column})")
    return x


def _cells(line: str, sep: str, source: str, number: int) -> list[str]:
    """The cells of one line (quotes as CSV has them, within the line); TaskError naming the line for a quote that is
    not closed, a field over csv's size limit, and the like (never the rest of the file in the message)."""
    if '"' not in line:
        return line.split(sep)
    try:
        return next(csv.reader([line], delimiter=sep, strict=True))
    except csv.Error as exc:
        raise TaskError(f"{source}:{number}: not a CSV row ({exc}): a quote opened and not closed on this line?") from None


#: the units a header may give a checked column in, and the factor to SI: time, an angle, a length
TIME_UNITS = {"": 1.0, "s": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6}
JOINT_UNITS = {"rad": {"": 1.0, "rad": 1.0, "deg": math.pi / 180, "°": math.pi / 180},
               "m": {"": 1.0, "m": 1.0, "mm": 1e-3}}


def column_scales(names: list[str], joint_units: tuple[str, ...] | None, source: str, line: int) -> np.ndarray:
    """Factors from the units in the header cells ``names`` (``t[ms]``, ``q1[deg]``, ``q3[mm]``; no unit: SI) of the
    columns t, q1 … qn to s, rad or m; TaskError naming the column for a unit that is not one of the column's
    (``q1[rpm]``, ``q3[deg]`` of a prismatic joint). Derivative columns are not read (check derives them)."""
    out = np.ones(len(names))
    for k, cell in enumerate(names):
        unit = cell.split("[", 1)[1].rstrip("]").strip() if "[" in cell else ""
        base = cell.split("[")[0].strip()
        if k == 0:
            table, kind = TIME_UNITS, "s"
        else:
            kind = joint_units[k - 1] if joint_units is not None else "rad"
            table = JOINT_UNITS.get(kind, {"": 1.0, kind: 1.0})
        if unit not in table:
            units = [u for u in table if u]
            allowed = ", ".join(units[:-1]) + " or " + units[-1] if len(units) > 1 else units[0]
            raise TaskError(f"{source}:{line}: column {cell!r}: {base} is read in {allowed} (the header's unit "
                            f"{unit!r} is not one of them)")
        out[k] = table[unit]
    return out


def _si_tool_unit(cell: str) -> bool:
    """Whether a tool column's header names the SI unit this tool writes (x [m], vx [m/s], ax [m/s^2], jx [m/s^3]),
    or none."""
    name, _, unit = cell.strip().partition("[")
    unit = unit.rstrip("]").strip().replace("²", "^2").replace("³", "^3")
    order = {"v": 1, "a": 2, "j": 3}.get(name.strip()[0], 0) if len(name.strip()) == 2 else 0
    return unit in ("", ("m", "m/s", "m/s^2", "m/s^3")[order])


def read_moves(text: str, source: str, joint_names: tuple[str, ...],
               joint_units: tuple[str, ...] | None = None) -> list[Samples]:
    """The moves of a trajectory CSV (see the module docstring); TaskError naming the file, line, column and
    value of the first problem. Units in the header (``t[ms]``, ``q1[deg]``, ``q3[mm]``, :func:`column_scales`;
    ``joint_units`` "rad" or "m" per joint, default rad) are converted to s, rad and m."""
    from .batch import sniff_delimiter

    numbered = [(n, ln) for n, ln in enumerate(text.removeprefix("\ufeff").splitlines(), start=1)
                if ln.strip() and not ln.lstrip().startswith("#")]
    need = ["t", *joint_names]
    if not numbered:
        raise TaskError(f"{source}: empty file (need a header with {', '.join(need)})")
    head_line, head = numbered[0]
    sep = sniff_delimiter(head)
    rows = [_cells(ln, sep, source, n) for n, ln in numbered]  # line by line: an open quote ends with its line
    header = [h.strip().split("[")[0].strip() for h in rows[0]]
    missing = [c for c in need if c not in header]
    if missing:
        raise TaskError(
            f"{source}:{head_line}: header lacks column(s) {', '.join(missing)} (need {', '.join(need)}; found {', '.join(header)})"
        )
    if len(rows) < 2:
        raise TaskError(f"{source}:{head_line}: a header and no samples (need rows of {', '.join(need)} after it; "
                        f"a move needs at least {MIN_SAMPLES})")
    tool = [c for c in TOOL_COLUMNS if c in header] if all(c in header for c in TOOL_COLUMNS) else []
    if tool and not all(_si_tool_unit(rows[0][header.index(c)]) for c in tool):
        tool = []  # the tool columns in other units than this tool writes: the joint positions alone are used
    cols = need + tool + (["move"] if "move" in header else [])
    idx = [header.index(c) for c in cols]
    scales = column_scales([rows[0][i].strip() for i in idx[: len(need)]], joint_units, source, head_line)
    data = np.empty((len(rows) - 1, len(cols)))
    lines = np.array([n for n, _ in numbered[1:]], dtype=int)
    for k, (r, line) in enumerate(zip(rows[1:], lines)):
        for c, (name, i) in enumerate(zip(cols, idx)):
            if i >= len(r):
                raise TaskError(
                    f"{source}:{line}: {name}: no value (the row has {len(r)} cells, the header {len(header)})"
                )
            data[k, c] = _number(r[i], name, source, int(line), f"{i + 1}, {rows[0][i].strip()!r}")
    data[:, : len(need)] *= scales  # the header's units (ms, deg, mm) to s, rad, m
    nq = len(joint_names)
    extra = (lambda a, b: data[a:b, 1 + nq:1 + nq + 12]) if tool else (lambda a, b: None)
    if "move" not in header:
        return [_one_move(None, data[:, 0], data[:, 1:1 + nq], lines, source, trim=False, tool=extra(0, len(data)))]
    move = data[:, -1]
    bad = np.flatnonzero(move != np.round(move))
    if bad.size:
        raise TaskError(f"{source}:{lines[bad[0]]}: move = {move[bad[0]]:g}: must be a whole number (the move's index)")
    starts = np.r_[0, np.flatnonzero(np.diff(move) != 0) + 1]
    ends = np.r_[starts[1:], len(move)]
    seen: dict[int, int] = {}
    moves = []
    for a, b in zip(starts, ends):
        m = int(move[a])
        if m in seen:
            raise TaskError(
                f"{source}:{lines[a]}: move = {m}: its rows must be consecutive (move {m} already ended at line {seen[m]})"
            )
        seen[m] = int(lines[b - 1])
        moves.append(_one_move(m, data[a:b, 0], data[a:b, 1:1 + nq], lines[a:b], source, trim=True, tool=extra(a, b)))
    return moves


def _one_move(move: int | None, t: np.ndarray, q: np.ndarray, lines: np.ndarray, source: str, trim: bool,
              tool: np.ndarray | None = None) -> Samples:
    what = f" (move {move})" if move is not None else ""
    dt = np.diff(t)
    if np.any(dt <= 0):
        i = int(np.flatnonzero(dt <= 0)[0]) + 1
        hint = ""
        if move is None and t[i] <= t[0]:
            hint = ("; the time starts again, as if the file held several moves one after another: keep their "
                    "'move' column (plan --batch and --round-trip write one) and each move is checked on its own")
        raise TaskError(
            f"{source}:{lines[i]}: t = {t[i]:.9g} s is not after the previous row's t = {t[i - 1]:.9g} s{what}: "
            f"t must increase strictly from row to row{hint}"
        )
    rest = 0
    last_line = int(lines[-1])
    if trim:
        at_end = np.all(q == q[-1], axis=1)
        rest = len(q) - 1 - int(np.flatnonzero(~at_end)[-1] + 1) if not at_end.all() else 0
        if rest:
            t, q, lines = t[: len(t) - rest], q[: len(q) - rest], lines[: len(lines) - rest]
            tool = None if tool is None else tool[: len(tool) - rest]
    if len(t) < MIN_SAMPLES:
        raise TaskError(
            f"{source}:{lines[0]}: {len(t)} samples{what}; a move needs at least {MIN_SAMPLES} for a quintic spline"
        )
    return Samples(move, t, q, lines, rest, last_line, tool)


def read_trajectory(text: str, source: str, joint_names: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray]:
    """(t (N,) s from 0, q (N, n)) of a file holding one move; TaskError naming the file, line and problem
    (also when the file holds several moves: :func:`read_moves` reads those)."""
    moves = read_moves(text, source, joint_names)
    if len(moves) > 1:
        raise TaskError(f"{source}: {len(moves)} moves (a 'move' column); read them with read_moves")
    s = moves[0]
    return s.t - s.t[0], s.q


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
                   notes=None, tool: np.ndarray | None = None, not_held: str = ""):
    """The limit report of the tool positions ``pos`` (N, 3) m (and angle, rad, a 4th column with a rotary axis) at
    ``t`` (N,) s from 0, through a reconstruction of
    the continuous motion (an interpolating spline split at the jerk steps found in the data,
    :func:`~pickplace_cli.curves.sampled.reconstruct`, or a smoothing spline), and the words that say how the
    derivatives were found. ``notes``: a function of those words → the report's notes. ``tool`` (N, 12): the
    file's own tool positions, velocities, accelerations and jerks (consistent with ``pos``), through which the
    motion between samples is the septic Hermite interpolant (exact at every sample up to the jerk). The tool's
    Cartesian capacity rows come from the same continuous motion (:func:`capacity_rows` on the check's grid);
    ``not_held``: why they are not held ("" when they are: they then decide the verdict with the others)."""
    from scipy.interpolate import UnivariateSpline

    T = float(t[-1])
    rotary = pos.shape[1] == 4  # the tool angle θ (a rotary fourth axis) as one more column
    extra = " and angle" if rotary else ""
    if tool is not None and not smoothing:
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
    report = check_limits(model, T, parts=model.parts(grid), dwell=profile.planning.dwell,
                          notes=() if notes is None else notes(how))
    return report.with_rows(capacity_rows(cpath, T, profile.capacity, not_held, grid=grid)), how


def _half(n: int) -> np.ndarray:
    """Every other sample of n, the last one always kept."""
    idx = np.arange(0, n, 2)
    return idx if idx[-1] == n - 1 else np.append(idx, n - 1)


def check_samples(s: Samples, profile: Profile, smoothing: float = 0.0, source: str = "<trajectory>",
                  not_held: str = "") -> LimitReport:
    """Limit report of one move read by :func:`read_moves` (see the module docstring).

    Every duration-dependent peak is estimated from the samples twice, from all of them and from every other one
    (the same reconstruction): their difference, and at least 0.1 % of the peak (``CHECK_RESOLUTION``), is the
    peak's stated accuracy (the error of an estimate that converges with the sample rate is smaller than its change
    when the rate halves). A row is exceeded only
    when its peak less that accuracy is beyond the limit (the data shows it exceeded); a peak whose accuracy is
    worse than 1 % of the limit is reported as not resolved by the samples (``LimitReport.unresolved``).
    ``not_held``: why the tool's Cartesian capacity is not held ("" when it is: an exceeded capacity then fails)."""
    robot = build_robot(profile.robot)
    t = s.t - s.t[0]
    pos = robot.forward_kinematics(s.q)
    _check_branch(s, robot, pos, source)
    T = float(t[-1])
    rest = f"; {s.rest} trailing samples at rest set aside as the dwell" if s.rest else ""

    def notes(how: str) -> tuple[str, ...]:
        return (f"{s.where(source)}: {len(t)} samples over {T:.6g} s{rest}; derivatives from {how}; joint positions "
                "checked as given in the file",)

    if smoothing == "auto":
        from ..curves.sampled import noise_level

        smoothing = noise_level(t, pos) ** 2
    tool = s.tool
    if tool is not None and np.max(np.abs(tool[:, :3] - pos)) > TOOL_TOL:
        off = float(np.max(np.abs(tool[:, :3] - pos)))
        rest += f"; its x, y, z differ from FK of its joint positions by up to {off:.3g} m, so its tool columns are not used"
        tool = None
    if getattr(robot, "rotary", False):  # the tool angle θ = FK of the fourth axis, one more column
        pos = np.column_stack([pos, robot.tool_angle(s.q)])
    report, _ = _motion_report(t, pos, robot, profile, smoothing, source, notes, tool, not_held)
    others = []
    half = _half(len(t))
    if len(half) >= 6:
        # the septic Hermite through positions to jerks converges as h⁵ in the third derivative: its estimate's error
        # is the change when the rate halves over 2⁵ − 1, taken twice (HERMITE_DIVISOR); the splines of positions
        # alone are taken at the whole change (a jerk step they do not find rings however fine the samples)
        share = 1.0 / HERMITE_DIVISOR if tool is not None and not smoothing else 1.0
        others.append((_motion_report(t[half], pos[half], robot, profile, smoothing, source, None,
                                      None if tool is None else tool[half])[0], share))
    if smoothing:  # what the smoothing takes away is as uncertain as the rest: the interpolated data's peaks
        others.append((_motion_report(t, pos, robot, profile, 0.0, source)[0], 1.0))
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


#: the largest trajectory file ``check`` reads [bytes] (~600,000 rows of a 3-joint trajectory at 1 kHz; its
#: parse holds a few times this in memory): larger is one line, exit 1, never a swap storm
CHECK_MAX_BYTES = 64 << 20


def check_file(path: str | Path, profile: Profile, smoothing: float | str = 0.0,
               limit_use: float | None = None, notify=None, hold_capacity: bool = True) -> list[MoveCheck]:
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
            raw = sys.stdin.buffer.read(CHECK_MAX_BYTES + 1)
        else:  # (a named pipe: its writer awaited for a bounded time, saying so through ``notify``)
            from ..model.files import open_for_reading

            with open(open_for_reading(str(p), "trajectory", TaskError, notify=notify), "rb") as fh:
                raw = fh.read(CHECK_MAX_BYTES + 1)
    except OSError as exc:
        raise TaskError(f"{p}: cannot read: {exc.strerror}") from None
    if len(raw) > CHECK_MAX_BYTES:
        raise TaskError(f"{source}: larger than {CHECK_MAX_BYTES} bytes ({CHECK_MAX_BYTES >> 20} MiB), the most check "
                        "reads at once; split the file by move (e.g. one file per move column value)")
    from ..model.text import decode_text

    text = decode_text(raw, source, "a CSV trajectory", TaskError)
    robot = build_robot(profile.robot)
    not_held = "" if hold_capacity else "--no-hold-capacity"
    out = []
    for s in read_moves(text, source, robot.joint_names, robot.joint_units):
        out.append(MoveCheck(s.move, int(s.lines[0]), s.last_line,
                             check_samples(s, profile, smoothing, source, not_held).rated(profile.limit_use)))
    return out


def check_trajectory(path: str | Path, profile: Profile, smoothing: float = 0.0) -> LimitReport:
    """Limit report of the one move in CSV file ``path`` (a file of several moves: :func:`check_file`)."""
    checks = check_file(path, profile, smoothing)
    if len(checks) > 1:
        raise TaskError(f"{path}: {len(checks)} moves (a 'move' column); check_file checks each")
    return checks[0].report
