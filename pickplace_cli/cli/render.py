"""Rendering for people and scripts: summaries, limit tables and verdicts on stderr, JSON lines on stdout, reports and trajectory writers."""

from __future__ import annotations

import sys
from typing import Callable, Optional

from .app import Compression, CsvDialectName, OutputFormat


def console(**kwargs):
    """A rich Console for the commands' output: no ANSI styling at all (colour nor bold) when the environment sets
    ``NO_COLOR`` to a non-empty value (no-color.org) or ``TERM=dumb``; rich alone drops only the colours."""
    import os

    from rich.console import Console

    if os.environ.get("NO_COLOR") or os.environ.get("TERM") == "dumb":
        kwargs.setdefault("color_system", None)
    return Console(**kwargs)


def _print_rendezvous(rv) -> None:
    xyz = ", ".join(f"{c:.4f}" for c in rv.meeting_point)
    wait = "; waits for the window (meets the part where it enters)" if rv.waited else ""
    sys.stderr.write(
        f"rendezvous: meets the part at ({xyz}) m at t = {rv.seconds:.4f} s ({rv.meeting_time_since_detection:.4f} s "
        f"after its detection), arriving with the belt velocity {rv.part.speed:.4g} m/s; allowed meeting "
        f"t = {rv.window_s[0]:.4f} … {rv.window_s[1]:.4f} s{wait}\n"
    )


def _writer(fmt, dialect, flavor, compression, columns: tuple[str, ...] | None = None, drive=None,
            bag: bool = False) -> Callable:
    """A function (samples, output path) that writes atomically in the chosen format; ``columns``: the CSV
    columns to write (:class:`~pickplace_cli.export.csv.CsvFormat`), None for all; ``drive``: the profile's
    :class:`~pickplace_cli.export.drive.DriveMap` (names, drive units), None without one; ``bag``: MCAP as a rosbag2
    directory (:mod:`~pickplace_cli.export.rosbag2`)."""
    from ..model.errors import ExportError

    if fmt != OutputFormat.mcap and compression != Compression.none:
        raise ExportError(f"compression = {compression.value}: only MCAP output is compressed (--format mcap)")
    if fmt != OutputFormat.csv and dialect != CsvDialectName.default:
        raise ExportError(f"csv-dialect = {dialect.value}: only applies to --format csv")

    csv_format = None
    if fmt == OutputFormat.csv:
        from ..export.csv import CsvFormat

        csv_format = CsvFormat(dialect.value, columns, drive)

    def write(samples, output: str) -> None:
        from ..export import atomic_output

        if fmt == OutputFormat.csv:
            from ..export.csv import write_csv

            with atomic_output(output) as stream:
                write_csv(samples, stream, dialect=csv_format)
        elif fmt == OutputFormat.json:
            from ..export.json import write_json

            with atomic_output(output) as stream:
                write_json(samples, stream, drive=drive)
        elif bag:
            from ..export.rosbag2 import write_rosbag2

            write_rosbag2(samples, output, compression=None if compression == Compression.none else compression.value,
                          drive=drive)
        else:
            from ..export.mcap import write_mcap

            with atomic_output(output, binary=True) as stream:
                write_mcap(samples, stream, flavor=flavor.value,
                           compression=None if compression == Compression.none else compression.value, drive=drive)

    write.one_timeline = fmt == OutputFormat.mcap  # type: ignore[attr-defined]
    write.csv_dialect = csv_format  # type: ignore[attr-defined]
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
    """One JSON document as a line on stdout, flushed; a failing stdout (``> /dev/full``) is an ExportError."""
    import json

    from ..export import _CheckedStdout

    out = _CheckedStdout(sys.stdout)
    out.write(json.dumps(doc, allow_nan=False, default=float) + "\n")
    out.flush()


def _emit_row_json(res) -> None:
    """A batch row's JSON line: row, exit code, error, and the plan's summary and violations when it has one."""
    doc: dict = {"row": res.row, "exit_code": res.code, "error": res.error}
    if res.plan is not None:
        doc.update(res.plan.summary())
        doc["violations"] = [v.as_dict() for v in res.plan.report.violations]
    _emit_json(doc)


