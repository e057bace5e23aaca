"""``--law-coefficients auto`` against 20 coefficients, side by side on the same moves.

    python bench/bench_law_auto.py            # the 120 moves of bench/results/optimal*.json (~1.5 min, 2 cores)
    python bench/bench_law_auto.py --moves 20 # quick look

For every move of ``bench/results/optimal.json`` and ``optimal_heldout.json`` (written by bench_optimal.py, the
default and the ``--seed 1000`` sets) plans ``--time optimal`` with 20 coefficients and with auto, one after the
other, and reports: on how many moves auto is longer (it must be none: a refined law is fitted next to its first
law and the shorter kept), T_auto / T_20 (median, min), the in-process plan times (medians and their ratio) and the
slowest auto plan. Prints one line; ``-o`` also writes it to a file.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pickplace_cli.model.task import Task  # noqa: E402
from pickplace_cli.planner import PlanOptions, plan  # noqa: E402
from tests.property.test_limit_truth import _profile  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--moves", type=int, default=0, help="only the first N moves (0: all)")
    ap.add_argument("-o", "--output", help="also write the result line to this file")
    args = ap.parse_args()
    res = ROOT / "bench" / "results"
    rows = json.loads((res / "optimal.json").read_text())["rows"] + json.loads((res / "optimal_heldout.json").read_text())["rows"]
    if args.moves:
        rows = rows[: args.moves]
    worse, ta, t20, ratio, slowest = 0, [], [], [], (0.0, "", 0.0)
    for r in rows:
        prof = _profile(r["profile"])
        task = Task(r["from"], r["to"], r["height"], 0.5)
        t0 = time.perf_counter()
        p20 = plan(task, prof, PlanOptions(method=r["method"], time="optimal", law_coefficients=20))
        d20 = time.perf_counter() - t0
        t0 = time.perf_counter()
        pa = plan(task, prof, PlanOptions(method=r["method"], time="optimal"))
        da = time.perf_counter() - t0
        ta.append(da)
        t20.append(d20)
        ratio.append(pa.duration.seconds / p20.duration.seconds)
        if pa.duration.seconds > p20.duration.seconds * (1 + 1e-9):
            worse += 1
            print("longer:", r["profile"], r["method"], pa.duration.seconds, p20.duration.seconds, flush=True)
        if not pa.report.ok:
            print("LIMIT BROKEN:", r, flush=True)
        if da > slowest[0]:
            slowest = (da, f"{r['profile']} {r['method']}", d20)
    line = (f"{len(rows)} moves: auto longer than 20 on {worse}; T_auto/T_20 median {statistics.median(ratio):.4f} "
            f"min {min(ratio):.4f}; plan median auto {statistics.median(ta) * 1e3:.0f} ms vs 20 "
            f"{statistics.median(t20) * 1e3:.0f} ms (ratio of medians {statistics.median(ta) / statistics.median(t20):.2f}); "
            f"slowest auto {slowest[0] * 1e3:.0f} ms ({slowest[1]}; 20: {slowest[2] * 1e3:.0f} ms)")
    print(line)
    if args.output:
        Path(args.output).write_text(line + "\n")


if __name__ == "__main__":
    main()
