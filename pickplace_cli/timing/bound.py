"""A lower bound on the duration of a path: its time-optimal traversal under peak motor torque (and motor speed)
alone, by TOPP-RA's two passes [Pham & Pham 2018] on the path's own parameter τ.

The law of a traversal is b(τ) = τ̇² with τ̈ = a = b′/2. Along the path the motor torque is affine in (b, a) and
the motor speed squared is linear in b (the motion model's terms at T = 1):

    motor torque_i = Am_i(τ)·b + m_i(τ)·a + Gm_i(τ)        (m: the torque of accelerating along p′ at rest)
    motor speed_i² = (N_i·q̇1_i(τ))²·b

On a grid τ_0 … τ_N with a constant over each step (b_{k+1} = b_k + 2Δ·a_k) and the constraints held at the
grid points, the backward pass computes the largest controllable b_k at every point (from which the end can
still be reached within the limits), and the forward pass takes the largest admissible a at every step: that
is the time-optimal law of the discretised problem (TOPP-RA's result), and its duration Σ 2Δ/(√b_k + √b_{k+1})
is the bound. It allows what a smooth law cannot: the torque may jump (no torque-rate limit), nothing limits
the RMS, the jerk is unbounded. So T_bound ≤ the duration of any law that holds the peak torque (and speed),
up to the grid's error (τ denser towards the ends, 500 points: within 0.01 % of 1000, 2000 and 4000 on the Adept
cycle, at half the time of 1000; ``bench/bench_bound.py`` holds it to ``toppra`` with the same constraint on the arc length).

The path's own τ is the parameter, not the arc length: where the path stands still (p′ = 0: its ends and the
corners of ``piecewise-poly``) the constraints do not bound b, and b may grow without bound there (``_CAP``).
"""

from __future__ import annotations

import math

import numpy as np

#: steps of the bound's τ grid (:func:`bound_grid`: denser towards the ends)
POINTS = 500
#: b where no constraint bounds it (the path stands still there)
_CAP = 1e12


def path_constraints(model, tau: np.ndarray, speed: bool = True, data=None) -> tuple[np.ndarray, np.ndarray,
                                                                                       np.ndarray, np.ndarray]:
    """The rows A·a + B·b + C ≤ g at every τ (each (len(τ), R)): both sides of every joint's peak motor torque
    and, with ``speed``, its motor speed squared. ``data``: the model's terms already evaluated on a union of grids
    (the time law's :class:`~pickplace_cli.timing.law_rows._GridData`), taken from there (the same values: each term
    is computed point by point)."""
    from .law_rows import _inertia_along

    if data is not None:
        pr = data.take(tau)
        m = pr.m
    else:
        path = model.path
        pr = model.parts(tau, derivatives=False, singularity=False)  # torques and speeds only
        p, p1 = path.all_orders(tau)[:2]
        m = _inertia_along(model, tau, p, p1)
    A, B, C, g = [], [], [], []
    for i, spec in enumerate(model.specs):
        drv = spec.drive
        if drv is None:
            continue
        if drv.peak_torque is not None:
            for sign in (1.0, -1.0):
                A.append(sign * m[:, i])
                B.append(sign * pr.Am[:, i])
                C.append(sign * pr.Gm[:, i])
                g.append(np.full(len(tau), drv.peak_torque))
        if speed and drv.max_speed is not None:
            A.append(np.zeros(len(tau)))
            B.append((drv.gear_ratio * pr.qd1[:, i]) ** 2)
            C.append(np.zeros(len(tau)))
            g.append(np.full(len(tau), drv.max_speed**2))
    if not A:
        raise ValueError("the profile limits no motor torque or speed: there is no bound")
    return tuple(np.column_stack(x) for x in (A, B, C, g))  # type: ignore[return-value]


