"""Reproduce Yang, Xie & Liu 2022 (velocity-constrained B-spline for conveyor tracking).

The paper prints no optimised numbers for its Sec. 2.3.1 example (Fig. 3 is a plot of the iterations), so
for that example the tests check what it does state — the set-up, the end velocities, the degenerate λ2
(v0 = v1), Fig. 2's convexity in λ — and pin our optimum (values in README) with the optimiser's
tolerance. For the Adept cycle of Sec. 3 the paper reports measured accelerations: "the acceleration on
the x-axis changes little, but the peak acceleration on the y-axis decreases by 26.37 %", which we compare
with the planned (commanded) accelerations.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from pickplace_cli.paths import bspline_vel as bv

from pickplace_cli.lookup import vel_slsqp as vq

from pickplace_cli.curves import vel_problem as vp
from pickplace_cli.model.task import Task
from pickplace_cli.model.trajectory import CartesianTrajectory

MM = 1e-3
# Sec. 2.3.1: (0,0,0) → (280, −200, 0) mm, 40 mm high, T = 0.250 s, 200 mm/s at both ends along +y, η = 0.5
EXAMPLE = Task([0, 0, 0], [280 * MM, -200 * MM, 0], 40 * MM, 0.5, [0, 0.2, 0], [0, 0.2, 0])
T_EXAMPLE = 0.250
# Sec. 3: Adept cycle with velocity: (∓305/(2√2), ±305/(2√2), −650) mm, 25 mm high, η = 0.5, 200 mm/s along
# +y at both ends, T = 0.213 s (the paper's trajectory-time network for the SR4 robot; an input here)
C = 305 * MM / (2 * math.sqrt(2))
ADEPT = Task([-C, C, -0.650], [C, -C, -0.650], 25 * MM, 0.5, [0, 0.2, 0], [0, 0.2, 0])
T_ADEPT = 0.213


def _peaks(task, T, params):
    """Physical (v, a, j) peaks [m/s, m/s², m/s³] and the trajectory of the path with ``params``."""
    traj = CartesianTrajectory(bv.plan_bspline_vel(task, T, params=params), T)
    return traj.peaks(), traj


@pytest.fixture(scope="module")
def example():
    return bv.solve(bv.make_problem(EXAMPLE, T_EXAMPLE))


@pytest.fixture(scope="module")
def adept():
    return bv.solve(bv.make_problem(ADEPT, T_ADEPT))


def test_example_setup_end_velocities_and_degenerate_lambda2(example):
    """The example's conveyor velocities are met exactly (1e-13 m/s: round-off), and λ2 is degenerate:
    v0 = v1, so the offset (v0 − v1)/2·λ2·T of Eq. 26 vanishes; it is held at the paper's 0.50."""
    path = bv.plan_bspline_vel(EXAMPLE, T_EXAMPLE, params=example.params)
    traj = CartesianTrajectory(path, T_EXAMPLE)
    np.testing.assert_allclose(traj(np.array([0.0, T_EXAMPLE]), 1), [[0, 0.2, 0], [0, 0.2, 0]], atol=1e-13)
    assert example.lambda_free == (True, False, True)
    assert example.params[5] == 0.5


