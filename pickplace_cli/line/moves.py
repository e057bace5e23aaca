"""A line robot's moves, planned fast and exactly: the conveyor B-spline of [Yang2022] with its shape held fixed
while the duration is searched.

A move runs from ``start`` (leaving with ``v_from``) to an end that may move with the duration T,
``end(T) = end_a + T·end_b`` (a part on a belt met at move time T: ``end_a`` its position at the move's start,
``end_b`` the belt velocity; a fixed place point: ``end_b = 0``), arriving with ``v_to``. For a fixed shape
p = (τ6, τ7, τ9, τ10, λ1, λ2, λ3) the path is the quintic B-spline through s0 … s4 with the end conditions
(v0·T, 0, 0) and (v1·T, 0, 0) [Yang2022, Eq. (16), (24)–(28)]. Every one of those 11 conditions is affine in T
(the via points of Eq. (28) above the end move with it; the offsets of Eq. (25)–(27) are v·λ·T), and the control
points are a fixed linear map of them (the collocation matrix of the shape's knots, inverted once per shape), so

    d^k p/dτ^k (τ; T) = A_k(τ) + T·B_k(τ),   k = 0 … 5,

with A_k, B_k two matrix products per move. The search for the duration then costs a few vector operations per
trial T (:meth:`Move.excess_auto`, on a 129-point grid, peaks refined by a parabola), and the exact peaks of the
path at the chosen T come from its piece polynomials (:func:`exact_rule`: the batched root search of
:func:`~pickplace_cli.curves.peaks.batch_norm_peaks`, the routine behind the method's own exact peaks), which
nudge T up until the rule holds exactly (:func:`verify_auto`). The path is the one :func:`~pickplace_cli.paths.bspline_vel.plan_bspline_vel` builds for the same task,
duration and shape (:meth:`Move.path`; tests compare them to 1e-12 m).

**The shape** comes from the shipped conveyor table for the move's dimensionless groups at a first estimate of
T (:class:`Shapes`, memoised on the groups rounded to ``GROUP_STEP``), or the paper's initial shape where the
table does not apply (other η, unequal heights); groups outside its range are clipped to it and the better of the
two shapes by the searched T is used. It is not re-optimised at every trial T as ``plan --to-belt`` does (a full
solve per trial: 0.1–1 s a move; :mod:`~pickplace_cli.line.optimal` does that for a robot with ``shape: optimal``);
the duration rule still holds exactly for the path that is run, and the meeting point and velocity are exact by
construction.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..model.errors import TableError, TaskError

#: uniform τ samples of a move's check grid (plus its breakpoints and the Gauss–Legendre nodes of every span): the
#: limit check's peaks on it are within 0.2 % of the exact check's (60 random moves; tests hold 1 %)
GRID_UNIFORM = 33
#: uniform τ samples of the grid the durations are searched on (plus the breakpoints; the peaks refined by a
#: parabola: within ~1e-4 of the exact ones, which then decide)
SEARCH_UNIFORM = 129
#: Gauss–Legendre nodes per knot span: the RMS integrals of a move are this quadrature (within 3.4e-7 of the limit
#: check's adaptive Gauss–Kronrod on 30 random moves; 10 nodes: 4e-8, 6: 2e-4)
GL_NODES = 8
#: the velocity groups v·T/b are rounded to this step, and h/b to this step in log h/b, before the table is asked
#: (the memo's key; the table's grid is 5× coarser, and its answer is an interpolation between optima)
GROUP_STEP = 0.05
#: the shortest move [s] (as the rendezvous search)
T_MIN = 1e-2
#: the longest move searched [s]
HORIZON = 20.0
#: trial durations of the first scan of the search
SCAN = 16
#: relative width at which the search of the first feasible T stops
RTOL = 1e-9
#: ... or when the excess at its feasible end is within this of 0
ETOL = 1e-11


class ShapeBasis:
    """The linear algebra of one shape p (7,): knots, breakpoints, and the matrices that map a move's 11 conditions
    D (11, 3) to the k-th τ-derivative on the check grid ``tau`` (``grid[k]`` (G, 11), k = 0 … 3), on the search
    grid ``search_tau`` (``search[k]``, k = 1 … 3; ``search[0]`` is None) and at the left end of every span
    (``left[r]`` (6, 11), r = 0 … 5); the RMS quadrature: indices of the Gauss–Legendre nodes in the check grid
    and their weights."""

    def __init__(self, params) -> None:
        from ..curves.bspline import yang_knots

        p = tuple(float(x) for x in params)
        self.params = p
        self.lam = np.array(p[4:7])
        knots = yang_knots(*p[:4])
        breaks = np.array([0.0, p[0], p[1], 0.5, p[2], p[3], 1.0])
        x, w = gauss_legendre()
        half = np.diff(breaks) / 2
        nodes = ((breaks[:-1] + half)[:, None] + half[:, None] * x).ravel()
        tau = np.unique(np.concatenate([np.linspace(0.0, 1.0, GRID_UNIFORM), breaks, nodes]))
        self.breaks, self.tau = breaks, tau
        self.gl_index = np.searchsorted(tau, nodes)
        self.gl_weight = (half[:, None] * w).ravel()
        # every basis function at every point needed, one evaluation per derivative order: the collocation
        # points (0, τ7, ½, τ9, 1), the grid, the spans' left ends
        from scipy.interpolate import BSpline

        spline = BSpline(knots, np.eye(11), 5, extrapolate=True)
        self.search_tau = np.unique(np.concatenate([np.linspace(0.0, 1.0, SEARCH_UNIFORM), breaks]))
        G, S = len(tau), len(self.search_tau)
        pts = np.concatenate([[0.0, p[1], 0.5, p[2], 1.0], tau, breaks[:-1], self.search_tau])
        vals = [spline(pts, nu=k) for k in range(6)]
        colloc = np.vstack([vals[k][0] for k in range(4)] + [vals[0][1:4]] + [vals[k][4] for k in range(4)])
        cinv = np.linalg.inv(colloc)
        self.grid = [vals[k][5:5 + G] @ cinv for k in range(4)]
        self.left = [vals[r][5 + G:11 + G] @ cinv for r in range(6)]
        self.search = [None] + [vals[k][11 + G:11 + G + S] @ cinv for k in (1, 2, 3)]


_GL: list = []


def gauss_legendre() -> tuple[np.ndarray, np.ndarray]:
    """The ``GL_NODES`` Gauss–Legendre nodes and weights on [−1, 1] (computed once)."""
    if not _GL:
        _GL.extend(np.polynomial.legendre.leggauss(GL_NODES))
    return _GL[0], _GL[1]


def conditions(start, v_from, end_a, end_b, v_to, height: float, eta: float, lam) -> tuple[np.ndarray, np.ndarray]:
    """(D_a, D_b), each (11, 3): the move's conditions D(T) = D_a + T·D_b in the collocation order
    [s0, v0·T, 0, 0, s1, s2, s3, s4, v1·T, 0, 0] (m, base frame). The via points s1′ … s3′ are
    :meth:`~pickplace_cli.model.task.Task.via_points` (lift-off above the start, apex above the midpoint, set-down
    above the end, at η of the rise to the apex), moved by λ·v·T [Yang2022, Eq. (25)–(28)]. ``end_b`` must be
    horizontal (the apex height then does not depend on T)."""
    s, e, eb = np.asarray(start, float), np.asarray(end_a, float), np.asarray(end_b, float)
    v0, v1 = np.asarray(v_from, float), np.asarray(v_to, float)
    if eb[2] != 0.0:
        raise TaskError("a moving end must move horizontally (a belt's velocity has no vertical component)")
    zt = max(s[2], e[2]) + height
    da = np.zeros((11, 3))
    db = np.zeros((11, 3))
    da[0] = s
    db[1] = v0
    da[4] = (s[0], s[1], s[2] + eta * (zt - s[2]))
    db[4] = lam[0] * v0
    da[5] = ((s[0] + e[0]) / 2, (s[1] + e[1]) / 2, zt)
    db[5] = (eb[0] / 2, eb[1] / 2, 0.0) + lam[1] * (v0 - v1) / 2
    da[6] = (e[0], e[1], e[2] + eta * (zt - e[2]))
    db[6] = (eb[0], eb[1], 0.0) - lam[2] * v1
    da[7] = e
    db[7] = eb
    db[8] = v1
    return da, db


class Move:
    """One move of a fixed shape: T → its path, the capacity rule's excess, exact peaks (module docstring).

    ``theta`` [rad] is the tool's angle about the base z axis at the start (a rotary fourth axis; 0 otherwise) and
    ``turn`` [rad] the turn it makes, as ``plan`` makes one (:func:`~pickplace_cli.paths.turn.turned`: the degree-9
    law between lift-off and set-down). Neither depends on T, nor does the window of the turn: the path's height
    (the z column of its conditions) is the same at every duration, so the law in τ is fixed per move."""

    def __init__(self, basis: ShapeBasis, start, v_from, end_a, end_b, v_to, height: float, eta: float,
                 theta: float = 0.0, turn: float = 0.0) -> None:
        self.basis = basis
        self.theta, self.turn = float(theta), float(turn)
        self._law = self._turn_peaks = None
        self.start = np.asarray(start, float)
        self.v_from, self.v_to = np.asarray(v_from, float), np.asarray(v_to, float)
        self.end_a, self.end_b = np.asarray(end_a, float), np.asarray(end_b, float)
        self.height, self.eta = float(height), float(eta)
        self.da, self.db = conditions(start, v_from, end_a, end_b, v_to, height, eta, basis.lam)
        self._check: tuple | None = None
        self._dot: dict = {}

    @property
    def A(self) -> list[np.ndarray]:
        """d^k p/dτ^k = A[k] + T·B[k] on the check grid, k = 0 … 3 (computed on first use)."""
        return self._ab()[0]

    @property
    def B(self) -> list[np.ndarray]:
        return self._ab()[1]

    def _ab(self) -> tuple:
        if self._check is None:
            self._check = ([g @ self.da for g in self.basis.grid], [g @ self.db for g in self.basis.grid])
        return self._check

    def end(self, T: float) -> np.ndarray:
        return self.end_a + T * self.end_b

    def samples(self, T: float) -> list[np.ndarray]:
        """[p, p′, p″, p‴] on the check grid at duration T, each (G, 3) (τ-derivatives: the motion at T = 1 s)."""
        return [a + T * b for a, b in zip(self.A, self.B)]

    def _dots(self, k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(‖A_k‖², 2·A_k·B_k, ‖B_k‖²) per point of the search grid: ‖d^k p/dτ^k‖² = aa + T·ab + T²·bb; k = 0:
        the three orders 1, 2, 3 side by side, each (G, 3)."""
        hit = self._dot.get(k)
        if hit is None and k == 0:
            hit = self._dot[0] = tuple(np.column_stack(x) for x in zip(*(self._dots(o) for o in (1, 2, 3))))
        elif hit is None:
            m = self.basis.search[k]
            a, b = m @ self.da, m @ self.db
            hit = self._dot[k] = (np.einsum("gd,gd->g", a, a), 2.0 * np.einsum("gd,gd->g", a, b),
                                  np.einsum("gd,gd->g", b, b))
        return hit

    def grid_peaks(self, Ts: np.ndarray, orders=(1, 2, 3)) -> np.ndarray:
        """Peaks of ‖d^k p/dτ^k‖ on the grid, refined by the parabola through the top sample and its neighbours
        (:func:`~pickplace_cli.curves.peaks.parabolic_peak`), for every trial duration: (len(Ts), len(orders))."""
        from ..curves.peaks import parabolic_peak

        T = np.asarray(Ts, float)[:, None]
        out = np.empty((T.shape[0], len(orders)))
        for c, k in enumerate(orders):
            aa, ab, bb = self._dots(k)
            y = aa + T * (ab + T * bb)
            out[:, c] = np.sqrt(np.maximum(parabolic_peak(self.basis.search_tau, y.T)[0], 0.0))
        return out

    def peaks_at(self, T: float) -> list[float]:
        """:meth:`grid_peaks` of the orders 1, 2, 3 at one duration (the search's inner loop: one call)."""
        from ..curves.peaks import parabolic_peak

        aa, ab, bb = self._dots(0)
        return np.sqrt(np.maximum(parabolic_peak(self.basis.search_tau, aa + T * (ab + T * bb))[0], 0.0)).tolist()

    def excess_auto(self, capacity) -> Callable[[np.ndarray], np.ndarray]:
        """e(T) = T_auto(path planned for T)/T − 1 on the grid (≤ 0: the capacity rule holds) [Li2018, Eq. (26)]."""
        vmax, amax, jmax = capacity.velocity, capacity.acceleration, capacity.jerk
        orders = (1, 2, 3) if jmax else (1, 2)

        def e(Ts: np.ndarray) -> np.ndarray:
            Ts = np.asarray(Ts, float)
            if Ts.size == 1:
                T = float(Ts.reshape(-1)[0])
                pk = self.peaks_at(T)
                t_rule = max(pk[0] / vmax, math.sqrt(pk[1] / amax))
                if jmax:
                    t_rule = max(t_rule, (pk[2] / jmax) ** (1.0 / 3.0))
                return np.array([t_rule / T - 1.0])
            pk = self.grid_peaks(Ts, orders)
            t_rule = np.maximum(pk[:, 0] / vmax, np.sqrt(pk[:, 1] / amax))
            if jmax:
                t_rule = np.maximum(t_rule, np.cbrt(pk[:, 2] / jmax))
            return t_rule / Ts - 1.0

        def floor(T: float) -> float:
            """A lower bound of e(T) from the grid's samples alone (a refined peak is never below the largest sample):
            a few vector operations, to tell a duration the rule cannot hold at without the search's evaluation."""
            aa, ab, bb = self._dots(0)
            pk = np.sqrt(np.maximum(np.max(aa + T * (ab + T * bb), axis=0), 0.0)).tolist()
            t_rule = max(pk[0] / vmax, math.sqrt(pk[1] / amax))
            if jmax:
                t_rule = max(t_rule, (pk[2] / jmax) ** (1.0 / 3.0))
            return t_rule / T - 1.0

        e.floor = floor  # type: ignore[attr-defined]
        return e

    def exact_peaks(self, T: float, orders=(1, 2, 3)) -> tuple[float, ...]:
        """Exact max over τ of ‖d^k p/dτ^k‖, k in ``orders``, of the path planned for T (its piece polynomials)."""
        from ..curves.bspline import pieces_norm_peaks

        d = self.da + T * self.db
        derivs = [m @ d for m in self.basis.left]
        return pieces_norm_peaks(self.basis.breaks, derivs, orders)  # type: ignore[return-value]

    def drop_caches(self) -> None:
        """Forget the grid matrices and dot products (recomputed on use): a committed move keeps only what defines
        it, so a long run holds a few kB a part."""
        self._check = None
        self._dot = {}
        self._law = None

    @property
    def theta_end(self) -> float:
        """The tool angle at the move's end [rad]."""
        return self.theta + self.turn

    def task(self, T: float, angles: bool | None = None):
        """The move's Task at duration T (with the tool angles when it turns, or when ``angles``)."""
        from ..model.task import Task

        if angles is None:
            angles = self.turn != 0.0
        th = (self.theta, self.theta_end) if angles else (None, None)
        return Task(self.start, self.end(T), self.height, self.eta, self.v_from, self.v_to, *th)

    def path(self, T: float, angle: bool = True):
        """The CartesianPath of the move planned for T, built by the method itself
        (:func:`~pickplace_cli.paths.bspline_vel.plan_bspline_vel` with this shape), carrying the tool's turn as
        ``plan`` attaches it (:func:`~pickplace_cli.paths.turn.turned`), or its constant angle (``angle``)."""
        from ..paths.bspline_vel import plan_bspline_vel

        path = plan_bspline_vel(self.task(T, angles=False), T, params=list(self.basis.params))
        if not angle or (self.turn == 0.0 and self.theta == 0.0):
            return path
        from dataclasses import replace

        from ..curves.rotation import RotationLaw, with_rotation

        if self.turn == 0.0:
            return replace(path, angle=RotationLaw(self.theta, 0.0))
        # turned()'s law (paths/turn.py, as plan attaches it), its window memoised: the path's height is the same at
        # every T, so the window found once on this move's shape and heights is this path's
        law = self.law()
        info = {"from_rad": self.theta, "to_rad": self.theta_end, "turn_rad": self.turn, "during": "transfer",
                "window_tau": [law.tau0, law.tau1]}
        path = with_rotation(path, self.theta, self.turn, (law.tau0, law.tau1))
        return replace(path, parameters={**path.parameters, "turn": info})

    def law(self):
        """The angle law of a turning move (:func:`turn_law`, kept)."""
        if self._law is None:
            self._law = turn_law(self)
        return self._law

    def turn_peaks(self) -> tuple[float, float, float]:
        """Exact max |θ′|, |θ″|, |θ‴| over τ of the tool angle's law [rad/1^k] (:attr:`RotationLaw.peaks`; 0 without a
        turn), kept with the move (three numbers: through :meth:`drop_caches` too)."""
        if self._turn_peaks is None:
            self._turn_peaks = self.law().peaks if self.turn != 0.0 else (0.0, 0.0, 0.0)
        return self._turn_peaks

    def angle_orders(self, tau) -> np.ndarray:
        """θ, θ′, θ″, θ‴ (4, N) of the tool angle at τ [rad/1^k] (the law of :meth:`path`, the same at every T)."""
        tau = np.asarray(tau, float)
        if self.turn == 0.0:
            out = np.zeros((4, len(tau)))
            out[0] = self.theta
            return out
        return self.law().all_orders(tau)


