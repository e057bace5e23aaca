"""The fitted duration in closed form: for a fixed path every limited quantity is a known function of the duration
T at each sample, so the smallest T at which a sample holds its limit is solved exactly, sample by sample, with
no root search (and no import of scipy.optimize: the default duration of ``plan`` is a fit, and start-up counts).

With the model evaluated once at T = 1 s (:class:`~pickplace_cli.limits.motion.Parts`), at a duration T and with
u = 1/T, s = 1/T²:

========================  ==========================  =====================================================
quantity                  value at T                  smallest T that holds the limit L at one sample
========================  ==========================  =====================================================
joint velocity, motor     |c|·u                       T = |c| / L
speed
joint acceleration        |c|·u²                      T = √(|c| / L)
joint jerk                |c|·u³                      T = ∛(|c| / L)
motor torque              |A·s + G|                   feasible s form an interval holding 0 when |G| ≤ L:
                                                      s ≤ (L − sgn(A)·G)/|A|, so T = 1/√(min over samples)
motor torque rate         |a·u³ + b·u|                the first u > 0 where |a·u³ + b·u| = L (convex pieces,
                                                      Newton from the safe side, monotone convergence)
RMS motor torque          √((2·T·(I_AA/T⁴ + 2·I_AG/T²  the largest real root of the quartic
                          + I_GG) + d·H)/(2T + 2d))   2(R² − I_GG)T⁴ + d(2R² − H)T³ − 4·I_AG·T² − 2·I_AA
========================  ==========================  =====================================================

Each threshold is the smallest T from which the limit holds at that sample *for every longer duration* (the
torque rate of one sample can dip back under its limit at a shorter T; the threshold is the first crossing
seen from long durations, as the bracketing search of :func:`~pickplace_cli.timing.screened_root` finds it).
The maximum over samples and quantities is the fit on the samples; the exact check (the continuous peaks)
then confirms it or nudges it up (:func:`~pickplace_cli.timing.fit_duration`).
"""

from __future__ import annotations

import math

import numpy as np

from ..model.errors import NoFeasibleDuration


def _largest(values: np.ndarray) -> tuple[float, int]:
    """(max, its index) of a 1-D array; (0, -1) when empty."""
    if values.size == 0:
        return 0.0, -1
    k = int(np.argmax(values))
    return float(values[k]), k


def torque_rate_threshold(a: np.ndarray, b: np.ndarray, limit: float) -> np.ndarray:
    """Per sample, the smallest u = 1/T > 0 at which |a·u³ + b·u| reaches ``limit`` (inf: never), in closed form.

    With a > 0 (the sign of both flipped otherwise, |·| unchanged) and p = b/a, ℓ = limit/a: for b ≥ 0 the
    function rises from 0, and the crossing is the one real root of u³ + p·u − ℓ = 0 (hyperbolic form). For b < 0
    it dips below 0 down to −(2/3)|b|·u_m at u_m = √(−p/3) and rises beyond u₀ = √(−p): when the dip reaches −limit
    the crossing is the smaller positive root of u³ + p·u + ℓ = 0 (trigonometric form, three real roots), else
    the largest root of u³ + p·u − ℓ = 0 (hyperbolic form with one real root, trigonometric with three). a = 0:
    u = limit/|b|."""
    a = np.asarray(a, float)
    b = np.asarray(b, float)
    flip = a < 0
    a = np.where(flip, -a, a)
    b = np.where(flip, -b, b)
    a, b, L = np.broadcast_arrays(a, b, np.asarray(limit, float))
    out = np.full(a.shape, np.inf)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        lin = a == 0.0
        out[lin & (b != 0)] = L[lin & (b != 0)] / np.abs(b[lin & (b != 0)])
        cub = ~lin
        if not cub.any():
            return out
        p, ell = b[cub] / a[cub], L[cub] / a[cub]
        u = np.empty(p.shape)
        pos, neg = p > 0, p < 0
        u[p == 0] = np.cbrt(ell[p == 0])
        # u³ + p·u − ℓ = 0, p > 0: u = 2√(p/3)·sinh(asinh(3ℓ/(2p)·√(3/p))/3)
        r = np.sqrt(p[pos] / 3.0)
        u[pos] = 2.0 * r * np.sinh(np.arcsinh(1.5 * ell[pos] / (p[pos] * r)) / 3.0)
        r = np.sqrt(-p[neg] / 3.0)  # p < 0: the extremes of u³ + p·u are at ±r, of size 2r³
        e = ell[neg]
        dip = e <= 2.0 * r**3  # |u³ + p·u| reaches ℓ on the dip
        x = np.clip(e / (2.0 * r**3), -1.0, 1.0)
        # dip: u³ + p·u + ℓ = 0, roots 2r·cos(θ/3 − 2πk/3) with cos θ = −ℓ/(2r³); the smaller positive one is k = 1
        th = np.arccos(-x)
        u_dip = 2.0 * r * np.cos(th / 3.0 - 2.0 * np.pi / 3.0)
        # beyond: u³ + p·u − ℓ = 0; one real root 2r·cosh(acosh(ℓ/(2r³))/3) when ℓ > 2r³, else the largest 2r·cos(θ/3)
        big = e / (2.0 * r**3)
        u_far = np.where(big > 1.0, 2.0 * r * np.cosh(np.arccosh(np.maximum(big, 1.0)) / 3.0),
                         2.0 * r * np.cos(np.arccos(x) / 3.0))
        u[neg] = np.where(dip, u_dip, u_far)
        out[cub] = u
    return out


