"""A line of any shipped robot, and a mixed line, against independent computations in this file:

* every pick meets its part: the tool's motion as written (the samples the run's MCAP file is made from,
  :func:`~pickplace_cli.line.trajectories.robot_samples`) extrapolated from inside the pick leg to the meeting time
  by a quadratic through three samples 1 µs apart is at the part's position x0 + v_belt·(t − t_detect) within 1e-6 m
  and moves with the belt's velocity within 1e-6 m/s; through the grip it stays on the part within 1e-6 m;
* each robot's RMS torque over the run (its motors', or its joints' for a robot without drives) agrees within 0.5 %
  with Simpson's rule on a 0.5 ms grid of the torque written to the run's MCAP file, decoded by mcap_ros2.
"""

from __future__ import annotations

import io

import numpy as np
import pytest

from pickplace_cli.line.engine import LineEngine
from pickplace_cli.line.parts import generate
from pickplace_cli.line.spec import parse_line
from pickplace_cli.model.profile import load_profile

BELT = "belt: {speed: 0.3, width: 0.2, direction: +y}\n"
#: one robot of each shipped kind, placed where its workspace covers its window (the SCARA beside the belt, 0.15 m
#: above it: its z stroke is 0.2 m; the Deltas 0.8 m above it; the gantry 0.5 m above it)
ROBOTS = {
    "scara-600": """\
  - name: s1
    profile: scara-600
    base: [0.0, 0.35, 0.15]
    window: [-0.1, 0.1]
    place: {points: [[0.3, 0.2, 0.0], [-0.3, 0.2, 0.0]]}
""",
    "delta-4axis": """\
  - name: d4
    profile: delta-4axis
    base: [0.6, 0.0, 0.8]
    window: [0.4, 0.8]
    place: {tray: {origin: [0.55, 0.35, 0.0], rows: 2, columns: 2, pitch: [0.05, 0.05]}}
""",
    "delta-su2018": """\
  - name: d3
    profile: delta-su2018
    base: [0.6, 0.0, 0.8]
    window: [0.4, 0.8]
    place: {points: [[0.6, 0.35, 0.0]]}
    time: auto
""",
    "gantry": """\
  - name: g1
    profile: gantry
    base: [1.4, 0.0, 0.5]
    window: [1.2, 1.6]
    place: {belt: {point: [1.5, 0.4, 0.0], velocity: [0.2, 0.0]}}
""",
}
PARTS = "parts:\n  generate: {{rate: {rate}, count: {count}, seed: 3, detect_at: -0.6}}\n  height: 0.01\n"
#: a SCARA, a 4-axis Delta and a gantry on one belt, each with its own rule; the gantry gets what the others leave
MIXED = BELT + "robots:\n" + ROBOTS["scara-600"] + ROBOTS["delta-4axis"].replace(
    "rows: 2", "rows: 2}}\n    time: 0.45\n    #").replace("#, columns", "# columns") + ROBOTS["gantry"] + PARTS.format(
    rate=4.0, count=16)


def _run(text: str):
    line = parse_line(text, "l.yaml")
    eng = LineEngine(line, {r.name: load_profile(r.profile) for r in line.robots})
    eng.check_speed()
    for d in generate(line.parts.generate, line.belt.width):
        eng.offer(d)
    return line, eng, eng.finish()


@pytest.fixture(scope="module", params=list(ROBOTS) + ["mixed"])
def run(request):
    if request.param == "mixed":
        return _run(MIXED)
    return _run(BELT + "robots:\n" + ROBOTS[request.param] + PARTS.format(rate=1.5, count=6))


def test_every_robot_picks(run):
    line, eng, s = run
    assert all(r.picks > 0 for r in s.robots), [(r.name, r.picks) for r in s.robots]
    assert not any(res.code == 1 for res in eng.results)


