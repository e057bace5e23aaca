"""The whole belt cycle on a controller's cycle: ``plan --to-belt … --round-trip --cycle`` (pick from the moving belt,
track, place back at the start, dwell) and a belt schedule under ``--cycle``.

The 4-axis cell of the manual: profile delta-4axis, a 0.5 m/s belt along +y, a 1 ms cycle. Everything is judged from
the written file, independently of the planner: the time stamps as decimals; the tool's position from the written
joint angles through the test's own Delta forward kinematics (``tests/reference/delta_rigid.py``, trilateration), set
against the part's position on the belt at that time (detected position + belt velocity · (latency + t)); velocities
by finite differences of those positions; every limit by ``pickplace check`` on the written file.
"""

from __future__ import annotations

import csv
import io
import json
import math
from decimal import Decimal

import numpy as np
import pytest
from typer.testing import CliRunner

from pickplace_cli.cli import app
from tests.reference.delta_rigid import forward_kinematics, params

runner = CliRunner()
CYCLE = 0.001
START = (-0.1525, 0.0, -0.8)
PART = (0.1525, -0.2, -0.8)
BELT = (0.0, 0.5, 0.0)
LATENCY = 0.05
CELL = ("-p", "delta-4axis", "--from", "-0.1525,0,-0.8", "--to", "0.1525,-0.2,-0.8", "--to-belt", "0,0.5,0",
        "--latency", "0.05", "--cycle", "0.001")
#: geometry of delta-4axis (R, r, L, l as the profile gives them: the reference's defaults)
GEOMETRY = params(R=0.150, r=0.051, L=0.325, l=0.800)


def run(*args, input=None):
    return runner.invoke(app, list(args), input=input, catch_exceptions=False)


def _table(path) -> tuple[list[str], list[list[str]]]:
    rows = list(csv.reader(io.StringIO(path.read_text())))
    return rows[0], rows[1:]


def _column(head, rows, name) -> np.ndarray:
    i = next(k for k, h in enumerate(head) if h.split("[")[0] == name)
    return np.array([float(r[i]) for r in rows])


def _tool(head, rows) -> np.ndarray:
    """FK of the written q1, q2, q3 (the reference's trilateration, not the planner's)."""
    q = np.stack([_column(head, rows, f"q{i}") for i in (1, 2, 3)], axis=1)
    return forward_kinematics(GEOMETRY, q)


def _part_at(t, latency=LATENCY, position=PART, belt=BELT) -> np.ndarray:
    return np.asarray(position) + np.multiply.outer(np.asarray(t) + latency, np.asarray(belt))


@pytest.fixture(scope="module")
def belt_cycle(tmp_path_factory):
    """The cycle written once as CSV (every column) with its --json summary."""
    out = tmp_path_factory.mktemp("belt") / "cycle.csv"
    res = run("plan", *CELL, "--round-trip", "-o", str(out), "--json")
    assert res.exit_code == 0, res.stderr
    return out, json.loads(res.stdout)


def test_every_step_is_one_cycle_and_every_segment_whole_cycles(belt_cycle):
    out, doc = belt_cycle
    head, rows = _table(out)
    t = [Decimal(r[1]) for r in rows]
    # every written stamp is k·1 ms exactly (decimal), one sample per cycle from 0 to the cycle's end
    assert all(s == k * Decimal("0.001") for k, s in enumerate(t))
    c = doc["belt_cycle"]
    for name in ("t_meet_s", "t_place_s", "t_end_s", "pick_duration_s", "place_duration_s", "dwell_s"):
        k = c[name] / CYCLE
        assert abs(c[name] - round(k) * CYCLE) <= 1e-12, (name, c[name])
    # pick, track (the dwell, gripping), place back at the start, dwell at rest: 0 … t_end
    assert c["t_end_s"] == pytest.approx(c["pick_duration_s"] + 2 * c["dwell_s"] + c["place_duration_s"], abs=1e-12)
    assert float(t[-1]) == pytest.approx(c["t_end_s"], abs=1e-12)
    assert doc["exit_code"] == 0 and doc["limits_ok"] is True and c["limits_ok"] is True
    move = _column(head, rows, "move")
    tn = np.array([float(x) for x in t])
    assert set(move[tn <= c["t_meet_s"] + c["dwell_s"] + 1e-9]) == {1}  # pick and tracking
    assert set(move[tn > c["t_meet_s"] + c["dwell_s"] + 1e-9]) == {2}  # place and its dwell


