"""Quintic B-spline pick-and-place path [Li2018, Sec. 2.3]: two time-ratio factors k1, k2 set the knots."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..curves.bspline import (
    DEGREE,
    batch_control_points,
    batch_li_knots,
    batch_piece_coefficients,
    batch_pieces,
    li_knots,
    make_spline,
    solve_control_points,
)
from ..model.errors import TableError, TaskError
from ..curves.peaks import batch_norm_peaks
from ..model.task import Task
from ..model.trajectory import CartesianPath


def bspline_curve(task: Task, k1: float, k2: float):
    """The scipy BSpline (11 control points in 3-D, base frame) of [Li2018, Eq. (11)–(16)]
    (:func:`bspline_control_points` wrapped by scipy; the planner uses the control points directly).

    Equivalent to Eq. (15) r = b·(s_u, λ⁻¹ s_v) mapped by Eq. (1): the control points are solved in base-frame
    axes directly (the map is affine, so the spline commutes with it). The spline holds the displacement
    from P1 (add ``task.p_from`` for positions): small coordinates keep the round-off of the cancelling
    end derivatives (|N‴| ~ 1/τ7³) at the level of the move, not of the robot's base offset.
    """
    return make_spline(*bspline_control_points(task, k1, k2))


def bspline_control_points(task: Task, k1: float, k2: float) -> tuple[np.ndarray, np.ndarray]:
    """Knots (17,) and control points (11, 3) [m, displacement from P1] of [Li2018, Eq. (11)–(16)]."""
    knots = li_knots(k1, k2)
    via_tau = knots[[0, 7, 8, 9, 16]]  # τ1 = 0, τ8, τ9, τ10, τ17 = 1 (Eq. 8 with f = 5)
    return knots, solve_control_points(knots, via_tau, task.via_points() - task.p_from)


#: range of the time-ratio factors k1, k2 (Eq. 14 needs 0 < k < 1; toward 0 or 1 a knot span shrinks to
#: nothing, the jerk and the duration grow without bound and the control-point solve becomes singular; the
#: table build's own floor for k2 is 1e-4)
K_RANGE = (1e-4, 1.0 - 1e-4)


def check_k(name: str, k: float) -> None:
    """TaskError unless ``k`` lies in :data:`K_RANGE`."""
    if not (np.isfinite(k) and K_RANGE[0] <= k <= K_RANGE[1]):
        raise TaskError(f"{name} = {k!r}: time-ratio factors must lie in [{K_RANGE[0]:g}, {K_RANGE[1]:g}]")


#: the largest arch accepted, as a multiple of the clearance h (a path 50 h tall is no pick-and-place move)
ARCH_MAX = 50.0


def check_arch(task: Task, arch: float) -> float:
    """The arch height [m] as a float; TaskError unless finite and in [0, ARCH_MAX·h]."""
    a = float(arch)
    if not (np.isfinite(a) and 0.0 <= a <= ARCH_MAX * task.height):
        raise TaskError(f"arch = {arch!r} m: the apex's height above the clearance must lie in [0, "
                        f"{ARCH_MAX:g}·h = {ARCH_MAX * task.height:g}] m")
    return a


def arched_via(task: Task, arch: float, eta_down: float | None = None, mid_x: float | None = None) -> np.ndarray:
    """The via points P1 … P5 (5, 3) [m, displacement from P1] of the widened family: [Li2018, Eq. (11)] with the
    midpoint P3 raised by ``arch`` [m] above the clearance; P2, P4 stay at η of the rise to the clearance
    (η·h over equal end heights), so the lift-off/set-down heights keep their meaning. ``eta_down`` [-] puts
    P4 at that ratio of the set-down end's rise instead (lift-off and set-down at two heights); ``mid_x`` [-]
    places P3 horizontally at that fraction of the way from P1 to P5 (Li: 1/2). ``arch = 0`` with both None is
    the Li path's own via points, bitwise."""
    via = task.via_points() - task.p_from
    if arch:
        via[2, 2] += arch
    if eta_down is not None:
        z5 = task.p_to[2] - task.p_from[2]
        via[3, 2] = z5 + eta_down * (task.z_top - task.p_to[2])
    if mid_x is not None:
        via[2, :2] = mid_x * via[4, :2]
    return via


