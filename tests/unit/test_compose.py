"""timing/compose.py: a path composed with a time law, against an independent composition written here (scipy's
adaptive quad for t(τ) = ∫dτ/√b, brentq for its inverse, the chain rule by hand) and the composed Cartesian peaks
against a dense evaluation."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.interpolate import BSpline
from scipy.optimize import brentq

from pickplace_cli.model.task import Task
from pickplace_cli.paths import plan_path
from pickplace_cli.timing.compose import compose
from pickplace_cli.timing.optimal import optimal_law

ADEPT = Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5)


def _random_law(seed: int, n: int = 20, k: int = 3) -> BSpline:
    """A B-spline b(τ) > 0 of degree ``k`` (3: the SLSQP's law, 5: the SQP's) on uniform knots, coefficients
    log-uniform over a factor 30 (a law ten times slower than elsewhere in places: harder than the optimiser's,
    which stays within a factor ~10)."""
    rng = np.random.default_rng(seed)
    knots = np.concatenate([[0.0] * k, np.linspace(0.0, 1.0, n - k + 1), [1.0] * k])
    return BSpline(knots, 100.0 * np.exp(rng.uniform(np.log(1 / 30), 0.0, n)), k, extrapolate=False)


def _reference(path, b, u: np.ndarray):
    """The composed motion at u by an independent route: T and t(τ) by scipy's quad (abs. 1e-14), τ(u) by brentq
    (xtol 1e-15), then p(τ) and its u-derivatives by the chain rule with τ′ = T√b, τ″ = T²b′/2, τ‴ = T³√b·b″/2."""
    f = lambda s: float(b(s)) ** -0.5  # noqa: E731
    pts = list(np.unique(b.t))
    T = quad(f, 0.0, 1.0, epsabs=1e-14, epsrel=1e-12, points=pts, limit=500)[0]
    tau = np.array([brentq(lambda s: quad(f, 0.0, s, epsabs=1e-14, epsrel=1e-12, limit=500)[0] - x * T, 0.0, 1.0,
                           xtol=1e-15) for x in u])
    bb, b1, b2 = b(tau), b.derivative(1)(tau), b.derivative(2)(tau)
    s1, s2, s3 = T * np.sqrt(bb), T**2 * b1 / 2, T**3 * np.sqrt(bb) * b2 / 2
    p, d1, d2, d3 = path.all_orders(tau)
    return [p, d1 * s1[:, None], d2 * (s1**2)[:, None] + d1 * s2[:, None],
            d3 * (s1**3)[:, None] + 3 * d2 * (s1 * s2)[:, None] + d1 * s3[:, None]]


@pytest.mark.parametrize("seed,k", [(1, 3), (2, 3), (3, 3), (4, 5), (5, 5)])
def test_composed_motion_is_the_independent_composition(seed, k):
    # position to 1e-11 m (the inverse's tolerance 1e-11 in τ times |p′| ≲ 1 m), every derivative to 1e-8 of its
    # largest value (the reference's own quad/brentq error is ~1e-13 in τ; the derivatives are exact at the composed τ)
    path = plan_path(ADEPT, "bspline")
    b = _random_law(seed, k=k)
    got = compose(path, b)
    u = np.random.default_rng(seed).uniform(0.0, 1.0, 40)
    ref = _reference(path, b, u)
    mine = got.all_orders(u)
    assert np.abs(mine[0] - ref[0]).max() < 1e-11
    for k in (1, 2, 3):
        assert np.abs(mine[k] - ref[k]).max() < 1e-8 * np.abs(ref[k]).max()


def test_composed_peaks_are_the_dense_peaks():
    # the composed path's v̂, â, ĵ against its own motion on 200,001 points and its breakpoints: the composition is
    # checked above, so this checks the peak search (a dense miss is ≤ ~(5e-6/width)², 1e-7 relative allowed; the
    # peaks found are the path's own values, known to 1e-10 of the true maxima: below the dense ones by no more)
    path = plan_path(ADEPT, "bspline")
    from pickplace_cli.model.profile import load_profile
    from pickplace_cli.planner import motion_model
    from pickplace_cli.timing import fit_duration

    prof = load_profile("delta-su2018")
    model = motion_model(path, prof)
    t_fit, _ = fit_duration(model, prof.planning.dwell)
    for b in (optimal_law(model, prof.planning.dwell, t_fit, coefficients=20).law, _random_law(4)):
        got = compose(path, b)
        u = np.unique(np.concatenate([np.linspace(0.0, 1.0, 200_001), got.breakpoints]))
        o = got.all_orders(u)
        dense = [np.linalg.norm(o[k], axis=1).max() for k in (1, 2, 3)]
        for k in range(3):
            assert dense[k] * (1 - 1e-10) <= got.peaks[k] <= dense[k] * (1 + 1e-7)
