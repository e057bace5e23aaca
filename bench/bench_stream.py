"""``plan --batch -`` as a pipeline stage: latency per row and throughput.

    python bench/bench_stream.py                      # ~7 min on 2 cores (~9 min with --old)
    python bench/bench_stream.py --old /tmp/oldclone  # also another checkout, side by side

Latency: one `pickplace plan --batch -` process; rows of the Adept cycle on the default Delta are written one
at a time with a pause between them (a vision system's pace); the latency of a row is from the moment its
last byte is written (after flush) to the moment the last byte of its answer is read: the JSON line (verdicts
only, ``--json``) or all its CSV rows at 1 kHz (``--rate 1000``: every column, and ``--columns t,q1,q2,q3``,
a PLC's position feed), then every row a different move near the Adept cycle (``varied_rows``: nothing helped
by a repeated input), 10 ms apart and at a picking pace (``--long-pause``, 100 ms: the CPU's caches go cold
between rows, the worst case). Reports p50 and p99 (targets with samples: 2 ms and 5 ms).
Throughput: a file of rows piped in at full speed (``--json`` verdicts and CSV samples, ``-j 1`` and ``-j 2``),
rows per second including start-up; with ``--old`` the same commands on another checkout side by side.
``--keep-warm S,…`` (default 0.002,0.005): the CSV latency cases also with ``--keep-warm S`` for each S, in
interleaved rounds, and the CPU time ``--keep-warm`` costs while the stream waits (0.002, 0.005, 0.01, 0.02 s).
With ``--old`` the latencies of the other checkout too, in interleaved rounds. Results go to
``bench/results/stream.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import select
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
HEADER = "from_x,from_y,from_z,to_x,to_y,to_z\n"
ROW = "-0.1525,0,-0.8,0.1525,0,-0.8\n"


def _cmd(root: Path, *args: str) -> tuple[list[str], dict]:
    """The command and environment that run ``root``'s pickplace (run it with ``cwd=root``: ``-m`` puts the working
    directory first on the path, before PYTHONPATH; an editable install's finder comes after both)."""
    env = dict(os.environ, PYTHONPATH=str(root))
    return [sys.executable, "-m", "pickplace_cli", "plan", "--batch", "-", *args], env


#: the harness's read buffer, allocated once: reading into it costs no allocation per answer (``os.read(fd, 1 MiB)``
#: maps and unmaps a fresh 1 MiB buffer each time, ~0.1 ms of the harness's own per row on this machine)
_BUF = bytearray(8 << 20)


def _read_lines(stream, n: int, timeout: float = 30.0, legacy: bool = False) -> None:
    """Read exactly n lines from a binary stream (raw fd reads, no Python buffering surprises), into a buffer
    allocated once (``legacy``: ``os.read`` of up to 1 MiB per read, a new bytes object each time, as older
    versions of this harness did)."""
    fd = stream.fileno()
    got = 0
    if legacy:
        buf = b""
        while got < n:
            ready, _, _ = select.select([fd], [], [], timeout)
            if not ready:
                raise TimeoutError(f"only {got} of {n} lines within {timeout} s")
            chunk = os.read(fd, 1 << 20)
            if not chunk:
                raise EOFError(f"output ended after {got} of {n} lines")
            buf += chunk
            got = buf.count(b"\n")
        if got > n:
            raise RuntimeError(f"read {got} lines, expected {n}: the answer is not where this benchmark thinks")
        return
    view = memoryview(_BUF)
    size = 0
    while got < n:
        ready, _, _ = select.select([fd], [], [], timeout)
        if not ready:
            raise TimeoutError(f"only {got} of {n} lines within {timeout} s")
        if size == len(_BUF):
            raise RuntimeError(f"an answer of more than {len(_BUF)} bytes: enlarge _BUF")
        k = os.readv(fd, [view[size:]])
        if not k:
            raise EOFError(f"output ended after {got} of {n} lines")
        got += _BUF.count(b"\n", size, size + k)
        size += k
    view.release()
    if got > n:
        raise RuntimeError(f"read {got} lines, expected {n}: the answer is not where this benchmark thinks")


