"""table.py: rebuild shipped rows, lookup, and every way a table file can be wrong."""

from __future__ import annotations

import numpy as np
import pytest

from pickplace_cli.lookup import bspline_table as T
from pickplace_cli.lookup import bspline_build as T_build
from pickplace_cli.lookup import bspline_optimum as T_optimum
from pickplace_cli.model.errors import TableError


@pytest.mark.slow
def test_rebuild_sample_rows_matches_shipped_table():
    """A fresh build of a few λ equals the shipped rows: k within 2e-4 (Nelder-Mead xatol 1e-5 on a flat
    ridge of F), F within 1e-7 relative (F is flat there to second order)."""
    shipped = T.load_table()
    lams = [1.0, 7.5, 28.0, 40.0]
    fresh = T_build.build_table(lams, T_optimum.TableSettings())
    for r in fresh.rows:
        ref = next(x for x in shipped.rows if x.lam == r.lam)
        assert r.k1 == pytest.approx(ref.k1, abs=2e-4) and r.k2 == pytest.approx(ref.k2, abs=2e-4)
        assert r.F == pytest.approx(ref.F, rel=1e-7)
        assert r.a_min == pytest.approx(ref.a_min, rel=1e-7) and r.j_min == pytest.approx(ref.j_min, rel=1e-7)


def test_shipped_table_provenance_and_shape():
    tab = T.load_table()
    assert tab.lam[0] == 1.0 and tab.lam[-1] == 40.0 and np.all(np.diff(tab.lam) <= 0.5 + 1e-12)
    assert tab.eta == 0.5
    assert tab.meta["weights"] == "0.5,0.5"
    assert "tool_version" in tab.meta and "fit_k1" in tab.meta
    # every row's peaks are the exact peaks at its (k1, k2) (1e-9: printed with 10 significant digits)
    for r in tab.rows[::10]:
        v, a, j = T_optimum.normalised_peaks(r.k1, r.k2, r.lam, 0.5)
        assert (v, a, j) == pytest.approx((r.v_max, r.a_max, r.j_max), rel=1e-8)
        assert r.F == pytest.approx(0.5 * r.a_min / a + 0.5 * r.j_min / j, rel=1e-8)


def test_lookup_interpolates_and_refuses_outside():
    tab = T.load_table()
    k1, k2 = tab.lookup(28.25)
    r0, r1 = (next(x for x in tab.rows if x.lam == v) for v in (28.0, 28.5))
    assert k1 == pytest.approx((r0.k1 + r1.k1) / 2, abs=1e-12)
    with pytest.raises(TableError, match="outside the table's range"):
        tab.lookup(0.5)
    with pytest.raises(TableError, match="outside the table's range"):
        tab.lookup(41)
    with pytest.raises(TableError, match="built for eta = 0.5"):
        tab.lookup(10, eta=0.6)


def test_scalar_lookup_is_numpy_interp_bitwise():
    """Table.lookup (one λ, plain floats) must give np.interp's bits: the batch verdict engine interpolates
    thousands of λ with np.interp, and a move planned alone must equal the same move in a batch."""
    tab = T.load_table()
    xp = tab.lam
    rng = np.random.default_rng(7)
    xs = np.concatenate([rng.uniform(xp[0], xp[-1], 5000), xp, np.nextafter(xp[1:], -np.inf), np.nextafter(xp[:-1], np.inf)])
    got = np.array([tab.lookup(float(x)) for x in xs])
    want = np.stack([np.interp(xs, xp, tab.column("k1")), np.interp(xs, xp, tab.column("k2"))], axis=1)
    assert np.array_equal(got, want)


GOOD = "# eta: 0.5\nlambda,k1,k2\n1,0.5,0.4\n2,0.55,0.3\n"


@pytest.mark.parametrize(
    "text,match",
    [
        ("", "no table rows"),
        ("lambda,k1,k2\n1,0.5,0.4\n2,0.55,0.3\n", "no '# eta: VALUE' header"),
        ("lambda,k1\n1,0.5\n", "lacks column"),
        ("lambda,k1,k2\n1,0.5,0.4\n2,abc,0.3\n", r":4: not a number"),
        ("lambda,k1,k2\n1,0.5,0.4\n2,0.5\n", r":4: 2 values"),
        ("lambda,k1,k2\n1,0.5,0.4\n2,1.5,0.3\n", r"k1 = 1.5: must lie strictly between 0 and 1"),
        ("lambda,k1,k2\n2,0.5,0.4\n1,0.5,0.3\n", "increase strictly"),
        ("lambda,k1,k2\n1,nan,0.4\n2,0.5,0.3\n", "finite"),
    ],
)
def test_corrupt_tables(text, match):
    if "eta" not in match and text:
        text = "# eta: 0.5\n" + text
    with pytest.raises(TableError, match=match):
        T.parse_table(text, "t.csv")


def test_missing_table(tmp_path):
    with pytest.raises(TableError, match="no such file"):
        T.load_table(tmp_path / "nope.csv")


def test_format_parse_round_trip():
    tab = T.load_table()
    text = T.format_table(T.Table(tab.rows, meta={"eta": 0.5}), "0.0")
    back = T.parse_table(text, "back.csv")
    for c in T.COLUMNS:  # 10 significant digits printed
        np.testing.assert_allclose(back.column(c), tab.column(c), rtol=1e-9)
    assert back.eta == 0.5
    assert T.parse_table(GOOD, "g.csv").lookup(1.5) == pytest.approx((0.525, 0.35))


