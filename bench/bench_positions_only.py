"""What ``check`` makes of ``plan --time optimal``'s own files, as written (joints and the tool's motion) and as
joint positions alone (another tool's file: the motion reconstructed from the positions), on random moves of the
SCARA and the gantry with drives (``tests/property/test_limit_truth.py``'s profiles and regions), the ``bspline`` and
``ph`` methods, at 1 and 5 kHz.

    python bench/bench_positions_only.py [--moves 5] [--seed 77]

Prints every file ``check`` refuses (the quantity and how far above its limit it reads) and the counts. A refusal
errs on the safe side (``plan`` wrote the law within its limits, the exact check of its continuous motion agrees);
the manual's ``check`` page states this limit. Not a test.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402

from pickplace_cli.model.errors import PickplaceError  # noqa: E402
from pickplace_cli.model.task import Task  # noqa: E402
from pickplace_cli.pipelines.check import check_file  # noqa: E402
from pickplace_cli.planner import PlanOptions, plan  # noqa: E402
from tests.property.test_limit_truth import REGIONS, _profile  # noqa: E402
from tests.property.test_plan_check_agreement import _text  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--moves", type=int, default=5, help="random moves per profile")
    ap.add_argument("--seed", type=int, default=77)
    args = ap.parse_args()
    tmp = Path(tempfile.mkdtemp())
    counts = {"full": [0, 0], "positions only": [0, 0]}
    for name in ("gantry", "scara-600"):
        prof = _profile(name)
        (lo, hi), (h0, h1) = REGIONS[name]
        rng = np.random.default_rng(args.seed)
        done = 0
        while done < args.moves:
            a, b = rng.uniform(lo, hi), rng.uniform(lo, hi)
            if np.linalg.norm(b[:2] - a[:2]) < 0.05:
                continue
            for method in ("bspline", "ph"):
                for rate in (1000.0, 5000.0):
                    try:
                        pl = plan(Task(a, b, float(rng.uniform(h0, h1)), 0.5), prof,
                                  PlanOptions(method=method, time="optimal", rate=rate))
                    except PickplaceError:
                        continue
                    if not pl.report.ok:
                        continue
                    for kind in counts:
                        f = tmp / "t.csv"
                        f.write_text(_text(pl, positions_only=kind == "positions only"))
                        rep = check_file(str(f), prof, hold_capacity=False)[0].report
                        counts[kind][0] += 1
                        if not rep.ok:
                            counts[kind][1] += 1
                            worst = max(rep.violations, key=lambda r: r.utilisation)
                            print(f"refused: {name} {method} {rate:.0f} Hz {kind}, T {pl.duration.seconds:.4f} s: "
                                  f"{worst.joint} {worst.quantity} read at {worst.utilisation * 100:.2f} % of its "
                                  f"limit", flush=True)
            done += 1
    for kind, (n, bad) in counts.items():
        print(f"{kind}: {bad} of {n} files refused")


if __name__ == "__main__":
    main()
