"""The limit check of a table as the drive rebuilds it (:func:`check_table`): the rebuilt joint motion
(:func:`~pickplace_cli.export.interpolate.rebuild`) becomes a path of the tool (forward kinematics, and the tool's
velocity, acceleration and jerk solved from the joints' through the robot's own joint mapping,
:func:`tool_motion`), which runs through the same motion model and continuous check as a plan.

Where the rebuilt acceleration steps (PVT at every point; a linear cam table at the ends of the one-cycle blend of
each point) the torque rate is unbounded for an instant: the drive takes the step within one controller cycle, in
which the motion goes on changing, so what the torque rate allows in one cycle bounds the step and the change
around it together — |Δ motor torque + motor torque rate · cycle| ≤ torque rate limit · cycle (and
|Δq̈ + q⃛ · cycle| ≤ jerk · cycle for a joint with a jerk limit), with the rate of either side of the step, and
the exact change over every window of one cycle that holds the step (:func:`_windows`: the curvature over the cycle
too) — and is reported as its own rows (``motor torque step`` and ``acceleration step``), the ends of the motion counted as steps
from and to rest.
"""

from __future__ import annotations

import numpy as np

from ..model.trajectory import CartesianPath
from .report import LimitReport, LimitRow

def tool_motion(robot, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, qddd: np.ndarray) -> tuple:
    """The tool's (p, v, a, j) (each (N, 3) [m, m/s, m/s², m/s³]) — and, with a rotary fourth axis, the tool angle's
    θ … θ⃛ (4, N) as a fifth entry — whose joint motion is (q, q̇, q̈, q⃛) (each (N, n)): p = FK(q); the joint mapping
    is q̇ = M·v, q̈ = M·a + c(p, v), q⃛ = M·j + d(p, v, a) with M = ∂q/∂p, so v, a, j are solved from the robot's own
    ``joint_motion`` (M column by column from unit velocities, c and d from the motion without the highest order)."""
    rotary = getattr(robot, "rotary", False)
    base = robot.base if rotary else robot
    q, qd, qdd, qddd = (np.asarray(x, float) for x in (q, qd, qdd, qddd))
    m = len(base.joint_names)
    qb = [x[:, :m] for x in (q, qd, qdd, qddd)]
    p = base.forward_kinematics(qb[0])
    zero = np.zeros_like(p)
    cols = []
    for k in range(3):
        unit = zero.copy()
        unit[:, k] = 1.0
        cols.append(base.joint_motion(p, unit, zero, zero)[1])
    M = np.stack(cols, axis=2)  # (N, m, 3)

    def solve(rhs: np.ndarray) -> np.ndarray:
        return np.linalg.solve(M, rhs[..., None])[..., 0]

    v = solve(qb[1])
    a = solve(qb[2] - base.joint_motion(p, v, zero, zero)[2])
    j = solve(qb[3] - base.joint_motion(p, v, a, zero)[3])
    if not rotary:
        return p, v, a, j
    return p, v, a, j, np.stack([robot.tool_angle(x) for x in (q, qd, qdd, qddd)])


class _TableAngle:
    """The tool angle's law of a table's path on a rotary fourth axis (θ = tool_angle(q), linear in q)."""

    def __init__(self, source: "_TablePath") -> None:
        self.source = source

    def all_orders(self, tau: np.ndarray) -> np.ndarray:
        return self.source.orders(tau)[4]

    def __call__(self, tau: np.ndarray, order: int = 0) -> np.ndarray:
        return self.all_orders(tau)[order]


