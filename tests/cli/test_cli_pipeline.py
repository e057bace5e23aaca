"""Pipelines: --batch (row numbers, per-row errors, --fail-fast, worst exit code), --round-trip, --json,
usage errors, shell completion. Values are compared with the in-memory plan to the printed precision."""

from __future__ import annotations

import csv
import io
import json

import numpy as np
import pytest
from typer.testing import CliRunner

from pickplace_cli.pipelines.batch import read_batch_text
from pickplace_cli.cli import app
from pickplace_cli.planner import PlanOptions, plan
from pickplace_cli.model.profile import load_profile
from pickplace_cli.model.task import Task

runner = CliRunner()
ADEPT = ["--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8"]

BATCH = """from_x,from_y,from_z,to_x,to_y,to_z,height,time
-0.1525,0,-0.8,0.1525,0,-0.8,,
0.1,0.1,-0.8,-0.1,-0.1,-0.8,0.03,0.2
# a comment line, skipped
0,0,-0.8,0.3,0,-0.8,0.000001,
0,0,-0.8,0.1,0,-0.8,,0.01
1,2,x,4,5,6,,
-0.1525,0,-0.8,0.1525,0,-0.8,,fit
"""


def run(*args, input=None):
    return runner.invoke(app, list(args), input=input, catch_exceptions=False)


def parse(text: str) -> tuple[list[str], np.ndarray]:
    rows = list(csv.reader(io.StringIO(text)))
    return rows[0], np.array(rows[1:], float)


def test_batch_reports_rows_plans_the_rest_and_exits_with_the_worst(tmp_path):
    src = tmp_path / "moves.csv"
    src.write_text(BATCH)
    out = tmp_path / "out.csv"
    r = run("plan", "--batch", str(src), "-o", str(out))
    # row 3: λ = 0.3/1e-6 = 3e5, beyond any (k1, k2) optimum (1), row 4: 10 ms is far too fast (3), row 5: not a number (1)
    assert r.exit_code == 3
    err = r.stderr
    assert f"row 3 ({src}:5)" in err and "where the optimal (k1, k2) can be solved" in err
    assert f"row 4 ({src}:6): limit exceeded" in err
    assert f"row 5 ({src}:7): from_z = 'x': not a number" in err
    assert "batch: 6 rows, 3 ok, 3 failed (first failing row 3); 3 written" in err
    header, data = parse(out.read_text())
    assert header[0] == "move[-]" and header[1] == "t[s]"
    assert sorted(set(data[:, 0].astype(int))) == [1, 2, 6]
    # each move keeps its own time from 0 s; row 2 was given 0.2 s
    for move in (1, 2, 6):
        t = data[data[:, 0] == move, 1]
        assert t[0] == 0.0 and np.all(np.diff(t) > 0)
    assert data[data[:, 0] == 2, 1][-1] == pytest.approx(0.2, abs=1e-12)
    # move 1 equals the single plan to the printed precision (12 significant digits)
    prof = load_profile("delta-su2018")
    single = plan(Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5), prof, PlanOptions(fit=False))
    m1 = data[data[:, 0] == 1, 1:]
    assert m1.shape[0] == len(single.t)
    np.testing.assert_allclose(m1[:, 0], single.t, rtol=1e-11, atol=1e-15)
    np.testing.assert_allclose(m1[:, 1:4], single.p, rtol=1e-11, atol=1e-14)
    np.testing.assert_allclose(m1[:, 13], single.joint.q[:, 0], rtol=1e-11, atol=1e-14)


def test_batch_fail_fast_stops_at_the_first_failing_row_from_stdin(tmp_path):
    out = tmp_path / "out.csv"
    r = run("plan", "--batch", "-", "--fail-fast", "-o", str(out), input=BATCH)
    assert r.exit_code == 1
    assert "row 3 (stdin:5)" in r.stderr and "row 4" not in r.stderr and "row 5" not in r.stderr
    _, data = parse(out.read_text())
    assert sorted(set(data[:, 0].astype(int))) == [1, 2]


def test_batch_json_lines_one_per_row():
    r = run("plan", "--batch", "-", "--json", "-q", input=BATCH)
    assert r.exit_code == 3
    docs = [json.loads(line) for line in r.stdout.splitlines()]
    assert [d["row"] for d in docs] == [1, 2, 3, 4, 5, 6]
    assert [d["exit_code"] for d in docs] == [0, 0, 1, 3, 1, 0]
    assert docs[1]["duration_s"] == pytest.approx(0.2)
    assert docs[5]["mode"] == "fit" and docs[5]["duration_s"] == pytest.approx(docs[5]["fit_s"])
    assert docs[3]["violations"] and docs[3]["limits_ok"] is False


