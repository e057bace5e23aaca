"""The Delta's rigid-body model against the lumped-mass model: what the lumped model misstates, and what the
rigid model costs.

    python bench/bench_delta_model.py [--moves 30] [--repeat 15] [--seed 3]

1. Error of the lumped model: plan N random moves of the default Delta with ``dynamics: lumped`` under
   ``--time fit`` and ``--time optimal``, then check the same motion (path, law and duration) with the rigid
   model: the largest limit use per quantity under the rigid model, where the lumped plan claims ≤ 100 %.
   Repeated for a copy whose pairs carry half their mass in the end fittings (a quarter at each end).
2. Cost, both models in the same run, interleaved: the default plan (``--time limits``) and ``--time optimal`` on
   the Adept cycle in process (median of ``--repeat``), and the model's per-sample cost (motion + dynamics with
   torque rates on 10,000 samples).

Writes bench/results/delta_model.json. Not a test.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from pickplace_cli import PlanOptions, Task, load_profile, plan  # noqa: E402
from pickplace_cli.limits.check import check_limits  # noqa: E402
from pickplace_cli.limits.motion import MotionModel  # noqa: E402
from pickplace_cli.planner import motion_model_static  # noqa: E402
from pickplace_cli.robots import build_robot  # noqa: E402

OUT = Path(__file__).resolve().parent / "results" / "delta_model.json"
ADEPT = Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], height=0.025)


def with_robot(profile, **update):
    """The profile with ``robot`` fields (and ``robot.masses`` fields under ``masses``) replaced."""
    masses = update.pop("masses", None)
    robot = profile.robot.model_copy(update=update)
    if masses:
        robot = robot.model_copy(update={"masses": robot.masses.model_copy(update=masses)})
    return profile.model_copy(update={"robot": robot})


def random_moves(n: int, seed: int) -> list[Task]:
    rng = np.random.default_rng(seed)
    moves = []
    while len(moves) < n:
        a = np.array([*rng.uniform(-0.3, 0.3, 2), rng.uniform(-0.9, -0.7)])
        b = np.array([*rng.uniform(-0.3, 0.3, 2), a[2] + rng.uniform(-0.05, 0.05)])
        if np.linalg.norm(b[:2] - a[:2]) > 0.05:
            moves.append(Task(a, b, height=0.025))
    return moves


def uses(report) -> dict[str, float]:
    """The largest utilisation per quantity over the joints (timed limits only)."""
    out: dict[str, float] = {}
    for row in report.rows:
        if row.kind == "limit":
            out[row.quantity] = max(out.get(row.quantity, 0.0), row.utilisation)
    return out


def lumped_error(moves, rigid, lumped, rule: str) -> dict:
    """Worst rigid-model use of each quantity over lumped plans that claim every limit holds."""
    static = motion_model_static(rigid)
    worst: dict[str, float] = {}
    over = 0
    dwell = rigid.planning.dwell
    for task in moves:
        p = plan(task, lumped, PlanOptions(time=rule))
        if not p.report.ok:
            continue
        model = MotionModel(p.cartesian.path, *static)
        rep = check_limits(model, p.duration.seconds, tau=np.linspace(0.0, 1.0, 4001), dwell=dwell)
        u = uses(rep)
        over += any(x > 1.0 for x in u.values())
        for k, x in u.items():
            worst[k] = max(worst.get(k, 0.0), x)
    return {"moves": len(moves), "moves_over_100_percent_under_rigid": over,
            "worst_rigid_use": {k: round(v, 5) for k, v in sorted(worst.items())}}


def timed(fn, repeat: int) -> list[float]:
    out = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t0)
    return out


def cost(rigid, lumped, repeat: int) -> dict:
    res: dict = {}
    for rule in ("limits", "optimal"):
        times = {"rigid": [], "lumped": []}
        for _ in range(repeat):  # interleaved: both models see the same machine load
            for name, prof in (("rigid", rigid), ("lumped", lumped)):
                times[name] += timed(lambda: plan(ADEPT, prof, PlanOptions(time=rule)), 1)
        med = {k: statistics.median(v) for k, v in times.items()}
        res[rule] = {"median_s": med, "ratio_rigid_over_lumped": med["rigid"] / med["lumped"]}
    rng = np.random.default_rng(0)
    n = 10_000
    p = np.column_stack((rng.uniform(-0.2, 0.2, (n, 2)), rng.uniform(-0.9, -0.7, n)))
    v, a, j = (rng.normal(scale=s, size=(n, 3)) for s in (2.0, 50.0, 3000.0))
    per = {"rigid": [], "lumped": []}
    for _ in range(repeat):
        for name, prof in (("rigid", rigid), ("lumped", lumped)):
            robot = build_robot(prof.robot)
            per[name] += timed(lambda: robot.motion_and_dynamics(p, v, a, j), 1)
    res["model_per_sample_s"] = {k: statistics.median(x) / n for k, x in per.items()}
    return res


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--moves", type=int, default=30)
    ap.add_argument("--repeat", type=int, default=15)
    ap.add_argument("--seed", type=int, default=3)
    args = ap.parse_args()
    from threadpoolctl import threadpool_limits

    threadpool_limits(1)
    rigid = load_profile("delta-su2018")
    lumped = with_robot(rigid, dynamics="lumped")
    m = rigid.robot.masses.forearm_pair
    fitted = with_robot(rigid, masses={"forearm_end_elbow": m / 4, "forearm_end_plate": m / 4})
    moves = random_moves(args.moves, args.seed)
    result = {
        "load_average": os.getloadavg(),
        "command": f"python bench/bench_delta_model.py --moves {args.moves} --repeat {args.repeat} --seed {args.seed}",
        "lumped_plans_under_rigid_model": {
            rule: {"uniform_rods": lumped_error(moves, rigid, lumped, rule),
                   "half_the_rod_mass_in_end_fittings": lumped_error(moves, fitted, lumped, rule)}
            for rule in ("fit", "optimal")
        },
        "cost": cost(rigid, lumped, args.repeat),
    }
    OUT.write_text(json.dumps(result, indent=2) + "\n")
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
