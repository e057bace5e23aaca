"""`plan`'s controller outputs: the cycle (``--cycle``), the drive view of the profile, and the compact tables a motion
kernel runs (``--format pvt|cam|cam-table`` and their ``-st`` forms) — parse, call the library, write."""

from __future__ import annotations

import sys

from .app import OutputFormat, _usage

#: the formats that are tables a controller interpolates (not samples)
TABLE_FORMATS = {"pvt": ("pvt", False), "pvt-st": ("pvt", True), "cam": ("cam", False), "cam-st": ("cam", True),
                 "cam-table": ("cam-table", False), "cam-table-st": ("cam-table", True)}


def resolve_cycle(given: str | None, rate: float | None, prof) -> float | None:
    """The controller cycle [s]: ``--cycle`` (seconds, or ``off``), else the profile's ``controller.cycle``, else None.
    A cycle ≤ 0 or not finite is exit 1; ``--rate`` with a cycle in force is a usage error (one sample per cycle)."""
    from ..timing.cycle import check_cycle

    ctl = getattr(prof, "controller", None)
    if given is not None and given.strip().lower() == "off":
        return None
    if given is not None:
        from ..model.text import plain_float

        try:
            value = plain_float(given)
        except ValueError:
            value = given
        cycle = check_cycle(value, "cycle")
        source = "--cycle"
    elif ctl is not None and ctl.cycle is not None:
        cycle, source = check_cycle(ctl.cycle, "controller.cycle"), f"the profile's controller.cycle ({ctl.cycle:g} s)"
    else:
        return None
    if rate is not None:
        _usage(f"--rate: with {source} every sample is one cycle; drop --rate, or give --cycle off to sample at "
               f"{rate:g} Hz")
    return cycle


def rounded_dwell(prof, cycle: float | None) -> float:
    """The profile's dwell [s], rounded up to whole cycles when a cycle is in force."""
    dwell = prof.planning.dwell
    if cycle is None:
        return dwell
    from ..timing.cycle import whole_cycles

    return whole_cycles(dwell, cycle) * cycle


def cycle_cost(legs, round_trip: bool) -> float | None:
    """What rounding to the cycle added to the duty cycle [s]: every move's extra time and every dwell's (two dwells
    per cycle: a round trip's two legs, or one move there and back); None without a cycle."""
    rounding = [leg.cycle for leg in legs if getattr(leg, "cycle", None) is not None]
    if not rounding:
        return None
    if round_trip:
        return sum(r.cost_s for r in rounding) + 2 * rounding[0].dwell_cost_s
    return 2 * (rounding[0].cost_s + rounding[0].dwell_cost_s)


def print_cycle_line(legs, round_trip: bool, quiet: bool) -> None:
    """The rounding's cost on the duty cycle, one line on stderr (nothing without a cycle, or with --quiet)."""
    cost = cycle_cost(legs, round_trip)
    if cost is None or quiet:
        return
    c = legs[0].cycle.cycle
    what = "round trip" if round_trip else "duty cycle (move, dwell, back, dwell)"
    sys.stderr.write(f"controller cycle {c * 1e3:g} ms: every step is one cycle; rounding adds {cost * 1e3:.4g} ms to "
                     f"the {what}\n")


def check_cycle_usage(a, cycle: float | None, fmt) -> None:
    """Usage (exit 2) of the table formats and their options."""
    table = fmt.value in TABLE_FORMATS
    if a.tolerance is not None and not table:
        _usage(f"--tolerance applies to the table formats (pvt, cam, cam-table and their -st forms), not {fmt.value}")
    if a.st_dialect.value != "strict" and not fmt.value.endswith("-st"):
        _usage(f"--st-dialect applies to the Structured Text formats (pvt-st, cam-st, cam-table-st), not {fmt.value}")
    if a.cam_master.value != "time" and not fmt.value.startswith("cam"):
        _usage(f"--cam-master applies to the cam formats, not {fmt.value}")
    if a.cam_master.value == "belt" and a.to_belt is None:
        _usage("--cam-master belt: the master is the belt's travel, which needs a conveyor move (--to-belt)")
    if a.table_end.value != "hold" and not table:
        _usage(f"--table-end applies to the table formats (pvt, cam, cam-table and their -st forms), not {fmt.value}")
    if a.cam_object.value != "none" and fmt.value not in ("cam-st", "cam-table-st"):
        _usage(f"--cam-object applies to the cam Structured Text formats (cam-st, cam-table-st), not {fmt.value}")
    if a.cam_object.value != "none" and a.st_dialect.value != "strict":
        _usage("--cam-object writes its own PROGRAM with the controller's cam types; drop --st-dialect")
    if a.plcopen_xml and not fmt.value.endswith("-st"):
        _usage(f"--plcopen-xml applies to the Structured Text formats (pvt-st, cam-st, cam-table-st), not {fmt.value}")
    if a.pvt_integer and fmt.value not in ("pvt", "pvt-st"):
        _usage(f"--pvt-integer applies to the PVT formats (pvt, pvt-st), not {fmt.value}")
    if table and a.batch is not None:
        _usage(f"--format {fmt.value}: one table per move; plan the rows one at a time (not with --batch)")
    if table and a.json_summary and a.output is None:
        _usage(f"--format {fmt.value}: with --json and no -o FILE no table is written (stdout carries the summary)")


