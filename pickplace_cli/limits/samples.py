"""The continuous motion a file of samples describes, and its limit report: the reading ``check`` runs a trajectory
file through, and ``plan`` the samples it writes (so that a plan whose samples ``check`` would refuse is re-timed
before it is called ok).

* **Reconstruction.** Positions go through forward kinematics to the tool path; the motion between samples is the
  septic Hermite polynomial through the file's tool positions, velocities, accelerations and jerks when the file has
  them and they agree with its positions (:func:`derivative_problems`), else a quintic spline of the positions
  (interpolating, or smoothing with ``smoothing`` > 0), split at the jerk steps found in the data
  (:mod:`pickplace_cli.curves.sampled`). It runs through the same joint mapping, dynamics and limit check as
  ``plan``.
* **Accuracy.** Every duration-dependent peak is estimated twice, from all samples and from every other one; their
  difference (over the reconstruction's order of convergence) is its stated accuracy, at least ``CHECK_RESOLUTION``.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..model.errors import TaskError
from .check import _range_row, capacity_rows, check_limits
from .grid import check_grid
from .motion import MotionModel
from .report import RESOLVED, LimitReport
from ..model.headroom import limit_specs
from ..model.profile import Profile
from ..robots import build_robot
from ..model.trajectory import CartesianPath

#: the largest disagreement, per derivative order (1 velocity, 2 acceleration, 3 jerk), of a derivative column with
#: the change over an interval of the column it is the derivative of, relative to the interval times the larger peak
#: of the two: plan's files at 100 Hz to 4 kHz, every method, stay below 2.8e-3, 5.1e-2 and (median) 9.2e-3 (one
#: time-optimal superposition law at 100 Hz: 0.27, judged from its positions); a column set to zero, left from another
#: timing or in other units is off by 0.3 to 1
AGREE = {1: 1e-2, 2: 1e-1, 3: 5e-2}
#: a velocity or acceleration column off its positions by one factor everywhere (a file re-timed without its derivative
#: columns, a column in another unit or scale) hides inside ``AGREE`` and biases every peak read from it: the factor s
#: that best fits the predicted changes to the measured ones (least squares over the intervals without a jerk step)
#: counts when |s − 1| is above ``SCALE_TOL`` and ``SCALE_SIG`` times what the misfit left over allows (|s − 1|·‖pred‖
#: over the residual's norm: ≤ 1.7 on plan's own files of every method at 25 Hz-5 kHz, where the misfit is the
#: interpolation's; 470-8 500 for a file re-timed 0.9 % faster or with its accelerations 7 % low)
SCALE_TOL = 2e-4
SCALE_SIG = 10.0
#: names of the tool's derivative columns per order
ORDER_COLUMNS = {1: "vx, vy, vz", 2: "ax, ay, az", 3: "jx, jy, jz"}
#: a joint position in the file may differ from the model's inverse kinematics of its own forward
#: kinematics by this much (rad or m) before it counts as another branch. FK∘IK round trips to ~1e-12 and
#: the CSV carries 12 digits; 1e-3 still separates real branch changes (an elbow flipped, a Delta arm
#: folded in: tenths of a radian and more) and does not trip on a pose within 1e-3 of a singularity, where
#: the singularity row reports the problem instead.
BRANCH_TOL = 1e-3
#: the finest accuracy ``check`` claims for a peak estimated from samples, relative to the peak: the values of a file
#: carry 12 significant digits, a reconstruction's third derivative amplifies their round-off, and a plan's peak sits at
#: its limit to ~1e-7; a file run 1 % faster moves every timed peak by 1 % or more
CHECK_RESOLUTION = 1e-3
#: the change of a peak when every other sample is dropped, over this, is the septic Hermite's accuracy: (2⁵ − 1)/2,
#: its third derivative converging as h⁵, with a factor 2 of safety
HERMITE_DIVISOR = 15.5
#: the file's x, y, z may differ from FK of its joint positions by this much [m] (12 significant digits: ~1e-12)
TOOL_TOL = 1e-7
#: a file without a move column whose last joint positions are its first to this [rad or m] returns to its start:
#: it is one whole duty cycle (a round trip or belt cycle written as one table, a recording of a cycle), and the RMS
#: torque is taken over the file itself, no dwell and no move back added (a one-way move's ends lie far apart)
CLOSED_TOL = 1e-6
#: the note that says so (the verdict's cycle line then gives the file's duration as the duty cycle)
CLOSED_NOTE = "it ends where it starts: one whole duty cycle, the RMS torque taken over the file (no dwell added)"

@dataclass(frozen=True)
class Samples:
    """One move of a trajectory file: ``move`` its number in the file's move column (None: no such column),
    ``t`` (N,) s and ``q`` (N, n) as in the file, ``lines`` (N,) the 1-based file line of every sample,
    ``rest`` how many trailing samples at rest were set aside (see the module docstring) and ``last_line``
    the file line of the move's last row (with them)."""

    move: int | None
    t: np.ndarray
    q: np.ndarray
    lines: np.ndarray
    rest: int
    last_line: int
    #: (N, 12) the tool's x, y, z [m], vx … [m/s], ax … [m/s²], jx … [m/s³] when the file has all of them (this
    #: tool's CSV does), else None
    tool: np.ndarray | None = None

    def where(self, source: str) -> str:
        name = f"move {self.move}" if self.move is not None else "the trajectory"
        return f"{source}: {name} (lines {int(self.lines[0])}–{self.last_line})"


