"""What ``plan`` writes for the drive, ``check`` reads with the same profile: the PLC feed (``--columns plc``, default
and twincat dialects, with the drive velocities), and the PVT, cam and cam-table tables
(CSV, and Structured Text in both dialects). Plan's files of moves within
their limits are accepted (exit 0); copies re-timed 1 % and 3 % faster (every time divided by the factor, the
velocity columns multiplied by it, accelerations by its square, as a controller running the same points faster would
see them) are refused where a limit that depends on the duration binds (``--time fit``: exit 3; a positions-only
file's 1 % copy may be a peak the samples do not resolve, which ``--strict`` refuses, exit 3)."""

from __future__ import annotations

import pytest
from typer.testing import CliRunner

from pickplace_cli.cli import app

runner = CliRunner()
MOVES = {"delta-su2018": ("-0.1525,0,-0.8", "0.1525,0,-0.8"),  # the Adept move
         "delta-4axis": ("-0.1525,0,-0.8,0", "0.1525,0,-0.8,1"),
         "gantry": ("0.1,0.1,-0.4", "0.5,0.3,-0.5")}
#: the files: (name, plan options)
FORMATS = {"plc": ("--columns", "plc"), "twincat": ("--columns", "plc", "--csv-dialect", "twincat"),
           "plc-vel": ("--columns", "plc,drive_vel"), "pvt": ("--format", "pvt"), "cam": ("--format", "cam"),
           "cam-table": ("--format", "cam-table"), "pvt-st": ("--format", "pvt-st"),
           "cam-st": ("--format", "cam-st", "--st-dialect", "codesys"), "cam-table-st": ("--format", "cam-table-st")}


def _plan(tmp_path, prof: str, fmt: str, rule: str) -> str:
    a, b = MOVES[prof]
    out = tmp_path / f"{prof}-{fmt}-{rule}.{'st' if fmt.endswith('-st') else 'csv'}"
    res = runner.invoke(app, ["plan", "-p", prof, "--from", a, "--to", b, "--time", rule, "-q", "-o", str(out),
                              *FORMATS[fmt]])
    if res.exit_code != 0:
        pytest.skip(f"not written by plan (exit {res.exit_code})")
    return str(out)


def retime(text: str, speed: float) -> str:
    """The file run ``speed`` times faster: t, dt, master / speed; NAME_vel · speed; NAME_acc · speed²."""
    nl = "\r\n" if "\r\n" in text else "\n"
    lines = text.split(nl)
    sep = ";" if ";" in lines[0] else ","
    head = [h.split("[")[0] for h in lines[0].split(sep)]
    out = [lines[0]]
    for ln in lines[1:]:
        if not ln:
            out.append(ln)
            continue
        cells = ln.split(sep)
        for i, h in enumerate(head):
            factor = (1 / speed if h in ("t", "dt", "master") else speed if h.endswith("_vel")
                      else speed**2 if h.endswith("_acc") else None)
            if factor is not None:
                cells[i] = repr(float(cells[i]) * factor)
        out.append(sep.join(cells))
    return nl.join(out)


def _check(path: str, prof: str, *extra: str) -> int:
    res = runner.invoke(app, ["check", path, "-p", prof, "-q", *extra])
    return res.exit_code


@pytest.mark.parametrize("prof", list(MOVES))
@pytest.mark.parametrize("fmt", list(FORMATS))
def test_plans_drive_files_are_accepted(tmp_path, prof, fmt):
    """The default rule (every limit of the profile holds): check accepts each file plan writes for the drive."""
    path = _plan(tmp_path, prof, fmt, "limits")
    assert _check(path, prof) == 0


@pytest.mark.parametrize("prof", ["delta-su2018", "delta-4axis"])
def test_a_faster_cam_table_is_refused_as_the_drive_runs_it(tmp_path, prof):
    """A cam-table is judged as the drive runs it (straight lines read every cycle, each velocity step blended over
    one cycle, each motor torque step held to the torque rate × the cycle), where plan's table at --time fit keeps a
    few % of margin: plan's table is accepted, and a copy run faster by 1.03 / (its highest use of a timed limit) —
    every timed peak rises at least in proportion to the speed — is refused (exit 3)."""
    import json

    path = _plan(tmp_path, prof, "cam-table", "fit")
    rep = tmp_path / "r.json"
    assert _check(path, prof, "--no-hold-capacity", "--report", str(rep)) == 0
    rows = json.loads(rep.read_text())["limits"]["rows"]
    top = max(r["utilisation"] for r in rows if r["kind"] == "limit" and "capacity" not in r["quantity"]
              and r["quantity"] != "rms motor torque")  # (the RMS is diluted by the dwell)
    assert 0.5 < top <= 1.0
    fast = tmp_path / "fast.csv"
    fast.write_text(retime(open(path, newline="").read(), 1.03 / top), newline="")
    assert _check(str(fast), prof, "--no-hold-capacity") == 3, f"{1.03 / top:.4f}× faster accepted"


