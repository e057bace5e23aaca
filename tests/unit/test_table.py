"""table.py: rebuild shipped rows, lookup, and every way a table file can be wrong."""

from __future__ import annotations

import numpy as np
import pytest

from pickplace_cli import table as T
from pickplace_cli.errors import TableError


@pytest.mark.slow
def test_rebuild_sample_rows_matches_shipped_table():
    """A fresh build of a few λ equals the shipped rows: k within 2e-4 (Nelder-Mead xatol 1e-5 on a flat
    ridge of F), F within 1e-7 relative (F is flat there to second order)."""
    shipped = T.load_table()
    lams = [1.0, 7.5, 28.0, 40.0]
    fresh = T.build_table(lams, T.TableSettings())
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
        v, a, j = T.normalised_peaks(r.k1, r.k2, r.lam, 0.5)
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
    g = T.lambda_grid(1, 40, 0.5)
    assert len(g) == 79 and g[0] == 1 and g[-1] == 40
    assert T.lambda_grid(1, 2, 0.3).tolist() == [1.0, 1.3, 1.6, 1.9, 2.0]
    with pytest.raises(TableError):
        T.lambda_grid(2, 1, 0.5)
    with pytest.raises(TableError):
        T.lambda_grid(1, 2, 0)


def test_settings_validation():
    with pytest.raises(TableError, match="weights"):
        T.TableSettings(weights=(0.5, 0.6))
    with pytest.raises(TableError, match="eta"):
        T.TableSettings(eta=1.0)
