"""``plan --optimize shape --time optimal --shape-law-evals N`` (a search of seconds) under the tool's process
guarantees: Ctrl-C (SIGINT to the whole group) and SIGTERM during the search are one line with exit 130 / 143,
an existing ``-o`` file left as it was and no temporary file; on a terminal its notes are styled, and with
NO_COLOR set they carry no escape sequence. Real subprocesses: signals and terminals are the point."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest

from tests.procs import group, kill_group, wait_started
from tests.terminal import stderr_on_terminal

ADEPT = ["--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8"]
SEARCH = ["--optimize", "shape", "--time", "optimal"]


def _cli(*args: str) -> list[str]:
    return [sys.executable, "-m", "pickplace_cli", *args]


@pytest.mark.skipif(not os.path.isdir("/proc"), reason="reads the process table from /proc")
@pytest.mark.parametrize("sig, code, line", [
    (signal.SIGINT, 130, "pickplace: error: interrupted; no output file was changed"),
    (signal.SIGTERM, 143, "pickplace: error: terminated (SIGTERM); no output file was changed")])
def test_a_signal_during_the_law_search_is_one_line(tmp_path, sig, code, line):
    """200 law evaluations take tens of seconds: the signal comes 1.5 s after the program starts, during the
    search. Exit ``code`` within 20 s, ``line`` all of stderr, the old ``-o`` file as it was, no temporary file
    and no process of the group left."""
    out = tmp_path / "move.csv"
    out.write_text("the previous good file\n")
    proc = subprocess.Popen(_cli("plan", *ADEPT, *SEARCH, "--shape-law-evals", "200", "-o", str(out)),
                            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            cwd=tmp_path, start_new_session=True)
    try:
        wait_started(proc)
        time.sleep(1.5)
        assert proc.poll() is None
        os.killpg(proc.pid, sig)
        assert proc.wait(20) == code
        assert proc.stderr.read().strip() == line
        assert out.read_text() == "the previous good file\n"
        assert not list(tmp_path.glob(".move.csv.*"))
        deadline = time.monotonic() + 10
        while group(proc.pid):
            assert time.monotonic() < deadline, f"processes {group(proc.pid)} of the group outlived it"
            time.sleep(0.05)
    finally:
        kill_group(proc)


@pytest.mark.parametrize("no_color", [None, "1"])
def test_no_color_on_a_terminal(no_color):
    """The search's plan on a terminal: its limit table is styled; with NO_COLOR set there is no escape sequence
    (two law evaluations keep it short)."""
    out = stderr_on_terminal(_cli("plan", *ADEPT, *SEARCH, "--shape-law-evals", "2", "-o", os.devnull), no_color,
                             120.0)
    assert b"optimal" in out
    assert (b"\x1b[" in out) is (no_color is None)
