"""Quintic B-spline machinery shared by the B-spline methods [Li2018, Sec. 2.2–2.3].

A motion profile is ``s(τ) = Σ Q_i N_{i,5}(τ)`` on τ ∈ [0, 1] (Eq. 3) with clamped knots (Eq. 7).
scipy's :class:`scipy.interpolate.BSpline` does the basis and evaluation; this module builds the knots
and solves for the control points.

Departure from the paper, on purpose: Eq. (10) solves the full 11×11 system ``A q = b``. That matrix is
badly conditioned for small k2 (cond ≈ 1e8 at k2 = 0.12, worse as k2 → 0). With clamped knots the
derivatives of order r at τ = 0 involve only Q_1 … Q_{r+1} (Eq. 9), so the boundary rows form a small
triangular system that fixes Q_1..Q_4 (and Q_8..Q_11 at τ = 1) directly; only the interior control points
are left for the interpolation rows (Eq. 8). Same solution, well conditioned.
"""

from __future__ import annotations

import numpy as np

from .peaks import ppoly_norm_peak

DEGREE = 5


def li_knots(k1: float, k2: float) -> np.ndarray:
    """The 17 knots of [Li2018, Eq. (14)] from the time-ratio factors k1 = τ8/τ9, k2 = τ7/τ8 (Eq. 13)."""
    if not (0.0 < k1 < 1.0 and 0.0 < k2 < 1.0):
        raise ValueError(f"k1 and k2 must lie in (0, 1), got k1={k1!r}, k2={k2!r}")
    return np.array(
        [0.0] * 6 + [k1 * k2 / 2, k1 / 2, 0.5, 1 - k1 / 2, 1 - k1 * k2 / 2] + [1.0] * 6
    )


def basis_matrix(knots: np.ndarray, x: np.ndarray, order: int = 0) -> np.ndarray:
    """(len(x), n) matrix of the ``order``-th derivative of every basis function N_{i,5} at x."""
    return _basis_spline(knots)(np.asarray(x, float), nu=order)


def solve_control_points(
    knots: np.ndarray,
    via_tau: np.ndarray,
    via: np.ndarray,
    start: np.ndarray | None = None,
    end: np.ndarray | None = None,
) -> np.ndarray:
    """Control points (n, d) of the quintic spline with the given knots that

    * passes through ``via`` (f, d) at ``via_tau`` (f,), first = τ 0 and last = τ 1 [Li2018, Eq. (8)];
    * has derivatives ``start`` = (s′, s″, s‴)(0) and ``end`` = (s′, s″, s‴)(1), each (3, d), zero when
      None [Li2018, Eq. (9)] (Yang 2022 sets s′ to the conveyor velocity).

    Uses the reduced system described in the module docstring: Q_1..Q_4 and Q_{n−3}..Q_n come from the
    end conditions, the remaining interior control points from the interior via points. The number of
    interior via points must equal the number of interior control points (n − 8).
    """
    via = np.asarray(via, dtype=float)
    if via.ndim == 1:
        via = via[:, None]
    d = via.shape[1]
    n = len(knots) - DEGREE - 1
    start = np.zeros((3, d)) if start is None else np.asarray(start, float).reshape(3, d)
    end = np.zeros((3, d)) if end is None else np.asarray(end, float).reshape(3, d)
    interior = np.asarray(via_tau, float)[1:-1]
    if interior.size != n - 8:
        raise ValueError(f"{n} control points need {n - 8} interior via points, got {interior.size}")
    q = np.empty((n, d))
    basis = _basis_spline(knots)
    if not np.any(start) and not np.any(end):
        # rest to rest: the r-th derivative at a clamped end is a combination of differences of
        # Q_1..Q_{r+1}, so zero velocity, acceleration and jerk there means Q_1 = Q_2 = Q_3 = Q_4 (and the
        # same at tau = 1): exact, no solve needed
        q[:4] = via[0]
        q[-4:] = via[-1]
        a = basis(interior)
        q[4:-4] = np.linalg.solve(a[:, 4:-4], via[1:-1] - a[:, :4] @ q[:4] - a[:, -4:] @ q[-4:])
        return q

    ends = np.array([knots[0], knots[-1]])
    rows = np.stack([basis(ends, nu=r) for r in range(4)])  # (4 orders, 2 ends, n)
    # end conditions: the derivative rows at τ=0 are lower-triangular in Q_1..Q_4 (Eq. 9)
    q[:4] = np.linalg.solve(rows[:, 0, :4], np.vstack([via[:1], start]))
    q[-4:] = np.linalg.solve(rows[:, 1, -4:], np.vstack([via[-1:], end]))
    if n > 8:
        a = basis(interior)
        rhs = via[1:-1] - a[:, :4] @ q[:4] - a[:, -4:] @ q[-4:]
        q[4:-4] = np.linalg.solve(a[:, 4:-4], rhs)
    return q


def _basis_spline(knots: np.ndarray):
    """A BSpline whose coefficient matrix is the identity: evaluating it gives every basis function."""
    from scipy.interpolate import BSpline

    n = len(knots) - DEGREE - 1
    return BSpline(knots, np.eye(n), DEGREE, extrapolate=True)


def make_spline(knots: np.ndarray, control_points: np.ndarray):
    """scipy BSpline of degree 5 (vector-valued when control_points is (n, d))."""
    from scipy.interpolate import BSpline

    return BSpline(knots, control_points, DEGREE, extrapolate=True)


def piece_coefficients(spline, order: int, _derivs: list | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Breakpoints (m+1,) and Taylor coefficients (m, d, 6−order) of the ``order``-th derivative.

    Piece i is Σ_p coef[i, :, p] (τ − breaks[i])^(deg−p), highest power first, deg = 5 − order. The
    coefficients are the derivatives of orders ``order``..5 at the left end of each piece divided by the
    factorials, i.e. the exact polynomial of that piece.
    """
    breaks = np.unique(spline.t)
    if _derivs is None:
        _derivs = _left_derivatives(spline, breaks)
    deg = DEGREE - order
    coef = np.stack([_derivs[order + p] / _FACT[p] for p in range(deg, -1, -1)], axis=-1)
    return breaks, coef


_FACT = (1.0, 1.0, 2.0, 6.0, 24.0, 120.0)


def _left_derivatives(spline, breaks: np.ndarray) -> list:
    left = breaks[:-1]
    return [np.asarray(spline(left, nu=r)).reshape(len(left), -1) for r in range(DEGREE + 1)]


def norm_peaks(spline, orders: tuple[int, ...] = (1, 2, 3)) -> tuple[float, ...]:
    """Exact max over τ ∈ [0, 1] of ‖d^r s/dτ^r‖ for each r in ``orders`` (piecewise-polynomial roots)."""
    breaks = np.unique(spline.t)
    derivs = _left_derivatives(spline, breaks)
    return tuple(ppoly_norm_peak(*piece_coefficients(spline, r, derivs))[0] for r in orders)
