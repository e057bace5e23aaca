"""The joint motion of a path on a robot (:class:`MotionModel`), evaluated at any normalised time τ.

Everything a limit depends on is a function of normalised time τ that scales *exactly* with the duration
T (for a fixed path):

    q(τ)                       joint position                      (independent of T)
    q̇ = q̇₁/T,  q̈ = q̈₁/T²,  q⃛ = q⃛₁/T³   (q̇₁ … : the motion at T = 1 s)
    joint torque  = A(τ)/T² + G(τ)         A: inertial (+ Coriolis, ∝ q̇²) part at T = 1, G: gravity
    motor torque  = A_m/T² + G_m            A_m = A/(N·η) + J_rotor·N·q̈₁,  G_m = G/(N·η)
    motor speed   = N·q̇₁/T
    torque rate   = A_m′/T³ + G_m′/T         (′ = d/dτ: the robot's analytic torque_rate)

so one evaluation of the model serves every T (``--time fit`` is a 1-D root search, not a re-plan).

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

from ..model.errors import UnreachableError
from ..model.trajectory import CartesianPath
from .grid import DTAU, adaptive_gk15, span_nodes
from .report import _ReportPlan

#: peaks within this fraction of their limit are refined exactly (golden section on the model)
EXACT_BAND = 0.05


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

    def sorted(self) -> "Parts":
        """These parts with ``tau`` in increasing order (``self`` when it is already)."""
        if self.order is None:
            return self
        o = self.order
        take = {name: (None if getattr(self, name) is None else getattr(self, name)[o])
                for name in ("tau", "p", "v1", "a1", "j1", "q", "qd1", "qdd1", "qddd1", "A", "G", "Am", "Gm", "dAm",
                             "dGm", "singularity")}
        return Parts(**take)


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
    _rms: tuple | None = field(default=None, init=False, repr=False, compare=False)

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
        p, v, a, j = motion[:4] if motion is not None else self.path.all_orders(tau)
        dA = dG = sing = None
        if getattr(robot, "rotary", False):  # a fourth axis: the tool angle's law joins the motion (None: θ ≡ 0)
            angle = motion[4] if motion is not None and len(motion) > 4 else self.path.angle_orders(tau)
            q, qd, qdd, qddd, A, G, dA, dG, sing = robot.motion_and_dynamics(p, v, a, j, rates=rates, angle=angle,
                                                                             singularity=singularity)
        elif hasattr(robot, "motion_and_dynamics"):  # one pass over the geometry (Delta)
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
              order: np.ndarray | None = None, singularity: bool = True) -> Parts:
        """Evaluate at τ; ``derivatives`` adds d/dτ of the motor torques.

        The robot's analytic ``torque_rate`` gives them when it has one; otherwise central differences of
        the model (step ``DTAU``, two more evaluations). ``motion`` = (p, v, a, j), each (N, 3) at T = 1 s,
        gives the Cartesian motion at τ directly instead of evaluating ``path`` (the batched verdict engine
        stacks many moves' samples into one call; needs the analytic rates); a fifth entry, the tool angle's
        θ, θ′, θ″, θ‴ (4, N), goes to a robot with a rotary fourth axis (without it: the path's angle law).
        ``order``: the permutation that sorts an unsorted ``tau`` (:func:`check_grid_order`), kept in the Parts.
        ``singularity=False`` skips the singularity measure (and its column)."""
        tau = np.asarray(tau, float)
        analytic = derivatives and hasattr(self.robot, "torque_rate")
        if motion is not None and derivatives and not analytic:
            raise ValueError("motion= needs a robot with an analytic torque_rate")
        p, v, a, j, q, qd, qdd, qddd, A, G, Am, Gm, dAm, dGm, sing = self._torques(tau, rates=analytic, motion=motion, singularity=singularity)
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
            zoom=np.array([c for c, m in enumerate(meta) if m[4] == "limit"], dtype=int),
            zoom_sub=np.array([c for c, m in enumerate(self._column_plan(rates, False)[0]) if m[4] == "limit"], dtype=int),
        )
        self.memo[key] = plan
        return plan

    def _first_round(self, parts: "Parts | None", nodes: np.ndarray, integrand) -> np.ndarray | None:
        """The integrand at the nodes of the RMS integral's first round, read off ``parts`` when its grid
        holds them all (within 1e-9 in τ: the check and fit grids do) and its ends τ = 0, 1; else None."""
        if parts is None:
            return None
        tau = parts.tau if parts.order is None else parts.tau[parts.order]
        if len(tau) < 2 or tau[0] != 0.0 or tau[-1] != 1.0:
            return None
        i = np.minimum(np.maximum(np.searchsorted(tau, nodes), 1), len(tau) - 1)
        i = np.where(np.abs(tau[i - 1] - nodes) < np.abs(tau[i] - nodes), i - 1, i)
        if np.abs(tau[i] - nodes).max() > 1e-9:
            return None
        if parts.order is not None:
            i = parts.order[i]
            ends = parts.order[[0, -1]]
        else:
            ends = np.array([0, len(tau) - 1])
        Am, Gm = parts.Am[i], parts.Gm[i]
        integrand.ends.append(parts.Gm[ends].copy())
        return np.concatenate([Am * Am, Am * Gm, Gm * Gm], axis=1)

    def rms_integrals(self, parts: "Parts | None" = None) -> tuple[np.ndarray, np.ndarray]:
        """The T-independent parts of the RMS motor torque (memoised per model): (I (3, n), G_end (2, n)).

        I = [∫A_m², ∫A_m·G_m, ∫G_m²] dτ over τ ∈ [0, 1] per joint, by adaptive Gauss–Kronrod (7/15 points)
        on the path's spans (:func:`adaptive_gk15`, relative tolerance ``RMS_RTOL``), so the integral is
        exact to round-off whatever the shape of the torque inside a span (a PH corner concentrates its
        curvature in a few percent of the move: a fixed rule per span misses it); G_end = G_m at τ = 0, 1
        (the holding torques of the two dwells). ``parts``: the model on a grid holding the first round's
        nodes (:func:`span_nodes`), which then need no evaluation of their own."""
        if self._rms is None:
            path = self.path
            n = len(self.robot.joint_names)
            ends: list[np.ndarray] = []

            def integrand(tau: np.ndarray) -> np.ndarray:
                try:
                    out = self._torques(np.concatenate([tau, [0.0, 1.0]]) if not ends else tau, singularity=False)
                except UnreachableError as exc:
                    s = float(tau[exc.index]) if exc.index is not None and exc.index < len(tau) else None
                    where = f" at τ = {s:.6f} of the move" if s is not None else ""
                    raise UnreachableError(f"{exc}{where}") from None
                Am, Gm = out[10], out[11]
                if not ends:
                    ends.append(Gm[-2:].copy())
                    Am, Gm = Am[:-2], Gm[:-2]
                return np.concatenate([Am * Am, Am * Gm, Gm * Gm], axis=1)

            integrand.ends = ends  # type: ignore[attr-defined]
            edges, nodes = span_nodes(path.breakpoints, path.jumps)
            total = adaptive_gk15(integrand, edges, n, first=self._first_round(parts, nodes, integrand))
            self._rms = (total.reshape(3, n), ends[0])
        return self._rms

    def rms_motor_torque(self, T: float | np.ndarray, dwell: float, parts: "Parts | None" = None) -> np.ndarray:
        """RMS motor torque [N·m] over the duty cycle move–dwell–back–dwell (module docstring), (n,) per
        joint; ``T`` [s] may be an array (shape (..., n) then). Exact for every T from one integration:
        ∫₀ᵀ (A_m/T² + G_m)² dt = T·(I_AA/T⁴ + 2·I_AG/T² + I_GG) (:meth:`rms_integrals`)."""
        integrals, ends = self.rms_integrals(parts)
        return duty_cycle_rms(integrals, ends, np.asarray(T, float)[..., None], dwell)


def duty_cycle_rms(integrals: np.ndarray, ends: np.ndarray, T, dwell: float) -> np.ndarray:
    """RMS motor torque [N·m] over the duty cycle move–dwell–back–dwell (module docstring) from the RMS integrals
    (:meth:`MotionModel.rms_integrals`: ``integrals`` (..., 3, n), ``ends`` (..., 2, n), one move or many) at the
    durations ``T`` [s] (broadcast against (..., n)): ∫₀ᵀ (A_m/T² + G_m)² dt = T·(I_AA/T⁴ + 2·I_AG/T² + I_GG)."""
    integrals, ends = np.asarray(integrals), np.asarray(ends)
    iaa, iag, igg = integrals[..., 0, :], integrals[..., 1, :], integrals[..., 2, :]
    move = T * (iaa / T**4 + 2.0 * iag / T**2 + igg)
    hold = ends[..., 0, :] ** 2 + ends[..., 1, :] ** 2
    return np.sqrt(np.maximum(2.0 * move + dwell * hold, 0.0) / (2.0 * T + 2.0 * dwell))


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


#: the motor quantities ``plot --motors`` draws as % of their limits
MOTOR_QUANTITIES = ("motor speed", "motor torque", "motor torque rate")


def limit_use(model, T: float, tau: np.ndarray, quantities: tuple[str, ...] = MOTOR_QUANTITIES,
              dwell: float = 0.0) -> tuple[list[tuple[str, str, np.ndarray]], list[tuple[str, float]]]:
    """How hard the motors work along the move at duration T [s]: ([(joint, quantity, |value| / limit · 100 on
    ``tau``)] for every limited column among ``quantities``, [(joint, RMS motor torque over the round trip
    with ``dwell`` [s] / rated · 100)] for every joint with a rated torque)."""
    parts = model.parts(np.asarray(tau, float))
    meta, data = model.columns(parts, T)
    curves = [(m[0], m[1], 100.0 * data[:, c] / m[3]) for c, m in enumerate(meta) if m[1] in quantities]
    rms = []
    rated = [s.drive.rated_torque if s.drive is not None else None for s in model.specs]
    if any(r for r in rated):
        values = model.rms_motor_torque(T, dwell)
        rms = [(name, 100.0 * float(v) / r) for name, v, r in zip(model.robot.joint_names, values, rated) if r]
    return curves, rms
