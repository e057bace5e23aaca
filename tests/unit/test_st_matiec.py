"""Every Structured Text the project writes, compiled by matiec (``iec2c``, the IEC 61131-3 compiler of Beremiz/OpenPLC)
with no error, and the C it generates compiled by gcc and run in a small harness written here:

* the 1-D and 2-D look-ups (``build-table -f st``) on thousands of points, bit for bit equal to the ST's arithmetic
  transcribed in Python (``test_st_strict``) and to ``Table.lookup`` / ``Table2D.lookup`` within 1e-12;
* the tables for a motion kernel (``plan -f pvt-st|cam-st|cam-table-st``: time and belt master, the 4-axis Delta, a
  round trip): the function block's arrays equal to the table's columns, and the kernel's interpolation evaluated
  in C on the arrays (written here: cubic Hermite, the quintic's Hermite basis, linear) within 1e-12 of Python's.

matiec is looked for at ``../shared/tools/matiec`` beside the repository (for a git worktree, beside its main clone
too); without it these tests are skipped, saying where it was looked for.
"""

from __future__ import annotations

import math
import re
import shutil
import subprocess
from functools import lru_cache
from pathlib import Path

import numpy as np
import pytest

from pickplace_cli.export.table2d_st import format_table_2d_st
from pickplace_cli.export.table_st import format_table_st
from pickplace_cli.lookup.bspline_table import load_table
from pickplace_cli.lookup.table2d import TableJumpError, load_table_2d
from pickplace_cli.model.errors import TableError

from .test_st_strict import lookup_1d_as_st, lookup_2d_as_st, st_arrays

ROOT = Path(__file__).resolve().parents[2]


def _matiec_candidates() -> list[Path]:
    out = [ROOT / ".." / "shared" / "tools" / "matiec"]
    git = ROOT / ".git"
    if git.is_file():  # a git worktree: ``gitdir: <main clone>/.git/worktrees/<name>``
        gitdir = Path(git.read_text().split(":", 1)[1].strip())
        common = gitdir / (gitdir / "commondir").read_text().strip() if (gitdir / "commondir").is_file() else gitdir
        out.append(common.resolve().parent / ".." / "shared" / "tools" / "matiec")
    return out


MATIEC = next((p for p in _matiec_candidates() if (p / "iec2c").is_file()), None)
GCC = shutil.which("gcc")
pytestmark = [
    pytest.mark.skipif(MATIEC is None, reason="matiec (iec2c) not found at "
                       + " or ".join(str(p) for p in _matiec_candidates())),
    pytest.mark.skipif(GCC is None, reason="gcc not found on PATH"),
]


def iec2c(text: str, out: Path) -> tuple[int, str]:
    """Compile the ST ``text`` with matiec into ``out`` → (exit code, its messages)."""
    out.mkdir(parents=True, exist_ok=True)
    src = out / "src.st"
    src.write_text(text)
    res = subprocess.run([str(MATIEC / "iec2c"), "-I", str(MATIEC / "lib"), "-T", str(out), str(src)],
                         capture_output=True, text=True)
    return res.returncode, res.stdout + res.stderr


def compile_ok(text: str, out: Path) -> None:
    code, msg = iec2c(text, out)
    errors = [line for line in msg.splitlines() if "error" in line.lower()]
    assert code == 0 and not errors, (code, len(errors), errors[:5])
    assert (out / "POUS.c").is_file()


def run_c(out: Path, body: str, stdin: str = "") -> str:
    """Build ``body`` (C statements of main) against the compiled POUS.c and run it; → its standard output.
    -ffp-contract=off: no fused multiply-add, so the C does each IEC operation as one rounded double operation."""
    harness = out / "harness.c"
    harness.write_text('#include <stdio.h>\n#include <stdlib.h>\n#include "POUS.h"\n#include "POUS.c"\n'
                       "TIME __CURRENT_TIME;\nBOOL __DEBUG;\n" + body)
    exe = out / "harness"
    subprocess.run([GCC, "-std=gnu99", "-O1", "-ffp-contract=off", "-I", str(MATIEC / "lib" / "C"), "-I", str(out),
                    "-o", str(exe), str(harness), "-lm"], check=True, capture_output=True, text=True)
    return subprocess.run([str(exe)], input=stdin, capture_output=True, text=True, check=True).stdout


