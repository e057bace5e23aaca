"""bspline.py: knots (Li 2018 Eq. 14), control points (Eq. 8-10), basis vs an independent Cox-de Boor."""

from __future__ import annotations

import numpy as np
import pytest

from pickplace_cli.curves.bspline import (
    DEGREE,
    basis_matrix,
    li_knots,
    make_spline,
    norm_peaks,
    solve_control_points,
)


def cox_de_boor(knots: np.ndarray, i: int, p: int, x: float) -> float:
    """Textbook recursion [Li2018, Eq. (4)], right end included in the last non-empty span."""
    if p == 0:
        last = knots[-1]
        if knots[i] <= x < knots[i + 1] or (x == last and knots[i] < knots[i + 1] == last):
            return 1.0
        return 0.0
    out = 0.0
    d1 = knots[i + p] - knots[i]
    if d1 > 0:
        out += (x - knots[i]) / d1 * cox_de_boor(knots, i, p - 1, x)
    d2 = knots[i + p + 1] - knots[i + 1]
    if d2 > 0:
        out += (knots[i + p + 1] - x) / d2 * cox_de_boor(knots, i + 1, p - 1, x)
    return out


def test_knots_eq14():
    t = li_knots(0.31, 0.12)
    assert t.shape == (17,)
    np.testing.assert_allclose(t[6:11], [0.31 * 0.12 / 2, 0.155, 0.5, 0.845, 1 - 0.31 * 0.12 / 2], rtol=0, atol=1e-15)
    assert np.all(t[:6] == 0) and np.all(t[11:] == 1)
    # Eq. 13: k1 = τ8/τ9, k2 = τ7/τ8
    assert t[7] / t[8] == pytest.approx(0.31, abs=1e-15) and t[6] / t[7] == pytest.approx(0.12, abs=1e-15)
    with pytest.raises(ValueError):
        li_knots(0.0, 0.5)
    with pytest.raises(ValueError):
        li_knots(0.5, 1.0)


@pytest.mark.parametrize("k1,k2", [(0.31, 0.12), (0.05, 0.9), (0.9, 0.01)])
def test_basis_matches_cox_de_boor(k1, k2):
    """scipy's basis equals the independent recursion to 1e-12 (round-off of a degree-5 recursion)."""
    t = li_knots(k1, k2)
    x = np.linspace(0, 1, 41)
    b = basis_matrix(t, x)
    ref = np.array([[cox_de_boor(t, i, DEGREE, xx) for i in range(11)] for xx in x])
    np.testing.assert_allclose(b, ref, atol=1e-12)
    np.testing.assert_allclose(b.sum(axis=1), 1.0, atol=1e-12)  # partition of unity


def _full_system(t, via, taus):
    """The paper's full 11x11 system A q = b (Eq. 10) with rows of Eq. 8 and Eq. 9, solved directly."""
    rows, rhs = [], []
    for tau, s in zip(taus, via):
        rows.append(basis_matrix(t, [tau])[0] if tau < 1 else np.eye(11)[-1])
        rhs.append(s)
    from scipy.interpolate import BSpline

    basis = BSpline(t, np.eye(11), DEGREE, extrapolate=True)
    for r in (1, 2, 3):
        rows.append(basis(np.array([0.0]), nu=r)[0])
        rhs.append(0.0)
        rows.append(basis(np.array([1.0]), nu=r)[0])
        rhs.append(0.0)
    a = np.array(rows)
    return np.linalg.solve(a, np.array(rhs)), np.linalg.cond(a)


def test_reduced_solve_equals_full_system():
    """The reduced solve and the paper's 11x11 system agree; the full one is badly conditioned (~1e8)."""
    t = li_knots(0.31, 0.12)
    taus = t[[0, 7, 8, 9, 16]]
    for via in ([0, 0, 0.5, 1, 1], [0, 0.5, 1, 0.5, 0]):
        q = solve_control_points(t, taus, np.array(via, float))[:, 0]
        q_full, cond = _full_system(t, via, taus)
        # full system loses ~cond * eps ≈ 1e-8 relative; the reduced one is exact to ~1e-15
        np.testing.assert_allclose(q, q_full, atol=1e-7)
    assert cond > 1e6


def test_interpolates_via_points_and_rests_at_ends():
    t = li_knots(0.4, 0.3)
    taus = t[[0, 7, 8, 9, 16]]
    via = np.array([[0, 0, 0], [0, 0, 0.3], [0.5, 0.1, 0.6], [1, 0.2, 0.3], [1, 0.2, 0]], float)
    s = make_spline(t, solve_control_points(t, taus, via))
    np.testing.assert_allclose(s(taus), via, atol=1e-12)
    for r in (1, 2, 3):
        # derivatives at a clamped end cancel to round-off of ~|N^(r)| * eps ≈ 1e-9 at r = 3
        np.testing.assert_allclose(s(np.array([0.0, 1.0]), nu=r), 0.0, atol=1e-8)