class _TablePath:
    """τ ∈ [0, 1] → the tool's motion of a TableMotion at T = 1 (derivatives × duration^k), last τ memoised."""

    def __init__(self, motion, robot) -> None:
        self.motion, self.robot = motion, robot
        self._last: tuple | None = None

    def orders(self, tau: np.ndarray) -> tuple:
        tau = np.atleast_1d(np.asarray(tau, float))
        if self._last is not None and self._last[0].shape == tau.shape and np.array_equal(self._last[0], tau):
            return self._last[1]
        D = self.motion.duration
        joints = self.motion.all_orders(self.motion.start + tau * D)
        out = tool_motion(self.robot, *joints)
        scaled = [x * D**k for k, x in enumerate(out[:4])]
        if len(out) > 4:
            scaled.append(out[4] * (D ** np.arange(4))[:, None])
        self._last = (tau.copy(), tuple(scaled))
        return self._last[1]

    def evaluate(self, tau: np.ndarray, order: int) -> np.ndarray:
        return self.orders(tau)[order]

    def evaluate_all(self, tau: np.ndarray) -> list:
        return [x.copy() for x in self.orders(tau)[:4]]


def table_path(motion, robot) -> CartesianPath:
    """The tool's path (T = 1 normalisation, :class:`~pickplace_cli.model.trajectory.CartesianPath`) of a rebuilt
    table ``motion`` (:class:`~pickplace_cli.export.interpolate.TableMotion`) on ``robot``: its breaks are the path's
    breakpoints and jumps (the check samples both sides and never interpolates across them)."""
    src = _TablePath(motion, robot)
    bp = (np.asarray(motion.breaks, float) - motion.start) / motion.duration
    bp[0], bp[-1] = 0.0, 1.0
    return CartesianPath(src.evaluate, f"{motion.kind} table", {"points": len(motion.points)}, (0.0, 0.0, 0.0),
                         bp, jumps=bp[1:-1], evaluate_all=src.evaluate_all,
                         angle=_TableAngle(src) if getattr(robot, "rotary", False) else None)


def _steps(model, motion, cycle: float) -> tuple[dict[str, np.ndarray], np.ndarray, np.ndarray]:
    """The per-cycle change at every break of the motion (the ends against the same position and velocity at rest:
    no acceleration, no jerk), ``cycle`` [s]: the drive takes the step within one cycle while the motion goes on
    changing, so over that cycle the motor torque moves by the step plus the torque rate × the cycle, with the rate
    of the side the cycle lies on (before or after the break: the larger of the two is taken) —
    max over sides of |Δτ + τ̇·cycle|, and likewise |Δq̈ + q⃛·cycle| → ({joint: that change (B,) [N·m]} for the
    joints whose motor torque is limited, the acceleration's (B, n), the breaks' times (B,) [s] from the motion's
    start)."""
    t = np.asarray(motion.breaks, float)
    left = motion.all_orders(t, side="left")
    right = motion.all_orders(t, side="right")
    for side, k in ((left, 0), (right, len(t) - 1)):  # before the start, after the end: at rest (the end held), or
        if motion.ends == "hold":  # going on at the end's velocity (--table-end continue)
            side[1][k] = 0.0
        side[2][k] = 0.0
        side[3][k] = 0.0
    torque, rate, limited = [], [], []
    for q, qd, qdd, qddd in (left, right):
        parts = model.parts(np.zeros(len(t)), derivatives=True, singularity=False,
                            motion=tool_motion(model.robot, q, qd, qdd, qddd))
        limited = [m[0] for m in model.columns(parts, 1.0)[0] if m[1] == "motor torque"]
        torque.append(parts.Am + parts.Gm)  # signed (the motion is in seconds: T = 1), not the limit column's |τ|
        rate.append(parts.dAm + parts.dGm)  # d/dt of the signed motor torque [N·m/s]
    names = list(model.robot.joint_names)

    def over_cycle(step: np.ndarray, before: np.ndarray, after: np.ndarray) -> np.ndarray:
        # a torque that changes sign across the step moves by the sum of its sizes: the signed change
        return np.maximum(np.abs(step + before * cycle), np.abs(step + after * cycle))

    dtau = torque[1] - torque[0]
    # the same change over every window of one cycle that holds the break (the break at its end, its start or between),
    # exact: the step and the motion's own change on either side, curvature included (the linear rule above misses
    # it: 0.85 % on a 4-axis Delta's PVT at a 2 ms cycle, reading 99.6 % where the window's change is 100.45 %)
    w_tau, w_acc = _windows(model, motion, t, cycle)
    dtorque = {name: np.maximum(over_cycle(dtau[:, i], rate[0][:, i], rate[1][:, i]), w_tau[:, i])
               for i, name in ((names.index(n), n) for n in limited)}
    dacc = np.maximum(over_cycle(right[2] - left[2], left[3], right[3]), w_acc)
    return dtorque, dacc, t - motion.start


