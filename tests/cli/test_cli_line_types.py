"""`pickplace line` with part types: the type in every output, detections with a type column, and each refusal one
line with its exit code."""

from __future__ import annotations

import csv
import json

import pytest

from tests.cli.test_cli_line import _one_line, run

TYPED = """\
name: two products
belt: {speed: 0.5, width: 0.3}
robots:
  - name: r1
    base: [0.6, 0.0, 0.8]
    window: [0.4, 0.8]
    places:
      A: {points: [[0.6, 0.35, 0.0]]}
  - name: r2
    base: [1.4, 0.0, 0.8]
    window: [1.2, 1.6]
    places:
      A: {points: [[1.4, 0.35, 0.0]]}
      B: {points: [[1.4, -0.35, 0.0]]}
parts:
  generate: {rate: 4.0, count: 12, seed: 2}
  types: {A: {share: 0.5}, B: {share: 0.5}}
  latency: 0.05
"""
DETECTIONS = "t[s],along[m],across[m],type\n0.0,0,0,A\n0.5,0,0.05,B\n1.0,0,0,C\n1.5,0,0,A\n"


@pytest.fixture
def typed(tmp_path):
    p = tmp_path / "line.yaml"
    p.write_text(TYPED)
    return p


def test_the_type_is_in_every_output(typed, tmp_path):
    out, summ = tmp_path / "parts.csv", tmp_path / "s.json"
    r = run("line", typed, "-o", out, "--summary", summ, "--robots-csv", tmp_path / "robots.csv")
    assert r.exit_code == 0, r.stderr
    rob = list(csv.DictReader((tmp_path / "robots.csv").open()))
    assert rob[0]["picks_B"] == "0" and int(rob[0]["picks_A"]) == int(rob[0]["picks"])
    assert int(rob[1]["picks_A"]) + int(rob[1]["picks_B"]) == int(rob[1]["picks"])
    rows = list(csv.DictReader(out.open()))
    assert list(rows[0])[6] == "type" and {x["type"] for x in rows} == {"A", "B"}
    assert all(x["robot"] == "r2" for x in rows if x["type"] == "B" and x["picked"] == "1")
    doc = json.loads(summ.read_text())
    assert set(doc["types"]) == {"A", "B"}
    assert sum(t["parts"] for t in doc["types"].values()) == doc["parts"] == 12
    assert "type A: " in r.stderr and "type B: " in r.stderr  # the table's per-type lines
    js = run("line", typed, "--json", "-q")
    docs = [json.loads(x) for x in js.stdout.splitlines()]
    assert [d["type"] for d in docs[:-1]] == [x["type"] for x in rows]


def test_a_line_without_types_has_no_type_column(typed, tmp_path):
    from tests.cli.test_cli_line import LINE

    p = tmp_path / "plain.yaml"
    p.write_text(LINE)
    r = run("line", p, "-q", "--summary", tmp_path / "s.json")
    assert r.exit_code == 0 and "type" not in r.stdout.splitlines()[0].split(",")
    assert "types" not in json.loads((tmp_path / "s.json").read_text())


def test_detections_with_an_unknown_type_are_refused_row_by_row(typed, tmp_path):
    det = tmp_path / "d.csv"
    det.write_text(DETECTIONS)
    r = run("line", typed, "--detections", det, "-q")
    assert r.exit_code == 1
    bad = [x for x in r.stderr.splitlines() if x.startswith("pickplace:")]
    assert len(bad) == 1 and "row 3" in bad[0] and "type = 'C'" in bad[0] and "parts.types: A, B" in bad[0], r.stderr
    rows = list(csv.DictReader(r.stdout.splitlines()))
    assert [x["type"] for x in rows if x["exit_code"] != "1"] == ["A", "B", "A"]  # the other rows are answered


@pytest.mark.parametrize("header, text", [
    ("t[s],along[m],across[m]", "missing column 'type'"),
])
def test_a_detection_file_without_the_type_column_is_one_line(typed, tmp_path, header, text):
    det = tmp_path / "d.csv"
    det.write_text(header + "\n0.0,0,0\n")
    _one_line(run("line", typed, "--detections", det, "-q"), 1, text)


def test_a_type_column_on_a_line_without_types_is_one_line(tmp_path):
    from tests.cli.test_cli_line import LINE

    p = tmp_path / "plain.yaml"
    p.write_text(LINE)
    det = tmp_path / "d.csv"
    det.write_text("t[s],along[m],across[m],type\n0.0,0,0,A\n")
    _one_line(run("line", p, "--detections", det, "-q"), 1, "column 'type': the line file declares no part types")