def test_batch_report_only_writes_limit_rows_but_not_broken_ones(tmp_path):
    text = "from_x,from_y,from_z,to_x,to_y,to_z,time\n-0.1525,0,-0.8,0.1525,0,-0.8,0.05\n0.1,0,-0.8,0.2,0,-0.8,\n"
    out = tmp_path / "o.csv"
    r = run("plan", "--batch", "-", "--report-only", "-o", str(out), input=text)
    assert r.exit_code == 0 and "row 1" in r.stderr and "limit exceeded" in r.stderr
    _, data = parse(out.read_text())
    assert sorted(set(data[:, 0].astype(int))) == [1, 2]


@pytest.mark.parametrize("source", ["file", "stdin", "-j2"])
def test_write_anyway_never_writes_a_workcell_row(tmp_path, source):
    """A move that leaves the workcell box (exit 4) is not a trajectory a drive may run: --write-anyway (which
    writes moves past a timed limit) does not write it, in a single plan or a batch, and the batch exits 4; the
    batch's good rows are written."""
    move = ["--from", "-0.1,0,-0.575", "--to", "0.1,0,-0.575", "--height", "0.03"]
    single = run("plan", *move, "-q", "--write-anyway", "-o", str(tmp_path / "one.csv"))
    assert single.exit_code == 4 and "workcell z" in single.stderr and not (tmp_path / "one.csv").exists()
    row = "-0.1,0,-0.575,0.1,0,-0.575,0.03\n"
    good = "-0.1525,0,-0.8,0.1525,0,-0.8,\n"
    text = "from_x,from_y,from_z,to_x,to_y,to_z,height\n" + row + good
    f = tmp_path / "b.csv"
    f.write_text(text)
    out = tmp_path / "o.csv"
    args = {"file": [str(f)], "stdin": ["-"], "-j2": [str(f), "-j", "2"]}[source]
    r = run("plan", "--batch", *args, "-q", "--write-anyway", "-o", str(out), input=text if source == "stdin" else None)
    assert r.exit_code == 4, r.stderr
    assert "row 1" in r.stderr and "workcell z" in r.stderr
    _, data = parse(out.read_text())
    assert sorted(set(data[:, 0].astype(int))) == [2]
    # --fail-fast stops at that row: the rows after it are not planned, and the exit code is that row's
    r = run("plan", "--batch", *args, "-q", "--write-anyway", "--fail-fast", "-o", str(out),
            input=text if source == "stdin" else None)
    assert r.exit_code == 4, r.stderr


@pytest.mark.parametrize(
    "text, message",
    [
        ("from_x,from_y,from_z,to_x,to_y\n", "column 'to_z' is missing"),
        ("from_x,from_y,from_z,to_x,to_y,to_z,speed\n", "column 'speed' is not known"),
        ("", "no header row"),
    ],
)
def test_batch_bad_header_is_one_line_exit_1(text, message):
    r = run("plan", "--batch", "-", input=text)
    assert r.exit_code == 1
    assert message in r.stderr and len(r.stderr.strip().splitlines()) == 1


def test_batch_row_cell_count():
    rows, bad = read_batch_text("from_x,from_y,from_z,to_x,to_y,to_z\n1,2,3\n")
    assert not rows and bad[0].row == 1 and "has 3 cells, the header has 6" in bad[0].error


def test_round_trip_is_one_cycle_with_dwells():
    r = run("plan", *ADEPT, "--round-trip", "-q")
    assert r.exit_code == 0, r.stderr
    header, data = parse(r.stdout)
    assert header[0] == "move[-]"
    t, x = data[:, 1], data[:, 2]
    prof = load_profile("delta-su2018")
    dwell = prof.planning.dwell
    single = plan(Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5), prof)
    T = single.duration.seconds
    assert np.all(np.diff(t) > 0)
    assert t[-1] == pytest.approx(2 * T + 2 * dwell, abs=1e-12)
    # at rest at the place point during the first dwell, back at the pick point at the end
    during = (t > T + 1e-9) & (t < T + dwell - 1e-9)
    assert during.any() and np.allclose(x[during], 0.1525, atol=1e-12)
    assert np.allclose(data[during, 5:14], 0.0)  # v, a, j = 0
    assert x[-1] == pytest.approx(-0.1525, abs=1e-12)
    assert set(data[:, 0].astype(int)) == {1, 2}


def test_round_trip_json_summary_counts_both_legs():
    r = run("plan", *ADEPT, "--round-trip", "--json", "-q")
    assert r.exit_code == 0
    doc = json.loads(r.stdout)
    legs = doc["moves"]
    assert len(legs) == 2
    cycle = legs[0]["duration_s"] + legs[1]["duration_s"] + 2 * 0.1
    assert doc["cycle_time_s"] == pytest.approx(cycle) and doc["picks_per_minute"] == pytest.approx(60 / cycle)


