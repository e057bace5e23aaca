"""compare (pickplace_cli.studies.compare): continuity class, true peaks, geometry, rows, writers."""

from __future__ import annotations

import csv
import io
import json

import numpy as np
import pytest

from pickplace_cli.studies import compare as cmp
from pickplace_cli.model.errors import TaskError
from pickplace_cli.curves.laws import POLY345, MotionLaw
from pickplace_cli.paths import Method, plan_path
from pickplace_cli.planner import PlanOptions, plan
from pickplace_cli.model.profile import load_profile
from pickplace_cli.model.task import Task
from pickplace_cli.model.trajectory import CartesianPath
from tests.conftest import ADEPT_FROM, ADEPT_TO

ADEPT = Task(ADEPT_FROM, ADEPT_TO, 0.025)


def _line_path(u_of_tau, breakpoints=(0.0, 1.0), params=None, origin=(0.0, 0.0, 0.0)) -> CartesianPath:
    """A straight move along x from ``origin`` driven by u_of_tau(tau, order) (m); peaks are not used."""

    def ev(tau, order):
        out = np.zeros((len(tau), 3))
        out[:, 0] = u_of_tau(tau, order)
        return out + np.asarray(origin) if order == 0 else out

    return CartesianPath(ev, "test", params or {}, (1.0, 1.0, 1.0), np.asarray(breakpoints, float))


# ------------------------------------------------------------------------------------- continuity


def test_bspline_is_C3_with_no_jumps():
    c = cmp.continuity(plan_path(ADEPT, "bspline"))
    assert c.order == 3 and c.label == "C3" and c.jumps == () and c.unbounded == () and c.jerk_continuous


def test_345_law_has_a_jerk_step_at_both_ends_of_exact_size():
    """3-4-5 from rest: v and a join rest, the jerk jumps 0 → s‴(0) = 60 (b = 1, T = 1), to 1e-6 relative
    (the one-sided limit is extrapolated from 1e-7 and 2e-7: error ~1e-14·|s⁗| ≈ 4e-12)."""
    c = cmp.continuity(_line_path(lambda t, k: POLY345(t, k)))
    assert c.order == 2 and c.label == "C2" and not c.jerk_continuous
    assert [(j.order, j.tau) for j in c.jumps] == [(3, 0.0), (3, 1.0)]
    for j in c.jumps:
        assert j.size == pytest.approx(60.0, rel=1e-6)
        assert j.relative == pytest.approx(1.0, rel=1e-6)  # 60 is also the jerk's peak


def test_cubic_law_is_C1():
    """s = 3τ² − 2τ³: the acceleration jumps 0 → 6 at the start and 6 → 0... (−6 at the end)."""
    cubic = MotionLaw("cubic", (0.0, 0.0, 3.0, -2.0))
    c = cmp.continuity(_line_path(lambda t, k: cubic(t, k)))
    assert c.order == 1
    acc = [j for j in c.jumps if j.order == 2]
    assert [j.tau for j in acc] == [0.0, 1.0] and all(j.size == pytest.approx(6.0, rel=1e-6) for j in acc)


def test_undeclared_interior_jump_is_found_by_the_scan():
    """Two 3-4-5 rises of different amplitude back to back, breakpoint NOT declared: the jerk jumps at
    τ = 0.5 by |A2 − A1|·60/0.5³ (s‴(1) = s‴(0) = 60); the scan locates it to 1e-9 and measures it to 1e-6."""
    a1, a2 = 0.1, 0.3

    def u(t, k):
        return a1 * POLY345.over(t, 0.0, 0.5, k) + a2 * POLY345.over(t, 0.5, 0.5, k)

    c = cmp.continuity(_line_path(u, breakpoints=(0.0, 1.0)))
    inner = [j for j in c.jumps if 0 < j.tau < 1]
    assert len(inner) == 1 and inner[0].order == 3
    assert inner[0].tau == pytest.approx(0.5, abs=1e-9)
    assert inner[0].size == pytest.approx((a2 - a1) * 60 / 0.125, rel=1e-6)
    # the same with the breakpoint declared gives the same jump
    c2 = cmp.continuity(_line_path(u, breakpoints=(0.0, 0.5, 1.0)))
    inner2 = [j for j in c2.jumps if 0 < j.tau < 1]
    assert len(inner2) == 1 and inner2[0].size == pytest.approx(inner[0].size, rel=1e-9)


