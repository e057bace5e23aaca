"""Interpolation error of the 2-D (λ, η) table, and its build time
(run: python bench/bench_table2d.py [--points N] [--table PATH] [--build-lambda-points N] [--workers N]).

Held-out points: ``--points`` (λ, η), fixed seed, λ log-uniform in [0.5, 200], η uniform in [0.1, 0.9]
(grid nodes are never drawn exactly). The reference at each is build-table's optimiser at that (λ, η)
(``optimise_lambda``, the build's settings: start grid 0.01), i.e. F* and its normalisers a_min, j_min.
The answer is what ``plan`` uses: ``Table2D.lookup_polished`` (bilinear in the cell, then for λ < 2 a short
polish of F from there; ``interpolation_alone`` reports the bilinear answer without it); in a cell beside a basin
jump, the on-demand solve (``solve_on_demand``, start grid 0.025). Gap = (F* − F(answer)) / F*, F of the
answer with the reference's normalisers and exact peaks (``fast_peaks``). Reported: median and worst over
the interpolated points and over all points, count within 0.5 %, the jump cells hit.

``--build-lambda-points N``: first build the table on N log-spaced λ × η 0.1..0.9 step 0.05 with
``--workers`` processes and time it (not stored unless --table names a new path).

Writes bench/results/table2d.json. Not a test: times depend on the machine and its load (recorded).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))


def _reference(point: tuple[float, float]) -> tuple[float, float, float, float, float]:
    from pickplace_cli.lookup.bspline_optimum import TableSettings, _coarse_for, optimise_lambda

    lam, eta = point
    s = TableSettings(eta=eta)
    r = optimise_lambda(lam, _coarse_for(s), s)
    return r.k1, r.k2, r.F, r.a_min, r.j_min


def main() -> int:
    import numpy as np

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=240)
    ap.add_argument("--seed", type=int, default=20240616)
    ap.add_argument("--table", default=None, help="2-D table CSV (default: the shipped one)")
    ap.add_argument("--build-lambda-points", type=int, default=0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default=str(ROOT / "bench" / "results" / "table2d.json"))
    args = ap.parse_args()

    from pickplace_cli.lookup.bspline_optimum import TableSettings, fast_peaks, solve_on_demand
    from pickplace_cli.lookup.table2d import (
        TableJumpError, eta_grid, format_table_2d, load_table_2d, log_lambda_grid, run_build_2d)

    result: dict = {"cpu_count": os.cpu_count()}
    if args.build_lambda_points:
        lams = log_lambda_grid(0.5, 200.0, args.build_lambda_points)
        etas = eta_grid(0.1, 0.9, 0.05)
        t0 = time.perf_counter()
        tab, _ = run_build_2d(lams, etas, TableSettings(), workers=args.workers)
        build_s = time.perf_counter() - t0
        result["build"] = {"seconds": round(build_s, 2), "workers": args.workers, "rows": len(tab.rows),
                           "lambda_points": len(lams), "eta_points": len(etas)}
        print(f"build: {len(tab.rows)} rows in {build_s:.1f} s on {args.workers} workers", file=sys.stderr)
        if args.table:
            Path(args.table).write_text(format_table_2d(tab, "bench"))
    tab = load_table_2d(args.table)
    result["table"] = tab.source if args.table else "tables/bspline-2d.csv"
    result["grid"] = {"eta": [tab.etas[0], tab.etas[-1], len(tab.etas)], "lambda": [tab.lams[0], tab.lams[-1], len(tab.lams)]}

    rng = np.random.default_rng(args.seed)
    lam_pts = np.exp(rng.uniform(np.log(0.5), np.log(200.0), args.points))
    eta_pts = rng.uniform(0.1, 0.9, args.points)
    points = [(round(float(a), 9), round(float(b), 9)) for a, b in zip(lam_pts, eta_pts)]
    t0 = time.perf_counter()
    if args.workers > 1:
        from concurrent.futures import ProcessPoolExecutor

        with ProcessPoolExecutor(args.workers) as pool:
            refs = list(pool.map(_reference, points, chunksize=8))
    else:
        refs = [_reference(p) for p in points]
    result["reference_seconds"] = round(time.perf_counter() - t0, 2)

    gaps, interp_gaps, jump_pts, worst, over, raw_gaps = [], [], [], None, [], []
    t_lookup = 0.0
    for (lam, eta), (_, _, f_ref, a_min, j_min) in zip(points, refs):
        t1 = time.perf_counter()
        try:
            k1, k2 = tab.lookup(lam, eta)
            how = "interpolated"
            _, a0, j0 = fast_peaks(k1, k2, lam, eta)[0]
            raw_gaps.append((f_ref - (0.5 * a_min / a0 + 0.5 * j_min / j0)) / f_ref)
            k1, k2, polished = tab.lookup_polished(lam, eta)  # what plan uses (polished below λ = 2)
            if polished:
                how = "interpolated and polished"
        except TableJumpError:
            k1, k2, _ = solve_on_demand(lam, eta)
            k1, k2 = tab.best_in_cell(lam, eta, others=[(k1, k2)])  # as plan does in a jump cell
            how = "on demand (jump cell)"
            jump_pts.append([lam, eta])
        t_lookup += time.perf_counter() - t1
        _, a, j = fast_peaks(k1, k2, lam, eta)[0]
        f = 0.5 * a_min / a + 0.5 * j_min / j
        gap = (f_ref - f) / f_ref
        gaps.append(gap)
        if how.startswith("interpolated"):
            interp_gaps.append(gap)
        if gap > 0.005:
            over.append({"gap": gap, "lambda": lam, "eta": eta, "how": how, "k": [k1, k2]})
        if worst is None or gap > worst["gap"]:
            worst = {"gap": gap, "lambda": lam, "eta": eta, "how": how, "k": [k1, k2], "F_ref": f_ref, "F": f}

    def stats(a):
        a = np.asarray(a, float)
        return {"n": int(a.size), "median": float(np.median(a)), "worst": float(a.max()),
                "within_0.5pct": int((a <= 0.005).sum())} if a.size else {"n": 0}

    result.update(points=args.points, seed=args.seed, all=stats(gaps), interpolated=stats(interp_gaps),
                  interpolation_alone=stats(raw_gaps), lookup_seconds=round(t_lookup, 3),
                  jump_cell_points=jump_pts, worst=worst, over_half_percent=over, basin_jumps=[[ax, a, b] for ax, a, b in tab.jumps])
    Path(args.out).write_text(json.dumps(result, indent=1) + "\n")
    print(json.dumps({k: result[k] for k in ("all", "interpolated", "interpolation_alone", "worst")}, indent=1))
    print(f"{len(jump_pts)} points in jump cells; written {args.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
