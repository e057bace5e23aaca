"""What ``check`` reads besides the model's own joint columns: the drive's view and the tables a kernel interpolates,
and whether a file's derivative columns agree with its positions.

* **The file's kind** (:func:`file_kind`) from its header's names: ``t`` and ``q1 … qn`` (the model's joints),
  ``t`` and the profile's drive names (``controller.joints``: ``plan --columns plc``, ``drive``, any CSV dialect, or a
  recording in those names and units), ``t``, ``dt`` and ``NAME``, ``NAME_vel`` (a PVT table), ``master``, ``NAME``,
  ``NAME_vel``, ``NAME_acc`` (a cam of XYVA points) or ``master`` and ``NAME`` (an equidistant cam table). Without
  ``controller.joints`` the tables' names are q1 … qn (as ``plan`` writes them then).
* **Drive units back to the joints:** q = d / (sign · k) + offset, q̇ = ḋ / (sign · k), q̈ = d̈ / (sign · k)
  (:class:`~pickplace_cli.export.drive.DriveMap`); a header unit other than the profile's label is refused.
* **Derivative columns** (:func:`derivative_problems`): the tool's ``vx … jz`` beside ``x, y, z`` are used only when
  each agrees with the column it is the derivative of, on the intervals between samples (trapezoidal rule with the
  Hermite end correction, exact for a quintic):
  velocity within ``AGREE[1]`` and acceleration within ``AGREE[2]`` of the interval's change on every interval, jerk
  within ``AGREE[3]`` on at least half of them (the jerk of a planned motion steps: on an interval across a step the
  rule is off by up to half the step), and a velocity or acceleration column not off by one factor everywhere
  (``SCALE_TOL``: a re-timed file's columns). Otherwise the file is judged from its positions.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass

import numpy as np

from ..model.errors import TaskError
from ..limits.samples import (AGREE, ORDER_COLUMNS, Samples, derivative_problems,  # noqa: F401
                              describe_problems)

#: fewest samples a move needs: a quintic spline has 6 coefficients
MIN_SAMPLES = 6
#: the tool's motion this tool's CSV writes beside the joints (m, m/s, m/s², m/s³): with all of them, and the
#: positions FK(q) within ``TOOL_TOL``, the motion between samples is the septic Hermite through them
TOOL_COLUMNS = ("x", "y", "z", "vx", "vy", "vz", "ax", "ay", "az", "jx", "jy", "jz")


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




@dataclass(frozen=True)
class Header:
    """The header line of a file: its 1-based line number, the separator, the cells as written and their bare names."""

    line: int
    sep: str
    cells: list[str]
    names: list[str]

    def unit(self, name: str) -> str:
        cell = self.cells[self.names.index(name)]
        return cell.split("[", 1)[1].rsplit("]", 1)[0].strip() if "[" in cell else ""


def read_header(text: str) -> Header | None:
    """The first line that is not blank or a ``#`` comment, as a :class:`Header` (None for an empty file)."""
    from .batch import sniff_delimiter

    for n, ln in enumerate(text.removeprefix("\ufeff").splitlines(), start=1):
        if ln.strip() and not ln.lstrip().startswith("#"):
            sep = sniff_delimiter(ln)
            cells = [c.strip().strip('"') for c in ln.split(sep)]
            return Header(n, sep, cells, [c.split("[")[0].strip() for c in cells])
    return None


#: the kinds of file ``check`` reads
KINDS = ("joints", "drive", "pvt", "cam", "cam-table")


def file_kind(head: Header, joint_names: tuple[str, ...], drive_names: tuple[str, ...] | None) -> str:
    """The kind of file a header names (module docstring): one of ``KINDS``; "joints" also when it fits none (the
    reader of the model's joints then says which column is missing)."""
    names = set(head.names)
    table_names = drive_names if drive_names is not None else joint_names
    if "t" in names and "dt" in names and all(n in names and f"{n}_vel" in names for n in table_names):
        return "pvt"  # (before the joints: without controller.joints a PVT table names them q1 … qn too)
    if "t" in names and set(joint_names) <= names:
        return "joints"
    if "master" in names and all(n in names for n in table_names):
        return "cam" if all(f"{n}_vel" in names and f"{n}_acc" in names for n in table_names) else "cam-table"
    if drive_names is not None and "t" in names and set(drive_names) <= names:
        return "drive"
    return "joints"


