"""``check``'s CPU time on one file as ``plan`` writes it: the Adept cycle on the default Delta, ``--time optimal
--hold-capacity`` at 1 kHz (149 rows with the tool columns, read through the septic Hermite), medians of ``--repeat``
reads in one process after a warm one; with ``--base REV`` the same file read by another revision's ``pickplace_cli``
too, alternating processes (``git archive`` into a temporary folder).

    python bench/bench_check_read.py [--repeat 15] [--base REV] [--rounds 3]

Not a test: timings depend on the machine and on what else runs on it.
"""

from __future__ import annotations

import argparse
import io
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
ROOT = Path(__file__).resolve().parents[1]


def write_file(path: str) -> None:
    """The Adept cycle's optimal plan (capacity held) as plan writes it, to ``path``."""
    sys.path.insert(0, str(ROOT))
    from pickplace_cli.export.csv import write_csv
    from pickplace_cli.model.profile import load_profile
    from pickplace_cli.model.task import Task
    from pickplace_cli.planner import PlanOptions, plan

    prof = load_profile("delta-su2018")
    pl = plan(Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5), prof,
              PlanOptions(time="optimal", hold_capacity=True))
    buf = io.StringIO()
    write_csv(pl, buf)
    Path(path).write_text(buf.getvalue())


def read_times(path: str, repeat: int) -> float:
    """Median CPU seconds of ``check_file`` on ``path`` (the ``pickplace_cli`` first on sys.path)."""
    from pickplace_cli.model.profile import load_profile
    from pickplace_cli.pipelines.check import check_file

    prof = load_profile("delta-su2018")
    check_file(path, prof)
    times = []
    for _ in range(repeat):
        c0 = time.process_time()
        check_file(path, prof)
        times.append(time.process_time() - c0)
    return statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeat", type=int, default=15)
    ap.add_argument("--base", help="another revision to read the same file with")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--worker", nargs=2, metavar=("FILE", "REPEAT"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        print(read_times(args.worker[0], int(args.worker[1])))
        return
    with tempfile.TemporaryDirectory() as tmp:
        f = str(Path(tmp) / "adept.csv")
        write_file(f)
        sides = {"this": str(ROOT)}
        if args.base:
            base = Path(tmp) / "base"
            base.mkdir()
            arch = subprocess.run(["git", "-C", str(ROOT), "archive", args.base, "pickplace_cli", "profiles", "tables"],
                                  check=True, capture_output=True).stdout
            subprocess.run(["tar", "-x", "-C", str(base)], input=arch, check=True)
            sides = {"base": str(base), **sides}
        got: dict = {k: [] for k in sides}
        for _ in range(args.rounds):
            for name, where in sides.items():
                env = dict(os.environ, PYTHONPATH=where)
                out = subprocess.run([sys.executable, __file__, "--worker", f, str(args.repeat)], env=env, cwd=tmp,
                                     check=True, capture_output=True, text=True).stdout
                got[name].append(float(out.strip().splitlines()[-1]))
        for name, vals in got.items():
            print(f"{name:5s} check of a 1 kHz Adept cycle file: {statistics.median(vals) * 1e3:.1f} ms CPU "
                  f"(median of {args.rounds} processes × {args.repeat} reads)")


if __name__ == "__main__":
    main()
