"""The septic Hermite interpolant ``check`` reads a full-column file with (``curves/sampled.septic_coefficients``),
solved on every interval at once, against scipy's ``BPoly.from_derivatives`` (the same unique polynomial, built
interval by interval through Bernstein coefficients) on a smooth motion sampled at uneven steps: every derivative up
to the jerk on 20 001 points, to 1e-8 of that derivative's largest value (scipy's own error in the jerk at 1 ms
steps is ~1e-10 of it), and the end conditions at every sample to 1e-13 (scipy's: ~1e-10)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.interpolate import BPoly, PPoly

from pickplace_cli.curves.sampled import hermite, septic_coefficients


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_septic_against_scipy_from_derivatives(seed):
    rng = np.random.default_rng(seed)
    n = 60
    t = np.concatenate([[0.0], np.cumsum(rng.uniform(0.2e-3, 2e-3, n - 1))])  # uneven steps, 0.2-2 ms
    # a smooth motion (three sines per coordinate, up to 60 Hz) and its exact derivatives, as a planner writes them
    amp, omega, phase = rng.uniform(0.01, 0.1, (3, 3)), rng.uniform(5.0, 400.0, (3, 3)), rng.uniform(0, 6.3, (3, 3))
    arg = omega[None] * t[:, None, None] + phase[None]  # (n, 3 sines, 3 coordinates)
    data = np.stack([(amp * omega**k * np.sin(arg + k * np.pi / 2)).sum(axis=1) for k in range(4)], axis=1)
    ours = PPoly(septic_coefficients(t, data), t)
    ref = PPoly.from_bernstein_basis(BPoly.from_derivatives(t, data))
    x = np.linspace(0.0, t[-1], 20_001)
    for nu in range(4):  # scipy's Bernstein route meets its own end conditions to ~1e-10 of the jerk's peak (~1e-13
        scale = np.abs(ref(x, nu)).max()  # of the positions'): the two agree to that
        assert np.abs(ours(x, nu) - ref(x, nu)).max() <= 1e-8 * scale, nu
    for nu in range(4):  # ours meets the end conditions at every sample (the last from its left) to round-off
        assert np.abs(ours(t, nu) - data[:, nu]).max() <= 1e-13 * np.abs(data[:, nu]).max(), nu


def test_hermite_of_a_polynomial_motion_is_exact():
    """A septic motion is its own interpolant: hermite() returns it (no jerk step found) to round-off."""
    t = np.linspace(0.0, 0.1, 101)
    coef = np.array([3.0, -2.0, 1.5, 0.7, -4.0, 2.0, 1.0, 0.5])  # powers of t/0.1, degree 7
    u = t / 0.1
    def der(nu):
        c = coef.copy()
        out = np.zeros_like(u)
        for k in range(nu, 8):
            f = np.prod(np.arange(k - nu + 1, k + 1)) if nu else 1.0
            out += c[k] * f * u ** (k - nu)
        return out / 0.1**nu
    cols = [der(nu)[:, None].repeat(3, axis=1) for nu in range(4)]
    ev, steps = hermite(t, *cols)
    x = np.linspace(0.0, 0.1, 5001)
    ux = x / 0.1
    want = sum(coef[k] * np.prod(np.arange(k - 2, k + 1)) * ux ** (k - 3) for k in range(3, 8)) / 0.1**3
    assert steps.size == 0
    assert np.abs(ev(x, 3)[:, 0] - want).max() <= 1e-9 * np.abs(want).max()
