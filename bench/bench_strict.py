"""What ``plan --strict`` costs: the in-process CPU time of a plan with and without ``PlanOptions(strict=True)`` (the
written samples read as ``check --strict`` reads them, and the law slowed until every peak is resolved), per duration
rule, on the Adept cycle and the first plannable random move of each shipped profile (``bench/moves.first_moves``),
both sides in the same run; and the stretch ``--strict`` adds.

    python bench/bench_strict.py [--repeat 7]

Medians of ``--repeat`` plans after a warm one, one BLAS thread (``time.process_time``). Results in
``bench/results/strict.json``. Not a test: timings depend on the machine and on what else runs on it.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pickplace_cli.model.errors import PickplaceError  # noqa: E402
from pickplace_cli.planner import PlanOptions, plan  # noqa: E402
from bench.moves import first_moves  # noqa: E402

RULES = ("limits", "fit", "optimal")


def timed(task, prof, options, repeat: int):
    plan(task, prof, options)
    times, got = [], None
    for _ in range(repeat):
        c0 = time.process_time()
        got = plan(task, prof, options)
        times.append(time.process_time() - c0)
    return statistics.median(times), got


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("-o", "--output", default=str(ROOT / "bench" / "results" / "strict.json"))
    args = ap.parse_args()
    rows = []
    for label, prof, task in first_moves():
        for rule in RULES:
            try:
                base, plain = timed(task, prof, PlanOptions(time=rule), args.repeat)
                cost, strict = timed(task, prof, PlanOptions(time=rule, strict=True), args.repeat)
            except PickplaceError as exc:  # (the gantry has no timed joint limit: no fit or optimal law)
                print(f"{label:13s} {rule:8s} not planned: {exc}", flush=True)
                continue
            row = {"move": label, "rule": rule, "ms": base * 1e3, "strict_ms": cost * 1e3,
                   "T": plain.duration.seconds, "T_strict": strict.duration.seconds,
                   "stretch": strict.duration.seconds / plain.duration.seconds,
                   "exit_code": strict.report.exit_code()}
            rows.append(row)
            print(f"{label:13s} {rule:8s} {row['ms']:7.1f} ms → --strict {row['strict_ms']:7.1f} ms "
                  f"(+{row['strict_ms'] - row['ms']:.1f}); T {row['T']:.5f} → {row['T_strict']:.5f} s "
                  f"(× {row['stretch']:.5f}), exit {row['exit_code']}", flush=True)
    Path(args.output).write_text(json.dumps({"command": "python bench/bench_strict.py " + " ".join(sys.argv[1:]),
                                             "load_average": list(os.getloadavg()), "rows": rows}, indent=1))


if __name__ == "__main__":
    main()
