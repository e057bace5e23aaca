"""The README's worked example of the rotary fourth axis: the Adept cycle (305 mm across, 25 mm up) with and without
a turn of the tool, at --time fit and optimal, on the 4-axis Delta (delta-4axis) and the SCARA (scara-600): the
duration, the picks per minute of the round trip (2T + 2·dwell), what binds, and how hard the fourth motor works.

    python bench/turn_example.py [--json bench/results/turn_example.json]

Every number is a plan's own (its duration, its limit report); nothing here is timed.
"""

from __future__ import annotations

import argparse
import json
import math

from pickplace_cli.model.profile import load_profile
from pickplace_cli.model.task import Task
from pickplace_cli.planner import PlanOptions, plan

MOVES = {
    "delta-4axis": ([-0.1525, 0.0, -0.8], [0.1525, 0.0, -0.8]),
    "scara-600": ([0.35, -0.1525, -0.15], [0.35, 0.1525, -0.15]),
}
#: (label, turn [rad] or None for three numbers, window)
TURNS = [("no turn (X,Y,Z)", None, "transfer"), ("90°, lift-off to set-down", math.pi / 2, "transfer"),
         ("90°, whole move", math.pi / 2, "whole"), ("180°, lift-off to set-down", math.pi, "transfer")]


def row(name: str, label: str, turn, during: str, time: str) -> dict:
    prof = load_profile(name)
    a, b = MOVES[name]
    task = Task(a, b, 0.025, 0.5, theta_from=None if turn is None else 0.0, theta_to=turn)
    res = plan(task, prof, PlanOptions(time=time, turn_during=during))
    T = res.duration.seconds
    q4 = {r.quantity: r.utilisation for r in res.report.rows if r.joint == "q4"}
    worst = max((r for r in res.report.rows if r.kind == "limit" or r.quantity == "rms motor torque"),
                key=lambda r: r.utilisation)
    return {"profile": name, "turn": label, "time": time, "T_s": T, "picks_per_minute": 60.0 / (2 * T + 2 * prof.planning.dwell),
            "binding": res.duration.binding, "ok": res.report.ok,
            "q4_motor_speed_use": q4.get("motor speed"), "q4_motor_torque_use": q4.get("motor torque"),
            "q4_rms_use": q4.get("rms motor torque"), "highest_use": f"{worst.joint} {worst.quantity} {worst.utilisation:.3f}"}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", help="also write the rows to this JSON file")
    args = ap.parse_args()
    rows = [row(name, label, turn, during, time) for name in MOVES for label, turn, during in TURNS
            for time in ("fit", "optimal")]
    print("| profile | turn | time | T [s] | picks/min | binding | q4 motor speed / torque / RMS use |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        use = " / ".join("–" if r[k] is None else f"{100 * r[k]:.0f} %" for k in
                         ("q4_motor_speed_use", "q4_motor_torque_use", "q4_rms_use"))
        print(f"| {r['profile']} | {r['turn']} | {r['time']} | {r['T_s']:.4f} | {r['picks_per_minute']:.1f} | "
              f"{r['binding']} | {use} |")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rows, fh, indent=1)


if __name__ == "__main__":
    main()
