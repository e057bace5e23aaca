"""peaks.py: exact piecewise-polynomial maxima and the golden-section refinement."""

from __future__ import annotations

import numpy as np
import pytest

from pickplace_cli.peaks import ppoly_norm_peak, refine_max


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
