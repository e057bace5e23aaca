"""build-table over (λ, η) and the one-row grid (issue 16), on tiny grids (the full 2-D build is the bench's)."""

from __future__ import annotations

import json

import pytest

from tests.cli.test_cli import ADEPT, run


def test_build_table_2d_csv_and_st(tmp_path):
    out = tmp_path / "t2.csv"
    r = run("build-table", "--lambda-min", "2", "--lambda-max", "4", "--lambda-points", "2",
            "--eta-min", "0.3", "--eta-max", "0.5", "--eta-step", "0.2", "-j", "1", "-o", str(out))
    assert r.exit_code == 0, r.stderr
    assert "4 rows (2 η × 2 λ)" in r.stderr and "basin jump" in r.stderr
    from pickplace_cli.lookup.table2d import load_table_2d

    tab = load_table_2d(out)
    assert tab.etas == (0.3, 0.5) and tab.lams == (2.0, 4.0)
    text = out.read_text()
    assert "# eta_grid: 0.3..0.5 step 0.2 (2 values)" in text
    # so coarse a grid (λ 2 → 4, η 0.3 → 0.5) crosses basins: the header lists the edges and the table reads them
    assert text.count("# basin_jumps: ") == 1 and len(tab.jumps) == text.split("# basin_jumps: ")[1].splitlines()[0].count(";") + 1
    st = tmp_path / "t2.st"
    r = run("build-table", "--lambda-min", "2", "--lambda-max", "4", "--lambda-points", "2", "--eta-list", "0.3,0.5",
            "-j", "1", "-q", "-f", "st", "-o", str(st))
    assert r.exit_code == 0, r.stderr
    assert "PP_TABLE2D_K1 : ARRAY[1..2, 1..2] OF LREAL" in st.read_text()


def test_one_row_grid_builds_and_plans(tmp_path):
    """--lambda-min 28 --lambda-max 28: one row, not refused; plan reads it at λ = 28."""
    out = tmp_path / "t.csv"
    r = run("build-table", "--lambda-min", "28", "--lambda-max", "28", "-j", "1", "-q", "-o", str(out))
    assert r.exit_code == 0, r.stderr
    from pickplace_cli.lookup.bspline_table import load_table

    tab = load_table(out)
    assert tab.lam.tolist() == [28.0]
    r = run("plan", *ADEPT, "--height", str(0.305 / 28), "--table", str(out), "--format", "json", "-q")
    assert r.exit_code == 0, r.stderr
    params = json.loads(r.stdout)["summary"]["parameters"]
    assert params["k_source"].startswith("table ") and params["k1"] == pytest.approx(tab.rows[0].k1, abs=1e-9)
    r = run("build-table", "--lambda-min", "28", "--lambda-max", "28", "-j", "1", "-q", "-f", "st", "-o", str(tmp_path / "t.st"))
    assert r.exit_code == 0 and "PP_TABLE_ROWS : DINT := 1;" in (tmp_path / "t.st").read_text()


@pytest.mark.parametrize("args,msg", [
    (["--eta-min", "0.9", "--eta-max", "0.1"], "--eta-max 0.1: must not be less than eta-min = 0.9"),
    (["--eta-min", "0", "--eta-max", "0.5"], "--eta-min 0.0: must lie in [0.01, 0.99]"),
    (["--eta-list", "0.2,x"], "--eta-list '0.2,x': give numbers separated by commas"),
    (["--eta-min", "0.2", "-f", "json"], "-f/--format json: a 2-D (λ, η) table is written as csv or st"),
    (["--lambda-points", "1"], "--lambda-points 1: need 1 for lambda-min = lambda-max, else at least 2"),
])
def test_build_table_2d_bad_input(tmp_path, args, msg):
    out = tmp_path / "t.out"  # (a suffix that names no format: -f decides)
    r = run("build-table", *args, "-o", str(out), "-q")
    assert r.exit_code == 1 and msg in r.stderr and len(r.stderr.strip().splitlines()) == 1 and not out.exists()


def test_eta_list_and_eta_min_together_is_a_usage_error(tmp_path):
    r = run("build-table", "--eta-list", "0.2,0.3", "--eta-min", "0.2", "-o", str(tmp_path / "t.csv"), "-q")
    assert r.exit_code == 2 and "--eta-list replaces --eta-min/--eta-max" in r.stderr


def test_plan_eta_half_unchanged_and_eta_04_uses_the_2d_table():
    r = run("plan", *ADEPT, "--format", "json", "-q")
    assert json.loads(r.stdout)["summary"]["parameters"]["k_source"] == "table bspline-eta0.5.csv (shipped)"
    r = run("plan", *ADEPT, "--eta", "0.4", "--format", "json", "-q")
    assert r.exit_code == 0
    assert json.loads(r.stdout)["summary"]["parameters"]["k_source"] == "2-D table bspline-2d.csv (shipped), interpolated"
