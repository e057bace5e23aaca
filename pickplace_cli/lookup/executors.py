"""Execution engines for ``build-table``: anything with the ``concurrent.futures.Executor`` interface.

:func:`pickplace_cli.lookup.bspline_build.run_build` takes an executor, so the engine is pluggable:

* local: a ``ProcessPoolExecutor`` (``run_build`` makes one itself for ``workers`` > 1);
* a Dask distributed cluster: :func:`dask_executor` yields ``distributed.Client(address).get_executor()``,
  Dask's standard ``concurrent.futures`` adapter. The workers need ``pickplace-cli`` installed (they import
  ``pickplace_cli.lookup.bspline_build`` and ``bspline_optimum`` to run a chunk of rows). Install with the extra ``pickplace-cli[dask]``.
"""

from __future__ import annotations

import os
import sys
from contextlib import contextmanager
from typing import TYPE_CHECKING, Iterator

from ..model.errors import TableError

if TYPE_CHECKING:  # pragma: no cover
    from concurrent.futures import Executor

#: seconds to wait for the scheduler before giving up
CONNECT_TIMEOUT = 10.0
#: in a worker of a pool made with a stop event (:func:`local_pool`): that event, which the parent sets when the answers
#: of the chunks still running are no longer wanted (their reader went away); None elsewhere
_STOP = None


def stopped() -> bool:
    """Whether this worker's parent asked its chunks to stop (:func:`local_pool`'s ``stop``): a chunk checks between
    rows and returns what it has."""
    return _STOP is not None and _STOP.is_set()


def ignore_sigint() -> None:  # pragma: no cover - runs in the worker processes
    """Workers leave Ctrl-C (SIGINT to the whole process group) to the parent, which checkpoints or stops in order
    and prints its one line."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)


def die_with_parent(parent: int) -> None:  # pragma: no cover - runs in the worker processes
    """Make this worker die when its parent ``parent`` (a pid) does, however the parent ends (SIGKILL by a
    supervisor or the OOM killer included): Linux's parent-death signal (``prctl(PR_SET_PDEATHSIG, SIGKILL)``),
    elsewhere a daemon thread that watches the parent's pid once a second. A parent that is already gone when this
    runs (it died while the worker started) ends the worker at once. Without it, orphaned workers went on for
    minutes holding the stderr pipe (``… 2>&1 | tee log`` never ended) and the build's checkpoint open."""
    import signal

    armed = False
    if sys.platform.startswith("linux"):
        try:
            import ctypes

            libc = ctypes.CDLL(None, use_errno=True)
            armed = libc.prctl(1, int(signal.SIGKILL), 0, 0, 0) == 0  # 1 = PR_SET_PDEATHSIG
        except (OSError, AttributeError):
            armed = False
    if os.getppid() != parent:  # the parent died before the signal was armed
        os._exit(1)
    if not armed:
        import threading
        import time

        def watch() -> None:
            while os.getppid() == parent:
                time.sleep(1.0)
            os._exit(1)

        threading.Thread(target=watch, daemon=True, name="parent-watch").start()


def worker_init(parent: int, stop=None) -> None:  # pragma: no cover - runs in the worker processes
    """The initializer of every local process pool (table builds, ``-j N`` batches and streams, compare):
    :func:`ignore_sigint` and :func:`die_with_parent`; ``stop``: the pool's stop event (:func:`stopped`)."""
    global _STOP
    _STOP = stop
    ignore_sigint()
    die_with_parent(parent)


def local_pool(workers: int, stop=None):
    """A ``ProcessPoolExecutor`` of ``workers`` processes whose workers leave Ctrl-C to this process and die with
    it (:func:`worker_init`), and whose exit after a Ctrl-C prints nothing (:func:`_quiet_wakeup`). ``stop``: a
    ``multiprocessing`` event the workers' chunks watch (:func:`stopped`)."""
    from concurrent.futures import ProcessPoolExecutor

    pool = ProcessPoolExecutor(max_workers=workers, initializer=worker_init, initargs=(os.getpid(), stop))
    _quiet_wakeup(pool)
    return pool