def test_the_rounded_cycle_meets_the_part_and_tracks_it(belt_cycle):
    """After rounding, the tool is on the part within 1e-6 m and moves with the belt within 1e-6 m/s: over the whole
    tracking segment (positions from FK of the written joints; velocity by forward differences, exact for the
    straight line at the belt's speed up to the file's 12 digits / 1 ms ≈ 1e-9 m/s), and arriving (a quintic through
    the last six pick samples, exact inside the path's last polynomial piece, differentiated at the meeting)."""
    out, doc = belt_cycle
    head, rows = _table(out)
    t = _column(head, rows, "t")
    p = _tool(head, rows)
    c = doc["belt_cycle"]
    T, D = c["t_meet_s"], c["dwell_s"]
    track = (t >= T - 1e-9) & (t <= T + D + 1e-9)
    assert track.sum() == round(D / CYCLE) + 1
    assert np.abs(p[track] - _part_at(t[track])).max() <= 1e-6
    v = np.diff(p[track], axis=0) / CYCLE
    assert np.abs(v - np.asarray(BELT)).max() <= 1e-6
    k = int(np.flatnonzero(track)[0])
    tt = t[k - 5: k + 1] - T
    arrive = [np.polyval(np.polyder(np.polyfit(tt, p[k - 5: k + 1, i], 5)), 0.0) for i in range(3)]
    assert np.abs(np.array(arrive) - np.asarray(BELT)).max() <= 1e-6
    # the JSON's meeting point is where the part is at the (rounded) meeting time
    assert np.abs(np.array(c["meeting_point_m"]) - _part_at(T)).max() <= 1e-9
    # the place leg leaves with the belt velocity and the cycle ends at rest at the start
    assert np.abs(p[-1] - np.asarray(START)).max() <= 1e-6
    assert np.abs(np.diff(p[-3:], axis=0)).max() <= 1e-12


def test_check_accepts_what_plan_wrote(belt_cycle):
    out, _ = belt_cycle
    res = run("check", str(out), "-p", "delta-4axis", "-q")
    assert res.exit_code == 0, res.stderr


def test_drive_units_plc_columns_and_check(belt_cycle, tmp_path):
    """--columns plc: t and the drive's counts d = k·q with k = gear · counts/rev / 2π (by hand from the profile:
    25 and 10 gear, 2^20 counts), the same samples as the full file; check reads the drive's file and accepts it."""
    full, _ = belt_cycle
    fh, frows = _table(full)
    out = tmp_path / "plc.csv"
    res = run("plan", *CELL, "--round-trip", "--columns", "plc", "-o", str(out), "-q")
    assert res.exit_code == 0, res.stderr
    head, rows = _table(out)
    assert [h.split("[")[0] for h in head] == ["move", "t", "A1", "A2", "A3", "A4"]
    assert np.array_equal(_column(head, rows, "t"), _column(fh, frows, "t"))
    for i, gear in ((1, 25.0), (2, 25.0), (3, 25.0), (4, 10.0)):
        k = gear * 2**20 / (2 * math.pi)
        # counts are written to the file's precision: within 1e-3 count of k·q (q has 12 significant digits)
        assert np.abs(_column(head, rows, f"A{i}") - k * _column(fh, frows, f"q{i}")).max() <= 1e-3 * max(1, k * 1e-6)
    res = run("check", str(out), "-p", "delta-4axis", "-q")
    assert res.exit_code == 0, res.stderr


