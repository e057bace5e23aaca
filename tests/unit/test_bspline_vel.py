"""methods/bspline_vel.py: the conveyor-tracking B-spline of Yang 2022 (Eq. 23-37) and its exact solve."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pickplace_cli.model.errors import TaskError
from pickplace_cli.paths import bspline_vel as bv
from pickplace_cli.lookup import vel_solver as vs
from pickplace_cli.lookup import vel_slsqp as vq
from pickplace_cli.curves import vel_problem as vp
from pickplace_cli.model.task import Task
from pickplace_cli.model.trajectory import CartesianTrajectory

# Yang 2022 Sec. 2.3.1 example: (0,0,0) → (280, −200, 0) mm, 40 mm high, T = 0.25 s, 200 mm/s along +y
EXAMPLE = Task([0, 0, 0], [0.28, -0.2, 0], 0.04, 0.5, [0, 0.2, 0], [0, 0.2, 0])
T_EX = 0.25
# a move with different end velocities (all three λ matter) and unequal heights
GENERAL = Task([-0.1, 0.05, -0.8], [0.15, -0.1, -0.78], 0.03, 0.4, [0.25, 0.1, 0.0], [-0.05, 0.3, 0.02])


def test_via_points_follow_eq25_to_28():
    """The path passes s0 … s4 of Eq. 25-28 at τ = 0, τ7, ½, τ9, 1 (to round-off of O(1) values)."""
    T = 0.3
    p = (0.03, 0.2, 0.75, 0.95, 0.3, 0.6, 0.4)
    path = bv.plan_bspline_vel(GENERAL, T, params=p)
    base = GENERAL.via_points()
    v0, v1 = GENERAL.v_from, GENERAL.v_to
    want = base.copy()
    want[1] += v0 * p[4] * T  # Eq. 25
    want[2] += (v0 - v1) / 2 * p[5] * T  # Eq. 26
    want[3] -= v1 * p[6] * T  # Eq. 27
    np.testing.assert_allclose(path(np.array([0, p[1], 0.5, p[2], 1.0])), want, atol=1e-13)


@pytest.mark.parametrize("task,T", [(EXAMPLE, T_EX), (GENERAL, 0.3)])
def test_end_velocities_exact_and_acceleration_jerk_zero_at_ends(task, T):
    """Eq. 24 boundary rows: v(0) = v0, v(T) = v1 to round-off (1e-13 m/s); a and j vanish at both ends
    (they cancel between control points ~|N‴| ~ 1/τ6³ apart: 1e-7 m/s², m/s³ of peaks ~1e2, 1e4)."""
    path = bv.plan_bspline_vel(task, T)
    traj = CartesianTrajectory(path, T)
    ends = np.array([0.0, T])
    np.testing.assert_allclose(traj(ends, 1), [task.v_from, task.v_to], atol=1e-13)
    np.testing.assert_allclose(traj(ends, 2), 0.0, atol=1e-7)
    np.testing.assert_allclose(traj(ends, 3), 0.0, atol=1e-6)
    np.testing.assert_allclose(traj(ends, 0), [task.p_from, task.p_to], atol=1e-14)


def test_continuity_c4_inside_the_move():
    """Quintic B-spline with simple interior knots: derivatives 0-4 continuous at every interior knot
    (one-sided limits at ±1e-9 agree to 1e-5 of the derivative's scale), the 5th jumps."""
    path = bv.plan_bspline_vel(GENERAL, 0.3)
    spline_knots = path.breakpoints[1:-1]
    eps = 1e-9
    for order in range(5):
        peak = np.abs(_deriv(path, np.linspace(0, 1, 2001), order)).max()
        for k in spline_knots:
            left, right = _deriv(path, np.array([k - eps]), order), _deriv(path, np.array([k + eps]), order)
            assert np.abs(left - right).max() <= 1e-5 * peak
    jumps = [np.abs(_deriv(path, np.array([k - eps]), 5) - _deriv(path, np.array([k + eps]), 5)).max() for k in spline_knots]
    assert max(jumps) > 1e-3  # the crackle is piecewise constant: C4, not C5


def _deriv(path, tau, order):
    """Derivative of any order of the path's spline (CartesianPath stops at jerk)."""
    prob = bv.make_problem(GENERAL, path.parameters["duration_s"])
    spline = bv.spline_of(prob, [path.parameters[n] for n in bv.PARAM_NAMES])
    return prob.scale * spline(tau, nu=order)


def test_path_depends_on_duration_and_records_it():
    """The same task planned for two durations has different normalised paths (end slope v·T)."""
    a = bv.plan_bspline_vel(EXAMPLE, 0.25, params=bv.PAPER_INITIAL)
    b = bv.plan_bspline_vel(EXAMPLE, 0.5, params=bv.PAPER_INITIAL)
    np.testing.assert_allclose(a(np.array([0.0]), 1)[0], EXAMPLE.v_from * 0.25, atol=1e-14)
    np.testing.assert_allclose(b(np.array([0.0]), 1)[0], EXAMPLE.v_from * 0.5, atol=1e-14)
    assert a.parameters["duration_s"] == 0.25 and b.parameters["duration_s"] == 0.5


def test_degenerate_lambdas_are_detected_and_held():
    """λ2 has no effect when v0 = v1 (offset (v0 − v1)/2 = 0), λ1 none when v0 = 0, λ3 none when v1 = 0:
    they are dropped from the optimisation and held at the paper's initial value."""
    assert bv.make_problem(EXAMPLE, T_EX).lambda_free == (True, False, True)
    still = Task([0, 0, 0], [0.28, -0.2, 0], 0.04, 0.5, [0, 0, 0], [0, 0.2, 0])
    assert bv.make_problem(still, T_EX).lambda_free == (False, True, True)
    res = bv.solve(bv.make_problem(EXAMPLE, T_EX))
    assert res.params[5] == bv.PAPER_INITIAL[5]
    # λ2 really has no effect there: the path is the same for any λ2
    p = list(res.params)
    a = bv.plan_bspline_vel(EXAMPLE, T_EX, params=p)
    p[5] = 0.9
    b = bv.plan_bspline_vel(EXAMPLE, T_EX, params=p)
    x = np.linspace(0, 1, 101)
    np.testing.assert_allclose(a(x), b(x), atol=1e-15)


def test_exact_peaks_bound_dense_samples():
    """Reported peaks are the exact maxima: ≥ every one of 200,001 samples and within 1e-6 of their max."""
    path = bv.plan_bspline_vel(GENERAL, 0.3)
    x = np.linspace(0, 1, 200_001)
    for k, peak in zip((1, 2, 3), path.peaks):
        sampled = np.linalg.norm(path(x, k), axis=1).max()
        assert peak >= sampled * (1 - 1e-12)
        assert peak == pytest.approx(sampled, rel=1e-6)


def test_batched_evaluator_matches_scipy():
    """The optimiser's batched evaluation (control points, Taylor coefficients per span) equals the scipy
    spline's acceleration and jerk, to 1e-12 relative, for several parameter vectors at once."""
    prob = bv.make_problem(GENERAL, 0.3)
    rng = np.random.default_rng(0)
    space = vq._Space((True, True, True), 0.01)
    params = space.full(space.from_unit(rng.uniform(size=(4, 7))))
    ev = vp._Evaluator(prob)
    piece, u = vp._grid(7)
    ga, gj = ev.sampled(params, piece, u)
    for p, a2, j2 in zip(params, ga, gj):
        s = bv.spline_of(prob, p)
        brk = s.t[5:12]
        x = brk[piece] + u * (brk[piece + 1] - brk[piece])
        ra, rj = np.sum(s(x, nu=2) ** 2, axis=1), np.sum(s(x, nu=3) ** 2, axis=1)
        np.testing.assert_allclose(a2, ra, rtol=1e-10, atol=1e-12 * ra.max())
        np.testing.assert_allclose(j2, rj, rtol=1e-10, atol=1e-12 * rj.max())


def test_taylor_form_evaluator_matches_the_bspline_route():
    """The optimiser's piecewise-Taylor evaluation (two-sided shooting, one 8 × 8 solve per vector) gives
    the Taylor coefficients of the B-spline route (control points of Eq. 16 on the Cox–de Boor basis) to
    1e-9 of their scale, on 300 quasi-random feasible vectors including knots on the margin (round-off
    of the shooting across spans 0.01 … 0.48 wide; measured worst 2e-11)."""
    prob = bv.make_problem(GENERAL, 0.3)
    space = vq._Space((True, True, True), 0.01)
    params = space.full(space.from_unit(vs._quasi_random(300, 7)))
    params[:3, 0], params[:3, 3] = 0.01, 0.99
    ev = vp._Evaluator(prob)
    w1, d1 = ev.prepare(params)
    w0, d0 = ev.prepare_bspline(params)
    np.testing.assert_array_equal(w0, w1)
    scale = np.abs(d0).max(axis=(1, 2, 3), keepdims=True)
    assert np.all(np.abs(d1 - d0) <= 1e-9 * scale)


def test_exact_segment_maxima_are_the_maxima():
    """Each segment's maximum (roots of d‖·‖²/dτ) is ≥ a dense sampling of that segment and within 1e-9."""
    prob = bv.make_problem(GENERAL, 0.3)
    p = np.array([[0.03, 0.2, 0.75, 0.95, 0.3, 0.6, 0.4]])
    ev = vp._Evaluator(prob)
    prep = ev.prepare(p)
    sub = 3
    for q in (0, 1):
        u = vq._exact_segment_maxima(prep, q, sub)
        piece = np.repeat(np.arange(6), sub)
        at = ev.values(prep, piece, u)[q][0]
        for k in range(6 * sub):
            lo, hi = (k % sub) / sub, (k % sub + 1) / sub
            uu = np.linspace(lo, hi, 2001)
            dense = ev.values(prep, np.full(uu.size, k // sub), uu)[q][0]
            assert at[k] >= dense.max() * (1 - 1e-12)
            assert at[k] == pytest.approx(dense.max(), rel=1e-6)
    # both quantities in one call (the F stage's batch): the same maxima, a's then j's
    both = vq._exact_segment_maxima(prep, (0, 1), sub)
    np.testing.assert_allclose(both, np.concatenate([vq._exact_segment_maxima(prep, q, sub) for q in (0, 1)]), atol=1e-12)


def _stages(prob, norms=(1.0, 1.0)):
    ev = vp._Evaluator(prob)
    space = vq._Space(prob.lambda_free, 0.01)
    return space, {k: vq._Stage(ev, space, k, *norms, bv.VelSettings()) for k in "ajF"}


def test_lockstep_runs_are_scipys_slsqp():
    """Runs of different stages advanced together (evaluations batched) end where scipy's
    minimize(method="SLSQP") ends from the same starts, each run alone on a fresh evaluator: the same
    routine and set-up (bitwise here; 1e-9 allows for batched round-off)."""
    prob = bv.make_problem(GENERAL, 0.3)
    space, _ = _stages(prob)
    x0 = space.from_unit(vs._quasi_random(4, space.n))
    ga, gj = vp._Evaluator(prob).grid_maxima(space.full(x0), 8)
    norms = (ga.min(), gj.min())  # F's normalisers: the smallest sampled peaks (squared) of the starts
    _, st = _stages(prob, norms)
    a_min, j_min = np.sqrt(norms)
    runs = [st["a"].run(x0[0]), st["j"].run(x0[1]), st["a"].run(x0[2], ftol=1e-5), st["F"].run(x0[3], a_min, j_min)]
    together = vq._run_slsqp(runs)
    for r, x in zip(runs, together):
        _, alone = _stages(prob, norms)
        ra = alone[r.stage.kind].run(r.x0, r.a_min, r.j_min, r.ftol)
        ref = vq._run_one(ra, ra.y0(ra.stage._eval(ra.x0)[0]))
        np.testing.assert_allclose(x, ref, atol=1e-9)
        assert r.stage.objective(x, r.a_min, r.j_min) < r.stage.objective(r.x0, r.a_min, r.j_min)


def test_lockstep_uses_the_private_routine_only_on_checked_scipy_versions(monkeypatch):
    """The private SLSQP routine is used on the checked versions (the installed one in CI: this test and
    the one above then compare it with minimize); on any other version the runs go through minimize and
    give the same results."""
    import scipy

    version = tuple(int(x) for x in scipy.__version__.split(".")[:2])
    in_range = vq._SLSQP_VERSIONS[0] <= version < vq._SLSQP_VERSIONS[1]
    assert (vq._slsqp_routine() is not None) == in_range
    prob = bv.make_problem(GENERAL, 0.3)
    space, st = _stages(prob)
    x0 = space.from_unit(vs._quasi_random(2, space.n))
    fast = vq._run_slsqp([st["a"].run(x0[0]), st["j"].run(x0[1])])
    monkeypatch.setattr(scipy, "__version__", "9.0.0")  # an unchecked scipy
    assert vq._slsqp_routine() is None
    _, st2 = _stages(prob)
    slow = vq._run_slsqp([st2["a"].run(x0[0]), st2["j"].run(x0[1])])
    for a, b in zip(fast, slow):
        np.testing.assert_allclose(a, b, atol=1e-9)


def test_cut_off_run_returns_its_best_feasible_point():
    """A run stopped after ``max_rounds`` evaluation rounds returns the best feasible point it evaluated:
    feasible (Eq. 36 with the margin) and no worse than its start."""
    prob = bv.make_problem(GENERAL, 0.3)
    space, st = _stages(prob)
    x0 = space.from_unit(vs._quasi_random(3, space.n))[2]
    (x,) = vq._run_slsqp([st["j"].run(x0, max_rounds=3)])
    assert np.all(x >= space.lo - 1e-12) and np.all(x <= space.hi + 1e-12) and np.all(space.order_gaps(x) >= -1e-12)
    assert st["j"].objective(x) <= st["j"].objective(x0)
    with pytest.raises(TaskError, match="max_rounds"):
        bv.VelSettings(max_rounds=1)


@pytest.mark.parametrize("free", [(True, True, True), (True, False, True)])
def test_segment_maxima_jacobian_exact_in_lambda_central_in_knots(free):
    """The constraint Jacobian: λ columns exact (the path is affine in λ), knot columns by central
    differences at the maximisers' fractions (envelope theorem). Both equal central differences of the
    exact segment maxima themselves to 1e-7 of the largest entry (their truncation and round-off)."""
    task = GENERAL if free[1] else Task([0, 0, 0], [0.28, -0.2, 0], 0.04, 0.5, [0, 0.2, 0], [0, 0.2, 0])
    prob = bv.make_problem(task, 0.3)
    assert prob.lambda_free == free
    space, st = _stages(prob)
    x = space.from_unit(vs._quasi_random(3, space.n))[2]
    for kind in "ajF":
        _, jacs = st[kind]._eval(x)
        for q, jac in enumerate(jacs):
            fd = np.zeros_like(jac)
            for k in range(space.n):
                e = np.zeros(space.n)
                e[k] = 1e-6
                fd[:, k] = (st[kind]._eval(x + e)[0][q] - st[kind]._eval(x - e)[0][q]) / 2e-6
            assert np.abs(fd - jac).max() <= 1e-7 * np.abs(jac).max()


def test_batched_pieces_match_the_one_at_a_time_ones():
    """Grid maxima without per-sample gathers = the maxima of ``sampled`` (exactly); segment maxima for a
    subset of vectors per quantity = the full computation's rows; the λ-derivatives of ``prepare`` =
    central differences (1e-9 relative: round-off only, as D is affine in λ)."""
    prob = bv.make_problem(GENERAL, 0.3)
    ev = vp._Evaluator(prob)
    space = vq._Space((True, True, True), 0.01)
    p = space.full(space.from_unit(vs._quasi_random(300, 7)))
    ga, gj = ev.sampled(p, *vp._grid(8))
    a2, j2 = ev.grid_maxima(p, 8)
    np.testing.assert_array_equal(ga.max(axis=1), a2)
    np.testing.assert_array_equal(gj.max(axis=1), j2)
    w, d, dl = ev.prepare(p[:6], np.array([1, 4]))
    full = vq._segment_maxima(w, d, (0, 1), 3)
    ua, uj = vq._segment_maxima(w, d, (0, 1), 3, (np.array([0, 2, 5]), np.array([1, 4])))
    np.testing.assert_array_equal(ua, full[[0, 2, 5], :18])
    np.testing.assert_array_equal(uj, full[[1, 4], 18:])
    for i in range(3):  # D is affine in λ: a wide central difference (0.05) has no truncation error
        hi, lo = p[[1, 4]].copy(), p[[1, 4]].copy()
        hi[:, 4 + i] += 0.05
        lo[:, 4 + i] -= 0.05
        fd = (ev.prepare(hi)[1] - ev.prepare(lo)[1]) / 0.1
        assert np.abs(fd - dl[:, i]).max() <= 1e-9 * np.abs(dl[:, i]).max()


def test_solve_improves_on_the_paper_initial_guess_and_respects_eq36():
    res = bv.solve(bv.make_problem(GENERAL, 0.3))
    t6, t7, t9, t10, *lam = res.params
    m = res.settings.margin
    assert m - 1e-12 <= t6 and t7 - t6 >= m - 1e-12 and 0.5 - t7 >= m - 1e-12
    assert t9 - 0.5 >= m - 1e-12 and t10 - t9 >= m - 1e-12 and 1 - t10 >= m - 1e-12
    assert all(0 <= x <= 1 for x in lam)
    prob = bv.make_problem(GENERAL, 0.3)
    _, a0, j0 = bv.exact_peaks(prob, bv.PAPER_INITIAL)
    assert res.F > res.a_min / a0 + res.j_min / j0
    assert res.a_min <= res.a_max and res.j_min <= res.j_max and 1.0 < res.F <= 2.0


def test_margin_is_a_setting_and_moves_min_a_max():
    """min a_max is approached at the boundary (τ6 → 0, τ10 → 1): a smaller margin gives a smaller
    minimum, and the minimiser sits on the margin."""
    prob = bv.make_problem(EXAMPLE, T_EX)
    wide = bv.solve(prob, bv.VelSettings(margin=0.02))
    narrow = bv.solve(prob, bv.VelSettings(margin=0.005))
    assert narrow.a_min < wide.a_min
    assert narrow.params_a[0] == pytest.approx(0.005, abs=1e-9)
    with pytest.raises(TaskError):
        bv.VelSettings(margin=0.0)


def test_invariance_under_the_dimensionless_groups():
    """Same h/b, η and v·T/b (along, across, vertical) → same optimum, whatever the scale, rotation about
    z, origin, duration and speeds: parameters agree to 1e-6 (the optimiser's tolerance), F to 1e-8."""
    base = bv.task_from_groups(
        dict(h_over_b=0.15, eta=0.5, v0_along=0.2, v0_across=-0.25, v1_along=-0.1, v1_across=0.3), b=1.0
    )
    ref = bv.solve(bv.make_problem(base, 1.0))
    th, c, T = 0.7, 0.37, 0.21
    rot = np.array([[np.cos(th), -np.sin(th), 0], [np.sin(th), np.cos(th), 0], [0, 0, 1]])
    origin = np.array([0.1, -0.2, -0.8])
    moved = Task(origin, origin + c * rot @ base.p_to, c * base.height, 0.5, c / T * rot @ base.v_from, c / T * rot @ base.v_to)
    g0, g1 = bv.groups(base, 1.0), bv.groups(moved, T)
    assert all(g1[k] == pytest.approx(g0[k], abs=1e-12) for k in g0)
    res = bv.solve(bv.make_problem(moved, T))
    np.testing.assert_allclose(res.params, ref.params, atol=1e-6)
    assert res.F == pytest.approx(ref.F, abs=1e-8)


def test_mirror_and_reversal_symmetries():
    """Mirroring in the move's vertical plane leaves the optimum; reversing the move (v0 ↔ v1) maps
    τ6 ↔ 1 − τ10, τ7 ↔ 1 − τ9, λ1 ↔ λ3 (what the table builder relies on). Tolerance 1e-6 (optimiser)."""
    from pickplace_cli.lookup.vel_table import reverse_params

    g = dict(h_over_b=0.2, eta=0.5, v0_along=0.3, v0_across=-0.2, v1_along=-0.1, v1_across=0.4)
    mirrored = dict(g, v0_across=0.2, v1_across=-0.4)
    swapped = dict(g, v0_along=-0.1, v0_across=0.4, v1_along=0.3, v1_across=-0.2)
    r = bv.solve(bv.make_problem(bv.task_from_groups(g), 1.0))
    rm = bv.solve(bv.make_problem(bv.task_from_groups(mirrored), 1.0))
    rs = bv.solve(bv.make_problem(bv.task_from_groups(swapped), 1.0))
    np.testing.assert_allclose(rm.params, r.params, atol=1e-6)
    np.testing.assert_allclose(reverse_params(rs.params), r.params, atol=1e-6)


def test_rest_to_rest_reduces_to_the_li_path():
    """v0 = v1 = 0: with Li's knots (τ6 = k1k2/2, τ7 = k1/2, τ9 = 1 − k1/2, τ10 = 1 − k1k2/2) the path is
    the bspline method's path to round-off; every λ is degenerate."""
    from pickplace_cli.paths.bspline import plan_bspline

    task = Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5)
    k1, k2 = 0.31, 0.12
    li = plan_bspline(task, k1=k1, k2=k2)
    vel = bv.plan_bspline_vel(task, 0.2, params=(k1 * k2 / 2, k1 / 2, 1 - k1 / 2, 1 - k1 * k2 / 2, 0.21, 0.5, 0.21))
    x = np.linspace(0, 1, 1001)
    for k in range(4):
        np.testing.assert_allclose(vel(x, k), li(x, k), atol=1e-9 * max(1.0, np.abs(li(x, k)).max()))
    assert bv.make_problem(task, 0.2).lambda_free == (False, False, False)


def test_param_checks_are_one_line_task_errors():
    with pytest.raises(TaskError, match="τ6 < τ7"):
        bv.plan_bspline_vel(EXAMPLE, T_EX, params=(0.3, 0.2, 0.7, 0.9, 0.2, 0.5, 0.2))
    with pytest.raises(TaskError, match="λ must lie"):
        bv.plan_bspline_vel(EXAMPLE, T_EX, params=(0.01, 0.2, 0.7, 0.9, 1.5, 0.5, 0.2))
    with pytest.raises(TaskError, match="seven"):
        bv.plan_bspline_vel(EXAMPLE, T_EX, params=(0.01, 0.2))
    with pytest.raises(TaskError, match="solver"):
        bv.plan_bspline_vel(EXAMPLE, T_EX, solver="nn")
    with pytest.raises(TaskError, match="duration"):
        bv.plan_bspline_vel(EXAMPLE, 0.0)
    with pytest.raises(TaskError, match="lambda2"):
        bv.plan_bspline_vel(EXAMPLE, T_EX, tau6=0.01, tau7=0.2, tau9=0.8, tau10=0.99, lambda1=0.2, lambda3=0.2)
    with pytest.raises(TaskError, match="no parameter 'k1'"):
        bv.PathFactory(EXAMPLE, k1=0.3)
    named = bv.plan_bspline_vel(EXAMPLE, T_EX, **dict(zip(bv.PARAM_NAMES, bv.PAPER_INITIAL)))
    assert named.parameters["params_source"] == "given"


def test_groups_and_canonical_task_round_trip():
    g = bv.groups(GENERAL, 0.3)
    back = bv.groups(bv.task_from_groups(g, b=2.0, duration=0.7), 0.7)
    assert all(back[k] == pytest.approx(g[k], abs=1e-12) for k in g)
    # along/across/vertical resolve v·T/b in the move's frame
    eu = GENERAL.e_u
    assert g["v0_along"] == pytest.approx(GENERAL.v_from @ eu * 0.3 / GENERAL.b, abs=1e-15)
    assert g["v1_vertical"] == pytest.approx(0.02 * 0.3 / GENERAL.b, abs=1e-15)


def test_path_factory_continuation_and_final_check():
    """The factory solves the first duration globally and later ones by continuation; ``final`` re-solves
    globally and agrees (same optimum) on this smooth family (F to 1e-9)."""
    f = bv.PathFactory(EXAMPLE)
    p1 = f(0.25)
    p2 = f(0.26)
    # the first (full) solve's words: whether the shipped table seeded it, carried by every path of the factory
    assert p1.parameters["params_source"] == p2.parameters["params_source"]
    assert p1.parameters["params_source"].startswith("exact (")
    path, agreed = f.final(0.26)
    assert agreed
    assert path.parameters["params_source"].startswith("exact (")
    glob = bv.solve(bv.make_problem(EXAMPLE, 0.26))
    assert path.parameters["F"] == pytest.approx(glob.F, abs=1e-9)
    assert f(0.26) is path


# ------------------------------------------------------------------------------- through the planner

ADEPT_BELT = Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5, [0.3, 0, 0], [0, 0.3, 0])


@pytest.fixture(scope="module")
def delta():
    from pickplace_cli.model.profile import load_profile

    return load_profile("delta-su2018")


def test_plan_given_duration_meets_the_belts(delta):
    from pickplace_cli.planner import PlanOptions, plan

    r = plan(ADEPT_BELT, delta, PlanOptions(method="bspline-vel", time=0.25))
    assert r.duration.mode == "given" and r.duration.seconds == 0.25
    np.testing.assert_allclose(r.v[0], [0.3, 0, 0], atol=1e-12)
    np.testing.assert_allclose(r.v[-1], [0, 0.3, 0], atol=1e-12)
    np.testing.assert_allclose([r.a[0], r.a[-1]], 0.0, atol=1e-7)
    assert r.parameters["duration_s"] == 0.25 and r.method == "bspline-vel"


def test_auto_duration_is_the_smallest_meeting_the_capacity(delta):
    """Eq. 26 with the shape re-optimised at each T: at T_auto the binding capacity is met with equality
    (1e-6) by the path planned for T_auto; the path planned for 0.999·T_auto exceeds it."""
    from pickplace_cli.planner import PlanOptions, plan
    from pickplace_cli.timing import auto_duration

    r = plan(ADEPT_BELT, delta, PlanOptions(method="bspline-vel", time="auto"))
    T = r.duration.seconds
    cap = delta.capacity
    v, a, j = r.cartesian.peaks()
    assert max(v / cap.velocity, a / cap.acceleration) == pytest.approx(1.0, abs=1e-6)
    shorter = bv.plan_bspline_vel(ADEPT_BELT, 0.999 * T)
    assert max(auto_duration(shorter, cap)[:2]) > 0.999 * T


@pytest.mark.slow
def test_fit_solves_eq38_every_motor_limit_at_the_optimal_shape(delta):
    """Eq. 38: the smallest T at which every limit (motor torque and its rate, speed, RMS …) holds with the
    shape optimal at T. All hold at T_fit; with 0.1 % less time (and the shape optimal there) one fails."""
    from pickplace_cli.limits.check import check_limits
    from pickplace_cli.planner import PlanOptions, motion_model, plan

    r = plan(ADEPT_BELT, delta, PlanOptions(method="bspline-vel", time="fit"))
    assert r.duration.mode == "fit" and r.report.ok
    T = r.duration.seconds
    shorter = 0.999 * T
    model = motion_model(bv.plan_bspline_vel(ADEPT_BELT, shorter), delta)
    rep = check_limits(model, shorter, dwell=delta.planning.dwell)
    assert not all(row.ok for row in rep.rows if row.kind != "reach")
    # the fitted path is the global optimum at T_fit (confirmed by the factory's final global solve)
    glob = bv.solve(bv.make_problem(ADEPT_BELT, T))
    assert r.parameters["F"] == pytest.approx(glob.F, abs=1e-8)


@pytest.mark.parametrize("table", ["passwd", "missing", "bspline"])
def test_a_named_table_that_cannot_be_read_is_refused(tmp_path, table):
    """A conveyor table the user names (``--table``) that is missing, foreign or of another method is refused in one
    line (exit 1), never silently replaced by the multi-start; one that only does not apply to the move (another η)
    is used as far as it can and the plan says why not."""
    import subprocess
    import sys

    path = {"passwd": tmp_path / "passwd", "missing": tmp_path / "none.csv",
            "bspline": Path(__file__).resolve().parents[2] / "tables" / "bspline-eta0.5.csv"}[table]
    if table == "passwd":
        path.write_text("root:x:0:0:root:/root:/bin/bash\n")
    r = subprocess.run([sys.executable, "-m", "pickplace_cli", "plan", "--from", "-0.1525,0,-0.8", "--to",
                        "0.1525,0,-0.8", "-m", "bspline-vel", "--table", str(path), "-o", str(tmp_path / "o.csv")],
                       capture_output=True, text=True)
    assert r.returncode == 1, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("pickplace: error:") and str(path) in lines[0], r.stderr
    assert not (tmp_path / "o.csv").exists()


def test_a_table_that_does_not_apply_says_why():
    task = Task(EXAMPLE.p_from, EXAMPLE.p_to, EXAMPLE.height, 0.3, v_from=EXAMPLE.v_from, v_to=EXAMPLE.v_to)
    p = bv.PathFactory(task)(0.25)
    assert "table not used: eta = 0.3" in p.parameters["params_source"]
