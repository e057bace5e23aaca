"""plan --batch with a t_detect column: a belt schedule (issue 17): exit codes, one-line errors, nothing written."""

from __future__ import annotations

import csv
import io
import json

import numpy as np
import pytest
from typer.testing import CliRunner

from pickplace_cli.cli import app

runner = CliRunner()
HEAD = "t_detect,to_x,to_y,to_z,to_belt_vx,to_belt_vy,to_belt_vz,place_x,place_y,place_z,from_x,from_y,from_z\n"
P = "-0.1525,0,-0.8"
GOOD = HEAD + (f"0.00,0.1525,-0.25,-0.8,0,0.3,0,{P},{P}\n"
               f"0.10,0.10,-1.25,-0.8,0,2.5,0,{P},,,\n"  # too fast: missed
               f"0.20,0.20,-0.35,-0.8,0,0.3,0,{P},,,\n")


def run(*args, input=None):
    return runner.invoke(app, list(args), input=input, catch_exceptions=False)


@pytest.fixture(scope="module")
def good_run(tmp_path_factory):
    d = tmp_path_factory.mktemp("sched")
    src = d / "parts.csv"
    src.write_text(GOOD)
    out = d / "out.csv"
    r = run("plan", "--batch", str(src), "--json", "-o", str(out))
    return r, out


def test_schedule_json_and_exit_4(good_run):
    r, out = good_run
    assert r.exit_code == 4, r.stderr
    docs = [json.loads(x) for x in r.stdout.splitlines()]
    assert [d.get("row") for d in docs[:3]] == [1, 2, 3] and [d["exit_code"] for d in docs[:3]] == [0, 4, 0]
    assert docs[3]["schedule"]["picks"] == 2 and docs[3]["schedule"]["failed_rows"] == [2]
    assert docs[2]["t_start_s"] == pytest.approx(docs[0]["t_end_s"], abs=1e-12)  # the missed part moved nothing
    assert docs[2]["start_m"] == docs[0]["place_m"]
    err = r.stderr.splitlines()
    assert sum(1 for ln in err if ln.startswith("pickplace: row 2 (")) == 1
    assert err[-1].startswith("schedule: 3 parts, 2 picked, 1 missed or failed (row 2); picks from t = 0.0000 to ")


def test_schedule_csv_is_continuous(good_run):
    _r, out = good_run
    rows = list(csv.reader(io.StringIO(out.read_text())))
    head, data = rows[0], np.array(rows[1:], float)
    assert head[:2] == ["move[-]", "t[s]"]
    move, t = data[:, 0], data[:, 1]
    assert sorted(set(move)) == [1.0, 3.0]
    assert np.all(np.diff(t) >= 0)  # one clock (the detection's) for the whole schedule
    last1, first3 = np.flatnonzero(move == 1)[-1], np.flatnonzero(move == 3)[0]
    xyz = [head.index(c) for c in ("x[m]", "y[m]", "z[m]")]
    assert abs(t[first3] - t[last1]) < 1e-9 and np.abs(data[first3, xyz] - data[last1, xyz]).max() < 1e-9


def test_streamed_schedule_same_rows(good_run):
    r0, _ = good_run
    r = run("plan", "--batch", "-", "--json", "-j", "2", input=GOOD)
    assert r.exit_code == 4
    src = json.loads(r0.stdout.splitlines()[1])["error"].split(" (")[1].split(":")[0]
    assert r.stdout == r0.stdout.replace(src, "stdin")  # the same answers, row by row
    assert "a belt schedule is planned row by row" in r.stderr


@pytest.mark.parametrize("edit, message", [
    (lambda t: t.replace("0.20,0.20", "0.05,0.20"), "row 3 (FILE:4): t_detect = 0.05 s is earlier than row 2's 0.1 s"),
    (lambda t: t.replace("0,2.5,0", "0,nan,0"), "row 2 (FILE:3): to_belt_vy = 'nan': must be finite"),
    (lambda t: t.replace("0,2.5,0", "0,inf,0"), "row 2 (FILE:3): to_belt_vy = 'inf': must be finite"),
    (lambda t: "latency," + t.splitlines()[0] + "\n" + "".join(f"{lat},{ln}\n" for lat, ln in
                                                             zip(("0", "-0.1", "0"), t.splitlines()[1:])),
     "row 2 (FILE:3): latency = '-0.1': must be >= 0 s"),
])
def test_bad_input_one_line_nothing_written(tmp_path, edit, message):
    src = tmp_path / "bad.csv"
    src.write_text(edit(GOOD))
    out = tmp_path / "out.csv"
    r = run("plan", "--batch", str(src), "-o", str(out))
    assert r.exit_code == 1
    assert r.stderr.splitlines() == [r.stderr.splitlines()[0]]  # one line
    assert r.stderr.startswith("pickplace: error: " + message.replace("FILE", str(src)))
    assert not out.exists() and list(tmp_path.iterdir()) == [src]


