"""Command-line interface: parse → call the library → render. The only module that prints or exits.

Exit codes: 0 success · 1 invalid input (profile, table, values) · 2 usage error ·
3 a limit is exceeded · 4 a point of the move is unreachable / outside the workspace.

Heavy modules (numpy, scipy, pydantic, rich) are imported inside the commands so that ``--help`` and
``--version`` stay fast.
"""

from __future__ import annotations

import functools
import sys
from enum import Enum
from typing import Callable, Optional

import typer

from . import __version__

app = typer.Typer(
    name="pickplace",
    help=(
        "Plan smooth, fast pick-and-place moves for high-speed robots and write the sampled joint "
        "trajectories (SI units: m, s, rad). Exit codes: 0 ok, 1 invalid input, 2 usage error, "
        "3 limit exceeded, 4 unreachable point."
    ),
    no_args_is_help=True,
    add_completion=True,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,
    context_settings={"help_option_names": ["-h", "--help"]},
)


class OutputFormat(str, Enum):
    csv = "csv"
    json = "json"
    mcap = "mcap"


class CsvDialectName(str, Enum):
    """Mirror of pickplace_cli.export.csv.CsvDialect."""

    default = "default"
    twincat = "twincat"
    tsv = "tsv"


class TableMethod(str, Enum):
    bspline = "bspline"
    bspline_vel = "bspline-vel"


class McapFlavor(str, Enum):
    ros2 = "ros2"
    foxglove = "foxglove"


#: --max-shift default [m]
MAX_SHIFT = 0.01


class Compression(str, Enum):
    none = "none"
    zstd = "zstd"


class MethodName(str, Enum):
    """Mirror of pickplace_cli.methods.Method (kept here so --help needs no numpy)."""

    bspline = "bspline"
    ph = "ph"
    superposition = "superposition"
    lame = "lame"
    piecewise_poly = "piecewise-poly"
    bspline_vel = "bspline-vel"


class OptimizeWhat(str, Enum):
    none = "none"
    shape = "shape"


def _err(message: str) -> None:
    sys.stderr.write(f"pickplace: error: {message}\n")


