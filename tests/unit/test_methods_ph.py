"""methods/ph.py: parameters, defaults, errors, unequal heights, jerk jumps, paper duration."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pickplace_cli.model.errors import TaskError
from pickplace_cli.paths import Method, plan_path
from pickplace_cli.paths.ph import PHCorner, cycle_time_eq22, paper_duration, path_length, ph_path, plan_ph
from pickplace_cli.model.profile import Capacity
from pickplace_cli.model.task import Task
from tests.conftest import ADEPT_FROM, ADEPT_TO

ADEPT = Task(ADEPT_FROM, ADEPT_TO, 0.025)


def test_defaults_are_section_IID():
    p = plan_ph(ADEPT)
    assert p.method == "ph" and p.parameters["m"] == pytest.approx(0.025, rel=1e-12)
    assert p.parameters["r"] == pytest.approx(0.1525, rel=1e-15)
    # no straight segments: joints only at A, D, G
    np.testing.assert_allclose(p.breakpoints, [0.0, 0.5, 1.0], atol=1e-15)
    assert p.parameters["length_m"] == pytest.approx(path_length(0.025, 0.305, 0.025, 0.1525), rel=1e-14)
    assert plan_path(ADEPT, Method.ph).parameters == p.parameters  # registry


def test_paper_duration_is_eq22():
    cap = Capacity(velocity=5.0, acceleration=100.0)
    assert paper_duration(ADEPT, cap) == pytest.approx(cycle_time_eq22(0.025, 0.305, 100.0), rel=1e-13)
    assert paper_duration(ADEPT, cap, m=0.01, r=0.05) == pytest.approx(cycle_time_eq22(0.025, 0.305, 100.0, 0.01, 0.05), rel=1e-13)
    # the tangential peak recorded in the parameters gives the same time
    p = plan_ph(ADEPT)
    assert math.sqrt(p.parameters["a_max_tangential"] / 100.0) == pytest.approx(paper_duration(ADEPT, cap), rel=1e-14)


@pytest.mark.parametrize(
    "kw,msg",
    [({"m": 0.03}, "m = 0.03"), ({"m": 0.0}, "m = 0.0"), ({"r": 0.2}, "r = 0.2"), ({"r": -1.0}, "r = -1.0"), ({"m": float("nan")}, "m = nan")],
)
def test_invalid_parameters(kw, msg):
    with pytest.raises(TaskError, match=msg):
        plan_ph(ADEPT, **kw)


def test_vertical_move_is_refused():
    with pytest.raises(TaskError, match="b = 0"):
        plan_ph(Task([0, 0, -0.8], [0, 0, -0.7], 0.02))


def test_unequal_heights_each_corner_spans_its_rise():
    t = Task([-0.1, 0.05, -0.8], [0.15, -0.1, -0.75], 0.03)  # top at -0.72: rises 0.08 and 0.03
    arc, pts = ph_path(t)
    c1, c2 = pts["corners"]
    assert (c1.m, c2.m) == pytest.approx((0.08, 0.03), rel=1e-12)
    p = plan_ph(t)
    np.testing.assert_allclose(p(np.array([0.0, 1.0])), [t.p_from, t.p_to], atol=1e-14)
    assert p(np.array([0.5]))[0, 2] <= t.z_top + 1e-12
    assert p.parameters["m_place"] == pytest.approx(0.03)
    # a given m applies to both corners and must fit under the lower rise (= the clearance)
    with pytest.raises(TaskError, match="m = 0.05"):
        plan_ph(t, m=0.05)
    _, pts = ph_path(t, m=0.02)
    assert pts["corners"][0].m == pts["corners"][1].m == 0.02


def test_jerk_jumps_where_declared_and_only_there():
    """The 3-4-5 jerk steps at the ends; dκ/ds jumps at every join (D by symmetry; B, C, E, F where a
    straight piece meets a corner whose dκ/ds ≠ 0). Acceleration is continuous everywhere."""
    p = plan_ph(ADEPT, m=0.015, r=0.1)
    tj = np.array(p.parameters["jerk_jumps_at"])
    assert len(tj) == 6 and tj[0] == 0.0 and tj[-1] == 1.0  # A, B, C, E, F, G (D lies inside the segment CE)
    inner = tj[1:-1]
    eps = 1e-9
    for k, should_jump in ((1, False), (2, False), (3, True)):
        d = np.linalg.norm(p(inner + eps, k) - p(inner - eps, k), axis=1) / p.peaks[k - 1]
        # a continuous derivative moves by ≤ |next derivative|·2ε ~ 1e-6 of its peak; a jump is ≥ 1e-3
        assert np.all(d > 1e-3) if should_jump else np.all(d < 1e-5), (k, d)
    # the 3-4-5 start: jerk = s‴(0)·l_all = 60·l_all straight up (the curve starts vertically), exact
    np.testing.assert_allclose(p(np.array([0.0]), 3)[0], [0, 0, 60 * p.parameters["length_m"]], rtol=1e-12, atol=1e-12)


def test_corner_piece_geometry():
    c = PHCorner(0.02, 0.1)
    P, P1, _, _ = c.curve(np.array([0.0, 1.0]))
    np.testing.assert_allclose(P, [[0, 0], [0.1, 0.02]], atol=1e-15)
    assert P1[0, 0] == 0 and P1[0, 1] > 0 and abs(P1[1, 1]) < 1e-15 and P1[1, 0] > 0  # vertical in, horizontal out
    s = np.linspace(0, c.length, 11)
    np.testing.assert_allclose(c.arclength(c.param(s)), s, atol=1e-16)