#: ranges of ``eta_down`` (the set-down ratio, as η: Task's own bound kept off 0 and 1 by the search's) and
#: ``mid_x`` (P3's horizontal placement as a fraction of the span)
ETA_DOWN_RANGE = (0.01, 0.99)
MID_X_RANGE = (0.2, 0.8)


def check_fraction(name: str, value: float, bounds: tuple[float, float], what: str) -> float:
    """``value`` as a float; TaskError naming the parameter, value and range unless finite and within ``bounds``."""
    v = float(value)
    if not (np.isfinite(v) and bounds[0] <= v <= bounds[1]):
        raise TaskError(f"{name} = {value!r}: {what} must lie in [{bounds[0]:g}, {bounds[1]:g}]")
    return v


#: range of the midpoint's knot τ9 (Li: 1/2) of the asymmetric family
MID_RANGE = (0.2, 0.8)


def general_knots(k1: float, k2: float, k3: float, k4: float, mid: float) -> np.ndarray:
    """The 17 knots of the asymmetric family: P3 at τ9 = ``mid``, the lift-off side's knots from k1 = τ8/τ9,
    k2 = τ7/τ8 as [Li2018, Eq. (13)], the set-down side's mirrored, k3 = (1 − τ10)/(1 − τ9), k4 = (1 − τ11)/(1 − τ10).
    k3 = k1, k4 = k2, mid = 1/2 are Li's knots (Eq. 14)."""
    return np.array([0.0] * 6 + [k1 * k2 * mid, k1 * mid, mid, 1 - k3 * (1 - mid), 1 - k3 * k4 * (1 - mid)]
                    + [1.0] * 6)


def plan_bspline(
    task: Task, k1: float | None = None, k2: float | None = None, table: str | Path | None = None,
    arch: float = 0.0, k3: float | None = None, k4: float | None = None, mid: float | None = None,
    eta_down: float | None = None, mid_x: float | None = None,
) -> CartesianPath:
    """CartesianPath of the B-spline method; k1, k2 from the look-up table at λ unless both are given.

    The widened family (``--optimize shape`` chooses its parameters; the defaults are Li's path, bitwise):
    ``arch`` [m] ≥ 0 raises the path's midpoint P3 above the clearance (the clearance becomes a lower bound, not
    the apex: :func:`arched_via`); ``k3``, ``k4`` (the set-down side's time-ratio factors, default k1, k2) and
    ``mid`` (P3's knot τ9, default 1/2) make the knots asymmetric (:func:`general_knots`), a departure from
    [Li2018], whose path is symmetric in time: a Delta's arms are not placed symmetrically about a move, so its
    fastest path is not either. ``eta_down`` [-] (default η) sets the set-down height apart from the lift-off's
    and ``mid_x`` [-] (default 1/2) places P3 along the span (:func:`arched_via`)."""
    return _plan_bspline(task, k1, k2, table, arch, k3, k4, mid, eta_down=eta_down, mid_x=mid_x)


def screen_bspline(task: Task, k1: float, k2: float, arch: float = 0.0, k3: float | None = None,
                   k4: float | None = None, mid: float | None = None, peaks: bool = True,
                   eta_down: float | None = None, mid_x: float | None = None) -> CartesianPath:
    """:func:`plan_bspline` for the shape search's screen: with ``peaks`` False an asymmetric path (k3, k4, mid
    given) skips its exact Cartesian peaks (NaN then: only the capacity's duration reads them, and the screen
    without the capacity never does); the path itself is bitwise plan_bspline's. Never returned to a user."""
    return _plan_bspline(task, k1, k2, None, arch, k3, k4, mid, peaks, eta_down, mid_x)


def check_placement(eta_down: float | None, mid_x: float | None) -> tuple[float | None, float | None]:
    """``eta_down``, ``mid_x`` as floats (None stays None); TaskError naming one outside its range."""
    if eta_down is not None:
        eta_down = check_fraction("eta_down", eta_down, ETA_DOWN_RANGE, "the set-down ratio (P4 at eta_down of the "
                                  "set-down end's rise to the clearance)")
    if mid_x is not None:
        mid_x = check_fraction("mid_x", mid_x, MID_X_RANGE, "the midpoint's horizontal placement (fraction of the "
                               "span from P1)")
    return eta_down, mid_x


