"""Robot/workcell profiles: YAML validated by pydantic (unknown keys rejected, SI units everywhere).

``load_profile(path)`` returns a frozen :class:`Profile`; every problem is a :class:`ProfileError` with a
one-line message ``FILE:LINE: FIELD = VALUE: RULE``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any, Literal, Union, get_origin

from pydantic import BaseModel, ConfigDict, Field, PrivateAttr, ValidationError, model_validator

from .controller import Controller
from .errors import ProfileError
from .numbers import NUMBER, Num, OptNum
from .yamlsafe import PROFILE_MAX_BYTES, _prune_union_branches, _show, _yaml_with_lines, locate

DEFAULT_PROFILE = "delta-su2018"


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


class JointLimits(_Model):
    """Kinematic limits of one joint. Units follow the joint: rad (revolute) or m (prismatic)."""

    position: tuple[Num, Num] | None = Field(
        default=None, description="Joint range [min, max] in rad or m (None: not limited; gantry: the axis travel)"
    )
    velocity: OptNum = Field(default=None, gt=0, description="Max |joint velocity| in rad/s or m/s")
    acceleration: OptNum = Field(default=None, gt=0, description="Max |joint acceleration| in rad/s² or m/s²")
    jerk: OptNum = Field(default=None, gt=0, description="Max |joint jerk| in rad/s³ or m/s³ (optional)")

    @model_validator(mode="after")
    def _ordered(self) -> "JointLimits":
        if self.position is not None and not self.position[0] < self.position[1]:
            raise ValueError(f"position must be [min, max] with min < max, got {list(self.position)}")
        return self


class Drive(_Model):
    """Motor + gearbox of one joint. Motor speed = N·q̇; motor torque = torque/(N·efficiency) + J_rotor·N·q̈."""

    gear_ratio: Num = Field(gt=0, description="N: motor angle per joint unit (rad/rad, or rad/m for a linear axis)")
    efficiency: Num = Field(default=1.0, gt=0, le=1, description="Gearbox efficiency (0, 1]")
    rotor_inertia: Num = Field(default=0.0, ge=0, description="Rotor (+ gearbox input) inertia in kg·m², motor side")
    rated_torque: OptNum = Field(default=None, gt=0, description="Continuous (rated) motor torque in N·m; limits the RMS over the duty cycle")
    peak_torque: OptNum = Field(default=None, gt=0, description="Peak motor torque in N·m")
    max_speed: OptNum = Field(default=None, gt=0, description="Max motor speed in rad/s (6000 rpm = 628.3 rad/s)")
    torque_rate: OptNum = Field(default=None, gt=0, description="Max |d(motor torque)/dt| in N·m/s (Yang 2022 Eq. 38)")

    @model_validator(mode="after")
    def _rated_within_peak(self) -> "Drive":
        if self.rated_torque is not None and self.peak_torque is not None and self.rated_torque > self.peak_torque:
            raise ValueError(
                f"rated_torque = {self.rated_torque:g} N·m is above peak_torque = {self.peak_torque:g} N·m: a drive's "
                "continuous (RMS) rating cannot exceed its peak torque"
            )
        return self


class JointSpec(_Model):
    """Limits and drive of one joint."""

    limits: JointLimits = Field(default_factory=JointLimits, description="Kinematic limits (joint side)")
    drive: Drive | None = Field(default=None, description="Motor and gearbox (None: no motor limits checked)")


JointSpecs = Union[JointSpec, list[JointSpec]]


def _per_joint(specs: "JointSpec | list[JointSpec]", n: int) -> list[JointSpec]:
    if isinstance(specs, JointSpec):
        return [specs] * n
    if len(specs) != n:
        raise ValueError(f"joints: give one entry for all joints or exactly {n}, got {len(specs)}")
    return list(specs)


class GantryAxis(_Model):
    """One Cartesian axis of a gantry; joint q_i is the tool coordinate along that axis."""

    name: Literal["x", "y", "z"] = Field(description="Cartesian axis this joint drives")
    travel: tuple[Num, Num] = Field(description="Joint travel [min, max] in m (base frame)")
    mass: Num = Field(default=0.0, ge=0.0, description="Mass moved by this axis in kg")
    limits: JointLimits = Field(default_factory=JointLimits, description="Velocity/acceleration/jerk limits (m/s, m/s², m/s³)")
    drive: Drive | None = Field(default=None, description="Motor and gearbox; gear_ratio in rad/m (2π / lead)")

    @model_validator(mode="after")
    def _travel_ordered(self) -> "GantryAxis":
        if not self.travel[0] < self.travel[1]:
            raise ValueError(f"travel must be [min, max] with min < max, got {list(self.travel)}")
        return self


class GantryModel(_Model):
    """Cartesian gantry: joints are x, y, z (identity kinematics); gravity acts on z."""

    kind: Literal["gantry"]
    axes: tuple[GantryAxis, GantryAxis, GantryAxis] = Field(description="The x, y and z axes, in that order")
    payload: Num = Field(default=0.0, ge=0, description="Payload in kg (added to every axis' moved mass)")

    @model_validator(mode="after")
    def _xyz(self) -> "GantryModel":
        names = [a.name for a in self.axes]
        if names != ["x", "y", "z"]:
            raise ValueError(f"axes must be x, y, z in that order, got {names}")
        return self

    def joint_specs(self) -> list[JointSpec]:
        return [
            JointSpec(limits=a.limits.model_copy(update={"position": a.travel}), drive=a.drive) for a in self.axes
        ]


class DeltaGeometry(_Model):
    R: float = Field(gt=0, description="Fixed platform radius: centre to motor axis, in m")
    r: Num = Field(gt=0, description="Moving platform radius: centre to forearm joint line, in m")
    L: float = Field(gt=0, description="Upper arm length, motor axis to elbow, in m")
    l: Num = Field(gt=0, description="Forearm (parallelogram) length, elbow to platform, in m")  # noqa: E741

    @model_validator(mode="after")
    def _physical(self) -> "DeltaGeometry":
        if not self.l > self.L:
            raise ValueError(f"forearm l = {self.l} m must be longer than the upper arm L = {self.L} m (Clavel Delta)")
        if not self.R > self.r:
            raise ValueError(f"fixed platform R = {self.R} m must be larger than the moving platform r = {self.r} m")
        return self


class DeltaMasses(_Model):
    upper_arm: Num = Field(ge=0, description="Upper arm mass in kg")
    upper_arm_inertia: Num = Field(ge=0, description="Upper arm inertia about the motor axis in kg·m²")
    upper_arm_com: Num = Field(ge=0, description="Distance of the upper arm's centre of mass from the motor axis in m")
    elbow: Num = Field(default=0.0, ge=0, description="Mass lumped at each elbow in kg")
    forearm_pair: Num = Field(ge=0, description="Mass of one forearm pair (both rods with their end fittings) in kg")
    forearm_end_elbow: Num = Field(default=0.0, ge=0, description="Mass of one pair's end fittings at the elbow "
                                     "(ball cups, springs), in kg; part of forearm_pair")
    forearm_end_plate: Num = Field(default=0.0, ge=0, description="Mass of one pair's end fittings at the plate, "
                                     "in kg; part of forearm_pair")
    forearm_rod_inertia: OptNum = Field(default=None, ge=0, description="Moment of inertia of one pair's rods "
                                              "(without the end fittings) about their own centre of mass, "
                                              "perpendicular to the rods, in kg·m²; default: uniform rods, "
                                              "m_rod·l²/12 with m_rod = forearm_pair minus the end fittings")
    plate: Num = Field(ge=0, description="Travelling plate mass in kg (tool included)")

    @model_validator(mode="after")
    def _fittings(self) -> "DeltaMasses":
        ends = self.forearm_end_elbow + self.forearm_end_plate
        if ends > self.forearm_pair:
            raise ValueError(f"forearm_end_elbow + forearm_end_plate = {ends:g} kg is more than forearm_pair = "
                             f"{self.forearm_pair:g} kg: the end fittings are part of the pair")
        return self


class RotaryAxis(_Model):
    """The fourth axis: turns the tool about the vertical (a Delta's rotary axis on the base, driving the tool
    through a telescopic shaft with a universal joint at each end; a SCARA's J4 spline shaft at the end of link 2).
    Tool angle θ (rad, about the base z axis) = sign·q4 on a Delta, q1 + q2 + sign·q4 on a SCARA."""

    sign: Literal[1, -1] = Field(default=1, description="Direction of q4 [1]: +1 when a positive q4 turns the tool "
                                 "counter-clockwise seen from above, -1 when clockwise")
    shaft_inertia: Num = Field(default=0.0, ge=0, description="Inertia of the shaft the axis turns (telescopic or "
                                 "spline shaft) about its axis, in kg·m²")
    tool_inertia: Num = Field(default=0.0, ge=0, description="Inertia of the tool (gripper, flange) about the tool "
                                "axis, in kg·m²")
    payload_inertia: Num = Field(default=0.0, ge=0, description="Inertia of the payload about the tool axis, in "
                                   "kg·m² (its mass is robot.payload)")
    joint: JointSpec = Field(default_factory=JointSpec, description="Limits of q4 (rad, rad/s, …) and its drive "
                             "(motor + gearbox; gear_ratio in motor rad per tool rad)")

    @property
    def inertia(self) -> float:
        """J_t [kg·m²]: everything the axis turns about the tool axis."""
        return self.shaft_inertia + self.tool_inertia + self.payload_inertia


class _ThreeJoints(_Model):
    """A robot whose ``joints`` field is one JointSpec for all three joints or a list of three, with an optional
    rotary fourth axis (``rotary``: its spec follows the three)."""

    def joint_specs(self) -> list[JointSpec]:
        rotary = getattr(self, "rotary", None)
        return _per_joint(self.joints, 3) + ([rotary.joint] if rotary is not None else [])  # type: ignore[attr-defined]

    @model_validator(mode="after")
    def _count(self) -> "_ThreeJoints":
        _per_joint(self.joints, 3)  # type: ignore[attr-defined]
        return self


class DeltaModel(_ThreeJoints):
    """Clavel Delta robot: rigid-body dynamics (every parallelogram rod a rigid body), or the lumped-mass model
    of Codourey 1998 by name."""

    kind: Literal["delta"]
    geometry: DeltaGeometry
    masses: DeltaMasses
    dynamics: Literal["rigid", "lumped"] = Field(default="rigid", description="Dynamic model: rigid (each "
                                                 "parallelogram rod a rigid body that translates and turns, its end "
                                                 "fittings point masses; the default) or lumped (each pair's mass "
                                                 "split 2/3 to the elbow, 1/3 to the plate, as in the papers)")
    payload: Num = Field(default=0.0, ge=0, description="Payload in kg")
    singularity_margin: Num = Field(default=0.05, ge=0, lt=1, description="Minimum singularity measure (0 = singular, 1 = best)")
    joints: JointSpecs = Field(default_factory=JointSpec, description="One joint spec for all three arms, or a list of three")
    rotary: RotaryAxis | None = Field(default=None, description="The rotary fourth axis q4 on the base, turning the "
                                      "tool through a telescopic shaft (optional; without it the tool does not turn)")


class ScaraLink(_Model):
    length: Num = Field(gt=0, description="Link length in m")
    mass: Num = Field(default=0.0, ge=0, description="Link mass in kg")
    com: Num = Field(default=0.0, ge=0, description="Centre of mass from the proximal joint in m")
    inertia: Num = Field(default=0.0, ge=0, description="Inertia about its own centre of mass (vertical axis) in kg·m²")


class ScaraModel(_ThreeJoints):
    """Serial SCARA: two revolute links, a prismatic z axis (q3, m, positive up), optionally J4 (``rotary``)."""

    kind: Literal["scara"]
    link1: ScaraLink
    link2: ScaraLink
    elbow: Literal["left", "right"] = Field(default="right", description="Elbow branch: left = q2 > 0 (counter-clockwise seen from above)")
    z0: Num = Field(default=0.0, description="Tool height at q3 = 0 in m (base frame)")
    z_mass: Num = Field(default=0.0, ge=0, description="Mass moved by the z axis (quill + tool) in kg")
    payload: Num = Field(default=0.0, ge=0, description="Payload in kg")
    singularity_margin: Num = Field(default=0.05, ge=0, lt=1, description="Minimum |sin q2| (0 at full stretch or fold)")
    joints: JointSpecs = Field(default_factory=JointSpec, description="One joint spec for all joints, or a list of three (q1, q2 rad; q3 m)")
    rotary: RotaryAxis | None = Field(default=None, description="J4, the rotary fourth axis at the end of link 2 "
                                      "(optional; without it the tool's angle is held fixed)")


RobotModel = Annotated[Union[GantryModel, DeltaModel, ScaraModel], Field(discriminator="kind")]


class Box(_Model):
    """Axis-aligned box in the base frame, m."""

    min: tuple[Num, Num, Num] = Field(description="Lower corner x, y, z in m")
    max: tuple[Num, Num, Num] = Field(description="Upper corner x, y, z in m")

    @model_validator(mode="after")
    def _ordered(self) -> "Box":
        if not all(a < b for a, b in zip(self.min, self.max)):
            raise ValueError(f"min must be below max on every axis, got min={list(self.min)} max={list(self.max)}")
        return self


class Workcell(_Model):
    box: Box | None = Field(default=None, description="The tool must stay inside this box (optional)")
    conveyor_pick_velocity: tuple[Num, Num, Num] | None = Field(
        default=None,
        description="Velocity of the pick conveyor in m/s (base frame): the tool leaves the pick point with it "
        "(method bspline-vel, Yang 2022; --v-from overrides it)",
    )
    conveyor_place_velocity: tuple[Num, Num, Num] | None = Field(
        default=None,
        description="Velocity of the place conveyor in m/s (base frame): the tool arrives at the place point with "
        "it (method bspline-vel; --v-to overrides it)",
    )
    belt_window: Box | None = Field(
        default=None,
        description="Belt window in m (base frame), an axis-aligned box: where along the belt the robot may meet a "
        "part (plan --to-belt) and track it for the dwell; a rendezvous or tracking segment that would leave it is "
        "exit 4 (optional; without it the workspace alone bounds the rendezvous)",
    )

    @model_validator(mode="after")
    def _window_in_box(self) -> "Workcell":
        w, b = self.belt_window, self.box
        if w is not None and b is not None and not all(max(w.min[c], b.min[c]) < min(w.max[c], b.max[c]) for c in range(3)):
            raise ValueError(
                f"belt_window min={list(w.min)} max={list(w.max)} m does not intersect the workcell box "
                f"min={list(b.min)} max={list(b.max)} m: the robot could never work on the belt"
            )
        return self


class Capacity(_Model):
    """Cartesian movement capacity of the tool over the task workspace [Li2018, Eq. (24)–(25)]."""

    velocity: Num = Field(gt=0, description="[v]: allowed tool speed in m/s")
    acceleration: Num = Field(gt=0, description="[a]: allowed tool acceleration norm in m/s²")
    jerk: OptNum = Field(default=None, gt=0, description="[j]: allowed tool jerk norm in m/s³ (optional)")


class Planning(_Model):
    """Defaults for ``pickplace plan`` (each can be overridden on the command line)."""

    height: Num = Field(gt=0, description="Clearance of the path's midpoint above the higher end point, in m")
    eta: Num = Field(default=0.5, gt=0, lt=1, description="Lift-off/set-down ratio η (dimensionless, 0 < η < 1)")
    rate: Num = Field(default=1000.0, gt=0, le=1e6, description="Output sample rate in Hz")
    dwell: Num = Field(default=0.1, ge=0, description="Dwell at pick and at place in s (duty cycle: move, dwell, move back, dwell)")
    limit_use: Num = Field(
        default=1.0, gt=0, le=1, description="Limit-use fraction (headroom), dimensionless in (0, 1]: the default "
        "duration, fit, optimal and --optimize shape plan every timed limit (joint velocity, acceleration, jerk, "
        "motor speed, torque, torque rate, RMS torque, Cartesian capacity) to at most this fraction of its rating, "
        "and the limit check holds every plan to it (e.g. 0.9 keeps 10 % in reserve). Positions and the workcell "
        "are not scaled.",
    )


class Vibration(_Model):
    """One flexible mode per base-frame axis x, y, z, excited by the tool acceleration (residual vibration:
    ẍ + 2ζωẋ + ω²x = −a(t), ω = 2π·frequency; see ``pickplace_cli.studies.vibration``)."""

    frequency: tuple[Annotated[float, Field(gt=0), NUMBER], Annotated[float, Field(gt=0), NUMBER], Annotated[float, Field(gt=0), NUMBER]] = Field(
        description="Natural frequency f_n of the mode along x, y, z in Hz"
    )
    damping: tuple[Annotated[float, Field(ge=0, lt=1), NUMBER], Annotated[float, Field(ge=0, lt=1), NUMBER], Annotated[float, Field(ge=0, lt=1), NUMBER]] = Field(
        description="Damping ratio ζ of the mode along x, y, z (dimensionless, 0 <= ζ < 1)"
    )


class Profile(_Model):
    """A robot and its workcell."""

    name: str = Field(min_length=1, description="Short name of the profile")
    description: str = Field(default="", description="Free text: robot, sources of the numbers")
    robot: RobotModel = Field(description="The robot: its kind (delta, scara or gantry), geometry, masses, joints "
                              "and drives")
    capacity: Capacity = Field(description="The tool's Cartesian capacity [v] m/s, [a] m/s², [j] m/s³ (Li 2018 "
                               "Eq. 24-26)")
    planning: Planning = Field(description="Defaults of a plan: clearance height [m], η, sample rate [Hz], dwell "
                               "[s], limit use")
    workcell: Workcell = Field(default_factory=Workcell, description="Where the tool may go (box [m]), conveyor "
                               "velocities [m/s] and the belt window [m] (optional)")
    vibration: Vibration | None = Field(default=None, description="Flexible modes for the residual-vibration estimate (optional)")
    controller: Controller | None = Field(default=None, description="The controller's cycle [s] and each joint's drive "
                                          "view: name, unit, sign, offset (optional)")
    #: the limit-use fraction this profile's timed limits are scaled by (:func:`with_limit_use`; 1: as rated)
    _limit_use: float = PrivateAttr(default=1.0)
    _rated: Any = PrivateAttr(default=None)  # the profile as rated, when this one is scaled

    @property
    def limit_use(self) -> float:
        """The fraction of every timed limit's rating that this profile's limits are (1.0: as rated)."""
        return self._limit_use

    @property
    def rated(self) -> "Profile":
        """This profile with its limits as rated (itself when it is not scaled)."""
        return self if self._rated is None else self._rated


#: the JSON Schema dialect of :func:`profile_schema`
SCHEMA_DIALECT = "https://json-schema.org/draft/2020-12/schema"
#: the file name of the shipped schema, beside the shipped profiles
SCHEMA_FILE = "profile.schema.json"


def profile_schema() -> dict[str, Any]:
    """The JSON Schema of a profile file, generated from the pydantic models.

    A YAML language server (editors) validates and completes a profile against it: the shipped profiles name the
    copy shipped beside them, ``profile.schema.json``, in their first line,
    ``# yaml-language-server: $schema=profile.schema.json``.

    Returns
    -------
    dict
        A JSON Schema (draft 2020-12); every field's description names its unit.
    """
    schema = Profile.model_json_schema()
    return {"$schema": SCHEMA_DIALECT, **schema, "title": "pickplace profile"}


# --------------------------------------------------------------------------------------------- loading


def shipped_profiles() -> dict[str, Path]:
    """The profiles shipped with the package.

    Returns
    -------
    dict of str to pathlib.Path
        Each shipped profile's name and its file.
    """
    from .resources import data_dir

    root = data_dir("profiles")
    return {p.stem: p for p in sorted(root.glob("*.yaml"))}


def resolve_profile_path(name_or_path: str | Path | None) -> Path:
    """A path as given, or the shipped profile of that name (``gantry`` → profiles/gantry.yaml)."""
    if name_or_path is None:
        name_or_path = DEFAULT_PROFILE
    p = Path(name_or_path)
    if p.exists():
        return p
    shipped = shipped_profiles()
    if str(name_or_path) in shipped:
        return shipped[str(name_or_path)]
    names = ", ".join(shipped) or "none"
    raise ProfileError(f"profile {str(name_or_path)!r}: no such file, and no shipped profile of that name (shipped: {names})")


def _unwrap(ann: Any, node: Any) -> Any:
    """The model class or container type of annotation ``ann`` that validates ``node`` (picks the branch
    of a union by the node's shape and, for robots, its ``kind``)."""
    import types
    import typing

    while True:
        origin = typing.get_origin(ann)
        if origin is Annotated:
            ann = typing.get_args(ann)[0]
        elif origin is Union or origin is types.UnionType:
            options = [a for a in typing.get_args(ann) if a is not type(None)]
            pick = options[0]
            for a in options:
                o = typing.get_origin(a)
                if isinstance(node, (list, tuple)) and o in (list, tuple):
                    pick = a
                    break
                if isinstance(node, dict) and isinstance(a, type) and issubclass(a, BaseModel):
                    kind = a.model_fields.get("kind")
                    if kind is None or node.get("kind") in typing.get_args(kind.annotation):
                        pick = a
                        break
            ann = pick
        else:
            return ann


def _field_of(path: list, data: Any) -> tuple[Any, Any]:
    """(FieldInfo of the last key in ``path`` or None, the model class holding the last part or None)."""
    import typing

    ann: Any = Profile
    node: Any = data
    info = None
    holder = None
    for part in path:
        cur = _unwrap(ann, node)
        holder = cur if isinstance(cur, type) and issubclass(cur, BaseModel) else None
        if isinstance(part, str):
            if holder is None or part not in holder.model_fields:
                return info, holder
            info = holder.model_fields[part]
            ann = info.annotation
        else:
            args = typing.get_args(cur)
            if typing.get_origin(cur) is list and args:
                ann = args[0]
            elif typing.get_origin(cur) is tuple and args:
                ann = args[0] if args[-1] is Ellipsis else (args[part] if part < len(args) else None)
            else:
                return info, None
        node = node[part] if isinstance(node, (dict, list, tuple)) and _has(node, part) else None
    return info, holder


def _has(node: Any, part: Any) -> bool:
    if isinstance(node, dict):
        return part in node
    return isinstance(part, int) and 0 <= part < len(node)


#: what a pydantic type error expects, in words
_EXPECTED = {
    "float_type": "a number", "float_parsing": "a number", "int_type": "a whole number", "int_parsing": "a whole number",
    "finite_number": "a finite number", "string_type": "text", "tuple_type": "a list [ … ]", "list_type": "a list [ … ]",
    "dict_type": "a mapping of keys", "model_type": "a mapping of keys", "model_attributes_type": "a mapping of keys",
}


def _describe(err: dict, data: Any, lines: dict[tuple, int], source: str, errors: list[dict]) -> str:
    """One line: ``FILE:LINE: FIELD = VALUE: RULE`` (FIELD a dotted path, list indices as numbers)."""
    real, node, where, field = locate(err, data, lines, source)
    info, holder = _field_of(real, data)
    about = ""
    if info is not None and info.description:
        d = info.description
        about = "; expected: " + (d[0].lower() + d[1:] if d[:2].istitle() and d[1:2].islower() else d)
    kind = err["type"]
    if kind == "extra_forbidden":
        known = f"; fields here: {', '.join(holder.model_fields)}" if holder is not None else ""
        guess = ""
        if holder is not None and real:
            import difflib

            close = difflib.get_close_matches(str(real[-1]), list(holder.model_fields), n=1, cutoff=0.6)
            guess = f": did you mean {close[0]!r}?" if close else ""
        return (f"{where}: unknown key {field!r}{guess or ': not a field of this section'} (check spelling; keys are "
                f"case-sensitive{known})")
    if kind == "missing" and real and isinstance(real[-1], int):
        # an element of a fixed-length list is absent: the list is too short
        parent = tuple(err["loc"])[:-1]
        absent = sum(1 for e in errors if e["type"] == "missing" and tuple(e["loc"])[:-1] == parent)
        given = err.get("input")
        n_given = len(given) if isinstance(given, (list, tuple)) else 0
        name = ".".join(str(p) for p in real[:-1])  # ``about`` is the list's field: an index is not a key
        return f"{where}: {name} = {_show(given)}: needs {n_given + absent} values, got {n_given}{about}"
    if kind == "missing":
        return f"{where}: {field}: required field is missing{about}"
    value = err.get("input")
    ctx = err.get("ctx") or {}
    if kind in ("too_long", "too_short"):
        n = ctx.get("max_length" if kind == "too_long" else "min_length")
        got = ctx.get("actual_length", len(value) if isinstance(value, (list, tuple)) else "?")
        return f"{where}: {field} = {_show(value)}: needs {n} values, got {got}{about}"
    if kind in _EXPECTED:
        what = _EXPECTED[kind]
        if isinstance(value, (list, tuple)) and not what.startswith("a list"):
            rule = f"must be {what}, not a list"
        elif isinstance(value, dict) and not what.startswith("a mapping"):
            rule = f"must be {what}, not a mapping"
        else:
            rule = f"must be {what}"
        return f"{where}: {field} = {_show(value)}: {rule}{about}"
    if kind == "union_tag_invalid":
        kind_line = lines.get(tuple(real) + ("kind",))  # the kind's own line where the document has one
        where = f"{source}:{kind_line}" if kind_line else where
        return f"{where}: {field}.kind = {_show(ctx.get('tag'))}: must be one of {ctx.get('expected_tags')}"
    msg = err["msg"].removeprefix("Value error, ")
    if kind == "value_error":
        if isinstance(value, dict):  # a rule across fields (a model validator): its message names the values
            return f"{where}: {field}: {msg}"
        return f"{where}: {field} = {_show(value)}: {msg}"
    return f"{where}: {field} = {_show(value)}: {msg}{about}"


def _reject_flags(node: Any, path: tuple, data: Any, lines: dict[tuple, int], source: str) -> None:
    """No field of a profile is a flag: YAML's true/false/yes/no/on/off would pass pydantic's lax mode as
    1.0/0.0 (or fail with a confusing message for text), so any of them is refused here, naming the field."""
    if isinstance(node, bool):
        info, _ = _field_of(list(path), data)
        what = "text (quote it)" if info is not None and (info.annotation is str or get_origin(info.annotation) is Literal) else "a number"
        field = ".".join(str(p) for p in path)
        where = f"{source}:{lines[path]}" if path in lines else source
        raise ProfileError(f"{where}: {field} = {_show(node)}: must be {what}, not a flag (YAML reads true/false/yes/no/on/off as one)")
    if isinstance(node, dict):
        for k, v in node.items():
            _reject_flags(v, path + (k,), data, lines, source)
    elif isinstance(node, list):
        for i, v in enumerate(node):
            _reject_flags(v, path + (i,), data, lines, source)


def parse_profile(text: str, source: str = "<profile>") -> Profile:
    """Validate a profile's YAML text.

    Parameters
    ----------
    text : str
        The YAML document (SI units).
    source : str
        The name the error messages give the text (a file name).

    Returns
    -------
    Profile
        The validated profile.

    Raises
    ------
    ProfileError
        As :func:`load_profile`.
    """
    data, lines = _yaml_with_lines(text, source)
    if not isinstance(data, dict):
        raise ProfileError(f"{source}: a profile must be a YAML mapping of keys (name, robot, capacity, planning)")
    _reject_flags(data, (), data, lines, source)
    try:
        profile = Profile.model_validate(data)
    except ValidationError as exc:
        errors = _prune_union_branches(exc.errors(), data)
        # every problem, one line each: unknown keys first (a misspelt key also makes its field "missing")
        errors.sort(key=lambda e: 0 if e["type"] == "extra_forbidden" else 1)
        described = list(dict.fromkeys(_describe(e, data, lines, source, errors) for e in errors))
        raise ProfileError("\n".join(described)) from None
    if profile.controller is not None:  # the drive view against the robot: joint count, kinds, drives
        from .controller import fit_problem

        problem = fit_problem(profile.controller, profile.robot)
        if problem is not None:
            path, value, rule = problem
            where = f"{source}:{lines[path]}" if path in lines else source
            raise ProfileError(f"{where}: {'.'.join(str(p) for p in path)} = {_show(value)}: {rule}")
    from .plausible import check_units

    check_units(profile, source)  # numbers in rpm, degrees, millimetres: refused or warned (model/plausible.py)
    return profile


def load_profile(name_or_path: str | Path | None = None) -> Profile:
    """Load and validate a profile.

    Parameters
    ----------
    name_or_path : str or pathlib.Path or None
        A YAML file, or the name of a shipped profile (:func:`shipped_profiles`); None: ``delta-su2018``. Every
        value in the file is in SI units (m, s, rad, kg, N·m).

    Returns
    -------
    Profile
        The validated, immutable profile.

    Raises
    ------
    ProfileError
        A missing, unreadable, unsafe or invalid file: one line per problem, ``FILE:LINE: FIELD = VALUE: RULE``.
    """
    path = resolve_profile_path(name_or_path)
    from .files import require_regular_file

    require_regular_file(str(path), "profile", ProfileError)  # a named pipe with no writer would block forever
    try:
        with open(path, "rb") as fh:  # bounded: a huge file is refused without reading it all
            raw = fh.read(PROFILE_MAX_BYTES + 1)
        if len(raw) > PROFILE_MAX_BYTES:
            raise ProfileError(f"{path}: larger than {PROFILE_MAX_BYTES} bytes (1 MiB); a profile is a few kB: is "
                               "this the right file?")
        if b"\0" in raw:
            from .text import utf16_hint

            raise ProfileError(f"{path}: a binary file (NUL bytes), not a YAML profile{utf16_hint(raw, csv=False)}")
        text = raw.decode("utf-8")
    except OSError as exc:
        raise ProfileError(f"{path}: cannot read profile: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise ProfileError(f"{path}: not a text (UTF-8) file") from None
    return parse_profile(text, str(path))
