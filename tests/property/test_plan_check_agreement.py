"""What ``plan`` writes as within its limits, ``check`` accepts; a copy of that file run 1 % or 3 % faster (every time
stamp divided by 1.01 or 1.03) is never accepted as within the limits: ``check`` shows a limit exceeded, or says
that the samples do not resolve a peak (``--strict`` then fails it too).

Random moves (seeded) on the three shipped profiles, every method, the rules that plan to a limit (fit, optimal and
the default, limits) and two sample rates (1 kHz and 5 kHz). Files as plan writes them (its default CSV, with the
tool's motion beside the joints) and with the joint positions only (another tool's file: the check then
reconstructs the motion from the positions alone). Bounded: one random move per combination."""

from __future__ import annotations

import io

import numpy as np
import pytest

from pickplace_cli.export.csv import write_csv
from pickplace_cli.model.errors import PickplaceError
from pickplace_cli.model.profile import load_profile
from pickplace_cli.model.task import Task
from pickplace_cli.pipelines.check import check_file
from pickplace_cli.planner import PlanOptions, plan

MOVES = {
    "delta-su2018": ((-0.2, 0.2), (-0.2, 0.2), (-0.95, -0.8)),
    "scara-600": ((0.25, 0.45), (-0.25, 0.25), (-0.18, -0.05)),
    "gantry": ((-0.5, 0.5), (-0.5, 0.5), (-0.6, -0.3)),
}
METHODS = ("bspline", "ph", "superposition", "lame", "piecewise-poly", "bspline-vel")


def _cases():
    out = []
    for prof in MOVES:
        for method in METHODS:
            for rule in ("fit", "optimal", "limits"):
                if prof == "gantry" and rule != "limits":  # no joint or motor limit depends on the duration there
                    continue
                if method == "bspline-vel" and rule == "optimal":  # refused: its path is planned for a duration
                    continue
                rate = 5000.0 if (len(out) % 2) else 1000.0
                out.append(pytest.param(prof, method, rule, rate, id=f"{prof}-{method}-{rule}-{rate:.0f}Hz"))
    return out


def _text(pl, speed: float = 1.0, positions_only: bool = False) -> str:
    buf = io.StringIO()
    write_csv(pl, buf)
    lines = buf.getvalue().splitlines()
    head = lines[0].split(",")
    keep = [i for i, h in enumerate(head) if h.split("[")[0] == "t" or (h[0] == "q" and h.split("[")[0][1:].isdigit())]
    if not positions_only:
        keep = list(range(len(head)))
    out = [",".join(head[i] for i in keep)]
    for ln in lines[1:]:
        cells = ln.split(",")
        cells[0] = repr(float(cells[0]) / speed)
        if speed != 1.0 and not positions_only:  # the tool's derivative columns scale with the speed
            for i, h in enumerate(head):
                k = {"v": 1, "a": 2, "j": 3}.get(h[:1]) if len(h) > 1 and h[1] in "xyz" and h[2] == "[" else None
                if k:
                    cells[i] = repr(float(cells[i]) * speed**k)
        out.append(",".join(cells[i] for i in keep))
    return "\n".join(out) + "\n"


def _check(tmp_path, text: str, prof, rule: str = "limits"):
    """check's report of ``text`` under plan's ``rule``: fit and optimal leave the Cartesian capacity out, and check
    does so too (``--no-hold-capacity``)."""
    f = tmp_path / "t.csv"
    f.write_text(text)
    return check_file(str(f), prof, hold_capacity=rule not in ("fit", "optimal"))[0].report


def _planned(prof_name, method, rule, rate, **options):
    """(profile, the plan of the combination's random move, whether a timed row is at its limit); ``options``: more
    PlanOptions fields."""
    prof = load_profile(prof_name)
    rng = np.random.default_rng(sum(map(ord, prof_name + method + rule)))
    ranges = MOVES[prof_name]
    a = np.array([rng.uniform(*r) for r in ranges])
    b = np.array([rng.uniform(*r) for r in ranges])
    try:
        pl = plan(Task(a, b, prof.planning.height, prof.planning.eta), prof, PlanOptions(method=method, time=rule,
                                                                                       rate=rate, **options))
    except PickplaceError as exc:  # a move this method cannot plan (too flat, out of reach): not this test's subject
        pytest.skip(f"not planned: {exc}")
    if not pl.report.ok:
        pytest.skip("a position limit (exit 4): not written by plan")
    timed = [r for r in pl.report.rows if r.kind == "limit" and not r.quantity.startswith("capacity")]
    return prof, pl, bool(timed) and max(r.utilisation for r in timed) > 0.999


