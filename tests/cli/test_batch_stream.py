"""``plan --batch -`` as a pipeline stage (issue 16, part 2): each row answered as soon as it is read, in row
order, with bounded input; a real subprocess and a real pipe (not CliRunner, which hands the input over whole)."""

from __future__ import annotations

import json
import os
import select
import subprocess
import sys
import time

import pytest

from pickplace_cli.pipelines.batch import BATCH_MAX_LINE

HEADER = "from_x,from_y,from_z,to_x,to_y,to_z\n"
ROW = "-0.1525,0,-0.8,0.1525,0,-0.8\n"
ROW2 = "0.1,0.05,-0.85,-0.1,0,-0.8\n"
TIMEOUT = 60.0  # s: generous for a cold start on a slow 2-core CI machine


def _start(*args: str) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "pickplace_cli", "plan", "--batch", "-", *args],
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, bufsize=1)


def _readline(stream, timeout: float = TIMEOUT) -> str:
    """One line of ``stream`` within ``timeout`` s (fails the test instead of hanging)."""
    ready, _, _ = select.select([stream], [], [], timeout)
    assert ready, f"no output within {timeout} s"
    return stream.readline()


def test_first_answer_arrives_before_the_second_row_is_written():
    """The issue's test: a row written, a pause, the next row. The first answer (a JSON line) must come while
    the input is still open and the second row not yet written."""
    proc = _start("--json")
    try:
        proc.stdin.write(HEADER + ROW)
        proc.stdin.flush()
        first = json.loads(_readline(proc.stdout))
        assert first["row"] == 1 and first["exit_code"] == 0 and first["limits_ok"]
        assert proc.poll() is None  # still running, waiting for more input
        proc.stdin.write(ROW2)
        proc.stdin.flush()
        second = json.loads(_readline(proc.stdout))
        assert second["row"] == 2
        proc.stdin.close()
        assert proc.wait(TIMEOUT) == 0
        assert proc.stdout.read() == ""
    finally:
        proc.kill()


def test_csv_rows_are_flushed_per_row():
    proc = _start("-q")
    try:
        proc.stdin.write(HEADER + ROW)
        proc.stdin.flush()
        header = _readline(proc.stdout)
        assert header.startswith("move[-],t[s],")
        line = _readline(proc.stdout)
        assert line.startswith("1,0,")
        proc.stdin.write(ROW2)
        proc.stdin.close()
        rest = proc.stdout.read()
        assert proc.wait(TIMEOUT) == 0
        moves = [ln.split(",", 1)[0] for ln in [line, *rest.splitlines()]]
        assert set(moves) == {"1", "2"} and moves == sorted(moves)
    finally:
        proc.kill()


def test_stream_keeps_row_order_with_workers_and_matches_a_file_batch(tmp_path):
    """-j 2 on a stream: answers in row order, the same documents as the file batch (same numbers), a parse
    error in the middle reported at its row."""
    rows = [ROW, ROW2, "1,2,3\n", ROW2, ROW, ROW2, ROW]
    text = HEADER + "".join(rows)
    f = tmp_path / "moves.csv"
    f.write_text(text)
    streamed = subprocess.run([sys.executable, "-m", "pickplace_cli", "plan", "--batch", "-", "--json", "-j", "2",
                               "-q"], input=text, capture_output=True, text=True, timeout=TIMEOUT)
    filed = subprocess.run([sys.executable, "-m", "pickplace_cli", "plan", "--batch", str(f), "--json", "-q"],
                           capture_output=True, text=True, timeout=TIMEOUT)
    assert streamed.returncode == filed.returncode == 1
    docs = [json.loads(x) for x in streamed.stdout.splitlines()]
    assert [d["row"] for d in docs] == list(range(1, 8))
    assert docs[2]["exit_code"] == 1 and "has 3 cells" in docs[2]["error"]
    want = [json.loads(x) for x in filed.stdout.splitlines()]
    strip = ("error",)
    assert [{k: v for k, v in d.items() if k not in strip} for d in docs] == [
        {k: v for k, v in d.items() if k not in strip} for d in want]


