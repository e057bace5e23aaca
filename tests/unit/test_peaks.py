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


def _vertex_by_hand(x, y):
    """The parabola-vertex estimate of one column, in plain Python (an independent slow implementation)."""
    i = max(range(len(y)), key=lambda j: (y[j], -j))  # the first maximum
    top, at = float(y[i]), float(x[i])
    if not 0 < i < len(y) - 1:
        return top, at
    x0, x1, x2 = (float(v) for v in x[i - 1 : i + 2])
    y0, y1, y2 = (float(v) for v in y[i - 1 : i + 2])
    d1, d2 = (y1 - y0) / (x1 - x0), (y2 - y1) / (x2 - x1)
    curv = (d2 - d1) / (x2 - x0)
    if not curv < 0:
        return top, at
    slope = d1 + curv * (x1 - x0)
    yv = y1 - slope * slope / (4 * curv)
    return (yv, min(max(x1 - slope / (2 * curv), x0), x2)) if yv >= top else (top, at)


def test_parabolic_peak_of_stacked_grids_is_each_grid_s_alone():
    """parabolic_peak of many grids stacked (``starts``, of one length and of many) = of every grid alone, bit for
    bit, and = the estimate written out by hand (within 1e-15: the same formula in Python floats)."""
    from pickplace_cli.curves.peaks import parabolic_peak

    rng = np.random.default_rng(5)
    for lengths in (rng.integers(1, 60, 40), np.full(12, 33)):
        xs, ys = [], []
        for n in lengths:
            x = np.sort(rng.uniform(0, 1, n))
            y = np.sin(rng.uniform(1, 20) * x[:, None] + rng.uniform(0, 6, 4)) + rng.normal(0, 0.01, (n, 4))
            y[rng.integers(0, n), 0] = y[:, 0].max()  # a tie: the first maximum counts, as np.argmax takes it
            xs.append(x)
            ys.append(y)
        starts = np.concatenate([[0], np.cumsum([len(x) for x in xs])])
        peak, at = parabolic_peak(np.concatenate(xs), np.concatenate(ys), starts)
        for k, (x, y) in enumerate(zip(xs, ys)):
            ref_peak, ref_at = parabolic_peak(x, y)
            assert np.array_equal(peak[k], ref_peak) and np.array_equal(at[k], ref_at)
            for c in range(y.shape[1]):
                assert (peak[k, c], at[k, c]) == pytest.approx(_vertex_by_hand(x, y[:, c]), rel=1e-15, abs=1e-15)


def test_parabolic_peak_never_across_a_jump():
    """Three samples in two segments: the sample, not the vertex."""
    from pickplace_cli.curves.peaks import parabolic_peak

    x = np.array([0.0, 0.4, 0.5, 0.6, 1.0])
    y = np.array([[0.0], [0.8], [1.0], [0.9], [0.0]])
    assert parabolic_peak(x, y)[0][0] > 1.0
    peak, at = parabolic_peak(x, y, seg=np.array([0, 0, 0, 1, 1]))
    assert peak[0] == 1.0 and at[0] == 0.5


def test_refine_max_rtol_agrees_with_the_full_search_and_stops_sooner():
    # a smooth maximum, a concave corner between samples and many near-equal maxima (all 1 by construction): with
    # rtol (every local maximum within 0.1 of the top searched, brackets that cannot win dropped) the smooth peaks are
    # within 1e-10 below the truth and the full search's
    calls = {"full": 0, "rtol": 0}

    def make(key):
        def f(x):
            calls[key] += 1
            return np.column_stack([np.sin(7.3 * x), 1.0 - np.abs(x - 0.31371), 0.999 + 0.001 * np.cos(40.0 * x)])
        return f

    x = np.linspace(0, 1, 41)
    full, _ = refine_max(make("full"), x, max_candidates=100)
    fast, at = refine_max(make("rtol"), x, within=0.1, rtol=1e-10)
    truth = np.array([1.0, 1.0, 1.0])
    assert np.all(fast <= truth + 1e-15)
    assert truth[0] - fast[0] <= 1e-10 and truth[2] - fast[2] <= 1e-10 and abs(fast[0] - full[0]) <= 1e-10
    # the corner between two samples: the value error is linear in the last bracket, so the iterations cap (3.6e-6
    # of the first bracket, as without rtol) stops the search before rtol does: within 1e-8, no worse than before
    assert truth[1] - fast[1] <= min(1e-8, truth[1] - full[1])
    assert at[1] == pytest.approx(0.31371, abs=1e-8)
    assert calls["rtol"] <= calls["full"]  # never more model calls (here as many: six tied maxima stay live)
