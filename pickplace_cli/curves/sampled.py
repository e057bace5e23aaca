"""A continuous motion through sampled positions whose jerk may jump: the reconstruction ``check`` runs a
trajectory file through.

An interpolating spline through samples of a motion whose jerk steps (a 3-4-5 law starting from rest, a
superposition of laws, a corner's curvature rate) rings next to the step: its third derivative overshoots the
one-sided values by ~10 % of the step, however fine the sampling, and a torque rate computed from it is then
overstated (a plan at exactly its torque-rate limit read back 8.7 % over it). This module finds the steps with
the essentially non-oscillatory (ENO) idea of Harten, Engquist, Osher & Chakravarthy (1987) and places them
inside their interval by subcell resolution (Harten 1989):

* the roughness of six consecutive samples is their fifth divided difference (p⁽⁵⁾/120 on a smooth motion; a
  jerk step J between two of them makes it ~J/h² larger; round-off makes it ~ε/h⁵, whatever the motion);
* an interval between two samples holds a step when every six-sample stencil over it is ``STEP_RATIO`` times
  rougher than the smoother one-sided stencil beside it and than the median stencil (the data's own level of
  smoothness or noise);
* the samples between steps get each their own interpolating quintic spline (C⁴, not-a-knot ends, as
  :func:`scipy.interpolate.make_interp_spline` builds it), extended to the step, which sits where the two
  splines' accelerations meet (the motion is C² across a jerk step).

The result passes through every sample; without steps it is the interpolating quintic spline itself.
"""

from __future__ import annotations

import numpy as np

#: samples a piece needs: a quintic has 6 coefficients
STENCIL = 6
#: an interval holds a step when the smoothest stencil containing it is this many times rougher (fifth divided
#: difference) than the smoother of the one-sided stencils beside it; smooth data gives ratios of order 1 (the
#: fifth derivative varies over a few samples), a jerk step of size J gives ~J/h² against p⁽⁵⁾
STEP_RATIO = 20.0
#: and the smoother one-sided stencils beside a step are this many times smoother than the roughest across it
SIDE_RATIO = 100.0


