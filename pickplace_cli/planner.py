"""plan(task, profile, options) → Plan: the one entry point the CLI and the tests use.

Pipeline [DESIGN §1]: Task + method → CartesianPath → choose_duration → CartesianTrajectory → samples
→ robot.joint_motion / inverse_dynamics → JointTrajectory.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .errors import UnreachableError
from .methods import Method, plan_path
from .profile import Profile
from .robots import build_robot
from .task import Task
from .timing import Duration, choose_duration
from .trajectory import CartesianTrajectory, JointTrajectory


@dataclass(frozen=True)
class PlanOptions:
    """What to plan beyond the task: method and its parameters, duration spec, sample rate [Hz]."""

    method: Method | str = Method.bspline
    method_params: dict[str, Any] = field(default_factory=dict)
    time: str | float = "auto"
    rate: float | None = None  # Hz; None → profile.planning.rate


@dataclass(frozen=True)
class Plan:
    """Everything one planned move produced (immutable)."""

    task: Task
    method: str
    parameters: dict[str, Any]
    duration: Duration
    cartesian: CartesianTrajectory
    t: np.ndarray  # (N,) s
    p: np.ndarray  # (N, 3) m
    v: np.ndarray  # (N, 3) m/s
    a: np.ndarray  # (N, 3) m/s²
    j: np.ndarray  # (N, 3) m/s³
    joint: JointTrajectory
    profile_name: str

    def summary(self) -> dict[str, Any]:
        """Scalars for reports and --format json (SI units, keys name the unit)."""
        vpk, apk, jpk = self.cartesian.peaks()
        T = self.duration.seconds
        return {
            "profile": self.profile_name,
            "method": self.method,
            "parameters": {k: v for k, v in self.parameters.items()},
            "from_m": self.task.p_from.tolist(),
            "to_m": self.task.p_to.tolist(),
            "height_m": self.task.height,
            "eta": self.task.eta,
            "b_m": self.task.b,
            "lambda": self.task.lam,
            **self.duration.as_dict(),
            "samples": int(len(self.t)),
            "peak_speed_m_s": vpk,
            "peak_acceleration_m_s2": apk,
            "peak_jerk_m_s3": jpk,
            "cycle_time_one_way_s": T,
        }


def plan(task: Task, profile: Profile, options: PlanOptions = PlanOptions()) -> Plan:
    """Plan ``task`` on ``profile``: path, duration, samples, joint motion."""
    path = plan_path(task, options.method, **options.method_params)
    duration = choose_duration(path, profile.capacity, options.time)
    traj = CartesianTrajectory(path, duration.seconds)
    rate = options.rate if options.rate is not None else profile.planning.rate
    t = traj.sample_times(rate)
    p, v, a, j = (traj(t, k) for k in range(4))
    robot = build_robot(profile.robot)
    try:
        q, qd, qdd, qddd = robot.joint_motion(p, v, a, j)
    except UnreachableError as exc:
        if exc.index is None:
            raise
        raise UnreachableError(f"{exc} at t = {t[exc.index]:.6g} s", index=exc.index) from None
    torque = robot.inverse_dynamics(q, qd, qdd, p, a)
    joint = JointTrajectory(t, q, qd, qdd, qddd, robot.joint_names, robot.joint_units, torque)
    return Plan(task, path.method, dict(path.parameters), duration, traj, t, p, v, a, j, joint, profile.name)
