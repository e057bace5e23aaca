"""Normalised motion laws s(u): rest-to-rest rises from s(0) = 0 to s(1) = 1 on u ∈ [0, 1].

Convention (the package's one evaluation convention): ``law(u, order=0)`` returns d^order s/du^order,
vectorised over ``u``; outside [0, 1] the law is at rest (s = 0 before, 1 after, every derivative 0), so a
law can be placed on a time interval and superposed with others (:meth:`MotionLaw.over`).

The laws are polynomials, so every derivative is closed form and the peaks are exact (roots of the next
derivative). Shipped laws:

* ``3-4-5`` s = 10u³ − 15u⁴ + 6u⁵ [Su2018, Eq. (19)]: velocity and acceleration vanish at both ends, the
  jerk does not (s‴(0) = s‴(1) = 60), so a move built on it has a jerk step at start and stop.
  Peaks: v 15/8, a 10/√3, j 60.
* ``4-5-6-7`` s = 35u⁴ − 84u⁵ + 70u⁶ − 20u⁷ (the C³ law Li 2018 uses for its baselines, [Li2018, Sec. 3.2]):
  velocity, acceleration and jerk vanish at both ends. Peaks: v 35/16, a 7.5132, j 52.5.

Units: u and s are dimensionless; scaled by a distance D [m] and a duration d [s], the k-th time
derivative is D/d^k · s^(k).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import Enum

import numpy as np

from ..model.errors import TaskError


#: relative distance from a law's ends under which :meth:`MotionLaw.over` snaps to the end
_SNAP = 1e-12


@dataclass(frozen=True)
class MotionLaw:
    """A polynomial rise s(u) = Σ c_k u^k on [0, 1] with s(0) = 0, s(1) = 1 (rest outside [0, 1]).

    ``coefficients`` are in the power basis, ascending (c_0, c_1, …). ``rest_order`` is the highest
    derivative that vanishes at both ends (2: velocity and acceleration; 3: also jerk), i.e. the law joined
    to rest before and after is C^rest_order.
    """

    name: str
    coefficients: tuple[float, ...]
    _derivs: tuple = field(init=False, repr=False, compare=False)
    _horner: tuple = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        p = np.polynomial.Polynomial(self.coefficients)
        if abs(p(0.0)) > 1e-12 or abs(p(1.0) - 1.0) > 1e-12:
            raise ValueError(f"law {self.name}: s(0) must be 0 and s(1) must be 1, got {p(0.0)}, {p(1.0)}")
        object.__setattr__(self, "_derivs", tuple(p.deriv(k) for k in range(p.degree() + 2)))
        # Horner tables (highest power first) for the fast path of __call__
        object.__setattr__(self, "_horner", tuple(tuple(d.coef[::-1].tolist()) for d in self._derivs))

    @property
    def degree(self) -> int:
        return len(self.coefficients) - 1

    def polynomial(self, order: int = 0) -> np.polynomial.Polynomial:
        """d^order s/du^order as a numpy Polynomial on [0, 1] (zero beyond the degree)."""
        if order < 0:
            raise ValueError(f"order must be ≥ 0, got {order}")
        return self._derivs[min(order, len(self._derivs) - 1)]

    def __call__(self, u: np.ndarray | float, order: int = 0) -> np.ndarray:
        """d^order s/du^order at u (array); at rest outside [0, 1]."""
        u = np.asarray(u, dtype=float)
        if order < 0:
            raise ValueError(f"order must be ≥ 0, got {order}")
        coef = self._horner[min(order, len(self._horner) - 1)]
        x = np.minimum(np.maximum(u, 0.0), 1.0)
        inside = np.full_like(x, coef[0])
        for c in coef[1:]:
            inside = inside * x + c
        if order == 0:
            return np.where(u <= 0.0, 0.0, np.where(u >= 1.0, 1.0, inside))
        return np.where((u < 0.0) | (u > 1.0), 0.0, inside)

    @property
    def rest_order(self) -> int:
        """Highest k such that s^(1..k) vanish at u = 0 and u = 1."""
        k = 0
        while k + 1 <= self.degree and all(abs(self.polynomial(k + 1)(x)) < 1e-12 for x in (0.0, 1.0)):
            k += 1
        return k

    def peak(self, order: int) -> float:
        """Exact max over [0, 1] of |s^(order)| (ends or roots of s^(order+1))."""
        p = self.polynomial(order)
        cand = [0.0, 1.0]
        dp = self.polynomial(order + 1)
        if dp.degree() > 0 or np.any(dp.coef):
            cand += [r.real for r in dp.roots() if abs(r.imag) < 1e-12 and 0.0 <= r.real <= 1.0]
        return float(max(abs(p(x)) for x in cand))

    @property
    def peaks(self) -> tuple[float, float, float]:
        """(max |s′|, max |s″|, max |s‴|) on [0, 1]."""
        return self.peak(1), self.peak(2), self.peak(3)

    def over(self, t: np.ndarray, start: float, duration: float, order: int = 0) -> np.ndarray:
        """The law run from ``start`` for ``duration`` (same units as t): d^order/dt^order of s((t − start)/duration).

        ``duration`` = 0 is a step at ``start`` (value 0 before, 1 from ``start`` on; derivatives 0).
        A u = (t − start)/duration within 1e-12 of 0 or 1 counts as the end itself, so a law placed to end
        at τ = 1 by ``start + duration`` (which round-off may leave at 1 − 1e-16) still shows its one-sided
        value at τ = 1 rather than the rest beyond it.
        """
        t = np.asarray(t, dtype=float)
        if duration <= 0.0:
            return (t >= start).astype(float) if order == 0 else np.zeros_like(t)
        u = (t - start) / duration
        u = np.where(np.abs(u - 1.0) <= _SNAP, 1.0, np.where(np.abs(u) <= _SNAP, 0.0, u))
        return self(u, order) / duration**order

    def piece_coefficients(self, start: float, duration: float, origin: float) -> np.ndarray:
        """Ascending power coefficients of s((t − start)/duration) in x = t − origin (exact piecewise peaks).

        Taylor expansion about u0 = (origin − start)/duration: c_k = s^(k)(u0)/(k!·duration^k), exact for a
        polynomial law (the polynomial itself, not its restriction to [0, 1]).
        """
        if duration <= 0.0:
            raise ValueError(f"duration must be > 0, got {duration}")
        u0 = (origin - start) / duration
        out = np.empty(self.degree + 1)
        for k in range(self.degree + 1):
            val = 0.0
            for c in self._horner[k]:
                val = val * u0 + c
            out[k] = val / (math.factorial(k) * duration**k)
        return out

    def piece_polynomials(self, start: float, duration: float, origin: float) -> np.polynomial.Polynomial:
        """s((t − start)/duration) as a Polynomial in x = t − origin (see :meth:`piece_coefficients`)."""
        return np.polynomial.Polynomial(self.piece_coefficients(start, duration, origin))


#: 3-4-5 polynomial [Su2018, Eq. (19)]
POLY345 = MotionLaw("3-4-5", (0.0, 0.0, 0.0, 10.0, -15.0, 6.0))
#: 4-5-6-7 polynomial [Li2018, Sec. 3.2] (the C³ law of its Lamé and piecewise baselines)
POLY4567 = MotionLaw("4-5-6-7", (0.0, 0.0, 0.0, 0.0, 35.0, -84.0, 70.0, -20.0))


class Law(str, Enum):
    """Names of the shipped laws."""

    poly345 = "3-4-5"
    poly4567 = "4-5-6-7"


LAWS: dict[Law, MotionLaw] = {Law.poly345: POLY345, Law.poly4567: POLY4567}


def poly345(u: np.ndarray | float, order: int = 0) -> np.ndarray:
    """The 3-4-5 law s = 10u³ − 15u⁴ + 6u⁵ and its derivatives [Su2018, Eq. (19)]."""
    return POLY345(u, order)


def poly4567(u: np.ndarray | float, order: int = 0) -> np.ndarray:
    """The 4-5-6-7 law s = 35u⁴ − 84u⁵ + 70u⁶ − 20u⁷ and its derivatives [Li2018, Sec. 3.2]."""
    return POLY4567(u, order)


def get_law(name: Law | str | MotionLaw) -> MotionLaw:
    """A MotionLaw by name ("3-4-5", "4-5-6-7") or itself; TaskError naming the choices otherwise."""
    if isinstance(name, MotionLaw):
        return name
    try:
        return LAWS[Law(name)]
    except ValueError:
        raise TaskError(f"law = {name!r}: choose one of {', '.join(x.value for x in Law)}") from None
