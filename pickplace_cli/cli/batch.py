"""`plan --batch FILE|-`: many moves from a CSV (a file, or a pipe answered row by row), and belt schedules (a t_detect column)."""

from __future__ import annotations

import contextlib
import sys
from typing import Optional

import typer

from .app import _usage, note_exit
from .render import SlowedRows, _batch_line, _cycle_not_held, _emit_json, _emit_row_json, _row_not_held, _write_report


def _plan_batch(source, prof, options, height, eta, fail_fast, writer, output, report, report_only, json_summary,
                quiet, workers: int = 1, belt: Optional[dict] = None, keep_warm: float = 0.0) -> None:
    """--batch: plan every row, report failures by row number, write the good ones, exit with the worst code.
    A batch with a t_detect column is a belt schedule (:func:`_plan_schedule`). ``keep_warm`` [s]: a streamed
    batch re-plans its last move after each such idle time (:mod:`~pickplace_cli.pipelines.warm`)."""
    from ..pipelines.batch import BatchRow

    belt = belt or {}
    name = "stdin" if source == "-" else source
    streamed = source == "-" or _is_fifo(source)  # a pipe: answer each row as it is read
    warmer = _warmer(keep_warm, source, streamed, prof, options, writer, output)
    with _batch_input(source, name, warmer, streamed) as (items, info):
        if info.get("schedule"):
            if warmer is not None:
                _usage("--keep-warm does not apply to a belt schedule (a batch with a t_detect column)")
            angles = any(c.endswith("_theta") for c in info.get("columns", ()))  # tool angles: the robot's is carried
            _plan_schedule(items, name, streamed, prof, options, height, eta, fail_fast, writer, output, report,
                           report_only, json_summary, quiet, workers, {**belt, "angles": angles})
            return
        if belt.get("latency") is not None:
            _usage("--latency with --batch is the default latency of a belt schedule's rows (a batch with a "
                   "t_detect column); this batch has none (independent belt rows take a latency column)")
        if streamed:
            _stream_batch(items, name, prof, options, height, eta, fail_fast, writer, output, report,
                          report_only, json_summary, quiet, workers, warmer)
            return
        rows, bad = [], []
        for item in items:
            (rows if isinstance(item, BatchRow) else bad).append(item)
    first_bad = min((b.row for b in bad), default=None)
    if fail_fast and first_bad is not None:
        rows = [r for r in rows if r.row < first_bad]
        bad = [b for b in bad if b.row == first_bad]
    pending = sorted(bad, key=lambda b: b.row)  # parse errors, answered in row order as planning passes them
    sink = _RowSink(writer, output, report, json_summary, report_only, options.cycle)
    progress = bar = None
    if not quiet and len(rows) + len(bad) >= 50 and sys.stderr.isatty():
        from .render import console
        from rich.progress import Progress

        progress = Progress(console=console(stderr=True), transient=True)
        progress.start()
        bar = progress.add_task(f"planning {len(rows) + len(bad)} moves", total=len(rows))
    outcomes = _file_outcomes(rows, prof, options, height, eta, fail_fast, name, workers, writer, output, report,
                              report_only, json_summary)
    try:
        # (closed at once when answering a row fails, e.g. a reader that went away: the workers stop too)
        with sink, contextlib.closing(outcomes):
            for res in outcomes:
                while pending and pending[0].row < res.row:
                    sink.add(pending.pop(0))
                if sink.add(res) and fail_fast:
                    break
                if progress is not None:
                    progress.advance(bar)
            else:
                while pending:
                    sink.add(pending.pop(0))
    finally:
        if progress is not None:
            progress.stop()
    code = _batch_exit(sink.outcomes, report_only, fail_fast)
    note_exit(code)
    sink.finish(prof, quiet)
    if code:
        raise typer.Exit(code)