def test_json_summary_on_stdout_trajectory_only_to_a_file(tmp_path):
    r = run("plan", *ADEPT, "--json")
    assert r.exit_code == 0
    doc = json.loads(r.stdout)  # stdout is only the JSON document
    assert doc["limits_ok"] is True and doc["exit_code"] == 0
    assert doc["cycle_time_s"] == pytest.approx(2 * (doc["duration_s"] + 0.1))
    out = tmp_path / "t.csv"
    r = run("plan", *ADEPT, "--json", "-o", str(out))
    assert r.exit_code == 0 and out.read_text().startswith("t[s],")


@pytest.mark.parametrize(
    "args",
    [
        ["--to", "0,0,-0.8"],
        ["--batch", "x.csv", *ADEPT],
        ["--batch", "x.csv", "--round-trip"],
        [*ADEPT, "--fail-fast"],
        [*ADEPT, "--json", "-o", "-"],
    ],
)
def test_usage_errors_exit_2(args):
    r = run("plan", *args)
    assert r.exit_code == 2


@pytest.mark.parametrize(
    "args, says",
    [
        (["--compression", "zstd"], "--compression zstd only applies to --format mcap"),
        (["--mcap-flavor", "foxglove"], "--mcap-flavor foxglove only applies to --format mcap"),
        (["--mcap-flavor", "foxglove", "-f", "json"], "--mcap-flavor foxglove only applies to --format mcap"),
        (["--format", "json", "--csv-dialect", "tsv"], "--csv-dialect tsv only applies to --format csv"),
        (["-j", "2"], "-j/--workers only applies to --batch"),
        (["--max-shift", "0.02"], "--max-shift only applies with --adjust-points"),
        (["--adjust-points"], "--adjust-points only applies with --fit-workspace"),
        (["--json", "-f", "mcap"], "with --json and no -o FILE no trajectory is written"),
        (["--json", "--report", "-"], "--report -: with --json stdout carries the summary"),
    ],
)
def test_options_that_do_not_apply_are_usage_errors(args, says, tmp_path):
    """An option that has no effect in this combination is a mistake (exit 2, one message), never ignored;
    nothing is written."""
    out = tmp_path / "x.out"
    to_file = [] if "no -o FILE" in says else ["-o", str(out)]
    r = run("plan", *ADEPT, *args, *to_file)
    assert r.exit_code == 2 and says in r.stderr and not out.exists() and r.stdout == ""


def test_batch_options_that_do_not_apply_are_usage_errors(tmp_path):
    moves = tmp_path / "m.csv"
    moves.write_text("from_x,from_y,from_z,to_x,to_y,to_z\n-0.1525,0,-0.8,0.1525,0,-0.8\n")
    for args, says in ((["--v-from", "0.3,0,0"], "--v-from/--v-to: with --batch give the velocities"),
                       (["--adjust-points"], "--adjust-points only applies with --fit-workspace")):
        r = run("plan", "--batch", str(moves), "--json", *args)
        assert r.exit_code == 2 and says in r.stderr and r.stdout == "", args


def test_format_options_that_apply_or_keep_their_default_are_accepted(tmp_path):
    """The rule: a non-default value where the option has no effect is refused; the default value itself
    (e.g. written out by a script) is accepted."""
    for args in (["-f", "mcap", "--compression", "zstd", "--mcap-flavor", "foxglove"], ["--csv-dialect", "tsv"],
                 ["--compression", "none"], ["--csv-dialect", "default", "-f", "mcap"],
                 ["--mcap-flavor", "ros2"], ["-j", "0"], ["--max-shift", "0.01"]):
        r = run("plan", *ADEPT, *args, "-q", "-o", str(tmp_path / "x.out"))
        assert r.exit_code == 0, (args, r.stderr)


def test_shell_completion_script_and_profile_names(monkeypatch):
    # name the shell: without it Typer detects the parent shell, and a run without one (a CI job, a
    # background run) gets "Shell  not supported"
    monkeypatch.setenv("_TYPER_COMPLETE_TEST_DISABLE_SHELL_DETECTION", "1")
    r = run("--show-completion", "bash")
    assert r.exit_code == 0 and "complete" in r.stdout and "pickplace" in r.stdout.lower()
    from pickplace_cli.cli.app import _complete_profile

    assert set(_complete_profile("")) >= {"delta-su2018", "scara-600", "gantry"}
    assert _complete_profile("sc") == ["scara-600"]


