"""`pickplace line` under faults: each is one line on stderr and a documented exit code, nothing already answered is
lost and no process of the run is left. Waits are for conditions (a process gone, a line printed, a file grown)
with generous caps, never a fixed time."""

from __future__ import annotations

import fcntl
import os
import select
import signal
import socket
import subprocess
import sys
import time

import pytest
from typer.testing import CliRunner

from pickplace_cli.cli import app
from tests.cli.test_cli_line import LINE  # the same two-robot line
from tests.procs import children, group, kill_group
from tests.terminal import stderr_on_terminal

runner = CliRunner()
CAP = 240.0  # s: the most any wait here lasts (a busy 2-core machine)
DETECTIONS = "t[s],along[m],across[m],id\n0.0,0.0,0.0,a\n0.5,0.0,0.05,b\n"

needs_proc = pytest.mark.skipif(not os.path.isdir("/proc"), reason="reads /proc")


def run(*args, input=None):
    return runner.invoke(app, [str(a) for a in args], input=input, catch_exceptions=False)


def _cli(*args) -> list[str]:
    return [sys.executable, "-m", "pickplace_cli", *[str(a) for a in args]]


@pytest.fixture
def line_file(tmp_path):
    p = tmp_path / "line.yaml"
    p.write_text(LINE)
    return p


def _one_line(stderr: str, text: str) -> str:
    err = [x for x in stderr.splitlines() if x.startswith("pickplace: error:")]
    assert len(err) == 1 and text in err[0], stderr
    assert "internal error" not in stderr and "Traceback" not in stderr, stderr
    return err[0]


def _wait(condition, what: str, proc=None) -> None:
    deadline = time.monotonic() + CAP
    while not condition():
        assert time.monotonic() < deadline, f"waited {CAP:g} s for {what}"
        if proc is not None and proc.poll() is not None:
            raise AssertionError(f"the run ended (exit {proc.returncode}) before {what}: {proc.stderr.read()}")
        time.sleep(0.05)


# ------------------------------------------------------------------------------------------------ sweeps