def _plan_bspline(
    task: Task, k1: float | None = None, k2: float | None = None, table: str | Path | None = None,
    arch: float = 0.0, k3: float | None = None, k4: float | None = None, mid: float | None = None,
    want_peaks: bool = True, eta_down: float | None = None, mid_x: float | None = None,
) -> CartesianPath:
    """:func:`plan_bspline`; with ``want_peaks`` False an asymmetric path's peaks are NaN (:func:`screen_bspline`)."""
    arch = check_arch(task, arch)
    eta_down, mid_x = check_placement(eta_down, mid_x)
    general = not (k3 is None and k4 is None and mid is None)
    if (k1 is None) != (k2 is None):
        raise TaskError("k1/k2: give both time-ratio factors or neither (then they come from the table)")
    source = "given"
    if k1 is None:
        from ..lookup.bspline_table import load_table

        if task.b == 0:
            raise TaskError(
                "from/to are vertically aligned (b = 0): the k1/k2 table starts at λ = b/h ≥ 1; "
                "give --k1 and --k2 for a purely vertical move"
            )
        tab = load_table(table)
        try:
            k1, k2 = tab.lookup(task.lam, eta=task.eta)
            source = f"table {tab.source}"
        except TableError as exc:  # a (λ, η) the table does not cover: the 2-D table, else solved for this move
            k1, k2, source = _k_beyond_table(task, tab.source, "η" if str(exc).startswith("eta") else "λ",
                                             two_d=table is None)
    for name, k in (("k1", k1), ("k2", k2)):
        check_k(name, k)
    if general:
        k3 = k1 if k3 is None else k3
        k4 = k2 if k4 is None else k4
        mid = 0.5 if mid is None else float(mid)
        for name, k in (("k3", k3), ("k4", k4)):
            check_k(name, k)
        if not (np.isfinite(mid) and MID_RANGE[0] <= mid <= MID_RANGE[1]):
            raise TaskError(f"mid = {mid!r}: the midpoint's knot must lie in [{MID_RANGE[0]:g}, {MID_RANGE[1]:g}]")
    # numpy only (no scipy import on the online path), and the very arithmetic of the batch verdict
    # engine (P = 1): control points, the exact polynomial of every piece, the exact peaks
    via = arched_via(task, arch, eta_down, mid_x)[None]
    k1a, k2a = np.array([float(k1)]), np.array([float(k2)])
    if general:  # asymmetric knots: the batched de Boor recursion on them
        b_all, c_all, pk_all = _deboor_knots(general_knots(k1, k2, k3, k4, mid)[None], via, want_peaks)
    else:
        route = np.array([_route_one(k1a[0], k2a[0], via[0])])  # _route's decision, on floats (one move)
        b_all, c_all, pk_all = batch_paths(k1a, k2a, via, route=route)
    breaks, coef = b_all[0], c_all[0]  # (m+1,), (m, 3, 6): the exact polynomial of each piece
    peaks = tuple(pk_all[0].tolist())
    # the end states exactly (clamped ends, Eq. 9: Q1 = … = Q4 and Q8 = … = Q11, so the derivatives there
    # are differences of equal control points, zero without round-off, as de Boor gives them)
    ends = np.zeros((2, 4, 3))  # (τ = 0, τ = 1) × (p, p′, p″, p‴)
    ends[0, 0], ends[1, 0] = via[0, 0], via[0, -1]

    origin = task.p_from
    # the polynomials of p, p′, p″, p‴ on every piece, highest power first, the derivatives padded with
    # leading zeros (Horner then gives each order bitwise as its own shorter Horner would), stored as
    # (m pieces, 6 powers, 12 = 4 orders × 3 axes): one gather per sample, then Horner on (N, 12) blocks
    stacked = np.zeros((len(coef), DEGREE + 1, 4, 3))
    stacked[:, :, 0] = coef.transpose(0, 2, 1)
    for k in range(1, 4):
        stacked[:, k:, k] = (coef[..., : DEGREE + 1 - k] * _FALLING[k]).transpose(0, 2, 1)
    by_piece = stacked.reshape(len(coef), DEGREE + 1, 12)
    ends12 = ends.reshape(2, 12)
    memo: list = [None]  # one entry (τ, (N, 4, 3)): the pipeline asks orders 0…3 at the same τ in turn

    def evaluate(tau: np.ndarray, order: int) -> np.ndarray:
        entry = memo[0]
        if entry is None or entry[0] is not tau:
            entry = (tau, _all_orders(tau))
            memo[0] = entry
        out = entry[1][:, order]
        return out + origin if order == 0 else out.copy()

    def evaluate_all(tau: np.ndarray) -> list[np.ndarray]:
        acc = _all_orders(tau)  # a new array: its views are the caller's alone
        return [acc[:, 0] + origin, acc[:, 1], acc[:, 2], acc[:, 3]]

    def _all_orders(tau: np.ndarray) -> np.ndarray:
        """(N, 4, 3): p, p′, p″, p‴ by Horner on the piece polynomials (one search for every order)."""
        i = np.minimum(np.maximum(np.searchsorted(breaks, tau, side="right") - 1, 0), len(coef) - 1)
        dx = np.repeat((tau - breaks[i])[:, None], 12, axis=1)  # (N, 12): no broadcasting in the loop
        c = by_piece[i]  # (N, 6, 12)
        acc = c[:, 0] * dx
        acc += c[:, 1]
        for col in range(2, DEGREE + 1):  # one Horner pass for all four orders, in place
            acc *= dx
            acc += c[:, col]
        # the end states exactly as de Boor gives them (v = a = 0 without round-off)
        if tau[0] <= 0.0 or tau[-1] >= 1.0 or ((tau <= 0.0) | (tau >= 1.0)).any():
            acc[tau <= 0.0] = ends12[0]
            acc[tau >= 1.0] = ends12[1]
        return acc.reshape(-1, 4, 3)

    return CartesianPath(
        evaluate=evaluate,
        evaluate_all=evaluate_all,
        method="bspline",
        parameters={"k1": float(k1), "k2": float(k2), "k_source": source, "lambda": task.lam, "eta": task.eta,
                    **({"arch": arch} if arch else {}),
                    **({"eta_down": eta_down} if eta_down is not None else {}),
                    **({"mid_x": mid_x} if mid_x is not None else {}),
                    **({"k3": float(k3), "k4": float(k4), "mid": mid} if general else {})},
        peaks=peaks,  # type: ignore[arg-type]
        breakpoints=breaks,
        jumps=(),  # a quintic B-spline on simple knots is C⁴: nothing steps at its knots
    )