def _file_outcomes(rows, prof, options, height, eta, fail_fast, name, workers, writer, output, report, report_only,
                   json_summary):
    """The RowResults of a file batch's good rows, in row order, on ``workers`` processes (0: all cores for 100
    rows or more): the verdict engine for a verdicts-only batch where it applies, else plan()."""
    from ..pipelines.batch import plan_rows_parallel
    from .guards import available_cores

    n_workers = workers or (available_cores() if len(rows) >= 100 else 1)
    if json_summary and output is None and report is None:
        from ..pipelines.verdicts import engine_applies, verdict_rows_parallel

        if engine_applies(prof, options):
            return verdict_rows_parallel(rows, prof, options, height, eta, fail_fast, name, workers=n_workers)
    csv_dialect = writer.csv_dialect if output is not None else None
    return plan_rows_parallel(rows, prof, options, height, eta, fail_fast, name, workers=n_workers,
                              csv_dialect=csv_dialect, format_failed=report_only)


class _RowSink:
    """Where a file batch's answers go, one row at a time and in row order, so that memory holds one row's
    trajectory (MCAP and JSON trajectories need the whole timeline: those rows are kept): its error lines on
    stderr, its JSON line (``--json``), its CSV rows into the temporary ``-o`` file, its limit report
    (``--report``). The ``-o`` file replaces the old one only when the batch ends (atomically); a batch that
    writes no row leaves it as it was."""

    def __init__(self, writer, output, report, json_summary: bool, report_only: bool, cycle: float | None = None) -> None:
        self.writer, self.output, self.report, self.cycle = writer, output, report, cycle
        self.json_summary, self.report_only = json_summary, report_only
        self.csv_out = output is not None and writer.csv_dialect is not None
        self.outcomes: list[tuple[int, bool]] = []  # (code, planned) per row answered
        self.first_failed = None
        self.written = 0
        self.kept: list = []  # MCAP / JSON trajectories: (row, PlanRecord)
        self.reports: list = []  # --report: (row, ReportRecord)
        self.slowed = SlowedRows()
        self._stack = contextlib.ExitStack()
        self._out = None

    def __enter__(self) -> "_RowSink":
        if self.csv_out:
            from ..export import atomic_output

            self._out = self._stack.enter_context(atomic_output(self.output))
        return self

    def __exit__(self, kind, exc, tb) -> bool:
        if kind is None and self._out is not None and self.written == 0:  # nothing to write: the old file stays
            self._stack.__exit__(_NothingWritten, _NothingWritten(), None)  # (the temporary file is removed)
            return False
        self._stack.__exit__(kind, exc, tb)
        return False

    def add(self, res) -> bool:
        """Answer one row; whether it failed."""
        self.outcomes.append((res.code, res.plan is not None))
        if res.code and self.first_failed is None:
            self.first_failed = res.row
        if res.error is not None:  # one line per problem (a limit row: one per exceeded limit)
            sys.stderr.write("".join(f"pickplace: {ln}\n" for ln in res.error.splitlines()))
        _row_not_held(res)
        self.slowed.add(res)
        if self.json_summary:
            _emit_row_json(res)
        if res.plan is not None and self.report is not None:
            from ..pipelines.batch import ReportRecord

            self.reports.append((res.row, ReportRecord.of(res.plan)))
        if res.plan is not None and self.output is not None and (res.code == 0 or (self.report_only and res.code == 3)):
            self.written += 1
            if self._out is not None:
                from ..export.csv import csv_header, csv_rows

                if self.written == 1:
                    self._out.write(csv_header(res.plan, self.writer.csv_dialect, move=True))
                self._out.write(res.text if res.text is not None else csv_rows(res.plan, self.writer.csv_dialect,
                                                                                move=res.row))
            else:
                from ..pipelines.batch import PlanRecord

                self.kept.append((res.row, res.plan if isinstance(res.plan, PlanRecord) else PlanRecord.of(res.plan)))
        return bool(res.code)

    def finish(self, prof, quiet: bool) -> None:
        """The report, the closing line, the MCAP/JSON trajectory file (the CSV one is in place already)."""
        if self.report is not None:
            _write_report([r for _, r in self.reports], self.report, rows=[n for n, _ in self.reports])
        if not quiet:
            _batch_line([c for c, _ in self.outcomes], self.first_failed,
                        self.written if self.output is not None else None, self.slowed)
        if self.kept:
            from ..pipelines.timeline import concatenate

            from ..pipelines.timeline import on_cycle
            from .controller import rounded_dwell

            samples = concatenate([p for _, p in self.kept], [r for r, _ in self.kept],
                                  restart_time=not self.writer.one_timeline, gap=rounded_dwell(prof, self.cycle))
            self.writer(on_cycle(samples, self.cycle), self.output)
        if self.output is not None and self.written == 0:
            sys.stderr.write("pickplace: no row could be written\n")


