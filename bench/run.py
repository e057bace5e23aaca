"""Run the benchmarks, or a quick subset, and write the summary the manual's Performance page shows.

    python bench/run.py --list              # the benchmarks: script, arguments, result file, what it measures
    python bench/run.py --quick             # the quick ones (a few minutes on 2 cores), then the summary
    python bench/run.py                     # every one (more than an hour on 2 cores), then the summary
    python bench/run.py --only core,stream  # these, then the summary
    python bench/run.py --summary           # only rewrite the summary from the result files as they are

Each benchmark is its own script under bench/ and writes ONE result file under bench/results/ (its history is git's).
The summary, ``bench/results/summary.md``, states the headline figures of every result file next to the command
that reproduces them. Timings depend on the machine and on what else runs on it: each script records the load
average (or a yardstick measured in the same run), and a comparison is made inside one run, both sides alike.
Not a test.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

BENCH = Path(__file__).resolve().parent
RESULTS = BENCH / "results"
SUMMARY = RESULTS / "summary.md"


def _ms(seconds: float) -> str:
    return f"{1e3 * seconds:.3g} ms"


def _pct(x: float) -> str:
    return f"{100 * x:.2g} %"


def _core(d: dict) -> list[str]:
    e = d["batch"]["engine"]
    return [f"in-process `plan`, Adept cycle, 1 kHz: {_ms(d['plan']['bspline']['median'])} median "
            f"(`--time fit`: {_ms(d['plan']['bspline_with_time_fit']['median'])})",
            f"batch verdicts in process: {e['1000']['in_process']['moves_per_s']['median']:,.0f} moves/s (1,000 moves); "
            f"CLI with start-up, 1,000 moves: {e['1000']['cli_j1']['moves_per_s']['median']:,.0f}/s (`-j 1`), "
            f"{e['1000']['cli_j2']['moves_per_s']['median']:,.0f}/s (`-j 2`)",
            f"`pickplace --help` {_ms(d['cli']['help']['median'])}; `plan` to a CSV file "
            f"{_ms(d['cli']['plan_adept_csv']['median'])} (wall, fresh process)",
            f"`build-table`, default grid: {d['build_table']['sequential']['median']:.2f} s (`-j 1`), "
            f"{d['build_table']['parallel']['median']:.2f} s (`-j 2`)",
            f"TOPP-RA's time-optimal traversal of the same path under the same \\|v\\|, \\|a\\|: "
            f"{d['toppra']['toppra_duration_s']:.4f} s against ours {d['toppra']['ours_duration_s']:.4f} s "
            f"(ours {d['toppra']['ratio_cycle_time']:.2f} ×, jerk-bounded)"]


def _plan(d: dict) -> list[str]:
    return [f"in-process `plan`, gantry, Adept cycle: {_ms(d['plan_inprocess_adept_1kHz']['median'])}",
            f"Delta: model, dynamics and limit check on 1,000 samples {_ms(d['delta_map_dynamics_check_1000']['median'])}; "
            f"`--time fit` {_ms(d['delta_time_fit']['median'])}",
            f"`pickplace --help` {_ms(d['cli_help']['median'])}; `plan` to a file {_ms(d['cli_plan_adept_csv']['median'])}"]


def _default(d: dict) -> list[str]:
    r = d["in_process_s"]["delta-su2018/bspline"]
    return [f"the default rule (`limits`) against `auto`, in process, Adept cycle: {_ms(r['limits'])} against "
            f"{_ms(r['auto'])} ({r['ratio']:.2f} ×); start-up of `plan`: {d['start_up_s']['limits']:.2f} s against "
            f"{d['start_up_s']['auto']:.2f} s"]


def _compare(d: dict) -> list[str]:
    return [f"`compare`, all methods, Adept cycle, in process: {d['compare_all_in_process']['median']:.2f} s; "
            f"CLI wall {d['compare_cli_wall']['median']:.2f} s"]


def _optimal(d: dict) -> list[str]:
    a = d["adept"]
    return [f"Adept cycle: `--time optimal` {a['t_optimal']:.4f} s = {a['t_optimal'] / a['t_fit']:.4f} × fit, "
            f"{a['median_ms']:.0f} ms in process",
            f"{d['moves']} random moves against 80 coefficients: worst gap {_pct(d['worst_gap'])}, median "
            f"{_pct(d['median_gap'])}; every limit holds: {d['all_ok']}"]


def _optimal_heldout(d: dict) -> list[str]:
    return [f"{d['moves']} other moves (`--seed 1000`): worst gap {_pct(d['worst_gap'])}, median {_pct(d['median_gap'])}"]


def _law_multistart(d: dict) -> list[str]:
    return [f"{d['moves']} moves: the law from 4 other starts at most {_pct(d['worst_gap_multistart'])} shorter; "
            f"a finer law space shorter by median {_pct(d['median_gap'])}, worst {_pct(d['worst_gap'])}"]


def _law_auto(text: str) -> list[str]:
    return [text.strip()]


def _shape(d: dict) -> list[str]:
    a = d["adept"]
    return [f"Adept cycle: `--optimize shape --time fit` {a['fit']['ratio']:.3f} × fit ({a['fit']['median_ms']:.0f} ms), "
            f"with `--time optimal` {a['optimal']['ratio']:.3f} × fit ({a['optimal']['median_ms']:.0f} ms)",
            f"{d['moves']} random moves against a dense grid search: worst gap {_pct(d['worst_gap'])}, median "
            f"{_pct(d['median_gap'])}"]


def _bound(d: dict) -> list[str]:
    a, c = d["adept"], d["ours_vs_toppra"]
    return [f"Adept cycle: torque-only lower bound {a['t_torque']:.4f} s; `--time optimal` {a['t_optimal']:.4f} s = "
            f"{a['t_optimal'] / a['t_torque']:.3f} × the bound",
            f"{d['moves']} moves: optimal / bound median {d['opt_over_torque']['median']:.3f} "
            f"({d['opt_over_torque']['min']:.3f} … {d['opt_over_torque']['max']:.3f}); our bound against toppra's: median "
            f"{_pct(c['median_relative'])}, worst {_pct(c['worst_relative'])} apart on {c['compared']}"]


def _on_demand(d: dict) -> list[str]:
    return [f"{d['points']} (λ, η) off the tables: median {d['median_ms']:.1f} ms, p90 {d['p90_ms']:.1f} ms, worst "
            f"{d['worst_ms']:.1f} ms; F lost median {d['gap_median']:.1e}, worst {d['gap_worst']:.1e}"]


def _table2d(d: dict) -> list[str]:
    a = d["all"]
    return [f"{a['n']} held-out (λ, η) (seed {d['seed']}): F lost median {a['median']:.3%}, worst {a['worst']:.3%}; "
            f"{a['within_0.5pct']} of {a['n']} within 0.5 %"]


def _conveyor(d: dict) -> list[str]:
    exact = d["exact (seeds + multi-start samples) random moves"]
    return [f"`bspline-vel` exact solve, 200 random moves: {_ms(exact['median'])} median; table answer "
            f"{_ms(d['table lookup']['median'])}",
            f"`plan` Delta, Adept with belts: `--time auto` {d['plan time=auto']['median']:.2f} s, `--time fit` "
            f"{d['plan time=fit']['median']:.2f} s"]


def _conveyor_table(d: dict) -> list[str]:
    a = d["F loss: answer (lookup)"]
    return [f"the conveyor table's answer alone: F lost median {a['median']:.2%}, worst {a['max']:.1%}; "
            f"{a['within_1pct']} of {a['n']} within 1 %"]


def _rendezvous(d: dict) -> list[str]:
    s = d["summary"]
    return [f"rendezvous / one exact solve (medians, same run): `auto` {s['auto']['ratio_of_medians']:.2f} × "
            f"({s['auto']['rendezvous_ms_median']:.0f} ms), `fit` {s['fit']['ratio_of_medians']:.2f} × "
            f"({s['fit']['rendezvous_ms_median']:.0f} ms)"]


def _stream(d: dict) -> list[str]:
    out = []
    for key in ("verdicts (--json)", "samples, varied moves (CSV, 1 kHz)",
                "samples, varied moves, 100 ms apart (CSV, 1 kHz)",
                "samples, varied moves, 100 ms apart (CSV, 1 kHz), --keep-warm 0.002"):
        if key in d:
            out.append(f"{key}: p50 {d[key]['p50_ms']:.2f} ms, p99 {d[key]['p99_ms']:.2f} ms")
    idle = [f"{k.rsplit(' ', 1)[-1]} s: {_pct(v['core_share'])}" for k, v in d.items()
            if k.startswith("idle CPU") and isinstance(v, dict) and "core_share" in v]
    if idle:
        out.append("idle CPU of `--keep-warm` " + ", ".join(idle))
    return out


def _threads(d: dict) -> list[str]:
    out = []
    for phase in ("idle", "loaded"):
        if phase in d:
            p = d[phase]
            out.append(f"{phase} (load {p['load_1min']:.1f}): `--time optimal` {p['default']['optimal']:.2f} s with "
                       f"a BLAS thread per core, {p['pinned']['optimal']:.2f} s with one")
    return out


def _line(d: dict) -> list[str]:
    m = d["median"]
    return [f"3 Deltas, {d['seconds']:.0f} s simulated: {m['ratio_cpu']:.1f} × real time on one core (CPU), "
            f"{m['ratio_wall']:.1f} × by the wall clock; {m['ms_per_part_cpu']:.2f} ms CPU per part; yardstick "
            f"(`plan()` of the Adept cycle) {d['yardstick_ms'][0]:.2f} ms"]


def _turn(text: str) -> list[str]:
    rows = [r for r in text.splitlines() if r.startswith("| auto") or r.startswith("| fit")]
    return [f"plan with and without a 90° turn, ratio of medians: " + ", ".join(
        f"{r.split('|')[1].strip()} {r.split('|')[4].strip()}" for r in rows)]


def _turn_example(rows: list) -> list[str]:
    return [f"{r['profile']}, {r['turn']}, `{r['time']}`: T = {r['T_s']:.4f} s, {r['picks_per_minute']:.1f} picks/min"
            for r in rows if "180" in r["turn"] or "no turn" in r["turn"]][:4]


def _fuzz(d: dict) -> list[str]:
    t = d["totals"]
    return [f"{t['runs']} runs, {t['rows']} rows: {t['tracebacks']} tracebacks, {t['hangs']} hangs, "
            f"{t['wrong_exit_codes']} wrong exit codes, {t['left_running']} processes left running"]


@dataclass(frozen=True)
class Bench:
    name: str
    script: str
    args: tuple[str, ...]
    result: str
    what: str
    summary: Callable
    quick: tuple[str, ...] | None = None  # arguments of the quick run (None: not in --quick)
    text: bool = False  # the result file is text, not JSON


BENCHMARKS = (
    Bench("core", "bench_core.py", (), "core.json", "plan per method, batches, CLI start-up, build-table, conveyor, "
          "TOPP-RA and Ruckig side by side", _core, quick=("--quick",)),
    Bench("plan", "bench_plan.py", (), "plan.json", "in-process plan (gantry, Delta), --time fit, CLI start-up", _plan,
          quick=()),
    Bench("default", "bench_default.py", (), "default.json", "the default duration rule against auto", _default,
          quick=()),
    Bench("compare", "bench_compare.py", (), "compare.json", "compare of all methods", _compare, quick=()),
    Bench("optimal", "bench_optimal.py", ("--moves", "4"), "optimal.json", "--time optimal against fit and an "
          "80-coefficient solve", _optimal),
    Bench("optimal_heldout", "bench_optimal.py", ("--moves", "4", "--seed", "1000", "-o",
          "bench/results/optimal_heldout.json"), "optimal_heldout.json", "the same on 60 other moves", _optimal_heldout),
    Bench("law_auto", "bench_law_auto.py", ("-o", "bench/results/law_auto.txt"), "law_auto.txt",
          "--law-coefficients auto against 20 on the moves of both sets", _law_auto, text=True),
    Bench("law_multistart", "bench_law_multistart.py", (), "law_multistart.json", "is the time law an optimum: other "
          "starts and a finer law space", _law_multistart),
    Bench("shape", "bench_shape.py", (), "shape.json", "--optimize shape against a dense search", _shape),
    Bench("bound", "bench_bound.py", (), "bound.json", "the torque-only lower bound (TOPP-RA) against --time optimal",
          _bound),
    Bench("on_demand", "bench_on_demand.py", (), "on_demand.json", "the (k1, k2) solve off the tables", _on_demand,
          quick=("--points", "12")),
    Bench("table2d", "bench_table2d.py", ("--points", "240", "--workers", "2"), "table2d.json", "the λ × η table "
          "against the optimiser on held-out points", _table2d),
    Bench("table2d_seed7", "bench_table2d.py", ("--points", "300", "--seed", "7", "--workers", "2", "--out",
          "bench/results/table2d_seed7.json"), "table2d_seed7.json", "the same, another seed", _table2d),
    Bench("conveyor", "bench_conveyor.py", ("--repeat", "5"), "conveyor.json", "the conveyor method's solvers and "
          "table", _conveyor),
    Bench("conveyor_table", "bench_conveyor_table.py", ("--moves", "200", "--polish", "40"), "conveyor_table.json",
          "interpolants of the conveyor table", _conveyor_table),
    Bench("rendezvous", "bench_rendezvous.py", ("--moves", "12", "--repeat", "3"), "rendezvous.json",
          "conveyor rendezvous against one exact solve", _rendezvous, quick=("--moves", "3", "--repeat", "1")),
    Bench("stream", "bench_stream.py", (), "stream.json", "streamed rows: latency and throughput", _stream),
    Bench("threads", "bench_threads.py", ("--repeats", "3", "--batches", "1", "--rows", "4", "--busy", "10"),
          "threads.json", "BLAS threads: one per core against one", _threads),
    Bench("line", "bench_line.py", (), "line.json", "a line of robots against real time", _line),
    Bench("turn", "bench_turn.py", ("--repeat", "7"), "turn.txt", "plan with and without the tool's turn", _turn,
          text=True),
    Bench("turn_example", "turn_example.py", ("--json", "bench/results/turn_example.json"), "turn_example.json",
          "the fourth axis' worked example", _turn_example, quick=("--json", "bench/results/turn_example.json")),
    Bench("fuzz", "fuzz.py", ("--seed", "1", "--minutes", "15"), "fuzz.json", "random batches, streams, hostile files "
          "and signals", _fuzz),
)


def command(b: Bench, quick: bool = False) -> list[str]:
    args = b.quick if quick and b.quick is not None else b.args
    return [sys.executable, str(BENCH / b.script), *args]


def shown(b: Bench) -> str:
    return " ".join(["python", f"bench/{b.script}", *b.args])


def write_summary() -> str:
    """bench/results/summary.md from the result files as they are."""
    lines = ["| benchmark | reproduce with | result file | latest results |", "|---|---|---|---|"]
    for b in BENCHMARKS:
        path = RESULTS / b.result
        if not path.exists():
            figures = ["(no result file)"]
        else:
            text = path.read_text(encoding="utf-8")
            try:
                figures = b.summary(text if b.text else json.loads(text))
            except (KeyError, TypeError, ValueError, IndexError, ZeroDivisionError) as exc:
                figures = [f"(the result file has another layout: {type(exc).__name__} {exc})"]
        lines.append(f"| {b.name}: {b.what} | `{shown(b)}` | `{b.result}` | {'<br>'.join(figures)} |")
    text = "\n".join(lines) + "\n"
    SUMMARY.write_text(text, encoding="utf-8")
    return text


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="only the quick benchmarks, with their quick arguments")
    ap.add_argument("--only", help="comma-separated benchmark names (see --list)")
    ap.add_argument("--summary", action="store_true", help="only rewrite bench/results/summary.md")
    ap.add_argument("--list", action="store_true", help="list the benchmarks and exit")
    args = ap.parse_args()
    if args.list:
        for b in BENCHMARKS:
            print(f"{b.name:16} {shown(b):70} -> bench/results/{b.result}{'' if b.quick is None else '  (quick)'}")
        return 0
    if not args.summary:
        names = {n.strip() for n in args.only.split(",")} if args.only else None
        unknown = sorted(names - {b.name for b in BENCHMARKS}) if names else []
        if unknown:
            ap.error(f"unknown benchmark(s): {', '.join(unknown)} (see --list)")
        chosen = [b for b in BENCHMARKS if (names is None or b.name in names) and (not args.quick or b.quick is not None)]
        failed = []
        for b in chosen:
            cmd = command(b, args.quick)
            print(f"== {b.name}: {' '.join(cmd[1:])}", flush=True)
            t0 = time.perf_counter()
            rc = subprocess.run(cmd, cwd=BENCH.parent).returncode
            print(f"== {b.name}: exit {rc}, {time.perf_counter() - t0:.0f} s", flush=True)
            if rc:
                failed.append(b.name)
        if failed:
            print(f"failed: {', '.join(failed)}", file=sys.stderr)
    print(write_summary())
    return 0


if __name__ == "__main__":
    sys.exit(main())
