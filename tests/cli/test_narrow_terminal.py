"""The limit table on a terminal 80 columns wide (a real pseudo-terminal of that window size): no line is wider than
the terminal and every row keeps its quantity and unit on one line (only the verdict column may wrap); a wide
terminal keeps the full layout (the "t peak [s]" header, the target column). Piped output is not affected."""

from __future__ import annotations

import os
import re
import sys

import pytest
from rich.cells import cell_len

from tests.terminal import stderr_on_terminal

ANSI = re.compile(r"\x1b\[[0-9;?]*[A-Za-z]")
ROW = re.compile(r"^(q\d|tool)\s")


def _cli(*args: str) -> list[str]:
    return [sys.executable, "-m", "pickplace_cli", *args]


def _lines(out: bytes) -> list[str]:
    return [ANSI.sub("", ln) for ln in out.decode("utf-8").replace("\r", "").splitlines()]


def _table(lines: list[str]) -> list[str]:
    first = next(i for i, ln in enumerate(lines) if ln.startswith("joint "))
    last = max(i for i, ln in enumerate(lines) if ROW.match(ln))
    while last + 1 < len(lines) and lines[last + 1].startswith(" "):  # the last row's wrapped verdict
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


@pytest.mark.parametrize("what", ["check", "plan-not-held"])
def test_80_columns_rows_on_one_line(what, unresolved_file):
    if what == "check":
        cmd = _cli("check", str(unresolved_file), "-p", "scara-600")
    else:  # the target % column and long "ok (not held: --time fit)" verdicts
        cmd = _cli("plan", "-p", "delta-4axis", "--from", "-0.1,0.1,-0.8,0", "--to", "0.15,-0.05,-0.85,1.5",
                   "--time", "fit", "--limit-use", "0.9", "-o", os.devnull)
    table = _table(_lines(stderr_on_terminal(cmd, None, 120.0, columns=80)))
    assert table[0].split()[-2:] == ["t", "[s]"], table[0]
    assert all(cell_len(ln) <= 80 for ln in table), max(table, key=cell_len)
    rows = [ln for ln in table if ROW.match(ln)]
    assert len(rows) >= 15
    assert all(re.search(r"\[[^\]]+\]\s", ln) for ln in rows), [ln for ln in rows if "]" not in ln]
    wrapped = [ln for ln in table[1:] if not ROW.match(ln) and ln.strip()]  # continuation lines: the verdict only
    assert all(ln.startswith(" " * 60) for ln in wrapped), wrapped
    if what == "check":
        assert any(ln.rstrip().endswith("unresolved") for ln in rows)
    else:  # every target is 90 %, which the duration line says: no target column; the verdict names no rule
        assert "target" not in table[0] and any(ln.rstrip().endswith("ok (not held)") for ln in rows)


def test_a_wide_terminal_keeps_the_full_layout(unresolved_file):
    table = _table(_lines(stderr_on_terminal(_cli("check", str(unresolved_file), "-p", "scara-600"), None, 120.0,
                                             columns=160)))
    assert table[0].split()[-3:] == ["t", "peak", "[s]"], table[0]
    assert all(ROW.match(ln) for ln in table[1:-1] if ln.strip())
