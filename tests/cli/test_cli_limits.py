"""CLI of the limit checks: exit 3 / --report-only / --report JSON, --time fit, check, profile validate/show,
bad robot input (exit 1 or 4, nothing written)."""

from __future__ import annotations

import json

import pytest

from pickplace_cli.limits.motion import EXACT_BAND
import yaml
from typer.testing import CliRunner

from pickplace_cli.cli import app
from pickplace_cli.model.profile import resolve_profile_path

runner = CliRunner()
ADEPT = ["--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8"]


def run(*args):
    return runner.invoke(app, list(args), catch_exceptions=False)


def test_limit_exceeded_exit_3_and_report(tmp_path):
    rep = tmp_path / "r.json"
    out = tmp_path / "o.csv"
    r = run("plan", *ADEPT, "--time", "0.1", "--report", str(rep), "-o", str(out))
    assert r.exit_code == 3
    assert "limit exceeded: q1 motor torque" in r.stderr and "at t = " in r.stderr and "EXCEEDED" in r.stderr
    doc = json.loads(rep.read_text())
    assert doc["limits"]["ok"] is False and doc["limits"]["violations"][0]["joint"] == "q1"
    assert not out.exists()  # a move that breaks a limit is not handed on …
    assert "trajectory not written" in r.stderr
    r2 = run("plan", *ADEPT, "--time", "0.1", "--report-only", "-q", "-o", str(out))
    assert r2.exit_code == 0 and "limit exceeded" in r2.stderr and out.exists()  # … unless asked


def test_time_fit_reports_both(tmp_path):
    r = run("plan", *ADEPT, "--time", "fit", "--format", "json", "-q")
    assert r.exit_code == 0
    s = json.loads(r.stdout)["summary"]
    assert s["mode"] == "fit" and s["duration_s"] == s["fit_s"] and s["auto_s"] > s["fit_s"]
    assert s["limits_ok"] is True and s["picks_per_minute"] > 0


def test_unreachable_point_exit_4_names_point_and_time(tmp_path):
    out = tmp_path / "o.csv"
    r = run("plan", "--from", "1.5,0,-0.8", "--to", "1.6,0,-0.8", "--k1", "0.3", "--k2", "0.1", "-o", str(out))
    assert r.exit_code == 4
    line = r.stderr.strip()
    assert "\n" not in line and "unreachable" in line and "t = 0 s" in line
    assert not out.exists()


def test_scara_elbow_cannot_reach_exit_4():
    r = run("plan", "-p", "scara-600", "--from", "0.01,0,-0.1", "--to", "0.3,0,-0.1", "--k1", "0.3", "--k2", "0.1")
    assert r.exit_code == 4 and "SCARA" in r.stderr


@pytest.mark.parametrize(
    "edit,msg",
    [
        (("upper_arm: 1.0", "upper_arm: -1.0"), "robot.masses.upper_arm = -1.0"),
        (("l: 0.800", "l: 0.300"), "must be longer than the upper arm"),
        (("gear_ratio: 25.0", "gear_ratio: 0"), "gear_ratio = 0"),
        (("efficiency: 0.9", "efficiency: 1.5"), "efficiency = 1.5"),
    ],
)
def test_non_physical_profile_exit_1(tmp_path, edit, msg):
    text = resolve_profile_path("delta-su2018").read_text().replace(*edit, 1)
    prof = tmp_path / "p.yaml"
    prof.write_text(text)
    out = tmp_path / "o.csv"
    r = run("plan", *ADEPT, "-p", str(prof), "-o", str(out))
    assert r.exit_code == 1 and msg in r.stderr and len(r.stderr.strip().splitlines()) == 1
    assert not out.exists()
    v = run("profile", "validate", str(prof))
    assert v.exit_code == 1 and msg in v.stderr


def test_check_own_csv_agrees_with_plan(tmp_path):
    out = tmp_path / "a.csv"
    rp = tmp_path / "plan.json"
    rc = tmp_path / "check.json"
    assert run("plan", *ADEPT, "-q", "-o", str(out), "--report", str(rp)).exit_code == 0
    r = run("check", str(out), "--report", str(rc))
    assert r.exit_code == 0 and "septic Hermite" in r.stderr
    # the Cartesian capacity is a planning rule: the check holds the joint and motor limits of the file
    a = {(x["joint"], x["quantity"]): x["peak"] for x in json.loads(rp.read_text())["limits"]["rows"]
         if not x["quantity"].startswith("capacity")}
    b = {(x["joint"], x["quantity"]): x["peak"] for x in json.loads(rc.read_text())["limits"]["rows"]}
    use = {(x["joint"], x["quantity"]): x["utilisation"] for x in json.loads(rp.read_text())["limits"]["rows"]}
    for key in a:
        # through the file's own tool motion (septic Hermite) a peak near its limit (refined exactly on the
        # continuous motion by both) agrees to 1e-6 (12-digit values); one far from it is a parabola-vertex estimate
        # on each side's own grid, good to ZOOM_TOL = 1e-4 of the peak; a position is checked on the file's
        # samples, which may miss the continuous extreme between two of them by ~1e-5
        near = abs(use[key]) >= 1.0 - EXACT_BAND
        tol = 1e-5 if key[1].startswith(("position", "workcell")) else 1e-6 if near else 1e-4
        if key[1].startswith(("position", "workcell")):  # a range row may show either side on a tie
            assert abs(b[key]) == pytest.approx(abs(a[key]), rel=tol, abs=1e-9), key
        else:
            assert b[key] == pytest.approx(a[key], rel=tol, abs=1e-9), key


