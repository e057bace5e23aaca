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

from dataclasses import dataclass

import numpy as np

#: cubic B-spline coefficients of b(τ) (uniform knots in τ); the benchmark compares with 2× as many
LAW_COEFFICIENTS = 20
#: uniform points of the optimiser's grid in τ (plus the path's knots and both sides of every jump)
LAW_GRID = 161
#: the optimiser keeps every constraint this far below its limit (the continuous check decides)
LAW_MARGIN = 0.0
#: bounds of the law's coefficients relative to the uniform law (b between 1/100 and 100 times 1/T_fit²:
#: the tool at most 10× slower or faster than uniform anywhere; keeps SLSQP away from b → 0 or ∞ at the
#: path's ends, where the rest-to-rest path leaves b nearly free)
LAW_BOUNDS = (1e-2, 1e2)
#: grid rows used by the full solve from the start: those above this fraction of their limit at its warm start
LAW_ACTIVE = 0.5
#: uniform points of the coarse first phase's grid (every row used); 0: no coarse phase
LAW_COARSE_GRID = 41
#: SLSQP's tolerance on the objective (the duration relative to T_fit): 1e-9 gives the same T to 4 digits as
#: 1e-10 on the Adept cycle for every method with fewer iterations (1e-7 lost up to 1 % on random moves)
LAW_FTOL = 1e-9
#: points of the table that inverts t(τ) for the composed path
LAW_TABLE = 4001


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


