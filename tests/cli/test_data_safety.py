"""Nothing lost, nothing hung, nothing left running: one regression test per defect a fault and fuzz test of the
CLI found (an output over its own input, two table builds sharing a checkpoint, a write-protected destination, a belt
at rest, a row that crashed its batch, a named pipe with no writer, workers outliving their parent, tracebacks on a
quoted CSV, a control character, memory and a full disk). Each runs the reproducer's command and checks the documented
outcome against an independent reference: the input's own bytes, a clean plan or build, the kernel's process table.

Real subprocesses where signals, resource limits or file descriptors are the point; waits are for conditions with a
generous cap, never for a fixed time."""

from __future__ import annotations

import json
import os
import resource
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from typer.testing import CliRunner

from pickplace_cli.cli import app
from pickplace_cli.model.profile import resolve_profile_path
from tests.procs import alive, children, kill_group

runner = CliRunner()
HEADER = "from_x,from_y,from_z,to_x,to_y,to_z\n"
ROW = "-0.1525,0,-0.8,0.1525,0,-0.8\n"
ADEPT = ["--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8"]
CAP = 60.0  # s: the longest any condition below is waited for (a busy machine), never a fixed sleep


def run(*args, input=None):
    return runner.invoke(app, list(args), input=input)


def _cli(*args: str) -> list[str]:
    return [sys.executable, "-m", "pickplace_cli", *args]