def _k_beyond_table(task: Task, table_source: str, why: str, two_d: bool) -> tuple[float, float, str]:
    """(k1, k2, k_source) for a (λ, η) the 1-D table does not cover: bilinear in the shipped 2-D (λ, η) table
    (``two_d``: only with the shipped 1-D table, whose settings it shares), else — outside its grid, in a cell
    across a basin jump, or without it — build-table's optimiser for this one move (cached)."""
    from ..lookup.bspline_optimum import solve_on_demand

    lam, eta = round(task.lam, 12), round(task.eta, 12)
    reason = f"{why} outside table {table_source}"
    if two_d:
        from ..lookup.table2d import TableJumpError, load_table_2d

        try:
            tab2 = load_table_2d()
        except TableError:  # not installed or unreadable: the on-demand solve still answers
            tab2 = None
        if tab2 is not None:
            try:
                k1, k2, polished = tab2.lookup_polished(lam, eta)
                how = "interpolated and polished (tall move: λ < 2)" if polished else "interpolated"
                return k1, k2, f"2-D table {tab2.source}, {how}"
            except TableJumpError:  # the on-demand solve, and a polish from every corner's basin: the best
                k1, k2, _ = solve_on_demand(lam, eta)
                k1, k2 = tab2.best_in_cell(lam, eta, others=[(k1, k2)])
                return k1, k2, (f"(λ, η) in a cell of 2-D table {tab2.source} across a basin jump: solved on demand "
                                "and from each corner's basin, the best; build-table's optimiser")
            except TableError:
                reason = f"{why} outside table {table_source} and outside 2-D table {tab2.source}"
    k1, k2, _ = solve_on_demand(lam, eta)
    return k1, k2, f"solved on demand: {reason}; build-table's optimiser, cached in this process"


