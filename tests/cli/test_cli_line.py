"""`pickplace line`: outputs, exit codes, one-line refusals, atomic files, streaming from stdin, sweeps."""

from __future__ import annotations

import csv
import io
import json
import os
import select
import subprocess
import sys

import pytest
from typer.testing import CliRunner

from pickplace_cli.cli import app

runner = CliRunner()
LINE = """\
name: two deltas
belt: {speed: 0.5, width: 0.3}
robots:
  - name: r1
    base: [0.6, 0.0, 0.8]
    window: [0.4, 0.8]
    place: {points: [[0.6, 0.35, 0.0]]}
  - name: r2
    base: [1.4, 0.0, 0.8]
    window: [1.2, 1.6]
    place: {points: [[1.4, 0.35, 0.0]]}
parts:
  generate: {rate: 4.0, count: 12, seed: 2}
  latency: 0.05
"""


def run(*args, input=None):
    return runner.invoke(app, [str(a) for a in args], input=input, catch_exceptions=False)


@pytest.fixture
def line_file(tmp_path):
    p = tmp_path / "line.yaml"
    p.write_text(LINE)
    return p


def _one_line(r, code: int, text: str) -> str:
    assert r.exit_code == code, (r.exit_code, r.stderr)
    err = [x for x in r.stderr.splitlines() if x.startswith("pickplace: error:")]
    assert len(err) == 1 and text in err[0], r.stderr
    return err[0]


def test_a_run_writes_parts_robots_and_summary(line_file, tmp_path):
    out, robots, summ = tmp_path / "parts.csv", tmp_path / "robots.csv", tmp_path / "s.json"
    r = run("line", line_file, "-o", out, "--robots-csv", robots, "--summary", summ)
    assert r.exit_code == 0, r.stderr
    rows = list(csv.DictReader(out.open()))
    assert len(rows) == 12 and rows[0]["t_meet[s]"] and "reason" in rows[0]
    doc = json.loads(summ.read_text())
    assert doc["parts"] == 12 and doc["picked"] == sum(r["picked"] == "1" for r in rows)
    assert doc["picked"] + doc["missed"] == 12
    rob = list(csv.DictReader(robots.open()))
    assert [x["robot"] for x in rob] == ["r1", "r2"] and "rms_q1[N*m]" in rob[0]
    assert "line: 12 parts" in r.stderr  # the table


def test_json_lines_and_the_closing_summary(line_file):
    r = run("line", line_file, "--json", "-q")
    docs = [json.loads(x) for x in r.stdout.splitlines()]
    assert len(docs) == 13 and docs[-1]["parts"] == 12
    picked = [d for d in docs[:-1] if d["picked"]]
    assert picked and {"robot", "t_meet_s", "meet_m", "pick_shape", "place_m"} <= set(picked[0])


def test_window_outside_the_workspace_is_exit_4(line_file):
    line_file.write_text(LINE.replace("window: [0.4, 0.8]", "window: [0.4, 1.19]"))
    _one_line(run("line", line_file, "-q"), 4, "robot r1: window [0.4, 1.19] m across [-0.15, 0.15] m: the point along")


def test_a_home_outside_the_workspace_names_the_robot(line_file):
    """A base too high for its place point (the robot's home): one line naming the robot and its home, exit 4 (it was
    the robot model's message alone, naming neither)."""
    line_file.write_text(LINE.replace("base: [0.6, 0.0, 0.8]", "base: [0.6, 0.0, 8]"))
    _one_line(run("line", line_file, "-q"), 4, "robot r1: home point [0.6, 0.35, 0] m (line frame) is outside the "
              "workspace of profile delta-su2018: Delta: sample 0")


def test_a_belt_too_fast_to_track_in_the_window_says_so(line_file):
    """At 5 m/s the dwell's tracking (0.1 s: 0.5 m) needs more than the 0.4 m window: no meeting point; the line says
    that (it said the part, upstream, was past its window's end)."""
    _one_line(run("line", line_file, "--belt-speed", "5", "-q"), 4,
              "robot r1: no meeting point in its window [0.4, 0.8] m: tracking the part for the dwell (0.1 s at 5 m/s = "
              "0.5 m) needs more than the window's 0.4 m")