def table_format(fmt: OutputFormat) -> bool:
    return fmt.value in TABLE_FORMATS


#: the tolerance of a table when none is given [rad or m]
DEFAULT_TOLERANCE = 1e-6


#: a table row is shown beside the trajectory's when it uses at least this fraction of its limit (or fails, or is the
#: table's limiting row, or a per-cycle step)
SHOWN_USE = 0.9


def judge_table(a, prof, legs: list, track, grid):
    """``--format pvt|cam|cam-table[-st]``: the table fitted to the continuous trajectory that would be written
    (points from ``grid``, the written samples' times [s]) and made to hold every limit as the drive rebuilds it
    (:func:`~pickplace_cli.pipelines.controller.judged_table`: more points, or — not for a conveyor move — a slower
    table); its verdict on stderr. → (JudgedTable, exit code of the table: 0, or 3 when it cannot be made to hold)."""
    from ..pipelines.controller import judged_table, timeline_of

    kind, _ = TABLE_FORMATS[a.fmt.value]
    dwell = legs[0].report.dwell
    motion = timeline_of(legs, prof, dwell, a.round_trip, track)
    tolerance = DEFAULT_TOLERANCE if a.tolerance is None else a.tolerance
    # the table holds the Cartesian capacity where the rule of the move holds it (not under --time fit or optimal)
    capacity = any(r.quantity.startswith("capacity") and r.held for leg in legs for r in leg.report.rows)
    retime = track is None and a.cam_master.value == "time"
    sized = None
    if a.cam_object.value != "none":
        from functools import partial

        from ..export.cam_objects import table_size

        sized = partial(table_size, a.cam_object.value, kind)
    written = None
    if a.pvt_integer:  # judge the integers the drive receives, not the table before rounding
        from functools import partial

        from ..export.pvt_int import as_written

        written = partial(as_written, drive=a.drive, joint_units=legs[0].joint.units)
    ends = a.table_end.value
    judged = judged_table(kind, grid, motion, tolerance, prof, 0.0 if a.round_trip else dwell, a.cycle_s,
                          retime=retime, capacity=capacity, size=sized, written=written, ends=ends)
    if written is not None:  # the deviation of the integers as written: the table's own plus what rounding adds
        import numpy as np

        judged = _rounded_deviation(judged, written)
        if max(judged.table.max_error) > tolerance:  # fit closer by the rounding's share, so the integers hold it
            rounding = float(np.max(judged.table.max_error - judged.fit_error))
            if rounding < tolerance:
                judged = _rounded_deviation(judged_table(
                    kind, grid, motion, tolerance - rounding, prof, 0.0 if a.round_trip else dwell, a.cycle_s,
                    retime=retime, capacity=capacity, size=sized, written=written, ends=ends), written, tolerance)
    code = judged.report.exit_code()
    _print_table_verdict(a, judged, legs + ([track] if track is not None else []), motion.duration, retime, prof)
    return judged, code