def _falling(n: np.ndarray, k: int) -> np.ndarray:
    """n (n−1) … (n−k+1): the factor a power n picks up from k derivatives."""
    out = np.ones_like(n)
    for r in range(k):
        out = out * (n - r)
    return out


#: the factors of the k-th derivative's coefficients (powers 5 … k, highest first), k = 0 … 3
_FALLING = [_falling(np.arange(DEGREE, -1, -1.0)[: DEGREE + 1 - k], k) for k in range(4)]


#: k1 range of the closed-form symmetric path (:func:`_unit_paths`): it loses digits towards k1 → 0 or 1
#: (3e-10 relative at k1 = 0.05, tests/unit/test_table.py); every table optimum lies in [0.18, 0.6]
UNIT_K1 = (0.1, 0.9)


def batch_paths(k1: np.ndarray, k2: np.ndarray, via: np.ndarray, route: np.ndarray | None = None):
    """The B-spline paths of P moves: (breaks (P, 7), position coefficients (P, 6, 3, 6) [displacement from
    P1, highest power first], peaks (P, 3) of ‖p′‖, ‖p″‖, ‖p‴‖ at T = 1). ``via`` (P, 5, 3) are the via
    points minus P1.

    Closed forms of the table build instead of the ~300 numpy calls of the Cox–de Boor recursion: moves
    between end points at the same height (the path is then symmetric about τ = 1/2) from the unit path
    (:func:`pickplace_cli.lookup.bspline_optimum.unit_pieces`, :func:`_unit_paths`); moves between end points
    at two heights (their via points lie in one vertical plane) from four cardinal functions
    (:func:`~pickplace_cli.lookup.bspline_optimum.plane_pieces`, :func:`_plane_paths`). Any other via points,
    and k1 outside ``UNIT_K1``, take the batched de Boor path. Either way every row is computed by operations
    on that row alone, so one move planned alone and the same move in a batch of thousands get bitwise the
    same path (tested). ``route``: the rows' :func:`_route` when the caller knows it already."""
    k1 = np.asarray(k1, float)
    k2 = np.asarray(k2, float)
    via = np.asarray(via, float)
    route = _route(k1, k2, via) if route is None else route
    fns = (_unit_paths, _plane_paths, _deboor_paths)
    first = route[0] if len(route) else ROUTE_DEBOOR
    if (route == first).all():
        return fns[first](k1, k2, via)
    breaks = np.empty((len(k1), 7))
    coef = np.empty((len(k1), 6, 3, 6))
    peaks = np.empty((len(k1), 3))
    for r, fn in enumerate(fns):
        rows = route == r
        if rows.any():
            breaks[rows], coef[rows], peaks[rows] = fn(k1[rows], k2[rows], via[rows])
    return breaks, coef, peaks


#: :func:`batch_paths`' ways to a path: the symmetric closed form, the planar one, the de Boor recursion
ROUTE_UNIT, ROUTE_PLANE, ROUTE_DEBOOR = 0, 1, 2


#: shortest middle piece [τ7, τ8] = k1 (1 − k2)/2 of the closed forms: shorter (k2 → 1, given by the user; the
#: table's optima have k2 ≤ 0.4) they lose digits (2.5e-9 of a coefficient at k1 = 0.1, k2 = 0.99; 7e-7 at
#: k2 = 0.9999), so such paths take de Boor
UNIT_PIECE_MIN = 1e-3


def _route(k1: np.ndarray, k2: np.ndarray, via: np.ndarray) -> np.ndarray:
    """Each row's way to its path (ROUTE_*): symmetric (:func:`_symmetric`), else planar (:func:`_planar`), else
    de Boor; de Boor too when the middle piece is shorter than ``UNIT_PIECE_MIN``."""
    closed = k1 * (1.0 - k2) / 2 >= UNIT_PIECE_MIN
    return np.where(closed & _symmetric(k1, via), ROUTE_UNIT,
                    np.where(closed & _planar(k1, via), ROUTE_PLANE, ROUTE_DEBOOR))