def rms_thresholds(iaa, iag, igg, hold, dwell: float, rated) -> np.ndarray:
    """Per joint, the smallest T [s] from which the RMS motor torque over the duty cycle stays ≤ ``rated``: the
    largest real root of the quartic of the module's table (its companion matrices' eigenvalues, all joints in
    one call); inf where the holding torque alone exceeds the rating (the RMS tends to √I_GG for long moves)."""
    iaa, iag, igg, hold, r2 = (np.asarray(x, float) for x in (iaa, iag, igg, hold, np.square(rated)))
    lead = 2.0 * (r2 - igg)
    out = np.full(lead.shape, np.inf)
    ok = lead > 0
    if not ok.any():
        return out
    # monic: T⁴ + c3·T³ + c2·T² + 0·T + c0
    c3 = dwell * (2.0 * r2[ok] - hold[ok]) / lead[ok]
    c2 = -4.0 * iag[ok] / lead[ok]
    c0 = -2.0 * iaa[ok] / lead[ok]
    m = np.zeros((int(ok.sum()), 4, 4))
    m[:, 1, 0] = m[:, 2, 1] = m[:, 3, 2] = 1.0
    m[:, 0, 0], m[:, 0, 1], m[:, 0, 3] = -c3, -c2, -c0
    roots = np.linalg.eigvals(m)
    real = np.where(np.abs(roots.imag) <= 1e-9 * np.maximum(np.abs(roots.real), 1.0), roots.real, 0.0)
    out[ok] = np.maximum(real.max(axis=1), 0.0)
    return out


def fit_thresholds(model, parts, dwell: float = 0.0, rms: bool = True) -> list[tuple[str, float]]:
    """[(name "joint quantity", the smallest T [s] from which it holds at every sample of ``parts``)] for every
    limit of ``model`` that depends on the duration (the module's table); an empty list when none does.
    Raises NoFeasibleDuration naming the quantity when no duration holds it (the holding torque alone exceeds it).
    ``rms=False`` leaves the RMS out (it does not depend on the samples)."""
    meta, _ = model.columns(parts, 1.0)
    index = {name: i for i, name in enumerate(model.robot.joint_names)}
    out: list[tuple[str, float]] = []
    rates: list[tuple[str, int, float]] = []
    for joint, quantity, _unit, limit, kind, _sign in meta:
        if kind != "limit":
            continue
        i = index[joint]
        name = f"{joint} {quantity}"
        if quantity == "velocity":
            t = _largest(np.abs(parts.qd1[:, i]))[0] / limit
        elif quantity == "motor speed":
            t = _largest(np.abs(model.gear[i] * parts.qd1[:, i]))[0] / limit
        elif quantity == "acceleration":
            t = math.sqrt(_largest(np.abs(parts.qdd1[:, i]))[0] / limit)
        elif quantity == "jerk":
            t = math.cbrt(_largest(np.abs(parts.qddd1[:, i]))[0] / limit)
        elif quantity == "motor torque":
            t = _torque_threshold(parts.Am[:, i], parts.Gm[:, i], limit, name)
        elif quantity == "motor torque rate":  # solved below, every joint in one call
            rates.append((name, i, float(limit)))
            continue
        else:  # pragma: no cover - a new timed quantity must be added to the table above
            raise ValueError(f"fit: no closed form for {quantity}")
        out.append((name, float(t)))
    if rates and len(parts.tau):
        cols = [i for _, i, _ in rates]
        u = torque_rate_threshold(parts.dAm[:, cols], parts.dGm[:, cols], np.array([lim for *_, lim in rates]))
        for (name, _, _), first in zip(rates, u.min(axis=0)):
            out.append((name, 1.0 / float(first) if np.isfinite(first) and first > 0 else 0.0))
    rated = [s.drive.rated_torque if s.drive is not None and s.drive.rated_torque else None for s in model.specs]
    has = [i for i, r in enumerate(rated) if r is not None]
    if rms and has:
        (iaa, iag, igg), g = model.rms_integrals(parts)
        hold = g[0] ** 2 + g[1] ** 2
        ts = rms_thresholds(iaa[has], iag[has], igg[has], hold[has], dwell, [rated[i] for i in has])
        for i, t in zip(has, ts):
            name = f"{model.robot.joint_names[i]} rms motor torque"
            if not math.isfinite(t):
                raise NoFeasibleDuration(f"time = fit: no duration satisfies {name} (the holding torque alone "
                                         f"exceeds the rated {rated[i]:g} N·m)")
            out.append((name, float(t)))
    return out