def _handle_errors(fn: Callable) -> Callable:
    """Turn the library's typed errors into one line on stderr and the documented exit code."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        from .errors import PickplaceError

        _JSON_ERRORS[0] = False
        try:
            return fn(*args, **kwargs)
        except PickplaceError as exc:
            _err(str(exc))
            if _JSON_ERRORS[0]:  # `plan --json`: stdout still carries one JSON document, like a batch row's
                import json

                sys.stdout.write(json.dumps({"exit_code": exc.exit_code, "error": str(exc)}) + "\n")
            raise typer.Exit(exc.exit_code) from None
        except KeyboardInterrupt:
            _err("interrupted; no output file was changed")
            raise typer.Exit(130) from None
        except BrokenPipeError:
            # the reader went away (e.g. `| head`): not an error of ours
            try:
                sys.stdout = None  # type: ignore[assignment]
            finally:
                raise typer.Exit(0) from None

    return wrapper


#: set by `plan --json` (one move or a round trip) once its options are read: an error after that also
#: goes to stdout as {"exit_code", "error"}, so a script reading the summary always gets a JSON document
_JSON_ERRORS = [False]


def _version_callback(value: bool) -> None:
    if value:
        typer.echo(f"pickplace {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: bool = typer.Option(
        False, "--version", callback=_version_callback, is_eager=True, help="Print the version and exit."
    ),
) -> None:
    """pickplace: smooth pick-and-place trajectories (Li 2018 quintic B-splines) checked for a robot."""


def _usage(message: str) -> None:
    """A usage error (exit 2), reported like any other misuse of the options."""
    raise typer.BadParameter(message)


def _parse_point(name: str, text: str, unit: str = "m"):
    from .errors import TaskError

    words = "metres" if unit == "m" else unit
    what = "coordinates" if unit == "m" else "components"
    parts = [p.strip() for p in text.split(",")]
    if len(parts) != 3 or not all(parts):
        example = "-0.1525,0,-0.8" if unit == "m" else "0,0.2,0"
        raise TaskError(f"{name} = {text!r}: give three {what} X,Y,Z in {words}, e.g. {example}")
    try:
        values = [float(p) for p in parts]
    except ValueError:
        raise TaskError(f"{name} = {text!r}: every {what[:-1]} must be a number in {words}") from None
    import math

    if not all(math.isfinite(v) for v in values):
        raise TaskError(f"{name} = {text!r}: every coordinate must be a finite number (no NaN or inf)")
    return values


def _finite(name: str, value: Optional[float], rule: str = "> 0") -> Optional[float]:
    import math

    from .errors import TaskError

    if value is None:
        return None
    if not math.isfinite(value) or (rule == "> 0" and value <= 0):
        raise TaskError(f"{name} = {value!r}: must be a finite number {rule}")
    return value


def _complete_profile(incomplete: str) -> list[str]:
    """Shell completion for --profile: the shipped profile names (files complete by the shell)."""
    try:
        from .resources import data_dir

        names = sorted(p.stem for p in data_dir("profiles").glob("*.yaml"))
    except Exception:  # completion must never fail loudly
        return []
    return [n for n in names if n.startswith(incomplete)]


@app.command()
@_handle_errors
def plan(
    ctx: typer.Context,
    from_: Optional[str] = typer.Option(None, "--from", help="Pick point X,Y,Z in m (base frame), e.g. -0.1525,0,-0.8."),
    to: Optional[str] = typer.Option(None, "--to", help="Place point X,Y,Z in m (base frame)."),
    profile: Optional[str] = typer.Option(
        None, "--profile", "-p", help="Profile YAML file, or the name of a shipped profile. [default: delta-su2018]",
        autocompletion=_complete_profile,
    ),
    height: Optional[float] = typer.Option(
        None, "--height", help="Clearance h in m of the path's midpoint above the higher end point. [default: profile]"
    ),
    eta: Optional[float] = typer.Option(
        None, "--eta", help="Lift-off/set-down ratio η, 0 < η < 1 (dimensionless). [default: profile]"
    ),
    v_from: Optional[str] = typer.Option(
        None, "--v-from", "--from-belt", help="Tool velocity VX,VY,VZ in m/s (base frame) leaving the pick point, e.g. the pick "
        "conveyor's (--method bspline-vel). [default: profile workcell.conveyor_pick_velocity, else 0]"
    ),
    v_to: Optional[str] = typer.Option(
        None, "--v-to", help="Tool velocity VX,VY,VZ in m/s arriving at the place point (--method bspline-vel). "
        "[default: profile workcell.conveyor_place_velocity, else 0]"
    ),
    to_belt: Optional[str] = typer.Option(
        None, "--to-belt", help="Conveyor rendezvous: the part at --to (m, when it was detected) moves at VX,VY,VZ m/s "
        "(base frame); the move meets it where it is after --latency + T and arrives with this velocity, then tracks it "
        "for the profile's dwell (s). Selects --method bspline-vel.",
    ),
    latency: Optional[float] = typer.Option(
        None, "--latency", help="With --to-belt: seconds (>= 0) from the part's detection to the start of the move "
        "(vision + planning + bus); the trajectory's t = 0 is the start of the move. [default: 0]",
    ),
    method: MethodName = typer.Option(MethodName.bspline, "--method", "-m", help="Planning method."),
    k1: Optional[float] = typer.Option(None, "--k1", help="B-spline time-ratio factor k1 = τ8/τ9 (overrides the table)."),
    k2: Optional[float] = typer.Option(None, "--k2", help="B-spline time-ratio factor k2 = τ7/τ8 (overrides the table)."),
    table: Optional[str] = typer.Option(
        None, "--table", help="bspline: λ → (k1, k2) table CSV; bspline-vel: conveyor table that seeds the exact "
        "solve. [default: shipped table]"
    ),
    param: Optional[list[str]] = typer.Option(
        None, "--param", help="A method parameter NAME=VALUE (repeatable): ph m=, r= (corner extents in m); "
        "lame m= (exponent, >= 3); piecewise-poly ratio= (τv/τu); bspline-vel margin=, tau6= … lambda3=. "
        "[default: the paper's values]",
    ),
    time: str = typer.Option(
        "auto",
        "--time",
        "-t",
        help="Duration of the move in s, or 'auto' (from the profile's Cartesian capacity, Li 2018 Eq. 26), "
        "or 'fit' (the smallest duration at which every joint and motor limit holds, path scaled uniformly in time), "
        "or 'optimal' (the same path with a non-uniform, jerk-bounded time law that minimises the duration under the "
        "same joint and motor limits, RMS included; ~0.3 s more; not for bspline-vel).",
    ),
    optimize: OptimizeWhat = typer.Option(
        OptimizeWhat.none, "--optimize", help="'shape' (--method bspline): also choose the path's k1, k2 and η "
        "(η within [0.1, 0.9]; give --eta to hold it) for the smallest duration on this robot's limits, instead of "
        "the table's values (Li 2018's Cartesian optimum); with --time fit or optimal (the fit and the law are then "
        "those of the chosen shape). The summary compares it with the table's shape. ~0.5-1 s more.",
    ),
    hold_capacity: bool = typer.Option(
        False, "--hold-capacity", help="With --time fit or optimal (and --optimize shape): also hold the profile's "
        "Cartesian capacity |v| ≤ capacity.velocity [m/s], |a| ≤ capacity.acceleration [m/s²] (and |j| ≤ capacity.jerk "
        "[m/s³] when set), e.g. for a payload or gripper that limits the tool. Default: off, fit and optimal hold "
        "the joint and motor limits only (auto holds the capacity only).",
    ),
    show_fit: bool = typer.Option(
        False, "--show-fit", help="With --time auto or seconds: also compute the fitted duration (the smallest at "
        "which every joint and motor limit holds) and report it next to the chosen one (fit_s in --json). Costs "
        "~0.5 s of start-up (scipy.optimize); --time fit always computes it.",
    ),
    rate: Optional[float] = typer.Option(None, "--rate", help="Samples per second in Hz. [default: profile]"),
    batch: Optional[str] = typer.Option(
        None, "--batch", help="Plan many moves from a CSV ('-' = stdin or a named pipe: streamed, each row answered "
        "and flushed as soon as it is read): columns from_x,from_y,from_z,to_x,to_y,to_z "
        "[m], optional height [m], eta, v_from_x.. v_to_z [m/s], time [s|auto|fit|optimal]. Output gets a move column."
    ),
    fail_fast: bool = typer.Option(False, "--fail-fast", help="With --batch: stop at the first row that fails."),
    workers: int = typer.Option(
        0, "--workers", "-j", help="With --batch: planner processes (0 = all cores for 100 rows or more, else 1). "
        "Results are the same and in row order whatever the number."
    ),
    round_trip: bool = typer.Option(
        False, "--round-trip", help="Write there, dwell, back, dwell (the profile's dwell in s) as one trajectory."
    ),
    fmt: OutputFormat = typer.Option(OutputFormat.csv, "--format", "-f", help="Output format."),
    csv_dialect: CsvDialectName = typer.Option(
        CsvDialectName.default, "--csv-dialect",
        help="CSV flavour: default (',' LF, header), twincat (';' CRLF, header), tsv (tab, no header).",
    ),
    mcap_flavor: McapFlavor = typer.Option(
        McapFlavor.ros2, "--mcap-flavor", help="MCAP: ros2 (CDR, ROS 2 messages) or foxglove (JSON, Foxglove schemas)."
    ),
    compression: Compression = typer.Option(Compression.none, "--compression", help="MCAP chunk compression."),
    output: Optional[str] = typer.Option(
        None, "--output", "-o", help="Output file ('-' = stdout, the default without --json). Written atomically."
    ),
    report: Optional[str] = typer.Option(None, "--report", help="Also write the limit report as JSON to this file."),
    report_only: bool = typer.Option(
        False,
        "--report-only",
        help="Write the trajectory and exit 0 even when a limit is exceeded (the report still says so). "
        "Without it, a move that breaks a limit is not written.",
    ),
    json_summary: bool = typer.Option(
        False, "--json", help="Print a JSON summary (durations in s, cycle time, picks/min, verdict) on stdout "
        "instead of the trajectory (one line per row with --batch); the trajectory then goes only to -o FILE.",
    ),
    fit_ws: bool = typer.Option(
        False, "--fit-workspace", help="If the path leaves the workcell box or the reachable set, lower the height "
        "in 1 mm steps until it fits (Su 2018 Sec. II.E) and say what changed."
    ),
    adjust_points: bool = typer.Option(
        False, "--adjust-points", help="With --fit-workspace: move a pick/place point that lies outside to the nearest "
        "inside point by Su 2018's potential field (Eq. 25), and report the distance. Never done silently."
    ),
    max_shift: float = typer.Option(
        MAX_SHIFT, "--max-shift", help="With --adjust-points: the largest allowed move of a point in m (farther: exit 4)."
    ),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="Nothing on stderr but errors and exceeded limits."),
) -> None:
    """Plan one move (or a round trip, or a batch), check it against the robot's limits, write the samples.

    CSV columns: t[s], x y z [m], vx… [m/s], ax… [m/s^2], jx… [m/s^3], then per joint q<i>, qd<i>, qdd<i>,
    then torque<i> (joint side, N·m or N), motor_speed<i> [rad/s], motor_torque<i> [N·m]; a batch or round
    trip adds a leading move column. Exit 3 when a limit is exceeded, 4 when a point is unreachable or
    outside the workcell, 1 for invalid input; a batch exits with the highest code of its rows.
    """
    from .errors import TaskError
    from .planner import PlanOptions
    from .profile import load_profile

    _JSON_ERRORS[0] = json_summary and batch is None  # a batch prints its own line per row
    _finite("height", height)
    _finite("rate", rate)
    if rate is not None and not (0 < rate <= 1e6):
        raise TaskError(f"rate = {rate!r} Hz: the output rate must lie in (0, 1e6] Hz (as the profile's planning.rate)")
    if k1 is not None or k2 is not None:
        from .methods.bspline import check_k

        for name, k in (("k1", k1), ("k2", k2)):
            if k is not None:
                check_k(name, k)
    if eta is not None and not (0 < eta < 1):
        raise TaskError(f"eta = {eta!r}: the lift-off/set-down ratio η must lie strictly between 0 and 1")
    if batch is not None and (from_ is not None or to is not None):
        _usage("--batch takes the moves from the file; do not also give --from/--to")
    if batch is None and (from_ is None or to is None):
        _usage(f"missing --{'to' if from_ is not None else 'from'}: give both --from X,Y,Z and --to X,Y,Z in m (or --batch FILE)")
    if batch is not None and round_trip:
        _usage("--round-trip is not available with --batch (give each leg as a row)")
    # an option set to anything but its default where it has no effect is a mistake: refused, not ignored
    if batch is None and (fail_fast or workers != 0):
        _usage(f"{'--fail-fast' if fail_fast else '-j/--workers'} only applies to --batch")
    if batch is not None and (v_from is not None or v_to is not None):
        _usage("--v-from/--v-to: with --batch give the velocities of each row as columns v_from_x … v_to_z")
    if fmt != OutputFormat.mcap and (mcap_flavor != McapFlavor.ros2 or compression != Compression.none):
        what = f"--mcap-flavor {mcap_flavor.value}" if mcap_flavor != McapFlavor.ros2 else f"--compression {compression.value}"
        _usage(f"{what} only applies to --format mcap (the format is {fmt.value})")
    if fmt != OutputFormat.csv and csv_dialect != CsvDialectName.default:
        _usage(f"--csv-dialect {csv_dialect.value} only applies to --format csv (the format is {fmt.value})")
    if json_summary and output is None and (fmt != OutputFormat.csv or csv_dialect != CsvDialectName.default):
        _usage("--format/--csv-dialect: with --json and no -o FILE no trajectory is written (stdout carries the summary)")
    if adjust_points and not fit_ws:
        _usage("--adjust-points only applies with --fit-workspace")
    if max_shift != MAX_SHIFT and not adjust_points:
        _usage("--max-shift only applies with --adjust-points")
    if json_summary and report == "-":
        _usage("--report -: with --json stdout carries the summary; give --report a file")
    if json_summary and output == "-":
        _usage("-o -: with --json stdout carries the summary; give -o a file for the trajectory")
    if output is None and not json_summary:
        output = "-"
    _check_output_paths(output, report)
    if to_belt is not None or latency is not None:
        method = _belt_method(ctx, method, to_belt, latency, v_to, batch, round_trip, fit_ws, optimize)
    prof = load_profile(profile)
    params: dict = _parse_params(param or [])
    if method == MethodName.bspline:
        params.update({"k1": k1, "k2": k2, "table": table})
    elif method == MethodName.bspline_vel and table is not None and k1 is None and k2 is None:
        params.update({"solver": "seeded", "table": table})  # that table seeds the exact polish
    elif k1 is not None or k2 is not None or table is not None:
        _usage(f"--k1/--k2/--table belong to --method bspline (--table also to bspline-vel), not {method.value}")
    writer = _writer(fmt, csv_dialect, mcap_flavor, compression)
    if batch is not None and fit_ws:
        _usage("--fit-workspace is not available with --batch")
    shape = optimize == OptimizeWhat.shape
    if shape and method != MethodName.bspline:
        _usage(f"--optimize shape chooses k1, k2, η of --method bspline; method {method.value} has no such shape")
    if shape and time not in ("fit", "optimal"):
        _usage(f"--optimize shape minimises the fitted duration on the robot's limits: use it with --time fit or "
               f"--time optimal (not --time {time})")
    if hold_capacity and time not in ("fit", "optimal"):
        _usage(f"--hold-capacity applies to --time fit or optimal (--time {time} "
               f"{'holds the capacity already' if time == 'auto' else 'is given'})")
    if shape and (k1 is not None or k2 is not None):
        _usage("--optimize shape chooses k1 and k2 itself: drop --k1/--k2 (or drop --optimize)")
    if batch is not None:
        options = PlanOptions(method=method.value, method_params=params, time=time, rate=rate,
                              fit=time == "fit" or show_fit, shape=shape, hold_eta=eta is not None,
                              hold_capacity=hold_capacity)
        if workers < 0:
            raise TaskError(f"workers = {workers}: must be 0 (automatic) or a positive number of processes")
        _plan_batch(batch, prof, options, height, eta, fail_fast, writer, output, report, report_only, json_summary,
                    quiet, workers)
        return
    from .task import Task

    p_from = _parse_point("from", from_)
    p_to = _parse_point("to", to)
    h = height if height is not None else prof.planning.height
    e = eta if eta is not None else prof.planning.eta
    options = PlanOptions(method=method.value, method_params=params, time=time, rate=rate, fit=time == "fit" or show_fit,
                          shape=shape, hold_eta=eta is not None, hold_capacity=hold_capacity)
    wc = prof.workcell
    vel_from = _parse_point("v-from", v_from, "m/s") if v_from is not None else (getattr(wc, "conveyor_pick_velocity", None) or (0.0, 0.0, 0.0))
    vel_to = _parse_point("v-to", v_to, "m/s") if v_to is not None else (getattr(wc, "conveyor_place_velocity", None) or (0.0, 0.0, 0.0))
    moving_ends = any(vel_from) or any(vel_to)
    if method != MethodName.bspline_vel and (v_from is not None or v_to is not None) and moving_ends:
        raise TaskError(
            f"v-from/v-to: method {method.value} plans moves from rest to rest; use --method bspline-vel "
            "for moving ends (conveyor tracking, Yang 2022)"
        )
    if method != MethodName.bspline_vel:
        vel_from = vel_to = (0.0, 0.0, 0.0)  # the profile's conveyors concern bspline-vel only
    if round_trip and moving_ends and method == MethodName.bspline_vel:
        _usage("--round-trip dwells at rest between the legs: not possible with moving ends (--v-from/--v-to)")
    task = Task(p_from, p_to, h, e, v_from=vel_from, v_to=vel_to)
    workspace_fit = None
    if fit_ws:
        from .workspace import fit_workspace

        _finite("max-shift", max_shift)
        workspace_fit = fit_workspace(task, prof, method.value, params, adjust_points=adjust_points, max_shift=max_shift)
        for line in workspace_fit.changes():
            sys.stderr.write(f"pickplace: {line}\n")
        task = workspace_fit.task
    rendezvous = track = None
    if to_belt is not None:
        legs, rendezvous, track = _plan_to_belt(p_from, p_to, to_belt, latency, prof, time, h, e, vel_from, params, rate)
    else:
        legs = [_run_plan(task, prof, options)]
    if round_trip:
        legs.append(_run_plan(Task(task.p_to, task.p_from, task.height, task.eta), prof, options))
    for i, leg in enumerate(legs):
        if not quiet:
            if round_trip:
                sys.stderr.write(f"--- move {i + 1} ({'there' if i == 0 else 'back'}) ---\n")
            _print_summary(leg)
            if rendezvous is not None and i == 0:
                _print_rendezvous(rendezvous)
            _print_limit_table(leg.report)
        _print_verdict(leg.report, quiet, with_cycle=not round_trip)
    code = max(leg.report.exit_code() for leg in legs)
    if track is not None:  # the tracking segment after the rendezvous: checked like a move
        if not quiet:
            sys.stderr.write(f"--- tracking the part: t = {rendezvous.seconds:.4f} … "
                             f"{rendezvous.seconds + track.duration.seconds:.4f} s at the belt velocity ---\n")
            _print_limit_table(track.report)
        _print_verdict(track.report, quiet, with_cycle=False)
        code = max(code, track.report.exit_code())
    dwell = prof.planning.dwell
    cycle = sum(leg.report.duration for leg in legs) + len(legs) * dwell if round_trip else legs[0].report.round_trip
    if round_trip and not quiet:
        sys.stderr.write(
            f"round trip: {legs[0].report.duration:.4f} s + {legs[1].report.duration:.4f} s + 2 × {dwell:g} s dwell "
            f"= {cycle:.4f} s, {60.0 / cycle:.1f} picks/min; {'all limits hold' if code == 0 else 'LIMITS EXCEEDED'}\n"
        )
    if report is not None:
        _write_report(legs + ([track] if track is not None else []), report)
    # the trajectory before the JSON summary: a failed write is then the one JSON document on stdout
    if output is not None and (code == 0 or report_only):
        if round_trip:
            from .timeline import round_trip as make_round_trip

            rate_hz = rate if rate is not None else prof.planning.rate
            samples = make_round_trip(legs[0], legs[1], dwell, rate_hz)
        elif track is not None:
            from .rendezvous import with_tracking

            samples = with_tracking(legs[0], track)
        else:
            samples = legs[0]
        writer(samples, output)
    if json_summary:
        doc = _json_summary(legs, cycle, code, exit_code=0 if report_only else code)
        if workspace_fit is not None:
            doc["workspace_fit"] = workspace_fit.as_dict()
        if rendezvous is not None:
            doc["rendezvous"] = rendezvous.as_dict()
            if track is not None:
                doc["tracking"] = {"t_start_s": rendezvous.seconds, "duration_s": track.duration.seconds,
                                   "limits_ok": track.report.ok,
                                   "violations": [r.as_dict() for r in track.report.violations]}
        _emit_json(doc)
    if code and not report_only:
        if output is not None:
            sys.stderr.write(
                "pickplace: trajectory not written (a limit is exceeded); --report-only writes it anyway\n"
            )
        raise typer.Exit(code)


def _parse_params(items: list[str]) -> dict:
    """--param NAME=VALUE items → {name: float}; one-line TaskError for a malformed item."""
    import math

    from .errors import TaskError

    out: dict = {}
    for item in items:
        name, sep, value = item.partition("=")
        name = name.strip()
        if not sep or not name:
            raise TaskError(f"param = {item!r}: write NAME=VALUE, e.g. --param m=0.025")
        try:
            x = float(value)
        except ValueError:
            raise TaskError(f"param {name} = {value!r}: not a number") from None
        if not math.isfinite(x):
            raise TaskError(f"param {name} = {value!r}: must be finite")
        if name in out:
            raise TaskError(f"param {name}: given twice")
        out[name] = x
    return out


def _belt_method(ctx, method, to_belt, latency, v_to, batch, round_trip, fit_ws, optimize):
    """--to-belt/--latency: the method that supports a moving end (bspline-vel) unless another is named; the
    options that cannot apply to a rendezvous are refused (exit 2)."""
    if to_belt is None:
        _usage("--latency only applies with --to-belt (the part's detection time)")
    for given, what in ((v_to is not None, "--v-to (the belt velocity is the arrival velocity)"),
                        (batch is not None, "--batch"), (round_trip, "--round-trip"), (fit_ws, "--fit-workspace"),
                        (optimize != OptimizeWhat.none, "--optimize")):
        if given:
            _usage(f"--to-belt: not available with {what}")
    if method == MethodName.bspline_vel:
        return method
    source = ctx.get_parameter_source("method")
    if source is None or source.name == "DEFAULT":
        return MethodName.bspline_vel
    from .errors import TaskError

    raise TaskError(f"to-belt: method {method.value} plans moves from rest to rest; a moving end needs "
                    "--method bspline-vel (the default with --to-belt)")


def _plan_to_belt(p_from, p_to, to_belt, latency, prof, time, height, eta, v_from, params, rate):
    """The rendezvous move and its tracking segment (the profile's dwell; None when 0): ([plan], Rendezvous, track)."""
    from .rendezvous import Part, plan_rendezvous

    part = Part(p_to, _parse_point("to-belt", to_belt, "m/s"), 0.0 if latency is None else latency)
    from .rendezvous import plan_tracking

    plan, rv = plan_rendezvous(p_from, part, prof, time, height, eta, v_from, params, rate)
    track = plan_tracking(plan, part, prof, rate=rate) if prof.planning.dwell > 0 else None
    return [plan], rv, track


def _print_rendezvous(rv) -> None:
    xyz = ", ".join(f"{c:.4f}" for c in rv.meeting_point)
    wait = "; waits for the window (meets the part where it enters)" if rv.waited else ""
    sys.stderr.write(
        f"rendezvous: meets the part at ({xyz}) m at t = {rv.seconds:.4f} s ({rv.meeting_time_since_detection:.4f} s "
        f"after its detection), arriving with the belt velocity {rv.part.speed:.4g} m/s; allowed meeting "
        f"t = {rv.window_s[0]:.4f} … {rv.window_s[1]:.4f} s{wait}\n"
    )


def _run_plan(task, prof, options):
    from .planner import plan as run_plan

    return run_plan(task, prof, options)


def _writer(fmt, dialect, flavor, compression) -> Callable:
    """A function (samples, output path) that writes atomically in the chosen format."""
    from .errors import ExportError

    if fmt != OutputFormat.mcap and compression != Compression.none:
        raise ExportError(f"compression = {compression.value}: only MCAP output is compressed (--format mcap)")
    if fmt != OutputFormat.csv and dialect != CsvDialectName.default:
        raise ExportError(f"csv-dialect = {dialect.value}: only applies to --format csv")

    def write(samples, output: str) -> None:
        from .export import atomic_output

        if fmt == OutputFormat.csv:
            from .export.csv import write_csv

            with atomic_output(output) as stream:
                write_csv(samples, stream, dialect=dialect.value)
        elif fmt == OutputFormat.json:
            from .export.json import write_json

            with atomic_output(output) as stream:
                write_json(samples, stream)
        else:
            from .export.mcap import write_mcap

            with atomic_output(output, binary=True) as stream:
                write_mcap(samples, stream, flavor=flavor.value,
                           compression=None if compression == Compression.none else compression.value)

    write.one_timeline = fmt == OutputFormat.mcap  # type: ignore[attr-defined]
    write.csv_dialect = dialect.value if fmt == OutputFormat.csv else None  # type: ignore[attr-defined]
    return write


def _json_summary(legs, cycle: float, code: int, exit_code: int) -> dict:
    """The --json document: per-move summaries plus the cycle and the verdict. ``exit_code`` is the process's
    own (0 with --report-only); ``limits_ok`` says whether every limit holds."""
    moves = []
    for leg in legs:
        s = leg.summary()
        s["violations"] = [r.as_dict() for r in leg.report.violations]
        moves.append(s)
    doc = dict(moves[0]) if len(moves) == 1 else {"moves": moves}
    doc.update({
        "cycle_time_s": cycle,
        "picks_per_minute": 60.0 / cycle,
        "limits_ok": code == 0,
        "exit_code": exit_code,
    })
    return doc


def _emit_json(doc: dict) -> None:
    import json

    sys.stdout.write(json.dumps(doc, allow_nan=False, default=float) + "\n")
    sys.stdout.flush()


def _plan_batch(source, prof, options, height, eta, fail_fast, writer, output, report, report_only, json_summary,
                quiet, workers: int = 1) -> None:
    """--batch: plan every row, report failures by row number, write the good ones, exit with the worst code."""
    import os

    from .batch import plan_rows_parallel, read_batch
    from .errors import TaskError

    name = "stdin" if source == "-" else source
    if source == "-" or _is_fifo(source):  # a pipe: answer each row as it is read
        if source == "-":
            try:  # undecodable bytes are an error, not surrogates (a C/POSIX locale's stdin escapes them)
                sys.stdin.reconfigure(errors="strict")
            except (AttributeError, ValueError, OSError):  # pragma: no cover - a test runner's stand-in
                pass
            _stream_batch(sys.stdin, name, prof, options, height, eta, fail_fast, writer, output, report,
                          report_only, json_summary, quiet, workers)
            return
        try:
            fh = open(source, encoding="utf-8-sig", newline="")
        except OSError as exc:
            raise TaskError(f"batch = {source}: cannot read it: {exc.strerror}") from None
        with fh:
            _stream_batch(fh, name, prof, options, height, eta, fail_fast, writer, output, report, report_only,
                          json_summary, quiet, workers)
        return
    if source == "-":  # pragma: no cover - streamed above
        rows, bad = read_batch(sys.stdin, name)
    else:
        try:
            with open(source, encoding="utf-8-sig", newline="") as fh:  # -sig: Excel's BOM
                rows, bad = read_batch(fh, name)
        except OSError as exc:
            raise TaskError(f"batch = {source}: cannot read it: {exc.strerror}") from None
    first_bad = min((b.row for b in bad), default=None)
    if fail_fast and first_bad is not None:
        rows = [r for r in rows if r.row < first_bad]
        bad = [b for b in bad if b.row == first_bad]
    total = len(rows) + len(bad)
    results: dict = {}
    pending = sorted(bad, key=lambda b: b.row)  # parse errors, reported in row order as planning passes them

    def flush(upto: float) -> None:
        while pending and pending[0].row < upto:
            b = pending.pop(0)
            results[b.row] = b
            sys.stderr.write("".join(f"pickplace: {ln}\n" for ln in b.error.splitlines()))

    progress = None
    if not quiet and total >= 50 and sys.stderr.isatty():
        from rich.console import Console
        from rich.progress import Progress

        progress = Progress(console=Console(stderr=True), transient=True)
        progress.start()
        bar = progress.add_task(f"planning {total} moves", total=len(rows))
    stopped = False
    try:
        n_workers = workers or ((os.cpu_count() or 1) if len(rows) >= 100 else 1)
        csv_dialect = writer.csv_dialect if output is not None else None
        verdicts_only = json_summary and output is None and report is None
        if verdicts_only:  # the batched verdict engine decides the rows clearly inside every limit (verdicts.py)
            from .verdicts import engine_applies, verdict_rows_parallel
        if verdicts_only and engine_applies(prof, options):
            outcomes = verdict_rows_parallel(rows, prof, options, height, eta, fail_fast, name, workers=n_workers)
        else:
            outcomes = plan_rows_parallel(rows, prof, options, height, eta, fail_fast, name, workers=n_workers,
                                          csv_dialect=csv_dialect, format_failed=report_only)
        for res in outcomes:
            flush(res.row)
            results[res.row] = res
            if progress is not None:
                progress.advance(bar)
            if res.error is not None:  # one line per problem (a limit row: one per exceeded limit)
                sys.stderr.write("".join(f"pickplace: {ln}\n" for ln in res.error.splitlines()))
                if fail_fast:
                    stopped = True
                    break
    finally:
        if progress is not None:
            progress.stop()
    if not stopped:
        flush(float("inf"))
    ordered = [results[k] for k in sorted(results)]
    if fail_fast:
        stop = next((r.row for r in ordered if r.code), None)
        if stop is not None:
            ordered = [r for r in ordered if r.row <= stop]
    codes = [r.code for r in ordered]
    worst = max(codes, default=0)
    planned = [r for r in ordered if r.plan is not None and (r.code == 0 or report_only)]
    if json_summary:
        for r in ordered:
            _emit_row_json(r)
    if report is not None:
        _write_report([r.plan for r in ordered if r.plan is not None], report, rows=[r.row for r in ordered if r.plan is not None])
    if not quiet:
        _batch_line(codes, next((r.row for r in ordered if r.code), None), len(planned) if output is not None else None)
    if output is not None and planned and writer.csv_dialect is not None:
        # CSV: header, then each plan's rows (formatted by the workers when there are several)
        from .export import atomic_output
        from .export.csv import csv_header, csv_rows

        with atomic_output(output) as stream:
            stream.write(csv_header(planned[0].plan, writer.csv_dialect, move=True))
            for r in planned:
                stream.write(r.text if r.text is not None else csv_rows(r.plan, writer.csv_dialect, move=r.row))
    elif output is not None and planned:
        from .timeline import concatenate

        # CSV/JSON: each move keeps its own time (the move column tells them apart); MCAP: one timeline,
        # moves one dwell apart
        samples = concatenate([r.plan for r in planned], [r.row for r in planned],
                              restart_time=not writer.one_timeline, gap=prof.planning.dwell)
        writer(samples, output)
    elif output is not None and not planned:
        sys.stderr.write("pickplace: no row could be written\n")
    if worst and not (report_only and all(c == 3 for c in codes if c)):
        raise typer.Exit(worst)


def _emit_row_json(res) -> None:
    """A batch row's JSON line: row, exit code, error, and the plan's summary and violations when it has one."""
    doc: dict = {"row": res.row, "exit_code": res.code, "error": res.error}
    if res.plan is not None:
        doc.update(res.plan.summary())
        doc["violations"] = [v.as_dict() for v in res.plan.report.violations]
    _emit_json(doc)


def _batch_line(codes: list, first_failed, written) -> None:
    """The batch's closing line on stderr (``written``: rows written to -o, None without -o)."""
    n_ok = sum(1 for c in codes if c == 0)
    sys.stderr.write(
        f"batch: {len(codes)} rows, {n_ok} ok, {len(codes) - n_ok} failed"
        + (f" (first failing row {first_failed})" if first_failed is not None else "")
        + (f"; {written} written" if written is not None else "") + "\n"
    )


def _is_fifo(path: str) -> bool:
    import os
    import stat

    try:
        return stat.S_ISFIFO(os.stat(path).st_mode)
    except OSError:
        return False


def _stream_batch(stream, name, prof, options, height, eta, fail_fast, writer, output, report, report_only,
                  json_summary, quiet, workers: int) -> None:
    """--batch - (or a named pipe): each row answered as soon as its line is read — a JSON line (``--json``)
    or its CSV rows, flushed — with the same row numbers, messages and exit codes as a file batch. Memory:
    one row's trajectory (MCAP and JSON trajectories need the whole timeline: those rows are kept until the
    input ends; ``--report`` keeps each row's limit report, not its samples)."""
    from contextlib import ExitStack

    from .batch import ReportRecord, iter_batch, plan_stream

    verdicts_only = json_summary and output is None and report is None
    engine = False
    if verdicts_only:
        from .verdicts import engine_applies

        engine = engine_applies(prof, options)
    csv_out = output is not None and writer.csv_dialect is not None
    kept: list = []  # MCAP / JSON trajectories: the rows to write when the input ends
    reports: list = []
    codes: list[int] = []
    first_failed = None
    n_written = 0
    with ExitStack() as stack:
        out = None
        if csv_out:
            from .export import atomic_output
            from .export.csv import csv_header, csv_rows

            out = stack.enter_context(atomic_output(output))
        results = plan_stream(iter_batch(stream, name), prof, options, height, eta, fail_fast, name,
                              workers=max(workers, 1), csv_dialect=writer.csv_dialect if csv_out else None,
                              format_failed=report_only, verdicts=engine)
        for res in results:
            codes.append(res.code)
            if res.code and first_failed is None:
                first_failed = res.row
            if res.error is not None:
                sys.stderr.write("".join(f"pickplace: {ln}\n" for ln in res.error.splitlines()))
                sys.stderr.flush()
            if json_summary:
                _emit_row_json(res)
            if res.plan is not None and report is not None:
                reports.append((res.row, ReportRecord.of(res.plan)))
            if res.plan is not None and output is not None and (res.code == 0 or report_only):
                n_written += 1
                if out is not None:
                    if n_written == 1:
                        out.write(csv_header(res.plan, writer.csv_dialect, move=True))
                    out.write(res.text if res.text is not None else csv_rows(res.plan, writer.csv_dialect, move=res.row))
                    out.flush()
                else:
                    from .batch import PlanRecord

                    kept.append((res.row, res.plan if isinstance(res.plan, PlanRecord) else PlanRecord.of(res.plan)))
            if fail_fast and res.code:
                break
    if kept:
        from .timeline import concatenate

        samples = concatenate([p for _, p in kept], [r for r, _ in kept], restart_time=not writer.one_timeline,
                              gap=prof.planning.dwell)
        writer(samples, output)
    if report is not None:
        _write_report([r for _, r in reports], report, rows=[n for n, _ in reports])
    worst = max(codes, default=0)
    if not quiet:
        _batch_line(codes, first_failed, n_written if output is not None else None)
    if output is not None and n_written == 0:
        sys.stderr.write("pickplace: no row could be written\n")
    if worst and not (report_only and all(c == 3 for c in codes if c)):
        raise typer.Exit(worst)


def _check_output_paths(output: str, report: Optional[str]) -> None:
    """Refuse colliding or impossible outputs before anything is computed or written."""
    import os

    from .errors import ExportError
    from .export import check_writable

    check_writable(output)
    if report is not None:
        check_writable(report)
        if report == "-" and output == "-":
            raise ExportError("report = -: stdout already carries the trajectory; give --report a file or -o a file")
        if report != "-" and output != "-" and os.path.abspath(report) == os.path.abspath(output):
            raise ExportError(f"report = {report}: the same file as --output; give them different paths")


def _write_report(results, path: str, rows: Optional[list] = None) -> None:
    """--report: summary and limit rows of one plan, or of every move (a round trip, a batch)."""
    import json

    from .export import atomic_output

    results = list(results) if isinstance(results, (list, tuple)) else [results]
    docs = [{"summary": r.summary(), "limits": r.report.as_dict()} for r in results]
    if rows is not None:
        for d, n in zip(docs, rows):
            d["row"] = n
    doc = docs[0] if len(docs) == 1 and rows is None else {"moves": docs}
    with atomic_output(path) as stream:
        json.dump(doc, stream, indent=2, allow_nan=False, default=float)
        stream.write("\n")


def _fmt(x: float) -> str:
    return f"{x:.4g}"


def _print_limit_table(report) -> None:
    from rich.console import Console
    from rich.markup import escape
    from rich.table import Table

    from .limits import percent

    table = Table(title=None, box=None, pad_edge=False, show_header=True, header_style="bold")
    for col, just in (("joint", "left"), ("quantity", "left"), ("peak", "right"), ("limit", "right"),
                      ("use %", "right"), ("t peak [s]", "right"), ("", "left")):
        table.add_column(escape(col), justify=just)  # type: ignore[arg-type]  ("[s]" is not rich markup)
    for r in report.rows:
        mark = "ok" if r.ok else "[bold red]EXCEEDED[/]"
        quantity = r.quantity
        if quantity.startswith(("position", "workcell")):  # a [min, max] range: say which side the row is
            quantity += " min" if r.bound == "lower" else " max"
        table.add_row(
            r.joint, escape(f"{quantity} [{r.unit}]"), _fmt(r.peak),
            ("≥ " if r.bound == "lower" else "≤ ") + _fmt(r.limit), percent(r.utilisation),
            "" if r.t_peak is None else f"{r.t_peak:.4f}", mark,
        )
    # a terminal wraps at its width; a pipe or log file gets whole rows (rich would assume 80 columns)
    width = None if sys.stderr.isatty() else 200
    Console(stderr=True, highlight=False, soft_wrap=True, width=width).print(table)


def _print_verdict(report, quiet: bool, with_cycle: bool = True) -> None:
    cycle = (
        f"cycle: {report.duration:.4f} s one way, {report.round_trip:.4f} s round trip "
        f"(dwell {report.dwell:g} s), {report.picks_per_minute:.1f} picks/min"
    )
    if not with_cycle:
        cycle = f"move {report.duration:.4f} s"
    if report.ok:
        if not quiet:
            sys.stderr.write(f"verdict: all limits hold; {cycle}\n")
        return
    from .batch import violation_text  # the same words as a batch row's limit lines

    for r in report.violations:
        sys.stderr.write(f"pickplace: {violation_text(r)}\n")
    if not quiet:
        sys.stderr.write(f"verdict: {len(report.violations)} limit(s) exceeded; {cycle}\n")


def _print_summary(result) -> None:
    s = result.summary()
    d = result.duration
    par = result.parameters
    if "k1" in par:
        ks = f"k1 = {par['k1']:.4f}, k2 = {par['k2']:.4f} ({par['k_source']})"
    else:  # the method's scalar shape parameters (e.g. ph m, r; bspline-vel τ6 … λ3 and F)
        skip = {"continuity", "eta", "height_m", "duration_s", "margin", "a_min", "j_min", "paper_time_factor"}
        ks = ", ".join(
            f"{k} = {v:.4g}" if isinstance(v, float) else f"{k} = {v}"
            for k, v in par.items() if k not in skip and isinstance(v, (int, float, str)) and not isinstance(v, bool)
        )
    shape = par.get("shape")
    if shape:
        t_shape = d.t_fit if d.t_fit is not None else shape["screened_fit_s"]
        tab = shape["table"]
        versus = (f"the table's k1 = {tab['k1']:.4f}, k2 = {tab['k2']:.4f}, η = {tab['eta']:g} fits in {tab['fit_s']:.4f} s "
                  f"→ {t_shape:.4f} s = {t_shape / tab['fit_s']:.3f} × table" if tab and tab.get("fit_s")
                  else "the table has no shape for this move")
        ks += f"\nshape: η = {shape['eta']:.4g} chosen with k1, k2 for this robot's limits (fit, uniform law): {versus}; {shape['note']}"
    bounds = f"v {d.t_velocity:.4f} s, a {d.t_acceleration:.4f} s" + (f", j {d.t_jerk:.4f} s" if d.t_jerk else "")
    fit = f"; fit {d.t_fit:.4f} s" if d.t_fit is not None else ""
    if d.t_optimal is not None and d.t_fit:
        fit += (f"; optimal {d.t_optimal:.4f} s = {d.t_optimal / d.t_fit:.3f} × fit, {d.t_optimal / d.t_auto:.3f} × auto"
                f" ({60 / (2 * d.t_optimal + 2 * result.report.dwell):.1f} against "
                f"{60 / (2 * d.t_fit + 2 * result.report.dwell):.1f} picks/min with fit)")
    sys.stderr.write(
        f"{s['profile']} / {s['method']}: b = {s['b_m']:.4g} m, h = {s['height_m']:.4g} m, λ = {s['lambda']:.4g}, η = {s['eta']:g}; {ks}\n"
        f"duration T = {d.seconds:.4f} s ({d.mode}, binding: {d.binding}); auto {d.t_auto:.4f} s (Eq. 26: {bounds}){fit}; "
        f"{s['samples']} samples\n"
        f"peaks |v| = {s['peak_speed_m_s']:.4g} m/s, |a| = {s['peak_acceleration_m_s2']:.4g} m/s², "
        f"|j| = {s['peak_jerk_m_s3']:.4g} m/s³\n"
    )


@app.command()
@_handle_errors
def check(
    trajectory: str = typer.Argument(
        ..., metavar="TRAJECTORY",
        help="CSV with a header holding t [s] and q1 … qn (this tool's CSV works, also --batch and --round-trip "
        "output); '-' = stdin.",
    ),
    profile: Optional[str] = typer.Option(None, "--profile", "-p", help="Profile YAML file or shipped name. [default: delta-su2018]"),
    smoothing: float = typer.Option(
        0.0, "--smoothing", help="Smoothing factor per sample, in m² (0 = interpolate exactly; > 0 for noisy measured data)."
    ),
    report: Optional[str] = typer.Option(None, "--report", help="Also write the limit report as JSON to this file."),
    report_only: bool = typer.Option(False, "--report-only", help="Exit 0 even when a limit is exceeded."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="Only violations and errors on stderr."),
) -> None:
    """Check an existing joint trajectory against a profile's limits (exit 3 if a limit is exceeded).

    Joint positions go through forward kinematics; a quintic spline of the tool positions gives the
    derivatives (the report says so), then the same dynamics and limit check as `plan`. Joint positions
    are checked as given (q1 = 5 rad is 5 rad, not wrapped).

    A file with a `move` column (`plan --batch` or `--round-trip` output) is checked move by move: each
    move gets its own limit table and verdict, and the exit code is the worst of them. Samples at the end
    of a move that repeat its last position (a round trip's dwell) are the dwell, not part of the move.
    """
    import json

    from .check import check_file
    from .errors import TaskError
    from .export import atomic_output
    from .profile import load_profile

    if not (smoothing >= 0 and smoothing < float("inf")):
        raise TaskError(f"smoothing = {smoothing!r}: must be a finite number >= 0")
    prof = load_profile(profile)
    checks = check_file(trajectory, prof, smoothing)
    several = len(checks) > 1 or checks[0].move is not None
    if report is not None:
        with atomic_output(report) as stream:
            if several:
                doc = {"profile": prof.name, "moves": [
                    {"move": c.move, "lines": [c.first_line, c.last_line], "limits": c.report.as_dict()} for c in checks
                ]}
            else:
                doc = {"profile": prof.name, "limits": checks[0].report.as_dict()}
            json.dump(doc, stream, indent=2, default=float)
            stream.write("\n")
    for c in checks:
        rep = c.report
        if several and (not quiet or not rep.ok):
            sys.stderr.write(f"--- move {c.move} (lines {c.first_line}–{c.last_line}) ---\n")
        if not quiet:
            for note in rep.notes:
                sys.stderr.write(f"{note}\n")
            _print_limit_table(rep)
        _print_verdict(rep, quiet, with_cycle=not several)
    code = max(c.report.exit_code() for c in checks)
    if several and not quiet:
        bad = sum(not c.report.ok for c in checks)
        sys.stderr.write(
            f"checked {len(checks)} move(s): {len(checks) - bad} within every limit, {bad} exceed one\n"
        )
    if code and not report_only:
        raise typer.Exit(code)


profile_app = typer.Typer(help="Validate or inspect a robot/workcell profile.", no_args_is_help=True)
app.add_typer(profile_app, name="profile")


@profile_app.command("validate")
@_handle_errors
def profile_validate(
    profile: str = typer.Argument(..., help="Profile YAML file or shipped name."),
) -> None:
    """Validate a profile: exit 0 and one line when it is valid, exit 1 with the first problem otherwise."""
    from .profile import load_profile, resolve_profile_path
    from .robots import build_robot

    prof = load_profile(profile)
    build_robot(prof.robot)
    typer.echo(f"ok: {resolve_profile_path(profile)}: {prof.name} ({prof.robot.kind})")


@profile_app.command("show")
@_handle_errors
def profile_show(
    profile: str = typer.Argument("delta-su2018", help="Profile YAML file or shipped name."),
    z: Optional[float] = typer.Option(None, "--z", help="Working height in m for the workspace extent. [default: middle of the workcell box, or the robot's home height]"),
) -> None:
    """Show a profile with its derived values: lumped masses, workspace extent at the working height, limits."""
    from rich.console import Console
    from rich.markup import escape

    from .profile import load_profile
    from .robots import build_robot

    _finite("z", z, "in m (no NaN or inf)")
    prof = load_profile(profile)
    robot = build_robot(prof.robot)
    specs = prof.robot.joint_specs()
    out = Console(highlight=False, soft_wrap=True)
    out.print(f"[bold]{escape(prof.name)}[/] ({prof.robot.kind}): {escape(prof.description)}")
    kind = prof.robot.kind
    if kind == "delta":
        out.print(
            f"lumped model (Codourey 1998): arm inertia I_b = {robot.arm_inertia:.5g} kg·m² per arm "
            f"(upper arm + elbow + 2/3 forearm at L); travelling mass m_p = {robot.platform_mass:.4g} kg "
            f"(plate + payload + 3 × 1/3 forearm pair); arm gravity moment {robot.arm_gravity_moment:.4g} kg·m"
        )
    elif kind == "scara":
        out.print(f"carried by link 2 (z axis + payload, lumped at its end): {robot.carried_mass:.4g} kg")
    else:
        out.print("moved masses (payload included): " + ", ".join(f"{n} {m:g} kg" for n, m in zip("xyz", robot.masses)))
    cap = prof.capacity
    out.print(escape(
        f"capacity: [v] = {cap.velocity:g} m/s, [a] = {cap.acceleration:g} m/s², "
        f"[j] = {cap.jerk if cap.jerk is not None else 'not limited'}{' m/s³' if cap.jerk else ''}"
    ))
    pl = prof.planning
    out.print(f"planning: height {pl.height:g} m, η = {pl.eta:g}, rate {pl.rate:g} Hz, dwell {pl.dwell:g} s")
    if z is None:
        box = prof.workcell.box
        z = (box.min[2] + box.max[2]) / 2 if box else (-0.8 if kind == "delta" else (robot.z0 - 0.1 if kind == "scara" else 0.0))
    if kind == "gantry":
        out.print("workspace: the travel box " + ", ".join(f"{n} [{a.travel[0]:g}, {a.travel[1]:g}] m" for n, a in zip("xyz", prof.robot.axes)))
    else:
        from .workspace import radial_extent

        out.print(escape(f"workspace at z = {z:g} m: {radial_extent(prof, z).describe()}"))
    def g(x, unit: str = "") -> str:
        return "–" if x is None else f"{x:g}{unit}"

    for name, unit, s in zip(robot.joint_names, robot.joint_units, specs):
        lim, d = s.limits, s.drive
        pos = "–" if lim.position is None else f"[{lim.position[0]:.4g}, {lim.position[1]:.4g}] {unit}"
        out.print(escape(
            f"{name}: position {pos}; velocity {g(lim.velocity, f' {unit}/s')}; "
            f"acceleration {g(lim.acceleration, f' {unit}/s²')}; jerk {g(lim.jerk, f' {unit}/s³')}"
        ))
        if d is not None:
            out.print(escape(
                f"    drive: gear {d.gear_ratio:g}, efficiency {d.efficiency:g}, rotor {d.rotor_inertia:g} kg·m²; "
                f"rated {g(d.rated_torque, ' N·m')}, peak {g(d.peak_torque, ' N·m')}, speed {g(d.max_speed, ' rad/s')}, "
                f"torque rate {g(d.torque_rate, ' N·m/s')}"
            ))


def _parse_weights(text: str) -> tuple[float, float]:
    from .errors import TableError

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
    lambda_min: float = typer.Option(1.0, "--lambda-min", help="Smallest width/height ratio λ = b/h."),
    lambda_max: float = typer.Option(40.0, "--lambda-max", help="Largest λ."),
    lambda_step: float = typer.Option(0.5, "--lambda-step", help="Step of the λ grid."),
    lambda_points: int = typer.Option(
        0, "--lambda-points", help="N values of λ spaced evenly in log λ from --lambda-min to --lambda-max "
        "(instead of --lambda-step; 0 = use the step)."),
    eta: float = typer.Option(0.5, "--eta", help="Lift-off/set-down ratio η, 0 < η < 1."),
    eta_min: Optional[float] = typer.Option(
        None, "--eta-min", help="Build the 2-D (λ, η) table: smallest η of its η axis (with --eta-max, --eta-step)."),
    eta_max: Optional[float] = typer.Option(None, "--eta-max", help="2-D table: largest η (default: --eta-min)."),
    eta_step: float = typer.Option(0.05, "--eta-step", help="2-D table: step of the η axis."),
    eta_list: Optional[str] = typer.Option(
        None, "--eta-list", help="2-D table: the η axis as increasing values, e.g. 0.1,0.2,0.5 (instead of --eta-min …)."),
    weights: str = typer.Option("0.5,0.5", "--weights", help="Weights WA,WJ of F_a and F_j in F (Li 2018 Eq. 22); WA + WJ = 1."),
    grid_step: float = typer.Option(0.01, "--grid-step", help="Step of the coarse (k1, k2) search grid."),
    fit_min: float = typer.Option(5.0, "--fit-min", help="Fit the Eq. 23 cubic on rows with λ ≥ this (no cubic follows λ < 5)."),
    workers: int = typer.Option(0, "--workers", "-j", help="Local worker processes (0 = all cores; 1 = in this process)."),
    scheduler: Optional[str] = typer.Option(
        None, "--scheduler", metavar="tcp://HOST:PORT",
        help="Run the rows on this Dask distributed scheduler instead of local processes (extra pickplace-cli[dask]).",
    ),
    resume: bool = typer.Option(
        False, "--resume",
        help="Continue an interrupted build from OUTPUT.partial.jsonl (rows already finished are not recomputed; needs -o FILE).",
    ),
    output: str = typer.Option("-", "--output", "-o", help="Output file ('-' = stdout). Written atomically."),
    table_format: TableFormat = typer.Option(
        TableFormat.csv, "--format", "-f",
        help="csv (the table file plan --table reads), json, or st (IEC 61131-3 Structured Text with a look-up function).",
    ),
    table_method: TableMethod = typer.Option(
        TableMethod.bspline, "--method", "-m",
        help="bspline: Li 2018's λ → (k1, k2) table; bspline-vel: Yang 2022's conveyor-tracking table over the "
        "dimensionless groups (h/b, v·T/b along and across; local processes and CSV only).",
    ),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No progress bar."),
) -> None:
    """Compute the optimal (k1*, k2*) of the B-spline method for a grid of λ, with the Eq. 23 cubic fit.

    With -o FILE, finished rows are also appended to FILE.partial.jsonl as they complete; after Ctrl-C
    or a kill, rerun the same command with --resume. The table replaces FILE only when it is complete.
    """
    import contextlib
    import os

    from .errors import TableError
    from .table import TableSettings, checkpoint_path, format_table, lambda_grid, run_build

    if table_method == TableMethod.bspline_vel:
        if scheduler or resume or table_format != TableFormat.csv:
            _usage("--method bspline-vel builds on local processes into a CSV (no --scheduler, --resume, --format)")
        _build_vel_table(eta, workers, output, quiet)
        return

    if not (0 < eta < 1):
        raise TableError(f"eta = {eta!r}: the lift-off/set-down ratio η must lie strictly between 0 and 1")
    settings = TableSettings(eta=eta, weights=_parse_weights(weights), grid_step=grid_step)
    if lambda_points:
        from .table2d import log_lambda_grid

        lams = log_lambda_grid(lambda_min, lambda_max, lambda_points)
        lam_text = f"{lambda_min:g}..{lambda_max:g} log-spaced ({len(lams)} values)"
    else:
        lams = lambda_grid(lambda_min, lambda_max, lambda_step)
        lam_text = f"{lambda_min:g}..{lambda_max:g} step {lambda_step:g} ({len(lams)} rows)"
    if eta_list is not None or eta_min is not None or eta_max is not None:
        if eta_list is not None and (eta_min is not None or eta_max is not None):
            _usage("--eta-list replaces --eta-min/--eta-max: give one or the other")
        _build_table_2d(lams, lam_text, settings, eta_list, eta_min, eta_max, eta_step, fit_min, workers, scheduler,
                        resume, output, table_format, quiet)
        return
    if workers < 0:
        raise TableError(f"workers = {workers}: must be 0 (all cores) or a positive number")
    to_file = output != "-"
    if resume and not to_file:
        raise TableError("--resume: needs -o FILE (the partial results live in FILE.partial.jsonl)")
    if to_file:
        from .export import check_writable

        check_writable(output)
    ckpt = checkpoint_path(output) if to_file else None
    n_workers = workers or os.cpu_count() or 1

    with contextlib.ExitStack() as stack:
        executor = None
        if scheduler:
            from .parallel import dask_executor

            executor, n_workers = stack.enter_context(dask_executor(scheduler))
        tick = None
        if not quiet:
            from rich.console import Console
            from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

            progress = stack.enter_context(Progress(
                TextColumn("[progress.description]{task.description}"),
                BarColumn(),
                TextColumn("{task.completed}/{task.total} λ"),
                TimeElapsedColumn(),
                TimeRemainingColumn(),
                console=Console(stderr=True),
                transient=False,
            ))
            engine = f"Dask {scheduler}" if scheduler else (f"{n_workers} processes" if n_workers > 1 else "1 process")
            bar = progress.add_task(f"optimising k1, k2 ({engine})", total=len(lams))

            def tick(n_done: int, total: int) -> None:
                progress.update(bar, completed=n_done, total=total)

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
    from .export import atomic_output

    extra = {
        "lambda_grid": lam_text,
        "optimiser": "coarse grid + bounded Nelder-Mead from each grid local optimum within basin_margin (one per basin); exact peaks",
        "fit_lambda_min": fit_min,
    }
    if table_format is TableFormat.json:
        from .export.table_json import format_table_json as formatter
    elif table_format is TableFormat.st:
        from .export.table_st import format_table_st as formatter
    else:
        formatter = format_table
    text = formatter(table, __version__, extra)
    with atomic_output(output) as stream:
        stream.write(text)
    if ckpt is not None:
        ckpt.unlink(missing_ok=True)  # the table is in place: the partial results are no longer needed
    if not quiet:
        g1, g2, res = table.fit(fit_min)
        resumed = f"; {report.resumed} rows resumed from {ckpt}, {report.computed} computed" if report.resumed else ""
        sys.stderr.write(
            f"{len(lams)} rows{resumed}; cubic fit (Eq. 23) on λ ≥ {fit_min:g}: max |residual| {res:.3g}; "
            f"k1 = {g1[0]:.4g} + {g1[1]:.4g} λ + {g1[2]:.4g} λ² + {g1[3]:.4g} λ³\n"
        )


