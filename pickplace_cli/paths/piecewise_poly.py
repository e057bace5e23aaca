"""Piecewise 4-5-6-7 polynomial baseline of [Li2018, Sec. 3.2] (after Li 2018 ref. [4]).

Each axis of the vertical plane of the move (local u along the move, v up, origin at the pick point P1)
gets its own 4-5-6-7 laws in normalised time τ = t/T. With τ_v the time from P1 to the lift-off point P2
and τ_u the time from P2 to the top P3, τ_v/τ_u = ``ratio`` (Li 2018: 0.35) and τ_v + τ_u = 1/2:

* u rises 0 → b with one 4-5-6-7 law over [τ_v, 1 − τ_v];
* v rises 0 → h over [0, 2τ_v], dwells at h, and falls h → 0 over [1 − 2τ_v, 1].

At τ_v the rise is half done, so the path passes P2 = (0, h/2) exactly when u starts: that is P2 for
η = 0.5 (the paper's case); η is not used otherwise. With unequal end heights (not in the paper) the
rise and the fall cover each end's own height.

Interface
---------
* :func:`plan_piecewise_poly` (``--method piecewise-poly``) → CartesianPath; parameter ``ratio`` = τ_v/τ_u,
  0 < ratio ≤ 1 (ratio ≤ 1 keeps the rise finished before the fall starts). Every piece is a polynomial
  in τ, so ``path.peaks`` are exact. Li 2018 Table 1 at λ = 28: a_max = 13.7, j_max = 132.5 (b = 1, T = 1).
* :func:`paper_duration`: Li 2018 Eq. (26), T = max(v̂/[v], sqrt(â/[a])) (s).
* Continuity: every law starts and ends with zero velocity, acceleration and jerk, so the motion is C³
  (jerk continuous) everywhere, ends included.
"""

from __future__ import annotations

import math

from ..model.errors import TaskError
from ..curves.laws import POLY4567
from ..model.task import Task
from ..model.trajectory import CartesianPath
from ._motion import AxisLaws, Placement, li_eq26, local_endpoints, to_cartesian

#: τ_v/τ_u of Li 2018 Sec. 3.2 ("optimized")
LI2018_RATIO = 0.35


def lift_time(ratio: float) -> float:
    """τ_v = ratio/(1 + ratio)/2 from τ_v/τ_u = ratio and τ_v + τ_u = 1/2."""
    return 0.5 * ratio / (1.0 + ratio)


def axis_laws(task: Task, ratio: float = LI2018_RATIO) -> AxisLaws:
    """The 4-5-6-7 laws on u and v (local, m) of the piecewise baseline."""
    if not (isinstance(ratio, (int, float)) and math.isfinite(ratio) and 0 < ratio <= 1):
        raise TaskError(f"ratio = {ratio!r}: τv/τu must satisfy 0 < ratio ≤ 1 (the rise must end before the fall starts)")
    b, h1, h2 = local_endpoints(task)
    tv = lift_time(float(ratio))
    return AxisLaws(
        u=[Placement(b, POLY4567, tv, 1.0 - 2.0 * tv)],
        v=[Placement(h1, POLY4567, 0.0, 2.0 * tv), Placement(-h2, POLY4567, 1.0 - 2.0 * tv, 2.0 * tv)],
    )


def plan_piecewise_poly(task: Task, ratio: float = LI2018_RATIO) -> CartesianPath:
    """CartesianPath of the piecewise-poly baseline (``--method piecewise-poly``); ``ratio`` = τv/τu."""
    laws = axis_laws(task, ratio)
    bp = laws.breakpoints()
    tv = lift_time(float(ratio))
    params = {"ratio": float(ratio), "tau_v": tv, "tau_u": 0.5 - tv, "law": POLY4567.name, "continuity": 3, "jerk_jumps_at": []}
    return to_cartesian(task, laws, "piecewise-poly", params, laws.exact_peaks(), bp)


def paper_duration(task: Task, capacity, ratio: float = LI2018_RATIO) -> float:
    """Li 2018's cycle time [Li2018, Eq. (26)] T = max(v̂/[v], sqrt(â/[a])) with the exact peaks (s)."""
    return li_eq26(plan_piecewise_poly(task, ratio), capacity)
