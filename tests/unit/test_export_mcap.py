"""export/mcap.py: ROS 2 and Foxglove MCAP, read back by independent readers and compared with the CSV.

ROS 2 files are read with ``rosbags`` (its own MCAP reader, CDR deserialiser and .msg parser: nothing is
shared with ``mcap``/``mcap_ros2``, which wrote the file). Foxglove files are read with ``mcap``'s reader
and ``json``. Every value is compared with the default-dialect CSV of the same samples, parsed back with
the csv module.

Tolerances: the CSV prints ``%.12g`` (12 significant digits), so a CSV value differs from the double it
came from by at most 5e-12 relative; RTOL = 6e-12 leaves a margin for the decimal→binary rounding of
the parsed number. Times: MCAP stores integer ns (rounded), so |t_mcap − t| <= 0.5 ns, plus the CSV's
printing error of t (≤ 5e-12 · t): ATOL_T = 1e-9 s.
"""

from __future__ import annotations

import io
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from pickplace_cli.model.errors import ExportError
from pickplace_cli.export import atomic_output
from pickplace_cli.export import mcap as M
from pickplace_cli.export.mcap import EPOCH_NS, mcap_bytes, ros2_msgdef, write_mcap
from tests.golden.samples import csv_table, delta_batch, delta_plan, gantry_plan, read_mcap_json, read_ros2

RTOL = 6e-12
ATOL_T = 1e-9
ROS2_TOPICS = {
    "/joint_trajectory": "trajectory_msgs/msg/JointTrajectory",
    "/joint_states": "sensor_msgs/msg/JointState",
    "/motor_states": "sensor_msgs/msg/JointState",
    "/tool_pose": "geometry_msgs/msg/PoseStamped",
    "/tool_twist": "geometry_msgs/msg/TwistStamped",
    "/tool_accel": "geometry_msgs/msg/AccelStamped",
    "/tool_jerk": "geometry_msgs/msg/Vector3Stamped",
}


def close(actual, expected, rtol=RTOL):
    np.testing.assert_allclose(np.asarray(actual, float), np.asarray(expected, float), rtol=rtol, atol=0)


def write_file(tmp_path: Path, samples, name="plan.mcap", **kw) -> Path:
    path = tmp_path / name
    with open(path, "wb") as fh:
        write_mcap(samples, fh, **kw)
    return path


def stamp_s(stamp) -> float:
    return (stamp.sec * 1_000_000_000 + stamp.nanosec - EPOCH_NS) / 1e9


def check_ros2_against_csv(samples, msgs, drives: bool):
    col = csv_table(samples)
    n = len(col["t"])
    nj = len(samples.joint.names)
    J = lambda name: np.column_stack([col[f"{name}{k}"] for k in range(1, nj + 1)])  # noqa: E731

    for topic in ("/joint_states", "/tool_pose", "/tool_twist", "/tool_accel", "/tool_jerk") + (("/motor_states",) if drives else ()):
        assert len(msgs[topic]) == n, topic
        times = np.array([ns for ns, _ in msgs[topic]])
        np.testing.assert_allclose((times - EPOCH_NS) / 1e9, col["t"], rtol=0, atol=ATOL_T)
        np.testing.assert_allclose([stamp_s(m.header.stamp) for _, m in msgs[topic]], col["t"], rtol=0, atol=ATOL_T)
    js = [m for _, m in msgs["/joint_states"]]
    assert all(list(m.name) == list(samples.joint.names) for m in js)
    close([m.position for m in js], J("q"))
    close([m.velocity for m in js], J("qd"))
    close([m.effort for m in js], J("torque"))
    if drives:
        ms = [m for _, m in msgs["/motor_states"]]
        assert all(len(m.position) == 0 for m in ms)
        close([m.velocity for m in ms], J("motor_speed"))
        close([m.effort for m in ms], J("motor_torque"))
    else:
        assert "/motor_states" not in msgs
    xyz = lambda v: [v.x, v.y, v.z]  # noqa: E731
    C = lambda prefix: np.column_stack([col[f"{prefix}{c}"] for c in "xyz"])  # noqa: E731
    poses = [m for _, m in msgs["/tool_pose"]]
    assert all(m.header.frame_id == "base" for m in poses)
    close([xyz(m.pose.position) for m in poses], np.column_stack([col["x"], col["y"], col["z"]]))
    assert all([m.pose.orientation.x, m.pose.orientation.y, m.pose.orientation.z, m.pose.orientation.w] == [0, 0, 0, 1] for m in poses)
    close([xyz(m.twist.linear) for _, m in msgs["/tool_twist"]], C("v"))
    assert all(xyz(m.twist.angular) == [0, 0, 0] for _, m in msgs["/tool_twist"])
    close([xyz(m.accel.linear) for _, m in msgs["/tool_accel"]], C("a"))
    close([xyz(m.vector) for _, m in msgs["/tool_jerk"]], C("j"))

    # one JointTrajectory per move, every sample of the move a point
    move = col.get("move", np.zeros(n))
    trajs = msgs["/joint_trajectory"]
    assert len(trajs) == int(move.max()) + 1
    for k, (ns, traj) in enumerate(trajs):
        idx = np.flatnonzero(move == k)
        t0 = col["t"][idx[0]]
        assert abs((ns - EPOCH_NS) / 1e9 - t0) <= ATOL_T  # logged at the move's start
        assert (traj.header.stamp.sec, traj.header.stamp.nanosec) == (0, 0)  # a controller starts it on receipt
        assert list(traj.joint_names) == list(samples.joint.names)
        assert len(traj.points) == len(idx)
        close([p.positions for p in traj.points], J("q")[idx])
        close([p.velocities for p in traj.points], J("qd")[idx])
        close([p.accelerations for p in traj.points], J("qdd")[idx])
        assert all(len(p.effort) == 0 for p in traj.points)  # the torques are in /joint_states
        tfs = np.array([p.time_from_start.sec + p.time_from_start.nanosec * 1e-9 for p in traj.points])
        np.testing.assert_allclose(tfs, col["t"][idx] - t0, rtol=0, atol=2 * ATOL_T)
        assert tfs[0] == 0.0


