"""Constrained workspace (pickplace_cli.studies.workspace): membership, APF point [Su2018, Eq. (25)], lowering h."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

from pickplace_cli.model.errors import TaskError, UnreachableError
from pickplace_cli.limits.check import check_limits
from pickplace_cli.limits.grid import check_grid
from pickplace_cli.paths import Method, plan_path
from pickplace_cli.planner import motion_model
from pickplace_cli.model.profile import load_profile
from pickplace_cli.model.task import Task
from pickplace_cli.studies.workspace import APF_MARGIN, Workspace, apf_point, fit_workspace


@pytest.fixture(scope="module")
def delta():
    return load_profile("delta-su2018")


@pytest.fixture(scope="module")
def gantry():
    return load_profile("gantry")


def _apf_offset(D: float, delta: float = APF_MARGIN) -> float:
    """Equilibrium depth d inside a flat boundary for a point D outside: (D + d)·d³ = δ⁴ (module doc)."""
    return brentq(lambda d: (D + d) * d**3 - delta**4, 0.0, delta)


def test_workspace_constraints_and_messages(delta):
    ws = Workspace(delta)
    assert ws.names[0] == "q1 position min -0.698132 rad" and ws.names[6] == "singularity measure min 0.05"
    assert ws.names[-1] == "workcell z max -0.55 m"
    P = np.array([[0, 0, -0.8], [0, 0, -0.53], [2.0, 0, -0.8]])
    np.testing.assert_array_equal(ws.inside(P), [True, False, False])
    assert ws.violation(P[0]) is None
    assert ws.violation(P[1]) == "workcell z max -0.55 m (violated by 0.02)"
    assert ws.violation(P[2]).startswith("unreachable: Delta: sample 0 at p = (2, 0, -0.8) m is unreachable")
    g = ws.slacks(P)
    assert g.shape == (3, len(ws.names)) and np.all(np.isneginf(g[2, :7]))
    assert g[1, -1] == pytest.approx(-0.02, abs=1e-15)


def test_distance_is_exact_for_a_box_face(gantry):
    """Gantry: the travel is the workspace, q = p, so g/‖∇g‖ is the exact distance (central differences
    of a linear function: exact to round-off, 1e-9 m)."""
    ws = Workspace(gantry)
    d, grad = ws.distance(np.array([0.9, 0.0, -0.5]))
    assert d == pytest.approx(0.1, abs=1e-9)
    np.testing.assert_allclose(grad, [-1, 0, 0], atol=1e-6)


def test_apf_equilibrium_on_the_gantry_travel(gantry):
    """A point D = 0.05 m beyond x max = 1 m: the APF equilibrium is at x = 1 − d, (D + d)d³ = δ⁴, y and z
    unchanged. 1e-8 m: the descent stops at steps < 1e-10 m and the distance is exact for this face."""
    ws = Workspace(gantry)
    p, it = apf_point(ws, np.array([1.05, 0.2, -0.5]))
    d = _apf_offset(0.05)
    np.testing.assert_allclose(p, [1.0 - d, 0.2, -0.5], atol=1e-8)
    assert 0 < it < 2000


def test_apf_equilibrium_below_the_delta_workcell_top(delta):
    """Delta, 20 mm above the workcell's top z = −0.55 m: adjusted to z = −0.55 − d (box face: exact)."""
    ws = Workspace(delta)
    p, _ = apf_point(ws, np.array([0.0, 0.0, -0.53]))
    np.testing.assert_allclose(p, [0.0, 0.0, -0.55 - _apf_offset(0.02)], atol=1e-8)


def test_apf_point_beyond_the_reach_is_the_nearest_inside(delta):
    """(0.45, 0.3, −1.05) m: outside (joint range / singularity / box). The APF point must be inside, within
    2δ of the boundary toward the requested point, and no farther from it than the nearest inside point of
    a 4 mm brute-force grid (+ 4 mm grid resolution · √3/2 + δ)."""
    ws = Workspace(delta)
    req = np.array([0.45, 0.3, -1.05])
    assert ws.violation(req) is not None
    p, _ = apf_point(ws, req)
    assert ws.inside(p[None, :])[0]
    dist = np.linalg.norm(p - req)
    toward = p + 2 * APF_MARGIN * (req - p) / dist
    assert not ws.inside(toward[None, :])[0]
    axes = [np.arange(c - 0.12, c + 0.12, 0.004) for c in req]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    ok = ws.inside(grid)
    best = np.min(np.linalg.norm(grid[ok] - req, axis=1))
    assert dist <= best + 0.004 * np.sqrt(3) / 2 + APF_MARGIN