@pytest.mark.slow
@pytest.mark.parametrize("prof_name,method,rule,rate", _cases())
def test_plan_writes_what_check_accepts_and_faster_fails(tmp_path, prof_name, method, rule, rate):
    """The file as plan writes it (its default CSV: the joints and the tool's motion x … jz): check decides every
    row (none unresolved) and accepts it; 1 % and 3 % faster copies show a limit exceeded."""
    prof, pl, at_limit = _planned(prof_name, method, rule, rate)
    rep = _check(tmp_path, _text(pl), prof, rule)
    assert rep.ok, [(r.joint, r.quantity, r.peak, r.accuracy, r.limit) for r in rep.violations]
    assert not rep.unresolved, [(r.joint, r.quantity, r.peak, r.accuracy) for r in rep.unresolved]
    if at_limit:  # (where the capacity binds, running faster need not break a joint or motor limit)
        for speed in (1.01, 1.03):
            assert not _check(tmp_path, _text(pl, speed), prof, rule).ok, f"{speed}× faster shows no limit exceeded"


#: positions alone, 1 kHz (measured against the plan's own model on 400,001 points, ``curves/sampled.py``'s reconstruction):
#: * a time-optimal law over a method whose jerk steps: the law's knots are steps of the snap (b‴ steps there, so the
#:   jerk has a kink) and the method's jerk steps, often within a sample interval of each other (lame, Delta: 114.9 %
#:   read at 59.29 ms, a jerk step 1.16 ms and a law knot 0.84 ms away, true 99.99 %; superposition, SCARA: 109.5 %,
#:   a jerk step on a law knot 0.88 ms away, true 99.98 %): the step finder needs six smooth samples each side, so
#:   neither is found and the quintic spline rings;
#: * piecewise-poly optimal (SCARA): 110.6 % at t = 0, where the law starts with a jerk step the end condition of
#:   the spline (not-a-knot) cannot represent;
#: * the rigid Delta's bspline fit move: 100.13 % read where the plan rides the limit at 100.000 %: no step, the
#:   quintic spline's own error in the third derivative at 1 kHz (~0.1 %) on a plan exactly at its limit.
#: * superposition optimal on the Delta at 5 kHz (the SQP's 60-coefficient quintic law): 104.7 % read at a jerk step of
#:   the method (t = 38.4 ms, found: split there) with law knots on both sides within a few samples; a larger
#:   smoothing term on the law (SQP_SMOOTH 1e-2) still reads 102.9 %.
#: * bspline optimal on the SCARA at 1 kHz: q2's torque rate read 101.2 % ± 1.8 % (not resolved; a reading beyond
#:   its limit by more than 1 % of it is exceeded whatever its accuracy).
#: Such a file may be refused although plan wrote it for its tool columns (never accepted when it breaks a limit):
#: write the tool columns (plan's default CSV) or sample faster; a plan for positions alone
#: (``--columns t,q1,…``: ``read_written="positions"``) reads them as check will and is accepted
#: (test_positions_only_file_planned_as_written). Reading these lower is not safe without a bound on the
#: reconstruction's error between samples, which positions alone do not give.
KNOWN_HIGH = {("superposition", "optimal", 1000.0), ("superposition", "optimal", 5000.0), ("lame", "optimal", 1000.0),
              ("piecewise-poly", "optimal", 1000.0),
              ("ph", "optimal", 1000.0), ("bspline", "fit", 1000.0), ("bspline", "optimal", 1000.0)}
#: plan's own file (tool columns) is not listed: a time-optimal law is slowed until check reads its written samples
#: within every limit (``timing/written.py``; the lame optimal move at 1 kHz here read q2's torque rate 100.11 %, a law
#: knot 0.23 ms from a sample inside a 1 ms interval, before plan read its own samples)


@pytest.mark.slow
@pytest.mark.parametrize("prof_name,method,rule,rate", _cases())
def test_positions_only_file(tmp_path, prof_name, method, rule, rate):
    """The joints' positions alone (another tool's file, or `plan --columns t,q1,...`): check reconstructs the motion
    from them; it accepts the plan's file, and a faster copy is never accepted as within every limit (exceeded, or a
    peak the samples do not resolve)."""
    prof, pl, at_limit = _planned(prof_name, method, rule, rate)
    rep = _check(tmp_path, _text(pl, positions_only=True), prof, rule)
    if not rep.ok and (method, rule, rate) in KNOWN_HIGH:
        pytest.xfail("positions alone at 1 kHz (superposition optimal: 5 kHz too): jerk steps next to a time law's knots "
                     "are not found, or a "
                     "plan at 100.000 % of its limit reads 0.1 % high: a torque-rate peak reads high (KNOWN_HIGH)")
    assert rep.ok, [(r.joint, r.quantity, r.peak, r.accuracy, r.limit) for r in rep.violations]
    if at_limit:
        for speed in (1.01, 1.03):
            fast = _check(tmp_path, _text(pl, speed, positions_only=True), prof, rule)
            assert not fast.ok or fast.unresolved, f"{speed}× faster accepted as within every limit"


