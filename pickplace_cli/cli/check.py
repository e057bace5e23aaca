"""`pickplace check`: check a trajectory file (this tool's CSV or another tool's) against a profile's limits."""

from __future__ import annotations

import sys
from typing import Optional

import typer

from .app import Panel, TableEnd, _handle_errors, app
from .render import _print_limit_table, _print_verdict


@app.command()
@_handle_errors
def check(
    trajectory: str = typer.Argument(
        ..., metavar="TRAJECTORY",
        help="CSV with a header holding t [s] (or t[ms], t[us]) and q1 … qn [rad or m] (this tool's CSV works, also "
        "--batch and --round-trip output); or, with the profile's controller.joints, t and the drives' columns in "
        "their units (plan --columns plc, any dialect with a header), or a pvt, cam or cam-table table, CSV or "
        "Structured Text (plan --format pvt|cam|cam-table and their -st forms, time master; integer PVT in counts; "
        "the CODESYS/TwinCAT cam objects of --cam-object), or plan --format json; '-' = stdin. A file without a "
        "move column that ends where it starts is judged as the whole duty cycle (RMS over the file). MCAP and "
        "PLCopen XML are not read.",
    ),
    profile: Optional[str] = typer.Option(None, "--profile", "-p", help="Profile YAML file or shipped name. [default: delta-su2018]", rich_help_panel=Panel.LIMITS),
    smoothing: str = typer.Option(
        "0", "--smoothing", metavar="M2|auto",
        help="Smoothing factor per sample, in m² of the tool position (0 = interpolate exactly, for planned "
        "trajectories; for measured, noisy data 'auto' takes the square of the noise level estimated from the "
        "samples). Smoothing lowers the peaks of rates: each peak's accuracy then includes the gap to the "
        "unsmoothed data's, and a rate peak the data cannot pin down is reported as not resolved.",
        rich_help_panel=Panel.LIMITS,
    ),
    limit_use: Optional[float] = typer.Option(
        None, "--limit-use", metavar="FRACTION", help="Hold every timed limit to this fraction of its rating, in "
        "(0, 1] (as plan --limit-use). [default: profile planning.limit_use, else 1]",
        rich_help_panel=Panel.LIMITS,
    ),
    strict: bool = typer.Option(
        False, "--strict", help="Exit 3 also when a peak is not resolved by the samples (its accuracy is worse than "
        "1 % of the limit and it may be beyond it), not only when the data shows a limit exceeded; and exit 1 for a "
        "file whose derivative columns (vx … jz) disagree with its positions, instead of judging it from its "
        "positions with a warning.",
        rich_help_panel=Panel.LIMITS,
    ),
    hold_capacity: bool = typer.Option(
        True, "--hold-capacity/--no-hold-capacity",
        help="Hold the profile's Cartesian capacity: the tool's |v| <= capacity.velocity [m/s], |a| <= "
        "capacity.acceleration [m/s²] (and |j| <= capacity.jerk [m/s³] when set), from the file's x, y, z "
        "columns (else forward kinematics of the joints), at the limit use. --no-hold-capacity: a trajectory "
        "planned with plan --time fit or optimal (joint and motor limits alone): the capacity rows are still "
        "reported, marked not held, and an exceeded capacity does not fail the check (exit 0).",
        rich_help_panel=Panel.LIMITS,
    ),
    cycle: Optional[str] = typer.Option(
        None, "--cycle", metavar="SECONDS", help="The controller cycle in s a drive's table runs at (as plan "
        "--cycle): a cam-table's straight lines are read once per cycle, each velocity step blended over one cycle, "
        "and a PVT or cam-table's acceleration steps (the ends from and to rest too) are taken within one cycle, so "
        "each motor torque step plus the torque's change at its rate over that cycle is held to the torque rate "
        "limit [N·m/s] × the cycle. Not used for other files (a "
        "warning says so). [default: profile controller.cycle, else the period of profile planning.rate, as plan]",
        rich_help_panel=Panel.CONTROLLER,
    ),
    table_end: TableEnd = typer.Option(
        TableEnd.hold, "--table-end", rich_help_panel=Panel.CONTROLLER,
        help="A drive's table that starts or ends moving (as plan --table-end): hold (the drive holds the end point: "
        "the velocity step to or from rest within one controller cycle is judged) or continue (the controller goes "
        "on at the end's velocity, e.g. geared to the belt: not judged past the end). Not used for other files."),
    report: Optional[str] = typer.Option(None, "--report", help="Also write the limit report as JSON to this file.", rich_help_panel=Panel.OUTPUT),
    report_only: bool = typer.Option(False, "--report-only", help="Exit 0 even when a limit is exceeded.", rich_help_panel=Panel.OUTPUT),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="Only violations, warnings and errors on stderr.", rich_help_panel=Panel.OUTPUT),
) -> None:
    """Check an existing joint trajectory against a profile's limits (exit 3 if a limit is exceeded).

    Joint positions go through forward kinematics; a quintic spline of the tool positions gives the
    derivatives (split at the jerk steps found in the data, each side checked: the report says so), then the
    same dynamics and limit check as `plan`. Joint positions are checked as given (q1 = 5 rad is 5 rad, not
    wrapped). Every duration-dependent peak is estimated twice, from all samples and from every other one: the
    difference, and at least 0.1 % of the peak, is its accuracy (the "± %" column); a limit counts as exceeded when the peak less its accuracy is
    beyond it, so a trajectory `plan` wrote as within its limits passes (`plan --time optimal` reads its own samples
    this way and slows the law until they pass), and one 1 % faster fails. Known
    exception, on the safe side: positions alone (a positions-only file) of a `--time optimal` law at 1 kHz can read
    a torque-rate peak high across the law's jerk steps (up to 21 % measured), and are then refused.

    A file's tool derivative columns (vx … jz [m/s, m/s², m/s³]) are used only where they agree with its
    positions (velocity within 1 %, acceleration 10 % of their peak on every interval, jerk 5 % on the median
    one); otherwise the move is judged from its positions, with a one-line warning. With the profile's
    controller.joints the drive's files are read in its names and units (d = sign·k·(q − offset) undone), and a PVT
    table is judged as the drive's cubic Hermite, a cam as the quintic through position, velocity and acceleration,
    a cam-table as straight lines read once per controller cycle (--cycle), each velocity step blended over that
    cycle; a PVT or cam-table's acceleration steps (with the torque's change over the cycle that takes them) are held to the torque rate × the
    cycle, as plan holds them.

    The tool's Cartesian capacity (speed, acceleration, jerk of x, y, z) is checked too, as `plan` does under its
    default rule; a trajectory planned with `plan --time fit` or `optimal` (joint and motor limits alone) is
    checked under the same rule with --no-hold-capacity.

    A file with a `move` column (`plan --batch` or `--round-trip` output) is checked move by move: each
    move gets its own limit table and verdict, and the exit code is the worst of them. Samples at the end
    of a move that repeat its last position (a round trip's dwell) are the dwell, not part of the move.
    """
    import json

    from ..pipelines.check import check_file
    from ..model.errors import TaskError
    from ..export import atomic_output
    from ..model.profile import load_profile

    smooth: float | str = smoothing.strip().lower()
    if smooth != "auto":
        try:
            smooth = float(smooth)
        except ValueError:
            raise TaskError(f"smoothing = {smoothing!r}: give a number of m² per sample >= 0, or auto") from None
        if not (smooth >= 0 and smooth < float("inf")):
            raise TaskError(f"smoothing = {smoothing!r}: must be a finite number >= 0 (m² per sample), or auto")
    if limit_use is not None:
        from ..model.headroom import check_limit_use

        check_limit_use(limit_use)
    seconds = None
    if cycle is not None:
        from ..timing.cycle import check_cycle

        seconds = check_cycle(cycle)
    from .guards import refuse_overwriting_inputs

    refuse_overwriting_inputs([("--report", report)], [("TRAJECTORY", trajectory)], profile)
    prof = load_profile(profile)
    checks = check_file(trajectory, prof, smooth, limit_use,
                        notify=lambda text: sys.stderr.write(f"pickplace: {text}\n"), strict=strict,
                        warn=lambda text: sys.stderr.write(f"pickplace: {text}\n"), hold_capacity=hold_capacity,
                        cycle=seconds, table_end=table_end.value)
    several = len(checks) > 1 or checks[0].move is not None
    if report is not None:
        with atomic_output(report) as stream:
            if several:
                doc = {"profile": prof.name, "moves": [
                    {"move": c.move, "lines": [c.first_line, c.last_line], "step_cycle_s": c.cycle,
                     "limits": c.report.as_dict()} for c in checks
                ]}
            else:  # step_cycle_s: the controller cycle a table's steps were held over (null: not a pvt or cam-table)
                doc = {"profile": prof.name, "step_cycle_s": checks[0].cycle, "table_end": table_end.value,
                       "limits": checks[0].report.as_dict()}
            json.dump(doc, stream, indent=2, default=float)
            stream.write("\n")
    for c in checks:
        rep = c.report
        if several and (not quiet or not rep.all_ok):
            sys.stderr.write(f"--- move {c.move} (lines {c.first_line}–{c.last_line}) ---\n")
        if not quiet:
            for note in rep.notes:
                sys.stderr.write(f"{note}\n")
            _print_limit_table(rep)
        _print_verdict(rep, quiet, with_cycle=not several)
    code = max(c.report.exit_code() for c in checks)
    bad = [r for c in checks for r in c.report.violations]
    on_cycle = _step_cycle(checks) if bad else None  # a table judged on a cycle: its verdict depends on the cycle
    if on_cycle is not None and seconds is None:
        given = ("the profile's controller.cycle" if getattr(prof.controller, "cycle", None) else
                 "from the profile's planning.rate, as plan without --cycle or --rate")
        sys.stderr.write(f"pickplace: hint: the table is judged on a controller cycle of {on_cycle:.9g} s ({given}): "
                         "its verdict depends on the cycle; give the one the drive runs it at with --cycle SECONDS "
                         "(plan's table summary names it when it differs)\n")
    elif bad and smooth == 0 and any("carry noise" in n for c in checks for n in c.report.notes):
        sys.stderr.write("pickplace: hint: the positions carry noise (whole encoder counts, a few decimals, a "
                         "measurement) that their derivatives amplify: a peak read past its limit may be the noise's; "
                         "check with --smoothing auto\n")
    elif hold_capacity and bad and all(r.quantity.startswith("capacity") for r in bad):
        sys.stderr.write("pickplace: hint: only the Cartesian capacity is exceeded; if the file was planned with --time "
                         "fit or optimal (which hold the joint and motor limits alone, not the capacity), check it with "
                         "--no-hold-capacity; under plan's default rule the capacity is held, and this excess is real\n")
    elif on_cycle is not None and any(r.quantity == "motor torque step" for r in bad):
        sys.stderr.write(f"pickplace: hint: each step is held to the torque rate over one controller cycle of "
                         f"{on_cycle:g} s (--cycle): the drive must take it within one cycle\n")
    if strict and not code and any(c.report.unresolved for c in checks):
        code = 3
    if several and not quiet:
        bad = sum(not c.report.ok for c in checks)
        loose = sum(c.report.ok and not c.report.all_ok for c in checks)
        within = "within every limit held" if loose else "within every limit"
        more = f", {loose} of them exceed the Cartesian capacity (not held: --no-hold-capacity)" if loose else ""
        sys.stderr.write(
            f"checked {len(checks)} move(s): {len(checks) - bad} {within}{more}, {bad} exceed one\n"
        )
    if code and not report_only:
        raise typer.Exit(code)


def _step_cycle(checks) -> float | None:
    """The controller cycle [s] a checked table's steps were held over, None for a file that is not a PVT or
    cam-table table."""
    return next((c.cycle for c in checks if c.cycle is not None), None)
