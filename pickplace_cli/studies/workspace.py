"""Constrained workspace [Su2018, Sec. II.E]: keep the move inside the workcell and the robot's reachable,
joint-limited set, by lowering the clearance h, and (only when asked) by moving a pick or place point that
is itself outside with the artificial potential field of [Su2018, Eq. (25)].

The constrained workspace W is the set of tool positions p [m] at which

* the inverse kinematics has a solution (the robot can reach p),
* every joint lies in its position range (profile ``joints.limits.position``; the gantry's travel),
* the singularity measure is at least the profile's ``singularity_margin``,
* p lies in the workcell box (profile ``workcell.box``), when there is one,

i.e. exactly the "reach" rows of the limit check (:func:`pickplace_cli.limits.check.check_limits`, exit 4).

:func:`fit_workspace` follows the paper's procedure, made explicit:

1. a pick or place point outside W is **refused** (UnreachableError, exit 4) unless ``adjust_points`` is
   set; then the APF point is computed (:func:`apf_point`) and reported with its distance from the
   requested one, and the move is planned from it — never silently: the result lists the change. If the
   adjusted point is farther than ``max_shift`` from the requested one the part "cannot be picked" and the
   task is terminated (UnreachableError), as the paper says;
2. while the path leaves W, h is lowered by ``step`` and the path re-planned, down to ``min_height``
   [Su2018, Sec. II.E, step 2]; the first h at which every sample (the limit check's grid, then the exact
   refined check) is inside is kept.

APF [Su2018, Eq. (25)]: U = U_d + U_c with U_d = ½k_d‖p − p_i‖² (attraction to the requested point p_i)
and U_c = k_c/d² (repulsion from the boundary, d = distance from p to the boundary of W);
F = −∇U_d − ∇U_c is followed from a point inside W until it vanishes. Choices the paper leaves open:
k_d = 1 and k_c = k_d·δ⁴/2, which puts the equilibrium for a requested point *on* the boundary at the
distance δ = ``margin`` inside (for a point at distance D outside a flat boundary, (D + d)·d³ = δ⁴);
d is the first-order distance min_k g_k/‖∇g_k‖ over the constraints g_k ≥ 0 above (exact for the box and
the gantry's travel; gradients by central differences, 1 µm); the descent starts from the boundary point
found by bisection on the segment from p_i to the nearest interior point of a 25³ grid over the
workcell box (or p_i ± 0.5 m), and takes normalised steps with step halving (it stops below 1e-10 m).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Mapping

import numpy as np

from ..model.errors import PickplaceError, TaskError, UnreachableError
from ..model.task import Task

#: default step by which h is lowered [m]
HEIGHT_STEP = 0.001
#: default lowest clearance tried [m]
MIN_HEIGHT = 0.001
#: default APF equilibrium margin δ for a requested point on the boundary [m]
APF_MARGIN = 0.001
#: default largest accepted distance between a requested and an adjusted point [m]; farther means the
#: part cannot be picked there and the task is terminated [Su2018, Sec. II.E]
MAX_SHIFT = 0.01
_GRAD_STEP = 1e-6  # m, central differences of the constraint functions
#: a constraint counts as met down to this slack below zero (m, rad or 1): the limit check's tolerance for
#: ranges (limits._range_row), so both agree on what is inside
INSIDE_TOL = 1e-12


def _fmt(p: np.ndarray) -> str:
    return "(" + ", ".join(f"{c:.6g}" for c in p) + ") m"


class Workspace:
    """The constrained workspace W of a profile: constraint functions g_k(p) ≥ 0 and membership.

    ``slacks(P)`` returns (N, K) values of every constraint at the points P (N, 3) [m]: the box faces in
    m, the joint ranges in rad or m, the singularity measure minus the margin (dimensionless); −inf for
    every kinematic constraint where the inverse kinematics has no solution. ``names`` names the K columns.
    """

    def __init__(self, profile) -> None:
        from ..robots import build_robot

        self.robot = build_robot(profile.robot)
        self.specs = profile.robot.joint_specs()
        self.margin = getattr(profile.robot, "singularity_margin", None)
        self.box = profile.workcell.box
        names: list[str] = []
        for name, unit, s in zip(self.robot.joint_names, self.robot.joint_units, self.specs):
            if s.limits.position is not None:
                names += [f"{name} position min {s.limits.position[0]:g} {unit}",
                          f"{name} position max {s.limits.position[1]:g} {unit}"]
        if self.margin is not None and hasattr(self.robot, "singularity_measure"):
            names.append(f"singularity measure min {self.margin:g}")
        self._n_kin = len(names)
        if self.box is not None:
            for c, axis in enumerate("xyz"):
                names += [f"workcell {axis} min {self.box.min[c]:g} m", f"workcell {axis} max {self.box.max[c]:g} m"]
        self.names = tuple(names)

    def _ik(self, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(q (N, n) with NaN rows where unreachable, reachable mask (N,))."""
        n = len(self.robot.joint_names)
        q = np.full((len(P), n), np.nan)
        ok = np.ones(len(P), bool)
        if hasattr(self.robot, "reachable"):
            ok = np.asarray(self.robot.reachable(P), bool)
        idx = np.flatnonzero(ok)
        if idx.size:
            try:
                q[idx] = self.robot.inverse_kinematics(P[idx])
            except UnreachableError:  # no vectorised reachability test (gantry): point by point
                for i in idx:
                    try:
                        q[i] = self.robot.inverse_kinematics(P[i : i + 1])[0]
                    except UnreachableError:
                        ok[i] = False
        return q, ok

    def slacks(self, P: np.ndarray) -> np.ndarray:
        P = np.atleast_2d(np.asarray(P, float))
        cols: list[np.ndarray] = []
        if self._n_kin:
            q, ok = self._ik(P)
            for i, s in enumerate(self.specs):
                if s.limits.position is not None:
                    cols += [q[:, i] - s.limits.position[0], s.limits.position[1] - q[:, i]]
            if self.margin is not None and hasattr(self.robot, "singularity_measure"):
                mu = np.full(len(P), np.nan)
                if ok.any():
                    mu[ok] = self.robot.singularity_measure(q[ok], P[ok])
                cols.append(mu - self.margin)
            kin = np.column_stack(cols)
            kin[~ok] = -np.inf
            cols = [kin]
        elif not np.all(self._ik(P)[1]):
            raise UnreachableError("workspace: a point is unreachable but the profile defines no kinematic constraint")
        if self.box is not None:
            lo, hi = np.asarray(self.box.min), np.asarray(self.box.max)
            cols.append(np.column_stack([x for c in range(3) for x in (P[:, c] - lo[c], hi[c] - P[:, c])]))
        if not cols:
            return np.full((len(P), 0), np.inf)
        return np.column_stack(cols)

    def inside(self, P: np.ndarray, strict: bool = False) -> np.ndarray:
        """(N,) True where every constraint holds (slack ≥ −INSIDE_TOL; ``strict``: slack > 0)."""
        g = self.slacks(P)
        if not g.shape[1]:
            return np.ones(len(np.atleast_2d(P)), bool)
        return np.all(g > 0, axis=1) if strict else np.all(g >= -INSIDE_TOL, axis=1)

    def reachable(self, P: np.ndarray) -> np.ndarray:
        """(N,) True where the inverse kinematics has a solution, every joint is in its range and the
        singularity measure is at least the margin (the workcell box is not considered)."""
        P = np.atleast_2d(np.asarray(P, float))
        if self._n_kin:
            return np.all(self.slacks(P)[:, : self._n_kin] >= -INSIDE_TOL, axis=1)
        return self._ik(P)[1]

    def violation(self, p: np.ndarray) -> str | None:
        """The most violated constraint at the single point p, as words; None when p is inside."""
        g = self.slacks(np.asarray(p, float)[None, :])[0]
        if g.size == 0 or np.all(g >= -INSIDE_TOL):
            return None
        if self._n_kin and np.all(np.isneginf(g[: self._n_kin])):
            try:
                self.robot.inverse_kinematics(np.asarray(p, float)[None, :])
            except UnreachableError as exc:  # the model's own words (arm, annulus, travel …)
                return f"unreachable: {exc}"
            return "unreachable (the inverse kinematics has no solution there)"
        k = int(np.argmin(g))
        return f"{self.names[k]} (violated by {-g[k]:.4g})"

    def distance(self, p: np.ndarray) -> tuple[float, np.ndarray]:
        """(d, ∇d) at p inside W: d = min_k g_k/‖∇g_k‖ [m] (first-order distance to the boundary), ∇d the
        unit gradient of the active constraint. Central differences of g, one-sided where a neighbour is
        unreachable."""
        p = np.asarray(p, float)
        h = _GRAD_STEP
        pts = np.vstack([p, p + h * np.eye(3), p - h * np.eye(3)])
        g = self.slacks(pts)
        g0, gp, gm = g[0], g[1:4], g[4:7]
        with np.errstate(invalid="ignore"):
            central = (gp - gm) / (2 * h)
            fwd = (gp - g0) / h
            bwd = (g0 - gm) / h
        grad = np.where(np.isfinite(central), central, np.where(np.isfinite(fwd), fwd, bwd))  # (3, K)
        grad = np.where(np.isfinite(grad), grad, 0.0)
        norm = np.linalg.norm(grad, axis=0)
        with np.errstate(divide="ignore", invalid="ignore"):
            d = np.where(norm > 0, g0 / norm, np.inf)
        k = int(np.argmin(d))
        return float(d[k]), (grad[:, k] / norm[k] if norm[k] > 0 else np.zeros(3))


