"""The drive's view of each joint (profile ``controller.joints``): names, units, signs and offsets in the CSV, the
JSON and the MCAP, read back independently (csv module; rosbags for the ROS 2 MCAP) and compared with the formula
d = sign · k · (q − offset) evaluated here from the profile's own numbers; and the profile's validation of it."""

from __future__ import annotations

import csv
import io
import json
import math
from pathlib import Path

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from pickplace_cli.cli import app

runner = CliRunner()
ADEPT = ("--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8")
GEAR = 25.0  # the shipped Delta's gear ratio
JOINTS = [
    {"name": "Arm_A", "unit": "counts", "counts_per_rev": 4096, "sign": -1, "offset": 0.1},
    {"name": "Arm_B", "unit": "motor_rev", "sign": 1, "offset": -0.05},
    {"name": "Arm_C", "unit": "deg", "sign": -1, "offset": 0.2},
]
#: sign · k per joint, from the numbers above (counts: N · cpr / 2π; motor revolutions: N / 2π; degrees: 180 / π)
SCALE = np.array([-GEAR * 4096 / (2 * math.pi), GEAR / (2 * math.pi), -180 / math.pi])
OFFSET = np.array([0.1, -0.05, 0.2])


def run(*args):
    return runner.invoke(app, list(args), catch_exceptions=False)


def profile_with(tmp_path: Path, controller: dict | None, base: str = "delta-su2018") -> Path:
    from pickplace_cli.model.profile import load_profile

    doc = json.loads(load_profile(base).model_dump_json(exclude_none=True))
    doc.pop("controller", None)
    if controller is not None:
        doc["controller"] = controller
    path = tmp_path / "p.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return path


def table(text: str) -> dict[str, np.ndarray]:
    rows = list(csv.reader(io.StringIO(text)))
    data = np.array(rows[1:], dtype=float)
    return {h: data[:, i] for i, h in enumerate(rows[0])}


def test_drive_columns_are_sign_scale_offset_of_the_joint_columns(tmp_path):
    prof = profile_with(tmp_path, {"joints": JOINTS})
    full = table(run("plan", *ADEPT, "--profile", str(prof), "-q").stdout)
    res = run("plan", *ADEPT, "--profile", str(prof), "-q", "--columns", "plc,drive_vel")
    assert res.exit_code == 0, res.stderr
    got = table(res.stdout)
    assert list(got) == ["t[s]", "Arm_A[counts]", "Arm_B[motor_rev]", "Arm_C[deg]", "Arm_A_vel[counts/s]",
                         "Arm_B_vel[motor_rev/s]", "Arm_C_vel[deg/s]"]
    q = np.column_stack([full[f"q{i}[rad]"] for i in (1, 2, 3)])
    qd = np.column_stack([full[f"qd{i}[rad/s]"] for i in (1, 2, 3)])
    d = np.column_stack([got[k] for k in ("Arm_A[counts]", "Arm_B[motor_rev]", "Arm_C[deg]")])
    dv = np.column_stack([got[k] for k in list(got)[4:]])
    # 12 significant digits printed on both sides: relative 1e-11; near the offset (q − offset → 0) the printed q's
    # last digit (≤ 5e-13 · |q| ≤ 1e-12 rad) times |k| ≤ 16,300 counts/rad: 1e-7 absolute
    np.testing.assert_allclose(d, SCALE * (q - OFFSET), rtol=1e-11, atol=1e-7)
    np.testing.assert_allclose(dv, SCALE * qd, rtol=1e-11, atol=1e-7)
    assert np.array_equal(got["t[s]"], full["t[s]"])
    # by default the model's columns only
    assert not any(k.startswith("Arm") for k in full)


def test_without_a_drive_view_the_sets_name_the_model_columns(tmp_path):
    prof = profile_with(tmp_path, None)
    got = table(run("plan", *ADEPT, "--profile", str(prof), "-q", "--columns", "plc,drive_vel").stdout)
    assert list(got) == ["t[s]", "q1[rad]", "q2[rad]", "q3[rad]", "qd1[rad/s]", "qd2[rad/s]", "qd3[rad/s]"]


