"""Benchmarks of conveyor tracking, bspline-vel [Yang2022] (run: python bench/bench_conveyor.py [--repeat N]
[--build] [--table PATH]).

Measures, medians with min–max:

* the multi-start solve of Eq. (37) (``solve``), on the paper's two examples and on 200 random moves;
* the "seeded" solver (the table cell's seeds polished, ``optimum(..., "seeded")``) and the default
  "exact" solver (seeds and the multi-start's sampled starts, ``optimum(..., "exact")``) on the same moves;
* the table answer (lookup + interpolation);
* ``plan`` through the planner with --time SECONDS, auto and fit (Eq. 38) on the default Delta;
* with ``--build``: the full table build on all cores (``build_vel_table``), wall time.

Also reports, on the random moves (held out: random groups, not grid nodes; ``--moves``, default 200, fixed
seed), how far each answer's F is below the best F any of the solvers found (common normalisers: the
lowest a_min and j_min any found): the table alone, seeded, exact (and with check_ratio 1.2), multi-start —
median, 95th percentile, worst, count within 1 % and within 1e-6. ``--reference-starts N`` adds a
stronger multi-start (N quasi-random starts, 4 refinements per stage) to the solvers the reference is
taken over (slow; a check of the reference itself). Writes bench/results/conveyor.json. Not a test:
timings depend on the machine and its load (recorded).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import sys
import time
from pathlib import Path


def stats(samples: list[float]) -> dict:
    return {"median": statistics.median(samples), "min": min(samples), "max": max(samples), "n": len(samples)}


def show(name: str, s: dict, unit: str = "ms", scale: float = 1e3) -> None:
    print(f"{name:<52} median {s['median'] * scale:9.3f} {unit}   (min {s['min'] * scale:.3f} – max {s['max'] * scale:.3f}, n={s['n']})")


def random_moves(n: int, seed: int = 2022):
    """Held-out moves: h/b log-uniform in [0.025, 1], each v·T/b group uniform in [−0.5, 0.5], b, T random."""
    import numpy as np

    from pickplace_cli.paths.bspline_vel import task_from_groups

    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        hb = float(np.exp(rng.uniform(np.log(0.025), np.log(1.0))))
        v = rng.uniform(-0.5, 0.5, 4)
        g = dict(h_over_b=hb, eta=0.5, v0_along=v[0], v0_across=v[1], v1_along=v[2], v1_across=v[3])
        b, T = float(rng.uniform(0.1, 0.6)), float(rng.uniform(0.1, 0.5))
        out.append((task_from_groups(g, b=b, duration=T), T))
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--moves", type=int, default=200)
    ap.add_argument("--build", action="store_true", help="also time the full table build on all cores")
    ap.add_argument("--table", default=None, help="bspline-vel table (default: the shipped one)")
    ap.add_argument("--reference-starts", type=int, default=0,
                    help="also solve each move by a multi-start with this many starts (4 refinements per stage) "
                         "and include it in the reference (0: off)")
    args = ap.parse_args()

    import numpy as np

    from pickplace_cli.paths import bspline_vel as bv
    from pickplace_cli.planner import PlanOptions, plan
    from pickplace_cli.model.profile import load_profile
    from pickplace_cli.lookup.vel_table import load_vel_table
    from pickplace_cli.model.task import Task

    results: dict = {"machine": {"platform": platform.platform(), "python": sys.version.split()[0],
                                 "cpus": os.cpu_count(), "load_avg_start": os.getloadavg()},
                     "reference_starts": args.reference_starts}
    c = 0.305 / (2 * 2**0.5)
    named = {
        "paper example (Sec. 2.3.1), T = 0.25 s": (Task([0, 0, 0], [0.28, -0.2, 0], 0.04, 0.5, [0, 0.2, 0], [0, 0.2, 0]), 0.25),
        "Adept with velocity (Sec. 3), T = 0.213 s": (Task([-c, c, -0.65], [c, -c, -0.65], 0.025, 0.5, [0, 0.2, 0], [0, 0.2, 0]), 0.213),
    }
    for name, (task, T) in named.items():
        prob = bv.make_problem(task, T)
        bv.solve(prob)  # warm: imports
        times = []
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            bv.solve(prob)
            times.append(time.perf_counter() - t0)
        results[f"multi-start {name}"] = s = stats(times)
        show(f"multi-start solve: {name}", s)

    moves = random_moves(args.moves)
    tab = load_vel_table(args.table)
    t_multi, t_seed, t_exact, t_fast, t_table, t_strong = [], [], [], [], [], []
    loss: dict = {"table": [], "seeded": [], "exact": [], "exact, check_ratio 1.2": [], "multi-start": []}
    fast_settings = bv.VelSettings(check_ratio=1.2)
    strong_name = f"multi-start, {args.reference_starts} starts"
    if args.reference_starts:
        loss[strong_name] = []
        strong_settings = bv.VelSettings(starts=args.reference_starts, refine=4, refine_F=4)
    for task, T in moves:
        prob = bv.make_problem(task, T)
        t0 = time.perf_counter()
        multi = bv.solve(prob)
        t_multi.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        seeded = bv.optimum(task, T, "seeded", args.table)[1]
        t_seed.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        exact = bv.optimum(task, T, "exact", args.table)[1]
        t_exact.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        fast = bv.optimum(task, T, "exact", args.table, fast_settings)[1]
        t_fast.append(time.perf_counter() - t0)
        for _ in range(10):
            t0 = time.perf_counter()
            p = tab.lookup(task, T)
            t_table.append(time.perf_counter() - t0)
        solved = {"seeded": seeded, "exact": exact, "exact, check_ratio 1.2": fast, "multi-start": multi}
        if args.reference_starts:
            t0 = time.perf_counter()
            solved[strong_name] = bv.solve(prob, strong_settings)
            t_strong.append(time.perf_counter() - t0)
        A = min(r.a_min for r in solved.values())
        J = min(r.j_min for r in solved.values())
        f_best = max(A / r.a_max + J / r.j_max for r in solved.values())
        _, a, j = bv.exact_peaks(prob, p)
        loss["table"].append(1 - (A / a + J / j) / f_best)
        for name, r in solved.items():
            loss[name].append(1 - (A / r.a_max + J / r.j_max) / f_best)
    for name, t in (("multi-start", t_multi), ("seeded (table seeds)", t_seed), ("exact (seeds + multi-start samples)", t_exact),
                    ("exact, check_ratio 1.2", t_fast)) + (((strong_name, t_strong),) if t_strong else ()):
        results[f"{name} random moves"] = s = stats(t)
        show(f"{name} solve: {args.moves} random moves", s)
    results["table lookup"] = s = stats(t_table)
    show("table answer (lookup + interpolation)", s)
    for name, v in loss.items():
        arr = np.array(v)
        results[f"F loss vs best: {name}"] = {"median": float(np.median(arr)), "p95": float(np.percentile(arr, 95)),
                                             "max": float(arr.max()), "within_1pct": int((arr <= 0.01).sum()),
                                             "within_1e-6": int((arr <= 1e-6).sum()), "n": len(arr)}
        print(f"{'F below best: ' + name:<52} median {100 * np.median(arr):.3f} %, p95 {100 * np.percentile(arr, 95):.3f} %, "
              f"worst {100 * arr.max():.3f} %, {(arr <= 0.01).sum()}/{len(arr)} within 1 %, "
              f"{(arr <= 1e-6).sum()}/{len(arr)} within 1e-6")

    prof = load_profile("delta-su2018")
    belt = Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5, [0.3, 0, 0], [0, 0.3, 0])
    for spec, reps in ((0.2, args.repeat), ("auto", max(2, args.repeat // 2)), ("fit", max(2, args.repeat // 2))):
        times = []
        for _ in range(reps):
            t0 = time.perf_counter()
            r = plan(belt, prof, PlanOptions(method="bspline-vel", time=spec))
            times.append(time.perf_counter() - t0)
        results[f"plan time={spec}"] = s = stats(times)
        s["duration_s"] = r.duration.seconds
        show(f"plan Delta Adept + belts, --time {spec} (T = {r.duration.seconds:.4f} s)", s)

    if args.build:
        from pickplace_cli.lookup.vel_table import VelGrid, build_vel_table

        t0 = time.perf_counter()
        built = build_vel_table(VelGrid(), workers=os.cpu_count() or 1)
        results["build"] = {"seconds": time.perf_counter() - t0, "workers": os.cpu_count(),
                            "solved_nodes": built.meta["solved_nodes"]}
        print(f"{'table build, all cores':<52} {results['build']['seconds']:.1f} s ({built.meta['solved_nodes']} solves, {os.cpu_count()} workers)")
    write_results(results, "conveyor.json")
    return 0


def write_results(results: dict, name: str) -> None:
    """Record the end load average and write ``results`` to bench/results/``name`` (JSON)."""
    results["machine"]["load_avg_end"] = os.getloadavg()
    out = Path(__file__).resolve().parent / "results" / name
    out.parent.mkdir(exist_ok=True)
    out.write_text(json.dumps(results, indent=2) + "\n")
    print(f"written {out}")


if __name__ == "__main__":
    raise SystemExit(main())