# --------------------------------------------------------------------------------------------- the compiler


def test_matiec_is_strict_about_var_after_var_constant(tmp_path):
    """The quirk the writers avoid: a VAR after a VAR CONSTANT is taken as constant (so the tests can fail)."""
    bad = ("FUNCTION F_Q : LREAL\nVAR_INPUT fX : LREAL; END_VAR\nVAR CONSTANT C_A : LREAL := 2.0; END_VAR\n"
           "VAR fW : LREAL; END_VAR\nfW := fX * C_A;\nF_Q := fW;\nEND_FUNCTION\n")
    code, msg = iec2c(bad, tmp_path / "bad")
    assert code != 0 and "Assignment to CONSTANT" in msg
    good = bad.replace("VAR CONSTANT C_A : LREAL := 2.0; END_VAR\nVAR fW : LREAL; END_VAR\n",
                       "VAR fW : LREAL; END_VAR\nVAR CONSTANT C_A : LREAL := 2.0; END_VAR\n")
    compile_ok(good, tmp_path / "good")


# -------------------------------------------------------------------------------------------- the look-ups

_LOOKUP_1D = """
int main(void) {
    char line[128];
    while (fgets(line, sizeof line, stdin)) {
        LREAL k1 = -1.0, k2 = -1.0;
        BOOL ok = F_PICKPLACEK(1, NULL, strtod(line, NULL), &k1, &k2);
        printf("%d %a %a\\n", (int)ok, k1, k2);
    }
    return 0;
}
"""
_LOOKUP_2D = """
int main(void) {
    char line[256];
    while (fgets(line, sizeof line, stdin)) {
        char *rest;
        double lam = strtod(line, &rest), eta = strtod(rest, NULL);
        LREAL k1 = -1.0, k2 = -1.0;
        BOOL ok = F_PICKPLACEK2D(1, NULL, lam, eta, &k1, &k2);
        printf("%d %a %a\\n", (int)ok, k1, k2);
    }
    return 0;
}
"""


def _results(stdout: str) -> list[tuple[bool, float, float]]:
    return [(line.split()[0] == "1", float.fromhex(line.split()[1]), float.fromhex(line.split()[2]))
            for line in stdout.splitlines()]


def test_1d_lookup_compiled_by_matiec_and_gcc_is_bit_exact(tmp_path):
    """The shipped table (79 rows): λ on 5,000 random points, every row, every midpoint, outside both ends and NaN.
    Bit for bit the ST's own arithmetic (each IEC operation one IEEE double operation in the same order: tolerance
    0); within 1e-12 of ``Table.lookup`` (k ≤ 1; the same line in another order of operations, a few ulp apart)."""
    table = load_table()
    text = format_table_st(table, "TEST")
    compile_ok(text, tmp_path)
    arr = st_arrays(text)
    L, K1, K2 = arr["PP_TABLE_LAMBDA"], arr["PP_TABLE_K1"], arr["PP_TABLE_K2"]
    rng = np.random.default_rng(61)
    xs = [float(x) for x in np.concatenate([rng.uniform(table.lam[0], table.lam[-1], 5000), table.lam,
                                            (table.lam[1:] + table.lam[:-1]) / 2])]
    xs += [float(table.lam[0]) - 1.0, float(table.lam[-1]) + 1.0, math.nan]
    got = _results(run_c(tmp_path, _LOOKUP_1D, "".join(f"{x.hex() if x == x else 'nan'}\n" for x in xs)))
    assert len(got) == len(xs)
    worst = 0.0
    for x, (ok, k1, k2) in zip(xs, got):
        assert (ok, k1, k2) == lookup_1d_as_st(x, L, K1, K2), x
        if table.lam[0] <= x <= table.lam[-1]:
            r1, r2 = table.lookup(x)
            worst = max(worst, abs(k1 - r1), abs(k2 - r2))
    assert worst <= 1e-12, worst
    rows = got[5000:5000 + len(table.lam)]  # at a row: that row's values exactly
    assert [r[1] for r in rows] == table.column("k1").tolist() and [r[2] for r in rows] == table.column("k2").tolist()
    assert got[-3][0] is False and got[-2][0] is False and got[-1] == (False, K1[1], K2[1])