_WINDOWS: dict = {}


def turn_law(mv: "Move"):
    """The angle law of a turning move: :func:`~pickplace_cli.paths.turn.turned`'s on the move's path, its window
    memoised on what the path's height depends on (the shape, the end heights, the clearance and η)."""
    from ..curves.rotation import RotationLaw

    key = (mv.basis.params, float(mv.start[2]), float(mv.end_a[2]), float(mv.v_from[2]), float(mv.v_to[2]), mv.height,
           mv.eta)
    window = _WINDOWS.get(key)
    if window is None:
        window = transfer_window(mv)
        if len(_WINDOWS) > 65536:
            _WINDOWS.clear()
        _WINDOWS[key] = window
    return RotationLaw(mv.theta, mv.turn, *window)


def transfer_window(mv: "Move") -> tuple[float, float]:
    """(τa, τb) of :func:`~pickplace_cli.curves.rotation.transfer_window` for the move's path (what
    :func:`~pickplace_cli.paths.turn.turned` uses: the first τ at which the tool has risen to the lift-off height,
    the last at which it is still at the set-down height or above, those heights η of the rise to the apex), found
    on the height's piece polynomials (each span a quintic: its real roots) instead of samples and bisection; (0, 1)
    when the path does not rise through both. Tests: equal to turned()'s window within 1e-9."""
    z_lift = mv.start[2] + mv.eta * (mv.da[5, 2] - mv.start[2])
    z_set = mv.end_a[2] + mv.eta * (mv.da[5, 2] - mv.end_a[2])
    breaks = mv.basis.breaks
    z = mv.da[:, 2]
    derivs = np.array([m @ z for m in mv.basis.left])  # (6, spans): d^r z/dτ^r at each span's left end
    spans = len(breaks) - 1
    coef = np.empty((2, spans, 6))  # per level and span: the quintic z − level, highest power first (as np.roots)
    coef[:] = (derivs[::-1] / _FACTORIALS[::-1, None]).T
    coef[0, :, -1] -= z_lift
    coef[1, :, -1] -= z_set
    roots = _quintic_roots(coef.reshape(-1, 6)).reshape(2, spans, -1)

    def crossings(level: int) -> list[float]:
        out = []
        for k in range(spans):
            h = breaks[k + 1] - breaks[k]
            for root in roots[level, k]:
                if abs(root.imag) < 1e-9 and -1e-12 <= root.real <= h + 1e-12:
                    out.append(float(breaks[k] + min(max(root.real, 0.0), h)))
        return sorted(out)

    up, down = crossings(0), crossings(1)
    if mv.start[2] >= z_lift:
        up = [0.0] + up
    if mv.end_a[2] >= z_set:
        down = down + [1.0]
    if not up or not down or not up[0] < down[-1]:
        return 0.0, 1.0
    return up[0], down[-1]