def test_negative_latency_option(tmp_path):
    src = tmp_path / "p.csv"
    src.write_text(GOOD)
    r = run("plan", "--batch", str(src), "--latency", "-1", "-o", str(tmp_path / "o.csv"))
    assert r.exit_code == 1 and r.stderr == "pickplace: error: --latency -1.0: must be a finite number of seconds >= 0 (detection to move start)\n"
    assert not (tmp_path / "o.csv").exists()


def test_latency_needs_a_schedule(tmp_path):
    src = tmp_path / "b.csv"
    src.write_text("from_x,from_y,from_z,to_x,to_y,to_z\n-0.1525,0,-0.8,0.1525,0,-0.8\n")
    r = run("plan", "--batch", str(src), "--latency", "0.1")
    assert r.exit_code == 2 and "--latency with --batch" in r.stderr


def test_report_holds_every_row_and_segment(tmp_path):
    """--report with a schedule: the closing summary and, per row, its exit code, error and (for a cycle) the
    summary and limit report of each segment (pick, track, place); the miss stays exit 4."""
    src = tmp_path / "p.csv"
    src.write_text(GOOD)
    rep = tmp_path / "r.json"
    r = run("plan", "--batch", str(src), "--report", str(rep), "-q")
    assert r.exit_code == 4
    doc = json.loads(rep.read_text())
    assert doc["schedule"]["picks"] == 2 and [x["exit_code"] for x in doc["rows"]] == [0, 4, 0]
    assert [s["segment"] for s in doc["rows"][0]["segments"]] == ["pick", "track", "place"]
    assert all(s["limits"]["ok"] for s in doc["rows"][0]["segments"])
    assert "segments" not in doc["rows"][1] and "the robot cannot reach it" in doc["rows"][1]["error"]


def test_report_only_runs_the_cycles_that_break_a_limit(tmp_path):
    """A profile whose motors' torque rate is too low for these cycles: every picked row is exit 3 (one line per
    limit and segment) and moves nothing; with --report-only the cycles run as planned (the robot goes on from
    each), are written, the report says which limits fail, and the exit code is 0."""
    text = open("profiles/delta-su2018.yaml").read().replace("torque_rate: 418.0", "torque_rate: 100.0")
    prof = tmp_path / "weak.yaml"
    prof.write_text(text)
    src = tmp_path / "p.csv"
    src.write_text(HEAD + f"0.00,0.1525,-0.25,-0.8,0,0.3,0,{P},{P}\n0.20,0.20,-0.35,-0.8,0,0.3,0,{P},,,\n")
    r = run("plan", "-p", str(prof), "--batch", str(src), "-t", "auto", "--json", "-o", str(tmp_path / "o.csv"))
    assert r.exit_code == 3
    docs = [json.loads(x) for x in r.stdout.splitlines()]
    assert [d["exit_code"] for d in docs[:2]] == [3, 3]
    assert docs[1]["start_m"] == [-0.1525, 0.0, -0.8]  # the failed row 1 moved nothing
    assert "motor torque rate" in r.stderr and ": pick: limit exceeded:" in r.stderr
    out, rep = tmp_path / "o2.csv", tmp_path / "r.json"
    r = run("plan", "-p", str(prof), "--batch", str(src), "-t", "auto", "--json", "--write-anyway", "--report", str(rep),
            "-o", str(out))
    assert r.exit_code == 0
    docs = [json.loads(x) for x in r.stdout.splitlines()]
    assert docs[1]["t_start_s"] == pytest.approx(docs[0]["t_end_s"], abs=1e-12)  # row 2 starts when row 1 ends
    rows = list(csv.reader(io.StringIO(out.read_text())))
    assert {row[0] for row in rows[1:]} == {"1", "2"}
    bad = [v for s in json.loads(rep.read_text())["rows"][0]["segments"] for v in s["limits"]["violations"]]
    assert bad and all(v["quantity"] == "motor torque rate" for v in bad)


def test_help_names_the_columns():
    r = run("plan", "--help")
    assert "t_detect" in r.stdout and "to_belt_vx" in r.stdout
