"""Invariants of the ph, superposition, lame and piecewise-poly paths over random valid moves (hypothesis):
rest at both ends, through the pick and place points, in the vertical plane, top at the clearance height,
continuity class as each method claims, and peaks that are the true maxima."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pickplace_cli.paths import Method, plan_path
from pickplace_cli.model.task import Task

METHODS = [Method.ph, Method.superposition, Method.lame, Method.piecewise_poly]
coord = st.floats(-0.5, 0.5, allow_nan=False)


@st.composite
def moves(draw):
    p0 = np.array([draw(coord), draw(coord), draw(st.floats(-0.9, -0.6))])
    p1 = np.array([draw(coord), draw(coord), draw(st.floats(-0.9, -0.6))])
    if np.linalg.norm(p1[:2] - p0[:2]) < 1e-2:
        p1[0] += 0.05
    return Task(p0, p1, draw(st.floats(0.005, 0.2)), draw(st.floats(0.1, 0.9)))


TAU = np.linspace(0.0, 1.0, 4001)


@pytest.mark.parametrize("method", METHODS, ids=lambda m: m.value)
@settings(max_examples=15, deadline=None)
@given(task=moves())
def test_rest_ends_plane_and_top(method, task):
    p = plan_path(task, method)
    np.testing.assert_allclose(p(np.array([0.0, 1.0])), [task.p_from, task.p_to], atol=1e-12)
    for k in (1, 2):
        # at rest: the laws' s′, s″ vanish at both ends exactly, so only round-off (1e-12 of the peak)
        assert np.all(np.linalg.norm(p(np.array([0.0, 1.0]), k), axis=1) <= 1e-12 * p.peaks[k - 1])
    j_ends = np.linalg.norm(p(np.array([0.0, 1.0]), 3), axis=1)
    if p.parameters["law"] == "4-5-6-7":  # jerk zero at the ends too
        assert np.all(j_ends <= 1e-9 * p.peaks[2])
    else:  # 3-4-5 laws: the declared jerk step at the ends
        assert p.parameters["law"] == "3-4-5" and p.parameters["continuity"] == 2
        assert p.parameters["jerk_jumps_at"][0] == 0.0 and p.parameters["jerk_jumps_at"][-1] == 1.0
        assert np.all(j_ends > 0)
    x = p(TAU)
    d = x - task.p_from
    # in the vertical plane through the two points (exactly, up to round-off of the frame map)
    np.testing.assert_allclose(d[:, 0] * task.e_u[1] - d[:, 1] * task.e_u[0], 0.0, atol=1e-14)
    # the highest point is the top of the path, z_top (sampling misses ≤ 1e-9 m of a smooth maximum)
    assert x[:, 2].max() <= task.z_top + 1e-12 and x[:, 2].max() >= task.z_top - 1e-6


@pytest.mark.parametrize("method", METHODS, ids=lambda m: m.value)
@settings(max_examples=15, deadline=None)
@given(task=moves())
def test_continuity_as_claimed(method, task):
    """At every breakpoint: v and a continuous; the jerk jumps exactly where ``jerk_jumps_at`` says.

    One-sided values at τ ± 1e-10: a continuous derivative moves by ≤ 2e-10·|next derivative|, ≲ 1e-6 of
    its peak even for the tightest corners here; a declared jump is ≥ 1e-5 of the jerk peak."""
    p = plan_path(task, method)
    declared = set(np.round(p.parameters["jerk_jumps_at"], 12))
    inner = p.breakpoints[(p.breakpoints > 1e-9) & (p.breakpoints < 1 - 1e-9)]
    lo, hi = inner - 1e-10, inner + 1e-10
    for k in (1, 2):
        d = np.linalg.norm(p(hi, k) - p(lo, k), axis=1)
        assert np.all(d <= 1e-6 * p.peaks[k - 1]), (k, inner, d)
    d3 = np.linalg.norm(p(hi, 3) - p(lo, 3), axis=1) / p.peaks[2]
    for t, d in zip(inner, d3):
        if np.round(t, 12) in declared:
            assert d > 1e-5, (t, d)
        else:
            assert d < 1e-6, (t, d)


@pytest.mark.parametrize("method", METHODS, ids=lambda m: m.value)
@settings(max_examples=10, deadline=None)
@given(task=moves())
def test_peaks_are_true_maxima(method, task):
    """Declared peaks vs an independent search: a 40001-sample scan plus the one-sided values at every
    breakpoint, then a 2001-point grid across ±1 step around each of the 5 best local maxima of the scan.
    The declared peak is never below any sample (1e-9: it is itself a value of the function, so only
    round-off) and within 1e-8 of the best fine-grid value (the fine step 2.5e-8 misses ≲ (2.5e-8)²/8·|f″/f|
    ≲ 1e-10 even for |f″/f| ~ 1e5, the sharp jerk peaks of tall moves)."""
    p = plan_path(task, method)
    bp = p.breakpoints
    tau = np.unique(np.concatenate([np.linspace(0, 1, 40001), bp, np.clip(bp - 1e-11, 0, 1), np.clip(bp + 1e-11, 0, 1)]))
    for k in (1, 2, 3):
        y = np.linalg.norm(p(tau, k), axis=1)
        assert y.max() <= p.peaks[k - 1] * (1 + 1e-9)
        is_max = np.concatenate([[y[0] >= y[1]], (y[1:-1] >= y[:-2]) & (y[1:-1] >= y[2:]), [y[-1] >= y[-2]]])
        best = np.flatnonzero(is_max)[np.argsort(y[is_max])[::-1][:5]]
        fine = np.concatenate([np.linspace(tau[max(i - 1, 0)], tau[min(i + 1, len(tau) - 1)], 2001) for i in best])
        ref = max(y.max(), np.linalg.norm(p(fine, k), axis=1).max())
        assert p.peaks[k - 1] == pytest.approx(ref, rel=1e-8), (k, p.peaks[k - 1], ref)


@pytest.mark.parametrize("method", METHODS, ids=lambda m: m.value)
@settings(max_examples=10, deadline=None)
@given(task=moves(), scale=st.floats(0.2, 5.0))
def test_scaling(method, task, scale):
    """A move scaled by s about the pick point (b and h by s) has s× the normalised peaks (same shape)."""
    big = Task(task.p_from, task.p_from + scale * (task.p_to - task.p_from), scale * task.height, task.eta)
    np.testing.assert_allclose(plan_path(big, method).peaks, scale * np.array(plan_path(task, method).peaks), rtol=1e-8)