@pytest.mark.parametrize("prof", ["delta-su2018", "delta-4axis"])
@pytest.mark.parametrize("fmt", ["plc", "twincat", "plc-vel"])
def test_faster_copies_are_refused(tmp_path, prof, fmt):
    """At --time fit (a motor limit at 100 %): plan's file is accepted, the 3 % faster copy shows a limit exceeded
    (exit 3), the 1 % faster copy is refused under --strict (exceeded, or a peak the samples do not resolve)."""
    path = _plan(tmp_path, prof, fmt, "fit")
    assert _check(path, prof, "--no-hold-capacity") == 0  # fit holds the joint and motor limits alone
    text = open(path, newline="").read()
    for speed, extra in ((1.01, ("--strict",)), (1.03, ())):
        fast = tmp_path / f"fast-{speed}.csv"
        fast.write_text(retime(text, speed), newline="")
        assert _check(str(fast), prof, "--no-hold-capacity", *extra) == 3, f"{speed}× faster accepted"


@pytest.mark.parametrize("fmt", ["pvt", "cam"])
def test_tables_are_judged_as_rebuilt_when_retimed(tmp_path, fmt):
    """A PVT or cam table re-timed 3 % faster is the same curve run faster: every joint's motor speed peak of the
    rebuilt motion rises by exactly 3 % (to 1e-6: the rebuild is exact under re-timing; the speed has no dynamics)."""
    import json

    path = _plan(tmp_path, "delta-su2018", fmt, "fit")
    fast = tmp_path / "fast.csv"
    fast.write_text(retime(open(path, newline="").read(), 1.03), newline="")
    peaks = []
    for p in (path, str(fast)):
        rep = tmp_path / "r.json"
        runner.invoke(app, ["check", p, "-q", "--report-only", "--report", str(rep)])
        rows = json.loads(rep.read_text())["limits"]["rows"]
        peaks.append({r["joint"]: r["peak"] for r in rows if r["quantity"] == "motor speed"})
    for joint, v in peaks[0].items():
        assert peaks[1][joint] == pytest.approx(1.03 * v, rel=1e-6)


@pytest.mark.parametrize("fmt", ["pvt", "cam"])
@pytest.mark.parametrize("rule", ["fit", "optimal"])
def test_plans_tables_at_the_motors_limit_are_accepted(tmp_path, fmt, rule):
    """plan judges a table as the drive rebuilds it (adding points or re-timing until it holds); check rebuilds it
    the same way, so the table plan writes at the motors' limit is accepted."""
    assert _check(_plan(tmp_path, "delta-su2018", fmt, rule), "delta-su2018", "--no-hold-capacity") == 0


@pytest.mark.parametrize("fmt", ["pvt", "cam", "cam-table"])
def test_structured_text_reads_as_its_csv(tmp_path, fmt):
    """The same table written as CSV and as Structured Text (codesys and strict dialects) is read to the same points
    (to 1e-12 relative: both print every value round-trip exactly, the ST with repr's 17 digits, the CSV with 12)."""
    import numpy as np

    from pickplace_cli.model.profile import load_profile
    from pickplace_cli.pipelines.check_read import read_checked
    from pickplace_cli.robots import build_robot

    prof = load_profile("delta-su2018")
    robot = build_robot(prof.robot)
    csv_path = _plan(tmp_path, "delta-su2018", fmt, "limits")
    got = []
    for path in (csv_path, _plan(tmp_path, "delta-su2018", f"{fmt}-st", "limits")):
        kind, what, _ = read_checked(open(path).read(), path, prof, robot)
        got.append(what)
    assert np.allclose(got[0].t, got[1].t, rtol=1e-11, atol=1e-15)
    assert np.allclose(got[0].q, got[1].q, rtol=1e-11, atol=1e-12)