def test_lambda_grid():
    g = T_build.lambda_grid(1, 40, 0.5)
    assert len(g) == 79 and g[0] == 1 and g[-1] == 40
    assert T_build.lambda_grid(1, 2, 0.3).tolist() == [1.0, 1.3, 1.6, 1.9, 2.0]
    with pytest.raises(TableError):
        T_build.lambda_grid(2, 1, 0.5)
    with pytest.raises(TableError):
        T_build.lambda_grid(1, 2, 0)


def test_settings_validation():
    with pytest.raises(TableError, match="weights"):
        T_optimum.TableSettings(weights=(0.5, 0.6))
    with pytest.raises(TableError, match="eta"):
        T_optimum.TableSettings(eta=1.0)


# ------------------------------------------------------------------ fast closed-form path vs scipy BSpline


def test_fast_peaks_match_scipy_reference_inside_the_box():
    """The build's batched closed form (unit_pieces + unit_peaks) against the scipy BSpline path of
    normalised_peaks, which shares no code with it, at 300 random (k1, k2, λ) with k1 in [0.05, 0.95]
    (every optimum lies in [0.18, 0.6]) and k2 down to the floor 1e-4. Tolerance 2e-9 relative: both are
    exact up to round-off, and where the optima lie we measure ~1e-13; the closed form loses digits
    towards small k1 (3e-10 at k1 = 0.05, k2 = 0.99, checked against a 50-digit mpmath solve), and
    scipy's own peak root sometimes ~7e-11."""
    rng = np.random.default_rng(7)
    k1 = rng.uniform(0.05, 0.95, 300)
    k2 = np.where(rng.random(300) < 0.2, 1e-4, rng.uniform(1e-4, 0.95, 300))
    lam = rng.uniform(0.5, 60.0, 300)
    for a, b, l in zip(k1, k2, lam):
        fast = T_optimum.fast_peaks(a, b, l, 0.5)[0]
        ref = np.array(T_optimum.normalised_peaks(a, b, l, 0.5))
        np.testing.assert_allclose(fast, ref, rtol=2e-9, err_msg=f"k1={a}, k2={b}, lam={l}")
    # batched = one at a time, and η other than 0.5
    batch = T_optimum.fast_peaks(k1[:20], k2[:20], 12.0, 0.3)
    one = np.array([T_optimum.normalised_peaks(a, b, 12.0, 0.3) for a, b in zip(k1[:20], k2[:20])])
    np.testing.assert_allclose(batch, one, rtol=2e-9)


def test_fast_peaks_near_the_corners_of_the_box():
    """Towards k1 → 0 the closed form loses digits: its Taylor coefficients at τ8 = k1/2 grow like
    (1/k1)^r and cancel along the long piece to τ = 1/2. Against a 50-digit mpmath solve we measure
    9.2e-6 relative at (k1, k2) = (1e-3, 0.99), 1.1e-8 at k1 = 0.01, 1e-10 at k1 = 0.999 (scipy: 4e-13).
    Tolerance 5e-5. The optimiser never goes there: F is tiny at the corners, no refinement starts
    there, and the coarse grid only ranks those points (values ~1e5 where the optima have ~10)."""
    for a in (1e-3, 0.01, 0.999):
        for b in (1e-4, 1e-3, 0.5, 0.99):
            np.testing.assert_allclose(T_optimum.fast_peaks(a, b, 5.0)[0], T_optimum.normalised_peaks(a, b, 5.0), rtol=5e-5)


def test_unit_pieces_are_the_li2018_spline():
    """Position and derivatives 1–5 of the closed-form pieces equal scipy's BSpline of Eq. (16) at
    random τ on both halves (the second by the mirror symmetry the closed form relies on). 1e-9 of the
    derivative's scale: high derivatives are ~1e4 at k2 = 0.05 and carry that many ulps."""
    rng = np.random.default_rng(3)
    for a, b in ((0.31, 0.12), (0.55, 0.4), (0.2, 0.05), (0.45, 1e-4)):
        h, coef = T_optimum.unit_pieces(a, b, 0.5)
        spline = T_optimum._unit_spline(a, b, 0.5)
        starts = np.concatenate(([0.0], np.cumsum(h[0])))
        for tau in rng.uniform(0, 1, 25):
            mirror = tau > 0.5
            t = 1.0 - tau if mirror else tau
            j = min(int(np.searchsorted(starts, t, side="right")) - 1, 2)
            x = t - starts[j]
            for r in range(6):
                P = np.polynomial.polynomial
                val = np.array([P.polyval(x, P.polyder(coef[0, j, d], r)) for d in range(2)])
                ref = spline(tau, nu=r)
                if mirror:  # s_u(τ) = 1 − s_u(1 − τ), s_v(τ) = s_v(1 − τ)
                    val = val * (-1.0) ** r
                    val[0] = 1.0 - val[0] if r == 0 else -val[0]
                scale = np.max(np.abs(spline(np.linspace(0, 1, 201), nu=r))) + 1e-300
                np.testing.assert_allclose(val, ref, atol=1e-9 * scale, err_msg=f"k=({a},{b}) tau={tau} r={r}")


def test_coarse_samples_under_estimate_exact_peaks_slightly():
    """The coarse stage's sampled peaks never exceed the exact peaks and stay within 1 % of them (16
    samples per piece: the reason ``basin_margin`` is 3 %)."""
    coarse = T_optimum._coarse_for(T_optimum.TableSettings(grid_step=0.1))
    for lam in (1.0, 12.0, 40.0):
        a_s, j_s = coarse.peaks(lam)
        exact = T_optimum.fast_peaks(coarse.k1, coarse.k2, lam, 0.5, (2, 3))
        assert np.all(a_s <= exact[:, 0] * (1 + 1e-12)) and np.all(j_s <= exact[:, 1] * (1 + 1e-12))
        assert np.all(a_s >= 0.99 * exact[:, 0]) and np.all(j_s >= 0.99 * exact[:, 1])
