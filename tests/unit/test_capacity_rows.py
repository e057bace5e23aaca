"""The Cartesian capacity's limit rows (limits.check.capacity_rows) and what a row the rule does not hold means for
the report (LimitReport.ok, all_ok, violations, exceeded_not_held, exit code, rated, JSON)."""

from __future__ import annotations

import numpy as np
import pytest

from pickplace_cli import PlanOptions, Task, load_profile, plan
from pickplace_cli.limits.check import capacity_rows
from pickplace_cli.limits.report import LimitReport, LimitRow
from pickplace_cli.paths import plan_path

ADEPT = Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5)


def _report(not_held: str) -> LimitReport:
    rows = (LimitRow("q1", "motor torque", "N·m", 1.0, 2.0, 0.5, 0.01, True),
            LimitRow("tool", "capacity acceleration", "m/s²", 150.0, 100.0, 1.5, None, False, not_held=not_held))
    return LimitReport(rows, 0.2, 0.1)


def test_a_row_not_held_is_reported_but_does_not_decide_the_verdict():
    held, loose = _report(""), _report("--time fit")
    assert not held.ok and held.exit_code() == 3 and len(held.violations) == 1 and held.exceeded_not_held == ()
    assert loose.ok and loose.exit_code() == 0 and loose.violations == ()
    assert not loose.all_ok and [r.quantity for r in loose.exceeded_not_held] == ["capacity acceleration"]
    doc = loose.as_dict()
    assert doc["ok"] is True and doc["all_limits_ok"] is False
    assert doc["exceeded_not_held"][0]["held"] is False and doc["exceeded_not_held"][0]["not_held"] == "--time fit"
    assert all(r["held"] for r in held.as_dict()["rows"])
    # a limit-use restatement keeps why a row is not held (the row's limit becomes its rating: 100 / 0.8)
    rated = loose.rated(0.8)
    assert rated.rows[1].not_held == "--time fit" and rated.rows[1].limit == pytest.approx(125.0, rel=1e-15)


def test_capacity_rows_on_a_grid_agree_with_the_exact_peaks_and_dense_samples():
    profile = load_profile("delta-su2018")
    path = plan_path(ADEPT, "bspline")
    T = 0.2
    exact = {r.quantity: r for r in capacity_rows(path, T, profile.capacity)}
    grid = {r.quantity: r for r in capacity_rows(path, T, profile.capacity, "--time fit", np.linspace(0, 1, 201))}
    # independent: the path's derivatives on 400,001 points, ‖d^k p/dτ^k‖ / T^k (the top sample is within
    # ~(Δτ)² of the peak: ~1e-11 relative; the grid search refines to ~1e-8 in τ, ~1e-14 relative in value)
    tau = np.linspace(0.0, 1.0, 400_001)
    dense = {q: float(np.max(np.linalg.norm(path(tau, k), axis=1))) / T**k
             for q, k in (("capacity speed", 1), ("capacity acceleration", 2))}
    for q, value in dense.items():
        assert exact[q].peak == pytest.approx(value, rel=1e-9)  # the exact peaks: 1e-9 covers the dense sampling
        assert grid[q].peak == pytest.approx(value, rel=1e-9)
        assert grid[q].not_held == "--time fit" and exact[q].held
        assert 0.0 <= grid[q].t_peak <= T and exact[q].t_peak is None


def test_plan_under_fit_has_the_capacity_rows_not_held_and_under_limits_held():
    profile = load_profile("delta-su2018")
    fit = plan(ADEPT, profile, PlanOptions(time="fit"))
    loose = [r for r in fit.report.rows if r.quantity.startswith("capacity")]
    assert [r.not_held for r in loose] == ["--time fit", "--time fit"]
    assert fit.report.ok and not fit.report.all_ok  # the Adept move under fit: 5.8 m/s, 184 m/s² (> 5, 100)
    T = fit.duration.seconds
    v, a, _ = fit.cartesian.path.peaks
    assert loose[0].peak == pytest.approx(v / T, rel=1e-12) and loose[1].peak == pytest.approx(a / T**2, rel=1e-12)
    default = plan(ADEPT, profile, PlanOptions())
    held = [r for r in default.report.rows if r.quantity.startswith("capacity")]
    assert all(r.held and r.ok for r in held) and default.report.all_ok
