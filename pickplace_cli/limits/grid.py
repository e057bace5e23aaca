"""Where the limit check evaluates the model: the τ grids (check, fit), and the RMS quadrature.

Every quantity is smooth inside a segment between the path's jumps, so the grids hold the path's breakpoints,
a few points per span and both sides of every jump (:func:`check_grid`); the RMS integrals are adaptive
Gauss–Kronrod 7/15 on the spans between breakpoints and jumps (:func:`rms_edges`, :func:`adaptive_gk15`).
"""

from __future__ import annotations

import numpy as np

#: the check samples at least this many uniform points of τ ∈ [0, 1] (plus the output samples, the
#: path's breakpoints, 15 points inside every span between breakpoints (:func:`span_nodes`), both sides of every
#: jump), so a peak's refinement does not depend on the output rate. Every quantity is smooth inside a
#: segment between the path's jumps (the paths are C² or better there, the robot models analytic away from
#: singularities), so a few points per span locate its local maxima; the parabolic estimate through three
#: points of one segment is never more than 4e-3 below the true peak (measured on every method and robot;
#: the test holds 1 %), far inside the 5 % band refined exactly (``EXACT_BAND``). At a jump (a law's jerk
#: steps, so the torque rate steps) the peak is the larger one-sided limit: the grid holds a point
#: ``JUMP_SIDE`` to each side, no parabola and no refinement bracket ever spans a jump, so the estimate there
#: is the one-sided value itself, whatever the output rate.
CHECK_SAMPLES = 129
#: the points each side of a jump sit this far from it in τ (the one-sided limits, to ~1e-8 relative)
JUMP_SIDE = 1e-8
#: samples of τ ∈ [0, 1] on which ``--time fit`` screens the peaks (plus the check's extra points)
FIT_SAMPLES = 1001


def check_grid(tau: np.ndarray, breakpoints: np.ndarray, jumps: np.ndarray | None = None) -> np.ndarray:
    """The τ grid the limit check samples: output samples ∪ uniform grid ∪ breakpoints ∪ points per span ∪
    both sides of every jump (``jumps``: None = every interior breakpoint, see :class:`CartesianPath`)."""
    grid, order = check_grid_order(tau, breakpoints, jumps)
    return grid[order]


