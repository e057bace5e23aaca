"""Sweeps: one line run per belt speed × robot count × strategy × seed, on local processes or a Dask cluster,
with a progress callback and results that survive an interruption.

Each case is the line file with ``belt.speed``, the first ``robots`` robots, the strategy (the file's own settings
when it is of that kind, else that strategy's defaults) and the generator's seed replaced
(:func:`case_line`), run whole by :func:`run_case` in a worker (the same engine as a single run). The engine is
:func:`pickplace_cli.lookup.executors.dask_executor`'s executor when a scheduler address is given, else a local
process pool (``workers`` processes; 1: in this process), as for ``build-table``.

**Resumable.** Each finished case is appended at once to ``OUTPUT.partial.jsonl`` (a first line names the sweep: a
digest of the line file and the axes, which every row carries too); ``resume`` reads it and runs only the cases it
lacks. One sweep at a time owns the file (the CLI holds it locked: a second sweep on the same output is refused). The table replaces
OUTPUT only when every case is done, and the partial file is then removed.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterable

from ..model.errors import PickplaceError, TaskError

SWEEP_COLUMNS = ("strategy", "robots", "belt_speed[m/s]", "seed", "parts", "picked", "missed", "miss_rate[-]",
                 "picks_per_minute[1/min]", "utilisation_min[-]", "utilisation_mean[-]", "utilisation_max[-]",
                 "rms_use_max[-]", "miss_rate_half[-]", "picks_per_minute_half[1/min]", "exit_code", "error")


@dataclass(frozen=True)
class Case:
    """One run of a sweep: belt speed [m/s], robot count, strategy, generator seed (None: the file's)."""

    speed: float
    robots: int
    strategy: str
    seed: int | None

    @property
    def key(self) -> str:
        return f"{self.strategy}|{self.robots}|{self.speed!r}|{self.seed}"


def cases(speeds: Iterable[float], counts: Iterable[int], strategies: Iterable[str], seeds: Iterable[int | None]) -> list[Case]:
    return [Case(float(v), int(n), str(k), s) for k in strategies for n in counts for v in speeds for s in seeds]


def case_line(line, case: Case):
    """The line file of one case (module docstring)."""
    from .spec import Bands, Quota, Skip, UpstreamFirst

    kinds = {"upstream_first": UpstreamFirst, "quota": Quota, "bands": Bands, "skip": Skip}
    belt = line.belt.model_copy(update={"speed": case.speed})
    strategy = line.strategy
    if strategy.kind != case.strategy:
        strategy = kinds[case.strategy](kind=case.strategy, claim=strategy.claim)
    if case.robots != len(line.robots):
        if getattr(strategy, "shares", None) is not None:
            shares = list(strategy.shares)[:case.robots]
            total = sum(shares)
            if total <= 0:
                raise TaskError(f"strategy.shares of the first {case.robots} robots add up to 0: cannot renormalise them")
            strategy = strategy.model_copy(update={"shares": [s / total for s in shares]})
        if getattr(strategy, "bands", None) is not None:
            raise TaskError(f"strategy.bands gives {len(strategy.bands)} bands: a sweep over robot counts needs the "
                            "default bands (the belt's width split equally); drop strategy.bands")
    parts = line.parts
    if case.seed is not None:
        if parts.generate is None:
            raise TaskError("--seeds: the line's parts come from a detection file, not a generator")
        parts = parts.model_copy(update={"generate": parts.generate.model_copy(update={"seed": case.seed})})
    robots = list(line.robots)[:case.robots]
    return line.model_copy(update={"belt": belt, "strategy": strategy, "parts": parts, "robots": robots})


def run_case(args: tuple) -> dict:
    """Run one case in a worker → its row (a dict). ``args`` = (line, profiles, case, detections or None)."""
    import time

    from .engine import LineEngine
    from .parts import generate, in_time_order

    from ..model.errors import UnreachableError

    line, profiles, case, detections = args
    t0, c0 = time.perf_counter(), time.process_time()
    row = {"strategy": case.strategy, "robots": case.robots, "belt_speed": case.speed, "seed": case.seed, "case": case.key}
    try:
        cl = case_line(line, case)
        from .spec import check_rules

        check_rules(cl, "line")
        eng = LineEngine(cl, profiles)
        items = detections if detections is not None else generate(cl.parts.generate, cl.belt.width, cl.parts.types)
        try:
            eng.check_speed()
        except UnreachableError as exc:  # a belt too fast for every robot: every part is missed (a result)
            n = sum(1 for d in items if not hasattr(d, "error"))
            row.update(parts=n, picked=0, missed=n, miss_rate=1.0 if n else math.nan, picks_per_minute=0.0,
                       utilisation=[0.0] * len(eng.robots), rms_use_max=math.nan, exit_code=4, error=str(exc),
                       seconds=time.perf_counter() - t0, cpu_seconds=time.process_time() - c0)
            return row
        for item in in_time_order(items, cl.parts.reorder):
            eng.offer(item)
        s = eng.finish()
    except PickplaceError as exc:
        row.update(parts=0, picked=0, missed=0, miss_rate=math.nan, picks_per_minute=math.nan,
                   utilisation=[], rms_use_max=math.nan, exit_code=exc.exit_code, error=str(exc))
        row["seconds"] = time.perf_counter() - t0
        row["cpu_seconds"] = time.process_time() - c0
        return row
    rms = [float(u) for r in s.robots for u in r.rms_use if math.isfinite(u)]
    row.update(parts=s.parts, picked=s.picked, missed=s.missed, miss_rate=s.miss_rate,
               picks_per_minute=s.picks_per_minute, utilisation=[r.utilisation for r in s.robots],
               rms_use_max=max(rms) if rms else math.nan, exit_code=s.exit_code(), error=None,
               simulated_s=s.span)
    iv = s.intervals
    if iv is not None and iv.miss is not None:  # the case's 95 % intervals by batch means (half-widths)
        row.update(miss_rate_half=iv.miss.half, picks_per_minute_half=iv.picks_per_minute.half)
    row["seconds"] = time.perf_counter() - t0  # wall and CPU time of the case (the checkpoint keeps them; the table
    row["cpu_seconds"] = time.process_time() - c0  # does not: the same sweep gives the same bytes)
    return row


def digest(line, axes: dict) -> str:
    """A short digest of the line and the axes: a checkpoint from another sweep is refused."""
    text = line.model_dump_json() + json.dumps(axes, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def checkpoint_path(output: str | Path) -> Path:
    return Path(f"{output}.partial.jsonl")


def read_checkpoint(path: Path, tag: str) -> dict[str, dict]:
    """The finished rows of a checkpoint (case key → row); TaskError when it belongs to another sweep, TableError
    when a row was written by another sweep under this one's header (each row carries its sweep's digest)."""
    from ..lookup.checkpoint import refuse_row_of_other_run

    if not path.exists():
        return {}
    rows: dict[str, dict] = {}
    with open(path, encoding="utf-8") as fh:
        for n, line in enumerate(fh, 1):
            if not line.strip():
                continue
            try:
                doc = json.loads(line)
            except json.JSONDecodeError:
                if n == 1:
                    raise TaskError(f"{path}:1: not a sweep checkpoint (remove it, or run without --resume)") from None
                continue  # a line cut short by a kill: that case is run again
            if n == 1:
                if not isinstance(doc, dict) or doc.get("sweep") != tag:
                    raise TaskError(f"{path}: the checkpoint of another sweep (other line file or axes); remove it or "
                                    "run the same command")
                continue
            if isinstance(doc, dict) and "case" in doc:
                refuse_row_of_other_run(doc, tag, path, n, "sweep")
                rows[doc["case"]] = doc
    return rows


def run_sweep(line, profiles, all_cases: list[Case], detections, workers: int = 1, executor=None,
              progress: Callable[[int, int], None] | None = None, checkpoint: Path | None = None,
              resume: bool = False, tag: str = "") -> list[dict]:
    """Every case's row (in ``all_cases`` order): the finished ones from the checkpoint when resuming, the others
    run on ``executor`` (or ``workers`` local processes that die with this one:
    :func:`~pickplace_cli.lookup.executors.local_pool`), each appended to the checkpoint as it finishes (synced;
    every row carries the sweep's digest). The caller holds the checkpoint
    (:func:`~pickplace_cli.lookup.checkpoint.checkpoint_lock`) for the whole sweep."""
    from ..lookup.checkpoint import CheckpointWriter

    done = read_checkpoint(checkpoint, tag) if (checkpoint is not None and resume) else {}
    todo = [c for c in all_cases if c.key not in done]
    writer = None
    if checkpoint is not None:
        writer = CheckpointWriter(checkpoint, {"sweep": tag, "cases": len(all_cases)}, tag,
                                  append=resume and checkpoint.exists())
    total = len(all_cases)
    if progress:
        progress(len(done), total)

    def finished(row: dict) -> None:
        done[row["case"]] = row
        if writer is not None:
            writer.add([_plain(row)])
        if progress:
            progress(len(done), total)

    try:
        args = [(line, profiles, c, detections) for c in todo]
        if executor is None and workers <= 1:
            for a in args:
                finished(run_case(a))
        else:
            from concurrent.futures import as_completed

            from ..lookup.executors import local_pool

            own = executor is None
            ex = local_pool(workers) if own else executor
            try:
                futures = [ex.submit(run_case, a) for a in args]
                for f in as_completed(futures):
                    finished(f.result())
            finally:
                if own:
                    ex.shutdown(wait=False, cancel_futures=True)
    finally:
        if writer is not None:
            writer.close()
    return [done[c.key] for c in all_cases]


def _plain(row: dict) -> dict:
    return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in row.items()}


def write_sweep_csv(rows: list[dict], stream) -> None:
    """The sweep's table: one row per case (no wall-clock time: the same sweep gives the same bytes)."""
    from .report import _num, _text

    stream.write(",".join(SWEEP_COLUMNS) + "\n")
    for r in rows:
        util = [u for u in (r.get("utilisation") or []) if u is not None]
        cells = [_text(r["strategy"]), str(r["robots"]), _num(r["belt_speed"]), "" if r["seed"] is None else str(r["seed"]),
                 str(r.get("parts", 0)), str(r.get("picked", 0)), str(r.get("missed", 0)), _num(r.get("miss_rate")),
                 _num(r.get("picks_per_minute")), _num(min(util) if util else None),
                 _num(sum(util) / len(util) if util else None), _num(max(util) if util else None),
                 _num(r.get("rms_use_max")), _num(r.get("miss_rate_half")), _num(r.get("picks_per_minute_half")),
                 str(r.get("exit_code", 0)), _text(r.get("error"))]
        stream.write(",".join(cells) + "\n")


def seed_intervals(rows: list[dict]) -> list[tuple[str, int, float, "object", "object"]]:
    """Per strategy, robot count and belt speed run with two seeds or more: (strategy, robots, speed, the miss
    rate's and picks/min's intervals across the seeds: :func:`~pickplace_cli.line.confidence.across_seeds`)."""
    from .confidence import across_seeds

    groups: dict = {}
    for r in rows:
        if r.get("error") and r.get("exit_code") != 4:
            continue
        groups.setdefault((r["strategy"], r["robots"], r["belt_speed"]), []).append(r)
    out = []
    for (kind, n, v), group in groups.items():
        miss = across_seeds([g.get("miss_rate") for g in group])
        if miss is not None:
            out.append((kind, n, v, miss, across_seeds([g.get("picks_per_minute") for g in group])))
    return out
