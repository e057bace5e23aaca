"""One robot of a line: its frame, profile, window and place targets, and the cycle it runs for a part.

**The cycle** (as a belt schedule's, :mod:`~pickplace_cli.pipelines.schedule`, with the robot's state carried
over): the robot is free from ``t_free`` at ``position`` (at rest, or moving with an outgoing belt after a place
on it). A part detected at ``t`` may be reached from ``t_ready = t + latency``. The pick move starts at
``t_start = max(t_free, t_ready)``:

1. **pick**: from the robot's position and velocity to the part, arriving with the belt's velocity at the
   meeting point, in T by the robot's duration rule (:mod:`~pickplace_cli.line.moves`); the meeting must lie
   in the window (from its start to ``claim`` into it) with room left for the tracking;
2. **track**: the profile's dwell plus the gripper's closing time with the part at the belt's velocity (the grip);
3. **place**: to the next place target (a point, a tray slot: arriving at rest; an outgoing belt: arriving with
   its velocity), leaving with the belt's velocity, duration by the same rule;
4. **release**: the dwell plus the gripper's opening time at the place point (at rest; on an outgoing belt, moving
   with it).

Then ``t_free = t_start + T_pick + (dwell + close) + T_place + (dwell + open)``. A robot left moving with an outgoing
belt starts its next pick from that motion when the part is already waiting; otherwise it first comes to rest by a
**stop** move to its home point (at once, at ``t_free``). A part the robot cannot take (no meeting in the window, a move
that breaks a limit or leaves the workspace) is declined with the reason; the robot's state does not change.

**Limits.** Every leg is checked against every limit of the profile except the RMS torque, which is a property
of the robot's whole sequence (:mod:`~pickplace_cli.line.engine`). The check evaluates the robot model once for
all legs of the cycle on each leg's grid (:class:`~pickplace_cli.line.moves.ShapeBasis`); a leg whose estimated
use of every limit is at most ``SCREEN_MARGIN`` is decided by that (the estimates are within 0.3 % of the exact
peaks, as the batch verdict engine measures); any other leg is checked by the project's exact limit check
(:func:`~pickplace_cli.limits.check.check_limits`) on its real path. A rotary fourth axis decoupled from the arm
(a Delta's: :mod:`~pickplace_cli.line.rotary_axis`) is left out of the model's evaluation and its limits' uses are
exact in closed form: they decide the axis (at most 1), the grid's estimates the rest. Under the rule ``limits`` the
same evaluation screens the capacity's durations against the motors (``LIMITS_SCREEN``) and is kept for the check of
the cycle's legs, so an accepted cycle costs one model evaluation.
"""

from __future__ import annotations

import math

import numpy as np

from ..curves.peaks import parabolic_peak
from ..model.errors import PickplaceError, TaskError, UnreachableError
from .frames import Frame
from .grids import UsePlan, _leg_of, track_basis
from .legs import Cycle, Decline, Leg, RobotState
from .limit_search import LIMITS_SCREEN, NUDGE_ORDER, SCREEN_MARGIN, TIMED, LimitSearch  # noqa: F401 - (re-exported)
from .moves import (HORIZON, Move, Shapes, Solved, T_MIN, first_feasible, search_auto, solve_auto,
                    solve_seconds, verify_auto)

#: the capacity rule's durations found on the grid are raised by this fraction before their exact check (the
#: refined grid peaks are within 1.3e-4 of the exact ones on a 3-robot line's moves, median 1e-5), so the exact
#: check rarely has to nudge one (which would move the meeting point and so the place move's start)
GRID_SAFETY = 2e-4
#: rounds of a cycle delayed until its place move arrives after an exchange (the part moves on meanwhile)
EXCHANGE_ROUNDS = 6


class _Reason:
    """The reason a part cannot be met in the window, with by how much when the capacity rule says so: worked out
    only when it is read (a part some other robot takes never needs it)."""

    def __init__(self, robot, moves, a, b, along0, busy) -> None:
        self.args = (robot, moves, a, b, along0, busy)
        self.text: str | None = None

    def __str__(self) -> str:
        if self.text is None:
            robot, moves, a, b, along0, busy = self.args
            self.text = robot._missed_reason(moves, a, b, along0, busy, by_how_much=True)
            self.args = None
        return self.text

    def short(self) -> str:
        """The reason without by how much (no search)."""
        if self.text is not None:
            return self.text
        robot, moves, a, b, along0, busy = self.args
        return robot._missed_reason(moves, a, b, along0, busy, by_how_much=False)