def _divided5(t: np.ndarray, p: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """|fifth divided difference| of the 6 samples from each start, the largest over the coordinates: (len(starts),)."""
    idx = starts[:, None] + np.arange(STENCIL)[None, :]
    x, y = t[idx], p[idx]  # (K, 6), (K, 6, d)
    for k in range(1, STENCIL):
        y = (y[:, 1:] - y[:, :-1]) / (x[:, k:] - x[:, :-k])[:, :, None]
    return np.abs(y[:, 0]).max(axis=1)


def steps_of(t: np.ndarray, p: np.ndarray) -> np.ndarray:
    """The intervals k (between samples k and k + 1) that hold a jerk step, increasing; none with fewer than 12
    samples. A step makes every six-sample stencil across it rough (its fifth divided difference ``STEP_RATIO``
    times the median stencil's or more): a run of two or more consecutive rough stencils starting at s₁ … s₂ holds
    a step in the samples they share, s₂ … s₁ + 5; of those intervals the one whose one-sided stencils on either
    side are the smoothest is the step's (a step right next to a sample leaves the stencil that starts or ends
    there smooth, so the run can be shorter than five)."""
    n = len(t)
    if n < 2 * STENCIL:
        return np.zeros(0, int)
    last = n - STENCIL
    rough = _divided5(t, p, np.arange(last + 1))
    level = max(float(np.median(rough)), 1e-300)
    hot = rough > STEP_RATIO * level
    out = []
    k = 0
    while k <= last:
        if not hot[k]:
            k += 1
            continue
        s1 = k
        while k + 1 <= last and hot[k + 1]:
            k += 1
        s2 = k
        k += 1
        if s2 == s1:  # one rough stencil alone: noise, or a step at the ends of the data
            continue
        cand = np.arange(max(s2, STENCIL - 1), min(s1 + STENCIL - 1, n - STENCIL - 1) + 1)
        if not cand.size:
            continue
        side = np.maximum(rough[cand - (STENCIL - 1)], rough[cand + 1])
        best = cand[int(np.argmin(side))]
        peak = float(rough[s1:s2 + 1].max())
        # both sides smooth, and far smoother than the run: a step inside this interval (a sharp but smooth feature,
        # e.g. a time law's quick start, roughens its neighbours too and is left to the interpolating spline)
        if side.min() <= STEP_RATIO * level and side.min() * SIDE_RATIO <= peak:
            if out and best - out[-1] < STENCIL:  # two steps closer than a stencil: the stretch between them is
                continue  # too short for its own spline; the first one is kept
            out.append(int(best))
    return np.array(out, int)


def reconstruct(t: np.ndarray, p: np.ndarray):
    """(evaluate(x, nu) → (len(x), d), the times [s] of the jerk steps found) for samples at t (N,) s, increasing,
    of positions p (N, d) m: the interpolating quintic spline of the samples between steps, each extended to its
    steps (module docstring). Needs N ≥ 6."""
    from scipy.interpolate import make_interp_spline

    t = np.asarray(t, float)
    p = np.asarray(p, float)
    n = len(t)
    if n < STENCIL:
        raise ValueError(f"{n} samples: a quintic needs {STENCIL}")
    ks = steps_of(t, p)
    bounds = np.concatenate([[0], ks + 1, [n]])  # the samples of segment i: bounds[i] … bounds[i + 1] − 1
    splines = []
    for lo, hi in zip(bounds[:-1], bounds[1:]):
        m = hi - lo
        splines.append(make_interp_spline(t[lo:hi], p[lo:hi], k=min(5, m - 1 - (m % 2 == 1 and m < 6))))
    cuts = np.array([_join_time(splines[i], splines[i + 1], t[kk], t[kk + 1]) for i, kk in enumerate(ks)])

    def evaluate(x: np.ndarray, nu: int = 0) -> np.ndarray:
        x = np.asarray(x, float)
        if not cuts.size:
            return splines[0](x, nu)
        seg = np.searchsorted(cuts, x, side="right")
        out = np.empty((len(x), p.shape[1]))
        for i in np.unique(seg):
            sel = seg == i
            out[sel] = splines[i](x[sel], nu)
        return out

    return evaluate, cuts


def _join_time(left, right, t0: float, t1: float) -> float:
    """Where the accelerations of the two splines meet in [t0, t1] (least squares over the coordinates of the nearly
    linear difference a_R − a_L ≈ J·(t − t*)); the middle when they run parallel."""
    f0 = right(t0, 2) - left(t0, 2)
    f1 = right(t1, 2) - left(t1, 2)
    slope = (f1 - f0) / (t1 - t0)
    den = float(np.dot(slope, slope))
    if den <= 0.0:
        return 0.5 * (t0 + t1)
    return float(t0 + min(max(-float(np.dot(f0, slope)) / den, 0.0), t1 - t0))


def noise_level(t: np.ndarray, p: np.ndarray) -> float:
    """The standard deviation [m] of white noise on the positions ``p`` (N, d), the largest over the coordinates,
    from their sixth differences (variance 924 σ² for white noise; a smooth motion adds only h⁶·p⁽⁶⁾), robustly
    (1.4826 × the median absolute value); 0 for fewer than 7 samples."""
    p = np.asarray(p, float)
    if len(p) < 7:
        return 0.0
    d6 = np.diff(p, n=6, axis=0)
    return float((1.4826 * np.median(np.abs(d6), axis=0) / np.sqrt(924.0)).max())


def hermite(t: np.ndarray, p: np.ndarray, v: np.ndarray, a: np.ndarray, j: np.ndarray, overshoot: bool = True,
            whole: np.ndarray | None = None):
    """(evaluate(x, nu) → (len(x), d), the times [s] of the jerk steps found) for samples at ``t`` (N,) s of positions,
    velocities, accelerations and jerks (each (N, d), m and its derivatives): the septic Hermite interpolant, C³ and
    exact at every sample (:meth:`scipy.interpolate.BPoly.from_derivatives`). An interval across which the jerk steps
    (its jump |j(k+1) − j(k)| more than ``STEP_RATIO`` times its neighbours' and the median's: a smooth motion's
    jumps vary slowly, ~h·snap) is not interpolated across the step: its two sides are the cubics of the samples'
    own jerk, from each end, joined where their accelerations meet (the motion is C² across the step). ``overshoot``
    False: only the jumps are steps, not the intervals whose interpolant's jerk overshoots (:func:`overshooting`);
    ``whole``: intervals (indices) left whole whatever their overshoot."""
    from scipy.interpolate import PPoly

    t = np.asarray(t, float)
    data = np.stack([p, v, a, j], axis=1)  # (N, 4, d)
    pp = PPoly(septic_coefficients(t, data), t)
    n = len(t)
    if n < 4:
        return (lambda x, nu=0: pp(np.asarray(x, float), nu)), np.zeros(0)
    ks = _jerk_jumps(j)
    if overshoot:
        ks = np.union1d(ks, np.setdiff1d(overshooting(pp, t, np.asarray(j, float), ks),
                                         np.zeros(0, int) if whole is None else whole))
    if not ks.size:
        return (lambda x, nu=0: pp(np.asarray(x, float), nu)), np.zeros(0)
    x = list(t)
    cols = [pp.c[:, i] for i in range(n - 1)]  # (8, d) each, powers of (t − t_i), highest first
    cuts = []
    for k in sorted(ks, reverse=True):
        h = t[k + 1] - t[k]
        a0, a1, j0, j1 = data[k, 2], data[k + 1, 2], data[k, 3], data[k + 1, 3]
        den = float(np.dot(j0 - j1, j0 - j1))
        # a0 + j0·s = a1 − j1·(h − s): least squares over the coordinates, inside the interval
        s = float(np.dot(a1 - a0 - j1 * h, j0 - j1)) / den if den > 0 else 0.5 * h
        s = min(max(s, 0.0), h)
        lo = _taylor(data[k], 0.0)  # powers of (t − t_k)
        hi = _taylor(data[k + 1], s - h)  # the cubic from t_(k+1), re-centred at the step
        cols[k] = np.concatenate([np.zeros((4, lo.shape[1])), lo])
        cols.insert(k + 1, np.concatenate([np.zeros((4, hi.shape[1])), hi]))
        x.insert(k + 1, t[k] + s)
        cuts.append(t[k] + s)
    split = PPoly(np.stack(cols, axis=1), np.array(x))
    return (lambda xx, nu=0: split(np.asarray(xx, float), nu)), np.array(sorted(cuts))


#: the septic's coefficients d4 … d7 of u⁴ … u⁷ (u = (t − t_k)/h on one interval) from what the end conditions at u = 1
#: leave: rows Σ d_k, Σ k·d_k, Σ k(k−1)·d_k, Σ k(k−1)(k−2)·d_k over k = 4 … 7
_SEPTIC_END = np.linalg.inv(np.array([[1.0, 1.0, 1.0, 1.0], [4.0, 5.0, 6.0, 7.0], [12.0, 20.0, 30.0, 42.0],
                                      [24.0, 60.0, 120.0, 210.0]]))
#: the same sums over k = 0 … 3 (what d0 … d3, fixed by the left end, contribute)
_SEPTIC_START = np.array([[1.0, 1.0, 1.0, 1.0], [0.0, 1.0, 2.0, 3.0], [0.0, 0.0, 2.0, 6.0], [0.0, 0.0, 0.0, 6.0]])


def septic_coefficients(t: np.ndarray, data: np.ndarray) -> np.ndarray:
    """The septic Hermite interpolant through positions, velocities, accelerations and jerks ``data`` (N, 4, d) at
    ``t`` (N,), as :class:`scipy.interpolate.PPoly` coefficients (8, N − 1, d): powers of (t − t_k), highest first.
    The same polynomial as ``BPoly.from_derivatives`` (unique: 8 conditions, degree 7), solved on every interval at
    once: on u = (t − t_k)/h the left end fixes d0 … d3 (p, h·v, h²·a/2, h³·j/6), and the right end's four
    conditions a constant 4 × 4 system for d4 … d7."""
    t = np.asarray(t, float)
    h = np.diff(t)[:, None]  # (N − 1, 1)
    lo, hi = data[:-1], data[1:]  # (N − 1, 4, d)
    scale = np.stack([np.ones_like(h), h, h * h, h**3], axis=1)  # (N − 1, 4, 1): h^order
    d03 = lo * scale / np.array([1.0, 1.0, 2.0, 6.0])[None, :, None]
    rhs = hi * scale - np.einsum("rk,nkd->nrd", _SEPTIC_START, d03)
    d47 = np.einsum("kr,nrd->nkd", _SEPTIC_END, rhs)
    d = np.concatenate([d03, d47], axis=1)  # (N − 1, 8, d): powers u⁰ … u⁷
    c = d / h[:, :, None] ** np.arange(8)[None, :, None]
    return np.ascontiguousarray(c[:, ::-1].transpose(1, 0, 2))


def overshoot_only(t: np.ndarray, p: np.ndarray, v: np.ndarray, a: np.ndarray, j: np.ndarray) -> np.ndarray:
    """The intervals :func:`hermite` splits only because its interpolant's jerk overshoots there (no jump of the
    samples' jerk): a jerk step near a sample, or a real extreme of the jerk the samples under-resolve. Both are
    possible from the samples alone, so a reader takes both readings (``limits.samples``)."""
    t = np.asarray(t, float)
    if len(t) < 8:
        return np.zeros(0, int)
    from scipy.interpolate import PPoly

    pp = PPoly(septic_coefficients(t, np.stack([p, v, a, j], axis=1)), t)
    return overshooting(pp, t, np.asarray(j, float), _jerk_jumps(j))


def _jerk_jumps(j: np.ndarray) -> np.ndarray:
    """The intervals across which the samples' jerk ``j`` (N, d) jumps: |j(k+1) − j(k)| more than ``STEP_RATIO``
    times its neighbours' and the median's (a smooth motion's jumps vary slowly, ~h·snap)."""
    dj = np.linalg.norm(np.diff(np.asarray(j, float), axis=0), axis=1)  # (N − 1,)
    left = np.concatenate([[0.0], dj[:-1]])
    right = np.concatenate([dj[1:], [0.0]])
    level = max(float(np.median(dj)), 1e-300)
    return np.flatnonzero(dj > STEP_RATIO * np.maximum(np.maximum(left, right), level))


def overshooting(pp, t: np.ndarray, j: np.ndarray, jumps: np.ndarray | None = None) -> np.ndarray:
    """The intervals where the Hermite interpolant's jerk leaves the range of the two samples' own jerks by more
    than a smooth motion can: a smooth extreme between two samples bulges by about |Δ²j|/8 (the jerk's second
    difference over three samples), so an interval whose bulge is more than 4 × that of the samples on either
    side (each side's three samples away from the interval, untouched by a step inside it) and more than 0.1 % of
    the largest jerk holds a jerk step the jump test may miss (a step near a sample, or next to another). ``jumps``:
    intervals already found to hold a step (left out of the answer)."""
    n = len(t)
    if n < 8:
        return np.zeros(0, int)
    u = np.linspace(0.0, 1.0, 9)[1:-1]
    x = t[:-1, None] + (t[1:] - t[:-1])[:, None] * u  # (n − 1, 7)
    jh = pp(x.ravel(), 3).reshape(n - 1, len(u), -1)  # (n − 1, 7, d)
    hi = np.maximum(j[:-1], j[1:])
    lo = np.minimum(j[:-1], j[1:])
    bulge = np.maximum(np.maximum(jh.max(axis=1) - hi, lo - jh.min(axis=1)), 0.0)  # (n − 1, d)
    d2 = np.abs(j[2:] - 2.0 * j[1:-1] + j[:-2])  # (n − 2, d): centred at samples 1 … n − 2
    k = np.arange(n - 1)
    left = np.where((k >= 2)[:, None], d2[np.clip(k - 2, 0, n - 3)], np.inf)  # samples k − 2 … k
    right = np.where((k + 3 <= n - 1)[:, None], d2[np.clip(k + 1, 0, n - 3)], np.inf)  # samples k + 1 … k + 3
    smooth = np.minimum(np.maximum(left, right), np.where(np.isinf(left), right, np.where(np.isinf(right), left,
                                                                                            np.maximum(left, right))))
    scale = 1e-3 * float(np.abs(j).max())
    flag = np.any((bulge > 4.0 * smooth / 8.0) & (bulge > scale), axis=1)
    return np.setdiff1d(np.flatnonzero(flag), np.zeros(0, int) if jumps is None else jumps)


def _taylor(row: np.ndarray, d: float) -> np.ndarray:
    """The cubic p + v·s + a·s²/2 + j·s³/6 about a sample (``row`` (4, dims): p, v, a, j) written in powers of
    (s − d), highest first: (4, dims)."""
    p, v, a, j = row
    # shift: s = u + d
    c3 = j / 6.0
    c2 = a / 2.0 + 3.0 * c3 * d
    c1 = v + a * d + 3.0 * c3 * d * d
    c0 = p + v * d + a * d * d / 2.0 + c3 * d**3
    return np.stack([c3, c2, c1, c0])