def test_jerk_unbounded_at_the_ends_is_reported():
    """u = τ^2.5 (1 − τ)^2.5: v and a vanish at the ends but the jerk grows like τ^−½ (a Lamé m < 3 end)."""

    def u(t, k):
        t = np.asarray(t, float)
        # derivatives of f·g with f = t^2.5, g = (1 − t)^2.5 by Leibniz (orders ≤ 3)
        def f(n):
            c = [1.0, 2.5, 2.5 * 1.5, 2.5 * 1.5 * 0.5][n]
            return c * np.power(t, 2.5 - n)

        def g(n):
            c = [1.0, -2.5, 2.5 * 1.5, -2.5 * 1.5 * 0.5][n]
            return c * np.power(1 - t, 2.5 - n)

        from math import comb

        with np.errstate(divide="ignore", invalid="ignore"):
            out = sum(comb(k, i) * f(i) * g(k - i) for i in range(k + 1))
        return np.where(np.isfinite(out), out, 0.0)  # a method returns a finite value exactly at the ends

    c = cmp.continuity(_line_path(u))
    assert c.order == 2 and c.unbounded == (3,)
    assert c.label == "C2 (jerk unbounded at the ends)"


def test_declared_continuity_is_read_but_not_trusted():
    c = cmp.continuity(_line_path(lambda t, k: POLY345(t, k), params={"continuity": "C3"}))
    assert c.declared == 3 and c.order == 2 and c.as_dict()["declared"] == "C3"


# -------------------------------------------------------------------------------- peaks, geometry


def test_true_peaks_match_exact_values():
    """3-4-5: (15/8, 10/√3, 60) exactly; B-spline: the method's exact piecewise-polynomial peaks. 1e-9
    relative: golden section brackets the maximum to ~4e-12 in τ (quadratic error ~1e-20)."""
    pk = cmp.true_peaks(_line_path(lambda t, k: POLY345(t, k)))
    np.testing.assert_allclose(pk, (15 / 8, 10 / np.sqrt(3), 60.0), rtol=1e-9)
    path = plan_path(ADEPT, "bspline")
    np.testing.assert_allclose(cmp.true_peaks(path), path.peaks, rtol=1e-9)


def test_geometry_of_the_adept_bspline_against_brute_force():
    """Backward drift ≈ 2.2 mm (README), forward the same by symmetry, top exactly at h: compared with a
    400,001-sample maximum (sampling error ≤ ½|u″|Δτ² ≈ 1e-12 m); tolerance 1e-9 m."""
    path = plan_path(ADEPT, "bspline")
    g = cmp.path_geometry(path, ADEPT)
    tau = np.linspace(0, 1, 400_001)
    p = path(tau, 0)
    u = (p - ADEPT.p_from) @ ADEPT.e_u
    assert g.drift_back == pytest.approx(-u.min(), abs=1e-9) and 0.0021 < g.drift_back < 0.0023
    assert g.drift_forward == pytest.approx(u.max() - ADEPT.b, abs=1e-9)
    assert g.drift == max(g.drift_back, g.drift_forward)
    assert g.max_height == pytest.approx(0.025, abs=1e-8)
    assert abs(g.overshoot) < 1e-8


