"""``--time optimal``'s two solvers of the time law, same moves, same run: the structured SQP (the default,
``timing/law_sqp.py``, a quintic law of 60 coefficients) against scipy's SLSQP (the solver before it: 20 coefficients refined to 40
when the law is more than 10 % faster than uniform).

    python bench/bench_law_solver.py --moves 5                 # Adept cycle + 5 random moves per shipped profile
    python bench/bench_law_solver.py --moves 3 --reference     # also the gap to the IPOPT transcription (slow)
    python bench/bench_law_solver.py --moves 3 --smooth 0 -o /tmp/s0.json \
        --reference-from bench/results/law_solver.json          # a variant of the SQP against the same references

For each move (the Adept cycle on delta-su2018, and random moves of delta-su2018, delta-4axis, scara-600 and the
gantry with drives, as ``bench/bench_optimal_online.py`` makes them): the cold in-process CPU time (one BLAS thread,
``time.process_time``) of the default ``plan``, of ``plan(time="optimal")`` with each solver, and of the law's solve
alone (``optimal_law``), and each plan's exact-checked duration. With ``--reference``, the gap of each to the IPOPT
direct transcription (``tests/reference/optimal_ipopt.py``: 160 cosine-spaced intervals, every limit at 4 points per
interval; started from the uniform law and from both solvers' laws, the shortest kept). Medians per profile, the
worst gap and the worst SQP/SLSQP duration ratio; results in ``bench/results/law_solver.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")


sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from pickplace_cli.model.errors import PickplaceError  # noqa: E402
from pickplace_cli.model.task import Task  # noqa: E402
from pickplace_cli.planner import PlanOptions, motion_model, plan  # noqa: E402
from pickplace_cli.timing import optimal as O  # noqa: E402
from bench.moves import ADEPT, PROFILES, measured  # noqa: E402
from tests.property.test_limit_truth import _profile  # noqa: E402

SOLVERS = ("sqp", "slsqp")


def law_seconds(planned) -> float:
    """The time law's own duration [s] (``Duration.t_optimal``): what the optimiser and the shape search reach. The
    plan's duration may be longer by ``written_stretch`` (its 1 kHz samples read as ``check`` reads them:
    ``pickplace_cli/timing/written.py``), a property of the written file, not of the law."""
    d = planned.duration
    return d.t_optimal if d.t_optimal is not None else d.seconds



def cpu(fn):
    c0 = time.process_time()
    out = fn()
    return out, time.process_time() - c0


#: reference durations [s] read from an earlier run (``--reference-from``), by move
KNOWN: dict = {}


def _key(row: dict) -> tuple:
    return row["profile"], tuple(round(v, 9) for v in row["from"]), tuple(round(v, 9) for v in row["to"]), \
        round(row["height"], 9)


def one(label: str, prof, task: Task, reference: bool) -> dict | None:
    row: dict = {"profile": label, "from": task.p_from.tolist(), "to": task.p_to.tolist(), "height": task.height}
    try:
        _, row["cpu_default"] = cpu(lambda: plan(task, prof, PlanOptions()))
        fit = plan(task, prof, PlanOptions(time="fit"))
    except PickplaceError:
        return None
    model = motion_model(fit.cartesian.path, prof)
    laws = {}
    for solver in SOLVERS:
        O.LAW_SOLVER = solver
        try:
            opt, row[f"cpu_{solver}"] = cpu(lambda: plan(task, prof, PlanOptions(time="optimal")))
        finally:
            O.LAW_SOLVER = "sqp"
        law, row[f"solve_{solver}"] = cpu(lambda: O.optimal_law(model, prof.planning.dwell, fit.duration.seconds,
                                                                 solver=solver))
        laws[solver] = law.law
        row[f"t_{solver}"] = law_seconds(opt)  # the law's own; written: opt.duration.seconds
        row[f"ok_{solver}"] = bool(opt.report.ok)
        row[f"law_{solver}"] = opt.duration.law
    row["t_fit"] = fit.duration.seconds
    row["ratio"] = row["t_sqp"] / row["t_slsqp"]
    t_ref = KNOWN.get(_key(row))
    if reference and t_ref is None:
        from tests.reference.optimal_ipopt import reference_duration

        t_ref = min(reference_duration(model, prof.planning.dwell, fit.duration.seconds, law=laws[s], scales=(1.0,))
                    for s in SOLVERS)
    if t_ref is not None:
        row["t_ref"] = t_ref
        for solver in SOLVERS:
            row[f"gap_{solver}"] = row[f"t_{solver}"] / t_ref - 1.0
    return row


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--moves", type=int, default=5, help="random moves per profile")
    ap.add_argument("--seed", type=int, default=500)
    ap.add_argument("--reference", action="store_true", help="also the IPOPT reference's gap (~10-40 s per move)")
    ap.add_argument("-o", "--output", default=str(Path(__file__).parent / "results" / "law_solver.json"))
    ap.add_argument("--smooth", type=float, default=None,
                    help="the SQP's smoothing weight (law_sqp.SQP_SMOOTH; 0: none) instead of the shipped one")
    ap.add_argument("--coefficients", type=int, default=None,
                    help="the SQP law's coefficients (optimal.LAW_SQP_COEFFICIENTS) instead of the shipped 60")
    ap.add_argument("--reference-from", metavar="JSON", default=None,
                    help="the IPOPT references of an earlier run's results file, for the moves it holds (a variant's "
                         "gaps without solving them again)")
    args = ap.parse_args()
    from pickplace_cli.model.threads import single_blas_thread

    if args.reference_from:
        KNOWN.update({_key(r): r["t_ref"] for r in json.loads(Path(args.reference_from).read_text())["moves"]
                      if "t_ref" in r})
    from pickplace_cli.timing import law_sqp

    if args.smooth is not None:
        law_sqp.SQP_SMOOTH = args.smooth
    if args.coefficients is not None:
        O.LAW_SQP_COEFFICIENTS = args.coefficients

    for solver in SOLVERS:  # imports and caches warm for both
        O.LAW_SOLVER = solver
        plan(ADEPT, _profile("delta-su2018"), PlanOptions(time="optimal"))
    O.LAW_SOLVER = "sqp"
    rows = []
    measure = single_blas_thread(lambda label, prof, task: one(label, prof, task, args.reference))
    for res in measured(args.seed, args.moves, measure):
        rows.append(res)
        Path(args.output).write_text(json.dumps({"partial": True, "moves": rows}, indent=1))  # a run cut short keeps these
        label = res["profile"]
        gaps = (f"  gap sqp {res['gap_sqp'] * 100:+.3f} %  slsqp {res['gap_slsqp'] * 100:+.3f} %"
                if "t_ref" in res else "")
        print(f"{label:13s} default {res['cpu_default'] * 1e3:5.1f} ms  optimal: sqp {res['cpu_sqp'] * 1e3:6.1f} ms "
              f"(solve {res['solve_sqp'] * 1e3:5.1f})  slsqp {res['cpu_slsqp'] * 1e3:6.1f} ms (solve "
              f"{res['solve_slsqp'] * 1e3:6.1f})  T sqp {res['t_sqp']:.5f}  slsqp {res['t_slsqp']:.5f}  "
              f"ratio {res['ratio']:.5f}{gaps}  ok={res['ok_sqp']}/{res['ok_slsqp']}", flush=True)
    summary: dict = {"command": "python bench/bench_law_solver.py " + " ".join(sys.argv[1:]),
                     "sqp_smooth": law_sqp.SQP_SMOOTH, "sqp_coefficients": O.LAW_SQP_COEFFICIENTS,
                     "load_average": list(os.getloadavg()), "per_profile": {}}
    for label in ["adept", *PROFILES]:
        rs = [r for r in rows if r["profile"] == label]
        if not rs:
            continue
        med = lambda k: statistics.median(r[k] for r in rs) * 1e3  # noqa: E731
        entry = {"moves": len(rs), "cpu_default_ms": med("cpu_default"), "cpu_sqp_ms": med("cpu_sqp"),
                 "cpu_slsqp_ms": med("cpu_slsqp"), "solve_sqp_ms": med("solve_sqp"), "solve_slsqp_ms": med("solve_slsqp"),
                 "sqp_over_default": med("cpu_sqp") / med("cpu_default"),
                 "ratio_median": statistics.median(r["ratio"] for r in rs),
                 "ratio_worst": max(r["ratio"] for r in rs), "ratio_best": min(r["ratio"] for r in rs),
                 "all_ok": all(r["ok_sqp"] and r["ok_slsqp"] for r in rs)}
        if all("t_ref" in r for r in rs):
            for s in SOLVERS:
                entry[f"gap_{s}_worst"] = max(r[f"gap_{s}"] for r in rs)
                entry[f"gap_{s}_median"] = statistics.median(r[f"gap_{s}"] for r in rs)
        summary["per_profile"][label] = entry
    summary["ratio_worst"] = max(r["ratio"] for r in rows)
    if all("t_ref" in r for r in rows):
        summary["gap_sqp_worst"] = max(r["gap_sqp"] for r in rows)
        summary["gap_slsqp_worst"] = max(r["gap_slsqp"] for r in rows)
    summary["moves"] = rows
    Path(args.output).write_text(json.dumps(summary, indent=1))
    print(json.dumps({k: v for k, v in summary.items() if k != "moves"}, indent=1))


if __name__ == "__main__":
    main()