@dataclass(frozen=True)
class RadialExtent:
    """Where the tool can be at height ``z`` [m]: along ``directions`` rays from the base z axis (azimuth
    measured from +x toward +y), the radius interval [m] each ray reaches (its longest run of reachable
    points on the scan grid; None when it reaches nothing), and the band from the smallest to the largest of
    those radii. ``within`` names what limits it (for the sentence)."""

    z: float
    azimuth: np.ndarray  # (D,) rad
    runs: tuple[tuple[float, float] | None, ...]  # per direction, m
    band: tuple[float, float] | None  # m
    full: np.ndarray  # (D,) bool: the direction reaches the whole band
    within: str

    @property
    def reached(self) -> int:
        return sum(r is not None for r in self.runs)

    def sectors(self) -> list[tuple[float, float]]:
        """The azimuth intervals [deg] of consecutive directions that reach the whole band (a sector through
        0° starts at a negative angle)."""
        full = self.full
        n = len(full)
        if full.all() or not full.any():
            return []
        deg = np.degrees(self.azimuth)
        start = int(np.flatnonzero(~full)[0])  # begin the circular walk at a direction outside every sector
        out, run = [], []
        for k in range(start, start + n + 1):
            i = k % n
            if full[i] and k < start + n:
                run.append(i)
            elif run:
                a, b = deg[run[0]], deg[run[-1]]
                out.append((a - 360.0 if a > b else a, b))
                run = []
        return sorted(out)

    def describe(self) -> str:
        """One sentence for ``profile show``: which radii are reachable, and in which directions."""
        n = len(self.runs)
        if self.band is None:
            return f"nothing is reachable at this height ({self.within})"
        found = [r for r in self.runs if r is not None]
        inner = (min(r[0] for r in found), max(r[0] for r in found))  # m: the nearest reachable radius varies in here
        outer = (min(r[1] for r in found), max(r[1] for r in found))  # m: the farthest one in here
        if self.reached == n:
            if inner[1] <= outer[0]:  # a ring (or disc) common to every direction
                text = f"radius {inner[1]:.3f} … {outer[0]:.3f} m reachable in every direction"
                more = []
                if inner[0] < inner[1]:
                    more.append(f"from {inner[0]:.3f} m")
                if outer[1] > outer[0]:
                    more.append(f"out to {outer[1]:.3f} m")
                if more:
                    text += f"; in some directions {' and '.join(more)}"
            else:
                text = (f"reachable in every direction, but over radii that depend on it: from {inner[0]:.3f} … "
                        f"{inner[1]:.3f} m out to {outer[0]:.3f} … {outer[1]:.3f} m, no radius in all of them")
            return f"{text} ({self.within})"
        lo, hi = self.band
        k = int(self.full.sum())
        partial = self.reached - k
        none = n - self.reached
        if k:
            where = ", ".join(f"{a:g}° … {b:g}°" if a != b else f"{a:g}°" for a, b in self.sectors())
            text = f"radius {lo:.3f} … {hi:.3f} m reachable in {k} of {n} directions (azimuth {where}, every {360.0 / n:g}°)"
            rest = ([f"{partial} more reach only part of that range"] if partial else []) + ([f"{none} reach nothing"] if none else [])
            if rest:
                text += "; " + " and ".join(rest)
        else:
            text = (f"reachable in {self.reached} of {n} directions over radii that depend on the direction, from "
                    f"{inner[0]:.3f} … {inner[1]:.3f} m out to {outer[0]:.3f} … {outer[1]:.3f} m; {none} reach nothing")
        return f"{text} ({self.within})"


