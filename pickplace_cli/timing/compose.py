"""A path composed with a time law: dτ/dt = √b(τ) (b > 0 a cubic B-spline in τ, the law of ``--time optimal``,
:mod:`~pickplace_cli.timing.optimal`) gives a :class:`~pickplace_cli.model.trajectory.CartesianPath` in u = t/T, on
which every writer and the continuous limit check run unchanged (:func:`compose`).

With t(τ) = ∫₀^τ dσ/√b(σ), T = t(1) and u = t/T, the reparametrisation τ(u) has the derivatives

    τ′ = T·√b(τ),   τ″ = T²·b′(τ)/2,   τ‴ = T³·√b(τ)·b″(τ)/2

so the composed motion's derivatives follow from the path's by the chain rule, exactly at any τ. Only τ(u) itself
needs a table, built with error control:

* t(τ) by Gauss–Legendre (8 nodes) on pieces between the law's knots and the path's breakpoints (1/√b is smooth
  there), each piece bisected until it agrees with its two halves to ``TABLE_RTOL`` of T;
* τ(u) by quintic Hermite interpolation on the pieces' ends (value, τ′ and τ″ are exact there), each piece
  bisected until the interpolant at its midpoint is within ``INVERSE_TOL`` in τ of the exact inverse (checked by
  integrating t from the piece's start to the interpolated τ).

The composed path's normalised Cartesian peaks (v̂, â, ĵ) are found on the continuous motion: sampled on its
knots and a uniform grid, every local maximum of the samples near the top refined
(:func:`~pickplace_cli.curves.peaks.refine_max` with ``within`` and ``rtol``).
"""

from __future__ import annotations

import numpy as np

#: t(τ) agrees with its two halves on every piece to this fraction of T (8-point Gauss–Legendre)
TABLE_RTOL = 1e-14
#: the inverse τ(u) is within this of the exact one at every piece's midpoint (quintic Hermite)
INVERSE_TOL = 1e-11
#: pieces per interval between the law's knots (and the path's breakpoints) that the table starts from
TABLE_START = 2
#: rounds of bisection at most (each halves the pieces that fail; 2⁻²⁰ of a knot interval: never reached)
TABLE_ROUNDS = 20
#: uniform points of u ∈ [0, 1] on which the composed path's Cartesian peaks are sampled (plus its knots and both
#: sides of every jump); each local maximum within ``PEAK_WITHIN`` of the top is then refined
PEAK_GRID = 257
PEAK_WITHIN = 0.05
#: … until each is known to this fraction of its value (:func:`~pickplace_cli.curves.peaks.refine_max`'s ``rtol``)
PEAK_RTOL = 1e-10

_XG, _WG = np.polynomial.legendre.leggauss(8)


