"""``--time fit``: the smallest duration at which every joint and motor limit holds, screened in closed form on
the fit grid (:mod:`pickplace_cli.timing.fit`), root-found and confirmed by the continuous check; the same search
for a path that depends on the duration (:func:`fit_duration_for`)."""

from __future__ import annotations

import numpy as np


def _worst_utilisation(model, dwell: float = 0.0, tau=None):
    """(worst, parts) for a fixed ``model``: worst(T) = (max utilisation − 1 over every T-dependent limit at
    duration T, its name), from one evaluation of the model (``parts``) on ``tau`` (default: the fit grid);
    None when no limit depends on T."""
    import numpy as np

    from ..curves.peaks import parabolic_peak
    from ..limits.grid import fit_grid, interior_jumps, segment_ids

    # 1,001 uniform points and the check's own extra points (knots, points per span, both sides of every
    # jump); the parabolic estimate never spans a jump, as in the check; the RMS is the model's exact integral
    path = model.path
    if tau is None:
        tau = fit_grid(path.breakpoints, path.jumps)
    seg = segment_ids(tau, interior_jumps(path.breakpoints, path.jumps))
    parts = model.parts(tau)
    meta, _ = model.columns(parts, 1.0)
    timed = [c for c, m in enumerate(meta) if not (m[1].startswith("position") or m[4] == "reach")]
    limits = np.array([meta[c][3] for c in timed])
    rated = np.array([s.drive.rated_torque if s.drive and s.drive.rated_torque else np.inf for s in model.specs])
    has_rated = np.isfinite(rated)
    if not timed and not has_rated.any():
        return None

    def worst(T: float) -> tuple[float, str]:
        m, data = model.columns(parts, T)
        if timed:
            d = data[:, timed]
            util = parabolic_peak(tau, d, seg=seg)[0] / limits
        else:
            util = np.zeros(0)
        rms = (model.rms_motor_torque(T, dwell, parts) / rated)[has_rated] if has_rated.any() else np.zeros(0)
        names = [f"{m[c][0]} {m[c][1]}" for c in timed] + [
            f"{n} rms motor torque" for n, h in zip(model.robot.joint_names, has_rated) if h
        ]
        allu = np.concatenate([util, rms])
        k = int(np.argmax(allu)) if allu.size else 0
        return (float(allu[k]) - 1.0 if allu.size else -1.0), (names[k] if allu.size else "none")

    return worst, parts


def screened_root(worst, start: float = 0.1, rtol: float = 1e-10) -> float:
    """The smallest T [s] with worst(T)[0] ≤ 0 on the screening grid: doubled up from ``start`` until feasible,
    scanned down in steps of 0.85 while feasible, then the crossing root-found (brentq, relative ``rtol``)."""
    from scipy.optimize import brentq

    from ..model.errors import NoFeasibleDuration

    hi = max(start, 1e-3)
    while worst(hi)[0] > 0:
        hi *= 2.0
        if hi > 1e4:
            raise NoFeasibleDuration(
                f"time = fit: no duration up to 1e4 s satisfies {worst(hi)[1]} (the holding torque alone exceeds it?)"
            )
    lo = hi
    while True:
        cand = lo * 0.85
        if cand < 1e-4 or worst(cand)[0] > 0:
            break
        lo = cand
    if lo * 0.85 < 1e-4:
        T = lo
    else:
        T = brentq(lambda x: worst(x)[0], lo * 0.85, lo, xtol=1e-12, rtol=rtol)
    return float(T)


def fit_duration(model, dwell: float = 0.0, start: float = 0.1, margin: float = 1e-7,
                 check=None) -> tuple[float | None, str | None]:
    """Smallest T [s] such that every T-dependent limit holds at T and at every longer duration.

    Every timed quantity is a closed-form function of T at each sample (:mod:`pickplace_cli.timing.fit`), so
    the smallest T at which the samples of the fit grid hold is solved exactly, sample by sample (velocity-type
    limits scale as 1/T^k; the peak motor torque |A_m s + G_m| is convex in s = 1/T², its feasible set an
    interval containing s = 0 when the holding torque fits; the torque rate is a cubic in 1/T; the RMS a
    quartic in T). Position, singularity and workcell limits do not depend on T and are not fitted (the limit
    report shows them). The result is nudged up until the exact (refined) check passes, starting ``margin``
    (relative) above the sampled root: 1e-7 for a method's own path; a composed time law's torque rate peaks
    sharply near the ends, where the sampled peak sits up to ~1e-5 under the continuous one (each failed
    check costs a second one).
    ``check(model, T)`` → LimitReport: the exact check to use (default: :func:`check_limits` on the fit's
    grid); the planner passes its own final check, on the output samples' grid, and keeps the last report,
    which is then the plan's own when the fit's T is the plan's.
    Returns (T, the binding quantity "joint quantity"), or (None, None) when no limit depends on T.
    """
    found = fit_screen(model, dwell)
    if found is None:
        return None, None
    return fit_confirm(model, fit_precise(model, found, dwell), dwell, margin, check, found[2]), found[1]


def fit_precise(model, screen: tuple, dwell: float = 0.0) -> float:
    """The screened fit ``screen`` (:func:`fit_screen`) solved again in closed form on the model itself at the τ of
    every quantity's maximum (one small evaluation of the model): the parabola's value estimate can sit a little
    above or below the continuous peak, the model's value at its vertex sits at or below it, ~1e-8 off. The RMS
    thresholds are exact already."""
    from .fit import fit_thresholds, rms_threshold

    T, _, parts, _ = screen
    where: list = []
    fit_thresholds(model, parts, dwell, rms=False, seg=screen[3], refine=True, vertices=where)
    precise = max(_solve_at(model, np.array(where), dwell), rms_threshold(model, parts, dwell))
    return precise if precise > 0 else T


