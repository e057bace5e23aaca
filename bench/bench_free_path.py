"""The free-path minimum time of a move against ``plan --optimize shape --time optimal``.

    python bench/bench_free_path.py                 # Adept cycle, delta-su2018, with and without the capacity (~3 min)
    python bench/bench_free_path.py --n-phase 8     # coarser transcription, quicker

The reference (``tests/reference/free_path.py``): direct transcription with CasADi + IPOPT, the tool path free
(piecewise-constant jerk on 4 × n_phase intervals), the via points of ``--optimize shape`` (lift-off and
set-down straight above the ends at η·h, η ∈ [0.1, 0.9]; the midpoint at or above the clearance h), the rigid
Delta written independently in CasADi symbols, every motor limit (speed, torque, torque rate, round-trip RMS),
the joint range, and optionally the profile's capacity (‖v‖ ≤ [v], ‖a‖ ≤ [a]). It is solved from several
initial shapes (smooth arches of different heights and lift-off ratios, timed over different durations); the
best and the spread of the starts are reported, and the largest utilisation of the best solution on a dense
sampling between the nodes (the limits are imposed at the nodes only: > 1 by a little means the reference is a
slight under-estimate).

pickplace: ``plan --optimize shape --time optimal`` (and with ``--hold-capacity``) on the same move, its ratio
to the reference, and the same with ``--law-evals`` more shapes of the widened family judged by the optimal law
itself (``timing.shape.LAW_POLISH_EVALS``; off in the shipped search: a law solve per shape).
Results go to ``bench/results/free_path.json``.
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

from pickplace_cli import PlanOptions, Task, load_profile, plan  # noqa: E402
from tests.reference import delta_rigid as D  # noqa: E402
from tests.reference import free_path as F  # noqa: E402

P_FROM, P_TO, HEIGHT = [-0.1525, 0.0, -0.8], [0.1525, 0.0, -0.8], 0.025
#: initial shapes: (η of the guess, lift of its apex above the clearance [m], duration of the guess [s])
STARTS = ((0.5, 0.0, 0.15), (0.1, 0.02, 0.12), (0.3, 0.04, 0.10), (0.1, 0.0, 0.20))


def law_seconds(planned) -> float:
    """The time law's own duration [s] (``Duration.t_optimal``): what the optimiser and the shape search reach. The
    plan's duration may be longer by ``written_stretch`` (its 1 kHz samples read as ``check`` reads them:
    ``pickplace_cli/timing/written.py``), a property of the written file, not of the law."""
    d = planned.duration
    return d.t_optimal if d.t_optimal is not None else d.seconds



def reference(prof, capacity: bool, n_phase: int) -> dict:
    lim = F.limits_from_profile(prof, capacity=capacity)
    P = D.params_from_robot(_robot(prof))
    p0, p1 = np.array(P_FROM), np.array(P_TO)
    rows = []
    for eta, lift, tg in STARTS:
        t0 = time.perf_counter()
        r = F.solve_free_path(p0, p1, HEIGHT, lim, P, n_phase=n_phase, t_guess=tg,
                              guess=F._default_guess(p0, p1, max(p0[2], p1[2]) + HEIGHT, eta, lift))
        dt = time.perf_counter() - t0
        rows.append({"start": [eta, lift, tg], "T": r.T, "eta": r.eta, "arch": r.arch, "status": r.status,
                     "dense_utilisation": r.dense_utilisation, "seconds": dt})
        print(f"  start η {eta:.1f} lift {lift * 1e3:4.0f} mm T0 {tg:.2f} s: T {r.T:.5f} s  η {r.eta:.3f}  apex "
              f"{r.arch * 1e3:+.1f} mm over h  {r.status}  dense utilisation {r.dense_utilisation:.4f}  {dt:.0f} s",
              flush=True)
    ok = [r for r in rows if r["status"] == "solved"]
    best = min(ok or rows, key=lambda r: r["T"])
    spread = max(r["T"] for r in ok) / best["T"] - 1 if ok else float("nan")
    return {"best": best, "spread": spread, "starts": rows}


def _robot(prof):
    from pickplace_cli.planner import motion_model_static

    return motion_model_static(prof)[0]


def li_family(prof, capacity: bool) -> dict:
    """The shipped search without the widening (timing.shape.ARCH_RANGE = (0, 0): Li's family only)."""
    from pickplace_cli.timing import shape as S

    old, S.ARCH_RANGE = S.ARCH_RANGE, (0.0, 0.0)
    try:
        got = plan(Task(P_FROM, P_TO, HEIGHT, 0.5), prof, PlanOptions(time="optimal", shape=True, hold_capacity=capacity))
    finally:
        S.ARCH_RANGE = old
    return {"T": law_seconds(got), "T_written": got.duration.seconds, "ok": bool(got.report.ok)}


def shipped(prof, capacity: bool) -> dict:
    task = Task(P_FROM, P_TO, HEIGHT, 0.5)
    times, search = [], []
    for _ in range(3):
        t0 = time.perf_counter()
        got = plan(task, prof, PlanOptions(time="optimal", shape=True, hold_capacity=capacity))
        times.append(time.perf_counter() - t0)
        t0 = time.perf_counter()  # the shape search alone, as plan runs it (the screened search + the law's judgement)
        _search(task, prof, capacity)
        search.append(time.perf_counter() - t0)
    sh = got.parameters["shape"]
    return {"T": law_seconds(got), "T_written": got.duration.seconds,
            "ok": bool(got.report.ok), "median_ms": statistics.median(times) * 1e3,
            "search_median_ms": statistics.median(search) * 1e3,
            "shape": {k: sh.get(k) for k in ("k1", "k2", "eta", "arch", "k3", "k4", "mid")}}


def _search(task, prof, capacity: bool):
    from pickplace_cli.planner import _optimised_shape

    _optimised_shape(task, prof, PlanOptions(time="optimal", shape=True, hold_capacity=capacity))


def polished(prof, capacity: bool, evals: int) -> dict:
    """The shipped search, then ``evals`` shapes judged by the optimal law itself (timing.shape.LAW_POLISH_EVALS)."""
    from pickplace_cli.timing import shape as S

    old, S.LAW_POLISH_EVALS = S.LAW_POLISH_EVALS, evals
    try:
        t0 = time.perf_counter()
        got = plan(Task(P_FROM, P_TO, HEIGHT, 0.5), prof, PlanOptions(time="optimal", shape=True, hold_capacity=capacity))
        dt = time.perf_counter() - t0
    finally:
        S.LAW_POLISH_EVALS = old
    sh = got.parameters["shape"]
    return {"T": law_seconds(got), "T_written": got.duration.seconds, "ok": bool(got.report.ok), "seconds": dt,
            "shape": {k: sh.get(k) for k in ("k1", "k2", "eta", "arch", "k3", "k4", "mid")}}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n-phase", type=int, default=12, help="intervals per phase of the transcription")
    ap.add_argument("--law-evals", type=int, default=60,
                    help="shapes judged by the optimal law after the shipped search (0: skip; slow, ~1 s each)")
    ap.add_argument("-o", "--output", default=str(Path(__file__).parent / "results" / "free_path.json"))
    args = ap.parse_args()
    prof = load_profile("delta-su2018")
    out = {}
    for capacity in (False, True):
        label = "with the capacity" if capacity else "motors alone"
        print(f"Adept cycle, delta-su2018, rigid, {label}: free-path reference (n_phase {args.n_phase})", flush=True)
        ref = reference(prof, capacity, args.n_phase)
        got = shipped(prof, capacity)
        row = {"reference": ref, "shipped": got, "ratio": got["T"] / ref["best"]["T"]}
        print(f"  reference T {ref['best']['T']:.5f} s (spread of the starts {ref['spread'] * 100:.2f} %); "
              f"--optimize shape --time optimal: T {got['T']:.5f} s = {row['ratio']:.4f} × reference, ok {got['ok']}, "
              f"median {got['median_ms']:.0f} ms, of which the shape search {got['search_median_ms']:.0f} ms", flush=True)
        print(f"  shipped shape {got['shape']}", flush=True)
        li = li_family(prof, capacity)
        row["li_family"] = li
        print(f"  Li's family alone: T {li['T']:.5f} s = {li['T'] / ref['best']['T']:.4f} × reference, ok {li['ok']}",
              flush=True)
        if args.law_evals:
            pol = polished(prof, capacity, args.law_evals)
            row["law_polished"] = pol
            print(f"  + {args.law_evals} shapes judged by the optimal law: T {pol['T']:.5f} s = "
                  f"{pol['T'] / ref['best']['T']:.4f} × reference, ok {pol['ok']}, {pol['seconds']:.0f} s; shape "
                  f"{pol['shape']}", flush=True)
        out["capacity" if capacity else "motors"] = row
    Path(args.output).parent.mkdir(parents=True, exist_ok=True)
    Path(args.output).write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
