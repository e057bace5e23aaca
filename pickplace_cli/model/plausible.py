"""Values in the wrong unit: a profile number that is valid as a number but not in the unit the field takes.

A profile is in SI units. Numbers copied from a data sheet often are not: a motor's maximum speed in rpm (3000, read
as 3000 rad/s = 28,648 rpm), a joint range in degrees ([-40, 90], read as radians: more than 14 turns), a stroke in
millimetres. Each such value would make a limit far looser than the real one, so a plan that breaks the real limit
would pass (exit 0). The rules, per field (the thresholds are far outside any robot this tool models):

* ``drive.max_speed`` [rad/s]: refused above :data:`MAX_MOTOR_SPEED` (20,000 rpm: no servo of a pick-and-place
  robot turns that fast; rpm meant), a warning above :data:`WARN_MOTOR_SPEED` (10,000 rpm).
* a revolute joint's ``limits.position`` [rad]: refused when a bound lies beyond one turn, ±2π (degrees meant: a
  Delta or SCARA arm cannot turn further without hitting itself).
* a prismatic joint's range or a gantry axis' ``travel`` [m]: refused beyond :data:`MAX_STROKE` (millimetres meant),
  a warning beyond :data:`WARN_STROKE`.

:func:`unit_problems` returns (refusals, warnings), one line each, naming the file, the field, the value and the
likely unit with the value converted.
"""

from __future__ import annotations

import math

#: fastest motor speed a profile may give [rad/s] (20,000 rpm); above: refused, rpm meant
MAX_MOTOR_SPEED = 20000 * 2 * math.pi / 60
#: a motor speed above this [rad/s] (10,000 rpm) gets a warning
WARN_MOTOR_SPEED = 10000 * 2 * math.pi / 60
#: the longest prismatic stroke or gantry travel bound [m]; beyond: refused, millimetres meant
MAX_STROKE = 100.0
#: a stroke or travel bound beyond this [m] gets a warning
WARN_STROKE = 10.0

#: the unit of each joint by robot kind (joints beyond the list are not checked here)
JOINT_UNITS = {"delta": ("rad", "rad", "rad"), "scara": ("rad", "rad", "m"), "gantry": ("m", "m", "m")}


def _rpm(x: float) -> str:
    return f"{x * 60 / (2 * math.pi):,.0f} rpm"


def unit_problems(profile, source: str) -> tuple[list[str], list[str]]:
    """(refusals, warnings) for values of ``profile`` (read from ``source``) in a likely wrong unit (module
    docstring)."""
    bad: list[str] = []
    warn: list[str] = []
    robot = profile.robot
    specs = robot.joint_specs()
    units = JOINT_UNITS.get(robot.kind, ())
    shared = robot.kind != "gantry" and not isinstance(getattr(robot, "joints", None), (list, tuple))
    for k, (spec, unit) in enumerate(zip(specs, units)):
        if shared and k > 0:
            break  # one spec for every joint: said once
        where = (f"robot.axes[{k}]" if robot.kind == "gantry" else
                 "robot.joints" if shared else f"robot.joints[{k}]")
        joint = "every joint" if shared else f"q{k + 1}"
        d = spec.drive
        if d is not None and d.max_speed is not None and d.max_speed > WARN_MOTOR_SPEED:
            line = (f"{source}: {where}.drive.max_speed = {d.max_speed:g} rad/s ({joint}) is {_rpm(d.max_speed)}: "
                    f"rpm meant? {d.max_speed:g} rpm = {d.max_speed * 2 * math.pi / 60:.4g} rad/s")
            if d.max_speed > MAX_MOTOR_SPEED:
                bad.append(line + f" (a profile gives rad/s; above {_rpm(MAX_MOTOR_SPEED)} is refused)")
            else:
                warn.append(line)
        pos = spec.limits.position
        if pos is None:
            continue
        field = f"{where}.travel" if robot.kind == "gantry" else f"{where}.limits.position"
        shown = f"[{pos[0]:g}, {pos[1]:g}]"
        if unit == "rad" and max(abs(pos[0]), abs(pos[1])) > 2 * math.pi:
            rad = ", ".join(f"{math.radians(x):.4f}" for x in pos)
            bad.append(f"{source}: {field} = {shown} rad ({joint}) reaches beyond one turn (±2π): degrees meant? "
                       f"{shown} deg = [{rad}] rad")
        elif unit == "m" and max(abs(pos[0]), abs(pos[1])) > WARN_STROKE:
            metres = ", ".join(f"{x / 1000:g}" for x in pos)
            line = (f"{source}: {field} = {shown} m ({joint}): millimetres meant? {shown} mm = [{metres}] m")
            (bad if max(abs(pos[0]), abs(pos[1])) > MAX_STROKE else warn).append(line)
    return bad, warn


class UnitWarning(UserWarning):
    """A value that is valid but likely in another unit (the CLI prints each as one line)."""


def check_units(profile, source: str) -> None:
    """ProfileError listing every refused value (:func:`unit_problems`); each warning through :mod:`warnings` as a
    :class:`UnitWarning`."""
    import warnings

    from .errors import ProfileError

    bad, warn = unit_problems(profile, source)
    if bad:
        raise ProfileError("\n".join(bad))
    for line in warn:
        warnings.warn(line, UnitWarning, stacklevel=3)


# ------------------------------------------------------------------------------ points and heights of a move

#: without a workcell box: a coordinate farther than this [m] is not a pick-and-place point
FAR_M = 10.0
#: without a workcell box: a height above this [m] is not a clearance
TALL_M = 2.0


def workcell_box(prof):
    """(min, max) [m] the tool must stay in: the workcell box, a gantry's travel, or None."""
    box = prof.workcell.box
    if box is not None:
        return tuple(box.min), tuple(box.max)
    if prof.robot.kind == "gantry":
        axes = prof.robot.axes
        return tuple(a.travel[0] for a in axes), tuple(a.travel[1] for a in axes)
    return None


def _inside(p, box) -> bool:
    if box is None:
        return max(abs(c) for c in p) <= FAR_M
    return all(lo <= c <= hi for c, lo, hi in zip(p, *box))


def millimetre_point(p, prof) -> tuple[list[float], str] | None:
    """(the point in metres, where it lies) when the point ``p`` [m] lies outside the profile's workcell box (a
    gantry: its travel; no box: farther than :data:`FAR_M`) and the same numbers in millimetres lie inside; else None."""
    box = workcell_box(prof)
    mm = [c / 1000 for c in p]
    if not _inside(p, box) and _inside(mm, box):
        return mm, ("outside the workcell box" if box is not None else f"farther than {FAR_M:g} m")
    return None


def millimetre_height(h: float, prof) -> float | None:
    """How tall the workcell is [m] when the clearance ``h`` [m] is taller and ``h`` in millimetres is not; else None."""
    box = workcell_box(prof)
    tall = (box[1][2] - box[0][2]) if box is not None else TALL_M
    return tall if h > tall and h / 1000 <= tall else None
