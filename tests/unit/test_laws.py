"""laws.py: the normalised motion laws s(u), their closed-form derivatives and exact peaks."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pickplace_cli.model.errors import TaskError
from pickplace_cli.curves.laws import LAWS, POLY345, POLY4567, Law, MotionLaw, get_law, poly345, poly4567

U = np.linspace(0.0, 1.0, 20001)


def test_closed_forms():
    u = np.linspace(0, 1, 11)
    np.testing.assert_allclose(poly345(u), 10 * u**3 - 15 * u**4 + 6 * u**5, atol=1e-15)
    np.testing.assert_allclose(poly4567(u), 35 * u**4 - 84 * u**5 + 70 * u**6 - 20 * u**7, atol=1e-14)
    # the 3-4-5 law's derivatives written out by hand [Su2018, Eq. (19)]
    np.testing.assert_allclose(poly345(u, 1), 30 * u**2 - 60 * u**3 + 30 * u**4, atol=1e-13)
    np.testing.assert_allclose(poly345(u, 2), 60 * u - 180 * u**2 + 120 * u**3, atol=1e-12)
    np.testing.assert_allclose(poly345(u, 3), 60 - 360 * u + 360 * u**2, atol=1e-12)


@pytest.mark.parametrize("law", [POLY345, POLY4567])
def test_derivatives_match_central_differences(law):
    """Independent check of every derivative: central differences of the order below, step 1e-6
    (truncation ~1e-12·|s⁽ᵏ⁺²⁾| ≤ 1e-8, round-off ~1e-16·|s|/1e-6 ≤ 1e-9 → tolerance 1e-6 absolute)."""
    u = np.linspace(0.01, 0.99, 37)
    e = 1e-6
    for k in (1, 2, 3, 4):
        num = (law(u + e, k - 1) - law(u - e, k - 1)) / (2 * e)
        np.testing.assert_allclose(law(u, k), num, atol=1e-6 * max(1.0, np.abs(law(u, k)).max()))


@pytest.mark.parametrize(
    "law,peaks",
    [
        (POLY345, (15 / 8, 10 / math.sqrt(3), 60.0)),
        # 4-5-6-7: s′ peaks at 1/2 (35/16); s″ at u = (5 − √5)/10 (s‴ = 840u(1−u)(5u² − 5u + 1) = 0); |s‴| at the centre
        (POLY4567, (35 / 16, None, 52.5)),
    ],
)
def test_exact_peaks(law, peaks):
    if peaks[1] is None:
        u = (5 - math.sqrt(5)) / 10
        peaks = (peaks[0], 420 * u**2 - 1680 * u**3 + 2100 * u**4 - 840 * u**5, peaks[2])
    assert law.peaks == pytest.approx(peaks, rel=1e-12)  # closed forms vs root-finding: round-off only
    # no sample of a 20001-point grid exceeds them, and the best sample is within the grid's reach:
    # a sample ≤ δ/2 = 2.5e-5 from the peak is below it by ≤ |f″|δ²/8 ≈ 360·6e-10/5.8 ≈ 4e-8 relative,
    # so 1e-7 (a wrong root set would miss by ≫ 1e-3)
    for k in (1, 2, 3):
        assert np.abs(law(U, k)).max() <= law.peak(k) * (1 + 1e-12)
        assert np.abs(law(U, k)).max() >= law.peak(k) * (1 - 1e-7)


def test_boundary_conditions_and_rest_order():
    ends = np.array([0.0, 1.0])
    assert POLY345(ends).tolist() == [0.0, 1.0] and POLY4567(ends).tolist() == [0.0, 1.0]
    for k in (1, 2):
        np.testing.assert_allclose(POLY345(ends, k), 0.0, atol=1e-12)
    np.testing.assert_allclose(POLY345(ends, 3), [60.0, 60.0], rtol=1e-12)  # the 3-4-5 jerk step
    for k in (1, 2, 3):
        np.testing.assert_allclose(POLY4567(ends, k), 0.0, atol=1e-11)
    assert POLY345.rest_order == 2 and POLY4567.rest_order == 3


@pytest.mark.parametrize("law", [POLY345, POLY4567])
def test_symmetry_and_rest_outside(law):
    u = np.linspace(0, 1, 101)
    np.testing.assert_allclose(law(1 - u), 1 - law(u), atol=1e-14)  # s(1 − u) = 1 − s(u)
    out = np.array([-2.0, -1e-9, 1 + 1e-9, 3.0])
    assert law(out).tolist() == [0.0, 0.0, 1.0, 1.0]
    for k in (1, 2, 3):
        assert np.all(law(out, k) == 0.0)


def test_over_scales_time_and_steps():
    t = np.linspace(-1, 3, 41)
    for k in range(4):
        np.testing.assert_allclose(POLY345.over(t, 0.5, 2.0, k), POLY345((t - 0.5) / 2.0, k) / 2.0**k, atol=1e-15)
    np.testing.assert_array_equal(POLY345.over(t, 1.0, 0.0), (t >= 1.0).astype(float))
    assert not np.any(POLY345.over(t, 1.0, 0.0, 2))


def test_piece_polynomial_matches_law():
    p = POLY4567.piece_polynomials(0.2, 0.5, origin=0.3)
    x = np.linspace(0, 0.4, 9)  # t = 0.3 … 0.7, inside [0.2, 0.7]
    np.testing.assert_allclose(p(x), POLY4567.over(x + 0.3, 0.2, 0.5), atol=1e-14)
    with pytest.raises(ValueError):
        POLY4567.piece_polynomials(0.2, 0.0, 0.3)


def test_registry_and_errors():
    assert get_law("3-4-5") is POLY345 and get_law(Law.poly4567) is POLY4567 and get_law(POLY345) is POLY345
    assert set(LAWS) == set(Law)
    with pytest.raises(TaskError, match="law = 'cycloid'"):
        get_law("cycloid")
    with pytest.raises(ValueError, match="s\\(1\\) must be 1"):
        MotionLaw("bad", (0.0, 2.0))
    with pytest.raises(ValueError):
        POLY345.polynomial(-1)
