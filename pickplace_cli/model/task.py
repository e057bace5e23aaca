"""The move to plan and its local frame [Li2018, Eq. (1)–(2)]."""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from math import isfinite, sqrt

import numpy as np

from .errors import TaskError


#: the largest coordinate or clearance accepted [m], and end speed [m/s]: far beyond any workcell, and small enough
#: that no power of a move's numbers up to the limit check's (a jerk squared, ~1e42 at 1 µs) overflows a double
MAX_METRES = 1e3
MAX_SPEED = 1e3
#: the smallest clearance accepted [m] (below it some methods divide by zero; the default method refuses λ = b/h
#: beyond 1e5 long before)
MIN_HEIGHT = 1e-6
#: the largest tool angle accepted [rad] (~159 turns: beyond any axis range; keeps the limit check's numbers finite)
MAX_RADIANS = 1e3


def _angle(name: str, value) -> float | None:
    """A tool angle [rad]: None stays None (no angle given); TaskError unless a finite number within ±MAX_RADIANS."""
    if value is None:
        return None
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise TaskError(f"{name} = {value!r}: the tool angle must be a number of radians") from None
    if not isfinite(x):
        raise TaskError(f"{name} = {value!r}: the tool angle must be a finite number of radians (no NaN or inf)")
    if abs(x) > MAX_RADIANS:
        raise TaskError(f"{name} = {value!r} rad: the tool angle must lie within ±{MAX_RADIANS:g} rad (SI units: "
                        "radians, not degrees)")
    return x


def _vec3(name: str, value, limit: float = MAX_METRES, unit: str = "m") -> np.ndarray:
    # a streamed row's three Python floats without numpy's per-call costs (~0.1 ms per Task after an idle
    # pause, the cold CPU of issue 16); anything else, and every error, by the general path below
    if type(value) in (list, tuple) and len(value) == 3:
        x, y, z = value
        if type(x) is float and type(y) is float and type(z) is float and -limit <= x <= limit \
                and -limit <= y <= limit and -limit <= z <= limit:
            return np.array((x, y, z), dtype=float)
    try:
        arr = np.asarray(value, dtype=float).reshape(-1)
    except (TypeError, ValueError):  # a string "0,0,-0.8", None, …: the library's callers get the CLI's one line
        raise TaskError(f"{name} = {value!r}: needs three numbers X,Y,Z in {unit} (a sequence, e.g. [0.1, 0, -0.8])") \
            from None
    if arr.shape != (3,):
        raise TaskError(f"{name} = {value!r}: needs three coordinates X,Y,Z in {unit}")
    if not np.all(np.isfinite(arr)):
        raise TaskError(f"{name} = {','.join(map(str, arr))}: every coordinate must be a finite number ({unit})")
    if not np.all(np.abs(arr) <= limit):
        raise TaskError(f"{name} = {','.join(f'{c:g}' for c in arr)}: every coordinate must lie within "
                        f"±{limit:g} {unit} (SI units)")
    return arr


