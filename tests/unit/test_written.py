"""A time-optimal law is slowed until ``check`` reads its written samples within every limit
(``pickplace_cli/timing/written.py``): what ``plan --time optimal`` calls ok, ``check`` accepts from its file.

The Adept cycle with the capacity held, at the default 1 kHz: the law's jerk falls from ~7 300 m/s³ to 0 in the
last 0.3 ms, and the septic Hermite through the 1 kHz samples read q1's torque rate at 100.2 % (accuracy 0.1 %)
while the motion itself peaks at 99.99 %. Tested: the file as plan writes it is accepted; without the reading
(``read_written=""``) the same file is refused (the test is not vacuous); the slowed motion holds its limits on an
independent dense finite-difference sampling of the model; the slowing is small and said."""

from __future__ import annotations

import io

import numpy as np
import pytest

from pickplace_cli.export.csv import write_csv
from pickplace_cli.model.profile import load_profile
from pickplace_cli.model.task import Task
from pickplace_cli.pipelines.check import check_file
from pickplace_cli.planner import PlanOptions, motion_model, plan
from pickplace_cli.timing import written

ADEPT = Task([-0.1525, 0.0, -0.8], [0.1525, 0.0, -0.8], height=0.025, eta=0.5)


def test_written_values_are_the_csv_numbers():
    """Every number as ``%.12g`` prints it and float() reads it back, over magnitudes from 1e-9 to 1e13, signs and
    zero (exact: the same doubles)."""
    rng = np.random.default_rng(7)
    x = rng.standard_normal((400, 5)) * 10.0 ** rng.integers(-9, 13, (400, 5))
    x[0, 0], x[1, 1], x[2, 2] = 0.0, -0.0, 0.5e-4
    want = np.vectorize(lambda v: float("%.12g" % v))(x)
    assert np.array_equal(written.written_values(x), want)


def _read(tmp_path, pl, prof, hold: bool):
    buf = io.StringIO()
    write_csv(pl, buf)
    f = tmp_path / "move.csv"
    f.write_text(buf.getvalue())
    return check_file(str(f), prof, hold_capacity=hold)[0].report


def _adept(**kw):
    prof = load_profile("delta-su2018")
    return prof, plan(ADEPT, prof, PlanOptions(time="optimal", hold_capacity=True, **kw))


def test_optimal_file_is_accepted_by_check(tmp_path):
    prof, pl = _adept()
    assert pl.report.ok
    rep = _read(tmp_path, pl, prof, hold=True)
    assert rep.ok, [(r.joint, r.quantity, r.peak, r.accuracy) for r in rep.violations]
    d = pl.duration
    # slowed, by little (the reading was 0.2 % high: the square root of that and a margin), and said so
    assert 1.0 < d.written_stretch < 1.005
    assert d.seconds == pytest.approx(d.t_optimal * d.written_stretch, rel=1e-12)
    assert "where check reads every limit within it" in d.written and "q1 motor torque rate" in d.written
    assert pl.t[-1] == pytest.approx(d.seconds, rel=1e-12)


def test_without_the_reading_the_same_file_is_refused(tmp_path, monkeypatch):
    """The case is real: the law written at its own duration (the reading switched off: ``read_written=""``) is
    refused by check (so the test above can fail); read but not slowed (``RETIMES`` = 0), the plan itself says the
    reading exceeds the limit (exit 3, not written as ok)."""
    prof = load_profile("delta-su2018")
    pl = plan(ADEPT, prof, PlanOptions(time="optimal", hold_capacity=True, read_written=""))
    assert pl.report.ok and pl.duration.written_stretch == 1.0
    rep = _read(tmp_path, pl, prof, hold=True)
    assert not rep.ok, ("check now accepts the unslowed law's 1 kHz file: the reading no longer needs the slowing "
                        "on this move; pick another move for this test")
    monkeypatch.setattr(written, "RETIMES", 0)
    unslowed = plan(ADEPT, prof, PlanOptions(time="optimal", hold_capacity=True))
    assert unslowed.report.exit_code() == 3 and unslowed.duration.seconds == pl.duration.seconds
    assert "the file is not written as within its limits" in unslowed.duration.written


