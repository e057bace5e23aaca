"""Robot models: inverse/forward kinematics, Jacobians, analytic joint derivatives, inverse dynamics.

``build_robot(profile.robot)`` turns the validated profile section into a model (a dict maps each
``kind`` to its builder). A model's own parameter check (ValueError) becomes a ProfileError.
"""

from __future__ import annotations

from typing import Any, Callable

from ..errors import ProfileError


def _gantry(model: Any):
    import numpy as np

    from .gantry import GantryRobot

    return GantryRobot(
        travel=np.array([a.travel for a in model.axes], float),
        masses=np.array([a.mass + model.payload for a in model.axes], float),
    )


def _delta(model: Any):
    from .delta import DeltaRobot

    g, m = model.geometry, model.masses
    return DeltaRobot(
        R=g.R, r=g.r, L=g.L, l=g.l,
        upper_arm_inertia=m.upper_arm_inertia, upper_arm_mass=m.upper_arm, upper_arm_com=m.upper_arm_com,
        elbow_mass=m.elbow, forearm_mass=m.forearm_pair, plate_mass=m.plate, payload=model.payload,
    )


def _scara(model: Any):
    from .scara import ScaraRobot

    a, b = model.link1, model.link2
    return ScaraRobot(
        l1=a.length, l2=b.length, elbow=model.elbow, z0=model.z0,
        m1=a.mass, m2=b.mass, lc1=a.com, lc2=b.com, I1=a.inertia, I2=b.inertia,
        m3=model.z_mass, payload=model.payload,
    )


BUILDERS: dict[str, Callable[[Any], Any]] = {"gantry": _gantry, "delta": _delta, "scara": _scara}


def build_robot(model: Any):
    """The robot model for a validated ``profile.robot`` section."""
    try:
        return BUILDERS[model.kind](model)
    except ValueError as exc:
        raise ProfileError(f"robot ({model.kind}): {exc}") from None