#: windows per break of :func:`_windows` (their starts spread over the cycle before it)
STEP_WINDOWS = 20


def _windows(model, motion, t: np.ndarray, cycle: float) -> tuple[np.ndarray, np.ndarray]:
    """The largest |τ(s + cycle) − τ(s)| (signed motor torque, (B, n) [N·m]) and |q̈(s + cycle) − q̈(s)| ((B, n)) over
    the windows [s, s + cycle] that hold each break t_b (s from t_b − cycle to t_b, ``STEP_WINDOWS`` + 1 of them). A
    window holds its own break's step and no other: the one that starts at t_b starts on the piece before it, the one
    that ends there ends on the piece after it, and an end that falls on another break (a linear table's blends are
    one cycle apart) stays on the window's side of it. Outside the motion its end values are held, as the drive
    holds them."""
    frac = np.linspace(0.0, 1.0, STEP_WINDOWS + 1)
    S = t[:, None] - cycle * frac[None, :]
    E = S + cycle
    # an end a rounding away from a break is on it (t_b + cycle is the next break of a linear table, to the last bit
    # or not): the side rules above then decide its piece
    for X in (S, E):
        k = np.clip(np.searchsorted(t, X), 1, len(t) - 1)
        near = np.where(np.abs(X - t[k - 1]) < np.abs(X - t[k]), t[k - 1], t[k])
        snap = np.abs(X - near) <= 1e-9 * cycle
        X[snap] = near[snap]

    def torque_acc(x: np.ndarray, side: str) -> tuple[np.ndarray, np.ndarray]:
        q, qd, qdd, qddd = motion.all_orders(x, side=side)
        # past an end (and at it, on the far side): at rest, or going on at the end's velocity (as :func:`_steps`)
        out = (x >= t[-1]) if side == "right" else (x <= t[0])
        if out.any():
            qdd[out], qddd[out] = 0.0, 0.0
            if motion.ends == "hold":
                qd[out] = 0.0
        parts = model.parts(np.zeros(len(x)), derivatives=True, singularity=False,
                            motion=tool_motion(model.robot, q, qd, qdd, qddd))
        return parts.Am + parts.Gm, qdd

    n = len(model.robot.joint_names)
    tau_s, acc_s = (a.reshape(len(t), len(frac), n) for a in torque_acc(S.ravel(), "right"))
    tau_e, acc_e = (a.reshape(len(t), len(frac), n) for a in torque_acc(E.ravel(), "left"))
    tau_s[:, 0], acc_s[:, 0] = torque_acc(S[:, 0], "left")  # the window that starts at the break: before its step
    tau_e[:, -1], acc_e[:, -1] = torque_acc(E[:, -1], "right")  # the one that ends there: after it
    return np.abs(tau_e - tau_s).max(axis=1), np.abs(acc_e - acc_s).max(axis=1)


def step_rows(model, motion, cycle: float) -> tuple[LimitRow, ...]:
    """The per-cycle step rows (module docstring) of a rebuilt ``motion`` on ``model`` (a MotionModel whose specs
    carry the limits at the plan's limit use), ``cycle`` [s]: per joint with a torque rate (jerk) limit, the largest
    change of the motor torque (acceleration) over the cycle that takes a step — the step plus the rate × the
    cycle (:func:`_steps`) — against torque rate (jerk) × cycle."""
    dtorque, dacc, times = _steps(model, motion, cycle)
    rows = []
    for i, (name, unit, spec) in enumerate(zip(model.robot.joint_names, model.robot.joint_units, model.specs)):
        rate = None if spec.drive is None else spec.drive.torque_rate
        for quantity, values, limit, u in (("motor torque step", dtorque.get(name), rate, "N·m"),
                                           ("acceleration step", dacc[:, i], spec.limits.jerk, f"{unit}/s^2")):
            if limit is None or values is None:
                continue
            bound = float(limit) * cycle
            k = int(np.argmax(values))
            peak = float(values[k])
            rows.append(LimitRow(name, quantity, u, peak, bound, peak / bound, float(times[k]), peak <= bound))
    return tuple(rows)


