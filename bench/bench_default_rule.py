"""The default duration rule against the fastest rule that holds every limit of the profile.

    python bench/bench_default_rule.py               # Adept + 30 random moves, the line example (~10 min on 2 cores)
    python bench/bench_default_rule.py --moves 5 --no-line   # quick look

Rules compared on delta-su2018 (rigid dynamics), each holding every limit the profile names — the motors and the
Cartesian capacity:

* ``limits`` (the default of ``plan``): the uniform law at max(auto, fit);
* ``optimal --hold-capacity``: the time-optimal law on the table's shape, the capacity held pointwise;
* ``optimal --hold-capacity --optimize shape``: the same on the shape chosen for the robot.

For every move: the duration, whether the continuous check holds every limit (capacity rows included), the
in-process plan time, and the residual vibration of the profile's modes (``studies/vibration.py``: the envelope
of the free decay of each axis' mode when the move ends, displacement [m] and acceleration [m/s²]). The moves:
the Adept cycle (−0.1525, 0, −0.8 → 0.1525, 0, −0.8, h = 25 mm) and ``--moves`` random moves (seed 7) in the
region of ``tests/property/test_limit_truth.py``. The line: ``pickplace line docs/line/deltas.yaml --robots 3``
with a short run (``--duration`` s of parts, seed 1) under each rule the line offers (limits, fit); the line has
no time-optimal law (its moves are planned for their duration), so ``fit`` (which does not hold the capacity)
shows what the capacity costs there. Results go to ``bench/results/default_rule.json``.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pickplace_cli import PlanOptions, Task, load_profile, plan  # noqa: E402
from pickplace_cli.model.errors import PickplaceError  # noqa: E402
from pickplace_cli.studies.vibration import residual_vibration  # noqa: E402
from tests.property.test_limit_truth import REGIONS  # noqa: E402

RULES = {
    "limits": PlanOptions(time="limits"),
    "optimal+capacity": PlanOptions(time="optimal", hold_capacity=True),
    "optimal+capacity+shape": PlanOptions(time="optimal", hold_capacity=True, shape=True),
}


def moves(n: int) -> list[Task]:
    out = [Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5)]
    (lo, hi), (h0, h1) = REGIONS["delta-su2018"]
    rng = np.random.default_rng(7)
    while len(out) < n + 1:
        p0, p1 = rng.uniform(lo, hi), rng.uniform(lo, hi)
        if np.linalg.norm(p1[:2] - p0[:2]) < 0.05:
            continue
        out.append(Task(p0, p1, float(rng.uniform(h0, h1)), 0.5))
    return out


def one(task: Task, prof, opts: PlanOptions) -> dict | None:
    try:
        t0 = time.perf_counter()
        p = plan(task, prof, opts)
        dt = time.perf_counter() - t0
    except PickplaceError as exc:
        return {"error": str(exc)}
    vib = residual_vibration(p.cartesian, prof.vibration)
    return {"T": p.duration.seconds, "ok": bool(p.report.ok), "ms": dt * 1e3, "amplitude_m": vib.max_amplitude,
            "acc_amplitude_m_s2": vib.max_acceleration_amplitude}


def line(rule: str, duration: float) -> dict:
    spec = yaml.safe_load((ROOT / "docs" / "line" / "deltas.yaml").read_text())
    for r in spec["robots"]:
        r["time"] = rule
    spec["parts"]["generate"]["duration"] = duration
    with tempfile.TemporaryDirectory() as tmp:
        f = Path(tmp) / "line.yaml"
        f.write_text(yaml.safe_dump(spec))
        summary = Path(tmp) / "summary.json"
        t0 = time.perf_counter()
        run = subprocess.run([sys.executable, "-m", "pickplace_cli", "line", str(f), "--robots", "3", "--seed", "1",
                              "-q", "-o", str(Path(tmp) / "parts.csv"), "--summary", str(summary)],
                             capture_output=True, text=True)
        dt = time.perf_counter() - t0
        if not summary.exists():
            return {"error": run.stderr.strip()[-400:], "exit": run.returncode}
        data = json.loads(summary.read_text())
    return {"exit": run.returncode, "seconds": dt, "summary": data}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--moves", type=int, default=30, help="random moves besides the Adept cycle")
    ap.add_argument("--duration", type=float, default=12.0, help="seconds of parts in the line run")
    ap.add_argument("--no-line", action="store_true")
    ap.add_argument("-o", "--output", default=str(Path(__file__).parent / "results" / "default_rule.json"))
    args = ap.parse_args()
    prof = load_profile("delta-su2018")
    tasks = moves(args.moves)
    rows = []
    for i, task in enumerate(tasks):
        row = {"from": task.p_from.tolist(), "to": task.p_to.tolist(), "height": task.height}
        for name, opts in RULES.items():
            row[name] = one(task, prof, opts)
        rows.append(row)
        print(f"{'Adept' if i == 0 else f'move {i:2d}'}: " + "  ".join(
            f"{n} {r['T']:.4f} s ok={r['ok']} vib {r['amplitude_m'] * 1e6:.1f} µm"
            if "T" in r else f"{n} error" for n, r in ((n, row[n]) for n in RULES)), flush=True)
    summary = {"adept": rows[0], "rules": {}}
    good = [r for r in rows if all("T" in r[n] for n in RULES)]
    for name in RULES:
        ratio = [r[name]["T"] / r["limits"]["T"] for r in good]
        vib = [r[name]["amplitude_m"] / max(r["limits"]["amplitude_m"], 1e-15) for r in good]
        summary["rules"][name] = {
            "moves": len(good), "all_ok": all(r[name]["ok"] for r in good),
            "T_ratio_median": statistics.median(ratio), "T_ratio_max": max(ratio), "T_ratio_min": min(ratio),
            "vib_ratio_median": statistics.median(vib), "vib_ratio_max": max(vib),
            "amplitude_median_um": statistics.median(r[name]["amplitude_m"] for r in good) * 1e6,
            "ms_median": statistics.median(r[name]["ms"] for r in good)}
        s = summary["rules"][name]
        print(f"{name:24s} {len(good)} moves: T/T_limits median {s['T_ratio_median']:.3f} (range "
              f"{s['T_ratio_min']:.3f} … {s['T_ratio_max']:.3f}); residual amplitude median {s['amplitude_median_um']:.1f} "
              f"µm, / limits' median {s['vib_ratio_median']:.2f} max {s['vib_ratio_max']:.2f}; all limits ok "
              f"{s['all_ok']}; plan median {s['ms_median']:.0f} ms", flush=True)
    if not args.no_line:
        summary["line"] = {}
        for rule in ("limits", "fit"):
            res = line(rule, args.duration)
            summary["line"][rule] = res
            if "summary" in res:
                ln = res["summary"]
                print(f"line docs/line/deltas.yaml --robots 3 --seed 1, {args.duration:g} s of parts, time {rule}: "
                      f"{ln['picked']}/{ln['parts']} picked, {ln['picks_per_minute']:.1f} picks/min, miss rate "
                      f"{ln['miss_rate']:.3f}, violations {len(ln['violations'])}, exit {res['exit']}", flush=True)
            else:
                print(f"line, time {rule}: {res}", flush=True)
    summary["rows"] = rows
    Path(args.output).parent.mkdir(parents=True, exist_ok=True)
    Path(args.output).write_text(json.dumps(summary, indent=1))


if __name__ == "__main__":
    main()
