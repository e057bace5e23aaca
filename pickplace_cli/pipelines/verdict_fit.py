"""The verdict engine's rows of the default duration rule (``time = limits``): plan()'s own numbers for many moves.

For a B-spline move under ``--time limits``, :func:`~pickplace_cli.planner.plan` takes the auto duration T_auto
[Li2018, Eq. (26)], evaluates the model once on the check grid of its output samples at T_auto (its "first
samples"), and screens the closed-form fit on that grid (:func:`~pickplace_cli.timing.fit_screen`). When the screened
fit t lies clearly below T_auto (t·(1 + 1e-5) < T_auto) the capacity binds: the duration is T_auto, ``fit_s`` is
t·(1 + 1e-7), and the limit check runs on the very same samples. This module gives those numbers for a block of
moves at once, bitwise:

1. every move's check grid exactly as plan() builds it (:func:`~pickplace_cli.limits.grid.check_grid_order` of
   its output samples at T_auto), sorted, for all moves at once (:class:`FirstSamples`);
2. the Cartesian motion on all grids by :class:`Pieces`, the path evaluator of
   :func:`~pickplace_cli.paths.bspline.plan_bspline` replayed on stacked samples (the same Horner steps on the
   same numbers, sample by sample), and ONE model evaluation ``model.parts(τ, motion=…)`` for the block: the robot
   models work sample by sample, so every number is the one plan() computes (tested bitwise);
3. the verdict: every limit's parabolic estimate on that grid at T_auto (plan()'s check sees the same samples)
   and the RMS motor torque within ``margin`` of its limit (see :mod:`~pickplace_cli.pipelines.verdicts`);
4. the RMS integrals by the model's own adaptive quadrature, for all moves at once (:func:`rms_integrals`: its
   first round read off the grid, as plan() reads it, every further round one model call), and the fit by
   :func:`~pickplace_cli.timing.fit.batch_fit_screen`, the vectorised form of fit_screen (bitwise, tested): every
   quantity's per-sample thresholds refined at the parabola vertex of its largest sample.

Bitwise means the same operations on the same numbers in the same order, and where numpy's order follows the
memory layout (the Gauss–Kronrod sums of ``numpy.einsum``) the same layout: the tests compare every number with
the functions replayed. A move whose screened fit is not clearly below T_auto (the joints or motors bind: plan()
then confirms the fit by the exact check), or whose numbers are not all finite, is not decided here.
"""

from __future__ import annotations

import numpy as np

from ..curves.bspline import DEGREE
from ..model.errors import UnreachableError

#: the factor a power picks up from k derivatives, powers 5 … k highest first (exact small integers, the table
#: of plan_bspline)
_FALLING = [np.array([float(np.prod([n - r for r in range(k)])) for n in range(DEGREE, k - 1, -1)]) for k in range(4)]
#: the fields of a Parts that are arrays over the samples
_FIELDS = ("tau", "p", "v1", "a1", "j1", "q", "qd1", "qdd1", "qddd1", "A", "G", "Am", "Gm", "dAm", "dGm", "singularity")


class Pieces:
    """The piece polynomials of P B-spline moves (``breaks`` (P, 7), ``coef`` (P, 6, 3, 6) [displacement, m],
    ``via`` (P, 5, 3) the via points minus ``origin`` (P, 3) [m]), evaluated exactly as each move's planned path
    evaluates itself (:func:`~pickplace_cli.paths.bspline.plan_bspline`)."""

    def __init__(self, breaks: np.ndarray, coef: np.ndarray, via: np.ndarray, origin: np.ndarray) -> None:
        P, m = coef.shape[:2]
        stacked = np.zeros((P, m, DEGREE + 1, 4, 3))  # [move, piece, power, order, axis], derivatives padded
        stacked[:, :, :, 0] = coef.transpose(0, 1, 3, 2)
        for k in range(1, 4):
            stacked[:, :, k:, k] = (coef[..., : DEGREE + 1 - k] * _FALLING[k]).transpose(0, 1, 3, 2)
        self.by_piece = stacked.reshape(P, m, DEGREE + 1, 12)
        self.breaks = breaks
        ends = np.zeros((P, 2, 4, 3))  # the end states exactly: at rest at the first and last via point
        ends[:, 0, 0], ends[:, 1, 0] = via[:, 0], via[:, -1]
        self.ends = ends.reshape(P, 2, 12)
        self.origin = origin

    def all_orders(self, tau: np.ndarray, move: np.ndarray) -> list[np.ndarray]:
        """[p, p′, p″, p‴] (each (M, 3), m/1^k) of the moves ``move`` (M,) at their τ (M,)."""
        P, m = self.by_piece.shape[:2]
        b = self.breaks[move]
        i = np.minimum(np.maximum((b <= tau[:, None]).sum(axis=1) - 1, 0), m - 1)  # searchsorted(right) − 1
        dx = (tau - self.breaks.ravel()[move * (m + 1) + i])[:, None]  # (the same products as the (M, 12) copies)
        c = self.by_piece.reshape(P * m, DEGREE + 1, 12)
        piece = move * m + i
        acc = c[piece, 0] * dx
        acc += c[piece, 1]
        for col in range(2, DEGREE + 1):
            acc *= dx
            acc += c[piece, col]
        lo, hi = tau <= 0.0, tau >= 1.0
        acc[lo] = self.ends[move[lo], 0]
        acc[hi] = self.ends[move[hi], 1]
        acc = acc.reshape(-1, 4, 3)
        return [acc[:, 0] + self.origin[move], acc[:, 1], acc[:, 2], acc[:, 3]]

    def evaluator(self, k: int):
        """``evaluate_all`` of move k's path (τ → [p, p′, p″, p‴])."""
        return lambda tau: self.all_orders(tau, np.full(len(tau), k))


