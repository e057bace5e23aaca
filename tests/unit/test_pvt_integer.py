"""export/pvt_int.py (``plan -f pvt|pvt-st --pvt-integer``): PVT in the drive's integer units, checked independently.

The CSV is read with the csv module; counts are turned back into rad with the scale derived here from the profile's
numbers (gear ratio 25 × 1048576 counts per rev / 2π); the drive's cubic is solved from each segment's conditions
(``numpy.linalg.solve``, from test_controller_tables) and compared with the robot's inverse kinematics of the
continuous trajectory. Tolerance: the table's own (1e-6 rad) plus what rounding to integers adds: half a count on a
position, and half a count/s on each end's velocity, which moves the cubic by at most 2 · 4/27 · h · 0.5 counts
(h ≤ 0.255 s: 0.038 counts); so 0.54 counts = 1.3e-7 rad here.
"""

from __future__ import annotations

import csv
import math
import re

import numpy as np
import pytest
from typer.testing import CliRunner

from pickplace_cli.cli import app
from pickplace_cli.export.drive import DriveMap
from pickplace_cli.export.knots import KnotTable
from pickplace_cli.export.pvt_int import MAX_SEGMENT_MS, integer_pvt
from pickplace_cli.model.errors import ExportError
from pickplace_cli.model.profile import load_profile, resolve_profile_path
from pickplace_cli.planner import PlanOptions, plan

from .test_controller_tables import ADEPT, BACK, THERE, continuous_q, interpolate, piece_poly

K = 25.0 * 1048576 / (2 * math.pi)  # counts per rad of the shipped Delta's joints
ROUNDING = 0.5 + 2 * 4 / 27 * 0.255 * 0.5  # counts: see the module docstring


def run(*args):
    return CliRunner().invoke(app, list(args), catch_exceptions=False)


def read_rows(path) -> tuple[list[str], list[list[str]]]:
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    return rows[0], rows[1:]


def test_round_trip_in_integer_units_follows_the_trajectory(tmp_path):
    out, ref = tmp_path / "int.csv", tmp_path / "float.csv"
    # at 0.2 s (81 % of the capacity acceleration) no limit binds the table: its points are the float table's
    common = ("plan", *ADEPT, "--time", "0.2", "--round-trip", "--cycle", "0.001", "-q", "--tolerance", "1e-6")
    assert run(*common, "-f", "pvt", "--pvt-integer", "-o", str(out)).exit_code == 0
    assert run(*common, "-f", "pvt", "-o", str(ref)).exit_code == 0
    head, rows = read_rows(out)
    assert head == ["t[ms]", "dt[ms]", "A1[counts]", "A1_vel[counts/s]", "A2[counts]", "A2_vel[counts/s]",
                    "A3[counts]", "A3_vel[counts/s]"]
    assert all(re.fullmatch(r"-?\d+", v) for row in rows for v in row)  # integers only
    data = np.array(rows, dtype=np.int64)
    t_ms, dt = data[:, 0], data[:, 1]
    assert dt[0] == 0 and np.all((dt[1:] >= 1) & (dt[1:] <= MAX_SEGMENT_MS)) and np.array_equal(np.cumsum(dt), t_ms)
    assert np.all(np.abs(data[:, 2:]) <= 2**31 - 1)
    # fitted closer than the float table by what rounding adds (so at least as many points), every point on a ms
    _, frows = read_rows(ref)
    fdata = np.array(frows, dtype=float)
    assert len(data) >= len(fdata)
    assert np.isin(np.rint(fdata[:, 0] * 1000)[[0, -1]], t_ms).all()
    # the drive's cubic through the integer points follows the robot's inverse kinematics
    err = _drive_deviation(data)
    assert np.all(err <= 1e-6), err  # the tolerance holds for the integers as written, rounding included


