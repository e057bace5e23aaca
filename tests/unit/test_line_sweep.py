"""Sweeps (line/sweep.py): each case is the same as a single run of that line; an interrupted sweep resumes
without running its finished cases again; local processes and a Dask cluster give the same rows."""

from __future__ import annotations

import pytest

from pickplace_cli.line import sweep as sw
from pickplace_cli.line.engine import LineEngine
from pickplace_cli.line.parts import generate
from pickplace_cli.line.spec import parse_line
from pickplace_cli.model.errors import TaskError
from pickplace_cli.model.profile import load_profile

PROFILE = load_profile()
LINE = parse_line("""\
belt: {speed: 0.5, width: 0.3}
robots:
  - {name: r1, base: [0.6, 0.0, 0.8], window: [0.4, 0.8], place: {points: [[0.6, 0.35, 0.0]]}}
  - {name: r2, base: [1.4, 0.0, 0.8], window: [1.2, 1.6], place: {points: [[1.4, 0.35, 0.0]]}}
parts: {generate: {rate: 5.0, count: 10, seed: 1}}
strategy: {kind: quota, shares: [0.4, 0.6]}
""", "l.yaml")
PROFILES = {"r1": PROFILE, "r2": PROFILE}
CASES = sw.cases([0.3, 0.6], [1, 2], ["quota", "upstream_first"], [1, 2])
KEYS = ("parts", "picked", "missed", "miss_rate", "picks_per_minute", "utilisation", "rms_use_max", "exit_code")


def _strip(row: dict) -> dict:
    return {k: row[k] for k in KEYS}


def test_a_case_is_the_single_run_of_its_line():
    case = sw.Case(0.6, 1, "quota", 2)
    cl = sw.case_line(LINE, case)
    assert cl.belt.speed == 0.6 and [r.name for r in cl.robots] == ["r1"] and cl.parts.generate.seed == 2
    assert cl.strategy.shares == [1.0]  # the first robot's share, renormalised
    eng = LineEngine(cl, PROFILES)
    for d in generate(cl.parts.generate, cl.belt.width):
        eng.offer(d)
    s = eng.finish()
    row = sw.run_case((LINE, PROFILES, case, None))
    assert (row["picked"], row["missed"], row["miss_rate"]) == (s.picked, s.missed, s.miss_rate)
    other = sw.case_line(LINE, sw.Case(0.6, 2, "skip", None))
    assert other.strategy.kind == "skip" and other.parts.generate.seed == 1


def test_resume_runs_only_the_missing_cases(tmp_path, monkeypatch):
    ckpt = tmp_path / "s.csv.partial.jsonl"
    tag = sw.digest(LINE, {"a": 1})
    calls = []
    real = sw.run_case

    def counting(args):
        calls.append(args[2].key)
        return real(args)

    monkeypatch.setattr(sw, "run_case", counting)

    def stop_after_three(done, total):
        if done == 3:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        sw.run_sweep(LINE, PROFILES, CASES, None, 1, None, stop_after_three, ckpt, False, tag)
    assert len(calls) == 3 and ckpt.exists()
    calls.clear()
    rows = sw.run_sweep(LINE, PROFILES, CASES, None, 1, None, None, ckpt, True, tag)
    assert len(calls) == len(CASES) - 3 and [r["case"] for r in rows] == [c.key for c in CASES]
    fresh = sw.run_sweep(LINE, PROFILES, CASES, None, 1, None, None, None, False, tag)
    assert [_strip(r) for r in rows] == [_strip(r) for r in fresh]  # resumed rows = rows of one uninterrupted run
    with pytest.raises(TaskError, match="the checkpoint of another sweep"):
        sw.run_sweep(LINE, PROFILES, CASES, None, 1, None, None, ckpt, True, sw.digest(LINE, {"a": 2}))


@pytest.mark.slow
def test_local_processes_and_dask_give_the_same_rows():
    distributed = pytest.importorskip("distributed")
    from pickplace_cli.lookup.executors import dask_executor

    few = CASES[:4]
    one = sw.run_sweep(LINE, PROFILES, few, None, 1)
    two = sw.run_sweep(LINE, PROFILES, few, None, 2)
    assert [_strip(r) for r in one] == [_strip(r) for r in two]
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None) as cluster:
        with dask_executor(cluster.scheduler_address) as (executor, threads):
            dask = sw.run_sweep(LINE, PROFILES, few, None, threads, executor)
    assert [_strip(r) for r in one] == [_strip(r) for r in dask]
