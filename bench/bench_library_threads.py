"""`--time optimal` through the library (no BLAS setting of the user's) against the same plan as the CLI runs it
(OPENBLAS_NUM_THREADS=1 set before numpy loads), each in its own fresh process, the in-process time of the plan.

    python bench/bench_library_threads.py [--repeat 15]

Both sides alternate in one run. Writes bench/results/library_threads.json. Not a test.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

OUT = Path(__file__).resolve().parent / "results" / "library_threads.json"
CODE = r"""
import time
from pickplace_cli import PlanOptions, Task, load_profile, plan
prof = load_profile("delta-su2018")
task = Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], height=0.025)
plan(task, prof, PlanOptions(time="optimal"))  # first call: imports, table, controller
times = []
for _ in range(5):
    t0 = time.perf_counter()
    plan(task, prof, PlanOptions(time="optimal"))
    times.append(time.perf_counter() - t0)
print(min(times))
"""


def one(cli_like: bool) -> float:
    env = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
                                                               "OMP_NUM_THREADS", "BLIS_NUM_THREADS")}
    if cli_like:
        env["OPENBLAS_NUM_THREADS"] = "1"
    out = subprocess.run([sys.executable, "-c", CODE], env=env, capture_output=True, text=True, check=True).stdout
    return float(out.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeat", type=int, default=15)
    args = ap.parse_args()
    lib, cli = [], []
    for _ in range(args.repeat):
        lib.append(one(False))
        cli.append(one(True))
    res = {"command": f"python bench/bench_library_threads.py --repeat {args.repeat}", "load_average": os.getloadavg(),
           "cores": os.cpu_count(), "library_s": statistics.median(lib), "cli_s": statistics.median(cli),
           "ratio": statistics.median(lib) / statistics.median(cli)}
    OUT.write_text(json.dumps(res, indent=2) + "\n")
    print(json.dumps(res, indent=2))


if __name__ == "__main__":
    main()
