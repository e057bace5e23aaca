"""PVT and cam tables (``plan --format pvt|cam|cam-table``), checked independently of the code that fits them.

The exported CSV is read with the csv module; its drive units are turned back into model joint positions with the
scale derived here from the profile's numbers (counts: gear ratio × counts per rev / 2π, deg: 180/π, mm: 1000);
the controller's interpolation is evaluated here with polynomial coefficients solved from the points' conditions
(``numpy.linalg.solve``: a cubic through (p, v) at both ends for PVT, a quintic through (p, v, a) for cam, a line for
the equidistant table), not with the exporter's Hermite basis; and the trajectory it must follow is the robot's
inverse kinematics of the plan's continuous Cartesian trajectory (``plan.cartesian``). The largest deviation must
lie within the tolerance asked for (to 1e-12 rad or m: the CSV's 12 significant digits of a position in counts,
~2.6e6, resolve 1e-5 counts = 2.4e-12 rad).
"""

from __future__ import annotations

import csv
import io
import math

import numpy as np
import pytest
from typer.testing import CliRunner

from pickplace_cli.cli import app
from pickplace_cli.model.profile import load_profile
from pickplace_cli.model.task import Task
from pickplace_cli.planner import PlanOptions, plan
from pickplace_cli.robots import build_robot

runner = CliRunner()
ADEPT = ("--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8")
THERE = Task([-0.1525, 0.0, -0.8], [0.1525, 0.0, -0.8], 0.025, 0.5)
BACK = Task([0.1525, 0.0, -0.8], [-0.1525, 0.0, -0.8], 0.025, 0.5)
SLACK = 1e-12  # rad or m: see the module docstring


def run(*args):
    return runner.invoke(app, list(args), catch_exceptions=False)


def read_table(path) -> tuple[list[str], np.ndarray]:
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    return rows[0], np.array(rows[1:], dtype=float)


def drive_scale(profile_name: str) -> tuple[np.ndarray, np.ndarray]:
    """(sign·k, offset) per joint of the shipped profiles' controller.joints, derived here from their numbers."""
    if profile_name == "delta-su2018":
        k = 25.0 * 1048576 / (2 * math.pi)
        return np.array([k, k, k]), np.zeros(3)
    if profile_name == "scara-600":
        return np.array([180 / math.pi, 180 / math.pi, -1000.0, 180 / math.pi]), np.zeros(4)
    return np.array([1000.0, 1000.0, 1000.0]), np.zeros(3)


def model_q(profile_name: str, head: list[str], data: np.ndarray, suffix: str = "") -> np.ndarray:
    """The joints' columns ``NAME{suffix}[..]`` of a table, in model units (positions with the offset added back)."""
    scale, offset = drive_scale(profile_name)
    names = [h.split("[")[0] for h in head]
    joints = [n for n in names if n not in ("t", "dt", "master") and not n.endswith(("_vel", "_acc"))]
    cols = np.column_stack([data[:, names.index(j + suffix)] for j in joints])
    return cols / scale + (offset if not suffix else 0.0)


def piece_poly(conds: list[tuple[float, int, float]]) -> np.ndarray:
    """Coefficients c (lowest first) of the polynomial of degree len(conds) − 1 meeting every (s, derivative order,
    value): solved as a linear system."""
    m = len(conds)
    A = np.zeros((m, m))
    b = np.zeros(m)
    for r, (s, order, value) in enumerate(conds):
        for c in range(order, m):
            A[r, c] = math.factorial(c) / math.factorial(c - order) * s ** (c - order)
        b[r] = value
    return np.linalg.solve(A, b)


