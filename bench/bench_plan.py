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
    from pickplace_cli.model.profile import load_profile
    from pickplace_cli.model.task import Task

    prof = load_profile("gantry")
    task = Task(np.array([-0.1525, 0, -0.8]), np.array([0.1525, 0, -0.8]), 0.025, 0.5)
    plan(task, prof)  # warm: table read and cached, scipy imported
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        plan(Task(task.p_from, task.p_to, 0.025, 0.5), prof, PlanOptions(fit=False))  # a new Task, as a caller makes
        times.append(time.perf_counter() - t0)
    return stats(times)


def bench_limits(repeat: int) -> tuple[dict, dict, dict]:
    """Delta: joint mapping + dynamics + limit check of 1,000 samples; --time fit; whole in-process plan."""
    import numpy as np

    from pickplace_cli.limits.check import check_limits
    from pickplace_cli.paths import plan_path
    from pickplace_cli.planner import PlanOptions, motion_model, plan
    from pickplace_cli.model.profile import load_profile
    from pickplace_cli.model.task import Task
    from pickplace_cli.timing import fit_duration

    prof = load_profile("delta-su2018")
    task = Task(np.array([-0.1525, 0, -0.8]), np.array([0.1525, 0, -0.8]), 0.025, 0.5)
    path = plan_path(task, "bspline")
    model = motion_model(path, prof)
    tau = np.linspace(0, 1, 1000)
    check_limits(model, 0.2, parts=model.parts(tau), dwell=0.1)
    t_map, t_fit, t_plan = [], [], []
    for _ in range(repeat):
        t0 = time.perf_counter()
        check_limits(model, 0.2, parts=model.parts(tau), dwell=0.1)
        t_map.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        fit_duration(model, 0.1, 0.18)
        t_fit.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        plan(Task(task.p_from, task.p_to, 0.025, 0.5), prof, PlanOptions(fit=False))  # a new Task, as a caller makes
        t_plan.append(time.perf_counter() - t0)
    return stats(t_map), stats(t_fit), stats(t_plan)


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
    from pickplace_cli.lookup.bspline_build import build_table, lambda_grid
    from pickplace_cli.lookup.bspline_optimum import TableSettings

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
    m, f, p = bench_limits(max(args.repeat, 30))
    results["delta_map_dynamics_check_1000"] = m
    show("Delta: IK + derivatives + dynamics + check, 1000 samples", m)
    results["delta_time_fit"] = f
    show("Delta: --time fit (fit_duration)", f)
    results["delta_plan_inprocess"] = p
    show("Delta: plan in-process (auto, 1 kHz, no fit)", p)
    results["cli_help"] = s = bench_cli(["--help"], args.repeat)
    show("pickplace --help (wall)", s)
    results["cli_version"] = s = bench_cli(["--version"], args.repeat)
    show("pickplace --version (wall)", s)
    results["cli_plan_adept_csv"] = s = bench_cli(["plan", *ADEPT, "-q"], args.repeat, stdout_file=True)
    show("pickplace plan Adept (Delta) > out.csv (wall)", s)
    results["cli_plan_adept_gantry_csv"] = s = bench_cli(["plan", "-p", "gantry", *ADEPT, "-q"], args.repeat, stdout_file=True)
    show("pickplace plan -p gantry Adept > out.csv (wall)", s)
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
