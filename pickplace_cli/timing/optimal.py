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
#: uniform points of the optimiser's grid in τ (plus the path's knots and both sides of every jump)
LAW_GRID = 161
#: the optimiser keeps every constraint this far below its limit (the continuous check decides)
LAW_MARGIN = 0.0
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
#: uniform points of the denser grid whose broken rows join the optimiser's grid (``LAW_CHECK_ROUNDS`` at most;
#: a row counts as broken beyond ``LAW_CHECK_TOL`` of its limit)
LAW_CHECK_GRID = 1001
LAW_CHECK_ROUNDS = 2
LAW_CHECK_TOL = 1e-5
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


def _basis(knots: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(B, B′, B″): the cubic B-spline basis on ``knots`` (full, end knots repeated) and its derivatives at x."""
    from scipy.interpolate import BSpline

    n = len(knots) - 4
    spl = BSpline(knots, np.eye(n), 3, extrapolate=False)
    xc = np.clip(x, knots[0], knots[-1])
    return np.nan_to_num(spl(xc)), np.nan_to_num(spl.derivative(1)(xc)), np.nan_to_num(spl.derivative(2)(xc))


def _law_grid(path, points: int = 0, spans: bool = True, clustered: bool = False) -> np.ndarray:
    """The optimiser's τ grid: ``points`` (default ``LAW_GRID``) uniform points (``clustered``: Chebyshev-spaced,
    denser towards the ends, where the path is slow and the law varies most), the path's knots, both sides
    of every jump and (``spans``) the check's Gauss-Kronrod nodes of every span."""
    from ..limits.grid import interior_jumps, jump_sides, span_nodes

    u = np.linspace(0.0, 1.0, points or LAW_GRID)
    parts = [0.5 * (1.0 - np.cos(np.pi * u)) if clustered else u, np.asarray(path.breakpoints, float),
             jump_sides(path.breakpoints, path.jumps)]
    if spans:
        parts.append(span_nodes(path.breakpoints, path.jumps)[1])
    g = np.unique(np.clip(np.concatenate(parts), 0.0, 1.0))
    j = interior_jumps(path.breakpoints, path.jumps)
    return g[~np.isin(g, j)]  # the jump itself is represented by its two sides


def _inertia_along(model, tau: np.ndarray, p: np.ndarray, p1: np.ndarray) -> np.ndarray:
    """m(τ): the motor torque of acceleration p′(τ) at rest at p(τ) (the inertia along the path)."""
    z = np.zeros_like(p)
    motion: tuple = (p, z, p1, z)
    angle = model.path.angle_orders(tau)
    if angle is not None:  # the tool's turn accelerates along with the path, from rest
        motion += (np.stack([angle[0], np.zeros(len(tau)), angle[1], np.zeros(len(tau))]),)
    return model.parts(tau, derivatives=False, motion=motion, singularity=False).Am


class _Problem:
    """The law's optimisation problem on one τ grid: ``objective(x)`` → (duration [s], gradient),
    ``subset(keep)`` → a function x ↦ (values ≥ 0 when feasible, Jacobian) of the grid rows ``keep`` and the RMS
    rows, ``values(x)`` → every row's value; ``n_rows`` grid rows (the RMS rows follow them)."""

    def __init__(self, model, tau: np.ndarray, knots: np.ndarray, t_fit: float, dwell: float, capacity,
                 data: "_GridData | None" = None) -> None:
        self.__dict__.update(_problem(model, tau, knots, t_fit, dwell, capacity, data))