def _row_not_held(res) -> None:
    """A batch row's limits exceeded that its rule does not hold (the Cartesian capacity under --time fit or
    optimal), one line each on stderr in a single plan's words; the row itself is within its rule (exit 0)."""
    rep = getattr(res.plan, "report", None)
    loose = () if rep is None else rep.exceeded_not_held
    if loose:
        sys.stderr.write("".join(f"pickplace: row {res.row}: {_violation_text(r)}\n" for r in loose))


def _cycle_not_held(res) -> None:
    """A belt schedule row's segments' limits exceeded that the rule does not hold, one line each on stderr."""
    c = res.cycle
    if c is None:
        return
    names = ("pick", "track", "place") if c.track is not None else ("pick", "place")
    sys.stderr.write("".join(f"pickplace: row {res.row}: {name}: {_violation_text(r)}\n"
                             for name, leg in zip(names, c.legs) for r in leg.report.exceeded_not_held))


class SlowedRows:
    """The batch rows whose time law was slowed so that ``check`` reads their written samples within every limit
    (``--time optimal``/``fit``: ``Duration.written_stretch`` > 1), for the closing line: how many, and the largest
    stretch with its row."""

    def __init__(self) -> None:
        self.count, self.worst, self.row = 0, 1.0, None

    def add(self, res) -> None:
        plan = res.plan
        if plan is None:
            return
        duration = getattr(plan, "duration", None)
        k = duration.written_stretch if duration is not None else plan.summary().get("written_stretch", 1.0)
        if k is not None and k > 1.0:
            self.count += 1
            if k > self.worst:
                self.worst, self.row = k, res.row

    def text(self) -> str:
        if not self.count:
            return ""
        return (f"; {self.count} slowed so that check reads their written samples within every limit (up to "
                f"× {self.worst:.5g}, row {self.row}; each row's written_stretch is in --json)")


def _batch_line(codes: list, first_failed, written, slowed: SlowedRows | None = None) -> None:
    """The batch's closing line on stderr (``written``: rows written to -o, None without -o; ``slowed``: the rows
    whose law was slowed for their written samples)."""
    n_ok = sum(1 for c in codes if c == 0)
    sys.stderr.write(
        f"batch: {len(codes)} rows, {n_ok} ok, {len(codes) - n_ok} failed"
        + (f" (first failing row {first_failed})" if first_failed is not None else "")
        + (f"; {written} written" if written is not None else "")
        + (slowed.text() if slowed is not None else "") + "\n"
    )


def _check_output_paths(output: Optional[str], report: Optional[str], bag: bool = False) -> None:
    """Refuse colliding or impossible outputs before anything is computed or written (``output`` None: no
    trajectory is written, as with ``--json`` alone; ``bag``: a rosbag2 directory)."""
    import os

    from ..model.errors import ExportError
    from ..export import check_writable, promise

    if bag:
        from ..export.rosbag2 import check_bag_directory

        check_bag_directory(output)
    else:
        check_writable(output)
    promise(output)
    if report is not None:
        check_writable(report)
        promise(report)
        if report == "-" and output == "-":
            raise ExportError("report = -: stdout already carries the trajectory; give --report a file or -o a file")
        if output is not None and report != "-" and output != "-" and os.path.abspath(report) == os.path.abspath(output):
            raise ExportError(f"report = {report}: the same file as --output; give them different paths")


def _write_report(results, path: str, rows: Optional[list] = None, extra: Optional[dict] = None) -> None:
    """--report: summary and limit rows of one plan, or of every move (a round trip, a batch); ``extra``: more keys
    of the document (a table's verdict)."""
    import json

    from ..export import atomic_output

    results = list(results) if isinstance(results, (list, tuple)) else [results]
    docs = [{"summary": r.summary(), "limits": r.report.as_dict()} for r in results]
    if rows is not None:
        for d, n in zip(docs, rows):
            d["row"] = n
    doc = docs[0] if len(docs) == 1 and rows is None else {"moves": docs}
    if extra:
        doc = {**doc, **extra}
    with atomic_output(path) as stream:
        json.dump(doc, stream, indent=2, allow_nan=False, default=float)
        stream.write("\n")


def _fmt(x: float) -> str:
    return f"{x:.4g}"


#: the columns a narrow terminal leaves out, in turn, until the table fits (the time of the peak, the target of a
#: limit use, the stated accuracy): the verdict column is never dropped or wrapped
NARROW_DROPS = ((), ("t",), ("t", "target"), ("t", "target", "acc"))


