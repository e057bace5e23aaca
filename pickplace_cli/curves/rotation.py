"""The tool's turn about the vertical: a smooth angle law θ(τ) planned with the move (the rotary fourth axis).

The Cartesian path stays 3-D; a path may carry an angle law next to it (``CartesianPath.angle``), evaluated like
the path itself: ``law(tau, order)`` → (N,) in rad/1^order on normalised time τ ∈ [0, 1], so a duration T scales
it exactly (dᵏθ/dtᵏ = law(t/T, k)/Tᵏ) and every time law composes it as it composes the path.

**The law.** The turn Δ = θ_end − θ_start runs on a window [τa, τb] of the move by the degree-9 rest-to-rest
polynomial

    θ(τ) = θ_start + Δ·s(x),   x = (τ − τa)/(τb − τa),   s(x) = 126x⁵ − 420x⁶ + 540x⁷ − 315x⁸ + 70x⁹

(s′(x) = 630 x⁴(1 − x)⁴), the lowest-degree polynomial whose first four derivatives vanish at both ends, and
θ constant outside the window. So θ is C⁴ everywhere — as smooth as the quintic B-spline path, which is C⁴
inside the move — and the angle's jerk (and with it every motor's torque rate) is continuous: the law adds no
jump to the limit check. Its exact peaks are Δ·max|s⁽ᵏ⁾|/(τb − τa)ᵏ (:func:`step_peaks`, from the roots of
s⁽ᵏ⁺¹⁾).

**The window** (:class:`TurnWindow`): the whole move (τa, τb = 0, 1), or only the transfer between lift-off and
set-down (the default): from the moment the tool has risen to the lift-off height of the path (the via point
P2 of [Li2018, Eq. (11)], η of the rise to the apex) until it sinks through the set-down height (P4) — so the
part does not turn while the gripper engages it at the pick or while it enters the place (a tray pocket). That
is how controllers run a pick-and-place jump (the rotation rides with the horizontal segment, after the depart
distance and before the approach distance).

**The way round** (:class:`TurnRule`): the shorter turn (|Δ| ≤ π; half a turn goes counter-clockwise), always
counter-clockwise (Δ ∈ [0, 2π)), always clockwise (Δ ∈ (−2π, 0]), or the end angle exactly as given.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from enum import Enum
from typing import Callable

import numpy as np


class TurnRule(str, Enum):
    """How the end angle is reached (``--turn``)."""

    shortest = "shortest"
    ccw = "ccw"
    cw = "cw"
    as_given = "as-given"


def _wrap(d: float) -> float:
    """d wrapped into (−π, π] (half a turn goes counter-clockwise)."""
    w = math.remainder(d, 2.0 * math.pi)  # in [−π, π]
    return math.pi if w == -math.pi else w


#: rule → (θ_to − θ_from as given [rad]) → the turn made [rad]
TURNS: dict[TurnRule, Callable[[float], float]] = {
    TurnRule.shortest: _wrap,
    TurnRule.ccw: lambda d: d % (2.0 * math.pi),
    TurnRule.cw: lambda d: -((-d) % (2.0 * math.pi)),
    TurnRule.as_given: lambda d: d,
}


def resolve_turn(theta_from: float, theta_to: float, rule: TurnRule | str = TurnRule.shortest) -> float:
    """The end angle [rad] of the turn from ``theta_from`` towards ``theta_to`` by ``rule`` (equal to ``theta_to``
    up to whole turns; exactly ``theta_to`` for ``as-given``)."""
    return float(theta_from) + TURNS[TurnRule(rule)](float(theta_to) - float(theta_from))


class TurnWindow(str, Enum):
    """When the tool turns (``--turn-during``): over the whole move, or between lift-off and set-down."""

    whole = "whole"
    transfer = "transfer"


#: s(x) of the module docstring and its derivatives up to the fifth: coefficients, highest power first (np.polyval)
_STEP_D = [np.array([70, -315, 540, -420, 126, 0, 0, 0, 0, 0], float)]
for _k in range(5):
    _STEP_D.append(np.polyder(_STEP_D[-1]))
del _k


def step(x, k: int = 0) -> np.ndarray:
    """s⁽ᵏ⁾(x) (k = 0 … 5) of the module docstring."""
    return np.polyval(_STEP_D[k], x)


@functools.cache
def step_peaks() -> tuple[float, float, float]:
    """max |s′|, |s″|, |s‴| on [0, 1], exact: s⁽ᵏ⁾ at the real roots of s⁽ᵏ⁺¹⁾ in [0, 1] and at the ends
    (s′ peaks at x = ½: 630/256)."""
    out = []
    for k in (1, 2, 3):
        roots = np.roots(_STEP_D[k + 1])
        x = np.concatenate([[0.0, 1.0], roots[np.abs(roots.imag) < 1e-12].real])
        x = x[(x >= 0.0) & (x <= 1.0)]
        out.append(float(np.max(np.abs(step(x, k)))))
    return tuple(out)  # type: ignore[return-value]


@dataclass(frozen=True)
class RotationLaw:
    """θ(τ) [rad] = ``start`` + ``turn``·s((τ − tau0)/(tau1 − tau0)) on [tau0, tau1], constant outside (module
    docstring). ``law(tau, order)`` → (N,) in rad/1^order; ``all_orders(tau)`` → (4, N): θ, θ′, θ″, θ‴."""

    start: float
    turn: float
    tau0: float = 0.0
    tau1: float = 1.0

    def __post_init__(self) -> None:
        for name in ("start", "turn", "tau0", "tau1"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"RotationLaw.{name} = {getattr(self, name)!r}: must be finite")
        if not 0.0 <= self.tau0 < self.tau1 <= 1.0:
            raise ValueError(f"RotationLaw window [{self.tau0!r}, {self.tau1!r}]: need 0 <= tau0 < tau1 <= 1")

    @property
    def end(self) -> float:
        return self.start + self.turn

    def all_orders(self, tau: np.ndarray) -> np.ndarray:
        tau = np.atleast_1d(np.asarray(tau, float))
        out = np.empty((4, len(tau)))
        for k in range(4):
            out[k] = self._order(tau, k)
        return out

    def _order(self, tau: np.ndarray, k: int) -> np.ndarray:
        w = self.tau1 - self.tau0
        x = np.clip((tau - self.tau0) / w, 0.0, 1.0)
        if k == 0:
            return self.start + self.turn * step(x)
        inside = (tau > self.tau0) & (tau < self.tau1)
        return np.where(inside, self.turn * step(x, k) / w**k, 0.0)

    def __call__(self, tau: np.ndarray, order: int = 0) -> np.ndarray:
        if not 0 <= order <= 3:
            raise ValueError(f"order must be in 0..3, got {order}")
        return self._order(np.atleast_1d(np.asarray(tau, float)), order)

    @property
    def peaks(self) -> tuple[float, float, float]:
        """Exact max |θ′|, |θ″|, |θ‴| on τ ∈ [0, 1] (rad/1^k)."""
        w = self.tau1 - self.tau0
        return tuple(abs(self.turn) * step_peaks()[k - 1] / w**k for k in (1, 2, 3))  # type: ignore[return-value]

    @property
    def breakpoints(self) -> tuple[float, ...]:
        """The window's interior ends (where s⁽⁵⁾ steps): the limit check samples there."""
        return tuple(t for t in (self.tau0, self.tau1) if 0.0 < t < 1.0)


