"""Vertical and horizontal 3-4-5 laws overlapped in time [Su2018, Sec. III] (the paper's comparison method).

In the vertical plane of the move (local u along the move, v up, origin at the pick point) the tool
rises by h with a 3-4-5 law over T1, moves across by w with a 3-4-5 law over T2, and descends by h over
T3 = T1. Each axis runs at the paper's per-axis acceleration limit, so its duration is
T_i = sqrt(10 d_i/(√3 a_max)) ∝ √d_i (the 3-4-5 law's acceleration peak is 10/√3·d/T²). The paper's
two cases:

* h ≤ w: the horizontal motion starts at T1/2, the descent at T2; T = T2 + T3 (Eq. 26);
* h > w: the horizontal motion starts at T1 − T2/2, the descent at T1; T = T1 + T3 (Eq. 27).

Both are one rule: the horizontal motion starts min(T1, T2)/2 before the rise ends, and the descent
starts min(T2, T3)/2 before the horizontal motion ends. We use that rule, which also covers unequal pick
and place heights (rise h1, descent h2; not in the paper) and reduces to Eq. (26)–(27) when h1 = h2.

Interface
---------
* :func:`plan_superposition` (``--method superposition``) → CartesianPath on τ = t/T with the paper's
  schedule. Every axis is a polynomial piece in τ, so ``path.peaks`` are exact: the true norms of v, a,
  j, which can exceed the per-axis limit (up to √2·[a] where the two axes' peaks coincide), so
  ``--time auto`` (true peaks) may be longer than the paper's time.
* :func:`cycle_time` / :func:`cycle_time_eq26` / :func:`cycle_time_eq27`: the paper's formulas (s) for
  h, w and a per-axis a_max; :func:`paper_duration` for a task and capacity (only [a] enters, as in the
  paper). ``parameters["paper_time_factor"]`` = T·sqrt(a_max), so T_paper = factor/sqrt([a]).
* Continuity: the 3-4-5 law starts and ends with a jerk of 60·d/T³ on each axis, so the jerk jumps at
  every start and end of an axis motion (``parameters["jerk_jumps_at"]``); acceleration is continuous.
"""

from __future__ import annotations

import math

import numpy as np

from ..curves.laws import POLY345
from ..model.task import Task
from ..model.trajectory import CartesianPath
from ._motion import AxisLaws, Placement, local_endpoints, to_cartesian

#: T_i = K·sqrt(d_i / a_max) with K = sqrt(10/√3) for a 3-4-5 law at its acceleration limit
_K = math.sqrt(10.0 / math.sqrt(3.0))


def _out(x):
    x = np.asarray(x, float)
    return float(x) if x.ndim == 0 else x


def axis_time(distance, a_max):
    """Duration (s) of a 3-4-5 move over ``distance`` (m) whose acceleration peak is a_max (m/s²)."""
    return _out(_K * np.sqrt(np.asarray(distance, float) / a_max))


def cycle_time_eq26(h, w, a_max):
    """T = sqrt(10w/(√3 a_max)) + sqrt(10h/(√3 a_max)) for h ≤ w [Su2018, Eq. (26)] (s); vectorised."""
    return _out(np.asarray(axis_time(w, a_max)) + axis_time(h, a_max))


def cycle_time_eq27(h, w, a_max):
    """T = 2·sqrt(10h/(√3 a_max)) for h > w [Su2018, Eq. (27)] (s); vectorised."""
    return _out(2.0 * np.asarray(axis_time(h, a_max)))


def cycle_time(h, w, a_max):
    """The paper's cycle time of the superposition method: Eq. (26) if h ≤ w, else Eq. (27) (s); vectorised."""
    h, w = np.asarray(h, float), np.asarray(w, float)
    return _out(np.where(h <= w, cycle_time_eq26(h, w, a_max), cycle_time_eq27(h, w, a_max)))


def schedule(h1: float, w: float, h2: float, a_max: float = 1.0) -> dict[str, float]:
    """Start times and durations (s) of the rise, the horizontal move and the descent, and the total T."""
    t1, t2, t3 = (_K * math.sqrt(d / a_max) for d in (h1, w, h2))
    start_u = t1 - min(t1, t2) / 2.0
    start_down = start_u + t2 - min(t2, t3) / 2.0
    return {"T1": t1, "T2": t2, "T3": t3, "start_u": start_u, "start_down": start_down, "T": start_down + t3}


def _axis_laws(task: Task) -> tuple[AxisLaws, dict[str, float]]:
    b, h1, h2 = local_endpoints(task)
    s = schedule(h1, b, h2)
    T = s["T"]
    laws = AxisLaws(
        u=[Placement(b, POLY345, s["start_u"] / T, s["T2"] / T)],
        v=[Placement(h1, POLY345, 0.0, s["T1"] / T), Placement(-h2, POLY345, s["start_down"] / T, s["T3"] / T)],
    )
    return laws, s


def plan_superposition(task: Task) -> CartesianPath:
    """CartesianPath of the superposition method (``--method superposition``); no parameters."""
    laws, s = _axis_laws(task)
    T = s["T"]
    bp = laws.breakpoints()
    params = {
        "law": POLY345.name,
        "rise_s": [0.0, s["T1"] / T],  # normalised start, duration
        "horizontal_s": [s["start_u"] / T, s["T2"] / T],
        "descent_s": [s["start_down"] / T, s["T3"] / T],
        "paper_time_factor": T,  # T_paper = this / sqrt([a]) (s·sqrt(m/s²))
        "continuity": 2,  # acceleration continuous; the jerk jumps where an axis starts or stops
        "jerk_jumps_at": [float(t) for t in bp],
    }
    return to_cartesian(task, laws, "superposition", params, laws.exact_peaks(), bp)


def paper_duration(task: Task, capacity) -> float:
    """The paper's cycle time [Su2018, Eq. (26)–(27)] for this task and the capacity's [a] (s).

    Per-axis acceleration limit only, as in the paper; for unequal end heights the same schedule rule.
    """
    _, h1, h2 = local_endpoints(task)
    return schedule(h1, task.b, h2, capacity.acceleration)["T"]
