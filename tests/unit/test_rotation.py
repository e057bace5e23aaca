"""Unit tests of pickplace_cli.curves.rotation: the tool's angle law (degree-9 rest-to-rest polynomial on a window),
the turn rules, the lift-off/set-down window and the composition with a time law.

Every numeric assertion states its tolerance and why; the references are hand derivations written here.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from pickplace_cli.curves.rotation import (
    ComposedRotation, RotationLaw, TurnRule, resolve_turn, step, step_peaks, transfer_window, with_rotation,
)
from pickplace_cli.model.task import Task
from pickplace_cli.paths import plan_path


def s_hand(x, k=0):
    """s(x) = ∫₀ˣ 630 u⁴(1 − u)⁴ du and its derivatives, from the expanded integrand (hand expansion:
    630 (u⁴ − 4u⁵ + 6u⁶ − 4u⁷ + u⁸))."""
    x = np.asarray(x, float)
    integrand = [0, 0, 0, 0, 630, -2520, 3780, -2520, 630]  # coefficients of u⁰ … u⁸
    prim = np.concatenate([[0.0], [c / (n + 1) for n, c in enumerate(integrand)]])  # of u⁰ … u⁹
    poly = np.polynomial.Polynomial(prim)
    return poly.deriv(k)(x) if k else poly(x)


def test_step_polynomial_is_the_hand_derived_one():
    # the module's coefficients are the primitive of 630 x⁴(1-x)⁴ (exact rationals: 1e-12 is round-off)
    x = np.linspace(0, 1, 101)
    assert np.max(np.abs(step(x) - s_hand(x))) < 1e-12
    assert step(0.0) == 0.0 and step(1.0) == pytest.approx(1.0, abs=1e-12)


@pytest.mark.parametrize("k", [1, 2, 3, 4])
def test_step_derivatives_vanish_at_both_ends(k):
    # C⁴ rest to rest: s′ … s⁗ are zero at x = 0 and 1 (integer coefficients: 1e-9 is round-off of ~1e4 terms)
    assert abs(s_hand(0.0, k)) < 1e-9 and abs(s_hand(1.0, k)) < 1e-9
    assert abs(step(0.0, k)) < 1e-9 and abs(step(1.0, k)) < 1e-9
    # the fifth does not: the law is C⁴, not C⁵ (s⁽⁵⁾(0) = 630·4! = 15120)
    assert abs(step(0.0, 5) - 15120.0) < 1e-6


def test_step_peaks_match_dense_sampling():
    x = np.linspace(0, 1, 2_000_001)
    for k, peak in zip((1, 2, 3), step_peaks()):
        dense = np.max(np.abs(s_hand(x, k)))
        # sampled every 5e-7: a smooth maximum is missed by ~(5e-7)²·|s⁽ᵏ⁺²⁾|, below 1e-8 relative
        assert peak == pytest.approx(dense, rel=1e-8)
    assert step_peaks()[0] == pytest.approx(630 / 256, rel=1e-14)  # s′(½) = 630/2⁸, by hand


def test_law_on_a_window_values_and_derivatives():
    law = RotationLaw(0.3, -2.0, 0.2, 0.7)
    tau = np.linspace(0, 1, 1001)
    got = law.all_orders(tau)
    w = 0.5
    x = np.clip((tau - 0.2) / w, 0, 1)
    inside = (tau > 0.2) & (tau < 0.7)
    assert np.max(np.abs(got[0] - (0.3 - 2.0 * s_hand(x)))) < 1e-12  # rad, round-off
    for k in (1, 2, 3):
        ref = np.where(inside, -2.0 * s_hand(x, k) / w**k, 0.0)
        assert np.max(np.abs(got[k] - ref)) <= 1e-10 * np.max(np.abs(ref))  # round-off of the same polynomial
    # constant outside the window: the start before, the end after (exactly)
    assert np.all(got[0][tau <= 0.2] == 0.3) and np.allclose(got[0][tau >= 0.7], -1.7, atol=1e-12, rtol=0)
    # the derivatives agree with central differences of θ itself (h = 1e-4: truncation h²θ‴/6 ~ 1e-6 rel)
    h = 1e-4
    mid = np.linspace(0.05, 0.95, 37)
    fd = (law(mid + h) - law(mid - h)) / (2 * h)
    assert np.max(np.abs(law(mid, 1) - fd)) <= 1e-6 * np.max(np.abs(law(mid, 1)))


def test_law_peaks_are_exact():
    law = RotationLaw(0.0, 1.5, 0.1, 0.85)
    tau = np.linspace(0, 1, 1_500_001)
    o = law.all_orders(tau)
    for k in (1, 2, 3):
        # sampled every 6.7e-7 in τ: a smooth peak is missed by < 1e-8 relative
        assert law.peaks[k - 1] == pytest.approx(np.max(np.abs(o[k])), rel=1e-7)


def test_law_refuses_bad_windows():
    with pytest.raises(ValueError, match="window"):
        RotationLaw(0.0, 1.0, 0.5, 0.5)
    with pytest.raises(ValueError, match="turn"):
        RotationLaw(0.0, math.nan)


@pytest.mark.parametrize("a, b, rule, end", [
    (0.0, 1.0, "shortest", 1.0),
    (0.0, 5.0, "shortest", 5.0 - 2 * math.pi),          # 5 rad the long way: −1.283 rad the short way
    (3.0, -3.0, "shortest", 3.0 + (2 * math.pi - 6.0)),  # across ±π: +0.283 rad
    (0.0, math.pi, "shortest", math.pi),                # half a turn: counter-clockwise
    (0.0, -math.pi, "shortest", math.pi),
    (0.0, -1.0, "ccw", 2 * math.pi - 1.0),
    (0.0, 1.0, "cw", 1.0 - 2 * math.pi),
    (0.0, 7.0, "as-given", 7.0),
    (1.0, 1.0, "shortest", 1.0),
    (0.0, 2 * math.pi, "ccw", 0.0),                     # a whole turn counter-clockwise is no turn
])
def test_turn_rules(a, b, rule, end):
    # hand-worked end angles; 1e-12 rad is round-off of one remainder
    got = resolve_turn(a, b, rule)
    assert got == pytest.approx(end, abs=1e-12)
    if rule != "as-given":  # the same tool orientation as asked for, up to whole turns
        assert math.remainder(got - b, 2 * math.pi) == pytest.approx(0.0, abs=1e-12)
    assert TurnRule(rule).value == rule


def test_transfer_window_on_the_adept_cycle():
    task = Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5)
    path = plan_path(task, "bspline")
    z_lift = -0.8 + 0.5 * 0.025
    a, b = transfer_window(path, z_lift, z_lift)
    # the tool height at the window's ends is the lift-off height (brentq to 1e-12 in τ: z to ~1e-12 m)
    assert path(np.array([a]), 0)[0, 2] == pytest.approx(z_lift, abs=1e-10)
    assert path(np.array([b]), 0)[0, 2] == pytest.approx(z_lift, abs=1e-10)
    # below it before a and after b, at or above it in between (sampled every 1e-4)
    tau = np.linspace(0, 1, 10001)
    z = path(tau, 0)[:, 2]
    assert np.all(z[tau < a - 1e-9] < z_lift + 1e-12) and np.all(z[(tau > a + 1e-9) & (tau < b - 1e-9)] > z_lift)
    # the symmetric move: a symmetric window (1e-9)
    assert a + b == pytest.approx(1.0, abs=1e-9)
    # the path passes its via point P2 at the lift-off height exactly, so the window starts before P3 (τ = ½)
    assert 0.0 < a < 0.5 < b < 1.0


def test_with_rotation_adds_the_window_to_the_breakpoints_not_the_jumps():
    task = Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5)
    path = plan_path(task, "ph")  # a method whose jumps are its breakpoints (None)
    turned = with_rotation(path, 0.0, 1.0, (0.2, 0.8))
    assert set(np.round(turned.breakpoints, 12)) >= {0.2, 0.8}
    assert np.array_equal(np.sort(turned.jump_points), np.sort(path.jump_points))  # the law adds no jump (C⁴)
    assert isinstance(turned.angle, RotationLaw) and turned.angle_orders(np.array([0.5])).shape == (4, 1)
    assert path.angle is None and path.angle_orders(np.array([0.5])) is None


def test_composed_rotation_is_the_chain_rule():
    law = RotationLaw(0.1, 1.2, 0.0, 1.0)

    def chain(u):  # τ(u) = u² (a law that starts slow): τ′ = 2u, τ″ = 2, τ‴ = 0
        return u**2, 2 * u, np.full_like(u, 2.0), np.zeros_like(u)

    comp = ComposedRotation(law, chain)
    u = np.linspace(0.05, 0.95, 19)
    assert np.max(np.abs(comp(u) - law(u**2))) < 1e-15
    for k in (1, 2, 3):  # against 4th-order central differences of θ(τ(u)) (h = 1e-3: truncation ~1e-11)
        h = 1e-3
        f = lambda x, k=k: comp(x, k - 1)  # noqa: E731
        fd = (-f(u + 2 * h) + 8 * f(u + h) - 8 * f(u - h) + f(u - 2 * h)) / (12 * h)
        assert np.max(np.abs(comp(u, k) - fd)) <= 1e-7 * np.max(np.abs(fd))
