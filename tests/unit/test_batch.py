"""pickplace_cli.pipelines.batch: reading the batch CSV (BOM, delimiters, header-only files) and the per-row limit
messages. The CLI side (exit codes, files written) is in tests/cli/test_batch_cli.py."""

from __future__ import annotations

import pytest

from pickplace_cli.pipelines.batch import plan_rows, read_batch_text, sniff_delimiter, violation_text
from pickplace_cli.model.errors import TaskError
from pickplace_cli.planner import PlanOptions, plan
from pickplace_cli.model.profile import load_profile
from pickplace_cli.model.task import Task

DELTA = load_profile("delta-su2018")
OPTS = PlanOptions(fit=False)
MOVES = (
    "from_x,from_y,from_z,to_x,to_y,to_z,height,time\n"
    "-0.1525,0,-0.8,0.1525,0,-0.8,,\n"
    "0.1,0.1,-0.8,-0.1,-0.1,-0.8,0.03,0.2\n"
)


def parsed(text: str, source: str = "m") -> list[tuple[int, int, dict]]:
    rows, bad = read_batch_text(text, source)
    assert not bad, [b.error for b in bad]
    return [(r.row, r.line, r.values) for r in rows]


def test_a_bom_before_the_header_is_not_part_of_the_first_column():
    """Excel's "CSV UTF-8" starts the file with U+FEFF; it used to become part of 'from_x'."""
    assert parsed("\ufeff" + MOVES) == parsed(MOVES)


@pytest.mark.parametrize("sep", [";", "\t"])
def test_semicolon_and_tab_separated_batches_read_like_commas(sep):
    assert parsed(MOVES.replace(",", sep)) == parsed(MOVES)


def test_semicolons_with_decimal_commas_say_what_is_wrong():
    """A German-locale Excel writes ';' and decimal commas: the cell is refused (no guessing of the
    decimal mark) with a hint, on its row."""
    rows, bad = read_batch_text("from_x;from_y;from_z;to_x;to_y;to_z\n-0,1525;0;-0,8;0,1525;0;-0,8\n", "de.csv")
    assert not rows and len(bad) == 1
    assert bad[0].error == "row 1 (de.csv:2): from_x = '-0,1525': not a number (the decimal mark is '.')"


@pytest.mark.parametrize(
    "header, sep",
    [
        ("from_x,from_y,from_z,to_x,to_y,to_z", ","),
        ("from_x;from_y;from_z;to_x;to_y;to_z", ";"),
        ("from_x\tfrom_y\tfrom_z\tto_x\tto_y\tto_z", "\t"),
        ("t,q1,q2,q3", ","),
        ("t;q1[rad];q2[rad];q3[rad]", ";"),
        ("t", ","),  # nothing to tell: the default
        ("t,q1;q2,q3", ","),  # the most frequent wins
    ],
)
def test_sniff_delimiter(header, sep):
    assert sniff_delimiter(header) == sep


@pytest.mark.parametrize(
    "text",
    [
        "from_x,from_y,from_z,to_x,to_y,to_z\n",
        "from_x,from_y,from_z,to_x,to_y,to_z",
        "# moves\nfrom_x,from_y,from_z,to_x,to_y,to_z\n\n# none yet\n",
        "\ufefffrom_x;from_y;from_z;to_x;to_y;to_z\r\n",
    ],
)
def test_a_header_without_moves_is_an_error_naming_the_file_and_rule(text):
    with pytest.raises(TaskError) as exc:
        read_batch_text(text, "moves.csv")
    line = 2 if text.startswith("#") else 1
    assert str(exc.value) == (
        f"moves.csv:{line}: no moves after the header (need one row per move with from_x, from_y, from_z, "
        "to_x, to_y, to_z)"
    )
    assert exc.value.exit_code == 1


def test_a_limit_row_lists_every_violation_in_the_single_plan_format():
    """The Adept cycle in 0.1 s breaks five limits on the default Delta (three torque rates, two RMS
    torques: measured, and the count is the single plan's own). The batch row gives each of them in the
    words a single plan uses, with the excess and utilisation, prefixed by row and file line."""
    text = "from_x,from_y,from_z,to_x,to_y,to_z,time\n0.1,0.1,-0.8,-0.1,-0.1,-0.8,0.1\n"
    rows, _ = read_batch_text(text, "moves.csv")
    (res,) = plan_rows(rows, DELTA, OPTS, source="moves.csv")
    single = plan(Task([0.1, 0.1, -0.8], [-0.1, -0.1, -0.8], DELTA.planning.height, DELTA.planning.eta),
                  DELTA, PlanOptions(fit=False, time=0.1))
    assert res.code == single.report.exit_code() == 3
    want = [f"row 1 (moves.csv:2): {violation_text(v)}" for v in single.report.violations]
    assert len(want) >= 2  # the point of the test: more than one violation on the row
    assert res.error.splitlines() == want
    for ln in want:
        assert "(by " in ln and " %)" in ln


