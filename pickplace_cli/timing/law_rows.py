"""The rows of ``--time optimal``'s problem on a τ grid: the model's terms, every limit as a row in (b, b′, b″),
the duration and RMS terms (the formulation is :mod:`pickplace_cli.timing.optimal`'s docstring). Shared by its two
solvers, SLSQP (:mod:`~pickplace_cli.timing.optimal`) and the structured SQP (:mod:`~pickplace_cli.timing.law_sqp`)."""

from __future__ import annotations

import numpy as np

#: uniform points of the optimiser's grid in τ (plus the path's knots and both sides of every jump)
LAW_GRID = 161
#: the optimiser keeps every constraint this far below its limit (the continuous check decides)
LAW_MARGIN = 0.0
#: uniform points of the denser grid whose broken rows join the optimiser's grid (``LAW_CHECK_ROUNDS`` at most;
#: a row counts as broken beyond ``LAW_CHECK_TOL`` of its limit)
LAW_CHECK_GRID = 1001
LAW_CHECK_ROUNDS = 2
LAW_CHECK_TOL = 1e-5


def degree(knots: np.ndarray) -> int:
    """The degree of a B-spline with full ``knots`` (its first knot repeated degree + 1 times)."""
    return int(np.count_nonzero(np.asarray(knots) == knots[0])) - 1


def _basis(knots: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(B, B′, B″): the B-spline basis on ``knots`` (full, end knots repeated: their count less one is the degree,
    3 for the SLSQP's law) and its derivatives at x."""
    from scipy.interpolate import BSpline

    k = degree(knots)
    n = len(knots) - k - 1
    spl = BSpline(knots, np.eye(n), k, extrapolate=False)
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


