"""The line file: a belt, the robots along it, the parts it carries and the strategy that shares them out.

``load_line(path)`` reads a YAML file (safe: no aliases, anchors or deep nesting, as for profiles) and validates it
with pydantic (unknown keys refused, SI units); every problem is a :class:`~pickplace_cli.model.errors.ProfileError`
(exit 1) with one line ``FILE:LINE: FIELD = VALUE: RULE``.

**The line frame.** ``along`` is the distance along the belt in its direction of travel [m], ``across`` the offset
from the belt's centre line to the left of that direction [m], ``height`` the height above the belt surface [m].
Every position in the file is given as ``[along, across, height]`` in this frame. The robots are mounted alike:
``belt.direction`` says which axis of their base frames the belt runs along (``+y``: along = the robot's y axis).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any, Literal, Optional, Union

from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from ..model.errors import ProfileError
from ..model.numbers import Int, Num  # a flag or a number in quotes is refused, as in a profile

#: a line file is a few kilobytes; larger ones are refused before they are parsed [bytes]
LINE_MAX_BYTES = 1 << 20
#: the most robots a line may have
MAX_ROBOTS = 16
#: the slowest and fastest belt [m/s]: slower than 1 mm/s a part takes longer than 10^3 s per metre of window, and
#: the times of a run lose the resolution the meeting needs (1e-300 m/s met 20 parts at one instant)
MIN_BELT_SPEED, MAX_BELT_SPEED = 1e-3, 100.0
#: the largest generator seed (numpy's seeds are any integer >= 0; a seed is a 64-bit number in practice)
MAX_SEED = 2**64 - 1


Xyz = tuple[Num, Num, Num]


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


class Belt(_Model):
    """The infeed belt that carries the parts past the robots."""

    speed: Num = Field(ge=MIN_BELT_SPEED, le=MAX_BELT_SPEED, description="Belt speed in m/s along its direction of "
                       "travel (0.001 … 100 m/s)")
    width: Num = Field(gt=0, le=10, description="Belt width in m (parts lie within ±width/2 of the centre line)")
    direction: Literal["+x", "-x", "+y", "-y"] = Field(
        default="+y", description="The belt's direction of travel as an axis of the robots' base frames")


class Tray(_Model):
    """A pattern of place points: rows along the belt, columns across it, filled row by row; a full tray is
    replaced at once by an empty one (the pattern starts again)."""

    origin: Xyz = Field(description="First slot [along, across, height] in m (line frame)")
    rows: Int = Field(default=1, ge=1, le=1000, description="Slots along the belt")
    columns: Int = Field(default=1, ge=1, le=1000, description="Slots across the belt")
    pitch: tuple[Num, Num] = Field(default=(0.05, 0.05), description="Slot spacing [along, across] in m (sign: direction)")


class OutgoingBelt(_Model):
    """A second belt the parts are put on: the tool arrives at ``point`` with the belt's velocity and releases
    the part while moving with it for the profile's dwell."""

    point: Xyz = Field(description="Place point [along, across, height] in m (line frame)")
    velocity: tuple[Num, Num] = Field(description="Outgoing belt velocity [along, across] in m/s (line frame)")
    pitch: Optional[Num] = Field(default=None, gt=0, le=10, description="Pockets (cartons, slots) every this many m "
                                 "along the outgoing belt: each part goes into the next pocket the robot can meet, "
                                 "met by a rendezvous (default none: put down at point, whatever passes there)")
    first: Num = Field(default=0.0, description="With pitch: the time in s (line clock) at which pocket 0 passes point")
    reach: Optional[Num] = Field(default=None, gt=0, le=10, description="With pitch: how far in m upstream or "
                                 "downstream of point along the outgoing belt a pocket may be met (default pitch / 2)")

    @model_validator(mode="after")
    def _pockets(self) -> "OutgoingBelt":
        if self.pitch is not None and math.hypot(*self.velocity) <= 0.0:
            raise ValueError("pitch: pockets on a belt that stands still are fixed points: give place.points instead")
        if self.pitch is None and (self.reach is not None or self.first != 0.0):
            raise ValueError("first and reach are for pockets: give pitch too")
        return self


class Exchange(_Model):
    """A place that is exchanged (a full tray replaced, a tray indexed): every ``every`` places the robot cannot
    place for ``time`` seconds."""

    every: Optional[Int] = Field(default=None, ge=1, le=100000, description="Places between two exchanges "
                                 "(default: the number of place targets, a full tray)")
    time: Num = Field(gt=0, le=3600, description="Seconds from the release of the last part until the robot may "
                                                 "place again (0 … 3600 s)")