def test_slowed_law_holds_on_a_dense_finite_difference(tmp_path):
    """Independent of the exact check's peak search: the motor torque on 200 001 uniform points of the model at the
    plan's duration, its rate by central differences (error ~h²·τ⁽³⁾ ≈ 1e-6 relative here), within every motor's
    torque-rate limit to 1e-4 relative (the plan's peak sits at the limit to 1e-7)."""
    prof, pl = _adept()
    T = pl.duration.seconds
    model = motion_model(pl.cartesian.path, prof)
    tau = np.linspace(0.0, 1.0, 200_001)
    parts = model.parts(tau)
    tm = parts.Am / T**2 + parts.Gm  # (N, 3) N·m
    rate = np.gradient(tm, tau * T, axis=0)
    rows = {r.joint: r.limit * r.target for r in pl.report.rows if r.quantity == "motor torque rate"}
    lim = np.array([rows[name] for name in pl.joint.names])
    assert np.all(np.abs(rate).max(axis=0) <= lim * (1 + 1e-4)), (np.abs(rate).max(axis=0), lim)


def test_on_a_cycle_the_slowed_law_is_whole_cycles(tmp_path):
    """With --cycle the slowed duration stays a whole number of cycles, and check accepts the file."""
    prof, pl = _adept(cycle=0.001)
    n = pl.duration.seconds / 0.001
    assert abs(n - round(n)) < 1e-9
    assert _read(tmp_path, pl, prof, hold=True).ok


def test_cli_plan_then_check_and_the_capacity_hint(tmp_path):
    """From the shell: plan --time optimal writes the file and says it slowed the law; check accepts it with
    --no-hold-capacity (the rule's own capacity setting); without it only the capacity is exceeded, and check says
    which option reads the file as planned."""
    from typer.testing import CliRunner

    from pickplace_cli.cli import app

    out = tmp_path / "opt.csv"
    runner = CliRunner()
    r = runner.invoke(app, ["plan", "--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8", "--time", "optimal",
                            "--hold-capacity", "-o", str(out)])
    assert r.exit_code == 0, r.stderr
    assert "written samples at 1000 Hz: check's reading of them put q1 motor torque rate" in r.stderr
    r = runner.invoke(app, ["check", str(out), "-q"])
    assert r.exit_code == 0, r.stderr
    r = runner.invoke(app, ["plan", "--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8", "--time", "optimal", "-q",
                            "-o", str(out)])
    assert r.exit_code == 0, r.stderr
    r = runner.invoke(app, ["check", str(out), "-q"])
    assert r.exit_code == 3 and "hint: only the Cartesian capacity is exceeded" in r.stderr
    r = runner.invoke(app, ["check", str(out), "-q", "--no-hold-capacity"])
    assert r.exit_code == 0 and "hint" not in r.stderr


def test_optimal_on_the_capacity_alone():
    """A profile without a timed joint or motor limit (the shipped gantry: no drives) under ``--time optimal
    --hold-capacity``: the law is timed by the capacity alone (it fell back to uniform scaling before), faster than
    Eq. 26's uniform law, and holds |v| ≤ [v], |a| ≤ [a] on 100 001 points of the composed path, its velocity and
    acceleration taken by finite differences of its positions (independent of the path's analytic derivatives;
    error ~h²·p⁽³⁾/6 ≈ 1e-6 relative), to 1e-3 relative."""
    prof = load_profile("gantry")
    pl = plan(Task([-0.3, 0.0, -0.5], [0.3, 0.2, -0.5], height=0.025, eta=0.5), prof,
              PlanOptions(time="optimal", hold_capacity=True))
    d = pl.duration
    assert pl.report.ok and d.law != "uniform (fallback)" and d.seconds < 0.9 * d.t_auto
    t = np.linspace(0.0, d.seconds, 100_001)
    p = pl.cartesian(t)
    v = np.gradient(p, t, axis=0)
    a = np.gradient(v, t, axis=0)
    cap = prof.capacity
    assert np.linalg.norm(v, axis=1).max() <= cap.velocity * (1 + 1e-3)
    assert np.linalg.norm(a[2:-2], axis=1).max() <= cap.acceleration * (1 + 1e-3)


def _file_ok(tmp_path, pl, prof, hold):
    return _read(tmp_path, pl, prof, hold).ok


