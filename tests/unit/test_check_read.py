"""pipelines/check_read: derivative columns judged against the positions, drive units read back, the tables rebuilt as
the drive interpolates them, and the work a hostile file can cause bounded. Every expectation is computed here, from
the profile's numbers or from polynomials solved in the test (numpy.linalg), never by the module under test."""

from __future__ import annotations

import math
import tracemalloc

import numpy as np
import pytest

from pickplace_cli.model.errors import PickplaceError, TaskError
from pickplace_cli.model.profile import load_profile
from pickplace_cli.pipelines import check_read as cr
from pickplace_cli.pipelines.check import check_file
from pickplace_cli.robots import build_robot

GEAR, CPR = 25.0, 1048576  # the shipped Delta's gear ratio and its encoders' counts per revolution (profile)
K_COUNTS = GEAR * CPR / (2 * math.pi)  # counts per joint rad: d = k · (q − 0), sign +1, offset 0 (delta-su2018.yaml)


def _septic_motion(n: int, duration: float = 0.2):
    """(t, (N, 12) x … jz) of an analytic motion: x = 0.1·sin(ωt) + 0.02·t³, y = 0.05·cos(ωt), z = −0.8 − 0.01·t⁴, and
    its exact derivatives (written out by hand)."""
    t = np.linspace(0.0, duration, n)
    w = 2 * math.pi / duration
    x = [0.1 * np.sin(w * t) + 0.02 * t**3, 0.1 * w * np.cos(w * t) + 0.06 * t**2,
         -0.1 * w**2 * np.sin(w * t) + 0.12 * t, -0.1 * w**3 * np.cos(w * t) + 0.12]
    y = [0.05 * np.cos(w * t), -0.05 * w * np.sin(w * t), -0.05 * w**2 * np.cos(w * t), 0.05 * w**3 * np.sin(w * t)]
    z = [-0.8 - 0.01 * t**4, -0.04 * t**3, -0.12 * t**2, -0.24 * t]
    cols = []
    for k in range(4):
        cols += [x[k], y[k], z[k]]
    return t, np.column_stack(cols)


@pytest.mark.parametrize("n", [20, 200, 2000])
def test_exact_derivative_columns_agree(n):
    """A motion's exact derivatives at 100 to 10,000 samples per second agree with its positions."""
    t, tool = _septic_motion(n)
    assert cr.derivative_problems(t, tool) == []


@pytest.mark.parametrize("order,change", [(1, "zero"), (2, "zero"), (3, "zero"), (1, "mm"), (3, "half"),
                                          (2, "stale")])
def test_disagreeing_derivative_columns_are_named(order, change):
    """Zeroed columns, velocities in mm/s, a halved jerk, accelerations of another timing (1.5× slower): the order
    concerned is reported (its misfit ≥ 0.2, far beyond its allowance)."""
    t, tool = _septic_motion(200)
    cols = slice(3 * order, 3 * order + 3)
    factor = {"zero": 0.0, "mm": 1000.0, "half": 0.5, "stale": 1 / 1.5**2}[change]
    tool = tool.copy()
    tool[:, cols] *= factor
    found = dict(cr.derivative_problems(t, tool))
    assert order in found and found[order] > 0.2, found


def _pvt_reference(t0, t1, p0, v0, p1, v1, x):
    """The cubic through p0, v0 at t0 and p1, v1 at t1, solved as a 4×4 linear system, at x."""
    A = np.array([[1, t0, t0**2, t0**3], [0, 1, 2 * t0, 3 * t0**2], [1, t1, t1**2, t1**3], [0, 1, 2 * t1, 3 * t1**2]])
    c = np.linalg.solve(A, [p0, v0, p1, v1])
    return np.polyval(c[::-1], x)


