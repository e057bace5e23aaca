"""``--optimize shape`` against the table's shape and against an independent, slower search.

    python bench/bench_shape.py               # Adept timing + 5 random bspline moves per robot (~3 min on 2 cores)
    python bench/bench_shape.py --moves 2     # quick look

For each move: T_table (``--time fit`` with the table's k1, k2 and η = 0.5), T_shape (``--optimize shape
--time fit``: the shipped search, ~250 shapes screened) and T_slow, a slower search by another route — a
dense 13 × 13 × 9 grid over (k1, k2, η) and Nelder-Mead with tight tolerances from its 4 best distinct points —
screened the same way; both winners are then fitted by the continuous check. Reports T_shape/T_table, the
gap T_shape/T_slow − 1 (how much the shipped search leaves on the table), and in-process medians of
``plan --optimize shape`` with ``--time fit`` and ``--time optimal`` on the Adept cycle.
Results go to ``bench/results/shape.json``.
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
from pickplace_cli.limits.grid import _extra_points  # noqa: E402
from pickplace_cli.paths import plan_path  # noqa: E402
from pickplace_cli.planner import PlanOptions, motion_model, plan  # noqa: E402
from pickplace_cli.model.task import Task  # noqa: E402
from pickplace_cli.timing import _worst_utilisation, fit_duration, screened_root  # noqa: E402
from pickplace_cli.timing import shape as S  # noqa: E402
from tests.property.test_limit_truth import REGIONS, _profile  # noqa: E402


def slow_search(prof, task) -> tuple[float, tuple[float, float, float]]:
    """Dense grid + tight Nelder-Mead from its 4 best distinct points; returns (exact fit T, shape)."""
    from scipy.optimize import minimize

    def screen(k1, k2, eta):
        try:
            path = plan_path(Task(task.p_from, task.p_to, task.height, eta), "bspline", k1=k1, k2=k2)
            model = motion_model(path, prof)
            worst, parts = _worst_utilisation(model, prof.planning.dwell,
                                              _extra_points(path.breakpoints, path.jumps, S.SHAPE_SAMPLES))
            if S._static_excess(model, parts) > 0:
                return np.inf
            return screened_root(worst, 0.1, rtol=1e-8)
        except PickplaceError:
            return np.inf

    grid = [(a, b, e) for e in np.linspace(*S.ETA_RANGE, 9) for a in np.linspace(0.03, 0.97, 13)
            for b in np.linspace(0.03, 0.97, 13)]
    vals = np.array([screen(*g) for g in grid])
    starts = []
    for i in np.argsort(vals):
        if not np.isfinite(vals[i]):
            break
        g = np.array(grid[i])
        if all(np.any(np.abs(g - s) > np.array([0.08, 0.08, 0.1])) for s in starts):
            starts.append(g)
        if len(starts) == 4:
            break
    best = (np.inf, None)
    for s in starts:
        res = minimize(lambda x: min(screen(*x), 1e6), s, method="Nelder-Mead",
                       bounds=[S.K_SEARCH, S.K_SEARCH, S.ETA_RANGE],
                       options={"xatol": 1e-5, "fatol": 1e-9, "maxfev": 600})
        if res.fun < best[0]:
            best = (float(res.fun), tuple(float(v) for v in res.x))
    k1, k2, eta = best[1]
    path = plan_path(Task(task.p_from, task.p_to, task.height, eta), "bspline", k1=k1, k2=k2)
    return fit_duration(motion_model(path, prof), prof.planning.dwell)[0], best[1]


def one(name: str, task: Task) -> dict | None:
    prof = _profile(name)
    try:
        ref = plan(task, prof, PlanOptions(time="fit"))
        if not ref.report.ok:
            return None  # a move the table's shape cannot make (joint range, box): not a fair comparison
        t0 = time.perf_counter()
        got = plan(task, prof, PlanOptions(time="fit", shape=True))
        dt = time.perf_counter() - t0
    except PickplaceError:
        return None
    t_slow, shape_slow = slow_search(prof, task)
    T, Tt = got.duration.seconds, ref.duration.seconds
    sh = got.parameters["shape"]
    return {"profile": name, "from": task.p_from.tolist(), "to": task.p_to.tolist(), "height": task.height,
            "t_table": Tt, "t_shape": T, "t_slow": t_slow, "ratio": T / Tt, "gap": T / t_slow - 1.0,
            "shape": [sh["k1"], sh["k2"], sh["eta"]], "shape_slow": list(shape_slow), "ok": bool(got.report.ok),
            "screened": sh["shapes_screened"], "seconds": dt}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--moves", type=int, default=5, help="random moves per robot")
    ap.add_argument("-o", "--output", default=str(Path(__file__).parent / "results" / "shape.json"))
    args = ap.parse_args()

    prof = _profile("delta-su2018")
    adept = Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5)
    fit = plan(adept, prof, PlanOptions(time="fit"))
    adept_rows = {}
    for mode in ("fit", "optimal"):
        times = []
        for _ in range(5):
            t0 = time.perf_counter()
            r = plan(adept, prof, PlanOptions(time=mode, shape=True))
            times.append(time.perf_counter() - t0)
        sh = r.parameters["shape"]
        adept_rows[mode] = {"t": r.duration.seconds, "ratio": r.duration.seconds / fit.duration.seconds,
                            "median_ms": statistics.median(times) * 1e3, "ok": bool(r.report.ok),
                            "shape": [sh["k1"], sh["k2"], sh["eta"]]}
        print(f"Adept, delta-su2018: --optimize shape --time {mode}: T {r.duration.seconds:.4f} s = "
              f"{r.duration.seconds / fit.duration.seconds:.3f} × table fit ({fit.duration.seconds:.4f} s); "
              f"k1 {sh['k1']:.3f} k2 {sh['k2']:.3f} η {sh['eta']:.3f}; in-process median "
              f"{statistics.median(times) * 1e3:.0f} ms; limits ok {r.report.ok}", flush=True)
    t_slow, shape_slow = slow_search(prof, adept)
    print(f"Adept slow search: T {t_slow:.5f} s (shape {np.round(shape_slow, 3).tolist()}); shipped "
          f"{adept_rows['fit']['t']:.5f} s: gap {(adept_rows['fit']['t'] / t_slow - 1) * 100:+.2f} %", flush=True)
    rows = []
    for name in REGIONS:
        (lo, hi), (h0, h1) = REGIONS[name]
        rng = np.random.default_rng(7 + len(rows))
        done = tries = 0
        while done < args.moves and tries < 20 * args.moves:
            tries += 1
            p0, p1 = rng.uniform(lo, hi), rng.uniform(lo, hi)
            if np.linalg.norm(p1[:2] - p0[:2]) < 0.05:
                continue
            res = one(name, Task(p0, p1, float(rng.uniform(h0, h1)), 0.5))
            if res is None:
                continue
            done += 1
            rows.append(res)
            print(f"{name:13s} table {res['t_table']:.4f}  shape {res['t_shape']:.4f} ({res['ratio']:.3f} × table)  "
                  f"slow {res['t_slow']:.4f}  gap {res['gap'] * 100:+.2f} %  {res['screened']} shapes "
                  f"{res['seconds'] * 1e3:.0f} ms  ok={res['ok']}", flush=True)
    gaps = [r["gap"] for r in rows]
    ratios = [r["ratio"] for r in rows]
    summary = {"adept": adept_rows, "adept_slow": {"t": t_slow, "shape": list(shape_slow)},
               "moves": len(rows), "worst_gap": max(gaps), "median_gap": statistics.median(gaps),
               "ratio_median": statistics.median(ratios), "ratio_max": max(ratios),
               "all_ok": all(r["ok"] for r in rows),
               "plan_ms_median": statistics.median(r["seconds"] for r in rows) * 1e3, "rows": rows}
    print(f"{len(rows)} moves: T_shape/T_table median {statistics.median(ratios):.3f} max {max(ratios):.3f}; gap to "
          f"the slow search worst {max(gaps) * 100:+.2f} % median {statistics.median(gaps) * 100:+.2f} %; plan "
          f"median {summary['plan_ms_median']:.0f} ms; all limits ok {summary['all_ok']}")
    Path(args.output).parent.mkdir(parents=True, exist_ok=True)
    Path(args.output).write_text(json.dumps(summary, indent=1))


if __name__ == "__main__":
    main()
