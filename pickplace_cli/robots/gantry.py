"""Cartesian gantry: joints q = (x, y, z) of the tool (identity kinematics), masses per axis."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..model.errors import UnreachableError

G = 9.80665


@dataclass(frozen=True)
class GantryRobot:
    """Three stacked linear axes. ``travel`` (3, 2) [m] are the joint ranges; ``masses`` (3,) [kg] the mass
    moved by each axis (an axis carries the axes mounted on it: give the total it moves)."""

    travel: np.ndarray
    masses: np.ndarray
    joint_names: tuple[str, ...] = ("q1", "q2", "q3")
    joint_units: tuple[str, ...] = ("m", "m", "m")
    g: float = G

    def inverse_kinematics(self, p: np.ndarray) -> np.ndarray:
        p = np.asarray(p, float)
        lo, hi = self.travel[:, 0], self.travel[:, 1]
        bad = np.flatnonzero(np.any((p < lo - 1e-12) | (p > hi + 1e-12), axis=1))
        if bad.size:
            i = int(bad[0])
            axis = int(np.flatnonzero((p[i] < lo - 1e-12) | (p[i] > hi + 1e-12))[0])
            raise UnreachableError(
                f"point ({', '.join(f'{c:.6g}' for c in p[i])}) m (sample {i}) is outside the travel of axis "
                f"{'xyz'[axis]}: [{lo[axis]:g}, {hi[axis]:g}] m",
                index=i,
            )
        return p.copy()

    def forward_kinematics(self, q: np.ndarray) -> np.ndarray:
        return np.asarray(q, float).copy()

    def joint_motion(self, p, v, a, j):
        return self.inverse_kinematics(p), np.array(v, float), np.array(a, float), np.array(j, float)

    def inverse_dynamics(self, q, qd, qdd, p, a) -> np.ndarray:
        """Axis forces [N]: m_i q̈_i, plus m_z g on z (gravity along −z)."""
        force = np.asarray(qdd, float) * self.masses
        force[:, 2] += self.masses[2] * self.g
        return force

    def torque_rate(self, q, qd, qdd, qddd, p=None, v=None, a=None, j=None) -> tuple[np.ndarray, np.ndarray]:
        """(dA, dG) [N/s]: d/dt of the inertial forces m_i q̈_i (= m_i q⃛_i) and of gravity (constant: 0)."""
        qddd = np.asarray(qddd, float)
        return qddd * self.masses, np.zeros_like(qddd)
