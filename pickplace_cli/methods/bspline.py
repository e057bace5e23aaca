"""Quintic B-spline pick-and-place path [Li2018, Sec. 2.3]: two time-ratio factors k1, k2 set the knots."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..bspline import li_knots, make_spline, norm_peaks, solve_control_points
from ..errors import TaskError
from ..task import Task
from ..trajectory import CartesianPath


def bspline_curve(task: Task, k1: float, k2: float):
    """The scipy BSpline (11 control points in 3-D, base frame) of [Li2018, Eq. (11)–(16)].

    Equivalent to Eq. (15) r = b·(s_u, λ⁻¹ s_v) mapped by Eq. (1): the control points are solved in base-frame
    axes directly (the map is affine, so the spline commutes with it). The spline holds the displacement
    from P1 (add ``task.p_from`` for positions): small coordinates keep the round-off of the cancelling
    end derivatives (|N‴| ~ 1/τ7³) at the level of the move, not of the robot's base offset.
    """
    knots = li_knots(k1, k2)
    via_tau = knots[[0, 7, 8, 9, 16]]  # τ1 = 0, τ8, τ9, τ10, τ17 = 1 (Eq. 8 with f = 5)
    q = solve_control_points(knots, via_tau, task.via_points() - task.p_from)
    return make_spline(knots, q)


def plan_bspline(
    task: Task, k1: float | None = None, k2: float | None = None, table: str | Path | None = None
) -> CartesianPath:
    """CartesianPath of the B-spline method; k1, k2 from the look-up table at λ unless both are given."""
    if (k1 is None) != (k2 is None):
        raise TaskError("k1/k2: give both time-ratio factors or neither (then they come from the table)")
    source = "given"
    if k1 is None:
        from ..table import load_table

        if task.b == 0:
            raise TaskError(
                "from/to are vertically aligned (b = 0): the k1/k2 table starts at λ = b/h ≥ 1; "
                "give --k1 and --k2 for a purely vertical move"
            )
        tab = load_table(table)
        k1, k2 = tab.lookup(task.lam, eta=task.eta)
        source = f"table {tab.source}"
    for name, k in (("k1", k1), ("k2", k2)):
        if not (np.isfinite(k) and 0 < k < 1):
            raise TaskError(f"{name} = {k!r}: time-ratio factors must lie strictly between 0 and 1")
    spline = bspline_curve(task, float(k1), float(k2))
    peaks = norm_peaks(spline, (1, 2, 3))

    origin = task.p_from

    def evaluate(tau: np.ndarray, order: int) -> np.ndarray:
        out = spline(tau, nu=order)
        return out + origin if order == 0 else out

    return CartesianPath(
        evaluate=evaluate,
        method="bspline",
        parameters={"k1": float(k1), "k2": float(k2), "k_source": source, "lambda": task.lam, "eta": task.eta},
        peaks=peaks,  # type: ignore[arg-type]
        breakpoints=np.unique(spline.t),
    )
