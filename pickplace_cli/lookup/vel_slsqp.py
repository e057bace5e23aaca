"""SLSQP in epigraph form for the stages of Eq. (37) [Yang2022, Sec. 2.3], many runs advanced in lockstep.

A stage (:class:`_Stage`) is a minimax over the parameters: minimise t subject to m_k(p) ≤ t, m_k the exact maximum
of ‖a‖² (‖j‖²) on a segment of a knot span (:func:`_segment_maxima`); :class:`_Space` maps the free variables
to the seven parameters with the ordering constraints of Eq. (36). :func:`_run_slsqp` / :class:`_Lockstep` step
scipy's SLSQP routine for several runs at once with one batched evaluation per round (:func:`_eval_stages`).
Used by :mod:`pickplace_cli.lookup.vel_solver`.
"""

from __future__ import annotations

import math

import numpy as np

from ..curves.peaks import _anti_diagonal_sum
from ..curves.vel_problem import PAPER_INITIAL, VelSettings, _Evaluator


class _Space:
    """Free variables x ↔ full parameters p; bounds and the linear ordering constraints of Eq. (36)."""

    def __init__(self, free_lambda: tuple[bool, bool, bool], margin: float) -> None:
        self.free = np.array([True] * 4 + list(free_lambda))
        self.fixed = np.array(PAPER_INITIAL)
        m = margin
        lo = np.array([m, 2 * m, 0.5 + m, 0.5 + 2 * m, 0.0, 0.0, 0.0])
        hi = np.array([0.5 - 2 * m, 0.5 - m, 1 - 2 * m, 1 - m, 1.0, 1.0, 1.0])
        self.lo, self.hi = lo[self.free], hi[self.free]
        self.m = m
        self.n = int(self.free.sum())

    def full(self, x: np.ndarray) -> np.ndarray:
        x = np.atleast_2d(x)
        p = np.broadcast_to(self.fixed, (x.shape[0], 7)).copy()
        p[:, self.free] = x
        return p

    def order_gaps(self, x: np.ndarray) -> np.ndarray:
        """τ7 − τ6 − m and τ10 − τ9 − m (≥ 0 when feasible); the rest are bounds."""
        return np.array([x[1] - x[0] - self.m, x[3] - x[2] - self.m])

    def order_jac(self) -> np.ndarray:
        j = np.zeros((2, self.n))
        j[0, 0], j[0, 1], j[1, 2], j[1, 3] = -1.0, 1.0, -1.0, 1.0
        return j

    def from_unit(self, u: np.ndarray) -> np.ndarray:
        """Map points of the unit cube onto the feasible set (knots in order, gaps ≥ margin)."""
        m = self.m
        x = np.empty_like(u)
        t7 = 2 * m + u[:, 1] * (0.5 - 3 * m)
        t6 = m + u[:, 0] * (t7 - 2 * m)
        t9 = 0.5 + m + u[:, 2] * (0.5 - 3 * m)
        t10 = t9 + m + u[:, 3] * (1 - m - t9 - m)
        x[:, 0], x[:, 1], x[:, 2], x[:, 3] = t6, t7, t9, t10
        x[:, 4:] = u[:, 4:]
        return x

    def clip(self, x: np.ndarray) -> np.ndarray:
        x = np.clip(x, self.lo, self.hi)
        x[1] = max(x[1], x[0] + self.m)
        x[3] = max(x[3], x[2] + self.m)
        return np.clip(x, self.lo, self.hi)


def _exact_segment_maxima(prep: tuple, q: int | tuple[int, ...], sub: int) -> np.ndarray:
    """u (6·sub·len(q),) of the maximum of ‖a‖² (q = 0) or ‖j‖² (q = 1) — or of each in the tuple ``q``, in
    that order — on each of the ``sub`` equal segments of every knot span, for the first parameter vector of
    ``prep`` (:func:`_segment_maxima` for several)."""
    return _segment_maxima(prep[0][:1], prep[1][:1], q, sub)[0]


