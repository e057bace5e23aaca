"""Check a trajectory that was planned elsewhere (or by this tool) against a profile's limits.

The CSV needs a header with ``t`` and the joint positions ``q1 … qn`` (unit suffixes like ``q1[rad]`` are
ignored). Positions go through forward kinematics to the tool path; a quintic spline through the tool
positions (interpolating by default, smoothing with ``smoothing`` > 0) gives the continuous motion and its
derivatives, which then run through the same joint mapping, dynamics and limit check as ``plan``.
"""

from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np

from .errors import TaskError
from .limits import LimitReport, MotionModel, check_grid, check_limits
from .profile import Profile
from .robots import build_robot
from .trajectory import CartesianPath


def read_trajectory(text: str, source: str, joint_names: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray]:
    """(t (N,), q (N, n)) from CSV text; TaskError naming the file, line and problem."""
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    if not lines:
        raise TaskError(f"{source}: empty file (need a header with t and {', '.join(joint_names)})")
    dialect_sep = ";" if lines[0].count(";") > lines[0].count(",") else ("\t" if "\t" in lines[0] else ",")
    rows = list(csv.reader(io.StringIO("\n".join(lines)), delimiter=dialect_sep))
    header = [h.strip().split("[")[0].strip() for h in rows[0]]
    need = ["t", *joint_names]
    missing = [c for c in need if c not in header]
    if missing:
        raise TaskError(f"{source}:1: header lacks column(s) {', '.join(missing)} (need {', '.join(need)}; found {', '.join(header)})")
    idx = [header.index(c) for c in need]
    data = np.empty((len(rows) - 1, len(need)))
    for n, r in enumerate(rows[1:], start=2):
        try:
            data[n - 2] = [float(r[i]) for i in idx]
        except (ValueError, IndexError):
            raise TaskError(f"{source}:{n}: not a number in a needed column ({', '.join(need)})") from None
    if not np.all(np.isfinite(data)):
        bad = int(np.argwhere(~np.isfinite(data))[0, 0]) + 2
        raise TaskError(f"{source}:{bad}: values must be finite")
    if len(data) < 6:
        raise TaskError(f"{source}: {len(data)} samples; need at least 6 for a quintic spline")
    t = data[:, 0]
    if np.any(np.diff(t) <= 0):
        bad = int(np.flatnonzero(np.diff(t) <= 0)[0]) + 3
        raise TaskError(f"{source}:{bad}: t must increase strictly from row to row")
    return t - t[0], data[:, 1:]


def check_trajectory(path: str | Path, profile: Profile, smoothing: float = 0.0) -> LimitReport:
    """Limit report of the trajectory in CSV file ``path`` on ``profile`` (see module docstring)."""
    from scipy.interpolate import UnivariateSpline, make_interp_spline

    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8") if str(path) != "-" else __import__("sys").stdin.read()
    except OSError as exc:
        raise TaskError(f"{p}: cannot read: {exc.strerror}") from None
    robot = build_robot(profile.robot)
    t, q = read_trajectory(text, str(p), robot.joint_names)
    pos = robot.forward_kinematics(q)
    T = float(t[-1])
    if smoothing > 0:
        splines = [UnivariateSpline(t, pos[:, k], k=5, s=smoothing * len(t)) for k in range(3)]

        def ev(x: np.ndarray, order: int) -> np.ndarray:
            return np.column_stack([s.derivative(order)(x) if order else s(x) for s in splines])

        how = f"a quintic smoothing spline (s = {smoothing:g}·N) of the tool positions FK(q)"
    else:
        spline = make_interp_spline(t, pos, k=5)

        def ev(x: np.ndarray, order: int) -> np.ndarray:
            return spline(x, nu=order)

        how = "a quintic interpolating spline of the tool positions FK(q)"

    def evaluate(tau: np.ndarray, order: int) -> np.ndarray:
        return ev(np.clip(tau, 0.0, 1.0) * T, order) * T**order

    cpath = CartesianPath(evaluate, "checked", {"source": str(p)}, (0.0, 0.0, 0.0), t / T)
    margin = getattr(profile.robot, "singularity_margin", None)
    model = MotionModel(cpath, robot, profile.robot.joint_specs(), margin, profile.workcell.box)
    tau = t / T
    notes = (f"{p}: {len(t)} samples over {T:.6g} s; derivatives from {how}",)
    grid = check_grid(tau, tau)
    return check_limits(model, T, parts=model.parts(grid), dwell=profile.planning.dwell, notes=notes)
