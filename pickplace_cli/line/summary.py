"""A line run summed up: per robot (picks/min, utilisation, idle time, peak use of every limit, RMS torque of every
motor over its actual sequence) and per line (picks/min, miss rate); the exit code of the run.

Two spans: the **feed**, from the first detection to the last, gives the rates — parts/min fed = 60·(N − 1)/feed
(exact for N parts at a regular rate), picks/min = parts/min · picked/N (the line's throughput: parts/min · (1 − miss
rate)), a robot's picks/min = parts/min · its picks/N; the **run**, from the first detection to the end of the last
leg of any robot (the last parts still travel to the downstream robots after the feed), is what utilisation, idle
time and the RMS torques are taken over, so that every move counts.

The RMS of a motor over the run (see :mod:`~pickplace_cli.line.engine`) adds the exact integral of τ² over every
leg and the holding torque squared over every rest: before the robot's first leg it holds the tool at its home
point; between legs it rests where the previous leg ended (a leg ending in motion — a release on an outgoing
belt — is always followed at once by the next pick or a stop).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np


@dataclass
class RobotSummary:
    """One robot: picks, picks/min (its share of the parts fed per minute), and over the run [t_begin, t_end]
    (``span``): busy time (moves and dwells), utilisation (busy / span), idle time, the peak use of every limit over its legs ((joint, quantity) → utilisation), and per
    motor the RMS torque over the sequence [N·m], its rated torque and use."""

    name: str
    picks: int
    busy: float
    span: float
    parts_per_minute: float
    parts: int
    peak_use: dict
    joints: list
    rms: np.ndarray
    rated: np.ndarray
    legs: int
    exact_legs: int
    exchanges: int = 0
    #: picks per part type (None: a line without types)
    type_picks: Any = None

    @property
    def picks_per_minute(self) -> float:
        return self.parts_per_minute * self.picks / self.parts if self.parts else 0.0

    @property
    def utilisation(self) -> float:
        return self.busy / self.span if self.span > 0 else 0.0

    @property
    def idle(self) -> float:
        return max(self.span - self.busy, 0.0)

    @property
    def rms_use(self) -> np.ndarray:
        with np.errstate(invalid="ignore", divide="ignore"):
            return self.rms / self.rated

    def violations(self) -> list[str]:
        """One line per motor whose RMS torque over the run exceeds its rated torque."""
        out = []
        for name, r, lim in zip(self.joints, self.rms, self.rated):
            if np.isfinite(lim) and r > lim:
                out.append(f"robot {self.name}: {name} rms motor torque {r:.4g} N·m over the run ({self.span:.4g} s of "
                           f"moves, dwells and rests) is {100 * r / lim:.1f} % of its rated {lim:.4g} N·m")
        return out

    def as_dict(self) -> dict[str, Any]:
        return {
            "robot": self.name, "picks": self.picks, "picks_per_minute": self.picks_per_minute,
            "busy_s": self.busy, "idle_s": self.idle, "utilisation": self.utilisation, "span_s": self.span,
            "legs": self.legs, "legs_checked_exactly": self.exact_legs, "place_exchanges": self.exchanges,
            "rms_motor_torque_N_m": {j: float(r) for j, r in zip(self.joints, self.rms)},
            "rated_torque_N_m": {j: (float(x) if np.isfinite(x) else None) for j, x in zip(self.joints, self.rated)},
            "rms_use": {j: (float(u) if np.isfinite(u) else None) for j, u in zip(self.joints, self.rms_use)},
            "peak_use": {f"{j} {q}": float(u) for (j, q), u in sorted(self.peak_use.items())},
            **({} if self.type_picks is None else {"picks_by_type": dict(self.type_picks)}),
        }


@dataclass
class TypeSummary:
    """One part type of a line with several: its parts, picked, missed, share of the generated parts (None: not
    generated), the line's parts/min fed (its rate is that times its share of the parts: as a robot's) and its
    intervals (:mod:`~pickplace_cli.line.confidence`, over this type's parts alone)."""

    name: str
    parts: int
    picked: int
    line_parts: int
    line_parts_per_minute: float
    share: float | None = None
    intervals: Any = None

    @property
    def missed(self) -> int:
        return self.parts - self.picked

    @property
    def miss_rate(self) -> float:
        return self.missed / self.parts if self.parts else 0.0

    @property
    def parts_per_minute(self) -> float:
        return self.line_parts_per_minute * self.parts / self.line_parts if self.line_parts else 0.0

    @property
    def picks_per_minute(self) -> float:
        return self.line_parts_per_minute * self.picked / self.line_parts if self.line_parts else 0.0

    def as_dict(self) -> dict[str, Any]:
        return {"parts": self.parts, "picked": self.picked, "missed": self.missed, "miss_rate": self.miss_rate,
                "parts_per_minute": self.parts_per_minute, "picks_per_minute": self.picks_per_minute,
                "share": self.share, "intervals": None if self.intervals is None else self.intervals.as_dict()}


@dataclass
class LineSummary:
    """The run: parts offered, picked, missed, bad rows; span [s]; per robot summaries; warnings."""

    parts: int
    picked: int
    missed: int
    bad_rows: int
    t_begin: float
    t_end: float
    t_last_detection: float
    robots: list = field(default_factory=list)
    warnings: list = field(default_factory=list)
    #: the miss rate's and picks/min's confidence intervals (:mod:`~pickplace_cli.line.confidence`)
    intervals: Any = None
    #: --until: {"precision", "reached", "max_s"} (None without it)
    until: Any = None
    #: per part type (a line with several): :class:`TypeSummary` in the file's order (None: one kind of part)
    types: Any = None

    @property
    def span(self) -> float:
        return max(self.t_end - self.t_begin, 0.0)

    @property
    def miss_rate(self) -> float:
        return self.missed / self.parts if self.parts else 0.0

    @property
    def feed(self) -> float:
        """First to last detection [s]."""
        return max(self.t_last_detection - self.t_begin, 0.0)

    @property
    def parts_per_minute(self) -> float:
        return 60.0 * (self.parts - 1) / self.feed if self.feed > 0 and self.parts > 1 else 0.0

    @property
    def picks_per_minute(self) -> float:
        return self.parts_per_minute * self.picked / self.parts if self.parts else 0.0

    def violations(self) -> list[str]:
        return [v for r in self.robots for v in r.violations()]

    def exit_code(self) -> int:
        """1 when a detection row was refused, else 3 when a motor's RMS over the run exceeds its rated torque,
        else 0 (missed parts are results, counted in the miss rate)."""
        if self.bad_rows:
            return 1
        return 3 if self.violations() else 0

    def as_dict(self) -> dict[str, Any]:
        return {
            "parts": self.parts, "picked": self.picked, "missed": self.missed, "bad_rows": self.bad_rows,
            "miss_rate": self.miss_rate, "parts_per_minute": self.parts_per_minute,
            "picks_per_minute": self.picks_per_minute, "feed_s": self.feed,
            "t_begin_s": self.t_begin if math.isfinite(self.t_begin) else None,
            "t_end_s": self.t_end if math.isfinite(self.t_end) else None, "span_s": self.span,
            "intervals": None if self.intervals is None else self.intervals.as_dict(),
            **({} if self.until is None else {"until": dict(self.until)}),
            **({} if self.types is None else {"types": {t.name: t.as_dict() for t in self.types}}),
            "exit_code": self.exit_code(), "violations": self.violations(), "warnings": list(self.warnings),
            "robots": [r.as_dict() for r in self.robots],
        }


def sequence_integral(legs: list, home_torque: np.ndarray, t_begin: float, t_end: float) -> tuple[np.ndarray, float]:
    """(Σ ∫ τ² dt per motor over [t_begin, t_end], busy time): the legs' exact integrals, and the holding torque
    over every rest (module docstring)."""
    total = np.zeros_like(home_torque, dtype=float)
    busy = 0.0
    t = t_begin
    hold = home_torque
    for leg in sorted(legs, key=lambda g: g.t0):
        if leg.t0 > t:
            total += hold**2 * (leg.t0 - t)
        total += leg.integral
        busy += leg.duration
        t = leg.t1
        hold = leg.end_torque
    if t_end > t:
        total += hold**2 * (t_end - t)
    return total, busy


def summarise(engine) -> LineSummary:
    """The :class:`LineSummary` of a finished :class:`~pickplace_cli.line.engine.LineEngine`."""
    ends = [leg.t1 for run in engine.runs for leg in run.legs]
    t_begin = engine.t_begin if math.isfinite(engine.t_begin) else 0.0
    t_end = max([engine.t_last if math.isfinite(engine.t_last) else t_begin] + ends)
    picked = sum(1 for r in engine.results if r.picked)
    parts = sum(1 for r in engine.results if r.detection is not None)
    t_last = engine.t_last if math.isfinite(engine.t_last) else t_begin
    out = LineSummary(parts, picked, parts - picked, engine.bad_rows, t_begin, t_end, t_last,
                      warnings=list(engine.warnings))
    span = max(t_end - t_begin, 0.0)
    from .confidence import summary_intervals

    out.intervals = summary_intervals(out, engine.results)
    if engine.types is not None:
        from .confidence import run_intervals, type_arrays

        shares = engine.line.parts.types
        out.types = []
        for kind in engine.types:
            t, missed = type_arrays(engine.results, kind)
            ts = TypeSummary(kind, len(t), int(len(t) - missed.sum()), parts, out.parts_per_minute,
                             float(shares[kind].share) if engine.line.parts.generate is not None else None)
            ts.intervals = run_intervals(t, missed, ts.picks_per_minute)
            out.types.append(ts)
    for run in engine.runs:
        r = run.robot
        integral, busy = sequence_integral(run.legs, r.home_torque, t_begin, t_end)
        rms = np.sqrt(integral / span) if span > 0 else np.zeros_like(integral)
        uses = [leg.use for leg in run.legs if leg.use is not None and len(leg.use)]
        # the limits' keys of whichever of the robot's places checked a leg (one profile: the same columns in all)
        keys = next((x.use_keys for x in getattr(run, "instances", [r]) if x.use_keys), r.use_keys)
        peak = dict(zip(keys, np.max(uses, axis=0).tolist())) if uses else {}
        if r.limit_use != 1.0:  # planned against use × rating: the use of the ratings themselves
            peak = {k: (v * r.limit_use if not k[1].startswith(("position", "workcell", "singularity")) else v)
                    for k, v in peak.items()}
        out.robots.append(RobotSummary(r.name, run.picks, busy, span, out.parts_per_minute, parts, peak, r.joint_names,
                                       rms, r.rated,
                                       len(run.legs), sum(1 for leg in run.legs if leg.exact), len(run.exchanges),
                                       None if engine.types is None else {k: run.type_picks.get(k, 0) for k in engine.types}))
    return out