def _quintic_reference(t0, t1, p0, v0, a0, p1, v1, a1, x):
    """The quintic through (p, v, a) at t0 and t1, solved as a 6×6 linear system, at x."""
    def rows(s):
        return [[s**k for k in range(6)], [k * s ** (k - 1) if k else 0 for k in range(6)],
                [k * (k - 1) * s ** (k - 2) if k > 1 else 0 for k in range(6)]]
    c = np.linalg.solve(np.array(rows(t0) + rows(t1), float), [p0, v0, a0, p1, v1, a1])
    return np.polyval(c[::-1], x)


@pytest.mark.parametrize("kind", ["pvt", "cam"])
def test_tables_are_rebuilt_as_the_drive_interpolates(kind):
    """Random points: the rebuilt joint positions equal the polynomial solved here from each segment's conditions,
    to 1e-9 (round-off of a 6×6 solve on segments ~0.01 s long)."""
    rng = np.random.default_rng(3)
    t = np.cumsum(np.r_[0.0, rng.uniform(0.005, 0.02, 6)])
    q, qd, qdd = rng.normal(size=(7, 2)), rng.normal(size=(7, 2)) * 10, rng.normal(size=(7, 2)) * 100
    table = cr.Table(kind, t, q, qd, qdd if kind == "cam" else None, np.arange(2, 9))
    ev = cr.joint_polynomial(table)
    for k in range(6):
        x = np.linspace(t[k], t[k + 1], 7)[1:-1]
        for j in range(2):
            if kind == "pvt":
                want = _pvt_reference(t[k], t[k + 1], q[k, j], qd[k, j], q[k + 1, j], qd[k + 1, j], x)
            else:
                want = _quintic_reference(t[k], t[k + 1], q[k, j], qd[k, j], qdd[k, j], q[k + 1, j], qd[k + 1, j],
                                          qdd[k + 1, j], x)
            assert np.allclose(ev(x)[:, j], want, rtol=0, atol=1e-9)
    if kind == "pvt":  # the acceleration steps at the interior points: second derivative of the solved cubics
        def acc(k, s):
            A = np.array([[1, t[k], t[k]**2, t[k]**3], [0, 1, 2 * t[k], 3 * t[k]**2],
                          [1, t[k + 1], t[k + 1]**2, t[k + 1]**3], [0, 1, 2 * t[k + 1], 3 * t[k + 1]**2]])
            c = np.linalg.solve(A, [q[k, 0], qd[k, 0], q[k + 1, 0], qd[k + 1, 0]])
            return 2 * c[2] + 6 * c[3] * s
        want = max(abs(acc(k, t[k]) - acc(k - 1, t[k])) for k in range(1, 6))
        assert cr.pvt_acceleration_steps(table)[0] == pytest.approx(want, rel=1e-9)  # round-off of the solve


def test_drive_counts_are_read_back_to_joint_radians(tmp_path):
    """A recording in the profile's drive names and counts (d = 25 · 2²⁰ / 2π · q, written here) is read as the
    joint positions it encodes, to 1e-9 rad (12 significant digits of a count ~1e6)."""
    prof = load_profile("delta-su2018")
    robot = build_robot(prof.robot)
    t = np.linspace(0, 0.2, 41)
    q = np.column_stack([0.3 + 0.2 * np.sin(10 * t), 0.4 + 0.1 * t, 0.35 - 0.1 * t])
    rows = "".join(f"{a:.12g};{b:.12g};{c:.12g};{d:.12g}\r\n" for a, b, c, d in
                   np.column_stack([t, q * K_COUNTS]))
    kind, moves, _ = cr.read_checked("t[s];A1[counts];A2[counts];A3[counts]\r\n" + rows, "rec.csv", prof, robot)
    assert kind == "samples"
    assert np.allclose(moves[0].q, q, rtol=0, atol=1e-9)