def capacity_rows(path, T: float, capacity, tau: np.ndarray) -> tuple[LimitRow, ...]:
    """The Cartesian capacity rows (|v| ≤ [v], |a| ≤ [a], |j| ≤ [j] when set) of a table's ``path`` run in ``T`` [s]:
    the peaks of the norms sampled on ``tau`` (sorted, both sides of every jump) and refined on the path itself,
    never across a jump (:func:`~pickplace_cli.curves.peaks.refine_max`)."""
    from ..curves.peaks import refine_max
    from .grid import interior_jumps, segment_ids

    def norms(s: np.ndarray) -> np.ndarray:
        p = path.all_orders(np.clip(s, 0.0, 1.0))
        return np.column_stack([np.linalg.norm(p[k], axis=1) / T**k for k in (1, 2, 3)])

    seg = segment_ids(tau, interior_jumps(path.breakpoints, path.jumps))
    peak, at = refine_max(norms, tau, norms(tau), segments=seg)
    rows = [("speed", "m/s", 0, capacity.velocity), ("acceleration", "m/s²", 1, capacity.acceleration)]
    if capacity.jerk is not None:
        rows.append(("jerk", "m/s³", 2, capacity.jerk))
    return tuple(LimitRow("tool", f"capacity {q}", unit, float(peak[c]), float(lim), float(peak[c]) / lim,
                          float(at[c]) * T, bool(peak[c] <= lim * (1.0 + 1e-12)), "limit") for q, unit, c, lim in rows)


def check_table(motion, robot, specs, cycle: float, dwell: float, margin=None, box=None,
                samples: np.ndarray | None = None, capacity=None) -> LimitReport:
    """Every limit of ``specs`` (joint specs at the plan's limit use) on the rebuilt table ``motion`` on ``robot``:
    the continuous check of :func:`~pickplace_cli.limits.check.check_limits` (duration = the motion's, RMS over
    move–``dwell``–back–``dwell``), plus the per-cycle step rows (``cycle`` [s]) where the acceleration steps
    (pvt, cam-table), and with ``capacity`` (the profile's Cartesian capacity) the tool's speed, acceleration and
    jerk. ``samples``: extra times [s] to sample (e.g. the controller's cycle)."""
    from .check import check_limits
    from .grid import check_grid
    from .motion import MotionModel

    path = table_path(motion, robot)
    model = MotionModel(path, robot, list(specs), margin, box)
    T = motion.duration
    tau = np.linspace(0.0, 1.0, 129) if samples is None else np.clip((np.asarray(samples) - motion.start) / T, 0, 1)
    grid = check_grid(np.unique(tau), path.breakpoints, path.jumps)
    report = check_limits(model, T, parts=model.parts(grid), dwell=dwell)
    rows = report.rows
    if capacity is not None:
        rows = rows + capacity_rows(path, T, capacity, grid)
    if motion.steps:
        rows = rows + step_rows(model, motion, cycle)
    shift = motion.start  # times from the table's own start (t = 0 at its first point)
    rows = tuple(LimitRow(r.joint, r.quantity, r.unit, r.peak, r.limit, r.utilisation,
                          None if r.t_peak is None else r.t_peak + shift, r.ok, r.kind, r.bound, r.target, r.accuracy)
                 for r in rows)
    return LimitReport(rows, T, dwell, (f"{motion.kind} table ({len(motion.points)} points) as the drive rebuilds it",))
