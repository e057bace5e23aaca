"""The local process pool's wake-up at the interpreter's exit (``lookup/executors._quiet_wakeup``): Python before 3.12
writes to every pool's wake-up pipe at exit without a lock against its manager thread closing it, and the write's
``OSError: [Errno 9] Bad file descriptor`` was printed as a traceback after a Ctrl-C's one line (a streamed batch with
``-j 2`` on a loaded machine). The race itself cannot be forced; what is tested is that the pool's wake-up, meeting
a pipe closed under it (its write raising EBADF), raises nothing, and wakes the manager thread as before otherwise."""

from __future__ import annotations

import errno

from pickplace_cli.lookup.executors import local_pool


class _ClosedPipe:
    def send_bytes(self, data: bytes) -> None:
        raise OSError(errno.EBADF, "Bad file descriptor")


def test_a_wakeup_on_a_closed_pipe_raises_nothing():
    pool = local_pool(1)
    try:
        assert pool.submit(int, "7").result(timeout=60) == 7
        wake = pool._executor_manager_thread_wakeup
        writer = wake._writer
        wake._writer = _ClosedPipe()  # what the exit handler meets when the manager thread closed the pipe first
        try:
            wake.wakeup()  # nothing raised
        finally:
            wake._writer = writer
        wake.wakeup()  # the real pipe: the manager thread woken as before
        assert pool.submit(int, "8").result(timeout=60) == 8
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
