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

BENCH = Path(__file__).resolve().parent
RESULTS = BENCH / "results"
SUMMARY = RESULTS / "summary.md"


#: the headline figures of each result file: str.format templates over its JSON as ``d`` (or its text as ``text``)
CORE = ("in-process `plan`, Adept cycle, 1 kHz: {d[plan][bspline][median]:.2e} s median (`--time fit`: "
        "{d[plan][bspline_with_time_fit][median]:.2e} s)",
        "batch verdicts in process: {d[batch][engine][1000][in_process][moves_per_s][median]:,.0f} moves/s (1,000 "
        "moves); CLI with start-up: {d[batch][engine][1000][cli_j1][moves_per_s][median]:,.0f}/s (`-j 1`), "
        "{d[batch][engine][1000][cli_j2][moves_per_s][median]:,.0f}/s (`-j 2`)",
        "`pickplace --help` {d[cli][help][median]:.3f} s; `plan` to a CSV file {d[cli][plan_adept_csv][median]:.3f} s "
        "(wall, fresh process)",
        "`build-table`, default grid: {d[build_table][sequential][median]:.2f} s (`-j 1`), "
        "{d[build_table][parallel][median]:.2f} s (`-j 2`)",
        "TOPP-RA's time-optimal traversal of the same path under the same speed and acceleration: "
        "{d[toppra][toppra_duration_s]:.4f} s; ours {d[toppra][ours_duration_s]:.4f} s "
        "({d[toppra][ratio_cycle_time]:.2f} ×, jerk-bounded)")
PLAN = ("in-process `plan`, gantry, Adept cycle: {d[plan_inprocess_adept_1kHz][median]:.2e} s",
        "Delta: model, dynamics and limit check on 1,000 samples {d[delta_map_dynamics_check_1000][median]:.2e} s; "
        "`--time fit` {d[delta_time_fit][median]:.2e} s",
        "`pickplace --help` {d[cli_help][median]:.3f} s; `plan` to a file {d[cli_plan_adept_csv][median]:.3f} s")
DEFAULT = ("the default rule (`limits`) against `auto`, in process, Adept cycle: "
           "{d[in_process_s][delta-su2018/bspline][limits]:.2e} s against "
           "{d[in_process_s][delta-su2018/bspline][auto]:.2e} s ({d[in_process_s][delta-su2018/bspline][ratio]:.2f} ×); "
           "`plan`'s start-up {d[start_up_s][limits]:.2f} s against {d[start_up_s][auto]:.2f} s",)
COMPARE = ("`compare`, all methods, Adept cycle: {d[compare_all_in_process][median]:.2f} s in process, "
           "{d[compare_cli_wall][median]:.2f} s through the CLI",)
OPTIMAL = ("Adept cycle: `--time optimal` {d[adept][t_optimal]:.4f} s against `--time fit` {d[adept][t_fit]:.4f} s, "
           "{d[adept][median_ms]:.0f} ms in process",
           "{d[moves]} random moves against 80 coefficients: worst gap {d[worst_gap]:.2%}, median {d[median_gap]:.3%}; "
           "every limit holds: {d[all_ok]}")
HELDOUT = ("{d[moves]} other moves (`--seed 1000`): worst gap {d[worst_gap]:.2%}, median {d[median_gap]:.3%}",)
MULTISTART = ("{d[moves]} moves: the law from 4 other starts at most {d[worst_gap_multistart]:.2%} shorter; a finer "
              "law space shorter by median {d[median_gap]:.2%}, worst {d[worst_gap]:.2%}",)
SHAPE = ("Adept cycle: `--optimize shape --time fit` {d[adept][fit][ratio]:.3f} × fit "
         "({d[adept][fit][median_ms]:.0f} ms), with `--time optimal` {d[adept][optimal][ratio]:.3f} × fit "
         "({d[adept][optimal][median_ms]:.0f} ms)",
         "{d[moves]} random moves against a dense grid search: worst gap {d[worst_gap]:.2%}, median {d[median_gap]:.3%}")
