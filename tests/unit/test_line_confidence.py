"""The miss rate's and picks/min's intervals (:mod:`pickplace_cli.line.confidence`) against independent computations:
scipy's own Wilson interval (``binomtest(...).proportion_ci``), the batch-means ratio estimator and the seeds' t
interval written out here in plain Python, and the coverage of both intervals on synthetic miss sequences with a
fixed seed: independent misses (both cover their true rate about 95 % of the time) and misses that come in bunches
(a two-state Markov chain: batch means still covers it, Wilson far less — why the line reports batch means)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from pickplace_cli.line.confidence import across_seeds, run_intervals, wilson


@pytest.mark.parametrize("k,n", [(0, 10), (3, 10), (41, 301), (300, 301), (1, 1)])
def test_wilson_is_scipys(k, n):
    ci = stats.binomtest(k, n).proportion_ci(confidence_level=0.95, method="wilson")
    lo, hi = wilson(k, n)
    assert lo == pytest.approx(ci.low, abs=1e-12) and hi == pytest.approx(ci.high, abs=1e-12)


def _by_hand(t, missed, B, picks):
    """The batch means written out with lists: windows of equal length over [t0, t1], the last one closed."""
    t0, t1 = min(t), max(t)
    w = (t1 - t0) / B
    n = [0] * B
    m = [0] * B
    for ti, mi in zip(t, missed):
        i = min(int((ti - t0) / w), B - 1)
        n[i] += 1
        m[i] += 1 if mi else 0
    R = sum(m) / sum(n)
    nbar = sum(n) / B
    se = math.sqrt(sum((mi - R * ni) ** 2 for mi, ni in zip(m, n)) / (B * (B - 1))) / nbar
    tq = stats.t.ppf(0.975, B - 1)
    rates = [60.0 * (ni - mi) / w for ni, mi in zip(n, m)]
    mean = sum(rates) / B
    sd = math.sqrt(sum((r - mean) ** 2 for r in rates) / (B - 1))
    return R, tq * se, tq * sd / math.sqrt(B)


def test_batch_means_by_hand():
    rng = np.random.default_rng(5)
    t = np.sort(rng.uniform(0.0, 300.0, 900))
    missed = rng.random(900) < 0.2
    got = run_intervals(t, missed, 123.0)
    R, half, half_p = _by_hand(t.tolist(), missed.tolist(), 20, 123.0)
    assert got.batches == 20
    assert got.miss.estimate == pytest.approx(R, abs=1e-15)
    assert got.miss.half == pytest.approx(half, rel=1e-12)
    assert got.picks_per_minute.estimate == 123.0
    assert got.picks_per_minute.half == pytest.approx(half_p, rel=1e-12)


def test_few_parts_give_wilson_only():
    got = run_intervals(np.arange(30.0), np.zeros(30, bool), 10.0)
    assert got.miss is None and got.picks_per_minute is None and got.miss_wilson.high > 0


def test_across_seeds_by_hand():
    x = [0.035, 0.136, 0.185]
    mean = sum(x) / 3
    sd = math.sqrt(sum((v - mean) ** 2 for v in x) / 2)
    got = across_seeds(x)
    assert got.estimate == pytest.approx(mean, abs=1e-15)
    assert got.half == pytest.approx(stats.t.ppf(0.975, 2) * sd / math.sqrt(3), rel=1e-12)
    assert across_seeds([0.1]) is None


def _markov(rng, n, stay, enter):
    """Misses as a two-state chain: P(miss | miss before) = stay, P(miss | hit before) = enter, started in its
    stationary law; its true miss rate enter / (1 − stay + enter)."""
    p = enter / (1 - stay + enter)
    out = np.empty(n, bool)
    u = rng.random(n)
    out[0] = u[0] < p
    for i in range(1, n):
        out[i] = u[i] < (stay if out[i - 1] else enter)
    return out, p


def _coverage(stay, enter, reps=300, n=2000):
    rng = np.random.default_rng(20261128)
    t = np.arange(n, dtype=float)
    hit_bm = hit_w = 0
    for _ in range(reps):
        missed, p = _markov(rng, n, stay, enter)
        iv = run_intervals(t, missed, 0.0)
        hit_bm += iv.miss.low <= p <= iv.miss.high
        hit_w += iv.miss_wilson.low <= p <= iv.miss_wilson.high
    return hit_bm / reps, hit_w / reps


def test_coverage_of_independent_misses():
    """stay = enter: independent misses at 11 %; both intervals cover ~95 % (300 runs: ± 2.5 % at 2 σ; the
    bounds leave 3.5 σ)."""
    bm, w = _coverage(0.11, 0.11)
    assert 0.90 <= bm <= 0.985 and 0.90 <= w <= 0.985, (bm, w)


def test_coverage_of_misses_in_bunches():
    """Misses that follow misses (lag-1 correlation 0.55, true rate 11.1 %): batch means still covers about 95 %
    (20 windows of 100 parts, much longer than the bunches), Wilson — which takes the parts as independent — far
    less (its interval is about √((1 + 0.55)/(1 − 0.55)) ≈ 1.9 times too narrow)."""
    bm, w = _coverage(0.6, 0.05)
    assert 0.90 <= bm <= 0.985, bm
    assert w <= 0.80, w
