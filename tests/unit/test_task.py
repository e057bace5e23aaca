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
