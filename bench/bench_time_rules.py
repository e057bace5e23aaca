"""In-process CPU time of one ``plan()`` per duration rule (``auto``, ``limits``, ``fit``), cold-ish: each call a fresh
plan of the same move, BLAS held to one thread, medians of ``--repeat`` calls after one warm-up, on the Adept cycle
of every shipped Delta/SCARA profile. ``auto`` shows the motors' fit beside its own duration, screened where the
capacity binds as ``limits`` does, so it costs no more than the default rule that contains it.

    python bench/bench_time_rules.py            # ~10 s
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from pickplace_cli import plan  # noqa: E402
from pickplace_cli.model.profile import load_profile  # noqa: E402
from pickplace_cli.model.task import Task  # noqa: E402
from pickplace_cli.planner import PlanOptions  # noqa: E402

MOVES = {
    "delta-su2018": ((-0.1525, 0.0, -0.8), (0.1525, 0.0, -0.8)),
    "delta-4axis": ((-0.1525, 0.0, -0.8), (0.1525, 0.0, -0.8)),
    "scara-600": ((0.3, -0.2, -0.1), (0.3, 0.2, -0.1)),
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=15)
    args = ap.parse_args()
    print(f"load average {os.getloadavg()[0]:.2f}; CPU ms per plan(), median of {args.repeat}")
    for name, (a, b) in MOVES.items():
        prof = load_profile(name)
        task = Task(np.array(a), np.array(b), 0.025)
        row = {}
        for rule in ("auto", "limits", "fit"):
            plan(task, prof, PlanOptions(time=rule))
            ts = []
            for _ in range(args.repeat):
                t0 = time.process_time()
                plan(task, prof, PlanOptions(time=rule))
                ts.append(time.process_time() - t0)
            row[rule] = statistics.median(ts) * 1e3
        print(f"{name:14s} " + "  ".join(f"{k} {v:6.2f}" for k, v in row.items())
              + f"  auto/limits {row['auto'] / row['limits']:.2f}")


if __name__ == "__main__":
    main()
