"""Figures of a line (matplotlib, the optional extra ``pickplace-cli[plot]``; only through
:class:`matplotlib.figure.Figure`, deterministic files as ``pickplace plot`` writes them):

* :func:`write_timeline` — a run: every part's way along the belt against time (detection to meeting, coloured
  by the robot that took it; a missed part in grey to the end of the line), the robots' windows, and below it
  each robot's legs (pick, track, place, release, stop) on a time axis, and its place's exchanges (hatched);
* :func:`write_sweep_plot` — a sweep: the miss rate against belt speed, one curve per strategy and robot count
  (the mean over the seeds, the band from the lowest to the highest).
"""

from __future__ import annotations

import math
from typing import IO

import numpy as np

from ..export.plot import FORMATS, require_matplotlib
from ..model.errors import ExportError

LEG_COLOURS = {"pick": "#1f77b4", "track": "#2ca02c", "place": "#ff7f0e", "release": "#9467bd", "stop": "#7f7f7f"}


def _save(fig, stream: IO[bytes], fmt: str) -> None:
    import matplotlib

    if fmt not in FORMATS:
        raise ExportError(f"format = {fmt!r}: a figure is written as {' or '.join(FORMATS)}")
    metadata = {"Date": None, "Creator": None} if fmt == "svg" else {"Software": None}
    with matplotlib.rc_context({"svg.hashsalt": "pickplace", "svg.fonttype": "path"}):
        fig.savefig(stream, format=fmt, metadata=metadata, dpi=110)


#: the meeting points' markers, one per part type in the file's order (the first: a line without types)
TYPE_MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*")


def write_timeline(engine, summary, stream: IO[bytes], fmt: str = "png", title: str | None = None) -> None:
    """The run's figure (module docstring) to the binary ``stream``."""
    require_matplotlib()
    from matplotlib.collections import LineCollection
    from matplotlib.figure import Figure

    robots = engine.robots
    colours = [f"C{k % 10}" for k in range(len(robots))]
    by_name = {r.name: k for k, r in enumerate(robots)}
    fig = Figure(figsize=(12.0, 7.5), layout="constrained")
    ax, gantt = fig.subplots(2, 1, sharex=True, height_ratios=[3, 1.4])
    speed = engine.line.belt.speed
    end_of_line = max(r.window[1] for r in robots) + 0.1
    segs, cols = [], []
    for res in engine.results:
        d = res.detection
        if d is None:
            continue
        if res.cycle is not None:
            segs.append([(d.t, d.along), (res.cycle.t_meet, float(res.cycle.meet_line[0]))])
            cols.append(colours[by_name[res.robot]])
        else:
            segs.append([(d.t, d.along), (d.t + (end_of_line - d.along) / speed, end_of_line)])
            cols.append("0.6")
    ax.add_collection(LineCollection(segs, colors=cols, linewidths=0.6))
    for k, r in enumerate(robots):
        ax.axhspan(r.window[0], r.window[1], color=colours[k], alpha=0.12, lw=0)
        ax.text(summary.t_begin, (r.window[0] + r.window[1]) / 2, f" {r.name}", va="center", fontsize=8, color=colours[k])
    types = getattr(engine, "types", None)
    for k, kind in enumerate(types or [None]):  # the meetings; on a line with part types one marker per type
        picked = [(res.cycle.t_meet, float(res.cycle.meet_line[0]), colours[by_name[res.robot]])
                  for res in engine.results if res.cycle is not None and (kind is None or res.detection.type == kind)]
        if picked:
            ax.scatter([p[0] for p in picked], [p[1] for p in picked], c=[p[2] for p in picked], s=6 if kind is None
                       else 10, zorder=3, marker=TYPE_MARKERS[k % len(TYPE_MARKERS)],
                       **({} if kind is None else {"label": f"type {kind}"}))
    if types:  # the markers in the legend in grey: the colours are the robots'
        legend = ax.legend(loc="upper left", fontsize=8, markerscale=1.5)
        for handle in getattr(legend, "legend_handles", None) or getattr(legend, "legendHandles", []):
            handle.set_color("0.3")
    ax.set_xlim(summary.t_begin, max(summary.t_end, summary.t_begin + 1e-3))
    ax.set_ylim(min([r.window[0] for r in robots] + [d.along for d in (x.detection for x in engine.results) if d]) - 0.05,
                end_of_line)
    ax.set_ylabel("along the belt [m]")
    ax.set_title(title or f"{summary.parts} parts ({summary.parts_per_minute:.0f}/min), {summary.picked} picked, "
                          f"{summary.missed} missed ({100 * summary.miss_rate:.1f} %): "
                          f"{summary.picks_per_minute:.1f} picks/min; grey: missed")
    for k, run in enumerate(engine.runs):
        for kind, colour in LEG_COLOURS.items():
            bars = [(leg.t0, leg.duration) for leg in run.legs if leg.kind == kind]
            if bars:
                gantt.broken_barh(bars, (k - 0.4, 0.8), facecolors=colour)
        swaps = [(t0, t1 - t0) for t0, t1 in run.exchanges]
        if swaps:  # the place is exchanged: the robot cannot place meanwhile
            gantt.broken_barh(swaps, (k - 0.4, 0.8), facecolors="none", edgecolors="0.4", hatch="///", lw=0.5)
    gantt.set_yticks(range(len(robots)), [r.name for r in robots])
    gantt.set_xlabel("t [s] (line clock)")
    from matplotlib.patches import Patch

    handles = [Patch(color=c, label=k) for k, c in LEG_COLOURS.items()]
    if any(run.exchanges for run in engine.runs):
        handles.append(Patch(facecolor="none", edgecolor="0.4", hatch="///", label="exchange"))
    gantt.legend(handles=handles, loc="upper right", fontsize=7, ncols=len(handles))
    _save(fig, stream, fmt)


def write_sweep_plot(rows: list[dict], stream: IO[bytes], fmt: str = "png", title: str | None = None) -> None:
    """The sweep's figure (module docstring) to the binary ``stream``."""
    require_matplotlib()
    from matplotlib.figure import Figure

    fig = Figure(figsize=(8.0, 5.0), layout="constrained")
    ax = fig.subplots()
    groups: dict = {}
    for r in rows:
        if r.get("miss_rate") is None or not math.isfinite(float(r["miss_rate"])):
            continue
        groups.setdefault((r["strategy"], r["robots"]), {}).setdefault(float(r["belt_speed"]), []).append(float(r["miss_rate"]))
    styles = ["-", "--", ":", "-."]
    counts = sorted({n for _, n in groups})
    strategies = sorted({k for k, _ in groups})
    for (kind, n), by_speed in sorted(groups.items()):
        v = np.array(sorted(by_speed))
        m = np.array([np.mean(by_speed[x]) for x in v])
        lo = np.array([np.min(by_speed[x]) for x in v])
        hi = np.array([np.max(by_speed[x]) for x in v])
        colour = f"C{strategies.index(kind) % 10}"
        ax.plot(v, 100 * m, styles[counts.index(n) % len(styles)], color=colour, marker="o", ms=3,
                label=f"{kind}, {n} robot{'s' if n > 1 else ''}")
        if np.any(hi > lo):
            ax.fill_between(v, 100 * lo, 100 * hi, color=colour, alpha=0.12, lw=0)
    ax.set_xlabel("belt speed [m/s]")
    ax.set_ylabel("miss rate [%]")
    ax.set_ylim(bottom=0)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    if title:
        ax.set_title(title)
    _save(fig, stream, fmt)
