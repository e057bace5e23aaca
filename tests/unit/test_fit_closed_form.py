"""The fitted duration in closed form (pickplace_cli.timing.fit) against independent computations: brentq on the
same functions (scipy), and the bracketing search of the fit's own screening (screened_root) on random moves."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from pickplace_cli.limits.grid import fit_grid
from pickplace_cli.model.profile import load_profile
from pickplace_cli.model.task import Task
from pickplace_cli.paths import plan_path
from pickplace_cli.planner import motion_model
from pickplace_cli.timing import _worst_utilisation, fit_duration, fit_screen, screened_root
from pickplace_cli.timing.fit import fit_thresholds, rms_thresholds, torque_rate_threshold


def _first_crossing_reference(a: float, b: float, L: float) -> float:
    """The first u > 0 with |a u³ + b u| = L: a fine logarithmic scan for the first sign change, then brentq."""
    xs = np.concatenate([[0.0], np.logspace(-9, 9, 6000)])
    v = np.abs(a * xs**3 + b * xs) - L
    i = np.flatnonzero(v >= 0)
    if not i.size:
        return math.inf
    return brentq(lambda x: abs(a * x**3 + b * x) - L, xs[i[0] - 1], xs[i[0]], xtol=1e-300, rtol=1e-15)


def test_torque_rate_threshold_matches_brentq_on_random_cubics():
    # every branch: b ≥ 0 (one real root), b < 0 with the dip reaching the limit (three real roots) or not,
    # a = 0 (linear); coefficients over six decades. Tolerance 1e-7: the trigonometric form loses digits only next
    # to a double root (dip just touching the limit), and the fit needs ~1e-8 (its exact check confirms it).
    rng = np.random.default_rng(7)
    a = rng.normal(size=4000) * 10 ** rng.uniform(-3, 3, 4000)
    b = rng.normal(size=4000) * 10 ** rng.uniform(-3, 3, 4000)
    a[:50] = 0.0
    L = 10 ** rng.uniform(-1, 2, 4000)
    got = torque_rate_threshold(a, b, L)
    ref = np.array([_first_crossing_reference(x, y, z) for x, y, z in zip(a, b, L)])
    assert np.all(np.isfinite(got) == np.isfinite(ref))
    fin = np.isfinite(ref)
    assert np.max(np.abs(got[fin] - ref[fin]) / ref[fin]) < 1e-7


def test_torque_rate_threshold_branches_by_hand():
    # |u³ − 3u| = 1: the dip reaches −2 at u = 1, so the first crossing is on the dip, where u³ − 3u = −1:
    # u = 2 cos(4π/9) (the smaller positive root of the trigonometric solution)
    assert torque_rate_threshold(np.array([1.0]), np.array([-3.0]), 1.0)[0] == pytest.approx(2 * math.cos(4 * math.pi / 9), rel=1e-12)
    # |u³ − 3u| = 3: the dip (−2) does not reach it; beyond u₀ = √3, u³ − 3u = 3 has one real root
    u = torque_rate_threshold(np.array([1.0]), np.array([-3.0]), 3.0)[0]
    assert u**3 - 3 * u == pytest.approx(3.0, rel=1e-12) and u > math.sqrt(3)
    # a sign flip of both coefficients changes nothing; a = 0 is linear
    assert torque_rate_threshold(np.array([-2.0]), np.array([-5.0]), 4.0)[0] == pytest.approx(
        torque_rate_threshold(np.array([2.0]), np.array([5.0]), 4.0)[0], rel=1e-15)
    assert torque_rate_threshold(np.array([0.0]), np.array([-4.0]), 2.0)[0] == 0.5


def test_rms_thresholds_match_brentq_on_the_duty_cycle_formula():
    # the RMS of move-dwell-back-dwell (MotionModel.rms_motor_torque's formula, written out here) crosses the rating
    rng = np.random.default_rng(3)
    for _ in range(200):
        iaa, igg = rng.uniform(0.01, 5.0), rng.uniform(0.0, 1.0)
        iag = rng.uniform(-1, 1) * math.sqrt(iaa * igg)
        hold, dwell = rng.uniform(0.0, 2.0), rng.uniform(0.0, 0.3)
        rated = math.sqrt(max(igg, hold / 2)) * rng.uniform(1.05, 3.0)

        def excess(T):
            move = T * (iaa / T**4 + 2 * iag / T**2 + igg)
            return math.sqrt((2 * move + dwell * hold) / (2 * T + 2 * dwell)) - rated

        got = rms_thresholds(np.array([iaa]), np.array([iag]), np.array([igg]), np.array([hold]), dwell,
                             np.array([rated]))[0]
        hi = 1e3
        assert excess(hi) < 0
        # the largest crossing: scan down from a long duration while the rating holds
        ts = np.geomspace(1e-4, hi, 20000)[::-1]
        ex = np.array([excess(t) for t in ts])
        j = np.flatnonzero(ex > 0)
        ref = 0.0 if not j.size else brentq(excess, ts[j[0]], ts[j[0] - 1], xtol=1e-15, rtol=1e-13)
        assert got == pytest.approx(ref, rel=1e-9, abs=1e-12)


CASES = [("delta-su2018", "bspline"), ("delta-su2018", "ph"), ("delta-su2018", "superposition"),
         ("delta-su2018", "lame"), ("delta-su2018", "piecewise-poly"), ("scara-600", "bspline"),
         ("scara-600", "ph"), ("scara-600", "lame")]


def _move(profile: str, rng) -> Task:
    if profile == "scara-600":
        a = [rng.uniform(0.25, 0.45), rng.uniform(-0.25, 0.25), rng.uniform(-0.18, -0.05)]
        b = [rng.uniform(0.25, 0.45), rng.uniform(-0.25, 0.25), rng.uniform(-0.18, -0.05)]
    else:
        a = [rng.uniform(-0.2, 0.2), rng.uniform(-0.2, 0.2), rng.uniform(-0.95, -0.8)]
        b = [rng.uniform(-0.2, 0.2), rng.uniform(-0.2, 0.2), rng.uniform(-0.95, -0.8)]
    return Task(np.array(a), np.array(b), 0.025, 0.5)


@pytest.mark.parametrize("profile,method", CASES)
def test_screened_fit_matches_the_bracketing_search(profile, method):
    """The closed form on the samples is a lower bound of the screened fit (the samples sit under the peaks), within
    5e-4 of the bracketing search (screened_root: a scan and brentq on the worst utilisation with each column's peak
    at its parabola vertex, an independent route); the exact fit is never longer than that search's root nudged up
    until the continuous check passes (the fit's former procedure, written out here), at most 1e-4 shorter, and
    holds every timed limit on the continuous check."""
    from pickplace_cli.limits.check import check_limits

    prof = load_profile(profile)
    dwell = prof.planning.dwell
    rng = np.random.default_rng(sum(map(ord, profile + method)))
    for _ in range(3):
        task = _move(profile, rng)
        path = plan_path(task, method)
        model = motion_model(path, prof)
        parts = model.parts(fit_grid(path.breakpoints, path.jumps))
        t_samples = max(t for _, t in fit_thresholds(model, parts, dwell))
        worst, _ = _worst_utilisation(model, dwell)
        t_ref = screened_root(worst, 0.1) * (1 + 1e-7)
        for _ in range(10):
            bad = [r for r in check_limits(model, t_ref, parts=parts, dwell=dwell).violations if r.kind != "reach"]
            if not bad:
                break
            t_ref *= max(r.utilisation for r in bad) * (1 + 1e-9)
        assert t_samples <= fit_screen(model, dwell)[0] * (1 + 1e-12)
        assert t_samples == pytest.approx(t_ref, rel=5e-4)
        T, _ = fit_duration(model, dwell)
        assert t_ref * (1 - 1e-4) <= T <= t_ref * (1 + 1e-7)
        assert not [r for r in check_limits(model, T, parts=parts, dwell=dwell).violations if r.kind != "reach"]


# ------------------------------------------------------------ the vectorised fit against the scalar one, move by move


def _stacked(models_parts):
    """The Parts of several moves one after the other, and their starts."""
    from pickplace_cli.limits.motion import Parts

    fields = ("tau", "p", "v1", "a1", "j1", "q", "qd1", "qdd1", "qddd1", "A", "G", "Am", "Gm", "dAm", "dGm", "singularity")
    parts = [p for _, p in models_parts]
    stacked = Parts(**{f: np.concatenate([getattr(p, f) for p in parts]) for f in fields})
    return stacked, np.concatenate([[0], np.cumsum([len(p.tau) for p in parts])])


def _fit_cases(which: str, n: int, seed: int):
    """(profile, [(model, parts on the fit grid)]) of n random B-spline moves (PH too for the thresholds)."""
    from pickplace_cli.model.headroom import with_limit_use

    from .test_verdict_fit import scara

    rng = np.random.default_rng(seed)
    prof = {"delta": load_profile("delta-su2018"), "scara": scara(),
            "delta-tight": with_limit_use(load_profile("delta-su2018"), 0.03)}[which]
    out = []
    for i in range(n):
        task = _move("scara-600" if which == "scara" else "delta-su2018", rng)
        path = plan_path(task, "ph" if i % 4 == 3 else "bspline")
        model = motion_model(path, prof)
        out.append((model, model.parts(fit_grid(path.breakpoints, path.jumps))))
    return prof, out


@pytest.mark.parametrize("which", ["delta", "scara", "delta-tight"])
def test_batch_fit_thresholds_are_the_scalar_thresholds_bitwise(which):
    """batch_fit_thresholds on the stacked samples of many moves = fit_thresholds of each move alone, bit for bit
    (the engine's fit_s must be plan()'s byte for byte); inf where the scalar raises NoFeasibleDuration (``delta-tight``:
    3 % of every rating, where the holding torque alone exceeds the motor torque and the RMS limits)."""
    from pickplace_cli.model.errors import NoFeasibleDuration
    from pickplace_cli.timing.fit import batch_fit_thresholds

    prof, cases = _fit_cases(which, 16, seed=11)
    dwell = prof.planning.dwell
    stacked, starts = _stacked(cases)
    rms = [m.rms_integrals(p) for m, p in cases]
    names, got = batch_fit_thresholds(cases[0][0], stacked, starts, (np.array([r[0] for r in rms]),
                                                                      np.array([r[1] for r in rms])), dwell)
    infeasible = 0
    for k, (model, parts) in enumerate(cases):
        try:
            ref = fit_thresholds(model, parts, dwell)
        except NoFeasibleDuration:
            infeasible += 1
            assert np.isinf(got[k]).any()
            continue
        assert names == [name for name, _ in ref]
        assert np.array_equal(got[k], np.array([t for _, t in ref]))
    assert (infeasible > 0) == (which == "delta-tight")
    # without the RMS (``rms=False``)
    names2, got2 = batch_fit_thresholds(cases[0][0], stacked, starts, None, dwell)
    assert names2 == [n for n in names if "rms" not in n] and np.array_equal(got2, got[:, : len(names2)])


@pytest.mark.parametrize("which", ["delta", "scara", "delta-tight"])
def test_batch_fit_screen_is_fit_screen_bitwise(which):
    """batch_fit_screen = fit_screen's T for each B-spline move (no jumps), bit for bit; NaN where it raises."""
    from pickplace_cli.model.errors import NoFeasibleDuration
    from pickplace_cli.timing.fit import batch_fit_screen

    prof, cases = _fit_cases(which, 12, seed=12)
    cases = [c for c in cases if c[0].path.method == "bspline"]
    dwell = prof.planning.dwell
    stacked, starts = _stacked(cases)
    rms = [m.rms_integrals(p) for m, p in cases]

    got = batch_fit_screen(cases[0][0], stacked, starts, (np.array([r[0] for r in rms]), np.array([r[1] for r in rms])),
                           dwell)
    raised = 0
    for k, (model, _) in enumerate(cases):
        try:
            ref = fit_screen(model, dwell)[0]
        except NoFeasibleDuration:
            raised += 1
            assert np.isnan(got[k])
            continue
        assert got[k] == ref, (k, got[k], ref)
    assert (raised > 0) == (which == "delta-tight")


@pytest.mark.parametrize("profile, a, b", [
    ("delta-su2018", (-0.1525, 0.0, -0.8), (0.1525, 0.0, -0.8)),
    ("delta-4axis", (-0.1, 0.05, -0.8), (0.12, -0.04, -0.8)),
    ("scara-600", (0.3, -0.2, -0.1), (0.3, 0.2, -0.1)),
])
def test_auto_shows_the_fit_of_the_fit_rule(profile, a, b):
    """``time = auto`` shows the motors' fit beside its own duration (screened where the capacity binds, as
    ``time = limits`` does): the fit rule's own duration, found by its exact check, is the reference. The screened
    value may sit above it by the screen's tolerance on the plan's first samples (5e-5, generous: ~1e-5 measured)
    and below it by no more than round-off; the auto duration itself is the capacity's, with or without the fit."""
    from pickplace_cli.planner import PlanOptions, plan

    prof = load_profile(profile)
    task = Task(np.array(a, float), np.array(b, float), 0.025)
    auto = plan(task, prof, PlanOptions(time="auto"))
    fit = plan(task, prof, PlanOptions(time="fit"))
    bare = plan(task, prof, PlanOptions(time="auto", fit=False))
    assert auto.duration.seconds == bare.duration.seconds
    assert auto.duration.t_fit is not None
    rel = auto.duration.t_fit / fit.duration.seconds - 1.0
    assert -1e-9 <= rel <= 5e-5, rel