def _build_table_2d(lams, lam_text, settings, eta_list, eta_min, eta_max, eta_step, fit_min, workers, scheduler,
                    resume, output, table_format, quiet) -> None:
    """build-table over a λ × η grid (table2d.run_build_2d): checkpoint, resume and executors as the 1-D build."""
    import contextlib
    import os
    import time

    from .errors import TableError
    from .table import checkpoint_path
    from .table2d import eta_grid, format_table_2d, parse_eta_list, run_build_2d

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
    if workers < 0:
        raise TableError(f"workers = {workers}: must be 0 (all cores) or a positive number")
    to_file = output != "-"
    if resume and not to_file:
        raise TableError("--resume: needs -o FILE (the partial results live in FILE.partial.jsonl)")
    if to_file:
        from .export import check_writable

        check_writable(output)
    ckpt = checkpoint_path(output) if to_file else None
    n_workers = workers or os.cpu_count() or 1
    total = len(lams) * len(etas)
    t0 = time.perf_counter()
    with contextlib.ExitStack() as stack:
        executor = None
        if scheduler:
            from .parallel import dask_executor

            executor, n_workers = stack.enter_context(dask_executor(scheduler))
        tick = None
        if not quiet:
            from rich.console import Console
            from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

            progress = stack.enter_context(Progress(
                TextColumn("[progress.description]{task.description}"), BarColumn(),
                TextColumn("{task.completed}/{task.total} (λ, η)"), TimeElapsedColumn(),
                console=Console(stderr=True), transient=False))
            engine = f"Dask {scheduler}" if scheduler else f"{n_workers} process{'es' if n_workers > 1 else ''}"
            bar = progress.add_task(f"optimising k1, k2 ({engine})", total=total)

            def tick(n_done: int, n_total: int) -> None:
                progress.update(bar, completed=n_done, total=n_total)

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
        from .export.table2d_st import format_table_2d_st

        text = format_table_2d_st(table, __version__, extra)
    else:
        text = format_table_2d(table, __version__, extra)
    from .export import atomic_output

    with atomic_output(output) as stream:
        stream.write(text)
    if ckpt is not None:
        ckpt.unlink(missing_ok=True)
    if not quiet:
        resumed = f"; {report.resumed} resumed from {ckpt}, {report.computed} computed" if report.resumed else ""
        jumps = table.jumps
        sys.stderr.write(f"{total} rows ({len(etas)} η × {len(lams)} λ){resumed} in {seconds:.1f} s; "
                         f"{len(jumps)} grid edge(s) with a basin jump (listed in the header)\n")


