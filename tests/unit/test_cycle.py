"""The controller's cycle (``plan --cycle``, profile ``controller.cycle``): durations and dwells rounded up to whole
cycles, the limit check run again on the rounded move, every written step exactly one cycle.

References: the rounding is recomputed here with ``decimal`` (exact decimal arithmetic on the printed numbers), the
unrounded duration comes from a plan without a cycle, and the re-run check is compared with a plan at the rounded
duration given explicitly (``--time``), which reaches the limit check by the ordinary path.
"""

from __future__ import annotations

import csv
import io
import json
import math
from decimal import Decimal

import numpy as np
import pytest
from typer.testing import CliRunner

from pickplace_cli.cli import app
from pickplace_cli.model.errors import TaskError
from pickplace_cli.model.profile import load_profile
from pickplace_cli.model.task import Task
from pickplace_cli.planner import PlanOptions, plan
from pickplace_cli.timing.cycle import CycleRounding, align_to_cycle, check_cycle, whole_cycles

runner = CliRunner()
ADEPT = ("--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8")
THERE = Task([-0.1525, 0.0, -0.8], [0.1525, 0.0, -0.8], 0.025, 0.5)


def run(*args, input=None):
    return runner.invoke(app, list(args), input=input, catch_exceptions=False)


def test_whole_cycles_by_hand():
    assert whole_cycles(0.18, 0.001) == 180  # exactly 180 cycles: not 181
    assert whole_cycles(0.179956, 0.001) == 180
    assert whole_cycles(0.1 + 0.2, 0.1) == 3  # 0.30000000000000004: a crumb, not a fourth cycle
    assert whole_cycles(0.3001, 0.1) == 4
    assert whole_cycles(0.0, 0.004) == 0 and whole_cycles(1e-9, 0.004) == 1


def test_check_cycle_refuses_what_is_not_a_cycle():
    assert check_cycle("0.001") == 0.001
    for bad in (0, -0.001, float("nan"), float("inf"), 2.0, 1e-7, "abc"):
        with pytest.raises(TaskError, match="cycle"):
            check_cycle(bad)


class _Report:
    def __init__(self, ok: bool) -> None:
        self.ok = ok
        self.violations = () if ok else (type("Row", (), {"joint": "q1", "quantity": "rms motor torque"})(),)


def test_a_rounded_duration_that_breaks_a_limit_gets_more_cycles():
    """A limit that held at T but breaks at ⌈T⌉ (RMS with gravity can rise as the move slows): the next cycles are
    tried until it holds; when none does, the rounded report (which says what is exceeded) is kept, with a note."""
    calls = []

    def check(T, dwell):
        calls.append(round(T / 0.001))
        return T, _Report(ok=round(T / 0.001) >= 183)

    rounding, samples, report = align_to_cycle(0.1805, 0.1, 0.001, check, held=True)
    assert calls == [181, 182, 183] and report.ok and rounding.cycles == 183 and rounding.extra_cycles == 2
    assert "q1 rms motor torque" in rounding.note and rounding.seconds == 183 * 0.001
    rounding, _, report = align_to_cycle(0.1805, 0.1, 0.001, lambda T, d: (T, _Report(False)), held=True)
    assert not report.ok and rounding.cycles == 181 and "does not fit" in rounding.note
    rounding, _, report = align_to_cycle(0.1805, 0.1, 0.001, lambda T, d: (T, _Report(False)), held=False)
    assert rounding.cycles == 181 and rounding.note == ""  # it did not hold before: nothing to restore


def _rows(text: str) -> tuple[list[str], list[list[str]]]:
    rows = list(csv.reader(io.StringIO(text)))
    return rows[0], rows[1:]


@pytest.mark.parametrize("cycle", ["0.0005", "0.001", "0.004"])
def test_adept_round_trip_every_step_is_one_cycle_and_the_cost_is_reported(cycle):
    c = Decimal(cycle)
    res = run("plan", *ADEPT, "--round-trip", "--cycle", cycle, "--columns", "t,drive", "-q")
    assert res.exit_code == 0, res.stderr
    head, rows = _rows(res.stdout)
    assert head[:2] == ["move[-]", "t[s]"]
    stamps = [Decimal(r[1]) for r in rows]
    assert all(s == k * c for k, s in enumerate(stamps)), "every printed stamp is k·cycle, exactly"
    # the unrounded plan, and the rounding recomputed here
    free = plan(THERE, load_profile("delta-su2018"), PlanOptions(fit=False))
    T = free.duration.seconds
    n = math.ceil(T / float(c))
    T_c, d_c = n * float(c), 0.1
    assert float(stamps[-1]) == pytest.approx(2 * (T_c + d_c), abs=1e-12)
    doc = json.loads(run("plan", *ADEPT, "--round-trip", "--cycle", cycle, "--json", "-o", "/dev/null").stdout)
    for move in doc["moves"]:
        cyc = move["cycle"]
        assert cyc["cycles"] == n and cyc["duration_s"] == pytest.approx(T_c, abs=1e-15)
        assert cyc["requested_duration_s"] == pytest.approx(T, rel=1e-12)
        assert cyc["dwell_s"] == pytest.approx(d_c, abs=1e-15)
    assert doc["cycle_rounding_cost_s"] == pytest.approx(2 * (T_c - T), abs=1e-12)
    text = run("plan", *ADEPT, "--round-trip", "--cycle", cycle, "-o", "/dev/null").stderr
    assert f"rounding adds {2 * (T_c - T) * 1e3:.4g} ms to the round trip" in text