@pytest.mark.parametrize("compression", [None, "zstd"])
def test_ros2_delta_read_by_rosbags_equals_csv(tmp_path, compression):
    pl = delta_plan()
    path = write_file(tmp_path, pl, compression=compression)
    msgs = read_ros2(path)
    assert {t: None for t in msgs} == {t: None for t in ROS2_TOPICS}
    check_ros2_against_csv(pl, msgs, drives=True)


def test_ros2_gantry_without_drives(tmp_path):
    pl = gantry_plan()
    msgs = read_ros2(write_file(tmp_path, pl))
    assert set(msgs) == set(ROS2_TOPICS) - {"/motor_states"}
    check_ros2_against_csv(pl, msgs, drives=False)


def test_ros2_batch_one_trajectory_per_move(tmp_path):
    batch = delta_batch()
    msgs = read_ros2(write_file(tmp_path, batch))
    assert len(msgs["/joint_trajectory"]) == 3
    check_ros2_against_csv(batch, msgs, drives=True)
    # the log times of the whole file never go back
    all_ns = sorted(ns for topic in msgs.values() for ns, _ in topic)
    assert all_ns[0] == EPOCH_NS and all_ns[-1] == EPOCH_NS + round(batch.t[-1] * 1e9)


def test_ros2_file_structure(tmp_path):
    """Profile ros2, every channel cdr with a ros2msg schema (no JSON channel), library without a version."""
    from mcap.reader import make_reader

    data = mcap_bytes(delta_plan())
    reader = make_reader(io.BytesIO(data))
    header = reader.get_header()
    summary = reader.get_summary()
    assert header.profile == "ros2" and header.library == "pickplace"
    chans = {c.topic: c for c in summary.channels.values()}
    assert set(chans) == set(ROS2_TOPICS)
    for topic, c in chans.items():
        schema = summary.schemas[c.schema_id]
        assert c.message_encoding == "cdr" and schema.encoding == "ros2msg", topic
        assert schema.name == ROS2_TOPICS[topic]
        assert schema.data.decode() == ros2_msgdef(ROS2_TOPICS[topic])
    assert all(ci.compression == "" for ci in summary.chunk_indexes)
    meta = {m.name: m.metadata for m in reader.iter_metadata()}
    assert meta["pickplace"]["epoch_offset_ns"] == str(EPOCH_NS) and meta["pickplace"]["frame_id"] == "base"


def test_zstd_chunks_are_compressed():
    from mcap.reader import make_reader

    pl = delta_plan(rate=1000)
    plain, packed = mcap_bytes(pl), mcap_bytes(pl, compression="zstd")
    summary = make_reader(io.BytesIO(packed)).get_summary()
    assert summary.chunk_indexes and all(ci.compression == "zstd" for ci in summary.chunk_indexes)
    assert len(packed) < 0.7 * len(plain)
    assert mcap_bytes(pl, compression="zstd") == packed  # zstd output is deterministic too


