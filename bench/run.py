"""pickplace benchmark suite: one command, medians with min–max, results in bench/results/bench.json.

    python bench/run.py            # full run (about 2–3 minutes on 2 cores, most of it build-table)
    python bench/run.py --quick    # fewer repeats, one build per mode (about 40 s)

What it measures (all on the Adept cycle (−0.1525, 0, −0.8) → (0.1525, 0, −0.8) m, h = 25 mm, on the
default Delta profile ``delta-su2018``, output at 1 kHz):

* in-process ``plan`` for every method in ``pickplace_cli.paths.Method`` (path, ``--time auto``, joint
  mapping, dynamics, limit check), and the B-spline plan with ``--time fit``;
* batch throughput in moves/s through ``pickplace_cli.pipelines.batch.plan_rows`` (full plans; and verdicts only,
  i.e. output rate 1 Hz — duration and verdict are the same, since the check grid does not depend on it);
  the batched verdict engine (``pickplace_cli.pipelines.verdicts``) in-process and through the CLI
  (``plan --batch F --json -q``, fresh process, -j 1 and -j 2) for 1,000 and 10,000 moves, under the default
  duration rule (``--time limits``) and under ``--time auto``, interleaved (bench/bench_default_batch.py: the same
  comparison alone);
* CLI cold start, wall time of a fresh process: ``--help``, ``--version``, one ``plan`` to a CSV file;
* ``build-table`` wall time for the default grid (79 λ), sequential (``-j 1``) and on all cores;
* the conveyor method ``bspline-vel``: exact solve and table lookup (when the module is there);
* side by side, when the ``bench`` extra is installed: TOPP-RA (the time-optimal parameterisation of our
  B-spline path's geometry under the same |v| and |a| limits: the cycle-time floor of that path) and
  Ruckig (jerk-limited state-to-state segments chained through the lift-off and set-down points), with
  our cycle time and compute time as ratios to theirs.

Every section header also prints the machine's speed at that moment, the median time of
``sum(range(1000))`` in µs (about 10–11 µs on this VM when it is quiet): the VM's speed drifts by up to
1.6× within minutes, and a section measured in a slow phase shows it there.

Norm limits and per-axis tools. The profile limits the *norm* |v| ≤ [v], |a| ≤ [a]; TOPP-RA and Ruckig
take per-axis bounds. For TOPP-RA the path (which lies in the vertical plane of the move) is given as its
projections on K = 36 directions of that plane, each bounded by [v]·cos(π/2K) and [a]·cos(π/2K): the
polygon these bounds cut out lies inside the disc |x| ≤ limit, so the result respects the norm limits and
is at most 1/cos(π/72) − 1 = 0.1 % slower than the exact norm-limited optimum (the run also reports the
circumscribed polygon, a lower bound). Ruckig has no such trick for a 3-axis move, so each axis gets
[v]/√2, [a]/√2, [j]/√2 (the move is planar: then the norm can never exceed the limit; conservative), and,
for reference, the optimistic per-axis = norm bound (the norm may then reach √2 × the limit). The
profile has no jerk capacity, so Ruckig's jerk limit is our plan's own peak jerk.

Not a test: timings depend on the machine and on what else runs on it. The load average is recorded
with the results; compare runs on a quiet machine.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ADEPT_FROM = (-0.1525, 0.0, -0.8)
ADEPT_TO = (0.1525, 0.0, -0.8)
ADEPT = ["--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8"]
PROFILE = "delta-su2018"
RESULTS = Path(__file__).resolve().parent / "results" / "bench.json"


# --------------------------------------------------------------------------------------------- helpers


def stats(samples: list[float]) -> dict:
    return {"median": statistics.median(samples), "min": min(samples), "max": max(samples), "n": len(samples)}


def timeit(fn, repeat: int, warm: int = 1) -> dict:
    for _ in range(warm):
        fn()
    out = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t0)
    return stats(out)


def show(name: str, s: dict, unit: str = "ms", scale: float = 1e3, target: str = "") -> None:
    med, lo, hi = s["median"] * scale, s["min"] * scale, s["max"] * scale
    fmt = ".3g" if med < 10 else ".1f"
    line = f"  {name:<58} {med:>9{fmt}} {unit:<3} ({lo:{fmt}}–{hi:{fmt}}, n={s['n']})"
    print(line + (f"   target {target}" if target else ""))


def note(name: str, text: str) -> None:
    print(f"  {name:<58} {text}")


#: speed of this machine at each section: median time of sum(range(1000)) [µs] (the VM's speed drifts by up
#: to 1.6× within minutes; a section run in a slow phase shows a larger number here, not a regression)
CALIBRATION: dict = {}


def calibration_us() -> float:
    import statistics
    import timeit as _timeit

    return statistics.median(_timeit.repeat("sum(range(1000))", number=200, repeat=15)) / 200 * 1e6


def section(title: str) -> None:
    c = calibration_us()
    CALIBRATION[title.split(",")[0]] = c
    print(f"\n{title}  [load average {os.getloadavg()[0]:.2f}; machine speed: sum(range(1000)) {c:.1f} µs]")


def machine() -> dict:
    cpu = platform.processor() or ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    mem = None
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemTotal"):
                mem = round(int(line.split()[1]) / 1024**2, 1)
    except OSError:
        pass
    versions = {}
    for mod in ("numpy", "scipy", "pydantic", "typer", "toppra", "ruckig", "distributed"):
        try:
            from importlib.metadata import version

            versions[mod] = version(mod)
        except Exception:  # noqa: BLE001 - not installed
            versions[mod] = None
    from pickplace_cli import __version__

    return {
        "cpu": cpu, "cores": os.cpu_count(), "memory_gib": mem, "platform": platform.platform(),
        "python": platform.python_version(), "pickplace": __version__, "versions": versions,
    }


def cli_command() -> list[str]:
    exe = shutil.which("pickplace")
    return [exe] if exe else [sys.executable, "-m", "pickplace_cli"]


def wall(cmd: list[str], repeat: int, cwd: str | None = None) -> dict:
    out = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True, cwd=cwd)
        out.append(time.perf_counter() - t0)
    return stats(out)


# -------------------------------------------------------------------------------------------- sections


def adept_task(**kw):
    from pickplace_cli.model.task import Task

    return Task(list(ADEPT_FROM), list(ADEPT_TO), 0.025, 0.5, **kw)


def bench_methods(repeat: int) -> dict:
    from pickplace_cli.paths import Method
    from pickplace_cli.planner import PlanOptions, plan
    from pickplace_cli.model.profile import load_profile

    section(f"in-process plan, Adept cycle, {PROFILE}, 1 kHz, kinematics + dynamics + limit check")
    prof = load_profile(PROFILE)
    task = adept_task()
    res: dict = {}
    for m in Method:
        opts = PlanOptions(method=m, fit=False)
        try:
            p = plan(task, prof, opts)
            t0 = time.perf_counter()
            plan(task, prof, opts)
            once = time.perf_counter() - t0
        except Exception as exc:  # noqa: BLE001 - a method that needs more input is reported, not fatal
            res[m.value] = {"error": f"{type(exc).__name__}: {exc}"}
            note(f"plan --method {m.value}", f"not run: {type(exc).__name__}: {exc}")
            continue
        n = max(3, min(repeat, int(2.0 / max(once, 1e-6))))  # about 2 s per method at most
        # a new Task per plan, as the CLI and any caller make one: Task caches its derived quantities
        s = timeit(lambda: plan(adept_task(), prof, opts), n, warm=0)
        s.update(duration_s=p.duration.seconds, samples=len(p.t), limits_ok=bool(p.report.ok))
        res[m.value] = s
        show(f"plan --method {m.value} (T = {p.duration.seconds:.4f} s, {len(p.t)} samples)", s,
             target="< 1 ms" if m.value == "bspline" else "")
    opts = PlanOptions(method="bspline", fit=True)
    s = timeit(lambda: plan(adept_task(), prof, opts), max(3, repeat // 2))
    res["bspline_with_time_fit"] = s
    show("plan --method bspline, also --time fit", s)
    return res


def _batch_rows(n: int) -> str:
    """n moves of different widths, directions and heights inside the Delta's workspace."""
    import numpy as np

    rng = np.random.default_rng(0)
    lines = ["from_x,from_y,from_z,to_x,to_y,to_z"]
    for _ in range(n):
        r = rng.uniform(0.05, 0.16)
        a = rng.uniform(0, 2 * np.pi)
        z0, z1 = rng.uniform(-0.82, -0.78, 2)
        lines.append(f"{-r * np.cos(a):.4f},{-r * np.sin(a):.4f},{z0:.4f},{r * np.cos(a):.4f},{r * np.sin(a):.4f},{z1:.4f}")
    return "\n".join(lines) + "\n"