def test_overlapping_windows_are_refused(line_file):
    line_file.write_text(LINE.replace("window: [1.2, 1.6]", "window: [0.7, 1.1]"))
    _one_line(run("line", line_file), 1, "robots r1 and r2: windows [0.4, 0.8] and [0.7, 1.1] m overlap")


def test_a_belt_no_robot_can_keep_up_with_is_exit_4(line_file):
    _one_line(run("line", line_file, "--belt-speed", "8"), 4, "belt.speed = 8 m/s: no robot can take a part")


def test_detections_out_of_order_refuse_the_row_and_go_on(line_file, tmp_path):
    det = tmp_path / "d.csv"
    det.write_text("t[s],along[m],across[m]\n0.0,0,0\n2.0,0,0.05\n1.0,0,0\n4.0,0,-0.05\n")
    r = run("line", line_file, "--detections", det, "--json", "-q")
    assert r.exit_code == 1
    docs = [json.loads(x) for x in r.stdout.splitlines()]
    assert [d["exit_code"] for d in docs[:4]] == [0, 0, 1, 0] and docs[-1]["bad_rows"] == 1
    err = [x for x in r.stderr.splitlines() if x.startswith("pickplace:")]
    assert err == ["pickplace: row 3 (part 3): t = 1 s is 1 s earlier than row 2's t = 2 s, already passed on: "
                   "detections must come in time order (set parts.reorder to a window in s to hold and re-order late "
                   "ones)"]
    # held and re-ordered within a 1.5 s window: every row answered
    line_file.write_text(LINE.replace("latency: 0.05", "latency: 0.05\n  reorder: 1.5"))
    r = run("line", line_file, "--detections", det, "--json", "-q")
    assert r.exit_code == 0 and [json.loads(x)["id"] for x in r.stdout.splitlines()[:4]] == ["1", "3", "2", "4"]


def test_a_failed_run_leaves_the_old_file_and_an_input_is_never_overwritten(line_file, tmp_path):
    out = tmp_path / "parts.csv"
    out.write_text("old\n")
    line_file.write_text(LINE.replace("window: [0.4, 0.8]", "window: [0.4, 1.19]"))
    assert run("line", line_file, "-o", out, "-q").exit_code == 4
    assert out.read_text() == "old\n"
    line_file.write_text(LINE)
    _one_line(run("line", line_file, "--summary", line_file), 1, "is an input of this run")
    assert line_file.read_text() == LINE


@pytest.mark.parametrize("args, text", [
    (["--strategy", "fastest"], "--strategy 'fastest': choose from upstream_first, quota, bands, skip"),
    (["--robots", "3"], "--robots 3: the line file has 2 robots"),
    (["--max-miss-rate", "2"], "--max-miss-rate 2.0: must be a share between 0 and 1"),
    (["--speeds", "0.2,x"], "--speeds '0.2,x': give numbers separated by commas"),
])
def test_bad_options_are_one_line(line_file, args, text):
    _one_line(run("line", line_file, *args), 1, text)


def test_sweep_only_options_are_usage_errors(line_file):
    r = run("line", line_file, "--resume")
    assert r.exit_code == 2 and "--resume, --scheduler and --workers are for a sweep" in r.stderr


