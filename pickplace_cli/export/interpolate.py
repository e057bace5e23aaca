"""A table as the drive rebuilds it: the joint motion f(t, order) a kernel runs from a
:class:`~pickplace_cli.export.knots.KnotTable`, with the interpolation its format names (:func:`rebuild`).

* **pvt**: the cubic Hermite through (p, v) at both ends of each segment (CiA 402 interpolated position mode,
  sub-mode −2); its acceleration steps at every point.
* **cam**: the quintic through (p, v, a) at both ends of each segment (PLCopen XYVA cam points, TwinCAT
  ``POLYNOM5_MM``); acceleration continuous, jerk steps at the points.
* **cam-table**: straight lines between equidistant positions, which a kernel reads once per controller cycle
  (``blend`` [s]): its setpoints are the lines' positions at every cycle from the first point (the last point held
  beyond the end), and the velocity steps at every setpoint within its cycle: here a parabolic blend one cycle long
  centred on the setpoint (at the first and last from and to rest), so the motion starts half a cycle before the
  first point and ends half a cycle after the last.

Before its first point and after its last a drive holds the table's end position (``ends="hold"``). A pvt or cam
table that starts or ends moving (a conveyor move ends at the belt's speed; a table cut short) therefore has a
velocity step there, which the drive takes within one controller cycle (``blend`` [s], when given): modelled as a
parabolic blend one cycle long from rest up to the first point and from the last point down to rest, outside the
table (its own motion unchanged). With ``ends="continue"`` the controller goes on at the end's velocity instead (a
drive geared to the belt after a conveyor move): no blend there, and a cam-table's lines go on at their first and last
slopes before and after it.

The motion is piecewise polynomial: ``breaks`` (P + 1,) [s] and power-basis coefficients in (t − breaks[k]); it is
right-continuous at a break (``side="left"`` evaluates the piece that ends there), and holds its end values
(zero derivatives) outside [start, end]. This is the function ``check`` and ``plan`` judge a table by.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: the highest derivative :meth:`TableMotion.__call__` gives (jerk)
MAX_ORDER = 3


@dataclass(frozen=True)
class TableMotion:
    """Joint motion of a rebuilt table: ``kind``, ``breaks`` (P + 1,) [s] and ``coef`` (P, 6, n) [rad or m per
    s^k] (power basis in t − breaks[k], degree ≤ 5); ``points`` (K,) [s] the table's own point times."""

    kind: str
    breaks: np.ndarray
    coef: np.ndarray
    points: np.ndarray
    #: before and after the table: "hold" (at rest at its end points) or "continue" (at its end velocities)
    ends: str = "hold"

    def __post_init__(self) -> None:
        if self.coef.ndim != 3 or self.coef.shape[0] != len(self.breaks) - 1 or self.coef.shape[1] != 6:
            raise ValueError(f"coef must be (pieces, 6, joints) with pieces = len(breaks) − 1 = "
                             f"{len(self.breaks) - 1}, got {self.coef.shape}")

    @property
    def start(self) -> float:
        return float(self.breaks[0])

    @property
    def duration(self) -> float:
        """From the motion's start to its end [s]."""
        return float(self.breaks[-1] - self.breaks[0])

    @property
    def steps(self) -> bool:
        """Whether the acceleration steps anywhere: a PVT's at its points, a cam-table's at its blends' ends, and any
        table's at the one-cycle blends from and to rest of an end that moves."""
        return bool(self.kind != "cam" or self.breaks[0] < self.points[0] or self.breaks[-1] > self.points[-1])

    @property
    def jumps(self) -> np.ndarray:
        """The interior breaks [s]: where a derivative up to jerk may step."""
        return self.breaks[1:-1]

    def __call__(self, t: np.ndarray, order: int = 0, side: str = "right") -> np.ndarray:
        """The ``order``-th derivative (0 … 3) at ``t`` (N,) [s] → (N, n)."""
        if not 0 <= order <= MAX_ORDER:
            raise ValueError(f"order must be in 0..{MAX_ORDER}, got {order}")
        t = np.atleast_1d(np.asarray(t, float))
        lo, hi = self.breaks[0], self.breaks[-1]
        inside = (t >= lo) & (t <= hi)
        tc = np.clip(t, lo, hi)
        k = np.clip(np.searchsorted(self.breaks, tc, side=side) - 1, 0, len(self.coef) - 1)
        x = (tc - self.breaks[k])[:, None]
        c = self.coef[k]  # (N, 6, n)
        out = np.zeros((len(t), c.shape[2]))
        for m in range(5, order - 1, -1):  # Horner on the order-th derivative
            fac = float(np.prod(np.arange(m - order + 1, m + 1))) if order else 1.0
            out = out * x + fac * c[:, m]
        if order:
            out[~inside] = 0.0
        return out

    def all_orders(self, t: np.ndarray, side: str = "right") -> list[np.ndarray]:
        """[q, q̇, q̈, q⃛] at ``t`` (each (N, n))."""
        return [self(t, k, side) for k in range(MAX_ORDER + 1)]