def test_geometry_of_a_monotone_move_has_no_drift():
    g = cmp.path_geometry(_line_path(lambda t, k: 0.3 * POLY345(t, k), origin=ADEPT_FROM),
                          Task(ADEPT_FROM, ADEPT_FROM + [0.3, 0, 0], 0.02))
    assert g.drift_back == 0.0 and g.drift_forward == pytest.approx(0.0, abs=1e-15)
    assert g.max_height == 0.0 and g.overshoot == pytest.approx(-0.02)


# --------------------------------------------------------------------------------------- the rows


@pytest.fixture(scope="module")
def delta():
    return load_profile("delta-su2018")


def test_row_agrees_with_plan(delta):
    comp = cmp.compare_methods(ADEPT, delta, "bspline")
    (row,) = comp.rows
    ref = plan(ADEPT, delta, PlanOptions())
    assert row.ok and row.method == "bspline"
    # the fit: solved and confirmed by compare's plan; where the capacity binds, the default's plan only screens it
    # (its parabola-vertex estimate on the first samples' grid, documented to ~1e-6)
    assert row.duration == ref.duration.seconds and row.auto == ref.duration.t_auto
    assert row.fit == pytest.approx(ref.duration.t_fit, rel=1e-6)
    v, a, j = ref.cartesian.peaks()
    # measured peaks vs the method's exact ones: 1e-9 relative (see test_true_peaks_match_exact_values)
    assert row.peak_speed == pytest.approx(v, rel=1e-9) and row.peak_acceleration == pytest.approx(a, rel=1e-9)
    assert row.peak_jerk == pytest.approx(j, rel=1e-9)
    assert row.a_norm == pytest.approx(ref.cartesian.path.peaks[1] / ADEPT.b, rel=1e-9)
    mt = max(r.utilisation for r in ref.report.rows if r.quantity == "motor torque")
    tr = max(r.utilisation for r in ref.report.rows if r.quantity == "motor torque rate")
    assert row.motor_torque_use == pytest.approx(mt, rel=1e-12) and row.torque_rate_use == pytest.approx(tr, rel=1e-12)
    # joint torque on the ≥ 1001-point grid vs the 1 kHz output samples: the grid is finer, so ≥, and
    # within 0.1 % (both sample a smooth curve at spacing ≤ 1e-3 of the move)
    out_peak = np.max(np.abs(ref.joint.torque))
    assert out_peak <= row.joint_torque_peak * (1 + 1e-12) and row.joint_torque_peak == pytest.approx(out_peak, rel=1e-3)
    assert row.joint_torque_unit == "N·m" and row.limits_ok
    assert row.continuity.label == "C3" and row.vibration is not None and row.notes == ()
    assert row.paper_duration is None  # the B-spline's paper formula (Eq. 26) is what auto computes


def test_li2018_table1_bspline_column_through_compare(delta):
    """[Li2018, Table 1] B-spline at λ = 28, η = 0.5, k1 = 0.31, k2 = 0.12: a_max 9.0, j_max 84.0 (the
    paper rounds: we get 9.0153 and 84.079, README) — 0.2 % covers the paper's rounding to 0.1 of 84."""
    task = Task([-0.14, 0, -0.8], [0.14, 0, -0.8], 0.28 / 28)
    (row,) = cmp.compare_methods(task, delta, "bspline", {"bspline": {"k1": 0.31, "k2": 0.12}}).rows
    assert row.a_norm == pytest.approx(9.0153, rel=1e-4) and row.j_norm == pytest.approx(84.079, rel=1e-4)
    assert row.a_norm == pytest.approx(9.0, rel=2e-3) and row.j_norm == pytest.approx(84.0, rel=2e-3)


