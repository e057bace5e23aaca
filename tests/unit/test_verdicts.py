"""The batched verdict engine (pickplace_cli.pipelines.verdicts) against plan() row by row.

The contract [issue 7, "a limit check never lies"]: a row the engine decides gets exactly the JSON line
plan() gives (same keys, same values: bitwise, since the engine does plan()'s arithmetic on stacked arrays),
and every other row is planned by plan() itself. Rows that violate a limit, are unreachable, are near a
limit or are invalid are therefore mixed into every agreement test.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pickplace_cli.pipelines.batch import plan_rows, read_batch_text
from pickplace_cli.model.errors import PickplaceError
from pickplace_cli.paths import plan_path
from pickplace_cli.planner import PlanOptions, motion_model, plan
from pickplace_cli.model.profile import load_profile
from pickplace_cli.model.task import Task
from pickplace_cli.pipelines.verdicts import (
    OFF_SWITCH,
    SCREEN_MARGIN,
    Verdict,
    batch_paths,
    decide,
    engine_applies,
    screen_block,
    verdict_rows,
    verdict_rows_parallel,
)

from .test_verdict_fit import scara

DELTA = load_profile("delta-su2018")
OPTS = PlanOptions(fit=False, time="auto")  # the engine decides the rows of auto and given seconds
HEADER = "from_x,from_y,from_z,to_x,to_y,to_z,height,time"


def random_batch(n: int, seed: int) -> str:
    """n moves over (and beyond) the Delta's workspace: some ok, some near or over a limit (short given
    times), some unreachable (far out), some outside the λ table (very low clearance)."""
    rng = np.random.default_rng(seed)
    lines = [HEADER]
    for _ in range(n):
        r = rng.uniform(0.02, 0.35)
        a = rng.uniform(0, 2 * np.pi)
        z0, z1 = rng.uniform(-0.95, -0.6, 2)
        c = rng.uniform(-0.25, 0.25, 2)
        h = rng.choice(["", f"{rng.uniform(0.005, 0.08):.4f}"])
        t = rng.choice(["", "", f"{rng.uniform(0.06, 0.3):.3f}"])
        lines.append(f"{c[0] - r * np.cos(a):.4f},{c[1] - r * np.sin(a):.4f},{z0:.4f},"
                     f"{c[0] + r * np.cos(a):.4f},{c[1] + r * np.sin(a):.4f},{z1:.4f},{h},{t}")
    return "\n".join(lines) + "\n"


def line(res) -> str:
    """The batch JSON line of a RowResult, as cli._plan_batch writes it."""
    doc = {"row": res.row, "exit_code": res.code, "error": res.error}
    if res.plan is not None:
        doc.update(res.plan.summary())
        doc["violations"] = [v.as_dict() for v in res.plan.report.violations]
    return json.dumps(doc)


def planned_both_ways(text: str, options):
    """(rows, plan()'s RowResults, the engine's RowResults) of a batch text on the Delta."""
    rows, bad = read_batch_text(text, "rand")
    assert not bad
    return rows, list(plan_rows(rows, DELTA, options, source="rand")), list(verdict_rows(rows, DELTA, options, source="rand"))


@pytest.fixture(scope="module")
def agreement():
    invalid = "0,0,-0.8,0,0,-0.8,,\n0,0,-0.8,0.3,0,-0.8,0.002,\n0,0,-0.8,0.1,0,-0.8,,-1\n"  # from = to, λ = 150, T < 0
    return planned_both_ways(random_batch(240, seed=7) + invalid, OPTS)


def test_engine_lines_equal_plan_lines_on_240_random_rows(agreement):
    rows, ref, got = agreement
    assert [r.row for r in got] == [r.row for r in ref] == [r.row for r in rows]
    # the mix the test needs: decided rows, limit violations, unreachable and invalid rows
    codes = [r.code for r in ref]
    # (rows outside the λ table were invalid, exit 1; they are solved on demand since issue 16)
    assert codes.count(3) >= 10 and codes.count(4) >= 10 and codes.count(1) >= 2
    decided = [g for g in got if isinstance(g.plan, Verdict)]
    assert len(decided) >= 100
    # identical lines: every key and value (floats bitwise: json.dumps writes the shortest round-trip repr)
    for a, b in zip(ref, got):
        assert line(a) == line(b), a.row
        assert a.code == b.code and (a.plan is None) == (b.plan is None)


def test_every_decided_row_is_ok_in_plan_and_clear_of_the_margin(agreement):
    _, ref, got = agreement
    for a, b in zip(ref, got):
        if isinstance(b.plan, Verdict):
            assert a.code == 0 and a.plan.report.ok
            # plan()'s own utilisation of every limit stays below the screening margin (+ its estimate error)
            # (the Cartesian capacity's rows: auto puts them at 100 %, and the engine checks them exactly)
            assert max(r.utilisation for r in a.plan.report.rows
                       if not r.quantity.startswith("capacity")) <= SCREEN_MARGIN + 0.01


def test_screening_estimates_match_plan_peaks():
    """The screening estimate (parabolic vertex on 129 uniform samples ∪ knots ∪ 7 points inside every piece)
    vs plan()'s peaks (~1,200 samples, refined exactly near a limit), for every upper-bounded quantity at
    30 %–200 % of its limit: never more than 1 % low (measured worst 0.2 % on 600 random moves; the short end
    pieces hold the sharpest torque-rate peaks). The 10 % screening margin is 10× that."""
    rows, _ = read_batch_text(random_batch(150, seed=3), "rand")
    tasks, Ts, refs = [], [], []
    for r in rows:
        v = r.values
        task = Task([v["from_x"], v["from_y"], v["from_z"]], [v["to_x"], v["to_y"], v["to_z"]],
                    v.get("height", 0.025), 0.5)
        try:
            p = plan(task, DELTA, PlanOptions(fit=False, time=v.get("time", "auto")))
        except PickplaceError:
            continue
        tasks.append(task)
        Ts.append(p.duration.seconds)
        refs.append(p)
    k = np.array([[p.parameters["k1"], p.parameters["k2"]] for p in refs])
    via = np.stack([t.via_points() - t.p_from for t in tasks])
    breaks, coef, _ = batch_paths(k[:, 0], k[:, 1], via)
    model = motion_model(plan_path(tasks[0]), DELTA)
    scr = screen_block(model, breaks, coef, np.stack([t.p_from for t in tasks]), np.array(Ts), DELTA.planning.dwell)
    ratios = []
    for i, p in enumerate(refs):
        if not np.all(np.isfinite(scr.peak[i])):
            continue  # unreachable on the screening grid: such a move is never decided by the engine
        by_name = {(r.joint, r.quantity): r for r in p.report.rows}
        for c, meta in enumerate(scr.meta):
            row = by_name.get(meta[:2])  # (the two sides of a range are one report row: skipped)
            if row is not None and row.bound == "upper" and 0.3 < row.utilisation < 2.0:
                ratios.append(scr.peak[i, c] / row.peak)
        for j, name in enumerate(model.robot.joint_names):  # RMS motor torque (trapezoid on either grid)
            ratios.append(scr.rms[i, j] / by_name[(name, "rms motor torque")].peak)
    assert len(ratios) > 300
    assert min(ratios) > 0.99, min(ratios)
    assert max(ratios) < 1.01, max(ratios)


def test_peaks_are_bitwise_plan_bspline_peaks():
    rng = np.random.default_rng(11)
    tasks = []
    for _ in range(150):
        r, a = rng.uniform(0.03, 0.3), rng.uniform(0, 2 * np.pi)
        z0, z1 = rng.uniform(-0.9, -0.7, 2)
        if rng.random() < 0.5:  # end points at one height: the closed-form symmetric path of batch_paths
            z1 = z0
        tasks.append(Task([-r * np.cos(a), -r * np.sin(a), z0], [r * np.cos(a), r * np.sin(a), z1],
                          rng.uniform(0.01, 0.06), rng.uniform(0.2, 0.8)))
    k1, k2 = rng.uniform(0.05, 0.95, 150), rng.uniform(0.05, 0.95, 150)
    via = np.stack([t.via_points() - t.p_from for t in tasks])
    breaks, coef, peaks = batch_paths(k1, k2, via)
    ref = np.array([plan_path(t, "bspline", k1=a, k2=b).peaks for t, a, b in zip(tasks, k1, k2)])
    assert np.array_equal(peaks, ref)  # bitwise: the JSON lines must not change with the engine
    # and the piece polynomials evaluate the path (1e-12 m: Horner round-off on ~0.1 m coordinates)
    from pickplace_cli.pipelines.verdicts import batch_motion

    tau = np.tile(np.linspace(0, 1, 33), (len(tasks), 1))
    mot = batch_motion(breaks, coef, tau)
    for i in (0, 77, 149):
        path = plan_path(tasks[i], "bspline", k1=k1[i], k2=k2[i])
        for order in range(4):
            ref_m = path(tau[i], order) - (tasks[i].p_from if order == 0 else 0)
            np.testing.assert_allclose(mot[order][i], ref_m, rtol=1e-10, atol=1e-12 * max(1.0, np.abs(ref_m).max()))


def _near_limit_time() -> float:
    """A given duration at which the Adept move's worst utilisation lies between the margin and 1."""
    task = Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5)
    lo, hi = 0.05, 0.18  # 0.05 s violates, 0.18 s (auto) is well inside
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        u = max(r.utilisation for r in plan(task, DELTA, PlanOptions(fit=False, time=mid)).report.rows
                if not r.quantity.startswith("capacity"))
        if u > 0.95:
            lo = mid
        else:
            hi = mid
        if SCREEN_MARGIN + 0.02 < u < 0.99:
            return mid
    raise AssertionError("no near-limit duration found")


