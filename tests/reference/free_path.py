"""Free-path minimum-time reference for a Delta pick-and-place move (tests and bench only).

Direct transcription with CasADi + IPOPT: the tool path is free (jerk-level controls, piecewise constant on
each of N intervals, so position is an exact piecewise cubic), split into four phases whose ends are the via
points of ``--optimize shape``:

* P1 → P2: lift-off straight above the pick point at z_from + η·h, η ∈ [η_min, η_max] (one η for both ends);
* P2 → P3: P3 at the horizontal midpoint, at or above the clearance z_top = max(z_from, z_to) + h;
* P3 → P4: set-down point straight above the place point at z_to + η·h;
* P4 → P5: rest to rest at both ends; every phase has its own duration, the move time is their sum.

The robot is written here in CasADi symbols from the formulas of :mod:`tests.reference.delta_rigid` (inverse
kinematics, knee-out branch; kinetic and potential energy body by body), not from the library: with the plate
position p as the generalised coordinates, F = d/dt ∂T/∂ṗ − ∂T/∂p + ∂V/∂p, the joint torques τ = (∂q/∂p)⁻ᵀ F
(virtual work), the motor torque τ/(N·η_drive) + J_rotor·N·q̈, its rate d/dt along the motion, the motor speed
N·q̇, and the round-trip RMS motor torque of the library's duty cycle (move, dwell holding the gravity torque at
the place point, move back along the same path, dwell at the pick point) by the trapezoid rule. The capacity
(optional): ‖v‖ ≤ [v], ‖a‖ ≤ [a], ‖j‖ ≤ [j] pointwise.

Limits are imposed at the grid nodes (the torque rate with the jerk of both adjacent intervals), so the
optimum can exceed a limit between nodes by a little: :func:`dense_check` reports the largest utilisation
on a fine sampling of the solution (the reference is then a slight under-estimate of the true minimum, which
makes a comparison with it conservative).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import delta_rigid as D


@dataclass(frozen=True)
class Limits:
    """Drive limits (motor side) and the duty cycle; the capacity caps [v], [a], [j] (None: not held)."""

    gear: float = 25.0
    efficiency: float = 0.9
    rotor: float = 1.5e-4
    rated: float = 2.39
    peak: float = 8.36
    speed: float = 628.3
    rate: float = 418.0
    dwell: float = 0.1
    q_range: tuple[float, float] = (-0.6981317, 1.5707963)
    v_cap: float | None = None
    a_cap: float | None = None
    j_cap: float | None = None


def limits_from_profile(profile, capacity: bool = False) -> Limits:
    """The limits of a library profile (its numbers only)."""
    drv = profile.robot.joints.drive
    cap = profile.capacity
    return Limits(gear=drv.gear_ratio, efficiency=drv.efficiency, rotor=drv.rotor_inertia, rated=drv.rated_torque,
                  peak=drv.peak_torque, speed=drv.max_speed, rate=drv.torque_rate, dwell=profile.planning.dwell,
                  q_range=tuple(profile.robot.joints.limits.position),
                  v_cap=cap.velocity if capacity else None, a_cap=cap.acceleration if capacity else None,
                  j_cap=cap.jerk if capacity else None)


def motor_functions(P: dict, lim: Limits):
    """CasADi Function (p, v, a, j) → (q, motor speed, motor torque, motor torque rate), each 3 × 1."""
    import casadi as ca

    P = D._resolved(P)
    R, r, L, l = P["R"], P["r"], P["L"], P["l"]
    p, v, a, j = (ca.SX.sym(n, 3) for n in "pvaj")
    q = []
    for c, s in zip(D._C, D._S):
        xc = c * p[0] + s * p[1] + r
        yc = -s * p[0] + c * p[1]
        zc = p[2]
        K = ((xc - R) ** 2 + yc**2 + zc**2 + L * L - l * l) / (2.0 * L)
        rho = ca.sqrt((xc - R) ** 2 + zc**2)
        q.append(-ca.atan2(zc, xc - R) - ca.acos(K / rho))  # the knee-out branch (delta_rigid.inverse_kinematics)
    q = ca.vertcat(*q)
    Jq = ca.jacobian(q, p)  # ∂q/∂p
    qd = Jq @ v
    # kinetic and potential energy (delta_rigid._mass_matrix, _potential), p the generalised coordinates
    kin = 0.5 * P["upper_arm_inertia"] * ca.dot(qd, qd)
    kin += 0.5 * (P["m_plate_total"] + 3.0 * P["forearm_end_plate"]) * ca.dot(v, v)
    pot = (P["m_plate_total"] + 3.0 * P["forearm_end_plate"] + 1.5 * P["m_rod"]) * p[2]
    for i, (c, s) in enumerate(zip(D._C, D._S)):
        e1 = ca.vertcat(-L * ca.sin(q[i]) * c, -L * ca.sin(q[i]) * s, -L * ca.cos(q[i]))  # ∂E_i/∂q_i
        Ed = e1 * qd[i]
        mid = 0.5 * (Ed + v)
        rel = v - Ed
        kin += 0.5 * ((P["elbow_mass"] + P["forearm_end_elbow"]) * ca.dot(Ed, Ed) + P["m_rod"] * ca.dot(mid, mid)
                      + P["I_rod"] / l**2 * ca.dot(rel, rel))
        pot += -P["upper_arm_mass"] * P["upper_arm_com"] * ca.sin(q[i]) \
            + (P["elbow_mass"] + P["forearm_end_elbow"] + 0.5 * P["m_rod"]) * (-L * ca.sin(q[i]))
    pot = P["g"] * pot
    dTdv = ca.gradient(kin, v)
    F = ca.jacobian(dTdv, v) @ a + ca.jacobian(dTdv, p) @ v - ca.gradient(kin, p) + ca.gradient(pot, p)
    torque = ca.solve(Jq.T, F)
    qdd = ca.jtimes(qd, ca.vertcat(p, v), ca.vertcat(v, a))
    motor = torque / (lim.gear * lim.efficiency) + lim.rotor * lim.gear * qdd
    rate = ca.jtimes(motor, ca.vertcat(p, v, a), ca.vertcat(v, a, j))
    return ca.Function("motor", [p, v, a, j], [q, lim.gear * qd, motor, rate])


def _step(x, u, h):
    """The exact state (p, v, a) after h [s] of constant jerk u."""
    p, v, a = x[0:3], x[3:6], x[6:9]
    return [p + v * h + a * h**2 / 2 + u * h**3 / 6, v + a * h + u * h**2 / 2, a + u * h]


@dataclass(frozen=True)
class FreePathResult:
    """The optimum found: move time T [s], η, apex height over z_top [m], the node times (N+1,) [s], states
    (N+1, 9) (p, v, a) and jerks (N, 3), IPOPT's status, and the largest utilisation on a dense check."""

    T: float
    eta: float
    arch: float
    t: np.ndarray
    x: np.ndarray
    u: np.ndarray
    status: str
    dense_utilisation: float