def _interval_misfit(lo: np.ndarray, hi: np.ndarray, hi2: np.ndarray | None, h: np.ndarray) -> np.ndarray:
    """Per interval: |Δlo − h·(hi₀ + hi₁)/2 − h²·(hi2₀ − hi2₁)/12| over h · the larger peak of |hi| and |Δlo/h|."""
    pred = h * (hi[1:] + hi[:-1]) / 2
    if hi2 is not None:
        pred = pred + h * h * (hi2[:-1] - hi2[1:]) / 12
    d = np.diff(lo, axis=0)
    with np.errstate(over="ignore", invalid="ignore"):
        scale = max(float(np.abs(hi).max()), float((np.abs(d) / h).max()), 1e-300)
        out = np.abs(d - pred).max(axis=1) / (h[:, 0] * scale)
    return np.where(np.isfinite(out), out, np.inf)


def _scale_fit(lo: np.ndarray, hi: np.ndarray, hi2: np.ndarray, h: np.ndarray, keep: np.ndarray) -> tuple[float, float]:
    """(s, significance): the factor s of the derivative columns ``hi`` (with ``hi2`` in the end correction) that best
    fits their predicted changes to the measured changes of ``lo`` on the intervals ``keep`` (least squares), and
    |s − 1|·‖pred‖ over the norm of what is left (a misfit of the interpolation varies in sign and leaves the
    significance about 1 or below; one factor off everywhere leaves little: hundreds and more)."""
    pred = (h * (hi[1:] + hi[:-1]) / 2)[keep].ravel()
    meas = (np.diff(lo, axis=0) - h * h * (hi2[:-1] - hi2[1:]) / 12)[keep].ravel()
    nn = float(pred @ pred)
    if not (nn > 0 and np.isfinite(nn)):
        return 1.0, 0.0
    s = float(pred @ meas) / nn
    left = float(np.linalg.norm(meas - s * pred))
    return s, abs(s - 1.0) * nn**0.5 / max(left, 1e-300)


def derivative_problems(t: np.ndarray, tool: np.ndarray) -> list[tuple[int, float]]:
    """(order, misfit) of each of the tool's derivative columns (``tool`` (N, 12): x … jz) that does not agree with its
    positions (module docstring), and (order, −s) for a velocity or acceleration column off them by one factor s
    (``SCALE_TOL``: the misfit's test allows it); [] when all agree."""
    from ..curves.sampled import _jerk_jumps

    t = np.asarray(t, float)
    h = np.diff(t)[:, None]
    p, v, a, j = tool[:, 0:3], tool[:, 3:6], tool[:, 6:9], tool[:, 9:12]
    fits = {1: float(np.max(_interval_misfit(p, v, a, h))), 2: float(np.max(_interval_misfit(v, a, j, h))),
            3: float(np.median(_interval_misfit(a, j, None, h)))}
    out = [(k, m) for k, m in fits.items() if not m <= AGREE[k]]
    if len(t) >= 6:
        keep = np.ones(len(h), bool)
        keep[_jerk_jumps(j)] = False  # (the rule's own misfit across a jerk step is up to half the step)
        for k, (lo, hi, hi2) in ((1, (p, v, a)), (2, (v, a, j))):
            s, sig = _scale_fit(lo, hi, hi2, h, keep)
            if fits[k] <= AGREE[k] and abs(s - 1.0) > SCALE_TOL and sig > SCALE_SIG:
                out.append((k, -s))
    return sorted(out)


def describe_problems(problems: list[tuple[int, float]]) -> str:
    """One clause naming the columns that disagree and by how much (a misfit, or one factor off: a negative entry)."""
    words = {1: "every interval", 2: "every interval", 3: "the median interval"}

    def one(k: int, m: float) -> str:
        if m < 0:
            return (f"{ORDER_COLUMNS[k]} say {100 * abs(-m - 1):.3g} % {'less' if -m > 1 else 'more'} than the "
                    f"positions' changes, by one factor everywhere (the changes are {-m:.6g} × theirs: a file re-timed "
                    f"without them, or another unit; allowed {100 * SCALE_TOL:g} %)")
        return (f"{ORDER_COLUMNS[k]} disagree with the positions by {100 * m:.3g} % of their peak on {words[k]} "
                f"(allowed {100 * AGREE[k]:g} %)")

    return "; ".join(one(k, m) for k, m in problems)


def closed_cycle(q: np.ndarray) -> bool:
    """Whether joint positions ``q`` (N, n) [rad or m] end where they start (``CLOSED_TOL``)."""
    q = np.asarray(q, float)
    return len(q) > 2 and bool(np.max(np.abs(q[-1] - q[0])) <= CLOSED_TOL)