def _limit_table(report, narrow: bool = False, drop: tuple = (), wrap: bool = False):
    """The limit rows as a rich Table. ``narrow`` (a terminal narrower than the table, e.g. 80 columns): one space
    between columns, a short time header, "(not held)" without the rule (the lines below the table name it), and
    every column at its full width, so that a quantity and its unit stay on one line and the verdict is never cut;
    ``drop``: columns left out ("t", "target", "acc"); ``wrap``: the quantity may wrap (the last resort)."""
    from rich.markup import escape
    from rich.table import Table
    from rich.text import Text

    from ..limits.report import percent

    table = Table(title=None, box=None, pad_edge=False, show_header=True, header_style="bold", collapse_padding=narrow)
    headroom = any(r.target < 1.0 for r in report.rows) and "target" not in drop  # a limit-use fraction's targets
    cols = [("joint", "left"), ("quantity", "left"), ("peak", "right"), ("limit", "right"), ("use %", "right")]
    cols += [("target %", "right")] if headroom else []
    estimated = any(r.accuracy is not None for r in report.rows) and "acc" not in drop  # peaks from samples (check)
    cols += [("± %", "right")] if estimated else []
    timed = "t" not in drop
    cols += [("t [s]" if narrow else "t peak [s]", "right")] if timed else []
    for col, just in cols + [("", "left")]:
        table.add_column(escape(col), justify=just)  # type: ignore[arg-type]  ("[s]" is not rich markup)
    for r in report.rows:
        mark = "ok" if r.ok else "[bold red]EXCEEDED[/]"
        if r.not_held:  # reported, not judged: the duration rule leaves this limit out (the capacity under fit)
            mark = escape(f"{'ok' if r.ok else 'EXCEEDED'} (not held{'' if narrow else ': ' + r.not_held})")
            mark = mark if r.ok else f"[bold yellow]{mark}[/]"
        quantity = r.quantity
        if quantity.startswith(("position", "workcell")):  # a [min, max] range: say which side the row is
            quantity += " min" if r.bound == "lower" else " max"
        cells = [r.joint, escape(f"{quantity} [{r.unit}]"), _fmt(r.peak),
                 ("≥ " if r.bound == "lower" else "≤ ") + _fmt(r.limit), percent(r.utilisation)]
        cells += [percent(r.target) if r.kind == "limit" else ""] if headroom else []
        if r.ok and r.accuracy is not None and not r.resolved:
            mark = "[yellow]unresolved[/]"
        if estimated:
            cells.append("" if r.accuracy is None else percent(r.accuracy / abs(r.limit)))
        cells += ["" if r.t_peak is None else f"{r.t_peak:.4f}"] if timed else []
        table.add_row(*cells, mark)
    if narrow:
        for i, column in enumerate(table.columns):
            if wrap and i == 1:  # the quantity, as the last resort: its words wrap, a longer one folds (never "…");
                column.overflow = "fold"  # (at least 8 wide: _print_limit_table)
                continue
            column.min_width = max(Text.from_markup(str(c)).cell_len for c in [column.header, *column.cells])
            column.no_wrap = True
    return table


def _print_limit_table(report) -> None:
    table = _limit_table(report)
    # a terminal wraps at its width; a pipe or log file gets whole rows (rich would assume 80 columns), without the
    # padding rich leaves after the last cell
    if sys.stderr.isatty():
        from rich.measure import Measurement

        con = console(stderr=True, highlight=False, soft_wrap=True)

        def width(t) -> int:
            return Measurement.get(con, con.options.update_width(10_000), t).maximum

        if width(table) > con.width:
            for drop in NARROW_DROPS:
                table = _limit_table(report, narrow=True, drop=drop)
                if width(table) <= con.width:
                    break
            else:
                table = _limit_table(report, narrow=True, drop=NARROW_DROPS[-1], wrap=True)
                quantity = table.columns[1]
                quantity.width = 8
                least = Measurement.get(con, con.options.update_width(10_000), table).minimum
                if least > con.width:  # its 8 columns kept (rich left it none at 40): the terminal wraps the rows
                    con = console(stderr=True, highlight=False, soft_wrap=True, width=least)
                else:  # what the other columns leave, at least 8
                    quantity.width = None
                con.print(table)
                return
        con.print(table)
        return
    out = console(stderr=True, highlight=False, soft_wrap=True, width=200)
    with out.capture() as captured:
        out.print(table)
    sys.stderr.write("".join(line.rstrip() + "\n" for line in captured.get().splitlines()))


