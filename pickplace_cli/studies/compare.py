"""compare_methods: every planning method on one move, side by side (``pickplace compare``).

One row per method (the registry :class:`~pickplace_cli.paths.Method`, iterated generically) with:

* durations: the chosen one (``auto`` by default), ``auto`` [Li2018, Eq. (26)] from the profile's
  Cartesian capacity on the method's true peaks, and ``fit`` (the smallest duration at which every joint
  and motor limit holds), from :func:`pickplace_cli.planner.plan`;
* the paper's own cycle-time formula where the method module offers one (``paper_duration``), next to
  the true-peak ``auto`` (they differ e.g. for PH, whose Eq. (22) bounds only the tangential part);
* normalised peaks v_max, a_max, j_max (b = 1, T = 1, i.e. the τ-peaks divided by b) [Li2018, Table 1];
* true peaks |v|, |a|, |j| at the chosen duration, measured on the continuous path here (dense samples
  + golden-section refinement), not taken from the method's declared values (a mismatch is noted);
* peak joint torque (joint side, sampled on the limit check's grid) and the utilisation of the motor
  torque and torque-rate limits (from the limit report);
* geometry: maximum height above the higher end point, overshoot above the clearance height h (z_top),
  backward drift (how far the tool moves along −e_u behind the pick point) and forward overshoot (past
  the place point along +e_u);
* continuity class, determined numerically (:func:`continuity`) from the jumps of v, a, j at the
  path's breakpoints, at the two ends (the tool rests before and after the move) and at any jump a dense
  scan finds between declared breakpoints;
* residual vibration (:mod:`pickplace_cli.studies.vibration`) when the profile has a ``vibration`` section.

A method that cannot plan this move (unreachable point, a table that does not cover λ …) gets a row
with its error instead of numbers; the other methods still run.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass, field
from typing import Any, Iterable, Mapping

import numpy as np

from ..model.errors import NoFeasibleDuration, PickplaceError, TaskError
from ..curves.peaks import DENSE, _dense_grid, true_peaks  # noqa: F401 - true_peaks: compare's measured peaks

#: a derivative "jumps" where its two one-sided limits differ by more than this fraction of its peak.
#: The one-sided limits are linear extrapolations from τ ± ε, τ ± 2ε with ε ≤ 1e-7: their error is
#: ~ε²·|f″| ≈ 1e-14·|f″|, i.e. ≤ 1e-8 of the peak for |f″|/|f| up to 1e6 — far below this threshold, while
#: a real jump (3-4-5 law: the jerk steps from 0 to its full value) is of order 1.
JUMP_TOL = 1e-6
_EPS = 1e-7
_ORDER_NAMES = {1: "velocity", 2: "acceleration", 3: "jerk"}


# ----------------------------------------------------------------------------------------- continuity


@dataclass(frozen=True)
class Jump:
    """A jump of the ``order``-th derivative at τ: ``size`` is ‖right − left‖ in m/1^k (b as given,
    T = 1); ``relative`` is size / peak of that derivative."""

    order: int
    tau: float
    size: float
    relative: float


@dataclass(frozen=True)
class Continuity:
    """Continuity class of a move from rest to rest, measured on the path.

    ``order`` is the highest k such that every derivative up to the k-th is continuous on [0, 1] *and*
    joins the rest before and after the move (0: position only … 3: jerk continuous, "C3");
    ``jumps`` lists every jump found (v, a, j); ``unbounded`` the derivative orders that grow without
    bound toward an end (e.g. the jerk of a Lamé curve with exponent < 3); ``declared`` is what the method
    claims (``parameters["continuity"]`` when given, else None).
    """

    order: int
    jumps: tuple[Jump, ...] = ()
    unbounded: tuple[int, ...] = ()
    declared: int | None = None

    @property
    def label(self) -> str:
        out = f"C{self.order}"
        if self.unbounded:
            out += " (" + ", ".join(_ORDER_NAMES[k] for k in self.unbounded) + " unbounded at the ends)"
        return out

    @property
    def jerk_continuous(self) -> bool:
        return self.order >= 3

    def as_dict(self) -> dict[str, Any]:
        return {
            "class": f"C{self.order}",
            "jerk_continuous": self.jerk_continuous,
            "declared": None if self.declared is None else f"C{self.declared}",
            "unbounded": [_ORDER_NAMES[k] for k in self.unbounded],
            "jumps": [
                {"quantity": _ORDER_NAMES[j.order], "tau": j.tau, "size": j.size, "relative": j.relative}
                for j in self.jumps
            ],
        }


def _scan_candidates(tau: np.ndarray, values: np.ndarray, peak: float) -> list[tuple[float, float]]:
    """Brackets of the dense samples where the change between neighbours stands out (> 8×) from the
    running median of the changes around it (11 samples): a hidden jump. Flagged neighbours are merged
    into one bracket (a sample *at* a jump may hold neither one-sided value)."""
    d = np.linalg.norm(np.diff(values, axis=0), axis=1)
    if d.size < 11:
        return []
    padded = np.pad(d, 5, mode="edge")
    base = np.median(np.lib.stride_tricks.sliding_window_view(padded, 11), axis=1)
    flag = (d > 8.0 * base) & (d > JUMP_TOL * peak)
    out: list[tuple[float, float]] = []
    i = 0
    while i < d.size:
        if flag[i]:
            k = i
            while k + 1 < d.size and flag[k + 1]:
                k += 1
            out.append((float(tau[i]), float(tau[k + 1])))
            i = k + 1
        else:
            i += 1
    return out


def _locate(path, order: int, brackets: list[tuple[float, float]]) -> np.ndarray:
    """Bisect every bracket toward the half with the larger change of the derivative (a jump's location);
    all brackets in one path evaluation per step."""
    lo = np.array([b[0] for b in brackets])
    hi = np.array([b[1] for b in brackets])
    n = len(lo)
    f = path(np.concatenate([lo, hi]), order)
    flo, fhi = f[:n], f[n:]
    while np.max(hi - lo) > 1e-12:
        mid = 0.5 * (lo + hi)
        fm = path(mid, order)
        left = np.linalg.norm(fm - flo, axis=1) >= np.linalg.norm(fhi - fm, axis=1)
        hi = np.where(left, mid, hi)
        fhi = np.where(left[:, None], fm, fhi)
        lo = np.where(left, lo, mid)
        flo = np.where(left[:, None], flo, fm)
    return 0.5 * (lo + hi)


#: the scales ε at which a jump is probed (τ ± ε, or the end ± ε); a jump's difference stays put as ε
#: shrinks, a continuous function's shrinks (100× per step when Lipschitz, 10× for a √τ-like end)
_SCALES = np.array([1e-4, 1e-6, 1e-8, 1e-10])


def _measure(path, k: int, tau: np.ndarray, gap: np.ndarray, side: np.ndarray, scale: float):
    """Jumps of the k-th derivative at the points ``tau`` (side 0: interior, ±1: an end, the sign pointing
    inward; the rest outside is zero). Returns (size (n,) with NaN where continuous, unbounded (n,))."""
    n = len(tau)
    ns = len(_SCALES)
    e = np.minimum(_SCALES[None, :], gap[:, None] / 4.0)  # (n, ns)
    ex = np.minimum(_EPS, gap / 4.0)  # extrapolation step (n,)
    interior = side == 0
    # right and left probe points: interior τ ± ε; an end: end + side·ε (and the rest value 0)
    right = np.where(interior[:, None], tau[:, None] + e, tau[:, None] + side[:, None] * e)
    left = tau[:, None] - e
    rx = np.where(interior, tau + ex, tau + side * ex)
    lx = tau - ex
    pts = np.concatenate([right.ravel(), left.ravel(), rx, rx + np.where(interior, ex, side * ex), lx, lx - ex])
    f = path(np.clip(pts, 0.0, 1.0), k)
    m = n * ns
    fr, fl = f[:m].reshape(n, ns, 3), f[m : 2 * m].reshape(n, ns, 3)
    fl = np.where(interior[:, None, None], fl, 0.0)
    d = np.linalg.norm(fr - fl, axis=2)  # (n, ns)
    r1, r2, l1, l2 = (f[2 * m + i * n : 2 * m + (i + 1) * n] for i in range(4))
    lim_r = 2 * r1 - r2
    lim_l = np.where(interior[:, None], 2 * l1 - l2, 0.0)
    size = np.linalg.norm(lim_r - lim_l, axis=1)
    with np.errstate(invalid="ignore"):
        jump = np.isfinite(d[:, -1]) & (d[:, -1] > JUMP_TOL * scale) & (d[:, -1] >= 0.5 * d[:, -2])
        unbounded = jump & (d[:, -1] > 1.5 * d[:, -2]) & (d[:, -2] > 1.5 * d[:, -3])
    size = np.where(unbounded | ~np.isfinite(size), d[:, -1], size)
    return np.where(jump, size, np.nan), unbounded


def continuity(path, rest_ends: bool = True, samples: dict[int, np.ndarray] | None = None,
               grid: np.ndarray | None = None) -> Continuity:
    """Measure the continuity class of ``path`` (a CartesianPath on τ ∈ [0, 1]).

    Checks v, a, j for jumps at every declared breakpoint, at the two ends against rest (when
    ``rest_ends``: the tool is at rest before and after the move, so a non-zero one-sided limit there is a
    jump) and at every bracket where a dense scan of the samples shows an isolated step (located by
    bisection). At each such τ the difference across it is probed at ε = 1e-4, 1e-6, 1e-8, 1e-10: it is a
    jump when the difference at 1e-10 exceeds ``JUMP_TOL`` of the peak and has not shrunk by half since
    1e-8 (a continuous derivative's difference shrinks 100×, or 10× for a √τ-like end); it is
    *unbounded* when the difference keeps growing (×1.5 per step) as ε shrinks. The reported size comes
    from one-sided limits extrapolated linearly from ε = 1e-7 and 2e-7 (error ~1e-14·|f″|).
    ``samples``/``grid`` may pass precomputed derivatives {order: (N, 3)} on ``grid``.
    """
    if grid is None:
        grid = _dense_grid(path)
    if samples is None:
        samples = {k: path(grid, k) for k in (1, 2, 3)}
    bp = np.asarray(path.breakpoints, float)
    interior = np.unique(bp[(bp > 1e-9) & (bp < 1 - 1e-9)])
    marks = np.concatenate([[0.0, 1.0], interior])
    jumps: list[Jump] = []
    unbounded: list[int] = []

    def gap_at(t: float) -> float:
        other = np.abs(marks - t)
        other = other[other > 1e-12]
        return float(np.min(other)) if other.size else 1.0

    for k in (1, 2, 3):
        vals = samples[k]
        norms = np.linalg.norm(vals, axis=1)
        peak = float(np.max(norms[np.isfinite(norms)], initial=0.0))
        scale = peak if peak > 0 else 1.0
        pts = [float(t) for t in interior]
        brackets = [b for b in _scan_candidates(grid, vals, scale)
                    if not np.any(np.abs(interior - 0.5 * (b[0] + b[1])) <= (b[1] - b[0]))]
        if brackets:
            pts += [float(t) for t in _locate(path, k, brackets)]
        sides = [0] * len(pts)
        if rest_ends:
            pts += [0.0, 1.0]
            sides += [1, -1]
        if not pts:
            continue
        tau = np.array(pts)
        size, unb = _measure(path, k, tau, np.array([gap_at(t) for t in pts]), np.array(sides), scale)
        for t, sz, u in zip(tau, size, unb):
            if np.isfinite(sz):
                jumps.append(Jump(k, float(t), float(sz), float(sz / scale)))
                if u and k not in unbounded:
                    unbounded.append(k)
    order = 3
    for j in jumps:
        order = min(order, j.order - 1)
    declared = path.parameters.get("continuity") if hasattr(path, "parameters") else None
    if isinstance(declared, str) and declared.upper().startswith("C") and declared[1:].isdigit():
        declared = int(declared[1:])
    elif not isinstance(declared, (int, np.integer)):
        declared = None
    jumps.sort(key=lambda j: (j.order, j.tau))
    return Continuity(order, tuple(jumps), tuple(sorted(unbounded)), None if declared is None else int(declared))


# ------------------------------------------------------------------------------ peaks and geometry


@dataclass(frozen=True)
class Geometry:
    """Extremes of the path in the vertical plane of the move [m].

    ``max_height``: highest z minus the higher end point's z; ``overshoot``: highest z minus z_top (the
    clearance height h above the higher end; > 0 means the path rises above h); ``drift_back``: how far the
    tool moves along −e_u behind the pick point; ``drift_forward``: how far it moves along +e_u past the
    place point (both ≥ 0; u = (p − p_from)·e_u)."""

    max_height: float
    overshoot: float
    drift_back: float
    drift_forward: float

    @property
    def drift(self) -> float:
        """The larger of the two drifts away from the target line [m]."""
        return max(self.drift_back, self.drift_forward)


def path_geometry(path, task, grid: np.ndarray | None = None, positions: np.ndarray | None = None) -> Geometry:
    """:class:`Geometry` of ``path`` for ``task``, extremes refined on the continuous path."""
    from ..curves.peaks import refine_max

    if grid is None:
        grid = _dense_grid(path)
    e_u = task.e_u
    origin = task.p_from
    b = task.b

    def cols(t: np.ndarray, p: np.ndarray | None = None) -> np.ndarray:
        p = path(t, 0) if p is None else p
        u = (p - origin) @ e_u
        return np.column_stack([p[:, 2], -u, u - b])

    # 12 golden-section steps leave a bracket of ~1e-3·0.618¹² ≈ 3e-6 in τ; the value error is quadratic
    # in it (≤ 1e-11 of |d²/dτ²|, i.e. < 1e-10 m for these paths)
    peak, _ = refine_max(cols, grid, cols(grid, positions), iterations=12)
    z_hi = float(max(task.p_from[2], task.p_to[2]))
    return Geometry(
        max_height=float(peak[0]) - z_hi,
        overshoot=float(peak[0]) - task.z_top,
        drift_back=max(0.0, float(peak[1])),
        drift_forward=max(0.0, float(peak[2])),
    )


# ---------------------------------------------------------------------------------------- the rows


@dataclass(frozen=True)
class CompareRow:
    """One method on the move (SI units; None where a quantity does not apply or was not computed)."""

    method: str
    error: str | None = None
    exit_code: int = 0
    parameters: Mapping[str, Any] = field(default_factory=dict)
    duration: float | None = None  # s, the chosen one
    duration_mode: str | None = None
    auto: float | None = None  # s
    fit: float | None = None  # s
    optimal: float | None = None  # s, the non-uniform time law of --time optimal (None with other --time)
    binding: str | None = None
    paper_duration: float | None = None  # s, the paper's own formula (None: the method has none)
    paper_formula: str | None = None
    v_norm: float | None = None  # normalised peaks (b = 1, T = 1)
    a_norm: float | None = None
    j_norm: float | None = None
    peak_speed: float | None = None  # m/s at the chosen duration
    peak_acceleration: float | None = None  # m/s²
    peak_jerk: float | None = None  # m/s³
    joint_torque_peak: float | None = None  # N·m (or N for a linear joint), joint side
    joint_torque_unit: str | None = None
    motor_torque_use: float | None = None  # peak / limit
    torque_rate_use: float | None = None
    limits_ok: bool | None = None  # every limit the duration rule holds (plan's limits_ok)
    worst_limit: str | None = None
    #: the rows beyond their limit that the duration rule does not hold (the Cartesian capacity under fit and
    #: optimal), as "capacity speed 116.5 %"; all_limits_ok counts them (plan's all_limits_ok)
    exceeded_not_held: tuple[str, ...] = ()
    all_limits_ok: bool | None = None
    geometry: Geometry | None = None
    continuity: Continuity | None = None
    vibration: Any = None  # ResidualVibration or None
    notes: tuple[str, ...] = ()

    @property
    def ok(self) -> bool:
        return self.error is None

    def as_dict(self) -> dict[str, Any]:
        """Flat JSON-ready dict (keys carry units)."""
        g, c, v = self.geometry, self.continuity, self.vibration
        return {
            "method": self.method,
            "error": self.error,
            "parameters": {k: (float(x) if isinstance(x, (np.floating,)) else x) for k, x in self.parameters.items()},
            "duration_s": self.duration,
            "duration_mode": self.duration_mode,
            "auto_s": self.auto,
            "fit_s": self.fit,
            "optimal_s": self.optimal,
            "binding": self.binding,
            "paper_duration_s": self.paper_duration,
            "paper_formula": self.paper_formula,
            "v_max_norm": self.v_norm,
            "a_max_norm": self.a_norm,
            "j_max_norm": self.j_norm,
            "peak_speed_m_s": self.peak_speed,
            "peak_acceleration_m_s2": self.peak_acceleration,
            "peak_jerk_m_s3": self.peak_jerk,
            "joint_torque_peak": self.joint_torque_peak,
            "joint_torque_unit": self.joint_torque_unit,
            "motor_torque_use": self.motor_torque_use,
            "torque_rate_use": self.torque_rate_use,
            "limits_ok": self.limits_ok,
            "all_limits_ok": self.all_limits_ok,
            "exceeded_not_held": list(self.exceeded_not_held),
            "worst_limit": self.worst_limit,
            "max_height_m": None if g is None else g.max_height,
            "overshoot_m": None if g is None else g.overshoot,
            "drift_back_m": None if g is None else g.drift_back,
            "drift_forward_m": None if g is None else g.drift_forward,
            "continuity": None if c is None else c.as_dict(),
            "residual_vibration": None if v is None else v.as_dict(),
            "notes": list(self.notes),
        }


@dataclass(frozen=True)
class Comparison:
    """Every requested method on one move: ``rows`` in registry order."""

    task: Any
    profile_name: str
    rows: tuple[CompareRow, ...]
    time: str | float = "auto"

    @property
    def ok_rows(self) -> tuple[CompareRow, ...]:
        return tuple(r for r in self.rows if r.ok)

    def as_dict(self) -> dict[str, Any]:
        t = self.task
        return {
            "profile": self.profile_name,
            "from_m": t.p_from.tolist(),
            "to_m": t.p_to.tolist(),
            "height_m": t.height,
            "eta": t.eta,
            "b_m": t.b,
            "lambda": t.lam,
            "time": self.time,
            "rows": [r.as_dict() for r in self.rows],
        }


def parse_methods(spec: str | Iterable[str] | None) -> list:
    """``all`` / None → every registered method; else a comma list (or iterable) of names, validated
    against the registry (TaskError naming the unknown one and the choices)."""
    from ..paths import Method

    if spec is None or (isinstance(spec, str) and spec.strip().lower() == "all"):
        return list(Method)
    if isinstance(spec, str) and not spec.strip():
        raise TaskError("methods = '': empty; give 'all' or method names separated by commas")
    names = [s.strip() for s in spec.split(",")] if isinstance(spec, str) else [str(s) for s in spec]
    out = []
    for n in names:
        if not n:
            raise TaskError(f"methods = {spec!r}: empty method name; give 'all' or names separated by commas")
        try:
            m = Method(n)
        except ValueError:
            raise TaskError(
                f"methods = {n!r}: unknown method; choose from {', '.join(x.value for x in Method)} or 'all'"
            ) from None
        if m not in out:
            out.append(m)
    return out


def paper_duration(method, task, profile) -> tuple[float, str] | None:
    """The method's own cycle-time formula, when its module offers ``paper_duration(task, capacity)``
    returning seconds or (seconds, formula name); None otherwise."""
    name = getattr(method, "value", str(method)).replace("-", "_")
    try:
        module = importlib.import_module(f"pickplace_cli.paths.{name}")
    except ImportError:
        return None
    fn = getattr(module, "paper_duration", None)
    if fn is None:
        return None
    out = fn(task, profile.capacity)
    if out is None:
        return None
    if isinstance(out, tuple):
        return float(out[0]), str(out[1])
    import re

    cite = re.search(r"\[(\w+\d{4}), (Eq\. \([^\]]*)\]", fn.__doc__ or "")
    label = f"{cite.group(1)} {cite.group(2)}" if cite else f"the {getattr(method, 'value', method)} paper's formula"
    return float(out), label


def compare_row(task, profile, method, params: Mapping[str, Any] | None = None, time: str | float = "auto") -> CompareRow:
    """One method on ``task``/``profile`` → :class:`CompareRow` (errors of that method become the row's error)."""
    from ..limits.grid import check_grid
    from ..limits.report import percent
    from ..planner import PlanOptions, motion_model, plan
    from .vibration import residual_vibration

    name = getattr(method, "value", str(method))
    params = dict(params or {})
    notes: list[str] = []
    try:
        try:
            result = plan(task, profile, PlanOptions(method=method, method_params=params, time=time, fit=True))
        except NoFeasibleDuration as exc:
            if time == "fit":
                raise
            result = plan(task, profile, PlanOptions(method=method, method_params=params, time=time, fit=False))
            notes.append(f"fit: {exc}")
    except PickplaceError as exc:
        return CompareRow(name, error=str(exc), exit_code=exc.exit_code)
    except Exception as exc:  # noqa: BLE001 - one method's failure is that method's row, never the comparison's end
        detail = " ".join(str(exc).split())[:200]
        return CompareRow(name, error=f"internal error ({type(exc).__name__}: {detail})", exit_code=1)
    path = result.cartesian.path
    T = result.duration.seconds
    grid = _dense_grid(path)
    samples = {k: path(grid, k) for k in range(4)}
    # the method's declared peaks are its exact maxima; check them against the dense samples (cheap) and
    # measure on the continuous path (refined) only when a sample exceeds them
    declared = np.asarray(path.peaks, float)
    sampled = np.array([np.max(np.linalg.norm(samples[k], axis=1)) for k in (1, 2, 3)])
    if np.all(sampled <= declared * (1 + 1e-9)):
        vn, an, jn = (float(x) for x in declared)
    else:
        vn, an, jn = true_peaks(path, grid, {k: samples[k] for k in (1, 2, 3)})
        notes.append(
            "declared peaks (v, a, j) = (" + ", ".join(f"{x:.6g}" for x in declared) + ") are below the path's "
            "measured (" + f"{vn:.6g}, {an:.6g}, {jn:.6g}); the measured ones are reported"
        )
    b = task.b
    norm = (vn / b, an / b, jn / b) if b > 0 else (None, None, None)
    if b == 0:
        notes.append("b = 0 (vertical move): normalised peaks (b = 1) are undefined")
    # joint torque (sampled) on the dense grid plus the limit check's extra points (knots, Kronrod nodes per
    # span, both sides of every jump)
    model = motion_model(path, profile)
    tq_grid = check_grid(grid, path.breakpoints, path.jumps)
    parts = model.parts(tq_grid, derivatives=False)
    torque = parts.A / T**2 + parts.G
    unit = "N" if all(u == "m" for u in model.robot.joint_units) else "N·m"
    util = {"motor torque": None, "motor torque rate": None}
    for r in result.report.rows:
        if r.quantity in util:
            util[r.quantity] = max(util[r.quantity] or 0.0, r.utilisation)
    # the worst of the limits the rule holds (fit and optimal: not the Cartesian capacity)
    worst = max((r for r in result.report.rows if r.held), key=lambda r: r.utilisation, default=None)
    paper = None
    try:
        paper = paper_duration(method, task, profile)
    except PickplaceError as exc:
        notes.append(f"paper formula: {exc}")
    if paper is not None and abs(paper[0] - result.duration.t_auto) > 1e-6 * result.duration.t_auto:
        notes.append(
            f"{paper[1]} gives {paper[0]:.4f} s; the true peaks of |v|, |a|, |j| along the path need "
            f"{result.duration.t_auto:.4f} s (auto)"
        )
    vib = residual_vibration(result.cartesian, profile.vibration) if profile.vibration is not None else None
    rest = not (np.any(task.v_from) or np.any(task.v_to))
    return CompareRow(
        method=name,
        parameters=dict(result.parameters),
        duration=T,
        duration_mode=result.duration.mode,
        auto=result.duration.t_auto,
        fit=result.duration.t_fit,
        optimal=result.duration.t_optimal,
        binding=result.duration.binding,
        paper_duration=None if paper is None else paper[0],
        paper_formula=None if paper is None else paper[1],
        v_norm=norm[0],
        a_norm=norm[1],
        j_norm=norm[2],
        peak_speed=vn / T,
        peak_acceleration=an / T**2,
        peak_jerk=jn / T**3,
        joint_torque_peak=float(np.max(np.abs(torque))),
        joint_torque_unit=unit,
        motor_torque_use=util["motor torque"],
        torque_rate_use=util["motor torque rate"],
        limits_ok=result.report.ok,
        all_limits_ok=result.report.all_ok,
        exceeded_not_held=tuple(f"{r.joint} {r.quantity} {percent(r.utilisation)} %" if r.joint != "tool" else
                                f"{r.quantity} {percent(r.utilisation)} %" for r in result.report.exceeded_not_held),
        worst_limit=None if worst is None else f"{worst.joint} {worst.quantity} {percent(worst.utilisation)} %",
        geometry=path_geometry(path, task, grid, samples[0]),
        continuity=continuity(path, rest_ends=rest, samples=samples, grid=grid),
        vibration=vib,
        notes=tuple(notes),
    )


def compare_methods(
    task,
    profile,
    methods: str | Iterable | None = None,
    method_params: Mapping[str, Mapping[str, Any]] | None = None,
    time: str | float = "auto",
) -> Comparison:
    """Every method in ``methods`` (``all``/None: the whole registry) on ``task`` with ``profile``.

    ``method_params`` maps a method name to keyword parameters of its planner (e.g.
    ``{"bspline": {"k1": 0.31, "k2": 0.12}}``); ``time`` is ``auto``, ``fit`` or seconds, as for ``plan``.
    Raises only for invalid arguments; a method that fails on this move gets a row with its error.
    """
    from ..timing import parse_time

    time = parse_time(time)
    chosen = parse_methods(methods)
    method_params = dict(method_params or {})
    known = {m.value for m in chosen}
    for k in method_params:
        if k not in known:
            raise TaskError(f"method_params: {k!r} is not among the compared methods ({', '.join(sorted(known))})")
    rows = tuple(compare_row(task, profile, m, method_params.get(m.value), time) for m in chosen)
    return Comparison(task, profile.name, rows, time)


# ------------------------------------------------------------------------------------------ writers

#: CSV columns: (header with unit, key of CompareRow.as_dict() or a callable on the row)
def _csv_columns() -> list[tuple[str, Any]]:
    def g(attr):
        return lambda r: None if r.geometry is None else getattr(r.geometry, attr)

    def vib(attr):
        return lambda r: None if r.vibration is None else getattr(r.vibration, attr)

    return [
        ("method", lambda r: r.method),
        ("duration[s]", lambda r: r.duration),
        ("mode", lambda r: r.duration_mode),
        ("auto[s]", lambda r: r.auto),
        ("fit[s]", lambda r: r.fit),
        ("optimal[s]", lambda r: r.optimal),
        ("paper[s]", lambda r: r.paper_duration),
        ("v_max_norm[1]", lambda r: r.v_norm),
        ("a_max_norm[1]", lambda r: r.a_norm),
        ("j_max_norm[1]", lambda r: r.j_norm),
        ("peak_speed[m/s]", lambda r: r.peak_speed),
        ("peak_acceleration[m/s^2]", lambda r: r.peak_acceleration),
        ("peak_jerk[m/s^3]", lambda r: r.peak_jerk),
        ("joint_torque_peak[N*m|N]", lambda r: r.joint_torque_peak),
        ("motor_torque_use[1]", lambda r: r.motor_torque_use),
        ("torque_rate_use[1]", lambda r: r.torque_rate_use),
        ("limits_ok", lambda r: r.limits_ok),
        ("all_limits_ok", lambda r: r.all_limits_ok),
        ("max_height[m]", g("max_height")),
        ("overshoot[m]", g("overshoot")),
        ("drift_back[m]", g("drift_back")),
        ("drift_forward[m]", g("drift_forward")),
        ("continuity", lambda r: None if r.continuity is None else r.continuity.label),
        ("jerk_continuous", lambda r: None if r.continuity is None else r.continuity.jerk_continuous),
        ("residual_amplitude[m]", vib("max_amplitude")),
        ("residual_acceleration[m/s^2]", vib("max_acceleration_amplitude")),
        ("error", lambda r: r.error),
    ]


def write_compare_csv(comparison: Comparison, stream) -> None:
    """One header row (names with units), one row per method; floats as %.12g, empty for None."""
    import csv

    from ..export import FLOAT_FORMAT

    cols = _csv_columns()
    w = csv.writer(stream, lineterminator="\n")
    w.writerow([c[0] for c in cols])
    for r in comparison.rows:
        out = []
        for _, fn in cols:
            x = fn(r)
            if x is None:
                out.append("")
            elif isinstance(x, bool):
                out.append("true" if x else "false")
            elif isinstance(x, (float, np.floating)):
                out.append(FLOAT_FORMAT % x)
            else:
                out.append(str(x))
        w.writerow(out)


def write_compare_json(comparison: Comparison, stream) -> None:
    import json

    json.dump(comparison.as_dict(), stream, indent=2, allow_nan=False, default=float)
    stream.write("\n")