class _GridData:
    """The model's terms of the law's rows (:func:`_problem`) evaluated once on a union of τ grids and taken by
    index for each grid of one :func:`optimal_law` call (the coarse, fine, check and refined grids share most of
    their points, and each model evaluation has a fixed cost: one evaluation instead of one per grid). A τ not
    yet held is evaluated and merged in. Every term is computed point by point, so a grid's rows are those of
    its own evaluation."""

    FIELDS = ("qd1", "qdd1", "qddd1", "Am", "Gm", "dAm", "dGm", "p1", "p2", "p3", "m", "dm")

    def __init__(self, model, tau: np.ndarray) -> None:
        self.model = model
        self.tau = np.zeros(0)
        self.arrays: dict = {}
        self._add(np.unique(np.asarray(tau, float)))

    def _add(self, tau: np.ndarray) -> None:
        model, path = self.model, self.model.path
        pr = model.parts(tau)
        p, p1, p2, p3 = path.all_orders(tau)
        m = _inertia_along(model, tau, p, p1)
        h = 1e-5
        lo, hi = np.clip(tau - h, 0.0, 1.0), np.clip(tau + h, 0.0, 1.0)
        plo, phi = path.all_orders(lo), path.all_orders(hi)
        dm = (_inertia_along(model, hi, phi[0], phi[1]) - _inertia_along(model, lo, plo[0], plo[1])) / (hi - lo)[:, None]
        new = {"qd1": pr.qd1, "qdd1": pr.qdd1, "qddd1": pr.qddd1, "Am": pr.Am, "Gm": pr.Gm, "dAm": pr.dAm,
               "dGm": pr.dGm, "p1": p1, "p2": p2, "p3": p3, "m": m, "dm": dm}
        if not len(self.tau):
            self.tau, self.arrays = tau, new
            return
        allt = np.concatenate([self.tau, tau])
        order = np.argsort(allt, kind="stable")
        self.tau = allt[order]
        self.arrays = {k: np.concatenate([self.arrays[k], new[k]])[order] for k in self.FIELDS}

    def take(self, tau: np.ndarray):
        """The terms at ``tau`` (sorted, unique), as a namespace of arrays."""
        from types import SimpleNamespace

        i = np.clip(np.searchsorted(self.tau, tau), 0, max(len(self.tau) - 1, 0))
        miss = self.tau[i] != tau if len(self.tau) else np.ones(len(tau), bool)
        if miss.any():
            self._add(np.unique(tau[miss]))
            i = np.searchsorted(self.tau, tau)
        return SimpleNamespace(**{k: v[i] for k, v in self.arrays.items()})


def _limit_rows(model, pr, m: np.ndarray, dm: np.ndarray, tool: tuple, capacity) -> tuple[list, list]:
    """The limited quantities over grid × joints, as two groups of rows, each row y = c0·b + c1·b′ + c2·b″ + c3:

    * linear rows (joint acceleration, motor torque; both signs): y ≤ L, entries (c (4, N), L);
    * quadratic rows (speeds, jerk, torque rate, the tool's capacity): b^p·‖y‖² ≤ L², y a vector of ≤ 3
      components, entries (c (4, N, 3), L, p).

    ``tool``: the path's first three τ-derivatives on the grid."""
    p1, p2, p3 = tool
    n = len(p1)
    zero = np.zeros(n)

    def vec(*cs):  # scalar coefficients → (4, N, 3) with the value in the first component
        out = np.zeros((4, n, 3))
        for k, c in enumerate(cs):
            out[k, :, 0] = c
        return out

    lin: list = []
    quad: list = []
    for i, spec in enumerate(model.specs):
        lim, drv = spec.limits, spec.drive
        q1, q2, q3 = pr.qd1[:, i], pr.qdd1[:, i], pr.qddd1[:, i]
        if lim.velocity is not None:  # b·q′² ≤ L²
            quad.append((vec(zero, zero, zero, q1), lim.velocity, 1))
        if lim.acceleration is not None:  # |q″b + q′b′/2| ≤ L
            c = np.array([q2, q1 / 2, zero, zero])
            lin += [(c, lim.acceleration), (-c, lim.acceleration)]
        if lim.jerk is not None:  # b·(q‴b + 3/2·q″b′ + q′b″/2)² ≤ L²
            quad.append((vec(q3, 1.5 * q2, q1 / 2, zero), lim.jerk, 1))
        if drv is not None:
            if drv.max_speed is not None:
                quad.append((vec(zero, zero, zero, drv.gear_ratio * q1), drv.max_speed, 1))
            if drv.peak_torque is not None:  # |A_m b + m b′/2 + G_m| ≤ L
                c = np.array([pr.Am[:, i], m[:, i] / 2, zero, pr.Gm[:, i]])
                lin += [(c, drv.peak_torque), (-c, drv.peak_torque)]
            if drv.torque_rate is not None:  # b·(A_m′b + (A_m + m′/2)b′ + m b″/2 + G_m′)² ≤ L²
                quad.append((vec(pr.dAm[:, i], pr.Am[:, i] + dm[:, i] / 2, m[:, i] / 2, pr.dGm[:, i]),
                             drv.torque_rate, 1))
    if capacity is not None:
        z3 = np.zeros_like(p1)
        quad.append((np.array([z3, z3, z3, p1]), capacity.velocity, 1))  # b‖p′‖² ≤ [v]²
        quad.append((np.array([p2, p1 / 2, z3, z3]), capacity.acceleration, 0))  # ‖p″b + p′b′/2‖² ≤ [a]²
        if capacity.jerk:
            quad.append((np.array([p3, 1.5 * p2, p1 / 2, z3]), capacity.jerk, 1))
    return lin, quad


