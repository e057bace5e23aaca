"""Building blocks shared by the methods of Su 2018 and the Li 2018 baselines.

Two ways of making a move in the vertical plane of the task (local coordinates u along the move, v up,
both in m, origin at the pick point; [Li2018, Eq. (1)]):

* **a law on the arc length of a planar curve** (``ph``, ``lame``): :class:`ArcLengthPath` chains curve
  pieces (straight segments, PH corners, Lamé arcs …), runs a :class:`~pickplace_cli.curves.laws.MotionLaw` on
  the total arc length S(τ) = L·s(τ), and differentiates the composition exactly:
  p′ = p_s Ṡ, p″ = p_ss Ṡ² + p_s S̈, p‴ = p_sss Ṡ³ + 3 p_ss Ṡ S̈ + p_s S⃛, where p_s, p_ss, p_sss are the
  arc-length derivatives of the curve (unit tangent, curvature vector, its derivative), obtained in
  closed form from the curve's own parameter derivatives. Only the inverse of the arc length is
  numerical (Newton with a bisection safeguard, to round-off).
* **laws superposed per axis** (``superposition``, ``piecewise-poly``): :class:`AxisLaws` sums laws placed
  on time intervals on each axis. Every piece is a polynomial in τ, so the peaks are exact
  (:func:`~pickplace_cli.curves.peaks.ppoly_norm_peak`).

:func:`to_cartesian` wraps either into a :class:`~pickplace_cli.model.trajectory.CartesianPath` in the base frame
(the map (u, v) → base is a rotation plus offset, so norms and peaks are the same in both frames).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable, Sequence

import numpy as np

from ..curves.laws import MotionLaw
from ..curves.peaks import ppoly_norm_peak
from ..model.task import Task
from ..model.trajectory import CartesianPath

#: equally spaced arc-length nodes of the quintic Hermite start for the inverse g(s) of a curve piece
HERMITE_NODES = 1025
#: interpolation error (fraction of the parameter range) below which no Newton polish is needed: a few
#: units of round-off
HERMITE_TOL = 1e-14
#: Newton/bisection stopping rule for the arc-length inverse: |Δg| ≤ this × max(|g|, initial bracket),
#: i.e. a few units in the last place (Newton converges quadratically, so the step before was ~1e-8)
_INV_TOL = 4 * np.finfo(float).eps
_INV_ITER = 60


def invert_monotone(
    f: Callable[[np.ndarray], np.ndarray],
    df: Callable[[np.ndarray], np.ndarray],
    target: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    x0: np.ndarray | None = None,
) -> np.ndarray:
    """Vectorised solve of f(x) = target for an increasing f on brackets [lo, hi] (f(lo) ≤ target ≤ f(hi)).

    Newton steps x − (f − target)/f′, replaced by bisection whenever a step leaves the current bracket;
    the bracket shrinks on every iteration by the sign of f − target. Converges quadratically from a good
    start (the callers start from a table interpolation) and never diverges.
    """
    target = np.asarray(target, dtype=float)
    lo = np.array(np.broadcast_to(lo, target.shape), dtype=float)
    hi = np.array(np.broadcast_to(hi, target.shape), dtype=float)
    x = 0.5 * (lo + hi) if x0 is None else np.clip(np.asarray(x0, dtype=float), lo, hi)
    tol = _INV_TOL * np.maximum(np.abs(x), hi - lo)
    with np.errstate(divide="ignore", invalid="ignore"):
        for _ in range(_INV_ITER):
            r = f(x) - target
            lo = np.where(r <= 0, x, lo)
            hi = np.where(r >= 0, x, hi)
            xn = x - r / df(x)
            ok = (xn >= lo) & (xn <= hi)  # False also for NaN/inf from a zero derivative
            xn = np.where(ok, xn, 0.5 * (lo + hi))
            xn = np.where(r == 0, x, xn)
            done = bool(np.all(np.abs(xn - x) <= tol))
            x = xn
            if done:
                break
    return x


def arc_derivatives(P1: np.ndarray, P2: np.ndarray, P3: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(p_s, p_ss, p_sss): derivatives with respect to arc length from the parameter derivatives P′, P″, P‴.

    With σ = ‖P′‖, σ′ = P′·P″/σ, σ″ = (‖P″‖² + P′·P‴ − σ′²)/σ and g(s) the inverse of the arc length:
    g_s = 1/σ, g_ss = −σ′/σ³, g_sss = −(σ″σ − 3σ′²)/σ⁵, then p_s = P′g_s, p_ss = P″g_s² + P′g_ss,
    p_sss = P‴g_s³ + 3P″g_s g_ss + P′g_sss. Needs σ > 0 (a regular parametrisation).
    """
    sig = np.linalg.norm(P1, axis=-1)
    sig1 = np.einsum("...i,...i", P1, P2) / sig
    sig2 = (np.einsum("...i,...i", P2, P2) + np.einsum("...i,...i", P1, P3) - sig1**2) / sig
    gs = 1.0 / sig
    gss = -sig1 / sig**3
    gsss = -(sig2 * sig - 3.0 * sig1**2) / sig**5
    ps = P1 * gs[..., None]
    pss = P2 * (gs**2)[..., None] + P1 * gss[..., None]
    psss = P3 * (gs**3)[..., None] + 3.0 * P2 * (gs * gss)[..., None] + P1 * gsss[..., None]
    return ps, pss, psss


