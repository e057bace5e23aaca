"""The shape search's budget against the stored benchmark moves: both budgets in the same run.

    python bench/bench_shape_budget.py            # reads bench/results/shape.json (from bench/bench_shape.py)
    python bench/bench_shape_budget.py --budget '{"SHAPE_GRID": [3, 3, 2], "SHAPE_STARTS": 1}'
    python bench/bench_shape_budget.py --peaks    # the screen without and with the asymmetric paths' exact peaks

For each stored move (and the Adept cycle) plans ``--optimize shape --time fit`` with the shipped search
constants and with a reduced budget (``--budget``: constants of ``timing/shape.py`` as JSON, default ``REDUCED``), and prints both durations, the stored slow-search duration
and the CPU time [ms] (``time.process_time``) of each plan. A reduced budget is acceptable only when no
move's duration grows.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from pickplace_cli.model.task import Task  # noqa: E402
from pickplace_cli.planner import PlanOptions, plan  # noqa: E402
from pickplace_cli.timing import shape as S  # noqa: E402
from tests.property.test_limit_truth import _profile  # noqa: E402

#: the reduced budget compared with the shipped constants (name → value)
REDUCED = {"SHAPE_GRID": (3, 3, 2), "SHAPE_STARTS": 1}


def run(task: Task, name: str, consts: dict) -> tuple[float, float, bool]:
    """(T [s], CPU [s], limits ok) of one shape + fit plan under the search constants ``consts``."""
    old = {k: getattr(S, k) for k in consts}
    try:
        for k, v in consts.items():
            setattr(S, k, v)
        c0 = time.process_time()
        r = plan(task, _profile(name), PlanOptions(time="fit", shape=True))
        return r.duration.seconds, time.process_time() - c0, bool(r.report.ok)
    finally:
        for k, v in old.items():
            setattr(S, k, v)


def peaks_skip(repeats: int = 3) -> None:
    """The Adept cycle's ``--optimize shape --time fit`` plan with the screen skipping the asymmetric paths' exact
    Cartesian peaks (shipped) and computing them, alternately in the same run: CPU medians and both results."""
    import pickplace_cli.paths.bspline as PB

    skip = PB.screen_bspline

    def with_peaks(*a, **k):
        return skip(*a, **{**k, "peaks": True})

    task = Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5)
    cpu: dict = {"skip": [], "peaks": []}
    got: dict = {}
    try:
        for _ in range(repeats):
            for name, fn in (("skip", skip), ("peaks", with_peaks)):
                PB.screen_bspline = fn
                c0 = time.process_time()
                r = plan(task, _profile("delta-su2018"), PlanOptions(time="fit", shape=True))
                cpu[name].append(time.process_time() - c0)
                got[name] = r.duration.seconds
    finally:
        PB.screen_bspline = skip
    for name in cpu:
        print(f"peaks {name:5s}: T {got[name]!r} s, CPU median {statistics.median(cpu[name]) * 1e3:.0f} ms")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--budget", default=json.dumps(REDUCED), help="reduced search constants as JSON")
    ap.add_argument("-o", "--output", default=None, help="append the summary (JSON lines) to this file")
    ap.add_argument("--peaks", action="store_true", help="compare the screen without and with exact peaks")
    args = ap.parse_args()
    if args.peaks:
        peaks_skip()
        return
    reduced = {k: tuple(v) if isinstance(v, list) else v for k, v in json.loads(args.budget).items()}
    stored = json.loads((Path(__file__).parent / "results" / "shape.json").read_text())
    moves = [("delta-su2018", Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5), None)]
    moves += [(r["profile"], Task(r["from"], r["to"], r["height"], 0.5), r["t_slow"]) for r in stored["rows"]]
    shipped = {k: getattr(S, k) for k in reduced}
    grow, cpu_a, cpu_b = [], [], []
    for name, task, t_slow in moves:
        ta, ca, oka = run(task, name, shipped)
        tb, cb, okb = run(task, name, reduced)
        grow.append(tb / ta - 1.0)
        cpu_a.append(ca)
        cpu_b.append(cb)
        slow = "" if t_slow is None else f"  slow {t_slow:.5f}"
        print(f"{name:13s} shipped {ta:.5f} s ({ca * 1e3:.0f} ms CPU, ok {oka})  reduced {tb:.5f} s "
              f"({cb * 1e3:.0f} ms CPU, ok {okb}){slow}  change {grow[-1] * 100:+.3f} %", flush=True)
    print(f"budget {reduced}")
    print(f"{len(moves)} moves: duration change worst {max(grow) * 100:+.3f} %; CPU median shipped "
          f"{statistics.median(cpu_a) * 1e3:.0f} ms, reduced {statistics.median(cpu_b) * 1e3:.0f} ms")
    if args.output:
        with open(args.output, "a", encoding="utf-8") as out:
            out.write(json.dumps({"budget": reduced, "moves": len(moves), "worst_change": max(grow),
                                  "median_change": statistics.median(grow), "changes": grow,
                                  "cpu_ms_median_shipped": statistics.median(cpu_a) * 1e3,
                                  "cpu_ms_median_reduced": statistics.median(cpu_b) * 1e3}) + "\n")


if __name__ == "__main__":
    main()
