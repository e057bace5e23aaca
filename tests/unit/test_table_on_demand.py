"""A (λ, η) the shipped table does not cover is solved on demand (issue 16, part 1), and table files are
bounded inputs (part 3)."""

from __future__ import annotations

import time

import numpy as np
import pytest

import pickplace_cli.lookup.bspline_table as T
from pickplace_cli.lookup import bspline_optimum as T_optimum
from pickplace_cli.model.errors import TableError
from pickplace_cli.planner import PlanOptions, plan
from pickplace_cli.model.profile import load_profile
from pickplace_cli.model.task import Task


def test_on_demand_matches_the_shipped_table_where_it_has_rows():
    """At the table's own rows (η = 0.5) the on-demand (k1, k2) reach the table's F to 2e-6 relative, measured
    with the table's normalisers a_min, j_min; the F it reports (with its own, looser j_min) to 2e-5."""
    tab = T.load_table()
    for row in tab.rows[::13]:
        k1, k2, F = T_optimum.solve_on_demand(row.lam, 0.5)
        a, j = T_optimum.fast_peaks(k1, k2, row.lam, 0.5, (2, 3))[0]
        assert 0.5 * row.a_min / a + 0.5 * row.j_min / j == pytest.approx(row.F, rel=2e-6), row.lam
        assert F == pytest.approx(row.F, rel=2e-5), row.lam


@pytest.mark.parametrize("lam, eta", [(2.4, 0.26), (61.0, 0.5), (150.0, 0.2), (7.5, 0.85), (0.7, 0.45)])
def test_on_demand_is_build_tables_optimum(lam, eta):
    """The on-demand settings (coarser start grid) find the same F as build-table's settings, off the table."""
    full = T_optimum.TableSettings(eta=eta)
    want = T_optimum.optimise_lambda(lam, T_optimum._coarse_for(full), full)
    k1, k2, F = T_optimum.solve_on_demand(lam, eta)
    assert F >= want.F * (1 - 1e-6)


def test_on_demand_is_cached_and_extreme_lambda_is_one_line():
    T_optimum.solve_on_demand.cache_clear()
    t0 = time.perf_counter()
    first = T_optimum.solve_on_demand(33.3, 0.37)
    cold = time.perf_counter() - t0
    t0 = time.perf_counter()
    assert T_optimum.solve_on_demand(33.3, 0.37) == first
    assert time.perf_counter() - t0 < cold / 10
    with pytest.raises(TableError, match=r"lambda = b/h = 3e\+05: outside \[0.001, 100000\]"):
        T_optimum.solve_on_demand(3e5, 0.5)


def test_plan_off_the_table_says_so_instead_of_failing():
    prof = load_profile("delta-su2018")
    # η = 0.05: outside the 1-D (η = 0.5) and the 2-D (η 0.1 … 0.9) tables
    for task, why in ((Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.05), "η outside"),
                      # λ = 305: beyond the 1-D (1 … 40) and the 2-D (0.5 … 200) tables
                      (Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.001, 0.5), "λ outside")):
        p = plan(task, prof, PlanOptions())
        assert p.report.ok and p.parameters["k_source"].startswith(f"solved on demand: {why}")
        k1, k2, _ = T_optimum.solve_on_demand(round(task.lam, 12), round(task.eta, 12))
        assert (p.parameters["k1"], p.parameters["k2"]) == (k1, k2)


def test_lambda_limits_of_the_optimum():
    """What the README says about extreme λ: tall moves (λ → 0) converge to k1 ≈ 0.563, k2 ≈ 0.45; flat
    moves (λ → ∞) shrink both toward 0 (the lift-off and set-down take an ever smaller share of the move)."""
    tall = [T_optimum.solve_on_demand(lam, 0.5)[:2] for lam in (0.01, 0.1)]
    assert np.allclose(tall[0], tall[1], atol=2e-3) and tall[0][0] == pytest.approx(0.563, abs=5e-3)
    flat = [T_optimum.solve_on_demand(lam, 0.5)[:2] for lam in (200.0, 1e3, 1e4)]
    assert flat[0][0] > flat[1][0] > flat[2][0] and flat[0][1] > flat[1][1] > flat[2][1]


def test_table_files_are_bounded(tmp_path, monkeypatch):
    binary = tmp_path / "t.csv"
    binary.write_bytes(b"# pickplace table\n\x00\x01\x02")
    with pytest.raises(TableError, match="binary file"):
        T.load_table(binary)
    text = tmp_path / "latin.csv"
    text.write_bytes(b"# caf\xe9\n")
    with pytest.raises(TableError, match="not a text"):
        T.load_table(text)
    monkeypatch.setattr(T, "TABLE_MAX_BYTES", 100)
    big = tmp_path / "big.csv"
    big.write_text("#" * 200 + "\n")
    with pytest.raises(TableError, match="more than 100"):
        T.load_table(big)
