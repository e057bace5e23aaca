"""choose_duration: explicit seconds, or ``auto`` from the Cartesian capacity [Li2018, Eq. (24)–(26)]."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
import numpy as np

from ..model.errors import TaskError
from ..model.profile import Capacity
from ..model.trajectory import CartesianPath


@dataclass(frozen=True)
class Duration:
    """The chosen duration T [s] and how it was chosen.

    Attributes
    ----------
    seconds : float
        The duration T [s].
    mode : str
        The rule that chose it: ``limits``, ``auto``, ``fit``, ``optimal`` or ``given``.
    t_velocity, t_acceleration, t_jerk : float
        The three bounds of Eq. (26) [s] (``t_jerk`` None without a jerk capacity); ``t_auto`` is their maximum.
    binding : str
        What set T (a capacity, or a joint's quantity).
    t_fit : float or None
        The smallest duration at which every joint and motor limit holds [s], when computed.
    t_optimal : float or None
        ``optimal``: the duration of the non-uniform time law [s].
    law : str or None
        ``optimal``: what the optimiser said.
    t_bound : float or None
        ``optimal``: the lower bound under peak motor torque and speed alone [s].

    ``auto`` is Eq. (26) extended by jerk: T = max(v̂/[v], √(â/[a]), ∛(ĵ/[j])) where v̂, â, ĵ are the exact
    peaks of ‖d^k p/dτ^k‖ of the path with T = 1 (for a symmetric move v̂ = b·v_max etc.). ``binding`` names
    the capacity that sets T. ``t_velocity``, ``t_acceleration``, ``t_jerk`` are the three bounds (s).
    """

    seconds: float
    mode: str
    t_velocity: float
    t_acceleration: float
    t_jerk: float | None
    binding: str
    t_fit: float | None = None  # smallest duration at which every motor/joint limit holds (when computed)
    #: --time optimal: the duration of the non-uniform law (None otherwise) and what the optimiser said
    t_optimal: float | None = None
    law: str | None = None
    #: --time optimal: the lower bound of the path, its time-optimal traversal under peak motor torque and speed
    #: alone (:mod:`pickplace_cli.timing.bound`; None otherwise)
    t_bound: float | None = None

    @property
    def t_auto(self) -> float:
        return max(self.t_velocity, self.t_acceleration, self.t_jerk or 0.0)

    def as_dict(self) -> dict:
        return {
            "duration_s": self.seconds,
            "mode": self.mode,
            "auto_s": self.t_auto,
            "fit_s": self.t_fit,
            "auto_bounds_s": {"velocity": self.t_velocity, "acceleration": self.t_acceleration, "jerk": self.t_jerk},
            "binding": self.binding,
            "optimal_s": self.t_optimal,
            "time_law": self.law or "uniform",
            "torque_bound_s": self.t_bound,
        }


def auto_duration(path: CartesianPath, capacity: Capacity) -> tuple[float, float, float | None, str]:
    """(T_v, T_a, T_j, binding) of Eq. (26) (+ jerk when the profile gives [j])."""
    v, a, j = path.peaks
    tv = v / capacity.velocity
    ta = math.sqrt(a / capacity.acceleration)
    tj = (j / capacity.jerk) ** (1.0 / 3.0) if capacity.jerk else None
    bounds = {"velocity": tv, "acceleration": ta}
    if tj is not None:
        bounds["jerk"] = tj
    binding = max(bounds, key=bounds.__getitem__)
    return tv, ta, tj, binding


#: the shortest duration accepted [s] (with moves up to :data:`~pickplace_cli.model.task.MAX_METRES`, the limit
#: check's numbers stay finite)
MIN_SECONDS = 1e-6


#: the duration rules by name (``--time``); a number is a duration in seconds
TIME_RULES = ("limits", "auto", "fit", "optimal")


def parse_time(spec: str | float) -> str | float:
    """``limits`` | ``auto`` | ``fit`` | ``optimal`` (any case, surrounding spaces ignored) | seconds (> 0, finite) →
    the spec; TaskError naming the rule otherwise (with the nearest rule name for a near miss)."""
    if isinstance(spec, str):
        s = spec.strip().lower()
        if s in TIME_RULES:
            return s
        try:
            value = float(s)
        except ValueError:
            import difflib

            near = difflib.get_close_matches(s, TIME_RULES, n=1, cutoff=0.6)
            hint = f"did you mean '{near[0]}'? " if near else ""
            raise TaskError(f"time = {spec!r}: {hint}give 'limits', 'auto', 'fit', 'optimal' or a duration in seconds "
                            "(e.g. 0.25)") from None
    else:
        value = float(spec)
    if not (math.isfinite(value) and value > 0):
        raise TaskError(f"time = {spec!r}: a duration must be a finite number of seconds > 0")
    if value < MIN_SECONDS:
        raise TaskError(f"time = {spec!r}: a duration must be at least {MIN_SECONDS:g} s (no robot moves faster; "
                        "shorter ones overflow the limit check's numbers)")
    return value


def choose_duration(
    path: CartesianPath, capacity: Capacity, spec: str | float = "auto", model=None, dwell: float = 0.0,
    hold_capacity: bool = False, check=None, parts=None,
) -> Duration:
    """Duration of the move: explicit seconds, ``auto`` (Eq. 26), or ``fit`` (needs ``model``, a
    :class:`~pickplace_cli.limits.motion.MotionModel`): the smallest T at which every limit holds.
    ``hold_capacity``: ``fit`` also holds the Cartesian capacity (T ≥ auto; the peaks scale exactly).
    ``check``: the fit's exact check (see :func:`fit_duration`)."""
    spec = parse_time(spec)
    tv, ta, tj, binding = auto_duration(path, capacity)
    t_auto = max(tv, ta, tj or 0.0)
    if not math.isfinite(t_auto):  # a degenerate path (λ = b/h far outside what the method's closed forms handle)
        lam = path.parameters.get("lambda") if isinstance(path.parameters, dict) else None
        where = f" (λ = b/h = {lam:.3g})" if isinstance(lam, float) else ""
        raise TaskError(f"method {path.method}: this move's path{where} has no finite peak speed or acceleration, so "
                        "no duration can be chosen; the move is too flat or too tall for this method: change the "
                        "height, or use the default method bspline")
    if spec == "limits":
        if model is None:
            raise TaskError("time = limits: needs the robot model (plan through pickplace_cli.planner.plan)")
        return _limits_duration(model, dwell, (tv, ta, tj, binding), check, parts)
    t_fit = fit_binding = None
    if model is not None:
        t_fit, fit_binding = fit_duration(model, dwell, start=t_auto, check=check)
    if spec == "auto":
        return Duration(t_auto, "auto", tv, ta, tj, binding, t_fit)
    if spec in ("fit", "optimal"):
        if model is None:
            raise TaskError("time = fit: needs the robot model (plan through pickplace_cli.planner.plan)")
        if hold_capacity and (t_fit is None or t_auto > t_fit):  # the capacity binds (or nothing else does)
            return Duration(t_auto, "fit", tv, ta, tj, f"capacity {binding}", t_auto)
        if t_fit is None:
            raise TaskError(
                "time = fit: the profile sets no velocity, acceleration, jerk or motor limit that depends on the "
                "duration; add joint limits or drives, or use --time auto / seconds"
            )
        return Duration(t_fit, "fit", tv, ta, tj, fit_binding, t_fit)  # type: ignore[arg-type]
    return Duration(float(spec), "given", tv, ta, tj, "given", t_fit)


def _limits_duration(model, dwell: float, auto: tuple, check=None, parts=None) -> Duration:
    """``--time limits`` (the default): the smallest T at which every limit of the profile holds, the joint and
    motor limits (the fit) and the Cartesian capacity (auto, exact: the path's peaks scale as 1/T^k). When the
    capacity binds, the fit is only screened (within ~1e-8, :func:`fit_screen`): the plan's final check at the
    longer auto duration is the exact one. ``Duration.t_fit`` is the motors' fit alone, shown next to it.
    ``parts``: the model already evaluated on a grid that holds the check's points (the plan's first samples),
    screened instead of the fit grid."""
    tv, ta, tj, binding = auto
    t_auto = max(tv, ta, tj or 0.0)
    found = fit_screen(model, dwell, parts)
    if found is None:  # no joint or motor limit depends on the duration: the capacity alone decides
        return Duration(t_auto, "limits", tv, ta, tj, f"capacity {binding}", None)
    from .fit import capacity_fit_s

    t_screen, fit_binding, parts, _ = found
    fit_s = float(capacity_fit_s(t_screen, t_auto))
    if fit_s == fit_s:  # the capacity binds: the fit is only screened
        return Duration(t_auto, "limits", tv, ta, tj, f"capacity {binding}", fit_s)
    t_fit = fit_confirm(model, fit_precise(model, found, dwell), dwell, check=check, parts=parts)
    if t_auto > t_fit:
        return Duration(t_auto, "limits", tv, ta, tj, f"capacity {binding}", t_fit)
    return Duration(t_fit, "limits", tv, ta, tj, fit_binding, t_fit)


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


def choose_duration_for(
    factory, capacity: Capacity, spec: str | float = "auto", model_of=None, dwell: float = 0.0, start: float | None = None
) -> tuple[Duration, CartesianPath]:
    """Duration and path for a method whose path depends on the duration: ``factory(T)`` → CartesianPath
    planned for T [s]. Returns (Duration, the path at that duration).

    * seconds: the path at T; the auto bounds shown are those of that path.
    * ``auto``: the smallest T at which the path planned for T meets the capacity, T ≥ max(v̂(T)/[v],
      √(â(T)/[a]), ∛(ĵ(T)/[j])) (Eq. 26 with the shape at T); a few fixed-point steps give the start.
    * ``fit`` (needs ``model_of(path)`` → MotionModel): the smallest T at which every joint and motor limit
      holds with the shape optimal at T [Yang2022, Eq. (38)]. Scanned down from ``start`` (default: auto)
      and root-found; the shape changes with T, so feasibility is established at every scanned T and at
      the result (verified by the exact check), not proven for all longer T as for a fixed path.
    """
    spec = parse_time(spec)

    def bounds(T: float):
        path = factory(T)
        return path, auto_duration(path, capacity)

    if isinstance(spec, float):
        path, (tv, ta, tj, _) = bounds(spec)
        return Duration(spec, "given", tv, ta, tj, "given", None), path

    def excess(T: float) -> float:
        tv, ta, tj, _ = bounds(T)[1]
        return max(tv, ta, tj or 0.0) / T - 1.0

    if start is None:
        T = 0.2
        for _ in range(3):  # fixed-point steps T ← T_auto(path(T)): a good start for the scan
            tv, ta, tj, _ = bounds(T)[1]
            T = max(tv, ta, tj or 0.0)
        t_auto = _smallest_feasible(excess, T * (1 + 1e-3), 0.95, 1e-8, "auto")
        for _ in range(20):  # land on the feasible side of the root
            if excess(t_auto) <= 1e-12:
                break
            t_auto *= 1 + max(excess(t_auto), 1e-12)
    else:
        t_auto = float(start)
    if spec in ("auto", "limits") and start is None:
        final = getattr(factory, "final", None)  # a factory that continued from a nearby T confirms it
        if final is not None and not final(t_auto)[1]:
            return choose_duration_for(factory, capacity, spec, model_of, dwell, start)  # a better branch
    path, (tv, ta, tj, binding) = bounds(t_auto)
    if spec == "auto":
        return Duration(t_auto, "auto", tv, ta, tj, binding, None), path
    if model_of is None:
        raise TaskError(f"time = {spec}: needs the robot model (plan through pickplace_cli.planner.plan)")
    t_fit, fit_binding, fpath = fit_duration_for(factory, model_of, dwell, start=t_auto)
    final = getattr(factory, "final", None)
    if final is not None and t_fit is not None and not final(t_fit)[1]:  # (a final check needs a duration)
        t_fit, fit_binding, fpath = fit_duration_for(factory, model_of, dwell, start=t_auto)
    if spec == "limits":  # the fit and the capacity: the longer of the two, the capacity confirmed at a longer fit
        if t_fit is None or t_fit <= t_auto:
            return Duration(t_auto, "limits", tv, ta, tj, f"capacity {binding}", t_fit), path
        T = t_fit
        for _ in range(20):
            ex = excess(T)
            if ex <= 1e-12:
                break
            T *= 1.0 + ex + 1e-12
        if T == t_fit:
            return Duration(T, "limits", tv, ta, tj, fit_binding, t_fit), fpath
        cpath, (_, _, _, cap) = bounds(T)
        return Duration(T, "limits", tv, ta, tj, f"capacity {cap}", t_fit), cpath
    path = fpath
    if t_fit is None:
        raise TaskError(
            "time = fit: the profile sets no velocity, acceleration, jerk or motor limit that depends on the "
            "duration; add joint limits or drives, or use --time auto / seconds"
        )
    # tv, ta, tj: the capacity bounds of the path planned for t_auto (so Duration.t_auto is the auto time)
    return Duration(t_fit, "fit", tv, ta, tj, fit_binding, t_fit), path


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


def choose_optimal(path: CartesianPath, profile, model, dwell: float, model_of,
                   hold_capacity: bool = False, coefficients: int | None = None, check=None) -> tuple[Duration, CartesianPath, str]:
    """``--time optimal``: the fit of the uniform law, then the optimised non-uniform law on the same path
    (:mod:`pickplace_cli.timing.optimal`), whose duration is fitted again by the continuous check on the
    composed path. Returns (Duration, the path to sample — the composed one, or ``path`` itself when the law
    is not faster than uniform scaling —, a note for the user). ``check``: both fits' exact check
    (:func:`fit_duration`)."""
    from ..model.errors import PickplaceError
    from .bound import torque_bound
    from .optimal import optimal_law

    fit = choose_duration(path, profile.capacity, "fit", model=model, dwell=dwell, hold_capacity=hold_capacity,
                          check=check)
    try:
        fit = replace(fit, t_bound=torque_bound(model))
    except ValueError:  # no motor torque or speed limit, or one exceeded at rest: no bound to show
        pass
    law = optimal_law(model, dwell, fit.seconds, coefficients, capacity=profile.capacity if hold_capacity else None)
    # a refined law and the law it was refined from are both fitted and the shorter is kept: never longer than the
    # first law, whatever the optimisers' estimates said
    fitted, why, refined = [], "", ""
    for cand in (law,) if law.first is None else (law, law.first):
        try:
            fitted.append((*fit_duration(model_of(cand.path), dwell, start=max(cand.t_estimate, 1e-3), margin=3e-5,
                                         check=check), cand))
        except PickplaceError as exc:  # this law's composed path cannot be fitted
            why = why or f" ({exc})"
    t_opt = binding = None
    if fitted:
        t_opt, binding, best = min(fitted, key=lambda f: f[0])
        why = ""
        if law.first is not None:
            n, n0 = law.law.c.size, law.first.law.c.size
            refined = (f" (refined from {n0})" if best is law else
                       f" (the {n}-coefficient refinement fitted longer: this {n0}-coefficient law is kept)")
        law = replace(best, iterations=law.iterations,
                      message=law.message if best is law else f"{law.message}; the refinement fitted longer: not used")
    composed = law.path
    if t_opt is not None and hold_capacity:  # the composed path's exact Cartesian peaks scale as 1/T^k
        tv, ta, tj, cap = auto_duration(composed, profile.capacity)
        if max(tv, ta, tj or 0.0) > t_opt:
            t_opt, binding = max(tv, ta, tj or 0.0), f"capacity {cap}"
    if t_opt is None or not t_opt < fit.seconds * (1 - 1e-6):
        got = f"{t_opt:.6g} s" if t_opt is not None else "no duration"
        note = (f"time = optimal: the optimised law ({got}{why}; {law.message}) is not faster than uniform "
                f"scaling ({fit.seconds:.6g} s); the uniform law of --time fit is used")
        return replace(fit, mode="optimal", t_optimal=fit.seconds, law="uniform (fallback)"), path, note
    note = (f"time = optimal: {t_opt:.4f} s = {t_opt / fit.seconds:.3f} × fit ({fit.seconds:.4f} s), "
            f"{t_opt / fit.t_auto:.3f} × auto; optimiser: {law.iterations} SLSQP iterations, {law.message}")
    return (replace(fit, seconds=t_opt, mode="optimal", binding=binding, t_optimal=t_opt,
                    law=f"cubic B-spline b(τ), {composed.parameters['law_coefficients']} coefficients{refined}"),
            composed, note)
