"""`pickplace plan --batch`: files as spreadsheets save them (BOM, ';' or tab), a header without moves,
the limit lines of a row, and what --fail-fast leaves in the output files. (The main batch behaviour —
row numbers, worst exit code, --json, -j — is in test_cli_pipeline.py.)"""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from pickplace_cli.cli import app

runner = CliRunner()

MOVES = (
    "from_x,from_y,from_z,to_x,to_y,to_z,height,time\n"
    "-0.1525,0,-0.8,0.1525,0,-0.8,,\n"
    "0.1,0.1,-0.8,-0.1,-0.1,-0.8,0.03,0.2\n"
)


def run(*args, input=None):
    return runner.invoke(app, list(args), input=input, catch_exceptions=False)


def planned(tmp_path, name: str, data: bytes) -> tuple[int, bytes, str]:
    src = tmp_path / name
    src.write_bytes(data)
    out = tmp_path / (name + ".out.csv")
    r = run("plan", "--batch", str(src), "-o", str(out), "-q")
    return r.exit_code, out.read_bytes() if out.exists() else b"", r.stderr


def test_excel_utf8_bom_file_plans_like_the_plain_file(tmp_path):
    code0, plain, _ = planned(tmp_path, "plain.csv", MOVES.encode())
    code, got, err = planned(tmp_path, "excel.csv", b"\xef\xbb\xbf" + MOVES.replace("\n", "\r\n").encode())
    assert code0 == 0 and code == 0, err
    assert got == plain and plain.count(b"\n") > 100


@pytest.mark.parametrize("sep", [";", "\t"])
def test_semicolon_and_tab_batches_plan_like_commas(tmp_path, sep):
    _, plain, _ = planned(tmp_path, "plain.csv", MOVES.encode())
    code, got, err = planned(tmp_path, "sep.csv", MOVES.replace(",", sep).encode())
    assert code == 0, err
    assert got == plain
    # and from stdin
    r = run("plan", "--batch", "-", "--json", "-q", input=MOVES.replace(",", sep))
    assert r.exit_code == 0 and [json.loads(ln)["row"] for ln in r.stdout.splitlines()] == [1, 2]


@pytest.mark.parametrize("extra", [[], ["--json"], ["--fail-fast"]])
def test_header_only_batch_is_one_line_exit_1_and_writes_nothing(tmp_path, extra):
    src = tmp_path / "moves.csv"
    src.write_text("from_x,from_y,from_z,to_x,to_y,to_z\n# nothing yet\n")
    out = tmp_path / "out.csv"
    r = run("plan", "--batch", str(src), "-o", str(out), *extra)
    assert r.exit_code == 1  # README "Exit codes": 1 = invalid input
    assert r.stderr.splitlines() == [
        f"pickplace: error: {src}:1: no moves after the header (need one row per move with from_x, from_y, "
        "from_z, to_x, to_y, to_z)"
    ]
    assert not out.exists()
    if "--json" in extra:  # the error that ends the batch is also the JSON document on stdout
        assert json.loads(r.stdout) == {"exit_code": 1, "error": r.stderr.splitlines()[0].removeprefix("pickplace: error: ")}
    else:
        assert r.stdout == ""


def test_limit_lines_of_a_row_are_the_single_plans_lines_with_row_and_line(tmp_path):
    """Every exceeded limit of a row gets its own stderr line, word for word the single plan's line
    (excess and utilisation included) after 'row N (FILE:LINE): ', so `grep 'row 2 '` finds them all."""
    src = tmp_path / "moves.csv"
    src.write_text("from_x,from_y,from_z,to_x,to_y,to_z,time\n"
                   "-0.1525,0,-0.8,0.1525,0,-0.8,\n"
                   "0.1,0.1,-0.8,-0.1,-0.1,-0.8,0.1\n")
    single = run("plan", "--from", "0.1,0.1,-0.8", "--to", "-0.1,-0.1,-0.8", "-t", "0.1", "-o", str(tmp_path / "s.csv"))
    batch = run("plan", "--batch", str(src), "-o", str(tmp_path / "b.csv"))
    assert single.exit_code == batch.exit_code == 3
    want = [ln for ln in single.stderr.splitlines() if ln.startswith("pickplace: limit exceeded: ")]
    got = [ln for ln in batch.stderr.splitlines() if ln.startswith("pickplace: row ")]
    assert len(want) >= 2 and all("(by " in ln for ln in want)
    assert got == [ln.replace("pickplace: ", f"pickplace: row 2 ({src}:3): ", 1) for ln in want]


def test_fail_fast_writes_the_rows_before_the_first_failure(tmp_path):
    """What README says about --fail-fast and files: the rows planned before the first failing row are
    written to -o (replacing the file), later rows are not planned; --report also holds the failing row
    when it was planned (a limit row); the exit code is the failing row's."""
    src = tmp_path / "moves.csv"
    src.write_text("from_x,from_y,from_z,to_x,to_y,to_z,time\n"
                   "-0.1525,0,-0.8,0.1525,0,-0.8,\n"
                   "0.1,0.1,-0.8,-0.1,-0.1,-0.8,0.1\n"
                   "-0.1525,0,-0.8,0.1525,0,-0.8,0.2\n")
    out, rep = tmp_path / "out.csv", tmp_path / "rep.json"
    out.write_text("old\n")
    r = run("plan", "--batch", str(src), "--fail-fast", "-o", str(out), "--report", str(rep))
    assert r.exit_code == 3
    assert "batch: 2 rows, 1 ok, 1 failed (first failing row 2); 1 written" in r.stderr
    assert "row 3" not in r.stderr
    moves = {ln.split(",")[0] for ln in out.read_text().splitlines()[1:]}
    assert moves == {"1"}
    assert [m["row"] for m in json.loads(rep.read_text())["moves"]] == [1, 2]
    # a first row that fails: nothing to write, the old file stays
    src.write_text("from_x,from_y,from_z,to_x,to_y,to_z,time\n0.1,0.1,-0.8,-0.1,-0.1,-0.8,0.1\n"
                   "-0.1525,0,-0.8,0.1525,0,-0.8,\n")
    out.write_text("old\n")
    r = run("plan", "--batch", str(src), "--fail-fast", "-o", str(out))
    assert r.exit_code == 3 and out.read_text() == "old\n"
