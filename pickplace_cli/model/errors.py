"""Typed errors. Library code raises these; only ``cli.py`` turns them into messages and exit codes.

Exit codes (documented in README):
0 success · 1 invalid input (profile, table, values) · 2 usage error ·
3 a limit is exceeded · 4 a point of the move is unreachable / outside the workspace.
"""

from __future__ import annotations


class PickplaceError(Exception):
    """Base of every expected failure. ``exit_code`` is what the CLI exits with."""

    exit_code = 1


class ProfileError(PickplaceError):
    """The robot/workcell profile is missing, unparsable or violates a rule."""


class UsageError(PickplaceError):
    """An option that cannot apply to this request (e.g. a time law for a method whose path depends on T)."""

    exit_code = 2


class TaskError(PickplaceError):
    """The requested move (points, height, η, duration …) is invalid."""


class TableError(PickplaceError):
    """A look-up table is missing, corrupt, or does not cover the requested λ."""


class ExportError(PickplaceError):
    """An output could not be written."""


class UnreachableError(PickplaceError):
    """A point of the move is outside the robot's workspace.

    ``index`` is the first failing sample when the model knows it (the planner adds its time).
    """

    exit_code = 4

    def __init__(self, message: str, index: int | None = None) -> None:
        super().__init__(message)
        self.index = index


class NoFeasibleDuration(PickplaceError):
    """``--time fit``: no duration satisfies a limit (e.g. the holding torque alone exceeds the motor's)."""

    exit_code = 3
