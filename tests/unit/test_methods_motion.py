"""methods/_motion.py: arc-length inversion, arc-length derivatives, law on arc length, axis laws."""

from __future__ import annotations

import numpy as np
import pytest

from pickplace_cli.curves.laws import POLY345, POLY4567
from pickplace_cli.paths._motion import (
    ArcLengthPath,
    AxisLaws,
    ParametricPiece,
    Placed,
    Placement,
    Segment,
    arc_derivatives,
    invert_monotone,
    sampled_peaks,
)


def test_invert_monotone_newton_and_bisection():
    f = lambda x: x**3 + x  # noqa: E731
    df = lambda x: 3 * x**2 + 1  # noqa: E731
    target = np.linspace(0.0, 10.0, 101)
    x = invert_monotone(f, df, target, 0.0, 3.0)
    np.testing.assert_allclose(f(x), target, atol=1e-13)  # converged to round-off of f
    # a useless derivative (always 0) forces bisection every step: still converges to the bracket width
    x2 = invert_monotone(f, lambda x: np.zeros_like(x), target, 0.0, 3.0)
    np.testing.assert_allclose(x2, x, atol=1e-12)


class _Circle(ParametricPiece):
    """Quarter circle of radius R with a non-uniform parameter: P(g) = R(cos θ, sin θ), θ = g + g²,
    g ∈ [0, g1] with θ(g1) = π/2 (speed R(1 + 2g) > 0: regular, but not unit speed)."""

    def __init__(self, R):
        self.R = R
        self.g0, self.g1 = 0.0, (-1 + np.sqrt(1 + 2 * np.pi)) / 2
        self.length = R * np.pi / 2
        self._build_table(33)

    def curve(self, g):
        R, t, t1, t2 = self.R, g + g**2, 1 + 2 * g, 2.0
        c, s = np.cos(t), np.sin(t)
        e1, e2, e3 = np.column_stack([-s, c]), np.column_stack([-c, -s]), np.column_stack([s, -c])
        P = R * np.column_stack([c, s])
        P1 = R * t1[:, None] * e1
        P2 = R * (t2 * e1 + (t1**2)[:, None] * e2)
        P3 = R * (3 * t1[:, None] * t2 * e2 + (t1**3)[:, None] * e3)
        return P, P1, P2, P3

    def arclength(self, g):
        return self.R * (g + g**2)

    def speed(self, g):
        return self.R * (1 + 2 * g)


def test_arc_derivatives_on_a_circle():
    """Unit tangent, curvature vector −x/R², and its derivative −t/R² for arc length, from a non-uniform
    parameter (θ = g + g² makes σ, σ′ non-trivial): exact formulas, so round-off tolerances."""
    c = _Circle(0.3)
    s = np.linspace(0.01, c.length - 0.01, 9)
    p, ps, pss, psss = c.at_length(s)
    ang = s / 0.3
    np.testing.assert_allclose(p, 0.3 * np.column_stack([np.cos(ang), np.sin(ang)]), atol=1e-14)
    t = np.column_stack([-np.sin(ang), np.cos(ang)])
    np.testing.assert_allclose(ps, t, atol=1e-12)
    np.testing.assert_allclose(pss, -p / 0.09, atol=1e-10)
    np.testing.assert_allclose(psss, -t / 0.09, atol=1e-9)


def test_arc_derivatives_direct():
    # straight line with a cubic parameter: P = (g³, 0) → p_s = (1, 0), p_ss = p_sss = 0
    g = np.linspace(0.5, 2, 5)
    z = np.zeros_like(g)
    ps, pss, psss = arc_derivatives(np.column_stack([3 * g**2, z]), np.column_stack([6 * g, z]), np.column_stack([6 + z, z]))
    np.testing.assert_allclose(ps, np.column_stack([1 + z, z]), atol=1e-15)
    np.testing.assert_allclose(pss, 0, atol=1e-14)
    np.testing.assert_allclose(psss, 0, atol=1e-13)


def test_law_on_a_polyline_and_a_reversed_mirrored_piece():
    """A segment, then a quarter circle placed mirrored and reversed: positions continuous at the join,
    velocity = law′·L·tangent, and derivatives agree with central differences (step 1e-6: ~1e-7)."""
    circle = _Circle(0.2)
    # the circle (from (0.2, 0) heading +v) continues the vertical segment at (0, 0.5)
    path = ArcLengthPath([Placed(Segment([0, 0], [0, 0.5])), Placed(circle, M=np.eye(2), c=np.array([-0.2, 0.5]))], POLY345)
    L = 0.5 + 0.2 * np.pi / 2
    assert path.length == pytest.approx(L, rel=1e-15)
    j = path.joints_tau()
    assert POLY345(j[1]) * L == pytest.approx(0.5, abs=1e-14)
    left, right = path(np.array([j[1] - 1e-12, j[1] + 1e-12]), 0)
    np.testing.assert_allclose(left, right, atol=1e-11)
    tau = np.array([0.1, 0.3, 0.6, 0.9])
    e = 1e-6
    for k in (1, 2, 3):
        num = (path(tau + e, k - 1) - path(tau - e, k - 1)) / (2 * e)
        np.testing.assert_allclose(path(tau, k), num, atol=1e-6 * np.abs(path(tau, k)).max() + 1e-9)
    # reversed + mirrored placement retraces the same points backwards
    back = ArcLengthPath([Placed(circle, M=np.diag([-1.0, 1.0]), reverse=True)], POLY4567)
    fwd = ArcLengthPath([Placed(circle)], POLY4567)
    t = np.linspace(0, 1, 7)
    np.testing.assert_allclose(back(t) * [-1, 1], fwd(1 - t), atol=1e-12)


def test_axis_laws_exact_peaks_and_values():
    laws = AxisLaws(u=[Placement(1.0, POLY345, 0.2, 0.6)], v=[Placement(0.1, POLY4567, 0.0, 0.4), Placement(-0.1, POLY4567, 0.6, 0.4)])
    np.testing.assert_array_equal(laws.breakpoints(), [0.0, 0.2, 0.4, 0.6, 0.8, 1.0])
    tau = np.linspace(0, 1, 200001)
    for k in (1, 2, 3):
        dense = np.linalg.norm(laws(tau, k), axis=1).max()
        exact = laws.exact_peaks()[k - 1]
        # exact ≥ every sample; the best sample (step 5e-6) is within ~1e-8 relative of a smooth max, or is
        # a one-sided limit at a breakpoint (jerk of the 3-4-5 law)
        assert exact >= dense * (1 - 1e-13) and exact <= dense * (1 + 1e-7)
    # piece polynomials reproduce the values
    br, coef = laws.piece_coefficients(0)
    i = 2
    x = np.linspace(0, br[i + 1] - br[i], 5)
    vals = np.stack([np.polyval(coef[i, a], x) for a in (0, 1)], axis=1)
    np.testing.assert_allclose(vals, laws(x + br[i]), atol=1e-14)


def test_sampled_peaks_match_dense_sampling():
    path = ArcLengthPath([Placed(_Circle(0.2))], POLY345)
    peaks = sampled_peaks(path.derivatives, path.joints_tau())
    tau = np.linspace(0, 1, 100001)
    for k in (1, 2, 3):
        dense = np.linalg.norm(path(tau, k), axis=1).max()
        assert dense <= peaks[k - 1] * (1 + 1e-12) and peaks[k - 1] <= dense * (1 + 1e-6)
