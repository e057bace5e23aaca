"""choose_duration: explicit seconds, or ``auto`` from the Cartesian capacity [Li2018, Eq. (24)–(26)]."""

from __future__ import annotations

import math
from dataclasses import dataclass

from .errors import TaskError
from .profile import Capacity
from .trajectory import CartesianPath


@dataclass(frozen=True)
class Duration:
    """The chosen duration T [s] and how it was chosen.

    ``auto`` is Eq. (26) extended by jerk: T = max(v̂/[v], √(â/[a]), ∛(ĵ/[j])) where v̂, â, ĵ are the exact
    peaks of ‖d^k p/dτ^k‖ of the path with T = 1 (for a symmetric move v̂ = b·v_max etc.). ``binding`` names
    the capacity that sets T. ``t_velocity``, ``t_acceleration``, ``t_jerk`` are the three bounds (s).
    """

    seconds: float
    mode: str
    t_velocity: float
    t_acceleration: float
    t_jerk: float | None
    binding: str

    def as_dict(self) -> dict:
        return {
            "duration_s": self.seconds,
            "mode": self.mode,
            "auto_bounds_s": {"velocity": self.t_velocity, "acceleration": self.t_acceleration, "jerk": self.t_jerk},
            "binding": self.binding,
        }


def auto_duration(path: CartesianPath, capacity: Capacity) -> tuple[float, float, float | None, str]:
    """(T_v, T_a, T_j, binding) of Eq. (26) (+ jerk when the profile gives [j])."""
    v, a, j = path.peaks
    tv = v / capacity.velocity
    ta = math.sqrt(a / capacity.acceleration)
    tj = (j / capacity.jerk) ** (1.0 / 3.0) if capacity.jerk else None
    bounds = {"velocity": tv, "acceleration": ta}
    if tj is not None:
        bounds["jerk"] = tj
    binding = max(bounds, key=bounds.__getitem__)
    return tv, ta, tj, binding


def parse_time(spec: str | float) -> str | float:
    """``auto`` | ``fit`` | seconds (> 0, finite) → the spec; TaskError naming the rule otherwise."""
    if isinstance(spec, str):
        s = spec.strip().lower()
        if s in ("auto", "fit"):
            return s
        try:
            value = float(s)
        except ValueError:
            raise TaskError(f"time = {spec!r}: give 'auto', 'fit' or a duration in seconds (e.g. 0.25)") from None
    else:
        value = float(spec)
    if not (math.isfinite(value) and value > 0):
        raise TaskError(f"time = {spec!r}: a duration must be a finite number of seconds > 0")
    return value


def choose_duration(path: CartesianPath, capacity: Capacity, spec: str | float = "auto") -> Duration:
    """Duration of the move: explicit seconds, or ``auto`` (Eq. 26). ``fit`` needs the robot model."""
    spec = parse_time(spec)
    tv, ta, tj, binding = auto_duration(path, capacity)
    if spec == "auto":
        return Duration(max(tv, ta, tj or 0.0), "auto", tv, ta, tj, binding)
    if spec == "fit":
        raise TaskError("time = fit: fitting the duration to motor limits needs a robot with drive limits (not yet available); use auto or seconds")
    return Duration(float(spec), "given", tv, ta, tj, "given")
