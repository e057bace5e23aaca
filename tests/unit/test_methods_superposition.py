"""methods/superposition.py: the schedule of Su 2018 Sec. III, its formulas, per-axis limits, unequal heights."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pickplace_cli.paths.superposition import (
    axis_time,
    cycle_time,
    cycle_time_eq26,
    cycle_time_eq27,
    paper_duration,
    plan_superposition,
    schedule,
)
from pickplace_cli.model.profile import Capacity
from pickplace_cli.model.task import Task
from tests.conftest import ADEPT_FROM, ADEPT_TO


def test_schedule_reduces_to_the_papers_two_cases():
    a = 100.0
    # h ≤ w: horizontal starts at T1/2, descent at T2, T = T2 + T3 (Eq. 26)
    s = schedule(0.025, 0.305, 0.025, a)
    assert s["start_u"] == pytest.approx(s["T1"] / 2, rel=1e-15)
    assert s["start_down"] == pytest.approx(s["T2"], rel=1e-15)
    assert s["T"] == pytest.approx(cycle_time_eq26(0.025, 0.305, a), rel=1e-15)
    # h > w: horizontal starts at T1 − T2/2, descent at T1, T = T1 + T3 (Eq. 27)
    s = schedule(0.2, 0.05, 0.2, a)
    assert s["start_u"] == pytest.approx(s["T1"] - s["T2"] / 2, rel=1e-15)
    assert s["start_down"] == pytest.approx(s["T1"], rel=1e-15)
    assert s["T"] == pytest.approx(cycle_time_eq27(0.2, 0.05, a), rel=1e-15)
    # continuous at h = w
    assert cycle_time_eq26(0.1, 0.1, a) == pytest.approx(cycle_time_eq27(0.1, 0.1, a), rel=1e-15)


def test_formulas_vectorised_and_closed_form():
    a = 160.0
    assert axis_time(0.3, a) == pytest.approx(math.sqrt(10 * 0.3 / (math.sqrt(3) * a)), rel=1e-15)
    h = np.array([0.01, 0.5])
    np.testing.assert_allclose(cycle_time(h, 0.3, a), [cycle_time_eq26(0.01, 0.3, a), cycle_time_eq27(0.5, 0.3, a)], rtol=1e-15)


def test_each_axis_meets_its_limit_exactly_at_the_papers_time():
    """At the paper's T every axis's acceleration peak is exactly a_max (the 3-4-5 law at its limit), while
    the norm exceeds it where the axes overlap, by at most √2."""
    task = Task(ADEPT_FROM, ADEPT_TO, 0.025)
    p = plan_superposition(task)
    T = paper_duration(task, Capacity(velocity=10.0, acceleration=100.0))
    tau = np.sort(np.concatenate([np.linspace(0, 1, 20001), p.breakpoints]))
    acc = p(tau, 2) / T**2
    per_axis = np.abs(acc).max(axis=0)
    # sampled every 5e-5 of T: the sampled peak of a 3-4-5 law is within ~1e-7 of its true peak
    assert per_axis[0] == pytest.approx(100.0, rel=1e-6) and per_axis[2] == pytest.approx(100.0, rel=1e-6)
    norm = p.peaks[1] / T**2
    assert 100.0 < norm <= math.sqrt(2) * 100.0


def test_unequal_heights_and_ends():
    t = Task([0.0, 0.0, -0.8], [0.2, 0.1, -0.76], 0.03)
    p = plan_superposition(t)
    np.testing.assert_allclose(p(np.array([0.0, 1.0])), [t.p_from, t.p_to], atol=1e-15)
    assert p(np.linspace(0, 1, 2001))[:, 2].max() == pytest.approx(t.z_top, abs=1e-12)
    s = schedule(0.07, t.b, 0.03)
    assert p.parameters["paper_time_factor"] == pytest.approx(s["T"], rel=1e-15)


def test_vertical_move_has_no_horizontal_law():
    t = Task([0.0, 0.0, -0.8], [0.0, 0.0, -0.8 + 1e-3], 0.02)
    p = plan_superposition(t)
    tau = np.linspace(0, 1, 101)
    assert np.all(p(tau)[:, :2] == 0.0)
    np.testing.assert_allclose(p(np.array([1.0]))[0], t.p_to, atol=1e-15)


def test_jerk_jumps_declared():
    p = plan_superposition(Task(ADEPT_FROM, ADEPT_TO, 0.025))
    tj = np.array(p.parameters["jerk_jumps_at"])
    np.testing.assert_array_equal(tj, p.breakpoints)
    inner = tj[1:-1]
    for k, jump in ((2, False), (3, True)):
        d = np.linalg.norm(p(inner + 1e-10, k) - p(inner - 1e-10, k), axis=1) / p.peaks[k - 1]
        assert np.all(d > 0.05) if jump else np.all(d < 1e-6)
