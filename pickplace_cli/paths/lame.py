"""Lamé-curve baseline of [Li2018, Sec. 3.2] (after Gauthier et al., Li 2018 ref. [10]).

The path is the upper half of the Lamé curve |2u/b − 1|^m + |v/h|^m = 1 in the vertical plane of the move
(local u along the move, v up, origin at the pick point P1): two symmetric quarter curves P1 → P3 → P5,
vertical at P1 and P5 and horizontal at the top P3 = (b/2, h). One 4-5-6-7 law runs on the arc length of
the whole path. With m = 3 (the default) this reproduces Li 2018 Table 1 (a_max = 7.8, j_max = 242.1 at
λ = 28, b = 1, T = 1; ``tests/papers/test_li2018_baselines.py``).

Interface
---------
* :func:`plan_lame` (``--method lame``) → CartesianPath; parameter ``m`` (Lamé exponent, ≥ 3, default 3).
  η is not used (the curve has no lift-off point).
* ``path.peaks`` are the true maxima of ‖v‖, ‖a‖, ‖j‖ (dense samples refined by golden section).
* :func:`paper_duration`: Li 2018's cycle time, Eq. (26), T = max(v_max b/[v], sqrt(a_max b/[a])) (s) with
  the exact normalised peaks (the paper's Sec. 4 values follow from its peaks rounded to one decimal).

How it is computed
------------------
The arc length has no closed form. Each quarter is split at the point where |X| = |Y| (X = 2u/b − 1,
Y = v/h) into two graphs, u(v) near the end and v(u) near the top, both smooth, with closed-form
derivatives up to the third; the arc length of each graph is a table of 16-point Gauss–Legendre
integrals, and is inverted by Newton with a bisection safeguard.

Continuity: for m = 3 the curvature is zero at the top but changes slope there (v ≈ h(1 − |X|³/3)), so
dκ/ds jumps and the normal jerk jumps at P3 (τ = 1/2 for a symmetric move); for m > 3 the jerk is
continuous. For m < 3 dκ/ds is unbounded at the ends, so m ≥ 3 is required.
"""

from __future__ import annotations

import math

import numpy as np

from ..model.errors import TaskError
from ..curves.laws import POLY4567
from ..model.task import Task
from ..model.trajectory import CartesianPath
from ._motion import ArcLengthPath, ParametricPiece, Placed, li_eq26, local_endpoints, sampled_peaks, to_cartesian

#: Gauss–Legendre nodes/weights on [-1, 1] for the arc-length integrals, and subintervals per graph
_GL_X, _GL_W = np.polynomial.legendre.leggauss(16)
_SUBINTERVALS = 64


