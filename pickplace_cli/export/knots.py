"""Compact tables a motion kernel interpolates itself: the fewest points for a position tolerance.

* **PVT** (position, velocity, time): cubic Hermite between points, as drives in PVT mode run them (CiA 402
  interpolated position mode, sub-mode −2; Copley, Elmo, Kollmorgen AKD): on [t0, t1] with h = t1 − t0 and
  s = (t − t0)/h, p(t) = h00(s)·p0 + h10(s)·h·v0 + h01(s)·p1 + h11(s)·h·v1.
* **cam** (PLCopen ``MC_CamIn`` points with position, velocity and acceleration: CODESYS SoftMotion's XYVA cam
  segments, TwinCAT's motion function points of type ``POLYNOM5_MM``): the quintic through (p, v, a) at both ends
  of each segment.
* **cam-table**: equidistant positions, interpolated linearly between them (the error bound assumes linear
  interpolation; a kernel that interpolates the table with a spline does better).

The points of PVT and cam tables are chosen from ``grid`` (the output samples: every controller cycle when one is
set, so a drive that takes segment times in whole cycles or milliseconds gets them), greedily: from each point the
farthest point whose segment holds the tolerance (doubling, then bisection), never across a ``break`` (the end of
a move, of a dwell: they are always points). A segment holds when its interpolation stays within
``SAFETY`` · tolerance of the trajectory on ``FINE`` points per grid step; the achieved maximum is then measured on a
grid four times finer still and reported.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..model.errors import TaskError

#: evaluation points per grid step when a segment is tested
FINE = 8
#: a segment is accepted when its error is at most this fraction of the tolerance (the check is on points)
SAFETY = 0.98
#: the most points an equidistant table may have
MAX_TABLE_POINTS = 200_000

#: (t (N,)) → (q, qd, qdd), each (N, n_joints) [rad or m, per s, per s²]: the continuous trajectory
Evaluator = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]]


def hermite3(t0, t1, p0, v0, p1, v1, t):
    """Cubic Hermite between (t0, p0, v0) and (t1, p1, v1) at ``t`` (M,): (M, n). p, v are (n,)."""
    h = t1 - t0
    s = ((np.asarray(t, float) - t0) / h)[:, None]
    s2, s3 = s * s, s * s * s
    return ((2 * s3 - 3 * s2 + 1) * p0 + (s3 - 2 * s2 + s) * h * v0 + (-2 * s3 + 3 * s2) * p1 + (s3 - s2) * h * v1)


def quintic(t0, t1, p0, v0, a0, p1, v1, a1, t):
    """The quintic with position, velocity and acceleration (p, v, a) at both ends of [t0, t1], at ``t`` (M,)."""
    h = t1 - t0
    s = ((np.asarray(t, float) - t0) / h)[:, None]
    dp = p1 - p0 - v0 * h - a0 * h * h / 2
    dv = (v1 - v0 - a0 * h) * h
    da = (a1 - a0) * h * h
    c3 = 10 * dp - 4 * dv + da / 2
    c4 = -15 * dp + 7 * dv - da
    c5 = 6 * dp - 3 * dv + da / 2
    return p0 + s * (v0 * h + s * (a0 * h * h / 2 + s * (c3 + s * (c4 + s * c5))))


@dataclass(frozen=True)
class KnotTable:
    """The points of a table: ``t`` (K,) [s], ``q``, ``qd``, ``qdd`` (K, n) of the model's joints [rad or m, /s, /s²]
    (``qdd`` None for PVT and equidistant tables), the interpolation (``kind``: pvt, cam, cam-table), the tolerance
    and the achieved largest error per joint [rad or m], and how many samples the trajectory has on its grid."""

    kind: str
    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray | None
    tolerance: float
    max_error: np.ndarray
    samples: int

    def as_dict(self) -> dict:
        return {"kind": self.kind, "points": int(len(self.t)), "samples": self.samples,
                "tolerance": self.tolerance, "max_error": [float(e) for e in self.max_error],
                "samples_per_point": self.samples / len(self.t)}


def check_tolerance(tolerance: float) -> float:
    """``tolerance`` [rad or m] as a float; TaskError unless finite and > 0."""
    tol = float(tolerance)
    if not (np.isfinite(tol) and tol > 0):
        raise TaskError(f"tolerance = {tolerance!r}: must be a finite deviation > 0 in rad (revolute) or m (linear)")
    return tol


def _fine(grid: np.ndarray, per_step: int) -> np.ndarray:
    """``grid`` with ``per_step`` − 1 points inserted in every step (the grid points are every per_step-th)."""
    u = np.arange(per_step) / per_step
    inner = (grid[:-1, None] + np.diff(grid)[:, None] * u).ravel()
    return np.append(inner, grid[-1])


def _segment_error(kind: str, ft: np.ndarray, fq: np.ndarray, fqd: np.ndarray, fqdd: np.ndarray, a: int, b: int,
                   per_step: int) -> np.ndarray:
    """Largest |interpolation − trajectory| per joint on the fine points of grid segment [a, b]."""
    i, j = a * per_step, b * per_step
    t = ft[i:j + 1]
    if kind == "pvt":
        approx = hermite3(ft[i], ft[j], fq[i], fqd[i], fq[j], fqd[j], t)
    else:
        approx = quintic(ft[i], ft[j], fq[i], fqd[i], fqdd[i], fq[j], fqd[j], fqdd[j], t)
    return np.max(np.abs(approx - fq[i:j + 1]), axis=0)


def fit_knots(kind: str, grid: np.ndarray, breaks: np.ndarray, evaluate: Evaluator, tolerance: float) -> KnotTable:
    """The fewest points of ``grid`` [s] (increasing; ``breaks``: indices that must be points, the ends included)
    whose ``kind`` interpolation (pvt: cubic Hermite; cam: quintic with accelerations) stays within ``tolerance``
    [rad or m] of ``evaluate``. TaskError when even one grid step breaks the tolerance."""
    tol = check_tolerance(tolerance)
    grid = np.asarray(grid, float)
    ft = _fine(grid, FINE)
    fq, fqd, fqdd = evaluate(ft)
    limit = SAFETY * tol
    must = sorted(set(int(b) for b in breaks) | {0, len(grid) - 1})
    knots = [0]

    def ok(a: int, b: int) -> bool:
        return bool(np.all(_segment_error(kind, ft, fq, fqd, fqdd, a, b, FINE) <= limit))

    for lo, hi in zip(must[:-1], must[1:]):
        a = lo
        while a < hi:
            if not ok(a, a + 1):
                err = _segment_error(kind, ft, fq, fqd, fqdd, a, a + 1, FINE).max()
                raise TaskError(
                    f"tolerance = {tol:g} (rad or m): too small for the data: the {kind} interpolation misses the "
                    f"trajectory by {err:.3g} between two samples {grid[a + 1] - grid[a]:.6g} s apart (t = "
                    f"{grid[a]:.6g} s); give a larger tolerance (or a shorter cycle)")
            good, step = a + 1, 2
            bad = None
            while good < hi:  # doubling
                b = min(a + step, hi)
                if ok(a, b):
                    good = b
                    step *= 2
                else:
                    bad = b
                    break
            while bad is not None and bad - good > 1:  # bisection
                mid = (good + bad) // 2
                if ok(a, mid):
                    good = mid
                else:
                    bad = mid
            knots.append(good)
            a = good
    return knot_table(kind, grid, np.array(knots), evaluate, tol)


def knot_table(kind: str, grid: np.ndarray, idx: np.ndarray, evaluate: Evaluator, tolerance: float) -> KnotTable:
    """The ``kind`` (pvt, cam) table whose points are ``grid[idx]`` [s] (``idx`` increasing, the ends included),
    with the trajectory's values there and the achieved error (:func:`achieved_error`)."""
    grid = np.asarray(grid, float)
    idx = np.asarray(idx, int)
    t = grid[idx]
    q, qd, qdd = evaluate(t)
    acc = qdd if kind == "cam" else None
    error = achieved_error(kind, t, q, qd, acc, evaluate)
    return KnotTable(kind, t, q, qd, acc, float(tolerance), error, len(grid))


