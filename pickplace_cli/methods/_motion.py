"""Building blocks shared by the methods of Su 2018 and the Li 2018 baselines.

Two ways of making a move in the vertical plane of the task (local coordinates u along the move, v up,
both in m, origin at the pick point; [Li2018, Eq. (1)]):

* **a law on the arc length of a planar curve** (``ph``, ``lame``): :class:`ArcLengthPath` chains curve
  pieces (straight segments, PH corners, Lamé arcs …), runs a :class:`~pickplace_cli.laws.MotionLaw` on
  the total arc length S(τ) = L·s(τ), and differentiates the composition exactly:
  p′ = p_s Ṡ, p″ = p_ss Ṡ² + p_s S̈, p‴ = p_sss Ṡ³ + 3 p_ss Ṡ S̈ + p_s S⃛, where p_s, p_ss, p_sss are the
  arc-length derivatives of the curve (unit tangent, curvature vector, its derivative), obtained in
  closed form from the curve's own parameter derivatives. Only the inverse of the arc length is
  numerical (Newton with a bisection safeguard, to round-off).
* **laws superposed per axis** (``superposition``, ``piecewise-poly``): :class:`AxisLaws` sums laws placed
  on time intervals on each axis. Every piece is a polynomial in τ, so the peaks are exact
  (:func:`~pickplace_cli.peaks.ppoly_norm_peak`).

:func:`to_cartesian` wraps either into a :class:`~pickplace_cli.trajectory.CartesianPath` in the base frame
(the map (u, v) → base is a rotation plus offset, so norms and peaks are the same in both frames).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable, Sequence

import numpy as np

from ..laws import MotionLaw
from ..peaks import ppoly_norm_peak, refine_max
from ..task import Task
from ..trajectory import CartesianPath

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
        g = np.linspace(self.g0, self.g1, n)
        self._table = (g, self.arclength(g))

    def param(self, s: np.ndarray) -> np.ndarray:
        """g with arclength(g) = s, for s ∈ [0, length] (clipped)."""
        gt, st = self._table
        s = np.clip(np.asarray(s, float), 0.0, self.length)
        k = np.clip(np.searchsorted(st, s, side="right") - 1, 0, len(gt) - 2)
        lo, hi = gt[k], gt[k + 1]
        x0 = lo + (s - st[k]) / np.maximum(st[k + 1] - st[k], 1e-300) * (hi - lo)
        return invert_monotone(self.arclength, self.speed, s, lo, hi, x0)

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


#: dense samples for the arc-length methods' peak search (plus the joins and both sides of each);
#: each local maximum of the samples is then refined by golden-section search (peaks.refine_max)
PEAK_SAMPLES = 2001
#: golden-section iterations per candidate: the bracket 2/(PEAK_SAMPLES − 1) shrinks to 1e-3·0.618²⁴ ≈ 1e-8,
#: so a smooth maximum (relative curvature f″/f ≲ 1e4 per unit τ², far above any path here) is off by
#: ≲ 1e4·(1e-8)²/2 ≈ 1e-12 relative
REFINE_ITERATIONS = 24


def sampled_peaks(fun: Callable[[np.ndarray, int], list[np.ndarray]], breakpoints: np.ndarray) -> tuple[float, float, float]:
    """True maxima of ‖x′‖, ‖x″‖, ‖x‴‖ over τ ∈ [0, 1] for a piecewise-smooth curve.

    Samples PEAK_SAMPLES points plus every breakpoint and τ ± 1e-11 on both sides of it (so a one-sided
    limit at a jump of the jerk is seen), then refines every local maximum by golden-section search.
    Golden section (REFINE_ITERATIONS) leaves a bracket of ~1e-8 in τ, so a smooth maximum is found to
    ~1e-12 relative and a one-sided limit to ~1e-11·|d/dτ|, i.e. ~1e-9 relative or better.
    """
    bp = np.asarray(breakpoints, float)
    tau = np.unique(np.concatenate([np.linspace(0.0, 1.0, PEAK_SAMPLES), bp, np.clip(bp - 1e-11, 0, 1), np.clip(bp + 1e-11, 0, 1)]))

    def norms(t: np.ndarray) -> np.ndarray:
        d = fun(t, 3)
        return np.column_stack([np.linalg.norm(d[k], axis=1) for k in (1, 2, 3)])

    peak, _ = refine_max(norms, tau, norms(tau), max_candidates=4, iterations=REFINE_ITERATIONS)
    return float(peak[0]), float(peak[1]), float(peak[2])


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
        """(breaks, coef) of the ``order``-th derivative for :func:`~pickplace_cli.peaks.ppoly_norm_peak`."""
        br = self.breakpoints()
        polys = []
        for i in range(len(br) - 1):
            lo, hi = br[i], br[i + 1]
            row = []
            for ax in self.axes:
                p = np.polynomial.Polynomial([0.0])
                for pl in ax:
                    if pl.amplitude == 0.0:
                        continue
                    if pl.duration > 0 and pl.start <= lo + 1e-12 and pl.start + pl.duration >= hi - 1e-12:
                        p = p + pl.amplitude * pl.law.piece_polynomials(pl.start, pl.duration, lo)
                    elif pl.start + max(pl.duration, 0.0) <= lo + 1e-12:
                        p = p + pl.amplitude
                row.append(p.deriv(order) if order else p)
            polys.append(row)
        deg = max(len(p.coef) for row in polys for p in row)
        coef = np.zeros((len(polys), 2, deg))
        for i, row in enumerate(polys):
            for a, p in enumerate(row):
                c = p.coef[::-1]  # highest power first
                coef[i, a, deg - len(c):] = c
        return br, coef

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
    local: Callable[[np.ndarray, int], np.ndarray],
    method: str,
    parameters: dict[str, Any],
    peaks: tuple[float, float, float],
    breakpoints: np.ndarray,
) -> CartesianPath:
    """CartesianPath from a local motion ``local(tau, order) -> (N, 2)`` in (u, v):
    base = p_from + u·e_u + v·e_z [Li2018, Eq. (1)]."""
    e_u = task.e_u
    e_z = np.array([0.0, 0.0, 1.0])
    origin = task.p_from.copy()

    def evaluate(tau: np.ndarray, order: int) -> np.ndarray:
        x = local(tau, order)
        out = x[:, :1] * e_u + x[:, 1:2] * e_z
        return out + origin if order == 0 else out

    return CartesianPath(
        evaluate=evaluate,
        method=method,
        parameters=parameters,
        peaks=tuple(float(p) for p in peaks),  # type: ignore[arg-type]
        breakpoints=np.asarray(breakpoints, float),
    )
