"""The limit check: every joint × quantity of a :class:`~pickplace_cli.limits.motion.MotionModel` at a
duration T → :class:`~pickplace_cli.limits.report.LimitReport` (:func:`check_limits`).

The model (:mod:`~pickplace_cli.limits.motion`) gives each quantity as a function of τ that scales exactly with T;
the grid (:mod:`~pickplace_cli.limits.grid`) says where to look. Peaks are found on the continuous trajectory:
sampled, then refined at the top sample by the vertex of the parabola through it and its neighbours; a column whose
peak comes within ``EXACT_BAND`` of its limit is refined exactly on the model itself, so the verdict near a limit
does not depend on sampling:

* every local maximum of its samples that reaches (by its sample, or by the vertex of the parabola through it and
  its neighbours) within ``EXACT_BAND`` of the limit below the column's largest sample is bracketed by its
  neighbours (never across a jump) and searched (:func:`~pickplace_cli.curves.peaks.refine_max`
  with ``within``), not only the highest few: a time-optimal law rides its limit, with dozens of local maxima
  within 1e-3 of each other, and a peak sampled on its flanks can rank low while it is the column's maximum;
* each search stops when its best point leads both neighbours by at most ``EXACT_RTOL`` of its value: the peak
  reported is the model's own value there, at most that far below the true maximum of a concave peak (a corner
  between two samples stops at the search's bracket limit first, ~1e-8; the path's knots and jumps are samples).

The precondition is the grid's: no local maximum of a limited quantity rises more than ``EXACT_BAND`` of its
limit above that estimate (measured on every shipped profile's default and time-optimal plans:
under 1 %, tests/unit/test_check_peaks.py).
"""

from __future__ import annotations

import numpy as np

from ..curves.peaks import parabolic_peak
from ..model.errors import UnreachableError
from .grid import interior_jumps, segment_ids
from .motion import EXACT_BAND, MotionModel, Parts
from .report import LimitReport, LimitRow


#: points per bracket of :func:`_zoom_peak` (the bracket's two ends are grid points already)
ZOOM_POINTS = 7
#: a column's second-highest local maximum of the samples is zoomed too when it is within this fraction
#: of the highest (the grid's parabola is never more than 1 % off, so a lower one cannot be the peak)
ZOOM_RIVAL = 0.02


#: a peak whose parabolic estimate may be off by more than this fraction of it is zoomed in on
ZOOM_TOL = 1e-4
#: the exact refinement of a peak near its limit stops when the peak is known to this fraction of it (the best
#: point's lead over its neighbours, :func:`~pickplace_cli.curves.peaks.refine_max`'s ``rtol``)
EXACT_RTOL = 1e-10


def _unresolved(x: np.ndarray, y: np.ndarray, i: np.ndarray, xv: np.ndarray, seg: np.ndarray | None) -> np.ndarray:
    """Which columns' parabolic peak estimates (vertex at ``xv``, through samples i−1, i, i+1) may be off by
    more than ``ZOOM_TOL`` of the peak: the parabola's error at its vertex is about
    f‴/6·(x − x₀)(x − x₁)(x − x₂), with f‴/6 the larger third divided difference of the four-point windows
    around i; a peak without four samples of one segment around it (at a jump, an end) counts as
    unresolved. → (n_cols,) bool."""
    n, ncol = y.shape
    if n < 5:
        return np.ones(ncol, bool)
    cols = np.arange(ncol)
    out = np.zeros(ncol, bool)
    k = np.minimum(np.maximum(i, 2), n - 3)
    err = np.zeros(ncol)
    for start in (k - 2, k - 1):  # windows i−2..i+1 and i−1..i+2
        w = start[None, :] + np.arange(4)[:, None]  # (4, n_cols)
        xs, ys = x[w], y[w, cols]
        d1 = (ys[1:] - ys[:-1]) / (xs[1:] - xs[:-1])
        d2 = (d1[1:] - d1[:-1]) / (xs[2:] - xs[:-2])
        d3 = (d2[1:] - d2[:-1]) / (xs[3:] - xs[:-3])
        err = np.maximum(err, np.abs(d3[0]))
        if seg is not None:
            out |= np.any(seg[w] != seg[w[0]], axis=0)
    x0, x1, x2 = x[np.maximum(i - 1, 0)], x[i], x[np.minimum(i + 1, n - 1)]
    err *= np.abs((xv - x0) * (xv - x1) * (xv - x2))
    out |= (k != i) | (err > ZOOM_TOL * np.abs(y[i, cols]))
    return out


