"""A table build's checkpoint file (``OUTPUT.partial.jsonl``): owned by one run at a time, its rows tagged with the
run's settings, and a failed write leaves it as it was.

* :func:`checkpoint_lock`: an exclusive ``flock`` on the checkpoint for the whole run (taken before it is read,
  truncated or appended to; released by the kernel however the run ends, SIGKILL included). A second build writing
  the same ``-o`` is refused in one line instead of truncating the first one's rows or appending its own under the
  other's header (a resume then merged rows of two η into one table, exit 0).
* :class:`CheckpointWriter`: appends rows (each carrying the settings key, so a row of another run is recognised
  even under the right header), flushed and synced per batch; a write that fails (a full disk) restores the file to
  what it was before this run — removed when this run created it — and raises a TableError naming the file.
"""

from __future__ import annotations

import json
import os
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

from ..model.errors import TableError


@contextmanager
def checkpoint_lock(path: Path | None, what: str = "build-table run") -> Iterator[None]:
    """Hold the build's checkpoint ``path`` for this run (None: no checkpoint, nothing to hold); TableError when
    another run holds it (``what``: the kind of run, as the message names it)."""
    if path is None:
        yield
        return
    try:
        fd = os.open(path, os.O_RDONLY | os.O_CREAT, 0o666)
    except OSError as exc:
        raise TableError(f"checkpoint {path}: cannot create: {exc.strerror}") from None
    created = os.fstat(fd).st_size == 0
    try:
        import fcntl

        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise TableError(f"checkpoint {path}: in use by another {what} writing the same output; wait "
                             "for it to finish, or give this run another -o") from None
        try:
            yield
        finally:
            if created and path.exists() and path.stat().st_size == 0:
                path.unlink(missing_ok=True)  # nothing was written (e.g. a usage error after the lock)
    finally:
        os.close(fd)


class CheckpointWriter:
    """Appends JSON lines (rows) to a checkpoint whose first line is ``head``; ``append`` keeps the rows already
    there (a resume), else the file starts over. Every row gets ``"key": key``."""

    def __init__(self, path: Path, head: dict, key: str, append: bool) -> None:
        self.path = path
        self.key = key
        self.created = not path.exists()
        try:
            if append and path.exists():
                _drop_cut_line(path)
            self.before = path.stat().st_size if append and path.exists() else 0
            self.fh = open(path, "a" if append else "w", encoding="utf-8")
        except OSError as exc:
            raise TableError(f"checkpoint {path}: cannot write: {exc.strerror}") from None
        self.fresh = not append
        if self.fh.tell() == 0:
            self._write([json.dumps(head, sort_keys=True)])

    def add(self, records: list[dict]) -> None:
        """Append one JSON line per record (floats as repr: they read back bit for bit), synced."""
        self._write([json.dumps({**r, "key": self.key}) for r in records])

    def _write(self, lines: list[str]) -> None:
        try:
            self.fh.write("".join(line + "\n" for line in lines))
            self.fh.flush()
            os.fsync(self.fh.fileno())
        except OSError as exc:
            self._restore()
            what = "removed" if self.fresh else f"left with the {self.before} bytes it had"
            raise TableError(f"checkpoint {self.path}: write failed ({exc.strerror or exc}); the checkpoint is {what}, "
                             "the output is not changed") from None

    def _restore(self) -> None:
        try:
            self.fh.close()
        except OSError:
            pass
        try:
            if self.fresh:
                self.path.unlink(missing_ok=True)
            else:
                os.truncate(self.path, self.before)
        except OSError:
            pass

    def close(self) -> None:
        try:
            self.fh.close()
        except OSError:
            pass


def refuse_row_of_other_run(rec: dict, key: str, path: Path, lineno: int, what: str = "build") -> None:
    """TableError when checkpoint row ``rec`` (line ``lineno``) was written by a run with other settings than the
    header's ``key`` (rows of older checkpoints carry no key: they are the header's); ``what``: build or sweep."""
    if "key" in rec and rec["key"] != key:
        raise TableError(f"checkpoint {path}:{lineno}: a row of another {what} (settings_key = {rec['key']}, the "
                         f"header's is {key}): the file mixes two runs; run without --resume to start over")


def _drop_cut_line(path: Path) -> None:
    """Truncate a last line cut short by a kill (no newline), so appended rows start on a line of their own."""
    with open(path, "rb+") as fh:
        data = fh.read()
        if data and not data.endswith(b"\n"):
            fh.truncate(data.rfind(b"\n") + 1)
