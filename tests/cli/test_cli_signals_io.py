"""The process's own edges (found by a new-user review, session 14): SIGTERM handled like Ctrl-C (exit 143, one
line, the temporary `-o` file removed, worker processes gone), a failing stdout (`> /dev/full`) as one line, and
`--json --report FILE` without `-o`. Real subprocesses: signals and file descriptors are the point."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import pytest

from tests.procs import alive, children, group, kill_group, wait_started

HEADER = "from_x,from_y,from_z,to_x,to_y,to_z\n"
ROW = "-0.1525,0,-0.8,0.1525,0,-0.8\n"
ADEPT = ["--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8"]
TIMEOUT = 60.0


def _cli(*args: str) -> list[str]:
    return [sys.executable, "-m", "pickplace_cli", *args]


_children, _group, _alive = children, group, alive


@pytest.mark.skipif(not os.path.isdir("/proc"), reason="reads the process table from /proc")
@pytest.mark.parametrize("workers", ["1", "2"])
def test_sigterm_stream_exits_143_cleanly(tmp_path, workers):
    """SIGTERM to a stream (`kill`, `timeout`, `docker stop`): one line, exit 143, the temporary -o file removed,
    an existing -o untouched, and no worker process left behind (they used to outlive the main process forever,
    holding stdout open, so the next stage of the pipeline never saw its end)."""
    out = tmp_path / "moves.csv"
    out.write_text("the previous good file\n")
    proc = subprocess.Popen(_cli("plan", "--batch", "-", "-q", "-j", workers, "-o", str(out)), stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path)
    try:
        proc.stdin.write(HEADER + ROW)
        proc.stdin.flush()
        deadline = time.monotonic() + TIMEOUT
        while not list(tmp_path.glob(".moves.csv.*.tmp")):  # the first row is planned and being written
            assert time.monotonic() < deadline and proc.poll() is None, proc.stderr.read()
            time.sleep(0.05)
        kids = _children(proc.pid)
        while len(kids) < (2 if workers == "2" else 0):  # the pool starts its workers after the -o file is opened
            assert time.monotonic() < deadline and proc.poll() is None, proc.stderr.read()
            time.sleep(0.05)
            kids = _children(proc.pid)
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(TIMEOUT) == 143
        err = proc.stderr.read()
        assert err.strip() == "pickplace: error: terminated (SIGTERM); no output file was changed"
        assert out.read_text() == "the previous good file\n"
        assert not list(tmp_path.glob(".moves.csv.*"))
        deadline = time.monotonic() + 10
        while any(_alive(k) for k in kids):
            assert time.monotonic() < deadline, f"worker processes {kids} outlived the main process"
            time.sleep(0.05)
    finally:
        proc.kill()
        proc.wait()


@pytest.mark.skipif(not os.path.isdir("/proc"), reason="reads the process table from /proc")
@pytest.mark.parametrize("streamed", [True, False])
def test_sigterm_to_the_whole_process_group_never_hangs(tmp_path, streamed):
    """SIGTERM to the whole group (`timeout`, `kill -- -PGID`, systemd), which also hits the -j 2 workers, three
    times at different points of a big batch at 1 kHz (large results in flight between the processes): every
    time exit 143 within 20 s, the one line, no temporary file, no process of the group left. (Unwinding with
    the workers dead could leave the pool's result pipe half-written and the pool's shutdown waiting forever.)"""
    rows = "".join(f"{-0.15 + 0.0001 * (i % 50)},0,-0.8,0.15,{0.0002 * (i % 30)},-0.79\n" for i in range(6000))
    src = tmp_path / "big.csv"
    src.write_text(HEADER + rows)
    for attempt, delay in enumerate((0.6, 1.2, 2.0)):
        out = tmp_path / f"o{attempt}.csv"
        args = ["plan", "--batch", "-" if streamed else str(src), "-q", "-j", "2", "--rate", "1000", "-o", str(out)]
        proc = _start_group(args, HEADER + rows if streamed else None, tmp_path, delay)
        _signal_the_group(proc, signal.SIGTERM, 143, "pickplace: error: terminated (SIGTERM); no output file was changed",
                          out)


def _start_group(args: list[str], stdin: str | None, cwd, delay: float) -> subprocess.Popen:
    """The CLI with ``args`` in a new process group, ``stdin`` written to it (and left open: still streaming when
    a signal comes; None: no stdin), after ``delay`` s."""
    proc = subprocess.Popen(_cli(*args), stdin=subprocess.PIPE if stdin is not None else subprocess.DEVNULL,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, cwd=cwd,
                            start_new_session=True)
    if stdin is not None:
        proc.stdin.write(stdin)
        proc.stdin.flush()
    wait_started(proc)
    time.sleep(delay)
    return proc


def _signal_the_group(proc, sig, code: int, line: str, out) -> None:
    """Send ``sig`` to the whole process group of ``proc`` (still running): exit ``code`` within 20 s, ``line`` all
    of stderr, neither ``out`` nor a temporary file of it, no process of the group left within 10 s. The group is
    killed in any case."""
    try:
        assert proc.poll() is None
        os.killpg(proc.pid, sig)
        assert proc.wait(20) == code
        err = proc.stderr.read()
        assert err.strip() == line, err
        assert not out.exists() and not list(out.parent.glob(f".{out.name}.*"))
        deadline = time.monotonic() + 10
        while _group(proc.pid):
            assert time.monotonic() < deadline, f"processes {_group(proc.pid)} of the group outlived it"
            time.sleep(0.05)
    finally:
        kill_group(proc)


@pytest.mark.skipif(not os.path.isdir("/proc"), reason="reads the process table from /proc")
@pytest.mark.parametrize("mode", ["streamed", "streamed-idle", "file", "verdicts"])
def test_ctrl_c_to_the_whole_process_group_is_one_line(tmp_path, mode):
    """Ctrl-C in a terminal sends SIGINT to the whole foreground group, the -j 2 workers too: exit 130 within 20 s,
    the one line, no temporary file, no process of the group left. (Workers waiting for work — a stream whose
    rows have all been answered — used to print a KeyboardInterrupt traceback each.)"""
    n = 200 if mode == "streamed-idle" else 6000
    rows = "".join(f"{-0.15 + 0.0001 * (i % 50)},0,-0.8,0.15,{0.0002 * (i % 30)},-0.79\n" for i in range(n))
    src = tmp_path / "big.csv"
    src.write_text(HEADER + rows)
    out = tmp_path / "o.csv"
    streamed = mode.startswith("streamed")
    args = ["plan", "--batch", "-" if streamed else str(src), "-q", "-j", "2"]
    args += ["--json"] if mode == "verdicts" else ["--rate", "1000", "-o", str(out)]
    proc = _start_group(args, HEADER + rows if streamed else None, tmp_path,
                        2.0 if mode == "streamed-idle" else 1.0 if mode != "verdicts" else 0.7)
    _signal_the_group(proc, signal.SIGINT, 130, "pickplace: error: interrupted; no output file was changed", out)


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full")
@pytest.mark.parametrize("args, stdin", [
    (["plan", *ADEPT, "-q"], None),
    (["plan", *ADEPT, "-q", "-f", "mcap"], None),
    (["plan", "--batch", "-", "-q"], HEADER + ROW),
    (["plan", "--batch", "-", "-q", "--json"], HEADER + ROW),
])
def test_a_full_stdout_is_one_line_exit_1(args, stdin):
    """`> /dev/full` (no space left on device): one line naming the output, exit 1, no traceback."""
    with open("/dev/full", "w") as full:
        r = subprocess.run(_cli(*args), input=stdin, stdout=full, stderr=subprocess.PIPE, text=True, timeout=TIMEOUT)
    assert r.returncode == 1
    assert "Traceback" not in r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("pickplace: error: ") and "No space left on device" in lines[0]


@pytest.mark.parametrize("batch", [False, True])
def test_json_with_report_file_and_no_output(tmp_path, batch):
    """`--json --report FILE` without -o: the summary on stdout, the report in the file (it raised a TypeError
    traceback: the output-collision check compared the report's path with no output)."""
    rep = tmp_path / "rep.json"
    args = ["plan", "--batch", "-"] if batch else ["plan", *ADEPT]
    r = subprocess.run(_cli(*args, "--json", "-q", "--report", str(rep)), input=HEADER + ROW if batch else None,
                       capture_output=True, text=True, timeout=TIMEOUT)
    assert r.returncode == 0, r.stderr
    line = json.loads(r.stdout.splitlines()[0])
    assert line["exit_code"] == 0
    doc = json.loads(rep.read_text())
    limits = doc["moves"][0]["limits"] if batch else doc["limits"]
    assert limits["ok"] is True


@pytest.mark.parametrize("args, stdin, unwritten, written", [
    (["plan", *ADEPT, "--round-trip", "-q", "--report", "-", "-o", "traj.csv"], None, ["traj.csv"], []),
    (["plan", "--batch", "-", "--json", "-q", "-o", "traj.csv"], HEADER + ROW + ROW, ["traj.csv"], []),
    # the files are written before the JSON summary goes to stdout: they are there, exit 0
    (["plan", *ADEPT, "--json", "-o", "traj.csv", "--report", "rep.json"], None, [], ["rep.json", "traj.csv"]),
    (["plan", *ADEPT, "-q"], None, [], []),
    (["plan", "--batch", "-", "--json", "-q"], HEADER + ROW, [], []),
])
def test_a_reader_that_goes_away_is_exit_0_unless_a_file_is_left_unwritten(tmp_path, args, stdin, unwritten, written):
    """stdout's reader gone (`| head`, here a pipe whose read end is closed before the command writes): exit 0 as
    before when every file asked for was written (or stdout was the only output); when an -o or --report file was
    still to be written (it is not: the command stops at the broken pipe) one line naming it and exit 1 (review,
    session 16: exit 0 without the file)."""
    r, w = os.pipe()
    os.close(r)
    try:
        p = subprocess.run(_cli(*args), input=stdin, stdout=w, stderr=subprocess.PIPE, text=True, timeout=TIMEOUT,
                           cwd=tmp_path)
    finally:
        os.close(w)
    assert "Traceback" not in p.stderr
    assert sorted(os.listdir(tmp_path)) == written  # no temporary file left
    if not unwritten:
        assert p.returncode == 0 and "pickplace: error" not in p.stderr
        return
    assert p.returncode == 1
    assert p.stderr.splitlines() == [f"pickplace: error: {', '.join(unwritten)}: not written: standard output was "
                                     "closed by its reader (broken pipe) before the command finished"]


@pytest.mark.parametrize("args, code", [
    (["plan", *ADEPT, "-q", "-o", "/dev/stdout"], 0),  # written in place: nothing left pending
    (["plan", *ADEPT, "--round-trip", "-q", "--report", "-", "-o", "/dev/null"], 0),
    (["plan", *ADEPT, "--time", "0.05", "--json", "-q", "-o", "x.csv"], 3),  # not written on purpose; verdict kept
    (["plan", *ADEPT, "--time", "0.05", "-q"], 3),
])
def test_a_reader_that_goes_away_keeps_the_verdict_and_ignores_devices(tmp_path, args, code):
    """Review of session 16's broken-pipe rule: a device or /dev path is written in place (never 'not written'); a
    file the command decided not to write (a limit exceeded) is not called lost; and the move's verdict (3) is the
    exit code even though stdout's reader went away (it used to be 0)."""
    r, w = os.pipe()
    os.close(r)
    try:
        p = subprocess.run(_cli(*args), stdout=w, stderr=subprocess.PIPE, text=True, timeout=TIMEOUT, cwd=tmp_path)
    finally:
        os.close(w)
    assert p.returncode == code, p.stderr
    assert "Traceback" not in p.stderr and "not written: standard output" not in p.stderr
    assert os.listdir(tmp_path) == []


def test_a_broken_pipe_says_whether_standard_output_was_closed(tmp_path):
    """The broken-pipe message names standard output only when it is standard output whose reader left (a FIFO given
    to --report or -o breaks too): its write end polls POLLERR then, not when it is a file or a live pipe."""
    code = "import sys; from pickplace_cli.cli.app import _stdout_broken; sys.stderr.write(str(_stdout_broken()))"
    r, w = os.pipe()
    os.close(r)  # the reader is gone before the child starts
    try:
        gone = subprocess.run([sys.executable, "-c", code], stdout=w, stderr=subprocess.PIPE, text=True, timeout=120)
    finally:
        os.close(w)
    with open(tmp_path / "out.txt", "w") as f:
        to_file = subprocess.run([sys.executable, "-c", code], stdout=f, stderr=subprocess.PIPE, text=True, timeout=120)
    live = subprocess.run([sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                          timeout=120)
    assert (gone.stderr, to_file.stderr, live.stderr) == ("True", "False", "False")
