"""``--optimize shape``: the shape search's place in a plan (:func:`optimised_shape`), and with ``--time optimal`` the
chosen shape's time law with and without the SQP's smoothing term, the shorter as written kept.

The smoothing term (``law_sqp.SQP_SMOOTH``) keeps a time-optimal law from following its binding rows with wiggles a
few knots wide, which a reader of the written samples sees as torque-rate peaks (``law_sqp``'s notes); it costs
0.1-0.7 % of the duration. Once the shape is chosen (seconds of search), two more law solves cost little, so the
plan is made twice: with the term (the shipped law) and without it, the latter read back as ``check --strict``
reads it (every peak resolved by the samples, the law slowed until it is: a law without the term must not leave
the file's peaks undecided). The shorter plan that holds every limit as written is kept; the law's note says which.
On the Adept cycle with 120 law coefficients the law without the term is kept: 1.0096 × the free-path minimum with
the capacity held (1.0103 × with the term), 1.0087 × with the motors alone (1.0095 ×),
``python bench/bench_shape_law_coefficients.py --coefficients 120``.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Callable


def shortest_as_written(planned: Callable, options):
    """``planned(options)`` → Plan, run with the shipped smoothing (``options``) and without the term (weight 0,
    read as ``check --strict`` reads it); the shorter of those whose report holds every limit (the shipped one when
    neither does or they tie). The other's duration is named in the kept law's note."""
    from ..model.errors import PickplaceError

    shipped = planned(options)
    try:
        bare = planned(replace(options, law_smoothing=0.0, strict=True))
    except PickplaceError:  # (strict: the written tool columns refused at a low rate) the shipped plan stands
        return shipped
    if bare.report.exit_code() != 0 or not (bare.duration.seconds < shipped.duration.seconds or not shipped.report.ok):
        return replace(shipped, duration=replace(shipped.duration, law=_said(
            shipped.duration.law, f"without the smoothing term {bare.duration.seconds:.6g} s as written: not shorter"
            if bare.report.exit_code() == 0 else "without the smoothing term its written samples do not hold")))
    said = f"without the smoothing term: shorter as written than with it ({shipped.duration.seconds:.6g} s)"
    report = replace(bare.report, strict=options.strict)
    return replace(bare, duration=replace(bare.duration, law=_said(bare.duration.law, said)), report=report)


def _said(law: str | None, note: str) -> str:
    return note if not law else f"{law}; {note}"


def optimised_shape(task, profile, options, motion_model) -> tuple:
    """``--optimize shape``: the task with the chosen η, the options with the chosen k1, k2
    (:func:`pickplace_cli.timing.shape.optimise_shape`), and what the search found for the path parameters
    (``shape``: the chosen shape, its screened duration, the table's shape and its exact fit duration); ``options``
    a PlanOptions, ``motion_model(path, profile)`` the planner's model of a path."""
    from ..model.errors import PickplaceError, TaskError, UsageError
    from ..paths import Method, plan_path
    from ..paths.turn import turned
    from . import choose_duration
    from . import shape as shape_module
    from .shape import optimise_shape

    if Method(options.method) is not Method.bspline:
        raise UsageError(f"--optimize shape: method {Method(options.method).value} has no shape parameters to choose; "
                         "it chooses k1, k2, η of --method bspline")
    if options.time not in ("fit", "optimal", "limits"):
        raise UsageError(f"--optimize shape minimises the fitted duration: use it with time limits, fit or optimal "
                         f"(not {options.time})")
    hold = options.hold_capacity or options.time == "limits"
    chosen = ("k1", "k2", "arch", "k3", "k4", "mid", "eta_down", "mid_x")  # the family's shape parameters
    given = {k for k, v in options.method_params.items() if v is not None and k in chosen}
    if given:
        raise UsageError(f"--optimize shape chooses k1, k2, the arch and k3, k4, mid itself and searches Li's placement "
                         f"of the via points (eta_down = η, mid_x = 1/2): drop --{'/--'.join(sorted(given))}")
    base = {k: v for k, v in options.method_params.items() if v is not None and k not in chosen}

    def model_of(p):
        return motion_model(turned(p, task, options.turn_during), profile)

    table_shape, t_table, ref = None, None, None
    try:
        ref = plan_path(task, Method.bspline, **base)
    except PickplaceError:  # outside the table: search without it
        pass
    if ref is not None:
        table_shape = (float(ref.parameters["k1"]), float(ref.parameters["k2"]), float(task.eta))
        # the table shape's fit; a profile with no duration-dependent limit is the same error as --time fit's
        try:
            t_table = choose_duration(ref, profile.capacity, "limits" if options.time == "limits" else "fit",
                                      model=model_of(ref), dwell=profile.planning.dwell, hold_capacity=hold).seconds
        except TaskError as exc:  # the message names the rule the user asked for, and the option
            raise TaskError("--optimize shape: " + str(exc).replace("time = fit:", f"time = {options.time}:", 1)) from None
    found = optimise_shape(task, profile, model_of, eta_fixed=task.eta if options.hold_eta else None,
                           table_shape=table_shape, capacity=profile.capacity if hold else None)
    if options.time == "optimal":  # the screen ranks by the uniform law: the law judges the winner and the table's
        found = shape_module.judge_by_law(task, profile, found, model_of, hold,
                                           options.shape_law_evals or shape_module.LAW_POLISH_EVALS)
    shaped = replace(task, eta=found.eta)
    info = {"k1": found.k1, "k2": found.k2, "eta": found.eta, "arch": found.arch, "k3": found.k3, "k4": found.k4,
            "mid": found.mid, "screened_fit_s": found.t_screen,
            "shapes_screened": found.evaluations, "note": found.note,
            "table": None if table_shape is None else {"k1": table_shape[0], "k2": table_shape[1],
                                                        "eta": table_shape[2], "fit_s": t_table}}
    arch = {"arch": found.arch} if found.arch else {}  # 0 and None: Li's path, planned as without them
    arch.update({} if found.k3 is None else {"k3": found.k3, "k4": found.k4, "mid": found.mid})
    return shaped, replace(options, method_params={**base, "k1": found.k1, "k2": found.k2, **arch}, shape=False), info
