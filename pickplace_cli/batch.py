"""Many moves from one CSV, planned in one process (``pickplace plan --batch FILE|-``).

Input: a header row, then one move per row. Required columns ``from_x, from_y, from_z, to_x, to_y, to_z``
[m, base frame]; optional ``height`` [m], ``eta`` [-], ``v_from_x … v_from_z``, ``v_to_x … v_to_z``
[m/s] and ``time`` [s, or "auto"/"fit"]. An empty optional cell takes the command-line/profile value.
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

from .errors import PickplaceError, TaskError

REQUIRED = ("from_x", "from_y", "from_z", "to_x", "to_y", "to_z")
OPTIONAL = ("height", "eta", "v_from_x", "v_from_y", "v_from_z", "v_to_x", "v_to_y", "v_to_z", "time")


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


def violation_text(r) -> str:
    """The one line that says a limit is exceeded (a :class:`~pickplace_cli.limits.LimitRow` that is not
    ok), as a single plan and every batch row print it: joint, quantity, peak [unit], when (t [s] or the
    duty cycle), limit, excess and utilisation, e.g. ``limit exceeded: q1 motor torque = 2.584 N·m at
    t = 0.0479 s; limit 2 N·m (by 0.584 N·m, 129.2 %)``."""
    from .limits import percent

    when = f" at t = {r.t_peak:.4f} s" if r.t_peak is not None else " over the duty cycle"
    return (
        f"limit exceeded: {r.joint} {r.quantity} = {r.peak:.4g} {r.unit}{when}; "
        f"limit {r.limit:.4g} {r.unit} (by {abs(r.excess):.4g} {r.unit}, {percent(r.utilisation)} %)"
    )


def read_batch(stream: IO[str], source: str = "batch") -> tuple[list[BatchRow], list[RowResult]]:
    """Parse the batch CSV → (good rows, rows that failed to parse). A bad header, or a header with no
    row after it, raises TaskError."""
    text = stream.read()
    text = text.removeprefix("\ufeff")  # a BOM (the CLI opens files as utf-8-sig; stdin and strings keep it)
    lines = [(n, t) for n, t in enumerate(text.splitlines(), start=1)]
    lines = [(n, t) for n, t in lines if t.strip() and not t.lstrip().startswith("#")]
    if not lines:
        raise TaskError(f"{source}: no header row (need columns {', '.join(REQUIRED)})")
    header_line, header_text = lines[0]
    sep = sniff_delimiter(header_text)
    header = [h.strip() for h in next(csv.reader([header_text], delimiter=sep))]
    unknown = [h for h in header if h not in REQUIRED + OPTIONAL]
    if unknown:
        raise TaskError(
            f"{source}:{header_line}: column {unknown[0]!r} is not known; columns are {', '.join(REQUIRED + OPTIONAL)}"
        )
    missing = [h for h in REQUIRED if h not in header]
    if missing:
        raise TaskError(f"{source}:{header_line}: column {missing[0]!r} is missing (required: {', '.join(REQUIRED)})")
    dup = sorted({h for h in header if header.count(h) > 1})
    if dup:
        raise TaskError(f"{source}:{header_line}: column {dup[0]!r} appears twice")
    if len(lines) == 1:
        raise TaskError(
            f"{source}:{header_line}: no moves after the header (need one row per move with {', '.join(REQUIRED)})"
        )
    rows: list[BatchRow] = []
    bad: list[RowResult] = []
    for number, (line, text) in enumerate(lines[1:], start=1):
        cells = [c.strip() for c in next(csv.reader([text], delimiter=sep))]
        try:
            if len(cells) != len(header):
                raise TaskError(f"has {len(cells)} cells, the header has {len(header)}")
            values: dict[str, Any] = {}
            for name, cell in zip(header, cells):
                if cell == "":
                    if name in REQUIRED:
                        raise TaskError(f"{name} is empty: give a number in metres")
                    continue
                if name == "time" and cell in ("auto", "fit", "optimal"):
                    values[name] = cell
                    continue
                try:
                    x = float(cell)
                except ValueError:
                    hint = " (the decimal mark is '.')" if "," in cell and sep != "," else ""
                    raise TaskError(f"{name} = {cell!r}: not a number{hint}") from None
                if not math.isfinite(x):
                    raise TaskError(f"{name} = {cell!r}: must be finite")
                values[name] = x
            rows.append(BatchRow(number, line, values))
        except TaskError as exc:
            bad.append(RowResult(number, error=f"row {number} ({source}:{line}): {exc}", code=exc.exit_code))
    return rows, bad


def row_task(values: dict, profile, height: float | None = None, eta: float | None = None):
    """The Task of one batch row: its cells, else ``height``/``eta`` (the command line), else the profile's
    planning defaults; end velocities [m/s] default to 0. TaskError for an invalid move."""
    import numpy as np

    from .task import Task

    v = values
    return Task(
        [v["from_x"], v["from_y"], v["from_z"]],
        [v["to_x"], v["to_y"], v["to_z"]],
        v.get("height", height if height is not None else profile.planning.height),
        v.get("eta", eta if eta is not None else profile.planning.eta),
        v_from=np.array([v.get(f"v_from_{c}", 0.0) for c in "xyz"]),
        v_to=np.array([v.get(f"v_to_{c}", 0.0) for c in "xyz"]),
    )


def plan_rows(
    rows: list[BatchRow], profile, options, height: float | None = None, eta: float | None = None,
    fail_fast: bool = False, source: str = "batch",
) -> Iterator[RowResult]:
    """Plan every row (in order); yields one RowResult per row. ``options`` is a PlanOptions template:
    a row's ``time`` replaces its duration. Stops after the first failing row when ``fail_fast``."""
    from dataclasses import replace

    from .planner import plan

    for r in rows:
        v = r.values
        try:
            task = row_task(v, profile, height, eta)
            opts = replace(options, time=v["time"]) if "time" in v else options
            result = plan(task, profile, opts)
            code = result.report.exit_code()
            err = None
            if code:  # every exceeded limit, one line each, in the single plan's words
                err = "\n".join(f"row {r.row} ({source}:{r.line}): {violation_text(x)}"
                                 for x in result.report.violations)
            yield RowResult(r.row, result, err, code)
        except PickplaceError as exc:
            yield RowResult(r.row, None, f"row {r.row} ({source}:{r.line}): {exc}", exc.exit_code)
            code = exc.exit_code
        if fail_fast and code:
            return