def bench_batch(n: int, repeat: int, engine_sizes: tuple[int, ...] = (1000, 10000)) -> dict:
    section(f"batch throughput ({n} moves, {PROFILE}, bspline)")
    try:
        from pickplace_cli.pipelines.batch import plan_rows, read_batch_text
    except ImportError:
        note("batch", "not available (pickplace_cli.pipelines.batch is missing); skipped")
        return {"error": "pickplace_cli.pipelines.batch not available"}
    from pickplace_cli.planner import PlanOptions
    from pickplace_cli.model.profile import load_profile

    prof = load_profile(PROFILE)
    rows, bad = read_batch_text(_batch_rows(n), "bench")
    assert not bad, bad
    res: dict = {"moves": n}
    for key, label, opts in (
        ("full", "full plans (1 kHz samples)", PlanOptions(fit=False)),
        ("verdicts", "durations + verdicts (output rate 1 Hz)", PlanOptions(fit=False, rate=1.0)),
    ):
        outcome: list = []
        s = timeit(lambda: outcome.__setitem__(slice(None), list(plan_rows(rows, prof, opts))), repeat)
        failed = sum(1 for r in outcome if r.error and r.plan is None)
        rate = {k: n / v for k, v in s.items() if k in ("median", "min", "max")}
        res[key] = {"seconds": s, "moves_per_s": {"median": n / s["median"], "min": n / s["max"], "max": n / s["min"]},
                    "not_planned": failed}
        show(f"batch, {label}", {"median": rate["median"], "min": n / s["max"], "max": n / s["min"], "n": s["n"]},
             "mv/s", 1.0, target="> 1000 mv/s" if key == "verdicts" else "")
        if failed:
            note("", f"({failed} of {n} rows could not be planned)")
    res["engine"] = _bench_verdict_engine(prof, engine_sizes, repeat)
    return res


