"""The line's fast moves (pickplace_cli/line/moves.py) against the method's own paths and duration rule.

References: plan_bspline_vel (the conveyor method, built through its own problem and solver code), its
CartesianPath's exact peaks, timing.auto_duration on those paths, the vel table's own lookup, and the limit
check's adaptive Gauss–Kronrod RMS integrals (MotionModel.rms_integrals)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pickplace_cli.line.moves import (Move, ShapeBasis, Shapes, first_feasible, search_auto, solve_auto,
                                      verify_auto)
from pickplace_cli.model.profile import load_profile
from pickplace_cli.model.task import Task
from pickplace_cli.paths.bspline_vel import plan_bspline_vel
from pickplace_cli.timing import auto_duration

PROFILE = load_profile()
SHAPE = (0.0337, 0.2212, 0.7788, 0.9663, 0.3, 0.5, 0.2)


def _random_move(rng, basis=None):
    start = np.array([rng.uniform(-0.3, 0.3), rng.uniform(0.2, 0.4), -0.8])
    v_from = np.array([0.0, rng.choice([0.0, 0.3]), 0.0])
    end_a = np.array([rng.uniform(-0.15, 0.15), rng.uniform(-0.4, 0.0), rng.choice([-0.8, -0.78])])
    belt = np.array([0.0, rng.uniform(0.2, 1.0), 0.0])
    return Move(basis or ShapeBasis(SHAPE), start, v_from, end_a, belt, belt, 0.025, 0.5)


@pytest.mark.parametrize("seed", range(4))
def test_move_is_the_methods_path(seed):
    """Samples of every order and the exact peaks equal plan_bspline_vel's path for the same task, T and shape
    (tolerance: 1e-12 m for positions, 1e-10 relative for the derivatives; both are the same spline solved two
    ways, round-off apart)."""
    rng = np.random.default_rng(seed)
    mv = _random_move(rng)
    for T in (0.12, 0.25, 0.6):
        path = plan_bspline_vel(mv.task(T), T, params=list(SHAPE))
        got = mv.samples(T)
        for k in range(4):
            ref = path(mv.basis.tau, k)
            scale = np.abs(ref).max() + 1e-300
            assert np.abs(got[k] - ref).max() <= (1e-12 if k == 0 else 1e-10 * scale)
        assert np.allclose(mv.exact_peaks(T), path.peaks, rtol=1e-10, atol=0)
        # the end conditions: at τ = 1 the part's point with the belt's velocity
        assert np.abs(got[0][-1] - mv.end(T)).max() < 1e-12
        assert np.abs(got[1][-1] / T - mv.v_to).max() < 1e-12


def test_first_feasible_against_a_fine_scan():
    """The smallest T with e(T) ≤ 0 on a function with two feasible stretches, against a scan of 2e6 points
    (tolerance: the scan's step, 1e-6 s)."""

    def e(T):
        T = np.asarray(T, float)
        return np.minimum((T - 0.3) * (T - 0.5), 0.9 - T)  # feasible in [0.3, 0.5] and for T >= 0.9

    scan = np.linspace(0.01, 2.0, 2_000_001)
    ref = scan[np.argmax(e(scan) <= 0)]
    got = first_feasible(e, 0.01, 2.0)
    assert abs(got - ref) < 1e-6
    assert first_feasible(e, 0.6, 0.8) is None
    assert first_feasible(e, 0.35, 2.0) == 0.35  # feasible at a: a


@pytest.mark.parametrize("seed", range(6))
def test_capacity_rule_holds_exactly_at_the_found_T(seed):
    """The found T meets the capacity rule on the method's own path (auto_duration ≤ T) and the same move
    planned 1e-3 shorter breaks it: T is the smallest (the rule is checked on exact peaks; 1e-3 is well above
    the search's 2e-4 safety raise)."""
    rng = np.random.default_rng(100 + seed)
    mv = _random_move(rng)
    found = search_auto([mv], PROFILE.capacity, 0.01, 5.0)
    solved = verify_auto([(found[0], found[1] * (1 + 2e-4), 5.0)], PROFILE.capacity)[0]
    T = solved.T
    for factor, holds in ((1.0, True), (1 - 1e-3, False)):
        t = T * factor
        path = plan_bspline_vel(mv.task(t), t, params=list(SHAPE))
        tv, ta, tj, _ = auto_duration(path, PROFILE.capacity)
        assert (max(tv, ta) <= t) is holds, (factor, max(tv, ta), t)
    assert abs(T / found[1] - 1) < 3e-4


def test_verify_nudges_a_short_duration_until_the_rule_holds():
    """A T too short is nudged up until the rule holds on the method's path (auto_duration); from just below the
    root it ends just above it (within 2e-4: the nudge T·T_auto/T overshoots by about the shortfall's effect on
    T_auto, small near the root); a nudge past the bound gives no move."""
    rng = np.random.default_rng(7)
    mv = _random_move(rng)
    T0 = search_auto([mv], PROFILE.capacity, 0.01, 5.0)[1]
    for start, near in ((0.95, False), (1 - 1e-4, True)):
        solved = verify_auto([(mv, start * T0, 5.0)], PROFILE.capacity)[0]
        path = plan_bspline_vel(mv.task(solved.T), solved.T, params=list(SHAPE))
        tv, ta, _, _ = auto_duration(path, PROFILE.capacity)
        assert max(tv, ta) <= solved.T
        if near:
            assert abs(solved.T / T0 - 1) < 2e-4
    assert verify_auto([(mv, 0.95 * T0, 0.96 * T0)], PROFILE.capacity) is None


def test_table_shape_is_the_tables_own_answer():
    """Shapes asks the table for the rounded groups: for a move whose groups are on the rounding grid the shape
    is exactly VelTable.lookup of the move itself (tolerance 1e-9: the canonical task of the same groups)."""
    from pickplace_cli.curves.vel_problem import task_from_groups
    from pickplace_cli.lookup.vel_table import load_vel_table

    g = {"h_over_b": math.exp(round(math.log(0.1) / 0.1) * 0.1), "eta": 0.5, "v0_along": 0.0, "v0_across": 0.0,
         "v1_along": 0.2, "v1_across": -0.15, "v0_vertical": 0.0, "v1_vertical": 0.0, "dz_over_b": 0.0}
    task = task_from_groups(g, b=0.3, duration=0.2)
    sh = Shapes()
    p, clipped = sh.table_shape(task, 0.2)
    ref = load_vel_table().lookup(task, 0.2)
    assert not clipped
    assert np.allclose(p, ref, atol=1e-9)
    assert [b.params for b in sh.candidates(task, 0.2)] == [tuple(round(x, 12) for x in p)]
    # unequal heights: the table does not apply, the paper's initial shape
    from pickplace_cli.curves.vel_problem import PAPER_INITIAL

    tall = Task(task.p_from, task.p_to + [0, 0, 0.02], 0.025, 0.5, task.v_from, task.v_to)
    assert [b.params for b in sh.candidates(tall, 0.2)] == [PAPER_INITIAL]


def test_gauss_legendre_rms_integral_against_the_limit_check():
    """∫ (A_m/T² + G_m)² dτ per motor from the move's Gauss–Legendre nodes against the limit check's adaptive
    Gauss–Kronrod integrals of the same path (MotionModel.rms_integrals; tolerance 1e-6 relative: 8 nodes per span
    on a smooth integrand, 3.4e-7 measured on 30 random moves)."""
    from pickplace_cli.limits.motion import MotionModel
    from pickplace_cli.planner import motion_model, motion_model_static

    rng = np.random.default_rng(3)
    mv = _random_move(rng)
    T = 0.22
    path = plan_bspline_vel(mv.task(T), T, params=list(SHAPE))
    (iaa, iag, igg), _ = motion_model(path, PROFILE).rms_integrals()
    ref = T * (iaa / T**4 + 2 * iag / T**2 + igg)
    robot, specs, margin, box, memo = motion_model_static(PROFILE)
    model = MotionModel(path, robot, specs, margin, box, memo)
    s = mv.samples(T)
    parts = model.parts(mv.basis.tau, motion=tuple(s))
    torque = parts.Am / T**2 + parts.Gm
    b = mv.basis
    got = T * (b.gl_weight[:, None] * torque[b.gl_index] ** 2).sum(axis=0)
    assert np.allclose(got, ref, rtol=1e-6, atol=0)


def test_solve_auto_keeps_the_better_candidate():
    """Of two shapes, solve_auto returns the move of the smaller rule duration (each checked alone)."""
    from pickplace_cli.curves.vel_problem import PAPER_INITIAL

    rng = np.random.default_rng(11)
    a = _random_move(rng)
    b = Move(ShapeBasis(PAPER_INITIAL), a.start, a.v_from, a.end_a, a.end_b, a.v_to, 0.025, 0.5)
    one = [solve_auto([m], PROFILE.capacity, 0.01, 5.0).T for m in (a, b)]
    both = solve_auto([a, b], PROFILE.capacity, 0.01, 5.0)
    assert both.T == pytest.approx(min(one), rel=1e-9)


def test_one_duration_s_peaks_are_the_grid_s():
    """peaks_at (the search's scalar steps) = grid_peaks at that duration, bit for bit (one estimate)."""
    rng = np.random.default_rng(3)
    mv = _random_move(rng)
    for T in rng.uniform(0.1, 1.0, 5):
        assert np.array_equal(np.array(mv.peaks_at(float(T))), mv.grid_peaks(np.array([T]))[0])


def test_screened_limit_use_against_the_exact_check():
    """The use of every limit from the move's check grid (model once, parabola at the top sample) against the
    project's exact limit check on the method's path, on 40 random moves: within 1 % (the screening decides a leg
    only below 90 % use; measured 0.2 %)."""
    from pickplace_cli.limits.check import check_limits
    from pickplace_cli.limits.motion import MotionModel
    from pickplace_cli.curves.peaks import parabolic_peak
    from pickplace_cli.line.robot import UsePlan
    from pickplace_cli.planner import motion_model, motion_model_static

    rng = np.random.default_rng(1)
    worst = 0.0
    for _ in range(40):
        shape = (rng.uniform(0.01, 0.05), rng.uniform(0.15, 0.3), rng.uniform(0.7, 0.85), rng.uniform(0.95, 0.99),
                 rng.uniform(0, 1), 0.5, rng.uniform(0, 1))
        mv = _random_move(rng, ShapeBasis(shape))
        T = rng.uniform(0.15, 0.3)
        path = mv.path(T)
        rep = check_limits(motion_model(path, PROFILE), T, dwell=0.0)
        model = MotionModel(path, *motion_model_static(PROFILE))
        parts = model.parts(mv.basis.tau, motion=tuple(mv.samples(T)))
        meta, data = model.columns(parts, np.full(len(mv.basis.tau), T))
        plan = UsePlan(meta)
        use = dict(zip(plan.keys, plan(parabolic_peak(mv.basis.tau, data)[0][None])[0]))
        for r in rep.rows:
            if (r.joint, r.quantity) in use and r.utilisation > 0.05:
                worst = max(worst, abs(use[(r.joint, r.quantity)] / r.utilisation - 1))
    assert worst < 0.01