def test_2d_lookup_compiled_by_matiec_and_gcc_is_bit_exact(tmp_path):
    """The shipped 2-D table on 6,000 random (λ, η), its nodes and points outside: bit for bit the ST's arithmetic
    (tolerance 0, as above), within 1e-12 of ``Table2D.lookup`` where it interpolates, FALSE where it refuses (a
    basin jump) or outside."""
    table = load_table_2d()
    text = format_table_2d_st(table, "TEST")
    compile_ok(text, tmp_path)
    arr = st_arrays(text)
    rng = np.random.default_rng(62)
    pts = list(zip(rng.uniform(table.lams[0], table.lams[-1], 6000).tolist(),
                   rng.uniform(table.etas[0], table.etas[-1], 6000).tolist()))
    pts += [(float(a), float(e)) for e in table.etas for a in table.lams]
    pts += [(table.lams[-1] + 1.0, table.etas[0]), (table.lams[0], table.etas[0] - 0.05)]
    got = _results(run_c(tmp_path, _LOOKUP_2D, "".join(f"{a.hex()} {e.hex()}\n" for a, e in pts)))
    assert len(got) == len(pts)
    worst, checked = 0.0, 0
    for (lam, eta), res in zip(pts, got):
        assert res == lookup_2d_as_st(lam, eta, arr, "PP_TABLE2D"), (lam, eta)
        try:
            r1, r2 = table.lookup(lam, eta)
        except (TableJumpError, TableError):  # a jump cell or outside: the ST says FALSE
            assert not res[0], (lam, eta)
            continue
        assert res[0]
        worst = max(worst, abs(res[1] - r1), abs(res[2] - r2))
        checked += 1
    assert checked >= 5000 and worst <= 1e-12, (checked, worst)
    assert not got[-1][0] and not got[-2][0]


# ------------------------------------------------------------------------- every ST file the CLI writes


def _cli(*args: str) -> None:
    from typer.testing import CliRunner

    from pickplace_cli.cli import app

    res = CliRunner().invoke(app, list(args), catch_exceptions=False)
    assert res.exit_code == 0, (args, res.stderr)


ADEPT = ("--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8")
BELT = ("--from", "-0.1525,0,-0.8", "--to", "0.05,0.1,-0.8", "--to-belt", "0.3,0,0", "--latency", "0.05")
D4 = ("-p", "delta-4axis", "--from", "-0.15,0,-0.8,0", "--to", "0.15,0,-0.8,1.2")
#: name → plan arguments of each table export (each written as CSV too, the columns the ST must hold)
PLANS = {
    "pvt": (*ADEPT, "-f", "pvt-st"),
    "cam": (*ADEPT, "-f", "cam-st"),
    "cam-table": (*ADEPT, "-f", "cam-table-st", "--tolerance", "1e-4"),
    "pvt-round-trip": (*ADEPT, "--round-trip", "--cycle", "0.001", "-f", "pvt-st"),
    # (a belt leg's table ends moving with the belt: with the drive holding its last point plan refuses it, exit 3;
    # these say the controller goes on with the belt after it; the equidistant one's lines then still read the
    # capacity's acceleration 0.1 % over, and a conveyor move is not re-timed: the compile test writes it anyway)
    "cam-belt": (*BELT, "-f", "cam-st", "--cam-master", "belt", "--tolerance", "1e-5", "--table-end", "continue"),
    "cam-table-belt": (*BELT, "-f", "cam-table-st", "--cam-master", "belt", "--tolerance", "1e-4", "--table-end",
                       "continue", "--write-anyway"),
    "pvt-delta-4axis": (*D4, "-f", "pvt-st"),
    "cam-delta-4axis": (*D4, "-f", "cam-st"),
    "pvt-integer": (*ADEPT, "--round-trip", "--cycle", "0.001", "-f", "pvt-st", "--pvt-integer"),
}


