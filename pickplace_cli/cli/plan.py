"""`pickplace plan`: parse the options → plan one move, a round trip or a conveyor rendezvous (or hand a batch over) → render."""

from __future__ import annotations

import sys
from typing import Optional

import typer

from .app import (
    Panel,
    _complete_profile,
    _finite,
    _handle_errors,
    _JSON_ERRORS,
    _parse_point,
    _parse_pose,
    _usage,
    note_exit,
    app,
    Compression,
    CamMaster,
    TableEnd,
    CamObject,
    CsvDialectName,
    MAX_SHIFT,
    McapFlavor,
    MethodName,
    OptimizeWhat,
    OutputFormat,
    StDialect,
    TurnDuring,
    TurnName,
)
from .batch import _plan_batch
from .plan_options import (
    _rosbag2_format,
    _check_plan_usage,
    _check_plan_values,
    _check_shape_usage,
    _columns,
    _finite_latency,
    _law_coefficients,
    _read_written,
    _shape_law_evals,
    _method_params,
)
from .render import (
    _check_output_paths,
    _emit_json,
    _json_summary,
    _print_limit_table,
    _print_rendezvous,
    _print_summary,
    _print_verdict,
    _write_report,
    _writer,
)


@app.command()
@_handle_errors
def plan(
    ctx: typer.Context,
    from_: Optional[str] = typer.Option(None, "--from", help="Pick point X,Y,Z in m (base frame), e.g. -0.1525,0,-0.8; "
                                        "X,Y,Z,THETA adds the tool angle THETA in rad about the base z axis (a profile "
                                        "with a rotary fourth axis; three numbers: the tool does not turn).", rich_help_panel=Panel.MOVE),
    to: Optional[str] = typer.Option(None, "--to", help="Place point X,Y,Z in m (base frame), or X,Y,Z,THETA with the "
                                     "tool angle in rad (give it with --from too).", rich_help_panel=Panel.MOVE),
    turn: TurnName = typer.Option(
        TurnName.shortest, "--turn", help="With tool angles (--from/--to X,Y,Z,THETA, or batch columns from_theta, "
        "to_theta [rad]): the way round to the end angle: shortest (at most half a turn), ccw or cw (always "
        "counter-clockwise or clockwise seen from above), as-given (to exactly THETA, even beyond a turn).",
        rich_help_panel=Panel.MOVE,
    ),
    turn_during: TurnDuring = typer.Option(
        TurnDuring.transfer, "--turn-during", help="With tool angles: when the tool turns: transfer (between lift-off "
        "and set-down, the heights of η of the rise: the part is not turned while the gripper engages it at either "
        "end) or whole (over the whole move: lower peaks on the fourth axis).",
        rich_help_panel=Panel.MOVE,
    ),
    profile: Optional[str] = typer.Option(
        None, "--profile", "-p", help="Profile YAML file, or the name of a shipped profile. [default: delta-su2018]",
        autocompletion=_complete_profile,
        rich_help_panel=Panel.MOVE,
    ),
    height: Optional[float] = typer.Option(
        None, "--height", help="Clearance h in m of the path's midpoint above the higher end point. [default: profile]", rich_help_panel=Panel.MOVE
    ),
    eta: Optional[float] = typer.Option(
        None, "--eta", help="Lift-off/set-down ratio η, 0 < η < 1 (dimensionless). [default: profile]", rich_help_panel=Panel.MOVE
    ),
    v_from: Optional[str] = typer.Option(
        None, "--v-from", "--from-belt", help="Tool velocity VX,VY,VZ in m/s (base frame) leaving the pick point, e.g. the pick "
        "conveyor's; a velocity other than 0 selects --method bspline-vel unless -m names one. [default: profile "
        "workcell.conveyor_pick_velocity, else 0]", rich_help_panel=Panel.BELT
    ),
    v_to: Optional[str] = typer.Option(
        None, "--v-to", help="Tool velocity VX,VY,VZ in m/s arriving at the place point; a velocity other than 0 "
        "selects --method bspline-vel unless -m names one. [default: profile workcell.conveyor_place_velocity, else 0]", rich_help_panel=Panel.BELT
    ),
    to_belt: Optional[str] = typer.Option(
        None, "--to-belt", help="Conveyor rendezvous: the part at --to (m, when it was detected) moves at VX,VY,VZ m/s "
        "(base frame); the move meets it where it is after --latency + T and arrives with this velocity, then tracks it "
        "for the profile's dwell (s). Selects --method bspline-vel. With --round-trip: the whole belt cycle (pick, track, "
        "place back at --from, dwell at rest).",
        rich_help_panel=Panel.BELT,
    ),
    latency: Optional[float] = typer.Option(
        None, "--latency", help="With --to-belt: seconds (>= 0) from the part's detection to the start of the move "
        "(vision + planning + bus); the trajectory's t = 0 is the start of the move. With a belt schedule (--batch "
        "with t_detect): the rows' earliest move start after their detection. [default: 0]",
        rich_help_panel=Panel.BELT,
    ),
    method: MethodName = typer.Option(MethodName.bspline, "--method", "-m", help="Planning method.", rich_help_panel=Panel.METHOD),
    k1: Optional[float] = typer.Option(None, "--k1", help="B-spline time-ratio factor k1 = τ8/τ9 (overrides the table).", rich_help_panel=Panel.METHOD),
    k2: Optional[float] = typer.Option(None, "--k2", help="B-spline time-ratio factor k2 = τ7/τ8 (overrides the table).", rich_help_panel=Panel.METHOD),
    table: Optional[str] = typer.Option(
        None, "--table", help="bspline: λ → (k1, k2) table CSV; bspline-vel: conveyor table that seeds the exact "
        "solve. [default: shipped table]", rich_help_panel=Panel.METHOD
    ),
    param: Optional[list[str]] = typer.Option(
        None, "--param", help="A method parameter NAME=VALUE (repeatable): ph m=, r= (corner extents in m); "
        "lame m= (exponent, >= 3); piecewise-poly ratio= (τv/τu); bspline arch= (m), k3=, k4=, mid= (-), "
        "eta_down= (set-down ratio, -), mid_x= (apex along the span, -); bspline-vel margin=, tau6= … lambda3=. "
        "[default: the paper's values]",
        rich_help_panel=Panel.METHOD,
    ),
    time: str = typer.Option(
        "limits",
        "--time",
        "-t",
        help="Duration of the move in s, or a rule: 'limits' (the shortest duration at which every limit of the "
        "profile holds: joint and motor limits, RMS torque and the Cartesian capacity), 'auto' (the Cartesian "
        "capacity alone, Li 2018 Eq. 26), 'fit' (the joint and motor limits alone, path scaled uniformly in time), "
        "or 'optimal' (the same path with a non-uniform, jerk-bounded time law that minimises the duration under the "
        "same joint and motor limits, RMS included; ~0.05-1 s more; not for bspline-vel). Names in any case. fit and "
        "optimal ride a motor limit: their written samples are read as check reads them and the law is slowed until "
        "they pass (the summary says by how much). fit "
        "and optimal do not hold the Cartesian capacity: its rows are reported as not held and a move beyond it "
        "exits 0 with the verdict saying so (--hold-capacity holds it).",
        rich_help_panel=Panel.METHOD,
    ),
    limit_use: Optional[float] = typer.Option(
        None, "--limit-use", metavar="FRACTION", help="Headroom: plan and check every timed limit (joint speed, "
        "acceleration, jerk, motor speed, torque, torque rate, RMS torque, Cartesian capacity) to at most this "
        "fraction of its rating, in (0, 1], e.g. 0.9 keeps 10 % in reserve. The limit table shows use against the "
        "rating and this target. [default: profile planning.limit_use, else 1]",
        rich_help_panel=Panel.LIMITS,
    ),
    optimize: OptimizeWhat = typer.Option(
        OptimizeWhat.none, "--optimize", help="'shape' (--method bspline): also choose the path's k1, k2 and η "
        "(η within [0.1, 0.9]; give --eta to hold it) for the smallest duration on this robot's limits, instead of "
        "the table's values (Li 2018's Cartesian optimum); with --time limits (the default), fit or optimal (the "
        "duration, the fit and the law are then those of the chosen shape). The summary compares it with the table's shape. ~0.5-1 s more.",
        rich_help_panel=Panel.METHOD,
    ),
    law_coefficients: str = typer.Option(
        "auto", "--law-coefficients", metavar="auto|N", help="With --time optimal: coefficients of the time law's "
        "quintic B-spline b(τ) [-], on uniform knots in the path parameter, solved by sequential quadratic programming "
        "(without the daqp package: scipy's SLSQP on a cubic law, 20 coefficients refined to 40). auto: 60 (SLSQP: 20 refined to 40). N (8 ... 120): N coefficients. "
        "More: closer to the continuous optimum, slower (Adept cycle, one core, the whole plan: about 50 ms at 40, "
        "65 ms at 60, 100 ms at 90, 165 ms at 120; 0.35 %, 0.23 % and 0.16 % above an independent optimum at 60, 90 "
        "and 120).",
        rich_help_panel=Panel.METHOD,
    ),
    hold_capacity: bool = typer.Option(
        False, "--hold-capacity", help="With --time fit or optimal (and --optimize shape): also hold the profile's "
        "Cartesian capacity |v| ≤ capacity.velocity [m/s], |a| ≤ capacity.acceleration [m/s²] (and |j| ≤ capacity.jerk "
        "[m/s³] when set), e.g. for a payload or gripper that limits the tool (exceeded: exit 3). Default: off, fit "
        "and optimal hold the joint and motor limits only (auto holds the capacity only): the capacity's rows are "
        "still in the limit table and JSON, marked not held, and an exceeded capacity is said on stderr and in the "
        "verdict (exit 0).",
        rich_help_panel=Panel.LIMITS,
    ),
    strict: bool = typer.Option(
        False, "--strict", help="Write samples that check --strict accepts: the plan reads its written samples as "
        "check does, also every other one for each peak's stated accuracy, and slows the time law until every peak is "
        "resolved by them (within its limit at that accuracy, or known to 1 % of the limit); a peak still not resolved "
        "is exit 3. For --time limits, auto, fit and optimal and a file check reads (CSV, JSON), not MCAP nor a drive's table "
        "(judged as the drive interpolates it) nor a duration given in seconds. Costs two readings (+5 to +25 ms); "
        "without it, check accepts the file and --strict may find a peak of a time-optimal law at 1 kHz not resolved.",
        rich_help_panel=Panel.LIMITS,
    ),
    show_fit: bool = typer.Option(
        False, "--show-fit", help="With --time auto or seconds: also compute the fitted duration (the smallest at "
        "which every joint and motor limit holds) and report it next to the chosen one (fit_s in --json). Costs "
        "~0.5 s of start-up (scipy.optimize); --time fit always computes it.",
        rich_help_panel=Panel.METHOD,
    ),
    shape_law_evals: int = typer.Option(
        0, "--shape-law-evals", metavar="N", show_default=False, help="With --optimize shape --time optimal: after the screened search, "
        "COBYQA (scipy's model-based solver) over the shape family with the optimal law's duration [s] itself as the "
        "objective, at most this many law solves (0-1000, out of range: exit 1; each ~0.1 s CPU, ~0.5-3 s with the SLSQP "
        "solver) after the 1-3 that judge the screened candidates; the summary's shape line counts both. 30 bring "
        "the Adept cycle from 1.016 to 1.011 × the free-path minimum time (capacity held: 1.021 to 1.013 ×). "
        "[default: 0, the screened search alone]",
        rich_help_panel=Panel.METHOD,
    ),
    rate: Optional[float] = typer.Option(None, "--rate", help="Samples per second in Hz; a move of fewer than 100 samples (or a file of the joint positions alone) is read back as check reads it and slowed until it passes; fewer than 6 samples: refused (exit 1), but for a drive's table. [default: profile]", rich_help_panel=Panel.METHOD),
    cycle: Optional[str] = typer.Option(
        None, "--cycle", metavar="SECONDS|off", help="The controller's cycle in s (e.g. 0.001): the duration and the "
        "dwell are rounded up to whole cycles, the limits checked again on the rounded move (a cycle more when it "
        "breaks one that held), one sample per cycle at t = k*cycle (the tsv dialect writes k); the summary says what "
        "the rounding cost. A conveyor move's meeting is solved again for its rounded duration; a belt cycle "
        "(--to-belt --round-trip) or belt schedule has every leg, dwell and start on whole cycles. off: sample at "
        "--rate. [default: profile controller.cycle, else off]",
        rich_help_panel=Panel.CONTROLLER,
    ),
    tolerance: Optional[float] = typer.Option(
        None, "--tolerance", help="pvt, cam, cam-table: the largest deviation in rad (revolute joint) or m (linear) of "
        "the controller's interpolation of the table from the planned trajectory; the table has the fewest points that "
        "hold it and, as the drive interpolates it, every limit (more points, else a slower table; exit 3 when it "
        "cannot; PVT steps bounded by the torque rate over one cycle). The achieved error is reported. A cam-table on a "
        "controller cycle has a point every cycle, and between two the drive runs a straight line: its deviation is the "
        "cycle's, reported beside the tolerance, not refused. At most 0.001 (1 mrad or 1 mm). [default: 1e-6]",
        rich_help_panel=Panel.CONTROLLER,
    ),
    st_dialect: StDialect = typer.Option(
        StDialect.strict, "--st-dialect", help="pvt-st, cam-st, cam-table-st: strict (IEC 61131-3: a FUNCTION_BLOCK "
        "holding the tables, for any compiler) or codesys (a VAR_GLOBAL CONSTANT list, CODESYS/TwinCAT).",
        rich_help_panel=Panel.CONTROLLER,
    ),
    pvt_integer: bool = typer.Option(
        False, "--pvt-integer", help="pvt, pvt-st: the drive's integer units: segment times in whole ms (1-255; a "
        "longer segment is split on its own cubic; needs a whole-ms --cycle), positions in encoder counts and "
        "velocities in counts/s as int32 (every profile controller.joints unit counts). A value past int32 is exit 1.", rich_help_panel=Panel.CONTROLLER),
    cam_master: CamMaster = typer.Option(
        CamMaster.time, "--cam-master", help="cam, cam-table: the master axis: time [s] from the start, or belt (with "
        "--to-belt): the belt's travel [m] since the part's detection.",
        rich_help_panel=Panel.CONTROLLER,
    ),
    table_end: TableEnd = typer.Option(
        TableEnd.hold, "--table-end", rich_help_panel=Panel.CONTROLLER,
        help="pvt, cam, cam-table (and -st): before a table that starts moving and after one that ends moving (a "
        "conveyor move ends at the belt's speed): hold (the drive holds the end point: the velocity step to or from "
        "rest, within one controller cycle, is judged) or continue (the controller goes on at the end's velocity, "
        "e.g. geared to the belt; not judged past the end, which the summary says; check it with the same option)."),
    cam_object: CamObject = typer.Option(
        CamObject.none, "--cam-object", rich_help_panel=Panel.CONTROLLER,
        help="cam-st, cam-table-st: one cam object per joint in the controller's own types, in a PROGRAM "
        "PRG_PickplaceCams that fills them on its first call. codesys: SoftMotion MC_CAM_REF with SMC_CAMXYVA points "
        "(cam-st; dV, dA per master unit and unit^2) or SMC_CAMTable_LREAL_128_1/_256_1 (cam-table-st: exactly 128 or "
        "256 equidistant points; a table needing more is exit 1). twincat: NC camming MC_CAM_REF with "
        "MC_MotionFunctionPoint rows of type POLYNOM5_MM (cam-st) or a two-column ARRAY[0..n-1, 0..1] OF LREAL "
        "(master [s|m], slave) equidistant table (cam-table-st, linear). none: one table of every joint.",
    ),
    plcopen_xml: bool = typer.Option(
        False, "--plcopen-xml", rich_help_panel=Panel.OUTPUT,
        help="pvt-st, cam-st, cam-table-st: write the Structured Text as a PLCopen XML project (TC6 XML v2.01: its "
        "function blocks and programs as POUs with typed variables, initial values and the ST body; a codesys "
        "global constant list as a configuration's constant globalVars), for CODESYS (Project > Import PLCopenXML), "
        "TwinCAT 3 (PLC project > Import PLCopenXML) and Beremiz (a project's plc.xml). Deterministic: a fixed "
        "creationDateTime (2000-01-01T00:00:00), no clock read.",
    ),
    batch: Optional[str] = typer.Option(
        None, "--batch", help="Plan many moves from a CSV file; '-' (stdin) or the path of a named pipe is streamed: "
        "each row answered and flushed as soon as it is read. Columns from_x,from_y,from_z,to_x,to_y,to_z "
        "[m], optional height [m], eta, v_from_x.. v_to_z [m/s], time [s|auto|fit|optimal], from_theta, to_theta "
        "[rad, the tool angle at the ends: a profile with a rotary fourth axis]; a belt row (as "
        "--to-belt): to_belt_vx,to_belt_vy,to_belt_vz [m/s] and optional latency [s >= 0]. Output gets a move column. "
        "A t_detect column makes it a belt schedule (one detected part per row, in time order, the robot's state "
        "carried over): t_detect [s], to_x,to_y,to_z [m, where the part was seen], to_belt_vx,to_belt_vy,to_belt_vz "
        "[m/s], place_x,place_y,place_z [m], optional latency [s >= 0, default --latency], height, eta, time, "
        "from_x,from_y,from_z [m, row 1 only: the robot's start], to_theta [rad, the part's angle as detected], "
        "place_theta [rad], from_theta [rad, row 1 only].", rich_help_panel=Panel.BATCH
    ),
    fail_fast: bool = typer.Option(False, "--fail-fast", help="With --batch: stop at the first row that fails.", rich_help_panel=Panel.BATCH),
    workers: int = typer.Option(
        0, "--workers", "-j", help="With --batch: planner processes (0 = all cores for 100 rows or more, else 1). "
        "Results are the same and in row order whatever the number.", rich_help_panel=Panel.BATCH
    ),
    keep_warm: float = typer.Option(
        0.0, "--keep-warm", metavar="SECONDS",
        help="With a streamed --batch (- or a named pipe): while no row is waiting, plan the last move again every "
        "SECONDS s (nothing written) so the CPU's caches stay warm for the next row: 0.5-0.9 ms less latency for "
        "rows 100 ms apart, for CPU time while idle (~40 % of a core at 0.002, ~25 % at 0.005, ~10 % at 0.02). "
        "0 = off; 0.001 ... 10 s. Warming stops 60 s after the last row, until the next. Rows are then planned "
        "one at a time in this process (-j 1).",
        rich_help_panel=Panel.BATCH,
    ),
    round_trip: bool = typer.Option(
        False, "--round-trip", help="Write there, dwell, back, dwell (the profile's dwell in s) as one trajectory. With "
        "--to-belt: the belt cycle: pick from the belt, track the part for the dwell, place back at --from (leaving "
        "with the belt velocity), dwell at rest.", rich_help_panel=Panel.MOVE
    ),
    fmt: OutputFormat = typer.Option(
        OutputFormat.csv, "--format", "-f", help="Output format: samples as csv, json or mcap; or a table a motion "
        "kernel interpolates itself: pvt (position, velocity, time per point; cubic Hermite), cam (PLCopen MC_CamIn "
        "points with position, velocity, acceleration: 5th-order segments), cam-table (equidistant positions, linear), "
        "as CSV or, with -st, IEC 61131-3 Structured Text. Drive names and units from profile controller.joints. "
        "Without -f: the one -o FILE's suffix names (.csv, .tsv, .txt: csv; .json; .mcap), else csv. A -f that "
        "contradicts the suffix is refused, and so is MCAP to a terminal.",
        rich_help_panel=Panel.OUTPUT,
    ),
    csv_dialect: CsvDialectName = typer.Option(
        CsvDialectName.default, "--csv-dialect",
        help="CSV flavour: default (',' LF, header), twincat (';' CRLF, header), tsv (tab, no header).",
        rich_help_panel=Panel.OUTPUT,
    ),
    columns: Optional[str] = typer.Option(
        None, "--columns", help="CSV: write only these columns, in this order: header names without units "
        "(t, x, vx, ax, jx, q1, qd1, qdd1, torque1, motor_speed1, motor_torque1, …), or with the unit exactly as the "
        "header prints it (q1[rad], torque1[N*m]), or shell-style globs (q?, q[12], motor_*), comma-separated, e.g. "
        "t,q1,q2,q3 for a PLC's position feed. The drive's view of each joint (profile controller.joints: NAME[unit], "
        "NAME_vel[unit/s]) by name or by the sets drive, drive_vel and plc (= t,drive): --columns plc. A batch's move "
        "column stays first. Default: every column but the drive's.",
        rich_help_panel=Panel.OUTPUT,
    ),
    mcap_flavor: McapFlavor = typer.Option(
        McapFlavor.ros2, "--mcap-flavor", help="MCAP: ros2 (CDR, ROS 2 messages) or foxglove (JSON, Foxglove schemas).", rich_help_panel=Panel.OUTPUT
    ),
    compression: Compression = typer.Option(Compression.none, "--compression", help="MCAP chunk compression.", rich_help_panel=Panel.OUTPUT),
    rosbag2: bool = typer.Option(
        False, "--rosbag2", help="MCAP (ros2 flavour; implies -f mcap): write -o DIR as a rosbag2 directory, "
        "DIR/DIR_0.mcap and DIR/metadata.yaml, as ros2 bag play and ros2 bag info read it. DIR must be new or empty.", rich_help_panel=Panel.OUTPUT),
    output: Optional[str] = typer.Option(
        None, "--output", "-o", help="Output file ('-' = stdout, the default without --json). Written atomically.", rich_help_panel=Panel.OUTPUT
    ),
    report: Optional[str] = typer.Option(None, "--report", help="Also write the limit report as JSON to this file.", rich_help_panel=Panel.OUTPUT),
    write_anyway: bool = typer.Option(
        False,
        "--write-anyway",
        help="Write the trajectory and exit 0 even when a timed limit is exceeded (exit 3: a speed, torque, torque "
        "rate, RMS torque or the Cartesian capacity; the report still says so), also for the rows of a batch. "
        "Never for a position: a move past a joint's range, the singularity margin or the workcell box (exit 4) is "
        "not written, nor is an unreachable or invalid one; --fail-fast still exits with the row it stopped at.",
        rich_help_panel=Panel.LIMITS,
    ),
    report_only: bool = typer.Option(False, "--report-only", hidden=True,
                                     help="Deprecated name of --write-anyway (warns once).", rich_help_panel=Panel.OUTPUT),
    json_summary: bool = typer.Option(
        False, "--json", help="Print a JSON summary (durations in s, cycle time, picks/min, verdict) on stdout "
        "instead of the trajectory (one line per row with --batch); the trajectory then goes only to -o FILE.",
        rich_help_panel=Panel.OUTPUT,
    ),
    fit_ws: bool = typer.Option(
        False, "--fit-workspace", help="If the path leaves the workcell box or the reachable set, lower the height "
        "in 1 mm steps until it fits (Su 2018 Sec. II.E) and say what changed.", rich_help_panel=Panel.LIMITS
    ),
    adjust_points: bool = typer.Option(
        False, "--adjust-points", help="With --fit-workspace: move a pick/place point that lies outside to the nearest "
        "inside point by Su 2018's potential field (Eq. 25), and report the distance. Never done silently.", rich_help_panel=Panel.LIMITS
    ),
    max_shift: float = typer.Option(
        MAX_SHIFT, "--max-shift", help="With --adjust-points: the largest allowed move of a point in m (farther: exit 4).", rich_help_panel=Panel.LIMITS
    ),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="Nothing on stderr but errors and exceeded limits.", rich_help_panel=Panel.OUTPUT),
) -> None:
    """Plan one move (or a round trip, or a batch), check it against the robot's limits, write the samples.

    CSV columns: t[s], x y z [m], vx… [m/s], ax… [m/s^2], jx… [m/s^3], then per joint q<i>, qd<i>, qdd<i>,
    then torque<i> (joint side, N*m or N), motor_speed<i> [rad/s], motor_torque<i> [N*m]; a batch or round
    trip adds a leading move column. Exit 3 when a limit the duration rule holds is exceeded (--time fit and
    optimal do not hold the Cartesian capacity: exceeded, it is reported and exits 0), 4 when a point is
    unreachable, a joint leaves its position range or the tool leaves the workcell box, 1 for invalid input; a batch
    exits with the highest code of its rows (with --report-only, of the rows that are not written).
    """
    from types import SimpleNamespace

    from ..model.profile import load_profile
    from ..planner import PlanOptions

    if report_only:
        sys.stderr.write("pickplace: warning: --report-only is deprecated: it is --write-anyway, which writes a move "
                         "that exceeds a timed limit (exit 3) but never one past a joint range or the workcell (exit 4)\n")
        write_anyway = report_only = True
    a = SimpleNamespace(**{k: v for k, v in locals().items() if k not in ("SimpleNamespace", "load_profile",
                                                                         "PlanOptions")})
    _JSON_ERRORS[0] = json_summary  # (a batch: its rows have their lines; an error that ends it gets one more)
    from .guards import output_format

    if rosbag2:
        fmt = _rosbag2_format(ctx, fmt, output)
    fmt = a.fmt = output_format(ctx, fmt, output if output is not None or json_summary else "-")
    _check_plan_values(a)
    _check_plan_usage(a)
    if a.output is None and not json_summary:
        a.output = "-"
    _check_output_paths(a.output, report, bag=rosbag2)
    from .guards import refuse_overwriting_inputs

    refuse_overwriting_inputs([("-o", a.output), ("--report", report)], [("--batch", batch), ("--table", table)], profile)
    if batch is not None and to_belt is None and latency is not None:  # a belt schedule's default row latency
        _finite_latency(latency)
    elif to_belt is not None or latency is not None:
        a.method = _belt_method(ctx, method, to_belt, latency, v_to, batch, round_trip, fit_ws, optimize)
    elif batch is None and (v_from is not None or v_to is not None):
        a.method = _moving_ends_method(ctx, method, v_from, v_to)
    from ..model.headroom import apply_limit_use

    prof = apply_limit_use(load_profile(profile), limit_use)  # --limit-use, else the profile's planning.limit_use
    from .units import check_option_units, refuse_unreadable, warn_few_samples

    check_option_units(a, prof)  # --from/--to/--height in mm refused, --time in ms warned (cli/units.py)
    params = _method_params(a)
    from ..export.drive import drive_map
    from .controller import check_cycle_usage, resolve_cycle

    a.cycle_s = resolve_cycle(cycle, rate, prof)
    check_cycle_usage(a, a.cycle_s, fmt)
    a.drive = drive_map(prof)
    writer = _writer(fmt, csv_dialect, mcap_flavor, compression, _columns(columns, prof, a.drive), a.drive, rosbag2)
    _check_shape_usage(a)
    # (values after their usage: an option that does not apply is said first)
    a.shape_law_evals = shape_law_evals = _shape_law_evals(shape_law_evals)
    law_coefficients = _law_coefficients(law_coefficients)
    options = PlanOptions(method=a.method.value, method_params=params, time=a.time, rate=rate,
                          fit=a.time == "fit" or show_fit, shape=a.optimize == OptimizeWhat.shape,
                          hold_eta=eta is not None, hold_capacity=hold_capacity, shape_law_evals=shape_law_evals,
                          law_coefficients=law_coefficients, limit_use=limit_use,
                          cycle=a.cycle_s, turn=turn.value, turn_during=turn_during.value,
                          read_written=_read_written(a, fmt, columns, prof), strict=strict)
    if batch is not None:
        from .guards import cap_workers

        workers = cap_workers(workers, "must be 0 (automatic) or a positive number of processes")
        source = ctx.get_parameter_source("method")
        belt = {"latency": latency, "method_given": source is not None and source.name != "DEFAULT"}
        _plan_batch(batch, prof, options, height, eta, fail_fast, writer, a.output, report, write_anyway, json_summary,
                    quiet, workers, belt, keep_warm)
        return
    task, workspace_fit, vel_from = _single_task(a, prof, params)
    rendezvous = track = None
    a.rendezvous = a.belt_cycle = None
    if to_belt is not None:
        legs, rendezvous, track, a.belt_cycle = _plan_to_belt(task, to_belt, latency, prof, a.time, vel_from, params,
                                                             rate, options, round_trip)
        a.rendezvous = rendezvous
    else:
        legs = [_run_plan(task, prof, options)]
    if round_trip and a.belt_cycle is None:  # back the same way: from the angle reached to the start's, retracing the turn
        from dataclasses import replace

        from ..model.task import Task

        back = Task(task.p_to, task.p_from, task.height, task.eta, theta_from=legs[0].task.theta_to,
                    theta_to=task.theta_from)
        legs.append(_run_plan(back, prof, replace(options, turn=TurnName.as_given.value)))
    refuse_unreadable(legs, options, rate, a.cycle_s, '--cycle' if cycle is not None else "the profile's controller.cycle")
    warn_few_samples(legs, rate, a.cycle_s, '--cycle' if cycle is not None else "the profile's controller.cycle")
    code, cycle = _render_legs(a, prof, legs, rendezvous, track)
    forgiven = write_anyway and code == 3  # a timed limit only: a position past its range is never written
    note_exit(0 if forgiven else code)  # the verdict, should stdout's reader go away before the end
    code = _write_plan_outputs(a, prof, writer, legs, track, code)  # a table's own verdict may raise it
    forgiven = write_anyway and code == 3
    note_exit(0 if forgiven else code)
    if forgiven and strict and a.output is not None:  # written as asked, but not what --strict promises
        sys.stderr.write("pickplace: warning: --strict: the file is written (--write-anyway) although check --strict "
                         "refuses it (exit 3)\n")
    if json_summary:
        _emit_json(_single_json(a, legs, cycle, code, forgiven, workspace_fit, rendezvous, track))
    if code and not forgiven:
        if a.output is not None:
            from .hints import not_written

            sys.stderr.write(f"pickplace: {not_written(legs + ([track] if track is not None else []), prof, options, code, getattr(a, 'table_info', None))}\n")
        raise typer.Exit(code)