def test_mcap_stamps_are_whole_cycles(tmp_path):
    from mcap.reader import make_reader

    out = tmp_path / "cycle.mcap"
    res = run("plan", *CELL, "--round-trip", "-o", str(out), "-q")
    assert res.exit_code == 0, res.stderr
    with open(out, "rb") as fh:
        stamps = sorted({m.log_time for _, ch, m in make_reader(fh).iter_messages() if ch.topic == "/joint_states"})
    # nanoseconds from the file's fixed epoch: every stamp k·1,000,000 ns after the first, one per cycle without a
    # gap, as many as the CSV's samples (pick 0 … t_end)
    rel = [s - stamps[0] for s in stamps]
    assert all(s % 1_000_000 == 0 for s in rel) and np.all(np.diff(stamps) == 1_000_000)
    res = run("plan", *CELL, "--round-trip", "--json", "-q")
    assert len(stamps) == round(json.loads(res.stdout)["belt_cycle"]["t_end_s"] / CYCLE) + 1


def test_belt_travel_per_sample_for_a_cam_with_the_belt_as_master():
    """The library's belt cycle carries the belt's travel since the detection per sample (a cam's master)."""
    from pickplace_cli.model.profile import load_profile
    from pickplace_cli.pipelines.rendezvous import Part
    from pickplace_cli.pipelines.schedule import plan_belt_cycle

    part = Part(np.array(PART), np.array(BELT), LATENCY)
    cyc = plan_belt_cycle(np.array(START), part, np.array(START), load_profile("delta-4axis"), cycle=CYCLE)
    tl = cyc.timeline(numbered=True)
    assert np.allclose(tl.belt_m, 0.5 * (tl.t + LATENCY), rtol=0, atol=1e-12)
    assert np.all(np.abs(tl.t / CYCLE - np.rint(tl.t / CYCLE)) <= 1e-9) and tl.cycle == CYCLE


def test_schedule_on_the_cycle(tmp_path):
    """Three parts, detections off the 1 ms grid, the second met as soon as the robot is free, the third after a wait:
    every row starts on the grid (not before its detection + latency), the file is one sample per cycle from the first
    start to the last end (no stamp twice, the waits at rest), each part met within 1e-6 m with the belt velocity
    within 1e-6 m/s, check accepts it."""
    parts = tmp_path / "parts.csv"
    parts.write_text("t_detect,to_x,to_y,to_z,to_belt_vx,to_belt_vy,to_belt_vz,place_x,place_y,place_z,"
                     "from_x,from_y,from_z\n"
                     "0.0003,0.15,-0.30,-0.8,0,0.5,0,-0.1525,0,-0.8,-0.1525,0,-0.8\n"
                     "0.1234,0.10,-0.30,-0.8,0,0.5,0,-0.1525,0,-0.8,,,\n"
                     "1.50017,0.12,-0.30,-0.8,0,0.5,0,-0.1525,0,-0.8,,,\n")
    out = tmp_path / "schedule.csv"
    res = run("plan", "-p", "delta-4axis", "--batch", str(parts), "--latency", "0.0505", "--cycle", "0.001",
              "-o", str(out), "--json")
    assert res.exit_code == 0, res.stderr
    docs = [json.loads(x) for x in res.stdout.splitlines()]
    head, rows = _table(out)
    move = _column(head, rows, "move")
    t = [Decimal(r[1]) for r in rows]
    first = Decimal(str(docs[0]["t_start_s"])).quantize(Decimal("0.001"))
    assert all(s == first + k * Decimal("0.001") for k, s in enumerate(t))  # every step one cycle, no gap
    assert float(t[-1]) == pytest.approx(docs[2]["t_end_s"], abs=1e-12)
    tn = _column(head, rows, "t")
    p = _tool(head, rows)
    detected = {1: (0.0003, (0.15, -0.30, -0.8)), 2: (0.1234, (0.10, -0.30, -0.8)), 3: (1.50017, (0.12, -0.30, -0.8))}
    assert docs[1]["t_start_s"] == pytest.approx(docs[0]["t_end_s"], abs=1e-12)  # free at once: no wait
    assert docs[2]["t_start_s"] == pytest.approx(1.551, abs=1e-12)  # ⌈1.50017 + 0.0505⌉ on the 1 ms grid
    wait = (tn > docs[1]["t_end_s"] + 1e-9) & (tn < docs[2]["t_start_s"] - 1e-9)
    assert wait.sum() == round((docs[2]["t_start_s"] - docs[1]["t_end_s"]) / CYCLE) - 1
    assert set(move[wait]) == {2} and np.abs(p[wait] - np.array(START)).max() <= 1e-6  # at rest at the place point
    for doc in docs[:3]:
        row = doc["row"]
        t_detect, where = detected[row]
        assert doc["t_start_s"] >= t_detect + 0.0505 - 1e-12
        for name in ("t_start_s", "t_meet_s", "t_place_s", "t_end_s"):
            assert abs(doc[name] - round(doc[name] / CYCLE) * CYCLE) <= 1e-12, (row, name)
        mine = move == row
        track = mine & (tn >= doc["t_meet_s"] - 1e-9) & (tn <= doc["t_meet_s"] + doc["dwell_s"] + 1e-9)
        on_belt = _part_at(tn[track] - t_detect, 0.0, where)
        assert np.abs(p[track] - on_belt).max() <= 1e-6
        assert np.abs(np.diff(p[track], axis=0) / CYCLE - np.asarray(BELT)).max() <= 1e-6
    assert docs[3]["schedule"]["picks"] == 3
    res = run("check", str(out), "-p", "delta-4axis", "-q")
    assert res.exit_code == 0, res.stderr


