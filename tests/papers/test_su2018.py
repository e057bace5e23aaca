"""Reproduce Su et al. 2018 (quintic PH curves for a Delta robot): the PH identities of Sec. II.A, the
trajectory of Sec. II.B–D, the superposition method of Sec. III, the Adept example and the Fig. 11 study
of Sec. IV. Each test names its source and tolerance."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

from pickplace_cli.paths.ph import (
    PHCorner,
    cycle_time_eq22,
    paper_duration,
    path_length,
    ph_arc_length,
    ph_coefficients,
    ph_control_points,
    ph_curvature,
    ph_length,
    ph_path,
    ph_sigma,
    plan_ph,
)
from pickplace_cli.paths.superposition import cycle_time, plan_superposition
from pickplace_cli.paths.superposition import paper_duration as sup_paper_duration
from pickplace_cli.model.profile import Capacity
from pickplace_cli.studies.parameters import fig11_study, paper_times, true_times
from pickplace_cli.model.task import Task

#: (m, r) in m: the Adept corner, a square one, a tall narrow one, a flat wide one
CORNERS = [(0.025, 0.1525), (0.1, 0.1), (0.3, 0.01), (0.005, 0.5)]
G = np.linspace(0.0, 1.0, 41)
#: Sec. IV: the Adept cycle, (−152.5, 0, −800) → (152.5, 0, −800) mm, h = 25 mm
ADEPT = Task([-0.1525, 0.0, -0.8], [0.1525, 0.0, -0.8], 0.025)


@pytest.mark.parametrize("m,r", CORNERS)
def test_eq14_solves_eq13(m, r):
    u0, u2, v2 = ph_coefficients(m, r)
    assert u2 == v2
    # Eq. (13), three lines; the solution is closed form, so round-off tolerances (1e-15 of the size)
    assert u0**2 / 5 + u0 * u2 / 15 + u2**2 / 5 - v2**2 / 5 == pytest.approx(m, rel=1e-13)
    assert u0 * v2 / 15 + 2 * u2 * v2 / 5 == pytest.approx(r, rel=1e-13)
    assert u2**2 / 5 - v2**2 / 5 == 0.0


@pytest.mark.parametrize("m,r", CORNERS)
def test_control_points_and_eq15(m, r):
    """Eq. (12) control points: P1 = P2, P3 = P4, P5 = (r, m); the Bézier curve equals the polynomials of
    Eq. (15) (both forms of x(γ)). Exact algebra: tolerance 1e-15 of the corner size."""
    u0, u2, v2 = ph_coefficients(m, r)
    cp = ph_control_points(u0, u2, v2)
    np.testing.assert_array_equal(cp[1], cp[2])
    np.testing.assert_array_equal(cp[3], cp[4])
    np.testing.assert_allclose(cp[5], [r, m], rtol=1e-13)
    g = G
    x1 = 2 / 3 * u0 * v2 * g**3 * (1 - g) ** 2 + 1 / 3 * u0 * v2 * g**4 * (1 - g) + (u0 * v2 / 15 + 2 / 5 * u2 * v2) * g**5
    x2 = 2 / 5 * (u0 * v2 + u2 * v2) * g**5 - u0 * v2 * g**4 + 2 / 3 * u0 * v2 * g**3
    y = (
        u0**2 * g * (1 - g) ** 4
        + 2 * u0**2 * g**2 * (1 - g) ** 3
        + (2 * u0**2 + 2 / 3 * u0 * u2) * g**3 * (1 - g) ** 2
        + (u0**2 + 1 / 3 * u0 * u2) * g**4 * (1 - g)
        + (u0**2 / 5 + u0 * u2 / 15) * g**5
    )
    P = PHCorner(m, r).curve(g)[0]
    scale = max(m, r)
    np.testing.assert_allclose(P[:, 0], x1, atol=1e-14 * scale)
    np.testing.assert_allclose(P[:, 0], x2, atol=1e-14 * scale)
    np.testing.assert_allclose(P[:, 1], y, atol=1e-14 * scale)


@pytest.mark.parametrize("m,r", CORNERS)
def test_pythagorean_hodograph(m, r):
    """Eq. (2)–(5), (16): the derivative of the Bézier curve is (x′, y′) = (2uv, u² − v²) and its norm is
    the polynomial σ = u² + v² (the PH property). Eq. (3) as printed, (u² − v², 2uv), would start
    horizontally (x′(0) = u0²), contradicting P0P1 on the Y axis (Eq. 8): the paper's slip."""
    c = PHCorner(m, r)
    P1 = c.curve(G)[1]
    np.testing.assert_allclose(P1, c.hodograph(G), atol=1e-14 * np.abs(P1).max())  # round-off of the Bernstein sums
    sig = ph_sigma(G, c.u0, c.u2, c.v2)
    np.testing.assert_allclose(np.linalg.norm(P1, axis=1), sig, rtol=1e-13, atol=1e-14 * sig.max())  # round-off
    u = c.u0 * (1 - G) ** 2 + c.u2 * G**2
    v = c.v2 * G**2
    eq3 = np.column_stack([u * u - v * v, 2 * u * v])
    assert np.abs(eq3[0] - P1[0]).max() > 0.5 * c.u0**2  # Eq. (3) as printed does not match the curve