def test_near_limit_unreachable_and_invalid_rows_are_planned_by_plan():
    t_near = _near_limit_time()
    text = (HEADER + "\n"
            "-0.1525,0,-0.8,0.1525,0,-0.8,,\n"              # 1: the Adept cycle, clearly ok
            f"-0.1525,0,-0.8,0.1525,0,-0.8,,{t_near!r}\n"  # 2: near a motor limit and past the capacity: plan()
            "0,0,-0.8,0.1,0,-0.3,,\n"                     # 3: unreachable (z = −0.3 m is above the arms' reach)
            "0,0,-0.8,0.1,0,-0.8,,0.01\n"                 # 4: far over the limits
            "0,0,-0.8,0,0,-0.8,,\n"                       # 5: from = to (invalid)
            "0,0,-0.8,0.1,0,-0.8,,fit\n")                 # 6: time = fit: plan()
    rows, _ = read_batch_text(text, "mix")
    ref = list(plan_rows(rows, DELTA, OPTS, source="mix"))
    got = list(verdict_rows(rows, DELTA, OPTS, source="mix"))
    assert [r.code for r in ref] == [r.code for r in got] == [0, 3, 4, 3, 1, 0]
    assert [line(a) for a in ref] == [line(b) for b in got]
    assert set(decide(rows, DELTA, OPTS)) == {1}
    assert isinstance(got[0].plan, Verdict) and not isinstance(got[1].plan, Verdict)
    assert "unreachable" in got[2].error and "limit exceeded" in got[3].error


