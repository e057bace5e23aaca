"""The time law's structured solver: sequential quadratic programming with a feasible inner approximation.

The problem is :mod:`pickplace_cli.timing.optimal`'s (read its docstring): minimise T = ∫dτ/√b over the law's
cubic B-spline coefficients x (b = B·x, b′ = B′·x, b″ = B″·x on a τ grid) under every limit's rows. Its structure
decides each row's treatment in the quadratic subproblem (QP) solved at every step from the current law x₀:

* joint acceleration and motor torque (affine in (b, b′)) and every speed (b·q′² ≤ L²: linear in b): exact
  linear rows;
* joint jerk and motor torque rate, b·y² ≤ 1 with y affine in (b, b′, b″) (scaled by the limit): written
  |y| ≤ b^(−1/2), whose right side is convex in b, so its tangent at b₀, b₀^(−1/2)·(1.5 − 0.5·b/b₀), lies below it
  and the two linear rows ±y ≤ tangent are an inner approximation (convex–concave procedure): every QP step holds
  these rows on the grid;
* the Cartesian capacity (‖y‖ ≤ limit, vectors) and the RMS rows: linearised at x₀. The RMS row
  2∫τ²/√b dτ + hold ≤ rated²·(2T + 2·dwell) is a convex function (τ²/√b is jointly convex in (τ, b)) less a concave
  one; its convex part's curvature, weighted by the row's multiplier, joins the QP's Hessian (a Lagrangian
  Hessian kept positive semi-definite), so the steps converge in a few iterations instead of zig-zagging along it;
* the objective: its exact second-order model (T is convex in b: Hessian Bᵀ·diag(¾·w·b^(−5/2))·B).

Each step is damped by a backtracking line search on an exact-penalty merit (T relative to its start plus μ × the
linearised rows' violation), and bounded by a trust box on the coefficients (``SQP_TRUST`` of each, and the plan's
``LAW_BOUNDS``). Only rows within ``SQP_ACTIVE`` of their limit at x₀ enter the QP; a row the step breaks joins and
the step is solved again. A later round on a finer grid (:func:`solve_law`) starts its first QP from the last
round's active set, carried to the new grid's rows. The QP is dense and small (n ≤ 80 coefficients, a few hundred to two thousand rows): the
dual active-set solver DAQP (Arnström, Bemporad & Axehill 2022, ``daqp`` on PyPI) solves it in well under a
millisecond. The converged law is then checked on a denser grid, whose broken points join the grid and the solve
goes on (:func:`solve_law`); the composed path is judged by the exact check of ``--time fit`` afterwards, as for
every law.
"""

from __future__ import annotations

import numpy as np

