"""Exact and refined peaks of vector-valued motion: max over the continuous curve, not only at samples.

Three tools:

* :func:`ppoly_norm_peak` — the exact maximum of ‖c(τ)‖ for a piecewise polynomial c (each piece a
  polynomial in τ): on each piece ‖c‖² is a polynomial whose maximum lies at an end or at a real root of
  its derivative, found from the eigenvalues of the companion matrix (all pieces in one batched call).
* :func:`parabolic_peak` — the peak of sampled values refined by the vertex of the parabola through the
  largest sample and its neighbours, for one grid or many stacked: the one sampled estimate of the package.
* :func:`refine_max` — for any smooth function known only by evaluation (joint torques, rates …):
  sample, take the local maxima of the samples, and refine each by a vectorised golden-section search
  inside its bracket. scipy's ``minimize_scalar`` would do the same one bracket at a time; doing all
  brackets in one array keeps it at a few hundred microseconds.
"""

from __future__ import annotations

from typing import Callable

import math

import numpy as np


def _poly_square_norm(coef: np.ndarray) -> np.ndarray:
    """Coefficients of Σ_d c_d(s)² for coef of shape (m, d, k+1) (highest power first) → (m, 2k+1)."""
    m, d, k1 = coef.shape
    outer = np.einsum("mdi,mdj->mij", coef, coef).reshape(m, k1 * k1)
    return outer @ _anti_diagonal_sum(k1)


def _anti_diagonal_sum(k1: int, _cache: dict = {}) -> np.ndarray:  # noqa: B006 - deliberate memo
    """(k1², 2k1−1) 0/1 matrix that sums the products c_i c_j into the coefficient of power i + j."""
    if k1 not in _cache:
        s = np.zeros((k1 * k1, 2 * k1 - 1))
        i, j = np.divmod(np.arange(k1 * k1), k1)
        s[np.arange(k1 * k1), i + j] = 1.0
        _cache[k1] = s
    return _cache[k1]


