"""`pickplace plan`'s options read and checked before anything is planned: values (exit 1), usage (exit 2), the
method's parameters, the columns and the time law's coefficients."""

from __future__ import annotations

from .app import (
    MAX_SHIFT,
    Compression,
    CsvDialectName,
    McapFlavor,
    MethodName,
    OptimizeWhat,
    OutputFormat,
    TurnDuring,
    TurnName,
    _finite,
    _usage,
)


#: the largest --tolerance of a table [rad or m]: 1 mrad or 1 mm (a larger one let a table of two points stand for
#: the move, 0.13 rad off it)
MAX_TOLERANCE = 1e-3


def _check_plan_values(a) -> None:
    """Values (exit 1): the time rule (normalised: any case and spacing), height, rate, k1/k2, η, limit use."""
    from ..model.errors import TaskError
    from ..model.headroom import check_limit_use
    from ..timing import parse_time

    a.time = parse_time(a.time)
    if not isinstance(a.time, str):
        a.time = repr(a.time)  # seconds, as the text the options carry
    if a.limit_use is not None:
        check_limit_use(a.limit_use)

    _finite("height", a.height)
    _finite("rate", a.rate)
    if a.rate is not None and not (0 < a.rate <= 1e6):
        raise TaskError(f"rate = {a.rate!r} Hz: the output rate must lie in (0, 1e6] Hz (as the profile's planning.rate)")
    if a.k1 is not None or a.k2 is not None:
        from ..paths.bspline import check_k

        for name, k in (("k1", a.k1), ("k2", a.k2)):
            if k is not None:
                check_k(name, k)
    if not (a.keep_warm == 0.0 or 0.001 <= a.keep_warm <= 10.0):  # (nan fails both)
        raise TaskError(f"keep_warm = {a.keep_warm!r} s: must be 0 (off) or in 0.001 ... 10 s (the pause between "
                        "two warm-ups; below 1 ms they would take the whole core)")
    if a.tolerance is not None and not (0 < a.tolerance <= MAX_TOLERANCE):  # (nan fails)
        raise TaskError(f"tolerance = {a.tolerance!r} (rad or m): a table's deviation must lie in (0, {MAX_TOLERANCE:g}] "
                        "(at most 1 mrad or 1 mm from the planned trajectory)")
    if a.eta is not None and not (0 < a.eta < 1):
        raise TaskError(f"eta = {a.eta!r}: the lift-off/set-down ratio η must lie strictly between 0 and 1")


def _rosbag2_format(ctx, fmt, output):
    """--rosbag2: the format (mcap; -f, when given, must say so) after the usage checks: a directory -o DIR."""
    source = ctx.get_parameter_source("fmt")
    if source is not None and source.name != "DEFAULT" and fmt != OutputFormat.mcap:
        _usage(f"--rosbag2 writes an MCAP bag: not with -f {fmt.value}")
    if output in (None, "-"):
        _usage("--rosbag2 writes a directory (DIR/DIR_0.mcap, DIR/metadata.yaml): give -o DIR")
    return OutputFormat.mcap


def _law_coefficients(text: str) -> int | None:
    """--law-coefficients: None for auto, else an integer in 8 ... 120 (TaskError, exit 1, otherwise)."""
    from ..model.errors import TaskError

    if text.strip().lower() == "auto":
        return None
    try:
        n = int(text)
    except ValueError:
        n = None
    if n is None or not 8 <= n <= 120:
        raise TaskError(f"law_coefficients = {text!r}: must be auto or a whole number in 8 ... 120 (coefficients of "
                        "the time law)")
    return n


def _shape_law_evals(n: int) -> int:
    """--shape-law-evals (a whole number: typer refuses others, exit 2): in 0 ... 1000 (TaskError, exit 1, otherwise)."""
    from ..model.errors import TaskError

    if not 0 <= n <= 1000:
        raise TaskError(f"shape_law_evals = {n}: must lie in 0 ... 1000 (law solves of the shape search; 0: the "
                        "screened search alone)")
    return n