def _rounded_deviation(judged, written, tolerance: float | None = None):
    """``judged`` with its table's ``max_error`` [rad or m per joint] that of the integers as the drive receives them
    (``written``: the table rounded to counts, back in model units): the table's deviation from the trajectory plus the
    largest difference between the drive's cubic through the rounded points and through the exact ones (each piece
    sampled at 64 points: a cubic's difference, so the sampled maximum is within 0.1 % of the true one) — an upper
    bound by the triangle inequality. ``tolerance``: the user's (the table was fitted to a smaller one)."""
    from dataclasses import replace

    import numpy as np

    from ..export.interpolate import rebuild

    table = judged.table
    exact, rounded = rebuild(table), rebuild(written(table))
    breaks = np.union1d(exact.breaks, rounded.breaks)
    u = np.linspace(0.0, 1.0, 64, endpoint=False)
    at = np.append((breaks[:-1, None] + np.diff(breaks)[:, None] * u).ravel(), breaks[-1])
    rounding = np.max(np.abs(rounded(at) - exact(at)), axis=0)
    tol = table.tolerance if tolerance is None else float(tolerance)
    fit = np.asarray(table.max_error, float)
    return replace(judged, table=replace(table, max_error=fit + rounding, tolerance=tol), fit_error=fit)


def _print_table_verdict(a, judged, plans: list, planned: float, retime: bool, prof=None) -> None:
    """The table's points, its limiting rows beside the trajectory's, the re-timing and the verdict (stderr; the
    verdict also with --quiet when the table fails), and, for a table whose steps are judged on a cycle, the
    ``check --cycle`` that reads it on the same cycle when ``check``'s default would be another."""
    from ..limits.report import percent

    table, report = judged.table, judged.report
    name = a.fmt.value
    failed = not report.ok
    if not a.quiet:
        sys.stderr.write(_points_line(a, judged))
        traj = {}
        for p in plans:
            for r in p.report.rows:
                key = (r.joint, r.quantity)
                if key not in traj or r.utilisation > traj[key].utilisation:
                    traj[key] = r
        timed = [r for r in report.rows if r.kind == "limit"]
        limiting = max(timed, key=lambda r: r.utilisation / r.target) if timed else None
        for r in timed:
            step = r.quantity.endswith("step")
            if r.ok and not step and r is not limiting and r.utilisation < SHOWN_USE * r.target:
                continue
            mine = traj.get((r.joint, r.quantity))
            beside = f"; trajectory {percent(mine.utilisation)} %" if mine is not None else ""
            if step:
                beside = f" (bound: one cycle of {judged.step * 1e3:g} ms at the {'torque rate' if 'torque' in r.quantity else 'jerk'} limit)"
            sys.stderr.write(f"  table {r.joint} {r.quantity}: {r.peak:.4g} {r.unit}, {percent(r.utilisation)} % of "
                             f"{r.limit:.4g}{beside}{'' if r.ok else '  EXCEEDED'}\n")
        if judged.stretch != 1.0 and not failed:
            cycles = ", on whole cycles" if a.cycle_s is not None else ""
            cycle = duty_cycle(a, judged)
            sys.stderr.write(f"  re-timed: the table runs {judged.duration:.6g} s where the trajectory runs "
                             f"{planned:.6g} s (every move x{judged.stretch:.6g}{cycles}) so that every limit holds as "
                             f"the drive interpolates it; the table's cycle {cycle:.4f} s, {60.0 / cycle:.1f} picks/min "
                             "(the verdict's cycle is the trajectory's)\n")
    how = {"pvt": "cubic Hermite", "cam": "5th-order segments",
           "cam-table": "linear, each step over one cycle"}[table.kind]
    if failed:
        worst = max(report.violations, key=lambda r: r.utilisation)
        moving = moving_ends(table) if a.table_end.value == "hold" else []
        why = (f"the table {'starts' if moving == ['first'] else 'ends' if moving == ['last'] else 'starts and ends'} "
               f"moving: {moving_cause(moving)}" if moving else
               f"more points{' and a slower table' if retime else ' (a conveyor move is not re-timed)'} did not make "
               "it hold; plan a longer --time or a lower --limit-use")
        sys.stderr.write(f"table verdict: LIMITS EXCEEDED as the drive interpolates the table ({how}): {worst.joint} "
                         f"{worst.quantity} {percent(worst.utilisation)} % of {worst.limit:.4g} {worst.unit}; {why}\n")
    elif not a.quiet:
        sys.stderr.write(f"table verdict: all limits hold as the drive interpolates the table ({how})\n")
    moving = moving_ends(table)
    if moving and a.table_end.value == "continue":  # (said under --quiet too: check needs the option)
        which = " and ".join(f"{'starts' if e == 'first' else 'ends'}" for e in moving)
        where = " and ".join(f"{'before' if e == 'first' else 'after'}" for e in moving)
        sys.stderr.write(f"pickplace: warning: the table {which} moving, judged as the controller going on at its "
                         f"{'start' if moving == ['first'] else 'end' if moving == ['last'] else 'end'} velocity "
                         f"(--table-end continue): what it does {where} the table is not checked; check the file with "
                         "pickplace check FILE --table-end continue\n")
    if (table.kind != "cam" or (moving and a.table_end.value == "hold")) and prof is not None and not failed:
        from ..pipelines.check import table_cycle

        default = table_cycle(prof, None, table)
        if abs(default - judged.step) > 1e-9 * judged.step:  # (check's default: the profile's cycle or rate)
            # said under --quiet too (as a warning): check's default cycle would judge the written file on another
            lead = "pickplace: warning: the table's" if a.quiet else "  its"
            sys.stderr.write(f"{lead} steps are judged on a cycle "
                             f"of {judged.step:.9g} s, and check's default here is {default:.9g} s: check it on the "
                             f"same cycle with pickplace check FILE --cycle {judged.step:.9g}\n")


