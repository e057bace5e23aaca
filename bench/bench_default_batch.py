"""A verdicts-only batch (``plan --batch F --json -q``) under the default duration rule (``--time limits``) against
``--time auto``, the same moves, both sides in the same run, interleaved so that a drift of the machine's speed hits
both alike.

    python bench/bench_default_batch.py [--moves 1000] [--repeat 5] [--starts 5] [--no-plan]

* in process: :func:`pickplace_cli.pipelines.verdicts.verdict_rows` (the batched verdict engine, plan() for the rows
  it leaves) with each rule, N times, medians; and, for reference, :func:`~pickplace_cli.pipelines.batch.plan_rows`
  (every row through plan(), as without the engine) under the default rule (``--no-plan`` skips it);
* through the CLI: a fresh ``pickplace plan --batch F --json -q [-t auto] -j J`` process for J = 1 and 2, wall time
  including start-up, medians (and the CPU time of the process and its workers: on a shared machine the wall time
  of -j 2 shows whether a second core was free); every row is answered and within its limits.

The moves are those of bench/bench_core.py (the Delta ``delta-su2018``, widths 0.1–0.32 m in every direction, output at
1 kHz): the Cartesian capacity sets the duration of each. Every section prints the machine's speed at that moment,
the median time of ``sum(range(1000))`` in µs (about 10–11 µs on a quiet 2-core machine).

Writes bench/results/default_batch.json. Not a test: timings depend on the machine and on what else runs on it.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_core import _batch_rows, calibration_us, cli_command  # noqa: E402

PROFILE = "delta-su2018"
RULES = ("auto", "limits")
RESULTS = Path(__file__).resolve().parent / "results" / "default_batch.json"


def _rate(n: int, seconds: list[float]) -> dict:
    s = sorted(seconds)
    return {"median_moves_per_s": n / statistics.median(s), "min_moves_per_s": n / s[-1], "max_moves_per_s": n / s[0],
            "median_s": statistics.median(s), "n": len(s)}


def in_process(n: int, repeat: int, with_plan: bool) -> dict:
    from pickplace_cli.model.profile import load_profile
    from pickplace_cli.pipelines.batch import plan_rows, read_batch_text
    from pickplace_cli.pipelines.verdicts import Verdict, verdict_rows
    from pickplace_cli.planner import PlanOptions

    prof = load_profile(PROFILE)
    rows, bad = read_batch_text(_batch_rows(n), "bench")
    assert not bad, bad
    opts = {r: PlanOptions(fit=False, time=r) for r in RULES}
    decided = {}
    for r in RULES:  # warm: tables read, imports done
        decided[r] = sum(isinstance(x.plan, Verdict) for x in verdict_rows(rows, prof, opts[r]))
    times: dict[str, list[float]] = {r: [] for r in RULES}
    for _ in range(repeat):
        for r in RULES:
            t0 = time.perf_counter()
            list(verdict_rows(rows, prof, opts[r]))
            times[r].append(time.perf_counter() - t0)
    out = {r: {**_rate(n, times[r]), "decided_by_engine": decided[r]} for r in RULES}
    out["ratio_limits_to_auto_time"] = out["limits"]["median_s"] / out["auto"]["median_s"]
    for r in RULES:
        print(f"in process, engine, --time {r:<7} {out[r]['median_moves_per_s']:7.0f} moves/s "
              f"({out[r]['min_moves_per_s']:.0f}–{out[r]['max_moves_per_s']:.0f}; {decided[r]} of {n} rows decided by the "
              f"engine; median of {repeat})", flush=True)
    if with_plan:
        t = []
        for _ in range(max(1, repeat // 2)):
            t0 = time.perf_counter()
            list(plan_rows(rows, prof, opts["limits"]))
            t.append(time.perf_counter() - t0)
        out["plan_rows_limits"] = _rate(n, t)
        print(f"in process, plan() for every row, --time limits {out['plan_rows_limits']['median_moves_per_s']:7.0f} "
              f"moves/s (median of {len(t)})", flush=True)
    return out


def through_cli(n: int, starts: int) -> dict:
    exe = cli_command()
    out: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        src = os.path.join(tmp, f"moves{n}.csv")
        Path(src).write_text(_batch_rows(n))
        for j in (1, 2):
            times: dict[str, list[float]] = {r: [] for r in RULES}
            cpu: dict[str, list[float]] = {r: [] for r in RULES}  # CPU seconds of the process and its workers
            lines: dict[str, list[str]] = {}
            for _ in range(starts):
                for r in RULES:
                    cmd = exe + ["plan", "--batch", src, "--json", "-q", "-j", str(j)] + (["-t", "auto"] if r == "auto" else [])
                    c0 = resource.getrusage(resource.RUSAGE_CHILDREN)
                    t0 = time.perf_counter()
                    done = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, check=False)
                    times[r].append(time.perf_counter() - t0)
                    c1 = resource.getrusage(resource.RUSAGE_CHILDREN)
                    cpu[r].append(c1.ru_utime - c0.ru_utime + c1.ru_stime - c0.ru_stime)
                    lines[r] = done.stdout.decode().splitlines()
            assert len(lines["auto"]) == len(lines["limits"]) == n, "every row answered"
            assert all(json.loads(x)["exit_code"] == 0 for x in lines["limits"]), "the bench's moves are all within limits"
            for r in RULES:
                out[f"j{j}_{r}"] = {**_rate(n, times[r]), "median_cpu_s": statistics.median(cpu[r])}
                print(f"CLI -j {j}, --time {r:<7} {out[f'j{j}_{r}']['median_moves_per_s']:7.0f} moves/s including start-up "
                      f"({out[f'j{j}_{r}']['median_s']:.3f} s; {out[f'j{j}_{r}']['min_moves_per_s']:.0f}–"
                      f"{out[f'j{j}_{r}']['max_moves_per_s']:.0f}; CPU {statistics.median(cpu[r]):.3f} s; median of {starts})",
                      flush=True)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--moves", type=int, default=1000)
    ap.add_argument("--repeat", type=int, default=5, help="in-process repeats per rule")
    ap.add_argument("--starts", type=int, default=5, help="CLI processes per rule and -j")
    ap.add_argument("--no-plan", action="store_true", help="skip the reference run of plan() on every row")
    ap.add_argument("-o", "--output", type=Path, default=RESULTS)
    a = ap.parse_args()
    res: dict = {"moves": a.moves, "profile": PROFILE, "load_average_start": os.getloadavg()}
    res["calibration_start_us"] = calibration_us()
    print(f"machine speed: sum(range(1000)) = {res['calibration_start_us']:.1f} µs; load average "
          f"{res['load_average_start'][0]:.2f}")
    res["in_process"] = in_process(a.moves, a.repeat, not a.no_plan)
    res["calibration_mid_us"] = calibration_us()
    print(f"machine speed: sum(range(1000)) = {res['calibration_mid_us']:.1f} µs")
    res["cli"] = through_cli(a.moves, a.starts)
    res["calibration_end_us"] = calibration_us()
    res["load_average_end"] = os.getloadavg()
    print(f"machine speed: sum(range(1000)) = {res['calibration_end_us']:.1f} µs; load average "
          f"{res['load_average_end'][0]:.2f}")
    a.output.parent.mkdir(parents=True, exist_ok=True)
    a.output.write_text(json.dumps(res, indent=2) + "\n")
    print(f"written {a.output}")


if __name__ == "__main__":
    main()