def _bench_verdict_engine(prof, sizes: tuple[int, ...], repeat: int) -> dict:
    """The batched verdict engine (``plan --batch F --json`` without -o) under the default duration rule (limits) and
    under ``--time auto``, interleaved: in-process moves/s through ``pickplace_cli.pipelines.verdicts.verdict_rows``,
    and the CLI's wall time (fresh process) with -j 1 and -j 2. (bench/bench_default_batch.py: the same comparison
    alone, with plan() on every row for reference.)"""
    try:
        from pickplace_cli.pipelines.verdicts import Verdict, verdict_rows
    except ImportError:
        note("verdict engine", "not available (pickplace_cli.pipelines.verdicts is missing); skipped")
        return {"error": "pickplace_cli.pipelines.verdicts not available"}
    from pickplace_cli.pipelines.batch import read_batch_text
    from pickplace_cli.planner import PlanOptions

    rules = ("auto", "limits")
    res: dict = {}
    cmd = cli_command()
    with tempfile.TemporaryDirectory() as d:
        for m in sizes:
            text = _batch_rows(m)
            rows, _ = read_batch_text(text, "bench")
            opts = {r: PlanOptions(fit=False, time=r) for r in rules}
            decided = {r: sum(isinstance(x.plan, Verdict) for x in verdict_rows(rows, prof, opts[r])) for r in rules}
            times: dict = {r: [] for r in rules}
            for _ in range(repeat):
                for r in rules:
                    t0 = time.perf_counter()
                    list(verdict_rows(rows, prof, opts[r]))
                    times[r].append(time.perf_counter() - t0)
            entry: dict = {}
            for r in rules:
                s = stats(times[r])
                rate = {"median": m / s["median"], "min": m / s["max"], "max": m / s["min"]}
                entry[r] = {"in_process": {"seconds": s, "moves_per_s": rate, "decided_by_engine": decided[r]}}
                show(f"verdict engine, --time {r}, in-process ({m} moves)", {**rate, "n": s["n"]}, "mv/s", 1.0,
                     target="> 1000 mv/s")
                note("", f"({decided[r]} of {m} rows decided by the engine, the rest by plan())")
            path = os.path.join(d, f"b{m}.csv")
            Path(path).write_text(text)
            for j in (1, 2):
                walls: dict = {r: [] for r in rules}
                for _ in range(repeat):
                    for r in rules:
                        extra = ["-t", "auto"] if r == "auto" else []
                        walls[r].append(wall(cmd + ["plan", "--batch", path, "--json", "-q", "-j", str(j), *extra], 1)["median"])
                for r in rules:
                    w = stats(walls[r])
                    wrate = {"median": m / w["median"], "min": m / w["max"], "max": m / w["min"]}
                    entry[r][f"cli_j{j}"] = {"seconds": w, "moves_per_s": wrate}
                    show(f"pickplace plan --batch ({m} moves) --json -q -j {j}, --time {r}", w, "s", 1.0,
                         target="> 1000 mv/s" if (j == 2 and m == 1000) else "")
                    note("", f"= {wrate['median']:.0f} moves/s ({wrate['min']:.0f}–{wrate['max']:.0f}) including start-up")
            res[str(m)] = entry
    return res