def test_too_few_samples_to_check_are_refused(tmp_path):
    """At 20 Hz the default plan of the Adept cycle has 5 samples, fewer than check reads a move from
    (``written.MIN_SAMPLES``): plan said every limit held (exit 0) and wrote a file check refuses (exit 1). It is now
    one line, exit 1, that names the rate and the least that works, and no file; that rate plans and check reads its
    file. The library's plan (no file) returns such a move, not read back, with a note that says why; a drive's table
    is not samples."""
    from typer.testing import CliRunner

    from pickplace_cli.cli import app

    prof = load_profile("delta-su2018")
    pl = plan(ADEPT, prof, PlanOptions(time="optimal", rate=25.0))
    assert pl.report.ok and len(pl.t) == 5 and pl.duration.written_stretch == 1.0
    assert "fewer than the 6 check reads" in pl.duration.written
    out = tmp_path / "few.csv"
    res = CliRunner().invoke(app, ["plan", "--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8", "--rate", "20",
                                   "-o", str(out), "-q"])
    assert res.exit_code == 1 and not out.exists(), res.output
    (line,) = [ln for ln in res.output.splitlines() if "error" in ln]
    assert line.startswith("pickplace: error: --rate 20 Hz: 5 samples") and "--rate 28 Hz or more" in line
    res = CliRunner().invoke(app, ["plan", "--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8", "--rate", "28",
                                   "-o", str(out), "-q"])
    assert res.exit_code == 0, res.output
    res = CliRunner().invoke(app, ["check", str(out), "-q"])
    assert res.exit_code == 0, res.output
    res = CliRunner().invoke(app, ["plan", "--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8", "--rate", "20",
                                   "-f", "cam", "--tolerance", "1e-3", "-o", str(tmp_path / "cam.csv"), "-q"])
    assert res.exit_code == 0, res.output  # a drive's table: its points are not samples


@pytest.mark.parametrize("rate", [50.0, 100.0])
def test_fit_at_a_low_rate_is_read_back(tmp_path, rate):
    """--time fit rides a motor limit too: at 50 Hz check read its file at 170 % of the torque rate and refused it
    (plan said ok); the uniform law is slowed until check accepts."""
    prof = load_profile("delta-su2018")
    pl = plan(ADEPT, prof, PlanOptions(time="fit", rate=rate))
    assert pl.report.ok
    assert _file_ok(tmp_path, pl, prof, hold=False)
    d = pl.duration
    assert d.written_stretch >= 1.0 and d.seconds == pytest.approx(d.t_fit * d.written_stretch, rel=1e-12)


def test_slowed_past_the_fit_the_uniform_law_is_written(tmp_path):
    """On a 8 ms controller cycle (125 samples/s) check reads the time-optimal law's samples ~2 × past the torque
    rate; slowing it to pass makes it longer than the uniform law of --time fit as written, so that law is written
    (the move never gets slower than --time fit because of the reading), and check accepts it."""
    prof = load_profile("delta-su2018")
    pl = plan(ADEPT, prof, PlanOptions(time="optimal", cycle=0.008))
    fit = plan(ADEPT, prof, PlanOptions(time="fit", cycle=0.008))
    assert pl.report.ok and fit.report.ok
    assert pl.duration.seconds <= fit.duration.seconds + 1e-12
    assert pl.duration.law.startswith("uniform") and "that law is written instead" in pl.duration.written
    assert _file_ok(tmp_path, pl, prof, hold=False)


def test_a_reading_that_swings_with_the_sample_phase_still_passes(tmp_path):
    """A shape the law-judged search finds (4 law solves): its 1 kHz reading rose while the law was slowed in small
    steps (100.11 → 100.22 %) and the plan gave up with exit 3; the growing margin and the bisection find a stretch
    that reads within every limit, under 1 %. (The shipped smoothing weight given: the shape's plan would otherwise
    keep the law without the term, which reads within its limits unslowed here.)"""
    from pickplace_cli.timing import law_sqp

    prof = load_profile("delta-su2018")
    pl = plan(ADEPT, prof, PlanOptions(time="optimal", shape=True, shape_law_evals=4, law_smoothing=law_sqp.SQP_SMOOTH))
    assert pl.report.ok and 1.0 < pl.duration.written_stretch < 1.01
    assert _file_ok(tmp_path, pl, prof, hold=False)


