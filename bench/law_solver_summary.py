"""Per-profile summary of one or more ``bench/bench_law_solver.py --reference`` results files (e.g. two seeds' runs,
or a run cut short: its file holds the moves measured so far). Moves are told apart by profile, ends and clearance;
one measured twice counts once.

    python bench/law_solver_summary.py bench/results/law_solver_500.json bench/results/law_solver_900.json

Prints, per profile: the moves, the median CPU of the default plan and of ``--time optimal`` with each solver, and
each solver's median and worst gap to the IPOPT reference; then the worst over all moves. Not a benchmark itself.
"""

from __future__ import annotations

import json
import statistics
import sys
from pathlib import Path


def main() -> None:
    moves: dict = {}
    for name in sys.argv[1:]:
        for r in json.loads(Path(name).read_text())["moves"]:
            if "t_ref" in r:
                moves[(r["profile"], tuple(r["from"]), tuple(r["to"]), r["height"])] = r
    rows = list(moves.values())
    if not rows:
        sys.exit("no move with a reference in " + " ".join(sys.argv[1:]))
    print(f"{'profile':13s} {'moves':>5s} {'default':>8s} {'SQP':>7s} {'SLSQP':>7s}   gap SQP median / worst"
          f"   gap SLSQP median / worst   (CPU medians, ms)")
    for label in dict.fromkeys(r["profile"] for r in rows):
        rs = [r for r in rows if r["profile"] == label]

        def med(k, rs=rs):
            return statistics.median(r[k] for r in rs)

        gs, gl = [r["gap_sqp"] for r in rs], [r["gap_slsqp"] for r in rs]
        print(f"{label:13s} {len(rs):5d} {med('cpu_default') * 1e3:8.1f} {med('cpu_sqp') * 1e3:7.1f} "
              f"{med('cpu_slsqp') * 1e3:7.1f}   {statistics.median(gs) * 100:+.2f} % / {max(gs) * 100:+.2f} %"
              f"          {statistics.median(gl) * 100:+.2f} % / {max(gl) * 100:+.2f} %")
    worst = max(rows, key=lambda r: r["gap_sqp"])
    print(f"all {len(rows)} moves: SQP worst {worst['gap_sqp'] * 100:+.3f} % ({worst['profile']} {worst['from']} -> "
          f"{worst['to']}), median {statistics.median(r['gap_sqp'] for r in rows) * 100:+.3f} %; SLSQP worst "
          f"{max(r['gap_slsqp'] for r in rows) * 100:+.3f} %; every plan ok: "
          f"{all(r['ok_sqp'] and r['ok_slsqp'] for r in rows)}; SQP within 0.1 %: "
          f"{sum(r['gap_sqp'] <= 1e-3 for r in rows)} of {len(rows)}")


if __name__ == "__main__":
    main()
