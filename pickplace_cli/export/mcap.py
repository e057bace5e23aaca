"""MCAP export: the sampled trajectory for ROS 2 tools (``ros2`` flavour) or Foxglove (``foxglove`` flavour).

Input is duck-typed (a :class:`~pickplace_cli.planner.Plan` or a batch/round-trip timeline): ``t`` (N,) s;
``p, v, a, j`` (N, 3) in m, m/s, m/s², m/s³; ``joint`` a :class:`~pickplace_cli.model.trajectory.JointTrajectory`;
optional ``move`` (N,) int = the move number of each sample (absent or None: one move); each run of
equal numbers is one move. ``t`` must not decrease.

Time base. Every message's log time (and the header stamp of every per-sample message) is
``EPOCH_NS + round(t · 1e9)`` ns: the sample time of the trajectory plus a fixed, documented epoch offset
(2024-01-01T00:00:00Z), never the wall clock, so the same plan always gives the same bytes. A
``/joint_trajectory`` message is a command for ros2_control's JointTrajectoryController: its header stamp is 0
("start on receipt"; any other stamp in the past is refused) and its points carry no effort (refused by a position
or velocity controller); its log time is the move's start, its points' ``time_from_start`` the time since then.

``ros2`` flavour (profile ``ros2``, every channel ``cdr`` with a ``ros2msg`` schema holding the full
message definition, dependencies included; no JSON channel, which ROS 2 tools reject): ``/joint_trajectory``
(trajectory_msgs/JointTrajectory, one per move), ``/joint_states`` and, with drives, ``/motor_states``
(sensor_msgs/JointState per sample), ``/tool_pose``, ``/tool_twist``, ``/tool_accel`` and ``/tool_jerk``
(geometry_msgs per sample; the turn of a rotary fourth axis about z in the pose and the angular parts). The
manual's Outputs page lists every field.

``foxglove`` flavour (no profile; every channel ``json`` with a ``jsonschema`` schema): ``/tool_pose``
(``foxglove.PoseInFrame`` per sample), ``/tool_path`` (``foxglove.PosesInFrame``, one per move: the whole
path), ``/joint_states`` (``pickplace.JointState``: name, position, velocity, acceleration, effort and,
with drives, motor_speed, motor_torque) and ``/tool_motion`` (``pickplace.ToolMotion``: velocity,
acceleration, jerk), each with a ``timestamp`` {sec, nsec}.

Both flavours carry a metadata record ``pickplace`` (epoch offset, frame, units). Determinism: header
library ``pickplace`` (no version), no compression unless asked (``zstd``), chunk size fixed
(``CHUNK_SIZE``), channels and schemas registered in a fixed order, CRCs on. The writer never seeks: it
counts the bytes it wrote for MCAP's offsets, so a pipe (``-o -``) gets the same bytes as a file.
"""

from __future__ import annotations

import io
import json
from enum import Enum
from typing import IO, Any, Callable

import numpy as np

from ..model.errors import ExportError

#: fixed epoch offset added to every message time: 2024-01-01T00:00:00Z in ns since the Unix epoch
EPOCH_NS = 1_704_067_200 * 1_000_000_000
#: MCAP header ``library`` field: a name without a version, so tool upgrades do not change the bytes
LIBRARY = "pickplace"
#: chunk size of the MCAP writer [bytes] (fixed: chunk boundaries are part of the bytes)
CHUNK_SIZE = 1024 * 1024
#: frame of the tool pose: the robot's base frame
FRAME_ID = "base"


class McapFlavor(str, Enum):
    ros2 = "ros2"
    foxglove = "foxglove"


class McapCompression(str, Enum):
    none = "none"
    zstd = "zstd"


# ------------------------------------------------------------------------ ROS 2 message definitions
# The .msg texts of ROS 2 (Humble and later; comments removed). A schema is the main type's text, then
# each dependency after a line of 80 '=' and "MSG: pkg/Type", as rosbag2's MCAP storage writes them.

