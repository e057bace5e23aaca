"""Joint motion of a path on a robot, and the limit check (check_limits → LimitReport).

Everything a limit depends on is a function of normalised time τ that scales *exactly* with the duration
T (for a fixed path):

    q(τ)                       joint position                      (independent of T)
    q̇ = q̇₁/T,  q̈ = q̈₁/T²,  q⃛ = q⃛₁/T³   (q̇₁ … : the motion at T = 1 s)
    joint torque  = A(τ)/T² + G(τ)         A: inertial (+ Coriolis, ∝ q̇²) part at T = 1, G: gravity
    motor torque  = A_m/T² + G_m            A_m = A/(N·η) + J_rotor·N·q̈₁,  G_m = G/(N·η)
    motor speed   = N·q̇₁/T
    torque rate   = A_m′/T³ + G_m′/T         (′ = d/dτ: the robot's analytic torque_rate)

so one evaluation of the model serves every T (``--time fit`` is a 1-D root search, not a re-plan).

Peaks are found on the continuous trajectory: sampled, then refined at the top sample by the vertex of
the parabola through it and its neighbours; a peak within ``EXACT_BAND`` of its limit is refined exactly by
golden-section search on the model itself, so the verdict near a limit does not depend on sampling.

The duty cycle (RMS torque): move there, dwell at the place point, move back, dwell at the pick point.
The move back is the time-reverse of the move (the tool retraces its path): positions and accelerations
are mirrored in time, velocities change sign, so joint and motor torques — even in q̇, odd terms absent —
are the forward ones mirrored in time, and ∫τ² is the same both ways. During a dwell the motor holds the
gravity torque G_m at that end.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .errors import UnreachableError
from .trajectory import CartesianPath

#: peaks within this fraction of their limit are refined exactly (golden section on the model)
EXACT_BAND = 0.05
#: the check samples at least this many uniform points of τ ∈ [0, 1] (plus the output samples, the
#: path's breakpoints and ``SPAN_SAMPLES`` points inside every span between breakpoints), so a peak's
#: refinement does not depend on the output rate. Every quantity is smooth inside a span (the paths are C²
#: or better there, the robot models analytic away from singularities), so a few points per span locate
#: its local maxima; the parabolic estimate through them is never more than 4e-3 below the true peak
#: (measured on every method and robot; the test holds 1 %), far inside the 5 % band refined exactly
#: (``EXACT_BAND``). (An estimate above the true peak, e.g. across a jump of the torque rate where a
#: law's jerk steps, only sends the quantity to the exact refinement.) The span points are Gauss–Legendre
#: nodes, on which the RMS torque is integrated (:func:`span_nodes`).
CHECK_SAMPLES = 129
SPAN_SAMPLES = 8


def check_grid(tau: np.ndarray, breakpoints: np.ndarray) -> np.ndarray:
    """The τ grid the limit check samples: output samples ∪ uniform grid ∪ breakpoints ∪ points per span."""
    grid, order = check_grid_order(tau, breakpoints)
    return grid[order]


def span_nodes(breakpoints: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Gauss–Legendre nodes (``SPAN_SAMPLES`` per span between consecutive breakpoints, all interior) and
    their weights (summing to 1 over τ ∈ [0, 1]). The check grid contains them: they sample every span,
    and the RMS torque integrates on them (exact for polynomials of degree 2·SPAN_SAMPLES − 1 per span;
    the integrand is smooth inside a span, so the rule is accurate to round-off for the paths here)."""
    key = tuple(np.asarray(breakpoints, float).tolist())
    hit = _NODES.get(key)
    if hit is None:
        b = np.unique(np.clip(np.asarray(breakpoints, float), 0.0, 1.0))
        b = np.unique(np.concatenate([[0.0], b, [1.0]]))
        x, w = _LEGGAUSS
        h = np.diff(b)[:, None]
        hit = ((b[:-1, None] + h * (x + 1.0) / 2.0).ravel(), (h * w / 2.0).ravel())
        if len(_NODES) > 256:
            _NODES.clear()
        _NODES[key] = hit
    return hit