def radial_extent(profile, z: float, directions: int = 72, step: float = 0.001, max_radius: float = 2.0) -> RadialExtent:
    """The reachable radii at height ``z`` [m] along ``directions`` rays from the base z axis, scanned every
    ``step`` [m] from 0 to ``max_radius`` (doubled while a ray is still reachable at the end of the scan).
    Reachable means :meth:`Workspace.reachable`: inverse kinematics, joint ranges, singularity margin (not
    the workcell box). Raises TaskError for a non-finite ``z``."""
    if not np.isfinite(z):
        raise TaskError(f"z = {z!r}: must be a finite height in m")
    ws = Workspace(profile)
    az = np.linspace(0.0, 2 * np.pi, directions, endpoint=False)
    while True:
        rho = np.arange(0.0, max_radius + step / 2, step)
        P = np.stack([np.outer(np.cos(az), rho), np.outer(np.sin(az), rho), np.full((directions, len(rho)), z)], axis=-1)
        ok = ws.reachable(P.reshape(-1, 3)).reshape(directions, len(rho))
        runs: list[tuple[int, int] | None] = []
        for row in ok:
            idx = np.flatnonzero(row)
            if idx.size == 0:
                runs.append(None)
                continue
            cut = np.flatnonzero(np.diff(idx) > 1)
            starts, ends = np.r_[idx[0], idx[cut + 1]], np.r_[idx[cut], idx[-1]]
            longest = int(np.argmax(ends - starts))
            runs.append((int(starts[longest]), int(ends[longest])))
        if max_radius >= 64.0 or not any(r is not None and r[1] == len(rho) - 1 for r in runs):
            break
        max_radius *= 2
    found = [r for r in runs if r is not None]
    band = (min(r[0] for r in found), max(r[1] for r in found)) if found else None
    full = np.array([r is not None and band is not None and r[0] <= band[0] and r[1] >= band[1] for r in runs])
    specs = profile.robot.joint_specs()
    limits = ["the arm's reach"]
    if any(s.limits.position is not None for s in specs):
        limits.append("the joint ranges")
    if ws.margin is not None and hasattr(ws.robot, "singularity_measure"):
        limits.append(f"the singularity margin {ws.margin:g}")
    within = "within " + (", ".join(limits[:-1]) + " and " + limits[-1] if len(limits) > 1 else limits[0])
    return RadialExtent(
        float(z), az, tuple(None if r is None else (float(rho[r[0]]), float(rho[r[1]])) for r in runs),
        None if band is None else (float(rho[band[0]]), float(rho[band[1]])), full, within,
    )