def _single_json(a, legs, cycle, code, forgiven, workspace_fit, rendezvous, track) -> dict:
    """The --json document of one move, round trip or belt cycle: the plan's, with the belt cycle, the cycle's
    rounding cost [s] and the table written, where there are."""
    doc = _plan_json(legs, cycle, code, forgiven, workspace_fit, rendezvous, track)
    if a.belt_cycle is not None:
        doc["belt_cycle"] = a.belt_cycle.as_dict()
    if a.cycle_s is not None:
        from .controller import cycle_cost

        doc["cycle_rounding_cost_s"] = cycle_cost(legs, a.round_trip)
    if getattr(a, "table_info", None) is not None:
        doc["table"] = a.table_info
        if not a.table_info["limits_ok"] and "all_limits_ok" in doc:  # the table's rows are limits too
            doc["all_limits_ok"] = False
    return doc


def _single_task(a, prof, params: dict):
    """(task, workspace fit or None, velocity leaving the pick point) of a one-move plan: the points, height,
    η and end velocities from the options and the profile; --fit-workspace applied."""
    from ..model.errors import TaskError
    from ..model.task import Task

    p_from, th_from = _parse_pose("from", a.from_)
    p_to, th_to = _parse_pose("to", a.to)
    if (th_from is None) != (th_to is None):
        given, other, text = ("from", "to", a.from_) if th_to is None else ("to", "from", a.to)
        raise TaskError(f"{given} = {text!r}: a tool angle THETA (the fourth number, rad) needs one at --{other} too "
                        "(or give neither: the tool does not turn)")
    h = a.height if a.height is not None else prof.planning.height
    e = a.eta if a.eta is not None else prof.planning.eta
    wc = prof.workcell
    vel_from = _parse_point("v-from", a.v_from, "m/s") if a.v_from is not None else (getattr(wc, "conveyor_pick_velocity", None) or (0.0, 0.0, 0.0))
    vel_to = _parse_point("v-to", a.v_to, "m/s") if a.v_to is not None else (getattr(wc, "conveyor_place_velocity", None) or (0.0, 0.0, 0.0))
    moving_ends = any(vel_from) or any(vel_to)
    if a.method != MethodName.bspline_vel and (a.v_from is not None or a.v_to is not None) and moving_ends:
        raise TaskError(
            f"v-from/v-to: method {a.method.value} plans moves from rest to rest; use --method bspline-vel "
            "for moving ends (conveyor tracking, Yang 2022)"
        )
    if a.method != MethodName.bspline_vel:
        vel_from = vel_to = (0.0, 0.0, 0.0)  # the profile's conveyors concern bspline-vel only
    if a.round_trip and moving_ends and a.method == MethodName.bspline_vel:
        _usage("--round-trip dwells at rest between the legs: not possible with moving ends (--v-from/--v-to)")
    task = Task(p_from, p_to, h, e, v_from=vel_from, v_to=vel_to, theta_from=th_from, theta_to=th_to)
    workspace_fit = None
    if a.fit_ws:
        from ..studies.workspace import fit_workspace

        _finite("max-shift", a.max_shift)
        workspace_fit = fit_workspace(task, prof, a.method.value, params, adjust_points=a.adjust_points,
                                      max_shift=a.max_shift)
        for line in workspace_fit.changes():
            sys.stderr.write(f"pickplace: {line}\n")
        task = workspace_fit.task
    return task, workspace_fit, vel_from


