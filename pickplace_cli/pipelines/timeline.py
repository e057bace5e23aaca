"""Several planned moves as one sampled trajectory: round trips and batches.

A :class:`Timeline` has the same sample attributes as a :class:`~pickplace_cli.planner.Plan` (``t``,
``p v a j``, ``joint``) plus ``move``, the move number of every sample, so every writer takes either.

* :func:`round_trip`: there, dwell at the place point, back, dwell at the pick point — one Adept cycle
  (2T + 2·dwell seconds), continuous time, the dwells sampled at the output rate with the tool at rest
  (joint torque = the holding torque, motor speed 0). Repeating the file repeats the cycle.
* :func:`concatenate`: moves one after another. ``restart_time=True`` (CSV batches): every move keeps
  its own time from 0 s and the ``move`` column tells them apart. ``False`` (MCAP): one timeline, each
  move starting ``gap`` seconds after the previous one ends (no samples in the gap).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from ..model.trajectory import JointTrajectory

_JOINT_FIELDS = ("q", "qd", "qdd", "qddd", "torque", "motor_speed", "motor_torque")


@dataclass(frozen=True)
class Segment:
    """One move (or dwell) of a timeline: ``move`` number, what it is, and its time span [s]."""

    move: int
    label: str  # "move", "dwell"
    t_start: float
    t_end: float


@dataclass(frozen=True)
class Timeline:
    """Samples of several moves: ``t`` (N,) s, ``p v a j`` (N, 3) SI, ``joint`` over the same samples,
    ``move`` (N,) int (the move each sample belongs to), ``segments`` in time order."""

    t: np.ndarray
    p: np.ndarray
    v: np.ndarray
    a: np.ndarray
    j: np.ndarray
    joint: JointTrajectory
    move: np.ndarray
    segments: tuple[Segment, ...]
    summaries: tuple[dict[str, Any], ...] = ()
    cycle: float | None = None  # s: the controller cycle every time stamp is a whole multiple of (None: any times)
    belt_m: np.ndarray | None = None  # m: a belt cycle's belt travel since the part's detection per sample (a cam's
    # master position with the belt as master); None: not a belt cycle

    def __post_init__(self) -> None:
        n = len(self.t)
        for name in ("p", "v", "a", "j"):
            if np.shape(getattr(self, name)) != (n, 3):
                raise ValueError(f"{name} must have shape ({n}, 3), got {np.shape(getattr(self, name))}")
        if np.shape(self.move) != (n,):
            raise ValueError(f"move must have shape ({n},), got {np.shape(self.move)}")
        if self.belt_m is not None and np.shape(self.belt_m) != (n,):
            raise ValueError(f"belt_m must have shape ({n},), got {np.shape(self.belt_m)}")


def _hold(plan, at_end: bool, t: np.ndarray) -> dict[str, Any]:
    """Samples of the tool at rest at the plan's end (or start) at times ``t``."""
    k = -1 if at_end else 0
    n = len(t)
    jt = plan.joint
    zeros3 = np.zeros((n, 3))
    joint: dict[str, Any] = {}
    for name in _JOINT_FIELDS:
        arr = getattr(jt, name)
        if arr is None:
            joint[name] = None
        elif name in ("q", "torque", "motor_torque"):
            # at rest the torque is the holding (gravity) torque, which the move's end sample already is
            joint[name] = np.repeat(arr[[k]], n, axis=0)
        else:
            joint[name] = np.zeros((n, arr.shape[1]))
    return {"t": t, "p": np.repeat(plan.p[[k]], n, axis=0), "v": zeros3,
            "a": zeros3, "j": zeros3, "joint": joint}


def _pieces_of(plan, offset: float) -> dict[str, Any]:
    jt = plan.joint
    return {"t": plan.t + offset, "p": plan.p, "v": plan.v, "a": plan.a, "j": plan.j,
            "joint": {name: getattr(jt, name) for name in _JOINT_FIELDS}}