class _Cubic:
    """A spline b(τ) (cubic, or of any degree) as pieces: breaks (m + 1,), coefficients (m, k + 1) in powers of
    (τ − break), highest first; ``at(τ)`` → (b, b′, b″)."""

    def __init__(self, spline) -> None:
        from scipy.interpolate import PPoly

        pp = PPoly.from_spline(spline)
        x, c = pp.x, pp.c
        keep = np.flatnonzero(np.diff(x) > 0)  # the repeated end knots give empty pieces
        self.breaks = np.concatenate([x[keep], [x[keep[-1] + 1]]])
        self.coef = c[:, keep].T

    def at(self, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        i = np.clip(np.searchsorted(self.breaks, tau, side="right") - 1, 0, len(self.coef) - 1)
        s = tau - self.breaks[i]
        c = self.coef[i]
        k = c.shape[1] - 1
        if k == 3:
            c3, c2, c1, c0 = c.T
            return ((c3 * s + c2) * s + c1) * s + c0, (3.0 * c3 * s + 2.0 * c2) * s + c1, 6.0 * c3 * s + 2.0 * c2
        b, b1, b2 = c[:, 0], k * c[:, 0], k * (k - 1) * c[:, 0]
        for j in range(1, k + 1):  # Horner on b and its first two derivatives (power k − j)
            b = b * s + c[:, j]
            if j < k:
                b1 = b1 * s + (k - j) * c[:, j]
            if j < k - 1:
                b2 = b2 * s + (k - j) * (k - j - 1) * c[:, j]
        return b, b1, b2


def _gauss(b: _Cubic, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """∫ dτ/√b over each [lo, hi] (8-point Gauss–Legendre)."""
    h = 0.5 * (hi - lo)
    nodes = (0.5 * (hi + lo))[:, None] + h[:, None] * _XG
    return (b.at(nodes.ravel())[0].reshape(nodes.shape) ** -0.5 @ _WG) * h


def _time_table(b: _Cubic, knots: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(τ nodes, t at the nodes): the pieces between ``knots`` split ``TABLE_START`` times, each bisected until its
    8-point Gauss integral agrees with the sum over its halves to ``TABLE_RTOL`` of the running total."""
    s = np.linspace(0.0, 1.0, TABLE_START + 1)[:-1]
    lo = (knots[:-1, None] + np.diff(knots)[:, None] * s).ravel()
    hi = np.concatenate([lo[1:], knots[-1:]])
    whole = _gauss(b, lo, hi)
    scale = float(whole.sum())
    done_lo, done_val = [], []
    for _ in range(TABLE_ROUNDS):
        mid = 0.5 * (lo + hi)
        left, right = _gauss(b, lo, mid), _gauss(b, mid, hi)
        ok = np.abs(left + right - whole) <= TABLE_RTOL * scale
        done_lo += [lo[ok], mid[ok]]
        done_val += [left[ok], right[ok]]
        if ok.all():
            break
        lo, hi = np.concatenate([lo[~ok], mid[~ok]]), np.concatenate([mid[~ok], hi[~ok]])
        whole = np.concatenate([left[~ok], right[~ok]])
    else:  # (an integrand that never settles: its last halves are kept)
        done_lo.append(lo)
        done_val.append(whole)
    lo, val = np.concatenate(done_lo), np.concatenate(done_val)
    o = np.argsort(lo)
    return np.concatenate([lo[o], knots[-1:]]), np.concatenate([[0.0], np.cumsum(val[o])])


class _Inverse:
    """τ(u) by quintic Hermite pieces on nodes (u_k, τ_k) with τ′ and τ″ exact at every node (module docstring)."""

    def __init__(self, b: _Cubic, tau: np.ndarray, t: np.ndarray) -> None:
        self.b, self.T = b, float(t[-1])
        for _ in range(TABLE_ROUNDS):
            self._fit(tau, t / self.T)
            um = 0.5 * (self.u[:-1] + self.u[1:])
            guess = self(um)
            # the exact u at the interpolated τ: t from the piece's start node
            k = np.arange(len(um))
            exact = self.u[k] + _gauss(b, tau[k], guess) / self.T
            bad = np.abs(exact - um) * self.T * np.sqrt(b.at(guess)[0]) > INVERSE_TOL
            if not bad.any():
                return
            mids = 0.5 * (tau[k[bad]] + tau[k[bad] + 1])
            tm = t[k[bad]] + _gauss(b, tau[k[bad]], mids)
            order = np.argsort(np.concatenate([tau, mids]), kind="stable")
            tau, t = np.concatenate([tau, mids])[order], np.concatenate([t, tm])[order]
        self._fit(tau, t / self.T)  # (not settled in TABLE_ROUNDS: the last table)

    def _fit(self, tau: np.ndarray, u: np.ndarray) -> None:
        bb, b1, _ = self.b.at(tau)
        d1, d2 = self.T * np.sqrt(bb), 0.5 * self.T**2 * b1
        h = np.diff(u)
        y0, y1 = tau[:-1], tau[1:]
        p0, p1 = h * d1[:-1], h * d1[1:]
        q0, q1 = h * h * d2[:-1], h * h * d2[1:]
        r0 = y1 - (y0 + p0 + 0.5 * q0)
        r1 = p1 - (p0 + q0)
        r2 = q1 - q0
        self.u, self.h = u, h
        # p(s) = Σ c_k s^k, s = (u − u_k)/h: c0..c2 from the left node, c3..c5 match value, τ′ and τ″ at the right
        self.c = np.stack([10.0 * r0 - 4.0 * r1 + 0.5 * r2, -15.0 * r0 + 7.0 * r1 - r2, 6.0 * r0 - 3.0 * r1 + 0.5 * r2])
        self.c = np.vstack([self.c[::-1], 0.5 * q0, p0, y0])  # highest power first: c5 … c0

    def __call__(self, u: np.ndarray) -> np.ndarray:
        i = np.clip(np.searchsorted(self.u, u, side="right") - 1, 0, len(self.h) - 1)
        s = (u - self.u[i]) / self.h[i]
        c = self.c[:, i]
        out = c[0]
        for k in range(1, 6):
            out = out * s + c[k]
        return out


def compose(path, b) -> object:
    """The path traversed with dτ/dt = √b(τ) (``b``: a scipy BSpline in τ), as a CartesianPath in u = t/T
    (its derivatives are those at T = 1 s; ``T`` of the law itself is ∫dτ/√b)."""
    from ..model.trajectory import CartesianPath

    law = _Cubic(b)
    knots = np.unique(np.clip(np.concatenate([[0.0, 1.0], np.asarray(path.breakpoints, float), law.breaks]), 0.0, 1.0))
    knots = knots[np.concatenate([[True], np.diff(knots) > 1e-12])]
    tau_tab, t_tab = _time_table(law, knots)
    inv = _Inverse(law, tau_tab, t_tab)
    T = inv.T

    def fwd(tau: np.ndarray) -> np.ndarray:
        """u(τ): t from the table node at or below τ."""
        tau = np.asarray(tau, float)
        k = np.clip(np.searchsorted(tau_tab, tau, side="right") - 1, 0, len(tau_tab) - 2)
        return (t_tab[k] + _gauss(law, tau_tab[k], tau)) / T

    def chain(u: np.ndarray):
        u = np.clip(np.asarray(u, float), 0.0, 1.0)
        tau = np.clip(inv(u), 0.0, 1.0)
        bb, b1, b2 = law.at(tau)
        sb = np.sqrt(bb)
        return tau, T * sb, T**2 * b1 / 2, T**3 * sb * b2 / 2

    def orders(u: np.ndarray):
        tau, s1, s2, s3 = chain(u)
        p, d1, d2, d3 = path.all_orders(tau)
        return [p, d1 * s1[:, None], d2 * (s1**2)[:, None] + d1 * s2[:, None],
                d3 * (s1**3)[:, None] + 3 * d2 * (s1 * s2)[:, None] + d1 * s3[:, None]]

    def evaluate(u: np.ndarray, order: int) -> np.ndarray:
        return orders(u)[order]

    # the path's knots and the law's (where b‴ steps, so the torque rate has a kink: the check's grid and its
    # Gauss-Kronrod spans then see it)
    bp = np.unique(np.clip(fwd(np.concatenate([np.asarray(path.breakpoints, float), law.breaks])), 0.0, 1.0))
    bp = np.unique(np.concatenate([[0.0, 1.0], bp]))
    jumps = fwd(path.jump_points) if len(path.jump_points) else np.zeros(0)
    shell = CartesianPath(evaluate, path.method, {}, (0.0, 0.0, 0.0), bp, jumps=tuple(jumps.tolist()),
                          evaluate_all=orders)
    peaks = composed_peaks(shell)
    params = dict(path.parameters)
    params.update(time_law="optimal", law_coefficients=len(b.c))
    angle = None
    if path.angle is not None:  # the tool's turn runs on the same time law
        from ..curves.rotation import ComposedRotation

        angle = ComposedRotation(path.angle, chain)
    return CartesianPath(evaluate, path.method, params, peaks, shell.breakpoints,
                         max_order=path.max_order, jumps=shell.jumps, evaluate_all=orders, angle=angle)


def composed_peaks(path) -> tuple[float, float, float]:
    """max ‖d^k p/du^k‖, k = 1, 2, 3, of a composed path (m/1^k, T = 1): sampled on ``PEAK_GRID`` uniform points,
    its breakpoints (the law's and the path's knots: where the jerk has a kink) and both sides of every jump; every
    local maximum of the samples within ``PEAK_WITHIN`` of its column's top refined on the path (never across a
    jump) to ``PEAK_RTOL``."""
    from ..curves.peaks import refine_max
    from ..limits.grid import interior_jumps, jump_sides, segment_ids

    grid = np.unique(np.concatenate([np.linspace(0.0, 1.0, PEAK_GRID), np.asarray(path.breakpoints, float),
                                     jump_sides(path.breakpoints, path.jumps)]))
    grid = grid[np.concatenate([[True], np.diff(grid) > 1e-12])]
    seg = segment_ids(grid, interior_jumps(path.breakpoints, path.jumps))

    def norms(t: np.ndarray) -> np.ndarray:
        o = path.all_orders(np.clip(t, 0.0, 1.0))
        return np.column_stack([np.sqrt(np.einsum("ij,ij->i", o[k], o[k])) for k in (1, 2, 3)])

    y = norms(grid)
    peak, _ = refine_max(norms, grid, y, segments=seg, within=PEAK_WITHIN * y.max(axis=0), rtol=PEAK_RTOL)
    return float(peak[0]), float(peak[1]), float(peak[2])