def _check_branch(s: Samples, robot, pos: np.ndarray, source: str) -> None:
    """TaskError when the file's joint positions are not the model's configuration (module docstring)."""
    rotary = getattr(robot, "rotary", False)  # a fourth axis: the model's q4 for the file's own tool angle
    q_model = robot.inverse_kinematics(pos, robot.tool_angle(s.q)) if rotary else robot.inverse_kinematics(pos)
    diff = s.q - q_model
    revolute = np.array([u == "rad" for u in robot.joint_units])
    turns = np.where(revolute, 2 * np.pi * np.round(diff / (2 * np.pi)), 0.0)
    off = np.abs(diff - turns)
    if rotary and np.max(off[:, :-1]) > BRANCH_TOL:  # the arm's branch: name its joint (q4 follows from it)
        off[:, -1] = 0.0
    if np.max(off) > BRANCH_TOL:
        k = int(np.flatnonzero(np.max(off, axis=1) > BRANCH_TOL)[0])  # the first such row
        j = int(np.argmax(off[k]))
        name, unit = robot.joint_names[j], robot.joint_units[j]
        p = ", ".join(f"{c:.6g}" for c in pos[k])
        raise TaskError(
            f"{source}:{s.lines[k]}: {name} = {s.q[k, j]:.6g} {unit} is another configuration than the profile's "
            f"model: for the same tool position ({p}) m its inverse kinematics gives {name} = {q_model[k, j]:.6g} "
            f"{unit}; check the profile (e.g. the SCARA's robot.elbow), the joint order and the units"
        )


def _motion_report(t: np.ndarray, pos: np.ndarray, robot, profile: Profile, smoothing: float, source: str,
                   notes=None, tool: np.ndarray | None = None, rebuilt=None, not_held: str = "",
                   dwell: float | None = None, whole: np.ndarray | None = None):
    """The limit report of the tool positions ``pos`` (N, 3) m (and angle, rad, a 4th column with a rotary axis) at
    ``t`` (N,) s from 0, through a reconstruction of
    the continuous motion (an interpolating spline split at the jerk steps found in the data,
    :func:`~pickplace_cli.curves.sampled.reconstruct`, or a smoothing spline), and the words that say how the
    derivatives were found. ``notes``: a function of those words → the report's notes. ``tool`` (N, 12): the
    file's own tool positions, velocities, accelerations and jerks (consistent with ``pos``), through which the
    motion between samples is the septic Hermite interpolant (exact at every sample up to the jerk). ``rebuilt``:
    (evaluate(x, order), the times of its steps [s], the words) of a motion already rebuilt (a table). The tool's
    Cartesian capacity rows come from the same continuous motion (:func:`capacity_rows` on the check's grid);
    ``not_held``: why they are not held ("" when they are: they then decide the verdict with the others).
    ``dwell`` [s]: the duty cycle's dwell for the RMS torque (None: the profile's; 0 for a whole cycle).
    ``whole``: intervals the septic Hermite is not split in whatever its overshoot (:func:`_read_motion`)."""
    from scipy.interpolate import UnivariateSpline

    T = float(t[-1])
    rotary = pos.shape[1] == 4  # the tool angle θ (a rotary fourth axis) as one more column
    extra = " and angle" if rotary else ""
    if rebuilt is not None:
        ev, steps, how = rebuilt
    elif tool is not None and not smoothing:
        from ..curves.sampled import hermite, reconstruct

        ev3, steps = hermite(t, tool[:, 0:3], tool[:, 3:6], tool[:, 6:9], tool[:, 9:12], whole=whole)
        how = ("septic Hermite polynomials through the file's tool positions, velocities, accelerations and jerks "
               "(x … jz; x, y, z agree with FK(q))")
        ev = ev3
        if rotary:  # the angle has no derivative columns: its interpolating spline, split at its own steps
            spline_angle, angle_steps = reconstruct(t, pos[:, 3:4])
            steps = np.union1d(steps, angle_steps)
            how += ", and a quintic interpolating spline of the tool angle"

            def ev(x: np.ndarray, order: int) -> np.ndarray:
                return np.column_stack([ev3(x, order), spline_angle(x, order)])

            ev.position, ev.angle = ev3, lambda x, order: spline_angle(x, order)[:, 0]  # (each alone, not both)

        if steps.size:
            shown = ", ".join(f"{x:.5g}" for x in steps[:6]) + (" …" if steps.size > 6 else "")
            how += f", split at the jerk steps found between samples at t = {shown} s ({steps.size}; both sides checked)"
    elif smoothing > 0:
        splines = [UnivariateSpline(t, pos[:, k], k=5, s=smoothing * len(t)) for k in range(pos.shape[1])]

        def ev(x: np.ndarray, order: int) -> np.ndarray:
            return np.column_stack([sp.derivative(order)(x) if order else sp(x) for sp in splines])

        how = f"a quintic smoothing spline (s = {smoothing:g}·N) of the tool positions FK(q){extra}"
        steps = np.zeros(0)
    else:
        from ..curves.sampled import reconstruct

        ev, steps = reconstruct(t, pos)
        how = f"a quintic interpolating spline of the tool positions FK(q){extra}"
        if steps.size:
            shown = ", ".join(f"{x:.5g}" for x in steps[:6]) + (" …" if steps.size > 6 else "")
            how += (f", one per stretch between the jerk steps found in the data at t = {shown} s ({steps.size}; both "
                    "sides checked)")

    # the positions and the angle each from their own interpolant where they have one (the septic Hermite and the
    # angle's spline), not both evaluated for either
    ev_position = getattr(ev, "position", lambda x, order: ev(x, order)[:, :3])
    ev_angle = getattr(ev, "angle", lambda x, order: ev(x, order)[:, 3])

    def evaluate(tau: np.ndarray, order: int) -> np.ndarray:
        return ev_position(np.clip(tau, 0.0, 1.0) * T, order) * T**order

    angle = None
    if rotary:
        from ..curves.rotation import SampledRotation

        angle = SampledRotation(lambda tau, order: ev_angle(np.clip(tau, 0.0, 1.0) * T, order) * T**order)
    # the pieces join across the samples to the interpolation error: nothing jumps there, peaks are fitted across
    # them; at a jerk step found in the data the check takes both one-sided values (never across it)
    jumps = steps / T
    cpath = CartesianPath(evaluate, "checked", {"source": source}, (0.0, 0.0, 0.0),
                          np.sort(np.concatenate([t / T, jumps])), jumps=jumps, angle=angle)
    margin = getattr(profile.robot, "singularity_margin", None)
    model = MotionModel(cpath, robot, limit_specs(profile), margin, profile.workcell.box)
    grid = check_grid(t / T, cpath.breakpoints, jumps=jumps)
    if steps.size and rebuilt is None:
        how += "; the change across each step over its sample interval counts as a rate"
    report = check_limits(model, T, parts=model.parts(grid), dwell=profile.planning.dwell if dwell is None else dwell,
                          notes=() if notes is None else notes(how))
    report = report.with_rows(capacity_rows(cpath, T, profile.capacity, not_held, grid=grid))
    if steps.size and rebuilt is None:
        report = _across_steps(report, model, cpath, t, pos)
    return report, how


