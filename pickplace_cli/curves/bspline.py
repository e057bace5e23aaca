"""Quintic B-spline machinery shared by the B-spline methods [Li2018, Sec. 2.2–2.3].

A motion profile is ``s(τ) = Σ Q_i N_{i,5}(τ)`` on τ ∈ [0, 1] (Eq. 3) with clamped knots (Eq. 7).
This module builds the knots and solves for the control points; :func:`make_spline` wraps the result in
scipy's :class:`scipy.interpolate.BSpline` (table builds, the conveyor method, the tests' reference).

**One evaluation path without scipy, on purpose.** Importing ``scipy.interpolate`` costs ~0.45 s of cold
start (it pulls in scipy.special and scipy.optimize), more than half of the 0.8 s budget of one
``pickplace plan`` [issue 7]. The online path of the default method (``paths.bspline.batch_paths``, for
one move in ``plan`` and for thousands in the batch verdict engine) therefore uses numpy only: closed forms
for a Task's via points (one height or two: ``lookup.bspline_optimum.unit_pieces`` / ``plane_pieces``), and
for any other via points the batched Cox–de Boor recursion at the end of this module
(:func:`batch_control_points`, :func:`batch_pieces`: the same arithmetic scipy's de Boor does; the conveyor
optimiser uses it for hundreds of knot vectors at once). Tests hold it to scipy's BSpline at 1e-12 (values and
every derivative order), and the closed forms to it.
"""

from __future__ import annotations

import numpy as np

DEGREE = 5


def li_knots(k1: float, k2: float) -> np.ndarray:
    """The 17 knots of [Li2018, Eq. (14)] from the time-ratio factors k1 = τ8/τ9, k2 = τ7/τ8 (Eq. 13)."""
    if not (0.0 < k1 < 1.0 and 0.0 < k2 < 1.0):
        raise ValueError(f"k1 and k2 must lie in (0, 1), got k1={k1!r}, k2={k2!r}")
    return np.array(
        [0.0] * 6 + [k1 * k2 / 2, k1 / 2, 0.5, 1 - k1 / 2, 1 - k1 * k2 / 2] + [1.0] * 6
    )


def yang_knots(tau6: float, tau7: float, tau9: float, tau10: float) -> np.ndarray:
    """The 17 normalised knots of [Yang2022, Eq. (23), (33)]: four free knots, τ8 = 1/2 (t8 = T/2).

    The paper's 1-based "τ_i, i = 1 … 17" of Eq. (33) is the 0-based index of Eq. (23) (t0 … t5 = 0,
    t11 … t16 = T); the array index here is that 0-based index.
    """
    if not (0.0 < tau6 < tau7 < 0.5 < tau9 < tau10 < 1.0):
        raise ValueError(
            f"need 0 < τ6 < τ7 < 0.5 < τ9 < τ10 < 1 [Yang2022, Eq. (36)], got {tau6!r}, {tau7!r}, {tau9!r}, {tau10!r}"
        )
    return np.array([0.0] * 6 + [tau6, tau7, 0.5, tau9, tau10] + [1.0] * 6)


def basis_matrix(knots: np.ndarray, x: np.ndarray, order: int = 0) -> np.ndarray:
    """(len(x), n) matrix of the ``order``-th derivative of every basis function N_{i,5} at x."""
    return _basis_spline(knots)(np.asarray(x, float), nu=order)


def solve_control_points(
    knots: np.ndarray,
    via_tau: np.ndarray,
    via: np.ndarray,
    start: np.ndarray | None = None,
    end: np.ndarray | None = None,
) -> np.ndarray:
    """Control points (n, d) of the quintic spline with the given knots that

    * passes through ``via`` (f, d) at ``via_tau`` (f,), first = τ 0 and last = τ 1 [Li2018, Eq. (8)];
    * has derivatives ``start`` = (s′, s″, s‴)(0) and ``end`` = (s′, s″, s‴)(1), each (3, d), zero when
      None [Li2018, Eq. (9)] (Yang 2022 sets s′ to the conveyor velocity).

    Uses the reduced system described in the module docstring: Q_1..Q_4 and Q_{n−3}..Q_n come from the
    end conditions, the remaining interior control points from the interior via points. The number of
    interior via points must equal the number of interior control points (n − 8).
    """
    via = np.asarray(via, dtype=float)
    if via.ndim == 1:
        via = via[:, None]
    d = via.shape[1]
    n = len(knots) - DEGREE - 1
    start = np.zeros((3, d)) if start is None else np.asarray(start, float).reshape(3, d)
    end = np.zeros((3, d)) if end is None else np.asarray(end, float).reshape(3, d)
    interior = np.asarray(via_tau, float)[1:-1]
    if interior.size != n - 8:
        raise ValueError(f"{n} control points need {n - 8} interior via points, got {interior.size}")
    q = np.empty((n, d))
    basis = _basis_spline(knots)
    if not np.any(start) and not np.any(end):
        # rest to rest: the r-th derivative at a clamped end is a combination of differences of
        # Q_1..Q_{r+1}, so zero velocity, acceleration and jerk there means Q_1 = Q_2 = Q_3 = Q_4 (and the
        # same at tau = 1): exact, no solve needed
        q[:4] = via[0]
        q[-4:] = via[-1]
        a = basis(interior)
        q[4:-4] = np.linalg.solve(a[:, 4:-4], via[1:-1] - a[:, :4] @ q[:4] - a[:, -4:] @ q[-4:])
        return q

    ends = np.array([knots[0], knots[-1]])
    rows = np.stack([basis(ends, nu=r) for r in range(4)])  # (4 orders, 2 ends, n)
    # end conditions: the derivative rows at τ=0 are lower-triangular in Q_1..Q_4 (Eq. 9)
    q[:4] = np.linalg.solve(rows[:, 0, :4], np.vstack([via[:1], start]))
    q[-4:] = np.linalg.solve(rows[:, 1, -4:], np.vstack([via[-1:], end]))
    if n > 8:
        a = basis(interior)
        rhs = via[1:-1] - a[:, :4] @ q[:4] - a[:, -4:] @ q[-4:]
        q[4:-4] = np.linalg.solve(a[:, 4:-4], rhs)
    return q