def test_li2018_section4_cycle_time_on_the_gantry():
    """[Li2018, Sec. 4] b = 0.7 m, [v] = 10 m/s, [a] = 160 m/s² (the shipped gantry's capacity): B-spline
    0.198 s. With our exact a_max 9.0153 the time is 0.1986 s; the paper used its rounded 9.0 (0.1984 s)."""
    gantry = load_profile("gantry")
    task = Task([-0.35, 0, -0.5], [0.35, 0, -0.5], 0.7 / 28)
    (row,) = cmp.compare_methods(task, gantry, "bspline", {"bspline": {"k1": 0.31, "k2": 0.12}}).rows
    assert row.auto == pytest.approx(np.sqrt(9.0153 * 0.7 / 160), rel=1e-4)
    assert row.auto == pytest.approx(0.198, abs=1e-3)
    assert row.fit is None  # the gantry has no time-dependent limit
    assert row.motor_torque_use is None and row.joint_torque_unit == "N"


def test_every_registered_method_gets_a_row(delta):
    comp = cmp.compare_methods(ADEPT, delta)
    assert [r.method for r in comp.rows] == [m.value for m in Method]
    for r in comp.ok_rows:
        assert r.duration > 0 and r.geometry is not None and r.continuity is not None


def test_errors_become_rows_and_bad_arguments_raise(delta):
    vertical = Task(ADEPT_FROM, ADEPT_FROM + [0, 0, 0.05], 0.02)
    (row,) = cmp.compare_methods(vertical, delta, "bspline").rows
    assert not row.ok and "b = 0" in row.error and row.exit_code == 1
    far = Task([0.0, 0.0, -0.8], [1.0, 0.0, -0.8], 0.05)
    (row,) = cmp.compare_methods(far, delta, "bspline").rows
    assert not row.ok and row.exit_code == 4
    with pytest.raises(TaskError, match="unknown method"):
        cmp.compare_methods(ADEPT, delta, "bspline,nope")
    with pytest.raises(TaskError, match="empty method name"):
        cmp.compare_methods(ADEPT, delta, "bspline,,")
    with pytest.raises(TaskError, match="not among the compared methods"):
        cmp.compare_methods(ADEPT, delta, "bspline", {"nope": {}})
    with pytest.raises(TaskError, match="time"):
        cmp.compare_methods(ADEPT, delta, "bspline", time="soon")


def test_time_fit_and_seconds(delta):
    (fit,) = cmp.compare_methods(ADEPT, delta, "bspline", time="fit").rows
    assert fit.duration == fit.fit and fit.duration_mode == "fit"
    # at T_fit every limit holds and the binding one is at 100 % (fit stops within 1e-7 relative)
    assert fit.limits_ok and fit.worst_limit.endswith(("100.0 %", "99.9 %")), fit.worst_limit
    (given,) = cmp.compare_methods(ADEPT, delta, "bspline", time=0.3).rows
    assert given.duration == 0.3 and given.duration_mode == "given"
    assert given.peak_acceleration == pytest.approx(given.a_norm * ADEPT.b / 0.09, rel=1e-12)


def test_no_vibration_section_no_vibration_column(delta):
    prof = delta.model_copy(update={"vibration": None})
    (row,) = cmp.compare_methods(ADEPT, prof, "bspline").rows
    assert row.vibration is None and row.as_dict()["residual_vibration"] is None


def test_writers(delta):
    comp = cmp.compare_methods(ADEPT, delta, "bspline")
    buf = io.StringIO()
    cmp.write_compare_csv(comp, buf)
    rows = list(csv.reader(io.StringIO(buf.getvalue())))
    assert rows[0][0] == "method" and "duration[s]" in rows[0] and "residual_amplitude[m]" in rows[0]
    assert len(rows) == 2 and rows[1][0] == "bspline" and rows[1][-1] == ""  # no error
    rec = dict(zip(rows[0], rows[1]))
    assert float(rec["duration[s]"]) == pytest.approx(comp.rows[0].duration, rel=1e-11)
    assert rec["continuity"] == "C3" and rec["jerk_continuous"] == "true"
    buf = io.StringIO()
    cmp.write_compare_json(comp, buf)
    doc = json.loads(buf.getvalue())
    assert doc["profile"] == "delta-su2018" and doc["rows"][0]["continuity"]["class"] == "C3"
    assert doc["rows"][0]["residual_vibration"]["amplitude_m"][1] == 0.0


