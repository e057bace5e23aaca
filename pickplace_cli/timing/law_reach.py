"""The reachability pass of ``--time optimal``: the fastest law along the path under the limits that are linear in
(b, b′) — joint and motor speed, joint acceleration, motor torque — on a grid of τ, as in TOPP-RA
[Pham2018]: backward controllable sets, then a greedy forward pass.

With b = (dτ/dt)² and b′ = db/dτ constant on each interval of the grid, b_{i+1} = b_i + Δ_i·b′_i, and every
row at τ_i reads a·b_i + c·b′_i ≤ r (:func:`~pickplace_cli.timing.optimal._limit_rows`: the torque
A_m·b + m·b′/2 + G_m, the acceleration q″b + q′b′/2; a speed row b·q′² ≤ L² is an upper bound on b). Each
step of either pass is a linear programme in two variables (b_i, b′_i), solved in closed form here by
enumerating the vertices of its polygon (the intersections of every pair of its lines), vectorised over the
rows.

What it gives: ``bmax`` (the upper edge of the controllable sets: no law that holds these rows at the grid
points is faster anywhere) and the bang-bang law's duration ``t_lower`` = Σ 2Δ_i/(√b_i + √b_{i+1}) (exact for
b linear on each interval). The plan's laws hold more rows (jerk, torque rate, RMS, a C² law), so ``t_lower``
is an estimate from below of their optimum: the share of the duration those rows cost. The grid holds the
rows at its points only, so with a coarse grid it can sit slightly above the continuous bound.

[Pham2018]: H. Pham, Q.-C. Pham, "A new approach to time-optimal path parameterization based on reachability
analysis", IEEE Trans. Robotics 34(3), 2018, Alg. 1 (its u = s̈ is b′/2 here).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: uniform points of the pass's τ grid (plus the path's knots and both sides of every jump)
REACH_GRID = 401


@dataclass(frozen=True)
class ReachResult:
    """The reachability pass on the grid ``tau``: the greedy law ``b`` [1/s²] (bang-bang in b′), the controllable
    sets' upper edge ``bmax`` [1/s²] and the law's duration ``t_lower`` [s]."""

    tau: np.ndarray
    b: np.ndarray
    bmax: np.ndarray
    t_lower: float

    def __post_init__(self) -> None:
        if not (self.tau.shape == self.b.shape == self.bmax.shape and self.tau.ndim == 1):
            raise ValueError(f"ReachResult: tau, b, bmax must be 1-D of one length, got {self.tau.shape}, "
                             f"{self.b.shape}, {self.bmax.shape}")


def _interval(a: np.ndarray, c: np.ndarray, r: np.ndarray) -> tuple[float, float]:
    """(min x, max x) over the polygon {(x, v): a·x + c·v ≤ r} (bounded in x and v by its rows), or
    (inf, −inf) when it is empty: the best of its vertices (every pair of lines that meets), vectorised."""
    i, j = np.triu_indices(len(a), 1)
    det = a[i] * c[j] - a[j] * c[i]
    ok = np.abs(det) > 1e-14 * (np.abs(a[i] * c[j]) + np.abs(a[j] * c[i]) + 1e-300)
    i, j, det = i[ok], j[ok], det[ok]
    x = (r[i] * c[j] - r[j] * c[i]) / det
    v = (a[i] * r[j] - a[j] * r[i]) / det
    ax, cv = a[:, None] * x[None, :], c[:, None] * v[None, :]
    feas = np.all(ax + cv <= r[:, None] + 1e-9 * (np.abs(r)[:, None] + np.abs(ax) + np.abs(cv)), axis=0)
    if not feas.any():
        return np.inf, -np.inf
    return float(x[feas].min()), float(x[feas].max())


def reach(tau: np.ndarray, a: np.ndarray, c: np.ndarray, r: np.ndarray, upper: np.ndarray,
          lower: float) -> ReachResult:
    """The pass on the grid ``tau`` (sorted, N points) for rows a[k, i]·b_i + c[k, i]·b′_i ≤ r[k, i] (K rows per
    point, arrays (K, N); a row of zeros with r ≥ 0 is void), b_i ≤ ``upper`` (N,) and b ≥ ``lower``. The last
    point's rows hold b only (its b′ leaves the grid). Raises ValueError when no law holds the rows."""
    tau = np.asarray(tau, float)
    n = len(tau)
    d = np.diff(tau)
    hi = np.minimum(np.asarray(upper, float), np.inf)
    lo_k, hi_k = np.full(n, lower), np.empty(n)
    # the last point: lower ≤ b ≤ upper, and its rows at b′ = 0 (a·b ≤ r)
    aN, rN = a[:, -1], r[:, -1]
    cap = np.min(np.where(aN > 0, rN / np.where(aN > 0, aN, 1.0), np.inf), initial=np.inf)
    hi_k[-1] = min(hi[-1], cap)
    if hi_k[-1] < lower:
        raise ValueError(f"law reachability: no b ≥ {lower:.3g} 1/s² holds the rows at τ = {tau[-1]:.4g}")
    one, zero = np.ones(1), np.zeros(1)
    for i in range(n - 2, -1, -1):  # backward: the controllable set K_i of b_i
        A = np.concatenate([a[:, i], one, -one, one, -one])
        C = np.concatenate([c[:, i], zero, zero, [d[i]], [-d[i]]])
        R = np.concatenate([r[:, i], [hi[i]], [-lower], [hi_k[i + 1]], [-lo_k[i + 1]]])
        lo_k[i], hi_k[i] = _interval(A, C, R)
        if not lo_k[i] <= hi_k[i]:
            raise ValueError(f"law reachability: no law holds the rows from τ = {tau[i]:.4g} on")
    b = np.empty(n)
    b[0] = hi_k[0]
    for i in range(n - 1):  # forward: the largest b′ that keeps b_{i+1} controllable
        x = b[i]
        A = np.concatenate([c[:, i], [d[i]], [-d[i]]])
        R = np.concatenate([r[:, i] - a[:, i] * x, [hi_k[i + 1] - x], [x - lo_k[i + 1]]])
        up = A > 0
        v = np.min(R[up] / A[up], initial=np.inf)
        b[i + 1] = float(np.clip(x + d[i] * v, lo_k[i + 1], hi_k[i + 1]))
    t = float(np.sum(2.0 * d / (np.sqrt(b[:-1]) + np.sqrt(b[1:]))))
    return ReachResult(tau, b, hi_k, t)


