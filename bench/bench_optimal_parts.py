"""Where ``plan(time="optimal")``'s CPU time goes, stage by stage, on the Adept cycle and the first random move of
each shipped profile (``bench/moves.py``, seed 500): the CPU time (``time.process_time``, one BLAS thread) spent
inside each stage during the plan, medians over ``--repeat`` plans after a warm one.

    python bench/bench_optimal_parts.py [--repeat 7]

Stages (each timed where ``choose_optimal`` calls it; nested times are not counted twice):

* ``uniform fit``: the uniform law's fitted duration (``choose_duration(..., "fit")``), the law's start and fallback;
* ``torque bound``: the reachability bound shown beside the duration (``timing.bound.torque_bound``);
* ``law``: the time law's solve (``timing.optimal.optimal_law``: model terms on the grids, the SQP's rounds, the
  composition of the law with the path);
* ``law fit``: the composed path's fitted duration and its exact check (``fit_duration`` on the composed law);
* ``written``: the written samples read as ``check`` reads them, and the law slowed until they hold
  (``timing.written.hold_as_written``);
* ``rest``: the plan's other stages (path, samples, the final report).

Not a test: timings depend on the machine and on what else runs on it.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.moves import first_moves  # noqa: E402
from pickplace_cli.model.threads import single_blas_thread  # noqa: E402
from pickplace_cli.planner import PlanOptions, plan  # noqa: E402
from pickplace_cli.timing import bound, choose, optimal, written  # noqa: E402

SPENT: dict = {}
INSIDE: list = []


def timed(module, name: str, stage: str) -> None:
    """Count the CPU time inside ``module.name`` as ``stage`` (the name as ``choose_optimal`` looks it up)."""
    real = getattr(module, name)

    def wrapper(*args, **kw):
        if INSIDE:  # within another stage (the uniform fit's own fit_duration): that stage's time
            return real(*args, **kw)
        INSIDE.append(stage)
        c0 = time.process_time()
        try:
            return real(*args, **kw)
        finally:
            SPENT[stage] = SPENT.get(stage, 0.0) + time.process_time() - c0
            INSIDE.pop()

    setattr(module, name, wrapper)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args()
    timed(choose, "choose_duration", "uniform fit")
    timed(choose, "fit_duration", "law fit")
    timed(bound, "torque_bound", "torque bound")
    timed(optimal, "optimal_law", "law")
    timed(written, "hold_as_written", "written")
    stages = ("uniform fit", "torque bound", "law", "law fit", "written", "rest")
    print(f"{'move':13s} {'default':>8s} {'optimal':>8s}  " + "  ".join(f"{s:>12s}" for s in stages) + "   [ms CPU]")
    for label, prof, task in first_moves():

        @single_blas_thread
        def once(opts):
            SPENT.clear()
            c0 = time.process_time()
            plan(task, prof, opts)
            total = time.process_time() - c0
            return total, dict(SPENT, rest=total - sum(SPENT.values()))

        once(PlanOptions(time="optimal"))
        runs = [once(PlanOptions(time="optimal")) for _ in range(args.repeat)]
        default = statistics.median(once(PlanOptions())[0] for _ in range(args.repeat))
        med = {s: statistics.median(r[1].get(s, 0.0) for r in runs) * 1e3 for s in stages}
        total = statistics.median(r[0] for r in runs) * 1e3
        print(f"{label:13s} {default * 1e3:8.1f} {total:8.1f}  " + "  ".join(f"{med[s]:12.1f}" for s in stages),
              flush=True)


if __name__ == "__main__":
    main()