def latency(args: list[str], lines_per_row: int | list[int], first_extra: int, rows: int, pause: float,
            root: Path | None = None, row_text: list[str] | None = None) -> list[float]:
    """Latencies [s] of rows 2..``rows`` (``row_text``: the rows to send, cycled, with ``lines_per_row`` the
    answer lines of each; else the Adept row every time)."""
    root = root or ROOT
    texts = row_text or [ROW]
    counts = lines_per_row if isinstance(lines_per_row, list) else [lines_per_row] * len(texts)
    cmd, env = _cmd(root, *args)
    proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                            env=env, bufsize=0, cwd=root)
    out = []
    try:
        os.write(proc.stdin.fileno(), HEADER.encode())
        for i in range(rows):
            os.write(proc.stdin.fileno(), texts[i % len(texts)].encode())
            t0 = time.perf_counter()
            _read_lines(proc.stdout, counts[i % len(texts)] + (first_extra if i == 0 else 0))
            out.append(time.perf_counter() - t0)
            time.sleep(pause)
        proc.stdin.close()
        proc.wait(30)
    finally:
        proc.kill()
    return out[1:]  # the first row pays the imports and the warm-up of the process: reported apart


def varied_rows(n: int, seed: int = 16) -> tuple[list[str], list[int]]:
    """``n`` different moves around the Adept cycle (each end moved by up to ±30 mm in x, y and ±20 mm in z,
    seeded), each one the default Delta plans within its limits, and the number of 1 kHz samples of each: a
    vision system's picks, so no answer is helped by a repeated input."""
    import numpy as np

    from pickplace_cli.model.profile import load_profile
    from pickplace_cli.model.task import Task
    from pickplace_cli.planner import PlanOptions, plan

    prof = load_profile("delta-su2018")
    rng = np.random.default_rng(seed)
    rows, counts = [], []
    while len(rows) < n:
        a = np.array([-0.1525, 0.0, -0.8]) + rng.uniform(-1, 1, 3) * [0.03, 0.03, 0.02]
        b = np.array([0.1525, 0.0, -0.8]) + rng.uniform(-1, 1, 3) * [0.03, 0.03, 0.02]
        a, b = np.round(a, 4), np.round(b, 4)
        p = plan(Task(a, b, 0.025, 0.5), prof, PlanOptions(rate=1000.0, fit=False))
        if p.report.exit_code():
            continue
        rows.append(",".join(f"{x:g}" for x in (*a, *b)) + "\n")
        counts.append(len(p.t))
    return rows, counts


def idle_cpu(interval: float, seconds: float = 10.0) -> float:
    """CPU time of a ``--keep-warm interval`` stream that waits ``seconds`` after answering one CSV row at 1 kHz,
    as a share of one core (user + system time from /proc: what the warm-ups cost while no row comes)."""
    cmd, env = _cmd(ROOT, "--rate", "1000", "-q", "--keep-warm", f"{interval:g}")
    proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            env=env, cwd=ROOT)

    def cpu() -> float:
        fields = Path(f"/proc/{proc.pid}/stat").read_text().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")

    try:
        proc.stdin.write((HEADER + ROW).encode())
        proc.stdin.flush()
        time.sleep(2.0)  # start-up and the row's answer
        c0, w0 = cpu(), time.perf_counter()
        time.sleep(seconds)
        c1, w1 = cpu(), time.perf_counter()
        proc.stdin.close()
        proc.wait(30)
    finally:
        proc.kill()
    return (c1 - c0) / (w1 - w0)