def solve_free_path(p_from, p_to, h: float, lim: Limits, P: dict | None = None, n_phase: int = 16,
                    guess=None, eta_range=(0.1, 0.9), t_guess: float = 0.12, max_iter: int = 3000,
                    verbose: bool = False) -> FreePathResult:
    """Minimum-time free path (module docstring). ``guess``: callable s ∈ [0, 1] → (N, 3) positions for
    the initial path (default: a smooth arch through the Li via points at η = 0.5), timed uniformly over
    ``t_guess``; the via points' phases are placed where the guess passes them."""
    import casadi as ca

    P = D.params() if P is None else P
    f = motor_functions(P, lim)
    p0, p1 = np.asarray(p_from, float), np.asarray(p_to, float)
    z_top = max(p0[2], p1[2]) + h
    N = 4 * n_phase
    opti = ca.Opti()
    X = opti.variable(9, N + 1)
    U = opti.variable(3, N)
    Tk = opti.variable(4)
    eta = opti.variable()
    opti.minimize(ca.sum1(Tk))
    opti.subject_to(opti.bounded(1e-3, Tk, 1.0))
    opti.subject_to(opti.bounded(eta_range[0], eta, eta_range[1]))
    for k in range(N):
        hk = Tk[k // n_phase] / n_phase
        nxt = _step(X[:, k], U[:, k], hk)
        opti.subject_to(X[:, k + 1] == ca.vertcat(*nxt))
    opti.subject_to(X[0:3, 0] == p0)
    opti.subject_to(X[0:3, N] == p1)
    opti.subject_to(X[3:9, 0] == 0)
    opti.subject_to(X[3:9, N] == 0)
    lift, down, mid = X[0:3, n_phase], X[0:3, 3 * n_phase], X[0:3, 2 * n_phase]
    opti.subject_to(lift[0:2] == p0[0:2])
    opti.subject_to(lift[2] == p0[2] + eta * (z_top - p0[2]))
    opti.subject_to(down[0:2] == p1[0:2])
    opti.subject_to(down[2] == p1[2] + eta * (z_top - p1[2]))
    opti.subject_to(mid[0:2] == (p0[0:2] + p1[0:2]) / 2)
    opti.subject_to(mid[2] >= z_top)
    sq = []
    for k in range(N + 1):
        xs = X[:, k]
        for u in ({U[:, max(k - 1, 0)], U[:, min(k, N - 1)]} if 0 < k < N else (U[:, min(k, N - 1)],)):
            q, spd, mot, rate = f(xs[0:3], xs[3:6], xs[6:9], u)
            opti.subject_to(opti.bounded(-lim.rate, rate, lim.rate))
        opti.subject_to(opti.bounded(lim.q_range[0], q, lim.q_range[1]))
        opti.subject_to(opti.bounded(-lim.speed, spd, lim.speed))
        opti.subject_to(opti.bounded(-lim.peak, mot, lim.peak))
        sq.append(mot**2)
        if lim.v_cap is not None:
            opti.subject_to(ca.sumsqr(xs[3:6]) <= lim.v_cap**2)
        if lim.a_cap is not None:
            opti.subject_to(ca.sumsqr(xs[6:9]) <= lim.a_cap**2)
    if lim.j_cap is not None:
        for k in range(N):
            opti.subject_to(ca.sumsqr(U[:, k]) <= lim.j_cap**2)
    # round-trip RMS: 2 ∫ τ² dt + dwell (G_end² + G_start²) ≤ rated² (2T + 2 dwell), trapezoid on each phase
    integral = 0
    for k in range(N):
        hk = Tk[k // n_phase] / n_phase
        integral = integral + hk * (sq[k] + sq[k + 1]) / 2
    hold = sq[0] + sq[N]  # at rest: the motor torque there is the gravity torque
    T = ca.sum1(Tk)
    opti.subject_to(2 * integral + lim.dwell * hold <= lim.rated**2 * (2 * T + 2 * lim.dwell))
    # the initial guess
    s = np.linspace(0.0, 1.0, N + 1)
    if guess is None:
        guess = _default_guess(p0, p1, z_top)
    pts = np.asarray(guess(s), float)
    dt = t_guess / N
    vel = np.gradient(pts, dt, axis=0)
    acc = np.gradient(vel, dt, axis=0)
    jer = np.diff(acc, axis=0) / dt
    opti.set_initial(X, np.vstack([pts.T, vel.T, acc.T]))
    opti.set_initial(U, jer.T)
    opti.set_initial(Tk, [t_guess / 4] * 4)
    opti.set_initial(eta, float(np.clip((pts[n_phase, 2] - p0[2]) / (z_top - p0[2]), *eta_range)))
    opti.solver("ipopt", {"print_time": False}, {"max_iter": max_iter, "print_level": 5 if verbose else 0,
                                                 "tol": 1e-9, "acceptable_tol": 1e-7, "mu_strategy": "adaptive"})
    try:
        sol = opti.solve()
        status = "solved"
        get = sol.value
    except RuntimeError:
        status = opti.stats().get("return_status", "failed")
        get = opti.debug.value
    Tv = np.asarray(get(Tk), float).reshape(-1)
    x = np.asarray(get(X), float).T
    u = np.asarray(get(U), float).T
    t = np.concatenate([[0.0], np.cumsum(np.repeat(Tv / n_phase, n_phase))])
    res = FreePathResult(T=float(Tv.sum()), eta=float(get(eta)), arch=float(x[:, 2].max() - z_top), t=t, x=x, u=u,
                         status=status, dense_utilisation=np.nan)
    return FreePathResult(**{**res.__dict__, "dense_utilisation": dense_check(res, f, lim)})


def _default_guess(p0, p1, z_top, eta: float = 0.5, lift: float = 0.0):
    """A smooth arch: horizontal smoothstep from p0 to p1, vertical bump reaching z_top + lift at s = 1/2."""
    def g(s):
        s = np.asarray(s)
        u = s**3 * (10 - 15 * s + 6 * s**2)
        bump = (16 * s**2 * (1 - s) ** 2)
        base = p0[2] + (p1[2] - p0[2]) * u
        out = p0[None] + (p1 - p0)[None] * u[:, None]
        out[:, 2] = base + (z_top + lift - max(p0[2], p1[2])) * bump ** (0.5 + eta)
        return out
    return g


def dense_check(res: FreePathResult, f=None, lim: Limits | None = None, per_interval: int = 8) -> float:
    """The largest utilisation (speed, torque, torque rate against their limits) on ``per_interval`` points of
    every interval of the solution (the exact cubic between nodes); 1.0 = at a limit."""
    worst = 0.0
    for k in range(len(res.u)):
        h = res.t[k + 1] - res.t[k]
        for frac in np.linspace(0.0, 1.0, per_interval + 1):
            p, v, a = (np.asarray(z, float).reshape(-1) for z in _step(res.x[k], res.u[k], frac * h))
            _, spd, mot, rate = (np.asarray(z, float).reshape(-1) for z in f(p, v, a, res.u[k]))
            worst = max(worst, np.abs(spd).max() / lim.speed, np.abs(mot).max() / lim.peak,
                        np.abs(rate).max() / lim.rate)
    return float(worst)