def model_at(model, pieces: Pieces, tau: np.ndarray, move: np.ndarray, lengths: np.ndarray, **options):
    """The model at the points ``tau`` of the moves ``move`` (``lengths`` points each, one move after the other):
    (Parts of the moves that are reachable at every point, or None; keep (len(lengths),) bool). ``options`` go to
    :meth:`~pickplace_cli.limits.motion.MotionModel.parts`."""
    owner = np.repeat(np.arange(len(lengths)), lengths)
    motion = pieces.all_orders(tau, move)
    keep = np.ones(len(lengths), bool)
    keep[owner[~model.robot.reachable(motion[0])]] = False
    while keep.any():
        rows = keep[owner]
        if not rows.all():  # the motion of the rest, laid out as for all (views of one array)
            motion = pieces.all_orders(tau[rows], move[rows])
        try:
            return model.parts(tau[rows], motion=tuple(motion), **options), keep
        except UnreachableError as exc:  # not caught by the reach mask
            if exc.index is None:
                break
            keep[owner[np.flatnonzero(rows)[exc.index]]] = False
    return None, np.zeros(len(lengths), bool)


def take_moves(parts, starts: np.ndarray, which: np.ndarray):
    """(the Parts of the moves ``which`` (indices, increasing) of stacked ``parts``, their starts)."""
    from ..limits.motion import Parts

    lengths = np.diff(starts)[which]
    rows = np.concatenate([np.arange(starts[k], starts[k + 1]) for k in which]) if len(which) else np.zeros(0, int)
    fields = {f: (None if getattr(parts, f) is None else getattr(parts, f)[rows]) for f in _FIELDS}
    return Parts(**fields), np.concatenate([[0], np.cumsum(lengths)])


def rms_integrals(first: "FirstSamples", moves: np.ndarray, parts, starts: np.ndarray, model, pieces: Pieces,
                  piece_of: np.ndarray, model_of) -> tuple[np.ndarray, np.ndarray]:
    """Every move's :meth:`~pickplace_cli.limits.motion.MotionModel.rms_integrals` (I (P, 3, n), G_end (P, 2, n)),
    bitwise: ``parts`` holds the moves ``moves`` (indices in ``first``; ``piece_of``: in ``pieces``) on their first
    samples, one after the other from ``starts``. The adaptive Gauss–Kronrod quadrature
    (:func:`~pickplace_cli.limits.grid.adaptive_gk15`) for all moves at once, round by round: the first read off
    the samples as plan() reads it, every further one evaluating the bisected spans' nodes of all moves in one model
    call (``model``, the motion by ``pieces``); the same sums in the same order, span by span. A move whose nodes
    are not on its grid is integrated by its own model (``model_of(j)``: the j-th of ``moves``); NaN for a move
    with an unreachable node (plan() raises there)."""
    from ..limits.grid import GK_NODES, gk15_many
    from ..limits.motion import Parts

    n, P, G = parts.Am.shape[1], len(moves), len(GK_NODES)
    pos = np.full(len(first.lengths), -1)
    pos[moves] = np.arange(P)
    sel = pos[first.span_owner] >= 0
    a, b, so = first.a[sel], first.b[sel], pos[first.span_owner[sel]]
    rows = (first.node_at.reshape(-1, G)[sel] + starts[so][:, None]).ravel()
    Am, Gm = parts.Am[rows], parts.Gm[rows]  # (gathered, as _first_round gathers them)

    def evaluate(x: np.ndarray, owner: np.ndarray):  # every move's nodes in one model call
        lengths = np.bincount(owner, minlength=P) * G
        got, keep = model_at(model, pieces, x, np.repeat(piece_of[owner], G), lengths, derivatives=False,
                             singularity=False)
        if got is None:
            return np.full((len(x), 3 * n), np.nan), keep
        # the model's arrays as they come: their memory order is the order of the Gauss–Kronrod sums (einsum's)
        f = np.concatenate([got.Am * got.Am, got.Am * got.Gm, got.Gm * got.Gm], axis=1)
        if keep.all():
            return f, keep
        out = np.full((len(x), 3 * n), np.nan, order="F" if f.flags.f_contiguous else "C")
        out[np.repeat(keep, lengths)] = f
        return out, keep

    done = gk15_many(evaluate, a, b, so, P, n, np.concatenate([Am * Am, Am * Gm, Gm * Gm], axis=1))
    integrals = done.reshape(P, 3, n)
    ends = np.stack([parts.Gm[starts[:-1]], parts.Gm[starts[1:] - 1]], axis=1)
    for j in np.flatnonzero(~first.nodes_ok[moves]):  # (never seen: the grids hold the nodes)
        one = Parts(**{name: (None if getattr(parts, name) is None else getattr(parts, name)[starts[j] : starts[j + 1]])
                       for name in _FIELDS})
        integrals[j], ends[j] = model_of(int(j)).rms_integrals(one)
    return integrals, ends


