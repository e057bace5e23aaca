"""A line of robots: simulated time against real time on one core, what each part of a pick costs, and a sweep on
2 local worker processes against 1 (the same run).

    python bench/bench_line.py                 # 3 runs of 120 s of the 3-robot line + the sweep (~3-5 min)
    python bench/bench_line.py --quick         # 1 run of 60 s, a small sweep

The line: ``docs/line/deltas.yaml`` with its first three robots (default Deltas, 300 parts/min, Poisson arrivals,
upstream_first). Each run is one process's engine on its own (no output files), timed by wall clock and by
this process's CPU time (``time.process_time``: the one-core cost, unaffected by other processes' load on a
shared machine); the ratio is simulated time (the run's span) / time. The first run of a process also fills the
shape memo (table look-ups), so it is reported apart ("cold"); the medians are over the warm runs (other seeds).

Where the time goes (one warm run, timers around the engine's stages, their overhead included): the table
look-ups of shapes, the grid searches of the durations, the exact peak checks, the limit checks (one robot
model evaluation per cycle, and the exact check of a leg near a limit), the reasons of misses, and the rest.

The sweep: belt speed × strategy cases of ``--sweep-seconds`` simulated each, run by ``run_sweep`` on a pool of 1
local process and on a pool of 2 (both fresh: each process imports and fills its shape memo, as in a real sweep);
speed-up = wall(1) / wall(2). Results: ``bench/results/line.json``.

Also (``--turns``, on by default): the same three robots as 4-axis Deltas (``delta-4axis``) with gripper times (close
0.03 s, open 0.02 s) and parts at random angles, each turned to its tray's 0 rad, against the same line placing the
parts as they lie (both sides in the same run, medians of ``--runs`` warm seeds), where the time of the turned line
goes (as above; ``searches on every limit``: the moves whose motors do not clear the capacity's durations, searched
on every limit with their exact checks); and a 10-minute run of the manual's line (``docs/line/deltas.yaml``, 3
robots, ``quota``): its CPU seconds.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pickplace_cli.line import moves as M  # noqa: E402
from pickplace_cli.line import robot as R  # noqa: E402
from pickplace_cli.line.engine import LineEngine  # noqa: E402
from pickplace_cli.line.parts import generate  # noqa: E402
from pickplace_cli.line.spec import load_line  # noqa: E402
from pickplace_cli.line.sweep import cases, run_sweep  # noqa: E402
from pickplace_cli.model.profile import load_profile  # noqa: E402

LINE = ROOT / "docs" / "line" / "deltas.yaml"


def the_line(seconds: float, seed: int, robots: int = 3):
    line = load_line(LINE)
    gen = line.parts.generate.model_copy(update={"duration": seconds, "count": None, "seed": seed})
    line = line.model_copy(update={"parts": line.parts.model_copy(update={"generate": gen}),
                                   "robots": list(line.robots)[:robots]})
    return line, {r.name: load_profile(r.profile) for r in line.robots}


def turning_line(seconds: float, seed: int, turns: bool = True):
    """The 3-robot line as 4-axis Deltas with gripper times, parts at random angles, turned to 0 rad (or not)."""
    line, _ = the_line(seconds, seed)
    robots = []
    for r in line.robots:
        place = r.place.model_copy(update={"angle": 0.0 if turns else None})
        robots.append(r.model_copy(update={"profile": "delta-4axis", "place": place,
                                           "gripper": r.gripper.model_copy(update={"close": 0.03, "open": 0.02})}))
    gen = line.parts.generate.model_copy(update={"angles": True})
    line = line.model_copy(update={"robots": robots, "parts": line.parts.model_copy(update={"generate": gen})})
    return line, {r.name: load_profile(r.profile) for r in line.robots}


def manual_line(seconds: float):
    """The manual's worked example: docs/line/deltas.yaml, 3 robots, quota, seed 1, for ``seconds`` of parts."""
    from pickplace_cli.line.spec import Quota

    line, profiles = the_line(seconds, 1)
    return line.model_copy(update={"strategy": Quota(kind="quota")}), profiles