@pytest.mark.parametrize("streamed", [False, True])
def test_a_batch_says_which_rows_were_slowed(tmp_path, streamed):
    """In a batch (a file, or a stream on stdin) the closing line says how many rows' laws were slowed for their
    written samples and the largest stretch with its row; each row's JSON line carries its written_stretch, the
    same as a single plan of that move (the library's ``Duration.written_stretch``)."""
    import json

    from typer.testing import CliRunner

    from pickplace_cli.cli import app

    src = tmp_path / "moves.csv"
    src.write_text("from_x,from_y,from_z,to_x,to_y,to_z\n-0.1525,0,-0.8,0.1525,0,-0.8\n0.1525,0,-0.8,-0.1525,0,-0.8\n")
    want = [plan(Task(a, b, height=0.025, eta=0.5), load_profile("delta-su2018"),
                 PlanOptions(time="optimal", hold_capacity=True)).duration.written_stretch
            for a, b in (([-0.1525, 0, -0.8], [0.1525, 0, -0.8]), ([0.1525, 0, -0.8], [-0.1525, 0, -0.8]))]
    assert want[0] > 1.0 and want[1] == 1.0  # the Adept cycle's way out is slowed, its way back is not
    args = ["plan", "--batch", "-" if streamed else str(src), "--time", "optimal", "--hold-capacity", "--json",
            "-o", str(tmp_path / "out.csv")]
    r = CliRunner().invoke(app, args, input=src.read_text() if streamed else None)
    assert r.exit_code == 0, r.stderr
    got = [json.loads(line)["written_stretch"] for line in r.stdout.splitlines()]
    assert got == pytest.approx(want, rel=1e-12)
    assert (f"batch: 2 rows, 2 ok, 0 failed; 2 written; 1 slowed so that check reads their written samples within "
            f"every limit (up to × {want[0]:.5g}, row 1;") in r.stderr


SCARA_HC = ("scara-600", Task([0.3, -0.15, -0.1], [0.4, 0.15, -0.1], height=0.025, eta=0.5))


def _strict_read(tmp_path, pl, prof):
    buf = io.StringIO()
    write_csv(pl, buf)
    f = tmp_path / "strict.csv"
    f.write_text(buf.getvalue())
    return check_file(str(f), prof, hold_capacity=False, strict=True)[0].report


def test_strict_plan_is_resolved_for_check_strict(tmp_path):
    """``PlanOptions(strict=True)`` (``plan --strict``): a time-optimal law whose 1 kHz file check reads within its
    limits but with q1's torque rate not resolved (100.1 % ± 1.5 %: ``check --strict`` exit 3) is slowed until
    every peak is resolved; check then finds none unresolved. The slowing is small (< 1 %: a torque rate falls as
    1/T³), said in the note, and the law is the same one (the plan without --strict, scaled in time)."""
    name, task = SCARA_HC
    prof = load_profile(name)
    loose = plan(task, prof, PlanOptions(time="optimal", hold_capacity=True))
    rep = _strict_read(tmp_path, loose, prof)
    assert rep.ok and rep.unresolved, "the file without --strict is resolved: pick another move for this test"
    pl = plan(task, prof, PlanOptions(time="optimal", hold_capacity=True, strict=True))
    assert pl.report.ok and pl.report.exit_code() == 0 and pl.report.strict
    assert 1.0 < pl.duration.written_stretch < 1.01
    assert pl.duration.seconds == pytest.approx(loose.duration.t_optimal * pl.duration.written_stretch, rel=1e-12)
    assert "check --strict's reading of them put q1 motor torque rate at" in pl.duration.written
    rep = _strict_read(tmp_path, pl, prof)
    assert rep.ok and not rep.unresolved, [(r.joint, r.quantity, r.peak, r.accuracy) for r in rep.unresolved]


