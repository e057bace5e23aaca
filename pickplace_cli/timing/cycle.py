"""The controller's cycle: a duration (and the dwell) rounded up to a whole number of cycles, the limit check run
again on the rounded duration.

A drive or PLC runs its interpolator every ``cycle`` seconds (1 ms, 0.5 ms, 4 ms …). A move of T seconds that is
not a whole number of cycles ends between two cycles: its last step is short (0.956 ms) and every time stamp after
it (the second leg of a round trip) is off the grid. :func:`align_to_cycle` rounds T up to n = ⌈T / cycle⌉ cycles and
the dwell up to m = ⌈dwell / cycle⌉ cycles, and runs the plan's limit check again at n·cycle with the dwell m·cycle.

Slower is not automatically safe: the peaks of velocity, acceleration, jerk and torque rate fall as T grows, but the
RMS motor torque over the duty cycle (move, dwell, back, dwell) need not: with gravity, the holding torque of the
longer dwell and the slower move can raise it. When the rounded duration breaks a limit that held at T, the next
cycle is tried, up to :data:`MAX_EXTRA_CYCLES` more; :class:`CycleRounding` records how many were added and why. When
none holds, the rounded plan's report says which limit is exceeded (exit 3), as for any duration.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable

from ..model.errors import TaskError

#: a duration within this fraction of a cycle of a whole number of cycles is taken as that number (T computed as
#: n·cycle by another step, 0.1 + 0.2 …): rounding it up would add a cycle for a floating-point crumb
WHOLE_TOLERANCE = 1e-9
#: how many cycles beyond ⌈T / cycle⌉ are tried when the rounded duration breaks a limit that held at T
MAX_EXTRA_CYCLES = 20
#: the shortest cycle accepted [s] (as the shortest duration: no drive interpolates faster)
MIN_CYCLE = 1e-6
#: the longest cycle accepted [s] (a PLC task of more than a second does not interpolate a move)
MAX_CYCLE = 1.0


def check_cycle(cycle: Any, field: str = "cycle") -> float:
    """``cycle`` [s] as a float; TaskError naming ``field`` unless it is finite and in [MIN_CYCLE, MAX_CYCLE]."""
    try:
        value = float(cycle)
    except (TypeError, ValueError):
        raise TaskError(f"{field} = {cycle!r}: must be a number of seconds (e.g. 0.001 for a 1 ms cycle)") from None
    if not (math.isfinite(value) and value > 0):
        raise TaskError(f"{field} = {cycle!r}: the controller cycle must be a finite number of seconds > 0 "
                        "(e.g. 0.001 for 1 ms)")
    if not MIN_CYCLE <= value <= MAX_CYCLE:
        raise TaskError(f"{field} = {cycle!r}: the controller cycle must lie in [{MIN_CYCLE:g}, {MAX_CYCLE:g}] s "
                        "(is it in ms? give seconds: 1 ms = 0.001)")
    return value


def whole_cycles(seconds: float, cycle: float) -> int:
    """The fewest whole cycles that last at least ``seconds`` (0 for 0 s; within :data:`WHOLE_TOLERANCE` of a cycle
    a duration counts as that many cycles)."""
    if seconds <= 0:
        return 0
    return max(int(math.ceil(seconds / cycle - WHOLE_TOLERANCE)), 1)


@dataclass(frozen=True)
class CycleRounding:
    """What rounding to the controller's cycle did to one move: the duration before (``requested_s``) and after
    (``cycles`` · ``cycle``), the dwell likewise, and the cycles added because the rounded duration broke a limit
    that held before (``extra_cycles``, with ``note``)."""

    cycle: float  # s
    requested_s: float  # T before rounding [s]
    cycles: int  # T = cycles · cycle
    dwell_requested_s: float  # the profile's dwell [s]
    dwell_cycles: int  # dwell = dwell_cycles · cycle
    extra_cycles: int = 0
    note: str = ""

    @property
    def seconds(self) -> float:
        """The rounded duration [s] (a whole number of cycles)."""
        return self.cycles * self.cycle

    @property
    def dwell_s(self) -> float:
        """The rounded dwell [s]."""
        return self.dwell_cycles * self.cycle

    @property
    def cost_s(self) -> float:
        """How much longer the move is [s]."""
        return self.seconds - self.requested_s

    @property
    def dwell_cost_s(self) -> float:
        """How much longer each dwell is [s]."""
        return self.dwell_s - self.dwell_requested_s

    def as_dict(self) -> dict[str, Any]:
        return {
            "cycle_s": self.cycle,
            "requested_duration_s": self.requested_s,
            "duration_s": self.seconds,
            "cycles": self.cycles,
            "rounding_cost_s": self.cost_s,
            "requested_dwell_s": self.dwell_requested_s,
            "dwell_s": self.dwell_s,
            "dwell_cycles": self.dwell_cycles,
            "dwell_rounding_cost_s": self.dwell_cost_s,
            "extra_cycles_for_limits": self.extra_cycles,
            "note": self.note,
        }

    def text(self) -> str:
        """One line for people: the cycle, T and the dwell before → after, and what it cost."""
        ms = 1e3
        extra = f"; {self.note}" if self.note else ""
        return (f"controller cycle {self.cycle * ms:g} ms: T {self.requested_s:.6g} s → {self.seconds:.6g} s "
                f"({self.cycles} cycles, +{self.cost_s * ms:.4g} ms); dwell {self.dwell_requested_s:g} s → "
                f"{self.dwell_s:.6g} s ({self.dwell_cycles} cycles, +{self.dwell_cost_s * ms:.4g} ms){extra}")


def align_to_cycle(T: float, dwell: float, cycle: float, check: Callable[[float, float], tuple[Any, Any]],
                   held: bool) -> tuple[CycleRounding, Any, Any]:
    """Round ``T`` [s] and ``dwell`` [s] up to whole cycles of ``cycle`` [s] and check the rounded move:
    ``check(T_rounded, dwell_rounded)`` → (samples, LimitReport). ``held``: every limit held at ``T``; then a rounded
    duration that breaks one is lengthened a cycle at a time (at most :data:`MAX_EXTRA_CYCLES`) until all hold again.
    → (rounding, samples, report) of the duration kept."""
    n = whole_cycles(T, cycle)
    m = whole_cycles(dwell, cycle)
    dwell_c = m * cycle
    samples, report = check(n * cycle, dwell_c)
    if report.ok or not held:
        return CycleRounding(cycle, T, n, dwell, m), samples, report
    broken = ", ".join(f"{r.joint} {r.quantity}" for r in report.violations)
    for extra in range(1, MAX_EXTRA_CYCLES + 1):
        s2, r2 = check((n + extra) * cycle, dwell_c)
        if r2.ok:
            note = (f"{n} cycles broke {broken} (held at T = {T:.6g} s): {extra} more cycle{'s' if extra > 1 else ''} "
                    "added until every limit holds")
            return CycleRounding(cycle, T, n + extra, dwell, m, extra, note), s2, r2
    note = (f"{n} cycles break {broken} (held at T = {T:.6g} s), and so do up to {MAX_EXTRA_CYCLES} more: the move "
            "does not fit this cycle's grid (a shorter cycle, or another duration)")
    return CycleRounding(cycle, T, n, dwell, m, 0, note), samples, report


def cycle_times(n: int, cycle: float) -> "Any":
    """The time stamps of a move of ``n`` cycles: k · cycle for k = 0 … n [s] (each one product, so every stamp is
    the same double wherever it is computed)."""
    import numpy as np

    return np.arange(n + 1) * cycle