def _zoom_peak(model: "MotionModel", T: float, x: np.ndarray, data: np.ndarray, seg: np.ndarray | None,
               rates: bool, cols: np.ndarray, sub: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every column's peak, zoomed in: the highest local maximum of the samples of each column (and the
    second highest when within ``ZOOM_RIVAL`` of it) is bracketed by its neighbours (never across a jump,
    ``seg``), the model is evaluated at ``ZOOM_POINTS`` more points inside each distinct bracket (one call
    for all columns), and the peak is the vertex of the parabola through the best zoomed sample and its
    neighbours (else that sample). The bracket is 8× finer than the grid, so the estimate's error
    (quadratic in the spacing) is ~60× smaller than a parabola through the grid's samples: ~1e-4 relative
    on a PH corner's narrow torque-rate peak at a 500 Hz output rate, where the grid's parabola misses by
    0.6 %. Zooms the columns ``cols`` of ``data``; ``sub``: their indices among the columns of the model
    without the singularity measure (which the zoom skips). → (peak, τ of the peak), each (len(cols),)."""
    data = data[:, cols]
    n, ncol = data.shape
    cols = np.arange(ncol)
    i1 = np.argmax(data, axis=0)
    if n < 3:
        return data[i1, cols], x[i1]
    top1 = data[i1, cols]
    left = np.vstack([np.full((1, ncol), -np.inf), data[:-1]])
    right = np.vstack([data[1:], np.full((1, ncol), -np.inf)])
    other = np.where((data >= left) & (data >= right), data, -np.inf)
    other[np.maximum(i1 - 1, 0), cols] = other[i1, cols] = other[np.minimum(i1 + 1, n - 1), cols] = -np.inf
    i2 = np.argmax(other, axis=0)
    rival = other[i2, cols] >= top1 - ZOOM_RIVAL * np.abs(top1)
    idx = np.concatenate([i1, i2[rival]])  # one bracket per candidate, its column in ``col``
    col = np.concatenate([cols, cols[rival]])
    lo, hi = np.maximum(idx - 1, 0), np.minimum(idx + 1, n - 1)
    if seg is not None:
        lo = np.where(seg[lo] == seg[idx], lo, idx)
        hi = np.where(seg[hi] == seg[idx], hi, idx)
    # the distinct brackets (columns often share one: the ends of the move, one joint's quantities)
    key, which = np.unique(lo * n + hi, return_inverse=True)
    which = which.ravel()
    a, b = x[key // n], x[key % n]
    u = np.linspace(0.0, 1.0, ZOOM_POINTS + 2)
    s = a[:, None] + (b - a)[:, None] * u  # (brackets, Z + 2), the ends = the bracket's grid points
    pr = model.parts(np.clip(s[:, 1:-1].ravel(), 0.0, 1.0), derivatives=rates, singularity=False)
    vals = model.columns(pr, T)[1][:, sub].reshape(len(key), ZOOM_POINTS, ncol)[which, :, col]  # (candidates, Z)
    y = np.concatenate([data[lo, col][:, None], vals, data[hi, col][:, None]], axis=1)
    s, g = s[which], ZOOM_POINTS + 2  # each candidate's own grid of g points: one stacked call
    top, at = (v[:, 0] for v in parabolic_peak(s.ravel(), y.reshape(-1, 1), np.arange(0, len(s) * g + 1, g)))
    peak, where = top[:ncol].copy(), at[:ncol].copy()
    for r in np.flatnonzero(rival):  # a rival that zooms higher wins
        c = ncol + int(np.sum(rival[:r]))
        if top[c] > peak[r]:
            peak[r], where[r] = top[c], at[c]
    return peak, where


def check_limits(
    model: MotionModel,
    T: float,
    tau: np.ndarray | None = None,
    parts: Parts | None = None,
    dwell: float = 0.0,
    notes: tuple[str, ...] = (),
) -> LimitReport:
    """Check every limit of ``model`` at duration ``T`` [s] → LimitReport.

    ``parts``: the model evaluated on ``tau`` (samples; computed here when None): the peaks are found on
    it, then refined (module docstring); the RMS torque is integrated on the model itself
    (:meth:`MotionModel.rms_integrals`), whatever the grid.
    """
    from ..curves.peaks import refine_max

    if parts is None:
        if tau is None:
            tau = np.linspace(0.0, 1.0, 1001)
        parts = model.parts(tau)
    x = parts.tau
    meta, data = model.columns(parts, T)
    if parts.order is not None:  # the grid is unsorted (output samples first): peaks need neighbours in τ
        x = x[parts.order]
        data = data[parts.order]
    plan = model.report_plan(parts.dAm is not None, parts.singularity is not None)
    rows: list[LimitRow] = []
    if data.shape[1]:
        seg = segment_ids(x, interior_jumps(model.path.breakpoints, model.path.jumps))
        imax = np.argmax(data, axis=0)
        peak, at = parabolic_peak(x, data, seg=seg, i=imax)
        limits = plan.limits  # in column sign convention
        close = (np.abs(peak - limits) <= plan.band) | (peak > limits)  # refined exactly below: no zoom needed
        # the duration-dependent peaks the grid does not resolve (a sharp one), zoomed in on the model
        zoom = plan.zoom[_unresolved(x, data[:, plan.zoom], imax[plan.zoom], at[plan.zoom], seg) & ~close[plan.zoom]]
        if zoom.size:
            sub = plan.zoom_sub[np.searchsorted(plan.zoom, zoom)]
            peak[zoom], at[zoom] = _zoom_peak(model, T, x, data, seg, parts.dAm is not None, zoom, sub)
        # refine exactly every peak near its limit or apparently beyond it (a violation is always confirmed
        # on the model itself, never taken from an interpolated estimate)
        near = np.flatnonzero(close | (np.abs(peak - limits) <= plan.band) | (peak > limits))
        if near.size:
            # only timed limits near: the model without its singularity measure, their columns there (a call is
            # ~30 % cheaper on a few points)
            timed = bool(np.isin(near, plan.zoom).all())
            cols = plan.zoom_sub[np.searchsorted(plan.zoom, near)] if timed else near
            sing = parts.singularity is not None and not timed  # (the columns of ``parts`` otherwise)

            def fun(s: np.ndarray) -> np.ndarray:
                pr = model.parts(np.clip(s, 0.0, 1.0), derivatives=parts.dAm is not None, singularity=sing)
                return model.columns(pr, T)[1][:, cols]

            # the exact value replaces the estimate; it is never below the sampled maximum
            exact, exact_at = refine_max(fun, x, data[:, near], segments=seg, within=plan.band[near], rtol=EXACT_RTOL)
            peak[near] = exact
            at[near] = exact_at
        values = (plan.signs * peak).tolist()
        times = (at * T).tolist()
    rms = model.rms_motor_torque(T, dwell, parts) if plan.rms else None
    # the rows in report order (joint by joint, its position range first), as planned once per profile
    for kind, c, spec in plan.rows:
        if kind == "single":
            joint, quantity, unit, limit, reach, lower = spec
            value = values[c]
            if lower:  # a minimum that must stay above the limit (singularity measure)
                util = limit / value if value > 0 else float("inf")
                rows.append(LimitRow(joint, quantity, unit, value, limit, util, times[c], value >= limit, reach, "lower"))
            else:
                rows.append(LimitRow(joint, quantity, unit, value, limit, value / limit, times[c], value <= limit, reach))
        elif kind == "range":
            rows.append(_range_row(spec, values[c[0]], values[c[1]], times[c[0]], times[c[1]]))
        else:  # RMS over the duty cycle
            joint, lim = spec
            r = float(rms[c])
            rows.append(LimitRow(joint, "rms motor torque", "N·m", r, lim, r / lim, None, r <= lim))
    return LimitReport(tuple(rows), T, dwell, notes)


def _range_row(spec: tuple, vmax: float, vmin: float, tmax: float, tmin: float) -> LimitRow:
    """One row for a [min, max] range: the side nearer its bound; utilisation = |x − mid| / half-range."""
    joint, base, unit, kind, lo, hi = spec
    mid, half = (lo + hi) / 2, (hi - lo) / 2
    u_hi, u_lo = (vmax - mid) / half, (mid - vmin) / half
    ok = vmax <= hi + 1e-12 and vmin >= lo - 1e-12
    if u_hi >= u_lo or u_hi != u_hi:  # (a NaN side is the side shown: it fails)
        return LimitRow(joint, base, unit, vmax, hi, u_hi, tmax, ok, kind, "upper")
    return LimitRow(joint, base, unit, vmin, lo, u_lo, tmin, ok, kind, "lower")


def reach_error(exc: UnreachableError, tau: np.ndarray, T: float | None) -> UnreachableError:
    """Re-raise an IK failure with the time of the failing sample (or its fraction of the move)."""
    if exc.index is None:
        return exc
    s = float(tau[exc.index])
    when = f"t = {s * T:.6g} s" if T else f"τ = {s:.4f} of the move"
    return UnreachableError(f"{exc} at {when}", index=exc.index)


def capacity_rows(path, T: float, capacity, not_held: str = "", grid: np.ndarray | None = None) -> tuple[LimitRow, ...]:
    """The Cartesian capacity as limit rows of the tool [Li2018, Eq. (24)–(25)]: |v| ≤ [v], |a| ≤ [a] (and |j| ≤ [j]
    when the profile sets it) [m/s, m/s², m/s³].

    Without ``grid`` each peak is the path's own exact normalised peak scaled to T [s] (v̂/T, â/T², ĵ/T³; a time-law
    path's peaks are its composed ones, found on the continuous motion) and its time is not located (t_peak None).
    With ``grid`` (τ samples, e.g. a checked file's) the peaks are found on the continuous path as the joint check
    finds its own: sampled there, each local maximum refined on the path itself (never across a jump), with their
    times. ``not_held``: why the duration rule does not hold the capacity ("" when it does): the rows are then
    reported, not judged (:attr:`LimitRow.not_held`)."""
    if grid is None:
        v, a, j = path.peaks
        at = (None, None, None)
    else:
        from ..curves.peaks import refine_max

        def norms(tau: np.ndarray) -> np.ndarray:
            o = path.all_orders(np.clip(tau, 0.0, 1.0))
            return np.column_stack([np.linalg.norm(o[k], axis=1) for k in (1, 2, 3)])

        x = np.unique(np.clip(np.asarray(grid, float), 0.0, 1.0))
        seg = segment_ids(x, interior_jumps(path.breakpoints, path.jumps))
        y = norms(x)  # every local maximum within the exact band of each norm's top is refined, as for the joints
        peak, where = refine_max(norms, x, y, segments=seg, within=EXACT_BAND * y.max(axis=0), rtol=EXACT_RTOL)
        v, a, j = (float(p) for p in peak)
        at = tuple(float(w) * T for w in where)
    rows = [("speed", "m/s", v / T, capacity.velocity, at[0]),
            ("acceleration", "m/s²", a / T**2, capacity.acceleration, at[1])]
    if capacity.jerk is not None:
        rows.append(("jerk", "m/s³", j / T**3, capacity.jerk, at[2]))
    return tuple(LimitRow("tool", f"capacity {q}", unit, float(peak), float(lim), float(peak) / lim, when,
                          bool(peak <= lim * (1.0 + 1e-12)), "limit", not_held=not_held)
                 for q, unit, peak, lim, when in rows)
