"""CLI: every command has help; exit codes; one-line errors; atomic outputs; stdout == file bytes."""

from __future__ import annotations

import csv
import io
import json
import subprocess
import sys

import numpy as np
import pytest
from typer.testing import CliRunner

from pickplace_cli import __version__
from pickplace_cli.cli import app

runner = CliRunner()
ADEPT = ["--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8"]


def run(*args):
    return runner.invoke(app, list(args), catch_exceptions=False)


@pytest.mark.parametrize("cmd", [[], ["plan"], ["build-table"]])
def test_help_everywhere(cmd):
    r = run(*cmd, "--help")
    assert r.exit_code == 0 and "Usage" in r.stdout


def test_version():
    r = run("--version")
    assert r.exit_code == 0 and r.stdout.strip() == f"pickplace {__version__}"


def test_plan_adept_csv():
    r = run("plan", *ADEPT)
    assert r.exit_code == 0, r.stderr
    rows = list(csv.reader(io.StringIO(r.stdout)))
    header = rows[0]
    names = [h.split("[")[0] for h in header]
    assert names[:13] == ["t", "x", "y", "z", "vx", "vy", "vz", "ax", "ay", "az", "jx", "jy", "jz"]
    assert names[13:22] == ["q1", "qd1", "qdd1", "q2", "qd2", "qdd2", "q3", "qd3", "qdd3"]
    assert names[22:] == [f"{c}{i}" for i in (1, 2, 3) for c in ("torque", "motor_speed", "motor_torque")]
    assert header[1] == "x[m]" and header[7] == "ax[m/s^2]" and header[13] == "q1[rad]"
    assert header[22] == "torque1[N*m]" and header[23] == "motor_speed1[rad/s]"
    data = np.array(rows[1:], float)
    assert data[0, 0] == 0.0
    t = data[:, 0]
    assert np.all(np.diff(t) > 0) and np.allclose(np.diff(t)[:-1], 1e-3)
    np.testing.assert_allclose(data[0, 1:4], [-0.1525, 0, -0.8], atol=1e-12)
    np.testing.assert_allclose(data[-1, 1:4], [0.1525, 0, -0.8], atol=1e-12)
    assert "duration T" in r.stderr and "λ = 12.2" in r.stderr and "verdict: all limits hold" in r.stderr


def test_last_sample_is_T_and_summary_json():
    r = run("plan", *ADEPT, "--format", "json", "-q")
    assert r.exit_code == 0
    doc = json.loads(r.stdout)
    T = doc["summary"]["duration_s"]
    assert doc["samples"]["t[s]"][-1] == pytest.approx(T, abs=1e-12)
    assert doc["summary"]["binding"] in ("capacity velocity", "capacity acceleration")
    assert r.stderr == ""


def test_explicit_time_rate_k_override():
    r = run("plan", *ADEPT, "--time", "0.25", "--rate", "200", "--k1", "0.31", "--k2", "0.12", "-q")
    assert r.exit_code == 0
    data = np.loadtxt(io.StringIO(r.stdout), delimiter=",", skiprows=1)
    assert data.shape[0] == 51 and data[-1, 0] == pytest.approx(0.25)


def test_stdout_and_file_identical(tmp_path):
    out = tmp_path / "a.csv"
    r1 = run("plan", *ADEPT, "-q")
    r2 = run("plan", *ADEPT, "-q", "-o", str(out))
    assert r2.exit_code == 0 and r2.stdout == ""
    assert out.read_text() == r1.stdout


def test_height_eta_change_the_path():
    # the 1-D table is for η = 0.5: another η is read from the 2-D (λ, η) table (issue 16) and says so
    r = run("plan", *ADEPT, "--height", "0.05", "--eta", "0.4", "--format", "json", "-q")
    assert r.exit_code == 0
    assert json.loads(r.stdout)["summary"]["parameters"]["k_source"] == "2-D table bspline-2d.csv (shipped), interpolated"
    # outside the 2-D table's η range (0.1 … 0.9): solved on demand, and said so
    r = run("plan", *ADEPT, "--height", "0.05", "--eta", "0.05", "--format", "json", "-q")
    assert r.exit_code == 0 and "solved on demand: η outside table" in json.loads(r.stdout)["summary"]["parameters"]["k_source"]
    r = run("plan", *ADEPT, "--height", "0.05", "--eta", "0.4", "--k1", "0.4", "--k2", "0.15", "--format", "json", "-q")
    doc = json.loads(r.stdout)
    assert max(doc["samples"]["z[m]"]) == pytest.approx(-0.75, abs=1e-6)
    assert doc["summary"]["eta"] == 0.4 and doc["summary"]["lambda"] == pytest.approx(6.1)


