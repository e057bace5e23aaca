"""``plan --optimize shape --time optimal --shape-law-evals N`` on the Adept cycle with time laws of several sizes
(``--law-coefficients``), against the free-path minimum time of ``bench/bench_free_path.py`` (CasADi + IPOPT, the same
limits and via points; read from ``bench/results/free_path.json``), with the motors alone and with the capacity held.

    python bench/bench_shape_law_coefficients.py                      # 60, 90, 120 coefficients, 30 law solves
    python bench/bench_shape_law_coefficients.py --coefficients 120 --evals 60

For each: the law's own duration (``Duration.t_optimal``) and the written one, their ratio to the reference and the
written one's to the 128-interval reference (``bench/results/free_path_convergence.json``: the 48-interval one is
not converged), the plan's verdict and its CPU time (one BLAS thread). Results in ``bench/results/shape_law_coefficients.json``. Not a
test: the CPU times depend on the machine.
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

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pickplace_cli.model.profile import load_profile  # noqa: E402
from pickplace_cli.planner import PlanOptions, plan  # noqa: E402
from bench.moves import ADEPT  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--coefficients", default="60,90,120", help="law coefficients, comma-separated")
    ap.add_argument("--evals", type=int, default=30, help="--shape-law-evals")
    ap.add_argument("-o", "--output", default=str(ROOT / "bench" / "results" / "shape_law_coefficients.json"))
    args = ap.parse_args()
    refs = json.loads((ROOT / "bench" / "results" / "free_path.json").read_text())
    # the 128-interval reference (bench/bench_free_path_convergence.py): the 48-interval one is not converged
    fine = json.loads((ROOT / "bench" / "results" / "free_path_convergence.json").read_text())
    prof = load_profile("delta-su2018")
    rows = []
    for n in (int(c) for c in args.coefficients.split(",")):
        for capacity in (False, True):
            ref = refs["capacity" if capacity else "motors"]["reference"]["best"]["T"]
            ref_fine = fine["capacity" if capacity else "motors"]["rows"][-1]["T"]
            c0 = time.process_time()
            got = plan(ADEPT, prof, PlanOptions(time="optimal", shape=True, hold_capacity=capacity,
                                                shape_law_evals=args.evals, law_coefficients=n))
            d = got.duration
            row = {"coefficients": n, "capacity": capacity, "reference_T": ref, "T": d.t_optimal,
                   "T_written": d.seconds, "ratio": d.t_optimal / ref, "ratio_written": d.seconds / ref,
                   "ok": bool(got.report.ok), "cpu_s": time.process_time() - c0, "reference_fine_T": ref_fine,
                   "ratio_written_fine": d.seconds / ref_fine, "law": d.law}
            rows.append(row)
            print(f"{n:4d} coefficients, {'capacity held' if capacity else 'motors alone '}: T {row['T']:.5f} s = "
                  f"{row['ratio']:.4f} × the free-path minimum (written {row['ratio_written']:.4f} ×; "
                  f"{row['ratio_written_fine']:.4f} × the 128-interval one), ok {row['ok']}, "
                  f"CPU {row['cpu_s']:.1f} s", flush=True)
    Path(args.output).write_text(json.dumps({
        "command": "python bench/bench_shape_law_coefficients.py " + " ".join(sys.argv[1:]),
        "evals": args.evals, "load_average": list(os.getloadavg()), "rows": rows}, indent=1))


if __name__ == "__main__":
    main()