def _torque_threshold(A: np.ndarray, G: np.ndarray, limit: float, name: str) -> float:
    """The smallest T with |A/T² + G| ≤ limit at every sample (module table)."""
    if np.any(np.abs(G) > limit):
        raise NoFeasibleDuration(f"time = fit: no duration satisfies {name} (the holding torque alone exceeds "
                                 f"{limit:g} N·m)")
    absA = np.abs(A)
    moving = absA > 0
    if not moving.any():
        return 0.0
    s_max = (limit - np.sign(A[moving]) * G[moving]) / absA[moving]
    smin = float(s_max.min())
    return math.inf if smin <= 0 else 1.0 / math.sqrt(smin)


def screened_fit(model, parts, dwell: float = 0.0) -> tuple[float, str] | None:
    """(T [s], binding "joint quantity"): the fit on the samples of ``parts``, the largest threshold of
    :func:`fit_thresholds`; None when no limit depends on the duration."""
    found = fit_thresholds(model, parts, dwell)
    if not found:
        return None
    name, t = max(found, key=lambda f: f[1])
    return t, name


# ------------------------------------------------------------------------- the same fit for many moves at once
#
# The batch verdict engine (:mod:`pickplace_cli.pipelines.verdicts`) evaluates the model of P moves in one call,
# their samples one move after the other (move k in rows starts[k]:starts[k + 1], sorted in τ within a move).
# The functions below give, for every move, the very numbers :func:`fit_thresholds`, :func:`screened_fit` and
# :func:`~pickplace_cli.timing.fit_screen` give for that move alone: the same operations sample by sample, and
# maxima, minima and arg-maxima per move (exact whatever the order). Where the scalar functions raise
# NoFeasibleDuration they give inf; where a number is NaN the move's result is NaN (the scalar functions' Python
# ``max`` skips a NaN that is not first: such a move is not comparable and is left to the scalar path).


