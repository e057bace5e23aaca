"""``check`` of a file whose tool derivative columns (vx … az) are off its positions by one factor everywhere: a file
re-timed without them, or accelerations in another scale. Such columns passed the per-interval agreement test (1 %
for velocities, 10 % for accelerations) and set the peaks: a motion past its RMS rating read 96.8-98.8 %, exit 0.
The columns are now refused as one factor off (``limits.samples.SCALE_TOL``) and the move is judged from its positions.

The reference for each edited file is independent of the sampled reading: the exact check of ``plan`` on the same
continuous motion (the move planned for the re-timed duration), and the unedited file's own verdict."""

from __future__ import annotations

import io

import numpy as np
import pytest

from pickplace_cli.export.csv import write_csv
from pickplace_cli.limits.samples import SCALE_TOL, derivative_problems
from pickplace_cli.model.errors import PickplaceError
from pickplace_cli.model.profile import load_profile
from pickplace_cli.model.task import Task
from pickplace_cli.pipelines.check import check_file
from pickplace_cli.planner import PlanOptions, plan
from pickplace_cli.timing.written import written_values
from tests.property.test_limit_truth import _profile

ADEPT = Task([-0.1525, 0.0, -0.8], [0.1525, 0.0, -0.8], height=0.025, eta=0.5)


def _rms_bound_profile(tmp_path):
    """The shipped Delta with its motors' torque-rate limits ×10: the RMS rating binds."""
    import re

    from pickplace_cli.model.profile import resolve_profile_path

    text = open(resolve_profile_path("delta-su2018")).read()
    text = re.sub(r"torque_rate: ([0-9.eE+-]+)", lambda m: f"torque_rate: {10 * float(m.group(1))}", text)
    text = re.sub(r"^name: .*$", "name: delta-rms", text, count=1, flags=re.M)
    path = tmp_path / "delta-rms.yaml"
    path.write_text(text)
    return load_profile(str(path))


def _rows(pl) -> tuple[list[str], np.ndarray]:
    buf = io.StringIO()
    write_csv(pl, buf)
    lines = buf.getvalue().splitlines()
    return lines[0].split(","), np.array([[float(x) for x in ln.split(",")] for ln in lines[1:]])


def _check(tmp_path, head, data, prof, name="edited.csv"):
    f = tmp_path / name
    f.write_text(",".join(head) + "\n" + "\n".join(",".join("%.12g" % x for x in row) for row in data) + "\n")
    warned: list = []
    (move,) = check_file(str(f), prof, hold_capacity=False, warn=warned.append)
    return move.report, warned


def _rms(report):
    return max(r.utilisation for r in report.rows if r.quantity == "rms motor torque")


def test_a_retimed_file_is_judged_from_its_positions(tmp_path):
    """The move written at 0.1285 s (RMS 99.7 % of the rating), its time column divided by 1.009 and nothing else:
    the motion is the move at 0.1285/1.009 s, whose exact check (``plan --time``) puts the RMS past the rating.
    check said 98.8 %, exit 0; it now names the factor and judges the positions: exceeded, as the exact check."""
    prof = _rms_bound_profile(tmp_path)
    pl = plan(ADEPT, prof, PlanOptions(time=0.1285))
    head, data = _rows(pl)
    data[:, 0] /= 1.009
    exact = plan(ADEPT, prof, PlanOptions(time=0.1285 / 1.009)).report
    assert _rms(exact) > 1.003 and not exact.ok  # the re-timed motion is past its rating (reference)
    report, warned = _check(tmp_path, head, data, prof)
    assert not report.ok and _rms(report) == pytest.approx(_rms(exact), abs=3e-3)
    assert any("vx, vy, vz say 0.9 % less than the positions' changes" in w and "judged from its positions alone" in w
               for w in warned), warned


def test_acceleration_columns_off_by_one_factor_are_not_used(tmp_path):
    """The move at 0.125 s (RMS 104 % of the rating by the exact check) with its ax, ay, az × 0.93: read 96.8 % through
    them, exit 0; now judged from the positions: the unedited file's verdict (exceeded, the same RMS to 0.3 %)."""
    prof = _rms_bound_profile(tmp_path)
    pl = plan(ADEPT, prof, PlanOptions(time=0.125))
    assert _rms(pl.report) > 1.03
    head, data = _rows(pl)
    names = [h.split("[")[0] for h in head]
    for c in ("ax", "ay", "az"):
        data[:, names.index(c)] *= 0.93
    report, warned = _check(tmp_path, head, data, prof)
    assert not report.ok and _rms(report) == pytest.approx(_rms(pl.report), abs=3e-3)
    assert any("ax, ay, az say" in w for w in warned), warned


@pytest.mark.parametrize("rate", [25.0, 100.0, 1000.0, 5000.0])
def test_plans_own_columns_are_never_one_factor_off(rate):
    """The factor test on plan's own files (every method, the Adept cycle and a SCARA and gantry move, the default and
    the time-optimal rule) at 25 Hz to 5 kHz: no column is refused (their misfit is the interpolation's)."""
    moves = [("delta-su2018", ADEPT), ("scara-600", Task([0.3, 0.2, -0.1], [0.45, -0.15, -0.12], 0.03, 0.5)),
             ("gantry", Task([-0.4, -0.3, -0.5], [0.3, 0.4, -0.45], 0.08, 0.5))]
    seen = 0
    for name, task in moves:
        prof = _profile(name)
        for method in ("bspline", "ph", "superposition", "lame", "piecewise-poly"):
            for rule in ("limits", "optimal"):
                try:
                    pl = plan(task, prof, PlanOptions(method=method, time=rule, rate=rate))
                except PickplaceError:
                    continue
                if len(pl.t) < 6:
                    continue
                t = written_values(pl.t - pl.t[0])
                tool = written_values(np.column_stack([pl.p, pl.v, pl.a, pl.j]))
                assert not [p for p in derivative_problems(t, tool) if p[1] < 0], (name, method, rule)
                seen += 1
    assert seen >= 20
    assert SCALE_TOL <= 1e-3