BOUND = ("Adept cycle: torque-only lower bound {d[adept][t_torque]:.4f} s; `--time optimal` {d[adept][t_optimal]:.4f} s",
         "{d[moves]} moves: optimal / bound median {d[opt_over_torque][median]:.3f} ({d[opt_over_torque][min]:.3f} … "
         "{d[opt_over_torque][max]:.3f}); our bound against toppra's: median {d[ours_vs_toppra][median_relative]:.3%}, "
         "worst {d[ours_vs_toppra][worst_relative]:.2%} apart on {d[ours_vs_toppra][compared]}")
ON_DEMAND = ("{d[points]} (λ, η) off the tables: median {d[median_ms]:.1f} ms, p90 {d[p90_ms]:.1f} ms, worst "
             "{d[worst_ms]:.1f} ms; F lost median {d[gap_median]:.1e}, worst {d[gap_worst]:.1e}",)
TABLE2D = ("{d[all][n]} held-out (λ, η) (seed {d[seed]}): F lost median {d[all][median]:.3%}, worst "
           "{d[all][worst]:.3%}; {d[all][within_0.5pct]} of {d[all][n]} within 0.5 %",)
CONVEYOR = ("`bspline-vel` exact solve, 200 random moves: "
            "{d[exact (seeds + multi-start samples) random moves][median]:.4f} s median; table answer "
            "{d[table lookup][median]:.2e} s",
            "`plan` Delta, Adept with belts: `--time auto` {d[plan time=auto][median]:.2f} s, `--time fit` "
            "{d[plan time=fit][median]:.2f} s")
CONVEYOR_TABLE = ("the conveyor table's answer alone: F lost median {d[F loss: answer (lookup)][median]:.2%}, worst "
                  "{d[F loss: answer (lookup)][max]:.1%}; {d[F loss: answer (lookup)][within_1pct]} of "
                  "{d[F loss: answer (lookup)][n]} within 1 %",)
RENDEZVOUS = ("rendezvous / one exact solve (medians, same run): `auto` {d[summary][auto][ratio_of_medians]:.2f} × "
              "({d[summary][auto][rendezvous_ms_median]:.0f} ms), `fit` {d[summary][fit][ratio_of_medians]:.2f} × "
              "({d[summary][fit][rendezvous_ms_median]:.0f} ms)",)
STREAM = ("`--json` verdicts: p50 {d[verdicts (--json)][p50_ms]:.2f} ms, p99 {d[verdicts (--json)][p99_ms]:.2f} ms",
          "1 kHz CSV, varied moves 10 ms apart: p50 {d[samples, varied moves (CSV, 1 kHz)][p50_ms]:.2f} ms, p99 "
          "{d[samples, varied moves (CSV, 1 kHz)][p99_ms]:.2f} ms",
          "… 100 ms apart: p50 {d[samples, varied moves, 100 ms apart (CSV, 1 kHz)][p50_ms]:.2f} ms; with "
          "`--keep-warm 0.002` {d[samples, varied moves, 100 ms apart (CSV, 1 kHz), --keep-warm 0.002][p50_ms]:.2f} ms",
          "idle CPU of `--keep-warm` 0.002 / 0.005 / 0.02 s: {d[idle CPU, --keep-warm 0.002][core_share]:.0%} / "
          "{d[idle CPU, --keep-warm 0.005][core_share]:.0%} / {d[idle CPU, --keep-warm 0.02][core_share]:.0%} of a core")
THREADS = ("idle (load {d[idle][load_1min]:.1f}): `--time optimal` {d[idle][default][optimal]:.2f} s with a BLAS "
           "thread per core, {d[idle][pinned][optimal]:.2f} s with one",
           "loaded (load {d[loaded][load_1min]:.1f}): {d[loaded][default][optimal]:.2f} s against "
           "{d[loaded][pinned][optimal]:.2f} s")
LINE = ("3 Deltas, {d[seconds]:.0f} s simulated: {d[median][ratio_cpu]:.1f} × real time on one core (CPU), "
        "{d[median][ratio_wall]:.1f} × by the wall clock; {d[median][ms_per_part_cpu]:.2f} ms CPU per part; "
        "yardstick (`plan()` of the Adept cycle) {d[yardstick_ms][0]:.2f} ms",
        "sweep of {d[sweep][cases]} cases: 2 processes {d[sweep][wall_s_2]:.2f} s against 1 process "
        "{d[sweep][wall_s_1]:.2f} s ({d[sweep][speedup]:.2f} ×; {d[sweep][cores_used_2]:.2f} cores busy)",)