def _batch_exit(rows: list[tuple[int, bool]], report_only: bool, fail_fast: bool = False) -> int:
    """A batch's exit code from its rows' (code, planned): the highest code; with ``--write-anyway``
    (``report_only``) the rows that were planned and only broke a timed limit (3: their trajectories are written)
    do not count, as for a single plan; a row past a joint range or the workcell box (4), an invalid or an
    unreachable row still does. With ``--fail-fast`` a batch that stopped at a row exits with that row's code (the
    rows after it were not planned), ``--write-anyway`` or not."""
    if fail_fast and rows and rows[-1][0]:
        return rows[-1][0]
    return max((c for c, planned in rows if c and not (report_only and planned and c == 3)), default=0)


def _warmer(keep_warm: float, source: str, streamed: bool, prof, options, writer, output):
    """``--keep-warm`` [s]: the stream's :class:`~pickplace_cli.pipelines.warm.Warmer`, or None when off; usage
    error for a batch that is not a pipe."""
    import os

    if not keep_warm:
        return None
    if not streamed and os.path.exists(source):  # (a missing file: the read says so, exit 1)
        _usage(f"--keep-warm only applies to a streamed batch (- or a named pipe); {source} is not a pipe: it "
               "is read whole")
    from ..pipelines.warm import Warmer

    csv_out = output is not None and writer.csv_dialect is not None
    return Warmer(prof, options, writer.csv_dialect if csv_out else None, keep_warm)


@contextlib.contextmanager
def _batch_input(source: str, name: str, warmer=None, streamed: bool = False):
    """The batch's rows (:func:`~pickplace_cli.pipelines.batch.iter_batch`, lazily) and its header ``info`` (plain batch or
    belt schedule), the header already read; the file (or stdin) stays open inside the ``with``. A stream (stdin,
    a named pipe: ``streamed``) is read by :class:`~pickplace_cli.pipelines.warm.WarmLines` from its file
    descriptor, so that a line ended by a lone ``\\r`` is answered at once (a text stream holds it back until the
    next byte shows whether ``\\n`` follows); with a ``warmer`` (``--keep-warm``) WarmLines calls it while it
    waits."""
    import itertools

    from ..pipelines.batch import iter_batch
    from ..model.errors import TaskError

    with contextlib.ExitStack() as stack:
        fd = None
        encoding = "utf-8"
        if source == "-" and sys.stdin is None:  # started with stdin closed (`<&-`)
            raise TaskError("batch = -: standard input is closed; give the rows on stdin or a file")
        if warmer is not None or streamed:
            if source == "-":
                try:
                    fd = sys.stdin.fileno()
                    encoding = sys.stdin.encoding or "utf-8"  # as the CLI's own stdin (the locale, PYTHONIOENCODING)
                except (AttributeError, ValueError, OSError):  # pragma: no cover - a test runner's stand-in: no fd
                    fd = None
            else:
                import os

                try:
                    fd = os.open(source, os.O_RDONLY)
                except OSError as exc:
                    raise TaskError(f"batch = {source}: cannot read it: {exc.strerror}") from None
                stack.callback(os.close, fd)
        if fd is not None:
            from ..pipelines.warm import WarmLines

            fh = WarmLines(fd, warmer.interval, warmer, encoding) if warmer is not None else WarmLines(fd, None, None, encoding)
        elif source == "-":
            try:  # undecodable bytes kept as surrogates, so iter_batch names their line (strict decoding fails on
                # the whole chunk read, before the rows above the bad line are answered); lines end at \n, \r\n or a
                # lone \r, as in a file (Python's stdin splits at \n only on POSIX)
                sys.stdin.reconfigure(errors="surrogateescape", newline="")
            except (AttributeError, ValueError, OSError):  # pragma: no cover - a test runner's stand-in
                pass
            fh = sys.stdin
        else:
            try:  # -sig: Excel's BOM
                fh = stack.enter_context(open(source, encoding="utf-8-sig", newline="", errors="surrogateescape"))
            except OSError as exc:
                raise TaskError(f"batch = {source}: cannot read it: {exc.strerror}") from None
        info: dict = {}
        items = iter_batch(fh, name, info)
        yield itertools.chain([next(items)], items), info  # next(): the header is read