def test_drive_offsets_and_signs_of_a_table(tmp_path):
    """A PVT table in the gantry's mm (k = 1000 per m) with t in ms: positions in m, velocities in m/s (1000 mm per m,
    1000 ms per s: the velocity column in mm/ms equals m/s), read exactly (1e-12)."""
    prof = load_profile("gantry")
    robot = build_robot(prof.robot)
    text = ("t[ms],dt[ms],AxisX[mm],AxisX_vel[mm/ms],AxisY[mm],AxisY_vel[mm/ms],AxisZ[mm],AxisZ_vel[mm/ms]\n"
            "0,0,100,0,200,0,-400,0\n10,10,150,2,210,0.5,-400,0\n20,10,180,0,220,0,-400,0\n")
    kind, table, _ = cr.read_checked(text, "p.csv", prof, robot)
    assert kind == "table" and table.kind == "pvt"
    assert np.allclose(table.t, [0, 0.01, 0.02], rtol=0, atol=1e-12)
    assert np.allclose(table.q[1], [0.15, 0.21, -0.4], rtol=0, atol=1e-12)
    assert np.allclose(table.qd[1], [2.0, 0.5, 0.0], rtol=0, atol=1e-12)


@pytest.mark.parametrize("text,words", [
    ("master[m],A1[counts],A2[counts],A3[counts]\n0,1,1,1\n", "belt master"),
    ("t[s],dt[s],A1[counts],A1_vel[counts/s],A2[counts],A2_vel[counts/s],A3[counts],A3_vel[counts/s]\n"
     "0,0,1,0,1,0,1,0\n0.01,0.02,1,0,1,0,1,0\n", "dt = 0.02"),
    ("t[s],A1[deg],A2[counts],A3[counts]\n0,1,1,1\n", "A1 is read in counts"),
    ("0\t1\t2\t3\n", "no header line"),
    ("t[s],B1,B2,B3\n0,1,1,1\n", "header lacks"),
])
def test_unreadable_drive_files_are_one_line(text, words):
    prof = load_profile("delta-su2018")
    with pytest.raises(TaskError) as exc:
        cr.read_checked(text, "f.csv", prof, build_robot(prof.robot))
    assert words in str(exc.value) and "\n" not in str(exc.value)


def _hostile(tmp_path, name: str, rows: list[str]) -> str:
    f = tmp_path / name
    f.write_text("t[s],q1[rad],q2[rad],q3[rad]\n" + "".join(rows))
    return str(f)


HOSTILE = {
    "q1 = 1e9 rad": lambda i: f"{i * 1e-3},1e9,0.3,0.3\n",
    "rows 1e-12 s apart": lambda i: f"{i * 1e-12},{0.6 + i * 1e-6},0.3,0.3\n",
    "t up to 1e11 s": lambda i: f"{i * 1e9},{0.6 + i * 1e-3},0.3,0.3\n",
    "alternating 1e3 rad": lambda i: f"{i * 1e-3},{(-1) ** i * 1e3},0.3,0.3\n",
}


@pytest.mark.parametrize("name", list(HOSTILE))
def test_hostile_100_row_files_do_bounded_work(tmp_path, name, monkeypatch):
    """A 100-row file of absurd values: an honest verdict or a one-line error, after a bounded number of model
    evaluations (counted here: at most 100,000 τ points over all reports of the move, measured ~22,000; before the RMS
    quadrature was bounded these files took tens of millions, tens of seconds and gigabytes) and less than 100 MB
    allocated at the peak (measured ~32 MB; a 64 MB read buffer was allocated for any file before)."""
    from pickplace_cli.limits.motion import MotionModel

    count = [0]
    orig = MotionModel._torques

    def counting(self, tau, *a, **k):
        count[0] += len(tau)
        return orig(self, tau, *a, **k)

    monkeypatch.setattr(MotionModel, "_torques", counting)
    path = _hostile(tmp_path, "h.csv", [HOSTILE[name](i) for i in range(100)])
    tracemalloc.start()
    try:
        try:
            checks = check_file(path, load_profile("delta-su2018"))
            assert checks[0].report.rows
        except PickplaceError as exc:  # invalid (exit 1) or unreachable (exit 4): one line
            assert "\n" not in str(exc)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert count[0] <= 100_000, count[0]
    assert peak < 100 << 20, peak