class Place(_Model):
    """Where a robot puts its parts: fixed ``points`` (used in turn), a ``tray`` pattern, or an outgoing ``belt``."""

    points: Optional[list[Xyz]] = Field(default=None, min_length=1, max_length=10000,
                                        description="Place points [along, across, height] in m, used in turn")
    tray: Optional[Tray] = Field(default=None, description="A tray pattern of place points")
    belt: Optional[OutgoingBelt] = Field(default=None, description="An outgoing belt")
    angle: Union[Num, list[Num], None] = Field(
        default=None, description="The angle [rad] about the vertical (line frame, counter-clockwise from the belt's "
        "direction seen from above) at which a part must lie once placed: one for every target, or one per target "
        "in turn (a tray's slots row by row); default none: a part is placed as it lies")
    angle_tolerance: Num = Field(default=0.0, ge=0, le=math.pi, description="How far [rad] a part's angle may lie "
                                 "from the place angle and still be placed unturned by a robot without a rotary "
                                 "fourth axis (0 … pi rad; default 0 rad)")
    exchange: Optional[Exchange] = Field(default=None, description="The tray's exchange: every N places, T seconds "
                                         "during which the robot cannot place (default: none)")

    @model_validator(mode="after")
    def _one(self) -> "Place":
        given = [k for k in ("points", "tray", "belt") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError(f"give exactly one of points, tray, belt (got {', '.join(given) or 'none'})")
        if self.exchange is not None and self.belt is not None:
            raise ValueError("exchange: an outgoing belt is not exchanged; give exchange with points or a tray")
        if isinstance(self.angle, list):
            n = (len(self.points) if self.points is not None else
                 self.tray.rows * self.tray.columns if self.tray is not None else 1)
            if len(self.angle) != n:
                raise ValueError(f"angle has {len(self.angle)} values for {n} place target{'s' if n > 1 else ''}: "
                                 "give one angle [rad] for all, or one per target")
        for x in self.angle if isinstance(self.angle, list) else [self.angle] if self.angle is not None else []:
            if abs(x) > 100.0:
                raise ValueError(f"angle = {x:g} rad: must lie within ±100 rad (SI units: radians, not degrees)")
        return self


class Gripper(_Model):
    """The gripper's switching times, each added to the profile's dwell: at the pick the tool tracks the part for the
    dwell plus ``close`` before it leaves; at the place it waits the dwell plus ``open`` before it moves on."""

    close: Num = Field(default=0.0, ge=0, le=10, description="Seconds from the grip command until the part is held "
                                                             "(the tool tracks the part meanwhile)")
    open: Num = Field(default=0.0, ge=0, le=10, description="Seconds from the release command until the part is free "
                                                            "(the tool waits at the place point meanwhile)")


class RobotSpec(_Model):
    """One robot of the line."""

    name: str = Field(min_length=1, max_length=40, pattern=r"^[A-Za-z][A-Za-z0-9_-]*$",
                      description="Name (letters, digits, _ and -; names the robot's topics and rows)")
    profile: str = Field(default="delta-su2018", min_length=1,
                         description="Its profile: a shipped name or a YAML file (relative to the line file)")
    base: Xyz = Field(description="Origin of its base frame [along, across, height above the belt] in m")
    window: tuple[Num, Num] = Field(description="Reach window [start, end] along the belt in m: where it may meet "
                                                "a part and track it")
    place: Optional[Place] = Field(default=None, description="Where it puts the parts (every part type, when the "
                                   "line has several: one place for all)")
    places: Optional[dict[str, Place]] = Field(default=None, min_length=1, description="Or, on a line with part "
                                               "types (parts.types): a place per type, keyed by the type's name; the "
                                               "robot takes only these types")
    home: Optional[Xyz] = Field(default=None, description="Rest point [along, across, height] in m where it starts "
                                                           "(default: its first place point)")
    time: Union[Literal["limits", "auto", "fit"], Num, None] = Field(
        default=None, description="Duration rule of every move: limits (every limit of the profile: the motors and the "
                                  "Cartesian capacity), auto (the capacity alone), fit (the joint and motor limits "
                                  "alone), or seconds (default: limits)")
    limit_use: Optional[Num] = Field(
        default=None, gt=0, le=1, description="Headroom: every timed limit planned to at most this fraction of its "
                                              "rating, in (0, 1] (default: the profile's planning.limit_use)")
    gripper: Gripper = Field(default_factory=Gripper, description="Gripper close and open times in s, each added "
                             "to the profile's dwell at the pick and at the place (default 0 s)")
    shape: Literal["table", "optimal"] = Field(
        default="table", description="table: each move's shape from the conveyor table, held fixed while its duration "
        "is searched (fast); optimal: re-optimised at every trial duration, as plan --to-belt (about a second a pick)")

    @model_validator(mode="after")
    def _window(self) -> "RobotSpec":
        if (self.place is None) == (self.places is None):
            raise ValueError("give one of place (every part type) or places (a place per part type)")
        if not self.window[0] < self.window[1]:
            raise ValueError(f"window = {list(self.window)} m: needs start < end along the belt")
        if isinstance(self.time, float) and not self.time > 0:
            raise ValueError(f"time = {self.time:g} s: a duration must be > 0 s")
        return self


class Generator(_Model):
    """Parts made up by a seeded random generator (the same seed gives the same parts)."""

    rate: Num = Field(gt=0, le=1000, description="Mean arrival rate in parts/s (300 parts/min = 5)")
    count: Optional[Int] = Field(default=None, ge=1, le=10_000_000, description="How many parts")
    duration: Optional[Num] = Field(default=None, gt=0, le=1e6, description="Or: arrivals during this many seconds")
    spread: Optional[Num] = Field(default=None, ge=0, description="Width in m across the belt, centred, where "
                                                                   "parts lie (uniform; default: the belt's width)")
    arrival: Literal["regular", "poisson"] = Field(default="poisson", description="regular: one every 1/rate s; "
                                                   "poisson: exponential gaps of mean 1/rate s")
    seed: Int = Field(default=0, ge=0, le=MAX_SEED, description="Seed of the random numbers (0 … 2^64 − 1)")
    detect_at: Num = Field(default=0.0, description="Where along the belt the parts are detected, in m")
    angles: bool = Field(default=False, description="Give each part a random angle in [-pi, pi) rad")

    @model_validator(mode="after")
    def _amount(self) -> "Generator":
        if (self.count is None) == (self.duration is None):
            raise ValueError("give one of count (parts) or duration (s)")
        return self


#: a part type's name: letters, digits, _ and - (it is a CSV cell and a key)
TYPE_NAME = r"^[A-Za-z][A-Za-z0-9_-]{0,39}$"


class PartType(_Model):
    """One kind of part on the belt (a product): its share of the generated parts."""

    share: Num = Field(ge=0, le=1, description="Share of the generated parts of this type, 0 … 1 (the types' shares "
                                               "add up to 1); detections name their type themselves")


class Parts(_Model):
    """Where the parts come from and how they are seen."""

    detections: Optional[str] = Field(default=None, description="A detection CSV (t[s], along[m], across[m], "
                                                                "optional angle[rad], id; type with parts.types); "
                                                                "relative to the line file")
    generate: Optional[Generator] = Field(default=None, description="A seeded generator instead of a file")
    height: Num = Field(default=0.0, ge=0, le=1, description="Grip point above the belt surface in m")
    latency: Num = Field(default=0.0, ge=0, le=10, description="Seconds from a detection until a robot may start "
                                                               "its move (vision, planning, bus)")
    reorder: Num = Field(default=0.0, ge=0, le=60, description="Seconds a detection may come late: detections are "
                                                               "held this long and put in time order")
    types: Optional[dict[str, PartType]] = Field(default=None, min_length=1, max_length=100, description="Part "
                                                 "types by name (default none: one kind of part): generated parts get "
                                                 "a type by the shares, detections name it in their type column")

    @model_validator(mode="after")
    def _source(self) -> "Parts":
        if self.detections is not None and self.generate is not None:
            raise ValueError("give one of detections (a file) or generate, not both")
        return self


class _Strategy(_Model):
    claim: Optional[Num] = Field(default=None, gt=0, description="How far into its window (m from the window's "
                                 "start) a robot may meet a part; a part it could only meet farther on passes on")


class UpstreamFirst(_Strategy):
    """Every part goes to the most upstream robot that can take it (all targets considered)."""

    kind: Literal["upstream_first"]


class Quota(_Strategy):
    """Each robot takes at most its share of the parts; a part over a robot's share passes on."""

    kind: Literal["quota"]
    shares: Optional[list[Num]] = Field(default=None, description="Share of each robot (in robot order, sum 1; "
                                                                  "default: equal)")
    feedback: bool = Field(default=False, description="End-of-line feedback: a part that leaves the line after a "
                           "robot passed it on because of its share gives that robot one more pick")


class Bands(_Strategy):
    """Each robot takes the parts in its band across the belt."""

    kind: Literal["bands"]
    bands: Optional[list[tuple[Num, Num]]] = Field(default=None, description="[low, high] across the belt in m per "
                                                   "robot (default: the width split equally, first robot lowest)")
    overlap: Num = Field(default=0.0, ge=0, description="A part within this many m of its band may also be taken by "
                                                        "the robot of the neighbouring band")


class Skip(_Strategy):
    """Robot k takes part n when n mod (skip + 1) = k (each robot takes one part, then lets ``skip`` pass)."""

    kind: Literal["skip"]
    skip: Optional[Int] = Field(default=None, ge=0, le=1000, description="Parts each robot lets pass after each "
                                                                         "one it takes (default: robots - 1)")
    pass_on: bool = Field(default=True, description="A part its robot cannot take is offered to the robots "
                                                    "downstream of it")


Strategy = Annotated[Union[UpstreamFirst, Quota, Bands, Skip], Field(discriminator="kind")]
STRATEGIES = ("upstream_first", "quota", "bands", "skip")


class Line(_Model):
    """A line of robots on one belt."""

    name: str = Field(default="line", min_length=1, description="Name of the line")
    description: str = Field(default="", description="Free text")
    belt: Belt
    robots: list[RobotSpec] = Field(min_length=1, max_length=MAX_ROBOTS, description="The robots (any order)")
    parts: Parts = Field(default_factory=Parts)
    strategy: Strategy = Field(default_factory=lambda: UpstreamFirst(kind="upstream_first"),
                               description="How the parts are shared out (default: upstream_first)")


# ------------------------------------------------------------------------------------------------- rules


def check_rules(line: Line, source: str = "line") -> None:
    """The rules across fields that pydantic cannot say alone: unique names, shares, bands, windows that the
    strategy can keep apart. ProfileError (exit 1), one line naming the robots and the rule."""
    names = [r.name for r in line.robots]
    dup = next((n for n in names if names.count(n) > 1), None)
    if dup is not None:
        raise ProfileError(f"{source}: robots: name {dup!r} is used twice; every robot needs its own name")
    n = len(line.robots)
    s = line.strategy
    half = line.belt.width / 2
    if isinstance(s, Quota) and s.shares is not None:
        if len(s.shares) != n:
            raise ProfileError(f"{source}: strategy.shares has {len(s.shares)} values for {n} robots: give one "
                               "share per robot, in robot order")
        if any(x < 0 for x in s.shares) or abs(sum(s.shares) - 1.0) > 1e-6:
            raise ProfileError(f"{source}: strategy.shares = {list(s.shares)}: every share must be >= 0 and they "
                               f"must add up to 1 (they add up to {sum(s.shares):.6g})")
    if isinstance(s, Bands) and s.bands is not None:
        if len(s.bands) != n:
            raise ProfileError(f"{source}: strategy.bands has {len(s.bands)} bands for {n} robots: give one "
                               "[low, high] per robot, in robot order")
        for name, (lo, hi) in zip(names, s.bands):
            if not lo < hi:
                raise ProfileError(f"{source}: strategy.bands of robot {name} = [{lo:g}, {hi:g}] m: needs low < high")
            if lo < -half - 1e-12 or hi > half + 1e-12:
                raise ProfileError(f"{source}: strategy.bands of robot {name} = [{lo:g}, {hi:g}] m: must lie on "
                                   f"the belt, within ±{half:g} m (belt.width / 2)")
    gen = line.parts.generate
    if gen is not None:
        from .parts import MAX_PARTS, expected_parts

        if expected_parts(gen) > MAX_PARTS:
            what = (f"count = {gen.count}" if gen.count is not None else
                    f"rate × duration = {gen.rate:g}/s × {gen.duration:g} s = {expected_parts(gen):.6g} parts")
            raise ProfileError(f"{source}: parts.generate.{what}: more than the {MAX_PARTS} parts a run may have (each "
                               "part's plan is kept for the results, about 0.14 MB a part): run a long production in "
                               "pieces")
    if line.parts.generate is not None and line.parts.generate.spread is not None \
            and line.parts.generate.spread > line.belt.width + 1e-12:
        raise ProfileError(f"{source}: parts.generate.spread = {line.parts.generate.spread:g} m: wider than the belt "
                           f"(belt.width = {line.belt.width:g} m)")
    check_types(line, source)
    check_windows(line, source)


#: how far the part types' shares may add up from 1
SHARE_TOLERANCE = 1e-9


def check_types(line: Line, source: str = "line") -> None:
    """Part types: names, shares adding up to 1 (within ``SHARE_TOLERANCE``), every robot's ``places`` keyed by
    declared types. ProfileError (exit 1), one line."""
    import re

    types = line.parts.types
    if types is None:
        bad = next((r for r in line.robots if r.places is not None), None)
        if bad is not None:
            raise ProfileError(f"{source}: robot {bad.name}: places = {sorted(bad.places)}: places per part type need "
                               "the types declared in parts.types (or give place: one place for every part)")
        return
    for name in types:
        if not re.match(TYPE_NAME, name):
            raise ProfileError(f"{source}: parts.types: name {name!r}: a type's name is a letter, then letters, digits, "
                               "_ or - (at most 40)")
    total = math.fsum(t.share for t in types.values())
    if abs(total - 1.0) > SHARE_TOLERANCE:
        raise ProfileError(f"{source}: parts.types: the shares {', '.join(f'{k} {t.share:.12g}' for k, t in types.items())} "
                           f"add up to {total:.12g}: they must add up to 1 (within {SHARE_TOLERANCE:g})")
    for r in line.robots:
        for name in r.places or {}:
            if name not in types:
                raise ProfileError(f"{source}: robot {r.name}: places.{name}: not a part type of parts.types "
                                   f"({', '.join(types)})")


def type_names(line: Line) -> list[str] | None:
    """The part types' names in file order (None: one kind of part)."""
    return None if line.parts.types is None else list(line.parts.types)


def robot_places(robot: RobotSpec, types: list[str] | None) -> dict:
    """{type: Place} of the types the robot takes (one place for every type, or its ``places``); {None: place} on
    a line without types."""
    if types is None:
        return {None: robot.place}
    if robot.places is None:
        return {t: robot.place for t in types}
    return {t: robot.places[t] for t in types if t in robot.places}


def untaken_types(line: Line) -> list[str]:
    """The part types no robot of the line takes (every part of them is missed)."""
    types = type_names(line)
    if types is None:
        return []
    return [t for t in types if not any(robot_places(r, types).get(t) is not None for r in line.robots)]


def robot_bands(line: Line) -> list[tuple[float, float]]:
    """Each robot's band [low, high] across the belt [m] (the strategy's, or the width split equally)."""
    s, n, half = line.strategy, len(line.robots), line.belt.width / 2
    if isinstance(s, Bands) and s.bands is not None:
        return [(float(lo), float(hi)) for lo, hi in s.bands]
    edges = [-half + line.belt.width * k / n for k in range(n + 1)]
    return list(zip(edges[:-1], edges[1:]))


def check_windows(line: Line, source: str = "line") -> None:
    """Two robots' windows may overlap along the belt only when the strategy keeps them apart across it (bands
    that do not overlap, counting the overlap tolerance): collisions between robots are not modelled."""
    robots = line.robots
    s = line.strategy
    bands = robot_bands(line) if isinstance(s, Bands) else None
    tol = s.overlap if isinstance(s, Bands) else 0.0
    for i in range(len(robots)):
        for j in range(i + 1, len(robots)):
            a, b = robots[i], robots[j]
            lo, hi = max(a.window[0], b.window[0]), min(a.window[1], b.window[1])
            if hi <= lo:
                continue
            if bands is not None:
                (l1, h1), (l2, h2) = bands[i], bands[j]
                if min(h1 + tol, h2 + tol) <= max(l1 - tol, l2 - tol):
                    continue
                why = (f"their bands [{l1:g}, {h1:g}] and [{l2:g}, {h2:g}] m (overlap tolerance {tol:g} m) share "
                       "part of the belt's width")
            else:
                why = f"strategy {s.kind} lets both work on the same stretch of belt"
            raise ProfileError(
                f"{source}: robots {a.name} and {b.name}: windows [{a.window[0]:g}, {a.window[1]:g}] and "
                f"[{b.window[0]:g}, {b.window[1]:g}] m overlap by {hi - lo:.4g} m along the belt, and {why}; "
                "collisions between robots are not modelled: give windows that do not overlap, or bands that do not"
            )


def upstream_order(line: Line) -> list[int]:
    """Robot indices from upstream to downstream (by window start; ties in file order)."""
    return sorted(range(len(line.robots)), key=lambda i: (line.robots[i].window[0], i))


# ------------------------------------------------------------------------------------------------ loading


def _describe(err: dict, data: Any, lines: dict, source: str, errors: list) -> str:
    """One line ``FILE:LINE: FIELD = VALUE: RULE`` of a pydantic error."""
    from ..model.yamlsafe import _show, locate

    real, node, where, field = locate(err, data, lines, source)
    kind = err["type"]
    if kind == "extra_forbidden":
        return f"{where}: unknown key {field!r}: not a field of this section (check spelling; keys are case-sensitive)"
    if kind == "missing" and real and isinstance(real[-1], int):  # a fixed-length list that is too short
        parent = ".".join(str(p) for p in real[:-1])
        given = err.get("input")
        absent = sum(1 for e in errors if e["type"] == "missing" and tuple(e["loc"])[:-1] == tuple(err["loc"])[:-1])
        n = len(given) if isinstance(given, (list, tuple)) else 0
        return f"{where}: {parent} = {_show(given)}: needs {n + absent} values, got {n}"
    if kind == "missing":
        return f"{where}: {field}: required field is missing"
    if kind == "union_tag_invalid":
        ctx = err.get("ctx") or {}
        return f"{where}: {field}.kind = {_show(ctx.get('tag'))}: must be one of {ctx.get('expected_tags')}"
    msg = err["msg"].removeprefix("Value error, ")
    value = err.get("input")
    if isinstance(value, dict) and kind == "value_error":
        return f"{where}: {field}: {msg}"
    return f"{where}: {field} = {_show(value)}: {msg}"


def parse_line(text: str, source: str = "<line>") -> Line:
    """Validate line-file YAML text (see :func:`load_line`)."""
    from ..model.yamlsafe import _prune_union_branches, _yaml_with_lines

    data, lines = _yaml_with_lines(text, source, what="line file")
    if not isinstance(data, dict):
        raise ProfileError(f"{source}: a line file must be a YAML mapping of keys (belt, robots, parts, strategy)")
    try:
        line = Line.model_validate(data)
    except ValidationError as exc:
        errors = _prune_union_branches(exc.errors(), data)
        errors.sort(key=lambda e: e["type"] != "extra_forbidden")  # a misspelt key explains the missing one
        first = _describe(errors[0], data, lines, source, errors)
        more = f" (and {len(errors) - 1} more problem{'s' if len(errors) > 2 else ''})" if len(errors) > 1 else ""
        raise ProfileError(first + more) from None
    check_rules(line, source)
    return line


def load_line(path: str | Path) -> Line:
    """Load and validate a line file (bounded read, UTF-8, safe YAML, pydantic, :func:`check_rules`)."""
    p = Path(path)
    try:
        with open(p, "rb") as fh:
            raw = fh.read(LINE_MAX_BYTES + 1)
    except OSError as exc:
        raise ProfileError(f"{p}: cannot read the line file: {exc.strerror or exc}") from None
    if len(raw) > LINE_MAX_BYTES:
        raise ProfileError(f"{p}: larger than {LINE_MAX_BYTES} bytes (1 MiB); a line file is a few kB: is this the "
                           "right file?")
    from ..model.text import decode_text

    return parse_line(decode_text(raw, str(p), "a YAML line file", ProfileError, csv=False), str(p))


def resolve_relative(name: str, line_path: str | Path | None) -> str:
    """A file named in the line file, relative to the line file's folder (a shipped profile name as it is)."""
    if line_path is None or Path(name).is_absolute():
        return name
    candidate = Path(line_path).parent / name
    return str(candidate) if candidate.exists() or "/" in name or name.endswith((".yaml", ".yml", ".csv")) else name


def time_rule(robot: RobotSpec) -> str | float:
    """The robot's duration rule: "limits", "auto", "fit" or seconds (default limits, as plan's)."""
    if robot.time is None:
        return "limits"
    return robot.time if isinstance(robot.time, str) else float(robot.time)