@pytest.mark.parametrize("m,r", CORNERS)
def test_curvature_eq9_and_zero_at_both_ends(m, r):
    """Eq. (9): κ = 4u0v2(γ − γ²)/σ² equals |P′ × P″|/‖P′‖³ of the curve, and is 0 at γ = 0 and 1."""
    c = PHCorner(m, r)
    _, P1, P2, _ = c.curve(G)
    k_num = np.abs(P1[:, 0] * P2[:, 1] - P1[:, 1] * P2[:, 0]) / np.linalg.norm(P1, axis=1) ** 3
    k = ph_curvature(G, c.u0, c.u2, c.v2)
    np.testing.assert_allclose(k, k_num, rtol=1e-11, atol=1e-11 * k.max())  # the cross product cancels at the ends
    assert ph_curvature(np.array([0.0, 1.0]), c.u0, c.u2, c.v2).tolist() == [0.0, 0.0]


@pytest.mark.parametrize("m,r", CORNERS)
def test_arc_length_eq17_eq18(m, r):
    """Eq. (17) equals the quadrature of ‖P′‖; Eq. (18) equals Eq. (17) at 1 and Sec. II.B's form
    u0²/5 + u0u2/15 + 2u2²/5 (equal because u2 = v2). Quadrature to 1e-13: tolerance 1e-12 relative."""
    c = PHCorner(m, r)
    for e in (0.25, 0.5, 1.0):
        ref = quad(lambda g: np.linalg.norm(c.curve(np.array([g]))[1]), 0.0, e, epsabs=0.0, epsrel=1e-13, limit=200)[0]
        assert ph_arc_length(e, c.u0, c.u2, c.v2) == pytest.approx(ref, rel=1e-12)
    l18 = ph_length(c.u0, c.u2, c.v2)
    assert l18 == pytest.approx(ph_arc_length(1.0, c.u0, c.u2, c.v2), rel=1e-14)
    assert l18 == pytest.approx(c.u0**2 / 5 + c.u0 * c.u2 / 15 + 2 * c.u2**2 / 5, rel=1e-15)


def test_eq22_forms_agree():
    """Eq. (22): sqrt(10 l_all/(√3 a)) with l_all of Eq. (20) equals the closed form in ψ, for m ≤ h,
    r ≤ w/2 (round-off only)."""
    rng = np.random.default_rng(1)
    for _ in range(20):
        h, w = rng.uniform(0.005, 0.3), rng.uniform(0.01, 1.0)
        m, r = rng.uniform(0.1, 1.0) * h, rng.uniform(0.1, 1.0) * w / 2
        t_len = math.sqrt(10 * path_length(h, w, m, r) / (math.sqrt(3) * 100.0))
        assert cycle_time_eq22(h, w, 100.0, m, r) == pytest.approx(t_len, rel=1e-12)