@pytest.mark.parametrize("cycle", [0.0005, 0.001, 0.004])
def test_the_limit_check_is_run_again_on_the_rounded_duration(cycle):
    """The report of the rounded move is the report of a plan at that duration given explicitly (peaks within 1e-9
    relative: the same model; the explicit plan's sample times k/rate differ from k·cycle by an ulp)."""
    prof = load_profile("delta-su2018")
    rounded = plan(THERE, prof, PlanOptions(cycle=cycle, fit=False))
    T_c = rounded.duration.seconds
    assert rounded.report.duration == T_c and T_c == rounded.cycle.cycles * cycle
    explicit = plan(THERE, prof, PlanOptions(time=T_c, rate=1.0 / cycle, fit=False))
    assert len(rounded.report.rows) == len(explicit.report.rows)
    for a, b in zip(rounded.report.rows, explicit.report.rows):
        assert (a.joint, a.quantity, a.ok) == (b.joint, b.quantity, b.ok)
        assert a.peak == pytest.approx(b.peak, rel=1e-9, abs=1e-12)
    assert np.array_equal(rounded.t, np.arange(len(rounded.t)) * cycle)


def test_numbers_only_dialect_writes_whole_cycles():
    res = run("plan", *ADEPT, "--cycle", "0.004", "--csv-dialect", "tsv", "--columns", "t,q1", "-q")
    assert res.exit_code == 0
    ks = [line.split("\t")[0] for line in res.stdout.splitlines()]
    assert ks == [str(k) for k in range(len(ks))] and len(ks) == 46  # 0.18 s = 45 cycles of 4 ms


def test_dwell_rounded_up_to_whole_cycles(tmp_path):
    text = load_profile("delta-su2018").model_dump_json()
    doc = json.loads(text)
    doc["planning"]["dwell"] = 0.1003
    doc["controller"] = {"cycle": 0.004}
    path = tmp_path / "p.yaml"
    import yaml

    path.write_text(yaml.safe_dump(doc))
    res = run("plan", *ADEPT, "--profile", str(path), "--json", "-o", "/dev/null")
    cyc = json.loads(res.stdout)["cycle"]
    assert cyc["dwell_cycles"] == 26 and cyc["dwell_s"] == pytest.approx(0.104, abs=1e-15)  # ⌈100.3 / 4⌉ = 26
    assert json.loads(res.stdout)["cycle_time_round_trip_s"] == pytest.approx(2 * (cyc["duration_s"] + 0.104), abs=1e-12)
    off = json.loads(run("plan", *ADEPT, "--profile", str(path), "--cycle", "off", "--json").stdout)
    assert "cycle" not in off  # --cycle off: sampled at the rate, no rounding


def test_batch_rows_and_belt_rows_are_on_the_cycle():
    batch = ("from_x,from_y,from_z,to_x,to_y,to_z,to_belt_vx,to_belt_vy,to_belt_vz,latency\n"
             "-0.1525,0,-0.8,0.1525,0,-0.8,,,,\n"
             "-0.1525,0,-0.8,0.05,0.1,-0.8,0.3,0,0,0.05\n")
    res = run("plan", "--batch", "-", "--cycle", "0.001", "--columns", "t,x", "-q", input=batch)
    assert res.exit_code == 0, res.stderr
    head, rows = _rows(res.stdout)
    for move in ("1", "2"):
        stamps = [Decimal(r[1]) for r in rows if r[0] == move]
        assert all(s == k * Decimal("0.001") for k, s in enumerate(stamps)), move
    lines = [json.loads(x) for x in run("plan", "--batch", "-", "--cycle", "0.001", "--json", input=batch).stdout.splitlines()]
    belt = lines[1]
    T_c = belt["duration_s"]
    assert round(T_c / 0.001) * 0.001 == pytest.approx(T_c, abs=1e-15) and belt["cycle"]["cycles"] == round(T_c / 0.001)
    # the part is met where it is after the rounded duration: P = position + velocity · (latency + T)
    met = belt["parameters"]["rendezvous"]["meeting_point_m"]
    assert met == pytest.approx([0.05 + 0.3 * (0.05 + T_c), 0.1, -0.8], abs=1e-12)


@pytest.mark.parametrize("bad", ["0", "-0.001", "nan", "inf", "abc", "2", "1e-7"])
def test_bad_cycle_is_one_line_exit_1_nothing_written(bad, tmp_path):
    out = tmp_path / "t.csv"
    out.write_text("old\n")
    res = run("plan", *ADEPT, "--cycle", bad, "-o", str(out), "-q")
    assert res.exit_code == 1
    assert res.stderr.count("\n") == 1 and "--cycle " in res.stderr and "Traceback" not in res.stderr
    assert out.read_text() == "old\n"


def test_cycle_usage_errors():
    res = run("plan", *ADEPT, "--cycle", "0.001", "--rate", "500")
    assert res.exit_code == 2 and "--rate" in res.stderr and res.stderr.count("\n") == 1
    # (a belt schedule on a cycle: tests/cli/test_cli_belt_cycle.py)


def test_rounding_dataclass_costs():
    r = CycleRounding(0.001, 0.1799, 180, 0.1003, 101)
    assert r.seconds == 0.18 and r.cost_s == pytest.approx(1e-4) and r.dwell_cost_s == pytest.approx(0.0007)
    assert "180 cycles" in r.text()
