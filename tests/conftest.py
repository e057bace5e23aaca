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