def test_fail_fast_stops_where_plan_rows_stops():
    text = HEADER + "\n-0.1525,0,-0.8,0.1525,0,-0.8,,\n0,0,-0.8,0.1,0,-0.8,,0.01\n0.1,0,-0.8,-0.1,0,-0.8,,\n"
    rows, _ = read_batch_text(text)
    ref = list(plan_rows(rows, DELTA, OPTS, fail_fast=True))
    got = list(verdict_rows(rows, DELTA, OPTS, fail_fast=True))
    assert [line(a) for a in ref] == [line(b) for b in got] and len(got) == 2


def test_parallel_equals_serial():
    rows, _ = read_batch_text(random_batch(120, seed=5))
    serial = [line(r) for r in verdict_rows(rows, DELTA, OPTS)]
    parallel = [line(r) for r in verdict_rows_parallel(rows, DELTA, OPTS, workers=2, chunk=40)]
    assert serial == parallel


def test_given_k_and_table_parameters_agree_with_plan():
    rows, _ = read_batch_text(random_batch(40, seed=9))
    for params in ({"k1": 0.4, "k2": 0.13, "table": None}, {"k1": None, "k2": None, "table": None}):
        opts = PlanOptions(fit=False, time="auto", method_params=params)
        ref = [line(r) for r in plan_rows(rows, DELTA, opts)]
        assert [line(r) for r in verdict_rows(rows, DELTA, opts)] == ref


