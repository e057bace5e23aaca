"""``plan(time="optimal")`` of this checkout against another git revision, on the same moves in the same run: the
cold in-process CPU time of each plan (``time.process_time``, one BLAS thread), medians per profile, and the
durations each side writes (their ratio: a speed-up that changes the answer shows here).

    python bench/bench_optimal_revisions.py --base main [--moves 30] [--rounds 3] [-o FILE]

Moves: the Adept cycle and the first ``--moves`` plannable random moves of each shipped profile (``bench/moves.py``,
seed 500; the gantry with the drives of ``tests/property/test_limit_truth.py``). Each side runs in its own process
(the base from a temporary ``git worktree`` of the revision), the sides alternating round by round so that a
machine busy with other work slows both alike; a plan's time is the median over the rounds. The default plan's
time is measured by this checkout's processes in the same rounds (the issue's ratio to it).

Not a test: timings depend on the machine and on what else runs on it.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def worker(moves: int, seed: int) -> None:
    """In the side's own process (its checkout first on sys.path): each move planned once warm-up, then timed; one
    JSON line per move on stdout."""
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    import time

    from bench.moves import measured
    from pickplace_cli.model.errors import PickplaceError
    from pickplace_cli.model.threads import single_blas_thread
    from pickplace_cli.planner import PlanOptions, plan

    @single_blas_thread
    def measure(label, prof, task):
        try:
            plan(task, prof, PlanOptions())
        except PickplaceError:
            return None
        c0 = time.process_time()
        plan(task, prof, PlanOptions())
        c1 = time.process_time()
        try:
            res = plan(task, prof, PlanOptions(time="optimal"))
        except PickplaceError as exc:
            return {"label": label, "error": str(exc)}
        c2 = time.process_time()
        return {"label": label, "default_ms": (c1 - c0) * 1e3, "optimal_ms": (c2 - c1) * 1e3,
                "T": res.duration.seconds, "ok": bool(res.report.ok)}

    from pickplace_cli.model.task import Task
    from tests.property.test_limit_truth import _profile

    # the modules the optimal plan loads on its first call (scipy.optimize, the QP solver), loaded on another move
    plan(Task([-0.15, 0.05, -0.8], [0.15, 0.05, -0.8], 0.025, 0.5),
         _profile("delta-su2018"), PlanOptions(time="optimal"))
    for row in measured(seed, moves, measure):
        print(json.dumps(row), flush=True)


def run_side(checkout: Path, moves: int, seed: int) -> list[dict]:
    env = dict(os.environ, PYTHONPATH=str(checkout), OPENBLAS_NUM_THREADS="1")
    out = subprocess.run([sys.executable, str(Path(__file__).resolve()), "--worker", "--moves", str(moves),
                          "--seed", str(seed)], cwd=str(checkout), env=env, capture_output=True, text=True,
                         check=True)
    return [json.loads(line) for line in out.stdout.splitlines() if line.startswith("{")]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--base", default="main", help="the git revision to compare with")
    ap.add_argument("--moves", type=int, default=30, help="random moves per shipped profile")
    ap.add_argument("--seed", type=int, default=500)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("-o", "--output", default=None, help="JSON results (default: print only)")
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        worker(args.moves, args.seed)
        return
    with tempfile.TemporaryDirectory() as tmp:
        base = Path(tmp) / "base"
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "-q", "--detach", str(base), args.base], check=True)
        try:
            runs: dict = {"base": [], "this": []}
            for r in range(args.rounds):
                for side, checkout in (("base", base), ("this", ROOT)) if r % 2 == 0 else (("this", ROOT), ("base", base)):
                    runs[side].append(run_side(checkout, args.moves, args.seed))
                    print(f"round {r + 1}/{args.rounds}: {side} done", file=sys.stderr, flush=True)
        finally:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(base)], check=False)
    moves = len(runs["this"][0])
    rows = []
    for i in range(moves):
        this = [run[i] for run in runs["this"]]
        base_ = [run[i] for run in runs["base"]]
        if any("error" in x for x in this + base_):
            rows.append({"label": this[0]["label"], "error": next(x["error"] for x in this + base_ if "error" in x)})
            continue
        rows.append({"label": this[0]["label"],
                     "default_ms": statistics.median(x["default_ms"] for x in this),
                     "this_ms": statistics.median(x["optimal_ms"] for x in this),
                     "base_ms": statistics.median(x["optimal_ms"] for x in base_),
                     "T_ratio": this[0]["T"] / base_[0]["T"], "ok": this[0]["ok"]})
    good = [r for r in rows if "error" not in r]
    print(f"{'profile':14s} {'moves':>5s} {'default':>8s} {'base':>8s} {'this':>8s} {'this/base':>9s} "
          f"{'this/default':>12s} {'T this/base (min..max)':>26s}   [ms CPU, medians]")
    for label in dict.fromkeys(r["label"] for r in good):
        sel = [r for r in good if r["label"] == label]
        med = {k: statistics.median(r[k] for r in sel) for k in ("default_ms", "this_ms", "base_ms")}
        t = [r["T_ratio"] for r in sel]
        print(f"{label:14s} {len(sel):5d} {med['default_ms']:8.1f} {med['base_ms']:8.1f} {med['this_ms']:8.1f} "
              f"{statistics.median(r['this_ms'] / r['base_ms'] for r in sel):9.3f} "
              f"{med['this_ms'] / med['default_ms']:12.1f} "
              f"{statistics.median(t):10.7f} ({min(t):.7f}..{max(t):.7f})")
    errors = [r for r in rows if "error" in r]
    if errors:
        print(f"{len(errors)} move(s) refused by a side: " + "; ".join(f"{r['label']}: {r['error']}" for r in errors[:3]))
    print(f"not ok (this side): {sum(not r['ok'] for r in good)}")
    if args.output:
        Path(args.output).write_text(json.dumps({"base": args.base, "moves": args.moves, "seed": args.seed,
                                                 "rounds": args.rounds, "rows": rows}, indent=1))


if __name__ == "__main__":
    main()
