"""Every robot's joint trajectory over a whole line run, sampled, and written as one MCAP file (one set of
topics per robot), so the run can be replayed in Foxglove or read by ROS 2 tools.

**Samples.** All robots share one clock: t = t_begin + k/rate (the run's span, the last sample at t_end). A sample
inside a leg is that leg's motion at τ = (t − t0)/T: the move's own path (the B-spline the method builds for the
leg's task, duration and shape: :meth:`~pickplace_cli.line.moves.Move.path`) or the straight tracking line, through
the robot's inverse kinematics and dynamics (:meth:`~pickplace_cli.limits.motion.MotionModel.parts`). Between legs
the robot rests where the last leg ended, holding the tool (velocity 0, torque = the holding torque); before its
first leg, at its home point.

**MCAP** (ROS 2 CDR, the message definitions of :mod:`~pickplace_cli.export.mcap`), per robot NAME:

* ``/NAME/joint_states`` — sensor_msgs/JointState: position q, velocity q̇, effort = joint torque (SI), the joints
  named as the profile's ``controller.joints`` names its drives (as ``plan``'s MCAP; without it q1 … qn);
* ``/NAME/motor_states`` — sensor_msgs/JointState (with drives): velocity = motor speed [rad/s], effort = motor
  torque [N·m];
* ``/NAME/tool_pose`` — geometry_msgs/PoseStamped in the frame ``line`` (along, across, height).

Message times are ``EPOCH_NS + round((t − t_begin)·1e9)``: the run starts at the fixed epoch of the project's MCAP
files (the line clock's t_begin is in the metadata record ``pickplace``), never the wall clock.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import IO

import numpy as np

from ..model.errors import ExportError

#: the most samples per robot a trajectory may have (100 minutes at 1 kHz)
MAX_SAMPLES = 6_000_000


@dataclass(frozen=True)
class RobotSamples:
    """One robot's samples: t [s, line clock] (N,), joint q, q̇, joint torque (N, n), motor speed and torque (N, n)
    or None (no drives), the tool in the line frame (N, 3) [m], and the joint names and units."""

    name: str
    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    torque: np.ndarray
    motor_speed: np.ndarray | None
    motor_torque: np.ndarray | None
    tool: np.ndarray
    joints: list
    units: list


def sample_times(t_begin: float, t_end: float, rate: float) -> np.ndarray:
    n = int(np.floor((t_end - t_begin) * rate + 1e-9)) + 1
    if n > MAX_SAMPLES:
        raise ExportError(f"rate = {rate:g} Hz over {t_end - t_begin:.6g} s: {n} samples per robot, more than "
                          f"{MAX_SAMPLES}; give a lower --rate")
    t = t_begin + np.arange(n) / rate
    return t if t[-1] >= t_end - 1e-12 else np.append(t, t_end)


def robot_samples(run, t: np.ndarray) -> RobotSamples:
    """The robot's trajectory (module docstring) at the times ``t`` (sorted) [s]."""
    r = run.robot
    model = r.model
    n = len(t)
    nj = len(r.joint_names)
    q, qd, tq = np.full((n, nj), np.nan), np.zeros((n, nj)), np.full((n, nj), np.nan)
    ms, mt = np.zeros((n, nj)), np.full((n, nj), np.nan)
    tool = np.full((n, 3), np.nan)
    legs = sorted(run.legs, key=lambda g: g.t0)
    filled = np.zeros(n, bool)
    for leg in legs:
        i0, i1 = np.searchsorted(t, [leg.t0, leg.t1], side="left")
        if i1 <= i0:
            continue
        T = leg.duration
        tau = np.clip((t[i0:i1] - leg.t0) / T, 0.0, 1.0)
        if leg.solved is not None:
            path = leg.solved.move.path(T)
            motion = tuple(path.all_orders(tau))
            angle = path.angle_orders(tau)
            if angle is not None:  # the tool's angle law, as the path carries it
                motion += (angle,)
        else:
            d = leg.velocity * T
            p = leg.point + np.multiply.outer(tau, d)
            z = np.zeros_like(p)
            motion = (p, np.broadcast_to(d, p.shape).copy(), z, z, leg.angle_orders(tau))
        parts = model.parts(tau, derivatives=False, motion=motion, singularity=False)
        q[i0:i1], qd[i0:i1] = parts.q, parts.qd1 / T
        tq[i0:i1] = parts.A / T**2 + parts.G
        if model.has_drives:
            ms[i0:i1] = model.gear * parts.qd1 / T
            mt[i0:i1] = parts.Am / T**2 + parts.Gm
        tool[i0:i1] = r.frame.to_line(parts.p)
        filled[i0:i1] = True
    # rests: hold where the last leg ended (its end state), or at home before the first leg
    hold = _hold_state(r, r.home)
    ends = {}
    for leg in legs:
        ends[leg.t1] = _hold_state(r, leg.end, leg.end_angle)
    k_leg = 0
    for i in np.flatnonzero(~filled):
        while k_leg < len(legs) and legs[k_leg].t1 <= t[i] + 1e-12:
            hold = ends[legs[k_leg].t1]
            k_leg += 1
        q[i], tq[i], mt[i], tool[i] = hold
        qd[i] = 0.0
        ms[i] = 0.0
    from ..export.drive import drive_map

    drive = drive_map(r.profile)  # the joints named as the drives name them (profile controller.joints), as plan's
    return RobotSamples(r.name, t, q, qd, tq, ms if model.has_drives else None, mt if model.has_drives else None,
                        tool, list(drive.names) if drive is not None else list(r.joint_names),
                        list(model.robot.joint_units))


