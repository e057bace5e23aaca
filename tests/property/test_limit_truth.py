"""The limit report tells the truth (issue 19): every reported peak equals an independent evaluation of the
tool's own written output, within 0.5 % in both directions (under-statement is a lie, over-statement a
false alarm), on random moves of every method on all three robots, at two output rates; and on the robots with a
rotary fourth axis (the 4-axis Delta, the SCARA's J4) with a random turn of the tool, so the fourth motor's peaks
(speed, torque, torque rate, RMS) are held to its written columns too.

The references are computed here from the CSV text the tool writes, at a fine rate (50 kHz) for the same
duration, never by the code under test:

* joint velocity / acceleration, motor speed, motor torque: the largest |value| of the written column
  (at 50 kHz a smooth peak is missed by < 1e-5 relative);
* motor torque rate: the finite difference of the written motor torque, on every sample interval that
  holds no jump of the path's jerk, and at each jump (and at the two ends) the one-sided values,
  extrapolated linearly from the two nearest differences on that side;
* RMS motor torque: the trapezoid rule over the written motor torque for the move, plus the two dwells
  holding the end torques, over move + dwell + return + dwell (the README's definition).
"""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from pickplace_cli.model.errors import PickplaceError
from pickplace_cli.export.csv import csv_header, csv_rows
from pickplace_cli.paths import Method
from pickplace_cli.planner import PlanOptions, plan
from pickplace_cli.model.profile import Profile, load_profile, resolve_profile_path
from pickplace_cli.model.task import Task

FINE = 50_000.0  # Hz: the reference rate
RATES = (500.0, 4000.0)  # Hz: the output rates whose reports are checked
TOL = 0.005

#: random moves per robot: (from, to) boxes [m] inside the reachable workspace, height range [m]
REGIONS = {
    "delta-su2018": (([-0.2, -0.2, -0.9], [0.2, 0.2, -0.75]), (0.01, 0.06)),
    "scara-600": (([0.28, -0.25, -0.15], [0.52, 0.25, -0.08]), (0.01, 0.05)),
    "gantry": (([-0.6, -0.6, -0.6], [0.6, 0.6, -0.3]), (0.01, 0.2)),
    "delta-4axis": (([-0.2, -0.2, -0.9], [0.2, 0.2, -0.75]), (0.01, 0.06)),
    "scara-600+turn": (([0.28, -0.25, -0.15], [0.52, 0.25, -0.08]), (0.01, 0.05)),
}
#: the robots planned with a random turn of the tool (angles in [−π, π], either window)
TURNING = ("delta-4axis", "scara-600+turn")


def _profile(name: str):
    """The shipped profile; the gantry's (which limits nothing) with joint limits and a belt/screw drive per
    axis added, so it has rows to check."""
    if name != "gantry":
        return load_profile(name.removesuffix("+turn"))
    d = yaml.safe_load(resolve_profile_path(name).read_text())
    for ax in d["robot"]["axes"]:
        ax["limits"] = {"velocity": 8.0, "acceleration": 150.0}
        ax["drive"] = {"gear_ratio": 314.159, "efficiency": 0.9, "rotor_inertia": 2e-5, "rated_torque": 1.5,
                       "peak_torque": 6.0, "max_speed": 628.3, "torque_rate": 600.0}
    return Profile.model_validate(d)


def _random_plan(name: str, method: Method, seed: int):
    """A plannable random move (retries on an unreachable path) → (profile, task, first plan); on a robot of
    ``TURNING`` with a random turn of the tool, over a random window."""
    prof = _profile(name)
    (lo, hi), (h0, h1) = REGIONS[name]
    rng = np.random.default_rng(seed)
    for _ in range(40):
        p0, p1 = rng.uniform(lo, hi), rng.uniform(lo, hi)
        th = rng.uniform(-np.pi, np.pi, 2) if name in TURNING else (None, None)
        during = str(rng.choice(["transfer", "whole"]))
        if np.linalg.norm(p1[:2] - p0[:2]) < 0.05:
            continue
        task = Task(p0, p1, float(rng.uniform(h0, h1)), 0.5, theta_from=th[0], theta_to=th[1])
        try:
            first = plan(task, prof, PlanOptions(method=method, fit=False, rate=RATES[0], turn_during=during))
        except PickplaceError:
            continue
        return prof, first.task, first
    pytest.skip(f"no plannable random move for {name} / {method.value}")