#: the shape search with the time-optimal law (``--optimize shape --time optimal``), the moves on which check read
#: plan's 1 kHz files 0.4 % to 3.5 % past the torque-rate limit before plan read its own samples
#: (``timing/written.py``): the Adept cycle both ways (the way back is a round trip's second move), a diagonal move,
#: the 4-axis Delta turning 90°, a SCARA move; with and without the capacity held
SHAPE_MOVES = [
    ("delta-su2018", (-0.1525, 0.0, -0.8), (0.1525, 0.0, -0.8)),
    ("delta-su2018", (0.1525, 0.0, -0.8), (-0.1525, 0.0, -0.8)),
    ("delta-su2018", (0.1, 0.1, -0.8), (-0.1, -0.1, -0.8)),
    ("delta-4axis", (-0.1525, 0.0, -0.8, 0.0), (0.1525, 0.0, -0.8, 1.5708)),
    ("scara-600", (0.3, -0.15, -0.1), (0.4, 0.15, -0.1)),
]


@pytest.mark.slow
@pytest.mark.parametrize("hold", [False, True], ids=["motors", "capacity"])
@pytest.mark.parametrize("prof_name,a,b", SHAPE_MOVES, ids=[f"{m[0]}-{i}" for i, m in enumerate(SHAPE_MOVES)])
def test_shape_optimal_file_is_accepted(tmp_path, prof_name, a, b, hold):
    """``--optimize shape --time optimal`` (with ``--hold-capacity`` or not) at 1 kHz: check accepts plan's file and
    resolves every row; a copy 3 % faster is never accepted (the law rides a motor limit)."""
    prof = load_profile(prof_name)
    angles = {"theta_from": a[3], "theta_to": b[3]} if len(a) == 4 else {}
    task = Task(a[:3], b[:3], prof.planning.height, prof.planning.eta, **angles)
    pl = plan(task, prof, PlanOptions(time="optimal", shape=True, hold_capacity=hold, rate=1000.0))
    assert pl.report.ok
    rule = "limits" if hold else "optimal"  # check holds the capacity as plan did
    rep = _check(tmp_path, _text(pl), prof, rule)
    assert rep.ok, [(r.joint, r.quantity, r.peak, r.accuracy, r.limit) for r in rep.violations]
    assert not rep.unresolved, [(r.joint, r.quantity, r.peak, r.accuracy) for r in rep.unresolved]
    fast = _check(tmp_path, _text(pl, 1.03), prof, rule)
    assert not fast.ok or fast.unresolved, "3 % faster accepted as within every limit"


@pytest.mark.slow
@pytest.mark.parametrize("prof_name,method,rule,rate", [c for c in _cases() if c.values[2] == "optimal"
                                                        and c.values[3] == 1000.0])
def test_positions_only_file_planned_as_written(tmp_path, prof_name, method, rule, rate):
    """``plan --time optimal --columns t,q1,…`` (``PlanOptions.read_written = "positions"``): the plan reads its joint
    positions alone as check will and slows the law until they pass, so check accepts the positions-only file it
    writes, KNOWN_HIGH's moves included (refused when planned for the tool columns)."""
    prof, pl, _ = _planned(prof_name, method, rule, rate, read_written="positions")
    rep = _check(tmp_path, _text(pl, positions_only=True), prof, rule)
    assert rep.ok, [(r.joint, r.quantity, r.peak, r.accuracy, r.limit) for r in rep.violations]


@pytest.mark.slow
@pytest.mark.parametrize("prof_name,method,rule,rate", _cases())
@pytest.mark.parametrize("columns", ["tool", "positions"])
def test_strict_plan_is_what_check_strict_accepts(tmp_path, prof_name, method, rule, rate, columns):
    """``plan --strict`` (``PlanOptions.strict``), the file with the tool columns or the joint positions alone: check
    accepts it and resolves every peak (``check --strict`` exit 0) — the positions-only files of KNOWN_HIGH and the
    1 kHz optimal files whose peaks were not resolved included (measured: slowed × 1.0019 at most with the tool
    columns, × 1.054 at most with positions alone)."""
    prof, pl, _ = _planned(prof_name, method, rule, rate, strict=True, read_written=columns)
    assert pl.report.exit_code() == 0
    rep = _check(tmp_path, _text(pl, positions_only=columns == "positions"), prof, rule)
    assert rep.ok, [(r.joint, r.quantity, r.peak, r.accuracy, r.limit) for r in rep.violations]
    assert not rep.unresolved, [(r.joint, r.quantity, r.peak, r.accuracy) for r in rep.unresolved]
