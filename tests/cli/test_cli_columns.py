"""`pickplace plan --columns`: a PLC feed of the columns it reads, the same numbers as the full CSV."""

from __future__ import annotations

import subprocess
import sys

import pytest
from typer.testing import CliRunner

from pickplace_cli.cli import app

runner = CliRunner()
MOVE = ("--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8")
BATCH = "from_x,from_y,from_z,to_x,to_y,to_z\n-0.1525,0,-0.8,0.1525,0,-0.8\n0.1,0.05,-0.85,-0.12,0,-0.8\n"


def run(*args, input=None):
    return runner.invoke(app, list(args), input=input, catch_exceptions=False)


def _table(text: str, sep: str = ",") -> tuple[list[str], list[list[str]]]:
    lines = text.splitlines()
    return lines[0].split(sep), [ln.split(sep) for ln in lines[1:]]


def _pick(full: str, names: list[str], sep: str = ",") -> list[list[str]]:
    head, rows = _table(full, sep)
    idx = [head.index(n) for n in names]
    return [[r[i] for i in idx] for r in rows]


def test_selected_columns_are_the_full_csvs_columns_in_the_order_given():
    full = run("plan", *MOVE, "-q")
    got = run("plan", *MOVE, "-q", "--columns", "q3, t,qd?")
    assert full.exit_code == got.exit_code == 0
    head, rows = _table(got.stdout)
    assert head == ["q3[rad]", "t[s]", "qd1[rad/s]", "qd2[rad/s]", "qd3[rad/s]"]
    assert rows == _pick(full.stdout, head) and len(rows) > 100


def test_globs_expand_in_the_headers_order():
    got = run("plan", *MOVE, "-q", "--columns", "motor_*")
    head, _ = _table(got.stdout)
    assert head == [f"{q}{k}[N*m]" if q == "motor_torque" else f"{q}{k}[rad/s]"
                    for k in (1, 2, 3) for q in ("motor_speed", "motor_torque")]


@pytest.mark.parametrize("workers", ["1", "2"])
def test_batch_keeps_its_move_column_first_streamed_or_from_a_file(tmp_path, workers):
    src = tmp_path / "b.csv"
    src.write_text(BATCH)
    full = run("plan", "--batch", str(src), "-q")
    from_file = run("plan", "--batch", str(src), "-q", "-j", workers, "--columns", "t,q?")
    streamed = run("plan", "--batch", "-", "-q", "-j", workers, "--columns", "t,q?", input=BATCH)
    head, rows = _table(from_file.stdout)
    assert head == ["move[-]", "t[s]", "q1[rad]", "q2[rad]", "q3[rad]"]
    assert rows == _pick(full.stdout, head)
    assert streamed.stdout == from_file.stdout
    assert {r[0] for r in rows} == {"1", "2"}


def test_tsv_and_twincat_dialects(tmp_path):
    tsv = run("plan", *MOVE, "-q", "--columns", "t,q1", "--csv-dialect", "tsv")
    assert tsv.exit_code == 0 and tsv.stdout.splitlines()[0] == "0\t0.619590432309"
    out = tmp_path / "tc.csv"
    tc = run("plan", *MOVE, "-q", "--columns", "t,q1", "--csv-dialect", "twincat", "-o", str(out))
    assert tc.exit_code == 0 and out.read_bytes().startswith(b"t[s];q1[rad]\r\n0;0.619590432309\r\n0.001;")


@pytest.mark.parametrize("value, says", [
    ("t,q4", "'q4': no such column"),
    ("t,q1,q?", "q1 is selected twice"),
    (" , ", "give at least one column name"),
    ("T", "'T': no such column"),  # names are case-sensitive, like the header
    ("t,,q1", "name 2 of 3 is empty"),  # a typo is not silently dropped
    ("t,", "name 2 of 2 is empty"),
    ("q1[deg]", "the header writes q1[rad]"),  # the right name with another unit
    ("torque1[N·m]", "the header writes torque1[N*m]"),
])
def test_bad_columns_are_a_usage_error_naming_the_value(value, says):
    r = subprocess.run([sys.executable, "-m", "pickplace_cli", "plan", *MOVE, "--columns", value],
                       capture_output=True, text=True)
    assert r.returncode == 2
    assert says in r.stderr and "--columns" in r.stderr and "Traceback" not in r.stderr
    assert r.stdout == ""


def test_columns_with_another_format_is_refused(tmp_path):
    r = run("plan", *MOVE, "--columns", "t", "-f", "mcap", "-o", str(tmp_path / "x.mcap"))
    assert r.exit_code == 2 and "--columns only applies to --format csv" in r.stderr
    assert not (tmp_path / "x.mcap").exists()


def test_columns_without_a_trajectory_output_is_refused():
    r = run("plan", *MOVE, "--json", "-q", "--columns", "t,q1")
    assert r.exit_code == 2 and "--columns: with --json and no -o FILE" in r.stderr


def test_header_names_with_units_and_the_move_column():
    got = run("plan", *MOVE, "-q", "--columns", "q1[rad],t")
    assert got.exit_code == 0 and got.stdout.splitlines()[0] == "q1[rad],t[s]"
    r = run("plan", *MOVE, "-q", "--columns", "move,t")
    assert r.exit_code == 2 and "move column is always written" in r.stderr