def _unit_check(head: Header, name: str, want: str, source: str) -> None:
    got = head.unit(name)
    if got not in ("", want):
        raise TaskError(f"{source}:{head.line}: column {name}[{got}]: the profile's controller.joints gives {name} in "
                        f"{want}; check reads it in {want} (a file in other units: give the profile that names them)")


def _rate_unit(head: Header, name: str, label: str, per: str, power: str, source: str) -> float:
    """The time unit [s] of a derivative column ``name`` of a ``label`` quantity: the header's ``label/s``,
    ``label/ms`` or ``label/us`` (with ``power`` "^2" for an acceleration); a column without a unit is per the
    master's unit ``per``. TaskError for any other unit."""
    got = head.unit(name)
    if got == "":
        return TIME_UNITS[per]
    for tu in ("s", "ms", "us", "µs"):
        if got == f"{label}/{tu}{power}":
            return TIME_UNITS[tu]
    raise TaskError(f"{source}:{head.line}: column {name}[{got}]: the profile's controller.joints gives {name} in "
                    f"{label}/{per}{power}; check reads it in {label} per s, ms or us{power and ' squared'} (a file in "
                    "other units: give the profile that names them)")


@dataclass(frozen=True)
class Table:
    """A table a kernel interpolates, in the model's joint units: ``kind`` (pvt, cam, cam-table), the points' times
    ``t`` (K,) [s], ``q``, ``qd``, ``qdd`` (K, n) [rad or m, per s, per s²] (``qd`` None for a cam-table, ``qdd`` None
    unless a cam) and the file ``lines`` (K,) of the points."""

    kind: str
    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray | None
    qdd: np.ndarray | None
    lines: np.ndarray


def read_table(text: str, source: str, kind: str, joint_names: tuple[str, ...], joint_units: tuple[str, ...],
               drive=None) -> Table:
    """The points of a ``kind`` table (pvt, cam, cam-table) as :func:`pickplace_cli.export.tables.table_columns`
    writes them, in drive units (``drive``, a DriveMap) or the model's; TaskError naming file, line, column and
    value of the first problem (a belt master, a time that does not increase, ``dt`` that disagrees with ``t``)."""
    head = read_header(text)
    names = list(drive.names) if drive is not None else list(joint_names)
    labels = list(drive.labels) if drive is not None else list(joint_units)
    tname = "t" if kind == "pvt" else "master"
    tunit = head.unit(tname)
    if tunit == "m":
        raise TaskError(f"{source}:{head.line}: column {tname}[m]: a belt master (belt travel since the detection); "
                        "check reads tables whose master is time [s] (plan --cam-master time)")
    if tunit not in TIME_UNITS:
        raise TaskError(f"{source}:{head.line}: column {head.cells[head.names.index(tname)]!r}: {tname} is read in s, "
                        f"ms or us (the header's unit {tunit!r} is not one of them)")
    k_t = TIME_UNITS[tunit]
    per = tunit or "s"
    k_vel, k_acc = [], []  # each derivative column's own time unit [s per unit]: plan --pvt-integer writes t[ms] and
    for name, label in zip(names, labels):  # velocities in counts/s
        _unit_check(head, name, label, source)
        if kind in ("pvt", "cam"):
            k_vel.append(_rate_unit(head, f"{name}_vel", label, per, "", source))
        if kind == "cam":
            k_acc.append(_rate_unit(head, f"{name}_acc", label, per, "^2", source))
    cols = [tname] + (["dt"] if kind == "pvt" else [])
    for name in names:
        cols += [name] + ([f"{name}_vel"] if kind in ("pvt", "cam") else []) + ([f"{name}_acc"] if kind == "cam" else [])
    idx = [head.names.index(c) for c in cols]
    rows, lines = [], []
    for n, ln in enumerate(text.removeprefix("\ufeff").splitlines(), start=1):
        if n <= head.line or not ln.strip() or ln.lstrip().startswith("#"):
            continue
        cells = _cells(ln, head.sep, source, n)
        row = []
        for c, i in zip(cols, idx):
            if i >= len(cells):
                raise TaskError(f"{source}:{n}: {c}: no value (the row has {len(cells)} cells, the header "
                                f"{len(head.cells)})")
            row.append(_number(cells[i], c, source, n, f"{i + 1}, {head.cells[i]!r}"))
        rows.append(row)
        lines.append(n)
    if len(rows) < 2:
        raise TaskError(f"{source}:{head.line}: {len(rows)} point(s) in a {kind} table; it needs at least 2")
    data = np.array(rows)
    lines_a = np.array(lines)
    t = data[:, 0] * k_t
    off = 2 if kind == "pvt" else 1
    if kind == "pvt":  # the drive runs the segment times dt: t must be their sum
        dt = data[:, 1] * (TIME_UNITS[head.unit("dt")] if head.unit("dt") in TIME_UNITS else 1.0)
        run = t[0] + np.concatenate([[0.0], np.cumsum(dt[1:])])
        bad = np.flatnonzero(np.abs(run - t) > 1e-9 * np.maximum(1.0, np.abs(t)) + 1e-12)
        if bad.size:
            k = int(bad[0])
            raise TaskError(f"{source}:{lines_a[k]}: dt = {dt[k]:.9g} s: t = {t[k]:.9g} s is not the previous point's "
                            f"t plus dt ({run[k]:.9g} s); the drive runs the segment times dt, so they must agree")
    step = np.diff(t)
    if np.any(step <= 0):
        k = int(np.flatnonzero(step <= 0)[0]) + 1
        raise TaskError(f"{source}:{lines_a[k]}: {tname} = {t[k]:.9g} s is not after the previous point's "
                        f"{t[k - 1]:.9g} s: a table's {tname} must increase strictly")
    width = {"pvt": 2, "cam": 3, "cam-table": 1}[kind]
    block = data[:, off:].reshape(len(t), len(names), width)
    scale = np.asarray(drive.scale) if drive is not None else np.ones(len(names))
    q = drive.joint_position(block[:, :, 0]) if drive is not None else block[:, :, 0].copy()
    qd = block[:, :, 1] / scale / np.asarray(k_vel) if width > 1 else None
    qdd = block[:, :, 2] / scale / np.asarray(k_acc) ** 2 if width > 2 else None
    return Table(kind, t, q, qd, qdd, lines_a)


