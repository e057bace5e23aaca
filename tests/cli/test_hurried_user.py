"""The edges a hurried user hits: the output format from -o's suffix, units in a checked file's header, a signal at
any moment of the start-up, a standard error closed early, values in the wrong unit, what `profile show` read, every
problem of a profile at once, `profile list/path/init`, NO_COLOR. One test (or more) per edge; each compares with an
independent reference where there is a number (the MCAP reader library, the same trajectory in SI units, a clean
run's bytes)."""

from __future__ import annotations

import json
import math
import os
import pty
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from pickplace_cli.cli import app
from pickplace_cli.model.profile import resolve_profile_path
from tests.terminal import stderr_on_terminal

runner = CliRunner()
ADEPT = ["--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8"]
CAP = 60.0


def run(*args, input=None, env=None):
    return runner.invoke(app, list(args), input=input, env=env)


def _cli(*args: str) -> list[str]:
    return [sys.executable, "-m", "pickplace_cli", *args]


# ------------------------------------------------------------------ the format from -o's suffix


def test_o_dot_mcap_writes_mcap(tmp_path):
    """`-o traj.mcap` wrote CSV; now MCAP, read back by the mcap library (the reference reader): one joint-state
    message per sample of the CSV written for the same move."""
    from mcap.reader import make_reader

    assert run("plan", *ADEPT, "-q", "-o", str(tmp_path / "t.mcap")).exit_code == 0
    assert run("plan", *ADEPT, "-q", "-o", str(tmp_path / "t.csv")).exit_code == 0
    n_samples = len((tmp_path / "t.csv").read_text().splitlines()) - 1
    with open(tmp_path / "t.mcap", "rb") as fh:
        counts: dict = {}
        for _schema, channel, _message in make_reader(fh).iter_messages():
            counts[channel.topic] = counts.get(channel.topic, 0) + 1
    assert n_samples in counts.values(), counts


def test_o_dot_json_writes_json(tmp_path):
    assert run("plan", *ADEPT, "-q", "-o", str(tmp_path / "t.json")).exit_code == 0
    doc = json.loads((tmp_path / "t.json").read_text())
    assert isinstance(doc, dict)


@pytest.mark.parametrize("fmt, out", [("mcap", "t.csv"), ("csv", "t.mcap"), ("json", "t.csv")])
def test_a_format_that_contradicts_the_suffix_is_refused(tmp_path, fmt, out):
    r = run("plan", *ADEPT, "-q", "-f", fmt, "-o", str(tmp_path / out))
    assert r.exit_code == 2
    assert f"-f {fmt} -o {tmp_path / out}: the file's suffix says" in r.stderr
    assert not (tmp_path / out).exists()


def test_a_dot_st_without_a_table_format_is_refused(tmp_path):
    """-o x.st names Structured Text but not which table the drive runs: refused (exit 2), nothing written; the
    trajectory's CSV under an .st name was written before. With -f pvt-st it is written."""
    r = run("plan", *ADEPT, "-q", "-o", str(tmp_path / "x.st"))
    assert r.exit_code == 2 and "-o " + str(tmp_path / "x.st") + ": the file's suffix says Structured Text" in r.stderr
    assert not (tmp_path / "x.st").exists()
    assert run("plan", *ADEPT, "-q", "-f", "pvt-st", "-o", str(tmp_path / "x.st")).exit_code == 0
    assert (tmp_path / "x.st").read_text().lstrip().startswith("(*")


def test_an_unknown_suffix_keeps_csv(tmp_path):
    assert run("plan", *ADEPT, "-q", "-o", str(tmp_path / "t.dat")).exit_code == 0
    assert (tmp_path / "t.dat").read_text().startswith("t[s],")


@pytest.mark.parametrize("suffix,first", [(".json", "{"), (".st", "(*"), (".csv", "# pickplace")])
def test_build_table_takes_the_format_from_the_suffix(tmp_path, suffix, first):
    out = tmp_path / f"t{suffix}"
    r = run("build-table", "--lambda-min", "10", "--lambda-max", "11", "--lambda-step", "1", "-q", "-o", str(out))
    assert r.exit_code == 0, r.stderr
    text = out.read_text()
    assert text.startswith(first), text[:80]
    if suffix == ".json":
        assert json.loads(text)["eta"] == 0.5


