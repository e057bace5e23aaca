"""An independent reference for ``--time optimal``: the same minimum-time problem written as a direct
transcription on a dense grid and solved by IPOPT (CasADi), from several starts.

The law b(τ) = τ̇² is a C² piecewise cubic with a knot at every node (:func:`nodes`: cosine-spaced, denser at
the path's ends where the law varies fastest, and the path's own knots, where the limits' coefficients change
slope or step): the variables are b, b′, b″ at every node and the constant b‴ of every interval, chained
exactly (b_{k+1} = b_k + h·b′_k + h²/2·b″_k + h³/6·b‴_k, …). Every limit of the plan's problem is a
constraint at ``SUB`` points of every interval (b, b′, b″ there from the interval's cubic) and the last node,
written here from the motion model's terms at T = 1 s (``MotionModel.parts``) — not from the plan's row code:

    joint velocity  b·q′² ≤ v²                 motor speed   b·(N q′)² ≤ ω²
    joint accel.    |q″b + q′b′/2| ≤ a          motor torque  |A_m b + m b′/2 + G_m| ≤ τ_max
    joint jerk      b·(q‴b + 3/2 q″b′ + q′b″/2)² ≤ j²
    torque rate     b·(A_m′b + (A_m + m′/2)b′ + m b″/2 + G_m′)² ≤ τ̇²
    RMS             (2∫τ²/√b dτ + dwell·(G_0² + G_1²)) / (2T + 2·dwell) ≤ rated²

(m: the motor torque of accelerating along p′ from rest, m′ its τ-derivative by central differences.) The
duration T = ∫dτ/√b and the RMS integral are Simpson's rule on every interval (its nodes and midpoint).
b is held to the plan's range [1e-2, 1e2] × the uniform law's 1/T_fit² (the plan bounds its coefficients so;
values in that range are a superset).

The constraints hold at those points only, so the reference may sit slightly *below* the true optimum of its
class (by its discretisation error, which a finer ``n`` shrinks); a plan's law is exact-checked continuously.
IPOPT is a local solver: :func:`reference_duration` solves from the uniform law (at a few faster scales too) and
from the plan's own law when given, on two node sets (with and without the path's knots), and keeps the shortest
answer: without the knots it came out 0.3 % *above* the plan on a SCARA move (its law could not bend where the
plan's does), with them 2–3.5 % above on two Delta moves.
"""

from __future__ import annotations

import numpy as np

#: the law's range relative to the uniform law (the plan's coefficient bounds)
B_RANGE = (1e-2, 1e2)
#: points per interval at which every limit is held (the law may bend between its nodes)
SUB = 4
#: the law's intervals
N = 160


def model_terms(model, tau: np.ndarray) -> dict:
    """The motion model's terms at ``tau`` (T = 1 s): the joints' q′, q″, q‴, the motor torque's inertial part
    A_m, gravity part G_m and their τ-derivatives, and m, m′ (the torque of p′ at rest, m′ by differences)."""
    path = model.path
    pr = model.parts(tau)

    def inertia(t):
        p, p1 = path.all_orders(t)[:2]
        z = np.zeros_like(p)
        motion = (p, z, p1, z)
        angle = path.angle_orders(t)
        if angle is not None:
            motion += (np.stack([angle[0], np.zeros(len(t)), angle[1], np.zeros(len(t))]),)
        return model.parts(t, derivatives=False, motion=motion, singularity=False).Am

    h = 1e-5
    lo, hi = np.clip(tau - h, 0, 1), np.clip(tau + h, 0, 1)
    return {"q1": pr.qd1, "q2": pr.qdd1, "q3": pr.qddd1, "A": pr.Am, "G": pr.Gm, "dA": pr.dAm, "dG": pr.dGm,
            "m": inertia(tau), "dm": (inertia(hi) - inertia(lo)) / (hi - lo)[:, None]}