def test_every_pick_meets_its_part_in_the_written_motion(run):
    from pickplace_cli.line.trajectories import robot_samples

    line, eng, _ = run
    runs = {r.robot.name: r for r in eng.runs}
    v_belt = np.array([line.belt.speed, 0.0, 0.0])  # line frame: along, across, height
    h = 1e-6  # s: the quadratic's error 11/6·h²·(jerk difference, < 1e5 m/s³) < 2e-7 m/s; round-off ~1e-9 m/s
    checked = 0
    for res in eng.results:
        if res.cycle is None:
            continue
        d, c = res.detection, res.cycle
        x0 = np.array([d.along, d.across, line.parts.height])

        def gap(t):  # the written tool position minus the part's, line frame [m]
            tool = robot_samples(runs[res.robot], np.atleast_1d(t)).tool
            return tool - (x0 + np.multiply.outer(np.atleast_1d(t) - d.t, v_belt))

        e = gap(c.t_meet - h * np.array([3.0, 2.0, 1.0]))  # inside the pick leg, which ends at t_meet
        at_meet = e[0] - 3 * e[1] + 3 * e[2]
        rate = (1.5 * e[0] - 4 * e[1] + 2.5 * e[2]) / h
        assert np.abs(at_meet).max() < 1e-6, (res.robot, at_meet)
        assert np.abs(rate).max() < 1e-6, (res.robot, rate)
        track = next(leg for leg in c.legs if leg.kind == "track")
        assert np.abs(gap(np.linspace(track.t0, track.t1 - 1e-9, 7))).max() < 1e-6
        checked += 1
    assert checked >= 2


def _decoded(eng, s, rate):
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    from pickplace_cli.line.trajectories import robot_samples, sample_times, write_line_mcap

    t = sample_times(s.t_begin, s.t_end, rate)
    buf = io.BytesIO()
    write_line_mcap([robot_samples(r, t) for r in eng.runs], s.t_begin, buf)
    buf.seek(0)
    series: dict = {}
    for _, channel, _, msg in make_reader(buf, decoder_factories=[DecoderFactory()]).iter_decoded_messages():
        stamp = msg.header.stamp
        if hasattr(msg, "effort"):
            series.setdefault(channel.topic, []).append((stamp.sec * 10**9 + stamp.nanosec, list(msg.effort)))
    return series


def test_rms_over_the_run_against_the_written_torque(run):
    from scipy.integrate import simpson

    _, eng, s = run
    series = _decoded(eng, s, 2000.0)
    for r, robot_run in zip(s.robots, eng.runs):
        topic = "motor_states" if robot_run.robot.has_drives else "joint_states"
        rows = series[f"/{r.name}/{topic}"]
        ns = np.array([x[0] for x in rows], dtype=np.int64)
        tt = (ns - ns[0]) * 1e-9
        torque = np.array([x[1] for x in rows])
        rms = np.sqrt(simpson(torque**2, x=tt, axis=0) / (tt[-1] - tt[0]))
        assert tt[-1] - tt[0] == pytest.approx(s.span, abs=2e-9)
        assert np.allclose(r.rms, rms, rtol=5e-3, atol=1e-9), (r.name, r.rms, rms)


def test_gripper_times_lengthen_the_grip_and_the_release():
    """``gripper: {close, open}``: the tracking lasts the dwell + close and the wait at the place the dwell + open
    (1e-12 s: sums of the same floats); the written tool stays on the part until the grip is done and the place move
    starts where the part is then, x0 + v_belt·(t_meet + dwell + close − t_detect) (1e-6 m, as the meeting)."""
    from pickplace_cli.line.trajectories import robot_samples

    close, opened = 0.05, 0.08
    robot = ROBOTS["delta-su2018"].replace("    time: auto\n", f"    time: auto\n    gripper: {{close: {close}, "
                                                                 f"open: {opened}}}\n")
    line, eng, _ = _run(BELT + "robots:\n" + robot + PARTS.format(rate=1.5, count=6))
    dwell = load_profile("delta-su2018").planning.dwell
    v_belt = np.array([line.belt.speed, 0.0, 0.0])
    picked = [res for res in eng.results if res.cycle is not None]
    assert len(picked) >= 3
    for res in picked:
        d, c = res.detection, res.cycle
        legs = {leg.kind: leg for leg in c.legs}
        assert legs["track"].duration == pytest.approx(dwell + close, abs=1e-12)
        assert legs["release"].duration == pytest.approx(dwell + opened, abs=1e-12)
        assert c.t_free - c.t_start == pytest.approx(legs["pick"].duration + legs["place"].duration + 2 * dwell + close
                                                     + opened, abs=1e-9)
        t_leave = c.t_meet + dwell + close
        assert legs["place"].t0 == pytest.approx(t_leave, abs=1e-9)
        x0 = np.array([d.along, d.across, line.parts.height])
        t = np.array([t_leave - 1e-6, t_leave])  # the end of the tracking, and the place move's first sample
        tool = robot_samples(eng.runs[0], t).tool
        part = x0 + np.multiply.outer(t - d.t, v_belt)
        assert np.abs(tool - part).max() < 1e-6