def test_nonzero_end_velocity_is_met():
    """The general end conditions (used by conveyor tracking) are met exactly."""
    t = li_knots(0.4, 0.3)
    taus = t[[0, 7, 8, 9, 16]]
    via = np.array([0.0, 0.0, 0.5, 1.0, 1.0])
    start = np.array([0.7, 0.0, 0.0])
    end = np.array([-0.3, 0.0, 0.0])
    s = make_spline(t, solve_control_points(t, taus, via, start, end))
    assert float(s(0.0, nu=1)[0]) == pytest.approx(0.7, abs=1e-9)
    assert float(s(1.0, nu=1)[0]) == pytest.approx(-0.3, abs=1e-9)
    np.testing.assert_allclose(s(taus)[:, 0], via, atol=1e-12)


@pytest.mark.parametrize("k1,k2", [(0.31, 0.12), (0.6, 0.4), (0.2, 0.02)])
def test_exact_peaks_bound_dense_samples(k1, k2):
    """Exact peaks ≥ every sample and within 1e-6 relative of a 200k-sample maximum."""
    t = li_knots(k1, k2)
    via = np.array([[0, 0], [0, 0.5 / 28], [0.5, 1 / 28], [1, 0.5 / 28], [1, 0]])
    s = make_spline(t, solve_control_points(t, t[[0, 7, 8, 9, 16]], via))
    x = np.linspace(0, 1, 200_001)
    for r, peak in zip((1, 2, 3), norm_peaks(s)):
        sampled = np.linalg.norm(s(x, nu=r), axis=1).max()
        assert peak >= sampled * (1 - 1e-12)
        assert peak == pytest.approx(sampled, rel=1e-6)


# ----------------------------------------------------------------- batched machinery (conveyor tracking)


def _random_knots(rng, count):
    """Clamped 17-knot vectors with four random free knots around τ8 = 1/2 (Yang 2022 Eq. 23)."""
    from pickplace_cli.curves.bspline import yang_knots

    out = []
    for _ in range(count):
        t6, t7 = np.sort(rng.uniform(0.01, 0.49, 2))
        t9, t10 = np.sort(rng.uniform(0.51, 0.99, 2))
        out.append(yang_knots(t6, t7, t9, t10))
    return np.array(out)


def test_yang_knots_eq23():
    from pickplace_cli.curves.bspline import yang_knots

    t = yang_knots(0.01, 0.21, 0.79, 0.99)
    assert t.shape == (17,) and t[8] == 0.5 and np.all(t[:6] == 0) and np.all(t[11:] == 1)
    with pytest.raises(ValueError):
        yang_knots(0.2, 0.1, 0.79, 0.99)  # τ6 > τ7 breaks Eq. 36
    with pytest.raises(ValueError):
        yang_knots(0.01, 0.21, 0.79, 1.0)


def test_batch_basis_matches_scipy_every_degree():
    """The batched Cox-de Boor (NURBS book A2.2) equals scipy's basis of each degree, to 1e-13 (round-off
    of a degree-5 recursion on O(1) values), on knot spans, their ends and τ = 1."""
    from scipy.interpolate import BSpline

    from pickplace_cli.curves.bspline import batch_basis

    rng = np.random.default_rng(3)
    knots = _random_knots(rng, 5)
    span = np.array([5, 6, 7, 8, 9, 10, 10, 7])
    u = np.array([0.3, 0.0, 1.0, 0.5, 0.9, 0.2, 1.0, 0.7])
    x = knots[:, span] + u * (knots[:, span + 1] - knots[:, span])
    got = batch_basis(knots, x, span, 5, all_degrees=True)
    for p, t in enumerate(knots):
        for deg in range(6):
            inner = t[5 - deg : len(t) - 5 + deg]  # the same knots with multiplicity deg + 1 at the ends
            n = len(inner) - deg - 1
            ref = BSpline(inner, np.eye(n), deg, extrapolate=True)(x[p])
            for m, s in enumerate(span):
                if deg == 0 and u[m] in (0.0, 1.0):
                    continue  # degree 0 jumps at a knot: A2.2 takes the caller's span, scipy the next one
                cols = np.arange(s - deg, s + 1) - (5 - deg)
                np.testing.assert_allclose(got[deg][p, m], ref[m, cols], atol=1e-13)
                assert abs(ref[m].sum() - 1.0) < 1e-12


