"""The line: robots along one belt, a strategy, and the parts offered to them one after another.

:class:`LineEngine` takes the detections in time order (:func:`~pickplace_cli.line.parts.in_time_order`) and
answers each at once (:meth:`LineEngine.offer`: the robot that takes it, with its cycle, or the reason it is
missed), so the same engine serves a file, a generator and a stream of detections. Robots are asked in the
strategy's order (:mod:`~pickplace_cli.line.strategies`); the first that can take the part in time takes it
and its state moves on (:mod:`~pickplace_cli.line.robot`). :meth:`LineEngine.finish` closes the run: per robot
the picks, utilisation, idle time, the peak use of every limit over its moves, and each motor's RMS torque over
the robot's actual sequence — its moves, dwells and the time it waits at rest holding the tool against gravity:

    RMS_m = sqrt( (Σ_legs ∫ τ_m(t)² dt + Σ_rests τ_hold,m² · t_rest) / (t_end − t_begin) ),

each leg's integral exact (Gauss–Legendre on every knot span of the leg: :mod:`~pickplace_cli.line.moves`), over
the run's span [t_begin, t_end] = [first detection, the later of the last detection and the end of the last
leg of any robot]; not the single-move duty cycle with its retrace assumption.

**Part types.** On a line with several part types (``parts.types``) a robot takes the types it has a place for
(:func:`~pickplace_cli.line.spec.robot_places`). A robot with a place per type is one
:class:`~pickplace_cli.line.robot.LineRobot` per place — each with that place's targets, tray counter, pockets and
exchanges — sharing one state: after every leg the robot's position, velocity, tool angle and free time are the same
in all of them (:meth:`RobotRun.sync`), so the robot moves as one, and a tray's exchange blocks only its own type.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Iterable, Iterator

import numpy as np

from ..model.errors import PickplaceError, TaskError, UnreachableError
from .parts import BadRow, Detection
from .reach import check_reach
from .robot import Cycle, Decline, Leg, LineRobot, RobotState
from .spec import Line, robot_bands, robot_places, type_names, untaken_types, upstream_order
from .summary import LineSummary, summarise


@dataclass
class PartResult:
    """The answer for one part: taken by ``robot`` with its ``cycle``, or missed (``reason``), or a bad row."""

    detection: Detection | None
    robot: str | None = None
    cycle: Cycle | None = None
    reason: str | None = None
    code: int = 0
    row: int = 0
    declines: dict = field(default_factory=dict)

    @property
    def picked(self) -> bool:
        return self.cycle is not None

    def as_dict(self) -> dict[str, Any]:
        d = self.detection
        doc: dict[str, Any] = {"id": d.id if d else None, "row": self.row, "picked": self.picked,
                               "exit_code": self.code, "robot": self.robot, "reason": self.reason}
        if d is not None:
            doc.update({"t_detect_s": d.t, "along_m": d.along, "across_m": d.across, "angle_rad": d.angle})
            if d.type is not None:
                doc["type"] = d.type
        c = self.cycle
        if c is not None:
            pick = c.pick
            place = next(leg for leg in c.legs if leg.kind == "place")
            doc.update({
                "t_start_s": c.t_start, "t_meet_s": c.t_meet, "meet_along_m": float(c.meet_line[0]),
                "meet_across_m": float(c.meet_line[1]), "meet_m": c.meet_robot.tolist(),
                "pick_duration_s": pick.duration, "place_duration_s": place.duration,
                "t_placed_s": c.t_placed, "t_free_s": c.t_free, "target": c.target, "place_m": c.place_point.tolist(),
                "waited_for_window": c.waited,
                "pick_shape": list(pick.solved.move.basis.params), "place_shape": list(place.solved.move.basis.params),
                "grip_angle_rad": pick.solved.move.theta_end, "place_angle_rad": place.solved.move.theta_end,
                "turn_rad": place.solved.move.turn,
            })
        if self.declines:
            doc["declined"] = dict(self.declines)
        return doc


@dataclass
class RobotRun:
    """What one robot did over a run: its legs (in time order) and picks. ``places``: part type → the
    :class:`LineRobot` with that type's place (``{None: robot}`` on a line without types); ``robot`` is the first."""

    robot: LineRobot
    legs: list = field(default_factory=list)
    picks: int = 0
    places: dict = field(default_factory=dict)
    #: picks per part type (a line with types)
    type_picks: dict = field(default_factory=dict)

    @property
    def instances(self) -> list:
        """The robot's distinct places' LineRobots (the first is ``robot``)."""
        out = [self.robot]
        for r in self.places.values():
            if all(r is not x for x in out):
                out.append(r)
        return out

    @property
    def exchanges(self) -> list:
        """Every exchange of the robot's places: (start, end) [s], in time order."""
        return sorted(x for r in self.instances for x in r.exchanges)

    def sync(self, src: LineRobot) -> None:
        """Every place's LineRobot takes ``src``'s state (the robot is one: where it is, how it moves, when free)."""
        for r in self.instances:
            if r is not src:
                r.state, r.last_T, r.last_place_T = src.state, src.last_T, src.last_place_T


