"""Reproduce Li, Huang & Chetwynd 2018 (quintic B-spline) numbers: Table 1, Sec. 3.1, Fig. 4 optimum,
Table 2, Eq. (26). Each test names its source and tolerance."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pickplace_cli.lookup import bspline_table as T
from pickplace_cli.lookup import bspline_optimum as T_optimum
from pickplace_cli.curves.bspline import piece_coefficients, _left_derivatives
from pickplace_cli.paths.bspline import plan_bspline
from pickplace_cli.model.task import Task

LAM, ETA = 28.0, 0.5


def test_table1_bspline_peaks():
    """Table 1 (B-spline, λ = 28, η = 0.5, k1 = 0.31, k2 = 0.12): a_max = 9.0, j_max = 84.0.

    We get 9.0153 and 84.079. Tolerance ±0.1: the paper prints one decimal, and 84.08 rounds to 84.1, one
    unit in the last printed place from 84.0 (their sampling of the curve probably missed the true peak).
    """
    v, a, j = T_optimum.normalised_peaks(0.31, 0.12, LAM, ETA)
    assert a == pytest.approx(9.0, abs=0.1)
    assert j == pytest.approx(84.0, abs=0.1)


def test_optimum_of_F_at_lambda_28():
    """Fig. 4: max F at k1* = 0.31, k2* = 0.12 (w_a = w_j = 0.5).

    The paper's optimum is the best point of a 0.01 grid: we find exactly (0.31, 0.12) there. The
    continuous optimum lies on the kink ridge of F at (0.3141, 0.1066): k1 agrees to two decimals, k2 does
    not (0.11); F differs by 0.003 between them, so the ridge is flat. Both are reported in README."""
    row = T.load_table().rows
    r28 = next(r for r in row if r.lam == LAM)
    a_min, j_min = r28.a_min, r28.j_min
    grid = np.round(np.arange(0.25, 0.40, 0.01), 2)
    k2s = np.round(np.arange(0.05, 0.20, 0.01), 2)
    best = max(
        ((0.5 * a_min / p[0] + 0.5 * j_min / p[1], k1, k2) for k1 in grid for k2 in k2s for p in [T_optimum.normalised_peaks(k1, k2, LAM, ETA, (2, 3))]),
    )
    assert (best[1], best[2]) == (0.31, 0.12)
    assert round(r28.k1, 2) == 0.31
    assert r28.F >= best[0] - 1e-9  # the continuous optimum is at least as good as any grid point
    assert r28.k2 == pytest.approx(0.1066, abs=5e-4)


def test_section31_minima_locations():
    """Sec. 3.1 at λ = 28: a_max's infimum as k2 → 0 at k1 = 0.21 and rising with k2 along the valley;
    j_max's minimum at (0.34, 0.07) (true on a 0.01 grid; continuous minimum (0.3446, 0.0578))."""
    from scipy.optimize import minimize_scalar

    def a_valley(k2):
        r = minimize_scalar(lambda x: T_optimum.normalised_peaks(x, k2, LAM, ETA, (2,))[0], bounds=(0.1, 0.4), method="bounded", options={"xatol": 1e-7})
        return r.x, r.fun

    k1_0, a0 = a_valley(1e-4)
    assert round(k1_0, 2) == 0.21
    vals = [a_valley(k2)[1] for k2 in (1e-4, 0.01, 0.05, 0.1, 0.2, 0.4)]
    assert all(np.diff(vals) > 0)  # monotonic increase along the valley
    k1s = np.round(np.arange(0.30, 0.40, 0.01), 2)
    k2s = np.round(np.arange(0.01, 0.15, 0.01), 2)
    jmin = min((T_optimum.normalised_peaks(a, b, LAM, ETA, (3,))[0], a, b) for a in k1s for b in k2s)
    assert (jmin[1], jmin[2]) == (0.34, 0.07)


def _rms(k1, k2, order):
    """Exact ∫‖d^r s/dτ^r‖² dτ over [0, 1] from the piece polynomials, square-rooted (Eq. 18-19)."""
    s = T_optimum._unit_spline(k1, k2, ETA)
    br = np.unique(s.t)
    d = [x * np.array([1.0, 1.0 / LAM]) for x in _left_derivatives(s, br)]
    b, c = piece_coefficients(s, order, d)
    total = 0.0
    for i in range(len(b) - 1):
        sq = sum(np.polymul(c[i, k], c[i, k]) for k in range(2))
        total += np.polyval(np.polyint(sq), b[i + 1] - b[i])
    return math.sqrt(total)


