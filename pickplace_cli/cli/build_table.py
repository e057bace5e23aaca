"""`pickplace build-table`: build the λ → (k1, k2) table of Li 2018 (or the conveyor table of Yang 2022) and export it."""

from __future__ import annotations

import contextlib
import sys
from enum import Enum
from typing import Optional

import typer

from .. import __version__
from .app import Panel, _handle_errors, _usage, app, StDialect, TableMethod

#: the --st-dialect of the running build-table (strict or codesys), read where the table is formatted
_ST_DIALECT = ["strict"]


def _parse_weights(text: str) -> tuple[float, float]:
    from ..model.errors import TableError

    try:
        wa, wj = (float(x) for x in text.split(","))
    except ValueError:
        raise TableError(f"weights = {text!r}: give two numbers WA,WJ with WA + WJ = 1, e.g. 0.5,0.5") from None
    return wa, wj


class TableFormat(str, Enum):
    csv = "csv"
    json = "json"
    st = "st"


@app.command("build-table")
@_handle_errors
def build_table_cmd(
    ctx: typer.Context,
    lambda_min: float = typer.Option(1.0, "--lambda-min", help="Smallest width/height ratio λ = b/h.", rich_help_panel=Panel.METHOD),
    lambda_max: float = typer.Option(40.0, "--lambda-max", help="Largest λ.", rich_help_panel=Panel.METHOD),
    lambda_step: float = typer.Option(0.5, "--lambda-step", help="Step of the λ grid.", rich_help_panel=Panel.METHOD),
    lambda_points: int = typer.Option(
        0, "--lambda-points", help="N values of λ spaced evenly in log λ from --lambda-min to --lambda-max "
        "(instead of --lambda-step; 0 = use the step).", rich_help_panel=Panel.METHOD),
    eta: float = typer.Option(0.5, "--eta", help="Lift-off/set-down ratio η, 0 < η < 1.", rich_help_panel=Panel.METHOD),
    eta_min: Optional[float] = typer.Option(
        None, "--eta-min", help="Build the 2-D (λ, η) table: smallest η of its η axis (with --eta-max, --eta-step).", rich_help_panel=Panel.METHOD),
    eta_max: Optional[float] = typer.Option(None, "--eta-max", help="2-D table: largest η (default: --eta-min).", rich_help_panel=Panel.METHOD),
    eta_step: float = typer.Option(0.05, "--eta-step", help="2-D table: step of the η axis.", rich_help_panel=Panel.METHOD),
    eta_list: Optional[str] = typer.Option(
        None, "--eta-list", help="2-D table: the η axis as increasing values, e.g. 0.1,0.2,0.5 (instead of --eta-min …).", rich_help_panel=Panel.METHOD),
    weights: str = typer.Option("0.5,0.5", "--weights", help="Weights WA,WJ of F_a and F_j in F (Li 2018 Eq. 22); WA + WJ = 1.", rich_help_panel=Panel.METHOD),
    grid_step: float = typer.Option(0.01, "--grid-step", help="Step of the coarse (k1, k2) search grid.", rich_help_panel=Panel.METHOD),
    fit_min: float = typer.Option(5.0, "--fit-min", help="Fit the Eq. 23 cubic on rows with λ ≥ this (no cubic follows λ < 5).", rich_help_panel=Panel.METHOD),
    workers: int = typer.Option(0, "--workers", "-j", help="Local worker processes (0 = all cores; 1 = in this process).", rich_help_panel=Panel.BATCH),
    scheduler: Optional[str] = typer.Option(
        None, "--scheduler", metavar="tcp://HOST:PORT",
        help="Run the rows on this Dask distributed scheduler instead of local processes (extra pickplace-cli[dask]).",
        rich_help_panel=Panel.BATCH,
    ),
    resume: bool = typer.Option(
        False, "--resume",
        help="Continue an interrupted build from OUTPUT.partial.jsonl (rows already finished are not recomputed; needs -o FILE).",
        rich_help_panel=Panel.BATCH,
    ),
    output: str = typer.Option("-", "--output", "-o", help="Output file ('-' = stdout). Written atomically.", rich_help_panel=Panel.OUTPUT),
    table_format: TableFormat = typer.Option(
        TableFormat.csv, "--format", "-f",
        help="csv (the table file plan --table reads), json, or st (IEC 61131-3 Structured Text with a look-up "
        "function). [default: from -o's suffix (.csv, .json, .st), else csv]",
        rich_help_panel=Panel.OUTPUT,
    ),
    st_dialect: StDialect = typer.Option(
        StDialect.strict, "--st-dialect", help="With --format st: strict (IEC 61131-3: the table is a constant block "
        "of the look-up FUNCTION; any compiler, matiec included) or codesys (a VAR_GLOBAL CONSTANT list beside the "
        "FUNCTION, for a CODESYS/TwinCAT global variable list).",
        rich_help_panel=Panel.CONTROLLER,
    ),
    table_method: TableMethod = typer.Option(
        TableMethod.bspline, "--method", "-m",
        help="bspline: Li 2018's λ → (k1, k2) table; bspline-vel: Yang 2022's conveyor-tracking table over the "
        "dimensionless groups (h/b, v·T/b along and across; local processes and CSV only).",
        rich_help_panel=Panel.METHOD,
    ),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No progress bar.", rich_help_panel=Panel.OUTPUT),
) -> None:
    """Compute the optimal (k1*, k2*) of the B-spline method for a grid of λ, with the Eq. 23 cubic fit.

    With -o FILE, finished rows are also appended to FILE.partial.jsonl as they complete; after Ctrl-C
    or a kill, rerun the same command with --resume. The table replaces FILE only when it is complete.
    """
    from ..model.errors import TableError
    from ..lookup.bspline_build import run_build
    from .guards import cap_workers
    from ..lookup.bspline_optimum import TableSettings
    from ..lookup.bspline_table import format_table

    from .guards import suffix_format

    table_format = suffix_format(ctx, table_format, output, {".csv": "csv", ".json": "json", ".st": "st"},
                                 "table_format")
    if st_dialect != StDialect.strict and table_format != TableFormat.st:
        _usage(f"--st-dialect applies to --format st, not {table_format.value}")
    _ST_DIALECT[0] = st_dialect.value
    if not scheduler:
        workers = cap_workers(workers)
    if table_method == TableMethod.bspline_vel:
        if scheduler or resume or table_format != TableFormat.csv:
            _usage("--method bspline-vel builds on local processes into a CSV (no --scheduler, --resume, --format)")
        _build_vel_table(eta, workers, output, quiet)
        return

    if not (0 < eta < 1):
        raise TableError(f"eta = {eta!r}: the lift-off/set-down ratio η must lie strictly between 0 and 1")
    settings = TableSettings(eta=eta, weights=_parse_weights(weights), grid_step=grid_step)
    lams, lam_text = _lambda_axis(lambda_min, lambda_max, lambda_step, lambda_points)
    if eta_list is not None or eta_min is not None or eta_max is not None:
        if eta_list is not None and (eta_min is not None or eta_max is not None):
            _usage("--eta-list replaces --eta-min/--eta-max: give one or the other")
        _build_table_2d(lams, lam_text, settings, eta_list, eta_min, eta_max, eta_step, workers, scheduler,
                        resume, output, table_format, quiet)
        return
    ckpt = _checkpoint_for(output, resume, workers)
    from ..lookup.checkpoint import checkpoint_lock

    with checkpoint_lock(ckpt):  # one run at a time owns OUTPUT.partial.jsonl, from its first read to its removal
        _note_checkpoint_on_sigterm(ckpt)
        with contextlib.ExitStack() as stack:
            executor, n_workers, tick = _engine(stack, scheduler, workers, quiet, len(lams), "λ", eta=False)
            try:
                table, report = run_build(
                    lams, settings, progress=tick, workers=n_workers, executor=executor, checkpoint=ckpt, resume=resume
                )
            except KeyboardInterrupt:
                saved = _checkpointed_rows(ckpt, settings)
                if saved:
                    sys.stderr.write(
                        f"pickplace: {saved} of {len(lams)} rows are saved in {ckpt}; "
                        "run the same command with --resume to continue\n"
                    )
                raise
        extra = {
            "lambda_grid": lam_text,
            "optimiser": "coarse grid + bounded Nelder-Mead from each grid local optimum within basin_margin (one per basin); exact peaks",
            "fit_lambda_min": fit_min,
        }
        if table_format is TableFormat.json:
            from ..export.table_json import format_table_json as formatter
        elif table_format is TableFormat.st:
            from ..export.table_st import format_table_st as formatter
        else:
            formatter = format_table
        text = (formatter(table, __version__, extra, dialect=_ST_DIALECT[0]) if table_format is TableFormat.st
                else formatter(table, __version__, extra))
        _write_table(output, text, ckpt, len(lams))
        if ckpt is not None:
            ckpt.unlink(missing_ok=True)  # the table is in place: the partial results are no longer needed
        if not quiet:
            g1, g2, res = table.fit(fit_min)
            resumed = f"; {report.resumed} rows resumed from {ckpt}, {report.computed} computed" if report.resumed else ""
            sys.stderr.write(
                f"{len(lams)} rows{resumed}; cubic fit (Eq. 23) on λ ≥ {fit_min:g}: max |residual| {res:.3g}; "
                f"k1 = {g1[0]:.4g} + {g1[1]:.4g} λ + {g1[2]:.4g} λ² + {g1[3]:.4g} λ³\n"
            )