@pytest.mark.parametrize("cell", ["nan", "inf", "-inf", "1e999"])
def test_non_finite_values_are_one_line(tmp_path, cell):
    rows = [f"{i * 1e-3},{cell if i == 50 else 0.6},0.3,0.3\n" for i in range(100)]
    with pytest.raises(TaskError) as exc:
        check_file(_hostile(tmp_path, "n.csv", rows), load_profile("delta-su2018"))
    assert ":52:" in str(exc.value) and "q1" in str(exc.value) and "\n" not in str(exc.value)


def test_rms_quadrature_budget():
    """An integrand that never settles (random noise) stops at the evaluation budget, where it bisected for 40 rounds
    before; a smooth one (∫₀¹ [x², x³, x⁴] = [1/3, 1/4, 1/5]) is exact to 1e-12 well inside it."""
    from pickplace_cli.limits.grid import RMS_MAX_NODES, adaptive_gk15

    rng = np.random.default_rng(0)
    n_eval = [0]

    def noise(x):
        n_eval[0] += len(x)
        return rng.normal(size=(len(x), 3))

    adaptive_gk15(noise, np.linspace(0, 1, 9), 1)
    assert n_eval[0] <= RMS_MAX_NODES
    got = adaptive_gk15(lambda x: np.column_stack([x**2, x**3, x**4]), np.linspace(0, 1, 5), 1)
    assert np.allclose(got, [1 / 3, 1 / 4, 1 / 5], rtol=0, atol=1e-12)


def test_tables_without_controller_joints_name_the_model_joints():
    """A profile without controller.joints: plan's tables name q1 … qn in rad; a PVT table (t, dt, q1, q1_vel …) is a
    table, not samples of t and q1 … qn; a cam-table (master, q1 …) too."""
    prof = load_profile("delta-su2018").model_copy(update={"controller": None})
    robot = build_robot(prof.robot)
    pvt = ("t[s],dt[s],q1[rad],q1_vel[rad/s],q2[rad],q2_vel[rad/s],q3[rad],q3_vel[rad/s]\n"
           "0,0,0.6,0,0.3,0,0.3,0\n0.1,0.1,0.5,0,0.35,0,0.35,0\n")
    kind, table, _ = cr.read_checked(pvt, "p.csv", prof, robot)
    assert kind == "table" and table.kind == "pvt"
    assert np.allclose(table.q[1], [0.5, 0.35, 0.35], rtol=0, atol=1e-15)


CAM_MOVE = ["-p", "delta-4axis", "--from", "-0.15,0,-0.8,0", "--to", "0.15,0,-0.8,1.2", "--cycle", "0.001", "-q"]


def _plan(tmp_path, name: str, *args: str):
    from typer.testing import CliRunner

    from pickplace_cli.cli import app

    out = tmp_path / name
    assert CliRunner().invoke(app, ["plan", *CAM_MOVE, *args, "-o", str(out)]).exit_code == 0
    return out.read_text()


@pytest.mark.parametrize("fmt,plain,obj", [("cam-st", "cam", "codesys"), ("cam-st", "cam", "twincat"),
                                           ("cam-table-st", "cam-table", "twincat")])
