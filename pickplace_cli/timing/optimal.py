"""``--time optimal``: the same path, traversed with a non-uniform time law that minimises the duration under
the robot's own limits.

Formulation (in the path parameter τ, like TOPP): the tool moves along the path with dτ/dt = √b(τ), where
b(τ) > 0 is a cubic B-spline (C², so the acceleration is continuous and the jerk bounded: b″ is piecewise
linear). The uniform law of ``--time fit`` is b ≡ 1/T². For every τ the robot model gives, at T = 1 s on
the uniform law (``MotionModel.parts``): q′, q″, q‴ (joint derivatives in τ), the inertial motor torque
A_m and its τ-derivative, the gravity motor torque G_m and its derivative; and here
m(τ) = the motor torque of the pure acceleration p′ (velocity 0) — the inertia seen along the path. Then

    joint velocity   q̇ = q′√b                       motor speed    N·q′√b
    joint accel.     q̈ = q″b + q′b′/2
    joint jerk       q⃛ = √b (q‴b + 3/2·q″b′ + q′b″/2)
    motor torque     τ = A_m·b + m·b′/2 + G_m        (exact: the torque is affine in (b, b′))
    torque rate      τ̇ = √b (A_m′b + A_m·b′ + m′b′/2 + m·b″/2 + G_m′)
    RMS              ∫τ² dt = ∫ τ² / √b dτ,   T = ∫ dτ/√b

so every constraint is an explicit function of (b, b′, b″) at a grid of τ, and b, b′, b″ are linear in the
spline's coefficients: SLSQP with exact Jacobians, warm-started at the uniform law of ``--time fit``.
Position, singularity and workcell limits belong to the path and do not change with the law.

The optimiser's grid is not the judge: the law found is composed with the path into a new
:class:`~pickplace_cli.model.trajectory.CartesianPath` (u = t/T: τ = σ(u) from the exact integral of 1/√b), and
``--time fit`` runs on that path with the continuous check (all limits, exact RMS). A law that is not
faster than uniform scaling is not used (the plan says so).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..model.threads import single_blas_thread
from .compose import compose
from .law_rows import (LAW_CHECK_GRID, LAW_CHECK_ROUNDS, LAW_CHECK_TOL, LAW_GRID, LAW_MARGIN,  # noqa: F401
                       _basis, _GridData, _inertia_along, _law_grid, _limit_rows, _Problem, _problem, _rows, _stack)

#: cubic B-spline coefficients of b(τ) of the first solve (uniform knots in τ)
LAW_COEFFICIENTS = 20
#: the default (``coefficients=None``, ``--law-coefficients auto``): the first law is refined to this many
#: coefficients when it is more than ``1 − LAW_REFINE_BELOW`` faster than uniform (on the knot placements of
#: ``LAW_REFINE_PLACEMENTS``, the path's knots and jumps among them). A law that far from uniform
#: has the narrow dips 20 uniform knots resolve worst: on the worst random moves of bench/bench_optimal.py the
#: refined law is 2-5 % shorter; the Adept cycle (0.927 × fit) is not refined (40 coefficients: 0.9247 × fit,
#: 0.2 % shorter, for ~6 × the planning time)
LAW_REFINED = 40
LAW_REFINE_BELOW = 0.9
#: the refinement's knot placements (:func:`_refined_knots`' weight: 1 uniform in the first law's time, 0 uniform
#: in τ; both with the path's knots): each is solved and the shortest law kept. Either alone left 1-3 of the
#: 60 moves of bench_optimal.py more than 1 % above the 80-coefficient solve (worst 1.16 % and 1.12 %), a
#: different move each time; the better of the two: worst 0.85 %
LAW_REFINE_PLACEMENTS = (1.0, 0.0)
#: bounds of the law's coefficients relative to the uniform law (b between 1/100 and 100 times 1/T_fit²:
#: the tool at most 10× slower or faster than uniform anywhere; keeps SLSQP away from b → 0 or ∞ at the
#: path's ends, where the rest-to-rest path leaves b nearly free)
LAW_BOUNDS = (1e-2, 1e2)
#: grid rows used by the full solve from the start: those above this fraction of their limit at its warm start
LAW_ACTIVE = 0.8
#: Chebyshev-spaced points of the coarse first phase's grid (every row used); 0: no coarse phase. Denser at
#: the ends than uniform points: a uniform coarse grid let the law race between its first points (b up to
#: 20× uniform) and the fine phase then needed 34 more iterations to undo it
LAW_COARSE_GRID = 31
#: … on its rows above this fraction of their limit at the start (a quadratic row's value is its utilisation
#: squared); 0.2 and up left out rows the law then needed, and the restart cost more than the rows saved
LAW_COARSE_ACTIVE = 0.1
#: SLSQP's tolerance on the objective (the duration relative to T_fit). With the log-parametrised coefficients
#: 1e-8 gives the T of 1e-9 within 1.2e-4 on 14 moves (all methods, three robots) with ~10 % fewer iterations
#: (in the linear parametrisation 1e-7 had lost up to 1 %)
LAW_FTOL = 1e-8
LAW_PEAK_SPREAD = 2


@dataclass(frozen=True)
class LawResult:
    """The optimised law: the composed path (u ∈ [0, 1], derivatives at T = 1 s), the optimiser's own
    duration estimate [s], its iterations and message."""

    path: object
    t_estimate: float
    iterations: int
    message: str
    #: the law b(τ) itself (a scipy BSpline; b = (dτ/dt)² [1/s²])
    law: object = None
    #: a refined law's first law (``LAW_COEFFICIENTS`` coefficients): the plan fits both and keeps the shorter
    #: (the optimisers' estimates rank them; the continuous fit can still reverse a close call)
    first: object = None
    #: what ``iterations`` counts: "SLSQP iterations" or "QP solves" (the structured SQP's)
    counted: str = "SLSQP iterations"


def _solve(prob: _Problem, x: np.ndarray, keep: np.ndarray, t_fit: float) -> tuple[np.ndarray, int, str, int]:
    """SLSQP on the rows ``keep`` from ``x``; rows the solution breaks are added (with every row above
    ``LAW_ACTIVE``/2 of its limit) and the problem solved again. Returns (x, iterations, message, rounds).

    The variables are the logarithms of the law's coefficients (b > 0 by construction, and SLSQP's quasi-Newton
    model fits the duration ∫dτ/√b better: about half the iterations of the linear parametrisation)."""
    from scipy.optimize import minimize

    nit, message = 0, ""
    y = np.log(x)
    bounds = [tuple(np.log(LAW_BOUNDS))] * len(x)
    for rounds in range(1, 6):
        evaluate = prob.subset(keep)
        cache: dict = {}

        def cons(y):
            key = y.tobytes()
            if key not in cache:
                cache.clear()
                ex = np.exp(y)
                v, J = evaluate(ex)
                cache[key] = (v, J * ex)
            return cache[key]

        def objective(y):
            ex = np.exp(y)
            f, g = prob.objective(ex)
            return f / t_fit, g * ex / t_fit

        res = minimize(objective, y, jac=True, method="SLSQP", bounds=bounds,
                       constraints=[{"type": "ineq", "fun": lambda y: cons(y)[0], "jac": lambda y: cons(y)[1]}],
                       options={"maxiter": 300, "ftol": LAW_FTOL})
        nit += int(res.nit)
        message = str(res.message)
        if np.all(np.isfinite(res.x)):
            y = res.x
        v = prob.values(np.exp(y))[: prob.n_rows]
        broken = (~keep) & (v < -1e-9)
        if not broken.any():
            break
        keep = keep | (v < 1.0 - LAW_ACTIVE / 2)
    return np.exp(y), nit, message, rounds


#: the law's solver: "sqp" (:mod:`pickplace_cli.timing.law_sqp`: the structured SQP, when ``daqp`` imports) or
#: "slsqp" (scipy's SLSQP on 20 coefficients refined to 40: the solver before it, kept as the fallback and for the
#: benchmarks' comparison)
LAW_SOLVER = "sqp"
#: coefficients of the SQP's quintic law (uniform knots) under ``--law-coefficients auto``: 40 left a PH move 0.9 %
#: above the 80-coefficient SLSQP solve where 60 are 0.7 % below it, and 60 are 0.1-0.3 % shorter than 40 elsewhere,
#: for about 1.5-2 × the time (``python bench/bench_law_solver.py``)
LAW_SQP_COEFFICIENTS = 60


def _sqp_grid(coefficients: int) -> tuple[np.ndarray, int]:
    """(knots, points of the first solve grid) of the SQP's law of ``coefficients`` uniform knots."""
    from . import law_sqp

    knots = _knots(coefficients, law_sqp.SQP_DEGREE)
    return knots, max(LAW_GRID, law_sqp.SQP_POINTS_PER_KNOT * (coefficients - law_sqp.SQP_DEGREE) + 1)


