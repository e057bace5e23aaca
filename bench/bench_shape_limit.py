"""What the B-spline family lacks against the free-path minimum time, on the Adept cycle (delta-su2018, rigid).

    python bench/bench_shape_limit.py                  # both cases, 40 law solves each (~5 min on a busy machine)
    python bench/bench_shape_limit.py --evals 20 --case capacity

For the motors alone and with the Cartesian capacity held (``--hold-capacity``), in one run:

* the free-path reference T_ref: read from ``bench/results/free_path.json`` (written by ``bench/bench_free_path.py``,
  CasADi + IPOPT, ~3 min per case; ``--reference`` recomputes it here);
* ``--optimize shape --time optimal`` with Li's family only (``timing.shape.ARCH_RANGE = (0, 0)``) and with the
  shipped widened family (arch, k3, k4, mid), their ratio to T_ref and CPU time (``time.process_time``, one BLAS
  thread);
* ``--shape-law-evals`` ``--evals`` (the shipped law-judged search: COBYQA from the screened shape);
* Nelder-Mead with the optimal law's duration as the objective (``--evals`` law solves) from the shipped
  shape, over the seven-parameter family and over nine parameters (plus ``eta_down`` and ``mid_x``, the via
  points' placement): whether those degrees of freedom close the gap.

``--others``: on another Delta move and a SCARA move (no free-path reference there: the reference models the
Delta only, at these ends not computed), ``--optimize shape --time optimal`` with and without ``--shape-law-evals``
(``--evals``) and the ratio between them. Results go to ``bench/results/shape_limit.json``. Timings on 2 shared cores: CPU seconds are the steadier figure.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
from scipy.optimize import minimize

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from pickplace_cli import PlanOptions, Task, load_profile, plan  # noqa: E402
from pickplace_cli.model.threads import single_blas_thread  # noqa: E402

P_FROM, P_TO, HEIGHT = [-0.1525, 0.0, -0.8], [0.1525, 0.0, -0.8], 0.025
K, ETA, ARCH, MID, PLACE_E, PLACE_X = (0.01, 0.99), (0.1, 0.9), (0.0, 3.0), (0.35, 0.65), (0.1, 0.9), (0.3, 0.7)


def law_seconds(planned) -> float:
    """The time law's own duration [s] (``Duration.t_optimal``): what the optimiser and the shape search reach. The
    plan's duration may be longer by ``written_stretch`` (its 1 kHz samples read as ``check`` reads them:
    ``pickplace_cli/timing/written.py``), a property of the written file, not of the law."""
    d = planned.duration
    return d.t_optimal if d.t_optimal is not None else d.seconds



def shape_optimal(prof, capacity: bool, li_only: bool) -> dict:
    from pickplace_cli.timing import shape as S

    old = S.ARCH_RANGE
    if li_only:
        S.ARCH_RANGE = (0.0, 0.0)
    try:
        c0, w0 = time.process_time(), time.perf_counter()
        got = plan(Task(P_FROM, P_TO, HEIGHT, 0.5), prof, PlanOptions(time="optimal", shape=True, hold_capacity=capacity))
        cpu, wall = time.process_time() - c0, time.perf_counter() - w0
    finally:
        S.ARCH_RANGE = old
    sh = got.parameters["shape"]
    return {"T": law_seconds(got), "T_written": got.duration.seconds,
            "ok": bool(got.report.ok), "cpu_s": cpu, "wall_s": wall,
            "shape": {k: sh.get(k) for k in ("k1", "k2", "eta", "arch", "k3", "k4", "mid")}}


def law_polish(prof, capacity: bool, start: dict, evals: int, placement: bool) -> dict:
    """Nelder-Mead on the optimal law's duration from ``start`` over (k1, k2, η, arch/h, k3, k4, mid[, eta_down,
    mid_x]); a plan whose check fails counts as 1 s."""
    def law_t(x):
        k1, k2, eta, arch, k3, k4, mid = x[:7]
        p = {"k1": k1, "k2": k2, "arch": max(arch, 0.0) * HEIGHT, "k3": k3, "k4": k4, "mid": mid}
        if placement:
            p.update(eta_down=x[7], mid_x=x[8])
        try:
            got = plan(Task(P_FROM, P_TO, HEIGHT, eta), prof,
                       PlanOptions(time="optimal", hold_capacity=capacity, method_params=p))
            return law_seconds(got) if got.report.ok else 1.0
        except Exception:  # noqa: BLE001 - a shape the robot cannot follow
            return 1.0

    s = start
    x0 = [s["k1"], s["k2"], s["eta"], (s["arch"] or 0.0) / HEIGHT, s["k3"] or s["k1"], s["k4"] or s["k2"],
          s["mid"] or 0.5] + ([s["eta"], 0.5] if placement else [])
    bounds = [K, K, ETA, ARCH, K, K, MID] + ([PLACE_E, PLACE_X] if placement else [])
    lo, hi = np.array([b[0] for b in bounds]), np.array([b[1] for b in bounds])
    steps = np.array([0.03, 0.03, 0.03, 0.3, 0.03, 0.03, 0.02] + ([0.05, 0.05] if placement else []))
    x0 = np.array(x0)
    simplex = np.array([x0] + [np.clip(x0 + np.eye(len(x0))[i] * steps[i], lo, hi) for i in range(len(x0))])
    c0 = time.process_time()
    res = minimize(lambda x: law_t(np.clip(x, lo, hi)), x0, method="Nelder-Mead", bounds=bounds,
                   options={"maxfev": evals, "initial_simplex": simplex})
    x = np.clip(res.x, lo, hi)
    names = ["k1", "k2", "eta", "arch_over_h", "k3", "k4", "mid"] + (["eta_down", "mid_x"] if placement else [])
    return {"T": float(res.fun), "evals": int(res.nfev), "cpu_s": time.process_time() - c0,
            "x": dict(zip(names, (float(v) for v in x)))}


@single_blas_thread
def run_case(prof, capacity: bool, evals: int, ref_T: float) -> dict:
    label = "with the capacity" if capacity else "motors alone"
    print(f"Adept cycle, delta-su2018, {label}: free-path reference T {ref_T:.5f} s", flush=True)
    row = {"reference_T": ref_T}
    for name, li in (("li_family", True), ("widened", False)):
        r = shape_optimal(prof, capacity, li)
        row[name] = r
        print(f"  --optimize shape --time optimal, {name}: T {r['T']:.5f} s = {r['T'] / ref_T:.4f} × ref, ok {r['ok']}, "
              f"CPU {r['cpu_s']:.2f} s (wall {r['wall_s']:.2f} s)", flush=True)
    if evals:
        c0 = time.process_time()
        got = plan(Task(P_FROM, P_TO, HEIGHT, 0.5), prof,
                   PlanOptions(time="optimal", shape=True, hold_capacity=capacity, shape_law_evals=evals))
        row["shipped_law_evals"] = r = {"T": law_seconds(got), "T_written": got.duration.seconds,
                                        "ok": bool(got.report.ok), "evals": evals,
                                        "cpu_s": time.process_time() - c0}
        print(f"  --shape-law-evals {evals} (shipped: COBYQA from the screened shape): T {r['T']:.5f} s = "
              f"{r['T'] / ref_T:.4f} × ref, ok {r['ok']}, CPU {r['cpu_s']:.1f} s", flush=True)
        for name, placement in (("law_7", False), ("law_9_placement", True)):
            r = law_polish(prof, capacity, row["widened"]["shape"], evals, placement)
            row[name] = r
            print(f"  + {r['evals']} law solves over {'9 (with eta_down, mid_x)' if placement else '7'} parameters: "
                  f"T {r['T']:.5f} s = {r['T'] / ref_T:.4f} × ref, CPU {r['cpu_s']:.0f} s; "
                  f"{ {k: round(v, 4) for k, v in r['x'].items()} }", flush=True)
    return row


OTHERS = (("delta-su2018", Task([-0.1, 0.05, -0.85], [0.12, -0.03, -0.78], 0.04, 0.3)),
          ("scara-600", Task([0.3, -0.2, -0.12], [0.5, 0.2, -0.12], 0.03, 0.5)))


@single_blas_thread
def others(evals: int) -> list[dict]:
    from tests.property.test_limit_truth import _profile

    rows = []
    for name, task in OTHERS:
        prof = _profile(name)
        row = {"profile": name}
        for key, n in (("screened", 0), ("law_judged", evals)):
            c0 = time.process_time()
            got = plan(task, prof, PlanOptions(time="optimal", shape=True, shape_law_evals=n))
            row[key] = {"T": law_seconds(got), "T_written": got.duration.seconds,
                        "ok": bool(got.report.ok), "cpu_s": time.process_time() - c0}
        row["ratio"] = row["law_judged"]["T"] / row["screened"]["T"]
        print(f"{name} {task.p_from.tolist()} -> {task.p_to.tolist()}: shape + optimal T {row['screened']['T']:.5f} s "
              f"(CPU {row['screened']['cpu_s']:.1f} s), with --shape-law-evals {evals} T {row['law_judged']['T']:.5f} s "
              f"= {row['ratio']:.4f} × (CPU {row['law_judged']['cpu_s']:.1f} s), ok {row['law_judged']['ok']}",
              flush=True)
        rows.append(row)
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--evals", type=int, default=40, help="law solves per Nelder-Mead run (0: skip)")
    ap.add_argument("--case", choices=("motors", "capacity", "both"), default="both")
    ap.add_argument("--reference", action="store_true", help="recompute the free-path reference (CasADi, ~3 min each)")
    ap.add_argument("--others", action="store_true", help="only the other moves (Delta, SCARA)")
    ap.add_argument("-o", "--output", default=str(Path(__file__).parent / "results" / "shape_limit.json"))
    args = ap.parse_args()
    prof = load_profile("delta-su2018")
    if args.others:
        out_o = {"others": others(args.evals)}
        Path(args.output).parent.mkdir(parents=True, exist_ok=True)
        Path(args.output).write_text(json.dumps(out_o, indent=1))
        return
    cached = json.loads((Path(__file__).parent / "results" / "free_path.json").read_text())
    out = {}
    for capacity in (False, True):
        key = "capacity" if capacity else "motors"
        if args.case not in (key, "both"):
            continue
        if args.reference:
            from bench_free_path import reference  # noqa: PLC0415 - casadi only when asked

            ref_T = reference(prof, capacity, 12)["best"]["T"]
        else:
            ref_T = cached[key]["reference"]["best"]["T"]
        out[key] = run_case(prof, capacity, args.evals, ref_T)
    Path(args.output).parent.mkdir(parents=True, exist_ok=True)
    Path(args.output).write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
