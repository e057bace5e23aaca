"""CLI of `profile show/validate` and `check`: messages a new user meets (one line naming field, value, rule;
exit codes), the workspace sentence, and check on this tool's own multi-move CSV."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from pickplace_cli.cli import app
from pickplace_cli.profile import resolve_profile_path

runner = CliRunner()
ADEPT = ["--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8"]


def run(*args, input=None):
    return runner.invoke(app, list(args), catch_exceptions=False, input=input)


def test_profile_show_scara_workspace_sentence():
    r = run("profile", "show", "scara-600")
    assert r.exit_code == 0
    line = next(x for x in r.stdout.splitlines() if x.startswith("workspace at z"))
    assert line.startswith("workspace at z = -0.1 m: radius 0.163 … 0.599 m reachable in 42 of 72 directions (azimuth -135° … 70°")
    assert "no common radius" not in line and "limit the rest" not in line


@pytest.mark.parametrize("z", ["nan", "inf", "-inf"])
def test_profile_show_refuses_non_finite_z(z):
    r = run("profile", "show", "--z", z)
    assert r.exit_code == 1 and r.stdout == ""
    assert r.stderr.strip() == f"pickplace: error: z = {float(z)!r}: must be a finite number in m (no NaN or inf)"


def test_profile_validate_names_a_short_range(tmp_path):
    prof = tmp_path / "p.yaml"
    prof.write_text(resolve_profile_path("delta-su2018").read_text().replace("position: [-0.6981317, 1.5707963]", "position: [-0.6981317]"))
    r = run("profile", "validate", str(prof))
    assert r.exit_code == 1 and len(r.stderr.strip().splitlines()) == 1
    assert f"{prof}:28: robot.joints.limits.position = [-0.6981317]: needs 2 values, got 1" in r.stderr