def sqp_data(model, coefficients: int | None = None, bound: bool = True) -> _GridData:
    """The model's terms on every grid the SQP's law of ``coefficients`` (None: ``LAW_SQP_COEFFICIENTS``) is solved
    and checked on, and (``bound``) on the torque bound's (:func:`~pickplace_cli.timing.bound.bound_grid`): one
    evaluation of the model for both (its cost is mostly per call)."""
    from . import law_sqp
    from .bound import bound_grid

    knots, points = _sqp_grid(coefficients or LAW_SQP_COEFFICIENTS)
    grids = [law_sqp.solve_grid(model.path, points, knots), law_sqp.check_grid(model.path)]
    return _GridData(model, np.concatenate(grids + ([bound_grid()] if bound else [])))


def _sqp_law(model, dwell: float, t_fit: float, coefficients: int, capacity,
             smooth: float | None = None, data: _GridData | None = None) -> LawResult | None:
    """The law of ``coefficients`` uniform knots by the structured SQP (:mod:`~pickplace_cli.timing.law_sqp`, with its
    smoothing term: weight ``smooth``, None the shipped ``law_sqp.smoothing``) from the uniform law; None when its
    answer breaks a row of its own (last) grid by more than 1e-6 of the limit (the caller falls back to SLSQP)."""
    from . import law_sqp

    knots, points = _sqp_grid(coefficients)
    data = data or sqp_data(model, coefficients, bound=False)
    x, t_est, solves, message, worst, _ = law_sqp.solve_law(model, dwell, t_fit, knots, capacity, data,
                                                            np.ones(coefficients), *LAW_BOUNDS, points,
                                                            smooth=law_sqp.smoothing(t_fit) if smooth is None else smooth)
    if not (np.all(np.isfinite(x)) and worst <= 1e-6):
        return None
    b = _law_spline(knots, x / t_fit**2)
    return LawResult(compose(model.path, b), float(t_est), solves, message, b, counted="QP solves")


