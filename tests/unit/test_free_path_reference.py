"""``--optimize shape --time optimal`` against an independent computation: the free-path minimum time of the
move by direct transcription (tests/reference/free_path.py: CasADi + IPOPT, the rigid Delta written
independently from tests/reference/delta_rigid.py's formulas), and that reference's own dynamics against
delta_rigid's Lagrangian."""

from __future__ import annotations

import numpy as np
import pytest

ca = pytest.importorskip("casadi")

from pickplace_cli.model.profile import load_profile  # noqa: E402
from pickplace_cli.model.task import Task  # noqa: E402
from pickplace_cli.planner import PlanOptions, plan  # noqa: E402
from tests.reference import delta_rigid as D  # noqa: E402
from tests.reference import free_path as F  # noqa: E402

ADEPT = Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5)


def test_reference_dynamics_agree_with_the_lagrangian_reference():
    """The CasADi motor torque (plate position as coordinates, τ = (∂q/∂p)⁻ᵀ F) equals delta_rigid's joint-space
    Lagrangian (complex step) through the drive (τ/(N·η) + J_rotor·N·q̈) to 1e-9 relative, and its rate equals a
    central difference along a constant-jerk motion to 1e-6 relative (step 1e-6 s: truncation ~1e-12 s², the
    round-off of torques ~10 N·m over 2e-6 s ~1e-8 N·m/s)."""
    P = D.params()
    lim = F.Limits()
    f = F.motor_functions(P, lim)
    rng = np.random.default_rng(3)
    for _ in range(5):
        q = rng.uniform(0.0, 0.8, (1, 3))
        qd, qdd = rng.uniform(-3, 3, (1, 3)), rng.uniform(-80, 80, (1, 3))
        p, v, a = D.cartesian_motion(D._resolved(P), q, qd, qdd)
        want = D.reference_torques(P, q, qd, qdd)[0] / (lim.gear * lim.efficiency) + lim.rotor * lim.gear * qdd[0]
        j = rng.uniform(-2000, 2000, 3)
        qq, spd, mot, rate = (np.asarray(x, float).ravel() for x in f(p[0], v[0], a[0], j))
        np.testing.assert_allclose(qq, q[0], rtol=0, atol=1e-12)
        np.testing.assert_allclose(spd, lim.gear * qd[0], rtol=1e-12, atol=1e-9)
        np.testing.assert_allclose(mot, want, rtol=1e-9, atol=1e-9)
        h = 1e-6

        def along(s):
            return np.asarray(f(p[0] + v[0] * s + a[0] * s**2 / 2 + j * s**3 / 6, v[0] + a[0] * s + j * s**2 / 2,
                                a[0] + j * s, j)[2], float).ravel()

        np.testing.assert_allclose(rate, (along(h) - along(-h)) / (2 * h), rtol=1e-6, atol=1e-3)


@pytest.mark.slow
def test_optimised_shape_against_the_free_path_minimum():
    """The free-path minimum time on a coarse transcription (6 intervals per phase, ~10 s; 0.10363 s, against
    0.10325 s at 8 and 0.10296 s at 12 intervals: it converges from above, within 1 % at 6) bounds what any path
    of the family can do: the plan's duration (every limit held by the continuous check) is not below 0.98 × the
    coarse reference (a plan faster than the free-path minimum would mean a limit mis-evaluated on one side),
    and the widened family with the optimal law comes within 4 % of it (measured 1.020 ×; Li's family alone,
    before the widening, 1.053 ×)."""
    prof = load_profile("delta-su2018")
    ref = F.solve_free_path(ADEPT.p_from, ADEPT.p_to, ADEPT.height, F.limits_from_profile(prof),
                            D.params_from_robot(_robot(prof)), n_phase=6)
    assert ref.status == "solved"
    assert ref.dense_utilisation <= 1.01  # limits at the nodes; between them within 1 %
    assert ref.eta == pytest.approx(0.1, abs=1e-6)  # the lift-off at the lower bound, as the shape search finds
    got = plan(ADEPT, prof, PlanOptions(time="optimal", shape=True))
    assert got.report.ok
    T = got.duration.seconds
    assert 0.98 * ref.T <= T <= 1.04 * ref.T


@pytest.mark.slow
def test_shape_with_the_capacity_against_the_free_path_minimum(tmp_path):
    """With the capacity held, ``--optimize shape --time optimal --shape-law-evals 30 --law-coefficients 120`` keeps
    the chosen shape's law without the smoothing term (shorter as written than with it: 0.13012 s against
    0.13021 s, read back as ``check --strict`` reads it), and its 1 kHz file is accepted by ``check --strict`` with
    every peak resolved. Against the free-path minimum (16 intervals per phase, 15 s; the transcription converges from
    above: 0.128628 s at 32, about 0.1285-0.1286 s extrapolated, ``bench/bench_free_path_convergence.py``) it is not
    below the reference (which would mean a limit misjudged on one side) and within 1.5 % of it (measured
    1.0107 ×; the issue's 1 % is not reached)."""
    from pickplace_cli.export.csv import write_csv
    from pickplace_cli.pipelines.check import check_file

    prof = load_profile("delta-su2018")
    p0, p1 = np.array(ADEPT.p_from), np.array(ADEPT.p_to)
    ref = F.solve_free_path(p0, p1, ADEPT.height, F.limits_from_profile(prof, capacity=True),
                            D.params_from_robot(_robot(prof)), n_phase=16, t_guess=0.12,
                            guess=F._default_guess(p0, p1, max(p0[2], p1[2]) + ADEPT.height, 0.1, 0.02))
    assert ref.status == "solved" and ref.dense_utilisation <= 1.001
    got = plan(ADEPT, prof, PlanOptions(time="optimal", shape=True, hold_capacity=True, shape_law_evals=30,
                                        law_coefficients=120))
    assert got.report.ok and "without the smoothing term: shorter as written" in got.duration.law
    assert ref.T <= got.duration.seconds <= 1.015 * ref.T
    f = tmp_path / "shape.csv"
    with open(f, "w") as out:
        write_csv(got, out)
    rep = check_file(f, prof, strict=True)[0].report
    assert rep.ok and not rep.unresolved and rep.exit_code() == 0


def _robot(prof):
    from pickplace_cli.planner import motion_model_static

    return motion_model_static(prof)[0]