def test_example_optimum_and_reduction_against_the_initial_guess(example):
    """From the paper's initial guess (0.01, 0.21, 0.79, 0.99, 0.21, 0.50, 0.21) the optimum of Eq. 37
    (margin 0.01) lowers a_max by 7.6 % and j_max by 29.9 % and raises F from 1.474 to 1.832.

    The paper gives no numbers for this example (Fig. 3 is a plot); these are ours, pinned at the
    optimiser's tolerance (parameters 1e-4, peaks and F 1e-4 relative). The optimum has λ1 = λ3 = 0: for
    this move (the belt runs across it, partly backwards), offsetting the lift-off and set-down points
    along the belt only lengthens the path."""
    (v0, a0, j0), _ = _peaks(EXAMPLE, T_EXAMPLE, bv.PAPER_INITIAL)
    (v1, a1, j1), _ = _peaks(EXAMPLE, T_EXAMPLE, example.params)
    np.testing.assert_allclose(example.params, [0.03374, 0.22117, 0.77883, 0.96626, 0.0, 0.5, 0.0], atol=1e-4)
    assert a0 == pytest.approx(66.085, rel=1e-4) and j0 == pytest.approx(2933.3, rel=1e-4)
    assert a1 == pytest.approx(61.089, rel=1e-4) and j1 == pytest.approx(2057.1, rel=1e-4)
    assert 1 - a1 / a0 == pytest.approx(0.0756, abs=1e-3) and 1 - j1 / j0 == pytest.approx(0.2987, abs=1e-3)
    scale = bv.make_problem(EXAMPLE, T_EXAMPLE).scale
    f0 = (example.a_min * scale / T_EXAMPLE**2) / a0 + (example.j_min * scale / T_EXAMPLE**3) / j0
    assert f0 == pytest.approx(1.4744, abs=1e-4) and example.F == pytest.approx(1.8319, abs=1e-4)


def test_fig2_peaks_are_convex_in_each_lambda():
    """Fig. 2: for given knots, a_max and j_max are convex in each λ_i (a maximum of norms of affine
    functions of λ: exact). Checked on a 21-point grid of each free λ at the initial knots: second
    differences ≥ −1e-9 of the peak (round-off of the exact peaks)."""
    prob = bv.make_problem(EXAMPLE, T_EXAMPLE)
    for i in (4, 6):  # λ1, λ3 (λ2 is degenerate here)
        vals = []
        for lam in np.linspace(0, 1, 21):
            p = list(bv.PAPER_INITIAL)
            p[i] = lam
            vals.append(bv.exact_peaks(prob, p)[1:])
        vals = np.array(vals)
        assert np.all(np.diff(vals, 2, axis=0) >= -1e-9 * vals.max(axis=0))


def test_adept_cycle_with_velocity_section3(adept):
    """Sec. 3 (Fig. 12): after optimisation "the acceleration on the x-axis changes little, but the peak
    acceleration on the y-axis decreases by 26.37 %" (measured with an accelerometer on the SR4 robot).

    Planned accelerations: y peak −28.9 %, x peak −1.5 %. Tolerance ±5 percentage points on y (the paper
    measures the real robot — arm compliance and the sensor's filtering change peaks — we compare the
    commanded motion); "little" on x taken as |change| < 5 %. Also the Cartesian a_max and j_max fall
    (−16.0 %, −24.5 %; the paper's joint jerk falls 26.68 % on the SR4, a robot we do not model)."""
    (_, a0, j0), tr0 = _peaks(ADEPT, T_ADEPT, bv.PAPER_INITIAL)
    (_, a1, j1), tr1 = _peaks(ADEPT, T_ADEPT, adept.params)
    t = np.linspace(0, T_ADEPT, 100_001)
    acc0, acc1 = np.abs(tr0(t, 2)).max(axis=0), np.abs(tr1(t, 2)).max(axis=0)
    y_drop = 1 - acc1[1] / acc0[1]
    x_change = acc1[0] / acc0[0] - 1
    assert y_drop == pytest.approx(0.2637, abs=0.05)
    assert abs(x_change) < 0.05
    assert y_drop == pytest.approx(0.2896, abs=2e-3)  # our value (README), at sampling precision
    assert 1 - a1 / a0 == pytest.approx(0.1604, abs=2e-3) and 1 - j1 / j0 == pytest.approx(0.2453, abs=2e-3)
    # the belt velocity is met exactly at pick and place
    np.testing.assert_allclose(tr1(np.array([0.0, T_ADEPT]), 1), [[0, 0.2, 0], [0, 0.2, 0]], atol=1e-13)