def _lambda_axis(lambda_min: float, lambda_max: float, lambda_step: float, lambda_points: int):
    """The λ values of a build and their description for the header: by --lambda-step, or --lambda-points
    spaced evenly in log λ (the 2-D table's axis: λ from 0.5 to 200 by a constant ratio)."""
    if lambda_points:
        from ..lookup.table2d import log_lambda_grid

        lams = log_lambda_grid(lambda_min, lambda_max, lambda_points)
        return lams, f"{lambda_min:g}..{lambda_max:g} log-spaced ({len(lams)} values)"
    from ..lookup.bspline_build import lambda_grid

    lams = lambda_grid(lambda_min, lambda_max, lambda_step)
    return lams, f"{lambda_min:g}..{lambda_max:g} step {lambda_step:g} ({len(lams)} rows)"


def _build_table_2d(lams, lam_text, settings, eta_list, eta_min, eta_max, eta_step, workers, scheduler,
                    resume, output, table_format, quiet) -> None:
    """build-table over a λ × η grid (table2d.run_build_2d): checkpoint, resume and executors as the 1-D build."""
    import time

    from ..model.errors import TableError
    from ..lookup.table2d import eta_grid, format_table_2d, parse_eta_list, run_build_2d

    if table_format is TableFormat.json:
        raise TableError("format = json: a 2-D (λ, η) table is written as csv or st")
    if eta_list is not None:
        etas = parse_eta_list(eta_list)
        eta_text = ",".join(f"{e:g}" for e in etas)
    else:
        lo = eta_min if eta_min is not None else eta_max
        hi = eta_max if eta_max is not None else eta_min
        etas = eta_grid(lo, hi, eta_step)
        eta_text = f"{lo:g}..{hi:g} step {eta_step:g}"
    ckpt = _checkpoint_for(output, resume, workers)
    from ..lookup.checkpoint import checkpoint_lock

    with checkpoint_lock(ckpt):  # one run at a time owns OUTPUT.partial.jsonl, from its first read to its removal
        _note_checkpoint_on_sigterm(ckpt)
        total = len(lams) * len(etas)
        t0 = time.perf_counter()
        with contextlib.ExitStack() as stack:
            executor, n_workers, tick = _engine(stack, scheduler, workers, quiet, total, "(λ, η)", eta=True)
            try:
                table, report = run_build_2d(lams, etas, settings, progress=tick, workers=n_workers, executor=executor,
                                             checkpoint=ckpt, resume=resume)
            except KeyboardInterrupt:
                if ckpt is not None and ckpt.exists():
                    sys.stderr.write(f"pickplace: finished rows are saved in {ckpt}; run the same command with --resume\n")
                raise
        seconds = time.perf_counter() - t0
        extra = {
            "lambda_grid": lam_text,
            "eta_grid": f"{eta_text} ({len(etas)} values)",
            "optimiser": "coarse grid + bounded Nelder-Mead from each grid local optimum within basin_margin (one per basin); exact peaks",
        }
        if table_format is TableFormat.st:
            from ..export.table2d_st import format_table_2d_st

            text = format_table_2d_st(table, __version__, extra, dialect=_ST_DIALECT[0])
        else:
            text = format_table_2d(table, __version__, extra)
        _write_table(output, text, ckpt, total)
        if ckpt is not None:
            ckpt.unlink(missing_ok=True)
        if not quiet:
            resumed = f"; {report.resumed} resumed from {ckpt}, {report.computed} computed" if report.resumed else ""
            jumps = table.jumps
            sys.stderr.write(f"{total} rows ({len(etas)} η × {len(lams)} λ){resumed} in {seconds:.1f} s; "
                             f"{len(jumps)} grid edge(s) with a basin jump (listed in the header)\n")