def topp(A: np.ndarray, B: np.ndarray, C: np.ndarray, g: np.ndarray, tau: np.ndarray, rest: bool = False) -> np.ndarray:
    """b at every grid point ``tau`` of the time-optimal law under A·a + B·b + C ≤ g (rows at each point, a on
    the step that starts there; the last point's a is free). ``rest``: b = 0 at both ends (a path that moves
    there); else the ends are free (a path that stands still there). ValueError when no law holds the rows
    (e.g. a point where the torque at rest, gravity alone, is over its limit)."""
    n = len(tau)
    two = 2.0 * np.diff(tau)  # 2Δ_k of step k (from point k)
    h = g - C  # A·a + B·b ≤ h
    with np.errstate(divide="ignore", invalid="ignore"):
        # a ≤ r·b + s (A > 0) and a ≥ p·b + q (A < 0); rows with A = 0 bound b alone: B·b ≤ h
        up, low, pure = A > 0, A < 0, A == 0
        r, s = np.where(up, -B / A, np.nan), np.where(up, h / A, np.nan)
        pl, ql = np.where(low, -B / A, np.nan), np.where(low, h / A, np.nan)
        if np.any(pure & (B <= 0) & (h < 0)):
            raise ValueError("no traversal holds the limits (a limit is exceeded at rest)")
        b_pure = np.where(pure & (B > 0), h / B, np.inf).min(axis=1)
        # static pairs (lower i, upper j): (p_i − r_j)·b ≤ s_j − q_i; with b_{k+1} ≥ 0: a ≥ −b/(2Δ_k)
        inv = np.append(1.0 / two, 0.0)[:, None]  # 1/(2Δ_k) (the last point has no step)
        P = np.concatenate([pl, -inv], axis=1)
        Q = np.concatenate([ql, np.zeros((n, 1))], axis=1)
        den = P[:, :, None] - r[:, None, :]
        num = s[:, None, :] - Q[:, :, None]
        pair = np.where(den > 0, num / den, np.inf)
        # (a pair with den < 0 asks for b ≥ num/den, a least speed: rare, left out, which can only lower the
        # bound; den = 0 with num < 0 holds for no b)
        if np.any((den == 0) & (num < 0)):
            raise ValueError("no traversal holds the limits (a limit is exceeded at rest)")
        beta_static = np.minimum(b_pure, np.where(np.isnan(pair), np.inf, pair).reshape(n, -1).min(axis=1))
        Pd = P + inv  # against the dynamic upper a ≤ (β_{k+1} − b)/(2Δ_k)
    beta_static = np.minimum(np.maximum(beta_static, 0.0), _CAP)
    if rest:
        beta_static[0] = beta_static[-1] = 0.0
    # backward pass: the largest controllable b_k
    # (plain floats: the passes are sequential, and Python's arithmetic on floats beats numpy's on scalars)
    Ql, Pdl = Q.tolist(), Pd.tolist()
    lows = [[(q, pd) for q, pd in zip(Ql[k], Pdl[k]) if pd > 0] for k in range(n - 1)]
    bs, tw = beta_static.tolist(), two.tolist()
    beta = [0.0] * n
    beta[-1] = bs[-1]
    for k in range(n - 2, -1, -1):
        top = beta[k + 1] / tw[k]
        bk = bs[k]
        for q, pd in lows[k]:
            c = (top - q) / pd
            if c < bk:
                bk = c
        if bk < 0:
            raise ValueError("no traversal holds the limits")
        beta[k] = bk
    # forward pass: the largest admissible a at every step, staying controllable
    rl, sl, upl = r.tolist(), s.tolist(), up.tolist()
    ups = [[(rr, ss) for rr, ss, u in zip(rl[k], sl[k], upl[k]) if u] for k in range(n - 1)]
    b = [0.0] * n
    b[0] = beta[0]
    for k in range(n - 1):
        bk = b[k]
        a = (beta[k + 1] - bk) / tw[k]
        for rr, ss in ups[k]:
            c = rr * bk + ss
            if c < a:
                a = c
        b[k + 1] = min(max(bk + tw[k] * a, 0.0), beta[k + 1])
    return np.array(b)


def law_duration(b: np.ndarray, tau: np.ndarray) -> float:
    """Σ 2Δ_k/(√b_k + √b_{k+1}) [s]: the duration of the law b on ``tau`` (a constant over each step)."""
    sq = np.sqrt(np.maximum(b, 0.0))
    den = sq[:-1] + sq[1:]
    if np.any(den <= 0):
        return math.inf
    return float(np.sum(2.0 * np.diff(tau) / den))


def bound_grid(points: int = POINTS) -> np.ndarray:
    """τ on [0, 1], denser towards the ends (τ = (1 − cos πx)/2, x uniform), where the path stands still and
    the optimal b changes fastest."""
    return 0.5 * (1.0 - np.cos(np.pi * np.linspace(0.0, 1.0, points + 1)))


def torque_bound(model, speed: bool = True, points: int = POINTS, data=None) -> float:
    """The bound T [s] of ``model``'s path: peak motor torque (and, with ``speed``, motor speed) alone. ``data``: the
    model's terms on a union of grids holding :func:`bound_grid` (:func:`path_constraints`)."""
    tau = bound_grid(points)
    A, B, C, g = path_constraints(model, tau, speed, data)
    return law_duration(topp(A, B, C, g, tau), tau)