def span_nodes(breakpoints: np.ndarray, jumps: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The start partition of the RMS integral (:func:`rms_edges`) and its Gauss–Kronrod nodes (15 per
    span, interior, denser towards the span's ends where a knot changes the curvature), memoised per
    breakpoints and jumps. The check grid and the fit grid contain the nodes: every span between
    breakpoints is sampled however short it is, and the RMS integral's first round is read off the grid."""
    jkey = None if jumps is None else tuple(np.asarray(jumps, float).tolist())
    key = (tuple(np.asarray(breakpoints, float).tolist()), jkey)
    hit = _NODES.get(key)
    if hit is None:
        edges = rms_edges(breakpoints, interior_jumps(breakpoints, jumps))
        c, h = 0.5 * (edges[1:] + edges[:-1]), 0.5 * np.diff(edges)
        hit = (edges, (c[:, None] + h[:, None] * GK_NODES).ravel())
        if len(_NODES) > 256:
            _NODES.clear()
        _NODES[key] = hit
    return hit


_NODES: dict = {}


def interior_jumps(breakpoints: np.ndarray, jumps: np.ndarray | None) -> np.ndarray:
    """The sorted interior τ ∈ (0, 1) of the jumps (every interior breakpoint when ``jumps`` is None)."""
    j = np.unique(np.asarray(breakpoints if jumps is None else jumps, float))
    return j[(j > 0.0) & (j < 1.0)]


def jump_sides(breakpoints: np.ndarray, jumps: np.ndarray | None) -> np.ndarray:
    """Points ``JUMP_SIDE`` before and after every interior jump (nearer when a span is shorter)."""
    j = interior_jumps(breakpoints, jumps)
    if not j.size:
        return j
    knots = np.unique(np.concatenate([[0.0, 1.0], np.asarray(breakpoints, float), j]))
    i = np.searchsorted(knots, j)
    d = np.minimum(JUMP_SIDE, 0.25 * np.minimum(j - knots[i - 1], knots[np.minimum(i + 1, len(knots) - 1)] - j))
    return np.concatenate([j - d, j + d])


def segment_ids(x: np.ndarray, jumps: np.ndarray) -> np.ndarray | None:
    """Segment of each sorted τ in ``x`` between the interior ``jumps`` (sorted): 2k inside the k-th
    segment, 2k+1 exactly at the k-th jump (a point on a jump belongs to neither side). None: no jumps."""
    if not len(jumps):
        return None
    return np.searchsorted(jumps, x, side="left") + np.searchsorted(jumps, x, side="right")


def _extra_points(breakpoints: np.ndarray, jumps: np.ndarray | None, uniform: bool | int) -> np.ndarray:
    """The sorted points the check adds to the output samples: breakpoints ∪ span points ∪ jump sides (∪ a
    uniform grid of ``CHECK_SAMPLES`` points, or of ``uniform`` points when it is an int > 1), without
    round-off twins (memoised per breakpoints and jumps, like :func:`span_nodes`)."""
    jkey = None if jumps is None else tuple(np.asarray(jumps, float).tolist())
    key = (tuple(np.asarray(breakpoints, float).tolist()), jkey, uniform)
    hit = _EXTRA.get(key)
    if hit is None:
        n = uniform if (uniform is not True and int(uniform) > 1) else (CHECK_SAMPLES if uniform else 0)
        parts = [breakpoints, span_nodes(breakpoints, jumps)[1], jump_sides(breakpoints, jumps)]
        if n:
            parts.append(np.linspace(0.0, 1.0, int(n)))
        hit = np.unique(np.concatenate(parts))
        hit = hit[np.concatenate([[True], np.diff(hit) > 1e-9])]
        if len(_EXTRA) > 256:
            _EXTRA.clear()
        _EXTRA[key] = hit
    return hit


_EXTRA: dict = {}


def fit_grid(breakpoints: np.ndarray, jumps: np.ndarray | None = None) -> np.ndarray:
    """The sorted τ grid ``--time fit`` screens on: ``FIT_SAMPLES`` uniform points ∪ the check's extra points."""
    return _extra_points(breakpoints, jumps, FIT_SAMPLES)


def check_grid_order(tau: np.ndarray, breakpoints: np.ndarray,
                     jumps: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The check grid with the output samples ``tau`` (sorted) first, then the extra points, and the
    permutation ``order`` that sorts it (``grid[order]`` is :func:`check_grid`). The model evaluated on this
    grid gives the output samples as its first ``len(tau)`` rows (views, no gather); pass ``order`` to
    :meth:`MotionModel.parts` so the check sorts what it needs.

    Extra points within 1e-9 of an output sample or of each other (round-off twins) are dropped, so
    every output sample is in the grid exactly. When the output samples already cover [0, 1] at least as
    densely as the uniform grid (e.g. 1 kHz for a move of 0.128 s or longer), the uniform grid adds nothing
    and is left out."""
    tau = np.asarray(tau, float)
    dense = (
        len(tau) >= CHECK_SAMPLES
        and tau[0] <= 0.0
        and tau[-1] >= 1.0
        and float((tau[1:] - tau[:-1]).max()) <= 1.0 / (CHECK_SAMPLES - 1)
    )
    extra = _extra_points(breakpoints, jumps, not dense)
    pos = np.minimum(np.maximum(np.searchsorted(tau, extra), 1), len(tau) - 1) if len(tau) > 1 else np.zeros(len(extra), int)
    near = np.minimum(np.abs(extra - tau[pos - 1 if len(tau) > 1 else 0]), np.abs(extra - tau[pos]))
    grid = np.concatenate([tau, extra[near > 1e-9]])
    return grid, np.argsort(grid, kind="stable")


#: central-difference step in τ for d/dτ of the torques (truncation ~1e-10 relative, round-off ~1e-10)
DTAU = 1e-5


#: relative tolerance of the RMS integrals (on each of ∫A_m², ∫G_m² and, for ∫A_m·G_m, their geometric mean)
RMS_RTOL = 1e-8
#: the RMS integration starts from spans no wider than this in τ (the adaptive rule refines from there)
RMS_START_WIDTH = 1.0 / 4.0
#: a span narrower than this in τ is accepted as it is (a singular integrand cannot stall the integration)
RMS_MIN_WIDTH = 1e-7
#: the most integrand evaluations one RMS integral makes: a smooth move needs far fewer (plans on the shipped profiles,
#: every method, default and optimal laws: 105–630; check of plan's files: up to ~4,000, 15 per span of up to 256
#: spans); an integrand that never settles (round-off of a file's absurd values, a torque that is noise) would
#: otherwise bisect for ``max_rounds`` rounds, doubling its spans every round (minutes, gigabytes). Past the budget
#: the last estimate of the unfinished spans is taken, as after ``max_rounds``.
RMS_MAX_NODES = 20_000

# Gauss–Kronrod 7/15 nodes on [-1, 1] (QUADPACK qk15): the Kronrod weights of all 15 nodes, the Gauss weights
# of the 7 that are the Gauss–Legendre nodes (every other one)
_XK = np.array([0.991455371120812639206854697526329, 0.949107912342758524526189684047851,
                0.864864423359769072789712788640926, 0.741531185599394439863864773280788,
                0.586087235467691130294144845693013, 0.405845151377397166906606412076961,
                0.207784955007898467600689403773245, 0.0])
_WK = np.array([0.022935322010529224963732008058970, 0.063092092629978553290700663189204,
                0.104790010322250183839876322541518, 0.140653259715525918745189590510238,
                0.169004726639267902826583426598550, 0.190350578064785409913256402421014,
                0.204432940075298892414161999234649, 0.209482141084727828012999174891714])
_WG = np.array([0.129484966168869693270611432679082, 0.279705391489276667901467771423780,
                0.381830050505118944950369775488975, 0.417959183673469387755102040816327])
GK_NODES = np.concatenate([-_XK[:-1], _XK[::-1]])  # 15 nodes, ascending
GK_WEIGHTS = np.concatenate([_WK[:-1], _WK[::-1]])
GK_GAUSS = np.zeros(15)
GK_GAUSS[1::2] = np.concatenate([_WG[:-1], _WG[::-1]])  # the Gauss nodes are the odd-indexed ones


def rms_edges(breakpoints: np.ndarray, jumps: np.ndarray) -> np.ndarray:
    """Start partition of [0, 1] for the RMS integrals: the jumps, the breakpoints (up to 256 spans: a path
    through every sample of a file is smooth across them) and spans no wider than ``RMS_START_WIDTH``."""
    b = np.asarray(breakpoints, float)
    b = b[(b > 0.0) & (b < 1.0)]
    if b.size > 255:
        b = b[:0]
    e = np.unique(np.concatenate([[0.0, 1.0], b, jumps]))
    out = []
    for lo, hi in zip(e[:-1], e[1:]):
        k = max(1, int(np.ceil((hi - lo) / RMS_START_WIDTH - 1e-9)))
        out.append(np.linspace(lo, hi, k + 1)[:-1])
    return np.concatenate(out + [[1.0]])


def adaptive_gk15(integrand, edges: np.ndarray, n: int, rtol: float = RMS_RTOL,
                  min_width: float = RMS_MIN_WIDTH, max_rounds: int = 40, first: np.ndarray | None = None,
                  max_nodes: int = RMS_MAX_NODES) -> np.ndarray:
    """∫ over [edges[0], edges[-1]] of ``integrand`` (τ (M,) → (M, 3n): the columns [f², f·g, g²] of n
    joints), vectorised adaptive Gauss–Kronrod 7/15: every round evaluates the nodes of all unfinished
    spans in one call; a span is accepted when |K15 − G7| of every column is within its share (∝ width) of
    ``rtol`` times that column's scale (∫f², ∫g², and √(∫f²·∫g²) for ∫f·g, plus 1e-13 of the largest),
    otherwise bisected. (scipy's quad_vec does the same adaptively but evaluates one point per call, ~100×
    slower on the robot models; the tests check this against it.) ``first``: the integrand at the first
    round's nodes ((len(edges) − 1)·15, 3n), when already known. ``max_nodes``: the evaluation budget
    (``RMS_MAX_NODES``); a round that would exceed it is not made, the last estimate is taken. The batch of one
    of :func:`gk15_many`."""
    a = np.asarray(edges[:-1], float)
    b = np.asarray(edges[1:], float)
    return gk15_many(lambda x, owner: (integrand(x), None), a, b, np.zeros(len(a), np.intp), 1, n,
                     first, rtol, min_width, max_rounds, float(edges[-1] - edges[0]), max_nodes)[0]


def _sums(values: np.ndarray, owner: np.ndarray, P: int) -> np.ndarray:
    """Per integral, the sum of its rows of ``values`` (``owner`` non-decreasing) as ``values[rows].sum(axis=0)``
    adds them (one after the other; ``np.add.reduceat`` adds in another order); 0 for an integral without rows."""
    count = np.bincount(owner, minlength=P)
    at = np.arange(len(owner)) - np.concatenate([[0], np.cumsum(count)])[owner]
    padded = np.zeros((P, int(count.max()) if len(owner) else 0, values.shape[1]))
    padded[owner, at] = values
    return padded.sum(axis=1)


def gk15_many(evaluate, a: np.ndarray, b: np.ndarray, owner: np.ndarray, P: int, n: int,
              first: np.ndarray | None = None, rtol: float = RMS_RTOL, min_width: float = RMS_MIN_WIDTH,
              max_rounds: int = 40, length: float = 1.0, max_nodes: int | None = None) -> np.ndarray:
    """:func:`adaptive_gk15` of P integrals at once (P (3n,) results, one after the other in ``owner``): the spans
    [a, b] of integral ``owner`` (non-decreasing), ``length`` the width of each integral's interval;
    ``evaluate(x, owner)`` → (the integrand at the nodes x of the spans of ``owner`` (S·15, 3n), which integrals
    could be evaluated: (P,) bool, or None for all); ``first``: the integrand at the first round's nodes. Each
    integral's spans are bisected, accepted and summed as :func:`adaptive_gk15` does them for that integral alone
    (its unfinished spans' left halves in order, then their right halves); NaN for an integral that could not be
    evaluated. ``max_nodes``: the evaluation budget (None: ``RMS_MAX_NODES`` per integral); a round that would
    exceed it is not made, the unfinished spans' last estimate is taken. → (P, 3n)."""
    G = len(GK_NODES)
    done = np.zeros((P, 3 * n))
    f = first
    budget = RMS_MAX_NODES * P if max_nodes is None else max_nodes
    used = 0
    for _ in range(max_rounds):
        if f is None and used and used + G * len(a) > budget:
            break  # the budget: the unfinished spans' last estimate (k of the halves' parent)
        used += G * len(a)
        c, h = 0.5 * (a + b), 0.5 * (b - a)
        if f is None:
            f, keep = evaluate((c[:, None] + h[:, None] * GK_NODES).ravel(), owner)
            if keep is not None:
                done[~keep] = np.nan
        f = f.reshape(len(a), G, 3 * n)
        k = h[:, None] * np.einsum("j,mjc->mc", GK_WEIGHTS, f)
        g = h[:, None] * np.einsum("j,mjc->mc", GK_GAUSS, f)
        f = None
        est = done + _sums(k, owner, P)
        aa, gg = np.abs(est[:, :n]), np.abs(est[:, 2 * n :])
        scale = np.concatenate([aa, np.sqrt(aa * gg), gg], axis=1)
        tol = rtol * (scale + 1e-13 * scale.max(axis=1, keepdims=True)) + 1e-300
        width = (b - a) / length
        ok = np.all(np.abs(k - g) <= tol[owner] * width[:, None], axis=1) | (b - a < min_width)
        ok |= np.isnan(done[owner, 0])  # (an integral that could not be evaluated: no further rounds)
        done = done + _sums(k[ok], owner[ok], P)
        if ok.all():
            return done
        rest, rest_owner = k[~ok], owner[~ok]
        # every integral's unfinished spans bisected: their left halves in order, then their right halves
        a, b, owner = a[~ok], b[~ok], rest_owner
        m = 0.5 * (a + b)
        o = np.argsort(np.concatenate([owner, owner]), kind="stable")
        a, b, owner = np.concatenate([a, m])[o], np.concatenate([m, b])[o], np.concatenate([owner, owner])[o]
    return done + _sums(rest, rest_owner, P)  # not converged in max_rounds or the budget: the last estimate