def test_streamed_detections_are_answered_one_by_one(line_file):
    """A row is answered before the next is written (read with select, a 120 s cap: no timing assumption)."""
    proc = subprocess.Popen([sys.executable, "-m", "pickplace_cli", "line", str(line_file), "--detections", "-",
                             "--json", "-q"], stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        proc.stdin.write(b"t[s],along[m],across[m],angle[rad]\n")
        answers = []
        for k, row in enumerate([b"0.0,0,0.02,0.5\n", b"0.5,0,-0.03,\n", b"0.2,0,0,\n"]):
            proc.stdin.write(row)
            proc.stdin.flush()
            ready, _, _ = select.select([proc.stdout], [], [], 120)
            assert ready, "no answer within 120 s"
            answers.append(json.loads(proc.stdout.readline()))
        proc.stdin.close()
        rest = proc.stdout.read().decode().splitlines()
        assert proc.wait(timeout=120) == 1  # the third row was out of order
    finally:
        if proc.poll() is None:
            proc.kill()
    assert [a["id"] for a in answers[:2]] == ["1", "2"] and answers[0]["angle_rad"] == 0.5
    assert answers[2]["exit_code"] == 1 and "earlier than row 2" in answers[2]["reason"]
    assert json.loads(rest[-1])["parts"] == 2


def test_a_sweep_writes_its_table_and_figure(line_file, tmp_path):
    pytest.importorskip("matplotlib")
    out, fig = tmp_path / "sweep.csv", tmp_path / "sweep.png"
    r = run("line", line_file, "--speeds", "0.3,0.5", "--strategies", "upstream_first,skip", "--seeds", "1,2",
            "-j", "1", "-o", out, "--plot", fig, "-q")
    assert r.exit_code == 0, r.stderr
    rows = list(csv.DictReader(out.open()))
    assert len(rows) == 8 and {x["strategy"] for x in rows} == {"upstream_first", "skip"}
    assert all(int(x["parts"]) == 12 for x in rows)
    assert fig.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not (tmp_path / "sweep.csv.partial.jsonl").exists()


def test_help_lists_the_command():
    r = run("line", "--help")
    assert r.exit_code == 0 and "--detections" in r.stdout and "--speeds" in r.stdout


def test_max_miss_rate_and_a_robot_that_can_never_take_a_part(line_file):
    """Parts detected past the first robot's window: a warning names it, and every part goes to r2; a miss-rate
    bound below the run's is exit 4 with one line."""
    line_file.write_text(LINE.replace("seed: 2}", "seed: 2, detect_at: 0.9}"))
    r = run("line", line_file, "--json", "-q", "--max-miss-rate", "0")
    warn = [x for x in r.stderr.splitlines() if x.startswith("pickplace: warning:")]
    assert len(warn) == 1 and "robot r1: its last meeting point along 0.75 m is upstream of where the parts are" in warn[0]
    docs = [json.loads(x) for x in r.stdout.splitlines()]
    assert {d["robot"] for d in docs[:-1] if d["picked"]} == {"r2"}
    if docs[-1]["missed"]:
        assert r.exit_code == 4 and "exceeds --max-miss-rate 0 %" in r.stderr
    else:
        assert r.exit_code == 0


def test_mcap_has_every_robots_topics(line_file, tmp_path):
    from mcap.reader import make_reader

    out = tmp_path / "run.mcap"
    r = run("line", line_file, "--mcap", out, "--rate", "100", "-q", "-o", tmp_path / "p.csv")
    assert r.exit_code == 0, r.stderr
    summary = make_reader(out.open("rb")).get_summary()
    topics = sorted(c.topic for c in summary.channels.values())
    assert topics == ["/r1/joint_states", "/r1/motor_states", "/r1/tool_pose",
                      "/r2/joint_states", "/r2/motor_states", "/r2/tool_pose"]
    counts = {summary.channels[k].topic: v for k, v in summary.statistics.channel_message_counts.items()}
    assert len(set(counts.values())) == 1  # one clock for every robot and topic
    # the joints are named as the profile's controller.joints names its drives, as plan's MCAP names them
    from mcap_ros2.decoder import DecoderFactory

    from pickplace_cli.model.profile import load_profile

    drives = [j.name for j in load_profile("delta-su2018").controller.joints]
    reader = make_reader(out.open("rb"), decoder_factories=[DecoderFactory()])
    _, channel, _, msg = next(reader.iter_decoded_messages(topics=["/r1/joint_states"]))
    assert list(msg.name) == drives == ["A1", "A2", "A3"]


@pytest.mark.parametrize("given", ["all", "quota,bands", " quota , skip"])
def test_several_strategies_outside_a_sweep_are_a_usage_error(line_file, tmp_path, given):
    """``--strategy`` names the one strategy of a run; several (or ``all``) are a sweep's ``--strategies``: a usage
    error (exit 2), never the first of them run in silence; nothing is written."""
    out = tmp_path / "parts.csv"
    r = run("line", line_file, "--strategy", given, "-q", "-o", out)
    _one_line(r, 2, "--strategies")
    assert not out.exists()


def test_an_unknown_strategy_names_the_choices(line_file):
    r = run("line", line_file, "--strategy", "nope", "-q", "-o", "-")
    text = _one_line(r, 1, "--strategy 'nope'")
    assert "upstream_first" in text and "(or all)" not in text
