"""The B-spline family's lift-off/set-down and midpoint-placement parameters (``eta_down``, ``mid_x``): their
defaults are Li's path bit for bit, their geometry matches a B-spline solved here from its definition, a plan on
them passes the limit check, and bad values are one-line errors with exit 1."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.interpolate import BSpline
from typer.testing import CliRunner

from pickplace_cli.cli.app import app
from pickplace_cli.model.errors import TaskError
from pickplace_cli.model.profile import load_profile
from pickplace_cli.model.task import Task
from pickplace_cli.paths import plan_path
from pickplace_cli.planner import PlanOptions, plan

ADEPT = Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5)
TILTED = Task([-0.1, 0.05, -0.85], [0.12, -0.03, -0.78], 0.04, 0.3)
TAU = np.linspace(0.0, 1.0, 2001)


@pytest.mark.parametrize("task", [ADEPT, TILTED])
def test_defaults_are_li_path_bitwise(task):
    """eta_down and mid_x left at None are Li's path: every order at every τ bitwise, the same parameters."""
    li = plan_path(task, "bspline", k1=0.3, k2=0.2)
    same = plan_path(task, "bspline", k1=0.3, k2=0.2, eta_down=None, mid_x=None)
    for order in range(4):
        assert np.array_equal(li.evaluate(TAU, order), same.evaluate(TAU, order))
    assert li.parameters == same.parameters
    assert li.peaks == same.peaks


def _independent(task: Task, k1: float, k2: float, eta_down: float, mid_x: float) -> BSpline:
    """The path from its definition, solved here: a clamped quintic B-spline on Li's knots [Li2018, Eq. (14)]
    with its first and last four control points at the ends, through P2 = P1 + η·(z_top − z1) e_z at τ8,
    P3 = P1 + mid_x·(P5 − P1) horizontally at z_top at τ9, P4 = P5 + eta_down·(z_top − z5) e_z at τ10 (scipy's
    design matrix, three unknown control points)."""
    t = np.array([0.0] * 6 + [k1 * k2 / 2, k1 / 2, 0.5, 1 - k1 / 2, 1 - k1 * k2 / 2] + [1.0] * 6)
    p1, p5 = task.p_from, task.p_to
    zt = max(p1[2], p5[2]) + task.height
    p2 = p1.copy(); p2[2] = p1[2] + task.eta * (zt - p1[2])
    p4 = p5.copy(); p4[2] = p5[2] + eta_down * (zt - p5[2])
    p3 = p1 + mid_x * (p5 - p1); p3[2] = zt
    B = BSpline.design_matrix(np.array([t[7], t[8], t[9]]), t, 5).toarray()
    ctrl = np.zeros((11, 3))
    ctrl[:4], ctrl[7:] = p1, p5
    rhs = np.array([p2, p3, p4]) - B[:, :4] @ ctrl[:4] - B[:, 7:] @ ctrl[7:]
    ctrl[4:7] = np.linalg.solve(B[:, 4:7], rhs)
    return BSpline(t, ctrl, 5)


@pytest.mark.parametrize("task", [ADEPT, TILTED])
@pytest.mark.parametrize("eta_down, mid_x", [(0.1, 0.5), (0.5, 0.42), (0.8, 0.6)])
def test_geometry_against_its_definition(task, eta_down, mid_x):
    """Position to 1e-12 m and velocity, acceleration, jerk (relative to their peak, 1e-9: the derivatives
    cancel end terms of size ~1/τ7³) against the B-spline solved here; the set-down point's height is
    z5 + eta_down·(z_top − z5) and P3 lies at mid_x of the span, to 1e-12 m (hand derivation)."""
    k1, k2 = 0.3, 0.2
    path = plan_path(task, "bspline", k1=k1, k2=k2, eta_down=eta_down, mid_x=mid_x)
    ref = _independent(task, k1, k2, eta_down, mid_x)
    for order in range(4):
        got, want = path.evaluate(TAU, order), ref(TAU, order)
        scale = 1.0 if order == 0 else np.abs(want).max()
        assert np.abs(got - want).max() <= (1e-12 if order == 0 else 1e-9 * scale), order
    zt = max(task.p_from[2], task.p_to[2]) + task.height
    p4 = path.evaluate(np.array([1 - k1 / 2]), 0)[0]
    assert p4[2] == pytest.approx(task.p_to[2] + eta_down * (zt - task.p_to[2]), abs=1e-12)
    assert p4[:2] == pytest.approx(task.p_to[:2], abs=1e-12)
    p3 = path.evaluate(np.array([0.5]), 0)[0]
    assert p3[:2] == pytest.approx((task.p_from + mid_x * (task.p_to - task.p_from))[:2], abs=1e-12)
    assert p3[2] == pytest.approx(zt, abs=1e-12)
    assert path.parameters["eta_down"] == eta_down and path.parameters["mid_x"] == mid_x


