"""The Robot protocol every model implements (SI units: m, rad, s, kg, N, N·m)."""

from __future__ import annotations

from typing import Protocol

import numpy as np


class Robot(Protocol):
    """Kinematic + dynamic model of one robot kind.

    Arrays: positions ``p`` are (N, 3) in the base frame [m]; joint arrays are (N, n_joints).
    """

    #: joint names, e.g. ("q1", "q2", "q3") — used for CSV columns q<i> and messages
    joint_names: tuple[str, ...]
    #: "m" (prismatic) or "rad" (revolute), one per joint
    joint_units: tuple[str, ...]

    def inverse_kinematics(self, p: np.ndarray) -> np.ndarray:
        """Joint positions (N, n) for tool positions p (N, 3); raises UnreachableError naming the first bad sample."""
        ...

    def forward_kinematics(self, q: np.ndarray) -> np.ndarray:
        """Tool positions (N, 3) for joint positions q (N, n)."""
        ...

    def joint_motion(
        self, p: np.ndarray, v: np.ndarray, a: np.ndarray, j: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """q, q̇, q̈, q⃛ (each (N, n)) from Cartesian p, v, a, j (each (N, 3)), analytically."""
        ...

    def inverse_dynamics(
        self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, p: np.ndarray, a: np.ndarray
    ) -> np.ndarray:
        """Joint-side torques/forces (N, n) [N·m or N] needed for the motion, gravity included."""
        ...
