"""The moves of the ``--time optimal`` benchmarks (``bench_law_solver.py``, ``bench_optimal_online.py``): the Adept
cycle on delta-su2018, then random moves of each shipped profile in its region of ``tests/property/test_limit_truth``
(both ends drawn uniformly, at least 5 cm apart horizontally, a clearance drawn in its range), the same for the same
seed. Not a benchmark itself."""

from __future__ import annotations

from collections.abc import Callable, Iterator

import numpy as np

from pickplace_cli.model.task import Task
from tests.property.test_limit_truth import REGIONS, _profile

PROFILES = ("delta-su2018", "delta-4axis", "scara-600", "gantry")
ADEPT = Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5)


def candidates(seed: int, moves: int) -> list[tuple[str, str, Task]]:
    """(label, profile name, move): the Adept cycle, then 3 × ``moves`` candidates per profile (drawn with the seed
    ``seed`` + the profile's place in ``PROFILES``; the unplannable ones are skipped by :func:`measured`)."""
    work = [("adept", "delta-su2018", ADEPT)]
    for name in PROFILES:
        (lo, hi), (h0, h1) = REGIONS[name]
        rng = np.random.default_rng(seed + PROFILES.index(name))
        for _ in range(moves * 3):
            p0, p1 = rng.uniform(lo, hi), rng.uniform(lo, hi)
            if np.linalg.norm(p1[:2] - p0[:2]) >= 0.05:
                work.append((name, name, Task(p0, p1, float(rng.uniform(h0, h1)), 0.5)))
    return work


def measured(seed: int, moves: int, measure: Callable[[str, object, Task], dict | None]) -> Iterator[dict]:
    """``measure(label, profile, move)`` on the Adept cycle and the first ``moves`` candidates of each profile it
    answers (None: an unplannable move, skipped), the profiles in turn (a run cut short has measured each about
    equally)."""
    work = candidates(seed, moves)
    yield from filter(None, [measure(*work[0][:1], _profile(work[0][1]), work[0][2])])
    queues = {name: [w for w in work[1:] if w[0] == name] for name in PROFILES}
    done = dict.fromkeys(PROFILES, 0)
    while any(queues.values()):
        for name in PROFILES:
            while queues[name] and done[name] < moves:
                label, prof_name, task = queues[name].pop(0)
                res = measure(label, _profile(prof_name), task)
                if res is not None:
                    done[name] += 1
                    yield res
                    break
            else:
                queues[name] = []


def first_moves(seed: int = 500) -> Iterator[tuple[str, object, Task]]:
    """(label, profile, move): the Adept cycle, then the first candidate of each profile the default plan plans."""
    from pickplace_cli.model.errors import PickplaceError
    from pickplace_cli.planner import PlanOptions, plan

    seen: set = set()
    for label, name, task in candidates(seed, 1):
        if label in seen:
            continue
        prof = _profile(name)
        try:
            plan(task, prof, PlanOptions())
        except PickplaceError:
            continue
        seen.add(label)
        yield label, prof, task
