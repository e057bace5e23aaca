"""``--time optimal``'s smoothing term (``timing/law_sqp.SQP_SMOOTH``) against the IPOPT references of earlier runs:
the law's own duration and the written one (its 1 kHz samples read back as ``check`` reads them, with the tool
columns and with the joint positions alone), per smoothing weight, on the same moves.

    python bench/bench_law_smoothing.py                       # weights 3e-3 (shipped), 3e-4, 0; 40 moves
    python bench/bench_law_smoothing.py --weights 0.003,0 --moves 20 --coefficients 90

The moves are those of ``bench/results/law_solver_500.json`` and ``law_solver_900.json`` that hold an IPOPT reference
(``bench/bench_law_solver.py --reference``), every k-th so that ``--moves`` remain. For each move and weight: the gap
of the law's own duration (``Duration.t_optimal``) and of the written one (``Duration.seconds``, after
``timing/written.py``'s slowing) to the reference, and the plan's CPU time (one BLAS thread). Medians and worsts per
weight; results in ``bench/results/law_smoothing.json``. Not a test: the numbers depend on the references' moves.
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

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pickplace_cli.model.errors import PickplaceError  # noqa: E402
from pickplace_cli.model.task import Task  # noqa: E402
from pickplace_cli.planner import PlanOptions, plan  # noqa: E402
from pickplace_cli.timing import law_sqp  # noqa: E402
from pickplace_cli.timing import optimal as O  # noqa: E402
from tests.property.test_limit_truth import _profile  # noqa: E402

REFERENCES = ("bench/results/law_solver_500.json", "bench/results/law_solver_900.json")
COLUMNS = ("tool", "positions")


def moves(n: int) -> list[dict]:
    rows = [r for f in REFERENCES for r in json.loads((ROOT / f).read_text())["moves"] if "t_ref" in r]
    return rows[:: max(1, len(rows) // n)][:n]


def one(row: dict, weight: float) -> dict:
    prof = _profile("delta-su2018" if row["profile"] == "adept" else row["profile"])
    task = Task(row["from"], row["to"], row["height"], 0.5)
    law_sqp.SQP_SMOOTH = weight
    out = {}
    for columns in COLUMNS:
        c0 = time.process_time()
        try:
            pl = plan(task, prof, PlanOptions(time="optimal", read_written=columns))
        except PickplaceError as exc:
            out[columns] = {"error": str(exc)}
            continue
        d = pl.duration
        out[columns] = {"law_gap": (d.t_optimal or d.seconds) / row["t_ref"] - 1.0,
                        "written_gap": d.seconds / row["t_ref"] - 1.0, "stretch": d.written_stretch,
                        "cpu_s": time.process_time() - c0, "ok": bool(pl.report.ok)}
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--weights", default="0.003,0.0003,0", help="smoothing weights, comma-separated")
    ap.add_argument("--moves", type=int, default=40)
    ap.add_argument("--coefficients", type=int, default=None, help="the SQP law's coefficients (default: shipped)")
    ap.add_argument("-o", "--output", default=str(ROOT / "bench" / "results" / "law_smoothing.json"))
    args = ap.parse_args()
    if args.coefficients is not None:
        O.LAW_SQP_COEFFICIENTS = args.coefficients
    weights = [float(w) for w in args.weights.split(",")]
    results = []
    for row in moves(args.moves):
        res = {"profile": row["profile"], "from": row["from"], "to": row["to"], "height": row["height"],
               "t_ref": row["t_ref"], "by_weight": {str(w): one(row, w) for w in weights}}
        results.append(res)
        print(row["profile"], "  ".join(
            f"{w:g}/{c}: law {v[c]['law_gap'] * 100:+.3f} % written {v[c]['written_gap'] * 100:+.3f} %"
            for w, v in zip(weights, res["by_weight"].values()) for c in COLUMNS if "law_gap" in v[c]), flush=True)
    summary = {}
    for w in weights:
        for c in COLUMNS:
            v = [r["by_weight"][str(w)][c] for r in results if "law_gap" in r["by_weight"][str(w)][c]]
            summary[f"{w:g} {c}"] = {
                "moves": len(v), "law_gap_median": statistics.median(x["law_gap"] for x in v),
                "law_gap_worst": max(x["law_gap"] for x in v),
                "written_gap_median": statistics.median(x["written_gap"] for x in v),
                "written_gap_worst": max(x["written_gap"] for x in v),
                "stretch_worst": max(x["stretch"] for x in v),
                "cpu_ms_median": 1e3 * statistics.median(x["cpu_s"] for x in v),
                "all_ok": all(x["ok"] for x in v)}
    for k, s in summary.items():
        print(f"{k:16s} law {s['law_gap_median'] * 100:+.3f} % median, {s['law_gap_worst'] * 100:+.3f} % worst | "
              f"written {s['written_gap_median'] * 100:+.3f} % / {s['written_gap_worst'] * 100:+.3f} % | "
              f"stretch ≤ {s['stretch_worst']:.4f} | {s['cpu_ms_median']:.0f} ms | all ok {s['all_ok']}")
    Path(args.output).write_text(json.dumps({
        "command": "python bench/bench_law_smoothing.py " + " ".join(sys.argv[1:]),
        "load_average": list(os.getloadavg()), "summary": summary, "moves": results}, indent=1))


if __name__ == "__main__":
    main()
