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


def write_table(a, prof, legs: list, track, grid) -> dict:
    """``--format pvt|cam|cam-table[-st]``: fit the table to the continuous trajectory that would be written (points
    from ``grid``, the written samples' times [s]), write it atomically to ``a.output`` as CSV or Structured Text, say
    how many points it has and how close it is; → what the --json summary reports of it."""
    from ..export import atomic_output
    from ..export.tables import Master, format_table_csv, format_table_st, table_columns, table_header
    from ..pipelines.controller import table_of, timeline_of

    kind, st = TABLE_FORMATS[a.fmt.value]
    motion = timeline_of(legs, prof, legs[0].report.dwell, a.round_trip, track)
    tolerance = DEFAULT_TOLERANCE if a.tolerance is None else a.tolerance
    table = table_of(kind, grid, motion, tolerance)
    master = Master()
    if a.cam_master.value == "belt":
        part = a.rendezvous.part
        master = Master("belt", part.speed, part.latency)
    if a.pvt_integer:
        text = _integer_text(a, table, legs, master, st)
    else:
        cols = table_columns(table, a.drive, legs[0].joint.units, master)
        text = (format_table_st(table, cols, a.st_dialect.value, table_header(table, a.drive, master)) if st
                else format_table_csv(cols))
    with atomic_output(a.output) as stream:
        stream.write(text)
    info = {"format": a.fmt.value, **table.as_dict(), "master": master.kind}
    if not a.quiet:
        err = max(table.max_error)
        sys.stderr.write(f"{a.fmt.value} table: {len(table.t)} points for {table.samples} samples "
                         f"({table.samples / len(table.t):.1f} x fewer); max deviation {err:.3g} (rad or m) within "
                         f"--tolerance {table.tolerance:g}\n")
    return info


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