def _one_error_line(stderr: str) -> str:
    lines = [ln for ln in stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("pickplace: error: "), stderr
    assert "Traceback" not in stderr
    return lines[0]


# ------------------------------------------------------------------ 1. an output that is the command's own input


def _inputs(tmp_path: Path) -> dict:
    moves = tmp_path / "moves.csv"
    moves.write_text(HEADER + ROW)
    robot = tmp_path / "robot.yaml"
    robot.write_text(resolve_profile_path("delta-su2018").read_text())
    table = tmp_path / "table.csv"
    table.write_bytes((resolve_profile_path("delta-su2018").parents[1] / "tables" / "bspline-eta0.5.csv").read_bytes()
                      if (resolve_profile_path("delta-su2018").parents[1] / "tables").is_dir() else b"")
    traj = tmp_path / "traj.csv"
    assert run("plan", *ADEPT, "-q", "-o", str(traj)).exit_code == 0
    return {"moves": moves, "robot": robot, "table": table, "traj": traj}


@pytest.mark.parametrize("case", ["batch", "profile", "table", "check", "hard link", "symlink"])
def test_an_output_that_is_an_input_is_refused_before_any_work(tmp_path, case):
    """`plan --batch moves.csv -o moves.csv`, `--report robot.yaml` with `-p robot.yaml`, `--table t.csv -o t.csv`,
    `check traj.csv --report traj.csv`, and the same through a hard or a symbolic link: exit 1, one line naming both
    options, and the input byte for byte as it was (it used to be replaced, exit 0)."""
    f = _inputs(tmp_path)
    if case == "table" and not f["table"].read_bytes():
        pytest.skip("no shipped table in this checkout")
    args = {
        "batch": ["plan", "--batch", str(f["moves"]), "-q", "-o", str(f["moves"])],
        "profile": ["plan", *ADEPT, "-q", "-p", str(f["robot"]), "--report", str(f["robot"]), "-o", str(tmp_path / "t.csv")],
        "table": ["plan", *ADEPT, "-q", "--table", str(f["table"]), "-o", str(f["table"])],
        "check": ["check", str(f["traj"]), "-q", "--report", str(f["traj"])],
        "hard link": ["plan", "--batch", str(f["moves"]), "-q", "-o", str(tmp_path / "hard.csv")],
        "symlink": ["plan", "--batch", str(tmp_path / "link.csv"), "-q", "-o", str(f["moves"])],
    }[case]
    if case == "hard link":
        os.link(f["moves"], tmp_path / "hard.csv")
    if case == "symlink":
        os.symlink(f["moves"], tmp_path / "link.csv")
    before = {k: p.read_bytes() for k, p in f.items()}
    r = run(*args)
    assert r.exit_code == 1, r.output
    line = _one_error_line(r.stderr)
    assert "is the file this command reads as" in line and "would replace the input" in line
    assert {k: p.read_bytes() for k, p in f.items()} == before


def test_a_batch_from_stdin_redirected_from_the_output_is_refused(tmp_path):
    """`plan --batch - -o m2.csv < m2.csv`: standard input is the file -o would replace (by inode)."""
    m2 = tmp_path / "m2.csv"
    m2.write_text(HEADER + ROW)
    with open(m2) as stdin:
        r = subprocess.run(_cli("plan", "--batch", "-", "-q", "-o", str(m2)), stdin=stdin, capture_output=True,
                           text=True, timeout=CAP)
    assert r.returncode == 1
    assert "standard input" in _one_error_line(r.stderr)
    assert m2.read_text() == HEADER + ROW


# ------------------------------------------------------------------ 2. one checkpoint, one run


GRID = ["--lambda-min", "1", "--lambda-max", "40", "--lambda-step", "0.1"]  # 391 rows: seconds of work to overlap


def test_a_second_build_writing_the_same_output_is_refused_and_leaves_the_first_alone(tmp_path):
    """Build A (η 0.4) runs; build B (η 0.5) with the same -o is refused in one line (it used to truncate A's
    checkpoint or append under A's header, and a resume then returned η 0.4 rows under an η 0.5 header, exit 0).
    A's checkpoint keeps its own header and rows; once A is killed, B --resume is refused (other settings)."""
    from pickplace_cli.lookup import bspline_build as B
    from pickplace_cli.lookup.bspline_optimum import TableSettings

    out = tmp_path / "table.csv"
    ckpt = B.checkpoint_path(out)
    a = subprocess.Popen(_cli("build-table", *GRID, "--eta", "0.4", "-q", "-j", "1", "-o", str(out)),
                         stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        deadline = time.monotonic() + CAP
        while not (ckpt.exists() and len(ckpt.read_text().splitlines()) >= 3):  # A has checkpointed rows
            assert a.poll() is None and time.monotonic() < deadline, a.stderr.read() if a.poll() is not None else ""
            time.sleep(0.02)
        r = subprocess.run(_cli("build-table", *GRID, "--eta", "0.5", "-q", "-j", "1", "-o", str(out)),
                           capture_output=True, text=True, timeout=CAP)
        assert r.returncode == 1
        assert "in use by another build-table run" in _one_error_line(r.stderr)
        head = json.loads(ckpt.read_text().splitlines()[0])
        assert head["settings"]["eta"] == 0.4
        assert len(B.read_checkpoint(ckpt, TableSettings(eta=0.4))) >= 2
    finally:
        os.killpg(a.pid, signal.SIGKILL)
        a.wait()
    r = subprocess.run(_cli("build-table", *GRID, "--eta", "0.5", "-q", "-j", "1", "--resume", "-o", str(out)),
                       capture_output=True, text=True, timeout=CAP)
    assert r.returncode == 1 and "written for other settings" in _one_error_line(r.stderr)
    assert not out.exists()


def test_a_checkpoint_row_of_another_run_is_refused_on_resume(tmp_path):
    """A row tagged with another run's settings key under this run's header (two writers that shared the file) makes
    the resume fail in one line, never merge."""
    from pickplace_cli.lookup import bspline_build as B
    from pickplace_cli.lookup.bspline_optimum import TableSettings
    from pickplace_cli.model.errors import TableError

    ckpt = tmp_path / "t.csv.partial.jsonl"
    w = B._Checkpoint(ckpt, TableSettings(eta=0.5), append=False)
    w.close()
    other = B.settings_key(TableSettings(eta=0.4))
    row = {"lambda": 2.0, "k1": 0.1, "k2": 0.2, "a_max": 1, "j_max": 1, "v_max": 1, "F": 1, "a_min": 1, "j_min": 1,
           "key": other}
    with open(ckpt, "a") as fh:
        fh.write(json.dumps(row) + "\n")
    with pytest.raises(TableError, match="a row of another build"):
        B.read_checkpoint(ckpt, TableSettings(eta=0.5))


# ------------------------------------------------------------------ 3. write-protected destinations


@pytest.mark.parametrize("what", ["-o", "--report", "check --report", "build-table -o"])
def test_a_write_protected_destination_is_refused_and_kept(tmp_path, what):
    """A destination of mode 0444 is left as it is (exit 1, one line naming it): the atomic rename needs only the
    directory to be writable and used to replace it, where a shell redirect is refused."""
    dest = tmp_path / ("out.json" if "report" in what else "out.csv")
    dest.write_text("protected\n")
    dest.chmod(0o444)
    traj = tmp_path / "traj.csv"
    assert run("plan", *ADEPT, "-q", "-o", str(traj)).exit_code == 0
    args = {"-o": ["plan", *ADEPT, "-q", "-o", str(dest)],
            "--report": ["plan", *ADEPT, "-q", "-o", str(tmp_path / "t.csv"), "--report", str(dest)],
            "check --report": ["check", str(traj), "-q", "--report", str(dest)],
            "build-table -o": ["build-table", "--lambda-min", "2", "--lambda-max", "2", "-q", "-j", "1", "-o", str(dest)]}[what]
    r = run(*args)
    assert r.exit_code == 1, r.output
    assert "write-protected (mode 0444)" in _one_error_line(r.stderr)
    assert dest.read_text() == "protected\n" and (dest.stat().st_mode & 0o777) == 0o444


# ------------------------------------------------------------------ 4. a belt at rest


def test_a_belt_velocity_of_zero_is_an_ordinary_fixed_end():
    """`--to-belt 0,0,0` planned a 20 s move (waited for the window, 1.5 picks/min); a part at rest is met like a
    fixed end: the same duration as bspline-vel to that point (reference), within 1e-6 relative (both root-find the
    same capacity bound to 1e-8; the rendezvous' T is nudged onto the feasible side)."""
    move = ["--from", "-0.1525,0,-0.8", "--to", "0.1525,-0.2,-0.8", "--json"]
    r = run("plan", *move, "--to-belt", "0,0,0")
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    ref = json.loads(run("plan", *move, "-m", "bspline-vel").stdout)
    assert doc["rendezvous"]["waited_for_window"] is False
    assert doc["duration_s"] == pytest.approx(ref["duration_s"], rel=1e-6)
    assert doc["duration_s"] < 1.0


# ------------------------------------------------------------------ 5. a row's failure is that row's answer

GANTRY_FIT = ["-p", "gantry", "-m", "bspline-vel", "-t", "fit"]


def test_gantry_bspline_vel_fit_is_one_line_not_a_traceback():
    r = run("plan", *GANTRY_FIT, "--from", "-0.3,0,-0.5", "--to", "0.3,0.1,-0.5", "-q")
    assert r.exit_code == 1
    assert "sets no velocity, acceleration, jerk or motor limit" in _one_error_line(r.stderr)


def test_the_error_names_the_rule_asked_for():
    """--time optimal on a profile without timed joint limits: the line names `optimal`, not the fit inside it."""
    r = run("plan", "-p", "gantry", "-t", "optimal", "--from", "-0.3,0,-0.5", "--to", "0.3,0.2,-0.5", "-q")
    assert r.exit_code == 1
    line = _one_error_line(r.stderr)
    assert "--time optimal:" in line and "--time fit" not in line
    assert "sets no velocity, acceleration, jerk or motor limit" in line


@pytest.mark.parametrize("streamed", [False, True])
def test_a_failing_row_does_not_lose_the_batch(tmp_path, streamed):
    """A file batch with such a row printed no JSON line at all for 3 rows, a stream stopped at it: every row now has
    its line, in order, the failing one with its error (the others as a plan of the same row alone says)."""
    rows = HEADER.strip() + ",time\n-0.3,0,-0.5,0.3,0.1,-0.5,1\n-0.3,0,-0.5,0.3,0.1,-0.5,fit\n-0.3,0,-0.5,0.3,0.1,-0.6,1\n"
    src = tmp_path / "g.csv"
    src.write_text(rows)
    args = ["plan", "-p", "gantry", "-m", "bspline-vel", "--batch", "-" if streamed else str(src), "--json", "-q"]
    r = subprocess.run(_cli(*args), input=rows if streamed else None, capture_output=True, text=True, timeout=CAP)
    lines = [json.loads(x) for x in r.stdout.splitlines()]
    assert [d["row"] for d in lines] == [1, 2, 3]
    assert [d["exit_code"] for d in lines] == [0, 1, 0]
    assert r.returncode == 1 and "Traceback" not in r.stderr


def test_compare_on_the_gantry_with_fit_answers_every_method():
    r = run("compare", "-p", "gantry", "-t", "fit", "--from", "-0.3,0,-0.5", "--to", "0.3,0.1,-0.5")
    assert "Traceback" not in r.output and r.exit_code == 1
    assert r.stderr.count("pickplace: method ") == 6  # every method named with its error


def test_an_unforeseen_failure_of_a_row_is_that_row_alone(monkeypatch, tmp_path):
    """Whatever a row raises (here a TypeError injected into the planner for one row), the batch answers it as that
    row's error and plans the others (--report: every row through plan(), not the verdict engine)."""
    from pickplace_cli import planner
    from pickplace_cli.pipelines import batch as B

    real = planner.plan

    def flaky(task, profile, options):
        if abs(task.p_to[1] - 0.1) < 1e-12:
            raise TypeError("injected")
        return real(task, profile, options)

    monkeypatch.setattr(planner, "plan", flaky)
    text = HEADER + ROW + "-0.1525,0,-0.8,0.1525,0.1,-0.8\n" + ROW
    r = run("plan", "--batch", "-", "--json", "-q", "-j", "1", "--report", str(tmp_path / "r.json"), input=text)
    docs = [json.loads(x) for x in r.stdout.splitlines()]
    assert [d["exit_code"] for d in docs] == [0, 1, 0]
    assert "internal error (TypeError: injected)" in docs[1]["error"]
    assert B  # (the module whose plan_rows answers the row)


# ------------------------------------------------------------------ 6. named pipes without a writer


@pytest.mark.parametrize("what", ["profile", "table"])
def test_a_named_pipe_as_profile_or_table_is_refused_at_once(tmp_path, what):
    """A FIFO with no writer given where a file is read whole blocked forever with no message: exit 1, one line."""
    fifo = tmp_path / "p.fifo"
    os.mkfifo(fifo)
    opt = ["-p", str(fifo)] if what == "profile" else ["--table", str(fifo)]
    r = subprocess.run(_cli("plan", *ADEPT, "-q", "-o", str(tmp_path / "t.csv"), *opt), capture_output=True,
                       text=True, timeout=CAP)
    assert r.returncode == 1
    assert f"{what} {fifo}: a named pipe, not a file" in _one_error_line(r.stderr)


def test_check_of_a_named_pipe_waits_a_bounded_time_and_says_for_what(tmp_path, monkeypatch):
    from pickplace_cli.model import files

    monkeypatch.setattr(files, "PIPE_WAIT_S", 1.5)
    fifo = tmp_path / "t.fifo"
    os.mkfifo(fifo)
    r = run("check", str(fifo), "-q")
    assert r.exit_code == 1
    assert "waiting for a writer on the named pipe" in r.stderr
    assert r.stderr.strip().splitlines()[-1].endswith("a named pipe with no writer: nothing came in 1.5 s (start the "
                                                      "program that writes it first, or give a file)")


def test_check_of_a_named_pipe_with_a_writer_reads_it(tmp_path):
    """The same FIFO with a writer (as `check <(pickplace plan …)`) is checked like the file the writer writes."""
    traj = tmp_path / "traj.csv"
    assert run("plan", *ADEPT, "-q", "-o", str(traj)).exit_code == 0
    fifo = tmp_path / "t.fifo"
    os.mkfifo(fifo)

    def write() -> None:
        with open(fifo, "w") as fh:
            fh.write(traj.read_text())

    t = threading.Thread(target=write, daemon=True)
    t.start()
    r = subprocess.run(_cli("check", str(fifo), "--report", str(tmp_path / "a.json"), "-q"), capture_output=True,
                       text=True, timeout=CAP)
    t.join(CAP)
    assert r.returncode == 0, r.stderr
    ref = subprocess.run(_cli("check", str(traj), "--report", str(tmp_path / "b.json"), "-q"), capture_output=True,
                         text=True, timeout=CAP)
    assert ref.returncode == 0
    a, b = (json.loads((tmp_path / n).read_text())["limits"] for n in ("a.json", "b.json"))
    assert a["rows"] == b["rows"]


# ------------------------------------------------------------------ 7. workers die with their parent


def _big_batch(tmp_path: Path, n: int = 3000) -> Path:
    src = tmp_path / "big.csv"
    src.write_text(HEADER + "".join(f"{-0.15 + 0.0001 * (i % 50)},0,-0.8,0.15,{0.0002 * (i % 30)},-0.79\n"
                                    for i in range(n)))
    return src


@pytest.mark.skipif(not os.path.isdir("/proc"), reason="reads the process table from /proc")
@pytest.mark.parametrize("how", ["SIGKILL", "SIGTERM with no reader of stderr"])
def test_workers_die_with_their_parent(tmp_path, how):
    """The main process of `plan --batch -j 2` killed by SIGKILL (a supervisor, the OOM killer), or given SIGTERM
    while nobody reads its stderr: both workers are gone within 5 s (they were re-parented and ran on for minutes,
    holding the stderr pipe open, so `… 2>&1 | tee log` never ended)."""
    src = _big_batch(tmp_path)
    r, w = os.pipe()
    proc = subprocess.Popen(_cli("plan", "--batch", str(src), "-q", "-j", "2", "-o", str(tmp_path / "o.csv")),
                            stdout=subprocess.DEVNULL, stderr=w, start_new_session=True)
    os.close(w)
    if how != "SIGKILL":
        os.close(r)  # no reader: a write to stderr fails
    try:
        deadline = time.monotonic() + CAP
        while len(kids := children(proc.pid)) < 2:
            assert proc.poll() is None and time.monotonic() < deadline
            time.sleep(0.02)
        proc.send_signal(signal.SIGKILL if how == "SIGKILL" else signal.SIGTERM)
        proc.wait(CAP)
        gone_by = time.monotonic() + 5.0
        while any(alive(k) for k in kids):
            assert time.monotonic() < gone_by, f"workers {kids} outlived their parent"
            time.sleep(0.02)
        assert not list(tmp_path.glob(".o.csv.*")) or how == "SIGKILL"  # (SIGKILL: no handler can remove it)
    finally:
        kill_group(proc)
        if how == "SIGKILL":
            os.close(r)


# ------------------------------------------------------------------ 8. quotes in a checked CSV


@pytest.mark.parametrize("cell", ['"' + "x" * 140_000, '"abc,'])
def test_check_a_csv_with_an_open_quote_is_one_short_line(tmp_path, cell):
    """A field over csv's 131,072-character limit was a `_csv.Error` traceback; a shorter open quote swallowed the
    rest of the file and echoed it (19 kB) in the "one-line" error: one line under 300 characters naming the line."""
    traj = tmp_path / "traj.csv"
    assert run("plan", *ADEPT, "-q", "-o", str(traj)).exit_code == 0
    lines = traj.read_text().splitlines()
    bad = tmp_path / "bad.csv"
    bad.write_text("\n".join(lines[:3] + [cell] + lines[3:]) + "\n")
    r = run("check", str(bad))
    assert r.exit_code == 1
    line = _one_error_line(r.stderr)
    assert line.startswith(f"pickplace: error: {bad}:4: not a CSV row") and len(line) < 300 + len(str(bad))


# ------------------------------------------------------------------ 9. control characters in a profile


@pytest.mark.parametrize("char", ["\x0b", "\x0c", "\x07", "\ufffe"])
def test_a_profile_with_a_control_character_is_one_line_and_one_json_document(tmp_path, char):
    prof = tmp_path / "p.yaml"
    text = resolve_profile_path("delta-su2018").read_text().replace("name: delta-su2018", f"name: delta{char}su2018")
    prof.write_text(text, encoding="utf-8")
    r = run("plan", *ADEPT, "-p", str(prof), "--json")
    assert r.exit_code == 1
    line = _one_error_line(r.stderr)
    at = next(n for n, row in enumerate(text.splitlines(), 1) if row.startswith("name: delta"))
    assert f"{prof}:{at}: not valid YAML: the character U+{ord(char):04X} is not allowed" in line
    doc = json.loads(r.stdout)
    assert doc["exit_code"] == 1 and "U+" in doc["error"]


# ------------------------------------------------------------------ 10. memory


def _limit_memory(nbytes: int):
    def apply() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (nbytes, nbytes))

    return apply


@pytest.mark.slow
def test_out_of_memory_is_the_rows_one_line_and_the_others_are_answered(tmp_path):
    """Under a 1 GB address-space limit, a 999 s move at 1 kHz cannot be planned: that row's one line names it and
    its size; the rows before and after are planned (it was a numpy _ArrayMemoryError traceback for the batch)."""
    src = tmp_path / "oom.csv"
    src.write_text("from_x,from_y,from_z,to_x,to_y,to_z,time\n" + "-0.1525,0,-0.8,0.1525,0,-0.8,auto\n"
                   "-0.1525,0,-0.8,0.1525,0,-0.8,999\n" + "-0.1525,0,-0.8,0.1525,0,-0.8,auto\n")
    r = subprocess.run(_cli("plan", "--batch", str(src), "--json", "--report", str(tmp_path / "r.json"), "-q"),
                       capture_output=True, text=True, timeout=10 * CAP, preexec_fn=_limit_memory(1 << 30))
    docs = [json.loads(x) for x in r.stdout.splitlines()]
    assert [d["exit_code"] for d in docs] == [0, 1, 0], r.stderr
    assert "out of memory planning this move (999 s at 1000 Hz: 999,001 samples" in docs[1]["error"]
    assert "Traceback" not in r.stderr and r.returncode == 1


@pytest.mark.slow
def test_a_batch_holds_one_rows_trajectory_at_a_time(tmp_path):
    """Peak memory (the kernel's ru_maxrss of the process) of a batch of 4 long rows written to CSV stays within 1.5×
    that of the same batch's first row alone (it held every row's samples until the end: ~4×). The factor leaves
    room for the allocator's fragmentation; each row is 60 s at 1 kHz (~60,000 samples, tens of MB)."""
    line = "-0.1525,0,-0.8,0.1525,0,-0.8,60\n"

    def peak(n: int) -> int:
        src = tmp_path / f"b{n}.csv"
        src.write_text("from_x,from_y,from_z,to_x,to_y,to_z,time\n" + line * n)
        code = ("import resource, sys; from pickplace_cli.__main__ import main; sys.argv = ['pickplace'] + sys.argv[1:]\n"
                "try:\n    main()\nexcept SystemExit:\n    pass\n"
                "sys.__stdout__.write(str(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss))")
        r = subprocess.run([sys.executable, "-c", code, "plan", "--batch", str(src), "-q", "-j", "1", "-o",
                            str(tmp_path / f"o{n}.csv")], capture_output=True, text=True, timeout=10 * CAP)
        assert (tmp_path / f"o{n}.csv").exists(), r.stderr
        return int(r.stdout.strip().splitlines()[-1])

    one, four = peak(1), peak(4)
    assert four < 1.5 * one, (one, four)


# ------------------------------------------------------------------ 11. a full disk


def _limit_file_size(nbytes: int):
    def apply() -> None:  # Python ignores SIGXFSZ: a write past the limit fails with EFBIG, as a full disk with ENOSPC
        resource.setrlimit(resource.RLIMIT_FSIZE, (nbytes, nbytes))

    return apply


def test_build_table_on_a_full_disk_names_its_checkpoint_and_removes_it(tmp_path):
    """A checkpoint write that fails (here: the file-size limit, as a full disk) was "I/O error: No space left on
    device" with no file named, and left the checkpoint: now one line naming it, the checkpoint removed, the old
    table untouched."""
    out = tmp_path / "t.csv"
    out.write_text("old table\n")
    r = subprocess.run(_cli("build-table", *GRID, "-q", "-j", "1", "-o", str(out)), capture_output=True, text=True,
                       timeout=10 * CAP, preexec_fn=_limit_file_size(1500))
    assert r.returncode == 1
    line = _one_error_line(r.stderr)
    assert f"checkpoint {out}.partial.jsonl: write failed" in line and "the checkpoint is removed" in line
    assert out.read_text() == "old table\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.csv"]


def test_a_streamed_json_batch_on_a_full_disk_says_why_on_stdout(tmp_path):
    """`--json -o FILE` of a stream answered row 1 and then stopped with nothing on stdout saying why: the last JSON
    document now carries the error (exit 1), stderr has the one line, the old file is kept."""
    out = tmp_path / "o.csv"
    out.write_text("old\n")
    r = subprocess.run(_cli("plan", "--batch", "-", "--json", "-q", "-o", str(out)), input=HEADER + ROW * 3,
                       capture_output=True, text=True, timeout=CAP, preexec_fn=_limit_file_size(30_000))
    assert r.returncode == 1
    docs = [json.loads(x) for x in r.stdout.splitlines()]
    assert docs[0]["row"] == 1 and "row" not in docs[-1]
    assert docs[-1]["exit_code"] == 1 and f"output {out}: write failed" in docs[-1]["error"]
    assert f"output {out}: write failed" in _one_error_line(r.stderr)
    assert out.read_text() == "old\n" and sorted(p.name for p in tmp_path.iterdir()) == ["o.csv"]