def _drive_deviation(data: np.ndarray) -> np.ndarray:
    """Per joint, the largest deviation [rad] of the drive's cubic through the integer table ``data`` (the Adept
    round trip at 0.2 s a leg) from the robot's inverse kinematics of the continuous trajectory, 24 points a
    segment."""
    prof = load_profile("delta-su2018")
    opts = PlanOptions(time=0.2, cycle=0.001, fit=False)
    legs = [plan(THERE, prof, opts), plan(BACK, prof, opts)]
    x = data[:, 0] / 1000.0
    p, v = data[:, 2::2] / K, data[:, 3::2] / K
    at = np.concatenate([np.linspace(x[k], x[k + 1], 24, endpoint=False) for k in range(len(x) - 1)] + [x[-1:]])
    return np.abs(interpolate("pvt", x, p, v, None, at) - continuous_q("delta-su2018", legs, 0.1, at)).max(axis=0)


def _drive(k: float, n: int = 2) -> DriveMap:
    return DriveMap(tuple(f"J{i + 1}" for i in range(n)), ("counts",) * n, (k,) * n, (0.0,) * n, ("counts",) * n,
                    (1,) * n)


def test_a_long_segment_is_split_on_its_own_cubic():
    """A 700 ms segment (a long dwell-free segment of a slow move) becomes 3 of 233, 233, 234 ms whose cubics, solved
    here from the integer points, are the original segment's cubic to within the rounding (in counts)."""
    rng = np.random.default_rng(71)
    t = np.array([0.0, 0.7, 0.75])
    q, qd = rng.uniform(-1, 1, (3, 2)), rng.uniform(-2, 2, (3, 2))
    table = KnotTable("pvt", t, q, qd, None, 1e-6, np.zeros(2), 751)
    k = 1e6
    pvt = integer_pvt(table, _drive(k))
    assert pvt.t_ms.tolist() == [0, 233, 466, 700, 750] and pvt.split == 1
    x = pvt.t_ms / 1000.0
    at = np.linspace(0.0, 0.7, 701)
    got = interpolate("pvt", x, pvt.pos.astype(float), pvt.vel.astype(float), None, at)
    for j in range(2):
        c = piece_poly([(0.0, 0, k * q[0, j]), (0.7, 0, k * q[1, j]), (0.0, 1, k * qd[0, j]), (0.7, 1, k * qd[1, j])])
        want = np.polynomial.polynomial.polyval(at, c)
        assert np.max(np.abs(got[:, j] - want)) <= ROUNDING, j


def test_off_the_millisecond_or_no_counts_is_refused():
    table = KnotTable("pvt", np.array([0.0, 0.0105]), np.zeros((2, 2)), np.zeros((2, 2)), None, 1e-6, np.zeros(2), 2)
    with pytest.raises(ExportError, match="not on a whole millisecond"):
        integer_pvt(table, _drive(1e5))
    table = KnotTable("pvt", np.array([0.0, 0.01]), np.zeros((2, 2)), np.zeros((2, 2)), None, 1e-6, np.zeros(2), 2)
    deg = DriveMap(("J1", "J2"), ("deg", "counts"), (57.3, 1e5), (0.0, 0.0), ("deg", "counts"), (1, 1))
    with pytest.raises(ExportError, match="J1 unit = deg"):
        integer_pvt(table, deg)
    with pytest.raises(ExportError, match="no controller.joints"):
        integer_pvt(table, None)


def test_past_32_bits_is_exit_1_one_line_nothing_written(tmp_path):
    """A 30-bit encoder behind the 25:1 gear: 4.3e9 counts per rad of the joint, ±0.5 rad in 32 bits; the Delta's
    joints sit near 0.6 rad, past it."""
    text = resolve_profile_path("delta-su2018").read_text()
    assert "counts_per_rev: 1048576" in text
    prof = tmp_path / "big.yaml"
    prof.write_text(text.replace("counts_per_rev: 1048576", "counts_per_rev: 1073741824"))
    out = tmp_path / "t.csv"
    res = run("plan", "-p", str(prof), *ADEPT, "--cycle", "0.001", "-q", "-f", "pvt", "--pvt-integer", "-o", str(out))
    assert res.exit_code == 1 and res.stderr.count("\n") == 1, res.stderr
    assert "A1 position = 2.6" in res.stderr and "32-bit" in res.stderr and "±0.5" in res.stderr
    assert not out.exists()