def _route_one(k1: float, k2: float, via: np.ndarray) -> int:
    """:func:`_route` of one move in Python floats (the same decisions, bitwise)."""
    if not k1 * (1.0 - k2) / 2 >= UNIT_PIECE_MIN:
        return ROUTE_DEBOOR
    if _symmetric_one(k1, via):
        return ROUTE_UNIT
    return ROUTE_PLANE if _planar_one(k1, via) else ROUTE_DEBOOR


def _planar(k1: np.ndarray, via: np.ndarray) -> np.ndarray:
    """Rows whose via points are those of Task.via_points at any heights: P2 straight above P1, P3 above the
    midpoint, P4 above P5 (so the path is P1 + s_u(τ)·(P5 − P1) horizontally), with b > 0, P3 above P1
    and k1 in ``UNIT_K1``."""
    d = via[:, 4]
    expect = np.zeros(via.shape[:2] + (2,))
    expect[:, 2] = d[:, :2] / 2
    expect[:, 3:] = d[:, None, :2]
    scale = np.abs(via).reshape(len(via), -1).max(axis=1)
    off = np.abs(via[:, :, :2] - expect).reshape(len(via), -1).max(axis=1)
    return (
        (off <= 1e-13 * scale)
        & (np.abs(via[:, 0, 2]) <= 1e-13 * scale)
        & (via[:, 2, 2] > 0.0)
        & (np.hypot(d[:, 0], d[:, 1]) > 1e-9 * scale)
        & (k1 >= UNIT_K1[0])
        & (k1 <= UNIT_K1[1])
    )


def _planar_one(k1: float, via: np.ndarray) -> bool:
    """:func:`_planar` of one move (``via`` (5, 3)) in Python floats."""
    (x0, y0, z0), (x1, y1, z1), (x2, y2, z2), (x3, y3, z3), (x4, y4, z4) = via.tolist()
    scale = max(abs(x0), abs(y0), abs(z0), abs(x1), abs(y1), abs(z1), abs(x2), abs(y2), abs(z2), abs(x3), abs(y3),
                abs(z3), abs(x4), abs(y4), abs(z4))
    off = max(abs(x0), abs(y0), abs(x1), abs(y1), abs(x2 - x4 / 2), abs(y2 - y4 / 2), abs(x3 - x4), abs(y3 - y4))
    return bool(off <= 1e-13 * scale and abs(z0) <= 1e-13 * scale and z2 > 0.0
                and np.hypot(x4, y4) > 1e-9 * scale and UNIT_K1[0] <= k1 <= UNIT_K1[1])


def _symmetric(k1: np.ndarray, via: np.ndarray) -> np.ndarray:
    """Rows whose via points are those of Task.via_points for end points at the same height (P5 − P1
    horizontal, P2 and P4 straight above the ends at one height, P3 above the midpoint) with b > 0."""
    d = via[:, 4]
    expect = np.zeros(via.shape)  # the via points of a symmetric move with this P5 − P1, clearance and lift
    expect[:, 1:4, 2] = via[:, [1, 2, 1], 2]
    expect[:, 2, :2] = d[:, :2] / 2
    expect[:, 3:, :2] = d[:, None, :2]
    scale = np.abs(d).sum(axis=1) + np.abs(via[:, 2, 2])
    off = np.abs(via - expect).reshape(len(via), -1).max(axis=1)
    return (
        (off <= 1e-13 * scale)
        & (via[:, 2, 2] > 0.0)
        & (np.hypot(d[:, 0], d[:, 1]) > 1e-9 * scale)
        & (k1 >= UNIT_K1[0])
        & (k1 <= UNIT_K1[1])
    )


