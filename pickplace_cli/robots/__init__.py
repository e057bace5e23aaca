"""Robot models: inverse/forward kinematics, Jacobians, analytic joint derivatives, inverse dynamics.

``build_robot(profile.robot)`` turns the validated profile section into a model (a dict maps each
``kind`` to its builder).
"""

from __future__ import annotations

from typing import Any, Callable


def _gantry(model: Any):
    import numpy as np

    from .gantry import GantryRobot

    return GantryRobot(
        travel=np.array([a.travel for a in model.axes], float),
        masses=np.array([a.mass for a in model.axes], float),
    )


BUILDERS: dict[str, Callable[[Any], Any]] = {"gantry": _gantry}


def build_robot(model: Any):
    """The robot model for a validated ``profile.robot`` section."""
    return BUILDERS[model.kind](model)
