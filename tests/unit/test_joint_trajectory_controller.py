"""The MCAP's ``/joint_trajectory`` is a command ros2_control's JointTrajectoryController accepts.

``validate_trajectory_msg`` below is a port, rule by rule, of the controller's own check of an incoming
``trajectory_msgs/JointTrajectory`` (ros2_controllers, joint_trajectory_controller.cpp,
``JointTrajectoryController::validate_trajectory_msg`` and ``validate_trajectory_point_field``, Humble and Jazzy),
with the controller's parameters as arguments: all the controller's joints named (unless partial goals are allowed),
no empty name list, a header stamp of 0 ("start now") or a trajectory that does not end in the past, only the
controller's joints, at least one point, the last point at rest (unless allowed otherwise), ``time_from_start``
strictly increasing, every field the size of the names (velocities, accelerations, effort may be empty) and no
effort without an effort command interface. The files are written by the CLI and read back with ``rosbags`` (its
own MCAP reader and CDR deserialiser), with its ROS 2 Humble and Jazzy type stores.
"""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from typer.testing import CliRunner

from pickplace_cli.cli import app

#: "now" of the controller's clock: 2026-11-28T00:00:00Z [s since the Unix epoch] (a fixed number, not the wall clock)
NOW_S = 1_795_824_000.0
#: float's machine epsilon: the controller's test of a last point at rest (``std::numeric_limits<float>::epsilon()``)
FLOAT_EPS = float(np.finfo(np.float32).eps)
ADEPT = ("--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8")


def _seconds(stamp) -> float:
    return stamp.sec + stamp.nanosec * 1e-9


def validate_trajectory_msg(traj, controller_joints: list[str], now_s: float = NOW_S, *,
                            allow_partial_joints_goal: bool = False, allow_integration_in_goal_trajectories: bool = False,
                            allow_nonzero_velocity_at_trajectory_end: bool = False,
                            has_effort_command_interface: bool = False) -> str | None:
    """None when the controller accepts ``traj``, else the reason it logs (the port: see the module docstring)."""
    names = list(traj.joint_names)
    if not allow_partial_joints_goal and len(names) != len(controller_joints):
        return "Joints on incoming trajectory don't match the controller joints."
    if not names:
        return "Empty joint names on incoming trajectory."
    start = _seconds(traj.header.stamp)
    if start != 0.0:  # 0: start now; otherwise refused when it ends before now
        end = start + sum(_seconds(p.time_from_start) for p in traj.points)
        if end < now_s:
            return f"Received trajectory with non-zero start time ({start}) that ends in the past ({end})"
    for name in names:
        if name not in controller_joints:
            return f"Incoming joint {name} doesn't match the controller's joints."
    points = list(traj.points)
    if not points:
        return "Empty trajectory received."
    if not allow_nonzero_velocity_at_trajectory_end:
        for i, v in enumerate(points[-1].velocities):
            if abs(v) > FLOAT_EPS:
                return f"Velocity of last trajectory point of joint {names[i]} is not zero: {v:.15f}"

    def field_ok(values, allow_empty: bool) -> bool:
        return (allow_empty and len(values) == 0) or len(values) == len(names)

    previous = 0.0
    for i, p in enumerate(points):
        t = _seconds(p.time_from_start)
        if i > 0 and t <= previous:
            return f"Time between points {i - 1} and {i} is not strictly increasing, it is {previous} and {t} respectively"
        previous = t
        if allow_integration_in_goal_trajectories:
            fields = (p.positions, p.velocities, p.accelerations)
            if all(len(f) == 0 for f in fields) or any(len(f) and not field_ok(f, False) for f in fields):
                return f"Mismatch between joint_names and a field at point #{i}."
        elif not (field_ok(p.positions, False) and field_ok(p.velocities, True) and field_ok(p.accelerations, True)
                  and field_ok(p.effort, True)):
            return f"Mismatch between joint_names and a field at point #{i}."
        if not has_effort_command_interface and len(p.effort):
            return "Trajectories with effort fields are only supported for controllers using the 'effort' command interface."
    return None


# ---------------------------------------------------------------------------------------- the port can refuse


def _msg(stamp=(0, 0), names=("A1", "A2"), times=(0.0, 0.1), vel_end=0.0, effort=False, sizes=2):
    pts = [SimpleNamespace(positions=[0.0] * sizes, velocities=[0.0, vel_end if k == len(times) - 1 else 0.0][:sizes],
                           accelerations=[], effort=[1.0] * sizes if effort else [],
                           time_from_start=SimpleNamespace(sec=int(t), nanosec=int(round((t % 1) * 1e9))))
           for k, t in enumerate(times)]
    return SimpleNamespace(header=SimpleNamespace(stamp=SimpleNamespace(sec=stamp[0], nanosec=stamp[1])),
                           joint_names=list(names), points=pts)


