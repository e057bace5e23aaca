"""`pickplace compare`: every method on one move, side by side."""

from __future__ import annotations

import sys
from enum import Enum
from typing import Optional

import typer

from .app import Panel, _err, _handle_errors, _task_from_options, app
from .render import _print_comparison


class CompareFormat(str, Enum):
    table = "table"
    csv = "csv"
    json = "json"


@app.command()
@_handle_errors
def compare(
    ctx: typer.Context,
    from_: str = typer.Option(..., "--from", help="Pick point X,Y,Z in m (base frame).", rich_help_panel=Panel.MOVE),
    to: str = typer.Option(..., "--to", help="Place point X,Y,Z in m (base frame).", rich_help_panel=Panel.MOVE),
    methods: str = typer.Option("all", "--methods", "-m", help="'all' or method names separated by commas.", rich_help_panel=Panel.STUDY),
    profile: Optional[str] = typer.Option(None, "--profile", "-p", help="Profile YAML file or shipped name. [default: delta-su2018]", rich_help_panel=Panel.MOVE),
    height: Optional[float] = typer.Option(None, "--height", help="Clearance h in m above the higher end point. [default: profile]", rich_help_panel=Panel.MOVE),
    eta: Optional[float] = typer.Option(None, "--eta", help="Lift-off/set-down ratio η, 0 < η < 1. [default: profile]", rich_help_panel=Panel.MOVE),
    time: str = typer.Option("limits", "--time", "-t", help="Duration for the peaks and torques: 'limits' (every limit "
                             "of the profile holds: joint and motor limits and the Cartesian capacity), 'auto' (the "
                             "capacity alone, Li 2018 Eq. 26), 'fit' (joint and motor limits alone), 'optimal' "
                             "(non-uniform time law) or seconds.", rich_help_panel=Panel.METHOD),
    fmt: CompareFormat = typer.Option(CompareFormat.table, "--format", "-f", help="table (stderr only), csv or json (stdout or -o). [default: from -o's suffix (.csv, .json), else table]", rich_help_panel=Panel.OUTPUT),
    output: str = typer.Option("-", "--output", "-o", help="Output file for csv/json ('-' = stdout). Written atomically.", rich_help_panel=Panel.OUTPUT),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No table on stderr with csv/json (errors still print).", rich_help_panel=Panel.OUTPUT),
) -> None:
    """Compare every planning method on one move: durations (auto, fit, the paper's formula), normalised
    and true peaks, joint torque and torque-rate use, height, overshoot, drift, continuity class, residual
    vibration. Exit 0 when at least one method planned (limits exceeded are shown, not fatal); otherwise
    the first method's error code.
    """
    from ..studies.compare import compare_methods, write_compare_csv, write_compare_json
    from ..model.errors import ExportError
    from ..export import atomic_output, check_writable

    from .guards import suffix_format

    fmt = suffix_format(ctx, fmt, output, {".csv": "csv", ".json": "json"}, "fmt")
    if fmt == CompareFormat.table and output != "-":
        raise ExportError(f"output = {output}: --format table prints to stderr; use --format csv or json to write a file")
    check_writable(output)
    from .guards import refuse_overwriting_inputs

    refuse_overwriting_inputs([("-o", output)], [], profile)
    prof, task = _task_from_options(from_, to, profile, height, eta)
    result = compare_methods(task, prof, methods, time=time)
    for r in result.rows:
        if not r.ok:
            sys.stderr.write(f"pickplace: method {r.method}: {r.error}\n")
    if not result.ok_rows:
        _err("no method could plan this move")
        raise typer.Exit(result.rows[0].exit_code or 1)
    if fmt == CompareFormat.table or not quiet:
        _print_comparison(result)
    if fmt != CompareFormat.table:
        writer = write_compare_csv if fmt == CompareFormat.csv else write_compare_json
        with atomic_output(output) as stream:
            writer(result, stream)
