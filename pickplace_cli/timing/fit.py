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

from typing import NamedTuple

import numpy as np

from ..model.errors import NoFeasibleDuration


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


def threshold_columns(model, parts) -> tuple[list[str], np.ndarray | None, list[tuple[str, float, np.ndarray]]]:
    """Every duration-dependent limit's threshold at every sample of ``parts`` (the module's table): (names "joint
    quantity", thresholds (samples, quantities) [s] or None when no limit depends on the duration, and for each
    motor torque (name, limit, the samples where the holding torque alone exceeds it)). Element by element: the
    samples of many moves stacked give each move's own numbers (the batch functions below)."""
    meta = model._column_plan(parts.dAm is not None, parts.singularity is not None)[0]
    index = {name: i for i, name in enumerate(model.robot.joint_names)}
    names, cols = [], []
    rates: list[tuple[int, float]] = []
    overloads: list[tuple[str, float, np.ndarray]] = []
    with np.errstate(divide="ignore", invalid="ignore"):
        for joint, quantity, _unit, limit, kind, _sign in meta:
            if kind != "limit":
                continue
            i = index[joint]
            name = f"{joint} {quantity}"
            if quantity == "velocity":
                col = np.abs(parts.qd1[:, i]) / limit
            elif quantity == "motor speed":
                col = np.abs(model.gear[i] * parts.qd1[:, i]) / limit
            elif quantity == "acceleration":
                col = np.sqrt(np.abs(parts.qdd1[:, i]) / limit)
            elif quantity == "jerk":
                col = np.cbrt(np.abs(parts.qddd1[:, i]) / limit)
            elif quantity == "motor torque":
                A, G = parts.Am[:, i], parts.Gm[:, i]
                overloads.append((name, float(limit), np.abs(G) > limit))
                absA = np.abs(A)
                s_max = (limit - np.sign(A) * G) / absA  # inf where A = 0
                col = np.where(absA > 0, 1.0 / np.sqrt(np.maximum(s_max, 0.0)), 0.0)
            elif quantity == "motor torque rate":  # solved below, every joint in one call
                rates.append((i, float(limit)))
                col = None
            else:  # pragma: no cover - a new timed quantity must be added to the table above
                raise ValueError(f"fit: no closed form for {quantity}")
            names.append(name)
            cols.append(col)
        if rates:
            idx = [i for i, _ in rates]
            u = torque_rate_threshold(parts.dAm[:, idx], parts.dGm[:, idx], np.array([lim for _, lim in rates]))
            per = iter(np.where(np.isfinite(u) & (u > 0), 1.0 / u, 0.0).T)
            cols = [next(per) if c is None else c for c in cols]
    data = np.column_stack(cols) if cols else None
    return names, data, overloads


def _rated(model) -> tuple[list, list[int]]:
    """Each joint's rated torque [N·m] or None, and the joints that have one."""
    rated = [s.drive.rated_torque if s.drive is not None and s.drive.rated_torque else None for s in model.specs]
    return rated, [i for i, r in enumerate(rated) if r is not None]


def fit_thresholds(model, parts, dwell: float = 0.0, rms: bool = True, seg=None,
                   refine: bool = False, vertices: list | None = None) -> list[tuple[str, float]]:
    """[(name "joint quantity", the smallest T [s] from which it holds at every sample of ``parts``)] for every
    limit of ``model`` that depends on the duration (the module's table); an empty list when none does.
    Raises NoFeasibleDuration naming the quantity when no duration holds it (the holding torque alone exceeds it).
    ``rms=False`` leaves the RMS out (it does not depend on the samples). ``refine``: each quantity's threshold is
    a smooth function of τ, so its largest sample is replaced by the vertex of the parabola through it and its
    neighbours (never across a jump: ``seg``, :func:`~pickplace_cli.limits.grid.segment_ids` of sorted ``parts``):
    the continuous maximum to ~1e-6 on the fit grid. ``vertices``: a list that receives the τ of each quantity's
    maximum (sampled or refined), the RMS aside.

    The batch of one of :func:`batch_fit_thresholds`: the same code for one move and many."""
    integrals = None
    if rms and _rated(model)[1]:
        integral, ends = model.rms_integrals(parts)
        integrals = (np.asarray(integral)[None], np.asarray(ends)[None])
    fit = _fit_table(model, parts, np.array([0, len(parts.tau)]), integrals, dwell, refine, seg)
    for c in np.flatnonzero(fit.infeasible[0]):  # the first one, in the table's order (motor torques, then RMS)
        raise NoFeasibleDuration(f"time = fit: no duration satisfies {fit.names[c]} (the holding torque alone "
                                 f"exceeds {fit.why[c]})")
    if vertices is not None:
        vertices.extend(fit.where[0].tolist())
    return list(zip(fit.names, fit.thresholds[0].tolist()))