_MSG: dict[str, str] = {
    "builtin_interfaces/Time": "int32 sec\nuint32 nanosec\n",
    "builtin_interfaces/Duration": "int32 sec\nuint32 nanosec\n",
    "std_msgs/Header": "builtin_interfaces/Time stamp\nstring frame_id\n",
    "geometry_msgs/Point": "float64 x\nfloat64 y\nfloat64 z\n",
    "geometry_msgs/Vector3": "float64 x\nfloat64 y\nfloat64 z\n",
    "geometry_msgs/Quaternion": "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n",
    "geometry_msgs/Pose": "geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n",
    "geometry_msgs/PoseStamped": "std_msgs/Header header\ngeometry_msgs/Pose pose\n",
    "geometry_msgs/Twist": "geometry_msgs/Vector3 linear\ngeometry_msgs/Vector3 angular\n",
    "geometry_msgs/TwistStamped": "std_msgs/Header header\ngeometry_msgs/Twist twist\n",
    "geometry_msgs/Accel": "geometry_msgs/Vector3 linear\ngeometry_msgs/Vector3 angular\n",
    "geometry_msgs/AccelStamped": "std_msgs/Header header\ngeometry_msgs/Accel accel\n",
    "geometry_msgs/Vector3Stamped": "std_msgs/Header header\ngeometry_msgs/Vector3 vector\n",
    "sensor_msgs/JointState": (
        "std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\nfloat64[] effort\n"
    ),
    "trajectory_msgs/JointTrajectoryPoint": (
        "float64[] positions\nfloat64[] velocities\nfloat64[] accelerations\nfloat64[] effort\n"
        "builtin_interfaces/Duration time_from_start\n"
    ),
    "trajectory_msgs/JointTrajectory": (
        "std_msgs/Header header\nstring[] joint_names\ntrajectory_msgs/JointTrajectoryPoint[] points\n"
    ),
}
_SEPARATOR = "=" * 80


def ros2_msgdef(datatype: str) -> str:
    """Full ROS 2 message definition of ``datatype`` ("pkg/msg/Type"), dependencies appended depth-first."""
    pkg, _, name = datatype.partition("/msg/")
    order: list[str] = []

    def visit(short: str) -> None:
        for line in _MSG[short].splitlines():
            ftype = line.split()[0].rstrip("[]")
            if "/" in ftype and ftype not in order:
                order.append(ftype)
                visit(ftype)

    root = f"{pkg}/{name}"
    visit(root)
    parts = [_MSG[root]] + [f"{_SEPARATOR}\nMSG: {dep}\n{_MSG[dep]}" for dep in order]
    return "".join(parts)


# ------------------------------------------------------------------------------ Foxglove JSON schemas

_TIME_SCHEMA = {
    "type": "object",
    "title": "time",
    "properties": {
        "sec": {"type": "integer", "minimum": 0},
        "nsec": {"type": "integer", "minimum": 0, "maximum": 999999999},
    },
}


def _vec_schema(title: str, description: str, unit: str) -> dict:
    return {
        "title": title,
        "description": description,
        "type": "object",
        "properties": {c: {"type": "number", "description": f"{c} [{unit}]"} for c in "xyz"},
    }


_POSE_SCHEMA = {
    "title": "foxglove.Pose",
    "description": "A position and orientation for an object or reference frame in 3D space",
    "type": "object",
    "properties": {
        "position": _vec_schema("foxglove.Vector3", "Point denoting position in 3D space", "m"),
        "orientation": {
            "title": "foxglove.Quaternion",
            "description": "Quaternion denoting orientation in 3D space",
            "type": "object",
            "properties": {c: {"type": "number", "description": f"{c} value"} for c in "xyzw"},
        },
    },
}

#: Foxglove's JSON schemas (https://github.com/foxglove/schemas, schemas/jsonschema) for the types used here
FOXGLOVE_SCHEMAS: dict[str, dict] = {
    "foxglove.PoseInFrame": {
        "title": "foxglove.PoseInFrame",
        "description": "A timestamped pose for an object or reference frame in 3D space",
        "type": "object",
        "properties": {
            "timestamp": {**_TIME_SCHEMA, "description": "Timestamp of pose"},
            "frame_id": {"type": "string", "description": "Frame of reference for pose position and orientation"},
            "pose": _POSE_SCHEMA,
        },
    },
    "foxglove.PosesInFrame": {
        "title": "foxglove.PosesInFrame",
        "description": "An array of timestamped poses for an object or reference frame in 3D space",
        "type": "object",
        "properties": {
            "timestamp": {**_TIME_SCHEMA, "description": "Timestamp of pose"},
            "frame_id": {"type": "string", "description": "Frame of reference for pose position and orientation"},
            "poses": {"type": "array", "items": _POSE_SCHEMA, "description": "Poses in 3D space"},
        },
    },
}


