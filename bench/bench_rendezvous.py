"""Conveyor rendezvous solve against one bspline-vel exact solve (target ≤ 5 × median).

    python bench/bench_rendezvous.py               # 12 random Adept-size moves onto a 0.5 m/s belt, 3 repeats (~1 min)
    python bench/bench_rendezvous.py --moves 4     # quick look

For each move (start on the Delta's working plane, a part detected 0.1–0.2 m upstream of the working point,
0.5 m/s in a random horizontal direction, latency 0–0.1 s): the time of ``find_rendezvous`` (``--time auto``
and ``--time fit``: T and the meeting point with the exact shape) and of one exact solve of the same move
(``plan_bspline_vel`` of the move to the meeting point at that T, the default ``exact`` solver, i.e. what
``--time SECONDS`` costs). Each timing is the median of ``--repeat`` runs (every run from a cold factory);
the ratio is median(rendezvous) / median(one solve) over the moves. Results go to
``bench/results/rendezvous.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from pickplace_cli.paths.bspline_vel import plan_bspline_vel  # noqa: E402
from pickplace_cli.model.profile import load_profile  # noqa: E402
from pickplace_cli.pipelines.rendezvous import Part, find_rendezvous  # noqa: E402


def cases(n: int, seed: int = 17):
    rng = np.random.default_rng(seed)
    centre = np.array([0.0, 0.0, -0.8])
    out = []
    for _ in range(n):
        a = rng.uniform(0, 2 * np.pi)
        start = centre + 0.1525 * np.array([np.cos(a), np.sin(a), 0.0])  # Adept-size: ~0.3 m to the part
        d = rng.uniform(0, 2 * np.pi)
        direction = np.array([np.cos(d), np.sin(d), 0.0])
        out.append((start, Part(centre - rng.uniform(0.1, 0.2) * direction, 0.5 * direction, rng.uniform(0, 0.1))))
    return out


def timed(fn, repeat: int) -> tuple[float, object]:
    times, result = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), result


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--moves", type=int, default=12)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--output", default=str(Path(__file__).parent / "results" / "rendezvous.json"))
    args = ap.parse_args()
    prof = load_profile("delta-su2018")
    find_rendezvous(*cases(1, seed=1)[0], prof, "auto")  # imports, table load
    rows = []
    for k, (start, part) in enumerate(cases(args.moves)):
        row = {"move": k, "start_m": start.tolist(), "part_m": part.position.tolist(),
               "belt_m_s": part.velocity.tolist(), "latency_s": part.latency}
        for rule in ("auto", "fit"):
            t_rv, rv = timed(lambda: find_rendezvous(start, part, prof, rule), args.repeat)
            t_one, _ = timed(lambda: plan_bspline_vel(rv.task, rv.seconds), args.repeat)
            row[rule] = {"T_s": rv.seconds, "meeting_point_m": rv.meeting_point.tolist(), "rendezvous_ms": 1e3 * t_rv,
                         "one_exact_solve_ms": 1e3 * t_one, "ratio": t_rv / t_one, "evaluations": rv.evaluations,
                         "waited": rv.waited}
        rows.append(row)
        print(f"move {k:2d}: auto T = {row['auto']['T_s']:.4f} s {row['auto']['rendezvous_ms']:6.1f} ms "
              f"({row['auto']['ratio']:.2f} × {row['auto']['one_exact_solve_ms']:.1f} ms); fit T = {row['fit']['T_s']:.4f} s "
              f"{row['fit']['rendezvous_ms']:6.1f} ms ({row['fit']['ratio']:.2f} ×)", flush=True)
    summary = {}
    for rule in ("auto", "fit"):
        rv_med = statistics.median(r[rule]["rendezvous_ms"] for r in rows)
        one_med = statistics.median(r[rule]["one_exact_solve_ms"] for r in rows)
        summary[rule] = {"rendezvous_ms_median": rv_med, "one_exact_solve_ms_median": one_med,
                         "ratio_of_medians": rv_med / one_med,
                         "ratio_max": max(r[rule]["ratio"] for r in rows), "target_ratio": 5.0}
        print(f"{rule}: rendezvous {rv_med:.1f} ms median, one exact solve {one_med:.1f} ms median: "
              f"{rv_med / one_med:.2f} × (target ≤ 5 ×; worst move {summary[rule]['ratio_max']:.2f} ×)")
    doc = {"command": "python bench/bench_rendezvous.py " + " ".join(sys.argv[1:]), "moves": args.moves,
           "repeat": args.repeat, "load_average": list(os.getloadavg()), "summary": summary, "rows": rows}
    Path(args.output).write_text(json.dumps(doc, indent=1) + "\n")


if __name__ == "__main__":
    main()
