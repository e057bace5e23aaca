"""CLI of the rotary fourth axis: --from/--to X,Y,Z,THETA, --turn, --turn-during, batch columns from_theta and
to_theta, belt rows and schedules with the part's angle, round trips, check, every output (q4 columns, MCAP joint
4), and bad input (one line, exit 1, nothing written)."""

from __future__ import annotations

import csv
import io
import json
import math

import numpy as np
import pytest
from typer.testing import CliRunner

from pickplace_cli.cli import app

runner = CliRunner()
D4 = ["-p", "delta-4axis"]
TURN = ["--from", "-0.1525,0,-0.8,0", "--to", "0.1525,0,-0.8,1.5708"]


def run(*args, **kw):
    return runner.invoke(app, list(args), catch_exceptions=False, **kw)


def table(text: str) -> dict[str, np.ndarray]:
    rows = list(csv.reader(io.StringIO(text)))
    names = [h.split("[")[0] for h in rows[0]]
    data = np.array(rows[1:], float)
    return {n: data[:, k] for k, n in enumerate(names)}


def test_plan_with_a_turn_writes_the_fourth_joint(tmp_path):
    out = tmp_path / "t.csv"
    r = run("plan", *TURN, *D4, "-o", str(out))
    assert r.exit_code == 0, r.stderr
    assert "turn: tool angle 0 → 1.571 rad (+90.0°) between lift-off and set-down" in r.stderr
    assert "q4     motor speed" in r.stderr
    header = out.read_text().splitlines()[0].split(",")
    assert {"q4[rad]", "qd4[rad/s]", "qdd4[rad/s^2]", "torque4[N*m]", "motor_speed4[rad/s]", "motor_torque4[N*m]"} <= set(header)
    col = table(out.read_text())
    assert col["q4"][0] == 0.0 and col["q4"][-1] == pytest.approx(1.5708, abs=1e-12)  # the CSV's 12 digits


def test_json_summary_names_the_angles():
    r = run("plan", *TURN, *D4, "--json", "--turn-during", "whole")
    doc = json.loads(r.stdout)
    assert doc["from_theta_rad"] == 0.0 and doc["to_theta_rad"] == 1.5708
    assert doc["parameters"]["turn"]["during"] == "whole" and doc["parameters"]["turn"]["window_tau"] == [0.0, 1.0]


def test_turn_direction_option():
    r = run("plan", "--from", "-0.1525,0,-0.8,0", "--to", "0.1525,0,-0.8,1", *D4, "--turn", "cw", "--json")
    assert json.loads(r.stdout)["to_theta_rad"] == pytest.approx(1 - 2 * math.pi, abs=1e-12)


@pytest.mark.parametrize("args, needle", [
    (["--from", "-0.1525,0,-0.8,0", "--to", "0.1525,0,-0.8,nan", *D4], "tool angle THETA must be a finite number"),
    (["--from", "-0.1525,0,-0.8,inf", "--to", "0.1525,0,-0.8,0", *D4], "tool angle THETA must be a finite number"),
    (["--from", "-0.1525,0,-0.8,0", "--to", "0.1525,0,-0.8,deg", *D4], "must be a number in rad"),
    (TURN, "needs a robot with a rotary fourth axis; profile delta-su2018"),
    (["--from", "-0.1525,0,-0.8,0", "--to", "0.1525,0,-0.8,13", *D4, "--turn", "as-given"], "beyond its whole range"),
    (["--from", "-0.1525,0,-0.8,0", "--to", "0.1525,0,-0.8", *D4], "needs one at --to too"),
    (["--from", "-0.1525,0,-0.8,0,1", "--to", "0.1525,0,-0.8,0", *D4], "optionally the tool angle THETA"),
])
def test_bad_angles_one_line_exit_1_nothing_written(tmp_path, args, needle):
    out = tmp_path / "o.csv"
    out.write_text("old\n")
    r = run("plan", *args, "-o", str(out))
    assert r.exit_code == 1, r.stderr
    assert needle in r.stderr and len(r.stderr.strip().splitlines()) == 1 and "Traceback" not in r.stderr
    assert out.read_text() == "old\n"  # the old file stays
    r = run("plan", *args, "-o", str(tmp_path / "new.csv"))
    assert r.exit_code == 1 and not (tmp_path / "new.csv").exists()


