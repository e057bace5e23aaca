"""Velocity-constrained quintic B-spline for conveyor tracking [Yang2022, Sec. 2.2–2.3].

The gripper leaves the pick point with the pick conveyor's velocity v0 and arrives at the place point
with the place conveyor's velocity v1 (accelerations and jerks zero at both ends, Eq. 24). The path is
the quintic B-spline of Eq. (29) through five path points (Eq. 25–28):

    s1 = s1′ + v0·λ1·T,   s2 = s2′ + (v0 − v1)/2·λ2·T,   s3 = s3′ − v1·λ3·T

where s1′ … s3′ are the lift-off, apex and set-down points of the rest-to-rest move (Eq. 28; the task's
``via_points``, which reduce to Eq. 28 for equal end heights), on the 17 knots of Eq. (23) with
t8 = T/2 and free knots τ6, τ7, τ9, τ10 (normalised, Eq. 33). The seven shape parameters
p = (τ6, τ7, τ9, τ10, λ1, λ2, λ3) come from the two-stage problem of Eq. (37): first the minima of
a_max and j_max (Eq. 34–35) each on its own, then the maximum of F = min a_max / a_max + min j_max / j_max.

**The path depends on the duration T.** In normalised time τ = t/T the end velocity is v·T and the offsets
are v·λ·T, so a path is built *for* a given T (:func:`plan_bspline_vel` takes ``duration``) and is only
valid when run in that time; :class:`PathFactory` gives T → CartesianPath for duration selection
(``timing.choose_duration_for``: --time auto and fit, Eq. 38, re-optimise the shape at every trial T).

**Dimensionless groups.** Dividing all lengths by the horizontal width b of the move, the optimum depends
only on h/b, η, and v0·T/b, v1·T/b resolved along the move (e_u), across it (e_z × e_u) and vertically.
:func:`groups` computes them; the table of :mod:`pickplace_cli.lookup.vel_table` is built over them.

**How the optimum is found.** Each stage of Eq. (37) is a minimax over τ, solved by SLSQP in epigraph
form: minimise t subject to m_k(p) ≤ t, where m_k is the exact maximum of ‖a‖² (‖j‖²) on the k-th of
three equal segments of each knot span (from the roots of its derivative: a is cubic on a span), with
Jacobians exact in λ (the path is affine in λ) and by central differences in the four knots, evaluated
as one numpy batch (:class:`_Evaluator`: the Taylor coefficients per span of the spline of Eq. 16 for
many parameter vectors at once, solved in piecewise-Taylor form; tests hold them to the B-spline route
and to scipy). The cost is per numpy call rather than per vector, so SLSQP runs advance together
(:class:`_Lockstep`: scipy's SLSQP routine stepped, one batched evaluation per round for all runs;
a test holds each run to ``scipy.optimize.minimize``). F has more than one local
maximum and a_max, j_max more than one local minimum, so :func:`solve` is a multi-start: the paper's
initial guess and a quasi-random (Kronecker) sample of the feasible set are evaluated in one pass, and
SLSQP runs from the best distinct ones (for a_max and j_max also from the best start with both end
knots off the margin; for F from the best sampled point and from the midpoint of the two minimisers).
Where the shipped table applies, :func:`solve_seeded` (the default "exact" solver) starts each stage
from the table's seeds for that stage (the interpolated optimum and the 32 corner optima of the query's
cell; the table stores the minimisers of a_max and j_max too) and screens the multi-start's starts
(loosely) alongside, polishing one when it beats the seed's result; the F stage starts as soon as the
two stage-1 runs from the seeds are done. Reported peaks are exact (``bspline.norm_peaks``). A test
compares with scipy's differential_evolution.

Departures from the paper, and its slips (all documented in README):

* **Boundary margin.** min a_max is approached at the boundary of the open set of Eq. (36) (τ6 → 0,
  τ10 → 1), where it is not attained, so min a_max — and with it F — depends on how close to the
  boundary one goes. ``VelSettings.margin`` (default 0.01, the distance of the paper's initial guess
  τ6 = 0.01, τ10 = 0.99 from the boundary) is kept between consecutive knots 0 < τ6 < τ7 < ½ < τ9 < τ10 < 1.
  λ_i ∈ [0, 1] is taken closed (no conditioning problem at its ends, and the optimum can sit on them).
* **Degenerate λ.** λ2 has no effect when v0 = v1 (the offset (v0 − v1)/2 vanishes) — the case of the
  paper's own example — and λ1 (λ3) none when v0 = 0 (v1 = 0). Such a λ is dropped from the
  optimisation and held at the paper's initial value (0.21, 0.50, 0.21); ``lambda_free`` says which.
* **B is 11×1.** The text after Eq. (18) says "B is 6 × 1": B = [B1; B2] stacks f + 1 = 5 path points and
  6 boundary values, so it is 11 × 1 (= n + 1, matching the 11 control points).
* **Convexity.** The paper argues F is convex and that a single fmincon run finds the global optimum. For
  fixed knots a_max and j_max are convex in λ (a maximum of norms of affine functions), but not jointly
  with the knots, and F is a sum of ratios; hence the multi-start.
* The θ column of Eq. (28) (tool rotation) is not planned: the robots here are 3-DOF.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ..curves.bspline import (
    batch_basis,
    batch_combine,
    batch_end_control_points,
    derivative_control_points,
    make_spline,
    norm_peaks,
    yang_knots,
)
from ..model.errors import TaskError
from ..curves.peaks import _anti_diagonal_sum
from ..model.task import Task
from ..model.trajectory import CartesianPath

#: the paper's initial guess (τ6, τ7, τ9, τ10, λ1, λ2, λ3) [Yang2022, Sec. 2.3.1]
PAPER_INITIAL = (0.01, 0.21, 0.79, 0.99, 0.21, 0.50, 0.21)
PARAM_NAMES = ("tau6", "tau7", "tau9", "tau10", "lambda1", "lambda2", "lambda3")
#: a velocity (in units of the move's length scale, after ×T) below this is zero: its λ is degenerate
_ZERO = 1e-12


@dataclass(frozen=True)
class VelSettings:
    """Settings of the exact solve (recorded in results and table headers).

    ``margin``: minimum gap kept between consecutive knots 0, τ6, τ7, ½, τ9, τ10, 1 (Eq. 36 is an open set;
    min a_max is approached at its boundary, so this choice sets min a_max and F).
    ``samples_per_piece``: points per knot span of the epigraph constraints (final peaks are exact).
    ``starts``: quasi-random (Kronecker sequence) candidates evaluated in the coarse stage; ``refine`` (``refine_F``): local
    SLSQP runs for each minimum (for F) from the best distinct candidates (the paper's initial guess is
    always a candidate). ``check_ratio`` (:func:`solve_seeded` only): a start of the a_max or j_max stage
    other than the seed is screened only when its sampled peak is below the result's times this (default:
    always; at 1.2 fewer runs, but a better basin is missed on about 1 % of moves: README); the bound is
    the seed's sampled peak times this. ``max_rounds`` (:func:`solve_seeded` only): evaluation rounds
    after which a run is cut off and its best feasible point taken (the long tails are line searches
    stalling at round-off, ~1 run in 50; 30 lost the optimum on 2 of 200 held-out moves, 40 and 50 none).
    """

    margin: float = 0.01
    samples_per_piece: int = 8
    starts: int = 256
    refine: int = 2
    refine_F: int = 2
    ftol: float = 1e-9
    screen_ftol: float = 1e-5
    screen_maxiter: int = 100
    radius: float = 0.05
    maxiter: int = 100
    check_ratio: float = math.inf
    max_rounds: int = 50

    def __post_init__(self) -> None:
        if not (0.0 < self.margin <= 0.1):
            raise TaskError(f"margin = {self.margin!r}: the knot margin must lie in (0, 0.1]")
        if self.samples_per_piece < 4 or self.refine < 1 or self.starts < 1 or self.max_rounds < 2:
            raise TaskError("samples_per_piece >= 4, refine >= 1, starts >= 1 and max_rounds >= 2 are required")


# ------------------------------------------------------------------------------------------ the problem


@dataclass(frozen=True)
class VelProblem:
    """The normalised problem of one move at one duration: lengths divided by ``scale`` [m], τ ∈ [0, 1].

    ``base`` (5, 3): s0, s1′, s2′, s3′, s4 of Eq. (28) relative to s0; ``offset`` (3, 3): the directions
    multiplied by λ1, λ2, λ3 in Eq. (25)–(27), i.e. v0·T, (v0 − v1)·T/2, −v1·T; ``v_start``, ``v_end``
    (3,): the end velocities in normalised time, v0·T and v1·T (all divided by ``scale``).
    """

    base: np.ndarray
    offset: np.ndarray
    v_start: np.ndarray
    v_end: np.ndarray
    scale: float

    @property
    def lambda_free(self) -> tuple[bool, bool, bool]:
        """Which λ_i changes the path (a zero offset direction makes its λ degenerate)."""
        return tuple(bool(np.linalg.norm(o) > _ZERO) for o in self.offset)  # type: ignore[return-value]


def make_problem(task: Task, duration: float) -> VelProblem:
    """The normalised problem of ``task`` run in ``duration`` seconds [Yang2022, Eq. (24)–(28)]."""
    T = float(duration)
    if not (math.isfinite(T) and T > 0):
        raise TaskError(f"duration = {duration!r}: must be a finite number of seconds > 0")
    scale = float(np.linalg.norm(task.p_to - task.p_from))
    base = (task.via_points() - task.p_from) / scale
    v0 = task.v_from * T / scale
    v1 = task.v_to * T / scale
    offset = np.vstack([v0, (v0 - v1) / 2.0, -v1])
    return VelProblem(base, offset, v0, v1, scale)


def groups(task: Task, duration: float) -> dict[str, float]:
    """The dimensionless groups the optimum depends on: h/b, η, and v·T/b resolved along the move (e_u),
    across it (e_z × e_u, to the left) and vertically, for both ends."""
    b = task.b
    if b <= 0:
        raise TaskError("from/to are vertically aligned (b = 0): the groups v·T/b and h/b need a horizontal move")
    eu = task.e_u
    ec = np.array([-eu[1], eu[0], 0.0])
    ez = np.array([0.0, 0.0, 1.0])
    out = {"h_over_b": task.height / b, "eta": task.eta}
    for name, v in (("v0", task.v_from), ("v1", task.v_to)):
        w = v * duration / b
        out[f"{name}_along"] = float(w @ eu)
        out[f"{name}_across"] = float(w @ ec)
        out[f"{name}_vertical"] = float(w @ ez)
    out["dz_over_b"] = float((task.p_to[2] - task.p_from[2]) / b)
    return out


def task_from_groups(g: dict[str, float], b: float = 1.0, duration: float = 1.0) -> Task:
    """A canonical task with the given groups: from the origin along +x, width ``b`` [m], in ``duration``."""
    v0 = np.array([g["v0_along"], g["v0_across"], g.get("v0_vertical", 0.0)]) * b / duration
    v1 = np.array([g["v1_along"], g["v1_across"], g.get("v1_vertical", 0.0)]) * b / duration
    return Task(
        np.zeros(3), np.array([b, 0.0, g.get("dz_over_b", 0.0) * b]), g["h_over_b"] * b, g["eta"], v0, v1
    )


# -------------------------------------------------------------------------------- batched evaluation


_VIA_SPAN = np.array([7, 8, 9])  # τ7, ½, τ9 evaluated on the span they open (the basis is C⁴ there)
_SPANS = np.arange(5, 11)  # the six non-empty knot spans [t5, t6] … [t10, t11]
_SHIFT_POWER = np.clip(np.subtract.outer(np.arange(6), np.arange(6)).T, 0, None)  # [r, q] = q − r (≥ 0)
_SHIFT_MASK = np.triu(np.ones((6, 6), bool))  # the Taylor shift of a quintic's state is upper triangular
_SHIFT_INDEX = np.where(_SHIFT_MASK, _SHIFT_POWER, 6)  # index 6: the zero below the diagonal
_INV_COUNT = 1.0 / np.arange(1, 6)  # step^k / k! as a running product
_UNIT = np.eye(16)  # y's unit rows
_START = np.zeros((6, 16))  # the state at τ = 0 in terms of y: s0, v0, 0, 0 known, snap and crackle unknown
_START[np.arange(4), np.arange(8, 12)] = 1.0
_START[4, 0] = _START[5, 1] = 1.0
_END = np.zeros((6, 16))  # the state at τ = 1: s4, v1, 0, 0 known, snap and crackle unknown
_END[np.arange(4), np.arange(12, 16)] = 1.0
_END[4, 4] = _END[5, 5] = 1.0
_DIAG3 = (np.arange(3), np.arange(3, 6))


class _Evaluator:
    """Acceleration and jerk of many parameter vectors at once (normalised units), at sample points given
    as (knot span k = 0 … 5, fraction u ∈ [0, 1] of it) — so the samples move with the knots."""

    def __init__(self, prob: VelProblem) -> None:
        self.prob = prob
        self.count = 0  # parameter vectors evaluated (for the benchmark)
        # the known end states [s0, v0, 0, 0, s4, v1, 0, 0] (the last 8 entries of prepare's y)
        self.known = np.zeros((8, 3))
        self.known[0], self.known[1], self.known[4], self.known[5] = prob.base[0], prob.v_start, prob.base[4], prob.v_end

    @staticmethod
    def knots(p: np.ndarray) -> np.ndarray:
        P = p.shape[0]
        k = np.empty((P, 17))
        k[:, :6] = 0.0
        k[:, 6], k[:, 7], k[:, 8], k[:, 9], k[:, 10] = p[:, 0], p[:, 1], 0.5, p[:, 2], p[:, 3]
        k[:, 11:] = 1.0
        return k

    def control_points(self, p: np.ndarray, knots: np.ndarray | None = None, n5: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(knots (P, 17), Q (P, 11, 3)) solving Eq. (16) with B = [s0 … s4, v0, 0, 0, v1, 0, 0] (11 × 1,
        not "6 × 1" as the text after Eq. (18) says). ``n5`` (P, 3, 6): the degree-5 basis at τ7, ½, τ9
        when the caller has it."""
        prob = self.prob
        P = p.shape[0]
        if knots is None:
            knots = self.knots(p)
        via = prob.base[None, :, :] + np.zeros((P, 1, 1))
        via[:, 1:4] += p[:, 4:7, None] * prob.offset[None, :, :]
        zeros = np.zeros((P, 2, 3))
        ds = np.concatenate([np.broadcast_to(prob.v_start, (P, 1, 3)), zeros], axis=1)
        de = np.concatenate([np.broadcast_to(prob.v_end, (P, 1, 3)), zeros], axis=1)
        q = np.empty((P, 11, 3))
        q[:, :4] = batch_end_control_points(knots, via[:, 0], ds)
        q[:, 7:] = batch_end_control_points(knots, via[:, 4], de, at_end=True)
        if n5 is None:
            n5 = batch_basis(knots, knots[:, [7, 8, 9]], _VIA_SPAN, 5)  # (P, 3, 6): N_{s−5 … s, 5}, s = 7, 8, 9
        a = np.zeros((P, 3, 11))
        for row, s in enumerate(_VIA_SPAN):
            a[:, row, s - 5 : s + 1] = n5[:, row]
        rhs = via[:, 1:4] - a[:, :, :4] @ q[:, :4] - a[:, :, 7:] @ q[:, 7:]
        q[:, 4:7] = np.linalg.solve(a[:, :, 4:7], rhs)
        return knots, q

    def prepare(self, p: np.ndarray, lambda_rows: np.ndarray | None = None) -> tuple[np.ndarray, ...]:
        """(widths (P, 6), D (P, 6, 4, 3)) of parameters p (P, 7): the knot spans' widths and, at the left
        end of each span, the derivatives of orders 2 … 5 (a, j, snap, crackle). The acceleration is cubic
        on a span, so these Taylor coefficients are exact: a(h) = D0 + D1 h + D2 h²/2 + D3 h³/6 at h = τ − τ_left.

        The same spline as Eq. (16) (quintic, C⁴ at the simple knots τ6, τ7, ½, τ9, τ10, through s0 … s4,
        with v, a, j = (v0, 0, 0) and (v1, 0, 0) at the ends), solved in piecewise-Taylor form rather than
        for B-spline control points — a departure for speed only, held to :meth:`prepare_bspline` and to
        scipy's BSpline by tests. Each span's state (derivatives 0 … 5 at its start) follows from the
        previous one by the exact Taylor shift of a quintic; only the crackle (constant on a span) is new.
        Shooting from τ = 0 forwards over the first three spans and from τ = 1 backwards over the last
        three (half the distance: well conditioned), the unknowns are snap and crackle at each end and the
        crackles of the four inner spans (8), fixed by the via points at τ7, ½, τ9 and C⁴ continuity at ½
        (8): one 8 × 8 solve per parameter vector and about 30 numpy calls for the batch, where the
        Cox–de Boor route takes about 150 (the cost here is per call, not per vector).

        ``lambda_rows``: also return, for those rows, ∂D/∂λ1 … ∂λ3 (R, 3, 6, 4, 3) — exact, since the path is
        affine in λ (Eq. 25–27); one solve with three more right-hand sides."""
        p = np.atleast_2d(p)
        P = p.shape[0]
        self.count += P
        starts = np.empty((P, 7))
        starts[:, 0], starts[:, 3], starts[:, 6] = 0.0, 0.5, 1.0
        starts[:, 1], starts[:, 2], starts[:, 4], starts[:, 5] = p[:, 0], p[:, 1], p[:, 2], p[:, 3]
        w = np.diff(starts, axis=1)
        step = np.concatenate([w[:, :3], -w[:, 3:]], axis=1)  # forwards on the left half, backwards on the right
        powers = np.zeros((P, 6, 7))  # step^k / k!, k = 0 … 5, and a zero for the lower triangle
        powers[:, :, 0] = 1.0
        np.cumprod(step[..., None] * _INV_COUNT, axis=2, out=powers[:, :, 1:6])
        shift = powers[:, :, _SHIFT_INDEX]  # (P, 6, 6, 6): [k, r, q] = step_k^(q−r) / (q−r)! for q ≥ r
        # y = [z (8 unknowns), s0, v0, 0, 0, s4, v1, 0, 0]; G[:, k] maps y to the state at the start of span k
        G = np.empty((P, 6, 6, 16))
        G[:, 0] = _START  # s0, v0, 0, 0 and the unknown snap, crackle at τ = 0
        for k in (0, 1):
            G[:, k + 1] = shift[:, k] @ G[:, k]
            G[:, k + 1, 5] = _UNIT[k + 2]  # the crackle of spans 1, 2
        half = shift[:, 2] @ G[:, 2]  # the state at ½ from the left
        end = _END  # the state at τ = 1: s4, v1, 0, 0, snap, crackle (of span 5)
        for k, crackle in ((5, 6), (4, 7), (3, None)):
            G[:, k] = shift[:, k] @ end  # the end of span k − 1 is the start of span k
            if crackle is not None:
                end = G[:, k].copy()
                end[:, 5] = _UNIT[crackle]  # the crackle of spans 4, 3
        rows = np.concatenate([G[:, 2, :1], G[:, 3, :1], G[:, 4, :1], half[:, :5] - G[:, 3, :5]], axis=1)
        prob = self.prob
        via = prob.base[1:4][None] + p[:, 4:7, None] * prob.offset[None]  # s1, s2, s3 of Eq. (25)–(27)
        known = self.known
        rhs = np.zeros((P, 8, 3 if lambda_rows is None else 6))
        rhs[:, :3, :3] = via
        rhs[:, :, :3] -= rows[:, :, 8:] @ known
        if lambda_rows is not None:
            rhs[:, _DIAG3[0], _DIAG3[1]] = 1.0  # columns 0–2 of the inverse: the via points' weights
        z = np.linalg.solve(rows[:, :, :8], rhs)
        d = G[:, :, 2:6, :8] @ z[:, None, :, :3] + G[:, :, 2:6, 8:] @ known
        if lambda_rows is None:
            return w, d
        # the path is affine in λ (Eq. 25–27: via point i moves by λ_i·offset_i): ∂d/∂λ_i exactly
        inv = z[lambda_rows, :, 3:]  # (R, 8, 3)
        g = G[lambda_rows][:, :, 2:6, :8]  # (R, 6, 4, 8)
        dl = np.einsum("rsok,rki->riso", g, inv)  # (R, 3, 6, 4)
        return w, d, dl[..., None] * prob.offset[None, :, None, None, :]  # (R, 3, 6, 4, 3)

    def prepare_bspline(self, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`prepare` by the B-spline route: control points of Eq. (16), derivatives from the control
        points of the derivative splines [Yang2022, Eq. (12)–(14), continued] on the Cox–de Boor basis
        (shared ``bspline`` machinery). The reference for :meth:`prepare` in tests."""
        p = np.atleast_2d(p)
        knots = self.knots(p)
        left = knots[:, 5:11]  # the six span starts 0, τ6, τ7, ½, τ9, τ10 (τ7, ½, τ9 are the via points)
        basis = batch_basis(knots, left, _SPANS, 5, all_degrees=True)
        knots, q = self.control_points(p, knots, basis[5][:, 2:5])
        ctrl = derivative_control_points(knots, q, 5)
        d = np.stack([batch_combine(basis[5 - r], _SPANS, ctrl[r], r) for r in (2, 3, 4, 5)], axis=2)
        return np.diff(knots[:, 5:12], axis=1), d

    @staticmethod
    def derivatives(prep: tuple, piece: np.ndarray, u: np.ndarray, count: int = 2) -> list[np.ndarray]:
        """[a, j, snap, crackle][:count], each (P, M, 3), at the samples (piece, u) of prepared parameters."""
        width, d = prep
        h = (u * width[:, piece])[..., None]  # (P, M, 1) offset from the span start
        c = d[:, piece]  # (P, M, 4, 3)
        out = [c[:, :, 0] + h * (c[:, :, 1] + h * (c[:, :, 2] / 2 + h * c[:, :, 3] / 6))]
        if count > 1:
            out.append(c[:, :, 1] + h * (c[:, :, 2] + h * c[:, :, 3] / 2))
        if count > 2:
            out.append(c[:, :, 2] + h * c[:, :, 3])
        if count > 3:
            out.append(c[:, :, 3])
        return out

    @classmethod
    def values(cls, prep: tuple, piece: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(‖a‖², ‖j‖²), each (P, M), at the samples (piece, u) of prepared parameters."""
        acc, jerk = cls.derivatives(prep, piece, u)
        return np.einsum("pmd,pmd->pm", acc, acc), np.einsum("pmd,pmd->pm", jerk, jerk)

    def grid_maxima(self, p: np.ndarray, per_piece: int) -> tuple[np.ndarray, np.ndarray]:
        """(max ‖a‖², max ‖j‖²), each (P,), over the samples of :func:`_grid` (``per_piece`` on each knot
        span and τ = 1): ``sampled(p, *_grid(per_piece))`` maximised, without gathering per sample (in
        blocks of 128 vectors: the temporaries stay in cache)."""
        if len(p) > 128:
            parts = [self.grid_maxima(p[i : i + 128], per_piece) for i in range(0, len(p), 128)]
            return np.concatenate([a for a, _ in parts]), np.concatenate([j for _, j in parts])
        width, d = self.prepare(p)
        h = (width[:, :, None] * (np.arange(per_piece) / per_piece))[..., None]  # (P, 6, per, 1)
        c = d[:, :, None]  # (P, 6, 1, 4, 3)
        acc = c[..., 0, :] + h * (c[..., 1, :] + h * (c[..., 2, :] / 2 + h * c[..., 3, :] / 6))
        jerk = c[..., 1, :] + h * (c[..., 2, :] + h * c[..., 3, :] / 2)
        w, e = width[:, 5, None], d[:, 5]  # τ = 1: the end of the last span
        acc_end = e[:, 0] + w * (e[:, 1] + w * (e[:, 2] / 2 + w * e[:, 3] / 6))
        jerk_end = e[:, 1] + w * (e[:, 2] + w * e[:, 3] / 2)
        ga = np.maximum(np.einsum("psud,psud->psu", acc, acc).reshape(len(width), -1).max(axis=1), np.einsum("pd,pd->p", acc_end, acc_end))
        gj = np.maximum(np.einsum("psud,psud->psu", jerk, jerk).reshape(len(width), -1).max(axis=1), np.einsum("pd,pd->p", jerk_end, jerk_end))
        return ga, gj

    def sampled(self, p: np.ndarray, piece: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(‖a‖², ‖j‖²) at the samples (piece, u), each (P, M) (normalised: lengths / scale, T = 1)."""
        return self.values(self.prepare(p), piece, u)


def _grid(per_piece: int) -> tuple[np.ndarray, np.ndarray]:
    """(piece, u) of ``per_piece`` + 1 points on each of the 6 knot spans (shared ends once)."""
    u = np.linspace(0.0, 1.0, per_piece + 1)
    piece = np.repeat(np.arange(6), per_piece)
    uu = np.tile(u[:-1], 6)
    return np.append(piece, 5), np.append(uu, 1.0)


def spline_of(prob: VelProblem, params) -> Any:
    """scipy BSpline (normalised: lengths / ``prob.scale``, τ ∈ [0, 1]) of full parameters p (7,)."""
    p = np.asarray(params, float).reshape(1, 7)
    yang_knots(*p[0, :4])  # validates Eq. (36)
    knots, q = _Evaluator(prob).control_points(p)
    return make_spline(knots[0], q[0])


def exact_peaks(prob: VelProblem, params) -> tuple[float, float, float]:
    """Exact (v_max, a_max, j_max) of Eq. (34)–(35) in the problem's normalised units."""
    return norm_peaks(spline_of(prob, params), (1, 2, 3))  # type: ignore[return-value]


# ------------------------------------------------------------------------------------------ optimiser


@dataclass(frozen=True)
class VelResult:
    """Optimum of Eq. (37) for one problem (peaks normalised: lengths / scale, T = 1).

    ``params`` (τ6, τ7, τ9, τ10, λ1, λ2, λ3); ``a_max``, ``j_max``, ``v_max`` exact peaks there; ``a_min``,
    ``j_min`` the stage-1 minima (the normalisers of F); ``F`` ≤ 2; ``lambda_free`` which λ were optimised;
    ``params_a``, ``params_j`` the minimisers of a_max and j_max; ``evaluations`` parameter vectors evaluated.
    """

    params: tuple[float, ...]
    a_max: float
    j_max: float
    v_max: float
    a_min: float
    j_min: float
    F: float
    lambda_free: tuple[bool, bool, bool]
    params_a: tuple[float, ...]
    params_j: tuple[float, ...]
    settings: VelSettings = field(default_factory=VelSettings)
    evaluations: int = 0

    def as_dict(self) -> dict[str, Any]:
        d = dict(zip(PARAM_NAMES, self.params))
        d.update(F=self.F, a_min=self.a_min, j_min=self.j_min, margin=self.settings.margin,
                 lambda_free=list(self.lambda_free))
        return d


def _quasi_random(n: int, d: int) -> np.ndarray:
    """n points of the unit cube [0, 1)^d from the Kronecker (R_d) low-discrepancy sequence: frac(k·α) with
    α_i = φ_d^−i, φ_d the real root of x^(d+1) = x + 1 (Roberts 2018). Deterministic, no import cost."""
    phi = 2.0
    for _ in range(40):
        phi = (1.0 + phi) ** (1.0 / (d + 1))
    alpha = phi ** -np.arange(1, d + 1)
    return np.mod(0.5 + np.arange(1, n + 1)[:, None] * alpha[None, :], 1.0)


class _Space:
    """Free variables x ↔ full parameters p; bounds and the linear ordering constraints of Eq. (36)."""

    def __init__(self, free_lambda: tuple[bool, bool, bool], margin: float) -> None:
        self.free = np.array([True] * 4 + list(free_lambda))
        self.fixed = np.array(PAPER_INITIAL)
        m = margin
        lo = np.array([m, 2 * m, 0.5 + m, 0.5 + 2 * m, 0.0, 0.0, 0.0])
        hi = np.array([0.5 - 2 * m, 0.5 - m, 1 - 2 * m, 1 - m, 1.0, 1.0, 1.0])
        self.lo, self.hi = lo[self.free], hi[self.free]
        self.m = m
        self.n = int(self.free.sum())

    def full(self, x: np.ndarray) -> np.ndarray:
        x = np.atleast_2d(x)
        p = np.broadcast_to(self.fixed, (x.shape[0], 7)).copy()
        p[:, self.free] = x
        return p

    def order_gaps(self, x: np.ndarray) -> np.ndarray:
        """τ7 − τ6 − m and τ10 − τ9 − m (≥ 0 when feasible); the rest are bounds."""
        return np.array([x[1] - x[0] - self.m, x[3] - x[2] - self.m])

    def order_jac(self) -> np.ndarray:
        j = np.zeros((2, self.n))
        j[0, 0], j[0, 1], j[1, 2], j[1, 3] = -1.0, 1.0, -1.0, 1.0
        return j

    def from_unit(self, u: np.ndarray) -> np.ndarray:
        """Map points of the unit cube onto the feasible set (knots in order, gaps ≥ margin)."""
        m = self.m
        x = np.empty_like(u)
        t7 = 2 * m + u[:, 1] * (0.5 - 3 * m)
        t6 = m + u[:, 0] * (t7 - 2 * m)
        t9 = 0.5 + m + u[:, 2] * (0.5 - 3 * m)
        t10 = t9 + m + u[:, 3] * (1 - m - t9 - m)
        x[:, 0], x[:, 1], x[:, 2], x[:, 3] = t6, t7, t9, t10
        x[:, 4:] = u[:, 4:]
        return x

    def clip(self, x: np.ndarray) -> np.ndarray:
        x = np.clip(x, self.lo, self.hi)
        x[1] = max(x[1], x[0] + self.m)
        x[3] = max(x[3], x[2] + self.m)
        return np.clip(x, self.lo, self.hi)


def _distinct_best(x: np.ndarray, values: np.ndarray, count: int, radius: float = 0.05) -> list[np.ndarray]:
    order = np.argsort(values)
    picked: list[np.ndarray] = []
    for i in order:
        if all(np.max(np.abs(x[i] - y)) > radius for y in picked):
            picked.append(x[i])
            if len(picked) == count:
                break
    return picked


def _exact_segment_maxima(prep: tuple, q: int | tuple[int, ...], sub: int) -> np.ndarray:
    """u (6·sub·len(q),) of the maximum of ‖a‖² (q = 0) or ‖j‖² (q = 1) — or of each in the tuple ``q``, in
    that order — on each of the ``sub`` equal segments of every knot span, for the first parameter vector of
    ``prep`` (:func:`_segment_maxima` for several)."""
    return _segment_maxima(prep[0][:1], prep[1][:1], q, sub)[0]


def _poly_maps(k: int) -> tuple[np.ndarray, np.ndarray]:
    """(k², 7), (k², 6): from the products c_i·c_j of a degree-(k−1) vector polynomial's coefficients to
    the coefficients (lowest power first) of its squared norm, padded to degree 6, and of that norm's
    derivative, padded to degree 5 — for k = 3 (jerk) the cubic derivative times (u − 10)², which adds two
    roots far outside [0, 1], so that both quantities share one batch of 5 × 5 companion matrices."""
    if k not in _POLY_MAPS:
        sq = np.zeros((k * k, 7))
        sq[:, : 2 * k - 1] = _anti_diagonal_sum(k)
        deriv = sq[:, 1:] * np.arange(1, 7)  # degree 2k − 3
        if k == 3:
            cubic = deriv[:, :4].copy()
            deriv = np.zeros((k * k, 6))
            deriv[:, :4] += 100.0 * cubic
            deriv[:, 1:5] -= 20.0 * cubic
            deriv[:, 2:] += cubic
        _POLY_MAPS[k] = (sq, deriv)
    return _POLY_MAPS[k]


_POLY_MAPS: dict[int, tuple[np.ndarray, np.ndarray]] = {}


def _segment_maxima(width: np.ndarray, d: np.ndarray, q: int | tuple[int, ...], sub: int,
                    rows: tuple[np.ndarray, ...] | None = None) -> np.ndarray | list[np.ndarray]:
    """u (R, 6·sub·len(q)) of the maxima of ‖a‖² (q = 0) or ‖j‖² (q = 1) — or of each in the tuple ``q``,
    in that order — on each of the ``sub`` equal segments of every knot span, for R prepared parameter
    vectors (``width`` (R, 6), ``d`` (R, 6, 4, 3) from :meth:`_Evaluator.prepare`): exact, from the real
    roots of the derivative of the span's polynomial ‖·‖² (companion-matrix eigenvalues, one batched call
    for all vectors and quantities) and the segment ends. With ``rows`` (one index array per quantity in
    ``q``): only those vectors for each quantity, returned as a list of (len(rows[i]), 6·sub) arrays."""
    qs = (q,) if isinstance(q, (int, np.integer)) else tuple(q)
    sel = rows if rows is not None else tuple(np.arange(width.shape[0]) for _ in qs)
    sqs, derivs = [], []
    for qq, idx in zip(qs, sel):
        R = len(idx)
        w = width[idx]  # (R, 6)
        wk = np.empty((R, 6, 4, 1))  # w^k / k!
        wk[:, :, 0, 0] = 1.0
        wk[:, :, 1, 0] = w
        wk[:, :, 2, 0] = w * w / 2
        wk[:, :, 3, 0] = wk[:, :, 2, 0] * w / 3
        if qq == 0:  # a(u) = D0 + D1 (wu) + D2 (wu)²/2 + D3 (wu)³/6, coefficients in powers of u (lowest first)
            c = d[idx] * wk
        else:  # j(u) = D1 + D2 (wu) + D3 (wu)²/2
            c = d[idx][:, :, 1:] * wk[:, :, :3]
        k = c.shape[2]
        prod = (c @ c.transpose(0, 1, 3, 2)).reshape(R * 6, k * k)
        to_sq, to_deriv = _poly_maps(k)
        sqs.append(prod @ to_sq)  # ‖·‖² (degree 2k − 2, padded to 6), lowest power first
        derivs.append(prod @ to_deriv)  # its derivative (padded to degree 5)
    sq, deriv = (np.concatenate(sqs), np.concatenate(derivs)) if len(sqs) > 1 else (sqs[0], derivs[0])
    # rows: quantity, vector, span
    m = sq.shape[0]
    n = 5
    lead = deriv[:, -1]
    scale = np.max(np.abs(deriv), axis=1) + 1e-300
    lead = np.where(np.abs(lead) > 1e-13 * scale, lead, 1e-13 * scale)  # a dropped degree: roots go far away
    comp = np.zeros((m, n, n))
    comp[:, 0, :] = -deriv[:, -2::-1] / lead[:, None]
    comp[:, _SUBDIAG[0], _SUBDIAG[1]] = 1.0
    roots = np.linalg.eigvals(comp)
    ends = np.arange(sub + 1) / sub
    cand = np.empty((m, n + sub + 1))  # the real roots (non-real → −1, outside) and the segment ends
    cand[:, :n] = np.where(np.abs(roots.imag) <= 1e-9 * (1.0 + np.abs(roots.real)), roots.real, -1.0)
    cand[:, n:] = ends
    powers = np.empty((m, n + sub + 1, 7))
    powers[:, :, 0] = 1.0
    np.cumprod(np.broadcast_to(cand[:, :, None], (m, n + sub + 1, 6)), axis=2, out=powers[:, :, 1:])
    val = np.einsum("scp,sp->sc", powers, sq)
    inside = (cand[:, None, :] >= ends[:-1, None] - 1e-15) & (cand[:, None, :] <= ends[1:, None] + 1e-15)
    best = np.argmax(np.where(inside, val[:, None, :], -np.inf), axis=2)  # (m, sub)
    u = np.clip(cand[np.arange(m)[:, None], best], ends[:-1], ends[1:]).reshape(m // 6, 6 * sub)  # rows: quantity, vector
    parts, at = [], 0
    for idx in sel:
        parts.append(u[at : at + len(idx)])
        at += len(idx)
    if rows is not None:
        return parts
    return np.concatenate(parts, axis=1)


_SUBDIAG = (np.arange(1, 5), np.arange(4))  # the companion matrix's subdiagonal


class _Stage:
    """One stage of Eq. (37) by SLSQP in epigraph form.

    ``kind`` 'a' / 'j': minimise t subject to m_k(p) ≤ t, where m_k is the maximum of ‖a‖² (‖j‖²) over
    segment k — each knot span cut into ``SUB`` equal segments that move with the knots; 'F': maximise
    a_min/√ta + j_min/√tj subject to both sets. Each m_k is exact (:func:`_segment_maxima`); its
    gradient is that of ‖a(τ*)‖² with τ* held at the same fraction of the span (envelope theorem: the
    motion of the maximiser does not change the maximum to first order), by central differences evaluated
    as one batch. Segments short enough to hold a single local maximum keep every m_k smooth (a whole span
    can hold two humps whose swap is a kink that stalls SLSQP's line search; an m_k whose maximiser is
    off by even 1e-4 of the span has a gradient wrong enough to do the same). Final peaks are exact.
    The lower bounds ta ≥ a_min², tj ≥ j_min² (valid: t ≥ max ≥ min) keep F-steps from t → 0.
    Several SLSQP runs (of any stages of one problem) advance together, their evaluations batched
    (:func:`_run_slsqp`).
    """

    SUB = 3

    def __init__(self, ev: _Evaluator, space: _Space, kind: str, a_norm: float, j_norm: float, settings: VelSettings):
        self.ev, self.space, self.kind = ev, space, kind
        self.norm = np.array([a_norm, j_norm])  # scale of ‖a‖², ‖j‖² (values / norm ~ 1)
        self.s = settings
        self.h = 1e-6
        n = space.n
        # central differences in the four knots only (the path is affine in λ: those derivatives are exact)
        self._steps = np.vstack([np.zeros(n), self.h * np.eye(n)[:4], -self.h * np.eye(n)[:4]])
        self.uses = (0,) if kind == "a" else (1,) if kind == "j" else (0, 1)
        self._memo: dict[bytes, tuple[list, list]] = {}

    def _eval(self, x: np.ndarray) -> tuple[list, list]:
        """Per quantity used: the 6·SUB segment maxima at x and their Jacobians (memoised on x)."""
        return _eval_stages([(self, x)])[0]

    def objective(self, x: np.ndarray, a_min: float = 1.0, j_min: float = 1.0) -> float:
        """The stage's objective at x from its own (segment-maximum) peaks: max ‖a‖² or ‖j‖², or −F."""
        vals, _ = self._eval(x)
        if self.kind == "F":
            return -(a_min / math.sqrt(vals[0].max() * self.norm[0]) + j_min / math.sqrt(vals[1].max() * self.norm[1]))
        return float(vals[0].max())

    def run(self, x0: np.ndarray, a_min: float = 1.0, j_min: float = 1.0, ftol: float | None = None,
            maxiter: int | None = None, max_rounds: int | None = None) -> _Run:
        """One SLSQP run from x0 (to pass to :func:`_run_slsqp` or :class:`_Lockstep`)."""
        r = _Run(self, np.asarray(x0, float), a_min, j_min, ftol or self.s.ftol, maxiter or self.s.maxiter)
        if max_rounds is not None:
            r.max_rounds = max_rounds
        return r


def _eval_stages(requests: list[tuple[_Stage, np.ndarray]]) -> list[tuple[list, list]]:
    """(values, Jacobians) of each (stage, x) — see :meth:`_Stage._eval` — computed in one batch for
    those not memoised (all stages share one evaluator and space): the 2n + 1 central-difference vectors
    of every x in one :meth:`_Evaluator.prepare`, the segment maxima of ‖a‖² and ‖j‖² at every x in one
    :func:`_segment_maxima` call. The cost is per numpy call far more than per vector."""
    for stage, _ in requests:
        if len(stage._memo) > 2048:
            stage._memo.clear()
    todo: dict[tuple[int, bytes], tuple[_Stage, np.ndarray]] = {}
    for stage, x in requests:
        key = x.tobytes()
        if key not in stage._memo:
            todo[(id(stage), key)] = (stage, x)
    if todo:
        stage0 = requests[0][0]
        ev, space, steps, sub = stage0.ev, stage0.space, stage0._steps, _Stage.SUB
        n, S, m = space.n, steps.shape[0], 6 * sub
        xs = np.array([x for _, x in todo.values()])
        R = xs.shape[0]
        width, d, dlam = ev.prepare(space.full((xs[:, None, :] + steps[None]).reshape(-1, n)), np.arange(0, R * S, S))
        stages = [stage for stage, _ in todo.values()]
        rows = tuple(np.array([r for r, st in enumerate(stages) if q in st.uses], int) for q in (0, 1))
        us = _segment_maxima(width[::S], d[::S], (0, 1), sub, rows)  # per quantity (len(rows[q]), m)
        lam = space.free[4:]
        width, d = width.reshape(R, S, 6), d.reshape(R, S, 6, 4, 3)
        h2 = 2 * stage0.h
        out: dict[tuple[int, int], tuple[np.ndarray, np.ndarray]] = {}
        for q in (0, 1):
            rq = rows[q]
            if not len(rq):
                continue
            c = d[rq][:, :, :, None]  # (·, S, 6, 1, 4, 3)
            cl = dlam[rq][:, :, :, None]  # (·, 3, 6, 1, 4, 3)
            h = (us[q].reshape(-1, 1, 6, sub) * width[rq][..., None])[..., None]  # (·, S, 6, sub, 1) from the span start
            hl = h[:, :1]
            if q == 0:  # a = D0 + D1 h + D2 h²/2 + D3 h³/6
                val = c[..., 0, :] + h * (c[..., 1, :] + h * (c[..., 2, :] / 2 + h * c[..., 3, :] / 6))
                dv = cl[..., 0, :] + hl * (cl[..., 1, :] + hl * (cl[..., 2, :] / 2 + hl * cl[..., 3, :] / 6))
            else:  # j = D1 + D2 h + D3 h²/2
                val = c[..., 1, :] + h * (c[..., 2, :] + h * c[..., 3, :] / 2)
                dv = cl[..., 1, :] + hl * (cl[..., 2, :] + hl * cl[..., 3, :] / 2)
            sqq = np.einsum("rsuvd,rsuvd->rsuv", val, val).reshape(-1, S, m)
            gq = 2.0 * np.einsum("rsuvd,riuvd->riuv", val[:, :1], dv).reshape(-1, 3, m)[:, lam]  # ∂‖·‖²/∂λ
            norm = np.array([stages[r].norm[q] for r in rq])[:, None, None]
            jac = np.concatenate([(sqq[:, 1:5] - sqq[:, 5:9]) / h2, gq], axis=1).transpose(0, 2, 1) / norm
            vals = sqq[:, 0] / norm[:, 0]
            for i, r in enumerate(rq):
                out[(q, r)] = (vals[i], jac[i])
        for r, ((_, key), stage) in enumerate(zip(todo, stages)):
            stage._memo[key] = ([out[(q, r)][0] for q in stage.uses], [out[(q, r)][1] for q in stage.uses])
    return [stage._memo[x.tobytes()] for stage, x in requests]


class _Run:
    """One SLSQP run of a stage in epigraph form: y = (x, t…), minimise t (or −F(t)) subject to
    t_q ≥ m_k(x) for every segment k of each quantity q used, and the ordering constraints of Eq. (36)."""

    def __init__(self, stage: _Stage, x0: np.ndarray, a_min: float, j_min: float, ftol: float, maxiter: int):
        self.stage, self.x0, self.ftol, self.maxiter = stage, x0, ftol, maxiter
        self.max_rounds = 10**9  # evaluation rounds before the run is cut off (solve_seeded: settings.max_rounds)
        self.a_min, self.j_min = a_min, j_min
        self.n, self.k = stage.space.n, len(stage.uses)
        norm = stage.norm
        self.cf = (a_min / math.sqrt(norm[0]), j_min / math.sqrt(norm[1]))
        # t ≥ max‖·‖² ≥ (its minimum)²: a valid bound that keeps SLSQP's F-steps from t → 0
        self.floor = [(a_min**2 / norm[0]), (j_min**2 / norm[1])]
        sp = stage.space
        if stage.kind == "F":
            tlo = [self.floor[q] * (1 - 1e-6) for q in stage.uses]
        else:
            tlo = [1e-12]
        self.lo = np.concatenate([sp.lo, tlo])
        self.hi = np.concatenate([sp.hi, [np.inf] * self.k])
        # the constant part of the constraint normals: the t columns and the ordering rows
        m = 6 * _Stage.SUB
        self.normals = np.zeros((self.k * m + 2, self.n + self.k), order="F")
        for i in range(self.k):
            self.normals[i * m : (i + 1) * m, self.n + i] = 1.0
        self.normals[-2:, : self.n] = sp.order_jac()

    def y0(self, vals: list) -> np.ndarray:
        y0 = np.concatenate([self.x0, [v.max() * (1 + 1e-9) for v in vals]])
        if self.stage.kind == "F":
            y0[self.n:] = np.maximum(y0[self.n:], self.floor)
        return y0

    def fun(self, y: np.ndarray) -> float:
        n = self.n
        if self.stage.kind == "F":
            return -(self.cf[0] / math.sqrt(y[n]) + self.cf[1] / math.sqrt(y[n + 1]))
        return float(y[n])

    def grad(self, y: np.ndarray) -> np.ndarray:
        n = self.n
        g = np.zeros(n + self.k)
        if self.stage.kind == "F":
            g[n] = 0.5 * self.cf[0] * y[n] ** -1.5
            g[n + 1] = 0.5 * self.cf[1] * y[n + 1] ** -1.5
        else:
            g[n] = 1.0
        return g

    def cons(self, y: np.ndarray, vals: list) -> np.ndarray:
        n = self.n
        return np.concatenate([y[n + i] - v for i, v in enumerate(vals)] + [self.stage.space.order_gaps(y[:n])])

    def fill_cons(self, out: np.ndarray, y: np.ndarray, vals: list) -> None:
        """:meth:`cons` written into ``out``."""
        n, m, gap = self.n, 6 * _Stage.SUB, self.stage.space.m
        for i, v in enumerate(vals):
            np.subtract(y[n + i], v, out=out[i * m : (i + 1) * m])
        out[-2] = y[1] - y[0] - gap
        out[-1] = y[3] - y[2] - gap

    def fill_normals(self, out: np.ndarray, jacs: list) -> None:
        """:meth:`cjac` written into ``out``, whose constant part (:attr:`normals`) is already there."""
        m = 6 * _Stage.SUB
        for i, d in enumerate(jacs):
            np.negative(d, out=out[i * m : (i + 1) * m, : self.n])

    def cjac(self, jacs: list) -> np.ndarray:
        out = self.normals.copy(order="F")
        m = 6 * _Stage.SUB
        for i, d in enumerate(jacs):
            out[i * m : (i + 1) * m, : self.n] = -d
        return out

    def feasible(self, x: np.ndarray) -> bool:
        """x (free variables) within the bounds and the ordering of Eq. (36), to 1e-12."""
        sp = self.stage.space
        return bool((x - sp.lo).min() >= -1e-12 and (sp.hi - x).min() >= -1e-12 and sp.order_gaps(x).min() >= -1e-12)


def _run_slsqp(runs: list[_Run]) -> list[np.ndarray]:
    """The results x (free variables, clipped to the feasible set) of several SLSQP runs of stages of one
    problem, advanced together (:class:`_Lockstep`)."""
    lock = _Lockstep()
    handles = [lock.add(r) for r in runs]
    while lock.active:
        lock.step()
    return [h.result() for h in handles]


class _Lockstep:
    """SLSQP runs of stages of one problem advanced together: each :meth:`step` evaluates the points all
    active runs ask for in one batch (:func:`_eval_stages`), so k runs cost about as many numpy calls as
    the longest of them alone. Runs may be added (and dropped) between steps.

    Each run is exactly scipy's SLSQP (``minimize(method="SLSQP")``: the same reverse-communication
    routine, bounds and tolerances, driven as ``scipy.optimize._minimize_slsqp`` drives it), cut off after
    ``_Run.max_rounds`` evaluation rounds (then its best feasible point counts). That routine is private
    scipy API: it is used only on the scipy versions this driver was checked against
    (``_SLSQP_VERSIONS``; a test compares it with ``minimize``); on any other version, or where it is
    missing, each run goes through ``minimize`` when added — the same results, slower."""

    def __init__(self) -> None:
        self.routine = _slsqp_routine()
        self.active: list[_LockstepSLSQP] = []

    def add(self, run: _Run) -> _LockstepSLSQP:
        st = _LockstepSLSQP(run, self.routine)
        if self.routine is None:
            st.finish_serial()
        else:
            self.active.append(st)
        return st

    def drop(self, states: list[_LockstepSLSQP]) -> None:
        self.active = [st for st in self.active if st not in states]

    def step(self) -> None:
        _eval_stages([(st.run.stage, st.want) for st in self.active])
        still = []
        for st in self.active:
            st.rounds += 1
            if st.advance() and st.rounds < st.run.max_rounds:
                still.append(st)
            else:
                st.done = True
        self.active = still


#: scipy (major, minor) versions whose private SLSQP routine the lockstep driver was checked against
#: (scipy 1.16 rewrote SLSQP; 1.17.1 tested): [first, last)
_SLSQP_VERSIONS = ((1, 16), (1, 18))


def _slsqp_routine():
    """scipy's private SLSQP routine on a checked scipy version, else None (then the public ``minimize``)."""
    import scipy

    try:
        version = tuple(int(x) for x in scipy.__version__.split(".")[:2])
    except ValueError:
        return None
    if not (_SLSQP_VERSIONS[0] <= version < _SLSQP_VERSIONS[1]):
        return None
    try:
        from scipy.optimize._slsqplib import slsqp
    except ImportError:
        return None
    return slsqp


def _run_one(r: _Run, y0: np.ndarray) -> np.ndarray:
    from scipy.optimize import minimize

    n = r.n
    res = minimize(
        r.fun, y0, jac=r.grad, method="SLSQP", bounds=list(zip(r.lo, [None if not math.isfinite(h) else h for h in r.hi])),
        constraints=[{"type": "ineq", "fun": lambda y: r.cons(y, r.stage._eval(y[:n].copy())[0]),
                      "jac": lambda y: r.cjac(r.stage._eval(y[:n].copy())[1])}],
        options={"ftol": r.ftol, "maxiter": r.maxiter},
    )
    return r.stage.space.clip(np.asarray(res.x[:n], float))


class _LockstepSLSQP:
    """scipy's SLSQP driver loop (``scipy.optimize._slsqp_py._minimize_slsqp``) for one run, stepped:
    :meth:`advance` calls the routine until it needs constraint values or normals at a point not yet
    evaluated (``want``), or stops. Same set-up as scipy's: x0 clipped to the bounds, infinite bounds as
    NaN, the same work-space sizes, acc = ftol, the objective evaluated at the bounds-clipped point."""

    def __init__(self, run: _Run, routine) -> None:
        self.run, self.routine = run, routine
        self.rounds, self.done = 0, False
        self.need = "start"  # first the values at x0 (the starting t), then f, g, constraints and normals
        self.want = run.x0
        self.seen: list[np.ndarray] = []  # the points evaluated for values (for a run cut off)
        self._result: np.ndarray | None = None

    def finish_serial(self) -> None:
        """Run to the end through ``scipy.optimize.minimize`` (no lockstep routine available)."""
        vals = self.run.stage._eval(self.run.x0)[0]
        self._result = _run_one(self.run, self.run.y0(vals))
        self.done = True

    def _setup(self, y0: np.ndarray) -> None:
        run = self.run
        n = y0.size
        self.x = np.clip(y0, run.lo, run.hi).astype(float)
        self.xl = np.where(np.isfinite(run.lo), run.lo, np.nan)
        self.xu = np.where(np.isfinite(run.hi), run.hi, np.nan)
        m = run.k * 6 * _Stage.SUB + 2
        self.state = {"acc": run.ftol, "alpha": 0.0, "f0": 0.0, "gs": 0.0, "h1": 0.0, "h2": 0.0, "h3": 0.0,
                      "h4": 0.0, "t": 0.0, "t0": 0.0, "tol": 10.0 * run.ftol, "exact": 0, "inconsistent": 0,
                      "reset": 0, "iter": 0, "itermax": int(run.maxiter), "line": 0, "m": m, "meq": 0,
                      "mode": 0, "n": n}
        self.indices = np.zeros(max(m + 2 * n + 2, 1), dtype=np.int32)
        size = n * (n + 1) // 2 + 3 * m * n - (m + 5 * n + 7) * 0 + 9 * m + 8 * n * n + 35 * n + 28
        self.buffer = np.zeros(max(size, 1))
        self.mult = np.zeros(max(1, m + 2 * n + 2))
        self.C = run.normals.copy(order="F")  # the constant part; fill_normals writes the rest
        self.d = np.zeros(m)
        self.need = "both"  # the initial call needs f, g, constraints and normals
        self.want = self._xpart()

    def result(self) -> np.ndarray:
        """x at the end (clipped to the feasible set); when the run was cut off (``max_rounds``), the best
        feasible point it evaluated (objective from the exact segment maxima)."""
        r = self.run
        if self._result is not None:
            return self._result
        if self.need == "start":
            return r.stage.space.clip(r.x0.copy())
        if abs(self.state["mode"]) == 1:
            best = None
            for x in self.seen:
                if r.feasible(x):
                    vals = r.stage._eval(x)[0]
                    if r.stage.kind == "F":
                        f = -(r.cf[0] / math.sqrt(vals[0].max()) + r.cf[1] / math.sqrt(vals[1].max()))
                    else:
                        f = float(vals[0].max())
                    if best is None or f < best[0]:
                        best = (f, x)
            if best is not None:
                return best[1]
        return r.stage.space.clip(np.asarray(self.x[: r.n], float))

    def _xpart(self) -> np.ndarray:
        return self.x[: self.run.n].copy()

    def advance(self) -> bool:
        """Step until an evaluation not yet memoised is needed (True) or the run has stopped (False)."""
        r, stage = self.run, self.run.stage
        while True:
            key = self.want.tobytes()
            if key not in stage._memo:
                return True
            vals, jacs = stage._memo[key]
            if self.need == "start":
                self._setup(r.y0(vals))
                continue
            if self.need in ("both", "f"):
                self.seen.append(self.want)
                xf = np.clip(self.x, r.lo, r.hi) if self.need == "both" else self.x
                self.fx = r.fun(xf)
                r.fill_cons(self.d, self.x, vals)
            if self.need in ("both", "g"):
                xg = np.clip(self.x, r.lo, r.hi) if self.need == "both" else self.x
                self.g = r.grad(xg)
                r.fill_normals(self.C, jacs)
            self.routine(self.state, self.fx, self.g, self.C, self.d, self.x, self.mult, self.xl, self.xu,
                         self.buffer, self.indices)
            mode = self.state["mode"]
            if abs(mode) != 1:
                return False
            self.need = "f" if mode == 1 else "g"
            self.want = self._xpart()


def solve(prob: VelProblem, settings: VelSettings = VelSettings(), warm: VelResult | None = None) -> VelResult:
    """The two-stage optimum of [Yang2022, Eq. (37)] under Eq. (36) with ``settings.margin``.

    Global: coarse quasi-random candidates, then SLSQP from the best distinct ones (module docstring).
    ``warm``: the optimum of a nearby problem (e.g. the same move at a slightly different duration); each
    stage then runs once, from that optimum's own point — a local continuation, used while searching
    over T; the caller confirms the end result with a global solve."""
    ev = _Evaluator(prob)
    free = prob.lambda_free
    space = _Space(free, settings.margin)
    if warm is not None and tuple(warm.lambda_free) == tuple(free):
        starts = {k: space.clip(np.asarray(p)[space.free]) for k, p in (("a", warm.params_a), ("j", warm.params_j), ("F", warm.params))}
        cand = np.vstack(list(starts.values()))
        pick = {"a": [starts["a"]], "j": [starts["j"]]}
    else:
        cand = space.from_unit(_quasi_random(settings.starts, space.n))
        cand = np.vstack([np.array(PAPER_INITIAL)[space.free][None, :], cand])
        starts = None
    ga, gj = ev.sampled(space.full(cand), *_grid(settings.samples_per_piece))
    amax, jmax = ga.max(axis=1), gj.max(axis=1)
    a_norm, j_norm = float(amax.min()), float(jmax.min())
    if starts is None:
        # min a_max and min j_max can each have a local minimum with an end knot on the margin (τ6 = m or
        # τ10 = 1 − m) and another inside: start from the best candidate of each kind
        inner = (cand[:, 0] >= 3 * settings.margin) & (cand[:, 3] <= 1 - 3 * settings.margin)
        pick = {}
        for kind, vals in (("a", amax), ("j", jmax)):
            best = _distinct_best(cand, vals, settings.refine, settings.radius)
            if not inner[int(np.argmin(vals))] and inner.any():
                best = best[:1] + [cand[inner][int(np.argmin(vals[inner]))]] + best[1:]
            pick[kind] = best[: max(settings.refine, 2)]

    def exact(x: np.ndarray) -> tuple[float, float, float]:
        return exact_peaks(prob, space.full(x)[0])

    best = {}
    stages = {kind: _Stage(ev, space, kind, a_norm, j_norm, settings) for kind in ("a", "j")}
    jobs = [(kind, stages[kind].run(x0)) for kind in ("a", "j") for x0 in pick[kind]]
    done = list(zip([kind for kind, _ in jobs], _run_slsqp([r for _, r in jobs])))  # all runs together
    for kind, idx in (("a", 1), ("j", 2)):
        runs = [x for k, x in done if k == kind]
        peaks = [exact(x)[idx] for x in runs]
        k = int(np.argmin(peaks))
        best[kind] = (runs[k], peaks[k])
    xa, a_min = best["a"]
    xj, j_min = best["j"]
    if starts is None:
        pool = np.vstack([cand, xa, xj])
        ga, gj = ev.sampled(space.full(pool), *_grid(settings.samples_per_piece))
        f_pool = a_min / np.sqrt(ga.max(axis=1)) + j_min / np.sqrt(gj.max(axis=1))
        # the best sampled candidate (often the minimiser of j_max), the midpoint of the two minimisers and
        # the minimiser of a_max: F trades a_max against j_max, and its basins lie between the two
        order = [pool[int(np.argmax(f_pool))], (xa + xj) / 2, xa] + _distinct_best(pool, -f_pool, settings.refine_F)
        f_starts = _distinct_best(np.array(order), np.arange(len(order)), settings.refine_F, radius=1e-3)
    else:
        f_starts = [starts["F"]]
    stage = _Stage(ev, space, "F", a_norm, j_norm, settings)
    if len(f_starts) > 2:
        # screen every start with a loose tolerance, then polish the best one (basins differ by > 1e-3 in F)
        screened = _run_slsqp([stage.run(x0, a_min, j_min, settings.screen_ftol, settings.screen_maxiter) for x0 in f_starts])
        f_starts = [min(screened, key=lambda x: stage.objective(x, a_min, j_min))]
    runs = _run_slsqp([stage.run(x0, a_min, j_min) for x0 in f_starts])
    scored = []
    for x in runs:
        v, a, j = exact(x)
        scored.append((a_min / a + j_min / j, x, v, a, j))
    F, x, v, a, j = max(scored, key=lambda s: s[0])
    full = tuple(float(c) for c in space.full(x)[0])
    return VelResult(
        full, a, j, v, a_min, j_min, float(F), free,
        tuple(float(c) for c in space.full(xa)[0]), tuple(float(c) for c in space.full(xj)[0]),
        settings, ev.count,
    )


def solve_seeded(prob: VelProblem, seeds: dict[str, np.ndarray], settings: VelSettings = VelSettings(),
                 check: bool = True) -> VelResult:
    """The two-stage optimum of [Yang2022, Eq. (37)] started from ``seeds``: for each stage ("a", "j",
    "F") a (k, 7) array of full parameter vectors near its optimum, e.g. the table's interpolated answer
    and the 32 corner optima of its cell (``VelTable.seeds``), each a global optimum of a nearby problem.

    Each stage is solved from the seed of that stage with the best sampled objective (the table's nodes
    carry the basins that are optimal nearby), and other starts are screened (``screen_ftol``,
    ``check_ratio``) at the same time; a screen that beats the seed's result is polished. Without ``check``
    (the "seeded" solver) the only other start is the interpolated F seed. With ``check`` (the "exact"
    solver) they are the multi-start's starts of :func:`solve`, from its quasi-random sample evaluated in
    the same batch as the seeds: for a_max and j_max the best two distinct sampled candidates and the best
    with both end knots off the margin, for F the best sampled candidate (minimisers included) and the
    midpoint of the two minimisers.

    All runs advance together (:class:`_Lockstep`, one batched evaluation per round). The F stage needs
    a_min and j_min, so it starts when both stage-1 runs from the seeds are done, while the stage-1 screens
    run on; if a screen then finds a lower minimum (its polish beats the seed's), the F stage restarts with
    the new normalisers. A run is cut off after ``max_rounds`` rounds (its best feasible point counts).
    Peaks and F are exact at the result."""
    ev = _Evaluator(prob)
    space = _Space(prob.lambda_free, settings.margin)
    rows = {k: np.vstack([space.clip(np.asarray(r, float)[space.free]) for r in np.atleast_2d(v)])
            for k, v in seeds.items()}
    sample = space.from_unit(_quasi_random(settings.starts, space.n)) if check else np.empty((0, space.n))
    sample = np.vstack([np.array(PAPER_INITIAL)[space.free][None, :], sample])
    pool = np.vstack([rows["a"], rows["j"], rows["F"], sample])
    ga, gj = ev.grid_maxima(space.full(pool), settings.samples_per_piece)
    amax, jmax = np.sqrt(ga), np.sqrt(gj)
    a_norm, j_norm = float(amax.min() ** 2), float(jmax.min() ** 2)
    offset = {"a": 0, "j": len(rows["a"]), "F": len(rows["a"]) + len(rows["j"])}
    in_sample = slice(offset["F"] + len(rows["F"]), None)

    def exact(x: np.ndarray) -> tuple[float, float, float]:
        return exact_peaks(prob, space.full(x)[0])

    lock = _Lockstep()

    class Group:
        """One stage: SLSQP from ``first`` (the lead) and from each other start 1e-3 away from it whose
        objective is below ``bound`` (screens, ``screen_ftol``); a finished screen that beats the lead's
        result is polished (full tolerance); ``best`` (x, objective) once the lead is done."""

        def __init__(self, stage: _Stage, first: np.ndarray, others: list[np.ndarray], norms: tuple, bound: float):
            self.stage, self.norms = stage, norms
            others = [x0 for x0 in others if np.max(np.abs(x0 - first)) > 1e-3]
            if math.isfinite(bound):  # check_ratio: the starts' objectives (in one batch)
                _eval_stages([(stage, x0) for x0 in others])
                others = [x0 for x0 in others if stage.objective(x0, *norms) < bound]
            # (the runs' first evaluations come with the next round's batch)
            self.lead = lock.add(stage.run(first, *norms, max_rounds=settings.max_rounds))
            self.screens = [
                lock.add(stage.run(x0, *norms, ftol=settings.screen_ftol, maxiter=settings.screen_maxiter,
                                   max_rounds=settings.max_rounds))
                for x0 in others
            ]
            self.polishes: list[_LockstepSLSQP] = []
            self.best: tuple[np.ndarray, float] | None = None
            self.handled: set[int] = set()

        def runs(self) -> list[_LockstepSLSQP]:
            return [self.lead, *self.screens, *self.polishes]

        def pending(self) -> list[tuple[_Stage, np.ndarray]]:
            """The results :meth:`update` will judge (to evaluate in one batch with other groups')."""
            return [(self.stage, st.result()) for st in self.runs() if st.done and id(st) not in self.handled]

        def update(self) -> None:
            """Take the results of runs finished since the last call (their objectives in one batch)."""
            fresh = [st for st in self.runs() if st.done and id(st) not in self.handled]
            if self.best is None and self.lead not in fresh:
                return  # the screens are judged against the lead's result
            self.handled.update(id(st) for st in fresh)
            xs = [st.result() for st in fresh]
            _eval_stages([(self.stage, x) for x in xs])
            for st, x in zip(fresh, xs):
                f = self.stage.objective(x, *self.norms)
                if st is self.lead:
                    self.best = (x, f) if self.best is None or f < self.best[1] else self.best
            for st, x in zip(fresh, xs):
                f = self.stage.objective(x, *self.norms)
                if st in self.screens and np.max(np.abs(x - self.best[0])) > 1e-3 and f < self.best[1]:
                    self.polishes.append(lock.add(self.stage.run(x, *self.norms, max_rounds=settings.max_rounds)))
                elif st in self.polishes and f < self.best[1]:
                    self.best = (x, f)

    sample, s_amax, s_jmax = pool[in_sample], amax[in_sample], jmax[in_sample]
    inner = (sample[:, 0] >= 3 * settings.margin) & (sample[:, 3] <= 1 - 3 * settings.margin)
    stage1 = []
    c = settings.check_ratio
    for kind, vals, s_vals in (("a", amax, s_amax), ("j", jmax, s_jmax)):
        stage = _Stage(ev, space, kind, a_norm, j_norm, settings)
        seg = slice(offset[kind], offset[kind] + len(rows[kind]))
        others = []
        if check:
            # stage 1 is multimodal (an end knot on the margin or inside, and the table's cell may straddle
            # a switch between basins): also the multi-start's starts, the best candidate of the pool and
            # the best with both end knots off the margin
            others += _distinct_best(sample, s_vals, settings.refine, settings.radius)
            if inner.any():
                others.append(sample[inner][int(np.argmin(s_vals[inner]))])
        i0 = int(np.argmin(vals[seg]))
        # check_ratio: screen only starts whose sampled peak is within c of the seed's sampled peak
        bound = float(vals[seg][i0] ** 2 / stage.norm[0 if kind == "a" else 1]) * c * c if math.isfinite(c) else np.inf
        stage1.append(Group(stage, pool[seg][i0], others, (), bound))
    ga1, gj1 = stage1

    def stage_F(xa: np.ndarray, fa: float, xj: np.ndarray, fj: float) -> tuple[Group, float, float]:
        # the exact peaks (a stage's objective is its largest exact segment maximum of ‖a‖², ‖j‖² / scale)
        a_min, j_min = math.sqrt(fa * ga1.stage.norm[0]), math.sqrt(fj * gj1.stage.norm[1])
        stage = _Stage(ev, space, "F", a_norm, j_norm, settings)
        f_pool = a_min / amax + j_min / jmax
        seg = slice(offset["F"], offset["F"] + len(rows["F"]))
        others = [pool[seg][0]]  # the interpolated seed (after the best one)
        if check:
            # the multi-start's first F starts: the best sampled candidate of the pool and of the minimisers
            extra = np.vstack([xa, xj, (xa + xj) / 2])
            ga2, gj2 = ev.grid_maxima(space.full(extra), settings.samples_per_piece)
            f_extra = a_min / np.sqrt(ga2) + j_min / np.sqrt(gj2)
            allx, allf = np.vstack([pool, extra]), np.concatenate([f_pool, f_extra])
            others = [allx[int(np.argmax(allf))], extra[2]]
        return Group(stage, pool[seg][int(np.argmax(f_pool[seg]))], others, (a_min, j_min), np.inf), a_min, j_min

    # The F stage starts as soon as both stage-1 leads are done, from their minima, while the stage-1
    # screens run on; a screen that finds a lower minimum (rare) restarts it with the new normalisers.
    gF, basis = None, None
    while True:
        _eval_stages([item for g in (ga1, gj1, gF) if g is not None for item in g.pending()])
        ga1.update()
        gj1.update()
        if ga1.best is not None and gj1.best is not None:
            now = (ga1.best[1], gj1.best[1])
            if basis != now:
                if gF is not None:
                    lock.drop(gF.runs())
                basis = now
                gF, a_min, j_min = stage_F(ga1.best[0], now[0], gj1.best[0], now[1])
            gF.update()
        if not lock.active:
            break
        lock.step()
    xa, xj, x = ga1.best[0], gj1.best[0], gF.best[0]
    v, a, j = exact(x)
    F = a_min / a + j_min / j
    return VelResult(
        tuple(float(c) for c in space.full(x)[0]), a, j, v, a_min, j_min, float(F), prob.lambda_free,
        tuple(float(c) for c in space.full(xa)[0]), tuple(float(c) for c in space.full(xj)[0]),
        settings, ev.count,
    )


# ------------------------------------------------------------------------------------------ the method


SOLVERS = ("exact", "seeded", "table")


def best_of(results: list[VelResult]) -> VelResult:
    """The best of several solves of one problem: F recomputed with the lowest a_min and j_min any of
    them found (each is a local minimum of a multimodal stage), then the largest F wins."""
    a_min = min(r.a_min for r in results)
    j_min = min(r.j_min for r in results)
    best = max(results, key=lambda r: a_min / r.a_max + j_min / r.j_max)
    pa = min(results, key=lambda r: r.a_min).params_a
    pj = min(results, key=lambda r: r.j_min).params_j
    return replace(best, a_min=a_min, j_min=j_min, F=a_min / best.a_max + j_min / best.j_max, params_a=pa,
                   params_j=pj, evaluations=sum(r.evaluations for r in results))


def optimum(task: Task, duration: float, solver: str = "exact", table: str | None = None,
            settings: VelSettings | None = None) -> tuple[tuple[float, ...], VelResult | None, str]:
    """(params, the solve's result or None, source) of Eq. (37) for ``task`` in ``duration`` seconds.

    ``solver``:

    * "exact" (default) — where the table applies, :func:`solve_seeded` with its check: the three stages
      started from the table's seeds (interpolated and corner optima of the query's cell, for each stage)
      and from the multi-start's starts (screened, polished when better), at least as good as the
      multi-start on the held-out moves (README). Elsewhere the global multi-start (:func:`solve`).
    * "seeded" — only the table's seeds, one SLSQP run per stage (F may also screen the interpolated
      seed): faster, exact to the optimum of its basin.
    * "table" — the table's answer alone (instant, approximate: README).

    Where the table does not apply (other η, unequal heights, vertical velocities, outside its range, no
    table), "exact" and "seeded" are the multi-start alone."""
    settings = settings or VelSettings()
    prob = make_problem(task, duration)
    if solver not in SOLVERS:
        raise TaskError(f"solver = {solver!r}: choose one of {', '.join(SOLVERS)}")
    from ..model.errors import TableError
    from ..lookup.vel_table import load_vel_table

    try:
        tab = load_vel_table(table)
        seeds = tab.seeds(task, duration)
    except TableError as exc:
        if solver == "table":
            raise
        res = solve(prob, settings)
        return res.params, res, f"exact (multi-start; table not used: {exc})"
    if solver == "table":
        return tab.lookup(task, duration), None, f"table {tab.source}"
    res = solve_seeded(prob, seeds, settings, check=solver == "exact")
    if solver == "seeded":
        return res.params, res, f"seeded (table {tab.source})"
    return res.params, res, f"exact (table {tab.source} seeds and multi-start samples)"


def _check_params(params) -> tuple[float, ...]:
    try:
        p = tuple(float(x) for x in params)
    except (TypeError, ValueError):
        raise TaskError(f"params = {params!r}: give seven numbers τ6, τ7, τ9, τ10, λ1, λ2, λ3") from None
    if len(p) != 7 or not all(math.isfinite(x) for x in p):
        raise TaskError(f"params = {params!r}: give seven finite numbers τ6, τ7, τ9, τ10, λ1, λ2, λ3")
    if not (0 < p[0] < p[1] < 0.5 < p[2] < p[3] < 1):
        raise TaskError(
            f"params = {','.join(f'{x:g}' for x in p[:4])}: the knots need 0 < τ6 < τ7 < 0.5 < τ9 < τ10 < 1 "
            "[Yang2022, Eq. (36)]"
        )
    if not all(0 <= x <= 1 for x in p[4:]):
        raise TaskError(f"params λ = {','.join(f'{x:g}' for x in p[4:])}: each λ must lie in [0, 1] [Yang2022, Eq. (36)]")
    return p


def plan_bspline_vel(
    task: Task,
    duration: float,
    params=None,
    solver: str = "exact",
    table: str | None = None,
    settings: VelSettings | None = None,
    margin: float | None = None,
    _result: VelResult | None = None,
    **named: float,
) -> CartesianPath:
    """CartesianPath of the conveyor-tracking B-spline for a move of ``duration`` seconds [Yang2022].

    The shape parameters (τ6, τ7, τ9, τ10, λ1, λ2, λ3) are ``params`` (or all seven by name: ``tau6`` …
    ``lambda3``) when given, else the optimum of Eq. (37) by ``solver`` (see :func:`optimum`): "exact"
    (default: table seeds and multi-start samples, :func:`solve_seeded`), "seeded" (the table's seeds
    polished to the optimum of their basin) or "table" (the interpolant of :mod:`pickplace_cli.lookup.vel_table` alone;
    ``table`` is its file, default the shipped one).
    ``margin`` overrides ``settings.margin``. The path is valid only when run in ``duration`` seconds:
    its τ-derivative at the ends is v·T.
    """
    if named:
        unknown = sorted(set(named) - set(PARAM_NAMES))
        if unknown:
            raise TypeError(f"plan_bspline_vel() got an unexpected keyword argument '{unknown[0]}'")
        missing = [n for n in PARAM_NAMES if n not in named]
        if missing or params is not None:
            raise TaskError(
                f"param {missing[0] if missing else 'params'}: give all seven shape parameters "
                f"({', '.join(PARAM_NAMES)}) or none"
            )
        params = [named[n] for n in PARAM_NAMES]
    if margin is not None:
        settings = replace(settings or VelSettings(), margin=float(margin))
    T = float(duration)
    prob = make_problem(task, T)
    extra: dict[str, Any] = {}
    res = _result  # an exact solve the caller (PathFactory) already did
    source = "exact"
    if res is not None:
        p = res.params
    elif params is not None:
        p = _check_params(params)
        source = "given"
    else:
        p, res, source = optimum(task, T, solver, table, settings)
    if res is not None:
        # F's normalisers in the move's own units (like CartesianPath.peaks: m per τ², τ³ at T = 1 s)
        extra = {"F": res.F, "a_min": res.a_min * prob.scale, "j_min": res.j_min * prob.scale,
                 "margin": res.settings.margin, "lambda_free": list(res.lambda_free)}
    spline = spline_of(prob, p)
    scale = prob.scale
    peaks = tuple(scale * x for x in norm_peaks(spline, (1, 2, 3)))
    origin = task.p_from

    def evaluate(tau: np.ndarray, order: int) -> np.ndarray:
        out = scale * spline(tau, nu=order)
        return out + origin if order == 0 else out

    parameters: dict[str, Any] = dict(zip(PARAM_NAMES, p))
    # C4 inside the move (quintic B-spline, simple interior knots); the measured class stops at jerk (C3).
    # With conveyor velocities the ends are not at rest: the tool moves on with the belt.
    parameters.update(continuity=3, jerk_jumps_at=[])
    parameters.update(
        params_source=source, duration_s=T, eta=task.eta, height_m=task.height,
        v_from_m_s=task.v_from.tolist(), v_to_m_s=task.v_to.tolist(), **extra,
    )
    return CartesianPath(
        evaluate=evaluate,
        method="bspline-vel",
        parameters=parameters,
        peaks=peaks,  # type: ignore[arg-type]
        breakpoints=np.unique(spline.t),
        jumps=(),  # C⁴ inside the move: nothing steps at the knots
    )


class PathFactory:
    """duration T [s] → CartesianPath of ``task`` planned for T (memoised): the hook the planner uses for
    methods whose normalised path depends on T (``depends_on_duration``). ``params`` are those of
    :func:`plan_bspline_vel` (checked here, so a wrong name fails before any duration is tried).

    With the exact solver, the first duration is solved globally and later ones by continuation from the
    nearest solved duration (``solve(..., warm=…)``, a few SLSQP steps): the optimum moves smoothly with T.
    :meth:`final` re-solves a duration globally; when that finds a better optimum the continuation had
    followed a worse branch, the factory stops using it, and the caller repeats its search."""

    depends_on_duration = True
    MAX_SWITCHES = 3
    _ALLOWED = {"params", "solver", "table", "settings", "margin", *PARAM_NAMES}

    def __init__(self, task: Task, **params: Any) -> None:
        unknown = sorted(set(params) - self._ALLOWED)
        if unknown:
            name = unknown[0]
            raise TaskError(
                f"param {name} = {params[name]!r}: method bspline-vel has no parameter {name!r} (see README, Methods)"
            )
        self.task = task
        self.params = params
        self.continuation = params.get("solver", "exact") in ("exact", "seeded") and not (
            params.get("params") is not None or any(n in params for n in PARAM_NAMES)
        )
        self._cache: dict[float, CartesianPath] = {}
        self._results: dict[float, VelResult] = {}
        self._switches = 0

    def task_at(self, duration: float) -> Task:
        """The task planned for ``duration`` [s]: the same for every T here; a conveyor rendezvous
        (:mod:`pickplace_cli.pipelines.rendezvous`) moves its end point with T."""
        return self.task

    def __call__(self, duration: float) -> CartesianPath:
        T = float(duration)
        if T not in self._cache:
            if len(self._cache) > 256:
                self._cache.clear()
                self._results.clear()
            if self.continuation and self._results:
                near = min(self._results, key=lambda x: abs(math.log(x / T)))
                self._cache[T] = self._exact(T, warm=self._results[near])
            elif self.continuation:
                self._cache[T] = self._exact(T, seeded=True)
            else:
                self._cache[T] = plan_bspline_vel(self.task_at(T), T, **self.params)
        return self._cache[T]

    def _exact(self, T: float, warm: VelResult | None = None, seeded: bool = False) -> CartesianPath:
        settings = self.params.get("settings") or VelSettings()
        if self.params.get("margin") is not None:
            settings = replace(settings, margin=float(self.params["margin"]))
        if warm is None:  # the first duration, or the final check: the requested solver in full
            solver = self.params.get("solver", "exact") if seeded else "exact"
            res = optimum(self.task_at(T), T, solver, self.params.get("table"), settings)[1]
        else:
            res = solve(make_problem(self.task_at(T), T), settings, warm=warm)
        self._results[T] = res
        return plan_bspline_vel(self.task_at(T), T, _result=res)

    def final(self, duration: float) -> tuple[CartesianPath, bool]:
        """(the path at T from the full solve (and the continuation: the better), whether the continuation's
        optimum was the better one).

        On disagreement the global optimum becomes the seed of later continuations (so the caller's
        repeated search follows the better branch); after ``MAX_SWITCHES`` switches only global solves are
        used."""
        T = float(duration)
        if not self.continuation:
            return self(T), True
        before = self._results.get(T)
        self._exact(T)
        full = self._results[T]
        both = best_of([full] + ([before] if before is not None else []))
        # the continuation agreed when its optimum is as good (F to 1e-9, common normalisers)
        agreed = before is not None and (
            both.a_min / before.a_max + both.j_min / before.j_max >= both.F - 1e-9
        )
        if agreed:
            both = replace(before, a_min=both.a_min, j_min=both.j_min, F=both.a_min / before.a_max + both.j_min / before.j_max)
        self._results[T] = both  # F with the lowest normalisers either search found
        path = plan_bspline_vel(self.task_at(T), T, _result=both)
        self._cache[T] = path
        if agreed or before is None:
            return path, True
        self._switches += 1
        self._cache = {T: path}
        self._results = {T: both}
        if self._switches >= self.MAX_SWITCHES:
            self.continuation = False
        return path, agreed


def resolve_velocities(workcell, v_from=None, v_to=None) -> tuple[np.ndarray, np.ndarray]:
    """End velocities [m/s, base frame]: the given ones, else the profile's conveyor velocities, else 0."""
    def pick(given, default):
        if given is not None:
            return np.asarray(given, float)
        return np.asarray(default, float) if default is not None else np.zeros(3)

    return (
        pick(v_from, getattr(workcell, "conveyor_pick_velocity", None)),
        pick(v_to, getattr(workcell, "conveyor_place_velocity", None)),
    )