@pytest.mark.parametrize("edit, text", [
    (("A: {share: 0.5}, B: {share: 0.5}", "A: {share: 0.5}, B: {share: 0.4999999}"),
     "parts.types: the shares A 0.5, B 0.4999999 add up to 0.9999999: they must add up to 1 (within 1e-09)"),
    (("      B: {points: [[1.4, -0.35, 0.0]]}", "      C: {points: [[1.4, -0.35, 0.0]]}"),
     "robot r2: places.C: not a part type of parts.types (A, B)"),
    (("  types: {A: {share: 0.5}, B: {share: 0.5}}\n", ""),
     "robot r1: places = ['A']: places per part type need the types declared in parts.types"),
    (("    places:\n      A: {points: [[0.6, 0.35, 0.0]]}", "    place: {points: [[0.6, 0.35, 0.0]]}\n    places:\n"
      "      A: {points: [[0.6, 0.35, 0.0]]}"), "give one of place (every part type) or places"),
    (("A: {share: 0.5}, B: {share: 0.5}", "A: {share: 0.5}, B: {share: 0.5, mass: 0.2}"), "unknown key 'parts.types.B.mass'"),
    (("A: {share: 0.5}, B:", "A: {share: 0.5}, 2B:"), "parts.types: name '2B': a type's name is a letter"),
])
def test_bad_types_are_one_line_exit_1(typed, edit, text):
    typed.write_text(TYPED.replace(*edit))
    _one_line(run("line", typed, "-q"), 1, text)


def test_a_type_no_robot_takes_is_a_warning_and_its_parts_are_missed(typed):
    typed.write_text(TYPED.replace("      B: {points: [[1.4, -0.35, 0.0]]}\n", ""))
    r = run("line", typed, "--json")
    assert r.exit_code == 0, r.stderr
    warn = [x for x in r.stderr.splitlines() if x.startswith("pickplace: warning:")]
    assert warn == ["pickplace: warning: parts.types.B: no robot has a place for type B: every part of it is missed"]
    docs = [json.loads(x) for x in r.stdout.splitlines()][:-1]
    b = [d for d in docs if d["type"] == "B"]
    assert b and not any(d["picked"] for d in b)
    assert all(d["reason"] == "missed: r1: takes no parts of type B (no place for them); r2: takes no parts of type B "
               "(no place for them)" for d in b)


def test_a_sweep_and_until_give_the_generated_parts_their_types(typed, tmp_path):
    """The sweep's cases and --until's longer run draw the types too: parts of type B are picked (by r2 only)."""
    out = tmp_path / "sweep.csv"
    r = run("line", typed, "--seeds", "1,2", "-j", "1", "-q", "-o", out)
    assert r.exit_code == 0, r.stderr
    rows = list(csv.DictReader(out.open()))
    assert len(rows) == 2 and all(int(x["picked"]) > 0 for x in rows)
    summ = tmp_path / "s.json"
    r = run("line", typed, "--until", "0.5", "--until-max", "5", "-q", "-o", tmp_path / "p.csv", "--summary", summ)
    assert r.exit_code == 0, r.stderr
    doc = json.loads(summ.read_text())
    assert doc["types"]["B"]["picked"] > 0 and doc["robots"][0]["picks_by_type"]["B"] == 0


def test_the_figure_of_a_typed_line(typed, tmp_path, monkeypatch):
    """--plot on a line with types: a PNG, and its figure (caught as it is saved) has a legend entry per type whose
    marker count is that type's picks."""
    pytest.importorskip("matplotlib")
    from matplotlib.figure import Figure

    seen = []
    save = Figure.savefig
    monkeypatch.setattr(Figure, "savefig", lambda self, *a, **k: (seen.append(self), save(self, *a, **k))[1])
    png = tmp_path / "line.png"
    r = run("line", typed, "-q", "-o", tmp_path / "p.csv", "--plot", png)
    assert r.exit_code == 0, r.stderr
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    ax = seen[0].axes[0]
    assert [t.get_text() for t in ax.get_legend().get_texts()] == ["type A", "type B"]
    rows = list(csv.DictReader((tmp_path / "p.csv").open()))
    counts = {c.get_label(): len(c.get_offsets()) for c in ax.collections if c.get_label().startswith("type")}
    assert counts == {f"type {k}": sum(x["type"] == k and x["picked"] == "1" for x in rows) for k in "AB"}