#: points per piece of a table's drive motion at which check reads its joint positions (denser at the piece's ends)
SEGMENT_POINTS = 24


def joint_polynomial(table: Table, blend: float | None = None):
    """evaluate(x (M,) [s]) → q (M, n): the table as the drive interpolates it, cubic Hermite through (q, q̇) for PVT,
    the quintic through (q, q̇, q̈) for a cam, the straight lines read every ``blend`` [s] (the controller cycle) with
    each velocity step blended over that cycle for a cam-table: :func:`pickplace_cli.export.interpolate.rebuild`, the
    function ``plan`` judges its own tables by."""
    motion = table_motion(table, blend)
    return lambda x: motion(np.asarray(x, float))


def table_motion(table: Table, blend: float | None = None, ends: str = "hold"):
    """The drive's motion of ``table`` (:func:`pickplace_cli.export.interpolate.rebuild`; ``blend`` [s]: the
    controller cycle; ``ends``: "hold" or "continue" past the table's ends)."""
    from ..export.interpolate import rebuild

    return rebuild(table, blend, ends)


def tool_motion(table: Table, robot, blend: float | None = None, motion=None):
    """(evaluate(x, order) → (M, d) the tool's motion [m, m/s, …; with a rotary fourth axis the angle in rad as a
    fourth column], the interior breaks' times [s]) of a PVT, cam or cam-table table (``blend``: the controller cycle
    [s]) on ``robot``: solved from the drive's joint motion through the robot's own joint mapping
    (:func:`~pickplace_cli.limits.table.tool_motion`, as ``plan`` judges its tables) — exact, where a fit through the
    forward kinematics of a piece a few tens of µs long loses its third derivative to rounding (a cam-table on a
    50 µs cycle read 271 % of the torque rate that held). The motion's derivatives step at the breaks (a PVT's
    acceleration, a cam's jerk, a cam-table's acceleration at each blend's ends): the check takes both one-sided
    values there. ``motion``: the table's :func:`table_motion` when the caller has it already. The last times'
    solve is kept: the orders are asked for one after another at the same times."""
    from ..limits.table import tool_motion as solved

    motion = table_motion(table, blend) if motion is None else motion
    rotary = getattr(robot, "rotary", False)
    last: list = [None, None]

    def evaluate(xx: np.ndarray, order: int = 0) -> np.ndarray:
        xx = np.asarray(xx, float)
        if last[0] is None or last[0].shape != xx.shape or not np.array_equal(last[0], xx):
            last[0], last[1] = xx.copy(), solved(robot, *motion.all_orders(xx))
        out = last[1]
        return np.column_stack([out[order], out[4][order]]) if rotary else out[order]

    return evaluate, np.asarray(motion.breaks, float)[1:-1].copy()