def _write_table(output: str, text: str, ckpt, rows: int) -> None:
    """The finished table to ``output`` (atomically); when that fails (a full disk) the error also says that the
    finished rows stay in the checkpoint for a --resume, which then only writes the table."""
    from ..export import atomic_output
    from ..model.errors import ExportError

    try:
        with atomic_output(output) as stream:
            stream.write(text)
    except ExportError as exc:
        if ckpt is None or not ckpt.exists():
            raise
        raise ExportError(f"{exc}; the {rows} finished rows are kept in {ckpt}: run the same command with --resume "
                          "once the output can be written") from None


def _checkpointed_rows(ckpt, settings) -> int:
    """Rows saved in a build-table checkpoint (0 when there is none or it cannot be read)."""
    from ..model.errors import PickplaceError
    from ..lookup.bspline_build import read_checkpoint

    try:
        return len(read_checkpoint(ckpt, settings)) if ckpt is not None else 0
    except PickplaceError:
        return 0


def _build_vel_table(eta: float, workers: int, output: str, quiet: bool) -> None:
    """build-table --method bspline-vel: Yang 2022 optima on the default dimensionless grid."""
    from ..model.errors import TableError
    from ..export import atomic_output, check_writable
    from ..lookup.vel_table import VelGrid, build_vel_table, format_vel_table

    if workers < 0:
        raise TableError(f"workers = {workers}: must be 0 (all cores) or a positive number")
    check_writable(output)
    grid = VelGrid(eta=eta)
    from .guards import available_cores

    n_workers = workers or available_cores()
    if quiet:
        table = build_vel_table(grid, workers=n_workers)
    else:
        from .render import console
        from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

        with Progress(TextColumn("{task.description}"), BarColumn(), TextColumn("{task.completed}/{task.total}"),
                      TimeElapsedColumn(), TimeRemainingColumn(), console=console(stderr=True)) as progress:
            bar = progress.add_task("solving Yang 2022 optima (one node per symmetry orbit)", total=None)
            table = build_vel_table(grid, workers=n_workers,
                                    progress=lambda done, total: progress.update(bar, completed=done, total=total))
    with atomic_output(output) as stream:
        stream.write(format_vel_table(table, __version__))