def _hold_state(r, point, angle: float = 0.0) -> tuple:
    """(q, joint torque, motor torque, tool in the line frame) of the robot at rest at ``point`` with the tool at
    ``angle`` [rad]."""
    z = np.zeros((1, 3))
    theta = np.zeros((4, 1))
    theta[0, 0] = angle
    parts = r.model.parts(np.zeros(1), derivatives=False, motion=(np.asarray(point, float)[None], z, z, z, theta),
                          singularity=False)
    mt = parts.Gm[0] if r.model.has_drives else np.full(len(r.joint_names), np.nan)
    return parts.q[0], parts.G[0], mt, r.frame.to_line(point)


def write_line_mcap(samples: list[RobotSamples], t_begin: float, stream: IO[bytes], compression: str | None = None) -> None:
    """The robots' samples as one MCAP file (module docstring)."""
    from mcap.writer import CompressionType, Writer
    from mcap_ros2._dynamic import serialize_dynamic

    from ..export.mcap import CHUNK_SIZE, EPOCH_NS, LIBRARY, _Channels, _CountingStream, _binary, _fixed_layout_cdr
    from ..export.mcap import log_times_ns, ros2_msgdef

    out = _CountingStream(_binary(stream))
    writer = Writer(out, chunk_size=CHUNK_SIZE, enable_crcs=True,
                    compression=CompressionType.ZSTD if compression == "zstd" else CompressionType.NONE)
    writer.start(profile="ros2", library=LIBRARY)
    channels = _Channels(writer)
    enc = {}
    for dt in ("sensor_msgs/msg/JointState", "geometry_msgs/msg/PoseStamped"):
        enc[dt] = serialize_dynamic(dt, ros2_msgdef(dt))[dt]
    per_topic = []
    for s in samples:
        ok = [np.all(np.isfinite(a)) for a in (s.q, s.qd, s.torque, s.tool, s.motor_speed, s.motor_torque)
              if a is not None]
        if not all(ok):
            raise ExportError(f"robot {s.name}: a sample is not finite; MCAP needs finite values")
        ns = log_times_ns(s.t - t_begin, EPOCH_NS)
        names = list(s.joints)
        nj = len(names)
        topics = [(f"/{s.name}/joint_states", "sensor_msgs/msg/JointState",
                   lambda sec, nsec, x, names=names, nj=nj: {
                       "header": {"stamp": {"sec": sec, "nanosec": nsec}, "frame_id": ""}, "name": names,
                       "position": x[:nj], "velocity": x[nj:2 * nj], "effort": x[2 * nj:]},
                   np.hstack([s.q, s.qd, s.torque]))]
        if s.motor_torque is not None:
            motors = [f"motor{i + 1}" for i in range(nj)]
            topics.append((f"/{s.name}/motor_states", "sensor_msgs/msg/JointState",
                           lambda sec, nsec, x, motors=motors, nj=nj: {
                               "header": {"stamp": {"sec": sec, "nanosec": nsec}, "frame_id": ""}, "name": motors,
                               "position": [], "velocity": x[:nj], "effort": x[nj:]},
                           np.hstack([s.motor_speed, s.motor_torque])))
        topics.append((f"/{s.name}/tool_pose", "geometry_msgs/msg/PoseStamped",
                       lambda sec, nsec, x: {"header": {"stamp": {"sec": sec, "nanosec": nsec}, "frame_id": "line"},
                                             "pose": {"position": {"x": x[0], "y": x[1], "z": x[2]},
                                                      "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}}},
                       s.tool))
        for topic, dt, build, values in topics:
            channels.add(topic, dt, "ros2msg", ros2_msgdef(dt).encode(), "cdr")
            per_topic.append((topic, ns.tolist(), _fixed_layout_cdr(enc[dt], build, ns, np.asarray(values, float))))
    n = max((len(ns) for _, ns, _ in per_topic), default=0)
    for k in range(n):
        for topic, ns, blobs in per_topic:
            if k < len(ns):
                channels.write(topic, ns[k], blobs[k])
    writer.add_metadata("pickplace", {
        "flavor": "ros2", "epoch_offset_ns": str(EPOCH_NS), "t_begin_s": repr(float(t_begin)),
        "time": "log time = header stamp = epoch_offset_ns + round((t - t_begin_s) * 1e9) ns; t = the line clock",
        "frame_id": "line (along, across, height)", "robots": ",".join(s.name for s in samples),
        "units": "SI: m, s, rad; joint effort N*m (revolute) or N (prismatic); motor torque N*m",
    })
    writer.finish()
    out.flush()