_FACTORIALS = np.array([math.factorial(r) for r in range(6)], float)


def _quintic_roots(coef: np.ndarray) -> np.ndarray:
    """The roots of every quintic of ``coef`` (n, 6) (highest power first), (n, 5) complex, NaN where fewer: the
    eigenvalues of their companion matrices in one batched call, as :func:`numpy.roots` forms them (a quintic whose
    highest or lowest coefficient is 0 goes to numpy.roots itself, which drops those)."""
    n = len(coef)
    out = np.full((n, 5), np.nan, complex)
    full = (coef[:, 0] != 0.0) & (coef[:, -1] != 0.0)
    if full.any():
        c = coef[full]
        companion = np.zeros((len(c), 5, 5))
        companion[:, 1:, :-1] = np.eye(4)
        companion[:, 0, :] = -c[:, 1:] / c[:, :1]
        out[full] = np.linalg.eigvals(companion)
    for i in np.flatnonzero(~full):
        r = np.roots(coef[i])
        out[i, :len(r)] = r
    return out


def first_feasible(excess: Callable[[np.ndarray], np.ndarray], a: float, b: float, rtol: float = RTOL,
                   scan: int = SCAN, guess: float | None = None) -> float | None:
    """The smallest T in [a, b] with excess(T) ≤ 0, bracketed then refined by regula falsi (Illinois) to ``rtol``;
    a when excess(a) ≤ 0; None when none is found. The bracket comes from a scan of ``scan`` durations
    (geometric), or, given a ``guess``, from a and the guess, stepping up from the guess by fixed-point steps
    T·(1 + e) (at least 2 %, at most 2×) while it is infeasible (a few scalar evaluations instead of a scan: the
    search of a moving robot's next move starts near its last one). ``excess`` takes an array of T (NaN counts as
    infeasible)."""
    if not (a <= b):
        return None
    if guess is not None:
        found = _bracket_up(excess, a, b, guess)
        if found is None or not isinstance(found, tuple):
            return found
        lo, hi, elo, ehi = found
        return _refine(excess, lo, hi, elo, ehi, rtol)
    Ts = np.geomspace(a, b, scan) if b > a else np.array([a])
    e = np.asarray(excess(Ts), float)
    ok = e <= 0
    if not ok.any():
        return None
    i = int(np.argmax(ok))
    if i == 0:
        return float(a)
    return _refine(excess, float(Ts[i - 1]), float(Ts[i]), float(e[i - 1]), float(e[i]), rtol)