def nodes(n: int, path=None) -> np.ndarray:
    """The law's nodes: n + 1 cosine-spaced (the law varies fastest near the path's ends, where p′ → 0) and the
    ``path``'s knots (where the limits' coefficients change slope or step, and the best law may bend), a node
    closer than 1e-4 to a knot giving way to it."""
    t = 0.5 * (1.0 - np.cos(np.pi * np.arange(n + 1) / n))
    if path is None:
        return t
    knots = np.asarray(path.breakpoints, float)
    knots = knots[(knots > 1e-6) & (knots < 1.0 - 1e-6)]
    keep = np.min(np.abs(t[:, None] - knots[None, :]), axis=1, initial=np.inf) > 1e-4 if knots.size else np.ones(len(t), bool)
    keep[[0, -1]] = True
    return np.unique(np.concatenate([t[keep], knots]))


def _solve(model, dwell: float, t_fit: float, n: int, start_b, knots: bool = True):
    """IPOPT from ``start_b`` (b at :func:`nodes`, or a callable b(τ) with a ``derivative`` method, whose b′, b″, b‴
    then start the other variables) → (T [s], b, b′ at the nodes) or None when it fails."""
    import casadi as ca

    tau = nodes(n, model.path if knots else None)
    n = len(tau) - 1
    h = np.diff(tau)
    theta = np.arange(SUB) / SUB  # the limits' points: SUB per interval (θ-major) and the last node
    pts = np.concatenate([(tau[None, :-1] + theta[:, None] * h[None, :]).ravel(), [1.0]])
    c = model_terms(model, pts)
    s = 1.0 / t_fit**2  # the variables are b relative to the uniform law (x = b·T_fit²)
    opti = ca.Opti()
    x, d, e = opti.variable(n + 1), opti.variable(n + 1), opti.variable(n + 1)  # b, b′, b″ (relative)
    j = opti.variable(n)  # b‴ per interval
    opti.subject_to(x[1:] == x[:-1] + h * d[:-1] + h**2 / 2 * e[:-1] + h**3 / 6 * j)
    opti.subject_to(d[1:] == d[:-1] + h * e[:-1] + h**2 / 2 * j)
    opti.subject_to(e[1:] == e[:-1] + h * j)
    xs, ds, es = [x[:-1]], [d[:-1]], [e[:-1]]
    for th in theta[1:]:  # b inside the intervals: variables (bounded like the nodes), tied to the cubic
        y = opti.variable(n)
        g = th * h
        opti.subject_to(y == x[:-1] + g * d[:-1] + g**2 / 2 * e[:-1] + g**3 / 6 * j)
        opti.subject_to(opti.bounded(B_RANGE[0], y, B_RANGE[1]))
        xs.append(y)
        ds.append(d[:-1] + g * e[:-1] + g**2 / 2 * j)
        es.append(e[:-1] + g * j)
    opti.subject_to(opti.bounded(B_RANGE[0], x, B_RANGE[1]))
    b, b1, b2 = (s * ca.vertcat(*parts, end[-1]) for parts, end in ((xs, x), (ds, d), (es, e)))
    # Simpson on every interval: its two nodes and its midpoint (θ = 1/2, a point of the limits)
    mid = SUB // 2
    wq = np.zeros(len(pts))
    wq[:n] += h / 6
    wq[n * mid: n * (mid + 1)] += 4 * h / 6
    wq[1:n] += h[:-1] / 6
    wq[-1] += h[-1] / 6
    inv = b ** -0.5
    T = ca.dot(wq, inv)
    def hold(constraint):  # a row that does not depend on the law (a joint the path does not move) is left out
        if not ca.MX(constraint).is_constant():
            opti.subject_to(constraint)

    for i, spec in enumerate(model.specs):
        lim, drv = spec.limits, spec.drive
        q1, q2, q3 = c["q1"][:, i], c["q2"][:, i], c["q3"][:, i]
        if lim.velocity is not None:
            hold(b * q1**2 <= lim.velocity**2)
        if lim.acceleration is not None:
            hold(opti.bounded(-lim.acceleration, q2 * b + q1 / 2 * b1, lim.acceleration))
        if lim.jerk is not None:
            hold(b * (q3 * b + 1.5 * q2 * b1 + q1 / 2 * b2) ** 2 <= lim.jerk**2)
        if drv is None:
            continue
        A, G, m = c["A"][:, i], c["G"][:, i], c["m"][:, i]
        torque = A * b + m / 2 * b1 + G
        if drv.max_speed is not None:
            hold(b * (drv.gear_ratio * q1) ** 2 <= drv.max_speed**2)
        if drv.peak_torque is not None:
            hold(opti.bounded(-drv.peak_torque, torque, drv.peak_torque))
        if drv.torque_rate is not None:
            rate = c["dA"][:, i] * b + (A + c["dm"][:, i] / 2) * b1 + m / 2 * b2 + c["dG"][:, i]
            hold(b * rate**2 <= drv.torque_rate**2)
        if drv.rated_torque:
            holding = dwell * (G[0] ** 2 + G[-1] ** 2)
            integral = ca.dot(wq, torque**2 * inv)
            hold(2 * integral + holding <= drv.rated_torque**2 * (2 * T + 2 * dwell))
    opti.minimize(T / t_fit)
    if callable(start_b):  # a law: its own derivatives (b‴ at each interval's middle)
        x0, d0, e0 = (np.asarray(start_b.derivative(k)(tau) if k else start_b(tau), float) * t_fit**2 for k in range(3))
        opti.set_initial(j, np.asarray(start_b.derivative(3)(tau[:-1] + h / 2), float) * t_fit**2)
    else:
        x0 = np.asarray(start_b, float) * t_fit**2
        d0 = np.gradient(x0, tau)
        e0 = np.gradient(d0, tau)
    opti.set_initial(x, np.clip(x0, *B_RANGE))
    opti.set_initial(d, d0)
    opti.set_initial(e, e0)
    opti.solver("ipopt", {"print_time": False, "detect_simple_bounds": True},
                {"print_level": 0, "max_iter": 3000, "tol": 1e-10, "constr_viol_tol": 1e-9, "sb": "yes"})
    try:
        sol = opti.solve()
    except RuntimeError:
        return None
    bv, dv = (s * np.asarray(sol.value(v)).ravel() for v in (x, d))
    return float(sol.value(T)), bv, dv


