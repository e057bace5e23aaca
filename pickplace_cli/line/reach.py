"""Whether a line robot reaches every point it may have to: its window across its band at the grip height, its place
targets and its home point (:func:`check_reach`, before a run)."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from ..model.errors import UnreachableError

if TYPE_CHECKING:  # pragma: no cover
    from .robot import LineRobot

#: points along the window checked at a time by :func:`check_reach`
REACH_CHUNK = 400


def _stretches(w0: float, w1: float, step: float):
    """The window's ends, then the points along it ``step`` apart (as ``np.linspace``), ``REACH_CHUNK`` at a time."""
    yield np.array([w0, w1])
    n = max(2, int(min(math.ceil((w1 - w0) / step), 1e15)) + 1)
    for k in range(0, n, REACH_CHUNK):
        al = w0 + (w1 - w0) * (np.arange(k, min(k + REACH_CHUNK, n)) / (n - 1))
        if k + REACH_CHUNK >= n:
            al[-1] = w1
        yield al


def check_reach(robot: "LineRobot", bands: tuple[float, float], step: float = 5e-3) -> None:
    """UnreachableError (exit 4) when part of the robot's window — along its window, across its band, at the
    grip height — or a place target or its home is outside its workspace (reach, joint ranges, workcell box). The
    window's corners are checked first, then its grid a stretch of ``REACH_CHUNK`` points along at a time (a window
    of any length costs bounded memory, and one outside the workspace is found at its corners)."""
    from ..pipelines.rendezvous import workspace_mask

    w0, w1 = robot.window
    lo, hi = bands
    ac = np.linspace(lo, hi, max(2, int(math.ceil((hi - lo) / step)) + 1))
    for al in _stretches(w0, w1, step):
        A, C = np.meshgrid(al, ac, indexing="ij")
        line_pts = np.column_stack([A.ravel(), C.ravel(), np.full(A.size, robot.grip)])
        ok = workspace_mask(robot.profile, robot.frame.to_robot(line_pts))
        if not ok.all():
            k = int(np.argmin(ok))
            raise UnreachableError(
                f"robot {robot.name}: window [{w0:g}, {w1:g}] m across [{lo:g}, {hi:g}] m: the point along "
                f"{line_pts[k, 0]:.4f} m, across {line_pts[k, 1]:.4f} m (grip height {robot.grip:g} m) is outside the "
                f"workspace of profile {robot.profile.name} (reach, joint range or workcell box); the window must lie "
                "inside it across the robot's part of the belt"
            )
    for what, pts in (("home point", [robot.home]), ("place target", [t[0] for t in robot.targets])):
        ok = workspace_mask(robot.profile, np.asarray(pts))
        if not ok.all():
            k = int(np.argmin(ok))
            ln = robot.frame.to_line(pts[k])
            raise UnreachableError(f"robot {robot.name}: {what} [{ln[0]:g}, {ln[1]:g}, {ln[2]:g}] m (line frame) is "
                                   f"outside the workspace of profile {robot.profile.name}")


__all__ = ["check_reach"]