def test_eta_down_at_eta_is_li_path():
    """eta_down = η and mid_x = 1/2 are Li's via points (computed another way: equal to 1e-15 m)."""
    li = plan_path(ADEPT, "bspline", k1=0.3, k2=0.2)
    same = plan_path(ADEPT, "bspline", k1=0.3, k2=0.2, eta_down=ADEPT.eta, mid_x=0.5)
    for order in range(4):
        a, b = li.evaluate(TAU, order), same.evaluate(TAU, order)
        assert np.abs(a - b).max() <= 1e-12 * max(1.0, np.abs(a).max()), order


def test_plan_on_new_parameters_passes_the_check():
    """A timed plan on the new parameters: the continuous check's verdict holds (fit duration on the Adept cycle)."""
    prof = load_profile("delta-su2018")
    got = plan(ADEPT, prof, PlanOptions(time="fit", method_params={"k1": 0.2, "k2": 0.1, "eta_down": 0.1,
                                                                    "mid_x": 0.48}))
    assert got.report.ok
    assert got.parameters["eta_down"] == 0.1


@pytest.mark.parametrize("name, bad", [("eta_down", 0.0), ("eta_down", 1.5), ("eta_down", float("nan")),
                                       ("mid_x", 0.1), ("mid_x", 0.95), ("mid_x", float("inf"))])
def test_bad_values_are_task_errors(name, bad):
    with pytest.raises(TaskError, match=name):
        plan_path(ADEPT, "bspline", k1=0.3, k2=0.2, **{name: bad})


@pytest.mark.parametrize("item", ["eta_down=1.2", "mid_x=0.05"])
def test_cli_bad_value_one_line_exit_1(item):
    r = CliRunner().invoke(app, ["plan", "--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8", "--k1", "0.3",
                                 "--k2", "0.2", "--param", item])
    assert r.exit_code == 1, r.output
    lines = [ln for ln in r.output.strip().splitlines() if ln.strip()]
    assert len(lines) == 1 and item.split("=")[0] in lines[0], r.output


def test_cli_optimize_shape_refuses_the_placement_parameters():
    """--optimize shape searches Li's placement of the via points: a given eta_down / mid_x is refused (exit 2,
    one line) rather than planned beside a shape searched without it."""
    r = CliRunner().invoke(app, ["plan", "--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8", "--optimize", "shape",
                                 "--time", "fit", "--param", "eta_down=0.2"])
    assert r.exit_code == 2, r.output
    lines = [ln for ln in r.output.strip().splitlines() if ln.strip()]
    assert len(lines) == 1 and "eta_down" in lines[0], r.output


#: the free-path minimum time of the Adept cycle on delta-su2018 (tests/reference/free_path.py, 12 intervals per
#: phase, best of four starts; bench/results/free_path.json): computing it takes ~3 min per case, so these cached
#: figures are used here; tests/unit/test_free_path_reference.py (slow) computes a coarse one and checks the
#: shipped search against it
REF_MOTORS, REF_CAPACITY = 0.10296385452799534, 0.12888472924248914


def test_shipped_search_against_the_free_path_minimum():
    """``--optimize shape --time optimal``: every limit held, never below the free-path minimum (a plan faster than
    it would mean a limit mis-evaluated), and within 3 % of it (measured 1.016 × motors alone, 1.021 × with the
    capacity: the 1 % aim is not reached by the shipped search; bench/bench_shape_limit.py). The law's own duration
    (the written 1 kHz file's may be a little longer: timing/written.py)."""
    prof = load_profile("delta-su2018")
    for capacity, ref in ((False, REF_MOTORS), (True, REF_CAPACITY)):
        got = plan(ADEPT, prof, PlanOptions(time="optimal", shape=True, hold_capacity=capacity))
        assert got.report.ok
        assert 0.995 * ref <= got.duration.t_optimal <= 1.03 * ref, (capacity, got.duration.t_optimal / ref)