def _note_checkpoint_on_sigterm(ckpt) -> None:
    """SIGTERM stops a build at once (:func:`~pickplace_cli.cli.app._on_sigterm`): it then says where the finished
    rows are, as Ctrl-C does."""
    if ckpt is not None:
        from .app import _TERM_NOTES

        _TERM_NOTES.append(f"pickplace: finished rows are saved in {ckpt}; run the same command with --resume\n")


def _checkpoint_for(output: str, resume: bool, workers: int):
    """The checkpoint file of a build writing ``output`` (None to stdout), after the checks every build makes:
    workers ≥ 0, --resume needs a file, the file is writable."""
    from ..lookup.bspline_build import checkpoint_path
    from ..model.errors import TableError

    if workers < 0:
        raise TableError(f"workers = {workers}: must be 0 (all cores) or a positive number")
    to_file = output != "-"
    if resume and not to_file:
        raise TableError("--resume: needs -o FILE (the partial results live in FILE.partial.jsonl)")
    if not to_file:
        return None
    from ..export import check_writable

    check_writable(output)
    return checkpoint_path(output)


def _engine(stack: contextlib.ExitStack, scheduler, workers: int, quiet: bool, total: int, unit: str, eta: bool,
            label: str = "optimising k1, k2"):
    """(executor or None, workers, progress callback or None) of a build (or a line sweep: ``label``): a Dask
    cluster when ``scheduler`` is given, else ``workers`` local processes (0: all cores); a rich progress bar on
    stderr unless ``quiet``."""
    from .guards import available_cores

    n_workers = workers or available_cores()
    executor = None
    if scheduler:
        from ..lookup.executors import dask_executor

        executor, n_workers = stack.enter_context(dask_executor(scheduler))
    if quiet:
        return executor, n_workers, None
    from .render import console
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

    columns = [TextColumn("[progress.description]{task.description}"), BarColumn(),
               TextColumn("{task.completed}/{task.total} " + unit), TimeElapsedColumn()]
    if not eta:
        columns.append(TimeRemainingColumn())
    progress = stack.enter_context(Progress(*columns, console=console(stderr=True), transient=False))
    engine = f"Dask {scheduler}" if scheduler else f"{n_workers} process{'es' if n_workers > 1 else ''}"
    bar = progress.add_task(f"{label} ({engine})", total=total)

    def tick(n_done: int, n_total: int) -> None:
        progress.update(bar, completed=n_done, total=n_total)

    return executor, n_workers, tick