def test_compare_takes_the_format_from_the_suffix_and_refuses_a_contradiction(tmp_path):
    out = tmp_path / "c.json"
    r = run("compare", *ADEPT, "-m", "bspline", "-q", "-o", str(out))
    assert r.exit_code == 0 and json.loads(out.read_text())["profile"] == "delta-su2018"
    r = run("compare", *ADEPT, "-m", "bspline", "-f", "csv", "-o", str(tmp_path / "d.json"))
    assert r.exit_code == 2 and "suffix says json" in r.stderr and not (tmp_path / "d.json").exists()
    r = run("build-table", "-f", "json", "-o", str(tmp_path / "t.csv"))
    assert r.exit_code == 2 and "suffix says csv" in r.stderr and not (tmp_path / "t.csv").exists()


def test_binary_mcap_is_not_written_to_a_terminal():
    """stdout a terminal (a pseudo-terminal here): refused, exit 2, nothing written to it but the error's absence."""
    leader, follower = pty.openpty()
    try:
        r = subprocess.run(_cli("plan", *ADEPT, "-q", "-f", "mcap"), stdout=follower, stderr=subprocess.PIPE,
                           text=True, timeout=CAP)
    finally:
        os.close(follower)
        os.close(leader)
    assert r.returncode == 2 and "MCAP is binary; not written to a terminal" in r.stderr


# ------------------------------------------------------------------ units in a checked file's header


def _si_and_converted(tmp_path: Path, profile: str, units: tuple[str, ...], factors: tuple[float, ...],
                      move: list[str]) -> tuple[Path, Path]:
    import csv

    full = tmp_path / "full.csv"
    assert run("plan", *move, "-p", profile, "-q", "-o", str(full)).exit_code == 0
    rows = list(csv.reader(full.open()))
    head = rows[0]
    names = ["t"] + [f"q{k}" for k in range(1, len(units))]
    cols = [next(i for i, h in enumerate(head) if h.split("[")[0] == n) for n in names]
    # both files hold the time and the joint positions only (the same reconstruction of the motion): SI, converted
    si, conv = tmp_path / "si.csv", tmp_path / "conv.csv"
    for path, us, fs in ((si, ["s"] + ["rad"] * (len(units) - 1), [1.0] * len(units)), (conv, units, factors)):
        if path is si and profile == "scara-600":
            us[3] = "m"
        with path.open("w") as fh:
            fh.write(",".join(f"{n}[{u}]" for n, u in zip(names, us)) + "\n")
            for r in rows[1:]:
                fh.write(",".join(repr(float(r[c]) * f) for c, f in zip(cols, fs)) + "\n")
    return si, conv


@pytest.mark.parametrize("profile, units, factors, move", [
    ("delta-su2018", ("ms", "deg", "deg", "deg"), (1e3, 180 / math.pi, 180 / math.pi, 180 / math.pi), ADEPT),
    ("scara-600", ("ms", "deg", "deg", "mm", "deg"), (1e3, 180 / math.pi, 180 / math.pi, 1e3, 180 / math.pi),
     ["--from", "0.3,-0.2,-0.1", "--to", "0.3,0.2,-0.1", "--time", "0.8"]),
])
def test_check_honours_the_headers_units(tmp_path, profile, units, factors, move):
    """`t[ms],q1[deg],…` (and a SCARA's q3[mm]) was read as s and rad; it is converted: every limit row's peak agrees
    with the check of the same trajectory in SI units (reference) to 1e-6 relative (the file carries 12 digits and
    each conversion adds a rounding; the spline through the same points is the same)."""
    si, conv = _si_and_converted(tmp_path, profile, units, factors, move)
    a = run("check", str(si), "-p", profile, "-q", "--report", str(tmp_path / "a.json"))
    b = run("check", str(conv), "-p", profile, "-q", "--report", str(tmp_path / "b.json"))
    assert a.exit_code == b.exit_code == 0, b.output
    ra, rb = (json.loads((tmp_path / n).read_text())["limits"]["rows"] for n in ("a.json", "b.json"))
    assert [(r["joint"], r["quantity"]) for r in ra] == [(r["joint"], r["quantity"]) for r in rb]
    for x, y in zip(ra, rb):
        assert y["peak"] == pytest.approx(x["peak"], rel=1e-6, abs=1e-9), (x, y)


@pytest.mark.parametrize("header, word", [("t[s],q1[rpm],q2,q3", "q1 is read in rad, deg or °"),
                                          ("t[min],q1,q2,q3", "t is read in s, ms, us or µs")])
def test_check_refuses_a_unit_it_cannot_convert(tmp_path, header, word):
    f = tmp_path / "u.csv"
    f.write_text(header + "\n" + "".join(f"{k * 0.01},0.1,0.2,0.3\n" for k in range(8)))
    r = run("check", str(f))
    assert r.exit_code == 1 and word in r.stderr and len(r.stderr.splitlines()) == 1