#: the most points a table may have for ``check`` (each segment gets its own fit): as many as ``plan`` writes at most
MAX_POINTS = 200_000

#: one array of a table in Structured Text as ``plan --format pvt-st|cam-st|cam-table-st`` writes it (either dialect):
#: ``NAME : ARRAY[1..n] OF LREAL := [ (* column [unit]: words *) values ];`` (``OF DINT``: ``--pvt-integer``)
_ST_ARRAY = (r"(\w+)\s*:\s*ARRAY\s*\[\s*1\s*\.\.\s*(\d+)\s*\]\s*OF\s*(?:LREAL|DINT)\s*:=\s*\[\s*\(\*\s*([^*]*?)\*\)"
             r"([^\]]*)\]")


def st_table_text(text: str, source: str) -> str | None:
    """A table in Structured Text (``plan --format pvt-st|cam-st|cam-table-st``) as the CSV ``plan --format
    pvt|cam|cam-table`` writes (each array's comment names its column and unit); None when ``text`` is not one. Row
    k + 1 of the CSV is point k of the arrays."""
    import re

    if ":= [" not in text or not re.search(r"FB_Pickplace(Pvt|Cam|CamTable)\b|PP_(PVT|CAM|CAMTABLE)_", text):
        return None
    cols = []
    for name, count, comment, body in re.findall(_ST_ARRAY, text):
        head = comment.split(":", 1)[0].strip()
        values = [v.strip() for v in body.split(",") if v.strip()]
        if len(values) != int(count):
            raise TaskError(f"{source}: {name}: {len(values)} values for ARRAY[1..{count}]: a table's arrays must be "
                            "complete")
        cols.append((head.replace(" [", "["), values))
    if not cols or len({len(v) for _, v in cols}) != 1:
        raise TaskError(f"{source}: not a table plan writes in Structured Text (no arrays, or arrays of different "
                        "lengths)")
    rows = [",".join(c[0] for c in cols)]
    rows += [",".join(v[k] for _, v in cols) for k in range(len(cols[0][1]))]
    return "\n".join(rows) + "\n"


#: one array of a cam object (``plan -f cam-st|cam-table-st --cam-object codesys|twincat``), indexed from 0 or 1:
#: ``NAME : ARRAY[a..b] OF LREAL := [ (* words [unit] *) values ];``
_CAM_ARRAY = (r"(\w+)\s*:\s*ARRAY\s*\[\s*(\d+)\s*\.\.\s*(\d+)\s*\]\s*OF\s*LREAL\s*:=\s*\[\s*\(\*\s*([^*]*?)\*\)"
              r"([^\]]*)\]")
#: a cam object's array name suffix → the column plan -f cam|cam-table writes (the jerk column is not read)
_CAM_SUFFIX = {"_y": "", "_v": "_vel", "_a": "_acc"}


def cam_object_text(text: str, source: str) -> str | None:
    """A cam object program (``PRG_PickplaceCams`` of ``plan -f cam-st|cam-table-st --cam-object codesys|twincat``)
    as the CSV ``plan -f cam|cam-table`` writes: the master (``fMaster``, or for CODESYS's equidistant table the
    ``xStart`` … ``xEnd`` its points span equally), each joint's ``NAME_y``, ``NAME_v``, ``NAME_a`` arrays as
    ``NAME``, ``NAME_vel``, ``NAME_acc`` with the units their comments give; None when ``text`` is not one."""
    import re

    if "PROGRAM PRG_PickplaceCams" not in text:
        return None
    cols: list[tuple[str, list[str]]] = []
    master = None
    for name, lo, hi, comment, body in re.findall(_CAM_ARRAY, text):
        values = [v.strip() for v in body.split(",") if v.strip()]
        if len(values) != int(hi) - int(lo) + 1:
            raise TaskError(f"{source}: {name}: {len(values)} values for ARRAY[{lo}..{hi}]: a cam's arrays must be "
                            "complete")
        unit = comment.rsplit("[", 1)[1].split("]", 1)[0].strip() if "[" in comment else ""
        if name == "fMaster":
            master = (f"master[{unit}]", values)
            continue
        for suffix, column in _CAM_SUFFIX.items():
            if name.endswith(suffix):
                cols.append((f"{name[: -len(suffix)]}{column}[{unit}]", values))
    if master is None:  # CODESYS's SMC_CAMTable: equidistant points from xStart to xEnd
        ends = {k: (float(v), u) for k, v, u in re.findall(
            r"\b(xStart|xEnd)\s*:\s*LREAL\s*:=\s*([^;]+);\s*\(\*[^\[]*\[([^\]]*)\]", text)}
        if set(ends) != {"xStart", "xEnd"} or not cols:
            raise TaskError(f"{source}: a cam object without its master (no fMaster array, no xStart and xEnd)")
        x = np.linspace(ends["xStart"][0], ends["xEnd"][0], len(cols[0][1]))
        master = (f"master[{ends['xStart'][1]}]", [repr(float(v)) for v in x])
    cols.insert(0, master)
    if len(cols) < 2 or len({len(v) for _, v in cols}) != 1:
        raise TaskError(f"{source}: not a cam object plan writes (no slave arrays, or arrays of different lengths)")
    rows = [",".join(c[0] for c in cols)]
    rows += [",".join(v[k] for _, v in cols) for k in range(len(cols[0][1]))]
    return "\n".join(rows) + "\n"


