"""How well the widened B-spline family can follow the free-path optimum's geometry, and what its optimal law makes
of that geometry (the Adept cycle, delta-su2018, motors alone or ``--capacity``).

    python bench/bench_shape_fit.py                # ~2 min: one IPOPT solve of the free path, three fits
    python bench/bench_shape_fit.py --capacity

1. The free path (``tests/reference/free_path.py``, CasADi + IPOPT, 16 intervals per phase, from the start that
   gave the best reference in ``bench/bench_free_path.py``), sampled 8 points per interval on its exact cubics.
2. A least-squares fit (scipy's ``least_squares``) of the family's nine parameters (k1, k2, η, arch/h, k3, k4, mid,
   eta_down, mid_x) to that geometry: each free-path point's distance to the family's curve (4001 points) and back,
   from three starts; the best fit's RMS and largest distance [m].
3. ``plan --time optimal`` on the fitted shape, its duration against the free path's.

Results go to ``bench/results/shape_fit.json``. Not a test.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from pickplace_cli import PlanOptions, Task, load_profile, plan  # noqa: E402
from pickplace_cli.paths import plan_path  # noqa: E402
from pickplace_cli.planner import motion_model_static  # noqa: E402
from tests.reference import delta_rigid as D  # noqa: E402
from tests.reference import free_path as F  # noqa: E402

P_FROM, P_TO, HEIGHT = [-0.1525, 0.0, -0.8], [0.1525, 0.0, -0.8], 0.025
NAMES = ("k1", "k2", "eta", "arch_over_h", "k3", "k4", "mid", "eta_down", "mid_x")
LO = np.array([0.01, 0.01, 0.1, 0.0, 0.01, 0.01, 0.35, 0.1, 0.3])
HI = np.array([0.99, 0.99, 0.9, 3.0, 0.99, 0.99, 0.65, 0.9, 0.7])
STARTS = ([0.2, 0.7, 0.1, 0.8, 0.3, 0.15, 0.5, 0.1, 0.5], [0.16, 0.74, 0.1, 0.43, 0.3, 0.15, 0.51, 0.1, 0.5],
          [0.3, 0.3, 0.1, 1.0, 0.3, 0.3, 0.5, 0.1, 0.5])


def free_points(prof, capacity: bool):
    lim = F.limits_from_profile(prof, capacity=capacity)
    P = D.params_from_robot(motion_model_static(prof)[0])
    p0, p1 = np.array(P_FROM), np.array(P_TO)
    r = F.solve_free_path(p0, p1, HEIGHT, lim, P, n_phase=16, t_guess=0.10,
                          guess=F._default_guess(p0, p1, max(p0[2], p1[2]) + HEIGHT, 0.3, 0.04))
    pts = []
    for i in range(len(r.t) - 1):
        p, v, a = r.x[i, :3], r.x[i, 3:6], r.x[i, 6:9]
        for dt in np.linspace(0.0, r.t[i + 1] - r.t[i], 8, endpoint=False):
            pts.append(p + v * dt + a * dt**2 / 2 + r.u[i] * dt**3 / 6)
    pts.append(r.x[-1, :3])
    return r, np.array(pts)


def shape(x) -> tuple[Task, dict]:
    k1, k2, eta, arch, k3, k4, mid, eta_down, mid_x = (float(v) for v in x)
    return Task(P_FROM, P_TO, HEIGHT, eta), {"k1": k1, "k2": k2, "arch": max(arch, 0.0) * HEIGHT, "k3": k3, "k4": k4,
                                             "mid": mid, "eta_down": eta_down, "mid_x": mid_x}


def main() -> None:
    from scipy.optimize import least_squares
    from scipy.spatial import cKDTree

    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--capacity", action="store_true", help="hold the profile's Cartesian capacity too")
    ap.add_argument("-o", "--output", default=str(Path(__file__).parent / "results" / "shape_fit.json"))
    args = ap.parse_args()
    prof = load_profile("delta-su2018")
    ref, pts = free_points(prof, args.capacity)
    print(f"free path: T {ref.T:.5f} s, η {ref.eta:.3f}, apex {ref.arch * 1e3:+.1f} mm over h, {ref.status}, "
          f"dense utilisation {ref.dense_utilisation:.4f}", flush=True)
    tau = np.linspace(0.0, 1.0, 4001)
    back = cKDTree(pts)

    def residual(x):
        try:
            curve = plan_path(*shape(x)[:1], "bspline", **shape(x)[1]).evaluate(tau, 0)
        except Exception:  # noqa: BLE001 - a parameter set the family refuses
            return np.full(len(pts) + len(tau[::10]), 1.0)
        return np.concatenate([cKDTree(curve).query(pts)[0], back.query(curve[::10])[0]])

    fits = []
    for x0 in STARTS:
        r = least_squares(residual, x0, bounds=(LO, HI), diff_step=1e-4)
        fits.append((float(np.sqrt(np.mean(r.fun**2))), float(np.abs(r.fun).max()), r.x))
        print(f"  fit from {x0}: RMS {fits[-1][0] * 1e3:.3f} mm, largest {fits[-1][1] * 1e3:.3f} mm", flush=True)
    rms, worst, x = min(fits, key=lambda f: f[0])
    task, params = shape(x)
    got = plan(task, prof, PlanOptions(time="optimal", hold_capacity=args.capacity, method_params=params))
    ratio = got.duration.seconds / ref.T
    print(f"fitted shape {dict(zip(NAMES, np.round(x, 4).tolist()))}: --time optimal T {got.duration.seconds:.5f} s "
          f"= {ratio:.4f} × the free path, ok {got.report.ok}", flush=True)
    out = {"command": "python bench/bench_shape_fit.py" + (" --capacity" if args.capacity else ""),
           "free_T": ref.T, "free_dense_utilisation": ref.dense_utilisation, "fit_rms_m": rms, "fit_max_m": worst,
           "x": dict(zip(NAMES, map(float, x))), "T_fitted_optimal": got.duration.seconds, "ratio": ratio,
           "ok": bool(got.report.ok)}
    Path(args.output).write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    main()