@single_blas_thread
def optimal_law(model, dwell: float, t_fit: float, coefficients: int | None = None,
                capacity=None, start: np.ndarray | None = None, direct: bool = False,
                solver: str | None = None, smooth: float | None = None, data: _GridData | None = None) -> LawResult:
    """Minimise the duration of ``model``'s path over time laws b(τ) (module docstring), warm-started at the
    uniform law of duration ``t_fit`` [s]. ``capacity``: also hold the profile's Cartesian |v|, |a| (and |j|
    when set) — optional, off by default. ``start``: the law's coefficients to start from (relative to the
    uniform law, which is all ones; the benchmark's multi-start). Returns the composed path (not yet checked).

    Each solve has two phases: every row of a coarse grid (``LAW_COARSE_GRID`` points and the path's knots and
    jump sides: few rows, so SLSQP's subproblems are cheap) from the start; then the full grid from that
    solution, on the rows above ``LAW_ACTIVE`` of their limit there (the coarse solution already works the
    right rows hardest), adding any row the solution breaks; then the check rounds (:func:`_check_rounds`).

    ``coefficients``: None (``--law-coefficients auto``) solves ``LAW_COEFFICIENTS`` and refines that law to
    ``LAW_REFINED`` coefficients when it is more than ``1 − LAW_REFINE_BELOW`` faster than uniform; N ≤
    ``LAW_COEFFICIENTS``: N uniform knots; N more: the law of ``LAW_COEFFICIENTS`` first, then N coefficients
    on each knot placement of ``LAW_REFINE_PLACEMENTS`` (:func:`_refined_knots`), started from its
    least-squares projection; the shortest refined law is kept, and only when its duration estimate is shorter
    than the first law's. ``direct`` or a ``start``: N (default
    ``LAW_COEFFICIENTS``) uniform knots solved from ``start`` or the uniform law (the benchmarks' independent
    solves). ``solver``: "sqp" or "slsqp" (None: ``LAW_SOLVER``). With the SQP (and neither ``start`` nor
    ``direct``), the law has N (default ``LAW_SQP_COEFFICIENTS``) uniform knots and is solved from the uniform law;
    SLSQP as above when ``daqp`` is missing or the SQP's answer breaks its own grid. ``smooth``: the SQP's smoothing
    weight (None: ``law_sqp.smoothing``). ``data``: the SQP's model terms already evaluated (:func:`sqp_data`)."""
    from . import law_sqp

    if (solver or LAW_SOLVER) == "sqp" and start is None and not direct and law_sqp.available():
        found = _sqp_law(model, dwell, t_fit, coefficients or LAW_SQP_COEFFICIENTS, capacity, smooth, data)
        if found is not None:
            return found
    if start is None and not direct and (coefficients is None or coefficients > LAW_COEFFICIENTS):
        data = _GridData(model, _shared_grid(model.path, coefficients or LAW_REFINED))
        first = _solve_law(model, dwell, t_fit, LAW_COEFFICIENTS, _knots(LAW_COEFFICIENTS), capacity, None,
                           data=data)
        n = coefficients or LAW_REFINED
        if coefficients is None and not first.t_estimate < LAW_REFINE_BELOW * t_fit:
            return first
        s = np.linspace(0.0, 1.0, 8 * n)
        fine, nit, tried = None, first.iterations, []
        for weight in LAW_REFINE_PLACEMENTS:  # each knot placement from the first law; the shortest is kept
            knots = _refined_knots(first.law, model.path, n, weight)
            x = np.clip(np.linalg.lstsq(_basis(knots, s)[0], first.law(s) * t_fit**2, rcond=None)[0], *LAW_BOUNDS)
            law = _solve_law(model, dwell, t_fit, n, knots, capacity, x, coarse=False, data=data)
            nit += law.iterations
            tried.append(f"{law.t_estimate:.5g} s")
            if fine is None or law.t_estimate < fine.t_estimate:
                fine = law
        if not fine.t_estimate < first.t_estimate:
            return replace(first, iterations=nit,
                           message=f"{first.message}; the {n}-coefficient refinements ({', '.join(tried)}) were not shorter")
        return replace(fine, iterations=nit, first=first,
                       message=f"{fine.message}, refined from {LAW_COEFFICIENTS} coefficients "
                               f"({first.t_estimate:.5g} s → {', '.join(tried)}: the shortest kept)")
    n = coefficients or LAW_COEFFICIENTS
    return _solve_law(model, dwell, t_fit, n, _knots(n), capacity, start)