#: rows within this fraction of their limit (slack below it) at the current law enter the QP (a row the step breaks
#: joins and the step is solved again; the law is checked on every row afterwards). 0.15 gives the laws of 0.5 (the
#: durations to 1e-7 on 37 moves of the shipped profiles) with QPs of fewer rows: DAQP's setup grows with them
SQP_ACTIVE = 0.15
#: the trust box: each coefficient moves by at most this fraction of itself per step (3: a law far from uniform — a
#: long gantry move's — is reached in fewer steps than with 1, to the same durations)
SQP_TRUST = 3.0
#: stop when T changes by less than this (relative) and no row is broken beyond ``SQP_FEASIBLE``
SQP_TOL = 1e-6
#: … on a grid the check may still grow (every round but the last): the next round moves T by 1e-4-1e-3, so converging
#: further there is lost work; the grid the check accepts is then solved on to ``SQP_TOL`` (from its own active set)
SQP_ROUND_TOL = 1e-4
SQP_FEASIBLE = 1e-9
#: steps at most (a solve converges in 4-8 on the shipped profiles' moves)
SQP_ITERATIONS = 60
#: a row broken by more than this share of its limit on the check grid adds its points to the solve's grid (the exact
#: check of the composed law then scales the whole law by about this share at most: finer costs rounds)
SQP_CHECK_TOL = 1e-4
#: Chebyshev-spaced points joining the uniform check grid (``LAW_CHECK_GRID``)
SQP_CHECK_ENDS = 1001
#: the solve's grid without the span nodes of the path (the SLSQP's grid has them: 15 Gauss-Kronrod nodes per span)
SQP_SPANS = False
#: grid points per knot interval of the law (and at least LAW_GRID)
SQP_POINTS_PER_KNOT = 6
#: the degree of the SQP's law b(τ): quintic, so b‴ and b⁗ are continuous and the composed motion's snap has no
#: steps at the law's knots (a cubic law's snap steps there, which a reader of the sampled file — ``check`` — cannot
#: tell from the samples alone: its torque rate then read up to 0.7 % high across a knot between two samples)
SQP_DEGREE = 5
#: weight of the smoothing term SQP_SMOOTH·T₀·‖Δ³x‖² (third differences of the coefficients, relative to the
#: duration): the law that minimises T alone follows its binding rows with wiggles a few knots wide, which the motion
#: carries into its snap; a reader of the sampled motion (``check`` on positions alone, or the septic Hermite through
#: the tool's derivatives) then saw the torque rate up to 1-7 % high on 4 moves of
#: tests/property/test_plan_check_agreement.py and refused files the plan had written as within their limits. With
#: 3e-3 they pass; it costs 0.07-0.7 % of the duration on those moves and up to 2.6 % on long gantry moves (against
#: the law without it). 1e-3 left one of those files refused; smoothing only the first and last coefficients cost as
#: much; solving without it first and keeping the smoothed law only when it cost < 0.7 % doubled the time and left
#: another file refused
SQP_SMOOTH = 3e-3
#: … for a law of about this duration [s] or shorter; a longer one gets SQP_SMOOTH·(SQP_SMOOTH_T / T)²: its wiggles
#: span proportionally more samples (a few knots of T/60 each), and the reconstruction's error falls with the
#: samples per wiggle; on long gantry moves the full weight cost 1-2.6 % of the duration
SQP_SMOOTH_T = 0.2


def smoothing(t_fit: float) -> float:
    """The smoothing weight for a law whose uniform duration is ``t_fit`` [s] (``SQP_SMOOTH``, ``SQP_SMOOTH_T``)."""
    return SQP_SMOOTH * min(1.0, (SQP_SMOOTH_T / t_fit) ** 2)


def available() -> bool:
    """True when the QP solver (``daqp``) can be imported."""
    try:
        import daqp  # noqa: F401
    except ImportError:
        return False
    return True


class _Band:
    """Rows of a matrix over the law's coefficients, each nonzero on k + 1 consecutive columns only (a degree-k
    B-spline's basis at one τ): ``v`` (m, k + 1) the values, ``c`` (m,) each row's first column. The problem's rows
    (thousands: grid points × joints × limits) are held this way; only the few hundred a QP holds are made dense."""

    __slots__ = ("v", "c", "at")

    def __init__(self, v: np.ndarray, c: np.ndarray, at: np.ndarray | None = None) -> None:
        self.v, self.c = v, c
        self.at = c[:, None] + np.arange(v.shape[1]) if at is None else at  # every entry's column

    def __getitem__(self, mask) -> "_Band":
        return _Band(self.v[mask], self.c[mask], self.at[mask])

    def __len__(self) -> int:
        return len(self.c)

    def dot(self, x: np.ndarray) -> np.ndarray:
        return np.einsum("ij,ij->i", self.v, x[self.at])

    def scaled(self, s: np.ndarray) -> "_Band":
        return _Band(self.v * s[:, None], self.c, self.at)

    def dense(self, n: int) -> np.ndarray:
        out = np.zeros((len(self.c), n))
        np.put_along_axis(out, self.at, self.v, axis=1)
        return out

    @staticmethod
    def stack(*bands: "_Band") -> "_Band":
        return _Band(np.vstack([b.v for b in bands]), np.concatenate([b.c for b in bands]))


