"""The line frame and a robot's base frame (see :mod:`~pickplace_cli.line.spec`): a translation and a right angle.

A robot's base frame has its origin at ``base`` = [along, across, height] (line frame) and is mounted so that
the belt runs along its axis ``direction`` (+x, −x, +y, −y); "across" is the vertical × "along" (to the left of
the direction of travel), "height" its z. A point [along, across, height] of the line is, in the robot's frame,

    p = (along − base_along)·d + (across − base_across)·c + (height − base_height)·ẑ,   c = ẑ × d.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

AXES = {"+x": (1.0, 0.0, 0.0), "-x": (-1.0, 0.0, 0.0), "+y": (0.0, 1.0, 0.0), "-y": (0.0, -1.0, 0.0)}


@dataclass(frozen=True)
class Frame:
    """A robot's base frame in the line: ``base`` [m, line frame]; ``d``, ``c`` the along and across axes in the
    robot's frame."""

    base: np.ndarray
    d: np.ndarray
    c: np.ndarray

    @classmethod
    def of(cls, base, direction: str) -> "Frame":
        d = np.array(AXES[direction])
        c = np.cross([0.0, 0.0, 1.0], d)
        return cls(np.asarray(base, float), d, c)

    @property
    def rotation(self) -> np.ndarray:
        """(3, 3): robot-frame vector = rotation @ line-frame vector."""
        return np.column_stack([self.d, self.c, [0.0, 0.0, 1.0]])

    def to_robot(self, line_points) -> np.ndarray:
        """Line-frame points [along, across, height] (…, 3) → the robot's base frame [m]."""
        return (np.asarray(line_points, float) - self.base) @ self.rotation.T

    def to_line(self, robot_points) -> np.ndarray:
        """Robot-frame points (…, 3) → the line frame [along, across, height] [m]."""
        return np.asarray(robot_points, float) @ self.rotation + self.base

    def velocity(self, along: float, across: float = 0.0) -> np.ndarray:
        """A horizontal line-frame velocity [m/s] in the robot's frame."""
        return along * self.d + across * self.c