def _plan_schedule(items, name, streamed, prof, options, height, eta, fail_fast, writer, output, report,
                   report_only, json_summary, quiet, workers, belt) -> None:
    """--batch with a t_detect column: a belt schedule (pickplace_cli/schedule.py), the robot's state carried
    from row to row. A file is checked whole (order, cells) before anything is planned or written; a stream
    row by row. Each row: a JSON line (--json) or a line on stderr; the picked cycles' samples (detection clock,
    move = row) to -o / stdout; the closing line; exit with the worst row's code."""
    from contextlib import ExitStack

    from ..model.errors import TaskError
    from ..pipelines.schedule import CycleStream, ScheduleSummary, check_order, plan_schedule

    if belt.get("method_given") and options.method != "bspline-vel":
        raise TaskError(f"method = {options.method}: a belt schedule meets each part with its velocity; it "
                        "needs --method bspline-vel (the default for a schedule)")
    if workers > 1 and not quiet:
        sys.stderr.write(f"pickplace: -j {workers}: a belt schedule is planned row by row (the robot's state carries "
                         "over from each row to the next); one process\n")
    if not streamed:  # every row read and checked first: an input error writes nothing
        items = list(check_order(items, name))
    params = {k: v for k, v in options.method_params.items() if k in ("solver", "table") and v is not None}
    results = plan_schedule(items, prof, options.time, height, eta, options.rate, belt.get("latency") or 0.0,
                            params, name, fail_fast, report_only, bool(belt.get("angles")), options.turn,
                            options.turn_during, options.cycle)
    report_rows: list = []  # --report: every row, its segments' summaries and limit reports
    codes: list[int] = []
    summary = ScheduleSummary()
    kept: list = []
    stream = CycleStream(options.cycle)  # the picked cycles as written (on a cycle: one sample per cycle)
    csv_out = output is not None and writer.csv_dialect is not None
    header_done = False
    try:
        with ExitStack() as stack:
            out = None
            if csv_out:
                from ..export import atomic_output

                out = stack.enter_context(atomic_output(output))
            for res in results:
                summary.add(res)
                codes.append(res.code)
                if report is not None:
                    report_rows.append({"row": res.row, "exit_code": res.code, "error": res.error,
                                        **({"segments": res.cycle.report_doc()} if res.cycle is not None else {})})
                if res.error is not None:
                    sys.stderr.write("".join(f"pickplace: {ln}\n" for ln in res.error.splitlines()))
                elif not quiet:
                    c = res.cycle
                    xyz = ", ".join(f"{x:.4f}" for x in c.rendezvous.meeting_point)
                    sys.stderr.write(f"row {res.row}: starts t = {c.t_start:.4f} s (latency {c.latency:.4f} s), meets the part "
                                     f"at ({xyz}) m at t = {c.t_meet:.4f} s, placed t = {c.t_place:.4f} s, free "
                                     f"t = {c.t_end:.4f} s\n")
                _cycle_not_held(res)
                sys.stderr.flush()
                if json_summary:
                    _emit_json(res.as_dict())
                written = res.code == 0 or (report_only and res.code == 3 and res.cycle is not None)
                if written and output is not None:
                    header_done = _write_pieces(stream.pieces(res.cycle), out, writer, kept, header_done)
            header_done = _write_pieces(stream.close(), out, writer, kept, header_done)
            _keep_unless_empty(out, output, header_done)
    except _NothingWritten:
        pass
    if kept:
        from ..pipelines.timeline import _join, _pieces_of

        writer(_join([_pieces_of(tl, 0.0) for tl in kept], [int(tl.move[0]) for tl in kept], kept[0].joint,
                     [sg for tl in kept for sg in tl.segments], [sm for tl in kept for sm in tl.summaries]), output)
    if json_summary:
        _emit_json({"schedule": summary.as_dict()})
    if report is not None:
        import json

        from ..export import atomic_output

        with atomic_output(report) as stream:
            json.dump({"schedule": summary.as_dict(), "rows": report_rows}, stream, indent=2, allow_nan=False,
                      default=float)
            stream.write("\n")
    if not quiet:
        sys.stderr.write(summary.line() + "\n")
    if output is not None and not header_done and not kept:
        sys.stderr.write("pickplace: no part was picked: nothing written\n")
    if summary.worst and not (report_only and all(c == 3 for c in codes if c)):
        raise typer.Exit(summary.worst)