def test_turn_options_without_angles_are_usage_errors():
    for opt in (["--turn", "ccw"], ["--turn-during", "whole"]):
        r = run("plan", "--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8", *D4, *opt)
        assert r.exit_code == 2 and "only applies with tool angles" in r.stderr


def test_round_trip_turns_back(tmp_path):
    out = tmp_path / "rt.csv"
    r = run("plan", "--from", "-0.1525,0,-0.8,3.0", "--to", "0.1525,0,-0.8,-3.0", *D4, "--round-trip", "-o", str(out))
    assert r.exit_code == 0, r.stderr
    col = table(out.read_text())
    # there the shorter way (+0.283 rad across ±π), back the same way round: ends where it started (12 digits)
    there = col["move"] == 1
    assert col["q4"][there].max() == pytest.approx(3.0 + (2 * math.pi - 6.0), abs=1e-11)
    assert col["q4"][-1] == pytest.approx(3.0, abs=1e-11) and np.all(np.abs(col["q4"] - 3.14) < 0.2)


def test_batch_columns_from_theta_to_theta(tmp_path):
    src = tmp_path / "moves.csv"
    src.write_text("from_x,from_y,from_z,to_x,to_y,to_z,from_theta[rad],to_theta\n"
                   "-0.1525,0,-0.8,0.1525,0,-0.8,0,1.0\n"
                   "0.1525,0,-0.8,-0.1525,0,-0.8,1.0,nan\n"
                   "0.1,0.1,-0.8,-0.1,-0.1,-0.8,,\n")
    out = tmp_path / "o.csv"
    r = run("plan", "--batch", str(src), *D4, "-o", str(out), "-q")
    assert r.exit_code == 1  # row 2's angle is not finite
    assert "row 2 (" in r.stderr and "to_theta = 'nan': must be finite" in r.stderr
    col = table(out.read_text())
    one, three = col["move"] == 1, col["move"] == 3
    assert col["q4"][one][-1] == pytest.approx(1.0, abs=1e-12) and not np.any(col["q4"][three])
    # the same batch on a profile without the axis: the rows with angles fail, one line each, exit 1
    r = run("plan", "--batch", str(src), "-o", str(tmp_path / "p.csv"), "-q")
    assert r.exit_code == 1 and r.stderr.count("rotary fourth axis") == 1
    # a header with one angle column only
    bad = tmp_path / "bad.csv"
    bad.write_text("from_x,from_y,from_z,to_x,to_y,to_z,to_theta\n-0.1525,0,-0.8,0.1525,0,-0.8,1\n")
    r = run("plan", "--batch", str(bad), *D4, "-o", str(tmp_path / "b.csv"))
    assert r.exit_code == 1 and "without 'from_theta'" in r.stderr and not (tmp_path / "b.csv").exists()


def test_batch_json_lines_carry_the_angles(tmp_path):
    src = tmp_path / "moves.csv"
    src.write_text("from_x,from_y,from_z,to_x,to_y,to_z,from_theta,to_theta\n-0.1525,0,-0.8,0.1525,0,-0.8,0.5,-0.5\n")
    r = run("plan", "--batch", str(src), *D4, "--json", "-q")
    doc = json.loads(r.stdout.splitlines()[0])
    assert doc["exit_code"] == 0 and doc["from_theta_rad"] == 0.5 and doc["to_theta_rad"] == -0.5


@pytest.mark.parametrize("move, prof", [(TURN, D4), (["--from", "0.35,-0.1525,-0.15,2.5", "--to", "0.35,0.1525,-0.15,-2.5"],
                                                ["-p", "scara-600"])], ids=["delta-4axis", "scara-600"])
