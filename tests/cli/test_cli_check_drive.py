"""`pickplace check` on files whose derivative columns or units cannot be believed, and on the drive's files: exit
codes and one-line messages naming the column, the value and the rule."""

from __future__ import annotations

import pytest
from typer.testing import CliRunner

from pickplace_cli.cli import app

runner = CliRunner()
ADEPT = ("--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8")
DERIVATIVES = ("vx", "vy", "vz", "ax", "ay", "az", "jx", "jy", "jz")


def run(*args):
    return runner.invoke(app, list(args), catch_exceptions=False)


@pytest.fixture(scope="module")
def adept_fast(tmp_path_factory):
    """The Adept move in 0.06 s, written anyway (motor torque 284.8 %, torque rate over 1000 %)."""
    out = tmp_path_factory.mktemp("fast") / "fast.csv"
    assert run("plan", *ADEPT, "--time", "0.06", "--write-anyway", "-q", "-o", str(out)).exit_code in (0, 3)
    assert out.stat().st_size
    return out.read_text()


@pytest.fixture(scope="module")
def adept(tmp_path_factory):
    out = tmp_path_factory.mktemp("ok") / "adept.csv"
    assert run("plan", *ADEPT, "-q", "-o", str(out)).exit_code == 0
    return out.read_text()


def _zeroed(text: str) -> str:
    lines = text.splitlines()
    head = [h.split("[")[0] for h in lines[0].split(",")]
    out = [lines[0]]
    for ln in lines[1:]:
        cells = ln.split(",")
        out.append(",".join("0" if head[i] in DERIVATIVES else c for i, c in enumerate(cells)))
    return "\n".join(out) + "\n"


def test_zeroed_derivative_columns_are_not_believed(tmp_path, adept_fast):
    """The over-limit move with its vx … jz set to zero: judged from its positions (exit 3), one warning line naming
    the columns and the rule."""
    f = tmp_path / "zero.csv"
    f.write_text(_zeroed(adept_fast))
    res = run("check", str(f), "-q")
    assert res.exit_code == 3
    warn = [ln for ln in res.stderr.splitlines() if "warning" in ln]
    assert len(warn) == 1 and "vx, vy, vz" in warn[0] and "allowed 1 %" in warn[0] and "positions" in warn[0]
    assert "motor torque" in res.stderr


def test_zeroed_derivative_columns_refused_under_strict(tmp_path, adept_fast):
    f = tmp_path / "zero.csv"
    f.write_text(_zeroed(adept_fast))
    res = run("check", str(f), "-q", "--strict")
    assert res.exit_code == 1
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "vx, vy, vz disagree with the positions by 100 %" in lines[0] and "--strict" in lines[0]


def test_time_header_in_ms_over_seconds_is_caught(tmp_path, adept):
    """The Adept move's times relabelled t[ms] (a 0.18 ms move whose tool columns still say 0.18 s): its derivative
    columns disagree, it is judged from its positions and exceeds every rate (exit 3)."""
    f = tmp_path / "ms.csv"
    f.write_text(adept.replace("t[s]", "t[ms]", 1))
    res = run("check", str(f), "-q")
    assert res.exit_code == 3
    assert "warning" in res.stderr and "vx, vy, vz" in res.stderr


def test_time_header_in_ms_with_ms_values_is_read(tmp_path, adept):
    """The same move with its times written in ms under t[ms]: read as seconds, accepted (exit 0, no warning)."""
    lines = adept.splitlines()
    out = [lines[0].replace("t[s]", "t[ms]", 1)]
    for ln in lines[1:]:
        c = ln.split(",")
        c[0] = repr(float(c[0]) * 1000)
        out.append(",".join(c))
    f = tmp_path / "ms.csv"
    f.write_text("\n".join(out) + "\n")
    res = run("check", str(f), "-q")
    assert res.exit_code == 0, res.stderr
    assert "warning" not in res.stderr


@pytest.mark.parametrize("header,words", [("t[h]", "t is read in s, ms"), ("t[min]", "t is read in s, ms")])
def test_time_in_unknown_units_is_refused(tmp_path, adept, header, words):
    f = tmp_path / "u.csv"
    f.write_text(adept.replace("t[s]", header, 1))
    res = run("check", str(f), "-q")
    assert res.exit_code == 1
    assert len(res.stderr.strip().splitlines()) == 1 and words in res.stderr


def test_plc_feed_is_read_with_the_profile(tmp_path):
    """plan --columns plc (t and the drives' counts): accepted with the profile that names the drives; with another
    profile one line says which columns were looked for."""
    f = tmp_path / "plc.csv"
    assert run("plan", *ADEPT, "--columns", "plc", "--csv-dialect", "twincat", "-q", "-o", str(f)).exit_code == 0
    assert run("check", str(f), "-q").exit_code == 0
    res = run("check", str(f), "-p", "scara-600", "-q")
    assert res.exit_code == 1 and "J1" in res.stderr and "A1" in res.stderr


def test_drive_unit_mismatch_names_the_column(tmp_path):
    f = tmp_path / "plc.csv"
    assert run("plan", *ADEPT, "--columns", "plc", "-q", "-o", str(f)).exit_code == 0
    f.write_text(f.read_text().replace("A2[counts]", "A2[deg]", 1))
    res = run("check", str(f), "-q")
    assert res.exit_code == 1 and "A2[deg]" in res.stderr and "counts" in res.stderr


def test_tsv_without_header_is_one_line(tmp_path):
    f = tmp_path / "p.tsv"
    assert run("plan", *ADEPT, "--columns", "plc", "--csv-dialect", "tsv", "-q", "-o", str(f)).exit_code == 0
    res = run("check", str(f), "-q")
    assert res.exit_code == 1 and "no header line" in res.stderr and len(res.stderr.strip().splitlines()) == 1


def test_pvt_with_inconsistent_dt_is_refused(tmp_path):
    f = tmp_path / "p.csv"
    assert run("plan", *ADEPT, "--format", "pvt", "-q", "-o", str(f)).exit_code == 0
    lines = f.read_text().splitlines()
    c = lines[3].split(",")
    c[1] = repr(float(c[1]) * 2)
    lines[3] = ",".join(c)
    f.write_text("\n".join(lines) + "\n")
    res = run("check", str(f), "-q")
    assert res.exit_code == 1 and ":4: dt =" in res.stderr and "segment times" in res.stderr
