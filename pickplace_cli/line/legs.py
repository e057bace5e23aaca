"""What a line robot's plan is made of: its state between parts, the legs of a cycle, a cycle, and a refusal."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .moves import Solved


@dataclass(frozen=True)
class RobotState:
    """Where the robot is from ``t_free`` [s] on: ``position`` [m, robot frame], ``velocity`` [m/s] (zero at
    rest; an outgoing belt's after a place on it)."""

    position: np.ndarray
    velocity: np.ndarray
    t_free: float
    angle: float = 0.0  #: the tool's angle about the base z axis [rad] (a rotary fourth axis; else 0)

    @property
    def moving(self) -> bool:
        return bool(np.any(self.velocity != 0.0))


@dataclass
class Leg:
    """One segment of a robot's sequence: ``kind`` (pick, track, place, release, stop), its start ``t0`` [s, line
    clock] and ``duration`` [s]; ``solved`` (the B-spline move; None for a track/release leg, which is
    ``point`` + ``velocity``·t); the exact ∫ motor torque² dt per motor over the leg [N²·m²·s]; the use of every
    limit (in the order of the robot's ``use_keys``: (joint, quantity)); the motor torque at its end [N·m];
    ``exact``: checked by the exact limit check."""

    kind: str
    t0: float
    duration: float
    solved: Solved | None = None
    point: np.ndarray | None = None
    velocity: np.ndarray | None = None
    integral: np.ndarray | None = None
    use: np.ndarray | None = None
    end_torque: np.ndarray | None = None
    exact: bool = False
    theta: float = 0.0  #: the tool angle [rad] of a track or release leg (held)

    @property
    def end_angle(self) -> float:
        """The tool angle at the leg's end [rad]."""
        return self.solved.move.theta_end if self.solved is not None else self.theta

    def angle_orders(self, tau) -> np.ndarray:
        """θ, θ′, θ″, θ‴ (4, N) of the tool angle over the leg at τ [rad/1^k]."""
        if self.solved is not None:
            return self.solved.move.angle_orders(tau)
        out = np.zeros((4, len(tau)))
        out[0] = self.theta
        return out

    @property
    def t1(self) -> float:
        return self.t0 + self.duration

    @property
    def end(self) -> np.ndarray:
        if self.solved is not None:
            return self.solved.end
        return self.point + self.velocity * self.duration


@dataclass
class Cycle:
    """A part taken: the legs (a stop first when the robot had to come to rest), the meeting (time, point in
    the robot's frame and in the line's), the place target, and the robot's state after."""

    legs: list
    t_start: float
    t_meet: float
    meet_robot: np.ndarray
    meet_line: np.ndarray
    target: int
    place_point: np.ndarray
    state: RobotState
    waited: bool = False

    @property
    def pick(self) -> Leg:
        return next(leg for leg in self.legs if leg.kind == "pick")

    @property
    def t_placed(self) -> float:
        return next(leg for leg in self.legs if leg.kind == "place").t1

    @property
    def t_free(self) -> float:
        return self.state.t_free


@dataclass(frozen=True)
class Decline:
    """Why a robot does not take a part: ``reason`` (one line; computed when first read) and the exit code it
    would be (4: cannot meet it in the window or a point is out of reach; 3: a limit; 1: no plan)."""

    why: object
    code: int = 4
    place: bool = False  #: no place move to the target (a pocket on an outgoing belt: the next one may do)

    @property
    def reason(self) -> str:
        return self.why if isinstance(self.why, str) else str(self.why)

    @property
    def short(self) -> str:
        """The reason without the costly details (for a part another robot took)."""
        return self.why if isinstance(self.why, str) else self.why.short()
