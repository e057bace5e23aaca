"""The verdict engine's rows of the default duration rule (``time = limits``): plan()'s own numbers for many moves.

For a B-spline move under ``--time limits``, :func:`~pickplace_cli.planner.plan` takes the auto duration T_auto
[Li2018, Eq. (26)], evaluates the model once on the check grid of its output samples at T_auto (its "first
samples"), and screens the closed-form fit on that grid (:func:`~pickplace_cli.timing.fit_screen`). When the screened
fit t lies clearly below T_auto (t·(1 + 1e-6) < T_auto) the capacity binds: the duration is T_auto, ``fit_s`` is
t·(1 + 1e-7), and the limit check runs on the very same samples. This module gives those numbers for a block of
moves at once, bitwise:

1. every move's check grid exactly as plan() builds it (:func:`~pickplace_cli.limits.grid.check_grid_order` of
   its output samples at T_auto), sorted;
2. the Cartesian motion on all grids by :class:`Pieces`, the path evaluator of
   :func:`~pickplace_cli.paths.bspline.plan_bspline` replayed on stacked samples (the same Horner steps on the
   same numbers, sample by sample), and ONE model evaluation ``model.parts(τ, motion=…)`` for the block: the robot
   models work sample by sample, so every number is the one plan() computes (tested bitwise);
3. the verdict: every limit's parabolic estimate on that grid at T_auto (plan()'s check sees the same samples)
   and the RMS motor torque within ``margin`` of its limit (see :mod:`~pickplace_cli.pipelines.verdicts`);
4. the RMS integrals per move by the model's own adaptive quadrature (its first round read off the grid, as
   plan() reads it), and the fit by :func:`~pickplace_cli.timing.fit.batch_fit_screen`, the vectorised form of
   fit_screen (bitwise, tested), its vertex points evaluated by the same stacked model.

A move whose screened fit is not clearly below T_auto (the joints or motors bind: plan() then confirms the fit by
the exact check), or whose numbers are not all finite, is not decided here.
"""

from __future__ import annotations

import numpy as np

from ..curves.bspline import DEGREE
from ..model.errors import UnreachableError

#: the factor a power picks up from k derivatives, powers 5 … k highest first (exact small integers, the table
#: of plan_bspline)
_FALLING = [np.array([float(np.prod([n - r for r in range(k)])) for n in range(DEGREE, k - 1, -1)]) for k in range(4)]
#: the capacity binds when the screened fit is below T_auto by more than this (relative; plan()'s own test)
CAPACITY_GAP = 1e-6
#: fit_s is the screened fit raised by this (relative; plan()'s own margin)
FIT_MARGIN = 1e-7
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
        b = self.breaks[move]
        m = self.by_piece.shape[1]
        i = np.minimum(np.maximum(np.sum(b <= tau[:, None], axis=1) - 1, 0), m - 1)  # searchsorted(right) − 1
        dx = np.repeat((tau - np.take_along_axis(b, i[:, None], axis=1)[:, 0])[:, None], 12, axis=1)
        c = self.by_piece[move, i]  # (M, 6, 12)
        acc = c[:, 0] * dx
        acc += c[:, 1]
        for col in range(2, DEGREE + 1):
            acc *= dx
            acc += c[:, col]
        lo, hi = tau <= 0.0, tau >= 1.0
        acc[lo] = self.ends[move[lo], 0]
        acc[hi] = self.ends[move[hi], 1]
        acc = acc.reshape(-1, 4, 3)
        return [acc[:, 0] + self.origin[move], acc[:, 1], acc[:, 2], acc[:, 3]]

    def evaluator(self, k: int):
        """``evaluate_all`` of move k's path (τ → [p, p′, p″, p‴])."""
        return lambda tau: self.all_orders(tau, np.full(len(tau), k))


def model_at(model, pieces: Pieces, tau: np.ndarray, move: np.ndarray, lengths: np.ndarray):
    """The model at the points ``tau`` of the moves ``move`` (``lengths`` points each, one move after the other):
    (Parts of the moves that are reachable at every point, or None; keep (len(lengths),) bool)."""
    owner = np.repeat(np.arange(len(lengths)), lengths)
    motion = pieces.all_orders(tau, move)
    keep = np.ones(len(lengths), bool)
    keep[owner[~model.robot.reachable(motion[0])]] = False
    while keep.any():
        rows = keep[owner]
        if not rows.all():  # the motion of the rest, laid out as for all (views of one array)
            motion = pieces.all_orders(tau[rows], move[rows])
        try:
            return model.parts(tau[rows], motion=tuple(motion)), keep
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


def _padded(parts, keep: np.ndarray, lengths: np.ndarray):
    """``parts`` of the kept moves as Parts of all moves, NaN at the rows of the others."""
    from ..limits.motion import Parts

    rows = np.repeat(keep, lengths)
    fields = {}
    for f in _FIELDS:
        x = getattr(parts, f)
        if x is None:
            fields[f] = None
            continue
        full = np.full((len(rows), *x.shape[1:]), np.nan)
        full[rows] = x
        fields[f] = full
    return Parts(**fields)


def rms_integrals(model_of, parts, starts: np.ndarray, moves: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every move's :meth:`~pickplace_cli.limits.motion.MotionModel.rms_integrals` on its rows of ``parts`` (its
    first round read off them, as plan() reads it off its first samples): (I (P, 3, n), G_end (P, 2, n)).
    ``model_of(k)`` → move ``moves[k]``'s MotionModel."""
    from ..limits.motion import Parts

    out_i, out_g = [], []
    for k in range(len(starts) - 1):
        s, e = starts[k], starts[k + 1]
        one = Parts(**{f: (None if getattr(parts, f) is None else getattr(parts, f)[s:e]) for f in _FIELDS})
        i, g = model_of(int(moves[k])).rms_integrals(one)
        out_i.append(i)
        out_g.append(g)
    return np.array(out_i), np.array(out_g)


def limits_fit(model, pieces: Pieces, parts, starts: np.ndarray, moves: np.ndarray, T: np.ndarray,
               rms: tuple, dwell: float) -> list[float | None] | None:
    """The ``fit_s`` of plan()'s ``time = limits`` for P moves whose capacity binds (``parts``: their model on their
    first samples, stacked and sorted; ``moves``: their indices in ``pieces``; ``T`` (P,) their auto durations
    [s]; ``rms`` their RMS integrals): per move the float plan() writes (None where no limit depends on the
    duration), or NaN where the move is not decided here (its fit is not clearly below T, or not a number)."""
    from ..timing.fit import batch_fit_screen

    def evaluate(tau: np.ndarray, which: np.ndarray):
        n = np.bincount(which, minlength=len(moves))
        got, keep = model_at(model, pieces, tau, moves[which], n)
        if got is None:
            return _nan_parts(parts, len(tau))
        return _padded(got, keep, n)

    t = batch_fit_screen(model, parts, starts, rms, dwell, evaluate)
    if t is None:
        return [None] * len(T)
    out: list[float | None] = []
    for t_screen, t_auto in zip(t.tolist(), T.tolist()):
        ok = t_screen == t_screen and t_screen * (1.0 + CAPACITY_GAP) < t_auto
        out.append(t_screen * (1.0 + FIT_MARGIN) if ok else float("nan"))
    return out


def _nan_parts(parts, n: int):
    """Parts of ``n`` rows, NaN everywhere (the fields ``parts`` has)."""
    from ..limits.motion import Parts

    return Parts(**{f: (None if getattr(parts, f) is None else np.full((n, *getattr(parts, f).shape[1:]), np.nan))
                    for f in _FIELDS})