def _read_written(a, fmt, columns, prof) -> str:
    """PlanOptions.read_written: how check will read the file: "" for a drive's table (judged as the drive
    interpolates it), "positions" when the written columns lack the tool's x … jz (``--columns``), else "tool".
    Columns check cannot read a move from (no t, or not every joint nor every drive): a usage error with --strict,
    else a warning."""
    import sys

    from .controller import table_format

    if table_format(fmt) and a.output is not None:
        return ""
    if columns is None:
        return "tool"
    from ..pipelines.check_read import TOOL_COLUMNS
    from ..planner import motion_model_static

    robot = motion_model_static(prof)[0]
    bare = {c.split("[")[0] for c in _selected(columns, prof, a.drive)}
    if not ("t" in bare and (set(robot.joint_names) <= bare or (a.drive is not None and set(a.drive.names) <= bare))):
        need = f"t and {', '.join(robot.joint_names)}" + (f" (or t and {', '.join(a.drive.names)})" if a.drive else "")
        if a.strict:
            _usage(f"--strict writes what check --strict accepts, and check reads a move from {need}: --columns "
                   f"{columns} leaves some out")
        sys.stderr.write(f"pickplace: warning: --columns {columns}: check cannot read the file (it reads a move from "
                         f"{need})\n")
    return "tool" if set(TOOL_COLUMNS) <= bare else "positions"


def _header_names(prof, drive) -> tuple[str, ...]:
    """The profile's CSV column names with their units (the drive's positions and velocities when it has drives)."""
    from ..export import column_names
    from ..planner import motion_model_static

    robot, specs = motion_model_static(prof)[:2]
    drives = all(s.drive is not None for s in specs)  # the motor columns: as the planner's MotionModel.has_drives
    names = column_names(robot.joint_units, motor_speed=drives, motor_torque=drives)
    if drive is not None:
        names += drive.position_names + drive.velocity_names
    return tuple(names)


def _selected(text: str, prof, drive) -> tuple[str, ...]:
    """The header names ``--columns`` selects (sets expanded, globs such as ``q?`` matched)."""
    from ..export.csv import parse_columns, select_columns
    from ..export.drive import expand_columns
    from ..planner import motion_model_static

    names = _header_names(prof, drive)
    n = len(motion_model_static(prof)[0].joint_units)
    return tuple(names[i] for i in select_columns(names, expand_columns(parse_columns(text), drive, n)))


def _columns(text: str | None, prof, drive=None) -> tuple[str, ...] | None:
    """``--columns`` as names, checked against the profile's CSV columns (usage error, exit 2: no such column,
    a column twice, none given)."""
    if text is None:
        return None
    from ..export.csv import parse_columns
    from ..model.errors import ExportError

    try:
        _selected(text, prof, drive)
    except ExportError as exc:
        _usage(f"--{exc}")
    return parse_columns(text)


def _check_plan_usage(a) -> None:
    """Usage (exit 2): options that contradict each other, or are set where they have no effect (refused, not
    ignored)."""
    batch, fmt = a.batch, a.fmt
    if batch is not None and (a.from_ is not None or a.to is not None):
        _usage("--batch takes the moves from the file; do not also give --from/--to")
    if batch is None and (a.from_ is None or a.to is None):
        _usage(f"missing --{'to' if a.from_ is not None else 'from'}: give both --from X,Y,Z and --to X,Y,Z in m (or --batch FILE)")
    if batch is not None and a.round_trip:
        _usage("--round-trip is not available with --batch (give each leg as a row)")
    if batch is None and (a.fail_fast or a.workers != 0):
        _usage(f"{'--fail-fast' if a.fail_fast else '-j/--workers'} only applies to --batch")
    if a.keep_warm != 0.0:
        if batch is None:
            _usage("--keep-warm only applies to a streamed --batch (- or a named pipe)")
        if a.workers > 1:
            _usage(f"--keep-warm plans the rows in this process, one at a time: give -j 1 (not -j {a.workers})")
    if batch is not None and (a.v_from is not None or a.v_to is not None):
        _usage("--v-from/--v-to: with --batch give the velocities of each row as columns v_from_x … v_to_z")
    if fmt != OutputFormat.mcap and (a.mcap_flavor != McapFlavor.ros2 or a.compression != Compression.none):
        what = f"--mcap-flavor {a.mcap_flavor.value}" if a.mcap_flavor != McapFlavor.ros2 else f"--compression {a.compression.value}"
        _usage(f"{what} only applies to --format mcap (the format is {fmt.value})")
    if a.rosbag2 and a.mcap_flavor != McapFlavor.ros2:
        _usage(f"--rosbag2 holds ROS 2 messages: not with --mcap-flavor {a.mcap_flavor.value}")
    if fmt != OutputFormat.csv and a.csv_dialect != CsvDialectName.default:
        _usage(f"--csv-dialect {a.csv_dialect.value} only applies to --format csv (the format is {fmt.value})")
    if fmt != OutputFormat.csv and a.columns is not None:
        _usage(f"--columns only applies to --format csv (the format is {fmt.value}: its schema is fixed)")
    if a.json_summary and a.output is None and (fmt != OutputFormat.csv or a.csv_dialect != CsvDialectName.default):
        _usage("--format/--csv-dialect: with --json and no -o FILE no trajectory is written (stdout carries the summary)")
    if a.json_summary and a.output is None and a.columns is not None:
        _usage("--columns: with --json and no -o FILE no trajectory is written (stdout carries the summary)")
    angles = batch is not None or any(len((x or "").split(",")) == 4 for x in (a.from_, a.to))
    if not angles and (a.turn != TurnName.shortest or a.turn_during != TurnDuring.transfer):
        what = f"--turn {a.turn.value}" if a.turn != TurnName.shortest else f"--turn-during {a.turn_during.value}"
        _usage(f"{what} only applies with tool angles: --from/--to X,Y,Z,THETA (or batch columns from_theta, to_theta)")
    if a.adjust_points and not a.fit_ws:
        _usage("--adjust-points only applies with --fit-workspace")
    if a.max_shift != MAX_SHIFT and not a.adjust_points:
        _usage("--max-shift only applies with --adjust-points")
    if a.json_summary and a.report == "-":
        _usage("--report -: with --json stdout carries the summary; give --report a file")
    if a.json_summary and a.output == "-":
        _usage("-o -: with --json stdout carries the summary; give -o a file for the trajectory")