def _print_verdict(report, quiet: bool, with_cycle: bool = True) -> None:
    from ..limits.report import percent

    from ..pipelines.check import CLOSED_NOTE

    cycle = (
        f"cycle: {report.duration:.4f} s one way, {report.round_trip:.4f} s round trip "
        f"(dwell {report.dwell:g} s), {report.picks_per_minute:.1f} picks/min"
    )
    if any(CLOSED_NOTE in n for n in report.notes):  # a checked file that returns to its start is the whole cycle
        cycle = (f"cycle: {report.duration:.4f} s, the whole duty cycle (the file ends where it starts), "
                 f"{60.0 / report.duration:.1f} picks/min")  # (its JSON: pipelines.check.WholeCycleReport)
    if not with_cycle:
        cycle = f"move {report.duration:.4f} s"
    if report.ok:
        for r in report.exceeded_not_held:  # said even with -q: the rule left this limit out and the move breaks it
            sys.stderr.write(f"pickplace: {_violation_text(r)}\n")
        vague = report.unresolved
        for r in vague:  # a peak the samples cannot pin down: said even with -q (the verdict depends on it)
            from ..pipelines.batch import unresolved_text

            sys.stderr.write(
                f"pickplace: {unresolved_text(r)}: the samples are too sparse (or too noisy) for this peak; it is not "
                "shown exceeded, but not shown within the limit either: check a trajectory sampled at a higher rate "
                "(plan --strict writes one with every peak resolved)\n")
        if not quiet:
            # a profile whose limits are all positions and the workcell (no joint speed, torque …): nothing that
            # the duration changes was checked, however short it is; say so instead of a bare "all limits hold"
            untimed = report.rows and all(r.kind == "reach" for r in report.rows)
            scope = " (positions and workcell only: this profile sets no limit that depends on the duration)" if untimed else ""
            held = ("all limits hold" if not vague else
                    f"no limit exceeded; {len(vague)} peak(s) not resolved by the samples")
            loose = report.exceeded_not_held
            if loose:  # the rule leaves the capacity out and the move exceeds it: never "all limits hold"
                held = (("every limit held by the rule holds" if not vague else held)
                        + f"; {_not_held_words(loose)}")
            elif any(r.not_held for r in report.rows):  # within the capacity although the rule does not hold it
                rules = " / ".join(sorted({r.not_held for r in report.rows if r.not_held}))
                held = held.replace("all limits hold", f"all limits hold, the Cartesian capacity too (not held under {rules})")
            sys.stderr.write(f"verdict: {held}{scope}; {cycle}\n")
        return
    from ..pipelines.batch import violation_text  # the same words as a batch row's limit lines

    for r in report.violations:
        sys.stderr.write(f"pickplace: {violation_text(r)}\n")
    for r in report.exceeded_not_held:
        sys.stderr.write(f"pickplace: {violation_text(r)}\n")
    if not quiet:
        loose = report.exceeded_not_held
        more = f"; {_not_held_words(loose)}" if loose else ""
        sys.stderr.write(f"verdict: {len(report.violations)} limit(s) exceeded{more}; {cycle}\n")


def _violation_text(r) -> str:
    from ..pipelines.batch import violation_text

    return violation_text(r)


def _not_held_words(rows) -> str:
    """The verdict's words for limits exceeded that the rule does not hold, e.g. ``Cartesian capacity exceeded,
    not held under --time fit (speed 116.5 %, acceleration 184.0 %)``."""
    from ..limits.report import percent

    what = ", ".join(f"{r.quantity.removeprefix('capacity ')} {percent(r.utilisation)} %" for r in rows)
    rules = sorted({r.not_held for r in rows})
    cap = all(r.quantity.startswith("capacity") for r in rows)
    return f"{'Cartesian capacity' if cap else 'limits'} exceeded, not held under {' / '.join(rules)} ({what})"