class _StandIn:
    """The path of the robot's stacked model calls: never evaluated (the motion is given to the model)."""

    breakpoints = np.array([0.0, 1.0])
    jumps = ()

    def __call__(self, tau, order=0):  # pragma: no cover - the model is always given the motion
        raise RuntimeError("the line's stacked model has no path")

    def angle_orders(self, tau):
        """No angle law: a robot with a rotary fourth axis holds the tool angle at 0 rad (its model's default)."""
        return None


class LineRobot(LimitSearch):
    """A robot of the line (module docstring): set up from its :class:`~pickplace_cli.line.spec.RobotSpec`."""

    def __init__(self, spec, line, profile, shapes: Shapes, latency: float, grip: float) -> None:
        from ..limits.motion import MotionModel
        from ..model.headroom import apply_limit_use, limit_specs
        from ..planner import motion_model_static
        from .spec import time_rule

        profile = apply_limit_use(profile, spec.limit_use)  # every timed limit at its limit-use fraction
        self.limit_use = profile.limit_use
        self.spec, self.name, self.profile = spec, spec.name, profile
        self.frame = Frame.of(spec.base, line.belt.direction)
        self.speed = float(line.belt.speed)
        self.v_belt = self.frame.velocity(self.speed)
        self.window = (float(spec.window[0]), float(spec.window[1]))
        claim = line.strategy.claim
        #: the tracking at the pick (the dwell and the gripper's closing) and the wait at the place (the dwell and its
        #: opening) [s]
        self.dwell = float(profile.planning.dwell) + float(spec.gripper.close)
        self.release = float(profile.planning.dwell) + float(spec.gripper.open)
        self.meet_end = self.window[1] - self.speed * self.dwell
        if claim is not None:
            self.meet_end = min(self.meet_end, self.window[0] + float(claim))
        self.latency, self.grip = float(latency), float(grip)
        self.rule = time_rule(spec)
        self.optimal = spec.shape == "optimal"
        self.height, self.eta = float(profile.planning.height), float(profile.planning.eta)
        self.capacity = profile.capacity
        self.shapes = shapes
        robot, specs, margin, box, memo = motion_model_static(profile)
        self.model = MotionModel(_StandIn(), robot, specs, margin, box, memo)
        self.joint_names = list(robot.joint_names)
        self.rated = np.array([s.drive.rated_torque if s.drive is not None and s.drive.rated_torque else np.nan
                               for s in limit_specs(profile.rated)])  # the RMS is reported against the ratings
        self.has_drives = self.model.has_drives
        self.targets = _targets(spec.place, self.frame)
        #: a robot that turns the tool (a rotary fourth axis); the base frame's angle in the line frame [rad]
        self.rotary = bool(getattr(robot, "rotary", False))
        self.phi = math.atan2(self.frame.d[1], self.frame.d[0])
        self.place_angles = _place_angles(spec.place, len(self.targets))
        #: pockets on an outgoing belt (pitch [m], time pocket 0 passes the point [s], reach [m], speed [m/s]) or
        #: None; the next pocket; the place's start time as a function of the pick's duration (set per cycle)
        out = spec.place.belt
        self.pockets = None
        if out is not None and out.pitch is not None:
            self.pockets = (float(out.pitch), float(out.first), float(out.reach if out.reach is not None else
                            out.pitch / 2), math.hypot(*out.velocity))
            if spec.shape == "optimal":
                from ..model.errors import ProfileError

                raise ProfileError(f"robot {spec.name}: shape: optimal does not place into pockets on an outgoing belt "
                                   "(place.belt.pitch): use shape: table")
        self.next_pocket = 0
        self._pocket_skip = 0
        self._leave_time = None
        self.turn_tolerance = float(spec.place.angle_tolerance)
        home = spec.home if spec.home is not None else None
        self.home = self.frame.to_robot(home) if home is not None else self.targets[0][0].copy()
        self.next_target = 0
        #: the rotary fourth axis in closed form where it is decoupled from the arm (a Delta's; else None)
        self.axis = _decoupled_axis(self.model, self.home) if self.rotary else None
        #: (places between two exchanges, seconds of an exchange), or None; until when it cannot place [s]; the
        #: exchanges (start, end) [s]
        ex = spec.place.exchange
        self.exchange = None if ex is None else (int(ex.every or len(self.targets)), float(ex.time))
        self.blocked_until = -math.inf
        self.exchanges: list = []
        self.state = RobotState(self.home.copy(), np.zeros(3), -math.inf)
        self.last_T = 0.2
        self.last_place_T = 0.2
        self._plan = None
        self._last_uses = self._kept = self._timed = None
        self.use_keys: list = []
        try:
            self.home_torque = self._holding(self.home)
        except UnreachableError as exc:  # (before check_reach: name the robot and its home, as check_reach does)
            ln = self.frame.to_line(self.home)
            raise UnreachableError(f"robot {self.name}: home point [{ln[0]:g}, {ln[1]:g}, {ln[2]:g}] m (line frame) is "
                                   f"outside the workspace of profile {self.profile.name}: {exc}") from None

    # ------------------------------------------------------------------------------------------ geometry
    def part_at(self, along: float, across: float) -> np.ndarray:
        """A part's grip point [m, robot frame] at ``along``, ``across`` on the belt."""
        return self.frame.to_robot(np.array([along, across, self.grip]))

    def _holding(self, point) -> np.ndarray:
        """The motor torque [N·m] that holds the tool at rest at ``point`` (gravity)."""
        z = np.zeros((1, 3))
        parts = self.model.parts(np.zeros(1), derivatives=False, motion=(np.asarray(point, float)[None], z, z, z),
                                 singularity=False)
        return parts.Gm[0].copy() if self.has_drives else parts.G[0].copy()

    # --------------------------------------------------------------------------------------- the cycle
    def stop_first(self, t_ready: float, along: float = math.inf, t_detect: float = 0.0) -> Leg | Decline | None:
        """The stop leg a robot moving with an outgoing belt needs before the next part (detected at ``t_detect``
        at ``along``, ready at ``t_ready``): None when it can start that pick from its motion — the part is known and
        already in its window when the robot is free — or it is at rest. Otherwise it comes to rest at its home
        point at once (the parts after it come later still)."""
        st = self.state
        if not st.moving:
            return None
        along_free = along + self.speed * (st.t_free - t_detect)
        if t_ready <= st.t_free and along_free >= self.window[0]:
            return None
        moves = [Move(b, st.position, st.velocity, self.home, np.zeros(3), np.zeros(3), self.height, self.eta, st.angle)
                 for b in self._shapes_for(st.position, st.velocity, self.home, np.zeros(3))]
        solved = self._solve(moves, T_MIN, HORIZON)
        if solved is None:
            return Decline(f"robot {self.name}: cannot come to rest at its home point after placing on the outgoing belt", 1)
        leg = Leg("stop", st.t_free, solved.T, solved)
        bad = self._check([leg])
        if bad is not None:
            return bad
        return leg

    def commit_stop(self, leg: Leg) -> None:
        self.state = RobotState(leg.end.copy(), np.zeros(3), leg.t1, leg.end_angle)

    def turns(self, angle: float | None, st: RobotState) -> tuple[float, float, float] | Decline:
        """(tool angle at the start, turn of the pick, turn of the place) [rad, base frame] for a part lying at
        ``angle`` [rad, line frame] (None: not known) placed at the next target's angle. The place needs the turn
        wrap(place − part) (the shorter way round, |turn| ≤ π); the tool puts the part down at the place angle taken
        within (−π, π] in the base frame, so it takes the part at that angle less the turn (the gripper takes it as
        it lies) and turns to it on the way there: every tool angle stays within 2π of 0 rad, and the pick's turn
        within π once the tool has placed a part. No turn without both angles; a Decline when the robot has no
        rotary axis and the turn is larger than the place's ``angle_tolerance``."""
        place = self.place_angles[self.next_target % len(self.targets)]
        if angle is None or place is None:
            return st.angle, 0.0, 0.0
        from ..curves.rotation import resolve_turn

        need = resolve_turn(angle, place) - angle
        if not self.rotary:
            if abs(need) <= self.turn_tolerance:
                return st.angle, 0.0, 0.0
            return Decline(f"robot {self.name}: the part lies at {angle:.4f} rad and the place wants {place:.4f} rad: "
                           f"a turn of {need:.4f} rad (more than angle_tolerance = {self.turn_tolerance:g} rad) and "
                           f"profile {self.profile.name} has no rotary fourth axis", 4)
        put = resolve_turn(0.0, place + self.phi)
        return st.angle, put - need - st.angle, need

    def plan(self, along: float, across: float, t_detect: float, state: RobotState | None = None,
             angle: float | None = None) -> Cycle | Decline:
        """The cycle of a part detected at ``t_detect`` [s] at ``along``, ``across`` [m] lying at ``angle`` [rad,
        line frame; None: not known] from ``state`` (default the robot's), or why it cannot take it (module
        docstring). Does not change the robot.

        While its place is being exchanged (until ``blocked_until``) the robot cannot place: a cycle whose place
        move would arrive before then starts later by the difference, again until it arrives at or after that
        time (the part is then further along; a few rounds), or the part is declined saying so."""
        st = self.state if state is None else state
        got = self._cycle(along, across, t_detect, st, angle)
        if self.pockets is not None:  # a pocket the place move cannot meet in time: the next one
            for skip in (1, 2, 3):
                if not (isinstance(got, Decline) and got.place):
                    break
                self._pocket_skip = skip
                got = self._cycle(along, across, t_detect, st, angle)
            self._pocket_skip = 0
        late = st
        for _ in range(EXCHANGE_ROUNDS):
            if isinstance(got, Cycle) and got.t_placed >= self.blocked_until - 1e-9:
                return got
            if not isinstance(got, Cycle):
                break
            # later by the shortfall and a quarter more (the part has moved on: the pick is a little shorter)
            late = RobotState(late.position, late.velocity,
                              got.t_start + 1.25 * (self.blocked_until - got.t_placed) + 1e-6, late.angle)
            got = self._cycle(along, across, t_detect, late, angle)
        if late is st:
            return got
        why = got.reason if isinstance(got, Decline) else "its place move still arrives before then"
        return Decline(f"robot {self.name}: its place is exchanged until t = {self.blocked_until:.4f} s, and a cycle "
                       f"placing after that cannot: {why.removeprefix(f'robot {self.name}: ')}",
                       got.code if isinstance(got, Decline) else 4)

    def _cycle(self, along: float, across: float, t_detect: float, st: RobotState,
              angle: float | None) -> Cycle | Decline:
        """:meth:`plan` without the exchange's wait."""
        turns = self.turns(angle, st)
        if isinstance(turns, Decline):
            return turns
        th0, t_pick, t_place = turns
        th_grip = th0 + t_pick
        pturn = (th_grip, t_place)
        t_ready = t_detect + self.latency
        t_start = max(st.t_free, t_ready)
        along0 = along + self.speed * (t_start - t_detect)  # where the part is when the move starts
        a = max(T_MIN, (self.window[0] - along0) / self.speed)
        b = (self.meet_end - along0) / self.speed
        busy = f"busy until t = {st.t_free:.4f} s, " if st.t_free > t_ready else ""
        if b < a and self.window[1] - self.speed * self.dwell < self.window[0] + 1e-12:  # the tracking outruns it
            w = self.window[1] - self.window[0]
            return Decline(f"robot {self.name}: no meeting point in its window [{self.window[0]:g}, {self.window[1]:g}] "
                           f"m: tracking the part for the dwell ({self.dwell:g} s at {self.speed:g} m/s = "
                           f"{self.speed * self.dwell:.4g} m) needs more than the window's {w:.4g} m")
        if b < a:
            where = "its window's end" if self.meet_end < self.window[0] + 1e-12 or along0 > self.window[0] else "it"
            return Decline(f"robot {self.name}: {busy}the part is at along {along0:.4f} m when a move could start, past "
                           f"{where} (last meeting point along {self.meet_end:.4f} m)")
        target, v_out = self.targets[self.next_target % len(self.targets)]
        solved = None
        waited = False
        if along0 < self.window[0] and not st.moving:
            # the part has not reached the window yet: the robot waits at rest and starts its move so as to meet it
            # where it enters the window, when the rule's move there fits in the time left
            entry = self.part_at(self.window[0], across)
            t_entry = t_detect + (self.window[0] - along) / self.speed
            wmoves = [Move(bs, st.position, st.velocity, entry, np.zeros(3), self.v_belt, self.height, self.eta, th0,
                           t_pick) for bs in self._shapes_for(st.position, st.velocity, entry, self.v_belt)]
            self._leave_time = lambda T: t_entry + self.dwell  # noqa: E731 - the place starts after the tracking
            got = self._pick_and_place(wmoves, T_MIN, t_entry - t_start, target, v_out, pturn)
            if isinstance(got, tuple) and t_entry - got[0].T >= t_start:
                solved, t_start, waited = got, t_entry - got[0].T, True
        if solved is None:
            p0 = self.part_at(along0, across)
            moves = [Move(bs, st.position, st.velocity, p0, self.v_belt, self.v_belt, self.height, self.eta, th0, t_pick)
                     for bs in self._shapes_for(st.position, st.velocity, p0 + self.v_belt * self.last_T, self.v_belt)]
            self._leave_time = lambda T: t_start + T + self.dwell  # noqa: E731
            solved = self._pick_and_place(moves, a, b, target, v_out, pturn)
            if solved is None:
                return Decline(_Reason(self, moves, a, b, along0, busy))
        if isinstance(solved, Decline):
            return solved
        pick, place = solved
        legs = self._legs(t_start, pick, place, pturn, v_out)
        meet = legs[1].point
        bad = self._check(legs)
        if bad is not None:
            return bad
        end = legs[-1].end
        state = RobotState(end.copy(), v_out.copy(), legs[-1].t1, th_grip + t_place)
        meet_line = self.frame.to_line(meet)
        where = place.move.pocket if self.pockets is not None else self.next_target % len(self.targets)
        return Cycle(legs, t_start, t_start + pick.T, meet.copy(), meet_line, where, place.end.copy(), state,
                     waited=waited)

    def _legs(self, t_start: float, pick: Solved, place: Solved, turn: tuple[float, float], v_out) -> list[Leg]:
        """The legs of a cycle from ``t_start`` [s]: pick, track (the grip, at the tool angle ``turn[0]``), place (the
        turn ``turn[1]``) and release."""
        track = Leg("track", t_start + pick.T, self.dwell, point=pick.end, velocity=self.v_belt.copy(), theta=turn[0])
        legs = [Leg("pick", t_start, pick.T, pick), track, Leg("place", track.t1, place.T, place)]
        legs.append(Leg("release", legs[-1].t1, self.release, point=place.end.copy(), velocity=np.array(v_out, float),
                        theta=turn[0] + turn[1]))
        return legs

    def commit(self, cycle: Cycle) -> None:
        self.state = cycle.state
        self.next_target += 1
        if self.pockets is not None:
            self.next_pocket = cycle.target + 1
        if self.exchange is not None and self.next_target % self.exchange[0] == 0:
            self.blocked_until = cycle.t_free + self.exchange[1]  # a full tray: exchanged once the part is released
            self.exchanges.append((cycle.t_free, self.blocked_until))
        self.last_T = cycle.pick.duration
        self.last_place_T = next(leg.duration for leg in cycle.legs if leg.kind == "place")

    # ------------------------------------------------------------------------------------------ solving
    def _shapes_for(self, start, v_from, end, v_to) -> list:
        """The candidate shapes of a move from ``start`` to about ``end`` (its groups estimated at the robot's last
        pick duration)."""
        from ..model.task import Task

        T = self.last_T
        try:
            task = Task(start, end, self.height, self.eta, v_from, v_to)
        except TaskError:
            return [self.shapes.basis(_paper())]
        return self.shapes.candidates(task, T)

    def _place_moves(self, leave, target, v_out, turn=(0.0, 0.0), T_pick: float = 0.0) -> list[Move]:
        """The candidate place moves; ``turn``: (tool angle at the start, the turn) [rad]. Each carries ``span``, the
        durations [s] it may take, and ``pocket``: a fixed target any (T_MIN … HORIZON, None); a pocket on an outgoing
        belt (:meth:`pocket`) is met like a part, its end moving with the belt, within its reach."""
        span, pocket, end_b = (T_MIN, HORIZON), None, np.zeros(3)
        if self.pockets is not None:
            pocket, target, span = self.pocket(self._leave_time(T_pick), v_out)
            end_b = v_out
        moves = [Move(bs, leave, self.v_belt, target, end_b, v_out, self.height, self.eta, *turn)
                 for bs in self._shapes_for(leave, self.v_belt, target + end_b * self.last_place_T, v_out)]
        for mv in moves:
            mv.span, mv.pocket = span, pocket
        return moves

    def pocket(self, t_leave: float, v_out) -> tuple[int, np.ndarray, tuple[float, float]]:
        """(k, where pocket k is at ``t_leave`` [m, robot frame], the place move's durations (a, b) [s] that meet it
        within its reach): the first pocket from the next free one on that the move can still meet, judged by the
        robot's last place duration (pocket k passes the point at first + k·pitch/speed)."""
        pitch, first, reach, speed = self.pockets
        point = self.targets[0][0]
        soonest = t_leave + max(T_MIN, 0.9 * self.last_place_T) - reach / speed
        k = max(self.next_pocket, math.ceil((soonest - first) * speed / pitch - 1e-9)) + self._pocket_skip
        t_k = first + k * pitch / speed
        span = (max(T_MIN, t_k - reach / speed - t_leave), t_k + reach / speed - t_leave)
        return k, point + v_out * (t_leave - t_k), span

    def _pick_and_place(self, moves: list[Move], a: float, b: float, target, v_out, turn=(0.0, 0.0)):
        """(pick, place) Solved, None when the pick cannot meet the part in [a, b], or a Decline for the place.
        The capacity rule: both durations searched on the grid (raised by ``GRID_SAFETY``), then checked on their
        exact peaks in one batch; a move the exact check nudges is searched again from where it must start."""
        if self.optimal:
            from .optimal import pick_and_place

            got = pick_and_place(self, moves[0], a, b, target, v_out, turn)
            return Decline(got, 1) if isinstance(got, str) else got
        if self.rule == "limits":
            # the capacity's durations first (cheap): where every joint and motor limit holds there with room to
            # spare (LIMITS_SCREEN), they are the rule's answer (no shorter move holds the capacity, and these hold
            # the motors: the cycle's check then decides the legs as for any rule)
            got = self._capacity_pick_and_place(moves, a, b, target, v_out, turn)
            if not isinstance(got, tuple):
                return got  # (None or a Decline: no move holds the capacity, so none holds every limit)
            pick, place = got
            clear = self._motors_clear_both(pick, place, turn, v_out)
            if clear[0]:
                if clear[1]:
                    return got
                # the pick stands; the place alone is searched on every limit, from its capacity duration up (the
                # rule's duration is the longer of both: none shorter holds)
                leave = pick.end + self.v_belt * self.dwell
                pm = self._place_moves(leave, target, v_out, turn, pick.T)
                place = self._solve_fit(pm, *pm[0].span, True, place.T)
                return (pick, place) if place is not None else self._no_place(leave, target)
            pick = self._solve_fit(moves, a, b, True, pick.T)
            if pick is None:
                return None
            leave = pick.end + self.v_belt * self.dwell  # (the place then starts elsewhere: searched from the
            pm = self._place_moves(leave, target, v_out, turn, pick.T)  # capacity's place duration up)
            place = self._solve_fit(pm, *pm[0].span, True, place.T)
            return (pick, place) if place is not None else self._no_place(leave, target)
        if self.rule != "auto":
            pick = self._solve(moves, a, b)
            if pick is None:
                return None
            pm = self._place_moves(pick.end + self.v_belt * self.dwell, target, v_out, turn, pick.T)
            place = self._solve(pm, *pm[0].span)
            return (pick, place) if place is not None else self._no_place(pick.end + self.v_belt * self.dwell, target)
        return self._capacity_pick_and_place(moves, a, b, target, v_out, turn)

    def _capacity_pick_and_place(self, moves: list[Move], a: float, b: float, target, v_out, turn=(0.0, 0.0)):
        """(pick, place) by the Cartesian capacity (the rule ``auto``), None, or a Decline for the place."""
        found = search_auto(moves, self.capacity, a, b, guess=self.last_T)
        if found is None:
            return None
        mv, T = found
        T = min(T * (1 + GRID_SAFETY), b) if T > a else T
        leave = mv.end(T) + self.v_belt * self.dwell
        pmoves = self._place_moves(leave, target, v_out, turn, T)
        lo, hi = pmoves[0].span
        pfound = search_auto(pmoves, self.capacity, lo, hi, guess=self.last_place_T)
        if pfound is None:
            return self._no_place(leave, target)
        pmv, pT = pfound
        both = verify_auto([(mv, T, b), (pmv, min(pT * (1 + GRID_SAFETY), hi) if pT > lo else pT, hi)], self.capacity)
        if both is not None and both[0].T == T:
            return both[0], both[1]
        pick = verify_auto([(mv, T, b)], self.capacity)  # the pick moved (rare): the place starts elsewhere
        if pick is None:
            return None
        pick = pick[0]
        pm = self._place_moves(pick.end + self.v_belt * self.dwell, target, v_out, turn, pick.T)
        place = self._solve(pm, *pm[0].span)
        return (pick, place) if place is not None else self._no_place(pick.end + self.v_belt * self.dwell, target)

    def _no_place(self, leave, target) -> Decline:
        return Decline(f"robot {self.name}: no place move from {_xyz(leave)} m to {_xyz(target)} m within "
                       f"{HORIZON:g} s by the rule {self.rule}" + (" (pockets: the next three tried too)" if self.pockets
                                                                   else ""), 1, place=True)

    def _solve(self, moves: list[Move], a: float, b: float) -> Solved | None:
        if a > b:
            return None
        if self.rule == "auto":
            return solve_auto(moves, self.capacity, a, b)
        if self.rule == "fit":
            return self._solve_fit(moves, a, b)
        if self.rule == "limits":
            return self._solve_fit(moves, a, b, capacity=True)
        return solve_seconds(moves, float(self.rule), a, b)

    def _missed_reason(self, moves: list[Move], a: float, b: float, along0: float, busy: str,
                       by_how_much: bool = True) -> str:
        """Why no meeting in [a, b]: by how much the part is missed when the capacity rule says so."""
        rule = self.rule if isinstance(self.rule, str) else f"{self.rule:g} s"
        text = (f"robot {self.name}: {busy}cannot meet the part in its window by the rule {rule} (the meeting must lie "
                f"between along {max(self.window[0], along0):.4f} and {self.meet_end:.4f} m)")
        if by_how_much and self.rule == "auto" and b < HORIZON:
            T = first_feasible(moves[0].excess_auto(self.capacity), b, HORIZON, guess=b)
            if T is not None:
                text += f"; the earliest meeting is {self.speed * (T - b) * 1e3:.0f} mm past that"
        return text

    def _check(self, legs: list[Leg]) -> Decline | None:
        """Check every leg (module docstring); fills each leg's integral, use and end torque. A Decline naming the
        leg and the limit (or the point out of reach) when one fails."""
        got = self._evaluate(legs)
        if isinstance(got, Decline):
            return got
        meta, peaks, sums = got
        plan = self._use_plan(meta)
        for leg, (integral, end) in zip(legs, sums):
            leg.integral, leg.end_torque = integral, end
        axis = None if self.axis is None else np.array([k[0] == self.axis.joint for k in self.use_keys], bool)
        uses = plan(peaks)
        for leg, use in zip(legs, uses):
            leg.use = use
            if axis is None and use.max(initial=0.0) > SCREEN_MARGIN or axis is not None and (
                    use[~axis].max(initial=0.0) > SCREEN_MARGIN or use[axis].max(initial=0.0) > 1.0):
                bad = self._exact_check(leg)
                if bad is not None:
                    return bad
        return None

    def _motors_clear_both(self, pick: Solved, place: Solved, turn, v_out) -> tuple[bool, bool]:
        """:meth:`_motors_clear` of the pick and of the place, from one evaluation of the model on the cycle's legs,
        kept for the cycle's check (:meth:`_evaluate`) when it asks for the same legs."""
        legs = self._legs(0.0, pick, place, turn, v_out)
        got = self._evaluate(legs)
        if isinstance(got, Decline):  # a point out of reach: each move on its own (that leg's search then says)
            return self._motors_clear(pick), self._motors_clear(place)
        self._kept = (legs, got)
        meta, peaks, _ = got
        if self._timed is None or self._timed[0] != meta:
            cols = [c for c, m in enumerate(meta) if m[1] in TIMED]
            self._timed = (meta, cols, np.array([meta[c][3] for c in cols]))
        _, cols, limits = self._timed
        use = np.max(peaks[[0, 2]][:, cols] / limits, axis=1, initial=0.0)
        return bool(use[0] <= LIMITS_SCREEN), bool(use[1] <= LIMITS_SCREEN)

    def _evaluate(self, legs: list[Leg]):
        """The robot model once on every leg's grid: (meta, column peaks (legs × columns; a decoupled fourth axis'
        exact), [(∫ torque² dt [N²·m²·s], end torque [N·m])] per leg), or a Decline naming the leg out of reach. The
        evaluation kept by :meth:`_motors_clear_both` serves when its legs are these (the same moves and durations)."""
        kept, self._kept = self._kept, None
        if kept is not None and _same_legs(kept[0], legs):
            return kept[1]
        grids = []
        for leg in legs:
            if leg.solved is not None:
                bs = leg.solved.move.basis
                grids.append((bs.tau, leg.solved.samples(), bs.gl_index, bs.gl_weight))
            else:
                tb = track_basis()
                d = leg.velocity * leg.duration
                p = leg.point + np.multiply.outer(tb.tau, d)
                z = np.zeros_like(p)
                grids.append((tb.tau, [p, np.broadcast_to(d, p.shape).copy(), z, z], tb.gl_index, tb.gl_weight))
        tau = np.concatenate([g[0] for g in grids])
        motion = tuple(np.concatenate([g[1][k] for g in grids]) for k in range(4))
        if self.rotary and self.axis is None:  # the tool angle of every leg (its turn, or held); a decoupled axis
            # is left out (θ ≡ 0 there: no column, no torque of it) and added in closed form below
            motion += (np.concatenate([leg.angle_orders(g[0]) for g, leg in zip(grids, legs)], axis=1),)
        Ts = np.concatenate([np.full(len(g[0]), max(leg.duration, 1e-9)) for g, leg in zip(grids, legs)])
        try:
            parts = self.model.parts(tau, motion=motion)
        except UnreachableError as exc:
            k = _leg_of(exc.index, grids)
            return Decline(f"robot {self.name}: the {legs[k].kind} move (t = {legs[k].t0:.4f} … {legs[k].t1:.4f} s) "
                           f"leaves the workspace: {exc}")
        meta, data = self.model.columns(parts, Ts)
        start = 0
        peaks = parabolic_peak(tau, data, np.concatenate([[0], np.cumsum([len(g[0]) for g in grids])]))[0]
        sums = []
        for leg, (gtau, _, gl_i, gl_w) in zip(legs, grids):
            sl = slice(start, start + len(gtau))
            start += len(gtau)
            T = max(leg.duration, 1e-9)
            am, gm = (parts.Am[sl], parts.Gm[sl]) if self.has_drives else (parts.A[sl], parts.G[sl])
            torque = am / T**2 + gm
            at_nodes = torque[gl_i]
            mv = leg.solved.move if leg.solved is not None else None
            if self.axis is not None:  # the decoupled axis: its torque (θ″ alone: 0 at a leg's end) and columns exact
                at_nodes[:, -1] += self.axis.torque(mv, gtau[gl_i], T)
                ends = (mv.theta, mv.theta_end) if mv is not None else (leg.theta, leg.theta)
                peaks[len(sums), self.axis.plan(meta)[0]] = self.axis.values(meta, mv, ends, T)[0]
            sums.append((T * (gl_w[:, None] * at_nodes ** 2).sum(axis=0), torque[-1].copy()))
        return meta, peaks, sums

    def _use_plan(self, meta) -> "UsePlan":
        if self._plan is None or self._plan.meta != meta:  # the same columns every time (a new list each call)
            self._plan = UsePlan(meta)
            self.use_keys = self._plan.keys
        return self._plan

    def _exact_check(self, leg: Leg) -> Decline | None:
        """The exact limit check of one leg on its real path (RMS aside); the leg's use from it."""
        from ..limits.check import check_limits
        from ..planner import motion_model

        T = leg.duration
        done = leg.solved.report if leg.solved is not None else None  # the duration search's own exact check
        try:
            rep = done if done is not None else check_limits(motion_model(_leg_path(leg), self.profile), T, dwell=0.0)
        except UnreachableError as exc:
            return Decline(f"robot {self.name}: the {leg.kind} move (t = {leg.t0:.4f} … {leg.t1:.4f} s) leaves the "
                           f"workspace: {exc}")
        leg.exact = True
        use = leg.use.copy()
        index = {k: i for i, k in enumerate(self.use_keys)}
        for r in rep.rows:
            if (r.joint, r.quantity) in index:
                use[index[(r.joint, r.quantity)]] = r.utilisation
        leg.use = use
        bad = [r for r in rep.violations if r.quantity != "rms motor torque"]
        if not bad:
            return None
        from ..pipelines.batch import violation_text

        worst = max(bad, key=lambda r: r.utilisation)
        code = 4 if worst.kind == "reach" else 3
        return Decline(f"robot {self.name}: the {leg.kind} move (t = {leg.t0:.4f} … {leg.t1:.4f} s): "
                       f"{violation_text(worst)}", code)


