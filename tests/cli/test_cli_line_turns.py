"""`pickplace line`: the turn's fields, the intervals, --until and the tray exchange: outputs and one-line refusals."""

from __future__ import annotations

import csv
import json

import pytest

from .test_cli_line import _one_line, run

LINE = """\
belt: {speed: 0.3, width: 0.2, direction: +y}
robots:
  - name: d4
    profile: delta-4axis
    base: [0.6, 0.0, 0.8]
    window: [0.4, 0.8]
    place: {tray: {origin: [0.55, 0.35, 0.0], rows: 2, columns: 2, pitch: [0.05, 0.05]}, angle: 0.5}
  - name: d3
    base: [1.4, 0.0, 0.8]
    window: [1.2, 1.6]
    place: {points: [[1.4, 0.35, 0.0]], angle: 0.5}
parts:
  generate: {rate: 2.0, count: 30, seed: 1, angles: true}
  height: 0.01
"""


@pytest.fixture
def line_file(tmp_path):
    p = tmp_path / "line.yaml"
    p.write_text(LINE)
    return p


def test_turns_in_the_parts_csv_and_the_reason_of_a_robot_without_the_axis(line_file, tmp_path):
    out = tmp_path / "parts.csv"
    r = run("line", line_file, "-o", out)
    assert r.exit_code == 0, r.stderr
    rows = list(csv.DictReader(out.open()))
    d4 = [x for x in rows if x["robot"] == "d4"]
    assert d4 and all(x["turn[rad]"] for x in d4)
    assert not any(x["robot"] == "d3" for x in rows)  # no part lies exactly at 0.5 rad: d3 can take none
    missed = [x for x in rows if x["picked"] == "0"]
    assert missed and all("d3: the part lies at" in x["reason"] and "no rotary fourth axis" in x["reason"]
                          for x in missed)
    assert "miss rate" in r.stderr  # the interval line (Wilson only: 30 parts are too few for batch means)


@pytest.mark.parametrize("old,new,text", [
    ("angle: 0.5}\n  - name: d3", "angle: [0.5, 1.0]}\n  - name: d3",
     "angle has 2 values for 4 place targets: give one angle [rad] for all, or one per target"),
    ("angle: 0.5}\n  - name: d3", "angle: true}\n  - name: d3", "must be a number, not a flag"),
    ("angle: 0.5}\n  - name: d3", "angle: 180}\n  - name: d3", "angle = 180 rad: must lie within ±100 rad"),
    ("[[1.4, 0.35, 0.0]], angle: 0.5}", "[[1.4, 0.35, 0.0]], angle: 0.5, angle_tolerance: 4}",
     "angle_tolerance = 4: Input should be less than or equal to 3.14159"),
    ("[[1.4, 0.35, 0.0]], angle: 0.5}", "[[1.4, 0.35, 0.0]], angle: 0.5, angle_tolerance: -0.1}",
     "angle_tolerance = -0.1: Input should be greater than or equal to 0"),
    ("[[1.4, 0.35, 0.0]], angle: 0.5}", "[[1.4, 0.35, 0.0]], exchange: {time: 0}}",
     "exchange.time = 0: Input should be greater than 0"),
    ("[[1.4, 0.35, 0.0]], angle: 0.5}", "[[1.4, 0.35, 0.0]], exchange: {time: 2, every: 0}}",
     "exchange.every = 0: Input should be greater than or equal to 1"),
    ("[[1.4, 0.35, 0.0]], angle: 0.5}", "[[1.4, 0.35, 0.0]], exchange: {every: 3}}", "exchange.time: required field"),
    ("points: [[1.4, 0.35, 0.0]], angle: 0.5}", "belt: {point: [1.4, 0.35, 0.0], velocity: [0.2, 0]}, "
     "exchange: {time: 2}}", "exchange: an outgoing belt is not exchanged"),
])
def test_bad_turn_fields_are_one_line(line_file, old, new, text):
    assert old in LINE
    line_file.write_text(LINE.replace(old, new))
    _one_line(run("line", line_file, "-q", "-o", "/dev/null"), 1, text)


@pytest.mark.parametrize("args,code,text", [
    (("--until", "0"), 1, "--until 0.0: the half-width of the miss rate's interval is a share from 0.001 to 0.5"),
    (("--until", "0.7"), 1, "--until 0.7"),
    (("--until", "0.05", "--until-max", "0.5"), 1, "--until-max 0.5 s: the longest run is from 1 to 1e5 s"),
    (("--until", "0.05", "--seeds", "1,2"), 2, "--until runs the line file's generator longer"),
])
def test_bad_until_is_one_line(line_file, args, code, text):
    r = run("line", line_file, "-q", "-o", "/dev/null", *args)
    assert r.exit_code == code, r.stderr
    assert text in r.stderr


def test_until_needs_a_generator(line_file, tmp_path):
    (tmp_path / "det.csv").write_text("t[s],along[m],across[m]\n0,0,0\n0.5,0,0.01\n")
    line_file.write_text(LINE.replace("  generate: {rate: 2.0, count: 30, seed: 1, angles: true}\n",
                                      "  detections: det.csv\n"))
    r = run("line", line_file, "-q", "-o", "/dev/null", "--until", "0.05")
    assert r.exit_code == 2, r.stderr
    assert "parts come from a detection file (parts.detections): give parts.generate" in r.stderr


def test_until_runs_until_the_interval_is_that_narrow(line_file, tmp_path):
    """A tolerance of ± 5 points is reached well inside --until-max, and the summary's batch-means interval says so;
    a 20 s cap that cannot reach ± 0.1 % stops there with a warning (exit 0: the interval is a result)."""
    summ = tmp_path / "s.json"
    r = run("line", line_file, "-q", "-o", "/dev/null", "--until", "0.05", "--summary", summ)
    assert r.exit_code == 0, r.stderr
    doc = json.loads(summ.read_text())
    assert doc["until"] == {"precision": 0.05, "reached": True, "max_s": 3600.0}
    iv = doc["intervals"]["miss_rate"]
    assert iv["method"] == "batch means" and iv["half_width"] <= 0.05 and doc["parts"] >= 400
    assert iv["low"] <= doc["miss_rate"] <= iv["high"]
    r = run("line", line_file, "-q", "-o", "/dev/null", "--until", "0.001", "--until-max", "20", "--summary", summ)
    assert r.exit_code == 0, r.stderr
    assert "--until 0.001: the miss rate's interval is" in r.stderr and "not as narrow as asked" in r.stderr
    doc = json.loads(summ.read_text())
    assert doc["until"]["reached"] is False and doc["feed_s"] <= 20.0