def _segment_reduce(ufunc, x: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """``ufunc.reduce`` of every move's rows of ``x`` (axis 0); every move has at least one row."""
    return ufunc.reduceat(x, starts[:-1], axis=0)


def _batch_torque_threshold(A: np.ndarray, G: np.ndarray, limit: float, starts: np.ndarray) -> np.ndarray:
    """:func:`_torque_threshold` per move (inf where the holding torque alone exceeds ``limit``)."""
    absA = np.abs(A)
    moving = absA > 0
    with np.errstate(divide="ignore", invalid="ignore"):
        s_max = np.where(moving, (limit - np.sign(A) * G) / absA, np.inf)
        smin = _segment_reduce(np.minimum, s_max, starts)
        t = np.where(smin <= 0, np.inf, 1.0 / np.sqrt(smin))
    t = np.where(_segment_reduce(np.logical_or, moving, starts), t, 0.0)
    return np.where(_segment_reduce(np.logical_or, np.abs(G) > limit, starts), np.inf, t)


def batch_fit_thresholds(model, parts, starts: np.ndarray, rms: tuple | None = None, dwell: float = 0.0,
                         only_max: bool = False) -> tuple[list[str], np.ndarray]:
    """:func:`fit_thresholds` of P moves at once: ``parts`` holds their samples one move after the other, move k in
    rows ``starts[k]:starts[k + 1]`` (at least one each); ``rms`` = (I (P, 3, n), G_end (P, 2, n)), every move's
    :meth:`~pickplace_cli.limits.motion.MotionModel.rms_integrals`, or None to leave the RMS out (``rms=False``).
    → (names "joint quantity" in fit_thresholds' order, thresholds (P, len(names)) [s]), bitwise fit_thresholds'
    numbers for each move; inf where it raises NoFeasibleDuration.

    ``only_max``: only each move's largest threshold is needed (the fit), so the costly closed forms are skipped
    where a bound shows them below the move's largest cheap threshold (velocity, acceleration, jerk, motor speed
    and torque, and the exact torque rate threshold of the sample of largest bound): a sample's torque rate
    threshold is at most max(∛(2|a|/L), 2|b|/L) (below it |a·u³ + b·u| < L; compared cubed), an RMS threshold at
    most a bound on the roots of its quartic (:func:`_batch_rms_thresholds`). A quantity below the move's largest
    may then read lower than its own threshold (0 when all its samples are skipped); the largest threshold of every
    move is unchanged, bit for bit."""
    starts = np.asarray(starts, dtype=np.intp)
    P = len(starts) - 1
    meta = model._column_plan(parts.dAm is not None, parts.singularity is not None)[0]
    index = {name: i for i, name in enumerate(model.robot.joint_names)}
    names: list[str] = []
    cols: list[np.ndarray] = []
    rates: list[tuple[str, int, float]] = []
    peak = lambda x: _segment_reduce(np.maximum, x, starts)  # noqa: E731
    for joint, quantity, _unit, limit, kind, _sign in meta:
        if kind != "limit":
            continue
        i = index[joint]
        name = f"{joint} {quantity}"
        if quantity == "velocity":
            t = peak(np.abs(parts.qd1[:, i])) / limit
        elif quantity == "motor speed":
            t = peak(np.abs(model.gear[i] * parts.qd1[:, i])) / limit
        elif quantity == "acceleration":
            t = np.sqrt(peak(np.abs(parts.qdd1[:, i])) / limit)
        elif quantity == "jerk":  # math.cbrt as the scalar fit takes it (numpy's cbrt may round differently)
            t = np.array([math.cbrt(x) for x in (peak(np.abs(parts.qddd1[:, i])) / limit).tolist()])
        elif quantity == "motor torque":
            t = _batch_torque_threshold(parts.Am[:, i], parts.Gm[:, i], limit, starts)
        elif quantity == "motor torque rate":
            rates.append((name, i, float(limit)))
            continue
        else:  # pragma: no cover - a new timed quantity must be added to the table above
            raise ValueError(f"fit: no closed form for {quantity}")
        names.append(name)
        cols.append(t)
    floor = (np.column_stack(cols).max(axis=1) if cols else np.zeros(P)) if only_max else None
    if rates and len(parts.tau):
        c = [i for _, i, _ in rates]
        t = _batch_rate_thresholds(parts.dAm[:, c], parts.dGm[:, c], np.array([lim for *_, lim in rates]), starts,
                                   floor)
        names += [name for name, _, _ in rates]
        cols += list(t.T)
        if only_max:
            floor = np.maximum(floor, t.max(axis=1))
    rated = [s.drive.rated_torque if s.drive is not None and s.drive.rated_torque else None for s in model.specs]
    has = [i for i, r in enumerate(rated) if r is not None]
    if rms is not None and has:
        integrals, ends = (np.asarray(x, float) for x in rms)
        hold = ends[:, 0] ** 2 + ends[:, 1] ** 2  # (P, n)
        flat = lambda x: x[:, has].ravel()  # noqa: E731
        ts = _batch_rms_thresholds(flat(integrals[:, 0]), flat(integrals[:, 1]), flat(integrals[:, 2]), flat(hold),
                                   dwell, np.tile([rated[i] for i in has], P),
                                   None if floor is None else np.repeat(floor, len(has))).reshape(P, len(has))
        names += [f"{model.robot.joint_names[i]} rms motor torque" for i in has]
        cols += list(ts.T)
    return names, (np.column_stack(cols) if cols else np.zeros((P, 0)))


#: relative safety of the bounds that skip a closed form (far above the bounds' round-off)
_BOUND_SAFETY = 1e-9


def _batch_rate_thresholds(a: np.ndarray, b: np.ndarray, limits: np.ndarray, starts: np.ndarray,
                           floor: np.ndarray | None) -> np.ndarray:
    """Per move and torque-rate column, the smallest T [s] from which |a/T³ + b/T| ≤ limit at all its samples
    (:func:`torque_rate_threshold`, the first crossing per sample, the latest over samples); with ``floor`` (P,) the
    samples whose bound (batch_fit_thresholds) lies below their move's floor are skipped."""
    if floor is None:
        u = torque_rate_threshold(a, b, limits)
    else:
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            y = 2.0 * np.abs(b) / limits
            cube = np.maximum(2.0 * np.abs(a) / limits, y * y * y)  # the bound cubed (no cube root needed)
            # the floor raised to the exact threshold of each column's sample of largest bound (a value the answer
            # reaches at least), so that only the samples that may reach the answer are solved
            top = np.array([np.argmax(cube[s:e], axis=0) + s for s, e in zip(starts[:-1].tolist(), starts[1:].tolist())])
            cols = np.arange(a.shape[1])
            first = torque_rate_threshold(a[top, cols], b[top, cols], np.broadcast_to(limits, top.shape))
            exact = np.where(np.isfinite(first) & (first > 0), 1.0 / first, 0.0)
            floor = np.maximum(floor, exact.max(axis=1)) / (1.0 + _BOUND_SAFETY)
            need = ~(cube < np.repeat(floor * floor * floor, np.diff(starts))[:, None])  # (NaN: computed, stays NaN)
        u = np.full(a.shape, np.inf)
        u[need] = torque_rate_threshold(a[need], b[need], np.broadcast_to(limits, a.shape)[need])
    first = _segment_reduce(np.minimum, u, starts)  # (P, columns)
    with np.errstate(divide="ignore"):
        return np.where(np.isfinite(first) & (first > 0), 1.0 / first, 0.0)


def _batch_rms_thresholds(iaa, iag, igg, hold, dwell: float, rated, floor: np.ndarray | None) -> np.ndarray:
    """:func:`rms_thresholds` of flat (move, joint) entries; with ``floor`` the entries whose quartic T⁴ + c3·T³ +
    c2·T² + c0 has no real root above it read 0 without a solve. The bound: with c3 ≥ 0 the quartic is at least
    T⁴ + c2·T² + c0 for T ≥ 0, whose largest root is √((−c2 + √(c2² − 4·c0))/2) (c0 ≤ 0); else Fujiwara's bound
    on every root, 2·max(|c3|, |c2|^½, |c0/2|^¼)."""
    if floor is None:
        return rms_thresholds(iaa, iag, igg, hold, dwell, rated)
    r2 = np.square(rated)
    lead = 2.0 * (r2 - igg)
    with np.errstate(divide="ignore", invalid="ignore"):
        c3, c2, c0 = dwell * (2.0 * r2 - hold) / lead, -4.0 * iag / lead, -2.0 * iaa / lead
        biquadratic = np.sqrt((-c2 + np.sqrt(c2 * c2 - 4.0 * c0)) / 2.0)
        fujiwara = 2.0 * np.maximum(np.maximum(np.abs(c3), np.sqrt(np.abs(c2))), np.sqrt(np.sqrt(np.abs(c0) / 2.0)))
        bound = np.where((c3 >= 0) & (c0 <= 0), biquadratic, fujiwara)
    skip = (lead > 0) & (bound * (1.0 + _BOUND_SAFETY) < floor)
    out = np.zeros(len(lead))
    keep = ~skip
    out[keep] = rms_thresholds(iaa[keep], iag[keep], igg[keep], hold[keep], dwell, np.asarray(rated)[keep])
    return out


def segment_parabolic_peak(x: np.ndarray, y: np.ndarray, starts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per move (rows ``starts[k]:starts[k + 1]`` of the sorted τ ``x`` (M,) and the columns ``y`` (M, C)):
    :func:`~pickplace_cli.limits.check._parabolic_peak` at every column's top sample (its first maximum, as
    ``np.argmax``), on a path without jumps. → (peak, τ of the peak), each (P, C), bitwise the function's."""
    starts = np.asarray(starts, dtype=np.intp)
    n = np.diff(starts)
    P, C = len(n), y.shape[1]
    if P == 0:
        return np.zeros((0, C)), np.zeros((0, C))
    # the first maximum of every move's column (np.argmax per move: faster than one call on padded arrays)
    i = np.array([np.argmax(y[s:e], axis=0) for s, e in zip(starts[:-1].tolist(), starts[1:].tolist())])
    first = starts[:-1, None]
    k = np.minimum(np.maximum(i, 1), np.maximum(n[:, None] - 2, 1)) + first
    i = i + first
    cols = np.arange(C)
    top, at_top = y[i, cols], x[i]
    near = [np.minimum(np.maximum(k + d, 0), len(x) - 1) for d in (-1, 0, 1)]  # (a move of < 3 samples: unused)
    (x0, x1, x2), (y0, y1, y2) = (x[j] for j in near), (y[j, cols] for j in near)
    with np.errstate(divide="ignore", invalid="ignore"):
        d1 = (y1 - y0) / (x1 - x0)
        d2 = (y2 - y1) / (x2 - x1)
        curv = (d2 - d1) / (x2 - x0)
        ok = (curv < 0) & (k == i) & (n[:, None] >= 3)
        slope = d1 + curv * (x1 - x0)
        safe = np.where(ok, curv, -1.0)
        xv = np.minimum(np.maximum(x1 - slope / (2 * safe), x0), x2)
        yv = y1 - slope**2 / (4 * safe)
    use = ok & (yv >= top)
    return np.where(use, yv, top), np.where(use, xv, at_top)


def _timed_columns(model, parts, T: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """The duration-dependent columns of :meth:`~pickplace_cli.limits.motion.MotionModel.columns` (kind "limit", in
    its order) with move k at duration T[k] [s]: the powers of T taken as the scalar columns take them (Python
    floats), so every value is bitwise the one of that move alone."""
    meta = model._column_plan(parts.dAm is not None, parts.singularity is not None)[0]
    index = {name: i for i, name in enumerate(model.robot.joint_names)}
    Ts = T.tolist()
    t1 = np.repeat(T, lengths)
    t2, t3 = (np.repeat(np.array([t**e for t in Ts]), lengths) for e in (2, 3))
    out = []
    for joint, quantity, _unit, _limit, kind, _sign in meta:
        if kind != "limit":
            continue
        i = index[joint]
        out.append({
            "velocity": lambda: np.abs(parts.qd1[:, i]) / t1,
            "acceleration": lambda: np.abs(parts.qdd1[:, i]) / t2,
            "jerk": lambda: np.abs(parts.qddd1[:, i]) / t3,
            "motor speed": lambda: np.abs(model.gear[i] * parts.qd1[:, i]) / t1,
            "motor torque": lambda: np.abs(parts.Am[:, i] / t2 + parts.Gm[:, i]),
            "motor torque rate": lambda: np.abs(parts.dAm[:, i] / t3 + parts.dGm[:, i] / t1),
        }[quantity]())
    return np.column_stack(out) if out else np.zeros((len(parts.tau), 0))


def batch_fit_screen(model, parts, starts: np.ndarray, rms: tuple | None, dwell: float, evaluate) -> np.ndarray | None:
    """:func:`~pickplace_cli.timing.fit_screen`'s duration for P moves at once (``parts``, ``starts``, ``rms`` as in
    :func:`batch_fit_thresholds`, every move's samples sorted in τ; paths without jumps): the closed-form fit on the
    samples raised to the closed form at the parabola vertices of the timed columns' top samples. ``evaluate(tau,
    move)`` → the model's Parts at the points ``tau`` (M,) of the moves ``move`` (M,), one after the other (NaN rows
    for a move it cannot evaluate). → (P,) [s], bitwise fit_screen's T for each move; NaN where fit_screen raises or
    a number is NaN; None when no limit depends on the duration (fit_screen's None)."""
    names, th = batch_fit_thresholds(model, parts, starts, rms, dwell, only_max=True)
    if not names:
        return None
    T = th.max(axis=1)  # the value of screened_fit's first maximum
    bad = ~(np.isfinite(T) & (T <= 1e4))
    T = np.where(bad, 1.0, np.maximum(T, 1e-4))  # (a placeholder where fit_screen raises: NaN below)
    lengths = np.diff(starts)
    d = _timed_columns(model, parts, T, lengths)
    if d.shape[1]:  # _at_peaks: the closed form at the vertices (_solve_at)
        _, at = segment_parabolic_peak(parts.tau, d, starts)
        P, C = at.shape
        more = evaluate(np.clip(at.ravel(), 0.0, 1.0), np.repeat(np.arange(P), C))
        found, th2 = batch_fit_thresholds(model, more, np.arange(0, P * C + 1, C), None, dwell, only_max=True)
        if found:
            at_vertices = th2.max(axis=1)
            bad |= np.isinf(at_vertices)  # a holding torque over its limit at a vertex: _solve_at raises
            T = np.maximum(T, at_vertices)
    return np.where(bad, np.nan, T)
