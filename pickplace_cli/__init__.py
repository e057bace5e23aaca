"""pickplace: smooth, fast pick-and-place trajectories for high-speed robots, checked against every motor limit.

The library behind the ``pickplace`` command. Everything a Python user needs is importable from here::

    from pickplace_cli import PlanOptions, Task, load_profile, plan

    profile = load_profile("delta-su2018")                     # a shipped profile's name, or a YAML file
    task = Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], height=0.025)   # the Adept cycle, m
    result = plan(task, profile, PlanOptions(time="limits"))
    print(f"{result.duration.seconds:.4f} s, limits ok: {result.report.ok}")

The names below are the public API (``__all__``): they keep their meaning and their import path from one version to
the next, while the modules behind them may move. They are loaded on first use (PEP 562), so ``import pickplace_cli``
costs nothing and ``pickplace --help`` stays fast.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

__version__ = "0.2.0"

#: public name → the module that defines it (below ``pickplace_cli``)
_PUBLIC = {
    # one move
    "plan": "planner",
    "PlanOptions": "planner",
    "Plan": "planner",
    "PlanInterrupted": "planner",
    "Task": "model.task",
    "Method": "paths",
    # profiles
    "load_profile": "model.profile",
    "parse_profile": "model.profile",
    "shipped_profiles": "model.profile",
    "profile_schema": "model.profile",
    "Profile": "model.profile",
    "with_limit_use": "model.headroom",
    # results
    "Duration": "timing",
    "LimitReport": "limits.report",
    "LimitRow": "limits.report",
    "CartesianTrajectory": "model.trajectory",
    "JointTrajectory": "model.trajectory",
    # checking a trajectory file
    "check_file": "pipelines.check",
    "MoveCheck": "pipelines.check",
    # writing outputs
    "atomic_output": "export",
    "write_csv": "export.csv",
    "write_json": "export.json",
    "write_mcap": "export.mcap",
    # errors (each carries the exit code the command line uses)
    "PickplaceError": "model.errors",
    "ProfileError": "model.errors",
    "TaskError": "model.errors",
    "TableError": "model.errors",
    "UsageError": "model.errors",
    "ExportError": "model.errors",
    "UnreachableError": "model.errors",
    "NoFeasibleDuration": "model.errors",
}

__all__ = ["__version__", *_PUBLIC]


def __getattr__(name: str) -> Any:
    """Load a public name from its module on first use (PEP 562) and keep it here."""
    module = _PUBLIC.get(name)
    if module is None:
        raise AttributeError(f"module 'pickplace_cli' has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})


if TYPE_CHECKING:  # for type checkers, editors and the API reference (never run)
    from .export import atomic_output
    from .export.csv import write_csv
    from .export.json import write_json
    from .export.mcap import write_mcap
    from .limits.report import LimitReport, LimitRow
    from .model.errors import (
        ExportError,
        NoFeasibleDuration,
        PickplaceError,
        ProfileError,
        TableError,
        TaskError,
        UnreachableError,
        UsageError,
    )
    from .model.headroom import with_limit_use
    from .model.profile import Profile, load_profile, parse_profile, profile_schema, shipped_profiles
    from .model.task import Task
    from .model.trajectory import CartesianTrajectory, JointTrajectory
    from .paths import Method
    from .pipelines.check import MoveCheck, check_file
    from .planner import Plan, PlanInterrupted, PlanOptions, plan
    from .timing import Duration