@pytest.mark.parametrize("args, code, says", [
    (("-f", "cam"), 2, "--pvt-integer applies to the PVT formats"),
    (("-f", "csv"), 2, "--pvt-integer applies to the PVT formats"),
    (("-f", "pvt"), 1, "not on a whole millisecond"),  # no cycle: the move's end is not on a millisecond
    (("-p", "scara-600", "--cycle", "0.001", "-f", "pvt"), 1, "unit = deg"),
])
def test_usage_and_refusals(args, code, says, tmp_path):
    moves = ("--from", "0.3,-0.2,-0.1", "--to", "0.3,0.2,-0.1") if "scara-600" in args else ADEPT
    res = run("plan", *moves, *args, "--pvt-integer", "-q", "-o", str(tmp_path / "t.csv"))
    assert res.exit_code == code and says in res.stderr, res.stderr


@pytest.mark.parametrize("dialect", ["strict", "codesys"])
def test_integer_st_parses_and_holds_the_csv_integers(dialect):
    """Both dialects parse with tree-sitter's IEC 61131-3 grammar (strict also compiles with matiec:
    test_st_matiec) and hold exactly the integers of the CSV form; no name is reserved."""
    from pickplace_cli.export.pvt_int import format_integer_csv, format_integer_st

    from .test_st_strict import _errors, _identifiers, _tree_sitter, reserved

    table = KnotTable("pvt", np.array([0.0, 0.004, 0.3]), np.array([[0.1, -0.2], [0.11, -0.19], [0.2, 0.0]]),
                      np.array([[0.0, 0.0], [3.0, 1.0], [0.0, 0.0]]), None, 1e-6, np.zeros(2), 301)
    pvt = integer_pvt(table, _drive(1e6))
    text = format_integer_st(pvt, dialect)
    tree = _tree_sitter(text)
    assert not _errors(tree.root_node)
    assert not [i for i in _identifiers(tree.root_node) if reserved(i)]
    _, *rows = [line.split(",") for line in format_integer_csv(pvt).splitlines()]
    prefix = "" if dialect == "strict" else "PP_PVT_"
    for k, name in enumerate(["nTime", "nDt", "J1_pos", "J1_vel", "J2_pos", "J2_vel"]):
        st_name = name if dialect == "strict" else prefix + name.upper()
        body = re.search(rf"{st_name} : ARRAY\[1\.\.(\d+)\] OF DINT := \[ \(\*.*?\*\)(.*?)\];", text, re.S)
        assert body and int(body.group(1)) == len(rows) == 4  # the 300 ms segment split in two
        assert [int(v) for v in body.group(2).split(",")] == [int(r[k]) for r in rows], name


@pytest.mark.parametrize("fmt,suffix", [("pvt", "csv"), ("pvt-st", "st")])
def test_check_reads_the_integer_table_plan_writes(tmp_path, fmt, suffix):
    """``check`` reads ``--pvt-integer`` (t[ms], velocities in counts/s, DINT arrays in ST) as the trajectory it was
    written from: at each point the position and the velocity of the cycle-sampled CSV of the same plan, to half a
    count and half a count/s (the rounding, over K counts per rad); and the drive's interpolation of those rounded
    integers holds every limit there as plan's table verdict says (check exit 0; the Adept move at 1 ms sits at 100 %
    of the capacity acceleration, where judging the values before rounding let the written table reach 100.4 %)."""
    from pickplace_cli.pipelines import check_read as cr
    from pickplace_cli.robots import build_robot

    out, ref = tmp_path / f"int.{suffix}", tmp_path / "samples.csv"
    common = ("plan", *ADEPT, "--cycle", "0.001", "-q")
    # 1.2e-6: the table's 0.95e-6 and rounding's 0.12e-6 fit in it, so the integer table is not re-fitted closer, nor
    # re-timed, and its points lie on the samples
    assert run(*common, "-f", fmt, "--pvt-integer", "--tolerance", "1.2e-6", "-o", str(out)).exit_code == 0
    assert run(*common, "-o", str(ref)).exit_code == 0
    prof = load_profile("delta-su2018")
    _, got, _ = cr.read_checked(out.read_text(), "int", prof, build_robot(prof.robot))
    head, rows = read_rows(ref)
    samples = np.array(rows, dtype=float)
    k = np.rint(got.t * 1000).astype(int)  # the points lie on the 1 ms grid, sample k at t = k ms
    q = samples[k][:, [head.index(f"q{j}[rad]") for j in (1, 2, 3)]]
    qd = samples[k][:, [head.index(f"qd{j}[rad/s]") for j in (1, 2, 3)]]
    assert np.allclose(got.t, samples[k, 0], rtol=0, atol=1e-12)
    assert np.allclose(got.q, q, rtol=0, atol=0.5 / K + 1e-11)  # 12 significant digits in the CSV
    assert np.allclose(got.qd, qd, rtol=0, atol=0.5 / K + 1e-9)  # not 1000 x: counts/s under t[ms]
    assert run("check", str(out), "-q").exit_code == 0