def _pad(cols: list[np.ndarray]) -> np.ndarray:
    """(P, 6, n) from the coefficient arrays c0 … (each (P, n)), zeros above."""
    out = np.zeros((cols[0].shape[0], 6, cols[0].shape[1]))
    for m, c in enumerate(cols):
        out[:, m] = c
    return out


def _pvt(t, q, qd) -> np.ndarray:
    h = np.diff(t)[:, None]
    dp = (q[1:] - q[:-1]) / h
    c2 = (3 * dp - 2 * qd[:-1] - qd[1:]) / h
    c3 = (-2 * dp + qd[:-1] + qd[1:]) / h**2
    return _pad([q[:-1], qd[:-1], c2, c3])


def _cam(t, q, qd, qdd) -> np.ndarray:
    h = np.diff(t)[:, None]
    p0, v0, a0 = q[:-1], qd[:-1], qdd[:-1]
    dp = q[1:] - p0 - v0 * h - a0 * h * h / 2
    dv = (qd[1:] - v0 - a0 * h) * h
    da = (qdd[1:] - a0) * h * h
    c3 = 10 * dp - 4 * dv + da / 2
    c4 = -15 * dp + 7 * dv - da
    c5 = 6 * dp - 3 * dv + da / 2
    return _pad([p0, v0, a0 / 2, c3 / h**3, c4 / h**4, c5 / h**5])


def moving_ends(t, q, qd=None) -> tuple[np.ndarray, np.ndarray]:
    """The velocities (n,) each of a table's first and last point (``qd``: its velocity column; without one, a
    cam-table's first and last lines' slopes), each zeroed where it is within 1e-9 of the table's largest speed (the
    rounding of a velocity at rest)."""
    t, q = np.asarray(t, float), np.asarray(q, float)
    v = np.asarray(qd, float) if qd is not None else np.diff(q, axis=0) / np.diff(t)[:, None]
    if len(v) == 0:
        return np.zeros(q.shape[1]), np.zeros(q.shape[1])
    tiny = 1e-9 * float(np.max(np.abs(v)))
    return tuple(np.where(np.abs(x) > tiny, x, 0.0) for x in (v[0], v[-1]))


def _rest_blends(t, coef, q, qd, blend: float) -> tuple[np.ndarray, np.ndarray]:
    """``t``, ``coef`` with a parabolic blend ``blend`` [s] long from rest up to the first point (when it moves:
    position q₀ − v₀·c/2 + v₀·x²/(2c), x from t₀ − c) and from the last point down to rest (q_N + v_N·x − v_N·x²/(2c))."""
    first, last = moving_ends(t, q, qd)
    c = float(blend)
    breaks, pieces = np.asarray(t, float), coef
    if np.any(first):
        head = np.zeros((1, 6, q.shape[1]))
        head[0, 0], head[0, 2] = q[0] - first * c / 2, first / (2 * c)
        breaks, pieces = np.append(breaks[0] - c, breaks), np.concatenate([head, pieces])
    if np.any(last):
        tail = np.zeros((1, 6, q.shape[1]))
        tail[0, 0], tail[0, 1], tail[0, 2] = q[-1], last, -last / (2 * c)
        breaks, pieces = np.append(breaks, breaks[-1] + c), np.concatenate([pieces, tail])
    return breaks, pieces