def _superellipse(y: np.ndarray, m: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """F(y) = (1 − y^m)^(1/m) and F′, F″, F‴ for 0 ≤ y < 1 (closed form)."""
    ym = y**m
    q = 1.0 - ym
    F = q ** (1.0 / m)
    F1 = -(y ** (m - 1)) * q ** (1.0 / m - 1.0)
    F2 = (1.0 - m) * y ** (m - 2) * q ** (1.0 / m - 2.0)
    F3 = (1.0 - m) * y ** (m - 3) * q ** (1.0 / m - 3.0) * ((m - 2.0) + (m + 1.0) * ym)
    return F, F1, F2, F3


class _LameGraph(ParametricPiece):
    """One graph of a quarter Lamé curve with semi-axes (a, h) = (b/2, h), origin at the end point.

    ``kind`` "rise": parameter g = v ∈ [0, v*], u = a(1 − F(v/h)); "top": g = u ∈ [u*, a], v = h·F(1 − u/a).
    """

    def __init__(self, kind: str, a: float, h: float, m: float) -> None:
        self.kind, self.a, self.h, self.m = kind, a, h, m
        split = 2.0 ** (-1.0 / m)  # |X| = |Y| = 2^(-1/m)
        if kind == "rise":
            self.g0, self.g1 = 0.0, h * split
        else:
            self.g0, self.g1 = a * (1.0 - split), a
        nodes = np.linspace(self.g0, self.g1, _SUBINTERVALS + 1)
        seg = self._gl(nodes[:-1], nodes[1:])
        self._nodes = nodes
        self._cum = np.concatenate([[0.0], np.cumsum(seg)])
        self.length = float(self._cum[-1])
        self._build_table(129)

    def curve(self, g: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        g = np.asarray(g, float)
        one, zero = np.ones_like(g), np.zeros_like(g)
        a, h, m = self.a, self.h, self.m
        if self.kind == "rise":
            F, F1, F2, F3 = _superellipse(g / h, m)
            return (
                np.column_stack([a * (1.0 - F), g]),
                np.column_stack([-a / h * F1, one]),
                np.column_stack([-a / h**2 * F2, zero]),
                np.column_stack([-a / h**3 * F3, zero]),
            )
        F, F1, F2, F3 = _superellipse(np.maximum(1.0 - g / a, 0.0), m)
        return (
            np.column_stack([g, h * F]),
            np.column_stack([one, -h / a * F1]),
            np.column_stack([zero, h / a**2 * F2]),
            np.column_stack([zero, -h / a**3 * F3]),
        )

    def speed(self, g: np.ndarray) -> np.ndarray:
        """‖P′(g)‖ = sqrt(1 + (c·F′)²), c = a/h (rise) or h/a (top); F′ = −y^(m−1)(1 − y^m)^(1/m − 1)."""
        m = self.m
        if self.kind == "rise":
            y, c = np.asarray(g, float) / self.h, self.a / self.h
        else:
            y, c = np.maximum(1.0 - np.asarray(g, float) / self.a, 0.0), self.h / self.a
        ym1 = y ** (m - 1.0)
        f1 = c * ym1 * (1.0 - ym1 * y) ** (1.0 / m - 1.0)
        return np.sqrt(1.0 + f1 * f1)

    def _gl(self, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        half = 0.5 * (hi - lo)
        x = (0.5 * (lo + hi))[:, None] + half[:, None] * _GL_X[None, :]
        return half * (self.speed(x.ravel()).reshape(x.shape) @ _GL_W)

    def arclength(self, g: np.ndarray) -> np.ndarray:
        g = np.clip(np.asarray(g, float), self.g0, self.g1)
        k = np.clip(np.searchsorted(self._nodes, g, side="right") - 1, 0, _SUBINTERVALS - 1)
        return self._cum[k] + self._gl(self._nodes[k], g)


def lame_path(task: Task, m: float = 3.0) -> ArcLengthPath:
    """The local ArcLengthPath P1 → P3 → P5 (two quarter Lamé curves, 4-5-6-7 law on the arc length)."""
    if not (isinstance(m, (int, float)) and math.isfinite(m) and m >= 3.0):
        raise TaskError(f"m = {m!r}: the Lamé exponent must be ≥ 3 (for m < 3 dκ/ds is unbounded at the ends)")
    b, h1, h2 = local_endpoints(task)
    if b <= 0:
        raise TaskError("from/to are vertically aligned (b = 0): the Lamé curve needs a horizontal move (method lame)")
    a = b / 2.0
    mirror = np.diag([-1.0, 1.0])
    end = np.array([b, h1 - h2])
    q2 = (_LameGraph("rise", a, h2, m), _LameGraph("top", a, h2, m))
    pieces = [
        Placed(_LameGraph("rise", a, h1, m)),
        Placed(_LameGraph("top", a, h1, m)),
        Placed(q2[1], M=mirror, c=end, reverse=True),
        Placed(q2[0], M=mirror, c=end, reverse=True),
    ]
    return ArcLengthPath(pieces, POLY4567)


def plan_lame(task: Task, m: float = 3.0) -> CartesianPath:
    """CartesianPath of the Lamé baseline (``--method lame``); ``m`` is the Lamé exponent (≥ 3, default 3)."""
    arc = lame_path(task, float(m))
    joints = arc.joints_tau()
    peaks = sampled_peaks(arc.derivatives, joints)
    top = float(joints[2])  # the join of the two quarters, P3
    params = {
        "m": float(m),
        "law": POLY4567.name,
        "length_m": arc.length,
        "continuity": 2 if m == 3.0 else 3,
        "jerk_jumps_at": [top] if m == 3.0 else [],
    }
    return to_cartesian(task, arc, "lame", params, peaks, joints)


def paper_duration(task: Task, capacity, m: float = 3.0) -> float:
    """Li 2018's cycle time [Li2018, Eq. (26)] T = max(v̂/[v], sqrt(â/[a])) with the exact peaks (s)."""
    return li_eq26(plan_lame(task, m), capacity)
