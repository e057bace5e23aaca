"""The reference for a line run's RMS motor torque: the run written to MCAP (1 kHz by default), read back by the
mcap library with the ROS 2 decoder (``mcap_ros2``, independent of the project's writer), and each motor's RMS
taken as the trapezoid integral of the written torque squared over the written span."""

from __future__ import annotations

import io

import numpy as np


def written_run(engine, summary, rate: float = 1000.0) -> dict:
    """{robot name: (t [s] from the first sample, motor torque (N, n) [N·m], joint positions (N, n))} as written to
    the run's MCAP file and decoded by ``mcap_ros2``."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    from pickplace_cli.line.trajectories import robot_samples, sample_times, write_line_mcap

    t = sample_times(summary.t_begin, summary.t_end, rate)
    buf = io.BytesIO()
    write_line_mcap([robot_samples(r, t) for r in engine.runs], summary.t_begin, buf)
    buf.seek(0)
    motor: dict = {}
    joints: dict = {}
    topics = [f"/{r.robot.name}/{k}" for r in engine.runs for k in ("motor_states", "joint_states")]
    reader = make_reader(buf, decoder_factories=[DecoderFactory()])
    for _, channel, _, msg in reader.iter_decoded_messages(topics=topics):
        stamp = msg.header.stamp
        row = (stamp.sec * 10**9 + stamp.nanosec, list(msg.position), list(msg.effort))
        name, kind = channel.topic.strip("/").split("/")
        (motor if kind == "motor_states" else joints).setdefault(name, []).append(row)
    out = {}
    for name, rows in motor.items():
        ns = np.array([x[0] for x in rows], dtype=np.int64)
        out[name] = ((ns - ns[0]) * 1e-9, np.array([x[2] for x in rows]), np.array([x[1] for x in joints[name]]))
    return out


def trapezoid_rms(t: np.ndarray, torque: np.ndarray) -> np.ndarray:
    """sqrt(∫ τ² dt / span) per motor by the trapezoid rule over the samples."""
    return np.sqrt(np.trapezoid(torque**2, t, axis=0) / (t[-1] - t[0]))
