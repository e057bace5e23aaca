"""What the limit check reports: one row per joint × quantity (:class:`LimitRow`) and the whole move
(:class:`LimitReport`: verdict, exit code, cycle time).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np


def percent(utilisation: float) -> str:
    """A utilisation as a percentage for people: one decimal up to 9999.9 %, then 3 significant digits
    (2.92e+07), so a wildly infeasible move does not print 29178779.3."""
    p = 100.0 * utilisation
    return f"{p:.1f}" if abs(p) < 9999.95 else f"{p:.3g}"


#: a peak estimated from samples counts as resolved when its accuracy is within this fraction of the allowed value
RESOLVED = 0.01


@dataclass(slots=True)
class LimitRow:
    """One checked limit: the peak of a quantity over the move, its limit and where the peak is.

    Attributes
    ----------
    joint : str
        ``q1`` … ``qn``, or ``tool`` (the singularity measure, the workcell box, the Cartesian capacity).
    quantity : str
        What is checked (``motor torque``, ``position min``, ``capacity speed`` …).
    unit : str
        The unit of ``peak`` and ``limit`` (rad, m, rad/s, N·m, N·m/s, m/s, …).
    peak : float
        The peak over the continuous move [unit] (signed for ranges and minima, a magnitude otherwise).
    limit : float
        The rating [unit].
    utilisation : float
        peak / limit [-] (a range: how far toward the bound, 1 at it).
    t_peak : float or None
        When the peak happens [s] (None for quantities of the whole cycle, e.g. RMS torque).
    ok : bool
        Whether the limit holds (at ``target`` × ``limit``).
    kind : str
        ``limit`` (a timed limit: exit code 3) or ``reach`` (position, workcell, singularity: exit code 4).
    bound : str
        ``upper`` (peak ≤ limit) or ``lower`` (peak ≥ limit).
    target : float
        The fraction [-] of ``limit`` the peak may use (the limit use of a timed limit, else 1).
    accuracy : float or None
        ± how far the peak may be off [unit] when estimated from samples (``check``); None on the continuous motion.
    not_held : str
        Empty when the duration rule holds this limit; else why it does not (e.g. ``--time fit``: the Cartesian
        capacity under a rule of joint and motor limits alone). Such a row is reported (peak, use, ``ok`` whether
        it is within the limit) but does not decide the verdict or the exit code.

    Notes
    -----
    (A plain slotted record, not a frozen dataclass: a report has ~25 rows per move and a frozen
    dataclass costs 5× as much to build, which the single-plan target of < 1 ms notices.)"""

    joint: str  # "q1" … or "tool"
    quantity: str
    unit: str
    peak: float  # signed for position bounds and the singularity minimum, |·| otherwise
    limit: float
    utilisation: float  # peak/limit (position: how far toward the bound, 1 = at it)
    t_peak: float | None  # s from the start of the move (None for whole-cycle quantities)
    ok: bool
    kind: str = "limit"  # "limit" (exit 3) or "reach" (exit 4)
    bound: str = "upper"  # "upper": peak ≤ limit; "lower": peak ≥ limit
    #: the fraction of ``limit`` the peak may use (the profile's limit-use fraction for a timed limit, else 1):
    #: ok ⇔ utilisation ≤ target
    target: float = 1.0
    #: ± how far the peak may be off [unit], when it is estimated from samples (``check``); None: found on the
    #: continuous motion. ok then means the peak less this is allowed: the data does not show the limit exceeded
    accuracy: float | None = None
    #: "" when the duration rule holds this limit; else why it does not (``--time fit``): reported, not judged
    not_held: str = ""

    @property
    def held(self) -> bool:
        """Whether the duration rule holds this limit (its verdict counts toward the report's ``ok``)."""
        return not self.not_held

    @property
    def resolved(self) -> bool:
        """Whether the samples decide this row: the peak is known to ``RESOLVED`` of the allowed value, or it is within
        the allowed value even at the far end of its accuracy (always, without an accuracy)."""
        return (self.accuracy is None or self.accuracy <= RESOLVED * abs(self.allowed)
                or self.peak + self.accuracy <= self.allowed)

    @property
    def allowed(self) -> float:
        """The value the peak may reach: ``target`` × ``limit`` (the limit itself without headroom)."""
        return self.limit * self.target

    @property
    def excess(self) -> float:
        """By how much the allowed value is exceeded (same unit; ≤ 0 when ok)."""
        return self.allowed - self.peak if self.bound == "lower" else self.peak - self.allowed

    def as_dict(self) -> dict[str, Any]:
        return {
            "joint": self.joint, "quantity": self.quantity, "unit": self.unit, "peak": self.peak,
            "limit": self.limit, "utilisation": self.utilisation, "t_peak_s": self.t_peak, "ok": self.ok,
            "kind": self.kind, "bound": self.bound, "excess": self.excess, "limit_use": self.target,
            **({} if self.accuracy is None else {"accuracy": self.accuracy, "resolved": self.resolved}),
            "held": self.held, **({"not_held": self.not_held} if self.not_held else {}),
        }


@dataclass(frozen=True)
class LimitReport:
    """Every joint × quantity checked for one move, with the duty cycle.

    Attributes
    ----------
    rows : tuple of LimitRow
        Every checked limit.
    duration : float
        The move's duration [s].
    dwell : float
        The dwell at each end of the duty cycle [s] (move, dwell, move back, dwell).
    notes : tuple of str
        What the check wants said (how a peak was found, what was left out).
    strict : bool
        A peak the samples do not resolve (``unresolved``) fails too: ``exit_code`` 3 (``plan --strict``).
    ok : bool
        Whether every limit the duration rule holds is within its limit; ``violations`` lists the rows that are
        not. Rows the rule does not hold (``LimitRow.not_held``, the Cartesian capacity under ``fit`` or
        ``optimal``) do not count: ``exceeded_not_held`` lists those beyond their limit, ``all_ok`` counts them.
    round_trip : float
        The duty cycle 2·(duration + dwell) [s]; ``picks_per_minute`` is 60 / round_trip [1/min].
    """

    rows: tuple[LimitRow, ...]
    duration: float
    dwell: float
    notes: tuple[str, ...] = ()
    strict: bool = False  # a peak the samples do not resolve (``unresolved``) fails too (exit 3): ``plan --strict``

    @property
    def ok(self) -> bool:
        return all(r.ok for r in self.rows if not r.not_held)

    @property
    def all_ok(self) -> bool:
        """Whether every row is within its limit, the rows the rule does not hold included."""
        return all(r.ok for r in self.rows)

    @property
    def violations(self) -> tuple[LimitRow, ...]:
        """The rows the rule holds that exceed their limit (they decide the exit code)."""
        return tuple(r for r in self.rows if not r.ok and not r.not_held)

    @property
    def exceeded_not_held(self) -> tuple[LimitRow, ...]:
        """The rows beyond their limit that the duration rule does not hold (``LimitRow.not_held``)."""
        return tuple(r for r in self.rows if not r.ok and r.not_held)

    @property
    def unresolved(self) -> tuple[LimitRow, ...]:
        """Rows the rule holds, within their limit, whose peak the samples do not resolve to ``RESOLVED`` (``check``)."""
        return tuple(r for r in self.rows if r.ok and not r.resolved and not r.not_held)

    @property
    def round_trip(self) -> float:
        return 2.0 * (self.duration + self.dwell)

    @property
    def picks_per_minute(self) -> float:
        return 60.0 / self.round_trip

    def exit_code(self) -> int:
        """0 ok · 3 a limit is exceeded (or, ``strict``, a peak is not resolved by the samples) · 4 a reach row
        (singularity, workcell) fails."""
        bad = self.violations
        if not bad:
            return 3 if self.strict and self.unresolved else 0
        return 4 if any(r.kind == "reach" for r in bad) else 3

    def rated(self, use: float) -> "LimitReport":
        """This report, planned and checked against limits scaled by ``use`` (the limit-use fraction), stated
        against the ratings: every timed row (kind "limit") gets limit = its rating, utilisation = peak / rating
        and target = ``use`` (its verdict unchanged); positions, the workcell and the singularity margin stay."""
        if use == 1.0:
            return self
        rows = []
        for r in self.rows:
            if r.kind == "limit" and r.bound == "upper":
                rating = r.limit / use
                r = LimitRow(r.joint, r.quantity, r.unit, r.peak, rating, r.peak / rating, r.t_peak, r.ok, r.kind,
                             r.bound, use, r.accuracy, r.not_held)
            rows.append(r)
        return replace(self, rows=tuple(rows))

    def with_rows(self, rows: tuple[LimitRow, ...]) -> "LimitReport":
        """This report with ``rows`` added after its own."""
        return replace(self, rows=self.rows + tuple(rows))

    def as_dict(self) -> dict[str, Any]:
        return {
            "ok": self.ok,
            "all_limits_ok": self.all_ok,
            "duration_s": self.duration,
            "dwell_s": self.dwell,
            "cycle_time_one_way_s": self.duration,
            "cycle_time_round_trip_s": self.round_trip,
            "picks_per_minute": self.picks_per_minute,
            "violations": [r.as_dict() for r in self.violations],
            "exceeded_not_held": [r.as_dict() for r in self.exceeded_not_held],
            "rows": [r.as_dict() for r in self.rows],
            "notes": list(self.notes),
        }


@dataclass(frozen=True)
class _ReportPlan:
    """:meth:`MotionModel.report_plan`: limits (column sign convention), exact-refinement bands and signs per
    column; rows as ("single", column, (joint, quantity, unit, limit, kind, lower)), ("range", (column of the
    max, of the min), (joint, base, unit, kind, lo, hi)) or ("rms", joint index, (joint, rated torque))."""

    limits: np.ndarray
    band: np.ndarray
    signs: np.ndarray
    rows: tuple
    rms: bool
    zoom: np.ndarray  # the duration-dependent columns (limit kind), whose peaks are zoomed in
    zoom_sub: np.ndarray  # their indices among the columns without the singularity measure