# ------------------------------------------------------------------ a signal at any moment of the start-up


HOOK = """
import builtins, os, signal, sys
import pickplace_cli.__main__ as entry
sys.argv = ["pickplace", "--version"]
real = builtins.__import__
sent = []
def hook(name, *args, **kwargs):
    if name == {module!r} and not sent:  # (the CLI's own modules import each other relatively: "app" is cli/app.py)
        sent.append(1)
        os.kill(os.getpid(), signal.{sig})
    return real(name, *args, **kwargs)
builtins.__import__ = hook
entry.main()
"""


@pytest.mark.parametrize("sig, code, line", [("SIGINT", 130, "interrupted"), ("SIGTERM", 143, "terminated (SIGTERM)")])
@pytest.mark.parametrize("module", ["typer", "app"])
def test_a_signal_while_the_cli_is_imported_is_one_line(sig, code, line, module):
    """The signal is sent at the moment the start-up imports ``module`` (typer's 0.1–0.2 s; deterministic: no timing):
    one line, exit 130 or 143 (it was a KeyboardInterrupt traceback, or rc −15)."""
    r = subprocess.run([sys.executable, "-c", HOOK.format(module=module, sig=sig)], capture_output=True, text=True,
                       timeout=CAP)
    assert r.returncode == code, r.stderr
    assert r.stderr == f"pickplace: error: {line}; no output file was changed\n"