def test_check_catches_a_violation_and_bad_files(tmp_path):
    out = tmp_path / "a.csv"
    assert run("plan", *ADEPT, "-q", "-o", str(out), "--time", "0.1", "--report-only").exit_code == 0
    r = run("check", str(out), "-q")
    assert r.exit_code == 3 and "q1 motor torque" in r.stderr
    bad = tmp_path / "bad.csv"
    bad.write_text("t,q1,q2\n0,1,2\n")
    r = run("check", str(bad))
    assert r.exit_code == 1 and "lacks column(s) q3" in r.stderr
    bad.write_text("t,q1,q2,q3\n" + "".join(f"{i * 0.01},0.3,0.3,0.3\n" for i in (0, 1, 1, 2, 3, 4, 5)))
    r = run("check", str(bad))
    assert r.exit_code == 1 and "increase strictly" in r.stderr


def test_profile_validate_and_show():
    r = run("profile", "validate", "scara-600")
    assert r.exit_code == 0 and r.stdout.startswith("ok: ")
    r = run("profile", "show")
    assert r.exit_code == 0
    # rigid-body model of uniform rods: I_b = 0.030 + (0.10 + 0.30/3) · 0.325² kg·m², plate 0.4 + 0.1 + 3 · 0.30/3 kg
    assert "arm inertia at the motor axis I_b = 0.051125 kg·m²" in r.stdout
    assert "mass the plate's acceleration drives 0.8 kg" in r.stdout and "weight on the plate 0.95 kg" in r.stdout
    assert "radius 0.000 … " in r.stdout and "[v] = 5 m/s" in r.stdout
    for cmd in (["check", "--help"], ["profile", "--help"], ["profile", "show", "--help"], ["profile", "validate", "--help"]):
        assert run(*cmd).exit_code == 0


def test_output_path_conflicts_and_modes(tmp_path):
    import os
    import stat

    out = tmp_path / "o.csv"
    r = run("plan", *ADEPT, "-q", "--report", "-")
    assert r.exit_code == 1 and "stdout already carries" in r.stderr
    r = run("plan", *ADEPT, "-q", "-o", str(out), "--report", str(out))
    assert r.exit_code == 1 and not out.exists()
    r = run("plan", *ADEPT, "-q", "-o", str(out), "--report", str(tmp_path / "nope" / "r.json"))
    assert r.exit_code == 1 and not out.exists()
    old = os.umask(0o022)
    try:
        assert run("plan", *ADEPT, "-q", "-o", str(out)).exit_code == 0
    finally:
        os.umask(old)
    assert stat.S_IMODE(out.stat().st_mode) == 0o644  # like a plain open(), not mkstemp's 0600


def test_gantry_fit_without_limits_is_refused():
    r = run("plan", "-p", "gantry", *ADEPT, "--time", "fit")
    assert r.exit_code == 1 and "no velocity, acceleration, jerk or motor limit" in r.stderr
    r = run("plan", "-p", "gantry", *ADEPT, "-q")
    assert r.exit_code == 0 and "motor_" not in r.stdout.splitlines()[0]  # no drives → no motor columns


def test_joint_range_violation_is_exit_4():
    r = run("plan", "-p", "scara-600", "--from", "0.35,-0.15,0.1", "--to", "0.35,0.15,0.1", "-q")
    assert r.exit_code == 4 and "q3 position" in r.stderr


def test_vertical_move_message():
    r = run("plan", "--from", "0,0,-0.8", "--to", "0,0,-0.75")
    assert r.exit_code == 1 and "vertically aligned" in r.stderr


