"""The numbers of README "Controller outputs": the Adept round trip on the shipped Delta at 0.5, 1 and 4 ms cycles
(rounded duration, rounding cost, every step one cycle) and the points of its PVT, cam and equidistant cam tables
against the 1 kHz samples, at tolerances 1e-4, 1e-5, 1e-6 rad.

    python bench/controller_outputs.py
"""

from __future__ import annotations

from decimal import Decimal

import numpy as np

from pickplace_cli.model.profile import load_profile
from pickplace_cli.model.task import Task
from pickplace_cli.pipelines.controller import table_of, timeline_of
from pickplace_cli.pipelines.timeline import on_cycle, round_trip
from pickplace_cli.planner import PlanOptions, plan

THERE = Task([-0.1525, 0.0, -0.8], [0.1525, 0.0, -0.8], 0.025, 0.5)
BACK = Task([0.1525, 0.0, -0.8], [-0.1525, 0.0, -0.8], 0.025, 0.5)


def main() -> None:
    prof = load_profile("delta-su2018")
    print("time | cycle [ms] | T [s] -> rounded [s] (cycles) | round trip [s] | rounding cost [ms] | steps == cycle | limits")
    for time, c in [(time, c) for time in ("auto", "fit") for c in (0.0005, 0.001, 0.004)]:
        legs = [plan(task, prof, PlanOptions(time=time, cycle=c, fit=False)) for task in (THERE, BACK)]
        tl = on_cycle(round_trip(legs[0], legs[1], legs[0].report.dwell, 1.0 / c), c)
        printed = [Decimal(f"{x:.12g}") for x in tl.t]
        exact = all(s == k * Decimal(str(c)) for k, s in enumerate(printed))
        r = legs[0].cycle
        cost = sum(leg.cycle.cost_s for leg in legs) + 2 * r.dwell_cost_s
        print(f"{time} | {c * 1e3:g} | {r.requested_s:.6f} -> {r.seconds:.6f} ({r.cycles}) | {tl.t[-1]:.6f} | "
              f"{cost * 1e3:.4f} | {exact} ({len(tl.t)} samples) | {all(leg.report.ok for leg in legs)}")
    legs = [plan(task, prof, PlanOptions(cycle=0.001, fit=False)) for task in (THERE, BACK)]
    tl = on_cycle(round_trip(legs[0], legs[1], legs[0].report.dwell, 1000.0), 0.001)
    motion = timeline_of(legs, prof, legs[0].report.dwell, True)
    print("\nAdept round trip, 1 ms cycle: table points against the", len(tl.t), "1 kHz samples")
    print("kind | tolerance [rad] | points | samples / point | achieved max error [rad]")
    for kind in ("pvt", "cam", "cam-table"):
        for tol in (1e-4, 1e-5, 1e-6):
            tab = table_of(kind, tl.t, motion, tol)
            print(f"{kind} | {tol:g} | {len(tab.t)} | {len(tl.t) / len(tab.t):.1f} | {np.max(tab.max_error):.3g}")


if __name__ == "__main__":
    main()
