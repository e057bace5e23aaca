"""peaks.py: exact piecewise-polynomial maxima and the golden-section refinement."""

from __future__ import annotations

import numpy as np
import pytest

from pickplace_cli.curves.peaks import ppoly_norm_peak, refine_max


def test_ppoly_peak_of_known_polynomial():
    # c(τ) = (τ(1-τ), 0) on one piece [0, 1]: max 0.25 at τ = 0.5
    coef = np.array([[[-1.0, 1.0, 0.0], [0.0, 0.0, 0.0]]])
    val, tau = ppoly_norm_peak(np.array([0.0, 1.0]), coef)
    assert val == pytest.approx(0.25, abs=1e-15) and tau == pytest.approx(0.5, abs=1e-12)


def test_ppoly_peak_handles_degree_drop_and_ends():
    # piece 1: constant 2 (degree drops to 0); piece 2: 2 + 3s on [0, 0.5] → max 3.5 at the right end
    coef = np.array([[[0.0, 0.0, 2.0]], [[0.0, 3.0, 2.0]]])
    val, tau = ppoly_norm_peak(np.array([0.0, 1.0, 1.5]), coef)
    assert val == pytest.approx(3.5, abs=1e-14) and tau == pytest.approx(1.5)


def test_refine_max_beats_samples():
    f = lambda x: np.column_stack([np.sin(7.3 * x), np.cos(3.1 * x + 0.2)])  # noqa: E731
    x = np.linspace(0, 1, 11)
    peak, at = refine_max(f, x)
    # sin(7.3x) peaks at x = π/14.6 with value 1; cos(3.1x + 0.2) at x = 0 (edge)
    assert peak[0] == pytest.approx(1.0, abs=1e-12) and at[0] == pytest.approx(np.pi / 14.6, abs=1e-6)
    assert peak[1] == pytest.approx(np.cos(0.2), abs=1e-12)


def test_batched_peaks_equal_one_by_one():
    """batch_norm_peaks (P moves × several orders in one eigenvalue call; lower degrees padded with roots at
    the piece's left end; pieces whose Bernstein bound is below a reached value skipped) gives the same
    peaks as ppoly_norm_peak move by move and order by order, to 1e-13 relative."""
    from pickplace_cli.curves.bspline import _left_derivatives, li_knots, make_spline, piece_coefficients, solve_control_points
    from pickplace_cli.curves.peaks import batch_norm_peaks

    rng = np.random.default_rng(3)
    breaks_all, coefs_all = [], []
    for _ in range(20):
        k1, k2 = rng.uniform(0.05, 0.95, 2)
        t = li_knots(k1, k2)
        q = solve_control_points(t, t[[0, 7, 8, 9, 16]], rng.normal(size=(5, 3)))
        breaks = np.unique(t)
        derivs = _left_derivatives(make_spline(t, q), breaks)
        breaks_all.append(breaks)
        coefs_all.append([piece_coefficients(None, r, derivs, breaks)[1] for r in (1, 2, 3, 4)])
    got = batch_norm_peaks(np.array(breaks_all), [np.array([c[k] for c in coefs_all]) for k in range(4)])
    for p, (breaks, coefs) in enumerate(zip(breaks_all, coefs_all)):
        for k, c in enumerate(coefs):
            assert got[p, k] == pytest.approx(ppoly_norm_peak(breaks, c)[0], rel=1e-13)