def test_stream_writes_a_file_atomically_and_fail_fast_stops(tmp_path):
    out = tmp_path / "out.csv"
    text = HEADER + ROW + "0,0,0,5,0,-0.8\n" + ROW2
    r = subprocess.run([sys.executable, "-m", "pickplace_cli", "plan", "--batch", "-", "-o", str(out), "--fail-fast",
                        "-q"], input=text, capture_output=True, text=True, timeout=TIMEOUT)
    assert r.returncode == 4, r.stderr
    assert "row 2" in r.stderr and "row 3" not in r.stderr
    moves = {ln.split(",", 1)[0] for ln in out.read_text().splitlines()[1:]}
    assert moves == {"1"}
    assert [p.name for p in tmp_path.iterdir()] == ["out.csv"]  # no temp file left behind


@pytest.mark.parametrize("payload, words", [
    (HEADER.encode() + b"\x00\x01\x02\n", "binary file (NUL bytes)"),
    (HEADER.encode() + b"\xff\xfe\xfd\n", "not UTF-8 text"),
    (HEADER.encode() + b"1" * (BATCH_MAX_LINE + 10), f"more than {BATCH_MAX_LINE} characters"),
])
def test_bad_input_is_one_line_exit_1(payload, words):
    r = subprocess.run([sys.executable, "-m", "pickplace_cli", "plan", "--batch", "-", "--json"], input=payload,
                       capture_output=True, timeout=TIMEOUT)
    err = r.stderr.decode()
    assert r.returncode == 1, err
    assert words in err and "Traceback" not in err
    assert len([ln for ln in err.splitlines() if ln.startswith("pickplace: error:")]) == 1


