"""Many moves from one CSV, planned in one process (``pickplace plan --batch FILE|-``).

Input: a header row, then one move per row. Required columns ``from_x, from_y, from_z, to_x, to_y, to_z``
[m, base frame]; optional ``height`` [m], ``eta`` [-], ``v_from_x … v_from_z``, ``v_to_x … v_to_z``
[m/s], ``time`` [s, or a rule: "limits", "auto", "fit", "optimal", any case] and ``limit_use`` [fraction of every
timed limit's rating, (0, 1]]. An empty optional cell takes the command-line/profile value.
Blank lines and lines starting with ``#`` are skipped. Rows are numbered from 1 (the first data row),
which is the number every message and the output's ``move`` column use. The cells may be separated by
``,``, ``;`` or a tab (:func:`sniff_delimiter`, as ``pickplace check`` reads), the decimal mark is ``.``,
and a UTF-8 byte-order mark before the header (Excel's "CSV UTF-8") is ignored. A header with no move
after it is an error.

A row that cannot be planned is a result (``RowResult.error``), not an exception: the batch goes on
(unless the caller stops at the first failure) and the exit code is the worst of all rows.
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass
from typing import IO, Any, Iterator

from ..model.errors import PickplaceError, TaskError
from ..model.text import plain_float, quoted, utf16_hint

REQUIRED = ("from_x", "from_y", "from_z", "to_x", "to_y", "to_z")
#: a belt row of a plain batch (no ``t_detect``): the part was at ``to`` [m] when detected and moves at
#: ``to_belt_v*`` [m/s]; the move starts ``latency`` [s, >= 0] after the detection (as ``--to-belt``/``--latency``)
BELT = ("to_belt_vx", "to_belt_vy", "to_belt_vz")
#: the tool angle about the base z axis at the ends [rad] (a profile with a rotary fourth axis; both or neither)
ANGLES = ("from_theta", "to_theta")
OPTIONAL = ("height", "eta", "v_from_x", "v_from_y", "v_from_z", "v_to_x", "v_to_y", "v_to_z", "time", *BELT, "latency",
            *ANGLES, "limit_use")
#: a belt schedule (a ``t_detect`` column; :mod:`~pickplace_cli.pipelines.schedule`): one detected part per row — where it
#: was seen [m], the belt velocity [m/s], the detection time stamp [s] and where to place it [m]; optional
#: ``latency`` [s, >= 0] (earliest move start after the detection), ``height`` [m], ``eta``, ``time``, and
#: ``from_x … from_z`` [m] on row 1 only (where the robot starts; later moves start where the previous ended)
SCHEDULE_REQUIRED = ("to_x", "to_y", "to_z", "to_belt_vx", "to_belt_vy", "to_belt_vz", "t_detect",
                     "place_x", "place_y", "place_z")
SCHEDULE_OPTIONAL = ("latency", "height", "eta", "time", "from_x", "from_y", "from_z", "to_theta", "place_theta",
                     "from_theta", "limit_use")


@dataclass(frozen=True)
class BatchRow:
    """One input row: its number (1 = first data row), line in the file, and parsed values (SI)."""

    row: int
    line: int
    values: dict[str, Any]


@dataclass(frozen=True)
class RowResult:
    """The outcome of one row: a plan, or an error with its exit code (1 input, 3 limit, 4 unreachable).
    ``error`` is one line per problem ("row N (FILE:LINE): …"): a row that exceeds several limits has
    several lines, one per exceeded limit."""

    row: int
    plan: Any = None
    error: str | None = None
    code: int = 0
    text: str | None = None  # the plan's CSV rows, when formatted in a worker (see plan_rows_parallel)


#: cell separators a batch or a checked trajectory may use (spreadsheets write ';' where ',' is the decimal mark)
DELIMITERS = (",", ";", "\t")


def sniff_delimiter(header: str) -> str:
    """The cell separator of a CSV file from its header line: the most frequent of ``,`` ``;`` and tab
    (``,`` on a tie or when there is none). Shared by the batch reader and ``pickplace check``."""
    counts = [header.count(d) for d in DELIMITERS]
    best = max(counts)
    return DELIMITERS[counts.index(best)] if best else ","


def unresolved_text(r) -> str:
    """The one line that says a peak is not resolved by the samples (a LimitRow within its limit whose accuracy is
    worse than 1 % of it: ``check --strict``, ``plan --strict``)."""
    from ..limits.report import percent

    return (f"not resolved: {r.joint} {r.quantity} = {r.peak:.4g} ± {r.accuracy:.2g} {r.unit} "
            f"({percent(r.utilisation)} % ± {percent(r.accuracy / abs(r.limit))} % of {r.limit:.4g} {r.unit})")


def violation_text(r) -> str:
    """The one line that says a limit is exceeded (a :class:`~pickplace_cli.limits.report.LimitRow` that is not
    ok), as a single plan and every batch row print it: joint, quantity, peak [unit], when (t [s] or the
    duty cycle), limit, excess and utilisation, e.g. ``limit exceeded: q1 motor torque = 2.584 N·m at
    t = 0.0479 s; limit 2 N·m (by 0.584 N·m, 129.2 %)``."""
    from ..limits.report import percent

    when = (f" at t = {r.t_peak:.4f} s" if r.t_peak is not None else
            " (peak of the move)" if r.quantity.startswith("capacity") else " over the duty cycle")
    head = "limit exceeded"
    if r.not_held:  # reported, not judged: the rule leaves this limit out (the Cartesian capacity under fit)
        head = f"limit exceeded, not held under {r.not_held}"
    # a reading the samples do not resolve (check): its accuracy said beside the excess
    vague = "" if r.accuracy is None or r.resolved else (
        f"; not resolved by the samples (± {percent(r.accuracy / abs(r.limit))} %)")
    if r.target < 1.0:  # headroom: the allowed use of the rating
        return (
            f"{head}: {r.joint} {r.quantity} = {r.peak:.4g} {r.unit}{when}; {percent(r.utilisation)} % of the "
            f"rated {r.limit:.4g} {r.unit}, above the limit use of {percent(r.target)} % (by {abs(r.excess):.4g} {r.unit})"
            f"{vague}"
        )
    return (
        f"{head}: {r.joint} {r.quantity} = {r.peak:.4g} {r.unit}{when}; "
        f"limit {r.limit:.4g} {r.unit} (by {abs(r.excess):.4g} {r.unit}, {percent(r.utilisation)} %){vague}"
    )


#: the longest line a batch may have [characters]: a row is one move, a few hundred characters; a longer line
#: (a binary file, a file with no line breaks) is one error line, never a read of the whole input into memory
BATCH_MAX_LINE = 1 << 16


def iter_batch(stream: IO[str], source: str = "batch", info: dict | None = None) -> Iterator[BatchRow | RowResult]:
    """Parse the batch CSV lazily, one line at a time: a :class:`BatchRow` per good row, a :class:`RowResult`
    (with its error) per row that failed to parse, each as soon as its line is read (a pipe is answered row
    by row). A bad header, a header with no row after it (at the end of the input), a line longer than
    :data:`BATCH_MAX_LINE`, a NUL byte or text that is not UTF-8 raise TaskError naming the line. ``info``
    (a dict) receives ``columns`` and ``schedule`` (a ``t_detect`` column: a belt schedule) once the header
    is read, i.e. before the first row is yielded."""
    header: list[str] | None = None
    required: tuple = REQUIRED
    header_line = 0
    sep = ","
    number = 0
    line = 0
    while True:
        try:
            text = stream.readline(BATCH_MAX_LINE + 1)
        except UnicodeDecodeError:
            raise TaskError(f"{source}:{line + 1}: not UTF-8 text (a binary file?); a batch is a CSV file") from None
        except BrokenPipeError:
            raise
        except OSError as exc:  # a device or special file that fails to read (EIO …)
            raise TaskError(f"{source}:{line + 1}: cannot read: {exc.strerror or exc}") from None
        if text == "":
            break
        line += 1
        if len(text) > BATCH_MAX_LINE and not text.endswith(("\n", "\r")):
            raise TaskError(f"{source}:{line}: a line of more than {BATCH_MAX_LINE} characters; a batch row is one "
                            "move (a binary file, or no line breaks?)")
        if "\0" in text:
            raise TaskError(f"{source}:{line}: a binary file (NUL bytes), not a CSV batch{utf16_hint(text)}")
        if not text.isascii():
            try:  # bytes the reader kept as surrogates (errors="surrogateescape"): this line is not UTF-8
                text.encode("utf-8")
            except UnicodeEncodeError:
                raise TaskError(f"{source}:{line}: not UTF-8 text (a binary file?); a batch is a CSV file") from None
        text = text.rstrip("\r\n")
        if line == 1:
            text = text.removeprefix("\ufeff")  # a BOM (the CLI opens files as utf-8-sig; stdin keeps it)
        if not text.strip() or text.lstrip().startswith("#"):
            continue
        if header is None:
            header_line = line
            sep = sniff_delimiter(text)
            header = _header(text, sep, source, line)
            required = SCHEDULE_REQUIRED if "t_detect" in header else REQUIRED
            if info is not None:
                info.update(columns=list(header), schedule="t_detect" in header)
            continue
        number += 1
        yield _row(number, line, text, header, sep, source, required)
    if header is None:
        raise TaskError(f"{source}: no header row (need columns {', '.join(REQUIRED)})")
    if number == 0:
        raise TaskError(
            f"{source}:{header_line}: no moves after the header (need one row per move with {', '.join(REQUIRED)})"
        )


#: the dimensionless columns: unit ``1`` (also written ``[-]`` or ``[]``)
DIMENSIONLESS = ("eta", "limit_use")


def _unit_of(name: str) -> str:
    """The SI unit of a batch column (``1`` for η and limit_use), as a header may write it: ``from_x[m]``,
    ``time[s]``, ``limit_use[1]``."""
    if name in DIMENSIONLESS:
        return "1"
    if name in ("time", "latency", "t_detect"):
        return "s"
    if name.endswith("_theta"):
        return "rad"
    if name.startswith(("v_from_", "v_to_", "to_belt_v")):
        return "m/s"
    return "m"


def _without_unit(name: str, source: str, line: int) -> str:
    """A header name with its unit in brackets (``from_x[m]``, the tool's own CSV style) as the bare name; a known
    column with another unit is a TaskError naming the unit it takes (values are read in SI units only)."""
    if not name.endswith("]") or "[" not in name:
        return name
    base, unit = name[:-1].split("[", 1)
    base, unit = base.strip(), unit.strip()
    if base not in REQUIRED + OPTIONAL + SCHEDULE_REQUIRED + SCHEDULE_OPTIONAL:
        return name  # an unknown column: reported as such, with its text
    if unit != _unit_of(base) and not (base in DIMENSIONLESS and unit in ("", "-")):
        raise TaskError(f"{source}:{line}: column {name!r}: {base} is read in {_unit_of(base)} "
                        f"(write {base} or {base}[{_unit_of(base)}])")
    return base


def _header(text: str, sep: str, source: str, line: int) -> list[str]:
    try:
        names = next(csv.reader([text], delimiter=sep))
    except csv.Error as exc:  # (a guard: see _row)
        raise TaskError(f"{source}:{line}: the header is not a CSV row: {exc}") from None
    header = [_without_unit(h.strip(), source, line) for h in names]
    schedule = "t_detect" in header
    required, optional = (SCHEDULE_REQUIRED, SCHEDULE_OPTIONAL) if schedule else (REQUIRED, OPTIONAL)
    unknown = [h for h in header if h not in required + optional]
    if unknown and not schedule and unknown[0] in SCHEDULE_REQUIRED + SCHEDULE_OPTIONAL:
        raise TaskError(
            f"{source}:{line}: column {unknown[0]!r} belongs to a belt schedule, which needs a t_detect column "
            f"(detection time stamp, s) and the columns {', '.join(SCHEDULE_REQUIRED)}"
        )
    if unknown:
        what = "a belt schedule's" if schedule else "the"
        raise TaskError(
            f"{source}:{line}: column {unknown[0]!r} is not known; {what} columns are {', '.join(required + optional)}"
        )
    if not schedule:
        belt = [h for h in BELT if h in header]
        if belt and len(belt) < 3:
            raise TaskError(f"{source}:{line}: column {next(h for h in BELT if h not in header)!r} is missing (a belt "
                            f"row gives the belt velocity as {', '.join(BELT)}, m/s)")
        if "latency" in header and not belt:
            raise TaskError(f"{source}:{line}: column 'latency' needs the belt columns {', '.join(BELT)} (m/s), or a "
                            "t_detect column for a belt schedule")
        angles = [h for h in ANGLES if h in header]
        if len(angles) == 1:
            raise TaskError(f"{source}:{line}: column {angles[0]!r} without "
                            f"{next(h for h in ANGLES if h != angles[0])!r}: the tool angle (rad) is given at both ends")
        if belt and any(h in header for h in ("v_to_x", "v_to_y", "v_to_z")):
            raise TaskError(f"{source}:{line}: columns v_to_* and to_belt_v* both give the end velocity: a belt row "
                            "arrives with the belt's")
    missing = [h for h in required if h not in header]
    if missing:
        what = "a belt schedule (t_detect) requires" if schedule else "required:"
        raise TaskError(f"{source}:{line}: column {missing[0]!r} is missing ({what} {', '.join(required)})")
    dup = sorted({h for h in header if header.count(h) > 1})
    if dup:
        raise TaskError(f"{source}:{line}: column {dup[0]!r} appears twice")
    return header


def _row(number: int, line: int, text: str, header: list[str], sep: str, source: str,
         required: tuple = REQUIRED) -> BatchRow | RowResult:
    try:
        try:
            if not text or '"' in text or "\0" in text or "\r" in text or "\n" in text:  # quoting, what csv refuses
                cells = [c.strip() for c in next(csv.reader([text], delimiter=sep))]
            else:  # what csv.reader gives a line without quotes, without its per-call cost (issue 16's latency)
                cells = [c.strip() for c in text.split(sep)]
        except csv.Error as exc:  # (a line is split at \r and \n before it gets here; this is a guard)
            raise TaskError(f"not a CSV row: {exc}") from None
        if len(cells) != len(header):
            raise TaskError(f"has {len(cells)} cells, the header has {len(header)}")
        values: dict[str, Any] = {}
        for name, cell in zip(header, cells):
            if cell == "":
                if name in required:
                    unit = {"t_detect": "seconds"}.get(name, "m/s" if name.startswith("to_belt") else "metres")
                    raise TaskError(f"{name} is empty: give a number in {unit}")
                continue
            if name == "time" and not cell[:1].isdigit() and cell[:1] not in "+-.":  # a rule's name (any case)
                from ..timing import parse_time

                values[name] = parse_time(cell)  # TaskError with the nearest name for a near miss
                continue
            try:
                x = plain_float(cell)
            except ValueError:
                hint = " (the decimal mark is '.')" if "," in cell and sep != "," else ""
                if "_" in cell or not cell.isascii():
                    hint += " (plain ASCII digits: no '_' separators, no other scripts' or full-width digits)"
                if name == "time":
                    hint += "; give seconds, or limits, auto, fit or optimal"
                raise TaskError(f"{name} = {quoted(cell)}: not a number{hint}") from None
            if not math.isfinite(x):
                raise TaskError(f"{name} = {quoted(cell)}: must be finite")
            if name == "latency" and x < 0:
                raise TaskError(f"latency = {quoted(cell)}: must be >= 0 s (the earliest move start after the detection)")
            if name == "limit_use":
                from ..model.headroom import check_limit_use

                try:
                    check_limit_use(x)
                except PickplaceError as exc:
                    raise TaskError(str(exc)) from None
            values[name] = x
        return BatchRow(number, line, values)
    except TaskError as exc:
        return RowResult(number, error=f"row {number} ({source}:{line}): {exc}", code=exc.exit_code)


def read_batch(stream: IO[str], source: str = "batch") -> tuple[list[BatchRow], list[RowResult]]:
    """Parse the whole batch CSV → (good rows, rows that failed to parse) (:func:`iter_batch`)."""
    rows: list[BatchRow] = []
    bad: list[RowResult] = []
    for item in iter_batch(stream, source):
        (rows if isinstance(item, BatchRow) else bad).append(item)
    return rows, bad


def row_task(values: dict, profile, height: float | None = None, eta: float | None = None):
    """The Task of one batch row: its cells, else ``height``/``eta`` (the command line), else the profile's
    planning defaults; end velocities [m/s] default to 0. TaskError for an invalid move."""
    from ..model.task import Task

    v = values
    _check_row_units(v, profile)
    return Task(
        [v["from_x"], v["from_y"], v["from_z"]],
        [v["to_x"], v["to_y"], v["to_z"]],
        v.get("height", height if height is not None else profile.planning.height),
        v.get("eta", eta if eta is not None else profile.planning.eta),
        v_from=[v.get("v_from_x", 0.0), v.get("v_from_y", 0.0), v.get("v_from_z", 0.0)],
        v_to=[v.get("v_to_x", 0.0), v.get("v_to_y", 0.0), v.get("v_to_z", 0.0)],
        theta_from=v.get("from_theta"), theta_to=v.get("to_theta"),
    )


def _check_row_units(v: dict, profile) -> None:
    """TaskError for a row's point or height in millimetres (the rules of ``plan``'s options,
    :mod:`pickplace_cli.model.plausible`): the cells named, with the values in metres."""
    from ..model.plausible import millimetre_height, millimetre_point

    for end in ("from", "to"):
        p = [v[f"{end}_x"], v[f"{end}_y"], v[f"{end}_z"]]
        found = millimetre_point(p, profile)
        if found is not None:
            mm, where = found
            raise TaskError(f"{end}_x,{end}_y,{end}_z = {','.join(f'{c:g}' for c in p)}: {where} of profile "
                            f"{profile.name}: millimetres meant? in metres: {','.join(f'{c:g}' for c in mm)} "
                            "(coordinates are in m)")
    if "height" in v:
        tall = millimetre_height(v["height"], profile)
        if tall is not None:
            raise TaskError(f"height = {v['height']:g} m: more than the workcell of profile {profile.name} is tall "
                            f"({tall:g} m): millimetres meant? {v['height'] / 1000:g} (the height is in m)")


def plan_rows(
    rows: list[BatchRow], profile, options, height: float | None = None, eta: float | None = None,
    fail_fast: bool = False, source: str = "batch",
) -> Iterator[RowResult]:
    """Plan every row (in order); yields one RowResult per row. ``options`` is a PlanOptions template:
    a row's ``time`` replaces its duration. Stops after the first failing row when ``fail_fast``."""
    from dataclasses import replace

    from ..planner import plan

    for r in rows:
        v = r.values
        try:
            if any(c in v for c in BELT):
                result = _plan_belt_row(r, profile, options, height, eta, source)
            else:
                task = row_task(v, profile, height, eta)
                opts = replace(options, time=v["time"]) if "time" in v else options
                if "limit_use" in v:
                    opts = replace(opts, limit_use=v["limit_use"])
                result = plan(task, profile, opts)
            code = result.report.exit_code()
            err = None
            if code:  # every exceeded limit, one line each, in the single plan's words
                said = ([violation_text(x) for x in result.report.violations]  # (strict: a peak not resolved)
                        or [unresolved_text(x) for x in result.report.unresolved])
                err = "\n".join(f"row {r.row} ({source}:{r.line}): {line}" for line in said)
            yield RowResult(r.row, result, err, code)
        except PickplaceError as exc:
            yield RowResult(r.row, None, f"row {r.row} ({source}:{r.line}): {exc}", exc.exit_code)
            code = exc.exit_code
        except Exception as exc:  # noqa: BLE001 - a row's failure is that row's answer, never the batch's end
            code = 1
            yield RowResult(r.row, None, f"row {r.row} ({source}:{r.line}): {unexpected_failure(exc, v, options.time, options.rate or profile.planning.rate)}", code)
        if fail_fast and code:
            return


