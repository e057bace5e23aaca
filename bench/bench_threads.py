"""BLAS threads: OpenBLAS's default (one thread per core) against one thread, idle and under load, in one run.

    python bench/bench_threads.py                 # 5 repeats in process, 3 batches; idle, then with 10 busy loops
    python bench/bench_threads.py --load 0        # idle only
    python bench/bench_threads.py --repeats 3 --batches 1 --rows 8 --busy 10

Cases, each measured as a median:
* ``optimal``: ``plan(--time optimal)`` of the Adept cycle in process (the first call, which loads the modules and
  the table, is not counted);
* ``shape``: ``plan(--time fit --optimize shape)`` of the Adept cycle in process;
* ``batch -j 2``: wall time of ``pickplace plan --batch ROWS -j 2 --json`` of ``--rows`` (default 8) random Delta
  moves with ``time = optimal`` (a CLI run: start-up included).

"default" runs with ``OPENBLAS_NUM_THREADS`` set to the number of cores (what OpenBLAS does when nothing pins it, as
before this release), "pinned" with ``OPENBLAS_NUM_THREADS=1`` (what the CLI now sets and the library's
``single_blas_thread`` does). Both configurations run in fresh interpreters, alternating, in the same phase; the load
phase starts ``--busy`` processes that spin (``while True: pass``) and stops them after. The machine's load average
is printed with each phase (other users of a shared machine add to it). Results also go to
``bench/results/threads.json``.
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

ROOT = Path(__file__).resolve().parents[1]

IN_PROCESS = r"""
import json, statistics, sys, time
sys.path.insert(0, {root!r})
from pickplace_cli.model.profile import load_profile
from pickplace_cli.model.task import Task
from pickplace_cli.planner import PlanOptions, plan
prof = load_profile("delta-su2018")
task = Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5)
cases = {{"optimal": PlanOptions(time="optimal"), "shape": PlanOptions(time="fit", shape=True)}}
out = {{}}
for name, opts in cases.items():
    plan(task, prof, opts)
    ts = []
    for _ in range({repeats}):
        t = time.perf_counter(); plan(task, prof, opts); ts.append(time.perf_counter() - t)
    out[name] = statistics.median(ts)
print(json.dumps(out))
"""


def _env(threads: int) -> dict:
    env = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
                                                               "OMP_NUM_THREADS", "BLIS_NUM_THREADS")}
    env["OPENBLAS_NUM_THREADS"] = str(threads)
    return env


def _rows(path: Path, n: int = 8, seed: int = 7) -> None:
    import random

    rng = random.Random(seed)
    lines = ["from_x,from_y,from_z,to_x,to_y,to_z,time"]
    for _ in range(n):
        a = [rng.uniform(-0.2, 0.2), rng.uniform(-0.2, 0.2), rng.uniform(-0.9, -0.75)]
        b = [rng.uniform(-0.2, 0.2), rng.uniform(-0.2, 0.2), rng.uniform(-0.9, -0.75)]
        lines.append(",".join(f"{x:.4f}" for x in a + b) + ",optimal")
    path.write_text("\n".join(lines) + "\n")


def measure(threads: int, repeats: int, batches: int, rows: Path) -> dict:
    """Medians [s] of the three cases with ``threads`` BLAS threads."""
    code = IN_PROCESS.format(root=str(ROOT), repeats=repeats)
    out = json.loads(subprocess.run([sys.executable, "-c", code], env=_env(threads), capture_output=True, text=True,
                                    check=True).stdout.strip().splitlines()[-1])
    walls = []
    for _ in range(batches):
        t = time.perf_counter()
        subprocess.run([sys.executable, "-m", "pickplace_cli", "plan", "--batch", str(rows), "-j", "2", "--json", "-q"],
                       env=_env(threads), capture_output=True, check=False, cwd=ROOT)
        walls.append(time.perf_counter() - t)
    out["batch -j 2"] = statistics.median(walls)
    return out


def phase(label: str, busy: int, repeats: int, batches: int, rows: Path) -> dict:
    procs = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(busy)]
    try:
        if busy:
            time.sleep(5)  # let the load average climb a little (it lags: the busy loops are the load)
        load = os.getloadavg()[0]
        cores = os.cpu_count() or 1
        res = {}
        for threads in (cores, 1):  # same phase, same conditions: default first, then pinned
            res["default" if threads == cores else "pinned"] = measure(threads, repeats, batches, rows)
        res["load_1min"] = load
        res["busy_loops"] = busy
    finally:
        for p in procs:
            p.kill()
            p.wait()
    print(f"--- {label}: {busy} busy loops, load average {load:.1f} (1 min) ---", flush=True)
    for case in ("optimal", "shape", "batch -j 2"):
        d, p = res["default"][case], res["pinned"][case]
        print(f"{case:12s} default ({cores} threads) {d * 1e3:8.0f} ms   pinned (1 thread) {p * 1e3:8.0f} ms   "
              f"ratio {d / p:5.2f}", flush=True)
    return res


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5, help="in-process repeats per case (median)")
    ap.add_argument("--batches", type=int, default=3, help="CLI batch runs per configuration (median)")
    ap.add_argument("--busy", type=int, default=10, help="busy-loop processes of the loaded phase")
    ap.add_argument("--load", type=int, choices=(0, 1), default=1, help="also run the loaded phase (1) or not (0)")
    ap.add_argument("--rows", type=int, default=8, help="optimal rows of the -j 2 batch")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        rows = Path(tmp) / "optimal_rows.csv"
        _rows(rows, args.rows)
        results = {"idle": phase("idle", 0, args.repeats, args.batches, rows)}
        if args.load:
            results["loaded"] = phase("loaded", args.busy, args.repeats, args.batches, rows)
    out = ROOT / "bench" / "results" / "threads.json"
    out.write_text(json.dumps(results, indent=2) + "\n")
    print(f"written {out.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
