"""The written trajectory as a continuous function of time, for the tables a motion kernel interpolates
(:mod:`pickplace_cli.export.knots`): one move, a round trip (there, dwell, back, dwell) or a conveyor move with its
tracking segment — each piece evaluated on the robot's model (not interpolated from samples)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Piece:
    """One piece of the timeline: ``plan`` (its path and duration) from ``t0`` [s], or a hold of ``hold`` (the joint
    positions at rest) for ``length`` [s]."""

    t0: float
    length: float
    plan: object = None
    hold: np.ndarray | None = None


class Motion:
    """q(t), q̇(t), q̈(t) of the pieces one after another (right-continuous at a piece's start)."""

    def __init__(self, pieces: list[Piece], profile) -> None:
        from ..planner import motion_model

        self.pieces = pieces
        self.models = [None if p.plan is None else motion_model(p.plan.cartesian.path, profile) for p in pieces]
        self.starts = np.array([p.t0 for p in pieces])
        self.duration = pieces[-1].t0 + pieces[-1].length
        self.breaks = np.array([p.t0 for p in pieces] + [self.duration])

    def __call__(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        t = np.asarray(t, float)
        which = np.clip(np.searchsorted(self.starts, t, side="right") - 1, 0, len(self.pieces) - 1)
        n = None
        out: list = [None, None, None]
        for k, (piece, model) in enumerate(zip(self.pieces, self.models)):
            sel = np.flatnonzero(which == k)
            if not sel.size:
                continue
            if model is None:
                q = np.repeat(piece.hold[None, :], sel.size, axis=0)
                qd = qdd = np.zeros_like(q)
            else:
                T = piece.length
                tau = np.clip((t[sel] - piece.t0) / T, 0.0, 1.0)
                parts = model.parts(tau, derivatives=False, singularity=False)
                q, qd, qdd = parts.q, parts.qd1 / T, parts.qdd1 / T**2
            if n is None:
                n = q.shape[1]
                out = [np.empty((len(t), n)) for _ in range(3)]
            out[0][sel], out[1][sel], out[2][sel] = q, qd, qdd
        return out[0], out[1], out[2]


def timeline_of(legs: list, profile, dwell: float, round_trip: bool, track=None) -> Motion:
    """The continuous trajectory that ``plan`` writes: one move; with ``round_trip`` there, dwell, back, dwell
    (``dwell`` [s]); with ``track`` the move then the tracking segment."""
    pieces: list[Piece] = []
    t0 = 0.0
    for k, leg in enumerate(legs):
        T = float(leg.cartesian.duration)
        pieces.append(Piece(t0, T, leg))
        t0 += T
        if round_trip and dwell > 0:
            pieces.append(Piece(t0, dwell, hold=np.asarray(leg.joint.q[-1], float)))
            t0 += dwell
    if track is not None:
        pieces.append(Piece(t0, float(track.cartesian.duration), track))
    return Motion(pieces, profile)


def table_of(kind: str, grid: np.ndarray, timeline: Motion, tolerance: float):
    """The :class:`~pickplace_cli.export.knots.KnotTable` of ``kind`` (pvt, cam, cam-table) of ``timeline``, its points
    taken from ``grid`` (the written samples' times [s]; the pieces' ends are always points)."""
    from ..export.knots import fit_equidistant, fit_knots

    if kind == "cam-table":
        return fit_equidistant(timeline.duration, timeline, tolerance, len(grid))
    breaks = [int(np.argmin(np.abs(grid - b))) for b in timeline.breaks]
    return fit_knots(kind, grid, np.array(breaks), timeline, tolerance)