def interpolate(kind: str, x: np.ndarray, p: np.ndarray, v: np.ndarray | None, a: np.ndarray | None,
                at: np.ndarray) -> np.ndarray:
    """The controller's interpolation of the points (x, p[, v[, a]]) at ``at`` (every joint)."""
    if kind == "cam-table":  # a line between nodes: numpy's own linear interpolation
        return np.column_stack([np.interp(at, x, p[:, j]) for j in range(p.shape[1])])
    out = np.empty((len(at), p.shape[1]))
    seg = np.clip(np.searchsorted(x, at, side="right") - 1, 0, len(x) - 2)
    for k in np.unique(seg):
        sel = seg == k
        h = x[k + 1] - x[k]
        for j in range(p.shape[1]):
            conds = [(0.0, 0, p[k, j]), (h, 0, p[k + 1, j])]
            if kind in ("pvt", "cam"):
                conds += [(0.0, 1, v[k, j]), (h, 1, v[k + 1, j])]
            if kind == "cam":
                conds += [(0.0, 2, a[k, j]), (h, 2, a[k + 1, j])]
            c = piece_poly(conds)
            out[sel, j] = np.polynomial.polynomial.polyval(at[sel] - x[k], c)
    return out


def continuous_q(profile_name: str, legs: list, dwell: float, t: np.ndarray, lengths: list | None = None) -> np.ndarray:
    """The joint positions of the written trajectory at ``t`` [s]: the legs one after another with a dwell after each
    (none after a single leg), by the robot's inverse kinematics of each plan's Cartesian trajectory; ``lengths``
    [s]: each leg run in that time instead of its own (a table re-timed so that it holds every limit as the drive
    interpolates it: the same path, uniformly slower)."""
    robot = build_robot(load_profile(profile_name).robot)
    out = np.full((len(t), len(robot.joint_names)), np.nan)
    t0 = 0.0
    for i, leg in enumerate(legs):  # (the CSV's 12 digits put the last time up to 1e-12 s past the end)
        T = leg.cartesian.duration
        L = T if lengths is None else lengths[i]
        sel = (t >= t0 - 1e-9) & (t <= t0 + L + (dwell if len(legs) > 1 else 1e-9))
        local = np.clip(t[sel] - t0, 0.0, L)
        out[sel] = robot.inverse_kinematics(leg.cartesian(local * (T / L)))
        t0 += L + (dwell if len(legs) > 1 else 0.0)
    return out


def check_table(kind, path, profile_name, legs, dwell, tolerance, per_segment=40, lengths=None):
    head, data = read_table(path)
    x = data[:, 0]
    p = model_q(profile_name, head, data)
    v = model_q(profile_name, head, data, "_vel") if kind != "cam-table" else None
    a = model_q(profile_name, head, data, "_acc") if kind == "cam" else None
    at = np.concatenate([np.linspace(x[k], x[k + 1], per_segment, endpoint=False) for k in range(len(x) - 1)] + [x[-1:]])
    if lengths is None and len(legs) == 1:  # a single move's table may be re-timed: it ends at the move's new end
        lengths = [x[-1]]
    true = continuous_q(profile_name, legs, dwell, at, lengths)
    assert np.all(np.isfinite(true))
    err = np.abs(interpolate(kind, x, p, v, a, at) - true).max(axis=0)
    assert np.all(err <= tolerance + SLACK), (kind, err, tolerance)
    return len(x), err


@pytest.fixture(scope="module")
def adept_round_trip():
    prof = load_profile("delta-su2018")
    opts = PlanOptions(cycle=0.001, fit=False)
    return [plan(THERE, prof, opts), plan(BACK, prof, opts)]