def bench_cli(repeat: int) -> dict:
    section("CLI cold start (fresh process, wall time)")
    cmd = cli_command()
    res = {}
    res["help"] = s = wall(cmd + ["--help"], repeat)
    show("pickplace --help", s, "s", 1.0, target="< 0.3 s")
    res["version"] = s = wall(cmd + ["--version"], repeat)
    show("pickplace --version", s, "s", 1.0)
    with tempfile.TemporaryDirectory() as d:
        res["plan_adept_csv"] = s = wall(cmd + ["plan", *ADEPT, "-q", "-o", os.path.join(d, "adept.csv")], repeat)
    show("pickplace plan (Adept cycle, Delta) -o adept.csv", s, "s", 1.0, target="< 0.8 s")
    return res


def bench_build_table(repeat: int) -> dict:
    cores = os.cpu_count() or 1
    section(f"build-table, default grid (λ 1…40 step 0.5, 79 rows), fresh process, wall time")
    cmd = cli_command()
    res = {}
    with tempfile.TemporaryDirectory() as d:
        out = os.path.join(d, "t.csv")
        for key, label, jobs in (("sequential", "-j 1", "1"), ("parallel", f"-j {cores} (all cores)", "0")):
            res[key] = s = wall(cmd + ["build-table", "-q", "-j", jobs, "-o", out], repeat)
            res[key]["workers"] = 1 if jobs == "1" else cores
            show(f"pickplace build-table {label}", s, "s", 1.0, target="< 5 s on 2 workers" if jobs == "0" else "")
    return res


def bench_conveyor(repeat: int) -> dict:
    section("conveyor tracking (bspline-vel), Adept cycle with conveyor velocities, T = 0.2 s")
    try:
        from pickplace_cli.paths.bspline_vel import plan_bspline_vel
    except ImportError:
        note("bspline-vel", "not available")
        return {"error": "not available"}
    import numpy as np

    task = adept_task(v_from=np.array([0.3, 0.0, 0.0]), v_to=np.array([0.0, 0.3, 0.0]))
    res: dict = {}
    for solver in ("exact", "table"):
        try:
            plan_bspline_vel(task, 0.2, solver=solver)
        except Exception as exc:  # noqa: BLE001 - e.g. the table is not shipped yet
            res[solver] = {"error": f"{type(exc).__name__}: {exc}"}
            note(f"bspline-vel {solver}", f"not available: {type(exc).__name__}: {exc}")
            continue
        res[solver] = s = timeit(lambda: plan_bspline_vel(task, 0.2, solver=solver), repeat if solver == "exact" else 10 * repeat)
        show(f"bspline-vel path, solver = {solver}", s)
    return res


def _our_bspline():
    from pickplace_cli.paths import plan_path
    from pickplace_cli.model.profile import load_profile
    from pickplace_cli.timing import choose_duration

    prof = load_profile(PROFILE)
    task = adept_task()

    def compute():
        path = plan_path(task, "bspline")
        return path, choose_duration(path, prof.capacity, "auto")

    return prof, task, compute


