"""table.run_build as an engine: process pool and Dask give the sequential result, chunking, checkpoints,
resume after SIGKILL / Ctrl-C without recomputing finished rows, and never a half-written table."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from pickplace_cli.lookup import bspline_table as T
from pickplace_cli.lookup import bspline_build as T_build
from pickplace_cli.lookup import bspline_optimum as T_optimum
from pickplace_cli.model.errors import TableError

LAMS = [1.0, 1.5, 7.0, 28.0, 40.0]  # both F maxima at λ = 1, the a_min-on-the-floor case, large λ


@pytest.fixture(scope="module")
def sequential():
    return T_build.build_table(LAMS, T_optimum.TableSettings())


def test_process_pool_equals_sequential(sequential):
    """Rows do not depend on each other or on the chunking: bit-identical with 2 processes."""
    table, report = T_build.run_build(LAMS, T_optimum.TableSettings(), workers=2)
    assert table.rows == sequential.rows
    assert report.computed == len(LAMS) and report.tasks == len(LAMS)  # 8 chunks per worker, capped by λ


def test_chunks_interleave_and_cover_every_lambda_once():
    lams = [float(x) for x in range(1, 80)]
    chunks = T_build._chunks(lams, 16)
    assert len(chunks) == 16 and sorted(x for c in chunks for x in c) == lams
    assert chunks[0][:3] == (1.0, 17.0, 33.0)  # interleaved: every chunk gets some small-λ rows
    assert max(map(len, chunks)) - min(map(len, chunks)) <= 1
    assert T_build._chunks(lams[:3], 16) == [(1.0,), (2.0,), (3.0,)]


def test_progress_counts_rows():
    seen = []
    T_build.run_build(LAMS[:2], T_optimum.TableSettings(), progress=lambda d, t: seen.append((d, t)))
    assert seen == [(0, 2), (1, 2), (2, 2)]


def test_dask_local_cluster_equals_local(sequential):
    """The same build through Dask's concurrent.futures executor on a LocalCluster (threads, so the
    test stays fast; a real cluster runs the same tasks in worker processes)."""
    distributed = pytest.importorskip("distributed")
    from pickplace_cli.lookup.executors import dask_executor

    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None) as cluster:
        with dask_executor(cluster.scheduler_address) as (executor, threads):
            assert threads == 2
            table, report = T_build.run_build(LAMS, T_optimum.TableSettings(), workers=threads, executor=executor)
    assert table.rows == sequential.rows
    assert report.computed == len(LAMS)


def test_dask_unreachable_scheduler_is_one_line():
    pytest.importorskip("distributed")
    from pickplace_cli.lookup.executors import dask_executor

    with pytest.raises(TableError, match=r"^scheduler = tcp://127.0.0.1:9: cannot reach the Dask scheduler within 0.5 s") as exc:
        with dask_executor("tcp://127.0.0.1:9", timeout=0.5):
            pass  # pragma: no cover
    assert "\n" not in str(exc.value)


def test_dask_not_installed(monkeypatch):
    from pickplace_cli.lookup.executors import dask_executor

    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed → ImportError
    with pytest.raises(TableError, match=r"Dask is not installed; install the extra: pip install 'pickplace-cli\[dask\]'"):
        with dask_executor("tcp://127.0.0.1:8786"):
            pass  # pragma: no cover


# ------------------------------------------------------------------------------------------ checkpoints


def _count_optimise_calls(monkeypatch) -> list[float]:
    calls: list[float] = []
    real = T_optimum.optimise_lambda

    def counting(lam, coarse, settings):
        calls.append(lam)
        return real(lam, coarse, settings)

    monkeypatch.setattr(T_optimum, "optimise_lambda", counting)  # what a chunk calls
    monkeypatch.setattr(T_build, "optimise_lambda", counting)  # what the build calls itself
    return calls


def test_checkpoint_round_trip_and_resume_skips_finished_rows(tmp_path, monkeypatch, sequential):
    ckpt = tmp_path / "t.csv.partial.jsonl"
    T_build.run_build(LAMS[:2], T_optimum.TableSettings(), checkpoint=ckpt)
    saved = T_build.read_checkpoint(ckpt, T_optimum.TableSettings())
    assert [saved[x] for x in LAMS[:2]] == list(sequential.rows[:2])  # floats read back bit for bit
    calls = _count_optimise_calls(monkeypatch)
    table, report = T_build.run_build(LAMS, T_optimum.TableSettings(), checkpoint=ckpt, resume=True)
    assert calls == LAMS[2:]
    assert (report.resumed, report.computed) == (2, 3)
    assert table.rows == sequential.rows
    assert set(T_build.read_checkpoint(ckpt, T_optimum.TableSettings())) == set(LAMS)  # new rows appended


def test_resume_refuses_a_checkpoint_of_other_settings(tmp_path):
    ckpt = tmp_path / "t.csv.partial.jsonl"
    T_build.run_build([27.5, 28.0], T_optimum.TableSettings(), checkpoint=ckpt)
    with pytest.raises(TableError, match=r"written for other settings .*run without --resume"):
        T_build.run_build([28.0], T_optimum.TableSettings(grid_step=0.02), checkpoint=ckpt, resume=True)
    with pytest.raises(TableError, match="other settings"):
        T_build.run_build([28.0], T_optimum.TableSettings(weights=(0.4, 0.6)), checkpoint=ckpt, resume=True)
    # without --resume the old file is simply replaced
    T_build.run_build([27.5, 28.0], T_optimum.TableSettings(grid_step=0.02), checkpoint=ckpt)
    assert json.loads(ckpt.read_text().splitlines()[0])["settings"]["grid_step"] == 0.02


def test_checkpoint_with_a_cut_last_line_and_corrupt_files(tmp_path, sequential):
    ckpt = tmp_path / "c.partial.jsonl"
    T_build.run_build(LAMS[:2], T_optimum.TableSettings(), checkpoint=ckpt)
    text = ckpt.read_text()
    ckpt.write_text(text[:-40])  # killed while writing the last row
    assert list(T_build.read_checkpoint(ckpt, T_optimum.TableSettings())) == [LAMS[0]]
    table, report = T_build.run_build(LAMS[:2], T_optimum.TableSettings(), checkpoint=ckpt, resume=True)  # appends after the cut
    assert (report.resumed, report.computed) == (1, 1) and table.rows == sequential.rows[:2]
    assert list(T_build.read_checkpoint(ckpt, T_optimum.TableSettings())) == LAMS[:2]
    lines = text.splitlines()
    ckpt.write_text("\n".join([lines[0], "garbage", lines[2]]) + "\n")
    with pytest.raises(TableError, match=r"c.partial.jsonl:2: not a table row"):
        T_build.read_checkpoint(ckpt, T_optimum.TableSettings())
    ckpt.write_text("lambda,k1\n")
    with pytest.raises(TableError, match="not a pickplace build-table checkpoint header"):
        T_build.read_checkpoint(ckpt, T_optimum.TableSettings())


GRID = ["--lambda-min", "1", "--lambda-max", "12", "--lambda-step", "0.5"]  # 23 rows, ~1.5 s of work


#: 391 rows, ~10 s with 2 workers: a build that is interrupted must still be running when its first rows
#: are checkpointed, with seconds to spare however fast the machine or the build is
LONG_GRID = ["--lambda-min", "1", "--lambda-max", "40", "--lambda-step", "0.1"]


def _start_build(out: Path, *extra: str, grid: list[str] = GRID) -> subprocess.Popen:
    cmd = [sys.executable, "-m", "pickplace_cli", "build-table", *grid, "-q", "-o", str(out), *extra]
    # the build starts with SIGINT at its default, as a command typed at a terminal does: a test run
    # started in the background by a non-interactive shell (`cmd &`) inherits SIGINT *ignored*, and Python
    # then (rightly) installs no KeyboardInterrupt handler, so Ctrl-C would not reach the build at all
    return subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))


def _wait_for_rows(proc: subprocess.Popen, ckpt: Path, rows: int, timeout: float = 60.0) -> int:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        n = len(ckpt.read_text().splitlines()) - 1 if ckpt.exists() else 0
        if n >= rows:
            return n
        assert proc.poll() is None, f"the build ended before it could be interrupted: {proc.communicate()}"
        time.sleep(0.01)
    raise AssertionError("no checkpointed rows in time")  # pragma: no cover


@pytest.mark.slow
def test_sigkill_then_resume_recomputes_only_missing_rows(tmp_path, monkeypatch):
    """Kill -9 a sequential build after a few rows are checkpointed: the good table already at OUT is
    untouched, the checkpoint holds the finished rows; --resume computes only the others and writes the
    same bytes as a clean build, then removes the checkpoint."""
    from typer.testing import CliRunner

    from pickplace_cli.cli import app

    out = tmp_path / "table.csv"
    out.write_text("a good old table\n")
    ckpt = T_build.checkpoint_path(out)
    proc = _start_build(out, "-j", "1")
    _wait_for_rows(proc, ckpt, 3)
    proc.kill()
    proc.wait()
    assert out.read_text() == "a good old table\n"
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")]
    saved = T_build.read_checkpoint(ckpt, T_optimum.TableSettings())
    assert 3 <= len(saved) < 23

    calls = _count_optimise_calls(monkeypatch)
    res = CliRunner().invoke(app, ["build-table", *GRID, "-j", "1", "--resume", "-o", str(out)])
    assert res.exit_code == 0, res.output
    assert f"{len(saved)} rows resumed from {ckpt}, {23 - len(saved)} computed" in res.output
    assert len(calls) == 23 - len(saved) and not set(calls) & set(saved)
    assert not ckpt.exists()

    clean = tmp_path / "clean.csv"
    res = CliRunner().invoke(app, ["build-table", *GRID, "-j", "1", "-q", "-o", str(clean)])
    assert res.exit_code == 0
    assert out.read_bytes() == clean.read_bytes()


@pytest.mark.slow
def test_ctrl_c_with_worker_pool_saves_rows_and_exits_130(tmp_path):
    """Ctrl-C (SIGINT to the whole process group, as a terminal sends it) during a 2-process build:
    exit 130, one line telling how to resume, the checkpoint is kept, no output file appears."""
    out = tmp_path / "t.csv"
    proc = _start_build(out, "-j", "2", grid=LONG_GRID)
    _wait_for_rows(proc, T_build.checkpoint_path(out), 1)
    os.killpg(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert "run the same command with --resume to continue" in err
    assert "Traceback" not in err
    assert not out.exists()
    assert 1 <= len(T_build.read_checkpoint(T_build.checkpoint_path(out), T_optimum.TableSettings())) < 391


def test_cli_resume_needs_an_output_file():
    from typer.testing import CliRunner

    from pickplace_cli.cli import app

    res = CliRunner().invoke(app, ["build-table", "--resume", "-q"])
    assert res.exit_code == 1
    assert "--resume: needs -o FILE" in res.output


@pytest.mark.parametrize("fmt", ["csv", "json", "st"])
def test_cli_build_table_formats(tmp_path, fmt):
    """--format picks the writer (export.table_json / table_st); the rows are the built ones."""
    from typer.testing import CliRunner

    from pickplace_cli.cli import app

    out = tmp_path / f"t.{fmt}"
    res = CliRunner().invoke(app, ["build-table", "--lambda-min", "27.5", "--lambda-max", "28", "-j", "1", "-q", "-f", fmt, "-o", str(out)])
    assert res.exit_code == 0, res.output
    text = out.read_text()
    ref = T_build.build_table([27.5, 28.0])
    if fmt == "csv":
        assert T.parse_table(text, "t.csv").rows == tuple(
            T_optimum.TableRow(*(float(f"{x:.10g}") for x in (r.lam, r.k1, r.k2, r.a_max, r.j_max, r.v_max, r.F, r.a_min, r.j_min)))
            for r in ref.rows)
    elif fmt == "json":
        assert json.loads(text)["rows"]["k1"] == [r.k1 for r in ref.rows]
    else:
        assert "FUNCTION F_PickplaceK" in text and "PP_TABLE_K1" in text
    assert not T_build.checkpoint_path(out).exists()


def test_fit_of_a_tiny_table_has_a_lower_degree():
    """Fewer rows than a cubic needs: the fit drops to the degree the rows allow (higher g = 0), no warning."""
    import warnings

    tab = T.Table(tuple(T_optimum.TableRow(lam, 0.3 + 0.01 * lam, 0.1, *[float("nan")] * 6) for lam in (27.0, 27.5, 28.0)), {"eta": 0.5})
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        g1, g2, res = tab.fit(5.0)
    assert g1 == pytest.approx([0.3, 0.01, 0.0, 0.0], abs=1e-9) and g1[3] == 0.0 and res < 1e-12