def _points_line(a, judged) -> str:
    """The table's first summary line: its points against the samples (the cycle grid with a cycle), the tolerance's
    own count, an equidistant table's master step in cycles, and the achieved deviation."""
    table = judged.table
    n, samples = len(table.t), table.samples
    grid = "the cycle grid" if a.cycle_s is not None else "the samples"
    if samples == n:
        ratio = f"as many points as {grid}"
    else:
        ratio = (f"{samples / n:.1f} x fewer points than {grid}" if samples > n
                 else f"{n / samples:.2f} x more points than {grid}")
    step = ""
    if judged.step_cycles is not None:
        k = judged.step_cycles
        step = f"; master step {k} cycle{'s' if k > 1 else ''} ({k * judged.step * 1e3:.6g} ms)"
    err = max(table.max_error)
    written = " of the integers as written (rounding included)" if a.pvt_integer else ""
    if err <= table.tolerance:
        dev = f"max deviation{written} {err:.3g} (rad or m) within --tolerance {table.tolerance:g}"
    elif judged.fit_error is not None:  # --pvt-integer: whole counts alone move the drive's cubic by that much
        rounding = max(e - f for e, f in zip(table.max_error, judged.fit_error))
        dev = (f"max deviation{written} {err:.3g} (rad or m), over --tolerance {table.tolerance:g}: rounding to whole "
               f"counts alone moves the drive's cubic by up to {rounding:.3g}; give a larger --tolerance")
    else:  # one point a cycle and the tolerance needs a finer step: the drive's cycle, not the table, sets it
        dev = (f"max deviation between the points {err:.3g} (rad or m), over --tolerance {table.tolerance:g}: it needs a "
               "step finer than the cycle the drive reads the table at, and between two cycles the drive runs a "
               "straight line whatever the table's step")
    return (f"{a.fmt.value} table: {n} points for {samples} samples ({ratio}; the tolerance alone needed "
            f"{judged.tolerance_points}{step}); {dev}\n")


def moving_ends(table) -> list[str]:
    """Which ends of ``table`` move ("first", "last"): a PVT's or cam's velocity there not zero, a cam-table's first or
    last line's slope above 10 % of that joint's largest, as ``check`` warns of a file that starts or ends moving (a table from
    and to rest has a slope of O(h²) there: a few % on a long cycle)."""
    from ..export.interpolate import moving_ends as ends

    import numpy as np

    first, last = ends(table.t, table.q, table.qd if table.kind != "cam-table" else None)
    if table.kind == "cam-table":
        v = np.abs(np.diff(table.q, axis=0) / np.diff(table.t)[:, None])
        top = v.max(axis=0) if v.size else 0.0  # per joint, as check's warning
        from ..pipelines.check import MOVING_END

        first, last = (np.where(np.abs(x) > MOVING_END * top, x, 0.0) for x in (first, last))
    return [name for name, v in (("first", first), ("last", last)) if np.any(v)]