def _num_array(description: str) -> dict:
    return {"type": "array", "items": {"type": "number"}, "description": description}


#: plain JSON schemas of pickplace's own JSON channels (units in the descriptions)
PICKPLACE_SCHEMAS: dict[str, dict] = {
    "pickplace.JointState": {
        "title": "pickplace.JointState",
        "description": "Joint state of one sample (SI units; per joint in the order of 'name')",
        "type": "object",
        "properties": {
            "timestamp": {**_TIME_SCHEMA, "description": "Sample time + the epoch offset"},
            "name": {"type": "array", "items": {"type": "string"}, "description": "joint names"},
            "position": _num_array("q [rad] (revolute) or [m] (prismatic)"),
            "velocity": _num_array("q' [rad/s] or [m/s]"),
            "acceleration": _num_array("q'' [rad/s^2] or [m/s^2]"),
            "effort": _num_array("joint torque [N*m] or force [N], inverse dynamics with gravity"),
            "motor_speed": _num_array("motor speed N*q' [rad/s] (only with drives)"),
            "motor_torque": _num_array("motor torque [N*m] (only with drives)"),
        },
        "required": ["timestamp", "name", "position", "velocity", "acceleration", "effort"],
    },
    "pickplace.ToolMotion": {
        "title": "pickplace.ToolMotion",
        "description": "Tool velocity, acceleration and jerk of one sample in the base frame",
        "type": "object",
        "properties": {
            "timestamp": {**_TIME_SCHEMA, "description": "Sample time + the epoch offset"},
            "frame_id": {"type": "string"},
            "velocity": _vec_schema("pickplace.Vector3", "tool velocity", "m/s"),
            "acceleration": _vec_schema("pickplace.Vector3", "tool acceleration", "m/s^2"),
            "jerk": _vec_schema("pickplace.Vector3", "tool jerk", "m/s^3"),
        },
        "required": ["timestamp", "frame_id", "velocity", "acceleration", "jerk"],
    },
}


# ------------------------------------------------------------------------------------------ helpers


class _CountingStream:
    """Write-only wrapper that answers ``tell()`` by counting bytes: MCAP's writer needs offsets, pipes
    cannot ``tell()``. The writer never seeks, so counting is exact and file and pipe get the same bytes."""

    def __init__(self, stream: IO[bytes]) -> None:
        self._stream = stream
        self._count = 0

    def write(self, data: bytes) -> int:
        self._stream.write(data)
        self._count += len(data)
        return len(data)

    def tell(self) -> int:
        return self._count

    def flush(self) -> None:
        self._stream.flush()


def _binary(stream: IO) -> IO[bytes]:
    if isinstance(stream, io.TextIOBase):
        buf = getattr(stream, "buffer", None)
        if buf is None:
            raise ExportError("output: MCAP is binary; the stream is text-only (use a binary file or stdout)")
        stream.flush()
        return buf
    return stream


def log_times_ns(t: np.ndarray, epoch_ns: int = EPOCH_NS) -> np.ndarray:
    """Message times [ns]: ``epoch_ns + round(t · 1e9)`` (int64)."""
    return epoch_ns + np.rint(np.asarray(t, dtype=float) * 1e9).astype(np.int64)


def move_slices(samples) -> list[slice]:
    """Sample ranges of each move (consecutive samples with the same ``move`` index; one move if absent)."""
    n = len(samples.t)
    move = getattr(samples, "move", None)
    if move is None:
        return [slice(0, n)]
    move = np.asarray(move)
    if move.shape != (n,):
        raise ExportError(f"move: shape {move.shape} must be ({n},), one move index per sample")
    cuts = np.flatnonzero(np.diff(move) != 0) + 1
    bounds = [0, *cuts.tolist(), n]
    return [slice(a, b) for a, b in zip(bounds[:-1], bounds[1:])]