#: how a reconstruction's steps are judged (the note's words): the pieces either side of a step found in the data are
#: fitted apart, so their positions, velocities, accelerations and torques need not meet there. A jerk step leaves them
#: continuous; a jump of position, a velocity step or an acceleration step (a torque step) does not, and neither side
#: alone shows it. So around every step the samples themselves bound the motion, whatever it does between them (the
#: mean value theorem for divided differences): over the interval [t_k, t_k+1] that holds the step the speed reaches
#: |q(t_k+1) − q(t_k)| / (t_k+1 − t_k); over each three samples spanning it the acceleration reaches 2·|q[t_i, t_i+1,
#: t_i+2]| (that divided difference is the mean of q̈ under a B-spline weight of unit mass), for the joints and the
#: tool alike; the motor torque reaches its mean under that weight, the torque of the mean acceleration at the middle
#: sample (gravity and the velocity terms barely change over two intervals); the torque rate reaches the change of
#: those means between the two windows over their distance, and the one-sided torques' change across the step over
#: its interval; the jerk likewise from the one-sided accelerations. The positions' rounding (12 digits, or the
#: file's own resolution: half its smallest step) is taken off each difference first. These bounds join the joints',
#: the motors' and the capacity's rows
STEP_RATE = "the change across each step over its sample interval"
#: a bound around a step replaces its row's reading only when it is this share above it: the torque's bounds take the
#: torque of a mean acceleration for its mean (within ~1 % where the motion changes fastest, at 50 kHz at the start of
#: a time-optimal law); the steps they are for (a jump, a kink, a stop) read many times their limit
STEP_MARGIN = 0.05