def _render_legs(a, prof, legs: list, rendezvous, track) -> tuple[int, float]:
    """Summary, limit table and verdict of every leg (and of the tracking segment) on stderr; (exit code,
    cycle time [s])."""
    quiet, round_trip = a.quiet, a.round_trip
    names = ("pick from the belt", "place at the start") if rendezvous is not None else ("there", "back")
    for i, leg in enumerate(legs):
        if not quiet:
            if round_trip:
                sys.stderr.write(f"--- move {i + 1} ({names[i]}) ---\n")
            _print_summary(leg)
            if rendezvous is not None and i == 0:
                _print_rendezvous(rendezvous)
            _print_limit_table(leg.report)
        _print_verdict(leg.report, quiet, with_cycle=not round_trip)
        if track is not None and i == 0:  # the tracking segment after the rendezvous: checked like a move
            if not quiet:
                sys.stderr.write(f"--- tracking the part: t = {rendezvous.seconds:.4f} … "
                                 f"{rendezvous.seconds + track.duration.seconds:.4f} s at the belt velocity ---\n")
                _print_limit_table(track.report)
            _print_verdict(track.report, quiet, with_cycle=False)
    code = max(leg.report.exit_code() for leg in legs + ([track] if track is not None else []))
    dwell = legs[0].report.dwell  # the profile's (on a controller's cycle: rounded up to whole cycles)
    cycle = sum(leg.report.duration for leg in legs) + len(legs) * dwell if round_trip else legs[0].report.round_trip
    if round_trip and not quiet:
        dwells = f"{dwell:g} s track + {dwell:g} s dwell" if rendezvous is not None else f"2 × {dwell:g} s dwell"
        sys.stderr.write(
            f"round trip: {legs[0].report.duration:.4f} s + {legs[1].report.duration:.4f} s + {dwells} "
            f"= {cycle:.4f} s, {60.0 / cycle:.1f} picks/min; {'all limits hold' if code == 0 else 'LIMITS EXCEEDED'}\n"
        )
    from .controller import print_cycle_line

    print_cycle_line(legs, round_trip, quiet)
    return code, cycle