def test_tiny_rate_keeps_both_ends():
    """A rate far below one sample per move keeps both ends (the library's plan: the CLI refuses to write a move in
    fewer samples than check reads, naming the rate)."""
    from pickplace_cli.model.profile import load_profile
    from pickplace_cli.model.task import Task
    from pickplace_cli.planner import PlanOptions, plan

    pl = plan(Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5), load_profile("delta-su2018"),
              PlanOptions(rate=1e-9, time=0.25))
    assert list(pl.t) == [0.0, 0.25]
    r = run("plan", *ADEPT, "--rate", "1e-9", "-q", "--time", "0.25")
    assert r.exit_code == 1 and "--rate 1e-09 Hz: 2 samples for a 0.25 s move" in r.stderr and not r.stdout


def test_wildly_infeasible_move_prints_readable_percentages_and_whole_rows():
    """T = 2 ms: utilisations of 10⁵–10⁷ % print with 3 significant digits, and the limit table is not
    wrapped at 80 columns when stderr is not a terminal (a log file gets one row per line)."""
    r = run("plan", *ADEPT, "--time", "0.002")
    assert r.exit_code == 3
    rows = [line for line in r.stderr.splitlines() if line.startswith("q1     motor torque rate")]
    assert len(rows) == 1 and "[N·m/s]" in rows[0] and "EXCEEDED" in rows[0]  # one line, unit included
    assert "2.91e+07" in rows[0] and "29125" not in r.stderr
    assert "t peak [s]" in r.stderr  # the unit of the header is text, not rich markup ("[s]" = strike)
    assert "limit exceeded: q1 motor torque rate" in r.stderr and "2.91e+07 %" in r.stderr


def test_percent_format():
    from pickplace_cli.limits.report import percent

    assert percent(0.5) == "50.0" and percent(99.9994) == "9999.9" and percent(99.9999) == "1e+04" and percent(100.0) == "1e+04"
    assert percent(291787.793) == "2.92e+07" and percent(-0.25) == "-25.0" and percent(float("inf")) == "inf"


def test_json_summary_on_error_is_still_one_json_document(tmp_path):
    """`plan --json` whose move fails (no feasible --time fit, an unreachable point) prints
    {"exit_code", "error"} on stdout, as a batch row does, besides the one-line error on stderr."""
    doc = yaml.safe_load(resolve_profile_path("delta-su2018").read_text())
    doc["robot"]["payload"] = 300.0  # the holding torque alone exceeds the rated torque: no duration fits
    heavy = tmp_path / "heavy.yaml"
    heavy.write_text(yaml.safe_dump(doc))
    r = run("plan", *ADEPT, "--json", "-t", "fit", "-p", str(heavy))
    out = json.loads(r.stdout)
    assert r.exit_code == 3 and out["exit_code"] == 3 and "--time fit" in out["error"]
    assert out["error"] in r.stderr
    r = run("plan", "--from", "0,0,-0.8", "--to", "2,0,-0.8", "--json")
    out = json.loads(r.stdout)
    assert r.exit_code == 4 and out == {"exit_code": 4, "error": out["error"]} and "is unreachable" in out["error"]
    r = run("plan", "--from", "0,0,-0.8", "--to", "2,0,-0.8")  # without --json stdout stays empty
    assert r.exit_code == 4 and r.stdout == ""


def test_json_summary_gets_exactly_one_document_when_an_option_or_the_write_fails(tmp_path):
    """An invalid value (exit 1) before anything is planned, and a trajectory write that fails after the
    plan succeeded (/dev/full: no space), both leave exactly one JSON document on stdout: the error."""
    r = run("plan", *ADEPT, "--json", "--eta", "1.5")
    assert r.exit_code == 1 and json.loads(r.stdout)["exit_code"] == 1 and "--eta 1.5" in json.loads(r.stdout)["error"]
    import os

    if os.path.exists("/dev/full"):
        r = run("plan", *ADEPT, "--json", "-q", "-o", "/dev/full")
        lines = r.stdout.splitlines()
        assert r.exit_code == 1 and len(lines) == 1
        doc = json.loads(lines[0])
        assert doc["exit_code"] == 1 and "write failed" in doc["error"] and "Traceback" not in r.stderr


def _csv_rms(path, dwell: float) -> dict[str, float]:
    """RMS of every written motor_torque column over move + dwell + return + dwell (README's duty cycle)."""
    import numpy as np

    lines = [ln for ln in path.read_text().splitlines() if ln and not ln.startswith("#")]
    names = lines[0].split(",")
    d = np.loadtxt(lines[1:], delimiter=",")
    t = d[:, 0]
    out = {}
    for k, n in enumerate(names):
        if n.startswith("motor_torque"):
            y = d[:, k]
            move = np.trapezoid(y**2, t)
            out["q" + n[len("motor_torque"):].split("[")[0]] = float(
                np.sqrt((2 * move + dwell * (y[0] ** 2 + y[-1] ** 2)) / (2 * (t[-1] - t[0]) + 2 * dwell)))
    return out