def test_ctrl_c_while_typer_parses_is_one_line_not_a_silent_130():
    """Ctrl-C while typer resolves the command (outside any command, where typer turns it into a silent exit 130)."""
    code = (
        "import os, signal, sys\nimport pickplace_cli.__main__ as entry\nimport typer.core as core\n"
        "real = core.TyperGroup.resolve_command\n"
        "def hook(self, ctx, args):\n    os.kill(os.getpid(), signal.SIGINT)\n    return real(self, ctx, args)\n"
        "core.TyperGroup.resolve_command = hook\nsys.argv = ['pickplace', 'profile', 'list']\nentry.main()\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=CAP)
    assert r.returncode == 130
    assert r.stderr == "pickplace: error: interrupted; no output file was changed\n"


# ------------------------------------------------------------------ stderr closed early


def test_a_closed_stderr_loses_the_messages_not_the_file(tmp_path):
    """`plan … -o e.csv 2>&1 | head -3`: the reader of stderr goes away; e.csv is written all the same, byte for byte
    as without the pipe (reference run), exit 0 (it was exit 1 and no file)."""
    ref = tmp_path / "ref.csv"
    assert subprocess.run(_cli("plan", *ADEPT, "-o", str(ref)), capture_output=True, timeout=CAP).returncode == 0
    r, w = os.pipe()
    os.close(r)  # nobody reads stderr: every write to it fails with a broken pipe
    try:
        proc = subprocess.run(_cli("plan", *ADEPT, "-o", str(tmp_path / "e.csv")), stderr=w, timeout=CAP)
    finally:
        os.close(w)
    assert proc.returncode == 0
    assert (tmp_path / "e.csv").read_bytes() == ref.read_bytes()


def test_head_of_a_merged_pipe_keeps_the_file(tmp_path):
    """The literal reproducer, through a shell: `2>&1 | head -3`."""
    cmd = " ".join(_cli("plan", *ADEPT, "-o", str(tmp_path / "e.csv")))
    r = subprocess.run(["bash", "-c", f"set -o pipefail; {cmd} 2>&1 | head -3 >/dev/null; echo ${{PIPESTATUS[0]}}"],
                       capture_output=True, text=True, timeout=CAP)
    assert r.stdout.strip().splitlines()[-1] == "0"
    assert (tmp_path / "e.csv").read_text().startswith("t[s],")


# ------------------------------------------------------------------ values in the wrong unit


def test_time_in_milliseconds_is_a_warning(tmp_path):
    """`--time 180` (ms meant) is planned as 180 s (a slow move can be meant), with a warning naming the unit."""
    r = run("plan", *ADEPT, "-q", "--time", "180", "--rate", "10", "-o", str(tmp_path / "t.csv"))
    assert r.exit_code == 0
    assert "pickplace: warning: --time 180: a 180 s move; milliseconds meant? --time 0.18" in r.stderr


@pytest.mark.parametrize("args, word", [
    (["--from", "-152.5,0,-800", "--to", "0.1525,0,-0.8"], "millimetres meant? in metres: --from -0.1525,0,-0.8"),
    (["--from", "-0.1525,0,-0.8", "--to", "152.5,0,-800"], "millimetres meant? in metres: --to 0.1525,0,-0.8"),
    ([*ADEPT, "--height", "25"], "millimetres meant? --height 0.025"),
])
def test_points_and_height_in_millimetres_are_refused(tmp_path, args, word):
    """A point or a height that lies outside the workcell box in metres but inside it in millimetres cannot be
    meant: refused before any work, exit 1, one line naming the likely unit and the value in metres."""
    r = run("plan", *args, "-q", "-o", str(tmp_path / "t.csv"))
    assert r.exit_code == 1 and word in r.stderr and len(r.stderr.splitlines()) == 1
    assert not (tmp_path / "t.csv").exists()


@pytest.mark.parametrize("engine", [True, False])
def test_batch_cells_in_millimetres_are_that_row_s_error(tmp_path, engine):
    """The same rules for a batch row's cells (the verdict engine's rows too): that row's one line, exit 1, naming
    the cells and the values in metres; the other rows are answered."""
    src = tmp_path / "b.csv"
    src.write_text("from_x,from_y,from_z,to_x,to_y,to_z,height\n-0.1525,0,-0.8,0.1525,0,-0.8,\n"
                   "-152.5,0,-800,152.5,0,-800,\n-0.1525,0,-0.8,0.1525,0,-0.8,25\n")
    env = None if engine else {"PICKPLACE_NO_VERDICT_ENGINE": "1"}
    r = run("plan", "--batch", str(src), "--json", "-q", env=env)
    rows = [json.loads(line) for line in r.stdout.splitlines()]
    assert [x["exit_code"] for x in rows] == [0, 1, 1]
    assert "from_x,from_y,from_z = -152.5,0,-800" in rows[1]["error"] and "in metres: -0.1525,0,-0.8" in rows[1]["error"]
    assert "height = 25 m" in rows[2]["error"] and "millimetres meant? 0.025" in rows[2]["error"]


def test_a_real_far_point_is_not_called_millimetres(tmp_path):
    """A point merely outside the workspace (not a millimetre value) keeps its own error: exit 4, no unit hint."""
    r = run("plan", "--from", "-0.5,0,-0.9", "--to", "0.5,0,-0.9", "-q", "-o", str(tmp_path / "t.csv"))
    assert "millimetres" not in r.stderr


def test_a_rate_that_gives_a_handful_of_samples_is_a_warning(tmp_path):
    """`--rate 30` for the 0.18 s Adept move: a handful of samples (the CSV has them: reference), a warning naming
    kHz; `--rate 10` (3 samples, fewer than check reads a move from) is refused, naming the least rate, no file."""
    r = run("plan", *ADEPT, "-q", "--rate", "30", "-o", str(tmp_path / "t.csv"))
    assert r.exit_code == 0
    n = len((tmp_path / "t.csv").read_text().splitlines()) - 1
    assert 6 <= n < 20
    assert f"pickplace: warning: --rate 30 Hz: {n} samples for a " in r.stderr and "kHz meant?" in r.stderr
    r = run("plan", *ADEPT, "-q", "--rate", "10", "-o", str(tmp_path / "u.csv"))
    assert r.exit_code == 1 and not (tmp_path / "u.csv").exists()
    assert "pickplace: error: --rate 10 Hz: 3 samples for a 0.18 s move" in r.stderr


def _edited(tmp_path: Path, old: str, new: str, name: str = "delta-su2018") -> Path:
    text = resolve_profile_path(name).read_text()
    assert old in text
    p = tmp_path / "p.yaml"
    p.write_text(text.replace(old, new))
    return p


def test_a_motor_speed_in_rpm_is_refused(tmp_path):
    """`max_speed: 3000` (rpm meant, read as 3000 rad/s = 28,648 rpm: the speed limit would never bind)."""
    p = _edited(tmp_path, "max_speed: 628.3 ", "max_speed: 3000 ")
    r = run("profile", "validate", str(p))
    assert r.exit_code == 1
    assert "max_speed = 3000 rad/s (every joint) is 28,648 rpm: rpm meant? 3000 rpm = 314.2 rad/s" in r.stderr


def test_a_fast_but_possible_motor_speed_is_a_warning(tmp_path):
    p = _edited(tmp_path, "max_speed: 628.3 ", "max_speed: 1500 ")
    r = run("profile", "validate", str(p))
    assert r.exit_code == 0 and "pickplace: warning:" in r.stderr and "14,324 rpm" in r.stderr


def test_a_joint_range_in_degrees_is_refused(tmp_path):
    """`position: [-40, 90]` (degrees, read as radians: 14 turns) — the value converted is the shipped one (reference)."""
    p = _edited(tmp_path, "position: [-0.6981317, 1.5707963]", "position: [-40, 90]")
    r = run("plan", *ADEPT, "-p", str(p), "-q")
    assert r.exit_code == 1
    assert "degrees meant? [-40, 90] deg = [-0.6981, 1.5708] rad" in r.stderr


def test_a_stroke_in_millimetres_is_refused(tmp_path):
    p = _edited(tmp_path, "position: [-0.2, 0.0]", "position: [-200, 0.0]", "scara-600")
    r = run("profile", "validate", str(p))
    assert r.exit_code == 1 and "millimetres meant? [-200, 0] mm = [-0.2, 0] m" in r.stderr


@pytest.mark.parametrize("name", ["delta-su2018", "scara-600", "gantry"])
def test_the_shipped_profiles_have_no_unit_warning(name):
    r = run("profile", "validate", name)
    assert r.exit_code == 0 and r.stderr == ""


# ------------------------------------------------------------------ profiles: show, errors, list, path, init


def test_profile_show_prints_the_numbers_it_read(tmp_path):
    """An edited copy (R 0.2 m, plate 0.7 kg) still showed "R = 150 mm …" from its free-text description: the geometry
    and masses line come from the fields read."""
    p = _edited(tmp_path, "R: 0.150 ", "R: 0.200 ")
    p.write_text(p.read_text().replace("plate: 0.40 ", "plate: 0.70 "))
    r = run("profile", "show", str(p))
    assert r.exit_code == 0
    assert "geometry: R = 0.2 m, r = 0.051 m, L = 0.325 m, l = 0.8 m" in r.stdout
    assert "plate 0.7 kg" in r.stdout and "description (free text, not read by the model)" in r.stdout


@pytest.mark.parametrize("name, word", [("scara-600", "link 1 length 0.325 m, mass 8 kg"),
                                        ("gantry", "x travel [-1, 1] m")])
def test_profile_show_other_kinds(name, word):
    r = run("profile", "show", name)
    assert r.exit_code == 0 and word in r.stdout


def test_a_profile_error_lists_every_problem_unknown_key_first(tmp_path):
    p = _edited(tmp_path, "gear_ratio: 25.0", "gear_raito: 25.0")
    p.write_text(p.read_text().replace("efficiency: 0.9", "efficiency: 1.9").replace("  eta: 0.5", "  eta: 1.5"))
    r = run("profile", "validate", str(p))
    assert r.exit_code == 1
    lines = r.stderr.splitlines()
    assert all(ln.startswith("pickplace: error: ") for ln in lines)
    assert "unknown key 'robot.joints.drive.gear_raito': did you mean 'gear_ratio'?" in lines[0]
    text = r.stderr
    assert "gear_ratio: required field is missing" in text and "efficiency = 1.9" in text and "planning.eta = 1.5" in text
    assert len(lines) == 4


def test_profile_list_path_and_init(tmp_path):
    from pickplace_cli.model.profile import shipped_profiles, load_profile

    r = run("profile", "list")
    assert r.exit_code == 0
    names = [ln.split("\t")[0] for ln in r.stdout.splitlines()]
    assert names == sorted(shipped_profiles())
    path = run("profile", "path", "gantry").stdout.strip()
    assert Path(path).read_text() == resolve_profile_path("gantry").read_text()
    mine = tmp_path / "mine.yaml"
    assert run("profile", "init", "scara-600", str(mine)).exit_code == 0
    assert load_profile(str(mine)) == load_profile("scara-600")
    again = run("profile", "init", "scara-600", str(mine))
    assert again.exit_code == 1 and "exists" in again.stderr


# ------------------------------------------------------------------ NO_COLOR


@pytest.mark.parametrize("no_color", [None, "1"])
def test_no_color_means_no_ansi_styling(no_color):
    """On a terminal (a pseudo-terminal) the limit table of a move that breaks a limit is styled (bold, red); with
    NO_COLOR set there is no escape sequence at all."""
    out = stderr_on_terminal(_cli("plan", *ADEPT, "--time", "0.1", "-o", os.devnull), no_color, CAP)
    assert b"EXCEEDED" in out
    assert (b"\x1b[" in out) is (no_color is None)
