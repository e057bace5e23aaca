"""How the free-path reference of ``bench/bench_free_path.py`` converges with its transcription's resolution.

    python bench/bench_free_path_convergence.py --n-phase 12,16,24,32

The Adept cycle on delta-su2018 (rigid), with the motors alone and with the capacity held: the free-path minimum
time (CasADi + IPOPT, ``tests/reference/free_path.py``: piecewise-constant jerk on 4 × n_phase intervals, every
limit at the nodes) from the start that converges fastest in ``bench_free_path.py`` (η 0.1, apex 20 mm above the
clearance, 0.12 s), at each ``--n-phase``; and the Richardson extrapolations of the two finest to n_phase → ∞ for a
first- and a second-order error (the transcription converges from above: a finer one lets the path bend more
sharply). Results in ``bench/results/free_path_convergence.json``. Not a test: minutes of CPU.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pickplace_cli.model.profile import load_profile  # noqa: E402
from pickplace_cli.planner import motion_model_static  # noqa: E402
from tests.reference import delta_rigid as D  # noqa: E402
from tests.reference import free_path as F  # noqa: E402

P_FROM, P_TO, HEIGHT = (-0.1525, 0.0, -0.8), (0.1525, 0.0, -0.8), 0.025


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n-phase", default="12,16,24,32", help="intervals per phase, comma-separated")
    ap.add_argument("-o", "--output", default=str(ROOT / "bench" / "results" / "free_path_convergence.json"))
    args = ap.parse_args()
    prof = load_profile("delta-su2018")
    P = D.params_from_robot(motion_model_static(prof)[0])
    p0, p1 = np.array(P_FROM), np.array(P_TO)
    out = {}
    for case, capacity in (("capacity", True), ("motors", False)):
        rows = []
        for n in (int(x) for x in args.n_phase.split(",")):
            t0 = time.process_time()
            r = F.solve_free_path(p0, p1, HEIGHT, F.limits_from_profile(prof, capacity=capacity), P, n_phase=n,
                                  t_guess=0.12, guess=F._default_guess(p0, p1, P_FROM[2] + HEIGHT, 0.1, 0.02))
            rows.append({"n_phase": n, "T": r.T, "status": r.status, "dense_utilisation": r.dense_utilisation,
                         "eta": r.eta, "arch": r.arch, "cpu_s": time.process_time() - t0})
            print(f"{case:8s} n_phase {n:3d}: T {r.T:.6f} s  {r.status}  dense utilisation {r.dense_utilisation:.6f}  "
                  f"apex {r.arch * 1e3:+.1f} mm over h", flush=True)
        (n1, t1), (n2, t2) = [(r["n_phase"], r["T"]) for r in rows[-2:]]
        first = (n2 * t2 - n1 * t1) / (n2 - n1)
        second = (n2**2 * t2 - n1**2 * t1) / (n2**2 - n1**2)
        print(f"{case:8s} n_phase → ∞: {first:.6f} s (first order), {second:.6f} s (second order)", flush=True)
        out[case] = {"rows": rows, "extrapolated_first_order": first, "extrapolated_second_order": second}
    Path(args.output).write_text(json.dumps({"command": "python bench/bench_free_path_convergence.py "
                                             + " ".join(sys.argv[1:]), **out}, indent=1))


if __name__ == "__main__":
    main()