@pytest.mark.parametrize("keep_warm", [[], ["--keep-warm", "0.005"]])
def test_a_named_pipe_streams_too(tmp_path, keep_warm):
    fifo = tmp_path / "moves.fifo"
    os.mkfifo(fifo)
    proc = subprocess.Popen([sys.executable, "-m", "pickplace_cli", "plan", "--batch", str(fifo), "--json", *keep_warm],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        with open(fifo, "w") as w:
            w.write(HEADER + ROW)
            w.flush()
            first = json.loads(_readline(proc.stdout))
            assert first["row"] == 1 and proc.poll() is None
            time.sleep(0.05)
            w.write(ROW2)
        assert proc.wait(TIMEOUT) == 0
        assert json.loads(proc.stdout.read())["row"] == 2
    finally:
        proc.kill()


def _raw_lines(fd: int, n: int, timeout: float = TIMEOUT) -> list[bytes]:
    """Exactly ``n`` lines from the raw file descriptor ``fd`` within ``timeout`` s (unbuffered: answers that
    arrive together are all counted, which select() on a buffered stream would miss)."""
    buf = b""
    deadline = time.monotonic() + timeout
    got = 0
    while got < n:
        ready, _, _ = select.select([fd], [], [], max(0.0, deadline - time.monotonic()))
        assert ready, f"{got} of {n} lines within {timeout} s"
        chunk = os.read(fd, 1 << 16)
        assert chunk, f"output ended after {got} of {n} lines"
        buf += chunk
        got = buf.count(b"\n")
    return buf.splitlines()


def test_workers_with_rows_arriving_slowly_do_not_hang():
    """-j 2 on a stream whose rows come in bursts: the worker processes are forked before the reader thread
    starts (a worker forked while that thread held stdin's lock used to hang, and the stream with it)."""
    proc = subprocess.Popen([sys.executable, "-m", "pickplace_cli", "plan", "--batch", "-", "--json", "-q", "-j", "2"],
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, bufsize=0)
    try:
        os.write(proc.stdin.fileno(), (HEADER + ROW + ROW2 + ROW).encode())
        docs = [json.loads(x) for x in _raw_lines(proc.stdout.fileno(), 3)]
        assert [d["row"] for d in docs] == [1, 2, 3]
        time.sleep(0.5)
        os.write(proc.stdin.fileno(), ROW2.encode())
        assert json.loads(_raw_lines(proc.stdout.fileno(), 1)[0])["row"] == 4
        proc.stdin.close()
        assert proc.wait(TIMEOUT) == 0
    finally:
        proc.kill()


@pytest.mark.parametrize("fail_fast", [True, False])
def test_a_stream_that_writes_no_row_leaves_the_output_alone(tmp_path, fail_fast):
    """No row written: -o FILE is neither created nor changed (as a file batch), not replaced by an empty file."""
    keep, new = tmp_path / "keep.csv", tmp_path / "new.csv"
    keep.write_text("a good file\n")
    bad = HEADER + "0.5,0.5,-0.2,0.1,0,-0.8\n"  # unreachable: exit 4
    for out in (keep, new):
        r = subprocess.run([sys.executable, "-m", "pickplace_cli", "plan", "--batch", "-", "-q", "-o", str(out),
                            *(["--fail-fast"] if fail_fast else [])], input=bad, capture_output=True, text=True,
                           timeout=TIMEOUT)
        assert r.returncode == 4 and "no row could be written" in r.stderr
    assert keep.read_text() == "a good file\n" and not new.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["keep.csv"]  # no temp file left


def test_invalid_utf8_is_named_at_its_line_after_the_rows_before_it(tmp_path):
    """A bad byte on line 3 of a stream: row 1 is answered, the error names line 3 (decoding used to fail on
    the whole chunk read, naming line 1 and answering nothing)."""
    payload = (HEADER + ROW).encode() + b"-0.1,\xe9,0,0,0,0\n" + ROW.encode()
    r = subprocess.run([sys.executable, "-m", "pickplace_cli", "plan", "--batch", "-", "--json", "-q"],
                       input=payload, capture_output=True, timeout=TIMEOUT)
    assert r.returncode == 1
    docs = [json.loads(x) for x in r.stdout.decode().splitlines()]
    assert [d["row"] for d in docs[:-1]] == [1]
    assert "row" not in docs[-1] and "stdin:3: not UTF-8 text" in docs[-1]["error"]  # the error that ended the stream
    assert "stdin:3: not UTF-8 text" in r.stderr.decode()
    f = tmp_path / "latin.csv"
    f.write_bytes(payload)
    r = subprocess.run([sys.executable, "-m", "pickplace_cli", "plan", "--batch", str(f), "--json", "-q"],
                       capture_output=True, timeout=TIMEOUT)
    assert r.returncode == 1 and "latin.csv:3: not UTF-8 text" in r.stderr.decode()


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="F_SETPIPE_SZ is Linux's")
def test_streamed_csv_widens_a_piped_stdout():
    """A streamed CSV on a pipe asks for a 1 MiB pipe buffer (one 1 kHz answer of the Adept cycle, ~72 kB, is
    more than Linux's 64 KiB default), so a row's answer goes in with one write; the pipe is the same object on
    both ends, so its size is read here. JSON verdicts (a line per row) leave the pipe as it is."""
    import fcntl

    from pickplace_cli.cli.batch import STREAM_PIPE_BYTES

    with open("/proc/sys/fs/pipe-max-size") as fh:
        if int(fh.read()) < STREAM_PIPE_BYTES:
            pytest.skip("this machine's pipe-max-size is below 1 MiB")
    get = getattr(fcntl, "F_GETPIPE_SZ", 1032)
    for args, widened in ((["-q", "--rate", "1000"], True), (["--json", "-q"], False)):
        r, w = os.pipe()
        try:
            before = fcntl.fcntl(r, get)
            proc = subprocess.run([sys.executable, "-m", "pickplace_cli", "plan", "--batch", "-", *args],
                                  input=(HEADER + ROW).encode(), stdout=w, stderr=subprocess.PIPE, timeout=TIMEOUT)
            assert proc.returncode == 0, proc.stderr
            after = fcntl.fcntl(r, get)
            assert after == (STREAM_PIPE_BYTES if widened else before)
            if widened:  # the whole answer sat in the pipe with no reader: more than the 64 KiB default holds
                assert len(os.read(r, 1 << 20)) > 65_536
        finally:
            os.close(r)
            os.close(w)