def _written(result) -> dict[str, np.ndarray]:
    """The columns of the CSV the tool writes for ``result``, parsed back from its text."""
    text = csv_header(result) + csv_rows(result)
    lines = [ln for ln in text.splitlines() if ln and not ln.startswith("#")]
    names = lines[0].split(",")
    data = np.loadtxt(lines[1:], delimiter=",")
    return {n.split("[")[0]: data[:, k] for k, n in enumerate(names)}


def _rate_reference(t: np.ndarray, y: np.ndarray, cuts: np.ndarray) -> float:
    """sup |dy/dt| from samples: finite differences on intervals without a jump, and one-sided values
    extrapolated to each jump (``cuts``, including both ends) from the nearest two differences per side."""
    d = np.diff(y) / np.diff(t)
    mid = 0.5 * (t[1:] + t[:-1])
    inner = cuts[(cuts > t[0]) & (cuts < t[-1])]
    clean = np.ones(len(d), bool)
    for c in inner:
        clean &= ~((t[:-1] < c) & (t[1:] > c))
    best = float(np.max(np.abs(d[clean])))
    for c in cuts:
        for side in (-1, 1):
            sel = np.flatnonzero(clean & ((mid < c) if side < 0 else (mid > c)))
            if len(sel) < 2:
                continue
            k = sel[-2:][::-1] if side < 0 else sel[:2]  # nearest first
            m1, m2, r1, r2 = mid[k[0]], mid[k[1]], d[k[0]], d[k[1]]
            best = max(best, abs(r1 + (r1 - r2) * (c - m1) / (m1 - m2)))
    return best


def _duty_rms(t: np.ndarray, y: np.ndarray, dwell: float) -> float:
    """RMS of a written motor-torque column over move, dwell, return (the move mirrored), dwell."""
    move = np.trapezoid(y**2, t)
    return float(np.sqrt((2 * move + dwell * (y[0] ** 2 + y[-1] ** 2)) / (2 * (t[-1] - t[0]) + 2 * dwell)))


CASES = [(name, m, seed) for name in REGIONS for m in Method for seed in ((1, 2) if name not in TURNING else (3,))]


@pytest.mark.parametrize("name,method,seed", CASES, ids=[f"{n}-{m.value}-{s}" for n, m, s in CASES])
def test_every_reported_peak_matches_the_written_output(name, method, seed):
    prof, task, first = _random_plan(name, method, seed)
    T = first.duration.seconds
    during = first.parameters["turn"]["during"] if "turn" in first.parameters else "transfer"
    fine = plan(task, prof, PlanOptions(method=method, fit=False, time=T, rate=FINE, turn="as-given",
                                        turn_during=during))
    assert fine.duration.seconds == pytest.approx(T, rel=1e-12)
    cols = _written(fine)
    t = cols["t"]
    path = fine.cartesian.path
    cuts = np.unique(np.concatenate([[0.0, 1.0], path.jump_points])) * T
    dwell = prof.planning.dwell
    joints = list(fine.joint.names)
    ref: dict[tuple[str, str], float] = {}
    for k, joint in enumerate(joints, start=1):
        ref[(joint, "velocity")] = np.max(np.abs(cols[f"qd{k}"]))
        ref[(joint, "acceleration")] = np.max(np.abs(cols[f"qdd{k}"]))
        if f"motor_torque{k}" in cols:
            mt = cols[f"motor_torque{k}"]
            ref[(joint, "motor speed")] = np.max(np.abs(cols[f"motor_speed{k}"]))
            ref[(joint, "motor torque")] = np.max(np.abs(mt))
            ref[(joint, "motor torque rate")] = _rate_reference(t, mt, cuts)
            ref[(joint, "rms motor torque")] = _duty_rms(t, mt, dwell)
    checked = 0
    for rate in RATES:
        result = first if rate == RATES[0] else plan(task, prof, PlanOptions(method=method, fit=False, time=T, rate=rate,
                                                                              turn="as-given", turn_during=during))
        for row in result.report.rows:
            key = (row.joint, row.quantity)
            if key not in ref:
                continue
            r = ref[key]
            assert abs(row.peak - r) <= TOL * r + 1e-9 * row.limit, (
                f"{name}/{method.value} @ {rate:g} Hz: {row.joint} {row.quantity} reported {row.peak:.6g}, "
                f"written output gives {r:.6g} ({(row.peak / r - 1) * 100:+.3f} %)"
            )
            checked += 1
    assert checked >= 2 * len(joints) * 2  # at least velocity and acceleration (or motor rows) per joint
    if name in TURNING:  # the fourth motor's rows were among them, and the tool did turn
        assert {"q4"} <= {r.joint for r in fine.report.rows if (r.joint, r.quantity) in ref}
        assert np.ptp(cols["q4"]) > 0