def test_engine_scope(monkeypatch):
    assert engine_applies(DELTA, OPTS)
    assert not engine_applies(DELTA, PlanOptions(fit=True, time="auto"))  # --show-fit: fit_s needs the fit
    assert engine_applies(DELTA, PlanOptions(fit=False))  # the default rule: the rows where the capacity binds
    assert not engine_applies(DELTA, PlanOptions(fit=False, time="fit"))
    assert not engine_applies(DELTA, PlanOptions(fit=False, method="ph"))
    assert not engine_applies(DELTA, PlanOptions(fit=False, method_params={"k1": 0.4}))
    assert not engine_applies(load_profile("gantry"), OPTS)  # no reach guard (singularity measure)
    assert engine_applies(scara(), OPTS)
    monkeypatch.setenv(OFF_SWITCH, "1")
    assert not engine_applies(DELTA, OPTS)


def test_scara_rows_agree_with_plan():
    rng = np.random.default_rng(4)
    lines = [HEADER]
    for _ in range(60):
        r0, r1 = rng.uniform(0.2, 0.58, 2)
        a0, a1 = rng.uniform(-1.2, 1.2, 2)  # in front of the robot (some moves still reach a limit)
        t = rng.choice(["", f"{rng.uniform(0.1, 0.5):.3f}"])
        lines.append(f"{r0 * np.cos(a0):.4f},{r0 * np.sin(a0):.4f},-0.15,{r1 * np.cos(a1):.4f},{r1 * np.sin(a1):.4f},-0.15,,{t}")
    rows, _ = read_batch_text("\n".join(lines) + "\n")
    ref = [line(r) for r in plan_rows(rows, scara(), OPTS)]
    got = list(verdict_rows(rows, scara(), OPTS))
    assert [line(r) for r in got] == ref
    assert any(isinstance(g.plan, Verdict) for g in got)


_coord = st.floats(-0.35, 0.35, allow_nan=False).map(lambda x: round(x, 4))
_z = st.floats(-1.0, -0.5, allow_nan=False).map(lambda x: round(x, 4))
_row = st.tuples(_coord, _coord, _z, _coord, _coord, _z,
                 st.one_of(st.just(""), st.floats(0.005, 0.1).map(lambda x: f"{x:.4f}")),
                 st.one_of(st.just(""), st.floats(0.03, 0.4).map(lambda x: f"{x:.3f}")))


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(_row, min_size=1, max_size=4), st.one_of(st.none(), st.tuples(st.floats(0.05, 0.95), st.floats(0.05, 0.95))))
def test_property_engine_never_changes_a_line(moves, k):
    """Any rows over and beyond the Delta's workspace (reachable or not, within limits or not), table or given
    k1, k2: the engine's lines are plan()'s lines."""
    text = HEADER + "\n" + "\n".join(",".join(str(c) for c in m) for m in moves) + "\n"
    rows, _ = read_batch_text(text)
    opts = PlanOptions(fit=False, time="auto", method_params={} if k is None else {"k1": k[0], "k2": k[1]})
    assert [line(r) for r in verdict_rows(rows, DELTA, opts)] == [line(r) for r in plan_rows(rows, DELTA, opts)]


# ------------------------------------------------------------------ the default rule (time = limits)

DEFAULT = PlanOptions(fit=False)  # the default rule: the shortest duration at which every limit holds


