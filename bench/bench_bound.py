"""How close is ``--time optimal`` to the limit? A lower bound from TOPP-RA under motor torque alone.

    python bench/bench_bound.py                 # Adept cycle + the 61 moves of bench/results/law_multistart.json
    python bench/bench_bound.py --moves 10      # the Adept cycle and the first 10 of them

For each move, the time-optimal traversal of *the same geometric path* (the method's path, re-parameterised
by arc length: a cubic spline through 400 exact points per piece; a piece ends where the path's speed vanishes
inside the move, as at the corners of ``piecewise-poly``) is computed with TOPP-RA (``toppra``, the ``bench``
extra only, never a runtime dependency) under

* **torque**: |motor torque| ≤ peak torque on every joint, the torque from our own robot model
  (``MotionModel``: the robot's inverse dynamics, gear, efficiency and rotor inertia, gravity included),
  written as TOPP-RA's canonical a(s)·s̈ + b(s)·ṡ² + c(s) with a, b, c evaluated by that model (the model is
  affine in the acceleration and quadratic in the velocity: checked on every move);
* **torque + speed**: the same plus |motor speed| ≤ max speed (b(s)·ṡ² ≤ ω_max², first order).

Any trajectory that holds the motor torque limit along that path takes at least T_torque (up to TOPP-RA's
discretisation: collocation on 1000 grid points per piece; the bench re-solves the Adept cycle on 2000 and
reports the change), so T_optimal / T_torque ≥ 1 says how much of the cycle the other limits cost:
the torque *rate* (a third-order limit TOPP-RA cannot express: its bang-bang answer jumps in torque), the RMS
torque of the round trip with the dwells, the motor speed and the smoothness of a C2 law with bounded jerk.
Results go to ``bench/results/bound.json``.
"""

from __future__ import annotations

import argparse
import json
import logging
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

try:
    import toppra
    import toppra.algorithm
    import toppra.constraint
except ImportError:  # pragma: no cover - the bench extra
    sys.exit("bench_bound.py needs toppra: pip install -e '.[bench]'")

from pickplace_cli.planner import PlanOptions, motion_model, plan  # noqa: E402
from pickplace_cli.model.profile import load_profile  # noqa: E402
from pickplace_cli.model.task import Task  # noqa: E402
from tests.property.test_limit_truth import _profile  # noqa: E402

logging.getLogger("toppra").setLevel(logging.WARNING)

STATIONS = 400
GRID = 1000


def _motor(model, p, v, a):
    """(motor torque [N·m], joint velocity) of the model at Cartesian p, v, a (each (N, 3)), jerk 0."""
    out = model._torques(np.zeros(len(p)), rates=False, motion=(p, v, a, np.zeros_like(p)), singularity=False)
    return out[10] + out[11], out[5]


class MotorTorque(toppra.constraint.LinearConstraint):
    """|motor torque| ≤ peak (and, with ``speed``, |motor speed| ≤ max speed) on a Cartesian geometric path,
    with a(s), b(s), c(s) from our robot model."""

    def __init__(self, model, speed: bool) -> None:
        super().__init__()
        self.model, self.speed = model, speed
        drives = [s.drive for s in model.specs]
        self.peak = np.array([d.peak_torque if d and d.peak_torque else np.inf for d in drives])
        self.omega = np.array([d.max_speed if d and d.max_speed else np.inf for d in drives])
        self.identical = True
        self.set_discretization_type(toppra.constraint.DiscretizationType.Collocation)

    def compute_constraint_params(self, path, gridpoints):
        p, ps, pss = path(gridpoints, 0), path(gridpoints, 1), path(gridpoints, 2)
        zero = np.zeros_like(p)
        c, _ = _motor(self.model, p, zero, zero)
        a = _motor(self.model, p, zero, ps)[0] - c
        b, qs = _motor(self.model, p, ps, pss)
        b = b - c
        # the model is affine in the acceleration and quadratic in the velocity, as TOPP-RA's form needs
        b2 = _motor(self.model, p, 2 * ps, 4 * pss)[0] - c
        assert np.allclose(b2, 4 * b, rtol=1e-7, atol=1e-9 * (1 + np.abs(b).max())), "model not quadratic in v"
        finite = np.isfinite(self.peak)
        m = int(finite.sum())
        # a·s̈ + b·ṡ² + c ≤ peak and −(a·s̈ + b·ṡ² + c) ≤ peak, one column each
        A = np.hstack([a[:, finite], -a[:, finite]])
        B = np.hstack([b[:, finite], -b[:, finite]])
        C = np.hstack([c[:, finite], -c[:, finite]])
        F = np.eye(2 * m)
        g = np.concatenate([self.peak[finite], self.peak[finite]])
        if self.speed:
            gear = self.model.gear
            fin = np.isfinite(self.omega)
            k = int(fin.sum())
            A = np.hstack([A, np.zeros((len(p), k))])
            B = np.hstack([B, (gear[fin] * qs[:, fin]) ** 2])
            C = np.hstack([C, np.zeros((len(p), k))])
            F = np.eye(A.shape[1])
            g = np.concatenate([g, self.omega[fin] ** 2])
        return A, B, C, F, g, None, None