def _check(samples) -> None:
    t = np.asarray(samples.t, dtype=float)
    if t.ndim != 1 or len(t) == 0:
        raise ExportError(f"t: shape {t.shape}: need at least one sample time in a 1-D array (s)")
    for name in ("p", "v", "a", "j"):
        arr = np.asarray(getattr(samples, name))
        if arr.shape != (len(t), 3):
            raise ExportError(f"{name}: shape {arr.shape} must be ({len(t)}, 3)")
    jt = samples.joint
    arrays = [("t", t), ("p", samples.p), ("v", samples.v), ("a", samples.a), ("j", samples.j)]
    arrays += [(name, getattr(jt, name)) for name in ("q", "qd", "qdd", "torque", "motor_speed", "motor_torque")]
    for name, arr in arrays:
        if arr is None:
            continue
        arr = np.asarray(arr, dtype=float)
        if arr.shape[0] != len(t):
            raise ExportError(f"{name}: {arr.shape[0]} samples, t has {len(t)}")
        bad = np.flatnonzero(~np.all(np.isfinite(arr.reshape(len(t), -1)), axis=1))
        if bad.size:
            raise ExportError(f"{name}: not finite at sample {int(bad[0])} (t = {t[bad[0]]:.9g} s): MCAP needs finite values")
    back = np.flatnonzero(np.diff(t) < 0)
    if back.size:
        i = int(back[0]) + 1
        raise ExportError(
            f"t = {t[i]:.9g} s at sample {i} is before t = {t[i - 1]:.9g} s: an MCAP timeline must not go back in time"
        )
    if t[0] < 0:
        raise ExportError(f"t = {t[0]:g} s at sample 0: times must be >= 0 s")