def one_run(seconds: float, seed: int, make=None) -> dict:
    line, profiles = (make or the_line)(seconds, seed)
    parts = generate(line.parts.generate, line.belt.width)
    w0, c0 = time.perf_counter(), time.process_time()
    eng = LineEngine(line, profiles)
    for d in parts:
        eng.offer(d)
    s = eng.finish()
    wall, cpu = time.perf_counter() - w0, time.process_time() - c0
    return {"seed": seed, "parts": s.parts, "picked": s.picked, "miss_rate": s.miss_rate, "simulated_s": s.span,
            "wall_s": wall, "cpu_s": cpu, "ratio_wall": s.span / wall, "ratio_cpu": s.span / cpu,
            "ms_per_part_cpu": 1e3 * cpu / s.parts}


class Timers:
    """Wall time inside the wrapped functions (the outermost call only, so nested stages are not counted twice
    within one stage; a stage inside another is counted in its own row and subtracted from the outer one)."""

    def __init__(self) -> None:
        self.total = defaultdict(float)
        self.calls = defaultdict(int)
        self.stack: list = []

    def wrap(self, owner, name: str, label: str) -> None:
        fn = getattr(owner, name)
        timers = self

        def wrapped(*a, **k):
            t0 = time.perf_counter()
            timers.stack.append(label)
            try:
                return fn(*a, **k)
            finally:
                timers.stack.pop()
                dt = time.perf_counter() - t0
                timers.total[label] += dt
                timers.calls[label] += 1
                if timers.stack:
                    timers.total[timers.stack[-1]] -= dt  # exclusive times

        setattr(owner, name, wrapped)


def breakdown(seconds: float, seed: int, make=None) -> dict:
    timers = Timers()
    saved = [(owner, name, getattr(owner, name)) for owner, name in (
        (M.Shapes, "candidates"), (R, "search_auto"), (R, "verify_auto"), (R.LineRobot, "_check"),
        (R.LineRobot, "_motors_clear_both"), (R.LineRobot, "_solve_fit"), (R.LineRobot, "_missed_reason"),
        (R.LineRobot, "plan"))]
    timers.wrap(M.Shapes, "candidates", "shape look-ups")
    timers.wrap(R, "search_auto", "duration searches (grid)")
    timers.wrap(R, "verify_auto", "exact peak checks")
    timers.wrap(R.LineRobot, "_check", "limit checks")
    timers.wrap(R.LineRobot, "_motors_clear_both", "limit checks")  # the cycle's one model evaluation, kept for _check
    timers.wrap(R.LineRobot, "_solve_fit", "searches on every limit (+ their exact checks)")
    timers.wrap(R.LineRobot, "_missed_reason", "reasons of misses")
    timers.wrap(R.LineRobot, "plan", "other (cycle assembly)")
    try:
        return _breakdown(timers, *(make or the_line)(seconds, seed))
    finally:
        for owner, name, fn in saved:
            setattr(owner, name, fn)


def _breakdown(timers: Timers, line, profiles) -> dict:
    parts = generate(line.parts.generate, line.belt.width)
    eng = LineEngine(line, profiles)
    w0 = time.perf_counter()
    for d in parts:
        eng.offer(d)
    s = eng.finish()
    wall = time.perf_counter() - w0
    plans = timers.calls["other (cycle assembly)"]
    rows = {k: {"ms_per_part": 1e3 * v / s.parts, "share": v / wall, "calls": timers.calls[k]}
            for k, v in sorted(timers.total.items(), key=lambda kv: -kv[1])}
    rows["engine outside the robots (strategy, results)"] = {
        "ms_per_part": 1e3 * (wall - sum(timers.total.values())) / s.parts,
        "share": (wall - sum(timers.total.values())) / wall, "calls": s.parts}
    return {"parts": s.parts, "picked": s.picked, "cycles_planned": plans, "wall_s": wall, "stages": rows}