def test_point_outside_is_refused_by_default(delta):
    task = Task([0.0, 0.0, -0.53], [0.1, 0.0, -0.8], 0.025)
    with pytest.raises(UnreachableError, match=r"from = \(0, 0, -0.53\) m is outside the workspace: workcell z max") as exc:
        fit_workspace(task, delta)
    assert exc.value.exit_code == 4 and "never moved silently" in str(exc.value)


def test_point_adjusted_only_when_asked_and_reported(gantry):
    """A pick point 3 mm below the gantry's z travel: moved to z = −1 + d (the face is exact), 1e-8 m."""
    task = Task([0.0, 0.0, -1.003], [0.3, 0.0, -0.9], 0.025)
    fit = fit_workspace(task, gantry, adjust_points=True)
    (adj,) = fit.adjustments
    assert adj.name == "from" and adj.distance == pytest.approx(0.003 + _apf_offset(0.003), abs=1e-8)
    np.testing.assert_allclose(fit.task.p_from, [0, 0, -1.0 + _apf_offset(0.003)], atol=1e-8)
    np.testing.assert_array_equal(fit.task.p_to, task.p_to)  # the other point is untouched
    np.testing.assert_array_equal(fit.requested.p_from, task.p_from)
    assert fit.changed and "moved by the APF" in fit.changes()[0] and "travel of axis z" in fit.changes()[0]
    doc = fit.as_dict()
    assert doc["adjustments"][0]["distance_m"] == adj.distance and doc["changed"]


def test_point_too_far_terminates(gantry):
    task = Task([0.0, 0.0, -1.2], [0.3, 0.0, -0.9], 0.025)
    with pytest.raises(UnreachableError, match=r"more than max_shift = 0.01 m: the part cannot be picked"):
        fit_workspace(task, gantry, adjust_points=True)
    fit = fit_workspace(task, gantry, adjust_points=True, max_shift=0.5)
    assert fit.adjustments[0].distance == pytest.approx(0.2 + _apf_offset(0.2), abs=1e-8)


def test_lowering_h_until_the_path_is_inside(delta):
    """Pick and place 50 mm below the workcell's top, h = 0.1 m: the path would rise 50 mm above the box.
    h is lowered in 1 mm steps to the first value at which the exact reach check passes; one step higher
    it fails (so the step search stopped at the first feasible h)."""
    task = Task([-0.1525, 0, -0.6], [0.1525, 0, -0.6], 0.1)
    fit = fit_workspace(task, delta)
    assert fit.steps > 0 and fit.changed and not fit.adjustments
    assert fit.task.height == pytest.approx(0.1 - fit.steps * 0.001, abs=1e-12)
    assert 0.045 <= fit.task.height <= 0.05
    assert "workcell z max" in fit.violation and "height lowered from 0.1 m" in fit.changes()[0]
    # the worst point of the requested path (its top, 0.1 - 0.05 = 0.05 m above the box; review, session 16: the
    # first point out, violated by ~0, was named)
    assert "worst at τ = 0.5000" in fit.violation and fit.violation.endswith("(violated by 0.05)")

    def reach_ok(h):
        path = plan_path(Task(task.p_from, task.p_to, h), "bspline")
        model = motion_model(path, delta)
        rep = check_limits(model, 1.0, parts=model.parts(check_grid(np.array([0.0, 1.0]), path.breakpoints)))
        return not [r for r in rep.violations if r.kind == "reach"]

    assert reach_ok(fit.task.height) and not reach_ok(fit.task.height + 0.001)


def test_inside_move_is_unchanged(delta):
    task = Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025)
    fit = fit_workspace(task, delta)
    assert not fit.changed and fit.steps == 0 and fit.violation is None and fit.changes() == []
    assert fit.task.height == task.height and fit.path.method == "bspline"


def test_no_height_fits(delta):
    """A pick 1 mm below the workcell top: no clearance ≥ 1 mm (nor the table's λ ≤ 40) keeps it inside."""
    task = Task([-0.1525, 0, -0.551], [0.1525, 0, -0.8], 0.025)
    with pytest.raises(UnreachableError, match="height: ") as exc:
        fit_workspace(task, delta)
    assert exc.value.exit_code == 4 and "workcell z max" in str(exc.value)


@pytest.mark.parametrize("name, value", [("step", 0.0), ("min_height", -1.0), ("margin", float("nan")), ("max_shift", 0.0)])
def test_bad_options(delta, name, value):
    task = Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025)
    with pytest.raises(TaskError, match=name):
        fit_workspace(task, delta, **{name: value})