def test_check_reads_the_fourth_joint(tmp_path, move, prof):
    out, rep, chk = tmp_path / "t.csv", tmp_path / "plan.json", tmp_path / "check.json"
    assert run("plan", *move, *prof, "-o", str(out), "--report", str(rep), "-q").exit_code == 0
    r = run("check", str(out), *prof, "--report", str(chk))
    assert r.exit_code == 0, r.stderr
    planned = {(x["joint"], x["quantity"]): x["peak"] for x in json.loads(rep.read_text())["limits"]["rows"]}
    checked = {(x["joint"], x["quantity"]): x["peak"] for x in json.loads(chk.read_text())["limits"]["rows"]}
    for q in ("motor speed", "motor torque", "rms motor torque"):
        # the README's agreement of check with plan on the tool's own CSV: within 1 %
        assert checked[("q4", q)] == pytest.approx(planned[("q4", q)], rel=0.01), q
    assert checked[("q4", "motor torque rate")] == pytest.approx(planned[("q4", "motor torque rate")], rel=0.02)


@pytest.mark.parametrize("move, prof", [(TURN, D4), (["--from", "0.35,-0.1525,-0.15,2.5", "--to", "0.35,0.1525,-0.15,-2.5"],
                                                ["-p", "scara-600"])], ids=["delta-4axis", "scara-600"])
def test_mcap_joint_four_and_the_tool_orientation(tmp_path, move, prof):
    """ROS 2 MCAP read back by rosbags (its own reader and CDR decoder) against the CSV of the same plan: joint 4 in
    the joint states, the tool's orientation about z (θ = q1 + q2 + q4 or q4, from the CSV's columns, the
    quaternion built here) and its angular rates. 1e-11: the CSV's 12 digits."""
    from tests.golden.samples import read_ros2

    out, csv_out = tmp_path / "t.mcap", tmp_path / "t.csv"
    assert run("plan", *move, *prof, "-f", "mcap", "-o", str(out), "-q").exit_code == 0
    assert run("plan", *move, *prof, "-o", str(csv_out), "-q").exit_code == 0
    col = table(csv_out.read_text())
    scara = prof[-1] == "scara-600"
    theta = col["q4"] + (col["q1"] + col["q2"] if scara else 0.0)
    omega = col["qd4"] + (col["qd1"] + col["qd2"] if scara else 0.0)
    alpha = col["qdd4"] + (col["qdd1"] + col["qdd2"] if scara else 0.0)
    msgs = read_ros2(out)
    js = [m for _, m in msgs["/joint_states"]]
    # the profile's drive names (controller.joints)
    names = ["J1", "J2", "J3", "J4"] if scara else ["A1", "A2", "A3", "A4"]
    assert list(js[0].name) == names and len(js) == len(theta)
    np.testing.assert_allclose([m.position[3] for m in js], col["q4"], rtol=0, atol=1e-11)
    quat = np.array([[m.pose.orientation.x, m.pose.orientation.y, m.pose.orientation.z, m.pose.orientation.w]
                     for _, m in msgs["/tool_pose"]])
    np.testing.assert_allclose(quat, np.column_stack([0 * theta, 0 * theta, np.sin(theta / 2), np.cos(theta / 2)]),
                               rtol=0, atol=1e-11)
    np.testing.assert_allclose([m.twist.angular.z for _, m in msgs["/tool_twist"]], omega, rtol=0,
                               atol=1e-11 * max(1.0, np.abs(omega).max()))
    np.testing.assert_allclose([m.accel.angular.z for _, m in msgs["/tool_accel"]], alpha, rtol=0,
                               atol=1e-11 * max(1.0, np.abs(alpha).max()))
    assert all(m.twist.angular.x == 0 and m.twist.angular.y == 0 for _, m in msgs["/tool_twist"])
    # the foxglove flavour's poses carry the same orientation (mcap's own reader, JSON)
    from tests.golden.samples import read_mcap_json

    fox = tmp_path / "f.mcap"
    assert run("plan", *move, *prof, "-f", "mcap", "--mcap-flavor", "foxglove", "-o", str(fox), "-q").exit_code == 0
    poses = read_mcap_json(fox.read_bytes())[1]["/tool_pose"]
    got = np.array([[d["pose"]["orientation"][k] for k in "zw"] for _, d in poses])
    np.testing.assert_allclose(got, np.column_stack([np.sin(theta / 2), np.cos(theta / 2)]), rtol=0, atol=1e-11)


