"""pickplace_cli/schedule.py (issue 17): a belt schedule carries the robot's state from cycle to cycle."""

from __future__ import annotations

import io

import numpy as np
import pytest

from pickplace_cli.pipelines.batch import read_batch
from pickplace_cli.model.errors import TaskError
from pickplace_cli.model.profile import load_profile
from pickplace_cli.pipelines.schedule import ScheduleSummary, check_order, plan_schedule

HEAD = "t_detect,to_x,to_y,to_z,to_belt_vx,to_belt_vy,to_belt_vz,place_x,place_y,place_z,from_x,from_y,from_z\n"
PLACE = "-0.1525,0,-0.8"


def rows_of(text: str):
    rows, bad = read_batch(io.StringIO(text), "s.csv")
    assert not bad, [b.error for b in bad]
    return rows


@pytest.fixture(scope="module")
def profile():
    return load_profile(None)


@pytest.fixture(scope="module")
def schedule(profile):
    # three parts detected 0.1 s apart: the robot is busy with each when the next is seen
    text = HEAD + (f"0.00,0.1525,-0.25,-0.8,0,0.3,0,{PLACE},-0.1525,0,-0.8\n"
                   f"0.10,0.10,-0.30,-0.8,0,0.3,0,{PLACE},,,\n"
                   f"0.20,0.20,-0.35,-0.8,0,0.3,0,{PLACE},,,\n")
    return list(plan_schedule(rows_of(text), profile, latency=0.05, source="s.csv"))


def test_state_carries_over(schedule):
    assert [r.code for r in schedule] == [0, 0, 0]
    cycles = [r.cycle for r in schedule]
    assert cycles[0].t_start == pytest.approx(0.05, abs=1e-12)  # detection + latency, the robot free
    for prev, nxt in zip(cycles, cycles[1:]):
        a, b = prev.timeline(), nxt.timeline()
        # the next move starts exactly when and where the previous cycle ended (round-off of the sums: 1e-9)
        assert abs(b.t[0] - a.t[-1]) < 1e-9 and abs(nxt.t_start - prev.t_end) < 1e-12
        assert np.abs(b.p[0] - a.p[-1]).max() < 1e-9
        assert np.abs(b.v[0]).max() < 1e-9 and np.abs(a.v[-1]).max() < 1e-9  # at rest between cycles
        # the effective latency is the time the robot was busy after the detection
        assert nxt.latency == pytest.approx(prev.t_end - nxt.t_detect, abs=1e-12)
        assert nxt.latency > 0.05


def test_cycle_meets_each_part(schedule):
    for r in schedule:
        c = r.cycle
        tl = c.timeline()
        k = int(np.argmin(np.abs(tl.t - c.t_meet)))
        assert abs(tl.t[k] - c.t_meet) < 1e-9
        part = c.rendezvous.part
        # the meeting point is where the part is at the meeting (detection + effective latency + T)
        assert np.abs(tl.p[k] - part.at(c.rendezvous.seconds)).max() < 1e-9
        assert np.abs(tl.v[k] - part.velocity).max() < 1e-6  # arrives with the belt velocity (the solve's 1e-6)
        assert c.t_end == pytest.approx(c.t_start + c.rendezvous.seconds + 2 * c.dwell + c.place.duration.seconds,
                                        abs=1e-12)


def test_summary(schedule):
    s = ScheduleSummary()
    for r in schedule:
        s.add(r)
    assert s.picks == 3 and not s.failed
    span = schedule[-1].cycle.t_end - schedule[0].cycle.t_start
    assert s.picks_per_minute == pytest.approx(180.0 / span, rel=1e-12)
    assert "3 parts, 3 picked, 0 missed" in s.line()


def test_missed_part_keeps_the_robot(profile):
    text = HEAD + (f"0.00,0.1525,-0.25,-0.8,0,0.3,0,{PLACE},-0.1525,0,-0.8\n"
                   f"0.10,0.10,-1.25,-0.8,0,2.5,0,{PLACE},,,\n"
                   f"0.20,0.20,-0.35,-0.8,0,0.3,0,{PLACE},,,\n")
    res = list(plan_schedule(rows_of(text), profile, source="s.csv"))
    assert [r.code for r in res] == [0, 4, 0]
    assert res[1].error.startswith("row 2 (s.csv:3): move from t = ")
    assert "part of row 2" in res[1].error and "leaves the workspace" in res[1].error
    # the missed part did not move the robot: row 3 starts when row 1 ended
    assert abs(res[2].cycle.t_start - res[0].cycle.t_end) < 1e-12
    assert res[1].t_start == res[0].cycle.t_end


def test_out_of_order_refused():
    text = HEAD + (f"0.20,0.1525,-0.25,-0.8,0,0.3,0,{PLACE},,,\n"
                   f"0.10,0.10,-0.30,-0.8,0,0.3,0,{PLACE},,,\n")
    with pytest.raises(TaskError, match=r"^row 2 \(s.csv:3\): t_detect = 0.1 s is earlier than row 1's 0.2 s"):
        list(check_order(rows_of(text), "s.csv"))


def test_from_only_on_row_one():
    text = HEAD + (f"0.0,0.1525,-0.25,-0.8,0,0.3,0,{PLACE},,,\n"
                   f"0.1,0.10,-0.30,-0.8,0,0.3,0,{PLACE},0,0,-0.8\n")
    with pytest.raises(TaskError, match=r"row 2 .*from_x = 0: only row 1 may say where the robot starts"):
        list(check_order(rows_of(text), "s.csv"))


@pytest.mark.parametrize("cell, message", [
    ("nan", "to_belt_vy = 'nan': must be finite"),
    ("inf", "to_belt_vy = 'inf': must be finite"),
])
def test_non_finite_belt_is_a_row_error(cell, message):
    rows, bad = read_batch(io.StringIO(HEAD + f"0.0,0.1525,-0.25,-0.8,0,{cell},0,{PLACE},,,\n"), "s.csv")
    assert not rows and len(bad) == 1 and bad[0].error == f"row 1 (s.csv:2): {message}"
    with pytest.raises(TaskError, match="must be finite"):
        list(check_order(bad, "s.csv"))


def test_negative_latency_refused():
    text = "latency," + HEAD + f"-0.1,0.0,0.1525,-0.25,-0.8,0,0.3,0,{PLACE},,,\n"
    _rows, bad = read_batch(io.StringIO(text), "s.csv")
    assert bad[0].error == "row 1 (s.csv:2): latency = '-0.1': must be >= 0 s (the earliest move start after the detection)"


def test_belt_columns_need_t_detect():
    """Schedule columns (place_*) need t_detect; belt velocity columns alone are a plain batch's belt rows, all
    three of them."""
    with pytest.raises(TaskError, match="column 'place_x' belongs to a belt schedule, which needs a t_detect column"):
        read_batch(io.StringIO("from_x,from_y,from_z,to_x,to_y,to_z,place_x\n0,0,-0.8,0.1,0,-0.8,0\n"), "s.csv")
    with pytest.raises(TaskError, match="column 'to_belt_vy' is missing \\(a belt row gives the belt velocity"):
        read_batch(io.StringIO("from_x,from_y,from_z,to_x,to_y,to_z,to_belt_vx\n0,0,-0.8,0.1,0,-0.8,0\n"), "s.csv")
    with pytest.raises(TaskError, match="column 'place_x' is missing \\(a belt schedule"):
        read_batch(io.StringIO("t_detect,to_x,to_y,to_z,to_belt_vx,to_belt_vy,to_belt_vz\n0,0,0,-0.8,0,0.3,0\n"), "s.csv")