BAD = [
    (["--from", "nan,0,-0.8", "--to", "0.1,0,-0.8"], "--from 'nan,0,-0.8'"),
    (["--from", "0.1,0,-0.8", "--to", "0.1,0,-0.8"], "end points must differ"),
    ([*ADEPT, "--height", "0"], "--height 0.0"),
    ([*ADEPT, "--height", "-0.1"], "--height -0.1"),
    ([*ADEPT, "--time", "0"], "--time '0'"),
    ([*ADEPT, "--time", "-1"], "--time '-1'"),
    ([*ADEPT, "--eta", "0"], "--eta 0.0"),
    ([*ADEPT, "--eta", "1.2"], "--eta 1.2"),
    ([*ADEPT, "--rate", "0"], "--rate 0.0"),
    ([*ADEPT, "--k1", "0.3"], "give both"),
    ([*ADEPT, "--k1", "1.3", "--k2", "0.1"], "--k1 1.3"),
    (["--from", "1,2", "--to", "0.1,0,-0.8"], "three coordinates"),
    (["--from", "-0.15_25,0,-0.8", "--to", "0.1,0,-0.8"], "--from '-0.15_25,0,-0.8': every coordinate must be a number"),
    ([*ADEPT, "--height", "1e-6"], "lambda = b/h = 3.05e+05: outside [0.001, 100000]"),
    ([*ADEPT, "--rate", "1e9"], "--rate 1000000000.0 Hz: the output rate must lie in (0, 1e6] Hz"),
    ([*ADEPT, "--k1", "1e-300", "--k2", "0.1"], "--k1 1e-300: time-ratio factors must lie in [0.0001, 0.9999]"),
    # inside the k range, but the knot spans are so short that the duration (~2e5 s) needs 1.8e8 samples
    ([*ADEPT, "--k1", "1e-4", "--k2", "0.5"], "at most 1,000,000 per move"),
    # absurd scales (review, session 16: NaN durations, overflow warnings and tracebacks before these bounds)
    (["--from", "-0.1525,0,-0.8", "--to", "0.1525,0,1e200"], "--to 0.1525,0,1e+200: every coordinate must lie within ±1000 m"),
    (["--from", "1e200,0,-0.8", "--to", "0,0,-0.8"], "--from 1e+200,0,-0.8: every coordinate must lie within ±1000 m"),
    (["--from", "1e200,0,-0.8", "--to", "0,0,-0.8", "-p", "scara-600"], "every coordinate must lie within ±1000 m"),
    ([*ADEPT, "--height", "1e200", "--k1", "0.3", "--k2", "0.1"], "--height 1e+200 m: must be at most 1000 m"),
    ([*ADEPT, "--height", "1e170", "-m", "ph"], "--height 1e+170 m: must be at most 1000 m"),
    ([*ADEPT, "--time", "1e-100"], "--time '1e-100': a duration must be at least 1e-06 s"),
    ([*ADEPT, "--time", "1e-100", "--json"], "--time '1e-100': a duration must be at least 1e-06 s"),
    (["--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8", "-m", "bspline-vel", "--v-from", "1e200,0,0"],
     "--v-from 1e+200,0,0: every coordinate must lie within ±1000 m/s"),
]


def test_numerical_warnings_are_one_line():
    """numpy's RuntimeWarnings of a degenerate move (two lines each, Python's way, by the dozen: review, session 16)
    are one line: the first, the others counted; with the error that follows, two lines in all."""
    r = run("plan", *ADEPT, "-m", "lame", "--height", "1e-6", "-q", "-o", "/dev/null")
    assert r.exit_code == 0
    (line,) = r.stderr.splitlines()
    assert line.startswith("pickplace: warning: RuntimeWarning: invalid value encountered in power (lame.py:")
    assert line.endswith("); further warnings not shown")
    r = run("plan", "--from", "-0.1525,0,-0.8", "--to", "-0.1525,1e-9,-0.8", "--height", "1000", "-m", "ph", "-q")
    assert r.exit_code == 1
    lines = r.stderr.splitlines()
    assert len(lines) == 2 and lines[0].startswith("pickplace: warning: RuntimeWarning: ")
    assert lines[1].startswith("pickplace: error: method ph: this move's path has no finite peak speed")


@pytest.mark.parametrize("args,msg", BAD)
def test_bad_input_exit_1_one_line_no_file(tmp_path, args, msg):
    out = tmp_path / "out.csv"
    r = run("plan", *args, "-o", str(out))
    assert r.exit_code == 1
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("pickplace: error: ") and msg in lines[0]
    assert "Traceback" not in r.stderr
    assert not out.exists()
    assert list(tmp_path.iterdir()) == []  # no temp file left either


def test_failed_run_keeps_existing_output(tmp_path):
    out = tmp_path / "keep.csv"
    out.write_text("precious\n")
    r = run("plan", *ADEPT, "--time", "-1", "-o", str(out))
    assert r.exit_code == 1 and out.read_text() == "precious\n"