def reach_law(model, t_fit: float, capacity=None, points: int = 0) -> ReachResult:
    """The pass on ``model``'s path (:func:`reach`) with its rows linear in (b, b′) and its speed rows, on
    ``points`` (default ``REACH_GRID``) uniform points with the path's knots and jump sides; b is held to the
    plan's law range (``LAW_BOUNDS`` × 1/``t_fit``²). ``capacity``: also the Cartesian speed |v| (its
    acceleration and jerk rows are not linear and are left out)."""
    from .optimal import LAW_BOUNDS, _GridData, _law_grid, _limit_rows, _stack

    tau = _law_grid(model.path, points or REACH_GRID, spans=False)
    pr = _GridData(model, tau).take(tau)
    rows = _stack(*_limit_rows(model, pr, pr.m, pr.dm, (pr.p1, pr.p2, pr.p3), capacity), len(tau))
    n = len(tau)
    cl = rows["lin_c"]  # c0·b + c1·b′ + c3 ≤ 1, stacked one group of n rows after another (the rows have no b″)
    a, c, r = (cl[:, 0].reshape(-1, n), cl[:, 1].reshape(-1, n), 1.0 - cl[:, 3].reshape(-1, n))
    qc, qp, qg = rows["quad_c"], rows["quad_p"], rows["quad_g"]
    speed = (qp == 1) & ~np.any(qc[:, :3, :], axis=(1, 2))  # b·‖c3‖² ≤ 1: b ≤ 1/‖c3‖²
    n2 = np.einsum("ij,ij->i", qc[speed, 3], qc[speed, 3])
    upper = np.full(n, LAW_BOUNDS[1] / t_fit**2)
    np.minimum.at(upper, qg[speed], np.where(n2 > 0, 1.0 / np.where(n2 > 0, n2, 1.0), np.inf))
    return reach(tau, a, c, r, upper, LAW_BOUNDS[0] / t_fit**2)