def test_violation_text_wording():
    """The one line per exceeded limit (README "How to read the limit table"): quantity, peak, time or
    duty cycle, limit, excess and utilisation, numbers to 4 significant digits."""
    from pickplace_cli.limits.report import LimitRow

    r = LimitRow("q1", "motor torque", "N·m", 2.5841, 2.0, 1.29205, 0.04791, False)
    assert violation_text(r) == (
        "limit exceeded: q1 motor torque = 2.584 N·m at t = 0.0479 s; limit 2 N·m (by 0.5841 N·m, 129.2 %)"
    )
    rms = LimitRow("q3", "rms motor torque", "N·m", 3.405, 2.39, 3.405 / 2.39, None, False)
    assert violation_text(rms) == (
        "limit exceeded: q3 rms motor torque = 3.405 N·m over the duty cycle; limit 2.39 N·m (by 1.015 N·m, 142.5 %)"
    )
    low = LimitRow("q1", "position", "rad", -0.61, -0.5, 1.2, 0.01, False, kind="reach", bound="lower")
    assert violation_text(low) == (
        "limit exceeded: q1 position = -0.61 rad at t = 0.0100 s; limit -0.5 rad (by 0.11 rad, 120.0 %)"
    )


def test_header_names_may_carry_their_si_units():
    """A header written in the tool's own CSV style, `from_x[m]`, `time[s]`, `eta[1]`, reads as the bare names;
    another unit (`from_x[mm]`) is refused naming the unit the column is read in (no silent scaling)."""
    with_units = MOVES.replace("from_x,from_y,from_z,to_x,to_y,to_z,height,time",
                               "from_x[m],from_y[m],from_z[m],to_x[m],to_y[m],to_z[m],height[m],time[s]")
    assert parsed(with_units) == parsed(MOVES)
    extra = "from_x,from_y,from_z,to_x,to_y,to_z,eta[1],v_to_x[m/s]\n-0.1525,0,-0.8,0.1525,0,-0.8,0.4,0\n"
    assert parsed(extra)[0][2] == {"from_x": -0.1525, "from_y": 0.0, "from_z": -0.8, "to_x": 0.1525, "to_y": 0.0,
                                   "to_z": -0.8, "eta": 0.4, "v_to_x": 0.0}
    for header, says in (("from_x[mm],from_y,from_z,to_x,to_y,to_z", "'from_x[mm]': from_x is read in m"),
                         ("from_x,from_y,from_z,to_x,to_y,to_z,time[ms]", "'time[ms]': time is read in s"),
                         ("from_x,from_y,from_z,to_x,to_y,to_z,v_to_x[m]", "'v_to_x[m]': v_to_x is read in m/s")):
        with pytest.raises(TaskError, match=r"m:1: column " + says.replace("[", r"\[").replace("]", r"\]")):
            read_batch_text(header + "\n-0.1525,0,-0.8,0.1525,0,-0.8" + ",1" * (header.count(",") - 5) + "\n", "m")


def test_a_dimensionless_column_takes_the_unit_1():
    """limit_use is a fraction, like η: `limit_use[1]` (the unit of a dimensionless quantity, as the tool's own CSV
    writes it) reads as limit_use, and `limit_use[m]` is refused (it was the other way round)."""
    row = "\n-0.1525,0,-0.8,0.1525,0,-0.8,0.9\n"
    for unit in ("1", "-", ""):
        assert parsed(f"from_x,from_y,from_z,to_x,to_y,to_z,limit_use[{unit}]" + row)[0][2]["limit_use"] == 0.9
    with pytest.raises(TaskError, match=r"column 'limit_use\[m\]': limit_use is read in 1 \(write limit_use or "
                                        r"limit_use\[1\]\)"):
        read_batch_text("from_x,from_y,from_z,to_x,to_y,to_z,limit_use[m]" + row, "m")