def chain_rule(d: np.ndarray, s1: np.ndarray, s2: np.ndarray, s3: np.ndarray) -> np.ndarray:
    """(4, N) derivatives in u of f(τ(u)) from those in τ, ``d`` (4, N), and τ′, τ″, τ‴ in u."""
    return np.stack([d[0], d[1] * s1, d[2] * s1**2 + d[1] * s2, d[3] * s1**3 + 3 * d[2] * s1 * s2 + d[1] * s3])


@dataclass(frozen=True)
class ComposedRotation:
    """An angle law traversed with a time law: ``chain(u)`` → (τ, τ′, τ″, τ‴) at u (the time law's
    reparametrisation, as the composed path uses it); derivatives in u by :func:`chain_rule`."""

    law: object
    chain: Callable

    def all_orders(self, u: np.ndarray) -> np.ndarray:
        tau, s1, s2, s3 = self.chain(np.atleast_1d(np.asarray(u, float)))
        return chain_rule(self.law.all_orders(tau), s1, s2, s3)  # type: ignore[attr-defined]

    def __call__(self, u: np.ndarray, order: int = 0) -> np.ndarray:
        return self.all_orders(u)[order]


@dataclass(frozen=True)
class SampledRotation:
    """An angle law given by a function ``evaluate(tau, order)`` → (N,) (e.g. a spline through measured angles)."""

    evaluate: Callable

    def all_orders(self, tau: np.ndarray) -> np.ndarray:
        tau = np.atleast_1d(np.asarray(tau, float))
        return np.stack([self.evaluate(tau, k) for k in range(4)])

    def __call__(self, tau: np.ndarray, order: int = 0) -> np.ndarray:
        return self.evaluate(np.atleast_1d(np.asarray(tau, float)), order)


def transfer_window(path, z_lift: float, z_set: float, points: int = 401) -> tuple[float, float]:
    """(τa, τb): the first τ at which the path's tool height reaches ``z_lift`` [m] and the last at which it is
    still at ``z_set`` [m] or above (each to 1e-12 in τ, by bisection of the sampled crossing); (0, 1) when the
    path does not rise through both (a degenerate move: then the whole move)."""
    from scipy.optimize import brentq

    tau = np.linspace(0.0, 1.0, points)
    z = path(tau, 0)[:, 2]
    up = np.flatnonzero(z >= z_lift)
    down = np.flatnonzero(z >= z_set)
    if not up.size or not down.size:
        return 0.0, 1.0
    i, k = int(up[0]), int(down[-1])

    def height(t: float) -> float:
        return float(path(np.array([t]), 0)[0, 2])

    a = 0.0 if i == 0 else brentq(lambda t: height(t) - z_lift, tau[i - 1], tau[i], xtol=1e-12)
    b = 1.0 if k == len(tau) - 1 else brentq(lambda t: height(t) - z_set, tau[k], tau[k + 1], xtol=1e-12)
    return (float(a), float(b)) if a < b else (0.0, 1.0)


def with_rotation(path, start: float, turn: float, window: tuple[float, float] = (0.0, 1.0)):
    """``path`` (a CartesianPath) carrying the angle law of a turn by ``turn`` [rad] from ``start`` [rad] on the
    window (τa, τb); the window's ends join the path's breakpoints (not its jumps: the law is C⁴)."""
    from dataclasses import replace

    law = RotationLaw(float(start), float(turn), *window)
    extra = np.asarray(law.breakpoints, float)
    if not extra.size:
        return replace(path, angle=law)
    jumps = path.jumps if path.jumps is not None else tuple(np.asarray(path.breakpoints, float).tolist())
    breakpoints = np.unique(np.concatenate([np.asarray(path.breakpoints, float), extra]))
    return replace(path, angle=law, breakpoints=breakpoints, jumps=jumps)