TURN_EXAMPLE = ("delta-4axis, half a turn: `fit` {d[6][T_s]:.4f} s ({d[6][binding]}), `optimal` {d[7][T_s]:.4f} s; "
                "without a turn {d[0][T_s]:.4f} s",)
DEFAULT_BATCH = ("1,000 verdicts-only rows in process: {d[in_process][limits][median_moves_per_s]:,.0f} moves/s under the "
                 "default rule against {d[in_process][auto][median_moves_per_s]:,.0f}/s under `auto` "
                 "({d[in_process][ratio_limits_to_auto_time]:.2f} × the time); CLI `-j 1`: "
                 "{d[cli][j1_limits][median_moves_per_s]:,.0f}/s against {d[cli][j1_auto][median_moves_per_s]:,.0f}/s",)
FIT_GAP = ("{d[moves]} random moves, both profiles, every fixed-path method: the closed-form fit against a bracketing "
           "search with the exact check, gap min {d[gap_min]:.1e}, median {d[gap_median]:.1e}, max {d[gap_max]:.1e}; "
           "{d[median_ms][closed_form]:.1f} ms against {d[median_ms][search]:.1f} ms",)
FUZZ = ("{d[totals][runs]} runs, {d[totals][rows]} rows: {d[totals][tracebacks]} tracebacks, {d[totals][hangs]} "
        "hangs, {d[totals][wrong_exit_codes]} wrong exit codes, {d[totals][left_running]} processes left running",)
TABLES = ("{d[cases]} controller tables (pvt, cam, cam-table; 4 moves, 3 tolerances, 3 cycles) judged as the drive "
          "rebuilds them: every limit holds: {d[all_ok]} (worst use {d[worst_table_use]:.4%}); {d[more_points]} needed "
          "more points than the tolerance, {d[retimed]} a slower table (at most x{d[max_stretch]:.4f}); slowest "
          "{d[max_seconds]:.2f} s",)
TEXT = ("{text}",)


@dataclass(frozen=True)
class Bench:
    name: str
    script: str
    args: tuple[str, ...]
    result: str
    what: str
    summary: tuple[str, ...]  # str.format templates (the constants above)
    quick: tuple[str, ...] | None = None  # arguments of the quick run (None: not in --quick)
    text: bool = False  # the result file is text, not JSON