def _bracket_up(excess, a: float, b: float, guess: float):
    """a (feasible at a), None (nothing feasible up to b), or (lo, hi, e(lo), e(hi)) with e(lo) > 0 ≥ e(hi) (e(a):
    a lower bound when ``excess.floor`` shows a infeasible)."""
    def one(T: float) -> float:
        v = float(np.asarray(excess(np.array([T])), float)[0])
        return v if v == v else math.inf

    floor = getattr(excess, "floor", None)  # a lower bound of the excess, when it has one (cheaper than it)
    ea = floor(a) if floor is not None else 0.0
    if not ea > 0:  # (no bound, or it does not show a infeasible: the excess itself)
        ea = one(a)
        if ea <= 0:
            return float(a)
    lo, elo = a, ea  # (elo a bound only: the refinement's first step and its secants do not use it)
    T = min(max(guess, a), b)
    while True:
        if T <= lo:
            T = min(lo * 1.02, b) if lo < b else b
        eT = one(T)
        if eT <= 0:
            return lo, T, elo, eT
        if T >= b:
            return None
        lo, elo = T, eT
        step = 1.0 + eT if math.isfinite(eT) else 2.0
        T = min(T * min(max(step * 1.01, 1.02), 2.0), b)


def _refine(excess, lo: float, hi: float, elo: float, ehi: float, rtol: float) -> float:
    """Regula falsi (Illinois) on a bracket [lo, hi] with e(lo) > 0 ≥ e(hi): the feasible end within ``rtol``. The
    first step is the fixed-point step T·(1 + e) from the feasible end (exact for a rule T_rule/T − 1 whose T_rule does
    not change with T); when a step lands feasible again, the next is the secant through the last two feasible points
    (the bracket's other end, often far — the guess's bracket starts at a — says little about the root there)."""
    side = 0
    wlo, whi = elo, ehi  # the Illinois weights: the true values, halved at an end that stays
    back = None  # the feasible point before hi
    for _ in range(60):
        if hi - lo <= rtol * hi or -ehi <= ETOL:
            break
        if side == 0:
            x = hi * (1.0 + ehi)
        elif side == -1 and back is not None and back[1] < ehi:
            x = hi - ehi * (hi - back[0]) / (ehi - back[1])
        else:
            x = hi - whi * (hi - lo) / (whi - wlo) if math.isfinite(wlo) and wlo > 0 else 0.5 * (lo + hi)
        if not lo < x < hi:
            x = 0.5 * (lo + hi)
        ex = float(excess(np.array([x]))[0])
        if ex <= 0:
            back = (hi, ehi)
            hi, ehi, whi = x, ex, ex
            if side == -1:
                wlo *= 0.5
            side = -1
        else:
            lo, elo = x, ex if math.isfinite(ex) else math.inf
            wlo = elo
            if side == 1:
                whi *= 0.5
            side = 1
    return hi


