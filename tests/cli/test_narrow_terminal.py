"""The limit table on a narrow terminal (a real pseudo-terminal of that window size): no line is wider than the
terminal, every row keeps its verdict (ok, EXCEEDED, unresolved, "(not held)"), and at 80 columns every row keeps
its quantity and unit on one line: the narrow layout leaves out the time of the peak, then the target, then the
stated accuracy, before anything else gives; a wide terminal keeps the full layout. Piped output is not affected."""

from __future__ import annotations

import os
import re
import sys

import pytest
from rich.cells import cell_len

from tests.terminal import stderr_on_terminal

ANSI = re.compile(r"\x1b\[[0-9;?]*[A-Za-z]")
ROW = re.compile(r"^(q\d|tool)\s")
VERDICT = re.compile(r"(ok|EXCEEDED|unresolved|\(not held\))\s*$")


def _cli(*args: str) -> list[str]:
    return [sys.executable, "-m", "pickplace_cli", *args]


def _lines(out: bytes) -> list[str]:
    return [ANSI.sub("", ln) for ln in out.decode("utf-8").replace("\r", "").splitlines()]


def _table(lines: list[str]) -> list[str]:
    first = next(i for i, ln in enumerate(lines) if ln.startswith("joint "))
    last = max(i for i, ln in enumerate(lines) if ROW.match(ln))
    while last + 1 < len(lines) and lines[last + 1].startswith(" "):  # the last row's wrapped quantity
        last += 1
    return lines[first:last + 1]


@pytest.fixture(scope="module")
def unresolved_file(tmp_path_factory):
    """A SCARA file check reads with its widest table: the ± column and an "unresolved" verdict."""
    from typer.testing import CliRunner

    from pickplace_cli.cli import app

    path = tmp_path_factory.mktemp("narrow") / "scara.csv"
    r = CliRunner().invoke(app, ["plan", "-p", "scara-600", "--from", "0.3,-0.15,-0.1", "--to", "0.4,0.15,-0.1",
                                 "--time", "optimal", "--hold-capacity", "-q", "-o", str(path)])
    assert r.exit_code == 0, r.stderr
    return path


def _command(what: str, path) -> list[str]:
    if what == "check":
        return _cli("check", str(path), "-p", "scara-600")
    if what == "check-limit-use":  # the target column too, and rows exceeded at the limit use
        return _cli("check", str(path), "-p", "scara-600", "--limit-use", "0.9")
    # the target % column and long "ok (not held: --time fit)" verdicts
    return _cli("plan", "-p", "delta-4axis", "--from", "-0.1,0.1,-0.8,0", "--to", "0.15,-0.05,-0.85,1.5",
                "--time", "fit", "--limit-use", "0.9", "-o", os.devnull)


@pytest.mark.parametrize("what", ["check", "check-limit-use", "plan-not-held"])
@pytest.mark.parametrize("columns", [80, 60])
def test_narrow_rows_keep_their_verdict(what, columns, unresolved_file):
    table = _table(_lines(stderr_on_terminal(_command(what, unresolved_file), None, 120.0, columns=columns)))
    assert all(cell_len(ln) <= columns for ln in table), max(table, key=cell_len)
    rows = [ln for ln in table if ROW.match(ln)]
    assert len(rows) >= 15
    assert all(VERDICT.search(ln) for ln in rows), [ln for ln in rows if not VERDICT.search(ln)]
    if columns == 80:  # each row on one line, its unit with it
        assert all(re.search(r"\[[^\]]+\]\s", ln) for ln in rows) and len(rows) == len(table) - 1, table
    if what == "check":
        assert any(ln.rstrip().endswith("unresolved") for ln in rows)
    if what == "plan-not-held":
        assert any(ln.rstrip().endswith("EXCEEDED (not held)") for ln in rows)


def test_a_wide_terminal_keeps_the_full_layout(unresolved_file):
    table = _table(_lines(stderr_on_terminal(_command("check-limit-use", unresolved_file), None, 120.0, columns=160)))
    assert "target" in table[0] and "±" in table[0] and table[0].split()[-3:] == ["t", "peak", "[s]"], table[0]
    assert all(ROW.match(ln) for ln in table[1:])


def test_a_very_narrow_terminal_folds_the_quantity_never_cuts_it(unresolved_file):
    """At 40 columns the table cannot fit (the joint, the peak, the limit, the use and "unresolved" take 42): the
    quantity keeps 8 columns (rich left it none: rows without their quantity), its words wrap and a longer one
    folds onto the next line, and the terminal wraps the row. Nothing is cut to "…" or dropped: each row's quantity, read down its column, is the whole text of the piped
    table's, and every row has its verdict."""
    import subprocess

    lines = _lines(stderr_on_terminal(_command("check", unresolved_file), None, 120.0, columns=40))
    table = _table(lines)
    assert not any("…" in ln for ln in table), [ln for ln in table if "…" in ln]
    assert all(VERDICT.search(ln) for ln in table if ROW.match(ln))
    head = next(ln for ln in lines[lines.index(table[0]) - 1:] if "quanti" in ln)  # (the header may fold too)
    start = head.index("quanti")
    stop = start + len(head[start:].split(" ")[0])
    rows = [i for i, ln in enumerate(table) if ROW.match(ln)]
    got = ["".join(ln[start:stop] for ln in table[i:j]).replace(" ", "")
           for i, j in zip(rows, rows[1:] + [len(table)])]
    piped = subprocess.run(_command("check", unresolved_file), capture_output=True, text=True, timeout=120)
    want = [re.split(r"\s{2,}", ln)[1].replace(" ", "") for ln in piped.stderr.splitlines() if ROW.match(ln)]
    assert got == want and len(want) >= 15, list(zip(got, want))
