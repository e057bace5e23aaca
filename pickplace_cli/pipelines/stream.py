"""Batch rows answered as they are read (``pickplace plan --batch -`` or a named pipe).

:func:`plan_stream` answers the rows of :func:`~pickplace_cli.pipelines.batch.iter_batch` in row order: rows
planned one by one, read one at a time (:func:`~pickplace_cli.pipelines.batch.plan_rows`), or, while a reader thread reads
ahead, decided together by the verdict engine (:mod:`~pickplace_cli.pipelines.verdicts`) or spread over worker processes.
"""

from __future__ import annotations

from typing import Iterator

from .batch import BatchRow, RowResult, _plan_chunk, plan_rows

#: most rows read ahead of the planner (parsed values only: bounded memory however fast the input comes)
STREAM_READ_AHEAD = 1000
#: most rows answered together: the rows already read when the planner is free (a pipe that delivers one row
#: at a time gets one-row batches, the lowest latency; a file piped in at full speed gets the batch
#: engine's throughput)
STREAM_BATCH = 250


def plan_stream(
    items: Iterator[BatchRow | RowResult], profile, options, height: float | None = None, eta: float | None = None,
    fail_fast: bool = False, source: str = "batch", workers: int = 1, csv_dialect: str | None = None,
    format_failed: bool = False, verdicts: bool = False,
) -> Iterator[RowResult]:
    """Answer the rows of :func:`iter_batch` as they are read, in row order. A reader thread reads ahead (at
    most ``STREAM_READ_AHEAD`` rows); whenever the planner is free it takes every row read so far (at most
    ``STREAM_BATCH``) and answers them — planned one by one (``workers`` = 1: one trajectory in memory at a
    time), decided by the verdict engine together (``verdicts``), or spread over ``workers`` processes in
    chunks — yielding each result as soon as it and every earlier row are done. A row that arrives alone is
    answered before the next line is read. Rows planned one by one (``workers`` = 1, no verdict engine) are
    read in the caller's thread instead, one at a time. Input errors (:func:`iter_batch`) are raised in row order, after
    every row before them. ``csv_dialect``: the workers also format the CSV rows (``RowResult.text``)."""
    if workers <= 1 and not verdicts:
        # rows planned one by one: read each in this thread (a reader thread buys nothing when every row is planned
        # alone, and its hand-off is one more thread wake-up per row; measured, it was not the ~0.2 ms between a
        # row's arrival and its plan, most of which is the row's Task built on a cold CPU)
        for item in items:
            for res in _answer([item], profile, options, height, eta, source, None, 1, csv_dialect, format_failed,
                               False):
                yield res
                if fail_fast and res.code:
                    return
        return
    import queue
    import threading

    inbox: queue.Queue = queue.Queue(maxsize=STREAM_READ_AHEAD)
    end = object()

    def reader() -> None:
        try:
            for item in items:
                inbox.put(item)
        except BaseException as exc:  # noqa: BLE001 - an input error: raised by the consumer, in order
            inbox.put(exc)
        inbox.put(end)

    pool = None
    if workers > 1:
        from ..lookup.executors import local_pool

        pool = local_pool(workers)  # Ctrl-C: this process's
        # fork every worker now, before the reader thread exists: a worker forked while that thread is blocked in
        # a read of stdin inherits stdin's lock held, and hangs closing stdin at start-up (multiprocessing's
        # _close_stdin); with the fork method the first submit starts them all
        pool.submit(int).result()
    threading.Thread(target=reader, daemon=True, name="batch-reader").start()
    interrupted = False
    try:
        finished = False
        while not finished:
            batch = [inbox.get()]
            while len(batch) < STREAM_BATCH:
                try:
                    batch.append(inbox.get_nowait())
                except queue.Empty:
                    break
            error = None
            if batch[-1] is end:
                batch.pop()
                finished = True
            if batch and isinstance(batch[-1], BaseException):
                error = batch.pop()
            for res in _answer(batch, profile, options, height, eta, source, pool, workers, csv_dialect,
                               format_failed, verdicts):
                yield res
                if fail_fast and res.code:
                    return
            if error is not None:
                raise error
    except KeyboardInterrupt:
        interrupted = True
        raise
    finally:
        if pool is not None:
            # waited for (the rows in flight; the rest cancelled) unless Ctrl-C: a pool left to the interpreter's
            # exit races its manager thread closing the wake-up pipe (Python < 3.12: an OSError traceback at exit,
            # which local_pool's wake-up now ignores when the race is lost anyway)
            pool.shutdown(wait=not interrupted, cancel_futures=True)


def _answer(batch: list, profile, options, height, eta, source, pool, workers, csv_dialect, format_failed,
            verdicts) -> Iterator[RowResult]:
    """The results of ``batch`` (BatchRows and parse failures) in row order (:func:`plan_stream`)."""
    rows = [b for b in batch if isinstance(b, BatchRow)]
    failed = {b.row: b for b in batch if isinstance(b, RowResult)}
    if pool is not None and len(rows) > 1:
        size = -(-len(rows) // workers)
        chunks = [rows[i : i + size] for i in range(0, len(rows), size)]
        if verdicts:
            from .verdicts import _verdict_chunk

            futures = [pool.submit(_verdict_chunk, (c, profile, options, height, eta, source)) for c in chunks]
        else:
            futures = [pool.submit(_plan_chunk, (c, profile, options, height, eta, source, csv_dialect, format_failed))
                       for c in chunks]
        answers = (res for fut in futures for res in fut.result())
    elif verdicts and len(rows) > 1:  # one row alone: plan() is quicker than the engine's batch set-up
        from .verdicts import verdict_rows

        answers = verdict_rows(rows, profile, options, height, eta, False, source)
    else:
        answers = plan_rows(rows, profile, options, height, eta, False, source)
    for res in answers:
        while failed and min(failed) < res.row:
            yield failed.pop(min(failed))
        yield res
    for n in sorted(failed):
        yield failed[n]