def json_samples_text(text: str, source: str) -> str | None:
    """The samples of ``plan -f json`` (``{"columns": [...], "samples": {column: [values]}}``) as the CSV ``plan``
    writes (the same columns and values); None when ``text`` is not a JSON document; TaskError for a JSON document
    without them."""
    import json

    if not text.lstrip().startswith(("{", "[")):
        return None
    try:
        doc = json.loads(text)
    except ValueError as exc:
        raise TaskError(f"{source}: not valid JSON ({exc}); check reads CSV, Structured Text and plan's JSON") from None
    cols = doc.get("columns") if isinstance(doc, dict) else None
    data = doc.get("samples") if isinstance(doc, dict) else None
    if not (isinstance(cols, list) and cols and isinstance(data, dict) and all(c in data for c in cols)):
        raise TaskError(f"{source}: a JSON document without plan's 'columns' and 'samples' (plan -f json writes them); "
                        "check reads CSV, Structured Text and plan's JSON")
    values = [data[c] for c in cols]
    if any(not isinstance(v, list) for v in values) or len({len(v) for v in values}) != 1:
        raise TaskError(f"{source}: samples: every column must be a list of the same length")
    rows = [",".join(str(c) for c in cols)]
    rows += [",".join(repr(v[k]) if not isinstance(v[k], str) else v[k] for v in values) for k in range(len(values[0]))]
    return "\n".join(rows) + "\n"


def read_checked(text: str, source: str, profile, robot):
    """What ``check`` judges in a file: ("samples", [Samples …]) of a file of joint or drive positions (drive units
    converted to the model's), ("table", Table) of a PVT, cam or equidistant cam table, each with the name its messages give the file (a table in Structured Text says how its lines count);
    TaskError naming the file, line and rule for a file without a header or without the columns needed."""
    from dataclasses import replace

    from ..export.drive import drive_map

    drive = drive_map(profile)
    js = json_samples_text(text, source)
    if js is not None:  # plan -f json: its samples as the CSV plan writes
        text, source = js, f"{source} (JSON; line k + 1 is sample k)"
    st = st_table_text(text, source)
    if st is None:
        st = cam_object_text(text, source)
    if st is not None:  # the same table in Structured Text: its arrays as CSV columns (line k + 1 = point k)
        text, source = st, f"{source} (Structured Text; line k + 1 is point k)"
    head = read_header(text)
    if head is not None and all(_is_number(c) for c in head.cells):
        raise TaskError(f"{source}:{head.line}: no header line (the tsv dialect writes none): check needs a header "
                        f"naming t and the joints q1 … qn" + (f" or the profile's drives {', '.join(drive.names)}"
                                                               if drive is not None else ""))
    if head is not None:
        _refuse_twice_named(head, source)
    kind = file_kind(head, robot.joint_names, drive.names if drive is not None else None) if head else "joints"
    if kind == "joints" and head is not None and drive is not None and set(drive.names) <= set(head.names):
        moves = read_moves(text, source, robot.joint_names, robot.joint_units)
        _drives_agree(moves, read_moves(text, source, drive.names, drive.labels), drive, source, robot.joint_names)
        return "samples", moves, source
    if kind == "joints":
        names = set(head.names) if head is not None else set()
        if head is not None and drive is not None and not names & set(robot.joint_names):
            lack = [c for c in ("t", *robot.joint_names) if c not in names]
            lack_d = [c for c in ("t", *drive.names) if c not in names]
            raise TaskError(f"{source}:{head.line}: header lacks column(s) {', '.join(lack)} (the joints) and "
                            f"{', '.join(lack_d)} (the profile's drives); need t and q1 … qn, or t and the drives' "
                            f"columns; found {', '.join(head.names)}")
        return "samples", read_moves(text, source, robot.joint_names, robot.joint_units), source
    if kind == "drive":
        moves = read_moves(text, source, drive.names, drive.labels)
        return "samples", [replace(m, q=drive.joint_position(m.q)) for m in moves], source
    table = read_table(text, source, kind, robot.joint_names, robot.joint_units, drive)
    if kind == "cam-table" and len(table.t) < 2:
        raise TaskError(f"{source}: {len(table.t)} point in a cam-table; a table needs at least 2")
    return "table", table, source