def _pieces(path, n: int = 20001) -> list[tuple[np.ndarray, np.ndarray]]:
    """The path sampled on τ, split where its speed vanishes inside the move: [(τ, arc length)] per piece."""
    tau = np.linspace(0.0, 1.0, n)
    sp = np.linalg.norm(path(tau, 1), axis=1)
    rest = sp < 1e-7 * sp.max()
    cuts = [0]
    i = 1
    while i < n - 1:
        if rest[i]:
            j = i
            while j < n - 1 and rest[j]:
                j += 1
            if j < n - 1:
                cuts.append((i + j) // 2)
            i = j
        i += 1
    cuts.append(n - 1)
    out = []
    for lo, hi in zip(cuts[:-1], cuts[1:]):
        t = tau[lo:hi + 1]
        pts = path(t, 0)
        s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
        if s[-1] > 1e-9:
            out.append((t, s))
    return out


def torque_bound(path, prof, speed: bool = False, stations: int = STATIONS, grid: int = GRID) -> float:
    """Minimum time [s] to traverse ``path``'s geometry under |motor torque| ≤ peak (+ motor speed)."""
    model = motion_model(path, prof)
    total = 0.0
    for t, s in _pieces(path):
        ss = np.linspace(0.0, s[-1], stations)
        geo = toppra.SplineInterpolator(ss, path(np.interp(ss, s, t), 0))
        algo = toppra.algorithm.TOPPRA([MotorTorque(model, speed)], geo, gridpoints=np.linspace(0.0, s[-1], grid),
                                       parametrizer="ParametrizeConstAccel")
        traj = algo.compute_trajectory(0, 0)
        if traj is None:
            raise RuntimeError("TOPP-RA found no parameterisation")
        total += float(traj.duration)
    return total


def _variant(drop: tuple[str, ...]):
    """The default Delta with the named drive limits removed (``rated_torque`` removes the RMS check)."""
    import yaml

    from pickplace_cli.model.profile import Profile, resolve_profile_path

    d = yaml.safe_load(resolve_profile_path("delta-su2018").read_text())
    for key in drop:
        d["robot"]["joints"]["drive"].pop(key, None)
    return Profile.model_validate(d)


def decompose(task: Task) -> list[tuple[str, float]]:
    """Our optimal law on the Adept cycle with the motor limits added one at a time: where the gap to the
    torque-only bound goes."""
    steps = [("peak torque only", ("torque_rate", "rated_torque", "max_speed")),
             ("+ motor speed", ("torque_rate", "rated_torque")),
             ("+ RMS (rated torque, round trip with dwells)", ("torque_rate",)),
             ("+ torque rate (= the default profile)", ())]
    out = []
    for label, drop in steps:
        r = plan(task, _variant(drop), PlanOptions(time="optimal"))
        assert r.report.ok
        out.append((label, r.duration.seconds, r.duration.binding))
    return out


def row(name: str, method: str, task: Task, t_opt: float | None = None, shape: bool = False) -> dict:
    from pickplace_cli.timing.bound import torque_bound as ours

    prof = _profile(name)
    fit = plan(task, prof, PlanOptions(method=method, time="fit"))
    if t_opt is None:
        t_opt = plan(task, prof, PlanOptions(method=method, time="optimal")).duration.seconds
    out = {"profile": name, "method": method, "from": task.p_from.tolist(), "to": task.p_to.tolist(),
           "height": task.height, "t_fit": fit.duration.seconds, "t_optimal": t_opt}
    model = motion_model(fit.cartesian.path, prof)
    out["t_ours"] = ours(model, speed=False)  # pickplace's own bound (τ-parameter TOPP-RA passes)
    out["t_ours_speed"] = ours(model, speed=True)
    try:
        t0 = time.perf_counter()
        out["t_torque"] = torque_bound(fit.cartesian.path, prof)
        out["bound_seconds"] = time.perf_counter() - t0
        out["t_torque_speed"] = torque_bound(fit.cartesian.path, prof, speed=True)
    except RuntimeError as exc:  # TOPP-RA found no parameterisation: ours stands alone
        out["toppra_error"] = str(exc)
        out["t_torque"] = out["t_torque_speed"] = None
    ref, ref_s = out["t_torque"] or out["t_ours"], out["t_torque_speed"] or out["t_ours_speed"]
    out["opt_over_torque"] = t_opt / ref
    out["opt_over_torque_speed"] = t_opt / ref_s
    out["fit_over_torque"] = out["t_fit"] / ref
    if out["t_torque"]:
        out["ours_over_toppra"] = out["t_ours"] / out["t_torque"]
        out["ours_over_toppra_speed"] = out["t_ours_speed"] / out["t_torque_speed"]
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--moves", type=int, default=None, help="how many of the recorded random moves (default all)")
    ap.add_argument("-o", "--output", default=str(Path(__file__).parent / "results" / "bound.json"))
    args = ap.parse_args()
    adept = Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5)
    prof = load_profile("delta-su2018")
    fit = plan(adept, prof, PlanOptions(time="fit"))
    opt = plan(adept, prof, PlanOptions(time="optimal"))
    shape_fit = plan(adept, prof, PlanOptions(time="fit", shape=True))
    shape_opt = plan(adept, prof, PlanOptions(time="optimal", shape=True))
    b = torque_bound(fit.cartesian.path, prof)
    b_fine = torque_bound(fit.cartesian.path, prof, stations=800, grid=2000)
    bs = torque_bound(fit.cartesian.path, prof, speed=True)
    b_shape = torque_bound(shape_opt.cartesian.path, prof)
    from pickplace_cli.timing.bound import torque_bound as ours

    model = motion_model(fit.cartesian.path, prof)
    b_ours = ours(model)
    ours_times = []
    for _ in range(5):
        t0 = time.perf_counter()
        ours(model)
        ours_times.append(time.perf_counter() - t0)
    times = []
    for _ in range(5):
        t0 = time.perf_counter()
        torque_bound(fit.cartesian.path, prof)
        times.append(time.perf_counter() - t0)
    adept_res = {
        "t_fit": fit.duration.seconds, "t_optimal": opt.duration.seconds, "t_torque": b, "t_torque_fine": b_fine,
        "t_torque_speed": bs, "t_shape_fit": shape_fit.duration.seconds, "t_shape_optimal": shape_opt.duration.seconds,
        "t_torque_shape_path": b_shape, "bound_ms_median": statistics.median(times) * 1e3,
        "binding_optimal": opt.duration.binding, "t_ours": b_ours, "ours_ms_median": statistics.median(ours_times) * 1e3,
    }
    print(f"  pickplace's own bound (timing/bound.py, in --time optimal's summary): {b_ours:.4f} s = "
          f"{b_ours / b:.4f} × TOPP-RA's, {statistics.median(ours_times) * 1e3:.0f} ms median")
    print(f"Adept cycle, delta-su2018, bspline (table k1, k2, η 0.5):")
    print(f"  T_fit {fit.duration.seconds:.4f} s  T_optimal {opt.duration.seconds:.4f} s  "
          f"TOPP-RA torque bound {b:.4f} s (grid 2000: {b_fine:.4f} s, {abs(b_fine / b - 1) * 100:.2f} % apart), "
          f"torque + speed {bs:.4f} s")
    print(f"  T_optimal / T_torque = {opt.duration.seconds / b:.3f}; T_fit / T_torque = {fit.duration.seconds / b:.3f}")
    print(f"  --optimize shape: fit {shape_fit.duration.seconds:.4f} s, optimal {shape_opt.duration.seconds:.4f} s; "
          f"torque bound on the optimised path {b_shape:.4f} s → T / bound {shape_opt.duration.seconds / b_shape:.3f}")
    print(f"  one bound: {statistics.median(times) * 1e3:.0f} ms median; binding limit of the optimal law: "
          f"{opt.duration.binding}", flush=True)
    steps = decompose(adept)
    adept_res["decomposition"] = steps
    print("  our optimal law (C2, bounded jerk) with the motor limits added one at a time:")
    for label, t, binding in steps:
        print(f"    {label:46s} T {t:.4f} s = {t / b:.3f} × bound  ({binding})")
    src = json.loads((Path(__file__).parent / "results" / "law_multistart.json").read_text())["rows"]
    src = [r for r in src if "Adept" not in r["profile"]][: args.moves]
    rows = []
    for r in src:
        task = Task(r["from"], r["to"], r["height"], 0.5)
        try:
            res = row(r["profile"], r["method"], task, t_opt=None)
        except Exception as exc:  # noqa: BLE001 - report and go on
            print(f"{r['profile']:13s} {r['method']:15s} failed: {exc}", flush=True)
            continue
        rows.append(res)
        tr = (f"TOPP-RA {res['t_torque']:.4f} (+speed {res['t_torque_speed']:.4f}), ours/TOPP-RA "
              f"{res['ours_over_toppra']:.4f} ({res['ours_over_toppra_speed']:.4f})" if res["t_torque"]
              else f"TOPP-RA failed ({res['toppra_error']})")
        print(f"{res['profile']:13s} {res['method']:15s} fit {res['t_fit']:.4f} optimal {res['t_optimal']:.4f} "
              f"ours {res['t_ours']:.4f} (+speed {res['t_ours_speed']:.4f})  {tr}  "
              f"opt/bound {res['opt_over_torque']:.3f}  fit/bound {res['fit_over_torque']:.3f}", flush=True)
    ratios = [r["opt_over_torque"] for r in rows]
    ratios_s = [r["opt_over_torque_speed"] for r in rows]
    summary = {"adept": adept_res, "moves": len(rows),
               "opt_over_torque": {"min": min(ratios), "median": statistics.median(ratios), "max": max(ratios)},
               "opt_over_torque_speed": {"min": min(ratios_s), "median": statistics.median(ratios_s),
                                         "max": max(ratios_s)},
               "fit_over_torque_median": statistics.median(r["fit_over_torque"] for r in rows),
               "rows": rows}
    print(f"{len(rows)} moves: T_optimal / T_torque min {min(ratios):.3f} median {statistics.median(ratios):.3f} "
          f"max {max(ratios):.3f}; / T_torque+speed median {statistics.median(ratios_s):.3f}; T_fit / T_torque "
          f"median {summary['fit_over_torque_median']:.3f}; below the bound: {sum(x < 1 for x in ratios)}")
    both = [r for r in rows if r["t_torque"]]
    dev = [abs(r["ours_over_toppra"] - 1) for r in both] + [abs(r["ours_over_toppra_speed"] - 1) for r in both]
    summary["ours_vs_toppra"] = {"compared": len(both), "worst_relative": max(dev), "median_relative": statistics.median(dev),
                                 "toppra_failed": len(rows) - len(both)}
    print(f"pickplace's own bound against TOPP-RA on {len(both)} moves (torque, torque + speed): median "
          f"{statistics.median(dev) * 100:.3f} %, worst {max(dev) * 100:.3f} % apart; TOPP-RA failed on "
          f"{len(rows) - len(both)} where ours gives a bound")
    Path(args.output).write_text(json.dumps(summary, indent=1))


if __name__ == "__main__":
    main()