@pytest.mark.parametrize("unit,scale", [("counts/s", 1.0), ("counts/ms", 1e3), ("counts/us", 1e6)])
def test_a_velocity_column_is_read_in_its_own_time_unit(unit, scale):
    """A table's velocity column carries its own time unit, whatever the time column's: 1 count/<unit> is
    ``scale`` counts/s, i.e. scale / K rad/s (K from the profile's numbers)."""
    from pickplace_cli.pipelines import check_read as cr
    from pickplace_cli.robots import build_robot

    prof = load_profile("delta-su2018")
    text = (f"t[ms],dt[ms],A1[counts],A1_vel[{unit}],A2[counts],A2_vel[{unit}],A3[counts],A3_vel[{unit}]\n"
            "0,0,2000000,0,2000000,0,2000000,0\n10,10,2000001,1,2000002,2,2000003,3\n")
    _, table, _ = cr.read_checked(text, "p.csv", prof, build_robot(prof.robot))
    assert np.allclose(table.qd[1], np.array([1, 2, 3]) * scale / K, rtol=1e-12, atol=0)


def test_a_velocity_in_an_unknown_time_unit_is_one_line():
    from pickplace_cli.model.errors import TaskError
    from pickplace_cli.pipelines import check_read as cr
    from pickplace_cli.robots import build_robot

    prof = load_profile("delta-su2018")
    text = ("t[ms],dt[ms],A1[counts],A1_vel[counts/min],A2[counts],A2_vel[counts/s],A3[counts],A3_vel[counts/s]\n"
            "0,0,1,0,1,0,1,0\n10,10,1,0,1,0,1,0\n")
    with pytest.raises(TaskError, match=r"A1_vel\[counts/min\].*per s, ms or us"):
        cr.read_checked(text, "p.csv", prof, build_robot(prof.robot))


@pytest.mark.parametrize("tolerance", [1e-6, 3e-7])
def test_the_stated_deviation_is_that_of_the_integers_as_written(tmp_path, tolerance):
    """The summary's deviation bounds the deviation of the drive's cubic through the written integers from the robot's
    inverse kinematics (measured here independently, 24 points a segment), and stays within --tolerance: the table is
    fitted closer by what rounding to whole counts adds (1.2e-7 rad here, a third of 3e-7)."""
    import json

    out = tmp_path / "int.csv"
    res = run("plan", *ADEPT, "--time", "0.2", "--round-trip", "--cycle", "0.001", "-q", "--tolerance", str(tolerance),
              "-f", "pvt", "--pvt-integer", "-o", str(out), "--json")
    assert res.exit_code == 0, res.stderr
    summary = json.loads(res.stdout)
    table = summary["table"] if "table" in summary else summary["plans"][0]["table"]
    stated = np.array(table["max_error"])
    assert table["tolerance"] == tolerance and np.all(stated <= tolerance), stated
    err = _drive_deviation(np.array(read_rows(out)[1], dtype=np.int64))
    assert np.all(err <= stated * (1 + 1e-3) + 1e-12), (err, stated)
    assert np.all(err <= tolerance), (err, tolerance)
