"""``pickplace check`` on hostile 100-row files: the time and memory a file of absurd values costs.

    python bench/bench_check_hostile.py          # ~1 min on 2 cores

Each file has a header ``t[s],q1[rad],q2[rad],q3[rad]`` and 100 rows (default profile, delta-su2018): positions of
1e9 rad, rows 1e-12 s apart, a duration of 1e11 s, positions alternating ±1000 rad, a NaN, an inf; and, for scale,
the Adept move as plan writes it (181 rows with the tool columns) and its PVT table. Measured: the in-process
``check_file`` time (median of 5, after one warm-up), its peak allocation (tracemalloc), and the wall time and peak
resident memory of a fresh ``pickplace check`` process (median of 3; /usr/bin/time's %M when present). Writes
``bench/results/check_hostile.json``. Not a test: the tests count the bounded work instead of timing it.
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
HEAD = "t[s],q1[rad],q2[rad],q3[rad]\n"
FILES = {
    "q1 = 1e9 rad": lambda i: f"{i * 1e-3},1e9,0.3,0.3\n",
    "rows 1e-12 s apart": lambda i: f"{i * 1e-12},{0.6 + i * 1e-6},0.3,0.3\n",
    "duration 1e11 s": lambda i: f"{i * 1e9},{0.6 + i * 1e-3},0.3,0.3\n",
    "alternating ±1000 rad": lambda i: f"{i * 1e-3},{(-1) ** i * 1e3},0.3,0.3\n",
    "a NaN": lambda i: f"{i * 1e-3},{'nan' if i == 50 else 0.6},0.3,0.3\n",
    "an inf": lambda i: f"{i * 1e-3},{'inf' if i == 50 else 0.6},0.3,0.3\n",
}


def _pickplace() -> list[str]:
    exe = Path(sys.executable).with_name("pickplace")
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "pickplace_cli"]


def main() -> None:
    from pickplace_cli.model.errors import PickplaceError
    from pickplace_cli.model.profile import load_profile
    from pickplace_cli.pipelines.check import check_file

    prof = load_profile("delta-su2018")
    tmp = Path(tempfile.mkdtemp())
    paths = {}
    for name, row in FILES.items():
        paths[name] = tmp / f"{len(paths)}.csv"
        paths[name].write_text(HEAD + "".join(row(i) for i in range(100)))
    for name, args in (("Adept move (plan's CSV, 181 rows)", []), ("Adept move (PVT table)", ["--format", "pvt"])):
        paths[name] = tmp / f"{len(paths)}.csv"
        subprocess.run(_pickplace() + ["plan", "--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8", "-q", "-o",
                                       str(paths[name]), *args], check=True)
    out = {"load_average": os.getloadavg(), "cases": {}}
    timer = ["/usr/bin/time", "-f", "%M"] if Path("/usr/bin/time").exists() else []
    for name, path in paths.items():
        def once():
            try:
                r = check_file(str(path), prof)
                return "exit 0" if all(c.report.ok for c in r) else "limits exceeded"
            except PickplaceError as exc:
                return f"error: {str(exc)[len(str(path)):][:80]}"
        verdict = once()
        times = []
        for _ in range(5):
            t0 = time.perf_counter()
            once()
            times.append(time.perf_counter() - t0)
        tracemalloc.start()
        once()
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        walls, rss = [], []
        for _ in range(3):
            t0 = time.perf_counter()
            p = subprocess.run(timer + _pickplace() + ["check", str(path), "-q"], capture_output=True, text=True)
            walls.append(time.perf_counter() - t0)
            if timer:
                rss.append(int(p.stderr.strip().splitlines()[-1]))
        out["cases"][name] = {"verdict": verdict, "exit_code": p.returncode,
                              "in_process_s_median": statistics.median(times),
                              "peak_alloc_MB": peak / 2**20, "cli_wall_s_median": statistics.median(walls),
                              "cli_max_rss_MB": (statistics.median(rss) / 1024) if rss else None}
        print(f"{name:36s} exit {p.returncode}  in-process {statistics.median(times):.3f} s  alloc "
              f"{peak / 2**20:6.1f} MB  CLI {statistics.median(walls):.2f} s  "
              f"RSS {(statistics.median(rss) / 1024) if rss else float('nan'):.0f} MB")
    res = ROOT / "bench" / "results" / "check_hostile.json"
    res.write_text(json.dumps(out, indent=2) + "\n")
    print(f"wrote {res}")


if __name__ == "__main__":
    main()
