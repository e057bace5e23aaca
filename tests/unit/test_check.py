"""check.py: reading trajectory files (one or several moves, errors naming line, column and value), positions
checked as given (no wrapping), the configuration test, and agreement with plan on this tool's own files."""

from __future__ import annotations

import io

import numpy as np
import pytest

from pickplace_cli.pipelines.check import check_file, check_trajectory, read_moves, read_trajectory
from pickplace_cli.model.errors import TaskError
from pickplace_cli.export.csv import write_csv
from pickplace_cli.planner import PlanOptions, plan
from pickplace_cli.model.profile import load_profile, parse_profile, resolve_profile_path
from pickplace_cli.model.task import Task
from pickplace_cli.pipelines.timeline import concatenate, round_trip

Q = ("q1", "q2", "q3")


@pytest.fixture(scope="module")
def delta():
    return load_profile("delta-su2018")


@pytest.fixture(scope="module")
def legs(delta):
    there = plan(Task(np.array([-0.1525, 0, -0.8]), np.array([0.1525, 0, -0.8]), 0.025, 0.5), delta)
    back = plan(Task(np.array([0.1525, 0, -0.8]), np.array([-0.1525, 0, -0.8]), 0.025, 0.5), delta)
    other = plan(Task(np.array([0.1, 0.1, -0.8]), np.array([-0.1, -0.1, -0.8]), 0.03, 0.5), delta)
    return there, back, other


def _csv(samples) -> str:
    buf = io.StringIO()
    write_csv(samples, buf)
    return buf.getvalue()


def test_batch_output_is_read_move_by_move(legs):
    there, _, other = legs
    text = _csv(concatenate([there, other], [1, 2], restart_time=True))
    moves = read_moves(text, "<b>", Q)
    assert [m.move for m in moves] == [1, 2] and [m.rest for m in moves] == [0, 0]
    assert len(moves[0].t) == len(there.t) and len(moves[1].t) == len(other.t)
    assert moves[0].lines[0] == 2 and moves[1].lines[0] == 2 + len(there.t) and moves[1].t[0] == 0.0
    # the file's numbers (12 significant digits) are the plan's
    np.testing.assert_allclose(moves[1].q, other.joint.q, rtol=1e-11, atol=1e-12)
    with pytest.raises(TaskError, match=r"<b>: 2 moves \(a 'move' column\)"):
        read_trajectory(text, "<b>", Q)


def test_round_trip_output_sets_the_dwell_aside(legs, delta):
    there, back, _ = legs
    dwell = delta.planning.dwell
    text = _csv(round_trip(there, back, dwell, delta.planning.rate))
    m1, m2 = read_moves(text, "<rt>", Q)
    # each move is the leg's own samples; the samples at rest after it (the dwell) are set aside, and they are
    # the whole dwell at the output rate (1 kHz: 0.1 s ≈ 100 samples; the first one is the leg's end sample)
    assert len(m1.t) == len(there.t) and len(m2.t) == len(back.t)
    assert m1.t[-1] == pytest.approx(there.t[-1], abs=1e-11) and m2.t[0] == pytest.approx(there.t[-1] + dwell, abs=1e-9)
    assert abs(m1.rest - dwell * delta.planning.rate) <= 1 and abs(m2.rest - dwell * delta.planning.rate) <= 1
    assert m1.last_line == m2.lines[0] - 1


def test_round_trip_checked_like_plan(tmp_path, legs, delta):
    there, back, _ = legs
    f = tmp_path / "rt.csv"
    f.write_text(_csv(round_trip(there, back, delta.planning.dwell, delta.planning.rate)))
    checks = check_file(f, delta)
    assert [c.move for c in checks] == [1, 2]
    # the second move starts after the first and its dwell: its peak times count from its own start, as it says
    start = there.t[-1] + delta.planning.dwell
    assert f"from t = {start:.6g} s of the file (peak times count from there)" in checks[1].report.notes[0]
    assert "of the file" not in checks[0].report.notes[0]
    for c, leg in zip(checks, (there, back)):
        # the move's duration is the leg's, not the leg + dwell (12-digit CSV time)
        assert c.report.duration == pytest.approx(leg.report.duration, abs=1e-9)
        # every row, the tool's Cartesian capacity included (check has its rows too, from the file's x, y, z)
        a = {(r.joint, r.quantity): r.peak for r in leg.report.rows}
        b = {(r.joint, r.quantity): r.peak for r in c.report.rows}
        assert a.keys() == b.keys()
        for key in a:
            # as the single-move CLI test: torques from a spline's second derivative agree to 1 % (2 % for the
            # torque rate, a third derivative) with the planner's analytic values; positions from 1 kHz samples
            tol = 2e-2 if "rate" in key[1] else 1e-2
            if key[1].startswith(("position", "workcell")):
                assert abs(b[key]) == pytest.approx(abs(a[key]), rel=tol, abs=1e-6), key
            else:
                assert b[key] == pytest.approx(a[key], rel=tol, abs=1e-9), key