def _poly_maps(k: int) -> tuple[np.ndarray, np.ndarray]:
    """(k², 7), (k², 6): from the products c_i·c_j of a degree-(k−1) vector polynomial's coefficients to
    the coefficients (lowest power first) of its squared norm, padded to degree 6, and of that norm's
    derivative, padded to degree 5 — for k = 3 (jerk) the cubic derivative times (u − 10)², which adds two
    roots far outside [0, 1], so that both quantities share one batch of 5 × 5 companion matrices."""
    if k not in _POLY_MAPS:
        sq = np.zeros((k * k, 7))
        sq[:, : 2 * k - 1] = _anti_diagonal_sum(k)
        deriv = sq[:, 1:] * np.arange(1, 7)  # degree 2k − 3
        if k == 3:
            cubic = deriv[:, :4].copy()
            deriv = np.zeros((k * k, 6))
            deriv[:, :4] += 100.0 * cubic
            deriv[:, 1:5] -= 20.0 * cubic
            deriv[:, 2:] += cubic
        _POLY_MAPS[k] = (sq, deriv)
    return _POLY_MAPS[k]


_POLY_MAPS: dict[int, tuple[np.ndarray, np.ndarray]] = {}


def _segment_maxima(width: np.ndarray, d: np.ndarray, q: int | tuple[int, ...], sub: int,
                    rows: tuple[np.ndarray, ...] | None = None) -> np.ndarray | list[np.ndarray]:
    """u (R, 6·sub·len(q)) of the maxima of ‖a‖² (q = 0) or ‖j‖² (q = 1) — or of each in the tuple ``q``,
    in that order — on each of the ``sub`` equal segments of every knot span, for R prepared parameter
    vectors (``width`` (R, 6), ``d`` (R, 6, 4, 3) from :meth:`_Evaluator.prepare`): exact, from the real
    roots of the derivative of the span's polynomial ‖·‖² (companion-matrix eigenvalues, one batched call
    for all vectors and quantities) and the segment ends. With ``rows`` (one index array per quantity in
    ``q``): only those vectors for each quantity, returned as a list of (len(rows[i]), 6·sub) arrays."""
    qs = (q,) if isinstance(q, (int, np.integer)) else tuple(q)
    sel = rows if rows is not None else tuple(np.arange(width.shape[0]) for _ in qs)
    sqs, derivs = [], []
    for qq, idx in zip(qs, sel):
        R = len(idx)
        w = width[idx]  # (R, 6)
        wk = np.empty((R, 6, 4, 1))  # w^k / k!
        wk[:, :, 0, 0] = 1.0
        wk[:, :, 1, 0] = w
        wk[:, :, 2, 0] = w * w / 2
        wk[:, :, 3, 0] = wk[:, :, 2, 0] * w / 3
        if qq == 0:  # a(u) = D0 + D1 (wu) + D2 (wu)²/2 + D3 (wu)³/6, coefficients in powers of u (lowest first)
            c = d[idx] * wk
        else:  # j(u) = D1 + D2 (wu) + D3 (wu)²/2
            c = d[idx][:, :, 1:] * wk[:, :, :3]
        k = c.shape[2]
        prod = (c @ c.transpose(0, 1, 3, 2)).reshape(R * 6, k * k)
        to_sq, to_deriv = _poly_maps(k)
        sqs.append(prod @ to_sq)  # ‖·‖² (degree 2k − 2, padded to 6), lowest power first
        derivs.append(prod @ to_deriv)  # its derivative (padded to degree 5)
    sq, deriv = (np.concatenate(sqs), np.concatenate(derivs)) if len(sqs) > 1 else (sqs[0], derivs[0])
    # rows: quantity, vector, span
    m = sq.shape[0]
    n = 5
    lead = deriv[:, -1]
    scale = np.max(np.abs(deriv), axis=1) + 1e-300
    lead = np.where(np.abs(lead) > 1e-13 * scale, lead, 1e-13 * scale)  # a dropped degree: roots go far away
    comp = np.zeros((m, n, n))
    comp[:, 0, :] = -deriv[:, -2::-1] / lead[:, None]
    comp[:, _SUBDIAG[0], _SUBDIAG[1]] = 1.0
    roots = np.linalg.eigvals(comp)
    ends = np.arange(sub + 1) / sub
    cand = np.empty((m, n + sub + 1))  # the real roots (non-real → −1, outside) and the segment ends
    cand[:, :n] = np.where(np.abs(roots.imag) <= 1e-9 * (1.0 + np.abs(roots.real)), roots.real, -1.0)
    cand[:, n:] = ends
    powers = np.empty((m, n + sub + 1, 7))
    powers[:, :, 0] = 1.0
    np.cumprod(np.broadcast_to(cand[:, :, None], (m, n + sub + 1, 6)), axis=2, out=powers[:, :, 1:])
    val = np.einsum("scp,sp->sc", powers, sq)
    inside = (cand[:, None, :] >= ends[:-1, None] - 1e-15) & (cand[:, None, :] <= ends[1:, None] + 1e-15)
    best = np.argmax(np.where(inside, val[:, None, :], -np.inf), axis=2)  # (m, sub)
    u = np.clip(cand[np.arange(m)[:, None], best], ends[:-1], ends[1:]).reshape(m // 6, 6 * sub)  # rows: quantity, vector
    parts, at = [], 0
    for idx in sel:
        parts.append(u[at : at + len(idx)])
        at += len(idx)
    if rows is not None:
        return parts
    return np.concatenate(parts, axis=1)


_SUBDIAG = (np.arange(1, 5), np.arange(4))  # the companion matrix's subdiagonal


class _Stage:
    """One stage of Eq. (37) by SLSQP in epigraph form.

    ``kind`` 'a' / 'j': minimise t subject to m_k(p) ≤ t, where m_k is the maximum of ‖a‖² (‖j‖²) over
    segment k — each knot span cut into ``SUB`` equal segments that move with the knots; 'F': maximise
    a_min/√ta + j_min/√tj subject to both sets. Each m_k is exact (:func:`_segment_maxima`); its
    gradient is that of ‖a(τ*)‖² with τ* held at the same fraction of the span (envelope theorem: the
    motion of the maximiser does not change the maximum to first order), by central differences evaluated
    as one batch. Segments short enough to hold a single local maximum keep every m_k smooth (a whole span
    can hold two humps whose swap is a kink that stalls SLSQP's line search; an m_k whose maximiser is
    off by even 1e-4 of the span has a gradient wrong enough to do the same). Final peaks are exact.
    The lower bounds ta ≥ a_min², tj ≥ j_min² (valid: t ≥ max ≥ min) keep F-steps from t → 0.
    Several SLSQP runs (of any stages of one problem) advance together, their evaluations batched
    (:func:`_run_slsqp`).
    """

    SUB = 3

    def __init__(self, ev: _Evaluator, space: _Space, kind: str, a_norm: float, j_norm: float, settings: VelSettings):
        self.ev, self.space, self.kind = ev, space, kind
        self.norm = np.array([a_norm, j_norm])  # scale of ‖a‖², ‖j‖² (values / norm ~ 1)
        self.s = settings
        self.h = 1e-6
        n = space.n
        # central differences in the four knots only (the path is affine in λ: those derivatives are exact)
        self._steps = np.vstack([np.zeros(n), self.h * np.eye(n)[:4], -self.h * np.eye(n)[:4]])
        self.uses = (0,) if kind == "a" else (1,) if kind == "j" else (0, 1)
        self._memo: dict[bytes, tuple[list, list]] = {}

    def _eval(self, x: np.ndarray) -> tuple[list, list]:
        """Per quantity used: the 6·SUB segment maxima at x and their Jacobians (memoised on x)."""
        return _eval_stages([(self, x)])[0]

    def objective(self, x: np.ndarray, a_min: float = 1.0, j_min: float = 1.0) -> float:
        """The stage's objective at x from its own (segment-maximum) peaks: max ‖a‖² or ‖j‖², or −F."""
        vals, _ = self._eval(x)
        if self.kind == "F":
            return -(a_min / math.sqrt(vals[0].max() * self.norm[0]) + j_min / math.sqrt(vals[1].max() * self.norm[1]))
        return float(vals[0].max())

    def run(self, x0: np.ndarray, a_min: float = 1.0, j_min: float = 1.0, ftol: float | None = None,
            maxiter: int | None = None, max_rounds: int | None = None) -> _Run:
        """One SLSQP run from x0 (to pass to :func:`_run_slsqp` or :class:`_Lockstep`)."""
        r = _Run(self, np.asarray(x0, float), a_min, j_min, ftol or self.s.ftol, maxiter or self.s.maxiter)
        if max_rounds is not None:
            r.max_rounds = max_rounds
        return r


def _eval_stages(requests: list[tuple[_Stage, np.ndarray]]) -> list[tuple[list, list]]:
    """(values, Jacobians) of each (stage, x) — see :meth:`_Stage._eval` — computed in one batch for
    those not memoised (all stages share one evaluator and space): the 2n + 1 central-difference vectors
    of every x in one :meth:`_Evaluator.prepare`, the segment maxima of ‖a‖² and ‖j‖² at every x in one
    :func:`_segment_maxima` call. The cost is per numpy call far more than per vector."""
    for stage, _ in requests:
        if len(stage._memo) > 2048:
            stage._memo.clear()
    todo: dict[tuple[int, bytes], tuple[_Stage, np.ndarray]] = {}
    for stage, x in requests:
        key = x.tobytes()
        if key not in stage._memo:
            todo[(id(stage), key)] = (stage, x)
    if todo:
        stage0 = requests[0][0]
        ev, space, steps, sub = stage0.ev, stage0.space, stage0._steps, _Stage.SUB
        n, S, m = space.n, steps.shape[0], 6 * sub
        xs = np.array([x for _, x in todo.values()])
        R = xs.shape[0]
        width, d, dlam = ev.prepare(space.full((xs[:, None, :] + steps[None]).reshape(-1, n)), np.arange(0, R * S, S))
        stages = [stage for stage, _ in todo.values()]
        rows = tuple(np.array([r for r, st in enumerate(stages) if q in st.uses], int) for q in (0, 1))
        us = _segment_maxima(width[::S], d[::S], (0, 1), sub, rows)  # per quantity (len(rows[q]), m)
        lam = space.free[4:]
        width, d = width.reshape(R, S, 6), d.reshape(R, S, 6, 4, 3)
        h2 = 2 * stage0.h
        out: dict[tuple[int, int], tuple[np.ndarray, np.ndarray]] = {}
        for q in (0, 1):
            rq = rows[q]
            if not len(rq):
                continue
            c = d[rq][:, :, :, None]  # (·, S, 6, 1, 4, 3)
            cl = dlam[rq][:, :, :, None]  # (·, 3, 6, 1, 4, 3)
            h = (us[q].reshape(-1, 1, 6, sub) * width[rq][..., None])[..., None]  # (·, S, 6, sub, 1) from the span start
            hl = h[:, :1]
            if q == 0:  # a = D0 + D1 h + D2 h²/2 + D3 h³/6
                val = c[..., 0, :] + h * (c[..., 1, :] + h * (c[..., 2, :] / 2 + h * c[..., 3, :] / 6))
                dv = cl[..., 0, :] + hl * (cl[..., 1, :] + hl * (cl[..., 2, :] / 2 + hl * cl[..., 3, :] / 6))
            else:  # j = D1 + D2 h + D3 h²/2
                val = c[..., 1, :] + h * (c[..., 2, :] + h * c[..., 3, :] / 2)
                dv = cl[..., 1, :] + hl * (cl[..., 2, :] + hl * cl[..., 3, :] / 2)
            sqq = np.einsum("rsuvd,rsuvd->rsuv", val, val).reshape(-1, S, m)
            gq = 2.0 * np.einsum("rsuvd,riuvd->riuv", val[:, :1], dv).reshape(-1, 3, m)[:, lam]  # ∂‖·‖²/∂λ
            norm = np.array([stages[r].norm[q] for r in rq])[:, None, None]
            jac = np.concatenate([(sqq[:, 1:5] - sqq[:, 5:9]) / h2, gq], axis=1).transpose(0, 2, 1) / norm
            vals = sqq[:, 0] / norm[:, 0]
            for i, r in enumerate(rq):
                out[(q, r)] = (vals[i], jac[i])
        for r, ((_, key), stage) in enumerate(zip(todo, stages)):
            stage._memo[key] = ([out[(q, r)][0] for q in stage.uses], [out[(q, r)][1] for q in stage.uses])
    return [stage._memo[x.tobytes()] for stage, x in requests]


class _Run:
    """One SLSQP run of a stage in epigraph form: y = (x, t…), minimise t (or −F(t)) subject to
    t_q ≥ m_k(x) for every segment k of each quantity q used, and the ordering constraints of Eq. (36)."""

    def __init__(self, stage: _Stage, x0: np.ndarray, a_min: float, j_min: float, ftol: float, maxiter: int):
        self.stage, self.x0, self.ftol, self.maxiter = stage, x0, ftol, maxiter
        self.max_rounds = 10**9  # evaluation rounds before the run is cut off (solve_seeded: settings.max_rounds)
        self.a_min, self.j_min = a_min, j_min
        self.n, self.k = stage.space.n, len(stage.uses)
        norm = stage.norm
        self.cf = (a_min / math.sqrt(norm[0]), j_min / math.sqrt(norm[1]))
        # t ≥ max‖·‖² ≥ (its minimum)²: a valid bound that keeps SLSQP's F-steps from t → 0
        self.floor = [(a_min**2 / norm[0]), (j_min**2 / norm[1])]
        sp = stage.space
        if stage.kind == "F":
            tlo = [self.floor[q] * (1 - 1e-6) for q in stage.uses]
        else:
            tlo = [1e-12]
        self.lo = np.concatenate([sp.lo, tlo])
        self.hi = np.concatenate([sp.hi, [np.inf] * self.k])
        # the constant part of the constraint normals: the t columns and the ordering rows
        m = 6 * _Stage.SUB
        self.normals = np.zeros((self.k * m + 2, self.n + self.k), order="F")
        for i in range(self.k):
            self.normals[i * m : (i + 1) * m, self.n + i] = 1.0
        self.normals[-2:, : self.n] = sp.order_jac()

    def y0(self, vals: list) -> np.ndarray:
        y0 = np.concatenate([self.x0, [v.max() * (1 + 1e-9) for v in vals]])
        if self.stage.kind == "F":
            y0[self.n:] = np.maximum(y0[self.n:], self.floor)
        return y0

    def fun(self, y: np.ndarray) -> float:
        n = self.n
        if self.stage.kind == "F":
            return -(self.cf[0] / math.sqrt(y[n]) + self.cf[1] / math.sqrt(y[n + 1]))
        return float(y[n])

    def grad(self, y: np.ndarray) -> np.ndarray:
        n = self.n
        g = np.zeros(n + self.k)
        if self.stage.kind == "F":
            g[n] = 0.5 * self.cf[0] * y[n] ** -1.5
            g[n + 1] = 0.5 * self.cf[1] * y[n + 1] ** -1.5
        else:
            g[n] = 1.0
        return g

    def cons(self, y: np.ndarray, vals: list) -> np.ndarray:
        n = self.n
        return np.concatenate([y[n + i] - v for i, v in enumerate(vals)] + [self.stage.space.order_gaps(y[:n])])

    def fill_cons(self, out: np.ndarray, y: np.ndarray, vals: list) -> None:
        """:meth:`cons` written into ``out``."""
        n, m, gap = self.n, 6 * _Stage.SUB, self.stage.space.m
        for i, v in enumerate(vals):
            np.subtract(y[n + i], v, out=out[i * m : (i + 1) * m])
        out[-2] = y[1] - y[0] - gap
        out[-1] = y[3] - y[2] - gap

    def fill_normals(self, out: np.ndarray, jacs: list) -> None:
        """:meth:`cjac` written into ``out``, whose constant part (:attr:`normals`) is already there."""
        m = 6 * _Stage.SUB
        for i, d in enumerate(jacs):
            np.negative(d, out=out[i * m : (i + 1) * m, : self.n])

    def cjac(self, jacs: list) -> np.ndarray:
        out = self.normals.copy(order="F")
        m = 6 * _Stage.SUB
        for i, d in enumerate(jacs):
            out[i * m : (i + 1) * m, : self.n] = -d
        return out

    def feasible(self, x: np.ndarray) -> bool:
        """x (free variables) within the bounds and the ordering of Eq. (36), to 1e-12."""
        sp = self.stage.space
        return bool((x - sp.lo).min() >= -1e-12 and (sp.hi - x).min() >= -1e-12 and sp.order_gaps(x).min() >= -1e-12)


def _run_slsqp(runs: list[_Run]) -> list[np.ndarray]:
    """The results x (free variables, clipped to the feasible set) of several SLSQP runs of stages of one
    problem, advanced together (:class:`_Lockstep`)."""
    lock = _Lockstep()
    handles = [lock.add(r) for r in runs]
    while lock.active:
        lock.step()
    return [h.result() for h in handles]


class _Lockstep:
    """SLSQP runs of stages of one problem advanced together: each :meth:`step` evaluates the points all
    active runs ask for in one batch (:func:`_eval_stages`), so k runs cost about as many numpy calls as
    the longest of them alone. Runs may be added (and dropped) between steps.

    Each run is exactly scipy's SLSQP (``minimize(method="SLSQP")``: the same reverse-communication
    routine, bounds and tolerances, driven as ``scipy.optimize._minimize_slsqp`` drives it), cut off after
    ``_Run.max_rounds`` evaluation rounds (then its best feasible point counts). That routine is private
    scipy API: it is used only on the scipy versions this driver was checked against
    (``_SLSQP_VERSIONS``; a test compares it with ``minimize``); on any other version, or where it is
    missing, each run goes through ``minimize`` when added — the same results, slower."""

    def __init__(self) -> None:
        self.routine = _slsqp_routine()
        self.active: list[_LockstepSLSQP] = []

    def add(self, run: _Run) -> _LockstepSLSQP:
        st = _LockstepSLSQP(run, self.routine)
        if self.routine is None:
            st.finish_serial()
        else:
            self.active.append(st)
        return st

    def drop(self, states: list[_LockstepSLSQP]) -> None:
        self.active = [st for st in self.active if st not in states]

    def step(self) -> None:
        _eval_stages([(st.run.stage, st.want) for st in self.active])
        still = []
        for st in self.active:
            st.rounds += 1
            if st.advance() and st.rounds < st.run.max_rounds:
                still.append(st)
            else:
                st.done = True
        self.active = still


#: scipy (major, minor) versions whose private SLSQP routine the lockstep driver was checked against
#: (scipy 1.16 rewrote SLSQP; 1.17.1 tested): [first, last)
_SLSQP_VERSIONS = ((1, 16), (1, 18))


def _slsqp_routine():
    """scipy's private SLSQP routine on a checked scipy version, else None (then the public ``minimize``)."""
    import scipy

    try:
        version = tuple(int(x) for x in scipy.__version__.split(".")[:2])
    except ValueError:
        return None
    if not (_SLSQP_VERSIONS[0] <= version < _SLSQP_VERSIONS[1]):
        return None
    try:
        from scipy.optimize._slsqplib import slsqp
    except ImportError:
        return None
    return slsqp


def _run_one(r: _Run, y0: np.ndarray) -> np.ndarray:
    from scipy.optimize import minimize

    n = r.n
    res = minimize(
        r.fun, y0, jac=r.grad, method="SLSQP", bounds=list(zip(r.lo, [None if not math.isfinite(h) else h for h in r.hi])),
        constraints=[{"type": "ineq", "fun": lambda y: r.cons(y, r.stage._eval(y[:n].copy())[0]),
                      "jac": lambda y: r.cjac(r.stage._eval(y[:n].copy())[1])}],
        options={"ftol": r.ftol, "maxiter": r.maxiter},
    )
    return r.stage.space.clip(np.asarray(res.x[:n], float))


class _LockstepSLSQP:
    """scipy's SLSQP driver loop (``scipy.optimize._slsqp_py._minimize_slsqp``) for one run, stepped:
    :meth:`advance` calls the routine until it needs constraint values or normals at a point not yet
    evaluated (``want``), or stops. Same set-up as scipy's: x0 clipped to the bounds, infinite bounds as
    NaN, the same work-space sizes, acc = ftol, the objective evaluated at the bounds-clipped point."""

    def __init__(self, run: _Run, routine) -> None:
        self.run, self.routine = run, routine
        self.rounds, self.done = 0, False
        self.need = "start"  # first the values at x0 (the starting t), then f, g, constraints and normals
        self.want = run.x0
        self.seen: list[np.ndarray] = []  # the points evaluated for values (for a run cut off)
        self._result: np.ndarray | None = None

    def finish_serial(self) -> None:
        """Run to the end through ``scipy.optimize.minimize`` (no lockstep routine available)."""
        vals = self.run.stage._eval(self.run.x0)[0]
        self._result = _run_one(self.run, self.run.y0(vals))
        self.done = True

    def _setup(self, y0: np.ndarray) -> None:
        run = self.run
        n = y0.size
        self.x = np.clip(y0, run.lo, run.hi).astype(float)
        self.xl = np.where(np.isfinite(run.lo), run.lo, np.nan)
        self.xu = np.where(np.isfinite(run.hi), run.hi, np.nan)
        m = run.k * 6 * _Stage.SUB + 2
        self.state = {"acc": run.ftol, "alpha": 0.0, "f0": 0.0, "gs": 0.0, "h1": 0.0, "h2": 0.0, "h3": 0.0,
                      "h4": 0.0, "t": 0.0, "t0": 0.0, "tol": 10.0 * run.ftol, "exact": 0, "inconsistent": 0,
                      "reset": 0, "iter": 0, "itermax": int(run.maxiter), "line": 0, "m": m, "meq": 0,
                      "mode": 0, "n": n}
        self.indices = np.zeros(max(m + 2 * n + 2, 1), dtype=np.int32)
        size = n * (n + 1) // 2 + 3 * m * n - (m + 5 * n + 7) * 0 + 9 * m + 8 * n * n + 35 * n + 28
        self.buffer = np.zeros(max(size, 1))
        self.mult = np.zeros(max(1, m + 2 * n + 2))
        self.C = run.normals.copy(order="F")  # the constant part; fill_normals writes the rest
        self.d = np.zeros(m)
        self.need = "both"  # the initial call needs f, g, constraints and normals
        self.want = self._xpart()

    def result(self) -> np.ndarray:
        """x at the end (clipped to the feasible set); when the run was cut off (``max_rounds``), the best
        feasible point it evaluated (objective from the exact segment maxima)."""
        r = self.run
        if self._result is not None:
            return self._result
        if self.need == "start":
            return r.stage.space.clip(r.x0.copy())
        if abs(self.state["mode"]) == 1:
            best = None
            for x in self.seen:
                if r.feasible(x):
                    vals = r.stage._eval(x)[0]
                    if r.stage.kind == "F":
                        f = -(r.cf[0] / math.sqrt(vals[0].max()) + r.cf[1] / math.sqrt(vals[1].max()))
                    else:
                        f = float(vals[0].max())
                    if best is None or f < best[0]:
                        best = (f, x)
            if best is not None:
                return best[1]
        return r.stage.space.clip(np.asarray(self.x[: r.n], float))

    def _xpart(self) -> np.ndarray:
        return self.x[: self.run.n].copy()

    def advance(self) -> bool:
        """Step until an evaluation not yet memoised is needed (True) or the run has stopped (False)."""
        r, stage = self.run, self.run.stage
        while True:
            key = self.want.tobytes()
            if key not in stage._memo:
                return True
            vals, jacs = stage._memo[key]
            if self.need == "start":
                self._setup(r.y0(vals))
                continue
            if self.need in ("both", "f"):
                self.seen.append(self.want)
                xf = np.clip(self.x, r.lo, r.hi) if self.need == "both" else self.x
                self.fx = r.fun(xf)
                r.fill_cons(self.d, self.x, vals)
            if self.need in ("both", "g"):
                xg = np.clip(self.x, r.lo, r.hi) if self.need == "both" else self.x
                self.g = r.grad(xg)
                r.fill_normals(self.C, jacs)
            self.routine(self.state, self.fx, self.g, self.C, self.d, self.x, self.mult, self.xl, self.xu,
                         self.buffer, self.indices)
            mode = self.state["mode"]
            if abs(mode) != 1:
                return False
            self.need = "f" if mode == 1 else "g"
            self.want = self._xpart()
