"""Benchmarks of the foundation (run: python bench/bench_plan.py [--table] [--repeat N]).

Prints medians with min–max and writes bench/results/plan.json. Not a test: timings depend on the
machine; the README records the numbers measured on the reference machine.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ADEPT = ["--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8"]


def stats(samples: list[float]) -> dict:
    return {"median": statistics.median(samples), "min": min(samples), "max": max(samples), "n": len(samples)}


def show(name: str, s: dict, unit: str = "ms", scale: float = 1e3) -> None:
    print(f"{name:<46} median {s['median'] * scale:9.3f} {unit}   (min {s['min'] * scale:.3f} – max {s['max'] * scale:.3f}, n={s['n']})")


def bench_inprocess(repeat: int) -> dict:
    import numpy as np

    from pickplace_cli.planner import PlanOptions, plan
    from pickplace_cli.profile import load_profile
    from pickplace_cli.task import Task

    prof = load_profile("gantry")
    task = Task(np.array([-0.1525, 0, -0.8]), np.array([0.1525, 0, -0.8]), 0.025, 0.5)
    plan(task, prof)  # warm: table read and cached, scipy imported
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        plan(task, prof, PlanOptions())
        times.append(time.perf_counter() - t0)
    return stats(times)


def bench_cli(args: list[str], repeat: int, stdout_file: bool = False) -> dict:
    exe = shutil.which("pickplace")
    cmd = [exe] if exe else [sys.executable, "-m", "pickplace_cli"]
    times = []
    with tempfile.TemporaryDirectory() as d:
        for _ in range(repeat):
            out = open(os.path.join(d, "out.csv"), "w") if stdout_file else subprocess.DEVNULL
            t0 = time.perf_counter()
            subprocess.run(cmd + args, stdout=out, stderr=subprocess.DEVNULL, check=True)
            times.append(time.perf_counter() - t0)
            if stdout_file:
                out.close()
    return stats(times)


def bench_table(workers: int) -> dict:
    from pickplace_cli.table import TableSettings, build_table, lambda_grid

    t0 = time.perf_counter()
    build_table(lambda_grid(1, 40, 0.5), TableSettings(), workers=workers)
    return stats([time.perf_counter() - t0])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeat", type=int, default=20)
    ap.add_argument("--table", action="store_true", help="also time the default table build (tens of seconds)")
    args = ap.parse_args()
    results: dict = {
        "machine": {"python": platform.python_version(), "platform": platform.platform(), "cpus": os.cpu_count()},
    }
    results["plan_inprocess_adept_1kHz"] = s = bench_inprocess(max(args.repeat, 50))
    show("plan in-process (Adept, gantry, 1 kHz)", s)
    results["cli_help"] = s = bench_cli(["--help"], args.repeat)
    show("pickplace --help (wall)", s)
    results["cli_version"] = s = bench_cli(["--version"], args.repeat)
    show("pickplace --version (wall)", s)
    results["cli_plan_adept_csv"] = s = bench_cli(["plan", *ADEPT, "-q"], args.repeat, stdout_file=True)
    show("pickplace plan Adept > out.csv (wall)", s)
    if args.table:
        for w in (1, os.cpu_count() or 1):
            results[f"build_table_default_workers{w}"] = s = bench_table(w)
            show(f"build-table default grid, {w} worker(s)", s, "s", 1.0)
    out = Path(__file__).parent / "results" / "plan.json"
    out.parent.mkdir(exist_ok=True)
    out.write_text(json.dumps(results, indent=2) + "\n")
    print(f"written {out}")


if __name__ == "__main__":
    main()