def limits_fit(model, parts, starts: np.ndarray, T: np.ndarray, rms: tuple, dwell: float) -> list[float | None]:
    """The ``fit_s`` of plan()'s ``time = limits`` for P moves whose capacity binds (``parts``: their model on their
    first samples, stacked and sorted; ``T`` (P,) their auto durations
    [s]; ``rms`` their RMS integrals): per move the float plan() writes (None where no limit depends on the
    duration), or NaN where the move is not decided here (its fit is not clearly below T, or not a number)."""
    from ..timing.fit import batch_fit_screen, capacity_fit_s

    t = batch_fit_screen(model, parts, starts, rms, dwell)
    if t is None:
        return [None] * len(T)
    return capacity_fit_s(t, T).tolist()


# ------------------------------------------------------- plan()'s first samples and RMS start, for many moves


def _rows(values: np.ndarray, owner: np.ndarray, P: int) -> tuple[np.ndarray, np.ndarray]:
    """Ragged ``values`` grouped by ``owner`` (non-decreasing) as rows (P, longest) padded with +inf, and each
    value's column."""
    count = np.bincount(owner, minlength=P)
    col = np.arange(len(values)) - np.concatenate([[0], np.cumsum(count)])[owner]
    out = np.full((P, int(count.max()) if len(values) else 0), np.inf)
    out[owner, col] = values
    return out, col