def bench_toppra(repeat: int) -> dict:
    section("TOPP-RA: time-optimal parameterisation of our B-spline path's geometry, same |v|, |a| limits")
    try:
        import logging

        import toppra
        import toppra.algorithm
        import toppra.constraint

        logging.getLogger("toppra").setLevel(logging.WARNING)
    except ImportError:
        note("toppra", "not installed (pip install 'pickplace-cli[bench]')")
        return {"error": "toppra not installed"}
    import numpy as np

    prof, task, compute = _our_bspline()
    path, dur = compute()
    ours = timeit(compute, 20 * repeat)
    d = task.p_to - task.p_from
    e_u = np.array([d[0], d[1], 0.0]) / np.hypot(d[0], d[1])
    dirs_angle = np.arange(36) * np.pi / 36
    dirs = np.cos(dirs_angle)[:, None] * e_u + np.sin(dirs_angle)[:, None] * np.array([0.0, 0.0, 1.0])
    k = len(dirs)
    tau = np.linspace(0.0, 1.0, 20001)
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(path(tau, 0), axis=0), axis=1))])
    length = float(arc[-1])

    def solve(scale: float, stations: int = 400, grid: int = 1001):
        """The path by arc length (cubic spline through `stations` exact points of our path: the path's
        own τ-parameterisation starts at rest, which TOPP-RA cannot use), its projections bounded."""
        ss = np.linspace(0.0, length, stations)
        geo = toppra.SplineInterpolator(ss, path(np.interp(ss, arc, tau), 0) @ dirs.T)
        v = prof.capacity.velocity * scale
        a = prof.capacity.acceleration * scale
        cons = [toppra.constraint.JointVelocityConstraint(np.tile([[-v, v]], (k, 1))),
                toppra.constraint.JointAccelerationConstraint(np.tile([[-a, a]], (k, 1)))]
        algo = toppra.algorithm.TOPPRA(cons, geo, gridpoints=np.linspace(0.0, length, grid), parametrizer="ParametrizeConstAccel")
        return algo.compute_trajectory(0, 0)

    inscribed = float(np.cos(np.pi / (2 * k)))
    traj = solve(inscribed)
    if traj is None:
        note("toppra", "failed to parameterise the path")
        return {"error": "toppra returned no trajectory"}
    lower = solve(1.0)
    theirs = timeit(lambda: solve(inscribed), repeat, warm=0)
    t = np.linspace(0, traj.duration, 4001)
    v_peak = float(np.max(np.linalg.norm(np.linalg.lstsq(dirs, traj(t, 1).T, rcond=None)[0], axis=0)))
    a_peak = float(np.max(np.linalg.norm(np.linalg.lstsq(dirs, traj(t, 2).T, rcond=None)[0], axis=0)))
    res = {
        "ours_duration_s": dur.seconds, "ours_binding": dur.binding, "ours_compute": ours,
        "toppra_duration_s": float(traj.duration), "toppra_duration_lower_bound_s": float(lower.duration),
        "toppra_compute": theirs, "toppra_peak_speed": v_peak, "toppra_peak_acceleration": a_peak,
        "setup": "36 projections, bounds x cos(pi/72); 400 arc-length stations, 1001 grid points, ParametrizeConstAccel",
        "ratio_cycle_time": dur.seconds / traj.duration, "ratio_compute_time": ours["median"] / theirs["median"],
    }
    note("our B-spline, --time auto (Eq. 26)", f"T = {dur.seconds:.4f} s ({dur.binding} binding)")
    note("TOPP-RA floor on the same path", f"T = {traj.duration:.4f} s (lower bound {lower.duration:.4f} s; "
         f"peaks |v| {v_peak:.3f} m/s, |a| {a_peak:.1f} m/s²)")
    show("our path + duration (plan_path + choose_duration)", ours)
    show("TOPP-RA (spline + constraints + solve)", theirs)
    note("ratio ours / TOPP-RA", f"cycle time {res['ratio_cycle_time']:.3f}, compute time {res['ratio_compute_time']:.3f}")
    return res