def _scara_file(tmp_path, shift: float = 0.0) -> tuple:
    prof = load_profile("scara-600")
    p = plan(Task(np.array([0.3, 0.1, -0.1]), np.array([0.2, -0.3, -0.1]), 0.025, 0.5), prof, PlanOptions(time="fit"))
    text = _csv(p)
    if shift:
        lines = text.splitlines()
        col = lines[0].split(",").index("q1[rad]")
        out = [lines[0]]
        for ln in lines[1:]:
            cells = ln.split(",")
            cells[col] = repr(float(cells[col]) + shift)
            out.append(",".join(cells))
        text = "\n".join(out) + "\n"
    f = tmp_path / f"scara{shift:g}.csv"
    f.write_text(text)
    return prof, p, f


def test_positions_are_checked_as_given_not_wrapped(tmp_path):
    """q1 + 2π is the same pose: every row but q1's position range is unchanged, and that row reports the file's
    value (was the model's IK, wrapped into (−π, π]: 5 rad read as −1.283 rad)."""
    prof, p, plain = _scara_file(tmp_path)
    _, _, wrapped = _scara_file(tmp_path, 2 * np.pi)
    a, b = check_trajectory(plain, prof), check_trajectory(wrapped, prof)
    assert a.ok and not b.ok and b.exit_code() == 4
    q1_max = float(np.max(p.joint.q[:, 0])) + 2 * np.pi
    (bad,) = b.violations
    assert (bad.joint, bad.quantity, bad.bound) == ("q1", "position", "upper")
    assert bad.peak == pytest.approx(q1_max, abs=1e-11) and bad.peak > 2.8
    assert bad.t_peak == pytest.approx(p.t[np.argmax(p.joint.q[:, 0])], abs=1e-12)
    for ra, rb in zip(a.rows, b.rows):
        if (ra.joint, ra.quantity) != ("q1", "position"):
            # the same pose: FK(q1 + 2π) differs from FK(q1) only by rounding (~1e-15 m), but the spline's third
            # derivative divides by dt³ = 1e-9 s³ (torque rate: ~1e-8 relative seen); 1e-6 leaves room
            assert (ra.joint, ra.quantity) == (rb.joint, rb.quantity) and rb.peak == pytest.approx(ra.peak, rel=1e-6)
    assert "joint positions checked as given" in b.notes[0]


def test_another_configuration_is_refused(tmp_path):
    prof, _, f = _scara_file(tmp_path)
    left = parse_profile(resolve_profile_path("scara-600").read_text().replace("elbow: right", "elbow: left"))
    with pytest.raises(TaskError) as ei:
        check_trajectory(f, left)
    msg = str(ei.value)
    assert msg.startswith(f"{f}:2: q2 = -") and "another configuration than the profile's model" in msg
    assert "robot.elbow" in msg and "\n" not in msg


HEAD = "t[s],q1[rad],q2[rad],q3[rad]\n"
ROWS = "".join(f"{k * 0.01:g},0.1,0.2,0.3\n" for k in range(8))


@pytest.mark.parametrize(
    "text,match",
    [
        (HEAD + ROWS.replace("0.03,0.1,0.2,0.3", "0.03,0.1,abc,0.3"), r"^<f>:5: q2 = 'abc': not a number \(column 3, 'q2\[rad\]'\)$"),
        ("# comment\n\n" + HEAD + ROWS.replace("0.03,0.1,0.2,0.3", "0.03,0.1,0.2,"), r"^<f>:7: q3 = '': not a number \(column 4, 'q3\[rad\]'\)$"),
        (HEAD + ROWS.replace("0.03,0.1,0.2,0.3", "0.03,0.1,0.2"), r"^<f>:5: q3: no value \(the row has 3 cells, the header 4\)$"),
        (HEAD + ROWS.replace("0.03,0.1,0.2,0.3", "0.03,nan,0.2,0.3"), r"^<f>:5: q1 = nan: must be a finite number \(column 2, 'q1\[rad\]'\)$"),
        (HEAD + ROWS + ROWS, r"^<f>:10: t = 0 s is not after the previous row's t = 0.07 s: t must increase strictly .*several moves one after another: keep their 'move' column"),
        (HEAD + ROWS.replace("0.03,", "0.01,"), r"^<f>:5: t = 0.01 s is not after the previous row's t = 0.02 s: t must increase strictly from row to row$"),
        ("move," + HEAD.replace(",", ",", 1) + "".join(f"{m},{r}" for m in (1, 2, 1) for r in ROWS.splitlines(True)),
         r"^<f>:18: move = 1: its rows must be consecutive \(move 1 already ended at line 9\)$"),
        ("move," + HEAD + "".join(f"1.5,{r}" for r in ROWS.splitlines(True)), r"^<f>:2: move = 1.5: must be a whole number"),
        ("move," + HEAD + "".join(f"1,{r}" for r in ROWS.splitlines(True)[:5]), r"^<f>:2: 5 samples \(move 1\); a move needs at least 6"),
        ("t,q1,q2\n0,1,2\n", r"^<f>:1: header lacks column\(s\) q3"),
    ],
)
def test_file_errors_name_line_column_and_value(text, match):
    with pytest.raises(TaskError, match=match):
        read_moves(text, "<f>", Q)


