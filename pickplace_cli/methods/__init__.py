"""Planning methods: each turns a Task into a CartesianPath. ``PLANNERS`` maps names to planners."""

from __future__ import annotations

from enum import Enum
from typing import Any, Callable

from ..task import Task
from ..trajectory import CartesianPath


class Method(str, Enum):
    """Names accepted by ``--method``."""

    bspline = "bspline"


def _bspline(task: Task, **params: Any) -> CartesianPath:
    from .bspline import plan_bspline

    return plan_bspline(task, **params)


#: method → planner(task, **params) -> CartesianPath (imports of the method modules stay lazy)
PLANNERS: dict[Method, Callable[..., CartesianPath]] = {
    Method.bspline: _bspline,
}


def plan_path(task: Task, method: Method | str = Method.bspline, **params: Any) -> CartesianPath:
    """Geometry + motion law of ``task`` by ``method`` (normalised time τ ∈ [0, 1])."""
    return PLANNERS[Method(method)](task, **params)