def test_end_and_derivative_control_points_match_the_general_solve():
    """Eq. 12-15 inverted step by step (batch_end_control_points) gives the same control points as the
    general solve with boundary rows (solve_control_points), for arbitrary v, a, j at both ends; the
    derivative control points (Eq. 12-14) reproduce scipy's derivatives."""
    from pickplace_cli.curves.bspline import (
        batch_end_control_points,
        derivative_control_points,
        make_spline,
        solve_control_points,
    )

    rng = np.random.default_rng(4)
    knots = _random_knots(rng, 3)
    for t in knots:
        via = rng.normal(size=(5, 3))
        start, end = rng.normal(size=(3, 3)), rng.normal(size=(3, 3))
        q = solve_control_points(t, t[[0, 7, 8, 9, 16]], via, start, end)
        q0 = batch_end_control_points(t[None], via[None, 0], start[None])[0]
        q1 = batch_end_control_points(t[None], via[None, 4], end[None], at_end=True)[0]
        # the general solve is a 4x4 triangular solve per end: agreement to round-off (~1e-12 relative)
        np.testing.assert_allclose(q0, q[:4], rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(q1, q[-4:], rtol=1e-10, atol=1e-12)
        s = make_spline(t, q)
        ctrl = derivative_control_points(t[None], q[None], 5)
        x = np.linspace(0.0, 1.0, 37)
        from scipy.interpolate import BSpline

        for r in range(1, 6):
            # the r-th derivative spline has degree 5 − r on the same knots: Σ Q_r[i] N_{i+r, 5−r}
            ds = BSpline(t[r:len(t) - r], ctrl[r][0], 5 - r, extrapolate=True)
            np.testing.assert_allclose(ds(x), s(x, nu=r), rtol=1e-9, atol=1e-9 * np.abs(s(x, nu=r)).max())


def test_batched_pieces_match_scipy():
    """The scipy-free online path (batch_li_knots, batch_control_points, batch_pieces; P moves at once)
    equals scipy's BSpline: the left-end derivatives of every order 0…5 of every piece to 1e-10 relative
    to the largest value of that order (the same de Boor arithmetic; the largest difference, 1.4e-11, is
    scipy's round-off at k2 = 0.01 where the exact value — a derivative at the rest end — is 0, which the
    batched path gives exactly), and the control points equal the general solver's to 1e-12."""
    from scipy.interpolate import BSpline

    from pickplace_cli.curves.bspline import batch_control_points, batch_li_knots, batch_pieces

    rng = np.random.default_rng(7)
    k = np.array([[0.31, 0.12], [0.05, 0.9], [0.9, 0.01], [0.3966, 0.1328]])
    via = rng.normal(size=(4, 5, 3))
    knots = batch_li_knots(k[:, 0], k[:, 1])
    q = batch_control_points(knots, via)
    breaks, derivs = batch_pieces(knots, q)
    for p in range(4):
        t = li_knots(*k[p])
        np.testing.assert_array_equal(knots[p], t)
        ref_q = solve_control_points(t, t[[0, 7, 8, 9, 16]], via[p])
        np.testing.assert_allclose(q[p], ref_q, rtol=0, atol=1e-12 * np.max(np.abs(ref_q)))
        np.testing.assert_array_equal(breaks[p], np.unique(t))
        s = BSpline(t, q[p], DEGREE)
        for r in range(DEGREE + 1):
            ref = s(breaks[p, :-1], nu=r)
            np.testing.assert_allclose(derivs[r][p], ref, rtol=0, atol=1e-10 * np.max(np.abs(ref)))


def _assert_matches_de_boor(closed_form, k1, k2, via):
    """A closed-form path (breaks, coefficients, peaks) against the batched de Boor path through the same via
    points: breaks bitwise, piece polynomials to 1e-9 of the largest coefficient of each power, peaks 1e-10."""
    from pickplace_cli.paths.bspline import _deboor_paths

    b1, c1, p1 = closed_form(k1, k2, via)
    b2, c2, p2 = _deboor_paths(k1, k2, via)
    np.testing.assert_array_equal(b1, b2)
    for o in range(6):
        np.testing.assert_allclose(c1[..., o], c2[..., o], rtol=0, atol=1e-9 * np.abs(c2[..., o]).max())
    np.testing.assert_allclose(p1, p2, rtol=1e-10)


def test_symmetric_closed_form_path_equals_de_boor():
    """batch_paths' closed form for moves between end points at one height (the table's unit path and its
    mirror image) against the batched de Boor path through the same via points, on 200 random moves per k1
    band: piece polynomials to 1e-9 of the largest coefficient of each power (measured 1.4e-10 at
    k1 = 0.1 with k2 = 1e-4, ~3e-12 inside; the closed form loses digits towards k1 → 0, hence UNIT_K1)
    and exact peaks to 1e-10 relative (measured 1.3e-11). Moves at two heights, and k1 outside UNIT_K1,
    take another path (two heights: the planar closed form, test_planar_closed_form_path_equals_de_boor; k1
    outside the band: de Boor), and a batch mixing them gives each row what it gets alone."""
    from pickplace_cli.paths.bspline import UNIT_K1, _symmetric, _unit_paths, batch_paths
    from pickplace_cli.model.task import Task

    rng = np.random.default_rng(5)
    tasks = []
    for _ in range(200):
        r, a, z = rng.uniform(0.03, 0.3), rng.uniform(0, 2 * np.pi), rng.uniform(-0.9, -0.7)
        tasks.append(Task([-r * np.cos(a), -r * np.sin(a), z], [r * np.cos(a), r * np.sin(a), z],
                          rng.uniform(0.01, 0.06), rng.uniform(0.2, 0.8)))
    via = np.stack([t.via_points() - t.p_from for t in tasks])
    for lo, hi in ((UNIT_K1[0], UNIT_K1[0] + 0.02), UNIT_K1, (UNIT_K1[1] - 0.02, UNIT_K1[1])):
        k1 = rng.uniform(lo, hi, 200)
        k2 = np.r_[rng.uniform(0.01, 0.99, 190), np.full(10, 1e-4)]
        assert _symmetric(k1, via).all()
        _assert_matches_de_boor(_unit_paths, k1, k2, via)
    # outside the band: de Boor, at two heights the planar form; a mixed batch row by row as alone
    k1 = np.r_[0.05, 0.5, 0.95, 0.5]
    via2 = via[:4].copy()
    via2[3, 4, 2] = 0.01  # P5 1 cm higher (the via points no longer symmetric)
    assert list(_symmetric(k1, via2)) == [False, True, False, False]
    b, c, p = batch_paths(k1, np.full(4, 0.3), via2)
    for i in range(4):
        bi, ci, pi = batch_paths(k1[i : i + 1], np.full(1, 0.3), via2[i : i + 1])
        assert np.array_equal(bi[0], b[i]) and np.array_equal(ci[0], c[i]) and np.array_equal(pi[0], p[i])


def test_planar_closed_form_path_equals_de_boor():
    """batch_paths' closed form for moves between end points at two heights (four cardinal functions of
    plane_pieces, mirrored, combined by the via heights) against the batched de Boor path through the same via
    points, on 200 random moves per k1 band (ends 0 to 20 cm apart in height, P1 the lower or the higher):
    piece polynomials to 1e-9 of the largest coefficient of each power (measured 1.5e-10 at k1 = 0.1 with
    k2 = 1e-4, ~1e-11 inside), exact peaks to 1e-10 relative (measured 8e-12). Routing: a move at one height
    takes the symmetric form, at two heights the planar one, other via points and k1 outside UNIT_K1 de Boor;
    the one-move decision (_route_one, on floats) is the batch's; a batch mixing all three gives each row
    bitwise what it gets alone."""
    from pickplace_cli.model.task import Task
    from pickplace_cli.paths.bspline import (ROUTE_DEBOOR, ROUTE_PLANE, ROUTE_UNIT, UNIT_K1, UNIT_PIECE_MIN,
                                             _plane_paths, _route, _route_one, _unit_paths, batch_paths)

    rng = np.random.default_rng(11)
    tasks = []
    for _ in range(200):
        r, a, z = rng.uniform(0.03, 0.3), rng.uniform(0, 2 * np.pi), rng.uniform(-0.9, -0.7)
        dz = rng.uniform(-0.2, 0.2)
        tasks.append(Task([-r * np.cos(a), -r * np.sin(a), z], [r * np.cos(a), r * np.sin(a), z + dz],
                          rng.uniform(0.01, 0.06), rng.uniform(0.2, 0.8)))
    via = np.stack([t.via_points() - t.p_from for t in tasks])
    for lo, hi in ((UNIT_K1[0], UNIT_K1[0] + 0.02), UNIT_K1, (UNIT_K1[1] - 0.02, UNIT_K1[1])):
        k1 = rng.uniform(lo, hi, 200)
        k2 = np.r_[rng.uniform(0.01, 0.99, 190), np.full(10, 1e-4)]
        closed = k1 * (1 - k2) / 2 >= UNIT_PIECE_MIN
        assert (_route(k1, k2, via) == np.where(closed, ROUTE_PLANE, ROUTE_DEBOOR)).all()
        assert all(_route_one(a, b, v) == r for a, b, v, r in zip(k1, k2, via, _route(k1, k2, via)))
        _assert_matches_de_boor(_plane_paths, k1, k2, via)
    # a short middle piece (k2 → 1, only from the user) takes de Boor: the closed forms lose digits there
    assert _route(np.r_[0.1, 0.1], np.r_[0.97, 0.99], via[:2]).tolist() == [ROUTE_PLANE, ROUTE_DEBOOR]
    assert _route_one(0.1, 0.99, via[0]) == ROUTE_DEBOOR
    # the same form reduces to the symmetric one for a move at one height
    flat = Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5)
    vf = (flat.via_points() - flat.p_from)[None]
    bu, cu, pu = _unit_paths(np.r_[0.3], np.r_[0.2], vf)
    bp, cp, pp = _plane_paths(np.r_[0.3], np.r_[0.2], vf)
    np.testing.assert_allclose(cp, cu, rtol=0, atol=1e-11 * np.abs(cu).max())
    np.testing.assert_allclose(pp, pu, rtol=1e-12)
    # routing and a mixed batch: one height, two heights, P3 off the midpoint, k1 outside the band
    odd = via[2].copy()
    odd[2, 0] += 0.01
    mixed = np.stack([vf[0], via[0], odd, via[1]])
    k1 = np.r_[0.5, 0.5, 0.5, 0.05]
    route = _route(k1, np.full(4, 0.3), mixed)
    assert list(route) == [ROUTE_UNIT, ROUTE_PLANE, ROUTE_DEBOOR, ROUTE_DEBOOR]
    assert [_route_one(a, 0.3, v) for a, v in zip(k1, mixed)] == list(route)
    b, c, p = batch_paths(k1, np.full(4, 0.3), mixed)
    for i in range(4):
        bi, ci, pi = batch_paths(k1[i : i + 1], np.full(1, 0.3), mixed[i : i + 1])
        assert np.array_equal(bi[0], b[i]) and np.array_equal(ci[0], c[i]) and np.array_equal(pi[0], p[i])


