"""The duration rules: what ``--time`` may say (:data:`TIME_RULES` or seconds, :func:`parse_time`) and the value
object a chosen duration is (:class:`Duration`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..model.errors import TaskError


@dataclass(frozen=True)
class Duration:
    """The chosen duration T [s] and how it was chosen.

    Attributes
    ----------
    seconds : float
        The duration T [s].
    mode : str
        The rule that chose it: ``limits``, ``auto``, ``fit``, ``optimal`` or ``given``.
    t_velocity, t_acceleration, t_jerk : float
        The three bounds of Eq. (26) [s] (``t_jerk`` None without a jerk capacity); ``t_auto`` is their maximum.
    binding : str
        What set T (a capacity, or a joint's quantity).
    t_fit : float or None
        The smallest duration at which every joint and motor limit holds [s], when computed.
    t_optimal : float or None
        ``optimal``: the duration of the non-uniform time law [s].
    law : str or None
        ``optimal``: what the optimiser said.
    t_bound : float or None
        ``optimal``: the lower bound under peak motor torque and speed alone [s].
    written_stretch : float
        ``fit`` and ``optimal``: how much longer [-] the law was made so that ``check`` reads its written samples within every
        limit (:mod:`pickplace_cli.timing.written`); 1 when it was not.
    written : str
        ``fit`` and ``optimal``: what that reading did, for the user ("" when nothing).

    ``auto`` is Eq. (26) extended by jerk: T = max(v̂/[v], √(â/[a]), ∛(ĵ/[j])) where v̂, â, ĵ are the exact
    peaks of ‖d^k p/dτ^k‖ of the path with T = 1 (for a symmetric move v̂ = b·v_max etc.). ``binding`` names
    the capacity that sets T. ``t_velocity``, ``t_acceleration``, ``t_jerk`` are the three bounds (s).
    """

    seconds: float
    mode: str
    t_velocity: float
    t_acceleration: float
    t_jerk: float | None
    binding: str
    t_fit: float | None = None  # smallest duration at which every motor/joint limit holds (when computed)
    #: --time optimal: the duration of the non-uniform law (None otherwise) and what the optimiser said
    t_optimal: float | None = None
    law: str | None = None
    #: --time optimal: the lower bound of the path, its time-optimal traversal under peak motor torque and speed
    #: alone (:mod:`pickplace_cli.timing.bound`; None otherwise)
    t_bound: float | None = None
    #: --time fit and optimal: how much the law was slowed so that ``check`` reads its written samples within every limit
    #: (:mod:`pickplace_cli.timing.written`; 1 when it was not) and what was done ("" then)
    written_stretch: float = 1.0
    written: str = ""

    @property
    def t_auto(self) -> float:
        return max(self.t_velocity, self.t_acceleration, self.t_jerk or 0.0)

    def as_dict(self) -> dict:
        return {
            "duration_s": self.seconds,
            "mode": self.mode,
            "auto_s": self.t_auto,
            "fit_s": self.t_fit,
            "auto_bounds_s": {"velocity": self.t_velocity, "acceleration": self.t_acceleration, "jerk": self.t_jerk},
            "binding": self.binding,
            "optimal_s": self.t_optimal,
            "time_law": self.law or "uniform",
            "torque_bound_s": self.t_bound,
            "written_stretch": self.written_stretch,
        }


#: the shortest duration accepted [s] (with moves up to :data:`~pickplace_cli.model.task.MAX_METRES`, the limit
#: check's numbers stay finite)
MIN_SECONDS = 1e-6


#: the duration rules by name (``--time``); a number is a duration in seconds
TIME_RULES = ("limits", "auto", "fit", "optimal")


def parse_time(spec: str | float) -> str | float:
    """``limits`` | ``auto`` | ``fit`` | ``optimal`` (any case, surrounding spaces ignored) | seconds (> 0, finite) →
    the spec; TaskError naming the rule otherwise (with the nearest rule name for a near miss)."""
    if isinstance(spec, str):
        s = spec.strip().lower()
        if s in TIME_RULES:
            return s
        try:
            value = float(s)
        except ValueError:
            import difflib

            near = difflib.get_close_matches(s, TIME_RULES, n=1, cutoff=0.6)
            hint = f"did you mean '{near[0]}'? " if near else ""
            raise TaskError(f"time = {spec!r}: {hint}give 'limits', 'auto', 'fit', 'optimal' or a duration in seconds "
                            "(e.g. 0.25)") from None
    else:
        value = float(spec)
    if not (math.isfinite(value) and value > 0):
        raise TaskError(f"time = {spec!r}: a duration must be a finite number of seconds > 0")
    if value < MIN_SECONDS:
        raise TaskError(f"time = {spec!r}: a duration must be at least {MIN_SECONDS:g} s (no robot moves faster; "
                        "shorter ones overflow the limit check's numbers)")
    return value
