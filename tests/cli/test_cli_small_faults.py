"""Small faults of the command line, one test each: a table tolerance beyond its rule, a hint naming a rate the user
never gave, ``profile show`` without the controller and the workcell, a belt plan's false fit line, and
``--from-belt`` not choosing the conveyor method."""

from __future__ import annotations

import pytest
from typer.testing import CliRunner

from pickplace_cli.cli import app

ADEPT = ["--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8"]


def _run(*args: str):
    return CliRunner().invoke(app, list(args), catch_exceptions=False)


@pytest.mark.parametrize("tolerance", ["10", "0.0011", "0", "-1e-6", "nan"])
def test_a_table_tolerance_beyond_its_rule_is_refused(tmp_path, tolerance):
    """--tolerance 10 wrote a cam table of two points, 0.13 rad off the move: a table's deviation lies in
    (0, 0.001] (rad or m), the rule the help states."""
    r = _run("plan", *ADEPT, "-f", "cam", "--tolerance", tolerance, "-q", "-o", str(tmp_path / "cam.csv"))
    assert r.exit_code == 1, r.output
    assert "a table's deviation must lie in (0, 0.001] (at most 1 mrad or 1 mm" in r.output
    assert not (tmp_path / "cam.csv").exists()


def test_the_largest_tolerance_is_accepted(tmp_path):
    r = _run("plan", *ADEPT, "-f", "cam", "--tolerance", "0.001", "-q", "-o", str(tmp_path / "cam.csv"))
    assert r.exit_code == 0, r.output
    assert "At most 0.001" in " ".join(_run("plan", "--help").output.split())


def test_a_short_move_without_rate_does_not_suggest_a_rate(tmp_path):
    """--time 0.0018 without --rate: the warning names the short move; it suggested --rate 1.1e6, a rate the user
    never gave ("kHz meant?")."""
    r = _run("plan", *ADEPT, "--time", "0.0018", "-q", "--write-anyway", "-o", str(tmp_path / "t.csv"))
    assert "pickplace: warning: a 0.0018 s move: 3 samples at the profile's planning.rate" in r.output
    assert "--rate" not in r.output and "kHz" not in r.output
    r = _run("plan", *ADEPT, "--rate", "10", "-q", "-o", str(tmp_path / "t.csv"))  # a rate given: it is named
    assert "--rate 10 Hz: 3 samples for a 0.18 s move" in r.output and "--rate 28 Hz or more" in r.output
    r = _run("plan", *ADEPT, "--cycle", "0.25", "-q", "-o", str(tmp_path / "t.csv"))  # a cycle: the cycle is named
    assert "--cycle 0.25 s: 2 samples (one per cycle) for a 0.25 s move" in r.output, r.output
    assert "planning.rate" not in r.output and "a cycle of 0.05 s or less" in r.output
    r = _run("plan", *ADEPT, "--rate", "30", "-q", "-o", str(tmp_path / "t.csv"))  # enough to check: the unit hint
    assert "--rate 30 Hz: 9 samples for a" in r.output and "kHz meant? --rate 30000" in r.output


def test_profile_show_prints_the_workcell_and_the_controller():
    r = _run("profile", "show", "delta-4axis")
    assert r.exit_code == 0, r.output
    assert "workcell: box (-0.6, -0.6, -1.1) … (0.6, 0.6, -0.55) m (the tool stays inside)" in r.output
    assert "controller: no cycle (samples at planning.rate)" in r.output
    assert "drive joint A4: unit counts, 1048576 counts per motor revolution, sign +1, offset 0 rad" in r.output
    r = _run("profile", "show", "scara-600")
    assert "drive joint J3: unit mm, sign -1, offset 0 m" in r.output
    r = _run("profile", "show", "gantry")
    assert "workcell: no box" in r.output and "drive joint AxisX: unit mm" in r.output