def _stack(lin: list, quad: list, n: int) -> dict:
    """The row groups as flat arrays: grid index, coefficients scaled by the limit, b's exponent."""
    idx = np.arange(n)
    out = {}
    if lin:
        out["lin_g"] = np.concatenate([idx] * len(lin))
        out["lin_c"] = np.concatenate([c / L for c, L in lin], axis=1).T  # (R, 4)
    else:
        out["lin_g"], out["lin_c"] = np.zeros(0, int), np.zeros((0, 4))
    if quad:
        out["quad_g"] = np.concatenate([idx] * len(quad))
        out["quad_c"] = np.concatenate([c / L for c, L, _ in quad], axis=1).transpose(1, 0, 2)  # (R, 4, 3)
        out["quad_p"] = np.concatenate([np.full(n, p, float) for _, _, p in quad])
    else:
        out["quad_g"], out["quad_c"], out["quad_p"] = np.zeros(0, int), np.zeros((0, 4, 3)), np.zeros(0)
    return out


def _rows(rows: dict, b: np.ndarray, b1: np.ndarray, b2: np.ndarray, jac: bool = True) -> tuple:
    """Values (≥ 0 when feasible) of the rows ``rows`` (a :func:`_stack` dict or a subset of it) at the law's
    (b, b′, b″) on the grid, and with ``jac`` the coefficients (a0, a1, a2) of each row's gradient in
    (b, b′, b″) at its grid point."""
    g, cl = rows["lin_g"], rows["lin_c"]
    v_lin = 1.0 - (cl[:, 0] * b[g] + cl[:, 1] * b1[g] + cl[:, 2] * b2[g] + cl[:, 3])
    g, c, p = rows["quad_g"], rows["quad_c"], rows["quad_p"]
    bq = b[g]
    y = c[:, 0] * bq[:, None] + c[:, 1] * b1[g][:, None] + c[:, 2] * b2[g][:, None] + c[:, 3]
    n2 = np.einsum("ij,ij->i", y, y)
    bp = np.where(p > 0, bq, 1.0)
    vals = np.concatenate([v_lin, 1.0 - bp * n2])
    if not jac:
        return vals
    a0 = np.concatenate([-cl[:, 0], -(p * n2 + 2 * bp * np.einsum("ij,ij->i", y, c[:, 0]))])
    a1 = np.concatenate([-cl[:, 1], -2 * bp * np.einsum("ij,ij->i", y, c[:, 1])])
    a2 = np.concatenate([-cl[:, 2], -2 * bp * np.einsum("ij,ij->i", y, c[:, 2])])
    return vals, a0, a1, a2


