"""methods/piecewise_poly.py: timing of the axis laws, P2 at τ_v, dwell, ratio, continuity."""

from __future__ import annotations

import numpy as np
import pytest

from pickplace_cli.model.errors import TaskError
from pickplace_cli.paths.piecewise_poly import lift_time, plan_piecewise_poly
from pickplace_cli.model.task import Task

TASK = Task([-0.1525, 0.0, -0.8], [0.1525, 0.0, -0.8], 0.025)


def test_timing_from_the_ratio():
    tv = lift_time(0.35)
    assert tv / (0.5 - tv) == pytest.approx(0.35, rel=1e-15)
    p = plan_piecewise_poly(TASK)
    np.testing.assert_allclose(p.breakpoints, [0, tv, 2 * tv, 1 - 2 * tv, 1 - tv, 1], atol=1e-15)


def test_passes_P2_when_u_starts_and_dwells_at_the_top():
    p = plan_piecewise_poly(TASK)
    tv = p.parameters["tau_v"]
    P = TASK.via_points()  # η = 0.5
    np.testing.assert_allclose(p(np.array([tv, 0.5, 1 - tv])), P[1:4], atol=1e-15)
    # u has not moved before τ_v, and v dwells at h over [2τ_v, 1 − 2τ_v]
    tau = np.linspace(0, tv, 50)
    np.testing.assert_allclose(p(tau)[:, 0], TASK.p_from[0], atol=0)
    tau = np.linspace(2 * tv, 1 - 2 * tv, 50)
    np.testing.assert_allclose(p(tau)[:, 2], TASK.z_top, atol=1e-15)


def test_jerk_continuous_everywhere():
    p = plan_piecewise_poly(TASK)
    assert p.parameters["continuity"] == 3
    bp = p.breakpoints
    for k in (1, 2, 3):
        d = np.linalg.norm(p(np.clip(bp + 1e-9, 0, 1), k) - p(np.clip(bp - 1e-9, 0, 1), k), axis=1)
        assert np.all(d < 1e-6 * p.peaks[k - 1])
    np.testing.assert_allclose(p(np.array([0.0, 1.0]), 3), 0.0, atol=1e-9)


@pytest.mark.parametrize("ratio", [0.0, -0.1, 1.2, float("nan")])
def test_ratio_validated(ratio):
    with pytest.raises(TaskError, match="ratio = "):
        plan_piecewise_poly(TASK, ratio)


def test_ratio_changes_peaks():
    a = plan_piecewise_poly(TASK, 0.2).peaks
    b = plan_piecewise_poly(TASK, 1.0).peaks
    assert a != b
    p = plan_piecewise_poly(TASK, 1.0)  # rise ends exactly where the fall starts
    np.testing.assert_allclose(p(np.array([0.5]))[0], TASK.via_points()[2], atol=1e-15)