def unexpected_failure(exc: Exception, values: dict, time, rate: float) -> str:
    """The words for a row that failed in a way no check foresaw: out of memory (with the trajectory's size when the
    row gives its duration), or an internal error named by its type."""
    if isinstance(exc, MemoryError):
        t = values.get("time", time)
        size = ""
        if isinstance(t, (int, float)) and rate:
            size = f" ({t:g} s at {rate:g} Hz: {t * rate + 1:,.0f} samples of every column)"
        return (f"out of memory planning this move{size}; plan it alone, at a lower --rate, or with more memory "
                "(a batch holds one row's trajectory at a time)")
    detail = " ".join(str(exc).split())[:200]
    return f"internal error ({type(exc).__name__}: {detail}); this row was not planned"


def _plan_belt_row(r: BatchRow, profile, options, height, eta, source: str):
    """A plain batch's belt row: the conveyor rendezvous of ``--to-belt`` (bspline-vel) with its tracking segment
    (:func:`~pickplace_cli.pipelines.tracking.plan_belt_move`). TaskError for a partial belt velocity or a
    method that cannot meet a moving part."""
    import numpy as np

    from ..paths import Method
    from .rendezvous import Part
    from .tracking import plan_belt_move

    v = r.values
    missing = [c for c in BELT if c not in v]
    if missing:
        raise TaskError(f"{missing[0]} is empty: a belt row gives all of {', '.join(BELT)} (m/s), a fixed end none")
    if Method(options.method) not in (Method.bspline, Method.bspline_vel):
        raise TaskError(f"to_belt_v* = ({', '.join(f'{v[c]:g}' for c in BELT)}) m/s: method "
                        f"{Method(options.method).value} plans moves from rest to rest; a belt row is planned by bspline-vel")
    part = Part(np.array([v["to_x"], v["to_y"], v["to_z"]]), np.array([v[c] for c in BELT]),
                v.get("latency", 0.0), angle=v.get("to_theta"))
    v_from = np.array([v.get(f"v_from_{c}", 0.0) for c in "xyz"])
    from ..model.headroom import apply_limit_use

    profile = apply_limit_use(profile, v.get("limit_use", options.limit_use))
    return plan_belt_move(np.array([v["from_x"], v["from_y"], v["from_z"]]), part, profile, v.get("time", options.time),
                          v.get("height", height), v.get("eta", eta), v_from, options.rate, v.get("from_theta"),
                          options.turn, options.turn_during, cycle=options.cycle)