@dataclass(frozen=True)
class PlanRecord:
    """The picklable part of a Plan (samples, joint motion, limit report, summary) — what a worker process
    sends back. It has the attributes every writer and :mod:`~pickplace_cli.timeline` use."""

    t: Any
    p: Any
    v: Any
    a: Any
    j: Any
    joint: Any
    report: Any
    summary_doc: dict

    def summary(self) -> dict:
        return dict(self.summary_doc)

    @classmethod
    def of(cls, plan) -> "PlanRecord":
        return cls(plan.t, plan.p, plan.v, plan.a, plan.j, plan.joint, plan.report, plan.summary())


def _plan_chunk(args) -> list[RowResult]:
    """Worker: plan a chunk of rows (no fail-fast inside a chunk; the parent stops in order). With a CSV
    dialect, the rows of every plan that will be written are formatted here too (formatting costs as much
    as planning, so it is worth spreading)."""
    rows, profile, options, height, eta, source, csv_dialect, format_failed = args
    out = []
    for r in plan_rows(rows, profile, options, height, eta, False, source):
        text = None
        if csv_dialect is not None and r.plan is not None and (r.code == 0 or format_failed):
            from .export.csv import csv_rows

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
    from concurrent.futures import ProcessPoolExecutor

    with ProcessPoolExecutor(max_workers=workers) as pool:
        futures = [pool.submit(fn, a) for a in args]
        try:
            for fut in futures:
                for res in fut.result():
                    yield res
                    if fail_fast and res.code:
                        return
        finally:
            for fut in futures:
                fut.cancel()


def read_batch_text(text: str, source: str = "batch") -> tuple[list[BatchRow], list[RowResult]]:
    """:func:`read_batch` on a string."""
    return read_batch(io.StringIO(text), source)