def test_unknown_profile_key(tmp_path):
    from pickplace_cli.model.profile import resolve_profile_path

    text = resolve_profile_path("gantry").read_text().replace("  eta: 0.5", "  eta: 0.5\n  speed: 3", 1)
    prof = tmp_path / "p.yaml"
    prof.write_text(text)
    r = run("plan", *ADEPT, "--profile", str(prof))
    assert r.exit_code == 1
    line = r.stderr.strip()
    assert "\n" not in line and f"{prof}:" in line and "unknown key 'planning.speed'" in line


@pytest.mark.parametrize(
    "content,msg",
    [(None, "no such file"), ("# eta: 0.5\ngarbage\n1,2\n", "lacks column"), ("lambda,k1,k2\n1,0.2,x\n", "not a number"), ("lambda,k1,k2\n1,0.2,0.1\n2,0.2,0.1\n", "eta")],
)
def test_missing_or_corrupt_table(tmp_path, content, msg):
    tab = tmp_path / "t.csv"
    if content is not None:
        tab.write_text(content)
    r = run("plan", *ADEPT, "--table", str(tab))
    assert r.exit_code == 1 and msg in r.stderr and len(r.stderr.strip().splitlines()) == 1


def test_usage_error_exit_2():
    r = runner.invoke(app, ["plan", "--from", "0,0,0"])
    assert r.exit_code == 2


def test_unreachable_exit_4():
    # the path's top (0.1 + 0.5 m) is above the z travel (0.2 m)
    r = run("plan", "-p", "gantry", "--from", "0.9,0,0.1", "--to", "0.95,0,0.1", "--height", "0.5", "--k1", "0.3", "--k2", "0.1")
    assert r.exit_code == 4
    assert "outside the travel of axis z" in r.stderr and "at t = " in r.stderr


def test_unreachable_end_point_is_exit_4_not_a_table_range():
    """A move the table does not cover because an end point is out of reach: its (k1, k2) are solved on
    demand (issue 16), and the end point is named (exit 4, one line; since session 16 the end itself, not the first
    sample the path loses on the way to it) — never the table's λ range, which would send the user to change
    --height. A λ no optimum covers names the end too."""
    r = run("plan", "--from", "-0.1525,0,-0.8", "--to", "2,0,-0.8")
    assert r.exit_code == 4
    assert r.stderr.strip().startswith("pickplace: error: --to 2,0,-0.8 m: outside the workspace of profile "
                                       "delta-su2018 (Delta: p = (2, 0, -0.8) m is unreachable")
    assert " at t = " in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1
    r = run("plan", "--from", "-0.1525,0,-0.8", "--to", "2,0,-0.8", "--height", "1e-6")
    assert r.exit_code == 4
    assert r.stderr.strip().startswith("pickplace: error: --to 2,0,-0.8 m: outside the workspace of profile delta-su2018")


def test_build_table_small(tmp_path):
    out = tmp_path / "t.csv"
    r = run("build-table", "--lambda-min", "27", "--lambda-max", "28", "--lambda-step", "0.5", "-o", str(out), "-j", "1", "-q")
    assert r.exit_code == 0, r.stderr
    from pickplace_cli.lookup.bspline_table import load_table

    tab = load_table(out)
    assert tab.lam.tolist() == [27.0, 27.5, 28.0]
    assert tab.meta["eta"] == 0.5 and "fit_k1" in tab.meta
    # the plan reads it
    r2 = run("plan", *ADEPT, "--height", str(0.305 / 27.5), "--table", str(out), "-q")
    assert r2.exit_code == 0


@pytest.mark.parametrize(
    "args,msg",
    [
        (["--weights", "0.5,0.6"], "weights"),
        (["--weights", "abc"], "weights"),
        (["--eta", "1"], "eta"),
        (["--lambda-min", "5", "--lambda-max", "2"], "lambda-max"),
        (["--lambda-step", "0"], "lambda-step"),
    ],
)
def test_build_table_bad_input(tmp_path, args, msg):
    out = tmp_path / "t.csv"
    r = run("build-table", *args, "-o", str(out), "-q")
    assert r.exit_code == 1 and msg in r.stderr and not out.exists()