def _symmetric_one(k1: float, via: np.ndarray) -> bool:
    """:func:`_symmetric` of one move (``via`` (5, 3)) in Python floats: the same IEEE operations on the same
    numbers (the same decision, bitwise), without the ~20 numpy calls of a one-row array."""
    (x0, y0, z0), (x1, y1, z1), (x2, y2, z2), (x3, y3, z3), (x4, y4, z4) = via.tolist()
    scale = abs(x4) + abs(y4) + abs(z4) + abs(z2)
    off = max(abs(x0), abs(y0), abs(z0), abs(x1), abs(y1), abs(x2 - x4 / 2), abs(y2 - y4 / 2),
              abs(x3 - x4), abs(y3 - y4), abs(z3 - z1), abs(z4))
    return bool(off <= 1e-13 * scale and z2 > 0.0 and np.hypot(x4, y4) > 1e-9 * scale
                and UNIT_K1[0] <= k1 <= UNIT_K1[1])


def _unit_paths(k1: np.ndarray, k2: np.ndarray, via: np.ndarray):
    """:func:`batch_paths` of symmetric moves from the closed-form unit path (s_u, s_v) of [Li2018,
    Eq. (16)] on [0, 1/2] and its mirror image s_u(1 − τ) = 1 − s_u(τ), s_v(1 − τ) = s_v(τ):
    p − P1 = s_u(τ)·(P5 − P1) + s_v(τ)·h e_z with h the clearance, and ‖p⁽ʳ⁾‖ = b ‖(s_u⁽ʳ⁾, s_v⁽ʳ⁾/λ)‖."""
    from ..lookup.bspline_optimum import unit_peaks, unit_pieces

    d = via[:, 4]
    top = via[:, 2, 2]
    eta = via[:, 1, 2] / top
    h, half = unit_pieces(k1, k2, eta, rowwise=True)  # (P, 3), (P, 3, 2, 6) lowest power first
    b = np.hypot(d[:, 0], d[:, 1])
    # pruning pays on batches (8.3 vs 9.5 ms per 250 moves) but not on one move's 9 pieces (0.119 vs 0.108 ms);
    # the maxima are bitwise the same either way
    peaks = b[:, None] * unit_peaks(h, half, (b / top)[:, None, None], prune=len(k1) > 1)
    unit = _mirror(h, half, odd=((0, 1.0),))  # s_u: 1 − s_u(1 − τ); s_v symmetric
    return _li_breaks(k1, k2), _position_coefficients(d, top, unit), peaks


def _plane_paths(k1: np.ndarray, k2: np.ndarray, via: np.ndarray):
    """:func:`batch_paths` of moves whose via points lie in one vertical plane (:func:`_planar`: end points at
    two heights) from the cardinal functions A1 = s_u, A2, S1, S2 of
    :func:`~pickplace_cli.lookup.bspline_optimum.plane_pieces` and their mirror images on [1/2, 1]: p − P1 =
    s_u(τ)·(P5 − P1) horizontally and w(τ) = Σ c_i F_i(τ) vertically, c from the via heights; the peaks
    ‖p⁽ʳ⁾‖ = b ‖(s_u⁽ʳ⁾, (w/h)⁽ʳ⁾/λ)‖ (h = P3's height over P1, λ = b/h) on all six pieces (no symmetry)."""
    from ..lookup.bspline_optimum import plane_pieces, unit_peaks

    n = len(k1)
    d = via[:, 4]
    top = via[:, 2, 2]
    zt = via[:, :, 2] / top[:, None]  # the via heights over P3's
    h, half = plane_pieces(k1, k2)  # (P, 3), (P, 3, 4, 6) lowest power first
    full = _mirror(h, half, odd=((0, 1.0), (1, 0.0)))  # A1: 1 − A1(1 − τ), A2: −A2(1 − τ); S1, S2 symmetric
    c = np.empty((n, 4, 1, 1))  # the vertical path's via values (0, z1, z2, z3, z4)/h in the cardinal basis
    c[:, 0, 0, 0] = zt[:, 4]
    c[:, 1, 0, 0] = (zt[:, 3] - zt[:, 4] - zt[:, 1]) / 2
    c[:, 2, 0, 0] = (zt[:, 3] - zt[:, 4] + zt[:, 1]) / 2
    c[:, 3, 0, 0] = zt[:, 2] - zt[:, 4] / 2
    unit = np.empty((n, 6, 2, 6))
    unit[:, :, 0] = full[:, :, 0]
    unit[:, :, 1] = full[:, :, 0] * c[:, 0] + full[:, :, 1] * c[:, 1] + full[:, :, 2] * c[:, 2] + full[:, :, 3] * c[:, 3]
    b = np.hypot(d[:, 0], d[:, 1])
    peaks = b[:, None] * unit_peaks(np.concatenate([h, h[:, ::-1]], axis=1), unit, (b / top)[:, None, None],
                                    prune=True)
    return _li_breaks(k1, k2), _position_coefficients(d, top, unit), peaks