def reference_law(tau: np.ndarray, b: np.ndarray, b1: np.ndarray):
    """The reference's law as a scipy BSpline: the C² cubic through b with end slopes b′ (the transcription's own
    piecewise cubic, knots at the nodes), for :func:`~pickplace_cli.timing.optimal.compose`."""
    from scipy.interpolate import make_interp_spline

    return make_interp_spline(tau, b, k=3, bc_type=([(1, b1[0])], [(1, b1[-1])]))


def reference_duration(model, dwell: float, t_fit: float, n: int = N, law=None,
                       scales: tuple = (1.0, 1.1, 1.25), knots: tuple = (True, False)) -> float:
    """The shortest duration [s] IPOPT finds from each start (the uniform law at T_fit/scale for each of
    ``scales``, and ``law`` — a callable b(τ) such as the plan's — when given) on each node set of ``knots``
    (with and without the path's knots among the nodes: each alone came out above the other by 0.3–4 % on some
    moves, a local optimum of IPOPT's); inf when none converges."""
    best = np.inf
    for with_knots in knots:
        tau = nodes(n, model.path if with_knots else None)
        starts = [np.full(len(tau), scale**2 / t_fit**2) for scale in scales]
        if law is not None:
            starts.append(law if hasattr(law, "derivative") else np.asarray(law(tau), float))
        for b0 in starts:
            got = _solve(model, dwell, t_fit, n, b0, with_knots)
            if got is not None:
                best = min(best, got[0])
    return best