def _join(pieces: list[dict[str, Any]], moves: list[int], template: JointTrajectory, segments, summaries) -> Timeline:
    cat = {k: np.concatenate([pc[k] for pc in pieces]) for k in ("t", "p", "v", "a", "j")}
    joint = {}
    for name in _JOINT_FIELDS:
        arrs = [pc["joint"][name] for pc in pieces]
        joint[name] = None if any(a is None for a in arrs) else np.concatenate(arrs)
    move = np.concatenate([np.full(len(pc["t"]), m, dtype=int) for pc, m in zip(pieces, moves)])
    jt = JointTrajectory(cat["t"], names=template.names, units=template.units, angle_weights=template.angle_weights,
                         **joint)
    return Timeline(cat["t"], cat["p"], cat["v"], cat["a"], cat["j"], jt, move, tuple(segments), tuple(summaries))


def from_plan(plan, move: int = 1) -> Timeline:
    """A single plan as a timeline (every sample in ``move``)."""
    seg = Segment(move, "move", float(plan.t[0]), float(plan.t[-1]))
    return _join([_pieces_of(plan, 0.0)], [move], plan.joint, [seg], [plan.summary()])


def on_cycle(timeline: Timeline, cycle: float | None) -> Timeline:
    """The timeline with every time stamp the exact multiple k·cycle it stands for (sums of rounded durations and
    offsets drift by an ulp); ValueError when a stamp is not within 1e-6 cycles of a multiple. None: unchanged."""
    if cycle is None:
        return timeline
    from dataclasses import replace

    k = np.rint(timeline.t / cycle)
    off = np.abs(timeline.t / cycle - k)
    if off.size and off.max() > 1e-6:
        i = int(np.argmax(off))
        raise ValueError(f"t = {timeline.t[i]:.9g} s is not a whole number of {cycle:g} s cycles")
    t = k * cycle
    return replace(timeline, t=t, joint=replace(timeline.joint, t=t), cycle=cycle)


def round_trip(there, back, dwell: float, rate: float) -> Timeline:
    """there → dwell at the place point → back → dwell at the pick point, one continuous trajectory.

    ``there`` and ``back`` are plans (``back`` from the place point to the pick point); ``dwell`` [s]
    is sampled at ``rate`` [Hz] with the tool at rest. Moves are numbered 1 (there) and 2 (back); a dwell
    belongs to the move it follows."""
    if not (np.allclose(there.p[-1], back.p[0], atol=1e-9) and np.allclose(back.p[-1], there.p[0], atol=1e-9)):
        raise ValueError("round_trip: 'back' must start where 'there' ends and end where it starts")
    pieces, moves, segs = [], [], []
    t0 = 0.0
    for m, plan in ((1, there), (2, back)):
        T = float(plan.t[-1])
        pieces.append(_pieces_of(plan, t0))
        moves.append(m)
        segs.append(Segment(m, "move", t0, t0 + T))
        t0 += T
        if dwell > 0:
            # samples in (0, dwell): the next move's first sample is at the dwell's end; the final dwell also
            # gets its end, so the cycle lasts exactly 2T + 2·dwell
            steps = np.arange(1, int(np.ceil(dwell * rate - 1e-9))) / rate
            if m == 2:
                steps = np.append(steps, dwell)
            pieces.append(_hold(plan, True, t0 + steps))
            moves.append(m)
            segs.append(Segment(m, "dwell", t0, t0 + dwell))
            t0 += dwell
    return _join(pieces, moves, there.joint, segs, [there.summary(), back.summary()])


def concatenate(plans: Sequence, moves: Sequence[int], restart_time: bool = True, gap: float = 0.0) -> Timeline:
    """Moves one after another (see the module docstring); ``moves`` numbers them (e.g. batch rows)."""
    if not plans:
        raise ValueError("concatenate: no plans")
    pieces, segs = [], []
    t0 = 0.0
    for plan, m in zip(plans, moves):
        offset = 0.0 if restart_time else t0
        pieces.append(_pieces_of(plan, offset))
        T = float(plan.t[-1])
        segs.append(Segment(int(m), "move", offset, offset + T))
        t0 = offset + T + gap
    return _join(pieces, list(moves), plans[0].joint, segs, [p.summary() for p in plans])