def achieved_error(kind: str, t: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray | None,
                   evaluate: Evaluator, per_step: int = 4 * FINE) -> np.ndarray:
    """Largest |interpolation − trajectory| per joint over the whole table, on ``per_step`` points per segment (one
    evaluation of the trajectory for all segments)."""
    t = np.asarray(t, float)
    u = np.arange(per_step + 1) / per_step
    h = np.diff(t)
    s = (t[:-1, None] + h[:, None] * u).ravel()  # (segments · (per_step + 1),)
    true = evaluate(s)[0]
    k = np.repeat(np.arange(len(h)), per_step + 1)
    x = np.tile(u, len(h))[:, None]
    hk = h[k][:, None]
    p0, p1 = q[k], q[k + 1]
    if kind == "pvt":
        x2, x3 = x * x, x * x * x
        approx = ((2 * x3 - 3 * x2 + 1) * p0 + (x3 - 2 * x2 + x) * hk * qd[k] + (-2 * x3 + 3 * x2) * p1
                  + (x3 - x2) * hk * qd[k + 1])
    elif kind == "cam":
        v0, v1, a0, a1 = qd[k], qd[k + 1], qdd[k], qdd[k + 1]
        dp = p1 - p0 - v0 * hk - a0 * hk * hk / 2
        dv = (v1 - v0 - a0 * hk) * hk
        da = (a1 - a0) * hk * hk
        c3, c4, c5 = 10 * dp - 4 * dv + da / 2, -15 * dp + 7 * dv - da, 6 * dp - 3 * dv + da / 2
        approx = p0 + x * (v0 * hk + x * (a0 * hk * hk / 2 + x * (c3 + x * (c4 + x * c5))))
    else:
        approx = p0 + (p1 - p0) * x
    return np.max(np.abs(approx - true), axis=0)