class CompareFormat(str, Enum):
    table = "table"
    csv = "csv"
    json = "json"


def _task_from_options(from_: str, to: str, profile: Optional[str], height: Optional[float], eta: Optional[float]):
    """(profile, task) from the shared move options of compare and plot (one-line errors)."""
    from .errors import TaskError
    from .profile import load_profile
    from .task import Task

    p_from = _parse_point("from", from_)
    p_to = _parse_point("to", to)
    _finite("height", height)
    if eta is not None and not (0 < eta < 1):
        raise TaskError(f"eta = {eta!r}: the lift-off/set-down ratio η must lie strictly between 0 and 1")
    prof = load_profile(profile)
    task = Task(p_from, p_to, height if height is not None else prof.planning.height,
                eta if eta is not None else prof.planning.eta)
    return prof, task


def _opt(x, fmt: str = "{:.4g}", scale: float = 1.0) -> str:
    return "–" if x is None else fmt.format(x * scale)


def _print_comparison(comparison) -> None:
    """One column per method, one row per quantity (fits a terminal with every method of the registry)."""
    from rich.console import Console
    from rich.markup import escape
    from rich.table import Table

    rows = [r for r in comparison.rows if r.ok]

    def geo(attr):
        return lambda r: _opt(getattr(r.geometry, attr))

    def vib(attr):
        return lambda r: _opt(None if r.vibration is None else getattr(r.vibration, attr))

    lines = [
        ("duration T [s]", lambda r: f"{r.duration:.4f} ({r.duration_mode})"),
        ("auto (true peaks) [s]", lambda r: _opt(r.auto, "{:.4f}")),
        ("fit (motor limits) [s]", lambda r: _opt(r.fit, "{:.4f}")),
        ("optimal law / fit [1]", lambda r: "–" if r.optimal is None or not r.fit else f"{r.optimal / r.fit:.3f}"),
        ("paper formula [s]", lambda r: _opt(r.paper_duration, "{:.4f}")),
        ("v_max (b = 1, T = 1)", lambda r: _opt(r.v_norm)),
        ("a_max (b = 1, T = 1)", lambda r: _opt(r.a_norm)),
        ("j_max (b = 1, T = 1)", lambda r: _opt(r.j_norm)),
        ("peak |v| [m/s]", lambda r: _opt(r.peak_speed)),
        ("peak |a| [m/s²]", lambda r: _opt(r.peak_acceleration)),
        ("peak |j| [m/s³]", lambda r: _opt(r.peak_jerk)),
        ("peak joint torque", lambda r: f"{r.joint_torque_peak:.4g} {r.joint_torque_unit}"),
        ("motor torque use %", lambda r: _opt(r.motor_torque_use, "{:.1f}", 100)),
        ("torque rate use %", lambda r: _opt(r.torque_rate_use, "{:.1f}", 100)),
        ("limits", lambda r: "ok" if r.limits_ok else "EXCEEDED"),
        ("max height above ends [m]", geo("max_height")),
        ("overshoot of h [m]", geo("overshoot")),
        ("backward drift [m]", geo("drift_back")),
        ("past the target [m]", geo("drift_forward")),
        ("continuity", lambda r: r.continuity.label),
        ("residual vibration [m]", vib("max_amplitude")),
        ("residual acceleration [m/s²]", vib("max_acceleration_amplitude")),
    ]
    if not any(r.optimal is not None for r in rows):  # the law's row only with --time optimal
        lines = [ln for ln in lines if not ln[0].startswith("optimal law")]
    table = Table(box=None, pad_edge=False, show_header=True, header_style="bold")
    table.add_column("quantity", justify="left")
    for r in rows:
        table.add_column(escape(r.method), justify="right")
    for name, fn in lines:
        table.add_row(escape(name), *(escape(fn(r)) for r in rows))
    t = comparison.task
    # wide enough for every column (a pipe gets rich's 80 columns otherwise, and the names would be cut)
    cells = [[name] + [fn(r) for r in rows] for name, fn in lines]
    need = sum(max(len(c[i]) for c in cells + [["quantity"] + [r.method for r in rows]]) + 2 for i in range(len(rows) + 1))
    out = Console(stderr=True, highlight=False, soft_wrap=True)
    if out.width < need:
        out = Console(stderr=True, highlight=False, soft_wrap=True, width=need)
    out.print(escape(
        f"{comparison.profile_name}: b = {t.b:.4g} m, h = {t.height:.4g} m, λ = {t.lam:.4g}, η = {t.eta:g}; "
        f"duration: {comparison.time}"
    ))
    out.print(table)
    for r in comparison.rows:
        for note in r.notes:
            sys.stderr.write(f"{r.method}: {note}\n")
        if r.ok and not r.limits_ok:
            sys.stderr.write(f"{r.method}: a limit is exceeded at T = {r.duration:.4f} s ({r.worst_limit})\n")


