"""The files a command reads and writes, as the operating system sees them: which file a path is (links followed,
hard links and standard input included), whether it is a regular file, and reading a pipe that may have no writer.

* :func:`refuse_inputs_as_outputs` refuses, before any work, an output that is a file the command reads (``plan
  --batch moves.csv -o moves.csv``, ``--report robot.yaml`` with ``-p robot.yaml``, ``check t.csv --report t.csv``,
  ``--batch - -o m.csv < m.csv``): the atomic rename would replace the input with the output, exit 0.
* :func:`require_regular_file` refuses a named pipe or a socket where a file is read whole (a profile, a table):
  opening a named pipe that has no writer blocks forever.
* :func:`wait_for_writer` bounds the wait for a pipe's first byte (``check`` of a named pipe or ``<(…)``) and says
  what it waits for (through the caller, which prints).
"""

from __future__ import annotations

import os
import stat
from typing import Iterable

from .errors import ExportError, PickplaceError

#: how long ``check`` waits for the first byte of a named pipe before it gives up [s]
PIPE_WAIT_S = 30.0


def file_identity(path: str) -> tuple[int, int] | None:
    """(device, inode) of the file ``path`` names, links followed (``-``: standard input when it is a regular file
    redirected from one); None when there is no such file, or it is a pipe, terminal or device (which an atomic
    write does not replace)."""
    try:
        st = os.fstat(0) if path == "-" else os.stat(path)
    except (OSError, ValueError):
        return None
    if not stat.S_ISREG(st.st_mode):
        return None
    return st.st_dev, st.st_ino


def refuse_inputs_as_outputs(outputs: Iterable[tuple[str, str | None]], inputs: Iterable[tuple[str, str | None]]) -> None:
    """ExportError (exit 1) when an output is the same file (by path or by inode: symbolic and hard links, standard
    input redirected from it) as an input. ``outputs`` and ``inputs``: (option as the user wrote it, path or None)."""
    ins = [(opt, p, file_identity(p)) for opt, p in inputs if p is not None]
    for out_opt, out in outputs:
        if out is None or out == "-":
            continue
        ident = file_identity(out)
        if ident is None:
            continue
        for in_opt, src, src_ident in ins:
            if src_ident == ident:
                given = "standard input" if src == "-" else src
                raise ExportError(f"{out_opt} {out}: is the file this command reads as {in_opt} ({given}); writing it "
                                  "would replace the input: give another output file")


def require_regular_file(path: str, what: str, error: type[PickplaceError]) -> None:
    """``error`` naming ``path`` when it is a named pipe or a socket (a ``what`` — profile, table — is read whole
    from a regular file; opening a pipe that has no writer would block forever). A missing file is left to the
    reader's own message."""
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return
    if stat.S_ISFIFO(mode) or stat.S_ISSOCK(mode):
        kind = "a named pipe" if stat.S_ISFIFO(mode) else "a socket"
        raise error(f"{what} {path}: {kind}, not a file; a {what} is read from a regular file")


def open_for_reading(path: str, what: str, error: type[PickplaceError], wait_s: float | None = None,
                     notify=None) -> int:
    """A file descriptor of ``path`` open for reading. A named pipe is opened without blocking and its first byte
    (or its writer's end) waited for at most ``wait_s`` seconds (default :data:`PIPE_WAIT_S`), calling
    ``notify(text)`` once with what is awaited (the CLI prints it); ``error`` (one line) when nothing comes."""
    try:
        fifo = stat.S_ISFIFO(os.stat(path).st_mode)
    except OSError:
        fifo = False
    try:
        fd = os.open(path, os.O_RDONLY | (os.O_NONBLOCK if fifo else 0))
    except OSError as exc:
        raise error(f"{path}: cannot read: {exc.strerror}") from None
    if fifo:
        try:
            wait_for_writer(fd, path, what, error, PIPE_WAIT_S if wait_s is None else wait_s, notify)
        except BaseException:
            os.close(fd)
            raise
    return fd


def wait_for_writer(fd: int, path: str, what: str, error: type[PickplaceError], wait_s: float, notify=None) -> None:
    """Wait until the pipe ``fd`` (opened non-blocking) has data or a writer that closed it, then make it blocking;
    ``notify(text)`` after the first second, ``error`` after ``wait_s`` seconds."""
    import select
    import time

    poller = select.poll()
    poller.register(fd, select.POLLIN | select.POLLHUP)
    deadline = time.monotonic() + wait_s
    said = False
    while True:
        left = deadline - time.monotonic()
        if left <= 0:
            raise error(f"{what} {path}: a named pipe with no writer: nothing came in {wait_s:g} s (start the program "
                        "that writes it first, or give a file)")
        if poller.poll(int(min(left, 1.0) * 1000)):
            break
        if not said and notify is not None:
            notify(f"waiting for a writer on the named pipe {path} (up to {wait_s:g} s)")
            said = True
    os.set_blocking(fd, True)