def throughput(root: Path, args: list[str], rows: int) -> float:
    cmd, env = _cmd(root, *args)
    text = HEADER + ROW * rows
    t0 = time.perf_counter()
    try:
        r = subprocess.run(cmd, input=text.encode(), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env,
                           cwd=root, timeout=120)
    except subprocess.TimeoutExpired:  # an older checkout with the -j N stream hang
        return float("nan")
    dt = time.perf_counter() - t0
    if r.returncode != 0:
        raise RuntimeError(f"{cmd} exited {r.returncode}")
    return rows / dt


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rows", type=int, default=300, help="rows for the latency runs")
    ap.add_argument("--pause", type=float, default=0.01, help="s between two rows in the latency runs")
    ap.add_argument("--long-pause", type=float, default=0.1,
                    help="s between two rows in the realistic-pace case (a pick every 100 ms or more)")
    ap.add_argument("--keep-warm", default="0.002,0.005",
                    help="s, comma-separated: the CSV latency cases also with --keep-warm each (0: none), side by "
                         "side; and the idle CPU time it costs")
    ap.add_argument("--old", type=Path, help="another checkout to compare the throughput with")
    ap.add_argument("-o", "--output", default=str(Path(__file__).parent / "results" / "stream.json"))
    args = ap.parse_args()
    sys.path.insert(0, str(ROOT))
    from pickplace_cli.planner import PlanOptions, plan
    from pickplace_cli.model.profile import load_profile
    from pickplace_cli.model.task import Task

    samples = len(plan(Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5), load_profile("delta-su2018"),
                       PlanOptions(rate=1000.0)).t)
    result: dict = {"rows": args.rows, "pause_s": args.pause, "samples_per_row": samples}
    varied, varied_counts = varied_rows(50)
    cases = (("verdicts (--json)", ["--json", "-q"], 1, 0, None, args.pause),
             ("samples (CSV, 1 kHz)", ["--rate", "1000", "-q"], samples, 1, None, args.pause),
             ("samples t,q1,q2,q3 (CSV, 1 kHz, --columns)", ["--rate", "1000", "-q", "--columns", "t,q1,q2,q3"],
              samples, 1, None, args.pause),
             ("samples, varied moves (CSV, 1 kHz)", ["--rate", "1000", "-q"], varied_counts, 1, varied, args.pause),
             (f"samples, varied moves, {args.long_pause * 1e3:.0f} ms apart (CSV, 1 kHz)", ["--rate", "1000", "-q"],
              varied_counts, 1, varied, args.long_pause))
    warms = [float(x) for x in args.keep_warm.split(",") if float(x) > 0]
    for name, cli, lines, extra, texts, pause in cases:
        long = pause != args.pause
        # (label, checkout, extra args): with --old the other checkout; the CSV cases also with --keep-warm
        variants = [("", ROOT, [])]
        if args.old and "--columns" not in cli:
            variants.append((", other checkout", args.old, []))
        if "--rate" in cli and "--columns" not in cli:
            variants += [(f", --keep-warm {w:g}", ROOT, ["--keep-warm", f"{w:g}"]) for w in warms]
        rounds = 3 if len(variants) > 1 else 1  # interleaved rounds: the machine's pace shared by every variant
        n_rows = max(args.rows // 3, 30) if long else args.rows  # a long pause: fewer rows, same run time order
        lats: dict = {v[0]: [] for v in variants}
        for k in range(rounds):
            for label, root, more in (variants if k % 2 == 0 else variants[::-1]):
                lats[label] += latency(cli + more, lines, extra, n_rows // rounds, pause, root, texts)
        for label, _, _ in variants:
            lat = sorted(lats[label])
            p50 = statistics.median(lat) * 1e3
            p99 = lat[min(len(lat) - 1, int(round(0.99 * (len(lat) - 1))))] * 1e3
            key = name + label
            result[key] = {"p50_ms": p50, "p99_ms": p99, "max_ms": lat[-1] * 1e3, "pause_s": pause, "rows": len(lat)}
            print(f"latency, {key}: p50 {p50:.2f} ms, p99 {p99:.2f} ms, max {lat[-1] * 1e3:.2f} ms "
                  f"({len(lat)} rows, {pause * 1e3:.0f} ms apart)", flush=True)
    if warms:
        for interval in sorted({0.002, 0.005, 0.01, 0.02, *warms}):
            share = idle_cpu(interval)
            result[f"idle CPU, --keep-warm {interval:g}"] = {"core_share": share}
            print(f"idle CPU, --keep-warm {interval:g}: {share * 100:.1f} % of a core (a stream waiting 10 s "
                  f"after a CSV row)", flush=True)
    runs = (("verdicts -j 1", ["--json", "-q", "-j", "1"], 3000), ("verdicts -j 2", ["--json", "-q", "-j", "2"], 3000),
            ("CSV -j 1", ["-q", "-j", "1"], 600), ("CSV -j 2", ["-q", "-j", "2"], 600))
    for name, cli, rows in runs:
        new = statistics.median(throughput(ROOT, cli, rows) for _ in range(3))  # nan: a run hung (120 s)
        line = f"throughput, {name}, {rows} rows piped in: {new:.0f} rows/s"
        entry = {"rows": rows, "rows_per_s": new}
        if args.old:
            old = statistics.median(throughput(args.old, cli, rows) for _ in range(3))
            entry["old_rows_per_s"] = old
            line += f" (other checkout {old:.0f} rows/s: {new / old:.2f} ×)"
        result[f"throughput {name}"] = entry
        print(line, flush=True)
    Path(args.output).parent.mkdir(parents=True, exist_ok=True)
    Path(args.output).write_text(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
