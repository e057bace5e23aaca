"""Does ``check`` accept every file ``plan`` writes as within its limits, at low rates and as joint positions alone?

    python bench/bench_written_sparse.py --seed 13 --moves 3 --rates 50,100,160,200,1000

Random moves (``--moves`` per shipped profile, seeded) with five methods under the default rule (``limits``), each
sampled at every ``--rates`` [Hz], written as ``plan`` writes its CSV (the tool's columns beside the joints) and as
the joint positions alone (planned with ``PlanOptions.read_written = "positions"``, as ``plan --columns t,q1,…``
does). Every file ``plan`` calls within its limits is checked as ``check`` reads it; a line per file (profile, method,
rate, positions alone, samples, duration [s], check's verdict, the worst row's reading less its accuracy counted up
to 1 % of the limit, over the allowed value) and the count refused per rate. Not a test: minutes of CPU.
"""

from __future__ import annotations

import argparse
import io
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from pickplace_cli.export.csv import write_csv  # noqa: E402
from pickplace_cli.model.errors import PickplaceError  # noqa: E402
from pickplace_cli.model.profile import load_profile  # noqa: E402
from pickplace_cli.model.task import Task  # noqa: E402
from pickplace_cli.pipelines.check import check_file  # noqa: E402
from pickplace_cli.planner import PlanOptions, plan  # noqa: E402

MOVES = {
    "delta-su2018": ((-0.2, 0.2), (-0.2, 0.2), (-0.95, -0.8)),
    "delta-4axis": ((-0.2, 0.2), (-0.2, 0.2), (-0.95, -0.8)),
    "scara-600": ((0.25, 0.45), (-0.25, 0.25), (-0.18, -0.05)),
    "gantry": ((-0.5, 0.5), (-0.5, 0.5), (-0.6, -0.3)),
}
METHODS = ("bspline", "ph", "superposition", "lame", "piecewise-poly")


def positions_only(text: str) -> str:
    lines = text.splitlines()
    head = lines[0].split(",")
    keep = [i for i, h in enumerate(head) if h.split("[")[0] == "t" or (h[0] == "q" and h.split("[")[0][1:].isdigit())]
    return "\n".join(",".join(ln.split(",")[i] for i in keep) for ln in lines) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seed", type=int, default=13)
    ap.add_argument("--moves", type=int, default=3)
    ap.add_argument("--rates", default="50,100,160,200,1000")
    args = ap.parse_args()
    rates = [float(r) for r in args.rates.split(",")]
    rng = np.random.default_rng(args.seed)
    counts: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "move.csv"
        for prof_name, box in MOVES.items():
            prof = load_profile(prof_name)
            for _ in range(args.moves):
                a, b = [rng.uniform(*r) for r in box], [rng.uniform(*r) for r in box]
                for method in METHODS:
                    for rate in rates:
                        for alone in (False, True):
                            opts = PlanOptions(method=method, rate=rate, read_written="positions" if alone else "tool")
                            try:
                                pl = plan(Task(a, b, 0.025, 0.5), prof, opts)
                            except PickplaceError:
                                continue
                            if not pl.report.ok:
                                continue
                            buf = io.StringIO()
                            write_csv(pl, buf)
                            text = positions_only(buf.getvalue()) if alone else buf.getvalue()
                            path.write_text(text)
                            rep = check_file(path, prof)[0].report
                            worst = max(((r.peak - min(r.accuracy or 0.0, 0.01 * r.allowed)) / r.allowed
                                         for r in rep.rows if r.kind == "limit" and r.bound == "upper"
                                         and not r.not_held and r.allowed > 0), default=0.0)
                            n = text.count("\n") - 1
                            key = (rate, alone)
                            seen, refused = counts.get(key, (0, 0))
                            counts[key] = (seen + 1, refused + (not rep.ok))
                            print(f"{prof_name:13s} {method:15s} {rate:7.0f} Hz {'positions' if alone else 'tool     '} "
                                  f"{n:5d} samples T {pl.duration.seconds:.4f} s  {'ok' if rep.ok else 'REFUSED'}  "
                                  f"worst {worst:.4f}", flush=True)
    for (rate, alone), (seen, refused) in sorted(counts.items()):
        print(f"{rate:7.0f} Hz {'positions alone' if alone else 'tool columns   '}: {refused} of {seen} refused")


if __name__ == "__main__":
    main()