# ------------------------------------------------------------------------ every registered method


@pytest.mark.parametrize("method", list(Method), ids=lambda m: m.value)
def test_measured_continuity_matches_each_methods_claim(method):
    """The numerical class equals what the method declares (``continuity``), and the measured jerk jumps
    sit exactly where it says (``jerk_jumps_at``, to 1e-9: the bisection/probe resolution) — the check is
    independent of the declaration (test_declared_continuity_is_read_but_not_trusted)."""
    # through the planner, which knows how to build every method (also one whose path depends on T)
    path = plan(ADEPT, load_profile("gantry"), PlanOptions(method=method, fit=False)).cartesian.path
    c = cmp.continuity(path)
    declared = path.parameters.get("continuity", 3 if method == Method.bspline else None)
    # a method without a declared class is held to what every method here guarantees: v and a continuous
    assert c.order == declared if declared is not None else c.order >= 2
    assert c.unbounded == ()
    if "jerk_jumps_at" in path.parameters:
        at = sorted(j.tau for j in c.jumps if j.order == 3)
        np.testing.assert_allclose(at, sorted(path.parameters["jerk_jumps_at"]), atol=1e-9)
    assert not [j for j in c.jumps if j.order < 3]  # v and a are continuous for every method


# [Li2018, Table 1] (λ = 28, η = 0.5) and Sec. 4 (b = 0.7 m, [v] = 10, [a] = 160: the shipped gantry)
LI_TABLE1 = {  # method: (a_max, j_max, cycle time [s])
    "lame": (7.8, 242.1, 0.185),
    "piecewise-poly": (13.7, 132.5, 0.245),
    "bspline": (9.0, 84.0, 0.198),
}


@pytest.mark.parametrize("method", list(LI_TABLE1))
def test_li2018_table1_and_section4_through_compare(method):
    """Normalised peaks to the paper's rounding (0.05; j_max of the B-spline 0.1: the paper prints 84.0
    for 84.079, see README), cycle times to 1 ms (the paper's times follow from its rounded a_max:
    √(a·b/[a]) with a = 7.8, 13.7, 9.0 gives 0.1847, 0.2448, 0.1984 s)."""
    if method not in {m.value for m in Method}:
        pytest.skip(f"{method} is not registered")
    a_pap, j_pap, t_pap = LI_TABLE1[method]
    task = Task([-0.35, 0, -0.5], [0.35, 0, -0.5], 0.7 / 28)
    params = {"bspline": {"k1": 0.31, "k2": 0.12}} if method == "bspline" else None
    (row,) = cmp.compare_methods(task, load_profile("gantry"), method, params).rows
    assert row.a_norm == pytest.approx(a_pap, abs=0.05)
    assert row.j_norm == pytest.approx(j_pap, abs=0.1 if method == "bspline" else 0.05)
    assert row.auto == pytest.approx(t_pap, abs=1e-3)
    assert np.sqrt(a_pap * 0.7 / 160) == pytest.approx(t_pap, abs=5e-4)
    assert row.binding == "acceleration"


def test_paper_formula_reported_next_to_true_peak_time():
    """PH [Su2018, Eq. (22)] bounds only the tangential acceleration and superposition [Eq. (26)–(27)] only
    each axis': both give a shorter time than the true |a| ≤ [a] needs; the row says so."""
    names = {m.value for m in Method}
    if not {"ph", "superposition"} <= names:
        pytest.skip("ph/superposition not registered")
    comp = cmp.compare_methods(ADEPT, load_profile("gantry"), "ph,superposition")
    for row in comp.rows:
        assert row.paper_duration is not None and row.paper_duration < row.auto
        assert row.paper_formula.startswith("Su2018 Eq. (2")
        assert any("gives" in n and "true peaks" in n for n in row.notes)