def screened_fit(model, parts, dwell: float = 0.0, seg=None, refine: bool = False) -> tuple[float, str] | None:
    """(T [s], binding "joint quantity"): the fit on the samples of ``parts``, the largest threshold of
    :func:`fit_thresholds` (``seg``, ``refine``: its parabola-vertex refinement); None when no limit depends on the
    duration."""
    found = fit_thresholds(model, parts, dwell, seg=seg, refine=refine)
    if not found:
        return None
    name, t = max(found, key=lambda f: f[1])
    return t, name


def rms_threshold(model, parts, dwell: float = 0.0) -> float:
    """The largest RMS threshold of :func:`fit_thresholds` [s] (0 without a rated torque): exact, sample-free (the
    RMS rows of its table alone: the model's integrals, memoised, and the quartics; ``parts`` may hold the first
    round of the integrals' nodes). Raises NoFeasibleDuration as fit_thresholds does for an RMS row."""
    rated, has = _rated(model)
    if not has:
        return 0.0
    integral, ends = (np.asarray(x, float) for x in model.rms_integrals(parts))
    hold = ends[0] ** 2 + ends[1] ** 2
    ts = rms_thresholds(integral[0, has], integral[1, has], integral[2, has], hold[has], dwell,
                        np.array([rated[i] for i in has]))
    for i, t in zip(has, ts):
        if not np.isfinite(t):
            raise NoFeasibleDuration(f"time = fit: no duration satisfies {model.robot.joint_names[i]} rms motor torque "
                                     f"(the holding torque alone exceeds the rated {rated[i]:g} N·m)")
    return float(ts.max())


#: the screened fit is searched up to this duration [s] (longer: no duration holds the limits)
FIT_CEILING = 1e4
#: the shortest screened fit [s]
FIT_FLOOR = 1e-4


def screen_bounds(T):
    """The screened fit T [s] (a float or an array) held to [``FIT_FLOOR``, …]: NaN where it is not a number or
    beyond ``FIT_CEILING`` (no duration holds the limits), as :func:`~pickplace_cli.timing.fit_screen` and
    :func:`batch_fit_screen` both give it."""
    T = np.asarray(T, float)
    bad = ~(np.isfinite(T) & (T <= FIT_CEILING))
    return np.where(bad, np.nan, np.maximum(T, FIT_FLOOR))


#: under ``time = limits`` the capacity binds when the screened fit lies below T_auto by more than this (relative)
CAPACITY_GAP = 1e-5
#: ... and ``fit_s`` is the screened fit raised by this (relative)
FIT_MARGIN = 1e-7


def capacity_fit_s(t_screen, t_auto):
    """``fit_s`` of ``time = limits`` where the Cartesian capacity binds (the screened fit t_screen [s] clearly below
    the auto duration t_auto [s]: t_screen·(1 + ``CAPACITY_GAP``) < t_auto): t_screen·(1 + ``FIT_MARGIN``); NaN
    where it does not (or t_screen is NaN). Floats or arrays: :func:`~pickplace_cli.timing._limits_duration` for one
    move, the verdict engine for many."""
    t_screen = np.asarray(t_screen, float)
    with np.errstate(invalid="ignore"):
        binds = t_screen * (1.0 + CAPACITY_GAP) < np.asarray(t_auto, float)
    return np.where(binds, t_screen * (1.0 + FIT_MARGIN), np.nan)


# ------------------------------------------------------------------------- the fit for many moves at once
#
# The batch verdict engine (:mod:`pickplace_cli.pipelines.verdicts`) evaluates the model of P moves in one call,
# their samples one move after the other (move k in rows starts[k]:starts[k + 1], sorted in τ within a move).
# :func:`_fit_table` gives every move's thresholds: :func:`threshold_columns` element by element, then maxima and
# arg-maxima per move (exact whatever the order); :func:`fit_thresholds` is its case of one move, so one move's
# numbers and many moves' are the same code. Where the scalar functions raise NoFeasibleDuration the batch ones
# give inf (fit_screen's T: NaN); where a number is NaN the move's result is NaN (the scalar functions' Python
# ``max`` skips a NaN that is not first: such a move is not comparable and is left to the scalar path).