#: why a table that starts or ends moving breaks a limit, whatever its duration
MOVING_TABLE = ("the drive holds the table's {which} point {when} it, a velocity step {way} rest within one controller "
                "cycle that no duration removes ({why}): {fix}where the controller {goes} at the table's {end} "
                "velocity (e.g. geared to the belt), say so with --table-end continue")


def moving_cause(ends: list[str]) -> str:
    """:data:`MOVING_TABLE` for the ``ends`` that move (:func:`moving_ends`: "first", "last" or both)."""
    first, last = "first" in ends, "last" in ends
    both = first and last
    return MOVING_TABLE.format(
        which="first and last" if both else ends[0], when="before and after" if both else "before" if first else "after",
        way="from and to" if both else "from" if first else "to",
        why=("a move from the belt starts at the belt's speed" if first else "") + (", and " if both else "")
        + ("a conveyor move ends at the belt's speed" if last else ""),
        fix="plan the whole belt cycle (--to-belt … --round-trip), or, " if last and not first else "",
        goes="comes in and goes on" if both else "comes in" if first else "goes on",
        end="start and end" if both else "start" if first else "end")


def duty_cycle(a, judged) -> float:
    """The duty cycle [s] of the table as written: the table itself for a round trip (its dwells inside), else
    move, dwell, the move back as long, dwell."""
    return judged.duration if a.round_trip else 2.0 * (judged.duration + judged.report.dwell)


def table_info(a, judged) -> dict:
    """What the --json summary and --report say of the table: points, tolerance, errors, re-timing and verdict."""
    t = judged.table
    return {"format": a.fmt.value, **t.as_dict(), "master": a.cam_master.value, "cam_object": a.cam_object.value,
            "moving_ends": moving_ends(t), "table_end": a.table_end.value,
            "tolerance_points": judged.tolerance_points, "duration_s": judged.duration, "stretch": judged.stretch,
            "cycle_s": duty_cycle(a, judged), "picks_per_minute": 60.0 / duty_cycle(a, judged),
            "step_cycle_s": judged.step, "master_step_cycles": judged.step_cycles, "limits_ok": judged.report.ok,
            "violations": [r.as_dict() for r in judged.report.violations],
            "rows": [r.as_dict() for r in judged.report.rows]}


def write_table(a, legs: list, judged) -> dict:
    """Write the judged table atomically to ``a.output`` as CSV or Structured Text; → :func:`table_info`."""
    from ..export import atomic_output
    from ..export.tables import Master, format_table_csv, format_table_st, table_columns, table_header

    _, st = TABLE_FORMATS[a.fmt.value]
    table = judged.table
    master = Master()
    if a.cam_master.value == "belt":
        part = a.rendezvous.part
        master = Master("belt", part.speed, part.latency)
    if a.pvt_integer:
        text = _integer_text(a, table, legs, master, st)
    elif a.cam_object.value != "none":
        from ..export.cam_objects import format_cam_objects_st

        cols = table_columns(table, a.drive, legs[0].joint.units, master)
        text = format_cam_objects_st(table.kind, cols, a.cam_object.value, master.unit,
                                     table_header(table, a.drive, master))
    else:
        cols = table_columns(table, a.drive, legs[0].joint.units, master)
        text = (format_table_st(table, cols, a.st_dialect.value, table_header(table, a.drive, master)) if st
                else format_table_csv(cols))
    if a.plcopen_xml:
        from ..export.plcopen import st_to_plcopen

        text = st_to_plcopen(text)
    with atomic_output(a.output) as stream:
        stream.write(text)
    return table_info(a, judged)


def _integer_text(a, table, legs: list, master, st: bool) -> str:
    """``--pvt-integer``: the PVT table in the drive's integer units (ms, counts, counts/s) as CSV or ST."""
    from ..export.pvt_int import format_integer_csv, format_integer_st, integer_pvt
    from ..export.tables import table_header

    pvt = integer_pvt(table, a.drive, legs[0].joint.units)
    if pvt.split and not a.quiet:
        sys.stderr.write(f"pvt integer: {pvt.split} segment(s) longer than 255 ms split in whole ms on their own cubic\n")
    if not st:
        return format_integer_csv(pvt)
    header = table_header(table, a.drive, master) + [f"integer units: {len(pvt.t_ms)} points (segments of 1-255 ms)"]
    return format_integer_st(pvt, a.st_dialect.value, header)