ISSUE19_PH = ["-m", "ph", "--from", "0.1976,-0.0072,-0.8372", "--to", "-0.0019,-0.2504,-0.7253",
              "--height", "0.0188", "--rate", "20000"]


def test_issue19_ph_rms_is_the_rms_of_the_written_columns(tmp_path):
    """Issue 19: on the Delta with rated_torque 0.60 N·m this PH move was passed at q1 RMS 0.5233 while the
    written motor_torque1 column's RMS was 0.797 (33 % over). At that old fitted duration (0.3172 s) the
    report now says 0.7973 and fails (exit 3); --time fit finds a duration whose written columns keep the
    rating, and every reported RMS equals the written columns' RMS to 1e-4."""
    d = yaml.safe_load(resolve_profile_path("delta-su2018").read_text())
    d["robot"]["dynamics"] = "lumped"  # the model the figures above were found with
    joints = d["robot"]["joints"]
    for j in joints if isinstance(joints, list) else [joints]:
        j["drive"]["rated_torque"] = 0.60
    prof = tmp_path / "delta-rated060.yaml"
    prof.write_text(yaml.safe_dump(d))
    rep, out = tmp_path / "r.json", tmp_path / "o.csv"
    r = run("plan", "-p", str(prof), *ISSUE19_PH, "--time", "0.3172", "--report", str(rep), "-o", str(out),
            "--report-only", "-q")
    assert r.exit_code == 0 and "limit exceeded: q1 rms motor torque" in r.stderr
    rows = {x["joint"]: x for x in json.loads(rep.read_text())["limits"]["rows"] if x["quantity"] == "rms motor torque"}
    written = _csv_rms(out, 0.1)
    assert rows["q1"]["peak"] == pytest.approx(0.79725, abs=2e-4) and rows["q1"]["ok"] is False
    for j, v in written.items():
        assert rows[j]["peak"] == pytest.approx(v, rel=1e-4)
    r = run("plan", "-p", str(prof), *ISSUE19_PH, "--time", "fit", "--report", str(rep), "-o", str(out), "-q")
    assert r.exit_code == 0
    doc = json.loads(rep.read_text())
    assert doc["summary"]["binding"] == "q1 rms motor torque"
    rows = {x["joint"]: x for x in doc["limits"]["rows"] if x["quantity"] == "rms motor torque"}
    written = _csv_rms(out, 0.1)
    assert written["q1"] <= 0.60 * (1 + 1e-4) and written["q1"] >= 0.60 * 0.999  # the fit is tight on it
    for j, v in written.items():
        assert rows[j]["peak"] == pytest.approx(v, rel=1e-4)


def test_issue19_superposition_torque_rate_does_not_depend_on_the_rate(tmp_path):
    """Issue 19: q2's torque-rate peak next to a jerk jump was 29.6 / 85.55 / 30.35 N·m/s at 1 / 2 / 200 kHz;
    the one-sided supremum is 27.16 (an independent model and a finite difference of the output agree)."""
    move = ["-p", "scara-600", "-m", "superposition", "--from", "0.285551,-0.236705,-0.095671",
            "--to", "0.534835,-0.116715,-0.131980", "--height", "0.046788"]
    for rate in ("1000", "2000", "200000"):
        rep = tmp_path / f"r{rate}.json"
        r = run("plan", *move, "--rate", rate, "--report", str(rep), "--report-only", "-q")
        assert r.exit_code == 0
        rows = {x["joint"]: x for x in json.loads(rep.read_text())["limits"]["rows"]
                if x["quantity"] == "motor torque rate"}
        assert rows["q2"]["peak"] == pytest.approx(27.16, abs=0.01), rate


def test_fit_workspace_names_a_finite_worst_point(tmp_path):
    """Without a workcell box, the requested height breaks q3's range where parts of the path are out of reach:
    the worst point is taken among the points where the constraint is defined (review, session 16: 'violated by
    inf' at an unreachable point)."""
    from pickplace_cli.model.profile import resolve_profile_path

    lines = resolve_profile_path("delta-su2018").read_text().splitlines(keepends=True)
    i = next(k for k, ln in enumerate(lines) if ln.startswith("workcell:"))
    j = next((k for k in range(i + 1, len(lines)) if lines[k][:1] not in (" ", "\t", "")), len(lines))
    prof = tmp_path / "nobox.yaml"
    prof.write_text("".join(lines[:i] + lines[j:]))
    r = run("plan", "-p", str(prof), "--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8", "--height", "0.4",
            "--fit-workspace", "-o", str(tmp_path / "o.csv"))
    assert "violated by inf" not in r.stderr and "Traceback" not in r.stderr
    assert r.exit_code == 0 and "at the requested height: worst at τ = " in r.stderr, r.stderr
    assert "q3 position min -0.698132 rad (violated by " in r.stderr