def _linear_blended(t, q, blend: float, going: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Breaks and coefficients of the straight lines through (t, q) with every velocity step taken in a parabolic
    blend ``blend`` [s] long centred on its point (from rest before the first point, to rest after the last; with
    ``going``, at the first and last lines' slopes before and after them: no step there)."""
    n = q.shape[1]
    slope = np.diff(q, axis=0) / np.diff(t)[:, None]
    before, after = (slope[:1], slope[-1:]) if going and len(slope) else (np.zeros((1, n)), np.zeros((1, n)))
    v = np.vstack([before, slope, after])  # v[i] before point i, v[i + 1] after it
    w = float(blend)
    breaks: list[float] = []
    coefs: list[list[np.ndarray]] = []
    for i in range(len(t)):
        a = t[i] - w / 2
        # blend: p = q_i + v_in (t − t_i) + (v_out − v_in)(t − a)² / (2w), in powers of (t − a)
        dv = v[i + 1] - v[i]
        breaks.append(a)
        coefs.append([q[i] - v[i] * w / 2, v[i], dv / (2 * w)])
        end = t[i] + w / 2
        if i + 1 < len(t) and t[i + 1] - w / 2 > end + 1e-15:  # a straight piece up to the next blend
            breaks.append(end)
            coefs.append([q[i] + v[i + 1] * w / 2, v[i + 1], np.zeros(n)])
    breaks.append(t[-1] + w / 2)
    return np.array(breaks), _pad([np.array([c[m] for c in coefs]) for m in range(3)])


def rebuild(table, blend: float | None = None, ends: str = "hold") -> TableMotion:
    """The motion a drive runs from ``table`` (a KnotTable): cubic Hermite (pvt), quintic (cam), or straight lines
    read every ``blend`` [s] with each velocity step blended over that cycle (cam-table: the controller cycle,
    required; pvt, cam: the blends from and to rest of an end that moves, when given). ``ends``: "hold" (the drive
    holds the end points before and after the table) or "continue" (the controller goes on at the end velocities)."""
    if ends not in ("hold", "continue"):
        raise ValueError(f"ends = {ends!r}: must be hold or continue")
    t = np.asarray(table.t, float)
    if table.kind in ("pvt", "cam"):
        coef = _pvt(t, table.q, table.qd) if table.kind == "pvt" else _cam(t, table.q, table.qd, table.qdd)
        breaks = t
        if blend is not None and ends == "hold":  # an end that moves: the drive's step from or to rest, in one cycle
            breaks, coef = _rest_blends(t, coef, np.asarray(table.q, float), np.asarray(table.qd, float), blend)
        return TableMotion(table.kind, breaks, coef, t, ends)
    if table.kind == "cam-table":
        if blend is None or not blend > 0:
            raise ValueError("cam-table: the blend (the controller cycle [s]) must be > 0")
        c = float(blend)
        ts = np.arange(int(np.ceil((t[-1] - t[0]) / c - 1e-9)) + 1) * c + t[0]  # the cycles the drive reads at
        q = np.asarray(table.q, float)
        setpoints = np.column_stack([np.interp(ts, t, q[:, i]) for i in range(q.shape[1])])
        breaks, coef = _linear_blended(ts, setpoints, c, ends == "continue")
        return TableMotion("cam-table", breaks, coef, t, ends)
    raise ValueError(f"kind = {table.kind!r}: not a table format (pvt, cam, cam-table)")