def test_help_imports_no_heavy_modules():
    """`pickplace --help` must not import numpy, scipy, pydantic or mcap (fast start-up)."""
    code = (
        "import sys; from pickplace_cli.cli import app\n"
        "try:\n    app(['--help'])\nexcept SystemExit:\n    pass\n"
        "heavy = [m for m in ('numpy', 'scipy', 'pydantic', 'mcap', 'yaml') if m in sys.modules]\n"
        "print('HEAVY=' + ','.join(heavy))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip().splitlines()[-1] == "HEAVY="


def test_json_exit_code_is_the_process_exit_code():
    """--json: exit_code is what the process returns (0 with --report-only), limits_ok the verdict; without
    -o nothing claims a trajectory was not written."""
    r = run("plan", *ADEPT, "--time", "0.1", "--json", "-q")
    doc = json.loads(r.stdout)
    assert r.exit_code == 3 and doc["exit_code"] == 3 and doc["limits_ok"] is False
    assert "trajectory not written" not in r.stderr
    r = run("plan", *ADEPT, "--time", "0.1", "--json", "-q", "--report-only")
    doc = json.loads(r.stdout)
    assert r.exit_code == 0 and doc["exit_code"] == 0 and doc["limits_ok"] is False


@pytest.mark.parametrize("args, words", [
    (["plan", "--bogus"], "No such option: --bogus"),
    (["bogus"], "No such command 'bogus'"),
    (["plan", "--from"], "Option '--from' requires an argument. (see pickplace --help)"),
])
def test_usage_errors_are_one_line_exit_2(args, words):
    """click's usage errors were four lines (Usage, Try, blank, Error); one line now, like every other error."""
    import subprocess
    import sys

    r = run(*args)
    assert r.exit_code == 2
    (line,) = r.stderr.splitlines()
    assert line.startswith("pickplace: error: ") and words in line
    p = subprocess.run([sys.executable, "-m", "pickplace_cli", *args], capture_output=True, text=True, timeout=60)
    assert p.returncode == 2 and p.stdout == ""
    (line,) = p.stderr.splitlines()
    assert line.startswith("pickplace: error: ") and words in line


@pytest.mark.parametrize("args, line", [
    (["plan", *ADEPT, "--height", "abc"], "--height 'abc': must be a number (see pickplace plan --help)"),
    (["plan", *ADEPT, "--rate=1e3x"], "--rate '1e3x': must be a number (see pickplace plan --help)"),
    (["plan", *ADEPT, "-m", "cubic"], "-m/--method 'cubic': must be one of 'bspline', 'ph', "),
    (["plan", *ADEPT, "-j", "1.5", "--batch", "-"], "-j/--workers '1.5': must be an integer"),
    (["check", "-", "--limit-use", "x"], "--limit-use 'x': must be a number (see pickplace check --help)"),
    (["line", "--seed", "x"], "--seed 'x': must be an integer (see pickplace line --help)"),
])
def test_a_value_a_typed_option_cannot_take_is_invalid_input(args, line):
    """A value that does not parse (a number, an integer, a choice) is invalid input like one out of range (exit 1),
    one line naming the option, the value as given and the rule, in a real process (the value is read from its
    command line), nothing on stdout."""
    import subprocess
    import sys

    p = subprocess.run([sys.executable, "-m", "pickplace_cli", *args], capture_output=True, text=True, timeout=60,
                       stdin=subprocess.DEVNULL)
    assert p.returncode == 1 and p.stdout == ""
    (got,) = p.stderr.splitlines()
    assert got.startswith("pickplace: error: " + line.split(" (see")[0]) and got.endswith(" --help)"), got


def test_a_verdict_says_when_nothing_timed_was_checked():
    """The gantry profile has position and workcell limits and its Cartesian capacity only: at 1 ms (|v| ~ 900 m/s)
    a given duration breaks the capacity (exit 3); the default plans to it. With the capacity not held (a library
    caller's fit-free rule), the verdict names its scope. A Delta's verdict is unchanged."""
    r = run("plan", "-p", "gantry", "--from", "0.1,0.1,-0.1", "--to", "0.4,0.3,-0.1", "--time", "0.001", "-o", "-")
    assert r.exit_code == 3 and "tool capacity speed" in r.stderr
    r = run("plan", "-p", "gantry", "--from", "0.1,0.1,-0.1", "--to", "0.4,0.3,-0.1", "-o", "-")
    assert r.exit_code == 0 and "binding: capacity acceleration" in r.stderr
    r = run("plan", *ADEPT, "-o", "-")
    assert "verdict: all limits hold; cycle" in r.stderr


def test_piped_limit_table_has_no_trailing_spaces(tmp_path):
    """A pipe or log gets whole rows (no wrap at 80 columns) and no padding after the last cell, from plan and from
    check, also when a row's verdict column is wide (a capacity not held)."""
    out = tmp_path / "t.csv"
    r = run("plan", *ADEPT, "--time", "fit", "-o", str(out))
    assert r.exit_code == 0
    rows = [ln for ln in r.stderr.splitlines() if ln.startswith(("q1 ", "tool "))]
    assert len(rows) >= 5 and all(ln == ln.rstrip() for ln in r.stderr.splitlines())
    assert any(ln.endswith("(not held: --time fit)") for ln in rows)
    r = run("check", str(out), "--no-hold-capacity")
    assert r.exit_code == 0 and all(ln == ln.rstrip() for ln in r.stderr.splitlines())
