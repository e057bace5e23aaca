"""A line robot's rotary fourth axis in closed form, where the axis is decoupled from the arm.

On a Delta the fourth axis turns the tool through a telescopic shaft from the base (:mod:`~pickplace_cli.robots.rotary`,
carrier c = 0): q4 = σ·θ and its torque is σ·J_t·θ̈ alone — the arm's motion does not reach it, and it reaches no arm.
A move's turn is the degree-9 law θ(τ) = θ0 + Δ·s((τ − τa)/(τb − τa))
(:class:`~pickplace_cli.curves.rotation.RotationLaw`), whose peaks are exact in closed form
(P_k = |Δ|·max|s⁽ᵏ⁾|/(τb − τa)ᵏ, :attr:`RotationLaw.peaks`), so each limit of the axis at a duration T is too:

    value_k(T) = c_k·P_k / T^k,    k = 1 (velocity, motor speed), 2 (acceleration, motor torque), 3 (jerk, torque rate)

and its range is the larger of the two end angles (the law is monotone). The coefficients c_k (the gear ratio, the
efficiency, J_t, the rotor's inertia) are not written out here: they are read off the robot model's own limit columns,
evaluated once at rest with a unit θ, θ′, θ″ or θ‴ — and each column must then depend on its own order alone
(no gravity, no velocity term), else the axis counts as coupled. The smallest duration at which all of them hold is

    T_axis = max_k (c_k·P_k / limit_k)^(1/k):

no move with that turn is shorter, whatever the arm does. :class:`~pickplace_cli.line.robot.LineRobot` uses it three
ways: the search of every limit starts at T_axis, the grid's estimates of the axis' uses are replaced by these exact
values, and a leg whose other limits the grid decides needs no exact check for the axis. A SCARA's J4 sits on link 2
(q4 = σ(θ − q1 − q2)): it is coupled to the arm, has no closed form here, and its moves take the general path.
"""

from __future__ import annotations

import math

import numpy as np

#: the limited quantities of the axis and the order of the angle's derivative each grows with (1/T^order)
ORDERS = {"velocity": 1, "motor speed": 1, "acceleration": 2, "motor torque": 2, "jerk": 3, "motor torque rate": 3}
#: T_axis is raised by this fraction (as the exact check nudges a duration: 1 + 1e-9), so the axis' use is below 1 by
#: more than the round-off (~1e-15) of any other evaluation of the same move (the planner's check of its path)
SAFETY = 1e-9
#: the range of the axis (a column of sign +1 holds q4, of sign −1 holds −q4)
RANGE = ("position max", "position min")