_NODES: dict = {}
_LEGGAUSS = np.polynomial.legendre.leggauss(SPAN_SAMPLES)


def quadrature_weights(tau: np.ndarray, breakpoints: np.ndarray) -> np.ndarray | None:
    """Weights (N,) on the sorted grid ``tau`` that integrate over [0, 1] by :func:`span_nodes`' Gauss rule
    (zero off the nodes), or None when the grid does not contain every node (within 1e-9)."""
    nodes, w = span_nodes(breakpoints)
    i = np.minimum(np.maximum(np.searchsorted(tau, nodes), 1), len(tau) - 1)
    i = np.where(np.abs(tau[i - 1] - nodes) < np.abs(tau[i] - nodes), i - 1, i)
    if len(tau) < 2 or np.abs(tau[i] - nodes).max() > 1e-9:
        return None
    return np.bincount(i, weights=w, minlength=len(tau))


def _extra_points(breakpoints: np.ndarray, uniform: bool) -> np.ndarray:
    """The sorted points the check adds to the output samples: breakpoints ∪ span nodes (∪ the uniform
    grid), without round-off twins (memoised per breakpoints, like :func:`span_nodes`)."""
    key = (tuple(np.asarray(breakpoints, float).tolist()), uniform)
    hit = _EXTRA.get(key)
    if hit is None:
        parts = [breakpoints, span_nodes(breakpoints)[0]] + ([np.linspace(0.0, 1.0, CHECK_SAMPLES)] if uniform else [])
        hit = np.unique(np.concatenate(parts))
        hit = hit[np.concatenate([[True], np.diff(hit) > 1e-9])]
        if len(_EXTRA) > 256:
            _EXTRA.clear()
        _EXTRA[key] = hit
    return hit


_EXTRA: dict = {}


