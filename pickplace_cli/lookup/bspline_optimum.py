"""The optimum (k1*, k2*) of the B-spline method for one λ [Li2018, Sec. 3.2, Eq. (20)–(23)]: the table's optimiser.

Build (offline): for every λ on a grid, maximise F = w_a F_a + w_j F_j (Eq. 22) over (k1, k2) ∈ (0, 1)²,
F_a = min a_max / a_max (Eq. 20), F_j = min j_max / j_max (Eq. 21), peaks on the normalised path (b = 1,
T = 1). Use (online): ``Table.lookup(λ)`` interpolates linearly between rows.

The optimisation is global, not a single gradient run (F has a kink where two jerk peaks are equal,
two local maxima at small λ, and min a_max is only approached as k2 → 0):

1. Coarse stage, shared by every λ: s_u and s_v do not depend on λ — only the scale 1/λ of the v axis
   does — so the squared acceleration and jerk components of both axes are sampled once per (k1, k2) on
   a grid (step ``grid_step``, plus the row k2 = ``k2_floor``), and each λ's a_max, j_max, F on the
   whole grid are array reductions.
2. Refinement: from the best grid points (distinct local optima of the sampled objective) a bounded
   Nelder–Mead on the exact objective (peaks from the piecewise-polynomial roots, not samples) polishes
   each; the best refined value wins. A start from which the exact objective falls monotonically to an
   optimum already found is in that optimum's basin and is not refined again. min a_max is taken as the
   infimum over k2 ≥ ``k2_floor`` (it is reached only in the limit k2 → 0 [Li2018, Sec. 3.1]; at 1e-4 it
   is within ~1e-5 relative of the limit).

Speed: the optimiser evaluates the exact peaks of the unit path a few hundred times per λ, so the build
uses a batched closed form of that path (:func:`unit_pieces`) instead of scipy's ``BSpline``: the path is
symmetric about τ = 1/2 (s_u antisymmetric, s_v symmetric: the knots of Eq. (14) and the via points of
Eq. (11) are), so its three pieces on [0, 1/2] are solved from four conditions per axis. A test checks it
against the scipy path of :func:`normalised_peaks`.
A λ the table does not cover is solved on demand by the same optimiser (:func:`solve_on_demand`).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

from ..model.errors import TableError


#: bump when a change of the optimiser can change rows: a checkpoint of another version is not resumed
ALGORITHM_VERSION = 3


@dataclass(frozen=True)
class TableSettings:
    """Optimiser settings of ``build_table`` (recorded in the table's provenance header)."""

    eta: float = 0.5
    weights: tuple[float, float] = (0.5, 0.5)
    grid_step: float = 0.01
    k2_floor: float = 1e-4
    samples_per_piece: int = 16
    refine_xatol: float = 1e-5
    refine_candidates: int = 4
    basin_margin: float = 0.03

    def __post_init__(self) -> None:
        if not (0 < self.eta < 1):
            raise TableError(f"eta = {self.eta!r}: the lift-off/set-down ratio must lie strictly between 0 and 1")
        wa, wj = self.weights
        if not (wa > 0 and wj > 0 and math.isclose(wa + wj, 1.0, abs_tol=1e-9)):
            raise TableError(f"weights = {wa!r},{wj!r}: need w_a > 0, w_j > 0 and w_a + w_j = 1 (Li 2018 Eq. 22)")
        if not (0 < self.grid_step <= 0.1):
            raise TableError(f"grid_step = {self.grid_step!r}: must lie in (0, 0.1]")


# ------------------------------------------------------------------------------------- normalised peaks


def _unit_spline(k1: float, k2: float, eta: float):
    """2-D spline (s_u, s_v) of [Li2018, Eq. (16)] (v not yet scaled by 1/λ)."""
    from ..curves.bspline import li_knots, make_spline, solve_control_points

    knots = li_knots(k1, k2)
    via = np.array([[0.0, 0.0], [0.0, eta], [0.5, 1.0], [1.0, eta], [1.0, 0.0]])
    return make_spline(knots, solve_control_points(knots, knots[[0, 7, 8, 9, 16]], via))


def normalised_peaks(
    k1: float, k2: float, lam: float, eta: float = 0.5, orders: tuple[int, ...] = (1, 2, 3)
) -> tuple[float, ...]:
    """Exact peaks of the normalised path (b = 1, T = 1) [Li2018, Eq. (17)–(19)]: (v_max, a_max, j_max)
    for the default ``orders``; λ scales the v column of the piece polynomials (Eq. 17)."""
    from ..curves.bspline import _left_derivatives, piece_coefficients
    from ..curves.peaks import ppoly_norm_peak

    s = _unit_spline(k1, k2, eta)
    breaks = np.unique(s.t)
    derivs = [d * np.array([1.0, 1.0 / lam]) for d in _left_derivatives(s, breaks)]
    return tuple(ppoly_norm_peak(*piece_coefficients(s, r, derivs))[0] for r in orders)


# ---------------------------------------------------------------------- unit path, batched closed form

_NC = 6  # Taylor coefficients of a quintic piece (lowest power first)


#: Taylor shift by h: new coefficient i = Σ_k C(k, i) h^(k−i) c_k
_SHIFT = np.array([[math.comb(k, i) for k in range(_NC)] for i in range(_NC)], float)


_EXP = np.array([[max(k - i, 0) for k in range(_NC)] for i in range(_NC)], float)


#: r-th derivative at x: Σ_k k!/(k−r)! x^(k−r) c_k; row r also gives coefficient k−r of the derivative
_DROW = np.array([[math.perm(k, r) for k in range(_NC)] for r in range(_NC)], float)


#: condition rows (0 = value at τ = k1/2, 1 + r = r-th derivative at τ = 1/2) per axis: s_u antisymmetric
#: about the midpoint (s_u'' = s_u'''' = 0 there), s_v symmetric (s_v' = s_v''' = 0)
_CONDITIONS = np.array([[0, 1, 3, 5], [0, 1, 2, 4]])


def _piece_system(k1, k2, rowwise: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The pieces' lengths ``h`` (N, 3), the maps ``m`` (N, 3 pieces, 6 coefficients, 4 unknowns) from the
    unknowns z = (d3, d4, d5, g2) of one axis to its Taylor coefficients on each piece of [0, 1/2], and the
    condition ``rows`` (N, 6, 4): the value at τ8, then derivatives 0 … 4 at τ = 1/2 (:func:`unit_pieces`)."""
    k1 = np.atleast_1d(np.asarray(k1, dtype=float))
    k2 = np.atleast_1d(np.asarray(k2, dtype=float))
    n = k1.size
    a = 0.5 * k1 * k2
    c = 0.5 * k1
    h = np.empty((n, 3))
    h[:, 0], h[:, 1], h[:, 2] = a, c - a, 0.5 - c
    # pieces 0 and 1 as M @ z, z = (d3, d4, d5, g2), entries powers of a (start value s(0) = 0)
    m = np.empty((n, 3, _NC, 4))
    if rowwise:
        m[:, :2] = ((a[:, None, None] ** _A_POWERS) @ _A_TERMS).reshape(n, 2, _NC, 4)
    else:
        m[:, :2] = ((a[:, None] ** _A_POWERS) @ _A_TERMS).reshape(n, 2, _NC, 4)
    m[:, 2] = (_SHIFT * h[:, 1, None, None] ** _EXP) @ m[:, 1]  # piece 2 continues piece 1 (C⁴) …
    m[:, 2, 5, 3] += 1.0  # … plus its own fifth coefficient g2
    rows = np.empty((n, 6, 4))
    rows[:, 0] = m[:, 2, 0]  # value at τ8
    rows[:, 1:] = (_DROW[:5] * h[:, 2, None, None] ** _EXP[:5]) @ m[:, 2]  # derivatives 0..4 at τ = 1/2
    return h, m, rows


def unit_pieces(
    k1: np.ndarray | float, k2: np.ndarray | float, eta: float | np.ndarray, rowwise: bool = False
) -> tuple[np.ndarray, np.ndarray]:
    """The unit path (s_u, s_v) of [Li2018, Eq. (16)] on τ ∈ [0, 1/2], for a batch of (k1, k2).

    Returns ``h`` (N, 3), the lengths of the pieces [0, τ7], [τ7, τ8], [τ8, 1/2] (τ7 = k1 k2/2, τ8 = k1/2,
    Eq. 14), and ``coef`` (N, 3, 2, 6), the Taylor coefficients (lowest power first, in x = τ − piece
    start) of s_u and s_v on each. The second half mirrors the first: s_u(1 − τ) = 1 − s_u(τ),
    s_v(1 − τ) = s_v(τ) (the knots and via points are symmetric, and the spline is unique).

    The same spline as :func:`pickplace_cli.curves.bspline.solve_control_points` builds, in another basis.
    Piece 0 starts at rest (value 0; first three derivatives 0: Eq. 9), so it is c4 x⁴ + c5 x⁵, written in
    terms of the third and fourth derivatives d3, d4 at τ7 (bounded as k2 → 0, where c4, c5 are not);
    piece 1 continues it C⁴ with a free fifth coefficient d5, piece 2 likewise with g2. The four unknowns
    (d3, d4, d5, g2) of each axis come from the via point at τ8 and the value plus two symmetry
    conditions at τ = 1/2 (Eq. 8, 11): one batched 4×4 solve. Agrees with the scipy path to ~1e-13
    relative for k1 ∈ [0.05, 0.95]; near the corners k1 → 0 or 1 of the box (never near an optimum) the
    solve loses digits (1e-7 at k1 = 0.001).

    ``rowwise``: every row by operations on that row alone (a stacked product instead of one matrix
    product over all rows, whose BLAS kernel may depend on the number of rows), so a row's result does not
    depend on the batch it is in: the planner (one move) and the batch verdict engine (thousands) agree
    bitwise. ``eta`` may then be an array (one η per row).
    """
    h, m, rows = _piece_system(k1, k2, rowwise)
    n = h.shape[0]
    if rowwise:
        rhs = np.zeros((n, 2, 4, 1))
        rhs[:, 0, 1, 0] = 0.5
        rhs[:, 1, 0, 0] = eta
        rhs[:, 1, 1, 0] = 1.0
    else:
        rhs = _rhs(eta)  # broadcasts over the rows
    z = np.linalg.solve(rows[:, _CONDITIONS], rhs)  # (N, 2 axes, 4, 1)
    return h, (m[:, :, None] @ z[:, None])[..., 0]


@functools.lru_cache(maxsize=8)
def _rhs(eta: float) -> np.ndarray:
    """Right-hand sides of the conditions: s_u(τ8) = 0, s_u(1/2) = 1/2; s_v(τ8) = η, s_v(1/2) = 1."""
    return np.array([[0.0, 0.5, 0.0, 0.0], [eta, 1.0, 0.0, 0.0]])[:, :, None]


#: right-hand sides of :func:`plane_pieces`' four cardinal combinations (value at τ8, value at 1/2, then zero
#: derivatives): antisymmetric about τ = 1/2 (conditions 0), A1 = s_u (0 at τ8, 1/2 at 1/2) and A2 (−1 at τ8, 0
#: at 1/2); symmetric (conditions 1), S1 (1 at τ8, 0 at 1/2) and S2 (0 at τ8, 1 at 1/2)
_PLANE_RHS = np.array([[[0.0, -1.0], [0.5, 0.0], [0.0, 0.0], [0.0, 0.0]],
                       [[1.0, 0.0], [0.0, 1.0], [0.0, 0.0], [0.0, 0.0]]])


def plane_pieces(k1: np.ndarray, k2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Four cardinal functions of the B-spline of [Li2018, Eq. (11)–(16)] on τ ∈ [0, 1/2], for a batch of
    (k1, k2): with them the path through any via values (0, V1, V2, V3, V4) at (0, τ8, 1/2, τ10, 1) is
    V4·A1 + (V3 − V4 − V1)/2·A2 + (V3 − V4 + V1)/2·S1 + (V2 − V4/2)·S2 (the spline is linear in its via points,
    and on Li's knots, symmetric about 1/2, every via vector splits into these symmetric and antisymmetric
    parts). A1 = s_u and A2 are antisymmetric about τ = 1/2 (A(1 − τ) = 2A(1/2) − A(τ); A1(1/2) = 1/2,
    A2(1/2) = 0), S1 and S2 symmetric (S(1 − τ) = S(τ)); s_v = η S1 + S2. What moves between end points at
    two heights need (their via points are in one vertical plane, see
    :func:`pickplace_cli.paths.bspline._plane_paths`).

    Returns ``h`` (N, 3) as :func:`unit_pieces` and ``coef`` (N, 3 pieces, 4 functions A1, A2, S1, S2, 6
    Taylor coefficients, lowest power first); every row by operations on that row alone."""
    h, m, rows = _piece_system(k1, k2, True)
    n = h.shape[0]
    rhs = np.empty((n, 2, 4, 2))
    rhs[:] = _PLANE_RHS
    z = np.linalg.solve(rows[:, _CONDITIONS], rhs)  # (N, 2 symmetries, 4 unknowns, 2 functions)
    coef = m[:, :, None] @ z[:, None]  # (N, 3 pieces, 2 symmetries, 6, 2 functions)
    return h, coef.transpose(0, 1, 2, 4, 3).reshape(n, 3, 4, _NC)


def _piece_terms() -> tuple[np.ndarray, np.ndarray]:
    """Pieces 0 and 1 of the unit path as Σ_p a^p C_p (a = τ7): piece 0 = c4 x⁴ + c5 x⁵ with
    c4 = d3/(2a) − d4 and c5 = (4a d4 − d3)/(10a²) (so that its third and fourth derivatives at a are
    6 d3 and 24 d4); piece 1 holds its Taylor coefficients at a (0.4a³d3 − 0.6a⁴d4, 1.5a²d3 − 2a³d4,
    2a d3 − 2a² d4) and d3, d4, d5."""
    powers = np.arange(-2, 5)
    terms = np.zeros((len(powers), 2, _NC, 4))

    def put(piece: int, coef: int, unknown: int, power: int, value: float) -> None:
        terms[power + 2, piece, coef, unknown] = value

    put(0, 4, 0, -1, 0.5), put(0, 4, 1, 0, -1.0), put(0, 5, 0, -2, -0.1), put(0, 5, 1, -1, 0.4)
    put(1, 0, 0, 3, 0.4), put(1, 0, 1, 4, -0.6), put(1, 1, 0, 2, 1.5), put(1, 1, 1, 3, -2.0)
    put(1, 2, 0, 1, 2.0), put(1, 2, 1, 2, -2.0)
    put(1, 3, 0, 0, 1.0), put(1, 4, 1, 0, 1.0), put(1, 5, 2, 0, 1.0)
    return powers.astype(float), terms.reshape(len(powers), -1)


_A_POWERS, _A_TERMS = _piece_terms()


@functools.lru_cache(maxsize=None)
def _peak_plan(orders: tuple[int, ...]) -> tuple:
    """Constants of :func:`unit_peaks` for one tuple of derivative orders (built once).

    ``maps`` (36, nr·(2k−1) + nr·m) takes the products c_i c_j of a piece's position coefficients (Taylor,
    lowest power first; i, j = 0 … 5) to, per order r, the coefficients of ‖·^(r)‖² (2k−1, lowest power
    first) and then of its derivative times x^z (m, highest power first; z brings every order to the
    common degree m − 1 of the lowest order, only adding roots at x = 0, an end of the piece)."""
    nr = len(orders)
    k = _NC - min(orders)  # coefficients of the highest-degree derivative
    m = 2 * k - 2  # coefficients of the derivative of its square
    n_sq = 2 * k - 1
    maps = np.zeros((_NC, _NC, nr * n_sq + nr * m))
    for o, r in enumerate(orders):
        z = 2 * (r - min(orders))
        for i in range(r, _NC):
            for j in range(r, _NC):
                w = math.perm(i, r) * math.perm(j, r)  # (c_i x^(i−r) perm(i, r)) (c_j x^(j−r) perm(j, r))
                power = i + j - 2 * r
                maps[i, j, o * n_sq + power] += w
                if power:
                    maps[i, j, nr * n_sq + o * m + (m - power - z)] += w * power  # x^(power−1+z), highest first
    companion = np.zeros((m - 1, m - 1))
    companion[np.arange(1, m - 1), np.arange(m - 2)] = 1.0
    return k, m, n_sq, maps.reshape(_NC * _NC, -1), np.arange(n_sq), companion


def unit_peaks(h: np.ndarray, coef: np.ndarray, lam: float, orders: tuple[int, ...] = (1, 2, 3),
               prune: bool = False) -> np.ndarray:
    """(N, len(orders)) exact max over τ ∈ [0, 1] of ‖(s_u^(r), s_v^(r)/λ)‖ for the pieces of
    :func:`unit_pieces` (Eq. 17–19 with b = 1, T = 1; the symmetric half is enough). ``lam`` is a number or
    an (N, 1, 1) array (one λ per row). Any number of pieces: ``h`` (N, pieces), ``coef`` (N, pieces, 2, 6)
    (a move at two heights passes all six, :func:`pickplace_cli.paths.bspline._plane_paths`).

    On each piece ‖·‖² is a polynomial; its maximum is at an end or at a real root of its derivative.
    The square norms and their derivatives come from the products of the position coefficients by one
    constant linear map (:func:`_peak_plan`); the roots are eigenvalues of companion matrices, all pieces
    and orders in one batched call (a lower-degree derivative is multiplied by a power of x: extra roots at
    x = 0, an end that is a candidate anyway). Every candidate is clipped into its piece and the square
    norm is evaluated there: a complex root's real part is then just another point of the piece, never
    above the maximum, so no test for real roots is needed. Every row by operations on that row alone
    (stacked products), so a row's peaks do not depend on the batch it is in. (Written for small N, where
    numpy's per-call cost dominates: the optimiser calls it with one point a few hundred times per λ.)
    ``prune``: roots only for the pieces whose upper bound reaches the largest value at a piece end (the
    planner's paths: 2–3× fewer eigenvalue problems on a batch; the same maxima, bitwise)."""
    n = h.shape[0]
    nr = len(orders)
    k, m, n_sq, maps, expo, companion = _peak_plan(tuple(orders))
    scaled = coef.copy()  # (N, pieces, 2 axes, 6)
    scaled[..., 1, :] *= 1.0 / lam
    pieces = coef.shape[1]
    prod = (scaled[..., :, None] * scaled[..., None, :]).sum(axis=2).reshape(n, pieces, _NC * _NC)
    both = prod @ maps  # (N, 3 pieces, nr·n_sq + nr·m)
    sq = both[..., : nr * n_sq].reshape(-1, n_sq, 1)  # rows (N, piece, order), lowest power first
    hf = both[..., nr * n_sq :].reshape(-1, m)  # derivative, highest power first
    hh = np.repeat(h.ravel(), nr)
    x = np.empty((hf.shape[0], m + 1))
    x[:, 0] = 0.0
    x[:, 1] = hh
    need = None
    if prune:
        # only a piece that can hold the maximum needs its roots: its upper bound on ‖·‖² (the largest Bernstein
        # coefficient on [0, h], plus 1e-9 of Σ|a_p| h^p for round-off) must reach the largest value at a piece
        # end of the same move and order (as batch_norm_peaks); the others keep their ends only, which leaves
        # the maximum, bitwise, as it is
        from ..curves.peaks import _bernstein

        ends = ((x[:, :2, None] ** expo) @ sq)[..., 0]  # (rows, 2)
        best = ends.reshape(n, pieces, nr, 2).max(axis=(1, 3))  # (N, orders)
        scaled = sq[..., 0] * hh[:, None] ** expo  # a_p h^p, lowest power first
        bound = (scaled[:, None, :] @ _bernstein(n_sq - 1))[:, 0].max(axis=1) + 1e-9 * np.abs(scaled).sum(axis=1)
        need = (bound.reshape(n, pieces, nr) >= best[:, None, :]).reshape(-1)
    if need is None or need.all():
        x[:, 2:] = _clipped_roots(hf, hh, companion)
    else:
        x[:, 2:] = 0.0  # an end: a candidate anyway
        r = np.flatnonzero(need)
        if r.size:
            x[r, 2:] = _clipped_roots(hf[r], hh[r], companion)
    vals = ((x[..., None] ** expo) @ sq).reshape(n, pieces, nr, m + 1)
    return np.sqrt(np.maximum(vals.max(axis=(1, 3)), 0.0))


def _clipped_roots(hf: np.ndarray, hh: np.ndarray, companion: np.ndarray) -> np.ndarray:
    """The roots of each row polynomial ``hf`` (highest power first), real parts clipped into [0, hh] (a complex
    root's real part is just another point of the piece): companion-matrix eigenvalues, numpy's roots for a
    row whose degree drops (rare)."""
    m = hf.shape[1]
    lead = hf[:, 0]
    full = np.abs(lead) > 1e-12 * np.abs(hf).max(axis=1)
    comp = np.empty((hf.shape[0], m - 1, m - 1))
    comp[:] = companion
    if full.all():
        comp[:, 0, :] = hf[:, 1:] / -lead[:, None]
        return np.minimum(np.maximum(np.linalg.eigvals(comp).real, 0.0), hh[:, None])
    comp[:, 0, :] = hf[:, 1:] / -np.where(full, lead, 1.0)[:, None]
    out = np.minimum(np.maximum(np.linalg.eigvals(comp).real, 0.0), hh[:, None])
    for i in np.flatnonzero(~full):
        v = np.roots(hf[i]).real if np.any(hf[i]) else np.zeros(0)
        out[i] = 0.0
        out[i, : v.size] = np.minimum(np.maximum(v, 0.0), hh[i])
    return out


def fast_peaks(k1, k2, lam: float, eta: float = 0.5, orders: tuple[int, ...] = (1, 2, 3)) -> np.ndarray:
    """Exact normalised peaks (N, len(orders)) for arrays of (k1, k2): :func:`normalised_peaks`, batched."""
    return unit_peaks(*unit_pieces(k1, k2, eta), lam, orders)


# ------------------------------------------------------------------------------------------ coarse grid


@dataclass(frozen=True)
class _Coarse:
    k1: np.ndarray  # (G,)
    k2: np.ndarray  # (G,)
    shape: tuple[int, int]
    acc_u2: np.ndarray  # (G, M) sampled s_u''², s_v''², s_u'''², s_v'''²
    acc_v2: np.ndarray
    jerk_u2: np.ndarray
    jerk_v2: np.ndarray

    def peaks(self, lam: float) -> tuple[np.ndarray, np.ndarray]:
        """Sampled a_max, j_max on the whole grid at λ (the v axis scales by 1/λ: Eq. 17)."""
        s = 1.0 / (lam * lam)
        a = np.sqrt(np.max(self.acc_u2 + s * self.acc_v2, axis=1))
        j = np.sqrt(np.max(self.jerk_u2 + s * self.jerk_v2, axis=1))
        return a, j


def _coarse_grid(settings: TableSettings) -> tuple[np.ndarray, np.ndarray]:
    step = settings.grid_step
    ks = np.round(np.arange(step, 1.0 - step / 2, step), 10)
    k1, k2 = np.meshgrid(ks, np.concatenate(([settings.k2_floor], ks)), indexing="ij")
    return k1.ravel(), k2.ravel()


@functools.lru_cache(maxsize=2)
def _coarse_for(settings: TableSettings) -> _Coarse:
    """The coarse stage for ``settings`` (computed once per process: a worker builds its own copy, which
    is cheaper than shipping the arrays)."""
    k1, k2 = _coarse_grid(settings)
    h, coef = unit_pieces(k1, k2, settings.eta)
    u = np.linspace(0.0, 1.0, settings.samples_per_piece + 1)  # both ends: the mirror half is covered
    comps = []
    for r in (2, 3):
        d = coef[..., r:] * _DROW[r, r:]  # (G, 3, 2, k): the r-th derivative's coefficients in x = h·u
        k = d.shape[-1]
        # Σ_p d_p (h u)^p = Σ_p (d_p h^p) u^p: one product with the powers of the sample points
        val = (d * (h[:, :, None, None] ** np.arange(k))) @ (u[None, :] ** np.arange(k)[:, None])
        val = np.moveaxis(val, 2, 1).reshape(len(k1), 2, -1)
        comps += [val[:, 0] ** 2, val[:, 1] ** 2]
    n1 = len(np.unique(k1))
    return _Coarse(k1, k2, (n1, len(k1) // n1), *comps)


# ------------------------------------------------------------------------------------------- optimiser


@dataclass(frozen=True)
class TableRow:
    lam: float
    k1: float
    k2: float
    a_max: float
    j_max: float
    v_max: float
    F: float
    a_min: float
    j_min: float


def _same_basin(fun_batch: Callable[[np.ndarray, np.ndarray], np.ndarray], start, optimum, points: int = 9) -> bool:
    """True when ``fun`` falls monotonically along the segment from ``start`` to a found ``optimum``:
    then a local search from ``start`` ends in that optimum's basin and need not run. (Two separate
    optima have a barrier between them, so the test fails and both are refined; it is conservative.)"""
    t = np.linspace(0.0, 1.0, points)
    k1 = start[0] + t * (optimum[0] - start[0])
    k2 = start[1] + t * (optimum[1] - start[1])
    vals = fun_batch(k1, k2)
    return bool(np.all(np.diff(vals) <= 1e-12 * np.max(np.abs(vals))))


def _minimise(
    fun: Callable[[float, float], float],
    fun_batch: Callable[[np.ndarray, np.ndarray], np.ndarray],
    starts: Sequence[tuple[float, float]],
    lo2: float,
    xatol: float,
    ftol: float = 1e-10,
):
    """Bounded Nelder–Mead (scipy) from each start not already in a found optimum's basin; the best.

    Stops when the simplex is within ``xatol`` and its values within ``ftol`` relative of the objective's
    value at the start (F ≈ 1, but j_max ≈ 100: an absolute tolerance would ask j for 1e-12)."""
    from scipy.optimize import minimize

    found: list[tuple[float, float, float]] = []
    for k1, k2 in starts:
        if any(_same_basin(fun_batch, (k1, k2), (x1, x2)) for x1, x2, _ in found):
            continue
        res = minimize(
            lambda x: fun(float(x[0]), float(x[1])),
            x0=np.array([k1, k2]),
            method="Nelder-Mead",
            bounds=[(1e-3, 1 - 1e-3), (lo2, 1 - 1e-3)],
            options={"xatol": xatol, "fatol": ftol * abs(fun(k1, k2)), "maxiter": 2000,
                     "initial_simplex": np.array([[k1, k2], [k1 + 0.01, k2], [k1, k2 + 0.01]])},
        )
        found.append((float(res.x[0]), float(res.x[1]), float(res.fun)))
    return min(found, key=lambda r: r[2])


def _minimise_on_floor(fun: Callable[[float, float], float], k1_starts: Sequence[float], k2: float, xatol: float) -> float:
    """min over k1 of fun(k1, k2) with k2 fixed, by bounded Brent in a ±0.02 bracket around each start."""
    from scipy.optimize import minimize_scalar

    best = math.inf
    for k1 in k1_starts:
        res = minimize_scalar(
            lambda x: fun(float(x), k2), bounds=(max(1e-3, k1 - 0.02), min(1 - 1e-3, k1 + 0.02)),
            method="bounded", options={"xatol": xatol * 0.1},
        )
        best = min(best, float(res.fun))
    return best


def _local_optima(values: np.ndarray, shape: tuple[int, int], count: int) -> list[int]:
    """Flat indices of up to ``count`` best local minima of ``values`` on the 2-D grid (8-neighbourhood)."""
    v = values.reshape(shape)
    pad = np.pad(v, 1, constant_values=np.inf)
    is_min = np.ones(shape, dtype=bool)
    for di in (-1, 0, 1):
        for dj in (-1, 0, 1):
            if di or dj:
                is_min &= v <= pad[1 + di : 1 + di + shape[0], 1 + dj : 1 + dj + shape[1]]
    idx = np.flatnonzero(is_min.ravel())
    idx = idx[np.argsort(values[idx], kind="stable")][:count]
    if idx.size == 0:
        idx = np.array([int(np.argmin(values))])
    return [int(i) for i in idx]


def optimise_lambda(lam: float, coarse: _Coarse, settings: TableSettings,
                    f_refine: tuple[float, float] | None = None, top_starts: int = 0) -> TableRow:
    """Global optimum of F (Eq. 22) at one λ, from the coarse grid and a bounded local refinement (Nelder–Mead
    to ``settings.refine_xatol`` in k and 1e-10 relative in the objective). ``f_refine`` = (xatol, ftol): a
    looser end for the searches of j_min and of F (a_min, a cheap 1-D search as a rule, stays tight). F's
    argmax hardly moves with its normaliser j_min, but its reported value does: on jerk's kinked minimum
    Nelder–Mead can stop up to ~1e-5 above j_min, which raises the reported F by as much. ``top_starts``: F is also refined from that many
    best grid points that are not in a found optimum's basin (a coarse grid can miss a narrow basin that
    shows as no local maximum of the samples: a tall move at grid step 0.025)."""
    eta = settings.eta
    wa, wj = settings.weights
    lo2 = settings.k2_floor
    a_grid, j_grid = coarse.peaks(lam)
    cache: dict[tuple[float, float], tuple[float, float]] = {}

    def batch(orders: tuple[int, ...]) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
        return lambda k1, k2: unit_peaks(*unit_pieces(k1, k2, eta), lam, orders)

    a_batch, j_batch, aj_batch = batch((2,)), batch((3,)), batch((2, 3))

    def a_only(k1: float, k2: float) -> float:
        return float(a_batch(k1, k2)[0, 0])

    def j_only(k1: float, k2: float) -> float:
        return float(j_batch(k1, k2)[0, 0])

    def peaks(k1: float, k2: float) -> tuple[float, float]:
        """Exact (a_max, j_max) at (k1, k2), memoised (F's refinement revisits points)."""
        key = (k1, k2)
        if key not in cache:
            a, j = aj_batch(k1, k2)[0]
            cache[key] = (float(a), float(j))
        return cache[key]

    def starts(values: np.ndarray) -> list[tuple[float, float]]:
        """Grid local minima whose sampled value is within ``basin_margin`` of the best one.

        Samples under-estimate a peak by well under 1 % at ``samples_per_piece`` = 16, so a basin whose
        sampled value is more than a few per cent worse cannot hold the global optimum."""
        idx = _local_optima(values, coarse.shape, settings.refine_candidates)
        best = values[idx[0]]
        keep = [i for i in idx if values[i] <= best + settings.basin_margin * abs(best)]
        return [(float(coarse.k1[i]), float(coarse.k2[i])) for i in keep]

    xatol = settings.refine_xatol
    # Sampled grid values under-estimate peaks, so only the refined exact values are used below.
    a_starts = starts(a_grid)
    if all(k2 == lo2 for _, k2 in a_starts):
        # the infimum of a_max lies at k2 → 0 [Li2018, Sec. 3.1]: a 1-D bounded search along k2 = k2_floor
        a_min = _minimise_on_floor(a_only, [k1 for k1, _ in a_starts], lo2, xatol)
    else:
        _, _, a_min = _minimise(a_only, lambda x, y: a_batch(x, y)[:, 0], a_starts, lo2, xatol)
    fx, ff = f_refine if f_refine is not None else (xatol, 1e-10)
    _, _, j_min = _minimise(j_only, lambda x, y: j_batch(x, y)[:, 0], starts(j_grid), lo2, fx, ff)

    def neg_f(k1: float, k2: float) -> float:
        a, j = peaks(k1, k2)
        return -(wa * a_min / a + wj * j_min / j)

    def neg_f_batch(k1: np.ndarray, k2: np.ndarray) -> np.ndarray:
        aj = aj_batch(k1, k2)
        return -(wa * a_min / aj[:, 0] + wj * j_min / aj[:, 1])

    f_grid = -(wa * a_min / a_grid + wj * j_min / j_grid)
    # F may have two local maxima (small λ): refine every grid local maximum near the best
    f_starts = starts(f_grid)
    if top_starts:
        limit = f_grid.min() + settings.basin_margin * abs(f_grid.min())
        f_starts += [(float(coarse.k1[i]), float(coarse.k2[i])) for i in np.argsort(f_grid, kind="stable")[:top_starts]
                     if f_grid[i] <= limit and (float(coarse.k1[i]), float(coarse.k2[i])) not in f_starts]
    k1, k2, nf = _minimise(neg_f, neg_f_batch, f_starts, lo2, fx, ff)
    v, a, j = (float(x) for x in fast_peaks(k1, k2, lam, eta)[0])
    return TableRow(lam, k1, k2, a, j, v, -nf, a_min, j_min)


def _optimise_chunk(lams: Sequence[float], settings: TableSettings) -> list[TableRow]:
    """One task of a parallel build: the rows of ``lams`` (module level, so executors can pickle it)."""
    coarse = _coarse_for(settings)
    return [optimise_lambda(float(lam), coarse, settings) for lam in lams]


# ------------------------------------------------------------------------------------ on-demand optimum

#: the optimiser's settings for a (λ, η) the table does not cover: a coarser start grid (0.025 instead of
#: 0.01) — the same F as build-table's settings on 20 random (λ, η) with η in [0.1, 0.9], λ in [0.5, 200]
#: (worst difference 1.5e-8), ~60 ms per solve instead of ~250 ms
ON_DEMAND_GRID = 0.025
#: … and a looser end of the searches of j_min and of F (k to 1e-4 instead of 1e-5, values to 1e-7 relative
#: instead of 1e-10; a_min stays tight): the (k1, k2) found lose at most 1.4e-6 of F against build-table's
#: settings on 60 random (λ, η) (bench/bench_on_demand.py), ~46 ms per solve instead of ~56; the F reported
#: can be up to ~1e-5 high (its normaliser j_min is found less tightly)
ON_DEMAND_F_REFINE = (1e-4, 1e-7)


#: … and F refined also from the best grid points outside a found basin (a narrow basin of a tall move)
ON_DEMAND_TOP_STARTS = 6


#: the λ = b/h an on-demand solve accepts (beyond, the optimum has run into the k bounds: see the README)
ON_DEMAND_LAMBDA = (1e-3, 1e5)


@functools.lru_cache(maxsize=4096)
def solve_on_demand(lam: float, eta: float, weights: tuple[float, float] = (0.5, 0.5)) -> tuple[float, float, float]:
    """(k1*, k2*, F) of Li 2018's Eq. (22) at one (λ, η) by build-table's global optimiser (coarse grid, then
    bounded refinement of every basin near the best), for a move the table does not cover; memoised in the
    process (the same move again costs nothing)."""
    lo, hi = ON_DEMAND_LAMBDA
    if not (np.isfinite(lam) and lo <= lam <= hi):
        raise TableError(f"lambda = b/h = {lam:.4g}: outside [{lo:g}, {hi:g}], where the optimal (k1, k2) can be "
                         "solved (see README: extreme lambda); change --height or give --k1 and --k2")
    settings = TableSettings(eta=float(eta), weights=tuple(weights), grid_step=ON_DEMAND_GRID)
    row = optimise_lambda(float(lam), _coarse_for(settings), settings, f_refine=ON_DEMAND_F_REFINE,
                          top_starts=ON_DEMAND_TOP_STARTS)
    return row.k1, row.k2, row.F