def test_strict_not_resolved_after_the_slowing_is_exit_3(tmp_path, monkeypatch):
    """A peak still not resolved when the slowing gives up fails the plan under --strict: exit 3, the row within its
    limit but not resolved (check's reading: peak and accuracy), and the CLI says why it wrote nothing; the same plan
    without --strict is written (exit 0). The slowing that gives up is simulated: the law slowed as without --strict
    (q1's torque rate then reads within its limit, ± 1.5 %), the strict reading's unresolved rows left over."""
    from dataclasses import replace as with_fields

    from typer.testing import CliRunner

    from pickplace_cli.cli import app

    real = written.hold_as_written

    def gave_up(*args, strict=False, **kwargs):
        w = real(*args, **kwargs)
        if not strict:
            return w
        read = written.read_as_written(*w.state[1], args[3], args[4], kwargs.get("positions_only", False), True)
        return with_fields(w, read=read, past=tuple(r for r, _ in written._past(read)))

    monkeypatch.setattr(written, "hold_as_written", gave_up)
    name, task = SCARA_HC
    pl = plan(task, load_profile(name), PlanOptions(time="optimal", hold_capacity=True, strict=True))
    assert pl.report.ok and pl.report.exit_code() == 3
    (row,) = pl.report.unresolved
    assert (row.joint, row.quantity) == ("q1", "motor torque rate") and row.accuracy > 0.01 * row.limit
    args = ["plan", "-p", name, "--from", "0.3,-0.15,-0.1", "--to", "0.4,0.15,-0.1", "--time", "optimal",
            "--hold-capacity", "-q", "-o", str(tmp_path / "s.csv")]
    r = CliRunner().invoke(app, [*args, "--strict"])
    assert r.exit_code == 3 and not (tmp_path / "s.csv").exists()
    assert "pickplace: not resolved: q1 motor torque rate = " in r.stderr
    assert "trajectory not written (--strict: a peak is not resolved by the written samples)" in r.stderr
    r = CliRunner().invoke(app, args)
    assert r.exit_code == 0 and (tmp_path / "s.csv").exists()


def test_strict_under_the_default_rule_and_its_usage(tmp_path):
    """--strict under the default rule (limits) reads the file too: the Adept cycle's is resolved as planned (no
    slowing); --strict with a duration in seconds or a drive's table is a usage error (exit 2); a batch row that
    stays unresolved is said on its own line (``unresolved_text``)."""
    from typer.testing import CliRunner

    from pickplace_cli.cli import app
    from pickplace_cli.pipelines.batch import unresolved_text

    prof = load_profile("delta-su2018")
    pl = plan(ADEPT, prof, PlanOptions(strict=True))
    assert pl.report.exit_code() == 0 and pl.duration.written_stretch == 1.0
    rep = _strict_read(tmp_path, pl, prof)
    assert not rep.unresolved
    base = ["plan", "--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8", "--strict", "-q"]
    r = CliRunner().invoke(app, [*base, "--time", "0.3", "-o", str(tmp_path / "a.csv")])
    assert r.exit_code == 2 and "--strict slows the law of a duration rule" in r.stderr
    r = CliRunner().invoke(app, [*base, "-f", "pvt", "-o", str(tmp_path / "a.csv")])
    assert r.exit_code == 2 and "a drive's table (-f pvt) is judged as the drive interpolates it" in r.stderr
    r = CliRunner().invoke(app, [*base, "-o", str(tmp_path / "a.csv")])
    assert r.exit_code == 0, r.stderr
    # --write-anyway writes a move past a limit (auto does not hold the motors' torque rate): said, under --strict
    r = CliRunner().invoke(app, [*base, "-m", "superposition", "--time", "auto", "--write-anyway", "-o",
                                 str(tmp_path / "w.csv")])
    assert r.exit_code == 0 and "warning: --strict: the file is written (--write-anyway) although check --strict" \
        in r.stderr
    row = rep.rows[0]
    from dataclasses import replace as rep_row

    text = unresolved_text(rep_row(row, peak=99.5, limit=100.0, utilisation=0.995, accuracy=1.5))
    assert text.startswith(f"not resolved: {row.joint} {row.quantity} = 99.5 ± 1.5 ") and "(99.5 % ± 1.5 % of 100" in text