@pytest.mark.parametrize("args, code, words", [
    (("--round-trip", "--v-from", "0.1,0,0"), 2, "--round-trip"),
    (("--round-trip", "--cycle", "0"), 1, "--cycle "),
    (("--round-trip", "--cycle", "0.001", "--rate", "500"), 2, "--rate"),
])
def test_bad_inputs_one_line_exit_code_nothing_written(args, code, words, tmp_path):
    out = tmp_path / "t.csv"
    out.write_text("old\n")
    res = run("plan", *CELL[:-2], *args, "-o", str(out), "-q")
    assert res.exit_code == code, res.stderr
    assert res.stderr.count("\n") == 1 and words in res.stderr and "Traceback" not in res.stderr
    assert out.read_text() == "old\n"


def test_the_profiles_controller_cycle_is_the_same_as_the_option(belt_cycle, tmp_path):
    """A profile with controller.cycle 0.001 s plans the belt cycle as --cycle 0.001 does; --cycle off leaves it."""
    from pathlib import Path

    import pickplace_cli

    text = (Path(pickplace_cli.__file__).parent.parent / "profiles" / "delta-4axis.yaml").read_text()
    if "controller:" not in text:  # pragma: no cover - the shipped profile names its drives
        pytest.skip("delta-4axis has no controller section")
    prof = tmp_path / "cell.yaml"
    prof.write_text(text.replace("controller:", "controller:\n  cycle: 0.001", 1))
    out = tmp_path / "cycle.csv"
    args = [a for a in CELL if a not in ("--cycle", "0.001")]
    args[args.index("delta-4axis")] = str(prof)
    res = run("plan", *args, "--round-trip", "-o", str(out), "-q")
    assert res.exit_code == 0, res.stderr
    assert out.read_text() == belt_cycle[0].read_text()
    res = run("plan", *args, "--round-trip", "--cycle", "off", "--json", "-q")
    doc = json.loads(res.stdout)
    assert res.exit_code == 0 and "cycle" not in doc["moves"][0]
    assert abs(doc["belt_cycle"]["t_meet_s"] / CYCLE - round(doc["belt_cycle"]["t_meet_s"] / CYCLE)) > 1e-6


