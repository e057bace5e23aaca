"""``check`` judges a drive's table on the controller cycle it runs at, as ``plan`` does: a cam-table's straight lines
read once per cycle, each velocity step blended over that cycle, and a PVT or cam-table's acceleration steps (the ends
from and to rest too) taken within one cycle, each motor torque step held to the torque rate × the cycle
(``check --cycle``, else the profile's ``controller.cycle``, else what ``plan`` takes without ``--cycle``).

Before, ``check`` read a cam-table as samples of a smooth motion (the quintic spline through its points): a table
``plan`` wrote on a 4 ms cycle as within every limit read 151-380 % of the torque rate there (exit 3), and a PVT
table's steps were not bounded by any cycle. The step rows are held against an independent computation: the
blends' accelerations derived here from the table's points, and the motor torque on both sides of each blend's edge
from the independent rigid-body reference (tests/reference/delta_rigid.py, no library code)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from pickplace_cli.cli import app

runner = CliRunner()
ADEPT = ("--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8")
MOVES = {"delta-su2018": ADEPT,
         "delta-4axis": ("--from", "-0.1525,0,-0.8,0", "--to", "0.1525,0,-0.8,1.5"),
         "scara-600": ("--from", "0.3,-0.15,-0.1", "--to", "0.4,0.15,-0.1")}


def _plan(tmp_path, prof: str, *args: str) -> tuple[str, str]:
    out = tmp_path / f"{prof}-{'-'.join(a.strip('-') for a in args)}.{'st' if any(a.endswith('-st') for a in args) else 'csv'}"
    res = runner.invoke(app, ["plan", "-p", prof, *MOVES[prof], "-o", str(out), *args])
    assert res.exit_code == 0, res.output[-2000:]
    return str(out), res.output


def _check(path: str, prof: str, *extra: str) -> tuple[int, dict, str]:
    rep = path + ".json"
    res = runner.invoke(app, ["check", path, "-p", prof, "--report", rep, *extra])
    return res.exit_code, json.loads(open(rep).read()), res.output


def _profile_with_cycle(tmp_path, prof: str, cycle: float) -> str:
    """A copy of the shipped profile with ``controller.cycle`` set (the drives' names and units kept)."""
    import yaml

    from pickplace_cli.model.profile import resolve_profile_path

    doc = yaml.safe_load(open(resolve_profile_path(prof)).read())
    doc.setdefault("controller", {})["cycle"] = cycle
    path = tmp_path / f"{prof}-cycle.yaml"
    path.write_text(yaml.safe_dump(doc))
    return str(path)


@pytest.mark.parametrize("prof", list(MOVES))
@pytest.mark.parametrize("rule", ["fit", "optimal"])
@pytest.mark.parametrize("fmt", ["cam-table", "cam-table-st", "pvt"])
def test_a_table_on_a_slow_cycle_is_accepted_on_that_cycle(tmp_path, prof, rule, fmt):
    """plan's table on a 4 ms cycle, within every limit as the drive runs it, is accepted by check on the same cycle
    (--cycle, or the profile's controller.cycle); its step rows are plan's (the same peaks to 1e-9)."""
    path, said = _plan(tmp_path, prof, "-f", fmt, "--time", rule, "--cycle", "0.004", "--tolerance", "1e-4")
    assert "table verdict: all limits hold" in said
    code, doc, out = _check(path, prof, "--no-hold-capacity", "--cycle", "0.004")
    assert code == 0, out[-3000:]
    steps = {r["joint"]: r["peak"] for r in doc["limits"]["rows"] if r["quantity"] == "motor torque step"}
    planned = {ln.split()[1]: float(ln.split("step: ")[1].split()[0]) for ln in said.splitlines()
               if "motor torque step:" in ln and ln.strip().startswith("table ")}
    assert steps and set(steps) == set(planned)
    for joint, peak in planned.items():  # (plan prints 4 significant digits)
        assert steps[joint] == pytest.approx(peak, rel=6e-4), joint
    code2, _, out2 = _check(path, _profile_with_cycle(tmp_path, prof, 0.004), "--no-hold-capacity")
    assert code2 == 0, out2[-3000:]


@pytest.mark.parametrize("fmt, args", [("cam-table", ("--cycle", "0.004", "--tolerance", "1e-4")),
                                       ("pvt", ("--rate", "100", "--tolerance", "1e-3"))])
def test_a_table_on_a_slow_cycle_is_refused_on_a_faster_one(tmp_path, fmt, args):
    """A table planned on a 4 ms cycle (cam-table) or at 100 Hz (PVT: its steps bounded over 10 ms) judged on a 1 ms
    cycle (the profile's planning rate: check without --cycle): the drive would take each step within 1 ms, past the
    torque rate's allowance there: exit 3, and the hint names --cycle. Given the cycle plan used, it is accepted."""
    path, _ = _plan(tmp_path, "delta-su2018", "-f", fmt, "--time", "fit", *args)
    cycle = "0.004" if fmt == "cam-table" else "0.01"
    assert _check(path, "delta-su2018", "--no-hold-capacity", "--cycle", cycle)[0] == 0
    code, doc, out = _check(path, "delta-su2018", "--no-hold-capacity")
    assert code == 3
    bad = [r for r in doc["limits"]["rows"] if r["quantity"] == "motor torque step" and not r["ok"]]
    assert bad and all(r["limit"] == pytest.approx(418 * 0.001 * _use("delta-su2018"), rel=1e-9) for r in bad)
    assert "its verdict depends on the cycle; give the one the drive runs it at with --cycle SECONDS" in out


def _use(prof: str) -> float:
    from pickplace_cli.model.profile import load_profile

    return load_profile(prof).planning.limit_use or 1.0


def test_cam_table_steps_against_an_independent_derivation(tmp_path):
    """The motor torque step rows of a cam-table on a 4 ms cycle, derived here: with a point every cycle the blends
    (one cycle, centred on each point) are contiguous; blend k's acceleration is (v_k − v_{k−1}) / c with v_k the
    slope from point k to k + 1 (at rest before the first and after the last); at the edge between blends k and
    k + 1 (half way between the points) the position and velocity are continuous and the acceleration steps from
    a_k to a_{k+1}, at the first blend's start from 0 and at the last one's end to 0. Motor torque from the
    independent rigid-body reference (Lagrange, complex step) as τ/(N·η) + J_rotor·N·q̈, its rate on either side
    by the reference's own difference along the blend's motion; the change over the cycle that takes a step is
    the step plus that rate × the cycle, the larger of the two sides, or, where larger, the exact change over a
    window of one cycle that holds the edge (each end u into its blend). Max over the edges per joint = check's row
    (1e-6 relative) and its time."""
    from pickplace_cli.model.profile import load_profile
    from pickplace_cli.pipelines.check_read import read_checked
    from pickplace_cli.robots import build_robot
    from tests.reference import delta_rigid as ref
    from tests.unit.test_delta_rigid_reference import drives, reference_params

    c = 0.004
    path, _ = _plan(tmp_path, "delta-su2018", "-f", "cam-table", "--time", "fit", "--cycle", str(c),
                    "--tolerance", "1e-4")
    prof = load_profile("delta-su2018")
    kind, table, _ = read_checked(open(path).read(), path, prof, build_robot(prof.robot))
    assert kind == "table" and table.kind == "cam-table"
    t, q = table.t - table.t[0], table.q
    assert np.allclose(np.diff(t), c, rtol=0, atol=1e-9)  # a point every cycle
    v = np.vstack([np.zeros((1, 3)), np.diff(q, axis=0) / c, np.zeros((1, 3))])  # v[k]: into point k … v[K]: out of it
    a = np.diff(v, axis=0) / c  # blend k's acceleration (K, 3)
    K = len(t)
    # the edges: the first blend's start (from rest), between blends k and k + 1, the last blend's end (to rest)
    qe = np.vstack([q[:1], (q[:-1] + q[1:]) / 2, q[-1:]])
    ve = np.vstack([np.zeros((1, 3)), v[1:K], np.zeros((1, 3))])
    before = np.vstack([np.zeros((1, 3)), a])
    after = np.vstack([a, np.zeros((1, 3))])
    te = np.append(t - c / 2, t[-1] + c / 2)
    N, eta, J = drives(prof)[:3]
    P = reference_params(prof)

    def motor(acc):
        return ref.reference_torques(P, qe, ve, acc) / (N * eta) + J * N * acc

    def motor_rate(acc):  # within a blend the acceleration is constant (no jerk): d/dt of the motor torque
        return ref.reference_torque_rate(P, qe, ve, acc, np.zeros_like(acc)) / (N * eta)

    # the drive takes each step within one cycle while the motion goes on: over that cycle the torque moves by the
    # step plus the rate × the cycle, the cycle before the edge or after it (the larger)
    jump = motor(after) - motor(before)
    step = np.maximum(np.abs(jump + motor_rate(before) * c), np.abs(jump + motor_rate(after) * c))
    # and exactly, the change over every window of one cycle that holds an edge: its start lies u into blend k, its
    # end u into blend k + 1 (u from 0 to c: the blends are one cycle long), the rest before the first blend and
    # after the last as blends of no motion; the row is the larger of the two
    z = np.zeros((1, 3))
    qs, vs, acs = np.vstack([qe[:1], qe[:-1], qe[-1:]]), np.vstack([z, ve[:-1], z]), np.vstack([z, a, z])

    def motor_at(qq, vv, aa):
        return ref.reference_torques(P, qq, vv, aa) / (N * eta) + J * N * aa

    window = np.zeros_like(step)
    for u in np.linspace(0.0, c, 21):
        tq = motor_at(qs + vs * u + acs * u * u / 2, vs + acs * u, acs)
        window = np.maximum(window, np.abs(tq[1:] - tq[:-1]))
    step = np.maximum(step, window)
    code, doc, out = _check(path, "delta-su2018", "--no-hold-capacity", "--cycle", str(c))
    assert code == 0, out[-2000:]
    rows = {r["joint"]: r for r in doc["limits"]["rows"] if r["quantity"] == "motor torque step"}
    for j, name in enumerate(("q1", "q2", "q3")):
        k = int(np.argmax(step[:, j]))
        assert rows[name]["peak"] == pytest.approx(step[k, j], rel=1e-6), name
        assert rows[name]["t_peak_s"] == pytest.approx(te[k], abs=1e-9), name
        assert rows[name]["limit"] == pytest.approx(418 * c * _use("delta-su2018"), rel=1e-9)


def test_pvt_steps_against_an_independent_derivation(tmp_path):
    """The motor torque step rows of a PVT table on a 1 ms cycle, derived here: the drive's cubic Hermite per segment
    from the table's points and velocities (its acceleration at both ends, its constant jerk), at rest before the
    first point and after the last (same position and velocity, no acceleration, no jerk). Motor torque and its rate
    on both sides of every point from the independent rigid-body reference; over the cycle that takes a step the
    torque moves by the step plus the rate × the cycle (either side: the larger). Max over the points per joint =
    check's row (1e-6 relative) and its time. The step alone (the rule before) is also computed, and is smaller
    somewhere: the test tells the two apart."""
    from pickplace_cli.model.profile import load_profile
    from pickplace_cli.pipelines.check_read import read_checked
    from pickplace_cli.robots import build_robot
    from tests.reference import delta_rigid as ref
    from tests.unit.test_delta_rigid_reference import drives, reference_params

    c = 0.001
    path, _ = _plan(tmp_path, "delta-su2018", "-f", "pvt", "--time", "fit", "--cycle", str(c))
    prof = load_profile("delta-su2018")
    kind, table, _ = read_checked(open(path).read(), path, prof, build_robot(prof.robot))
    assert kind == "table" and table.kind == "pvt"
    t, q, v = table.t - table.t[0], table.q, table.qd
    h = np.diff(t)[:, None]
    a2 = (3 * (q[1:] - q[:-1]) / h - 2 * v[:-1] - v[1:]) / h  # q(x) = q0 + v0 x + a2 x² + a3 x³ on [0, h]
    a3 = (2 * (q[:-1] - q[1:]) / h + v[:-1] + v[1:]) / h**2
    zero = np.zeros((1, 3))
    acc_before = np.vstack([zero, 2 * a2 + 6 * a3 * h])  # at each point: the segment before it (rest at the first)
    acc_after = np.vstack([2 * a2, zero])
    jerk_before = np.vstack([zero, 6 * a3])
    jerk_after = np.vstack([6 * a3, zero])
    N, eta, J = drives(prof)[:3]
    P = reference_params(prof)

    def motor(acc):
        return ref.reference_torques(P, q, v, acc) / (N * eta) + J * N * acc

    def motor_rate(acc, jerk):
        return ref.reference_torque_rate(P, q, v, acc, jerk) / (N * eta) + J * N * jerk

    jump = motor(acc_after) - motor(acc_before)
    moved = np.maximum(np.abs(jump + motor_rate(acc_before, jerk_before) * c),
                       np.abs(jump + motor_rate(acc_after, jerk_after) * c))
    assert (moved.max(axis=0) > np.abs(jump).max(axis=0) * (1 + 1e-3)).any()  # the rule before differs here
    code, doc, out = _check(path, "delta-su2018", "--no-hold-capacity", "--cycle", str(c))
    assert code == 0, out[-2000:]
    rows = {r["joint"]: r for r in doc["limits"]["rows"] if r["quantity"] == "motor torque step"}
    for j, name in enumerate(("q1", "q2", "q3")):
        k = int(np.argmax(moved[:, j]))
        assert rows[name]["peak"] == pytest.approx(moved[k, j], rel=1e-6), name
        assert rows[name]["t_peak_s"] == pytest.approx(t[k], abs=1e-9), name


def test_cycle_on_a_file_of_samples_is_named_not_used(tmp_path):
    """--cycle on a file of samples (no drive table): a one-line warning that it is not used; the verdict as
    without it."""
    path, _ = _plan(tmp_path, "delta-su2018", "-q")
    code, doc, out = _check(path, "delta-su2018", "--cycle", "0.004", "-q")
    assert code == 0 and "pickplace: warning: --cycle 0.004 s: not used" in out
    assert doc["step_cycle_s"] is None  # a file of samples has no step a cycle bounds


@pytest.mark.parametrize("args, cycle", [(("-f", "pvt"), None), (("-f", "cam-table"), None), (("-f", "pvt"), "0.002"),
                                         (("-f", "cam-table", "--round-trip"), "0.002")])
def test_the_report_names_the_cycle_the_steps_were_held_over(tmp_path, args, cycle):
    """check --report gives the controller cycle a table's steps were held over (step_cycle_s; a round trip's table
    is one table): --cycle when given, else what plan takes without it, as the step rows' limit (torque rate ×
    cycle)."""
    path, _ = _plan(tmp_path, "delta-su2018", "-q", *args)
    code, doc, out = _check(path, "delta-su2018", *(("--cycle", cycle) if cycle else ()))
    assert code == 0, out[-2000:]
    for m in [doc]:
        step = m["step_cycle_s"]
        if cycle is not None:
            assert step == float(cycle)
        else:
            assert step == pytest.approx(0.001, rel=0.01)  # about the 1 kHz planning rate's period
        rows = [r for r in m["limits"]["rows"] if r["quantity"] == "motor torque step"]
        assert rows and all(r["limit"] == pytest.approx(418 * step * _use("delta-su2018"), rel=1e-9) for r in rows)


@pytest.mark.parametrize("value, words", [("abc", "--cycle 'abc': must be a number of seconds"),
                                          ("0", "--cycle '0': the controller cycle must be a finite number"),
                                          ("4", "--cycle '4': the controller cycle must lie in")])
def test_a_bad_cycle_is_one_line(tmp_path, value, words):
    path, _ = _plan(tmp_path, "delta-su2018", "-f", "cam-table")
    res = runner.invoke(app, ["check", path, "--cycle", value])
    assert res.exit_code == 1
    (line,) = res.output.splitlines()
    assert line.startswith("pickplace: error: " + words), line


@pytest.mark.parametrize("args, keep", [((), 90), (("-f", "pvt"), 20), (("--round-trip",), None), ((), None),
                                        (("--rate", "100"), None), (("-f", "pvt"), None)])
def test_a_file_cut_short_says_it_ends_moving(tmp_path, args, keep):
    """A file cut off at speed (its first ``keep`` lines) is judged as it holds, with one warning that its motion ends
    moving and what follows is not checked; a whole file (a move, a round trip, at 100 Hz, a PVT table) has none.
    A cut PVT table also ends with its acceleration step to rest, held to the cycle's allowance (exit 3)."""
    path, _ = _plan(tmp_path, "delta-su2018", "-q", *args)
    if keep is not None:
        lines = open(path).read().splitlines()[:keep]
        open(path, "w").write("\n".join(lines) + "\n")
    res = runner.invoke(app, ["check", path, "-q"])
    warned = [ln for ln in res.output.splitlines() if "the motion ends moving" in ln]
    assert len(warned) == (1 if keep is not None else 0), res.output
    if keep is not None:
        assert warned[0].startswith("pickplace: warning: ")
        assert "% of its peak speed" in warned[0] and "a file cut short?" in warned[0]
        assert res.exit_code == (3 if "pvt" in args else 0), res.output
    else:
        assert res.exit_code == 0, res.output


@pytest.mark.parametrize("fmt", ["cam-table", "cam-table-st", "pvt"])
@pytest.mark.parametrize("rate", ["100", "500"])
def test_plan_names_the_cycle_check_needs_when_it_is_not_the_default(tmp_path, fmt, rate):
    """plan --rate R without --cycle judges a table's steps on a cycle from R, which check cannot know (the file does
    not hold it): plan's summary names the --cycle to give, and check with it accepts the table (check's default,
    the profile's planning rate, may not: the verdict depends on the cycle, and its hint says so)."""
    import re

    path, said = _plan(tmp_path, "delta-su2018", "-f", fmt, "--time", "optimal", "--rate", rate, "--tolerance", "1e-3")
    assert "table verdict: all limits hold" in said
    m = re.search(r"check it on the same cycle with pickplace check FILE --cycle ([0-9.e-]+)", said)
    assert m, said[-1500:]
    assert float(m.group(1)) == pytest.approx(1.0 / float(rate), rel=0.05)
    code, _, out = _check(path, "delta-su2018", "--no-hold-capacity", "--cycle", m.group(1))
    assert code == 0, out[-2000:]
    code, _, out = _check(path, "delta-su2018", "--no-hold-capacity")
    assert code == 0 or "its verdict depends on the cycle" in out


def test_plan_on_the_default_cycle_names_no_cycle(tmp_path):
    """plan without --rate or --cycle: check's default is plan's cycle; no --cycle line."""
    _, said = _plan(tmp_path, "delta-su2018", "-f", "cam-table")
    assert "table verdict: all limits hold" in said and "check it on the same cycle" not in said


@pytest.mark.parametrize("cycle, words", [(float("inf"), "cycle = inf: the controller cycle must be a finite"),
                                          (-1, "cycle = -1: the controller cycle must be a finite"),
                                          (0, "cycle = 0: the controller cycle must be a finite"),
                                          ("abc", "cycle = 'abc': must be a number of seconds"),
                                          (0.5, "cycle = 0.5 s: longer than the pvt table it runs")])
def test_check_file_refuses_a_bad_cycle(tmp_path, cycle, words):
    """The library's check_file(cycle=…) refuses what check --cycle refuses (a TaskError, never inf accepted or a
    ZeroDivisionError), and a cycle longer than the table itself."""
    from pickplace_cli import TaskError, check_file

    path, _ = _plan(tmp_path, "delta-su2018", "-f", "pvt", "-q")
    with pytest.raises(TaskError) as info:
        check_file(path, "delta-su2018", cycle=cycle)
    assert str(info.value).startswith(words), str(info.value)


def test_a_table_that_breaks_a_limit_suggests_no_trajectory_duration(tmp_path, monkeypatch):
    """A 256-point CODESYS cam table of a given duration breaks a step limit as the drive runs it while the trajectory
    holds (here the table is not re-timed: it would run 3.5 × as long): the closing line says the table is not
    written and why, and does not suggest the trajectory's holding duration (--time 0.3333 or --time limits, which
    fail as tables too)."""
    from pickplace_cli.pipelines import controller

    monkeypatch.setattr(controller, "RETIMES", 0)
    out = tmp_path / "sc.st"
    res = runner.invoke(app, ["plan", "-p", "scara-600", *MOVES["scara-600"], "-f", "cam-table-st", "--cam-object",
                              "codesys", "--tolerance", "1e-4", "--time", "0.5", "-o", str(out)])
    assert res.exit_code == 3 and not out.exists()
    last = [ln for ln in res.output.splitlines() if ln.startswith("pickplace: ")][-1]
    assert last.startswith("pickplace: table not written: the table breaks a limit as the drive interpolates it")
    assert "--time 0.3333" not in res.output and "--time limits holds" not in res.output


def test_the_report_of_several_moves_has_a_cycle_per_move(tmp_path):
    """A file of several moves (a round trip's samples): each move's entry carries step_cycle_s, null (no steps)."""
    path, _ = _plan(tmp_path, "delta-su2018", "-q", "--round-trip")
    code, doc, out = _check(path, "delta-su2018")
    assert code == 0, out[-2000:]
    assert len(doc["moves"]) == 2 and all(m["step_cycle_s"] is None for m in doc["moves"])


@pytest.mark.parametrize("args, words", [
    (("-f", "pvt", "--cycle", "0.000001"), "-f pvt: a table of 0.179957 s on a controller cycle of 1e-06 s (--cycle) "
                                           "is 179,957 cycles"),
    (("-f", "cam-table", "--cycle", "0.000002"), "-f cam-table: a table of 0.179958 s on a controller cycle of 2e-06 s"),
    (("-f", "cam", "--rate", "1000000"), "-f cam: a table of 0.179956 s on a sample period of 1e-06 s (--rate; no "
                                         "--cycle)")])
def test_a_table_of_too_many_cycles_is_one_line(tmp_path, args, words):
    """A drive's table is judged on every cycle (again after each round of points): one of more than 20,000 cycles
    (a microsecond cycle, or a MHz rate without a cycle) is refused at once, one line, exit 1, nothing written (it
    took minutes and gigabytes)."""
    out = tmp_path / "t.csv"
    res = runner.invoke(app, ["plan", *MOVES["delta-su2018"], *args, "-q", "-o", str(out)])
    assert res.exit_code == 1 and not out.exists()
    (line,) = res.output.splitlines()
    assert line.startswith("pickplace: error: " + words) and "at most 20,000" in line, line


def test_plan_quiet_still_names_the_cycle_to_check_on(tmp_path):
    """plan -q on a cycle that is not check's default still says (one warning) which --cycle check needs: without it
    check judges the file on its default cycle and refuses it."""
    out = tmp_path / "q4.csv"
    res = runner.invoke(app, ["plan", *ADEPT, "-f", "cam-table", "--cycle", "0.004", "-q", "-o", str(out)])
    assert res.exit_code == 0
    (line,) = res.output.splitlines()
    assert line.startswith("pickplace: warning: the table's steps are judged on a cycle of 0.004 s") and \
        line.endswith("pickplace check FILE --cycle 0.004"), line


def test_structured_text_times_are_the_csv_times(tmp_path):
    """A PVT's segment times on a 2 ms cycle are whole cycles: the Structured Text's fTime and fDt hold the CSV's
    numbers (0.006, not the difference's 0.005999999999999998)."""
    import re

    move = ("-p", "scara-600", "--from", "0.3,0,-0.1", "--to", "0.4,0,-0.1", "--cycle", "0.002", "-q")
    st, csv = tmp_path / "t.st", tmp_path / "t.csv"
    assert runner.invoke(app, ["plan", *move, "-f", "pvt-st", "-o", str(st)]).exit_code == 0
    assert runner.invoke(app, ["plan", *move, "-f", "pvt", "-o", str(csv)]).exit_code == 0
    rows = np.loadtxt(csv, delimiter=",", skiprows=1)
    text = st.read_text()
    for name, col in (("fTime", 0), ("fDt", 1)):
        body = re.search(name + r" : ARRAY\[1\.\.\d+\] OF LREAL := \[ \(\*[^*]*\*\)(.*?)\];", text, re.S).group(1)
        values = [float(v) for v in body.replace("\n", " ").split(",")]
        assert values == rows[:, col].tolist(), name
        assert all(len(repr(v)) <= 14 for v in values), name  # no float noise
    cycles = rows[1:, 1] / 0.002
    assert np.allclose(cycles, np.round(cycles), rtol=0, atol=1e-9)


@pytest.mark.parametrize("prof", ["delta-su2018", "gantry"])
def test_a_low_rate_file_from_rest_to_rest_does_not_say_it_starts_moving(tmp_path, prof):
    """At 50 Hz a move from rest covers 12-28 % of a joint's peak speed in its first interval (the gantry's short z
    axis): the interval's mean speed is no speed at its start. check said the motion starts moving (a file cut
    short?); the end speeds are now the slopes at the end samples of the parabolas through the first and last three
    samples. The same file cut off at 80 % of its samples (a joint at 28-63 % of its peak speed there, read from the
    file's own qd columns, an independent record of the motion) still says it ends moving."""
    move = MOVES.get(prof, ("--from", "-0.3,-0.2,-0.5", "--to", "0.3,0.3,-0.45"))
    path = str(tmp_path / f"{prof}-50.csv")
    res = runner.invoke(app, ["plan", "-p", prof, *move, "-o", path, "--rate", "50", "-q"])
    assert res.exit_code == 0, res.output
    res = runner.invoke(app, ["check", path, "-p", prof, "-q"])
    assert "moving (" not in res.output, res.output
    lines = open(path).read().splitlines()
    keep = int(0.8 * (len(lines) - 1))
    head = lines[0].split(",")
    cols = [i for i, h in enumerate(head) if h.startswith("qd") and not h.startswith("qdd")]
    qd = np.array([[float(x) for x in ln.split(",")] for ln in lines[1:keep + 1]])[:, cols]
    assert np.max(np.abs(qd[-1]) / np.abs(qd).max(axis=0)) > 0.25  # the cut file really ends at speed
    open(path, "w").write("\n".join(lines[:keep + 1]) + "\n")
    res = runner.invoke(app, ["check", path, "-p", prof, "-q"])
    assert "the motion ends moving" in res.output and "motion starts moving" not in res.output, res.output
