"""The closed-form fit (``--time fit``, the motors' part of the default rule) against an independent, slower search.

    python bench/bench_fit_gap.py [--moves 6] [--seed 2026]

For random moves on the Delta (``delta-su2018``) and the SCARA (``scara-600``), every method with a fixed path
(bspline, ph, superposition, lame, piecewise-poly), ``--moves`` moves each:

* ours: :func:`pickplace_cli.timing.fit_duration` (per-sample thresholds in closed form, refined at the parabola
  vertex, confirmed by the exact check);
* the reference: the worst utilisation over every timed limit on the same model, evaluated on the fit grid at each
  trial duration, bracketed and root-found by ``scipy.optimize.brentq`` (:func:`pickplace_cli.timing.screened_root`),
  then raised until the exact check (:func:`pickplace_cli.limits.check.check_limits`) passes.

Reports (T_ours − T_ref)/T_ref: min, median, max over the moves (a negative gap larger than the check's
resolution would mean the closed form misses a crossing; a positive one, that it is conservative) and the time of
each. Writes bench/results/fit_gap.json. Not a test.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time
from pathlib import Path

import numpy as np

RESULTS = Path(__file__).resolve().parent / "results" / "fit_gap.json"
MOVES = {"delta-su2018": ((-0.2, 0.2), (-0.2, 0.2), (-0.95, -0.8)),
         "scara-600": ((0.25, 0.45), (-0.25, 0.25), (-0.18, -0.05))}
METHODS = ("bspline", "ph", "superposition", "lame", "piecewise-poly")


def reference(model, dwell: float) -> float:
    """The bracketing search on the grid's worst utilisation, then nudged up until the exact check passes."""
    from pickplace_cli.limits.check import check_limits
    from pickplace_cli.timing import _worst_utilisation, screened_root

    worst, parts = _worst_utilisation(model, dwell)
    t = screened_root(worst, 0.1) * (1 + 1e-7)
    for _ in range(10):
        bad = [r for r in check_limits(model, t, parts=parts, dwell=dwell).violations if r.kind != "reach"]
        if not bad:
            break
        t *= max(r.utilisation for r in bad) * (1 + 1e-9)
    return t


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--moves", type=int, default=6, help="moves per profile and method")
    ap.add_argument("--seed", type=int, default=2026)
    ap.add_argument("-o", "--output", type=Path, default=RESULTS)
    a = ap.parse_args()

    from pickplace_cli.model.profile import load_profile
    from pickplace_cli.model.task import Task
    from pickplace_cli.paths import plan_path
    from pickplace_cli.planner import motion_model
    from pickplace_cli.timing import fit_duration

    rng = np.random.default_rng(a.seed)
    rows, t_ours, t_ref, skipped = [], [], [], 0
    for name, box in MOVES.items():
        prof = load_profile(name)
        dwell = prof.planning.dwell
        for method in METHODS:
            for _ in range(a.moves):
                p0 = [float(rng.uniform(*r)) for r in box]
                p1 = [float(rng.uniform(*r)) for r in box]
                try:
                    model = motion_model(plan_path(Task(np.array(p0), np.array(p1), 0.025, 0.5), method), prof)
                    s = time.perf_counter()
                    ours, binding = fit_duration(model, dwell)
                    t_ours.append(time.perf_counter() - s)
                    s = time.perf_counter()
                    ref = reference(model, dwell)
                    t_ref.append(time.perf_counter() - s)
                except Exception as exc:  # an unreachable or infeasible random move: counted, not compared
                    skipped += 1
                    print(f"skipped {name} {method} {p0} -> {p1}: {exc}")
                    continue
                rows.append({"profile": name, "method": method, "from": p0, "to": p1, "fit_s": ours, "ref_s": ref,
                             "gap": (ours - ref) / ref, "binding": binding})
    gaps = [r["gap"] for r in rows]
    res = {
        "moves": len(rows), "skipped": skipped, "seed": a.seed, "load_1min": os.getloadavg()[0],
        "gap_min": min(gaps), "gap_median": statistics.median(gaps), "gap_max": max(gaps),
        "worst": max(rows, key=lambda r: abs(r["gap"])),
        "median_ms": {"closed_form": 1e3 * statistics.median(t_ours), "search": 1e3 * statistics.median(t_ref)},
        "rows": rows,
    }
    print(f"{len(rows)} moves ({skipped} skipped): (T_fit - T_ref)/T_ref min {res['gap_min']:.2e}, median "
          f"{res['gap_median']:.2e}, max {res['gap_max']:.2e}; median time {res['median_ms']['closed_form']:.1f} ms "
          f"against {res['median_ms']['search']:.1f} ms for the search")
    a.output.write_text(json.dumps(res, indent=2) + "\n")


if __name__ == "__main__":
    main()
