"""What the tool's turn costs the planner: in-process `plan` of the Adept cycle on delta-4axis with three numbers
and with a 90° turn (between lift-off and set-down), at --time auto, fit and optimal, interleaved in one run;
medians (and min) of --repeat runs each, in ms.

    python bench/bench_turn.py [--repeat 7]
"""

from __future__ import annotations

import argparse
import math
import statistics
import time

from pickplace_cli.model.profile import load_profile
from pickplace_cli.model.task import Task
from pickplace_cli.planner import PlanOptions, plan


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args()
    prof = load_profile("delta-4axis")
    a, b = [-0.1525, 0.0, -0.8], [0.1525, 0.0, -0.8]
    tasks = {"no turn": Task(a, b, 0.025), "90° turn": Task(a, b, 0.025, theta_from=0.0, theta_to=math.pi / 2)}
    modes = {"auto": PlanOptions(time="auto", fit=False), "fit": PlanOptions(time="fit"),
             "optimal": PlanOptions(time="optimal")}
    for task in tasks.values():  # warm-up: imports, table, caches
        plan(task, prof, modes["auto"])
    times: dict[tuple[str, str], list[float]] = {(t, m): [] for t in tasks for m in modes}
    for _ in range(args.repeat):
        for m, opts in modes.items():
            for t, task in tasks.items():  # interleaved: both sides see the same load
                t0 = time.perf_counter()
                plan(task, prof, opts)
                times[(t, m)].append(1e3 * (time.perf_counter() - t0))
    print("| time | no turn: median (min) ms | 90° turn: median (min) ms | ratio of medians |")
    print("|---|---|---|---|")
    for m in modes:
        a_, b_ = times[("no turn", m)], times[("90° turn", m)]
        print(f"| {m} | {statistics.median(a_):.1f} ({min(a_):.1f}) | {statistics.median(b_):.1f} ({min(b_):.1f}) | "
              f"{statistics.median(b_) / statistics.median(a_):.2f} |")


if __name__ == "__main__":
    main()