def _refuse_twice_named(head: Header, source: str) -> None:
    """TaskError for a header that names a column twice (``q1[rad]`` and ``q1[rad]``, or ``q1[rad]`` and
    ``q1[deg]``): which one the motion is would be a guess."""
    seen: dict[str, int] = {}
    for i, name in enumerate(head.names):
        if not name:
            continue
        if name in seen:
            raise TaskError(f"{source}:{head.line}: column {name!r} is named twice (columns {seen[name] + 1} and {i + 1}: "
                            f"{head.cells[seen[name]]!r}, {head.cells[i]!r}); check reads each quantity from one "
                            "column: drop or rename one")
        seen[name] = i


#: a drive column agrees with its joint's when they differ by at most half of each column's last digit (half a count
#: for counts, half a µm for mm to 3 decimals, …: :func:`_last_digit`) plus this share of the joint's value
DRIVE_AGREE = 1e-9


def _last_digit(col: np.ndarray) -> float:
    """The step of a column's last written digit: the largest 10⁻ᵈ (d = 0 … 12) whose multiples all its values are,
    else the 12th significant digit of its largest value."""
    col = np.asarray(col, float)
    big = max(float(np.max(np.abs(col))), 1e-300)
    for d in range(13):
        step = 10.0 ** -d
        if np.all(np.abs(col / step - np.round(col / step)) <= 1e-6):
            return step
    return 10.0 ** (np.floor(np.log10(big)) - 11)


def _drives_agree(moves: list, drives: list, drive, source: str, joint_names: tuple[str, ...]) -> None:
    """TaskError when a file that holds both the model's joints and the profile's drives (``plan --columns
    t,q?,drive``) has a drive column that is not its joint converted by ``controller.joints`` (q = d / (sign · k) +
    offset): the joints are what ``check`` judges, the drive runs its own column."""
    for m, d in zip(moves, drives):
        got = drive.joint_position(d.q)
        for j, name in enumerate(drive.names):
            col = d.q[:, j]
            tol = (0.5 * _last_digit(col) / abs(drive.scale[j]) + 0.5 * _last_digit(m.q[:, j])
                   + DRIVE_AGREE * max(1.0, float(np.max(np.abs(m.q[:, j])))))
            off = np.abs(got[:, j] - m.q[:, j])
            if np.max(off) > tol:
                k = int(np.argmax(off))
                raise TaskError(f"{source}:{m.lines[k]}: {name} = {col[k]:.12g} {drive.labels[j]} is not "
                                f"{joint_names[j]} = {m.q[k, j]:.12g} converted by "
                                f"the profile's controller.joints (it gives {got[k, j]:.12g}; off by {off[k]:.3g}, "
                                f"allowed {tol:.3g}): check judges the joints, the drive runs its own column: write one "
                                "of them, or the same motion in both")


def _is_number(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return False
    return True


def pvt_acceleration_steps(table: Table) -> np.ndarray:
    """Per joint: the largest step of the acceleration [rad/s² or m/s²] at a PVT table's interior points (the cubic
    Hermite is C¹: its acceleration at the end of one segment, (−6Δq/h + 2q̇₀ + 4q̇₁)/h, and at the start of the next,
    (6Δq/h − 4q̇₀ − 2q̇₁)/h, differ); zeros for fewer than 3 points."""
    if len(table.t) < 3:
        return np.zeros(table.q.shape[1])
    h = np.diff(table.t)[:, None]
    dq = np.diff(table.q, axis=0)
    v0, v1 = table.qd[:-1], table.qd[1:]
    start = (6 * dq / h - 4 * v0 - 2 * v1) / h
    end = (-6 * dq / h + 2 * v0 + 4 * v1) / h
    return np.abs(start[1:] - end[:-1]).max(axis=0)

