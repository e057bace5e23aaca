"""CLI: `pickplace compare` and `pickplace plot` — exit codes, files written, one-line errors."""

from __future__ import annotations

import csv
import io
import json
import subprocess
import sys

import pytest
from typer.testing import CliRunner

from pickplace_cli.cli import app
from pickplace_cli.paths import Method

runner = CliRunner()
ADEPT = ["--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8"]


def run(*args):
    return runner.invoke(app, list(args), catch_exceptions=False)


def _one_line_error(r, code: int, text: str) -> None:
    assert r.exit_code == code, (r.exit_code, r.stderr)
    lines = [x for x in r.stderr.splitlines() if x.startswith("pickplace: error:")]
    assert len(lines) == 1 and text in lines[0], r.stderr
    assert "Traceback" not in r.stderr


@pytest.mark.parametrize("cmd", ["compare", "plot"])
def test_help(cmd):
    r = run(cmd, "--help")
    assert r.exit_code == 0 and "Usage" in r.stdout and "--from" in r.stdout


def test_help_imports_nothing_heavy():
    """`compare --help` / `plot --help` import no numpy, scipy, matplotlib or yaml (pydantic is left out
    of this list: typer's own help rendering imports it for every sub-command, ours or not)."""
    code = (
        "import sys; from pickplace_cli.cli import app\n"
        "for cmd in (['compare', '--help'], ['plot', '--help']):\n"
        "    try:\n        app(cmd)\n    except SystemExit:\n        pass\n"
        "print('HEAVY=' + ','.join(m for m in ('numpy', 'scipy', 'matplotlib', 'yaml', 'mcap') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip().splitlines()[-1] == "HEAVY="


def test_compare_table_on_stderr_all_methods():
    r = run("compare", *ADEPT)
    assert r.exit_code == 0, r.stderr
    assert r.stdout == ""
    for m in Method:
        assert m.value in r.stderr
    assert "continuity" in r.stderr and "residual vibration [m]" in r.stderr and "λ = 12.2" in r.stderr


def test_compare_csv_stdout_and_json_file(tmp_path):
    r = run("compare", *ADEPT, "--methods", "bspline", "-f", "csv", "-q")
    assert r.exit_code == 0 and r.stderr == ""
    rows = list(csv.reader(io.StringIO(r.stdout)))
    assert rows[0][0] == "method" and [x[0] for x in rows[1:]] == ["bspline"]
    out = tmp_path / "cmp.json"
    r = run("compare", *ADEPT, "-m", "bspline", "-f", "json", "-o", str(out))
    assert r.exit_code == 0 and r.stdout == "" and "bspline" in r.stderr  # the table still on stderr
    doc = json.loads(out.read_text())
    assert doc["rows"][0]["method"] == "bspline" and doc["rows"][0]["continuity"]["class"] == "C3"
    assert not list(tmp_path.glob(".*.tmp"))  # atomic: no temporary file left behind


@pytest.mark.parametrize(
    "args, code, text",
    [
        (["-m", "bspline,nope"], 1, "-m/--methods 'nope': unknown method"),
        (["-m", ""], 1, "-m/--methods '': empty"),
        (["-m", "bspline", "--eta", "1.5"], 1, "--eta 1.5"),
        (["-m", "bspline", "--time", "soon"], 1, "--time 'soon'"),
        (["-m", "bspline", "-o", "x.out"], 1, "--format table prints to stderr"),
        (["-m", "bspline", "-f", "csv", "-o", "/no/such/dir/x.csv"], 1, "does not exist"),
        (["-m", "bspline", "-p", "nope"], 1, "profile 'nope'"),
    ],
)
def test_compare_bad_input(args, code, text):
    _one_line_error(run("compare", *ADEPT, *args), code, text)


def test_compare_bad_point():
    _one_line_error(run("compare", "--from", "1,2", "--to", "0,0,-0.8"), 1, "--from '1,2'")


def test_compare_every_method_unreachable_exits_4(tmp_path):
    out = tmp_path / "c.csv"
    r = run("compare", "--from", "0,0,-0.8", "--to", "1.0,0,-0.8", "--height", "0.05", "-f", "csv", "-o", str(out))
    assert r.exit_code == 4 and not out.exists()
    assert r.stderr.count("pickplace: method ") == len(Method)
    assert "pickplace: error: no method could plan this move" in r.stderr


def test_compare_some_methods_fail_others_run():
    """λ = 3e5 is beyond any B-spline (k1, k2) optimum: that row fails, the others plan (exit 0)."""
    others = [m.value for m in Method if m.value != "bspline"]
    if not others:
        pytest.skip("only the B-spline is registered")
    r = run("compare", "--from", "-0.15,0,-0.8", "--to", "0.15,0,-0.8", "--height", "1e-6", "-m", f"bspline,{others[0]}")
    assert r.exit_code == 0 and "pickplace: method bspline: lambda = b/h = 3e+05" in r.stderr


def test_plot_png_and_svg(tmp_path):
    png, svg = tmp_path / "f.png", tmp_path / "f.svg"
    r = run("plot", *ADEPT, "-m", "bspline", "-o", str(png))
    assert r.exit_code == 0, r.stderr
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    r = run("plot", *ADEPT, "-o", str(svg), "--normalised")
    assert r.exit_code == 0, r.stderr
    text = svg.read_text()
    assert text.startswith("<?xml") and "<svg" in text
    # deterministic: the same figure twice gives the same bytes
    again = tmp_path / "g.svg"
    run("plot", *ADEPT, "-o", str(again), "--normalised")
    assert again.read_bytes() == svg.read_bytes()


def test_plot_format_flag_and_stdout(tmp_path):
    out = tmp_path / "figure"
    r = run("plot", *ADEPT, "-m", "bspline", "-o", str(out), "--format", "svg")
    assert r.exit_code == 0 and out.read_text().startswith("<?xml")


@pytest.mark.parametrize(
    "args, text",
    [
        (["-o", "figure"], "cannot tell the figure format"),
        (["-o", "f.pdf"], "output f.pdf: its suffix 'pdf'"),
        (["-o", "f.png", "-f", "jpeg"], "-f/--format 'jpeg'"),
        (["-o", "/no/such/dir/f.png"], "does not exist"),
        (["-o", "f.png", "-m", "nope"], "unknown method"),
    ],
)
def test_plot_bad_input(tmp_path, monkeypatch, args, text):
    monkeypatch.chdir(tmp_path)
    _one_line_error(run("plot", *ADEPT, *args), 1, text)
    assert not list(tmp_path.iterdir())


def test_plot_without_matplotlib(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # import matplotlib → ImportError
    out = tmp_path / "f.png"
    r = run("plot", *ADEPT, "-o", str(out))
    _one_line_error(r, 1, "needs matplotlib")
    assert "pip install 'pickplace-cli[plot]'" in r.stderr and not out.exists()


def test_plot_unreachable_exits_4(tmp_path):
    out = tmp_path / "f.png"
    r = run("plot", "--from", "0,0,-0.8", "--to", "1.0,0,-0.8", "--height", "0.05", "-o", str(out))
    assert r.exit_code == 4 and not out.exists()


def test_plot_motors_panels(tmp_path):
    """--motors adds the motors' use in % of their limits; the same figure without it is smaller; with
    --normalised it is refused (exit 2, nothing written)."""
    plain, motors = tmp_path / "p.svg", tmp_path / "m.svg"
    assert run("plot", *ADEPT, "-m", "bspline", "-t", "fit", "-o", str(plain)).exit_code == 0
    r = run("plot", *ADEPT, "-m", "bspline,lame", "-t", "optimal", "--motors", "-o", str(motors))
    assert r.exit_code == 0, r.stderr
    assert motors.read_text().startswith("<?xml") and motors.stat().st_size > plain.stat().st_size
    bad = tmp_path / "n.png"
    r = run("plot", *ADEPT, "--motors", "--normalised", "-o", str(bad))
    assert r.exit_code == 2 and "--normalised" in r.output and not bad.exists()


def test_limit_use_agrees_with_the_limit_report():
    """The curves plot --motors draws are the check's own columns: each curve's maximum on the plot's grid is
    within 1 % below (never above) the report's refined peak, the binding torque rate touches 100 %, and the
    RMS bars are the report's RMS rows."""
    import numpy as np

    from pickplace_cli.limits.motion import limit_use
    from pickplace_cli.planner import PlanOptions, motion_model, plan
    from pickplace_cli.model.profile import load_profile
    from pickplace_cli.model.task import Task

    prof = load_profile("delta-su2018")
    res = plan(Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5), prof, PlanOptions(time="fit"))
    T = res.duration.seconds
    curves, rms = limit_use(motion_model(res.cartesian.path, prof), T, np.linspace(0, 1, 4001), dwell=prof.planning.dwell)
    rows = {(r.joint, r.quantity): r for r in res.report.rows}
    assert len(curves) == 9 and len(rms) == 3
    for joint, quantity, pct in curves:
        ref = 100 * rows[(joint, quantity)].utilisation
        # never above the report's peak beyond its accuracy: 1e-6 near the limit (refined exactly), ZOOM_TOL = 1e-4
        # of the peak far from it (the parabola vertex on the check's grid)
        slack = 1e-6 if rows[(joint, quantity)].utilisation >= 0.95 else 1e-4
        assert ref * 0.99 <= pct.max() <= ref * (1 + slack), (joint, quantity)
    assert max(pct.max() for _, q, pct in curves if q == "motor torque rate") == pytest.approx(100, rel=5e-3)
    for joint, pct in rms:
        assert pct == pytest.approx(100 * rows[(joint, "rms motor torque")].utilisation, rel=1e-9)


def test_compare_says_the_capacity_is_exceeded_not_held_under_fit():
    """Under ``--time fit`` (joint and motor limits alone) the Adept cycle runs past the tool's Cartesian capacity: compare
    says so as plan does — the table's limits cell, one line on stderr, ``all_limits_ok`` false and the rows in the
    JSON — while ``limits_ok`` (the rule's own limits) stays true; under ``--time limits`` nothing is listed."""
    plan_doc = _plan_json("fit")
    want = {r["quantity"] for r in plan_doc["exceeded_not_held"]}
    assert want == {"capacity speed", "capacity acceleration"}
    r = run("compare", *ADEPT, "-m", "bspline", "-t", "fit")
    assert r.exit_code == 0, r.stderr
    assert "capacity EXCEEDED, not held" in r.stderr
    line = next(x for x in r.stderr.splitlines() if x.startswith("bspline: exceeded, not held under --time fit"))
    for q in want:
        assert q in line
    doc = json.loads(run("compare", *ADEPT, "-m", "bspline", "-t", "fit", "-f", "json", "-q").stdout)
    row = doc["rows"][0]
    assert row["limits_ok"] is True and row["all_limits_ok"] is False
    assert {" ".join(x.split()[:2]) for x in row["exceeded_not_held"]} == want
    # the percentages are plan's (peak over limit)
    use = {r["quantity"]: 100 * r["peak"] / r["limit"] for r in plan_doc["exceeded_not_held"]}
    for x in row["exceeded_not_held"]:
        q = " ".join(x.split()[:2])
        assert float(x.split()[2]) == pytest.approx(use[q], abs=0.06)
    rows = list(csv.DictReader(io.StringIO(run("compare", *ADEPT, "-m", "bspline", "-t", "fit", "-f", "csv", "-q").stdout)))
    assert rows[0]["limits_ok"] == "true" and rows[0]["all_limits_ok"] == "false"
    held = json.loads(run("compare", *ADEPT, "-m", "bspline", "-f", "json", "-q").stdout)["rows"][0]
    assert held["all_limits_ok"] is True and held["exceeded_not_held"] == []


def _plan_json(rule: str) -> dict:
    r = subprocess.run([sys.executable, "-m", "pickplace_cli", "plan", *ADEPT, "--time", rule, "--json", "-q", "-o",
                        "/dev/null"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    doc = json.loads(r.stdout)
    return doc.get("summary", doc)