@lru_cache(maxsize=None)
def _plan_files(name: str, folder: str) -> tuple[str, list[list[str]], list[str]]:
    """(ST text, the CSV table's rows as text, its column names) of one export, written by ``pickplace plan``."""
    args = PLANS[name]
    st, csv = Path(folder) / f"{name}.st", Path(folder) / f"{name}.csv"
    _cli("plan", *args, "-q", "-o", str(st))
    fmt = args[args.index("-f") + 1]
    csv_args = list(args)
    csv_args[args.index("-f") + 1] = fmt[:-3]
    _cli("plan", *csv_args, "-q", "-o", str(csv))
    lines = csv.read_text().splitlines()
    names = [h.split("[")[0] for h in lines[0].split(",")]
    data = [line.split(",") for line in lines[1:]]
    return st.read_text(), data, names


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> str:
    return str(tmp_path_factory.mktemp("plans"))


def test_build_table_st_from_the_cli_compiles(tmp_path):
    """build-table -f st, 1-D and 2-D (tiny grids), strict dialect: 0 errors (the 2-D one crosses a basin jump)."""
    one, two = tmp_path / "t1.st", tmp_path / "t2.st"
    _cli("build-table", "--lambda-min", "4", "--lambda-max", "6", "--lambda-step", "1", "-j", "1", "-q", "-o", str(one))
    _cli("build-table", "--lambda-min", "2", "--lambda-max", "4", "--lambda-points", "2", "--eta-list", "0.3,0.5",
         "-j", "1", "-q", "--st-dialect", "strict", "-o", str(two))
    for path in (one, two):
        text = path.read_text()
        assert "VAR CONSTANT" in text and text.index("\nVAR\n") < text.index("VAR CONSTANT")
        compile_ok(text, tmp_path / path.stem)


_KINDS = {"FB_PICKPLACEPVT": "pvt", "FB_PICKPLACECAM": "cam", "FB_PICKPLACECAMTABLE": "cam-table"}


def _fb_harness(fb: str, arrays: list[str], joints: list[str], x: str, x_scale: float) -> str:
    """C main: init and run a static instance (matiec's initialiser), print nPoints, each array, then the kernel's
    interpolation at s = 1/4, 1/2, 3/4 of every segment, per joint (``%a``: exact doubles); the master ``x`` times
    ``x_scale`` is in the unit of the velocities' denominator (ms → s: 1e-3)."""
    kind = _KINDS[fb]
    lines = [f"static {fb} fb;", "static void seg(int k, int n) {", "    static const double S[3] = {0.25, 0.5, 0.75};",
             f"    double x0 = fb.{x}.value.table[k] * {x_scale!r}, x1 = fb.{x}.value.table[k + 1] * {x_scale!r};",
             "    double h = x1 - x0;",
             "    for (int m = 0; m < 3; m++) {", "        double s = S[m];"]
    for j in joints:
        p = f"fb.{j}_POS.value.table"
        if kind == "pvt":
            v = f"fb.{j}_VEL.value.table"
            expr = (f"(2*s*s*s - 3*s*s + 1) * {p}[k] + (s*s*s - 2*s*s + s) * h * {v}[k]"
                    f" + (-2*s*s*s + 3*s*s) * {p}[k + 1] + (s*s*s - s*s) * h * {v}[k + 1]")
        elif kind == "cam":  # the quintic's Hermite basis
            v, a = f"fb.{j}_VEL.value.table", f"fb.{j}_ACC.value.table"
            expr = ("(1 - 10*s*s*s + 15*s*s*s*s - 6*s*s*s*s*s) * " + f"{p}[k]"
                    " + (s - 6*s*s*s + 8*s*s*s*s - 3*s*s*s*s*s) * h * " + f"{v}[k]"
                    " + 0.5 * (s*s - 3*s*s*s + 3*s*s*s*s - s*s*s*s*s) * h * h * " + f"{a}[k]"
                    " + 0.5 * (s*s*s - 2*s*s*s*s + s*s*s*s*s) * h * h * " + f"{a}[k + 1]"
                    " + (-4*s*s*s + 7*s*s*s*s - 3*s*s*s*s*s) * h * " + f"{v}[k + 1]"
                    " + (10*s*s*s - 15*s*s*s*s + 6*s*s*s*s*s) * " + f"{p}[k + 1]")
        else:
            expr = f"(1 - s) * {p}[k] + s * {p}[k + 1]"
        lines.append(f'        printf("%a ", {expr});')
    lines += ['        printf("\\n");', "    }", "}", "int main(void) {", f"    {fb}_init__(&fb, 0);",
              f"    {fb}_body__(&fb);", "    int n = fb.NPOINTS.value;", '    printf("%d\\n", n);']
    for name in arrays:
        lines.append(f'    for (int i = 0; i < n; i++) printf("%a ", (double)fb.{name}.value.table[i]);\n    printf("\\n");')
    lines += ["    for (int k = 0; k + 1 < n; k++) seg(k, n);", "    return 0;", "}"]
    return "\n".join(lines) + "\n"