def check_grid_order(tau: np.ndarray, breakpoints: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The check grid with the output samples ``tau`` (sorted) first, then the extra points, and the
    permutation ``order`` that sorts it (``grid[order]`` is :func:`check_grid`). The model evaluated on this
    grid gives the output samples as its first ``len(tau)`` rows (views, no gather); pass ``order`` to
    :meth:`MotionModel.parts` so the check sorts what it needs.

    Extra points within 1e-9 of an output sample or of each other (round-off twins) are dropped, so
    every output sample is in the grid exactly. When the output samples already cover [0, 1] at least as
    densely as the uniform grid (e.g. 1 kHz for a move of 0.128 s or longer), the uniform grid adds nothing
    and is left out."""
    tau = np.asarray(tau, float)
    dense = (
        len(tau) >= CHECK_SAMPLES
        and tau[0] <= 0.0
        and tau[-1] >= 1.0
        and float((tau[1:] - tau[:-1]).max()) <= 1.0 / (CHECK_SAMPLES - 1)
    )
    extra = _extra_points(breakpoints, not dense)
    pos = np.minimum(np.maximum(np.searchsorted(tau, extra), 1), len(tau) - 1) if len(tau) > 1 else np.zeros(len(extra), int)
    near = np.minimum(np.abs(extra - tau[pos - 1 if len(tau) > 1 else 0]), np.abs(extra - tau[pos]))
    grid = np.concatenate([tau, extra[near > 1e-9]])
    return grid, np.argsort(grid, kind="stable")


#: central-difference step in τ for d/dτ of the torques (truncation ~1e-10 relative, round-off ~1e-10)
DTAU = 1e-5


def percent(utilisation: float) -> str:
    """A utilisation as a percentage for people: one decimal up to 9999.9 %, then 3 significant digits
    (2.92e+07), so a wildly infeasible move does not print 29178779.3."""
    p = 100.0 * utilisation
    return f"{p:.1f}" if abs(p) < 9999.95 else f"{p:.3g}"


@dataclass(slots=True)
class LimitRow:
    """One checked limit: the peak of a quantity over the move, its limit and where the peak is.

    (A plain slotted record, not a frozen dataclass: a report has ~25 rows per move and a frozen
    dataclass costs 5× as much to build, which the single-plan target of < 1 ms notices.)"""

    joint: str  # "q1" … or "tool"
    quantity: str
    unit: str
    peak: float  # signed for position bounds and the singularity minimum, |·| otherwise
    limit: float
    utilisation: float  # peak/limit (position: how far toward the bound, 1 = at it)
    t_peak: float | None  # s from the start of the move (None for whole-cycle quantities)
    ok: bool
    kind: str = "limit"  # "limit" (exit 3) or "reach" (exit 4)
    bound: str = "upper"  # "upper": peak ≤ limit; "lower": peak ≥ limit

    @property
    def excess(self) -> float:
        """By how much the limit is exceeded (same unit; ≤ 0 when ok)."""
        return self.limit - self.peak if self.bound == "lower" else self.peak - self.limit

    def as_dict(self) -> dict[str, Any]:
        return {
            "joint": self.joint, "quantity": self.quantity, "unit": self.unit, "peak": self.peak,
            "limit": self.limit, "utilisation": self.utilisation, "t_peak_s": self.t_peak, "ok": self.ok,
            "kind": self.kind, "bound": self.bound, "excess": self.excess,
        }


@dataclass(frozen=True)
class LimitReport:
    """Every joint × quantity checked for one move of ``duration`` seconds, with the duty cycle."""

    rows: tuple[LimitRow, ...]
    duration: float
    dwell: float
    notes: tuple[str, ...] = ()

    @property
    def ok(self) -> bool:
        return all(r.ok for r in self.rows)

    @property
    def violations(self) -> tuple[LimitRow, ...]:
        return tuple(r for r in self.rows if not r.ok)

    @property
    def round_trip(self) -> float:
        return 2.0 * (self.duration + self.dwell)

    @property
    def picks_per_minute(self) -> float:
        return 60.0 / self.round_trip

    def exit_code(self) -> int:
        """0 ok · 3 a limit is exceeded · 4 a reach row (singularity, workcell) fails."""
        bad = self.violations
        if not bad:
            return 0
        return 4 if any(r.kind == "reach" for r in bad) else 3

    def as_dict(self) -> dict[str, Any]:
        return {
            "ok": self.ok,
            "duration_s": self.duration,
            "dwell_s": self.dwell,
            "cycle_time_one_way_s": self.duration,
            "cycle_time_round_trip_s": self.round_trip,
            "picks_per_minute": self.picks_per_minute,
            "violations": [r.as_dict() for r in self.violations],
            "rows": [r.as_dict() for r in self.rows],
            "notes": list(self.notes),
        }


@dataclass(frozen=True)
class _ReportPlan:
    """:meth:`MotionModel.report_plan`: limits (column sign convention), exact-refinement bands and signs per
    column; rows as ("single", column, (joint, quantity, unit, limit, kind, lower)), ("range", (column of the
    max, of the min), (joint, base, unit, kind, lo, hi)) or ("rms", joint index, (joint, rated torque))."""

    limits: np.ndarray
    band: np.ndarray
    signs: np.ndarray
    rows: tuple
    rms: bool


@dataclass(frozen=True)
class Parts:
    """The model evaluated at τ (N,): every array (N, n_joints) unless noted; motion at T = 1 s."""

    tau: np.ndarray
    p: np.ndarray  # (N, 3) m
    v1: np.ndarray  # (N, 3)
    a1: np.ndarray  # (N, 3)
    j1: np.ndarray  # (N, 3)
    q: np.ndarray
    qd1: np.ndarray
    qdd1: np.ndarray
    qddd1: np.ndarray
    A: np.ndarray  # joint torque, inertial part at T = 1
    G: np.ndarray  # joint torque, gravity part
    Am: np.ndarray  # motor torque, inertial part at T = 1
    Gm: np.ndarray  # motor torque, gravity part
    dAm: np.ndarray | None = None  # d/dτ of Am
    dGm: np.ndarray | None = None
    singularity: np.ndarray | None = None  # (N,)
    order: np.ndarray | None = None  # the permutation that sorts ``tau`` (None: ``tau`` is sorted)


@dataclass
class MotionModel:
    """A path on a robot with its joint specs: evaluates :class:`Parts` at any τ."""

    path: CartesianPath
    robot: Any
    specs: list  # JointSpec per joint
    singularity_margin: float | None = None
    box: Any = None  # profile Box or None
    #: memo of what depends only on robot, specs, margin and box (the column plans); the planner shares one
    #: per profile between the models of successive moves
    memo: dict = field(default_factory=dict, repr=False, compare=False)
    has_drives: bool = field(init=False)
    gear: np.ndarray = field(init=False)
    eff: np.ndarray = field(init=False)
    rotor: np.ndarray = field(init=False)
    _ng: np.ndarray = field(init=False, repr=False)
    _rotor_gear: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        n = len(self.robot.joint_names)
        if len(self.specs) != n:
            raise ValueError(f"{len(self.specs)} joint specs for {n} joints")
        hit = self.memo.get("drives")  # the memo is shared per profile: the drive arrays are built once
        if hit is None:
            drives = [s.drive for s in self.specs]
            gear = np.array([d.gear_ratio if d else 1.0 for d in drives])
            eff = np.array([d.efficiency if d else 1.0 for d in drives])
            rotor = np.array([d.rotor_inertia if d else 0.0 for d in drives])
            arrays = (gear, eff, rotor, gear * eff, rotor * gear)
            for a in arrays:
                a.flags.writeable = False  # shared by every model of the profile
            hit = self.memo["drives"] = (all(d is not None for d in drives), *arrays)
        self.has_drives, self.gear, self.eff, self.rotor, self._ng, self._rotor_gear = hit

    # --------------------------------------------------------------------------------- evaluation
    def _torques(self, tau: np.ndarray, rates: bool = False, motion: tuple | None = None, singularity: bool = True):
        robot = self.robot
        p, v, a, j = motion if motion is not None else self.path.all_orders(tau)
        dA = dG = sing = None
        if hasattr(robot, "motion_and_dynamics"):  # one pass over the geometry (Delta)
            q, qd, qdd, qddd, A, G, dA, dG, sing = robot.motion_and_dynamics(p, v, a, j, rates=rates)
        else:
            q, qd, qdd, qddd = robot.joint_motion(p, v, a, j)
            full = robot.inverse_dynamics(q, qd, qdd, p, a)
            zeros = np.zeros_like(q)
            G = robot.inverse_dynamics(q, zeros, zeros, p, np.zeros_like(a))
            A = full - G
            if rates:
                dA, dG = robot.torque_rate(q, qd, qdd, qddd, p, v, a, j)
            if singularity and hasattr(robot, "singularity_measure"):
                sing = robot.singularity_measure(q, p)
        ng, rg = self._ng, self._rotor_gear  # N·η and J_rotor·N per joint
        Am = A / ng + rg * qdd
        Gm = G / ng
        dAm = dGm = None
        if rates:
            dAm = dA / ng + rg * qddd
            dGm = dG / ng
        return p, v, a, j, q, qd, qdd, qddd, A, G, Am, Gm, dAm, dGm, sing

    def parts(self, tau: np.ndarray, derivatives: bool = True, motion: tuple | None = None,
              order: np.ndarray | None = None) -> Parts:
        """Evaluate at τ; ``derivatives`` adds d/dτ of the motor torques.

        The robot's analytic ``torque_rate`` gives them when it has one; otherwise central differences of
        the model (step ``DTAU``, two more evaluations). ``motion`` = (p, v, a, j), each (N, 3) at T = 1 s,
        gives the Cartesian motion at τ directly instead of evaluating ``path`` (the batched verdict engine
        stacks many moves' samples into one call; needs the analytic rates). ``order``: the permutation that
        sorts an unsorted ``tau`` (:func:`check_grid_order`), kept in the Parts for the check."""
        tau = np.asarray(tau, float)
        analytic = derivatives and hasattr(self.robot, "torque_rate")
        if motion is not None and derivatives and not analytic:
            raise ValueError("motion= needs a robot with an analytic torque_rate")
        p, v, a, j, q, qd, qdd, qddd, A, G, Am, Gm, dAm, dGm, sing = self._torques(tau, rates=analytic, motion=motion)
        if derivatives and not analytic:
            hi = self._torques(tau + DTAU, singularity=False)
            lo = self._torques(tau - DTAU, singularity=False)
            dAm = (hi[10] - lo[10]) / (2 * DTAU)
            dGm = (hi[11] - lo[11]) / (2 * DTAU)
        return Parts(tau, p, v, a, j, q, qd, qdd, qddd, A, G, Am, Gm, dAm, dGm, sing, order)

    # ------------------------------------------------------------------------- scaled quantities
    def columns(self, parts: Parts, T: float) -> tuple[list[tuple], np.ndarray]:
        """Limited quantities at duration T as columns: (meta list, (N, n_cols) values to maximise).

        meta = (joint, quantity, unit, limit, kind, sign) where the column holds sign·value, so every
        check is "max of the column ≤ limit" (position min and singularity use sign −1). ``T`` may also be
        an (N,) array, one duration per sample (every column is computed sample by sample): the batch
        verdict engine stacks moves of different durations into one call."""
        meta, groups, perm = self._column_plan(parts.dAm is not None, parts.singularity is not None)
        if not meta:
            return meta, np.zeros((len(parts.tau), 0))
        Tc = T if np.ndim(T) == 0 else np.asarray(T)[:, None]
        # one array operation per quantity, all joints at once
        cols = [_COLUMNS[kind](parts, idx, Tc, self.gear) for kind, idx in groups]
        return list(meta), np.concatenate(cols, axis=1)[:, perm]

    def _column_plan(self, rates: bool, singularity: bool) -> tuple[list[tuple], list[tuple], np.ndarray]:
        """The columns of :meth:`columns` (memoised): meta per column in report order (joint by joint), the
        quantity groups computed for all joints at once, and the permutation from group order to meta order."""
        key = ("columns", rates, singularity)
        plans = self.memo
        if key in plans:
            return plans[key]
        entries: list[tuple] = []  # (meta, group kind, joint index or axis)
        for i, (name, unit, spec) in enumerate(zip(self.robot.joint_names, self.robot.joint_units, self.specs)):
            lim, drv = spec.limits, spec.drive
            if lim.position is not None:
                # a joint range is part of the reachable workspace: no duration fixes it (exit 4)
                entries.append(((name, "position max", unit, lim.position[1], "reach", 1.0), "position max", i))
                entries.append(((name, "position min", unit, lim.position[0], "reach", -1.0), "position min", i))
            for qname, limit, u in (
                ("velocity", lim.velocity, f"{unit}/s"),
                ("acceleration", lim.acceleration, f"{unit}/s^2"),
                ("jerk", lim.jerk, f"{unit}/s^3"),
            ):
                if limit is not None:
                    entries.append(((name, qname, u, limit, "limit", 1.0), qname, i))
            if drv is not None:
                if drv.max_speed is not None:
                    entries.append(((name, "motor speed", "rad/s", drv.max_speed, "limit", 1.0), "motor speed", i))
                if drv.peak_torque is not None:
                    entries.append(((name, "motor torque", "N·m", drv.peak_torque, "limit", 1.0), "motor torque", i))
                if drv.torque_rate is not None and rates:
                    entries.append(((name, "motor torque rate", "N·m/s", drv.torque_rate, "limit", 1.0),
                                    "motor torque rate", i))
        if self.singularity_margin is not None and singularity:
            entries.append((("tool", "singularity measure min", "1", self.singularity_margin, "reach", -1.0),
                            "singularity", 0))
        if self.box is not None:
            for c, axis in enumerate("xyz"):
                entries.append((("tool", f"workcell {axis} max", "m", self.box.max[c], "reach", 1.0), "workcell max", c))
                entries.append((("tool", f"workcell {axis} min", "m", self.box.min[c], "reach", -1.0), "workcell min", c))
        groups: list[tuple] = []
        order: list[int] = []  # entry index of each computed column, in group order
        for kind in dict.fromkeys(e[1] for e in entries):
            members = [k for k, e in enumerate(entries) if e[1] == kind]
            idx = [entries[k][2] for k in members]
            width = 3 if kind.startswith("workcell") else len(self.robot.joint_names)
            # every joint (axis) in order: a plain slice, a view instead of a gather
            groups.append((kind, slice(None) if idx == list(range(width)) else np.array(idx)))
            order += members
        position = {k: n for n, k in enumerate(order)}
        perm = np.array([position[k] for k in range(len(entries))], dtype=int)
        plans[key] = ([e[0] for e in entries], groups, perm)
        return plans[key]

    def report_plan(self, rates: bool, singularity: bool) -> _ReportPlan:
        """How :func:`check_limits` turns the columns' peaks into report rows (memoised: it depends only on
        the robot, specs, margin and box): the limits and exact-refinement bands per column, and every row
        in report order (joint by joint, its position range first, then the tool's rows)."""
        key = ("report", rates, singularity)
        if key in self.memo:
            return self.memo[key]
        meta = self._column_plan(rates, singularity)[0]
        entries: list[tuple] = []  # (joint, quantity) sort key fields, then the row plan
        ranges: dict[tuple[str, str], dict[str, int]] = {}
        for c, (joint, quantity, unit, limit, kind, sign) in enumerate(meta):
            base, _, side = quantity.rpartition(" ")
            if side in ("max", "min") and base.startswith(("position", "workcell")):
                if (joint, base) not in ranges:
                    ranges[(joint, base)] = {}
                    entries.append((joint, base, "range", None, (joint, base, unit, kind)))
                ranges[(joint, base)][side] = c
            else:
                entries.append((joint, quantity, "single", c, (joint, quantity, unit, float(limit), kind, sign < 0)))
        rows = []
        for joint, base, kind, c, spec in entries:
            if kind == "range":
                cols = ranges[(joint, base)]
                spec = (*spec, float(meta[cols["min"]][3]), float(meta[cols["max"]][3]))
                c = (cols["max"], cols["min"])
            rows.append((joint, base, kind, c, spec))
        for i, (name, spec) in enumerate(zip(self.robot.joint_names, self.specs)):
            if spec.drive is not None and spec.drive.rated_torque is not None:
                rows.append((name, "rms motor torque", "rms", i, (name, float(spec.drive.rated_torque))))
        order = {name: i for i, name in enumerate(list(self.robot.joint_names) + ["tool"])}
        rows.sort(key=lambda r: (order.get(r[0], 99), 0 if r[1].startswith("position") else 1))
        limits = np.array([m[3] * m[5] for m in meta], dtype=float)
        plan = _ReportPlan(
            limits=limits,
            band=EXACT_BAND * np.maximum(np.abs(limits), 1e-12),
            signs=np.array([m[5] for m in meta], dtype=float),
            rows=tuple((kind, c, spec) for _, _, kind, c, spec in rows),
            rms=any(r[2] == "rms" for r in rows),
        )
        self.memo[key] = plan
        return plan

    def rms_motor_torque(self, parts: Parts, T: float, dwell: float) -> np.ndarray:
        """RMS motor torque (n,) [N·m] over the duty cycle move–dwell–back–dwell (see module docstring).

        ``parts`` must be on a grid covering τ ∈ [0, 1]. When the grid holds the Gauss nodes of
        :func:`span_nodes` (the check grid and the fit grid do), the integral is Gauss–Legendre on them, so
        it does not depend on which other points the grid has; otherwise the trapezoid rule."""
        tau = parts.tau
        tm = parts.Am / T**2 + parts.Gm
        order = parts.order
        if order is None:
            w = quadrature_weights(tau, self.path.breakpoints)
            first, last = 0, -1
        else:  # an unsorted grid: the weights of the sorted one, put back in place
            w = quadrature_weights(tau[order], self.path.breakpoints)
            if w is not None:
                w[order] = w.copy()
            first, last = order[0], order[-1]
        if w is not None:
            integral = T * (w @ tm**2)
        else:
            sq = tm**2 if order is None else (tm**2)[order]
            integral = T * np.trapezoid(sq, tau if order is None else tau[order], axis=0)
        hold = parts.Gm[first] ** 2 + parts.Gm[last] ** 2
        return np.sqrt((2 * integral + dwell * hold) / (2 * T + 2 * dwell))


#: each limited quantity as columns (N, len(idx)) of the joints (or axes) ``idx``: (parts, idx, T, gear) → values
_COLUMNS = {
    "position max": lambda pr, idx, T, gear: pr.q[:, idx],
    "position min": lambda pr, idx, T, gear: -pr.q[:, idx],
    "velocity": lambda pr, idx, T, gear: np.abs(pr.qd1[:, idx]) / T,
    "acceleration": lambda pr, idx, T, gear: np.abs(pr.qdd1[:, idx]) / T**2,
    "jerk": lambda pr, idx, T, gear: np.abs(pr.qddd1[:, idx]) / T**3,
    "motor speed": lambda pr, idx, T, gear: np.abs(gear[idx] * pr.qd1[:, idx]) / T,
    "motor torque": lambda pr, idx, T, gear: np.abs(pr.Am[:, idx] / T**2 + pr.Gm[:, idx]),
    "motor torque rate": lambda pr, idx, T, gear: np.abs(pr.dAm[:, idx] / T**3 + pr.dGm[:, idx] / T),
    "singularity": lambda pr, idx, T, gear: -pr.singularity[:, None],
    "workcell max": lambda pr, idx, T, gear: pr.p[:, idx],
    "workcell min": lambda pr, idx, T, gear: -pr.p[:, idx],
}


def _parabolic_peak(x: np.ndarray, y: np.ndarray, i: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Vertex of the parabola through samples i−1, i, i+1 of each column (falls back to the sample: at an
    end of the grid, where the parabola opens upwards, or where its vertex lies below the sample)."""
    n = len(x)
    cols = np.arange(y.shape[1])
    top, at_top = y[i, cols], x[i]
    if n < 3:
        return top, at_top
    k = np.minimum(np.maximum(i, 1), n - 2)  # the middle of the three samples (i itself inside the grid)
    three = k + _NEIGHBOURS  # (3, n_cols)
    (x0, x1, x2), (y0, y1, y2) = x[three], y[three, cols]
    d1 = (y1 - y0) / (x1 - x0)
    d2 = (y2 - y1) / (x2 - x1)
    curv = (d2 - d1) / (x2 - x0)  # = a of a(x-x1)^2 + ...
    ok = (curv < 0) & (k == i)
    slope = d1 + curv * (x1 - x0)  # derivative at x1
    safe = np.where(ok, curv, -1.0)
    xv = np.minimum(np.maximum(x1 - slope / (2 * safe), x0), x2)
    yv = y1 - slope**2 / (4 * safe)
    use = ok & (yv >= top)
    return np.where(use, yv, top), np.where(use, xv, at_top)


_NEIGHBOURS = np.array([-1, 0, 1])[:, None]


def check_limits(
    model: MotionModel,
    T: float,
    tau: np.ndarray | None = None,
    parts: Parts | None = None,
    dwell: float = 0.0,
    rms_parts: Parts | None = None,
    notes: tuple[str, ...] = (),
) -> LimitReport:
    """Check every limit of ``model`` at duration ``T`` [s] → LimitReport.

    ``parts``: the model evaluated on ``tau`` (samples; computed here when None). ``rms_parts``: a grid
    covering [0, 1] for the RMS integral (defaults to ``parts``).
    """
    from .peaks import refine_max

    if parts is None:
        if tau is None:
            tau = np.linspace(0.0, 1.0, 1001)
        parts = model.parts(tau)
    x = parts.tau
    meta, data = model.columns(parts, T)
    if parts.order is not None:  # the grid is unsorted (output samples first): peaks need neighbours in τ
        x = x[parts.order]
        data = data[parts.order]
    plan = model.report_plan(parts.dAm is not None, parts.singularity is not None)
    rows: list[LimitRow] = []
    if data.shape[1]:
        imax = np.argmax(data, axis=0)
        peak, at = _parabolic_peak(x, data, imax)
        limits = plan.limits  # in column sign convention
        # refine exactly every peak near its limit or apparently beyond it (a violation is always confirmed
        # on the model itself, never taken from an interpolated estimate)
        near = np.flatnonzero((np.abs(peak - limits) <= plan.band) | (peak > limits))
        if near.size:

            def fun(s: np.ndarray) -> np.ndarray:
                pr = model.parts(np.clip(s, 0.0, 1.0), derivatives=True)
                return model.columns(pr, T)[1][:, near]

            # the exact value replaces the parabolic estimate (which can overshoot where the curvature
            # changes between samples, e.g. across a knot); it is never below the sampled maximum
            exact, exact_at = refine_max(fun, x, data[:, near])
            peak[near] = exact
            at[near] = exact_at
        values = (plan.signs * peak).tolist()
        times = (at * T).tolist()
    rms = model.rms_motor_torque(rms_parts if rms_parts is not None else parts, T, dwell) if plan.rms else None
    # the rows in report order (joint by joint, its position range first), as planned once per profile
    for kind, c, spec in plan.rows:
        if kind == "single":
            joint, quantity, unit, limit, reach, lower = spec
            value = values[c]
            if lower:  # a minimum that must stay above the limit (singularity measure)
                util = limit / value if value > 0 else float("inf")
                rows.append(LimitRow(joint, quantity, unit, value, limit, util, times[c], value >= limit, reach, "lower"))
            else:
                rows.append(LimitRow(joint, quantity, unit, value, limit, value / limit, times[c], value <= limit, reach))
        elif kind == "range":
            rows.append(_range_row(spec, values[c[0]], values[c[1]], times[c[0]], times[c[1]]))
        else:  # RMS over the duty cycle
            joint, lim = spec
            r = float(rms[c])
            rows.append(LimitRow(joint, "rms motor torque", "N·m", r, lim, r / lim, None, r <= lim))
    return LimitReport(tuple(rows), T, dwell, notes)


def _range_row(spec: tuple, vmax: float, vmin: float, tmax: float, tmin: float) -> LimitRow:
    """One row for a [min, max] range: the side nearer its bound; utilisation = |x − mid| / half-range."""
    joint, base, unit, kind, lo, hi = spec
    mid, half = (lo + hi) / 2, (hi - lo) / 2
    u_hi, u_lo = (vmax - mid) / half, (mid - vmin) / half
    ok = vmax <= hi + 1e-12 and vmin >= lo - 1e-12
    if u_hi >= u_lo:
        return LimitRow(joint, base, unit, vmax, hi, u_hi, tmax, ok, kind, "upper")
    return LimitRow(joint, base, unit, vmin, lo, u_lo, tmin, ok, kind, "lower")


def reach_error(exc: UnreachableError, tau: np.ndarray, T: float | None) -> UnreachableError:
    """Re-raise an IK failure with the time of the failing sample (or its fraction of the move)."""
    if exc.index is None:
        return exc
    s = float(tau[exc.index])
    when = f"t = {s * T:.6g} s" if T else f"τ = {s:.4f} of the move"
    return UnreachableError(f"{exc} at {when}", index=exc.index)