def _write_plan_outputs(a, prof, writer, legs: list, track, code: int) -> int:
    """The table's verdict (a table format), --report, then the trajectory or table (before the JSON summary: a
    failed write is then the one JSON document on stdout): the move, the round trip, or the move with its tracking
    segment; not written when a limit is exceeded — by the trajectory, or by the table as the drive interpolates
    it — unless --write-anyway. → the exit code with the table's verdict."""
    from .controller import judge_table, table_format, table_info, write_table

    judged = None
    if table_format(a.fmt) and a.output is not None and (code == 0 or (a.write_anyway and code == 3)):
        judged, table_code = judge_table(a, prof, legs, track, _written_times(a, prof, legs, track))
        code = max(code, table_code)
        a.table_info = table_info(a, judged)
    if a.report is not None:
        _write_report(legs + ([track] if track is not None else []), a.report,
                      extra=None if judged is None else {"table": a.table_info})
    if a.output is None or not (code == 0 or (a.write_anyway and code == 3)):
        from ..export import unpromise

        unpromise(a.output)  # not written on purpose: a broken stdout later must not call it lost
        return code
    from ..pipelines.timeline import on_cycle

    if judged is not None:  # a table the controller interpolates itself
        a.table_info = write_table(a, legs, judged)
        return code
    if a.belt_cycle is not None:
        samples = a.belt_cycle.timeline(numbered=True)
    elif a.round_trip:
        from ..pipelines.timeline import round_trip as make_round_trip

        rate_hz = a.rate if a.rate is not None else prof.planning.rate
        if a.cycle_s is not None:
            rate_hz = 1.0 / a.cycle_s
        samples = on_cycle(make_round_trip(legs[0], legs[1], legs[0].report.dwell, rate_hz), a.cycle_s)
    elif track is not None:
        from ..pipelines.tracking import with_tracking

        samples = on_cycle(with_tracking(legs[0], track), a.cycle_s)
    else:
        samples = legs[0]
    writer(samples, a.output)
    return code


