"""choose_duration: the duration rule applied to a path — explicit seconds, ``auto`` from the Cartesian capacity
[Li2018, Eq. (24)–(26)], ``fit``, ``limits`` (the default: both) and ``optimal`` (a non-uniform law); the same for a
path planned for its duration (:func:`choose_duration_for`)."""

from __future__ import annotations

import math
from dataclasses import replace

from ..model.errors import TaskError
from ..model.profile import Capacity
from ..model.trajectory import CartesianPath
from .auto import auto_duration
from .rules import Duration, parse_time
from .search import _smallest_feasible, fit_confirm, fit_duration, fit_duration_for, fit_precise, fit_screen


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
    if spec == "auto":  # the fit is only shown beside it: screened where the capacity binds, as time = limits
        return Duration(t_auto, "auto", tv, ta, tj, binding, _fit_beside(model, dwell, t_auto, check, parts))
    t_fit = fit_binding = None
    if model is not None:
        t_fit, fit_binding = fit_duration(model, dwell, start=t_auto, check=check)
    if spec in ("fit", "optimal"):
        if model is None:
            raise TaskError("time = fit: needs the robot model (plan through pickplace_cli.planner.plan)")
        if hold_capacity and (t_fit is None or t_auto > t_fit):  # the capacity binds (or nothing else does)
            return Duration(t_auto, "fit", tv, ta, tj, f"capacity {binding}", t_auto)
        if t_fit is None:
            raise TaskError(
                "time = fit: the profile sets no velocity, acceleration, jerk or motor limit that depends on the "
                "duration; add joint limits or drives, hold the Cartesian capacity (--hold-capacity), or use --time "
                "auto / seconds"
            )
        return Duration(t_fit, "fit", tv, ta, tj, fit_binding, t_fit)  # type: ignore[arg-type]
    return Duration(float(spec), "given", tv, ta, tj, "given", t_fit)


def _fit_beside(model, dwell: float, t_auto: float, check=None, parts=None) -> float | None:
    """The motors' fit [s] shown beside ``time = auto`` (None without a model or when no limit depends on the
    duration). Where the Cartesian capacity binds (the screened fit clearly below ``t_auto``) the screened fit
    (within ~1e-8, as :func:`_limits_duration` shows it), else the fit confirmed by the exact check."""
    if model is None:
        return None
    from .fit import capacity_fit_s

    found = fit_screen(model, dwell, parts)
    if found is None:
        return None
    fit_s = float(capacity_fit_s(found[0], t_auto))
    if fit_s == fit_s:
        return fit_s
    return fit_confirm(model, fit_precise(model, found, dwell), dwell, check=check, parts=found[2])


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
            "duration; add joint limits or drives, hold the Cartesian capacity (--hold-capacity), or use --time auto / "
            "seconds"
        )
    # tv, ta, tj: the capacity bounds of the path planned for t_auto (so Duration.t_auto is the auto time)
    return Duration(t_fit, "fit", tv, ta, tj, fit_binding, t_fit), path


_DEGREE = {3: "cubic", 5: "quintic"}


def choose_optimal(path: CartesianPath, profile, model, dwell: float, model_of,
                   hold_capacity: bool = False, coefficients: int | None = None, check=None,
                   smooth: float | None = None) -> tuple[Duration, CartesianPath, str]:
    """``--time optimal``: the fit of the uniform law, then the optimised non-uniform law on the same path
    (:mod:`pickplace_cli.timing.optimal`), whose duration is fitted again by the continuous check on the
    composed path. Returns (Duration, the path to sample — the composed one, or ``path`` itself when the law
    is not faster than uniform scaling —, a note for the user). ``check``: both fits' exact check
    (:func:`fit_duration`). ``smooth``: the SQP law's smoothing weight (None: the shipped one)."""
    from ..model.errors import PickplaceError
    from .bound import torque_bound
    from .optimal import optimal_law

    try:
        fit = choose_duration(path, profile.capacity, "fit", model=model, dwell=dwell, hold_capacity=hold_capacity,
                              check=check)
    except TaskError as exc:  # the message names the rule the user asked for
        raise TaskError(str(exc).replace("time = fit:", "time = optimal:", 1)) from None
    from . import law_sqp
    from .optimal import LAW_SOLVER, sqp_data

    # the model's terms on the SQP's grids and the bound's, evaluated once for both
    data = sqp_data(model, coefficients) if LAW_SOLVER == "sqp" and law_sqp.available() else None
    try:
        fit = replace(fit, t_bound=torque_bound(model, data=data))
    except ValueError:  # no motor torque or speed limit, or one exceeded at rest: no bound to show
        pass
    law = optimal_law(model, dwell, fit.seconds, coefficients, capacity=profile.capacity if hold_capacity else None,
                      smooth=smooth, data=data)
    # a refined law and the law it was refined from are both fitted and the shorter is kept: never longer than the
    # first law, whatever the optimisers' estimates said
    fitted, why, refined = [], "", ""
    for cand in (law,) if law.first is None else (law, law.first):
        try:
            t_cand, b_cand = fit_duration(model_of(cand.path), dwell, start=max(cand.t_estimate, 1e-3), margin=3e-5,
                                          check=check)
        except PickplaceError as exc:  # this law's composed path cannot be fitted
            why = why or f" ({exc})"
            continue
        if t_cand is None and hold_capacity:  # no timed joint or motor limit: the capacity alone times the law
            tv, ta, tj, cap = auto_duration(cand.path, profile.capacity)
            t_cand, b_cand = max(tv, ta, tj or 0.0), f"capacity {cap}"
        if t_cand is not None:
            fitted.append((t_cand, b_cand, cand))
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
            f"{t_opt / fit.t_auto:.3f} × auto; optimiser: {law.iterations} {law.counted}, {law.message}")
    return (replace(fit, seconds=t_opt, mode="optimal", binding=binding, t_optimal=t_opt,
                    law=f"{_DEGREE.get(law.law.k, 'B-spline')} B-spline b(τ), {composed.parameters['law_coefficients']} "
                        f"coefficients{refined}"),
            composed, note)
