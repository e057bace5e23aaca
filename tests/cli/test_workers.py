"""Worker processes of ``plan --batch -j N`` and ``build-table -j N``: reaped by the main process when SIGTERM stops
it (none left behind, not even as a zombie), and ``-j`` capped at the cores this process may use."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest
from typer.testing import CliRunner

from pickplace_cli.cli import app
from tests.procs import children, kill_group

TIMEOUT = 120.0  # generous: the bound waits for a slow, shared machine; no test asserts a speed
HEADER = "from_x,from_y,from_z,to_x,to_y,to_z,height\n"


def _moves(path, n: int) -> None:
    rows = [f"{-0.15 + 0.0001 * (i % 500):.4f},0,-0.8,0.1525,{0.0001 * (i % 300):.4f},-0.8,0.025\n" for i in range(n)]
    path.write_text(HEADER + "".join(rows))


def _exists(pid: int) -> bool:
    """The process table still has ``pid``, a zombie included."""
    return os.path.exists(f"/proc/{pid}")


@pytest.mark.skipif(not os.path.isdir("/proc"), reason="reads the process table from /proc")
@pytest.mark.parametrize("command", ["batch", "build-table"])
def test_sigterm_reaps_the_workers_before_the_main_process_ends(tmp_path, command):
    """SIGTERM to the main process alone: once it has ended, its -j 2 workers are gone from the process table. They
    used to be killed but left as zombies for init to collect, seconds later (a supervisor saw them outlive the
    command). The order is what is checked, never a speed: the main process reaps them before it exits."""
    src = tmp_path / "moves.csv"
    _moves(src, 3000)
    args = {"batch": ["plan", "--batch", str(src), "-q", "-j", "2", "-o", str(tmp_path / "out.csv")],
            "build-table": ["build-table", "-q", "-j", "2", "--lambda-min", "5", "--lambda-max", "40",
                            "-o", str(tmp_path / "t.csv")]}[command]
    proc = subprocess.Popen([sys.executable, "-m", "pickplace_cli", *args], stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True, cwd=tmp_path, start_new_session=True)
    try:
        deadline = time.monotonic() + TIMEOUT
        kids = children(proc.pid)
        while len(kids) < 2:
            assert time.monotonic() < deadline and proc.poll() is None, proc.stderr.read()
            time.sleep(0.05)
            kids = children(proc.pid)
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(TIMEOUT) == 143
        assert "terminated (SIGTERM)" in proc.stderr.read()
        left = [k for k in kids if _exists(k)]
        assert not left, f"worker processes {left} outlived the main process (as zombies: not reaped by it)"
    finally:
        kill_group(proc)


def _cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover
        return os.cpu_count() or 1


def test_plan_batch_caps_workers_at_the_cores(tmp_path, monkeypatch):
    """``plan --batch -j 1000`` plans on as many processes as there are cores, with a one-line note (it started a
    thousand processes)."""
    import pickplace_cli.pipelines.batch as batch

    seen = []
    original = batch.plan_rows_parallel

    def record(*args, workers=1, **kwargs):
        seen.append(workers)
        return original(*args, workers=1, **kwargs)  # the rows themselves in this process

    monkeypatch.setattr(batch, "plan_rows_parallel", record)
    src = tmp_path / "moves.csv"
    _moves(src, 2)
    r = CliRunner().invoke(app, ["plan", "--batch", str(src), "-q", "-j", "1000", "-o", str(tmp_path / "out.csv")],
                           catch_exceptions=False)
    assert r.exit_code == 0, r.output
    cores = _cores()
    assert seen == [cores]
    note = f"pickplace: note: -j 1000: {cores} core{'s' if cores > 1 else ''} available; running {cores} worker"
    assert note in r.output


def test_build_table_caps_workers_at_the_cores(tmp_path, monkeypatch):
    """``build-table -j 1000``: the same cap and note."""
    import pickplace_cli.lookup.bspline_build as build

    seen = []
    original = build.run_build

    def record(*args, workers=1, **kwargs):
        seen.append(workers)
        return original(*args, workers=1, **kwargs)

    monkeypatch.setattr(build, "run_build", record)
    r = CliRunner().invoke(app, ["build-table", "-q", "-j", "1000", "--lambda-min", "5", "--lambda-max", "6",
                                 "--lambda-step", "1", "--fit-min", "5", "-o", str(tmp_path / "t.csv")],
                           catch_exceptions=False)
    cores = _cores()
    assert seen == [cores], r.output
    assert f"pickplace: note: -j 1000: {cores} core" in r.output