def _problem(model, tau: np.ndarray, knots: np.ndarray, t_fit: float, dwell: float, capacity,
             data: _GridData | None = None) -> dict:
    pr = (data or _GridData(model, tau)).take(tau)
    p1, p2, p3, m, dm = pr.p1, pr.p2, pr.p3, pr.m, pr.dm

    B0, B1, B2 = _basis(knots, tau)
    w = np.zeros(len(tau))  # trapezoid weights on the grid
    dt = np.diff(tau)
    w[:-1] += dt / 2
    w[1:] += dt / 2
    scale = 1.0 / t_fit**2  # b = scale · (B0 @ x): x ≡ 1 is the uniform law at t_fit
    B0s, B1s, B2s = B0 * scale, B1 * scale, B2 * scale

    rows = _stack(*_limit_rows(model, pr, m, dm, (p1, p2, p3), capacity), len(tau))
    n_lin = len(rows["lin_g"])
    n_rows = n_lin + len(rows["quad_g"])
    rated = [(i, s.drive.rated_torque) for i, s in enumerate(model.specs) if s.drive and s.drive.rated_torque]
    ri = [i for i, _ in rated]
    A_r, m_r, G_r = pr.Am[:, ri], m[:, ri], pr.Gm[:, ri]
    hold_r = dwell * (pr.Gm[0, ri] ** 2 + pr.Gm[-1, ri] ** 2)
    r2_r = np.array([r for _, r in rated], float) ** 2

    def state(x):
        return B0s @ x, B1s @ x, B2s @ x

    def objective(x):
        b = B0s @ x
        return w @ b**-0.5, (w * -0.5 * b**-1.5) @ B0s

    def rms_rows(b, b1):
        """RMS over the duty cycle, one row per rated joint: (2∫τ²/√b dτ + dwell·(G0² + G1²)) / (2T + 2·dwell)
        ≤ rated²: (values, Jacobian)."""
        if not rated:
            return np.zeros(0), np.zeros((0, B0.shape[1]))
        ib = b**-0.5
        Tn = w @ ib
        dT = (w * -0.5 * ib**3) @ B0s
        tq = A_r * b[:, None] + m_r / 2 * b1[:, None] + G_r  # (N, k): every rated joint at once
        wt = (w * ib)[:, None] * tq
        I = np.einsum("nk,nk->k", wt, tq)
        dI = (2 * wt * A_r - 0.5 * (w * ib**3)[:, None] * tq**2).T @ B0s + (wt * m_r).T @ B1s
        den = 2 * Tn + 2 * dwell
        ms = (2 * I + hold_r) / den
        dms = (2 * dI * den - (2 * I + hold_r)[:, None] * 2 * dT) / den**2
        return 1.0 - ms / r2_r, -dms / r2_r[:, None]

    def subset(keep=None):
        """x ↦ (values ≥ 0 when feasible, Jacobian) of the grid rows ``keep`` (all: None) and the RMS rows."""
        if keep is None:
            keep = np.ones(n_rows, bool)
        kl, kq = keep[:n_lin], keep[n_lin:]
        sub = {"lin_g": rows["lin_g"][kl], "lin_c": rows["lin_c"][kl], "quad_g": rows["quad_g"][kq],
               "quad_c": rows["quad_c"][kq], "quad_p": rows["quad_p"][kq]}
        g = np.concatenate([sub["lin_g"], sub["quad_g"]])
        G0, G1, G2 = B0s[g], B1s[g], B2s[g]

        def evaluate(x):
            b, b1, b2 = state(x)
            v, a0, a1, a2 = _rows(sub, b, b1, b2)
            J = a0[:, None] * G0 + a1[:, None] * G1 + a2[:, None] * G2
            rv, rJ = rms_rows(b, b1)
            return np.concatenate([v, rv]) - LAW_MARGIN, np.vstack([J, rJ])

        return evaluate

    def values(x):
        """Every row's value (grid rows, then RMS rows), no Jacobian."""
        b, b1, b2 = state(x)
        return np.concatenate([_rows(rows, b, b1, b2, jac=False), rms_rows(b, b1)[0]]) - LAW_MARGIN

    return {"objective": objective, "subset": subset, "values": values, "n_rows": n_rows, "tau": tau,
            "row_tau": tau[np.concatenate([rows["lin_g"], rows["quad_g"]])]}


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


@single_blas_thread
def optimal_law(model, dwell: float, t_fit: float, coefficients: int | None = None,
                capacity=None, start: np.ndarray | None = None, direct: bool = False) -> LawResult:
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
    solves)."""
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


def _knots(coefficients: int) -> np.ndarray:
    """The law's knots: uniform in τ, the ends repeated (cubic)."""
    return np.concatenate([[0.0] * 3, np.linspace(0.0, 1.0, coefficients - 2), [1.0] * 3])


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

    return BSpline(knots, coef, 3, extrapolate=False)
