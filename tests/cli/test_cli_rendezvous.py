"""plan --to-belt/--latency (issue 17): exit codes, one-line errors, nothing written on error, summary line."""

from __future__ import annotations

import csv
import io
import json

import numpy as np
import pytest
from typer.testing import CliRunner

from pickplace_cli.cli import app

runner = CliRunner()
BELT = ["--from", "-0.1525,0,-0.8", "--to", "0.1525,-0.1,-0.8", "--to-belt", "0,0.5,0"]


def run(*args):
    return runner.invoke(app, list(args), catch_exceptions=False)


def test_to_belt_meets_the_part(tmp_path):
    out = tmp_path / "rv.csv"
    r = run("plan", *BELT, "--latency", "0.05", "-o", str(out))
    assert r.exit_code == 0, r.stderr
    line = next(s for s in r.stderr.splitlines() if s.startswith("rendezvous:"))
    assert "meets the part at (0.1525, " in line and "after its detection" in line
    assert "/ bspline-vel:" in r.stderr  # the belt end selected the velocity-constrained method
    rows = list(csv.reader(io.StringIO(out.read_text())))
    head = rows[0]
    data = np.array(rows[1:], float)
    T = float(line.split("at t = ")[1].split(" s")[0])
    meet = data[np.argmin(np.abs(data[:, head.index("t[s]")] - T))]
    part = np.array([0.1525, -0.1 + 0.5 * (0.05 + meet[head.index("t[s]")]), -0.8])
    # the CSV's fixed float format (and the summary's 4 digits for T) limit this comparison, not the solve
    assert np.abs(meet[[head.index(c) for c in ("x[m]", "y[m]", "z[m]")]] - part).max() < 1e-6
    assert np.abs(meet[[head.index(c) for c in ("vx[m/s]", "vy[m/s]", "vz[m/s]")]] - [0, 0.5, 0]).max() < 1e-6


def test_json_has_the_rendezvous():
    r = run("plan", *BELT, "--json", "-q")
    assert r.exit_code == 0, r.stderr
    doc = json.loads(r.stdout)
    rv = doc["rendezvous"]
    assert doc["method"] == "bspline-vel"
    assert rv["meeting_time_s"] == doc["duration_s"]
    assert rv["meeting_point_m"][1] == pytest.approx(-0.1 + 0.5 * rv["meeting_time_s"], abs=1e-12)


def test_from_belt_is_v_from():
    r1 = run("plan", "--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8", "-m", "bspline-vel", "--from-belt", "0,0.3,0",
             "--time", "0.2", "-q")
    r2 = run("plan", "--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8", "-m", "bspline-vel", "--v-from", "0,0.3,0",
             "--time", "0.2", "-q")
    assert r1.exit_code == r2.exit_code == 0 and r1.stdout == r2.stdout


@pytest.mark.parametrize(
    "extra, code, message",
    [
        (["--to-belt", "0,nan,0"], 1, "--to-belt '0,nan,0': every coordinate must be a finite number"),
        (["--to-belt", "0,inf,0"], 1, "--to-belt '0,inf,0'"),
        (["--to-belt", "0,0.5"], 1, "--to-belt '0,0.5': give three components"),
        (["--to-belt", "0,0.5,0", "--latency", "-0.1"], 1, "--latency -0.1: must be a finite number of seconds >= 0"),
        (["--to-belt", "0,0.5,0", "--latency", "nan"], 1, "--latency nan"),
        (["--to-belt", "0,0.5,0", "-m", "ph"], 1, "to-belt: method ph plans moves from rest to rest"),
        (["--to-belt", "0,0.5,0", "-t", "optimal"], 2, "--time optimal: method bspline-vel"),
        (["--to-belt", "0,0.5,0", "--param", "tau6=0.01"], 2, "shape parameters are chosen for each trial"),
        (["--to-belt", "0,3,0"], 4, "the robot cannot reach it before it leaves the workspace"),
    ],
)
def test_bad_input_one_line_nothing_written(tmp_path, extra, code, message):
    out = tmp_path / "x.csv"
    r = run("plan", "--from", "-0.1525,0,-0.8", "--to", "0.1525,-0.1,-0.8", *extra, "-o", str(out))
    assert r.exit_code == code, r.stderr
    assert message in r.stderr
    if code != 2:  # usage errors are click's short usage message
        assert len(r.stderr.strip().splitlines()) == 1 and "Traceback" not in r.stderr
    assert not out.exists()


