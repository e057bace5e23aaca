"""The installed package finds its shipped profiles and tables (package data, not only a checkout)."""

from __future__ import annotations

import json
import sys
from importlib import metadata

import pytest

from pickplace_cli.model.resources import data_dir


def test_data_dirs_hold_the_shipped_files():
    assert (data_dir("profiles") / "gantry.yaml").is_file()
    assert (data_dir("tables") / "bspline-eta0.5.csv").is_file()


def test_wheel_contains_package_data():
    # look in site-packages only: setuptools leaves a pickplace_cli.egg-info in the checkout, which is on
    # sys.path when tests run from it and would shadow the installed distribution's record
    site = [p for p in sys.path if p.endswith("site-packages")]
    dists = [d for d in metadata.distributions(path=site) if d.metadata["Name"] == "pickplace-cli"]
    if not dists:
        pytest.skip("pickplace-cli is not installed (running from a bare checkout)")
    dist = dists[0]
    direct = dist.read_text("direct_url.json")
    if direct and json.loads(direct).get("dir_info", {}).get("editable"):
        pytest.skip("editable install: data comes from the checkout")
    files = {str(f) for f in dist.files or []}
    assert "pickplace_cli/profiles/gantry.yaml" in files
    assert "pickplace_cli/tables/bspline-eta0.5.csv" in files


def test_installed_tool_runs_from_any_directory(tmp_path):
    """Run the package as a user would, from an unrelated directory (so the checkout is not on sys.path):
    the default profile and table must be found as package data."""
    import subprocess

    env = {k: v for k, v in __import__("os").environ.items() if k != "PYTHONPATH"}
    r = subprocess.run(
        [sys.executable, "-m", "pickplace_cli", "plan", "--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8", "-q"],
        cwd=tmp_path, capture_output=True, text=True, env=env,
    )
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith("t[s],x[m]")