def test_keep_warm_answers_the_same_bytes_row_by_row(tmp_path):
    """--keep-warm: rows that arrive with pauses between them (warm-ups run in the pauses) get byte for byte the
    answers of a stream without it, each before the next row is written; a parse error still names its row."""
    rows = [ROW, ROW2, "1,2,3\n", ROW]
    plain = subprocess.run([sys.executable, "-m", "pickplace_cli", "plan", "--batch", "-", "--rate", "1000", "-q"],
                           input=HEADER + "".join(rows), capture_output=True, text=True, timeout=TIMEOUT)
    assert plain.returncode == 1 and "row 3 (stdin:4)" in plain.stderr
    proc = subprocess.Popen([sys.executable, "-m", "pickplace_cli", "plan", "--batch", "-", "--rate", "1000", "-q",
                             "--keep-warm", "0.002"], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, bufsize=0)
    try:
        out = []
        expected = plain.stdout.encode().splitlines()
        os.write(proc.stdin.fileno(), HEADER.encode())
        for i, row in enumerate(rows):
            os.write(proc.stdin.fileno(), row.encode())
            if row != "1,2,3\n":
                want = sum(1 for ln in expected[1:] if ln.split(b",", 1)[0] == str(i + 1).encode())
                out += _raw_lines(proc.stdout.fileno(), want + (1 if not out else 0))
            time.sleep(0.1)  # ~50 warm-up intervals
        proc.stdin.close()
        assert proc.wait(TIMEOUT) == 1
        out += proc.stdout.read().splitlines()
        assert out == expected
        assert "row 3 (stdin:4)" in proc.stderr.read().decode()
    finally:
        proc.kill()


@pytest.mark.parametrize("args, code, words", [
    (["--from", "0,0,-0.8", "--to", "0.1,0,-0.8", "--keep-warm", "0.005"], 2, "only applies to a streamed --batch"),
    (["--batch", "FILE", "--keep-warm", "0.005"], 2, "is not a pipe: it is read whole"),
    (["--batch", "-", "--keep-warm", "0.005", "-j", "2"], 2, "give -j 1 (not -j 2)"),
    (["--batch", "-", "--keep-warm", "0.0001"], 1, "--keep-warm 0.0001 s: must be 0 (off) or in 0.001 ... 10 s"),
    (["--batch", "-", "--keep-warm", "nan"], 1, "--keep-warm nan s"),
    (["--batch", "-", "--keep-warm", "-1"], 1, "--keep-warm -1.0 s"),
])
def test_keep_warm_usage(tmp_path, args, code, words):
    batch = tmp_path / "moves.csv"
    batch.write_text(HEADER + ROW)
    args = [str(batch) if a == "FILE" else a for a in args]
    r = subprocess.run([sys.executable, "-m", "pickplace_cli", "plan", *args], input=HEADER + ROW,
                       capture_output=True, text=True, timeout=TIMEOUT)
    assert r.returncode == code, r.stderr
    assert words in r.stderr and "Traceback" not in r.stderr
    if code == 1:  # a bad value: one line (a usage error, exit 2, has click's usage lines above its own)
        assert len(r.stderr.strip().splitlines()) == 1