@pytest.mark.parametrize("extra", [["--latency", "0.1"], ["--to-belt", "0,0.5,0", "--v-to", "0,0.5,0"],
                                   ["--to-belt", "0,0.5,0", "--round-trip", "--v-from", "0.1,0,0"],
                                   ["--to-belt", "0,0.5,0", "--fit-workspace"]])
def test_usage_errors(extra):
    r = run("plan", "--from", "-0.1525,0,-0.8", "--to", "0.1525,-0.1,-0.8", *extra)
    assert r.exit_code == 2


def test_help_names_units():
    r = run("plan", "--help")
    text = " ".join(r.stdout.split())
    assert "--to-belt" in text and "--latency" in text and "--from-belt" in text


def test_csv_includes_the_tracking_segment(tmp_path):
    """The written trajectory goes on from T to T + dwell (the profile's 0.1 s) with the tool on the part."""
    out = tmp_path / "rv.csv"
    r = run("plan", *BELT, "-o", str(out))
    assert r.exit_code == 0, r.stderr
    assert "--- tracking the part: t = " in r.stderr
    rows = list(csv.reader(io.StringIO(out.read_text())))
    head, data = rows[0], np.array(rows[1:], float)
    t = data[:, head.index("t[s]")]
    T = json.loads(run("plan", *BELT, "--json", "-q").stdout)["duration_s"]
    assert t[-1] == pytest.approx(T + 0.1, abs=1e-9) and np.all(np.diff(t) > 0)
    late = t > T
    y = data[late, head.index("y[m]")]
    assert np.abs(y - (-0.1 + 0.5 * t[late])).max() < 1e-9  # the CSV's 12 significant digits
    assert np.all(data[late, head.index("vy[m/s]")] == 0.5)
    r = run("check", str(out))
    assert r.exit_code == 0, r.stderr


def test_window_miss_is_exit_4_nothing_written(tmp_path):
    from pickplace_cli.model.resources import data_dir

    text = (data_dir("profiles") / "delta-su2018.yaml").read_text()
    anchor = "  box: {min: [-0.6, -0.6, -1.1], max: [0.6, 0.6, -0.55]}"
    assert anchor in text
    prof = tmp_path / "belt.yaml"
    prof.write_text(text.replace(anchor, anchor + "\n  belt_window: {min: [0.0, -0.3, -0.9], max: [0.3, 0.0, -0.7]}"))
    out = tmp_path / "x.csv"
    r = run("plan", *BELT, "-p", str(prof), "-o", str(out))
    assert r.exit_code == 4
    assert len(r.stderr.strip().splitlines()) == 1
    assert "the part leaves the belt window 4" in r.stderr and "mm before the robot can reach it" in r.stderr
    assert not out.exists()


BELT_BATCH = ("from_x,from_y,from_z,to_x,to_y,to_z,to_belt_vx,to_belt_vy,to_belt_vz,latency\n"
              "-0.1525,0,-0.8,0.1525,-0.1,-0.8,0,0.5,0,0.05\n"   # a belt row
              "-0.1525,0,-0.8,0.1525,-0.1,-0.8,,,,\n"             # a fixed end (empty belt cells)
              "-0.1525,0,-0.8,0.1525,-0.2,-0.8,0,2.5,0,0.05\n")  # a part the robot cannot catch


