"""Robot models: inverse/forward kinematics, Jacobians, analytic joint derivatives, inverse dynamics.

``build_robot(profile.robot)`` turns the validated profile section into a model (a dict maps each
``kind`` to its builder). A model's own parameter check (ValueError) becomes a ProfileError.
"""

from __future__ import annotations

from typing import Any, Callable

from ..model.errors import ProfileError


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
        forearm_end_elbow=m.forearm_end_elbow, forearm_end_plate=m.forearm_end_plate,
        forearm_rod_inertia=m.forearm_rod_inertia, dynamics=model.dynamics,
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


#: the tool angle's dependence on the base joints of a robot with a rotary fourth axis (robots/rotary.py): a SCARA's
#: J4 sits at the end of link 2 (θ = q1 + q2 + σ·q4), a Delta's plate does not turn (θ = σ·q4)
CARRIERS: dict[str, tuple[float, float, float]] = {"delta": (0.0, 0.0, 0.0), "scara": (1.0, 1.0, 0.0)}


def build_robot(model: Any):
    """The robot model for a validated ``profile.robot`` section (with its rotary fourth axis when it has one)."""
    try:
        robot = BUILDERS[model.kind](model)
        rotary = getattr(model, "rotary", None)
        if rotary is not None:
            from .rotary import RotaryAxisRobot

            robot = RotaryAxisRobot(robot, inertia=rotary.inertia, sign=float(rotary.sign), carrier=CARRIERS[model.kind])
        return robot
    except ValueError as exc:
        raise ProfileError(f"robot ({model.kind}): {exc}") from None


def radial_reach(robot, specs, z: float, margin: float | None = None, directions: int = 72) -> tuple[float, float, int]:
    """(inner, outer, n): over the ``n`` of ``directions`` rays from the z axis at height z that reach
    anything, the radii [m] between which all of them are reachable within the joint position limits and
    the singularity margin (inner = 0 for a full disc; outer < inner when they share no radius).
    Scanned on a 1 mm grid along each ray."""
    import numpy as np

    from ..model.errors import UnreachableError

    rho = np.linspace(0, 2.0, 2001)
    inner, outer, count = 0.0, np.inf, 0
    for a in np.linspace(0, 2 * np.pi, directions, endpoint=False):
        pts = np.column_stack([rho * np.cos(a), rho * np.sin(a), np.full_like(rho, z)])
        try:
            q = robot.inverse_kinematics(pts)
            ok = np.ones(len(pts), bool)
            for i, s in enumerate(specs):
                if s.limits.position is not None:
                    ok &= (q[:, i] >= s.limits.position[0]) & (q[:, i] <= s.limits.position[1])
            if margin is not None and hasattr(robot, "singularity_measure"):
                ok &= robot.singularity_measure(q, pts) >= margin
        except UnreachableError:
            ok = np.array([_one_inside(robot, specs, margin, p) for p in pts])
        good = np.flatnonzero(ok)
        if good.size == 0:
            continue
        count += 1
        first = good[0]
        run_end = first
        while run_end + 1 < len(ok) and ok[run_end + 1]:
            run_end += 1
        inner = max(inner, float(rho[first]))
        outer = min(outer, float(rho[run_end]))
    return inner, (float(outer) if count else -1.0), count


def _one_inside(robot, specs, margin, p) -> bool:
    from ..model.errors import UnreachableError

    try:
        q = robot.inverse_kinematics(p[None, :])
    except UnreachableError:
        return False
    for i, s in enumerate(specs):
        if s.limits.position is not None and not (s.limits.position[0] <= q[0, i] <= s.limits.position[1]):
            return False
    if margin is not None and hasattr(robot, "singularity_measure"):
        return bool(robot.singularity_measure(q, p[None, :])[0] >= margin)
    return True
