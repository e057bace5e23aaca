"""Headroom: a profile whose timed limits are a fraction of their ratings (the limit-use fraction).

``with_limit_use(profile, 0.9)`` is the same robot with every timed limit at 90 % of its rating: the Cartesian
capacity here, the joints' and drives' limits through :func:`limit_specs` (what the planner and the check build
their models from). Positions, the workcell and the singularity margin are not scaled. The limit report states
use against the ratings again (:meth:`~pickplace_cli.limits.report.LimitReport.rated`).
"""

from __future__ import annotations

from .errors import ProfileError
from .profile import JointSpec, Profile

def check_limit_use(use: float, where: str = "limit-use") -> float:
    """``use`` as a float in (0, 1]; ProfileError (exit 1) naming ``where``, the value and the rule otherwise."""
    import math

    try:
        x = float(use)
    except (TypeError, ValueError):
        raise ProfileError(f"{where} = {use!r}: a fraction in (0, 1] (e.g. 0.9 keeps 10 % of every rating in reserve)") from None
    if not (math.isfinite(x) and 0.0 < x <= 1.0):
        raise ProfileError(f"{where} = {use!r}: must be a fraction in (0, 1] of every timed limit's rating "
                           "(e.g. 0.9 keeps 10 % in reserve; 1 plans to the ratings)")
    return x


def with_limit_use(profile: Profile, use: float) -> Profile:
    """The profile whose timed limits are ``use`` × their ratings.

    Parameters
    ----------
    profile : Profile
        The profile as rated (or already scaled: the ratings are its own).
    use : float
        The fraction (0, 1] [-] of every timed limit's rating to plan and check to (0.9 keeps 10 % in reserve).

    Returns
    -------
    Profile
        The scaled profile (the same object for the same profile and fraction).

    Raises
    ------
    ProfileError
        ``use`` outside (0, 1].

    Notes
    -----
    Scaled: the Cartesian capacity, and through
    :func:`limit_specs` every joint's velocity, acceleration and jerk and every drive's speed, peak torque, torque
    rate and rated (RMS) torque. Positions, the workcell and the singularity margin stay. Memoised, so the same
    (profile, use) is the same object (the planner keeps its models per profile)."""
    base = profile.rated
    use = check_limit_use(use)
    if use == profile.limit_use:
        return profile
    if use == 1.0:
        return base
    key = (id(base), use)
    hit = _SCALED.get(key)
    if hit is not None and hit[0] is base:
        return hit[1]
    cap = base.capacity
    scaled = base.model_copy(update={"capacity": cap.model_copy(update={
        "velocity": cap.velocity * use, "acceleration": cap.acceleration * use,
        "jerk": None if cap.jerk is None else cap.jerk * use})})
    scaled._limit_use = use
    scaled._rated = base
    if len(_SCALED) > 64:
        _SCALED.clear()
    _SCALED[key] = (base, scaled)
    return scaled


_SCALED: dict = {}


def apply_limit_use(profile: Profile, use: float | None = None) -> Profile:
    """The profile at the limit-use fraction in force: ``use`` when given, else the one it is scaled to already,
    else its own ``planning.limit_use`` (:func:`with_limit_use`)."""
    if use is not None:
        return with_limit_use(profile, use)
    if profile.rated is not profile:
        return profile
    return with_limit_use(profile, profile.planning.limit_use)


def limit_specs(profile: Profile) -> list[JointSpec]:
    """The profile's joint specs with their timed limits scaled by its limit-use fraction (:func:`with_limit_use`)."""
    specs = profile.robot.joint_specs()
    use = profile.limit_use
    if use == 1.0:
        return specs

    def times(x):
        return None if x is None else x * use

    out = []
    for s in specs:
        lim = s.limits.model_copy(update={"velocity": times(s.limits.velocity),
                                          "acceleration": times(s.limits.acceleration), "jerk": times(s.limits.jerk)})
        drv = None if s.drive is None else s.drive.model_copy(update={
            "max_speed": times(s.drive.max_speed), "peak_torque": times(s.drive.peak_torque),
            "torque_rate": times(s.drive.torque_rate), "rated_torque": times(s.drive.rated_torque)})
        out.append(s.model_copy(update={"limits": lim, "drive": drv}))
    return out