@pytest.mark.parametrize("method", [m for m in Method if m.value != "bspline"], ids=lambda m: m.value)
def test_every_method_can_be_fitted(delta, method):
    task = Task([-0.1525, 0, -0.6], [0.1525, 0, -0.6], 0.08)
    try:
        plan_path(task, method)
    except (TypeError, TaskError) as exc:  # a path that depends on the duration needs it in method_params
        pytest.skip(f"{method.value}: {exc}")
    fit = fit_workspace(task, delta, method)
    assert fit.path.method == method.value and fit.task.height <= 0.05 and fit.steps >= 30


def test_a_move_that_cannot_be_planned_keeps_its_own_error(delta):
    """λ = 3e5 is beyond any (k1, k2) optimum: TableError (exit 1), not a workspace verdict."""
    from pickplace_cli.model.errors import TableError

    with pytest.raises(TableError, match="lambda = b/h = 3e"):
        fit_workspace(Task([-0.15, 0, -0.8], [0.15, 0, -0.8], 1e-6), delta)


# ------------------------------------------------------------------ radial extent (profile show's sentence)


def test_radial_extent_scara_matches_the_closed_form():
    """SCARA at its default height: the band is r_min (q2 at its ±150° stop) … r_max (|sin q2| = the margin
    0.05), and a direction reaches the whole band iff q1 = θ + β(r) stays within ±132° for every r in it,
    β(r) = atan2(l2·sin|q2|, l1 + l2·cos q2) (elbow right, q2 < 0). Tolerance: the 1 mm scan grid."""
    from pickplace_cli.studies.workspace import radial_extent

    prof = load_profile("scara-600")
    l1, l2 = prof.robot.link1.length, prof.robot.link2.length
    q2_stop, margin = prof.robot.joint_specs()[1].limits.position[1], prof.robot.singularity_margin
    r_min = np.sqrt(l1**2 + l2**2 + 2 * l1 * l2 * np.cos(q2_stop))
    r_max = np.sqrt(l1**2 + l2**2 + 2 * l1 * l2 * np.cos(np.arcsin(margin)))
    ext = radial_extent(prof, -0.1)
    assert ext.band[0] == pytest.approx(r_min, abs=1e-3) and ext.band[1] == pytest.approx(r_max, abs=1e-3)

    def beta(r):
        c2 = (r**2 - l1**2 - l2**2) / (2 * l1 * l2)
        return np.arctan2(l2 * np.sqrt(1 - c2**2), l1 + l2 * c2)

    q1_max = prof.robot.joint_specs()[0].limits.position[1]
    lo, hi = ext.band
    theta = np.degrees((ext.azimuth + np.pi) % (2 * np.pi) - np.pi)
    expect = (np.radians(theta) + beta(lo) <= q1_max) & (np.radians(theta) + beta(hi) >= -q1_max)
    np.testing.assert_array_equal(ext.full, expect)
    assert ext.full.sum() == 42 and ext.sectors() == [(-135.0, 70.0)]
    text = ext.describe()
    assert text.startswith("radius 0.163 … 0.599 m reachable in 42 of 72 directions (azimuth -135° … 70°, every 5°)")
    assert "21 more reach only part of that range and 9 reach nothing" in text and "no common radius" not in text


def test_radial_extent_delta_disc_and_errors(delta):
    from pickplace_cli.studies.workspace import radial_extent

    from pickplace_cli.robots import build_robot, radial_reach

    ext = radial_extent(delta, -0.825, directions=12)
    # the common disc agrees with robots.radial_reach, an independent scan of the same constraints (same 1 mm
    # grid, so exactly; 12 directions: its point-by-point fallback is slow)
    inner, outer, n = radial_reach(build_robot(delta.robot), delta.robot.joint_specs(), -0.825,
                                   delta.robot.singularity_margin, directions=12)
    assert ext.reached == n == 12
    assert max(r[0] for r in ext.runs) == inner and min(r[1] for r in ext.runs) == pytest.approx(outer, abs=1e-12)
    assert ext.describe().startswith(f"radius {inner:.3f} … {outer:.3f} m reachable in every direction; in some directions out to ")
    assert radial_extent(delta, 0.5).describe().startswith("nothing is reachable at this height")
    for z in (float("nan"), float("inf")):
        with pytest.raises(TaskError, match=r"z = (nan|inf): must be a finite height in m"):
            radial_extent(delta, z)