def bench_ruckig(repeat: int) -> dict:
    section("Ruckig: jerk-limited segments P1 → P2 (lift-off) → P4 (set-down) → P5, same limits")
    try:
        from ruckig import InputParameter, Result, Ruckig, Trajectory
    except ImportError:
        note("ruckig", "not installed (pip install 'pickplace-cli[bench]')")
        return {"error": "ruckig not installed"}
    import numpy as np

    prof, task, compute = _our_bspline()
    path, dur = compute()
    ours = timeit(compute, 20 * repeat)
    T = dur.seconds
    j_ours = path.peaks[2] / T**3
    via = task.via_points()
    k1 = path.parameters["k1"]
    vel = path(np.array([k1 / 2, 1 - k1 / 2]), 1) / T  # our velocity at the lift-off and set-down points
    cap = prof.capacity

    def chain(scale: float, through: bool) -> float:
        vmax, amax, jmax = cap.velocity * scale, cap.acceleration * scale, j_ours * scale
        mid = [np.clip(v, -vmax, vmax) if through else np.zeros(3) for v in vel]
        states = [(via[0], np.zeros(3)), (via[1], mid[0]), (via[3], mid[1]), (via[4], np.zeros(3))]
        otg, total = Ruckig(3), 0.0
        for (p0, v0), (p1, v1) in zip(states[:-1], states[1:]):
            inp = InputParameter(3)
            inp.current_position, inp.current_velocity, inp.current_acceleration = list(p0), list(v0), [0.0] * 3
            inp.target_position, inp.target_velocity, inp.target_acceleration = list(p1), list(v1), [0.0] * 3
            inp.max_velocity, inp.max_acceleration, inp.max_jerk = [vmax] * 3, [amax] * 3, [jmax] * 3
            traj = Trajectory(3)
            if otg.calculate(inp, traj) not in (Result.Working, Result.Finished):
                raise RuntimeError("ruckig could not compute a segment")
            total += traj.duration
        return total

    axis = 1 / np.sqrt(2)
    t_cons = chain(axis, True)
    theirs = timeit(lambda: chain(axis, True), 50 * repeat)
    res = {
        "ours_duration_s": T, "ours_compute": ours, "jerk_limit_m_s3": j_ours,
        "ruckig_duration_s": t_cons, "ruckig_duration_per_axis_equal_norm_s": chain(1.0, True),
        "ruckig_duration_stop_at_via_s": chain(axis, False), "ruckig_compute": theirs,
        "setup": "3 segments, per-axis limits = norm/sqrt(2), our velocity at P2/P4, zero acceleration there",
        "ratio_cycle_time": T / t_cons, "ratio_compute_time": ours["median"] / theirs["median"],
    }
    note("our B-spline, --time auto", f"T = {T:.4f} s (peak jerk {j_ours:.0f} m/s³, used as Ruckig's limit)")
    note("Ruckig chain, per-axis = norm/√2", f"T = {t_cons:.4f} s (per-axis = norm: "
         f"{res['ruckig_duration_per_axis_equal_norm_s']:.4f} s; stopping at P2, P4: {res['ruckig_duration_stop_at_via_s']:.4f} s)")
    show("our path + duration", ours)
    show("Ruckig, 3 segments", theirs)
    note("ratio ours / Ruckig", f"cycle time {res['ratio_cycle_time']:.3f}, compute time {res['ratio_compute_time']:.3f}")
    return res


# ------------------------------------------------------------------------------------------------ main


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="fewer repeats and one table build per mode")
    ap.add_argument("--no-table", action="store_true", help="skip the build-table timings (the longest part)")
    ap.add_argument("-o", "--output", type=Path, default=RESULTS, help=f"results JSON (default {RESULTS})")
    args = ap.parse_args()
    q = args.quick
    started = time.time()
    results: dict = {"machine": machine(), "quick": q, "load_average_start": os.getloadavg()}
    m = results["machine"]
    print(f"pickplace {m['pickplace']} · {m['cpu']} · {m['cores']} cores · Python {m['python']} · {m['platform']}")
    results["plan"] = bench_methods(10 if q else 50)
    results["batch"] = bench_batch(50 if q else 200, 1 if q else 3, (1000,) if q else (1000, 10000))
    results["cli"] = bench_cli(3 if q else 10)
    if not args.no_table:
        results["build_table"] = bench_build_table(1 if q else 3)
    results["conveyor"] = bench_conveyor(2 if q else 5)
    results["toppra"] = bench_toppra(2 if q else 5)
    results["ruckig"] = bench_ruckig(2 if q else 5)
    results["load_average_end"] = os.getloadavg()
    results["calibration_sum_range_1000_us"] = CALIBRATION
    results["wall_s"] = time.time() - started
    args.output.parent.mkdir(parents=True, exist_ok=True)
    args.output.write_text(json.dumps(results, indent=2, default=float) + "\n")
    print(f"\nwritten {args.output} ({results['wall_s']:.0f} s; load average {results['load_average_start'][0]:.2f} "
          f"at the start, {results['load_average_end'][0]:.2f} at the end)")


if __name__ == "__main__":
    main()
