"""``--time auto``: the duration at which the path's exact Cartesian peaks meet the capacity [Li2018, Eq. (24)–(26)]."""

from __future__ import annotations

import math

from ..model.profile import Capacity
from ..model.trajectory import CartesianPath


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