def test_a_rounded_pick_that_breaks_a_limit_gets_whole_cycles_more():
    """The loop of the rendezvous on a cycle, with the meeting and the plan given as functions: a rule duration of
    0.1834 s (184 cycles) whose rounded moves break a limit below 0.1865 s gets 3 cycles more (0.187 s), the meeting
    solved again for each; one that did not hold at its own duration is not lengthened; none past the window."""
    from dataclasses import dataclass

    from pickplace_cli.pipelines.rendezvous import _on_cycle

    @dataclass(frozen=True)
    class Report:
        ok: bool
        violations: tuple = ()
        notes: tuple = ()

    @dataclass(frozen=True)
    class Got:
        report: Report
        cycle: object = None

    @dataclass(frozen=True)
    class Duration:
        seconds: float

    @dataclass(frozen=True)
    class Found:
        duration: Duration
        window_s: tuple = (0.01, 1.3)

        @property
        def seconds(self) -> float:
            return self.duration.seconds

    solved = []

    def solve(T, dwell):
        solved.append((round(T / CYCLE), round(dwell / CYCLE)))
        return Found(Duration(T))  # (the fields the loop replaces: duration, window_s)

    def make_planned(threshold, held_at_rule=True):
        def planned(found, on_cycle=True):
            T = found.duration.seconds
            ok = T >= threshold if on_cycle else held_at_rule
            return Got(Report(ok))
        return planned

    rv = Found(Duration(0.1834))
    found, got, note = _on_cycle(rv, make_planned(0.1865), CYCLE, solve, 0.1003)
    assert found.duration.seconds == pytest.approx(0.187, abs=1e-15) and got.report.ok
    assert solved == [(184, 101), (185, 101), (186, 101), (187, 101)]  # solved again for each, dwell 101 cycles
    assert "3 more cycles" in note
    solved.clear()
    found, got, note = _on_cycle(rv, make_planned(0.1865, held_at_rule=False), CYCLE, solve, 0.1)
    assert found.duration.seconds == pytest.approx(0.184, abs=1e-15) and not got.report.ok and note == ""
    solved.clear()
    found, got, _ = _on_cycle(Found(Duration(0.1834), (0.01, 0.1851)), make_planned(0.1865), CYCLE, solve, 0.1)
    assert not got.report.ok and max(n for n, _ in solved) == 185  # 0.186 s would meet the part past the window

    # a plan that lengthened itself (its rounded dwell broke a limit) arrives at the old meeting point late: it is
    # never returned as holding, and when no whole-cycle pick is left the rendezvous fails (exit 3), one line
    @dataclass(frozen=True)
    class Rounding:
        extra_cycles: int

    @dataclass(frozen=True)
    class Labelled(Found):
        part: object = None

    class Named:
        def label(self):
            return "part (test)"

    def self_lengthened(found, on_cycle=True):
        return Got(Report(True), Rounding(1) if on_cycle else None)

    from pickplace_cli.model.errors import NoFeasibleDuration

    with pytest.raises(NoFeasibleDuration) as err:
        _on_cycle(Labelled(Duration(0.1834), (0.01, 1.3), Named()), self_lengthened, CYCLE, solve, 0.1003)
    assert err.value.exit_code == 3 and "part (test)" in str(err.value) and "\n" not in str(err.value)


def test_schedule_mcap_is_one_sample_per_cycle(tmp_path):
    from mcap.reader import make_reader

    parts = tmp_path / "parts.csv"
    parts.write_text("t_detect,to_x,to_y,to_z,to_belt_vx,to_belt_vy,to_belt_vz,place_x,place_y,place_z\n"
                     "0.0003,0.15,-0.30,-0.8,0,0.5,0,-0.1525,0,-0.8\n"
                     "0.9,0.10,-0.30,-0.8,0,0.5,0,-0.1525,0,-0.8\n")
    out = tmp_path / "schedule.mcap"
    res = run("plan", "-p", "delta-4axis", "--batch", str(parts), "--cycle", "0.001", "-o", str(out), "-q")
    assert res.exit_code == 0, res.stderr
    with open(out, "rb") as fh:
        stamps = [m.log_time for _, ch, m in make_reader(fh).iter_messages() if ch.topic == "/joint_states"]
    assert np.all(np.diff(stamps) == 1_000_000)  # ns: every step one cycle, the wait included, no stamp twice


