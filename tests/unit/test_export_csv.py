"""export/csv.py: the three dialects byte for byte, and a round trip to the in-memory values.

Round-trip tolerance: values are printed with ``%.12g`` (12 significant digits), so a parsed value is
within 5e-12 relative of the double it came from; RTOL = 6e-12 adds a margin for the decimal→binary
rounding of the parse. Zero stays exactly zero (atol = 0).
"""

from __future__ import annotations

import io

import numpy as np
import pytest

from pickplace_cli.model.errors import ExportError
from pickplace_cli.export import atomic_output, plan_columns
from pickplace_cli.export.csv import MOVE_COLUMN, CsvDialect, write_csv
from tests.golden.samples import delta_batch, delta_plan, gantry_plan, parse_csv

RTOL = 6e-12


def text_of(samples, dialect=None) -> str:
    buf = io.StringIO(newline="")
    if dialect is None:
        write_csv(samples, buf)  # the pre-dialect call keeps working
    else:
        write_csv(samples, buf, dialect)
    return buf.getvalue()


def expected_matrix(samples) -> tuple[list[str], np.ndarray]:
    """Column names and values straight from the sample arrays (not through the writer)."""
    jt = samples.joint
    cols = [("t[s]", samples.t)]
    for k, c in enumerate("xyz"):
        cols.append((f"{c}[m]", samples.p[:, k]))
    for pre, arr, unit in (("v", samples.v, "m/s"), ("a", samples.a, "m/s^2"), ("j", samples.j, "m/s^3")):
        for k, c in enumerate("xyz"):
            cols.append((f"{pre}{c}[{unit}]", arr[:, k]))
    for i, u in enumerate(jt.units):
        cols += [(f"q{i + 1}[{u}]", jt.q[:, i]), (f"qd{i + 1}[{u}/s]", jt.qd[:, i]), (f"qdd{i + 1}[{u}/s^2]", jt.qdd[:, i])]
    for i, u in enumerate(jt.units):
        cols.append((f"torque{i + 1}[{'N' if u == 'm' else 'N*m'}]", jt.torque[:, i]))
        if jt.motor_speed is not None:
            cols += [(f"motor_speed{i + 1}[rad/s]", jt.motor_speed[:, i]), (f"motor_torque{i + 1}[N*m]", jt.motor_torque[:, i])]
    move = getattr(samples, "move", None)
    if move is not None:
        cols.insert(0, (MOVE_COLUMN, move.astype(float)))
    return [n for n, _ in cols], np.column_stack([v for _, v in cols])


@pytest.mark.parametrize("make", [delta_plan, gantry_plan, delta_batch], ids=["delta", "gantry", "batch"])
@pytest.mark.parametrize("dialect", ["default", "twincat", "tsv"])
def test_round_trip_equals_memory(make, dialect):
    samples = make()
    text = text_of(samples, dialect)
    sep, nl, header = {"default": (",", "\n", True), "twincat": (";", "\r\n", True), "tsv": ("\t", "\n", False)}[dialect]
    lines = text.split(nl)
    assert lines[-1] == "" and all(("\r" not in ln and "\n" not in ln) for ln in lines)  # one line end everywhere
    names, data = parse_csv(text, sep, header)
    exp_names, exp = expected_matrix(samples)
    if header:
        assert names == exp_names
    else:
        assert names is None and not any(c.isalpha() for c in lines[0].replace("e", ""))  # numbers only
    assert data.shape == exp.shape
    np.testing.assert_allclose(data, exp, rtol=RTOL, atol=0)