@dataclass(frozen=True)
class PlanRecord:
    """The picklable part of a Plan (samples, joint motion, limit report, summary) — what a worker process
    sends back. It has the attributes every writer and :mod:`~pickplace_cli.pipelines.timeline` use."""

    t: Any
    p: Any
    v: Any
    a: Any
    j: Any
    joint: Any
    report: Any
    summary_doc: dict
    cycle: Any = None  # timing.cycle.CycleRounding of a plan on a controller's cycle

    def summary(self) -> dict:
        return dict(self.summary_doc)

    @classmethod
    def of(cls, plan) -> "PlanRecord":
        return cls(plan.t, plan.p, plan.v, plan.a, plan.j, plan.joint, plan.report, plan.summary(),
                   getattr(plan, "cycle", None))


def _plan_chunk(args) -> list[RowResult]:
    """Worker: plan a chunk of rows (no fail-fast inside a chunk; the parent stops in order). With a CSV
    dialect, the rows of every plan that will be written are formatted here too (formatting costs as much
    as planning, so it is worth spreading)."""
    from ..lookup.executors import stopped

    rows, profile, options, height, eta, source, csv_dialect, format_failed = args
    out = []
    if stopped():  # (a chunk queued before the parent stopped: not started)
        return out
    for r in plan_rows(rows, profile, options, height, eta, False, source):
        if stopped():  # the parent no longer wants the answers
            break
        text = None
        if csv_dialect is not None and r.plan is not None and (r.code == 0 or (format_failed and r.code == 3)):
            from ..export.csv import csv_rows

            text = csv_rows(r.plan, csv_dialect, move=r.row)
        out.append(RowResult(r.row, None if r.plan is None else PlanRecord.of(r.plan), r.error, r.code, text))
    return out