def _horner(coefs: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Evaluate row i of ``coefs`` (m, k+1), highest power first, at every x[i, :]."""
    out = np.zeros_like(x)
    for c in coefs.T:
        out = out * x + c[:, None]
    return out


def _keep_real(v: np.ndarray, h: np.ndarray) -> np.ndarray:
    ok = (np.abs(v.imag) <= 1e-9 * (1.0 + np.abs(v.real))) & (v.real > 0) & (v.real < h[:, None])
    return np.where(ok, v.real, 0.0)


def _critical_points(dcoefs: np.ndarray, h: np.ndarray) -> np.ndarray:
    """(m, n) real roots of each row polynomial inside (0, h_i); other entries are 0 (an end, harmless)."""
    m, n1 = dcoefs.shape
    n = n1 - 1
    out = np.zeros((m, max(n, 1)))
    if n < 1:
        return out
    scale = np.max(np.abs(dcoefs), axis=1)
    lead = np.abs(dcoefs[:, 0]) > 1e-12 * np.where(scale > 0, scale, 1.0)
    rows = np.flatnonzero(lead)
    if rows.size:
        comp = np.zeros((rows.size, n, n))
        comp[:, 0, :] = -dcoefs[rows, 1:] / dcoefs[rows, :1]
        if n > 1:
            comp[:, np.arange(1, n), np.arange(n - 1)] = 1.0
        out[rows] = _keep_real(np.linalg.eigvals(comp), h[rows])
    for r in np.flatnonzero(~lead):  # the degree drops (rare): one by one
        if np.any(dcoefs[r]):
            v = _keep_real(np.roots(dcoefs[r])[None, :], h[r : r + 1])[0]
            out[r, : v.size] = v
    return out


def ppoly_norm_peak(breaks: np.ndarray, coef: np.ndarray) -> tuple[float, float]:
    """Exact max of ‖c(τ)‖ over [breaks[0], breaks[-1]].

    ``coef`` has shape (m, d, k+1): piece i is c_d(τ) = Σ coef[i, d, p] (τ − breaks[i])^(k−p) on
    [breaks[i], breaks[i+1]]. Returns (peak value, τ of the peak).
    """
    h = np.diff(breaks)
    sq = _poly_square_norm(coef)
    k2 = sq.shape[1] - 1
    dsq = sq[:, :-1] * np.arange(k2, 0, -1)
    cand = np.concatenate([np.zeros((len(h), 1)), h[:, None], _critical_points(dsq, h)], axis=1)
    vals = _horner(sq, cand)
    i, j = np.unravel_index(int(np.argmax(vals)), vals.shape)
    return float(np.sqrt(max(vals[i, j], 0.0))), float(breaks[i] + cand[i, j])


def batch_norm_peaks(breaks: np.ndarray, coefs: list[np.ndarray]) -> np.ndarray:
    """Exact max of ‖c(τ)‖ per move and per piecewise polynomial, (P, len(coefs)):
    :func:`ppoly_norm_peak` of several piecewise polynomials for P moves at once. ``breaks`` (P, m+1); each of
    ``coefs`` (P, m, d, k+1), piece i of move p being Σ coef[p, i, :, j] (τ − breaks[p, i])^(k−j). On each
    piece ‖c‖² is a polynomial; its maximum is at an end or at a real root of its derivative (companion-matrix
    eigenvalues; every derivative padded to the highest degree by powers of (τ − breaks[i]), which only adds
    roots at the piece's left end, a candidate anyway). The same row-wise arithmetic as the one-move function
    (per-move matrix products, one eigenvalue problem per row), so the peaks are bitwise equal (tested)."""
    P, m = breaks.shape[0], breaks.shape[1] - 1
    h = np.diff(breaks, axis=1).reshape(P * m)
    sqs = []
    for c in coefs:
        k1 = c.shape[-1]
        flat = c.reshape(P * m, c.shape[2], k1)
        outer = np.einsum("mdi,mdj->mij", flat, flat).reshape(P, m, k1 * k1)
        sqs.append((outer @ _anti_diagonal_sum(k1)).reshape(P * m, 2 * k1 - 1))  # per-move products
    degs = [sq.shape[1] - 1 for sq in sqs]
    top = max(degs)
    # Only pieces that can hold the maximum need their roots: a piece whose upper bound on ‖c‖² (the largest
    # Bernstein coefficient on [0, h]) lies below the value already reached at some piece end of the same
    # move cannot (its candidates are all smaller, so leaving them out does not change the max). Round-off
    # allowance: 1e-9 of Σ|a_p| h^p.
    ends, need = [], []
    for sq in sqs:
        e = _horner(sq, np.column_stack([np.zeros(P * m), h]))
        best = np.max(e.reshape(P, -1), axis=1)
        n = sq.shape[1] - 1
        scaled = sq[:, ::-1] * h[:, None] ** np.arange(n + 1)  # a_p h^p, lowest power first
        bound = np.max(scaled @ _bernstein(n), axis=1) + 1e-9 * np.sum(np.abs(scaled), axis=1)
        ends.append(e)
        need.append(bound.reshape(P, m) >= best[:, None])
    rows = [np.flatnonzero(nd.reshape(-1)) for nd in need]
    dsq = np.zeros((sum(r.size for r in rows), top))
    at = 0
    for sq, d, r in zip(sqs, degs, rows):
        if d:
            dsq[at : at + r.size, :d] = sq[r, :-1] * np.arange(d, 0, -1)
        at += r.size
    crit = _critical_points(dsq, np.concatenate([h[r] for r in rows]))
    out = np.empty((P, len(sqs)))
    at = 0
    for k, (sq, r) in enumerate(zip(sqs, rows)):
        vals = np.full((P * m, 2 + crit.shape[1]), -np.inf)
        vals[:, :2] = ends[k]
        vals[r, 2:] = _horner(sq[r], crit[at : at + r.size])
        at += r.size
        out[:, k] = np.sqrt(np.maximum(np.max(vals.reshape(P, -1), axis=1), 0.0))
    return out



def parabolic_peak(x: np.ndarray, y: np.ndarray, starts: np.ndarray | None = None, seg: np.ndarray | None = None,
                   i: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The peak of every column of samples ``y`` (M, C) on the sorted grid ``x`` (M,), refined by the vertex of the
    parabola through the largest sample (the first maximum, as ``np.argmax``; or the rows ``i`` (C,) given) and its
    two neighbours. The vertex is kept when the parabola opens downward and the vertex lies at or above the
    sample; else the sample (at an end of the grid, with fewer than three samples, where the three samples are
    not in one segment ``seg`` (:func:`~pickplace_cli.limits.grid.segment_ids`): never across a jump).
    → (peak, τ of the peak), each (C,).

    ``starts`` (P + 1,): the rows of P grids stacked one after the other, grid k in rows starts[k]:starts[k + 1]
    (at least one each; every grid sorted); → (peak, τ), each (P, C), every grid's numbers those of the grid alone
    (bitwise: the same operations on the same numbers). The one estimate of the limit check, the duration fit
    (one move and many), the verdict engine's screening and the line's searches."""
    x, y = np.asarray(x), np.asarray(y)
    C = y.shape[1]
    if starts is None:
        first = np.zeros((1, 1), np.intp)
        n = np.array([[len(x)]])
        i = (np.argmax(y, axis=0) if i is None else np.asarray(i))[None]
    else:
        starts = np.asarray(starts, dtype=np.intp)
        n = np.diff(starts)
        P = len(n)
        if P == 0:
            return np.zeros((0, C)), np.zeros((0, C))
        first = starts[:-1, None]
        if i is not None:
            i = np.asarray(i)
        elif np.all(n == n[0]):  # grids of one length: one call
            i = np.argmax(y[starts[0] : starts[-1]].reshape(P, int(n[0]), C), axis=1)
        else:  # np.argmax per grid: faster than one call on padded arrays
            i = np.array([np.argmax(y[s:e], axis=0) for s, e in zip(starts[:-1].tolist(), starts[1:].tolist())])
        n = n[:, None]
    # the middle k of the three samples (i itself inside the grid), global rows
    k = np.minimum(np.maximum(i, 1), np.maximum(n - 2, 1)) + first
    i = i + first
    cols = np.arange(C)
    top, at_top = y[i, cols], x[i]
    near = [np.minimum(np.maximum(k + d, 0), len(x) - 1) for d in (-1, 0, 1)]  # (fewer than 3 samples: unused)
    (x0, x1, x2), (y0, y1, y2) = (x[j] for j in near), (y[j, cols] for j in near)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        d1 = (y1 - y0) / (x1 - x0)
        d2 = (y2 - y1) / (x2 - x1)
        curv = (d2 - d1) / (x2 - x0)  # = a of a(x − x1)² + …
        ok = (curv < 0) & (k == i) & (n >= 3)
        if seg is not None:
            s0, s1, s2 = (seg[j] for j in near)
            ok &= (s0 == s1) & (s1 == s2)
        slope = d1 + curv * (x1 - x0)  # the derivative at x1
        safe = np.where(ok, curv, -1.0)
        xv = np.minimum(np.maximum(x1 - slope / (2 * safe), x0), x2)
        yv = y1 - slope**2 / (4 * safe)
        use = ok & (yv >= top)
    peak, at = np.where(use, yv, top), np.where(use, xv, at_top)
    return (peak[0], at[0]) if starts is None else (peak, at)


#: points per call of the peaks' refinement (:func:`refine_max`): a call of a model costs ~0.35 ms, a point ~1.5 µs
REFINE_BUDGET = 512


def _bernstein(n: int, _cache: dict = {}) -> np.ndarray:  # noqa: B006 - deliberate memo
    """(n+1, n+1) matrix M with b = a M: power coefficients a_i of x^i on [0, 1] (lowest first) → Bernstein
    coefficients b_j = Σ_{i≤j} C(j, i)/C(n, i) a_i (the polynomial lies between min b and max b)."""
    if n not in _cache:
        from math import comb

        _cache[n] = np.array([[comb(j, i) / comb(n, i) if i <= j else 0.0 for j in range(n + 1)] for i in range(n + 1)])
    return _cache[n]


def _search(f, a: np.ndarray, b: np.ndarray, cols: np.ndarray, ncol: int, budget: int, target: float,
            rtol: float) -> tuple[np.ndarray, np.ndarray]:
    """:func:`refine_max`'s bracketing grid search with ``rtol`` → (best value, its x) per bracket [a, b] of column
    ``cols``. Each round spreads ``budget`` points over the brackets still searched (8 … 64 inside each: fewer
    brackets, finer rounds) and keeps the two intervals beside each best point. A bracket stops when its best
    point leads both neighbours by at most ``rtol`` of its value, when it is ``target`` of its first width, or when
    it cannot hold its column's maximum: where the function is concave across the bracket its maximum lies at most
    that lead above the best point, so a bracket whose best value plus twice its lead is below a value already
    reached in its column is dropped."""
    k_count = a.size
    a, b = a.copy(), b.copy()
    width = (b - a) * target
    fm, xm = np.full(k_count, -np.inf), a.copy()
    live = np.arange(k_count)
    while live.size:
        p = int(min(64, max(8, budget // live.size)))
        frac = np.linspace(0.0, 1.0, p + 2)
        rows = np.arange(live.size)
        s = a[live, None] + (b[live] - a[live])[:, None] * frac  # (K, p + 2), both ends included
        vals = f(s.ravel()).reshape(live.size, p + 2, -1)[rows, :, cols[live]]
        k = np.argmax(vals, axis=1)
        lo, hi = np.maximum(k - 1, 0), np.minimum(k + 1, p + 1)
        fm[live], xm[live] = vals[rows, k], s[rows, k]
        a[live], b[live] = s[rows, lo], s[rows, hi]
        gap = np.maximum(fm[live] - vals[rows, lo], fm[live] - vals[rows, hi])
        top = np.full(ncol, -np.inf)
        np.maximum.at(top, cols, fm)
        done = (gap <= rtol * np.abs(fm[live])) | (b[live] - a[live] <= width[live])
        done |= fm[live] + 2.0 * gap < top[cols[live]]
        live = live[~done]
    return fm, xm


def _vertex_reach(x: np.ndarray, y: np.ndarray, segments: np.ndarray | None) -> np.ndarray:
    """(N, n_cols): each sample's value, or the vertex of the parabola through it and its two neighbours where that
    opens downward and rises above it (three samples of one segment): how high a local maximum of the samples is
    estimated to reach, for :func:`refine_max`'s ``within``."""
    out = y.copy()
    if len(x) < 3:
        return out
    x0, x1, x2 = x[:-2, None], x[1:-1, None], x[2:, None]
    y0, y1, y2 = y[:-2], y[1:-1], y[2:]
    with np.errstate(divide="ignore", invalid="ignore"):
        d1, d2 = (y1 - y0) / (x1 - x0), (y2 - y1) / (x2 - x1)
        curv = (d2 - d1) / (x2 - x0)
        slope = d1 + curv * (x1 - x0)
        top = np.where(curv < 0, y1 - slope**2 / (4 * np.where(curv < 0, curv, -1.0)), y1)
    if segments is not None:
        one = (segments[:-2] == segments[1:-1]) & (segments[1:-1] == segments[2:])
        top = np.where(one[:, None], top, y1)
    out[1:-1] = np.maximum(y1, np.nan_to_num(top, nan=-np.inf))
    return out


def refine_max(
    fun: Callable[[np.ndarray], np.ndarray],
    x: np.ndarray,
    y: np.ndarray | None = None,
    *,
    max_candidates: int = 8,
    iterations: int = 26,
    segments: np.ndarray | None = None,
    budget: int = REFINE_BUDGET,
    within: np.ndarray | float | None = None,
    rtol: float | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Refine the maxima of each column of ``fun`` beyond the samples ``x`` (N,).

    ``fun(x)`` returns (len(x), n_cols) (or (len(x),)). For each column, the ``max_candidates`` highest
    local maxima of the samples are bracketed by their neighbours and refined by a bracketing grid search:
    each round evaluates p + 2 equally spaced points across every bracket in one call of ``fun`` and keeps the
    two intervals beside the best point (for a maximum that is unimodal in its bracket, it lies there), so a
    bracket shrinks by 2/(p + 1) per call. The rounds continue until the bracket is as small as
    ``iterations`` steps of golden-section search would leave it (0.618^26 = 3.6e-6 of it: ~1e-8 in x for a
    bracket of two 1e-3 sample steps; the value error of a smooth maximum is quadratic in that, ~1e-14
    relative for a peak of width ~0.1). ``fun`` costs far more per call than per point (a model
    evaluation), so p is chosen for about ``budget`` points per call (8 … 64 per bracket): 4–9 calls instead
    of golden-section's 29. Returns (peak (n_cols,), x_peak (n_cols,)): the best point evaluated, never lower
    than the sampled maximum. ``segments`` (N,): a label per sample of the piece it lies on
    (:func:`pickplace_cli.limits.grid.segment_ids`); a bracket never reaches into a neighbour of another
    label, so a search never straddles a jump of ``fun``.

    ``within`` (a number or (n_cols,)): instead of the ``max_candidates`` highest, *every* local maximum of the
    samples whose sampled value, or the vertex of the parabola through it and its neighbours, is at least the
    column's largest sample minus ``within`` is refined (a peak that rises more than ``within`` above that is one
    the grid does not resolve: the grid must be chosen so that none does). Taking the highest samples only is not safe: a time-optimal law rides its
    limit, so a column has dozens of local maxima within 1e-3 of each other, and a narrow peak sampled on its
    flanks can rank below eight of them while its top is the column's maximum (100.005 % of a torque-rate
    limit reported as 99.9 %).

    ``rtol``: a bracket stops early once its best point leads both its neighbours by at most ``rtol`` of its
    value. Where the function is concave across the final bracket (any smooth maximum once the bracket is small;
    a concave corner, such as the torque rate's kink at a law's knot) its maximum there lies at most that lead
    above the best point (the chord slopes of a concave function bound its slopes beyond them), so the peak
    returned is then within ``rtol`` (relative) below the true one; the ``iterations`` bound still caps the
    rounds (it stops a corner between samples first, whose value error is linear in the bracket: ~1e-8 there).
    Brackets that cannot hold their column's maximum are dropped on the way and the points of each call spread
    over the rest (:func:`_search`).
    """
    x = np.asarray(x, dtype=float)
    if y is None:
        y = fun(x)
    y = np.asarray(y, dtype=float)
    squeeze = y.ndim == 1
    if squeeze:
        y = y[:, None]
        f = lambda s: np.asarray(fun(s), dtype=float).reshape(len(s), 1)  # noqa: E731
    else:
        f = lambda s: np.asarray(fun(s), dtype=float)  # noqa: E731
    n, ncol = y.shape
    best = np.max(y, axis=0)
    best_x = x[np.argmax(y, axis=0)]
    if n < 3:
        return (best[0], best_x[0]) if squeeze else (best, best_x)
    # local maxima of the samples (ends included), strongest first, per column
    left = np.vstack([np.full((1, ncol), -np.inf), y[:-1]])
    right = np.vstack([y[1:], np.full((1, ncol), -np.inf)])
    is_peak = (y >= left) & (y >= right)
    lo_list, hi_list, col_list = [], [], []
    floor = None if within is None else best - np.broadcast_to(np.asarray(within, float), best.shape)
    reach = None if floor is None else _vertex_reach(x, y, segments)
    for c in range(ncol):
        idx = np.flatnonzero(is_peak[:, c])
        if floor is None:
            idx = idx[np.argsort(y[idx, c])[::-1][:max_candidates]]
        else:
            idx = idx[reach[idx, c] >= floor[c]]
        lo, hi = np.maximum(idx - 1, 0), np.minimum(idx + 1, n - 1)
        if segments is not None:
            lo = np.where(segments[lo] == segments[idx], lo, idx)
            hi = np.where(segments[hi] == segments[idx], hi, idx)
        lo_list.append(x[lo])
        hi_list.append(x[hi])
        col_list.append(np.full(lo.size, c))
    a = np.concatenate(lo_list)
    b = np.concatenate(hi_list)
    cols = np.concatenate(col_list)
    k_count = a.size
    target = ((np.sqrt(5.0) - 1.0) / 2.0) ** iterations  # golden-section's bracket after ``iterations`` steps
    if rtol is not None:
        fm, xm = _search(f, a, b, cols, ncol, budget, target, rtol)
    else:
        p = int(min(64, max(8, budget // max(k_count, 1))))  # interior points per bracket and call
        rounds = max(1, math.ceil(math.log(target) / math.log(2.0 / (p + 1))))
        frac = np.linspace(0.0, 1.0, p + 2)
        rows = np.arange(k_count)
        for _ in range(rounds):
            s = a[:, None] + (b - a)[:, None] * frac  # (K, p + 2), both ends included
            vals = f(s.ravel()).reshape(k_count, p + 2, -1)[rows, :, cols]  # (K, p + 2): each bracket's column
            k = np.argmax(vals, axis=1)
            fm, xm = vals[rows, k], s[rows, k]
            a = s[rows, np.maximum(k - 1, 0)]
            b = s[rows, np.minimum(k + 1, p + 1)]
    for c in range(ncol):
        sel = cols == c
        if np.any(sel):
            k = np.argmax(fm[sel])
            if fm[sel][k] > best[c]:
                best[c] = fm[sel][k]
                best_x[c] = xm[sel][k]
    return (best[0], best_x[0]) if squeeze else (best, best_x)


#: uniform samples of τ ∈ [0, 1] for the numerical peaks, extremes and the continuity scan (plus the
#: breakpoints and both sides of each); every local maximum is then refined by golden-section search
DENSE = 2001


def _dense_grid(path) -> np.ndarray:
    bp = np.clip(np.asarray(path.breakpoints, float), 0.0, 1.0)
    g = np.unique(np.concatenate([np.linspace(0.0, 1.0, DENSE), bp, np.clip(bp - 1e-11, 0, 1), np.clip(bp + 1e-11, 0, 1)]))
    return g


def true_peaks(path, grid: np.ndarray | None = None, samples: dict[int, np.ndarray] | None = None) -> tuple[float, float, float]:
    """max ‖d^k p/dτ^k‖ for k = 1, 2, 3 over τ ∈ [0, 1] (m/1^k, T = 1), measured on the path: dense
    samples (plus every breakpoint and τ ± 1e-11 on both sides, so a one-sided limit at a jump is seen),
    every local maximum within 5 % of the top refined (:func:`pickplace_cli.curves.peaks.refine_max`)."""
    if grid is None:
        grid = _dense_grid(path)

    def norms(t: np.ndarray) -> np.ndarray:
        o = path.all_orders(t)  # one pass for the three orders (a composed path evaluates its law once)
        return np.column_stack([np.linalg.norm(o[k], axis=1) for k in (1, 2, 3)])

    y = norms(grid) if samples is None else np.column_stack([np.linalg.norm(samples[k], axis=1) for k in (1, 2, 3)])
    # every local maximum within 5 % of each norm's top is refined (not only the eight highest samples')
    peak, _ = refine_max(norms, grid, y, within=0.05 * np.max(y, axis=0))
    return float(peak[0]), float(peak[1]), float(peak[2])
