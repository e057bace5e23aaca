"""CLI: `plan --method` for the methods of issue 5 (ph, superposition, lame, piecewise-poly) end to end on
the default Delta profile: `--time auto` uses each path's true peaks, so the binding peak meets the
capacity exactly."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from pickplace_cli.cli import app

runner = CliRunner()
ADEPT = ["--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8"]


@pytest.mark.parametrize("method", ["ph", "superposition", "lame", "piecewise-poly"])
def test_plan_each_method_json(method):
    # --write-anyway: on the default Delta the 3-4-5 jerk steps can exceed the motor torque-rate limit at
    # the auto duration (exit 3 is then the right verdict); this test is about the planning, not the verdict
    r = runner.invoke(app, ["plan", *ADEPT, "--method", method, "-t", "auto", "--format", "json", "-q", "--write-anyway"],
                      catch_exceptions=False)
    assert r.exit_code == 0, r.stderr
    doc = json.loads(r.stdout)
    s = doc["summary"] if "summary" in doc else doc
    assert s["method"] == method
    # auto duration from the true peaks: the default Delta profile's [a] = 100 m/s² binds for every one of
    # these on the Adept cycle, so the true peak acceleration at T equals it (closed form scaling: 1e-9)
    assert s["binding"] == "acceleration"
    assert s["peak_acceleration_m_s2"] == pytest.approx(100.0, rel=1e-9)
    assert s["peak_speed_m_s"] <= 5.0


def test_plan_ph_stderr_summary_names_method():
    r = runner.invoke(app, ["plan", *ADEPT, "-m", "ph", "-t", "auto", "-o", "-", "--write-anyway"], catch_exceptions=False)
    assert r.exit_code == 0
    assert "delta-su2018 / ph" in r.stderr and "|a| = 100 m/s²" in r.stderr


def test_unknown_method_is_invalid_input():
    """A value the option cannot take is invalid input (exit 1), like a value out of range; the line names the option
    and the choices."""
    r = runner.invoke(app, ["plan", *ADEPT, "--method", "cubic"])
    assert r.exit_code == 1
    assert "-m/--method: 'cubic' is not one of 'bspline'" in r.output


@pytest.mark.parametrize("args, line", [
    (["--param", "m=abc"], "--param m='abc': not a number"),
    (["--param", "m=2"], "--param m=2.0: method bspline has no parameter 'm'"),
    (["-m", "lame", "--param", "m=1"], "--param m=1.0: the Lamé exponent must be ≥ 3"),
    (["-m", "ph", "--param", "r=0.5"], "--param r=0.5: the PH corner's horizontal extent must satisfy 0 < r ≤ w/2"),
    (["-m", "bspline-vel", "--param", "tau6=0.9"], "--param tau7: give all seven shape parameters"),
])
def test_a_method_parameter_error_names_param(args, line):
    """An error about a method parameter given with --param names the option as it was given (NAME=VALUE), whether
    the command line's parser or the method refuses it; exit 1, one line."""
    r = runner.invoke(app, ["plan", *ADEPT, *args, "-o", "-"])
    assert r.exit_code == 1
    (got,) = r.output.splitlines()
    assert got.startswith("pickplace: error: " + line), got
