"""`plan --batch FILE --json` without -o: the batched verdict engine (pickplace_cli.pipelines.verdicts) must not change
a byte of the output, the messages or the exit code (PICKPLACE_NO_VERDICT_ENGINE=1 switches it off)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from pickplace_cli.pipelines import verdicts
from pickplace_cli.cli import app

runner = CliRunner()

MIXED = """from_x,from_y,from_z,to_x,to_y,to_z,height,time
-0.1525,0,-0.8,0.1525,0,-0.8,,
0.1,0.1,-0.8,-0.1,-0.1,-0.8,0.03,0.2
# a comment line, skipped
0,0,-0.8,0.3,0,-0.8,0.000001,
0,0,-0.8,0.1,0,-0.8,,0.01
1,2,x,4,5,6,,
0,0,-0.8,0.1,0,-0.3,,
0.05,-0.1,-0.85,-0.08,0.12,-0.78,0.04,
-0.1525,0,-0.8,0.1525,0,-0.8,,fit
"""


def random_rows(n: int, seed: int) -> str:
    rng = np.random.default_rng(seed)
    lines = ["from_x,from_y,from_z,to_x,to_y,to_z,time"]
    for _ in range(n):
        r, a = rng.uniform(0.03, 0.3), rng.uniform(0, 2 * np.pi)
        z0, z1 = rng.uniform(-0.95, -0.65, 2)
        t = rng.choice(["", "", f"{rng.uniform(0.06, 0.25):.3f}"])
        lines.append(f"{-r * np.cos(a):.4f},{-r * np.sin(a):.4f},{z0:.4f},{r * np.cos(a):.4f},{r * np.sin(a):.4f},{z1:.4f},{t}")
    return "\n".join(lines) + "\n"


def both(args, text, monkeypatch):
    """(with the engine, without it): CliRunner results of the same command."""
    monkeypatch.delenv(verdicts.OFF_SWITCH, raising=False)
    on = runner.invoke(app, args, input=text, catch_exceptions=False)
    monkeypatch.setenv(verdicts.OFF_SWITCH, "1")
    off = runner.invoke(app, args, input=text, catch_exceptions=False)
    return on, off


def spy(monkeypatch) -> list:
    """Record how many rows the engine decides (to show that it ran)."""
    seen: list = []
    real = verdicts.decide

    def recording(*a, **k):
        out = real(*a, **k)
        seen.append(len(out))
        return out

    monkeypatch.setattr(verdicts, "decide", recording)
    return seen


@pytest.mark.parametrize("extra", [[], ["-q"], ["--fail-fast"], ["--rate", "250", "--height", "0.03"], ["--eta", "0.4"]])
def test_mixed_batch_identical_with_and_without_the_engine(monkeypatch, extra):
    seen = spy(monkeypatch)
    on, off = both(["plan", "--batch", "-", "--json", "-t", "auto", "-j", "1", *extra], MIXED, monkeypatch)
    assert seen  # the engine ran
    if extra != ["--eta", "0.4"]:  # (the shipped table is for η = 0.5: every row goes to plan(), which solves it)
        assert seen[0] >= 2  # it decided rows 1, 2 (and 7) itself
    assert on.stdout == off.stdout
    assert on.stderr == off.stderr
    # --eta 0.4: the rows go to plan() (not in the η = 0.5 table; plan reads the 2-D table); row 6 is unreachable (4);
    # --fail-fast: row 3 (λ = 3e5, beyond any optimum: 1) stops the batch
    assert on.exit_code == off.exit_code == {"--fail-fast": 1}.get(extra[0] if extra else "", 4)
    if not extra:
        docs = [json.loads(x) for x in on.stdout.splitlines()]
        assert [d["exit_code"] for d in docs] == [0, 0, 1, 3, 1, 4, 0, 0]


@pytest.mark.parametrize("jobs", ["1", "2"])
def test_a_row_with_too_many_samples_fails_alone_with_the_engine(monkeypatch, tmp_path, jobs):
    """A time of 1500 s (a column in ms by mistake) has 1.5e6 samples at 1 kHz, over the cap: the engine raised the
    row's TaskError out of the whole batch (nothing on stdout, one line without a row number, exit 1). Now only
    that row fails, with its row number, and the others are answered, as without the engine."""
    from functools import partial

    monkeypatch.setattr(verdicts, "verdict_rows_parallel", partial(verdicts.verdict_rows_parallel, chunk=2))
    src = tmp_path / "ms.csv"
    src.write_text("from_x,from_y,from_z,to_x,to_y,to_z,time\n-0.1525,0,-0.8,0.1525,0,-0.8,0.3\n"
                   "-0.1525,0,-0.8,0.1525,0,-0.8,1500\n0.1,0.1,-0.8,-0.1,-0.1,-0.8,0.4\n")
    seen = spy(monkeypatch)
    on, off = both(["plan", "--batch", str(src), "--json", "-t", "auto", "-j", jobs], None, monkeypatch)
    assert seen  # the engine ran
    assert on.stdout == off.stdout and on.stderr == off.stderr and on.exit_code == off.exit_code == 1
    docs = [json.loads(x) for x in on.stdout.splitlines()]
    assert [(d["row"], d["exit_code"]) for d in docs] == [(1, 0), (2, 1), (3, 0)]
    assert "row 2 (" in on.stderr and "at most 1,000,000 per move" in on.stderr


def test_random_batch_identical_on_two_workers(monkeypatch, tmp_path):
    from functools import partial

    # chunks of 100 rows (the default, ≥ 500, would keep 300 rows in one process)
    monkeypatch.setattr(verdicts, "verdict_rows_parallel", partial(verdicts.verdict_rows_parallel, chunk=100))
    src = tmp_path / "moves.csv"
    src.write_text(random_rows(300, seed=1))
    on, off = both(["plan", "--batch", str(src), "--json", "-t", "auto", "-q", "-j", "2"], None, monkeypatch)
    assert on.stdout == off.stdout and on.stderr == off.stderr and on.exit_code == off.exit_code
    codes = {json.loads(x)["exit_code"] for x in on.stdout.splitlines()}
    assert 0 in codes and 3 in codes  # both verdicts occur


def test_engine_not_used_with_an_output_file_or_another_method(monkeypatch, tmp_path):
    seen = spy(monkeypatch)
    out = tmp_path / "o.csv"
    r = runner.invoke(app, ["plan", "--batch", "-", "--json", "-q", "-o", str(out)], input=MIXED)
    r2 = runner.invoke(app, ["plan", "--batch", "-", "--json", "-q", "-m", "ph"], input=MIXED)
    r3 = runner.invoke(app, ["plan", "--batch", "-", "--json", "-q", "--show-fit"], input=MIXED)
    assert r.exit_code == r2.exit_code == r3.exit_code == 4
    assert seen == []


@pytest.mark.parametrize("extra", [[], ["--fail-fast"], ["--rate", "250", "--height", "0.03"], ["--limit-use", "0.8"]])
def test_default_rule_batch_identical_with_and_without_the_engine(monkeypatch, extra):
    """The default duration rule (no -t): the engine decides the rows where the capacity binds, with plan()'s fit_s."""
    seen = spy(monkeypatch)
    on, off = both(["plan", "--batch", "-", "--json", "-j", "1", *extra], MIXED, monkeypatch)
    assert seen and seen[0] >= 2  # the engine ran and decided rows 1, 2 (and 7) itself
    assert on.stdout == off.stdout and on.stderr == off.stderr
    assert on.exit_code == off.exit_code == (1 if extra == ["--fail-fast"] else 4)
    if not extra:
        docs = [json.loads(x) for x in on.stdout.splitlines()]
        assert [d["exit_code"] for d in docs] == [0, 0, 1, 3, 1, 4, 0, 0]
        assert docs[0]["mode"] == "limits" and docs[0]["binding"].startswith("capacity") and docs[0]["fit_s"] > 0


def test_default_rule_random_batch_identical_on_two_workers(monkeypatch, tmp_path):
    from functools import partial

    monkeypatch.setattr(verdicts, "verdict_rows_parallel", partial(verdicts.verdict_rows_parallel, chunk=100))
    src = tmp_path / "moves.csv"
    src.write_text(random_rows(300, seed=2))
    seen = spy(monkeypatch)
    on, off = both(["plan", "--batch", str(src), "--json", "-q", "-j", "2"], None, monkeypatch)
    assert on.stdout == off.stdout and on.stderr == off.stderr and on.exit_code == off.exit_code
    assert seen  # (the parent's warm-up; the workers' decisions are their own)
    docs = [json.loads(x) for x in on.stdout.splitlines()]
    assert {d["exit_code"] for d in docs} >= {0, 3} and any(d.get("mode") == "limits" for d in docs)