# ------------------------------------------------------------------------------------------------ helpers


def _same_legs(a: list[Leg], b: list[Leg]) -> bool:
    """The same legs but for their start times: kinds, durations, the same moves, track/release lines and angles."""
    return len(a) == len(b) and all(
        x.kind == y.kind and x.duration == y.duration and x.solved is y.solved and x.theta == y.theta
        and (x.solved is not None or np.array_equal(x.point, y.point) and np.array_equal(x.velocity, y.velocity))
        for x, y in zip(a, b))


def _decoupled_axis(model, point):
    """:class:`~pickplace_cli.line.rotary_axis.DecoupledAxis` of the model, None when coupled (or ``point`` is out
    of reach)."""
    from .rotary_axis import DecoupledAxis

    try:
        return DecoupledAxis.of(model, point)
    except UnreachableError:
        return None


def _paper():
    from ..curves.vel_problem import PAPER_INITIAL

    return PAPER_INITIAL


def _xyz(p) -> str:
    return ",".join(f"{c:.4f}" for c in p)


def _leg_path(leg: Leg):
    """The CartesianPath of a leg (its move's, with the turn; a track or release leg's straight line, its angle
    held)."""
    if leg.solved is not None:
        return leg.solved.move.path(leg.duration)
    from ..pipelines.tracking import tracking_path

    path = tracking_path(leg.point, leg.velocity, leg.duration)
    if leg.theta == 0.0:
        return path
    from dataclasses import replace

    from ..curves.rotation import RotationLaw

    return replace(path, angle=RotationLaw(leg.theta, 0.0))


def _place_angles(place, n: int) -> list:
    """The place angle of every target in turn [rad, line frame] (None: the part is placed as it lies)."""
    a = place.angle
    if a is None:
        return [None] * n
    if isinstance(a, (int, float)):
        return [float(a)] * n
    return [float(x) for x in a]


def _targets(place, frame: Frame) -> list[tuple[np.ndarray, np.ndarray]]:
    """(point, arrival velocity) of every place target in turn [m, m/s, robot frame]."""
    if place.belt is not None:
        v = frame.velocity(*place.belt.velocity)
        return [(frame.to_robot(place.belt.point), v)]
    if place.tray is not None:
        t = place.tray
        o = np.asarray(t.origin, float)
        pts = [o + np.array([i * t.pitch[0], j * t.pitch[1], 0.0]) for i in range(t.rows) for j in range(t.columns)]
    else:
        pts = [np.asarray(p, float) for p in place.points]
    return [(frame.to_robot(p), np.zeros(3)) for p in pts]


__all__ = ["LineRobot", "RobotState", "Leg", "Cycle", "Decline", "PickplaceError"]
