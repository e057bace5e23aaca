"""atomic_output: a writer killed mid-write leaves the old file (or none), never a truncated one.

A child process writes a real export (CSV of a batch, or MCAP) through ``atomic_output`` into a stream
wrapper that, at 64 KiB (in the middle of one of the writer's writes), flushes, tells the parent and sleeps: the kill is guaranteed to land
in the middle of the write, with partial data already on disk in the temporary file. The parent SIGKILLs
it (no cleanup handler can run) and checks the target. A control run writes the same way to the target
directly (no atomic_output) and does leave a truncated file, so the test can tell the difference.

SIGKILL leaves the temporary file behind (``.NAME.XXXX.tmp`` next to the target, hidden, ignored by
git); an exception or Ctrl-C inside the writer removes it (tested below).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from pickplace_cli.model.errors import ExportError
from pickplace_cli.export import atomic_output

ROOT = Path(__file__).resolve().parents[2]

CHILD = r"""
import sys, time
sys.path.insert(0, {root!r})
from tests.golden.samples import delta_plan, timeline
from pickplace_cli.export import atomic_output

target, kind, mode = sys.argv[1], sys.argv[2], sys.argv[3]
binary = kind == "mcap"

class Stall:
    # passes writes through until 64 KiB, writing the first part of the write that crosses it;
    # then flushes to disk, tells the parent and waits to be killed
    def __init__(self, fh):
        self.fh, self.n = fh, 0
    def write(self, data):
        if self.n + len(data) >= 65536:
            self.fh.write(data[: 65536 - self.n])
            self.fh.flush()
            print("STALLED", flush=True)
            time.sleep(120)
        self.fh.write(data)
        self.n += len(data)
        return len(data)
    def tell(self):
        return self.n
    def flush(self):
        self.fh.flush()

def export(fh):
    if kind == "csv":
        from pickplace_cli.export.csv import write_csv
        write_csv(timeline([delta_plan(rate=1000), delta_plan(rate=1000, back=True)]), fh)
    else:
        from pickplace_cli.export.mcap import write_mcap
        write_mcap(delta_plan(rate=1000), fh)

if mode == "atomic":
    with atomic_output(target, binary=binary) as fh:
        export(Stall(fh))
else:  # control: a plain, non-atomic write to the target
    with open(target, "wb" if binary else "w", newline=None if binary else "") as fh:
        export(Stall(fh))
print("DONE", flush=True)
"""


def run_and_kill(target: Path, kind: str, mode: str) -> None:
    proc = subprocess.Popen(
        [sys.executable, "-c", CHILD.format(root=str(ROOT)), str(target), kind, mode],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        line = proc.stdout.readline()
        assert line.strip() == "STALLED", (line, proc.stderr.read() if proc.poll() is not None else "")
        partial = [p for p in target.parent.iterdir() if p.name.startswith(f".{target.name}.") and p.stat().st_size == 65536]
        if mode == "atomic":
            assert partial, "the temporary file should hold the partial output while the writer runs"
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(timeout=30)
        assert proc.returncode == -signal.SIGKILL
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        proc.stdout.close()
        proc.stderr.close()


OLD = b"t[s],x[m]\n0,1\n"  # a complete earlier output


@pytest.mark.parametrize("kind", ["csv", "mcap"])
def test_kill_mid_write_keeps_the_old_file(tmp_path, kind):
    target = tmp_path / f"out.{kind}"
    target.write_bytes(OLD)
    run_and_kill(target, kind, "atomic")
    assert target.read_bytes() == OLD
    leftovers = sorted(p.name for p in tmp_path.iterdir() if p != target)
    # only the hidden temp file of the killed writer remains (SIGKILL cannot be cleaned up after)
    assert len(leftovers) == 1 and leftovers[0].startswith(f".{target.name}.") and leftovers[0].endswith(".tmp")


@pytest.mark.parametrize("kind", ["csv", "mcap"])
def test_kill_mid_write_leaves_no_file(tmp_path, kind):
    target = tmp_path / f"new.{kind}"
    run_and_kill(target, kind, "atomic")
    assert not target.exists()


def test_control_plain_write_is_truncated(tmp_path):
    """Without atomic_output the same kill leaves a truncated target: the tests above can fail."""
    target = tmp_path / "out.csv"
    target.write_bytes(OLD)
    run_and_kill(target, "csv", "plain")
    data = target.read_bytes()
    assert len(data) == 65536 and data != OLD  # the first 64 KiB of a longer output: truncated


@pytest.mark.parametrize("exc", [ExportError("boom"), KeyboardInterrupt()])
def test_exception_mid_write_keeps_old_file_and_removes_temp(tmp_path, exc):
    target = tmp_path / "out.csv"
    target.write_bytes(OLD)
    with pytest.raises(type(exc)):
        with atomic_output(target) as fh:
            fh.write("t[s]\n" * 100000)
            fh.flush()
            raise exc
    assert target.read_bytes() == OLD
    assert [p.name for p in tmp_path.iterdir()] == ["out.csv"]


def test_success_replaces_and_keeps_mode(tmp_path):
    target = tmp_path / "out.csv"
    target.write_bytes(OLD)
    os.chmod(target, 0o640)
    with atomic_output(target) as fh:
        fh.write("new\r\n")
    assert target.read_bytes() == b"new\r\n"  # newline='' : line ends unchanged
    assert target.stat().st_mode & 0o777 == 0o640
    assert [p.name for p in tmp_path.iterdir()] == ["out.csv"]


def test_symlink_is_followed_and_kept(tmp_path):
    """-o LINK replaces the file the link points to (atomically) and leaves the link a link."""
    (tmp_path / "real").mkdir()
    real = tmp_path / "real" / "target.csv"
    real.write_bytes(OLD)
    link = tmp_path / "link.csv"
    link.symlink_to(real)
    with atomic_output(link) as fh:
        fh.write("new\n")
    assert link.is_symlink() and os.readlink(link) == str(real)
    assert real.read_bytes() == b"new\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link.csv", "real"]


def test_named_pipe_is_written_in_place(tmp_path):
    """A FIFO (e.g. read by a PLC gateway) cannot be replaced by a rename: it is written in place and stays
    a FIFO. (Writing /dev/null is the same case; not tested on the device itself: a regression run as root
    would replace the machine's /dev/null.)"""
    import stat
    import threading

    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    got: list[bytes] = []
    reader = threading.Thread(target=lambda: got.append(fifo.read_bytes()))
    reader.start()
    with atomic_output(fifo) as fh:
        fh.write("t[s]\n0\n")
    reader.join(timeout=10)
    assert got == [b"t[s]\n0\n"]
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)
    assert [p.name for p in tmp_path.iterdir()] == ["pipe"]


@pytest.mark.parametrize("make,match", [
    (lambda d: d, "is a directory"),
    (lambda d: "", "empty path"),
    (lambda d: d / "missing" / "out.csv", "does not exist"),
])
def test_unwritable_paths_are_one_line_errors(tmp_path, make, match):
    from pickplace_cli.export import check_writable

    path = make(tmp_path)
    for call in (lambda: check_writable(path), lambda: atomic_output(path).__enter__()):
        with pytest.raises(ExportError, match=match):
            call()
    assert [p.name for p in tmp_path.iterdir()] == []
