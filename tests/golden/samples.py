"""Sample inputs shared by the export tests: real plans, a batch timeline, and CSV/MCAP readers.

The readers here are deliberately independent of the writers: CSV is parsed with the ``csv`` module,
MCAP with ``rosbags`` (ROS 2 flavour) or ``mcap``'s reader + ``json`` (Foxglove flavour).
"""

from __future__ import annotations

import csv
import io
import json
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from pickplace_cli.planner import PlanOptions, plan
from pickplace_cli.profile import load_profile
from pickplace_cli.task import Task
from pickplace_cli.trajectory import JointTrajectory

ADEPT = Task([-0.1525, 0.0, -0.8], [0.1525, 0.0, -0.8], 0.025, 0.5)
ADEPT_BACK = Task([0.1525, 0.0, -0.8], [-0.1525, 0.0, -0.8], 0.025, 0.5)
GANTRY_MOVE = Task([0.1, 0.1, -0.2], [0.4, 0.2, -0.2], 0.05, 0.5)


@lru_cache(maxsize=None)
def delta_plan(rate: float = 200.0, time: float = 0.2, back: bool = False):
    """The Adept cycle (``back``: its return move) on the shipped Delta (drives: motor columns present)."""
    task = ADEPT_BACK if back else ADEPT
    return plan(task, load_profile("delta-su2018"), PlanOptions(time=time, rate=rate, fit=False))


@lru_cache(maxsize=None)
def gantry_plan(rate: float = 100.0):
    """A gantry move (no drives: torque but no motor columns)."""
    return plan(GANTRY_MOVE, load_profile("gantry"), PlanOptions(time=0.25, rate=rate, fit=False))


@dataclass(frozen=True)
class Timeline:
    """Duck-typed batch: moves one after another with ``dwell`` s between them, ``move`` per sample."""

    t: np.ndarray
    p: np.ndarray
    v: np.ndarray
    a: np.ndarray
    j: np.ndarray
    joint: JointTrajectory
    move: np.ndarray


def timeline(plans, dwell: float = 0.1) -> Timeline:
    ts, offset = [], 0.0
    for pl in plans:
        ts.append(pl.t + offset)
        offset += pl.t[-1] + dwell
    cat = lambda name: np.vstack([getattr(pl, name) for pl in plans])  # noqa: E731
    jcat = lambda name: None if getattr(plans[0].joint, name) is None else np.vstack([getattr(pl.joint, name) for pl in plans])  # noqa: E731
    t = np.concatenate(ts)
    jt = JointTrajectory(
        t,
        jcat("q"),
        jcat("qd"),
        jcat("qdd"),
        jcat("qddd"),
        plans[0].joint.names,
        plans[0].joint.units,
        torque=jcat("torque"),
        motor_speed=jcat("motor_speed"),
        motor_torque=jcat("motor_torque"),
    )
    move = np.concatenate([np.full(len(pl.t), k) for k, pl in enumerate(plans)])
    return Timeline(t, cat("p"), cat("v"), cat("a"), cat("j"), jt, move)


def delta_batch() -> Timeline:
    """Three Delta moves (there, back, there) with 0.1 s dwell."""
    return timeline([delta_plan(), delta_plan(back=True), delta_plan()], dwell=0.1)


# ------------------------------------------------------------------------------------------- readers


def parse_csv(text: str, sep: str = ",", header: bool = True) -> tuple[list[str] | None, np.ndarray]:
    """(header or None, data) of CSV text, parsed with the csv module (no knowledge of the writer)."""
    rows = list(csv.reader(io.StringIO(text, newline=""), delimiter=sep))
    names = rows.pop(0) if header else None
    return names, np.array(rows, dtype=float)


def csv_table(samples) -> dict[str, np.ndarray]:
    """Column name (without unit) → values, from the default-dialect CSV of ``samples``."""
    from pickplace_cli.export.csv import write_csv

    buf = io.StringIO(newline="")
    write_csv(samples, buf)
    names, data = parse_csv(buf.getvalue())
    return {n.split("[")[0]: data[:, i] for i, n in enumerate(names)}


def read_ros2(path: Path) -> dict[str, list[tuple[int, Any]]]:
    """topic → [(log time ns, message)] read by rosbags' AnyReader (independent of mcap/mcap_ros2)."""
    from rosbags.highlevel import AnyReader

    out: dict[str, list[tuple[int, Any]]] = {}
    with AnyReader([Path(path)]) as reader:
        for conn in reader.connections:
            out.setdefault(conn.topic, [])
        for conn, ns, raw in reader.messages():
            out[conn.topic].append((ns, reader.deserialize(raw, conn.msgtype)))
    return out


def read_mcap_json(data: bytes) -> tuple[dict, dict[str, list[tuple[int, dict]]]]:
    """(summary info, topic → [(log time ns, decoded JSON)]) of a JSON-channel MCAP via mcap's reader."""
    from mcap.reader import make_reader

    reader = make_reader(io.BytesIO(data))
    header = reader.get_header()
    summary = reader.get_summary()
    info = {
        "profile": header.profile,
        "library": header.library,
        "channels": {c.topic: (c.message_encoding, summary.schemas[c.schema_id]) for c in summary.channels.values()},
    }
    out: dict[str, list[tuple[int, dict]]] = {c.topic: [] for c in summary.channels.values()}
    for _schema, channel, message in reader.iter_messages(log_time_order=False):
        out[channel.topic].append((message.log_time, json.loads(message.data)))
    return info, out