def _solve_law(model, dwell: float, t_fit: float, coefficients: int, knots: np.ndarray, capacity,
               start: np.ndarray | None, coarse: bool = True, data: _GridData | None = None) -> LawResult:
    """One solve of the law on ``knots`` (:func:`optimal_law`): the coarse phase (unless not ``coarse``: a warm
    start from a solved law needs none), the fine phase and its check rounds."""
    path = model.path
    data = data or _GridData(model, _shared_grid(path, coefficients))
    x0 = np.ones(coefficients)
    x = x0 if start is None else np.clip(np.asarray(start, float), *LAW_BOUNDS)
    nit = 0
    if LAW_COARSE_GRID and coarse:
        coarse_pr = _Problem(model, _law_grid(path, LAW_COARSE_GRID, spans=False, clustered=True), knots, t_fit,
                             dwell, capacity, data)
        # the rows above LAW_COARSE_ACTIVE of their limit at the start (a quarter of them on the Adept cycle:
        # SLSQP's cost per iteration grows with the rows); a row the solution breaks joins and the solve goes on
        keep = coarse_pr.values(x)[: coarse_pr.n_rows] < 1.0 - LAW_COARSE_ACTIVE
        xc, nit, message, _ = _solve(coarse_pr, x, keep, t_fit)
        if coarse_pr.values(xc).min() > -1e-3:  # a usable warm start (the fine grid may still bend it)
            x = xc
    # the optimiser's grid: at least 4 points per knot interval (an 80-coefficient law on the 161 points that
    # suit 40 coefficients came out longer than the 20-coefficient law on the Adept cycle)
    points = max(LAW_GRID, 4 * (coefficients - 3) + 1)
    x, n2, message, rounds, fine = _check_rounds(model, knots, t_fit, dwell, capacity, x, points, data)
    nit += n2
    # a law that breaks its own grid constraints (the solver stopped somewhere infeasible) is not used
    worst = float(fine.values(x).min()) if np.all(np.isfinite(x)) else -np.inf
    if worst < -1e-6:
        message = f"{message}; the solver's point breaks a limit on its grid by {-worst:.2g}: the uniform law is kept"
        x = x0
    message = f"{message} ({rounds} round(s) on {fine.n_rows} grid rows)"
    scale = 1.0 / t_fit**2
    b = _law_spline(knots, scale * x)
    return LawResult(compose(path, b), float(fine.objective(x)[0]), nit, message, b)


def _shared_grid(path, coefficients: int) -> np.ndarray:
    """The union of the grids one solve of ``coefficients`` coefficients starts with (coarse, fine, check): the
    τ of its :class:`_GridData`."""
    return np.concatenate([_law_grid(path, LAW_COARSE_GRID, spans=False, clustered=True),
                           _law_grid(path, max(LAW_GRID, 4 * (coefficients - 3) + 1)),
                           _law_grid(path, LAW_GRID), _law_grid(path, LAW_CHECK_GRID)])