# ------------------------------------------------------------------------------------------------ shapes


class Shapes:
    """Shape parameters per move and their :class:`ShapeBasis`, memoised: the conveyor table's shape for the
    move's groups (rounded to ``GROUP_STEP``, clipped to the table's range), and the paper's initial shape."""

    def __init__(self, table: str | None = None) -> None:
        self._table_path = table
        self._table = None
        self._shapes: dict = {}
        self._bases: dict = {}
        self.hits = self.misses = 0
        self._axes = None

    @classmethod
    def shared(cls, table: str | None = None) -> "Shapes":
        """The process's memo for ``table`` (the default: the shipped table): every line run in a process, a
        sweep's included, shares the shapes it has looked up."""
        hit = _SHARED.get(table)
        if hit is None:
            hit = _SHARED[table] = cls(table)
        return hit

    def _load(self):
        if self._table is None:
            from ..lookup.vel_table import load_vel_table

            self._table = load_vel_table(self._table_path)
        return self._table

    def basis(self, params) -> ShapeBasis:
        key = tuple(round(float(x), 12) for x in params)
        hit = self._bases.get(key)
        if hit is None:
            if len(self._bases) > 4096:
                self._bases.clear()
            hit = self._bases[key] = ShapeBasis(key)
        return hit

    def candidates(self, task, T: float) -> list[ShapeBasis]:
        """The bases to try for ``task`` run in about ``T`` seconds: the table's shape when the table covers the
        move's (rounded) groups; when it covers them only once clipped to its range, that shape and the paper's
        initial one (the search keeps the better); where the table does not apply, the paper's initial shape."""
        from ..curves.vel_problem import PAPER_INITIAL

        found = self.table_shape(task, T)
        if found is None:
            return [self.basis(PAPER_INITIAL)]
        p, clipped = found
        return [self.basis(p), self.basis(PAPER_INITIAL)] if clipped else [self.basis(p)]

    def table_shape(self, task, T: float):
        """(shape, clipped?) from the table for the move's groups rounded to ``GROUP_STEP`` and clipped to the
        table's range, or None where the table does not apply (unequal heights, a vertical move, another η)."""
        from ..curves.vel_problem import groups, task_from_groups

        if task.b <= 1e-9 or abs(task.p_to[2] - task.p_from[2]) > 1e-9:
            return None
        tab = self._load()
        g = groups(task, T)
        if abs(g["eta"] - tab.grid.eta) > 1e-9:
            return None
        q = {}
        clipped = False
        if self._axes is None:
            self._axes = [(float(a[0]), float(a[-1])) for a in tab.grid.axes()]
        for name, (lo, hi) in zip(_GROUPS, self._axes):
            x = g[name]
            if name == "h_over_b":
                x = math.exp(round(math.log(x) / (2 * GROUP_STEP)) * 2 * GROUP_STEP)
            else:
                x = round(x / GROUP_STEP) * GROUP_STEP
            c = min(max(x, lo), hi)
            clipped |= c != x
            q[name] = c
        key = tuple(q[n] for n in _GROUPS)
        if key in self._shapes:
            self.hits += 1
            p = self._shapes[key]
            return None if p is None else (p, clipped)
        self.misses += 1
        q.update(eta=tab.grid.eta, v0_vertical=0.0, v1_vertical=0.0, dz_over_b=0.0)
        try:
            p = tab.lookup(task_from_groups(q), 1.0)
        except (TableError, TaskError):
            p = None
        if len(self._shapes) > 65536:
            self._shapes.clear()
        self._shapes[key] = p
        return None if p is None else (p, clipped)