def _basis(knots: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(B, B′, B″): the cubic B-spline basis on ``knots`` (full, end knots repeated) and its derivatives at x."""
    from scipy.interpolate import BSpline

    n = len(knots) - 4
    spl = BSpline(knots, np.eye(n), 3, extrapolate=False)
    xc = np.clip(x, knots[0], knots[-1])
    return np.nan_to_num(spl(xc)), np.nan_to_num(spl.derivative(1)(xc)), np.nan_to_num(spl.derivative(2)(xc))


def _law_grid(path, points: int = 0, spans: bool = True) -> np.ndarray:
    """The optimiser's τ grid: ``points`` (default ``LAW_GRID``) uniform points, the path's knots, both sides
    of every jump and (``spans``) the check's Gauss-Kronrod nodes of every span."""
    from ..limits.grid import interior_jumps, jump_sides, span_nodes

    parts = [np.linspace(0.0, 1.0, points or LAW_GRID), np.asarray(path.breakpoints, float),
             jump_sides(path.breakpoints, path.jumps)]
    if spans:
        parts.append(span_nodes(path.breakpoints, path.jumps)[1])
    g = np.unique(np.clip(np.concatenate(parts), 0.0, 1.0))
    j = interior_jumps(path.breakpoints, path.jumps)
    return g[~np.isin(g, j)]  # the jump itself is represented by its two sides


def _inertia_along(model, tau: np.ndarray, p: np.ndarray, p1: np.ndarray) -> np.ndarray:
    """m(τ): the motor torque of acceleration p′(τ) at rest at p(τ) (the inertia along the path)."""
    z = np.zeros_like(p)
    return model.parts(tau, derivatives=False, motion=(p, z, p1, z), singularity=False).Am


class _Problem:
    """The law's optimisation problem on one τ grid: ``objective(x)`` → (T/T_fit-scaled duration, gradient),
    ``constraints(x, keep)`` → (values ≥ 0 when feasible, Jacobian) of the grid rows ``keep`` and the RMS
    rows, ``values(x)`` → every row's value; ``n_rows`` grid rows (the RMS rows follow them)."""

    def __init__(self, model, tau: np.ndarray, knots: np.ndarray, t_fit: float, dwell: float, capacity) -> None:
        self.__dict__.update(_problem(model, tau, knots, t_fit, dwell, capacity))


def _limit_rows(model, pr, m: np.ndarray, dm: np.ndarray, tool: tuple, capacity) -> list[tuple]:
    """The limited quantities, each as (kind, coefficient arrays, limit) over grid × joints: joint speed,
    acceleration, jerk, motor speed, torque and torque rate per joint spec, and the tool's capacity (``tool``:
    the path's first three τ-derivatives on the grid)."""
    p1, p2, p3 = tool
    rows: list[tuple] = []
    for i, spec in enumerate(model.specs):
        lim, drv = spec.limits, spec.drive
        q1, q2, q3 = pr.qd1[:, i], pr.qdd1[:, i], pr.qddd1[:, i]
        if lim.velocity is not None:
            rows.append(("speed", q1, lim.velocity))
        if lim.acceleration is not None:
            rows.append(("affine", (q2, q1 / 2, 0.0 * q1), lim.acceleration))
        if lim.jerk is not None:
            rows.append(("rate", (q3, 1.5 * q2, q1 / 2, 0.0 * q1), lim.jerk))
        if drv is not None:
            if drv.max_speed is not None:
                rows.append(("speed", drv.gear_ratio * q1, drv.max_speed))
            if drv.peak_torque is not None:
                rows.append(("affine", (pr.Am[:, i], m[:, i] / 2, pr.Gm[:, i]), drv.peak_torque))
            if drv.torque_rate is not None:
                rows.append(("rate", (pr.dAm[:, i], pr.Am[:, i] + dm[:, i] / 2, m[:, i] / 2, pr.dGm[:, i]),
                             drv.torque_rate))
    if capacity is not None:
        rows.append(("speed", np.linalg.norm(p1, axis=1), capacity.velocity))
        rows.append(("vaffine", (p2, p1 / 2), capacity.acceleration))
        if capacity.jerk:
            rows.append(("vrate", (p3, 1.5 * p2, p1 / 2), capacity.jerk))
    return rows


def _pointwise(rows: list[tuple], b: np.ndarray, b1: np.ndarray, b2: np.ndarray) -> tuple:
    """Every grid row: (values ≥ 0 when feasible, and the coefficients a0, a1, a2 of its gradient in
    (b, b′, b″)), each (R,); the row's Jacobian in x is (a0·B0 + a1·B1 + a2·B2)·scale at its grid point."""
    zero = np.zeros(len(b))
    vals, a0, a1, a2 = [], [], [], []
    for kind, c, limit in rows:
        L2 = limit**2
        if kind == "speed":  # c²·b ≤ L²
            vals.append(1.0 - c**2 * b / L2)
            a0.append(-(c**2) / L2), a1.append(zero), a2.append(zero)
        elif kind == "affine":  # |c0 b + c1 b′ + c2| ≤ L
            val = (c[0] * b + c[1] * b1 + c[2]) / limit
            vals += [1.0 - val, 1.0 + val]
            a0 += [-c[0] / limit, c[0] / limit]
            a1 += [-c[1] / limit, c[1] / limit]
            a2 += [zero, zero]
        elif kind == "rate":  # b·(c0 b + c1 b′ + c2 b″ + c3)² ≤ L²
            y = c[0] * b + c[1] * b1 + c[2] * b2 + c[3]
            vals.append(1.0 - b * y**2 / L2)
            a0.append(-(y**2 + 2 * b * y * c[0]) / L2)
            a1.append(-2 * b * y * c[1] / L2)
            a2.append(-2 * b * y * c[2] / L2)
        elif kind == "vaffine":  # ‖c0 b + c1 b′‖² ≤ L²
            v = c[0] * b[:, None] + c[1] * b1[:, None]
            vals.append(1.0 - np.sum(v * v, axis=1) / L2)
            a0.append(-2 * np.sum(v * c[0], axis=1) / L2)
            a1.append(-2 * np.sum(v * c[1], axis=1) / L2)
            a2.append(zero)
        elif kind == "vrate":  # b‖c0 b + c1 b′ + c2 b″‖² ≤ L²
            v = c[0] * b[:, None] + c[1] * b1[:, None] + c[2] * b2[:, None]
            n2 = np.sum(v * v, axis=1)
            vals.append(1.0 - b * n2 / L2)
            a0.append(-(n2 + 2 * b * np.sum(v * c[0], axis=1)) / L2)
            a1.append(-2 * b * np.sum(v * c[1], axis=1) / L2)
            a2.append(-2 * b * np.sum(v * c[2], axis=1) / L2)
    return np.concatenate(vals), np.concatenate(a0), np.concatenate(a1), np.concatenate(a2)


def _problem(model, tau: np.ndarray, knots: np.ndarray, t_fit: float, dwell: float, capacity) -> dict:
    path = model.path
    pr = model.parts(tau)
    p, p1, p2, p3 = path.all_orders(tau)
    m = _inertia_along(model, tau, p, p1)
    h = 1e-5
    lo, hi = np.clip(tau - h, 0.0, 1.0), np.clip(tau + h, 0.0, 1.0)
    plo, phi = path.all_orders(lo), path.all_orders(hi)
    dm = (_inertia_along(model, hi, phi[0], phi[1]) - _inertia_along(model, lo, plo[0], plo[1])) / (hi - lo)[:, None]

    B0, B1, B2 = _basis(knots, tau)
    w = np.zeros(len(tau))  # trapezoid weights on the grid
    dt = np.diff(tau)
    w[:-1] += dt / 2
    w[1:] += dt / 2
    scale = 1.0 / t_fit**2  # b = scale · (B0 @ x): x ≡ 1 is the uniform law at t_fit

    rows = _limit_rows(model, pr, m, dm, (p1, p2, p3), capacity)
    rated = [(i, s.drive.rated_torque) for i, s in enumerate(model.specs) if s.drive and s.drive.rated_torque]

    def state(x):
        b = scale * (B0 @ x)
        return b, scale * (B1 @ x), scale * (B2 @ x)

    def objective(x):
        b = scale * (B0 @ x)
        f = w @ b**-0.5
        g = (w * -0.5 * b**-1.5 * scale) @ B0
        return f, g

    def pointwise(b, b1, b2):
        return _pointwise(rows, b, b1, b2)

    n_rows = len(pointwise(*state(np.ones(B0.shape[1])))[0])
    at = np.tile(np.arange(len(tau)), n_rows // len(tau))  # the grid point of every row

    def rms_rows(x, b, b1):
        """RMS over the duty cycle, one row per rated joint: (2∫τ²/√b dτ + dwell·(G0² + G1²)) / (2T + 2·dwell)
        ≤ rated²: (values, Jacobian)."""
        Tn = w @ b**-0.5
        dT = (w * -0.5 * b**-1.5 * scale) @ B0
        vals, jacs = [], []
        for i, r in rated:
            tq = pr.Am[:, i] * b + m[:, i] / 2 * b1 + pr.Gm[:, i]
            I = w @ (tq**2 * b**-0.5)
            dI = (w * (2 * tq * b**-0.5 * pr.Am[:, i] - 0.5 * tq**2 * b**-1.5)) @ B0 * scale + (
                w * 2 * tq * b**-0.5 * m[:, i] / 2) @ B1 * scale
            hold = dwell * (pr.Gm[0, i] ** 2 + pr.Gm[-1, i] ** 2)
            den = 2 * Tn + 2 * dwell
            ms = (2 * I + hold) / den
            dms = (2 * dI * den - (2 * I + hold) * 2 * dT) / den**2
            vals.append(1.0 - ms / r**2)
            jacs.append(-dms / r**2)
        return np.array(vals), np.array(jacs).reshape(len(vals), B0.shape[1])  # (0, n) with no rated joint

    def constraints(x, keep=None):
        """(values ≥ 0 when feasible, Jacobian) over the grid rows ``keep`` (all: None) and the RMS rows."""
        b, b1, b2 = state(x)
        v, a0, a1, a2 = pointwise(b, b1, b2)
        if keep is not None:
            v, a0, a1, a2, g = v[keep], a0[keep], a1[keep], a2[keep], at[keep]
        else:
            g = at
        J = (a0[:, None] * B0[g] + a1[:, None] * B1[g] + a2[:, None] * B2[g]) * scale
        rv, rJ = rms_rows(x, b, b1)
        return np.concatenate([v, rv]) - LAW_MARGIN, np.vstack([J, rJ])

    def values(x):
        """Every row's value (grid rows, then RMS rows), no Jacobian."""
        b, b1, b2 = state(x)
        return np.concatenate([pointwise(b, b1, b2)[0], rms_rows(x, b, b1)[0]]) - LAW_MARGIN

    return {"objective": objective, "constraints": constraints, "values": values, "n_rows": n_rows}


def _solve(prob: _Problem, x: np.ndarray, keep: np.ndarray, t_fit: float) -> tuple[np.ndarray, int, str, int]:
    """SLSQP on the rows ``keep`` from ``x``; rows the solution breaks are added (with every row above
    ``LAW_ACTIVE``/2 of its limit) and the problem solved again. Returns (x, iterations, message, rounds)."""
    from scipy.optimize import minimize

    cache: dict = {}

    def cons(x):
        key = x.tobytes()
        if key not in cache:
            cache.clear()
            cache[key] = prob.constraints(x, keep)
        return cache[key]

    nit, message = 0, ""
    for rounds in range(1, 6):
        cache.clear()
        res = minimize(lambda x: tuple(v / t_fit for v in prob.objective(x)), x, jac=True, method="SLSQP",
                       bounds=[LAW_BOUNDS] * len(x),
                       constraints=[{"type": "ineq", "fun": lambda x: cons(x)[0], "jac": lambda x: cons(x)[1]}],
                       options={"maxiter": 300, "ftol": LAW_FTOL})
        nit += int(res.nit)
        message = str(res.message)
        if np.all(np.isfinite(res.x)):
            x = res.x
        v = prob.values(x)[: prob.n_rows]
        broken = (~keep) & (v < -1e-9)
        if not broken.any():
            break
        keep = keep | (v < 1.0 - LAW_ACTIVE / 2)
    return x, nit, message, rounds


def optimal_law(model, dwell: float, t_fit: float, coefficients: int = LAW_COEFFICIENTS,
                capacity=None, start: np.ndarray | None = None) -> LawResult:
    """Minimise the duration of ``model``'s path over time laws b(τ) (module docstring), warm-started at the
    uniform law of duration ``t_fit`` [s]. ``capacity``: also hold the profile's Cartesian |v|, |a| (and |j|
    when set) — optional, off by default. ``start``: the law's coefficients to start from (relative to the
    uniform law, which is all ones; the benchmark's multi-start). Returns the composed path (not yet checked).

    Two phases: every row of a coarse grid (``LAW_COARSE_GRID`` points and the path's knots and jump sides:
    few rows, so SLSQP's subproblems are cheap) from the uniform law; then the full grid from that solution,
    on the rows above ``LAW_ACTIVE`` of their limit there (the coarse solution already works the right rows
    hardest), adding any row the solution breaks."""
    path = model.path
    knots = np.concatenate([[0.0] * 3, np.linspace(0.0, 1.0, coefficients - 2), [1.0] * 3])
    x0 = np.ones(coefficients)
    nit, message = 0, ""
    x = x0 if start is None else np.clip(np.asarray(start, float), *LAW_BOUNDS)
    if LAW_COARSE_GRID:
        coarse = _Problem(model, _law_grid(path, LAW_COARSE_GRID, spans=False), knots, t_fit, dwell, capacity)
        xc, nit, message, _ = _solve(coarse, x, np.ones(coarse.n_rows, bool), t_fit)
        if coarse.values(xc).min() > -1e-3:  # a usable warm start (the fine grid may still bend it)
            x = xc
    fine = _Problem(model, _law_grid(path), knots, t_fit, dwell, capacity)
    keep = fine.values(x)[: fine.n_rows] < 1.0 - LAW_ACTIVE
    x, n2, message, rounds = _solve(fine, x, keep, t_fit)
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


def _law_spline(knots: np.ndarray, coef: np.ndarray):
    from scipy.interpolate import BSpline

    return BSpline(knots, coef, 3, extrapolate=False)


def compose(path, b) -> object:
    """The path traversed with dτ/dt = √b(τ) (``b``: a scipy BSpline in τ), as a CartesianPath in u = t/T
    (its derivatives are those at T = 1 s; ``T`` of the law itself is ∫dτ/√b)."""
    from scipy.interpolate import CubicHermiteSpline

    from ..model.trajectory import CartesianPath

    b1, b2 = b.derivative(1), b.derivative(2)
    # t(τ) = ∫ dτ/√b: 4-point Gauss on every interval of a fine table (b is a cubic spline: ~1e-13)
    tab = np.unique(np.concatenate([np.linspace(0.0, 1.0, LAW_TABLE), np.asarray(path.breakpoints, float),
                                    b.t[3:-3]]))
    xg, wg = np.polynomial.legendre.leggauss(4)
    lo, hi = tab[:-1], tab[1:]
    nodes = (lo[:, None] + (hi - lo)[:, None] * (xg + 1) / 2)
    seg = ((b(nodes) ** -0.5) * wg).sum(axis=1) * (hi - lo) / 2
    t_tab = np.concatenate([[0.0], np.cumsum(seg)])
    T = float(t_tab[-1])
    u_tab = t_tab / T
    speed = T * np.sqrt(b(tab))  # dτ/du
    inv = CubicHermiteSpline(u_tab, tab, speed)  # τ(u)
    fwd = CubicHermiteSpline(tab, u_tab, 1.0 / speed)  # u(τ)

    def orders(u: np.ndarray):
        u = np.clip(np.asarray(u, float), 0.0, 1.0)
        tau = np.clip(inv(u), 0.0, 1.0)
        bb = b(tau)
        s1 = T * np.sqrt(bb)
        s2 = T**2 * b1(tau) / 2
        s3 = T**3 * np.sqrt(bb) * b2(tau) / 2
        p, d1, d2, d3 = path.all_orders(tau)
        return [p, d1 * s1[:, None], d2 * (s1**2)[:, None] + d1 * s2[:, None],
                d3 * (s1**3)[:, None] + 3 * d2 * (s1 * s2)[:, None] + d1 * s3[:, None]]

    def evaluate(u: np.ndarray, order: int) -> np.ndarray:
        return orders(u)[order]

    dense = np.linspace(0.0, 1.0, 4001)
    bp = np.unique(np.clip(fwd(np.asarray(path.breakpoints, float)), 0.0, 1.0))
    jumps = fwd(path.jump_points) if len(path.jump_points) else np.zeros(0)
    from ..curves.peaks import true_peaks

    shell = CartesianPath(evaluate, path.method, {}, (0.0, 0.0, 0.0), np.unique(np.concatenate([[0.0, 1.0], bp])),
                          jumps=tuple(jumps.tolist()), evaluate_all=orders)
    peaks = true_peaks(shell, np.unique(np.concatenate([dense, shell.breakpoints])))
    params = dict(path.parameters)
    params.update(time_law="optimal", law_coefficients=len(b.c))
    return CartesianPath(evaluate, path.method, params, tuple(float(x) for x in peaks), shell.breakpoints,
                         max_order=path.max_order, jumps=shell.jumps, evaluate_all=orders)