def rules_batch(n: int, seed: int) -> str:
    """random_batch's moves with every kind of time cell: empty (the default rule), limits in any case, auto, seconds."""
    rng = np.random.default_rng(seed)
    out = []
    for i, row in enumerate(random_batch(n, seed).splitlines()):
        if i == 0 or not row.endswith(","):
            out.append(row)
            continue
        out.append(row + rng.choice(["", "", "", "limits", "LIMITS ", "auto"]))
    return "\n".join(out) + "\n"


@pytest.fixture(scope="module")
def default_agreement():
    # from = to, λ = 150 (solved on demand), T < 0, time = fit (plan())
    invalid = "0,0,-0.8,0,0,-0.8,,\n0,0,-0.8,0.3,0,-0.8,0.002,\n0,0,-0.8,0.1,0,-0.8,,-1\n0,0,-0.8,0.1,0,-0.8,,fit\n"
    return planned_both_ways(rules_batch(240, seed=17) + invalid, DEFAULT)


def test_default_rule_lines_equal_plan_lines_on_240_random_rows(default_agreement):
    rows, ref, got = default_agreement
    assert [r.row for r in got] == [r.row for r in ref] == [r.row for r in rows]
    for a, b in zip(ref, got):  # every key and value, fit_s included (floats bitwise: shortest round-trip repr)
        assert line(a) == line(b), a.row
    codes = [r.code for r in ref]
    assert codes.count(3) >= 10 and codes.count(4) >= 10 and codes.count(1) >= 2
    by_mode = {}
    for b in got:
        if isinstance(b.plan, Verdict):
            by_mode[b.plan.summary()["mode"]] = by_mode.get(b.plan.summary()["mode"], 0) + 1
    assert by_mode.get("limits", 0) >= 60 and by_mode.get("auto", 0) >= 10 and by_mode.get("given", 0) >= 5


def test_default_rule_decided_rows_are_capacity_bound_and_clear_of_the_margin(default_agreement):
    _, ref, got = default_agreement
    for a, b in zip(ref, got):
        if isinstance(b.plan, Verdict) and b.plan.summary()["mode"] == "limits":
            s = a.plan.summary()
            assert a.code == 0 and s["binding"].startswith("capacity") and s["duration_s"] == s["auto_s"]
            # plan()'s own rule for "the capacity binds" (fit_s = the screened fit · (1 + 1e-7): inside it too)
            assert s["fit_s"] is not None and s["fit_s"] * (1 + 1e-6) < s["auto_s"]
            # plan()'s utilisation of every limit stays under the screening margin + 1 %: the engine estimates on
            # plan()'s own samples, and plan()'s zoom and refinement move a peak by well under 1 %
            assert max(r.utilisation for r in a.plan.report.rows
                       if not r.quantity.startswith("capacity")) <= SCREEN_MARGIN + 0.01


def test_default_rule_rows_where_the_motors_bind_go_to_plan():
    """On the SCARA the joints and motors set the duration of many moves (plan() confirms that fit by its exact
    check): none of those is decided by the engine, and every line is plan()'s."""
    rng = np.random.default_rng(8)
    lines = [HEADER]
    for _ in range(60):
        r0, r1 = rng.uniform(0.2, 0.58, 2)
        a0, a1 = rng.uniform(-1.2, 1.2, 2)
        lines.append(f"{r0 * np.cos(a0):.4f},{r0 * np.sin(a0):.4f},-0.15,{r1 * np.cos(a1):.4f},{r1 * np.sin(a1):.4f},"
                     f"{rng.uniform(-0.19, -0.01):.4f},,")
    rows, _ = read_batch_text("\n".join(lines) + "\n")
    ref = list(plan_rows(rows, scara(), DEFAULT))
    got = list(verdict_rows(rows, scara(), DEFAULT))
    assert [line(r) for r in got] == [line(r) for r in ref]
    motors = [a.row for a in ref if a.plan is not None and not a.plan.summary()["binding"].startswith("capacity")]
    decided = [b.row for b in got if isinstance(b.plan, Verdict)]
    assert motors and decided and not set(motors) & set(decided)


