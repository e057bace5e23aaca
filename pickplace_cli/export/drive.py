"""The drive's view of each joint (profile ``controller.joints``): names, zero offsets, signs and position units.

A :class:`DriveMap` turns the model's joint motion (q [rad or m] and its derivatives) into what each drive takes:
``d = sign · k · (q − offset)``, ``ḋ = sign · k · q̇``, ``d̈ = sign · k · q̈`` with ``k`` the unit's scale
(:func:`unit_scale`). Writers take it as ``drive=``: CSV columns ``<name>[<unit>]`` and ``<name>_vel[<unit>/s]``
(selected by name or by the sets ``drive``, ``drive_vel``, ``plc``: :func:`expand_columns`), JSON columns, MCAP
``JointState.name`` and a ``/drive_states`` channel. Without a ``controller.joints`` section the sets name the model's
own columns (``drive`` = q1 … qn, ``drive_vel`` = qd1 … qdn).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..model.errors import ProfileError

#: the column sets ``--columns`` expands (besides names and globs)
COLUMN_SETS = ("plc", "drive", "drive_vel")


def unit_scale(unit: str, kind: str, gear_ratio: float | None, counts_per_rev: int | None) -> tuple[float, str]:
    """(k, label) of a drive position unit: drive position = k · joint position (before sign and offset); ``kind``
    'revolute' (joint in rad) or 'linear' (m); ``gear_ratio`` N [rad of motor per rad or per m of the joint]."""
    if unit == "joint":
        return 1.0, "rad" if kind == "revolute" else "m"
    fixed = {"rad": (1.0, "rad"), "deg": (180.0 / math.pi, "deg"), "m": (1.0, "m"), "mm": (1000.0, "mm")}
    if unit in fixed:
        return fixed[unit]
    if gear_ratio is None:
        raise ProfileError(f"controller.joints unit = {unit!r}: needs the joint's drive (gear_ratio) in the profile")
    if unit == "motor_rad":
        return float(gear_ratio), "motor_rad"
    if unit == "motor_rev":
        return float(gear_ratio) / (2.0 * math.pi), "motor_rev"
    return float(gear_ratio) * float(counts_per_rev) / (2.0 * math.pi), "counts"


@dataclass(frozen=True)
class DriveMap:
    """Per joint: ``names``, header unit ``labels``, ``scale`` = sign · k and ``offset`` [rad or m]."""

    names: tuple[str, ...]
    labels: tuple[str, ...]
    scale: tuple[float, ...]
    offset: tuple[float, ...]
    units: tuple[str, ...] = ()  # the profile's unit names (joint, rad, deg, counts …)
    signs: tuple[int, ...] = ()

    def position(self, q: np.ndarray) -> np.ndarray:
        """Drive positions (N, n) of model joint positions ``q`` (N, n) [rad or m]."""
        return (np.asarray(q, float) - np.asarray(self.offset)) * np.asarray(self.scale)

    def rate(self, qd: np.ndarray) -> np.ndarray:
        """Drive velocities (or accelerations) of model joint velocities (accelerations) ``qd`` (N, n)."""
        return np.asarray(qd, float) * np.asarray(self.scale)

    def joint_position(self, d: np.ndarray) -> np.ndarray:
        """The model joint positions [rad or m] of drive positions ``d`` (the inverse of :meth:`position`)."""
        return np.asarray(d, float) / np.asarray(self.scale) + np.asarray(self.offset)

    @property
    def position_names(self) -> list[str]:
        return [f"{n}[{u}]" for n, u in zip(self.names, self.labels)]

    @property
    def velocity_names(self) -> list[str]:
        return [f"{n}_vel[{u}/s]" for n, u in zip(self.names, self.labels)]

    def columns(self, samples) -> tuple[list[str], np.ndarray]:
        """Header names and data (N, 2n) of ``samples``' drive positions then drive velocities."""
        jt = samples.joint
        if jt.q.shape[1] != len(self.names):
            raise ProfileError(f"controller.joints: {len(self.names)} entries for a trajectory of {jt.q.shape[1]} joints")
        return self.position_names + self.velocity_names, np.hstack([self.position(jt.q), self.rate(jt.qd)])

    def describe(self) -> list[dict]:
        """Per joint: name, unit, header label, sign, offset [rad or m] and scale (drive unit per rad or m)."""
        return [{"name": n, "unit": u, "label": lb, "sign": sg, "offset": o, "scale_per_joint_unit": abs(k)}
                for n, u, lb, sg, o, k in zip(self.names, self.units, self.labels, self.signs, self.offset, self.scale)]


def drive_map(profile) -> DriveMap | None:
    """The profile's :class:`DriveMap` (None without ``controller.joints``); ProfileError when it does not fit the
    robot (joint count, unit of the other kind, a motor unit without a drive)."""
    ctl = getattr(profile, "controller", None)
    if ctl is None or ctl.joints is None:
        return None
    from ..model.controller import fit_problem, joint_kinds

    problem = fit_problem(ctl, profile.robot)
    if problem is not None:
        path, value, rule = problem
        raise ProfileError(f"profile {profile.name}: {'.'.join(str(p) for p in path)} = {value!r}: {rule}")
    kinds = joint_kinds(profile.robot)
    specs = profile.robot.joint_specs()
    labels, scale = [], []
    for j, kind, spec in zip(ctl.joints, kinds, specs):
        k, label = unit_scale(j.unit, kind, spec.drive.gear_ratio if spec.drive else None, j.counts_per_rev)
        labels.append(label)
        scale.append(j.sign * k)
    return DriveMap(tuple(j.name for j in ctl.joints), tuple(labels), tuple(scale), tuple(j.offset for j in ctl.joints),
                    tuple(j.unit for j in ctl.joints), tuple(j.sign for j in ctl.joints))


def expand_columns(columns: tuple[str, ...], drive: DriveMap | None, n_joints: int) -> tuple[str, ...]:
    """``--columns`` with the sets ``plc`` (t and the drive positions), ``drive`` (drive positions) and ``drive_vel``
    (drive velocities) written out as column names; without a drive map the sets name q1 … qn and qd1 … qdn."""
    if drive is not None:
        pos, vel = list(drive.names), [f"{n}_vel" for n in drive.names]
    else:
        pos, vel = [f"q{i}" for i in range(1, n_joints + 1)], [f"qd{i}" for i in range(1, n_joints + 1)]
    out: list[str] = []
    for c in columns:
        out += {"plc": ["t", *pos], "drive": pos, "drive_vel": vel}.get(c, [c])
    return tuple(out)