def _finite_latency(latency: float) -> None:
    import math

    from ..model.errors import TaskError

    if not (math.isfinite(latency) and latency >= 0):
        raise TaskError(f"latency = {latency!r}: must be a finite number of seconds >= 0 (detection to move start)")


def _method_params(a) -> dict:
    """The method's parameters: --param NAME=VALUE, and --k1/--k2/--table where the method takes them."""
    params: dict = _parse_params(a.param or [])
    k_given = a.k1 is not None or a.k2 is not None
    if a.method == MethodName.bspline:
        params.update({"k1": a.k1, "k2": a.k2, "table": a.table})
    elif a.method == MethodName.bspline_vel and a.table is not None and not k_given:
        params.update({"solver": "seeded", "table": a.table})  # that table seeds the exact polish
    elif k_given or a.table is not None:
        _usage(f"--k1/--k2/--table belong to --method bspline (--table also to bspline-vel), not {a.method.value}")
    return params


def _check_shape_usage(a) -> None:
    """Usage (exit 2) of --fit-workspace with --batch, --optimize shape, --hold-capacity and --strict."""
    from .controller import table_format

    if a.batch is not None and a.fit_ws:
        _usage("--fit-workspace is not available with --batch")
    shape = a.optimize == OptimizeWhat.shape
    if shape and a.method != MethodName.bspline:
        _usage(f"--optimize shape chooses k1, k2, η of --method bspline; method {a.method.value} has no such shape")
    if shape and a.time not in ("fit", "optimal", "limits"):
        _usage(f"--optimize shape minimises the fitted duration on the robot's limits: use it with --time limits "
               f"(the default), fit or optimal (not --time {a.time})")
    if a.shape_law_evals and not (shape and a.time == "optimal"):
        _usage(f"--shape-law-evals judges shapes by the optimal law: use it with --optimize shape --time optimal "
               f"(not {'--time ' + str(a.time) if shape else 'without --optimize shape'})")
    if str(a.law_coefficients).strip().lower() != "auto" and a.time != "optimal":  # (given: its value is checked after)
        _usage(f"--law-coefficients shapes the time law of --time optimal (--time {a.time} scales the path uniformly)")
    if a.strict and a.time not in ("limits", "auto", "fit", "optimal"):
        _usage(f"--strict slows the law of a duration rule until check --strict accepts the written samples: use it "
               f"with --time limits (the default), auto, fit or optimal (a duration of {a.time} s is given)")
    if a.strict and a.fmt == OutputFormat.mcap:
        _usage("--strict writes what check --strict accepts, and check reads CSV and JSON trajectories, not MCAP: "
               "write -f csv or -f json")
    if a.strict and table_format(a.fmt) and a.output is not None:
        _usage(f"--strict reads sampled files as check --strict does: a drive's table (-f {a.fmt.value}) is judged as "
               "the drive interpolates it")
    if a.hold_capacity and a.time not in ("fit", "optimal"):
        _usage(f"--hold-capacity applies to --time fit or optimal (--time {a.time} "
               f"{'holds the capacity already' if a.time in ('auto', 'limits') else 'is given'})")
    if shape and (a.k1 is not None or a.k2 is not None):
        _usage("--optimize shape chooses k1 and k2 itself: drop --k1/--k2 (or drop --optimize)")


def _parse_params(items: list[str]) -> dict:
    """--param NAME=VALUE items → {name: float}; one-line TaskError for a malformed item."""
    import math

    from ..model.errors import TaskError

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
    from .app import GIVEN_PARAMS

    GIVEN_PARAMS.update(out)
    return out