def _written_times(a, prof, legs: list, track):
    """The time stamps [s] of the samples the plan writes (the round trip with its dwells, the move and its tracking)."""
    from ..pipelines.timeline import on_cycle

    if a.belt_cycle is not None:
        return a.belt_cycle.timeline(numbered=True).t
    if a.round_trip:
        from ..pipelines.timeline import round_trip as make_round_trip

        rate_hz = 1.0 / a.cycle_s if a.cycle_s is not None else (a.rate if a.rate is not None else prof.planning.rate)
        return on_cycle(make_round_trip(legs[0], legs[1], legs[0].report.dwell, rate_hz), a.cycle_s).t
    if track is not None:
        from ..pipelines.tracking import with_tracking

        return on_cycle(with_tracking(legs[0], track), a.cycle_s).t
    return legs[0].t


def _plan_json(legs: list, cycle: float, code: int, forgiven: bool, workspace_fit, rendezvous, track) -> dict:
    """The --json summary of a one-move plan (a round trip, a rendezvous with its tracking segment)."""
    doc = _json_summary(legs, cycle, code, exit_code=0 if forgiven else code)
    if workspace_fit is not None:
        doc["workspace_fit"] = workspace_fit.as_dict()
    if rendezvous is not None:
        doc["rendezvous"] = rendezvous.as_dict()
        if track is not None:
            doc["tracking"] = {"t_start_s": rendezvous.seconds, "duration_s": track.duration.seconds,
                               "limits_ok": track.report.ok,
                               "violations": [r.as_dict() for r in track.report.violations]}
    return doc