def test_cam_objects_are_read_as_the_plain_table(tmp_path, fmt, plain, obj):
    """A cam object program (``--cam-object``) is read as the same points as the plain CSV table of the same plan:
    master, positions, velocities, accelerations, to the CSV's 12 significant digits (1e-9 relative)."""
    prof = load_profile("delta-4axis")
    robot = build_robot(prof.robot)
    got = cr.read_checked(_plan(tmp_path, "o.st", "-f", fmt, "--cam-object", obj), "o.st", prof, robot)
    want = cr.read_checked(_plan(tmp_path, "p.csv", "-f", plain), "p.csv", prof, robot)
    assert got[0] == want[0]
    a, b = got[1], want[1]
    assert np.allclose(a.t, b.t, rtol=1e-9, atol=1e-12)
    assert np.allclose(a.q, b.q, rtol=1e-9, atol=1e-12)
    for x, y in ((getattr(a, "qd", None), getattr(b, "qd", None)), (getattr(a, "qdd", None), getattr(b, "qdd", None))):
        assert (x is None) == (y is None)
        if x is not None:
            assert np.allclose(x, y, rtol=1e-9, atol=1e-6 * np.abs(y).max())


def test_codesys_equidistant_cam_object_spans_xstart_to_xend(tmp_path):
    """CODESYS's SMC_CAMTable holds the slave positions only: the master runs from xStart to xEnd in equal steps
    (256 points here), and check judges it within every limit, as plan's table verdict says."""
    import re

    from typer.testing import CliRunner

    from pickplace_cli.cli import app

    text = _plan(tmp_path, "c.st", "-f", "cam-table-st", "--cam-object", "codesys")
    x0 = float(re.search(r"xStart : LREAL := ([^;]+);", text).group(1))
    x1 = float(re.search(r"xEnd : LREAL := ([^;]+);", text).group(1))
    prof = load_profile("delta-4axis")
    kind, s, _ = cr.read_checked(text, "c.st", prof, build_robot(prof.robot))
    assert kind == "table" and s.kind == "cam-table" and len(s.t) == 256
    assert np.allclose(s.t, x0 + (x1 - x0) * np.arange(256) / 255, rtol=0, atol=1e-12)
    assert CliRunner().invoke(app, ["check", "-p", "delta-4axis", str(tmp_path / "c.st"), "-q"]).exit_code == 0


def test_a_cam_object_without_its_master_is_one_line():
    prof = load_profile("delta-4axis")
    text = ("PROGRAM PRG_PickplaceCams\nVAR CONSTANT\n    A1_y : ARRAY[0..1] OF LREAL := [ (* A1 slave position "
            "[counts] *)\n        0.0, 1.0];\nEND_VAR\n")
    with pytest.raises(TaskError, match="without its master"):
        cr.read_checked(text, "c.st", prof, build_robot(prof.robot))


def test_plan_json_is_checked_as_its_csv(tmp_path):
    """``plan -f json`` (a round trip: two moves) is checked as the CSV of the same plan: the same moves, the same
    peaks (the JSON's values are the CSV's to 12 significant digits: 1e-6 relative on a peak)."""
    prof = load_profile("delta-su2018")
    common = ["--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8", "--round-trip", "--cycle", "0.001", "-q"]
    from typer.testing import CliRunner

    from pickplace_cli.cli import app

    for name, fmt in (("r.json", "json"), ("r.csv", "csv")):
        assert CliRunner().invoke(app, ["plan", *common, "-f", fmt, "-o", str(tmp_path / name)]).exit_code == 0
    got = check_file(tmp_path / "r.json", prof)
    want = check_file(tmp_path / "r.csv", prof)
    assert [c.move for c in got] == [c.move for c in want] == [1, 2]
    for a, b in zip(got, want):
        assert [(r.joint, r.quantity) for r in a.report.rows] == [(r.joint, r.quantity) for r in b.report.rows]
        assert np.allclose([r.peak for r in a.report.rows], [r.peak for r in b.report.rows], rtol=1e-6, atol=1e-12)
        assert a.report.ok


@pytest.mark.parametrize("text,words", [('{"a": 1}', "without plan's 'columns' and 'samples'"),
                                        ('{"a":', "not valid JSON")])
def test_other_json_is_one_line(text, words):
    prof = load_profile("delta-su2018")
    with pytest.raises(TaskError, match=words):
        cr.read_checked(text, "x.json", prof, build_robot(prof.robot))