def fit_screen(model, dwell: float = 0.0, parts=None) -> tuple[float, str, object] | None:
    """The fit on the model's fit grid, in closed form (:mod:`pickplace_cli.timing.fit`), each quantity's largest
    per-sample threshold refined to the vertex of the parabola through it and its neighbours: (T [s], binding "joint
    quantity", the Parts on the grid); None when no limit depends on the duration. Within ~1e-8 of the continuous fit; :func:`fit_confirm`
    confirms it by the exact check. ``parts``: the model on another grid holding the check's extra points
    (e.g. the plan's first samples), used instead of the fit grid."""
    from ..limits.grid import fit_grid, interior_jumps, segment_ids
    from .fit import screen_bounds, screened_fit

    path = model.path
    parts = model.parts(fit_grid(path.breakpoints, path.jumps)) if parts is None else parts.sorted()
    seg = segment_ids(parts.tau, interior_jumps(path.breakpoints, path.jumps))
    found = screened_fit(model, parts, dwell, seg, refine=True)
    if found is None:
        return None
    T, binding = found
    T = float(screen_bounds(T))
    if T != T:
        from ..model.errors import NoFeasibleDuration

        raise NoFeasibleDuration(f"time = fit: no duration up to 1e4 s satisfies {binding}")
    return T, binding, parts, seg


def fit_confirm(model, T: float, dwell: float = 0.0, margin: float = 1e-7, check=None, parts=None) -> float:
    """T [s] from :func:`fit_screen`, ``margin`` (relative) above, nudged up until the exact check (``check(model,
    T)``, default :func:`check_limits` on ``parts``) finds no timed limit exceeded."""
    from ..limits.check import check_limits

    T *= 1.0 + margin
    for _ in range(10):
        rep = check_limits(model, T, parts=parts, dwell=dwell) if check is None else check(model, T)
        bad = [r for r in rep.violations if r.kind != "reach"]
        if not bad:
            break
        # re-solve at the continuous peaks the check found (once more where a peak moves with T); where that does
        # not move T, every timed quantity but the RMS falls at least as 1/T, and the RMS is solved exactly: T·u
        again = _solve_at(model, np.array([r.t_peak / T for r in bad if r.t_peak is not None]), dwell)
        T = again * (1.0 + margin) if again > T else T * max(r.utilisation for r in bad) * (1.0 + 1e-9)
    return float(T)


def _solve_at(model, tau, dwell: float) -> float:
    """The closed-form fit (:func:`~pickplace_cli.timing.fit.fit_thresholds`, without the RMS, which is exact
    already) on the model evaluated at the points ``tau`` only; 0 when there are none."""
    import numpy as np

    from .fit import fit_thresholds

    tau = np.clip(np.unique(np.asarray(tau, float)), 0.0, 1.0)
    if not tau.size:
        return 0.0
    found = fit_thresholds(model, model.parts(tau), dwell, rms=False)
    return max((t for _, t in found), default=0.0)


# ------------------------------------------------------------------ paths that depend on the duration
#
# A method such as bspline-vel (conveyor tracking, Yang 2022) builds a different normalised path for every
# duration T (its end velocities enter as v·T and its shape is re-optimised at T), so the exact T-scaling
# used above does not hold: each trial duration needs its own path. ``factory(T)`` gives that path.


def _smallest_feasible(g, start: float, factor: float, rtol: float, what: str) -> float:
    """Smallest T with g(T) ≤ 0 reached by scanning from ``start`` (down while feasible, up while not) in
    steps of ``factor`` and root-finding the crossing (brentq): every scanned T above it is feasible."""
    from scipy.optimize import brentq

    from ..model.errors import NoFeasibleDuration

    T = float(start)
    if g(T) > 0:
        while g(T) > 0:
            lo, T = T, T / factor
            if T > 1e4:
                raise NoFeasibleDuration(f"time = {what}: no duration up to 1e4 s satisfies the limits")
        hi = T
    else:
        hi = T
        while True:
            lo = hi * factor
            if lo < 1e-4:
                return hi
            if g(lo) > 0:
                break
            hi = lo
    return float(brentq(g, lo, hi, rtol=rtol, xtol=1e-12))


def fit_duration_for(factory, model_of, dwell: float = 0.0, start: float = 0.1, rtol: float = 1e-7):
    """(T, binding, path): the smallest T [s] at which every T-dependent limit holds on the path planned
    for T [Yang2022, Eq. (38)] (see :func:`choose_duration_for`); (None, None, path) when no limit depends
    on T. Each trial T plans its own path and evaluates the model once on it."""
    from ..limits.check import check_limits

    def worst(T: float):
        found = _worst_utilisation(model_of(factory(T)), dwell)
        return None if found is None else found[0](T)

    if worst(start) is None:
        return None, None, factory(start)
    T = _smallest_feasible(lambda x: worst(x)[0], start, 0.85, rtol, "fit")
    # sampled peaks sit a hair under the continuous ones: nudge up until the exact check passes
    T *= 1.0 + 1e-7
    for _ in range(10):
        model = model_of(factory(T))
        rep = check_limits(model, T, dwell=dwell)
        bad = [r for r in rep.violations if r.kind != "reach"]
        if not bad:
            break
        T *= max(r.utilisation for r in bad) * (1.0 + 1e-9)
    binding = worst(T * (1 - 1e-9))[1]
    return float(T), binding, factory(T)
