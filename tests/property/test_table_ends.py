"""A drive's table that ends moving (a conveyor move ends tracking at the belt's speed): before its first point and
after its last a drive holds the table's end position, so the velocity step to rest is taken within one controller
cycle. ``plan`` and ``check`` judge it so for every table format alike (``--table-end hold``, the default): the PVT
and the cam (quintic) formats got no step there before, and were written and accepted with "all limits hold" while the
same move as a cam-table was refused. ``--table-end continue`` says the controller goes on at the end's velocity
(e.g. geared to the belt): not judged past the end, and said so. The step rows at the end are held against an
independent computation: the drive's Hermite and the blend to rest derived here, the motor torque from the
independent rigid-body reference (tests/reference/delta_rigid.py)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from pickplace_cli.cli import app

runner = CliRunner()
BELT = ("--from", "-0.1525,0,-0.8", "--to", "0.1525,-0.2,-0.8", "--to-belt", "0,0.5,0", "--latency", "0.05")


def _plan(tmp_path, fmt: str, *args: str):
    out = tmp_path / f"belt-{fmt}-{len(args)}.csv"
    res = runner.invoke(app, ["plan", *BELT, "-f", fmt, "--cycle", "0.001", "-o", str(out), *args])
    return res, out


def _check(path, *args: str):
    rep = str(path) + ".json"
    res = runner.invoke(app, ["check", str(path), "--cycle", "0.001", "--report", rep, *args])
    return res, json.loads(open(rep).read())


@pytest.mark.parametrize("fmt", ["pvt", "cam", "cam-table"])
def test_a_table_that_ends_moving_is_judged_alike_in_every_format(tmp_path, fmt):
    """hold (default): refused by plan (exit 3, nothing written, the cause named: no duration removes it) and by check
    (the same step row); continue: written, a warning says what is not judged, and check accepts it with the option."""
    res, out = _plan(tmp_path, fmt)
    assert res.exit_code == 3 and not out.exists(), res.output[-1500:]
    assert "the table ends moving: the drive holds the table's last point after it" in res.output
    last = [ln for ln in res.output.splitlines() if ln.startswith("pickplace: ")][-1]
    assert last.startswith("pickplace: table not written: the drive holds the table's last point after it")
    assert "--table-end continue" in last and "--time" not in last  # no duration suggested: none removes the step
    res, out = _plan(tmp_path, fmt, "--table-end", "continue", "--report", str(tmp_path / f"{fmt}.json"))
    assert res.exit_code == 0, res.output[-1500:]
    assert "judged as the controller going on at its end velocity (--table-end continue)" in res.output
    table = json.loads((tmp_path / f"{fmt}.json").read_text())["table"]
    assert table["moving_ends"] == ["last"] and table["table_end"] == "continue"
    res, doc = _check(out, "--table-end", "continue", "-q")
    assert res.exit_code == 0, res.output[-1500:]
    assert "judged as the controller going on at the end's velocity after it (--table-end continue)" in res.output
    res, doc = _check(out, "-q")  # the same file, the drive holding its last point: the step to rest
    assert res.exit_code == 3, res.output[-1500:]
    assert "so the step to rest is judged" in res.output
    worst = max((r for r in doc["limits"]["rows"] if not r["ok"]), key=lambda r: r["utilisation"])
    assert worst["quantity"] in ("motor torque step", "motor torque") and worst["utilisation"] > 10


def test_the_step_to_rest_against_an_independent_derivation(tmp_path):
    """The PVT written with --table-end continue, checked with the drive holding its last point: after the last
    point (q_N, v_N) the drive decelerates to rest within one cycle c (a blend at −v_N/c, outside the table), so the
    motor torque steps at the blend's start (from the Hermite's end: acceleration a_N, jerk 6·a₃) and at its end (at
    q_N + v_N·c/2, to rest). Each step plus the rate on either side × c, from the independent rigid-body reference,
    or, where larger, the exact change over a window of one cycle that holds the step, is check's q2 row (the
    largest of all: 1e-6 relative) and its time."""
    from pickplace_cli.model.profile import load_profile
    from pickplace_cli.pipelines.check_read import read_checked
    from pickplace_cli.robots import build_robot
    from tests.reference import delta_rigid as ref
    from tests.unit.test_delta_rigid_reference import drives, reference_params

    c = 0.001
    res, out = _plan(tmp_path, "pvt", "--table-end", "continue")
    assert res.exit_code == 0, res.output[-1500:]
    prof = load_profile("delta-su2018")
    kind, table, _ = read_checked(out.read_text(), str(out), prof, build_robot(prof.robot))
    t, q, v = table.t - table.t[0], table.q, table.qd
    h = t[-1] - t[-2]
    dp = (q[-1] - q[-2]) / h
    a2 = (3 * dp - 2 * v[-2] - v[-1]) / h
    a3 = (-2 * dp + v[-2] + v[-1]) / h**2
    a_end, j_end = 2 * a2 + 6 * a3 * h, 6 * a3  # the last Hermite segment at the last point
    a_blend = -v[-1] / c
    N, eta, J = drives(prof)[:3]
    P = reference_params(prof)

    def motor(qq, vv, aa):
        return ref.reference_torques(P, qq[None], vv[None], aa[None])[0] / (N * eta) + J * N * aa

    def rate(qq, vv, aa, jj):
        return ref.reference_torque_rate(P, qq[None], vv[None], aa[None], jj[None])[0] / (N * eta) + J * N * jj

    zero = np.zeros(3)
    # the blend's start: the Hermite's end → the blend
    step1 = motor(q[-1], v[-1], a_blend) - motor(q[-1], v[-1], a_end)
    moved1 = np.maximum(np.abs(step1 + rate(q[-1], v[-1], a_end, j_end) * c),
                        np.abs(step1 + rate(q[-1], v[-1], a_blend, zero) * c))
    # the blend's end: at rest at q_N + v_N·c/2
    qe = q[-1] + v[-1] * c / 2
    step2 = motor(qe, zero, zero) - motor(qe, zero, a_blend)
    moved2 = np.maximum(np.abs(step2 + rate(qe, zero, a_blend, zero) * c), np.abs(step2))
    # exactly, over every window of one cycle that holds a break (the larger of the two is the row): across the blend's
    # start, from x = h − c·f into the last Hermite segment to c·(1 − f) into the blend; across its end, from
    # c·(1 − f) into the blend to the rest after it
    def hermite(x):
        return (q[-2] + v[-2] * x + a2 * x * x + a3 * x**3, v[-2] + 2 * a2 * x + 3 * a3 * x * x, 2 * a2 + 6 * a3 * x)

    def blend(s):
        return q[-1] + v[-1] * s + a_blend * s * s / 2, v[-1] + a_blend * s, a_blend + zero

    for f in np.linspace(0.0, 1.0, 21):
        moved1 = np.maximum(moved1, np.abs(motor(*blend(c * (1 - f))) - motor(*hermite(h - c * f))))
        moved2 = np.maximum(moved2, np.abs(motor(qe, zero, zero) - motor(*blend(c * (1 - f)))))
    res, doc = _check(out, "-q")
    assert res.exit_code == 3
    rows = {r["joint"]: r for r in doc["limits"]["rows"] if r["quantity"] == "motor torque step"}
    k = 1  # q2
    want, at = (moved1[k], t[-1]) if moved1[k] >= moved2[k] else (moved2[k], t[-1] + c)
    assert rows["q2"]["peak"] == pytest.approx(want, rel=1e-6)
    assert rows["q2"]["t_peak_s"] == pytest.approx(at + table.t[0], abs=1e-9)


def test_a_table_from_and_to_rest_is_unchanged_by_the_option(tmp_path):
    """A move from and to rest: --table-end continue changes nothing (no end moves): the same file, the same rows."""
    args = ("--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8", "-f", "pvt", "--cycle", "0.002", "-q")
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    ra = runner.invoke(app, ["plan", *args, "-o", str(a), "--report", str(a) + ".json"])
    rb = runner.invoke(app, ["plan", *args, "-o", str(b), "--table-end", "continue", "--report", str(b) + ".json"])
    assert ra.exit_code == rb.exit_code == 0 and a.read_text() == b.read_text()
    ja, jb = (json.loads(open(str(p) + ".json").read())["table"] for p in (a, b))
    assert ja["rows"] == jb["rows"] and ja["moving_ends"] == jb["moving_ends"] == []


def test_table_end_is_a_table_option_and_a_checked_value(tmp_path):
    res = runner.invoke(app, ["plan", *BELT, "--table-end", "continue", "-q"])
    assert res.exit_code == 2 and "--table-end applies to the table formats" in res.output
    res = runner.invoke(app, ["plan", *BELT, "-f", "pvt", "--table-end", "later", "-q", "-o", str(tmp_path / "x.csv")])
    assert res.exit_code == 1 and "--table-end" in res.output and "'later'" in res.output
    assert "one of 'hold', 'continue'" in res.output and len(res.output.splitlines()) == 1
    from pickplace_cli import check_file
    from pickplace_cli.model.errors import TaskError

    with pytest.raises(TaskError, match="table_end = 'later': must be hold or continue"):
        check_file(str(tmp_path / "x.csv"), "delta-su2018", table_end="later")


def test_a_table_that_starts_moving_names_its_start(tmp_path):
    """A move from the belt (--from-belt) starts at the belt's speed: held, the step from rest before the first point
    is judged and the table refused, the line naming the start (not a conveyor move's end, nor --round-trip); with
    --table-end continue it is written, the warning naming what comes before the table, and check agrees."""
    move = ("-m", "bspline-vel", "--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8", "--from-belt", "0,0.5,0",
            "-f", "pvt", "--cycle", "0.001", "-q")
    out = tmp_path / "fb.csv"
    res = runner.invoke(app, ["plan", *move, "-o", str(out)])
    assert res.exit_code == 3 and not out.exists()
    last = res.output.splitlines()[-1]
    assert last.startswith("pickplace: table not written: the drive holds the table's first point before it, a "
                           "velocity step from rest") and "starts at the belt's speed" in last
    assert "--round-trip" not in last and "--table-end continue" in last
    res = runner.invoke(app, ["plan", *move, "-o", str(out), "--table-end", "continue"])
    assert res.exit_code == 0 and "what it does before the table is not checked" in res.output
    res, _ = _check(out, "--table-end", "continue", "-q")
    assert res.exit_code == 0
    res, _ = _check(out, "-q")
    assert res.exit_code == 3 and "so the step from rest is judged" in res.output


def test_json_of_a_refused_table_says_a_limit_breaks(tmp_path):
    """--json of a table refused for its step to rest: limits_ok and all_limits_ok false (the table's rows are limits
    too, though the trajectory holds), exit code 3, the table's violations under table."""
    out = tmp_path / "j.csv"
    res = runner.invoke(app, ["plan", *BELT, "-f", "pvt", "--cycle", "0.001", "-o", str(out), "--json", "-q"])
    assert res.exit_code == 3 and not out.exists()
    doc = json.loads(res.stdout)
    assert doc["limits_ok"] is False and doc["all_limits_ok"] is False and doc["exit_code"] == 3
    assert doc["table"]["limits_ok"] is False and doc["table"]["violations"]
    assert doc["table"]["moving_ends"] == ["last"] and doc["table"]["table_end"] == "hold"


def test_a_cam_table_from_rest_on_a_long_cycle_is_not_called_moving(tmp_path):
    """A rest-to-rest move as a cam-table on an 8 ms cycle (few points: its first and last lines' slopes are a few %
    of the largest) is not said to start or end moving."""
    rep = tmp_path / "r.json"
    res = runner.invoke(app, ["plan", "--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8", "-f", "cam-table",
                              "--cycle", "0.008", "--table-end", "continue", "-o", str(tmp_path / "c.csv"),
                              "--report", str(rep)])
    assert res.exit_code == 0 and "moving" not in res.output
    assert json.loads(rep.read_text())["table"]["moving_ends"] == []