def show_breakdown(title: str, parts: dict) -> None:
    print(f"{title}where the time goes (seed 2, {parts['parts']} parts, {parts['cycles_planned']} cycles planned, "
          f"{parts['wall_s']:.2f} s wall with the timers):")
    for k, v in parts["stages"].items():
        print(f"  {k:48s} {v['ms_per_part']:6.3f} ms/part  {100 * v['share']:5.1f} %  ({v['calls']} calls)", flush=True)


def reference(n: int = 50) -> float:
    """Median CPU ms of the project's plan() of the Adept cycle on the Delta (1 kHz, limit check, no fitted duration:
    bench/bench_plan.py's case): a yardstick of the machine's speed in this run (README, Known gaps: 0.85–0.92 ms in
    its normal phases, 1.2–1.5 ms in slow ones)."""
    from pickplace_cli.model.task import Task
    from pickplace_cli.planner import PlanOptions, plan

    prof = load_profile()
    task = Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025)
    options = PlanOptions(fit=False)
    plan(task, prof, options)
    times = []
    for _ in range(n):
        c0 = time.process_time()
        plan(task, prof, options)
        times.append(time.process_time() - c0)
    return 1e3 * statistics.median(times)


def sweep(seconds: float, speeds: list[float], strategies: list[str]) -> dict:
    line = load_line(LINE)
    gen = line.parts.generate.model_copy(update={"duration": seconds, "count": None})
    line = line.model_copy(update={"parts": line.parts.model_copy(update={"generate": gen})})
    profiles = {r.name: load_profile(r.profile) for r in line.robots}
    all_cases = cases(speeds, [3], strategies, [1])
    out = {"cases": len(all_cases), "simulated_s_each": seconds}
    from concurrent.futures import ProcessPoolExecutor

    from pickplace_cli.lookup.executors import ignore_sigint

    for workers in (1, 2):
        # both sides on fresh local processes (imports and the shape memo start cold in each), as a sweep runs
        w0 = time.perf_counter()
        with ProcessPoolExecutor(max_workers=workers, initializer=ignore_sigint) as ex:
            rows = run_sweep(line, profiles, all_cases, None, workers, ex)
        out[f"wall_s_{workers}"] = time.perf_counter() - w0
        out[f"miss_rates_{workers}"] = [r["miss_rate"] for r in rows]
        out[f"cpu_s_{workers}"] = sum(r["cpu_seconds"] for r in rows)  # CPU time the workers got
        out[f"cores_used_{workers}"] = out[f"cpu_s_{workers}"] / out[f"wall_s_{workers}"]
    out["speedup"] = out["wall_s_1"] / out["wall_s_2"]
    out["same_rows"] = out["miss_rates_1"] == out["miss_rates_2"]
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=120.0, help="simulated seconds per run")
    ap.add_argument("--runs", type=int, default=3, help="warm runs (seeds 2, 3, …) after the cold one (seed 1)")
    ap.add_argument("--sweep-seconds", type=float, default=30.0)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--no-turns", dest="turns", action="store_false", help="leave out the 4-axis turning runs")
    ap.add_argument("--output", default=str(ROOT / "bench" / "results" / "line.json"))
    args = ap.parse_args()
    if args.quick:
        args.seconds, args.runs, args.sweep_seconds = 60.0, 1, 15.0
    load = os.getloadavg()
    print(f"load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}; {os.cpu_count()} cores", flush=True)
    yard = reference()
    print(f"yardstick: plan() of the Adept cycle on the Delta {yard:.3f} ms CPU (median of 50)", flush=True)
    cold = one_run(args.seconds, 1)
    print(f"cold run (fills the shape memo): {cold['simulated_s']:.1f} s simulated in {cold['wall_s']:.2f} s wall "
          f"({cold['ratio_wall']:.1f}×), {cold['cpu_s']:.2f} s CPU ({cold['ratio_cpu']:.1f}×)", flush=True)
    warm = [one_run(args.seconds, 2 + k) for k in range(args.runs)]
    for w in warm:
        print(f"  seed {w['seed']}: {w['parts']} parts, miss rate {100 * w['miss_rate']:.1f} %, {w['simulated_s']:.1f} s "
              f"simulated in {w['wall_s']:.2f} s wall ({w['ratio_wall']:.1f}×) / {w['cpu_s']:.2f} s CPU "
              f"({w['ratio_cpu']:.1f}×), {w['ms_per_part_cpu']:.2f} ms CPU per part", flush=True)
    med = {k: statistics.median(w[k] for w in warm) for k in ("ratio_wall", "ratio_cpu", "ms_per_part_cpu")}
    print(f"median of the warm runs: {med['ratio_wall']:.1f}× real time (wall), {med['ratio_cpu']:.1f}× (CPU), "
          f"{med['ms_per_part_cpu']:.2f} ms CPU per part; target ≥ 50×", flush=True)
    parts = breakdown(args.seconds, 2)
    show_breakdown("", parts)
    sw = sweep(args.sweep_seconds, [0.3, 0.5, 0.7, 0.9], ["upstream_first", "quota"])
    print(f"sweep: {sw['cases']} cases of {sw['simulated_s_each']:g} s: 1 worker {sw['wall_s_1']:.2f} s wall "
          f"({sw['cpu_s_1']:.2f} s CPU: {sw['cores_used_1']:.2f} cores), 2 local processes {sw['wall_s_2']:.2f} s wall "
          f"({sw['cpu_s_2']:.2f} s CPU: {sw['cores_used_2']:.2f} cores): speed-up {sw['speedup']:.2f}× (same rows: "
          f"{sw['same_rows']})", flush=True)
    turns = {}
    if args.turns:
        for name, flag in (("turned", True), ("as they lie", False)):
            one_run(args.seconds, 1, lambda t, s, f=flag: turning_line(t, s, f))  # cold: fills the memos
            runs = [one_run(args.seconds, 2 + k, lambda t, s, f=flag: turning_line(t, s, f)) for k in range(args.runs)]
            turns[name] = {"runs": runs, "median_ratio_cpu": statistics.median(w["ratio_cpu"] for w in runs),
                           "median_ratio_wall": statistics.median(w["ratio_wall"] for w in runs),
                           "median_ms_per_part_cpu": statistics.median(w["ms_per_part_cpu"] for w in runs)}
            print(f"3 × delta-4axis, gripper times, parts {name}: median {turns[name]['median_ratio_cpu']:.1f}× real "
                  f"time (CPU), {turns[name]['median_ratio_wall']:.1f}× (wall), "
                  f"{turns[name]['median_ms_per_part_cpu']:.2f} ms CPU per part", flush=True)
        turns["breakdown_turned"] = breakdown(args.seconds, 2, lambda t, s: turning_line(t, s, True))
        show_breakdown("the turned line: ", turns["breakdown_turned"])
        ten = one_run(600.0, 1, lambda t, s: manual_line(t))
        turns["manual_line_600s"] = ten
        print(f"the manual's line (3 Deltas, quota) for 600 s of parts: {ten['parts']} parts, {ten['cpu_s']:.2f} s CPU "
              f"({ten['ratio_cpu']:.1f}× real time), {ten['wall_s']:.2f} s wall", flush=True)
    yard_after = reference()
    print(f"yardstick after the runs: {yard_after:.3f} ms CPU", flush=True)
    doc = {"load_average": load, "cores": os.cpu_count(), "yardstick_ms": [yard, yard_after], "seconds": args.seconds,
           "cold": cold, "warm": warm,
           "median": med, "breakdown": parts, "sweep": sw, "turns": turns}
    Path(args.output).parent.mkdir(parents=True, exist_ok=True)
    Path(args.output).write_text(json.dumps(doc, indent=1) + "\n")
    print(f"written {args.output}")


if __name__ == "__main__":
    main()
