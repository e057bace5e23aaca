"""CLI of `profile show/validate` and `check`: messages a new user meets (one line naming field, value, rule;
exit codes), the workspace sentence, and check on this tool's own multi-move CSV."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from pickplace_cli.cli import app
from pickplace_cli.model.profile import resolve_profile_path

runner = CliRunner()
ADEPT = ["--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8"]


def run(*args, input=None):
    return runner.invoke(app, list(args), catch_exceptions=False, input=input)


def test_profile_show_scara_workspace_sentence():
    r = run("profile", "show", "scara-600")
    assert r.exit_code == 0
    line = next(x for x in r.stdout.splitlines() if x.startswith("workspace at z"))
    assert line.startswith("workspace at z = -0.1 m: radius 0.163 … 0.599 m reachable in 42 of 72 directions (azimuth -135° … 70°")
    assert "no common radius" not in line and "limit the rest" not in line


@pytest.mark.parametrize("z", ["nan", "inf", "-inf"])
def test_profile_show_refuses_non_finite_z(z):
    r = run("profile", "show", "--z", z)
    assert r.exit_code == 1 and r.stdout == ""
    assert r.stderr.strip() == f"pickplace: error: --z {float(z)!r}: must be a finite number in m (no NaN or inf)"


def test_profile_validate_names_a_short_range(tmp_path):
    prof = tmp_path / "p.yaml"
    prof.write_text(resolve_profile_path("delta-su2018").read_text().replace("position: [-0.6981317, 1.5707963]", "position: [-0.6981317]"))
    r = run("profile", "validate", str(prof))
    assert r.exit_code == 1 and len(r.stderr.strip().splitlines()) == 1
    line = next(n for n, row in enumerate(prof.read_text().splitlines(), 1) if "position: [-0.6981317]" in row)
    assert f"{prof}:{line}: robot.joints.limits.position = [-0.6981317]: needs 2 values, got 1" in r.stderr


def _batch(tmp_path, second_time: str = "") -> tuple:
    moves = tmp_path / "moves.csv"
    moves.write_text(
        "from_x,from_y,from_z,to_x,to_y,to_z,height,time\n"
        "-0.1525,0,-0.8,0.1525,0,-0.8,,\n"
        f"0.1,0.1,-0.8,-0.1,-0.1,-0.8,0.03,{second_time}\n"
    )
    out = tmp_path / "batch.csv"
    r = run("plan", "--batch", str(moves), "-q", "--report-only", "-o", str(out))
    assert r.exit_code == 0, r.stderr
    return out


def test_check_batch_output_move_by_move(tmp_path):
    out = _batch(tmp_path)
    rep = tmp_path / "r.json"
    r = run("check", str(out), "--report", str(rep))
    # was exit 1: "t must increase strictly from row to row" where move 2 starts again at t = 0
    assert r.exit_code == 0, r.stderr
    assert "--- move 1 (lines 2–" in r.stderr and "--- move 2 (lines " in r.stderr
    assert r.stderr.rstrip().endswith("checked 2 move(s): 2 within every limit, 0 exceed one")
    doc = json.loads(rep.read_text())
    assert [m["move"] for m in doc["moves"]] == [1, 2] and all(m["limits"]["ok"] for m in doc["moves"])
    assert doc["moves"][1]["lines"][0] == doc["moves"][0]["lines"][1] + 1


def test_check_batch_names_the_move_that_fails(tmp_path):
    out = _batch(tmp_path, second_time="0.08")
    r = run("check", str(out), "-q")
    assert r.exit_code == 3
    lines = r.stderr.strip().splitlines()
    assert lines[0].startswith("--- move 2 (lines ") and "limit exceeded: q" in lines[1]
    assert "move 1" not in r.stderr  # -q: only the failing move


def test_check_round_trip_output(tmp_path):
    out = tmp_path / "rt.csv"
    assert run("plan", *ADEPT, "--round-trip", "-q", "-o", str(out)).exit_code == 0
    r = run("check", str(out))
    assert r.exit_code == 0
    assert "--- move 2 (lines " in r.stderr and "trailing samples at rest set aside as the dwell" in r.stderr


def test_check_reports_positions_as_given(tmp_path):
    """A Delta file with q1 shifted by a whole turn: the same pose, but q1 = 2π + … is outside [−0.698, 1.571] rad
    and is reported as the file's value (was the IK's wrapped value, inside the range: exit 0)."""
    import math

    out = tmp_path / "a.csv"
    assert run("plan", *ADEPT, "-q", "-o", str(out)).exit_code == 0
    lines = out.read_text().splitlines()
    col = lines[0].split(",").index("q1[rad]")
    rows = [ln.split(",") for ln in lines[1:]]
    q1_max = max(float(c[col]) for c in rows) + 2 * math.pi
    for c in rows:
        c[col] = repr(float(c[col]) + 2 * math.pi)
    out.write_text("\n".join([lines[0]] + [",".join(c) for c in rows]) + "\n")
    r = run("check", str(out), "-q")
    assert r.exit_code == 4
    assert f"limit exceeded: q1 position = {q1_max:.4g} rad" in r.stderr and "limit 1.571 rad" in r.stderr


@pytest.mark.parametrize("cell", ["x1", "0.3_1"])  # 0.3_1: float() reads 0.31 (review, session 16)
def test_check_not_a_number_names_column_row_and_value(tmp_path, cell):
    bad = tmp_path / "bad.csv"
    bad.write_text("t,q1,q2,q3\n" + "".join(f"{i * 0.01},0.3,{cell if i == 3 else 0.3},0.3\n" for i in range(8)))
    r = run("check", str(bad))
    assert r.exit_code == 1
    assert r.stderr.strip() == f"pickplace: error: {bad}:5: q2 = {cell!r}: not a number (column 3, 'q2')"


@pytest.mark.parametrize("text", ["t,q1,q2,q3\n", "t,q1,q2,q3\n\n# only a comment\n", "move,t,q1,q2,q3\n"])
def test_check_a_header_without_samples_is_one_line(tmp_path, text):
    """A header and no sample rows ended in an IndexError traceback (review, session 16)."""
    f = tmp_path / "empty.csv"
    f.write_text(text)
    for args, name, inp in (((str(f),), str(f), None), (("-",), "<stdin>", text)):
        r = runner.invoke(app, ["check", *args], input=inp)
        assert r.exit_code == 1 and isinstance(r.exception, SystemExit), r.exception  # not an IndexError
        assert r.stderr.strip() == (f"pickplace: error: {name}:1: a header and no samples (need rows of t, q1, q2, "
                                    "q3 after it; a move needs at least 6)")


def test_check_help_names_the_argument():
    r = run("check", "--help")
    assert r.exit_code == 0 and "{TRAJECTORY}" in r.stdout and "{trajectory}" not in r.stdout
    assert "move by move" in r.stdout