@pytest.mark.parametrize("kind", ["pvt", "cam", "cam-table"])
def test_adept_round_trip_table_within_tolerance_and_fewer_points(kind, tmp_path, adept_round_trip):
    out = tmp_path / f"rt.{kind}.csv"
    res = run("plan", *ADEPT, "--round-trip", "--cycle", "0.001", "-f", kind, "--tolerance", "1e-6", "-o", str(out),
              "--json")
    assert res.exit_code == 0, res.stderr
    import json

    info = json.loads(res.stdout)["table"]
    # a re-timed table (every move x stretch, on whole 1 ms cycles) follows the same path, slower
    lengths = [math.ceil(info["stretch"] * leg.cartesian.duration / 0.001 - 1e-9) * 0.001 for leg in adept_round_trip]
    # an equidistant table on a 1 ms cycle has one point per cycle (the drive reads one point a cycle and runs
    # straight between its setpoints: a finer step changes nothing it runs), so its points are on the trajectory
    # and the lines between them as far off it as the cycle makes them: checked at the points only
    per = 1 if kind == "cam-table" else 40
    n, err = check_table(kind, out, "delta-su2018", adept_round_trip, 0.1, 1e-6, per_segment=per, lengths=lengths)
    samples = round((sum(lengths) + 0.2) / 0.001) + 1  # 0.56 s at one sample per 1 ms cycle, both ends included
    assert samples == 561 or info["stretch"] > 1.0
    assert f"{n} points for {samples} samples" in res.stderr
    if kind != "cam-table":
        assert n < samples / 5, n
    else:
        assert n == samples and info["master_step_cycles"] == 1 and info["tolerance_points"] > n
        assert "master step 1 cycle (1 ms)" in res.stderr and "over --tolerance 1e-06" in res.stderr
    if kind == "pvt":  # the points lie on the cycle grid: every segment time a whole number of cycles
        _, data = read_table(out)
        k = data[:, 0] / 0.001
        assert np.all(np.abs(k - np.rint(k)) < 1e-9)


RANDOM_MOVES = {
    "delta-su2018": (np.array([-0.12, -0.08, -0.82]), np.array([0.10, 0.09, -0.86])),
    "scara-600": (np.array([0.35, -0.20, -0.05]), np.array([0.30, 0.25, -0.12])),
    "gantry": (np.array([-0.4, 0.3, -0.3]), np.array([0.5, -0.2, -0.5])),
}


@pytest.mark.parametrize("profile_name", sorted(RANDOM_MOVES))
@pytest.mark.parametrize("kind", ["pvt", "cam"])
def test_a_move_per_profile_table_within_tolerance(profile_name, kind, tmp_path):
    rng = np.random.default_rng(sum(map(ord, profile_name)))
    a, b = RANDOM_MOVES[profile_name]
    start = a + rng.uniform(-0.01, 0.01, 3)
    end = b + rng.uniform(-0.01, 0.01, 3)
    xyz = lambda p: ",".join(f"{c:.4f}" for c in p)  # noqa: E731
    out = tmp_path / "t.csv"
    res = run("plan", "--profile", profile_name, "--from", xyz(start), "--to", xyz(end), "-f", kind,
              "--tolerance", "1e-5", "-o", str(out), "--report-only")
    assert res.exit_code == 0, res.stderr
    prof = load_profile(profile_name)
    task = Task([float(c) for c in xyz(start).split(",")], [float(c) for c in xyz(end).split(",")],
                prof.planning.height, prof.planning.eta)
    leg = plan(task, prof, PlanOptions(fit=False))
    n, err = check_table(kind, out, profile_name, [leg], 0.0, 1e-5)
    assert n < len(leg.t) / 3


def test_tolerance_too_small_for_the_data_is_exit_1_and_nothing_written(tmp_path):
    out = tmp_path / "t.csv"
    out.write_text("old\n")
    res = run("plan", *ADEPT, "-q", "-f", "pvt", "--tolerance", "1e-15", "-o", str(out))
    assert res.exit_code == 1
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "--tolerance 1e-15" in lines[0] and "too small" in lines[0]
    assert out.read_text() == "old\n"
    for bad in ("0", "-1e-6", "nan"):
        res = run("plan", *ADEPT, "-q", "-f", "cam", "--tolerance", bad, "-o", str(out))
        assert res.exit_code == 1 and "tolerance" in res.stderr and res.stderr.count("\n") == 1, bad
        assert out.read_text() == "old\n"


