"""task.py: the local frame (Li 2018 Eq. 1-2), via points (Eq. 11), validation."""

from __future__ import annotations

import numpy as np
import pytest

from pickplace_cli.model.errors import TaskError
from pickplace_cli.model.task import Task


def test_local_frame_eq1_eq2():
    t = Task([0.1, 0.2, -0.8], [0.1 + 0.3, 0.2 + 0.4, -0.8], 0.025, 0.5)
    assert t.b == pytest.approx(0.5, abs=1e-15)
    assert t.gamma == pytest.approx(np.arctan2(0.4, 0.3), abs=1e-15)
    assert t.lam == pytest.approx(20.0, abs=1e-12)
    via = t.via_points()
    np.testing.assert_allclose(via[2], [0.25, 0.4, -0.775], atol=1e-15)
    np.testing.assert_allclose(via[1], [0.1, 0.2, -0.8 + 0.0125], atol=1e-15)


def test_unequal_heights_measure_clearance_from_higher_end():
    t = Task([0, 0, -0.8], [0.3, 0, -0.7], 0.05, 0.5)
    via = t.via_points()
    assert via[2, 2] == pytest.approx(-0.65)
    assert via[1, 2] == pytest.approx(-0.8 + 0.5 * 0.15)
    assert via[3, 2] == pytest.approx(-0.7 + 0.5 * 0.05)


@pytest.mark.parametrize(
    "kw,match",
    [
        ({"p_from": [0, 0, 0], "p_to": [0, 0, 0]}, "must differ"),
        ({"height": 0.0}, "height"),
        ({"height": float("nan")}, "height"),
        ({"eta": 0.0}, "eta"),
        ({"eta": 1.0}, "eta"),
        ({"p_from": [0, float("nan"), 0]}, "finite"),
        ({"p_from": [0, 0]}, "three coordinates"),
        # scales no workcell has (they overflowed or divided by zero further on; review, session 16)
        ({"p_from": [0.0, 0.0, 1000.5]}, r"from = 0,0,1000.5: every coordinate must lie within ±1000 m"),
        ({"p_to": np.array([-1e200, 0, 0])}, r"to = -1e\+200,0,0: every coordinate must lie within ±1000 m"),
        ({"v_to": [0.0, 2e3, 0.0]}, r"v_to = 0,2000,0: every coordinate must lie within ±1000 m/s"),
        ({"height": 1e3 + 1}, r"height = 1001.0 m: must be at most 1000 m"),
        ({"height": 1e-300}, r"height = 1e-300 m: must be at least 1e-06 m"),
    ],
)
def test_invalid_tasks(kw, match):
    args = {"p_from": [0, 0, -0.8], "p_to": [0.3, 0, -0.8], "height": 0.025, "eta": 0.5}
    args.update(kw)
    with pytest.raises(TaskError, match=match):
        Task(**args)


def test_vertical_move_has_a_frame():
    t = Task([0, 0, -0.8], [0, 0, -0.7], 0.05)
    assert t.b == 0 and t.lam == 0 and t.gamma == 0


@pytest.mark.parametrize("p_from", [[0.1, -0.2, -0.8], (0.1, -0.2, -0.8), np.array([0.1, -0.2, -0.8]), [0, 0, -1]])
def test_the_float_fast_path_builds_the_same_task_as_numpy(p_from):
    """A streamed row gives three Python floats (the fast path without numpy calls); arrays, tuples and ints take
    the general path: the same arrays, the same frame, bitwise."""
    fast = Task([float(c) for c in p_from], [0.3, 0.1, -0.75], 0.03, 0.4, v_from=[0.0, 0.0, 0.0], v_to=[0.5, 0.0, 0.0])
    slow = Task(np.asarray(p_from, float), np.array([0.3, 0.1, -0.75]), 0.03, 0.4,
                v_from=np.zeros(3), v_to=np.array([0.5, 0.0, 0.0]))
    for name in ("p_from", "p_to", "v_from", "v_to"):
        a, b = getattr(fast, name), getattr(slow, name)
        assert a.dtype == b.dtype == np.float64 and a.shape == b.shape == (3,)
        assert a.tobytes() == b.tobytes()
    assert fast.via_points().tobytes() == slow.via_points().tobytes()
    assert (fast.b, fast.gamma, fast.lam) == (slow.b, slow.gamma, slow.lam)


@pytest.mark.parametrize("bad", [[0.0, float("nan"), -0.8], [float("inf"), 0.0, -0.8], [0.0, -float("inf"), 0.0]])
def test_non_finite_floats_leave_the_fast_path_with_the_same_error(bad):
    with pytest.raises(TaskError, match=r"^from = .*every coordinate must be a finite number \(m\)$"):
        Task(bad, [0.3, 0.0, -0.8], 0.03)


def test_ends_closer_than_a_nanometre_are_refused_by_either_path():
    with pytest.raises(TaskError, match="must differ"):
        Task([0.1, 0.2, -0.8], [0.1, 0.2 + 5e-10, -0.8], 0.03)
    Task([0.1, 0.2, -0.8], [0.1, 0.2 + 2e-9, -0.8], 0.03)  # 2 nm apart: a move


def test_the_scale_bounds_are_inclusive():
    Task([-1000.0, 0.0, 1000.0], [1000.0, 0.0, -1000.0], 1000.0, v_from=[1000.0, -1000.0, 0.0])
    Task([0.0, 0.0, -0.8], [0.3, 0.0, -0.8], 1e-6)
