"""``check`` on files whose samples step: an acceleration (torque) step, a position jump, a velocity step, a stop.

The reconstruction of a file (``curves/sampled.py``) splits its spline where it finds a step in the data and fits each
side apart; a jerk step leaves the acceleration (and the motor torque) continuous there, an acceleration step does not.
Checking both sides alone, ``check`` once called such a file "all limits hold". Now the change across each step over
its sample interval is a rate the torque-rate rows hold (``limits/samples.STEP_RATE``).

The file here: the Adept cycle's joint positions with a smooth-looking bump added to q1,
δ(t) = A·cos²(π(t − c)/(2w)) for |t − c| < w: δ and δ′ vanish at the bump's edges, δ″ steps there by A·π²/(2w²).
The expected torque step is derived independently: the rigid-body reference (``tests/reference/delta_rigid.py``, no
library code) gives M(q)·Δq̈ as the torque of the acceleration step alone at the edge's pose (τ is affine in q̈), on the
motor side /(N·η) + J·N·Δq̈; over one sample interval h the torque rate is then at least |Δτ|/h."""

from __future__ import annotations

import numpy as np
import pytest
from typer.testing import CliRunner

from pickplace_cli.cli import app
from pickplace_cli.model.profile import load_profile
from pickplace_cli.pipelines.check import check_file

runner = CliRunner()
ADEPT = ["--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8"]
#: the bump: amplitude [rad], centre and half-width [s]
A, C, W = 0.005, 0.080, 0.015


def _positions(tmp_path, rate: float):
    out = tmp_path / f"adept-{rate:g}.csv"
    r = runner.invoke(app, ["plan", *ADEPT, "--rate", str(rate), "--columns", "t,q1,q2,q3", "-q", "-o", str(out)])
    assert r.exit_code == 0, r.output
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    return out, data


def _bumped(tmp_path, data: np.ndarray, rate: float):
    d = data.copy()
    x = (d[:, 0] - C) / W
    inside = np.abs(x) < 1
    d[inside, 1] += A * np.cos(x[inside] * np.pi / 2) ** 2
    out = tmp_path / f"bumped-{rate:g}.csv"
    np.savetxt(out, d, delimiter=",", header="t[s],q1[rad],q2[rad],q3[rad]", comments="", fmt="%.12g")
    return out