def test_online_bspline_path_loads_no_scipy():
    """Planning the default method's path (table lookup, control points, peaks, evaluation) imports no
    scipy: the cold-start budget of `pickplace plan` [issue 7]. Run in a fresh interpreter."""
    import subprocess
    import sys

    code = (
        "import sys, numpy as np\n"
        "from pickplace_cli.paths import plan_path\n"
        "from pickplace_cli.model.task import Task\n"
        "p = plan_path(Task(np.array([-0.15, 0, -0.8]), np.array([0.15, 0, -0.8]), 0.025, 0.5), 'bspline')\n"
        "p(np.linspace(0, 1, 11), 3)\n"
        "print(sorted(m for m in sys.modules if m.startswith('scipy')))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def test_symmetric_one_is_the_batched_decision():
    """plan_bspline decides on floats (_symmetric_one) what the batch engine decides on arrays (_symmetric):
    both must agree on every move, or one move planned alone and in a batch would take different paths."""
    from pickplace_cli.paths.bspline import UNIT_K1, _symmetric, _symmetric_one
    from pickplace_cli.model.task import Task

    rng = np.random.default_rng(7)
    vias, k1s = [], []
    for i in range(3000):
        scale = 10.0 ** rng.uniform(-4, 2)  # from sub-mm moves to 100 m coordinates
        p1 = rng.uniform(-1, 1, 3) * scale
        p5 = p1 + rng.uniform(-1, 1, 3) * 10.0 ** rng.uniform(-6, 0)
        if i % 2:
            p5[2] = p1[2]  # equal heights (the symmetric case) for half of them
        if i % 7 == 0:
            p5[2] = np.nextafter(p1[2], np.inf)  # one ulp apart
        try:
            task = Task(p1, p5, 10.0 ** rng.uniform(-7, 0), rng.uniform(0.05, 0.95))
        except Exception:  # end points too close: not a move
            continue
        vias.append(task.via_points() - task.p_from)
        k1s.append(rng.choice([rng.uniform(0.01, 0.99), UNIT_K1[0], UNIT_K1[1]]))
    vias, k1s = np.array(vias), np.array(k1s)
    batch = _symmetric(k1s, vias)
    one = np.array([_symmetric_one(k, v) for k, v in zip(k1s, vias)])
    assert batch.any() and not batch.all()
    np.testing.assert_array_equal(one, batch)