def test_belt_rendezvous_meets_the_part_at_its_angle(tmp_path):
    out = tmp_path / "belt.csv"
    r = run("plan", "--from", "-0.1525,0,-0.8,0", "--to", "0.1525,-0.2,-0.8,0.8", "--to-belt", "0,0.5,0",
            "--latency", "0.05", *D4, "-o", str(out), "--json")
    assert r.exit_code == 0, r.stderr
    doc = json.loads(r.stdout)
    assert doc["rendezvous"]["part_theta_rad"] == 0.8
    col = table(out.read_text())
    T = doc["rendezvous"]["meeting_time_s"]
    # at the meeting and all through the tracking the tool holds the part's angle (12 digits of the CSV)
    after = col["t"] >= T - 1e-9
    assert after.sum() > 10 and np.max(np.abs(col["q4"][after] - 0.8)) < 1e-11
    assert np.max(np.abs(col["qd4"][after])) < 1e-9


def test_schedule_with_angles(tmp_path):
    src = tmp_path / "parts.csv"
    src.write_text(
        "t_detect,to_x,to_y,to_z,to_belt_vx,to_belt_vy,to_belt_vz,place_x,place_y,place_z,from_x,from_y,from_z,"
        "to_theta,place_theta\n"
        "0.00,0.15,-0.30,-0.8,0,0.3,0,-0.1525,0,-0.8,-0.1525,0,-0.8,0.7,0\n"
        "0.15,0.10,-0.30,-0.8,0,0.3,0,-0.1525,0,-0.8,,,,-0.5,\n")
    out = tmp_path / "s.csv"
    r = run("plan", "--batch", str(src), *D4, "--latency", "0.05", "-o", str(out), "--json")
    assert r.exit_code == 0, r.stderr
    rows = [json.loads(ln) for ln in r.stdout.splitlines()]
    assert rows[0]["pick_theta_rad"] == 0.7 and rows[0]["place_theta_rad"] == 0.0
    # row 2 starts at row 1's place angle and keeps the part's angle for the place (no place_theta)
    assert rows[1]["start_theta_rad"] == 0.0 and rows[1]["pick_theta_rad"] == -0.5 and rows[1]["place_theta_rad"] == -0.5
    col = table(out.read_text())
    for row, th in ((rows[0], 0.7), (rows[1], -0.5)):
        meet = np.argmin(np.abs(col["t"] - row["t_meet_s"]))
        assert col["q4"][meet] == pytest.approx(th, abs=1e-11)
    # a schedule with angles on a profile without the axis: row errors, exit 1
    r = run("plan", "--batch", str(src), "--latency", "0.05", "-o", str(tmp_path / "x.csv"), "-q")
    assert r.exit_code == 1 and "rotary fourth axis" in r.stderr


def test_fit_workspace_keeps_the_angles():
    r = run("plan", *TURN, *D4, "--height", "0.4", "--fit-workspace", "--json", "-q")
    doc = json.loads(r.stdout)
    assert doc["height_m"] < 0.4 and doc["to_theta_rad"] == 1.5708  # the height lowered, the turn kept


def test_profile_rotary_section(tmp_path):
    from pickplace_cli.model.profile import resolve_profile_path

    r = run("profile", "show", "scara-600")
    assert "rotary fourth axis: tool angle = q1 + q2 + q4" in r.stdout and "q4: position [-6.283, 6.283] rad" in r.stdout
    text = resolve_profile_path("delta-4axis").read_text()
    for old, new, needle in (("    sign: 1\n", "    sign: 2\n", "robot.rotary.sign = 2"),
                             ("    tool_inertia: 1.0e-4", "    tool_inertia: -1.0e-4", "robot.rotary.tool_inertia = -0.0001"),
                             ("    sign: 1\n", "    sign: 1\n    mass: 2\n", "unknown key 'robot.rotary.mass'")):
        bad = tmp_path / "bad.yaml"
        bad.write_text(text.replace(old, new, 1))
        r = run("profile", "validate", str(bad))
        assert r.exit_code == 1 and needle in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr


def test_check_without_the_fourth_column_is_refused(tmp_path):
    f = tmp_path / "three.csv"
    f.write_text("t,q1,q2,q3\n" + "".join(f"{k * 0.01:g},0.1,-1.0,-0.1\n" for k in range(8)))
    r = run("check", str(f), "-p", "scara-600")
    assert r.exit_code == 1 and "lacks column(s) q4" in r.stderr and len(r.stderr.strip().splitlines()) == 1