def test_belt_master_cam_is_belt_travel_with_derivatives_per_metre(tmp_path):
    """A conveyor move's cam over the belt's travel x = speed·(latency + t): the quintic in x, evaluated here, follows
    the IK of the move (and of its tracking segment) at t = x/speed − latency. The cam ends moving with the belt:
    with the drive holding its last point it is refused (the step to rest, exit 3), with --table-end continue (the
    controller goes on with the belt) it is written."""
    out = tmp_path / "belt.csv"
    args = ("--from", "-0.1525,0,-0.8", "--to", "0.05,0.1,-0.8", "--to-belt", "0.3,0,0", "--latency", "0.05")
    res = run("plan", *args, "-f", "cam", "--cam-master", "belt", "--tolerance", "1e-5", "-o", str(out))
    assert res.exit_code == 3 and not out.exists(), res.stderr
    assert "the drive holds the table's last point after it" in res.stderr and "--table-end continue" in res.stderr
    res = run("plan", *args, "-f", "cam", "--cam-master", "belt", "--tolerance", "1e-5", "-o", str(out),
              "--table-end", "continue")
    assert res.exit_code == 0, res.stderr
    assert "judged as the controller going on at its end velocity" in res.stderr
    head, data = read_table(out)
    assert head[0] == "master[m]" and head[2] == "A1_vel[counts/m]" and head[3] == "A1_acc[counts/m^2]"
    x = data[:, 0]
    assert x[0] == pytest.approx(0.3 * 0.05, abs=1e-12)  # the belt travelled during the latency
    from pickplace_cli.pipelines.rendezvous import Part, plan_rendezvous
    from pickplace_cli.pipelines.tracking import plan_tracking

    prof = load_profile("delta-su2018")
    part = Part(np.array([0.05, 0.1, -0.8]), np.array([0.3, 0.0, 0.0]), 0.05)
    move, _rv = plan_rendezvous(np.array([-0.1525, 0.0, -0.8]), part, prof)
    track = plan_tracking(move, part, prof)
    p = model_q("delta-su2018", head, data)
    v = model_q("delta-su2018", head, data, "_vel")
    acc = model_q("delta-su2018", head, data, "_acc")
    at = np.concatenate([np.linspace(x[k], x[k + 1], 30, endpoint=False) for k in range(len(x) - 1)] + [x[-1:]])
    t = at / 0.3 - 0.05
    robot = build_robot(prof.robot)
    T = move.cartesian.duration
    q = np.where((t <= T)[:, None], robot.inverse_kinematics(move.cartesian(np.clip(t, 0, T))),
                 robot.inverse_kinematics(track.cartesian(np.clip(t - T, 0, track.cartesian.duration))))
    err = np.abs(interpolate("cam", x, p, v, acc, at) - q).max()
    assert err <= 1e-5 + SLACK, err


def test_a_retimed_tables_duty_cycle_is_the_tables():
    """``plan --time optimal -f cam`` on the Adept cycle is re-timed (the quintics' jerk at the points misses the
    law's): the table's ``cycle_s`` is 2·(its duration + the 0.1 s dwell) and its picks/min 60 / that, below the
    trajectory's by the stretch; the summary line says both."""
    import json
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        res = run("plan", *ADEPT, "--time", "optimal", "-f", "cam", "-o", f"{tmp}/t.cam.csv", "--json")
    assert res.exit_code == 0, res.stderr
    doc = json.loads(res.stdout)
    info = doc["table"]
    assert info["stretch"] > 1.0
    assert info["cycle_s"] == pytest.approx(2 * (info["duration_s"] + 0.1), rel=1e-12)
    assert info["picks_per_minute"] == pytest.approx(60.0 / info["cycle_s"], rel=1e-12)
    assert info["picks_per_minute"] < doc["picks_per_minute"]
    assert f"the table's cycle {info['cycle_s']:.4f} s, {info['picks_per_minute']:.1f} picks/min" in res.stderr