def test_path_length_decreases_in_m_and_r():
    """Sec. II.D: the optimum has |AB| = |GF| = 0, |CE| = 0, i.e. m = h and r = w/2. Reason: l_all
    (Eq. 20), and with it Eq. (22)'s T, decreases strictly in m and in r, so the largest corner wins.
    Checked on a grid of corners for the Adept cycle and a tall move."""
    for h, w in ((0.025, 0.305), (0.2, 0.1)):
        ms = np.linspace(0.05, 1.0, 20) * h
        rs = np.linspace(0.05, 1.0, 20) * w / 2
        L = np.array([[path_length(h, w, m, r) for r in rs] for m in ms])
        assert np.all(np.diff(L, axis=0) < 0) and np.all(np.diff(L, axis=1) < 0)
        assert L.min() == L[-1, -1] == pytest.approx(path_length(h, w, h, w / 2))
        # the planned path agrees: default parameters give the shortest path of all
        task = Task([0, 0, 0], [w, 0, 0], h)
        assert plan_ph(task).parameters["length_m"] == pytest.approx(L[-1, -1], rel=1e-12)
        assert plan_ph(task, m=ms[10], r=rs[10]).parameters["length_m"] == pytest.approx(L[10, 10], rel=1e-12)


def test_default_corner_is_also_best_for_the_true_norm_at_adept():
    """Not in the paper: at the Adept cycle, m = h, r = w/2 also minimises the *true* peak acceleration
    (so the true-norm cycle time) over a 4 × 4 grid of smaller corners (m/h, 2r/w ∈ {0.25 … 1}); a
    smaller corner has a larger curvature, which costs more than the shorter path saves."""
    task = ADEPT
    best = plan_ph(task).peaks[1]
    for fm in (0.25, 0.5, 0.75):
        for fr in (0.25, 0.5, 0.75, 1.0):
            assert plan_ph(task, m=fm * 0.025, r=fr * 0.1525).peaks[1] > best
        assert plan_ph(task, m=0.025, r=fm * 0.1525).peaks[1] > best


def test_path_passes_A_to_G():
    """Fig. 3: A B (vertical, |AB| = h − m), B C (PH corner), C D E (horizontal, |CE| = w − 2r), E F, F G,
    at the joins of the arc-length law; tangents vertical on AB/FG and horizontal on CE. Exact up to the
    arc-length inverse (round-off): 1e-12 m."""
    m, r = 0.015, 0.1
    p = plan_ph(ADEPT, m=m, r=r)
    _, pts = ph_path(ADEPT, m=m, r=r)
    tau = np.array(p.parameters["jerk_jumps_at"])  # A, B, C, E, F, G
    base = {k: ADEPT.p_from + pts[k][0] * ADEPT.e_u + np.array([0, 0, pts[k][1]]) for k in "ABCDEFG"}
    np.testing.assert_allclose(p(tau), np.array([base[k] for k in "ABCEFG"]), atol=1e-12)
    np.testing.assert_allclose(p(np.array([0.5]))[0], base["D"], atol=1e-12)
    np.testing.assert_allclose(base["B"], [-0.1525, 0, -0.8 + 0.025 - m], atol=1e-15)
    np.testing.assert_allclose(base["C"], [-0.1525 + r, 0, -0.775], atol=1e-15)
    v = p(tau[1:-1], 1)
    assert np.all(np.abs(v[[0, 3], 0]) < 1e-12 * np.abs(v[[0, 3], 2]))  # vertical at B, F
    assert np.all(np.abs(v[[1, 2], 2]) < 1e-12 * np.abs(v[[1, 2], 0]))  # horizontal at C, E


def test_adept_example():
    """Sec. IV, the Adept cycle with h = 25 mm (m = h, r = w/2 per Sec. II.D). The paper gives figures,
    not numbers; what it states is that the PH path is smooth, passes the end points and the top, and that
    its cycle time (Eq. 22) is shorter than superposition's (Eq. 26). With [a] = 100 m/s²: Eq. (22)
    0.13881 s vs Eq. (26) 0.17069 s. Holding the true acceleration norm to the same [a] reverses it:
    PH 0.22703 s (its normal acceleration κṡ² dominates: â/â_tangential = 2.675) vs superposition 0.18773 s
    (its norm exceeds the per-axis limit by 20.9 %, below √2). Closed forms vs exact/refined peaks:
    tolerances 1e-9 relative."""
    cap = Capacity(velocity=5.0, acceleration=100.0)
    ph, sup = plan_ph(ADEPT), plan_superposition(ADEPT)
    for p in (ph, sup):
        np.testing.assert_allclose(p(np.array([0.0, 0.5, 1.0])), [ADEPT.p_from, [0, 0, -0.775], ADEPT.p_to], atol=1e-15)
    t22, t26 = paper_duration(ADEPT, cap), sup_paper_duration(ADEPT, cap)
    assert t22 == pytest.approx(cycle_time_eq22(0.025, 0.305, 100.0), rel=1e-13)
    assert t26 == pytest.approx(cycle_time(0.025, 0.305, 100.0), rel=1e-15)
    assert t22 < t26  # the paper's claim, by its formulas
    # the 3-4-5 law's tangential peak is exactly 10/√3·l_all: Eq. (22) is right about the tangential part
    L = ph.parameters["length_m"]
    assert ph.parameters["a_max_tangential"] == pytest.approx(10 / math.sqrt(3) * L, rel=1e-15)
    t_ph, t_sup = math.sqrt(ph.peaks[1] / 100.0), math.sqrt(sup.peaks[1] / 100.0)
    assert t_ph > t_sup  # the true-norm reversal
    assert ph.peaks[1] / ph.parameters["a_max_tangential"] > 2.5
    assert 1.0 < sup.peaks[1] / (sup.parameters["paper_time_factor"] ** 2) <= math.sqrt(2)
    assert (t_ph, t_sup) == pytest.approx(true_times(0.025, 0.305, 100.0), rel=1e-9)


