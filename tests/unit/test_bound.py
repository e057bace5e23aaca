"""The lower bound of ``--time optimal``'s summary (pickplace_cli.timing.bound): TOPP-RA's passes on the path's τ."""

from __future__ import annotations

import numpy as np
import pytest

from tests.conftest import lumped

from pickplace_cli.model.profile import load_profile
from pickplace_cli.model.task import Task
from pickplace_cli.paths import plan_path
from pickplace_cli.planner import PlanOptions, motion_model, plan
from pickplace_cli.timing.bound import bound_grid, law_duration, topp, torque_bound

ADEPT = Task(np.array([-0.1525, 0.0, -0.8]), np.array([0.1525, 0.0, -0.8]), 0.025, 0.5)


def _rows(n, M=2.0, L=5.0, G=0.0):
    col = np.ones((n, 1))
    A = np.hstack([M * col, -M * col])
    return A, np.zeros_like(A), np.hstack([G * col, -G * col]), np.full_like(A, L)


@pytest.mark.parametrize("grid", ["uniform", "ends"])
def test_bang_bang_of_a_constant_inertia_is_exact(grid):
    """|M·τ̈| ≤ L from rest to rest over τ ∈ [0, 1]: accelerate at L/M to the middle, brake: T = 2√(M/L)."""
    tau = np.linspace(0.0, 1.0, 2001) if grid == "uniform" else bound_grid(2000)
    b = topp(*_rows(len(tau)), tau, rest=True)
    assert law_duration(b, tau) == pytest.approx(2.0 * np.sqrt(2.0 / 5.0), rel=1e-3 if grid == "ends" else 1e-9)
    assert np.all(np.abs(2.0 * np.diff(b) / (2.0 * np.diff(tau))) <= 5.0 * (1 + 1e-9))  # |M·a| ≤ L, a = Δb/(2Δτ)


def test_gravity_over_the_limit_has_no_bound():
    tau = np.linspace(0.0, 1.0, 101)
    with pytest.raises(ValueError, match="no traversal"):
        topp(*_rows(len(tau), G=6.0), tau, rest=True)


def test_adept_bound_matches_toppra_and_converges():
    """TOPP-RA (toppra 0.6, arc-length parameter, 1000 grid points, our motor-torque model as a custom
    constraint: bench/bench_bound.py, bench/results/bound.json) gives 0.07644 s on the Adept cycle with the default
    (rigid-body) Delta model, and 0.0768 s with the lumped model."""
    model = motion_model(plan_path(ADEPT, "bspline"), load_profile(None))
    t = torque_bound(model)
    assert t == pytest.approx(0.07644, rel=2e-3)
    assert torque_bound(motion_model(plan_path(ADEPT, "bspline"), lumped(load_profile(None)))) == pytest.approx(
        0.0768, rel=2e-3)
    assert torque_bound(model, points=4000) == pytest.approx(t, rel=5e-4)


@pytest.mark.parametrize("profile, method", [(None, "bspline"), (None, "ph"), ("scara-600", "lame")])
def test_bound_is_below_every_law_that_holds_the_limits(profile, method):
    prof = load_profile(profile)
    task = ADEPT if profile is None else Task(np.array([0.35, -0.2, 0.0]), np.array([0.3, 0.25, 0.0]), 0.03, 0.5)
    res = plan(task, prof, PlanOptions(method=method, time="optimal"))
    d = res.duration
    assert d.t_bound is not None and 0 < d.t_bound < d.seconds <= d.t_fit * (1 + 1e-9)
    assert res.summary()["torque_bound_s"] == d.t_bound


@pytest.mark.parametrize("name, task", [("delta-su2018", Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5)),
                                        ("scara-600", Task([0.3, 0.2, -0.1], [0.45, -0.15, -0.12], 0.03, 0.5)),
                                        ("delta-4axis", Task([-0.1, 0.05, -0.8], [0.12, -0.05, -0.78], 0.03, 0.5))])
def test_the_bound_from_the_laws_grid_data_is_the_same(name, task):
    """``--time optimal`` takes the bound's model terms from the time law's grid data (one model evaluation for
    both): the bound is the one evaluated on its own, to the bit (each term is computed point by point)."""
    from pickplace_cli.planner import PlanOptions, motion_model, plan
    from pickplace_cli.timing.optimal import sqp_data
    from tests.property.test_limit_truth import _profile

    prof = _profile(name)
    fit = plan(task, prof, PlanOptions(time="fit"))
    model = motion_model(fit.cartesian.path, prof)
    assert torque_bound(model, data=sqp_data(model)) == torque_bound(model)
    opt = plan(task, prof, PlanOptions(time="optimal"))
    assert opt.duration.t_bound == torque_bound(model)
