"""The default duration (``--time limits``: every limit of the profile) against ``--time auto`` (the Cartesian capacity
alone), both sides in the same run, interleaved so that a drift of the machine's speed hits both alike.

    python bench/bench_default.py [--repeat N] [--starts N]

* in process: ``plan`` of the Adept cycle on the default Delta (bspline: the capacity binds; ph: q1's torque rate
  binds) and of the scara-600 move (0.3,-0.2,-0.1) -> (0.3,0.2,-0.1), one rule after the other, N times; medians;
* start-up: a fresh ``pickplace plan`` process writing the Adept cycle to a file, one rule after the other;
  medians of wall time.

Writes bench/results/default.json. Not a test: timings depend on the machine and on what else runs on it.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

CASES = [("delta-su2018", "bspline", (-0.1525, 0, -0.8), (0.1525, 0, -0.8)),
         ("delta-su2018", "ph", (-0.1525, 0, -0.8), (0.1525, 0, -0.8)),
         ("scara-600", "bspline", (0.3, -0.2, -0.1), (0.3, 0.2, -0.1))]
RULES = ("auto", "limits")


def in_process(repeat: int) -> dict:
    import numpy as np

    from pickplace_cli import planner
    from pickplace_cli.model.profile import load_profile
    from pickplace_cli.model.task import Task

    out = {}
    for prof_name, method, a, b in CASES:
        prof = load_profile(prof_name)
        task = Task(np.array(a), np.array(b), prof.planning.height, prof.planning.eta)
        opts = {r: planner.PlanOptions(method=method, time=r, fit=False) for r in RULES}
        for r in RULES:  # warm: tables read, imports done
            planner.plan(task, prof, opts[r])
        times: dict[str, list[float]] = {r: [] for r in RULES}
        for _ in range(repeat):
            for r in RULES:
                t0 = time.perf_counter()
                planner.plan(task, prof, opts[r])
                times[r].append(time.perf_counter() - t0)
        key = f"{prof_name}/{method}"
        out[key] = {r: statistics.median(times[r]) for r in RULES}
        out[key]["ratio"] = out[key]["limits"] / out[key]["auto"]
        print(f"in process {key:<24} auto {out[key]['auto'] * 1e3:7.3f} ms   limits {out[key]['limits'] * 1e3:7.3f} ms"
              f"   ratio {out[key]['ratio']:.2f}  (medians of {repeat})", flush=True)
    return out


def start_up(starts: int) -> dict:
    exe = [sys.executable, "-m", "pickplace_cli"]
    times: dict[str, list[float]] = {r: [] for r in RULES}
    with tempfile.TemporaryDirectory() as tmp:
        target = os.path.join(tmp, "a.csv")
        for _ in range(starts):
            for r in RULES:
                t0 = time.perf_counter()
                subprocess.run(exe + ["plan", "-q", "-t", r, "--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8",
                                      "-o", target], check=True)
                times[r].append(time.perf_counter() - t0)
    out = {r: statistics.median(times[r]) for r in RULES}
    out["ratio"] = out["limits"] / out["auto"]
    print(f"start-up (fresh process, Adept cycle to a file): auto {out['auto']:.3f} s   limits {out['limits']:.3f} s   "
          f"ratio {out['ratio']:.2f}  (medians of {starts})")
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=300)
    ap.add_argument("--starts", type=int, default=15)
    args = ap.parse_args()
    load = os.getloadavg()[0]
    print(f"load average (1 min): {load:.2f}")
    result = {"load_1min": load, "in_process_s": in_process(args.repeat), "start_up_s": start_up(args.starts)}
    path = Path(__file__).parent / "results" / "default.json"
    path.write_text(json.dumps(result, indent=2) + "\n")
    print(f"written {path}")


if __name__ == "__main__":
    main()