@pytest.mark.parametrize("second", ["q1[rad]", "q1[deg]"])
def test_a_column_named_twice_is_refused(tmp_path, second):
    """Two columns of one name: which is the motion would be a guess (read by position, swapping them flipped exit 0
    to exit 4): one line naming both cells, exit 1."""
    prof = load_profile("delta-su2018")
    rows = [f"{k * 1e-3:g},0.1,0.2,0.3,{0.1 + k * 1e-3:g}" for k in range(10)]
    f = tmp_path / "twice.csv"
    f.write_text(f"t[s],q1[rad],q2[rad],q3[rad],{second}\n" + "\n".join(rows) + "\n")
    with pytest.raises(TaskError, match=r"column 'q1' is named twice \(columns 2 and 5"):
        check_file(f, prof)


def test_drive_columns_beside_the_joints_must_be_the_same_motion(tmp_path):
    """``plan --columns t,q?,drive`` writes both; a drive column that is not its joint × k (counts, rounded to whole
    counts) is refused, one line naming both values; the file as written (whole counts) is read."""
    prof = load_profile("delta-su2018")
    t = np.linspace(0.0, 0.2, 41)
    q = np.column_stack([0.3 + 0.1 * np.sin(10 * t), 0.2 + 0.05 * t, 0.25 - 0.05 * t])
    counts = np.round(q * K_COUNTS)

    def text(c):
        return _joints_and_drives("t[s],q1[rad],q2[rad],q3[rad],A1[counts],A2[counts],A3[counts]", t, q, c, 0)
    ok = tmp_path / "both.csv"
    ok.write_text(text(counts))
    assert check_file(ok, prof)
    bad = counts.copy()
    bad[20, 0] += 5000  # 5000 counts ≈ 0.0012 rad off q1 at line 22
    f = tmp_path / "off.csv"
    f.write_text(text(bad))
    with pytest.raises(TaskError, match=r"off\.csv:22: A1 = .* counts is not q1 = .* converted by the profile"):
        check_file(f, prof)


@pytest.mark.parametrize("decimals", [3, 6])
def test_drive_and_joint_columns_rounded_like_a_logger_agree(tmp_path, decimals):
    """The gantry's axes in mm to 3 decimals (half a µm of rounding) beside joints in m to 12 digits, and joints to 6
    decimals beside axes to 3: each column's own last digit is allowed (it refused 5e-7 m "allowed 1e-9"); a
    drive column 10 µm off is still refused."""
    prof = load_profile("gantry")
    t = np.linspace(0.0, 0.2, 41)
    q = np.column_stack([0.1 + 0.3 * np.sin(5 * t), -0.2 + 0.1 * t + 0.01 * np.sin(7 * t), -0.5 + 0.05 * np.cos(3 * t)])
    qs = np.round(q, decimals) if decimals == 6 else q
    mm = np.round(q * 1000.0, 3)

    def text(d):
        return _joints_and_drives("t[s],q1[m],q2[m],q3[m],AxisX[mm],AxisY[mm],AxisZ[mm]", t, qs, d, 3)
    f = tmp_path / "g.csv"
    f.write_text(text(mm))
    assert check_file(f, prof)
    off = mm.copy()
    off[10, 1] += 0.01
    f.write_text(text(off))
    with pytest.raises(TaskError, match="AxisY = .* mm is not q2 = "):
        check_file(f, prof)


def _joints_and_drives(head: str, t: np.ndarray, q: np.ndarray, d: np.ndarray, decimals: int) -> str:
    """A CSV of t, the joints (12 digits) and the drives (``decimals`` decimals) under ``head``."""
    return head + "\n" + "".join(f"{a:.12g}," + ",".join(f"{x:.12g}" for x in b) + ","
                                 + ",".join(f"{x:.{decimals}f}" for x in c) + "\n" for a, b, c in zip(t, q, d))