class FitTable(NamedTuple):
    """Every move's thresholds: ``names`` "joint quantity" (Q,), ``thresholds`` (P, Q) [s] (inf where no duration
    holds it), ``infeasible`` (P, Q) bool (the holding torque alone exceeds the limit), ``why`` (Q,) the limit in
    words, ``where`` (P, sampled Q) the τ of every sampled quantity's maximum (refined or sampled)."""

    names: list
    thresholds: np.ndarray
    infeasible: np.ndarray
    why: list
    where: np.ndarray


def _fit_table(model, parts, starts: np.ndarray, rms: tuple | None, dwell: float, refine: bool,
               seg=None) -> FitTable:
    """:class:`FitTable` of P moves (``parts`` stacked, move k in rows starts[k]:starts[k + 1]): every column's
    largest sample (``refine``: the parabola vertex at it, never across a jump ``seg``), and the RMS thresholds from
    ``rms`` = (I (P, 3, n), G_end (P, 2, n)), or none when ``rms`` is None."""
    from ..curves.peaks import parabolic_peak

    starts = np.asarray(starts, dtype=np.intp)
    P = len(starts) - 1
    names, data, overloads = threshold_columns(model, parts)
    if data is None or not len(parts.tau):
        names, out, where = [], np.zeros((P, 0)), np.zeros((P, 0))
    elif refine:
        out, where = parabolic_peak(parts.tau, data, starts, seg)
    elif P == 1:
        top = np.argmax(data, axis=0)
        out, where = data[top, np.arange(data.shape[1])][None], parts.tau[top][None]
    else:
        out, where = np.maximum.reduceat(data, starts[:-1], axis=0), np.zeros((P, 0))
    bad = np.zeros(out.shape, bool)
    why = [""] * len(names)
    for name, limit, over in overloads:
        if name in names:
            c = names.index(name)
            bad[:, c] = np.logical_or.reduceat(over, starts[:-1], axis=0) if len(over) else False
            out[:, c] = np.where(bad[:, c], np.inf, out[:, c])
            why[c] = f"{limit:g} N·m"
    rated, has = _rated(model)
    if rms is not None and has:
        integrals, ends = (np.asarray(x, float) for x in rms)
        hold = ends[:, 0] ** 2 + ends[:, 1] ** 2  # (P, n)
        flat = lambda x: x[:, has].ravel()  # noqa: E731
        ts = rms_thresholds(flat(integrals[:, 0]), flat(integrals[:, 1]), flat(integrals[:, 2]), flat(hold), dwell,
                            np.tile([rated[i] for i in has], P)).reshape(P, len(has))
        names = names + [f"{model.robot.joint_names[i]} rms motor torque" for i in has]
        why = why + [f"the rated {rated[i]:g} N·m" for i in has]
        out = np.concatenate([out, ts], axis=1)
        bad = np.concatenate([bad, ~np.isfinite(ts)], axis=1)
    return FitTable(names, out, bad, why, where)


def batch_fit_thresholds(model, parts, starts: np.ndarray, rms: tuple | None = None,
                         dwell: float = 0.0) -> tuple[list[str], np.ndarray]:
    """:func:`fit_thresholds` of P moves at once: ``parts`` holds their samples one move after the other, move k in
    rows ``starts[k]:starts[k + 1]`` (at least one each); ``rms`` = (I (P, 3, n), G_end (P, 2, n)), every move's
    :meth:`~pickplace_cli.limits.motion.MotionModel.rms_integrals`, or None to leave the RMS out (``rms=False``).
    → (names "joint quantity" in fit_thresholds' order, thresholds (P, len(names)) [s]); inf where fit_thresholds
    raises NoFeasibleDuration."""
    fit = _fit_table(model, parts, starts, rms, dwell, refine=False)
    return fit.names, fit.thresholds


def batch_fit_screen(model, parts, starts: np.ndarray, rms: tuple | None, dwell: float) -> np.ndarray | None:
    """:func:`~pickplace_cli.timing.fit_screen`'s duration for P moves at once (``parts``, ``starts``, ``rms`` as in
    :func:`batch_fit_thresholds`, every move's samples sorted in τ; paths without jumps): every quantity's
    per-sample thresholds refined at the parabola vertex of its largest sample, the largest over quantities and
    the RMS. → (P,) [s], fit_screen's T for each move; NaN where fit_screen raises or a number is NaN; None when
    no limit depends on the duration (fit_screen's None)."""
    fit = _fit_table(model, parts, starts, rms, dwell, refine=True)
    if not fit.names:
        return None
    return screen_bounds(fit.thresholds.max(axis=1))