_SHARED: dict = {}
_GROUPS = ("h_over_b", "v0_along", "v0_across", "v1_along", "v1_across")


@dataclass(frozen=True)
class Solved:
    """A move with its duration: the Move (fixed shape), T [s], exact peaks (‖p′‖, ‖p″‖, ‖p‴‖ at T = 1 s; the
    jerk's only when the capacity limits it, else NaN); ``report``: the exact limit check of the move at T when
    the duration search ran it (the leg's check then uses it instead of running it again)."""

    move: Move
    T: float
    peaks: tuple[float, float, float]
    report: object = None

    @property
    def end(self) -> np.ndarray:
        return self.move.end(self.T)

    def samples(self) -> list[np.ndarray]:
        return self.move.samples(self.T)


def search_auto(moves: list[Move], capacity, a: float, b: float, guess: float | None = None) -> tuple[Move, float] | None:
    """(move, T): of the candidate shapes, the one with the smallest first T in [a, b] at which the capacity rule
    holds on the grid (searched from ``guess`` when given: :func:`first_feasible`); None when none does."""
    best = None
    for mv in moves:
        T = first_feasible(mv.excess_auto(capacity), a, b, guess=guess)
        if T is not None and (best is None or T < best[1]):
            best = (mv, T)
    return best


#: an order whose grid duration is below this share of the binding one is left out of the exact peak search
#: (the grid's peaks are within ~1e-4 of the exact ones, so it cannot bind)
BIND_SHARE = 0.99


