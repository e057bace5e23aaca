"""A line robot's search of the shortest duration at which every limit of its profile holds (the rules ``fit`` and
``limits``), and the screen of the capacity's durations against the motors: a part of
:class:`~pickplace_cli.line.robot.LineRobot`.

The search runs on the move's grid (:class:`~pickplace_cli.line.moves.ShapeBasis`: the robot model once per trial
duration, peaks refined by a parabola), then decides the move at the duration found: by the exact limit check
(:func:`~pickplace_cli.limits.check.check_limits`, nudging T up until it holds), or — when the limit that binds is
exact already (the Cartesian capacity on the path's exact peaks, a decoupled fourth axis in closed form:
:mod:`~pickplace_cli.line.rotary_axis`) and every other timed limit is used at most ``SCREEN_MARGIN`` on the grid — by
the leg's check, as any leg below that margin. A decoupled fourth axis also bounds the search from below: no move with
its turn is shorter than T_axis.
"""

from __future__ import annotations

import numpy as np

from ..curves.peaks import parabolic_peak
from ..model.errors import TaskError, UnreachableError
from .moves import Move, Solved, exact_rule, first_feasible

#: a leg is decided by the screening when every estimated limit use is at most this
SCREEN_MARGIN = 0.9
#: under the rule ``limits`` the capacity's durations stand when no joint or motor limit is used beyond this on the
#: grid (its estimates are within 0.3 % of the exact peaks; a leg above SCREEN_MARGIN is still checked exactly)
LIMITS_SCREEN = 0.95
#: the quantities a duration changes (the fit rule's); positions, workcell and singularity do not
TIMED = frozenset({"velocity", "acceleration", "jerk", "motor speed", "motor torque", "motor torque rate"})
#: the power of 1/T each of them grows with at most (a torque's gravity part does not grow: less than 2)
NUDGE_ORDER = {"velocity": 1, "motor speed": 1, "acceleration": 2, "motor torque": 2, "jerk": 3, "motor torque rate": 3}


