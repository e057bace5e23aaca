"""Building the λ → (k1*, k2*) table (``pickplace build-table``): one optimum per λ of the grid
(:func:`~pickplace_cli.lookup.bspline_optimum.optimise_lambda`).

Rows are independent of each other, so the build splits λ into chunks for any
``concurrent.futures.Executor`` (a local process pool or a Dask cluster) and can resume from a checkpoint of finished rows.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Callable, Sequence

import numpy as np

from ..model.errors import TableError
from .bspline_optimum import _coarse_for, _optimise_chunk, ALGORITHM_VERSION, optimise_lambda, TableRow, TableSettings
from .bspline_table import COLUMNS, Table
from .checkpoint import CheckpointWriter, refuse_row_of_other_run
from .executors import local_pool

if TYPE_CHECKING:  # pragma: no cover
    from concurrent.futures import Executor


def lambda_grid(lam_min: float, lam_max: float, step: float) -> np.ndarray:
    """λ from ``lam_min`` to ``lam_max`` (included) by ``step``; one value when they are equal."""
    for name, v in (("lambda-min", lam_min), ("lambda-max", lam_max)):
        if not (np.isfinite(v) and v > 0):
            raise TableError(f"{name} = {v!r}: must be a finite number > 0")
    return step_grid("lambda", lam_min, lam_max, step)


def step_grid(axis: str, lo: float, hi: float, step: float) -> np.ndarray:
    """``lo`` to ``hi`` (included) by ``step`` (the last step shorter when it does not divide), rounded to 1e-12;
    one value when ``lo`` = ``hi``. ``axis`` names the options in the errors (``{axis}-min`` …)."""
    if not (np.isfinite(step) and step > 0):
        raise TableError(f"{axis}-step = {step!r}: must be a finite number > 0")
    if hi < lo:
        raise TableError(f"{axis}-max = {hi:g}: must not be less than {axis}-min = {lo:g}")
    lam_min, lam_max = lo, hi
    n = int(math.floor((lam_max - lam_min) / step + 1e-9))
    grid = lam_min + step * np.arange(n + 1)
    if lam_max - grid[-1] > 1e-9 * step:
        grid = np.append(grid, lam_max)
    return np.round(grid, 12)


def settings_key(settings: TableSettings) -> str:
    """A short hash of everything that determines a row besides λ (settings and optimiser version)."""
    blob = json.dumps({"algorithm": ALGORITHM_VERSION, **asdict(settings)}, sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()[:16]


def checkpoint_path(output: str | Path) -> Path:
    """Where a build writing ``output`` keeps its finished rows: ``OUTPUT.partial.jsonl`` beside it."""
    p = Path(output)
    return p.with_name(p.name + ".partial.jsonl")


def read_checkpoint(path: Path, settings: TableSettings) -> dict[float, TableRow]:
    """Rows of a checkpoint written by :func:`run_build` for the same settings, keyed by λ.

    TableError when the file belongs to other settings (a different grid, η, weights or optimiser
    version would give other rows). A last line cut short by a kill is ignored."""
    key = settings_key(settings)
    rows: dict[float, TableRow] = {}
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except FileNotFoundError:
        return rows
    except (OSError, UnicodeDecodeError) as exc:
        raise TableError(f"checkpoint {path}: cannot read: {exc}") from None
    if not lines:
        return rows
    try:
        head = json.loads(lines[0])
    except json.JSONDecodeError:
        head = {}
    if not isinstance(head, dict) or head.get("checkpoint") != "pickplace build-table":
        raise TableError(f"checkpoint {path}: line 1 is not a pickplace build-table checkpoint header; delete the file")
    if head.get("settings_key") != key:
        raise TableError(
            f"checkpoint {path}: settings_key = {head.get('settings_key')}: it was written for other settings "
            f"({head.get('settings')}), this build has {key}; run without --resume to start over"
        )
    for lineno, line in enumerate(lines[1:], 2):
        try:
            rec = json.loads(line)
            row = TableRow(*(float(rec[c]) for c in COLUMNS))
        except (json.JSONDecodeError, KeyError, TypeError, ValueError):
            if lineno == len(lines):
                break  # cut short by a kill while writing
            raise TableError(f"checkpoint {path}:{lineno}: not a table row; delete the file") from None
        refuse_row_of_other_run(rec, key, path, lineno)
        rows[row.lam] = row
    return rows


class _Checkpoint(CheckpointWriter):
    """Appends finished rows to the checkpoint file, flushed and synced per batch of rows (a failed write restores
    the file and names it: :class:`~pickplace_cli.lookup.checkpoint.CheckpointWriter`)."""

    def __init__(self, path: Path, settings: TableSettings, append: bool) -> None:
        head = {"checkpoint": "pickplace build-table", "settings_key": settings_key(settings),
                "settings": asdict(settings), "algorithm": ALGORITHM_VERSION}
        super().__init__(path, head, settings_key(settings), append)

    def add(self, rows: Sequence[TableRow]) -> None:  # type: ignore[override]
        super().add([dict(zip(COLUMNS, (r.lam, r.k1, r.k2, r.a_max, r.j_max, r.v_max, r.F, r.a_min, r.j_min)))
                     for r in rows])


@dataclass(frozen=True)
class BuildReport:
    """What a build did: rows in the table, rows computed now, rows taken from a checkpoint."""

    rows: int
    computed: int
    resumed: int
    tasks: int
    checkpoint: Path | None = None


def _chunks(lams: Sequence[float], n_tasks: int) -> list[tuple[float, ...]]:
    """Split λ into ``n_tasks`` interleaved chunks (λ0, λn, λ2n …): costs vary smoothly with λ, so each
    chunk gets a fair share of the expensive small-λ rows."""
    n_tasks = max(1, min(n_tasks, len(lams)))
    return [tuple(lams[i::n_tasks]) for i in range(n_tasks) if lams[i::n_tasks]]


def run_build(
    lams: Sequence[float],
    settings: TableSettings = TableSettings(),
    *,
    progress: Callable[[int, int], None] | None = None,
    workers: int = 1,
    executor: Executor | None = None,
    checkpoint: str | Path | None = None,
    resume: bool = False,
) -> tuple[Table, BuildReport]:
    """Optimal (k1*, k2*) for every λ in ``lams`` (see the module docstring for the method).

    * ``workers`` > 1: a local process pool; ``executor``: any ``concurrent.futures.Executor`` instead
      (e.g. ``distributed.Client(address).get_executor()``; ``workers`` then sets how many chunks).
      λ is split into about 8 chunks per worker, so each task carries several rows and the per-task
      overhead (a pickled tuple of floats and a few rows back) stays small; each worker process computes
      the coarse grid once. Rows do not depend on each other or on the chunking: any engine and any
      number of workers give the same table as the sequential build.
    * ``checkpoint``: a file to which finished rows are appended (and synced) as their chunks finish;
      with ``resume`` its rows for the same settings (:func:`settings_key`) are reused, not recomputed.
      The caller deletes it once the table is safely written.
    * ``progress(done, total)`` is called as rows finish (total = number of λ).
    """
    lams = [float(x) for x in lams]
    if not lams:
        raise TableError("lambda grid: no values to build")
    done_rows: dict[float, TableRow] = {}
    ckpt_path = Path(checkpoint) if checkpoint is not None else None
    if ckpt_path is not None and resume:
        saved = read_checkpoint(ckpt_path, settings)
        done_rows = {lam: saved[lam] for lam in lams if lam in saved}
    todo = [lam for lam in lams if lam not in done_rows]
    resumed = len(done_rows)
    total = len(lams)
    if progress:
        progress(resumed, total)

    parallel = executor is not None or workers > 1
    chunks = _chunks(todo, 8 * max(workers, 1) if parallel else len(todo))
    writer = _Checkpoint(ckpt_path, settings, append=resume) if ckpt_path is not None else None
    pool = None
    futures: list = []
    try:
        if todo and parallel:
            from concurrent.futures import as_completed

            if executor is None:
                executor = pool = local_pool(workers)
            futures = [executor.submit(_optimise_chunk, chunk, settings) for chunk in chunks]
            for fut in as_completed(futures):
                rows = fut.result()
                _finish(rows, done_rows, writer, progress, total)
        else:
            coarse = _coarse_for(settings) if todo else None
            for chunk in chunks:
                rows = [optimise_lambda(lam, coarse, settings) for lam in chunk]  # type: ignore[arg-type]
                _finish(rows, done_rows, writer, progress, total)
    finally:
        for fut in futures:  # after an error or Ctrl-C: drop what has not started (a no-op when done)
            fut.cancel()
        if pool is not None:
            pool.shutdown(wait=True, cancel_futures=True)
        if writer is not None:
            writer.close()
    meta = {"method": "bspline", **{k: v for k, v in asdict(settings).items()}}
    meta["weights"] = list(settings.weights)
    table = Table(tuple(done_rows[lam] for lam in lams), meta=meta)
    return table, BuildReport(len(lams), len(todo), resumed, len(chunks) if todo else 0, ckpt_path)


def _finish(rows, done_rows, writer, progress, total) -> None:
    for r in rows:
        done_rows[r.lam] = r
    if writer is not None:
        writer.add(rows)
    if progress:
        progress(len(done_rows), total)


def build_table(
    lams: Sequence[float],
    settings: TableSettings = TableSettings(),
    progress: Callable[[int, int], None] | None = None,
    workers: int = 1,
    executor: Executor | None = None,
) -> Table:
    """Optimal (k1*, k2*) for every λ in ``lams``: :func:`run_build` without a checkpoint."""
    return run_build(lams, settings, progress=progress, workers=workers, executor=executor)[0]