def test_keep_warm_refuses_a_belt_schedule():
    text = ("t_detect,to_x,to_y,to_z,to_belt_vx,to_belt_vy,to_belt_vz,place_x,place_y,place_z\n"
            "0,0.0,0.05,-0.85,0.2,0,0,0.15,0,-0.8\n")
    r = subprocess.run([sys.executable, "-m", "pickplace_cli", "plan", "--batch", "-", "--keep-warm", "0.005"],
                       input=text, capture_output=True, text=True, timeout=TIMEOUT)
    assert r.returncode == 2 and "does not apply to a belt schedule" in r.stderr and "Traceback" not in r.stderr


@pytest.mark.parametrize("keep_warm", [[], ["--keep-warm", "0.005"]])
def test_lone_cr_line_ends_on_stdin(keep_warm):
    """Lines ended by a lone \\r (old Mac files) on stdin, as in a file: each row answered (Python's stdin splits at
    \\n only: this was a csv traceback)."""
    text = HEADER.replace("\n", "\r") + ROW.replace("\n", "\r") + ROW2
    r = subprocess.run([sys.executable, "-m", "pickplace_cli", "plan", "--batch", "-", "--json", "-q", *keep_warm],
                       input=text.encode(), capture_output=True, timeout=TIMEOUT)
    assert r.returncode == 0, r.stderr
    assert [json.loads(ln)["row"] for ln in r.stdout.splitlines()] == [1, 2]


@pytest.mark.parametrize("keep_warm", [[], ["--keep-warm", "0.005"]])
@pytest.mark.parametrize("end", ["\r", "\r\n"])
def test_a_row_ended_by_cr_is_answered_before_the_next_byte(keep_warm, end):
    """A serial device's CR-terminated rows: each answered before anything more is written (a text stream held a
    last \\r back until the next byte showed whether \\n followed: one row late; review, session 16). With \\r\\n
    written as \\r, a pause, then \\n, the \\n is the rest of that line end, not a row."""
    proc = _start("--json", "-q", *keep_warm)
    try:
        proc.stdin.write(HEADER.replace("\n", "\r") + ROW.replace("\n", "\r"))
        proc.stdin.flush()
        assert json.loads(_readline(proc.stdout))["row"] == 1
        proc.stdin.write(end[1:] + ROW2.replace("\n", "\r"))
        proc.stdin.flush()
        assert json.loads(_readline(proc.stdout))["row"] == 2
        proc.stdin.write("\n")  # the \n of a \r\n: nothing to answer
        proc.stdin.close()
        assert proc.wait(TIMEOUT) == 0
        assert proc.stdout.read() == "" and proc.stderr.read() == ""
    finally:
        proc.kill()


def test_closed_stdin_is_one_line():
    r = subprocess.run([sys.executable, "-m", "pickplace_cli", "plan", "--batch", "-", "--json"],
                       stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=TIMEOUT,
                       preexec_fn=lambda: os.close(0))
    assert r.returncode == 1 and "Traceback" not in r.stderr
    assert r.stderr.strip() == "pickplace: error: --batch -: standard input is closed; give the rows on stdin or a file"


def test_keep_warm_with_a_missing_batch_file_says_it_is_missing(tmp_path):
    r = subprocess.run([sys.executable, "-m", "pickplace_cli", "plan", "--batch", str(tmp_path / "no.csv"),
                        "--keep-warm", "0.01"], capture_output=True, text=True, timeout=TIMEOUT)
    assert r.returncode == 1 and "cannot read it: No such file or directory" in r.stderr


def test_keep_warm_reads_stdin_in_its_encoding():
    """PYTHONIOENCODING=latin-1: the same answers with and without --keep-warm (a header comment in latin-1)."""
    text = ("# pièce\n" + HEADER + ROW).encode("latin-1")
    env = dict(os.environ, PYTHONIOENCODING="latin-1")
    outs = [subprocess.run([sys.executable, "-m", "pickplace_cli", "plan", "--batch", "-", "--json", "-q", *kw],
                           input=text, capture_output=True, timeout=TIMEOUT, env=env) for kw in ([], ["--keep-warm", "0.005"])]
    assert outs[0].returncode == outs[1].returncode == 0 and outs[0].stdout == outs[1].stdout
