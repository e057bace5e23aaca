"""The rotary fourth axis: a translational robot (Delta, SCARA) that also turns the tool about the vertical.

Conventions (SI units: m, rad, s, kg, N·m)
-----------------------------------------
* The tool angle θ [rad] is measured about the base z axis (counter-clockwise seen from above), in the base
  frame. Joint q4 [rad] is the fourth axis; the tool angle is

      θ = ψ(q) + σ·q4,     ψ(q) = c·(q1, q2, q3)

  with σ = ±1 the axis's sign and ψ the angle of the body that carries the axis' output bearing:
  * **Delta** (c = 0): the motor sits on the base and drives the tool through a telescopic shaft with a
    universal joint at each end. The travelling plate never turns, so θ = σ·q4: the angle adds to no arm.
    Both ends of the shaft are vertical (the motor's axis and the tool's), so with the two yokes of the
    intermediate shaft in phase the double Cardan joint passes the angle on exactly (homokinetic): the model
    has no kinematic error to add. Only the intermediate tube turns unevenly (its speed ratio swings between
    cos β and 1/cos β for a shaft inclined β to the vertical: ±1.8 % at the Adept cycle's ends on the shipped
    Delta); its own inertia is counted as if it turned with q4, that fluctuation is neglected.
  * **SCARA** (c = (1, 1, 0)): J4 turns the spline shaft at the end of link 2, so θ = q1 + q2 + σ·q4. Holding
    the tool's angle while the arm swings therefore moves J4 (q4 = σ(θ − q1 − q2)): J4 counter-rotates.
* **Dynamics.** The axis turns J_t = shaft + tool + payload inertia about the tool axis (the masses are
  already in the translational model: the Delta's plate and payload, the SCARA's carried mass). Its kinetic
  energy ½·J_t·θ̇² with θ̇ = c·q̇ + σ·q̇4 (ψ is linear in q) adds to the Lagrangian of the base robot, so

      τ4 = σ·J_t·θ̈,       τ_i += c_i·J_t·θ̈   (i = 1, 2, 3),       no velocity-dependent term, no gravity

  For the SCARA this is the coupling both ways: J4's torque includes the arm's angular acceleration
  (θ̈ = q̈1 + q̈2 + σ q̈4), and J1 and J2 each carry J_t·θ̈, the reaction of J4's motor housing on link 2.
  For the Delta the axis is decoupled: the other motors see the rotating parts' mass (in the plate and
  payload) and nothing of their turning. The rotor of each motor is seen through its own joint only
  (motor torque = τ/(N·η) + J_rotor·N·q̈, as for every joint): the J4 rotor's share of the arm's rotation
  (J_rotor·(q̈1 + q̈2) on a SCARA) and its gyroscopic terms are neglected, as is any coupling of J4 with the
  z axis through a ball-screw spline.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np


def _rows(x: np.ndarray | None, n: int) -> np.ndarray:
    """(4, n) angle orders, zeros for None (the tool angle held at 0)."""
    if x is None:
        return np.zeros((4, n))
    x = np.asarray(x, float)
    if x.shape != (4, n):
        raise ValueError(f"angle must have shape (4, {n}) (θ, θ̇, θ̈, θ⃛ per sample), got {x.shape}")
    return x


@dataclass(frozen=True)
class RotaryAxisRobot:
    """``base`` (a 3-joint Delta or SCARA model) plus a rotary fourth joint q4 turning the tool (module docstring).

    ``inertia`` [kg·m²]: J_t, everything the axis turns about the tool axis; ``sign`` σ = ±1; ``carrier`` c, the
    tool angle's dependence on the base joints (Delta (0, 0, 0), SCARA (1, 1, 0)). Raises ValueError for a
    negative or non-finite inertia, a sign other than ±1, or a carrier of the wrong length."""

    base: Any
    inertia: float = 0.0
    sign: float = 1.0
    carrier: tuple[float, float, float] = (0.0, 0.0, 0.0)
    joint_names: tuple[str, ...] = field(init=False)
    joint_units: tuple[str, ...] = field(init=False)
    #: marks a model that takes the tool angle's law with the Cartesian motion (the motion model passes it)
    rotary = True

    def __post_init__(self) -> None:
        if not (math.isfinite(self.inertia) and self.inertia >= 0.0):
            raise ValueError(f"RotaryAxisRobot.inertia = {self.inertia!r} is not physical: must be finite and >= 0")
        if self.sign not in (1.0, -1.0):
            raise ValueError(f"RotaryAxisRobot.sign = {self.sign!r}: must be +1 or -1")
        if len(self.carrier) != len(self.base.joint_names):
            raise ValueError(f"RotaryAxisRobot.carrier = {self.carrier!r}: one weight per base joint")
        object.__setattr__(self, "joint_names", (*self.base.joint_names, f"q{len(self.base.joint_names) + 1}"))
        object.__setattr__(self, "joint_units", (*self.base.joint_units, "rad"))

    @property
    def angle_weights(self) -> tuple[float, ...]:
        """w with θ = q·w (q (N, 4)): the carrier's weights and σ."""
        return (*map(float, self.carrier), float(self.sign))

    @property
    def _c(self) -> np.ndarray:
        return np.asarray(self.carrier, float)

    def __getattr__(self, name: str):  # the base model's own helpers (geometry, lumped masses, reachable …)
        if name.startswith("__") or name == "base":
            raise AttributeError(name)
        return getattr(self.base, name)

    # ------------------------------------------------------------------ kinematics
    def tool_angle(self, q: np.ndarray) -> np.ndarray:
        """θ (N,) [rad] for joint positions q (N, 4): c·q[:3] + σ·q4."""
        q = np.asarray(q, float)
        return q[:, :3] @ self._c + self.sign * q[:, 3]

    def inverse_kinematics(self, p: np.ndarray, angle: np.ndarray | None = None) -> np.ndarray:
        """q (N, 4) for tool positions p (N, 3) [m] and tool angles ``angle`` (N,) [rad] (None: θ = 0)."""
        q = self.base.inverse_kinematics(p)
        theta = np.zeros(len(q)) if angle is None else np.broadcast_to(np.asarray(angle, float), (len(q),))
        return np.column_stack([q, self.sign * (theta - q @ self._c)])

    def forward_kinematics(self, q: np.ndarray) -> np.ndarray:
        """Tool positions p (N, 3) [m] for q (N, 4) (the tool angle: :meth:`tool_angle`)."""
        return self.base.forward_kinematics(np.asarray(q, float)[:, :3])

    def singularity_measure(self, q: np.ndarray, p: np.ndarray | None = None) -> np.ndarray:
        """The base robot's measure (N,): the fourth axis adds no singularity."""
        return self.base.singularity_measure(np.asarray(q, float)[:, :3], p)

    def joint_motion(self, p, v, a, j, angle: np.ndarray | None = None):
        """q, q̇, q̈, q⃛ (each (N, 4)) from the tool motion p, v, a, j (each (N, 3)) and the tool angle's
        θ, θ̇, θ̈, θ⃛ ``angle`` (4, N) (None: θ ≡ 0): the base robot's joints, and q4⁽ᵏ⁾ = σ(θ⁽ᵏ⁾ − c·q⁽ᵏ⁾)."""
        base = self.base.joint_motion(p, v, a, j)
        th = _rows(angle, len(base[0]))
        return tuple(np.column_stack([b, self.sign * (th[k] - b @ self._c)]) for k, b in enumerate(base))

    # ------------------------------------------------------------------ dynamics
    def _couple(self, base_torque: np.ndarray, accel: np.ndarray) -> np.ndarray:
        """(N, 4): the base robot's torques plus J_t·θ̈·c, and τ4 = σ·J_t·θ̈ (``accel`` = θ̈ (N,), or θ⃛ for rates)."""
        load = self.inertia * accel
        return np.column_stack([base_torque + load[:, None] * self._c, self.sign * load])

    def inverse_dynamics(self, q, qd, qdd, p, a) -> np.ndarray:
        """Joint torques (N, 4) [N·m (N for a prismatic joint)], gravity included: the base robot's plus the
        turning inertia's (module docstring), θ̈ = c·q̈[:3] + σ·q̈4 from ``qdd`` itself."""
        q, qd, qdd = (np.asarray(x, float) for x in (q, qd, qdd))
        base = self.base.inverse_dynamics(q[:, :3], qd[:, :3], qdd[:, :3], p, a)
        return self._couple(base, self.tool_angle(qdd))

    def torque_rate(self, q, qd, qdd, qddd, p=None, v=None, a=None, j=None) -> tuple[np.ndarray, np.ndarray]:
        """(dA, dG), each (N, 4): the base robot's and J_t·θ⃛ through the same coupling (gravity: none)."""
        q, qd, qdd, qddd = (np.asarray(x, float) for x in (q, qd, qdd, qddd))
        dA, dG = self.base.torque_rate(q[:, :3], qd[:, :3], qdd[:, :3], qddd[:, :3], p, v, a, j)
        return self._couple(dA, self.tool_angle(qddd)), np.column_stack([dG, np.zeros(len(dG))])

    def motion_and_dynamics(self, p, v, a, j, rates: bool = True, angle: np.ndarray | None = None,
                            singularity: bool = True) -> tuple:
        """(q, q̇, q̈, q⃛, A, G, dA, dG, μ) as the Delta's one-pass method gives them (each (N, 4) but μ (N,);
        dA, dG None unless ``rates``; μ None unless ``singularity``), with the tool angle's orders ``angle``
        (4, N) (None: θ ≡ 0)."""
        base = self.base
        if hasattr(base, "motion_and_dynamics"):
            q, qd, qdd, qddd, A, G, dA, dG, sing = base.motion_and_dynamics(p, v, a, j, rates=rates)
        else:
            q, qd, qdd, qddd = base.joint_motion(p, v, a, j)
            zeros = np.zeros_like(q)
            G = base.inverse_dynamics(q, zeros, zeros, p, np.zeros_like(a))
            A = base.inverse_dynamics(q, qd, qdd, p, a) - G
            dA, dG = base.torque_rate(q, qd, qdd, qddd, p, v, a, j) if rates else (None, None)
            sing = base.singularity_measure(q, p) if singularity else None
        th = _rows(angle, len(q))
        c, s = self._c, self.sign
        joints = [np.column_stack([x, s * (th[k] - x @ c)]) for k, x in enumerate((q, qd, qdd, qddd))]
        A4 = self._couple(A, th[2])
        G4 = np.column_stack([G, np.zeros(len(G))])
        dA4 = dG4 = None
        if rates:
            dA4 = self._couple(dA, th[3])
            dG4 = np.column_stack([dG, np.zeros(len(dG))])
        return (*joints, A4, G4, dA4, dG4, sing if singularity else None)

    def kinetic_energy(self, q, qd, v=None) -> np.ndarray:
        """KE (N,) [J]: the base robot's plus ½·J_t·θ̇²."""
        q, qd = np.asarray(q, float), np.asarray(qd, float)
        return self.base.kinetic_energy(q[:, :3], qd[:, :3], v) + 0.5 * self.inertia * self.tool_angle(qd) ** 2

    def potential_energy(self, q, p=None) -> np.ndarray:
        """PE (N,) [J]: the base robot's (the axis turns about the vertical: no gravity)."""
        return self.base.potential_energy(np.asarray(q, float)[:, :3], p)
