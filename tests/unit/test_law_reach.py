"""The reachability pass of ``--time optimal`` (:mod:`pickplace_cli.timing.law_reach`) against an independent
brute-force dynamic programme over a dense grid of b, and on a real path against the plan's own rows."""

from __future__ import annotations

import numpy as np
import pytest

from pickplace_cli.timing.law_reach import reach


def _rows(n: int, seed: int):
    """Torque-like rows on n points of τ ∈ [0, 1] for two joints: |A·b + m·b′/2 + G| ≤ 1 with smooth A, m, G
    (m vanishing at the ends like p′ of a rest-to-rest path), and a speed bound b ≤ upper."""
    rng = np.random.default_rng(seed)
    tau = np.linspace(0.0, 1.0, n)
    a, c, r = [], [], []
    for _ in range(2):
        A = rng.uniform(-0.5, 0.5) + 0.4 * np.sin(2 * np.pi * tau + rng.uniform(0, 6))
        m = (0.5 + rng.uniform(0, 0.5)) * np.sin(np.pi * tau) * rng.choice([-1, 1])
        G = rng.uniform(-0.2, 0.2) * np.ones(n)
        a += [A, -A]
        c += [m / 2, -m / 2]
        r += [1 - G, 1 + G]
    upper = 3.0 + np.cos(3 * tau + rng.uniform(0, 6))
    return tau, np.array(a), np.array(c), np.array(r), upper


def _dp(tau, a, c, r, upper, lower, levels: int) -> float:
    """The shortest duration over laws whose b takes one of ``levels`` values at each point: the exact minimum
    over that restricted set (so never below the pass's, and above it by the levels' spacing at most)."""
    x = np.linspace(lower, upper.max(), levels)
    n = len(tau)
    ok_last = np.all(a[:, -1, None] * x[None, :] <= r[:, -1, None] + 1e-12, axis=0) & (x <= upper[-1])
    cost = np.where(ok_last, 0.0, np.inf)  # cost-to-go from point n−1
    for i in range(n - 2, -1, -1):
        d = tau[i + 1] - tau[i]
        v = (x[None, :] - x[:, None]) / d  # (from, to)
        ok = np.all(a[:, i, None, None] * x[None, :, None] + c[:, i, None, None] * v[None] <= r[:, i, None, None] + 1e-12,
                    axis=0)
        ok &= (x <= upper[i])[:, None]
        step = 2 * d / (np.sqrt(x)[:, None] + np.sqrt(x)[None, :])
        cost = np.min(np.where(ok, step + cost[None, :], np.inf), axis=1)
    return float(cost.min())


@pytest.mark.parametrize("seed", range(4))
def test_reach_matches_a_brute_force_dynamic_programme(seed):
    # the pass is exact for its discrete problem; the DP restricts b to 1500 levels, so it lies above by the
    # levels' spacing (~2e-3 of b's range: well under 1 % of the duration at these b) and never below (1e-9:
    # round-off)
    tau, a, c, r, upper = _rows(30, seed)
    res = reach(tau, a, c, r, upper, 0.05)
    t_dp = _dp(tau, a, c, r, upper, 0.05, 1500)
    assert res.t_lower <= t_dp * (1 + 1e-9)
    assert t_dp <= res.t_lower * 1.01, (t_dp, res.t_lower)
    # the greedy law holds every row at every point (its b′ from differences), and stays under bmax
    v = np.diff(res.b) / np.diff(tau)
    lhs = a[:, :-1] * res.b[:-1] + c[:, :-1] * v
    assert np.all(lhs <= r[:, :-1] + 1e-9 * (1 + np.abs(r[:, :-1])))
    assert np.all(res.b <= res.bmax * (1 + 1e-12)) and np.all(res.b >= 0.05 * (1 - 1e-12))


def test_reach_raises_when_no_law_holds_the_rows():
    tau = np.linspace(0.0, 1.0, 5)
    a, c = np.ones((1, 5)), np.zeros((1, 5))
    with pytest.raises(ValueError, match="reachability"):
        reach(tau, a, c, np.full((1, 5), 0.01), np.full(5, 1.0), 0.05)  # b ≤ 0.01 against b ≥ 0.05


def test_reach_law_bounds_the_plans_optimal_law_from_below():
    # the pass holds a subset of the plan's rows (no jerk, torque rate or RMS) on any law, so its duration is
    # below the optimal plan's exact-checked one; and the plan's law stays under the controllable sets' edge
    # bmax (2 %: the pass holds its rows at its grid points with b′ constant per interval)
    from pickplace_cli.model.task import Task
    from pickplace_cli.planner import PlanOptions, motion_model, plan
    from pickplace_cli.timing.law_reach import reach_law
    from pickplace_cli.timing.optimal import optimal_law
    from tests.property.test_limit_truth import _profile

    prof = _profile("delta-su2018")
    task = Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5)
    fit = plan(task, prof, PlanOptions(time="fit"))
    model = motion_model(fit.cartesian.path, prof)
    res = reach_law(model, fit.duration.seconds, points=101)
    law = optimal_law(model, prof.planning.dwell, fit.duration.seconds, 20).law
    t_law = float(np.trapezoid(law(np.linspace(0, 1, 20001)) ** -0.5, np.linspace(0, 1, 20001)))
    assert 0.3 * fit.duration.seconds < res.t_lower < t_law
    assert np.all(law(res.tau) <= res.bmax * 1.02)