def _print_summary(result) -> None:
    s = result.summary()
    d = result.duration
    par = result.parameters
    if "k1" in par:
        wide = "".join(f", {k} = {par[k]:.4f}" for k in ("k3", "k4", "mid") if k in par)
        wide += f", arch = {par['arch'] * 1e3:.2f} mm" if "arch" in par else ""  # the widened family's
        ks = f"k1 = {par['k1']:.4f}, k2 = {par['k2']:.4f}{wide} ({par['k_source']})"
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
    turn = par.get("turn")
    if turn:  # a rotary fourth axis: the tool's turn planned with the move
        import math

        when = ("over the whole move" if turn["during"] == "whole" else
                "between lift-off and set-down (τ {:.3f} … {:.3f})".format(*turn["window_tau"]))
        ks += (f"\nturn: tool angle {turn['from_rad']:.4g} → {turn['to_rad']:.4g} rad "
               f"({math.degrees(turn['turn_rad']):+.1f}°) {when}")
    bounds = f"v {d.t_velocity:.4f} s, a {d.t_acceleration:.4f} s" + (f", j {d.t_jerk:.4f} s" if d.t_jerk else "")
    fit = f"; fit {d.t_fit:.4f} s" if d.t_fit is not None else ""
    rule = d.mode
    if d.mode == "limits":  # the default: say what the capacity costs against the motors alone
        rule = "limits: every limit of the profile"
        timed = any(r.kind == "limit" and r.joint != "tool" for r in result.report.rows)
        fit = (f"; fit (joint and motor limits alone) {d.t_fit:.4f} s" if d.t_fit is not None
               else "" if timed  # (a belt's rendezvous chooses its duration without the fit of one move)
               else "; fit: no joint or motor limit depends on the duration")
    loose = sorted({r.not_held for r in result.report.rows if r.not_held})
    if loose:  # fit / optimal: the joint and motor limits alone
        rule += f": joint and motor limits alone, the Cartesian capacity not held"
    use = result.report.rows and min(r.target for r in result.report.rows)
    if use and use < 1.0:
        rule += f", limit use {100 * use:g} %"
    if d.t_optimal is not None and d.t_fit:
        fit += (f"; optimal {d.t_optimal:.4f} s = {d.t_optimal / d.t_fit:.3f} × fit, {d.t_optimal / d.t_auto:.3f} × auto"
                f" ({60 / (2 * d.t_optimal + 2 * result.report.dwell):.1f} against "
                f"{60 / (2 * d.t_fit + 2 * result.report.dwell):.1f} picks/min with fit)")
        if d.t_bound:
            fit += (f"; lower bound {d.t_bound:.4f} s (peak motor torque and speed alone: T = {d.seconds / d.t_bound:.3f} "
                    "× bound; the rest is torque rate, RMS and smoothness)")
    sys.stderr.write(
        f"{s['profile']} / {s['method']}: b = {s['b_m']:.4g} m, h = {s['height_m']:.4g} m, λ = {s['lambda']:.4g}, η = {s['eta']:g}; {ks}\n"
        f"duration T = {d.seconds:.4f} s ({rule}; binding: {d.binding}); auto {d.t_auto:.4f} s (Eq. 26: {bounds}){fit}; "
        f"{s['samples']} samples\n"
        f"peaks |v| = {s['peak_speed_m_s']:.4g} m/s, |a| = {s['peak_acceleration_m_s2']:.4g} m/s², "
        f"|j| = {s['peak_jerk_m_s3']:.4g} m/s³\n"
    )
    if d.written:  # a time-optimal law slowed so that check reads its written samples within every limit
        sys.stderr.write(d.written + "\n")
    if getattr(result, "cycle", None) is not None:  # the controller's cycle: what rounding did and cost
        sys.stderr.write(result.cycle.text() + "\n")


def _opt(x, fmt: str = "{:.4g}", scale: float = 1.0) -> str:
    return "–" if x is None else fmt.format(x * scale)


def _print_comparison(comparison) -> None:
    """One column per method, one row per quantity (fits a terminal with every method of the registry)."""
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
        ("limits", lambda r: ("ok" if r.limits_ok else "EXCEEDED")
         + ("; capacity EXCEEDED, not held" if r.exceeded_not_held else "")),
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
    out = console(stderr=True, highlight=False, soft_wrap=True)
    if out.width < need:
        out = console(stderr=True, highlight=False, soft_wrap=True, width=need)
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
        if r.ok and r.exceeded_not_held:
            sys.stderr.write(f"{r.method}: exceeded, not held under --time {comparison.time}: "
                             f"{', '.join(r.exceeded_not_held)} (--time limits holds it)\n")