def test_dialect_bytes():
    pl = delta_plan()
    default, twincat, tsv = (text_of(pl, d) for d in ("default", "twincat", "tsv"))
    assert default == text_of(pl)  # default dialect = the pre-dialect output
    names, data = plan_columns(pl)
    first = "%.12g" % 0.0
    assert default.startswith("t[s],x[m],y[m],z[m],vx[m/s]") and default.count("\r") == 0
    assert default.split("\n")[1].startswith(first + ",")
    assert twincat.startswith("t[s];x[m];y[m];z[m];vx[m/s]") and twincat.count("\n") == twincat.count("\r\n") == len(pl.t) + 1
    assert "," not in twincat  # decimal point is '.', separator ';'
    assert tsv.count("\n") == len(pl.t) and "[" not in tsv and "\r" not in tsv
    assert tsv.split("\n")[0].split("\t")[0] == first and len(tsv.split("\n")[0].split("\t")) == len(names)
    # same numbers in all three, only separators and line ends differ
    assert twincat.replace(";", ",").replace("\r\n", "\n") == default
    assert tsv == default.split("\n", 1)[1].replace(",", "\t")


def test_batch_move_column_is_integer():
    b = delta_batch()
    text = text_of(b, "default")
    header, *rows = text.splitlines()
    assert header.startswith("move[-],t[s],")
    moves = [r.split(",", 1)[0] for r in rows]
    assert set(moves) == {"0", "1", "2"}  # printed as integers, not 0.0 / 1e+00
    assert moves == [str(m) for m in b.move]
    twincat = text_of(b, "twincat")
    assert twincat.split("\r\n")[1].startswith("0;0;")


def test_no_negative_zero_and_fixed_format():
    pl = delta_plan()
    text = text_of(pl)
    assert ",-0," not in text and ",-0\n" not in text
    assert text == text_of(pl)  # deterministic


def test_unknown_dialect_and_bad_move():
    pl = delta_plan()
    with pytest.raises(ExportError, match="dialect = 'excel'"):
        text_of(pl, "excel")
    b = delta_batch()
    bad = type(b)(b.t, b.p, b.v, b.a, b.j, b.joint, b.move[:-1])
    with pytest.raises(ExportError, match="move"):
        text_of(bad)


def test_twincat_line_ends_survive_atomic_output(tmp_path):
    """atomic_output opens files with newline='' so the dialect's CRLF reaches the file unchanged."""
    target = tmp_path / "t.csv"
    with atomic_output(target) as fh:
        write_csv(delta_plan(), fh, CsvDialect.twincat)
    raw = target.read_bytes()
    assert raw == text_of(delta_plan(), "twincat").encode() and raw.count(b"\r\n") == len(delta_plan().t) + 1


@pytest.mark.parametrize("dialect", ["default", "twincat", "tsv"])
def test_batch_written_one_plan_at_a_time(dialect):
    """csv_header(move=True) + csv_rows(plan, move=k) for each plan == write_csv of the batch's samples."""
    from pickplace_cli.export.csv import csv_header, csv_rows, dialect_spec

    plans = [delta_plan(), delta_plan(back=True)]
    spec = dialect_spec(dialect)
    streamed = csv_header(plans[0], dialect, move=True) + "".join(csv_rows(pl, dialect, move=k + 7) for k, pl in enumerate(plans))
    # the same samples as one batch object whose t restarts per move (as a CSV batch does)
    b = delta_batch()
    n0 = len(plans[0].t)
    same = type(b)(np.concatenate([pl.t for pl in plans]), np.vstack([pl.p for pl in plans]), np.vstack([pl.v for pl in plans]),
                   np.vstack([pl.a for pl in plans]), np.vstack([pl.j for pl in plans]),
                   type(b.joint)(np.concatenate([pl.t for pl in plans]), *(np.vstack([getattr(pl.joint, f) for pl in plans]) for f in ("q", "qd", "qdd", "qddd")),
                                 plans[0].joint.names, plans[0].joint.units,
                                 **{f: np.vstack([getattr(pl.joint, f) for pl in plans]) for f in ("torque", "motor_speed", "motor_torque")}),
                   np.array([7] * n0 + [8] * len(plans[1].t)))
    assert streamed == text_of(same, dialect)
    assert csv_header(plans[0], dialect, move=False) == (spec.sep.join(plan_columns(plans[0])[0]) + spec.newline if spec.header else "")
    assert csv_header(delta_batch(), dialect, move=False) == csv_header(plans[0], dialect)