def _stamp(ns: int) -> dict:
    return {"sec": ns // 1_000_000_000, "nanosec": ns % 1_000_000_000}


def _vec(row: list[float]) -> dict:
    return {"x": row[0], "y": row[1], "z": row[2]}


_ZERO = {"x": 0.0, "y": 0.0, "z": 0.0}
_IDENTITY = {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}


def _metadata(flavor: str, epoch_ns: int, frame_id: str, samples) -> dict[str, str]:
    """Metadata record ``pickplace``: only what is needed to read the file (no paths, no versions)."""
    meta = {
        "flavor": flavor,
        "epoch_offset_ns": str(epoch_ns),
        "time": "log time = header stamp = epoch_offset_ns + round(t * 1e9) ns; t = time from the start of the trajectory"
                + ("; /joint_trajectory: header stamp 0 (start on receipt)" if flavor == "ros2" else ""),
        "frame_id": frame_id,
        "units": "SI: m, s, rad; joint effort N*m (revolute) or N (prismatic); motor torque N*m",
        "joints": ",".join(f"{n}[{u}]" for n, u in zip(samples.joint.names, samples.joint.units)),
        "moves": str(len(move_slices(samples))),
    }
    return meta


# ------------------------------------------------------------------------------------------ writers


def write_mcap(
    samples,
    stream: IO[bytes],
    flavor: McapFlavor | str = McapFlavor.ros2,
    compression: McapCompression | str | None = None,
    *,
    epoch_ns: int = EPOCH_NS,
    frame_id: str = FRAME_ID,
    drive=None,
) -> None:
    """Write ``samples`` (SI units, REP 103) as MCAP to the binary ``stream`` (a file or a pipe; nothing is seeked).

    Parameters
    ----------
    samples : Plan or Timeline
    stream : binary stream
    flavor : McapFlavor or str
        ``ros2`` (CDR channels for ROS 2 tools) or ``foxglove`` (JSON channels with Foxglove schemas).
    compression : McapCompression or str or None
        ``none`` (default) or ``zstd`` chunks.
    epoch_ns : int
        The time of t = 0 [ns since the Unix epoch]: every stamp is ``epoch_ns`` + t·1e9 [ns].
    frame_id : str
        The frame of the tool's pose.
    drive : DriveMap, optional
        The joints carry its names, and (ros2) ``/drive_states`` the drive positions and velocities in the drive's
        units (``d = sign·k·(q − offset)``).

    Raises
    ------
    ExportError
        An unknown flavour or compression, or samples that cannot be written.
    """
    from mcap.writer import CompressionType, Writer

    try:
        flavor = McapFlavor(flavor)
    except ValueError:
        raise ExportError(f"mcap flavor = {flavor!r}: must be one of {', '.join(f.value for f in McapFlavor)}") from None
    try:
        comp = McapCompression(compression or "none")
    except ValueError:
        raise ExportError(
            f"mcap compression = {compression!r}: must be one of {', '.join(c.value for c in McapCompression)}"
        ) from None
    _check(samples)
    out = _CountingStream(_binary(stream))
    writer = Writer(
        out,
        chunk_size=CHUNK_SIZE,
        compression=CompressionType.ZSTD if comp is McapCompression.zstd else CompressionType.NONE,
        enable_crcs=True,
    )
    writer.start(profile="ros2" if flavor is McapFlavor.ros2 else "", library=LIBRARY)
    if drive is not None:
        samples = _Named(samples, drive)
    _WRITERS[flavor](writer, samples, epoch_ns, frame_id)
    meta = _metadata(flavor.value, epoch_ns, frame_id, samples)
    if drive is not None:
        meta["drive"] = "; ".join(f"{d['name']}: {d['label']} = {d['sign']:+d} * {d['scale_per_joint_unit']:.17g} * "
                                  f"(q - {d['offset']:.17g})" for d in drive.describe())
    writer.add_metadata("pickplace", meta)
    writer.finish()
    out.flush()


class _Named:
    """``samples`` with the drive map's joint names (every other attribute the samples'); ``drive`` the map."""

    def __init__(self, samples, drive) -> None:
        from dataclasses import replace

        self._samples, self.drive = samples, drive
        self.joint = replace(samples.joint, names=tuple(drive.names))

    def __getattr__(self, name: str):
        return getattr(self._samples, name)


def mcap_bytes(samples, **kwargs: Any) -> bytes:
    """The MCAP file of ``samples`` as bytes (same arguments as :func:`write_mcap`)."""
    buf = io.BytesIO()
    write_mcap(samples, buf, **kwargs)
    return buf.getvalue()


class _Channels:
    """Registers schemas/channels in a fixed order and keeps a per-channel sequence counter."""

    def __init__(self, writer) -> None:
        self.writer = writer
        self.ids: dict[str, int] = {}
        self.seq: dict[str, int] = {}
        self.schemas: dict[str, int] = {}

    def add(self, topic: str, schema_name: str, schema_encoding: str, schema_data: bytes, encoding: str) -> None:
        sid = self.schemas.get(schema_name)
        if sid is None:
            sid = self.schemas[schema_name] = self.writer.register_schema(schema_name, schema_encoding, schema_data)
        self.ids[topic] = self.writer.register_channel(topic=topic, message_encoding=encoding, schema_id=sid)
        self.seq[topic] = 0

    def write(self, topic: str, ns: int, data: bytes) -> None:
        self.writer.add_message(self.ids[topic], log_time=ns, data=data, publish_time=ns, sequence=self.seq[topic])
        self.seq[topic] += 1


def _fixed_layout_cdr(
    encode: Callable[[Any], bytes], build: Callable[[int, int, list[float]], dict], ns: np.ndarray, values: np.ndarray
) -> list[bytes]:
    """CDR bytes of one message per row of ``values`` (N, M) at times ``ns`` (N,), for a message type whose
    layout is the same for every sample (fixed strings, fixed array lengths): ``build(sec, nanosec, floats)``
    makes the message, mcap_ros2's ``encode`` serialises it.

    Serialising 10⁵–10⁶ messages one by one costs ~20 µs each, so the layout is found once by probing
    ``encode`` with distinct sentinel values (the offset of every float64 and of the stamp), then all
    messages are filled in with numpy. The first and last message are re-encoded by ``encode`` and
    compared byte for byte; on any doubt (a sentinel not found exactly once, a mismatch) every message
    is encoded by ``encode``, so the result is always mcap_ros2's serialisation."""
    n, m = values.shape
    sec = ns // 1_000_000_000
    nsec = ns % 1_000_000_000

    def slow() -> list[bytes]:
        rows = values.tolist()
        return [encode(build(int(s), int(c), r)) for s, c, r in zip(sec.tolist(), nsec.tolist(), rows)]

    template = np.frombuffer(encode(build(0, 0, [0.0] * m)), dtype=np.uint8)
    sentinels = [1000.25 + 3.5 * k for k in range(m)]
    probe = encode(build(0x12345678, 0x0ABCDEF0, sentinels))
    if len(probe) != len(template):
        return slow()
    offsets = []
    for pattern in [np.float64(x).astype("<f8").tobytes() for x in sentinels] + [
        np.int32(0x12345678).astype("<i4").tobytes(),
        np.uint32(0x0ABCDEF0).astype("<u4").tobytes(),
    ]:
        at = probe.find(pattern)
        if at < 0 or probe.find(pattern, at + 1) >= 0:
            return slow()
        offsets.append(at)
    out = np.repeat(template[None, :], n, axis=0)
    for k in range(m):
        out[:, offsets[k] : offsets[k] + 8] = values[:, k].astype("<f8").view(np.uint8).reshape(n, 8)
    out[:, offsets[m] : offsets[m] + 4] = sec.astype("<i4").view(np.uint8).reshape(n, 4)
    out[:, offsets[m + 1] : offsets[m + 1] + 4] = nsec.astype("<u4").view(np.uint8).reshape(n, 4)
    blobs = [row.tobytes() for row in out]
    for i in {0, n - 1}:
        if blobs[i] != encode(build(int(sec[i]), int(nsec[i]), values[i].tolist())):
            return slow()
    return blobs


def _per_sample_channels(samples, names: list, motor_names: list, frame_id: str, drives: bool,
                         has_torque: bool) -> list[tuple[str, Callable[[int, int, list[float]], dict], np.ndarray]]:
    """The channels written once per sample: (topic, build(sec, nanosec, floats) → message dict, values (N, M))."""
    jt = samples.joint
    nj = len(names)

    def f64(x):
        return np.asarray(x, dtype=float)

    def hdr(s: int, c: int, frame: str) -> dict:
        return {"stamp": {"sec": s, "nanosec": c}, "frame_id": frame}

    per_sample: list[tuple[str, Callable[[int, int, list[float]], dict], np.ndarray]] = [
        (
            "/joint_states",
            lambda s, c, x: {
                "header": hdr(s, c, ""),
                "name": names,
                "position": x[:nj],
                "velocity": x[nj : 2 * nj],
                "effort": x[2 * nj :],
            },
            np.hstack([f64(jt.q), f64(jt.qd)] + ([f64(jt.torque)] if has_torque else [])),
        )
    ]
    if drives:
        per_sample.append(
            (
                "/motor_states",
                lambda s, c, x: {
                    "header": hdr(s, c, ""),
                    "name": motor_names,
                    "position": [],
                    "velocity": x[:nj],
                    "effort": x[nj:],
                },
                np.hstack([f64(jt.motor_speed), f64(jt.motor_torque)]),
            )
        )
    drive = getattr(samples, "drive", None)
    if drive is not None:  # what each drive is sent: position and velocity in its unit, under the joint's name
        per_sample.append(
            (
                "/drive_states",
                lambda s, c, x: {"header": hdr(s, c, ""), "name": names, "position": x[:nj], "velocity": x[nj:],
                                 "effort": []},
                np.hstack([drive.position(jt.q), drive.rate(jt.qd)]),
            )
        )
    per_sample += [
        (
            "/tool_pose",
            lambda s, c, x: {"header": hdr(s, c, frame_id), "pose": {"position": _vec(x), "orientation": _IDENTITY}},
            f64(samples.p),
        ),
        (
            "/tool_twist",
            lambda s, c, x: {"header": hdr(s, c, frame_id), "twist": {"linear": _vec(x), "angular": _ZERO}},
            f64(samples.v),
        ),
        (
            "/tool_accel",
            lambda s, c, x: {"header": hdr(s, c, frame_id), "accel": {"linear": _vec(x), "angular": _ZERO}},
            f64(samples.a),
        ),
        ("/tool_jerk", lambda s, c, x: {"header": hdr(s, c, frame_id), "vector": _vec(x)}, f64(samples.j)),
    ]
    turn = tool_turn(jt)
    if turn is not None:  # a rotary fourth axis: the tool's orientation about z, its angular velocity and acceleration
        per_sample[-4:-1] = [
            ("/tool_pose", lambda s, c, x: {"header": hdr(s, c, frame_id), "pose": {
                "position": _vec(x[:3]), "orientation": {"x": 0.0, "y": 0.0, "z": x[3], "w": x[4]}}},
             np.hstack([f64(samples.p), turn[0]])),
            ("/tool_twist", lambda s, c, x: {"header": hdr(s, c, frame_id), "twist": {
                "linear": _vec(x[:3]), "angular": {"x": 0.0, "y": 0.0, "z": x[3]}}}, np.hstack([f64(samples.v), turn[1]])),
            ("/tool_accel", lambda s, c, x: {"header": hdr(s, c, frame_id), "accel": {
                "linear": _vec(x[:3]), "angular": {"x": 0.0, "y": 0.0, "z": x[3]}}}, np.hstack([f64(samples.a), turn[2]])),
        ]
    return per_sample


def tool_turn(jt) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """A rotary fourth axis (``jt.angle_weights``): the tool's orientation about the base z axis as the quaternion's
    (z, w) = (sin θ/2, cos θ/2) (N, 2), its angular velocity θ̇ [rad/s] and acceleration θ̈ [rad/s²] (each (N, 1)),
    θ = q·w; None when the tool does not turn."""
    w = getattr(jt, "angle_weights", None)
    if w is None:
        return None
    w = np.asarray(w, dtype=float)
    theta = np.asarray(jt.q, dtype=float) @ w
    return (np.column_stack([np.sin(theta / 2), np.cos(theta / 2)]), (np.asarray(jt.qd, dtype=float) @ w)[:, None],
            (np.asarray(jt.qdd, dtype=float) @ w)[:, None])


def _write_ros2(writer, samples, epoch_ns: int, frame_id: str, fast: bool = True) -> None:
    from mcap_ros2._dynamic import serialize_dynamic  # encode-only; its public Writer stamps its version (pinned <0.7)

    jt = samples.joint
    nj = len(jt.names)
    drives = jt.motor_speed is not None and jt.motor_torque is not None
    topics = [
        ("/joint_trajectory", "trajectory_msgs/msg/JointTrajectory"),
        ("/joint_states", "sensor_msgs/msg/JointState"),
        *([("/motor_states", "sensor_msgs/msg/JointState")] if drives else []),
        *([("/drive_states", "sensor_msgs/msg/JointState")] if getattr(samples, "drive", None) is not None else []),
        ("/tool_pose", "geometry_msgs/msg/PoseStamped"),
        ("/tool_twist", "geometry_msgs/msg/TwistStamped"),
        ("/tool_accel", "geometry_msgs/msg/AccelStamped"),
        ("/tool_jerk", "geometry_msgs/msg/Vector3Stamped"),
    ]
    channels = _Channels(writer)
    encoders: dict[str, Callable[[Any], bytes]] = {}
    for topic, datatype in topics:
        text = ros2_msgdef(datatype)
        channels.add(topic, datatype, "ros2msg", text.encode(), "cdr")
        encoders[topic] = serialize_dynamic(datatype, text)[datatype]

    ns_arr = log_times_ns(samples.t, epoch_ns)
    ns = ns_arr.tolist()
    names = list(jt.names)
    motor_names = [f"motor{i + 1}" for i in range(nj)]
    has_torque = jt.torque is not None
    per_sample = _per_sample_channels(samples, names, motor_names, frame_id, drives, has_torque)
    blobs: list[tuple[str, list[bytes]]] = []
    for topic, build, values in per_sample:
        enc = encoders[topic]
        if fast:
            blobs.append((topic, _fixed_layout_cdr(enc, build, ns_arr, values)))
        else:
            sec, nsec = (ns_arr // 1_000_000_000).tolist(), (ns_arr % 1_000_000_000).tolist()
            blobs.append((topic, [enc(build(s, c, r)) for s, c, r in zip(sec, nsec, values.tolist())]))

    q, qd, qdd = jt.q.tolist(), jt.qd.tolist(), jt.qdd.tolist()
    for sl in move_slices(samples):
        t0 = ns[sl.start]
        # for ros2_control's JointTrajectoryController: stamp 0 = start on receipt (a past stamp is refused), no effort
        # (refused without an effort command interface; the torques are in /joint_states and /motor_states)
        points = [
            {
                "positions": q[i],
                "velocities": qd[i],
                "accelerations": qdd[i],
                "effort": [],
                "time_from_start": _stamp(ns[i] - t0),
            }
            for i in range(sl.start, sl.stop)
        ]
        traj = {"header": {"stamp": _stamp(0), "frame_id": ""}, "joint_names": names, "points": points}
        channels.write("/joint_trajectory", t0, encoders["/joint_trajectory"](traj))
        for i in range(sl.start, sl.stop):
            for topic, data in blobs:
                channels.write(topic, ns[i], data[i])


def _json(doc: dict) -> bytes:
    try:
        return json.dumps(doc, separators=(",", ":"), allow_nan=False).encode()
    except ValueError:
        raise ExportError("mcap foxglove: a value is not finite; JSON needs finite numbers") from None


def _write_foxglove(writer, samples, epoch_ns: int, frame_id: str) -> None:
    jt = samples.joint
    drives = jt.motor_speed is not None and jt.motor_torque is not None
    channels = _Channels(writer)
    for topic, name in (
        ("/tool_pose", "foxglove.PoseInFrame"),
        ("/tool_path", "foxglove.PosesInFrame"),
        ("/joint_states", "pickplace.JointState"),
        ("/tool_motion", "pickplace.ToolMotion"),
    ):
        schema = FOXGLOVE_SCHEMAS.get(name) or PICKPLACE_SCHEMAS[name]
        channels.add(topic, name, "jsonschema", json.dumps(schema, separators=(",", ":")).encode(), "json")

    ns = log_times_ns(samples.t, epoch_ns).tolist()
    names = list(jt.names)
    q, qd, qdd = jt.q.tolist(), jt.qd.tolist(), jt.qdd.tolist()
    torque = jt.torque.tolist() if jt.torque is not None else [[] for _ in ns]
    mspeed = jt.motor_speed.tolist() if drives else None
    mtorque = jt.motor_torque.tolist() if drives else None
    p, v, a, j = (np.asarray(x, dtype=float).tolist() for x in (samples.p, samples.v, samples.a, samples.j))
    turn = tool_turn(jt)
    quat = [{"x": 0.0, "y": 0.0, "z": z, "w": w} for z, w in turn[0].tolist()] if turn is not None else None

    def ts(n: int) -> dict:
        return {"sec": n // 1_000_000_000, "nsec": n % 1_000_000_000}

    for sl in move_slices(samples):
        t0 = ns[sl.start]
        poses = [{"position": _vec(p[i]), "orientation": _IDENTITY if quat is None else quat[i]}
                 for i in range(sl.start, sl.stop)]
        channels.write("/tool_path", t0, _json({"timestamp": ts(t0), "frame_id": frame_id, "poses": poses}))
        for i in range(sl.start, sl.stop):
            ti = ns[i]
            stamp = ts(ti)
            channels.write("/tool_pose", ti, _json({"timestamp": stamp, "frame_id": frame_id, "pose": poses[i - sl.start]}))
            state = {
                "timestamp": stamp,
                "name": names,
                "position": q[i],
                "velocity": qd[i],
                "acceleration": qdd[i],
                "effort": torque[i],
            }
            if drives:
                state["motor_speed"] = mspeed[i]
                state["motor_torque"] = mtorque[i]
            channels.write("/joint_states", ti, _json(state))
            motion = {
                "timestamp": stamp,
                "frame_id": frame_id,
                "velocity": _vec(v[i]),
                "acceleration": _vec(a[i]),
                "jerk": _vec(j[i]),
            }
            channels.write("/tool_motion", ti, _json(motion))


_WRITERS: dict[McapFlavor, Callable[..., None]] = {
    McapFlavor.ros2: _write_ros2,
    McapFlavor.foxglove: _write_foxglove,
}