@dataclass(frozen=True)
class PointAdjustment:
    """A pick or place point moved into the workspace by the APF [Su2018, Eq. (25)] (positions in m)."""

    name: str  # "from" or "to"
    requested: np.ndarray
    adjusted: np.ndarray
    distance: float  # m between requested and adjusted
    violation: str  # what the requested point violated
    iterations: int

    def as_dict(self) -> dict[str, Any]:
        return {"point": self.name, "requested_m": self.requested.tolist(), "adjusted_m": self.adjusted.tolist(),
                "distance_m": self.distance, "violation": self.violation, "iterations": self.iterations}


@dataclass(frozen=True)
class WorkspaceFit:
    """What :func:`fit_workspace` did: ``task`` is the move to plan (``requested`` unless something
    changed), ``path`` its CartesianPath; ``violation`` what the requested move violated (None if nothing);
    ``steps`` how many times h was lowered; ``adjustments`` the moved end points (only with
    ``adjust_points``)."""

    requested: Task
    task: Task
    path: Any
    method: str
    violation: str | None
    steps: int
    adjustments: tuple[PointAdjustment, ...] = ()

    @property
    def changed(self) -> bool:
        return bool(self.steps or self.adjustments)

    def changes(self) -> list[str]:
        """One line per change, for the user (empty when the requested move was inside)."""
        out = [
            f"{a.name} moved by the APF (Su 2018 Eq. 25) from {_fmt(a.requested)} to {_fmt(a.adjusted)}: "
            f"{a.distance:.4g} m away (the requested point: {a.violation})"
            for a in self.adjustments
        ]
        if self.steps:
            out.append(
                f"height lowered from {self.requested.height:.4g} m to {self.task.height:.4g} m in {self.steps} "
                f"step(s) so the path stays inside the workspace (at the requested height: {self.violation})"
            )
        return out

    def as_dict(self) -> dict[str, Any]:
        return {
            "method": self.method,
            "changed": self.changed,
            "height_requested_m": self.requested.height,
            "height_m": self.task.height,
            "height_steps": self.steps,
            "violation_at_request": self.violation,
            "from_m": self.task.p_from.tolist(),
            "to_m": self.task.p_to.tolist(),
            "adjustments": [a.as_dict() for a in self.adjustments],
            "changes": self.changes(),
        }