def _write_pieces(pieces: list, out, writer, kept: list, header_done: bool) -> bool:
    """Write a belt schedule's timelines to the CSV stream ``out`` (the header before the first), or keep them for a
    one-timeline writer (MCAP, JSON); → whether the header is written."""
    from ..export.csv import csv_header, csv_rows

    for timeline in pieces:
        if out is not None:
            if not header_done:
                out.write(csv_header(timeline, writer.csv_dialect, move=True))
                header_done = True
            out.write(csv_rows(timeline, writer.csv_dialect))
            out.flush()
        else:
            kept.append(timeline)
    return header_done


class _NothingWritten(Exception):
    """Raised inside an atomic output that received no row: its temporary file is removed, the target neither
    created nor changed (as a file batch that writes nothing)."""


def _keep_unless_empty(out, output: str | None, written: bool) -> None:
    """_NothingWritten when ``out`` is a temporary file (``-o FILE``) that got no row."""
    if out is not None and not written and output not in (None, "-"):
        raise _NothingWritten


def _is_fifo(path: str) -> bool:
    import os
    import stat

    try:
        return stat.S_ISFIFO(os.stat(path).st_mode)
    except OSError:
        return False


#: the pipe buffer a streamed CSV asks for [bytes] (Linux's default is 64 KiB, less than one 1 kHz answer of
#: the Adept cycle with every column, ~72 kB; 1 MiB is the most an unprivileged process may ask by default)
STREAM_PIPE_BYTES = 1 << 20


def _widen_pipe(out) -> None:
    """Best effort: when ``out`` is a pipe (stdout piped to the next stage, or a named pipe), enlarge its buffer
    (F_SETPIPE_SZ, Linux) so that a row's whole answer goes in with one write instead of waiting for the reader
    to drain the first 64 KiB (measured: ~0.1 ms less latency per streamed answer). Nothing changes elsewhere."""
    import os
    import stat

    try:
        import fcntl

        fd = out.fileno()
        if not stat.S_ISFIFO(os.fstat(fd).st_mode):
            return
        setpipe = getattr(fcntl, "F_SETPIPE_SZ", 1031)  # Python < 3.10 lacks the name
        if fcntl.fcntl(fd, getattr(fcntl, "F_GETPIPE_SZ", 1032)) < STREAM_PIPE_BYTES:
            fcntl.fcntl(fd, setpipe, STREAM_PIPE_BYTES)
    except (ImportError, OSError, ValueError, AttributeError, TypeError):  # not Linux, no fd, or over the limit
        pass