_SIGN = (-1.0) ** np.arange(6)  # x → −x on Taylor coefficients, lowest power first


def _mirror(h: np.ndarray, half: np.ndarray, odd: tuple[tuple[int, float], ...]) -> np.ndarray:
    """The six pieces (P, 6, F, 6), lowest power first, of F functions given on [0, 1/2] by ``half`` (P, 3, F, 6)
    with piece lengths ``h`` (P, 3): pieces 5, 4, 3 mirror pieces 0, 1, 2 (a Taylor shift to the piece's right end,
    then x → −x). A function listed in ``odd`` as (index, c) is antisymmetric about τ = 1/2, f(1 − τ) = c − f(τ);
    the others are symmetric, f(1 − τ) = f(τ)."""
    from ..lookup.bspline_optimum import _EXP, _SHIFT

    right = ((_SHIFT * h[:, :, None, None, None] ** _EXP) @ half[..., None])[..., 0] * _SIGN
    for i, c in odd:
        right[:, :, i] = -right[:, :, i]
        if c:
            right[:, :, i, 0] += c
    return np.concatenate([half, right[:, ::-1]], axis=1)


def _position_coefficients(d: np.ndarray, top: np.ndarray, unit: np.ndarray) -> np.ndarray:
    """(P, 6, 3, 6) position coefficients [m, highest power first] of p − P1 = u(τ)·(P5 − P1) horizontally and
    w(τ)·h vertically, from ``unit`` (P, 6, 2 (u, w), 6) lowest power first; ``d`` = P5 − P1, ``top`` = h."""
    unit = unit[..., ::-1]
    coef = np.empty((len(d), 6, 3, 6))
    coef[:, :, 0] = d[:, 0, None, None] * unit[:, :, 0]
    coef[:, :, 1] = d[:, 1, None, None] * unit[:, :, 0]
    coef[:, :, 2] = top[:, None, None] * unit[:, :, 1]
    return coef


def _li_breaks(k1: np.ndarray, k2: np.ndarray) -> np.ndarray:
    """(P, 7) piece breaks 0, τ7, τ8, 1/2, τ10, τ11, 1 by the arithmetic of batch_li_knots (bitwise its interior
    knots)."""
    breaks = np.empty((len(k1), 7))
    breaks[:, 0], breaks[:, 3], breaks[:, 6] = 0.0, 0.5, 1.0
    breaks[:, 1], breaks[:, 2] = k1 * k2 / 2, k1 / 2
    breaks[:, 4], breaks[:, 5] = 1 - k1 / 2, 1 - k1 * k2 / 2
    return breaks


def _deboor_paths(k1: np.ndarray, k2: np.ndarray, via: np.ndarray):
    """:func:`batch_paths` by the batched Cox–de Boor recursion (any via points)."""
    return _deboor_knots(batch_li_knots(k1, k2), via)


def _deboor_knots(knots: np.ndarray, via: np.ndarray, want_peaks: bool = True):
    """:func:`batch_paths` on any knot vectors (P, 17) by the batched Cox–de Boor recursion (peaks NaN unless
    ``want_peaks``)."""
    q = batch_control_points(knots, via)
    breaks, derivs = batch_pieces(knots, q)
    if not want_peaks:
        return breaks, batch_piece_coefficients(derivs, 0), np.full((len(knots), 3), np.nan)
    peaks = batch_norm_peaks(breaks, [batch_piece_coefficients(derivs, r) for r in (1, 2, 3)])
    return breaks, batch_piece_coefficients(derivs, 0), peaks
