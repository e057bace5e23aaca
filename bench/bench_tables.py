"""Points of the controller tables before and after they are made to hold every limit as the drive interpolates them.

For pvt, cam and cam-table on the Adept move (`--time fit` and `--time optimal`, shipped Delta), the 4-axis Delta
with a tool turn (0 → 3.14159 rad, default duration) and the gantry (default duration), at tolerances 1e-4, 1e-5,
1e-6 (rad or m) and without a cycle (1 kHz samples), 1 ms and 2 ms cycles: the points the tolerance alone needs
(what the table had before), the points after (where the rebuilt motion exceeded a limit, more points), the
re-timing factor (1: none), the rebuilt table's largest limit use [%] (the per-cycle step rows included) against the
trajectory's, and the time to make it [s].

    python bench/bench_tables.py [-o bench/results/tables.json]
"""

from __future__ import annotations

import argparse
import json
import os
import time

from pickplace_cli.model.profile import load_profile
from pickplace_cli.model.task import Task
from pickplace_cli.pipelines.controller import judged_table, timeline_of
from pickplace_cli.planner import PlanOptions, plan

ADEPT = Task([-0.1525, 0.0, -0.8], [0.1525, 0.0, -0.8], 0.025, 0.5)
TURN = Task([-0.1525, 0.0, -0.8], [0.1525, 0.0, -0.8], 0.025, 0.5, theta_from=0.0, theta_to=3.14159)
GANTRY = Task([-0.4, 0.3, -0.3], [0.5, -0.2, -0.5], 0.025, 0.5)
CASES = {"adept-fit": ("delta-su2018", ADEPT, {"time": "fit"}),
         "adept-optimal": ("delta-su2018", ADEPT, {"time": "optimal"}),
         "delta-4axis-turn": ("delta-4axis", TURN, {}),
         "gantry": ("gantry", GANTRY, {})}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--output", default="bench/results/tables.json")
    args = ap.parse_args()
    rows = []
    print("case | cycle [ms] | format | tolerance | points before -> after | re-timed x | table use % | "
          "trajectory use % | s")
    for case, (name, task, opts) in CASES.items():
        prof = load_profile(name)
        for cycle in (None, 0.001, 0.002):
            move = plan(task, prof, PlanOptions(cycle=cycle, **opts))
            line = timeline_of([move], prof, move.report.dwell, False)
            capacity = any(r.quantity.startswith("capacity") for r in move.report.rows)
            traj = max(r.utilisation for r in move.report.rows if r.kind == "limit")
            for kind in ("pvt", "cam", "cam-table"):
                for tol in (1e-4, 1e-5, 1e-6):
                    t0 = time.perf_counter()
                    out = judged_table(kind, move.t, line, tol, prof, move.report.dwell, cycle, capacity=capacity)
                    took = time.perf_counter() - t0
                    use = max(r.utilisation for r in out.report.rows if r.kind == "limit")
                    worst = max((r for r in out.report.rows if r.kind == "limit"), key=lambda r: r.utilisation)
                    row = {"case": case, "profile": name, "cycle_s": cycle, "format": kind, "tolerance": tol,
                           "points_before": out.tolerance_points, "points_after": len(out.table.t),
                           "samples": out.table.samples, "stretch": out.stretch, "ok": out.report.ok,
                           "table_use": use, "table_limiting": f"{worst.joint} {worst.quantity}",
                           "trajectory_use": traj, "seconds": took}
                    rows.append(row)
                    print(f"{case} | {0 if cycle is None else cycle * 1e3:g} | {kind} | {tol:g} | "
                          f"{row['points_before']} -> {row['points_after']} | {out.stretch:.5f} | {100 * use:.2f} "
                          f"({row['table_limiting']}) | {100 * traj:.2f} | {took:.2f}", flush=True)
    doc = {"rows": rows, "cases": len(rows), "all_ok": all(r["ok"] for r in rows),
           "more_points": sum(r["points_after"] > r["points_before"] for r in rows),
           "retimed": sum(r["stretch"] > 1.0 for r in rows), "max_stretch": max(r["stretch"] for r in rows),
           "worst_table_use": max(r["table_use"] for r in rows),
           "max_seconds": max(r["seconds"] for r in rows), "load_average": os.getloadavg()[0],
           "command": "python bench/bench_tables.py"}
    with open(args.output, "w") as fh:
        json.dump(doc, fh, indent=1)
        fh.write("\n")
    print(f"all hold: {doc['all_ok']}; wrote {args.output}")


if __name__ == "__main__":
    main()
