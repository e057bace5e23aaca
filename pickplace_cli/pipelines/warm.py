"""``plan --batch - --keep-warm SECONDS``: a streamed batch that keeps the planner's caches warm while it waits.

A row that arrives after a pause of 10 ms or more is planned on a cold CPU: on a 2-core VM, one plan of the Adept
cycle at 1 kHz takes ~0.75 ms back to back and ~1.2–1.6 ms after a 10 ms pause (the interpreter's and numpy's
code and data were evicted, by the host's other work while this process slept; busy-waiting keeps only part of
them, 1.0–1.1 ms; re-running the same code keeps them). :class:`WarmLines` reads the batch's lines from a file
descriptor and, each time ``interval`` seconds pass with no complete line, calls ``idle(ready)``; :class:`Warmer` is that ``idle``: it plans
the last row's move again (and formats its CSV text) and throws the result away. The cost is CPU time while the
stream is idle, about one plan per ``interval`` (measured in ``bench/bench_stream.py --keep-warm``); nothing is
written and no state is changed. A row that arrives during a warm-up waits for the stage running: ``ready`` is
polled between the plan's stages (:func:`~pickplace_cli.planner.plan`'s ``interrupt``: path, samples, limit check;
~0.3 ms each) and before the CSV text (~0.4 ms). The warming stops :data:`WARM_IDLE_LIMIT` seconds after the last
row (a line that has stopped costs no CPU overnight) and starts again with the next row; before the first row there
is nothing to warm and the reader just waits.
"""

from __future__ import annotations

import codecs
import os
import select
import time
from typing import Callable

#: bytes asked of one read
_CHUNK = 1 << 16
#: seconds after the last row answered when the warming stops until the next row (the first row after a longer
#: pause is planned cold, ~0.5-1 ms slower): a picking line sends rows every 0.3-3 s while it runs
WARM_IDLE_LIMIT = 60.0


class WarmLines:
    """``readline(limit)`` over the file descriptor ``fd`` (``encoding``, undecodable bytes kept as surrogates, as
    the CLI's own stdin), a line being ended by ``\\n``, ``\\r\\n`` or ``\\r``: a line that ends in ``\\r`` is returned
    at once (a serial device's CR-terminated messages are answered as they come), and a ``\\n`` that then follows
    is taken as the rest of that ``\\r\\n``. While no complete line is buffered it waits on ``fd``; with ``idle``, at
    most ``interval`` seconds at a time and, each time that passes with nothing read, it calls ``idle(ready)``
    (``ready()``: True once a line can be read without waiting); once ``idle`` returns False it is not called again
    before the next line, and the reader waits without a timeout. Without ``idle`` (a stream without
    ``--keep-warm``) it just waits."""

    def __init__(self, fd: int, interval: float | None = None,
                 idle: Callable[[Callable[[], bool]], bool | None] | None = None, encoding: str = "utf-8") -> None:
        self.fd, self.interval, self.idle, self.encoding = fd, interval, idle, encoding
        self._buf = b""
        self._pos = 0  # the unread bytes are _buf[_pos:] (lines are taken by moving _pos: no copy per line)
        self._eof = False
        self._after_cr = False  # the last line ended in a \r that was the last byte read: a \n next belongs to it

    def ready(self) -> bool:
        """True when a line (or the end of the input) can be read now."""
        if self._eof or self._line_end() >= 0:
            return True
        r, _, _ = select.select([self.fd], [], [], 0)
        return bool(r)

    def _line_end(self) -> int:
        """Index just past the first complete line's end in the buffer, or -1."""
        buf, pos = self._buf, self._pos
        n = buf.find(b"\n", pos)
        r = buf.find(b"\r", pos, n if n >= 0 else len(buf))
        if r >= 0:  # a lone \r ends a line, \r\n is one end
            return r + 2 if buf[r + 1 : r + 2] == b"\n" else r + 1
        return n + 1 if n >= 0 else -1

    def readline(self, limit: int = -1) -> str:
        """The next line with its end (``""`` at the end of the input); at most ``limit`` characters when a line
        is longer (as ``TextIOWrapper.readline``)."""
        dormant = self.idle is None  # no idle, or idle said "not before the next line"
        while True:
            end = self._line_end()
            pos, size = self._pos, len(self._buf)
            if 0 <= limit < (end if end >= 0 else size) - pos:  # maybe more than ``limit`` characters
                # (a character whose bytes have not all come yet is not counted, unless the input has ended)
                decoder = codecs.getincrementaldecoder(self.encoding)("surrogateescape")
                head = decoder.decode(self._buf[pos : end if end >= 0 else size], final=end >= 0 or self._eof)
                if len(head) > limit or (end < 0 and len(head) == limit):
                    end = pos + len(head[:limit].encode(self.encoding, "surrogateescape"))
            if end < 0 and self._eof:
                end = size
            if end >= 0:
                line = self._buf[pos:end]
                self._pos = end
                self._after_cr = end == size and line.endswith(b"\r")
                return line.decode(self.encoding, "surrogateescape")
            r, _, _ = select.select([self.fd], [], [], None if dormant else self.interval)
            if not r:
                dormant = self.idle(self.ready) is False  # type: ignore[misc]
                continue
            chunk = os.read(self.fd, _CHUNK)
            if chunk:
                if self._after_cr and chunk[:1] == b"\n":  # the \n of a \r\n whose \r ended the last line
                    chunk = chunk[1:]
                self._after_cr = False
                self._buf = self._buf[self._pos :] + chunk
                self._pos = 0
            else:
                self._eof = True


