"""Is ``--time optimal``'s law an optimum? The shipped solve against two independent, slower ones.

    python bench/bench_law_multistart.py              # 4 random moves per method and robot = 60 (~6 min, 2 cores)
    python bench/bench_law_multistart.py --moves 1    # quick look

For each random move (the generator of ``bench/bench_optimal.py``: 3 robots × 5 methods, the gantry with
drives added) and the Adept cycle:
* T_opt — the shipped first law (20 coefficients, two phases from the uniform law; ``--law-coefficients auto``
  refines it when it is far from uniform: bench/bench_optimal.py measures that), fitted by the continuous check;
* T_ms — multi-start: the same law space solved from 4 other starts (uniform × 0.5, × 2, × 4 and a smooth
  random law), the best of them fitted the same way: a T_opt above T_ms is a local optimum;
* T_fine — a finer law space that contains the shipped one (every knot interval halved: 37 coefficients, on a
  321-point grid), solved from the shipped law written in it (the discretisation's share of the gap).
The gap is T_opt / min(T_opt, T_ms, T_fine) − 1 (target ≤ 1 %), reported per reference. Results go to
``bench/results/law_multistart.json``.
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


def fitted(law, prof) -> float:
    """The law's duration fitted by the continuous check on the composed path (inf when it cannot be)."""
    try:
        T, _ = fit_duration(motion_model(law.path, prof), prof.planning.dwell, start=max(law.t_estimate, 1e-3))
    except PickplaceError:
        return float("inf")
    return float(T) if T is not None else float("inf")


def one(prof, method: str, task: Task, rng) -> dict | None:
    try:
        fit = plan(task, prof, PlanOptions(method=method, time="fit"))
    except PickplaceError:
        return None
    if not fit.report.ok:
        return None
    dwell = prof.planning.dwell
    model = motion_model(fit.cartesian.path, prof)
    tf = fit.duration.seconds
    t0 = time.perf_counter()
    shipped = O.optimal_law(model, dwell, tf, coefficients=O.LAW_COEFFICIENTS)  # auto's first law
    T_opt = min(fitted(shipped, prof), tf)  # plan falls back to fit's law
    dt = time.perf_counter() - t0
    n = O.LAW_COEFFICIENTS
    smooth = np.interp(np.linspace(0, 1, n), np.linspace(0, 1, 5), rng.uniform(0.5, 4.0, 5))
    starts = [0.5 * np.ones(n), 2.0 * np.ones(n), 4.0 * np.ones(n), smooth]
    T_ms = min(fitted(O.optimal_law(model, dwell, tf, start=s), prof) for s in starts)
    # the finer law space contains the shipped one (every knot interval halved: 2n − 3 coefficients), and
    # its solve starts from the shipped law written in it, so it can only find a faster law
    n2 = 2 * n - 3
    knots2 = np.concatenate([[0.0] * 3, np.linspace(0.0, 1.0, n2 - 2), [1.0] * 3])
    dense = np.linspace(0.0, 1.0, 2001)
    x2 = np.linalg.lstsq(O._basis(knots2, dense)[0], shipped.law(dense) * tf**2, rcond=None)[0]
    grid0 = O.LAW_GRID
    try:
        O.LAW_GRID = 2 * grid0 - 1
        T_fine = min(fitted(O.optimal_law(model, dwell, tf, coefficients=n2, start=x2), prof), T_opt)
    finally:
        O.LAW_GRID = grid0
    best = min(T_opt, T_ms, T_fine)
    return {"method": method, "from": task.p_from.tolist(), "to": task.p_to.tolist(), "height": task.height,
            "t_fit": tf, "t_optimal": T_opt, "t_multistart": T_ms, "t_fine": T_fine, "gap": T_opt / best - 1.0,
            "gap_multistart": T_opt / min(T_opt, T_ms) - 1.0, "gap_fine": T_opt / min(T_opt, T_fine) - 1.0,
            "law_seconds": dt}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--moves", type=int, default=4, help="random moves per method and robot")
    ap.add_argument("-o", "--output", default=str(Path(__file__).parent / "results" / "law_multistart.json"))
    args = ap.parse_args()
    rows = []
    adept = one(_profile("delta-su2018"), "bspline", Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5),
                np.random.default_rng(0))
    adept["profile"] = "delta-su2018 (Adept)"
    rows.append(adept)
    print(f"Adept: T_opt {adept['t_optimal']:.5f}  multi-start {adept['t_multistart']:.5f}  fine law "
          f"{adept['t_fine']:.5f}  gap {adept['gap'] * 100:+.2f} %", flush=True)
    for name in REGIONS:
        prof = _profile(name)
        (lo, hi), (h0, h1) = REGIONS[name]
        for method in METHODS:
            rng = np.random.default_rng(1000 + len(rows))
            done = tries = 0
            while done < args.moves and tries < 30 * args.moves:
                tries += 1
                p0, p1 = rng.uniform(lo, hi), rng.uniform(lo, hi)
                if np.linalg.norm(p1[:2] - p0[:2]) < 0.05:
                    continue
                res = one(prof, method, Task(p0, p1, float(rng.uniform(h0, h1)), 0.5), rng)
                if res is None:
                    continue
                res["profile"] = name
                done += 1
                rows.append(res)
                print(f"{name:13s} {method:15s} fit {res['t_fit']:.4f} opt {res['t_optimal']:.4f} multi-start "
                      f"{res['t_multistart']:.4f} fine {res['t_fine']:.4f}  gap {res['gap'] * 100:+.2f} % "
                      f"(local {res['gap_multistart'] * 100:+.2f} %, discretisation {res['gap_fine'] * 100:+.2f} %)"
                      f"  law {res['law_seconds'] * 1e3:.0f} ms", flush=True)
    gaps = [r["gap"] for r in rows]
    summary = {"moves": len(rows), "worst_gap": max(gaps), "median_gap": statistics.median(gaps),
               "over_1_percent": sum(g > 0.01 for g in gaps),
               "worst_gap_multistart": max(r["gap_multistart"] for r in rows),
               "worst_gap_fine": max(r["gap_fine"] for r in rows),
               "law_ms_median": statistics.median(r["law_seconds"] for r in rows) * 1e3, "rows": rows}
    print(f"{len(rows)} moves: gap to the best reference worst {summary['worst_gap'] * 100:.2f} %, median "
          f"{summary['median_gap'] * 100:.2f} %, {summary['over_1_percent']} over 1 %; worst against multi-start "
          f"{summary['worst_gap_multistart'] * 100:.2f} %, against the finer law space {summary['worst_gap_fine'] * 100:.2f} %;"
          f" law median {summary['law_ms_median']:.0f} ms")
    Path(args.output).parent.mkdir(parents=True, exist_ok=True)
    Path(args.output).write_text(json.dumps(summary, indent=1))


if __name__ == "__main__":
    main()