def test_strict_at_a_low_rate_the_tool_columns_agree_with_the_positions(tmp_path):
    """At 100 Hz the tool's jerk columns of a time-optimal lamé move disagree with its positions by more than the 5 %
    ``check --strict`` allows (it refuses the file, exit 1); ``plan --strict`` slows the law until they agree and the
    file is accepted by check --strict with every peak resolved. The duration says what binds it now."""
    from pickplace_cli.model.errors import TaskError

    prof = load_profile("delta-su2018")
    options = dict(method="lame", time="optimal", rate=100.0)
    loose = plan(ADEPT, prof, PlanOptions(**options))
    with pytest.raises(TaskError, match="disagree with the positions"):
        _strict_read(tmp_path, loose, prof)
    pl = plan(ADEPT, prof, PlanOptions(**options, strict=True))
    assert pl.report.exit_code() == 0 and pl.duration.written_stretch > 1.0
    assert pl.duration.binding == "the written samples as check --strict reads them"
    rep = _strict_read(tmp_path, pl, prof)
    assert rep.ok and not rep.unresolved


def test_strict_says_what_it_read_and_refuses_what_check_cannot_read(tmp_path):
    """Not slowed, --strict still says what check --strict reads; it is refused (exit 2) for MCAP, which check does
    not read, and for --columns without every joint (without --strict: a warning that check cannot read the file)."""
    from typer.testing import CliRunner

    from pickplace_cli.cli import app

    pl = plan(ADEPT, load_profile("delta-su2018"), PlanOptions(strict=True))
    assert pl.duration.written_stretch == 1.0
    assert pl.duration.written.startswith("written samples at 1000 Hz: check --strict reads every peak resolved")
    scara = ["plan", "-p", "scara-600", "--from", "0.3,-0.15,-0.1", "--to", "0.4,0.15,-0.1", "-q"]
    out = str(tmp_path / "s.csv")
    r = CliRunner().invoke(app, [*scara, "--strict", "-f", "mcap", "-o", str(tmp_path / "s.mcap")])
    assert r.exit_code == 2 and "check reads CSV and JSON trajectories, not MCAP" in r.stderr
    r = CliRunner().invoke(app, [*scara, "--strict", "--columns", "t,q1,q2,q3", "-o", out])
    assert r.exit_code == 2 and "--columns t,q1,q2,q3 leaves some out" in r.stderr
    r = CliRunner().invoke(app, [*scara, "--columns", "t,q1,q2,q3", "-o", out])
    assert r.exit_code == 0 and "warning: --columns t,q1,q2,q3: check cannot read the file" in r.stderr
    r = CliRunner().invoke(app, [*scara, "--strict", "--columns", "plc", "-o", out])  # t and the drives: readable
    assert r.exit_code == 0, r.stderr
    r = CliRunner().invoke(app, ["check", out, "-p", "scara-600", "--strict", "-q"])
    assert r.exit_code == 0, r.stderr


def test_a_path_planned_for_its_duration_is_read_back_and_replanned(tmp_path):
    """``bspline-vel`` (a pick from a moving belt) plans its path for its duration. At 40 Hz check read the default
    plan's file at 149 % of the capacity acceleration and refused it (exit 3) while plan said every limit held: the
    written samples were not read back for such a path. They are now, and each longer duration's path is planned
    again rather than the path slowed: the slowed file still leaves the pick at the belt's velocity (a path slowed
    in time would leave it at v/k; read from the CSV's first row), check accepts it, and a given duration the
    reading exceeds is judged (exit 3)."""
    prof = load_profile("delta-su2018")
    task = Task([-0.15, 0.0, -0.8], [0.15, 0.0, -0.8], height=0.025, eta=0.5, v_from=[0.3, 0.0, 0.0])
    pl = plan(task, prof, PlanOptions(method="bspline-vel", rate=40.0))
    assert pl.report.ok and pl.duration.written_stretch > 1.01, pl.duration.written
    assert "slowed" in pl.duration.written
    buf = io.StringIO()
    write_csv(pl, buf)
    rows = np.genfromtxt(io.StringIO(buf.getvalue()), delimiter=",", names=True)
    assert rows["vxms"][0] == pytest.approx(0.3, abs=1e-9) and abs(rows["vzms"][0]) < 1e-9
    assert rows["ts"][-1] == pytest.approx(pl.duration.seconds, rel=1e-12)
    assert _file_ok(tmp_path, pl, prof, hold=True)
    given = plan(task, prof, PlanOptions(method="bspline-vel", rate=40.0, time=pl.duration.t_auto))
    assert given.report.exit_code() == 3 and "not written as within its limits" in given.duration.written