def test_a_row_without_quotes_is_split_as_the_csv_module_splits_it(monkeypatch):
    """_row splits a line without quotes with str.split (issue 16's latency) and leaves quoted lines, empty ones
    and NUL bytes to the csv module: on 6,000 seeded random lines every cell and every error is the same as with
    the csv module for every line."""
    import random

    import pickplace_cli.pipelines.batch as B

    header = ["from_x", "from_y", "from_z", "to_x", "to_y", "to_z", "height"]
    rng = random.Random(16)
    alphabet = ["0", "1", ".", "-", "e", " ", "\t", ",", ";", "x", "nan", "inf", "", "'", "3.5", '"']
    lines = ["".join(rng.choice(alphabet) for _ in range(rng.randint(0, 30))) for _ in range(1000)]

    def cell() -> str:
        c = rng.choice(["0.1", "-0.8", " 0.03 ", "1e-2", "", "nan", "x", "-0"])
        return f'"{c}"' if rng.random() < 0.1 else c

    got = {}
    for sep in (",", ";", "\t"):
        rows = lines + [sep.join(cell() for _ in range(rng.choice([6, 7, 7, 7, 8]))) for _ in range(1000)]
        got[sep] = [(t, B._row(1, 2, t, header, sep, "b")) for t in rows]

    class Always(str):  # a line that says it holds a quote: _row takes the csv module's path for every line
        def __contains__(self, item):
            return True

    for sep, results in got.items():
        for text, res in results:
            ref = B._row(1, 2, Always(text), header, sep, "b")
            assert type(res) is type(ref), text
            assert getattr(res, "values", None) == getattr(ref, "values", None), text
            assert getattr(res, "error", None) == getattr(ref, "error", None), text
    assert sum(isinstance(r, B.BatchRow) for rs in got.values() for _, r in rs) > 50  # good rows too (75 with this seed)


@pytest.mark.parametrize("cell", ["-0.15_25", "0.\u0661525", "\uff10.1525", "1_000"])
def test_a_number_float_takes_but_a_typo_or_a_locale_makes_is_refused(cell):
    """float() reads '0.15_25' as 0.1525 and other scripts' digits as digits: a cell must be plain ASCII (review)."""
    rows, bad = read_batch_text(f"from_x,from_y,from_z,to_x,to_y,to_z\n{cell},0,-0.8,0.1525,0,-0.8\n")
    assert not rows and f"from_x = {cell!r}: not a number (plain ASCII digits" in bad[0].error


def test_a_utf16_batch_is_named_as_such(tmp_path):
    """Excel's "Unicode Text" (UTF-16 with a BOM) and BOM-less UTF-16: the NUL-bytes error says what it likely is."""
    from pickplace_cli.model.text import utf16_hint
    from pickplace_cli.pipelines.batch import iter_batch

    text = "from_x,from_y,from_z,to_x,to_y,to_z\r\n-0.1525,0,-0.8,0.1525,0,-0.8\r\n"
    for enc in ("utf-16", "utf-16-le", "utf-16-be"):
        f = tmp_path / f"{enc}.csv"
        f.write_bytes(text.encode(enc))
        with open(f, encoding="utf-8-sig", newline="", errors="surrogateescape") as fh:
            with pytest.raises(TaskError, match=r":1: a binary file \(NUL bytes\), not a CSV batch \(UTF-16 text"):
                list(iter_batch(fh, str(f)))
    assert utf16_hint(b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR") == ""  # a binary file is not called UTF-16
    assert utf16_hint(bytes(200)) == "" and utf16_hint(b"\xff\xfe" + bytes(20)) == ""  # nor zeros (review)
    import numpy as np

    assert utf16_hint(np.arange(40, dtype=np.int32).tobytes()) == ""
    assert utf16_hint("a\0b\0".encode(), csv=False) == " (UTF-16 text? save it as UTF-8)"


def _wait_for_stop(args):
    """A chunk for :func:`run_chunks_in_order`: the first answers at once, the others wait (at most 60 s) until the
    parent asks the chunks to stop, and leave a file saying they saw it."""
    import time

    from pickplace_cli.lookup.executors import stopped

    k, folder = args
    if k == 0:
        return [k]
    for _ in range(6000):
        if stopped():
            open(f"{folder}/stopped-{k}", "w").close()
            return [k]
        time.sleep(0.01)
    return [k]


def test_a_reader_that_goes_away_stops_the_running_chunks(tmp_path):
    """``plan --batch FILE --json | head -1``: the reader takes one answer and goes; closing the answers' generator
    sets the pool's stop event, and the chunks still running see it and return (they are not waited for to the end)."""
    from pickplace_cli.pipelines.batch import run_chunks_in_order

    gen = run_chunks_in_order(_wait_for_stop, [(k, str(tmp_path)) for k in range(3)], 2, False)
    assert next(gen) == 0
    gen.close()  # (returns once the pool has shut down: the running chunk saw the stop)
    assert (tmp_path / "stopped-1").exists()


def test_ctrl_c_stops_the_running_chunks(tmp_path):
    """Ctrl-C (KeyboardInterrupt in the parent while it waits for an answer) sets the pool's stop event: the chunks
    still running return after their current row, where the parent waited for each to its end (7 s with 25 time-optimal
    plans per chunk on 4 workers of 2 cores)."""
    from pickplace_cli.pipelines.batch import run_chunks_in_order

    gen = run_chunks_in_order(_wait_for_stop, [(k, str(tmp_path)) for k in range(3)], 2, False)
    assert next(gen) == 0
    with pytest.raises(KeyboardInterrupt):
        gen.throw(KeyboardInterrupt)  # (returns once the pool has shut down: the running chunk saw the stop)
    assert (tmp_path / "stopped-1").exists()