def exact_rule(found: list[tuple[Move, float]], capacity) -> tuple[list[tuple[float, ...]], list[float]]:
    """(exact peaks, T_auto) of several moves at their durations: the peaks of the orders that may bind (velocity,
    acceleration, jerk when limited; an order whose duration on the grid is below ``BIND_SHARE`` of the largest
    is left out, its peak NaN) in one batched root search of the moves' piece polynomials
    (:func:`~pickplace_cli.curves.peaks.batch_norm_peaks`)."""
    from ..curves.bspline import piece_coefficients
    from ..curves.peaks import batch_norm_peaks

    all_orders = (1, 2, 3) if capacity.jerk else (1, 2)
    grid = np.array([_rule_times(mv.peaks_at(T), capacity) for mv, T in found])
    need = np.any(grid >= BIND_SHARE * grid.max(axis=1, keepdims=True), axis=0)
    orders = tuple(o for o, n in zip(all_orders, need) if n)
    breaks = np.stack([mv.basis.breaks for mv, _ in found])
    derivs = []
    for mv, T in found:
        d = mv.da + T * mv.db
        derivs.append([m @ d for m in mv.basis.left])
    coefs = [np.stack([piece_coefficients(None, r, dv, mv.basis.breaks)[1] for dv, (mv, _) in zip(derivs, found)])
             for r in orders]
    pk = batch_norm_peaks(breaks, coefs)
    out_peaks, out_t = [], []
    for row, g in zip(pk, grid):
        vals = dict(zip(orders, (float(x) for x in row)))
        peaks = tuple(vals.get(o, math.nan) for o in (1, 2, 3))
        exact = _rule_times([vals.get(o, 0.0) for o in all_orders], capacity)
        t = max(max(e if o in vals else g[i] for i, (o, e) in enumerate(zip(all_orders, exact))), 0.0)
        out_peaks.append(peaks)
        out_t.append(t)
    return out_peaks, out_t