def _linear_error(duration: float, n: int, evaluate: Evaluator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(node times, node positions, largest error per joint) of ``n`` equidistant nodes on [0, duration]."""
    t = np.linspace(0.0, duration, n)
    ft = _fine(t, FINE)
    fq = evaluate(ft)[0]
    nodes = fq[::FINE]
    approx = np.repeat(nodes[:-1], FINE, axis=0) + np.repeat(np.diff(nodes, axis=0), FINE, axis=0) * \
        np.tile(np.arange(FINE) / FINE, n - 1)[:, None]
    approx = np.vstack([approx, nodes[-1:]])
    return t, nodes, np.max(np.abs(approx - fq), axis=0)


def fit_equidistant(duration: float, evaluate: Evaluator, tolerance: float, samples: int) -> KnotTable:
    """The fewest equidistant nodes on [0, ``duration``] [s] whose linear interpolation stays within ``tolerance``
    (doubling, then bisection on the count); TaskError beyond :data:`MAX_TABLE_POINTS`."""
    tol = check_tolerance(tolerance)
    limit = SAFETY * tol
    good, bad = None, 1
    n = 2
    while True:
        if np.all(_linear_error(duration, n, evaluate)[2] <= limit):
            good = n
            break
        bad = n
        if n >= MAX_TABLE_POINTS:
            raise TaskError(f"tolerance = {tol:g} (rad or m): too small for an equidistant table: {MAX_TABLE_POINTS:,} "
                            "points interpolated linearly do not hold it; give a larger tolerance or use --format cam")
        n = min(2 * n, MAX_TABLE_POINTS)
    while good - bad > 1:
        mid = (good + bad) // 2
        if np.all(_linear_error(duration, mid, evaluate)[2] <= limit):
            good = mid
        else:
            bad = mid
    return equidistant_table(duration, good, evaluate, tol, samples)


def equidistant_table(duration: float, n: int, evaluate: Evaluator, tolerance: float, samples: int) -> KnotTable:
    """The cam-table of ``n`` equidistant points on [0, ``duration``] [s] with the achieved error."""
    t = np.linspace(0.0, duration, int(n))
    nodes = evaluate(t)[0]
    zero = np.zeros_like(nodes)
    error = achieved_error("cam-table", t, nodes, zero, None, evaluate)
    return KnotTable("cam-table", t, nodes, zero, None, float(tolerance), error, samples)