class DecoupledAxis:
    """The rotary fourth axis of ``model`` (a :class:`~pickplace_cli.limits.motion.MotionModel` of a robot with
    ``rotary``) in closed form (module docstring); :meth:`of` gives None when the axis is coupled to the arm.
    ``point``: a reachable tool position [m] to read the coefficients at (any: they do not depend on it)."""

    def __init__(self, model, point) -> None:
        self.model = model
        self.joint = model.robot.joint_names[-1]
        self._coef = self._read(np.asarray(point, float))
        self._plans: dict = {}

    @classmethod
    def of(cls, model, point) -> "DecoupledAxis | None":
        robot = model.robot
        if not getattr(robot, "rotary", False) or any(float(c) != 0.0 for c in getattr(robot, "carrier", (1.0,))):
            return None
        axis = cls(model, point)
        return axis if axis._coef is not None else None

    def _read(self, point: np.ndarray) -> dict | None:
        """{quantity: (order, coefficient, limit)} of the axis' columns from the model at rest at ``point`` with θ = 1, then
        θ′ = 1, θ″ = 1, θ‴ = 1 (one sample each): None when a column depends on another order than its own."""
        z = np.zeros((4, 3))
        angle = np.eye(4)  # sample i: the i-th derivative of θ is 1, the others 0
        rates = hasattr(self.model.robot, "torque_rate")  # (the torque rate's columns need the analytic rates)
        parts = self.model.parts(np.zeros(4), derivatives=rates, motion=(np.repeat(point[None], 4, 0), z, z, z, angle),
                                 singularity=False)
        meta, data = self.model.columns(parts, 1.0)
        # the axis' own torque (motor's, or the joint's without drives) per unit θ″, signed: θ″ alone, no gravity
        torque = (parts.Am if self.model.has_drives else parts.A)[:, -1]
        if np.any(np.delete(torque, 2) != 0.0) or np.any(parts.Gm[:, -1] != 0.0) or np.any(parts.G[:, -1] != 0.0):
            return None
        self.torque_coef = float(torque[2])
        out = {}
        for c, m in enumerate(meta):
            if m[0] != self.joint:
                continue
            col = data[:, c]
            k = 0 if m[1] in RANGE else ORDERS.get(m[1])
            if k is None:
                return None
            others = np.delete(col, k)
            if np.any(others != 0.0) or not math.isfinite(col[k]):
                return None
            out[m[1]] = (k, float(col[k]), float(m[3]))
        return out

    def plan(self, meta) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(column indices, orders, coefficients, limits) of the axis' columns among ``meta`` (the model's columns),
        memoised per column layout; order 0: the range."""
        hit = self._plans.get(len(meta))
        if hit is None or hit[4] != meta:
            idx = [c for c, m in enumerate(meta) if m[0] == self.joint and m[1] in self._coef]
            orders = np.array([self._coef[meta[c][1]][0] for c in idx], int)
            coef = np.array([self._coef[meta[c][1]][1] for c in idx])
            limits = np.array([float(meta[c][3]) for c in idx])
            hit = self._plans[len(meta)] = (np.array(idx, int), orders, coef, limits, list(meta))
        return hit[:4]

    @staticmethod
    def law_peaks(move) -> tuple[float, float, float]:
        """Exact max |θ′|, |θ″|, |θ‴| over the move's τ [rad/1^k] (0 without a turn)."""
        return (0.0, 0.0, 0.0) if move is None else move.turn_peaks()

    def values(self, meta, move, theta: tuple[float, float], T) -> np.ndarray:
        """The axis' columns (column sign convention, as :meth:`MotionModel.columns` holds them) at the peaks of a leg
        at the durations ``T`` [s] (scalar or (n,)): (n, columns). ``move``: the leg's Move (None: the angle held);
        ``theta``: the tool angle at its start and end [rad]."""
        idx, orders, coef, _ = self.plan(meta)
        Ts = np.atleast_1d(np.asarray(T, float))
        P = np.array((0.0, *self.law_peaks(move)))[orders]
        timed = coef * P / Ts[:, None] ** orders
        ends = np.maximum(coef * theta[0], coef * theta[1])  # the range (order 0): q4 = σθ is monotone in τ
        return np.where(orders == 0, ends, timed)

    def torque(self, move, tau: np.ndarray, T: float) -> np.ndarray:
        """The axis' torque [N·m] (its motor's; its joint's without drives) at τ (N,) of the move at the duration T [s]:
        the model's own coefficient times θ″(τ)/T² (0 without a turn)."""
        if move is None or move.turn == 0.0:
            return np.zeros(len(tau))
        return self.torque_coef * move.law()(tau, 2) / T**2

    def _needs(self, move) -> list[tuple[int, float]]:
        """(order k, c_k·P_k/limit) of every timed limit of the axis for the move's turn."""
        P = (0.0, *self.law_peaks(move))
        return [(k, c * P[k] / lim) for k, c, lim in self._coef.values() if k > 0]

    def use(self, move, T: float) -> float:
        """The largest use of the axis' timed limits by the move at the duration T [s] (exact)."""
        return max((x / T**k for k, x in self._needs(move)), default=0.0)

    def shortest(self, move) -> float:
        """T_axis [s] of the module docstring: the shortest duration at which every timed limit of the axis holds
        exactly for the move's turn, raised by ``SAFETY`` (0 without a turn)."""
        return max((x ** (1.0 / k) for k, x in self._needs(move)), default=0.0) * (1.0 + SAFETY)
