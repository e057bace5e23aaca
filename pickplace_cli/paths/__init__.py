"""Planning methods: each turns a Task into a CartesianPath. ``PLANNERS`` maps names to planners."""

from __future__ import annotations

from typing import Any, Callable

from ..model.errors import TaskError
from ..model.methods import Method
from ..model.task import Task
from ..model.trajectory import CartesianPath


def _bspline(task: Task, **params: Any) -> CartesianPath:
    from .bspline import plan_bspline

    return plan_bspline(task, **params)


def _ph(task: Task, **params: Any) -> CartesianPath:
    from .ph import plan_ph

    return plan_ph(task, **params)


def _superposition(task: Task, **params: Any) -> CartesianPath:
    from .superposition import plan_superposition

    return plan_superposition(task, **params)


def _lame(task: Task, **params: Any) -> CartesianPath:
    from .lame import plan_lame

    return plan_lame(task, **params)


def _piecewise_poly(task: Task, **params: Any) -> CartesianPath:
    from .piecewise_poly import plan_piecewise_poly

    return plan_piecewise_poly(task, **params)


def _bspline_vel(task: Task, duration: float | None = None, **params: Any) -> CartesianPath:
    if duration is None:
        raise TaskError(
            "method bspline-vel: its path depends on the duration (the end velocities enter as v·T); "
            "give duration=SECONDS, or plan through pickplace_cli.planner.plan (--time auto|fit|SECONDS)"
        )
    from .bspline_vel import plan_bspline_vel

    return plan_bspline_vel(task, duration, **params)


def _bspline_vel_factory(task: Task, **params: Any) -> Callable[[float], CartesianPath]:
    from .bspline_vel import PathFactory

    return PathFactory(task, **params)


#: methods whose normalised path depends on the duration T: method → factory(task, **params), a callable
#: T [s] → CartesianPath planned for T (the planner's duration selection calls it at each trial T)
PATH_FACTORIES: dict[Method, Callable[..., Callable[[float], CartesianPath]]] = {
    Method.bspline_vel: _bspline_vel_factory,
}


def depends_on_duration(method: Method | str) -> bool:
    """True when the method's path must be planned for a given duration (see ``PATH_FACTORIES``)."""
    return Method(method) in PATH_FACTORIES


def path_factory(task: Task, method: Method | str, **params: Any) -> Callable[[float], CartesianPath]:
    """T [s] → CartesianPath of ``task`` by ``method`` (the same path for every T when it does not depend on T)."""
    m = Method(method)
    if m in PATH_FACTORIES:
        return PATH_FACTORIES[m](task, **params)
    path = plan_path(task, m, **params)
    return lambda duration: path


#: method → planner(task, **params) -> CartesianPath (imports of the method modules stay lazy)
PLANNERS: dict[Method, Callable[..., CartesianPath]] = {
    Method.bspline: _bspline,
    Method.ph: _ph,
    Method.superposition: _superposition,
    Method.lame: _lame,
    Method.piecewise_poly: _piecewise_poly,
    Method.bspline_vel: _bspline_vel,
}


def plan_path(task: Task, method: Method | str = Method.bspline, **params: Any) -> CartesianPath:
    """Geometry + motion law of ``task`` by ``method`` (normalised time τ ∈ [0, 1]).

    A parameter the method does not take is a TaskError naming it (not a TypeError)."""
    m = Method(method)
    try:
        return PLANNERS[m](task, **params)
    except TypeError as exc:
        text = str(exc)
        if "unexpected keyword argument" not in text:
            raise
        name = text.rsplit("argument", 1)[-1].strip(" '\"")
        raise TaskError(
            f"param {name} = {params.get(name)!r}: method {m.value} has no parameter {name!r} (see README, Methods)"
        ) from None
