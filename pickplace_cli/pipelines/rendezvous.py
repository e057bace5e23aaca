"""Conveyor rendezvous: meet a part moving on a belt, arrive with the belt's velocity, track it through the pick.

A camera saw a part at ``position`` [m] on a belt moving at ``velocity`` [m/s]; the move starts ``latency``
seconds after the detection, and t = 0 is the start of the move. The move of duration T therefore has to end
at the meeting point

    P(T) = position + velocity · (latency + T)

with the tool's velocity equal to the belt's: the velocity-constrained B-spline of [Yang2022] with v1 = belt
velocity (``--method bspline-vel``). T itself comes from the user's duration rule applied to the move to P(T),
and P(T) from T — a fixed point T = T_rule(P(T)).

**How the fixed point is solved.** For a rule that is a *feasibility* threshold (``auto``: the capacity bound
of the path planned for T at most T, Eq. 26; ``fit``: every joint and motor limit holds at T, Eq. 38), the
fixed point is the smallest T at which the move to P(T), planned for T, meets the rule: writing
e(T) = (rule's excess of the move to P(T) in T), the rendezvous is the first root of e. This is the brief's
g(T) = T_rule(P(T)) − T = 0 without nesting one root-find inside another: at the first root of e, the move to
the fixed point P(T*) meets the rule at T* and at no shorter duration close by, so T_rule(P(T*)) = T*
(a test re-plans the move to P(T*) with the plain ``--time auto`` and gets T* back). It is found in two
phases, each bracketed before ``brentq``:

1. screening on cheap paths (the conveyor table's answer, or the paper's initial shape where the table does
   not apply, ~1-2 ms each): a few fixed-point steps give a start, then a scan in 10 % steps inside the
   allowed interval brackets the first sign change;
2. the exact shape (the default ``exact`` solver, continued from the nearest solved T as ``--time auto``
   does): a 2 % scan around the screening root brackets it again, ``brentq`` finds it, a global solve confirms
   the shape at the root, and T is nudged up until the rule holds exactly.

A duration in seconds needs no search: P(T) follows from T.

**Where the robot may meet the part.** The allowed meeting times form an interval [a, b] of move time: the
part must be inside the workspace (the robot's reachable set, its joint ranges and the workcell box) and the
profile's belt window (``workcell.belt_window``), from the meeting until the end of the tracking segment
(the dwell, when the tool moves with the belt holding the grip). When the first root lies before a, the robot
waits: it meets the part at a (a longer move, still within the rule). When no T ≤ b meets the rule, there is
no rendezvous: :class:`~pickplace_cli.model.errors.UnreachableError` (exit 4) says by how much the part is missed
(the distance along the belt between the last allowed meeting point and the earliest feasible one).
Only the first stretch of allowed meeting times is used (a part that leaves the workspace and comes back is
not chased into its second stretch). The workspace is sampled every millimetre of belt travel.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ..model.errors import TableError, TaskError, UnreachableError
from ..model.task import Task

#: the shortest move considered [s]
T_MIN = 1e-2
#: how far ahead in move time the part is followed [s]
HORIZON = 20.0
#: belt travel per workspace sample [m]
WORKSPACE_STEP = 1e-3


@dataclass(frozen=True)
class Part:
    """A part on a belt: detected at ``position`` [m, base frame], moving at ``velocity`` [m/s]; the move
    starts ``latency`` [s] after the detection. ``name`` labels it in messages (e.g. "row 3"). ``angle`` [rad]:
    the part's angle about the base z axis as detected (a robot with a rotary fourth axis meets it at that
    angle: the belt translates it, it does not turn it); None: no angle given."""

    position: np.ndarray
    velocity: np.ndarray
    latency: float = 0.0
    name: str = "part"
    angle: float | None = None

    def __post_init__(self) -> None:
        from ..model.task import MAX_METRES, MAX_SPEED, _angle

        object.__setattr__(self, "angle", _angle("to_theta", self.angle))

        for label, unit, value, limit in (("to", "m", self.position, MAX_METRES),
                                          ("to-belt", "m/s", self.velocity, MAX_SPEED)):
            arr = np.asarray(value, float).reshape(-1)
            if arr.shape != (3,) or not np.all(np.isfinite(arr)):
                raise TaskError(f"{label} = {value!r}: give three finite components X,Y,Z in {unit}")
            if not np.all(np.abs(arr) <= limit):
                raise TaskError(f"{label} = {','.join(f'{c:g}' for c in arr)}: every component must lie within "
                                f"±{limit:g} {unit} (SI units)")
            object.__setattr__(self, "position" if label == "to" else "velocity", arr)
        lat = float(self.latency)
        if not (math.isfinite(lat) and lat >= 0):
            raise TaskError(f"latency = {self.latency!r}: must be a finite number of seconds >= 0 (detection to move start)")
        object.__setattr__(self, "latency", lat)

    def at(self, t_move: float | np.ndarray) -> np.ndarray:
        """Position [m] at move time ``t_move`` [s] (t = 0: the move starts), (3,) or (N, 3)."""
        t = np.asarray(t_move, float) + self.latency
        return self.position + np.multiply.outer(t, self.velocity)

    @property
    def speed(self) -> float:
        return float(np.linalg.norm(self.velocity))

    def label(self) -> str:
        xyz = ",".join(f"{c:g}" for c in self.position)
        vel = ",".join(f"{c:g}" for c in self.velocity)
        return f"{self.name} (detected at {xyz} m, belt {vel} m/s)"


@dataclass(frozen=True)
class Rendezvous:
    """Where and when the move meets the part: ``task`` (from the start to the meeting point, arriving with
    the belt velocity), its ``duration`` (T [s], how it was chosen), the exact ``path`` planned for T, the
    allowed meeting interval ``window_s`` (a, b) [s of move time], and what the search did."""

    part: Part
    task: Task
    duration: Any  # timing.Duration
    path: Any  # CartesianPath planned for duration.seconds
    window_s: tuple[float, float]
    waited: bool = False
    evaluations: dict = field(default_factory=dict)

    @property
    def seconds(self) -> float:
        return float(self.duration.seconds)

    @property
    def meeting_point(self) -> np.ndarray:
        return self.task.p_to

    @property
    def meeting_time_since_detection(self) -> float:
        return self.part.latency + self.seconds

    def as_dict(self) -> dict[str, Any]:
        return {
            "part_detected_m": self.part.position.tolist(),
            "belt_velocity_m_s": self.part.velocity.tolist(),
            **({} if self.part.angle is None else {"part_theta_rad": self.part.angle}),
            "latency_s": self.part.latency,
            "meeting_point_m": self.meeting_point.tolist(),
            "meeting_time_s": self.seconds,
            "meeting_time_since_detection_s": self.meeting_time_since_detection,
            "allowed_meeting_s": list(self.window_s),
            "waited_for_window": self.waited,
            "evaluations": dict(self.evaluations),
        }


# ------------------------------------------------------------------------------------------ the factory


def _factory_class():
    from ..paths.bspline_vel import PathFactory

    class RendezvousFactory(PathFactory):
        """T [s] → the bspline-vel path from the start to P(T), arriving with the belt velocity, planned for T
        (memoised; the exact solver continues its optimum from the nearest solved T, like ``--time auto``)."""

        def __init__(self, start: np.ndarray, part: Part, height: float, eta: float, v_from,
                     angles: tuple = (None, None), **params: Any) -> None:
            self.start, self.part = np.asarray(start, float), part
            self.height, self.eta, self.v_from = height, eta, np.asarray(v_from, float)
            self.angles = angles  # the tool angle at the start and at the meeting [rad] (the turn resolved), or None
            self._tasks: dict[float, Task] = {}
            super().__init__(self.task_at(1.0), **params)

        def task_at(self, duration: float) -> Task:
            T = float(duration)
            task = self._tasks.get(T)
            if task is None:
                if len(self._tasks) > 512:
                    self._tasks.clear()
                task = self._tasks[T] = Task(self.start, self.part.at(T), self.height, self.eta, self.v_from,
                                             self.part.velocity, *self.angles)
            return task

    return RendezvousFactory


def _screening_factory(start, part, height, eta, v_from, table):
    """The cheap factory of phase 1: the table's answer where the table applies, else the paper's initial shape."""
    from ..paths.bspline_vel import PAPER_INITIAL

    cls = _factory_class()
    fac = cls(start, part, height, eta, v_from, solver="table", **({"table": table} if table else {}))

    def call(T: float):
        nonlocal fac
        try:
            return fac(T)
        except TableError:  # outside the table (other η, unequal heights, vertical belt …): the paper's shape
            fac = cls(start, part, height, eta, v_from, params=PAPER_INITIAL)
            return fac(T)

    return call


# ------------------------------------------------------------------------------------------ the rules


class _Rule:
    """e(T): the excess of the duration rule for the move to P(T) planned for T (≤ 0: the rule holds)."""

    def __init__(self, kind: str, profile, factory, dwell: float) -> None:
        self.kind, self.profile, self.factory, self.dwell = kind, profile, factory, dwell
        self.count = 0

    def __call__(self, T: float) -> float:
        from ..timing import auto_duration

        self.count += 1
        try:
            path = self.factory(T)
        except TaskError:  # e.g. the meeting point straight below the start (b = 0): no move of this method
            return math.inf
        cap = None
        if self.kind in ("auto", "limits"):
            tv, ta, tj, _ = auto_duration(path, self.profile.capacity)
            cap = max(tv, ta, tj or 0.0) / T - 1.0
            if self.kind == "auto":
                return cap
        from ..planner import motion_model
        from ..timing import _worst_utilisation

        try:
            found = _worst_utilisation(motion_model(path, self.profile), self.dwell)
        except UnreachableError:  # this trial move leaves the workspace: not a feasible meeting
            return math.inf
        if found is None:
            if cap is not None:  # limits: the capacity alone
                return cap
            raise TaskError(
                "time = fit: the profile sets no velocity, acceleration, jerk or motor limit that depends on the "
                "duration; add joint limits or drives, or use --time auto / seconds"
            )
        fit = found[0](T)[0]
        return fit if cap is None else max(fit, cap)


def _finite(x: float) -> float:
    return x if math.isfinite(x) else 1e6  # brentq needs finite values; the sign is what matters


def _first_feasible(e, a: float, b: float, start: float, factor: float, rtol: float) -> float | None:
    """The smallest T in [a, b] with e(T) ≤ 0 near ``start``: scanned down (while feasible) or up (while not)
    in steps of ``factor`` < 1, the crossing bracketed and root-found (brentq). ``a`` when e(a) ≤ 0 is reached;
    None when no scanned T ≤ b is feasible."""
    from scipy.optimize import brentq

    T = min(max(start, a), b)
    if e(T) <= 0:
        hi = T
        while True:
            if hi <= a:
                return a
            lo = max(hi * factor, a)
            if e(lo) > 0:
                break
            hi = lo
    else:
        lo = T
        while True:
            if lo >= b:
                return None
            hi = min(lo / factor, b)
            if e(hi) <= 0:
                break
            lo = hi
    return float(brentq(lambda x: _finite(e(x)), lo, hi, xtol=1e-13, rtol=rtol))


def _root_near(e_raw, a: float, b: float, start: float, rtol: float = 1e-6, steps: int = 10,
               power: float = 1.0) -> float | None:
    """The smallest T in [a, b] with e(T) ≤ 0 near ``start``, by secant steps (the first one the fixed-point
    step T·(1 + e), exact for the capacity rule when the shape does not change with T) kept inside the bracket
    they find (a step that leaves it bisects). Returns the feasible end of a bracket narrower than ``rtol``
    (relative; e is only smooth to ~1e-7 near the root, the exact shape being an optimiser's answer), or of a
    step that predicts the root within ``rtol`` of it; ``a`` when e(a) ≤ 0 is reached. None when it does not
    settle in ``steps`` evaluations or meets a non-finite value: the caller then scans (``_first_feasible``).

    ``power`` k: the steps are taken on (1 + e)^(1/k) − 1 (same sign, same root), linear in 1/T when the
    binding quantity scales as T^-k: 1 for the capacity rule (e = T_auto/T − 1), 3 for fit (the Delta's torque
    rate, a jerk; a quantity that falls more slowly only makes the first step land short of the root)."""

    def e(T: float) -> float:
        v = e_raw(T)
        return (1.0 + v) ** (1.0 / power) - 1.0 if power != 1.0 and math.isfinite(v) and v > -1.0 else v

    T0 = min(max(start, a), b)
    e0 = e(T0)
    if not math.isfinite(e0):
        return None
    lo = hi = None  # the largest infeasible T below the root, the smallest feasible T above it
    if e0 > 0:
        lo = T0
    else:
        hi = T0
    T1 = min(max(T0 * (1.0 + e0), a), b)
    for _ in range(steps):
        if hi is not None and (T1 >= hi or (lo is not None and T1 <= lo)):
            T1 = 0.5 * (hi + lo) if lo is not None else T1
        if T1 == T0:
            return hi if hi is not None and abs(hi - T0) <= rtol * hi else None
        e1 = e(T1)
        if not math.isfinite(e1):
            return None
        if e1 > 0:
            lo = T1 if lo is None else max(lo, T1)
            if T1 >= b:
                return None  # infeasible at the window's end: the caller reports the miss
        else:
            hi = T1 if hi is None else min(hi, T1)
            if T1 <= a:
                return a
        if lo is not None and hi is not None and hi - lo <= rtol * hi:
            return hi
        T2 = T1 - e1 * (T1 - T0) / (e1 - e0) if e1 != e0 else T1 * (1.0 + e1)
        T2 = min(max(T2, a), b)
        if hi is not None and e1 <= 0 and abs(T2 - T1) <= rtol * T1 and (lo is None or T2 > lo):
            return hi  # the step predicts the root within rtol below a feasible T
        T0, e0, T1 = T1, e1, T2
    return None


# ------------------------------------------------------------------------------------------ where


def workspace_mask(profile, points: np.ndarray) -> np.ndarray:
    """Boolean (N,): True where the tool can be at ``points`` (N, 3) [m]: the robot reaches it (IK), every
    joint within its position range, inside the workcell box."""
    from ..planner import motion_model_static

    robot, specs, _margin, box, _memo = motion_model_static(profile)
    p = np.asarray(points, float)
    ok = np.all(np.isfinite(p), axis=1)
    if box is not None:
        ok &= np.all((p >= np.asarray(box.min) - 1e-12) & (p <= np.asarray(box.max) + 1e-12), axis=1)
    if hasattr(robot, "reachable"):
        ok &= robot.reachable(np.where(ok[:, None], p, 0.0))
    travel = getattr(robot, "travel", None)  # the gantry: joints are the coordinates
    if travel is not None:
        ok &= np.all((p >= travel[:, 0] - 1e-12) & (p <= travel[:, 1] + 1e-12), axis=1)
    idx = np.flatnonzero(ok)
    if idx.size:
        try:
            q = robot.inverse_kinematics(p[idx])
        except UnreachableError:  # pragma: no cover - reachable() and IK agree for the shipped robots
            return np.zeros(len(p), bool)
        for c, spec in enumerate(specs):
            rng = spec.limits.position if spec.limits is not None else None
            if rng is not None:
                bad = (q[:, c] < rng[0] - 1e-12) | (q[:, c] > rng[1] + 1e-12)
                ok[idx[bad]] = False
    return ok


def window_times(part: Part, window) -> tuple[float, float]:
    """(enter, exit) [s since detection] of the part in the belt window (an axis-aligned box); (inf, -inf)
    when its line misses the window. A static part inside the window: (-inf, inf)."""
    lo_t, hi_t = -math.inf, math.inf
    for c in range(3):
        x0, v, lo, hi = part.position[c], part.velocity[c], window.min[c], window.max[c]
        if abs(v) < 1e-15:
            if not lo <= x0 <= hi:
                return math.inf, -math.inf
            continue
        t1, t2 = (lo - x0) / v, (hi - x0) / v
        lo_t, hi_t = max(lo_t, min(t1, t2)), min(hi_t, max(t1, t2))
    return (lo_t, hi_t) if lo_t <= hi_t else (math.inf, -math.inf)


def allowed_interval(part: Part, profile, dwell: float) -> tuple[float, float, str]:
    """(a, b, what ends it) [s of move time]: the first stretch of meeting times T ≥ T_MIN at which the part
    and the tracking segment [T, T + dwell] stay inside the workspace and the belt window; UnreachableError
    (exit 4) naming the part when there is none. ``what`` is "window", "workspace" or "horizon"."""
    window = getattr(profile.workcell, "belt_window", None)
    a_w, b_w = -math.inf, math.inf
    if window is not None:
        enter, leave = window_times(part, window)
        if enter > leave:
            raise UnreachableError(f"{part.label()}: its path never crosses the belt window of profile {profile.name}")
        if leave - part.latency < T_MIN + dwell:
            past = part.speed * (part.latency + T_MIN + dwell - leave)
            raise UnreachableError(
                f"{part.label()}: already past the belt window when the move starts (latency {part.latency:g} s): "
                f"it leaves the window {past * 1e3:.0f} mm before the earliest pick and {dwell:g} s of tracking could end"
            )
        a_w, b_w = enter - part.latency, leave - part.latency - dwell
    speed = part.speed
    # (a part at rest: one position, sampled as a slow belt's; it was sampled once, 20 s after the start, and every
    # move waited 20 s for it)
    dt = min(WORKSPACE_STEP / speed, HORIZON / 200) if speed > 0 else HORIZON / 200
    t = np.arange(0.0, HORIZON + dwell + dt, dt)
    inside = workspace_mask(profile, part.at(t))
    m = int(math.ceil(dwell / dt - 1e-9))  # samples the tracking segment spans after the meeting
    cs = np.concatenate([[0], np.cumsum(~inside)])
    n = len(t) - m
    inside_k = (cs[m + 1: m + 1 + n] - cs[:n]) == 0  # every sample of [t_k, t_k + dwell] inside
    tk = t[:n]
    ok = inside_k & (tk >= max(T_MIN, a_w) - 1e-12) & (tk <= b_w + 1e-12)
    first = np.flatnonzero(ok)
    if not first.size:
        where = "the belt window and " if window is not None else ""
        raise UnreachableError(
            f"{part.label()}: it is never inside {where}the workspace of profile {profile.name} for the pick and "
            f"{dwell:g} s of tracking within {HORIZON:g} s of the move's start (at the start, latency "
            f"{part.latency:g} s, it is at {','.join(f'{c:.4g}' for c in part.at(0.0))} m)"
        )
    k = int(first[0])
    end = k + int(np.argmin(ok[k:])) if not ok[k:].all() else n
    a = max(float(tk[k]), a_w, T_MIN)
    if k > 0 and inside_k[k - 1]:  # inside since the sample before: the stretch starts where T_MIN or the window say
        a = max(a_w, T_MIN, float(tk[k - 1]))
    if end >= n:
        b, what = min(float(tk[-1]), b_w), "horizon"
    else:
        b = min(float(tk[end - 1]), b_w)
        what = "window" if b_w <= float(tk[end - 1]) + dt else "workspace"
    if window is not None and b_w <= b + 1e-12:
        what = "window"
    return a, b, what


# ------------------------------------------------------------------------------------------ the solve


#: the solver of the first exact evaluation of a rendezvous search (bspline-vel's ``solver``; the confirming
#: solve at the root is always "exact")
FIRST_SOLVER = "seeded"
#: relative width at which the secant search of the exact root stops (:func:`_root_near`): T is then within
#: 1e-5 of the root (~1.4 µs on an Adept-size move; the meeting point is exact at whatever T is chosen), one
#: continued solve fewer than 1e-6 for the capacity rule (bench/bench_rendezvous.py)
ROOT_RTOL = 1e-5


def find_rendezvous(
    start, part: Part, profile, time: str | float = "limits", height: float | None = None, eta: float | None = None,
    v_from=None, method_params: dict | None = None, dwell: float | None = None, start_angle: float | None = None,
    turn: str = "shortest", turn_during: str = "transfer",
) -> Rendezvous:
    """The duration T and meeting point P(T) of a bspline-vel move from ``start`` [m] (leaving with ``v_from``
    [m/s], default 0) that meets ``part`` with the belt's velocity, under the duration rule ``time`` (seconds,
    "auto" or "fit"; "optimal" is refused like for ``--method bspline-vel``). ``dwell`` [s]: the tracking
    segment that must stay in the window and workspace after the meeting (default: the profile's dwell).
    ``start_angle`` [rad]: the tool angle at the start, turned to the part's ``angle`` by ``turn`` over
    ``turn_during`` (a rotary fourth axis; both or neither). See the module docstring for the method;
    UnreachableError (exit 4) when there is no rendezvous."""
    from ..model.errors import UsageError
    from ..paths.turn import turned_at
    from ..timing import Duration, auto_duration, parse_time

    spec = parse_time(time)
    if spec == "optimal":
        raise UsageError(
            "--time optimal: method bspline-vel plans its path for a duration (the end velocities enter as v·T), "
            "so a time law would change the path; use --time fit"
        )
    params = dict(method_params or {})
    if params.get("params") is not None or any(k in params for k in ("tau6", "lambda1")):
        raise UsageError("--to-belt: the shape parameters are chosen for each trial meeting time; drop --param tau6 … lambda3")
    h = float(height if height is not None else profile.planning.height)
    e_ratio = float(eta if eta is not None else profile.planning.eta)
    dwell = float(profile.planning.dwell if dwell is None else dwell)
    start = np.asarray(start, float)
    v0 = np.zeros(3) if v_from is None else np.asarray(v_from, float)
    angles = _angles(start, part, profile, start_angle, turn)
    a, b, what = allowed_interval(part, profile, dwell)
    cls = _factory_class()
    # the first exact solve from the table's seeds only ("seeded": one SLSQP run per stage, about half the
    # multi-start's time); later trial T continue from it, and a global solve confirms the shape at the root
    exact = cls(start, part, h, e_ratio, v0, angles, **({"solver": FIRST_SOLVER} | params))
    turning = turned_at(exact, turn_during)  # the paths the limits see: with the tool's turn, when there is one
    if isinstance(spec, float):
        T = spec
        if not a - 1e-12 <= T <= b + 1e-12:
            _outside(part, T, a, b, what, f"--time {T:g} s")
        path = exact(T)
        tv, ta, tj, _ = auto_duration(path, profile.capacity)
        return Rendezvous(part, exact.task_at(T), Duration(T, "given", tv, ta, tj, "given"), path, (a, b),
                          evaluations={"exact": 1})
    plan_dwell = profile.planning.dwell
    screen = _Rule(spec, profile, _screening_factory(start, part, h, e_ratio, v0, params.get("table")), plan_dwell)
    # a start near the root: fixed-point steps T ← T_auto(P(T)) on the cheap paths (capacity rule for both)
    cap = _Rule("auto", profile, screen.factory, plan_dwell)
    T0 = min(max(0.2, a), b)
    for _ in range(3):
        T0 = min(max(T0 * (1.0 + cap(T0)), a), b)
        if not math.isfinite(T0):
            T0 = min(max(0.2, a), b)
            break
    T_screen = _first_feasible(screen, a, b, T0, 0.9, 1e-6)
    rule = _Rule(spec, profile, turning, plan_dwell)
    if T_screen is None:  # by how much: the first feasible T beyond b, screened, then on the exact shape
        beyond = _first_feasible(screen, b, HORIZON, b, 0.8, 1e-6) if b < HORIZON else None
        if beyond is not None and math.isfinite(beyond):
            beyond = _first_feasible(rule, b, HORIZON, beyond, 0.98, 1e-10)
        _missed(part, rule, a, b, what, spec, known=beyond if beyond is not None else math.inf)
    # the exact root: secant steps from the screened one (a few continued solves), the scan if they do not settle
    power = 1.0 if spec == "auto" else 3.0
    T = _root_near(rule, a, b, T_screen, rtol=ROOT_RTOL, power=power)
    if T is None:
        T = _first_feasible(rule, a, b, T_screen, 0.98, 1e-8)
    if T is not None and T > a:
        path, agreed = exact.final(T)  # a global solve confirms the continued shape at the root
        if not agreed:  # the continuation had followed a worse branch: search again on the better one
            T2 = _root_near(rule, a, b, T, rtol=ROOT_RTOL, power=power)
            T = T2 if T2 is not None else _first_feasible(rule, a, b, T, 0.98, 1e-8)
    if T is None:
        _missed(part, rule, a, b, what, spec)
    T = _nudge(rule, turning, profile, spec, T, plan_dwell)
    if T > b + 1e-12:
        _missed(part, rule, a, b, what, spec, known=T)
    path = exact(T)
    tv, ta, tj, binding = auto_duration(path, profile.capacity)
    if spec == "auto":
        duration = Duration(T, "auto", tv, ta, tj, binding)
    elif spec == "limits":
        from ..timing import _worst_utilisation
        from ..planner import motion_model

        found = _worst_utilisation(motion_model(path, profile), plan_dwell)
        fit_excess, fit_name = found[0](T * (1 - 1e-9)) if found is not None else (-1.0, None)
        cap_excess = max(tv, ta, tj or 0.0) / (T * (1 - 1e-9)) - 1.0
        duration = Duration(T, "limits", tv, ta, tj, fit_name if fit_excess >= cap_excess else f"capacity {binding}")
    else:
        from ..timing import _worst_utilisation
        from ..planner import motion_model

        worst = _worst_utilisation(motion_model(turning(T), profile), plan_dwell)[0]
        duration = Duration(T, "fit", tv, ta, tj, worst(T * (1 - 1e-9))[1], T)
    return Rendezvous(part, exact.task_at(T), duration, path, (a, b), waited=T <= a + 1e-12,
                      evaluations={"screening": screen.count + cap.count, "exact": rule.count})


def _angles(start, part: Part, profile, start_angle: float | None, turn: str) -> tuple:
    """(tool angle at the start, at the meeting) [rad] (:func:`~pickplace_cli.paths.turn.resolve_angles`)."""
    from ..paths.turn import resolve_angles
    from ..planner import motion_model_static

    robot, specs = motion_model_static(profile)[:2]
    return resolve_angles(start, part.position, start_angle, part.angle, turn, robot, specs, profile.name)


def _nudge(rule: _Rule, factory, profile, spec: str, T: float, dwell: float) -> float:
    """T nudged up until the rule holds exactly at T (a root is within brentq's tolerance of the crossing,
    and each nudge moves P(T) a little); for fit, the exact (refined) limit check decides, as in --time fit."""
    for _ in range(20):
        if spec in ("auto", "limits"):
            ex = rule(T) if spec == "auto" else _Rule("auto", profile, factory, dwell)(T)
            if ex > 0:
                T *= 1.0 + ex + 1e-13
                continue
            if spec == "auto":
                return T
        if spec != "auto":
            from ..limits.check import check_limits
            from ..planner import motion_model

            rep = check_limits(motion_model(factory(T), profile), T, dwell=dwell)
            bad = [r for r in rep.violations if r.kind != "reach"]
            if not bad:
                return T
            T *= max(r.utilisation for r in bad) * (1.0 + 1e-9)
    return T  # pragma: no cover - converges in one or two steps (tests)


def _outside(part: Part, T: float, a: float, b: float, what: str, rule: str) -> None:
    if T < a:
        raise UnreachableError(
            f"{part.label()}: {rule} meets it at t = {T:.4f} s, {part.speed * (a - T) * 1e3:.0f} mm before it "
            f"enters the {'window' if what == 'window' else 'workspace'} (earliest meeting t = {a:.4f} s)"
        )
    raise UnreachableError(
        f"{part.label()}: {rule} meets it at t = {T:.4f} s, {part.speed * (T - b) * 1e3:.0f} mm after the last "
        f"point where it can be picked and tracked inside the {what if what != 'horizon' else 'workspace'} "
        f"(t = {b:.4f} s)"
    )


def _missed(part: Part, rule: _Rule, a: float, b: float, what: str, spec: str, known: float | None = None) -> None:
    """UnreachableError: the robot cannot meet the part by ``b``; by how much (``known``, or the first feasible
    T beyond b by ``rule``, when there is one within the horizon)."""
    T_f = (known if math.isfinite(known) else None) if known is not None else (_first_feasible(rule, b, HORIZON, b, 0.8, 1e-6) if b < HORIZON else None)
    place = {"window": "the belt window", "workspace": "the workspace", "horizon": "the workspace"}[what]
    if T_f is None or not math.isfinite(T_f):
        raise UnreachableError(
            f"{part.label()}: the robot cannot reach it before it leaves {place} (last possible meeting "
            f"t = {b:.4f} s after the move starts; --time {spec} needs longer)"
        )
    raise UnreachableError(
        f"{part.label()}: the part leaves {place} {part.speed * (T_f - b) * 1e3:.0f} mm before the robot can reach "
        f"it (--time {spec}: earliest meeting t = {T_f:.4f} s, last allowed t = {b:.4f} s after the move starts)"
    )


# ------------------------------------------------------------------------------------------ the plan


def plan_rendezvous(start, part: Part, profile, time: str | float = "limits", height: float | None = None,
                    eta: float | None = None, v_from=None, method_params: dict | None = None,
                    rate: float | None = None, dwell: float | None = None, start_angle: float | None = None,
                    turn: str = "shortest", turn_during: str = "transfer", cycle: float | None = None):
    """(Plan of the move to the meeting point, Rendezvous): :func:`find_rendezvous`, then the planner's
    pipeline (samples, joint motion, limit check) on that move at T, with the found shape (no second solve).
    The plan's duration says how T was chosen; ``parameters["rendezvous"]`` says where and when it meets.
    ``start_angle``, ``turn``, ``turn_during``: the tool's turn to the part's angle (:func:`find_rendezvous`).
    ``cycle`` [s]: T rounded up to whole cycles, the part met where it is then (P(T) planned again for it)."""
    from ..model.headroom import apply_limit_use
    from ..planner import PlanOptions, plan
    from ..timing import parse_time

    profile = apply_limit_use(profile)  # every timed limit at its limit-use fraction
    rv = find_rendezvous(start, part, profile, time, height, eta, v_from, method_params, dwell, start_angle, turn,
                         turn_during)
    T_rule = rv.seconds

    def planned(found: Rendezvous, on_cycle: bool = True):
        shape = [found.path.parameters[k] for k in ("tau6", "tau7", "tau9", "tau10", "lambda1", "lambda2", "lambda3")]
        options = PlanOptions(method="bspline-vel", method_params={"params": shape}, time=found.seconds, rate=rate,
                              fit=False, cycle=cycle if on_cycle else None, capacity_rows=parse_time(time) != "fit",
                              turn="as-given", turn_during=turn_during)  # the task's end angle is resolved already
        return plan(found.task, profile, options)

    if cycle is None:
        got = planned(rv)
    else:
        rv, got, note = _on_cycle(rv, planned, cycle, lambda T, d: find_rendezvous(
            start, part, profile, T, height, eta, v_from, method_params, d, start_angle, turn, turn_during),
            profile.planning.dwell if dwell is None else dwell)
        got = replace(got, cycle=replace(got.cycle, requested_s=T_rule, extra_cycles=got.cycle.cycles - _whole(
            T_rule, cycle), note=note or got.cycle.note))
    parameters = {**rv.path.parameters, "rendezvous": rv.as_dict()}
    return replace(got, duration=rv.duration, parameters=parameters), rv


def _whole(seconds: float, cycle: float) -> int:
    from ..timing.cycle import whole_cycles

    return whole_cycles(seconds, cycle)


def _on_cycle(rv: Rendezvous, planned, cycle: float, solve, dwell: float):
    """The rendezvous ``rv`` (duration T by its rule) on a controller's ``cycle`` [s]: T rounded up to n whole
    cycles and the meeting solved again for n·cycle (``solve(T, dwell)``: the part met where it is then, the
    tracking ``dwell`` [s] rounded up to whole cycles inside the window); ``planned(rendezvous)`` → its Plan on the
    cycle. When the rounded move breaks a limit that held at T, a cycle more is tried (the meeting solved again each
    time; at most :data:`~pickplace_cli.timing.cycle.MAX_EXTRA_CYCLES`), never past the last allowed meeting.
    → (Rendezvous, Plan, note: what was added and why, else ""); the Plan's report says what fails when nothing
    holds (exit 3)."""
    from ..timing.cycle import MAX_EXTRA_CYCLES

    T_rule = rv.seconds
    n = _whole(T_rule, cycle)
    d_c = _whole(dwell, cycle) * cycle
    held = None  # whether every limit held at T_rule (planned only when a rounded move breaks one)
    first = None
    for extra in range(MAX_EXTRA_CYCLES + 1):
        T_c = (n + extra) * cycle
        if extra and T_c > rv.window_s[1] + 1e-12:
            break  # the part would be past the last allowed meeting
        try:
            found = rv if T_c == T_rule else solve(T_c, d_c)
        except UnreachableError:
            if not extra:
                raise
            break  # the tracking would leave the window or the workspace
        found = replace(found, duration=replace(rv.duration, seconds=T_c), window_s=rv.window_s)
        got = planned(found)
        # a plan that added cycles of its own (its dwell rounded) no longer meets the part: counted as not holding
        ok = got.report.ok and (got.cycle is None or got.cycle.extra_cycles == 0)
        if first is None:
            first = (found, got)
        if ok:
            if extra:
                broken = ", ".join(f"{r.joint} {r.quantity}" for r in first[1].report.violations) or "a limit"
                note = (f"{n} cycles broke {broken} (held at T = {T_rule:.6g} s): {extra} more "
                        f"cycle{'s' if extra > 1 else ''} added, the meeting solved again for each")
                got = replace(got, report=replace(got.report, notes=got.report.notes + (note,)))
                return found, got, note
            return found, got, ""
        if held is None:
            held = T_c != T_rule and planned(rv, on_cycle=False).report.ok
            if not held:
                break
    found, got = first
    if got.cycle is not None and got.cycle.extra_cycles:  # its own extra cycles moved the meeting: never written
        from ..model.errors import NoFeasibleDuration

        raise NoFeasibleDuration(
            f"{rv.part.label()}: on the {cycle * 1e3:g} ms cycle a pick of {n} cycles breaks a limit with the dwell "
            f"rounded to {d_c:.6g} s, and so do the longer picks tried: no whole-cycle pick meets the part within "
            "the limits (another --cycle or --time)")
    return found, got, ""