def test_default_rule_on_the_four_axis_delta():
    prof = load_profile("delta-4axis")
    rows, _ = read_batch_text(random_batch(60, seed=21))
    ref = [line(r) for r in plan_rows(rows, prof, DEFAULT)]
    got = list(verdict_rows(rows, prof, DEFAULT))
    assert [line(r) for r in got] == ref
    assert sum(isinstance(g.plan, Verdict) for g in got) >= 15


def test_a_row_s_limit_use_scales_the_limits_the_engine_checks():
    """A row's limit_use column plans that row at that fraction of every rating: the engine checks the same scaled
    limits (it once checked the full ratings, and answered exit 0 for row 1, which exceeds its RMS limits at 5 %)."""
    text = ("from_x,from_y,from_z,to_x,to_y,to_z,time,limit_use\n"
            "-0.1525,0,-0.8,0.1525,0,-0.8,3.5,0.05\n"   # 1: RMS motor torque over 5 % of its rating: exit 3
            "-0.1525,0,-0.8,0.1525,0,-0.8,,0.8\n"      # 2: the default rule at 80 %: decided, T = auto at 80 %
            "-0.1525,0,-0.8,0.1525,0,-0.8,auto,0.5\n"  # 3: auto at 50 %
            "-0.1525,0,-0.8,0.1525,0,-0.8,,\n"         # 4: the profile's own use
            "0.1,0.1,-0.8,-0.1,-0.1,-0.8,,0.9\n")
    rows, _ = read_batch_text(text)
    for opts in (PlanOptions(fit=False, limit_use=0.7), DEFAULT):
        ref = list(plan_rows(rows, DELTA, opts))
        got = list(verdict_rows(rows, DELTA, opts))
        assert [line(r) for r in got] == [line(r) for r in ref]
        assert ref[0].code == 3 and not isinstance(got[0].plan, Verdict)
        assert all(isinstance(g.plan, Verdict) for g in got[1:])
    # the capacity binds (acceleration): T = √(â / (use·[a])), so 80 % of the capacity takes 1/√0.8 of the full
    # rating's time (rtol 1e-14: two roundings of the same closed form)
    at_80, at_full = (got[i].plan.summary() for i in (1, 3))
    assert at_80["binding"] == at_full["binding"] == "capacity acceleration"
    assert at_80["duration_s"] == pytest.approx(at_full["duration_s"] / np.sqrt(0.8), rel=1e-14)


def test_default_rule_parallel_equals_serial():
    rows, _ = read_batch_text(rules_batch(120, seed=5))
    serial = [line(r) for r in verdict_rows(rows, DELTA, DEFAULT)]
    parallel = [line(r) for r in verdict_rows_parallel(rows, DELTA, DEFAULT, workers=2, chunk=40)]
    assert serial == parallel


def test_default_rule_with_given_k_agrees_with_plan():
    rows, _ = read_batch_text(rules_batch(40, seed=9))
    # (k2 = 0.999: a middle piece shorter than the closed forms take: the de Boor route)
    for params in ({"k1": 0.4, "k2": 0.13, "table": None}, {"k1": 0.3, "k2": 0.999, "table": None}):
        opts = PlanOptions(fit=False, method_params=params)
        got = list(verdict_rows(rows, DELTA, opts))
        assert [line(r) for r in got] == [line(r) for r in plan_rows(rows, DELTA, opts)]
        assert any(isinstance(g.plan, Verdict) for g in got)


@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(_row, min_size=1, max_size=4), st.sampled_from(["", "limits", "auto"]))
def test_property_default_rule_never_changes_a_line(moves, rule):
    """Any rows over and beyond the Delta's workspace under the default rule (and rows of other rules): the engine's
    lines are plan()'s lines."""
    text = HEADER + "\n" + "\n".join(",".join(str(c) for c in m[:-1]) + "," + (m[-1] or rule) for m in moves) + "\n"
    rows, _ = read_batch_text(text)
    assert [line(r) for r in verdict_rows(rows, DELTA, DEFAULT)] == [line(r) for r in plan_rows(rows, DELTA, DEFAULT)]