def _reference_step(prof, data: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(the motor torque step [N·m] per joint at each edge (2, 3), the edges' times [s])."""
    from tests.reference import delta_rigid as ref
    from tests.unit.test_delta_rigid_reference import drives, reference_params

    edges = np.array([C - W, C + W])
    q = np.column_stack([np.interp(edges, data[:, 0], data[:, 1 + j]) for j in range(3)])
    dqdd = np.zeros((2, 3))
    dqdd[:, 0] = A * np.pi**2 / (2 * W**2)  # δ″ just inside the bump, 0 outside
    P = reference_params(prof)
    N, eta, J = drives(prof)[:3]
    zero = np.zeros_like(q)
    joint = ref.reference_torques(P, q, zero, dqdd) - ref.reference_torques(P, q, zero, zero)  # M(q)·Δq̈
    return joint / (N * eta) + J * N * dqdd, edges


@pytest.mark.parametrize("rate", [1000.0, 20000.0])
def test_an_acceleration_step_is_an_exceeded_torque_rate(tmp_path, rate):
    prof = load_profile("delta-su2018")
    plain, data = _positions(tmp_path, rate)
    before = check_file(str(plain), prof)[0].report
    assert before.ok  # the planned file itself is accepted
    step, edges = _reference_step(prof, data)
    h = 1.0 / rate
    bound = np.abs(step) / h  # the least torque rate that makes the step within one sample interval
    assert bound[:, 0].max() > 418  # q1's step is beyond its limit (418 N·m/s) however the samples fall
    rep = check_file(str(_bumped(tmp_path, data, rate)), prof)[0].report
    assert not rep.ok
    row = next(r for r in rep.rows if r.joint == "q1" and r.quantity == "motor torque rate")
    assert not row.ok and row.peak - (row.accuracy or 0.0) > row.limit
    # the check's rate at the step is the reconstruction's step over h: within 10 % of the reference's
    assert row.peak == pytest.approx(bound[:, 0].max(), rel=0.1)
    assert min(abs(row.t_peak - e) for e in edges) <= 1.5 * h
    # the other joints move with q1 through the parallel arms: their steps as the reference gives them
    for j, name in ((1, "q2"), (2, "q3")):
        r = next(x for x in rep.rows if x.joint == name and x.quantity == "motor torque rate")
        assert r.peak >= 0.9 * bound[:, j].max()


def test_a_jerk_step_alone_is_not_a_rate_step(tmp_path):
    """A move whose jerk steps (Lamé curve and PH corners: their jerk is discontinuous, their acceleration not):
    check's torque-rate rows read what plan's continuous check found (within its accuracy and 2 %), not a step."""
    prof = load_profile("delta-su2018")
    for method in ("lame", "ph"):
        out = tmp_path / f"{method}.csv"
        rep_json = tmp_path / f"{method}.json"
        r = runner.invoke(app, ["plan", *ADEPT, "-m", method, "--columns", "t,q1,q2,q3", "-q", "-o", str(out),
                                "--report", str(rep_json)])
        assert r.exit_code == 0, r.output
        import json

        planned = {(x["joint"], x["quantity"]): x["peak"] for x in json.loads(rep_json.read_text())["limits"]["rows"]}
        rep = check_file(str(out), prof)[0].report
        assert rep.ok, [(x.joint, x.quantity, x.peak) for x in rep.violations]
        for x in rep.rows:
            if x.quantity == "motor torque rate":
                assert x.peak <= planned[(x.joint, x.quantity)] * 1.02 + (x.accuracy or 0.0), (method, x.joint)


def _edited(tmp_path, name: str, data: np.ndarray, column: int, add) -> str:
    d = data.copy()
    d[:, column] += add(d[:, 0])
    out = tmp_path / f"{name}.csv"
    header = ",".join(["t[s]"] + [f"q{j}[rad]" for j in range(1, d.shape[1])])
    np.savetxt(out, d, delimiter=",", header=header, comments="", fmt="%.12g")
    return str(out)


@pytest.mark.parametrize("jump", [0.05, 0.002])
def test_a_position_jump_is_a_speed_and_a_torque_past_the_limits(tmp_path, jump):
    """q1 of the Adept cycle's 1 kHz positions jumps by ``jump`` [rad] between two samples: whatever the motion between
    them, q1 moves ``jump`` + its own motion within 1 ms (its speed reaches the secant: the mean value theorem) and,
    leaving and arriving at its own speed, accelerates with more than the rotor's torque allows."""
    from tests.unit.test_delta_rigid_reference import drives

    prof = load_profile("delta-su2018")
    _, data = _positions(tmp_path, 1000.0)
    path = _edited(tmp_path, "jump", data, 1, lambda t: np.where(t >= 0.0895, jump, 0.0))
    rep = check_file(path, prof)[0].report
    assert not rep.ok
    i = int(np.searchsorted(data[:, 0], 0.0895))
    secant = abs(data[i, 1] + jump - data[i - 1, 1]) / (data[i, 0] - data[i - 1, 0])
    N = drives(prof)[0][0]
    speed = next(r for r in rep.rows if r.joint == "q1" and r.quantity == "motor speed")
    assert speed.peak >= N * secant * (1 - 1e-5)  # (less the rounding allowance: half the smallest step)
    assert (not speed.ok) == (N * secant > 628.3)  # 50 mrad: 1073 rad/s against 628.3; 2 mrad: within it
    torque = next(r for r in rep.rows if r.joint == "q1" and r.quantity == "motor torque")
    # the samples' second difference across the jump is q1's mean acceleration under a unit weight: the rotor
    # alone (J·N·q̈, the link adds to it on the diagonal) needs at least J·N·that
    J = drives(prof)[2][0]
    dd = abs(jump) / 1e-6 - 2e3  # (jump / h², less the move's own acceleration at most)
    assert torque.peak >= J * N * dd and not torque.ok


@pytest.mark.parametrize("dv", [0.5, 2.0])
def test_a_velocity_step_is_a_torque_rate_past_the_limit(tmp_path, dv):
    """q1 gains ``dv`` [rad/s] at t = 0.09 s (a kink in its positions): its acceleration's mean over the three samples
    around the kink is dv / h, over the next three 0 (the reference: the rigid-body model's diagonal inertia at the
    kink's pose, plus the rotor's); the torque changes by that inertia × dv / h within h at least."""
    from tests.reference import delta_rigid as ref
    from tests.unit.test_delta_rigid_reference import drives, reference_params

    prof = load_profile("delta-su2018")
    _, data = _positions(tmp_path, 1000.0)
    path = _edited(tmp_path, "kink", data, 1, lambda t: dv * np.maximum(t - 0.09, 0.0))
    rep = check_file(path, prof)[0].report
    row = next(r for r in rep.rows if r.joint == "q1" and r.quantity == "motor torque rate")
    assert not rep.ok and not row.ok
    q = np.array([[np.interp(0.09, data[:, 0], data[:, 1 + j]) for j in range(3)]])
    N, eta, J = (x[0] for x in drives(prof)[:3])
    P = reference_params(prof)
    e1 = np.array([[1.0, 0.0, 0.0]])
    m11 = (ref.reference_torques(P, q, 0 * q, e1) - ref.reference_torques(P, q, 0 * q, 0 * q))[0, 0]
    inertia = m11 / (N * eta) + J * N  # motor torque per rad/s² of q1 alone
    h = 1e-3
    assert row.peak >= J * N * dv / h**2  # the rotor alone: a bound whatever the link does
    # the samples' own bound (the change of two windows' mean torque over h) is about the full inertia's
    assert row.peak == pytest.approx(inertia * dv / h**2, rel=0.25)


def test_a_stop_inside_a_move_is_refused(tmp_path):
    """The robot halted for 20 ms at full speed and restarted (samples held, the rest shifted later): no motor can."""
    prof = load_profile("delta-su2018")
    _, data = _positions(tmp_path, 1000.0)
    i = int(np.searchsorted(data[:, 0], 0.09))
    held = np.repeat(data[i:i + 1, 1:], 20, axis=0)
    rows = np.vstack([data[:i, 1:], held, data[i:, 1:]])
    t = np.arange(len(rows)) * 1e-3
    out = tmp_path / "stop.csv"
    np.savetxt(out, np.column_stack([t, rows]), delimiter=",", header="t[s],q1[rad],q2[rad],q3[rad]", comments="",
               fmt="%.12g")
    rep = check_file(str(out), prof)[0].report
    torque = next(r for r in rep.rows if r.joint == "q1" and r.quantity == "motor torque")
    assert not rep.ok and not torque.ok
