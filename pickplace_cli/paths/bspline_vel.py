"""Velocity-constrained quintic B-spline for conveyor tracking [Yang2022, Sec. 2.2–2.3]: the method.

The gripper leaves the pick point with the pick conveyor's velocity v0 and arrives at the place point with
the place conveyor's velocity v1 (accelerations and jerks zero at both ends, Eq. 24), on the quintic B-spline
of Eq. (29) whose seven shape parameters p = (τ6, τ7, τ9, τ10, λ1, λ2, λ3) maximise F of Eq. (37).

Its seams, one module each:

* the problem (path points, knots, dimensionless groups, batched evaluation, exact peaks):
  :mod:`pickplace_cli.curves.vel_problem`;
* the optimiser (multi-start, seeded): :mod:`pickplace_cli.lookup.vel_solver`, its SLSQP stages in
  epigraph form: :mod:`pickplace_cli.lookup.vel_slsqp`;
* the table of optima over the groups: :mod:`pickplace_cli.lookup.vel_table`;
* this module: the optimum for a task (table, seeded or exact), the path for a duration
  (:func:`plan_bspline_vel`), and T → path (:class:`PathFactory`) for duration selection.

**The path depends on the duration T.** In normalised time τ = t/T the end velocity is v·T and the offsets
are v·λ·T, so a path is built *for* a given T and is only valid when run in that time.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

import numpy as np

from ..curves.vel_problem import (  # noqa: F401 (re-exported: the method's public names)
    PAPER_INITIAL,
    PARAM_NAMES,
    VelProblem,
    VelSettings,
    exact_peaks,
    groups,
    make_problem,
    spline_of,
    task_from_groups,
)
from ..curves.bspline import norm_peaks
from ..lookup.vel_solver import VelResult, solve, solve_seeded  # noqa: F401 (re-exported)
from ..model.errors import TaskError
from ..model.task import Task
from ..model.trajectory import CartesianPath

# ------------------------------------------------------------------------------------------ the method


SOLVERS = ("exact", "seeded", "table")


def best_of(results: list[VelResult]) -> VelResult:
    """The best of several solves of one problem: F recomputed with the lowest a_min and j_min any of
    them found (each is a local minimum of a multimodal stage), then the largest F wins."""
    a_min = min(r.a_min for r in results)
    j_min = min(r.j_min for r in results)
    best = max(results, key=lambda r: a_min / r.a_max + j_min / r.j_max)
    pa = min(results, key=lambda r: r.a_min).params_a
    pj = min(results, key=lambda r: r.j_min).params_j
    return replace(best, a_min=a_min, j_min=j_min, F=a_min / best.a_max + j_min / best.j_max, params_a=pa,
                   params_j=pj, evaluations=sum(r.evaluations for r in results))


def optimum(task: Task, duration: float, solver: str = "exact", table: str | None = None,
            settings: VelSettings | None = None) -> tuple[tuple[float, ...], VelResult | None, str]:
    """(params, the solve's result or None, source) of Eq. (37) for ``task`` in ``duration`` seconds.

    ``solver``:

    * "exact" (default) — where the table applies, :func:`solve_seeded` with its check: the three stages
      started from the table's seeds (interpolated and corner optima of the query's cell, for each stage)
      and from the multi-start's starts (screened, polished when better), at least as good as the
      multi-start on the held-out moves (README). Elsewhere the global multi-start (:func:`solve`).
    * "seeded" — only the table's seeds, one SLSQP run per stage (F may also screen the interpolated
      seed): faster, exact to the optimum of its basin.
    * "table" — the table's answer alone (instant, approximate: README).

    Where the table does not apply (other η, unequal heights, vertical velocities, outside its range, no
    table), "exact" and "seeded" are the multi-start alone. A ``table`` given that cannot be read as a conveyor table
    (missing, foreign, malformed) is refused (TableError), whatever the solver."""
    settings = settings or VelSettings()
    prob = make_problem(task, duration)
    if solver not in SOLVERS:
        raise TaskError(f"solver = {solver!r}: choose one of {', '.join(SOLVERS)}")
    from ..model.errors import TableError
    from ..lookup.vel_table import load_vel_table

    try:
        tab = load_vel_table(table)
    except TableError:
        if solver == "table" or table is not None:  # a table the user named and that cannot be read: refused
            raise
        tab = None  # (the shipped table missing: the multi-start alone)
    try:
        if tab is None:
            raise TableError("no conveyor table")
        seeds = tab.seeds(task, duration)
    except TableError as exc:
        if solver == "table":
            raise
        res = solve(prob, settings)
        return res.params, res, f"exact (multi-start; table not used: {exc})"
    if solver == "table":
        return tab.lookup(task, duration), None, f"table {tab.source}"
    res = solve_seeded(prob, seeds, settings, check=solver == "exact")
    if solver == "seeded":
        return res.params, res, f"seeded (table {tab.source})"
    return res.params, res, f"exact (table {tab.source} seeds and multi-start samples)"


def _check_params(params) -> tuple[float, ...]:
    try:
        p = tuple(float(x) for x in params)
    except (TypeError, ValueError):
        raise TaskError(f"params = {params!r}: give seven numbers τ6, τ7, τ9, τ10, λ1, λ2, λ3") from None
    if len(p) != 7 or not all(math.isfinite(x) for x in p):
        raise TaskError(f"params = {params!r}: give seven finite numbers τ6, τ7, τ9, τ10, λ1, λ2, λ3")
    if not (0 < p[0] < p[1] < 0.5 < p[2] < p[3] < 1):
        raise TaskError(
            f"params = {','.join(f'{x:g}' for x in p[:4])}: the knots need 0 < τ6 < τ7 < 0.5 < τ9 < τ10 < 1 "
            "[Yang2022, Eq. (36)]"
        )
    if not all(0 <= x <= 1 for x in p[4:]):
        raise TaskError(f"params λ = {','.join(f'{x:g}' for x in p[4:])}: each λ must lie in [0, 1] [Yang2022, Eq. (36)]")
    return p


def plan_bspline_vel(
    task: Task,
    duration: float,
    params=None,
    solver: str = "exact",
    table: str | None = None,
    settings: VelSettings | None = None,
    margin: float | None = None,
    _result: VelResult | None = None,
    _source: str = "exact",
    **named: float,
) -> CartesianPath:
    """CartesianPath of the conveyor-tracking B-spline for a move of ``duration`` seconds [Yang2022].

    The shape parameters (τ6, τ7, τ9, τ10, λ1, λ2, λ3) are ``params`` (or all seven by name: ``tau6`` …
    ``lambda3``) when given, else the optimum of Eq. (37) by ``solver`` (see :func:`optimum`): "exact"
    (default: table seeds and multi-start samples, :func:`solve_seeded`), "seeded" (the table's seeds
    polished to the optimum of their basin) or "table" (the interpolant of :mod:`pickplace_cli.lookup.vel_table` alone;
    ``table`` is its file, default the shipped one).
    ``margin`` overrides ``settings.margin``. The path is valid only when run in ``duration`` seconds:
    its τ-derivative at the ends is v·T.
    """
    if named:
        unknown = sorted(set(named) - set(PARAM_NAMES))
        if unknown:
            raise TypeError(f"plan_bspline_vel() got an unexpected keyword argument '{unknown[0]}'")
        missing = [n for n in PARAM_NAMES if n not in named]
        if missing or params is not None:
            raise TaskError(
                f"param {missing[0] if missing else 'params'}: give all seven shape parameters "
                f"({', '.join(PARAM_NAMES)}) or none"
            )
        params = [named[n] for n in PARAM_NAMES]
    if margin is not None:
        settings = replace(settings or VelSettings(), margin=float(margin))
    T = float(duration)
    prob = make_problem(task, T)
    extra: dict[str, Any] = {}
    res = _result  # an exact solve the caller (PathFactory) already did
    source = _source  # (a solve the caller did: its words, e.g. whether a table seeded it)
    if res is not None:
        p = res.params
    elif params is not None:
        p = _check_params(params)
        source = "given"
    else:
        p, res, source = optimum(task, T, solver, table, settings)
    if res is not None:
        # F's normalisers in the move's own units (like CartesianPath.peaks: m per τ², τ³ at T = 1 s)
        extra = {"F": res.F, "a_min": res.a_min * prob.scale, "j_min": res.j_min * prob.scale,
                 "margin": res.settings.margin, "lambda_free": list(res.lambda_free)}
    spline = spline_of(prob, p)
    scale = prob.scale
    peaks = tuple(scale * x for x in norm_peaks(spline, (1, 2, 3)))
    origin = task.p_from

    def evaluate(tau: np.ndarray, order: int) -> np.ndarray:
        out = scale * spline(tau, nu=order)
        return out + origin if order == 0 else out

    parameters: dict[str, Any] = dict(zip(PARAM_NAMES, p))
    # C4 inside the move (quintic B-spline, simple interior knots); the measured class stops at jerk (C3).
    # With conveyor velocities the ends are not at rest: the tool moves on with the belt.
    parameters.update(continuity=3, jerk_jumps_at=[])
    parameters.update(
        params_source=source, duration_s=T, eta=task.eta, height_m=task.height,
        v_from_m_s=task.v_from.tolist(), v_to_m_s=task.v_to.tolist(), **extra,
    )
    return CartesianPath(
        evaluate=evaluate,
        method="bspline-vel",
        parameters=parameters,
        peaks=peaks,  # type: ignore[arg-type]
        breakpoints=np.unique(spline.t),
        jumps=(),  # C⁴ inside the move: nothing steps at the knots
    )


class PathFactory:
    """duration T [s] → CartesianPath of ``task`` planned for T (memoised): the hook the planner uses for
    methods whose normalised path depends on T (``depends_on_duration``). ``params`` are those of
    :func:`plan_bspline_vel` (checked here, so a wrong name fails before any duration is tried).

    With the exact solver, the first duration is solved globally and later ones by continuation from the
    nearest solved duration (``solve(..., warm=…)``, a few SLSQP steps): the optimum moves smoothly with T.
    :meth:`final` re-solves a duration globally; when that finds a better optimum the continuation had
    followed a worse branch, the factory stops using it, and the caller repeats its search."""

    depends_on_duration = True
    MAX_SWITCHES = 3
    _ALLOWED = {"params", "solver", "table", "settings", "margin", *PARAM_NAMES}

    def __init__(self, task: Task, **params: Any) -> None:
        unknown = sorted(set(params) - self._ALLOWED)
        if unknown:
            name = unknown[0]
            raise TaskError(
                f"param {name} = {params[name]!r}: method bspline-vel has no parameter {name!r} (see README, Methods)"
            )
        self.task = task
        self.params = params
        self.continuation = params.get("solver", "exact") in ("exact", "seeded") and not (
            params.get("params") is not None or any(n in params for n in PARAM_NAMES)
        )
        self._cache: dict[float, CartesianPath] = {}
        self._results: dict[float, VelResult] = {}
        self._switches = 0
        self._source = "exact"  # the last full solve's words (:func:`optimum`): its table, or why none was used

    def task_at(self, duration: float) -> Task:
        """The task planned for ``duration`` [s]: the same for every T here; a conveyor rendezvous
        (:mod:`pickplace_cli.pipelines.rendezvous`) moves its end point with T."""
        return self.task

    def __call__(self, duration: float) -> CartesianPath:
        T = float(duration)
        if T not in self._cache:
            if len(self._cache) > 256:
                self._cache.clear()
                self._results.clear()
            if self.continuation and self._results:
                near = min(self._results, key=lambda x: abs(math.log(x / T)))
                self._cache[T] = self._exact(T, warm=self._results[near])
            elif self.continuation:
                self._cache[T] = self._exact(T, seeded=True)
            else:
                self._cache[T] = plan_bspline_vel(self.task_at(T), T, **self.params)
        return self._cache[T]

    def _exact(self, T: float, warm: VelResult | None = None, seeded: bool = False) -> CartesianPath:
        settings = self.params.get("settings") or VelSettings()
        if self.params.get("margin") is not None:
            settings = replace(settings, margin=float(self.params["margin"]))
        if warm is None:  # the first duration, or the final check: the requested solver in full
            solver = self.params.get("solver", "exact") if seeded else "exact"
            _, res, self._source = optimum(self.task_at(T), T, solver, self.params.get("table"), settings)
        else:
            res = solve(make_problem(self.task_at(T), T), settings, warm=warm)
        self._results[T] = res
        return plan_bspline_vel(self.task_at(T), T, _result=res, _source=self._source)

    def final(self, duration: float) -> tuple[CartesianPath, bool]:
        """(the path at T from the full solve (and the continuation: the better), whether the continuation's
        optimum was the better one).

        On disagreement the global optimum becomes the seed of later continuations (so the caller's
        repeated search follows the better branch); after ``MAX_SWITCHES`` switches only global solves are
        used."""
        T = float(duration)
        if not self.continuation:
            return self(T), True
        before = self._results.get(T)
        self._exact(T)
        full = self._results[T]
        both = best_of([full] + ([before] if before is not None else []))
        # the continuation agreed when its optimum is as good (F to 1e-9, common normalisers)
        agreed = before is not None and (
            both.a_min / before.a_max + both.j_min / before.j_max >= both.F - 1e-9
        )
        if agreed:
            both = replace(before, a_min=both.a_min, j_min=both.j_min, F=both.a_min / before.a_max + both.j_min / before.j_max)
        self._results[T] = both  # F with the lowest normalisers either search found
        path = plan_bspline_vel(self.task_at(T), T, _result=both, _source=self._source)
        self._cache[T] = path
        if agreed or before is None:
            return path, True
        self._switches += 1
        self._cache = {T: path}
        self._results = {T: both}
        if self._switches >= self.MAX_SWITCHES:
            self.continuation = False
        return path, agreed


def resolve_velocities(workcell, v_from=None, v_to=None) -> tuple[np.ndarray, np.ndarray]:
    """End velocities [m/s, base frame]: the given ones, else the profile's conveyor velocities, else 0."""
    def pick(given, default):
        if given is not None:
            return np.asarray(given, float)
        return np.asarray(default, float) if default is not None else np.zeros(3)

    return (
        pick(v_from, getattr(workcell, "conveyor_pick_velocity", None)),
        pick(v_to, getattr(workcell, "conveyor_place_velocity", None)),
    )