def test_rest_to_rest_degenerates_to_li2018():
    """v0 = v1 = 0: every λ is degenerate and the four free knots settle symmetric, on the optimum of the
    bspline method: with a margin of 1e-3, k1 = 2τ7 and k2 = τ6/τ7 equal the shipped Li table's (k1, k2) to
    1e-3, and j_min equals the table's j_min to 1e-8 relative (a_min differs only through the margin: the
    Li table reaches k2 = 1e-4)."""
    from pickplace_cli.lookup.bspline_table import load_table

    tab = load_table()
    for lam in (5.0, 28.0):
        task = Task([0, 0, 0], [lam * 0.025, 0, 0], 0.025, 0.5)
        res = bv.solve(bv.make_problem(task, 1.0), bv.VelSettings(margin=1e-3))
        t6, t7, t9, t10 = res.params[:4]
        assert t9 == pytest.approx(1 - t7, abs=1e-5) and t10 == pytest.approx(1 - t6, abs=1e-5)
        k1, k2 = tab.lookup(lam)
        assert 2 * t7 == pytest.approx(k1, abs=1e-3) and t6 / t7 == pytest.approx(k2, abs=1e-3)
        row = next(r for r in tab.rows if r.lam == lam)
        assert res.j_min == pytest.approx(row.j_min, rel=1e-6)
        assert row.a_min <= res.a_min <= row.a_min * 1.005


def _de_solve(prob, margin=0.01, seed=1):
    """Independent global optimum of the three stages by scipy's differential_evolution (on sampled
    peaks, 32 samples per knot span; then exact peaks at its result)."""
    from scipy.optimize import differential_evolution

    space = vq._Space(prob.lambda_free, margin)
    ev = vp._Evaluator(prob)
    grid = vp._grid(32)

    def peaks(u):
        ga, gj = ev.sampled(space.full(space.from_unit(np.atleast_2d(u.T))), *grid)
        return np.sqrt(ga.max(axis=1)), np.sqrt(gj.max(axis=1))

    kw = dict(vectorized=True, updating="deferred", popsize=15, tol=1e-8, maxiter=250, seed=seed, polish=False)
    bounds = [(0, 1)] * space.n
    ra = differential_evolution(lambda u: peaks(u)[0], bounds, **kw)
    rj = differential_evolution(lambda u: peaks(u)[1], bounds, **kw)

    def full(u):
        return space.full(space.from_unit(np.atleast_2d(u)))[0]

    a_min = bv.exact_peaks(prob, full(ra.x))[1]
    j_min = bv.exact_peaks(prob, full(rj.x))[2]
    rf = differential_evolution(lambda u: -(a_min / peaks(u)[0] + j_min / peaks(u)[1]), bounds, **kw)
    _, a, j = bv.exact_peaks(prob, full(rf.x))
    return a_min, j_min, a, j


@pytest.mark.slow
@pytest.mark.parametrize(
    "task,T",
    [
        (EXAMPLE, T_EXAMPLE),
        (ADEPT, T_ADEPT),
        (Task([0, 0, -0.7], [0.3, 0.1, -0.7], 0.05, 0.5, [0.25, -0.1, 0], [-0.1, 0.3, 0]), 0.3),
    ],
    ids=["example", "adept", "general"],
)
def test_global_optimum_agrees_with_differential_evolution(task, T):
    """The paper solves Eq. 37 by one interior-point run and argues convexity; F is not convex (it can have
    two local maxima), so we check our multi-start solve against an independent global method. Our
    minima of a_max and j_max are at least as low as DE's (to 1e-4: DE stops on sampled peaks) and our F,
    with common normalisers, at least as high (to 1e-4)."""
    prob = bv.make_problem(task, T)
    res = bv.solve(prob)
    a_de, j_de, a, j = _de_solve(prob)
    assert res.a_min <= a_de * (1 + 1e-4) and res.j_min <= j_de * (1 + 1e-4)
    A, J = min(a_de, res.a_min), min(j_de, res.j_min)
    assert A / res.a_max + J / res.j_max >= A / a + J / j - 1e-4
