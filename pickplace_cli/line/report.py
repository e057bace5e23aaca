"""A line run's results as files and tables: per part (CSV, written row by row as parts are answered, or JSON
lines), per robot (CSV), the whole run (JSON), and the terminal table (rich, on stderr).

Every column header carries its unit (``[s]``, ``[m]``, ``[rad]``, ``[N*m]``, ``[1/min]``; ``[-]`` for a ratio).
Numbers are written with a fixed format (``%.12g``), so the same run gives the same bytes.
"""

from __future__ import annotations

import json
import math
from typing import IO, Any

PART_COLUMNS = (
    "id", "row", "t_detect[s]", "along[m]", "across[m]", "angle[rad]", "picked", "robot", "t_start[s]", "t_meet[s]",
    "meet_along[m]", "meet_across[m]", "pick_duration[s]", "place_duration[s]", "t_placed[s]", "t_free[s]",
    "target", "turn[rad]", "exit_code", "reason",
)


def _num(x) -> str:
    if x is None:
        return ""
    if isinstance(x, bool):
        return "1" if x else "0"
    if isinstance(x, int):
        return str(x)
    x = float(x)
    return "%.12g" % x if math.isfinite(x) else ""


def _text(s) -> str:
    """A CSV cell of free text: quoted when it holds a comma, quote or line break."""
    s = "" if s is None else str(s)
    if any(c in s for c in ',"\n\r'):
        return '"' + s.replace('"', '""') + '"'
    return s


class PartsCsv:
    """The per-part CSV: :meth:`header` once, then :meth:`row` per answered part. ``typed`` (a line with part types):
    a ``type`` column after ``angle[rad]``."""

    def __init__(self, stream: IO[str], typed: bool = False) -> None:
        self.stream = stream
        self.typed = typed

    def header(self) -> None:
        cols = list(PART_COLUMNS)
        if self.typed:
            cols.insert(cols.index("angle[rad]") + 1, "type")
        self.stream.write(",".join(cols) + "\n")

    def row(self, res) -> None:
        d = res.as_dict()
        cells = [_text(d.get("id")), str(d.get("row", "")), _num(d.get("t_detect_s")), _num(d.get("along_m")),
                 _num(d.get("across_m")), _num(d.get("angle_rad")), _num(bool(d["picked"])), _text(d.get("robot")),
                 _num(d.get("t_start_s")), _num(d.get("t_meet_s")), _num(d.get("meet_along_m")),
                 _num(d.get("meet_across_m")), _num(d.get("pick_duration_s")), _num(d.get("place_duration_s")),
                 _num(d.get("t_placed_s")), _num(d.get("t_free_s")), _num(d.get("target")),
                 _num(d.get("turn_rad")), str(d["exit_code"]),
                 _text(d.get("reason"))]
        if self.typed:
            cells.insert(PART_COLUMNS.index("angle[rad]") + 1, _text(d.get("type")))
        self.stream.write(",".join(cells) + "\n")


def part_json(res) -> str:
    """One part's answer as a JSON line (its assignment and plan, or why it is missed)."""
    return json.dumps(_finite(res.as_dict()), separators=(",", ":"))


def _finite(doc: Any) -> Any:
    if isinstance(doc, float):
        return doc if math.isfinite(doc) else None
    if isinstance(doc, dict):
        return {k: _finite(v) for k, v in doc.items()}
    if isinstance(doc, (list, tuple)):
        return [_finite(v) for v in doc]
    return doc


def summary_json(summary, line_name: str, compact: bool = False) -> str:
    """The run (line, robots) as one JSON document (``compact``: one line)."""
    doc = {"line": line_name, **summary.as_dict()}
    if compact:
        return json.dumps(_finite(doc), separators=(",", ":")) + "\n"
    return json.dumps(_finite(doc), indent=1) + "\n"