def test_a_belt_plan_does_not_say_no_limit_depends_on_the_duration(tmp_path):
    """A --to-belt plan chooses its duration without a fit: it said "fit: no joint or motor limit depends on the
    duration" of a profile whose motor limits all do."""
    r = _run("plan", "--from", "-0.1525,0,-0.8", "--to", "0.1525,-0.2,-0.8", "--to-belt", "0,0.5,0", "--latency",
             "0.05", "-o", str(tmp_path / "pick.csv"))
    assert r.exit_code == 0, r.output
    assert "duration T = " in r.output and "no joint or motor limit depends" not in r.output


def test_from_belt_chooses_the_conveyor_method_as_to_belt_does(tmp_path):
    """--from-belt (and --v-to) with a moving end select bspline-vel when -m is not given (it was refused: "method
    bspline plans moves from rest to rest"); a named rest-to-rest method is still refused, a zero velocity keeps
    the default method."""
    for option in ("--from-belt", "--v-from", "--v-to"):
        r = _run("plan", *ADEPT, option, "0,0.5,0", "-o", str(tmp_path / "b.csv"))
        assert r.exit_code == 0, r.output
        assert r.output.startswith("delta-su2018 / bspline-vel:"), r.output
    r = _run("plan", *ADEPT, "--from-belt", "0,0.5,0", "-m", "lame", "-o", str(tmp_path / "b.csv"))
    assert r.exit_code == 1 and "method lame plans moves from rest to rest" in r.output
    r = _run("plan", *ADEPT, "--from-belt", "0,0,0", "-o", str(tmp_path / "b.csv"))
    assert r.exit_code == 0 and r.output.startswith("delta-su2018 / bspline:"), r.output


BIG = "1" * 5000


@pytest.mark.parametrize("args, says", [
    (["plan", *ADEPT, "--time", BIG], "--time '" + "1" * 60 + "' … (5,000 characters)"),
    (["plan", "--from", BIG + ",0,-0.8", "--to", "0.1525,0,-0.8"], "--from '" + "1" * 60 + "' … (5,007 characters)"),
    (["plan", *ADEPT, "-m", BIG], "'" + "1" * 60 + "' … (5,000 characters)"),
    (["build-table", "--weights", BIG], "--weights '" + "1" * 60 + "' … (5,000 characters)"),
])
def test_a_5000_digit_value_is_one_short_error_line(args, says):
    """A 5,000-digit number pasted into an option: one line that shows the value cut to 60 characters with its
    length (the whole value was echoed, a 5,000-character line)."""
    r = _run(*args)
    assert r.exit_code in (1, 2), r.output
    lines = r.output.splitlines()
    assert len(lines) == 1 and len(lines[0]) < 300 and says in lines[0], r.output[:300]
    assert "internal error" not in r.output


def test_a_5000_digit_cell_of_a_batch_is_one_short_error(tmp_path):
    src = tmp_path / "m.csv"
    src.write_text("from_x,from_y,from_z,to_x,to_y,to_z\n" + BIG + ",0,-0.8,0.1525,0,-0.8\n")
    r = _run("plan", "--batch", str(src), "--json", "-q")
    assert r.exit_code == 1
    assert "from_x = '" + "1" * 60 + "' … (5,000 characters): must be finite" in r.output
    assert max(len(line) for line in r.output.splitlines()) < 300


@pytest.mark.parametrize("option", ["--v-to", "--v-from"])
def test_an_end_faster_than_the_capacity_names_its_option(tmp_path, option):
    """An end velocity of 100 m/s against the Delta's capacity.velocity of 5 m/s: no duration can meet it. One line
    naming the option, its value and the capacity, exit 1 (it said "-t/--time auto: no duration up to 1e4 s satisfies
    the limits", exit 3, a rule the user never gave)."""
    r = _run("plan", *ADEPT, option, "0,100,0", "-o", str(tmp_path / "v.csv"))
    assert r.exit_code == 1, r.output
    assert f"{option} (0, 100, 0) m/s: its speed 100 m/s is above the profile's capacity.velocity 5 m/s" in r.output
    assert not (tmp_path / "v.csv").exists()
