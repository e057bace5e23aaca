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
from pickplace_cli.model.profile import load_profile
from pickplace_cli.model.task import Task
from pickplace_cli.model.trajectory import JointTrajectory

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


# ------------------------------------------------------------------- frozen inputs for the golden files
# Golden files test the *formats*, so their input must not move when the planner or the shipped table
# changes: closed-form samples (a quintic rest-to-rest blend and simple joint functions) and a small
# closed-form table. Values are exact up to a few ulp on any platform.


@dataclass(frozen=True)
class Synthetic:
    t: np.ndarray
    p: np.ndarray
    v: np.ndarray
    a: np.ndarray
    j: np.ndarray
    joint: JointTrajectory
    move: np.ndarray | None = None


def synthetic(n: int = 21, duration: float = 0.2, drives: bool = True, start=(-0.15, 0.0, -0.8),
              end=(0.15, 0.05, -0.78), t0: float = 0.0, move: int | None = None) -> Synthetic:
    """A rest-to-rest quintic blend s(u) = 10u³ − 15u⁴ + 6u⁵ between two points, joints q = f(p)."""
    T = duration
    t = np.linspace(0.0, T, n)
    u = t / T
    s = [10 * u**3 - 15 * u**4 + 6 * u**5, (30 * u**2 - 60 * u**3 + 30 * u**4) / T,
         (60 * u - 180 * u**2 + 120 * u**3) / T**2, (60 - 360 * u + 360 * u**2) / T**3]
    d = np.asarray(end, float) - np.asarray(start, float)
    p = np.asarray(start, float) + s[0][:, None] * d
    v, a, j = (sk[:, None] * d for sk in s[1:])
    q = np.column_stack([np.arctan2(p[:, 1], p[:, 0] + 1.0), 0.5 * np.sin(3 * p[:, 0]), p[:, 2] + 0.9])
    qd = np.column_stack([np.gradient(q[:, k], t) for k in range(3)])
    qdd = np.column_stack([np.gradient(qd[:, k], t) for k in range(3)])
    qddd = np.column_stack([np.gradient(qdd[:, k], t) for k in range(3)])
    torque = np.column_stack([2.0 * qdd[:, 0] - 1.5, 0.8 * qdd[:, 1] + 0.3 * qd[:, 1], 40.0 * (qdd[:, 2] + 9.81)])
    gear = np.array([25.0, 25.0, 10.0])
    jt = JointTrajectory(t + t0, q, qd, qdd, qddd, ("q1", "q2", "q3"), ("rad", "rad", "m"), torque=torque,
                         motor_speed=gear * qd if drives else None,
                         motor_torque=torque / (gear * 0.9) + 1.5e-4 * gear * qdd if drives else None)
    mv = None if move is None else np.full(n, move)
    return Synthetic(t + t0, p, v, a, j, jt, mv)


def synthetic_batch() -> Synthetic:
    """Two synthetic moves (numbered 1 and 2, like batch rows), the second 0.1 s after the first."""
    one = synthetic(move=1)
    two = synthetic(start=(0.15, 0.05, -0.78), end=(-0.15, 0.0, -0.8), t0=0.3, move=2)
    cat = lambda name: np.concatenate([getattr(one, name), getattr(two, name)])  # noqa: E731
    jcat = lambda name: np.concatenate([getattr(one.joint, name), getattr(two.joint, name)])  # noqa: E731
    jt = JointTrajectory(cat("t"), jcat("q"), jcat("qd"), jcat("qdd"), jcat("qddd"), one.joint.names, one.joint.units,
                         torque=jcat("torque"), motor_speed=jcat("motor_speed"), motor_torque=jcat("motor_torque"))
    return Synthetic(cat("t"), cat("p"), cat("v"), cat("a"), cat("j"), jt, cat("move"))


def synthetic_table():
    """A 12-row table of closed-form values (non-uniform λ grid, small k2 with an exponent literal)."""
    from pickplace_cli.lookup.bspline_optimum import TableRow
    from pickplace_cli.lookup.bspline_table import Table

    lams = [1.0, 1.5, 2.0, 3.0, 5.0, 7.5, 10.0, 12.5, 15.0, 20.0, 30.0, 40.0]
    rows = []
    for lam in lams:
        k1 = 0.579 - 1.99e-2 * lam + 5.09e-4 * lam**2 - 4.91e-6 * lam**3
        k2 = 0.218 - 1.09e-2 * lam + 4.15e-4 * lam**2 - 5.41e-6 * lam**3 if lam < 40 else 1.5e-5
        a_max, j_max = 8.0 + 1.0 / lam, 80.0 + 10.0 / lam
        rows.append(TableRow(lam, k1, k2, a_max, j_max, 2.0 + 0.3 / lam, 0.93, a_max - 0.5, j_max - 1.0))
    meta = {"eta": 0.5, "weights": [0.5, 0.5], "method": "bspline", "grid_step": 0.01, "tool_version": "golden"}
    return Table(tuple(rows), meta=meta, source="/anywhere/golden-table.csv")


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
