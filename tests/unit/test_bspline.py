"""bspline.py: knots (Li 2018 Eq. 14), control points (Eq. 8-10), basis vs an independent Cox-de Boor."""

from __future__ import annotations

import numpy as np
import pytest

from pickplace_cli.bspline import (
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