@pytest.mark.parametrize(
    "name",
    [
        "trajectory_msgs/msg/JointTrajectory",
        "sensor_msgs/msg/JointState",
        "geometry_msgs/msg/PoseStamped",
        "geometry_msgs/msg/TwistStamped",
        "geometry_msgs/msg/AccelStamped",
        "geometry_msgs/msg/Vector3Stamped",
    ],
)
def test_msgdefs_match_ros2_humble(name):
    """Our message definitions parse (rosbags' .msg parser) to exactly the types of ROS 2 Humble:
    the same types (root and every dependency), each with the same fields in the same order."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    ref = get_typestore(Stores.ROS2_HUMBLE).fielddefs
    ours = get_types_from_msg(ros2_msgdef(name), name)

    def nested(desc):
        kind, arg = desc
        if kind.name == "NAME":
            yield arg
        elif kind.name in ("SEQUENCE", "ARRAY"):
            yield from nested(arg[0])

    closure, todo = set(), [name]
    while todo:
        typ = todo.pop()
        if typ not in closure:
            closure.add(typ)
            todo += [sub for _, desc in ref[typ][1] for sub in nested(desc)]
    assert set(ours) == closure
    for typ in closure:
        assert ours[typ][1] == ref[typ][1], typ


def test_fast_cdr_equals_mcap_ros2_serialiser(monkeypatch):
    """The vectorised CDR fill gives the same bytes as mcap_ros2 serialising every message."""
    for samples in (delta_plan(), gantry_plan(), delta_batch()):
        fast = mcap_bytes(samples)
        orig = M._write_ros2
        monkeypatch.setitem(M._WRITERS, M.McapFlavor.ros2, lambda *a: orig(*a, fast=False))
        slow = mcap_bytes(samples)
        monkeypatch.setitem(M._WRITERS, M.McapFlavor.ros2, orig)
        assert fast == slow


# ----------------------------------------------------------------------------------------- foxglove


def check_schema(doc, schema, where="$"):
    """A small JSON-schema check (types, properties, items, required) — enough for these schemas."""
    kind = schema.get("type")
    if kind == "object":
        assert isinstance(doc, dict), where
        props = schema.get("properties", {})
        assert set(doc) <= set(props), (where, set(doc) - set(props))
        for key in schema.get("required", []):
            assert key in doc, (where, key)
        for key, val in doc.items():
            check_schema(val, props[key], f"{where}.{key}")
    elif kind == "array":
        assert isinstance(doc, list), where
        for i, item in enumerate(doc):
            check_schema(item, schema["items"], f"{where}[{i}]")
    elif kind == "number":
        assert isinstance(doc, (int, float)) and not isinstance(doc, bool), where
    elif kind == "integer":
        assert isinstance(doc, int) and not isinstance(doc, bool), where
        assert schema.get("minimum", doc) <= doc <= schema.get("maximum", doc), where
    elif kind == "string":
        assert isinstance(doc, str), where


@pytest.mark.parametrize("samples", ["delta", "gantry", "batch"])
def test_foxglove_read_with_mcap_and_json_equals_csv(samples):
    import json

    samples = {"delta": delta_plan, "gantry": gantry_plan, "batch": delta_batch}[samples]()
    info, msgs = read_mcap_json(mcap_bytes(samples, flavor="foxglove"))
    assert info["profile"] == "" and info["library"] == "pickplace"
    names = {topic: (enc, schema.name, schema.encoding) for topic, (enc, schema) in info["channels"].items()}
    assert names == {
        "/tool_pose": ("json", "foxglove.PoseInFrame", "jsonschema"),
        "/tool_path": ("json", "foxglove.PosesInFrame", "jsonschema"),
        "/joint_states": ("json", "pickplace.JointState", "jsonschema"),
        "/tool_motion": ("json", "pickplace.ToolMotion", "jsonschema"),
    }
    schemas = {topic: json.loads(schema.data) for topic, (_, schema) in info["channels"].items()}
    for topic, items in msgs.items():
        for _, doc in items:
            check_schema(doc, schemas[topic])
    col = csv_table(samples)
    n = len(col["t"])
    nj = len(samples.joint.names)
    J = lambda name: np.column_stack([col[f"{name}{k}"] for k in range(1, nj + 1)])  # noqa: E731
    C = lambda prefix: np.column_stack([col[f"{prefix}{c}"] for c in "xyz"])  # noqa: E731
    xyz = lambda d: [d["x"], d["y"], d["z"]]  # noqa: E731
    ts = lambda d: (d["timestamp"]["sec"] * 10**9 + d["timestamp"]["nsec"] - EPOCH_NS) / 1e9  # noqa: E731

    pose = msgs["/tool_pose"]
    assert len(pose) == n
    np.testing.assert_allclose([(ns - EPOCH_NS) / 1e9 for ns, _ in pose], col["t"], rtol=0, atol=ATOL_T)
    np.testing.assert_allclose([ts(d) for _, d in pose], col["t"], rtol=0, atol=ATOL_T)
    close([xyz(d["pose"]["position"]) for _, d in pose], np.column_stack([col["x"], col["y"], col["z"]]))
    assert all(d["frame_id"] == "base" and d["pose"]["orientation"] == {"x": 0, "y": 0, "z": 0, "w": 1} for _, d in pose)
    js = [d for _, d in msgs["/joint_states"]]
    close([d["position"] for d in js], J("q"))
    close([d["velocity"] for d in js], J("qd"))
    close([d["acceleration"] for d in js], J("qdd"))
    close([d["effort"] for d in js], J("torque"))
    if samples.joint.motor_speed is not None:
        close([d["motor_speed"] for d in js], J("motor_speed"))
        close([d["motor_torque"] for d in js], J("motor_torque"))
    else:
        assert all("motor_speed" not in d for d in js)
    mo = [d for _, d in msgs["/tool_motion"]]
    close([xyz(d["velocity"]) for d in mo], C("v"))
    close([xyz(d["acceleration"]) for d in mo], C("a"))
    close([xyz(d["jerk"]) for d in mo], C("j"))
    move = col.get("move", np.zeros(n))
    paths = msgs["/tool_path"]
    assert len(paths) == int(move.max()) + 1
    for k, (ns, d) in enumerate(paths):
        idx = np.flatnonzero(move == k)
        assert abs((ns - EPOCH_NS) / 1e9 - col["t"][idx[0]]) <= ATOL_T
        close([xyz(p["position"]) for p in d["poses"]], np.column_stack([col["x"], col["y"], col["z"]])[idx])


# ------------------------------------------------------------------------------ determinism and pipes


@pytest.mark.parametrize("flavor", ["ros2", "foxglove"])
def test_deterministic_bytes_file_pipe_and_stream(tmp_path, flavor):
    pl = delta_plan()
    first = mcap_bytes(pl, flavor=flavor)
    assert mcap_bytes(pl, flavor=flavor) == first
    # a write-only stream without tell()/seek() (like a pipe) gets the same bytes
    class WriteOnly:
        def __init__(self):
            self.parts = []

        def write(self, b):
            self.parts.append(bytes(b))
            return len(b)

        def flush(self):
            pass

    sink = WriteOnly()
    write_mcap(pl, sink, flavor=flavor)
    assert b"".join(sink.parts) == first
    # through atomic_output to a file
    target = tmp_path / "out.mcap"
    with atomic_output(target, binary=True) as fh:
        write_mcap(pl, fh, flavor=flavor)
    assert target.read_bytes() == first
    # no version string of any library in the file (the header's library field is a bare name)
    import mcap

    assert f"mcap-python/{mcap.__version__}".encode() not in first and b"mcap-ros2-support" not in first


def test_stdout_pipe_equals_file(tmp_path):
    """A real pipe: a child process writes to its stdout through atomic_output('-'); bytes == the file."""
    code = (
        "import sys; sys.path.insert(0, %r)\n"
        "from tests.golden.samples import delta_plan\n"
        "from pickplace_cli.export import atomic_output\n"
        "from pickplace_cli.export.mcap import write_mcap\n"
        "with atomic_output('-', binary=True) as fh:\n"
        "    write_mcap(delta_plan(), fh)\n"
    ) % str(Path(__file__).resolve().parents[2])
    proc = subprocess.run([sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE, check=True)
    assert proc.stdout == mcap_bytes(delta_plan()), proc.stderr.decode()


def test_times_come_from_the_trajectory_not_the_clock():
    from mcap.reader import make_reader

    pl = delta_plan()
    reader = make_reader(io.BytesIO(mcap_bytes(pl, epoch_ns=0)))
    times = sorted({m.log_time for _, _, m in reader.iter_messages()})
    assert times == [round(t * 1e9) for t in pl.t]


def test_errors():
    pl = delta_plan()
    with pytest.raises(ExportError, match="flavor"):
        mcap_bytes(pl, flavor="ros1")
    with pytest.raises(ExportError, match="compression"):
        mcap_bytes(pl, compression="lz5")
    batch = delta_batch()
    bad = type(batch)(batch.t[::-1].copy(), batch.p, batch.v, batch.a, batch.j, batch.joint, batch.move)
    with pytest.raises(ExportError, match="back in time"):
        mcap_bytes(bad)


def test_non_finite_value_is_refused():
    from dataclasses import replace

    pl = delta_plan()
    torque = pl.joint.torque.copy()
    torque[7, 1] = np.nan
    bad = replace(pl, joint=replace(pl.joint, torque=torque))
    for flavor in ("ros2", "foxglove"):
        with pytest.raises(ExportError, match=r"torque: not finite at sample 7"):
            mcap_bytes(bad, flavor=flavor)
