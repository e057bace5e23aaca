"""``--time optimal`` online: its in-process CPU time against the default plan's, per shipped profile, and its
duration against an independent reference solve (IPOPT on a dense direct transcription,
``tests/reference/optimal_ipopt.py``).

    python bench/bench_optimal_online.py --moves 30            # the users' spec: 30 random moves per profile (over an hour:
                                                               # ~40 s of IPOPT per move on a loaded machine)
    python bench/bench_optimal_online.py --moves 5 --no-shape  # a quicker look

For each profile (delta-su2018, delta-4axis, scara-600, gantry with the drives of
``tests/property/test_limit_truth.py``; the default method, bspline) and for the Adept cycle: the cold
in-process time of ``plan`` with the default duration and with ``time="optimal"`` (each a fresh call on the
same move, one after the other; CPU time by ``time.process_time`` with BLAS held to one thread, and wall time),
``--optimize shape --time optimal`` (unless ``--no-shape``), the law's solve alone (``optimal_law`` on the fit's
motion model, without composing or checking: the part of the time the law's solver owns), the plan's torque
bound T_bound (``timing/bound.py``: TOPP-RA under peak motor torque and speed alone; T_opt/T_bound is the share
of the duration the torque rate, jerk and RMS rows cost), and the reference duration T_ref (IPOPT from the uniform
law and from the plan's own law, the shorter kept). Printed per move:
T_opt/T_ref − 1 (the gap: the plan's exact-checked duration above the reference's point-wise optimum; the
reference holds its limits at 4 points per interval of 160 cosine-spaced intervals and the path's knots only, so it can sit a little
below the true optimum of smooth laws: a small positive gap is its discretisation error, a larger one the
plan's own). Medians per profile and the worst gap. Results go to ``bench/results/optimal_online.json``.
Needs ``casadi`` (the ``bench`` extra).
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
from bench.moves import ADEPT, PROFILES, measured  # noqa: E402
from tests.property.test_limit_truth import _profile  # noqa: E402
from tests.reference.optimal_ipopt import reference_duration  # noqa: E402



def timed(task, prof, options) -> tuple[object, float, float]:
    """(result, CPU s, wall s) of one in-process plan."""
    c0, w0 = time.process_time(), time.perf_counter()
    r = plan(task, prof, options)
    return r, time.process_time() - c0, time.perf_counter() - w0


def one(name: str, prof, task: Task, shape: bool) -> dict | None:
    try:
        default, c_def, w_def = timed(task, prof, PlanOptions())
        opt, c_opt, w_opt = timed(task, prof, PlanOptions(time="optimal"))
    except PickplaceError:
        return None
    row = {"profile": name, "from": task.p_from.tolist(), "to": task.p_to.tolist(), "height": task.height,
           "cpu_default": c_def, "wall_default": w_def, "cpu_optimal": c_opt, "wall_optimal": w_opt,
           "t_optimal": opt.duration.seconds, "law": opt.duration.law, "ok": bool(opt.report.ok)}
    if shape:
        try:
            _, c_sh, w_sh = timed(task, prof, PlanOptions(time="optimal", shape=True))
            row.update(cpu_shape=c_sh, wall_shape=w_sh)
        except PickplaceError:
            pass
    fit = plan(task, prof, PlanOptions(time="fit"))
    model = motion_model(fit.cartesian.path, prof)
    from pickplace_cli.timing.optimal import optimal_law

    c0 = time.process_time()
    solved = optimal_law(model, prof.planning.dwell, fit.duration.seconds)
    row.update(cpu_solve=time.process_time() - c0, t_bound=opt.duration.t_bound or float("nan"))
    law = solved.law if opt.duration.law != "uniform (fallback)" else None
    t_ref = reference_duration(model, prof.planning.dwell, fit.duration.seconds, law=law, scales=(1.0,))
    row.update(t_fit=fit.duration.seconds, t_ref=t_ref, gap=opt.duration.seconds / t_ref - 1.0)
    return row


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--moves", type=int, default=30, help="random moves per profile")
    ap.add_argument("--seed", type=int, default=500)
    ap.add_argument("--no-shape", action="store_true", help="leave out --optimize shape --time optimal")
    ap.add_argument("-o", "--output", default=str(Path(__file__).parent / "results" / "optimal_online.json"))
    args = ap.parse_args()
    from pickplace_cli.model.threads import single_blas_thread

    plan(ADEPT, _profile("delta-su2018"), PlanOptions(time="optimal"))  # imports and caches warm
    rows = []
    measure = single_blas_thread(lambda label, prof, task: one(label, prof, task, not args.no_shape))
    for res in measured(args.seed, args.moves, measure):
        rows.append(res)
        label = res["profile"]
        print(f"{label:13s} default {res['cpu_default'] * 1e3:6.1f} ms  optimal {res['cpu_optimal'] * 1e3:6.1f} ms "
              f"(wall {res['wall_optimal'] * 1e3:6.1f})  shape+optimal {res.get('cpu_shape', float('nan')) * 1e3:6.0f} ms  "
              f"solve {res['cpu_solve'] * 1e3:6.1f} ms  "
              f"T_opt {res['t_optimal']:.5f}  T_bound {res['t_bound']:.5f}  T_ref {res['t_ref']:.5f}  gap {res['gap'] * 100:+.3f} %  ok={res['ok']}",
              flush=True)
    summary: dict = {"command": "python bench/bench_optimal_online.py " + " ".join(sys.argv[1:]), "per_profile": {}}
    for label in ["adept", *PROFILES]:
        rs = [r for r in rows if r["profile"] == label]
        if not rs:
            continue
        med = lambda k: statistics.median(r[k] for r in rs if k in r) * 1e3 if any(k in r for r in rs) else None  # noqa: E731
        s = {"moves": len(rs), "cpu_default_ms": med("cpu_default"), "cpu_optimal_ms": med("cpu_optimal"),
             "cpu_solve_ms": med("cpu_solve"),
             "bound_ratio": statistics.median(r["t_optimal"] / r["t_bound"] for r in rs),
             "wall_optimal_ms": med("wall_optimal"), "cpu_shape_ms": med("cpu_shape"),
             "ratio_to_default": statistics.median(r["cpu_optimal"] / r["cpu_default"] for r in rs),
             "worst_gap": max(r["gap"] for r in rs), "median_gap": statistics.median(r["gap"] for r in rs),
             "min_gap": min(r["gap"] for r in rs), "all_ok": all(r["ok"] for r in rs)}
        summary["per_profile"][label] = s
        print(f"{label:13s} {s['moves']:3d} moves: CPU median default {s['cpu_default_ms']:.1f} ms, optimal "
              f"{s['cpu_optimal_ms']:.1f} ms ({s['ratio_to_default']:.1f} × default; the law's solve alone "
              f"{s['cpu_solve_ms']:.1f} ms; T_opt/T_bound {s['bound_ratio']:.3f}), shape+optimal "
              f"{s['cpu_shape_ms'] or float('nan'):.0f} ms; gap to the reference worst {s['worst_gap'] * 100:+.3f} % "
              f"median {s['median_gap'] * 100:+.3f} % min {s['min_gap'] * 100:+.3f} %; all ok {s['all_ok']}")
    summary["worst_gap"] = max(r["gap"] for r in rows)
    summary["rows"] = rows
    Path(args.output).parent.mkdir(parents=True, exist_ok=True)
    Path(args.output).write_text(json.dumps(summary, indent=1))


if __name__ == "__main__":
    main()
