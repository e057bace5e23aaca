"""Part types on a line: what a run costs with types against the same line without them (both in the same run).

    python bench/bench_line_types.py             # 3 warm runs of 60 s each side, after a cold one
    python bench/bench_line_types.py --runs 1 --seconds 20

Typed: ``docs/line/two-products.yaml`` (3 Deltas, two part types, places per type). Untyped: the same file with the
types removed and each robot placing every part at its first place (one place per robot). The two runs pick
different parts (a robot takes only its types), so the figure to compare is the CPU time per part offered
(``time.process_time``: the one-core cost, unaffected by other processes on a shared machine) and per part picked;
medians over warm runs (seeds 2, 3, …; the first run of the process fills the shape memo and is left out).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pickplace_cli.line.engine import LineEngine  # noqa: E402
from pickplace_cli.line.parts import generate  # noqa: E402
from pickplace_cli.line.spec import load_line  # noqa: E402
from pickplace_cli.model.profile import load_profile  # noqa: E402

LINE = ROOT / "docs" / "line" / "two-products.yaml"


def the_line(seconds: float, seed: int, typed: bool):
    line = load_line(LINE)
    gen = line.parts.generate.model_copy(update={"duration": seconds, "count": None, "seed": seed})
    parts = line.parts.model_copy(update={"generate": gen})
    robots = list(line.robots)
    if not typed:
        parts = parts.model_copy(update={"types": None})
        robots = [r.model_copy(update={"place": next(iter(r.places.values())), "places": None}) for r in robots]
    line = line.model_copy(update={"parts": parts, "robots": robots})
    return line, {r.name: load_profile(r.profile) for r in line.robots}


def one_run(seconds: float, seed: int, typed: bool) -> dict:
    line, profiles = the_line(seconds, seed, typed)
    c0, w0 = time.process_time(), time.perf_counter()
    eng = LineEngine(line, profiles)
    for d in generate(line.parts.generate, line.belt.width, line.parts.types):
        eng.offer(d)
    s = eng.finish()
    cpu, wall = time.process_time() - c0, time.perf_counter() - w0
    return {"parts": s.parts, "picked": s.picked, "cpu_s": cpu, "wall_s": wall,
            "cpu_ms_per_part": 1e3 * cpu / s.parts, "cpu_ms_per_pick": 1e3 * cpu / max(s.picked, 1)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--seconds", type=float, default=60.0)
    args = ap.parse_args()
    for typed in (True, False):
        one_run(10.0, 1, typed)  # cold: fills the shape memo
    runs = {True: [], False: []}
    for k in range(args.runs):
        for typed in (True, False):  # alternated: both sides see the same machine load
            runs[typed].append(one_run(args.seconds, 2 + k, typed))
    for typed, label in ((True, "typed (two-products.yaml)"), (False, "untyped (first place each)")):
        med = {key: statistics.median(r[key] for r in runs[typed]) for key in runs[typed][0]}
        print(f"{label}: median of {args.runs}: {med['parts']:.0f} parts, {med['picked']:.0f} picked, "
              f"CPU {med['cpu_s']:.2f} s ({med['cpu_ms_per_part']:.2f} ms a part, {med['cpu_ms_per_pick']:.2f} ms a "
              f"pick), wall {med['wall_s']:.2f} s, {args.seconds / med['cpu_s']:.1f}x real time on one core")


if __name__ == "__main__":
    main()