def _belt_method(ctx, method, to_belt, latency, v_to, batch, round_trip, fit_ws, optimize):
    """--to-belt/--latency: the method that supports a moving end (bspline-vel) unless another is named; the
    options that cannot apply to a rendezvous are refused (exit 2)."""
    if to_belt is None:
        _usage("--latency only applies with --to-belt (the part's detection time)")
    for given, what in ((v_to is not None, "--v-to (the belt velocity is the arrival velocity)"),
                        (batch is not None, "--batch"), (fit_ws, "--fit-workspace"),
                        (optimize != OptimizeWhat.none, "--optimize")):
        if given:
            _usage(f"--to-belt: not available with {what}")
    if method == MethodName.bspline_vel:
        return method
    source = ctx.get_parameter_source("method")
    if source is None or source.name == "DEFAULT":
        return MethodName.bspline_vel
    from ..model.errors import TaskError

    raise TaskError(f"to-belt: method {method.value} plans moves from rest to rest; a moving end needs "
                    "--method bspline-vel (the default with --to-belt)")


def _moving_ends_method(ctx, method, v_from, v_to):
    """--from-belt/--v-from, --v-to with a velocity other than zero: the method that supports moving ends
    (bspline-vel), as --to-belt chooses it, unless -m names one (a rest-to-rest method is then refused)."""
    source = ctx.get_parameter_source("method")
    if source is not None and source.name != "DEFAULT":
        return method
    moving = any(any(_parse_point(name, text, "m/s")) for name, text in (("v-from", v_from), ("v-to", v_to))
                 if text is not None)
    return MethodName.bspline_vel if moving else method


