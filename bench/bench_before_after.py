"""This checkout against another revision, both sides in the same run: the verdict engine's rows per second (a
verdicts-only batch under ``--time limits`` and ``--time auto``), one plan()'s time (the Adept cycle on the default
Delta, bspline and ph, and the scara-600 move of bench/bench_default.py), and whether plan()'s durations and the
engine's summaries are the same to the bit.

    python bench/bench_before_after.py [--base main] [--moves 300] [--rounds 7] [--plans 40] [--optimal N]

The base revision's ``pickplace_cli`` is written to a temporary folder (``git archive``); every round runs one fresh
process per side, alternating (base, this, base, this, …) so that a drift of the machine's speed hits both alike;
medians over rounds. Not a test: timings depend on the machine and on what else runs on it.
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

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
CASES = [("delta-su2018", "bspline", (-0.1525, 0, -0.8), (0.1525, 0, -0.8)),
         ("delta-su2018", "ph", (-0.1525, 0, -0.8), (0.1525, 0, -0.8)),
         ("scara-600", "bspline", (0.3, -0.2, -0.1), (0.3, 0.2, -0.1))]


def worker(moves: int, plans: int, optimal: int = 0) -> dict:
    """One side's numbers, in this process (the ``pickplace_cli`` first on sys.path)."""
    import hashlib

    import numpy as np

    sys.path.insert(0, str(HERE))
    from bench_core import _batch_rows

    from pickplace_cli import planner
    from pickplace_cli.model.profile import load_profile
    from pickplace_cli.model.task import Task
    from pickplace_cli.pipelines.batch import read_batch_text
    from pickplace_cli.pipelines.verdicts import Verdict, verdict_rows

    out: dict = {"where": __import__("pickplace_cli").__file__}
    prof = load_profile("delta-su2018")
    rows, bad = read_batch_text(_batch_rows(moves), "bench")
    assert not bad, bad
    digest = hashlib.sha256()
    for rule in ("limits", "auto"):
        opts = planner.PlanOptions(fit=False, time=rule)
        got = list(verdict_rows(rows, prof, opts))  # warm
        for r in got:
            digest.update(json.dumps(r.plan.summary() if r.plan is not None else r.error, sort_keys=True).encode())
        out[f"decided_{rule}"] = sum(isinstance(r.plan, Verdict) for r in got)
        t0 = time.perf_counter()
        list(verdict_rows(rows, prof, opts))
        out[f"verdicts_per_s_{rule}"] = moves / (time.perf_counter() - t0)
    out["summaries_sha256"] = digest.hexdigest()
    durations = {}
    for prof_name, method, a, b in CASES:
        p = load_profile(prof_name)
        task = Task(np.array(a), np.array(b), p.planning.height, p.planning.eta)
        for rule in ("limits", "fit"):
            opts = planner.PlanOptions(method=method, time=rule, fit=rule == "fit")
            res = planner.plan(task, p, opts)
            durations[f"{prof_name}/{method}/{rule}"] = (res.duration.seconds.hex(),
                                                         None if res.duration.t_fit is None else res.duration.t_fit.hex())
        opts = planner.PlanOptions(method=method, time="limits", fit=False)
        t = []
        for _ in range(plans):
            t0 = time.perf_counter()
            planner.plan(task, p, opts)
            t.append(time.perf_counter() - t0)
        out[f"plan_ms_{prof_name}/{method}"] = statistics.median(t) * 1e3
    out["durations"] = durations
    if optimal:
        _optimal(out, optimal)
    return out


def _optimal(out: dict, repeat: int) -> None:
    """``plan(time="optimal")`` on the Adept cycle and the first random move of each shipped profile
    (``bench/moves.py``, seed 500): the median CPU time [ms] of ``repeat`` plans after a warm one, one BLAS thread,
    and each duration (to the bit)."""
    sys.path.append(str(ROOT))  # bench.moves and the tests' profiles; pickplace_cli stays the side's own
    from bench.moves import first_moves

    from pickplace_cli import planner
    from pickplace_cli.model.threads import single_blas_thread

    for label, prof, task in first_moves():
        opts = planner.PlanOptions(time="optimal")
        run = single_blas_thread(lambda: planner.plan(task, prof, opts))
        res = run()
        t = []
        for _ in range(repeat):
            c0 = time.process_time()
            run()
            t.append(time.process_time() - c0)
        out[f"optimal_cpu_ms_{label}"] = statistics.median(t) * 1e3
        out.setdefault("optimal_durations", {})[label] = res.duration.seconds.hex()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", default="main")
    ap.add_argument("--moves", type=int, default=300)
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--plans", type=int, default=40)
    ap.add_argument("--optimal", type=int, default=0, metavar="N",
                    help="also time plan(time='optimal') on the Adept cycle and one random move per shipped profile, "
                         "N plans a round (CPU, one BLAS thread)")
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.worker:
        print(json.dumps(worker(a.moves, a.plans, a.optimal)))
        return
    with tempfile.TemporaryDirectory() as tmp:
        arch = subprocess.run(["git", "-C", str(ROOT), "archive", a.base, "pickplace_cli", "profiles", "tables"], check=True,
                              capture_output=True).stdout
        subprocess.run(["tar", "-x", "-C", tmp], input=arch, check=True)
        sides = {"base": tmp, "this": str(ROOT)}
        runs: dict[str, list[dict]] = {s: [] for s in sides}
        for _ in range(a.rounds):
            for side, path in sides.items():
                env = dict(os.environ, PYTHONPATH=path)
                got = subprocess.run([sys.executable, __file__, "--worker", "--moves", str(a.moves), "--plans",
                                      str(a.plans), "--optimal", str(a.optimal)], env=env, check=True,
                                     capture_output=True, text=True, cwd=tmp)
                runs[side].append(json.loads(got.stdout.splitlines()[-1]))
    for side in sides:
        assert all(r["where"].startswith(sides[side]) for r in runs[side]), "a side imported the other's code"
    keys = [k for k in runs["this"][0] if k.startswith(("verdicts_per_s", "plan_ms", "optimal_cpu_ms"))]
    print(f"{a.base} against this checkout, medians of {a.rounds} rounds ({a.moves} moves, {a.plans} plans a round)")
    for k in keys:
        b, t = (statistics.median(r[k] for r in runs[s]) for s in ("base", "this"))
        print(f"  {k:<40} base {b:9.2f}   this {t:9.2f}   this/base {t / b:6.3f}")
    for k in ("decided_limits", "decided_auto", "summaries_sha256", "durations", "optimal_durations"):
        same = runs["base"][0].get(k) == runs["this"][0].get(k)
        print(f"  {k:<40} {'the same' if same else 'DIFFERENT'}")
    if "optimal_durations" in runs["this"][0] and "optimal_durations" in runs["base"][0]:
        b, t = runs["base"][0]["optimal_durations"], runs["this"][0]["optimal_durations"]
        rel = max(abs(float.fromhex(t[k]) / float.fromhex(b[k]) - 1.0) for k in t if k in b)
        print(f"  {'optimal durations: largest relative change':<40} {rel:.2e}")


if __name__ == "__main__":
    main()