@pytest.mark.parametrize("kwargs, says", [
    ({}, None),
    ({"stamp": (1_704_067_200, 0)}, "ends in the past"),
    ({"stamp": (int(NOW_S) + 60, 0)}, None),  # a start in the future is kept
    ({"effort": True}, "effort"),
    ({"names": ("A1", "B2")}, "doesn't match the controller's joints"),
    ({"names": ("A1",), "sizes": 1}, "don't match the controller joints"),
    ({"times": (0.0, 0.1, 0.1)}, "not strictly increasing"),
    ({"times": ()}, "Empty trajectory"),
    ({"vel_end": 1e-3}, "is not zero"),
    ({"sizes": 3}, "Mismatch"),
])
def test_the_port_refuses_what_the_controller_refuses(kwargs, says):
    reason = validate_trajectory_msg(_msg(**kwargs), ["A1", "A2"])
    assert (reason is None) if says is None else (reason is not None and says in reason), reason


# --------------------------------------------------------------------------------------- the files the CLI writes


def _cli(*args: str) -> None:
    res = CliRunner().invoke(app, list(args), catch_exceptions=False)
    assert res.exit_code == 0, (args, res.stderr)


def _typestore(name: str):
    from rosbags.typesys import Stores, get_typestore

    return get_typestore({"humble": Stores.ROS2_HUMBLE, "jazzy": Stores.ROS2_JAZZY}[name])


def read_topic(path: Path, topic: str, store: str) -> list:
    """(log time ns, message) of ``topic`` in the MCAP file or rosbag2 directory ``path``, deserialised by rosbags with
    the type store ``store`` (humble or jazzy), not by the definitions in the file."""
    from rosbags.highlevel import AnyReader

    ts = _typestore(store)
    out = []
    with AnyReader([path]) as reader:
        for conn, ns, raw in reader.messages(connections=[c for c in reader.connections if c.topic == topic]):
            out.append((ns, ts.deserialize_cdr(raw, conn.msgtype)))
    return out


CASES = {
    "adept": ("-p", "delta-su2018", *ADEPT),
    "round-trip": ("-p", "delta-su2018", *ADEPT, "--round-trip"),
    "delta-4axis": ("-p", "delta-4axis", "--from", "-0.15,0,-0.8,0", "--to", "0.15,0,-0.8,1.2"),
    "scara": ("-p", "scara-600", "--from", "0.3,-0.2,-0.1", "--to", "0.3,0.2,-0.1"),
    "gantry": ("-p", "gantry", "--from", "0.1,0.1,-0.1", "--to", "0.4,0.3,-0.1"),
}


def _profile_joint_names(profile: str) -> list[str]:
    from pickplace_cli.model.profile import load_profile

    return [j.name for j in load_profile(profile).controller.joints]


@pytest.mark.parametrize("store", ["humble", "jazzy"])
@pytest.mark.parametrize("case", sorted(CASES))
def test_joint_trajectory_is_accepted_by_the_controller(case, store, tmp_path):
    """Each /joint_trajectory message: accepted by the port with the controller's strictest settings (all joints,
    last point at rest within float's epsilon, no integration, no effort interface) at a "now" long after the file's
    times; its names are the profile's controller.joints names; it holds every sample of its move."""
    args = CASES[case]
    path = tmp_path / "out.mcap"
    _cli("plan", *args, "-q", "-o", str(path))
    joints = _profile_joint_names(args[1])
    trajs = read_topic(path, "/joint_trajectory", store)
    states = read_topic(path, "/joint_states", store)
    assert len(trajs) == (2 if case == "round-trip" else 1)
    for _, traj in trajs:
        assert list(traj.joint_names) == joints
        assert validate_trajectory_msg(traj, joints) is None
        assert (traj.header.stamp.sec, traj.header.stamp.nanosec) == (0, 0)
        assert all(len(p.effort) == 0 and len(p.positions) == len(joints) for p in traj.points)
    assert sum(len(t.points) for _, t in trajs) == len(states)
    assert all(len(m.effort) == len(joints) for _, m in states)  # the torques stay in /joint_states


def test_belt_move_needs_the_controller_to_allow_a_moving_end(tmp_path):
    """A move onto a belt ends tracking the part at the belt's speed: accepted once the controller allows a last
    point that moves (allow_nonzero_velocity_at_trajectory_end: true), refused otherwise; the manual says so."""
    path = tmp_path / "belt.mcap"
    _cli("plan", "--from", "-0.1525,0,-0.8", "--to", "0.05,0.1,-0.8", "--to-belt", "0.3,0,0", "--latency", "0.05",
         "-q", "-o", str(path))
    joints = _profile_joint_names("delta-su2018")
    (_, traj), = read_topic(path, "/joint_trajectory", "humble")
    assert validate_trajectory_msg(traj, joints, allow_nonzero_velocity_at_trajectory_end=True) is None
    assert "is not zero" in validate_trajectory_msg(traj, joints)
