"""Shared fixtures. ``--update-golden`` rewrites the golden files instead of comparing."""

from __future__ import annotations

import numpy as np
import pytest


def pytest_addoption(parser):
    parser.addoption("--update-golden", action="store_true", help="rewrite tests/golden/data/* from the current output")


@pytest.fixture
def update_golden(request) -> bool:
    return bool(request.config.getoption("--update-golden"))


ADEPT_FROM = np.array([-0.1525, 0.0, -0.8])
ADEPT_TO = np.array([0.1525, 0.0, -0.8])


def lumped(profile):
    """``profile`` with the Delta's lumped-mass model (``robot.dynamics: lumped``): the model the papers use and
    the one earlier reference figures (TOPP-RA, the manual's worked numbers) were computed with."""
    return profile.model_copy(update={"robot": profile.robot.model_copy(update={"dynamics": "lumped"})})