def write_robots_csv(summary, stream: IO[str]) -> None:
    """One row per robot: picks, picks/min, busy, idle, utilisation, per motor RMS over the run, rated and use,
    and the peak use of every limit (columns: the union over the robots); on a line with part types its picks of each
    type (``picks_TYPE``)."""
    joints = []
    for r in summary.robots:
        joints += [j for j in r.joints if j not in joints]
    keys = sorted({k for r in summary.robots for k in r.peak_use})
    head = ["robot", "picks", "picks_per_minute[1/min]", "busy[s]", "idle[s]", "utilisation[-]"]
    for j in joints:
        head += [f"rms_{j}[N*m]", f"rated_{j}[N*m]", f"rms_use_{j}[-]"]
    head += [f"peak_use_{j}_{q.replace(' ', '_')}[-]" for j, q in keys]
    types = [t.name for t in summary.types] if summary.types else []
    head += [f"picks_{t}" for t in types]  # a line with part types: each robot's picks of each type
    stream.write(",".join(head) + "\n")
    for r in summary.robots:
        cells = [_text(r.name), str(r.picks), _num(r.picks_per_minute), _num(r.busy), _num(r.idle), _num(r.utilisation)]
        rms = dict(zip(r.joints, r.rms))
        rated = dict(zip(r.joints, r.rated))
        for j in joints:
            x, lim = rms.get(j), rated.get(j)
            cells += [_num(x), _num(lim), _num(x / lim if x is not None and lim is not None and lim > 0 else None)]
        cells += [_num(r.peak_use.get(k)) for k in keys]
        cells += [str((r.type_picks or {}).get(t, 0)) for t in types]
        stream.write(",".join(cells) + "\n")


def interval_text(iv) -> list[str]:
    """The intervals as lines of text (none without them)."""
    if iv is None:
        return []
    level = f"{100 * iv.miss_wilson.level:g} %"
    wil = f"Wilson, were the parts missed independently: {100 * iv.miss_wilson.low:.1f} … {100 * iv.miss_wilson.high:.1f} %"
    if iv.miss is None:
        return [f"miss rate {100 * iv.miss_wilson.estimate:.1f} % ({level}: {wil}; too few parts for batch means)"]
    return [f"miss rate {100 * iv.miss.estimate:.1f} ± {100 * iv.miss.half:.1f} % ({level}, batch means over "
            f"{iv.batches} windows of {iv.window:.3g} s; {wil})",
            f"picks/min {iv.picks_per_minute.estimate:.1f} ± {iv.picks_per_minute.half:.1f} ({level}, batch means)"]


def type_text(ts) -> list[str]:
    """A part type's figures as lines of text: its counts, then its intervals (as :func:`interval_text`)."""
    head = (f"type {ts.name}: {ts.parts} parts, {ts.picked} picked, {ts.missed} missed ({100 * ts.miss_rate:.1f} %): "
            f"{ts.picks_per_minute:.1f} picks/min")
    return [head] + ["  " + x for x in interval_text(ts.intervals)]


def print_table(summary, console=None) -> None:
    """The per-robot table and the line's totals, on stderr (rich)."""
    from rich.console import Console
    from rich.table import Table

    console = console or Console(stderr=True, highlight=False)
    t = Table(title=f"line: {summary.parts} parts ({summary.parts_per_minute:.1f}/min), {summary.picked} picked, "
                    f"{summary.missed} missed ({100 * summary.miss_rate:.1f} %): {summary.picks_per_minute:.1f} "
                    f"picks/min; run {summary.span:.2f} s", title_justify="left")
    for col, just in (("robot", "left"), ("picks", "right"), ("picks/min", "right"), ("utilisation", "right"),
                      ("idle [s]", "right"), ("peak motor limit use", "left"), ("RMS torque / rated", "left")):
        t.add_column(col, justify=just)
    for r in summary.robots:
        motor = {k: u for k, u in r.peak_use.items() if k[1] in ("motor torque", "motor speed", "motor torque rate")}
        pool = motor or r.peak_use
        if pool:
            (j, q), u = max(pool.items(), key=lambda kv: kv[1])
            peak = f"{j} {q} {100 * u:.1f} %"
        else:
            peak = "-"
        uses = r.rms_use
        rms = ", ".join(f"{j} {100 * u:.1f} %" for j, u in zip(r.joints, uses) if math.isfinite(u)) or "-"
        t.add_row(r.name, str(r.picks), f"{r.picks_per_minute:.1f}", f"{100 * r.utilisation:.1f} %",
                  f"{r.idle:.2f}", peak, rms)
    console.print(t)
    for text in interval_text(summary.intervals) + [x for ts in summary.types or [] for x in type_text(ts)]:
        console.print(text, soft_wrap=True, markup=False)
