"""The profile's ``controller`` section: the controller's cycle and the drive's view of each joint.

```yaml
controller:
  cycle: 0.001              # s: every output step is one cycle (plan --cycle overrides; optional)
  joints:                   # one entry per joint, in the robot's joint order (optional)
    - {name: A1, unit: counts, counts_per_rev: 1048576, sign: -1, offset: 0.05}
```

The drive position of a joint is ``sign · k · (q − offset)``: ``q`` the model's joint position [rad or m],
``offset`` the model position [rad or m] at which the drive reads zero, ``sign`` +1 or −1 (the drive counts the
other way), ``k`` the unit's scale (:data:`UNITS`; ``motor_*`` and ``counts`` through the drive's gear ratio N, in
rad per rad or rad per m). Velocities and accelerations scale by ``sign · k``.
"""

from __future__ import annotations

import re
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from .iec import st_identifier_problem
from .numbers import Num, OptInt, OptNum

#: drive position units → (joint kinds it applies to, what it is)
UNITS: dict[str, tuple[tuple[str, ...], str]] = {
    "joint": (("revolute", "linear"), "the model's own unit: rad (revolute) or m (linear)"),
    "rad": (("revolute",), "joint angle in rad"),
    "deg": (("revolute",), "joint angle in degrees"),
    "m": (("linear",), "axis position in m"),
    "mm": (("linear",), "axis position in mm"),
    "motor_rad": (("revolute", "linear"), "motor angle in rad (gear ratio N × the joint's position)"),
    "motor_rev": (("revolute", "linear"), "motor revolutions (N / 2π × the joint's position)"),
    "counts": (("revolute", "linear"), "encoder counts on the motor (counts_per_rev × N / 2π × the joint's position)"),
}

#: column names and column sets of a trajectory CSV a joint name must not shadow (lower case)
_TAKEN = {"t", "x", "y", "z", "move", "drive", "drive_vel", "plc", "all"} | {f"{k}{c}" for k in "vaj" for c in "xyz"}
_TAKEN_PATTERN = re.compile(r"(q|qd|qdd|torque|motor_speed|motor_torque)\d+\Z")


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


class DriveJoint(_Model):
    """How one joint's drive sees it: name, zero, direction and position unit."""

    name: str = Field(min_length=1, max_length=32, description="Joint name in CSV headers, JSON, MCAP JointState.name "
                      "and Structured Text (an IEC 61131-3 identifier, not a keyword or standard function)")
    unit: Literal["joint", "rad", "deg", "m", "mm", "motor_rad", "motor_rev", "counts"] = Field(
        default="joint", description="Drive position unit: joint (rad or m, as the model), rad, deg (revolute), m, mm "
        "(linear), motor_rad, motor_rev, counts (through the drive's gear_ratio; counts need counts_per_rev)")
    sign: Literal[1, -1] = Field(default=1, description="+1: the drive counts with the model's joint; -1: against it")
    offset: Num = Field(default=0.0, description="The model joint position in rad (revolute) or m (linear) at which "
                          "the drive reads zero")
    counts_per_rev: OptInt = Field(default=None, gt=0, le=2**40, description="Encoder counts per motor "
                                       "revolution (unit counts only; at most 2^40), e.g. 1048576 for a 20-bit encoder")

    @field_validator("name")
    @classmethod
    def _identifier(cls, name: str) -> str:
        problem = st_identifier_problem(name)
        if problem:
            raise ValueError(problem)
        low = name.lower()
        if low in _TAKEN or _TAKEN_PATTERN.match(low):
            raise ValueError("is a column name or column set of the trajectory CSV (t, x, q1, qd1, torque1, drive, "
                             "plc …); give the joint another name, e.g. A1")
        return name

    @model_validator(mode="after")
    def _counts(self) -> "DriveJoint":
        if self.unit == "counts" and self.counts_per_rev is None:
            raise ValueError("unit counts needs counts_per_rev (encoder counts per motor revolution, > 0)")
        if self.unit != "counts" and self.counts_per_rev is not None:
            raise ValueError(f"counts_per_rev applies to unit counts only (this joint's unit is {self.unit})")
        return self


class Controller(_Model):
    """The controller the trajectory is for: its cycle and each joint's drive view (both optional)."""

    cycle: OptNum = Field(default=None, gt=0, le=1.0, description="Controller cycle in s (e.g. 0.001): the "
                                "duration and dwell are rounded up to whole cycles and every output step is one cycle")
    joints: tuple[DriveJoint, ...] | None = Field(default=None, description="One entry per joint, in the robot's "
                                                  "joint order: name, unit, sign, offset [rad or m]")

    @model_validator(mode="after")
    def _distinct(self) -> "Controller":
        if self.joints is not None:
            seen: dict[str, int] = {}
            for i, j in enumerate(self.joints):
                low = j.name.lower()
                if low in seen:
                    raise ValueError(f"joints.{i}.name = {j.name!r} repeats joints.{seen[low]}.name (names must be "
                                     "distinct, case-insensitively: Structured Text does not tell A1 from a1)")
                seen[low] = i
            names = set(seen)
            for j in self.joints:
                if f"{j.name.lower()}_vel" in names:
                    raise ValueError(f"joint name {j.name}_vel is the velocity column of joint {j.name}; rename it")
        return self


def joint_kinds(robot) -> tuple[str, ...]:
    """'revolute' or 'linear' per joint of a profile's robot section (a 4th axis is a rotary one)."""
    own = getattr(robot, "joint_kinds", None)
    if callable(own):
        return tuple(own())
    n = len(robot.joint_specs())
    if robot.kind == "gantry":
        return ("linear",) * n
    if robot.kind == "scara":
        return ("revolute", "revolute", "linear") + ("revolute",) * (n - 3)
    return ("revolute",) * n


def fit_problem(controller: Controller, robot) -> tuple[tuple, object, str] | None:
    """The first way ``controller.joints`` does not fit the profile's ``robot``: (path in the profile, the value,
    the rule), or None. A joint count that differs, a unit for the other kind of joint, a motor unit on a joint
    without a drive."""
    joints = controller.joints
    if joints is None:
        return None
    kinds = joint_kinds(robot)
    specs = robot.joint_specs()
    if len(joints) != len(kinds):
        return ("controller", "joints"), f"{len(joints)} entries", f"needs one entry per joint of this robot ({len(kinds)})"
    for i, (j, kind, spec) in enumerate(zip(joints, kinds, specs)):
        allowed = UNITS[j.unit][0]
        if kind not in allowed:
            fits = ", ".join(u for u, (ks, _) in UNITS.items() if kind in ks)
            return (("controller", "joints", i, "unit"), j.unit,
                    f"joint {i + 1} is {kind} ({'rad' if kind == 'revolute' else 'm'}); its units are {fits}")
        if j.unit.startswith("motor_") or j.unit == "counts":
            if spec.drive is None:
                return (("controller", "joints", i, "unit"), j.unit,
                        f"joint {i + 1} has no drive (gear ratio) in the profile; use {'rad or deg' if kind == 'revolute' else 'm or mm'}")
    return None
