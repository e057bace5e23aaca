"""The optimiser of Eq. (37) for the velocity-constrained B-spline [Yang2022, Sec. 2.3]: multi-start.

The problem (path, parameters, evaluation) is :mod:`pickplace_cli.curves.vel_problem`; the SLSQP stages in
epigraph form, stepped in lockstep, are :mod:`pickplace_cli.lookup.vel_slsqp`.

**How the optimum is found.** Each stage of Eq. (37) is a minimax over τ, solved by SLSQP in epigraph
form: minimise t subject to m_k(p) ≤ t, where m_k is the exact maximum of ‖a‖² (‖j‖²) on the k-th of
three equal segments of each knot span (from the roots of its derivative: a is cubic on a span), with
Jacobians exact in λ (the path is affine in λ) and by central differences in the four knots, evaluated
as one numpy batch (:class:`_Evaluator`: the Taylor coefficients per span of the spline of Eq. 16 for
many parameter vectors at once, solved in piecewise-Taylor form; tests hold them to the B-spline route
and to scipy). The cost is per numpy call rather than per vector, so SLSQP runs advance together
(:class:`_Lockstep`: scipy's SLSQP routine stepped, one batched evaluation per round for all runs;
a test holds each run to ``scipy.optimize.minimize``). F has more than one local
maximum and a_max, j_max more than one local minimum, so :func:`solve` is a multi-start: the paper's
initial guess and a quasi-random (Kronecker) sample of the feasible set are evaluated in one pass, and
SLSQP runs from the best distinct ones (for a_max and j_max also from the best start with both end
knots off the margin; for F from the best sampled point and from the midpoint of the two minimisers).
Where the shipped table applies, :func:`solve_seeded` (the default "exact" solver) starts each stage
from the table's seeds for that stage (the interpolated optimum and the 32 corner optima of the query's
cell; the table stores the minimisers of a_max and j_max too) and screens the multi-start's starts
(loosely) alongside, polishing one when it beats the seed's result; the F stage starts as soon as the
two stage-1 runs from the seeds are done. Reported peaks are exact (``bspline.norm_peaks``). A test
compares with scipy's differential_evolution.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..curves.vel_problem import PAPER_INITIAL, PARAM_NAMES, VelProblem, VelSettings, _Evaluator, _grid, exact_peaks
from .vel_slsqp import _eval_stages, _Lockstep, _LockstepSLSQP, _run_slsqp, _Space, _Stage

# ------------------------------------------------------------------------------------------ optimiser


@dataclass(frozen=True)
class VelResult:
    """Optimum of Eq. (37) for one problem (peaks normalised: lengths / scale, T = 1).

    ``params`` (τ6, τ7, τ9, τ10, λ1, λ2, λ3); ``a_max``, ``j_max``, ``v_max`` exact peaks there; ``a_min``,
    ``j_min`` the stage-1 minima (the normalisers of F); ``F`` ≤ 2; ``lambda_free`` which λ were optimised;
    ``params_a``, ``params_j`` the minimisers of a_max and j_max; ``evaluations`` parameter vectors evaluated.
    """

    params: tuple[float, ...]
    a_max: float
    j_max: float
    v_max: float
    a_min: float
    j_min: float
    F: float
    lambda_free: tuple[bool, bool, bool]
    params_a: tuple[float, ...]
    params_j: tuple[float, ...]
    settings: VelSettings = field(default_factory=VelSettings)
    evaluations: int = 0

    def as_dict(self) -> dict[str, Any]:
        d = dict(zip(PARAM_NAMES, self.params))
        d.update(F=self.F, a_min=self.a_min, j_min=self.j_min, margin=self.settings.margin,
                 lambda_free=list(self.lambda_free))
        return d


def _quasi_random(n: int, d: int) -> np.ndarray:
    """n points of the unit cube [0, 1)^d from the Kronecker (R_d) low-discrepancy sequence: frac(k·α) with
    α_i = φ_d^−i, φ_d the real root of x^(d+1) = x + 1 (Roberts 2018). Deterministic, no import cost."""
    phi = 2.0
    for _ in range(40):
        phi = (1.0 + phi) ** (1.0 / (d + 1))
    alpha = phi ** -np.arange(1, d + 1)
    return np.mod(0.5 + np.arange(1, n + 1)[:, None] * alpha[None, :], 1.0)


def _distinct_best(x: np.ndarray, values: np.ndarray, count: int, radius: float = 0.05) -> list[np.ndarray]:
    order = np.argsort(values)
    picked: list[np.ndarray] = []
    for i in order:
        if all(np.max(np.abs(x[i] - y)) > radius for y in picked):
            picked.append(x[i])
            if len(picked) == count:
                break
    return picked


def solve(prob: VelProblem, settings: VelSettings = VelSettings(), warm: VelResult | None = None) -> VelResult:
    """The two-stage optimum of [Yang2022, Eq. (37)] under Eq. (36) with ``settings.margin``.

    Global: coarse quasi-random candidates, then SLSQP from the best distinct ones (module docstring).
    ``warm``: the optimum of a nearby problem (e.g. the same move at a slightly different duration); each
    stage then runs once, from that optimum's own point — a local continuation, used while searching
    over T; the caller confirms the end result with a global solve."""
    ev = _Evaluator(prob)
    free = prob.lambda_free
    space = _Space(free, settings.margin)
    if warm is not None and tuple(warm.lambda_free) == tuple(free):
        starts = {k: space.clip(np.asarray(p)[space.free]) for k, p in (("a", warm.params_a), ("j", warm.params_j), ("F", warm.params))}
        cand = np.vstack(list(starts.values()))
        pick = {"a": [starts["a"]], "j": [starts["j"]]}
    else:
        cand = space.from_unit(_quasi_random(settings.starts, space.n))
        cand = np.vstack([np.array(PAPER_INITIAL)[space.free][None, :], cand])
        starts = None
    ga, gj = ev.sampled(space.full(cand), *_grid(settings.samples_per_piece))
    amax, jmax = ga.max(axis=1), gj.max(axis=1)
    a_norm, j_norm = float(amax.min()), float(jmax.min())
    if starts is None:
        # min a_max and min j_max can each have a local minimum with an end knot on the margin (τ6 = m or
        # τ10 = 1 − m) and another inside: start from the best candidate of each kind
        inner = (cand[:, 0] >= 3 * settings.margin) & (cand[:, 3] <= 1 - 3 * settings.margin)
        pick = {}
        for kind, vals in (("a", amax), ("j", jmax)):
            best = _distinct_best(cand, vals, settings.refine, settings.radius)
            if not inner[int(np.argmin(vals))] and inner.any():
                best = best[:1] + [cand[inner][int(np.argmin(vals[inner]))]] + best[1:]
            pick[kind] = best[: max(settings.refine, 2)]

    def exact(x: np.ndarray) -> tuple[float, float, float]:
        return exact_peaks(prob, space.full(x)[0])

    best = {}
    stages = {kind: _Stage(ev, space, kind, a_norm, j_norm, settings) for kind in ("a", "j")}
    jobs = [(kind, stages[kind].run(x0)) for kind in ("a", "j") for x0 in pick[kind]]
    done = list(zip([kind for kind, _ in jobs], _run_slsqp([r for _, r in jobs])))  # all runs together
    for kind, idx in (("a", 1), ("j", 2)):
        runs = [x for k, x in done if k == kind]
        peaks = [exact(x)[idx] for x in runs]
        k = int(np.argmin(peaks))
        best[kind] = (runs[k], peaks[k])
    xa, a_min = best["a"]
    xj, j_min = best["j"]
    if starts is None:
        pool = np.vstack([cand, xa, xj])
        ga, gj = ev.sampled(space.full(pool), *_grid(settings.samples_per_piece))
        f_pool = a_min / np.sqrt(ga.max(axis=1)) + j_min / np.sqrt(gj.max(axis=1))
        # the best sampled candidate (often the minimiser of j_max), the midpoint of the two minimisers and
        # the minimiser of a_max: F trades a_max against j_max, and its basins lie between the two
        order = [pool[int(np.argmax(f_pool))], (xa + xj) / 2, xa] + _distinct_best(pool, -f_pool, settings.refine_F)
        f_starts = _distinct_best(np.array(order), np.arange(len(order)), settings.refine_F, radius=1e-3)
    else:
        f_starts = [starts["F"]]
    stage = _Stage(ev, space, "F", a_norm, j_norm, settings)
    if len(f_starts) > 2:
        # screen every start with a loose tolerance, then polish the best one (basins differ by > 1e-3 in F)
        screened = _run_slsqp([stage.run(x0, a_min, j_min, settings.screen_ftol, settings.screen_maxiter) for x0 in f_starts])
        f_starts = [min(screened, key=lambda x: stage.objective(x, a_min, j_min))]
    runs = _run_slsqp([stage.run(x0, a_min, j_min) for x0 in f_starts])
    scored = []
    for x in runs:
        v, a, j = exact(x)
        scored.append((a_min / a + j_min / j, x, v, a, j))
    F, x, v, a, j = max(scored, key=lambda s: s[0])
    full = tuple(float(c) for c in space.full(x)[0])
    return VelResult(
        full, a, j, v, a_min, j_min, float(F), free,
        tuple(float(c) for c in space.full(xa)[0]), tuple(float(c) for c in space.full(xj)[0]),
        settings, ev.count,
    )


class _Group:
    """One stage of :func:`solve_seeded`: SLSQP from ``first`` (the lead) and from each other start 1e-3 away from it whose
    objective is below ``bound`` (screens, ``screen_ftol``); a finished screen that beats the lead's
    result is polished (full tolerance); ``best`` (x, objective) once the lead is done."""

    def __init__(self, lock: _Lockstep, settings: VelSettings, stage: _Stage, first: np.ndarray, others: list[np.ndarray],
                 norms: tuple, bound: float):
        self.stage, self.norms, self.lock, self.settings = stage, norms, lock, settings
        self.max_rounds = settings.max_rounds
        others = [x0 for x0 in others if np.max(np.abs(x0 - first)) > 1e-3]
        if math.isfinite(bound):  # check_ratio: the starts' objectives (in one batch)
            _eval_stages([(stage, x0) for x0 in others])
            others = [x0 for x0 in others if stage.objective(x0, *norms) < bound]
        # (the runs' first evaluations come with the next round's batch)
        self.lead = lock.add(stage.run(first, *norms, max_rounds=self.max_rounds))
        self.screens = [
            lock.add(stage.run(x0, *norms, ftol=self.settings.screen_ftol, maxiter=self.settings.screen_maxiter,
                               max_rounds=self.max_rounds))
            for x0 in others
        ]
        self.polishes: list[_LockstepSLSQP] = []
        self.best: tuple[np.ndarray, float] | None = None
        self.handled: set[int] = set()

    def runs(self) -> list[_LockstepSLSQP]:
        return [self.lead, *self.screens, *self.polishes]

    def pending(self) -> list[tuple[_Stage, np.ndarray]]:
        """The results :meth:`update` will judge (to evaluate in one batch with other groups')."""
        return [(self.stage, st.result()) for st in self.runs() if st.done and id(st) not in self.handled]

    def update(self) -> None:
        """Take the results of runs finished since the last call (their objectives in one batch)."""
        fresh = [st for st in self.runs() if st.done and id(st) not in self.handled]
        if self.best is None and self.lead not in fresh:
            return  # the screens are judged against the lead's result
        self.handled.update(id(st) for st in fresh)
        xs = [st.result() for st in fresh]
        _eval_stages([(self.stage, x) for x in xs])
        for st, x in zip(fresh, xs):
            f = self.stage.objective(x, *self.norms)
            if st is self.lead:
                self.best = (x, f) if self.best is None or f < self.best[1] else self.best
        for st, x in zip(fresh, xs):
            f = self.stage.objective(x, *self.norms)
            if st in self.screens and np.max(np.abs(x - self.best[0])) > 1e-3 and f < self.best[1]:
                self.polishes.append(self.lock.add(self.stage.run(x, *self.norms, max_rounds=self.max_rounds)))
            elif st in self.polishes and f < self.best[1]:
                self.best = (x, f)


def solve_seeded(prob: VelProblem, seeds: dict[str, np.ndarray], settings: VelSettings = VelSettings(),
                 check: bool = True) -> VelResult:
    """The two-stage optimum of [Yang2022, Eq. (37)] started from ``seeds``: for each stage ("a", "j",
    "F") a (k, 7) array of full parameter vectors near its optimum, e.g. the table's interpolated answer
    and the 32 corner optima of its cell (``VelTable.seeds``), each a global optimum of a nearby problem.

    Each stage is solved from the seed of that stage with the best sampled objective (the table's nodes
    carry the basins that are optimal nearby), and other starts are screened (``screen_ftol``,
    ``check_ratio``) at the same time; a screen that beats the seed's result is polished. Without ``check``
    (the "seeded" solver) the only other start is the interpolated F seed. With ``check`` (the "exact"
    solver) they are the multi-start's starts of :func:`solve`, from its quasi-random sample evaluated in
    the same batch as the seeds: for a_max and j_max the best two distinct sampled candidates and the best
    with both end knots off the margin, for F the best sampled candidate (minimisers included) and the
    midpoint of the two minimisers.

    All runs advance together (:class:`_Lockstep`, one batched evaluation per round). The F stage needs
    a_min and j_min, so it starts when both stage-1 runs from the seeds are done, while the stage-1 screens
    run on; if a screen then finds a lower minimum (its polish beats the seed's), the F stage restarts with
    the new normalisers. A run is cut off after ``max_rounds`` rounds (its best feasible point counts).
    Peaks and F are exact at the result."""
    ev = _Evaluator(prob)
    space = _Space(prob.lambda_free, settings.margin)
    rows = {k: np.vstack([space.clip(np.asarray(r, float)[space.free]) for r in np.atleast_2d(v)])
            for k, v in seeds.items()}
    sample = space.from_unit(_quasi_random(settings.starts, space.n)) if check else np.empty((0, space.n))
    sample = np.vstack([np.array(PAPER_INITIAL)[space.free][None, :], sample])
    pool = np.vstack([rows["a"], rows["j"], rows["F"], sample])
    ga, gj = ev.grid_maxima(space.full(pool), settings.samples_per_piece)
    amax, jmax = np.sqrt(ga), np.sqrt(gj)
    a_norm, j_norm = float(amax.min() ** 2), float(jmax.min() ** 2)
    offset = {"a": 0, "j": len(rows["a"]), "F": len(rows["a"]) + len(rows["j"])}
    in_sample = slice(offset["F"] + len(rows["F"]), None)

    def exact(x: np.ndarray) -> tuple[float, float, float]:
        return exact_peaks(prob, space.full(x)[0])

    lock = _Lockstep()

    sample, s_amax, s_jmax = pool[in_sample], amax[in_sample], jmax[in_sample]
    inner = (sample[:, 0] >= 3 * settings.margin) & (sample[:, 3] <= 1 - 3 * settings.margin)
    stage1 = []
    c = settings.check_ratio
    for kind, vals, s_vals in (("a", amax, s_amax), ("j", jmax, s_jmax)):
        stage = _Stage(ev, space, kind, a_norm, j_norm, settings)
        seg = slice(offset[kind], offset[kind] + len(rows[kind]))
        others = []
        if check:
            # stage 1 is multimodal (an end knot on the margin or inside, and the table's cell may straddle
            # a switch between basins): also the multi-start's starts, the best candidate of the pool and
            # the best with both end knots off the margin
            others += _distinct_best(sample, s_vals, settings.refine, settings.radius)
            if inner.any():
                others.append(sample[inner][int(np.argmin(s_vals[inner]))])
        i0 = int(np.argmin(vals[seg]))
        # check_ratio: screen only starts whose sampled peak is within c of the seed's sampled peak
        bound = float(vals[seg][i0] ** 2 / stage.norm[0 if kind == "a" else 1]) * c * c if math.isfinite(c) else np.inf
        stage1.append(_Group(lock, settings, stage, pool[seg][i0], others, (), bound))
    ga1, gj1 = stage1

    def stage_F(xa: np.ndarray, fa: float, xj: np.ndarray, fj: float) -> tuple[_Group, float, float]:
        # the exact peaks (a stage's objective is its largest exact segment maximum of ‖a‖², ‖j‖² / scale)
        a_min, j_min = math.sqrt(fa * ga1.stage.norm[0]), math.sqrt(fj * gj1.stage.norm[1])
        stage = _Stage(ev, space, "F", a_norm, j_norm, settings)
        f_pool = a_min / amax + j_min / jmax
        seg = slice(offset["F"], offset["F"] + len(rows["F"]))
        others = [pool[seg][0]]  # the interpolated seed (after the best one)
        if check:
            # the multi-start's first F starts: the best sampled candidate of the pool and of the minimisers
            extra = np.vstack([xa, xj, (xa + xj) / 2])
            ga2, gj2 = ev.grid_maxima(space.full(extra), settings.samples_per_piece)
            f_extra = a_min / np.sqrt(ga2) + j_min / np.sqrt(gj2)
            allx, allf = np.vstack([pool, extra]), np.concatenate([f_pool, f_extra])
            others = [allx[int(np.argmax(allf))], extra[2]]
        return _Group(lock, settings, stage, pool[seg][int(np.argmax(f_pool[seg]))], others, (a_min, j_min), np.inf), a_min, j_min

    # The F stage starts as soon as both stage-1 leads are done, from their minima, while the stage-1
    # screens run on; a screen that finds a lower minimum (rare) restarts it with the new normalisers.
    gF, basis = None, None
    while True:
        _eval_stages([item for g in (ga1, gj1, gF) if g is not None for item in g.pending()])
        ga1.update()
        gj1.update()
        if ga1.best is not None and gj1.best is not None:
            now = (ga1.best[1], gj1.best[1])
            if basis != now:
                if gF is not None:
                    lock.drop(gF.runs())
                basis = now
                gF, a_min, j_min = stage_F(ga1.best[0], now[0], gj1.best[0], now[1])
            gF.update()
        if not lock.active:
            break
        lock.step()
    xa, xj, x = ga1.best[0], gj1.best[0], gF.best[0]
    v, a, j = exact(x)
    F = a_min / a + j_min / j
    return VelResult(
        tuple(float(c) for c in space.full(x)[0]), a, j, v, a_min, j_min, float(F), prob.lambda_free,
        tuple(float(c) for c in space.full(xa)[0]), tuple(float(c) for c in space.full(xj)[0]),
        settings, ev.count,
    )
