"""Benchmark of `compare` (run: python bench/bench_compare.py [--repeat N] [--profile P]).

In-process `compare_methods` of every registered method on the Adept cycle, with the robot mapping, the
limit check, `--time fit` and the residual vibration (the profile's modes), plus one row per method and
the wall time of the `pickplace compare` command. Prints medians with min–max and writes
bench/results/compare.json. Target: all methods on one move under 1 s in-process.
Not a test: timings depend on the machine (and on its load).
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path

ADEPT = ["--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8"]


def stats(samples: list[float]) -> dict:
    return {"median": statistics.median(samples), "min": min(samples), "max": max(samples), "n": len(samples)}


def show(name: str, s: dict, unit: str = "ms", scale: float = 1e3) -> None:
    print(f"{name:<44} median {s['median'] * scale:9.1f} {unit}   (min {s['min'] * scale:.1f} – max {s['max'] * scale:.1f}, n={s['n']})")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--profile", default="delta-su2018")
    args = ap.parse_args()

    import numpy as np

    from pickplace_cli.studies.compare import compare_methods, compare_row
    from pickplace_cli.paths import Method
    from pickplace_cli.model.profile import load_profile
    from pickplace_cli.model.task import Task

    prof = load_profile(args.profile)
    if prof.vibration is None:
        sys.exit(f"profile {args.profile} has no vibration section: the benchmark includes the residual vibration")
    task = Task(np.array([-0.1525, 0, -0.8]), np.array([0.1525, 0, -0.8]), 0.025, 0.5)
    compare_methods(task, prof)  # warm: imports, table read and cached
    results: dict = {"machine": platform.platform(), "python": platform.python_version(), "profile": prof.name}
    t_all = []
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        comp = compare_methods(task, prof)
        t_all.append(time.perf_counter() - t0)
    assert all(r.ok for r in comp.rows), [r.error for r in comp.rows]
    results["compare_all_in_process"] = stats(t_all)
    show(f"compare, {len(comp.rows)} methods, in-process", results["compare_all_in_process"])
    per = {}
    for m in Method:
        ts = []
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            compare_row(task, prof, m)
            ts.append(time.perf_counter() - t0)
        per[m.value] = stats(ts)
        show(f"  row {m.value}", per[m.value])
    results["rows"] = per
    wall = []
    for _ in range(max(3, args.repeat // 2)):
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-m", "pickplace_cli", "compare", *ADEPT, "-p", args.profile],
                       check=True, capture_output=True)
        wall.append(time.perf_counter() - t0)
    results["compare_cli_wall"] = stats(wall)
    show("pickplace compare (all methods), wall", results["compare_cli_wall"])
    out = Path(__file__).parent / "results" / "compare.json"
    out.parent.mkdir(exist_ok=True)
    out.write_text(json.dumps(results, indent=2) + "\n")
    print(f"written {out}")


if __name__ == "__main__":
    main()
