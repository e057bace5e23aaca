"""``--optimize shape``: choose the B-spline path's own parameters — the time-ratio factors k1, k2 and the
lift-off/set-down ratio η of [Li2018] — for the smallest duration under the robot's limits.

Li 2018's table picks (k1, k2) for a Cartesian objective (Eq. 22: weighted peak acceleration and jerk at
unit b, h), the same for every robot. Here the objective is the robot's own: the duration ``--time fit``
would give the path (uniform scaling until the first joint, motor or RMS limit touches), screened on a
coarse grid (``SHAPE_SAMPLES`` uniform points ∪ knots ∪ the points the check adds per span, ~3 ms per
shape); a shape that breaks a limit no duration fixes (a joint range, the workcell box, the singularity
margin — the shape moves the path) ranks below every shape that keeps them. The landscape has several local minima (and its minimum often lies on the η bound), so the search
is global in two steps: a coarse grid over (k1, k2, η), then Nelder-Mead (scipy, with bounds) from the best
``SHAPE_STARTS`` distinct grid points and from the table's own shape. The winner is then planned as usual
(the exact fit, or ``--time optimal``'s law, judged by the continuous check).

With ``--time optimal`` the shape is the one that is fastest for the *uniform* law; the time law is then
optimised on that shape (choosing both at once would need a law solve per trial shape, ~100× the cost). The
benchmark (``bench/bench_shape.py``) compares the result with a slower search.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..model.threads import single_blas_thread

#: uniform points of the screening grid (plus the knots and the check's points per span)
SHAPE_SAMPLES = 101
#: default range searched for η (Li 2018 uses 0.5; the λ × η table covers 0.1 … 0.9); k1, k2 in K_SEARCH
ETA_RANGE = (0.1, 0.9)
K_SEARCH = (0.01, 0.99)
#: range searched for the arch (the midpoint P3's height above the clearance), as a multiple of the clearance h;
#: (0, 0) keeps Li's path (apex at h). Nelder-Mead searches it from ARCH_START·h at every start
ARCH_RANGE = (0.0, 1.0)
ARCH_START = 0.1
#: the widened family's other parameters: the set-down side's k3, k4 (in K_SEARCH) and P3's knot τ9 (Li: 1/2);
#: Nelder-Mead budget per run and restarts from its own result (bench/bench_free_path.py measures the gain)
MID_SEARCH = (0.35, 0.65)
WIDE_MAXFEV = 150
WIDE_RESTARTS = 1
#: the coarse grid: points per axis (k1, k2, η)
SHAPE_GRID = (5, 5, 3)
#: Nelder-Mead runs from this many best grid points (plus the table's shape); bench/bench_shape.py compares
#: this budget (~250 shapes) with a slower search
SHAPE_STARTS = 2
#: Nelder-Mead stopping tolerances: on (k1, k2, η) and on the screened duration [s]
SHAPE_XATOL = 2e-3
SHAPE_FATOL = 1e-6
SHAPE_MAXFEV = 60


#: a shape that breaks a limit no duration fixes (joint range, workcell box, singularity margin) is screened
#: as T + INFEASIBLE·(1 + its relative excess): worse than every feasible shape, better the less it breaks
INFEASIBLE = 1e3


def _static_excess(model, parts) -> float:
    """The largest relative excess over the duration-independent limits (joint position range, workcell box,
    singularity margin: kind "reach") on the screening grid; ≤ 0 when they all hold."""
    meta, data = model.columns(parts, 1.0)
    worst = 0.0
    for c, m in enumerate(meta):
        if m[4] == "reach":
            lim = m[3] * m[5]  # the column's sign convention: max of the column ≤ lim
            worst = max(worst, (float(data[:, c].max()) - lim) / max(abs(m[3]), 1e-3))
    return worst


def _capacity_screen(model, path, tau: np.ndarray, capacity) -> float:
    """A shape's screened duration [s] on a profile whose only duration limit is the Cartesian capacity: Eq. 26's
    auto duration of the path's peaks, ranked below every feasible shape when it breaks a duration-independent limit
    (``INFEASIBLE``)."""
    from . import auto_duration

    excess = _static_excess(model, model.parts(tau, derivatives=False))
    val = max(x for x in auto_duration(path, capacity)[:3] if x is not None)
    return val + INFEASIBLE * (1.0 + round(excess, 6)) if excess > 0 else val


def _AXIS(n: int) -> np.ndarray:
    """Grid values of k1 and k2: the lower end of the range (the optimum often lies there) and n − 1 points
    spread over [0.15, 0.85]."""
    return np.concatenate([[K_SEARCH[0]], np.linspace(0.15, 0.85, n - 1)])


_LOG_T = (np.log(1e-4), np.log(1e4))


def _log_secant_root(worst, start: float, xtol: float = 1e-7, iterations: int = 30) -> float | None:
    """The T [s] where the worst utilisation u(T) = 1 by the secant method on log u against log T (u ∝ T^-k
    for k = 1…3 for every quantity but the gravity-loaded torque: ~4 evaluations); None when it does not
    converge (the caller falls back to the bracketing :func:`~pickplace_cli.timing.screened_root`)."""
    x0 = np.log(start)
    u0 = worst(start)[0] + 1.0
    if not (u0 > 0 and np.isfinite(u0)):
        return None
    x1 = float(np.clip(x0 + 0.5 * np.log(u0), *_LOG_T))  # as if u ∝ T^-2
    y0 = np.log(u0)
    for _ in range(iterations):
        u1 = worst(float(np.exp(x1)))[0] + 1.0
        if not (u1 > 0 and np.isfinite(u1)):
            return None
        y1 = np.log(u1)
        if abs(x1 - x0) < xtol and abs(y1) < 1e-6:
            return float(np.exp(x1))
        if y1 == y0:
            return None
        x0, y0, x1 = x1, y1, x1 - y1 * (x1 - x0) / (y1 - y0)
        if not (np.isfinite(x1) and _LOG_T[0] < x1 < _LOG_T[1]):  # left the durations screened_root scans
            return None
    return None


def _widened(f, shape_of, screen, best: tuple, bounds: list, arch_range: tuple) -> tuple:
    """The widened family from Li's best ``best`` = (T, (k1, k2, η, 0, None, None, None)): Nelder-Mead over
    (k1, k2[, η], arch/h, k3, k4, mid) from the symmetric shape (k3 = k1, k4 = k2, mid = 1/2, arch 0), restarted
    ``WIDE_RESTARTS`` times from its own result (a simplex in 7-D stalls); kept only when it screens faster."""
    from scipy.optimize import minimize

    from ..paths.bspline import MID_RANGE

    k1, k2, eta = best[1][:3]
    na = len(bounds)
    x = np.array([k1, k2, eta][:na] + [arch_range[0], k1, k2, 0.5])
    wide = bounds + [tuple(arch_range), K_SEARCH, K_SEARCH, MID_SEARCH]
    lo, hi = np.array([b[0] for b in wide]), np.array([b[1] for b in wide])
    steps = np.array([0.05] * na + [ARCH_START, 0.05, 0.05, 0.03])
    for _ in range(1 + WIDE_RESTARTS):
        simplex = np.array([x] + [np.clip(x + np.eye(len(x))[i] * steps[i] * (1 if x[i] + steps[i] <= hi[i] else -1),
                                          lo, hi) for i in range(len(x))])
        res = minimize(f, x, method="Nelder-Mead", bounds=wide,
                       options={"xatol": SHAPE_XATOL, "fatol": SHAPE_FATOL, "maxfev": WIDE_MAXFEV,
                                "initial_simplex": simplex})
        cand = shape_of(res.x)
        v = screen(*cand)
        if v < best[0]:
            best = (v, cand)
            x = np.clip(res.x, lo, hi)
    assert MID_RANGE[0] <= MID_SEARCH[0] and MID_SEARCH[1] <= MID_RANGE[1]
    return best


def _grid_starts(screen, eta_fixed: float | None, lo_e: float, hi_e: float) -> list[tuple[float, float, float]]:
    """The best ``SHAPE_STARTS`` points of the coarse (k1, k2, η) grid that are not neighbours of one another."""
    n1, n2, ne = SHAPE_GRID
    k_axis, k2_axis = _AXIS(n1), _AXIS(n2)
    e_axis = np.linspace(lo_e, hi_e, ne) if eta_fixed is None else np.array([eta_fixed])
    grid = [(a, b, e) for e in e_axis for a in k_axis for b in k2_axis]
    vals = np.array([screen(*g) for g in grid])
    order = np.argsort(vals)
    starts: list[tuple[float, float, float]] = []
    for i in order:  # the best grid points that are not neighbours of a start already taken
        if not np.isfinite(vals[i]):
            break  # sorted: the rest cannot be planned at all
        g = np.array(grid[i])
        step = np.array([k_axis[1] - k_axis[0], k2_axis[1] - k2_axis[0], (e_axis[1] - e_axis[0]) if len(e_axis) > 1 else 1.0])
        if all(np.any(np.abs(g - np.array(s)) > 1.01 * step) for s in starts):
            starts.append(tuple(g))
        if len(starts) >= SHAPE_STARTS:
            break
    return starts


@dataclass(frozen=True)
class ShapeResult:
    """The chosen (k1, k2, η), its screened fit duration [s] (None when no shape keeps the duration-independent
    limits), the table's shape and its screened duration (None when the table has no entry or its shape breaks
    such a limit), the number of shapes screened and a note for the user."""

    k1: float
    k2: float
    eta: float
    t_screen: float | None
    table: tuple[float, float, float] | None
    t_table_screen: float | None
    evaluations: int
    note: str
    arch: float = 0.0  # [m] the midpoint's height above the clearance (0: Li's path)
    k3: float | None = None  # the set-down side's time-ratio factors and P3's knot (None: Li's symmetric knots)
    k4: float | None = None
    mid: float | None = None
    symmetric: tuple[float, float, float] | None = None  # (k1, k2, η): the best of Li's family, before the widening


@single_blas_thread
def optimise_shape(task, profile, model_of, eta_fixed: float | None = None,
                   eta_range: tuple[float, float] = ETA_RANGE,
                   table_shape: tuple[float, float, float] | None = None, capacity=None,
                   arch_range: tuple[float, float] | None = None) -> ShapeResult:
    """The (k1, k2, η) of the B-spline path of ``task`` with the smallest screened ``--time fit`` duration on
    ``profile`` (module docstring). ``model_of(path)``: the path's motion model on the profile's robot.
    ``eta_fixed``: hold η (search k1, k2 only). ``table_shape``: (k1, k2, η) of the look-up table, screened
    and used as one more start. ``capacity``: also hold the Cartesian capacity (T ≥ Eq. 26's auto).
    ``arch_range``: the arch searched, as multiples of the clearance h (default ``ARCH_RANGE``; (0, 0): Li's
    family only, no widening); the grid
    screens Li's path (arch 0), Nelder-Mead searches the arch from every start."""
    from scipy.optimize import minimize

    from ..model.errors import PickplaceError
    from ..limits.grid import _extra_points
    from ..paths.bspline import screen_bspline
    from ..model.task import Task
    from . import _worst_utilisation, auto_duration, screened_root

    dwell = profile.planning.dwell
    seen: dict[tuple, float] = {}
    last_t = [0.1]

    arch_range = ARCH_RANGE if arch_range is None else arch_range
    widen = arch_range[1] > arch_range[0]

    def screen(k1: float, k2: float, eta: float, arch: float = 0.0, k3=None, k4=None, mid=None) -> float:
        key = (round(k1, 12), round(k2, 12), round(eta, 12), round(arch, 15), k3, k4, mid)
        hit = seen.get(key)
        if hit is not None:
            return hit
        try:
            t = Task(task.p_from, task.p_to, task.height, eta)
            path = screen_bspline(t, k1, k2, arch, *((None,) * 3 if k3 is None else (k3, k4, mid)),
                                  peaks=capacity is not None)
            model = model_of(path)
            tau = _extra_points(path.breakpoints, path.jumps, SHAPE_SAMPLES)
            found = _worst_utilisation(model, dwell, tau)
            if found is None:  # no joint or motor limit times the move: the capacity does, when it is held
                val = np.inf if capacity is None else _capacity_screen(model, path, tau, capacity)
            else:
                excess = _static_excess(model, found[1])
                val = _log_secant_root(found[0], last_t[0])
                if val is None or found[0](val * (1 + 1e-6))[0] > 0:  # not converged, or not the last crossing
                    val = screened_root(found[0], last_t[0], rtol=1e-6)
                if capacity is not None:
                    val = max(val, *(x for x in auto_duration(path, capacity)[:3] if x is not None))
                last_t[0] = val
                if excess > 0:  # ranked by its excess (rounded: the same excess ranks by duration), then T
                    val += INFEASIBLE * (1.0 + round(excess, 6))
        except PickplaceError:  # a shape the robot cannot follow (out of reach, no feasible duration)
            val = np.inf
        seen[key] = val
        return val

    lo_e, hi_e = (eta_fixed, eta_fixed) if eta_fixed is not None else eta_range
    starts = _grid_starts(screen, eta_fixed, lo_e, hi_e)
    t_table = None
    if table_shape is not None:
        t_table = screen(*table_shape) if eta_fixed is None else screen(table_shape[0], table_shape[1], eta_fixed)
        if np.isfinite(t_table):
            starts.append(table_shape if eta_fixed is None else (table_shape[0], table_shape[1], eta_fixed))
    if not starts:
        from ..model.errors import NoFeasibleDuration

        raise NoFeasibleDuration(
            f"--optimize shape: no (k1, k2, η) on the search grid gives a feasible move on profile {profile.name}")

    best = min(((screen(*s), s) for s in starts), key=lambda x: x[0])
    if not np.isfinite(best[0]):  # pragma: no cover - the starts are finite by construction
        best = (np.inf, starts[0])
    bounds = [K_SEARCH, K_SEARCH] + ([] if eta_fixed is not None else [(lo_e, hi_e)])
    na = len(bounds)

    def shape_of(x: np.ndarray) -> tuple:
        """(k1, k2, η, arch [m], k3, k4, mid) of a search vector (k1, k2[, η][, arch/h, k3, k4, mid])."""
        e = eta_fixed if eta_fixed is not None else float(x[2])
        if len(x) == na:
            return float(x[0]), float(x[1]), e, 0.0, None, None, None
        a = float(np.clip(x[na], *arch_range)) * task.height
        return (float(x[0]), float(x[1]), e, a, *(float(v) for v in x[na + 1:]))

    def f(x: np.ndarray) -> float:
        v = screen(*shape_of(x))
        return v if np.isfinite(v) else 1e12

    for s in starts:  # Li's family from every start
        res = minimize(f, np.array(s[:na]), method="Nelder-Mead", bounds=bounds,
                       options={"xatol": SHAPE_XATOL, "fatol": SHAPE_FATOL, "maxfev": SHAPE_MAXFEV})
        cand = shape_of(res.x)
        v = screen(*cand)
        if v < best[0]:
            best = (v, cand)
    best = (best[0], tuple(best[1][:3]) + (0.0, None, None, None))
    li_best = tuple(float(v) for v in best[1][:3])
    if widen:
        best = _widened(f, shape_of, screen, best, bounds, arch_range)
    t_best, (k1, k2, eta, arch, k3, k4, mid) = best
    if t_best >= INFEASIBLE:
        note_static = ("; no shape keeps the joint ranges, the workcell box and the singularity margin: the one "
                       "that breaks them least is planned and the check reports it")
    else:
        note_static = ""
    what = "k1, k2" if eta_fixed is not None else f"k1, k2, η ∈ [{lo_e:g}, {hi_e:g}]"
    if widen:
        what += (f", arch ∈ [{arch_range[0]:g}, {arch_range[1]:g}]·h and the asymmetric knots (k3, k4, mid) from "
                 "Li's best")
    note = f"{what} searched: {len(seen)} shapes screened, {len(starts)} Nelder-Mead starts{note_static}"
    return ShapeResult(float(k1), float(k2), float(eta), float(t_best) if t_best < INFEASIBLE else None,
                       table_shape, None if t_table is None or t_table >= INFEASIBLE else float(t_table), len(seen), note,
                       float(arch), k3, k4, mid, li_best)


#: ``--time optimal``: shapes judged by the optimal law itself after the screened search, besides the screened
#: winner and the table's shape (each costs a law solve, ~0.15 s on the Adept cycle): 0 = none (the default).
#: bench/bench_free_path.py measures what a budget buys against the free-path minimum time
LAW_POLISH_EVALS = 0
#: the law-judged search's trust region (COBYQA's first and last radius, in the family's parameters: k1, k2, η,
#: arch/h, k3, k4, mid). COBYQA builds a quadratic model of the law's duration from its evaluations, and reaches
#: further with the same budget than Nelder-Mead (the search before it): on the Adept cycle, 60 law solves from the
#: screened shape gave 1.0109 × the free-path reference against 1.0146 × (``python bench/bench_shape_limit.py``)
LAW_POLISH_RADIUS = (0.05, 1e-4)


def judge_by_law(task, profile, found: ShapeResult, model_of, hold_capacity: bool, evals: int = 0) -> ShapeResult:
    """``--time optimal``: the screened winner ``found``, Li's family's best and the table's shape judged by the duration of the
    optimal law on each (the screen ranks shapes by the uniform law's fit, with the capacity by Eq. 26's auto: a
    shape faster for the uniform law can be slower for the optimal one), the faster kept; then, with ``evals`` > 0,
    COBYQA (scipy's model-based derivative-free solver) over the widened family (k1, k2, η, arch/h, k3, k4, mid)
    from it with the law's duration as the objective (at most ``evals`` more law solves)."""
    from scipy.optimize import minimize

    from ..model.errors import PickplaceError
    from ..model.task import Task
    from ..paths import plan_path
    from . import choose_optimal

    dwell = profile.planning.dwell
    seen: dict = {}

    def law_time(x: np.ndarray) -> float:
        key = tuple(np.round(x, 12))
        if key not in seen:
            k1, k2, eta, arch, k3, k4, mid = (float(v) for v in x)
            wide = {} if (k3, k4, mid) == (k1, k2, 0.5) else {"k3": k3, "k4": k4, "mid": mid}
            try:
                path = plan_path(Task(task.p_from, task.p_to, task.height, eta), "bspline", k1=k1, k2=k2,
                                 arch=arch * task.height, **wide)
                seen[key] = choose_optimal(path, profile, model_of(path), dwell, model_of,
                                           hold_capacity=hold_capacity)[0].seconds
            except PickplaceError:
                seen[key] = 1e12
        return seen[key]

    bounds = [K_SEARCH, K_SEARCH, ETA_RANGE, ARCH_RANGE, K_SEARCH, K_SEARCH, MID_SEARCH]
    x0 = np.array([found.k1, found.k2, found.eta, found.arch / task.height,
                   found.k1 if found.k3 is None else found.k3, found.k2 if found.k4 is None else found.k4,
                   0.5 if found.mid is None else found.mid])
    cands, names = [x0], ["the screened shape"]
    for other, name in ((found.symmetric, "Li's family's best"), (found.table, "the table's shape")):
        if other is not None:
            k1, k2, eta = other
            cands.append(np.array([k1, k2, eta, 0.0, k1, k2, 0.5]))
            names.append(name)
    x = min(cands, key=law_time)
    judged = len(seen)  # the candidates' solves, before the search's own
    if evals > 0:
        lo, hi = np.array([b[0] for b in bounds]), np.array([b[1] for b in bounds])
        res = minimize(law_time, np.clip(x, lo, hi), method="COBYQA", bounds=bounds,
                       options={"maxfev": evals, "initial_tr_radius": LAW_POLISH_RADIUS[0],
                                "final_tr_radius": LAW_POLISH_RADIUS[1]})
        if law_time(res.x) < law_time(x):
            x = res.x
    solves = f"{len(seen)} law solves: {judged} of the candidates, {len(seen) - judged} of the search"
    if x is x0:
        if evals <= 0:
            return found
        return replace(found, evaluations=found.evaluations + len(seen),
                       note=f"{found.note}; no shape judged faster by the optimal law itself ({solves})")
    k1, k2, eta, arch, k3, k4, mid = (float(v) for v in x)
    sym = (k3, k4, mid) == (k1, k2, 0.5)
    which = next((name for c, name in zip(cands, names) if x is c), "a shape")
    return ShapeResult(k1, k2, eta, found.t_screen, found.table, found.t_table_screen, found.evaluations + len(seen),
                       f"{found.note}; {which} judged faster by the optimal law itself ({solves})",
                       arch * task.height, None if sym else k3, None if sym else k4, None if sym else mid)