def test_batch_belt_rows_are_rendezvous_with_tracking(tmp_path):
    """A plain batch (no t_detect) with to_belt_v* and latency columns: each belt row is the --to-belt plan of
    that row (the same samples, tracking segment included), an empty belt row a fixed move, a missed part
    exit 4 with its one line; --json carries rendezvous and tracking; a pipe gives the same answers."""
    src = tmp_path / "belt.csv"
    src.write_text(BELT_BATCH)
    out = tmp_path / "out.csv"
    r = run("plan", "--batch", str(src), "-o", str(out))
    assert r.exit_code == 4
    assert "belt.csv:4): part (detected at 0.1525,-0.2,-0.8 m, belt 0,2.5,0 m/s): the robot cannot reach it" in r.stderr
    single = tmp_path / "single.csv"
    assert run("plan", *BELT, "--latency", "0.05", "-o", str(single)).exit_code == 0
    rows = list(csv.reader(io.StringIO(out.read_text())))
    mine = [row for row in rows[1:] if row[0] == "1"]  # move 1: the --to-belt CSV numbers its move 1 too
    assert mine == list(csv.reader(io.StringIO(single.read_text())))[1:]
    assert {row[0] for row in rows[1:]} == {"1", "2"}
    r = run("plan", "--batch", str(src), "--json")
    docs = [json.loads(x) for x in r.stdout.splitlines()]
    assert docs[0]["method"] == "bspline-vel" and docs[0]["parameters"]["rendezvous"]["latency_s"] == 0.05
    assert docs[0]["parameters"]["tracking"]["duration_s"] == pytest.approx(0.1)
    assert docs[1]["method"] == "bspline" and docs[2]["exit_code"] == 4
    piped = runner.invoke(app, ["plan", "--batch", "-", "--json"], input=BELT_BATCH, catch_exceptions=False)
    assert [json.loads(x)["exit_code"] for x in piped.stdout.splitlines()] == [0, 0, 4]
    assert json.loads(piped.stdout.splitlines()[0])["duration_s"] == docs[0]["duration_s"]


@pytest.mark.parametrize("header, cells, message", [
    ("from_x,from_y,from_z,to_x,to_y,to_z,to_belt_vx,to_belt_vy", "0,0,-0.8,0.1,0,-0.8,0,0.5",
     "column 'to_belt_vz' is missing (a belt row gives the belt velocity as to_belt_vx, to_belt_vy, to_belt_vz, m/s)"),
    ("from_x,from_y,from_z,to_x,to_y,to_z,latency", "0,0,-0.8,0.1,0,-0.8,0.1", "column 'latency' needs the belt columns"),
    ("from_x,from_y,from_z,to_x,to_y,to_z,to_belt_vx,to_belt_vy,to_belt_vz,v_to_y", "0,0,-0.8,0.1,0,-0.8,0,0.5,0,0.5",
     "columns v_to_* and to_belt_v* both give the end velocity"),
])
def test_batch_belt_header_errors(tmp_path, header, cells, message):
    src = tmp_path / "b.csv"
    src.write_text(f"{header}\n{cells}\n")
    r = run("plan", "--batch", str(src))
    assert r.exit_code == 1 and message in r.stderr and len(r.stderr.strip().splitlines()) == 1


def test_batch_belt_row_errors(tmp_path):
    """A partial belt velocity in a row, a negative latency, a method that plans from rest to rest: that row's
    one line (exit 1 or 2), the other rows planned."""
    src = tmp_path / "b.csv"
    src.write_text("from_x,from_y,from_z,to_x,to_y,to_z,to_belt_vx,to_belt_vy,to_belt_vz,latency\n"
                   "-0.1525,0,-0.8,0.1525,-0.1,-0.8,0,0.5,,\n"
                   "-0.1525,0,-0.8,0.1525,-0.1,-0.8,0,0.5,0,-0.1\n"
                   "-0.1525,0,-0.8,0.1525,-0.1,-0.8,0,0.5,0,0\n")
    r = run("plan", "--batch", str(src), "--json")
    docs = [json.loads(x) for x in r.stdout.splitlines()]
    assert "to_belt_vz is empty: a belt row gives all of to_belt_vx, to_belt_vy, to_belt_vz" in docs[0]["error"]
    assert "latency = '-0.1': must be >= 0 s" in docs[1]["error"]
    assert docs[2]["exit_code"] == 0
    r = run("plan", "--batch", str(src), "--method", "lame", "--json")
    assert "method lame plans moves from rest to rest; a belt row is planned by bspline-vel" in \
        json.loads(r.stdout.splitlines()[2])["error"]