def test_section31_rms_minima():
    """Sec. 3.1: a_rms's minimum as k2 → 0 at k1 = 0.23 (holds: 0.228); j_rms's at k1 = 0.31 as k2 → 0
    — does NOT hold to two decimals: we find 0.3006 (k1 = 0.30). Asserted as we find it, noted in README."""
    from scipy.optimize import minimize_scalar

    ra = minimize_scalar(lambda x: _rms(x, 1e-4, 2), bounds=(0.1, 0.5), method="bounded", options={"xatol": 1e-7})
    rj = minimize_scalar(lambda x: _rms(x, 1e-4, 3), bounds=(0.1, 0.5), method="bounded", options={"xatol": 1e-7})
    assert round(ra.x, 2) == 0.23
    assert rj.x == pytest.approx(0.3006, abs=1e-3)
    # and both rise with k2 (the minimum is at the boundary k2 → 0)
    assert _rms(ra.x, 0.05, 2) > ra.fun and _rms(rj.x, 0.05, 3) > rj.fun


def test_table2_polynomial_agrees_with_our_table():
    """Table 2 / Eq. 23: the paper's cubic vs our optimal table on λ ∈ [5, 40]: k1 within 0.01, k2 within
    0.02 (the issue's tolerances; we measure 0.008 and 0.016). Our own fit reproduces our table on the fit
    range to within its recorded residual (k1 ≈ 0.009: k1*(λ) is not exactly cubic)."""
    tab = T.load_table()
    lam = tab.lam
    sel = (lam >= 5) & (lam <= 40)
    poly = np.polynomial.polynomial
    k1_paper = poly.polyval(lam[sel], T.LI2018_TABLE2[0])
    k2_paper = poly.polyval(lam[sel], T.LI2018_TABLE2[1])
    assert np.max(np.abs(tab.column("k1")[sel] - k1_paper)) < 0.01
    assert np.max(np.abs(tab.column("k2")[sel] - k2_paper)) < 0.02
    g1, g2, res = tab.fit(5.0)
    assert res < 0.01
    assert np.max(np.abs(poly.polyval(lam[sel], g1) - tab.column("k1")[sel])) <= res + 1e-12
    assert np.max(np.abs(poly.polyval(lam[sel], g2) - tab.column("k2")[sel])) <= res + 1e-12


def test_eq26_cycle_time_section4():
    """Sec. 4: b = 0.7 m, [v] = 10 m/s, [a] = 160 m/s² → T = 0.198 s for the B-spline.

    With the exact a_max = 9.0153 (k = 0.31, 0.12) Eq. 26 gives 0.1986 s; the paper's 0.198 follows from
    its rounded a_max = 9.0 (0.1984 s). Tolerance 1 ms."""
    from pickplace_cli.model.profile import Capacity
    from pickplace_cli.timing import choose_duration

    task = Task([0.0, 0.0, -0.8], [0.7, 0.0, -0.8], 0.7 / LAM, ETA)
    path = plan_bspline(task, k1=0.31, k2=0.12)
    d = choose_duration(path, Capacity(velocity=10.0, acceleration=160.0))
    assert d.seconds == pytest.approx(0.198, abs=1e-3)
    assert d.binding == "acceleration"
    assert math.sqrt(9.0 * 0.7 / 160) == pytest.approx(0.198, abs=5e-4)


@pytest.mark.slow
@pytest.mark.parametrize("lam", [1.0, 2.0, 5.0, 28.0])
def test_table_optimum_is_global(lam):
    """The table's F at λ is not beaten by an independent global optimiser (scipy differential evolution
    on the exact F with the table's own normalisers, seeded). Small λ included: F has two local maxima
    there. Tolerance 1e-6 in F (the table refines k to ~1e-5; F is flat to second order off the kink)."""
    from scipy.optimize import differential_evolution

    tab = T.load_table()
    r = next(x for x in tab.rows if x.lam == lam)

    def neg_f(x):
        a, j = T_optimum.normalised_peaks(float(x[0]), float(x[1]), lam, ETA, (2, 3))
        return -(0.5 * r.a_min / a + 0.5 * r.j_min / j)

    res = differential_evolution(neg_f, [(0.01, 0.99), (1e-4, 0.99)], seed=1, tol=1e-10, maxiter=300, popsize=20, polish=True)
    assert r.F >= -res.fun - 1e-6, (r, res.x, -res.fun)
