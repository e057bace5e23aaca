"""Detections (CSV file or stream), the seeded generator, and the hold-and-reorder window (line/parts.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pickplace_cli.line.parts import BadRow, Detection, generate, in_time_order, read_detections
from pickplace_cli.line.spec import Generator
from pickplace_cli.model.errors import TaskError


def test_reads_columns_in_any_order_with_or_without_units():
    rows = list(read_detections(["# a comment", "across[m],t,along[m],id,angle[rad]", "", "0.1,0.5,0,a7,0.25",
                                 "-0.05,0.7,0.01,,"], "d.csv"))
    assert rows == [Detection("a7", 0.5, 0.0, 0.1, 0.25, 1), Detection("2", 0.7, 0.01, -0.05, None, 2)]


@pytest.mark.parametrize("header, rule", [
    ("t[s],along[m]", "missing column 'across'"),
    ("t[ms],along[m],across[m]", "t is in s, not 'ms'"),
    ("t,along,across,speed", "column 'speed': not a detection column"),
    ("t,t,along,across", "column 't' appears twice"),
])
def test_bad_header_is_one_line(header, rule):
    with pytest.raises(TaskError) as exc:
        list(read_detections([header, "0,0,0"], "d.csv"))
    assert rule in str(exc.value) and "\n" not in str(exc.value) and str(exc.value).startswith("d.csv:1:")


def test_a_bad_row_is_answered_and_reading_goes_on():
    rows = list(read_detections(["t,along,across", "0.1,0,0", "0.2,x,0", "nan,0,0", "0.3,0,0,9", "0.4,0,0"], "d.csv"))
    assert [type(r).__name__ for r in rows] == ["Detection", "BadRow", "BadRow", "BadRow", "Detection"]
    assert rows[1].error == "row 2 (d.csv:3): along = 'x': must be a number in m"
    assert "must be a finite number" in rows[2].error
    assert "4 cells for 3 columns" in rows[3].error


def test_in_time_order_without_a_window_refuses_a_late_row_and_goes_on():
    d = [Detection(str(k), t, 0.0, 0.0, None, k) for k, t in enumerate([0.1, 0.3, 0.2, 0.4], 1)]
    out = list(in_time_order(d, 0.0))
    assert [x.id if isinstance(x, Detection) else None for x in out] == ["1", "2", None, "4"]
    assert isinstance(out[2], BadRow) and out[2].row == 3
    assert "row 3 (part 3): t = 0.2 s is 0.1 s earlier than row 2's t = 0.3 s" in out[2].error
    assert "set parts.reorder" in out[2].error


def test_in_time_order_reorders_within_the_window():
    """Hand-worked, window 0.15 s: a detection is passed on once one 0.15 s later has been read."""
    d = [Detection(str(k), t, 0.0, 0.0, None, k) for k, t in enumerate([0.1, 0.3, 0.2, 0.5, 0.25, 0.9], 1)]
    out = list(in_time_order(d, 0.15))
    # 0.1 released when 0.3 arrives (0.1 <= 0.3 - 0.15); 0.2 held; 0.5 releases 0.2 and 0.3 (<= 0.35);
    # 0.25 then comes after 0.3 was released: refused; 0.9 releases 0.5; the end releases 0.9
    assert [x.id if isinstance(x, Detection) else "bad" for x in out] == ["1", "3", "2", "bad", "4", "6"]
    assert [x.t for x in out if isinstance(x, Detection)] == sorted(x.t for x in out if isinstance(x, Detection))


def test_generator_is_seeded_and_has_its_rate_and_spread():
    g = Generator(rate=5.0, count=4000, spread=0.2, arrival="poisson", seed=3, angles=True)
    a, b = generate(g, 0.3), generate(g, 0.3)
    assert a == b  # same seed, same parts
    t = np.array([d.t for d in a])
    assert np.all(np.diff(t) >= 0)
    # mean gap 1/rate: the sample mean of 4000 exponential gaps is within 5 % (≈ 3 standard errors, 1/sqrt(4000))
    assert np.mean(np.diff(t)) == pytest.approx(0.2, rel=0.05)
    across = np.array([d.across for d in a])
    assert across.min() >= -0.1 and across.max() <= 0.1
    assert all(-math.pi <= d.angle < math.pi for d in a)
    c = generate(Generator(rate=5.0, count=4000, spread=0.2, arrival="poisson", seed=4), 0.3)
    assert [d.t for d in c] != list(t)
    reg = generate(Generator(rate=4.0, duration=1.0, arrival="regular"), 0.3)
    assert [d.t for d in reg] == [0.0, 0.25, 0.5, 0.75]


def test_a_part_off_the_belt_is_a_bad_row():
    """With the belt's width, a detection farther across than half of it is a bad row naming the value and the
    bound (the other rows are read on); at the edge it is a part."""
    rows = list(read_detections(["t,along,across", "0.1,0,0.15", "0.2,0,-0.15", "0.3,0,5", "0.4,0,-0.1500001"],
                                "d.csv", width=0.3))
    assert [type(r).__name__ for r in rows] == ["Detection", "Detection", "BadRow", "BadRow"]
    assert rows[2].error == "row 3 (d.csv:4): across = 5 m: not on the belt, within ±0.15 m (belt.width / 2)"
    assert "across = -0.15" in rows[3].error
    # without a width (a reader that knows no belt) nothing is tested
    assert all(type(r).__name__ == "Detection" for r in read_detections(["t,along,across", "0.3,0,5"], "d.csv"))
