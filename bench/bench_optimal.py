"""``--time optimal`` against ``--time fit`` and against an independent, slower solve.

    python bench/bench_optimal.py --moves 4                      # Adept timing + 60 random moves (~20 min, 2 cores)
    python bench/bench_optimal.py --moves 4 --coefficients 20    # the same for plan --law-coefficients 20
    python bench/bench_optimal.py --moves 2                      # quick look
    python bench/bench_optimal.py --moves 4 --seed 1000          # a held-out set of 60 other random moves

For each move: T_fit (uniform law), T_opt (``plan --time optimal`` with ``--coefficients`` law coefficients,
default auto: 20, refined to 40 when the law is more than 10 % faster than uniform; on its 161-point grid plus
the check rounds) and T_slow (an independent slower solve: twice the most coefficients the plan may use — 80
for auto — on uniform knots and a 321-point grid, directly from the uniform law), each fitted by the continuous check on the
composed path. Reports T_opt/T_fit, the gap T_opt/min(T_slow, T_opt) − 1 (target ≤ 1 %), that T_opt ≤ T_fit
always (a fallback to the uniform law is counted), and in-process medians of ``plan --time optimal`` on the
Adept cycle. Random moves: ``--moves`` per method (bspline, ph, superposition, lame, piecewise-poly) × 3 robots
(the gantry with the drives of ``tests/property/test_limit_truth.py``).
Results go to ``bench/results/optimal.json``.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from pickplace_cli.model.errors import PickplaceError  # noqa: E402
from pickplace_cli.planner import PlanOptions, motion_model, plan  # noqa: E402
from pickplace_cli.model.task import Task  # noqa: E402
from pickplace_cli.timing import fit_duration  # noqa: E402
from pickplace_cli.timing import optimal as O  # noqa: E402
from tests.property.test_limit_truth import REGIONS, _profile  # noqa: E402

METHODS = ["bspline", "ph", "superposition", "lame", "piecewise-poly"]


def slow_solve(model, dwell: float, t_fit: float) -> float:
    """The slower solve: 2× the law coefficients on 2× the grid; its duration fitted on the composed path."""
    grid0 = O.LAW_GRID
    try:
        O.LAW_GRID = 321
        law = O.optimal_law(model, dwell, t_fit, coefficients=2 * (COEFFICIENTS[0] or O.LAW_REFINED), direct=True)
        T, _ = fit_duration(motion_model(law.path, _PROF[0]), dwell, start=law.t_estimate)
    finally:
        O.LAW_GRID = grid0
    return float(T)


_PROF: list = [None]
#: the shipped solve's law coefficients (``--coefficients``; None: auto); the slow solve takes twice the most the
#: plan may use, directly
COEFFICIENTS: list = [None]


def one(name: str, method: str, task: Task) -> dict | None:
    prof = _profile(name)
    _PROF[0] = prof
    dwell = prof.planning.dwell
    try:
        fit = plan(task, prof, PlanOptions(method=method, time="fit"))
    except PickplaceError:
        return None
    t0 = time.perf_counter()
    opt = plan(task, prof, PlanOptions(method=method, time="optimal", law_coefficients=COEFFICIENTS[0]))
    dt = time.perf_counter() - t0
    model = motion_model(fit.cartesian.path, prof)
    t_slow = slow_solve(model, dwell, fit.duration.seconds)
    T, Tf = opt.duration.seconds, fit.duration.seconds
    return {"profile": name, "method": method, "from": task.p_from.tolist(), "to": task.p_to.tolist(),
            "height": task.height, "t_fit": Tf, "t_optimal": T, "t_slow": t_slow, "ratio": T / Tf,
            "gap": T / min(t_slow, T) - 1.0, "slow_better_by": T / t_slow - 1.0, "ok": bool(opt.report.ok),
            "coefficients": opt.parameters.get("law_coefficients"),
            "fallback": opt.duration.law == "uniform (fallback)", "seconds": dt}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--moves", type=int, default=3, help="random moves per method and robot")
    ap.add_argument("--coefficients", type=int, default=None, help="the law's coefficients (plan --law-coefficients; "
                    "default auto); the slow solve takes twice the most the plan may use, from the uniform law")
    ap.add_argument("--seed", type=int, default=100, help="first seed of the random moves (another seed: a held-out "
                    "set of moves, e.g. to check that constants tuned on the default set still hold)")
    ap.add_argument("-o", "--output", default=str(Path(__file__).parent / "results" / "optimal.json"))
    args = ap.parse_args()
    COEFFICIENTS[0] = args.coefficients
    from pickplace_cli.model.profile import load_profile

    prof = load_profile("delta-su2018")
    adept = Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5)
    times = []
    for _ in range(7):
        t0 = time.perf_counter()
        r = plan(adept, prof, PlanOptions(time="optimal", law_coefficients=args.coefficients))
        times.append(time.perf_counter() - t0)
    fit = plan(adept, prof, PlanOptions(time="fit"))
    print(f"Adept cycle, delta-su2018, bspline: T_fit {fit.duration.seconds:.4f} s, T_optimal "
          f"{r.duration.seconds:.4f} s = {r.duration.seconds / fit.duration.seconds:.4f} × fit; in-process plan "
          f"--time optimal median {statistics.median(times) * 1e3:.0f} ms (min {min(times) * 1e3:.0f}), limits ok "
          f"{r.report.ok}")
    rows = []
    for name in REGIONS:
        (lo, hi), (h0, h1) = REGIONS[name]
        for method in METHODS:
            rng = np.random.default_rng(args.seed + len(rows))
            done = 0
            while done < args.moves:
                p0, p1 = rng.uniform(lo, hi), rng.uniform(lo, hi)
                if np.linalg.norm(p1[:2] - p0[:2]) < 0.05:
                    continue
                res = one(name, method, Task(p0, p1, float(rng.uniform(h0, h1)), 0.5))
                if res is None:
                    continue
                done += 1
                rows.append(res)
                print(f"{name:13s} {method:15s} fit {res['t_fit']:.4f}  optimal {res['t_optimal']:.4f} "
                      f"({res['ratio']:.3f} × fit, {res['coefficients']} coef.)  slow {res['t_slow']:.4f}  gap {res['gap'] * 100:+.2f} %  "
                      f"{'fallback ' if res['fallback'] else ''}{res['seconds'] * 1e3:.0f} ms  ok={res['ok']}", flush=True)
    gaps = [r["gap"] for r in rows]
    ratios = [r["ratio"] for r in rows]
    summary = {
        "command": "python bench/bench_optimal.py " + " ".join(sys.argv[1:]), "coefficients": args.coefficients,
        "adept": {"t_fit": fit.duration.seconds, "t_optimal": r.duration.seconds,
                  "median_ms": statistics.median(times) * 1e3},
        "moves": len(rows), "worst_gap": max(gaps), "median_gap": statistics.median(gaps),
        "ratio_min": min(ratios), "ratio_median": statistics.median(ratios), "ratio_max": max(ratios),
        "fallbacks": sum(r["fallback"] for r in rows), "all_ok": all(r["ok"] for r in rows),
        "plan_ms_median": statistics.median(r["seconds"] for r in rows) * 1e3, "rows": rows,
    }
    print(f"{len(rows)} moves: T_opt/T_fit min {min(ratios):.3f} median {statistics.median(ratios):.3f} max "
          f"{max(ratios):.3f}; gap to the slow solve worst {max(gaps) * 100:.2f} % median "
          f"{statistics.median(gaps) * 100:.2f} %; fallbacks {summary['fallbacks']}; all limits ok {summary['all_ok']}")
    Path(args.output).parent.mkdir(parents=True, exist_ok=True)
    Path(args.output).write_text(json.dumps(summary, indent=1))


if __name__ == "__main__":
    main()
