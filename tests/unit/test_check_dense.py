"""A file so dense that the rounding of its 12 digits would dominate the reconstruction's third derivative is read
from one sample in k (``limits.samples.reading_stride``): at 200 kHz the Adept cycle's q1 torque rate read 140 % of its
limit from the rounding alone (the motion: 40 %), and ``plan --strict`` refused the move."""

from __future__ import annotations

import io

import numpy as np
import pytest

from pickplace_cli.export.csv import write_csv
from pickplace_cli.limits import samples as S
from pickplace_cli.model.profile import load_profile
from pickplace_cli.model.task import Task
from pickplace_cli.pipelines.check import check_file
from pickplace_cli.planner import PlanOptions, plan

ADEPT = Task([-0.1525, 0.0, -0.8], [0.1525, 0.0, -0.8], height=0.025, eta=0.5)


def test_the_stride_by_hand():
    """x = J·t³/6 (jerk J) over 1 s with |x| ≤ 1: k = ⌈(G·δ/(share·J))^(1/3) / h⌉, δ = ROUNDING·1."""
    J = 6.0
    for rate in (1e3, 2e4, 2e5):
        t = np.arange(0.0, 1.0 + 0.5 / rate, 1.0 / rate)
        pos = np.column_stack([J * t**3 / 6.0, np.zeros_like(t), np.zeros_like(t)])
        need = (S.ROUNDING_GAIN * S.ROUNDING / (S.ROUNDING_SHARE * J)) ** (1.0 / 3.0)
        want = max(1, int(np.ceil(need * rate - 1e-9)))
        assert S.reading_stride(t, pos) == want
        tool = np.column_stack([pos, np.zeros((len(t), 6)), np.tile([J, 0.0, 0.0], (len(t), 1))])
        assert S.reading_stride(t, pos, tool) == want
    assert S.reading_stride(np.arange(0.0, 1.0, 1e-3), np.zeros((1000, 3))) == 1  # no motion: nothing to drown


@pytest.mark.parametrize("columns", ["tool", "positions"])
def test_a_200_khz_file_reads_the_motion_not_its_rounding(tmp_path, columns):
    """The Adept cycle at 200 kHz: check's q1 torque rate within 0.2 % of the plan's continuous check (the motion's
    exact peak, 40 % of the limit), and that of the same move's 1 kHz file; the note names the stride."""
    prof = load_profile("delta-su2018")
    dense = plan(ADEPT, prof, PlanOptions(rate=200_000.0, read_written="positions" if columns == "positions" else "tool"))
    exact = next(r.peak for r in dense.report.rows if r.joint == "q1" and r.quantity == "motor torque rate")
    buf = io.StringIO()
    write_csv(dense, buf)
    text = buf.getvalue()
    if columns == "positions":
        lines = text.splitlines()
        head = lines[0].split(",")
        keep = [i for i, h in enumerate(head) if h.split("[")[0] in ("t", "q1", "q2", "q3")]
        text = "\n".join(",".join(ln.split(",")[i] for i in keep) for ln in lines) + "\n"
    f = tmp_path / "dense.csv"
    f.write_text(text)
    rep = check_file(f, prof)[0].report
    row = next(r for r in rep.rows if r.joint == "q1" and r.quantity == "motor torque rate")
    assert rep.ok and rep.exit_code() == 0
    assert row.peak == pytest.approx(exact, rel=2e-3) and row.resolved
    assert any("read from one sample in" in n for n in rep.notes)


def test_plan_strict_at_200_khz_holds_the_move():
    """``plan --strict`` reads its 200 kHz samples the same way: the move at 40 % of its torque rate is written."""
    prof = load_profile("delta-su2018")
    pl = plan(ADEPT, prof, PlanOptions(rate=200_000.0, strict=True))
    assert pl.report.ok and pl.report.exit_code() == 0


def test_a_spike_between_the_samples_read_is_not_left_out(tmp_path):
    """A 2 µrad spike on one sample of a 50 kHz positions-only file, on a sample the stride would leave out: the
    samples left out must lie on the quintic spline through the others (to 1e-9 of the positions), so every sample is
    read, and the spike's torque rate (orders beyond the limit) is exceeded."""
    prof = load_profile("delta-su2018")
    dense = plan(ADEPT, prof, PlanOptions(rate=50_000.0, read_written="positions"))
    q = np.asarray(dense.joint.q).copy()
    i = 4501
    q[i, 0] += 2e-6
    rows = "".join(f"{a:.12g},{b[0]:.12g},{b[1]:.12g},{b[2]:.12g}\n" for a, b in zip(dense.t, q))
    f = tmp_path / "spike.csv"
    f.write_text("t[s],q1[rad],q2[rad],q3[rad]\n" + rows)
    t = np.asarray(dense.t)
    pos = np.asarray(dense.p)
    assert i % S.reading_stride(t, pos) != 0  # the stride of the clean file would leave the spike out
    rep = check_file(f, prof)[0].report
    assert not rep.ok and rep.exit_code() == 3
    assert not any("read from one sample in" in n for n in rep.notes)


def test_a_nanometre_bump_between_the_samples_read_is_read(tmp_path):
    """A Gaussian bump of 1 nm (σ = 10 µs) on the tool's x of the Adept cycle at 200 kHz, through the inverse
    kinematics: its jerk is A/σ³ ~ 1e6 m/s³ (q1's torque rate ~72 × its limit, by the robot model on the bump's
    analytic derivatives), though no left-out sample is 1e-9 of the positions off the spline through the others. The
    samples left out must lie within 10 × the rounding δ of that spline: every sample is read, and it is exceeded."""
    from pickplace_cli.robots import build_robot

    prof = load_profile("delta-su2018")
    robot = build_robot(prof.robot)
    dense = plan(ADEPT, prof, PlanOptions(rate=200_000.0, read_written=""))
    t = np.asarray(dense.t)
    p = np.asarray(dense.p).copy()
    u = (t - 0.0905) / 1e-5
    p[:, 0] += 1e-9 * np.exp(-u * u / 2)
    q = robot.inverse_kinematics(p)
    f = tmp_path / "bump.csv"
    f.write_text("t[s],q1[rad],q2[rad],q3[rad]\n" + "".join(f"{a:.12g},{b[0]:.12g},{b[1]:.12g},{b[2]:.12g}\n"
                                                           for a, b in zip(t, q)))
    rep = check_file(f, prof)[0].report
    assert not rep.ok and rep.exit_code() == 3
    assert not any("read from one sample in" in n for n in rep.notes)
