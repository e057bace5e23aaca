"""The law's solve alone (``optimal_law``: SLSQP on the B-spline law's coefficients, no composition, no exact
check) by coefficient count: its CPU time and its duration estimate against the torque bound and, with
``--reference``, the IPOPT direct transcription (``tests/reference/optimal_ipopt.py``, a C² law with a knot at
every one of its 160 nodes).

    python bench/bench_optimal_solve.py                 # the Adept cycle and 1 random move per shipped profile
    python bench/bench_optimal_solve.py --moves 3 --reference

What it shows: how much of ``--time optimal``'s gap to the reference is the law's class (20 / 40 / 80
coefficients) and what each class costs the solver (one BLAS thread, ``time.process_time``; the machine may be
shared: medians are not taken, one cold solve per row). Results: ``bench/results/optimal_solve.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from pickplace_cli.model.errors import PickplaceError  # noqa: E402
from pickplace_cli.model.task import Task  # noqa: E402
from pickplace_cli.planner import PlanOptions, motion_model, plan  # noqa: E402
from tests.property.test_limit_truth import REGIONS, _profile  # noqa: E402

PROFILES = ("delta-su2018", "delta-4axis", "scara-600", "gantry")
COUNTS = (20, None, 40, 80)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--moves", type=int, default=1, help="random moves per profile")
    ap.add_argument("--seed", type=int, default=500)
    ap.add_argument("--reference", action="store_true", help="also the IPOPT reference (needs casadi; ~40 s a move)")
    ap.add_argument("-o", "--output", default=str(Path(__file__).parent / "results" / "optimal_solve.json"))
    args = ap.parse_args()
    from pickplace_cli.model.threads import single_blas_thread
    from pickplace_cli.timing.bound import torque_bound
    from pickplace_cli.timing.optimal import optimal_law

    work = [("adept", "delta-su2018", Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5))]
    for name in PROFILES:
        (lo, hi), (h0, h1) = REGIONS[name]
        rng = np.random.default_rng(args.seed + PROFILES.index(name))
        got = 0
        while got < args.moves:
            p0, p1 = rng.uniform(lo, hi), rng.uniform(lo, hi)
            if np.linalg.norm(p1[:2] - p0[:2]) >= 0.05:
                work.append((name, name, Task(p0, p1, float(rng.uniform(h0, h1)), 0.5)))
                got += 1
    plan(work[0][2], _profile("delta-su2018"), PlanOptions(time="optimal"))  # imports and caches warm
    rows = []
    for label, name, task in work:
        prof = _profile(name)
        try:
            fit = plan(task, prof, PlanOptions(time="fit"))
        except PickplaceError:
            continue
        model = motion_model(fit.cartesian.path, prof)
        t_fit, dwell = fit.duration.seconds, prof.planning.dwell
        row = {"profile": label, "t_fit": t_fit, "t_bound": torque_bound(model), "solves": {}}
        best = None
        for n in COUNTS:
            c0 = time.process_time()
            law = single_blas_thread(optimal_law)(model, dwell, t_fit, n)
            cpu = time.process_time() - c0
            row["solves"][str(n or "auto")] = {"cpu_ms": cpu * 1e3, "t_estimate": law.t_estimate}
            best = law.law if n == 80 else best
        if args.reference:
            from tests.reference.optimal_ipopt import reference_duration

            row["t_ref"] = reference_duration(model, dwell, t_fit, law=best, scales=(1.0,))
        rows.append(row)
        ref = row.get("t_ref", float("nan"))
        print(f"{label:13s} T_fit {t_fit:.5f}  T_bound {row['t_bound']:.5f}  T_ref {ref:.5f}  " + "  ".join(
            f"{k}: {v['cpu_ms']:6.0f} ms T {v['t_estimate']:.5f} ({(v['t_estimate'] / ref - 1) * 100:+.2f} %)"
            for k, v in row["solves"].items()), flush=True)
    out = {"command": "python bench/bench_optimal_solve.py " + " ".join(sys.argv[1:]), "rows": rows}
    Path(args.output).parent.mkdir(parents=True, exist_ok=True)
    Path(args.output).write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