def _interior_start(ws: Workspace, p_req: np.ndarray) -> np.ndarray:
    """An interior point near p_req: the nearest interior point of a 25³ grid over the box (or p_req ±
    0.5 m), then bisection on the segment toward p_req to the boundary (kept on the inside)."""
    if ws.box is not None:
        lo, hi = np.asarray(ws.box.min, float), np.asarray(ws.box.max, float)
    else:
        lo, hi = p_req - 0.5, p_req + 0.5
    axes = [np.linspace(lo[c], hi[c], 25) for c in range(3)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    g = ws.slacks(grid)
    inside = np.all(g > 0, axis=1)
    if not inside.any():
        raise UnreachableError(f"workspace: no point of the search region around {_fmt(p_req)} is inside the workspace")
    cand = grid[inside]
    a = cand[int(np.argmin(np.linalg.norm(cand - p_req, axis=1)))]  # inside
    b = p_req.copy()  # outside
    for _ in range(60):
        mid = 0.5 * (a + b)
        if ws.inside(mid[None, :], strict=True)[0]:
            a = mid
        else:
            b = mid
        if np.linalg.norm(b - a) < 1e-12:
            break
    return a


def apf_point(ws: Workspace, p_req, margin: float = APF_MARGIN, k_d: float = 1.0, max_iter: int = 2000) -> tuple[np.ndarray, int]:
    """(adjusted point [m], iterations): the equilibrium of F = −∇U_d − ∇U_c [Su2018, Eq. (25)] inside the
    workspace nearest the requested point ``p_req`` (see the module docstring for k_d, k_c and d)."""
    p_req = np.asarray(p_req, float)
    if not (np.isfinite(margin) and margin > 0):
        raise ValueError(f"margin must be a finite positive distance in m, got {margin!r}")
    k_c = k_d * margin**4 / 2.0

    def energy(p: np.ndarray) -> tuple[float, np.ndarray]:
        d, gd = ws.distance(p)
        if not d > 0:
            return np.inf, np.zeros(3)
        u = 0.5 * k_d * float(np.sum((p - p_req) ** 2)) + k_c / d**2
        force = -k_d * (p - p_req) + 2.0 * k_c / d**3 * gd  # F = −∇U_d − ∇U_c (∇U_c = −2k_c/d³ ∇d)
        return u, force

    p = _interior_start(ws, p_req)
    u, f = energy(p)
    step = max(margin, 1e-6)
    it = 0
    while it < max_iter and step > 1e-10:
        it += 1
        fn = np.linalg.norm(f)
        if fn == 0:
            break
        cand = p + step * f / fn
        if ws.inside(cand[None, :], strict=True)[0]:
            uc, fc = energy(cand)
            if uc < u:
                p, u, f = cand, uc, fc
                step *= 1.5
                continue
        step *= 0.5
    return p, it


def fit_workspace(
    task: Task,
    profile,
    method: str = "bspline",
    method_params: Mapping[str, Any] | None = None,
    *,
    step: float = HEIGHT_STEP,
    min_height: float = MIN_HEIGHT,
    adjust_points: bool = False,
    margin: float = APF_MARGIN,
    max_shift: float = MAX_SHIFT,
) -> WorkspaceFit:
    """Fit ``task`` into the profile's constrained workspace [Su2018, Sec. II.E] (module docstring).

    ``step`` [m]: how much h is lowered per step; ``min_height`` [m]: the lowest h tried; ``adjust_points``:
    move a pick/place point outside the workspace by the APF (otherwise refuse: UnreachableError, exit 4);
    ``margin`` [m]: the APF's δ; ``max_shift`` [m]: farther than this the part cannot be picked
    (UnreachableError). Raises UnreachableError when no h ≥ ``min_height`` keeps the path inside; the
    error of the method itself when the requested move cannot be planned at all (e.g. TableError).
    ``method_params`` go to the planner (a method whose path depends on the duration needs it there).
    """
    from ..limits.check import check_limits
    from ..limits.grid import check_grid
    from ..limits.motion import MotionModel
    from ..paths import plan_path
    from ..planner import motion_model

    for name, value in (("step", step), ("min_height", min_height), ("margin", margin), ("max_shift", max_shift)):
        if not (np.isfinite(value) and value > 0):
            raise TaskError(f"{name} = {value!r}: must be a finite distance in m > 0")
    params = dict(method_params or {})
    ws = Workspace(profile)
    adjustments: list[PointAdjustment] = []
    points = {"from": task.p_from, "to": task.p_to}
    for name, p in points.items():
        why = ws.violation(p)
        if why is None:
            continue
        if not adjust_points:
            raise UnreachableError(
                f"{name} = {_fmt(p)} is outside the workspace: {why}; a pick or place point is never moved "
                "silently: ask for the APF-adjusted point (--adjust-points) to see the nearest one inside"
            )
        q, it = apf_point(ws, p, margin)
        dist = float(np.linalg.norm(q - p))
        if dist > max_shift:
            raise UnreachableError(
                f"{name} = {_fmt(p)} is outside the workspace ({why}) and the nearest point inside by the APF, "
                f"{_fmt(q)}, is {dist:.4g} m away, more than max_shift = {max_shift:g} m: the part cannot be "
                "picked there; task terminated (Su 2018 Sec. II.E)"
            )
        adjustments.append(PointAdjustment(name, p.copy(), q, dist, why, it))
        points[name] = q
    base = replace(task, p_from=points["from"], p_to=points["to"])  # the tool angles, if any, stay

    def outside(t: Task):
        """(path, None) when the path of t is inside W, else (path or None, reason)."""
        try:
            path = plan_path(t, method, **params)
        except PickplaceError as exc:
            if t is base:
                raise  # the requested move itself cannot be planned: not a workspace problem
            return None, f"cannot plan at h = {t.height:.4g} m: {exc}"
        grid = check_grid(np.array([0.0, 1.0]), path.breakpoints, path.jumps)
        P = path(grid, 0)
        inside = ws.inside(P)
        if not inside.all():
            i = int(np.argmin(inside))  # the first point out, and the constraint it breaks most
            g = ws.slacks(P)
            k = int(np.argmin(g[i]))
            if np.isfinite(g[i, k]):  # that constraint where the path breaks it most (the first point out barely
                # does: its excess understated the violation), among the points where it is defined (reachable)
                i = int(np.argmin(np.where(np.isfinite(g[:, k]), g[:, k], np.inf)))
                return path, f"worst at τ = {grid[i]:.4f}, {_fmt(P[i])}: {ws.names[k]} (violated by {-g[i, k]:.4g})"
            return path, f"τ = {grid[i]:.4f} at {_fmt(P[i])}: {ws.violation(P[i])}"
        # the exact check of plan (reach rows refined on the continuous path)
        model: MotionModel = motion_model(path, profile)
        try:
            rep = check_limits(model, 1.0, parts=model.parts(grid))
        except UnreachableError as exc:
            return path, str(exc)
        bad = [r for r in rep.violations if r.kind == "reach"]
        if bad:
            r = bad[0]
            return path, f"{r.joint} {r.quantity} = {r.peak:.6g} {r.unit} at τ = {r.t_peak:.4f}; limit {r.limit:.6g} {r.unit}"
        return path, None

    path, first = outside(base)
    if first is None:
        return WorkspaceFit(task, base, path, str(getattr(method, "value", method)), None, 0, tuple(adjustments))
    k = 0
    reason = first
    while True:
        k += 1
        h = task.height - k * step
        if h < min_height - 1e-12:
            raise UnreachableError(
                f"height: no clearance between {task.height:.4g} m and {min_height:.4g} m (step {step:g} m) keeps "
                f"the path inside the workspace; at h = {task.height:.4g} m: {first}; last tried: {reason}"
            )
        cand = replace(base, height=h)
        path, reason = outside(cand)
        if path is None:
            raise UnreachableError(
                f"height: lowered to {h:.4g} m without getting inside the workspace and {reason}; "
                f"at h = {task.height:.4g} m: {first}"
            )
        if reason is None:
            return WorkspaceFit(task, cand, path, str(getattr(method, "value", method)), first, k, tuple(adjustments))