def _quiet_wakeup(pool) -> None:
    """Python before 3.12: the interpreter's exit wakes every pool's manager thread through a pipe that thread may be
    closing at that moment (no lock between them), and the write's ``OSError: [Errno 9] Bad file descriptor`` was
    printed as a traceback after the one line of a Ctrl-C (a streamed ``plan --batch - -j 2`` on a loaded machine).
    The pool's wake-up ignores a pipe already closed: there is nothing left to wake."""
    wake = getattr(pool, "_executor_manager_thread_wakeup", None)
    send = getattr(wake, "wakeup", None)
    if send is None:
        return

    def wakeup() -> None:
        try:
            send()
        except OSError:
            pass

    wake.wakeup = wakeup


@contextmanager
def dask_executor(address: str, timeout: float = CONNECT_TIMEOUT) -> Iterator[tuple["Executor", int]]:
    """Connect to the Dask scheduler at ``address`` (e.g. ``tcp://10.0.0.5:8786``) and yield
    ``(executor, threads)``: a ``concurrent.futures`` executor on the cluster and its total number of
    worker threads (used to size the chunks). TableError, one line, when Dask is not installed or the
    scheduler cannot be reached within ``timeout`` seconds. The client is closed on exit."""
    try:
        from distributed import Client
    except ImportError:
        raise TableError(
            f"scheduler = {address}: Dask is not installed; install the extra: pip install 'pickplace-cli[dask]'"
        ) from None
    if not address or "://" not in address and ":" not in address:
        raise TableError(f"scheduler = {address!r}: expected a scheduler address such as tcp://HOST:PORT")
    try:
        client = Client(address, timeout=timeout, set_as_default=False)
    except (OSError, TimeoutError, ValueError) as exc:
        detail = " ".join(str(exc).split()) or type(exc).__name__
        raise TableError(f"scheduler = {address}: cannot reach the Dask scheduler within {timeout:g} s ({detail})") from None
    quiet = _quiet_dask_logs()
    try:
        threads = sum(client.nthreads().values()) or 1
        yield client.get_executor(), threads
    except _lost_errors() as exc:
        detail = " ".join(str(exc).split())[:200] or type(exc).__name__
        raise TableError(f"scheduler = {address}: lost the Dask scheduler while the work ran ({detail}); restart the "
                         "scheduler and run the same command (with --resume to keep what was finished)") from None
    finally:
        try:
            client.close(timeout=timeout)
        except Exception:  # noqa: BLE001 - a client whose scheduler is gone may fail to close: nothing is left to do
            pass
        quiet()


def _lost_errors() -> tuple[type[BaseException], ...]:
    """The exceptions by which a Dask client says its scheduler is gone (cancelled futures, a closed comm)."""
    import asyncio
    import concurrent.futures

    errors: list[type[BaseException]] = [concurrent.futures.CancelledError, asyncio.CancelledError]
    try:
        from distributed.comm.core import CommClosedError

        errors.append(CommClosedError)
    except ImportError:  # pragma: no cover - distributed is installed when a client exists
        pass
    return tuple(dict.fromkeys(errors))


def _quiet_dask_logs():
    """Silence Dask's own loggers while the client lives (a lost scheduler logged a traceback per reconnect attempt
    before the command's one line); returns the function that restores their levels."""
    import logging

    loggers = [logging.getLogger(name) for name in list(logging.root.manager.loggerDict)
               if name == "distributed" or name.startswith(("distributed.", "tornado"))]
    levels = [(lg, lg.level) for lg in loggers]
    for lg in loggers:
        lg.setLevel(logging.CRITICAL + 1)

    def restore() -> None:
        for lg, level in levels:
            lg.setLevel(level)

    return restore
