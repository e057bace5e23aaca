"""The problem of Yang 2022's velocity-constrained quintic B-spline [Yang2022, Sec. 2.2–2.3]: path, groups, peaks.

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
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..model.errors import TaskError
from ..model.task import Task
from .bspline import (
    batch_basis,
    batch_combine,
    batch_end_control_points,
    derivative_control_points,
    make_spline,
    norm_peaks,
    yang_knots,
)

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
