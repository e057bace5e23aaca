"""methods/lame.py: the curve is the Lamé curve, arc length, exponent, continuity, errors."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad

from pickplace_cli.model.errors import TaskError
from pickplace_cli.paths.lame import lame_path, plan_lame
from pickplace_cli.model.task import Task

TASK = Task([0.1, -0.2, -0.8], [0.4, 0.2, -0.8], 0.05)  # b = 0.5, λ = 10, γ ≠ 0


@pytest.mark.parametrize("m", [3.0, 4.0, 5.5])
def test_points_lie_on_the_lame_curve(m):
    p = plan_lame(TASK, m)
    tau = np.linspace(0, 1, 401)
    x = p(tau) - TASK.p_from
    u = x @ TASK.e_u
    v = x[:, 2]
    b, h = TASK.b, TASK.height
    # |2u/b − 1|^m + |v/h|^m = 1 to round-off (the graph parametrisation is exact, the arc-length inverse
    # only moves points along the curve)
    np.testing.assert_allclose(np.abs(2 * u / b - 1) ** m + np.abs(v / h) ** m, 1.0, atol=1e-12)
    # the move stays in the vertical plane through the two points
    np.testing.assert_allclose(x[:, 0] * TASK.e_u[1] - x[:, 1] * TASK.e_u[0], 0.0, atol=1e-15)


def test_arc_length_against_quadrature():
    arc = lame_path(TASK, 3.0)
    for placed in arc.pieces:
        g = placed.piece
        ref = quad(lambda x: g.speed(np.array([x]))[0], g.g0, g.g1, epsabs=1e-15, epsrel=1e-13)[0]
        assert g.length == pytest.approx(ref, rel=1e-12)  # 64 × 16-point Gauss–Legendre on an analytic integrand
        s = np.linspace(0, g.length, 7)
        np.testing.assert_allclose(g.arclength(g.param(s)), s, atol=1e-15)


def test_continuity_depends_on_the_exponent():
    """m = 3: v ≈ h(1 − |X|³/3) at the top, so dκ/ds flips sign there and the jerk jumps at τ = 1/2;
    m = 4: the top is analytic and the jerk is continuous."""
    p3, p4 = plan_lame(TASK, 3.0), plan_lame(TASK, 4.0)
    assert p3.parameters["continuity"] == 2 and p3.parameters["jerk_jumps_at"] == [pytest.approx(0.5, abs=1e-12)]
    assert p4.parameters["continuity"] == 3 and p4.parameters["jerk_jumps_at"] == []
    t = np.array([0.5 - 1e-9, 0.5 + 1e-9])
    j3 = p3(t, 3)
    j4 = p4(t, 3)
    assert np.linalg.norm(j3[1] - j3[0]) > 0.1 * p3.peaks[2]
    assert np.linalg.norm(j4[1] - j4[0]) < 1e-6 * p4.peaks[2]
    for p in (p3, p4):
        np.testing.assert_allclose(p(np.array([0.0, 1.0]), 3), 0.0, atol=1e-9 * p.peaks[2])  # 4-5-6-7: jerk 0


@pytest.mark.parametrize("m", [2.0, 2.999, float("inf"), float("nan")])
def test_exponent_must_be_at_least_3(m):
    with pytest.raises(TaskError, match="m = "):
        plan_lame(TASK, m)


def test_vertical_move_refused_and_unequal_heights():
    with pytest.raises(TaskError, match="b = 0"):
        plan_lame(Task([0, 0, -0.8], [0, 0, -0.7], 0.02))
    t = Task([0.0, 0.0, -0.8], [0.3, 0.0, -0.78], 0.02)
    p = plan_lame(t)
    np.testing.assert_allclose(p(np.array([0.0, 1.0])), [t.p_from, t.p_to], atol=1e-14)
    top = p(np.linspace(0, 1, 4001))[:, 2].max()
    assert top == pytest.approx(t.z_top, abs=1e-9)
