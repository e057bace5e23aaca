"""``optimal_law`` of this checkout against another revision's ``pickplace_cli/timing/optimal.py``, both in one
process, alternating call by call: CPU time (``time.process_time``, BLAS held to one thread by the law itself)
and wall time, medians; and whether both give the same law (the duration estimate to the bit).

    python bench/bench_optimal_before_after.py [--base main] [--rounds 7]

Moves: the Adept cycle (delta-su2018) and one random bspline move per shipped profile (seed 500, the first
plannable one; the gantry with the drives of ``tests/property/test_limit_truth.py``). The law alone (the fit of
the uniform law, the composed path's fit and the check around it are the same code on both sides).
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pickplace_cli.model.errors import PickplaceError  # noqa: E402
from pickplace_cli.model.task import Task  # noqa: E402
from pickplace_cli.planner import PlanOptions, motion_model, plan  # noqa: E402
from pickplace_cli.timing import optimal as this  # noqa: E402
from tests.property.test_limit_truth import REGIONS, _profile  # noqa: E402


def base_module(rev: str):
    """``rev``'s optimal.py as a module of the installed package (its relative imports resolve to this checkout's
    other modules, which the law's own code does not differ in)."""
    src = subprocess.run(["git", "-C", str(ROOT), "show", f"{rev}:pickplace_cli/timing/optimal.py"], check=True,
                         capture_output=True, text=True).stdout
    spec = importlib.util.spec_from_loader("pickplace_cli.timing._optimal_base", loader=None)
    mod = importlib.util.module_from_spec(spec)
    mod.__package__ = "pickplace_cli.timing"
    sys.modules[spec.name] = mod  # its dataclasses look their module up
    exec(compile(src, f"{rev}:optimal.py", "exec"), mod.__dict__)
    return mod


def moves() -> list[tuple[str, object, Task]]:
    out = [("adept", _profile("delta-su2018"), Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5))]
    for name in ("delta-su2018", "delta-4axis", "scara-600", "gantry"):
        (lo, hi), (h0, h1) = REGIONS[name]
        rng = np.random.default_rng(500)
        prof = _profile(name)
        for _ in range(20):
            p0, p1 = rng.uniform(lo, hi), rng.uniform(lo, hi)
            task = Task(p0, p1, float(rng.uniform(h0, h1)), 0.5)
            try:
                plan(task, prof, PlanOptions(time="fit"))
            except PickplaceError:
                continue
            out.append((name, prof, task))
            break
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--base", default="main")
    ap.add_argument("--rounds", type=int, default=7)
    args = ap.parse_args()
    base = base_module(args.base)
    for label, prof, task in moves():
        fit = plan(task, prof, PlanOptions(time="fit"))
        model = motion_model(fit.cartesian.path, prof)
        dwell, T = prof.planning.dwell, fit.duration.seconds
        got: dict = {"base": ([], [], None), "this": ([], [], None)}
        for _ in range(args.rounds):
            for side, mod in (("base", base), ("this", this)):
                c0, w0 = time.process_time(), time.perf_counter()
                law = mod.optimal_law(model, dwell, T)
                cpu, wall, _ = got[side]
                cpu.append(time.process_time() - c0)
                wall.append(time.perf_counter() - w0)
                got[side] = (cpu, wall, law.t_estimate)
        (cb, wb, tb), (ct, wt, tt) = got["base"], got["this"]
        print(f"{label:13s} optimal_law CPU median {args.base} {statistics.median(cb) * 1e3:6.1f} ms, this "
              f"{statistics.median(ct) * 1e3:6.1f} ms ({statistics.median(cb) / statistics.median(ct):.2f} ×); wall "
              f"{statistics.median(wb) * 1e3:6.1f} / {statistics.median(wt) * 1e3:6.1f} ms; T estimate {tb:.9f} / "
              f"{tt:.9f} s (same: {tb == tt}, relative difference {abs(tb / tt - 1):.1e})", flush=True)


if __name__ == "__main__":
    main()