BENCHMARKS = (
    Bench("core", "bench_core.py", (), "core.json", "plan per method, batches, CLI start-up, build-table, conveyor, "
          "TOPP-RA and Ruckig side by side", CORE, quick=("--quick",)),
    Bench("plan", "bench_plan.py", (), "plan.json", "in-process plan (gantry, Delta), --time fit, CLI start-up", PLAN,
          quick=()),
    Bench("default", "bench_default.py", (), "default.json", "the default duration rule against auto", DEFAULT,
          quick=()),
    Bench("default_batch", "bench_default_batch.py", (), "default_batch.json", "a verdicts-only batch under the default "
          "rule against auto", DEFAULT_BATCH),
    Bench("fit_gap", "bench_fit_gap.py", (), "fit_gap.json", "the closed-form fit against an independent search",
          FIT_GAP),
    Bench("compare", "bench_compare.py", (), "compare.json", "compare of all methods", COMPARE, quick=()),
    Bench("optimal", "bench_optimal.py", ("--moves", "4"), "optimal.json", "--time optimal against fit and an "
          "80-coefficient solve", OPTIMAL),
    Bench("optimal_heldout", "bench_optimal.py", ("--moves", "4", "--seed", "1000", "-o",
          "bench/results/optimal_heldout.json"), "optimal_heldout.json", "the same on 60 other moves", HELDOUT),
    Bench("law_auto", "bench_law_auto.py", ("-o", "bench/results/law_auto.txt"), "law_auto.txt",
          "--law-coefficients auto against 20 on the moves of both sets", TEXT, text=True),
    Bench("law_multistart", "bench_law_multistart.py", (), "law_multistart.json", "is the time law an optimum: other "
          "starts and a finer law space", MULTISTART),
    Bench("shape", "bench_shape.py", (), "shape.json", "--optimize shape against a dense search", SHAPE),
    Bench("bound", "bench_bound.py", (), "bound.json", "the torque-only lower bound (TOPP-RA) against --time optimal",
          BOUND),
    Bench("tables", "bench_tables.py", (), "tables.json", "controller tables: points before and after they hold "
          "every limit as the drive rebuilds them", TABLES, quick=()),
    Bench("on_demand", "bench_on_demand.py", (), "on_demand.json", "the (k1, k2) solve off the tables", ON_DEMAND,
          quick=("--points", "12")),
    Bench("table2d", "bench_table2d.py", ("--points", "240", "--workers", "2"), "table2d.json", "the λ × η table "
          "against the optimiser on held-out points", TABLE2D),
    Bench("table2d_seed7", "bench_table2d.py", ("--points", "300", "--seed", "7", "--workers", "2", "--out",
          "bench/results/table2d_seed7.json"), "table2d_seed7.json", "the same, another seed", TABLE2D),
    Bench("conveyor", "bench_conveyor.py", ("--repeat", "5"), "conveyor.json", "the conveyor method's solvers and "
          "table", CONVEYOR),
    Bench("conveyor_table", "bench_conveyor_table.py", ("--moves", "200", "--polish", "40"), "conveyor_table.json",
          "interpolants of the conveyor table", CONVEYOR_TABLE),
    Bench("rendezvous", "bench_rendezvous.py", ("--moves", "12", "--repeat", "3"), "rendezvous.json",
          "conveyor rendezvous against one exact solve", RENDEZVOUS, quick=("--moves", "3", "--repeat", "1")),
    Bench("stream", "bench_stream.py", (), "stream.json", "streamed rows: latency and throughput", STREAM),
    Bench("threads", "bench_threads.py", ("--repeats", "3", "--batches", "1", "--rows", "4", "--busy", "10"),
          "threads.json", "BLAS threads: one per core against one", THREADS),
    Bench("line", "bench_line.py", (), "line.json", "a line of robots against real time", LINE),
    Bench("turn", "bench_turn.py", ("--repeat", "7"), "turn.txt", "plan with and without the tool's turn", TEXT,
          text=True),
    Bench("turn_example", "turn_example.py", ("--json", "bench/results/turn_example.json"), "turn_example.json",
          "the fourth axis' worked example", TURN_EXAMPLE, quick=("--json", "bench/results/turn_example.json")),
    Bench("fuzz", "fuzz.py", ("--seed", "1", "--minutes", "15"), "fuzz.json", "random batches, streams, hostile files "
          "and signals", FUZZ),
)


def command(b: Bench, quick: bool = False) -> list[str]:
    args = b.quick if quick and b.quick is not None else b.args
    return [sys.executable, str(BENCH / b.script), *args]


def shown(b: Bench) -> str:
    return " ".join(["python", f"bench/{b.script}", *b.args])


def _digit_keys(obj: dict) -> dict:
    """A JSON object whose keys are numerals also by number: str.format reads ``d[1000]`` as the integer 1000."""
    return {**obj, **{int(k): v for k, v in obj.items() if k.isdigit()}}


def write_summary() -> str:
    """bench/results/summary.md from the result files as they are."""
    lines = ["| benchmark | reproduce with | result file | latest results |", "|---|---|---|---|"]
    for b in BENCHMARKS:
        path = RESULTS / b.result
        if not path.exists():
            figures = ["(no result file)"]
        else:
            text = path.read_text(encoding="utf-8")
            fields = {"text": " ".join(text.split()).replace("|", "\\|")} if b.text else {"d": json.loads(text, object_hook=_digit_keys)}
            try:
                figures = [template.format(**fields) for template in b.summary]
            except (KeyError, TypeError, ValueError, IndexError) as exc:
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