def _refined_knots(law, path, coefficients: int, weight: float = 1.0) -> np.ndarray:
    """Knots for ``coefficients`` coefficients refined from a solved ``law``: uniform in w·t(τ) + (1 − w)·τ with
    t the law's own time (``weight`` w = 1: where the law is slow — the dips at its binding limits — gets more
    knots than uniform-in-τ gives; w = 0: uniform in τ), the path's interior knots and jumps among them (each
    takes the place of its nearest knot), where the limits' rows change slope or step and b‴ may then step too."""
    from scipy.integrate import cumulative_trapezoid

    s = np.linspace(0.0, 1.0, 2001)
    t = cumulative_trapezoid(law(s) ** -0.5, s, initial=0.0)  # the law's time (∫dτ/√b) on a fine grid
    inner = np.interp(np.linspace(0.0, 1.0, coefficients - 2), weight * t / t[-1] + (1.0 - weight) * s, s)
    free = np.ones(len(inner), bool)
    free[[0, -1]] = False
    extra = np.unique(np.concatenate([np.asarray(path.breakpoints, float), np.asarray(path.jump_points, float)]))
    for e in extra[(extra > 1e-9) & (extra < 1.0 - 1e-9)]:
        if not free.any():
            break
        j = np.flatnonzero(free)[np.argmin(np.abs(inner[free] - e))]
        inner[j], free[j] = e, False
    return np.concatenate([[0.0] * 3, np.sort(inner), [1.0] * 3])


def _knots(coefficients: int, degree: int = 3) -> np.ndarray:
    """The law's knots: uniform in τ, the ends repeated (``degree`` 3: cubic)."""
    return np.concatenate([[0.0] * degree, np.linspace(0.0, 1.0, coefficients - degree + 1), [1.0] * degree])


def _check_rounds(model, knots, t_fit: float, dwell: float, capacity, x: np.ndarray, points: int = 0,
                  data: _GridData | None = None):
    """The fine phase from ``x`` and its check rounds: between the grid's points the law may still break a limit
    (a peak the grid straddles); the rows of a denser grid (``LAW_CHECK_GRID``) find where, those τ join the grid
    and the solve continues from its answer (``LAW_CHECK_ROUNDS`` at most). Returns (x, iterations, message,
    rounds, the last fine problem)."""
    path = model.path
    check = _Problem(model, _law_grid(path, LAW_CHECK_GRID), knots, t_fit, dwell, capacity, data)
    # the check grid's local peaks of every row above LAW_ACTIVE at x join the grid from the start (the fine
    # solve then rarely needs a check round: each round is a cold SLSQP restart)
    v = check.values(x)[: check.n_rows].reshape(-1, len(check.tau))
    mid = v[:, 1:-1]
    peak = (mid <= v[:, :-2]) & (mid <= v[:, 2:]) & (mid < 1.0 - LAW_ACTIVE)
    at = np.flatnonzero(peak.any(axis=0)) + 1
    near = (at[:, None] + np.arange(-LAW_PEAK_SPREAD, LAW_PEAK_SPREAD + 1)).ravel()
    grid = np.union1d(_law_grid(path, points), check.tau[np.clip(near, 0, len(check.tau) - 1)])
    fine = _Problem(model, grid, knots, t_fit, dwell, capacity, data)
    keep = fine.values(x)[: fine.n_rows] < 1.0 - LAW_ACTIVE
    x, nit, message, rounds = _solve(fine, x, keep, t_fit)
    for _ in range(LAW_CHECK_ROUNDS):
        v = check.values(x)[: check.n_rows]
        bad = np.unique(check.row_tau[v < -LAW_CHECK_TOL])
        if not bad.size:
            break
        grid = np.union1d(grid, bad)
        fine = _Problem(model, grid, knots, t_fit, dwell, capacity, data)
        keep = fine.values(x)[: fine.n_rows] < 1.0 - LAW_ACTIVE
        x, n3, message, r3 = _solve(fine, x, keep, t_fit)
        nit, rounds = nit + n3, rounds + r3
    return x, nit, message, rounds, fine


def _law_spline(knots: np.ndarray, coef: np.ndarray):
    from scipy.interpolate import BSpline

    from .law_rows import degree

    return BSpline(knots, coef, degree(knots), extrapolate=False)