@dataclass(frozen=True)
class Task:
    """A pick-and-place move from ``p_from`` to ``p_to`` (base frame, m).

    Parameters
    ----------
    p_from, p_to : array_like
        The pick and place points x, y, z [m], base frame.
    height : float
        Clearance h [m] of the path's midpoint above the higher end point.
    eta : float
        Lift-off/set-down ratio η [-], 0 < η < 1 [Li2018, Eq. (11)].
    v_from, v_to : array_like
        Tool velocity [m/s] leaving the pick and reaching the place point (zero: from rest to rest).
    theta_from, theta_to : float or None
        Tool angle [rad] about the base z axis at the ends (a rotary fourth axis; both or neither).

    Raises
    ------
    TaskError
        A value that is not finite or outside its range, equal end points, an angle at one end only.

    Notes
    -----
    ``height`` [m] is the clearance of the path's midpoint P3 above the *higher* of the two end points;
    ``eta`` is the lift-off/set-down ratio η of [Li2018, Eq. (11)]; ``v_from``/``v_to`` [m/s] are the tool
    velocities at the ends (zero for a move from rest to rest). ``theta_from``/``theta_to`` [rad] are the tool's
    angles about the base z axis at the ends, for a robot with a rotary fourth axis (both or neither; None: the
    tool does not turn); the planner turns the shorter way round unless told otherwise.

    Immutable: the derived quantities (b, γ, λ, the via points) are computed once, on first use.
    """

    p_from: np.ndarray
    p_to: np.ndarray
    height: float
    eta: float = 0.5
    v_from: np.ndarray = field(default_factory=lambda: np.zeros(3))
    v_to: np.ndarray = field(default_factory=lambda: np.zeros(3))
    theta_from: float | None = None
    theta_to: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "theta_from", _angle("from_theta", self.theta_from))
        object.__setattr__(self, "theta_to", _angle("to_theta", self.theta_to))
        if (self.theta_from is None) != (self.theta_to is None):
            given, other = ("from_theta", "to_theta") if self.theta_to is None else ("to_theta", "from_theta")
            raise TaskError(f"{given} = {self.theta_from if self.theta_to is None else self.theta_to!r} rad without "
                            f"{other}: give the tool angle at both ends (or at neither)")
        object.__setattr__(self, "p_from", _vec3("from", self.p_from))
        object.__setattr__(self, "p_to", _vec3("to", self.p_to))
        object.__setattr__(self, "v_from", _vec3("v_from", self.v_from, MAX_SPEED, "m/s"))
        object.__setattr__(self, "v_to", _vec3("v_to", self.v_to, MAX_SPEED, "m/s"))
        try:
            h = float(self.height)
        except (TypeError, ValueError):
            raise TaskError(f"height = {self.height!r}: must be a finite number of metres > 0 (the clearance; the "
                            "profile's planning.height is the CLI's default)") from None
        if not (isfinite(h) and h > 0):
            raise TaskError(f"height = {self.height!r}: must be a finite number of metres > 0")
        if h > MAX_METRES:
            raise TaskError(f"height = {self.height!r} m: must be at most {MAX_METRES:g} m (SI units)")
        if h < MIN_HEIGHT:
            raise TaskError(f"height = {self.height!r} m: must be at least {MIN_HEIGHT:g} m (1 µm; SI units)")
        try:
            e = float(self.eta)
        except (TypeError, ValueError):
            raise TaskError(f"eta = {self.eta!r}: the lift-off/set-down ratio η must be a number in (0, 1)") from None
        if not (isfinite(e) and 0 < e < 1):
            raise TaskError(f"eta = {self.eta!r}: the lift-off/set-down ratio η must lie strictly between 0 and 1")
        object.__setattr__(self, "height", h)
        object.__setattr__(self, "eta", e)
        dx, dy, dz = (self.p_to - self.p_from).tolist()
        if sqrt(dx * dx + dy * dy + dz * dz) < 1e-9:  # np.linalg.norm's sum, in Python floats
            raise TaskError(
                f"from = to = {','.join(f'{c:g}' for c in self.p_from)}: the end points must differ (by more than 1 nm)"
            )

    # --- local frame P1-uv [Li2018, Eq. (1)]
    @cached_property
    def b(self) -> float:
        """Horizontal width of the move b [m] (Eq. 2)."""
        return float(np.hypot(*(self.p_to[:2] - self.p_from[:2])))

    @cached_property
    def gamma(self) -> float:
        """Direction of the move in the x-y plane γ [rad] (Eq. 1); 0 for a purely vertical move."""
        d = self.p_to[:2] - self.p_from[:2]
        return float(np.arctan2(d[1], d[0])) if self.b > 0 else 0.0

    @property
    def e_u(self) -> np.ndarray:
        """Unit vector of the local u axis in the base frame."""
        g = self.gamma
        return np.array([np.cos(g), np.sin(g), 0.0])

    @cached_property
    def lam(self) -> float:
        """Width/height ratio λ = b/h (Eq. 2), h = clearance above the higher end point."""
        return self.b / self.height

    @cached_property
    def z_top(self) -> float:
        """Height of the path's midpoint P3 [m]."""
        return max(self.p_from[2], self.p_to[2]) + self.height

    def via_points(self) -> np.ndarray:
        """P1 … P5 of [Li2018, Eq. (11)] in the base frame, (5, 3) [m].

        With unequal end heights each end lifts off at η of its own rise to P3 (the clearance is measured
        from the higher end), which reduces to Eq. (11) when z_from = z_to.
        """
        return self._via.copy()

    @cached_property
    def _via(self) -> np.ndarray:
        p1, p5 = self.p_from, self.p_to
        zt = self.z_top
        via = np.empty((5, 3))
        via[0], via[1], via[3], via[4] = p1, p1, p5, p5
        via[1, 2] = p1[2] + self.eta * (zt - p1[2])  # P2, P4 straight above the ends
        via[3, 2] = p5[2] + self.eta * (zt - p5[2])
        via[2] = ((p1[0] + p5[0]) / 2, (p1[1] + p5[1]) / 2, zt)  # P3 above the midpoint
        return via