def test_tool_angle_turned_to_the_part_held_while_tracking_and_back(tmp_path):
    """With tool angles (delta-4axis: tool angle = q4, sign 1) under --time fit: q4 = the part's 1 rad over the
    tracking (1e-9 rad: the written digits), 0 at both ends of the cycle; check accepts the file under the same rule."""
    out = tmp_path / "angles.csv"
    args = list(CELL)
    args[args.index("--from") + 1] += ",0"
    args[args.index("--to") + 1] += ",1.0"
    res = run("plan", *args, "--round-trip", "--time", "fit", "-o", str(out), "--json", "-q")
    assert res.exit_code == 0, res.stderr
    c = json.loads(res.stdout)["belt_cycle"]
    head, rows = _table(out)
    t, q4 = _column(head, rows, "t"), _column(head, rows, "q4")
    track = (t >= c["t_meet_s"] - 1e-9) & (t <= c["t_meet_s"] + c["dwell_s"] + 1e-9)
    assert np.abs(q4[track] - 1.0).max() <= 1e-9
    assert abs(q4[0]) <= 1e-12 and abs(q4[-1]) <= 1e-9
    assert all(abs(c[n] - round(c[n] / CYCLE) * CYCLE) <= 1e-12 for n in ("t_meet_s", "t_place_s", "t_end_s"))
    res = run("check", str(out), "-p", "delta-4axis", "--no-hold-capacity", "-q")
    assert res.exit_code == 0, res.stderr


def test_pvt_table_of_the_belt_cycle(belt_cycle, tmp_path):
    """-f pvt: the table spans the whole cycle (pick, track, place, dwell: last point at t_end), every point on a
    whole cycle, the drive's counts at the ends those of the written samples; check judges it as the drive
    interpolates it and accepts it."""
    _, doc = belt_cycle
    out = tmp_path / "cycle.pvt.csv"
    res = run("plan", *CELL, "--round-trip", "-f", "pvt", "-o", str(out), "-q")
    assert res.exit_code == 0, res.stderr
    head, rows = _table(out)
    t = _column(head, rows, "t")
    assert t[0] == 0 and t[-1] == pytest.approx(doc["belt_cycle"]["t_end_s"], abs=1e-12)
    assert np.abs(t / CYCLE - np.rint(t / CYCLE)).max() <= 1e-9
    k = 25.0 * 2**20 / (2 * math.pi)
    fh, frows = _table(belt_cycle[0])
    q1 = _column(fh, frows, "q1")
    assert abs(_column(head, rows, "A1")[0] - k * q1[0]) <= 1e-3 and abs(_column(head, rows, "A1")[-1] - k * q1[-1]) <= 1e-3
    res = run("check", str(out), "-p", "delta-4axis", "-q")
    assert res.exit_code == 0, res.stderr


def test_streamed_schedule_on_the_cycle_writes_what_the_file_does(tmp_path):
    """--batch - (rows answered as they are read, a row's last sample held back until the next) writes the same
    file as the schedule read whole."""
    text = ("t_detect,to_x,to_y,to_z,to_belt_vx,to_belt_vy,to_belt_vz,place_x,place_y,place_z\n"
            "0.0003,0.15,-0.30,-0.8,0,0.5,0,-0.1525,0,-0.8\n"
            "0.9,0.10,-0.30,-0.8,0,0.5,0,-0.1525,0,-0.8\n")
    parts = tmp_path / "parts.csv"
    parts.write_text(text)
    whole, streamed = tmp_path / "whole.csv", tmp_path / "streamed.csv"
    res = run("plan", "-p", "delta-4axis", "--batch", str(parts), "--cycle", "0.001", "-o", str(whole), "-q")
    assert res.exit_code == 0, res.stderr
    res = run("plan", "-p", "delta-4axis", "--batch", "-", "--cycle", "0.001", "-o", str(streamed), "-q", input=text)
    assert res.exit_code == 0, res.stderr
    assert streamed.read_text() == whole.read_text()
    t = [Decimal(r[1]) for r in _table(whole)[1]]
    assert all(b - a == Decimal("0.001") for a, b in zip(t, t[1:]))