@needs_proc
@pytest.mark.slow
def test_sweep_workers_die_with_a_killed_main_process(line_file, tmp_path):
    out = tmp_path / "sweep.csv"
    ckpt = tmp_path / "sweep.csv.partial.jsonl"
    proc = subprocess.Popen(_cli("line", line_file, "--seeds", "1:60:1", "-j", "2", "-q", "-o", out),
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        _wait(lambda: len(children(proc.pid)) >= 2 and ckpt.exists() and len(ckpt.read_text().splitlines()) > 1,
              "two workers and a finished case", proc)
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(CAP)
        _wait(lambda: not group(proc.pid), "the workers to end after their parent was killed")
    finally:
        kill_group(proc)
    assert not out.exists()


def test_a_second_sweep_on_the_same_output_is_refused(line_file, tmp_path):
    """Another sweep holds OUTPUT.partial.jsonl (here: this test holds its lock): this one is refused in one line,
    exit 1, and the other's checkpoint is left as it was (it used to be truncated and mixed)."""
    out = tmp_path / "sweep.csv"
    ckpt = tmp_path / "sweep.csv.partial.jsonl"
    ckpt.write_text('{"sweep": "the other one"}\n')
    with open(ckpt) as held:
        fcntl.flock(held, fcntl.LOCK_EX)
        r = run("line", line_file, "--seeds", "1,2", "-j", "1", "-q", "-o", out)
    assert r.exit_code == 1
    _one_line(r.stderr, "in use by another line sweep")
    assert ckpt.read_text() == '{"sweep": "the other one"}\n' and not out.exists()


def test_a_checkpoint_with_rows_of_another_sweep_is_refused_on_resume(tmp_path):
    """Rows another sweep appended under this sweep's header are recognised by the digest each row carries."""
    from pickplace_cli.line import sweep as sw
    from pickplace_cli.line.spec import parse_line
    from pickplace_cli.model.errors import TableError
    from pickplace_cli.model.profile import load_profile

    line = parse_line(LINE.replace("count: 12", "count: 3"), "l.yaml")
    profiles = {r.name: load_profile() for r in line.robots}
    cases = sw.cases([0.3, 0.5], [1], ["upstream_first"], [1])
    files = {}
    for name in ("a", "b"):
        files[name] = tmp_path / f"{name}.csv.partial.jsonl"

        def stop(done, total):
            if done == 1:
                raise KeyboardInterrupt

        with pytest.raises(KeyboardInterrupt):
            sw.run_sweep(line, profiles, cases, None, 1, None, stop, files[name], False, sw.digest(line, {"s": name}))
    tag_a = sw.digest(line, {"s": "a"})
    assert len(sw.read_checkpoint(files["a"], tag_a)) == 1
    mixed = files["a"].read_text() + files["b"].read_text().split("\n", 1)[1]  # b's rows under a's header
    files["a"].write_text(mixed)
    with pytest.raises(TableError, match="a row of another sweep"):
        sw.read_checkpoint(files["a"], tag_a)


@pytest.mark.slow
def test_a_lost_dask_scheduler_is_one_line(line_file, tmp_path):
    pytest.importorskip("distributed")
    bindir = os.path.dirname(sys.executable)
    dask = os.path.join(bindir, "dask")
    if not os.path.exists(dask):
        pytest.skip("the dask command is not installed")
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    address = f"tcp://127.0.0.1:{port}"
    out, ckpt = tmp_path / "sweep.csv", tmp_path / "sweep.csv.partial.jsonl"
    procs = [subprocess.Popen([dask, "scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)]
    try:
        procs.append(subprocess.Popen([dask, "worker", address, "--nthreads", "1", "--no-dashboard"],
                                      stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True))
        sweep = subprocess.Popen(_cli("line", line_file, "--seeds", "1:300:1", "--scheduler", address, "-q", "-o", out),
                                 stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, start_new_session=True)
        procs.append(sweep)
        _wait(lambda: ckpt.exists() and len(ckpt.read_text().splitlines()) > 1, "a finished case", sweep)
        procs[0].kill()
        code = sweep.wait(CAP)
        err = sweep.stderr.read()
    finally:
        for p in procs:
            try:
                os.killpg(p.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            p.wait()
    assert code == 1, err
    _one_line(err, "lost the Dask scheduler")
    assert len(err.strip().splitlines()) == 1, err
    assert ckpt.exists() and not out.exists()  # the finished cases are kept for --resume


def test_more_workers_than_cores_are_capped_with_a_note(line_file, tmp_path):
    r = run("line", line_file, "--seeds", "1,2", "-j", "1000", "-q", "-o", tmp_path / "s.csv")
    assert r.exit_code == 0, r.stderr
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    notes = [x for x in r.stderr.splitlines() if "-j 1000" in x]
    assert len(notes) == 1 and f"{cores} core" in notes[0], r.stderr


# ------------------------------------------------------------------------------------------------ reading


def test_a_generator_beyond_the_parts_bound_is_refused(line_file):
    from pickplace_cli.line.parts import MAX_PARTS, generate
    from pickplace_cli.line.spec import Generator, parse_line
    from pickplace_cli.model.errors import PickplaceError

    text = LINE.replace("{rate: 4.0, count: 12, seed: 2}", "{rate: 1000, duration: 1.0e6}")
    with pytest.raises(PickplaceError, match=f"more than the {MAX_PARTS} parts"):
        parse_line(text, "l.yaml")
    line_file.write_text(text)
    r = run("line", line_file, "-q", "-o", os.devnull)
    assert r.exit_code == 1
    _one_line(r.stderr, "1e+09 parts")
    with pytest.raises(PickplaceError, match="more than the"):  # the library's own guard
        generate(Generator(rate=1000, duration=1e6), 0.3)


def _limited(limit_bytes: int = 3 << 30):
    def apply():  # pragma: no cover - runs in the child
        import resource

        resource.setrlimit(resource.RLIMIT_AS, (limit_bytes, limit_bytes))
    return apply


@pytest.mark.parametrize("source", ["/dev/zero", "-"])
def test_an_endless_line_is_refused_in_bounded_memory(line_file, source):
    """/dev/zero (one endless line of NUL bytes), as a file or on stdin: refused at once, in bounded memory (the run
    is given 3 GB of address space: reading the line whole used to grow without bound)."""
    if not os.path.exists("/dev/zero"):
        pytest.skip("no /dev/zero")
    with open("/dev/zero", "rb") as zero:
        r = subprocess.run(_cli("line", line_file, "--detections", source, "-q", "-o", os.devnull),
                           stdin=zero if source == "-" else subprocess.DEVNULL, capture_output=True, text=True,
                           timeout=CAP, preexec_fn=_limited())
    assert r.returncode == 1, r.stderr
    _one_line(r.stderr, "a line of more than 4096 characters")


def test_an_over_long_line_on_a_stream_is_answered_once(line_file):
    """One 100 kB row among good ones on stdin: one refused row, and the rows after it keep their row and id."""
    text = ("t[s],along[m],across[m],id\n0.0,0.0,0.0,a\n0.5,0.0," + "1" * 100_000 + ",b\n1.0,0.0,0.01,c\n"
            "1.5,0.0,-0.02,d\n")
    r = subprocess.run(_cli("line", line_file, "--detections", "-", "-q"), input=text, capture_output=True, text=True,
                       timeout=CAP)
    rows = [x.split(",") for x in r.stdout.strip().splitlines()[1:]]
    assert [(x[0], x[1]) for x in rows] == [("a", "1"), ("", "2"), ("c", "3"), ("d", "4")], r.stdout
    assert "longer than 4096 characters" in rows[1][-1]
    assert r.returncode == 1 and r.stderr.count("longer than 4096 characters") == 1, r.stderr


@needs_proc
def test_a_named_pipe_without_a_writer_says_what_it_waits_for(line_file, tmp_path):
    fifo = tmp_path / "detections.fifo"
    os.mkfifo(fifo)
    proc = subprocess.Popen(_cli("line", line_file, "--detections", fifo, "-q"), stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        ready, _, _ = select.select([proc.stderr], [], [], CAP)
        assert ready, "nothing said while waiting for the pipe's writer"
        said = proc.stderr.readline()
        assert said.startswith("pickplace: waiting for a writer on the named pipe") and str(fifo) in said, said
        with open(fifo, "w") as fh:
            fh.write(DETECTIONS)
        out, err = proc.communicate(timeout=CAP)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 0, err
    assert [x.split(",")[0] for x in out.strip().splitlines()[1:]] == ["a", "b"]


# ------------------------------------------------------------------------------------------------ values


@pytest.mark.parametrize("args,text", [
    (("--seed", "-5"), "--seed '-5': a seed is a whole number from 0"),
    (("--seeds", "1," + "9" * 5000), "--seeds '1,999"),
    (("--seeds", "18446744073709551616"), "seeds are whole numbers from 0 to 2^64"),
    (("--belt-speed", "1e-300"), "--belt-speed 1e-300: must be at least 0.001"),
    (("--speeds", "1e-300,0.5"), "every belt speed must be at least 0.001"),
])
def test_values_out_of_range_are_one_short_line(line_file, args, text):
    r = run("line", line_file, *args, "-q", "-o", os.devnull)
    assert r.exit_code == 1, r.stderr
    line = _one_line(r.stderr, text)
    assert len(line) < 300


@pytest.mark.parametrize("edit,code,text", [
    (("seed: 2", "seed: " + "9" * 5000), 1, ":13: a number of more than 4000 digits"),
    (("speed: 0.5", "speed: 1.0e-300"), 1, "belt.speed = 1e-300: Input should be greater than or equal to 0.001"),
    (("window: [0.4, 0.8]", "window: [-1.0e9, 1.0e9]"), 4, "window [-1e+09, 1e+09] m across"),  # (r2 dropped)
])
def test_line_file_values_out_of_range(line_file, edit, code, text):
    """(The window of a billion metres is checked at its ends first: exit 4 at once, where the whole grid was built
    before and ran out of memory.)"""
    edited = LINE.replace(*edit, 1)
    if "1.0e9" in edit[1]:
        edited = edited.replace(LINE[LINE.index("  - name: r2"):LINE.index("parts:")], "")
    line_file.write_text(edited)
    r = run("line", line_file, "-q", "-o", os.devnull)
    assert r.exit_code == code, r.stderr
    _one_line(r.stderr, text)


# ------------------------------------------------------------------------------------------------ NO_COLOR


@pytest.mark.parametrize("no_color", [None, "1"])
def test_the_table_honours_no_color(line_file, no_color):
    """On a terminal (a pseudo-terminal) the robots' table is styled; with NO_COLOR set it has no escape sequence."""
    out = stderr_on_terminal(_cli("line", line_file, "-o", os.devnull), no_color, CAP)
    assert b"line: 12 parts" in out
    assert (b"\x1b[" in out) is (no_color is None)