def test_ph_jerk_jumps_at_D():
    """The paper calls the PH jerk continuous; it is not at D: both corners reach D with zero curvature but
    with dκ/ds of opposite signs (κ even about D by symmetry, Eq. 9 gives dκ/dγ(1) = −4u0v2/σ(1)²), so the
    normal jerk jumps by 2|dκ/ds|·ṡ³ with ṡ = 15/8·l_all at τ = 1/2. Closed form vs the path: 1e-6
    (one-sided values at τ = 1/2 ± 1e-10)."""
    p = plan_ph(ADEPT)
    c = ph_path(ADEPT)[1]["corners"][0]
    s1 = ph_sigma(1.0, c.u0, c.u2, c.v2)
    dk_ds = 4 * c.u0 * c.v2 / s1**2 / s1
    sdot = 15 / 8 * p.parameters["length_m"]
    jl, jr = p(np.array([0.5 - 1e-10, 0.5 + 1e-10]), 3)
    assert np.linalg.norm(jr - jl) == pytest.approx(2 * dk_ds * sdot**3, rel=1e-6)


def test_fig11_study_both_ways():
    """Fig. 11: T_PH − T_superposition over 0 ≤ h ≤ 0.3 m, 0 ≤ w ≤ 1 m; the paper: negative on 99.70 %.

    By the paper's formulas (Eq. 22 vs Eq. 26–27) on a 1 mm grid (301 × 1001 points), PH is faster at every
    point except the h = 0 row, where both formulas give the same horizontal move (a tie): 1 − 1/301 =
    99.668 %. That matches the paper's 99.70 % to 0.04 points (tolerance 0.05): the paper's grid was
    presumably ~1 mm and its h = 0 ties fell either way by round-off.

    With the true acceleration norm held to the same limit, PH is faster only where h/w < ρ* ≈ 0.0259 —
    4.1 % of the grid. The classification by ρ is checked against direct planning at grid points on both
    sides of ρ* and elsewhere (independent of the scaling argument)."""
    r = fig11_study()
    assert r.paper_faster.shape == (301, 1001)
    assert r.paper_percent == pytest.approx(100 * (1 - 1 / 301), abs=1e-9)
    assert not r.paper_faster[0].any() and r.paper_faster[1:].all()
    assert r.paper_percent == pytest.approx(99.70, abs=0.05)
    assert len(r.crossings) == 1 and r.faster_below
    rho = r.crossings[0]
    assert 0.02 < rho < 0.03
    assert 3.0 < r.true_percent < 6.0
    # spot checks by direct planning (true_times plans the actual h × w move): around ρ* and far from it
    H, W = r.h, r.w
    picks = [(25, 1000), (26, 1000), (5, 190), (5, 195), (300, 1000), (150, 300), (1, 1000), (10, 100)]
    for i, k in picks:
        t_ph, t_sup = true_times(H[i], W[k], 1.0)
        assert r.true_faster[i, k] == (t_ph < t_sup), (H[i], W[k], t_ph, t_sup)
    # the paper's formulas, vectorised, agree with the scalar functions
    tp, ts = paper_times(0.025, 0.305, 1.0)
    assert tp == pytest.approx(cycle_time_eq22(0.025, 0.305, 1.0)) and ts == pytest.approx(cycle_time(0.025, 0.305, 1.0))