def test_law_polished_placement_shape_against_the_free_path_minimum():
    """The best nine-parameter shape bench/bench_shape_limit.py found (Nelder-Mead on the optimal law's duration,
    40 law solves, motors alone): planned with the optimal law, its check holds and its duration lies within
    1.6 % of the free-path minimum (measured 1.0149 ×) and not below it."""
    prof = load_profile("delta-su2018")
    task = Task(ADEPT.p_from, ADEPT.p_to, ADEPT.height, 0.10333333333333339)
    params = {"k1": 0.18659928566624603, "k2": 0.7852149693961702, "arch": 0.19638555591867596 * ADEPT.height,
              "k3": 0.3304290331284749, "k4": 0.12422663343242493, "mid": 0.47908282751154624,
              "eta_down": 0.10000000000000003, "mid_x": 0.5096538468051957}
    got = plan(task, prof, PlanOptions(time="optimal", method_params=params))
    assert got.report.ok
    assert REF_MOTORS <= got.duration.t_optimal <= 1.016 * REF_MOTORS, got.duration.t_optimal / REF_MOTORS


@pytest.mark.parametrize("extra", [["--shape-law-evals", "5", "--time", "fit", "--optimize", "shape"],
                                   ["--shape-law-evals", "5", "--time", "optimal"]])
def test_cli_shape_law_evals_usage_exit_2(extra):
    r = CliRunner().invoke(app, ["plan", "--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8"] + extra)
    assert r.exit_code == 2, r.output
    assert "shape-law-evals" in r.output and "Traceback" not in r.output


def test_cli_shape_law_evals_not_an_integer_exit_1():
    """A count that is not an integer is invalid input (exit 1), like one out of range."""
    r = CliRunner().invoke(app, ["plan", "--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8", "--time", "optimal",
                                 "--optimize", "shape", "--shape-law-evals", "2.5"])
    assert r.exit_code == 1, r.output
    assert "--shape-law-evals" in r.output and "must be an integer" in r.output and "Traceback" not in r.output


@pytest.mark.parametrize("n", ["-1", "1001", "100000"])
def test_cli_shape_law_evals_out_of_range_exit_1(n):
    """An out-of-range count is invalid input (exit 1), one line naming the option, the value and the range, as
    --rate 0 or --limit-use 2 are."""
    r = CliRunner().invoke(app, ["plan", "--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8", "--optimize", "shape",
                                 "--time", "optimal", "--shape-law-evals", n])
    assert r.exit_code == 1, r.output
    assert f"--shape-law-evals {n}: must lie in 0 ... 1000" in r.output and "Traceback" not in r.output
    # without --optimize shape the option does not apply: that usage error (exit 2) comes first
    r = CliRunner().invoke(app, ["plan", "--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8", "--shape-law-evals", n])
    assert r.exit_code == 2 and "--shape-law-evals judges shapes by the optimal law" in r.output, r.output


def test_law_judged_search_against_the_free_path_minimum():
    """``shape_law_evals`` = 30 (COBYQA on the optimal law's duration after the screened search): never slower than
    the screened search's shape (it keeps a shape only when the law says faster), its check holds, not below the
    free-path minimum, and within 1.5 % of it on the Adept cycle, motors alone (measured 1.011 ×: the 1 % aim is not
    reached; bench/bench_shape_limit.py); the note says the budget searched."""
    prof = load_profile("delta-su2018")
    base = plan(ADEPT, prof, PlanOptions(time="optimal", shape=True))
    got = plan(ADEPT, prof, PlanOptions(time="optimal", shape=True, shape_law_evals=30))
    assert got.report.ok
    # the search ranks laws by their own duration (t_optimal); the written samples may slow the law a little more
    # so that check reads its 1 kHz file within every limit (timing/written.py: × 1.005 here)
    assert REF_MOTORS <= got.duration.t_optimal <= base.duration.t_optimal * (1 + 1e-9)
    assert got.duration.t_optimal <= 1.015 * REF_MOTORS, got.duration.t_optimal / REF_MOTORS
    assert got.duration.seconds == pytest.approx(got.duration.t_optimal * got.duration.written_stretch, rel=1e-12)
    assert 1.0 <= got.duration.written_stretch <= 1.01
    print("ratio", got.duration.t_optimal / REF_MOTORS, got.parameters["shape"]["note"])
    assert "law solves" in got.parameters["shape"]["note"]