def test_bom_and_semicolons():
    text = "\ufeff" + (HEAD + ROWS).replace(",", ";")
    (m,) = read_moves(text, "<f>", Q)
    assert m.move is None and len(m.t) == 8 and m.q[0].tolist() == [0.1, 0.2, 0.3]


def _trapezoid_rms(path) -> dict[str, float]:
    """RMS motor torque [N·m] per joint of a CSV ``plan`` wrote, by the trapezoidal rule over the samples of the whole
    file (a round trip: its moves and both dwells, at rest with the holding torque): an independent estimate."""
    with open(path) as fh:
        head = fh.readline().strip().split(",")
    d = np.loadtxt(path, delimiter=",", skiprows=1)
    t = d[:, head.index("t[s]")]
    out = {}
    for j in (1, 2, 3):
        tau = d[:, head.index(f"motor_torque{j}[N*m]")]
        out[f"q{j}"] = float(np.sqrt(np.sum(0.5 * (tau[1:] ** 2 + tau[:-1] ** 2) * np.diff(t)) / (t[-1] - t[0])))
    return out


@pytest.mark.parametrize("fmt", ["pvt", "cam", "cam-table"])
def test_a_round_trip_table_is_one_whole_duty_cycle(tmp_path, fmt):
    """A round trip written as one table (no move column) returns to its start: check takes the RMS torque over the
    table itself, as the drive repeats it, not over the table plus a dwell and a move back (which gave 2.02 N·m
    for 2.23 N·m, 9 % low, and a cycle of 1.13 s for 0.466 s). Against the trapezoidal RMS of plan's own 1 ms
    samples of the same round trip: 0.5 % (the table is within 1e-6 rad of it; the trapezoid's error at 1 ms and
    the check's stated accuracy are ~0.1 %)."""
    from typer.testing import CliRunner

    from pickplace_cli.cli import app

    samples, table = tmp_path / "rt.csv", tmp_path / f"rt-{fmt}.csv"
    common = ["plan", "--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8", "--round-trip", "--cycle", "0.001",
              "--time", "fit", "-q"]
    assert CliRunner().invoke(app, common + ["-o", str(samples)]).exit_code == 0
    assert CliRunner().invoke(app, common + ["-f", fmt, "-o", str(table)]).exit_code == 0
    want = _trapezoid_rms(samples)
    [checked] = check_file(table, load_profile("delta-su2018"))
    got = {r.joint: r.peak for r in checked.report.rows if r.quantity == "rms motor torque"}
    for joint, rms in want.items():
        assert got[joint] == pytest.approx(rms, rel=5e-3), joint
    assert checked.report.round_trip == pytest.approx(0.466, abs=1e-9)  # 466 cycles of 1 ms
    assert checked.report.picks_per_minute == pytest.approx(60 / 0.466, rel=1e-9)
    res = CliRunner().invoke(app, ["check", str(table), "--no-hold-capacity", "--report", str(tmp_path / "r.json")])
    assert res.exit_code == 0
    assert "cycle: 0.4660 s, the whole duty cycle (the file ends where it starts), 128.8 picks/min" in res.stderr
    import json

    said = json.loads((tmp_path / "r.json").read_text())
    said = said.get("limits", said)
    assert said["cycle_time_round_trip_s"] == pytest.approx(0.466, abs=1e-9)


def test_a_one_way_table_keeps_the_profiles_duty_cycle(tmp_path):
    """A one-way table (its ends apart) is still one move of the duty cycle move, dwell, back, dwell."""
    from typer.testing import CliRunner

    from pickplace_cli.cli import app

    table = tmp_path / "one.csv"
    res = CliRunner().invoke(app, ["plan", "--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8", "-f", "pvt",
                                   "--cycle", "0.001", "-q", "-o", str(table)])
    assert res.exit_code == 0
    [checked] = check_file(table, load_profile("delta-su2018"))
    assert checked.report.dwell == load_profile("delta-su2018").planning.dwell
    assert not any("whole duty cycle" in n for n in checked.report.notes)
