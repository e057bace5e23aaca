"""The written trajectory as a continuous function of time, for the tables a motion kernel interpolates
(:mod:`pickplace_cli.export.knots`): one move, a round trip (there, dwell, back, dwell) or a conveyor move with its
tracking segment — each piece evaluated on the robot's model (not interpolated from samples)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: rounds of adding points where the rebuilt table exceeds a limit before the table is re-timed
REFINE_ROUNDS = 24
#: times the table may be re-timed (slowed) before it counts as not holding
RETIMES = 6
#: the most controller cycles (or sample periods, without a cycle) a drive's table ``plan`` writes may span: it is
#: judged on every cycle, again after each round of points added (20,000 cycles: about 5 s; 90,000: 150 s and 6 GB)
MAX_TABLE_CYCLES = 20_000


def bounded_table(kind: str, duration: float, step: float, cycle: float | None) -> None:
    """TaskError (exit 1, one line) when a ``kind`` table of ``duration`` [s] on ``step`` [s] (the controller
    ``cycle``, else the sample period) spans more than :data:`MAX_TABLE_CYCLES` cycles."""
    from ..model.errors import TaskError

    n = duration / step
    if n > MAX_TABLE_CYCLES:
        on = f"a controller cycle of {cycle:g} s (--cycle)" if cycle is not None else \
            f"a sample period of {step:g} s (--rate; no --cycle)"
        fix = "the controller's cycle in s (1 ms = 0.001)" if cycle is not None else \
            "the controller's cycle in s with --cycle SECONDS (1 ms = 0.001), or a lower --rate"
        raise TaskError(f"-f {kind}: a table of {duration:.6g} s on {on} is {n:,.0f} cycles; plan judges a drive's "
                        f"table on every cycle, at most {MAX_TABLE_CYCLES:,}: give {fix}")


@dataclass(frozen=True)
class Piece:
    """One piece of the timeline: ``plan`` (its path and duration) from ``t0`` [s], or a hold of ``hold`` (the joint
    positions at rest) for ``length`` [s]."""

    t0: float
    length: float
    plan: object = None
    hold: np.ndarray | None = None


class Motion:
    """q(t), q̇(t), q̈(t) of the pieces one after another (right-continuous at a piece's start); ``models``: the
    pieces' motion models when they are known already (the same moves re-timed), else built from ``profile``."""

    def __init__(self, pieces: list[Piece], profile, models: list | None = None) -> None:
        from ..planner import motion_model

        self.pieces = pieces
        self.models = models if models is not None else [
            None if p.plan is None else motion_model(p.plan.cartesian.path, profile) for p in pieces]
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
    (``dwell`` [s]); with ``track`` the move then the tracking segment; with both the belt cycle: the pick, the
    tracking segment, the place move and the dwell at rest."""
    pieces: list[Piece] = []
    t0 = 0.0
    belt = round_trip and track is not None
    seq = [legs[0], track, *legs[1:]] if belt else list(legs)
    for k, leg in enumerate(seq):
        T = float(leg.cartesian.duration)
        pieces.append(Piece(t0, T, leg))
        t0 += T
        if round_trip and dwell > 0 and (not belt or k == len(seq) - 1):
            pieces.append(Piece(t0, dwell, hold=np.asarray(leg.joint.q[-1], float)))
            t0 += dwell
    if track is not None and not belt:
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


def stretched(timeline: Motion, k: float, cycle: float | None, step: float) -> tuple[Motion, np.ndarray]:
    """``timeline`` with every move ``k`` times longer (rounded up to whole ``cycle``s [s] when one is set; holds
    unchanged) and its grid: every ``step`` [s] from each piece's start, and the pieces' ends."""
    pieces: list[Piece] = []
    t0 = 0.0
    for p in timeline.pieces:
        length = p.length
        if p.plan is not None:
            length = k * p.length
            if cycle is not None:
                length = np.ceil(length / cycle - 1e-9) * cycle
        pieces.append(Piece(t0, float(length), p.plan, p.hold))
        t0 += float(length)
    out = Motion(pieces, None, timeline.models)
    grid = np.concatenate([p.t0 + np.arange(0.0, p.length - 1e-9 * step, step) for p in pieces] + [[t0]])
    return out, grid


@dataclass(frozen=True)
class JudgedTable:
    """A table fitted to a tolerance and then made to hold every limit as the drive rebuilds it: ``table`` (a
    KnotTable), ``report`` (the LimitReport of the rebuilt motion), ``stretch`` (the moves' durations over the
    planned ones: 1 unless re-timed), ``tolerance_points`` (what the tolerance alone needed), ``duration`` [s] of the
    table's timeline, ``step`` [s] (the cycle the per-cycle steps are bounded by) and, for an equidistant table on a
    known controller cycle, ``step_cycles``: its master step in whole cycles."""

    table: object
    report: object
    stretch: float
    tolerance_points: int
    duration: float
    step: float
    step_cycles: int | None = None
    #: the table's own deviation per joint [rad or m] when ``table.max_error`` also holds a rounding's (``--pvt-integer``)
    fit_error: np.ndarray | None = None


def _segments_at(t: np.ndarray, times: list[float]) -> set[int]:
    """The segments of points ``t`` holding (or ending at) each time."""
    out: set[int] = set()
    for x in times:
        i = int(np.clip(np.searchsorted(t, x, side="right") - 1, 0, len(t) - 2))
        out.add(i)
        if i > 0 and abs(x - t[i]) <= 1e-9 * max(1.0, abs(x)):
            out.add(i - 1)
        if i + 1 < len(t) - 1 and abs(x - t[i + 1]) <= 1e-9 * max(1.0, abs(x)):
            out.add(i + 1)
    return out


def _refine_knots(kind, grid, timeline, table, report, judge, tolerance):
    """Split the segments where the rebuilt ``table`` exceeds a limit (at its grid midpoint) until it holds or
    ``REFINE_ROUNDS`` pass (or no segment can be split) → (table, report)."""
    from ..export.knots import knot_table

    for _ in range(REFINE_ROUNDS):
        bad = [r.t_peak for r in report.violations if r.t_peak is not None]
        if not bad:
            break
        idx = np.searchsorted(grid, table.t - 1e-12)
        new = set(idx.tolist())
        for s in _segments_at(table.t, bad):
            a, b = int(idx[s]), int(idx[s + 1])
            if b - a > 1:
                new.add((a + b) // 2)
        if len(new) == len(idx):
            break
        table = knot_table(kind, grid, np.array(sorted(new)), timeline, tolerance)
        report = judge(table)
    return table, report


def _refine_count(timeline, table, report, judge, tolerance, read):
    """An equidistant table whose points the drive reads exactly: ``read`` [s] divides the duration into K whole
    steps (the controller cycle), and the counts tried are m·K + 1 (m = 1, 2, 4, 8, the first at least the
    tolerance's count), whose points lie on every read setpoint — between points the drive's setpoints would be
    off the trajectory by up to the tolerance, and their differences over a cycle magnify that into acceleration
    (4·tolerance / cycle²). → (table, report), the last tried when none holds."""
    from ..export.knots import MAX_TABLE_POINTS, equidistant_table

    if report.ok:
        return table, report
    K = max(1, int(round(timeline.duration / read)))
    m = max(1, int(np.ceil((len(table.t) - 1) / K)))
    for _ in range(4):
        n = m * K + 1
        if n > MAX_TABLE_POINTS:
            break
        table = equidistant_table(timeline.duration, n, timeline, tolerance, table.samples)
        report = judge(table)
        if report.ok:
            break
        m *= 2
    return table, report


def _cycle_step_table(timeline, table, judge, tolerance, cycle: float):
    """An equidistant table read every ``cycle`` [s] (the timeline whole cycles long, K of them): its master step is
    the largest whole number of cycles k that divides K and is at most the step the tolerance needs (``table``: the
    tolerance's own count), and at least one cycle — the drive reads one point a cycle and runs straight between
    its setpoints, so points closer than a cycle change nothing it runs (a point on every setpoint already puts the
    setpoints on the trajectory); a step that breaks a limit as the drive rebuilds it is halved (down to one cycle).
    → (table, report, k)."""
    from ..export.knots import equidistant_table

    K = max(1, int(round(timeline.duration / cycle)))
    wanted = (timeline.duration / max(1, len(table.t) - 1)) / cycle  # the tolerance's step in cycles
    k = max(1, min(K, int(np.floor(wanted + 1e-9))))
    samples = table.samples
    while True:
        while K % k:
            k -= 1
        table = equidistant_table(timeline.duration, K // k + 1, timeline, tolerance, samples)
        report = judge(table)
        # between the points the setpoints are off the trajectory (by up to the tolerance, magnified over a cycle
        # into acceleration): a step of fewer cycles, down to one (every setpoint on the trajectory)
        if report.ok or k == 1:
            return table, report, k
        k = max(1, k // 2)


def _sized_table(timeline, table, judge, tolerance, fixed: int, size):
    """The equidistant table of ``fixed`` points (a controller's table type), the next larger type's when that one
    exceeds a limit as the drive rebuilds it → (table, report), the last tried when none holds."""
    from ..export.knots import equidistant_table
    from ..model.errors import ExportError

    while True:
        table = equidistant_table(timeline.duration, fixed, timeline, tolerance, table.samples)
        report = judge(table)
        if report.ok:
            return table, report
        try:
            fixed = size(fixed + 1)
        except ExportError:
            return table, report


def judged_table(kind: str, grid: np.ndarray, timeline: Motion, tolerance: float, profile, dwell: float,
                 cycle: float | None, retime: bool = True, capacity: bool = False, size=None,
                 written=None, ends: str = "hold") -> JudgedTable:
    """The ``kind`` table of ``timeline`` (:func:`table_of`: its points from ``grid`` [s] within ``tolerance``)
    made to hold every limit of ``profile`` (at its limit use) as the drive rebuilds it
    (:func:`~pickplace_cli.limits.table.check_table`; per-cycle steps bounded over ``cycle`` [s], else over the
    grid's step): points are added where the rebuilt motion exceeds a limit, then, when ``retime`` (not for a
    conveyor move) and that is not enough, every move is slowed (``stretch``) and the table fitted again. The
    report says whether it holds; a table that cannot be made to is returned with its violations. ``capacity``: the
    profile's Cartesian capacity is checked too (when the plan's duration rule holds it). ``size``: for a cam-table,
    (points the tolerance needs) → the count a controller's table type holds (None: any), which the table then has
    (no points added). ``written``: (table) → the table as the file holds it (e.g. rounded to a drive's integer
    units), which is then what is judged (None: the table itself). ``ends``: what the drive does before and after the
    table (:func:`~pickplace_cli.export.interpolate.rebuild`: "hold" its end points, or "continue" at their
    velocities)."""
    from ..export.interpolate import rebuild
    from ..limits.table import check_table
    from ..planner import motion_model_static

    robot, specs, margin, box = motion_model_static(profile)[:4]
    grid = np.asarray(grid, float)
    step = float(cycle) if cycle is not None else float(np.median(np.diff(grid)))
    bounded_table(kind, timeline.duration, step, cycle)

    def judge_on(g, read):
        def judge(table):
            return check_table(rebuild(written(table) if written is not None else table, read, ends), robot, specs, read, dwell, margin, box, samples=g,
                               capacity=profile.capacity if capacity else None).rated(profile.limit_use)
        return judge

    k = 1.0
    line, g = timeline, grid
    first = None
    per = None
    used = 1.0
    for attempt in range(RETIMES + 1):
        used = k
        if attempt:
            # an equidistant table without a known cycle is re-timed to whole sample periods too: it is then read at
            # exactly that period (a drive reading it at the sample period off its points ran a sharp law's
            # acceleration 3.5 % past the limit between them)
            line, g = stretched(timeline, k, cycle if cycle is not None or kind != "cam-table" else step, step)
            bounded_table(kind, line.duration, step, cycle)
        # an equidistant table is read every cycle: whole cycles of the duration (without a cycle, whole steps of
        # about the sample period)
        read = line.duration / max(1, round(line.duration / step)) if kind == "cam-table" else step
        judge = judge_on(g, read)
        table = table_of(kind, g, line, tolerance)
        first = len(table.t) if first is None else first
        report = judge(table)
        needed = len(table.t)
        if cycle is not None:  # on a known cycle one point a cycle is all the drive reads (_cycle_step_table)
            needed = min(needed, int(round(line.duration / read)) + 1)
        fixed = size(needed) if (size is not None and kind == "cam-table") else None
        if fixed is not None:
            table, report = _sized_table(line, table, judge, tolerance, fixed, size)
        elif kind == "cam-table" and cycle is not None:
            table, report, per = _cycle_step_table(line, table, judge, tolerance, read)
        elif kind == "cam-table":
            table, report = _refine_count(line, table, report, judge, tolerance, read)
        else:
            table, report = _refine_knots(kind, g, line, table, report, judge, tolerance)
        failing = report.violations
        if not failing or not retime or any(r.kind != "limit" for r in failing):
            break
        worst = max(r.utilisation / r.target for r in failing)
        k *= max(worst, 1.0 + 1e-4) ** 0.5 * (1.0 + 1e-4)
    return JudgedTable(table, report, used, first, line.duration, read, per)