class Warmer:
    """The ``idle`` of :class:`WarmLines` (every ``interval`` s [s] of waiting): plans the last move answered again
    (:meth:`remember`), then formats its CSV text when the stream writes CSV, stopping between two stages once a
    line is ready; results are discarded. Returns False (no more calls before the next line) before the first move
    and once ``idle_limit`` seconds [s] have passed since the last one."""

    def __init__(self, profile, options, csv_dialect: str | None, interval: float,
                 idle_limit: float = WARM_IDLE_LIMIT, clock: Callable[[], float] = time.monotonic) -> None:
        from dataclasses import replace

        self.profile, self.csv_dialect, self.interval = profile, csv_dialect, interval
        # the warm-up plans with --time auto and no shape search: --time fit/optimal and --optimize shape search for
        # 50 ms to 1 s per plan, which a warm-up cannot stop midway (a row would wait for it) and where a cold cache
        # is under 1 % of the time; the path, samples and limit check they share are still warmed
        if options.time in ("fit", "optimal") or options.shape or options.fit:
            options = replace(options, time="auto", shape=False, fit=False)
        self.options = options
        self.idle_limit, self.clock = idle_limit, clock
        self.task = None
        self.last_row = clock()  # when the last move was remembered
        self.warm_ups = 0  # started
        self.interrupted = 0  # of them, stopped between two stages of the plan by a line that came

    def remember(self, plan) -> None:
        """A row was answered (``plan``: its Plan, or None for a row that failed): the idle time starts again, and
        the move to warm up with is the last one planned from rest to rest (a belt row's move, with a moving end,
        is planned by the rendezvous, not by the stream's options: the previous move is kept)."""
        self.last_row = self.clock()
        task = getattr(plan, "task", None)
        if task is not None and not (task.v_from.any() or task.v_to.any()):
            self.task = task

    def __call__(self, ready: Callable[[], bool]) -> bool:
        """One warm-up, unless a line is ready; False when there is nothing to warm or the stream has been idle
        for ``idle_limit`` s (the reader then waits for the next line without calling again)."""
        if self.task is None or self.clock() - self.last_row > self.idle_limit:
            return False
        if ready():
            return True
        from ..model.errors import PickplaceError
        from ..planner import PlanInterrupted, plan

        self.warm_ups += 1
        try:
            p = plan(self.task, self.profile, self.options, interrupt=ready)
            if self.csv_dialect is not None and not ready():
                from ..export.csv import csv_rows

                csv_rows(p, self.csv_dialect, move=1)
        except PlanInterrupted:  # a line came: the row goes first
            self.interrupted += 1
        except PickplaceError:  # the move re-planned with the stream's options (not the row's time): any outcome
            pass
        return True
