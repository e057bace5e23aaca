"""``compose`` (a path with a time law, :mod:`pickplace_cli.timing.compose`) and the exact judge of the composed law,
before and after, in the same run.

    python bench/bench_compose.py                 # the Adept cycle + 12 random moves of delta-su2018 (~1 min)
    python bench/bench_compose.py --moves 30 --repeat 30
    python bench/bench_compose.py -o bench/results/compose.txt     # appends what it prints

The laws are solved once (``optimal_law`` of ``plan --time optimal``'s first law); then, per law, medians of
``--repeat`` interleaved rounds: ``compose`` as it was (a 4001-point cubic-Hermite table of τ(u) and the Cartesian
peaks on a 4001-point grid, kept below as ``compose_before``) and as it is, and the exact judge of each composed
path (the fit as ``plan --time optimal`` runs it: the screen on the fit grid, the precise solve and the plan's
final check, ``_FinalCheck``). Both judges run the current limit check: "judge before/after" differ only by the
composed path they judge (for the limit check before and after, run this script on an older checkout). Printed: wall and CPU
medians [ms] (BLAS held to one thread; on a shared machine the figures carry its load), the two fitted
durations' relative difference, the largest difference of the composed positions [m] and of the Cartesian peaks
(relative), and the verdicts.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from pickplace_cli.model.errors import PickplaceError  # noqa: E402
from pickplace_cli.model.profile import load_profile  # noqa: E402
from pickplace_cli.model.task import Task  # noqa: E402
from pickplace_cli.paths import plan_path  # noqa: E402
from pickplace_cli.planner import _FinalCheck, motion_model  # noqa: E402
from pickplace_cli.timing import fit_duration  # noqa: E402
from pickplace_cli.timing import optimal as O  # noqa: E402
try:  # (run on a checkout from before timing/compose.py existed, the same command gives the "before" figures)
    from pickplace_cli.timing.compose import compose  # noqa: E402
except ImportError:  # pragma: no cover
    from pickplace_cli.timing.optimal import compose  # noqa: E402

LAW_TABLE = 4001


def compose_before(path, b) -> object:
    """The path traversed with dτ/dt = √b(τ) (``b``: a scipy BSpline in τ), as a CartesianPath in u = t/T
    (its derivatives are those at T = 1 s; ``T`` of the law itself is ∫dτ/√b)."""
    from scipy.interpolate import CubicHermiteSpline

    from pickplace_cli.model.trajectory import CartesianPath

    b1, b2 = b.derivative(1), b.derivative(2)
    # t(τ) = ∫ dτ/√b: 4-point Gauss on every interval of a fine table (b is a cubic spline: ~1e-13)
    tab = np.unique(np.concatenate([np.linspace(0.0, 1.0, LAW_TABLE), np.asarray(path.breakpoints, float),
                                    b.t[3:-3]]))
    tab = tab[np.concatenate([[True], np.diff(tab) > 1e-12])]  # round-off twins would make t(τ) stand still
    xg, wg = np.polynomial.legendre.leggauss(4)
    lo, hi = tab[:-1], tab[1:]
    nodes = (lo[:, None] + (hi - lo)[:, None] * (xg + 1) / 2)
    seg = ((b(nodes) ** -0.5) * wg).sum(axis=1) * (hi - lo) / 2
    t_tab = np.concatenate([[0.0], np.cumsum(seg)])
    T = float(t_tab[-1])
    u_tab = t_tab / T
    speed = T * np.sqrt(b(tab))  # dτ/du
    inv = CubicHermiteSpline(u_tab, tab, speed)  # τ(u)
    fwd = CubicHermiteSpline(tab, u_tab, 1.0 / speed)  # u(τ)

    def chain(u: np.ndarray):
        u = np.clip(np.asarray(u, float), 0.0, 1.0)
        tau = np.clip(inv(u), 0.0, 1.0)
        bb = b(tau)
        return tau, T * np.sqrt(bb), T**2 * b1(tau) / 2, T**3 * np.sqrt(bb) * b2(tau) / 2

    def orders(u: np.ndarray):
        tau, s1, s2, s3 = chain(u)
        p, d1, d2, d3 = path.all_orders(tau)
        return [p, d1 * s1[:, None], d2 * (s1**2)[:, None] + d1 * s2[:, None],
                d3 * (s1**3)[:, None] + 3 * d2 * (s1 * s2)[:, None] + d1 * s3[:, None]]

    def evaluate(u: np.ndarray, order: int) -> np.ndarray:
        return orders(u)[order]

    dense = np.linspace(0.0, 1.0, 4001)
    # the path's knots and the law's (where b‴ steps, so the torque rate has a kink: the check's grid and its
    # Gauss-Kronrod spans then see it, and the fit's first check passes instead of nudging by 2e-5)
    bp = np.unique(np.clip(fwd(np.concatenate([np.asarray(path.breakpoints, float), b.t[3:-3]])), 0.0, 1.0))
    jumps = fwd(path.jump_points) if len(path.jump_points) else np.zeros(0)
    from pickplace_cli.curves.peaks import true_peaks

    shell = CartesianPath(evaluate, path.method, {}, (0.0, 0.0, 0.0), np.unique(np.concatenate([[0.0, 1.0], bp])),
                          jumps=tuple(jumps.tolist()), evaluate_all=orders)
    peaks = true_peaks(shell, np.unique(np.concatenate([dense, shell.breakpoints])))
    params = dict(path.parameters)
    params.update(time_law="optimal", law_coefficients=len(b.c))
    angle = None
    if path.angle is not None:  # the tool's turn runs on the same time law
        from pickplace_cli.curves.rotation import ComposedRotation

        angle = ComposedRotation(path.angle, chain)
    return CartesianPath(evaluate, path.method, params, tuple(float(x) for x in peaks), shell.breakpoints,
                         max_order=path.max_order, jumps=shell.jumps, evaluate_all=orders, angle=angle)


def laws(moves: int, seed: int) -> list[tuple[str, object, object]]:
    """(name, path, law b(τ)) for the Adept cycle and ``moves`` random moves of delta-su2018 (default method)."""
    prof = load_profile("delta-su2018")
    rng = np.random.default_rng(seed)
    tasks = [("adept", Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5))]
    while len(tasks) < moves + 1:
        p0, p1 = rng.uniform([-0.2, -0.2, -0.9], [0.2, 0.2, -0.75], (2, 3))
        if np.linalg.norm(p1[:2] - p0[:2]) >= 0.05:
            tasks.append((f"random {len(tasks)}", Task(p0, p1, float(rng.uniform(0.01, 0.06)), 0.5)))
    out = []
    for name, task in tasks:
        try:
            path = plan_path(task, "bspline")
            model = motion_model(path, prof)
            t_fit, _ = fit_duration(model, prof.planning.dwell)
            law = O.optimal_law(model, prof.planning.dwell, t_fit, coefficients=O.LAW_COEFFICIENTS)
        except PickplaceError:
            continue
        out.append((name, path, law.law, law.t_estimate))
    return out


def judge(prof, path, t_law):
    """The exact judge of a composed path as ``plan --time optimal`` runs it: the fit (screen on the fit grid,
    precise solve, the check) from the law's own duration with the plan's final check → (T [s], report)."""
    check = _FinalCheck(prof.planning.rate, prof.planning.dwell)
    T, _ = fit_duration(motion_model(path, prof), prof.planning.dwell, start=t_law, margin=3e-5, check=check)
    return T, check.last[3]


def timed(fn, *args):
    c0, w0 = time.process_time(), time.perf_counter()
    out = fn(*args)
    return out, time.perf_counter() - w0, time.process_time() - c0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--moves", type=int, default=12)
    ap.add_argument("--repeat", type=int, default=15)
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("-o", "--out", default=None, help="also append the lines printed to this text file")
    args = ap.parse_args()
    lines: list[str] = []

    def say(text: str) -> None:
        print(text, flush=True)
        lines.append(text)

    say(f"# python bench/bench_compose.py --moves {args.moves} --repeat {args.repeat} --seed {args.seed} "
        f"(load average {os.getloadavg()[0]:.2f}, {os.cpu_count()} cores)")
    from threadpoolctl import threadpool_limits

    threadpool_limits(1)
    prof = load_profile("delta-su2018")
    rows = []
    u = np.linspace(0.0, 1.0, 10001)
    for name, path, b, t_law in laws(args.moves, args.seed):
        times = {k: [] for k in ("compose_before", "compose", "judge_before", "judge")}
        cpu = {k: [] for k in times}
        for _ in range(args.repeat):  # interleaved: both sides see the same load
            for key, fn, jd in (("before", compose_before, judge), ("", compose, judge)):
                c, w, p = timed(fn, path, b)
                times["compose" + ("_" + key if key else "")].append(w)
                cpu["compose" + ("_" + key if key else "")].append(p)
                (T, rep), w, p = timed(jd, prof, c, t_law)
                times["judge" + ("_" + key if key else "")].append(w)
                cpu["judge" + ("_" + key if key else "")].append(p)
        old, new = compose_before(path, b), compose(path, b)
        (t_old, r_old), (t_new, r_new) = judge(prof, old, t_law), judge(prof, new, t_law)
        dp = float(np.abs(old(u, 0) - new(u, 0)).max())
        dpk = float(np.max(np.abs(np.subtract(old.peaks, new.peaks)) / np.abs(old.peaks)))
        med = {k: 1e3 * statistics.median(v) for k, v in times.items()}
        mc = {k: 1e3 * statistics.median(v) for k, v in cpu.items()}
        rows.append((med, mc))
        say(f"{name:10s} compose {med['compose_before']:6.2f} → {med['compose']:5.2f} ms (CPU {mc['compose_before']:.2f} → "
              f"{mc['compose']:.2f})  judge {med['judge_before']:6.2f} → {med['judge']:5.2f} ms (CPU {mc['judge_before']:.2f} → "
              f"{mc['judge']:.2f})  T {t_new:.6f} s (ΔT/T {t_new / t_old - 1:+.1e})  |Δp| {dp:.1e} m  Δpeaks {dpk:.1e}  "
              f"ok {r_old.ok}/{r_new.ok}")
    for k in ("compose_before", "compose", "judge_before", "judge"):
        say(f"median over moves: {k:15s} {statistics.median(r[0][k] for r in rows):6.2f} ms wall, "
            f"{statistics.median(r[1][k] for r in rows):6.2f} ms CPU")
    if args.out:
        with open(args.out, "a", encoding="utf-8") as fh:
            fh.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
