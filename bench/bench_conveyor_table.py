"""Accuracy options of the bspline-vel table answer [Yang2022] on the held-out moves of bench_conveyor
(run: python bench/bench_conveyor_table.py [--moves N] [--polish N] [--table PATH]).

For each held-out move (bench_conveyor.random_moves: random groups, not grid nodes, fixed seed) the
reference is the best of the multi-start solve and the default "exact" solver (F with the lowest a_min
and j_min either found). Each option's F loss against it (exact peaks of its parameters, the same
normalisers) — count within 1 %, median, 95th percentile, worst:

* multilinear — the 32 corners of the query's cell (``VelTable.interpolate``);
* via-point λ — λ blended as via-point displacements (``VelTable.via_interpolate``);
* answer — the shipped answer, the better of the two by sampled F (``VelTable.lookup``), and its time;
* cubic — tensor-product cubic spline of the optima (scipy RegularGridInterpolator, method "cubic");
* nearest corner, best corner (exact F of all 32 corners: not an answer, a bound for picking one);
* with ``--polish N``: on the first N moves, SLSQP on the F stage from the multilinear answer
  (interpolated normalisers), 1, 3 and all iterations, with times.

Writes bench/results/conveyor_table.json. Not a test: timings depend on the machine and its load
(recorded).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path


def summary(losses) -> dict:
    import numpy as np

    a = np.asarray(losses, float)
    return {"within_1pct": int((a <= 0.01).sum()), "n": len(a), "median": float(np.median(a)),
            "p95": float(np.percentile(a, 95)), "max": float(a.max())}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--moves", type=int, default=200)
    ap.add_argument("--polish", type=int, default=0, help="moves on which to time an SLSQP polish of the F stage")
    ap.add_argument("--table", default=None, help="bspline-vel table (default: the shipped one)")
    args = ap.parse_args()

    import numpy as np
    from scipy.interpolate import RegularGridInterpolator

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from bench_conveyor import random_moves, write_results

    from pickplace_cli.paths import bspline_vel as bv

    from pickplace_cli.lookup import vel_slsqp as vq

    from pickplace_cli.curves import vel_problem as vp
    from pickplace_cli.lookup.vel_table import _order_knots, load_vel_table

    tab = load_vel_table(args.table)
    margin = tab.grid.margin
    cubic = RegularGridInterpolator(tuple(tab._scaled), tab.params, method="cubic")
    results: dict = {"machine": {"cpus": os.cpu_count(), "load_avg_start": os.getloadavg()}}

    def feasible(p):
        p = np.array(p, float)
        p[:4] = _order_knots(np.clip(p[:4], [margin, 2 * margin, 0.5 + margin, 0.5 + 2 * margin],
                                     [0.5 - 2 * margin, 0.5 - margin, 1 - 2 * margin, 1 - margin]), margin)
        p[4:] = np.clip(p[4:], 0.0, 1.0)
        return p

    loss: dict = {k: [] for k in ("multilinear", "via-point lambda", "answer (lookup)", "cubic spline",
                                  "nearest corner", "best corner (exact F, a bound)")}
    polish: dict = {}
    t_answer = []
    t0 = time.perf_counter()
    for i, (task, T) in enumerate(random_moves(args.moves)):
        prob = bv.make_problem(task, T)
        multi, exact = bv.solve(prob), bv.optimum(task, T, "exact", args.table)[1]
        A, J = min(multi.a_min, exact.a_min), min(multi.j_min, exact.j_min)
        f_best = max(A / r.a_max + J / r.j_max for r in (multi, exact))

        def lost(p, prob=prob, A=A, J=J, f_best=f_best):
            _, a, j = bv.exact_peaks(prob, feasible(p))
            return 1 - (A / a + J / j) / f_best

        x = tab.query_groups(task, T)
        at, w = tab._cell(x)
        corner = tab.params[tuple(at)]
        lin = w @ corner
        loss["multilinear"].append(lost(lin))
        loss["via-point lambda"].append(lost(tab.via_interpolate(x)))
        tab.lookup(task, T)
        for _ in range(10):
            s = time.perf_counter()
            p = tab.lookup(task, T)
            t_answer.append(time.perf_counter() - s)
        loss["answer (lookup)"].append(lost(p))
        loss["cubic spline"].append(lost(cubic(np.concatenate([[np.log(x[0])], x[1:]])[None])[0]))
        corner_loss = [lost(c) for c in corner]
        loss["nearest corner"].append(corner_loss[int(np.argmax(w))])
        loss["best corner (exact F, a bound)"].append(min(corner_loss))
        if i < args.polish:
            space = vq._Space(prob.lambda_free, margin)
            a_min, j_min = float(w @ tab.a_min[tuple(at)]), float(w @ tab.j_min[tuple(at)])
            for iters in (1, 3, 100):
                stage = vq._Stage(vp._Evaluator(prob), space, "F", a_min**2, j_min**2, bv.VelSettings(margin=margin))
                s = time.perf_counter()
                xs = stage.solve(space.clip(feasible(lin)[space.free]), a_min, j_min, maxiter=iters)
                dt = time.perf_counter() - s
                polish.setdefault(iters, ([], []))
                polish[iters][0].append(lost(space.full(xs)[0]))
                polish[iters][1].append(dt)
    results["wall_s"] = time.perf_counter() - t0
    for name, v in loss.items():
        results[f"F loss: {name}"] = s = summary(v)
        print(f"{name:<34} {s['within_1pct']:3d}/{s['n']} within 1 %, median {100 * s['median']:.2f} %, "
              f"p95 {100 * s['p95']:.2f} %, worst {100 * s['max']:.2f} %")
    for iters, (v, t) in polish.items():
        results[f"F loss: SLSQP polish, {iters} iterations"] = s = summary(v)
        s["time_median_s"] = float(np.median(t))
        print(f"{'SLSQP polish, ' + str(iters) + ' iterations':<34} {s['within_1pct']:3d}/{s['n']} within 1 %, median "
              f"{100 * s['median']:.2f} %, p95 {100 * s['p95']:.2f} %, worst {100 * s['max']:.2f} %, "
              f"{1e3 * s['time_median_s']:.2f} ms")
    ta = np.array(t_answer)
    results["answer time"] = {"median": float(np.median(ta)), "p95": float(np.percentile(ta, 95)), "n": len(ta)}
    print(f"answer (lookup) time: median {1e3 * np.median(ta):.3f} ms, p95 {1e3 * np.percentile(ta, 95):.3f} ms")
    write_results(results, "conveyor_table.json")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