def _merge(first: np.ndarray, second: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Every row of ``first`` (P, a) and ``second`` (P, b) merged in order: (the merged values (P, a + b),
    from_second (P, a + b) bool, seen (P, a + b): how many of ``first`` come at or before each place, the
    permutation (P, a + b)). An element of ``first`` comes before an equal one of ``second`` (a stable sort: two
    sorted runs, which it merges in linear time)."""
    both = np.concatenate([first, second], axis=1)
    o = np.argsort(both, axis=1, kind="stable")
    from_second = o >= first.shape[1]
    return np.take_along_axis(both, o, axis=1), from_second, np.cumsum(~from_second, axis=1), o


class FirstSamples:
    """plan()'s check grid at the auto duration (:func:`~pickplace_cli.limits.grid.check_grid_order` of the output
    samples ``taus`` (P lists of τ) on paths with breakpoints ``breaks`` (P, m + 1), 0 < … < 1, and no jumps), sorted,
    for P moves at once (the same values: the same arithmetic, every set operation on exact values), and the start
    of each move's RMS quadrature (:func:`~pickplace_cli.limits.grid.span_nodes`): the spans and, for every
    Gauss–Kronrod node, its nearest grid point as the model's first round takes it
    (:meth:`~pickplace_cli.limits.motion.MotionModel._first_round`).

    ``grid`` (M,), ``lengths`` (P,); ``a``, ``b`` (S,) the spans, ``span_owner`` (S,); ``node_at`` (S·15,) the
    index of each node's grid point within its move's grid; ``nodes_ok`` (P,): every node within 1e-9 of it."""

    def __init__(self, taus: list[np.ndarray], breaks: np.ndarray) -> None:
        with np.errstate(invalid="ignore"):  # (inf − inf in the padding)
            self._build(taus, breaks)

    def _build(self, taus: list[np.ndarray], breaks: np.ndarray) -> None:
        from ..limits.grid import CHECK_SAMPLES, GK_NODES, RMS_START_WIDTH

        P = breaks.shape[0]
        # rms_edges: every span between breakpoints cut into k equal parts (np.linspace's arithmetic), then 1
        lo, hi = breaks[:, :-1], breaks[:, 1:]
        k = np.maximum(1, np.ceil((hi - lo) / RMS_START_WIDTH - 1e-9)).astype(np.intp)
        j = np.arange(k.max(), dtype=float)
        pts = j * ((hi - lo) / k)[..., None] + lo[..., None]
        inside = j < k[..., None]
        counts = inside.sum(axis=(1, 2))
        edges = np.insert(pts[inside], np.cumsum(counts), 1.0)
        edge_owner = np.repeat(np.arange(P), counts + 1)
        same = edge_owner[1:] == edge_owner[:-1]
        self.a, self.b = edges[:-1][same], edges[1:][same]
        self.span_owner = edge_owner[:-1][same]
        nodes = (0.5 * (self.b + self.a))[:, None] + (0.5 * (self.b - self.a))[:, None] * GK_NODES  # span_nodes
        node_rows, node_col = _rows(nodes.ravel(), np.repeat(self.span_owner, len(GK_NODES)), P)
        # the output samples; dense when they cover [0, 1] as densely as the check's uniform grid
        n_tau = np.array([len(t) for t in taus])
        tau = np.full((P, int(n_tau.max())), np.inf)
        for r, t in enumerate(taus):
            tau[r, : len(t)] = t
        gaps = np.where(np.isfinite(tau[:, 1:]), np.diff(tau, axis=1), -np.inf)
        dense = (n_tau >= CHECK_SAMPLES) & (tau[:, 0] <= 0.0) & (np.take_along_axis(tau, n_tau[:, None] - 1, 1)[:, 0]
                                                                 >= 1.0) & (gaps.max(axis=1) <= 1.0 / (CHECK_SAMPLES - 1))
        # _extra_points: breakpoints ∪ nodes (∪ the uniform grid), sorted; duplicates and round-off twins (within
        # 1e-9 of the value before) dropped
        uniform = np.where(dense[:, None], np.inf, np.linspace(0.0, 1.0, CHECK_SAMPLES))
        cand = np.sort(np.concatenate([breaks, node_rows, uniform], axis=1), axis=1)
        keep = np.isfinite(cand) & np.c_[np.ones(P, bool), cand[:, 1:] - cand[:, :-1] > 1e-9]
        extra = np.where(keep, cand, np.inf)
        # check_grid_order: the extra points farther than 1e-9 from the nearest output samples (below, above)
        merged, is_extra, seen, _ = _merge(tau, extra)
        below = np.maximum(seen - 1, 0)
        above = np.minimum(seen, n_tau[:, None] - 1)
        near = np.minimum(np.abs(merged - np.take_along_axis(tau, below, 1)),
                          np.abs(merged - np.take_along_axis(tau, above, 1)))
        in_grid = np.isfinite(merged) & (~is_extra | (near > 1e-9))
        self.grid = merged[in_grid]
        self.lengths = in_grid.sum(axis=1)
        # each node's nearest grid point, as _first_round takes it (searchsorted, then the nearer neighbour)
        grid_rows = np.sort(np.where(in_grid, merged, np.inf), axis=1, kind="stable")  # the grid in order, then inf
        merged, is_node, seen, o = _merge(grid_rows, node_rows)
        lo_i = np.maximum(seen - 1, 0)
        hi_i = np.minimum(seen, self.lengths[:, None] - 1)
        g_lo, g_hi = np.take_along_axis(grid_rows, lo_i, 1), np.take_along_axis(grid_rows, hi_i, 1)
        pick = np.where(np.abs(g_lo - merged) < np.abs(g_hi - merged), lo_i, hi_i)
        far = np.abs(np.take_along_axis(grid_rows, pick, 1) - merged) > 1e-9
        at = np.zeros(node_rows.shape, np.intp)
        rows = np.nonzero(is_node)
        at[rows[0], o[is_node] - grid_rows.shape[1]] = pick[is_node]
        self.node_at = at[np.repeat(self.span_owner, len(GK_NODES)), node_col]
        self.nodes_ok = ~np.any(far & is_node & np.isfinite(merged), axis=1)