def test_method_parameters_by_name():
    r = run("plan", *ADEPT, "--method", "ph", "--param", "m=0.02", "--param", "r=0.1", "--json", "--report-only", "-q")
    assert r.exit_code == 0
    par = json.loads(r.stdout)["parameters"]
    assert par["m"] == pytest.approx(0.02) and par["r"] == pytest.approx(0.1)
    r = run("plan", *ADEPT, "--method", "ph", "--param", "q=1")
    assert r.exit_code == 1 and "method ph has no parameter 'q'" in r.stderr
    r = run("plan", *ADEPT, "--param", "m")
    assert r.exit_code == 1 and "write NAME=VALUE" in r.stderr
    r = run("plan", *ADEPT, "--method", "ph", "--k1", "0.3", "--k2", "0.1")
    assert r.exit_code == 2


def test_fit_workspace_lowers_the_height_and_says_so():
    # 0.3 m up would cross the workcell's top (z = -0.55 m): refused without, lowered with --fit-workspace
    r = run("plan", *ADEPT, "--height", "0.3", "-q")
    assert r.exit_code == 4 and "workcell z" in r.stderr
    r = run("plan", *ADEPT, "--height", "0.3", "--fit-workspace", "--json", "-q")
    assert r.exit_code == 0, r.stderr
    assert "height lowered from 0.3 m to" in r.stderr
    doc = json.loads(r.stdout)
    assert doc["height_m"] < 0.3 and doc["limits_ok"] and "workspace_fit" in doc


def test_a_point_outside_is_refused_and_adjusted_only_when_asked():
    far = ["--from", "-0.7,0,-0.8", "--to", "0.1525,0,-0.8"]
    r = run("plan", *far, "--fit-workspace", "-q")
    assert r.exit_code == 4 and "--adjust-points" in r.stderr and r.stdout == ""
    r = run("plan", *far, "--fit-workspace", "--adjust-points", "-q")
    assert r.exit_code == 4 and "more than max_shift" in r.stderr  # 0.13 m is too far to move a part
    r = run("plan", *ADEPT, "--adjust-points")
    assert r.exit_code == 2


def test_batch_on_two_processes_writes_the_same_bytes(tmp_path):
    rng = np.random.default_rng(3)
    lines = ["from_x,from_y,from_z,to_x,to_y,to_z"]
    for i in range(60):
        a, b = rng.uniform(-0.2, 0.2, 2), rng.uniform(-0.2, 0.2, 2)
        lines.append(f"{a[0]:.4f},{a[1]:.4f},-0.8,{b[0]:.4f},{b[1]:.4f},-0.8" if i != 30 else "0,0,-0.8,9,0,-0.8")
    src = tmp_path / "m.csv"
    src.write_text("\n".join(lines) + "\n")
    outs = []
    for j in ("1", "2"):
        out = tmp_path / f"o{j}.csv"
        r = run("plan", "--batch", str(src), "-j", j, "-o", str(out), "-q")
        assert r.exit_code in (1, 3, 4) and "row 31 " in r.stderr  # 9 m away: unreachable (4); others may break limits
        outs.append(out.read_bytes())
    assert outs[0] == outs[1] and len(outs[0]) > 0


def test_end_velocities_need_the_velocity_method():
    """Moving ends are planned by bspline-vel: chosen when -m is not given (as --to-belt does), a rest-to-rest
    method named with -m refused."""
    moving = ["--from", "0,0,-0.8", "--to", "0.28,-0.2,-0.8", "--height", "0.04", "--v-from", "0,0.2,0", "--v-to", "0,0.2,0"]
    r = run("plan", *moving, "--method", "bspline")
    assert r.exit_code == 1 and "use --method bspline-vel" in r.stderr
    r = run("plan", *moving, "--time", "0.25", "--report-only", "-q")
    assert r.exit_code == 0 and r.stdout == run("plan", *moving, "--method", "bspline-vel", "--time", "0.25",
                                                "--report-only", "-q").stdout
    r = run("plan", *moving, "--method", "bspline-vel", "--time", "0.25", "--report-only", "-q")
    assert r.exit_code == 0, r.stderr
    header, data = parse(r.stdout)
    v = data[:, 4:7]
    # Yang 2022 Eq. 24: the end velocities are met exactly (to the printed precision)
    np.testing.assert_allclose(v[0], [0, 0.2, 0], atol=1e-11)
    np.testing.assert_allclose(v[-1], [0, 0.2, 0], atol=1e-11)
    r = run("plan", *moving, "--method", "bspline-vel", "--round-trip")
    assert r.exit_code == 2
    r = run("plan", *moving[:6], "--v-from", "0,0.2", "--method", "bspline-vel")
    assert r.exit_code == 1 and "three components X,Y,Z in m/s" in r.stderr


def test_build_table_bspline_vel_options():
    r = run("build-table", "--method", "bspline-vel", "--format", "st")
    assert r.exit_code == 2