class Segment:
    """Straight segment from ``a`` to ``b`` (local 2-D, m), parametrised by its arc length."""

    def __init__(self, a: Sequence[float], b: Sequence[float]) -> None:
        self.a = np.asarray(a, dtype=float)
        self.b = np.asarray(b, dtype=float)
        self.length = float(np.linalg.norm(self.b - self.a))
        self.e = (self.b - self.a) / self.length if self.length > 0 else np.zeros(2)

    def at_length(self, s: np.ndarray) -> tuple[np.ndarray, ...]:
        s = np.asarray(s, float)
        z = np.zeros(s.shape + (2,))
        return self.a + s[:, None] * self.e, np.broadcast_to(self.e, z.shape).copy(), z, z.copy()


class ParametricPiece:
    """A regular planar curve P(g), g ∈ [g0, g1], with its arc length s(g) and inverse g(s).

    Subclasses provide ``curve(g) -> (P, P′, P″, P‴)`` (each (N, 2), m and m per unit g^k),
    ``arclength(g)`` (N,) and ``speed(g)`` = ‖P′(g)‖ (N,), plus ``g0``, ``g1`` and ``length``.
    ``at_length`` inverts the arc length (Newton + bisection from a tabulated start) and returns the
    arc-length derivatives (P, p_s, p_ss, p_sss).
    """

    g0: float
    g1: float
    length: float
    _table: tuple[np.ndarray, np.ndarray]

    def curve(self, g: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:  # pragma: no cover
        raise NotImplementedError

    def arclength(self, g: np.ndarray) -> np.ndarray:  # pragma: no cover
        raise NotImplementedError

    def speed(self, g: np.ndarray) -> np.ndarray:  # pragma: no cover
        raise NotImplementedError

    def _build_table(self, n: int = 129) -> None:
        """Tables for the inverse g(s): a coarse (g, s(g)) table, then g, g′, g″ at HERMITE_NODES equally
        spaced s (g′ = 1/σ, g″ = −σ′/σ³, exact), so :meth:`param` starts Newton from a quintic Hermite
        interpolant that is already at round-off for smooth pieces (one Newton step confirms it)."""
        g = np.linspace(self.g0, self.g1, n)
        self._table = (g, self.arclength(g))
        sn = np.linspace(0.0, self.length, HERMITE_NODES)
        gn = self._param_from_table(sn)
        _, P1, P2, _ = self.curve(gn)
        sig = np.linalg.norm(P1, axis=1)
        sig1 = np.einsum("ij,ij->i", P1, P2) / sig
        self._hermite = (self.length / (HERMITE_NODES - 1), gn, 1.0 / sig, -sig1 / sig**3)
        # self-check at the midpoints between nodes (where interpolation is worst): the cheapest polish
        # that reaches round-off there is used for every call
        mid = 0.5 * (sn[1:] + sn[:-1])
        self._polish = True
        exact = self._param_from_table(mid)
        tol = HERMITE_TOL * (self.g1 - self.g0)
        for mode in ("none", "newton", "bracketed"):
            self._polish = mode
            if mode == "bracketed" or np.max(np.abs(self.param(mid) - exact)) <= tol:
                break

    def _param_from_table(self, s: np.ndarray) -> np.ndarray:
        gt, st = self._table
        k = np.clip(np.searchsorted(st, s, side="right") - 1, 0, len(gt) - 2)
        lo, hi = gt[k], gt[k + 1]
        x0 = lo + (s - st[k]) / np.maximum(st[k + 1] - st[k], 1e-300) * (hi - lo)
        return invert_monotone(self.arclength, self.speed, s, lo, hi, x0)

    def param(self, s: np.ndarray) -> np.ndarray:
        """g with arclength(g) = s, for s ∈ [0, length] (clipped): the quintic Hermite interpolant, polished as
        the build-time check (at the midpoints between nodes) found necessary to reach round-off: not at
        all, by one Newton step, or by bracketed Newton iterations (extreme aspect ratios)."""
        s = np.minimum(np.maximum(np.asarray(s, float), 0.0), self.length)
        g = self._interpolate(s)
        if self._polish == "newton":  # one step from an interpolant good to ≲ 1e-8: quadratic → round-off
            g = np.minimum(np.maximum(g - (self.arclength(g) - s) / self.speed(g), self.g0), self.g1)
        elif self._polish == "bracketed":  # Newton with bisection inside the bracket of the two nodes
            step, gn = self._hermite[:2]
            k = np.minimum((s / step).astype(int), len(gn) - 2)
            g = invert_monotone(self.arclength, self.speed, s, gn[k], gn[k + 1], g)
        return g

    def _interpolate(self, s: np.ndarray) -> np.ndarray:
        step, gn, d1, d2 = self._hermite
        x = s / step
        k = np.minimum(x.astype(int), len(gn) - 2)
        t = x - k
        t2 = t * t
        t3 = t2 * t
        t4 = t3 * t
        t5 = t4 * t
        h01 = 10 * t3 - 15 * t4 + 6 * t5
        g0, g1 = gn[k], gn[k + 1]
        x0 = (
            g0 * (1 - h01)
            + g1 * h01
            + step * (d1[k] * (t - 6 * t3 + 8 * t4 - 3 * t5) + d1[k + 1] * (-4 * t3 + 7 * t4 - 3 * t5))
            + step * step * 0.5 * (d2[k] * (t2 - 3 * t3 + 3 * t4 - t5) + d2[k + 1] * (t3 - 2 * t4 + t5))
        )
        return x0

    def at_length(self, s: np.ndarray) -> tuple[np.ndarray, ...]:
        g = self.param(s)
        P, P1, P2, P3 = self.curve(g)
        return (P, *arc_derivatives(P1, P2, P3))


@dataclass(frozen=True)
class Placed:
    """A piece placed in the local (u, v) plane: x = M·p + c, optionally traversed from its end."""

    piece: Any
    M: np.ndarray = field(default_factory=lambda: np.eye(2))
    c: np.ndarray = field(default_factory=lambda: np.zeros(2))
    reverse: bool = False

    @property
    def length(self) -> float:
        return float(self.piece.length)

    def at_length(self, s: np.ndarray) -> tuple[np.ndarray, ...]:
        """(x, x_s, x_ss, x_sss) at local arc length s from the placed start."""
        L = self.length
        p, ps, pss, psss = self.piece.at_length(L - s if self.reverse else s)
        if self.reverse:
            ps, psss = -ps, -psss
        M = self.M
        return p @ M.T + self.c, ps @ M.T, pss @ M.T, psss @ M.T


class ArcLengthPath:
    """Pieces joined end to end in the (u, v) plane, run by ``law`` on the total arc length [Su2018, Eq. (21)]."""

    def __init__(self, pieces: Sequence[Placed], law: MotionLaw) -> None:
        self.pieces = [p for p in pieces if p.length > 0]
        self.law = law
        lengths = np.array([p.length for p in self.pieces])
        self.starts = np.concatenate([[0.0], np.cumsum(lengths)])
        self.length = float(self.starts[-1])

    def joints_tau(self) -> np.ndarray:
        """τ of every join between pieces (plus 0 and 1): S(τ) = the cumulative lengths."""
        target = self.starts[1:-1] / self.length
        inner = invert_monotone(lambda x: self.law(x, 0), lambda x: self.law(x, 1), target, 0.0, 1.0)
        return np.concatenate([[0.0], inner, [1.0]])

    def derivatives(self, tau: np.ndarray, max_order: int = 3) -> list[np.ndarray]:
        """[x, x′, x″, x‴][: max_order + 1] in local (u, v), each (N, 2), derivatives in τ (T = 1)."""
        tau = np.clip(np.asarray(tau, float), 0.0, 1.0)
        L = self.length
        S = L * self.law(tau, 0)
        S1, S2, S3 = (L * self.law(tau, k) for k in (1, 2, 3))
        k = np.clip(np.searchsorted(self.starts, S, side="right") - 1, 0, len(self.pieces) - 1)
        x = np.empty((tau.size, 2))
        xs = np.empty_like(x)
        xss = np.empty_like(x)
        xsss = np.empty_like(x)
        for i, piece in enumerate(self.pieces):
            sel = k == i
            if sel.any():
                x[sel], xs[sel], xss[sel], xsss[sel] = piece.at_length(S[sel] - self.starts[i])
        out = [x]
        if max_order >= 1:
            out.append(xs * S1[:, None])
        if max_order >= 2:
            out.append(xss * (S1**2)[:, None] + xs * S2[:, None])
        if max_order >= 3:
            out.append(xsss * (S1**3)[:, None] + 3.0 * xss * (S1 * S2)[:, None] + xs * S3[:, None])
        return out

    def __call__(self, tau: np.ndarray, order: int = 0) -> np.ndarray:
        return self.derivatives(tau, order)[order]


#: dense samples for the arc-length methods' peak search (plus the joins and both sides of each)
PEAK_SAMPLES = 2001
#: local maxima refined per derivative order, and the zoom of the refinement: each round evaluates
#: ZOOM_POINTS equally spaced points across the current bracket and keeps the two intervals around the
#: best one, so the bracket shrinks by (ZOOM_POINTS − 1)/2 per round: 2/2000 → 1e-3·10⁻⁶ = 1e-9 after 6
#: rounds, where a smooth maximum (relative curvature |f″/f| ≲ 1e6 per unit τ²) is off by ≲ 1e-12
PEAK_CANDIDATES = 4
ZOOM_POINTS = 21
ZOOM_ROUNDS = 6


def sampled_peaks(fun: Callable[[np.ndarray, int], list[np.ndarray]], breakpoints: np.ndarray) -> tuple[float, float, float]:
    """True maxima of ‖x′‖, ‖x″‖, ‖x‴‖ over τ ∈ [0, 1] for a piecewise-smooth curve (``fun(tau, 3)`` gives
    [x, x′, x″, x‴]).

    Samples PEAK_SAMPLES points plus every breakpoint and τ ± 1e-11 on both sides of it (so a one-sided
    limit at a jump of the jerk is seen), then zooms into the PEAK_CANDIDATES best local maxima of each
    order (all brackets of all orders in one evaluation per round). The result never falls below the best
    sample, and every value it returns is a value of the function; a smooth maximum is found to ~1e-12
    relative, a one-sided limit at a jump to ~1e-11·|d/dτ| (the breakpoint samples).
    """
    bp = np.asarray(breakpoints, float)
    tau = np.unique(np.concatenate([np.linspace(0.0, 1.0, PEAK_SAMPLES), bp, np.clip(bp - 1e-11, 0, 1), np.clip(bp + 1e-11, 0, 1)]))

    def norms(t: np.ndarray) -> np.ndarray:
        d = fun(t, 3)
        return np.column_stack([np.linalg.norm(d[k], axis=1) for k in (1, 2, 3)])

    y = norms(tau)
    best = y.max(axis=0)
    n = len(tau)
    lo_l, hi_l, col_l = [], [], []
    for c in range(3):
        yc = y[:, c]
        left = np.concatenate([[-np.inf], yc[:-1]])
        right = np.concatenate([yc[1:], [-np.inf]])
        idx = np.flatnonzero((yc >= left) & (yc >= right))
        idx = idx[np.argsort(yc[idx])[::-1][:PEAK_CANDIDATES]]
        lo_l.append(tau[np.maximum(idx - 1, 0)])
        hi_l.append(tau[np.minimum(idx + 1, n - 1)])
        col_l.append(np.full(idx.size, c))
    lo, hi, col = np.concatenate(lo_l), np.concatenate(hi_l), np.concatenate(col_l)
    frac = np.linspace(0.0, 1.0, ZOOM_POINTS)
    for _ in range(ZOOM_ROUNDS):
        grid = lo[:, None] + (hi - lo)[:, None] * frac[None, :]  # (brackets, ZOOM_POINTS)
        vals = norms(grid.ravel()).reshape(grid.shape + (3,))[np.arange(len(col)), :, col]
        k = np.argmax(vals, axis=1)
        for c in range(3):
            sel = col == c
            if sel.any():
                best[c] = max(best[c], float(vals[sel].max()))
        lo = grid[np.arange(len(k)), np.maximum(k - 1, 0)]
        hi = grid[np.arange(len(k)), np.minimum(k + 1, ZOOM_POINTS - 1)]
    return float(best[0]), float(best[1]), float(best[2])


@dataclass(frozen=True)
class Placement:
    """One law on one axis: ``amplitude`` [m] · law((τ − start)/duration)."""

    amplitude: float
    law: MotionLaw
    start: float
    duration: float


class AxisLaws:
    """u(τ) and v(τ) as sums of placed laws (each axis a list of :class:`Placement`); piecewise polynomial."""

    def __init__(self, u: Sequence[Placement], v: Sequence[Placement]) -> None:
        self.axes = (list(u), list(v))

    def breakpoints(self) -> np.ndarray:
        pts = {0.0, 1.0}
        for ax in self.axes:
            for p in ax:
                if p.amplitude != 0.0:
                    pts.update((p.start, p.start + p.duration))
        # round-off twins of 0, 1 or of each other (a law ending where the next starts) merge; 0 and 1 stay exact
        b = np.array(sorted(0.0 if x < 1e-12 else 1.0 if x > 1 - 1e-12 else x for x in pts if -1e-12 <= x <= 1 + 1e-12))
        return b[np.concatenate([[True], np.diff(b) > 1e-12])]

    def __call__(self, tau: np.ndarray, order: int = 0) -> np.ndarray:
        tau = np.asarray(tau, float)
        out = np.zeros((tau.size, 2))
        for a, ax in enumerate(self.axes):
            for p in ax:
                out[:, a] += p.amplitude * p.law.over(tau, p.start, p.duration, order)
        return out

    def derivatives(self, tau: np.ndarray, max_order: int = 3) -> list[np.ndarray]:
        return [self(tau, k) for k in range(max_order + 1)]

    def piece_coefficients(self, order: int) -> tuple[np.ndarray, np.ndarray]:
        """(breaks, coef) of the ``order``-th derivative for :func:`~pickplace_cli.curves.peaks.ppoly_norm_peak`."""
        br = self.breakpoints()
        deg = max((pl.law.degree for ax in self.axes for pl in ax), default=0)
        pos = np.zeros((len(br) - 1, 2, deg + 1))  # ascending powers of (τ − br[i])
        for i in range(len(br) - 1):
            lo, hi = br[i], br[i + 1]
            for a, ax in enumerate(self.axes):
                for pl in ax:
                    if pl.amplitude == 0.0:
                        continue
                    if pl.duration > 0 and pl.start <= lo + 1e-12 and pl.start + pl.duration >= hi - 1e-12:
                        c = pl.law.piece_coefficients(pl.start, pl.duration, lo)
                        pos[i, a, : c.size] += pl.amplitude * c
                    elif pl.start + max(pl.duration, 0.0) <= lo + 1e-12:
                        pos[i, a, 0] += pl.amplitude
        coef = pos
        for _ in range(order):  # differentiate: c_k → k·c_k at power k − 1
            coef = coef[:, :, 1:] * np.arange(1, coef.shape[2])
        return br, coef[:, :, ::-1].copy()  # highest power first

    def exact_peaks(self) -> tuple[float, float, float]:
        """Exact max of ‖x^(k)‖, k = 1, 2, 3, on the polynomial pieces (one-sided limits included)."""
        return tuple(ppoly_norm_peak(*self.piece_coefficients(k))[0] for k in (1, 2, 3))  # type: ignore[return-value]


def li_eq26(path: CartesianPath, capacity) -> float:
    """Li 2018's cycle time T = max(v̂/[v], sqrt(â/[a])) [Li2018, Eq. (26)] (s) from the path's exact peaks
    (v̂ = b·v_max, â = b·a_max for the normalised peaks of the paper); no jerk term, as in the paper."""
    v, a, _ = path.peaks
    return max(v / capacity.velocity, math.sqrt(a / capacity.acceleration))


def local_endpoints(task: Task) -> tuple[float, float, float]:
    """(b, h1, h2): width [m] and the rises from the pick and the place point to the top of the path [m]."""
    zt = task.z_top
    return task.b, float(zt - task.p_from[2]), float(zt - task.p_to[2])


def to_cartesian(
    task: Task,
    local: Any,
    method: str,
    parameters: dict[str, Any],
    peaks: tuple[float, float, float],
    breakpoints: np.ndarray,
) -> CartesianPath:
    """CartesianPath from a local motion in (u, v) — an :class:`ArcLengthPath` or :class:`AxisLaws`, i.e.
    anything with ``derivatives(tau, 3) -> [x, x′, x″, x‴]`` — mapped by base = p_from + u·e_u + v·e_z
    [Li2018, Eq. (1)].

    The pipeline asks for orders 0…3 at the same τ one after another (robot models, limit refinement);
    the arc-length methods compute all four in one pass (one arc-length inversion), so the last τ and its
    four derivatives are kept and reused when the next call passes an equal τ array.
    """
    e_u = task.e_u
    e_z = np.array([0.0, 0.0, 1.0])
    origin = task.p_from.copy()
    memo: list = [None]  # one entry (τ, [p, p′, p″, p‴]), replaced in one assignment (thread-safe reads)

    def evaluate(tau: np.ndarray, order: int) -> np.ndarray:
        entry = memo[0]
        if entry is None or entry[0].shape != tau.shape or not np.array_equal(entry[0], tau):
            out = [x[:, :1] * e_u + x[:, 1:2] * e_z for x in local.derivatives(tau, 3)]
            out[0] += origin
            entry = (tau.copy(), out)
            memo[0] = entry
        return entry[1][order].copy()

    return CartesianPath(
        evaluate=evaluate,
        method=method,
        parameters=parameters,
        peaks=tuple(float(p) for p in peaks),  # type: ignore[arg-type]
        breakpoints=np.asarray(breakpoints, float),
        # where the jerk steps (the law's ends, a PH corner's joints, an axis law's start or end): the limit
        # check samples both sides there; without the declaration every breakpoint counts as one
        jumps=parameters.get("jerk_jumps_at"),
    )