def _python_interpolation(kind: str, cols: dict[str, np.ndarray], joints: list[str], x_scale: float) -> np.ndarray:
    """The same points by the exporter's own formulas (knots.hermite3 / knots.quintic; linear)."""
    from pickplace_cli.export.knots import hermite3, quintic

    x = cols["t" if kind == "pvt" else "master"] * x_scale
    out = []
    for k in range(len(x) - 1):
        at = x[k] + np.array([0.25, 0.5, 0.75]) * (x[k + 1] - x[k])
        row = []
        for j in joints:
            p = cols[j]
            if kind == "pvt":
                v = cols[f"{j}_vel"]
                row.append(hermite3(x[k], x[k + 1], p[k:k + 1], v[k:k + 1], p[k + 1:k + 2], v[k + 1:k + 2], at)[:, 0])
            elif kind == "cam":
                v, a = cols[f"{j}_vel"], cols[f"{j}_acc"]
                row.append(quintic(x[k], x[k + 1], p[k:k + 1], v[k:k + 1], a[k:k + 1], p[k + 1:k + 2],
                                   v[k + 1:k + 2], a[k + 1:k + 2], at)[:, 0])
            else:
                row.append(np.interp(at, x[k:k + 2], p[k:k + 2]))
        out.append(np.column_stack(row))
    return np.vstack(out)


@pytest.mark.parametrize("name", sorted(PLANS))
def test_table_st_compiles_and_runs_in_c(name, folder, tmp_path):
    """The ST of each table compiles with 0 errors; run in C, its arrays are the CSV table's columns (the doubles,
    printed as the CSV prints them, give the CSV's text exactly: the ST holds the doubles, the CSV 12 digits) and the kernel's interpolation of them
    in C agrees with Python's within 1e-12 of the column's largest magnitude (the same polynomial in another order
    of operations, on positions up to ~1e6 counts)."""
    text, data, names = _plan_files(name, folder)
    text_cols = [list(c) for c in zip(*data)]
    compile_ok(text, tmp_path)
    fb = re.search(r"^FUNCTION_BLOCK (\w+)$", text, re.M).group(1).upper()
    kind = _KINDS[fb]
    integer = "--pvt-integer" in PLANS[name]  # times in ms, DINT arrays nTime, nDt
    st_names = {"t": "NTIME", "dt": "NDT"} if integer else {"t": "FTIME", "dt": "FDT", "master": "FMASTER"}
    x_scale = 1e-3 if integer else 1.0
    arrays = [st_names.get(n, n.upper() if n.endswith(("_vel", "_acc")) else f"{n.upper()}_POS") for n in names]
    joints = [n.upper() for n in names if n not in st_names and not n.endswith(("_vel", "_acc"))]
    x = st_names["t" if kind == "pvt" else "master"]
    out = run_c(tmp_path, _fb_harness(fb, arrays, joints, x, x_scale)).splitlines()
    n = int(out[0])
    assert n == len(data) >= 2
    got = {nm: np.array([float.fromhex(v) for v in line.split()]) for nm, line in zip(names, out[1:1 + len(names)])}
    for k, nm in enumerate(names):  # exactly the CSV's text when printed as the CSV prints (%.12g)
        assert [float(f"{v:.12g}") for v in got[nm]] == [float(v) for v in text_cols[k]], nm  # (-0.0 == 0.0)
    c_interp = np.array([[float.fromhex(v) for v in line.split()] for line in out[1 + len(names):]])
    jn = [n for n in names if n.upper() in joints]
    py = _python_interpolation(kind, got, jn, x_scale)
    assert c_interp.shape == py.shape == (3 * (n - 1), len(jn))
    scale = np.max(np.abs(np.column_stack([got[j] for j in jn])), axis=0)
    assert np.all(np.abs(c_interp - py) <= 1e-12 * scale), np.max(np.abs(c_interp - py) / scale)