class LimitSearch:
    """The duration search on every limit (module docstring); mixed into the line robot, whose ``model``, ``profile``,
    ``capacity``, ``rotary`` and ``axis`` it reads."""

    _last_uses = None  #: (move, T, other, axis) of the last single-T evaluation (the search's last is often asked again)

    def _motors_clear(self, solved: Solved) -> bool:
        """Every timed joint and motor limit used at most ``LIMITS_SCREEN`` on the move's grid at its duration (a
        decoupled fourth axis' exact: beyond it, no need to evaluate the model)."""
        if self.axis is not None and self.axis.use(solved.move, solved.T) > LIMITS_SCREEN:
            return False
        return bool(self._excess_fit(solved.move, np.array([solved.T]))[0] <= LIMITS_SCREEN - 1.0)

    def _solve_fit(self, moves: list[Move], a: float, b: float, capacity: bool = False,
                   guess: float | None = None) -> Solved | None:
        """The smallest T in [a, b] (from T_axis up, with a decoupled fourth axis) at which every timed limit holds on
        the grid, then decided at T (module docstring): screened, or by the exact check and nudged up until it holds
        (as the rendezvous fit does). ``capacity``: the Cartesian capacity too (the rule limits: the longer of both,
        the capacity on the exact peaks)."""
        def excess(mv):
            if not capacity:
                return lambda Ts: self._excess_fit(mv, Ts)
            auto = mv.excess_auto(self.capacity)
            return lambda Ts: np.maximum(self._excess_fit(mv, Ts), auto(Ts))

        best = None
        for mv in moves:
            lo = max(a, self.axis.shortest(mv)) if self.axis is not None else a  # below it the fourth axis breaks one
            g = None if guess is None else max(guess, lo)
            if capacity:  # the capacity's own first T (cheap: no model); where the motors hold there, it is the answer,
                lo = g = first_feasible(mv.excess_auto(self.capacity), lo, b, scan=8, guess=g)  # else from there up
                if lo is None:
                    continue
            T = first_feasible(excess(mv), lo, b, scan=8, guess=g)
            if T is not None and (best is None or T < best[1]):
                best = (mv, T)
        if best is None:
            return None
        mv, T = best
        from ..limits.check import check_limits
        from ..planner import motion_model

        for _ in range(20):
            if T > b * (1 + 1e-12):
                return None
            peaks = None
            if capacity:  # the capacity on the exact peaks: T_auto(T)/T > 1 when it is exceeded: nudged first (the
                (peaks,), (t_rule,) = exact_rule([(mv, T)], self.capacity)  # limits are then checked where it holds)
                if t_rule > T:
                    T *= t_rule / T * (1.0 + 1e-9)
                    continue
            if self._screened(mv, T):  # (the binding limit is exact: the capacity or the fourth axis)
                return Solved(mv, T, peaks if peaks is not None else mv.exact_peaks(T))
            try:
                rep = check_limits(motion_model(mv.path(T), self.profile), T, dwell=0.0)
            except (UnreachableError, TaskError):
                return None
            # each use scales with T as T^-k (speeds k = 1, accelerations and torques at most 2, jerks and torque
            # rates at most 3): the step u^(1/k) is exact for a speed and never too long for the others
            bad = [r.utilisation ** (1 / NUDGE_ORDER[r.quantity]) for r in rep.violations if r.quantity in TIMED]
            if not bad:
                return Solved(mv, T, mv.exact_peaks(T), rep)
            T *= max(bad) * (1.0 + 1e-9)
        return None  # pragma: no cover - converges in one or two steps

    def _screened(self, mv: Move, T: float) -> bool:
        """Every timed limit but the decoupled fourth axis' used at most ``SCREEN_MARGIN`` on the move's grid at T,
        and the axis' (exact in closed form) at most 1: the leg's check then decides the move without the exact
        check (as any leg below the margin), so the search needs none."""
        hit = self._last_uses
        other, axis = hit[2:] if hit is not None and hit[0] is mv and hit[1] == T else self._uses_fit(mv, np.array([T]))
        return bool(other[0] <= SCREEN_MARGIN and axis[0] <= 1.0)

    def _excess_fit(self, mv: Move, Ts: np.ndarray) -> np.ndarray:
        """max over the timed limits of use − 1 on the grid for each trial T (inf where a sample is out of reach);
        a decoupled fourth axis' uses exact (:mod:`~pickplace_cli.line.rotary_axis`)."""
        other, axis = self._uses_fit(mv, np.asarray(Ts, float))
        return np.maximum(other, axis) - 1.0

    def _uses_fit(self, mv: Move, Ts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(max use of the timed limits on the grid but a decoupled fourth axis', max use of the axis' exact) for each
        trial T (inf where a sample is out of reach; the axis' 0 when there is none)."""
        tau = mv.basis.tau
        G = len(tau)
        n = len(Ts)
        motion = [np.concatenate([a + T * b for T in Ts]) for a, b in zip(mv.A, mv.B)]
        if self.rotary and self.axis is None:  # (a decoupled axis is left out: θ ≡ 0 there, its uses exact below)
            motion.append(np.tile(mv.angle_orders(tau), n))
        try:
            parts = self.model.parts(np.tile(tau, n), motion=tuple(motion), singularity=False)
        except UnreachableError:
            if n > 1:
                got = [self._uses_fit(mv, np.array([T])) for T in Ts]
                return np.concatenate([g[0] for g in got]), np.concatenate([g[1] for g in got])
            return np.full(1, np.inf), np.zeros(1)
        meta, data = self.model.columns(parts, np.repeat(Ts, G))
        cols = [c for c, m in enumerate(meta) if m[1] in TIMED]
        axis = np.zeros(n)
        if not cols:  # no timed limit (a gantry without drives' ratings): none binds
            return np.zeros(n), axis
        timed = [meta[c] for c in cols]
        limits = np.array([m[3] for m in timed])
        peaks = parabolic_peak(np.tile(tau, n), data[:, cols], np.arange(0, n * G + 1, G))[0] / limits
        if self.axis is not None:
            idx, _, _, lim = self.axis.plan(timed)
            axis = np.max(self.axis.values(timed, mv, (mv.theta, mv.theta_end), Ts) / lim, axis=1, initial=0.0)
            peaks[:, idx] = 0.0
        other = np.max(peaks, axis=1)
        if n == 1:
            self._last_uses = (mv, float(Ts[0]), other, axis)
        return other, axis

    # ---------------------------------------------------------------------------------------- the check