def plan_rows_parallel(
    rows: list[BatchRow], profile, options, height: float | None = None, eta: float | None = None,
    fail_fast: bool = False, source: str = "batch", workers: int = 2, chunk: int = 25,
    csv_dialect: str | None = None, format_failed: bool = False,
) -> Iterator[RowResult]:
    """:func:`plan_rows` on ``workers`` processes, chunks of ``chunk`` rows, results in row order (the
    plans come back as :class:`PlanRecord`). The same numbers as the sequential planner (same code).
    ``csv_dialect``: also format each written plan's CSV rows in the worker (``RowResult.text``; rows whose
    limits fail only when ``format_failed``)."""
    if workers <= 1 or len(rows) <= chunk:
        yield from plan_rows(rows, profile, options, height, eta, fail_fast, source)
        return
    chunks = [rows[i : i + chunk] for i in range(0, len(rows), chunk)]
    yield from run_chunks_in_order(
        _plan_chunk, [(c, profile, options, height, eta, source, csv_dialect, format_failed) for c in chunks],
        workers, fail_fast,
    )


def run_chunks_in_order(fn, args: list, workers: int, fail_fast: bool) -> Iterator[RowResult]:
    """``fn(a)`` → list of RowResult for every ``a`` of ``args`` on a process pool of ``workers``; yields the
    results in the order of ``args`` (and within each list), stops after the first failing row when
    ``fail_fast`` and cancels the chunks not started yet."""
    import multiprocessing

    from ..lookup.executors import local_pool

    # the workers leave Ctrl-C (SIGINT to the terminal's whole process group) to this process: it cancels the chunks
    # not started and sets ``stop``, and the running ones return after their current row, without a traceback from
    # each (it waited for each running chunk to the end: 7 s for 25 time-optimal plans on 4 workers of 2 cores); a
    # reader that goes away (the generator closed: ``… --json | head -1``) sets ``stop`` too
    stop = multiprocessing.get_context().Event()
    with local_pool(workers, stop) as pool:
        futures = [pool.submit(fn, a) for a in args]
        try:
            for fut in futures:
                for res in fut.result():
                    yield res
                    if fail_fast and res.code:
                        stop.set()
                        return
        except (GeneratorExit, KeyboardInterrupt):
            stop.set()
            raise
        finally:
            for fut in futures:
                fut.cancel()


def read_batch_text(text: str, source: str = "batch") -> tuple[list[BatchRow], list[RowResult]]:
    """:func:`read_batch` on a string."""
    return read_batch(io.StringIO(text), source)


@dataclass(frozen=True)
class ReportRecord:
    """What ``--report`` keeps of a streamed row: its summary and limit report (not its samples)."""

    report: Any
    summary_doc: dict

    def summary(self) -> dict:
        return dict(self.summary_doc)

    @classmethod
    def of(cls, plan) -> "ReportRecord":
        return cls(plan.report, plan.summary())