class _Rows:
    """The rows of the law's problem on one τ grid as dense matrices over the coefficients (scaled so that x ≡ 1
    is the uniform law of duration ``t_fit``), built once per grid."""

    def __init__(self, model, tau: np.ndarray, knots: np.ndarray, t_fit: float, dwell: float, capacity, data) -> None:
        from .law_rows import _basis, _limit_rows, _stack, degree

        pr = data.take(tau)
        rows = _stack(*_limit_rows(model, pr, pr.m, pr.dm, (pr.p1, pr.p2, pr.p3), capacity), len(tau))
        B0, B1, B2 = _basis(knots, tau)
        scale = 1.0 / t_fit**2
        self.B0, self.B1 = B0 * scale, B1 * scale
        B2 = B2 * scale
        # each τ's band of nonzero basis functions: the k + 1 from the knot interval holding τ
        k = degree(knots)
        n = B0.shape[1]
        first = np.clip(np.searchsorted(knots, tau, side="right") - 1 - k, 0, n - k - 1)
        at = first[:, None] + np.arange(k + 1)
        L0, L1, L2 = (np.take_along_axis(B, at, axis=1) for B in (self.B0, self.B1, B2))
        w = np.zeros(len(tau))
        dt = np.diff(tau)
        w[:-1] += dt / 2
        w[1:] += dt / 2
        self.w, self.tau, self.n = w, tau, B0.shape[1]
        self._L0, self._L1 = L0, L1
        # each band entry pair's place in an n × n matrix (for :meth:`gram`)
        self._pairs = ((at[:, :, None] * self.n + at[:, None, :]).ravel())

        def lin(g, c):  # rows c0·b + c1·b′ + c2·b″ over x, banded
            return _Band(c[:, 0, None] * L0[g] + c[:, 1, None] * L1[g] + c[:, 2, None] * L2[g], first[g])

        lg, lc = rows["lin_g"], rows["lin_c"]
        qg, qc, qp = rows["quad_g"], rows["quad_c"], rows["quad_p"]
        scalar = np.all(qc[:, :, 1:] == 0, axis=(1, 2)) & (qp == 1)
        c = qc[:, :, 0]
        speed = scalar & np.all(c[:, :3] == 0, axis=1)  # b·c3² ≤ 1: linear in b
        dyn = scalar & ~speed
        # exact linear rows A x ≤ u: accelerations and torques, then speeds
        gs = qg[speed]
        # each row's place among the grid's block-major rows (block × grid point), to carry a QP's active set to a
        # finer grid (:meth:`_Active.carried`)
        self.n_lin, self.speed, self.dyn = len(lg), speed, dyn
        self.A = _Band.stack(lin(lg, lc), _Band(c[speed, 3, None] ** 2 * L0[gs], first[gs]))
        self.u = np.concatenate([1.0 - lc[:, 3], np.ones(int(speed.sum()))])
        # b·y² ≤ 1 rows (jerk, torque rate): y = Ay x + y3, b = Bg x (the same columns as Ay's)
        gd = qg[dyn]
        self.Ay, self.y3, self.Bg = lin(gd, c[dyn]), c[dyn, 3], _Band(L0[gd], first[gd])
        # the other quadratic rows (the capacity's vectors, rows with b⁰): linearised from their values
        other = ~scalar
        self.other = {"lin_g": np.zeros(0, int), "lin_c": np.zeros((0, 4)), "quad_g": qg[other], "quad_c": qc[other],
                      "quad_p": qp[other]}
        self.Og0, self.Og1, self.Og2 = self.B0[qg[other]], self.B1[qg[other]], B2[qg[other]]
        rated = [(i, s.drive.rated_torque) for i, s in enumerate(model.specs) if s.drive and s.drive.rated_torque]
        ri = [i for i, _ in rated]
        self.r2 = np.array([r for _, r in rated], float) ** 2
        self.Ar, self.mr, self.Gr = pr.Am[:, ri], pr.m[:, ri] / 2, pr.Gm[:, ri]
        self.hold = dwell * (pr.Gm[0, ri] ** 2 + pr.Gm[-1, ri] ** 2)
        self.dwell = dwell

    def gram(self, d0: np.ndarray, d01: np.ndarray | None = None, d1: np.ndarray | None = None) -> np.ndarray:
        """B0ᵀ·diag(d0)·B0 (+ B0ᵀ·diag(d01)·B1 + its transpose + B1ᵀ·diag(d1)·B1 when given), n × n, from the
        bands: each grid point adds its (k + 1)² products (the dense products cost N·n² instead)."""
        L0, L1 = self._L0, self._L1
        v = d0[:, None, None] * L0[:, :, None] * L0[:, None, :]
        if d01 is not None:
            c = d01[:, None, None] * L0[:, :, None] * L1[:, None, :]
            v = v + c + c.transpose(0, 2, 1) + d1[:, None, None] * L1[:, :, None] * L1[:, None, :]
        return np.bincount(self._pairs, weights=v.ravel(), minlength=self.n * self.n).reshape(self.n, self.n)

    def duration(self, x: np.ndarray) -> float:
        return float(self.w @ (self.B0 @ x) ** -0.5)

    def rms(self, x: np.ndarray, weights: np.ndarray | None = None):
        """The RMS rows g_j = (2∫τ_j²/√b + hold_j) / (rated_j²·(2T + 2·dwell)) − 1 ≤ 0; with ``weights`` (one per row,
        the multipliers) also their gradients (of the numerator less rated²·(2T + 2·dwell), over the denominator at
        x: the linearisation of g_j·den_j) and Σ_j weight_j × the Hessian of row j's convex part over its denominator
        (τ²/√b per grid point, jointly convex in (τ, b): its Hessian in (b, b′) mapped to x)."""
        b, b1 = self.B0 @ x, self.B1 @ x
        ib = b**-0.5
        y = self.Ar * b[:, None] + self.mr * b1[:, None] + self.Gr
        T = self.w @ ib
        den = self.r2 * (2 * T + 2 * self.dwell)
        g = (2 * ((self.w * ib) @ y**2) + self.hold) / den - 1.0
        if weights is None:
            return g
        wi = self.w * ib
        dT = self.B0.T @ (self.w * -0.5 * ib**3)
        dCb = wi[:, None] * (2 * y * self.Ar) - (self.w * 0.5 * ib**3)[:, None] * y**2
        dCb1 = wi[:, None] * (2 * y * self.mr)
        J = (2 * (self.B0.T @ dCb + self.B1.T @ dCb1).T - 2 * self.r2[:, None] * dT[None, :]) / den[:, None]
        k = 2 * np.asarray(weights, float) / den  # per row
        if not np.any(k):
            return g, J, np.zeros((self.n, self.n))
        a, c = self.Ar, self.mr
        fyy, fyb, fbb = 2 * ib[:, None], -y * (ib**3)[:, None], 0.75 * y**2 * (ib**5)[:, None]
        hbb = ((fyy * a * a + 2 * fyb * a + fbb) @ k) * self.w
        hbc = ((fyy * a * c + fyb * c) @ k) * self.w
        hcc = ((fyy * c * c) @ k) * self.w
        return g, J, self.gram(hbb, hbc, hcc)

    def others(self, x: np.ndarray, jac: bool = False):
        """The linearised rows' values (≥ 0 when held) and, with ``jac``, their gradients over x."""
        from .law_rows import _rows

        if not len(self.other["quad_g"]):
            return (np.zeros(0), np.zeros((0, self.n))) if jac else np.zeros(0)
        g = self.other["quad_g"]
        bb, bb1, bb2 = np.zeros(len(self.tau)), np.zeros(len(self.tau)), np.zeros(len(self.tau))
        bb[g], bb1[g], bb2[g] = self.Og0 @ x, self.Og1 @ x, self.Og2 @ x
        if not jac:
            return _rows(self.other, bb, bb1, bb2, jac=False)
        v, a0, a1, a2 = _rows(self.other, bb, bb1, bb2)
        return v, a0[:, None] * self.Og0 + a1[:, None] * self.Og1 + a2[:, None] * self.Og2

    def worst(self, x: np.ndarray) -> float:
        """The largest share by which a row is broken (≤ 0 when every row holds on the grid)."""
        s_lin, s_dyn = self.slack(x)
        return float(max(np.max(-s_lin, initial=-1.0), np.max(-s_dyn, initial=-1.0), np.max(self.rms(x), initial=-1.0),
                         np.max(-self.others(x), initial=-1.0)))

    def slack(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(slack of the exact linear rows, slack of the b·y² ≤ 1 rows as 1 − b·y²): ≥ 0 when held."""
        y = self.Ay.dot(x) + self.y3
        return self.u - self.A.dot(x), 1.0 - self.Bg.dot(x) * y**2


def _qp(*args, **kw):
    """DAQP's dense QP: minimise ½·dxᵀP·dx + gᵀdx subject to lower ≤ [dx; A·dx] ≤ upper."""
    import daqp

    return daqp.solve(*args, **kw)


class _Active:
    """The rows active in the last QP (by their place among all the problem's rows), DAQP's warm start for the next
    one: the SQP's steps keep nearly the same active set, and a QP started from it takes a few active-set iterations
    instead of a hundred."""

    def __init__(self, rows: _Rows) -> None:
        self.n = rows.n
        self.box = np.zeros(rows.n, np.int8)  # +1: at its upper bound, −1: at its lower
        self.lin, self.up, self.down = np.zeros(len(rows.A), bool), np.zeros(len(rows.Ay), bool), np.zeros(len(rows.Ay), bool)
        self.tail = None  # the RMS and linearised rows (always all of them)

    def sense(self, keep_lin: np.ndarray, keep_dyn: np.ndarray, m: int) -> np.ndarray:
        """DAQP's ``sense`` of the QP over the rows ``keep_*`` (``m`` constraints, the box first): 1 active (at the
        upper bound), 3 active at the lower bound."""
        out = np.zeros(m, np.int32)
        out[: self.n][self.box > 0], out[: self.n][self.box < 0] = 1, 3
        rows = [self.lin[keep_lin], self.up[keep_dyn], self.down[keep_dyn]]
        if self.tail is not None and self.n + sum(map(len, rows)) + len(self.tail) == m:
            rows.append(self.tail)
        act = np.concatenate(rows)
        out[self.n: self.n + len(act)][act] = 1
        return out

    def carried(self, old: _Rows, new: _Rows) -> "_Active":
        """This active set (of the rows ``old``) on the rows ``new`` of a grid that holds every point of ``old``'s:
        a row active at a point stays active there (the next round's first QP then starts next to its answer instead
        of from no active row: 100-170 of DAQP's iterations on the shipped profiles' moves instead of a few)."""
        out = _Active(new)
        at = np.searchsorted(new.tau, old.tau)
        if at.size and (at.max() >= len(new.tau) or np.any(new.tau[at] != old.tau)):
            return out  # not a finer grid of the same points: no warm start
        N0, N1 = len(old.tau), len(new.tau)

        def moved(flags: np.ndarray, size: int) -> np.ndarray:  # block-major flags of old's grid → new's
            blk, g = np.divmod(np.flatnonzero(flags), N0)
            f = np.zeros(size, bool)
            f[blk * N1 + at[g]] = True
            return f

        nq0, nq1 = len(old.speed), len(new.speed)
        out.box = self.box.copy()
        lin = moved(self.lin[: old.n_lin], new.n_lin)
        speed, up, down = np.zeros(nq0, bool), np.zeros(nq0, bool), np.zeros(nq0, bool)
        speed[old.speed], up[old.dyn], down[old.dyn] = self.lin[old.n_lin:], self.up, self.down
        out.lin = np.concatenate([lin, moved(speed, nq1)[new.speed]])
        out.up, out.down = moved(up, nq1)[new.dyn], moved(down, nq1)[new.dyn]
        if self.tail is not None:  # the RMS rows (the linearised rows that follow them start inactive)
            out.tail = np.concatenate([self.tail[: len(new.r2)], np.zeros(len(new.other["quad_g"]), bool)])
        return out

    def record(self, lam: np.ndarray, keep_lin: np.ndarray, keep_dyn: np.ndarray) -> None:
        n, ml, md = self.n, int(keep_lin.sum()), int(keep_dyn.sum())
        self.box = np.sign(lam[:n]).astype(np.int8)
        for full, keep, part in ((self.lin, keep_lin, lam[n: n + ml]), (self.up, keep_dyn, lam[n + ml: n + ml + md]),
                                 (self.down, keep_dyn, lam[n + ml + md: n + ml + 2 * md])):
            full[:] = False
            full[keep] = part != 0
        self.tail = lam[n + ml + 2 * md:] != 0


def _warm_qp(P, g, A, ub, lb, warm: _Active, keep_lin, keep_dyn):
    """The step's QP (:func:`_qp`) started from the last QP's active set; solved again from none when that start
    fails. Returns (dx, DAQP's exit flag, its info, QPs solved)."""
    args = (np.ascontiguousarray(P), np.ascontiguousarray(g), np.ascontiguousarray(A), ub, lb)
    sense = warm.sense(keep_lin, keep_dyn, len(ub))
    dx, _, flag, info = _qp(*args, sense, primal_tol=1e-10)
    if flag >= 0 or not sense.any():
        return np.asarray(dx, float), flag, info, 1
    dx, _, flag, info = _qp(*args, np.zeros(len(ub), np.int32), primal_tol=1e-10)
    return np.asarray(dx, float), flag, info, 2


def solve_sqp(rows: _Rows, x: np.ndarray, lo: float, hi: float, smooth: float = 0.0,
              warm: "_Active | None" = None, tol: float = SQP_TOL) -> tuple[np.ndarray, int, str, "_Active"]:
    """The SQP iterations from ``x`` (a law that holds the rows) on ``rows``; coefficients within [lo, hi]; the first
    QP started from the active set ``warm`` (None: from none); converged when a step changes T by less than ``tol``
    (relative) and breaks no row. Returns (x, QP solves, message, the last QP's active set)."""
    n = rows.n
    T = rows.duration(x)
    # the smoothing term SQP_SMOOTH·T₀·‖Δ³x‖² (third differences of the coefficients): quadratic, so exact in the QP
    D = np.diff(np.eye(n), 3, axis=0)
    S = smooth * T * (D.T @ D)
    lam = np.zeros(len(rows.r2))
    keep_lin, keep_dyn = None, None
    warm = _Active(rows) if warm is None else warm
    solves, message = 0, "SQP: iteration limit"
    for it in range(SQP_ITERATIONS):
        b = rows.B0 @ x
        gT = rows.B0.T @ (rows.w * -0.5 * b**-1.5) + 2 * S @ x
        HT = rows.gram(rows.w * 0.75 * b**-2.5)
        g, J, Hc = rows.rms(x, lam)
        den = rows.r2 * (2 * T + 2 * rows.dwell)
        # the Lagrangian's curvature: the objective's and the RMS rows' convex parts', less their concave parts' share
        # of the objective's (kept ≥ 1e-3 of it: positive definite whatever the multipliers)
        P = max(1.0 - float(np.sum(lam * 2 * rows.r2 / den)), 1e-3) * HT + Hc + 2 * S
        ov, oJ = rows.others(x, jac=True)
        s_lin, s_dyn = rows.slack(x)
        if keep_lin is None:
            keep_lin, keep_dyn = s_lin < SQP_ACTIVE, s_dyn < SQP_ACTIVE
        keep_lin |= s_lin < SQP_ACTIVE
        keep_dyn |= s_dyn < SQP_ACTIVE
        for _ in range(4):  # a row the step breaks joins, and the step is solved again
            solved_lin, solved_dyn = keep_lin.copy(), keep_dyn.copy()  # the rows of this QP (its multipliers' order)
            Bg, Ay = rows.Bg[keep_dyn], rows.Ay[keep_dyn]
            b0 = Bg.dot(x)
            s0 = b0**-0.5
            tang = Bg.scaled(0.5 * s0 / b0)  # the same columns as Ay's
            ya, ta = Ay.dot(x), tang.dot(x)
            A = np.vstack([rows.A[keep_lin].dense(n), _Band(Ay.v + tang.v, Ay.c, Ay.at).dense(n),
                           _Band(tang.v - Ay.v, Ay.c, Ay.at).dense(n), J, -oJ])
            rhs = np.concatenate([s_lin[keep_lin], 1.5 * s0 - rows.y3[keep_dyn] - ya - ta,
                                  1.5 * s0 + rows.y3[keep_dyn] + ya - ta, -g, ov])
            box_hi = np.minimum(hi, x * (1 + SQP_TRUST)) - x
            box_lo = np.maximum(lo, x / (1 + SQP_TRUST)) - x
            ub = np.concatenate([box_hi, rhs])
            lb = np.concatenate([box_lo, np.full(len(rhs), -1e30)])
            dx, flag, info, tries = _warm_qp(P, gT, A, ub, lb, warm, keep_lin, keep_dyn)
            solves += tries
            if flag < 0:  # the QP failed (infeasible, cycling): keep the last law
                return x, solves, f"SQP: the QP solver stopped (DAQP exit flag {flag}) after {it} steps", warm
            warm.record(np.asarray(info["lam"], float), keep_lin, keep_dyn)
            s_lin_n, s_dyn_n = rows.slack(x + dx)
            new_lin = ~keep_lin & (s_lin_n < 0)
            new_dyn = ~keep_dyn & (s_dyn_n < 0)
            if not (new_lin.any() or new_dyn.any()):
                break
            keep_lin |= new_lin | (~keep_lin & (s_lin_n < SQP_ACTIVE))
            keep_dyn |= new_dyn | (~keep_dyn & (s_dyn_n < SQP_ACTIVE))
        lam_all = np.asarray(info["lam"], float)
        # the last QP's rows: after a fourth solve whose step broke more rows, those joined keep_* unsolved
        m_lin, m_dyn = int(solved_lin.sum()), int(solved_dyn.sum())
        lam = np.maximum(lam_all[n + m_lin + 2 * m_dyn: n + m_lin + 2 * m_dyn + len(g)], 0.0)
        mu = 10.0 * max(1.0, float(np.max(lam_all[n:], initial=0.0)))

        # the rows the QP held (every other row has ≥ SQP_ACTIVE of slack at x and holds at x + dx, and the
        # linear and inner-approximated rows' sets are convex: it holds on the whole step)
        Ak, uk, Ayk, y3k, Bgk = rows.A[keep_lin], rows.u[keep_lin], rows.Ay[keep_dyn], rows.y3[keep_dyn], rows.Bg[keep_dyn]

        def violation(xx, rms=None, oth=None):
            sl, sd = uk - Ak.dot(xx), 1.0 - Bgk.dot(xx) * (Ayk.dot(xx) + y3k) ** 2
            rms = rows.rms(xx) if rms is None else rms
            oth = rows.others(xx) if oth is None else oth
            return (np.sum(np.maximum(rms, 0.0)) + np.sum(np.maximum(-oth, 0.0)) + np.sum(np.maximum(-sl, 0.0))
                    + np.sum(np.maximum(-sd, 0.0)))

        def merit(xx):
            return (rows.duration(xx) + xx @ S @ xx) / T + mu * violation(xx)

        m0 = merit(x)
        pred = float(gT @ dx) / T - mu * violation(x, g, ov)
        alpha = 1.0
        for _ in range(30):
            xn = x + alpha * dx
            if merit(xn) <= m0 + 1e-4 * alpha * min(pred, 0.0):
                break
            alpha *= 0.5
        else:
            return x, solves, f"SQP: no descent after {it} steps (line search)", warm
        Tn = rows.duration(xn)
        change = abs(T - Tn) / T
        x, T = xn, Tn
        if change < tol and (violation(x) <= SQP_FEASIBLE or alpha < 1e-3):
            return x, solves, f"SQP: converged in {it + 1} steps", warm
    return x, solves, message, warm


def solve_grid(path, points: int, knots: np.ndarray) -> np.ndarray:
    """The solve's first grid: ``points`` uniform points, the path's knots and jump sides, and the law's own knots (a
    row's derivative may kink there: often its peak)."""
    from .law_rows import _law_grid

    return np.union1d(_law_grid(path, points, spans=SQP_SPANS), np.unique(knots))


def check_grid(path) -> np.ndarray:
    """The grid on which a solved law is checked: ``LAW_CHECK_GRID`` uniform points and ``SQP_CHECK_ENDS``
    Chebyshev-spaced ones, denser at the ends, where the path is slow, b small and the rows vary fastest in τ (peaks
    between 1001 uniform points there broke a row by 0.2 % on the Adept cycle), with the path's knots and jump sides."""
    from .law_rows import LAW_CHECK_GRID, _law_grid

    return np.union1d(_law_grid(path, LAW_CHECK_GRID), _law_grid(path, SQP_CHECK_ENDS, spans=False, clustered=True))


def solve_law(model, dwell: float, t_fit: float, knots: np.ndarray, capacity, data, x: np.ndarray, lo: float,
              hi: float, points: int, smooth: float = 0.0, grid: np.ndarray | None = None,
              max_rounds: int | None = None):
    """The law on ``knots`` from ``x`` (relative coefficients): :func:`solve_sqp` (with the smoothing weight
    ``smooth``) on the grid ``grid``, or of ``points`` uniform points (:func:`solve_grid`), then on that grid with
    the points of the check grid (:func:`check_grid`) where a row is broken beyond ``SQP_CHECK_TOL`` and the local
    peaks of those rows (``max_rounds`` more rounds at most, default ``LAW_CHECK_ROUNDS``). Returns (x, the duration
    estimate [s], QP solves, message, the largest broken share of a row on the last grid — ≤ 0 when every row holds
    there —, the last grid)."""
    from .law_rows import LAW_CHECK_ROUNDS, _Problem

    path = model.path
    tau = solve_grid(path, points, knots) if grid is None else grid
    check = _Problem(model, check_grid(path), knots, t_fit, dwell, capacity, data)
    total, rows, warm, grown = 0, None, None, True
    last_round = (LAW_CHECK_ROUNDS if max_rounds is None else max_rounds) + 1
    rounds, tol = 1, SQP_ROUND_TOL
    while True:
        if grown:  # the grid's rows, and the last QP's active set carried to them
            last, rows = rows, _Rows(model, tau, knots, t_fit, dwell, capacity, data)
            warm = None if last is None else warm.carried(last, rows)
        x, solves, message, warm = solve_sqp(rows, x, lo, hi, smooth, warm, SQP_TOL if rounds == last_round else tol)
        total += solves
        v = check.values(x)[: check.n_rows]
        if not (v < -SQP_CHECK_TOL).any():
            if tol == SQP_TOL or rounds == last_round:
                break
            tol, grown = SQP_TOL, False  # this grid holds: the law converged on it to the final tolerance
            continue
        if rounds == last_round:
            break
        # every local peak of a broken row on the check grid joins, with its neighbours: the peaks the next solve
        # moves towards are then on the grid too (adding only the broken points took a round for each neighbour)
        V = v.reshape(-1, len(check.tau))
        mid = V[:, 1:-1]
        peak = (mid <= V[:, :-2]) & (mid <= V[:, 2:]) & (mid < -SQP_CHECK_TOL)
        at = np.flatnonzero(peak.any(axis=0)) + 1
        near = np.clip((at[:, None] + np.arange(-1, 2)).ravel(), 0, len(check.tau) - 1)
        tau = np.union1d(tau, np.concatenate([check.tau[near], np.unique(check.row_tau[v < -SQP_CHECK_TOL])]))
        rounds, grown = rounds + 1, True
    return (x, rows.duration(x), total, f"{message} ({rounds} grid round(s), {len(tau)} points)", rows.worst(x),
            rows.tau)