@app.command()
@_handle_errors
def compare(
    from_: str = typer.Option(..., "--from", help="Pick point X,Y,Z in m (base frame)."),
    to: str = typer.Option(..., "--to", help="Place point X,Y,Z in m (base frame)."),
    methods: str = typer.Option("all", "--methods", "-m", help="'all' or method names separated by commas."),
    profile: Optional[str] = typer.Option(None, "--profile", "-p", help="Profile YAML file or shipped name. [default: delta-su2018]"),
    height: Optional[float] = typer.Option(None, "--height", help="Clearance h in m above the higher end point. [default: profile]"),
    eta: Optional[float] = typer.Option(None, "--eta", help="Lift-off/set-down ratio η, 0 < η < 1. [default: profile]"),
    time: str = typer.Option("auto", "--time", "-t", help="Duration for the peaks and torques: 'auto', 'fit', 'optimal' (non-uniform time law) or seconds."),
    fmt: CompareFormat = typer.Option(CompareFormat.table, "--format", "-f", help="table (stderr only), csv or json (stdout or -o)."),
    output: str = typer.Option("-", "--output", "-o", help="Output file for csv/json ('-' = stdout). Written atomically."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No table on stderr with csv/json (errors still print)."),
) -> None:
    """Compare every planning method on one move: durations (auto, fit, the paper's formula), normalised
    and true peaks, joint torque and torque-rate use, height, overshoot, drift, continuity class, residual
    vibration. Exit 0 when at least one method planned (limits exceeded are shown, not fatal); otherwise
    the first method's error code.
    """
    from .compare import compare_methods, write_compare_csv, write_compare_json
    from .errors import ExportError
    from .export import atomic_output, check_writable

    if fmt == CompareFormat.table and output != "-":
        raise ExportError(f"output = {output}: --format table prints to stderr; use --format csv or json to write a file")
    check_writable(output)
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


@app.command()
@_handle_errors
def plot(
    from_: str = typer.Option(..., "--from", help="Pick point X,Y,Z in m (base frame)."),
    to: str = typer.Option(..., "--to", help="Place point X,Y,Z in m (base frame)."),
    output: str = typer.Option(..., "--output", "-o", help="Figure file (.png or .svg), written atomically; '-' = stdout with --format."),
    methods: str = typer.Option("all", "--methods", "-m", help="'all' or method names separated by commas."),
    profile: Optional[str] = typer.Option(None, "--profile", "-p", help="Profile YAML file or shipped name. [default: delta-su2018]"),
    height: Optional[float] = typer.Option(None, "--height", help="Clearance h in m above the higher end point. [default: profile]"),
    eta: Optional[float] = typer.Option(None, "--eta", help="Lift-off/set-down ratio η, 0 < η < 1. [default: profile]"),
    time: str = typer.Option("auto", "--time", "-t", help="Duration of each method's move: 'auto', 'fit', 'optimal' (non-uniform time law, same path) or seconds."),
    normalised: bool = typer.Option(False, "--normalised", help="Plot with b = 1 and T = 1 against τ (like Li 2018 Fig. 5)."),
    motors: bool = typer.Option(
        False, "--motors", help="Add each motor's speed, torque and torque rate against time in % of its limit "
        "(line style per joint), and the round trip's RMS motor torque in % of rated: where the motors idle."),
    fmt: Optional[str] = typer.Option(None, "--format", "-f", help="png or svg. [default: from the file's suffix]"),
) -> None:
    """Draw the path in the vertical plane (u along the move, z) and |v|, |a|, |j| against time for one or
    several methods, and with --motors how hard each motor works (PNG or SVG; needs the optional extra:
    pip install 'pickplace-cli[plot]')."""
    from .compare import parse_methods
    from .errors import PickplaceError
    from .export import atomic_output, check_writable
    from .export.plot import PlotMove, plot_format, require_matplotlib, write_plot
    from .planner import PlanOptions
    from .planner import plan as run_plan
    from .timing import parse_time

    if motors and normalised:
        _usage("--motors draws the motors at each move's duration: not with --normalised")
    require_matplotlib()
    kind = plot_format(output, fmt)
    check_writable(output)
    prof, task = _task_from_options(from_, to, profile, height, eta)
    spec = parse_time(time)
    moves = []
    first_error = None
    for m in parse_methods(methods):
        try:
            res = run_plan(task, prof, PlanOptions(method=m, time=spec, fit=spec == "fit"))
        except PickplaceError as exc:
            sys.stderr.write(f"pickplace: method {m.value}: {exc}\n")
            first_error = first_error or exc
            continue
        use = None
        if motors:
            use = _motor_use(res, prof)
        moves.append(PlotMove(f"{m.value} (T = {res.duration.seconds:.4f} s)", res.cartesian, task, use))
    if not moves:
        _err("no method could plan this move")
        raise typer.Exit(first_error.exit_code if first_error else 1)
    title = f"{prof.name}: b = {task.b:.4g} m, h = {task.height:.4g} m, λ = {task.lam:.4g}"
    with atomic_output(output, binary=True) as stream:
        write_plot(moves, stream, kind, normalised, title)


def _motor_use(res, prof) -> tuple:
    """(t [s], motor curves in % of limit, RMS % of rated) of a planned move for ``plot --motors``."""
    import numpy as np

    from .export.plot import PLOT_SAMPLES
    from .limits import jump_sides, limit_use
    from .planner import motion_model

    path, T = res.cartesian.path, res.duration.seconds
    bp = np.asarray(path.breakpoints, float)
    tau = np.unique(np.clip(np.concatenate([np.linspace(0.0, 1.0, PLOT_SAMPLES), bp,
                                            jump_sides(bp, path.jumps)]), 0.0, 1.0))
    curves, rms = limit_use(motion_model(path, prof), T, tau, dwell=prof.planning.dwell)
    return tau * T, curves, rms


def _checkpointed_rows(ckpt, settings) -> int:
    """Rows saved in a build-table checkpoint (0 when there is none or it cannot be read)."""
    from .errors import PickplaceError
    from .table import read_checkpoint

    try:
        return len(read_checkpoint(ckpt, settings)) if ckpt is not None else 0
    except PickplaceError:
        return 0


def _build_vel_table(eta: float, workers: int, output: str, quiet: bool) -> None:
    """build-table --method bspline-vel: Yang 2022 optima on the default dimensionless grid."""
    import os

    from .errors import TableError
    from .export import atomic_output, check_writable
    from .table_vel import VelGrid, build_vel_table, format_vel_table

    if workers < 0:
        raise TableError(f"workers = {workers}: must be 0 (all cores) or a positive number")
    check_writable(output)
    grid = VelGrid(eta=eta)
    n_workers = workers or os.cpu_count() or 1
    if quiet:
        table = build_vel_table(grid, workers=n_workers)
    else:
        from rich.console import Console
        from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

        with Progress(TextColumn("{task.description}"), BarColumn(), TextColumn("{task.completed}/{task.total}"),
                      TimeElapsedColumn(), TimeRemainingColumn(), console=Console(stderr=True)) as progress:
            bar = progress.add_task("solving Yang 2022 optima (one node per symmetry orbit)", total=None)
            table = build_vel_table(grid, workers=n_workers,
                                    progress=lambda done, total: progress.update(bar, completed=done, total=total))
    with atomic_output(output) as stream:
        stream.write(format_vel_table(table, __version__))


def main() -> None:
    """Console-script entry point."""
    app()


if __name__ == "__main__":  # pragma: no cover
    main()