def _rule_times(peaks, capacity) -> np.ndarray:
    """(T_v, T_a[, T_j]) of Eq. (26) from the peaks of ‖p′‖, ‖p″‖[, ‖p‴‖] at T = 1 s."""
    out = [peaks[0] / capacity.velocity, math.sqrt(peaks[1] / capacity.acceleration)]
    if capacity.jerk:
        out.append((peaks[2] / capacity.jerk) ** (1.0 / 3.0))
    return np.array(out)


def verify_auto(found: list[tuple[Move, float, float]], capacity) -> list[Solved] | None:
    """Each (move, T from the grid, b) checked on its exact peaks and nudged up until the rule holds exactly
    (T·T_auto/T, as the rendezvous search does), all in one batch per round; None when a nudged T passes its b."""
    cur = [(mv, T) for mv, T, _ in found]
    limits = [b for _, _, b in found]
    for _ in range(30):
        peaks, t_rule = exact_rule(cur, capacity)
        late = [i for i, ((_, T), t) in enumerate(zip(cur, t_rule)) if t > T]
        if not late:
            return [Solved(mv, T, pk) for (mv, T), pk in zip(cur, peaks)]
        for i in late:
            mv, T = cur[i]
            T = t_rule[i] * (1.0 + 1e-13)
            if T > limits[i] * (1 + 1e-12):
                return None
            cur[i] = (mv, T)
    return None  # pragma: no cover - one or two nudges (tests)


def solve_auto(moves: list[Move], capacity, a: float, b: float) -> Solved | None:
    """:func:`search_auto` then :func:`verify_auto` for one move."""
    found = search_auto(moves, capacity, a, b)
    if found is None:
        return None
    out = verify_auto([(found[0], found[1], b)], capacity)
    return None if out is None else out[0]


def solve_seconds(moves: list[Move], T: float, a: float, b: float) -> Solved | None:
    """A move of the given duration T [s] (the first candidate shape), None when T is outside [a, b]."""
    if not (a - 1e-12 <= T <= b + 1e-12):
        return None
    mv = moves[0]
    return Solved(mv, T, mv.exact_peaks(T))