def _plan_to_belt(task, to_belt, latency, prof, time, v_from, params, rate, options, round_trip: bool = False):
    """The rendezvous move and its tracking segment (the profile's dwell; None when 0): ([plan], Rendezvous, track,
    None); with ``round_trip`` the whole belt cycle (pick, track, place back at the start, dwell):
    ([pick, place], Rendezvous, track, Cycle). The part lies on the belt at the tool angle ``task.theta_to`` (rad;
    None: no angle), the move starts (and the round trip ends) at ``task.theta_from``."""
    from ..pipelines.rendezvous import Part, plan_rendezvous

    part = Part(task.p_to, _parse_point("to-belt", to_belt, "m/s"), 0.0 if latency is None else latency,
                angle=task.theta_to)
    if round_trip:
        from ..pipelines.schedule import plan_belt_cycle

        cyc = plan_belt_cycle(task.p_from, part, task.p_from, prof, time, task.height, task.eta, rate, params,
                              task.theta_from, task.theta_from, options.turn, TurnName.as_given.value,
                              options.turn_during, options.cycle)
        return [cyc.move, cyc.place], cyc.rendezvous, cyc.track, cyc
    from ..pipelines.tracking import plan_tracking

    plan, rv = plan_rendezvous(task.p_from, part, prof, time, task.height, task.eta, v_from, params, rate,
                               start_angle=task.theta_from, turn=options.turn, turn_during=options.turn_during,
                               cycle=options.cycle)
    track = plan_tracking(plan, part, prof, rate=rate, cycle=options.cycle) if prof.planning.dwell > 0 else None
    return [plan], rv, track, None


def _run_plan(task, prof, options):
    from ..planner import plan as run_plan

    return run_plan(task, prof, options)