class LineEngine:
    """The line of ``line`` (a :class:`~pickplace_cli.line.spec.Line`), its robots in upstream order. ``profiles``:
    robot name → Profile (loaded by the caller: the CLI names the file); ``robots``: use only the first this
    many robots of the file (a sweep's robot count)."""

    def __init__(self, line: Line, profiles: dict, robots: int | None = None) -> None:
        from .moves import Shapes
        from .strategies import Sharing

        specs = list(line.robots) if robots is None else list(line.robots)[:robots]
        if robots is not None:
            line = line.model_copy(update={"robots": specs})
        self.line = line
        order = upstream_order(line)
        bands = robot_bands(line)
        shapes = Shapes.shared()
        self.types = type_names(line)
        self.robots: list[LineRobot] = []
        self.runs: list[RobotRun] = []
        own_bands = []
        for i in order:
            spec = line.robots[i]
            run = self._robot(spec, line, profiles[spec.name], shapes)
            self.robots.append(run.robot)
            self.runs.append(run)
            own_bands.append(bands[i])
        strategy = line.strategy
        half = line.belt.width / 2
        for run, band in zip(self.runs, own_bands):
            lo, hi = band if strategy.kind == "bands" else (-half, half)
            tol = getattr(strategy, "overlap", 0.0) if strategy.kind == "bands" else 0.0
            for r in run.instances:
                check_reach(r, (max(lo - tol, -half), min(hi + tol, half)))
        self.sharing = Sharing(strategy, len(self.robots), own_bands)
        self.n = 0
        self.t_begin = math.inf
        self.t_last = -math.inf
        self.results: list[PartResult] = []
        self.bad_rows = 0
        self.warnings: list[str] = [f"parts.types.{t}: no robot has a place for type {t}: every part of it is "
                                    "missed" for t in untaken_types(line)]
        self.finished = None

    @staticmethod
    def _robot(spec, line: Line, profile, shapes) -> RobotRun:
        """The robot's run: one LineRobot per distinct place (module docstring), all at the first one's home."""
        made: dict = {}
        places = {}
        first = None
        for kind, place in robot_places(spec, type_names(line)).items():
            if id(place) not in made:
                sub = spec if place is spec.place else spec.model_copy(update={"place": place, "places": None})
                r = LineRobot(sub, line, profile, shapes, line.parts.latency, line.parts.height)
                if first is None:
                    first = r
                else:  # one robot: one home, one state
                    r.home, r.home_torque, r.state = first.home.copy(), first.home_torque, first.state
                made[id(place)] = r
            places[kind] = made[id(place)]
        return RobotRun(first, places=places)

    # ---------------------------------------------------------------------------------------------- setup
    def check_speed(self) -> None:
        """UnreachableError (exit 4) when no robot could take a part even alone and at rest: a part on its band's
        centre line detected 1 s before it enters the robot's window, the robot free at home. A robot that cannot
        is named in a warning (``warnings``)."""
        why = []
        for r, (lo, hi) in zip(self.robots, self.sharing.bands):
            across = (lo + hi) / 2 if self.line.strategy.kind == "bands" else 0.0
            along = r.window[0] - r.speed * 1.0
            res = r.plan(along, across, 0.0, RobotState(r.home.copy(), np.zeros(3), -math.inf))
            if isinstance(res, Decline):
                why.append(res.reason)
        if len(why) == len(self.robots):
            raise UnreachableError(f"belt.speed = {self.line.belt.speed:g} m/s: no robot can take a part even alone and "
                                   f"at rest (a part detected 1 s before its window): {why[0]}"
                                   + (f" (and {len(why) - 1} more robot{'s' if len(why) > 2 else ''})" if len(why) > 1 else ""))
        self.warnings += [f"{w} (a part detected 1 s before its window, the robot at rest): it can never take a part "
                          f"at belt speed {self.line.belt.speed:g} m/s" for w in why]
        gen = self.line.parts.generate
        if gen is not None:
            reach = gen.detect_at + self.line.belt.speed * self.line.parts.latency
            self.warnings += [f"robot {r.name}: its last meeting point along {r.meet_end:.4g} m is upstream of where the "
                              f"parts are when a move may start (detected at {gen.detect_at:g} m, then {reach:.4g} m "
                              "after the latency): it can never take a part" for r in self.robots if r.meet_end < reach]

    # ----------------------------------------------------------------------------------------------- run
    def offer(self, item: Detection | BadRow) -> PartResult:
        """Answer one detection (module docstring); a BadRow is answered with its error (code 1)."""
        if isinstance(item, BadRow):
            self.bad_rows += 1
            res = PartResult(None, reason=item.error, code=item.code, row=item.row)
            self.results.append(res)
            return res
        d = item
        if (self.types is None) != (d.type is None) or (d.type is not None and d.type not in self.types):
            self.bad_rows += 1
            why = ("the line declares no part types (parts.types)" if self.types is None else
                   f"not a part type of the line ({', '.join(self.types)})")
            res = PartResult(None, reason=f"row {d.row} (part {d.id}): type = {d.type!r}: {why}", code=1, row=d.row)
            self.results.append(res)
            return res
        self.n += 1
        self.t_begin = min(self.t_begin, d.t)
        self.t_last = max(self.t_last, d.t)
        t_ready = d.t + self.line.parts.latency
        for run in self.runs:
            self._stop_if_due(run, t_ready, d.along, d.t)
        takes = None if self.types is None else {i for i, run in enumerate(self.runs) if d.type in run.places}
        ask, left_out = self.sharing.order(d.across, self.n, takes, d.type)
        declines = {self.robots[i].name: why for i, why in left_out.items()}
        for i in ask:
            r = self.runs[i].places[d.type]
            res = r.plan(d.along, d.across, d.t, angle=d.angle)
            if isinstance(res, Cycle):
                r.commit(res)
                self.runs[i].sync(r)
                for leg in res.legs:
                    if leg.solved is not None:
                        leg.solved.move.drop_caches()
                self.runs[i].legs += res.legs
                self.runs[i].picks += 1
                if d.type is not None:
                    self.runs[i].type_picks[d.type] = self.runs[i].type_picks.get(d.type, 0) + 1
                self.sharing.picked(i)
                declines = {k: v if isinstance(v, str) else v.short for k, v in declines.items()}
                out = PartResult(d, r.name, res, row=d.row, declines=declines)
                self.results.append(out)
                return out
            declines[r.name] = res
        self.sharing.missed(left_out)
        declines = {k: v if isinstance(v, str) else v.reason for k, v in declines.items()}
        reason = "; ".join(f"{k}: {v.removeprefix(f'robot {k}: ')}" for k, v in declines.items()) or "no robot"
        out = PartResult(d, reason=f"missed: {reason}", code=4, row=d.row, declines=declines)
        self.results.append(out)
        return out

    def _stop_if_due(self, run: RobotRun, t_ready: float, along: float = math.inf, t_detect: float = 0.0) -> None:
        leg = run.robot.stop_first(t_ready, along, t_detect)
        if leg is None:
            return
        if isinstance(leg, Decline):
            raise TaskError(leg.reason)
        run.robot.commit_stop(leg)
        run.sync(run.robot)
        leg.solved.move.drop_caches()
        run.legs.append(leg)

    def run(self, items: Iterable[Detection | BadRow]) -> Iterator[PartResult]:
        for item in items:
            yield self.offer(item)

    def finish(self) -> "LineSummary":
        """Close the run (robots still moving with an outgoing belt come to rest) and sum it up."""
        for run in self.runs:
            self._stop_if_due(run, math.inf)
        self.finished = summarise(self)
        return self.finished


__all__ = ["LineEngine", "PartResult", "RobotRun", "LineSummary", "PickplaceError", "Leg"]
