"""Batch verdicts for many B-spline moves at once (``pickplace plan --batch FILE --json``, no ``-o``).

When a batch only asks for durations and verdicts, planning every row with :func:`~pickplace_cli.planner.plan`
spends most of its 3–5 ms in per-call numpy overhead on ~1,200 points [issue 7]. This engine stacks the rows:

1. k1, k2 of every move from the λ table in one :func:`numpy.interp` (the same interpolation as
   :meth:`~pickplace_cli.lookup.bspline_table.Table.lookup`, which calls it once per move);
2. the control points of every move in one batched solve, the piece polynomials of every move from the
   batched Cox–de Boor recursion (:func:`~pickplace_cli.curves.bspline.batch_basis` on P knot vectors), the exact
   path peaks ‖p′‖, ‖p″‖, ‖p‴‖ per move (:func:`batch_norm_peaks`, a batched
   :func:`~pickplace_cli.curves.peaks.ppoly_norm_peak`) [Li2018, Eq. (3), (8)–(16)], and the duration per move by
   :func:`~pickplace_cli.timing.choose_duration` itself (auto: [Li2018, Eq. (26)]; or the row's seconds);
3. a *screening* grid per move (``SCREEN_SAMPLES`` uniform τ ∪ its knots ∪ ``PIECE_SAMPLES`` points inside
   every piece), the Cartesian motion of a block of moves stacked into one (B·G, 3) array per order, ONE
   call ``model.parts(tau, motion=…)`` per block, the limit columns with each move's own duration, the
   parabolic-vertex estimate of every peak and the RMS motor torque per move.

**Contract: a limit check never lies.** A move is decided here only when every screened quantity is clearly
inside its limit: estimated utilisation ≤ ``SCREEN_MARGIN`` (0.9) for every column and the RMS torque, the
singularity measure ≥ max(margin, ``REACH_GUARD``)/0.9 (the measure vanishes on the boundary of the
reachable set of the Delta — D = d·E′ = −½ ∂f/∂q is zero where the loop-closure root is double — and of
the SCARA, |sin q2| = 0 at full stretch, so no unreachable point hides between screening samples), and
every value finite. That is stricter than plan()'s own 5 % exact-refinement band (``limits.EXACT_BAND``):
at ≤ 0.9 plan() never refines and never finds a violation (the screening estimate is within ~0.3 % of
plan()'s peaks; tests/unit/test_verdicts.py measures it). Every other row (near or over a limit,
unreachable, a parse/task/table error, ``time = fit``, moving ends, the motors binding the default rule's duration,
anything unusual) is planned by
:func:`~pickplace_cli.pipelines.batch.plan_rows`, i.e. by ``plan()`` itself, so its verdict, violation rows and
messages are exactly the existing ones. A decided row's summary is built by ``Plan.summary`` from the same
numbers ``plan()`` computes (the same arithmetic on stacked arrays: bitwise equal, tested).

**The default rule** (``time = limits``: the longer of the capacity's duration and the joints' and motors' fit).
For these rows plan() evaluates the model on its first samples (the check grid of the output samples at the auto
duration) and screens the closed-form fit there; when the capacity binds (the fit is clearly shorter) the duration
is the auto one and ``fit_s`` that screened fit. The engine replays exactly that (:mod:`.verdict_fit`): the same
grid, the same model numbers (the path's own evaluator replayed on stacked samples), the vectorised closed-form
fit (:func:`~pickplace_cli.timing.fit.batch_fit_screen`, bitwise the scalar one), and decides a row when the
screening above holds on those samples and the capacity binds. A row whose joints or motors set the duration
(plan() confirms that fit by its exact check, refining peaks at their limits) is left to plan().

Scope: method ``bspline`` only, rest-to-rest, ``time`` limits, auto or seconds, no ``--show-fit``
(``options.fit``), robots with an analytic ``torque_rate``, a ``reachable`` mask and a ``singularity_measure``
(Delta, SCARA; the gantry goes through ``plan()``). A row's ``limit_use`` plans it on the profile at that use, as
plan() does (the rows are grouped by profile). ``PICKPLACE_NO_VERDICT_ENGINE=1`` switches the engine off
(debugging aid: the output must not change).
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from .batch import ANGLES, BELT, BatchRow, RowResult, plan_rows, row_task, run_chunks_in_order
from ..curves.bspline import DEGREE
from ..curves.peaks import parabolic_peak
from ..paths.bspline import batch_paths
from ..model.errors import PickplaceError, UnreachableError
from ..limits.check import capacity_rows
from ..limits.report import LimitReport

#: uniform τ samples of the screening grid per move (plus its interior knots and PIECE_SAMPLES points inside
#: every piece: 144 in all); the parabolic-vertex estimate is within 0.3 % of plan()'s peaks (tests)
SCREEN_SAMPLES = 97
#: extra screening samples inside every piece of the spline (evenly spaced)
PIECE_SAMPLES = 7
#: a move is decided by the engine only when every estimated utilisation is at most this
SCREEN_MARGIN = 0.9
#: singularity-measure floor of the screening even when the profile's margin is lower (reach guard)
REACH_GUARD = 0.05
#: moves per model call (B·G samples ≈ 8–9k keep the model's arrays in cache: ~1 µs per sample, ×4 beyond)
BLOCK_MOVES = 64
#: samples per model call for the rows of ``time = limits`` (their check grids: ~300–450 samples a move)
BLOCK_SAMPLES = 8192
#: env var that switches the engine off (debugging aid; the output must not change)
OFF_SWITCH = "PICKPLACE_NO_VERDICT_ENGINE"

_PARAMS = {"k1", "k2", "table"}


@dataclass(frozen=True)
class Verdict:
    """A row decided by the engine: its summary (``Plan.summary()`` of that row) and an empty-violation
    report (every limit clearly holds). Light and picklable; what the batch JSON line needs."""

    summary_doc: dict
    report: LimitReport

    def summary(self) -> dict:
        return dict(self.summary_doc)


@dataclass(frozen=True)
class Screen:
    """Screening of a block of moves: ``decided`` (P,), estimated peaks (P, n_cols) in plan()'s sign
    convention (the value the limit row would show), the utilisation of every column and of every joint's
    RMS motor torque (P, n_cols + n_joints; inf for a move not screened) and the RMS motor torque
    (P, n_joints) [N·m]; ``meta`` as :meth:`~pickplace_cli.limits.motion.MotionModel.columns` gives it."""

    decided: np.ndarray
    peak: np.ndarray
    utilisation: np.ndarray
    rms: np.ndarray
    meta: list


def _given(params: dict) -> dict:
    """The method parameters that are set (plan_bspline treats None as not given)."""
    return {k: v for k, v in params.items() if v is not None}


def engine_enabled() -> bool:
    """False when ``PICKPLACE_NO_VERDICT_ENGINE`` is set to a non-empty value other than 0."""
    return os.environ.get(OFF_SWITCH, "") in ("", "0")


def engine_applies(profile, options) -> bool:
    """True when the engine can decide rows of this batch (method, options and robot in scope, switch on)."""
    from ..paths import Method
    from ..robots import build_robot

    if not engine_enabled():
        return False
    try:
        if Method(options.method) is not Method.bspline:
            return False
    except ValueError:
        return False
    params = _given(options.method_params)
    if getattr(options, "cycle", None) is not None:  # the controller's cycle: each row rounded and checked again
        return False
    if options.fit or options.shape or options.time in ("fit", "optimal") or not set(params) <= _PARAMS or ("k1" in params) != ("k2" in params):
        return False
    try:
        robot = build_robot(profile.robot)
    except PickplaceError:
        return False
    return all(hasattr(robot, n) for n in ("torque_rate", "reachable", "singularity_measure")) and (
        getattr(profile.robot, "singularity_margin", None) is not None
    )


# ------------------------------------------------------------------------------------ batched geometry


def batch_motion(breaks: np.ndarray, coef: np.ndarray, tau: np.ndarray) -> list[np.ndarray]:
    """p, p′, p″, p‴ (each (P, G, 3), p as displacement) of P piecewise quintics at their own τ (P, G):
    Horner on the piece polynomials (the bspline path's evaluator does the same per move), all four orders
    in one pass: the derivative coefficients are stacked, right-aligned, beside the position's."""
    P, m = coef.shape[:2]
    powers = np.arange(DEGREE, -1, -1.0)
    stacked = np.zeros((P, m, 4, 3, DEGREE + 1))
    for k in range(4):
        f = np.ones(DEGREE + 1 - k)
        for r in range(k):
            f = f * (powers[: DEGREE + 1 - k] - r)
        stacked[:, :, k, :, k:] = coef[..., : DEGREE + 1 - k] * f
    G = tau.shape[1]
    i = np.clip(np.sum(tau[:, :, None] >= breaks[:, None, 1:-1], axis=-1), 0, m - 1)
    dx = tau - np.take_along_axis(breaks, i, axis=1)
    # Σ_p coef[piece(τ), :, p] (τ − t_piece)^(5−p) as one matrix product per move: the powers of (τ − t_piece)
    # placed in the columns of that sample's piece, times every piece's coefficients (no (P, G, 12, 6) gather)
    w = np.zeros((P, G, m, DEGREE + 1))
    powers_dx = dx[..., None] ** powers  # highest power first, like the coefficients
    np.put_along_axis(w, i[..., None, None], powers_dx[:, :, None, :], axis=2)
    coefs = stacked.transpose(0, 1, 4, 2, 3).reshape(P, m * (DEGREE + 1), 12)  # [piece, power] × [order, axis]
    acc = w.reshape(P, G, m * (DEGREE + 1)) @ coefs
    return [acc[..., 3 * k : 3 * k + 3] for k in range(4)]


# ------------------------------------------------------------------------------------------ screening


def _thresholds(meta: list, margin: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For every column of ``MotionModel.columns``: (mid, scale, kind) to turn a column peak (column sign
    convention) into plan()'s utilisation. kind 0: upper bound, u = peak/limit; 1: lower bound (singularity
    measure, column = −value), u = floor/value with floor = max(limit, REACH_GUARD); 2: one side of a
    [min, max] range (positions, workcell), u = (value − mid)/half on the max side, (mid − value)/half on
    the min side (plan()'s range utilisation)."""
    n = len(meta)
    mid, scale, kind = np.zeros(n), np.ones(n), np.zeros(n, int)
    ranges: dict = {}
    for c, (joint, quantity, _unit, limit, _k, sign) in enumerate(meta):
        base, _, side = quantity.rpartition(" ")
        if side in ("max", "min") and base.startswith(("position", "workcell")):
            ranges.setdefault((joint, base), {})[side] = (c, float(limit))
        elif sign < 0:
            kind[c] = 1
            scale[c] = max(float(limit), REACH_GUARD)
        else:
            scale[c] = float(limit)
    for sides in ranges.values():
        (cmax, hi), (cmin, lo) = sides["max"], sides["min"]
        for c in (cmax, cmin):
            kind[c] = 2
            mid[c], scale[c] = (lo + hi) / 2, (hi - lo) / 2
    return mid, scale, kind


def _utilisation(meta: list, est: np.ndarray, margin: float) -> tuple[np.ndarray, np.ndarray]:
    """(peaks in plan()'s sign convention (the value the limit row shows), utilisations) of estimated column
    peaks ``est`` (P, n_cols) in the column sign convention of ``MotionModel.columns`` (``meta``)."""
    mid, scale, kind = _thresholds(meta, margin)
    sign = np.array([m[5] for m in meta])
    value = sign * est
    with np.errstate(divide="ignore", invalid="ignore"):
        u = np.where(kind == 0, value / scale, 0.0)
        u = np.where(kind == 1, np.where(value > 0, scale / value, np.inf), u)
        u = np.where(kind == 2, sign * (value - mid) / scale, u)
    return value, u


def screen_block(model, breaks: np.ndarray, coef: np.ndarray, origin: np.ndarray, T: np.ndarray, dwell: float,
                 samples: int = SCREEN_SAMPLES, margin: float = SCREEN_MARGIN) -> Screen:
    """Screen B moves (their piece polynomials ``breaks`` (B, 7), ``coef`` (B, 6, 3, 6) [displacement from
    ``origin`` (B, 3), m], durations ``T`` (B,) [s]) on ``samples`` uniform τ ∪ their interior knots with ONE
    model evaluation. Moves with an unreachable screening sample are not decided (they go to plan())."""
    B = len(T)
    uniform = np.linspace(0.0, 1.0, samples)
    # the knots and PIECE_SAMPLES points inside every piece: the end pieces are short (k1·k2/2 of the move,
    # ~0.01) and the torque-rate peak often sits inside one, narrower than the uniform step
    frac = np.arange(1, PIECE_SAMPLES + 1) / (PIECE_SAMPLES + 1)
    inner = (breaks[:, :-1, None] + np.diff(breaks, axis=1)[:, :, None] * frac).reshape(B, -1)
    tau = np.sort(np.concatenate([np.broadcast_to(uniform, (B, samples)), breaks[:, 1:-1], inner], axis=1), axis=1)
    G = tau.shape[1]
    p, v, a, j = batch_motion(breaks, coef, tau)
    p = p + origin[:, None, :]
    flat = lambda x: x.reshape(-1, 3)
    robot = model.robot
    reach = np.all(robot.reachable(flat(p)).reshape(B, G), axis=1)
    use = np.flatnonzero(reach)
    n_cols = None
    peak = util = rms = None
    meta: list = []
    while use.size:
        try:
            parts = model.parts(tau[use].reshape(-1), motion=tuple(flat(x[use]) for x in (p, v, a, j)))
        except UnreachableError as exc:  # not caught by the reach mask: leave that move to plan()
            if exc.index is None:
                use = use[:0]
                break
            use = np.delete(use, int(exc.index) // G)
            continue
        Tn = np.repeat(T[use], G)
        meta, data = model.columns(parts, Tn)  # every column is per sample: T may be per sample
        n_cols = data.shape[1]
        b = len(use)
        est = parabolic_peak(tau[use].reshape(-1), data, np.arange(0, b * G + 1, G))[0]
        value, u = _utilisation(meta, est, margin)
        # RMS motor torque over the duty cycle move–dwell–back–dwell (limits module docstring), per move
        tm = parts.Am.reshape(b, G, -1) / T[use, None, None] ** 2 + parts.Gm.reshape(b, G, -1)
        integral = T[use, None] * np.trapezoid(tm**2, tau[use][:, :, None], axis=1)
        gm = parts.Gm.reshape(b, G, -1)
        hold = gm[:, 0] ** 2 + gm[:, -1] ** 2
        r = np.sqrt((2 * integral + dwell * hold) / (2 * T[use, None] + 2 * dwell))
        rated = np.array([s.drive.rated_torque if s.drive and s.drive.rated_torque else np.inf for s in model.specs])
        peak = np.full((B, n_cols), np.nan)
        util = np.full((B, n_cols + len(rated)), np.inf)
        rms = np.full((B, len(rated)), np.nan)
        peak[use], util[use, :n_cols], util[use, n_cols:], rms[use] = value, u, r / rated, r
        break
    if peak is None:
        return Screen(np.zeros(B, bool), np.full((B, 0), np.nan), np.full((B, 1), np.inf), np.full((B, 0), np.nan), meta)
    decided = np.all(util <= margin, axis=1)  # False for NaN
    return Screen(decided, peak, util, rms, meta)


# ------------------------------------------------------------------------------------------- the engine


def _no_evaluation(tau, order):  # the engine's stand-in path is never evaluated (the motion is given)
    raise RuntimeError("the verdict engine's path stand-in has no evaluator")


def _k_source(options) -> tuple[Any, tuple[float, float] | None, str] | None:
    """(table, given (k1, k2), source text) of the engine's k1, k2, or None when the options are out of its
    scope (other parameters, one of k1/k2 only, a k outside (0, 1), a table that does not load)."""
    params = _given(options.method_params)
    if not set(params) <= _PARAMS or ("k1" in params) != ("k2" in params):
        return None
    if "k1" in params:
        try:
            k_given = (float(params["k1"]), float(params["k2"]))
        except (TypeError, ValueError):
            return None
        if not all(np.isfinite(k) and 0 < k < 1 for k in k_given):
            return None
        return None, k_given, "given"
    from ..lookup.bspline_table import load_table

    try:
        tab = load_table(params.get("table"))
    except PickplaceError:
        return None
    return tab, None, f"table {tab.source}"


def _candidates(rows: list[BatchRow], profile, options, height, eta) -> dict[int, tuple[Any, list]]:
    """The rows in the engine's scope with their tasks (built as plan_rows builds them: same validation, same numbers)
    and duration rules, grouped by the profile plan() plans them on (a row's ``limit_use`` scales its limits):
    {id(profile): (profile, [(row, task, rule)])}."""
    from ..model.headroom import apply_limit_use
    from ..timing import parse_time

    groups: dict[int, tuple[Any, list]] = {}
    for r in rows:
        v = r.values
        if any(v.get(f"v_{e}_{c}", 0.0) for e in ("from", "to") for c in "xyz") or any(c in v for c in BELT + ANGLES):
            continue  # moving ends, belt rows and turns of the tool: plan()
        try:
            spec = parse_time(v.get("time", options.time))
            if spec in ("fit", "optimal"):
                continue
            prof = apply_limit_use(profile, v.get("limit_use", options.limit_use))
            task = row_task(v, profile, height, eta)
        except PickplaceError:
            continue
        groups.setdefault(id(prof), (prof, []))[1].append((r, task, spec))
    return groups


def _k_values(cand: list, tab, k_given) -> tuple[np.ndarray, np.ndarray, list]:
    """k1, k2 of every candidate: Table.lookup's interpolation, vectorised; the candidates it would refuse are
    dropped (plan() plans them). → (k1, k2, the candidates kept)."""
    if tab is None:
        return np.full(len(cand), k_given[0]), np.full(len(cand), k_given[1]), cand
    lam = np.array([t.lam for _, t, _ in cand])
    b = np.array([t.b for _, t, _ in cand])
    etas = np.array([t.eta for _, t, _ in cand])
    lo, hi = float(tab.lam[0]), float(tab.lam[-1])
    keep = (b != 0) & np.isfinite(lam) & (lo - 1e-9 <= lam) & (lam <= hi + 1e-9)
    if tab.eta is not None:
        keep &= np.abs(etas - tab.eta) <= 1e-9
    k1 = np.interp(lam, tab.lam, tab.column("k1"))
    k2 = np.interp(lam, tab.lam, tab.column("k2"))
    keep &= np.isfinite(k1) & np.isfinite(k2) & (k1 > 0) & (k1 < 1) & (k2 > 0) & (k2 < 1)
    idx = np.flatnonzero(keep)
    return k1[idx], k2[idx], [cand[i] for i in idx]


def decide(rows: list[BatchRow], profile, options, height: float | None = None, eta: float | None = None,
           block: int = BLOCK_MOVES) -> dict[int, Verdict]:
    """The rows the engine decides: {row number: Verdict}. Every row not in the answer must be planned by
    plan() (it is near or over a limit, unreachable, invalid or out of the engine's scope)."""
    ks = _k_source(options)
    if ks is None:
        return {}
    out: dict[int, Verdict] = {}
    for prof, cand in _candidates(rows, profile, options, height, eta).values():
        out.update(_decide_group(cand, prof, options, ks, block))
    return out


def _decide_group(cand: list, profile, options, ks: tuple, block: int) -> dict[int, Verdict]:
    """:func:`decide` for candidates planned on one profile."""
    from ..planner import motion_model
    from ..timing import choose_duration
    from ..model.trajectory import CartesianPath, CartesianTrajectory
    from .verdict_fit import Pieces

    tab, k_given, source = ks
    rate = options.rate if options.rate is not None else profile.planning.rate
    dwell = profile.planning.dwell
    k1, k2, cand = _k_values(cand, tab, k_given)
    model = None
    out: dict[int, Verdict] = {}
    for s in range(0, len(cand), block):
        part = cand[s : s + block]
        kb1, kb2 = k1[s : s + block], k2[s : s + block]
        via = np.stack([t.via_points() - t.p_from for _, t, _ in part])
        breaks, coef, peaks = batch_paths(kb1, kb2, via)
        # the (first) duration of each move exactly as plan() chooses it (auto, Eq. 26, or the row's seconds)
        done = []
        for i, (r, task, spec) in enumerate(part):
            parameters = {"k1": float(kb1[i]), "k2": float(kb2[i]), "k_source": source, "lambda": task.lam,
                          "eta": task.eta}
            path = CartesianPath(_no_evaluation, "bspline", parameters, tuple(float(x) for x in peaks[i]), breaks[i],
                                 jumps=())
            try:
                duration = choose_duration(path, profile.capacity, "auto" if spec == "limits" else spec)
                traj = CartesianTrajectory(path, duration.seconds)
                t = traj.sample_times(rate)
            except (PickplaceError, ValueError):  # e.g. too many samples (a time in ms): plan() says so, for the row
                continue
            if not all(c.ok for c in capacity_rows(path, duration.seconds, profile.capacity)):
                continue  # a given duration past the Cartesian capacity: plan() says which (exit 3)
            done.append((i, r, task, path, duration, traj, t, spec == "limits"))
        if not done:
            continue
        if model is None:
            model = motion_model(done[0][3], profile)
        given = [d for d in done if not d[7]]
        if given:
            sel = np.array([d[0] for d in given])
            screen = screen_block(model, breaks[sel], coef[sel], np.stack([d[2].p_from for d in given]),
                                  np.array([d[4].seconds for d in given]), dwell)
            for ok, d in zip(screen.decided, given):
                if ok:
                    out[d[1].row] = _verdict(d[2], d[3], d[4], d[5], d[6], profile)
        rule = [d for d in done if d[7]]
        if rule:
            pieces = Pieces(breaks, coef, via, np.stack([t.p_from for _, t, _ in part]))
            fits = _limits_block(model, profile, pieces, [(d[0], d[4].seconds, d[6]) for d in rule])
            for i, r, task, path, duration, traj, t, _ in rule:
                if i in fits:
                    duration = replace(duration, mode="limits", binding=f"capacity {duration.binding}", t_fit=fits[i])
                    out[r.row] = _verdict(task, path, duration, traj, t, profile)
    return out


def _verdict(task, path, duration, traj, t, profile) -> Verdict:
    """The Verdict of a decided row: ``Plan.summary`` of the numbers plan() computes, every limit clearly held."""
    from types import SimpleNamespace

    from ..planner import Plan

    report = LimitReport((), duration.seconds, profile.planning.dwell)
    stand_in = SimpleNamespace(task=task, method=path.method, parameters=path.parameters, duration=duration,
                               cartesian=traj, t=t, report=report, profile_name=profile.name)
    return Verdict(Plan.summary(stand_in), report)  # type: ignore[arg-type]


def _limits_block(model, profile, pieces, items: list, margin: float = SCREEN_MARGIN) -> dict[int, float | None]:
    """The rows of ``time = limits`` (``items``: (index in ``pieces``, auto duration T [s], output sample times
    [s])) that the engine decides: {index: fit_s [s] or None}, as plan() computes them on its first samples
    (:mod:`~pickplace_cli.pipelines.verdict_fit`); a row is decided when every limit is clearly held at T (the
    screening's contract) and the capacity binds (the fit is clearly shorter)."""
    from ..limits.motion import MotionModel, duty_cycle_rms
    from ..model.trajectory import CartesianPath
    from ..planner import motion_model_static
    from .verdict_fit import FirstSamples, limits_fit, model_at, rms_integrals, take_moves

    static = motion_model_static(profile)
    dwell = profile.planning.dwell
    rated = np.array([s.drive.rated_torque if s.drive and s.drive.rated_torque else np.inf for s in model.specs])

    def model_of(k: int):  # one move's model: its RMS quadrature evaluates the path where it refines
        return MotionModel(CartesianPath(_no_evaluation, "bspline", {}, (0.0, 0.0, 0.0), pieces.breaks[k], jumps=(),
                                         evaluate_all=pieces.evaluator(k)), *static)

    # the grids below assume breakpoints 0 < … < 1 (always so for the B-spline; any other move: plan())
    br = pieces.breaks
    items = [it for it in items if br[it[0], 0] == 0.0 and br[it[0], -1] == 1.0 and np.all(np.diff(br[it[0]]) > 0)]
    out: dict[int, float | None] = {}
    for chunk in _sample_blocks([len(t) + 200 for _, _, t in items]):
        idx = np.array([items[c][0] for c in chunk])
        T = np.array([items[c][1] for c in chunk])
        first = FirstSamples([items[c][2] / items[c][1] for c in chunk], br[idx])  # plan()'s first samples, sorted
        parts, keep = model_at(model, pieces, first.grid, np.repeat(idx, first.lengths), first.lengths)
        if parts is None:
            continue
        local = np.flatnonzero(keep)
        idx, T = idx[keep], T[keep]
        lengths = first.lengths[keep]
        starts = np.concatenate([[0], np.cumsum(lengths)])
        meta, data = model.columns(parts, np.repeat(T, lengths))
        est, _ = parabolic_peak(parts.tau, data, starts)
        clear = np.flatnonzero(np.all(_utilisation(meta, est, margin)[1] <= margin, axis=1))
        if not clear.size:
            continue
        if len(clear) < len(idx):
            parts, starts = take_moves(parts, starts, clear)
            idx, T, local = idx[clear], T[clear], local[clear]
        rms = rms_integrals(first, local, parts, starts, model, pieces, idx, lambda j: model_of(int(idx[j])))
        fits = limits_fit(model, parts, starts, T, rms, dwell)
        held = np.all(duty_cycle_rms(*rms, T[:, None], dwell) / rated <= margin, axis=1)
        for k, fit, ok in zip(idx.tolist(), fits, held):
            if ok and (fit is None or fit == fit):
                out[k] = fit
    return out


def _sample_blocks(lengths: list[int]) -> list[list[int]]:
    """Consecutive groups of moves of about ``BLOCK_SAMPLES`` samples in all (at least one move each)."""
    groups: list[list[int]] = [[]]
    total = 0
    for i, n in enumerate(lengths):
        if groups[-1] and total + n > BLOCK_SAMPLES:
            groups.append([])
            total = 0
        groups[-1].append(i)
        total += n
    return groups if groups[0] else []


def verdict_rows(
    rows: list[BatchRow], profile, options, height: float | None = None, eta: float | None = None,
    fail_fast: bool = False, source: str = "batch",
) -> Iterator[RowResult]:
    """:func:`~pickplace_cli.pipelines.batch.plan_rows` for a verdicts-only batch: the rows the engine decides
    (:func:`decide`) come back as :class:`Verdict`, every other row is planned by plan_rows (plan()), in row
    order. Stops after the first failing row when ``fail_fast``."""
    decided = decide(rows, profile, options, height, eta) if engine_applies(profile, options) else {}
    for r in rows:
        if r.row in decided:
            yield RowResult(r.row, decided[r.row], None, 0)
            continue
        res = next(plan_rows([r], profile, options, height, eta, False, source))
        yield res
        if fail_fast and res.code:
            return


def _verdict_chunk(args) -> list[RowResult]:
    """Worker: :func:`verdict_rows` on a chunk; plans come back as light Verdicts (summary + report)."""
    from ..lookup.executors import stopped

    rows, profile, options, height, eta, source = args
    out = []
    if stopped():  # (a chunk queued before the parent stopped: not started)
        return out
    for r in verdict_rows(rows, profile, options, height, eta, False, source):
        if stopped():  # the parent no longer wants the answers
            break
        plan = r.plan
        if plan is not None and not isinstance(plan, Verdict):
            plan = Verdict(plan.summary(), plan.report)
        out.append(RowResult(r.row, plan, r.error, r.code))
    return out


def verdict_rows_parallel(
    rows: list[BatchRow], profile, options, height: float | None = None, eta: float | None = None,
    fail_fast: bool = False, source: str = "batch", workers: int = 2, chunk: int | None = None,
) -> Iterator[RowResult]:
    """:func:`verdict_rows` on ``workers`` processes (chunks of ``chunk`` rows, default: about four per
    worker, at least 500: the engine decides ~2,500 rows/s per process, so a smaller chunk costs more in
    process start-up and transfer than it saves), results in row order; one process when there are too
    few rows."""
    if chunk is None:
        chunk = max(500, -(-len(rows) // (4 * max(workers, 1))))
    if workers <= 1 or len(rows) <= chunk:
        yield from verdict_rows(rows, profile, options, height, eta, fail_fast, source)
        return
    chunks = [rows[i : i + chunk] for i in range(0, len(rows), chunk)]
    # warm up here (imports, the λ table, the planner's modules): forked workers inherit it instead of each
    # paying ~0.3 s for it
    decide(rows[:1], profile, options, height, eta)
    next(plan_rows(rows[:1], profile, options, height, eta, False, source), None)
    yield from run_chunks_in_order(
        _verdict_chunk, [(c, profile, options, height, eta, source) for c in chunks], workers, fail_fast
    )