def _basis_spline(knots: np.ndarray):
    """A BSpline whose coefficient matrix is the identity: evaluating it gives every basis function."""
    from scipy.interpolate import BSpline

    n = len(knots) - DEGREE - 1
    return BSpline(knots, np.eye(n), DEGREE, extrapolate=True)


def make_spline(knots: np.ndarray, control_points: np.ndarray):
    """scipy BSpline of degree 5 (vector-valued when control_points is (n, d))."""
    from scipy.interpolate import BSpline

    return BSpline(knots, control_points, DEGREE, extrapolate=True)


def piece_coefficients(spline, order: int, _derivs: list | None = None, breaks: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Breakpoints (m+1,) and Taylor coefficients (m, d, 6−order) of the ``order``-th derivative.

    Piece i is Σ_p coef[i, :, p] (τ − breaks[i])^(deg−p), highest power first, deg = 5 − order. The
    coefficients are the derivatives of orders ``order``..5 at the left end of each piece divided by the
    factorials, i.e. the exact polynomial of that piece.
    """
    if breaks is None:
        breaks = np.unique(spline.t)
    if _derivs is None:
        _derivs = _left_derivatives(spline, breaks)
    deg = DEGREE - order
    coef = np.stack([_derivs[order + p] / _FACT[p] for p in range(deg, -1, -1)], axis=-1)
    return breaks, coef


_FACT = (1.0, 1.0, 2.0, 6.0, 24.0, 120.0)


def _left_derivatives(spline, breaks: np.ndarray) -> list:
    left = breaks[:-1]
    return [np.asarray(spline(left, nu=r)).reshape(len(left), -1) for r in range(DEGREE + 1)]


def norm_peaks(spline, orders: tuple[int, ...] = (1, 2, 3)) -> tuple[float, ...]:
    """Exact max over τ ∈ [0, 1] of ‖d^r s/dτ^r‖ for each r in ``orders`` (piecewise-polynomial roots)."""
    breaks = np.unique(spline.t)
    return pieces_norm_peaks(breaks, _left_derivatives(spline, breaks), orders)


def pieces_norm_peaks(breaks: np.ndarray, derivs: list, orders: tuple[int, ...] = (1, 2, 3)) -> tuple[float, ...]:
    """:func:`norm_peaks` from breakpoints and left-end derivatives (six (m, d) arrays), all orders in one
    batched root search."""
    from .peaks import batch_norm_peaks

    coefs = [piece_coefficients(None, r, derivs, breaks)[1][None] for r in orders]
    return tuple(float(v) for v in batch_norm_peaks(np.asarray(breaks)[None], coefs)[0])


# ------------------------------------------------------------------------------- batched (many knot vectors)
#
# The conveyor-tracking optimiser [Yang2022] evaluates hundreds of knot vectors per solve. scipy's BSpline
# holds one knot vector per object, so a Python loop over them costs ~60 µs each; the functions below do
# the same arithmetic for a whole batch in one numpy pass. They follow the paper's own formulas: the
# Cox–de Boor recursion [Yang2022, Eq. (2)–(3)] and the control points of the derivative splines
# [Yang2022, Eq. (12)–(14)]; tests compare them with scipy's BSpline.


def batch_basis(
    knots: np.ndarray, x: np.ndarray, span: np.ndarray, degree: int = DEGREE, all_degrees: bool = False
) -> np.ndarray | list[np.ndarray]:
    """The degree + 1 non-zero B-spline basis functions at each point, for a batch of knot vectors.

    ``knots`` (P, K); ``x`` (P, M) the points; ``span`` (P, M) or (M,) the knot span s of each point
    (t_s ≤ x ≤ t_{s+1}, t_s < t_{s+1}), given rather than searched so that a point on a knot (or at τ = 1)
    is evaluated on the piece the caller means. Returns (P, M, degree + 1): [..., r] = N_{s−degree+r, degree}(x)
    (with ``all_degrees`` the list of these arrays for degrees 0 … ``degree``: the recursion passes through
    them). The Cox–de Boor recursion [Yang2022, Eq. (2)–(3)] restricted to the non-zero functions (Piegl &
    Tiller, The NURBS Book, Algorithm A2.2).
    """
    t = np.asarray(knots, float)
    x = np.asarray(x, float)
    span = np.broadcast_to(np.asarray(span), x.shape)
    rows = np.arange(t.shape[0])[:, None, None]
    lo = t[rows, span[..., None] + 1 - np.arange(1, degree + 1)]  # t_{s+1−j}, j = 1 … degree
    hi = t[rows, span[..., None] + np.arange(1, degree + 1)]  # t_{s+j}
    left = [None] + list(np.moveaxis(x[..., None] - lo, -1, 0))
    right = [None] + list(np.moveaxis(hi - x[..., None], -1, 0))
    n = [np.ones_like(x)]
    out = [np.ones_like(x)[..., None]]
    for j in range(1, degree + 1):
        saved = 0.0
        nxt = []
        for r in range(j):
            temp = n[r] / (right[r + 1] + left[j - r])
            nxt.append(saved + right[r + 1] * temp)
            saved = left[j - r] * temp
        nxt.append(saved)
        n = nxt
        if all_degrees:
            out.append(np.stack(n, axis=-1))
    return out if all_degrees else np.stack(n, axis=-1)


def batch_combine(values: np.ndarray, span: np.ndarray, coef: np.ndarray, shift: int) -> np.ndarray:
    """Σ_r values[..., r] · coef[p, s − deg + r − shift] for basis values from :func:`batch_basis`.

    ``coef`` (P, n_c, d) are control points whose i-th multiplies N_{i+shift, deg} (``shift`` = r for the
    r-th derivative spline of Eq. (9)–(11)); returns (P, M, d).
    """
    P, M, k = values.shape
    idx = np.broadcast_to(np.asarray(span), (P, M))[..., None] - (k - 1) + np.arange(k) - shift
    rows = np.arange(P)[:, None, None]
    return np.einsum("pmr,pmrd->pmd", values, coef[rows, idx])


def derivative_control_points(knots: np.ndarray, q: np.ndarray, order: int = 3) -> list[np.ndarray]:
    """Control points of the derivative splines [Yang2022, Eq. (12)–(14)], batched.

    ``knots`` (P, K), ``q`` (P, n, d) → [Q, Q_V, Q_A, Q_J, …][: order + 1], Q_r of shape (P, n − r, d).
    The r-th derivative is Σ_i Q_r[i] N_{i+r, 5−r} on the same knot vector (Eq. 9–11).
    """
    t = np.asarray(knots, float)
    out = [np.asarray(q, float)]
    n = out[0].shape[1]
    for r in range(1, order + 1):
        prev = out[-1]
        m = n - r
        i = np.arange(m)
        den = t[:, i + DEGREE + 1] - t[:, i + r]  # t_{i+p+1} − t_{i+r}
        out.append((DEGREE + 1 - r) / den[:, :, None] * (prev[:, 1:] - prev[:, :-1]))
    return out


def batch_end_control_points(knots: np.ndarray, p0: np.ndarray, d0: np.ndarray, at_end: bool = False) -> np.ndarray:
    """The four control points fixed at a clamped end by position and (s′, s″, s‴) there, batched.

    ``knots`` (P, K); ``p0`` (P, d) the end point; ``d0`` (P, 3, d) its first three derivatives. Inverts
    Eq. (12)–(15) of [Yang2022] step by step (the boundary rows are triangular in Q_0 … Q_3): returns
    (P, 4, d) = Q_0 … Q_3, or Q_{n−4} … Q_{n−1} (in that order) when ``at_end``.
    """
    t = np.asarray(knots, float)
    K = t.shape[1]
    p0 = np.asarray(p0, float)
    d0 = np.asarray(d0, float)
    if not at_end:
        # Q_{r,0} = d0[r−1];  Q_{r−1,i+1} = Q_{r−1,i} + Q_{r,i}·(t_{i+p+1} − t_{i+r})/(p + 1 − r)
        v0, a0, j0 = d0[:, 0], d0[:, 1], d0[:, 2]
        gap = lambda i, r: (t[:, i + DEGREE + 1] - t[:, i + r])[:, None] / (DEGREE + 1 - r)  # noqa: E731
        qa1 = a0 + j0 * gap(0, 3)
        qv1 = v0 + a0 * gap(0, 2)
        qv2 = qv1 + qa1 * gap(1, 2)
        q1 = p0 + v0 * gap(0, 1)
        q2 = q1 + qv1 * gap(1, 1)
        q3 = q2 + qv2 * gap(2, 1)
        return np.stack([p0, q1, q2, q3], axis=1)
    # mirror image: with n control points the last derivative control points are Q_{r, n−1−r}
    n = K - DEGREE - 1
    v1, a1, j1 = d0[:, 0], d0[:, 1], d0[:, 2]
    gap = lambda i, r: (t[:, i + DEGREE + 1] - t[:, i + r])[:, None] / (DEGREE + 1 - r)  # noqa: E731
    qa7 = a1 - j1 * gap(n - 4, 3)
    qv8 = v1 - a1 * gap(n - 3, 2)
    qv7 = qv8 - qa7 * gap(n - 4, 2)
    q9 = p0 - v1 * gap(n - 2, 1)
    q8 = q9 - qv8 * gap(n - 3, 1)
    q7 = q8 - qv7 * gap(n - 4, 1)
    return np.stack([q7, q8, q9, p0], axis=1)


# -------------------------------------------- batched Li 2018 paths (the planner with P = 1, the verdict engine)


def batch_li_knots(k1: np.ndarray, k2: np.ndarray) -> np.ndarray:
    """(P, 17) knots of [Li2018, Eq. (14)] (the arithmetic of :func:`li_knots`)."""
    P = len(k1)
    return np.column_stack(
        [np.zeros((P, 6)), k1 * k2 / 2, k1 / 2, np.full(P, 0.5), 1 - k1 / 2, 1 - k1 * k2 / 2, np.ones((P, 6))]
    )


def batch_spans(knots: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Knot span of each x (P, M) on its own knot vector (P, K): t_s ≤ x < t_{s+1}, the last non-empty
    span at the right end (as scipy evaluates), for :func:`batch_basis`."""
    n = knots.shape[1] - DEGREE - 1
    s = np.sum(knots[:, None, :] <= x[:, :, None], axis=-1) - 1  # = searchsorted(side="right") − 1
    return np.clip(s, DEGREE, n - 1)


def batch_control_points(knots: np.ndarray, via: np.ndarray) -> np.ndarray:
    """Control points (P, 11, 3) of the rest-to-rest quintic through ``via`` (P, 5, 3) [Li2018, Eq. (8)–(10)]
    at τ = 0, knots[7], knots[8], knots[9], 1, with zero end velocity, acceleration and jerk (Eq. 9): the
    reduced system of :func:`solve_control_points` (Q1..Q4 and Q8..Q11 fixed by the
    ends, the three interior ones from one batched 3×3 solve)."""
    P, K = knots.shape
    n = K - DEGREE - 1
    x = knots[:, [7, 8, 9]]
    span = batch_spans(knots, x)
    vals = batch_basis(knots, x, span, degree=DEGREE)  # (P, 3, 6)
    a = np.zeros((P, 3, n))
    a[np.arange(P)[:, None, None], np.arange(3)[None, :, None], span[..., None] - DEGREE + np.arange(DEGREE + 1)] = vals
    q = np.empty((P, n, via.shape[2]))
    q[:, :4] = via[:, :1]
    q[:, -4:] = via[:, -1:]
    rhs = via[:, 1:-1] - a[:, :, :4] @ q[:, :4] - a[:, :, -4:] @ q[:, -4:]
    q[:, 4:-4] = np.linalg.solve(a[:, :, 4:-4], rhs)
    return q


def batch_pieces(knots: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, list[np.ndarray]]:
    """Breakpoints (P, 7) and left-end derivatives of orders 0…5 of each move's 6 pieces (six (P, 6, d)
    arrays), for P knot vectors (distinct interior knots)."""
    breaks = knots[:, DEGREE : knots.shape[1] - DEGREE]
    x = breaks[:, :-1]
    span = batch_spans(knots, x)
    qs = derivative_control_points(knots, q, DEGREE)
    values = batch_basis(knots, x, span, all_degrees=True)
    return breaks, [batch_combine(values[DEGREE - r], span, qs[r], shift=r) for r in range(DEGREE + 1)]


def batch_piece_coefficients(derivs: list[np.ndarray], order: int) -> np.ndarray:
    """(P, m, d, 6 − order) Taylor coefficients of the ``order``-th derivative, highest power first
    (:func:`piece_coefficients` per move)."""
    deg = DEGREE - order
    return np.stack([derivs[order + p] / _FACT[p] for p in range(deg, -1, -1)], axis=-1)