def test_mcap_names_offsets_and_signs_read_back_with_rosbags(tmp_path):
    from tests.golden.samples import read_ros2

    prof = profile_with(tmp_path, {"joints": JOINTS})
    out = tmp_path / "t.mcap"
    csv_text = run("plan", *ADEPT, "--profile", str(prof), "-q").stdout
    res = run("plan", *ADEPT, "--profile", str(prof), "-q", "-f", "mcap", "-o", str(out))
    assert res.exit_code == 0, res.stderr
    topics = read_ros2(out)
    full = table(csv_text)
    q = np.column_stack([full[f"q{i}[rad]"] for i in (1, 2, 3)])
    qd = np.column_stack([full[f"qd{i}[rad/s]"] for i in (1, 2, 3)])
    states = topics["/joint_states"]
    drives = topics["/drive_states"]
    assert len(states) == len(drives) == len(q)
    for (_, js), (_, ds) in zip(states, drives):
        assert list(js.name) == list(ds.name) == ["Arm_A", "Arm_B", "Arm_C"]
    pos = np.array([m.position for _, m in drives])
    vel = np.array([m.velocity for _, m in drives])
    model = np.array([m.position for _, m in states])
    np.testing.assert_allclose(model, q, rtol=1e-11, atol=1e-12)  # /joint_states stays in rad (REP 103)
    np.testing.assert_allclose(pos, SCALE * (model - OFFSET), rtol=1e-14, atol=1e-9)  # float64 both: exact but for rounding
    np.testing.assert_allclose(vel, SCALE * qd, rtol=1e-11, atol=1e-9)
    traj = topics["/joint_trajectory"]
    assert list(traj[0][1].joint_names) == ["Arm_A", "Arm_B", "Arm_C"]


def test_json_carries_the_drive_view(tmp_path):
    prof = profile_with(tmp_path, {"joints": JOINTS})
    out = tmp_path / "t.json"
    assert run("plan", *ADEPT, "--profile", str(prof), "-q", "-f", "json", "-o", str(out)).exit_code == 0
    doc = json.loads(out.read_text())
    assert [j["name"] for j in doc["joints"]] == ["Arm_A", "Arm_B", "Arm_C"]
    q1 = np.array(doc["samples"]["q1[rad]"])
    np.testing.assert_allclose(doc["samples"]["Arm_A[counts]"], SCALE[0] * (q1 - 0.1), rtol=1e-11, atol=1e-7)


BAD = [
    ({"joints": [dict(JOINTS[0], counts_per_rev=0), *JOINTS[1:]]}, "controller.joints.0.counts_per_rev = 0"),
    ({"joints": [dict(JOINTS[0], counts_per_rev=-4096), *JOINTS[1:]]}, "counts_per_rev"),
    ({"joints": [{"name": "A1", "unit": "counts"}, *JOINTS[1:]]}, "needs counts_per_rev"),
    ({"joints": [JOINTS[0], dict(JOINTS[1], name="arm_a"), JOINTS[2]]}, "repeats"),
    ({"joints": [dict(JOINTS[0], name="1A"), *JOINTS[1:]]}, "IEC 61131-3 identifier"),
    ({"joints": [dict(JOINTS[0], name="A-1"), *JOINTS[1:]]}, "IEC 61131-3 identifier"),
    ({"joints": [dict(JOINTS[0], name="nE"), *JOINTS[1:]]}, "standard function NE"),
    ({"joints": [dict(JOINTS[0], name="q1"), *JOINTS[1:]]}, "column name"),
    ({"joints": [dict(JOINTS[0], name="Arm__A"), *JOINTS[1:]]}, "two _ in a row"),
    ({"joints": JOINTS[:2]}, "one entry per joint of this robot (3)"),
    ({"joints": [dict(JOINTS[0], unit="mm", counts_per_rev=None), *JOINTS[1:]]}, "joint 1 is revolute"),
    ({"joints": [dict(JOINTS[0], sign=2), *JOINTS[1:]]}, "sign"),
    ({"cycle": 0}, "controller.cycle = 0"),
    ({"cycle": -0.001}, "controller.cycle"),
]


@pytest.mark.parametrize("controller, needle", BAD)
def test_bad_drive_view_is_one_line_exit_1(controller, needle, tmp_path):
    controller = {k: ([{kk: vv for kk, vv in j.items() if vv is not None} for j in v] if k == "joints" else v)
                  for k, v in controller.items()}
    prof = profile_with(tmp_path, controller)
    res = run("profile", "validate", str(prof))
    assert res.exit_code == 1, res.stdout
    assert res.stderr.count("\n") == 1 and needle in res.stderr, res.stderr
    out = tmp_path / "t.csv"
    out.write_text("old\n")
    assert run("plan", *ADEPT, "--profile", str(prof), "-o", str(out)).exit_code == 1
    assert out.read_text() == "old\n"


def test_motor_units_need_a_drive(tmp_path):
    prof = profile_with(tmp_path, {"joints": [{"name": "X1", "unit": "motor_rev"}, {"name": "Y1", "unit": "mm"},
                                              {"name": "Z1", "unit": "mm"}]}, base="gantry")
    res = run("profile", "validate", str(prof))
    assert res.exit_code == 1 and "joint 1 has no drive" in res.stderr and res.stderr.count("\n") == 1


def test_shipped_profiles_name_their_joints():
    from pickplace_cli.export.drive import drive_map
    from pickplace_cli.model.profile import load_profile

    names = {p: drive_map(load_profile(p)).names for p in ("delta-su2018", "scara-600", "gantry")}
    assert names == {"delta-su2018": ("A1", "A2", "A3"), "scara-600": ("J1", "J2", "J3", "J4"),
                     "gantry": ("AxisX", "AxisY", "AxisZ")}