def _joints_at(model: MotionModel, pos: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """The joint positions of the tool's positions ``pos`` (N, 3) [m] (a 4th column: the tool angle [rad]) at ``tau``."""
    z = np.zeros((len(pos), 3))
    motion: tuple = (pos[:, :3], z, z, z)
    if pos.shape[1] == 4:
        motion += (np.stack([pos[:, 3], np.zeros(len(pos)), np.zeros(len(pos)), np.zeros(len(pos))]),)
    return model.parts(tau, derivatives=False, singularity=False, motion=motion).q


def _noise(x: np.ndarray) -> np.ndarray:
    """Per column of samples ``x`` (N, d): how far rounding may move a value, the larger of 1e-12 of the column's
    largest magnitude (12 significant digits) and half its smallest nonzero step (a file in counts or microns)."""
    d = np.abs(np.diff(x, axis=0))
    d = np.where(d > 0, d, np.inf)
    small = np.min(d, axis=0, initial=np.inf)
    return np.maximum(1e-12 * np.max(np.abs(x), axis=0), np.where(np.isfinite(small), small / 2, 0.0))


def _across_steps(report: LimitReport, model: MotionModel, cpath, t: np.ndarray, pos: np.ndarray) -> LimitReport:
    """``report`` with each row of a speed, acceleration, torque, torque rate or jerk (joints, motors, the tool's
    capacity) at least its bound around every interior step of the reconstruction ``cpath`` of the samples at ``t``
    [s] of the tool's positions ``pos`` (N, 3) [m] (and angle [rad], a 4th column with a rotary axis)
    (:data:`STEP_RATE`)."""
    from .grid import interior_jumps, jump_sides
    from .report import LimitRow

    T = float(t[-1])
    N = len(t)
    sides = jump_sides(cpath.breakpoints, cpath.jumps)  # (every interior jump's left sides, then its right sides)
    n = len(sides) // 2
    if not n or N < 4:
        return report
    steps = interior_jumps(cpath.breakpoints, cpath.jumps) * T  # the steps inside the move, as the sides are
    k = np.clip(np.searchsorted(t, steps), 1, N - 1)  # the step lies in [t[k − 1], t[k]]
    h = (t[k] - t[k - 1])[:, None]
    pr = model.parts(sides, derivatives=False, singularity=False)
    torque = pr.Am / T**2 + pr.Gm
    # the samples from two before the step's interval to two after it, as the file gives them (never a piece's value:
    # a step found at a sample's own time puts that sample on the other piece), the joints by the inverse kinematics
    idx = np.clip(k[:, None] + np.arange(-3, 4)[None, :], 0, N - 1)  # (n, 7): k−3 … k+3
    q_all = _joints_at(model, pos, t / T)
    tq, q, p = t[idx], q_all[idx], pos[idx][..., :3]  # (n, 7), (n, 7, joints), (n, 7, 3)
    revolute = np.array([u == "rad" for u in model.robot.joint_units])
    nq, np_ = _noise(q_all), _noise(pos[:, :3])

    def unwrap(d):
        d = d.copy()
        d[..., revolute] = (d[..., revolute] + np.pi) % (2 * np.pi) - np.pi  # (an angle's wrap is no motion)
        return d

    # speeds over the step's interval [k − 1, k] and the one each side of it (a step found at a sample's time may
    # belong to either interval that meets there)
    vq = vp = 0.0
    for c in (1, 2, 3):
        dt1 = np.maximum(tq[:, c + 1] - tq[:, c], 1e-300)[:, None]
        vq = np.maximum(vq, np.maximum(np.abs(unwrap(q[:, c + 1] - q[:, c])) - 2 * nq, 0.0) / dt1)
        vp = np.maximum(vp, np.maximum(np.linalg.norm(p[:, c + 1] - p[:, c], axis=1) - 2 * np.linalg.norm(np_), 0.0)
                        / dt1[:, 0])
    # accelerations: every window of three samples that holds one of those intervals (k−3 … k+3)
    acc_q, acc_p, means = [], [], []
    ang = pos[idx][..., 3] if pos.shape[1] == 4 else None  # the tool angle [rad] (a rotary fourth axis)
    for w in (0, 1, 2, 3, 4):
        t0, t1, t2 = tq[:, w], tq[:, w + 1], tq[:, w + 2]
        real = (t1 > t0) & (t2 > t1)  # (a window the move's ends clip has repeated samples: no bound)
        d01, d12 = np.where(real, t1 - t0, 1.0)[:, None], np.where(real, t2 - t1, 1.0)[:, None]
        span = d01 + d12

        def second(x, noise):  # 2·x[t0, t1, t2] less the rounding's share, per component
            a = 2 * ((x[:, w + 2] - x[:, w + 1]) / d12 - (x[:, w + 1] - x[:, w]) / d01) / span
            return np.where(real[:, None], np.sign(a) * np.maximum(np.abs(a) - 4 * noise / (d01 * d12), 0.0), 0.0)

        acc_q.append(second(np.stack([unwrap(q[:, c] - q[:, w + 1]) for c in range(q.shape[1])], axis=1), nq))
        ap = second(p, np_)
        acc_p.append(np.linalg.norm(ap, axis=1))
        vmid = (p[:, w + 2] - p[:, w]) / span
        motion: tuple = (p[:, w + 1], vmid * T, ap * T**2, np.zeros_like(ap))
        if ang is not None:  # the angle's own mean acceleration over the window
            th = ang[..., None]
            motion += (np.stack([ang[:, w + 1], (ang[:, w + 2] - ang[:, w]) / span[:, 0] * T,
                                 second(th, np.array([1e-12]))[:, 0] * T**2, np.zeros(len(ang))]),)
        mid = model.parts(t1 / T, derivatives=False, singularity=False, motion=motion)
        means.append((np.where(real[:, None], mid.Am / T**2 + mid.Gm, 0.0), t1, real))
    # (two windows' means: both real, one sample apart)
    rate = np.max([np.where((r1 & r2 & (c2 > c1))[:, None], np.abs(m2 - m1), 0.0) / np.maximum(c2 - c1, 1e-300)[:, None]
                   for (m1, c1, r1), (m2, c2, r2) in zip(means[:-1], means[1:])], axis=0)
    gear = np.array([s.drive.gear_ratio if s.drive is not None else 1.0 for s in model.specs])
    joints = {"velocity": vq, "motor speed": vq * gear, "acceleration": np.max(np.abs(acc_q), axis=0),
              "motor torque": np.max([np.abs(m) for m, _, _ in means], axis=0),
              "motor torque rate": np.maximum(np.abs(torque[n:] - torque[:n]) / h, rate),
              "jerk": np.abs(pr.qdd1[n:] - pr.qdd1[:n]) / T**2 / h}
    acc3 = cpath.all_orders(sides)[2][:, :3] / T**2
    tool = {"capacity speed": vp, "capacity acceleration": np.max(acc_p, axis=0),
            "capacity jerk": np.linalg.norm(acc3[n:] - acc3[:n], axis=1) / h[:, 0]}
    names = list(model.robot.joint_names)
    rows = []
    for r in report.rows:
        if r.quantity in joints and r.joint in names:
            col = joints[r.quantity][:, names.index(r.joint)]
        elif r.joint == "tool" and r.quantity in tool:
            col = tool[r.quantity]
        else:
            rows.append(r)
            continue
        i = int(np.argmax(col))
        if col[i] > (1.0 + STEP_MARGIN) * r.peak:  # (accuracy 0: a bound the samples set, not an estimate)
            r = LimitRow(r.joint, r.quantity, r.unit, float(col[i]), r.limit, float(col[i]) / r.limit,
                         float(steps[i]), float(col[i]) <= r.limit, r.kind, r.bound, r.target, 0.0, r.not_held)
        rows.append(r)
    return replace(report, rows=tuple(rows))


#: a CSV's numbers carry 12 significant digits: each is off by up to this share of its magnitude
ROUNDING = 5e-13
#: the reconstruction's jerk from that rounding is about ROUNDING_GAIN · δ / h³ (δ the positions' rounding [m], h the
#: sample interval; measured ~7.5 for the septic Hermite of the Adept cycle at 200 kHz: its q1 torque rate read
#: 587 N·m/s, the motion's 167 N·m/s)
ROUNDING_GAIN = 10.0
#: … and may be at most this share of the motion's own jerk: a file so dense that it would be more is read every
#: k-th sample (at 200 kHz the rounding alone read q1's torque rate of the Adept cycle at 140 % of the limit where
#: the motion reaches 40 %)
ROUNDING_SHARE = 1e-3
#: … unless a sample left out is off the quintic spline through the others by more than this many times the rounding
#: δ (a feature between the samples read, however small, carries a jerk beyond the rounding's: a 1 nm bump 10 µs wide
#: on the Adept cycle at 200 kHz is a torque rate of 72 × the limit): then every sample is read. Smooth data leave
#: out samples within ~2δ of the spline (its own error at the stride is orders below δ)
ROUNDING_SPARED = 10.0


def reading_stride(t: np.ndarray, pos: np.ndarray, tool: np.ndarray | None = None) -> int:
    """Every how many samples the motion is read (1: every one): the smallest k for which the rounding of the file's
    12 digits (``ROUNDING``) puts at most ``ROUNDING_SHARE`` of the motion's jerk into the reconstruction's
    (``ROUNDING_GAIN``·δ/(k·h)³, h the median interval). The motion's jerk: the tool's jerk columns when given, else
    third differences of the tool positions ``pos`` (N, 3+) [m] taken ~200 samples apart. 1 when a sample left out is
    off the quintic spline through the others (``ROUNDING_SPARED``)."""
    n = len(t)
    if n < 50:
        return 1
    h = float(np.median(np.diff(t)))
    if not h > 0:
        return 1
    p = np.asarray(pos, float)[:, :3]
    delta = ROUNDING * max(1.0, float(np.max(np.abs(p))))
    if tool is not None:
        jerk = float(np.max(np.linalg.norm(tool[:, 9:12], axis=1)))
    else:
        c = max(1, n // 200)
        q = p[::c]
        jerk = float(np.max(np.linalg.norm(np.diff(q, 3, axis=0), axis=1), initial=0.0)) / (c * h) ** 3
    if not jerk > 0:
        return 1
    need = (ROUNDING_GAIN * delta / (ROUNDING_SHARE * jerk)) ** (1.0 / 3.0)
    k = max(1, min(int(np.ceil(need / h - 1e-9)), n // 50))
    if k > 1:  # the samples left out must lie on the motion the others give: a spike or step between them is read
        from scipy.interpolate import make_interp_spline

        keep = strided(n, k)
        between = make_interp_spline(t[keep], p[keep], k=5)(t)
        if float(np.max(np.abs(between - p))) > ROUNDING_SPARED * delta:
            return 1
    return k


def strided(n: int, k: int) -> np.ndarray:
    """Every k-th of n samples, the last one always kept."""
    idx = np.arange(0, n, k)
    return idx if idx[-1] == n - 1 else np.append(idx, n - 1)


def _half(n: int) -> np.ndarray:
    """Every other sample of n, the last one always kept."""
    idx = np.arange(0, n, 2)
    return idx if idx[-1] == n - 1 else np.append(idx, n - 1)


def check_samples(s: Samples, profile: Profile, smoothing: float = 0.0, source: str = "<trajectory>",
                  strict: bool = False, warn=None, not_held: str = "") -> LimitReport:
    """Limit report of one move read by :func:`read_moves` (see the module docstring).

    Every duration-dependent peak is estimated from the samples twice, from all of them and from every other one
    (the same reconstruction): their difference, and at least 0.1 % of the peak (``CHECK_RESOLUTION``), is the
    peak's stated accuracy (the error of an estimate that converges with the sample rate is smaller than its change
    when the rate halves). A row is exceeded only
    when its peak less that accuracy is beyond the limit (the data shows it exceeded); a peak whose accuracy is
    worse than 1 % of the limit is reported as not resolved by the samples (``LimitReport.unresolved``).

    The file's tool derivative columns (vx … jz) are used only when they agree with its positions
    (:func:`derivative_problems`); otherwise the move is judged from its positions
    and ``warn`` (a callable) is told in one line, or with ``strict`` the file is refused (TaskError).
    ``not_held``: why the tool's Cartesian capacity is not held ("" when it is: an exceeded capacity then fails)."""
    robot = build_robot(profile.robot)
    t = s.t - s.t[0]
    pos = robot.forward_kinematics(s.q)
    _check_branch(s, robot, pos, source)
    T = float(t[-1])
    rest = f"; {s.rest} trailing samples at rest set aside as the dwell" if s.rest else ""
    dwell = 0.0 if s.move is None and closed_cycle(s.q) else None
    whole = f"; {CLOSED_NOTE}" if dwell is not None else ""

    def notes(how: str) -> tuple[str, ...]:
        start = f" from t = {s.t[0]:.6g} s of the file (peak times count from there)" if s.t[0] != 0 else ""
        return (f"{s.where(source)}: {len(s.t)} samples over {T:.6g} s{start}{rest}; derivatives from {how}; joint positions "
                f"checked as given in the file{whole}",)

    if smoothing == "auto":
        from ..curves.sampled import noise_level

        smoothing = noise_level(t, pos) ** 2
    tool = s.tool
    if tool is not None and np.max(np.abs(tool[:, :3] - pos)) > TOOL_TOL:
        off = float(np.max(np.abs(tool[:, :3] - pos)))
        rest += f"; its x, y, z differ from FK of its joint positions by up to {off:.3g} m, so its tool columns are not used"
        tool = None
    if tool is not None:
        problems = derivative_problems(t, tool)
        if problems:
            said = f"{s.where(source)}: {describe_problems(problems)}"
            if strict:
                raise TaskError(f"{said}: refused (--strict); without --strict the move is judged from its positions")
            if warn is not None:
                warn(f"warning: {said}: judged from its positions alone")
            rest += f"; its derivative columns are not used ({describe_problems(problems)})"
            tool = None
    if getattr(robot, "rotary", False):  # the tool angle θ = FK of the fourth axis, one more column
        pos = np.column_stack([pos, robot.tool_angle(s.q)])
    k = reading_stride(t, pos, tool)
    if k > 1:  # so dense that the 12 digits' rounding would be read as jerk: every k-th sample
        keep = strided(len(t), k)
        rest += (f"; the motion read from one sample in {k} ({len(keep)} of {len(t)}: at this rate the rounding of "
                 "the file's 12 digits would dominate their third derivative)")
        t, pos, tool = t[keep], pos[keep], None if tool is None else tool[keep]  # (the positions: every sample, below)
    sigma = noisy(t, pos, tool) if not smoothing else 0.0
    if sigma:
        rest += (f"; the positions carry noise of σ = {sigma:.2g} m (whole counts or a few decimals?), which their "
                 "third derivative amplifies: --smoothing auto reads through it")
    report = _read_motion(t, pos, robot, profile, smoothing, source, notes, tool, not_held, dwell)
    others = []
    half = _half(len(t))
    if len(half) >= 6:
        # the septic Hermite through positions to jerks converges as h⁵ in the third derivative: its estimate's error
        # is the change when the rate halves over 2⁵ − 1, taken twice (HERMITE_DIVISOR); the splines of positions
        # alone are taken at the whole change (a jerk step they do not find rings however fine the samples)
        share = 1.0 / HERMITE_DIVISOR if tool is not None and not smoothing else 1.0
        # (split where the septic overshoots: at half the rate its overshoot at a step near the ends is no estimate
        # of the full reading's error, which holds the higher of both readings)
        others.append((_motion_report(t[half], pos[half], robot, profile, smoothing, source, None,
                                      None if tool is None else tool[half], dwell=dwell)[0], share))
    if smoothing:  # what the smoothing takes away is as uncertain as the rest: the interpolated data's peaks
        others.append((_motion_report(t, pos, robot, profile, 0.0, source, dwell=dwell)[0], 1.0))
    report = _with_accuracy(report, others, noise=bool(sigma))
    # the position ranges on the file's own values (the model's inverse kinematics wraps revolute joints)
    specs = limit_specs(profile)
    given = {}
    for j, (name, unit, spec) in enumerate(zip(robot.joint_names, robot.joint_units, specs)):
        if spec.limits.position is not None:
            lo, hi = spec.limits.position
            kmax, kmin = int(np.argmax(s.q[:, j])), int(np.argmin(s.q[:, j]))
            given[name] = _range_row((name, "position", unit, "reach", float(lo), float(hi)),
                                     float(s.q[kmax, j]), float(s.q[kmin, j]), float(s.t[kmax] - s.t[0]),
                                     float(s.t[kmin] - s.t[0]))
    rows = tuple(given.get(r.joint, r) if r.quantity == "position" else r for r in report.rows)
    return replace(report, rows=rows)


#: where the septic Hermite's jerk overshoots between two samples near the move's ends (the first and last
#: ``UNSPLIT_ENDS`` intervals, where the overshoot test sees one side only) without a jump of the samples' jerk, the
#: samples do not tell a jerk step near a sample from a real extreme of the jerk; in a move of fewer than
#: ``UNSPLIT_BELOW`` samples the reading takes the higher of the split one (a step) and the unsplit septic's (an
#: extreme). The Adept cycle at 0.128 s peaks at 464.6 N·m/s (111 % of q1's torque rate) 2.6 ms before its end: split,
#: 250 Hz (33 samples) read 417.1 ± 0.4, 500 Hz 439.0, 600 Hz (77) 454.4; both, 461.9, 464.9, 464.6; from 700 Hz
#: (90 samples) on the split reading is the peak. At a real step near the end (a time-optimal law's, at 1 kHz) the
#: unsplit septic overshoots by 0.04-2 %: more samples take the split reading, as before
UNSPLIT_ENDS = 3
UNSPLIT_BELOW = 100


def _read_motion(t: np.ndarray, pos: np.ndarray, robot, profile: Profile, smoothing: float, source: str, notes=None,
                 tool: np.ndarray | None = None, not_held: str = "", dwell: float | None = None) -> LimitReport:
    """The limit report of :func:`_motion_report`, and through the file's tool columns (``tool``, no smoothing)
    each timed peak raised to the unsplit septic's reading where the split one is lower (``UNSPLIT_ENDS``,
    ``UNSPLIT_BELOW``)."""
    report = _motion_report(t, pos, robot, profile, smoothing, source, notes, tool, not_held=not_held, dwell=dwell)[0]
    if tool is None or smoothing or len(t) >= UNSPLIT_BELOW:
        return report
    from ..curves.sampled import overshoot_only
    from .report import LimitRow

    ks = overshoot_only(t, tool[:, 0:3], tool[:, 3:6], tool[:, 6:9], tool[:, 9:12])
    ks = ks[(ks < UNSPLIT_ENDS) | (ks >= len(t) - 1 - UNSPLIT_ENDS)]
    if not ks.size:
        return report
    alt = {(r.joint, r.quantity): r for r in _motion_report(t, pos, robot, profile, 0.0, source, None, tool,
                                                            not_held=not_held, dwell=dwell, whole=ks)[0].rows}
    rows = []
    for r in report.rows:
        o = alt.get((r.joint, r.quantity))
        if o is not None and r.kind == "limit" and r.bound == "upper" and o.peak > r.peak:
            r = LimitRow(r.joint, r.quantity, r.unit, o.peak, r.limit, o.utilisation, o.t_peak, o.ok, r.kind, r.bound,
                         r.target, r.accuracy, r.not_held)
        rows.append(r)
    return replace(report, rows=tuple(rows))


#: positions whose noise (:func:`~pickplace_cli.curves.sampled.noise_level`, white: the same at every other sample,
#: where a smooth motion's sixth differences grow 64-fold) would put more than ``ROUNDING_SHARE`` of the motion's jerk
#: into the reconstruction's (``ROUNDING_GAIN``·σ/h³) are noisy: whole encoder counts or a few decimals at 1-4 kHz
NOISE_SAME = 4.0


def noisy(t: np.ndarray, pos: np.ndarray, tool: np.ndarray | None = None) -> float:
    """The white noise σ [m] of the tool positions ``pos`` when it matters for their third derivative (module
    constants above), else 0."""
    from ..curves.sampled import noise_level

    n = len(t)
    if n < 50 or tool is not None:  # (a file with the tool's columns reads its jerks, not differences of positions)
        return 0.0
    p = np.asarray(pos, float)[:, :3]
    s1, s2 = noise_level(t, p), noise_level(t[::2], p[::2])
    if not (s1 > 0 and s2 < NOISE_SAME * s1):
        return 0.0
    h = float(np.median(np.diff(t)))
    c = max(1, n // 200)
    jerk = float(np.max(np.linalg.norm(np.diff(p[::c], 3, axis=0), axis=1), initial=0.0)) / (c * h) ** 3
    return s1 if ROUNDING_GAIN * s1 / h**3 > ROUNDING_SHARE * jerk else 0.0


def _with_accuracy(fine: LimitReport, others: list[tuple[LimitReport, float]], noise: bool = False) -> LimitReport:
    """``fine``'s duration-dependent rows with accuracy = the largest share × |its peak − the same row's peak| over
    ``others`` ((report, share): other estimates from the same data), at least ``CHECK_RESOLUTION`` of the peak, and
    the verdict that the data supports: exceeded only when the peak less its accuracy is beyond the allowed value —
    the accuracy counted up to ``RESOLVED`` of the allowed value: a peak the samples do not resolve is judged by its
    best estimate (the reading from all samples) with that margin, not given the benefit of an accuracy of 100 % or
    more (a torque rate read 219 % ± 166 % of its limit is exceeded, not "within its limit"). ``noise``: the positions
    are noisy (:func:`noisy`): their reading is no best estimate, and the whole accuracy counts (not resolved)."""
    from .report import LimitRow

    if not others:
        return fine
    other = [({(r.joint, r.quantity): r for r in o.rows}, share) for o, share in others]
    rows = []
    for r in fine.rows:
        cs = [(o[(r.joint, r.quantity)], share) for o, share in other if (r.joint, r.quantity) in o]
        if r.kind == "limit" and r.bound == "upper" and r.accuracy == 0.0:  # a step's bound (_across_steps)
            acc = CHECK_RESOLUTION * abs(r.peak)
            r = LimitRow(r.joint, r.quantity, r.unit, r.peak, r.limit, r.utilisation, r.t_peak, r.peak - acc <= r.allowed,
                         r.kind, r.bound, r.target, acc, r.not_held)
        elif r.kind == "limit" and r.bound == "upper" and cs:
            acc = max(max(share * abs(r.peak - c.peak) for c, share in cs), CHECK_RESOLUTION * abs(r.peak))
            ok = r.peak - (acc if noise else min(acc, RESOLVED * abs(r.allowed))) <= r.allowed
            r = LimitRow(r.joint, r.quantity, r.unit, r.peak, r.limit, r.utilisation, r.t_peak, ok, r.kind, r.bound,
                         r.target, acc, r.not_held)
        rows.append(r)
    return replace(fine, rows=tuple(rows))

