"""The installed package finds its shipped profiles and tables (package data, not only a checkout)."""

from __future__ import annotations

import json
from importlib import metadata

import pytest

from pickplace_cli.resources import data_dir


def test_data_dirs_hold_the_shipped_files():
    assert (data_dir("profiles") / "gantry.yaml").is_file()
    assert (data_dir("tables") / "bspline-eta0.5.csv").is_file()


def test_wheel_contains_package_data():
    try:
        dist = metadata.distribution("pickplace-cli")
    except metadata.PackageNotFoundError:
        pytest.skip("pickplace-cli is not installed (running from a bare checkout)")
    direct = dist.read_text("direct_url.json")
    if direct and json.loads(direct).get("dir_info", {}).get("editable"):
        pytest.skip("editable install: data comes from the checkout")
    files = {str(f) for f in dist.files or []}
    assert "pickplace_cli/profiles/gantry.yaml" in files
    assert "pickplace_cli/tables/bspline-eta0.5.csv" in files