def _stream_batch(items, name, prof, options, height, eta, fail_fast, writer, output, report, report_only,
                  json_summary, quiet, workers: int, warmer=None) -> None:
    """--batch - (or a named pipe): the rows of :func:`~pickplace_cli.pipelines.batch.iter_batch` (``items``), each
    answered as soon as its line is read — a JSON line (``--json``)
    or its CSV rows, flushed — with the same row numbers, messages and exit codes as a file batch. Memory:
    one row's trajectory (MCAP and JSON trajectories need the whole timeline: those rows are kept until the
    input ends; ``--report`` keeps each row's limit report, not its samples)."""
    from contextlib import ExitStack

    from ..pipelines.batch import ReportRecord
    from ..pipelines.stream import plan_stream

    verdicts_only = json_summary and output is None and report is None
    engine = False
    if verdicts_only and warmer is None:  # (--keep-warm: every row planned alone, as it comes)
        from ..pipelines.verdicts import engine_applies

        engine = engine_applies(prof, options)
    csv_out = output is not None and writer.csv_dialect is not None
    kept: list = []  # MCAP / JSON trajectories: the rows to write when the input ends
    reports: list = []
    codes: list[int] = []
    planned_rows: list[bool] = []
    first_failed = None
    n_written = 0
    slowed = SlowedRows()
    try:
        with ExitStack() as stack:
            out = None
            if csv_out:
                from ..export import atomic_output
                from ..export.csv import csv_header, csv_rows

                out = stack.enter_context(atomic_output(output))
                _widen_pipe(out)
            results = plan_stream(items, prof, options, height, eta, fail_fast, name,
                                  workers=max(workers, 1), csv_dialect=writer.csv_dialect if csv_out else None,
                                  format_failed=report_only, verdicts=engine)
            for res in results:
                codes.append(res.code)
                planned_rows.append(res.plan is not None)
                note_exit(_batch_exit([(res.code, res.plan is not None)], report_only, fail_fast))
                if res.code and first_failed is None:
                    first_failed = res.row
                if res.error is not None:
                    sys.stderr.write("".join(f"pickplace: {ln}\n" for ln in res.error.splitlines()))
                    sys.stderr.flush()
                _row_not_held(res)
                slowed.add(res)
                if json_summary:
                    _emit_row_json(res)
                if warmer is not None:
                    warmer.remember(res.plan)
                if res.plan is not None and report is not None:
                    reports.append((res.row, ReportRecord.of(res.plan)))
                if res.plan is not None and output is not None and (res.code == 0 or (report_only and res.code == 3)):
                    n_written += 1
                    if out is not None:
                        if n_written == 1:
                            out.write(csv_header(res.plan, writer.csv_dialect, move=True))
                        out.write(res.text if res.text is not None else csv_rows(res.plan, writer.csv_dialect, move=res.row))
                        out.flush()
                    else:
                        from ..pipelines.batch import PlanRecord

                        kept.append((res.row, res.plan if isinstance(res.plan, PlanRecord) else PlanRecord.of(res.plan)))
                if fail_fast and res.code:
                    break
            _keep_unless_empty(out, output, n_written > 0)
    except _NothingWritten:
        pass
    if kept:
        from ..pipelines.timeline import concatenate

        from ..pipelines.timeline import on_cycle
        from .controller import rounded_dwell

        samples = concatenate([p for _, p in kept], [r for r, _ in kept], restart_time=not writer.one_timeline,
                              gap=rounded_dwell(prof, options.cycle))
        writer(on_cycle(samples, options.cycle), output)
    if report is not None:
        _write_report([r for _, r in reports], report, rows=[n for n, _ in reports])
    if not quiet:
        _batch_line(codes, first_failed, n_written if output is not None else None, slowed)
    if output is not None and n_written == 0:
        sys.stderr.write("pickplace: no row could be written\n")
    code = _batch_exit(list(zip(codes, planned_rows)), report_only, fail_fast)
    if code:
        raise typer.Exit(code)
