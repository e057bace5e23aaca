"""Invariants of the B-spline path over random valid moves (hypothesis)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from pickplace_cli.curves.bspline import li_knots
from pickplace_cli.paths.bspline import plan_bspline
from pickplace_cli.model.task import Task
from pickplace_cli.model.trajectory import CartesianTrajectory

coord = st.floats(-0.5, 0.5, allow_nan=False)
k = st.floats(0.05, 0.95)


@st.composite
def moves(draw):
    p0 = np.array([draw(coord), draw(coord), draw(st.floats(-0.9, -0.6))])
    p1 = np.array([draw(coord), draw(coord), draw(st.floats(-0.9, -0.6))])
    if np.linalg.norm(p1[:2] - p0[:2]) < 1e-3:
        p1[0] += 0.05
    return Task(p0, p1, draw(st.floats(0.005, 0.2)), draw(st.floats(0.1, 0.9)))


@settings(max_examples=60, deadline=None)
@given(moves(), k, k)
def test_passes_via_points_and_rests(task, k1, k2):
    path = plan_bspline(task, k1=k1, k2=k2)
    t = li_knots(k1, k2)
    np.testing.assert_allclose(path(t[[0, 7, 8, 9, 16]]), task.via_points(), atol=1e-12)
    move = np.linalg.norm(task.via_points() - task.p_from, axis=1).max()
    for r in (1, 2, 3):
        ends = np.linalg.norm(path(np.array([0.0, 1.0]), r), axis=1)
        # rest at both ends, up to the round-off of Σ Q_i N_i^(r) with |N^(r)| ≤ ~(2/τ7)^r:
        # 1e-13 · |move| · (2/τ7)^r (a wrong boundary row would give O(peak), many orders larger)
        bound = 1e-13 * move * (2.0 / (k1 * k2 / 2)) ** r
        assert np.all(ends <= bound), (r, ends, bound)
        assert bound < 1e-3 * path.peaks[r - 1]  # the bound itself is tight enough to mean "zero"


@settings(max_examples=40, deadline=None)
@given(moves(), k, k)
def test_jerk_continuous_across_knots(task, k1, k2):
    """Quintic with simple interior knots is C4: jerk and its derivative match on both sides of a knot."""
    path = plan_bspline(task, k1=k1, k2=k2)
    knots = li_knots(k1, k2)[6:11]
    eps = 1e-9
    for r in (3,):
        left = path(knots - eps, r)
        right = path(knots + eps, r)
        # |jerk| jumps by at most |snap| * 2 eps at a C4 knot: far below 1e-6 of the jerk peak
        assert np.max(np.abs(left - right)) <= 1e-6 * path.peaks[2]


@settings(max_examples=40, deadline=None)
@given(moves(), k, k, st.floats(0.05, 2.0), st.floats(0.1, 10.0))
def test_scaling_laws(task, k1, k2, duration, scale):
    """Scaling b (and h) by s and T by c scales v, a, j by s/c, s/c², s/c³ exactly."""
    path = plan_bspline(task, k1=k1, k2=k2)
    big = Task(task.p_from * scale, task.p_to * scale, task.height * scale, task.eta)
    path_big = plan_bspline(big, k1=k1, k2=k2)
    tr = CartesianTrajectory(path, 1.0)
    tr_big = CartesianTrajectory(path_big, duration)
    for got, ref, n in zip(tr_big.peaks(), tr.peaks(), (1, 2, 3)):
        assert np.isclose(got, ref * scale / duration**n, rtol=1e-9)
    tau = np.linspace(0.02, 0.98, 7)  # interior: the ends are round-off zeros, checked in the rest test
    for r in (1, 2, 3):
        np.testing.assert_allclose(tr_big(tau * duration, r), tr(tau, r) * scale / duration**r, rtol=1e-9, atol=1e-9 * tr.peaks()[r - 1] * scale / duration**r)


@settings(max_examples=30, deadline=None)
@given(moves(), k, k)
def test_derivatives_are_analytic(task, k1, k2):
    """Velocity equals a central difference of position to the O(h²) truncation of the difference."""
    path = plan_bspline(task, k1=k1, k2=k2)
    tau = np.linspace(0.05, 0.95, 9)
    h = 1e-6
    fd = (path(tau + h) - path(tau - h)) / (2 * h)
    np.testing.assert_allclose(path(tau, 1), fd, atol=1e-5 * path.peaks[0])
