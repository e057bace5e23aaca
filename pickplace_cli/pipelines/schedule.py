"""A belt schedule: a vision list of detected parts becomes a pick schedule with the robot's state carried over.

Input: the rows of a batch CSV with a ``t_detect`` column (:data:`~pickplace_cli.pipelines.batch.SCHEDULE_REQUIRED`), in
time order (non-decreasing ``t_detect``; a row out of order is refused, naming it). Times are on the
detection clock [s]; the written trajectory uses the same clock.

**The cycle model.** The robot starts at rest at row 1's ``from_x … from_z`` (else at row 1's place point),
free from the first detection on. Each part row is one cycle:

1. the pick move starts at ``t_start = max(t_free, t_detect + latency)``: when the robot is free (at rest where
   the previous cycle left it) but not before the detection plus the row's minimum ``latency`` (vision and
   planning; default the command line's ``--latency``, else 0). The effective latency ``t_start − t_detect``
   is what the rendezvous sees: a busy robot meets the part farther downstream;
2. the rendezvous move (:func:`~pickplace_cli.pipelines.rendezvous.plan_rendezvous`, ``bspline-vel``, arriving with the
   belt velocity) from the robot's position at rest to the part, duration T by the ``time`` rule;
3. the tracking dwell: the profile's ``planning.dwell`` seconds with the part, at the belt velocity;
4. the place move (``bspline-vel``, leaving with the belt velocity, arriving at rest) to the row's place point,
   duration by the same rule;
5. the place dwell: the profile's dwell at rest (release). The robot is then free at the place point:
   ``t_free = t_start + T + dwell + T_place + dwell``.

A part the robot cannot meet inside the workspace and the belt window (exit 4), a cycle that exceeds a limit
(exit 3) or cannot be planned (exit 1) is a result of that row with its reason; the robot does not move (its
position and ``t_free`` stay) and the next row is planned from the same state. Rows are therefore planned one
after another, never in parallel.

**On a controller cycle** (``cycle`` [s]): ``t_start`` is rounded up to a whole number of cycles of the detection
clock, every leg and dwell is whole cycles (:func:`plan_belt_cycle`), and :class:`CycleStream` writes the picked
cycles as one sample per cycle, the waits between them at rest.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Iterable, Iterator

import numpy as np

from ..model.errors import PickplaceError, TaskError


@dataclass(frozen=True)
class RobotState:
    """Where the robot is (at rest, ``position`` [m]; ``angle`` [rad] its tool angle, None when the schedule gives
    no angles) and from when it is free (``t_free`` [s, detection clock]; -inf: from the start)."""

    position: np.ndarray
    t_free: float = -math.inf
    angle: float | None = None


@dataclass(frozen=True)
class Cycle:
    """One picked part: the pick move (a Plan), its Rendezvous, the tracking segment (a Plan, None without a
    dwell), the place move (a Plan), and when: ``t_start`` (move start), ``t_end`` (free again) [s]."""

    row: int
    t_detect: float
    t_start: float
    dwell: float
    move: Any
    rendezvous: Any
    track: Any
    place: Any
    cycle: float | None = None  # s: the controller cycle every leg, dwell and start is a whole number of (None: off)

    @property
    def latency(self) -> float:
        return self.t_start - self.t_detect

    @property
    def t_meet(self) -> float:
        return self.t_start + self.rendezvous.seconds

    @property
    def t_place(self) -> float:
        return self.t_meet + (self.dwell if self.track is not None else 0.0) + float(self.place.duration.seconds)

    @property
    def t_end(self) -> float:
        return self.t_place + self.dwell

    @property
    def legs(self) -> list:
        return [self.move] + ([self.track] if self.track is not None else []) + [self.place]

    @property
    def code(self) -> int:
        return max(leg.report.exit_code() for leg in self.legs)

    def as_dict(self) -> dict[str, Any]:
        names = ["pick"] + (["track"] if self.track is not None else []) + ["place"]
        return {
            "t_detect_s": self.t_detect, "t_start_s": self.t_start, "latency_s": self.latency,
            "start_m": self.move.task.p_from.tolist(),
            "t_meet_s": self.t_meet, "meeting_point_m": self.rendezvous.meeting_point.tolist(),
            "t_place_s": self.t_place, "t_end_s": self.t_end, "place_m": self.place.task.p_to.tolist(),
            **({} if self.place.task.theta_to is None else {"start_theta_rad": self.move.task.theta_from,
               "pick_theta_rad": self.move.task.theta_to, "place_theta_rad": self.place.task.theta_to}),
            "pick_duration_s": self.rendezvous.seconds, "place_duration_s": float(self.place.duration.seconds),
            "dwell_s": self.dwell, "cycle_s": self.t_end - self.t_start,
            "rendezvous": self.rendezvous.as_dict(),
            "limits_ok": self.code == 0,
            "violations": [{"segment": n, **r.as_dict()} for n, leg in zip(names, self.legs)
                           for r in leg.report.violations],
            # limits beyond their rating that the rule does not hold (the Cartesian capacity under fit)
            "exceeded_not_held": [{"segment": n, **r.as_dict()} for n, leg in zip(names, self.legs)
                                  for r in leg.report.exceeded_not_held],
        }

    def report_doc(self) -> list[dict[str, Any]]:
        """The ``--report`` entries of the cycle: per segment (pick, track, place) its summary and limit report."""
        names = ["pick"] + (["track"] if self.track is not None else []) + ["place"]
        return [{"segment": n, "summary": leg.summary(), "limits": leg.report.as_dict()} for n, leg in zip(names, self.legs)]

    def belt_travel(self, t: np.ndarray) -> np.ndarray:
        """The belt's travel [m] since the part's detection at times ``t`` [s, the timeline's clock]: the master
        position of a cam that follows the belt (|belt velocity| · (t − t_detect))."""
        return self.rendezvous.part.speed * (np.asarray(t, float) - self.t_detect)

    def timeline(self, numbered: bool = False):
        """The cycle's samples on the detection clock: pick move, tracking, place move, place dwell at rest
        (a :class:`~pickplace_cli.pipelines.timeline.Timeline`, every sample in move = ``row``; ``numbered``: move 1
        the pick and its tracking, 2 the place and its dwell, as a round trip numbers its legs). On a controller
        cycle every time stamp is the exact multiple k·cycle. Its ``belt_m`` is :meth:`belt_travel` per sample."""
        from dataclasses import replace as _replace

        from .timeline import Segment, _hold, _join, _pieces_of, on_cycle

        pieces, segs, moves = [], [], []
        t0 = self.t_start
        rate = 1.0 / float(np.median(np.diff(self.move.t))) if len(self.move.t) > 1 else 1000.0
        if self.cycle is not None:
            rate = 1.0 / self.cycle
        for k, (label, leg) in enumerate(zip(("move", "track", "place"), (self.move, self.track, self.place))):
            if leg is None:
                continue
            piece = _pieces_of(leg, t0)
            if k:  # its first sample is the previous segment's last
                piece = {n: ({j: None if a is None else a[1:] for j, a in v.items()} if n == "joint" else v[1:])
                         for n, v in piece.items()}
            pieces.append(piece)
            m = (1 if k < 2 else 2) if numbered else self.row
            moves.append(m)
            T = float(leg.t[-1])
            segs.append(Segment(m, label, t0, t0 + T))
            t0 += T
        if self.dwell > 0:
            steps = np.append(np.arange(1, int(np.ceil(self.dwell * rate - 1e-9))) / rate, self.dwell)
            pieces.append(_hold(self.place, True, t0 + steps))
            moves.append(2 if numbered else self.row)
            segs.append(Segment(moves[-1], "dwell", t0, t0 + self.dwell))
        summaries = [self.move.summary()] + ([self.place.summary()] if numbered else [])
        out = on_cycle(_join(pieces, moves, self.move.joint, segs, summaries), self.cycle)
        return _replace(out, belt_m=self.belt_travel(out.t))


@dataclass(frozen=True)
class ScheduleRow:
    """The outcome of one part row: a Cycle, or an error (one line per problem) with its exit code
    (4 missed, 3 a limit exceeded, 1 no plan); ``t_start``/``latency`` say when the move would have started."""

    row: int
    t_detect: float
    t_start: float
    cycle: Cycle | None = None
    error: str | None = None
    code: int = 0

    def as_dict(self) -> dict[str, Any]:
        doc: dict[str, Any] = {"row": self.row, "exit_code": self.code, "error": self.error,
                               "picked": self.cycle is not None and self.code == 0}
        if self.cycle is not None:
            doc.update(self.cycle.as_dict())
        else:
            doc.update({"t_detect_s": self.t_detect, "t_start_s": self.t_start, "latency_s": self.t_start - self.t_detect})
        return doc


@dataclass
class ScheduleSummary:
    """The schedule so far: rows, picks, missed/failed rows, and the picks' time span [s]."""

    rows: int = 0
    picks: int = 0
    failed: list = None  # type: ignore[assignment]
    t_first: float = math.inf
    t_last: float = -math.inf
    worst: int = 0  # the highest exit code of the rows

    def __post_init__(self) -> None:
        self.failed = [] if self.failed is None else self.failed

    def add(self, res: ScheduleRow) -> None:
        self.rows += 1
        self.worst = max(self.worst, res.code)
        if res.code:
            self.failed.append(res.row)
            return
        self.picks += 1
        self.t_first = min(self.t_first, res.cycle.t_start)
        self.t_last = max(self.t_last, res.cycle.t_end)

    @property
    def span(self) -> float:
        return self.t_last - self.t_first if self.picks else 0.0

    @property
    def picks_per_minute(self) -> float:
        return 60.0 * self.picks / self.span if self.picks and self.span > 0 else 0.0

    def as_dict(self) -> dict[str, Any]:
        return {"rows": self.rows, "picks": self.picks, "missed": len(self.failed), "failed_rows": list(self.failed),
                "t_first_start_s": self.t_first if self.picks else None,
                "t_last_end_s": self.t_last if self.picks else None,
                "span_s": self.span, "picks_per_minute": self.picks_per_minute}

    def line(self) -> str:
        """The closing line, e.g. ``schedule: 4 parts, 3 picked, 1 missed (row 3); picks from t = 0.0500 to
        1.9000 s: 94.7 picks/min``."""
        missed = ""
        if self.failed:
            shown = ", ".join(str(r) for r in self.failed[:10]) + (" …" if len(self.failed) > 10 else "")
            missed = f" (row{'s' if len(self.failed) > 1 else ''} {shown})"
        tail = (f"; picks from t = {self.t_first:.4f} to {self.t_last:.4f} s: {self.picks_per_minute:.1f} picks/min"
                if self.picks else "")
        return f"schedule: {self.rows} parts, {self.picks} picked, {len(self.failed)} missed or failed{missed}{tail}"


def _xyz(values: dict, prefix: str) -> np.ndarray:
    return np.array([values[f"{prefix}{c}"] for c in "xyz"], float)


def start_state(first_values: dict, angles: bool = False) -> RobotState:
    """The robot at rest at row 1's ``from_x … from_z`` (all three, or none: then at row 1's place point); with
    ``angles`` (the schedule has tool angle columns) its tool angle is row 1's ``from_theta``, else its
    ``place_theta``, else 0 rad."""
    given = [c for c in "xyz" if f"from_{c}" in first_values]
    if given and len(given) != 3:
        missing = next(c for c in "xyz" if c not in given)
        raise TaskError(f"from_{missing} is empty: row 1 gives the robot's start with all of from_x, from_y, from_z "
                        "(or none: it starts at the place point)")
    angle = first_values.get("from_theta", first_values.get("place_theta", 0.0)) if angles else None
    return RobotState(_xyz(first_values, "from_" if given else "place_"), angle=angle)


def check_order(rows: Iterable, source: str = "batch") -> Iterator:
    """The BatchRows of a schedule, checked as they pass: non-decreasing ``t_detect``, no ``from_*`` after row 1
    (TaskError naming the row; a row that failed to parse is raised as TaskError too — a schedule needs every
    row, since the robot's state runs through them)."""
    from .batch import RowResult

    prev = None
    for r in rows:
        if isinstance(r, RowResult):
            raise TaskError(r.error)
        where = f"row {r.row} ({source}:{r.line})"
        t = r.values["t_detect"]
        if prev is not None and t < prev[1]:
            raise TaskError(f"{where}: t_detect = {t:g} s is earlier than row {prev[0]}'s {prev[1]:g} s; a belt "
                            "schedule's rows must be in time order (non-decreasing t_detect)")
        if prev is not None:
            extra = next((f"from_{c}" for c in ("x", "y", "z", "theta") if f"from_{c}" in r.values), None)
            if extra:
                raise TaskError(f"{where}: {extra} = {r.values[extra]:g}: only row 1 may say where the robot starts; "
                                "each later move starts where the previous cycle ended (leave it empty)")
        prev = (r.row, t)
        yield r


def plan_belt_cycle(start, part, place, profile, time: str | float = "limits", height: float | None = None,
                    eta: float | None = None, rate: float | None = None, method_params: dict | None = None,
                    start_angle: float | None = None, place_angle: float | None = None, turn: str = "shortest",
                    place_turn: str | None = None, turn_during: str = "transfer", cycle: float | None = None,
                    t_start: float = 0.0, row: int = 1) -> Cycle:
    """The whole belt cycle from rest at ``start`` [m] (the move starting at ``t_start`` [s], the part detected
    ``part.latency`` s before): the rendezvous move to ``part`` (duration by ``time``), tracking it for the
    profile's dwell, the place move (``bspline-vel``, leaving with the belt velocity) to ``place`` [m] arriving at
    rest, and the dwell there (release) — every segment checked against every limit. ``start_angle``,
    ``place_angle`` [rad]: the tool angle at the start and at the place point (None: the part's as picked), the
    pick turned by ``turn``, the place by ``place_turn`` (default ``turn``), over ``turn_during``. ``cycle`` [s]: on
    a controller's cycle — each leg and each dwell a whole number of cycles (one sample per cycle), the meeting
    solved again for the rounded pick and every leg checked again on its rounded motion (a leg that breaks a limit
    that held gets more cycles: :func:`~pickplace_cli.pipelines.rendezvous.plan_rendezvous`,
    :func:`~pickplace_cli.planner.plan`); ``t_start`` should then be a whole number of cycles too."""
    from ..model.task import Task
    from ..planner import PlanOptions, plan
    from .rendezvous import plan_rendezvous
    from .tracking import plan_tracking

    move, rv = plan_rendezvous(start, part, profile, time, height, eta, np.zeros(3), method_params, rate, None,
                               start_angle, turn, turn_during, cycle=cycle)
    dwell = float(profile.planning.dwell)
    if cycle is not None:
        from ..timing.cycle import whole_cycles

        dwell = whole_cycles(dwell, cycle) * cycle
    track = plan_tracking(move, part, profile, rate=rate, cycle=cycle) if dwell > 0 else None
    leave = part.at(rv.seconds + dwell) if track is not None else rv.meeting_point
    held = move.task.theta_to  # the part's angle as the tool holds it (None without angles)
    place_task = Task(leave, np.asarray(place, float), height if height is not None else profile.planning.height,
                      eta if eta is not None else profile.planning.eta, v_from=part.velocity, v_to=np.zeros(3),
                      theta_from=held, theta_to=None if held is None else (held if place_angle is None else place_angle))
    placed = plan(place_task, profile, PlanOptions(method="bspline-vel", method_params=dict(method_params or {}),
                                                   time=time, rate=rate, fit=time == "fit", cycle=cycle,
                                                   turn=place_turn or turn, turn_during=turn_during))
    return Cycle(row, t_start - part.latency, t_start, dwell, move, rv, track, placed, cycle)


def plan_cycle(state: RobotState, r, profile, time: str = "limits", height: float | None = None,
               eta: float | None = None, rate: float | None = None, latency: float = 0.0,
               method_params: dict | None = None, source: str = "batch", turn: str = "shortest",
               turn_during: str = "transfer", cycle: float | None = None) -> ScheduleRow:
    """One row of the schedule from ``state`` (see the module docstring): a ScheduleRow with its Cycle, or the
    reason the part is missed (exit 4) or the cycle fails (1, 3). With tool angles (``state.angle`` not None) the
    pick turns the tool to the part's ``to_theta`` (empty: no turn) by ``turn`` over ``turn_during``, the tool
    holds it while tracking, and the place turns it to ``place_theta`` (empty: the part's angle). ``cycle`` [s]:
    on a controller's cycle (:func:`plan_belt_cycle`), the move's start rounded up to a whole number of cycles of
    the detection clock."""
    from .rendezvous import Part

    v = r.values
    t_detect = float(v["t_detect"])
    t_start = max(state.t_free, t_detect + float(v.get("latency", latency)))
    if cycle is not None:  # every time stamp k·cycle on the detection clock: the start too
        t_start = math.ceil(t_start / cycle - 1e-9) * cycle
    where = f"row {r.row} ({source}:{r.line})"
    try:
        angle = state.angle
        part = Part(_xyz(v, "to_"), np.array([v[f"to_belt_v{c}"] for c in "xyz"], float), t_start - t_detect,
                    name=f"part of row {r.row}", angle=None if angle is None else v.get("to_theta", angle))
        from ..model.headroom import apply_limit_use

        cyc = plan_belt_cycle(state.position, part, _xyz(v, "place_"), apply_limit_use(profile, v.get("limit_use")),
                              v.get("time", time), v.get("height", height), v.get("eta", eta), rate, method_params,
                              angle, v.get("place_theta"), turn, None, turn_during, cycle, t_start, r.row)
    except PickplaceError as exc:
        busy = f"robot busy until t = {state.t_free:.4f} s, " if state.t_free > t_detect + v.get("latency", latency) else ""
        return ScheduleRow(r.row, t_detect, t_start,
                           error=f"{where}: move from t = {t_start:.4f} s ({busy}latency {t_start - t_detect:.4f} s): {exc}",
                           code=exc.exit_code)
    cyc = replace(cyc, t_detect=t_detect)  # the row's own stamp (t_start − latency up to round-off)
    error = None
    if cyc.code:
        from .batch import violation_text

        error = "\n".join(f"{where}: {name}: {violation_text(x)}" for name, leg in
                          zip(("pick", "track", "place") if cyc.track is not None else ("pick", "place"), cyc.legs)
                          for x in leg.report.violations)
    return ScheduleRow(r.row, t_detect, t_start, cyc, error, cyc.code)


def plan_schedule(rows: Iterable, profile, time: str = "limits", height: float | None = None, eta: float | None = None,
                  rate: float | None = None, latency: float = 0.0, method_params: dict | None = None,
                  source: str = "batch", fail_fast: bool = False, report_only: bool = False, angles: bool = False,
                  turn: str = "shortest", turn_during: str = "transfer",
                  cycle: float | None = None) -> Iterator[ScheduleRow]:
    """Plan the rows (BatchRows from :func:`~pickplace_cli.pipelines.batch.iter_batch`, lazily: a streamed row is answered
    as soon as it is read) one after another, the robot's state carried from each picked part to the next;
    yields a ScheduleRow per row. Input errors (order, a bad row) raise TaskError at that row. ``report_only``:
    a cycle that only exceeds a limit (exit 3) is run as planned (the robot's state goes on from it), so the
    schedule is the one the robot would run if the limits were not checked. ``angles``: the schedule has tool angle
    columns (``to_theta``, ``place_theta``, ``from_theta``; rad): the robot's tool angle is carried too, each turn
    by ``turn`` over ``turn_during`` (:func:`plan_cycle`). ``cycle`` [s]: every start, leg and dwell on a
    controller's cycle (:func:`plan_cycle`)."""
    state = None
    for r in check_order(rows, source):
        if state is None:
            try:
                state = start_state(r.values, angles)
            except TaskError as exc:
                raise TaskError(f"row {r.row} ({source}:{r.line}): {exc}") from None
        res = plan_cycle(state, r, profile, time, height, eta, rate, latency, method_params, source, turn, turn_during,
                         cycle)
        if res.code == 0 or (report_only and res.code == 3 and res.cycle is not None):
            state = RobotState(res.cycle.place.task.p_to, res.cycle.t_end, res.cycle.place.task.theta_to)
        yield res
        if fail_fast and res.code:
            return


class CycleStream:
    """The picked cycles as they are written, one after another on the detection clock. Without a controller cycle
    each cycle's :meth:`Cycle.timeline` as it is (the robot waits at rest between cycles with no samples). On a
    ``cycle`` [s] one sample per cycle from the first cycle's start to the last one's end: a cycle's last sample is
    held back until the next cycle comes; the robot's wait at rest at the place point in between is written as
    samples of the earlier row (segment "wait"), and a cycle that starts as the previous one ends takes the shared
    time stamp as its first sample (no time stamp twice)."""

    def __init__(self, cycle: float | None) -> None:
        self.cycle = cycle
        self.last: Cycle | None = None

    def pieces(self, cyc: Cycle) -> list:
        """The Timelines to write for the picked cycle ``cyc`` (in order)."""
        whole = cyc.timeline()
        if self.cycle is None:
            return [whole]
        out = []
        if self.last is not None:
            k0, k1 = round(self.last.t_end / self.cycle), round(cyc.t_start / self.cycle)
            if k1 > k0:
                out.append(self._wait(np.arange(k0, k1) * self.cycle))
        self.last = cyc
        return out + [_samples(whole, slice(0, len(whole.t) - 1))]

    def close(self) -> list:
        """The last cycle's held-back final sample (nothing without a cycle or a cycle written)."""
        if self.cycle is None or self.last is None:
            return []
        k = round(self.last.t_end / self.cycle)
        return [self._wait(np.array([k * self.cycle]))]

    def _wait(self, t: np.ndarray):
        from .timeline import Segment, _hold, _join

        c = self.last
        return _join([_hold(c.place, True, t)], [c.row], c.move.joint, [Segment(c.row, "wait", float(t[0]),
                                                                                 float(t[-1]))], [])


def _samples(timeline, sl: slice):
    """The samples ``sl`` of ``timeline`` (a Timeline of one move number)."""
    from .timeline import _join

    piece = {k: getattr(timeline, k)[sl] for k in ("t", "p", "v", "a", "j")}
    piece["joint"] = {n: None if getattr(timeline.joint, n) is None else getattr(timeline.joint, n)[sl]
                      for n in ("q", "qd", "qdd", "qddd", "torque", "motor_speed", "motor_torque")}
    out = _join([piece], [int(timeline.move[0])], timeline.joint, timeline.segments, timeline.summaries)
    from dataclasses import replace as _replace

    return _replace(out, cycle=timeline.cycle, belt_m=None if timeline.belt_m is None else timeline.belt_m[sl])
