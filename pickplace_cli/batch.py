"""Many moves from one CSV, planned in one process (``pickplace plan --batch FILE|-``).

Input: a header row, then one move per row. Required columns ``from_x, from_y, from_z, to_x, to_y, to_z``
[m, base frame]; optional ``height`` [m], ``eta`` [-], ``v_from_x … v_from_z``, ``v_to_x … v_to_z``
[m/s] and ``time`` [s, or "auto"/"fit"]. An empty optional cell takes the command-line/profile value.
Blank lines and lines starting with ``#`` are skipped. Rows are numbered from 1 (the first data row),
which is the number every message and the output's ``move`` column use.

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
    """The outcome of one row: a plan, or an error with its exit code (1 input, 3 limit, 4 unreachable)."""

    row: int
    plan: Any = None
    error: str | None = None
    code: int = 0
    text: str | None = None  # the plan's CSV rows, when formatted in a worker (see plan_rows_parallel)


def read_batch(stream: IO[str], source: str = "batch") -> tuple[list[BatchRow], list[RowResult]]:
    """Parse the batch CSV → (good rows, rows that failed to parse). A bad header raises TaskError."""
    lines = [(n, text) for n, text in enumerate(stream.read().splitlines(), start=1)]
    lines = [(n, t) for n, t in lines if t.strip() and not t.lstrip().startswith("#")]
    if not lines:
        raise TaskError(f"{source}: no header row (need columns {', '.join(REQUIRED)})")
    header_line, header_text = lines[0]
    header = [h.strip() for h in next(csv.reader([header_text]))]
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
    rows: list[BatchRow] = []
    bad: list[RowResult] = []
    for number, (line, text) in enumerate(lines[1:], start=1):
        cells = [c.strip() for c in next(csv.reader([text]))]
        try:
            if len(cells) != len(header):
                raise TaskError(f"has {len(cells)} cells, the header has {len(header)}")
            values: dict[str, Any] = {}
            for name, cell in zip(header, cells):
                if cell == "":
                    if name in REQUIRED:
                        raise TaskError(f"{name} is empty: give a number in metres")
                    continue
                if name == "time" and cell in ("auto", "fit"):
                    values[name] = cell
                    continue
                try:
                    x = float(cell)
                except ValueError:
                    raise TaskError(f"{name} = {cell!r}: not a number") from None
                if not math.isfinite(x):
                    raise TaskError(f"{name} = {cell!r}: must be finite")
                values[name] = x
            rows.append(BatchRow(number, line, values))
        except TaskError as exc:
            bad.append(RowResult(number, error=f"row {number} ({source}:{line}): {exc}", code=exc.exit_code))
    return rows, bad


def plan_rows(
    rows: list[BatchRow], profile, options, height: float | None = None, eta: float | None = None,
    fail_fast: bool = False, source: str = "batch",
) -> Iterator[RowResult]:
    """Plan every row (in order); yields one RowResult per row. ``options`` is a PlanOptions template:
    a row's ``time`` replaces its duration. Stops after the first failing row when ``fail_fast``."""
    from dataclasses import replace

    import numpy as np

    from .planner import plan
    from .task import Task

    for r in rows:
        v = r.values
        try:
            task = Task(
                [v["from_x"], v["from_y"], v["from_z"]],
                [v["to_x"], v["to_y"], v["to_z"]],
                v.get("height", height if height is not None else profile.planning.height),
                v.get("eta", eta if eta is not None else profile.planning.eta),
                v_from=np.array([v.get(f"v_from_{c}", 0.0) for c in "xyz"]),
                v_to=np.array([v.get(f"v_to_{c}", 0.0) for c in "xyz"]),
            )
            opts = replace(options, time=v["time"]) if "time" in v else options
            result = plan(task, profile, opts)
            code = result.report.exit_code()
            err = None
            if code:
                worst = result.report.violations[0]
                err = (f"row {r.row} ({source}:{r.line}): limit exceeded: {worst.joint} {worst.quantity} "
                       f"= {worst.peak:.4g} {worst.unit}, limit {worst.limit:.4g} {worst.unit}"
                       + (f" at t = {worst.t_peak:.4f} s" if worst.t_peak is not None else ""))
                if len(result.report.violations) > 1:
                    err += f" (+{len(result.report.violations) - 1} more)"
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
